#!/bin/sh
# Sweep throughput of models with cables (BENCHMARKS.md "Parameter
# sweeps"): cases per second on 1 and 2 threads of
#  - cables alone: models/ancf/pendulum.ron (a 16-element Cable2D rod
#    pinned at one end, falling from horizontal) with its Young's modulus
#    made a parameter `E`, 40 values;
#  - mixed: models/ancf/pendulum_rod.ron (the 8-element rod on a rigid
#    link), 40 values of the rod's length `L`;
# generalized-α, fixed step 1e-3 s, 0.5 s each. The mean run time per case
# is the mean of the results' `cpu_s` column.
#   EOM_GEN=target/release/eom-gen sh bench/sweep/cables.sh
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
gen=${EOM_GEN:-$root/target/release/eom-gen}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
sed -e 's/young: 0.7e6,/young: "E",/' \
    -e 's/    gravity: (0, -9.81, 0),/    gravity: (0, -9.81, 0),\n    parameters: [(name: "E", value: 0.7e6, doc: "Young'"'"'s modulus, Pa")],/' \
    "$root/models/ancf/pendulum.ron" >"$out/pendulum_e.ron"
mean_cpu() { # mean of the cpu_s column of DIR/results.csv
    python3 -c 'import csv,sys; r=list(csv.DictReader(open(sys.argv[1]))); n=len(r); print("%.2f ms mean run, %d/%d finished" % (1e3*sum(float(x["cpu_s"]) for x in r)/n, sum(x["stop"]=="finished" for x in r), n))' "$1/results.csv"
}
for jobs in 1 2; do
    "$gen" sweep "$out/pendulum_e.ron" --param E=0.5e6:2.45e6:0.05e6 --t-end 0.5 --jobs "$jobs" --out "$out/alone$jobs"
    mean_cpu "$out/alone$jobs"
    "$gen" sweep "$root/models/ancf/pendulum_rod.ron" --param L=1.0:1.39:0.01 --t-end 0.5 --jobs "$jobs" --out "$out/mixed$jobs"
    mean_cpu "$out/mixed$jobs"
done
