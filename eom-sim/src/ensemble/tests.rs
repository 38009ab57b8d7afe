//! The ensemble against the single-state integrators, lane by lane, on
//! systems written both ways: the pendulum `θ̈ = −(g/L) sin θ` (lanes of
//! different lengths and amplitudes take different steps), Riccati's
//! `y' = p y²` (`y = y0 / (1 − p y0 t)`: blows up at `t = 1/(p y0)` for
//! `p y0 > 0`), and a unit vector spun about `z` projected after each step.

use super::*;
use crate::{Dopri5, OdeSystem, Rk4, SolveOptions, integrate};

/// A pendulum of length `l` (m) under `g = 9.81`.
#[derive(Clone, Copy)]
struct Pendulum {
    l: f64,
}

const G: f64 = 9.81;

impl OdeSystem<2> for Pendulum {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        dy[0] = y[1];
        dy[1] = -(G / self.l) * y[0].sin();
    }
}

impl OdeLanes<2> for Pendulum {
    fn rhs_lanes<const W: usize>(
        models: &[Self; W],
        _t: Lanes<W>,
        y: &[Lanes<W>; 2],
        dy: &mut [Lanes<W>; 2],
    ) {
        let gl = Lanes::from_fn(|l| G / models[l].l);
        dy[0] = y[1];
        dy[1] = -(gl * y[0].sin());
    }
}

/// `y' = p y²`.
#[derive(Clone, Copy)]
struct Riccati {
    p: f64,
}

impl OdeSystem<1> for Riccati {
    fn rhs(&self, _t: f64, y: &[f64; 1], dy: &mut [f64; 1]) {
        dy[0] = self.p * y[0] * y[0];
    }
}

impl OdeLanes<1> for Riccati {
    fn rhs_lanes<const W: usize>(
        models: &[Self; W],
        _t: Lanes<W>,
        y: &[Lanes<W>; 1],
        dy: &mut [Lanes<W>; 1],
    ) {
        dy[0] = Lanes::from_fn(|l| models[l].p) * y[0] * y[0];
    }
}

/// `ẋ = −ω y, ẏ = ω x` with `(x, y)` normalised after every step.
#[derive(Clone, Copy)]
struct Spin {
    omega: f64,
}

impl OdeSystem<2> for Spin {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        dy[0] = -self.omega * y[1];
        dy[1] = self.omega * y[0];
    }
    fn project(&self, _t: f64, y: &mut [f64; 2]) -> bool {
        let n = (y[0] * y[0] + y[1] * y[1]).sqrt();
        y[0] /= n;
        y[1] /= n;
        true
    }
}

impl OdeLanes<2> for Spin {
    fn rhs_lanes<const W: usize>(
        models: &[Self; W],
        _t: Lanes<W>,
        y: &[Lanes<W>; 2],
        dy: &mut [Lanes<W>; 2],
    ) {
        let w = Lanes::from_fn(|l| models[l].omega);
        dy[0] = -(w * y[1]);
        dy[1] = w * y[0];
    }
    fn project_lanes<const W: usize>(_models: &[Self; W], y: &mut [Lanes<W>; 2]) -> bool {
        let n = (y[0] * y[0] + y[1] * y[1]).sqrt();
        y[0] = y[0] / n;
        y[1] = y[1] / n;
        true
    }
}

/// The single-state run of `sys` from `y0` with the ensemble's method.
fn single<const N: usize, S: OdeSystem<N>>(
    sys: &S,
    method: LaneMethod,
    y0: [f64; N],
    t_end: f64,
    max_steps: usize,
) -> crate::Solution<N> {
    let opts = SolveOptions {
        max_steps,
        ..SolveOptions::default()
    };
    match method {
        LaneMethod::Rk4 { dt } => integrate(&mut Rk4::new(dt), sys, 0.0, y0, t_end, &opts, &mut []),
        LaneMethod::Dopri5 { rtol, atol } => integrate(
            &mut Dopri5::new(rtol, atol),
            sys,
            0.0,
            y0,
            t_end,
            &opts,
            &mut [],
        ),
    }
}

