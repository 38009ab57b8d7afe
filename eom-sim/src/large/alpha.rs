//! Generalized-α (Chung and Hulbert 1993, in the form of Arnold and Brüls
//! 2007), written once for every model whose state is a vector: a
//! structure of elements alone ([`super::StructuralModel`]) and rigid parts
//! carrying cables ([`super::MixedModel`]), through [`AlphaModel`].
//!
//! The equations are `M ÿ + f(t, y, ẏ) − f_ext + Φ_yᵀ λ = 0`,
//! `Φ(t, y) = 0` (index 3; without constraints `Φ` has no rows). Each step
//! solves for the accelerations and multipliers by Newton with the
//! iteration matrix `[[M + γ' D + β' K, Φ_yᵀ], [Φ_y, 0]]` (the constraint
//! rows scaled by `1/β'`), by default modified Newton: the factored matrix
//! kept while each correction is at most a quarter of the one before, a
//! failed step retried once with full Newton.
//!
//! **Step size.** Fixed ([`AlphaOptions::h`]) or, with
//! [`AlphaOptions::control`], adaptive: the local error of the positions
//! is estimated from the change of the auxiliary accelerations,
//! `e = h² (β − 1/6 + (α_m − α_f)/2) (a_{n+1} − a_n)` (the `h³` term of the
//! position update against Taylor's series; for the trapezoidal rule,
//! `ρ∞ = 1`, it is Zienkiewicz and Xie's `h²/12 Δq̈`), measured in the
//! weighted RMS norm `atol + rtol |y|` as the explicit methods measure
//! theirs. A step with `‖e‖ > 1`, or whose Newton iteration fails even
//! with a fresh matrix, is rejected and retried smaller; the next step
//! grows or shrinks by `0.9 ‖e‖^{-1/3}` within `[0.2, 5]`.
//!
//! **Restarts.** Started at `a₀ = ÿ₀` ([`GeneralizedAlpha::new`]), the
//! method overshoots on a mode its step does not resolve that starts
//! displaced (`ÿ₀ = −ω² x₀`): for `ẍ = −ω² x` at `ρ∞ = 0.8` the energy
//! grows to 4.9 times its start at `ω h = 100`, 420 times at `ω h = 1000`,
//! before `ρ∞` damps it. A stiff cable just after an impact or a change of
//! its contacts starts so, and restarts there piled the overshoots up into
//! runs that gained hundreds of joules. [`GeneralizedAlpha::restarted`]
//! takes its first step by Newmark's rule with `β = ½`, `γ = 1` (`y₁ = y₀ +
//! h ẏ₀ + ½ h² ÿ₁`, `ẏ₁ = ẏ₀ + h ÿ₁`), which reads no auxiliary
//! accelerations: a stiff mode's energy after it is at most `4/(ω h)²` of
//! its start, the positions stay second order (local error `h³/3 ÿ⃛`,
//! which the error estimate above measures with `β = ½`, `α = 0`), the
//! speeds first order in that one step. Generalized-α goes on from it at
//! `a₁ = ÿ₁`, now on a stiff mode that starts at rest position and moves,
//! which does not overshoot. A step retaken from a state the integrator
//! reached resumes with what it carried there ([`GeneralizedAlpha::carried`],
//! [`GeneralizedAlpha::resume`]), so it is the step the run would take.

use super::norm_inf;
use super::run::{AlphaOptions, DynamicsError, DynamicsStats, State, StepControl};

