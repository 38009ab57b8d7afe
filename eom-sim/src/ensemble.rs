//! The ensemble integrator: `W` states advanced together through the
//! batched right-hand side ([`OdeLanes::rhs_lanes`], one state per SIMD
//! lane), each lane giving the answer the single-state integrator gives for
//! its state.
//!
//! | method | step | lanes |
//! | --- | --- | --- |
//! | [`LaneMethod::Rk4`] | fixed, `n = ceil(T / dt)` equal steps as [`crate::Rk4`] | lockstep: one time for all |
//! | [`LaneMethod::Dopri5`] | adaptive, Hairer's DOPRI5 controller as [`crate::Dopri5`] | **per-lane error control** |
//!
//! # Per-lane error control
//!
//! Every lane of DOPRI5 keeps its own time, step size, controller state
//! (Hairer's PI controller with its `facold` memory) and counters. One
//! attempt evaluates the six stages of every running lane at once, each at
//! its own `t` and `h` (time is a `Lanes<W>` too); then each lane decides on
//! its own error: an accepted lane moves on, a rejected one retries from the
//! same point with its smaller step in the next attempt, alongside lanes
//! that move on. A lane is thus the single-state integrator, step for step:
//! the same initial step (HINIT), the same sequence of accepted and rejected
//! steps, the same arithmetic in the same order. Lane `l` equals
//! `integrate(&mut Dopri5::new(rtol, atol), …)` of its state to rounding
//! (the batched right-hand side's `sin_cos` is within 1 ulp of the C
//! library's), and exactly in its counters unless a step's error lands
//! within rounding of the acceptance threshold.
//!
//! The price is idle lanes: a lane that has finished (or failed) waits for
//! the others; [`EnsembleReport::utilisation`] is the fraction of lane
//! evaluations that did work. The alternative, one step size for the pack
//! (the smallest, with a step rejected when any lane rejects it), keeps the
//! lanes busy but makes every lane take the worst lane's steps and gives a
//! lane a different answer than its single-state run; it is not offered
//! (see BENCHMARKS.md "Ensembles and sweeps in lanes" for the measured
//! utilisation).
//!
//! # Failures
//!
//! A lane that fails — a non-finite state or right-hand side, a step size
//! below round-off, too many steps — stops with its [`StopReason`] at the
//! time it reached, exactly as the single-state run would; the other lanes
//! go on. Its lane keeps being evaluated (lanes cannot be switched off), on
//! its frozen state with a zero step, and is ignored.
//!
//! No step allocates: the work arrays are `[Lanes<W>; N]` on the stack.
//! Projection ([`OdeLanes::project_lanes`], unit quaternions) follows each
//! accepted step as in [`crate::integrate`], with the right-hand side
//! refreshed at the projected state. Not supported (use the single-state
//! runner): events, dense output, the stiffness test (its counters stay
//! zero; it never changes the steps unless asked to stop).

// The kernels index several arrays with the same loop variable, as the
// formulas do.
#![allow(clippy::needless_range_loop)]

use crate::batch::{Lanes, OdeLanes};
// DOPRI5's Butcher tableau and step-size control are `integrate::dopri5`'s own.
use crate::integrate::dopri5::{
    A21, A31, A32, A41, A42, A43, A51, A52, A53, A54, A61, A62, A63, A64, A65, A71, A73, A74, A75,
    A76, C2, C3, C4, C5, Control, E1, E3, E4, E5, E6, E7, Verdict,
};
use crate::integrate::fixed::uniform_steps;
use crate::integrate::{ExplicitConfig, Stats, StopReason, weight};

/// The method of an ensemble run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LaneMethod {
    /// Classical RK4, nominal step `dt` (every lane the same steps).
    Rk4 {
        /// Nominal step size, s.
        dt: f64,
    },
    /// DOPRI5 with Hairer's defaults, each lane its own steps.
    Dopri5 {
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance.
        atol: f64,
    },
}

/// How one lane ended: its time and state, why it stopped, its counters.
#[derive(Clone, Debug, PartialEq)]
pub struct LaneResult<const N: usize> {
    /// Time reached (`t_end` when finished).
    pub t: f64,
    /// State at `t` (the last finite one for a lane that became non-finite).
    pub y: [f64; N],
    /// Why the lane stopped.
    pub stop: StopReason,
    /// The lane's counters, as the single-state run counts them.
    pub stats: Stats,
}

