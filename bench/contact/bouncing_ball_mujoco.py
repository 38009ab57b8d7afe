#!/usr/bin/env python3
"""The bouncing ball side by side: eom (exact impacts, located events)
against MuJoCo (soft contact), both against the closed forms (issue #26).

The ball of models/bouncing_ball.ron: mass 1 kg, radius 0.1 m, on a
vertical slider, its lowest point dropped from h0 = 1 m onto the floor
z = 0, g = 9.81 m/s^2, coefficient of restitution e = 0.8. Closed forms:
the n-th rebound reaches e^(2n) h0; the ball comes to rest at
t* = sqrt(2 h0/g) (1 + e)/(1 - e) = 4.0637 s.

MuJoCo has no restitution coefficient: a contact is a spring-damper in
constraint space; in solref's direct form (-k, -b) a linear oscillator
with damping ratio z = b/(2 sqrt k) rebounds with
e = exp(-z pi / sqrt(1 - z^2)), so we ask for e = 0.8 through
z = -ln e / sqrt(pi^2 + ln^2 e) and sweep the time step and the
stiffness k. Measured per
run: the first five rebound heights (apex of z - r between contacts)
against e^(2n) h0, the rest time (the first time after which the ball
never leaves the floor by more than 1e-6 m again) against t*, and CPU time
(process time of the stepping loop; for eom the report's cpu_s, which is
the integration alone, the compiled model).

Usage (from the repository root; bench/contact/run.sh installs MuJoCo and
builds eom-gen):
    python3 bench/contact/bouncing_ball_mujoco.py EOM_GEN_BINARY
"""
import json
import math
import subprocess
import sys
import time

import mujoco

G, H0, E, R, M = 9.81, 1.0, 0.8, 0.1, 1.0
T_REST = math.sqrt(2 * H0 / G) * (1 + E) / (1 - E)
T_END = 5.0
N_HEIGHTS = 5
WANT = [E ** (2 * (n + 1)) * H0 for n in range(N_HEIGHTS)]


def mujoco_xml(dt, stiffness, integrator):
    # solref in MuJoCo's direct form (-stiffness, -damping): the contact's
    # reference acceleration -b v - k r, a linear spring-damper whose
    # rebound is e = exp(-z pi / sqrt(1 - z^2)) for z = b / (2 sqrt(k));
    # solimp near 1 so that the impedance does not soften it further.
    z = -math.log(E) / math.sqrt(math.pi ** 2 + math.log(E) ** 2)
    damping = 2 * z * math.sqrt(stiffness)
    soft = f'solref="-{stiffness} -{damping}" solimp="0.9999 0.9999 0.001"'
    return f"""
<mujoco>
  <option timestep="{dt}" gravity="0 0 -{G}" integrator="{integrator}"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1" {soft}/>
    <body name="ball" pos="0 0 0">
      <joint name="drop" type="slide" axis="0 0 1"/>
      <geom name="ball" type="sphere" size="{R}" mass="{M}" {soft}/>
    </body>
  </worldbody>
</mujoco>"""


def mujoco_run(dt, stiffness, integrator="RK4"):
    model = mujoco.MjModel.from_xml_string(mujoco_xml(dt, stiffness, integrator))
    data = mujoco.MjData(model)
    data.qpos[0] = H0 + R
    steps = int(round(T_END / dt))
    zs = [0.0] * (steps + 1)
    zs[0] = data.qpos[0] - R
    start = time.process_time()
    for k in range(steps):
        mujoco.mj_step(model, data)
        zs[k + 1] = data.qpos[0] - R
    cpu = time.process_time() - start
    # Apexes between contacts: the maxima of z - r over each flight.
    # The drop itself is not a rebound: count flights after the first touch.
    heights, best, flying, touched = [], 0.0, False, False
    for zk in zs[1:]:
        if zk > 1e-6:
            flying = touched
            best = max(best, zk) if touched else 0.0
        else:
            if flying:
                heights.append(best)
            best, flying, touched = 0.0, False, True
    last_air = max((k for k, zk in enumerate(zs) if zk > 1e-6), default=0)
    rest = (last_air + 1) * dt
    return heights[:N_HEIGHTS], rest, cpu, steps


def eom_run(binary, atol):
    cmd = [binary, "simulate", "models/bouncing_ball.ron", "--t-end", str(T_END),
           "--rtol", "1e-10", "--atol", str(atol), "--json"]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    report = json.loads(out)
    events = report["contact_events"]
    impacts = [e for e in events if e["kind"] == "impact"]
    heights = [e["contacts"][0]["speed_after"] ** 2 / (2 * G) for e in impacts[:N_HEIGHTS]]
    rest = next((e["t"] for e in events if e["kind"] == "rest"), float("nan"))
    return heights, rest, report["cpu_s"], report["stats"]["steps"], len(impacts)


def errors(heights, rest):
    h = max((abs(a - b) / b for a, b in zip(heights, WANT)), default=float("nan"))
    if len(heights) < N_HEIGHTS:
        h = float("nan")
    return h, rest - T_REST


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else "eom-gen"
    print(f"closed form: rest at {T_REST:.9f} s; heights {', '.join(f'{w:.6f}' for w in WANT)} m")
    print()
    print("| code | setting | steps | CPU (ms) | rebound heights 1-5 (m) | max rel. error of heights | rest at (s) | rest - t* (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for atol in [1e-6, 1e-8, 1e-10, 1e-12]:
        heights, rest, cpu, steps, n = eom_run(binary, atol)
        eh, er = errors(heights, rest)
        hs = ", ".join(f"{h:.6f}" for h in heights)
        print(f"| eom (dopri5, compiled) | rtol 1e-10, atol {atol:g} | {steps} | {cpu * 1e3:.3f} | {hs} | {eh:.1e} | {rest:.6f} | {er:+.2e} |")
    for integrator in ["RK4", "implicitfast"]:
        for dt in [1e-3, 2e-4, 1e-4]:
            for stiffness in [1e4, 1e6]:
                heights, rest, cpu, steps = mujoco_run(dt, stiffness, integrator)
                eh, er = errors(heights, rest)
                hs = ", ".join(f"{h:.6f}" for h in heights)
                print(f"| MuJoCo {mujoco.__version__} ({integrator}) | dt {dt:g}, k {stiffness:g} /s², e(z) = {E} | {steps} | {cpu * 1e3:.3f} | {hs} | {eh:.1e} | {rest:.6f} | {er:+.2e} |")


if __name__ == "__main__":
    main()
