#!/usr/bin/env bash
# eom against Pinocchio and MuJoCo, side by side (issue 8). See README.md.
#
#   bash bench/peers/run.sh [--states N] [--reps N] [--seed S] [--check K] [--only MODEL ...]
#
# Installs the peers from PyPI into target/peers/venv (versions pinned in
# requirements.txt), builds eom-gen and the chain models, compiles the C++
# timing program against the headers and libraries inside the wheels, and
# runs peers.py, which prints the table and writes bench/results/peers.csv.
# Builds use one job and a lower priority (the machine is shared).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$root/target/peers"
mkdir -p "$out/models"
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
export EOM_CACHE_DIR="${EOM_CACHE_DIR:-$root/target/eom-cache}"

# 1. The peers, from PyPI.
if [ ! -x "$out/venv/bin/python" ]; then
    python3 -m venv "$out/venv"
fi
"$out/venv/bin/pip" install -q -r "$here/requirements.txt"
site="$("$out/venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
prefix="$site/cmeel.prefix"
mj="$site/mujoco"
libmujoco="$(ls "$mj"/libmujoco.so* | head -n 1)"
for need in "$prefix/include/pinocchio/algorithm/aba.hpp" "$prefix/include/eigen3/Eigen/Core" \
    "$prefix/include/urdfdom_headers/urdf_model/model.h" "$mj/include/mujoco/mujoco.h" "$libmujoco"; do
    [ -e "$need" ] || { echo "missing from the wheels: $need" >&2; exit 1; }
done

# 2. eom-gen and the chains (eom_gen::model::builder::n_link_chain).
(cd "$root" && nice -n 10 cargo build -q --release -p eom-gen --bin eom-gen \
    && nice -n 10 cargo build -q --release -p eom --example build_chain)
for n in 5 10 50; do
    "$root/target/release/examples/build_chain" "$n" "$out/models/planar_chain$n.ron" --planar 2>/dev/null
    "$root/target/release/examples/build_chain" "$n" "$out/models/spatial_chain$n.ron" 2>/dev/null
done

# 3. The C++ timing program: Pinocchio header-only and MuJoCo's libmujoco,
# -O3 -march=native (see the head of peers.cpp for why the URDF is read with
# urdfdom rather than libpinocchio_parsers).
exe="$out/peers"
if [ ! -x "$exe" ] || [ "$here/peers.cpp" -nt "$exe" ] || [ "$here/run.sh" -nt "$exe" ]; then
    # (GCC warns about Eigen's AVX-512 stores in Pinocchio's composite
    # joints, not used here; the warnings go to peers-build.log.)
    echo "compiling $exe (about 2 minutes) …" >&2
    nice -n 10 g++ -O3 -march=native -DNDEBUG -std=c++17 \
        -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 \
        -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12 \
        -I"$prefix/include" -I"$prefix/include/eigen3" -I"$prefix/include/urdfdom_headers" \
        -I"$prefix/include/urdfdom" -I"$mj/include" \
        "$here/peers.cpp" -o "$exe" \
        -L"$prefix/lib" -Wl,-rpath,"$prefix/lib" \
        -lurdfdom_model \
        "$libmujoco" -Wl,-rpath,"$mj" 2> "$out/peers-build.log" \
        || { cat "$out/peers-build.log" >&2; exit 1; }
fi

# 4-5. Check, time, tabulate.
cd "$here"
"$out/venv/bin/python" peers.py --eom "$root/target/release/eom-gen" --peers "$exe" \
    --models-dir "$out/models" --root "$root" --csv "$root/bench/results/peers.csv" "$@"
