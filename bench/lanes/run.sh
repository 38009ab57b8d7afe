#!/bin/sh
# Ensembles and sweeps in SIMD lanes (#28, #29): BENCHMARKS.md "Ensembles
# in lanes". Needs a release eom-gen:
#   cargo build --release -p eom-cli
#   EOM=target/release/eom-gen sh bench/lanes/run.sh > bench/results/lanes.txt
# Every figure is the median of REPS runs (default 5); the machine may be
# shared, so compare the ratios within one run.
set -eu
EOM=${EOM:-target/release/eom-gen}
REPS=${REPS:-5}
export EOM_CACHE_DIR=${EOM_CACHE_DIR:-target/eom-cache}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

# Ensemble throughput: N members of MODEL to T s with dopri5 (rtol 1e-8,
# atol 1e-10, per-lane control) or rk4 (dt 1e-3), W states per call, one
# thread per pack. From the runner's own pack times (`integration_s`):
# state-steps per second and ns per state per right-hand side.
ensemble() { # model t_end n integrator [--native]
  for w in 1 4 8; do
    for r in $(seq "$REPS"); do
      "$EOM" simulate "models/$1.ron" --t-end "$2" --ensemble "$3" --seed 1 \
        --perturb q=0.05,u=0.05 --integrator "$4" --dt 1e-3 --lanes "$w" ${5:-} --json 2>/dev/null |
        python3 -c 'import json,sys; v=json.load(sys.stdin); print(v["integration_s"], v["steps"], v["rhs_evals"], v["finished"])'
    done > "$TMP/e"
    s=$(awk '{print $1}' "$TMP/e" | median)
    read -r _ steps rhs fin < "$TMP/e"
    python3 -c "s=$s; steps=$steps; rhs=$rhs; print(f'ensemble $1 $4 ${5:-} W=$w: $fin finished, {steps} steps, {rhs} rhs, {s:.4f} s: {steps/s:.3e} state-steps/s, {s/rhs*1e9:.1f} ns per state per rhs')"
  done
}

# Sweep cases per second: interpreted, compiled one state per call, lanes.
sweep() { # model param t_end label extra...
  m=$1; p=$2; t=$3; shift 3
  for j in 1 2; do
    for mode in interpreted "--compiled --lanes 1" "--compiled --lanes 4" "--compiled --lanes 8"; do
      extra=""; [ "$mode" = interpreted ] || extra=$mode
      # One run to build the cached crate, then REPS timed.
      "$EOM" sweep "models/$m.ron" --param "$p" --t-end "$t" --jobs "$j" $extra --out "$TMP/s" >/dev/null 2>&1 || true
      for r in $(seq "$REPS"); do
        "$EOM" sweep "models/$m.ron" --param "$p" --t-end "$t" --jobs "$j" $extra --out "$TMP/s" 2>/dev/null |
          sed -n 's/.*(\([0-9.]*\) cases\/s.*/\1/p'
      done | median | sed "s/^/sweep $m jobs=$j $mode: /; s/$/ cases\/s/"
    done
  done
}

# `sh run.sh ensemble` or `sh run.sh sweep` for one part (default both).
if [ "${1:-all}" != sweep ]; then
  for native in "" --native; do
    ensemble pendulum 10 1024 dopri5 $native
    ensemble pendulum 10 1024 rk4 $native
    ensemble arm7 2 256 dopri5 $native
    ensemble arm7 2 256 rk4 $native
  done
fi
if [ "${1:-all}" != ensemble ]; then
  sweep pendulum l=0.5:2.495:0.005 10
  sweep arm7 g=1:10.9:0.1 1
fi