/// The lanes' results and what the pack cost.
#[derive(Clone, Debug)]
pub struct EnsembleReport<const N: usize, const W: usize> {
    /// Lane `l`'s result.
    pub lanes: [LaneResult<N>; W],
    /// Calls of the batched right-hand side (each evaluates all `W` lanes).
    pub rhs_calls: usize,
}

impl<const N: usize, const W: usize> EnsembleReport<N, W> {
    /// The fraction of lane evaluations that did a lane's work:
    /// `Σ_l rhs_evals_l / (W rhs_calls)` (1 when every lane takes the
    /// same steps).
    pub fn utilisation(&self) -> f64 {
        let used: usize = self.lanes.iter().map(|l| l.stats.rhs_evals).sum();
        used as f64 / (W * self.rhs_calls).max(1) as f64
    }
}

/// Lane `l` of a pack.
#[inline(always)]
fn get<const N: usize, const W: usize>(v: &[Lanes<W>; N], l: usize) -> [f64; N] {
    core::array::from_fn(|i| v[i].0[l])
}

/// The batched right-hand side, kept out of line so that the step loops
/// (four and six call sites of a long straight-line program) stay small.
/// Its effect alone was not measured (the wall-clock comparison that
/// prompted it was the machine's load, not the code; BENCHMARKS.md
/// "Ensembles and sweeps in lanes" has the CPU-time figures with it).
#[inline(never)]
fn rhs<M: OdeLanes<N>, const N: usize, const W: usize>(
    models: &[M; W],
    t: Lanes<W>,
    y: &[Lanes<W>; N],
    dy: &mut [Lanes<W>; N],
) {
    M::rhs_lanes(models, t, y, dy);
}

/// `to ← from` in the lanes marked in `mask` (a lane-wise select, which
/// vectorises; every lane at once when all are marked).
#[inline(always)]
fn take<const N: usize, const W: usize>(
    mask: &[bool; W],
    to: &mut [Lanes<W>; N],
    from: &[Lanes<W>; N],
) {
    if mask.iter().all(|&m| m) {
        *to = *from;
        return;
    }
    let m = Lanes::from_fn(|l| if mask[l] { 1.0 } else { 0.0 });
    for i in 0..N {
        to[i] = Lanes::select(m, from[i], to[i]);
    }
}

/// Index of the first non-finite entry of lane `l`.
#[inline(always)]
fn non_finite<const N: usize, const W: usize>(v: &[Lanes<W>; N], l: usize) -> Option<usize> {
    (0..N).find(|&i| !v[i].0[l].is_finite())
}

/// Integrates `W` states from `t0` to `t_end`, state `l` from `y0[l]` with
/// the parameters of `models[l]`: lane by lane what the single-state
/// integrator of the same method gives (see the module docs).
pub fn integrate_lanes<M: OdeLanes<N>, const N: usize, const W: usize>(
    models: &[M; W],
    method: LaneMethod,
    t0: f64,
    y0: &[[f64; N]; W],
    t_end: f64,
    max_steps: usize,
) -> EnsembleReport<N, W> {
    let mut lanes: [LaneResult<N>; W] = core::array::from_fn(|l| LaneResult {
        t: t0,
        y: y0[l],
        stop: StopReason::Finished,
        stats: Stats::default(),
    });
    let mut running = [true; W];
    for (l, r) in lanes.iter_mut().enumerate() {
        if let Some(component) = r.y.iter().position(|v| !v.is_finite()) {
            r.stop = StopReason::NonFinite { t: t0, component };
            running[l] = false;
        }
    }
    let mut report = EnsembleReport {
        lanes,
        rhs_calls: 0,
    };
    if t_end == t0 || !running.contains(&true) {
        return report;
    }
    match method {
        LaneMethod::Rk4 { dt } => rk4(models, dt, t0, t_end, max_steps, &mut running, &mut report),
        LaneMethod::Dopri5 { rtol, atol } => dopri5(
            models,
            &ExplicitConfig::dopri5(rtol, atol),
            t0,
            t_end,
            max_steps,
            &mut running,
            &mut report,
        ),
    }
    report
}

