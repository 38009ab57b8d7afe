//! Static equilibrium of a [`MixedModel`]: rigid bodies and ANCF chains
//! joined by attachment constraints, solved by Newton on the KKT system
//! with load stepping (the frame shared with the structure alone,
//! [`super::super::statics::load_stepping`]).
//!
//! Unknowns `z = (x, q_r, λ)`: the structure's free coordinates, the rigid
//! part's coordinates and the attachment multipliers. At rest (`u = 0`)
//! the equations are
//!
//! ```text
//! f_int(x) − f_ext + Φ_xᵀ λ = 0
//! b(q_r, 0, t) + Φ_qᵀ λ = 0
//! Φ(x, q_r, t) = 0
//! ```
//!
//! (`b` of `M u̇ = τ − b`: at rest the rigid part's gravity, springs and
//! constant forces). Newton's matrix is `[[H, Φ_yᵀ], [Φ_y, 0]]` with
//! `H = ∂(f_int + Φ_xᵀλ, b + Φ_qᵀλ)/∂(x, q_r)`: the structure's exact
//! sparse tangent, the rigid block by forward differences as
//! [`super::MixedAlpha`] takes it, and the clamps' exact coupling terms.
//! The constraint rows and the multipliers' columns are scaled by the
//! largest diagonal entry of `H` so that the condition estimate measures
//! the stiffness, not the units.
//!
//! **Load stepping.** The load factor `s` goes from 0 to 1 in steps, each
//! solved by Newton from the secant extrapolation of the last two
//! equilibria, halved when Newton fails (as [`crate::large::solve_static`]).
//! At factor `s` the structure carries `s f_ext` (gravity, end forces, end
//! masses' weight) and the rigid part `b(q_r) − (1 − s) b(q_r⁰)`: its
//! force out of balance at the start is brought in with the same factor
//! (a Newton homotopy `F(z) − (1 − s) F(z⁰)`; for the structure, which
//! starts unstressed, that is exactly `f_int − s f_ext`).
//!
//! **Zero-stress modes.** A cable pinned at one end and free at the
//! other has no stiffness against swinging about the pin until it is in
//! tension: the first tangent is singular although the equilibrium is
//! not. When the tangent's condition estimate exceeds
//! [`StaticOptions::max_condition`], the step is taken with `H + μ M`
//! (pseudo-transient continuation, Kelley and Keyes 1998: a step of
//! implicit dynamics from rest, `M` the mass matrix of structure and rigid
//! part) with `μ` falling in proportion to the residual, and Newton
//! resumes as soon as the tangent is regular. Such steps are counted in
//! [`MixedStaticSolution::regularized`].
//!
//! **Mechanisms.** At the converged equilibrium the tangent without
//! regularisation must be regular: a rigid part that can move without
//! any force resisting it (a cart on a frictionless rail, a pendulum
//! whose axis is along gravity) has a singular tangent there, and the
//! solve refuses with [`MixedStaticError::Mechanism`] and the direction
//! that moves freely.
//!
//! **Stability.** Newton converges to unstable equilibria as readily as
//! to stable ones. The solution carries the smallest eigenvalue `ω²` of
//! the tangent reduced to the motions the attachments allow, against the
//! mass matrix (`Zᵀ H Z v = ω² Zᵀ M Z v`, `Z` a basis of the null space of
//! `Φ_y`): the squared lowest angular frequency of small vibration about
//! the equilibrium, negative when the equilibrium is unstable (dense, up
//! to [`STABILITY_LIMIT`] unknowns).

use super::super::norm_inf;
use super::super::sparse::{FactorError, FaerLu, SparseMatrix, SparseSolver};
use super::super::statics::{LoadStep, Newton, StaticOptions, load_stepping};
use super::{ConstraintEval, MixedModel, RigidScratch};
use nalgebra::{DMatrix, SymmetricEigen};
use std::fmt;

/// Largest number of unknowns `(x, q_r)` whose stability is checked (a
/// dense eigenproblem).
pub const STABILITY_LIMIT: usize = 1500;

/// The largest change of a rigid coordinate in one Newton iteration (rad
/// or m): larger corrections are scaled down as a whole.
pub const MAX_RIGID_STEP: f64 = 0.5;

