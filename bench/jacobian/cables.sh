#!/usr/bin/env bash
# Work-precision of generalized-α on the falling ANCF pendulum with the
# elements' generated tangent against forward differences of their forces
# (issue #27): `simulate --jacobian generated|differences`, release eom-gen.
# Fixed steps and step control; the error is the largest distance of the
# tip from a reference run (fixed h = 1e-4 s, generated tangent) over the
# whole run, sampled every 10 ms; the CPU time is the report's `cpu_s`,
# median of 5 runs.
#
#   bench/jacobian/cables.sh         # prints a Markdown table
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$root/target/jacobian"
mkdir -p "$out"
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
cargo build -q --release -p eom-cli --manifest-path "$root/Cargo.toml"
bin="${CARGO_TARGET_DIR:-$root/target}/release/eom-gen"
model="$root/models/ancf/pendulum.ron"
t_end=1

run() { # name jacobian step-flags... -> $out/NAME.json and .csv
    local name=$1 jac=$2
    shift 2
    "$bin" simulate "$model" --t-end "$t_end" --jacobian "$jac" --every 0.01 \
        --csv "$out/$name.csv" --json "$@" > "$out/$name.json"
}
run ancf_ref generated --dt 1e-4

echo "| run | tangent | largest tip error (m) | cpu (ms, median of 5) | steps (rejected) | Newton iterations | force evaluations | factorisations |"
echo "|---|---|---|---|---|---|---|---|"
for case in "dt 4e-3" "dt 2e-3" "dt 1e-3" "dt 5e-4" "rtol 1e-3" "rtol 1e-4" "rtol 1e-5" "rtol 1e-6"; do
    set -- $case
    if [ "$1" = dt ]; then flags="--dt $2"; else flags="--dt 1e-3 --rtol $2 --atol $2"; fi
    for jac in generated differences; do
        for k in 1 2 3 4 5; do run "ancf.$1.$2.$jac.$k" "$jac" $flags; done
        python3 - "$out/ancf_ref.csv" "$out"/"ancf.$1.$2.$jac".*.json <<PY
import csv, json, statistics, sys
def tip(path):
    rows = list(csv.DictReader(open(path)))
    last = max(int(k.split(".")[1][4:]) for k in rows[0] if k.startswith("rod.node"))
    return {round(float(r["t"]), 6): (float(r[f"rod.node{last}.x"]), float(r[f"rod.node{last}.y"])) for r in rows}
ref = tip(sys.argv[1])
runs = [json.load(open(f)) for f in sys.argv[2:]]
mine = tip(sys.argv[2].replace(".json", ".csv"))
err = max(((mine[t][0] - ref[t][0]) ** 2 + (mine[t][1] - ref[t][1]) ** 2) ** 0.5 for t in ref if t in mine)
cpu = statistics.median(x["cpu_s"] for x in runs) * 1e3
s = runs[0]["stats"]
print(f"| $1 = $2 | {s.get('jacobian')} | {err:.2e} | {cpu:.1f} | {s['accepted']} ({s['rejected']}) | {s['newton_iterations']} | {s['rhs_evals']} | {s['jacobian_evals']} |")
PY
    done
done