/// A model whose state is a vector, as [`GeneralizedAlpha`] integrates it:
/// `n` coordinates `y` with speeds `ẏ`, `m` constraint equations.
///
/// The model keeps its run's scratch and factored matrix in
/// [`AlphaModel::Work`], made once per run, so a step allocates nothing
/// it does not return.
pub trait AlphaModel {
    /// Scratch of one run: expanded coordinates, matrices, the factorisation.
    type Work;
    /// Coordinates.
    fn n(&self) -> usize;
    /// Constraint equations (multipliers).
    fn n_constraints(&self) -> usize;
    /// The scratch for a run from `state`.
    fn work(&self, state: &State) -> Self::Work;
    /// Checks the starting state (constraints holding at position and
    /// speed level) and writes the consistent initial accelerations and
    /// multipliers.
    fn start(
        &self,
        w: &mut Self::Work,
        state: &State,
        acc: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError>;
    /// `r[..n] = M a + f(t, y, v) − f_ext + Φ_yᵀ λ` and `r[n..] = Φ(t, y)`
    /// (unscaled); leaves `(y, v)` expanded in `w` for [`AlphaModel::factor`].
    #[allow(clippy::too_many_arguments)]
    fn residual(
        &self,
        w: &mut Self::Work,
        t: f64,
        y: &[f64],
        v: &[f64],
        acc: &[f64],
        lambda: &[f64],
        r: &mut [f64],
    );
    /// Builds and factors the iteration matrix at the iterate the last
    /// [`AlphaModel::residual`] saw, with `β'` = `bp` and `γ'` = `gp`.
    #[allow(clippy::too_many_arguments)]
    fn factor(
        &self,
        w: &mut Self::Work,
        t: f64,
        y: &[f64],
        v: &[f64],
        acc: &[f64],
        lambda: &[f64],
        bp: f64,
        gp: f64,
    ) -> Result<(), DynamicsError>;
    /// Solves with the factored iteration matrix in place.
    fn solve(&self, w: &mut Self::Work, r: &mut [f64]);
    /// An accepted state: expands it in `w`, and returns `‖Φ‖∞` there.
    fn accepted(&self, w: &mut Self::Work, state: &State) -> f64;
    /// The full coordinates of the last accepted state (a structure's
    /// supported coordinates included), as observers read node positions.
    fn full<'w>(&self, w: &'w Self::Work) -> &'w [f64];
}

/// The generalized-α integrator on model `M`, with its state
/// (accelerations, the auxiliary accelerations and the multipliers carried
/// between steps).
pub struct GeneralizedAlpha<'m, M: AlphaModel + ?Sized> {
    model: &'m M,
    opts: AlphaOptions,
    alpha_m: f64,
    alpha_f: f64,
    beta: f64,
    gamma: f64,
    /// The step the next [`GeneralizedAlpha::step`] takes.
    h: f64,
    state: State,
    /// True accelerations `ÿ_n`.
    acc: Vec<f64>,
    /// Auxiliary accelerations `a_n`.
    aux: Vec<f64>,
    lambda: Vec<f64>,
    work: M::Work,
    /// The next step is a restart's first ([`Self::restarted`]).
    restart: bool,
    have_matrix: bool,
    /// The iteration matrix was factored for these `(β', γ')`.
    matrix_for: (f64, f64),
    /// Counters and the largest constraint residual.
    pub stats: DynamicsStats,
}

/// The coefficients `(α_m, α_f, β, γ)` for the spectral radius at infinity
/// `ρ∞` (clamped to `[0, 1]`): second order, unconditionally stable,
/// dissipation of the highest frequencies set by `ρ∞` alone.
pub fn coefficients(rho_inf: f64) -> (f64, f64, f64, f64) {
    let rho = rho_inf.clamp(0.0, 1.0);
    let alpha_m = (2.0 * rho - 1.0) / (rho + 1.0);
    let alpha_f = rho / (rho + 1.0);
    let gamma = 0.5 + alpha_f - alpha_m;
    let beta = 0.25 * (gamma + 0.5).powi(2);
    (alpha_m, alpha_f, beta, gamma)
}

/// What [`GeneralizedAlpha`] carries from one step to the next: the
/// state, the true and auxiliary accelerations, the multipliers, and
/// whether the next step is a restart's first. [`GeneralizedAlpha::resume`]
/// goes on from it.
#[derive(Clone, Debug)]
pub struct Carried {
    state: State,
    acc: Vec<f64>,
    aux: Vec<f64>,
    lambda: Vec<f64>,
    restart: bool,
}

impl Carried {
    /// The state carried.
    pub fn state(&self) -> &State {
        &self.state
    }
}

/// Newmark's `(α_m, α_f, β, γ)` of a restart's first step: `β = ½`, `γ = 1`
/// read none of the auxiliary accelerations carried into the step.
const RESTART: (f64, f64, f64, f64) = (0.0, 0.0, 0.5, 1.0);

/// The outcome of one attempted step.
struct Attempt {
    y: Vec<f64>,
    v: Vec<f64>,
    acc: Vec<f64>,
    aux: Vec<f64>,
}

