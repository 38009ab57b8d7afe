//! Constrained multibody systems: closed loops and user constraints.
//!
//! A model with constraints has, besides `q̇ = N(q) u` and
//! `M(q) u̇ = τ − b(q, u, t)`, `m` constraint equations on the speeds
//!
//! ```text
//! Φ̇(q, u, t) = J(q, t) u + Φ_t(q, t) = 0,      J u̇ = γ(q, u, t),
//! ```
//!
//! of which the first `m_h` are time derivatives of position-level
//! (holonomic) conditions `Φ(q, t) = 0` (cut joints, user expressions) and
//! the rest are nonholonomic (rolling without slipping). The constraint
//! forces are `Jᵀλ`: `M u̇ = τ − b + Jᵀλ` (Wittenburg 5.6, Shabana 5.9–5.12).
//!
//! Four ways to integrate them are built here ([`Method`]):
//!
//! | method | unknowns | drift |
//! |---|---|---|
//! | [`Method::Baumgarte`] | `(q, u)`, `λ` eliminated per right-hand side | Baumgarte terms `γ − 2α Φ̇ − β² Φ` |
//! | [`Method::Projection`] | `(q, u)`, as above | Newton onto `Φ = 0`, then `u` onto `Φ̇ = 0`, minimum-norm steps after every step |
//! | [`Method::Partitioning`] | `(q, u)`, as above | dependent coordinates from the independent ones (Wehage–Haug) after every step |
//! | [`Method::Index3`] | `(q, u, λ)`: the index-3 DAE for [`Radau5`](crate::Radau5) | none: `Φ = 0` is an equation |
//!
//! `λ` comes from the Schur complement `J M⁻¹ Jᵀ λ = γ − J M⁻¹ (τ − b)`,
//! solved through its symmetric eigendecomposition with eigenvalues below
//! `1e-10` of the largest dropped: redundant equations (Bricard's loop)
//! give the minimum-norm `λ` and the numerical rank is reported.

use crate::model::{Model, Vector};
use crate::{OdeSystem, SMatrix};
pub use nalgebra::{DMatrix, DVector};
use std::cell::RefCell;

/// A generated model with constraint equations (see the module docs).
pub trait ConstrainedModel: Model {
    /// Number of constraint equations `m`.
    const NC: usize;
    /// Number of holonomic equations `m_h` (they come first).
    const NHOLONOMIC: usize;
    /// Names of the equations (`joint.k` for cut joints, the constraint's
    /// name for user constraints).
    const CONSTRAINT_NAMES: &'static [&'static str];
    /// `[f64; NC]`.
    type Constraints: Vector;
    /// `J`, `[f64; NC * NU]`, by rows.
    type ConstraintJacobian: Vector;
    /// Sets the multipliers `λ` that [`Model::outputs`] uses for joint
    /// reactions (the constraint forces `Jᵀλ` act on the bodies).
    fn set_multipliers(&mut self, lambda: &Self::Constraints);
    /// `Φ` (zero for nonholonomic rows), `Φ̇ = J u + Φ_t`, `γ` (`J u̇ = γ`)
    /// and `J`.
    #[allow(clippy::too_many_arguments)]
    fn constraints(
        &self,
        t: f64,
        q: &Self::Q,
        u: &Self::U,
        phi: &mut Self::Constraints,
        phidot: &mut Self::Constraints,
        gamma: &mut Self::Constraints,
        jacobian: &mut Self::ConstraintJacobian,
    );
}

/// Constraint values at one state.
#[derive(Clone, Debug)]
pub struct ConstraintValues {
    /// `Φ` (holonomic rows; zero for nonholonomic ones).
    pub phi: DVector<f64>,
    /// `Φ̇ = J u + Φ_t`.
    pub phidot: DVector<f64>,
    /// `γ` with `J u̇ = γ`.
    pub gamma: DVector<f64>,
    /// `J`, `m × n_u`.
    pub jacobian: DMatrix<f64>,
}

impl ConstraintValues {
    /// Zeros for `m` equations and `nu` speeds.
    pub fn zeros(m: usize, nu: usize) -> Self {
        ConstraintValues {
            phi: DVector::zeros(m),
            phidot: DVector::zeros(m),
            gamma: DVector::zeros(m),
            jacobian: DMatrix::zeros(m, nu),
        }
    }
}

/// A constrained model seen through slices: what the solvers need. It is
/// implemented for generated code through [`Generated`] and by `eom-gen`'s
/// interpreter.
pub trait Dynamics {
    /// Number of positions.
    fn nq(&self) -> usize;
    /// Number of speeds.
    fn nu(&self) -> usize;
    /// Number of constraint equations.
    fn nc(&self) -> usize;
    /// Number of holonomic equations (the first ones).
    fn n_holonomic(&self) -> usize;
    /// Positions of unit quaternions in `q`.
    fn quaternions(&self) -> &[usize];
    /// `q̇ = N(q) u`.
    fn qdot(&self, q: &[f64], u: &[f64], qdot: &mut [f64]);
    /// `M(q)`.
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut DMatrix<f64>);
    /// `b(q, u, t)`.
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut DVector<f64>);
    /// The constraint values.
    fn constraints(&self, t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues);

    /// Normalises the unit quaternions in `q`.
    fn normalize(&self, q: &mut [f64]) {
        for &a in self.quaternions() {
            if let Some(quat) = q.get_mut(a..a + 4) {
                let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                if n > 0.0 && n.is_finite() {
                    quat.iter_mut().for_each(|x| *x /= n);
                }
            }
        }
    }
}

