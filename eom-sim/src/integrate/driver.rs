//! The run loop shared by all step-by-step integrators: events located on
//! dense output, dense sampling at requested times, projection, non-finite
//! detection, step recording.

use super::system::OdeSystem;
use super::{Stats, StopReason, first_non_finite};

/// One integration method, advanced one accepted step at a time by
/// [`integrate`]. Implemented by [`Euler`](crate::Euler),
/// [`Rk4`](crate::Rk4), [`Dopri5`](crate::Dopri5),
/// [`Dop853`](crate::Dop853), [`Radau5`](crate::Radau5) and
/// [`ImplicitMidpoint`](crate::ImplicitMidpoint).
pub trait Stepper<const N: usize> {
    /// Prepares a run from `(t0, y0)` towards `t_end` (`t_end != t0`; either
    /// direction). `dense` tells whether dense output will be requested
    /// (DOP853 then computes its three extra stages). Allocation, if any,
    /// happens here.
    fn init<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t0: f64,
        y0: &[f64; N],
        t_end: f64,
        dense: bool,
        stats: &mut Stats,
    ) -> Result<(), StopReason>;

    /// Advances by one accepted step (retrying rejected ones internally),
    /// never past `t_end`; the last step lands exactly on `t_end`. Fails
    /// with the reason to stop.
    fn step<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t_end: f64,
        max_steps: usize,
        stats: &mut Stats,
    ) -> Result<(), StopReason>;

    /// Current time (end of the last accepted step).
    fn t(&self) -> f64;

    /// Start of the last accepted step.
    fn t_prev(&self) -> f64;

    /// Current state.
    fn y(&self) -> &[f64; N];

    /// Dense output of the last accepted step at `t` in `[t_prev, t]`.
    fn dense(&self, t: f64, out: &mut [f64; N]);

    /// Replaces the current state (after projection) and refreshes cached
    /// data such as the FSAL derivative.
    fn reset_state<S: OdeSystem<N>>(&mut self, sys: &S, y: &[f64; N], stats: &mut Stats);
}

/// Which zero crossings of an event function count.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// `g` goes from negative to non-negative.
    Rising,
    /// `g` goes from positive to non-positive.
    Falling,
    /// Either.
    Both,
}

/// What happens when an event fires.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EventAction {
    /// Stop the run at the located time ([`StopReason::EventStop`]).
    Stop,
    /// Record it in [`Solution::events`] and continue.
    Record,
}

/// A boxed event function `g(t, y)`.
pub type EventFn<'a, const N: usize> = Box<dyn Fn(f64, &[f64; N]) -> f64 + 'a>;

/// An event function `g(t, y)` whose zero crossings are located on the
/// dense output.
///
/// Crossings are bracketed by the signs of `g` at the ends of each accepted
/// step and refined with the Illinois variant of regula falsi; two
/// crossings inside one step cancel and are missed (limit the step size if
/// that matters).
pub struct Event<'a, const N: usize> {
    /// The event function.
    pub g: EventFn<'a, N>,
    /// Direction filter.
    pub direction: Direction,
    /// Stop or record.
    pub action: EventAction,
}

impl<'a, const N: usize> Event<'a, N> {
    /// An event from a closure.
    pub fn new(
        g: impl Fn(f64, &[f64; N]) -> f64 + 'a,
        direction: Direction,
        action: EventAction,
    ) -> Self {
        Event {
            g: Box::new(g),
            direction,
            action,
        }
    }
}

/// A located event.
#[derive(Debug, Clone, PartialEq)]
pub struct EventHit<const N: usize> {
    /// Index of the event in the slice given to [`integrate`].
    pub index: usize,
    /// Located time.
    pub t: f64,
    /// Dense-output state at `t`.
    pub y: [f64; N],
    /// `true` if `g` rose through zero, `false` if it fell.
    pub rising: bool,
}

/// Options of a run that do not depend on the method.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveOptions {
    /// Maximal number of attempted steps (default 100 000).
    pub max_steps: usize,
    /// Record `(t, y)` after every accepted step in [`Solution::t`] /
    /// [`Solution::y`] (default `true`).
    pub record_steps: bool,
    /// Times at which to sample the dense output (in the direction of
    /// integration, sorted); recorded in [`Solution::t_out`] /
    /// [`Solution::y_out`]. Times outside `[t0, t_end]` are skipped.
    pub t_eval: Vec<f64>,
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions {
            max_steps: 100_000,
            record_steps: true,
            t_eval: Vec::new(),
        }
    }
}

