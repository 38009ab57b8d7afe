//! `eom-gen bench MODEL --per-call`: the cost of one call of the compiled
//! forward dynamics, mass matrix and inverse dynamics, next to their
//! operation counts.
//!
//! A timing program is written around the model's generated source and
//! built in release mode in the same cache as `eom-gen eval` (see
//! [`crate::compiled`]). It draws `states` random states with a fixed seed
//! (every position uniform in `[-π, π]`, then unit quaternions normalised;
//! speeds, generalised forces and accelerations uniform in `[-1, 1]`), calls
//! each function once per state in a loop (`std::hint::black_box` on inputs
//! and outputs so nothing is hoisted or removed), and repeats the loop
//! `reps` times after one warm-up pass. Each repetition gives one figure,
//! total time / `states`; the report is the median over repetitions with
//! the quartiles and the extremes.

use crate::compiled::{CachedCrate, build_cached};
use crate::error::Error;
use eom_gen::emit::camel;
use eom_gen::generate::Generated;

/// How to measure.
#[derive(Clone, Debug)]
pub struct PerCallOptions {
    /// Number of random states per repetition.
    pub states: usize,
    /// Number of timed repetitions (after one warm-up pass).
    pub reps: usize,
    /// Seed of the state generator (SplitMix64).
    pub seed: u64,
    /// Build with `-C target-cpu=native` (a separate target directory).
    pub native: bool,
    /// Emit `mul_add` for `a·b + c` (only with `native` on a machine with
    /// FMA: see `crate::compiled::native_fma`).
    pub fma: bool,
    /// Also generate and time `forward_dynamics_derivatives`.
    pub derivatives: bool,
    /// Also emit the batched functions and time `forward_dynamics_lanes`
    /// at every pack width of [`WIDTHS`] (ns per state); with
    /// `derivatives`, `forward_dynamics_derivatives_lanes` too, at
    /// [`DERIVATIVE_WIDTHS`].
    pub batch: bool,
}

/// The pack widths `--batch` times: 2 lanes fill an SSE2 register, 4 an
/// AVX2 one, 8 an AVX-512 one, 16 two of them.
pub const WIDTHS: [usize; 4] = [2, 4, 8, 16];

/// The pack widths of the batched derivatives: one AVX2 and one AVX-512
/// register (their programs are several times forward dynamics', so each
/// width is a long build, and two or sixteen lanes were never the fastest
/// width of forward dynamics on an AVX2 or AVX-512 machine).
pub const DERIVATIVE_WIDTHS: [usize; 2] = [4, 8];

impl Default for PerCallOptions {
    fn default() -> Self {
        PerCallOptions {
            states: 1024,
            reps: 31,
            seed: 1,
            native: false,
            fma: false,
            derivatives: false,
            batch: false,
        }
    }
}

/// Nanoseconds per call over the repetitions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Median over repetitions.
    pub median: f64,
    /// Lower quartile.
    pub q1: f64,
    /// Upper quartile.
    pub q3: f64,
    /// Fastest repetition.
    pub min: f64,
    /// Slowest repetition.
    pub max: f64,
}

/// The per-call times of the three functions.
#[derive(Clone, Debug, PartialEq)]
pub struct PerCall {
    /// `forward_dynamics`.
    pub forward_dynamics: Timing,
    /// `mass_matrix`.
    pub mass_matrix: Timing,
    /// `inverse_dynamics`.
    pub inverse_dynamics: Timing,
    /// `forward_dynamics_derivatives`, when asked for.
    pub derivatives: Option<Timing>,
    /// `forward_dynamics_lanes` per pack width (ns per state), with `--batch`.
    pub batched: Vec<(usize, Timing)>,
    /// `forward_dynamics_derivatives_lanes` per pack width (ns per state),
    /// with `--batch --derivatives`.
    pub batched_derivatives: Vec<(usize, Timing)>,
}

