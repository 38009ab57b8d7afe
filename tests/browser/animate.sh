#!/bin/sh
# The animation page in a real browser: installs Debian's chromium if
# missing, writes the pages of 2 s runs of the double pendulum (drawn from
# its joint frames) and of a URDF with every kind of `<visual>` (shapes and
# meshes) and of the crane's rope (a cable's deformed shape on a rigid
# boom) and of the hub and beam (a flexible body's deformed shape), opens
# each headless at t = 0 and t = 1 s (the page honours `#t=SECONDS`;
# `#deform=10` scales flexible bodies' deformation), requires no console error and no uncaught exception, and
# checks that both screenshots show the mechanism and differ
# (tests/browser/png_check.py); and that the bouncing ball flashes at its
# impact and not before.
#   tests/browser/animate.sh            (from the repository root)
# EOM_GEN=path/to/eom-gen uses that binary instead of `cargo run`.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
here="$root/tests/browser"
if ! command -v chromium >/dev/null 2>&1; then
    echo "installing chromium (apt-get) ..."
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -q >/dev/null
    apt-get install -y -q chromium >/dev/null
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
gen() { # gen ARGS...: eom-gen with ARGS, from the repository root
    if [ -n "${EOM_GEN:-}" ]; then
        (cd "$root" && "$EOM_GEN" "$@")
    else
        (cd "$root" && cargo run -q -p eom-cli -- "$@")
    fi
}
shot() { # shot PAGE T FILE: a screenshot of PAGE at time T; the browser's log in FILE.log
    timeout 120 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
        --disable-background-networking --disable-component-update --disable-sync \
        --enable-unsafe-swiftshader --user-data-dir="$(mktemp -d -p "$out")" \
        --enable-logging=stderr --v=0 --window-size=800,600 \
        --screenshot="$3" "file://$1#t=$2" 2>"$3.log" >/dev/null
    # Console lines of the page, less WebGL's performance notes.
    if grep 'CONSOLE' "$3.log" | grep -v 'GL Driver Message' | grep -q .; then
        echo "console messages of $1 at t = $2:"
        grep 'CONSOLE' "$3.log" | grep -v 'GL Driver Message'
        exit 1
    fi
    test -s "$3" || { echo "no screenshot of $1 at t = $2"; cat "$3.log"; exit 1; }
}
check() { # check NAME: the page NAME.html at t = 0 and 1 s, drawn and moved
    shot "$out/$1.html" 0 "$out/$1-t0.png"
    shot "$out/$1.html" 1 "$out/$1-t1.png"
    python3 "$here/png_check.py" "$out/$1-t0.png" "$out/$1-t1.png"
    if [ -n "${EOM_SHOTS:-}" ]; then cp "$out/$1-t0.png" "$out/$1-t1.png" "$EOM_SHOTS/"; fi
    echo "$1: drawn, moved, no console errors"
}
# Links and masses drawn from the joint frames (compiled model).
gen animate models/double_pendulum.ron --t-end 2 -o "$out/pendulum.html"
check pendulum
# URDF <visual> shapes: box on the ground, cylinder, sphere, a binary STL
# by package:// and an OBJ on a merged link (interpreted: no build).
gen animate eom-gen/tests/urdf/visual_pkg/robots/visuals.urdf --interpret \
    --q0 1.2 --t-end 2 -o "$out/visuals.html"
check visuals
# A cable's deformed shape: the crane's rope (ANCF nodes, their line) on
# its rigid boom.
gen animate models/ancf/crane_rope.ron --t-end 1 -o "$out/crane.html"
check crane
# A flexible body's deformed shape: the hub and beam (floating frame,
# 4 modes) with its first mode excited; and at t = 0.5 s the beam drawn
# at 1× and 10× its deformation (`#deform=`) differs: the bending is drawn.
gen animate models/hub_beam.ron --interpret --q0 0,0.02,0,0,0 --t-end 1 -o "$out/hub_beam.html"
check hub_beam
shot "$out/hub_beam.html" "0.5&deform=1" "$out/hub-x1.png"
shot "$out/hub_beam.html" "0.5&deform=10" "$out/hub-x10.png"
python3 "$here/png_check.py" "$out/hub-x1.png" "$out/hub-x10.png"
echo "hub_beam: the beam's bending is drawn"
# Contacts flash on impact: the bouncing ball's first impact is at
# t = √(2·1 m/9.81 m/s²) = 0.4515 s; a red halo at t = 0.5, none at 0.3.
gen animate models/bouncing_ball.ron --interpret --t-end 1 -o "$out/ball.html"
shot "$out/ball.html" 0.5 "$out/ball-impact.png"
shot "$out/ball.html" 0.3 "$out/ball-before.png"
python3 "$here/png_check.py" --flash "$out/ball-impact.png" "$out/ball-before.png"
echo "ball: the impact flashes"