/// What assembly needs of a constrained model: its sizes, `q̇ = N(q) u`
/// and the constraint values without `γ`. Every [`Dynamics`] has it;
/// `eom-gen`'s `f64` reference algorithms implement it too, so one
/// assembly serves both.
pub trait Assemble {
    /// Number of speeds.
    fn speeds(&self) -> usize;
    /// Number of constraint equations.
    fn equations(&self) -> usize;
    /// Number of holonomic equations (the first ones).
    fn holonomic(&self) -> usize;
    /// `q̇ = N(q) u`.
    fn rates(&self, q: &[f64], u: &[f64], qdot: &mut [f64]);
    /// `Φ`, `Φ̇` and `J` (`γ` is not read).
    fn closure(&self, t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues);
    /// Normalises the unit quaternions in `q`.
    fn unit_quaternions(&self, q: &mut [f64]);
}

impl<D: Dynamics + ?Sized> Assemble for D {
    fn speeds(&self) -> usize {
        self.nu()
    }
    fn equations(&self) -> usize {
        self.nc()
    }
    fn holonomic(&self) -> usize {
        self.n_holonomic()
    }
    fn rates(&self, q: &[f64], u: &[f64], qdot: &mut [f64]) {
        self.qdot(q, u, qdot);
    }
    fn closure(&self, t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues) {
        self.constraints(t, q, u, c);
    }
    fn unit_quaternions(&self, q: &mut [f64]) {
        self.normalize(q);
    }
}

/// Generated code as [`Dynamics`].
pub struct Generated<'a, M>(pub &'a M);

pub(crate) fn load<V: Vector>(src: &[f64]) -> V {
    let mut v = V::ZERO;
    for (d, s) in v.as_mut().iter_mut().zip(src) {
        *d = *s;
    }
    v
}

impl<M: ConstrainedModel> Dynamics for Generated<'_, M> {
    fn nq(&self) -> usize {
        M::NQ
    }
    fn nu(&self) -> usize {
        M::NU
    }
    fn nc(&self) -> usize {
        M::NC
    }
    fn n_holonomic(&self) -> usize {
        M::NHOLONOMIC
    }
    fn quaternions(&self) -> &[usize] {
        M::QUATERNIONS
    }
    fn qdot(&self, q: &[f64], u: &[f64], qdot: &mut [f64]) {
        let mut out = M::Q::ZERO;
        self.0.qdot(&load(q), &load(u), &mut out);
        for (d, s) in qdot.iter_mut().zip(out.as_ref()) {
            *d = *s;
        }
    }
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut DMatrix<f64>) {
        let mut out = M::MASS_ZERO;
        self.0.mass_matrix(t, &load(q), &mut out);
        for (i, row) in out.as_ref().iter().enumerate() {
            for (j, v) in row.as_ref().iter().enumerate() {
                if i < m.nrows() && j < m.ncols() {
                    m[(i, j)] = *v;
                }
            }
        }
    }
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut DVector<f64>) {
        let mut out = M::U::ZERO;
        self.0.bias(t, &load(q), &load(u), &mut out);
        for (d, s) in b.iter_mut().zip(out.as_ref()) {
            *d = *s;
        }
    }
    fn constraints(&self, t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues) {
        let (mut phi, mut phidot, mut gamma) = (
            M::Constraints::ZERO,
            M::Constraints::ZERO,
            M::Constraints::ZERO,
        );
        let mut jac = M::ConstraintJacobian::ZERO;
        self.0.constraints(
            t,
            &load(q),
            &load(u),
            &mut phi,
            &mut phidot,
            &mut gamma,
            &mut jac,
        );
        for (d, s) in c.phi.iter_mut().zip(phi.as_ref()) {
            *d = *s;
        }
        for (d, s) in c.phidot.iter_mut().zip(phidot.as_ref()) {
            *d = *s;
        }
        for (d, s) in c.gamma.iter_mut().zip(gamma.as_ref()) {
            *d = *s;
        }
        let nu = M::NU;
        for (k, v) in jac.as_ref().iter().enumerate() {
            let (r, col) = (k / nu.max(1), k % nu.max(1));
            if r < c.jacobian.nrows() && col < c.jacobian.ncols() {
                c.jacobian[(r, col)] = *v;
            }
        }
    }
}

/// How constraints are kept (see the module docs); projection by default.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Method {
    /// Multipliers with Baumgarte stabilisation `γ − 2α Φ̇ − β² Φ`.
    Baumgarte {
        /// `α`, s⁻¹.
        alpha: f64,
        /// `β`, s⁻¹.
        beta: f64,
    },
    /// Multipliers, then projection of `q` and `u` after every step.
    #[default]
    Projection,
    /// Multipliers, then the dependent coordinates and speeds recomputed
    /// from the independent ones after every step.
    Partitioning,
    /// The index-3 DAE in `(q, u, λ)`.
    Index3,
    /// Augmented Lagrangian (Bayo and Ledesma 1996; García de Jalón and
    /// Bayo 1994): every constrained solve — the accelerations at each
    /// right-hand side and the mass-orthogonal projections of `q` and `u`
    /// after every step — minimises `½ xᵀMx − fᵀx` subject to `J x = r` by
    /// iterating `(M + αJᵀJ) x_{k+1} = f + Jᵀ(λ_k + α r)`,
    /// `λ_{k+1} = λ_k + α (r − J x_{k+1})` from `λ_0 = 0`. The leading
    /// matrix stays positive definite when `J` is singular or redundant.
    AugmentedLagrangian {
        /// `α` relative to `max diag M / max diag JᵀJ` (dimensionless).
        penalty: f64,
        /// Most iterations per solve (it stops earlier once `J x = r`
        /// holds to round-off).
        iterations: usize,
    },
}

impl Method {
    /// Baumgarte with `α = β = 10 s⁻¹`, the default of `eom-gen simulate`.
    pub const BAUMGARTE: Method = Method::Baumgarte {
        alpha: 10.0,
        beta: 10.0,
    };

    /// The augmented Lagrangian with `α = 1e5` (relative) and at most 20
    /// iterations per solve, the default of `--constraints
    /// augmented-lagrangian`.
    pub const AUGMENTED_LAGRANGIAN: Method = Method::AugmentedLagrangian {
        penalty: 1e5,
        iterations: 20,
    };
}

