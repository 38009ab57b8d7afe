"""eom on the robots of example-robot-data, against Pinocchio (issue 15).

Run by run.sh (which installs `pin` and `example-robot-data` into a venv and
builds eom-gen); see README.md. For every URDF of the collection:

1. writes a copy with the `<mimic>` tags removed (Pinocchio's default parser
   ignores them; eom would add a holonomic constraint for each);
2. `eom-gen check --json` (loads? which warnings) and `eom-gen stats --json`
   (operation counts, generation time; the process's wall time is import +
   generation);
3. builds the Pinocchio model of the same file (`pin.buildModelFromUrdf`,
   fixed base) and maps its joints to eom's coordinates by name;
4. at STATES random states (positions uniform in [-pi, pi], speeds and
   forces in [-1, 1]) runs `eom-gen eval --json` (compiled for the robots of
   `--compile`, else `--interpret`) and compares the mass matrix with
   `pin.crba` and the accelerations with `pin.aba` at tau - D u, D the URDF
   damping (eom applies it as a joint damper; Pinocchio's ABA does not):
   max |difference| / max |Pinocchio's value|;
5. a 1 s `eom-gen simulate --json` from the model's initial state;
6. with `--timing ROBOT ...`: `eom-gen bench --per-call --json` and the C++
   program `aba_timing` (Pinocchio ABA over the same kind of random states,
   compiled with -O3 -march=native); run.sh builds it.

Prints one progress line per robot and writes the Markdown table (and the raw
rows as JSON beside it). Nothing here is timed but the wall clock of eom-gen's
processes.
"""

import argparse
import glob
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

TOLERANCE = 1e-12

# What the Pinocchio comparison covers: 1-DOF joints (the collection has no
# other movable kind once its commented-out floating bases are left aside).
ONE_DOF = ("revolute", "continuous", "prismatic")

# Compiled eval and simulate for these small robots (besides every robot
# over 16 DOF, which the interpreter cannot simulate): each family once, the
# zero-DOF case and the timing robots; the rest interpreted.
DEFAULT_COMPILE = [
    "double_pendulum",
    "ur5_robot",
    "panda",
    "solo12",
    "bolt",
    "quadrotor_base",
]
DEFAULT_TIMING = ["panda", "ur5_robot", "talos_reduced"]

# Names eom reserves (t, pi, ground and its function names) get a trailing
# `_`; see `identifier` in eom-gen/src/model/urdf.rs.
RESERVED = {"t", "pi", "ground", "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sqrt", "exp",
            "ln", "log", "abs", "sign", "min", "max", "pow", "sinh", "cosh", "tanh", "floor", "ceil"}


def identifier(name):
    s = "".join(c if (c.isascii() and c.isalnum()) else "_" for c in name)
    if not s or s[0].isdigit():
        s = "_" + s
    if s in RESERVED:
        s += "_"
    return s


class Failed(Exception):
    pass


def run(cmd, env, timeout=1500):
    t0 = time.perf_counter()
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)
    return out, time.perf_counter() - t0


def run_json(cmd, env, what, timeout=1500):
    out, secs = run(cmd, env, timeout)
    if out.returncode != 0:
        raise Failed(f"{what} failed ({out.returncode}): {first_error(out.stderr)}")
    return json.loads(out.stdout), secs


def first_error(stderr):
    lines = [ln.strip() for ln in stderr.splitlines() if "error" in ln]
    return (lines[0] if lines else stderr.strip().splitlines()[-1] if stderr.strip() else "")[:300]


def strip_mimic(text):
    return re.sub(r"<mimic\b[^>]*/>|<mimic\b[^>]*>.*?</mimic>", "", text, flags=re.S)


def urdf_damping(path):
    """Joint name -> URDF `<dynamics damping>` (0 if absent); the joints of
    the robot, not the `<joint>` references inside `<transmission>`."""
    out = {}
    for j in ET.parse(path).getroot().findall("joint"):
        d = j.find("dynamics")
        out[j.get("name")] = float(d.get("damping", "0")) if d is not None else 0.0
    return out


def join(v):
    return ",".join(repr(float(x)) for x in v)