/// Whether an equilibrium is stable.
#[derive(Clone, Debug, PartialEq)]
pub enum Stability {
    /// Every eigenvalue of the reduced tangent is positive.
    Stable {
        /// The smallest `ω²`, 1/s².
        omega2_min: f64,
    },
    /// Some eigenvalue is negative: a small disturbance grows.
    Unstable {
        /// The smallest `ω²`, 1/s².
        omega2_min: f64,
        /// How many are negative.
        negative: usize,
    },
    /// Not checked (too many unknowns, or a singular mass matrix).
    NotChecked {
        /// Why not.
        reason: Unchecked,
    },
}

/// Why the stability of an equilibrium was not checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unchecked {
    /// More unknowns than the dense eigenvalue problem takes.
    TooLarge {
        /// Unknowns.
        unknowns: usize,
        /// The limit.
        limit: usize,
    },
    /// The tangent or the mass matrix holds a non-finite entry.
    NonFinite,
    /// The mass matrix on the allowed motions is not positive definite.
    MassNotPositive,
    /// The mass matrix is singular.
    MassSingular,
}

impl fmt::Display for Unchecked {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Unchecked::TooLarge { unknowns, limit } => {
                write!(f, "{unknowns} unknowns, more than the dense limit {limit}")
            }
            Unchecked::NonFinite => f.write_str("the tangent is not finite"),
            Unchecked::MassNotPositive => {
                f.write_str("the mass matrix on the allowed motions is not positive definite")
            }
            Unchecked::MassSingular => f.write_str("the mass matrix is singular"),
        }
    }
}

impl fmt::Display for Stability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stability::Stable { omega2_min } => write!(
                f,
                "stable (smallest ω² of the reduced tangent {omega2_min:.6e} 1/s², lowest frequency {:.6e} Hz)",
                omega2_min.sqrt() / std::f64::consts::TAU
            ),
            Stability::Unstable {
                omega2_min,
                negative,
            } => write!(
                f,
                "UNSTABLE ({negative} negative eigenvalue(s) of the reduced tangent, smallest ω² {omega2_min:.6e} 1/s²): a small disturbance moves the system away"
            ),
            Stability::NotChecked { reason } => write!(
                f,
                "stability not checked ({reason}); the equilibrium may be unstable"
            ),
        }
    }
}

/// A static solution of a mixed model.
#[derive(Clone, Debug)]
pub struct MixedStaticSolution {
    /// `(x, q_r)`: the structure's free coordinates, then the rigid part's
    /// (the layout of [`MixedModel::initial_state`]'s `q`).
    pub y: Vec<f64>,
    /// The structure's full coordinates.
    pub q_full: Vec<f64>,
    /// The attachment multipliers `λ`.
    pub lambda: Vec<f64>,
    /// The accepted load steps in order; each step's residuals are the
    /// force rows' `‖r‖∞` (structure and rigid part).
    pub steps: Vec<LoadStep>,
    /// Load steps that failed and were halved.
    pub cuts: usize,
    /// Numeric factorisations of the KKT matrix.
    pub factorizations: usize,
    /// Newton steps taken with `H + μ M` because `H` was singular.
    pub regularized: usize,
    /// `‖Φ‖∞` at the solution.
    pub constraint_residual: f64,
    /// Condition estimate of the scaled KKT matrix at the solution.
    pub condition: f64,
    /// Stability of the equilibrium.
    pub stability: Stability,
}

impl MixedStaticSolution {
    /// The force each mount applies to its cable end, world axes (`−λ` of
    /// the position rows; `z = 0` when planar), in the order of
    /// [`MixedModel::attachments`].
    pub fn reactions(&self, model: &MixedModel<'_>) -> Vec<[f64; 3]> {
        model.mount_forces(&self.lambda)
    }
}

/// Why a mixed static solve gave up.
#[derive(Clone, Debug, PartialEq)]
pub enum MixedStaticError {
    /// The rigid start has the wrong number of coordinates.
    StartSize {
        /// Coordinates given.
        given: usize,
        /// The rigid part's coordinates.
        needed: usize,
    },
    /// The attachments do not hold at the start (a cable end away from
    /// its marker, a clamped end's tangent off the clamp's axis).
    StartOpen {
        /// `‖Φ‖∞` there.
        residual: f64,
    },
    /// Newton did not converge at the smallest load step allowed.
    NoConvergence {
        /// Last load factor reached in equilibrium.
        lambda_reached: f64,
        /// Load factor tried.
        lambda_tried: f64,
        /// Residual history of the last attempt.
        residuals: Vec<f64>,
        /// Regularised steps of the last attempt (a singular tangent).
        regularized: usize,
    },
    /// The KKT matrix could not be factored even with regularisation.
    Singular {
        /// Load factor tried.
        lambda: f64,
        /// The factorisation's failure at the last regularisation tried
        /// (`None`: it factored, but too ill-conditioned).
        factor: Option<FactorError>,
        /// The last condition estimate (NaN where it did not factor).
        condition: f64,
    },
    /// The equilibrium reached is not isolated: the tangent is singular
    /// there (a mechanism).
    Mechanism {
        /// The condition estimate.
        condition: f64,
        /// The direction of `(x, q_r)` that moves without force (unit
        /// length): the null vector of the tangent.
        direction: Vec<f64>,
        /// Structural free coordinates (the first entries of `direction`).
        n_structural: usize,
    },
    /// The equilibrium found goes through contacts, which statics does not
    /// hold: each with its gap (negative; NaN where it could not be
    /// evaluated).
    Penetrated(Vec<(String, f64)>),
}

