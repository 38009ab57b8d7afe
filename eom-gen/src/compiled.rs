//! Running the generated code compiled: `eom-gen eval` writes a small crate
//! around a model's generated source into a cache directory keyed by the
//! content hash, builds it in release mode once (cargo shows its progress),
//! and reuses the binary on later calls.
//!
//! The cache is `$EOM_CACHE_DIR`, else `$XDG_CACHE_HOME/eom`, else
//! `~/.cache/eom`; all cached crates share one target directory there.

use crate::emit::{camel, fnv1a};
use crate::interpret::Evaluation;
use std::path::PathBuf;
use std::process::Command;

fn cache_root() -> PathBuf {
    if let Some(d) = std::env::var_os("EOM_CACHE_DIR") {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(d).join("eom");
    }
    match std::env::var_os("HOME") {
        Some(h) => PathBuf::from(h).join(".cache").join("eom"),
        None => std::env::temp_dir().join("eom-cache"),
    }
}

/// The `eom-sim` dependency line for the cached crate: this checkout's
/// source if present, else the published version.
fn eom_sim_dependency() -> String {
    let local = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../eom-sim"));
    match local.canonicalize() {
        Ok(p) if p.join("Cargo.toml").exists() => {
            format!("eom-sim = {{ path = {:?} }}", p.display().to_string())
        }
        _ => format!("eom-sim = \"{}\"", env!("CARGO_PKG_VERSION")),
    }
}

/// A hash of the local runtime's sources (empty without a checkout), so a
/// changed `eom-sim` rebuilds the cached crates.
fn runtime_fingerprint() -> String {
    fn walk(dir: &std::path::Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push((p.clone(), std::fs::read(&p).unwrap_or_default()));
            }
        }
    }
    let mut files = Vec::new();
    walk(
        &PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../eom-sim/src")),
        &mut files,
    );
    files.sort();
    let mut bytes = Vec::new();
    for (p, text) in files {
        bytes.extend(p.to_string_lossy().as_bytes());
        bytes.extend(text);
    }
    format!("{:016x}", fnv1a(&bytes))
}

const MAIN: &str = r#"//! Evaluates the generated model at a state given on the command line and
//! prints JSON: `eval Q U TAU T` with comma-separated lists.
mod model;
use eom_sim::{Model, Vector};

fn list(s: &str) -> Vec<f64> {
    s.split(',').filter(|x| !x.trim().is_empty()).map(|x| x.trim().parse().unwrap_or(f64::NAN)).collect()
}

fn vector<V: Vector>(v: &[f64]) -> V {
    let mut out = V::ZERO;
    for (o, x) in out.as_mut().iter_mut().zip(v) {
        *o = *x;
    }
    out
}

fn json(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| if x.is_finite() { format!("{x:?}") } else { "null".into() }).collect();
    format!("[{}]", items.join(","))
}

