//! A structural model of dynamic size: element groups assembled over one
//! coordinate vector, fixed coordinates eliminated, a constant sparse mass
//! matrix, constant external loads.
//!
//! Coordinates come in two numberings: the *full* vector (every nodal
//! coordinate, what elements read) and the *free* vector (the full one less
//! the coordinates fixed by supports, what the solvers iterate on). Fixed
//! coordinates keep their prescribed values for ever, so their rows and
//! columns simply drop out of the mass matrix and the tangent.

use super::sparse::{Pattern, SparseMatrix};
use crate::elements::{ElementKernel, Lanes};
use crate::run::Jacobian;
use std::marker::PhantomData;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Gauss–Legendre nodes and weights on `[0, 1]` used for the strain energy
/// as a path integral of the elastic force (16 points: exact for
/// polynomial energies up to degree 32 along the path).
fn gauss01() -> &'static [(f64, f64)] {
    use std::sync::OnceLock;
    static RULE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    RULE.get_or_init(|| {
        let n = 16;
        let mut out = Vec::with_capacity(n);
        for i in 0..n {
            // Newton on the Legendre polynomial from Chebyshev guesses.
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            out.push((0.5 * (1.0 + x), 0.5 * w));
        }
        out
    })
}

/// Mass per unit reference length from an element's parameters: `rhoA`,
/// or `rho · A`, or `rho · b · h` (a rectangular section), whichever the
/// kernel has.
pub fn mass_per_length(names: &[&str], values: &[f64]) -> Option<f64> {
    let get = |n: &str| names.iter().position(|&p| p == n).map(|k| values[k]);
    get("rhoA")
        .or_else(|| Some(get("rho")? * get("A")?))
        .or_else(|| Some(get("rho")? * get("b")? * get("h")?))
}

