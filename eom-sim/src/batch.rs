//! Many states per call: the batched functions of generated models.
//!
//! With batched emission (`eom_gen::EmitOptions::lanes`, `Builder::lanes`,
//! `eom-gen dump --lanes`; not yet from `#[multibody]`) every generated function of the table also
//! exists as `NAME_lanes::<W>`, an associated function of the model that
//! evaluates `W` states at once, one per SIMD lane ([`Lanes<W>`]), by the
//! same straight-line program as the single-state method. Its arguments are
//! the single-state method's with every number a `Lanes<W>` (entry `k` of
//! `q`, lane `l`, is coordinate `k` of state `l`), plus the `W` models the
//! lanes belong to (`&[Self; W]`: lane `l` reads its tunable parameters,
//! inputs and multipliers from model `l`, so the lanes of one call may have
//! different parameters); the result is the flat layout of
//! [`crate::Model::evaluate`]. `W` is chosen by the caller: 4 fills an
//! AVX2 register, 8 an AVX-512 one (`-C target-cpu=native`).
//!
//! [`Batched`] reaches them by name, as `Model::evaluate` does the
//! single-state ones; [`OdeLanes`] is the first-order system `y = (q, u)`
//! over lanes, which [`crate::ensemble::integrate_lanes`] integrates, `W`
//! states at a time (RK4 in lockstep, DOPRI5 with per-lane error control).

pub use eom_lanes::Lanes;

use crate::model::Model;

/// Where a batched function is evaluated: `W` states, one per lane (the
/// lanes of [`crate::Point`]); a function reads only its own arguments.
#[derive(Clone, Copy, Debug)]
pub struct PointLanes<'a, const W: usize> {
    /// Time.
    pub t: Lanes<W>,
    /// Positions `q` (`NQ` entries).
    pub q: &'a [Lanes<W>],
    /// Speeds `u` (`NU`).
    pub u: &'a [Lanes<W>],
    /// Speed rates `u̇` (`NU`, or empty for zeros).
    pub udot: &'a [Lanes<W>],
    /// Extra generalised forces `τ` (`NU`, or empty for zeros).
    pub tau: &'a [Lanes<W>],
    /// Constraint multipliers `λ` (`NC`, or empty for zeros).
    pub lambda: &'a [Lanes<W>],
}

impl<const W: usize> Default for PointLanes<'_, W> {
    fn default() -> Self {
        PointLanes {
            t: Lanes::default(),
            q: &[],
            u: &[],
            udot: &[],
            tau: &[],
            lambda: &[],
        }
    }
}

/// A model whose generated functions exist over lanes (emitted with
/// batched emission on).
pub trait Batched: Model + Copy {
    /// Evaluates the generated function `name` at the `W` states of `at`,
    /// state `l` with the parameters of `models[l]`, into `out` (its flat
    /// result as [`Model::evaluate`]'s, `FunctionInfo::len` entries).
    /// `false`, leaving `out` untouched, for an unknown name, a function
    /// without a batched form (one the scene derives from others) or a
    /// slice of the wrong length.
    fn evaluate_lanes<const W: usize>(
        models: &[Self; W],
        name: &str,
        at: &PointLanes<'_, W>,
        out: &mut [Lanes<W>],
    ) -> bool;
}

/// The first-order system `y' = f(t, y)` of `W` states at once, `N`
/// entries per state, `y = (q, u)` with `τ = 0` for generated models (the
/// lanes of [`crate::OdeSystem`]).
pub trait OdeLanes<const N: usize>: Sized {
    /// `dy = f(t, y)`, state `l` with the parameters of `models[l]`.
    fn rhs_lanes<const W: usize>(
        models: &[Self; W],
        t: Lanes<W>,
        y: &[Lanes<W>; N],
        dy: &mut [Lanes<W>; N],
    );
    /// Projects every lane back onto the model's manifold after a step
    /// (unit quaternions); `true` if the model has anything to project.
    fn project_lanes<const W: usize>(_models: &[Self; W], _y: &mut [Lanes<W>; N]) -> bool {
        false
    }
}

/// Helpers of generated code; not a public API.
#[doc(hidden)]
pub mod __private {
    use super::Lanes;
    /// An argument of [`super::Batched::evaluate_lanes`] as an array:
    /// `None` if its length is wrong; an empty slice is zeros when
    /// `optional`.
    pub fn arg_lanes<const N: usize, const W: usize>(
        v: &[Lanes<W>],
        optional: bool,
    ) -> Option<[Lanes<W>; N]> {
        if optional && v.is_empty() {
            return Some([Lanes::default(); N]);
        }
        v.try_into().ok()
    }
    /// Lane `l` of `v`.
    pub fn lane<const N: usize, const W: usize>(v: &[Lanes<W>; N], l: usize) -> [f64; N] {
        v.map(|x| x.0.get(l).copied().unwrap_or(0.0))
    }
}
