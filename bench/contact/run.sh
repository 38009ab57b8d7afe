#!/usr/bin/env bash
# The contact benchmarks of BENCHMARKS.md ("Impacts"), issue #26:
#  1. the bouncing ball side by side with MuJoCo (bouncing_ball_mujoco.py);
#  2. the cost of event location per step and of one impact event (costs.sh).
# MuJoCo comes from PyPI (the version pinned in bench/peers/requirements.txt)
# into a venv under the target directory, as bench/peers/setup.sh installs the
# peers; eom-gen is built in release. One build job, lower priority.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
target="${CARGO_TARGET_DIR:-$root/target}"
venv="$target/peers/venv"
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/pip" install -q "$(grep '^mujoco==' "$root/bench/peers/requirements.txt")" \
    "$(grep '^numpy==' "$root/bench/peers/requirements.txt")"
(cd "$root" && nice -n 10 cargo build -q --release -p eom-cli --bin eom-gen)
bin="$target/release/eom-gen"
cd "$root"
# The first run builds the compiled model into the cache (not timed).
"$bin" simulate models/bouncing_ball.ron --t-end 0.1 --json > /dev/null
"$venv/bin/python" "$here/bouncing_ball_mujoco.py" "$bin"
echo
"$here/costs.sh" "$bin"