/// The reference coordinates `r` of a two-node element moved rigidly so
/// that its chord (node 0 to node 1) lies along the chord of `q` and its
/// node 0 on `q`'s: positions are rotated about node 0 and translated,
/// gradients rotated. Coordinates per node: position (`dim`) then
/// gradients (`dim` each).
fn placed_reference<const N: usize>(r: &[f64; N], q: &[f64; N], dim: usize, nc: usize) -> [f64; N] {
    let chord = |v: &[f64; N]| -> [f64; 3] {
        let mut c = [0.0; 3];
        for (k, ck) in c.iter_mut().enumerate().take(dim) {
            *ck = v[nc + k] - v[k];
        }
        c
    };
    let (a, b) = (chord(r), chord(q));
    let norm = |v: &[f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let (na, nb) = (norm(&a), norm(&b));
    if na == 0.0 || nb == 0.0 || dim < 2 {
        return *r;
    }
    let a = a.map(|x| x / na);
    let b = b.map(|x| x / nb);
    // Rotation taking a to b (Rodrigues about a × b).
    let axis = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let s = norm(&axis);
    let c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let rot = |v: [f64; 3]| -> [f64; 3] {
        if s < 1e-300 {
            // Parallel or antiparallel: identity, or a half turn about an
            // axis normal to a (in the plane for dim 2: z).
            if c > 0.0 {
                return v;
            }
            let k = if dim == 2 || a[2].abs() < 0.9 {
                let z = [0.0, 0.0, 1.0];
                let p = [
                    z[1] * a[2] - z[2] * a[1],
                    z[2] * a[0] - z[0] * a[2],
                    z[0] * a[1] - z[1] * a[0],
                ];
                let n = norm(&p);
                p.map(|x| x / n)
            } else {
                [1.0, 0.0, 0.0]
            };
            let d = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
            return [
                2.0 * d * k[0] - v[0],
                2.0 * d * k[1] - v[1],
                2.0 * d * k[2] - v[2],
            ];
        }
        let k = axis.map(|x| x / s);
        let kv = [
            k[1] * v[2] - k[2] * v[1],
            k[2] * v[0] - k[0] * v[2],
            k[0] * v[1] - k[1] * v[0],
        ];
        let kd = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
        [0, 1, 2].map(|i| v[i] * c + kv[i] * s + k[i] * kd * (1.0 - c))
    };
    let mut out = *r;
    for node in 0..2 {
        let base = node * nc;
        for block in 0..nc / dim {
            let at = base + block * dim;
            let mut v = [0.0; 3];
            for k in 0..dim {
                v[k] = if block == 0 {
                    r[at + k] - r[k]
                } else {
                    r[at + k]
                };
            }
            let w = rot(v);
            for k in 0..dim {
                out[at + k] = if block == 0 { w[k] + q[k] } else { w[k] };
            }
        }
    }
    out
}

/// Elements of one type, object-safe so that a model holds groups of
/// different kernels. Vectors are full-size.
pub trait ElementGroup: Send + Sync {
    /// The kernel's name (`"Cable2D"`, …).
    fn name(&self) -> &'static str;
    /// Coordinates per element.
    fn dofs(&self) -> usize;
    /// Number of elements.
    fn len(&self) -> usize;
    /// True without elements.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Full coordinate indices of element `e`.
    fn connectivity(&self, e: usize) -> &[usize];
    /// `f += f_int(q, q̇)` over all elements.
    fn add_internal(&self, q: &[f64], qd: &[f64], f: &mut [f64]);
    /// Adds `a ∂f_int/∂q + b ∂f_int/∂q̇` of element `e` through `add(i, j, v)`
    /// for local indices `i, j`; `k`, `d` are scratch of `dofs²` each.
    fn element_jacobian(
        &self,
        e: usize,
        q: &[f64],
        qd: &[f64],
        scratch: &mut Vec<f64>,
        out: &mut dyn FnMut(usize, usize, f64, f64),
    );
    /// `values[slots[e·dofs² + i·dofs + j]] += a ∂f_i/∂q_j + b ∂f_i/∂q̇_j`
    /// over all elements `e` (slots `usize::MAX` skipped). The default goes
    /// through [`ElementGroup::element_jacobian`] element by element.
    fn add_jacobian(
        &self,
        q: &[f64],
        qd: &[f64],
        a: f64,
        b: f64,
        slots: &[usize],
        values: &mut [f64],
    ) {
        let d = self.dofs();
        let mut scratch = Vec::new();
        for e in 0..self.len() {
            let base = e * d * d;
            self.element_jacobian(e, q, qd, &mut scratch, &mut |i, j, k, dd| {
                let slot = slots[base + i * d + j];
                if slot != usize::MAX {
                    values[slot] += a * k + b * dd;
                }
            });
        }
    }
    /// The mass matrix of element `e` through `add(i, j, m_ij)`.
    fn element_mass(&self, e: usize, out: &mut dyn FnMut(usize, usize, f64));
    /// `f += ` the generalised force of the uniform load `w` per unit
    /// length over all elements.
    fn add_uniform_load(&self, w: [f64; 3], f: &mut [f64]);
    /// Strain energy `U(q) − U(q_ref)` from the path integral of the
    /// elastic force (velocity zero, so damping is left out) along the
    /// straight line from each element's reference coordinates.
    fn strain_energy(&self, q: &[f64]) -> f64;
    /// `f += ` the gravity load: the uniform load `ρA · g` on every
    /// element ([`mass_per_length`]; kernels without one get none).
    fn add_gravity(&self, g: [f64; 3], f: &mut [f64]);
}

/// Elements evaluated at once by the assembly loops of [`Elements`] (the
/// kernels' lane count): four `f64` lanes, one AVX register, when the
/// build targets AVX (`-C target-cpu=x86-64-v3` or `native`); otherwise
/// two, one SSE2 register (the default x86-64 target; wider lanes there
/// only spill registers: BENCHMARKS.md, "ANCF elements").
#[cfg(target_feature = "avx")]
pub const LANES: usize = 4;
/// Elements evaluated at once by the assembly loops of [`Elements`] (the
/// kernels' lane count): two `f64` lanes, one SSE2 register, for targets
/// without AVX (the default x86-64 target); four with AVX
/// (`-C target-cpu=x86-64-v3` or `native`).
#[cfg(not(target_feature = "avx"))]
pub const LANES: usize = 2;

/// The elements of one kernel type `E`: per element its full coordinate
/// indices, parameters and reference (stress-free) coordinates.
///
/// The assembly loops evaluate [`LANES`] elements per kernel call, and use
/// the elastic kernels (`∂U/∂q`, symmetric `∂²U/∂q²`) when no element of
/// the group is damped, or when the velocities are zero and `∂f/∂q̇` is
/// not asked for (statics).
pub struct Elements<E, const N: usize, const P: usize> {
    conn: Vec<[usize; N]>,
    params: Vec<[f64; P]>,
    reference: Vec<[f64; N]>,
    damped: bool,
    kernel: PhantomData<fn() -> E>,
}

impl<E: ElementKernel<N, P>, const N: usize, const P: usize> Default for Elements<E, N, P> {
    fn default() -> Self {
        Elements {
            conn: Vec::new(),
            params: Vec::new(),
            reference: Vec::new(),
            damped: false,
            kernel: PhantomData,
        }
    }
}

impl<E: ElementKernel<N, P>, const N: usize, const P: usize> Elements<E, N, P> {
    /// No elements yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one element: its full coordinate indices, parameters, and the
    /// coordinates at which it is free of stress.
    pub fn push(&mut self, conn: [usize; N], params: [f64; P], reference: [f64; N]) {
        self.damped |= !E::is_undamped(&params);
        self.conn.push(conn);
        self.params.push(params);
        self.reference.push(reference);
    }

    /// Coordinates (`v`) and parameters of elements `e0 … e0 + LANES − 1`
    /// in lanes; lanes past the last element repeat it.
    fn gather_lanes(&self, e0: usize, v: &[f64], out: &mut [Lanes<LANES>; N]) {
        let last = self.conn.len() - 1;
        for l in 0..LANES {
            let c = &self.conn[(e0 + l).min(last)];
            for (o, &i) in out.iter_mut().zip(c) {
                o.0[l] = v[i];
            }
        }
    }

    fn params_lanes(&self, e0: usize) -> [Lanes<LANES>; P] {
        let last = self.conn.len() - 1;
        let mut out = [Lanes::default(); P];
        for l in 0..LANES {
            let p = &self.params[(e0 + l).min(last)];
            for (o, &v) in out.iter_mut().zip(p) {
                o.0[l] = v;
            }
        }
        out
    }

    fn gather(&self, e: usize, v: &[f64]) -> [f64; N] {
        let mut out = [0.0; N];
        for (o, &i) in out.iter_mut().zip(&self.conn[e]) {
            *o = v[i];
        }
        out
    }
}

impl<E: ElementKernel<N, P>, const N: usize, const P: usize> ElementGroup for Elements<E, N, P> {
    fn name(&self) -> &'static str {
        E::NAME
    }
    fn dofs(&self) -> usize {
        N
    }
    fn len(&self) -> usize {
        self.conn.len()
    }
    fn connectivity(&self, e: usize) -> &[usize] {
        &self.conn[e]
    }
    fn add_internal(&self, q: &[f64], qd: &[f64], f: &mut [f64]) {
        let ne = self.conn.len();
        let elastic = !self.damped || qd.iter().all(|&v| v == 0.0);
        let mut ql = [Lanes::default(); N];
        let mut qdl = [Lanes::default(); N];
        let mut fl = [Lanes::default(); N];
        for e0 in (0..ne).step_by(LANES) {
            self.gather_lanes(e0, q, &mut ql);
            let pl = self.params_lanes(e0);
            if elastic {
                E::elastic_forces_lanes(&ql, &pl, &mut fl);
            } else {
                self.gather_lanes(e0, qd, &mut qdl);
                E::forces_lanes(&ql, &qdl, &pl, &mut fl);
            }
            for l in 0..LANES.min(ne - e0) {
                for (&i, v) in self.conn[e0 + l].iter().zip(&fl) {
                    f[i] += v.0[l];
                }
            }
        }
    }
    fn add_jacobian(
        &self,
        q: &[f64],
        qd: &[f64],
        a: f64,
        b: f64,
        slots: &[usize],
        values: &mut [f64],
    ) {
        let ne = self.conn.len();
        let elastic = !self.damped || (b == 0.0 && qd.iter().all(|&v| v == 0.0));
        let mut ql = [Lanes::default(); N];
        let mut qdl = [Lanes::default(); N];
        let mut kl = [[Lanes::default(); N]; N];
        let mut dl = [[Lanes::default(); N]; N];
        for e0 in (0..ne).step_by(LANES) {
            self.gather_lanes(e0, q, &mut ql);
            let pl = self.params_lanes(e0);
            if elastic {
                E::elastic_stiffness_lanes(&ql, &pl, &mut kl);
            } else {
                self.gather_lanes(e0, qd, &mut qdl);
                E::jacobians_lanes(&ql, &qdl, &pl, &mut kl, &mut dl);
            }
            for l in 0..LANES.min(ne - e0) {
                let s = &slots[(e0 + l) * N * N..(e0 + l + 1) * N * N];
                for i in 0..N {
                    for j in 0..N {
                        let slot = s[i * N + j];
                        if slot == usize::MAX {
                            continue;
                        }
                        values[slot] += if elastic {
                            a * kl[i][j].0[l]
                        } else {
                            a * kl[i][j].0[l] + b * dl[i][j].0[l]
                        };
                    }
                }
            }
        }
    }
    fn element_jacobian(
        &self,
        e: usize,
        q: &[f64],
        qd: &[f64],
        _scratch: &mut Vec<f64>,
        out: &mut dyn FnMut(usize, usize, f64, f64),
    ) {
        let mut k = [[0.0; N]; N];
        let mut d = [[0.0; N]; N];
        let (qe, qde) = (self.gather(e, q), self.gather(e, qd));
        E::internal_jacobians(&qe, &qde, &self.params[e], &mut k, &mut d);
        for i in 0..N {
            for j in 0..N {
                out(i, j, k[i][j], d[i][j]);
            }
        }
    }
    fn element_mass(&self, e: usize, out: &mut dyn FnMut(usize, usize, f64)) {
        let mut m = [[0.0; N]; N];
        E::mass(&self.params[e], &mut m);
        for (i, row) in m.iter().enumerate() {
            for (j, &v) in row.iter().enumerate() {
                out(i, j, v);
            }
        }
    }
    fn add_uniform_load(&self, w: [f64; 3], f: &mut [f64]) {
        let mut fe = [0.0; N];
        for e in 0..self.conn.len() {
            E::uniform_load(&self.params[e], &w, &mut fe);
            for (&i, v) in self.conn[e].iter().zip(&fe) {
                f[i] += v;
            }
        }
    }
    fn strain_energy(&self, q: &[f64]) -> f64 {
        let zero = [0.0; N];
        let mut fe = [0.0; N];
        let mut u = 0.0;
        for e in 0..self.conn.len() {
            let qe = self.gather(e, q);
            // Start the path at the reference moved rigidly onto the
            // element (strain energy is invariant under rigid motions), so
            // that it stays short and away from a vanishing gradient.
            let r = placed_reference::<N>(&self.reference[e], &qe, E::DIM, E::NODE_COORDS);
            let mut dq = [0.0; N];
            for i in 0..N {
                dq[i] = qe[i] - r[i];
            }
            for &(s, w) in gauss01() {
                let mut x = [0.0; N];
                for i in 0..N {
                    x[i] = r[i] + s * dq[i];
                }
                E::internal_forces(&x, &zero, &self.params[e], &mut fe);
                u += w * fe.iter().zip(&dq).map(|(a, b)| a * b).sum::<f64>();
            }
        }
        u
    }
    fn add_gravity(&self, g: [f64; 3], f: &mut [f64]) {
        let mut fe = [0.0; N];
        for e in 0..self.conn.len() {
            let Some(mu) = mass_per_length(&E::PARAMS, &self.params[e]) else {
                return;
            };
            let w = g.map(|x| mu * x);
            E::uniform_load(&self.params[e], &w, &mut fe);
            for (&i, v) in self.conn[e].iter().zip(&fe) {
                f[i] += v;
            }
        }
    }
}

