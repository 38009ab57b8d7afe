//! The runtime for large structural models (hundreds to thousands of
//! coordinates): element kernels ([`crate::elements`]) assembled by a loop
//! over elements into a dynamic-size model with a constant sparse mass
//! matrix and a sparse tangent, solved by `faer`'s sparse direct solvers
//! with the symbolic factorisation reused.
//!
//! - [`ancf`]: chains of ANCF elements between two points, by kernel name.
//! - [`contact`]: contacts at cable nodes (events, impacts, sustained
//!   contact) through the rigid runtime's impact map and event types.
//! - [`elastica`]: reference solutions of the planar elastica for tests.
//! - [`model`]: element groups, fixed coordinates eliminated, loads.
//! - [`statics`]: Newton with load stepping.
//! - [`alpha`]: generalized-α (implicit; fixed step or step-size control),
//!   written once over [`alpha::AlphaModel`], which a structure alone and a
//!   mixed model implement.
//! - [`run`]: the run's types (state, options, step control, errors,
//!   counters), shared by both integrators and every vector model.
//! - [`simulate`]: one run of cables alone or a mixed model into the
//!   common [`crate::RunReport`] and CSV [`crate::table::Table`].
//! - [`dynamics`]: the structure's side of [`alpha::AlphaModel`], and RK4
//!   (explicit).
//! - [`mixed`]: rigid parts and chains in one model, attachment
//!   constraints, index-3 generalized-α; [`mixed::statics`]: their static
//!   equilibrium (Newton on the KKT system with load stepping).
//! - [`sparse`]: the pattern, the matrix and the solvers behind a trait.

pub mod alpha;
pub mod ancf;
pub mod contact;
pub mod dynamics;
pub mod elastica;
pub mod linear;
pub mod mixed;
pub mod model;
pub mod run;
pub mod simulate;
pub mod sparse;
pub mod statics;

pub use alpha::{AlphaModel, Carried, GeneralizedAlpha};
pub use contact::{NodeContact, NodeOnBody, NodeSphere};
pub use dynamics::integrate_rk4;
pub use linear::{SecondOrder, second_order};
pub use mixed::statics::{MixedStaticError, MixedStaticSolution, Stability, solve_static_mixed};
pub use mixed::{Attachment, ByName, MixedAlpha, MixedError, MixedModel, RigidPart};
pub use model::{ElementGroup, Elements, ModelBuilder, StructuralModel};
pub use run::{AlphaOptions, DynamicsError, DynamicsStats, State, StepControl, Violation};
pub use simulate::{
    CableLayout, ElementRun, contact_gaps_mixed, contact_gaps_structure, equilibrium_mixed,
    equilibrium_structure, simulate_mixed, simulate_structure,
};
pub use sparse::{AutoLu, BandedLu, FaerCholesky, FaerLu, Pattern, SparseMatrix, SparseSolver};
pub use statics::{LoadStep, StaticError, StaticOptions, StaticSolution, solve_static};

/// The largest absolute entry of `v` (0 for an empty vector).
pub(crate) fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}
