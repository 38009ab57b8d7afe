//! Events, dense sampling, non-finite states, limits.

// Reference values keep their published digits; loops mirror the formulas.
#![allow(clippy::excessive_precision, clippy::needless_range_loop)]

use crate::common;

use common::*;
use eom_sim::{
    Direction, Dop853, Dopri5, Euler, Event, EventAction, FnSystem, ImplicitMidpoint, OdeSystem,
    Radau5, Rk4, SolveOptions, Stepper, StopReason, integrate,
};
use std::f64::consts::PI;

/// y1' = y2, y2' = -y1, y(0) = (1, 0): y1 = cos t.
struct Osc;
impl OdeSystem<2> for Osc {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        dy[0] = y[1];
        dy[1] = -y[0];
    }
}

fn stop_at_first_zero<M: Stepper<2>>(name: &str, mut m: M, tol: f64) {
    let mut events = [Event::new(
        |_t, y: &[f64; 2]| y[0],
        Direction::Falling,
        EventAction::Stop,
    )];
    let s = integrate(
        &mut m,
        &Osc,
        0.0,
        [1.0, 0.0],
        10.0,
        &SolveOptions::default(),
        &mut events,
    );
    let StopReason::EventStop { index, t } = s.stop else {
        panic!("{name}: got {:?} want EventStop", s.stop);
    };
    assert_eq!(index, 0);
    eprintln!(
        "{name}: event at {t:.17} (π/2 error {:.2e}), y = {:?}",
        (t - PI / 2.0).abs(),
        s.y_final
    );
    assert!(
        (t - PI / 2.0).abs() < tol,
        "{name}: event time got {t} want π/2 ± {tol:e}"
    );
    assert_eq!(s.t_final, t);
    assert!(
        s.y_final[0] <= 0.0 && s.y_final[0].abs() < 1e-9,
        "{name}: y at event {:?}",
        s.y_final
    );
}

/// cos t crosses zero (falling) at π/2; located on the dense output to
/// 1e-10 by every adaptive method at tight tolerance.
#[test]
fn terminal_event_located_to_1e_10() {
    stop_at_first_zero("DOPRI5", Dopri5::<2>::new(1e-12, 1e-12), 1e-10);
    stop_at_first_zero("DOP853", Dop853::<2>::new(1e-12, 1e-12), 1e-10);
    stop_at_first_zero("RADAU5", Radau5::<2>::new(1e-12, 1e-12), 1e-10);
    // Fixed step with Hermite dense output: accuracy h^4-limited.
    stop_at_first_zero("RK4 h=0.01", Rk4::<2>::new(0.01), 1e-8);
}

/// Record mode with direction filters: on [0, 10] cos t has zeros at π/2,
/// 3π/2, 5π/2 (falling, rising, falling); the ball-like event y1 = 0.5
/// crosses six times.
#[test]
fn recorded_events_with_direction_filter() {
    let mut events = [
        Event::new(
            |_t, y: &[f64; 2]| y[0],
            Direction::Both,
            EventAction::Record,
        ),
        Event::new(
            |_t, y: &[f64; 2]| y[0],
            Direction::Rising,
            EventAction::Record,
        ),
        Event::new(
            |_t, y: &[f64; 2]| y[0] - 0.5,
            Direction::Falling,
            EventAction::Record,
        ),
    ];
    let mut m = Dopri5::<2>::new(1e-10, 1e-10);
    let s = integrate(
        &mut m,
        &Osc,
        0.0,
        [1.0, 0.0],
        10.0,
        &SolveOptions::default(),
        &mut events,
    );
    assert_eq!(s.stop, StopReason::Finished);
    let times = |i: usize| {
        s.events
            .iter()
            .filter(|e| e.index == i)
            .map(|e| e.t)
            .collect::<Vec<_>>()
    };
    let both = times(0);
    let rising = times(1);
    let half = times(2);
    let want_both = [PI / 2.0, 1.5 * PI, 2.5 * PI];
    assert_eq!(both.len(), 3, "got {both:?} want {want_both:?}");
    for (g, w) in both.iter().zip(want_both) {
        assert!((g - w).abs() < 1e-9, "got {g} want {w}");
    }
    assert_eq!(rising.len(), 1, "rising filter got {rising:?}");
    assert!((rising[0] - 1.5 * PI).abs() < 1e-9);
    // cos t = 0.5 falling at π/3, 2π + π/3 (≈ 6.81), and 4π + π/3 > 10.
    let want_half = [PI / 3.0, 2.0 * PI + PI / 3.0];
    assert_eq!(half.len(), 2, "got {half:?} want {want_half:?}");
    for (g, w) in half.iter().zip(want_half) {
        assert!((g - w).abs() < 1e-9, "got {g} want {w}");
    }
    // Events come out in time order.
    assert!(s.events.windows(2).all(|w| w[0].t <= w[1].t));
}