/// The pack width with the lowest median ns per state, and its timing.
fn fastest(by_width: &[(usize, Timing)]) -> Option<(usize, Timing)> {
    by_width
        .iter()
        .copied()
        .min_by(|a, b| a.1.median.total_cmp(&b.1.median))
}

impl PerCall {
    /// The pack width with the lowest median ns per state of batched
    /// forward dynamics, and its timing.
    pub fn best_batched(&self) -> Option<(usize, Timing)> {
        fastest(&self.batched)
    }

    /// The same for the batched derivatives.
    pub fn best_batched_derivatives(&self) -> Option<(usize, Timing)> {
        fastest(&self.batched_derivatives)
    }
}

const MAIN: &str = r#"//! Times the generated model's forward dynamics, mass matrix and inverse
//! dynamics over random states and prints JSON: `bench STATES REPS SEED`.
mod model;
use eom_sim::{Model, Vector};
use std::hint::black_box;
use std::time::Instant;

type Q = <model::MODEL as Model>::Q;
type U = <model::MODEL as Model>::U;

/// SplitMix64, mapped to a uniform number in [-1, 1).
struct Rng(u64);

impl Rng {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn vector<V: Vector>(&mut self, scale: f64) -> V {
        let mut v = V::ZERO;
        for x in v.as_mut() {
            *x = scale * self.uniform();
        }
        v
    }
}

/// One warm-up pass, then `reps` timed passes over `n` calls of `per`
/// states each; ns per state.
fn time(n: usize, per: usize, reps: usize, mut f: impl FnMut(usize)) -> String {
    for k in 0..n {
        f(k);
    }
    let mut ns: Vec<f64> = (0..reps)
        .map(|_| {
            let start = Instant::now();
            for k in 0..n {
                f(k);
            }
            start.elapsed().as_secs_f64() * 1e9 / (n * per) as f64
        })
        .collect();
    ns.sort_by(f64::total_cmp);
    let at = |p: f64| {
        let x = p * (ns.len() - 1) as f64;
        let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
        ns[lo] + (ns[hi] - ns[lo]) * (x - lo as f64)
    };
    format!(
        "{{\"median\":{:?},\"q1\":{:?},\"q3\":{:?},\"min\":{:?},\"max\":{:?}}}",
        at(0.5), at(0.25), at(0.75), at(0.0), at(1.0)
    )
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: usize, d: u64| args.get(k).and_then(|a| a.parse().ok()).unwrap_or(d);
    let (n, reps, seed) = (arg(1, 1024).max(1) as usize, arg(2, 31).max(1) as usize, arg(3, 1));
    let m = model::MODEL::default();
    let mut rng = Rng(seed);
    let states: Vec<(Q, U, U, U)> = (0..n)
        .map(|_| {
            let mut q: Q = rng.vector(std::f64::consts::PI);
            m.normalize(&mut q);
            (q, rng.vector(1.0), rng.vector(1.0), rng.vector(1.0))
        })
        .collect();
    let mut udot = U::ZERO;
    let fd = time(n, 1, reps, |k| {
        let (q, u, tau, _) = &states[k];
        m.forward_dynamics(0.0, black_box(q), black_box(u), black_box(tau), &mut udot);
        black_box(&mut udot);
    });
    let mut mm = <model::MODEL as Model>::MASS_ZERO;
    let mass = time(n, 1, reps, |k| {
        m.mass_matrix(0.0, black_box(&states[k].0), &mut mm);
        black_box(&mut mm);
    });
    let mut tau = U::ZERO;
    let id = time(n, 1, reps, |k| {
        let (q, u, _, a) = &states[k];
        m.inverse_dynamics(0.0, black_box(q), black_box(u), black_box(a), &mut tau);
        black_box(&mut tau);
    });
    let extra = extra(n, reps, &m, &states);
    println!("{{\"forward_dynamics\":{fd},\"mass_matrix\":{mass},\"inverse_dynamics\":{id}{extra}}}");
}
"#;