/// A structural model: full coordinates, which of them are fixed, element
/// groups, extra point masses, constant loads.
pub struct StructuralModel {
    q0: Vec<f64>,
    free_of_full: Vec<Option<usize>>,
    full_of_free: Vec<usize>,
    groups: Vec<Box<dyn ElementGroup>>,
    point_masses: Vec<(usize, f64)>,
    load: Vec<f64>,
    pattern: Arc<Pattern>,
    /// Per group, per element, `dofs²` slots into the pattern's values
    /// (`usize::MAX` where a fixed coordinate is involved).
    slots: Vec<Vec<usize>>,
    mass: SparseMatrix,
    /// The initial speeds of the full coordinates (zero unless set).
    v0: Vec<f64>,
    /// Where the tangent of the internal forces comes from
    /// ([`StructuralModel::set_tangent`]).
    tangent: Jacobian,
    /// Columns of the pattern that share no row, perturbed together by the
    /// differenced tangent (greedy colouring, computed when first asked).
    colors: std::sync::OnceLock<Vec<Vec<usize>>>,
    /// Internal-force evaluations spent on differenced tangents.
    differenced: AtomicUsize,
}

/// Builds a [`StructuralModel`].
pub struct ModelBuilder {
    q0: Vec<f64>,
    fixed: Vec<bool>,
    groups: Vec<Box<dyn ElementGroup>>,
    point_masses: Vec<(usize, f64)>,
    gravity: [f64; 3],
    point_loads: Vec<(usize, f64)>,
}