impl<'m, M: AlphaModel + ?Sized> GeneralizedAlpha<'m, M> {
    /// Starts at `state` with consistent accelerations (and multipliers);
    /// refuses a start the model finds inconsistent.
    pub fn new(model: &'m M, state: State, opts: AlphaOptions) -> Result<Self, DynamicsError> {
        let (alpha_m, alpha_f, beta, gamma) = coefficients(opts.rho_inf);
        let (n, m) = (model.n(), model.n_constraints());
        let mut work = model.work(&state);
        let mut acc = vec![0.0; n];
        let mut lambda = vec![0.0; m];
        model.start(&mut work, &state, &mut acc, &mut lambda)?;
        let h = match opts.control {
            Some(c) => opts.h.clamp(c.h_min, c.h_max),
            None => opts.h,
        };
        Ok(GeneralizedAlpha {
            model,
            alpha_m,
            alpha_f,
            beta,
            gamma,
            h,
            aux: acc.clone(),
            acc,
            lambda,
            work,
            restart: false,
            have_matrix: false,
            matrix_for: (f64::NAN, f64::NAN),
            state,
            opts,
            stats: DynamicsStats::default(),
        })
    }

    /// [`Self::new`] at a state where the motion changed abruptly (after an
    /// impulse, or a contact taken or released): the first step is
    /// Newmark's `β = ½`, `γ = 1`, which does not excite the modes the step
    /// does not resolve (module documentation, "Restarts").
    pub fn restarted(
        model: &'m M,
        state: State,
        opts: AlphaOptions,
    ) -> Result<Self, DynamicsError> {
        let mut ga = Self::new(model, state, opts)?;
        ga.restart = true;
        Ok(ga)
    }

    /// What the integrator carries to its next step.
    pub fn carried(&self) -> Carried {
        Carried {
            state: self.state.clone(),
            acc: self.acc.clone(),
            aux: self.aux.clone(),
            lambda: self.lambda.clone(),
            restart: self.restart,
        }
    }

    /// Goes on from `c` (taken of an integrator on `model` with
    /// [`Self::carried`]) with options `opts`: the next step is the one that
    /// integrator would have taken at `opts.h`.
    pub fn resume(model: &'m M, c: Carried, opts: AlphaOptions) -> Self {
        let (alpha_m, alpha_f, beta, gamma) = coefficients(opts.rho_inf);
        let mut work = model.work(&c.state);
        model.accepted(&mut work, &c.state);
        let h = match opts.control {
            Some(ctl) => opts.h.clamp(ctl.h_min, ctl.h_max),
            None => opts.h,
        };
        GeneralizedAlpha {
            model,
            alpha_m,
            alpha_f,
            beta,
            gamma,
            h,
            acc: c.acc,
            aux: c.aux,
            lambda: c.lambda,
            work,
            restart: c.restart,
            have_matrix: false,
            matrix_for: (f64::NAN, f64::NAN),
            state: c.state,
            opts,
            stats: DynamicsStats::default(),
        }
    }

    /// Sets the step the next [`Self::step`] takes (a fixed step's too).
    pub fn set_step_size(&mut self, h: f64) {
        self.h = h;
    }

    /// `(α_m, α_f, β, γ)` of the next step: [`RESTART`]'s for a restart's
    /// first step, else generalized-α's.
    fn coefficients_now(&self) -> (f64, f64, f64, f64) {
        if self.restart {
            RESTART
        } else {
            (self.alpha_m, self.alpha_f, self.beta, self.gamma)
        }
    }

    /// The current state.
    pub fn state(&self) -> &State {
        &self.state
    }

    /// The current full coordinates.
    pub fn q_full(&self) -> &[f64] {
        self.model.full(&self.work)
    }

    /// The current accelerations; right after [`Self::new`] the consistent
    /// initial accelerations.
    pub fn acceleration(&self) -> &[f64] {
        &self.acc
    }

    /// The current multipliers `λ`.
    pub fn multipliers(&self) -> &[f64] {
        &self.lambda
    }