/// `MAIN`'s `extra` without `--batch`: nothing more to time.
const NO_EXTRA: &str = r#"
fn extra(_n: usize, _reps: usize, _m: &model::MODEL, _states: &[(Q, U, U, U)]) -> String {
    String::new()
}
"#;

/// `MAIN`'s `extra` with `--batch`: `forward_dynamics_lanes` at every pack
/// width, the states packed `W` at a time (lane `l` of pack `k` is state
/// `W k + l`), ns per state.
const BATCHED: &str = r#"
use eom_sim::Lanes;
const NQ: usize = <model::MODEL as Model>::NQ;
const NU: usize = <model::MODEL as Model>::NU;

type Pack<const W: usize> = ([Lanes<W>; NQ], [Lanes<W>; NU], [Lanes<W>; NU]);

fn batched<const W: usize>(reps: usize, m: &model::MODEL, states: &[(Q, U, U, U)]) -> String {
    let models = [*m; W];
    let packs: Vec<Pack<W>> = packs_of(states);
    let mut udot = [Lanes::<W>::splat(0.0); NU];
    time(packs.len(), W, reps, |k| {
        let (q, u, tau) = &packs[k];
        model::MODEL::forward_dynamics_lanes(
            &models,
            Lanes::splat(0.0),
            black_box(q),
            black_box(u),
            black_box(tau),
            &mut udot,
        );
        black_box(&mut udot);
    })
}

fn extra(_n: usize, reps: usize, m: &model::MODEL, states: &[(Q, U, U, U)]) -> String {
    format!(
        ",\"batched_forward_dynamics\":{{\"2\":{},\"4\":{},\"8\":{},\"16\":{}}}{}",
        batched::<2>(reps, m, states),
        batched::<4>(reps, m, states),
        batched::<8>(reps, m, states),
        batched::<16>(reps, m, states),
        batched_derivatives(reps, m, states),
    )
}

/// The states packed `W` at a time (lane `l` of pack `k` is state `W k + l`).
fn packs_of<const W: usize>(states: &[(Q, U, U, U)]) -> Vec<Pack<W>> {
    let lanes = |c: &[(Q, U, U, U)], f: &dyn Fn(&(Q, U, U, U)) -> Vec<f64>, k: usize| {
        Lanes::<W>(std::array::from_fn(|l| f(&c[l])[k]))
    };
    states
        .chunks_exact(W)
        .map(|c| {
            (
                std::array::from_fn(|k| lanes(c, &|s| s.0.as_ref().to_vec(), k)),
                std::array::from_fn(|k| lanes(c, &|s| s.1.as_ref().to_vec(), k)),
                std::array::from_fn(|k| lanes(c, &|s| s.2.as_ref().to_vec(), k)),
            )
        })
        .collect()
}
"#;

/// `BATCHED`'s `batched_derivatives` without `--derivatives`: nothing.
const NO_BATCHED_DERIVATIVES: &str = r#"
fn batched_derivatives(_reps: usize, _m: &model::MODEL, _states: &[(Q, U, U, U)]) -> String {
    String::new()
}
"#;

/// `BATCHED`'s `batched_derivatives` with `--derivatives`:
/// `forward_dynamics_derivatives_lanes` at 4 and 8 lanes, ns per state.
const BATCHED_DERIVATIVES: &str = r#"
fn batched_derivatives_at<const W: usize>(
    reps: usize,
    m: &model::MODEL,
    packs: &[Pack<W>],
) -> String {
    let models = [*m; W];
    let mut out = [Lanes::<W>::splat(0.0); model::DERIVATIVES_LEN];
    time(packs.len(), W, reps, |k| {
        let (q, u, tau) = &packs[k];
        model::MODEL::forward_dynamics_derivatives_lanes(
            &models,
            Lanes::splat(0.0),
            black_box(q),
            black_box(u),
            black_box(tau),
            &mut out,
        );
        black_box(&mut out);
    })
}

