#!/usr/bin/env python3
"""Write an eom modal data file (`ModalData`, RON or JSON) from a generic
finite-element export.

Input (the usual export of any FE code):
  --nodes FILE      CSV, one node per line: `x, y, z` or `name, x, y, z`
                    (body axes, m); a header line and `#` comments are skipped.
  --mass FILE       the assembled mass matrix, Matrix Market coordinate format
  --stiffness FILE  the assembled stiffness matrix, Matrix Market
                    (`symmetric` or `general`); degrees of freedom node by node,
                    six per node: u_x, u_y, u_z, θ_x, θ_y, θ_z.
  --fix N:DOFS      reference conditions: degrees of freedom held at zero, e.g.
                    `--fix 0:all --fix 10:uy,uz` (names ux uy uz rx ry rz, all);
                    without `--fix` the model is free–free and its rigid-body
                    modes (the lowest six, ω ≈ 0) are dropped.
  --modes-kept K    how many of the lowest normal modes to write (default 4).
  --given-modes F   instead of solving the eigenproblem: CSV with one mode per
                    line, 6N numbers (the nodal shapes), used as they are.
  --damping ZETA    modal damping ratio of every mode written (default 0).
  --lumped-only     leave out the consistent-mass invariants (see below).
  --geometric-centrifugal FILE, --geometric-axial FILE
                    the assembled geometric stiffness matrices (Matrix Market)
                    of the body's two unit axial inertia loads, for geometric
                    stiffening (`stiffening: true` on the body): K_G under the
                    axial force N₁(x) of spinning at Ω = 1 rad/s about an axis
                    through the frame origin normal to the body's x axis, and
                    under N₂(x) of a unit axial acceleration of the root (tip
                    free, tension positive); both or neither.
  -o FILE           output, `.json` for JSON, anything else RON.

What it writes (see docs/model-format.md, "Imported modal data"):
  - nodes with the row-sum lumped mass of the translational degrees of freedom
    (m_n = mean over directions d of (M r_d)_{n,d}, r_d the rigid translation
    along d) and the row-sum lumped rotary inertia (J_n,ab = Σ_j M[(n,θ_a),(j,θ_b)]);
  - the mode shapes at the nodes (translations and rotations);
  - modal mass Φᵀ M Φ, stiffness Φᵀ K Φ and damping diag(2 ζ ω_i) (mass-normalised
    modes), from the matrices as given (consistent or lumped);
  - `consistent`: the first-order inertia invariants of M itself, with R_t, R_r
    the nodal vectors of unit rigid translations and rotations about the origin:
    mass, first moment, inertia R_rᵀ M R_r, and per mode R_tᵀ M φ_j (S̄) and
    R_rᵀ M φ_j (Ī_θf⁰). With them eom reproduces the FE model's frequencies and
    these invariants exactly (only the second-order terms stay lumped);
  - `geometric_stiffness` (with the two --geometric-* files): Φᵀ K_G Φ of each,
    symmetrised (the foreshortening matrices K₁, K₂ eom's stiffening needs).

The eigenproblem K φ = ω² M φ on the free degrees of freedom is solved with
numpy when it is installed, else by a plain-Python cyclic Jacobi method on
L⁻¹ M L⁻ᵀ with (K + σ M) = L Lᵀ (fine up to a few hundred degrees of
freedom). Mode shapes are mass-normalised, largest entry positive.
"""

import argparse
import csv
import json
import math
import sys

DOFS = ["ux", "uy", "uz", "rx", "ry", "rz"]


def read_nodes(path):
    nodes = []
    with open(path, newline="") as f:
        for row in csv.reader(f):
            row = [c.strip() for c in row if c.strip() != ""]
            if not row or row[0].startswith("#"):
                continue
            try:
                nums = [float(c) for c in row[-3:]]
            except ValueError:
                continue  # a header line
            name = row[0] if len(row) == 4 else None
            nodes.append((name, nums))
    return nodes


def read_mtx(path):
    """A dense matrix (list of rows) from a Matrix Market coordinate file."""
    with open(path) as f:
        header = f.readline().lower().split()
        if len(header) < 5 or header[0] != "%%matrixmarket" or header[2] != "coordinate":
            sys.exit(f"{path}: expected a Matrix Market coordinate file")
        symmetric = header[4] == "symmetric"
        line = f.readline()
        while line.startswith("%"):
            line = f.readline()
        rows, cols, _ = (int(x) for x in line.split())
        a = [[0.0] * cols for _ in range(rows)]
        for line in f:
            if not line.strip() or line.startswith("%"):
                continue
            i, j, v = line.split()
            i, j, v = int(i) - 1, int(j) - 1, float(v)
            a[i][j] += v
            if symmetric and i != j:
                a[j][i] += v
    return a