/// A falling ball y'' = -9.81 from height 10 hits the ground at
/// t = sqrt(2·10/9.81).
#[test]
fn ball_hits_ground() {
    let ball = FnSystem(|_t: f64, y: &[f64; 2], dy: &mut [f64; 2]| {
        dy[0] = y[1];
        dy[1] = -9.81;
    });
    let mut ev = [Event::new(
        |_t, y: &[f64; 2]| y[0],
        Direction::Falling,
        EventAction::Stop,
    )];
    let mut m = Dop853::<2>::new(1e-10, 1e-10);
    let s = integrate(
        &mut m,
        &ball,
        0.0,
        [10.0, 0.0],
        5.0,
        &SolveOptions::default(),
        &mut ev,
    );
    let want = (20.0f64 / 9.81).sqrt();
    let StopReason::EventStop { t, .. } = s.stop else {
        panic!("got {:?}", s.stop)
    };
    assert!((t - want).abs() < 1e-12, "impact got {t} want {want}");
}

/// Dense sampling every DT reproduces the exact solution between steps.
#[test]
fn dense_sampling_every_dt() {
    let opts = SolveOptions::every(0.0, 10.0, 0.1);
    assert_eq!(opts.t_eval.len(), 101);
    for (name, mut errs) in [
        ("DOPRI5", {
            let mut m = Dopri5::<1>::new(1e-10, 1e-10);
            let s = integrate(&mut m, &Forced, 0.0, [1.0], 10.0, &opts, &mut []);
            assert!(
                s.t.is_empty(),
                "steps not recorded when record_steps = false"
            );
            s.t_out
                .iter()
                .zip(&s.y_out)
                .map(|(t, y)| (y[0] - forced_exact(*t)).abs())
                .collect::<Vec<_>>()
        }),
        ("DOP853", {
            let mut m = Dop853::<1>::new(1e-10, 1e-10);
            let s = integrate(&mut m, &Forced, 0.0, [1.0], 10.0, &opts, &mut []);
            s.t_out
                .iter()
                .zip(&s.y_out)
                .map(|(t, y)| (y[0] - forced_exact(*t)).abs())
                .collect::<Vec<_>>()
        }),
        ("RADAU5", {
            let mut m = Radau5::<1>::new(1e-10, 1e-10);
            let s = integrate(&mut m, &Forced, 0.0, [1.0], 10.0, &opts, &mut []);
            s.t_out
                .iter()
                .zip(&s.y_out)
                .map(|(t, y)| (y[0] - forced_exact(*t)).abs())
                .collect::<Vec<_>>()
        }),
    ] {
        assert_eq!(errs.len(), 101, "{name}: sample count");
        errs.sort_by(f64::total_cmp);
        let worst = errs[100];
        eprintln!("{name}: worst dense-sample error {worst:.2e}");
        assert!(
            worst < 1e-8,
            "{name}: dense sample error got {worst:e} want < 1e-8"
        );
    }
}

/// Integration backwards in time: from t = 5 with the exact value back to 0.
#[test]
fn backward_integration() {
    let y5 = [forced_exact(5.0)];
    let mut m = Dopri5::<1>::new(1e-10, 1e-10);
    let s = integrate(
        &mut m,
        &Forced,
        5.0,
        y5,
        0.0,
        &SolveOptions::default(),
        &mut [],
    );
    assert_eq!(s.stop, StopReason::Finished);
    assert_eq!(s.t_final, 0.0);
    assert!(
        (s.y_final[0] - 1.0).abs() < 1e-8,
        "got {} want 1",
        s.y_final[0]
    );
    let mut r = Radau5::<1>::new(1e-10, 1e-10);
    let s = integrate(
        &mut r,
        &Forced,
        5.0,
        y5,
        0.0,
        &SolveOptions::default(),
        &mut [],
    );
    assert!(
        (s.y_final[0] - 1.0).abs() < 1e-8,
        "RADAU5 got {} want 1",
        s.y_final[0]
    );
}