def singular_in_pinocchio(path):
    """True when Pinocchio's mass matrix at its neutral configuration is
    singular (its ABA then gives NaN): the file's dynamics are ill-posed."""
    model = pin.buildModelFromUrdf(path)
    if model.nv == 0:
        return False
    m = pin.crba(model, model.createData(), pin.neutral(model))
    m = np.triu(m) + np.triu(m, 1).T
    ev = np.linalg.eigvalsh(m)
    return ev[0] <= 1e-12 * ev[-1]


def compare(eom, original, path, short, nstates, rng, compiled, env):
    """One robot; returns the row (raises Failed for a failed step).
    `original` is the file as shipped, `path` the copy without mimic tags."""
    row = {"robot": short}
    info, secs = run(eom_cmd(eom, "check", original, "--json"), env)
    if info.returncode != 0:
        row["outcome"] = "rejected"
        row["why"] = first_error(info.stderr)
        if "has no links" in info.stderr:
            row["outcome"] = "rejected: empty file"
        else:
            try:
                if singular_in_pinocchio(path):
                    row["outcome"] = "rejected: mass matrix singular (Pinocchio's too)"
            except Exception as e:  # Pinocchio cannot load it either
                row["outcome"] = "rejected (Pinocchio too)"
                row["why"] += f"; Pinocchio: {e}"
        return row
    w = json.loads(info.stdout).get("warnings", 0)
    row["warnings_original"] = w if isinstance(w, int) else len(w)
    info, secs = run(eom_cmd(eom, "check", path, "--json"), env)
    if info.returncode != 0:
        raise Failed(f"loads, but not without its mimic tags: {first_error(info.stderr)}")
    info = json.loads(info.stdout)
    if compiled is None:
        # The interpreter integrates up to 32 states.
        compiled = 2 * info["nu"] > 32
    row["mode"] = "compiled" if compiled else "interpreted"
    row["nq"], row["nu"] = info["nq"], info["nu"]
    w = info.get("warnings", 0)
    row["warnings"] = w if isinstance(w, int) else len(w)
    row["check_s"] = secs
    stats, secs = run_json(eom_cmd(eom, "stats", path, "--json"), env, "stats")
    row["import_generate_s"] = secs
    row["generation_ms"] = stats["generation_ms"]
    row["fd_ops"] = (stats["ops"].get("forward_dynamics") or {}).get("total")
    row["mass_matrix_ops"] = (stats["ops"].get("mass_matrix") or {}).get("total")
    row["formulation"] = stats["formulation"]

    # Pinocchio's model and the map from its speeds to eom's.
    model = pin.buildModelFromUrdf(path)
    data = model.createData()
    row["pin_nv"] = model.nv
    names = info["coordinate_names"]
    index = {n: k for k, n in enumerate(names)}
    perm = []  # perm[pinocchio v index] = eom speed index
    pin_q = []  # (idx_q, nq) per Pinocchio speed, in v order
    damping = urdf_damping(path)
    for j, joint in zip(model.names[1:], model.joints[1:]):
        if joint.nv != 1:
            raise Failed(f"Pinocchio joint `{j}` has {joint.nv} speeds (only 1-DOF joints are compared)")
        eom_name = identifier(j)
        if eom_name not in index:
            raise Failed(f"no eom coordinate for Pinocchio joint `{j}` (looked for `{eom_name}`)")
        perm.append(index[eom_name])
        pin_q.append((joint.idx_q, joint.nq, damping.get(j, 0.0)))
    if sorted(perm) != list(range(len(names))) or model.nv != info["nu"]:
        raise Failed(f"joints differ: Pinocchio nv {model.nv}, eom nu {info['nu']}")
    pin_damping = np.array(model.damping)
    row["damping"] = max([d for _, _, d in pin_q], default=0.0)
    ours_d = np.array([d for _, _, d in pin_q])
    if len(ours_d) and np.max(np.abs(pin_damping - ours_d)) > 0:
        row["note"] = "Pinocchio's model.damping differs from the URDF's"

    dm = du = kappa = 0.0
    eval_s = []
    start = None
    for _ in range(nstates):
        q = rng.uniform(-math.pi, math.pi, len(names))
        start = q if start is None else start
        u = rng.uniform(-1, 1, len(names))
        tau = rng.uniform(-1, 1, len(names))
        args = ["--q", join(q), "--u", join(u), "--tau", join(tau), "--json"]
        if not compiled:
            args.append("--interpret")
        e, secs = run_json(eom_cmd(eom, "eval", path, *args), env, "eval")
        eval_s.append(secs)
        # Pinocchio's state in its order; continuous joints are (cos, sin).
        qp = pin.neutral(model)
        vp = np.zeros(model.nv)
        tp = np.zeros(model.nv)
        for v, (iq, nq, d) in enumerate(pin_q):
            k = perm[v]
            if nq == 2:
                qp[iq], qp[iq + 1] = math.cos(q[k]), math.sin(q[k])
            else:
                qp[iq] = q[k]
            vp[v] = u[k]
            tp[v] = tau[k] - d * u[k]
        m_pin = pin.crba(model, data, qp)
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
        a_pin = pin.aba(model, data, qp, vp, tp)
        if model.nv:
            m_eom = np.array(e["mass_matrix"], dtype=float).reshape(model.nv, model.nv)
            m_eom = np.tril(m_eom) + np.tril(m_eom, -1).T  # eom fills the lower triangle
            m_eom = m_eom[np.ix_(perm, perm)]
            a_eom = np.array(e["udot"], dtype=float)[perm]
            dm = max(dm, np.max(np.abs(m_eom - m_pin)) / np.max(np.abs(m_pin)))
            kappa = max(kappa, np.linalg.cond(m_pin))
            du = max(du, np.max(np.abs(a_eom - a_pin)) / max(np.max(np.abs(a_pin)), 1e-300))
        elif e.get("udot", []) != []:
            raise Failed("zero-DOF eval printed accelerations")
    row["dM"], row["dudot"] = dm, du
    row["eval_s"] = eval_s
    if compiled and len(eval_s) > 1:
        # The first call builds the crate; the others reuse it.
        row["compile_s"] = eval_s[0] - min(eval_s[1:])

    # From the first random configuration at rest (the initial state, zero,
    # can be a configuration singularity: icub's neck).
    sim_args = ["--t-end", "1", "--json", "--q0", join(start if start is not None else []),
                "--u0", join(np.zeros(len(names)))] + ([] if compiled else ["--interpret"])
    row["simulate_integrator"] = "dopri5"
    out, secs = run(eom_cmd(eom, "simulate", path, *sim_args), env)
    if out.returncode == 3 and "step limit" in out.stderr:
        # Stiff (allegro: damping 10 N m s on 1e-5 kg m² fingers, time
        # constants of microseconds): the implicit method.
        row["simulate_integrator"] = "radau5 (DOPRI5: " + first_error(out.stderr).split(": ", 1)[-1][:60] + "…)"
        out, secs = run(eom_cmd(eom, "simulate", path, *sim_args, "--integrator", "radau5"), env)
    if out.returncode != 0:
        raise Failed(f"simulate failed ({out.returncode}): {first_error(out.stderr)}")
    sim = json.loads(out.stdout)
    row["simulate_s"] = secs
    row["simulate_steps"] = sim.get("stats", {}).get("accepted")
    row["simulate_cpu_s"] = sim.get("cpu_s")
    row["simulate_t"] = sim.get("t")
    row["cond_M"] = kappa
    row["outcome"] = "agrees" if dm <= TOLERANCE and du <= TOLERANCE else "disagrees"
    if dm <= TOLERANCE and TOLERANCE < du <= 1e-15 * kappa:
        # Solving with M loses up to cond(M) times the rounding of M and
        # of the forces, in both tools (icub: cond(M) ~ 1e7).
        row["outcome"] = "agrees to cond(M)·1e-15 (M ill-conditioned)"
    if info["nu"] == 0:
        row["outcome"] = "zero DOF: eval and simulate on empty vectors"
    if sim.get("t") != 1.0:
        row["outcome"] = "simulate stopped early"
    return row