def cholesky(a):
    n = len(a)
    l = [[0.0] * n for _ in range(n)]
    for i in range(n):
        for j in range(i + 1):
            s = a[i][j] - sum(l[i][k] * l[j][k] for k in range(j))
            if i == j:
                if s <= 0.0:
                    sys.exit("the shifted stiffness K + σM is not positive definite: check --fix")
                l[i][i] = math.sqrt(s)
            else:
                l[i][j] = s / l[j][j]
    return l


def solve_lower(l, b):
    """L⁻¹ B for a lower-triangular L and B given by columns (list of vectors)."""
    n = len(l)
    out = []
    for col in b:
        x = [0.0] * n
        for i in range(n):
            x[i] = (col[i] - sum(l[i][k] * x[k] for k in range(i))) / l[i][i]
        out.append(x)
    return out


def solve_upper_t(l, y):
    """L⁻ᵀ y."""
    n = len(l)
    x = [0.0] * n
    for i in reversed(range(n)):
        x[i] = (y[i] - sum(l[k][i] * x[k] for k in range(i + 1, n))) / l[i][i]
    return x


def jacobi(a, sweeps=100):
    """Eigenvalues and eigenvectors (columns) of a symmetric matrix."""
    n = len(a)
    a = [row[:] for row in a]
    v = [[float(i == j) for j in range(n)] for i in range(n)]
    for _ in range(sweeps):
        off = sum(a[i][j] ** 2 for i in range(n) for j in range(i + 1, n))
        scale = sum(a[i][i] ** 2 for i in range(n))
        if off <= 1e-30 * scale:
            break
        for p in range(n):
            for q in range(p + 1, n):
                if a[p][q] == 0.0:
                    continue
                theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q])
                t = math.copysign(1.0, theta) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):
                    akp, akq = a[k][p], a[k][q]
                    a[k][p] = c * akp - s * akq
                    a[k][q] = s * akp + c * akq
                for k in range(n):
                    apk, aqk = a[p][k], a[q][k]
                    a[p][k] = c * apk - s * aqk
                    a[q][k] = s * apk + c * aqk
                for k in range(n):
                    vkp, vkq = v[k][p], v[k][q]
                    v[k][p] = c * vkp - s * vkq
                    v[k][q] = s * vkp + c * vkq
    return [a[i][i] for i in range(n)], v


def lowest_modes(k_free, m_free, count, free_free):
    """The lowest `count` elastic modes of (K, M): (ω², shapes), mass-normalised."""
    n = len(k_free)
    # Shift for free–free models (rigid modes make K singular).
    tr_k = sum(k_free[i][i] for i in range(n))
    tr_m = sum(m_free[i][i] for i in range(n))
    sigma = 1e-3 * tr_k / tr_m if free_free else 0.0
    try:
        import numpy as np

        kk = np.array(k_free) + sigma * np.array(m_free)
        l = np.linalg.cholesky(kk)
        li = np.linalg.inv(l)
        b = li @ np.array(m_free) @ li.T
        mu, y = np.linalg.eigh((b + b.T) / 2)
        vecs = [list(li.T @ y[:, j]) for j in range(n)]
        mu = list(mu)
    except ImportError:
        shifted = [[k_free[i][j] + sigma * m_free[i][j] for j in range(n)] for i in range(n)]
        l = cholesky(shifted)
        x = solve_lower(l, [[m_free[i][j] for i in range(n)] for j in range(n)])  # L⁻¹ M by columns
        # B = L⁻¹ (L⁻¹ M)ᵀ: columns of (L⁻¹ M)ᵀ are the rows of L⁻¹ M.
        rows = [[x[j][i] for j in range(n)] for i in range(n)]
        bcols = solve_lower(l, rows)
        b = [[0.5 * (bcols[j][i] + bcols[i][j]) for j in range(n)] for i in range(n)]
        mu, y = jacobi(b)
        vecs = [solve_upper_t(l, [y[i][j] for i in range(n)]) for j in range(n)]
    order = sorted(range(n), key=lambda j: -mu[j])
    out = []
    for j in order:
        if mu[j] <= 0.0:
            continue
        w2 = 1.0 / mu[j] - sigma
        if free_free and w2 < 1e-6 * sigma:
            continue  # a rigid-body mode
        vec = vecs[j]
        mass = sum(vec[r] * sum(m_free[r][c] * vec[c] for c in range(n)) for r in range(n))
        big = max(vec, key=abs)
        s = math.copysign(1.0, big) / math.sqrt(mass)
        out.append((w2, [s * x for x in vec]))
        if len(out) == count:
            break
    return out


