#!/usr/bin/env python3
"""eom and Exudyn on one flexible body (#17): the same reduced model, the same
motion, CPU time at equal error.

The body: a slender block 1 m x 0.04 m x 0.04 m (rho = 1000 kg/m3,
E = 1e9 Pa, nu = 0.3), meshed by linear tetrahedra (each hexahedral cell of
a 16 x 2 x 2 grid cut into six), lumped nodal masses (rho V / 4 per tetrahedron
corner). Its elastic coordinates are the lowest `MODES` eigenmodes with the
root face (x = 0) clamped: fixed-interface modes, so the body frame is the
root face. Both tools get these nodes, masses and mode shapes; eom through its
imported modal format (written here), Exudyn through its FEMinterface and
ObjectFFRFreducedOrder. With lumped masses both compute the same inertia
invariants (sums over point masses), so the two are one model.

The motion: the body floats free (no gravity), spinning at
omega0 = (0, 1, 4) rad/s about its root, undeformed at rest relative to the
frame at t = 0; the spin bends it (centrifugal load) and the bending
oscillates. Error: the tip-face centre's position at t = T_END against a
reference (eom, DOP853 at rtol = atol = 1e-13, checked against eom's RADAU5
and Exudyn's tightest run). Time: wall-clock time of the integration only,
single-threaded both (eom: `cpu_s` of `eom-gen simulate --json`, the median
of three runs, code compiled beforehand; Exudyn: time.perf_counter() around
SolveDynamic, one run); run it on a quiet machine.

    python3 bench/flex/shared_case.py [--eom target/release/eom-gen] [--csv out.csv]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

L, B, H = 1.0, 0.04, 0.04
RHO, E, NU = 1000.0, 1.0e9, 0.3
NX, NY, NZ = 16, 2, 2
MODES = 6
OMEGA0 = np.array([0.0, 1.0, 4.0])
T_END = 2.0


def mesh():
    """Nodes (n x 3) and tetrahedra (m x 4) of the block, Kuhn's six-tet split."""
    xs = np.linspace(0.0, L, NX + 1)
    ys = np.linspace(-B / 2, B / 2, NY + 1)
    zs = np.linspace(-H / 2, H / 2, NZ + 1)
    idx = {}
    nodes = []
    for i, x in enumerate(xs):
        for j, y in enumerate(ys):
            for k, z in enumerate(zs):
                idx[(i, j, k)] = len(nodes)
                nodes.append((x, y, z))
    # The six tetrahedra of the unit cube along the main diagonal 0 -> 7
    # (corners numbered by bits (x, y, z)); conforming across cells.
    paths = [(1, 3), (1, 5), (2, 3), (2, 6), (4, 5), (4, 6)]
    tets = []
    for i in range(NX):
        for j in range(NY):
            for k in range(NZ):
                c = [idx[(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1))] for b in range(8)]
                for a, b in paths:
                    tets.append((c[0], c[a], c[b], c[7]))
    return np.array(nodes), np.array(tets)


def matrices(nodes, tets):
    """Lumped mass (diagonal, 3n) and linear-elastic stiffness (3n x 3n)."""
    n = len(nodes)
    lam = E * NU / ((1 + NU) * (1 - 2 * NU))
    mu = E / (2 * (1 + NU))
    d = np.zeros((6, 6))
    d[:3, :3] = lam
    d[np.arange(3), np.arange(3)] += 2 * mu
    d[np.arange(3, 6), np.arange(3, 6)] = mu
    k = np.zeros((3 * n, 3 * n))
    m = np.zeros(3 * n)
    for t in tets:
        x = nodes[list(t)]
        a = np.hstack([np.ones((4, 1)), x])
        vol = abs(np.linalg.det(a)) / 6.0
        grads = np.linalg.inv(a)[1:, :]  # d N_i / d x_j: rows j, columns i
        bm = np.zeros((6, 12))
        for i in range(4):
            gx, gy, gz = grads[:, i]
            bm[:, 3 * i:3 * i + 3] = [[gx, 0, 0], [0, gy, 0], [0, 0, gz],
                                      [gy, gx, 0], [0, gz, gy], [gz, 0, gx]]
        ke = vol * bm.T @ d @ bm
        dofs = np.array([[3 * v, 3 * v + 1, 3 * v + 2] for v in t]).ravel()
        k[np.ix_(dofs, dofs)] += ke
        for v in t:
            m[3 * v:3 * v + 3] += RHO * vol / 4.0
    return m, k