/// `sim INTEGRATOR RTOL ATOL DT T_END EVERY CSV CONSTRAINTS`: integrate from
/// the model's initial state (assembled, for constrained models) and print
/// JSON; `EVERY` 0 records the accepted steps.
fn simulate(args: &[String]) {
    use eom_sim::{ConstrainedModel, ConstrainedSystem, Generated, Index3System, Method, Settings, SolveOptions, solve};
    let arg = |k: usize| args.get(k).map(String::as_str).unwrap_or("");
    let num = |k: usize, d: f64| arg(k).parse::<f64>().unwrap_or(d);
    let settings = Settings {
        integrator: arg(2).to_string(),
        rtol: num(3, 1e-8),
        atol: num(4, 1e-10),
        dt: num(5, 1e-3),
        index_vars: (0, 0),
    };
    let (t_end, every) = (num(6, 1.0), num(7, 0.0));
    let m = model::MODEL::default();
    let (q0, u0) = (m.q0(), m.u0());
    let mut y0 = [0.0; model::NY];
    y0[..model::NQ].copy_from_slice(q0.as_ref());
    y0[model::NQ..].copy_from_slice(u0.as_ref());
    let opts = if every > 0.0 { SolveOptions::every(0.0, t_end, every) } else { SolveOptions::default() };
    let fail = |msg: &str| -> ! {
        eprintln!("{msg}");
        std::process::exit(1)
    };
    let start = std::time::Instant::now();
    if <model::MODEL as ConstrainedModel>::NC == 0 {
        let sol = solve(&settings, &m, 0.0, y0, t_end, &opts).unwrap_or_else(|| fail("unknown integrator"));
        report(&sol, &m, every, arg(8), start.elapsed().as_secs_f64(), &y0, "", &|_, _| None);
        return;
    }
    let g = Generated(&m);
    let a = eom_sim::constrained::assemble(&g, q0.as_ref(), u0.as_ref(), 0.0);
    y0[..model::NQ].copy_from_slice(&a.q);
    y0[model::NQ..].copy_from_slice(&a.u);
    let method = Method::from_name(arg(9)).unwrap_or(Method::Projection);
    let start = std::time::Instant::now();
    let stats_json = |s: eom_sim::ConstraintStats, lambda: &[f64]| {
        format!(
            ",\"constraints\":\"{}\",\"max_constraint_residual\":{:?},\"max_velocity_residual\":{:?},\"constraint_rank\":{},\"min_constraint_rank\":{},\"min_singular_ratio\":{:?},\"repartitions\":{},\"lambda\":{},\"constraint_names\":[{}],\"assembly\":{{\"residual\":{:?},\"velocity_residual\":{:?},\"iterations\":{}}}",
            arg(9), s.max_position_residual, s.max_velocity_residual, s.rank, s.min_rank, s.min_singular_ratio, s.repartitions, json(lambda),
            <model::MODEL as ConstrainedModel>::CONSTRAINT_NAMES.iter().map(|n| format!("{n:?}")).collect::<Vec<_>>().join(","),
            a.residual, a.velocity_residual, a.iterations
        )
    };
    if method == Method::Index3 {
        let sys = Index3System::new(&g);
        let y0c = sys.initial::<{ model::NYC }>(0.0, &a.q, &a.u).unwrap_or_else(|| fail("the mass matrix is singular at the initial state"));
        let s = Settings { index_vars: sys.index_vars(), ..settings };
        let sol = solve(&s, &sys, 0.0, y0c, t_end, &opts).unwrap_or_else(|| fail("unknown integrator"));
        let cpu = start.elapsed().as_secs_f64();
        let extra = stats_json(sys.stats(), &sys.multipliers(&sol.y_final));
        let outputs_at = ConstrainedSystem::new(&g, Method::Projection);
        report(&sol, &m, every, arg(8), cpu, &y0, &extra, &|t, y| outputs_at.accelerations(t, &y[..model::NQ], &y[model::NQ..model::NY]));
    } else {
        let sys = ConstrainedSystem::new(&g, method);
        let sol = solve(&settings, &sys, 0.0, y0, t_end, &opts).unwrap_or_else(|| fail("unknown integrator"));
        let cpu = start.elapsed().as_secs_f64();
        let (q, u) = sol.y_final.split_at(model::NQ);
        let lambda = sys.accelerations(sol.t_final, q, u).map(|(_, l)| l.as_slice().to_vec()).unwrap_or_default();
        let extra = stats_json(sys.stats(), &lambda);
        report(&sol, &m, every, arg(8), cpu, &y0, &extra, &|t, y| sys.accelerations(t, &y[..model::NQ], &y[model::NQ..model::NY]));
    }
}

fn state(y: &[f64]) -> (<model::MODEL as Model>::Q, <model::MODEL as Model>::U) {
    let mut q = <model::MODEL as Model>::Q::ZERO;
    let mut u = <model::MODEL as Model>::U::ZERO;
    q.as_mut().copy_from_slice(&y[..model::NQ]);
    u.as_mut().copy_from_slice(&y[model::NQ..model::NY]);
    (q, u)
}

/// `u̇` and `λ` of a constrained model at a state, for the outputs.
type Accelerations<'a> = dyn Fn(f64, &[f64]) -> Option<(eom_sim::constrained::DVector<f64>, eom_sim::constrained::DVector<f64>)> + 'a;

