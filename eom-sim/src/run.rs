//! One run of a model from its initial state, the same for compiled and
//! interpreted models: typed options in, a typed report out.
//!
//! [`simulate`] integrates anything that implements [`Simulate`] — generated
//! code through [`Generated`], `eom-gen`'s evaluator through its own
//! implementation — with the [`Integrator`] and constraint [`Method`] of
//! [`RunOptions`], and returns a [`RunReport`]: the final state, the
//! energy at both ends, why the run stopped ([`Stop`]), the integrator's
//! counters and, for constrained models, the assembly, the constraint
//! residuals and rank, the multipliers and the cut joints' reactions. With
//! [`RunOptions::csv`] it writes the trajectory with the requested outputs.
//! With the `serde` feature the options and the report (de)serialise, which
//! is how `eom-gen simulate` talks to a compiled model.

use crate::constrained::{
    ConstrainedModel, ConstrainedSystem, ConstraintStats, Dynamics, Generated, Index3System,
    Method, Refusal, assemble,
};
pub use crate::integrate::by_name::{Integrator, UnknownName};
use crate::integrate::by_name::{Settings, solve};
use crate::integrate::driver::{Solution, SolveOptions};
use crate::integrate::system::OdeSystem;
use crate::integrate::{Stats, StopReason};
use crate::model::{Point, Vector};
use std::fmt;
use std::str::FromStr;
use std::time::Instant;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

pub(crate) mod contact;
pub use contact::{ContactEvent, ContactEventKind, ContactImpulse, GAP_TOL, JointImpulse, MAX_LCP};
pub(crate) mod impulse;
pub use impulse::lcp;
mod elements;
mod redundant;
mod soccp;
pub use elements::{
    CableState, ContactForce, ElementReport, LoadStepReport, MountForce, StabilityReport,
    StaticReport,
};

impl Method {
    /// The methods with their default settings, in the order of the docs.
    pub const ALL: [Method; 5] = [
        Method::Projection,
        Method::BAUMGARTE,
        Method::Partitioning,
        Method::Index3,
        Method::AUGMENTED_LAGRANGIAN,
    ];

    /// Its name (as `eom-gen simulate --constraints` takes it).
    pub fn name(self) -> &'static str {
        match self {
            Method::Baumgarte { .. } => "baumgarte",
            Method::Projection => "projection",
            Method::Partitioning => "partitioning",
            Method::Index3 => "index3",
            Method::AugmentedLagrangian { .. } => "augmented-lagrangian",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| UnknownName {
                what: "constraint method",
                name: s.to_string(),
                known: Method::ALL.iter().map(|m| m.name()).collect(),
                // The multipliers with Baumgarte's stabilisation were once
                // called by what they solve for.
                hint: (s == "multipliers").then_some("baumgarte"),
            })
    }
}

#[cfg(feature = "serde")]
impl Serialize for Method {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

#[cfg(feature = "serde")]
impl<'de> Deserialize<'de> for Method {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

/// Where an implicit integrator (RADAU5, the implicit midpoint rule) gets
/// the Jacobian `∂(q̇, u̇)/∂(q, u)` of an unconstrained model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Jacobian {
    /// The generated one where the model has `forward_dynamics_derivatives`
    /// and `q̇ = u` (no quaternions) and no constraints, forward differences
    /// of the right-hand side otherwise.
    #[default]
    Auto,
    /// The generated `[[0, I], [∂u̇/∂q, ∂u̇/∂u]]`; a run that cannot have it
    /// refuses to start ([`RunError::Options`]).
    Generated,
    /// Forward differences of the right-hand side (Hairer's increment), `N`
    /// right-hand sides per Jacobian.
    Differences,
}

impl Jacobian {
    /// Every choice, in the order of the docs.
    pub const ALL: [Jacobian; 3] = [Jacobian::Auto, Jacobian::Generated, Jacobian::Differences];

    /// Its name (as `eom-gen simulate --jacobian` takes it).
    pub fn name(self) -> &'static str {
        match self {
            Jacobian::Auto => "auto",
            Jacobian::Generated => "generated",
            Jacobian::Differences => "differences",
        }
    }
}

impl fmt::Display for Jacobian {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Jacobian {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        Jacobian::ALL
            .into_iter()
            .find(|j| j.name() == s)
            .ok_or_else(|| UnknownName {
                what: "Jacobian",
                name: s.to_string(),
                known: Jacobian::ALL.iter().map(|j| j.name()).collect(),
                hint: matches!(s, "fd" | "finite-differences" | "numeric").then_some("differences"),
            })
    }
}

#[cfg(feature = "serde")]
impl Serialize for Jacobian {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

#[cfg(feature = "serde")]
impl<'de> Deserialize<'de> for Jacobian {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

/// How to run: integrator, its settings, the constraint method, the end
/// time and what to record.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct RunOptions {
    /// The integrator.
    pub integrator: Integrator,
    /// Relative tolerance (adaptive methods).
    pub rtol: f64,
    /// Absolute tolerance (adaptive methods).
    pub atol: f64,
    /// Step size, s (fixed-step methods).
    pub dt: f64,
    /// End time, s (the run starts at 0).
    pub t_end: f64,
    /// Most attempted steps before the run stops with [`Stop::MaxSteps`].
    pub max_steps: usize,
    /// How constraints are kept (models with constraints only).
    pub method: Method,
    /// Initial positions instead of the model's `q0` (assembled onto the
    /// constraints, if any).
    pub q0: Option<Vec<f64>>,
    /// Initial speeds instead of the model's `u0`.
    pub u0: Option<Vec<f64>>,
    /// Write `t`, the coordinates, the speeds and the model's outputs to
    /// this CSV file.
    pub csv: Option<String>,
    /// Rows of the CSV every this many seconds by dense output (the final
    /// state always included); `None`: every accepted step.
    pub every: Option<f64>,
    /// Add `kinetic_energy` and `potential_energy` columns to the CSV
    /// (`eom-gen simulate` sets it when the model requests the `Energy`
    /// output).
    #[cfg_attr(feature = "serde", serde(default))]
    pub energy_columns: bool,
    /// Add the momentum columns `angular_momentum_{x,y,z}` (about the world
    /// origin) and `linear_momentum_{x,y,z}` (world axes) to the CSV (set
    /// when the model requests the `Momentum` output).
    #[cfg_attr(feature = "serde", serde(default))]
    pub momentum_columns: bool,
    /// Add the columns `constraint_residual` (`max |Φ|` of the holonomic
    /// constraints) and `velocity_constraint_residual` (`max |Φ̇|` of all)
    /// to the CSV, for models with constraints (`eom-gen simulate --plot`
    /// sets it).
    #[cfg_attr(feature = "serde", serde(default))]
    pub constraint_columns: bool,
    /// Write the contact events (impacts, contacts coming to rest and
    /// released) to this CSV file, one row per contact row and event.
    #[cfg_attr(feature = "serde", serde(default))]
    pub events_csv: Option<String>,
    /// Where RADAU5 and the implicit midpoint rule get their Jacobian.
    #[cfg_attr(feature = "serde", serde(default))]
    pub jacobian: Jacobian,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            integrator: Integrator::Dopri5,
            rtol: 1e-8,
            atol: 1e-10,
            dt: 1e-3,
            t_end: 1.0,
            max_steps: 100_000,
            method: Method::Projection,
            q0: None,
            u0: None,
            csv: None,
            every: None,
            energy_columns: false,
            momentum_columns: false,
            constraint_columns: false,
            events_csv: None,
            jacobian: Jacobian::Auto,
        }
    }
}

