"""Exudyn's ANCFCable2D on the ANCF cases of issue #18, for BENCHMARKS.md
("ANCF runtime"), beside `cargo run --release -p eom-sim --example ancf_bench`.

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install exudyn numpy
    /tmp/venv/bin/python bench/peers/ancf_exudyn_cases.py static
    /tmp/venv/bin/python bench/peers/ancf_exudyn_cases.py pendulum N H

static: the Gerstmayr-Irschik cantilever (L = 2 m, E = 2.07e11 Pa,
b = h = 0.1 m, tip force 3EI/L^2), 16 and 64 elements, 10 load steps,
Newton tolerances 1e-8 and 1e-10 (the tighter fails at 64 elements); CPU time of the solve and the tip.
pendulum: Berzeri and Shabana's falling pendulum (L = 1.2 m, A = 0.0018 m^2,
I = 1.215e-8 m^4, rho = 5540 kg/m^3, E = 0.7e6 Pa), pinned, released
horizontal, generalized-alpha with spectral radius 1 and step H to 1 s; CPU
time and the tip at 1 s. Errors are computed against eom's references in
BENCHMARKS.md.
"""

import sys
import time

import exudyn as exu
from exudyn.beams import GenerateStraightBeam
from exudyn.itemInterface import (LoadForceVector, MarkerNodePosition,
                                  ObjectANCFCable2D)


def cantilever(n, tol):
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    L, b, E, rho = 2.0, 0.1, 2.07e11, 7800.0
    A, I = b * b, b ** 4 / 12
    P = 3 * E * I / L ** 2
    cable = ObjectANCFCable2D(massPerLength=rho * A, bendingStiffness=E * I,
                              axialStiffness=E * A, useReducedOrderIntegration=0)
    nodes, _, _, _, _ = GenerateStraightBeam(
        mbs, [0, 0, 0], [L, 0, 0], n, cable, gravity=[0, 0, 0],
        fixedConstraintsNode0=[1, 1, 1, 1], fixedConstraintsNode1=[0, 0, 0, 0])
    tip = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
    mbs.AddLoad(LoadForceVector(markerNumber=tip, loadVector=[0, -P, 0]))
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = 10
    s.staticSolver.newton.relativeTolerance = tol
    s.staticSolver.newton.absoluteTolerance = tol
    s.staticSolver.newton.maxIterations = 50
    s.staticSolver.verboseMode = 0
    s.linearSolverType = exu.LinearSolverType.EigenSparse
    s.solutionSettings.writeSolutionToFile = False
    s.timeIntegration.verboseMode = 0
    t0 = time.process_time()
    exu.SolveStatic(mbs, s)
    cpu = time.process_time() - t0
    pos = mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Position)
    return cpu, pos


def pendulum(n, h):
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    L, A, I, rho, E = 1.2, 0.0018, 1.215e-8, 5540.0, 0.7e6
    cable = ObjectANCFCable2D(massPerLength=rho * A, bendingStiffness=E * I,
                              axialStiffness=E * A, useReducedOrderIntegration=0)
    nodes, _, _, _, _ = GenerateStraightBeam(
        mbs, [0, 0, 0], [L, 0, 0], n, cable, gravity=[0, -9.81, 0],
        fixedConstraintsNode0=[1, 1, 0, 0], fixedConstraintsNode1=[0, 0, 0, 0])
    mbs.Assemble()
    s = exu.SimulationSettings()
    s.timeIntegration.numberOfSteps = int(round(1.0 / h))
    s.timeIntegration.endTime = 1.0
    s.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    s.timeIntegration.newton.relativeTolerance = 1e-10
    s.timeIntegration.newton.absoluteTolerance = 1e-10
    s.timeIntegration.verboseMode = 0
    s.linearSolverType = exu.LinearSolverType.EigenSparse
    s.solutionSettings.writeSolutionToFile = False
    s.timeIntegration.verboseMode = 0
    t0 = time.process_time()
    exu.SolveDynamic(mbs, s)
    cpu = time.process_time() - t0
    pos = mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Position)
    return cpu, pos


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "static"
    if what == "static":
        for n in (16, 64):
            for tol in (1e-8, 1e-10):
                try:
                    runs = [cantilever(n, tol) for _ in range(20)]
                    best = sum(r[0] for r in runs) / len(runs)
                    pos = runs[-1][1]
                except exu.SolverError:
                    print(f"exudyn static n = {n:3d} tol {tol:g}: the static solver failed")
                    continue
                print(f"exudyn static n = {n:3d} tol {tol:g}: {best * 1e3:.3f} ms CPU (mean of 20), "
                      f"tip ({pos[0]:.10f}, {pos[1]:.10f})")
    else:
        n = int(sys.argv[2])
        h = float(sys.argv[3])
        cpu, pos = pendulum(n, h)
        print(f"exudyn pendulum n = {n:3d} h = {h:g}: tip at 1 s ({pos[0]:.9f}, "
              f"{pos[1]:.9f}), {cpu:.3f} s CPU")