/// Projects the lanes marked in `moved` (after their accepted step) and
/// refreshes their right-hand side `f` at time `t`, as the single-state
/// driver's `project` and `reset_state` do.
fn project<M: OdeLanes<N>, const N: usize, const W: usize>(
    models: &[M; W],
    moved: &[bool; W],
    t: &Lanes<W>,
    y: &mut [Lanes<W>; N],
    f: &mut [Lanes<W>; N],
    report: &mut EnsembleReport<N, W>,
) {
    let mut yp = *y;
    if !M::project_lanes(models, &mut yp) {
        return;
    }
    let mut fp = [Lanes::default(); N];
    rhs::<M, N, W>(models, *t, &yp, &mut fp);
    report.rhs_calls += 1;
    take(moved, y, &yp);
    take(moved, f, &fp);
    for l in 0..W {
        if moved[l] {
            report.lanes[l].stats.rhs_evals += 1;
        }
    }
}

/// RK4 in lockstep: every lane the same `n` equal steps (as
/// [`crate::Rk4`]: `k1 = f(t0, y0)` reused from the last step).
fn rk4<M: OdeLanes<N>, const N: usize, const W: usize>(
    models: &[M; W],
    dt: f64,
    t0: f64,
    t_end: f64,
    max_steps: usize,
    running: &mut [bool; W],
    report: &mut EnsembleReport<N, W>,
) {
    if !(dt.is_finite() && dt != 0.0) {
        for l in 0..W {
            if running[l] {
                report.lanes[l].stop = StopReason::StepSizeTooSmall { t: t0, h: dt };
            }
        }
        return;
    }
    let (n, h) = uniform_steps(t0, t_end, dt);
    let mut y: [Lanes<W>; N] = core::array::from_fn(|i| Lanes::from_fn(|l| report.lanes[l].y[i]));
    let mut f = [Lanes::default(); N];
    rhs::<M, N, W>(models, Lanes::splat(t0), &y, &mut f);
    report.rhs_calls += 1;
    for l in 0..W {
        if running[l] {
            report.lanes[l].stats.rhs_evals += 1;
        }
    }
    let mut k2 = [Lanes::default(); N];
    let mut k3 = [Lanes::default(); N];
    let mut k4 = [Lanes::default(); N];
    let mut yt = [Lanes::default(); N];
    let mut t = t0;
    for k in 0..n {
        if !running.contains(&true) {
            return;
        }
        for l in 0..W {
            if running[l] && report.lanes[l].stats.steps >= max_steps {
                let r = &mut report.lanes[l];
                r.stop = StopReason::MaxSteps { t };
                r.t = t;
                r.y = get(&y, l);
                running[l] = false;
            }
        }
        let t1 = if k + 1 == n {
            t_end
        } else {
            t0 + (k + 1) as f64 * h
        };
        // The tableau of `rk4_tableau`, in its order of operations.
        let hs = t1 - t;
        let (half, full) = (Lanes::splat(0.5 * hs), Lanes::splat(hs));
        let tm = Lanes::splat(t + 0.5 * hs);
        for i in 0..N {
            yt[i] = y[i] + half * f[i];
        }
        rhs::<M, N, W>(models, tm, &yt, &mut k2);
        for i in 0..N {
            yt[i] = y[i] + half * k2[i];
        }
        rhs::<M, N, W>(models, tm, &yt, &mut k3);
        for i in 0..N {
            yt[i] = y[i] + full * k3[i];
        }
        rhs::<M, N, W>(models, Lanes::splat(t1), &yt, &mut k4);
        let sixth = Lanes::splat(hs / 6.0);
        let two = Lanes::splat(2.0);
        let mut y1 = [Lanes::default(); N];
        for i in 0..N {
            y1[i] = y[i] + sixth * (f[i] + two * (k2[i] + k3[i]) + k4[i]);
        }
        let mut f1 = [Lanes::default(); N];
        rhs::<M, N, W>(models, Lanes::splat(t1), &y1, &mut f1);
        report.rhs_calls += 4;
        let mut moved = [false; W];
        for l in 0..W {
            if !running[l] {
                continue;
            }
            let r = &mut report.lanes[l];
            r.stats.rhs_evals += 4;
            r.stats.steps += 1;
            r.stats.accepted += 1;
            if let Some(component) = non_finite(&y1, l) {
                // The driver's check after a step: stop at the last finite
                // state.
                r.stop = StopReason::NonFinite { t, component };
                r.t = t;
                r.y = get(&y, l);
                running[l] = false;
                continue;
            }
            moved[l] = true;
        }
        take(&moved, &mut y, &y1);
        take(&moved, &mut f, &f1);
        t = t1;
        project(models, &moved, &Lanes::splat(t), &mut y, &mut f, report);
    }
    for l in 0..W {
        if running[l] {
            let r = &mut report.lanes[l];
            r.t = t_end;
            r.y = get(&y, l);
            r.stop = StopReason::Finished;
        }
    }
}