impl MixedStaticError {
    /// For [`MixedStaticError::Mechanism`]: the rigid coordinates that the
    /// free direction moves, by index into `q_r`, with their share of
    /// the direction, largest first; empty if only the structure moves.
    pub fn free_rigid_coordinates(&self) -> Vec<(usize, f64)> {
        let MixedStaticError::Mechanism {
            direction,
            n_structural,
            ..
        } = self
        else {
            return Vec::new();
        };
        let mut out: Vec<(usize, f64)> = direction[*n_structural..]
            .iter()
            .enumerate()
            .filter(|(_, v)| v.abs() > 1e-3)
            .map(|(i, v)| (i, *v))
            .collect();
        out.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        out
    }
}

impl fmt::Display for MixedStaticError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MixedStaticError::Penetrated(through) => {
                f.write_str(&crate::large::statics::penetrated_message(through))
            }
            MixedStaticError::StartSize { given, needed } => {
                write!(f, "the rigid part has {needed} coordinates, not {given}")
            }
            MixedStaticError::StartOpen { residual } => write!(
                f,
                "the attachments do not hold at the start (|Φ|∞ = {residual:.3e}): put each cable end at its marker, with a clamped end's tangent along the clamp's axis"
            ),
            MixedStaticError::NoConvergence {
                lambda_reached,
                lambda_tried,
                residuals,
                regularized,
            } => {
                write!(
                    f,
                    "Newton did not converge: equilibrium reached up to load factor {lambda_reached}, \
                     the step to {lambda_tried} failed after halving (residuals {:?})",
                    residuals
                        .iter()
                        .map(|r| format!("{r:.3e}"))
                        .collect::<Vec<_>>()
                )?;
                if *regularized > 0 {
                    write!(
                        f,
                        "; the tangent was singular in {regularized} of its iterations \
                         (a cable not yet in tension, or a mechanism: a part that nothing holds \
                         under a load that pushes it); try more iterations or load steps, \
                         or hold the part by a spring or a support"
                    )
                } else {
                    f.write_str("; try more load steps or check the supports")
                }
            }
            MixedStaticError::Singular {
                lambda,
                factor,
                condition,
            } => {
                let reason = match factor {
                    Some(e) => e.to_string(),
                    None => format!("condition estimate {condition:.1e}"),
                };
                write!(
                    f,
                    "the KKT matrix is singular at load factor {lambda} even with regularisation ({reason}): \
                     are the rigid part and the cables held against free motion?"
                )
            }
            MixedStaticError::Mechanism {
                condition,
                direction,
                n_structural,
            } => {
                let rigid: Vec<String> = self
                    .free_rigid_coordinates()
                    .iter()
                    .map(|(i, v)| format!("rigid coordinate {i} ({v:+.3})"))
                    .collect();
                let cable = norm_inf(&direction[..*n_structural]);
                write!(
                    f,
                    "the equilibrium is not isolated: the tangent is singular there (condition estimate {condition:.1e}), \
                     a mechanism moves without any force resisting it"
                )?;
                if rigid.is_empty() {
                    write!(f, " (the cable alone, largest component {cable:.3})")?;
                } else {
                    write!(f, ": the free direction moves {}", rigid.join(", "))?;
                }
                f.write_str(
                    "; hold it by a spring or a support, or give it a load that it must balance",
                )
            }
        }
    }
}

impl std::error::Error for MixedStaticError {}