impl ModelBuilder {
    /// A model of `q0.len()` full coordinates with initial (reference)
    /// values `q0`, all free.
    pub fn new(q0: Vec<f64>) -> ModelBuilder {
        let n = q0.len();
        ModelBuilder {
            q0,
            fixed: vec![false; n],
            groups: Vec::new(),
            point_masses: Vec::new(),
            gravity: [0.0; 3],
            point_loads: Vec::new(),
        }
    }

    /// Adds a group of elements.
    pub fn elements(mut self, g: impl ElementGroup + 'static) -> Self {
        self.groups.push(Box::new(g));
        self
    }

    /// Adds a boxed group of elements.
    pub fn boxed_elements(mut self, g: Box<dyn ElementGroup>) -> Self {
        self.groups.push(g);
        self
    }

    /// Fixes full coordinate `i` at its value in `q0`.
    pub fn fix(mut self, i: usize) -> Self {
        self.fixed[i] = true;
        self
    }

    /// A point mass `m` on the translational coordinate `i` (a lumped
    /// particle: add it to each of its position coordinates).
    pub fn point_mass(mut self, i: usize, m: f64) -> Self {
        self.point_masses.push((i, m));
        self
    }

    /// Gravity `g` (m/s²): the uniform load `rhoA · g` on elements that
    /// have a `rhoA` parameter (point masses take their weight as a
    /// [`ModelBuilder::point_load`]).
    pub fn gravity(mut self, g: [f64; 3]) -> Self {
        self.gravity = g;
        self
    }

