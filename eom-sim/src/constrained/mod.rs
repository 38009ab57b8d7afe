//! Constrained multibody systems: closed loops and user constraints.
//!
//! A model with constraints has, besides `q̇ = N(q) u` and
//! `M(q) u̇ = τ − b(q, u, t)`, `m` constraint equations on the speeds
//!
//! ```text
//! Φ̇(q, u, t) = J(q, t) u + Φ_t(q, t) = 0,      J u̇ = γ(q, u, t),
//! ```
//!
//! of which the first `m_h` are time derivatives of position-level
//! (holonomic) conditions `Φ(q, t) = 0` (cut joints, user expressions) and
//! the rest are nonholonomic (rolling without slipping). The constraint
//! forces are `Jᵀλ`: `M u̇ = τ − b + Jᵀλ` (Wittenburg 5.6, Shabana 5.9–5.12).
//!
//! Four ways to integrate them are built here ([`Method`]):
//!
//! | method | unknowns | drift |
//! |---|---|---|
//! | [`Method::Baumgarte`] | `(q, u)`, `λ` eliminated per right-hand side | Baumgarte terms `γ − 2α Φ̇ − β² Φ` |
//! | [`Method::Projection`] | `(q, u)`, as above | Newton onto `Φ = 0`, then `u` onto `Φ̇ = 0`, minimum-norm steps after every step |
//! | [`Method::Partitioning`] | `(q, u)`, as above | dependent coordinates from the independent ones (Wehage–Haug) after every step |
//! | [`Method::Index3`] | `(q, u, λ)`: the index-3 DAE for [`Radau5`](crate::Radau5) | none: `Φ = 0` is an equation |
//!
//! `λ` comes from the Schur complement `J M⁻¹ Jᵀ λ = γ − J M⁻¹ (τ − b)`,
//! solved through its symmetric eigendecomposition with eigenvalues below
//! `1e-10` of the largest dropped: redundant equations (Bricard's loop)
//! give the minimum-norm `λ` and the numerical rank is reported.

mod assembly;
mod generated;
mod index3;
mod linalg;
mod method;
mod stats;
mod system;
#[cfg(test)]
mod tests;

use crate::model::{Model, Vector};
pub use nalgebra::{DMatrix, DVector};

pub use assembly::{Assembly, assemble};
pub use generated::Generated;
pub(crate) use generated::load;
pub use index3::{Derivatives, INDEX3_SINGULAR_LIMIT, Index3System};
pub use linalg::{accelerations, al_solve, min_norm_solve, weighted_min_norm};
pub use method::Method;
pub use stats::{ConstraintStats, Refusal};
pub use system::{BAUMGARTE_SINGULAR_LIMIT, ConstrainedSystem};

/// A generated model with constraint equations (see the module docs).
pub trait ConstrainedModel: Model {
    /// Number of constraint equations `m`.
    const NC: usize;
    /// Number of holonomic equations `m_h` (they come first).
    const NHOLONOMIC: usize;
    /// Names of the equations (`joint.k` for cut joints, the constraint's
    /// name for user constraints).
    const CONSTRAINT_NAMES: &'static [&'static str];
    /// `[f64; NC]`.
    type Constraints: Vector;
    /// `J`, `[f64; NC * NU]`, by rows.
    type ConstraintJacobian: Vector;
    /// Sets the multipliers `λ` that [`Model::outputs`] uses for joint
    /// reactions (the constraint forces `Jᵀλ` act on the bodies).
    fn set_multipliers(&mut self, lambda: &Self::Constraints);
    /// `Φ` (zero for nonholonomic rows), `Φ̇ = J u + Φ_t`, `γ` (`J u̇ = γ`)
    /// and `J`.
    #[allow(clippy::too_many_arguments)]
    fn constraints(
        &self,
        t: f64,
        q: &Self::Q,
        u: &Self::U,
        phi: &mut Self::Constraints,
        phidot: &mut Self::Constraints,
        gamma: &mut Self::Constraints,
        jacobian: &mut Self::ConstraintJacobian,
    );
}

/// Constraint values at one state.
#[derive(Clone, Debug)]
pub struct ConstraintValues {
    /// `Φ` (holonomic rows; zero for nonholonomic ones).
    pub phi: DVector<f64>,
    /// `Φ̇ = J u + Φ_t`.
    pub phidot: DVector<f64>,
    /// `γ` with `J u̇ = γ`.
    pub gamma: DVector<f64>,
    /// `J`, `m × n_u`.
    pub jacobian: DMatrix<f64>,
}

impl ConstraintValues {
    /// Zeros for `m` equations and `nu` speeds.
    pub fn zeros(m: usize, nu: usize) -> Self {
        ConstraintValues {
            phi: DVector::zeros(m),
            phidot: DVector::zeros(m),
            gamma: DVector::zeros(m),
            jacobian: DMatrix::zeros(m, nu),
        }
    }
}

/// A constrained model seen through slices: what the solvers need. It is
/// implemented for generated code through [`Generated`] and by `eom-gen`'s
/// interpreter.
pub trait Dynamics {
    /// Number of positions.
    fn nq(&self) -> usize;
    /// Number of speeds.
    fn nu(&self) -> usize;
    /// Number of constraint equations.
    fn nc(&self) -> usize;
    /// Number of holonomic equations (the first ones).
    fn n_holonomic(&self) -> usize;
    /// Positions of unit quaternions in `q`.
    fn quaternions(&self) -> &[usize];
    /// `q̇ = N(q) u`.
    fn qdot(&self, q: &[f64], u: &[f64], qdot: &mut [f64]);
    /// `M(q)`.
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut DMatrix<f64>);
    /// `b(q, u, t)`.
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut DVector<f64>);
    /// The constraint values.
    fn constraints(&self, t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues);

    /// Normalises the unit quaternions in `q`.
    fn normalize(&self, q: &mut [f64]) {
        for &a in self.quaternions() {
            if let Some(quat) = q.get_mut(a..a + 4) {
                let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                if n > 0.0 && n.is_finite() {
                    quat.iter_mut().for_each(|x| *x /= n);
                }
            }
        }
    }
}

/// What assembly needs of a constrained model: its sizes, `q̇ = N(q) u`
/// and the constraint values without `γ`. Every [`Dynamics`] has it;
/// `eom-gen`'s `f64` reference algorithms implement it too, so one
/// assembly serves both.
pub trait Assemble {
    /// Number of speeds.
    fn speeds(&self) -> usize;
    /// Number of constraint equations.
    fn equations(&self) -> usize;
    /// Number of holonomic equations (the first ones).
    fn holonomic(&self) -> usize;
    /// `q̇ = N(q) u`.
    fn rates(&self, q: &[f64], u: &[f64], qdot: &mut [f64]);
    /// `Φ`, `Φ̇` and `J` (`γ` is not read).
    fn closure(&self, t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues);
    /// Normalises the unit quaternions in `q`.
    fn unit_quaternions(&self, q: &mut [f64]);
}

impl<D: Dynamics + ?Sized> Assemble for D {
    fn speeds(&self) -> usize {
        self.nu()
    }
    fn equations(&self) -> usize {
        self.nc()
    }
    fn holonomic(&self) -> usize {
        self.n_holonomic()
    }
    fn rates(&self, q: &[f64], u: &[f64], qdot: &mut [f64]) {
        self.qdot(q, u, qdot);
    }
    fn closure(&self, t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues) {
        self.constraints(t, q, u, c);
    }
    fn unit_quaternions(&self, q: &mut [f64]) {
        self.normalize(q);
    }
}
