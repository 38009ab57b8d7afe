//! Observed orders of convergence and of dense output.
//!
//! Global error of a method of order p with constant step h behaves like
//! C h^p, so the least-squares slope of log(err) against log(h) estimates
//! p. For dense output the local interpolation error after ONE step from
//! exact data is O(h^{p*+1}) for a continuous extension of order p*.

// Reference values keep their published digits; loops mirror the formulas.
#![allow(clippy::excessive_precision, clippy::needless_range_loop)]

use crate::common;

use common::*;
use eom_sim::{Euler, ImplicitMidpoint, OdeSystem, Rk4, SolveOptions, Stepper, integrate};

const T_END: f64 = 5.0;

fn global_error<M: Stepper<1>>(mut m: M) -> f64 {
    let sol = integrate(
        &mut m,
        &Forced,
        0.0,
        [1.0],
        T_END,
        &SolveOptions::default(),
        &mut [],
    );
    assert_eq!(sol.stop, eom_sim::StopReason::Finished);
    (sol.y_final[0] - forced_exact(T_END)).abs()
}

fn check_order<M: Stepper<1>>(
    name: &str,
    make: impl Fn(f64) -> M,
    ns: &[usize],
    p: f64,
    band: f64,
) {
    let hs: Vec<f64> = ns.iter().map(|&n| T_END / n as f64).collect();
    let errs: Vec<f64> = hs.iter().map(|&h| global_error(make(h))).collect();
    let s = slope(&hs, &errs);
    eprintln!("{name}: h = {hs:?}\n  err = {errs:?}\n  observed order {s:.3}");
    assert!(
        (s - p).abs() <= band,
        "{name}: observed order got {s:.3} want {p} ± {band} (errors {errs:?})"
    );
}

#[test]
fn euler_is_order_1() {
    check_order(
        "Euler",
        Euler::<1>::new,
        &[100, 200, 400, 800, 1600],
        1.0,
        0.1,
    );
}

#[test]
fn rk4_is_order_4() {
    check_order("RK4", Rk4::<1>::new, &[10, 20, 40, 80, 160], 4.0, 0.2);
}

#[test]
fn implicit_midpoint_is_order_2() {
    check_order(
        "implicit midpoint",
        ImplicitMidpoint::<1>::new,
        &[10, 20, 40, 80, 160],
        2.0,
        0.1,
    );
}

#[test]
fn dopri5_is_order_5() {
    check_order(
        "DOPRI5",
        dopri5_fixed::<1>,
        &[10, 20, 40, 80, 160],
        5.0,
        0.3,
    );
}

#[test]
fn dop853_is_order_8() {
    // The forced problem reaches round-off before the asymptotic regime is
    // clean; the harmonic oscillator over [0, 40] (error growing linearly
    // in t) keeps the errors between 1e-6 and 1e-11.
    let t_end = 40.0;
    let ns = [40usize, 56, 80, 113, 160];
    let hs: Vec<f64> = ns.iter().map(|&n| t_end / n as f64).collect();
    let errs: Vec<f64> = hs
        .iter()
        .map(|&h| {
            let mut m = dop853_fixed::<2>(h);
            let sol = integrate(
                &mut m,
                &Osc,
                0.0,
                [1.0, 0.0],
                t_end,
                &SolveOptions::default(),
                &mut [],
            );
            (sol.y_final[0] - t_end.cos())
                .abs()
                .max((sol.y_final[1] + t_end.sin()).abs())
        })
        .collect();
    let s = slope(&hs, &errs);
    eprintln!("DOP853: h = {hs:?}\n  err = {errs:?}\n  observed order {s:.3}");
    assert!(
        (s - 8.0).abs() <= 0.4,
        "DOP853: observed order got {s:.3} want 8 ± 0.4 (errors {errs:?})"
    );
}

#[test]
fn radau5_is_order_5() {
    check_order(
        "RADAU5",
        radau5_fixed::<1>,
        &[10, 20, 40, 80, 160],
        5.0,
        0.3,
    );
}

/// Harmonic oscillator y1' = y2, y2' = -y1 with y(0) = (1, 0): y = (cos t, -sin t).
struct Osc;
impl OdeSystem<2> for Osc {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        dy[0] = y[1];
        dy[1] = -y[0];
    }
}

/// Max dense-output error inside one step of size h from the exact value
/// at t0 = 0.3.
fn one_step_dense_error<M: Stepper<2>>(mut m: M, h: f64) -> f64 {
    let t0 = 0.3;
    let thetas = [0.1, 0.25, 0.4, 0.5, 0.6, 0.75, 0.9];
    let opts = SolveOptions {
        t_eval: thetas.iter().map(|th| t0 + th * h).collect(),
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut m,
        &Osc,
        t0,
        [t0.cos(), -t0.sin()],
        t0 + h,
        &opts,
        &mut [],
    );
    assert_eq!(
        sol.stats.accepted, 1,
        "expected one step, stats {:?}",
        sol.stats
    );
    let mut e: f64 = 0.0;
    for (t, y) in sol.t_out.iter().zip(&sol.y_out) {
        e = e.max((y[0] - t.cos()).abs()).max((y[1] + t.sin()).abs());
    }
    e
}

fn check_dense<M: Stepper<2>>(
    name: &str,
    make: impl Fn(f64) -> M,
    hs: &[f64],
    p_local: f64,
    band: f64,
) {
    let errs: Vec<f64> = hs
        .iter()
        .map(|&h| one_step_dense_error(make(h), h))
        .collect();
    let s = slope(hs, &errs);
    eprintln!("{name} dense: h = {hs:?}\n  err = {errs:?}\n  observed local order {s:.3}");
    assert!(
        (s - p_local).abs() <= band,
        "{name} dense output: local error exponent got {s:.3} want {p_local} ± {band} (errors {errs:?})"
    );
}

#[test]
fn dopri5_dense_output_is_order_4() {
    // 4th-order continuous extension: local error O(h^5).
    check_dense("DOPRI5", dopri5_fixed::<2>, &[0.8, 0.4, 0.2, 0.1], 5.0, 0.3);
}

#[test]
fn dop853_dense_output_is_order_7() {
    // 7th-order continuous extension: local error O(h^8).
    check_dense(
        "DOP853",
        dop853_fixed::<2>,
        &[1.6, 1.2, 0.8, 0.6, 0.4],
        8.0,
        0.5,
    );
}

#[test]
fn radau5_dense_output_is_collocation_order_3() {
    // Collocation polynomial of degree 3 (stage order 3): local error O(h^4).
    check_dense(
        "RADAU5",
        radau5_fixed::<2>,
        &[0.4, 0.2, 0.1, 0.05],
        4.0,
        0.3,
    );
}

#[test]
fn rk4_hermite_dense_output_is_order_3() {
    // Cubic Hermite through O(h^5)-accurate end data: local error O(h^4).
    check_dense("RK4", Rk4::<2>::new, &[0.4, 0.2, 0.1, 0.05], 4.0, 0.3);
}