def eom_cmd(eom, *args):
    return [eom, *args]


def timing(eom, path, row, aba_exe, states, reps, env):
    """eom FD ns per call (compiled timing program, --native) and Pinocchio ABA
    ns per call (C++), over random states of the same distribution."""
    b, _ = run_json([eom, "bench", path, "--per-call", "--json", "--native", "--states", str(states),
                     "--reps", str(reps)], env, "bench")
    row["eom_fd_ns"] = b["forward_dynamics_ns"]
    row["eom_mass_matrix_ns"] = b.get("mass_matrix_ns")
    row["eom_id_ns"] = b.get("inverse_dynamics_ns")
    if aba_exe:
        out, _ = run([aba_exe, path, str(states), str(reps), "1"], env)
        if out.returncode != 0:
            raise Failed(f"aba_timing failed: {out.stderr.strip()}")
        p = json.loads(out.stdout)
        row["pin_aba_ns"] = p["aba"]["median"]
        row["pin_crba_ns"] = p["crba"]["median"]
        row["pin_rnea_ns"] = p["rnea"]["median"]
        # The C++ model (urdfdom + Pinocchio's API) against Pinocchio's parser.
        model = pin.buildModelFromUrdf(path)
        data = model.createData()
        s = p["check"]
        if model.nq != model.nv:  # continuous joints: (cos, sin) in the parser's model
            return
        ref = pin.aba(model, data, np.array(s["q"]), np.array(s["v"]), np.array(s["tau"]))
        row["aba_cpp_vs_parser"] = float(np.max(np.abs(ref - np.array(s["a"]))) / np.max(np.abs(ref)))


