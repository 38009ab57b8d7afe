//! Elements of absolute nodal coordinates (ANCF; Shabana, *Dynamics of
//! Multibody Systems*, ch. 7), derived symbolically once per element type.
//!
//! An element's coordinates are the positions and position gradients of
//! its two nodes in the inertial frame. Its mass matrix is constant and its
//! elastic forces carry all the nonlinearity. For each element type this
//! module builds, in an [`Arena`]:
//! - the strain energy `U(q)` (a Gauss rule fixed here and unrolled, or
//!   exact where the integrand is a polynomial: a Gauss rule of enough
//!   points is exact for it),
//! - the Kelvin–Voigt dissipation function `R(q, q̇)` (the same strain
//!   measures' rates, squared),
//! - the constant consistent mass matrix and the generalised force of a
//!   uniform load, integrated exactly (rational coefficients),
//!
//! and differentiates them with [`Arena::diff`]: `f_int = ∂U/∂q + ∂R/∂q̇`,
//! `K = ∂f_int/∂q` (not symmetric with damping: it holds `∂(D q̇)/∂q`),
//! `D = ∂f_int/∂q̇ = ∂²R/∂q̇²` (symmetric, built on one triangle), and for
//! undamped elements and statics the elastic kernels `∂U/∂q` and the
//! symmetric `∂²U/∂q²` (built on the upper triangle and mirrored). The
//! results are lowered to [`Program`]s (common subexpressions shared across
//! all outputs of a kernel) and emitted by [`emit::emit`] as one
//! `eom_elements::ElementKernel` implementation per element type.
//!
//! Element types ([`Kind`]):
//! - [`Kind::Cable2D`]: planar cable, Gerstmayr and Irschik 2008,
//!   `ε = |r'| − 1`, `κ = (r' × r'')/|r'|²`;
//! - [`Kind::Cable2DGreen`]: planar cable, Green axial strain
//!   `ε_G = ½(r'·r' − 1)` and `κ ≈ r' × r''` (polynomial, integrated exactly);
//! - [`Kind::Cable3D`]: spatial cable (no torsion), `ε = |r'| − 1`,
//!   `κ = |r' × r''|/|r'|³` (Gerstmayr and Shabana 2006);
//! - [`Kind::Beam2D`]: planar fully parameterised beam, Green–Lagrange
//!   strain of the continuum (Omar and Shabana 2001; Berzeri and Shabana
//!   2000), against locking with ν = 0 in the normal-strain terms and
//!   Cowper's shear correction (Sopanen and Mikkola 2003; Gerstmayr,
//!   Matikainen and Mikkola 2008).

pub mod emit;
mod gauss;
mod kind;
mod shapes;

pub use gauss::gauss_legendre;
pub use kind::Kind;

use crate::sym::{Arena, Id, LowerOptions, OpCount, Program, SymId, SymKind};

/// An element type's symbolic definition (built by [`define`]).
pub struct Definition {
    /// Type name as written in models and of the generated struct.
    pub name: &'static str,
    /// File stem of the generated module (`elements/src/<module>.rs`).
    pub module: &'static str,
    /// Dimension of positions.
    pub dim: usize,
    /// Coordinates per node.
    pub node_coords: usize,
    /// Names of the per-coordinate slots of a node, e.g. `["r_x", "r_y", "r'_x", "r'_y"]`.
    pub node_layout: Vec<String>,
    /// Parameter names, in order, and their meaning.
    pub params: Vec<(&'static str, &'static str)>,
    /// What the element is (formulation, strain measures, sources), markdown.
    pub summary: String,
    /// The integration rule and why, markdown.
    pub integration: String,
    /// Linear combinations of `q` shared by the points' `z` (symbols and
    /// their expressions; `z` may be written in these symbols).
    pub pre: Vec<(SymId, Id)>,
    /// The quadrature points: `U = Σ weight·φ(z)`, `R = Σ weight·ψ(z, ż)`.
    pub points: Vec<Point>,
    /// Mass matrix entries, row-major `n × n`.
    pub mass: Vec<Vec<Id>>,
    /// Generalised force of the uniform load `(w_x, w_y, w_z)` per unit length.
    pub load: Vec<Id>,
}