    /// A constant force `f` on full coordinate `i`.
    pub fn point_load(mut self, i: usize, f: f64) -> Self {
        self.point_loads.push((i, f));
        self
    }

    /// Numbers the free coordinates, builds the sparse pattern and the
    /// mass matrix, and sums the constant loads.
    pub fn build(self) -> StructuralModel {
        let n = self.q0.len();
        let mut free_of_full = vec![None; n];
        let mut full_of_free = Vec::new();
        for (i, &fixed) in self.fixed.iter().enumerate() {
            if !fixed {
                free_of_full[i] = Some(full_of_free.len());
                full_of_free.push(i);
            }
        }
        let mut entries = Vec::new();
        for g in &self.groups {
            for e in 0..g.len() {
                let c = g.connectivity(e);
                for &a in c {
                    for &b in c {
                        if let (Some(i), Some(j)) = (free_of_full[a], free_of_full[b]) {
                            entries.push((i, j));
                        }
                    }
                }
            }
        }
        let pattern = Arc::new(Pattern::new(full_of_free.len(), entries));
        let slots: Vec<Vec<usize>> = self
            .groups
            .iter()
            .map(|g| {
                let mut s = Vec::with_capacity(g.len() * g.dofs() * g.dofs());
                for e in 0..g.len() {
                    let c = g.connectivity(e);
                    for &a in c {
                        for &b in c {
                            let slot = match (free_of_full[a], free_of_full[b]) {
                                (Some(i), Some(j)) => pattern.slot(i, j),
                                _ => None,
                            };
                            s.push(slot.unwrap_or(usize::MAX));
                        }
                    }
                }
                s
            })
            .collect();
        let mut mass = SparseMatrix::zeros(pattern.clone());
        for (g, s) in self.groups.iter().zip(&slots) {
            let d = g.dofs();
            for e in 0..g.len() {
                let base = e * d * d;
                g.element_mass(e, &mut |i, j, v| {
                    let k = s[base + i * d + j];
                    if k != usize::MAX {
                        mass.values[k] += v;
                    }
                });
            }
        }
        let mut load = vec![0.0; n];
        for &(i, m) in &self.point_masses {
            if let Some(fi) = free_of_full[i]
                && let Some(k) = pattern.slot(fi, fi)
            {
                mass.values[k] += m;
            }
        }
        if self.gravity.iter().any(|&g| g != 0.0) {
            for g in &self.groups {
                g.add_gravity(self.gravity, &mut load);
            }
        }
        for &(i, f) in &self.point_loads {
            load[i] += f;
        }
        StructuralModel {
            q0: self.q0,
            free_of_full,
            full_of_free,
            groups: self.groups,
            point_masses: self.point_masses,
            load,
            pattern,
            slots,
            mass,
            v0: Vec::new(),
            tangent: Jacobian::Generated,
            colors: std::sync::OnceLock::new(),
            differenced: AtomicUsize::new(0),
        }
    }
}