fn batched_derivatives(reps: usize, m: &model::MODEL, states: &[(Q, U, U, U)]) -> String {
    format!(
        ",\"batched_forward_dynamics_derivatives\":{{\"4\":{},\"8\":{}}}",
        batched_derivatives_at::<4>(reps, m, &packs_of(states)),
        batched_derivatives_at::<8>(reps, m, &packs_of(states)),
    )
}
"#;

/// What replaces `MAIN`'s last line when the derivatives are timed too (the
/// model file then defines `DERIVATIVES_LEN`).
const PRINT: &str = r#"    println!("{{\"forward_dynamics\":{fd},\"mass_matrix\":{mass},\"inverse_dynamics\":{id}{extra}}}");"#;
const PRINT_WITH_DERIVATIVES: &str = r#"    let mut jac = [0.0; model::DERIVATIVES_LEN];
    let dfd = time(n, 1, reps, |k| {
        let (q, u, tau, _) = &states[k];
        m.forward_dynamics_derivatives(0.0, black_box(q), black_box(u), black_box(tau), &mut jac);
        black_box(&mut jac);
    });
    println!("{{\"forward_dynamics\":{fd},\"mass_matrix\":{mass},\"inverse_dynamics\":{id},\"forward_dynamics_derivatives\":{dfd}{extra}}}");"#;

/// Builds (once, cached) the timing program of a generated model and runs it.
pub fn per_call(g: &Generated, o: &PerCallOptions) -> Result<PerCall, Error> {
    let name = &g.checked.system.name;
    let mut model = format!("{}\npub type MODEL = {};\n", g.source, camel(name));
    let derivatives = g
        .formulation
        .program(eom_gen::functions::Function::ForwardDynamicsDerivatives)
        .filter(|_| o.derivatives);
    let mut main = match derivatives {
        Some(p) => {
            model += &format!("pub const DERIVATIVES_LEN: usize = {};\n", p.outputs.len());
            MAIN.replace(PRINT, PRINT_WITH_DERIVATIVES)
        }
        None => MAIN.to_string(),
    };
    if o.batch {
        main += BATCHED;
        main += if derivatives.is_some() {
            BATCHED_DERIVATIVES
        } else {
            NO_BATCHED_DERIVATIVES
        };
    } else {
        main += NO_EXTRA;
    }
    if derivatives.is_some() && !MAIN.contains(PRINT) {
        return Err(Error::Program(
            "internal: the timing program's last line changed; `PRINT` must match it".into(),
        ));
    }
    let exe = build_cached(&CachedCrate {
        prefix: "eom-bench",
        name,
        main: &main,
        model: &model,
        rustflags: o.native.then_some("-C target-cpu=native"),
    })?;
    let out = std::process::Command::new(&exe)
        .args([o.states.to_string(), o.reps.to_string(), o.seed.to_string()])
        .output()
        .map_err(|e| Error::Program(format!("cannot run {}: {e}", exe.display())))?;
    if !out.status.success() {
        return Err(Error::Program(format!(
            "{} failed ({}): {}",
            exe.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr)
        )));
    }
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| Error::Program(format!("unexpected output of {}: {e}", exe.display())))?;
    let timing = |f: &str| -> Result<Timing, Error> {
        let x = |k: &str| {
            let at = f.split('/').fold(&v, |v, key| &v[key]);
            at[k]
                .as_f64()
                .ok_or_else(|| Error::Program(format!("{} printed no `{f}.{k}`", exe.display())))
        };
        Ok(Timing {
            median: x("median")?,
            q1: x("q1")?,
            q3: x("q3")?,
            min: x("min")?,
            max: x("max")?,
        })
    };
    Ok(PerCall {
        forward_dynamics: timing("forward_dynamics")?,
        mass_matrix: timing("mass_matrix")?,
        inverse_dynamics: timing("inverse_dynamics")?,
        derivatives: match derivatives {
            Some(_) => Some(timing("forward_dynamics_derivatives")?),
            None => None,
        },
        batched: if o.batch {
            WIDTHS
                .iter()
                .map(|w| Ok((*w, timing(&format!("batched_forward_dynamics/{w}"))?)))
                .collect::<Result<_, Error>>()?
        } else {
            Vec::new()
        },
        batched_derivatives: if o.batch && derivatives.is_some() {
            DERIVATIVE_WIDTHS
                .iter()
                .map(|w| {
                    Ok((
                        *w,
                        timing(&format!("batched_forward_dynamics_derivatives/{w}"))?,
                    ))
                })
                .collect::<Result<_, Error>>()?
        } else {
            Vec::new()
        },
    })
}

