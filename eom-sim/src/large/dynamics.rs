//! Time integration of `M q̈ + f_int(q, q̇) = f_ext` for large structural
//! models (free coordinates, constant sparse `M`): the run's types shared
//! by every vector model ([`State`], [`AlphaOptions`], [`DynamicsError`],
//! [`DynamicsStats`]), the structure's side of the generalized-α contract
//! ([`super::alpha::AlphaModel`]: the iteration matrix `M + γ' D + β' K`
//! assembled sparse and factored by LU, [`super::sparse::AutoLu`], banded
//! when the pattern is, else sparse with the symbolic analysis reused),
//! and [`integrate_rk4`], the classical explicit Runge–Kutta method, fixed
//! step, for non-stiff cases (soft structures, short runs), `M` factored
//! once by sparse Cholesky.

use super::alpha::{AlphaModel, StepControl};
use super::model::StructuralModel;
use super::sparse::{AutoLu, FactorError, FaerCholesky, SparseMatrix, SparseSolver};
use std::fmt;

/// A state on the free coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct State {
    /// Time.
    pub t: f64,
    /// Free coordinates.
    pub q: Vec<f64>,
    /// Free velocities.
    pub v: Vec<f64>,
}

/// Settings of [`super::GeneralizedAlpha`].
#[derive(Clone, Debug)]
pub struct AlphaOptions {
    /// Step size (with [`AlphaOptions::control`], the first step's).
    pub h: f64,
    /// Step-size control by a local error estimate; `None`: fixed step `h`.
    pub control: Option<StepControl>,
    /// Spectral radius at infinite frequency, in `[0, 1]`.
    pub rho_inf: f64,
    /// Newton iterations per step.
    pub max_iterations: usize,
    /// Newton stops when the position correction `‖β' Δq̈‖∞ ≤ tol · (1 + ‖q‖∞)`.
    pub tol: f64,
    /// Modified Newton: keep the factored iteration matrix across
    /// iterations and steps, rebuilding it when a correction is more than
    /// a quarter of the one before (and retrying a failed step with full
    /// Newton) (the element Jacobians cost about 16
    /// force evaluations for the planar cable). `false`: full Newton.
    pub reuse_matrix: bool,
}

impl Default for AlphaOptions {
    fn default() -> Self {
        AlphaOptions {
            h: 1e-3,
            control: None,
            rho_inf: 1.0,
            max_iterations: 20,
            tol: 1e-10,
            reuse_matrix: true,
        }
    }
}

/// Why a run stopped early.
#[derive(Clone, Debug, PartialEq)]
pub enum DynamicsError {
    /// Newton did not converge within the iterations allowed.
    NewtonFailed {
        /// Time of the step that failed.
        t: f64,
        /// `‖β' Δq̈‖∞` per iteration.
        corrections: Vec<f64>,
    },
    /// A matrix could not be factored.
    Singular {
        /// Time.
        t: f64,
        /// The solver's reason.
        reason: FactorError,
    },
    /// The starting state violates the model's constraints (a cable end
    /// away from its marker, a rigid loop open or its speeds leaving it).
    Inconsistent {
        /// Time.
        t: f64,
        /// `‖Φ‖∞` at the start (0 where the positions hold and the speeds
        /// do not).
        residual: f64,
        /// Which constraints, by how much.
        violations: Vec<Violation>,
    },
    /// The state became non-finite.
    NonFinite {
        /// Time.
        t: f64,
    },
    /// Step-size control needed a step below its smallest.
    StepTooSmall {
        /// Time of the last accepted step.
        t: f64,
        /// The step that was still too large.
        h: f64,
        /// Its error estimate (1 = the tolerance).
        error: f64,
    },
}

impl fmt::Display for DynamicsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DynamicsError::NewtonFailed { t, corrections } => write!(
                f,
                "Newton failed at t = {t} (corrections {:?}); take a smaller step",
                corrections
                    .iter()
                    .map(|c| format!("{c:.2e}"))
                    .collect::<Vec<_>>()
            ),
            DynamicsError::Singular { t, reason } => {
                write!(f, "singular matrix at t = {t}: {reason}")
            }
            DynamicsError::Inconsistent {
                t,
                residual,
                violations,
            } => {
                write!(f, "inconsistent start at t = {t}: ")?;
                let speeds: Vec<String> = violations
                    .iter()
                    .filter_map(|v| match v {
                        Violation::RigidSpeed { constraint, rate } => {
                            Some(format!("`{constraint}` changes at {rate:.3e}/s"))
                        }
                        _ => None,
                    })
                    .collect();
                let positions: Vec<String> = violations
                    .iter()
                    .filter(|v| !matches!(v, Violation::RigidSpeed { .. }))
                    .map(|v| v.to_string())
                    .collect();
                if !positions.is_empty() || speeds.is_empty() {
                    write!(
                        f,
                        "the constraints do not hold at the start (|Φ|∞ = {residual:.3e}): {}",
                        positions.join("; ")
                    )?;
                }
                if !speeds.is_empty() {
                    write!(
                        f,
                        "the rigid part's speeds leave its loop at the start: {} (give speeds with J u + Φ_t = 0, e.g. from `eom_gen::cables::rigid_start`)",
                        speeds.join(", ")
                    )?;
                }
                Ok(())
            }
            DynamicsError::NonFinite { t } => write!(f, "the state became non-finite at t = {t}"),
            DynamicsError::StepTooSmall { t, h, error } => write!(
                f,
                "step size {h:.1e} s still too large at t = {t} (error estimate {error:.1e} of the tolerance); loosen --rtol/--atol or check the model"
            ),
        }
    }
}