/// What the solver saw along a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConstraintStats {
    /// Largest `|Φ|` (holonomic rows) at the accepted states.
    pub max_position_residual: f64,
    /// Largest `|Φ̇|` at the accepted states.
    pub max_velocity_residual: f64,
    /// Numerical rank of `J` (at the last accepted state).
    pub rank: usize,
    /// Smallest rank seen.
    pub min_rank: usize,
    /// Changes of the coordinate partition ([`Method::Partitioning`]).
    pub repartitions: usize,
    /// Smallest `σ_r / σ_1` of `J` at the accepted states, `r` the rank at
    /// the first of them: how near the run came to a singular
    /// configuration (of order 1 far from one, towards 0 at one, such as
    /// the four-bar's change point, where the rank drops between steps
    /// without any step landing on it); 1 if nothing was recorded.
    pub min_singular_ratio: f64,
    /// Why the method stopped the run, if it refused to go on (the
    /// right-hand side is NaN from then on, so the integrator stops with
    /// [`StopReason::NonFinite`](crate::StopReason::NonFinite)).
    pub refusal: Option<Refusal>,
}

/// A method's refusal to continue a run it cannot get right.
#[derive(Clone, Debug, PartialEq)]
pub enum Refusal {
    /// Near a singular configuration (a rank drop of `J`, where the
    /// mobility changes: the four-bar's collinear change point).
    SingularConfiguration {
        /// The method's `--constraints` name.
        method: &'static str,
        /// Time of the state that came too near.
        t: f64,
        /// `σ_r / σ_1` of `J M^{-1/2}` there, `r` the rank at the start.
        singular_ratio: f64,
        /// Methods that pass such configurations.
        recommended: &'static str,
    },
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::SingularConfiguration {
                method,
                t,
                singular_ratio,
                recommended,
            } => write!(
                f,
                "--constraints {method} stopped at t = {t} s near a singular configuration: the \
                 constraint Jacobian is losing rank (σ_r/σ_1 = {singular_ratio:.1e}; links \
                 aligned, the mobility changes there), where this method's multipliers are \
                 undetermined along the vanishing direction and would corrupt the motion; use \
                 --constraints {recommended}"
            ),
        }
    }
}

/// [`ConstraintStats`] gathered at the accepted states of a run, and the
/// rank of `J` at the first of them (which singular value to watch).
struct Recorder(RefCell<(ConstraintStats, Option<usize>)>);

impl Recorder {
    fn new() -> Self {
        Recorder(RefCell::new((
            ConstraintStats {
                min_rank: usize::MAX,
                min_singular_ratio: 1.0,
                ..ConstraintStats::default()
            },
            None,
        )))
    }

    /// Residuals of the first `nh` (holonomic) rows and of all speed rows,
    /// the rank of `J` and how near it is to losing it, at an accepted state.
    fn record(&self, nh: usize, c: &ConstraintValues) {
        let sigma = singular_values(&c.jacobian);
        let largest = sigma.first().copied().unwrap_or(0.0);
        let rank = numerical_rank(&sigma);
        let (s, first_rank) = &mut *self.0.borrow_mut();
        s.max_position_residual = s.max_position_residual.max(max_abs(c.phi.iter().take(nh)));
        s.max_velocity_residual = s.max_velocity_residual.max(max_abs(c.phidot.iter()));
        let watched = *first_rank.get_or_insert(rank);
        if watched > 0 && largest > 0.0 {
            let ratio = sigma.get(watched - 1).copied().unwrap_or(0.0) / largest;
            s.min_singular_ratio = s.min_singular_ratio.min(ratio);
        }
        s.rank = rank;
        s.min_rank = s.min_rank.min(rank);
    }

    fn stats(&self) -> ConstraintStats {
        let mut s = self.0.borrow().0.clone();
        if s.min_rank == usize::MAX {
            s.min_rank = s.rank;
        }
        s
    }

    fn repartitioned(&self) {
        self.0.borrow_mut().0.repartitions += 1;
    }
}

/// Singular values below this fraction of the largest count as zero.
const RANK_TOL: f64 = 1e-10;

/// How many singular values (largest first) are above [`RANK_TOL`] of the
/// largest.
fn numerical_rank(sigma: &[f64]) -> usize {
    let largest = sigma.first().copied().unwrap_or(0.0);
    sigma
        .iter()
        .filter(|&&x| x > RANK_TOL * largest.max(1e-300))
        .count()
}

/// Singular values of `a`, largest first (none for an empty matrix).
fn singular_values(a: &DMatrix<f64>) -> Vec<f64> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return Vec::new();
    }
    // nalgebra's SVD panics on NaN; a non-finite J has no singular values.
    if !a.iter().all(|x| x.is_finite()) {
        return vec![f64::NAN; a.nrows().min(a.ncols())];
    }
    let mut s: Vec<f64> = a.clone().singular_values().iter().copied().collect();
    s.sort_by(|x, y| y.total_cmp(x));
    s
}

/// Minimum-norm solution of `a x = r` via the SVD, and the numerical rank
/// (singular values below `1e-10` of the largest dropped).
pub fn min_norm_solve(a: &DMatrix<f64>, r: &DVector<f64>) -> (DVector<f64>, usize) {
    if a.nrows() == 0 || a.ncols() == 0 {
        return (DVector::zeros(a.ncols()), 0);
    }
    // nalgebra's SVD panics on NaN: a non-finite system has no solution.
    if !(a.iter().all(|x| x.is_finite()) && r.iter().all(|x| x.is_finite())) {
        return (DVector::from_element(a.ncols(), f64::NAN), 0);
    }
    let svd = a.clone().svd(true, true);
    let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let eps = RANK_TOL * largest.max(1e-300);
    let rank = svd.singular_values.iter().filter(|&&s| s > eps).count();
    match svd.solve(r, eps) {
        Ok(x) => (x, rank),
        Err(_) => (DVector::zeros(a.ncols()), rank),
    }
}

