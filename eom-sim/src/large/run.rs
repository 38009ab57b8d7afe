//! The run's types shared by every vector model (a structure alone and a
//! mixed model) and by both integrators: the [`State`] on the free
//! coordinates, the generalized-α [`AlphaOptions`] and [`StepControl`], the [`DynamicsError`]
//! a run stops with (and the constraint [`Violation`]s it names), and the
//! [`DynamicsStats`] it counts.

use super::sparse::FactorError;
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
    /// A contact event (at a cable node) could not be resolved.
    Contact {
        /// Time of the event.
        t: f64,
        /// Why.
        message: String,
    },
    /// The energy of a model that can gain none (gravity, springs,
    /// dampers, impacts and friction only) rose above its start by more
    /// than a hundredth of the energies it is made of: the integration is
    /// wrong, and the run stops rather than report it.
    EnergyRose {
        /// Time of the state.
        t: f64,
        /// The energy at the start, J.
        start: f64,
        /// The energy reached, J.
        reached: f64,
        /// The size of the energies it is measured against
        /// (`|T| + |V|`, the larger of the start's and the state's), J.
        scale: f64,
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
            DynamicsError::Contact { t, message } => write!(f, "at t = {t}: {message}"),
            DynamicsError::EnergyRose {
                t,
                start,
                reached,
                scale,
            } => write!(
                f,
                "the energy rose from {start:.6e} J to {reached:.6e} J by t = {t} (the energies it is made of are {scale:.3e} J) in a model that can gain none (gravity, springs, dampers, impacts and friction only): the integration is wrong, not the model; take a smaller --dt, or a smaller --rho-inf to damp the modes the step does not resolve"
            ),
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

/// Step-size control of [`super::GeneralizedAlpha`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepControl {
    /// Relative tolerance of the positions' local error.
    pub rtol: f64,
    /// Absolute tolerance, in the coordinates' units.
    pub atol: f64,
    /// Smallest step: a step that must be smaller fails the run.
    pub h_min: f64,
    /// Largest step.
    pub h_max: f64,
}

impl StepControl {
    /// `rtol`, `atol`, with steps between 1e-12 s and unbounded.
    pub fn new(rtol: f64, atol: f64) -> Self {
        StepControl {
            rtol,
            atol,
            h_min: 1e-12,
            h_max: f64::INFINITY,
        }
    }
}