/// Lane `l` against the single-state run: the same stop, the same
/// counters (the same steps, accepted and rejected), and the state to
/// `tol` of its scale.
fn agree<const N: usize>(lane: &LaneResult<N>, sol: &crate::Solution<N>, tol: f64, what: &str) {
    assert_eq!(lane.stop, sol.stop, "{what}: stop");
    assert_eq!(lane.t, sol.t_final, "{what}: t");
    assert_eq!(lane.stats.steps, sol.stats.steps, "{what}: steps");
    assert_eq!(lane.stats.accepted, sol.stats.accepted, "{what}: accepted");
    assert_eq!(lane.stats.rejected, sol.stats.rejected, "{what}: rejected");
    assert_eq!(lane.stats.rhs_evals, sol.stats.rhs_evals, "{what}: rhs");
    if let StopReason::NonFinite { t, .. } = sol.stop
        && t > 0.0
    {
        // The single-state driver interpolates at the last finite step
        // with the non-finite end of the step, which gives NaN (0 · ∞);
        // the lane keeps its last finite state.
        assert!(lane.y.iter().all(|x| x.is_finite()), "{what}: {:?}", lane.y);
        return;
    }
    for i in 0..N {
        let (got, want) = (lane.y[i], sol.y_final[i]);
        assert!(
            (got.is_nan() && want.is_nan()) || (got - want).abs() <= tol * want.abs().max(1.0),
            "{what}: y[{i}] got {got:e} want {want:e}"
        );
    }
}

/// Four pendulums (lengths 0.5–2 m, amplitudes 0.1–3 rad: nearly linear to
/// nearly inverted) over 5 s. Each lane takes its own steps (DOPRI5) and
/// ends where its single-state run ends: the same step sequence, so the
/// states differ only by the rounding of the lanes' `sin` (1 ulp,
/// amplified over ~100 steps): 1e-12 relative, four orders below the
/// `rtol = 1e-8` that bounds the integration error itself.
#[test]
fn dopri5_lanes_are_the_single_state_runs() {
    let models = [0.5, 1.0, 1.5, 2.0].map(|l| Pendulum { l });
    let y0 = [[0.1, 0.0], [1.0, 0.5], [2.0, -1.0], [3.0, 0.0]];
    let method = LaneMethod::Dopri5 {
        rtol: 1e-8,
        atol: 1e-10,
    };
    let r = integrate_lanes(&models, method, 0.0, &y0, 5.0, 100_000);
    let steps: Vec<usize> = r.lanes.iter().map(|l| l.stats.steps).collect();
    assert!(
        steps.iter().any(|&s| s != steps[0]),
        "the lanes should take different numbers of steps: {steps:?}"
    );
    for l in 0..4 {
        let sol = single(&models[l], method, y0[l], 5.0, 100_000);
        agree(&r.lanes[l], &sol, 1e-12, &format!("lane {l}"));
    }
    let u = r.utilisation();
    assert!(u > 0.0 && u <= 1.0, "utilisation {u}");
}

/// RK4 in lockstep, eight lanes: every lane the single-state RK4 run (the
/// same 500 steps; the states to the rounding of `sin`).
#[test]
fn rk4_lanes_are_the_single_state_runs() {
    let models: [Pendulum; 8] = core::array::from_fn(|l| Pendulum {
        l: 0.5 + 0.25 * l as f64,
    });
    let y0: [[f64; 2]; 8] = core::array::from_fn(|l| [0.3 * l as f64, 0.1]);
    let method = LaneMethod::Rk4 { dt: 0.01 };
    let r = integrate_lanes(&models, method, 0.0, &y0, 5.0, 100_000);
    for l in 0..8 {
        let sol = single(&models[l], method, y0[l], 5.0, 100_000);
        assert_eq!(sol.stats.steps, 500);
        agree(&r.lanes[l], &sol, 1e-12, &format!("lane {l}"));
    }
    assert_eq!(r.utilisation(), 1.0);
}