/// Total operation counts of forward dynamics, mass matrix and inverse
/// dynamics (as `eom-gen stats` counts them), `None` where not generated.
pub fn op_totals(g: &Generated) -> [Option<usize>; 3] {
    let f = &g.formulation;
    [
        f.program(eom_gen::functions::Function::ForwardDynamics),
        f.program(eom_gen::functions::Function::MassMatrix),
        f.program(eom_gen::functions::Function::InverseDynamics),
    ]
    .map(|p| p.as_ref().map(|p| p.op_count().total()))
}

/// The JSON report: `{"model", "forward_dynamics_ns", "mass_matrix_ns",
/// "inverse_dynamics_ns"` (with `--derivatives` also
/// `"forward_dynamics_derivatives_ns"`, in `ops` and `spread` too)`,
/// "ops": {…}, "fd_form", "spread", "states",
/// "reps", "seed", "target_cpu_native", "fma"}`; with `--batch` also
/// `"batched_forward_dynamics_ns"` (the median ns per state of the fastest
/// pack width), `"batched_width"` (that width) and
/// `"batched_forward_dynamics_ns_by_width"`, and with `--derivatives` as
/// well `"batched_forward_dynamics_derivatives_ns"`,
/// `"batched_derivatives_width"` and
/// `"batched_forward_dynamics_derivatives_ns_by_width"`.
pub fn json(g: &Generated, o: &PerCallOptions, r: &PerCall) -> serde_json::Value {
    let [fd, mm, id] = op_totals(g);
    let spread =
        |t: &Timing| serde_json::json!({"q1": t.q1, "q3": t.q3, "min": t.min, "max": t.max});
    let mut v = serde_json::json!({
        "model": g.checked.system.name,
        "forward_dynamics_ns": r.forward_dynamics.median,
        "mass_matrix_ns": r.mass_matrix.median,
        "inverse_dynamics_ns": r.inverse_dynamics.median,
        "ops": {"forward_dynamics": fd, "mass_matrix": mm, "inverse_dynamics": id},
        "fd_form": format!("{:?}", g.formulation.fd_form),
        "spread": {
            "forward_dynamics": spread(&r.forward_dynamics),
            "mass_matrix": spread(&r.mass_matrix),
            "inverse_dynamics": spread(&r.inverse_dynamics),
        },
        "states": o.states,
        "reps": o.reps,
        "seed": o.seed,
        "target_cpu_native": o.native,
        "fma": o.fma,
    });
    if let Some(t) = &r.derivatives {
        let ops = g
            .formulation
            .program(eom_gen::functions::Function::ForwardDynamicsDerivatives)
            .map(|p| p.op_count().total());
        v["forward_dynamics_derivatives_ns"] = serde_json::json!(t.median);
        v["ops"]["forward_dynamics_derivatives"] = serde_json::json!(ops);
        v["spread"]["forward_dynamics_derivatives"] = spread(t);
    }
    if let Some((w, best)) = r.best_batched() {
        v["batched_forward_dynamics_ns"] = serde_json::json!(best.median);
        v["batched_width"] = serde_json::json!(w);
        v["batched_forward_dynamics_ns_by_width"] = r
            .batched
            .iter()
            .map(|(w, t)| (w.to_string(), serde_json::json!(t.median)))
            .collect::<serde_json::Map<_, _>>()
            .into();
        v["spread"]["batched_forward_dynamics"] = spread(&best);
    }
    if let Some((w, best)) = r.best_batched_derivatives() {
        v["batched_forward_dynamics_derivatives_ns"] = serde_json::json!(best.median);
        v["batched_derivatives_width"] = serde_json::json!(w);
        v["batched_forward_dynamics_derivatives_ns_by_width"] = r
            .batched_derivatives
            .iter()
            .map(|(w, t)| (w.to_string(), serde_json::json!(t.median)))
            .collect::<serde_json::Map<_, _>>()
            .into();
        v["spread"]["batched_forward_dynamics_derivatives"] = spread(&best);
    }
    v
}