def quad(a, x, y):
    return sum(x[r] * sum(a[r][c] * y[c] for c in range(len(y)) if a[r][c] != 0.0) for r in range(len(x)))


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--nodes", required=True)
    p.add_argument("--mass", required=True)
    p.add_argument("--stiffness", required=True)
    p.add_argument("--fix", action="append", default=[])
    p.add_argument("--modes-kept", type=int, default=4)
    p.add_argument("--given-modes")
    p.add_argument("--damping", type=float, default=0.0)
    p.add_argument("--lumped-only", action="store_true")
    p.add_argument("--geometric-centrifugal")
    p.add_argument("--geometric-axial")
    p.add_argument("-o", "--output", required=True)
    a = p.parse_args()

    nodes = read_nodes(a.nodes)
    m = read_mtx(a.mass)
    k = read_mtx(a.stiffness)
    ndof = 6 * len(nodes)
    if len(m) != ndof or len(k) != ndof:
        sys.exit(f"{len(nodes)} nodes need {ndof}×{ndof} matrices; got {len(m)} and {len(k)}")

    fixed = set()
    for spec in a.fix:
        node, _, dofs = spec.partition(":")
        names = DOFS if dofs in ("", "all") else dofs.split(",")
        for d in names:
            if d not in DOFS:
                sys.exit(f"--fix {spec}: unknown degree of freedom `{d}` (use {', '.join(DOFS)} or all)")
            fixed.add(6 * int(node) + DOFS.index(d))
    free = [i for i in range(ndof) if i not in fixed]

    if a.given_modes:
        shapes = []
        with open(a.given_modes) as f:
            for row in csv.reader(f):
                if row and not row[0].startswith("#"):
                    shapes.append([float(x) for x in row])
    else:
        kf = [[k[i][j] for j in free] for i in free]
        mf = [[m[i][j] for j in free] for i in free]
        modes = lowest_modes(kf, mf, a.modes_kept, free_free=not fixed)
        shapes = []
        for _, vec in modes:
            full = [0.0] * ndof
            for r, i in enumerate(free):
                full[i] = vec[r]
            shapes.append(full)

    kk = len(shapes)
    modal_mass = [[quad(m, shapes[i], shapes[j]) for j in range(kk)] for i in range(kk)]
    modal_stiffness = [[quad(k, shapes[i], shapes[j]) for j in range(kk)] for i in range(kk)]
    damping = [
        [2.0 * a.damping * math.sqrt(modal_stiffness[i][i] / modal_mass[i][i]) * modal_mass[i][i] if i == j else 0.0 for j in range(kk)]
        for i in range(kk)
    ]

    out_nodes = []
    for n, (name, pos) in enumerate(nodes):
        masses = [sum(m[6 * n + d][6 * j + d] for j in range(len(nodes))) for d in range(3)]
        inertia = [[sum(m[6 * n + 3 + r][6 * j + 3 + c] for j in range(len(nodes))) for c in range(3)] for r in range(3)]
        node = {"position": pos, "mass": sum(masses) / 3.0}
        if any(x != 0.0 for row in inertia for x in row):
            node["inertia"] = inertia
        if name is not None:
            node["name"] = name
        out_nodes.append(node)
    out_modes = [
        {
            "translation": [s[6 * n : 6 * n + 3] for n in range(len(nodes))],
            "rotation": [s[6 * n + 3 : 6 * n + 6] for n in range(len(nodes))],
        }
        for s in shapes
    ]
    data = {
        "doc": f"written by examples/modal_export.py from {a.mass}, {a.stiffness}",
        "nodes": out_nodes,
        "modes": out_modes,
        "modal_mass": modal_mass,
        "modal_stiffness": modal_stiffness,
    }
    if a.damping > 0.0:
        data["modal_damping"] = damping
    if not a.lumped_only:
        data["consistent"] = consistent(m, nodes, shapes)
    if bool(a.geometric_centrifugal) != bool(a.geometric_axial):
        sys.exit("--geometric-centrifugal and --geometric-axial go together")
    if a.geometric_centrifugal:
        data["geometric_stiffness"] = {}
        for key, path in (("centrifugal", a.geometric_centrifugal), ("axial", a.geometric_axial)):
            g = read_mtx(path)
            if len(g) != ndof:
                sys.exit(f"{path}: {len(nodes)} nodes need a {ndof}×{ndof} matrix; got {len(g)}")
            full = [[quad(g, shapes[i], shapes[j]) for j in range(kk)] for i in range(kk)]
            data["geometric_stiffness"][key] = [[0.5 * (full[i][j] + full[j][i]) for j in range(kk)] for i in range(kk)]
    with open(a.output, "w") as f:
        if a.output.lower().endswith(".json"):
            json.dump(data, f, indent=1)
        else:
            f.write(to_ron(data))


