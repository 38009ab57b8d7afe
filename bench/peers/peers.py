"""eom against Pinocchio and MuJoCo: accelerations and ns per call.

Run by run.sh (which installs the peers, builds eom-gen, the chain models
and the C++ timing program); see README.md. For each model:

1. writes its URDF and MJCF (models.py);
2. runs the C++ program: Pinocchio ABA/RNEA/CRBA/computeABADerivatives and
   MuJoCo mj_forward/mjd_transitionFD over the same random states as
   `eom-gen bench` (same generator and seed), and the accelerations and
   derivatives of both at the first few states;
3. checks those accelerations against `eom-gen eval` (compiled) at the same
   states: max |difference| / max |eom's accelerations| <= 1e-10; and eom's
   derivatives (`eom-gen linearize --json` at the same q, u, zero forces)
   against Pinocchio's ddq_dq, ddq_dv, Minv (<= 1e-10 relative to each
   matrix's largest entry) and MuJoCo's centred differences (<= 1e-5);
4. runs `eom-gen bench MODEL --per-call --json` (`--native --derivatives`,
   and without both);
5. prints two tables (functions; derivatives) and writes two CSVs.

Besides the standard library, Pinocchio's Python bindings are used once per
model to check that the C++ program's model (built from the URDF with
urdfdom, see peers.cpp) gives the same accelerations as Pinocchio's own URDF
parser. Nothing of this is timed.
"""

import argparse
import csv
import json
import os
import subprocess
import statistics
import sys

import models
import reference

TOLERANCE = 1e-10
# MuJoCo's derivatives are centred differences (eps = 1e-6) of its Euler
# step, divided by the step (1e-3): about 1e-7 relative is what they can do.
FD_TOLERANCE = 1e-5
# The issue's target (issue 27): eom's derivatives at least this many times
# faster than Pinocchio's computeABADerivatives.
TARGET = 5.0


def run(cmd, **kw):
    out = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if out.returncode != 0:
        sys.exit(f"failed ({out.returncode}): {' '.join(cmd)}\n{out.stderr}")
    return out.stdout


def eom_json(eom, args, env):
    return json.loads(run([eom, *args], env=env))


# Names eom reserves get a trailing `_`; other characters than ASCII letters
# and digits become `_` (`identifier` in eom-gen/src/model/urdf.rs, as
# bench/robots/compare.py maps them).
RESERVED = {"t", "pi", "ground", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sqrt", "exp",
            "ln", "log", "abs", "sign", "min", "max", "pow", "sinh", "cosh", "tanh", "floor", "ceil"}


def identifier(name):
    s = "".join(c if (c.isascii() and c.isalnum()) else "_" for c in name)
    if not s or s[0].isdigit():
        s = "_" + s
    if s in RESERVED:
        s += "_"
    return s


def robots_dir():
    """example-robot-data's `robots` directory inside this venv's wheel."""
    import sysconfig

    site = sysconfig.get_paths()["purelib"]
    return os.path.join(site, "cmeel.prefix", "share", "example-robot-data", "robots")


def merged_rounds(runs):
    """One report from the reports of several rounds of the same timing
    program: every figure the median over the rounds (a timing's `median`,
    an `_ns` number, a `by_width` entry), every fastest pass the minimum;
    everything else from the first round."""
    first = runs[0]
    if isinstance(first, dict):
        out = {}
        for k, v in first.items():
            vals = [r[k] for r in runs if isinstance(r, dict) and k in r]
            if k == "min" and all(isinstance(x, (int, float)) for x in vals):
                out[k] = min(vals)
            elif isinstance(v, dict):
                out[k] = merged_rounds(vals)
            elif isinstance(v, float) and (k == "median" or k.endswith("_ns") or k.isdigit()):
                out[k] = statistics.median(vals)
            else:
                out[k] = v
        return out
    return first


def ratio(a, b):
    return a / b if b > 0 else float("nan")


def rel_diff(ours, theirs):
    """max |ours - theirs| / max |theirs| over two flat lists."""
    scale = max(abs(x) for x in theirs)
    return max(abs(x - y) for x, y in zip(ours, theirs)) / scale