/// `u̇` and `λ` of `M u̇ = −b + Jᵀλ + τ`, `J u̇ = γ`, and the rank of the
/// Schur complement; `None` if `M` is not positive definite.
pub fn accelerations(
    m: &DMatrix<f64>,
    force: &DVector<f64>,
    jacobian: &DMatrix<f64>,
    gamma: &DVector<f64>,
) -> Option<(DVector<f64>, DVector<f64>, usize)> {
    let chol = m.clone().cholesky()?;
    let free = chol.solve(force);
    if jacobian.nrows() == 0 {
        return Some((free, DVector::zeros(0), 0));
    }
    let minv_jt = chol.solve(&jacobian.transpose());
    let schur = jacobian * &minv_jt;
    let rhs = gamma - jacobian * &free;
    // Well-conditioned (the usual case): Cholesky. Its pivots bound the
    // eigenvalues' spread from below, so a pivot ratio above the cut means
    // the Schur complement is far from a rank drop and the weighted SVD
    // would give the same λ.
    if let Some(chol) = schur.clone().cholesky() {
        let d = chol.l_dirty().diagonal();
        let (lo, hi) = d.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
            (lo.min(x * x), hi.max(x * x))
        });
        if lo > FAST_PIVOT_RATIO * hi {
            let lambda = chol.solve(&rhs);
            let udot = free + minv_jt * &lambda;
            return Some((udot, lambda, jacobian.nrows()));
        }
    }
    let l = m.clone().cholesky()?.l();
    let (x, lambda, rank) = weighted_min_norm(&l, jacobian, &rhs, RANK_TOL)?;
    Some((free + x, lambda, rank))
}

/// The Schur complement's Cholesky factor is used when its smallest squared
/// pivot is above this fraction of the largest (singular-value ratio of
/// `J M^{-1/2}` above about 1e-2); nearer a rank drop, the weighted SVD.
const FAST_PIVOT_RATIO: f64 = 1e-4;

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

/// Singular values of `J L⁻ᵀ` below this fraction of the largest are
/// round-off of exactly redundant equations and dropped.
const NOISE_TOL: f64 = 1e-13;

/// The mass-weighted minimum-norm solution of `J x = r`: `x` minimises
/// `xᵀ M x` (`M = L Lᵀ`, `l` the lower Cholesky factor), `x = M⁻¹ Jᵀ y`
/// with `y = (J M⁻¹ Jᵀ)⁺ r`; and the numerical rank.
///
/// It goes through the SVD `J L⁻ᵀ = U Σ Vᵀ`: `x = L⁻ᵀ V Σ⁺ Uᵀ r`, one
/// division by each `σ` (the Schur complement's eigendecomposition divides
/// by `σ²` and needs the cut-off at `σ ≈ 1e-5 σ₁`). The pseudo-inverse is
/// damped (Tikhonov) with `μ = RANK_TOL σ₁`: `σ⁺ = σ / (σ² + μ²)`, so `x`
/// is continuous through a rank drop (the four-bar's change point, where
/// `Uᵀ r` and `σ` vanish together and their ratio is the finite
/// acceleration that keeps the branch) and equal to the exact solution to
/// `(μ/σ)²` away from it; singular values at round-off (`NOISE_TOL σ₁`,
/// exactly redundant equations) are dropped, which gives the minimum-norm
/// `y` there. The rank counts `σ > μ`.
pub fn weighted_min_norm(
    l: &DMatrix<f64>,
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    damping: f64,
) -> Option<(DVector<f64>, DVector<f64>, usize)> {
    let (m, n) = j.shape();
    if m == 0 || n == 0 {
        return Some((DVector::zeros(n), DVector::zeros(m), 0));
    }
    let at = l.solve_lower_triangular(&j.transpose())?;
    let svd = at.transpose().svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let s = &svd.singular_values;
    let largest = s.iter().copied().fold(0.0, f64::max);
    if !(largest > 0.0 && largest.is_finite()) {
        return Some((DVector::zeros(n), DVector::zeros(m), 0));
    }
    let mu = damping.max(RANK_TOL) * largest;
    let mu4 = mu.powi(4);
    let mut w = DVector::zeros(n);
    let mut y = DVector::zeros(m);
    let mut rank = 0;
    for (k, &sk) in s.iter().enumerate() {
        if sk > RANK_TOL * largest {
            rank += 1;
        }
        if sk <= NOISE_TOL * largest {
            continue;
        }
        let c = u.column(k).dot(r);
        let s2 = sk * sk;
        let den = s2 * s2 + mu4;
        w += vt.row(k).transpose() * (c * sk * s2 / den);
        y += u.column(k) * (c * s2 / den);
    }
    let x = l.tr_solve_lower_triangular(&w)?;
    (x.iter().chain(y.iter()).all(|v| v.is_finite())).then_some((x, y, rank))
}

/// `min ½ xᵀMx − fᵀx` subject to `J x = r` by the augmented Lagrangian
/// iteration of [`Method::AugmentedLagrangian`]: `x` and `λ` (`M x = f +
/// Jᵀλ`), or `None` if `M + αJᵀJ` is not positive definite. With `f = 0`
/// it is the mass-orthogonal projection `x = M⁻¹Jᵀ(JM⁻¹Jᵀ)⁻¹r`. Each
/// iteration contracts the error along an eigenvector of `J M⁻¹ Jᵀ` with
/// eigenvalue `e` by `1/(1 + αe)`: at once where `J` is regular, and not
/// at all in a direction that a rank drop of `J` takes away (the four-bar's
/// change point), so `x` stays bounded and continuous through it.
pub fn al_solve(
    m: &DMatrix<f64>,
    f: &DVector<f64>,
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    penalty: f64,
    iterations: usize,
) -> Option<(DVector<f64>, DVector<f64>)> {
    al_iterate(m, f, j, r, penalty, iterations).map(|(x, lambda, _)| (x, lambda))
}

