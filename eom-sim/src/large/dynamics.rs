//! Time integration of `M q̈ + f_int(q, q̇) = f_ext` for large structural
//! models (free coordinates, constant sparse `M`).
//!
//! - [`GeneralizedAlpha`]: Chung and Hulbert's generalized-α method (1993)
//!   in the form of Arnold and Brüls (2007), implicit, second order,
//!   numerical dissipation of the highest frequencies set by the spectral
//!   radius at infinity `ρ∞` (`ρ∞ = 1`: none, the trapezoidal rule /
//!   average acceleration, which keeps the energy of linear undamped
//!   systems exactly). Newton on the accelerations with the iteration
//!   matrix `S = M + γ' D + β' K` assembled sparse and factored by LU
//!   ([`super::sparse::AutoLu`]: banded when the pattern is, else sparse
//!   with the symbolic analysis reused); by default modified Newton (the factored
//!   matrix kept while the iteration contracts fast, [`AlphaOptions::reuse_matrix`]). **Fixed step**: no error estimate or
//!   step control; the user picks `h` and checks convergence by halving it
//!   (the tests do). A step whose Newton iteration fails stops the run
//!   with a typed error naming the time.
//! - [`integrate_rk4`]: the classical explicit Runge–Kutta method, fixed
//!   step, for non-stiff cases (soft structures, short runs); `M` factored
//!   once by sparse Cholesky.

use super::model::StructuralModel;
use super::sparse::{AutoLu, FaerCholesky, SparseMatrix, SparseSolver};
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

/// Settings of [`GeneralizedAlpha`].
#[derive(Clone, Debug)]
pub struct AlphaOptions {
    /// Step size.
    pub h: f64,
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
        /// The solver's message.
        reason: String,
    },
    /// The starting state violates the model's constraints (a cable end
    /// away from its marker).
    Inconsistent {
        /// Time.
        t: f64,
        /// Which constraints, by how much.
        reason: String,
    },
    /// The state became non-finite.
    NonFinite {
        /// Time.
        t: f64,
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
            DynamicsError::Inconsistent { t, reason } => {
                write!(f, "inconsistent start at t = {t}: {reason}")
            }
            DynamicsError::NonFinite { t } => write!(f, "the state became non-finite at t = {t}"),
        }
    }
}

impl std::error::Error for DynamicsError {}

/// Counters of a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DynamicsStats {
    /// Steps taken.
    pub steps: usize,
    /// Newton iterations in all.
    pub newton_iterations: usize,
    /// Numeric factorisations.
    pub factorizations: usize,
    /// Internal force evaluations (over all elements).
    pub force_evaluations: usize,
}

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// The generalized-α integrator with its state (accelerations and the
/// auxiliary acceleration variable carried between steps).
pub struct GeneralizedAlpha<'m> {
    model: &'m StructuralModel,
    opts: AlphaOptions,
    alpha_m: f64,
    alpha_f: f64,
    beta: f64,
    gamma: f64,
    state: State,
    /// True accelerations `q̈_n`.
    acc: Vec<f64>,
    /// Auxiliary accelerations `a_n`.
    aux: Vec<f64>,
    load: Vec<f64>,
    iteration: SparseMatrix,
    lu: AutoLu,
    have_matrix: bool,
    q_full: Vec<f64>,
    v_full: Vec<f64>,
    scratch: Vec<f64>,
    /// Counters.
    pub stats: DynamicsStats,
}

/// Consistent initial accelerations `M q̈ = f_ext − f_int(q, v)`.
fn initial_acceleration(
    model: &StructuralModel,
    q_full: &[f64],
    v_full: &[f64],
    load: &[f64],
) -> Result<Vec<f64>, String> {
    let n = model.n_free();
    let mut scratch = vec![0.0; model.n_full()];
    let mut f = vec![0.0; n];
    model.internal(q_full, v_full, &mut scratch, &mut f);
    let mut rhs: Vec<f64> = load.iter().zip(&f).map(|(a, b)| a - b).collect();
    let mut chol = FaerCholesky::default();
    chol.factor(model.mass()).map_err(|e| e.0)?;
    chol.solve(&mut rhs);
    Ok(rhs)
}

impl<'m> GeneralizedAlpha<'m> {
    /// Starts at `state` (free coordinates) with consistent accelerations.
    pub fn new(
        model: &'m StructuralModel,
        state: State,
        opts: AlphaOptions,
    ) -> Result<Self, DynamicsError> {
        let rho = opts.rho_inf.clamp(0.0, 1.0);
        let alpha_m = (2.0 * rho - 1.0) / (rho + 1.0);
        let alpha_f = rho / (rho + 1.0);
        let gamma = 0.5 + alpha_f - alpha_m;
        let beta = 0.25 * (gamma + 0.5).powi(2);
        let load = model.load_free();
        let q_full = model.expand(&state.q);
        let v_full = model.expand_rate(&state.v);
        let acc = initial_acceleration(model, &q_full, &v_full, &load)
            .map_err(|reason| DynamicsError::Singular { t: state.t, reason })?;
        Ok(GeneralizedAlpha {
            model,
            opts,
            alpha_m,
            alpha_f,
            beta,
            gamma,
            aux: acc.clone(),
            acc,
            load,
            iteration: SparseMatrix::zeros(model.pattern().clone()),
            lu: AutoLu::default(),
            have_matrix: false,
            q_full,
            v_full,
            scratch: vec![0.0; model.n_full()],
            state,
            stats: DynamicsStats::default(),
        })
    }

