//! Mechanics: joints, tree kinematics and dynamics, written once over any
//! [`Scalar`](crate::sym::Scalar) — run on `f64` they are the reference
//! numerics, run on [`Expr`](crate::sym::Expr) they build the expressions
//! the generator emits.
//!
//! The recursive algorithms, one per file (Featherstone, *Rigid Body
//! Dynamics Algorithms*, 2008), over the tree of [`tree::TreeModel`]:
//!
//! - [`kinematics`]: poses, subspaces and velocities, root to leaves, and
//!   the [`Evaluator`] that runs the others;
//! - [`rnea`]: inverse dynamics by recursive Newton–Euler (§5.3);
//! - [`crba`]: the joint-space mass matrix by composite rigid bodies (§6.2);
//! - [`aba`]: forward dynamics in O(n) by articulated bodies (§7.3);
//! - [`passes`]: the articulated-body algorithm's operations pass by pass;
//! - [`ltdl`]: the sparse `LᵀDL` factorisation of the mass matrix that
//!   follows the tree (§6.5), the other forward-dynamics route;
//! - [`energy`], [`loads`] (the force elements of [`applied`] at a state);
//! - [`looped`]: forward dynamics, mass matrix, inverse dynamics and bias
//!   of long serial chains as loops over generated body steps;
//! - [`derivatives`]: `∂u̇/∂(q, u, τ, inputs)` of the generated forward
//!   dynamics, symbolically;
//! - [`rnea_derivatives`]: `∂τ/∂(q, u)` of Newton–Euler by recursion
//!   (Carpentier and Mansard 2018), one of the routes of [`derivatives`].
//!
//! Building the tree: [`env`] (what parameters are), [`lower`] (model
//! expressions as scalars), [`error`] (why a system cannot be formulated).

pub mod aba;
pub mod applied;
pub mod constraints;
pub mod contacts;
pub mod count;
pub mod crba;
pub mod dense;
pub mod derivatives;
pub mod energy;
pub mod env;
pub mod error;
pub mod flex_outputs;
pub mod flex_state;
pub mod flex_tunable;
pub mod flexible;
pub mod formulate;
pub mod initial;
pub mod joint;
pub mod kinematics;
pub mod loads;
pub mod looped;
pub mod lower;
pub mod ltdl;
pub mod mounts;
pub mod numeric;
pub mod passes;
pub mod rnea;
pub mod rnea_derivatives;
pub mod spatial;
pub mod stiffening;
pub mod tree;

pub use applied::Applied;
pub use dense::solve_dense;
pub use env::{Env, NumericEnv};
pub use error::MechError;
pub use formulate::{FdForm, Formulation, formulate};
pub use joint::JointModel;
pub use kinematics::{Evaluator, Kinematics, State};
pub use ltdl::{ltdl, ltdl_solve};
pub use numeric::Numeric;
pub use spatial::{Force, Motion, Pose, RigidInertia};
pub use tree::TreeModel;