/// The human report: one row per function.
pub fn table(g: &Generated, o: &PerCallOptions, r: &PerCall) -> String {
    let sys = &g.checked.system;
    let mut s = format!(
        "{}: ns per call, median of {} repetitions over {} random states{}\n",
        sys.name,
        o.reps,
        o.states,
        match (o.native, o.fma) {
            (true, true) => " (target-cpu=native, mul_add)",
            (true, false) => " (target-cpu=native)",
            _ => "",
        }
    );
    s += &format!(
        "  {:<28} {:>10} {:>10} {:>10} {:>10} {:>10} {:>8} {:>7}\n",
        "function", "median", "q1", "q3", "min", "max", "ops", "ops/ns"
    );
    let ops = op_totals(g);
    let derivative_ops = g
        .formulation
        .program(eom_gen::functions::Function::ForwardDynamicsDerivatives)
        .map(|p| p.op_count().total());
    let rows = [
        ("forward_dynamics", Some(&r.forward_dynamics), ops[0]),
        ("mass_matrix", Some(&r.mass_matrix), ops[1]),
        ("inverse_dynamics", Some(&r.inverse_dynamics), ops[2]),
        (
            "forward_dynamics_derivatives",
            r.derivatives.as_ref(),
            derivative_ops,
        ),
    ];
    // One row: the function, its timing, its operations and their rate.
    let row = |f: &str, t: &Timing, n: Option<usize>| {
        let (n, rate) = match n {
            Some(n) => (n.to_string(), format!("{:.2}", n as f64 / t.median)),
            None => ("-".into(), "-".into()),
        };
        format!(
            "  {f:<28} {:>10.1} {:>10.1} {:>10.1} {:>10.1} {:>10.1} {n:>8} {rate:>7}\n",
            t.median, t.q1, t.q3, t.min, t.max
        )
    };
    for (f, t, n) in rows {
        if let Some(t) = t {
            s += &row(f, t, n);
        }
    }
    for (w, t) in &r.batched {
        s += &row(&format!("forward_dynamics_lanes W={w}"), t, ops[0]);
    }
    for (w, t) in &r.batched_derivatives {
        s += &row(&format!("derivatives_lanes W={w}"), t, derivative_ops);
    }
    if let Some((w, _)) = r.best_batched() {
        let derivatives = r
            .best_batched_derivatives()
            .map(|(w, _)| format!(" ({w} for the derivatives)"))
            .unwrap_or_default();
        s += &format!(
            "  batched rows: ns per state, {w} states per call the fastest{derivatives}\n"
        );
    }
    s += &format!("  forward dynamics: {}\n", g.formulation.fd_form);
    if !sys.graph.cut_joints().is_empty() || !sys.constraints.is_empty() {
        s += "  note: closed loops or constraints; these are the spanning tree's functions\n";
    }
    s
}

#[cfg(test)]
mod tests {
    /// The derivatives' timing replaces the timing program's last line.
    #[test]
    fn the_print_line_is_in_the_timing_program() {
        assert!(super::MAIN.contains(super::PRINT));
    }
}
