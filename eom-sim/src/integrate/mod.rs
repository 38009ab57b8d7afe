//! Integrators: shared types (statistics, stop reasons, step-size control
//! configuration) and helpers used by several methods.

// The numerical kernels index several arrays with the same loop variable,
// as the formulas do; iterator chains would obscure them.
#![allow(clippy::needless_range_loop)]

pub mod by_name;
pub mod dop853;
pub mod dopri5;
pub mod driver;
pub mod fixed;
pub(crate) mod lu;
pub mod midpoint;
pub mod radau5;
pub mod system;

use system::OdeSystem;

/// Unit round-off used in the step-size-too-small test, as in Hairer's codes
/// (they default to 2.3e-16; we use the exact double-precision epsilon).
pub(crate) const UROUND: f64 = f64::EPSILON;

/// Counters of one run. Every integrator fills the fields that apply to it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    /// Attempted steps (accepted + rejected), as Hairer's `NSTEP`.
    pub steps: usize,
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps (error test failed, Newton diverged, non-finite trial).
    pub rejected: usize,
    /// Evaluations of the right-hand side `f(t, y)`, including those spent on
    /// finite-difference Jacobians and on the initial step-size guess.
    pub rhs_evals: usize,
    /// Jacobian evaluations (analytic or by finite differences).
    pub jac_evals: usize,
    /// LU decompositions (for Radau5 one real and one complex decomposition
    /// count as one, as Hairer's `NDEC`).
    pub lu_decomps: usize,
    /// Linear solves / Newton iterations of implicit methods.
    pub newton_iters: usize,
    /// How many times the explicit codes' stiffness test fired (Hairer: 15
    /// consecutive positive tests for DOPRI5/DOP853).
    pub stiffness_detections: usize,
    /// Time at which stiffness was first detected, if ever.
    pub stiff_at: Option<f64>,
}

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopReason {
    /// Reached `t_end`.
    Finished,
    /// A terminal event fired: event `index` at time `t`.
    EventStop {
        /// Index of the event in the slice given to [`driver::integrate`].
        index: usize,
        /// Located time of the zero crossing.
        t: f64,
    },
    /// The step size fell below round-off relative to `t` (Hairer's
    /// `0.1 |h| <= |t| uround` test).
    StepSizeTooSmall {
        /// Time reached.
        t: f64,
        /// The step size that was too small.
        h: f64,
    },
    /// The integrator does not integrate this kind of system
    /// (generalized-α on a first-order ODE); nothing was integrated.
    NotApplicable {
        /// Time of the start.
        t: f64,
        /// The integrator asked for.
        integrator: by_name::Integrator,
    },
    /// The maximum number of attempted steps was exceeded.
    MaxSteps {
        /// Time reached.
        t: f64,
    },
    /// The state (or every trial step from it) became NaN or infinite.
    NonFinite {
        /// Last time at which the state was finite (or the time at which the
        /// non-finite value appeared, for fixed-step methods).
        t: f64,
        /// Index of the first non-finite component.
        component: usize,
    },
    /// The explicit method detected stiffness and was asked to stop on it.
    StiffnessDetected {
        /// Time of detection.
        t: f64,
    },
    /// Implicit solver failure: Newton iteration does not converge or the
    /// iteration matrix is repeatedly singular.
    ConvergenceFailure {
        /// Time reached.
        t: f64,
    },
}

/// Step-size control parameters of the adaptive explicit codes (DOPRI5,
/// DOP853), with Hairer's names in parentheses.
#[derive(Debug, Clone, PartialEq)]
pub struct ExplicitConfig {
    /// Relative tolerance (`RTOL`).
    pub rtol: f64,
    /// Absolute tolerance (`ATOL`).
    pub atol: f64,
    /// Initial step size; `0.0` means Hairer's `HINIT` guess.
    pub h0: f64,
    /// Maximal step size (`HMAX`); `f64::INFINITY` means `|t_end - t0|`.
    pub hmax: f64,
    /// Safety factor (`SAFE`, 0.9).
    pub safety: f64,
    /// Lower bound of `h_new / h` (`FAC1`: 0.2 DOPRI5, 0.333 DOP853).
    pub fac_min: f64,
    /// Upper bound of `h_new / h` (`FAC2`: 10 DOPRI5, 6 DOP853).
    pub fac_max: f64,
    /// Lund-stabilisation exponent of the PI controller (`BETA`: 0.04
    /// DOPRI5, 0 DOP853).
    pub beta: f64,
    /// Stiffness test every `nstiff` accepted steps (`NSTIFF`, 1000); `0`
    /// disables the test.
    pub nstiff: usize,
    /// Stop the run with [`StopReason::StiffnessDetected`] when stiffness is
    /// detected (Hairer's codes return `IDID = -4`); default `false`: only
    /// count it in [`Stats`].
    pub stop_on_stiffness: bool,
}

/// Mixed error weight `atol + rtol * max(|a|, |b|)` of Hairer's codes.
#[inline]
pub(crate) fn weight(atol: f64, rtol: f64, a: f64, b: f64) -> f64 {
    atol + rtol * a.abs().max(b.abs())
}

/// Index of the first non-finite component, if any.
#[inline]
pub(crate) fn first_non_finite(y: &[f64]) -> Option<usize> {
    y.iter().position(|v| !v.is_finite())
}

/// Hairer's initial step-size guess `HINIT` (dopri5.f / dop853.f; Hairer,
/// Nørsett & Wanner I, II.4): a first guess from `|y|/|f|`, one explicit
/// Euler step to estimate the second derivative, then
/// `h = min(100 h0, (0.01 / max(|f'|, |f|))^(1/order), hmax)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn hinit<const N: usize, S: OdeSystem<N>>(
    sys: &S,
    t: f64,
    y: &[f64; N],
    f0: &[f64; N],
    posneg: f64,
    order: i32,
    hmax: f64,
    rtol: f64,
    atol: f64,
    stats: &mut Stats,
) -> f64 {
    let mut dnf = 0.0;
    let mut dny = 0.0;
    for i in 0..N {
        let sk = atol + rtol * y[i].abs();
        dnf += (f0[i] / sk).powi(2);
        dny += (y[i] / sk).powi(2);
    }
    let mut h = if dnf <= 1e-10 || dny <= 1e-10 {
        1e-6
    } else {
        (dny / dnf).sqrt() * 0.01
    };
    h = h.min(hmax) * posneg;
    let mut y1 = [0.0; N];
    for i in 0..N {
        y1[i] = y[i] + h * f0[i];
    }
    let mut f1 = [0.0; N];
    sys.rhs(t + h, &y1, &mut f1);
    stats.rhs_evals += 1;
    let mut der2 = 0.0;
    for i in 0..N {
        let sk = atol + rtol * y[i].abs();
        der2 += ((f1[i] - f0[i]) / sk).powi(2);
    }
    let der2 = der2.sqrt() / h.abs();
    let der12 = der2.max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 || !der12.is_finite() {
        (1e-6f64).max(h.abs() * 1e-3)
    } else {
        (0.01 / der12).powf(1.0 / f64::from(order))
    };
    (100.0 * h.abs()).min(h1).min(hmax) * posneg
}