impl SolveOptions {
    /// Dense samples every `dt` from `t0` to `t_end` inclusive, without
    /// recording the steps. Sample `k` is `t0 + k·dt`; when `t_end` lies
    /// within `dt·1e-6` of a multiple, the last sample is `t_end` exactly
    /// (so round-off in `k·dt` never drops it).
    pub fn every(t0: f64, t_end: f64, dt: f64) -> Self {
        let span = t_end - t0;
        let dt = dt.abs() * span.signum();
        let t_eval = if dt == 0.0 || !dt.is_finite() {
            vec![t0]
        } else {
            let r = span / dt;
            let n = (r + 1e-6).floor().max(0.0) as usize;
            let mut v: Vec<f64> = (0..=n).map(|k| t0 + k as f64 * dt).collect();
            if (r - n as f64).abs() <= 1e-6 {
                v[n] = t_end;
            }
            v
        };
        SolveOptions {
            record_steps: false,
            t_eval,
            ..SolveOptions::default()
        }
    }
}

/// The result of a run.
#[derive(Debug, Clone)]
pub struct Solution<const N: usize> {
    /// Times of the initial point and accepted steps (if recorded).
    pub t: Vec<f64>,
    /// States after projection at [`Solution::t`].
    pub y: Vec<[f64; N]>,
    /// Dense-output sample times (from [`SolveOptions::t_eval`]).
    pub t_out: Vec<f64>,
    /// Dense-output samples at [`Solution::t_out`].
    pub y_out: Vec<[f64; N]>,
    /// Located events in the order of time.
    pub events: Vec<EventHit<N>>,
    /// Time where the run stopped.
    pub t_final: f64,
    /// State where the run stopped (at the event for an event stop).
    pub y_final: [f64; N],
    /// Counters.
    pub stats: Stats,
    /// Why the run stopped.
    pub stop: StopReason,
}

/// Locates a sign change of `g` in `[a, b]` (`ga`, `gb` of opposite signs,
/// neither zero) with the Illinois variant of regula falsi (superlinear,
/// never leaves the bracket). Returns the bracket end on the side of `b`
/// (where `g` has the sign of `gb`, i.e. just after the crossing), once the
/// bracket is a few ulps wide.
fn illinois(
    g: &mut dyn FnMut(f64) -> f64,
    mut a: f64,
    mut ga: f64,
    mut b: f64,
    mut gb: f64,
) -> f64 {
    let after_sign = gb.signum();
    for _ in 0..200 {
        let tol = 4.0 * f64::EPSILON * a.abs().max(b.abs()).max(1e-300);
        if (b - a).abs() <= tol {
            break;
        }
        let mut c = b - gb * (b - a) / (gb - ga);
        // Keep c strictly inside the bracket (guards against round-off).
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        if !(c > lo && c < hi) {
            c = 0.5 * (a + b);
        }
        let gc = g(c);
        if gc == 0.0 || !gc.is_finite() {
            return c;
        }
        if gc * gb < 0.0 {
            // The root lies between b and c: the old b becomes the retained end.
            a = b;
            ga = gb;
        } else {
            // Same side as b: halve the retained end's value (Illinois) so
            // the secant does not stall on one side.
            ga *= 0.5;
        }
        b = c;
        gb = gc;
    }
    if gb.signum() == after_sign { b } else { a }
}