impl std::error::Error for DynamicsError {}

/// One constraint that does not hold at a start.
#[derive(Clone, Debug, PartialEq)]
pub enum Violation {
    /// A cable end away from its marker.
    Gap {
        /// The attachment.
        attachment: String,
        /// The distance, m.
        gap: f64,
    },
    /// A clamped end's tangent off the clamp's axis.
    ClampAxis {
        /// The attachment.
        attachment: String,
    },
    /// A rigid part's own constraint off (its loop not closed).
    RigidPosition {
        /// The constraint's name.
        constraint: String,
        /// Its value.
        value: f64,
    },
    /// A rigid part's speeds leaving its loop: `dΦ_r/dt ≠ 0`.
    RigidSpeed {
        /// The constraint's name.
        constraint: String,
        /// `dΦ/dt`.
        rate: f64,
    },
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Violation::Gap { attachment, gap } => {
                write!(f, "`{attachment}` is {gap:.3e} m from its marker")
            }
            Violation::ClampAxis { attachment } => {
                write!(f, "`{attachment}`'s tangent is off the clamp's axis")
            }
            Violation::RigidPosition { constraint, value } => write!(
                f,
                "the rigid part's constraint `{constraint}` is {value:.3e} off (the loop is not closed: assemble the rigid part first, e.g. `eom_gen::cables::rigid_start`)"
            ),
            Violation::RigidSpeed { constraint, rate } => {
                write!(f, "`{constraint}` changes at {rate:.3e}/s")
            }
        }
    }
}

/// Counters of a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DynamicsStats {
    /// Steps taken (accepted).
    pub steps: usize,
    /// Steps rejected by the step-size control (error estimate above the
    /// tolerance, or Newton failing even with a fresh matrix).
    pub rejected: usize,
    /// Newton iterations in all.
    pub newton_iterations: usize,
    /// Numeric factorisations.
    pub factorizations: usize,
    /// Internal force evaluations (over all elements).
    pub force_evaluations: usize,
    /// Largest `‖Φ‖∞` after a step (0 without constraints; m, and for
    /// clamps the sine of the tangent's angle off the axis times `|r'|`;
    /// a rigid part's own equations in their units).
    pub max_constraint_residual: f64,
}

/// The structure's scratch for [`super::GeneralizedAlpha`]: the load, the
/// iteration matrix and its LU, the expanded coordinates.
pub struct StructuralWork {
    load: Vec<f64>,
    iteration: SparseMatrix,
    lu: AutoLu,
    q_full: Vec<f64>,
    v_full: Vec<f64>,
    scratch: Vec<f64>,
}

/// Consistent initial accelerations `M q̈ = f_ext − f_int(q, v)`.
fn initial_acceleration(
    model: &StructuralModel,
    q_full: &[f64],
    v_full: &[f64],
    load: &[f64],
) -> Result<Vec<f64>, FactorError> {
    let n = model.n_free();
    let mut scratch = vec![0.0; model.n_full()];
    let mut f = vec![0.0; n];
    model.internal(q_full, v_full, &mut scratch, &mut f);
    let mut rhs: Vec<f64> = load.iter().zip(&f).map(|(a, b)| a - b).collect();
    let mut chol = FaerCholesky::default();
    chol.factor(model.mass())?;
    chol.solve(&mut rhs);
    Ok(rhs)
}

/// A structure alone: `M q̈ + f_int(q, q̇) − f_ext = 0` on the free
/// coordinates, no constraint rows.
impl AlphaModel for StructuralModel {
    type Work = StructuralWork;

    fn n(&self) -> usize {
        self.n_free()
    }

    fn n_constraints(&self) -> usize {
        0
    }

    fn work(&self, state: &State) -> StructuralWork {
        StructuralWork {
            load: self.load_free(),
            iteration: SparseMatrix::zeros(self.pattern().clone()),
            lu: AutoLu::default(),
            q_full: self.expand(&state.q),
            v_full: self.expand_rate(&state.v),
            scratch: vec![0.0; self.n_full()],
        }
    }