impl RunOptions {
    /// Every problem with the options, each as a sentence naming the
    /// option; empty when they are usable.
    pub fn problems(&self) -> Vec<String> {
        let mut p = Vec::new();
        if !(self.t_end.is_finite() && self.t_end > 0.0) {
            p.push(format!(
                "--t-end must be a positive number of seconds, not {}",
                self.t_end
            ));
        }
        if self.integrator.is_adaptive() {
            if !(self.rtol.is_finite() && self.rtol >= 0.0) {
                p.push(format!(
                    "--rtol must be a non-negative number, not {}",
                    self.rtol
                ));
            }
            if !(self.atol.is_finite() && self.atol >= 0.0) {
                p.push(format!(
                    "--atol must be a non-negative number, not {}",
                    self.atol
                ));
            }
            if self.rtol <= 0.0 && self.atol <= 0.0 {
                p.push("--rtol and --atol cannot both be zero: no step would be accepted".into());
            } else if self.rtol > 0.0 && self.rtol < 10.0 * f64::EPSILON && self.atol <= 0.0 {
                p.push(format!(
                    "--rtol {} is below round-off (about 2e-15) and --atol is 0",
                    self.rtol
                ));
            }
        }
        // Checked even where the integrator has its own steps: a step that
        // is not positive is a mistake in any case.
        if !(self.dt.is_finite() && self.dt > 0.0) {
            p.push(format!(
                "--dt must be a positive step size in seconds, not {}",
                self.dt
            ));
        }
        if let Some(e) = self.every
            && !(e.is_finite() && e > 0.0)
        {
            p.push(format!(
                "--every must be a positive interval in seconds, not {e}"
            ));
        }
        if self.max_steps == 0 {
            p.push("--max-steps must be at least 1".into());
        }
        if !self.integrator.runs_odes() {
            p.push(format!(
                "--integrator {} runs models with cables; this model's integrators are {}",
                self.integrator,
                Integrator::names_where(Integrator::runs_odes)
            ));
        }
        if self.method == Method::Index3 && self.integrator != Integrator::Radau5 {
            p.push(
                "--constraints index3 integrates the index-3 DAE and needs --integrator radau5"
                    .into(),
            );
        }
        for (v, name) in [(&self.q0, "--q0"), (&self.u0, "--u0")] {
            if let Some(v) = v
                && v.iter().any(|x| !x.is_finite())
            {
                p.push(format!("{name} must be finite numbers"));
            }
        }
        p
    }

    /// The times of the CSV rows by dense output: `0, every, 2·every, …`
    /// and `t_end` itself (empty without `every`).
    pub fn sample_times(&self) -> Vec<f64> {
        let Some(every) = self.every else {
            return Vec::new();
        };
        let mut t = SolveOptions::every(0.0, self.t_end, every).t_eval;
        if t.last().is_none_or(|&last| last < self.t_end) {
            t.push(self.t_end);
        }
        t
    }
}

/// Why a run stopped.
#[derive(Clone, Debug, PartialEq)]
pub enum Stop {
    /// It reached `t_end`.
    Finished,
    /// A terminal event fired at `t`.
    Event {
        /// Time of the event.
        t: f64,
    },
    /// The step size fell below round-off at `t` (a singularity, a force
    /// with a pole, tolerances too tight, or a stiff problem for an
    /// explicit method).
    StepSizeTooSmall {
        /// Time reached.
        t: f64,
        /// The step size that was too small.
        h: f64,
    },
    /// `max_steps` attempted steps did not reach `t_end`.
    MaxSteps {
        /// Time reached.
        t: f64,
    },
    /// The state became NaN or infinite.
    NonFinite {
        /// Last time at which it was finite.
        t: f64,
        /// The first coordinate, speed or multiplier that was not.
        coordinate: String,
    },
    /// The solver could not go on (a singular mass matrix or constraint
    /// system, a failed assembly).
    Failed {
        /// Time reached.
        t: f64,
        /// What went wrong.
        message: String,
    },
}

impl Stop {
    /// True for a run that reached its end time.
    pub fn is_finished(&self) -> bool {
        matches!(self, Stop::Finished)
    }

    /// The snake-case name of the reason (`finished`, `step_size_too_small`, …).
    pub fn reason(&self) -> &'static str {
        match self {
            Stop::Finished => "finished",
            Stop::Event { .. } => "event",
            Stop::StepSizeTooSmall { .. } => "step_size_too_small",
            Stop::MaxSteps { .. } => "max_steps",
            Stop::NonFinite { .. } => "non_finite",
            Stop::Failed { .. } => "failed",
        }
    }

    /// The solver's stop in the run's terms; `names` are the state's
    /// (a component beyond them is a multiplier; without names, its index).
    /// Public for runners outside this module (the ensemble's lanes).
    pub fn from_solver(s: StopReason, names: &[String]) -> Stop {
        match s {
            StopReason::Finished => Stop::Finished,
            StopReason::EventStop { t, .. } => Stop::Event { t },
            StopReason::StepSizeTooSmall { t, h } => Stop::StepSizeTooSmall { t, h },
            StopReason::MaxSteps { t } => Stop::MaxSteps { t },
            StopReason::NonFinite { t, component } => Stop::NonFinite {
                t,
                coordinate: names.get(component).cloned().unwrap_or_else(|| {
                    if names.is_empty() {
                        format!("state component {component}")
                    } else {
                        "multiplier".into()
                    }
                }),
            },
            StopReason::StiffnessDetected { t } => Stop::Failed {
                t,
                message: "the problem became stiff for the explicit integrator; use --integrator \
                          radau5"
                    .into(),
            },
            StopReason::ConvergenceFailure { t } => Stop::Failed {
                t,
                message: "the implicit integrator's Newton iteration did not converge (a singular \
                          constraint or mass matrix, or a step the iteration cannot follow)"
                    .into(),
            },
            StopReason::NotApplicable { t, integrator } => Stop::Failed {
                t,
                message: format!(
                    "{integrator} integrates element models (cables), not this model's ODE; \
                     use one of {}",
                    Integrator::names_where(Integrator::runs_odes)
                ),
            },
        }
    }
}