/// [`al_solve`], and whether `J x = r` was reached to round-off within
/// `iterations`.
fn al_iterate(
    m: &DMatrix<f64>,
    f: &DVector<f64>,
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    penalty: f64,
    iterations: usize,
) -> Option<(DVector<f64>, DVector<f64>, bool)> {
    let (nc, nu) = j.shape();
    let mut lambda = DVector::zeros(nc);
    if nc == 0 {
        return Some((m.clone().cholesky()?.solve(f), lambda, true));
    }
    let jtj = j.transpose() * j;
    let mmax = m.diagonal().iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let jmax = jtj.diagonal().iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let alpha = if jmax > 0.0 {
        penalty * mmax / jmax
    } else {
        0.0
    };
    let chol = (m + &jtj * alpha).cholesky()?;
    let scale = max_abs(r.iter()).max(f64::MIN_POSITIVE);
    let mut x = DVector::zeros(nu);
    for _ in 0..iterations.max(1) {
        let rhs = f + j.transpose() * (&lambda + r * alpha);
        x = chol.solve(&rhs);
        let res = r - j * &x;
        lambda += &res * alpha;
        let xs = max_abs(x.iter());
        if max_abs(res.iter()) <= 1e-15 * (scale + jmax.sqrt() * xs) {
            return Some((x, lambda, true));
        }
    }
    Some((x, lambda, false))
}

/// A consistent state near a guess.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// Positions with `Φ(q, t) = 0`.
    pub q: Vec<f64>,
    /// Speeds with `J u + Φ_t = 0`.
    pub u: Vec<f64>,
    /// `max |Φ|` reached.
    pub residual: f64,
    /// `max |J u + Φ_t|` reached.
    pub velocity_residual: f64,
    /// Newton iterations on the positions.
    pub iterations: usize,
}

