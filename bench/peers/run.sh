#!/usr/bin/env bash
# eom against Pinocchio and MuJoCo, side by side (issue 8). See README.md.
#
#   bash bench/peers/run.sh [--states N] [--reps N] [--seed S] [--check K] [--only MODEL ...]
#
# Installs the peers, builds eom-gen and the chain models (setup.sh),
# compiles the C++ timing program against the headers and libraries inside
# the wheels, and runs peers.py, which prints the table and writes
# bench/results/peers.csv.
set -euo pipefail
source "$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/setup.sh"

exe="$out/peers"
compile_peer "$here/peers.cpp" "$exe"

# Check, time, tabulate.
cd "$here"
"$out/venv/bin/python" peers.py --eom "$bin/eom-gen" --peers "$exe" \
    --models-dir "$out/models" --root "$root" --csv "$root/bench/results/peers.csv" \
    --deriv-csv "$root/bench/results/peers_derivatives.csv" "$@"
