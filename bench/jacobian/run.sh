#!/usr/bin/env bash
# Work-precision of RADAU5 with the generated Jacobian against forward
# differences (issue #27), on stiff models, compiled (release eom-gen, the
# cached model crates): for each tolerance rtol = atol, the error of the end
# state against a reference run (RADAU5, rtol = atol = 1e-13, generated
# Jacobian), the CPU time of the integration (the report's `cpu_s`, median
# of 5 runs), steps and right-hand sides.
#
#   bench/jacobian/run.sh            # prints a Markdown table per model
#
# Models: the double pendulum with a stiff, overdamped elbow spring
# (k = 1e5 N m/rad, c = 1e4 N m s), and arm7 with a stiff spring-damper on
# every joint (k = 1e4, c = 10), and Andrews' squeezing mechanism as the
# index-3 DAE (`--constraints index3`; the constraints' curvature term by
# differences of the generated J). Models with quaternions, and loops kept by
# the other methods, have no generated Jacobian (`--jacobian generated`
# refuses); cables run generalized-α on the elements' generated kernels.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$root/target/jacobian"
mkdir -p "$out"
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
export EOM_CACHE_DIR="${EOM_CACHE_DIR:-$root/target/eom-cache}"
cargo build -q --release -p eom-cli --manifest-path "$root/Cargo.toml"
bin="${CARGO_TARGET_DIR:-$root/target}/release/eom-gen"

sed 's|    outputs: \[|    forces: [JointSpringDamper(name: "s", joint: "elbow", stiffness: 1e5, damping: 1e4, rest: 0)],\n    outputs: [|; s/name: "double_pendulum"/name: "stiff_double_pendulum"/' \
    "$root/models/double_pendulum.ron" > "$out/stiff_double_pendulum.ron"
springs=""
for j in $(grep -o 'name: "j[0-9]"' "$root/models/arm7.ron" | grep -o 'j[0-9]'); do
    springs="$springs JointSpringDamper(name: \"s_$j\", joint: \"$j\", stiffness: 1e4, damping: 10, rest: 0),"
done
python3 - "$root/models/arm7.ron" "$out/stiff_arm7.ron" "$springs" <<'PY'
import re, sys
src, dst, springs = sys.argv[1], sys.argv[2], sys.argv[3]
text = open(src).read().replace('name: "arm7"', 'name: "stiff_arm7"', 1)
if 'forces: [' in text:
    text = text.replace('forces: [', 'forces: [' + springs, 1)
else:
    text = re.sub(r'\n\)\s*$', '\n    forces: [' + springs + '],\n)\n', text)
open(dst, 'w').write(text)
PY

cp "$root/models/andrews.ron" "$out/andrews.ron"

run() { # model t_end tol jacobian [flags] -> JSON
    "$bin" simulate "$1" --t-end "$2" --integrator radau5 --rtol "$3" --atol "$3" \
        --jacobian "$4" --max-steps 10000000 --json ${5:-}
}
for case in "stiff_double_pendulum 1 1e-13" "stiff_arm7 1 1e-13" "andrews 0.03 1e-12 --constraints=index3"; do
    set -- $case
    model="$out/$1.ron"
    flags="${4:-}"
    run "$model" "$2" "$3" generated "$flags" > "$out/$1.ref.json"
    echo
    echo "### $1, t_end = $2 s $flags (reference: radau5 at $3, generated)"
    echo
    echo "| rtol = atol | Jacobian | error (max abs, q and u) | cpu (ms, median of 5) | steps | rejected | right-hand sides | Jacobians |"
    echo "|---|---|---|---|---|---|---|---|"
    for tol in 1e-4 1e-6 1e-8 1e-10; do
        for jac in generated differences; do
            for k in 1 2 3 4 5; do run "$model" "$2" "$tol" "$jac" "$flags" > "$out/$1.$tol.$jac.$k.json"; done
            python3 - "$out/$1.ref.json" "$out"/"$1.$tol.$jac".*.json <<PY
import json, statistics, sys
ref = json.load(open(sys.argv[1]))
runs = [json.load(open(f)) for f in sys.argv[2:]]
r = runs[0]
err = max(abs(a - b) for a, b in zip(ref["q"] + ref["u"], r["q"] + r["u"]))
cpu = statistics.median(x["cpu_s"] for x in runs) * 1e3
s = r["stats"]
print(f"| $tol | {s.get('jacobian')} | {err:.2e} | {cpu:.3f} | {s['steps']} | {s['rejected']} | {s['rhs_evals']} | {s['jacobian_evals']} |")
PY
        done
    done
done
