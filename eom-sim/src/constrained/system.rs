//! [`ConstrainedSystem`]: a constrained model as an ODE on `(q, u)` with the
//! multipliers eliminated at every right-hand side (Baumgarte, projection,
//! partitioning, augmented Lagrangian), and the projections after every
//! step.

use super::linalg::{
    FAST_PIVOT_RATIO, Partition, accelerations, al_or_weighted, complete_pivoting, max_abs,
    pivot_quality, weighted_min_norm,
};
use super::stats::{Recorder, weighted_singular_ratio};
use super::{ConstraintStats, ConstraintValues, DMatrix, DVector, Dynamics, Method, Refusal};
use crate::OdeSystem;
use std::cell::RefCell;

/// Damping of the accelerations' solve near a rank drop of `J` (relative
/// to `σ₁` of `J M^{-1/2}`, see [`weighted_min_norm`]).
///
/// It trades two errors (issue 16, measured on the N-four-bar, N = 1 and
/// 2, over 10 s; tests/singular_loops.rs). Off the constraint manifold
/// the component of `u̇` along the vanishing singular direction is
/// `(uₖᵀr)/σₖ` with `uₖᵀr` no longer vanishing with `σₖ`: the Runge–Kutta
/// stages, which are off the manifold by about the local error, see a
/// right-hand side amplified by `1/σₖ`, which the damping caps at `1/(2μ)`;
/// below `μ ≈ 1e-6 σ₁` that noise dominates (DOP853 leaves the branch or
/// shrinks its step to nothing at `1e-7`). On the manifold the damping
/// biases that component by `(μ/σₖ)²` over the window `σₖ ≲ μ`, a
/// motion error that does not depend on the tolerance: at `1e-3` (the
/// earlier value) it left the error of the crank at a few 1e-8 rad
/// whatever the tolerance. Between, at `3e-5`, the error falls with the
/// tolerance (about 5e-9 rad at 1e-10, 5e-11 at 1e-12 with DOP853).
const ACC_DAMPING: f64 = 3e-5;

/// Pivot ratio of the dependent block below which [`Method::Partitioning`]
/// projects mass-orthogonally instead.
const SINGULAR_BLOCK: f64 = 0.3;

/// Damping of the projections' Newton and speed solves.
const PROJ_DAMPING: f64 = 1e-5;

/// `J[rows, cols] x = r[rows]` for the dependent speeds `cols`, as the
/// smallest change in the metric of `M[cols, cols]` ([`weighted_min_norm`],
/// damped): the exact solution while the dependent block is regular, and
/// bounded and continuous where it goes singular with `J` (at the
/// four-bar's change point every 2×2 block of `J` is singular, whatever
/// the partition, while the crank stays a valid independent coordinate).
fn solve_partition(
    j: &DMatrix<f64>,
    p: &Partition,
    r: &DVector<f64>,
    m: &DMatrix<f64>,
) -> Option<DVector<f64>> {
    let n = p.rows.len();
    let sub = DMatrix::from_fn(n, p.cols.len(), |a, b| j[(p.rows[a], p.cols[b])]);
    let mdd = DMatrix::from_fn(p.cols.len(), p.cols.len(), |a, b| m[(p.cols[a], p.cols[b])]);
    let rhs = DVector::from_fn(n, |a, _| r[p.rows[a]]);
    let l = mdd.cholesky()?.l();
    weighted_min_norm(&l, &sub, &rhs, PROJ_DAMPING).map(|(x, _, _)| x)
}

/// Most Newton iterations of a projection onto `Φ(q, t) = 0`.
const NEWTON_ITERATIONS: usize = 40;

