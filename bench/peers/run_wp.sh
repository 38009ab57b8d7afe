#!/usr/bin/env bash
# Work-precision of eom against MuJoCo RK4 and Pinocchio + DOP853 (issue 8).
# See README.md.
#
#   bash bench/peers/run_wp.sh [--only MODEL ...] [--reps N] [--budget S] [--ref-tol T] ...
#
# Installs the peers, builds eom-gen and the chain models (setup.sh),
# compiles peers_wp.cpp, and runs peers_wp.py, which prints a table per
# case (also into bench/results/peers_wp.md) and writes
# bench/results/peers_wp.csv, then draws bench/results/peers_wp-CASE.svg
# (eom-gen bench --plot). The runs are niced.
set -euo pipefail
source "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/setup.sh"

exe="$out/peers_wp"
compile_peer "$here/peers_wp.cpp" "$exe"

cd "$here"
nice -n 10 "$out/venv/bin/python" peers_wp.py --eom "$bin/eom-gen" --peers-wp "$exe" \
    --models-dir "$out/models" --root "$root" --csv "$root/bench/results/peers_wp.csv" "$@" \
    | tee "$root/bench/results/peers_wp.md"

# The work-precision diagrams, one per case (eom-gen bench --plot).
"$bin/eom-gen" bench --plot "$root/bench/results/peers_wp_plot.csv" \
    --svg "$root/bench/results/peers_wp.svg" --error-label "largest |q - q_ref| at the end, rad"
