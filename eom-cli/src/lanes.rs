//! Many runs of one compiled model, `W` at a time in SIMD lanes: the
//! runner of `eom-gen sweep --compiled` and `eom-gen simulate --ensemble`.
//!
//! The model's source is generated with its batched functions
//! (`NAME_lanes::<W>`, `eom_sim::OdeLanes`) and built once into a cached
//! crate (as `simulate`'s, [`crate::compiled`]) whose program reads one
//! JSON request on standard input — the method, the end time, the names of
//! the tunable parameters set per case, and every case's parameter values
//! and initial state — and integrates the cases in packs of `W` lanes with
//! `eom_sim::integrate_lanes` (lane `l` of a pack: case `l`'s parameters
//! and state; a last, short pack repeats its last case in the spare
//! lanes). Packs are shared among threads. It prints `{"done": k}` after
//! each pack (the progress) and one line `{"results": […]}` at the end.
//!
//! Only models whose batched first-order system exists run here: no
//! constraints, no contacts, no cables, no events. Each lane's answer is
//! the single-state DOPRI5 / RK4 run's (see `eom_sim::ensemble`).

use crate::compiled::{CachedCrate, build_cached, model_module};
use crate::error::Error;
use eom_sim::Integrator;
use eom_sim::run::Stop;
use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};

/// The pack widths the runner is built for (1: one state per call, the
/// compiled baseline; 4: an AVX2 register; 8: two, or AVX-512).
pub const WIDTHS: [usize; 3] = [1, 4, 8];

/// The states per call when `--lanes` is not given: 8 for a `--native`
/// build on a CPU with AVX-512 (one `zmm` register a value: arm7's
/// ensemble 48 against 71 ns per state per right-hand side at 4, DOPRI5;
/// BENCHMARKS.md "Ensembles and sweeps in lanes"), else 4 (the default
/// build's SSE2 runs 4 and 8 alike; AVX2's register holds 4).
pub fn default_width(native: bool) -> usize {
    #[cfg(target_arch = "x86_64")]
    if native && std::arch::is_x86_feature_detected!("avx512f") {
        return 8;
    }
    let _ = native;
    4
}

/// How to run every case.
#[derive(Clone, Debug)]
pub struct LaneRun {
    /// `rk4` or `dopri5`.
    pub integrator: Integrator,
    /// Relative tolerance (dopri5).
    pub rtol: f64,
    /// Absolute tolerance (dopri5).
    pub atol: f64,
    /// Step size (rk4).
    pub dt: f64,
    /// End time, s.
    pub t_end: f64,
    /// Most attempted steps per case.
    pub max_steps: usize,
    /// States per call, one of [`WIDTHS`].
    pub width: usize,
    /// Threads sharing the packs.
    pub threads: usize,
    /// Build with `-C target-cpu=native` (AVX2 / AVX-512 lanes; the
    /// default build has SSE2's two lanes per instruction).
    pub native: bool,
}

/// The integrators the lanes run.
pub const INTEGRATORS: &str =
    "rk4 (fixed step, lanes in lockstep) or dopri5 (adaptive, each lane its own steps)";

/// One case: the swept parameters' values and the initial state `(q, u)`.
#[derive(Clone, Debug, serde::Serialize)]
pub struct LaneCase {
    /// Values of [`run`]'s `params`, in order.
    pub p: Vec<f64>,
    /// `(q0, u0)`.
    pub y0: Vec<f64>,
}

/// How one case ended.
#[derive(Clone, Debug, serde::Deserialize)]
pub struct LaneOutcome {
    /// Time reached.
    pub t: Option<f64>,
    /// `(q, u)` at `t`.
    pub y: Vec<Option<f64>>,
    /// Why it stopped.
    pub stop: Stop,
    /// Attempted steps.
    pub steps: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Right-hand sides evaluated for this lane.
    pub rhs_evals: usize,
    /// Total energy at the start and at `t`.
    pub energy: [Option<f64>; 2],
    /// This case's share of its pack's time, s (the pack's time over
    /// the cases it ran: the spare lanes of a short last pack are charged
    /// to its cases).
    pub cpu_s: f64,
}

/// The program of the cached crate (see the module docs).
const MAIN: &str = r#"//! Integrates many cases of the generated model for `eom-gen`, `W` per
//! call in SIMD lanes (`eom_sim::integrate_lanes`): one JSON request on
//! standard input; `{"done": k}` per pack and `{"results": [...]}` on
//! standard output.
mod model;
use eom_sim::Model as _;
use std::io::{Read, Write};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

#[derive(serde::Deserialize)]
struct Request {
    integrator: String,
    rtol: f64,
    atol: f64,
    dt: f64,
    t_end: f64,
    max_steps: usize,
    width: usize,
    threads: usize,
    inputs: Vec<f64>,
    params: Vec<String>,
    names: Vec<String>,
    cases: Vec<Case>,
}