/// Newton onto the holonomic equations `Φ(q, t) = 0` from `q`: each step
/// `Δu = step(q, J_h, −Φ)`, mapped to `Δq` by `q̇ = N(q) Δu`, for as long as
/// `max |Φ|` falls — to round-off — and then the best iterate.
///
/// A fixed stop such as `|Φ| < 1e-13` is not enough near a rank drop of
/// `J` (issue 16): at the four-bar's change point the two assembly branches
/// cross, `Φ` is quadratic along the direction that leads from one to the
/// other, `Φ ≈ ½ κ δ²`, and Newton converges only linearly there (`δ`
/// halves per step). Stopping at `|Φ| < 1e-13` left `δ ≈ 3e-7`, and the
/// mass-orthogonal projections after the change point turned that into an
/// error of the motion along the branch of up to 6e-7 rad that did not fall
/// with the tolerance. Iterating while `|Φ|` falls takes `δ` to the
/// round-off of `Φ` (`√ε` at the crossing itself, far less a step away).
fn newton_onto_positions<D: Dynamics + ?Sized>(
    d: &D,
    t: f64,
    q: &mut [f64],
    mut step: impl FnMut(&[f64], &DMatrix<f64>, &DVector<f64>) -> Option<DVector<f64>>,
) {
    let (nu, nh) = (d.nu(), d.n_holonomic());
    let mut c = ConstraintValues::zeros(d.nc(), nu);
    let zero = vec![0.0; nu];
    let mut dq = vec![0.0; q.len()];
    let mut best = q.to_vec();
    let mut best_residual = f64::INFINITY;
    for k in 0..=NEWTON_ITERATIONS {
        d.constraints(t, q, &zero, &mut c);
        let residual = max_abs(c.phi.iter().take(nh));
        if residual.is_nan() || residual >= best_residual {
            // No progress (round-off reached) or not finite: the best.
            q.copy_from_slice(&best);
            return;
        }
        best.copy_from_slice(q);
        best_residual = residual;
        if residual == 0.0 || k == NEWTON_ITERATIONS {
            return;
        }
        let jh = c.jacobian.rows(0, nh).into_owned();
        let minus_phi = -c.phi.rows(0, nh).into_owned();
        let Some(du) = step(q, &jh, &minus_phi) else {
            return;
        };
        d.qdot(q, du.as_slice(), &mut dq);
        q.iter_mut().zip(&dq).for_each(|(q, d)| *q += d);
        d.normalize(q);
    }
}

/// Buffers of the per-right-hand-side solve, allocated once per run.
struct Workspace {
    m: DMatrix<f64>,
    b: DVector<f64>,
    c: ConstraintValues,
    minv_jt: DMatrix<f64>,
    schur: DMatrix<f64>,
    rhs: DVector<f64>,
}

impl Workspace {
    fn new(nu: usize, nc: usize) -> Self {
        Workspace {
            m: DMatrix::zeros(nu, nu),
            b: DVector::zeros(nu),
            c: ConstraintValues::zeros(nc, nu),
            minv_jt: DMatrix::zeros(nu, nc),
            schur: DMatrix::zeros(nc, nc),
            rhs: DVector::zeros(nc),
        }
    }

    /// `u̇` into `b` (and `λ` into `rhs`) without allocating when `M` and
    /// the Schur complement are well conditioned; otherwise through
    /// [`accelerations`]. `false` if `M` is not positive definite.
    fn solve<D: Dynamics + ?Sized>(
        &mut self,
        d: &D,
        method: Method,
        t: f64,
        q: &[f64],
        u: &[f64],
    ) -> bool {
        let (nu, nc) = (d.nu(), d.nc());
        d.mass_matrix(t, q, &mut self.m);
        d.bias(t, q, u, &mut self.b);
        d.constraints(t, q, u, &mut self.c);
        if let Method::Baumgarte { alpha, beta } = method {
            for i in 0..nc {
                self.c.gamma[i] -= 2.0 * alpha * self.c.phidot[i] + beta * beta * self.c.phi[i];
            }
        }
        self.b.neg_mut();
        if let Method::AugmentedLagrangian {
            penalty,
            iterations,
        } = method
        {
            let Some((x, lambda)) = al_or_weighted(
                &self.m,
                &self.b,
                &self.c.jacobian,
                &self.c.gamma,
                (penalty, iterations),
                ACC_DAMPING,
            ) else {
                return false;
            };
            self.b.copy_from(&x);
            self.rhs.copy_from(&lambda);
            return true;
        }
        let m = std::mem::replace(&mut self.m, DMatrix::zeros(0, 0));
        let Some(chol) = m.cholesky() else {
            self.m = DMatrix::zeros(nu, nu);
            return false;
        };
        chol.solve_mut(&mut self.b);
        self.c.jacobian.transpose_to(&mut self.minv_jt);
        chol.solve_mut(&mut self.minv_jt);
        self.m = chol.unpack_dirty();
        if nc == 0 {
            return true;
        }
        self.schur.gemm(1.0, &self.c.jacobian, &self.minv_jt, 0.0);
        self.rhs.copy_from(&self.c.gamma);
        self.rhs.gemv(-1.0, &self.c.jacobian, &self.b, 1.0);
        let schur = std::mem::replace(&mut self.schur, DMatrix::zeros(0, 0));
        let fast = match schur.cholesky() {
            Some(chol) => {
                let d = chol.l_dirty().diagonal();
                let (lo, hi) = d.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
                    (lo.min(x * x), hi.max(x * x))
                });
                let ok = lo > FAST_PIVOT_RATIO * hi;
                if ok {
                    chol.solve_mut(&mut self.rhs);
                }
                self.schur = chol.unpack_dirty();
                ok
            }
            None => {
                self.schur = DMatrix::zeros(nc, nc);
                false
            }
        };
        if !fast {
            // Near a rank drop (or redundant): the damped mass-weighted
            // minimum-norm solve (`weighted_min_norm`) on `M`'s factor.
            let l = self.m.lower_triangle();
            let Some((x, lambda, _)) =
                weighted_min_norm(&l, &self.c.jacobian, &self.rhs, ACC_DAMPING)
            else {
                return false;
            };
            self.b += x;
            self.rhs.copy_from(&lambda);
            return true;
        }
        self.b.gemv(1.0, &self.minv_jt, &self.rhs, 1.0);
        true
    }
}

