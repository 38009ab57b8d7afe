//! Work-precision of the constraint solvers on compiled closed loops:
//! Andrews' squeezing mechanism to t = 0.03 s (the IVP test set's end time)
//! and the parallelogram four-bar to t = 0.5 s (before its first singular
//! position) and t = 5 s (through seven of them).
//!
//! For each solver and integrator a sweep of tolerances; each point is the
//! median CPU time of 5 runs, right-hand sides, the error at the end time
//! (largest coordinate error, relative to the largest coordinate) against
//! our own reference, and the significant correct digits `−log10(error)`.
//! The reference is the multiplier form with projection at
//! rtol = atol = 1e-13, by RADAU5 (Andrews) or DOP853 (four-bar), checked
//! by a second method at the same tolerance (DOP853, or coordinate
//! partitioning); their difference is printed.
//!
//! `cargo bench -p eom-bench --bench loops` (writes
//! `bench/results/loops.csv`).

use eom_generated as g;
use eom_sim::work_precision::{ModelRunner, Runner, Trajectory, end_error};
use eom_sim::{ConstrainedModel, Method, OdeSystem, Settings, StopReason};
use std::time::Instant;

fn settings(integrator: &str, tol: f64) -> Settings {
    Settings {
        integrator: integrator.parse().expect("a known integrator"),
        rtol: tol,
        atol: tol,
        dt: 1e-3,
        index_vars: (0, 0),
    }
}

/// One run from the assembled initial state (assembly included, as it is
/// part of what a run costs); `N = n_q + n_u`, `NC = N + m`.
fn once<M: ConstrainedModel + OdeSystem<N> + Default, const N: usize, const NC: usize>(
    method: Method,
    integrator: &str,
    tol: f64,
    t_end: f64,
) -> Trajectory {
    let m = M::default();
    ModelRunner::<M, N, NC>::new(&m)
        .run(&settings(integrator, tol), method, t_end, &[])
        .expect("a known integrator, and RADAU5 for the index-3 DAE")
}

#[allow(clippy::too_many_arguments)]
fn sweep<M: ConstrainedModel + OdeSystem<N> + Default, const N: usize, const NC: usize>(
    label: &str,
    t_end: f64,
    reference: &[f64],
    combos: &[(Method, &str)],
    tols: &[f64],
    csv: &mut String,
) {
    for &(method, integrator) in combos {
        for &tol in tols {
            let mut times = Vec::new();
            let mut end = None;
            for _ in 0..5 {
                let start = Instant::now();
                let e = once::<M, N, NC>(method, integrator, tol, t_end);
                times.push(start.elapsed().as_secs_f64());
                end = Some(e);
            }
            times.sort_by(f64::total_cmp);
            let Some(end) = end else { continue };
            let (err, digits, outcome) = match end.stop {
                StopReason::Finished => {
                    let e = end_error(&end.q_final, reference);
                    (e, -e.max(1e-17).log10(), "finished".to_string())
                }
                other => (f64::NAN, f64::NAN, format!("{other:?}")),
            };
            println!(
                "| {label} | {} | {integrator} | {tol:.0e} | {} | {:.3} | {err:.1e} | {digits:.1} | {outcome} |",
                method.name(),
                end.stats.rhs_evals,
                times[2] * 1e3
            );
            *csv += &format!(
                "{label},{},{integrator},{tol:e},{},{:e},{err:e},{digits},{outcome}\n",
                method.name(),
                end.stats.rhs_evals,
                times[2]
            );
        }
    }
}

fn main() {
    // `cargo bench` passes `--bench`; any other argument filters nothing.
    let mut csv =
        String::from("model,constraints,integrator,tol,rhs_evals,cpu_s,error,digits,outcome\n");
    println!(
        "| model | constraints | integrator | tol | rhs | CPU ms | error | digits | outcome |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let tols = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];

    type A = g::andrews::Andrews;
    let reference = once::<A, 14, 20>(Method::Projection, "radau5", 1e-13, 0.03);
    let check = once::<A, 14, 20>(Method::Projection, "dop853", 1e-13, 0.03);
    eprintln!(
        "andrews reference (projection RADAU5, 1e-13) against projection DOP853 at 1e-13: {:.1e}; q(0.03) = {:?}",
        end_error(&check.q_final, &reference.q_final),
        reference.q_final
    );
    sweep::<A, 14, 20>(
        "andrews",
        0.03,
        &reference.q_final,
        &[
            (Method::Index3, "radau5"),
            (Method::Projection, "radau5"),
            (Method::Partitioning, "radau5"),
            (Method::BAUMGARTE, "radau5"),
            (Method::Projection, "dop853"),
        ],
        &tols,
        &mut csv,
    );

    type F = g::fourbar::Fourbar;
    for t_end in [0.5, 5.0] {
        let reference = once::<F, 6, 8>(Method::Projection, "dop853", 1e-13, t_end);
        let check = once::<F, 6, 8>(Method::Partitioning, "dop853", 1e-13, t_end);
        eprintln!(
            "fourbar to {t_end} s reference (projection DOP853, 1e-13) against partitioning DOP853 at 1e-13: {:.1e}",
            end_error(&check.q_final, &reference.q_final)
        );
        sweep::<F, 6, 8>(
            &format!("fourbar_{t_end}s"),
            t_end,
            &reference.q_final,
            &[
                (Method::Projection, "dop853"),
                (Method::Partitioning, "dop853"),
                (Method::BAUMGARTE, "dop853"),
                (Method::Projection, "dopri5"),
                (Method::Index3, "radau5"),
            ],
            &tols,
            &mut csv,
        );
    }
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/results");
    let path = format!("{dir}/loops.csv");
    match std::fs::create_dir_all(dir).and_then(|_| std::fs::write(&path, csv)) {
        Ok(()) => eprintln!("wrote {path}"),
        Err(e) => eprintln!("cannot write {path}: {e}"),
    }
}
