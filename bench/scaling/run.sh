#!/usr/bin/env bash
# Scaling study (issue 8): for spatial and planar n-link chains
# (eom_gen::model::builder::n_link_chain), the generation time, generated
# source size, operation counts, rustc release compile time of the
# generated crate, and ns per call of the compiled forward dynamics.
#
#   bash bench/scaling/run.sh [N ...]        (default: 5 10 20 50 100 200)
#
# Writes bench/results/scaling.csv and prints a Markdown table. Compile
# times are wall-clock times of `cargo build --release` of a fresh cached
# crate whose dependencies are already built (one cache, warmed first), one
# job (CARGO_BUILD_JOBS=1): the 200-link chain takes minutes.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="$root/target/scaling"
mkdir -p "$out" "$root/bench/results"
export CARGO_BUILD_JOBS="${CARGO_BUILD_JOBS:-1}"
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(5 10 20 50 100 200)

(cd "$root" && nice -n 10 cargo build -q --release -p eom-cli --bin eom-gen \
    && nice -n 10 cargo build -q --release -p eom --example build_chain)
gen="$root/target/release/eom-gen"
chain="$root/target/release/examples/build_chain"

csv="$root/bench/results/scaling.csv"
# The nominal rates of the machine at the clock /proc/cpuinfo reports (a VM:
# turbo is not visible): two floating-point additions or multiplications per
# cycle (two FP ports, no FMA) on one lane (scalar), or on the two lanes of
# SSE2, the vector width of the baseline x86-64 target the code is built for.
mhz="$(awk -F: '/cpu MHz/ {gsub(/ /, "", $2); print $2; exit}' /proc/cpuinfo 2>/dev/null || true)"
mhz="${mhz:-0}"
echo "nominal scalar peak: 2 ops/cycle at $mhz MHz" >&2
echo "kind,links,generation_ms,source_bytes,fd_ops,m_ops,id_ops,compile_s,fd_ns,m_ns,id_ns,fd_ops_per_ns,fd_of_scalar_peak,fd_of_sse2_peak" > "$csv"
echo "| chain | links | generation ms | source KiB | FD ops | M ops | ID ops | compile s | FD ns | M ns | ID ns | FD ops/ns | of scalar peak | of SSE2 peak |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
# One cache for all chains, warmed with the pendulum so that the runtime
# and its dependencies are built before any compile time is taken.
cache="$out/cache"
rm -rf "$cache"
EOM_CACHE_DIR="$cache" "$gen" bench "$root/models/pendulum.ron" --per-call --states 1 --reps 1 --json > /dev/null
for kind in spatial planar; do
    for n in "${sizes[@]}"; do
        model="$out/${kind}_chain$n.ron"
        flag=""
        [ "$kind" = planar ] && flag="--planar"
        "$chain" "$n" "$model" $flag 2>/dev/null
        echo "… $kind chain $n" >&2
        stats="$("$gen" stats "$model" --json)"
        # A fresh crate in the warmed cache: only the generated code compiles.
        start=$(date +%s.%N)
        # The first call builds the timing crate (the compile time), with a
        # single state so that the timing itself is negligible.
        EOM_CACHE_DIR="$cache" "$gen" bench "$model" --per-call --states 1 --reps 1 --json > /dev/null
        end=$(date +%s.%N)
        timing="$(EOM_CACHE_DIR="$cache" "$gen" bench "$model" --per-call --json)"
        python3 - "$kind" "$n" "$start" "$end" "$stats" "$timing" "$csv" "$mhz" <<'PY'
import json, sys
kind, n, start, end, stats, timing, csv, mhz = sys.argv[1:]
s, t = json.loads(stats), json.loads(timing)
ops = lambda k: (s["ops"].get(k) or {}).get("total", 0)
compile_s = float(end) - float(start)
row = [kind, n, f'{s["generation_ms"]:.1f}', s["source_bytes"], ops("forward_dynamics"),
       ops("mass_matrix"), ops("inverse_dynamics"), f"{compile_s:.1f}",
       f'{t["forward_dynamics_ns"]:.1f}', f'{t["mass_matrix_ns"]:.1f}', f'{t["inverse_dynamics_ns"]:.1f}']
rate = ops("forward_dynamics") / t["forward_dynamics_ns"]
peak = 2 * float(mhz) / 1000
share = f"{100 * rate / peak:.0f} % | {50 * rate / peak:.0f} %" if peak > 0 else "- | -"
row += [f"{rate:.3f}", f"{rate / peak:.3f}" if peak > 0 else "", f"{rate / peak / 2:.3f}" if peak > 0 else ""]
open(csv, "a").write(",".join(map(str, row)) + "\n")
print(f'| {kind} | {n} | {s["generation_ms"]:.1f} | {s["source_bytes"] / 1024:.0f} | {ops("forward_dynamics")} | '
      f'{ops("mass_matrix")} | {ops("inverse_dynamics")} | {compile_s:.1f} | {t["forward_dynamics_ns"]:.0f} | '
      f'{t["mass_matrix_ns"]:.0f} | {t["inverse_dynamics_ns"]:.0f} | {rate:.2f} | {share} |')
PY
    done
done
echo "wrote $csv" >&2