    fn start(
        &self,
        w: &mut StructuralWork,
        state: &State,
        acc: &mut [f64],
        _lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let a = initial_acceleration(self, &w.q_full, &w.v_full, &w.load)
            .map_err(|reason| DynamicsError::Singular { t: state.t, reason })?;
        acc.copy_from_slice(&a);
        Ok(())
    }

    fn residual(
        &self,
        w: &mut StructuralWork,
        _t: f64,
        y: &[f64],
        v: &[f64],
        acc: &[f64],
        _lambda: &[f64],
        r: &mut [f64],
    ) {
        self.expand_into(y, &mut w.q_full);
        self.expand_into(v, &mut w.v_full);
        // r = M q̈ + f_int(q, v) − f_ext.
        self.internal(&w.q_full, &w.v_full, &mut w.scratch, r);
        for (ri, fi) in r.iter_mut().zip(&w.load) {
            *ri -= fi;
        }
        self.mass().sym_mul_add(1.0, acc, r);
    }

    fn factor(
        &self,
        w: &mut StructuralWork,
        t: f64,
        _y: &[f64],
        _v: &[f64],
        _acc: &[f64],
        _lambda: &[f64],
        bp: f64,
        gp: f64,
    ) -> Result<(), DynamicsError> {
        self.jacobian(&w.q_full, &w.v_full, bp, gp, 1.0, &mut w.iteration);
        w.lu.factor(&w.iteration)
            .map_err(|reason| DynamicsError::Singular { t, reason })
    }

    fn solve(&self, w: &mut StructuralWork, r: &mut [f64]) {
        w.lu.solve(r);
    }

    fn accepted(&self, w: &mut StructuralWork, state: &State) -> f64 {
        self.expand_into(&state.q, &mut w.q_full);
        self.expand_into(&state.v, &mut w.v_full);
        0.0
    }

    fn full<'w>(&self, w: &'w StructuralWork) -> &'w [f64] {
        &w.q_full
    }
}

/// Fixed-step classical Runge–Kutta (order 4) from `state` to `t_end` in
/// `steps` steps, `M` factored once (sparse Cholesky); `observe` after every
/// step gets the state and the full coordinates.
pub fn integrate_rk4(
    model: &StructuralModel,
    mut state: State,
    t_end: f64,
    steps: usize,
    mut observe: impl FnMut(&State, &[f64]),
) -> Result<(State, DynamicsStats), DynamicsError> {
    let n = model.n_free();
    let mut chol = FaerCholesky::default();
    chol.factor(model.mass())
        .map_err(|reason| DynamicsError::Singular { t: state.t, reason })?;
    let load = model.load_free();
    let mut q_full = model.expand(&state.q);
    let mut v_full = model.expand_rate(&state.v);
    let mut scratch = vec![0.0; model.n_full()];
    let mut f = vec![0.0; n];
    let mut stats = DynamicsStats {
        factorizations: 1,
        ..DynamicsStats::default()
    };
    let h = (t_end - state.t) / steps.max(1) as f64;
    let mut accel = |q: &[f64], v: &[f64], out: &mut Vec<f64>, stats: &mut DynamicsStats| {
        model.expand_into(q, &mut q_full);
        model.expand_into(v, &mut v_full);
        model.internal(&q_full, &v_full, &mut scratch, &mut f);
        stats.force_evaluations += 1;
        out.clear();
        out.extend(load.iter().zip(&f).map(|(a, b)| a - b));
        chol.solve(out);
    };
    let (mut a1, mut a2, mut a3, mut a4) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let axpy = |x: &[f64], a: f64, y: &[f64]| -> Vec<f64> {
        x.iter().zip(y).map(|(u, w)| u + a * w).collect()
    };
    for _ in 0..steps {
        let (q, v) = (&state.q, &state.v);
        accel(q, v, &mut a1, &mut stats);
        let v1 = v.clone();
        let q2 = axpy(q, 0.5 * h, &v1);
        let v2 = axpy(v, 0.5 * h, &a1);
        accel(&q2, &v2, &mut a2, &mut stats);
        let q3 = axpy(q, 0.5 * h, &v2);
        let v3 = axpy(v, 0.5 * h, &a2);
        accel(&q3, &v3, &mut a3, &mut stats);
        let q4 = axpy(q, h, &v3);
        let v4 = axpy(v, h, &a3);
        accel(&q4, &v4, &mut a4, &mut stats);
        let mut qn = q.clone();
        let mut vn = v.clone();
        for i in 0..n {
            qn[i] += h / 6.0 * (v1[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            vn[i] += h / 6.0 * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i]);
        }
        if qn.iter().chain(&vn).any(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite { t: state.t + h });
        }
        state.q = qn;
        state.v = vn;
        state.t += h;
        stats.steps += 1;
        let qf = model.expand(&state.q);
        observe(&state, &qf);
    }
    Ok((state, stats))
}
