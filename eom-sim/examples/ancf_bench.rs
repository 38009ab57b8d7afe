//! CPU time and error of the ANCF cases of issue #18 on the large-model
//! runtime (BENCHMARKS.md, "ANCF runtime"):
//!
//! ```text
//! cargo run --release -p eom-sim --example ancf_bench -- static
//! cargo run --release -p eom-sim --example ancf_bench -- pendulum N H [RHO_INF [TOL]]
//! cargo run --release -p eom-sim --example ancf_bench -- kernels
//! ```
//!
//! `static`: the Gerstmayr–Irschik cantilever (16 and 64 elements, 10
//! load steps), tip error against the extensible elastica. `pendulum`:
//! Berzeri and Shabana's falling pendulum to 1 s with N elements and step H
//! (generalized-α), printing the tip, the energy error and the CPU time.
//! `kernels`: ns per element for one force and one Jacobian evaluation.

use eom_sim::elements::{Cable2D, ElementKernel};
use eom_sim::large::ancf::{Chain, ChainSpec, Section, Support, chain};
use eom_sim::large::elastica::extensible_cantilever;
use eom_sim::large::{AlphaOptions, GeneralizedAlpha, State, StaticOptions, solve_static};
use std::time::Instant;

/// CPU time of this thread in seconds (Linux `/proc/thread-self/schedstat`,
/// nanoseconds on the CPU; the runtime is single-threaded), so that the
/// figures compare with Exudyn's `time.process_time()` on a loaded machine.
/// Wall time where that file is missing.
fn cpu_now() -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or_else(
            || START.get_or_init(Instant::now).elapsed().as_secs_f64(),
            |ns| ns * 1e-9,
        )
}

fn cantilever(n: usize) -> (Chain, f64) {
    let (l, b) = (2.0, 0.1);
    let section = Section {
        e: 2.07e11,
        rho: 7800.0,
        area: b * b,
        inertia: b * b * b * b / 12.0,
        b,
        h: b,
        ..Section::default()
    };
    let p = 3.0 * section.e * section.inertia / (l * l);
    let spec = ChainSpec {
        kernel: "Cable2D".into(),
        start: [0.0; 3],
        end: [l, 0.0, 0.0],
        elements: n,
        section,
        start_support: Support::Clamped,
        end_support: Support::Free,
        end_force: [0.0, -p, 0.0],
        end_mass: 0.0,
        gravity: [0.0; 3],
    };
    match chain(&spec) {
        Ok(c) => (c, p),
        Err(e) => panic!("{e}"),
    }
}

fn pendulum(n: usize) -> Chain {
    let spec = ChainSpec {
        kernel: "Cable2D".into(),
        start: [0.0; 3],
        end: [1.2, 0.0, 0.0],
        elements: n,
        section: Section {
            e: 0.7e6,
            rho: 5540.0,
            area: 0.0018,
            inertia: 1.215e-8,
            ..Section::default()
        },
        start_support: Support::Pinned,
        end_support: Support::Free,
        end_force: [0.0; 3],
        end_mass: 0.0,
        gravity: [0.0, -9.81, 0.0],
    };
    match chain(&spec) {
        Ok(c) => c,
        Err(e) => panic!("{e}"),
    }
}