/// The KKT system of the statics at one load factor.
struct Kkt<'a, 'r> {
    model: &'a MixedModel<'r>,
    t: f64,
    /// `f_ext` on the free coordinates.
    load: Vec<f64>,
    /// `f_int(x⁰)` (zero for an unstressed start).
    f0: Vec<f64>,
    /// `b(q_r⁰, 0)`.
    b0: Vec<f64>,
    s_matrix: SparseMatrix,
    matrix: SparseMatrix,
    lu: FaerLu,
    q_full: Vec<f64>,
    zero_full: Vec<f64>,
    scratch: Vec<f64>,
    rs: RigidScratch,
    /// Scale of the constraint rows and multiplier columns.
    sigma: f64,
}

impl<'a, 'r> Kkt<'a, 'r> {
    fn new(model: &'a MixedModel<'r>, t: f64) -> Self {
        let st = &model.structure;
        let (n_s, n_r) = (model.n_s, model.n_r);
        Kkt {
            model,
            t,
            load: st.load_free(),
            f0: vec![0.0; n_s],
            b0: vec![0.0; n_r],
            s_matrix: SparseMatrix::zeros(st.pattern().clone()),
            matrix: SparseMatrix::zeros(model.pattern.clone()),
            lu: FaerLu::default(),
            q_full: st.q0().to_vec(),
            zero_full: vec![0.0; st.n_full()],
            scratch: vec![0.0; st.n_full()],
            rs: RigidScratch {
                mass: vec![0.0; n_r * n_r],
                mounts: vec![0.0; model.buffer_len()],
                c: ConstraintEval::default(),
            },
            sigma: 1.0,
        }
    }

    fn sizes(&self) -> (usize, usize, usize, usize) {
        let m = self.model;
        (m.n_s, m.n_r, m.n_s + m.n_r, m.m)
    }

    /// `r = (f_int − s f_ext − (1−s) f_int⁰ + Φ_xᵀλ, b − (1−s) b⁰ + Φ_qᵀλ, Φ)`.
    fn residual(&mut self, z: &[f64], s: f64, r: &mut [f64]) {
        let (n_s, n_r, n, m) = self.sizes();
        let model = self.model;
        model.structure.expand_into(&z[..n_s], &mut self.q_full);
        let mut f = vec![0.0; n_s];
        model
            .structure
            .internal(&self.q_full, &self.zero_full, &mut self.scratch, &mut f);
        for i in 0..n_s {
            r[i] = f[i] - s * self.load[i] - (1.0 - s) * self.f0[i];
        }
        let zeros = vec![0.0; n_r];
        let mut rr = vec![0.0; n_r];
        model.rigid_residual(
            self.t,
            &self.q_full,
            &z[n_s..n],
            &zeros,
            &zeros,
            &z[n..],
            &mut self.rs,
            &mut rr,
        );
        for i in 0..n_r {
            r[n_s + i] = rr[i] - (1.0 - s) * self.b0[i];
        }
        let c = &self.rs.c;
        for &(row, col, v) in &c.jac {
            if col < n_s {
                r[col] += v * z[n + row];
            }
        }
        r[n..n + m].copy_from_slice(&c.phi);
    }

    /// Builds `[[H + μ M, σ Φ_yᵀ], [σ Φ_y, 0]]` at `z` (after
    /// [`Kkt::residual`] at `z`, which left `q_full` there) and factors it.
    fn assemble(&mut self, z: &[f64], mu: f64) -> Result<(), FactorError> {
        let (n_s, n_r, n, _) = self.sizes();
        let model = self.model;
        let lambda = &z[n..];
        self.matrix.clear();
        model.structure.jacobian(
            &self.q_full,
            &self.zero_full,
            1.0,
            0.0,
            mu,
            &mut self.s_matrix,
        );
        for (k, &slot) in model.s_map.iter().enumerate() {
            if slot != usize::MAX {
                self.matrix.values[slot] += self.s_matrix.values[k];
            }
        }
        // Rigid block: ∂(b + Φ_qᵀλ)/∂q_r by forward differences, + μ M_r.
        let q_r = &z[n_s..n];
        let zeros = vec![0.0; n_r];
        let mut g0 = vec![0.0; n_r];
        let mut g1 = vec![0.0; n_r];
        model.rigid_residual(
            self.t,
            &self.q_full,
            q_r,
            &zeros,
            &zeros,
            lambda,
            &mut self.rs,
            &mut g0,
        );
        let mass = self.rs.mass.clone();
        let mut qp = q_r.to_vec();
        for j in 0..n_r {
            let e = 1e-7 * (1.0 + q_r[j].abs());
            qp[j] = q_r[j] + e;
            model.rigid_residual(
                self.t,
                &self.q_full,
                &qp,
                &zeros,
                &zeros,
                lambda,
                &mut self.rs,
                &mut g1,
            );
            qp[j] = q_r[j];
            for i in 0..n_r {
                let v = (g1[i] - g0[i]) / e + mu * mass[i * n_r + j];
                if let Some(s) = model.pattern.slot(n_s + i, n_s + j) {
                    self.matrix.values[s] += v;
                }
            }
        }
        // The scale of the constraint rows: the largest diagonal of H.
        self.sigma = (0..n)
            .filter_map(|i| model.pattern.slot(i, i))
            .map(|s| self.matrix.values[s].abs())
            .fold(0.0, f64::max)
            .max(1.0);
        let mut c = std::mem::take(&mut self.rs.c);
        model.constraints(self.t, &self.q_full, q_r, &mut self.rs.mounts, &mut c);
        for &(row, col, val) in &c.jac {
            for (i, j) in [(n + row, col), (col, n + row)] {
                if let Some(s) = model.pattern.slot(i, j) {
                    self.matrix.values[s] += self.sigma * val;
                }
            }
        }
        for &(row, gi, qj, d) in &c.cross {
            let v = lambda[row] * d;
            for (i, j) in [(gi, qj), (qj, gi)] {
                if let Some(s) = model.pattern.slot(i, j) {
                    self.matrix.values[s] += v;
                }
            }
        }
        self.rs.c = c;
        self.lu.factor(&self.matrix)
    }