def derivative_check(a, ron, peer, env, perm, eom_order, robot):
    """eom's dudot/dq, dudot/du, dudot/dtau (`linearize --json` at q, u of the
    first --deriv-check states, zero applied forces: its operating point)
    against Pinocchio's computeABADerivatives and MuJoCo's centred
    differences there. `perm[k]` is eom's index of Pinocchio's speed k,
    `eom_order` maps a vector in Pinocchio's order to eom's. On the robots
    the URDF's dampers are in eom's model (`τ − D u`): Pinocchio's ddq_dv
    (at fixed τ = −D v) gets their `−M⁻¹ D`; MuJoCo's differences (in its
    own joint order, its dampers integrated implicitly) are compared on the
    chains only. Returns the largest relative difference per (tool, matrix)."""
    import numpy as np

    err = {}
    damping = np.array(peer["damping"])
    for s in peer["check"][: a.deriv_check]:
        join = lambda v: ",".join(repr(x) for x in v)  # noqa: E731
        # (The random states leave the robots' joint limits, which the peers
        # do not model either: eom imports the URDF without them here.)
        limits = ["--no-urdf-limits"] if robot else []
        lin = eom_json(
            a.eom,
            ["linearize", ron, *limits, "--q", join(eom_order(s["q"])), "--u", join(eom_order(s["u"])), "--json"],
            env,
        )
        n = len(s["u"])
        big_a, big_b = lin["A"], lin["B"]
        if len(big_a) != 2 * n or len(big_b) != 2 * n or len(big_b[0]) != n:
            sys.exit(
                f"{ron}: linearize gave A {len(big_a)}x{len(big_a[0])}, B {len(big_b)}x{len(big_b[0])}; "
                f"expected {2 * n}, {2 * n}x{n}"
            )
        # eom's blocks in Pinocchio's order.
        dq = [big_a[n + perm[i]][perm[j]] for i in range(n) for j in range(n)]
        du = [big_a[n + perm[i]][n + perm[j]] for i in range(n) for j in range(n)]
        dtau = [big_b[n + perm[i]][perm[j]] for i in range(n) for j in range(n)]
        minv = np.array(s["pinocchio_minv_upper"]).reshape(n, n)
        pin_du = (np.array(s["pinocchio_ddq_dv"]).reshape(n, n) - minv * damping[None, :]).ravel().tolist()
        pairs = [
            (("pinocchio", "dq"), dq, s["pinocchio_ddq_dq"]),
            (("pinocchio", "du"), du, pin_du),
            (("pinocchio", "dtau"), dtau, s["pinocchio_minv_upper"]),
        ]
        if not robot:
            pairs += [
                (("mujoco_fd", "dq"), dq, s["mujoco_fd_dq"]),
                (("mujoco_fd", "du"), du, s["mujoco_fd_dv"]),
            ]
        for key, ours, theirs in pairs:
            err[key] = max(err.get(key, 0.0), rel_diff(ours, theirs))
    return err


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--eom", required=True, help="the eom-gen binary")
    ap.add_argument("--peers", required=True, help="the C++ timing program")
    ap.add_argument("--models-dir", required=True, help="where the chain RONs are; URDF/MJCF go there")
    ap.add_argument("--root", required=True, help="the repository root")
    ap.add_argument("--states", type=int, default=1024)
    ap.add_argument("--reps", type=int, default=31)
    ap.add_argument(
        "--rounds",
        type=int,
        default=3,
        help="times each side's timing program runs, alternately (peers, eom, peers, …); "
        "every figure is the median over the rounds, every fastest pass the minimum",
    )
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--check", type=int, default=5, help="states whose accelerations are compared")
    ap.add_argument("--deriv-check", type=int, default=3, help="states whose derivatives are compared")
    ap.add_argument("--only", nargs="*", help="model names (default: all)")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--deriv-csv", required=True)
    ap.add_argument(
        "--deriv-max-dof",
        type=int,
        default=10,
        help="derivatives only for models with at most this many speeds (a 50-link chain's are ~5e5 operations)",
    )
    ap.add_argument(
        "--native-only",
        action="store_true",
        help="skip eom's generic (no target-cpu=native) build: one compile less per model",
    )
    a = ap.parse_args()
    if not 1 <= a.deriv_check <= a.check:
        sys.exit("--deriv-check must be between 1 and --check")
    if a.rounds < 1:
        sys.exit("--rounds must be at least 1")

    env = dict(os.environ)
    table = models.models()
    names = a.only or list(table) + list(models.ROBOTS)
    unknown = [x for x in names if x not in table and x not in models.ROBOTS]
    if unknown:
        sys.exit(f"unknown models: {', '.join(unknown)}")
    rows = []
    drows = []
    failures = []
    for name in names:
        base = os.path.join(a.models_dir, name)
        robot = name in models.ROBOTS
        if robot:
            # example-robot-data's URDF (mimics, visuals and collisions
            # removed) for eom and Pinocchio; the same with MuJoCo's options
            # for MuJoCo's own URDF import.
            with open(os.path.join(robots_dir(), models.ROBOTS[name])) as f:
                text = models.robot_urdf(f.read())
            mj_path = base + ".mujoco.urdf"
            with open(base + ".urdf", "w") as f:
                f.write(text)
            with open(mj_path, "w") as f:
                f.write(models.robot_mujoco(text))
            ron = base + ".urdf"
        else:
            links = table[name]
            mj_path = base + ".xml"
            with open(base + ".urdf", "w") as f:
                f.write(models.urdf(name, links))
            with open(mj_path, "w") as f:
                f.write(models.mjcf(name, links))
            ron = os.path.join(a.root, "models", "arm7.ron") if name == "arm7" else base + ".ron"

        info = eom_json(a.eom, ["check", ron, "--json"], env)
        # (On the robots, against Pinocchio only: MuJoCo's differences are
        # in its own order with its dampers; see derivative_check.)
        deriv = info["nu"] <= a.deriv_max_dof

        def peer_run(check):
            """One run of the peers' timing program, `check` states checked."""
            return json.loads(
                run([a.peers, base + ".urdf", mj_path, str(a.states), str(a.reps), str(a.seed), str(check),
                     "1" if deriv else "0"])
            )

        peer = peer_run(a.check)
        # The peers' models are what we meant them to be.
        assert peer["nq"] == info["nq"] and peer["nv"] == info["nu"], (name, peer["nq"], info["nq"])
        assert robot or peer["nq"] == len(links), (name, peer["nq"])
        assert peer["mujoco_gravity"] == [0, 0, -9.81] and peer["pinocchio_gravity"] == [0, 0, -9.81], peer
        assert peer["mujoco_max_armature"] == 0, peer
        # Damping: none on the chains; on the robots MuJoCo's per joint is the
        # URDF's (which Pinocchio's ABA is given as tau - D v).
        assert peer["mujoco_damping"] == peer["damping"], (name, peer["mujoco_damping"], peer["damping"])
        assert robot or peer["mujoco_max_damping"] == 0, peer
        # eom's coordinate of each of Pinocchio's joints (Pinocchio's and
        # MuJoCo's order: peers.cpp maps MuJoCo's by name). The identity on
        # the chains; eom's own order on a tree may differ.
        if robot:
            index = {x: k for k, x in enumerate(info["coordinate_names"])}
            perm = [index.get(identifier(j), -1) for j in peer["joints"]]
        else:
            perm = list(range(peer["nv"]))
        if sorted(perm) != list(range(peer["nv"])):
            sys.exit(f"{name}: joints {peer['joints']} do not match eom's coordinates {info.get('coordinate_names')}")

        def eom_order(v):
            out = [0.0] * len(v)
            for k, x in zip(perm, v):
                out[k] = x
            return out

        # Pinocchio's own URDF parser agrees with the C++ program's model.
        import numpy as np
        import pinocchio as pin

        pmodel = pin.buildModelFromUrdf(base + ".urdf")
        pdata = pmodel.createData()
        parser_diff = 0.0
        damping = np.array(peer["damping"])
        for s in peer["check"]:
            tau_d = np.array(s["tau"]) - damping * np.array(s["u"])
            ref = pin.aba(pmodel, pdata, np.array(s["q"]), np.array(s["u"]), tau_d)
            scale = max(abs(x) for x in ref)
            parser_diff = max(parser_diff, max(abs(x - y) for x, y in zip(ref, s["pinocchio"])) / scale)
        if not parser_diff <= TOLERANCE:
            failures.append(f"{name}: the C++ Pinocchio model differs from Pinocchio's URDF parser by {parser_diff:.2e}")

        # Accelerations at the check states. On the chains the arbiter is
        # the 40-digit articulated-body algorithm (reference.py): eom and
        # Pinocchio must match it and each other to TOLERANCE. MuJoCo solves
        # M u̇ = τ − b by an LDLᵀ of M, whose forward error is bounded by
        # κ(M)·ε, which passes 1e-10 on the 200-link chain (κ ≈ 1e9): its
        # limit is the larger of TOLERANCE and that bound, and both its
        # difference from the reference and the bound are reported. A
        # model that differs in any number misses by orders more.
        err = {"pinocchio": 0.0, "mujoco": 0.0}
        exact = {"eom": 0.0, "pinocchio": 0.0, "mujoco": 0.0}
        kappa = 0.0
        for s in peer["check"]:
            tau_d = np.array(s["tau"]) - damping * np.array(s["u"])
            m = pin.crba(pmodel, pdata, np.array(s["q"]))
            kappa = max(kappa, float(np.linalg.cond(np.triu(m) + np.triu(m, 1).T)))
            join = lambda v: ",".join(repr(x) for x in v)  # noqa: E731
            e = eom_json(
                a.eom,
                ["eval", ron, "--q", join(eom_order(s["q"])), "--u", join(eom_order(s["u"])),
                 "--tau", join(eom_order(s["tau"])), "--json"],
                env,
            )
            ours = [e["udot"][k] for k in perm]  # Pinocchio's order
            scale = max(abs(x) for x in ours)
            for tool in err:
                diff = max(abs(x - y) for x, y in zip(ours, s[tool]))
                err[tool] = max(err[tool], diff / scale)
            if not robot:
                ref = reference.forward_dynamics(links, s["q"], s["u"], list(tau_d))
                for tool, acc in (("eom", ours), ("pinocchio", s["pinocchio"]), ("mujoco", s["mujoco"])):
                    diff = max(abs(x - y) for x, y in zip(acc, ref))
                    exact[tool] = max(exact[tool], diff / max(abs(x) for x in ref))
        # The κ(M)·ε allowance only where the 40-digit reference arbitrates.
        bound = TOLERANCE if robot else max(TOLERANCE, kappa * sys.float_info.epsilon)
        limits = {"pinocchio": TOLERANCE, "mujoco": bound}
        for tool, x in err.items():
            if not x <= limits[tool]:
                failures.append(f"{name}: {tool} accelerations differ from eom's by {x:.2e} (relative; limit {limits[tool]:.0e})")
        if not robot:
            limits["eom"] = TOLERANCE
            for tool, x in exact.items():
                if not x <= limits[tool]:
                    failures.append(f"{name}: {tool} accelerations differ from the 40-digit reference by {x:.2e} (relative)")

        # Derivatives at the first check states.
        derr = derivative_check(a, ron, peer, env, perm, eom_order, robot) if deriv else {}
        for (tool, what), x in derr.items():
            limit = TOLERANCE if tool == "pinocchio" else FD_TOLERANCE
            if not x <= limit:
                failures.append(f"{name}: {tool} d(udot)/{what} differs from eom's by {x:.2e} (relative)")

        # Timings: each side's program `--rounds` times, alternately (a
        # process's figures move by up to half between runs on this shared
        # host; BENCHMARKS.md "Rounds in the peers harness"). The peers'
        # first round is the checked run above.
        native = ["--native"] + (["--derivatives"] if deriv else [])
        flavours = [("native", native)] + ([] if a.native_only else [("generic", [])])
        eom_runs = {flavour: [] for flavour, _ in flavours}
        peer_runs = [peer]
        for r in range(a.rounds):
            if r > 0:
                peer_runs.append(peer_run(1))
            for flavour, extra in flavours:
                eom_runs[flavour].append(
                    eom_json(
                        a.eom,
                        ["bench", ron, "--per-call", "--json", "--states", str(a.states), "--reps",
                         str(a.reps), "--seed", str(a.seed), *extra],
                        env,
                    )
                )
        bench = {flavour: merged_rounds(v) for flavour, v in eom_runs.items()}
        peer = merged_rounds(peer_runs)

        def per_round(theirs, ours):
            """Their figure over ours in each round, as `a/b/c`."""
            return "/".join(
                f"{ratio(p[theirs]['median'], e[ours]):.2f}" for p, e in zip(peer_runs, eom_runs["native"])
            )

        eom_fd = bench["native"]["forward_dynamics_ns"]
        row = {
            "model": name,
            "dof": peer["nv"],
            "eom_fd_ns": eom_fd,
            "eom_fd_ns_generic": bench["generic"]["forward_dynamics_ns"] if "generic" in bench else float("nan"),
            "eom_fd_ops": bench["native"]["ops"]["forward_dynamics"],
            "eom_fd_form": bench["native"]["fd_form"],
            "pinocchio_aba_ns": peer["pinocchio_aba"]["median"],
            "mujoco_forward_ns": peer["mujoco_forward"]["median"],
            "pinocchio_aba_over_eom": ratio(peer["pinocchio_aba"]["median"], eom_fd),
            "mujoco_forward_over_eom": ratio(peer["mujoco_forward"]["median"], eom_fd),
            "pinocchio_aba_over_eom_rounds": per_round("pinocchio_aba", "forward_dynamics_ns"),
            "mujoco_forward_over_eom_rounds": per_round("mujoco_forward", "forward_dynamics_ns"),
            "eom_id_ns": bench["native"]["inverse_dynamics_ns"],
            "pinocchio_rnea_ns": peer["pinocchio_rnea"]["median"],
            "eom_mass_matrix_ns": bench["native"]["mass_matrix_ns"],
            "pinocchio_crba_ns": peer["pinocchio_crba"]["median"],
            "max_rel_diff_pinocchio": err["pinocchio"],
            "max_rel_diff_mujoco": err["mujoco"],
            "condition_of_m": kappa,
            "max_rel_err_eom_vs_40_digits": exact["eom"] if not robot else "",
            "max_rel_err_pinocchio_vs_40_digits": exact["pinocchio"] if not robot else "",
            "max_rel_err_mujoco_vs_40_digits": exact["mujoco"] if not robot else "",
            "max_rel_diff_pinocchio_parser": parser_diff,
            "pinocchio_version": peer["pinocchio_version"],
            "mujoco_version": peer["mujoco_version"],
            "states": a.states,
            "reps": a.reps,
            "rounds": a.rounds,
            "seed": a.seed,
        }
        rows.append(row)
        if deriv:
            eom_d = bench["native"]["forward_dynamics_derivatives_ns"]
            pin_d = peer["pinocchio_aba_derivatives"]["median"]
            drow = {
                "model": name,
                "dof": peer["nv"],
                "eom_derivatives_ns": eom_d,
                "eom_derivatives_ops": bench["native"]["ops"]["forward_dynamics_derivatives"],
                "pinocchio_aba_derivatives_ns": pin_d,
                "mujoco_transition_fd_forward_ns": peer["mujoco_transition_fd_forward"]["median"],
                "mujoco_transition_fd_centered_ns": peer["mujoco_transition_fd_centered"]["median"],
                "mujoco_fd_passes": peer["mujoco_transition_fd_forward"]["passes"],
                # The fastest pass of each (the figure a neighbour's build on the
                # shared cores disturbs least).
                "eom_derivatives_min_ns": bench["native"]["spread"]["forward_dynamics_derivatives"]["min"],
                "pinocchio_aba_derivatives_min_ns": peer["pinocchio_aba_derivatives"]["min"],
                "mujoco_transition_fd_forward_min_ns": peer["mujoco_transition_fd_forward"]["min"],
                "pinocchio_over_eom": ratio(pin_d, eom_d),
                "pinocchio_over_eom_rounds": per_round(
                    "pinocchio_aba_derivatives", "forward_dynamics_derivatives_ns"
                ),
                "mujoco_fd_forward_over_eom": ratio(peer["mujoco_transition_fd_forward"]["median"], eom_d),
                "pinocchio_over_eom_min": ratio(
                    peer["pinocchio_aba_derivatives"]["min"],
                    bench["native"]["spread"]["forward_dynamics_derivatives"]["min"],
                ),
                # Met only if both the medians and the fastest passes say so.
                "target_met": min(
                    ratio(pin_d, eom_d),
                    ratio(
                        peer["pinocchio_aba_derivatives"]["min"],
                        bench["native"]["spread"]["forward_dynamics_derivatives"]["min"],
                    ),
                )
                >= TARGET,
                "max_rel_diff_pinocchio_dq": derr[("pinocchio", "dq")],
                "max_rel_diff_pinocchio_du": derr[("pinocchio", "du")],
                "max_rel_diff_pinocchio_minv": derr[("pinocchio", "dtau")],
                "max_rel_diff_mujoco_fd_dq": derr.get(("mujoco_fd", "dq"), float("nan")),
                "max_rel_diff_mujoco_fd_du": derr.get(("mujoco_fd", "du"), float("nan")),
                "checked_states": a.deriv_check,
                "mujoco_integrator": peer["mujoco_integrator"],
                "mujoco_timestep": peer["mujoco_timestep"],
                "pinocchio_version": peer["pinocchio_version"],
                "mujoco_version": peer["mujoco_version"],
                "states": a.states,
                "reps": a.reps,
                "rounds": a.rounds,
                "seed": a.seed,
            }
            drows.append(drow)
            print(
                f"{name}: eom derivatives {eom_d:.0f} ns, Pinocchio computeABADerivatives {pin_d:.0f} ns, "
                f"MuJoCo mjd_transitionFD {drow['mujoco_transition_fd_forward_ns']:.0f} ns (forward); "
                f"max relative difference {max(v for (t, _), v in derr.items() if t == 'pinocchio'):.1e} (Pinocchio) "
                f"/ {max([v for (t, _), v in derr.items() if t == 'mujoco_fd'] or [float('nan')]):.1e} (MuJoCo FD)",
                file=sys.stderr,
            )
        print(
            f"{name}: eom FD {eom_fd:.0f} ns, Pinocchio ABA {row['pinocchio_aba_ns']:.0f} ns, "
            f"MuJoCo mj_forward {row['mujoco_forward_ns']:.0f} ns; "
            f"max relative difference {err['pinocchio']:.1e} / {err['mujoco']:.1e}"
            + (
                ""
                if robot
                else f"; against 40 digits eom {exact['eom']:.1e}, Pinocchio {exact['pinocchio']:.1e}, "
                f"MuJoCo {exact['mujoco']:.1e} (κ(M)·ε = {kappa * sys.float_info.epsilon:.1e})"
            ),
            file=sys.stderr,
        )

    for path, table_rows in [(a.csv, rows), (a.deriv_csv, drows)]:
        if not table_rows:
            continue
        os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
        with open(path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(table_rows[0]))
            w.writeheader()
            for r in table_rows:
                w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})

    print(
        "| model | dof | eom FD ns (native / generic) | Pinocchio ABA ns | MuJoCo mj_forward ns "
        "| ABA / eom (rounds) | mj_forward / eom (rounds) | eom ID ns | Pinocchio RNEA ns | eom M ns "
        "| Pinocchio CRBA ns | max rel. diff (Pin / MuJoCo) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['model']} | {r['dof']} | {r['eom_fd_ns']:.0f} / {r['eom_fd_ns_generic']:.0f} "
            f"| {r['pinocchio_aba_ns']:.0f} | {r['mujoco_forward_ns']:.0f} "
            f"| {r['pinocchio_aba_over_eom']:.1f}× ({r['pinocchio_aba_over_eom_rounds']}) "
            f"| {r['mujoco_forward_over_eom']:.1f}× ({r['mujoco_forward_over_eom_rounds']}) "
            f"| {r['eom_id_ns']:.0f} | {r['pinocchio_rnea_ns']:.0f} "
            f"| {r['eom_mass_matrix_ns']:.0f} | {r['pinocchio_crba_ns']:.0f} "
            f"| {r['max_rel_diff_pinocchio']:.1e} / {r['max_rel_diff_mujoco']:.1e} |"
        )
    print(
        "\n| model | dof | eom ∂u̇/∂(q, u, τ) ns (ops) | Pinocchio computeABADerivatives ns "
        "| MuJoCo mjd_transitionFD ns (forward / centred) | Pinocchio / eom (fastest passes; rounds) "
        "| MuJoCo forward / eom "
        f"| ≥ {TARGET:g}× Pinocchio | max rel. diff Pinocchio (∂q / ∂u / M⁻¹) "
        "| max rel. diff MuJoCo FD (∂q / ∂u) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in drows:
        print(
            f"| {r['model']} | {r['dof']} | {r['eom_derivatives_ns']:.0f} ({r['eom_derivatives_ops']}) "
            f"| {r['pinocchio_aba_derivatives_ns']:.0f} "
            f"| {r['mujoco_transition_fd_forward_ns']:.0f} / {r['mujoco_transition_fd_centered_ns']:.0f} "
            f"| {r['pinocchio_over_eom']:.1f}× ({r['pinocchio_over_eom_min']:.1f}×; {r['pinocchio_over_eom_rounds']}) "
            f"| {r['mujoco_fd_forward_over_eom']:.0f}× "
            f"| {'yes' if r['target_met'] else 'no'} "
            f"| {r['max_rel_diff_pinocchio_dq']:.1e} / {r['max_rel_diff_pinocchio_du']:.1e} / "
            f"{r['max_rel_diff_pinocchio_minv']:.1e} "
            f"| {r['max_rel_diff_mujoco_fd_dq']:.1e} / {r['max_rel_diff_mujoco_fd_du']:.1e} |"
        )
    written = [path for path, table_rows in [(a.csv, rows), (a.deriv_csv, drows)] if table_rows]
    print(f"\nwritten {', '.join(written)}", file=sys.stderr)
    if failures:
        sys.exit("results disagree:\n  " + "\n  ".join(failures))


if __name__ == "__main__":
    main()