/// A method that refused to go on stopped the run on purpose (its
/// right-hand side is NaN from there on): the stop is its reason, not the
/// NaN it left behind.
impl From<&Refusal> for Stop {
    fn from(r: &Refusal) -> Stop {
        let Refusal::SingularConfiguration { t, .. } = r;
        Stop::Failed {
            t: *t,
            message: r.to_string(),
        }
    }
}

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stop::Finished => f.write_str("finished"),
            Stop::Event { t } => write!(f, "stopped by an event at t = {t}"),
            Stop::StepSizeTooSmall { t, h } => write!(
                f,
                "step size too small at t = {t} s (h = {h:e}): a singularity, a force with a pole, \
                 tolerances below round-off, or a stiff problem for an explicit method (try radau5)"
            ),
            Stop::MaxSteps { t } => write!(
                f,
                "reached the step limit at t = {t} s before the end time (raise --max-steps, \
                 or use an implicit method if the problem is stiff)"
            ),
            Stop::NonFinite { t, coordinate } => {
                write!(f, "`{coordinate}` became NaN or infinite after t = {t} s")
            }
            Stop::Failed { t, message } => write!(f, "failed at t = {t} s: {message}"),
        }
    }
}

/// `"finished"`, or an object with the `reason` and its details.
#[cfg(feature = "serde")]
#[derive(Serialize, Deserialize)]
#[serde(untagged)]
enum StopWire {
    Plain(String),
    Detail {
        reason: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        t: Option<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        h: Option<f64>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        coordinate: Option<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        message: Option<String>,
    },
}

#[cfg(feature = "serde")]
impl Serialize for Stop {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let reason = self.reason().to_string();
        let wire = match self.clone() {
            Stop::Finished => StopWire::Plain(reason),
            Stop::Event { t } | Stop::MaxSteps { t } => StopWire::Detail {
                reason,
                t: Some(t),
                h: None,
                coordinate: None,
                message: Some(self.to_string()),
            },
            Stop::StepSizeTooSmall { t, h } => StopWire::Detail {
                reason,
                t: Some(t),
                h: Some(h),
                coordinate: None,
                message: Some(self.to_string()),
            },
            Stop::NonFinite { t, coordinate } => StopWire::Detail {
                reason,
                t: Some(t),
                h: None,
                message: Some(self.to_string()),
                coordinate: Some(coordinate),
            },
            Stop::Failed { t, message } => StopWire::Detail {
                reason,
                t: Some(t),
                h: None,
                coordinate: None,
                message: Some(message),
            },
        };
        wire.serialize(s)
    }
}

#[cfg(feature = "serde")]
impl<'de> Deserialize<'de> for Stop {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let nan = f64::NAN;
        Ok(match StopWire::deserialize(d)? {
            StopWire::Plain(s) if s == "finished" => Stop::Finished,
            StopWire::Plain(s) => Stop::Failed { t: nan, message: s },
            StopWire::Detail {
                reason,
                t,
                h,
                coordinate,
                message,
            } => {
                let t = t.unwrap_or(nan);
                match reason.as_str() {
                    "event" => Stop::Event { t },
                    "step_size_too_small" => Stop::StepSizeTooSmall {
                        t,
                        h: h.unwrap_or(nan),
                    },
                    "max_steps" => Stop::MaxSteps { t },
                    "non_finite" => Stop::NonFinite {
                        t,
                        coordinate: coordinate.unwrap_or_default(),
                    },
                    _ => Stop::Failed {
                        t,
                        message: message.unwrap_or(reason),
                    },
                }
            }
        })
    }
}

/// Non-finite numbers travel as JSON `null` and come back as NaN.
#[cfg(feature = "serde")]
mod nan {
    use serde::{Deserialize, Deserializer};

    pub fn one<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }

    pub fn list<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<Option<f64>>::deserialize(d)?
            .into_iter()
            .map(|x| x.unwrap_or(f64::NAN))
            .collect())
    }

    pub fn array<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<[f64; N], D::Error> {
        let v = list(d)?;
        let mut a = [f64::NAN; N];
        for (d, s) in a.iter_mut().zip(v) {
            *d = s;
        }
        Ok(a)
    }
}

/// The integrator's counters, and the constraint statistics for
/// constrained models.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct RunStats {
    /// Attempted steps.
    pub steps: usize,
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
    /// Jacobian evaluations.
    pub jacobian_evals: usize,
    /// Where the Jacobians came from (`generated` or `differences`), for
    /// the integrators that use one.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub jacobian: Option<Jacobian>,
    /// LU decompositions.
    pub lu_decompositions: usize,
    /// Newton iterations.
    pub newton_iterations: usize,
    /// Times the explicit methods' stiffness test fired.
    pub stiffness_detections: usize,
    /// The constraint statistics (also at the top of the report).
    #[cfg_attr(
        feature = "serde",
        serde(flatten, default, skip_serializing_if = "Option::is_none")
    )]
    pub constraints: Option<ConstraintSummary>,
}

/// What the constraint solver saw along a run.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct ConstraintSummary {
    /// Largest `|Φ|` at the accepted states.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::one"))]
    pub max_constraint_residual: f64,
    /// Largest `|Φ̇|` at the accepted states.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::one"))]
    pub max_velocity_residual: f64,
    /// Numerical rank of `J` at the last accepted state.
    pub constraint_rank: usize,
    /// Smallest rank of `J` seen.
    pub min_constraint_rank: usize,
    /// Smallest `σ_r / σ_1` of `J` (how near the run came to a singular
    /// configuration).
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::one"))]
    pub min_singular_ratio: f64,
    /// Changes of the coordinate partition.
    pub repartitions: usize,
}

impl From<ConstraintStats> for ConstraintSummary {
    fn from(s: ConstraintStats) -> Self {
        ConstraintSummary {
            max_constraint_residual: s.max_position_residual,
            max_velocity_residual: s.max_velocity_residual,
            constraint_rank: s.rank,
            min_constraint_rank: s.min_rank,
            min_singular_ratio: s.min_singular_ratio,
            repartitions: s.repartitions,
        }
    }
}

/// The initial assembly as reported.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct AssemblyReport {
    /// `max |Φ|` reached.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::one"))]
    pub residual: f64,
    /// `max |Φ̇|` reached.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::one"))]
    pub velocity_residual: f64,
    /// Newton iterations.
    pub iterations: usize,
}

/// Force and torque a cut joint applies to its child body at the end of a
/// run, in the axes of the parent joint frame.
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct Reaction {
    /// Force, N.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::array"))]
    pub force: [f64; 3],
    /// Torque, N m.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::array"))]
    pub torque: [f64; 3],
}

/// The constrained part of a [`RunReport`].
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct ConstraintReport {
    /// The method.
    pub constraints: Method,
    /// Names of the constraint equations.
    pub constraint_names: Vec<String>,
    /// The initial assembly.
    pub assembly: AssemblyReport,
    /// Residuals, rank and nearness to a singular configuration.
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub summary: ConstraintSummary,
    /// Multipliers `λ` at the end.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::list"))]
    pub lambda: Vec<f64>,
    /// Reactions of the cut joints at the end, by joint name in model
    /// order.
    pub cut_joint_reactions: std::collections::BTreeMap<String, Reaction>,
}

