//! The contract between generated code and the runtime.
//!
//! `eom-gen` emits, per model, a struct holding the tunable parameters and
//! the runtime inputs, and implements [`Model`] for it with fixed-size
//! arrays (`[f64; NQ]`, `[f64; NU]`, …) as the associated types. The
//! generated functions are straight-line code: no allocation, no panics
//! (indices are compile-time constants into fixed-size arrays).
//!
//! The equations of motion are `q̇ = N(q) u` and `M(q) u̇ = τ − b(q, u, t)`
//! with `b = C + g − Jᵀ f_ext − Q` (velocity products, gravity, point
//! forces and the model's own generalised forces, inputs included);
//! `τ` is any extra generalised force.

/// A fixed-size vector of `f64` (`[f64; N]`).
pub trait Vector: Copy + AsRef<[f64]> + AsMut<[f64]> {
    /// All zeros.
    const ZERO: Self;
}

impl<const N: usize> Vector for [f64; N] {
    const ZERO: Self = [0.0; N];
}

/// Where a generated function is evaluated: every argument any of them
/// takes (a function reads only its own; see [`Model::FUNCTIONS`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct Point<'a> {
    /// Time.
    pub t: f64,
    /// Positions `q`.
    pub q: &'a [f64],
    /// Speeds `u`.
    pub u: &'a [f64],
    /// Speed rates `u̇` (inverse dynamics, joint reactions).
    pub udot: &'a [f64],
    /// Extra generalised forces `τ` (forward dynamics).
    pub tau: &'a [f64],
    /// Constraint multipliers `λ` (reactions in closed loops).
    pub lambda: &'a [f64],
}

/// One generated function as [`Model::evaluate`] offers it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FunctionInfo {
    /// Its name (as in scenes and `eom-gen eval`).
    pub name: &'static str,
    /// Length of its flat result.
    pub len: usize,
    /// What it computes and how the result is laid out.
    pub doc: &'static str,
    /// Names of the result's groups, in order (the cut joints of
    /// `cut_joint_reactions`, six numbers each; the outputs of `outputs`,
    /// one each); empty where the result has no named groups.
    pub labels: &'static [&'static str],
}

/// A generated multibody model.
pub trait Model {
    /// The model's name.
    const NAME: &'static str;
    /// Number of position coordinates.
    const NQ: usize;
    /// Number of speeds.
    const NU: usize;
    /// Number of runtime inputs.
    const NINPUTS: usize;
    /// Coordinate names, in order.
    const COORDINATE_NAMES: &'static [&'static str];
    /// Speed names, in order.
    const SPEED_NAMES: &'static [&'static str];
    /// Input names, in order.
    const INPUT_NAMES: &'static [&'static str];
    /// Positions of the first entries of unit quaternions in `q`.
    const QUATERNIONS: &'static [usize];
    /// Names of the requested outputs (marker positions and velocities,
    /// joint reactions), in order.
    const OUTPUT_NAMES: &'static [&'static str];
    /// Positions `[f64; NQ]`.
    type Q: Vector;
    /// Speeds `[f64; NU]`.
    type U: Vector;
    /// Inputs `[f64; NINPUTS]`.
    type Inputs: Vector;
    /// Requested outputs `[f64; OUTPUT_NAMES.len()]`.
    type Outputs: Vector;
    /// Mass matrix `[[f64; NU]; NU]`, by rows.
    type MassMatrix: Copy + AsRef<[Self::U]> + AsMut<[Self::U]>;
    /// A zero mass matrix (to fill).
    const MASS_ZERO: Self::MassMatrix;

    /// Initial positions from the model file.
    fn q0(&self) -> Self::Q;
    /// Initial speeds from the model file.
    fn u0(&self) -> Self::U;
    /// `q̇ = N(q) u`.
    fn qdot(&self, q: &Self::Q, u: &Self::U, qdot: &mut Self::Q);
    /// Forward dynamics: `u̇ = M⁻¹ (τ − b)`.
    fn forward_dynamics(&self, t: f64, q: &Self::Q, u: &Self::U, tau: &Self::U, udot: &mut Self::U);
    /// Mass matrix `M(q)` (symmetric, filled completely).
    fn mass_matrix(&self, t: f64, q: &Self::Q, m: &mut Self::MassMatrix);
    /// Bias `b(q, u, t)`.
    fn bias(&self, t: f64, q: &Self::Q, u: &Self::U, b: &mut Self::U);
    /// Inverse dynamics: `τ = M u̇ + b`.
    fn inverse_dynamics(&self, t: f64, q: &Self::Q, u: &Self::U, udot: &Self::U, tau: &mut Self::U);
    /// Kinetic and potential energy.
    fn energy(&self, t: f64, q: &Self::Q, u: &Self::U) -> [f64; 2];
    /// Angular momentum about the world origin, then linear momentum, world axes.
    fn momentum(&self, t: f64, q: &Self::Q, u: &Self::U) -> [f64; 6];
    /// The requested outputs; joint reactions need the accelerations `udot`.
    fn outputs(&self, t: f64, q: &Self::Q, u: &Self::U, udot: &Self::U, out: &mut Self::Outputs);

    /// Every function of this model that [`Model::evaluate`] runs, in
    /// the generator's order.
    const FUNCTIONS: &'static [FunctionInfo];

    /// Evaluates the generated function `name` at `at` into `out` (its flat
    /// result, `FunctionInfo::len` long). `false`, leaving `out` untouched,
    /// for an unknown name or a slice of the wrong length.
    fn evaluate(&self, name: &str, at: &Point<'_>, out: &mut [f64]) -> bool;

    /// Normalises the unit quaternions in `q` (after an integration step).
    fn normalize(&self, q: &mut Self::Q) {
        let q = q.as_mut();
        for &a in Self::QUATERNIONS {
            if let Some(quat) = q.get_mut(a..a + 4) {
                let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                if n > 0.0 && n.is_finite() {
                    quat.iter_mut().for_each(|x| *x /= n);
                }
            }
        }
    }
}

