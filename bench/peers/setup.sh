# Shared by run.sh and run_wp.sh (sourced, not run): installs the peers from
# PyPI into target/peers/venv (versions pinned in requirements.txt), builds
# eom-gen and the chain models, and defines `compile_peer SRC EXE`, which
# compiles a C++ program against the headers and libraries inside the
# wheels. Builds use one job and a lower priority (the machine is shared).
# Sets: here, root, out, bin (cargo's release directory), site, prefix, mj.

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$root/target/peers"
bin="${CARGO_TARGET_DIR:-$root/target}/release"
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
(cd "$root" && nice -n 10 cargo build -q --release -p eom-cli --bin eom-gen \
    && nice -n 10 cargo build -q --release -p eom --example build_chain)
for n in 5 10 50; do
    "$bin/examples/build_chain" "$n" "$out/models/planar_chain$n.ron" --planar 2>/dev/null
    "$bin/examples/build_chain" "$n" "$out/models/spatial_chain$n.ron" 2>/dev/null
done
"$bin/examples/build_chain" 200 "$out/models/spatial_chain200.ron" 2>/dev/null

# 3. compile_peer SRC EXE: Pinocchio header-only and MuJoCo's libmujoco,
# -O3 -march=native (see the head of peers.cpp for why the URDF is read with
# urdfdom rather than libpinocchio_parsers); only if EXE is missing or older
# than SRC, the shared header or this file.
compile_peer() {
    local src="$1" exe="$2"
    if [ ! -x "$exe" ] || [ "$src" -nt "$exe" ] || [ "$here/pinocchio_urdf.hpp" -nt "$exe" ] \
        || [ "$here/setup.sh" -nt "$exe" ]; then
        # (GCC warns about Eigen's AVX-512 stores in Pinocchio's composite
        # joints, not used here; the warnings go to EXE-build.log.)
        echo "compiling $exe (about 2 minutes) …" >&2
        nice -n 10 g++ -O3 -march=native -DNDEBUG -std=c++17 \
            -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 \
            -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12 \
            -I"$prefix/include" -I"$prefix/include/eigen3" -I"$prefix/include/urdfdom_headers" \
            -I"$prefix/include/urdfdom" -I"$mj/include" \
            "$src" -o "$exe" \
            -L"$prefix/lib" -Wl,-rpath,"$prefix/lib" \
            -lurdfdom_model \
            "$libmujoco" -Wl,-rpath,"$mj" 2> "$exe-build.log" \
            || { cat "$exe-build.log" >&2; exit 1; }
    fi
}