    /// The step the next [`Self::step`] takes.
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// The model.
    pub fn model(&self) -> &'m M {
        self.model
    }

    /// One step of the current size (fixed step: [`AlphaOptions::h`]); with
    /// step-size control, one accepted step, retried smaller as often as
    /// the error estimate or Newton asks.
    pub fn step(&mut self) -> Result<(), DynamicsError> {
        self.step_within(f64::INFINITY)
    }

    /// [`Self::step`], not past `t_max` (the step shortened to land on it,
    /// with the fixed step too; the next step is the full one again).
    pub fn step_within(&mut self, t_max: f64) -> Result<(), DynamicsError> {
        let Some(control) = self.opts.control else {
            let h = self.h.min(t_max - self.state.t);
            let attempt = self.newton_retrying(h)?;
            self.accept(h, attempt);
            return Ok(());
        };
        loop {
            let h = self.h.min(t_max - self.state.t).max(0.0);
            let attempt = match self.newton_retrying(h) {
                Ok(a) => a,
                Err(DynamicsError::NewtonFailed { t, corrections }) => {
                    // Newton fails with a fresh matrix: a smaller step.
                    self.stats.rejected += 1;
                    self.h = h / 4.0;
                    if self.h < control.h_min {
                        return Err(DynamicsError::NewtonFailed { t, corrections });
                    }
                    continue;
                }
                Err(e) => return Err(e),
            };
            let err = self.error_norm(h, &attempt, &control);
            let factor = if err == 0.0 {
                5.0
            } else {
                (0.9 * err.powf(-1.0 / 3.0)).clamp(0.2, 5.0)
            };
            if err.is_nan() {
                return Err(DynamicsError::NonFinite {
                    t: self.state.t + h,
                });
            }
            if err <= 1.0 {
                self.accept(h, attempt);
                // A step shortened to land on `t_max` does not shrink the
                // next one.
                let base = if h < self.h { self.h } else { h };
                self.h = (base * factor).clamp(control.h_min, control.h_max);
                return Ok(());
            }
            self.stats.rejected += 1;
            self.h = (h * factor.min(0.9)).max(control.h_min);
            if h <= control.h_min {
                return Err(DynamicsError::StepTooSmall {
                    t: self.state.t,
                    h,
                    error: err,
                });
            }
        }
    }

    /// The local error estimate of the positions, weighted RMS.
    fn error_norm(&self, h: f64, a: &Attempt, c: &StepControl) -> f64 {
        let n = self.model.n();
        if n == 0 {
            return 0.0;
        }
        let (am, af, beta, _) = self.coefficients_now();
        let k = h * h * (beta - 1.0 / 6.0 + 0.5 * (am - af));
        let mut sum = 0.0;
        for i in 0..n {
            let e = k * (a.aux[i] - self.aux[i]);
            let scale = c.atol + c.rtol * self.state.q[i].abs().max(a.y[i].abs());
            sum += (e / scale).powi(2);
        }
        (sum / n as f64).sqrt()
    }

    /// Newton at step `h`; with [`AlphaOptions::reuse_matrix`], a failed
    /// modified Newton iteration is retried with full Newton.
    fn newton_retrying(&mut self, h: f64) -> Result<Attempt, DynamicsError> {
        match self.newton(h, false) {
            Err(DynamicsError::NewtonFailed { .. }) if self.opts.reuse_matrix => {
                self.newton(h, true)
            }
            other => other,
        }
    }

    fn newton(&mut self, h: f64, always_refresh: bool) -> Result<Attempt, DynamicsError> {
        let model = self.model;
        let (am, af, beta, gamma) = self.coefficients_now();
        let (n, m) = (model.n(), model.n_constraints());
        let t1 = self.state.t + h;
        // Predictor: ÿ_{n+1} = ÿ_n; for a restart's first step
        // `ÿ_{n+1} = 0`, `y_{n+1} = y_n + h ẏ_n`: a stiff mode displaced at
        // the restart has `ÿ_n = −ω² x_n`, and `½ h² ÿ_n` would predict it
        // `½ (ω h)²` times its displacement away, where Newton can find
        // another root of the step's equations (the pendulum's stiff cable:
        // a link spun up to 16 rad/s in one step).
        let mut acc1 = if self.restart {
            vec![0.0; n]
        } else {
            self.acc.clone()
        };
        let mut aux1: Vec<f64> = (0..n)
            .map(|i| (af * self.acc[i] + (1.0 - af) * acc1[i] - am * self.aux[i]) / (1.0 - am))
            .collect();
        let mut y1: Vec<f64> = (0..n)
            .map(|i| {
                self.state.q[i]
                    + h * self.state.v[i]
                    + h * h * ((0.5 - beta) * self.aux[i] + beta * aux1[i])
            })
            .collect();
        let mut v1: Vec<f64> = (0..n)
            .map(|i| self.state.v[i] + h * ((1.0 - gamma) * self.aux[i] + gamma * aux1[i]))
            .collect();
        let lambda0 = self.lambda.clone();
        let da = (1.0 - af) / (1.0 - am);
        let bp = h * h * beta * da;
        let gp = h * gamma * da;
        let mut r = vec![0.0; n + m];
        let mut corrections = Vec::new();
        // Modified Newton: the factored iteration matrix is kept across
        // iterations and steps (of one size) while each correction is at
        // most a quarter of the one before; otherwise (or on the first
        // use) it is rebuilt.
        let mut refresh = always_refresh
            || !self.opts.reuse_matrix
            || !self.have_matrix
            || self.matrix_for != (bp, gp);
        let mut fresh = false;
        for _ in 0..self.opts.max_iterations {
            model.residual(&mut self.work, t1, &y1, &v1, &acc1, &self.lambda, &mut r);
            self.stats.force_evaluations += 1;
            for x in &mut r[n..] {
                *x /= bp;
            }
            if refresh {
                let factored =
                    model.factor(&mut self.work, t1, &y1, &v1, &acc1, &self.lambda, bp, gp);
                if let Err(e) = factored {
                    self.lambda = lambda0;
                    self.have_matrix = false;
                    return Err(e);
                }
                self.stats.factorizations += 1;
                self.have_matrix = true;
                self.matrix_for = (bp, gp);
                refresh = always_refresh || !self.opts.reuse_matrix;
                fresh = true;
            }
            model.solve(&mut self.work, &mut r);
            self.stats.newton_iterations += 1;
            for i in 0..n {
                let d = -r[i];
                acc1[i] += d;
                aux1[i] += da * d;
                y1[i] += bp * d;
                v1[i] += gp * d;
            }
            for k in 0..m {
                self.lambda[k] -= r[n + k];
            }
            let c = bp * norm_inf(&r[..n]);
            corrections.push(c);
            if !c.is_finite() {
                self.lambda = lambda0;
                return Err(DynamicsError::NonFinite { t: t1 });
            }
            if c <= self.opts.tol * (1.0 + norm_inf(&y1)) {
                return Ok(Attempt {
                    y: y1,
                    v: v1,
                    acc: acc1,
                    aux: aux1,
                });
            }
            if let [.., before, last] = corrections[..]
                && last > 0.25 * before
                && !fresh
            {
                refresh = true;
            }
            fresh = false;
        }
        self.lambda = lambda0;
        Err(DynamicsError::NewtonFailed { t: t1, corrections })
    }

    fn accept(&mut self, h: f64, a: Attempt) {
        self.state.t += h;
        self.state.q = a.y;
        self.state.v = a.v;
        self.acc = a.acc;
        self.aux = a.aux;
        self.restart = false;
        let phi = self.model.accepted(&mut self.work, &self.state);
        self.stats.max_constraint_residual = self.stats.max_constraint_residual.max(phi);
        self.stats.steps += 1;
    }

    /// Steps until `t_end`, calling `observe` after every step with the
    /// state and the full coordinates. Fixed step: the last step lands on
    /// `t_end` to within `h/1000` (`t_end − t` should be a multiple of
    /// `h`). With step-size control the last step is shortened to land on
    /// `t_end`.
    pub fn run_to(
        &mut self,
        t_end: f64,
        mut observe: impl FnMut(&State, &[f64]),
    ) -> Result<(), DynamicsError> {
        self.run_to_checked(t_end, |s, q| {
            observe(s, q);
            Ok(())
        })
    }

    /// [`Self::run_to`] with an observer that may stop the run: its error
    /// ends the run with that error.
    pub fn run_to_checked(
        &mut self,
        t_end: f64,
        mut observe: impl FnMut(&State, &[f64]) -> Result<(), DynamicsError>,
    ) -> Result<(), DynamicsError> {
        if self.opts.control.is_none() {
            let steps = ((t_end - self.state.t) / self.h - 1e-3).ceil().max(0.0) as usize;
            for _ in 0..steps {
                self.step()?;
                observe(&self.state, self.model.full(&self.work))?;
            }
            return Ok(());
        }
        let eps = 1e-12 * t_end.abs().max(1.0);
        while self.state.t < t_end - eps {
            self.step_within(t_end)?;
            observe(&self.state, self.model.full(&self.work))?;
        }
        Ok(())
    }
}