impl Definition {
    /// Coordinates per element.
    pub fn n(&self) -> usize {
        2 * self.node_coords
    }
}

/// One quadrature point of an element: the kinematic values `z` there
/// (linear in `q`: derivatives of the position field), and the energy and
/// dissipation densities written in symbols standing for `z` and `ż`.
pub struct Point {
    /// Quadrature weight times the measure (`w L`, `w L b h`).
    pub weight: Id,
    /// `z` in terms of `q`.
    pub z: Vec<Id>,
    /// The symbols standing for `z` (inputs `zz<g>_<a>`).
    pub zs: Vec<SymId>,
    /// The symbols standing for `ż` (inputs `zv<g>_<a>`).
    pub zds: Vec<SymId>,
    /// Energy density `φ(z)` (per unit weight).
    pub phi: Id,
    /// Dissipation density `ψ(z, ż)`, quadratic in `ż`.
    pub psi: Id,
}

impl Point {
    /// A point with fresh symbols for `z`, `ż` (densities zero until set).
    pub fn new(a: &mut Arena, g: usize, weight: Id, z: Vec<Id>) -> Point {
        let sym = |a: &mut Arena, name: String| {
            let id = a.input(&name).expect("point symbols are identifiers");
            a.as_sym(id).expect("an input is a symbol")
        };
        let zs = (0..z.len()).map(|i| sym(a, format!("zz{g}_{i}"))).collect();
        let zds = (0..z.len()).map(|i| sym(a, format!("zv{g}_{i}"))).collect();
        let zero = a.constant(0.0);
        Point {
            weight,
            z,
            zs,
            zds,
            phi: zero,
            psi: zero,
        }
    }

    /// The symbol nodes standing for `z`.
    pub fn z_nodes(&self, a: &Arena) -> Vec<Id> {
        self.zs.iter().map(|&s| a.sym_node(s)).collect()
    }

    /// The rate of a strain `e(z)`: `Σ ∂e/∂z_a ż_a`.
    pub fn rate(&self, a: &mut Arena, e: Id) -> Id {
        let terms: Vec<Id> = self
            .zs
            .iter()
            .zip(&self.zds)
            .map(|(&z, &zd)| {
                let d = a.diff(e, z);
                let v = a.sym_node(zd);
                a.mul2(d, v)
            })
            .collect();
        a.add(&terms)
    }
}

/// The symbols an element definition is written in.
pub struct Symbols {
    /// Element coordinates `q_0 … q_{n−1}`.
    pub q: Vec<Id>,
    /// Their rates.
    pub qd: Vec<Id>,
    /// Parameters, in [`Definition::params`] order.
    pub p: Vec<Id>,
    /// The uniform load per unit length `(w_x, w_y, w_z)`.
    pub w: [Id; 3],
}

/// Name of the load symbols.
pub const LOAD_NAMES: [&str; 3] = ["w_x", "w_y", "w_z"];

fn symbols(a: &mut Arena, n: usize, params: &[(&str, &str)]) -> Symbols {
    let q = (0..n as u32).map(|i| a.q(i)).collect();
    let qd = (0..n as u32).map(|i| a.qd(i)).collect();
    let p = params
        .iter()
        .map(|(name, _)| {
            a.param(name)
                .expect("element parameter names are identifiers")
        })
        .collect();
    let w = LOAD_NAMES.map(|name| a.input(name).expect("load names are identifiers"));
    Symbols { q, qd, p, w }
}

/// Builds the definition of `kind` in `a`.
pub fn define(a: &mut Arena, kind: Kind) -> Definition {
    match kind {
        Kind::Cable2D => shapes::cable2d(a, false),
        Kind::Cable2DGreen => shapes::cable2d(a, true),
        Kind::Cable3D => shapes::cable3d(a),
        Kind::Beam2D => shapes::beam2d(a),
    }
}