impl StructuralModel {
    /// Number of full coordinates.
    pub fn n_full(&self) -> usize {
        self.q0.len()
    }

    /// Number of free coordinates (the unknowns).
    pub fn n_free(&self) -> usize {
        self.full_of_free.len()
    }

    /// The initial full coordinates (fixed ones keep these values).
    pub fn q0(&self) -> &[f64] {
        &self.q0
    }

    /// Sets the initial speeds of the full coordinates (m/s, and 1/s for
    /// slopes; a run starts from them instead of rest). The speeds of
    /// fixed coordinates are ignored; a `v0` of another length than
    /// [`StructuralModel::n_full`] is padded with zeros or cut.
    pub fn set_initial_velocity(&mut self, mut v0: Vec<f64>) {
        v0.resize(self.q0.len(), 0.0);
        self.v0 = v0;
    }

    /// The initial speeds on the free coordinates (zero unless set by
    /// [`StructuralModel::set_initial_velocity`]).
    pub fn initial_velocity(&self) -> Vec<f64> {
        if self.v0.is_empty() {
            vec![0.0; self.n_free()]
        } else {
            self.restrict(&self.v0)
        }
    }

    /// The sparse pattern over the free coordinates.
    pub fn pattern(&self) -> &Arc<Pattern> {
        &self.pattern
    }

    /// The constant mass matrix over the free coordinates.
    pub fn mass(&self) -> &SparseMatrix {
        &self.mass
    }

    /// The element groups.
    pub fn groups(&self) -> &[Box<dyn ElementGroup>] {
        &self.groups
    }

    /// Free index of full coordinate `i` (`None` if fixed).
    pub fn free_index(&self, i: usize) -> Option<usize> {
        self.free_of_full[i]
    }

    /// The constant external load on the full coordinates.
    pub fn load_full(&self) -> &[f64] {
        &self.load
    }