/// One lane blows up (`y' = y²` from 1: `y → ∞` at `t = 1`), one starts
/// non-finite, one runs out of steps; the others finish on the closed form
/// `y = y0 / (1 − p y0 t)`, and every lane reports what its single-state
/// run reports, for both methods.
#[test]
fn a_failing_lane_stops_alone() {
    let models = [1.0, -1.0, -2.0, -0.5].map(|p| Riccati { p });
    let y0 = [[1.0], [1.0], [f64::NAN], [1.0]];
    for method in [
        LaneMethod::Dopri5 {
            rtol: 1e-9,
            atol: 1e-12,
        },
        LaneMethod::Rk4 { dt: 1e-3 },
    ] {
        let r = integrate_lanes(&models, method, 0.0, &y0, 2.0, 100_000);
        assert!(
            !matches!(r.lanes[0].stop, StopReason::Finished),
            "{method:?}: the blow-up should stop lane 0"
        );
        assert!(
            matches!(r.lanes[2].stop, StopReason::NonFinite { t: 0.0, .. }),
            "{method:?}: {:?}",
            r.lanes[2].stop
        );
        for l in [1, 3] {
            assert_eq!(r.lanes[l].stop, StopReason::Finished);
            let want = 1.0 / (1.0 - models[l].p * 2.0);
            let got = r.lanes[l].y[0];
            assert!(
                (got - want).abs() < 1e-7,
                "{method:?} lane {l}: got {got} want {want}"
            );
        }
        for l in 0..4 {
            let sol = single(&models[l], method, y0[l], 2.0, 100_000);
            // The blown-up lane's last state is huge: compare relatively.
            agree(&r.lanes[l], &sol, 1e-12, &format!("{method:?} lane {l}"));
        }
        // Too few steps for lane 3 only (p = −0.5 is the smoothest: it
        // takes the fewest steps, so give it a pack of its own).
        let few = integrate_lanes(&[models[3]; 2], method, 0.0, &[[1.0], [1.0]], 2.0, 3);
        for lane in &few.lanes {
            assert!(
                matches!(lane.stop, StopReason::MaxSteps { .. }),
                "{:?}",
                lane.stop
            );
            let sol = single(&models[3], method, [1.0], 2.0, 3);
            agree(lane, &sol, 1e-14, &format!("{method:?} max steps"));
        }
    }
}

/// Projection after every accepted step, as the single-state driver does
/// (and the right-hand side refreshed at the projected state): the unit
/// vector stays on the circle, each lane the single-state run.
#[test]
fn projection_follows_each_accepted_step() {
    let models = [1.0, 2.0, 5.0, 0.1].map(|omega| Spin { omega });
    let y0 = [[1.0, 0.0]; 4];
    for method in [
        LaneMethod::Dopri5 {
            rtol: 1e-6,
            atol: 1e-9,
        },
        LaneMethod::Rk4 { dt: 0.05 },
    ] {
        let r = integrate_lanes(&models, method, 0.0, &y0, 3.0, 100_000);
        for l in 0..4 {
            let y = r.lanes[l].y;
            assert!((y[0].hypot(y[1]) - 1.0).abs() < 1e-15);
            let sol = single(&models[l], method, y0[l], 3.0, 100_000);
            agree(&r.lanes[l], &sol, 1e-13, &format!("{method:?} lane {l}"));
        }
    }
}

/// A run of zero length is finished at once, without evaluating anything
/// (as the single-state driver).
#[test]
fn zero_length_run_is_finished() {
    let r = integrate_lanes(
        &[Riccati { p: 1.0 }; 2],
        LaneMethod::Rk4 { dt: 0.1 },
        1.0,
        &[[1.0], [2.0]],
        1.0,
        10,
    );
    for lane in &r.lanes {
        assert_eq!(lane.stop, StopReason::Finished);
        assert_eq!(lane.stats.rhs_evals, 0);
    }
}