fn statics() {
    let (l, b, e): (f64, f64, f64) = (2.0, 0.1, 2.07e11);
    let (ea, ei) = (e * b * b, e * b.powi(4) / 12.0);
    let p = 3.0 * ei / (l * l);
    let Some(reference) = extensible_cantilever(l, ea, ei, [0.0, -p]) else {
        panic!("elastica");
    };
    println!("reference tip ({:.12}, {:.12})", reference.x, reference.y);
    for n in [16usize, 64] {
        let (ch, _) = cantilever(n);
        let mut tip = [0.0; 3];
        let mut iters = 0;
        let reps = 50;
        let t0 = cpu_now();
        for _ in 0..reps {
            let sol = match solve_static(&ch.model, &StaticOptions::default()) {
                Ok(s) => s,
                Err(e) => panic!("{e}"),
            };
            tip = ch.node_position(&sol.q, ch.nodes - 1);
            iters = sol.steps.iter().map(|s| s.iterations()).sum::<usize>();
        }
        let mean = (cpu_now() - t0) / reps as f64;
        let err = ((tip[0] - reference.x).powi(2) + (tip[1] - reference.y).powi(2)).sqrt();
        println!(
            "static n = {n:>3}: {:.3} ms CPU (mean of 50), {iters} Newton iterations in 10 load steps, tip ({:.10}, {:.10}), error {err:.2e} m",
            mean * 1e3,
            tip[0],
            tip[1]
        );
    }
}

fn fall(n: usize, h: f64, rho: f64, tol: f64) {
    let ch = pendulum(n);
    let m = &ch.model;
    let state = State {
        t: 0.0,
        q: m.restrict(m.q0()),
        v: vec![0.0; m.n_free()],
    };
    let opts = AlphaOptions {
        h,
        rho_inf: rho,
        tol,
        ..AlphaOptions::default()
    };
    let e0 = m.energy(m.q0(), &state.v);
    let t0 = cpu_now();
    let mut ga = match GeneralizedAlpha::new(m, state, opts) {
        Ok(g) => g,
        Err(e) => panic!("{e}"),
    };
    if let Err(e) = ga.run_to(1.0, |_, _| {}) {
        panic!("{e}");
    }
    let cpu = cpu_now() - t0;
    let tip = ch.node_position(ga.q_full(), ch.nodes - 1);
    let e1 = m.energy(ga.q_full(), &ga.state().v);
    println!(
        "pendulum n = {n:>3} h = {h:e} rho_inf = {rho} tol = {tol:e}: tip at 1 s ({:.9}, {:.9}), energy change {:.2e} J, {:.3} s CPU, {} steps, {} Newton iterations, {} factorisations",
        tip[0],
        tip[1],
        e1 - e0,
        cpu,
        ga.stats.steps,
        ga.stats.newton_iterations,
        ga.stats.factorizations
    );
}

fn kernels() {
    let p = [0.1, 2.0e9, 1.7e6, 78.0, 0.0, 0.0];
    let q = [0.0, 0.0, 0.99, 0.1, 0.1, 0.01, 0.98, 0.12];
    let qd = [0.0; 8];
    let reps = 2_000_000;
    let mut f = [0.0; 8];
    let mut acc = 0.0;
    let t0 = Instant::now();
    for k in 0..reps {
        let mut qk = q;
        qk[7] += k as f64 * 1e-12;
        Cable2D::internal_forces(std::hint::black_box(&qk), &qd, &p, &mut f);
        acc += f[3];
    }
    let ns_f = t0.elapsed().as_secs_f64() / reps as f64 * 1e9;
    let mut kk = [[0.0; 8]; 8];
    let mut dd = [[0.0; 8]; 8];
    let reps_j = reps / 4;
    let t0 = Instant::now();
    for k in 0..reps_j {
        let mut qk = q;
        qk[7] += k as f64 * 1e-12;
        Cable2D::internal_jacobians(std::hint::black_box(&qk), &qd, &p, &mut kk, &mut dd);
        acc += kk[3][3];
    }
    let ns_j = t0.elapsed().as_secs_f64() / reps_j as f64 * 1e9;
    println!(
        "Cable2D: {ns_f:.1} ns per element force evaluation, {ns_j:.1} ns per element Jacobian (K and D) ({acc:.1e})"
    );
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("static") => statics(),
        Some("pendulum") => {
            let n = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(8);
            let h = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1e-3);
            let rho = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1.0);
            let tol = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(1e-10);
            fall(n, h, rho, tol);
        }
        Some("kernels") => kernels(),
        _ => eprintln!("usage: ancf_bench static | pendulum N H [RHO_INF [TOL]] | kernels"),
    }
}
