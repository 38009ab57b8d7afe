#!/bin/sh
# Ensembles and sweeps in SIMD lanes (#28, #29): BENCHMARKS.md "Ensembles
# and sweeps in lanes". Needs a release eom-gen for the sweep part:
#   cargo build --release -p eom-cli
#   EOM=target/release/eom-gen sh bench/lanes/run.sh [ensemble|sweep]
# The machine is shared: every figure is the median of REPS runs (default
# 3) of **CPU time** (user + sys of the process, /usr/bin/time), which a
# loaded machine inflates far less than wall time; compare ratios within
# one run.
set -eu
EOM=${EOM:-target/release/eom-gen}
REPS=${REPS:-3}
export EOM_CACHE_DIR=${EOM_CACHE_DIR:-target/eom-cache}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

# Ensemble throughput: the lanes' runner of MODEL (built by one `simulate
# --ensemble` run, whose members' drawn states it then integrates) run
# directly on one thread with W = 1, 4, 8 states per call: state-steps per
# CPU second and CPU ns per state per right-hand side.
ensemble() { # model t_end n integrator [--native]
  "$EOM" simulate "models/$1.ron" --t-end 0.01 --ensemble "$3" --seed 1 \
    --perturb q=0.05,u=0.05 --integrator "$4" ${5:-} --json > "$TMP/m.json" 2>/dev/null || true
  dir="$EOM_CACHE_DIR/target/release"
  [ -n "${5:-}" ] && dir="$EOM_CACHE_DIR/target-flags/release"
  exe=$(ls -t "$dir"/eom-lanes-"$1"-* | grep -v '\.d$' | head -1)
  for w in 1 4 8; do
    python3 - "$TMP/m.json" "$4" "$2" "$w" > "$TMP/req.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
rows = m["members_results"]
names = [f"y{i}" for i in range(len(rows[0]["q0"]) + len(rows[0]["u0"]))]
print(json.dumps({"integrator": sys.argv[2], "rtol": 1e-8, "atol": 1e-10, "dt": 1e-3,
  "t_end": float(sys.argv[3]), "max_steps": 10**7, "width": int(sys.argv[4]), "threads": 1,
  "inputs": [], "params": [], "names": names,
  "cases": [{"p": [], "y0": r["q0"] + r["u0"]} for r in rows]}))
PY
    for r in $(seq "$REPS"); do
      /usr/bin/time -f "%U %S" -o "$TMP/t" "$exe" < "$TMP/req.json" > "$TMP/out.json"
      awk '{print $1 + $2}' "$TMP/t"
    done > "$TMP/e"
    s=$(median < "$TMP/e")
    python3 - "$TMP/out.json" "$s" "$1 $4 ${5:-default} W=$w" <<'PY'
import json, sys
r = json.loads(open(sys.argv[1]).read().splitlines()[-1])["results"]
s = float(sys.argv[2]); steps = sum(x["steps"] for x in r); rhs = sum(x["rhs_evals"] for x in r)
fin = sum(1 for x in r if x["stop"] == "finished")
print(f"ensemble {sys.argv[3]}: {len(r)} members ({fin} finished), {steps} steps, {rhs} rhs, "
      f"{s:.2f} CPU s: {steps / s:.3e} state-steps/s, {s / rhs * 1e9:.0f} ns per state per rhs")
PY
  done
}