/// Integration of a constrained model with [`Method::Baumgarte`],
/// [`Method::Projection`] or [`Method::Partitioning`] as an [`OdeSystem`]
/// on `y = (q, u)`; `N = n_q + n_u`.
pub struct ConstrainedSystem<'a, D: ?Sized> {
    d: &'a D,
    method: Method,
    stats: Recorder,
    partitions: RefCell<Option<(Partition, Partition)>>,
    work: RefCell<Workspace>,
    start_rank: std::cell::Cell<Option<usize>>,
    /// `σ_r / σ_1` of `J M^{-1/2}` at the first state checked: the
    /// baseline a rank drop is measured against.
    start_ratio: std::cell::Cell<Option<f64>>,
}

/// [`Method::Baumgarte`] refuses to go on when `σ_r/σ_1` of `J M^{-1/2}`
/// (`r` the rank at the start) falls below this fraction of its value at
/// the start: its terms `−2αΦ̇ − β²Φ` have components along the vanishing
/// singular direction, which the multipliers divide by `σ_r`. Measured
/// against the start, the test sees a coming rank drop, not the
/// conditioning of `J M^{-1/2}` itself: many nearly redundant loops (the
/// N-four-bar with N = 40 starts at `σ_r/σ_1` of a few 1e-3) make that small
/// everywhere, far from any singular position.
pub const BAUMGARTE_SINGULAR_LIMIT: f64 = 5e-2;

impl<'a, D: Dynamics + ?Sized> ConstrainedSystem<'a, D> {
    /// The system of `d` kept by `method` (not [`Method::Index3`], which is
    /// [`Index3System`](super::Index3System)).
    pub fn new(d: &'a D, method: Method) -> Self {
        ConstrainedSystem {
            d,
            method,
            stats: Recorder::new(),
            partitions: RefCell::new(None),
            work: RefCell::new(Workspace::new(d.nu(), d.nc())),
            start_rank: std::cell::Cell::new(None),
            start_ratio: std::cell::Cell::new(None),
        }
    }

    /// What was seen along the run so far.
    pub fn stats(&self) -> ConstraintStats {
        self.stats.stats()
    }

    /// `σ_r / σ_1` of `J M^{-1/2}` at a state, `r` the rank at the first
    /// state asked about; 1 without constraints.
    fn singular_ratio(&self, t: f64, q: &[f64]) -> f64 {
        weighted_singular_ratio(self.d, t, q, &self.start_rank)
    }