#[derive(serde::Deserialize)]
struct Case {
    p: Vec<f64>,
    y0: Vec<f64>,
}

#[derive(serde::Serialize)]
struct Outcome {
    t: f64,
    y: Vec<f64>,
    stop: eom_sim::run::Stop,
    steps: usize,
    rejected: usize,
    rhs_evals: usize,
    energy: [f64; 2],
    cpu_s: f64,
}

/// Total energy at `y`.
fn energy(m: &model::MODEL, t: f64, y: &[f64; model::NY]) -> f64 {
    let q: [f64; model::NQ] = core::array::from_fn(|i| y[i]);
    let u: [f64; model::NU] = core::array::from_fn(|i| y[model::NQ + i]);
    let [k, p] = m.energy(t, &q, &u);
    k + p
}

/// One pack of at most `W` cases.
fn pack<const W: usize>(r: &Request, method: eom_sim::LaneMethod, cases: &[Case]) -> Vec<Outcome> {
    let mut models = [model::MODEL::default(); W];
    let mut y0 = [[0.0; model::NY]; W];
    for l in 0..W {
        let c = &cases[l.min(cases.len() - 1)];
        for (d, s) in models[l].inputs.iter_mut().zip(&r.inputs) {
            *d = *s;
        }
        for (n, v) in r.params.iter().zip(&c.p) {
            model::set_param(&mut models[l], n, *v);
        }
        for (d, s) in y0[l].iter_mut().zip(&c.y0) {
            *d = *s;
        }
    }
    let started = std::time::Instant::now();
    let rep = eom_sim::integrate_lanes(&models, method, 0.0, &y0, r.t_end, r.max_steps);
    let cpu_s = started.elapsed().as_secs_f64() / cases.len() as f64;
    rep.lanes
        .iter()
        .zip(&models)
        .zip(&y0)
        .take(cases.len())
        .map(|((lane, m), y0)| Outcome {
            t: lane.t,
            y: lane.y.to_vec(),
            stop: eom_sim::run::Stop::from_solver(lane.stop, &r.names),
            steps: lane.stats.steps,
            rejected: lane.stats.rejected,
            rhs_evals: lane.stats.rhs_evals,
            energy: [energy(m, 0.0, y0), energy(m, lane.t, &lane.y)],
            cpu_s,
        })
        .collect()
}

fn main() {
    let mut text = String::new();
    let _ = std::io::stdin().read_to_string(&mut text);
    let r: Request = match serde_json::from_str(&text) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("bad request: {e}");
            std::process::exit(2);
        }
    };
    let method = match r.integrator.as_str() {
        "rk4" => eom_sim::LaneMethod::Rk4 { dt: r.dt },
        _ => eom_sim::LaneMethod::Dopri5 { rtol: r.rtol, atol: r.atol },
    };
    let w = r.width.max(1);
    let packs: Vec<&[Case]> = r.cases.chunks(w).collect();
    let results: Mutex<Vec<Option<Vec<Outcome>>>> = Mutex::new((0..packs.len()).map(|_| None).collect());
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..r.threads.max(1).min(packs.len().max(1)) {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(cases) = packs.get(k) else { break };
                let out = match w {
                    8 => pack::<8>(&r, method, cases),
                    4 => pack::<4>(&r, method, cases),
                    _ => pack::<1>(&r, method, cases),
                };
                if let Ok(mut all) = results.lock() {
                    all[k] = Some(out);
                }
                let n = done.fetch_add(cases.len(), Ordering::Relaxed) + cases.len();
                let _ = writeln!(std::io::stdout().lock(), "{{\"done\":{n}}}");
            });
        }
    });
    let all: Vec<Outcome> = results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .flatten()
        .collect();
    match serde_json::to_string(&all) {
        Ok(text) => println!("{{\"results\":{text}}}"),
        Err(e) => {
            eprintln!("cannot encode the results: {e}");
            std::process::exit(1);
        }
    }
}
"#;

/// The `model` module of the lanes' crate: [`model_module`]'s, `NU`, and
/// `set_param` (a tunable parameter by name).
fn lanes_model(name: &str, source: &str, nq: usize, nu: usize, tunable: &[String]) -> String {
    let fields = eom_gen::emit::field_names(tunable.iter().map(String::as_str));
    let arms: String = tunable
        .iter()
        .zip(&fields)
        .map(|(n, f)| format!("        {n:?} => m.params.{f} = v,\n"))
        .collect();
    format!(
        "{}pub const NU: usize = NY - NQ;\nconst _: usize = NYC;\n\n/// Sets the tunable parameter `name` of `m` (others: nothing).\n#[allow(unused_variables)]\npub fn set_param(m: &mut MODEL, name: &str, v: f64) {{\n    match name {{\n{arms}        _ => {{}}\n    }}\n}}\n",
        model_module(name, source, nq, nu)
    )
}

