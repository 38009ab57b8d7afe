#!/usr/bin/env bash
# eom on every robot of example-robot-data, against Pinocchio (issue 15).
# See README.md.
#
#   bash bench/robots/run.sh [compare.py options: --only STEM ... --compile all|STEM ... --states N ...]
#
# 1. installs Pinocchio (`pin`) and `example-robot-data` from PyPI into a venv
#    ($EOM_ROBOTS_VENV, default /tmp/eom-robots-venv; versions pinned in
#    requirements.txt, with the C++ headers of Eigen and urdfdom);
# 2. builds eom-gen (release, one job, niced);
# 3. compiles aba_timing.cpp (Pinocchio header-only, -O3 -march=native) for
#    the ns-per-call comparison;
# 4. runs compare.py, niced: a progress line per robot, the table in
#    bench/results/robots.md (rows as JSON in bench/results/robots.json).
#
# Compiled code goes to $EOM_CACHE_DIR (default target/eom-cache of this
# checkout); a fresh cache gives honest compile times.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="${EOM_ROBOTS_VENV:-/tmp/eom-robots-venv}"
bin="${CARGO_TARGET_DIR:-$root/target}/release"
work="${EOM_ROBOTS_WORK:-/tmp/eom-robots-work}"
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
export EOM_CACHE_DIR="${EOM_CACHE_DIR:-$root/target/eom-cache}"
mkdir -p "$work"

# 1. Pinocchio and the robots.
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/pip" install -q -r "$here/requirements.txt"
site="$("$venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
prefix="$site/cmeel.prefix"
robots="$prefix/share/example-robot-data/robots"
[ -d "$robots" ] || { echo "missing from the wheels: $robots" >&2; exit 1; }

# 2. eom-gen.
(cd "$root" && nice -n 10 cargo build -q --release -p eom-cli --bin eom-gen)

# 3. The C++ timing program (only if missing or older than its source).
aba="$work/aba_timing"
if [ ! -x "$aba" ] || [ "$here/aba_timing.cpp" -nt "$aba" ]; then
    echo "compiling $aba (about 2 minutes) …" >&2
    nice -n 10 g++ -O3 -march=native -DNDEBUG -std=c++17 \
        -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 \
        -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12 \
        -I"$prefix/include" -I"$prefix/include/eigen3" -I"$prefix/include/urdfdom_headers" \
        -I"$prefix/include/urdfdom" \
        "$here/aba_timing.cpp" -o "$aba" \
        -L"$prefix/lib" -Wl,-rpath,"$prefix/lib" -lurdfdom_model 2> "$aba-build.log" \
        || { cat "$aba-build.log" >&2; exit 1; }
fi

# 4. Compare, time, tabulate (after building the runtime into the cache once,
# so that the first robot's compile time is its own).
"$bin/eom-gen" eval "$root/models/pendulum.ron" --json > /dev/null
nice -n 10 "$venv/bin/python" "$here/compare.py" --eom "$bin/eom-gen" --robots "$robots" \
    --work "$work" --aba "$aba" --out "$root/bench/results/robots.md" "$@"