/// Runs `method` on `sys` from `(t0, y0)` to `t_end`, with `events` located
/// on the dense output. Never panics on a misbehaving system; always
/// terminates (bounded by `opts.max_steps`).
pub fn integrate<const N: usize, S: OdeSystem<N>, M: Stepper<N>>(
    method: &mut M,
    sys: &S,
    t0: f64,
    y0: [f64; N],
    t_end: f64,
    opts: &SolveOptions,
    events: &mut [Event<'_, N>],
) -> Solution<N> {
    let mut sol = Solution {
        t: Vec::new(),
        y: Vec::new(),
        t_out: Vec::new(),
        y_out: Vec::new(),
        events: Vec::new(),
        t_final: t0,
        y_final: y0,
        stats: Stats::default(),
        stop: StopReason::Finished,
    };
    if opts.record_steps {
        sol.t.push(t0);
        sol.y.push(y0);
    }
    if let Some(i) = first_non_finite(&y0) {
        sol.stop = StopReason::NonFinite {
            t: t0,
            component: i,
        };
        return sol;
    }
    let dir = if t_end >= t0 { 1.0 } else { -1.0 };
    // Dense samples: skip those before t0.
    let mut k_out = 0;
    while k_out < opts.t_eval.len() && (opts.t_eval[k_out] - t0) * dir < 0.0 {
        k_out += 1;
    }
    while k_out < opts.t_eval.len() && opts.t_eval[k_out] == t0 {
        sol.t_out.push(t0);
        sol.y_out.push(y0);
        k_out += 1;
    }
    if t_end == t0 {
        return sol;
    }
    let need_dense = !events.is_empty() || k_out < opts.t_eval.len();
    if let Err(r) = method.init(sys, t0, &y0, t_end, need_dense, &mut sol.stats) {
        sol.stop = r;
        return sol;
    }
    let mut g_prev: Vec<f64> = events.iter().map(|e| (e.g)(t0, &y0)).collect();
    let mut hits: Vec<(f64, usize, bool)> = Vec::with_capacity(events.len());
    let mut tmp = [0.0; N];
    loop {
        if method.t() == t_end {
            sol.stop = StopReason::Finished;
            break;
        }
        if let Err(r) = method.step(sys, t_end, opts.max_steps, &mut sol.stats) {
            sol.stop = r;
            break;
        }
        let t_prev = method.t_prev();
        let t = method.t();
        let y = *method.y();
        if let Some(i) = first_non_finite(&y) {
            sol.stop = StopReason::NonFinite {
                t: t_prev,
                component: i,
            };
            sol.t_final = t_prev;
            method.dense(t_prev, &mut sol.y_final);
            return sol;
        }
        // Events: bracket on step boundaries, refine on dense output.
        hits.clear();
        for (i, ev) in events.iter().enumerate() {
            let ga = g_prev[i];
            let gb = (ev.g)(t, &y);
            if ga == 0.0 || !ga.is_finite() || !gb.is_finite() {
                continue;
            }
            let rising = ga < 0.0 && gb >= 0.0;
            let falling = ga > 0.0 && gb <= 0.0;
            let wanted = match ev.direction {
                Direction::Rising => rising,
                Direction::Falling => falling,
                Direction::Both => rising || falling,
            };
            if !wanted {
                continue;
            }
            let tr = if gb == 0.0 {
                t
            } else {
                let mut gf = |s: f64| {
                    method.dense(s, &mut tmp);
                    (ev.g)(s, &tmp)
                };
                illinois(&mut gf, t_prev, ga, t, gb)
            };
            hits.push((tr, i, rising));
        }
        hits.sort_by(|a, b| ((a.0 - b.0) * dir).total_cmp(&0.0));
        let mut stop_event: Option<(usize, f64)> = None;
        for &(tr, i, rising) in &hits {
            let mut yr = [0.0; N];
            method.dense(tr, &mut yr);
            sol.events.push(EventHit {
                index: i,
                t: tr,
                y: yr,
                rising,
            });
            if events[i].action == EventAction::Stop {
                stop_event = Some((i, tr));
                break;
            }
        }
        let t_lim = stop_event.map_or(t, |(_, tr)| tr);
        while k_out < opts.t_eval.len() && (opts.t_eval[k_out] - t_lim) * dir <= 0.0 {
            let te = opts.t_eval[k_out];
            method.dense(te, &mut tmp);
            sol.t_out.push(te);
            sol.y_out.push(tmp);
            k_out += 1;
        }
        if let Some((index, tr)) = stop_event {
            method.dense(tr, &mut tmp);
            sol.t_final = tr;
            sol.y_final = tmp;
            if opts.record_steps {
                sol.t.push(tr);
                sol.y.push(tmp);
            }
            sol.stop = StopReason::EventStop { index, t: tr };
            return sol;
        }
        let mut yp = y;
        if sys.project(t, &mut yp) {
            method.reset_state(sys, &yp, &mut sol.stats);
        }
        for (i, ev) in events.iter().enumerate() {
            g_prev[i] = (ev.g)(t, &yp);
        }
        if opts.record_steps {
            sol.t.push(t);
            sol.y.push(yp);
        }
    }
    sol.t_final = method.t();
    sol.y_final = *method.y();
    sol
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_ends_exactly_on_t_end() {
        for (t0, t1, dt, n) in [
            (0.0, 1.0, 0.1, 11),
            (0.0, 0.7, 0.1, 8),
            (1.0, 0.0, 0.1, 11),
            (0.0, 1.05, 0.1, 11),
        ] {
            let o = SolveOptions::every(t0, t1, dt);
            assert_eq!(
                o.t_eval.len(),
                n,
                "every({t0}, {t1}, {dt}) got {:?}",
                o.t_eval
            );
            assert_eq!(o.t_eval[0], t0);
            if n == 11 && t1 != 1.05 {
                assert_eq!(*o.t_eval.last().unwrap(), t1, "got {:?}", o.t_eval);
            }
        }
    }

    #[test]
    fn illinois_finds_roots_to_ulps() {
        // cos has its root at π/2; cubic t³ - 2 at 2^(1/3); both bracketed.
        let mut g = |t: f64| t.cos();
        let r = illinois(&mut g, 1.0, 1f64.cos(), 2.0, 2f64.cos());
        assert!((r - std::f64::consts::FRAC_PI_2).abs() < 1e-15, "got {r}");
        assert!(
            r.cos() <= 0.0,
            "root must be on the after side, got cos = {}",
            r.cos()
        );
        let mut c = |t: f64| t * t * t - 2.0;
        let r = illinois(&mut c, 0.0, -2.0, 2.0, 6.0);
        assert!((r - 2f64.cbrt()).abs() < 1e-15, "got {r}");
    }
}
