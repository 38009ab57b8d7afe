#!/usr/bin/env bash
# Cost of the friction problems of contacts (issue #26) in a compiled run,
# from the runs' own CPU time (`cpu_s`: the integration alone) and
# counters; median of REPS runs each (bench/contact/friction/*.ron).
#  - one impact with friction: a ball bouncing obliquely (ball.ron,
#    e = 0.9) with mu = 0.5 (sticks: leaves rolling), mu = 0.02 (slides
#    through the impacts) and mu = 0 (frictionless), against the same ball
#    with the floor out of reach: (CPU - CPU free) / impacts;
#  - four simultaneous frictional contacts: a box landing flat on its four
#    corners (box4.ron), the same way;
#  - sustained friction per step: a block held on its plane (block.ron),
#    sliding (slip, mu = 0.3), sticking on an incline (theta = 0.3, mu =
#    0.5) and sliding frictionless (mu = 0): CPU per step.
set -euo pipefail
bin="${1:-eom-gen}"
reps="${REPS:-21}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
dir=bench/contact/friction
median() { # median CPU (s), steps, impact events, all events of REPS runs of "$@"
    local out all=""
    for _ in $(seq "$reps"); do
        out="$("$bin" simulate "$@" --json)"
        all="$all $(echo "$out" | python3 -c 'import json,sys; print(json.load(sys.stdin)["cpu_s"])')"
    done
    echo "$out" | python3 -c "
import json, statistics, sys
r = json.load(sys.stdin)
ev = r.get('contact_events', [])
cpu = statistics.median([float(x) for x in '$all'.split()])
print(cpu, r['stats']['steps'], sum(e['kind'] == 'impact' for e in ev), len(ev))"
}
uptime
opts=(--rtol 1e-10 --atol 1e-12)
for model in ${MODELS:-ball box4}; do
    t_end=4
    [ "$model" = box4 ] && t_end=2
    "$bin" simulate "$dir/$model.ron" --t-end 0.1 --json > /dev/null
    read -r c0 s0 _ _ <<< "$(median "$dir/$model.ron" --param floor=-100 --param mu=0 --t-end "$t_end" "${opts[@]}")"
    echo "$model, floor out of reach: ${c0} s, ${s0} steps"
    for mu in 0 0.02 0.5; do
        read -r c s i n <<< "$(median "$dir/$model.ron" --param "mu=$mu" --t-end "$t_end" "${opts[@]}")"
        python3 -c "print(f'$model mu=$mu: {$c*1e3:.3f} ms, $s steps, $i impacts, $n events: {($c - $c0) / max($i, 1) * 1e6:.1f} us per impact (all in)')"
    done
done
"$bin" simulate "$dir/block.ron" --t-end 0.1 --json > /dev/null
for case in "mu=0" "mu=0.3" "mu=0.5 --param theta=0.3 --param v0=0"; do
    # shellcheck disable=SC2086
    read -r c s i n <<< "$(median "$dir/block.ron" --param $case --t-end 0.9 "${opts[@]}")"
    python3 -c "print(f'block $case: {$c*1e3:.3f} ms, $s steps, $n events: {$c / $s * 1e6:.2f} us per step')"
done
