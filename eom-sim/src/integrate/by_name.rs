//! Running the integrator an [`Integrator`] names.

use super::StopReason;
use super::driver::{Solution, SolveOptions, integrate};
use super::system::OdeSystem;
use std::fmt;
use std::str::FromStr;

use crate::{Dop853, Dopri5, Euler, ImplicitMidpoint, Radau5, Rk4};
#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

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
    solve_with_events(s, sys, t0, y0, t_end, opts, &mut [])
}

/// [`solve`] with `events` located on the dense output (see
/// [`integrate`]).
pub fn solve_with_events<const N: usize, S: OdeSystem<N>>(
    s: &Settings,
    sys: &S,
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    opts: &SolveOptions,
    events: &mut [super::driver::Event<'_, N>],
) -> Solution<N> {
    match s.integrator {
        Integrator::Euler => integrate(&mut Euler::new(s.dt), sys, t0, y0, t_end, opts, events),
        Integrator::Rk4 => integrate(&mut Rk4::new(s.dt), sys, t0, y0, t_end, opts, events),
        Integrator::Midpoint => integrate(
            &mut ImplicitMidpoint::new(s.dt),
            sys,
            t0,
            y0,
            t_end,
            opts,
            events,
        ),
        Integrator::Dopri5 => integrate(
            &mut Dopri5::new(s.rtol, s.atol),
            sys,
            t0,
            y0,
            t_end,
            opts,
            events,
        ),
        Integrator::Dop853 => integrate(
            &mut Dop853::new(s.rtol, s.atol),
            sys,
            t0,
            y0,
            t_end,
            opts,
            events,
        ),
        Integrator::Radau5 => {
            let mut r = Radau5::new(s.rtol, s.atol);
            (r.index2_vars, r.index3_vars) = s.index_vars;
            integrate(&mut r, sys, t0, y0, t_end, opts, events)
        }
        // Generalized-α integrates `M q̈ = f` of element models
        // (`crate::large::alpha`), not a first-order ODE: the run stops
        // where it starts, saying so.
        Integrator::GeneralizedAlpha => Solution {
            t: Vec::new(),
            y: Vec::new(),
            t_out: Vec::new(),
            y_out: Vec::new(),
            events: Vec::new(),
            t_final: t0,
            y_final: y0,
            stats: Default::default(),
            stop: StopReason::NotApplicable {
                t: t0,
                integrator: Integrator::GeneralizedAlpha,
            },
        },
    }
}

/// The integrators, one name each (as `eom-gen simulate --integrator`
/// takes them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "lowercase"))]
pub enum Integrator {
    /// Explicit Euler, fixed step.
    Euler,
    /// Classical Runge–Kutta, fixed step.
    Rk4,
    /// Implicit midpoint rule, fixed step, symplectic.
    Midpoint,
    /// Dormand–Prince 5(4), adaptive.
    Dopri5,
    /// Dormand–Prince 8(5,3), adaptive.
    Dop853,
    /// Radau IIA order 5, implicit, adaptive (stiff problems, index-3 DAEs).
    Radau5,
    /// Generalized-α of Chung–Hulbert / Arnold–Brüls, implicit, fixed step
    /// or step-size control: the integrator of element models (cables,
    /// alone or hung at rigid bodies; `crate::large::alpha`).
    #[cfg_attr(feature = "serde", serde(rename = "generalized-alpha"))]
    GeneralizedAlpha,
}

impl Integrator {
    /// Every integrator, in the order of the docs.
    pub const ALL: [Integrator; 7] = [
        Integrator::Euler,
        Integrator::Rk4,
        Integrator::Midpoint,
        Integrator::Dopri5,
        Integrator::Dop853,
        Integrator::Radau5,
        Integrator::GeneralizedAlpha,
    ];

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Euler => "euler",
            Integrator::Rk4 => "rk4",
            Integrator::Midpoint => "midpoint",
            Integrator::Dopri5 => "dopri5",
            Integrator::Dop853 => "dop853",
            Integrator::Radau5 => "radau5",
            Integrator::GeneralizedAlpha => "generalized-alpha",
        }
    }

    /// True for the methods of compiled and interpreted models (first-order
    /// ODEs `y' = f(t, y)`): all but generalized-α.
    pub fn runs_odes(self) -> bool {
        self != Integrator::GeneralizedAlpha
    }

    /// True for the methods of element models (cables): generalized-α and
    /// RK4.
    pub fn runs_element_models(self) -> bool {
        matches!(self, Integrator::GeneralizedAlpha | Integrator::Rk4)
    }

    /// The names of the integrators for which `keep` holds, comma-separated.
    pub fn names_where(keep: impl Fn(Integrator) -> bool) -> String {
        Integrator::ALL
            .into_iter()
            .filter(|i| keep(*i))
            .map(Integrator::name)
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Whether it solves with a Jacobian of the right-hand side (RADAU5
    /// and the implicit midpoint rule): generated or by differences, see
    /// [`crate::Jacobian`].
    pub fn uses_jacobian(self) -> bool {
        matches!(self, Integrator::Radau5 | Integrator::Midpoint)
    }

    /// True for the methods with error control (tolerances), false for the
    /// fixed-step ones (a step size).
    pub fn is_adaptive(self) -> bool {
        matches!(
            self,
            Integrator::Dopri5 | Integrator::Dop853 | Integrator::Radau5
        )
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is not one of a list.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownName {
    /// What was named (`integrator`, `constraint method`).
    pub what: &'static str,
    /// The name given.
    pub name: String,
    /// The names known.
    pub known: Vec<&'static str>,
    /// A known name the given one was probably meant to be.
    pub hint: Option<&'static str>,
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown {} `{}`; choose one of {}",
            self.what,
            self.name,
            self.known.join(", ")
        )?;
        if let Some(h) = self.hint {
            write!(f, " (did you mean `{h}`?)")?;
        }
        Ok(())
    }
}

impl std::error::Error for UnknownName {}

impl FromStr for Integrator {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        Integrator::ALL
            .into_iter()
            .find(|i| i.name() == s)
            .ok_or_else(|| UnknownName {
                what: "integrator",
                name: s.to_string(),
                known: Integrator::ALL.iter().map(|i| i.name()).collect(),
                hint: None,
            })
    }
}