def clamped_modes(nodes, m, k, count):
    """Lowest `count` modes with the root face clamped, unit modal mass."""
    root = np.where(nodes[:, 0] < 1e-12)[0]
    fixed = np.zeros(3 * len(nodes), dtype=bool)
    for v in root:
        fixed[3 * v:3 * v + 3] = True
    free = ~fixed
    mf = m[free]
    kf = k[np.ix_(free, free)]
    # Symmetric form: M^-1/2 K M^-1/2.
    s = 1.0 / np.sqrt(mf)
    w2, v = np.linalg.eigh(s[:, None] * kf * s[None, :])
    phi = np.zeros((3 * len(nodes), count))
    phi[free, :] = s[:, None] * v[:, :count]
    return w2[:count], phi


def tip_position(nodes, phi, r, a, qf):
    """World position of the tip-face centre node."""
    tip = np.argmin(np.linalg.norm(nodes - np.array([L, 0.0, 0.0]), axis=1))
    u = nodes[tip] + phi[3 * tip:3 * tip + 3, :] @ qf
    return r + a @ u


def exudyn_runs(nodes, m, k, phi, w2, plan):
    """Exudyn: ObjectFFRFreducedOrder, each (method, setting) of `plan`."""
    import exudyn as exu
    import exudyn.FEM as fem_mod
    from exudyn.itemInterface import MarkerNodeRigid  # noqa: F401  (API presence)
    import scipy.sparse as sp

    out = []
    for method, setting in plan:
        fem = fem_mod.FEMinterface()
        fem.nodes = {"Position": nodes}
        fem.massMatrix = sp.csr_matrix(np.diag(m))
        fem.stiffnessMatrix = sp.csr_matrix(k)
        fem.modeBasis = {"matrix": phi}
        fem.eigenValues = w2
        fem.surface = []
        node_type = ("NodeType.RotationRotationVector" if method == "DOPRI5"
                     else "NodeType.RotationEulerParameters")
        cms = fem_mod.ObjectFFRFreducedOrderInterface(fem, rigidBodyNodeType=node_type)
        sc = exu.SystemContainer()
        mbs = sc.AddSystem()
        obj = cms.AddObjectFFRFreducedOrder(mbs, initialAngularVelocity=list(OMEGA0))
        mbs.Assemble()
        ss = exu.SimulationSettings()
        ss.timeIntegration.endTime = T_END
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.write = False
        ss.show.computationTime = False
        ss.show.statistics = False
        if method == "GeneralizedAlpha":
            ss.timeIntegration.numberOfSteps = int(setting)
            ss.timeIntegration.generalizedAlpha.spectralRadius = 1.0
            ss.timeIntegration.newton.relativeTolerance = 1e-12
            ss.timeIntegration.newton.absoluteTolerance = 1e-14
            solver = exu.DynamicSolverType.GeneralizedAlpha
        else:
            ss.timeIntegration.numberOfSteps = 100
            ss.timeIntegration.automaticStepSize = True
            ss.timeIntegration.absoluteTolerance = setting
            ss.timeIntegration.relativeTolerance = setting
            ss.timeIntegration.explicit.useLieGroupIntegration = True
            solver = exu.DynamicSolverType.DOPRI5
        t0 = time.perf_counter()
        mbs.SolveDynamic(ss, solverType=solver)
        cpu = time.perf_counter() - t0
        print(f"exudyn {method} {setting}: {cpu:.3f} s", file=sys.stderr)
        n_rigid = obj["nRigidBody"]
        n_modal = obj["nGenericODE2"]
        r = np.array(mbs.GetNodeOutput(n_rigid, exu.OutputVariableType.Position))
        a = np.array(mbs.GetNodeOutput(n_rigid, exu.OutputVariableType.RotationMatrix)).reshape(3, 3)
        qf = np.array(mbs.GetNodeOutput(n_modal, exu.OutputVariableType.Coordinates))
        out.append(("exudyn", method, setting, cpu, tip_position(nodes, phi, r, a, qf)))
    return out


