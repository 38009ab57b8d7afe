"""ns per element of Exudyn's ANCFCable2D: elastic forces (ODE2 right-hand
side) and their Jacobian, timed through Exudyn's own solver entry points on
a chain of N elements at a deformed state with velocities, the same section
as eom's `bench/benches/ancf.rs` (steel 0.1 m x 0.1 m, element length
0.25 m), with material damping (so that the damping terms are computed)
and without (the elastic forces alone, eom's elastic kernels).

Each call loops over all elements in C++ and assembles into the system
vector / Jacobian; per-element time = (median call time) / N. Python's
call overhead (~1 us) is amortised over N.

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install exudyn numpy
    /tmp/venv/bin/python bench/peers/ancf_exudyn_kernels.py
"""
import math
import statistics
import time

import exudyn as exu
from exudyn.itemInterface import NodePoint2DSlope1, ObjectANCFCable2D


def build(n, reduced, damped):
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    E, b, h, rho, le = 2.07e11, 0.1, 0.1, 7800.0, 0.25
    A, I = b * h, b * h**3 / 12
    nodes = []
    for i in range(n + 1):
        # a deformed state: the same smooth perturbation pattern as the Rust bench
        init = [0.03 * math.sin(1.7 * (4 * i + k)) for k in range(4)]
        vel = [0.5 * math.cos(0.9 * (4 * i + k)) for k in range(4)]
        nodes.append(mbs.AddNode(NodePoint2DSlope1(
            referenceCoordinates=[i * le, 0, 1, 0],
            initialCoordinates=init, initialVelocities=vel)))
    for i in range(n):
        mbs.AddObject(ObjectANCFCable2D(
            length=le, massPerLength=rho * A,
            bendingStiffness=E * I, axialStiffness=E * A,
            bendingDamping=1e-3 * E * I if damped else 0.0,
            axialDamping=1e-3 * E * A if damped else 0.0,
            useReducedOrderIntegration=reduced,
            nodeNumbers=[nodes[i], nodes[i + 1]]))
    mbs.Assemble()
    solver = exu.MainSolverImplicitSecondOrder()
    settings = exu.SimulationSettings()
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    settings.solution.file.write = False
    solver.InitializeSolver(mbs, settings)
    return mbs, solver


def median_ns(f, reps, rounds=15):
    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(reps):
            f()
        times.append((time.perf_counter() - t0) / reps * 1e9)
    return statistics.median(times)


def main():
    print("exudyn", exu.config.Version() if hasattr(exu, "config") else exu.__version__)
    for damped, reduced in ((True, 0), (True, 1), (False, 0)):
        for n in (64, 256, 1024):
            mbs, solver = build(n, reduced, damped)
            rhs = median_ns(lambda: solver.ComputeODE2RHS(mbs), 20)
            jac = median_ns(lambda: solver.ComputeJacobianODE2RHS(mbs, 1.0, 1.0, 1.0), 3, 7)
            print(f"ANCFCable2D damping {'on' if damped else 'off'} "
                  f"useReducedOrderIntegration={reduced} N={n}: "
                  f"ODE2RHS {rhs / n:.0f} ns/element, JacobianODE2RHS (K + D) {jac / n:.0f} ns/element")


if __name__ == "__main__":
    main()