fn max_abs<'a>(v: impl IntoIterator<Item = &'a f64>) -> f64 {
    v.into_iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Assembly: Newton with minimum-norm steps and backtracking onto the
/// holonomic equations `Φ = 0`, then the smallest change of the speeds that
/// satisfies every speed equation `J u + Φ_t = 0`.
pub fn assemble<D: Assemble + ?Sized>(d: &D, q0: &[f64], u0: &[f64], t: f64) -> Assembly {
    let (nu, nh) = (d.speeds(), d.holonomic());
    let mut c = ConstraintValues::zeros(d.equations(), nu);
    let zero = vec![0.0; nu];
    let mut q = q0.to_vec();
    d.unit_quaternions(&mut q);
    let holonomic_residual = |q: &[f64], c: &mut ConstraintValues| {
        d.closure(t, q, &zero, c);
        max_abs(c.phi.iter().take(nh))
    };
    let mut residual = holonomic_residual(&q, &mut c);
    let mut iterations = 0;
    let mut dq = vec![0.0; q.len()];
    while residual > 1e-13 && iterations < 50 {
        iterations += 1;
        let jh = c.jacobian.rows(0, nh).into_owned();
        let minus_phi = -c.phi.rows(0, nh).into_owned();
        let (du, _) = min_norm_solve(&jh, &minus_phi);
        d.rates(&q, du.as_slice(), &mut dq);
        let mut step = 1.0;
        let mut improved = false;
        while step > 1e-6 {
            let mut trial: Vec<f64> = q.iter().zip(&dq).map(|(q, d)| q + step * d).collect();
            d.unit_quaternions(&mut trial);
            let r = holonomic_residual(&trial, &mut c);
            if r < residual {
                q = trial;
                residual = r;
                improved = true;
                break;
            }
            step /= 2.0;
        }
        if !improved {
            break;
        }
    }
    d.closure(t, &q, u0, &mut c);
    let (du, _) = min_norm_solve(&c.jacobian, &-c.phidot.clone());
    let u: Vec<f64> = u0.iter().zip(du.iter()).map(|(u, d)| u + d).collect();
    d.closure(t, &q, &u, &mut c);
    Assembly {
        velocity_residual: max_abs(c.phidot.iter()),
        residual: max_abs(c.phi.iter().take(nh)),
        q,
        u,
        iterations,
    }
}

/// A choice of dependent speeds: `rows` of `J` solved for the speeds
/// `cols` (Wehage–Haug), with the pivot ratio it was chosen at.
#[derive(Clone, Debug, Default)]
struct Partition {
    rows: Vec<usize>,
    cols: Vec<usize>,
    quality: f64,
}

/// Gaussian elimination with complete pivoting on `a`: the pivot rows and
/// columns in order of elimination (the numerical rank many of them, pivots
/// below `1e-10` of the first dropped) and `min |pivot| / max |pivot|`.
fn complete_pivoting(a: &DMatrix<f64>) -> Partition {
    let mut a = a.clone();
    let (m, n) = a.shape();
    let mut rows: Vec<usize> = (0..m).collect();
    let mut cols: Vec<usize> = (0..n).collect();
    let mut first = 0.0;
    let mut smallest = f64::INFINITY;
    let mut rank = 0;
    for k in 0..m.min(n) {
        let (mut pi, mut pj, mut best) = (k, k, 0.0);
        for i in k..m {
            for j in k..n {
                if a[(i, j)].abs() > best {
                    (pi, pj, best) = (i, j, a[(i, j)].abs());
                }
            }
        }
        if k == 0 {
            first = best;
        }
        if best <= 1e-10 * first || best == 0.0 {
            break;
        }
        a.swap_rows(k, pi);
        a.swap_columns(k, pj);
        rows.swap(k, pi);
        cols.swap(k, pj);
        for i in k + 1..m {
            let f = a[(i, k)] / a[(k, k)];
            for j in k..n {
                a[(i, j)] -= f * a[(k, j)];
            }
        }
        smallest = smallest.min(best);
        rank += 1;
    }
    rows.truncate(rank);
    cols.truncate(rank);
    Partition {
        rows,
        cols,
        quality: if rank == 0 { 1.0 } else { smallest / first },
    }
}

/// `min |pivot| / max |pivot|` of `J[rows, cols]` by partial pivoting.
fn pivot_quality(j: &DMatrix<f64>, p: &Partition) -> f64 {
    let r = p.rows.len();
    let sub = DMatrix::from_fn(r, r, |a, b| j[(p.rows[a], p.cols[b])]);
    let lu = sub.lu();
    let d = lu.u().diagonal();
    let largest = max_abs(d.iter());
    let smallest = d.iter().fold(f64::INFINITY, |m, x| m.min(x.abs()));
    if r == 0 {
        1.0
    } else {
        smallest / largest.max(1e-300)
    }
}

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

/// [`al_solve`] where its iteration converges; where it does not within
/// `iterations` (near a rank drop of `J`, the only place: the error along
/// an eigenvector of `J M⁻¹ Jᵀ` with eigenvalue `e` contracts by
/// `1/(1 + αe)` per iteration, `e → 0` there), the damped mass-weighted
/// minimum-norm solve ([`weighted_min_norm`], `damping`) instead.
///
/// The truncated iteration is itself a regularisation of the vanishing
/// direction, with the filter `1 − (1 + ασ²)^{−k}` in place of Tikhonov's
/// `σ²/(σ² + μ²)`; its window is wide (`σ² ≲ 35/(kα)`, about 4e-3 σ₁ with
/// the defaults) and its edge steep, and it left the four-bar's crank with
/// an error of about 1e-8 rad that did not fall with the tolerance
/// (issue 16; no choice of penalty and iteration count from 20 to 1000
/// removed it). `None` if `M` (or `M + αJᵀJ`) is not positive definite.
fn al_or_weighted(
    m: &DMatrix<f64>,
    f: &DVector<f64>,
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    (penalty, iterations): (f64, usize),
    damping: f64,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let (x, lambda, converged) = al_iterate(m, f, j, r, penalty, iterations)?;
    if converged {
        return Some((x, lambda));
    }
    let chol = m.clone().cholesky()?;
    let free = chol.solve(f);
    let rhs = r - j * &free;
    let (x, lambda, _) = weighted_min_norm(&chol.l(), j, &rhs, damping)?;
    Some((free + x, lambda))
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

/// `σ_r / σ_1` of `J M^{-1/2}` at `(t, q)`, `r` the rank at the first state
/// asked about (kept in `start_rank`); 1 without constraints, 0 where `M`
/// is not positive definite.
fn weighted_singular_ratio<D: Dynamics + ?Sized>(
    d: &D,
    t: f64,
    q: &[f64],
    start_rank: &std::cell::Cell<Option<usize>>,
) -> f64 {
    let (nu, nc) = (d.nu(), d.nc());
    let mut m = DMatrix::zeros(nu, nu);
    let mut c = ConstraintValues::zeros(nc, nu);
    d.mass_matrix(t, q, &mut m);
    d.constraints(t, q, &vec![0.0; nu], &mut c);
    let Some(l) = m.cholesky().map(|c| c.l()) else {
        return 0.0;
    };
    let Some(at) = l.solve_lower_triangular(&c.jacobian.transpose()) else {
        return 0.0;
    };
    let sigma = singular_values(&at);
    let r = match start_rank.get() {
        Some(r) => r,
        None => {
            let r = numerical_rank(&sigma);
            start_rank.set(Some(r));
            r
        }
    };
    match (r, sigma.first()) {
        (0, _) | (_, None) => 1.0,
        (r, Some(&s1)) => sigma.get(r - 1).copied().unwrap_or(0.0) / s1.max(f64::MIN_POSITIVE),
    }
}

/// [`Method::Index3`] refuses to go on when `σ_r/σ_1` of `J M^{-1/2}` falls
/// below this at an accepted state: near a rank drop of `J` the index-3
/// DAE's multipliers are undetermined along the vanishing direction, and
/// RADAU5 either crosses to another motion (the four-bar at loose
/// tolerances: energy off by 3e-4) or its Newton iteration fails (at
/// tight ones).
pub const INDEX3_SINGULAR_LIMIT: f64 = 5e-2;

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
    /// [`Index3System`]).
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
    /// [`Self::project_mass_orthogonal`], each step by [`al_solve`].
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

/// The index-3 DAE `q̇ = N(q) u`, `u̇ = M⁻¹(Jᵀλ − b)`, `0 = Φ(q, t)` (and
/// `0 = Φ̇` for nonholonomic rows) for [`Radau5`](crate::Radau5) with the
/// mass matrix `diag(I, I, 0)`, on `y = (q, u, λ_nonholonomic, λ_holonomic)`;
/// `N = n_q + n_u + m`. Set the integrator's index variables with
/// [`Index3System::index_vars`]. Redundant equations make its Newton
/// matrix singular: use a multiplier method for them.
pub struct Index3System<'a, D: ?Sized> {
    d: &'a D,
    stats: Recorder,
    start_rank: std::cell::Cell<Option<usize>>,
}

impl<'a, D: Dynamics + ?Sized> Index3System<'a, D> {
    /// The DAE of `d`.
    pub fn new(d: &'a D) -> Self {
        Index3System {
            d,
            stats: Recorder::new(),
            start_rank: std::cell::Cell::new(None),
        }
    }

    /// Why the run was stopped, if the DAE refused to go on (near a
    /// singular configuration, see [`INDEX3_SINGULAR_LIMIT`]).
    pub fn refusal(&self) -> Option<Refusal> {
        self.stats.0.borrow().0.refusal.clone()
    }

    /// (index-2 variables, index-3 variables) for
    /// [`Radau5::index2_vars`](crate::Radau5::index2_vars) and
    /// [`Radau5::index3_vars`](crate::Radau5::index3_vars).
    pub fn index_vars(&self) -> (usize, usize) {
        let (nu, nc, nh) = (self.d.nu(), self.d.nc(), self.d.n_holonomic());
        let speeds = if nh > 0 { nu } else { 0 };
        (speeds + nc - nh, nh)
    }

    /// The initial state `(q, u, λ)` from a consistent `(q, u)`, with `λ`
    /// from the multipliers; `None` if `N` is not `n_q + n_u + m` or `M` is
    /// singular.
    pub fn initial<const N: usize>(&self, t: f64, q: &[f64], u: &[f64]) -> Option<[f64; N]> {
        let (nq, nu, nc, nh) = (self.d.nq(), self.d.nu(), self.d.nc(), self.d.n_holonomic());
        if N != nq + nu + nc {
            return None;
        }
        let sys = ConstrainedSystem::new(self.d, Method::Projection);
        let (_, lambda) = sys.accelerations(t, q, u)?;
        let mut y = [0.0; N];
        y[..nq].copy_from_slice(q.get(..nq)?);
        y[nq..nq + nu].copy_from_slice(u.get(..nu)?);
        for (k, l) in lambda.iter().enumerate() {
            y[self.slot(k, nq + nu, nc, nh)] = *l;
        }
        Some(y)
    }

    /// Where `λ_k` sits in `y`.
    fn slot(&self, k: usize, base: usize, nc: usize, nh: usize) -> usize {
        if k < nh {
            base + nc - nh + k
        } else {
            base + k - nh
        }
    }

    /// `λ` in the model's equation order from a state.
    pub fn multipliers<const N: usize>(&self, y: &[f64; N]) -> Vec<f64> {
        let (nq, nu, nc, nh) = (self.d.nq(), self.d.nu(), self.d.nc(), self.d.n_holonomic());
        (0..nc)
            .map(|k| {
                y.get(self.slot(k, nq + nu, nc, nh))
                    .copied()
                    .unwrap_or(f64::NAN)
            })
            .collect()
    }

    /// What was seen along the run so far.
    pub fn stats(&self) -> ConstraintStats {
        self.stats.stats()
    }
}

impl<const N: usize, D: Dynamics + ?Sized> OdeSystem<N> for Index3System<'_, D> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        if self.stats.0.borrow().0.refusal.is_some() {
            // Refused (see `project`): the run stops here.
            dy.iter_mut().for_each(|d| *d = f64::NAN);
            return;
        }
        let d = self.d;
        let (nq, nu, nc, nh) = (d.nq(), d.nu(), d.nc(), d.n_holonomic());
        let q = &y[..nq];
        let u = &y[nq..nq + nu];
        let lambda = DVector::from_iterator(nc, self.multipliers(y));
        let mut m = DMatrix::zeros(nu, nu);
        let mut b = DVector::zeros(nu);
        let mut c = ConstraintValues::zeros(nc, nu);
        d.mass_matrix(t, q, &mut m);
        d.bias(t, q, u, &mut b);
        d.constraints(t, q, u, &mut c);
        d.qdot(q, u, &mut dy[..nq]);
        let force = c.jacobian.transpose() * lambda - b;
        match m.cholesky() {
            Some(chol) => {
                let a = chol.solve(&force);
                dy[nq..nq + nu]
                    .iter_mut()
                    .zip(a.iter())
                    .for_each(|(d, s)| *d = *s);
            }
            None => dy[nq..nq + nu].iter_mut().for_each(|d| *d = f64::NAN),
        }
        for k in 0..nc {
            let residual = if k < nh { c.phi[k] } else { c.phidot[k] };
            dy[self.slot(k, nq + nu, nc, nh)] = residual;
        }
    }

    fn mass_matrix(&self, m: &mut SMatrix<f64, N, N>) -> bool {
        let n = self.d.nq() + self.d.nu();
        m.fill(0.0);
        for i in 0..n.min(N) {
            m[(i, i)] = 1.0;
        }
        true
    }

    fn project(&self, t: f64, y: &mut [f64; N]) -> bool {
        let d = self.d;
        let (nq, nu) = (d.nq(), d.nu());
        d.normalize(&mut y[..nq]);
        let mut c = ConstraintValues::zeros(d.nc(), nu);
        d.constraints(t, &y[..nq], &y[nq..nq + nu], &mut c);
        self.stats.record(d.n_holonomic(), &c);
        if d.nc() > 0 && self.stats.0.borrow().0.refusal.is_none() {
            let ratio = weighted_singular_ratio(d, t, &y[..nq], &self.start_rank);
            if ratio < INDEX3_SINGULAR_LIMIT {
                self.stats.0.borrow_mut().0.refusal = Some(Refusal::SingularConfiguration {
                    method: "index3",
                    t,
                    singular_ratio: ratio,
                    recommended: "projection or partitioning",
                });
            }
        }
        !d.quaternions().is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Settings, SolveOptions, StopReason, solve};

    /// A point mass on a massless rod of length `L` in the vertical plane,
    /// in Cartesian coordinates: `Φ = (x² + y² − L²)/2`, `J = (x, y)`,
    /// `γ = −(ẋ² + ẏ²)`; the same motion as `θ̈ = −(g/L) sin θ`.
    struct CartesianPendulum;

    const G: f64 = 9.81;
    const L: f64 = 1.5;

    impl Dynamics for CartesianPendulum {
        fn nq(&self) -> usize {
            2
        }
        fn nu(&self) -> usize {
            2
        }
        fn nc(&self) -> usize {
            1
        }
        fn n_holonomic(&self) -> usize {
            1
        }
        fn quaternions(&self) -> &[usize] {
            &[]
        }
        fn qdot(&self, _q: &[f64], u: &[f64], qdot: &mut [f64]) {
            qdot.copy_from_slice(u);
        }
        fn mass_matrix(&self, _t: f64, _q: &[f64], m: &mut DMatrix<f64>) {
            m.fill(0.0);
            m[(0, 0)] = 2.0;
            m[(1, 1)] = 2.0;
        }
        fn bias(&self, _t: f64, _q: &[f64], _u: &[f64], b: &mut DVector<f64>) {
            b[0] = 0.0;
            b[1] = 2.0 * G;
        }
        fn constraints(&self, _t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues) {
            c.phi[0] = (q[0] * q[0] + q[1] * q[1] - L * L) / 2.0;
            c.phidot[0] = q[0] * u[0] + q[1] * u[1];
            c.gamma[0] = -(u[0] * u[0] + u[1] * u[1]);
            c.jacobian[(0, 0)] = q[0];
            c.jacobian[(0, 1)] = q[1];
        }
    }

    fn angle_reference(theta0: f64, t_end: f64) -> f64 {
        let sys = crate::FnSystem(|_t: f64, y: &[f64; 2], dy: &mut [f64; 2]| {
            dy[0] = y[1];
            dy[1] = -(G / L) * y[0].sin();
        });
        let s = Settings {
            integrator: crate::Integrator::Dop853,
            rtol: 1e-13,
            atol: 1e-13,
            dt: 0.0,
            index_vars: (0, 0),
        };
        let sol = solve(
            &s,
            &sys,
            0.0,
            [theta0, 0.0],
            t_end,
            &SolveOptions::default(),
        );
        sol.y_final[0]
    }

    #[test]
    fn every_method_reproduces_the_pendulum() {
        // Released from 1 rad (x = L sin θ, y = −L cos θ) and run 3 s: the
        // angle atan2(x, −y) follows the pendulum equation integrated in θ.
        let theta0 = 1.0f64;
        let t_end = 3.0;
        let want = angle_reference(theta0, t_end);
        let (q0, u0) = ([L * theta0.sin(), -L * theta0.cos()], [0.0, 0.0]);
        let d = CartesianPendulum;
        let a = assemble(&d, &q0, &u0, 0.0);
        assert!(a.residual < 1e-15 && a.velocity_residual == 0.0);
        let settings = |integrator: &str| Settings {
            integrator: integrator.parse().expect("a known integrator"),
            rtol: 1e-11,
            atol: 1e-11,
            dt: 0.0,
            index_vars: (0, 0),
        };
        for method in [Method::BAUMGARTE, Method::Projection, Method::Partitioning] {
            let sys = ConstrainedSystem::new(&d, method);
            let y0 = [q0[0], q0[1], 0.0, 0.0];
            let sol = solve(
                &settings("dop853"),
                &sys,
                0.0,
                y0,
                t_end,
                &SolveOptions::default(),
            );
            assert_eq!(sol.stop, StopReason::Finished);
            let got = sol.y_final[0].atan2(-sol.y_final[1]);
            assert!(
                (got - want).abs() < 1e-8,
                "{method:?}: θ = {got}, want {want}"
            );
            let s = sys.stats();
            assert_eq!(s.rank, 1);
            if method != Method::BAUMGARTE {
                assert!(s.max_position_residual < 1e-12, "{method:?}: {s:?}");
            }
        }
        let dae = Index3System::new(&d);
        let y0: [f64; 5] = dae.initial(0.0, &q0, &u0).expect("initial");
        // At rest, the rod carries the weight's radial part: λ L = −m g cos θ0
        // with M u̇ = −b + Jᵀλ and J = (x, y) (so the rod force is λ (x, y)).
        assert!(
            (y0[4] * L + 2.0 * G * theta0.cos()).abs() < 1e-12,
            "λ0 = {}",
            y0[4]
        );
        let s = Settings {
            index_vars: dae.index_vars(),
            ..settings("radau5")
        };
        assert_eq!(dae.index_vars(), (2, 1));
        let sol = solve(&s, &dae, 0.0, y0, t_end, &SolveOptions::default());
        assert_eq!(sol.stop, StopReason::Finished);
        let got = sol.y_final[0].atan2(-sol.y_final[1]);
        assert!((got - want).abs() < 1e-7, "index-3: θ = {got}, want {want}");
    }

    #[test]
    fn fast_and_minimum_norm_multipliers_agree_and_redundancy_is_handled() {
        let m = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let force = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let j = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 0.0, 0.0, 1.0, -1.0]);
        let gamma = DVector::from_vec(vec![0.3, -0.7]);
        let (udot, lambda, rank) = accelerations(&m, &force, &j, &gamma).expect("solves");
        assert_eq!(rank, 2);
        // M u̇ = f + Jᵀλ and J u̇ = γ.
        assert!((&m * &udot - &force - j.transpose() * &lambda).norm() < 1e-13);
        assert!((&j * &udot - &gamma).norm() < 1e-13);
        // The same equations written twice (rank 2 of 3): the same motion,
        // and the multipliers split evenly (minimum norm).
        let j2 = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.0, 0.0, 1.0, -1.0, 1.0, 2.0, 0.0]);
        let g2 = DVector::from_vec(vec![0.3, -0.7, 0.3]);
        let (u2, l2, r2) = accelerations(&m, &force, &j2, &g2).expect("solves");
        assert_eq!(r2, 2);
        assert!((&u2 - &udot).norm() < 1e-12);
        assert!((l2[0] - l2[2]).abs() < 1e-12 && (l2[0] + l2[2] - lambda[0]).abs() < 1e-12);
    }

    #[test]
    fn complete_pivoting_finds_the_rank_and_a_regular_block() {
        // Row 2 = row 0 + row 1: rank 2; the chosen 2×2 block is regular.
        let a = DMatrix::from_row_slice(
            3,
            4,
            &[1.0, 0.0, 2.0, 0.0, 0.0, 3.0, 0.0, 1.0, 1.0, 3.0, 2.0, 1.0],
        );
        let p = complete_pivoting(&a);
        assert_eq!((p.rows.len(), p.cols.len()), (2, 2));
        let block = DMatrix::from_fn(2, 2, |i, k| a[(p.rows[i], p.cols[k])]);
        assert!(block.determinant().abs() > 1e-6, "{p:?}");
        assert!(pivot_quality(&a, &p) > 0.0 && p.quality > 0.0);
    }
}