/// `Lanes::splat`, short.
#[inline(always)]
fn s<const W: usize>(x: f64) -> Lanes<W> {
    Lanes::splat(x)
}

/// Hairer's `HINIT` (as `integrate::hinit`), every lane its own guess from
/// its own state, with one batched right-hand side.
#[allow(clippy::too_many_arguments)]
fn hinit_lanes<M: OdeLanes<N>, const N: usize, const W: usize>(
    models: &[M; W],
    t: f64,
    y: &[Lanes<W>; N],
    f0: &[Lanes<W>; N],
    posneg: f64,
    hmax: f64,
    cfg: &ExplicitConfig,
    running: &[bool; W],
    report: &mut EnsembleReport<N, W>,
) -> [f64; W] {
    let order = 5;
    let (rtol, atol) = (cfg.rtol, cfg.atol);
    let mut dnf = [0.0; W];
    let mut h = [0.0; W];
    for l in 0..W {
        let mut dny = 0.0;
        for i in 0..N {
            let sk = atol + rtol * y[i].0[l].abs();
            dnf[l] += (f0[i].0[l] / sk).powi(2);
            dny += (y[i].0[l] / sk).powi(2);
        }
        let hl = if dnf[l] <= 1e-10 || dny <= 1e-10 {
            1e-6
        } else {
            (dny / dnf[l]).sqrt() * 0.01
        };
        h[l] = hl.min(hmax) * posneg;
    }
    let hl = Lanes(h);
    let mut y1 = [Lanes::default(); N];
    for i in 0..N {
        y1[i] = y[i] + hl * f0[i];
    }
    let mut f1 = [Lanes::default(); N];
    rhs::<M, N, W>(models, s::<W>(t) + hl, &y1, &mut f1);
    report.rhs_calls += 1;
    core::array::from_fn(|l| {
        if running[l] {
            report.lanes[l].stats.rhs_evals += 1;
        }
        let mut der2 = 0.0;
        for i in 0..N {
            let sk = atol + rtol * y[i].0[l].abs();
            der2 += ((f1[i].0[l] - f0[i].0[l]) / sk).powi(2);
        }
        let der2 = der2.sqrt() / h[l].abs();
        let der12 = der2.max(dnf[l].sqrt());
        let h1 = if der12 <= 1e-15 || !der12.is_finite() {
            (1e-6f64).max(h[l].abs() * 1e-3)
        } else {
            (0.01 / der12).powf(1.0 / f64::from(order))
        };
        (100.0 * h[l].abs()).min(h1).min(hmax) * posneg
    })
}