/// Prints the run's JSON (and writes the CSV) from the `(q, u)` part of its
/// states; outputs use the constrained accelerations and multipliers when
/// `constrained` gives them.
#[allow(clippy::too_many_arguments)]
fn report<const N: usize>(sol: &eom_sim::Solution<N>, m: &model::MODEL, every: f64, csv: &str, cpu: f64, y0: &[f64], extra: &str, constrained: &Accelerations<'_>) {
    use eom_sim::StopReason;
    let names: Vec<&str> = <model::MODEL as Model>::COORDINATE_NAMES
        .iter()
        .chain(<model::MODEL as Model>::SPEED_NAMES)
        .copied()
        .collect();
    let stop = match sol.stop {
        StopReason::Finished => "\"finished\"".to_string(),
        StopReason::NonFinite { t, component } => format!(
            "{{\"reason\":\"non-finite state\",\"t\":{t:?},\"coordinate\":\"{}\"}}",
            names.get(component).copied().unwrap_or("multiplier")
        ),
        other => format!("\"{other:?}\""),
    };
    if !csv.is_empty() && csv != "-" {
        let (ts, ys) = if every > 0.0 { (&sol.t_out, &sol.y_out) } else { (&sol.t, &sol.y) };
        let outputs = <model::MODEL as Model>::OUTPUT_NAMES;
        let header: Vec<&str> = names.iter().chain(outputs).copied().collect();
        let mut text = format!("t,{}\n", header.join(","));
        for (t, y) in ts.iter().zip(ys) {
            let mut row: Vec<String> = y[..model::NY].iter().map(|x| format!("{x:?}")).collect();
            if !outputs.is_empty() {
                // Outputs at the sample; reactions need u̇ from forward dynamics.
                let (q, u) = state(y);
                let mut udot = <model::MODEL as Model>::U::ZERO;
                let mut at = *m;
                match constrained(*t, y) {
                    Some((a, lambda)) => {
                        udot.as_mut().iter_mut().zip(a.iter()).for_each(|(d, s)| *d = *s);
                        let mut l = <<model::MODEL as eom_sim::ConstrainedModel>::Constraints as Vector>::ZERO;
                        l.as_mut().iter_mut().zip(lambda.iter()).for_each(|(d, s)| *d = *s);
                        eom_sim::ConstrainedModel::set_multipliers(&mut at, &l);
                    }
                    None => m.forward_dynamics(*t, &q, &u, &<model::MODEL as Model>::U::ZERO, &mut udot),
                }
                let mut out = <model::MODEL as Model>::Outputs::ZERO;
                at.outputs(*t, &q, &u, &udot, &mut out);
                row.extend(out.as_ref().iter().map(|x| format!("{x:?}")));
            }
            text += &format!("{t:?},{}\n", row.join(","));
        }
        if let Err(e) = std::fs::write(csv, text) {
            eprintln!("cannot write {csv}: {e}");
            std::process::exit(1);
        }
    }
    let s = &sol.stats;
    let energy = |y: &[f64], t: f64| -> f64 {
        let (q, u) = state(y);
        m.energy(t, &q, &u).iter().sum()
    };
    let (e0, e1) = (energy(y0, 0.0), energy(&sol.y_final, sol.t_final));
    println!(
        "{{\"t\":{:?},\"q\":{},\"u\":{},\"energy\":[{e0:?},{e1:?}],\"stop\":{stop},\"stats\":{{\"steps\":{},\"accepted\":{},\"rejected\":{},\"rhs_evals\":{},\"jacobian_evals\":{},\"lu_decompositions\":{},\"newton_iterations\":{},\"stiffness_detections\":{}}},\"cpu_s\":{cpu:?}{extra}}}",
        sol.t_final,
        json(&sol.y_final[..model::NQ]),
        json(&sol.y_final[model::NQ..model::NY]),
        s.steps, s.accepted, s.rejected, s.rhs_evals, s.jac_evals, s.lu_decomps, s.newton_iters, s.stiffness_detections
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("sim") {
        simulate(&args);
        return;
    }
    let arg = |k: usize| args.get(k).map(String::as_str).unwrap_or("");
    let m = model::MODEL::default();
    let q: <model::MODEL as Model>::Q = vector(&list(arg(1)));
    let u: <model::MODEL as Model>::U = vector(&list(arg(2)));
    let tau: <model::MODEL as Model>::U = vector(&list(arg(3)));
    let t: f64 = arg(4).parse().unwrap_or(0.0);
    let mut qdot = <model::MODEL as Model>::Q::ZERO;
    m.qdot(&q, &u, &mut qdot);
    let mut udot = <model::MODEL as Model>::U::ZERO;
    m.forward_dynamics(t, &q, &u, &tau, &mut udot);
    let mut mm = <model::MODEL as Model>::MASS_ZERO;
    m.mass_matrix(t, &q, &mut mm);
    let mut b = <model::MODEL as Model>::U::ZERO;
    m.bias(t, &q, &u, &mut b);
    let e = m.energy(t, &q, &u);
    let rows: Vec<String> = mm.as_ref().iter().map(|r| json(r.as_ref())).collect();
    println!(
        "{{\"qdot\":{},\"udot\":{},\"mass_matrix\":[{}],\"bias\":{},\"kinetic_energy\":{},\"potential_energy\":{}}}",
        json(qdot.as_ref()), json(udot.as_ref()), rows.join(","), json(b.as_ref()), json(&e[..1]).trim_matches(|c| c == '[' || c == ']'), json(&e[1..]).trim_matches(|c| c == '[' || c == ']')
    );
}
"#;

/// The release profile of the cached crates: one codegen unit, so the
/// generated functions and the loops that call them are optimised together.
const PROFILE: &str = "[profile.release]\ncodegen-units = 1\n";

/// A model without constraint equations, as a constrained one with none
/// (so that one simulator template serves both).
const UNCONSTRAINED: &str = "
impl ::eom_sim::ConstrainedModel for MODEL_TYPE {
    const NC: usize = 0;
    const NHOLONOMIC: usize = 0;
    const CONSTRAINT_NAMES: &'static [&'static str] = &[];
    type Constraints = [f64; 0];
    type ConstraintJacobian = [f64; 0];
    fn set_multipliers(&mut self, _: &[f64; 0]) {}
    fn constraints(&self, _: f64, _: &[f64; NQ], _: &[f64; NY - NQ], _: &mut [f64; 0], _: &mut [f64; 0], _: &mut [f64; 0], _: &mut [f64; 0]) {}
}
";