/// The model's state names (coordinates, then speeds), for the stops.
pub fn state_names(sys: &eom_gen::system::System) -> Vec<String> {
    sys.coordinate_names()
        .iter()
        .chain(sys.speed_names().iter())
        .map(|n| n.to_string())
        .collect()
}

/// Builds (once) the lanes' crate of a model generated with lanes (its
/// tunable parameters, in order, `tunable`) and runs `cases`;
/// `progress(done)` after every pack. The outcomes are in the cases'
/// order.
#[allow(clippy::too_many_arguments)]
pub fn run(
    sys: &eom_gen::system::System,
    source: &str,
    tunable: &[String],
    params: &[String],
    inputs: &[f64],
    o: &LaneRun,
    cases: &[LaneCase],
    progress: &mut dyn FnMut(usize),
) -> Result<Vec<LaneOutcome>, Error> {
    let model = lanes_model(&sys.name, source, sys.nq(), sys.nu(), tunable);
    let exe = build_cached(&CachedCrate {
        prefix: "eom-lanes",
        name: &sys.name,
        main: MAIN,
        model: &model,
        rustflags: o.native.then_some("-C target-cpu=native"),
    })?;
    let request = serde_json::json!({
        "integrator": o.integrator.to_string(), "rtol": o.rtol, "atol": o.atol, "dt": o.dt,
        "t_end": o.t_end, "max_steps": o.max_steps, "width": o.width, "threads": o.threads,
        "inputs": inputs, "params": params, "names": state_names(sys), "cases": cases,
    });
    let mut child = Command::new(&exe)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| Error::Program(format!("cannot run {}: {e}", exe.display())))?;
    {
        let mut stdin = child
            .stdin
            .take()
            .ok_or_else(|| Error::Program(format!("no input of {}", exe.display())))?;
        stdin
            .write_all(request.to_string().as_bytes())
            .map_err(|e| Error::Program(format!("writing to {}: {e}", exe.display())))?;
    }
    let stdout = child
        .stdout
        .take()
        .ok_or_else(|| Error::Program(format!("no output from {}", exe.display())))?;
    let mut results = None;
    for line in BufReader::new(stdout).lines() {
        let line = line.map_err(|e| Error::Program(format!("reading {}: {e}", exe.display())))?;
        let v: serde_json::Value = serde_json::from_str(&line)
            .map_err(|e| Error::Program(format!("unexpected output of {}: {e}", exe.display())))?;
        if let Some(n) = v.get("done").and_then(serde_json::Value::as_u64) {
            progress(n as usize);
        } else if let Some(r) = v.get("results") {
            results = Some(Vec::<LaneOutcome>::deserialize(r).map_err(|e| {
                Error::Program(format!("unexpected results of {}: {e}", exe.display()))
            })?);
        }
    }
    let out = child
        .wait_with_output()
        .map_err(|e| Error::Program(format!("waiting for {}: {e}", exe.display())))?;
    if !out.status.success() {
        return Err(Error::Program(format!(
            "the lanes' runner failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    let results =
        results.ok_or_else(|| Error::Program(format!("{} printed no results", exe.display())))?;
    if results.len() != cases.len() {
        return Err(Error::Program(format!(
            "{} returned {} results for {} cases",
            exe.display(),
            results.len(),
            cases.len()
        )));
    }
    Ok(results)
}

use serde::Deserialize as _;

/// Why a model cannot run in lanes, if it cannot: constraints, contacts,
/// cables (the batched first-order system is the unconstrained `τ = 0`
/// one).
pub fn refusal(checked: &eom_gen::Checked) -> Option<String> {
    let sys = &checked.system;
    let why = if crate::ancf::has_cables(checked) {
        "it has cables"
    } else if !sys.graph.cut_joints().is_empty() || !sys.constraints.is_empty() {
        "it has closed loops or constraints"
    } else if !sys.contacts.is_empty() {
        "it has contacts"
    } else {
        return None;
    };
    Some(format!(
        "`{}` cannot run in lanes: {why} (the lanes integrate the unconstrained first-order \
         system `y = (q, u)`, without events)",
        sys.name
    ))
}

/// Why an integrator cannot run in lanes, if it cannot.
pub fn integrator_refusal(i: Integrator) -> Option<String> {
    (!matches!(i, Integrator::Rk4 | Integrator::Dopri5))
        .then(|| format!("--integrator {i} does not run in lanes; they run {INTEGRATORS}"))
}

#[cfg(test)]
mod width_tests {
    use super::{WIDTHS, default_width};

    /// The default width is one the runner is built for; the default
    /// build (SSE2) takes 4 whatever the CPU.
    #[test]
    fn default_width_is_a_built_width() {
        assert_eq!(default_width(false), 4);
        assert!(WIDTHS.contains(&default_width(true)));
    }
}
