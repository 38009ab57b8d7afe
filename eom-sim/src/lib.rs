//! eom-sim: the runtime side of eom.
//!
//! Generated code implements this crate's model trait; integrators and
//! constraint solvers run on it. It depends on `nalgebra`, never on
//! `eom-gen`.
//!
//! # Integrators
//!
//! Every integrator works on a first-order system `M y' = f(t, y)` of fixed
//! dimension `N` (a const generic), described by [`OdeSystem`]. States are
//! `[f64; N]`; no integrator allocates on the heap inside its step loop
//! (work arrays are allocated once when the run starts; recording the
//! accepted steps or dense samples into the [`Solution`] grows its vectors).
//!
//! | method | kind | order | dense output |
//! | --- | --- | --- | --- |
//! | [`Euler`] | explicit, fixed step (teaching baseline) | 1 | linear |
//! | [`Rk4`] | explicit, fixed step | 4 | cubic Hermite (order 3) |
//! | [`Dopri5`] | explicit, adaptive, Hairer's DOPRI5 | 5(4) | 4th order (Shampine) |
//! | [`Dop853`] | explicit, adaptive, Hairer's DOP853 | 8(5,3) | 7th order |
//! | [`Radau5`] | implicit, adaptive, Hairer's RADAU5 (stiff, `M y' = f`) | 5 | collocation polynomial (order 3) |
//! | [`ImplicitMidpoint`] | implicit, fixed step, symplectic | 2 | cubic Hermite |
//!
//! [`stormer_verlet`] integrates separable second-order systems
//! `q'' = a(t, q)` with the symplectic Störmer–Verlet (leapfrog) scheme.
//!
//! Runs go through [`integrate`], which handles events ([`Event`]), dense
//! sampling at requested times ([`SolveOptions::t_eval`]), the projection
//! hook ([`OdeSystem::project`]), non-finite detection and statistics.
//!
//! ```
//! use eom_sim::{Direction, Dopri5, Event, EventAction, FnSystem, SolveOptions, StopReason, integrate};
//!
//! // Harmonic oscillator y'' = -y from y = 1 at rest: y = cos t.
//! let sys = FnSystem(|_t: f64, y: &[f64; 2], dy: &mut [f64; 2]| {
//!     dy[0] = y[1];
//!     dy[1] = -y[0];
//! });
//! // Stop when y falls through zero (at t = π/2), sampling every 0.1.
//! let mut events = [Event::new(|_t, y: &[f64; 2]| y[0], Direction::Falling, EventAction::Stop)];
//! let opts = SolveOptions::every(0.0, 10.0, 0.1);
//! let mut method = Dopri5::new(1e-10, 1e-10);
//! let sol = integrate(&mut method, &sys, 0.0, [1.0, 0.0], 10.0, &opts, &mut events);
//! let StopReason::EventStop { t, .. } = sol.stop else { panic!("{:?}", sol.stop) };
//! assert!((t - std::f64::consts::FRAC_PI_2).abs() < 1e-10);
//! assert_eq!(sol.t_out.len(), 16); // 0.0, 0.1, ..., 1.5
//! assert!((sol.y_out[10][0] - 1f64.cos()).abs() < 1e-9);
//! println!("{:?}", sol.stats);
//! ```

pub mod batch;
pub mod constrained;
pub mod ensemble;
/// The element kernels (the `eom-elements` crate), with the `cables`
/// feature.
#[cfg(feature = "cables")]
pub use eom_elements as elements;
mod integrate;
#[cfg(feature = "cables")]
pub mod large;
mod model;
pub mod run;
pub mod state;
pub mod table;
pub mod work_precision;

pub use batch::{Batched, Lanes, OdeLanes, PointLanes};
pub use constrained::{
    Assembly, ConstrainedModel, ConstrainedSystem, ConstraintStats, ConstraintValues, Dynamics,
    Generated, Index3System, Method, Refusal,
};
pub use ensemble::{EnsembleReport, LaneMethod, LaneResult, integrate_lanes};
pub use model::{__private, FunctionInfo, Model, Point, Vector};
/// Fixed-size matrices of the integrators' Jacobians and mass matrices.
pub use nalgebra::SMatrix;
pub use run::{
    ASSEMBLY_TOL, Integrator, Jacobian, JacobianShape, RunError, RunOptions, RunReport, Simulate,
    Stop, UnknownName, jacobian_choice, simulate, simulate_generated,
};

pub use integrate::by_name::{Settings, solve};
pub use integrate::dop853::Dop853;
pub use integrate::dopri5::Dopri5;
pub use integrate::driver::{
    Direction, Event, EventAction, EventFn, EventHit, Solution, SolveOptions, Stepper, integrate,
};
pub use integrate::fixed::{Euler, Rk4};
pub use integrate::midpoint::{
    ImplicitMidpoint, SecondOrderSystem, VerletSolution, stormer_verlet,
};
pub use integrate::radau5::Radau5;
pub use integrate::system::{FnSystem, OdeSystem};
pub use integrate::{ExplicitConfig, Stats, StopReason};