/// The derived kernels of one element type.
pub struct Kernels {
    /// The arena everything lives in.
    pub arena: Arena,
    /// The definition.
    pub def: Definition,
    /// `f_int` (outputs `f0 … f{n−1}`).
    pub forces: Program,
    /// `K` then `D`, row-major (outputs `k_i_j`, then `d_i_j`).
    pub jacobians: Program,
    /// `∂U/∂q`: the forces without the dissipation (outputs `f0 …`).
    pub elastic_forces: Program,
    /// `∂²U/∂q²`, symmetric, row-major (outputs `k_i_j`).
    pub elastic_stiffness: Program,
    /// Indices of the parameters that only the dissipation uses; with all
    /// of them zero the element is undamped and the elastic programs give
    /// its forces and `K` exactly (`D = 0`).
    pub damping_params: Vec<usize>,
    /// `M`, row-major (outputs `m_i_j`).
    pub mass: Program,
    /// Uniform load force (outputs `f0 …`).
    pub load: Program,
    /// Symbolic `f_int`.
    pub f: Vec<Id>,
    /// Symbolic `K`.
    pub k: Vec<Vec<Id>>,
    /// Symbolic `D`.
    pub d: Vec<Vec<Id>>,
}

/// Derives the kernels of `kind`: builds its definition, differentiates,
/// lowers.
///
/// Per quadrature point `g` with kinematic values `z_g = B_g q` (`B_g`
/// constant) and weight `w_g`: `σ_g = ∂φ/∂z + ∂ψ/∂ż`, `H_g = ∂σ_g/∂z`,
/// `C_g = ∂σ_g/∂ż`, all by [`Arena::diff`] in symbols standing for `z_g`,
/// `ż_g` (common factors taken out of `σ` by the `factor` rewrite); then
/// `f = Σ w_g B_gᵀ σ_g`, `K = Σ w_g B_gᵀ H_g B_g`, `D = Σ w_g B_gᵀ C_g B_g`
/// (exact: `z` is linear in `q`, so `∂²z/∂q² = 0`). The three stages are
/// lowered separately, so the point quantities are computed once and not
/// multiplied out into every entry, and chained into one program.
pub fn derive(kind: Kind) -> Kernels {
    let mut a = Arena::new();
    let def = define(&mut a, kind);
    let n = def.n();
    let full = derive_pass(&mut a, &def, false);
    let elastic = derive_pass(&mut a, &def, true);
    let Pass {
        forces,
        jacobians,
        f,
        k,
        d,
        back,
        stage1,
        pre_of,
        pre_rate_of,
    } = full;
    let names = |prefix: &str, m: usize| -> Vec<String> {
        (0..m)
            .flat_map(|i| (0..m).map(move |j| (i, j)))
            .map(|(i, j)| format!("{prefix}_{i}_{j}"))
            .collect()
    };
    let zip = |names: Vec<String>, ids: &[Id]| -> Vec<(String, Id)> {
        names.into_iter().zip(ids.iter().copied()).collect()
    };
    let lower = |a: &Arena, outs: &[(String, Id)]| {
        let outs: Vec<(&str, Id)> = outs.iter().map(|(s, id)| (s.as_str(), *id)).collect();
        // Lanes only, bound by throughput: chains, not trees.
        a.lower(
            &outs,
            LowerOptions {
                balance: false,
                ..LowerOptions::default()
            },
        )
    };
    let fnames: Vec<String> = (0..n).map(|i| format!("f{i}")).collect();
    let mids: Vec<Id> = def.mass.iter().flatten().copied().collect();
    let mass = lower(&a, &zip(names("m", n), &mids));
    let load = lower(&a, &zip(fnames, &def.load));
    let damping_params = damping_params(&mut a, &def);
    // The same quantities as expressions of q, q̇ and the parameters only
    // (for checking the lowering against the arena's evaluation).
    let mut roots: Vec<Id> = f.clone();
    roots.extend(k.iter().flatten());
    roots.extend(d.iter().flatten());
    let stage2: rustc_hash::FxHashMap<SymId, Id> = back.into_iter().collect();
    let roots = a.substitute(&roots, |s| stage2.get(&s).copied());
    let roots = a.substitute(&roots, |s| stage2.get(&s).copied());
    let mut z_of: rustc_hash::FxHashMap<SymId, Id> = rustc_hash::FxHashMap::default();
    for (nm, e) in &stage1 {
        if let Some(s) = a.find_symbol(nm) {
            z_of.insert(s, *e);
        }
    }
    let roots = a.substitute(&roots, |s| z_of.get(&s).copied());
    let roots = a.substitute(&roots, |s| pre_of.get(&s).or(pre_rate_of.get(&s)).copied());
    let f_full = roots[..n].to_vec();
    let k_full = roots[n..n + n * n].chunks(n).map(<[Id]>::to_vec).collect();
    let d_full = roots[n + n * n..].chunks(n).map(<[Id]>::to_vec).collect();
    Kernels {
        arena: a,
        def,
        forces,
        jacobians,
        elastic_forces: elastic.forces,
        elastic_stiffness: elastic.jacobians,
        damping_params,
        mass,
        load,
        f: f_full,
        k: k_full,
        d: d_full,
    }
}

