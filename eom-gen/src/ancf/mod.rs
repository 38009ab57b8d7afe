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
//! `K = ∂f_int/∂q` (the elastic part `∂²U/∂q²` built on the upper
//! triangle and mirrored), `D = ∂f_int/∂q̇ = ∂²R/∂q̇²` (symmetric). The
//! results are lowered to [`Program`]s (common subexpressions shared across
//! all outputs of a kernel) and emitted by [`emit::emit`] as one
//! `eom_sim::elements::ElementKernel` implementation per element type.
//!
//! Element types ([`Kind`]):
//! - [`Kind::Cable2D`]: planar cable, Gerstmayr and Irschik 2008,
//!   `ε = |r'| − 1`, `κ = (r' × r'')/|r'|²`;
//! - [`Kind::Cable2DGreen`]: planar cable, Green axial strain
//!   `ε_G = ½(r'·r' − 1)` and `κ ≈ r' × r''` (polynomial, integrated exactly);
//! - [`Kind::Cable3D`]: spatial cable (no torsion), `ε = |r'| − 1`,
//!   `κ = |r' × r''|/|r'|³` (Gerstmayr and Shabana 2006);
//! - [`Kind::Beam2D`]: planar fully parameterised beam, Green–Lagrange
//!   strain of the continuum, plane stress (Omar and Shabana 2001; Berzeri
//!   and Shabana 2000).

pub mod emit;
mod gauss;
mod shapes;

pub use gauss::gauss_legendre;

use crate::sym::{Arena, Id, LowerOptions, OpCount, Program, SymId, SymKind, TimeDerivative};

/// The element types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Planar cable, Gerstmayr–Irschik strain and material curvature.
    Cable2D,
    /// Planar cable, Green axial strain and the polynomial curvature `r' × r''`.
    Cable2DGreen,
    /// Spatial cable, axial strain and curvature, no torsion.
    Cable3D,
    /// Planar fully parameterised beam (continuum Green–Lagrange strain).
    Beam2D,
}

impl Kind {
    /// Every element type, in the order the files are written.
    pub const ALL: [Kind; 4] = [
        Kind::Cable2D,
        Kind::Cable2DGreen,
        Kind::Cable3D,
        Kind::Beam2D,
    ];
}

/// An element type's symbolic definition (built by [`define`]).
pub struct Definition {
    /// Type name as written in models and of the generated struct.
    pub name: &'static str,
    /// File stem of the generated module (`eom-sim/src/elements/<module>.rs`).
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
    /// Strain energy `U(q)`.
    pub energy: Id,
    /// Dissipation function `R(q, q̇)`, quadratic in `q̇`.
    pub dissipation: Id,
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
pub fn derive(kind: Kind) -> Kernels {
    let mut a = Arena::new();
    let def = define(&mut a, kind);
    let n = def.n();
    let qs: Vec<SymId> = (0..n as u32)
        .map(|i| {
            let id = a.q(i);
            a.as_sym(id).expect("q is a symbol")
        })
        .collect();
    let qds: Vec<SymId> = (0..n as u32)
        .map(|i| {
            let id = a.qd(i);
            a.as_sym(id).expect("qd is a symbol")
        })
        .collect();
    let fu = a.gradient(def.energy, &qs);
    let fr = a.gradient(def.dissipation, &qds);
    let f: Vec<Id> = fu.iter().zip(&fr).map(|(&x, &y)| a.add2(x, y)).collect();
    // Elastic stiffness: upper triangle, mirrored.
    let mut ku = vec![vec![a.constant(0.0); n]; n];
    for i in 0..n {
        for j in i..n {
            let v = a.diff(fu[i], qs[j]);
            ku[i][j] = v;
            ku[j][i] = v;
        }
    }
    let mut k = vec![vec![ku[0][0]; n]; n];
    let mut d = vec![vec![ku[0][0]; n]; n];
    for i in 0..n {
        for j in 0..n {
            let kr = a.diff(fr[i], qs[j]);
            k[i][j] = a.add2(ku[i][j], kr);
        }
        for j in i..n {
            let v = a.diff(fr[i], qds[j]);
            d[i][j] = v;
            d[j][i] = v;
        }
    }
    let names = |prefix: &str, m: usize| -> Vec<String> {
        (0..m)
            .flat_map(|i| (0..m).map(move |j| (i, j)))
            .map(|(i, j)| format!("{prefix}_{i}_{j}"))
            .collect()
    };
    let lower = |a: &Arena, names: &[String], ids: &[Id]| {
        let outs: Vec<(&str, Id)> = names
            .iter()
            .map(|s| s.as_str())
            .zip(ids.iter().copied())
            .collect();
        a.lower(&outs, LowerOptions::default())
    };
    let fnames: Vec<String> = (0..n).map(|i| format!("f{i}")).collect();
    let forces = lower(&a, &fnames, &f);
    let mut jn = names("k", n);
    jn.extend(names("d", n));
    let jids: Vec<Id> = k.iter().chain(&d).flatten().copied().collect();
    let jacobians = lower(&a, &jn, &jids);
    let mids: Vec<Id> = def.mass.iter().flatten().copied().collect();
    let mass = lower(&a, &names("m", n), &mids);
    let load = lower(&a, &fnames, &def.load);
    Kernels {
        arena: a,
        def,
        forces,
        jacobians,
        mass,
        load,
        f,
        k,
        d,
    }
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

/// Helpers shared by the element definitions.
pub(crate) fn time_rate(a: &mut Arena, e: Id) -> Id {
    TimeDerivative::new()
        .apply(a, e)
        .expect("element strains depend on q and parameters only")
}
