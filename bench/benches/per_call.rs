//! ns per call of the compiled generated functions (forward dynamics, mass
//! matrix, inverse dynamics) next to the generic `f64` algorithms they were
//! generated from (the speed-up of generation), at a fixed random state.
//!
//! `cargo bench -p eom-bench --bench per_call`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use eom_gen::mech::Numeric;
use eom_sim::{Model, Vector};
use std::hint::black_box;

fn state<M: Model>(m: &M) -> (M::Q, M::U) {
    let mut q = m.q0();
    for (k, x) in q.as_mut().iter_mut().enumerate() {
        *x += 0.1 * ((k as f64) * 1.3).sin();
    }
    m.normalize(&mut q);
    let mut u = M::U::ZERO;
    for (k, x) in u.as_mut().iter_mut().enumerate() {
        *x = 0.5 * ((k as f64) * 0.7).cos();
    }
    (q, u)
}

fn bench_model<M: Model + Default>(c: &mut Criterion, label: &str, sys: &eom_gen::System) {
    let m = M::default();
    let (q, u) = state(&m);
    let tau = M::U::ZERO;
    let mut g = c.benchmark_group(label);
    g.bench_function(BenchmarkId::new("generated", "forward_dynamics"), |b| {
        let mut out = M::U::ZERO;
        b.iter(|| {
            m.forward_dynamics(0.0, black_box(&q), black_box(&u), &tau, &mut out);
            black_box(&out);
        })
    });
    g.bench_function(BenchmarkId::new("generated", "mass_matrix"), |b| {
        let mut out = M::MASS_ZERO;
        b.iter(|| {
            m.mass_matrix(0.0, black_box(&q), &mut out);
            black_box(&out);
        })
    });
    g.bench_function(BenchmarkId::new("generated", "inverse_dynamics"), |b| {
        let mut out = M::U::ZERO;
        b.iter(|| {
            m.inverse_dynamics(0.0, black_box(&q), black_box(&u), black_box(&tau), &mut out);
            black_box(&out);
        })
    });
    let num = Numeric::new(sys).unwrap_or_else(|e| panic!("{e}"));
    let (qv, uv, tv) = (
        q.as_ref().to_vec(),
        u.as_ref().to_vec(),
        tau.as_ref().to_vec(),
    );
    g.bench_function(BenchmarkId::new("f64 algorithm", "forward_dynamics"), |b| {
        b.iter(|| black_box(num.forward_dynamics(black_box(&qv), black_box(&uv), 0.0, &tv, &[])))
    });
    g.bench_function(BenchmarkId::new("f64 algorithm", "mass_matrix"), |b| {
        b.iter(|| black_box(num.terms(black_box(&qv), black_box(&uv), 0.0, &[])))
    });
    g.finish();
}

fn system(name: &str) -> eom_gen::System {
    let path = format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    eom_gen::check_file(&path)
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

fn chain(n: usize) -> eom_gen::System {
    let text = eom_gen::model::builder::n_link_chain(n, true).to_ron();
    eom_gen::check(&eom_gen::Source::new("chain", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

fn benches(c: &mut Criterion) {
    bench_model::<eom_generated::pendulum::Pendulum>(c, "pendulum", &system("pendulum"));
    bench_model::<eom_generated::arm7::Arm7>(c, "arm7", &system("arm7"));
    bench_model::<eom_bench::chain10::Chain10>(c, "chain10", &chain(10));
    bench_model::<eom_bench::chain50::Chain50>(c, "chain50", &chain(50));
}

criterion_group! {
    name = per_call;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2)).warm_up_time(std::time::Duration::from_millis(500));
    targets = benches
}
criterion_main!(per_call);
