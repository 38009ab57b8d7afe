#!/usr/bin/env bash
# Cost of elastic coordinates (#17): a rigid hub carrying a beam on a hinge,
# the beam rigid (k = 0) or flexible with k = 2, 4, 8, 16 modes (16
# elements, clamped reference). Prints op counts and generation time
# (`eom-gen stats`) and ns per call (`eom-gen bench --per-call`, median of
# 31 repetitions over 1024 random states) for each k, in one run.
#
#   bash bench/flex/modes.sh            # from the repository root
set -euo pipefail
cd "$(dirname "$0")/../.."
out=$(mktemp -d)
cargo build -q --release -p eom-cli
bin=target/release/eom-gen
model() { # $1 = name, $2 = the beam body's fields
    cat > "$out/$1.ron" <<RON
// A hub (revolute about z) carrying a 2 m beam on a hinge about y, gravity
// along −z; the beam: rho_a 1.5 kg/m, EA 1e6 N, EI 400/300 N m², GJ 200 N m².
Model(
    name: "$1",
    gravity: (0, 0, -9.81),
    bodies: [
        (name: "hub", mass: 2.0, inertia: Diag(0.1, 0.1, 0.2)),
        (name: "beam", $2),
    ],
    joints: [
        (name: "hub_j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "hub"),
        (name: "beam_j", kind: Revolute(axis: (0, 1, 0)), parent: "hub", child: "beam",
         parent_frame: (position: (0.3, 0, 0))),
    ],
)
RON
}
# The rigid rod of the same mass and inertia (ρA L = 3 kg, centre at L/2,
# m L²/12 about the centre, ρI_p L about the axis).
model rigid 'mass: 3.0, com: (1.0, 0, 0), inertia: Diag(0.004, 1.0, 1.0)'
for k in 2 4 8 16; do
    model "flex$k" "flexible: Beam(length: 2.0, rho_a: 1.5, rho_ip: 0.002, ea: 1e6,
            ei_y: 400, ei_z: 300, gj: 200, elements: 16, reference: Clamped, modes: $k)"
done
for m in rigid flex2 flex4 flex8 flex16; do
    echo "## $m"
    "$bin" stats "$out/$m.ron"
    nice "$bin" bench --per-call "$out/$m.ron"
done