    /// The external load restricted to the free coordinates.
    pub fn load_free(&self) -> Vec<f64> {
        self.full_of_free.iter().map(|&i| self.load[i]).collect()
    }

    /// Free coordinates of a full vector.
    pub fn restrict(&self, full: &[f64]) -> Vec<f64> {
        self.full_of_free.iter().map(|&i| full[i]).collect()
    }

    /// Writes the free vector `x` into the full vector `full` (fixed
    /// entries untouched).
    pub fn expand_into(&self, x: &[f64], full: &mut [f64]) {
        for (&i, &v) in self.full_of_free.iter().zip(x) {
            full[i] = v;
        }
    }

    /// The full coordinates for free ones `x` (fixed at `q0`).
    pub fn expand(&self, x: &[f64]) -> Vec<f64> {
        let mut full = self.q0.clone();
        self.expand_into(x, &mut full);
        full
    }

    /// Full velocities for free ones (zero on fixed coordinates).
    pub fn expand_rate(&self, v: &[f64]) -> Vec<f64> {
        let mut full = vec![0.0; self.q0.len()];
        self.expand_into(v, &mut full);
        full
    }

    /// Internal forces on the free coordinates at full `q`, `qd`;
    /// `scratch` is full-size.
    pub fn internal(&self, q: &[f64], qd: &[f64], scratch: &mut [f64], out: &mut [f64]) {
        scratch.fill(0.0);
        for g in &self.groups {
            g.add_internal(q, qd, scratch);
        }
        for (o, &i) in out.iter_mut().zip(&self.full_of_free) {
            *o = scratch[i];
        }
    }

    /// Where [`StructuralModel::jacobian`] takes the tangent of the
    /// internal forces from: the elements' generated kernels
    /// ([`Jacobian::Generated`], the default; `Auto` is the same), or
    /// forward differences of the internal forces ([`Jacobian::Differences`]:
    /// columns that share no row of the pattern perturbed together: one
    /// evaluation at the point, and one per colour and per `q`/`q̇` block;
    /// what the generated tangent saves, for work-precision comparisons).
    pub fn set_tangent(&mut self, tangent: Jacobian) {
        self.tangent = tangent;
    }

    /// The tangent's source ([`StructuralModel::set_tangent`]).
    pub fn tangent(&self) -> Jacobian {
        match self.tangent {
            Jacobian::Differences => Jacobian::Differences,
            Jacobian::Auto | Jacobian::Generated => Jacobian::Generated,
        }
    }

    /// Internal-force evaluations spent on differenced tangents so far.
    pub fn differenced_evaluations(&self) -> usize {
        self.differenced.load(Ordering::Relaxed)
    }

    /// `out = a ∂f_int/∂q + b ∂f_int/∂q̇ + c M` on the free coordinates,
    /// the tangent as [`StructuralModel::set_tangent`] says.
    pub fn jacobian(&self, q: &[f64], qd: &[f64], a: f64, b: f64, c: f64, out: &mut SparseMatrix) {
        out.clear();
        if self.tangent() == Jacobian::Differences {
            self.add_differenced_tangent(q, qd, a, b, out);
        } else {
            for (g, s) in self.groups.iter().zip(&self.slots) {
                g.add_jacobian(q, qd, a, b, s, &mut out.values);
            }
        }
        if c != 0.0 {
            for (o, m) in out.values.iter_mut().zip(&self.mass.values) {
                *o += c * m;
            }
        }
    }

    /// Columns of the pattern in groups that share no row (greedy, in
    /// column order): a banded tangent needs about its bandwidth of them.
    fn colors(&self) -> &[Vec<usize>] {
        self.colors.get_or_init(|| {
            let p = &self.pattern;
            let mut colors: Vec<Vec<usize>> = Vec::new();
            let mut taken: Vec<Vec<bool>> = Vec::new();
            for j in 0..p.n() {
                let k = taken
                    .iter()
                    .position(|t| p.entries_of(j).all(|(i, _)| !t[i]))
                    .unwrap_or_else(|| {
                        colors.push(Vec::new());
                        taken.push(vec![false; p.n()]);
                        colors.len() - 1
                    });
                colors[k].push(j);
                for (i, _) in p.entries_of(j) {
                    taken[k][i] = true;
                }
            }
            colors
        })
    }