/// What a run did.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct RunReport {
    /// Time reached.
    pub t: f64,
    /// Positions at `t`.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::list"))]
    pub q: Vec<f64>,
    /// Speeds at `t`.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::list"))]
    pub u: Vec<f64>,
    /// Total energy (kinetic + potential) at the start and at `t`.
    #[cfg_attr(feature = "serde", serde(deserialize_with = "nan::array"))]
    pub energy: [f64; 2],
    /// The size of the energies the change is measured against:
    /// `max(|T| + |V|)` over the start and `t` (NaN without an energy
    /// function). The total can be near zero (a pendulum released
    /// horizontally) while `T` and `V` are not.
    #[cfg_attr(feature = "serde", serde(default, deserialize_with = "nan::one"))]
    pub energy_scale: f64,
    /// Why the run stopped.
    pub stop: Stop,
    /// The integrator's counters.
    pub stats: RunStats,
    /// CPU (wall) time of the integration, s.
    pub cpu_s: f64,
    /// Constraint method, assembly, residuals, multipliers and reactions
    /// (models with constraints).
    #[cfg_attr(
        feature = "serde",
        serde(flatten, default, skip_serializing_if = "Option::is_none")
    )]
    pub constrained: Option<ConstraintReport>,
    /// Cables' nodes, markers' forces and element counters (models with
    /// elements; their `q`, `u` are the rigid part's coordinates and
    /// speeds, empty for cables alone).
    #[cfg_attr(
        feature = "serde",
        serde(flatten, default, skip_serializing_if = "Option::is_none")
    )]
    pub elements: Option<ElementReport>,
    /// The contact events in the order of time (models with contacts).
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Vec::is_empty")
    )]
    pub contact_events: Vec<ContactEvent>,
}

/// The names a run reports by.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Names {
    /// Coordinates `q`.
    pub coordinates: Vec<String>,
    /// Speeds `u`.
    pub speeds: Vec<String>,
    /// The model's requested outputs (CSV columns after the state).
    pub outputs: Vec<String>,
    /// Constraint equations.
    pub constraints: Vec<String>,
    /// Cut joints (six reaction components each in `cut_joint_reactions`).
    pub cut_joints: Vec<String>,
    /// The contacts' gap rows (the labels of the generated `contacts`).
    pub contacts: Vec<String>,
    /// The tree joints whose impulses `joint_impulses` gives.
    pub impulse_joints: Vec<String>,
}

/// A model a run integrates: its [`Dynamics`] (for the constraint
/// solvers), forward dynamics (for the unconstrained ODE) and the generated
/// functions by name ([`Model::evaluate`]'s contract: `energy`, `outputs`,
/// `cut_joint_reactions`, …).
pub trait Simulate: Dynamics {
    /// The names of coordinates, speeds, outputs, constraints, cut joints.
    fn names(&self) -> Names;
    /// The initial positions and speeds of the model file.
    fn initial_state(&self) -> (Vec<f64>, Vec<f64>);
    /// `u̇` with `τ = 0`.
    fn forward_dynamics(&self, t: f64, q: &[f64], u: &[f64], udot: &mut [f64]);
    /// Evaluates a generated function (see [`Model::evaluate`]); `false`
    /// if the model has none of that name or `out` has the wrong length.
    fn evaluate(&self, name: &str, at: &Point<'_>, out: &mut [f64]) -> bool;
    /// The length of the flat result of the generated function `name`, if
    /// the model offers it (default: none known).
    fn function_len(&self, _name: &str) -> Option<usize> {
        None
    }
}

impl<M: ConstrainedModel + Clone> Simulate for Generated<'_, M> {
    fn names(&self) -> Names {
        let own = |v: &[&str]| v.iter().map(|s| s.to_string()).collect();
        let cut_joints = M::FUNCTIONS
            .iter()
            .find(|f| f.name == "cut_joint_reactions")
            .map_or_else(Vec::new, |f| own(f.labels));
        let labels = |name: &str| {
            M::FUNCTIONS
                .iter()
                .find(|f| f.name == name)
                .map_or_else(Vec::new, |f| own(f.labels))
        };
        let (contacts, impulse_joints) = (labels("contacts"), labels("joint_impulses"));
        Names {
            coordinates: own(M::COORDINATE_NAMES),
            speeds: own(M::SPEED_NAMES),
            outputs: own(M::OUTPUT_NAMES),
            constraints: own(M::CONSTRAINT_NAMES),
            cut_joints,
            contacts,
            impulse_joints,
        }
    }
    fn initial_state(&self) -> (Vec<f64>, Vec<f64>) {
        (self.0.q0().as_ref().to_vec(), self.0.u0().as_ref().to_vec())
    }
    fn forward_dynamics(&self, t: f64, q: &[f64], u: &[f64], udot: &mut [f64]) {
        let mut out = M::U::ZERO;
        self.0.forward_dynamics(
            t,
            &crate::constrained::load(q),
            &crate::constrained::load(u),
            &M::U::ZERO,
            &mut out,
        );
        for (d, s) in udot.iter_mut().zip(out.as_ref()) {
            *d = *s;
        }
    }
    fn evaluate(&self, name: &str, at: &Point<'_>, out: &mut [f64]) -> bool {
        self.0.evaluate(name, at, out)
    }
    fn function_len(&self, name: &str) -> Option<usize> {
        M::FUNCTIONS.iter().find(|f| f.name == name).map(|f| f.len)
    }
}

/// The unconstrained first-order system `y = (q, u)` of a [`Simulate`];
/// the flag: whether its Jacobian is the generated one (see
/// [`jacobian_choice`]).
struct Free<'a, S: ?Sized>(&'a S, bool);

impl<const N: usize, S: Simulate + ?Sized> OdeSystem<N> for Free<'_, S> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let nq = self.0.nq();
        let (q, u) = y.split_at(nq);
        let (dq, du) = dy.split_at_mut(nq);
        self.0.qdot(q, u, dq);
        self.0.forward_dynamics(t, q, u, du);
    }
    fn project(&self, _t: f64, y: &mut [f64; N]) -> bool {
        self.0.normalize(&mut y[..self.0.nq()]);
        !self.0.quaternions().is_empty()
    }
    /// `∂(q̇, u̇)/∂(q, u) = [[0, I], [∂u̇/∂q, ∂u̇/∂u]]` from the generated
    /// `forward_dynamics_derivatives` (at `τ = 0`), when the model offers
    /// them and `q̇ = u` (without quaternions: their derivatives are in the
    /// tangent space, not in `q`); otherwise `false`, and the implicit
    /// methods difference `rhs`.
    fn jacobian(&self, t: f64, y: &[f64; N], jac: &mut nalgebra::SMatrix<f64, N, N>) -> bool {
        let (nq, nu) = (self.0.nq(), self.0.nu());
        if !self.1 || nq + nu != N {
            return false;
        }
        let Some(len) = self.0.function_len(DERIVATIVES) else {
            return false;
        };
        let mut d = vec![0.0; len];
        let (q, u) = y.split_at(nq);
        let at = Point {
            t,
            q,
            u,
            tau: &[],
            udot: &[],
            lambda: &[],
        };
        if !self.0.evaluate(DERIVATIVES, &at, &mut d) || d.iter().any(|x| !x.is_finite()) {
            return false;
        }
        jac.fill(0.0);
        for i in 0..nu {
            jac[(i, nq + i)] = 1.0;
            for j in 0..nu {
                jac[(nq + i, j)] = d[i * nu + j];
                jac[(nq + i, nq + j)] = d[nu * nu + i * nu + j];
            }
        }
        true
    }
}