def fmt(x, spec):
    return "—" if x is None else format(x, spec)


def simulated(r):
    if "simulate_s" not in r:
        return "—"
    method = r.get("simulate_integrator", "dopri5").split(" ")[0]
    return f"{method}, {r.get('simulate_steps')}, {r['simulate_s']:.1f}"


def table(rows):
    lines = [
        "| robot | nq | outcome | warnings | max rel. ΔM | max rel. Δu̇ | max cond(M) | max damping | import+generate s "
        "| FD ops | M ops | eval mode | compile s | simulate 1 s: method, steps, wall s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        outcome = r["outcome"] + (f": {r['why']}" if r.get("why") else "")
        lines.append(
            f"| {r['robot']} | {r.get('nq', '—')} | {outcome} | {r.get('warnings_original', '—')} "
            f"| {fmt(r.get('dM'), '.1e')} "
            f"| {fmt(r.get('dudot'), '.1e')} | {fmt(r.get('cond_M'), '.0e')} | {fmt(r.get('damping'), 'g')} "
            f"| {fmt(r.get('import_generate_s'), '.2f')} | {fmt(r.get('fd_ops'), 'd')} "
            f"| {fmt(r.get('mass_matrix_ops'), 'd')} | {r.get('mode', '—')} | {fmt(r.get('compile_s'), '.1f')} "
            f"| {simulated(r)} |"
        )
    return "\n".join(lines)


def write(rows, path, states, seed):
    """The Markdown table at `path` and the rows as JSON beside it."""
    counts = {}
    for r in rows:
        counts[r["outcome"]] = counts.get(r["outcome"], 0) + 1
    timed = [r for r in rows if "eom_fd_ns" in r]
    with open(path, "w") as out:
        out.write("# eom on example-robot-data, against Pinocchio\n\n")
        out.write(f"Written by `bench/robots/run.sh` (Pinocchio {pin.__version__}); "
                  f"{states} random states per robot, seed {seed}; tolerance {TOLERANCE:g} "
                  "(max |difference| / max |Pinocchio's value|). A dash: not measured "
                  "(cond(M) only in the later runs of `--merge`).\n\n")
        out.write("| outcome | files |\n|---|---|\n")
        for k, v in sorted(counts.items(), key=lambda kv: -kv[1]):
            out.write(f"| {k} | {v} |\n")
        out.write("\n" + table(rows) + "\n")
        if timed:
            out.write("\n## Forward dynamics, ns per call\n\n")
            out.write("| robot | nv | eom FD ns (compiled, native) | Pinocchio ABA ns (C++) | ABA / eom "
                      "| eom M ns | Pinocchio CRBA ns | eom ID ns | Pinocchio RNEA ns |\n")
            out.write("|---|---|---|---|---|---|---|---|---|\n")
            for r in timed:
                aba = r.get("pin_aba_ns")
                out.write(
                    f"| {r['robot']} | {r['nu']} | {r['eom_fd_ns']:.0f} | {fmt(aba, '.0f')} "
                    f"| {fmt(aba / r['eom_fd_ns'] if aba else None, '.1f')} "
                    f"| {fmt(r.get('eom_mass_matrix_ns'), '.0f')} | {fmt(r.get('pin_crba_ns'), '.0f')} "
                    f"| {fmt(r.get('eom_id_ns'), '.0f')} | {fmt(r.get('pin_rnea_ns'), '.0f')} |\n"
                )
    with open(os.path.splitext(path)[0] + ".json", "w") as out:
        json.dump(rows, out, indent=1)
    print(f"written {path}: " + ", ".join(f"{v} {k}" for k, v in counts.items()), file=sys.stderr)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--eom", required=True, help="the eom-gen binary")
    ap.add_argument("--robots", required=True, help="example-robot-data's robots directory")
    ap.add_argument("--work", required=True, help="scratch directory (URDF copies)")
    ap.add_argument("--out", required=True, help="the Markdown table to write")
    ap.add_argument("--states", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--only", nargs="*", help="robots (file stems) to run (default: all)")
    ap.add_argument("--compile", nargs="*", default=DEFAULT_COMPILE,
                    help="robots evaluated compiled besides those over 16 DOF, which the interpreter cannot "
                    "simulate ('all' for every one; default: a representative subset of the small ones)")
    ap.add_argument("--timing", nargs="*", default=DEFAULT_TIMING, help="robots timed against Pinocchio ABA")
    ap.add_argument("--aba", help="the C++ Pinocchio ABA timing program (default: no Pinocchio timing)")
    ap.add_argument("--merge", action="store_true",
                    help="keep the rows of robots not run now from the JSON beside --out")
    ap.add_argument("--timing-states", type=int, default=1024)
    ap.add_argument("--timing-reps", type=int, default=31)
    a = ap.parse_args()

    env = dict(os.environ)
    files = sorted(glob.glob(os.path.join(a.robots, "**", "*.urdf"), recursive=True))
    os.makedirs(a.work, exist_ok=True)
    rows = []
    rng = np.random.default_rng(a.seed)
    stems = [os.path.splitext(os.path.basename(f))[0] for f in files]
    for f, stem in zip(files, stems):
        if a.only and stem not in a.only:
            continue
        # Two files share a stem (anymal.urdf): name the second by its folder.
        short = stem if stems.count(stem) == 1 else os.path.relpath(f, a.robots).split(os.sep)[0] + "/" + stem
        path = os.path.join(a.work, short.replace("/", "__") + ".urdf")
        with open(f) as src, open(path, "w") as dst:
            dst.write(strip_mimic(src.read()))
        # None: compiled when the interpreter cannot simulate it.
        compiled = True if ("all" in a.compile or stem in a.compile) else None
        t0 = time.perf_counter()
        try:
            row = compare(a.eom, f, path, short, a.states, rng, compiled, env)
        except Failed as e:
            row = {"robot": short, "outcome": "failed", "why": str(e)}
        except Exception as e:  # Pinocchio cannot load it, say
            row = {"robot": short, "outcome": "failed", "why": f"{type(e).__name__}: {e}"}
        row["file"] = os.path.relpath(f, a.robots)
        if "why" in row:  # paths relative to the collection
            row["why"] = row["why"].replace(os.path.abspath(a.robots) + os.sep, "").replace(a.robots + os.sep, "")
        if stem in a.timing and row["outcome"] == "agrees":
            try:
                timing(a.eom, path, row, a.aba, a.timing_states, a.timing_reps, env)
            except Failed as e:
                row["timing_error"] = str(e)
        rows.append(row)
        print(
            f"[{len(rows):2}] {short}: {row['outcome']}"
            + (f" ({row['why']})" if row.get("why") else "")
            + (f", nq {row['nq']}, ΔM {row['dM']:.1e}, Δu̇ {row['dudot']:.1e}" if "dM" in row else "")
            + (f", {row['mode']}" if "dM" in row else "")
            + f", {time.perf_counter() - t0:.1f} s",
            file=sys.stderr,
            flush=True,
        )

    if a.merge and os.path.exists(os.path.splitext(a.out)[0] + ".json"):
        # Earlier rows of the robots not run now, in file order.
        with open(os.path.splitext(a.out)[0] + ".json") as f:
            old = {r["robot"]: r for r in json.load(f)}
        old.update({r["robot"]: r for r in rows})
        rows = sorted(old.values(), key=lambda r: r.get("file", r["robot"]))
    write(rows, a.out, a.states, a.seed)


if __name__ == "__main__":
    main()