    /// Refuses (see [`Refusal`]) when `self.method` cannot go on at `(t, q)`.
    fn check_refusal(&self, t: f64, q: &[f64]) {
        if !matches!(self.method, Method::Baumgarte { .. }) || self.d.nc() == 0 {
            return;
        }
        if self.stats.0.borrow().0.refusal.is_some() {
            return;
        }
        let ratio = self.singular_ratio(t, q);
        let start = match self.start_ratio.get() {
            Some(r) => r,
            None => {
                self.start_ratio.set(Some(ratio));
                ratio
            }
        };
        if ratio < BAUMGARTE_SINGULAR_LIMIT * start.min(1.0) {
            self.stats.0.borrow_mut().0.refusal = Some(Refusal::SingularConfiguration {
                method: "baumgarte",
                t,
                singular_ratio: ratio,
                recommended: "augmented-lagrangian or projection",
            });
        }
    }

    /// Why the run was stopped, if the method refused to go on.
    pub fn refusal(&self) -> Option<Refusal> {
        self.stats.0.borrow().0.refusal.clone()
    }

    /// `u̇` and `λ` at a state (with this method's stabilisation).
    pub fn accelerations(
        &self,
        t: f64,
        q: &[f64],
        u: &[f64],
    ) -> Option<(DVector<f64>, DVector<f64>)> {
        let (nu, nc) = (self.d.nu(), self.d.nc());
        let mut m = DMatrix::zeros(nu, nu);
        let mut b = DVector::zeros(nu);
        let mut c = ConstraintValues::zeros(nc, nu);
        self.d.mass_matrix(t, q, &mut m);
        self.d.bias(t, q, u, &mut b);
        self.d.constraints(t, q, u, &mut c);
        let mut gamma = c.gamma;
        if let Method::Baumgarte { alpha, beta } = self.method {
            gamma -= c.phidot * (2.0 * alpha) + c.phi * (beta * beta);
        }
        accelerations(&m, &-b, &c.jacobian, &gamma).map(|(a, l, _)| (a, l))
    }

    /// Mass-orthogonal projection: Newton steps `Δ = −M⁻¹Jᵀ(JM⁻¹Jᵀ)⁺Φ`
    /// onto `Φ = 0` (the smallest change in the kinetic-energy metric, so
    /// the correction is normal to the motion and the steps from the
    /// predicted state stay on its assembly branch), then the speeds by
    /// `Δu = −M⁻¹Jᵀ(JM⁻¹Jᵀ)⁺Φ̇`, which leaves the momentum along the
    /// admissible motions unchanged ([`weighted_min_norm`], continuous
    /// through rank drops of `J`).
    fn project_mass_orthogonal(&self, t: f64, q: &mut [f64], u: &mut [f64]) {
        let d = self.d;
        let nu = d.nu();
        let mut c = ConstraintValues::zeros(d.nc(), nu);
        let mut m = DMatrix::zeros(nu, nu);
        let factor = |q: &[f64], m: &mut DMatrix<f64>| {
            d.mass_matrix(t, q, m);
            m.clone().cholesky().map(|c| c.l())
        };
        newton_onto_positions(d, t, q, |q, jh, r| {
            let mut m = DMatrix::zeros(nu, nu);
            let l = factor(q, &mut m)?;
            weighted_min_norm(&l, jh, r, PROJ_DAMPING).map(|(x, _, _)| x)
        });
        d.constraints(t, q, u, &mut c);
        let Some(l) = factor(q, &mut m) else {
            return;
        };
        if let Some((du, _, _)) =
            weighted_min_norm(&l, &c.jacobian, &-c.phidot.clone(), PROJ_DAMPING)
        {
            u.iter_mut().zip(du.iter()).for_each(|(u, d)| *u += d);
        }
    }

    /// Mass-orthogonal projections of `q` (Newton) and `u` as in
    /// [`Self::project_mass_orthogonal`], each step by [`al_solve`](super::al_solve).
    fn project_augmented(
        &self,
        t: f64,
        q: &mut [f64],
        u: &mut [f64],
        penalty: f64,
        iterations: usize,
    ) {
        let d = self.d;
        let nu = d.nu();
        let mut c = ConstraintValues::zeros(d.nc(), nu);
        let mut m = DMatrix::zeros(nu, nu);
        let f = DVector::zeros(nu);
        let settings = (penalty, iterations);
        newton_onto_positions(d, t, q, |q, jh, r| {
            let mut m = DMatrix::zeros(nu, nu);
            d.mass_matrix(t, q, &mut m);
            al_or_weighted(&m, &f, jh, r, settings, PROJ_DAMPING).map(|(x, _)| x)
        });
        d.constraints(t, q, u, &mut c);
        d.mass_matrix(t, q, &mut m);
        if let Some((du, _)) = al_or_weighted(
            &m,
            &f,
            &c.jacobian,
            &-c.phidot.clone(),
            settings,
            PROJ_DAMPING,
        ) {
            u.iter_mut().zip(du.iter()).for_each(|(u, d)| *u += d);
        }
    }