/// What decides whether a run can have the generated Jacobian: the
/// model's shape, known before its functions are generated (so that
/// `eom-gen simulate` refuses `--jacobian` and chooses what to generate by
/// the same rule as the run).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct JacobianShape {
    /// Loop or closure constraints (holonomic or not).
    pub constrained: bool,
    /// Nonholonomic constraints among them.
    pub nonholonomic: bool,
    /// Quaternion coordinates (`q̇ ≠ u`).
    pub quaternions: bool,
    /// `forward_dynamics_derivatives` is (or will be) generated.
    pub derivatives: bool,
}

impl JacobianShape {
    fn of<S: Simulate + ?Sized>(model: &S) -> Self {
        let nu = model.nu();
        JacobianShape {
            constrained: model.nc() > 0,
            nonholonomic: model.nc() > model.n_holonomic(),
            quaternions: model.nq() != nu || !model.quaternions().is_empty(),
            derivatives: model
                .function_len(DERIVATIVES)
                .is_some_and(|len| len >= 2 * nu * nu),
        }
    }
}

/// Which Jacobian a run of a model of this `shape` with `options` uses:
/// `Ok(None)` for an integrator that uses none, `Ok(Some(_))` the source
/// it uses, `Err` with the reason when [`Jacobian::Generated`] or
/// [`Jacobian::Differences`] was asked for where it does not apply.
pub fn jacobian_choice(
    shape: JacobianShape,
    options: &RunOptions,
) -> Result<Option<Jacobian>, String> {
    if !options.integrator.uses_jacobian() {
        return match options.jacobian {
            Jacobian::Auto => Ok(None),
            asked => Err(format!(
                "--jacobian {asked} applies to the integrators that use a Jacobian ({}); \
                 {} uses none",
                Integrator::names_where(Integrator::uses_jacobian),
                options.integrator
            )),
        };
    }
    let why_not = if shape.constrained && options.method != Method::Index3 {
        Some(format!(
            "the model has constraints, kept by {} (a right-hand side through the \
             constraint solver, differenced); --constraints index3 has a generated Jacobian",
            options.method
        ))
    } else if shape.nonholonomic {
        Some("the model has nonholonomic constraints (their Jacobian is differenced)".to_string())
    } else if shape.quaternions {
        Some("the model has quaternion coordinates (`q̇ ≠ u`)".to_string())
    } else if !shape.derivatives {
        Some(format!(
            "the model has no `{DERIVATIVES}` (`eom-gen simulate` generates them for \
             --integrator {})",
            Integrator::names_where(Integrator::uses_jacobian)
        ))
    } else {
        None
    };
    match (options.jacobian, why_not) {
        (Jacobian::Differences, _) | (Jacobian::Auto, Some(_)) => Ok(Some(Jacobian::Differences)),
        (Jacobian::Generated, Some(why)) => Err(format!(
            "--jacobian generated: not for this run: {why}; --jacobian differences \
             differences the right-hand side"
        )),
        (Jacobian::Generated | Jacobian::Auto, None) => Ok(Some(Jacobian::Generated)),
    }
}

/// The generated derivatives of forward dynamics (see `eom_gen::functions`:
/// `∂u̇/∂q`, `∂u̇/∂u`, … each `NU × NU` by rows).
const DERIVATIVES: &str = "forward_dynamics_derivatives";

/// Why a run could not start.
#[derive(Clone, Debug, PartialEq)]
pub enum RunError {
    /// The options are not usable (each problem a sentence).
    Options(Vec<String>),
    /// The state size `N` the run was instantiated with does not fit the
    /// model and method (a programming error of the caller).
    StateSize {
        /// `N`.
        given: usize,
        /// What the model and method need.
        needed: usize,
    },
    /// The mass matrix is singular at the initial state.
    SingularMass,
    /// The CSV could not be written.
    Csv(String),
    /// The initial state cannot be assembled: Newton on the position
    /// constraints stalled with `max |Φ|` above [`ASSEMBLY_TOL`] (a loop
    /// that cannot close, constraints that contradict each other).
    NotAssembled {
        /// The smallest `max |Φ|` reached.
        residual: f64,
        /// Newton iterations.
        iterations: usize,
        /// The constraint equation furthest from satisfied.
        equation: String,
    },
    /// A model with elements cannot start (constraints off at the start,
    /// a singular matrix).
    #[cfg(feature = "cables")]
    Elements(crate::large::DynamicsError),
}

/// The largest `max |Φ|` (m or rad) an assembled initial state may keep:
/// assembly converges quadratically to round-off where the constraints can
/// be met at all, so a run never starts from a state further off than this.
pub const ASSEMBLY_TOL: f64 = 1e-8;