/// Helpers of generated code; not a public API.
#[doc(hidden)]
pub mod __private {
    /// An argument of [`super::Model::evaluate`] as an array: `None` if its
    /// length is wrong; an empty slice is zeros when `optional`.
    pub fn arg<const N: usize>(v: &[f64], optional: bool) -> Option<[f64; N]> {
        if optional && v.is_empty() {
            return Some([0.0; N]);
        }
        v.try_into().ok()
    }

    /// `(sin x, cos x)` of several angles in one vectorised pass (the
    /// kernel of the lanes, within 1 ulp of the C library;
    /// `f64::sin_cos` for `|x| ≥ 10⁶` and non-finite `x`).
    pub use eom_lanes::sincos::sin_cos_lanes;

    /// `(sin x, cos x)` of the first `n` angles by the C library's
    /// `f64::sin_cos`, one call each (the other lanes zero): the
    /// [`sin_cos_lanes`] of builds without 256-bit vectors.
    #[inline(always)]
    pub fn sin_cos_each<const W: usize>(x: [f64; W], n: usize) -> ([f64; W], [f64; W]) {
        let (mut s, mut c) = ([0.0; W], [0.0; W]);
        for i in 0..n.min(W) {
            (s[i], c[i]) = f64::sin_cos(x[i]);
        }
        (s, c)
    }
}

#[cfg(test)]
mod tests {
    use super::__private::{sin_cos_each, sin_cos_lanes};

    /// The two branches of a generated function's `sin_cos` of its inputs:
    /// the C library's bit for bit on the first `n` lanes (the padding
    /// zero), and the vectorised kernel within 1 ulp of it, on angles of
    /// a robot's range and beyond the reduction's (which go to the C
    /// library).
    #[test]
    fn the_inputs_sin_cos_match_the_c_library() {
        let x = [0.3, -2.9, 1e-9, 7.5, -1.2e3, 2e6, -0.0, 3.0];
        let (s, c) = sin_cos_each(x, 6);
        for i in 0..8 {
            let (es, ec) = if i < 6 {
                f64::sin_cos(x[i])
            } else {
                (0.0, 0.0)
            };
            assert_eq!(
                (s[i].to_bits(), c[i].to_bits()),
                (es.to_bits(), ec.to_bits()),
                "lane {i}"
            );
        }
        let (s, c) = sin_cos_lanes(x);
        let ulp = |a: f64, b: f64| (a - b).abs() / (f64::EPSILON * b.abs().max(f64::MIN_POSITIVE));
        for i in 0..8 {
            let (es, ec) = f64::sin_cos(x[i]);
            assert!(
                ulp(s[i], es) <= 1.0 && ulp(c[i], ec) <= 1.0,
                "lane {i}: {} {} against {es} {ec}",
                s[i],
                c[i]
            );
        }
    }
}
