#!/usr/bin/env bash
# Cost of contact handling in a compiled run (issue #26), from the runs'
# own CPU time (`cpu_s`: the integration alone) and counters; minimum of
# REPS runs each.
#  - event location per step: the swinging arm (eom-gen/tests/urdf/
#    swing_arm.urdf, 4 joint-limit rows watched) before its first impact,
#    with its limits and without (--no-urdf-limits), same steps;
#  - one impact event: the bouncing ball (models/bouncing_ball.ron) over
#    4 s (its impacts) against the ball with the floor far below over the
#    same span: (CPU with - CPU without) / impacts; it includes the
#    location, the impact map and the integrator's restart.
set -euo pipefail
bin="${1:-eom-gen}"
reps="${REPS:-20}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$root"
field() { python3 -c "import json,sys; r=json.load(sys.stdin); print($1)"; }
best() { # best CPU (s) and the steps and events of REPS runs of "$@"
    local b=1e9 out
    for _ in $(seq "$reps"); do
        out="$("$bin" simulate "$@" --json)"
        b="$(python3 -c "print(min($b, $(echo "$out" | field 'r["cpu_s"]')))")"
    done
    echo "$b $(echo "$out" | field 'r["stats"]["steps"]') $(echo "$out" | field 'len(r.get("contact_events", []))')"
}
arm=eom-gen/tests/urdf/swing_arm.urdf
"$bin" simulate "$arm" --t-end 0.1 --json > /dev/null
"$bin" simulate "$arm" --no-urdf-limits --t-end 0.1 --json > /dev/null
read -r c1 s1 e1 <<< "$(best "$arm" --t-end 0.15 --rtol 1e-8 --atol 1e-10)"
read -r c0 s0 e0 <<< "$(best "$arm" --no-urdf-limits --t-end 0.15 --rtol 1e-8 --atol 1e-10)"
echo "swing arm, 0.15 s: with limits ${c1} s, ${s1} steps, ${e1} events; without ${c0} s, ${s0} steps"
python3 -c "print(f'event location: {($c1 - $c0) / $s1 * 1e6:.2f} us per step (4 rows), run {$c0 / $s0 * 1e6:.2f} us per step without')"
far="$(mktemp -d)/ball_far.ron"
sed 's/normal: (0, 0, 1)/point: (0, 0, -100), normal: (0, 0, 1)/' models/bouncing_ball.ron > "$far"
"$bin" simulate "$far" --t-end 0.1 --json > /dev/null
read -r c1 s1 e1 <<< "$(best models/bouncing_ball.ron --t-end 4 --rtol 1e-10 --atol 1e-12)"
read -r c0 s0 e0 <<< "$(best "$far" --t-end 4 --rtol 1e-10 --atol 1e-12)"
echo "bouncing ball, 4 s: ${c1} s, ${s1} steps, ${e1} events; free fall ${c0} s, ${s0} steps"
python3 -c "print(f'one contact event: {($c1 - $c0) / $e1 * 1e6:.1f} us')"