/// The name of the holonomic equation with the largest `|Φ|` at `q`.
fn worst_equation<S: Simulate + ?Sized>(model: &S, q: &[f64], names: &[String]) -> String {
    let mut c = crate::constrained::ConstraintValues::zeros(model.nc(), model.nu());
    let zero = vec![0.0; model.nu()];
    crate::constrained::Assemble::closure(model, 0.0, q, &zero, &mut c);
    let worst = c
        .phi
        .iter()
        .take(model.n_holonomic())
        .enumerate()
        .fold(
            (0, -1.0),
            |(k, m), (i, x)| {
                if x.abs() > m { (i, x.abs()) } else { (k, m) }
            },
        )
        .0;
    names
        .get(worst)
        .cloned()
        .unwrap_or_else(|| format!("equation {worst}"))
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Options(p) => f.write_str(&p.join("; ")),
            RunError::StateSize { given, needed } => write!(
                f,
                "the run was built for {given} states, the model and method need {needed}"
            ),
            RunError::SingularMass => f.write_str(
                "the mass matrix is singular at the initial state (a joint whose motion has no inertia)",
            ),
            RunError::Csv(e) => f.write_str(e),
            RunError::NotAssembled {
                residual,
                iterations,
                equation,
            } => write!(
                f,
                "the initial state cannot be assembled: the constraints cannot all be met \
                 (the smallest max |Φ| reached is {residual:.3e} after {iterations} Newton step(s), \
                 above the tolerance {ASSEMBLY_TOL:e}; furthest off: `{equation}`); \
                 a loop that cannot close (check the joint frames and lengths), \
                 or contradictory constraints"
            ),
            #[cfg(feature = "cables")]
            RunError::Elements(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for RunError {}

/// The state size a run of `d` with `options` integrates: `n_q + n_u`, plus
/// the multipliers for the index-3 DAE.
pub fn state_len<D: Dynamics + ?Sized>(d: &D, options: &RunOptions) -> usize {
    let extra = if d.nc() > 0 && options.method == Method::Index3 {
        d.nc()
    } else {
        0
    };
    d.nq() + d.nu() + extra
}

/// Integrates `model` from its initial state (or `options.q0`/`u0`),
/// assembled onto its constraints if it has any, with `N` =
/// [`state_len`]`(model, options)`.
pub fn simulate<const N: usize, S: Simulate + ?Sized>(
    model: &S,
    options: &RunOptions,
) -> Result<RunReport, RunError> {
    let problems = options.problems();
    if !problems.is_empty() {
        return Err(RunError::Options(problems));
    }
    let needed = state_len(model, options);
    if N != needed {
        return Err(RunError::StateSize { given: N, needed });
    }
    let names = model.names();
    let (nq, nu, nc) = (model.nq(), model.nu(), model.nc());
    let (dq0, du0) = model.initial_state();
    let q0 = options.q0.clone().unwrap_or(dq0);
    let u0 = options.u0.clone().unwrap_or(du0);
    let mut size = Vec::new();
    if q0.len() != nq {
        size.push(format!(
            "--q0 has {} value(s), the model has {nq} coordinate(s)",
            q0.len()
        ));
    }
    if u0.len() != nu {
        size.push(format!(
            "--u0 has {} value(s), the model has {nu} speed(s)",
            u0.len()
        ));
    }
    if !size.is_empty() {
        return Err(RunError::Options(size));
    }
    let settings = Settings {
        integrator: options.integrator,
        rtol: options.rtol,
        atol: options.atol,
        dt: options.dt,
        index_vars: (0, 0),
    };
    let solve_options = SolveOptions {
        max_steps: options.max_steps,
        record_steps: options.csv.is_some() && options.every.is_none(),
        t_eval: if options.csv.is_some() {
            options.sample_times()
        } else {
            Vec::new()
        },
    };
    let state_names: Vec<String> = names
        .coordinates
        .iter()
        .chain(&names.speeds)
        .cloned()
        .collect();
    let jacobian = jacobian_choice(JacobianShape::of(model), options)
        .map_err(|e| RunError::Options(vec![e]))?;
    let generated = jacobian == Some(Jacobian::Generated);
    let nk = contact::count(model);
    if nk > 0 {
        contact_problems(model, nk, &q0, &u0, options)?;
    }
    let start = Instant::now();
    if nc == 0 {
        let mut y0 = [0.0; N];
        for (d, s) in y0.iter_mut().zip(q0.iter().chain(&u0)) {
            *d = *s;
        }
        if nk > 0 {
            let run = contact_run(model, &names, nk, options);
            let (sol, events, failed) = run.run(
                &Free(model, generated),
                &settings,
                y0,
                options.t_end,
                &solve_options,
            );
            let cpu = start.elapsed().as_secs_f64();
            let mut report = finish(model, &names, &state_names, &sol, &y0, cpu, None);
            report.stats.jacobian = jacobian;
            if let Some((t, message)) = failed {
                report.stop = Stop::Failed { t, message };
            }
            report.contact_events = events;
            write_csv(model, &names, options, &sol, &|_, _| None)?;
            write_events_csv(model, &names, options, &report.contact_events)?;
            return Ok(report);
        }
        let sol = solve(
            &settings,
            &Free(model, generated),
            0.0,
            y0,
            options.t_end,
            &solve_options,
        );
        let cpu = start.elapsed().as_secs_f64();
        let mut report = finish(model, &names, &state_names, &sol, &y0, cpu, None);
        report.stats.jacobian = jacobian;
        write_csv(model, &names, options, &sol, &|_, _| None)?;
        return Ok(report);
    }
    let a = assemble(model, &q0, &u0, 0.0);
    if a.residual.is_nan() || a.residual > ASSEMBLY_TOL {
        return Err(RunError::NotAssembled {
            residual: a.residual,
            iterations: a.iterations,
            equation: worst_equation(model, &a.q, &names.constraints),
        });
    }
    let assembly = AssemblyReport {
        residual: a.residual,
        velocity_residual: a.velocity_residual,
        iterations: a.iterations,
    };
    let start = Instant::now();
    let constrained = |stats: ConstraintStats, lambda: Vec<f64>, q: &[f64], t: f64| {
        let mut reactions = std::collections::BTreeMap::new();
        let mut flat = vec![0.0; 6 * names.cut_joints.len()];
        let at = Point {
            t,
            q,
            lambda: &lambda,
            ..Point::default()
        };
        if !flat.is_empty() && model.evaluate("cut_joint_reactions", &at, &mut flat) {
            for (name, r) in names.cut_joints.iter().zip(flat.chunks(6)) {
                reactions.insert(
                    name.clone(),
                    Reaction {
                        force: [r[0], r[1], r[2]],
                        torque: [r[3], r[4], r[5]],
                    },
                );
            }
        }
        ConstraintReport {
            constraints: options.method,
            constraint_names: names.constraints.clone(),
            assembly: assembly.clone(),
            summary: stats.into(),
            lambda,
            cut_joint_reactions: reactions,
        }
    };
    if options.method == Method::Index3 {
        let derivatives = |t: f64, q: &[f64], u: &[f64], tau: &[f64], out: &mut [f64]| {
            let at = Point {
                t,
                q,
                u,
                tau,
                ..Point::default()
            };
            let len = model.function_len(DERIVATIVES).unwrap_or(0);
            let mut all = vec![0.0; len];
            let ok = len >= out.len() && model.evaluate(DERIVATIVES, &at, &mut all);
            out.iter_mut().zip(&all).for_each(|(d, s)| *d = *s);
            ok
        };
        let dae = if generated {
            Index3System::new(model).with_derivatives(&derivatives)
        } else {
            Index3System::new(model)
        };
        let y0 = dae
            .initial::<N>(0.0, &a.q, &a.u)
            .ok_or(RunError::SingularMass)?;
        let settings = Settings {
            index_vars: dae.index_vars(),
            ..settings
        };
        let sol = solve(&settings, &dae, 0.0, y0, options.t_end, &solve_options);
        let cpu = start.elapsed().as_secs_f64();
        let lambda = dae.multipliers(&sol.y_final);
        let c = constrained(dae.stats(), lambda, &sol.y_final[..nq], sol.t_final);
        let mut report = finish(model, &names, &state_names, &sol, &y0, cpu, Some(c));
        report.stats.jacobian = jacobian;
        if let Some(r) = dae.refusal() {
            report.stop = Stop::from(&r);
        }
        let outputs_at = ConstrainedSystem::new(model, Method::Projection);
        write_csv(model, &names, options, &sol, &|t, y| {
            outputs_at.accelerations(t, &y[..nq], &y[nq..nq + nu])
        })?;
        return Ok(report);
    }
    let cs = ConstrainedSystem::new(model, options.method);
    let mut y0 = [0.0; N];
    for (d, s) in y0.iter_mut().zip(a.q.iter().chain(&a.u)) {
        *d = *s;
    }
    let (sol, events, failed) = if nk > 0 {
        let run = contact_run(model, &names, nk, options);
        run.run(&cs, &settings, y0, options.t_end, &solve_options)
    } else {
        let sol = solve(&settings, &cs, 0.0, y0, options.t_end, &solve_options);
        (sol, Vec::new(), None)
    };
    let cpu = start.elapsed().as_secs_f64();
    let (q, u) = sol.y_final[..nq + nu].split_at(nq);
    let lambda = cs
        .accelerations(sol.t_final, q, u)
        .map(|(_, l)| l.as_slice().to_vec())
        .unwrap_or_else(|| vec![f64::NAN; nc]);
    let c = constrained(cs.stats(), lambda, q, sol.t_final);
    let mut report = finish(model, &names, &state_names, &sol, &y0, cpu, Some(c));
    report.stats.jacobian = jacobian;
    if let Some(r) = cs.refusal() {
        report.stop = Stop::from(&r);
    }
    if let Some((t, message)) = failed {
        report.stop = Stop::Failed { t, message };
    }
    report.contact_events = events;
    write_csv(model, &names, options, &sol, &|t, y| {
        cs.accelerations(t, &y[..nq], &y[nq..nq + nu])
    })?;
    write_events_csv(model, &names, options, &report.contact_events)?;
    Ok(report)
}

/// The contact runner of `model` (see [`contact`]).
fn contact_run<'a, S: Simulate + ?Sized>(
    model: &'a S,
    names: &'a Names,
    nk: usize,
    options: &RunOptions,
) -> contact::Run<'a, S> {
    contact::Run {
        model,
        names: &names.contacts,
        joints: &names.impulse_joints,
        nk,
        rest_height: options.atol.max(1e-14),
    }
}

