//! ns per element of the generated ANCF element kernels
//! (`eom_sim::elements`): `internal_forces` and `internal_jacobians` over a
//! loop of 64 elements, each at its own deformed state (a straight element
//! bent and stretched by a few per cent, with rates), as the runtime's
//! assembly loop calls them. Reported per element (criterion's time / 64).
//!
//! `cargo bench -p eom-bench --bench ancf`

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use eom_sim::elements::{Beam2D, Cable2D, Cable2DGreen, Cable3D, ElementKernel};
use std::hint::black_box;

const ELEMENTS: usize = 64;

/// Coordinates of element `e`: the straight element of length `l` along x
/// (`gradient slots` per node after the position), perturbed smoothly.
fn states<const N: usize>(dim: usize, l: f64, beam: bool) -> Vec<([f64; N], [f64; N])> {
    (0..ELEMENTS)
        .map(|e| {
            let mut q = [0.0; N];
            let nc = N / 2;
            for node in 0..2 {
                let b = node * nc;
                q[b] = node as f64 * l;
                q[b + dim] = 1.0;
                if beam {
                    q[b + 2 * dim + 1] = 1.0;
                }
            }
            let mut qd = [0.0; N];
            for k in 0..N {
                let s = (e * N + k) as f64;
                q[k] += 0.03 * (1.7 * s).sin();
                qd[k] = 0.5 * (0.9 * s).cos();
            }
            (q, qd)
        })
        .collect()
}

fn bench<const N: usize, const P: usize, E: ElementKernel<N, P>>(c: &mut Criterion, p: [f64; P]) {
    let st = states::<N>(E::DIM, p[0], E::NAME == "Beam2D");
    let mut g = c.benchmark_group(format!("ancf/{}", E::NAME));
    g.throughput(Throughput::Elements(ELEMENTS as u64));
    g.bench_function("internal_forces", |b| {
        let mut f = [0.0; N];
        b.iter(|| {
            for (q, qd) in &st {
                E::internal_forces(black_box(q), black_box(qd), black_box(&p), &mut f);
                black_box(&f);
            }
        })
    });
    g.bench_function("internal_jacobians", |b| {
        let mut k = [[0.0; N]; N];
        let mut d = [[0.0; N]; N];
        b.iter(|| {
            for (q, qd) in &st {
                E::internal_jacobians(black_box(q), black_box(qd), black_box(&p), &mut k, &mut d);
                black_box((&k, &d));
            }
        })
    });
    g.finish();
}

fn ancf(c: &mut Criterion) {
    // Gerstmayr–Irschik's cantilever section: L = 2/8 m, steel 0.1 × 0.1 m.
    let (e, a, i) = (2.07e11, 0.01, 0.1f64.powi(4) / 12.0);
    let cable = [0.25, e * a, e * i, 7800.0 * a, 0.0, 0.0];
    bench::<8, 6, Cable2D>(c, cable);
    bench::<8, 6, Cable2DGreen>(c, cable);
    bench::<12, 6, Cable3D>(c, cable);
    bench::<12, 7, Beam2D>(c, [0.25, e, 0.3, 7800.0, 0.1, 0.1, 0.0]);
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = ancf
}
criterion_main!(benches);