/// Indices of the parameters that only the dissipation uses (e.g. `d_a`,
/// `d_b`, `mu`), if setting them all to zero makes every point's
/// dissipation density vanish identically (checked by substitution);
/// otherwise empty (the element is then never treated as undamped).
fn damping_params(a: &mut Arena, def: &Definition) -> Vec<usize> {
    let syms: Vec<SymId> = def
        .params
        .iter()
        .map(|(name, _)| {
            let id = a
                .param(name)
                .expect("element parameter names are identifiers");
            a.as_sym(id).expect("a parameter is a symbol")
        })
        .collect();
    let idx: Vec<usize> = (0..syms.len())
        .filter(|&i| {
            def.points.iter().any(|pt| a.depends_on(pt.psi, syms[i]))
                && !def.points.iter().any(|pt| a.depends_on(pt.phi, syms[i]))
        })
        .collect();
    if idx.is_empty() {
        return idx;
    }
    let zero = a.constant(0.0);
    let psis: Vec<Id> = def.points.iter().map(|pt| pt.psi).collect();
    let dsyms: Vec<SymId> = idx.iter().map(|&i| syms[i]).collect();
    let gone = a.substitute(&psis, |s| dsyms.contains(&s).then_some(zero));
    if gone
        .iter()
        .all(|&e| a.num(e).is_some_and(|v| v.to_f64() == 0.0))
    {
        idx
    } else {
        Vec::new()
    }
}

/// The lowered kernels of one pass of [`derive`] and what the check of the
/// lowering needs.
struct Pass {
    forces: Program,
    jacobians: Program,
    f: Vec<Id>,
    k: Vec<Vec<Id>>,
    d: Vec<Vec<Id>>,
    back: Vec<(SymId, Id)>,
    stage1: Vec<(String, Id)>,
    pre_of: rustc_hash::FxHashMap<SymId, Id>,
    pre_rate_of: rustc_hash::FxHashMap<SymId, Id>,
}

