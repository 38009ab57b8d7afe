//! The part of a [`super::RunReport`] that only models with elements have
//! (cables alone, or hung at markers of a rigid part): the integrator's
//! element counters, each cable's nodes at the end and the force of each
//! marker on the cable end it holds. The run itself is
//! `eom_sim::large::simulate` (feature `cables`); these are plain data, so
//! a report reads the same with or without that feature.

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

/// One cable at the end of a run.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct CableState {
    /// The cable's name.
    pub cable: String,
    /// Its element type (`Cable2D`, …).
    pub element: String,
    /// Number of elements.
    pub elements: usize,
    /// Position of the first node, m (`z = 0` when planar).
    pub first_node: [f64; 3],
    /// Position of the last node, m.
    pub last_node: [f64; 3],
    /// Every node's position, first to last, m.
    pub nodes: Vec<[f64; 3]>,
}

/// The force a marker applies to the cable end it holds, at the end of a
/// run.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct MountForce {
    /// The attachment (`CABLE.start` or `CABLE.end`).
    pub attachment: String,
    /// The force on the cable, N (world axes).
    pub force: [f64; 3],
}

/// What a run of a model with elements reports beyond the common fields.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct ElementReport {
    /// Spectral radius at infinite frequency of generalized-α (NaN for
    /// RK4).
    pub rho_inf: f64,
    /// Largest `‖Φ‖∞` of the attachments and the rigid part's own
    /// equations after a step (0 without constraints).
    pub largest_constraint_residual: f64,
    /// Every cable, in file order.
    pub cables: Vec<CableState>,
    /// Every marker holding a cable end (`System::cable_mounts` order).
    pub mounts: Vec<MountForce>,
    /// The normal force of every contact at a cable node sustained at the
    /// end of the run (N, `≥ 0`; contacts not touching are left out).
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Vec::is_empty")
    )]
    pub contact_forces: Vec<ContactForce>,
}

/// The normal force a sustained contact carries.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct ContactForce {
    /// The contact.
    pub contact: String,
    /// Its normal force `λ ≥ 0`, N.
    pub force: f64,
}

/// One load step of a static solve.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct LoadStepReport {
    /// Load factor reached.
    pub lambda: f64,
    /// Newton iterations.
    pub iterations: usize,
    /// `‖r‖∞` before each Newton correction and after the last one.
    pub residuals: Vec<f64>,
}

/// Whether a static equilibrium is stable, from the smallest eigenvalue
/// `ω²` of the (constraint-reduced) tangent.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct StabilityReport {
    /// `true` stable, `false` unstable, `None` not checked.
    pub stable: Option<bool>,
    /// The smallest `ω²` (NaN when not checked).
    pub omega2_min: f64,
    /// Negative eigenvalues (unstable directions).
    pub negative: usize,
    /// Why it was not checked.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub reason: Option<String>,
    /// In words.
    pub summary: String,
}

/// What `solve-static` reports for a model with elements, cables alone or
/// hung at a rigid part.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct StaticReport {
    /// The rigid part's coordinates at equilibrium (empty for cables
    /// alone).
    pub q: Vec<f64>,
    /// Unknowns of the solve (free coordinates, with the rigid part's).
    pub unknowns: usize,
    /// Constraint equations (attachments and the rigid part's own).
    pub constraints: usize,
    /// The accepted load steps in order.
    pub load_steps: Vec<LoadStepReport>,
    /// Load steps that failed and were halved.
    pub cuts: usize,
    /// Newton iterations whose tangent was singular and regularised.
    pub regularized: usize,
    /// Numeric factorisations.
    pub factorizations: usize,
    /// CPU (wall) time, s.
    pub cpu_s: f64,
    /// `‖Φ‖∞` at equilibrium (0 without constraints).
    pub constraint_residual: f64,
    /// Condition estimate of the KKT matrix (NaN without constraints).
    pub condition: f64,
    /// Stability of the equilibrium (`None`: not assessed, cables alone).
    pub stability: Option<StabilityReport>,
    /// Every cable at equilibrium, in file order.
    pub cables: Vec<CableState>,
    /// Every marker's force on the cable end it holds.
    pub mounts: Vec<MountForce>,
}
