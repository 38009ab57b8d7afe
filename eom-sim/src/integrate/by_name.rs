//! Running the integrator an [`Integrator`] names.

use super::driver::{Solution, SolveOptions, integrate};
use super::system::OdeSystem;
use crate::run::Integrator;
use crate::{Dop853, Dopri5, Euler, ImplicitMidpoint, Radau5, Rk4};

/// How to integrate: method name, tolerances (adaptive methods), step
/// (fixed-step methods) and RADAU5's DAE index variables.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// The integrator.
    pub integrator: Integrator,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Step size of the fixed-step methods.
    pub dt: f64,
    /// RADAU5's index-2 and index-3 variable counts (the last components).
    pub index_vars: (usize, usize),
}

/// Integrates `sys` from `(t0, y0)` to `t_end` with the integrator of `s`.
pub fn solve<const N: usize, S: OdeSystem<N>>(
    s: &Settings,
    sys: &S,
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    opts: &SolveOptions,
) -> Solution<N> {
    match s.integrator {
        Integrator::Euler => integrate(&mut Euler::new(s.dt), sys, t0, y0, t_end, opts, &mut []),
        Integrator::Rk4 => integrate(&mut Rk4::new(s.dt), sys, t0, y0, t_end, opts, &mut []),
        Integrator::Midpoint => integrate(
            &mut ImplicitMidpoint::new(s.dt),
            sys,
            t0,
            y0,
            t_end,
            opts,
            &mut [],
        ),
        Integrator::Dopri5 => integrate(
            &mut Dopri5::new(s.rtol, s.atol),
            sys,
            t0,
            y0,
            t_end,
            opts,
            &mut [],
        ),
        Integrator::Dop853 => integrate(
            &mut Dop853::new(s.rtol, s.atol),
            sys,
            t0,
            y0,
            t_end,
            opts,
            &mut [],
        ),
        Integrator::Radau5 => {
            let mut r = Radau5::new(s.rtol, s.atol);
            (r.index2_vars, r.index3_vars) = s.index_vars;
            integrate(&mut r, sys, t0, y0, t_end, opts, &mut [])
        }
    }
}