/// The staged derivation of [`derive`]. With `elastic`, the dissipation is
/// left out (`ψ = 0`): the forces are `∂U/∂q` and the Jacobian program has
/// the outputs of `K = ∂²U/∂q²` only, every symmetric matrix (`H_g`, the
/// assembled `K` in `w` and in `q`) built on its upper triangle and
/// mirrored, so each distinct entry is computed once.
fn derive_pass(a: &mut Arena, def: &Definition, elastic: bool) -> Pass {
    let n = def.n();
    let qs: Vec<SymId> = (0..n as u32)
        .map(|i| {
            let id = a.q(i);
            a.as_sym(id).expect("q is a symbol")
        })
        .collect();
    let qd: Vec<Id> = (0..n as u32).map(|i| a.qd(i)).collect();
    let zero = a.constant(0.0);
    let is_zero = |a: &Arena, e: Id| a.num(e).is_some_and(|v| v.to_f64() == 0.0);
    let name = |a: &Arena, s: SymId| a.symbol(s).name.clone();
    let psi_of = |pt: &Point| if elastic { zero } else { pt.psi };
    // Stage 0: the shared linear combinations of q (and the same of q̇).
    let mut stage0: Vec<(String, Id)> = Vec::new();
    let mut pre_of: rustc_hash::FxHashMap<SymId, Id> = rustc_hash::FxHashMap::default();
    let mut pre_rate: rustc_hash::FxHashMap<SymId, Id> = rustc_hash::FxHashMap::default();
    let mut pre_rate_of: rustc_hash::FxHashMap<SymId, Id> = rustc_hash::FxHashMap::default();
    let rate_of_q: rustc_hash::FxHashMap<SymId, Id> =
        qs.iter().copied().zip(qd.iter().copied()).collect();
    for &(sym, e) in &def.pre {
        let nm = name(a, sym);
        stage0.push((nm.clone(), e));
        let ed = a.substitute(&[e], |s| rate_of_q.get(&s).copied())[0];
        let rate = a.input(&format!("{nm}_d")).expect("identifier");
        stage0.push((format!("{nm}_d"), ed));
        pre_of.insert(sym, e);
        pre_rate.insert(sym, rate);
        pre_rate_of.insert(a.as_sym(rate).expect("symbol"), ed);
    }
    // Stage 1: z_g and ż_g = B_g q̇ (z of the rates of stage 0).
    let mut stage1: Vec<(String, Id)> = Vec::new();
    for pt in &def.points {
        let zd = a.substitute(&pt.z, |s| pre_rate.get(&s).or(rate_of_q.get(&s)).copied());
        for (k, &z) in pt.z.iter().enumerate() {
            stage1.push((name(a, pt.zs[k]), z));
            stage1.push((name(a, pt.zds[k]), zd[k]));
        }
    }
    // Stage 2: σ, H, C per point, as symbols for stage 3.
    let mut s2_forces: Vec<(String, Id)> = Vec::new();
    let mut s2_jac: Vec<(String, Id)> = Vec::new();
    let mut sig_sym: Vec<Vec<Id>> = Vec::new();
    let mut h_sym: Vec<Vec<Vec<Id>>> = Vec::new();
    let mut c_sym: Vec<Vec<Vec<Id>>> = Vec::new();
    let mut back: Vec<(SymId, Id)> = Vec::new();
    let tag = if elastic { "e" } else { "" };
    for (g, pt) in def.points.iter().enumerate() {
        let m = pt.z.len();
        let psi = psi_of(pt);
        let mut sig = Vec::with_capacity(m);
        for k in 0..m {
            let d1 = a.diff(pt.phi, pt.zs[k]);
            let d2 = a.diff(psi, pt.zds[k]);
            sig.push(a.add2(d1, d2));
        }
        // Common factors out of each σ_a (e.g. `(EA ε + d_a ε̇)/|r'|` of `z_a`).
        let mut runner = crate::sym::Runner::with_rules(a.rules());
        runner.rewrites = crate::sym::rewrites();
        sig = runner.run(a, &sig).roots;
        let mut hs = vec![vec![zero; m]; m];
        let mut cs = vec![vec![zero; m]; m];
        let mut ss = Vec::with_capacity(m);
        for k in 0..m {
            let nm = format!("sg{tag}{g}_{k}");
            s2_forces.push((nm.clone(), sig[k]));
            let sym = a.input(&nm).expect("identifier");
            back.push((a.as_sym(sym).expect("symbol"), sig[k]));
            ss.push(sym);
            for l in 0..m {
                // Elastic: H = ∂²φ/∂z² is symmetric; build l ≥ k only.
                if !(elastic && l < k) {
                    let h = a.diff(sig[k], pt.zs[l]);
                    if !is_zero(a, h) {
                        let nm = format!("hg{tag}{g}_{k}_{l}");
                        s2_jac.push((nm.clone(), h));
                        let sym = a.input(&nm).expect("identifier");
                        back.push((a.as_sym(sym).expect("symbol"), h));
                        hs[k][l] = sym;
                        if elastic {
                            hs[l][k] = sym;
                        }
                    }
                }
                if l >= k && !elastic {
                    let c = a.diff(sig[k], pt.zds[l]);
                    if !is_zero(a, c) {
                        let nm = format!("cg{g}_{k}_{l}");
                        s2_jac.push((nm.clone(), c));
                        let sym = a.input(&nm).expect("identifier");
                        back.push((a.as_sym(sym).expect("symbol"), c));
                        cs[k][l] = sym;
                        cs[l][k] = sym;
                    }
                }
            }
        }
        sig_sym.push(ss);
        h_sym.push(hs);
        c_sym.push(cs);
    }
    // Stage 3a: assembly over the points in the variables `w` that `z` is
    // written in (stage-0 combinations and coordinates; for the elements
    // here, the chords replace the two nodes' positions, so `w` has `dim`
    // fewer entries than `q`: the element's forces are invariant to
    // translation).
    let mut wvars: Vec<SymId> = def.pre.iter().map(|&(s, _)| s).collect();
    for &qsym in &qs {
        if def
            .points
            .iter()
            .any(|pt| pt.z.iter().any(|&z| a.depends_on(z, qsym)))
        {
            wvars.push(qsym);
        }
    }
    let nw = wvars.len();
    let one = a.constant(1.0);
    let t: Vec<Vec<Id>> = wvars
        .iter()
        .map(|&w| match pre_of.get(&w) {
            Some(&e) => a.gradient(e, &qs),
            None => qs
                .iter()
                .map(|&q| if q == w { one } else { zero })
                .collect(),
        })
        .collect();
    let bw: Vec<Vec<Vec<Id>>> = def
        .points
        .iter()
        .map(|pt| pt.z.iter().map(|&z| a.gradient(z, &wvars)).collect())
        .collect();
    let mut fw = Vec::with_capacity(nw);
    for i in 0..nw {
        let mut terms = Vec::new();
        for (g, bg) in bw.iter().enumerate() {
            for (k, row) in bg.iter().enumerate() {
                if !is_zero(a, row[i]) {
                    terms.push(a.mul(&[def.points[g].weight, row[i], sig_sym[g][k]]));
                }
            }
        }
        fw.push(a.add(&terms));
    }
    let quad = |a: &mut Arena, mats: &[Vec<Vec<Id>>], i: usize, j: usize| -> Id {
        let mut terms = Vec::new();
        for (g, bg) in bw.iter().enumerate() {
            for (k, rk) in bg.iter().enumerate() {
                if is_zero(a, rk[i]) {
                    continue;
                }
                for (l, rl) in bg.iter().enumerate() {
                    if is_zero(a, rl[j]) || is_zero(a, mats[g][k][l]) {
                        continue;
                    }
                    terms.push(a.mul(&[def.points[g].weight, rk[i], rl[j], mats[g][k][l]]));
                }
            }
        }
        a.add(&terms)
    };
    let mut kw = vec![vec![zero; nw]; nw];
    let mut dw = vec![vec![zero; nw]; nw];
    for i in 0..nw {
        for j in 0..nw {
            if elastic {
                if j >= i {
                    kw[i][j] = quad(a, &h_sym, i, j);
                    kw[j][i] = kw[i][j];
                }
                continue;
            }
            kw[i][j] = quad(a, &h_sym, i, j);
            if j >= i {
                dw[i][j] = quad(a, &c_sym, i, j);
                dw[j][i] = dw[i][j];
            }
        }
    }
    // Stage 3b: back to q through T = ∂w/∂q (constant, sparse).
    let mut s3_forces: Vec<(String, Id)> = Vec::new();
    let mut s3_jac: Vec<(String, Id)> = Vec::new();
    let mut as_sym = |a: &mut Arena, out: &mut Vec<(String, Id)>, nm: String, e: Id| -> Id {
        if is_zero(a, e) {
            return e;
        }
        let sym = a.input(&nm).expect("identifier");
        back.push((a.as_sym(sym).expect("symbol"), e));
        out.push((nm, e));
        sym
    };
    let fws: Vec<Id> = (0..nw)
        .map(|i| as_sym(a, &mut s3_forces, format!("fw{tag}{i}"), fw[i]))
        .collect();
    let mut kws = vec![vec![zero; nw]; nw];
    let mut dws = vec![vec![zero; nw]; nw];
    for i in 0..nw {
        for j in 0..nw {
            if elastic {
                if j >= i {
                    kws[i][j] = as_sym(a, &mut s3_jac, format!("kwe{i}_{j}"), kw[i][j]);
                    kws[j][i] = kws[i][j];
                }
                continue;
            }
            kws[i][j] = as_sym(a, &mut s3_jac, format!("kw{i}_{j}"), kw[i][j]);
            if j >= i {
                dws[i][j] = as_sym(a, &mut s3_jac, format!("dw{i}_{j}"), dw[i][j]);
                dws[j][i] = dws[i][j];
            }
        }
    }
    let mut f = Vec::with_capacity(n);
    for i in 0..n {
        let terms: Vec<Id> = t
            .iter()
            .zip(&fws)
            .map(|(tw, &fw)| a.mul2(tw[i], fw))
            .collect();
        f.push(a.add(&terms));
    }
    let back_q = |a: &mut Arena, m: &[Vec<Id>], i: usize, j: usize| -> Id {
        let mut terms = Vec::new();
        for (w, tw) in t.iter().enumerate() {
            if is_zero(a, tw[i]) {
                continue;
            }
            for (v, tv) in t.iter().enumerate() {
                if !is_zero(a, tv[j]) && !is_zero(a, m[w][v]) {
                    terms.push(a.mul(&[tw[i], tv[j], m[w][v]]));
                }
            }
        }
        a.add(&terms)
    };
    let mut k = vec![vec![zero; n]; n];
    let mut d = vec![vec![zero; n]; n];
    for i in 0..n {
        for j in 0..n {
            if elastic {
                if j >= i {
                    k[i][j] = back_q(a, &kws, i, j);
                    k[j][i] = k[i][j];
                }
                continue;
            }
            k[i][j] = back_q(a, &kws, i, j);
            if j >= i {
                d[i][j] = back_q(a, &dws, i, j);
                d[j][i] = d[i][j];
            }
        }
    }
    let names = |prefix: &str, m: usize| -> Vec<String> {
        (0..m)
            .flat_map(|i| (0..m).map(move |j| (i, j)))
            .map(|(i, j)| format!("{prefix}_{i}_{j}"))
            .collect()
    };
    let lower = |a: &Arena, outs: &[(String, Id)]| {
        let outs: Vec<(&str, Id)> = outs.iter().map(|(s, id)| (s.as_str(), *id)).collect();
        // Lanes only, bound by throughput: chains, not trees.
        a.lower(
            &outs,
            LowerOptions {
                balance: false,
                ..LowerOptions::default()
            },
        )
    };
    let zip = |names: Vec<String>, ids: &[Id]| -> Vec<(String, Id)> {
        names.into_iter().zip(ids.iter().copied()).collect()
    };
    let fnames: Vec<String> = (0..n).map(|i| format!("f{i}")).collect();
    let p1 = chain(&lower(a, &stage0), &lower(a, &stage1));
    let forces = chain(
        &chain(&chain(&p1, &lower(a, &s2_forces)), &lower(a, &s3_forces)),
        &lower(a, &zip(fnames, &f)),
    );
    let mut jn = names("k", n);
    let mut jids: Vec<Id> = k.iter().flatten().copied().collect();
    if !elastic {
        jn.extend(names("d", n));
        jids.extend(d.iter().flatten());
    }
    let jacobians = chain(
        &chain(&chain(&p1, &lower(a, &s2_jac)), &lower(a, &s3_jac)),
        &lower(a, &zip(jn, &jids)),
    );
    Pass {
        forces,
        jacobians,
        f,
        k,
        d,
        back,
        stage1,
        pre_of,
        pre_rate_of,
    }
}

