//! Work-precision table: error at t_end against f evaluations and CPU time.
//!
//! Run with `cargo bench -p eom-sim --bench work_precision`. Prints a
//! markdown table; CPU time is the median of repeated runs (at least 5,
//! and at least ~0.2 s of total work per row) because the machine is shared
//! and noisy.

// Published constants keep all their digits.
#![allow(clippy::excessive_precision, clippy::needless_range_loop)]

use std::time::Instant;

use eom_sim::{Dop853, Dopri5, OdeSystem, Radau5, Rk4, Solution, SolveOptions, Stepper, integrate};

const MU: f64 = 0.012277471;
const Y0: [f64; 4] = [0.994, 0.0, 0.0, -2.00158510637908252240537862224];
const T: f64 = 17.0652165601579625588917206249;

struct Arenstorf;
impl OdeSystem<4> for Arenstorf {
    fn rhs(&self, _t: f64, y: &[f64; 4], dy: &mut [f64; 4]) {
        let mup = 1.0 - MU;
        let r1 = ((y[0] + MU).powi(2) + y[1] * y[1]).powf(1.5);
        let r2 = ((y[0] - mup).powi(2) + y[1] * y[1]).powf(1.5);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = y[0] + 2.0 * y[3] - mup * (y[0] + MU) / r1 - MU * (y[0] - mup) / r2;
        dy[3] = y[1] - 2.0 * y[2] - mup * y[1] / r1 - MU * y[1] / r2;
    }
}

struct VanDerPol;
const EPS: f64 = 1e-6;
impl OdeSystem<2> for VanDerPol {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        dy[0] = y[1];
        dy[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / EPS;
    }
    fn jacobian(&self, _t: f64, y: &[f64; 2], j: &mut nalgebra::SMatrix<f64, 2, 2>) -> bool {
        j[(0, 0)] = 0.0;
        j[(0, 1)] = 1.0;
        j[(1, 0)] = (-2.0 * y[0] * y[1] - 1.0) / EPS;
        j[(1, 1)] = (1.0 - y[0] * y[0]) / EPS;
        true
    }
}
const VDP_REF: [f64; 2] = [1.706167732170469, -0.8928097010248125];

fn timed<const N: usize, M: Stepper<N>, S: OdeSystem<N>>(
    make: impl Fn() -> M,
    sys: &S,
    y0: [f64; N],
    t_end: f64,
) -> (Solution<N>, f64) {
    let opts = SolveOptions {
        record_steps: false,
        max_steps: 10_000_000,
        ..SolveOptions::default()
    };
    let mut times = Vec::new();
    let start = Instant::now();
    let mut sol = None;
    while times.len() < 5 || (start.elapsed().as_secs_f64() < 0.2 && times.len() < 500) {
        let mut m = make();
        let t0 = Instant::now();
        let s = integrate(&mut m, sys, 0.0, y0, t_end, &opts, &mut []);
        times.push(t0.elapsed().as_secs_f64());
        sol = Some(s);
    }
    times.sort_by(f64::total_cmp);
    (sol.expect("ran"), times[times.len() / 2])
}

fn row<const N: usize>(method: &str, param: &str, sol: &Solution<N>, err: f64, secs: f64) {
    assert_eq!(sol.stop, eom_sim::StopReason::Finished, "{method} {param}");
    println!(
        "| {method} | {param} | {err:.2e} | {} | {} | {} | {} | {:.1} |",
        sol.stats.rhs_evals,
        sol.stats.accepted,
        sol.stats.rejected,
        sol.stats.lu_decomps,
        secs * 1e6
    );
}

fn main() {
    // Ignore the harness's arguments (e.g. --bench).
    println!("### Arenstorf orbit, one period, error = max_i |y_i(T) - y_i(0)|\n");
    println!(
        "| method | rtol = atol / h | error | f evals | accepted | rejected | LU | median µs |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    let arenstorf_err = |y: &[f64; 4]| (0..4).map(|i| (y[i] - Y0[i]).abs()).fold(0.0, f64::max);
    for k in 3..=12 {
        let tol = 10f64.powi(-k);
        let (s, t) = timed(|| Dopri5::<4>::new(tol, tol), &Arenstorf, Y0, T);
        row(
            "DOPRI5",
            &format!("1e-{k}"),
            &s,
            arenstorf_err(&s.y_final),
            t,
        );
    }
    for k in 3..=12 {
        let tol = 10f64.powi(-k);
        let (s, t) = timed(|| Dop853::<4>::new(tol, tol), &Arenstorf, Y0, T);
        row(
            "DOP853",
            &format!("1e-{k}"),
            &s,
            arenstorf_err(&s.y_final),
            t,
        );
    }
    for n in [
        2000usize, 5000, 10_000, 20_000, 50_000, 100_000, 200_000, 500_000,
    ] {
        let h = T / n as f64;
        let (s, t) = timed(|| Rk4::<4>::new(h), &Arenstorf, Y0, T);
        row(
            "RK4",
            &format!("h = T/{n}"),
            &s,
            arenstorf_err(&s.y_final),
            t,
        );
    }
    println!(
        "\n### Van der Pol, ε = 1e-6, y0 = (2, 0), t ∈ [0, 2], analytic Jacobian; error = max_i |y_i(2) - ref_i| (Test Set reference)\n"
    );
    println!("| method | rtol = atol | error | f evals | accepted | rejected | LU | median µs |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- |");
    for k in 3..=12 {
        let tol = 10f64.powi(-k);
        let (s, t) = timed(|| Radau5::<2>::new(tol, tol), &VanDerPol, [2.0, 0.0], 2.0);
        let err = (0..2)
            .map(|i| (s.y_final[i] - VDP_REF[i]).abs())
            .fold(0.0, f64::max);
        row("RADAU5", &format!("1e-{k}"), &s, err, t);
    }
}
