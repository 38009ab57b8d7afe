//! Flexible bodies in the floating frame of reference (FFR; Shabana,
//! *Dynamics of Multibody Systems*, ch. 5–6): the numeric foundation.
//!
//! A flexible body's points sit at `r = R + A (ū₀ + S(ū₀) q_f)`: a reference
//! frame `(R, A)` that moves like a rigid body, and `k` elastic coordinates
//! `q_f` whose shape functions `S` come from a finite-element model reduced to
//! a few modes. This module is `f64` only and not yet part of the generator
//! pipeline; the symbolic FFR terms inside the recursive algorithms will be
//! checked against it.
//!
//! - [`beam`]: a straight 3-D Euler–Bernoulli (or Timoshenko) beam, consistent FE mass,
//!   stiffness and geometric stiffness;
//! - [`modes`]: reference conditions that fix the frame (Shabana 6.2), normal
//!   modes and Craig–Bampton modes;
//! - [`invariants`]: the inertia shape integrals of the reduced body
//!   (Shabana 5.2; Wallrapp's standard input data);
//! - [`assumed`]: assumed modes (Rayleigh–Ritz) of a slender body, shape
//!   functions of `x` integrated by Gauss–Legendre quadrature;
//! - [`imported`]: modal data of an external FE model (file format, lumped-mass
//!   invariants); [`ritz`]: the checks and normal modes of such given bases;
//! - [`ffr`]: the FFR mass matrix `M(q)` and quadratic velocity vector `Q_v`
//!   of one free flexible body (Shabana 5.5).

pub mod assumed;
pub mod beam;
pub mod ffr;
pub mod imported;
pub mod invariants;
pub mod modes;
pub mod ritz;

pub use beam::{Beam, Deformation, NodeDof, Section, Shear};
pub use ffr::{mass_matrix, quadratic_velocity};
pub use invariants::Invariants;
pub use modes::{Basis, Dof, Modes, Reference, craig_bampton, normal_modes};

use std::fmt;

/// What can go wrong building a flexible body.
#[derive(Clone, Debug, PartialEq)]
pub enum FlexError {
    /// Beam data that cannot describe a beam: every problem, one per entry.
    InvalidBeam(Vec<String>),
    /// The reference conditions leave the frame undefined: these rigid-body
    /// motions of the whole beam satisfy them (each described in words).
    FrameUndefined(Vec<String>),
    /// A node index past the last node.
    UnknownNode {
        /// The index given.
        node: usize,
        /// How many nodes the beam has.
        nodes: usize,
    },
    /// More modes asked for than the constrained model has.
    TooManyModes {
        /// Modes asked for.
        asked: usize,
        /// Degrees of freedom available.
        available: usize,
    },
    /// Craig–Bampton needs reference conditions that fix nodal degrees of
    /// freedom (not the mean axis).
    NeedsNodalReference,
    /// A matrix that must be positive definite is not (which one, in words).
    NotPositiveDefinite(String),
}

impl fmt::Display for FlexError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FlexError::InvalidBeam(problems) => {
                write!(f, "invalid beam: {}", problems.join("; "))
            }
            FlexError::FrameUndefined(free) => write!(
                f,
                "the reference conditions leave the body frame undefined: the rigid-body \
                 motion{} {} of the whole beam satisfie{} them; fix more degrees of freedom \
                 (e.g. `θ_x` at x = 0 for the chord frame) or use the mean axis",
                if free.len() == 1 { "" } else { "s" },
                free.join(", "),
                if free.len() == 1 { "s" } else { "" },
            ),
            FlexError::UnknownNode { node, nodes } => write!(
                f,
                "node {node} does not exist: the beam has nodes 0..={}",
                nodes - 1
            ),
            FlexError::TooManyModes { asked, available } => write!(
                f,
                "{asked} modes asked for, but the constrained beam has only {available} \
                 degrees of freedom; use more elements or fewer modes"
            ),
            FlexError::NeedsNodalReference => write!(
                f,
                "Craig–Bampton modes need reference conditions that fix nodes \
                 (clamped, pinned–pinned or fixed degrees of freedom), not the mean axis"
            ),
            FlexError::NotPositiveDefinite(what) => write!(f, "{what} is not positive definite"),
        }
    }
}

impl std::error::Error for FlexError {}