/// `second` after `first`: inputs of `second` named like an output of
/// `first` read that output; the result is optimised again (constant
/// propagation, value numbering and dead-code elimination across the two).
pub fn chain(first: &Program, second: &Program) -> Program {
    use crate::sym::{Instr, Op, Operand};
    let off = first.n_tmps;
    let mut inputs = first.inputs.clone();
    let map_in: Vec<Operand> = second
        .inputs
        .iter()
        .map(|s| {
            if let Some((_, o)) = first.outputs.iter().find(|(n, _)| *n == s.name) {
                *o
            } else if let Some(i) = inputs.iter().position(|t| t == s) {
                Operand::Var(i as u32)
            } else {
                inputs.push(s.clone());
                Operand::Var(inputs.len() as u32 - 1)
            }
        })
        .collect();
    let map = |o: Operand| match o {
        Operand::Const(_) => o,
        Operand::Var(i) => map_in[i as usize],
        Operand::Tmp(t) => Operand::Tmp(t + off),
    };
    let mut instrs = first.instrs.clone();
    instrs.extend(second.instrs.iter().map(|ins| Instr {
        dst: ins.dst + off,
        op: ins.op.map(map),
    }));
    let outputs = second
        .outputs
        .iter()
        .map(|(n, o)| (n.clone(), map(*o)))
        .collect();
    let mut p = Program {
        inputs,
        instrs,
        outputs,
        n_tmps: off + second.n_tmps,
        products: second.products.clone(),
    };
    p.optimize();
    let _ = Op::Neg;
    p
}

