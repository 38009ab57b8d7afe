//! Mechanics: joints, tree kinematics and dynamics, written once over any
//! [`Scalar`](crate::sym::Scalar) — run on `f64` they are the reference
//! numerics, run on [`Expr`](crate::sym::Expr) they build the expressions
//! the generator emits.

pub mod constraints;
pub mod count;
pub mod dynamics;
pub mod flex_outputs;
pub mod flex_tunable;
pub mod flexible;
pub mod formulate;
pub mod initial;
pub mod joint;
pub mod mounts;
pub mod numeric;
pub mod spatial;
pub mod stiffening;
pub mod tree;

pub use dynamics::{Applied, Evaluator, Kinematics, State, ltdl, ltdl_solve};
pub use formulate::{FdForm, Formulation, formulate};
pub use joint::JointModel;
pub use numeric::Numeric;
pub use spatial::{Force, Motion, Pose, RigidInertia};
pub use tree::{Env, MechError, NumericEnv, TreeModel};