    /// `out += a ∂f_int/∂q + b ∂f_int/∂q̇` by forward differences of
    /// [`StructuralModel::internal`], increment `√ε · max(1, |x_j|)`.
    fn add_differenced_tangent(
        &self,
        q: &[f64],
        qd: &[f64],
        a: f64,
        b: f64,
        out: &mut SparseMatrix,
    ) {
        let n = self.n_free();
        let mut scratch = vec![0.0; q.len()];
        let (mut f0, mut f1) = (vec![0.0; n], vec![0.0; n]);
        self.internal(q, qd, &mut scratch, &mut f0);
        let mut evaluations = 1;
        let mut x = Vec::with_capacity(q.len());
        for (block, coef) in [(0, a), (1, b)] {
            if coef == 0.0 {
                continue;
            }
            for color in self.colors() {
                x.clear();
                x.extend_from_slice(if block == 0 { q } else { qd });
                let step = |xj: f64| f64::EPSILON.sqrt() * xj.abs().max(1.0);
                for &j in color {
                    let i = self.full_of_free[j];
                    x[i] += step(x[i]);
                }
                if block == 0 {
                    self.internal(&x, qd, &mut scratch, &mut f1);
                } else {
                    self.internal(q, &x, &mut scratch, &mut f1);
                }
                evaluations += 1;
                let base = if block == 0 { q } else { qd };
                for &j in color {
                    let i = self.full_of_free[j];
                    let h = x[i] - base[i];
                    for (row, slot) in self.pattern.entries_of(j) {
                        out.values[slot] += coef * (f1[row] - f0[row]) / h;
                    }
                }
            }
        }
        self.differenced.fetch_add(evaluations, Ordering::Relaxed);
    }

    /// Kinetic energy `½ vᵀ M v` for free velocities `v`.
    pub fn kinetic_energy(&self, v: &[f64]) -> f64 {
        0.5 * self.mass.quadratic_form(v)
    }

    /// Strain energy at full `q` (path integral of the elastic forces).
    pub fn strain_energy(&self, q: &[f64]) -> f64 {
        self.groups.iter().map(|g| g.strain_energy(q)).sum()
    }

    /// Potential of the constant external load, `−f_extᵀ (q − q0)`.
    pub fn load_potential(&self, q: &[f64]) -> f64 {
        -self
            .load
            .iter()
            .zip(q.iter().zip(&self.q0))
            .map(|(f, (a, b))| f * (a - b))
            .sum::<f64>()
    }

    /// Total energy: kinetic + strain + load potential.
    pub fn energy(&self, q_full: &[f64], v_free: &[f64]) -> f64 {
        self.kinetic_energy(v_free) + self.strain_energy(q_full) + self.load_potential(q_full)
    }

    /// The point masses.
    pub fn point_masses(&self) -> &[(usize, f64)] {
        &self.point_masses
    }

    /// Adds a dead load `w` per unit reference length (N/m, world axes)
    /// on every element to the constant external load (each element's
    /// consistent generalised force, `∫ Sᵀ w dx`, exact).
    pub fn add_distributed_load(&mut self, w: [f64; 3]) {
        for g in &self.groups {
            g.add_uniform_load(w, &mut self.load);
        }
    }

    /// Adds a dead load `w` per unit reference length (N/m, world axes)
    /// on the elements of group `group` only (one chain of several:
    /// `ancf::Chains::add_distributed_load`).
    pub fn add_group_distributed_load(&mut self, group: usize, w: [f64; 3]) {
        self.groups[group].add_uniform_load(w, &mut self.load);
    }

    /// Adds a constant force `f` on full coordinate `i` to the external
    /// load.
    pub fn add_point_load(&mut self, i: usize, f: f64) {
        self.load[i] += f;
    }
}
