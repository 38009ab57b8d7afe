//! Benchmarks of the symbolic engine (criterion, plus a one-shot report).
//!
//! `cargo bench -p eom-gen --bench sym` first prints a report (arena sizes,
//! bytes per node, op counts, one timed run per phase) and then runs the
//! criterion groups:
//! - `intern`: hash-consing throughput, new nodes (miss) and existing (hit);
//! - `pipeline`: build + simplify (runner) + lower for two ~10⁵-node DAGs:
//!   `chain` (generic spatial-chain kinematics on `Expr`, velocities,
//!   accelerations by total time derivative, Jacobian of the tip) and
//!   `random` (a random trig DAG).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group};
use eom_gen::sym::{
    Arena, Axis, Context, Expr, Id, LowerOptions, Mat3, Program, RuleSet, Runner, Scalar,
    TimeDerivative, Vec3,
};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Nodes interned by the `intern` benchmark.
const N_INTERN: u32 = 100_000;

/// Build `N_INTERN` distinct nodes in a raw arena: unary and binary nodes
/// over a growing pool (no flattening), i.e. pure hash-consing cost.
fn intern_nodes(a: &mut Arena) -> Id {
    let x = a.param("x").unwrap();
    let mut prev = x;
    let mut last = x;
    for i in 0..N_INTERN {
        let n = match i % 4 {
            0 => a.sin(prev),
            1 => a.pow(prev, 2 + (i % 7) as i32),
            2 => a.atan2(prev, last),
            _ => a.cos(prev),
        };
        last = prev;
        prev = n;
    }
    prev
}

/// Links in the `chain` workload (tuned to give ~10⁵ nodes).
const CHAIN_LINKS: u32 = 84;