def write_eom_model(directory, nodes, m, phi, w2):
    """eom's model: the body from an imported modal file (JSON), a free joint."""
    tip = int(np.argmin(np.linalg.norm(nodes - np.array([L, 0.0, 0.0]), axis=1)))
    data = {
        "doc": "bench/flex/shared_case.py: tetrahedral block 1 x 0.04 x 0.04 m, lumped mass, "
               f"{MODES} clamped-root modes, unit modal mass; SI units",
        "nodes": [{"position": [float(c) for c in x], "mass": float(m[3 * i])}
                  | ({"name": "tip"} if i == tip else {})
                  for i, x in enumerate(nodes)],
        "modes": [{"translation": [[float(v) for v in phi[3 * i:3 * i + 3, j]]
                                   for i in range(len(nodes))]}
                  for j in range(phi.shape[1])],
        "modal_mass": np.eye(len(w2)).tolist(),
        "modal_stiffness": np.diag(w2).tolist(),
    }
    with open(os.path.join(directory, "block.modal.json"), "w") as f:
        json.dump(data, f)
    model = f"""// bench/flex/shared_case.py: a free flexible block spinning (eom vs Exudyn).
Model(
    name: "shared_block",
    bodies: [(name: "block", flexible: Modal(file: "block.modal.json"))],
    joints: [(
        name: "float",
        kind: Free,
        parent: "ground",
        child: "block",
        u0: [0, 0, 0, {OMEGA0[0]}, {OMEGA0[1]}, {OMEGA0[2]}],
    )],
)
"""
    path = os.path.join(directory, "shared_block.ron")
    with open(path, "w") as f:
        f.write(model)
    return path


def quat_matrix(w, x, y, z):
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def eom_runs(eom, model, nodes, phi, plan, repeats=3):
    """eom: `eom-gen simulate --json` for each (integrator, tolerance); the
    median `cpu_s` of `repeats` runs (the compiled code is cached)."""
    out = []
    for integrator, tol in plan:
        cpus = []
        for _ in range(repeats):
            res = subprocess.run(
                [eom, "simulate", model, "--t-end", str(T_END), "--integrator", integrator,
                 "--rtol", str(tol), "--atol", str(tol), "--max-steps", "10000000", "--json"],
                capture_output=True, text=True, check=False)
            if res.returncode != 0:
                sys.exit(f"eom-gen simulate failed ({integrator}, {tol}): {res.stderr}")
            report = json.loads(res.stdout)
            cpus.append(report["cpu_s"])
        q = np.array(report["q"])
        print(f"eom {integrator} {tol}: {np.median(cpus):.4f} s", file=sys.stderr)
        a = quat_matrix(*q[3:7])
        out.append(("eom", integrator, tol, float(np.median(cpus)),
                    tip_position(nodes, phi, q[:3], a, q[7:])))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--eom", default="target/release/eom-gen")
    ap.add_argument("--csv")
    ap.add_argument("--write-model", help="also write eom's model and modal file here")
    args = ap.parse_args()
    nodes, tets = mesh()
    m, k = matrices(nodes, tets)
    w2, phi = clamped_modes(nodes, m, k, MODES)
    print(f"mesh: {len(nodes)} nodes, {len(tets)} tetrahedra, mass {m.sum() / 3:.6f} kg; "
          f"modes (Hz): {', '.join(f'{np.sqrt(x) / 2 / np.pi:.3f}' for x in w2)}",
          file=sys.stderr)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        model = write_eom_model(tmp, nodes, m, phi, w2)
        if args.write_model:
            write_eom_model(args.write_model, nodes, m, phi, w2)
        ref = eom_runs(args.eom, model, nodes, phi, [("dop853", 1e-13)], repeats=1)[0][4]
        check = eom_runs(args.eom, model, nodes, phi, [("radau5", 1e-12)], repeats=1)[0][4]
        print(f"reference: eom dop853 1e-13, tip {ref}; eom radau5 1e-12 differs by "
              f"{np.linalg.norm(check - ref):.2e} m", file=sys.stderr)
        plan = [("dopri5", t) for t in (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)]
        plan += [("dop853", t) for t in (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)]
        plan += [("radau5", t) for t in (1e-4, 1e-6, 1e-8, 1e-10)]
        rows += eom_runs(args.eom, model, nodes, phi, plan)
    plan = [("DOPRI5", t) for t in (1e-4, 1e-6, 1e-8, 1e-10)]
    plan += [("GeneralizedAlpha", n) for n in (200, 400, 800, 1600, 3200, 6400, 12800)]
    rows += exudyn_runs(nodes, m, k, phi, w2, plan)
    lines = ["tool,method,setting,cpu_s,tip_error_m"]
    print(f"{'tool':8} {'method':17} {'setting':>8} {'CPU s':>10} {'tip error, m':>12}")
    for tool, method, setting, cpu, tip in rows:
        err = float(np.linalg.norm(tip - ref))
        print(f"{tool:8} {method:17} {setting:>8g} {cpu:10.3e} {err:12.2e}")
        lines.append(f"{tool},{method},{setting},{cpu},{err}")
    if args.csv:
        with open(args.csv, "w") as f:
            f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