/// y' = y², y(0) = 1 blows up at t = 1 (y = 1/(1 - t)). Every method must
/// stop cleanly near t = 1 with NonFinite or StepSizeTooSmall (or MaxSteps
/// for fixed-step methods that cannot reach overflow), never panic or loop.
#[test]
fn blow_up_stops_cleanly() {
    let sys = FnSystem(|_t: f64, y: &[f64; 1], dy: &mut [f64; 1]| dy[0] = y[0] * y[0]);
    let opts = SolveOptions::default();
    let check = |name: &str, stop: StopReason, t: f64| {
        eprintln!("{name}: {stop:?} at t = {t}");
        assert!(
            matches!(
                stop,
                StopReason::NonFinite { component: 0, .. } | StopReason::StepSizeTooSmall { .. }
            ),
            "{name}: got {stop:?}"
        );
        assert!(t <= 1.0 + 0.02 && t > 0.9, "{name}: stopped at t = {t}");
    };
    let s = integrate(
        &mut Dopri5::<1>::new(1e-8, 1e-8),
        &sys,
        0.0,
        [1.0],
        2.0,
        &opts,
        &mut [],
    );
    check("DOPRI5", s.stop, s.t_final);
    let s = integrate(
        &mut Dop853::<1>::new(1e-8, 1e-8),
        &sys,
        0.0,
        [1.0],
        2.0,
        &opts,
        &mut [],
    );
    check("DOP853", s.stop, s.t_final);
    let s = integrate(
        &mut Radau5::<1>::new(1e-8, 1e-8),
        &sys,
        0.0,
        [1.0],
        2.0,
        &opts,
        &mut [],
    );
    check("RADAU5", s.stop, s.t_final);
    let s = integrate(
        &mut Rk4::<1>::new(0.01),
        &sys,
        0.0,
        [1.0],
        2.0,
        &opts,
        &mut [],
    );
    check("RK4", s.stop, s.t_final);
    let s = integrate(
        &mut Euler::<1>::new(0.01),
        &sys,
        0.0,
        [1.0],
        2.0,
        &opts,
        &mut [],
    );
    assert!(
        matches!(s.stop, StopReason::NonFinite { .. } | StopReason::Finished),
        "Euler {:?}",
        s.stop
    );
    let s = integrate(
        &mut ImplicitMidpoint::<1>::new(0.01),
        &sys,
        0.0,
        [1.0],
        2.0,
        &opts,
        &mut [],
    );
    eprintln!("midpoint: {:?} at {}", s.stop, s.t_final);
    assert!(
        matches!(
            s.stop,
            StopReason::NonFinite { .. } | StopReason::ConvergenceFailure { .. }
        ),
        "midpoint got {:?}",
        s.stop
    );
}

/// A NaN appearing in one component (sqrt of a negative number once
/// y0 > 1 at t = 1) is reported with the component index.
#[test]
fn nan_component_is_named() {
    let sys = FnSystem(|_t: f64, y: &[f64; 3], dy: &mut [f64; 3]| {
        dy[0] = 1.0;
        dy[1] = 0.0;
        dy[2] = (1.0 - y[0]).sqrt();
    });
    let opts = SolveOptions::default();
    let s = integrate(
        &mut Rk4::<3>::new(0.03),
        &sys,
        0.0,
        [0.0; 3],
        2.0,
        &opts,
        &mut [],
    );
    eprintln!("RK4: {:?}", s.stop);
    assert!(
        matches!(s.stop, StopReason::NonFinite { component: 2, t } if t > 0.9 && t <= 1.0),
        "got {:?}",
        s.stop
    );
    for (name, stop) in [
        (
            "DOPRI5",
            integrate(
                &mut Dopri5::<3>::new(1e-8, 1e-8),
                &sys,
                0.0,
                [0.0; 3],
                2.0,
                &opts,
                &mut [],
            )
            .stop,
        ),
        (
            "DOP853",
            integrate(
                &mut Dop853::<3>::new(1e-8, 1e-8),
                &sys,
                0.0,
                [0.0; 3],
                2.0,
                &opts,
                &mut [],
            )
            .stop,
        ),
        (
            "RADAU5",
            integrate(
                &mut Radau5::<3>::new(1e-8, 1e-8),
                &sys,
                0.0,
                [0.0; 3],
                2.0,
                &opts,
                &mut [],
            )
            .stop,
        ),
    ] {
        eprintln!("{name}: {stop:?}");
        assert!(
            matches!(stop, StopReason::NonFinite { component: 2, t } if (t - 1.0).abs() < 1e-3),
            "{name}: got {stop:?} want NonFinite {{ component: 2, t ≈ 1 }}"
        );
    }
    // A non-finite initial state is rejected before any step.
    let s = integrate(
        &mut Dopri5::<3>::new(1e-6, 1e-6),
        &sys,
        0.0,
        [0.0, f64::NAN, 0.0],
        1.0,
        &opts,
        &mut [],
    );
    assert_eq!(
        s.stop,
        StopReason::NonFinite {
            t: 0.0,
            component: 1
        }
    );
}

#[test]
fn max_steps_is_enforced() {
    let opts = SolveOptions {
        max_steps: 50,
        ..SolveOptions::default()
    };
    let s = integrate(
        &mut Dopri5::<4>::new(1e-12, 1e-12),
        &Arenstorf,
        0.0,
        ARENSTORF_Y0,
        ARENSTORF_T,
        &opts,
        &mut [],
    );
    assert!(
        matches!(s.stop, StopReason::MaxSteps { .. }),
        "got {:?}",
        s.stop
    );
    assert_eq!(s.stats.steps, 50);
    let s = integrate(
        &mut Rk4::<4>::new(1e-3),
        &Arenstorf,
        0.0,
        ARENSTORF_Y0,
        ARENSTORF_T,
        &opts,
        &mut [],
    );
    assert!(
        matches!(s.stop, StopReason::MaxSteps { .. }),
        "got {:?}",
        s.stop
    );
    let s = integrate(
        &mut Radau5::<2>::new(1e-10, 1e-10),
        &VanDerPol {
            eps: 1e-6,
            analytic_jacobian: false,
        },
        0.0,
        [2.0, 0.0],
        2.0,
        &opts,
        &mut [],
    );
    assert!(
        matches!(s.stop, StopReason::MaxSteps { .. }),
        "got {:?}",
        s.stop
    );
}