    /// Solves the factored system for the Newton correction of `z` from
    /// the residual `r` (in place).
    fn solve(&self, r: &mut [f64]) {
        let n = self.model.n();
        for v in &mut r[n..] {
            *v *= self.sigma;
        }
        self.lu.solve(r);
        for v in &mut r[n..] {
            *v *= self.sigma;
        }
    }

    /// `‖A‖∞ ‖A⁻¹‖₂`-estimate of the factored matrix by inverse iteration,
    /// and the last iterate (the direction `A` stretches least).
    fn condition(&self) -> (f64, Vec<f64>) {
        let k = &self.matrix;
        let size = k.pattern().n();
        let mut row_sums = vec![0.0; size];
        let ones = vec![1.0; size];
        let mut abs = k.clone();
        abs.values.iter_mut().for_each(|v| *v = v.abs());
        abs.mul_add(1.0, &ones, &mut row_sums);
        let knorm = norm_inf(&row_sums);
        let mut x: Vec<f64> = (0..size)
            .map(|i| 1.0 + ((i * 7919) % 13) as f64 / 13.0)
            .collect();
        let mut growth = 0.0;
        for _ in 0..8 {
            let nx = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            x.iter_mut().for_each(|v| *v /= nx);
            self.lu.solve(&mut x);
            growth = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            if !growth.is_finite() {
                return (f64::INFINITY, x);
            }
        }
        let nx = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        x.iter_mut().for_each(|v| *v /= nx);
        (knorm * growth, x)
    }