impl Kernels {
    /// Input values of `p` (a program of these kernels) for the given
    /// element state, parameters and load.
    pub fn inputs(
        &self,
        p: &Program,
        q: &[f64],
        qd: &[f64],
        params: &[f64],
        w: &[f64; 3],
    ) -> Vec<f64> {
        p.inputs
            .iter()
            .map(|s| match s.kind {
                SymKind::Coord(i) => q.get(i as usize).copied().unwrap_or(f64::NAN),
                SymKind::CoordRate(i) => qd.get(i as usize).copied().unwrap_or(f64::NAN),
                SymKind::Param => self
                    .def
                    .params
                    .iter()
                    .position(|(n, _)| *n == s.name)
                    .and_then(|k| params.get(k).copied())
                    .unwrap_or(f64::NAN),
                SymKind::Input => LOAD_NAMES
                    .iter()
                    .position(|n| *n == s.name)
                    .map_or(f64::NAN, |k| w[k]),
                _ => f64::NAN,
            })
            .collect()
    }

    /// `f_int` by the lowered program.
    pub fn eval_forces(&self, q: &[f64], qd: &[f64], params: &[f64]) -> Vec<f64> {
        self.forces
            .eval(&self.inputs(&self.forces, q, qd, params, &[0.0; 3]))
    }