    /// Dependent coordinates by Newton with the independent ones held, then
    /// the dependent speeds; re-partitions when the pivot ratio of the
    /// dependent block fell below a tenth of what it was chosen at.
    fn project_partitioned(&self, t: f64, q: &mut [f64], u: &mut [f64]) {
        let d = self.d;
        let (nu, nh) = (d.nu(), d.n_holonomic());
        let mut c = ConstraintValues::zeros(d.nc(), nu);
        d.constraints(t, q, u, &mut c);
        let jh = c.jacobian.rows(0, nh).into_owned();
        let mut parts = self.partitions.borrow_mut();
        let renew = match parts.as_ref() {
            None => true,
            Some((ph, pa)) => {
                pivot_quality(&jh, ph) < 0.1 * ph.quality
                    || pivot_quality(&c.jacobian, pa) < 0.1 * pa.quality
            }
        };
        if renew {
            if parts.is_some() {
                self.stats.repartitioned();
            }
            *parts = Some((complete_pivoting(&jh), complete_pivoting(&c.jacobian)));
        }
        let Some((ph, pa)) = parts.as_ref() else {
            return;
        };
        if pivot_quality(&jh, ph) < SINGULAR_BLOCK
            || pivot_quality(&c.jacobian, pa) < SINGULAR_BLOCK
        {
            // Near a rank drop of J every dependent block is nearly
            // singular (the four-bar's change point): the dependent
            // coordinates are ill-determined by the independent ones there,
            // so this step is projected mass-orthogonally instead.
            drop(parts);
            self.project_mass_orthogonal(t, q, u);
            return;
        }
        let mut m = DMatrix::zeros(nu, nu);
        newton_onto_positions(d, t, q, |q, jh, r| {
            let mut m = DMatrix::zeros(nu, nu);
            d.mass_matrix(t, q, &mut m);
            let x = solve_partition(jh, ph, r, &m)?;
            let mut du = DVector::zeros(nu);
            for (k, &col) in ph.cols.iter().enumerate() {
                du[col] = x[k];
            }
            Some(du)
        });
        d.constraints(t, q, u, &mut c);
        d.mass_matrix(t, q, &mut m);
        if let Some(x) = solve_partition(&c.jacobian, pa, &-c.phidot.clone(), &m) {
            for (k, &col) in pa.cols.iter().enumerate() {
                u[col] += x[k];
            }
        }
    }
}

impl<const N: usize, D: Dynamics + ?Sized> OdeSystem<N> for ConstrainedSystem<'_, D> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let nq = self.d.nq();
        let (q, u) = y.split_at(nq);
        let (qd, ud) = dy.split_at_mut(nq);
        self.d.qdot(q, u, qd);
        self.check_refusal(t, q);
        let refused = self.stats.0.borrow().0.refusal.is_some();
        let mut w = self.work.borrow_mut();
        if !refused && w.solve(self.d, self.method, t, q, u) {
            ud.iter_mut().zip(w.b.iter()).for_each(|(d, s)| *d = *s);
        } else {
            ud.iter_mut().for_each(|d| *d = f64::NAN);
        }
    }

    fn project(&self, t: f64, y: &mut [f64; N]) -> bool {
        let (nq, nu) = (self.d.nq(), self.d.nu());
        let (q, u) = y.split_at_mut(nq);
        self.d.normalize(q);
        match self.method {
            Method::Projection => self.project_mass_orthogonal(t, q, u),
            Method::Partitioning => self.project_partitioned(t, q, u),
            Method::AugmentedLagrangian {
                penalty,
                iterations,
            } => self.project_augmented(t, q, u, penalty, iterations),
            Method::Baumgarte { .. } | Method::Index3 => {}
        }
        let mut c = ConstraintValues::zeros(self.d.nc(), nu);
        self.d.constraints(t, q, u, &mut c);
        self.stats.record(self.d.n_holonomic(), &c);
        true
    }
}