/// What a run with contacts refuses: the index-3 method (its state holds
/// multipliers that an impact would have to jump too).
fn contact_problems<S: Simulate + ?Sized>(
    model: &S,
    nk: usize,
    q0: &[f64],
    u0: &[f64],
    options: &RunOptions,
) -> Result<(), RunError> {
    let mut problems = Vec::new();
    if model.nc() > 0 && options.method == Method::Index3 {
        problems.push(
            "the model has contacts: the index-3 method does not apply impacts; use --constraints projection (or another method)"
                .to_string(),
        );
    }
    if contact::rows(model, nk, 0.0, q0, u0).is_none() {
        problems.push("the model's generated `contacts` could not be evaluated".into());
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(RunError::Options(problems))
    }
}

/// The contact events as a table: one row per
/// event with `t`, `kind` (0 impact, 1 rest, 2 release, 3 stick, 4 slip),
/// the energies before and after, per contact row (`contacts`) its
/// impulse and normal speeds before and after (empty where the row took
/// no part; with friction, `rough`, also its tangential impulses
/// `impulse_t1`, `impulse_t2`), the generalised impulse per speed
/// (`speeds`), and every tree joint's impulse (force, torque). Rigid runs
/// and the runs of cables (their node contacts, the free coordinates as
/// speeds) write the same table.
pub fn events_table(
    contacts: &[String],
    speeds: &[String],
    impulse_joints: &[String],
    rough: bool,
    events: &[ContactEvent],
) -> crate::table::Table {
    let mut header: Vec<String> = ["t", "kind", "energy_before", "energy_after"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let per_row: &[&str] = if rough {
        &[
            "impulse",
            "speed_before",
            "speed_after",
            "impulse_t1",
            "impulse_t2",
        ]
    } else {
        &["impulse", "speed_before", "speed_after"]
    };
    for c in contacts {
        for what in per_row {
            header.push(format!("{c}.{what}"));
        }
    }
    for s in speeds {
        header.push(format!("impulse_{s}"));
    }
    for j in impulse_joints {
        for c in ["fx", "fy", "fz", "nx", "ny", "nz"] {
            header.push(format!("{j}.impulse_{c}"));
        }
    }
    let mut table = crate::table::Table::new(header);
    for e in events {
        let kind = match e.kind {
            ContactEventKind::Impact => 0.0,
            ContactEventKind::Rest => 1.0,
            ContactEventKind::Release => 2.0,
            ContactEventKind::Stick => 3.0,
            ContactEventKind::Slip => 4.0,
        };
        let mut row = vec![e.t, kind, e.energy_before, e.energy_after];
        for c in contacts {
            match e.contacts.iter().find(|x| &x.contact == c) {
                Some(x) => {
                    row.extend([x.impulse, x.speed_before, x.speed_after]);
                    if rough {
                        row.extend(x.tangential_impulse);
                    }
                }
                None => row.extend(vec![f64::NAN; per_row.len()]),
            }
        }
        row.extend(
            e.generalized_impulse
                .iter()
                .copied()
                .chain(std::iter::repeat(f64::NAN))
                .take(speeds.len()),
        );
        for j in impulse_joints {
            match e.joint_impulses.iter().find(|x| &x.joint == j) {
                Some(x) => row.extend(x.force.iter().chain(&x.torque)),
                None => row.extend([f64::NAN; 6]),
            }
        }
        table.push(row);
    }
    table
}

/// Writes the contact events to [`RunOptions::events_csv`] ([`events_table`]).
fn write_events_csv<S: Simulate + ?Sized>(
    model: &S,
    names: &Names,
    options: &RunOptions,
    events: &[ContactEvent],
) -> Result<(), RunError> {
    let Some(path) = &options.events_csv else {
        return Ok(());
    };
    let rough = model.function_len("friction").is_some();
    let table = events_table(
        &names.contacts,
        &names.speeds,
        &names.impulse_joints,
        rough,
        events,
    );
    table
        .write(path)
        .map_err(|e| RunError::Csv(format!("cannot write `{path}`: {e}")))
}

/// Total energy at a state; NaN if the model has no energy function.
fn energy<S: Simulate + ?Sized>(model: &S, t: f64, y: &[f64]) -> f64 {
    let [k, p] = energies(model, t, y);
    k + p
}

/// Kinetic and potential energy at a state; NaN if the model has no
/// energy function.
fn energies<S: Simulate + ?Sized>(model: &S, t: f64, y: &[f64]) -> [f64; 2] {
    let (nq, nu) = (model.nq(), model.nu());
    let mut e = [0.0; 2];
    let at = Point {
        t,
        q: &y[..nq],
        u: &y[nq..nq + nu],
        ..Point::default()
    };
    if model.evaluate("energy", &at, &mut e) {
        e
    } else {
        [f64::NAN; 2]
    }
}

fn finish<const N: usize, S: Simulate + ?Sized>(
    model: &S,
    names: &Names,
    state_names: &[String],
    sol: &Solution<N>,
    y0: &[f64; N],
    cpu: f64,
    constrained: Option<ConstraintReport>,
) -> RunReport {
    let (nq, nu) = (model.nq(), model.nu());
    let _ = names;
    let s: &Stats = &sol.stats;
    RunReport {
        t: sol.t_final,
        q: sol.y_final[..nq].to_vec(),
        u: sol.y_final[nq..nq + nu].to_vec(),
        energy: [
            energy(model, 0.0, y0),
            energy(model, sol.t_final, &sol.y_final),
        ],
        energy_scale: [
            energies(model, 0.0, y0),
            energies(model, sol.t_final, &sol.y_final),
        ]
        .iter()
        .map(|[k, p]| k.abs() + p.abs())
        .fold(f64::NAN, f64::max),
        stop: Stop::from_solver(sol.stop, state_names),
        stats: RunStats {
            steps: s.steps,
            accepted: s.accepted,
            rejected: s.rejected,
            rhs_evals: s.rhs_evals,
            jacobian_evals: s.jac_evals,
            jacobian: None,
            lu_decompositions: s.lu_decomps,
            newton_iterations: s.newton_iters,
            stiffness_detections: s.stiffness_detections,
            constraints: constrained.as_ref().map(|c| c.summary.clone()),
        },
        cpu_s: cpu,
        constrained,
        elements: None,
        contact_events: Vec::new(),
    }
}

/// `u̇` and `λ` of a constrained model at a state `(q, u, …)`.
type Accelerations<'a> = dyn Fn(
        f64,
        &[f64],
    ) -> Option<(
        crate::constrained::DVector<f64>,
        crate::constrained::DVector<f64>,
    )> + 'a;

