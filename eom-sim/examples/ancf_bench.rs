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

use eom_sim::elements::{Cable2D, ElementKernel, Lanes};
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
        kernel: eom_sim::elements::Element::Cable2D,
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
        kernel: eom_sim::elements::Element::Cable2D,
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
    let t_build = Instant::now();
    let ch = pendulum(n);
    let build = t_build.elapsed().as_secs_f64();
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
        "pendulum n = {n:>3} h = {h:e} rho_inf = {rho} tol = {tol:e}: tip at 1 s ({:.9}, {:.9}), energy change {:.2e} J, {:.3} s CPU, {} steps, {} Newton iterations, {} factorisations; model built in {:.3} ms",
        tip[0],
        tip[1],
        e1 - e0,
        cpu,
        ga.stats.steps,
        ga.stats.newton_iterations,
        ga.stats.factorizations,
        build * 1e3
    );
}

/// The 64 element states of `bench/benches/ancf.rs` (and of Exudyn's
/// `ancf_exudyn_kernels.py`): a straight element of length 0.25 m bent and
/// stretched by a few per cent, with rates.
fn kernel_states() -> Vec<([f64; 8], [f64; 8])> {
    (0..64)
        .map(|e| {
            let mut q = [0.0, 0.0, 1.0, 0.0, 0.25, 0.0, 1.0, 0.0];
            let mut qd = [0.0; 8];
            for k in 0..8 {
                let s = (e * 8 + k) as f64;
                q[k] += 0.03 * (1.7 * s).sin();
                qd[k] = 0.5 * (0.9 * s).cos();
            }
            (q, qd)
        })
        .collect()
}

/// Median over 7 rounds (each ≥ 0.1 s, as the CPU clock read from
/// `schedstat` advances in scheduler ticks) of the CPU time per element of `f` applied to
/// all 64 elements `reps` times, ns.
fn per_element(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..7)
        .map(|_| {
            let t0 = cpu_now();
            for _ in 0..reps {
                f();
            }
            (cpu_now() - t0) / (reps * 64) as f64 * 1e9
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[t.len() / 2]
}

fn lanes_of<const W: usize>(st: &[([f64; 8], [f64; 8])]) -> Vec<([Lanes<W>; 8], [Lanes<W>; 8])> {
    st.chunks(W)
        .map(|c| {
            let mut q = [Lanes::<W>::default(); 8];
            let mut qd = [Lanes::<W>::default(); 8];
            for (l, (a, b)) in c.iter().enumerate() {
                for i in 0..8 {
                    q[i].0[l] = a[i];
                    qd[i].0[l] = b[i];
                }
            }
            (q, qd)
        })
        .collect()
}

/// ns per element of the `W`-lane kernels: full forces, full Jacobians,
/// elastic forces, elastic stiffness.
fn lane_kernels<const W: usize>(st: &[([f64; 8], [f64; 8])], p: &[f64; 6]) -> [f64; 4] {
    let ls = lanes_of::<W>(st);
    let pl = p.map(Lanes::<W>::splat);
    let mut f = [Lanes::<W>::default(); 8];
    let mut k = [[Lanes::<W>::default(); 8]; 8];
    let mut d = [[Lanes::<W>::default(); 8]; 8];
    use std::hint::black_box as bb;
    let ff = per_element(50_000, || {
        for (q, qd) in &ls {
            Cable2D::forces_lanes(bb(q), bb(qd), bb(&pl), &mut f);
            bb(&f);
        }
    });
    let jj = per_element(5_000, || {
        for (q, qd) in &ls {
            Cable2D::jacobians_lanes(bb(q), bb(qd), bb(&pl), &mut k, &mut d);
            bb((&k, &d));
        }
    });
    let ef = per_element(50_000, || {
        for (q, _) in &ls {
            Cable2D::elastic_forces_lanes(bb(q), bb(&pl), &mut f);
            bb(&f);
        }
    });
    let ek = per_element(5_000, || {
        for (q, _) in &ls {
            Cable2D::elastic_stiffness_lanes(bb(q), bb(&pl), &mut k);
            bb(&k);
        }
    });
    [ff, jj, ef, ek]
}

fn kernels() {
    // Gerstmayr–Irschik's section, element length 0.25 m, damping on as
    // in Exudyn's figures (1e-3 s × EA, EI).
    let (e, a, i) = (2.07e11, 0.01, 0.1f64.powi(4) / 12.0);
    let p = [0.25, e * a, e * i, 7800.0 * a, 1e-3 * e * a, 1e-3 * e * i];
    let st = kernel_states();
    println!(
        "ns per element, Cable2D, 64 elements at their own deformed states with rates (medians):"
    );
    println!("lanes  forces  K and D  elastic forces  elastic K");
    for (w, r) in [
        (1, lane_kernels::<1>(&st, &p)),
        (2, lane_kernels::<2>(&st, &p)),
        (4, lane_kernels::<4>(&st, &p)),
        (8, lane_kernels::<8>(&st, &p)),
    ] {
        println!(
            "{w:>5}  {:>6.1}  {:>7.1}  {:>14.1}  {:>9.1}",
            r[0], r[1], r[2], r[3]
        );
    }
    // The runtime's assembly (gather, kernel, scatter into the full vector
    // and the sparse matrix) on a free chain of 64 such elements, as
    // Exudyn's ComputeODE2RHS / ComputeJacobianODE2RHS do.
    for damped in [true, false] {
        let mut sec = Section {
            e,
            rho: 7800.0,
            area: a,
            inertia: i,
            ..Section::default()
        };
        if damped {
            sec.damping_axial = 1e-3 * e * a;
            sec.damping_bending = 1e-3 * e * i;
        }
        let spec = ChainSpec {
            kernel: eom_sim::elements::Element::Cable2D,
            start: [0.0; 3],
            end: [16.0, 0.0, 0.0],
            elements: 64,
            section: sec,
            start_support: Support::Free,
            end_support: Support::Free,
            end_force: [0.0; 3],
            end_mass: 0.0,
            gravity: [0.0; 3],
        };
        let ch = match chain(&spec) {
            Ok(c) => c,
            Err(e) => panic!("{e}"),
        };
        let m = &ch.model;
        let mut q = m.q0().to_vec();
        let mut qd = vec![0.0; q.len()];
        for (k, (x, v)) in q.iter_mut().zip(qd.iter_mut()).enumerate() {
            *x += 0.03 * (1.7 * k as f64).sin();
            *v = 0.5 * (0.9 * k as f64).cos();
        }
        let mut scratch = vec![0.0; q.len()];
        let mut out = vec![0.0; m.n_free()];
        let mut jac = eom_sim::large::SparseMatrix::zeros(m.pattern().clone());
        let rhs = per_element(50_000, || {
            m.internal(&q, &qd, &mut scratch, &mut out);
            std::hint::black_box(&out);
        });
        let jj = per_element(5_000, || {
            m.jacobian(&q, &qd, 1.0, 1.0, 1.0, &mut jac);
            std::hint::black_box(&jac);
        });
        println!(
            "assembled (StructuralModel::internal / ::jacobian incl. M), 64 elements, damping {}: {rhs:.1} ns / {jj:.1} ns per element",
            if damped { "on" } else { "off" }
        );
    }
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
