#!/usr/bin/env python3
"""Work-precision of runs with impacts (issue #26): error against CPU time
for several integrators and tolerances.

- The bouncing ball (models/bouncing_ball.ron, e = 0.8, h0 = 1 m): its
  impact times have a closed form, t_1 = sqrt(2 h0/g),
  t_{n+1} = t_n + 2 e^n sqrt(2 g h0)/g; the error is the largest of the
  first N_BALL impact times' errors.
- A URDF arm swinging into its joint limits (eom-gen/tests/urdf/
  swing_arm.urdf, imported with its limits, restitution raised from the
  importer's plastic 0 to E_ARM so that it bounces between them): no closed
  form, so the reference is DOP853 at rtol 1e-13, atol 1e-15, checked
  against RADAU5 at rtol 1e-12; the errors are the largest of the first
  N_ARM impact times' errors (and whether the sequence of contacts struck
  is the reference's) and the error of the time the first sustained
  contact starts (`rest`: the end of a Zeno sequence of bounces).

CPU is the run's own `cpu_s` (the integration, event location and impact
maps; not the start-up or the model's compilation), minimum of REPS runs.

Usage: bench/contact/work_precision.py [EOM_GEN_BINARY]   (REPS=5 default)
"""

import json
import math
import os
import subprocess
import sys
import tempfile

BIN = sys.argv[1] if len(sys.argv) > 1 else "eom-gen"
REPS = int(os.environ.get("REPS", "5"))
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
G, H0, E = 9.81, 1.0, 0.8
N_BALL = 12
T_BALL = 4.5
E_ARM = 0.5
T_ARM = 2.0
N_ARM = 12

ADAPTIVE = [
    (integ, tol)
    for integ in ("dopri5", "dop853", "radau5")
    for tol in (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
]
FIXED = [("rk4", dt) for dt in (1e-2, 1e-3, 1e-4)]


def simulate(model, t_end, integ, tol, atol=None):
    args = [BIN, "simulate", model, "--t-end", str(t_end), "--integrator", integ, "--json"]
    if integ == "rk4":
        args += ["--dt", str(tol), "--max-steps", "10000000"]
    else:
        atol = tol * 1e-2 if atol is None else atol
        args += ["--rtol", str(tol), "--atol", str(atol), "--max-steps", "10000000"]
    best, report = math.inf, None
    for _ in range(REPS):
        out = subprocess.run(args, capture_output=True, text=True, cwd=ROOT)
        if out.returncode not in (0, 3):
            return None, out.stderr.strip().splitlines()[-1] if out.stderr else "failed"
        report = json.loads(out.stdout)
        best = min(best, report["cpu_s"])
    return best, report


def impacts(report):
    return [
        (e["t"], tuple(c["contact"] for c in e["contacts"] if c["impulse"] > 0))
        for e in report.get("contact_events", [])
        if e["kind"] == "impact"
    ]


def ball():
    v0 = math.sqrt(2 * G * H0)
    want = [math.sqrt(2 * H0 / G)]
    for n in range(1, N_BALL):
        want.append(want[-1] + 2 * E**n * v0 / G)
    model = os.path.join(ROOT, "models", "bouncing_ball.ron")
    print(f"## bouncing ball, first {N_BALL} impact times against the closed form")
    print("| integrator | rtol (atol = rtol/100) or dt | steps | impacts | CPU (ms) | max impact-time error (s) |")
    print("|---|---|---|---|---|---|")
    for integ, tol in ADAPTIVE + FIXED:
        cpu, r = simulate(model, T_BALL, integ, tol)
        if cpu is None:
            print(f"| {integ} | {tol:g} | – | – | – | refused: {r} |")
            continue
        got = [t for t, _ in impacts(r)]
        if len(got) < N_BALL:
            err = f"only {len(got)} impacts"
        else:
            err = f"{max(abs(a - b) for a, b in zip(got, want)):.2e}"
        print(
            f"| {integ} | {tol:g} | {r['stats']['steps']} | {len(got)} | {cpu * 1e3:.3f} | {err} |"
        )


def arm_model():
    d = tempfile.mkdtemp()
    path = os.path.join(d, "swing_arm_bouncing.ron")
    urdf = os.path.join(ROOT, "eom-gen", "tests", "urdf", "swing_arm.urdf")
    subprocess.run([BIN, "import", urdf, "-o", path], check=True, capture_output=True)
    text = open(path).read()
    n = text.count("e: 0.0") + text.count("e: 0,") + text.count("e: 0)")
    text = text.replace("e: 0.0", f"e: {E_ARM}").replace("e: 0,", f"e: {E_ARM},").replace(
        "e: 0)", f"e: {E_ARM})"
    )
    if n != 2:
        sys.exit(f"expected the two imported limits with e = 0 in {path}, found {n}")
    open(path, "w").write(text)
    return path


def rest_time(report):
    return next((e["t"] for e in report.get("contact_events", []) if e["kind"] == "rest"), None)


def arm():
    model = arm_model()
    _, ref = simulate(model, T_ARM, "dop853", 1e-13, 1e-15)
    _, chk = simulate(model, T_ARM, "radau5", 1e-12)
    ref_i, chk_i = impacts(ref), impacts(chk)
    agree_t = max(abs(a[0] - b[0]) for a, b in zip(ref_i[:N_ARM], chk_i[:N_ARM]))
    agree_r = abs(rest_time(ref) - rest_time(chk))
    print()
    print(
        f"## swing arm (e = {E_ARM}), {T_ARM} s: reference DOP853 rtol 1e-13 atol 1e-15, "
        f"{len(ref_i)} impacts, {len(ref.get('contact_events', []))} events, first rest at "
        f"{rest_time(ref):.9f} s; the first {N_ARM} impacts: "
        f"{', '.join(f'{t:.6f} {c}' for t, c in ref_i[:N_ARM])}; RADAU5 rtol 1e-12 agrees to "
        f"{agree_t:.1e} s in these and {agree_r:.1e} s in the rest time"
    )
    print(f"| integrator | rtol (atol = rtol/100) or dt | steps | events | CPU (ms) | max error, first {N_ARM} impact times (s) | error of the first rest time (s) |")
    print("|---|---|---|---|---|---|---|")
    for integ, tol in ADAPTIVE + FIXED:
        cpu, r = simulate(model, T_ARM, integ, tol)
        if cpu is None:
            print(f"| {integ} | {tol:g} | – | – | – | refused: {r} | |")
            continue
        got = impacts(r)
        same = all(a[1] == b[1] for a, b in zip(got[:N_ARM], ref_i[:N_ARM]))
        if len(got) < N_ARM or not same:
            terr = f"sequence differs ({len(got)} impacts)"
        else:
            terr = f"{max(abs(a[0] - b[0]) for a, b in zip(got, ref_i[:N_ARM])):.2e}"
        rt = rest_time(r)
        rerr = "no rest" if rt is None else f"{rt - rest_time(ref):+.2e}"
        print(
            f"| {integ} | {tol:g} | {r['stats']['steps']} | {len(r.get('contact_events', []))} "
            f"| {cpu * 1e3:.3f} | {terr} | {rerr} |"
        )


if __name__ == "__main__":
    ball()
    arm()