/// Writes the CSV of a run: `t`, the coordinates, the speeds and the
/// model's outputs at every accepted step or dense sample, and the final
/// state as the last row. Outputs use the constrained accelerations and
/// multipliers where `constrained` gives them.
fn write_csv<const N: usize, S: Simulate + ?Sized>(
    model: &S,
    names: &Names,
    options: &RunOptions,
    sol: &Solution<N>,
    constrained: &Accelerations<'_>,
) -> Result<(), RunError> {
    let Some(path) = &options.csv else {
        return Ok(());
    };
    let (nq, nu) = (model.nq(), model.nu());
    let (ts, ys) = if options.every.is_some() {
        (&sol.t_out, &sol.y_out)
    } else {
        (&sol.t, &sol.y)
    };
    let mut rows: Vec<(f64, &[f64; N])> = ts.iter().copied().zip(ys).collect();
    // A run that stopped early ends where it stopped, not at a sample.
    if rows.last().is_none_or(|(t, _)| *t < sol.t_final) {
        rows.push((sol.t_final, &sol.y_final));
    }
    let energy_names = if options.energy_columns {
        &["kinetic_energy", "potential_energy"][..]
    } else {
        &[]
    };
    let momentum_names = if options.momentum_columns {
        &MOMENTUM_COLUMNS[..]
    } else {
        &[]
    };
    let nc = model.nc();
    let constraint_names = if options.constraint_columns && nc > 0 {
        &CONSTRAINT_COLUMNS[..]
    } else {
        &[]
    };
    let header: Vec<&str> = names
        .coordinates
        .iter()
        .chain(&names.speeds)
        .chain(&names.outputs)
        .map(String::as_str)
        .chain(energy_names.iter().copied())
        .chain(momentum_names.iter().copied())
        .chain(constraint_names.iter().copied())
        .collect();
    let mut table = crate::table::Table::new(
        std::iter::once("t")
            .chain(header)
            .map(str::to_string)
            .collect(),
    );
    let mut out = vec![0.0; names.outputs.len()];
    let mut udot = vec![0.0; nu];
    for (t, y) in rows {
        let (q, u) = y[..nq + nu].split_at(nq);
        let mut row: Vec<f64> = std::iter::once(t)
            .chain(y[..nq + nu].iter().copied())
            .collect();
        if !out.is_empty() {
            let lambda = match constrained(t, &y[..nq + nu]) {
                Some((a, l)) => {
                    udot.copy_from_slice(a.as_slice());
                    l.as_slice().to_vec()
                }
                None => {
                    model.forward_dynamics(t, q, u, &mut udot);
                    Vec::new()
                }
            };
            let at = Point {
                t,
                q,
                u,
                udot: &udot,
                lambda: &lambda,
                ..Point::default()
            };
            if !model.evaluate("outputs", &at, &mut out) {
                out.iter_mut().for_each(|x| *x = f64::NAN);
            }
            row.extend_from_slice(&out);
        }
        let at = Point {
            t,
            q,
            u,
            ..Point::default()
        };
        for (on, name, len) in [
            (options.energy_columns, "energy", 2),
            (options.momentum_columns, "momentum", 6),
        ] {
            if on {
                let mut v = vec![f64::NAN; len];
                if !model.evaluate(name, &at, &mut v) {
                    v.iter_mut().for_each(|x| *x = f64::NAN);
                }
                row.extend_from_slice(&v);
            }
        }
        if !constraint_names.is_empty() {
            let mut c = crate::constrained::ConstraintValues::zeros(nc, nu);
            model.constraints(t, q, u, &mut c);
            let largest = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let nh = model.n_holonomic().min(nc);
            row.push(largest(&c.phi.as_slice()[..nh]));
            row.push(largest(c.phidot.as_slice()));
        }
        table.push(row);
    }
    table
        .write(path)
        .map_err(|e| RunError::Csv(format!("cannot write `{path}`: {e}")))
}

/// The CSV columns of [`RunOptions::constraint_columns`].
const CONSTRAINT_COLUMNS: [&str; 2] = ["constraint_residual", "velocity_constraint_residual"];

/// The CSV columns of [`RunOptions::momentum_columns`].
const MOMENTUM_COLUMNS: [&str; 6] = [
    "angular_momentum_x",
    "angular_momentum_y",
    "angular_momentum_z",
    "linear_momentum_x",
    "linear_momentum_y",
    "linear_momentum_z",
];

/// Runs a generated model: [`simulate`] with the state size its method
/// needs (`NY = n_q + n_u`, `NYC = NY + n_c`).
pub fn simulate_generated<M: ConstrainedModel + Clone, const NY: usize, const NYC: usize>(
    model: &M,
    options: &RunOptions,
) -> Result<RunReport, RunError> {
    let g = Generated(model);
    if M::NC > 0 && options.method == Method::Index3 {
        simulate::<NYC, _>(&g, options)
    } else {
        simulate::<NY, _>(&g, options)
    }
}