    /// The current state.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The current full coordinates.
    pub fn q_full(&self) -> &[f64] {
        &self.q_full
    }

    /// One step of size `h`. With [`AlphaOptions::reuse_matrix`], a step
    /// whose modified Newton iteration fails is retried with full Newton
    /// before the run stops.
    pub fn step(&mut self) -> Result<(), DynamicsError> {
        match self.try_step(false) {
            Err(DynamicsError::NewtonFailed { .. }) if self.opts.reuse_matrix => {
                self.try_step(true)
            }
            other => other,
        }
    }

    fn try_step(&mut self, always_refresh: bool) -> Result<(), DynamicsError> {
        let h = self.opts.h;
        let (am, af, beta, gamma) = (self.alpha_m, self.alpha_f, self.beta, self.gamma);
        let n = self.model.n_free();
        let t1 = self.state.t + h;
        // Predictor: q̈_{n+1} = q̈_n.
        let mut acc1 = self.acc.clone();
        let mut aux1: Vec<f64> = (0..n)
            .map(|i| (af * self.acc[i] + (1.0 - af) * acc1[i] - am * self.aux[i]) / (1.0 - am))
            .collect();
        let mut q1: Vec<f64> = (0..n)
            .map(|i| {
                self.state.q[i]
                    + h * self.state.v[i]
                    + h * h * ((0.5 - beta) * self.aux[i] + beta * aux1[i])
            })
            .collect();
        let mut v1: Vec<f64> = (0..n)
            .map(|i| self.state.v[i] + h * ((1.0 - gamma) * self.aux[i] + gamma * aux1[i]))
            .collect();
        let da = (1.0 - af) / (1.0 - am);
        let beta_p = h * h * beta * da;
        let gamma_p = h * gamma * da;
        let mut r = vec![0.0; n];
        let mut corrections = Vec::new();
        let mut converged = false;
        // Modified Newton: the factored iteration matrix is kept across
        // iterations and steps while each correction is at most a quarter
        // of the one before; otherwise (or on the first use) it is rebuilt.
        let mut refresh = always_refresh || !self.opts.reuse_matrix || !self.have_matrix;
        let mut fresh = false;
        for _ in 0..self.opts.max_iterations {
            self.model.expand_into(&q1, &mut self.q_full);
            self.model.expand_into(&v1, &mut self.v_full);
            // r = M q̈ + f_int(q, v) − f_ext.
            self.model
                .internal(&self.q_full, &self.v_full, &mut self.scratch, &mut r);
            self.stats.force_evaluations += 1;
            for (ri, fi) in r.iter_mut().zip(&self.load) {
                *ri -= fi;
            }
            self.model.mass().sym_mul_add(1.0, &acc1, &mut r);
            if refresh {
                self.model.jacobian(
                    &self.q_full,
                    &self.v_full,
                    beta_p,
                    gamma_p,
                    1.0,
                    &mut self.iteration,
                );
                if let Err(e) = self.lu.factor(&self.iteration) {
                    return Err(DynamicsError::Singular { t: t1, reason: e.0 });
                }
                self.stats.factorizations += 1;
                self.have_matrix = true;
                refresh = always_refresh || !self.opts.reuse_matrix;
                fresh = true;
            }
            self.lu.solve(&mut r);
            self.stats.newton_iterations += 1;
            for i in 0..n {
                let d = -r[i];
                acc1[i] += d;
                aux1[i] += da * d;
                q1[i] += beta_p * d;
                v1[i] += gamma_p * d;
            }
            let c = beta_p * norm_inf(&r);
            corrections.push(c);
            if !c.is_finite() {
                return Err(DynamicsError::NonFinite { t: t1 });
            }
            if c <= self.opts.tol * (1.0 + norm_inf(&q1)) {
                converged = true;
                break;
            }
            if let [.., before, last] = corrections[..]
                && last > 0.25 * before
                && !fresh
            {
                refresh = true;
            }
            fresh = false;
        }
        if !converged {
            return Err(DynamicsError::NewtonFailed { t: t1, corrections });
        }
        self.state.t = t1;
        self.state.q = q1;
        self.state.v = v1;
        self.acc = acc1;
        self.aux = aux1;
        self.model.expand_into(&self.state.q, &mut self.q_full);
        self.model.expand_into(&self.state.v, &mut self.v_full);
        self.stats.steps += 1;
        Ok(())
    }

    /// Steps until `t_end` (the last step lands on it to within `h/1000`;
    /// `t_end − t` should be a multiple of `h`), calling `observe` after
    /// every step.
    pub fn run_to(
        &mut self,
        t_end: f64,
        mut observe: impl FnMut(&State, &[f64]),
    ) -> Result<(), DynamicsError> {
        let steps = ((t_end - self.state.t) / self.opts.h - 1e-3)
            .ceil()
            .max(0.0) as usize;
        for _ in 0..steps {
            self.step()?;
            observe(&self.state, &self.q_full);
        }
        Ok(())
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
        .map_err(|e| DynamicsError::Singular {
            t: state.t,
            reason: e.0,
        })?;
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