/// DOPRI5 with per-lane error control (see the module docs).
fn dopri5<M: OdeLanes<N>, const N: usize, const W: usize>(
    models: &[M; W],
    cfg: &ExplicitConfig,
    t0: f64,
    t_end: f64,
    max_steps: usize,
    running: &mut [bool; W],
    report: &mut EnsembleReport<N, W>,
) {
    let expo1 = 0.2 - cfg.beta * 0.75;
    let mut y: [Lanes<W>; N] = core::array::from_fn(|i| Lanes::from_fn(|l| report.lanes[l].y[i]));
    let mut k1 = [Lanes::default(); N];
    rhs::<M, N, W>(models, s(t0), &y, &mut k1);
    report.rhs_calls += 1;
    for l in 0..W {
        if !running[l] {
            continue;
        }
        report.lanes[l].stats.rhs_evals += 1;
        if let Some(component) = non_finite(&k1, l) {
            report.lanes[l].stop = StopReason::NonFinite { t: t0, component };
            running[l] = false;
        }
    }
    // `Control::init` with the lanes' HINIT.
    let posneg = if t_end >= t0 { 1.0 } else { -1.0 };
    let hmax = if cfg.hmax.is_finite() {
        cfg.hmax.abs()
    } else {
        (t_end - t0).abs()
    };
    let h0 = hinit_lanes(models, t0, &y, &k1, posneg, hmax, cfg, running, report);
    let mut ctl: [Control; W] = core::array::from_fn(|l| {
        let mut c = Control::new();
        c.posneg = posneg;
        c.hmax = hmax;
        c.h = h0[l];
        c
    });
    let mut t = [t0; W];
    let (mut k2, mut k3, mut k4) = ([s(0.0); N], [s(0.0); N], [s(0.0); N]);
    let (mut k5, mut k6, mut k7) = ([s(0.0); N], [s(0.0); N], [s(0.0); N]);
    let (mut y1, mut ysti) = ([s(0.0); N], [s(0.0); N]);
    loop {
        // Checks before an attempt, lane by lane (the driver's end test,
        // `Control::pre_step`); a stopped lane steps by zero.
        let mut h = [0.0; W];
        for l in 0..W {
            if !running[l] {
                continue;
            }
            if t[l] == t_end {
                running[l] = false;
                report.lanes[l].stop = StopReason::Finished;
                continue;
            }
            match ctl[l].pre_step(t[l], t_end, max_steps, &mut report.lanes[l].stats) {
                Ok(()) => h[l] = ctl[l].h,
                Err(why) => {
                    running[l] = false;
                    report.lanes[l].stop = why;
                }
            }
        }
        if !running.contains(&true) {
            break;
        }
        let (tl, hl) = (Lanes(t), Lanes(h));
        for i in 0..N {
            y1[i] = y[i] + hl * s(A21) * k1[i];
        }
        rhs::<M, N, W>(models, tl + s(C2) * hl, &y1, &mut k2);
        for i in 0..N {
            y1[i] = y[i] + hl * (s(A31) * k1[i] + s(A32) * k2[i]);
        }
        rhs::<M, N, W>(models, tl + s(C3) * hl, &y1, &mut k3);
        for i in 0..N {
            y1[i] = y[i] + hl * (s(A41) * k1[i] + s(A42) * k2[i] + s(A43) * k3[i]);
        }
        rhs::<M, N, W>(models, tl + s(C4) * hl, &y1, &mut k4);
        for i in 0..N {
            y1[i] = y[i] + hl * (s(A51) * k1[i] + s(A52) * k2[i] + s(A53) * k3[i] + s(A54) * k4[i]);
        }
        rhs::<M, N, W>(models, tl + s(C5) * hl, &y1, &mut k5);
        for i in 0..N {
            ysti[i] = y[i]
                + hl * (s(A61) * k1[i]
                    + s(A62) * k2[i]
                    + s(A63) * k3[i]
                    + s(A64) * k4[i]
                    + s(A65) * k5[i]);
        }
        let tph = tl + hl;
        rhs::<M, N, W>(models, tph, &ysti, &mut k6);
        for i in 0..N {
            y1[i] = y[i]
                + hl * (s(A71) * k1[i]
                    + s(A73) * k3[i]
                    + s(A74) * k4[i]
                    + s(A75) * k5[i]
                    + s(A76) * k6[i]);
        }
        rhs::<M, N, W>(models, tph, &y1, &mut k7);
        report.rhs_calls += 6;
        // err = sqrt(mean((h Σ e_j k_j / (atol + rtol max(|y0|, |y1|)))^2)),
        // lane by lane.
        let mut err = [0.0; W];
        for i in 0..N {
            let e = hl
                * (s(E1) * k1[i]
                    + s(E3) * k3[i]
                    + s(E4) * k4[i]
                    + s(E5) * k5[i]
                    + s(E6) * k6[i]
                    + s(E7) * k7[i]);
            for l in 0..W {
                err[l] += (e.0[l] / weight(cfg.atol, cfg.rtol, y[i].0[l], y1[i].0[l])).powi(2);
            }
        }
        let mut moved = [false; W];
        for l in 0..W {
            if !running[l] {
                continue;
            }
            let stats = &mut report.lanes[l].stats;
            stats.rhs_evals += 6;
            let mut e = (err[l] / N.max(1) as f64).sqrt();
            if let Some(i) = non_finite(&y1, l).or_else(|| non_finite(&k7, l)) {
                ctl[l].nonfinite = Some(i);
                e = f64::INFINITY;
            }
            match ctl[l].decide(e, expo1, cfg, stats) {
                Verdict::Reject => {}
                Verdict::Accept { hnew } => {
                    t[l] = if ctl[l].last { t_end } else { tph.0[l] };
                    ctl[l].h = hnew;
                    moved[l] = true;
                }
            }
        }
        if moved.contains(&true) {
            take(&moved, &mut y, &y1);
            take(&moved, &mut k1, &k7);
            project(models, &moved, &Lanes(t), &mut y, &mut k1, report);
        }
    }
    for l in 0..W {
        let r = &mut report.lanes[l];
        r.t = t[l];
        r.y = get(&y, l);
    }
}

#[cfg(test)]
mod tests;