    /// `(K, D)` by the lowered program, row-major.
    pub fn eval_jacobians(&self, q: &[f64], qd: &[f64], params: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut v = self
            .jacobians
            .eval(&self.inputs(&self.jacobians, q, qd, params, &[0.0; 3]));
        let d = v.split_off(v.len() / 2);
        (v, d)
    }

    /// `M` by the lowered program, row-major.
    pub fn eval_mass(&self, params: &[f64]) -> Vec<f64> {
        self.mass
            .eval(&self.inputs(&self.mass, &[], &[], params, &[0.0; 3]))
    }

    /// Uniform load force by the lowered program.
    pub fn eval_load(&self, params: &[f64], w: &[f64; 3]) -> Vec<f64> {
        self.load
            .eval(&self.inputs(&self.load, &[], &[], params, w))
    }

    /// Value of a symbolic expression of these kernels (the arena's own
    /// evaluator, independent of lowering).
    pub fn eval_expr(&self, e: Id, q: &[f64], qd: &[f64], params: &[f64]) -> f64 {
        let a = &self.arena;
        let values = a.values_with(|s| match a.symbol(s).kind {
            SymKind::Coord(i) => q.get(i as usize).copied().unwrap_or(f64::NAN),
            SymKind::CoordRate(i) => qd.get(i as usize).copied().unwrap_or(f64::NAN),
            SymKind::Param => self
                .def
                .params
                .iter()
                .position(|(n, _)| *n == a.symbol(s).name)
                .and_then(|k| params.get(k).copied())
                .unwrap_or(f64::NAN),
            _ => f64::NAN,
        });
        a.eval(e, &values)
    }

    /// Operation counts: forces, jacobians, mass, load.
    pub fn op_counts(&self) -> [OpCount; 4] {
        [
            self.forces.op_count(),
            self.jacobians.op_count(),
            self.mass.op_count(),
            self.load.op_count(),
        ]
    }
}