    /// The smallest `ω²` of `Zᵀ H Z v = ω² Zᵀ M Z v` from the factored
    /// (unregularised) matrix at the solution `z`.
    fn stability(&self, z: &[f64]) -> Stability {
        let (n_s, n_r, n, m) = self.sizes();
        if n > STABILITY_LIMIT {
            return Stability::NotChecked {
                reason: Unchecked::TooLarge {
                    unknowns: n,
                    limit: STABILITY_LIMIT,
                },
            };
        }
        let mut h = DMatrix::<f64>::zeros(n, n);
        let mut a = DMatrix::<f64>::zeros(m, n);
        for (i, j, s) in self.model.pattern.entries() {
            let v = self.matrix.values[s];
            if i < n && j < n {
                h[(i, j)] = v;
            } else if i >= n && j < n {
                a[(i - n, j)] = v / self.sigma;
            }
        }
        let h = (&h + h.transpose()) * 0.5;
        let mut mass = DMatrix::<f64>::zeros(n, n);
        for (i, j, s) in self.model.structure.mass().pattern().entries() {
            mass[(i, j)] = self.model.structure.mass().values[s];
        }
        let mut mr = vec![0.0; n_r * n_r];
        self.model.rigid.mass_matrix(self.t, &z[n_s..n], &mut mr);
        for i in 0..n_r {
            for j in 0..n_r {
                mass[(n_s + i, n_s + j)] = 0.5 * (mr[i * n_r + j] + mr[j * n_r + i]);
            }
        }
        if h.iter()
            .chain(mass.iter())
            .chain(a.iter())
            .any(|v| !v.is_finite())
        {
            return Stability::NotChecked {
                reason: Unchecked::NonFinite,
            };
        }
        // Z: eigenvectors of AᵀA with zero eigenvalues.
        let ata = a.transpose() * &a;
        let eig = SymmetricEigen::new(ata);
        let top = eig.eigenvalues.iter().fold(0.0_f64, |x, v| x.max(v.abs()));
        let null: Vec<usize> = (0..n)
            .filter(|&i| eig.eigenvalues[i] <= 1e-10 * top.max(f64::MIN_POSITIVE))
            .collect();
        let mut zb = DMatrix::<f64>::zeros(n, null.len());
        for (c, &i) in null.iter().enumerate() {
            zb.set_column(c, &eig.eigenvectors.column(i));
        }
        let hr = zb.transpose() * &h * &zb;
        let mr = zb.transpose() * &mass * &zb;
        let Some(chol) = mr.clone().cholesky() else {
            return Stability::NotChecked {
                reason: Unchecked::MassNotPositive,
            };
        };
        let l = chol.l();
        // C = L⁻¹ Hr L⁻ᵀ.
        let Some(x) = l.solve_lower_triangular(&hr) else {
            return Stability::NotChecked {
                reason: Unchecked::MassSingular,
            };
        };
        let Some(ct) = l.solve_lower_triangular(&x.transpose()) else {
            return Stability::NotChecked {
                reason: Unchecked::MassSingular,
            };
        };
        let c = (&ct + ct.transpose()) * 0.5;
        let w = SymmetricEigen::new(c).eigenvalues;
        let big = w.iter().fold(0.0_f64, |x, v| x.max(v.abs()));
        let omega2_min = w.iter().copied().fold(f64::INFINITY, f64::min);
        // Round-off in the eigenvalues is about ε ‖C‖; the rigid block's
        // forward differences are far below any physical ω².
        let negative = w.iter().filter(|&&v| v < -1e-12 * big).count();
        if negative > 0 {
            Stability::Unstable {
                omega2_min,
                negative,
            }
        } else {
            Stability::Stable { omega2_min }
        }
    }
}