/// The `model` module of a cached crate: the generated source, `MODEL`
/// (its type), `NQ`, `NY = NQ + NU`, `NYC = NY + NC`, and an empty
/// `ConstrainedModel` impl for a model without constraints.
pub(crate) fn model_module(name: &str, source: &str, nq: usize, nu: usize) -> String {
    format!(
        "{source}\npub type MODEL = {};\n#[allow(dead_code)]\npub const NQ: usize = {nq};\npub const NY: usize = {};\npub const NYC: usize = NY + <MODEL as ::eom_sim::ConstrainedModel>::NC;\n{}",
        camel(name),
        nq + nu,
        if source.contains("impl ::eom_sim::ConstrainedModel for") {
            String::new()
        } else {
            UNCONSTRAINED.replace("MODEL_TYPE", &camel(name))
        }
    )
}

/// Builds (once) the cached crate of a model and returns its executable.
pub fn executable(name: &str, source: &str, nq: usize, nu: usize) -> Result<PathBuf, String> {
    let model = model_module(name, source, nq, nu);
    build_cached(&CachedCrate {
        prefix: "eom-eval",
        name,
        main: MAIN,
        model: &model,
        rustflags: None,
    })
}

/// A binary crate around a model's generated source, built in the cache.
pub(crate) struct CachedCrate<'a> {
    /// First part of the binary's name (`eom-eval`, `eom-bench`).
    pub prefix: &'a str,
    /// The model's name.
    pub name: &'a str,
    /// `src/main.rs`; it declares `mod model;`.
    pub main: &'a str,
    /// `src/model.rs`: the generated source and whatever `main` needs.
    pub model: &'a str,
    /// Extra `rustc` flags (e.g. `-C target-cpu=native`); such builds use
    /// their own target directory so the default one is not rebuilt.
    pub rustflags: Option<&'a str>,
}

