//! The system description integrators work on.

use nalgebra::SMatrix;

/// A first-order system `M y' = f(t, y)` of fixed dimension `N`.
///
/// Only [`rhs`](OdeSystem::rhs) is required. Generated models will
/// implement this through an adapter that stacks `(q, u)` into `y` with
/// `N = NQ + NU`.
pub trait OdeSystem<const N: usize> {
    /// Writes `f(t, y)` into `dy`. Must not panic; a non-finite result is
    /// detected by the integrators.
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]);

    /// Writes the Jacobian `∂f/∂y` into `jac` and returns `true`, or returns
    /// `false` (the default) to let implicit methods use forward finite
    /// differences with Hairer's increment `sqrt(uround * max(1e-5, |y_i|))`.
    fn jacobian(&self, _t: f64, _y: &[f64; N], _jac: &mut SMatrix<f64, N, N>) -> bool {
        false
    }

    /// Writes the constant mass matrix `M` of `M y' = f` into `m` and returns
    /// `true`, or returns `false` (the default) for `M = I`. Only
    /// [`Radau5`](crate::Radau5) uses it; `M` may be singular (index-1 DAE:
    /// zero rows for algebraic equations). The explicit methods and the
    /// implicit midpoint rule ignore it and integrate `y' = f`.
    fn mass_matrix(&self, _m: &mut SMatrix<f64, N, N>) -> bool {
        false
    }

    /// Called by [`integrate`](crate::integrate) after every accepted step
    /// with the new state; may modify it (unit-quaternion normalisation,
    /// projection onto constraint manifolds) and returns `true` if it did,
    /// so the integrator refreshes what it cached about the state. The
    /// default does nothing.
    fn project(&self, _t: f64, _y: &mut [f64; N]) -> bool {
        false
    }
}

/// Adapts a closure `f(t, y, dy)` into an [`OdeSystem`] without Jacobian,
/// mass matrix or projection.
pub struct FnSystem<F>(pub F);

impl<const N: usize, F> OdeSystem<N> for FnSystem<F>
where
    F: Fn(f64, &[f64; N], &mut [f64; N]),
{
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        (self.0)(t, y, dy)
    }
}