/// Solves the static equilibrium of `model` at time `t` from the
/// structure's reference and the rigid coordinates `q_r0` (the cable ends
/// must be at their markers there).
pub fn solve_static_mixed(
    model: &MixedModel<'_>,
    t: f64,
    q_r0: &[f64],
    opts: &StaticOptions,
) -> Result<MixedStaticSolution, MixedStaticError> {
    let (n_s, n_r, m) = (model.n_s, model.n_r, model.m);
    let n = n_s + n_r;
    if q_r0.len() != n_r {
        return Err(MixedStaticError::StartSize {
            given: q_r0.len(),
            needed: n_r,
        });
    }
    let st = &model.structure;
    let mut z = st.restrict(st.q0());
    z.extend_from_slice(q_r0);
    z.extend(std::iter::repeat_n(0.0, m));
    let phi0 = model.constraint_residual(t, &z[..n]);
    let worst = norm_inf(&phi0);
    if worst.is_nan() || worst > 1e-8 {
        return Err(MixedStaticError::StartOpen { residual: worst });
    }
    let mut kkt = Kkt::new(model, t);
    // F(z⁰): the structure's internal forces and the rigid part's bias at
    // the start (λ = 0).
    let mut r = vec![0.0; n + m];
    kkt.residual(&z, 0.0, &mut r);
    kkt.f0.copy_from_slice(&r[..n_s]);
    kkt.b0.copy_from_slice(&r[n_s..n]);
    let force_scale = norm_inf(&kkt.load)
        .max(norm_inf(&kkt.f0))
        .max(norm_inf(&kkt.b0));
    let mass_scale = {
        let mut mr = vec![0.0; n_r * n_r];
        model.rigid.mass_matrix(t, q_r0, &mut mr);
        let diag = (0..n_r).map(|i| mr[i * n_r + i].abs()).fold(0.0, f64::max);
        st.mass()
            .pattern()
            .entries()
            .filter(|(i, j, _)| i == j)
            .map(|(_, _, s)| st.mass().values[s].abs())
            .fold(diag, f64::max)
            .max(f64::MIN_POSITIVE)
    };
    let mut regularized_total = 0usize;
    let newton = |target: f64, zt: &mut Vec<f64>| {
        let base_tol = opts.rtol * target * force_scale + opts.atol;
        let mut tol = base_tol;
        let mut residuals = Vec::new();
        let mut converged = false;
        let mut mu = 0.0_f64;
        let mut regularized = 0usize;
        for it in 0..=opts.max_iterations {
            kkt.residual(zt, target, &mut r);
            let rn = norm_inf(&r[..n]);
            let cn = norm_inf(&r[n..]);
            let ctol = opts.rtol * (1.0 + norm_inf(&zt[..n])) + 1e-14;
            residuals.push(rn);
            if !(rn.is_finite() && cn.is_finite()) {
                break;
            }
            if rn <= tol && cn <= ctol {
                converged = true;
                break;
            }
            if it == opts.max_iterations {
                break;
            }
            let regular = kkt.assemble(zt, 0.0).is_ok() && {
                let (cond, _) = kkt.condition();
                cond.is_finite() && cond < opts.max_condition
            };
            tol = base_tol + 4.0 * f64::EPSILON * kkt.sigma * norm_inf(&zt[..n]);
            if regular {
                mu = 0.0;
            } else {
                // Pseudo-transient continuation: μ from the stiffness and
                // mass scales, then falling with the residual.
                mu = if mu > 0.0 {
                    let before = residuals[residuals.len() - 2];
                    mu * (rn / before).clamp(1e-3, 1e3)
                } else {
                    1e-4 * kkt.sigma / mass_scale
                };
                let mut ok = false;
                let (mut factor, mut condition) = (None, f64::NAN);
                for _ in 0..6 {
                    match kkt.assemble(zt, mu) {
                        Ok(()) => {
                            let (cond, _) = kkt.condition();
                            if cond.is_finite() && cond < opts.max_condition {
                                ok = true;
                                break;
                            }
                            (factor, condition) = (None, cond);
                        }
                        Err(e) => (factor, condition) = (Some(e), f64::NAN),
                    }
                    mu *= 100.0;
                }
                if !ok {
                    return Err(MixedStaticError::Singular {
                        lambda: target,
                        factor,
                        condition,
                    });
                }
                regularized += 1;
            }
            kkt.solve(&mut r);
            // A rigid coordinate moves at most `MAX_RIGID_STEP` per
            // iteration (the whole correction scaled): far from
            // equilibrium Newton's linearisation of the rigid part's
            // trigonometry would otherwise throw it around several turns.
            let big = norm_inf(&r[n_s..n]);
            let scale = if big > MAX_RIGID_STEP {
                MAX_RIGID_STEP / big
            } else {
                1.0
            };
            for (a, d) in zt.iter_mut().zip(&r) {
                *a -= scale * d;
            }
        }
        regularized_total += regularized;
        Ok(if converged {
            Newton::Converged {
                tolerance: tol,
                residuals,
            }
        } else {
            Newton::Failed((residuals, regularized))
        })
    };
    let (steps, cuts) = load_stepping(opts, &mut z, newton, |at, (residuals, regularized)| {
        MixedStaticError::NoConvergence {
            lambda_reached: at.lambda_reached,
            lambda_tried: at.lambda_tried,
            residuals,
            regularized,
        }
    })?;
    // The unregularised tangent at the solution: regular, or a mechanism.
    kkt.residual(&z, 1.0, &mut r);
    let constraint_residual = norm_inf(&r[n..]);
    let factored = kkt.assemble(&z, 0.0);
    let (condition, direction) = if factored.is_ok() {
        kkt.condition()
    } else {
        (f64::INFINITY, vec![0.0; n + m])
    };
    if !(condition.is_finite() && condition < opts.max_condition) {
        // An exactly singular matrix gives no direction: inverse iteration
        // with a slightly regularised one (H + μ M, μ at 1e-10 of the
        // stiffness over the mass) finds the motion of least stiffness.
        let mut direction = direction;
        if !direction.iter().all(|v| v.is_finite()) || norm_inf(&direction[..n]) == 0.0 {
            let mu = 1e-10 * kkt.sigma / mass_scale;
            if kkt.assemble(&z, mu).is_ok() {
                direction = kkt.condition().1;
            }
        }
        let mut d: Vec<f64> = direction[..n]
            .iter()
            .map(|v| if v.is_finite() { *v } else { 0.0 })
            .collect();
        let nd = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        if nd > 0.0 && nd.is_finite() {
            d.iter_mut().for_each(|v| *v /= nd);
        }
        return Err(MixedStaticError::Mechanism {
            condition,
            direction: d,
            n_structural: n_s,
        });
    }
    let stability = kkt.stability(&z);
    let factorizations = kkt.lu.factorizations();
    let q_full = st.expand(&z[..n_s]);
    let lambda_out = z[n..].to_vec();
    z.truncate(n);
    Ok(MixedStaticSolution {
        y: z,
        q_full,
        lambda: lambda_out,
        steps,
        cuts,
        factorizations,
        regularized: regularized_total,
        constraint_residual,
        condition,
        stability,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::large::ancf::{ChainSpec, Section, Support, chain};
    use crate::large::{MixedModel, RigidPart};

    /// A link on a torsion spring, pivoted at the origin, the clamp's axis
    /// along it (as in the integration tests).
    struct Link;

    impl RigidPart for Link {
        fn n(&self) -> usize {
            1
        }
        fn mass_matrix(&self, _t: f64, _q: &[f64], m: &mut [f64]) {
            m[0] = 0.1;
        }
        fn bias(&self, _t: f64, q: &[f64], _u: &[f64], b: &mut [f64]) {
            b[0] = 2.0 * q[0].cos() + 20.0 * q[0];
        }
        fn energy(&self, _t: f64, _q: &[f64], _u: &[f64]) -> f64 {
            0.0
        }
        fn attachments(&self, _t: f64, q: &[f64], out: &mut [f64]) {
            let (s, c) = q[0].sin_cos();
            let a = 0.5;
            out.copy_from_slice(&[
                a * c,
                -a * s,
                a * s,
                a * c,
                0.0,
                0.0,
                -s,
                -c,
                c,
                -s,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                1.0,
                0.0,
            ]);
        }
    }

    /// The assembled `[[H, σ Φ_yᵀ], [σ Φ_y, 0]]` against central
    /// differences of the residual, at a state off equilibrium with
    /// nonzero multipliers: the structure's tangent, the rigid block, the
    /// constraint Jacobian and the clamp's coupling terms.
    #[test]
    fn the_kkt_matrix_is_the_residuals_jacobian() {
        let spec = ChainSpec {
            kernel: crate::elements::Element::Cable2D,
            start: [0.5, 0.0, 0.0],
            end: [1.0, 0.0, 0.0],
            elements: 2,
            section: Section {
                e: 1e7,
                rho: 7800.0,
                area: 4e-4,
                inertia: 1.3e-8,
                ..Section::default()
            },
            start_support: Support::Free,
            end_support: Support::Free,
            end_force: [0.0; 3],
            end_mass: 0.0,
            gravity: [0.0, -9.81, 0.0],
        };
        let ch = chain(&spec).unwrap_or_else(|e| panic!("{e}"));
        let at = ch.attachment("rod.start", false, true);
        let model =
            MixedModel::new(ch.model, Box::new(Link), vec![at]).unwrap_or_else(|e| panic!("{e}"));
        let (n, m) = (model.n(), model.n_constraints());
        let mut kkt = Kkt::new(&model, 0.0);
        let mut z = model.structure().restrict(model.structure().q0());
        z.push(0.3);
        z.extend([5.0, -7.0, 3.0]);
        for (i, v) in z.iter_mut().enumerate().take(n - 1) {
            *v += 1e-2 * ((i * 37 % 11) as f64 / 11.0 - 0.5);
        }
        let mut r = vec![0.0; n + m];
        kkt.residual(&z, 0.7, &mut r);
        kkt.assemble(&z, 0.0).unwrap_or_else(|e| panic!("{e}"));
        let sigma = kkt.sigma;
        let mut worst = 0.0_f64;
        let mut rp = vec![0.0; n + m];
        let mut rm = vec![0.0; n + m];
        for j in 0..n + m {
            let h = 1e-6;
            let mut zp = z.clone();
            zp[j] += h;
            kkt.residual(&zp, 0.7, &mut rp);
            zp[j] -= 2.0 * h;
            kkt.residual(&zp, 0.7, &mut rm);
            for i in 0..n + m {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                let mut got = model
                    .pattern
                    .slot(i, j)
                    .map_or(0.0, |s| kkt.matrix.values[s]);
                if (i >= n) != (j >= n) {
                    got /= sigma;
                }
                if i >= n && j >= n {
                    continue;
                }
                let err = (got - fd).abs() / (1.0 + fd.abs());
                assert!(err < 1e-5, "({i}, {j}): matrix {got}, differences {fd}");
                worst = worst.max(err);
            }
        }
        println!("largest relative difference {worst:.2e}");
    }
}
