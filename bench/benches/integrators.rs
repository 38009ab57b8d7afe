//! Right-hand-side evaluations, CPU time and energy error of the runtime's
//! integrators on compiled models: 10 s of double_pendulum and arm7 at
//! rtol = atol = 1e-6, 1e-9, 1e-12, and RK4 at h = 1e-3 s (median of 5
//! runs).
//!
//! `cargo bench -p eom-bench --bench integrators`

use eom_sim::{Dop853, Dopri5, Model, OdeSystem, Radau5, Rk4, SolveOptions, Stepper, integrate};
use std::time::Instant;

fn run<M, S, const N: usize>(m: &M, mut make: impl FnMut() -> S) -> (usize, f64, f64)
where
    M: Model + OdeSystem<N>,
    S: Stepper<N>,
{
    let (q0, u0) = (m.q0(), m.u0());
    let mut y0 = [0.0; N];
    y0[..M::NQ].copy_from_slice(q0.as_ref());
    y0[M::NQ..].copy_from_slice(u0.as_ref());
    let opts = SolveOptions {
        record_steps: false,
        max_steps: 10_000_000,
        ..SolveOptions::default()
    };
    let energy = |y: &[f64; N]| {
        let (mut q, mut u) = (q0, u0);
        q.as_mut().copy_from_slice(&y[..M::NQ]);
        u.as_mut().copy_from_slice(&y[M::NQ..]);
        m.energy(0.0, &q, &u)
    };
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..5 {
        let mut method = make();
        let start = Instant::now();
        let sol = integrate(&mut method, m, 0.0, y0, 10.0, &opts, &mut []);
        times.push(start.elapsed().as_secs_f64());
        last = Some(sol);
    }
    times.sort_by(f64::total_cmp);
    let Some(sol) = last else {
        return (0, 0.0, 0.0);
    };
    let ([t0, v0], [t1, v1]) = (energy(&y0), energy(&sol.y_final));
    let de = ((t1 + v1) - (t0 + v0)).abs() / (t0.abs() + v0.abs()).max(t1.abs() + v1.abs());
    (sol.stats.rhs_evals, times[2], de)
}

fn table<M, const N: usize>(name: &str, m: &M)
where
    M: Model + OdeSystem<N>,
{
    for tol in [1e-6, 1e-9, 1e-12] {
        for (method, (evals, secs, de)) in [
            ("dopri5", run(m, || Dopri5::new(tol, tol))),
            ("dop853", run(m, || Dop853::new(tol, tol))),
            ("radau5", run(m, || Radau5::new(tol, tol))),
        ] {
            println!(
                "| {name} | {method} | {tol:e} | {evals} | {:.3} | {de:.1e} |",
                secs * 1e3
            );
        }
    }
    // The fixed step: RK4 at h = 1e-3 s (10 000 steps), the same tableau the
    // element models run.
    let (evals, secs, de) = run(m, || Rk4::new(1e-3));
    println!(
        "| {name} | rk4 | h = 1e-3 | {evals} | {:.3} | {de:.1e} |",
        secs * 1e3
    );
}

fn main() {
    println!(
        "| model | method | rtol = atol | rhs evaluations | CPU ms (median of 5) | energy error (relative to T + |V|) |"
    );
    println!("|---|---|---|---|---|---|");
    table::<_, 4>(
        "double_pendulum",
        &eom_generated::double_pendulum::DoublePendulum::default(),
    );
    table::<_, 14>("arm7", &eom_generated::arm7::Arm7::default());
}