/// Builds (once) a cached crate in release mode and returns its executable.
/// The cache key covers the sources, the flags and the runtime used.
pub(crate) fn build_cached(c: &CachedCrate<'_>) -> Result<PathBuf, String> {
    let root = cache_root();
    let key = format!(
        "{:016x}",
        fnv1a(
            format!(
                "{}{}{PROFILE}{}{}{}",
                c.model,
                c.main,
                eom_sim_dependency(),
                runtime_fingerprint(),
                c.rustflags.unwrap_or("")
            )
            .as_bytes()
        )
    );
    let name = c.name;
    let dir = root.join(format!("{name}-{key}"));
    let exe_name = format!("{}-{name}-{key}", c.prefix);
    let target = root.join(if c.rustflags.is_some() {
        "target-flags"
    } else {
        "target"
    });
    let exe = target.join("release").join(&exe_name);
    if !exe.exists() {
        std::fs::create_dir_all(dir.join("src"))
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        let manifest = format!(
            "[package]\nname = \"{exe_name}\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n[dependencies]\n{}\n\n[workspace]\n\n{PROFILE}",
            eom_sim_dependency()
        );
        for (file, text) in [
            ("Cargo.toml", manifest.as_str()),
            ("src/main.rs", c.main),
            ("src/model.rs", c.model),
        ] {
            std::fs::write(dir.join(file), text)
                .map_err(|e| format!("cannot write {file}: {e}"))?;
        }
        eprintln!("compiling the generated code of `{name}` in release mode (first time only) …");
        let mut cargo = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
        cargo
            .args(["build", "--release", "--manifest-path"])
            .arg(dir.join("Cargo.toml"))
            .arg("--target-dir")
            .arg(&target);
        if let Some(flags) = c.rustflags {
            cargo.env_remove("RUSTFLAGS").env(
                "CARGO_ENCODED_RUSTFLAGS",
                flags.split_whitespace().collect::<Vec<_>>().join("\u{1f}"),
            );
        }
        let status = cargo
            .status()
            .map_err(|e| format!("cannot run cargo: {e}"))?;
        if !status.success() {
            return Err(format!(
                "building the generated code failed ({status}); the crate is in {}",
                dir.display()
            ));
        }
    }
    Ok(exe)
}

/// Builds (once) and runs the compiled model at a state.
pub fn evaluate(
    name: &str,
    source: &str,
    q: &[f64],
    u: &[f64],
    tau: &[f64],
    t: f64,
) -> Result<Evaluation, String> {
    let exe = executable(name, source, q.len(), u.len())?;
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:?}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let out = Command::new(&exe)
        .args([join(q), join(u), join(tau), format!("{t:?}")])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("unexpected output of {}: {e}", exe.display()))?;
    let vec = |k: &str| -> Vec<f64> {
        v[k].as_array()
            .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
            .unwrap_or_default()
    };
    let mass_matrix = v["mass_matrix"]
        .as_array()
        .map(|rows| {
            rows.iter()
                .map(|r| {
                    r.as_array()
                        .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
                        .unwrap_or_default()
                })
                .collect()
        })
        .unwrap_or_default();
    Ok(Evaluation {
        qdot: vec("qdot"),
        udot: vec("udot"),
        mass_matrix,
        bias: vec("bias"),
        kinetic_energy: v["kinetic_energy"].as_f64().unwrap_or(f64::NAN),
        potential_energy: v["potential_energy"].as_f64().unwrap_or(f64::NAN),
    })
}

/// How to integrate.
#[derive(Clone, Debug)]
pub struct SimOptions {
    /// `euler`, `rk4`, `midpoint`, `dopri5`, `dop853` or `radau5`.
    pub integrator: String,
    /// Relative tolerance (adaptive methods).
    pub rtol: f64,
    /// Absolute tolerance (adaptive methods).
    pub atol: f64,
    /// Step size (fixed-step methods).
    pub dt: f64,
    /// End time.
    pub t_end: f64,
    /// Output interval for the CSV (dense output); 0 = accepted steps.
    pub every: f64,
    /// CSV file to write, if any.
    pub csv: Option<String>,
    /// Constraints: `multipliers` (Baumgarte), `projection`, `partitioning`
    /// or `index3` (RADAU5 only).
    pub constraints: String,
}

/// Integrates the compiled model from its initial state; returns the JSON
/// object the simulator printed.
pub fn simulate(
    name: &str,
    source: &str,
    nq: usize,
    nu: usize,
    o: &SimOptions,
) -> Result<serde_json::Value, String> {
    let exe = executable(name, source, nq, nu)?;
    let out = Command::new(&exe)
        .args([
            "sim".to_string(),
            o.integrator.clone(),
            format!("{:?}", o.rtol),
            format!("{:?}", o.atol),
            format!("{:?}", o.dt),
            format!("{:?}", o.t_end),
            format!("{:?}", o.every),
            o.csv.clone().unwrap_or_else(|| "-".into()),
            o.constraints.clone(),
        ])
        .output()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    serde_json::from_slice(&out.stdout)
        .map_err(|e| format!("unexpected output of {}: {e}", exe.display()))
}