# Sweep cases per second (the CLI's own figure, wall time) and per CPU
# second: interpreted, compiled one state per call, lanes of 4 and 8.
sweep() { # model param t_end
  for j in 1 2; do
    for mode in interpreted "--compiled --lanes 1" "--compiled --lanes 4" "--compiled --lanes 8"; do
      extra=""; [ "$mode" = interpreted ] || extra=$mode
      # One run to build the cached crate, then REPS timed.
      "$EOM" sweep "models/$1.ron" --param "$2" --t-end "$3" --jobs "$j" $extra --out "$TMP/s" >/dev/null 2>&1 || true
      for r in $(seq "$REPS"); do
        /usr/bin/time -f "%U %S" -o "$TMP/t" "$EOM" sweep "models/$1.ron" --param "$2" --t-end "$3" \
          --jobs "$j" $extra --out "$TMP/s" > "$TMP/o" 2>/dev/null || true
        n=$(sed -n 's/.*: \([0-9]*\) cases.*/\1/p' "$TMP/o")
        w=$(sed -n 's/.*(\([0-9.]*\) cases\/s.*/\1/p' "$TMP/o")
        awk -v n="$n" -v w="$w" '{printf "%s %.1f\n", w, n / ($1 + $2)}' "$TMP/t"
      done > "$TMP/sw"
      a=$(awk '{print $1}' "$TMP/sw" | median); b=$(awk '{print $2}' "$TMP/sw" | median)
      echo "sweep $1 jobs=$j $mode: $a cases/s (wall), $b cases per CPU s"
    done
  done
}

# The compiled sweep's runner alone (what `sweep --compiled` spends past
# the CLI's per-case check): the cases of `sweep MODEL --param NAME=a:b:step`
# (the runner built by one `sweep --compiled` run), W = 1, 4, 8, on 1 and
# 2 threads; cases per CPU second and per wall second.
sweep_runner() { # model name a b step t_end
  "$EOM" sweep "models/$1.ron" --param "$2=$3:$4:$5" --t-end "$6" --compiled --lanes 1 \
    --out "$TMP/s" >/dev/null 2>&1 || true
  "$EOM" simulate "models/$1.ron" --t-end 0.01 --ensemble 1 --json > "$TMP/m.json" 2>/dev/null || true
  exe=$(ls -t "$EOM_CACHE_DIR"/target/release/eom-lanes-"$1"-* | grep -v '\.d$' | head -1)
  for th in 1 2; do
    for w in 1 4 8; do
      python3 - "$TMP/m.json" "$2" "$3" "$4" "$5" "$6" "$w" "$th" > "$TMP/req.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))["members_results"][0]
a, b, st = map(float, sys.argv[3:6]); n = int(round((b - a) / st)) + 1
print(json.dumps({"integrator": "dopri5", "rtol": 1e-8, "atol": 1e-10, "dt": 1e-3,
  "t_end": float(sys.argv[6]), "max_steps": 100000, "width": int(sys.argv[7]),
  "threads": int(sys.argv[8]), "inputs": [], "params": [sys.argv[2]],
  "names": ["y"] * (len(m["q0"]) + len(m["u0"])),
  "cases": [{"p": [a + k * st], "y0": m["q0"] + m["u0"]} for k in range(n)]}))
PY
      n=$(python3 -c "import json; print(len(json.load(open('$TMP/req.json'))['cases']))")
      for r in $(seq "$REPS"); do
        /usr/bin/time -f "%e %U %S" -o "$TMP/t" "$exe" < "$TMP/req.json" > /dev/null
        awk -v n="$n" '{printf "%.1f %.1f\n", n / $1, n / ($2 + $3)}' "$TMP/t"
      done > "$TMP/sw"
      a1=$(awk '{print $1}' "$TMP/sw" | median); b1=$(awk '{print $2}' "$TMP/sw" | median)
      echo "sweep runner $1 threads=$th W=$w: $a1 cases/s (wall), $b1 cases per CPU s"
    done
  done
}

if [ "${1:-all}" = runner ]; then
  sweep_runner pendulum l 0.5 2.4995 0.0005 10
  sweep_runner arm7 g 1 10.99 0.01 1
  exit 0
fi
if [ "${1:-all}" != sweep ]; then
  for native in "" --native; do
    ensemble pendulum 10 4096 dopri5 $native
    ensemble pendulum 10 256 rk4 $native
    ensemble arm7 2 1024 dopri5 $native
    ensemble arm7 2 256 rk4 $native
  done
fi
if [ "${1:-all}" != ensemble ]; then
  sweep pendulum l=0.5:2.495:0.005 10
  sweep arm7 g=1:10.9:0.1 1
fi