/// Generic spatial-chain kinematics: rotations, positions, angular and
/// linear velocities, accelerations (total time derivative with q̇ = u) and
/// the Jacobian of the tip position.
fn chain_workload(cx: &Context, n: u32) -> Vec<(String, Id)> {
    let mut r = Mat3::<Expr<'_>>::identity();
    let mut p = Vec3::<Expr<'_>>::zero();
    let mut w = Vec3::<Expr<'_>>::zero();
    let mut v = Vec3::<Expr<'_>>::zero();
    let mut outs: Vec<(String, Expr<'_>)> = Vec::new();
    for i in 0..n {
        let axis = [Axis::Z, Axis::Y, Axis::X][i as usize % 3];
        let l = cx.param(&format!("l{i}")).unwrap();
        let d = cx.param(&format!("d{i}")).unwrap();
        r = r * Mat3::rot(axis, cx.q(i));
        w = w + r.mul_vec(Vec3::unit(axis).scale(cx.u(i)));
        let arm = r.mul_vec(Vec3::new(l, Expr::zero(), d));
        v = v + w.cross(arm);
        p = p + arm;
        for k in 0..3 {
            outs.push((format!("p{i}_{k}"), p[k]));
            outs.push((format!("w{i}_{k}"), w[k]));
            outs.push((format!("v{i}_{k}"), v[k]));
        }
    }
    let mut ids: Vec<(String, Id)> = outs.iter().map(|(s, e)| (s.clone(), cx.id(*e))).collect();
    let (v, p) = (v.map(|e| cx.id(e)), p.map(|e| cx.id(e)));
    let mut a = cx.arena_mut();
    // accelerations of the tip: d/dt v with q̇ = u
    let mut td = TimeDerivative::new();
    for i in 0..n {
        let (q, u) = (a.q(i), a.u(i));
        td.rate(a.as_sym(q).unwrap(), u);
    }
    for k in 0..3 {
        let acc = td.apply(&mut a, v[k]).unwrap();
        ids.push((format!("a_{k}"), acc));
    }
    // Jacobian of the tip position
    for j in 0..n {
        let q = a.q(j);
        let s = a.as_sym(q).unwrap();
        for k in 0..3 {
            let dp = a.diff(p[k], s);
            ids.push((format!("J{k}_{j}"), dp));
        }
    }
    ids
}

/// Nodes in the `random` workload.
const N_RANDOM: usize = 100_000;

/// A random trig DAG built with every rule on, until the arena has
/// `N_RANDOM` nodes; every node built is an output, so the whole arena is
/// the DAG.
fn random_workload(a: &mut Arena) -> Vec<(String, Id)> {
    let mut pool: Vec<Id> = (0..8).map(|i| a.q(i)).collect();
    pool.extend((0..8).map(|i| a.param(&format!("k{i}")).unwrap()));
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let one = a.constant(1.0);
    while a.len() < N_RANDOM {
        let n = pool.len() as u64;
        let x = pool[(next() % n) as usize];
        let y = pool[(next() % n) as usize];
        let r = match next() % 9 {
            0 | 1 => a.add2(x, y),
            2 | 3 => a.mul2(x, y),
            4 => a.sub(x, y),
            5 => a.sin(x),
            6 => a.cos(x),
            7 => {
                let y2 = a.pow(y, 2);
                let den = a.add2(one, y2);
                a.div(x, den)
            }
            _ => {
                let c = a.constant(0.5 + (next() % 8) as f64);
                a.mul2(c, x)
            }
        };
        pool.push(r);
    }
    pool.iter()
        .enumerate()
        .map(|(i, &id)| (format!("o{i}"), id))
        .collect()
}

/// Simplify and lower; returns the program and the runner's stop reason.
fn simplify_and_lower(a: &mut Arena, outs: &[(String, Id)]) -> (Program, String) {
    let roots: Vec<Id> = outs.iter().map(|(_, id)| *id).collect();
    let rep = Runner::default().run(a, &roots);
    let named: Vec<(&str, Id)> = outs
        .iter()
        .map(|(s, _)| s.as_str())
        .zip(rep.roots)
        .collect();
    (
        a.lower(&named, LowerOptions::default()),
        format!("{:?} after {} iterations", rep.stop, rep.iterations),
    )
}

fn median(mut xs: Vec<Duration>) -> Duration {
    xs.sort();
    xs[xs.len() / 2]
}

/// One-shot report: sizes, memory, op counts, and the median of 5 runs per phase.
fn report() {
    println!("== sym report ==");
    println!(
        "size_of::<View>() = {} bytes (stored Node is 12, plus a 4-byte structural hash)",
        std::mem::size_of::<eom_gen::sym::View>()
    );
    let mut times = Vec::new();
    for _ in 0..5 {
        let mut a = Arena::with_rules(RuleSet::NONE);
        let t = Instant::now();
        black_box(intern_nodes(&mut a));
        times.push(t.elapsed());
    }
    let t = median(times);
    println!(
        "intern: {} new nodes in {:.2?} = {:.1} M nodes/s",
        N_INTERN,
        t,
        N_INTERN as f64 / t.as_secs_f64() / 1e6
    );

    println!("chain scaling (links: nodes built, program ops, build+simplify+lower time):");
    for limit in [usize::MAX, eom_gen::sym::DEFAULT_FLATTEN_LIMIT] {
        for n in [8u32, 16, 32, 64] {
            let t0 = Instant::now();
            let cx = Context::new();
            cx.arena_mut().set_flatten_limit(limit);
            let outs = chain_workload(&cx, n);
            let mut a = cx.into_arena();
            let built = a.len();
            let (p, _) = simplify_and_lower(&mut a, &outs);
            println!(
                "  limit {limit} n {n}: {built} nodes, {} ops, {:.1?}",
                p.op_count().total(),
                t0.elapsed()
            );
        }
    }
    for name in ["chain", "random"] {
        let (mut tb, mut ts, mut tt) = (Vec::new(), Vec::new(), Vec::new());
        let mut last = None;
        for _ in 0..5 {
            let t0 = Instant::now();
            let (mut arena, outs) = if name == "chain" {
                let cx = Context::new();
                let outs = chain_workload(&cx, CHAIN_LINKS);
                (cx.into_arena(), outs)
            } else {
                let mut a = Arena::new();
                let outs = random_workload(&mut a);
                (a, outs)
            };
            let t1 = Instant::now();
            let built = arena.len();
            let mem = arena.memory();
            let dag = arena.dag_size(&outs.iter().map(|(_, id)| *id).collect::<Vec<_>>());
            let roots: Vec<Id> = outs.iter().map(|(_, id)| *id).collect();
            let rep = Runner::default().run(&mut arena, &roots);
            let t2 = Instant::now();
            let named: Vec<(&str, Id)> = outs
                .iter()
                .map(|(s, _)| s.as_str())
                .zip(rep.roots.iter().copied())
                .collect();
            let p = arena.lower(&named, LowerOptions::default());
            let t3 = Instant::now();
            let second = arena.lower(
                &named,
                LowerOptions {
                    second_round: true,
                    ..LowerOptions::default()
                },
            );
            // The arena only grows, so the unsimplified roots are still valid.
            let unsimplified: Vec<(&str, Id)> =
                outs.iter().map(|(s, id)| (s.as_str(), *id)).collect();
            let no_runner = arena
                .lower(&unsimplified, LowerOptions::default())
                .op_count();
            tb.push(t1 - t0);
            ts.push(t2 - t1);
            tt.push(t3 - t2);
            last = Some((built, mem, dag, rep, p, second, outs.len(), no_runner));
        }
        let (built, mem, dag, rep, p, second, n_out, no_runner) = last.unwrap();
        let (b, s, l) = (median(tb), median(ts), median(tt));
        println!("{name}: {built} nodes built, {dag} reachable from {n_out} outputs");
        println!(
            "  memory: {} nodes, {} B nodes + {} B child lists = {:.1} B/node (+ {} B hash table = {:.1} B/node)",
            mem.nodes,
            mem.node_bytes,
            mem.arg_bytes,
            mem.bytes_per_node(),
            mem.table_bytes,
            (mem.node_bytes + mem.arg_bytes + mem.table_bytes) as f64 / mem.nodes as f64
        );
        println!(
            "  runner: {:?} after {} iterations, applied {:?}, DAG {} -> {}",
            rep.stop, rep.iterations, rep.applied, rep.dag_size.0, rep.dag_size.1
        );
        println!(
            "  program: {} instructions, {}",
            p.instrs.len(),
            p.op_count()
        );
        println!("  (with second round:    {})", second.op_count());
        println!("  (without the runner:   {no_runner})");
        println!(
            "  median of 5: build {:.1?} + simplify {:.1?} + lower {:.1?} = {:.1?}",
            b,
            s,
            l,
            b + s + l
        );
    }
}

fn bench_intern(c: &mut Criterion) {
    let mut g = c.benchmark_group("intern");
    g.throughput(Throughput::Elements(N_INTERN as u64));
    g.bench_function("miss", |b| {
        b.iter(|| {
            let mut a = Arena::with_rules(RuleSet::NONE);
            black_box(intern_nodes(&mut a))
        })
    });
    let mut warm = Arena::with_rules(RuleSet::NONE);
    intern_nodes(&mut warm);
    g.bench_function("hit", |b| b.iter(|| black_box(intern_nodes(&mut warm))));
    g.finish();
}

fn bench_pipeline(c: &mut Criterion) {
    let mut g = c.benchmark_group("pipeline");
    g.sample_size(10).measurement_time(Duration::from_secs(20));
    g.bench_function(BenchmarkId::new("build_simplify_lower", "chain"), |b| {
        b.iter(|| {
            let cx = Context::new();
            let outs = chain_workload(&cx, CHAIN_LINKS);
            let mut a = cx.into_arena();
            black_box(simplify_and_lower(&mut a, &outs))
        })
    });
    g.bench_function(BenchmarkId::new("build_simplify_lower", "random"), |b| {
        b.iter(|| {
            let mut a = Arena::new();
            let outs = random_workload(&mut a);
            black_box(simplify_and_lower(&mut a, &outs))
        })
    });
    g.finish();
}

criterion_group!(benches, bench_intern, bench_pipeline);

fn main() {
    // `cargo bench` passes `--bench`; `cargo test --benches` does not, and
    // then only criterion's quick test mode runs.
    if std::env::args().any(|a| a == "--bench") {
        report();
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