def consistent(m, nodes, shapes):
    """First-order inertia invariants of the mass matrix m (see the docstring)."""
    ndof = 6 * len(nodes)
    rigid = [[0.0] * ndof for _ in range(6)]  # columns of R, as rows here
    for n, (_, r) in enumerate(nodes):
        for d in range(3):
            rigid[d][6 * n + d] = 1.0
        for a in range(3):
            e = [float(a == i) for i in range(3)]
            cross = [e[1] * r[2] - e[2] * r[1], e[2] * r[0] - e[0] * r[2], e[0] * r[1] - e[1] * r[0]]
            for d in range(3):
                rigid[3 + a][6 * n + d] = cross[d]
            rigid[3 + a][6 * n + 3 + a] = 1.0
    g = [[quad(m, rigid[i], rigid[j]) for j in range(6)] for i in range(6)]
    mass = (g[0][0] + g[1][1] + g[2][2]) / 3.0
    # R_tᵀ M R_r = −c̃ for the first moment c.
    first = [g[1][5], g[2][3], g[0][4]]
    return {
        "mass": mass,
        "first_moment": first,
        "inertia": [[g[3 + i][3 + j] for j in range(3)] for i in range(3)],
        "s_bar": [[quad(m, rigid[d], s) for d in range(3)] for s in shapes],
        "coupling": [[quad(m, rigid[3 + a], s) for a in range(3)] for s in shapes],
    }


def to_ron(data):
    # Positions, translations, rotations are tuples `(x, y, z)`, inertia a tuple of tuples.
    def tup(v):
        return "(" + ", ".join(repr(float(x)) for x in v) + ")"

    lines = ["// eom modal data (docs/model-format.md, \"Imported modal data\")", "ModalData("]
    lines.append(f"    doc: {json.dumps(data['doc'])},")
    lines.append("    nodes: [")
    for n in data["nodes"]:
        parts = [f"position: {tup(n['position'])}", f"mass: {repr(float(n['mass']))}"]
        if "inertia" in n:
            parts.append("inertia: (" + ", ".join(tup(r) for r in n["inertia"]) + ")")
        if "name" in n:
            parts.append(f"name: {json.dumps(n['name'])}")
        lines.append("        (" + ", ".join(parts) + "),")
    lines.append("    ],")
    lines.append("    modes: [")
    for mode in data["modes"]:
        lines.append("        (")
        lines.append("            translation: [" + ", ".join(tup(t) for t in mode["translation"]) + "],")
        lines.append("            rotation: [" + ", ".join(tup(t) for t in mode["rotation"]) + "],")
        lines.append("        ),")
    lines.append("    ],")
    for key in ("modal_mass", "modal_stiffness", "modal_damping"):
        if key in data:
            rows = ", ".join("[" + ", ".join(repr(float(x)) for x in row) + "]" for row in data[key])
            lines.append(f"    {key}: [{rows}],")
    if "consistent" in data:
        c = data["consistent"]
        lines.append("    consistent: (")
        lines.append(f"        mass: {repr(float(c['mass']))},")
        lines.append(f"        first_moment: {tup(c['first_moment'])},")
        lines.append("        inertia: (" + ", ".join(tup(r) for r in c["inertia"]) + "),")
        lines.append("        s_bar: [" + ", ".join(tup(v) for v in c["s_bar"]) + "],")
        lines.append("        coupling: [" + ", ".join(tup(v) for v in c["coupling"]) + "],")
        lines.append("    ),")
    if "geometric_stiffness" in data:
        g = data["geometric_stiffness"]
        lines.append("    geometric_stiffness: (")
        for key in ("centrifugal", "axial"):
            rows = ", ".join("[" + ", ".join(repr(float(x)) for x in row) + "]" for row in g[key])
            lines.append(f"        {key}: [{rows}],")
        lines.append("    ),")
    lines.append(")")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
