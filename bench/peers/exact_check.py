"""Pinocchio's `aba` and MuJoCo's `mj_forward` against the 40-digit
articulated-body algorithm (reference.py) on the benchmark chains, with the
condition number of the mass matrix: which of two double-precision results
is right when they differ (BENCHMARKS.md, "Peers": the 200-link chain).

    target/peers/venv/bin/python bench/peers/exact_check.py [--states 3] [--only spatial_chain200]

Random states: q uniform in (−π, π), u and τ in (−1, 1), numpy seed 1.
"""

import argparse
import sys

import mujoco
import numpy as np
import pinocchio as pin

import models
import reference


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=3)
    ap.add_argument("--only", nargs="*")
    a = ap.parse_args()
    table = models.models()
    names = a.only or list(table)
    unknown = [x for x in names if x not in table]
    if unknown:
        sys.exit(f"unknown models: {', '.join(unknown)}")
    print("| model | max κ(M) | κ(M)·ε | Pinocchio vs 40 digits | MuJoCo vs 40 digits |")
    print("|---|---|---|---|---|")
    for name in names:
        links = table[name]
        n = len(links)
        pm = pin.buildModelFromXML(models.urdf(name, links))
        pd = pm.createData()
        mm = mujoco.MjModel.from_xml_string(models.mjcf(name, links))
        md = mujoco.MjData(mm)
        rng = np.random.default_rng(1)
        worst = {"pin": 0.0, "mj": 0.0, "kappa": 0.0}
        for _ in range(a.states):
            q, u, tau = rng.uniform(-np.pi, np.pi, n), rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
            ref = np.array(reference.forward_dynamics(links, q, u, tau))
            scale = np.abs(ref).max()
            ours = pin.aba(pm, pd, q, u, tau)
            md.qpos[:], md.qvel[:], md.qfrc_applied[:] = q, u, tau
            mujoco.mj_forward(mm, md)
            m = pin.crba(pm, pd, q)
            m = np.triu(m) + np.triu(m, 1).T
            worst["pin"] = max(worst["pin"], np.abs(ours - ref).max() / scale)
            worst["mj"] = max(worst["mj"], np.abs(md.qacc - ref).max() / scale)
            worst["kappa"] = max(worst["kappa"], np.linalg.cond(m))
        eps = sys.float_info.epsilon
        print(
            f"| {name} | {worst['kappa']:.1e} | {worst['kappa'] * eps:.1e} | {worst['pin']:.1e} | {worst['mj']:.1e} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
