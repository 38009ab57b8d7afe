//! `eom-gen simulate MODEL --ensemble N [--seed S] [--perturb q=σ,u=σ]
//! [--param-spread NAME=σ]`: `N` seeded perturbations of the initial state
//! (and of tunable parameters) run compiled, `--lanes` at a time in SIMD
//! lanes ([`crate::lanes`]), with a results table of the final states and
//! per-member statistics.
//!
//! Member `k`'s draws depend only on the seed, `k` and the component (a
//! splitmix64 hash and Box–Muller, as the sweep's `--samples`), so a run
//! is reproducible and a member is the same whatever `N` or `--lanes`.

use crate::error::Error;
use crate::lanes::{LaneCase, LaneRun};
use crate::output::fail;
use eom_sim::RunOptions;
use eom_sim::run::Stop;
use std::process::ExitCode;

/// What `--ensemble` draws.
#[derive(Clone, Debug, Default)]
pub struct Spread {
    /// Members.
    pub n: usize,
    /// Seed.
    pub seed: u64,
    /// Standard deviation of every initial position (`--perturb q=σ`).
    pub q: f64,
    /// Standard deviation of every initial speed (`--perturb u=σ`).
    pub u: f64,
    /// Parameters and their standard deviations (`--param-spread`).
    pub params: Vec<(String, f64)>,
    /// States per call.
    pub width: usize,
    /// Build with `-C target-cpu=native`.
    pub native: bool,
}

/// `--perturb q=σ,u=σ` (either part may be left out).
pub fn parse_perturb(text: &str) -> Result<(f64, f64), String> {
    let (mut q, mut u) = (0.0, 0.0);
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let bad = || {
            format!(
                "--perturb `{part}`: expected q=σ or u=σ (standard deviations of the initial \
                 positions and speeds, non-negative numbers), e.g. --perturb q=0.01,u=0.1"
            )
        };
        let (name, v) = part.split_once('=').ok_or_else(bad)?;
        let v: f64 = v
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v >= 0.0)
            .ok_or_else(bad)?;
        match name.trim() {
            "q" => q = v,
            "u" => u = v,
            _ => return Err(bad()),
        }
    }
    Ok((q, u))
}

/// `--param-spread NAME=σ`.
pub fn parse_param_spread(text: &str) -> Result<(String, f64), String> {
    let bad = || {
        format!(
            "--param-spread `{text}`: expected NAME=σ (the standard deviation of a parameter \
             across the members, a non-negative number)"
        )
    };
    let (name, v) = text.split_once('=').ok_or_else(bad)?;
    let v: f64 = v
        .trim()
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite() && *v >= 0.0)
        .ok_or_else(bad)?;
    let name = name.trim();
    if name.is_empty() {
        return Err(bad());
    }
    Ok((name.to_string(), v))
}

/// splitmix64 (Steele, Lea and Flood 2014).
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A standard normal number for member `k`, component `j` (Box–Muller of
/// two uniforms in `(0, 1]` and `[0, 1)`).
fn normal(seed: u64, k: usize, j: usize) -> f64 {
    let u = |salt: u64| {
        let z = mix(mix(mix(mix(seed) ^ k as u64) ^ j as u64) ^ salt);
        (z >> 11) as f64 / (1u64 << 53) as f64
    };
    let (a, b) = (1.0 - u(1), u(2));
    (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
}

/// Member `k`'s initial state and parameter values around the nominal
/// ones; unit quaternions renormalised.
fn member(
    s: &Spread,
    k: usize,
    q0: &[f64],
    u0: &[f64],
    quats: &[usize],
    nominal: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let mut y: Vec<f64> = q0.iter().chain(u0).copied().collect();
    let nq = q0.len();
    for (j, v) in y.iter_mut().enumerate() {
        let sigma = if j < nq { s.q } else { s.u };
        if sigma > 0.0 {
            *v += sigma * normal(s.seed, k, j);
        }
    }
    for &a in quats {
        if let Some(quat) = y.get_mut(a..a + 4) {
            let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
            if n > 0.0 {
                quat.iter_mut().for_each(|x| *x /= n);
            }
        }
    }
    let p = s
        .params
        .iter()
        .zip(nominal)
        .enumerate()
        .map(|(j, ((_, sigma), v))| v + sigma * normal(s.seed, k, y.len() + j))
        .collect();
    (p, y)
}

/// Runs the ensemble of an opened model (checked for lanes before) and
/// writes / prints the results.
pub fn run(
    opened: &crate::open::Opened,
    o: &RunOptions,
    s: &Spread,
    json: bool,
) -> Result<ExitCode, Error> {
    let sys = &opened.checked.system;
    // The spread parameters tunable; every other value as checked.
    let mut checked = opened.checked.clone();
    let names: Vec<String> = s.params.iter().map(|(n, _)| n.clone()).collect();
    let known: Vec<&str> = sys.parameters.iter().map(|p| p.name.as_str()).collect();
    let mut problems = Vec::new();
    for n in &names {
        if !known.contains(&n.as_str()) {
            let hint = match eom_gen::diag::did_you_mean(n, known.iter().copied()) {
                Some(m) => format!(" (did you mean `{m}`?)"),
                None => format!("; its parameters: {}", known.join(", ")),
            };
            problems.push(format!(
                "--param-spread: `{}` has no parameter `{n}`{hint}",
                sys.name
            ));
        }
    }
    if !problems.is_empty() {
        return Ok(fail(&Error::Usage(problems)));
    }
    for p in &mut checked.system.parameters {
        if names.contains(&p.name) {
            p.tunable = true;
        }
    }
    let nominal: Vec<f64> = names
        .iter()
        .map(|n| {
            checked
                .system
                .parameters
                .iter()
                .find(|p| &p.name == n)
                .map_or(f64::NAN, |p| p.value.value)
        })
        .collect();
    let formulation = eom_gen::generate::formulate_request(&checked, checked.request())
        .map_err(|e| Error::Refused(e.to_string()))?;
    let emit = eom_gen::EmitOptions {
        lanes: true,
        fma: s.native && crate::compiled::native_fma(),
        ..Default::default()
    };
    let sys = &checked.system;
    let source = eom_gen::emit::emit_with(sys, &formulation, &checked.content(), &emit);
    let tunable: Vec<String> = sys
        .parameters
        .iter()
        .filter(|p| p.tunable)
        .map(|p| p.name.clone())
        .collect();
    let q0 = o.q0.clone().unwrap_or_else(|| sys.q0());
    let u0 = o.u0.clone().unwrap_or_else(|| sys.u0());
    let quats = sys.quaternion_indices();
    let cases: Vec<LaneCase> = (0..s.n)
        .map(|k| {
            let (p, y0) = member(s, k, &q0, &u0, &quats, &nominal);
            LaneCase { p, y0 }
        })
        .collect();
    let run = LaneRun {
        integrator: o.integrator,
        rtol: o.rtol,
        atol: o.atol,
        dt: o.dt,
        t_end: o.t_end,
        max_steps: o.max_steps,
        width: s.width,
        threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        native: s.native,
    };
    let bar = indicatif::ProgressBar::new(s.n as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} members, {elapsed} elapsed, {eta} left",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(sys.name.clone());
    let started = std::time::Instant::now();
    let outcomes = crate::lanes::run(
        sys,
        &source,
        &tunable,
        &names,
        &opened.inputs,
        &run,
        &cases,
        &mut |n| bar.set_position(n as u64),
    )?;
    bar.finish_and_clear();
    let wall = started.elapsed().as_secs_f64();
    // The table: member, spread parameters, t, q, u, energies, counters.
    let mut header: Vec<String> = vec!["member".into()];
    header.extend(names.iter().cloned());
    header.push("t".into());
    header.extend(sys.coordinate_names().iter().map(|n| n.to_string()));
    header.extend(sys.speed_names().iter().map(|n| n.to_string()));
    header.extend(
        [
            "energy_start",
            "energy_end",
            "steps",
            "rejected",
            "rhs_evals",
            "cpu_s",
        ]
        .map(String::from),
    );
    let nan = |x: Option<f64>| x.unwrap_or(f64::NAN);
    let mut table = eom_sim::table::Table::new(header);
    let mut stops = Vec::new();
    for (k, (c, r)) in cases.iter().zip(&outcomes).enumerate() {
        let mut v = vec![k as f64];
        v.extend(&c.p);
        v.push(nan(r.t));
        v.extend(r.y.iter().map(|x| nan(*x)));
        v.extend(r.energy.map(nan));
        v.extend([
            r.steps as f64,
            r.rejected as f64,
            r.rhs_evals as f64,
            r.cpu_s,
        ]);
        table.push(v);
        stops.push(match &r.stop {
            Stop::Finished => "finished".to_string(),
            s => s.to_string(),
        });
    }
    let results = crate::study::Results { table, stop: stops };
    if let Some(path) = &o.csv
        && let Err(code) = crate::output::write_file(path, &results.to_csv())
    {
        return Ok(code);
    }
    let finished = outcomes
        .iter()
        .filter(|r| matches!(r.stop, Stop::Finished))
        .count();
    let steps: usize = outcomes.iter().map(|r| r.steps).sum();
    // The integration's own time (the packs', summed over threads), apart
    // from a first build.
    let cpu: f64 = outcomes.iter().map(|r| r.cpu_s).sum();
    let rhs: usize = outcomes.iter().map(|r| r.rhs_evals).sum();
    if json {
        let rows: Vec<serde_json::Value> = cases
            .iter()
            .zip(&outcomes)
            .enumerate()
            .map(|(k, (c, r))| {
                serde_json::json!({
                    "member": k,
                    "params": names.iter().cloned().zip(c.p.iter().copied()).collect::<std::collections::BTreeMap<_, _>>(),
                    "q0": &c.y0[..sys.nq()], "u0": &c.y0[sys.nq()..],
                    "t": r.t, "q": &r.y[..sys.nq()], "u": &r.y[sys.nq()..],
                    "energy": r.energy, "steps": r.steps, "rejected": r.rejected,
                    "rhs_evals": r.rhs_evals, "cpu_s": r.cpu_s, "stop": r.stop,
                })
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({
                "model": sys.name, "members": s.n, "seed": s.seed, "lanes": s.width,
                "integrator": o.integrator.to_string(), "t_end": o.t_end,
                "finished": finished, "wall_s": wall, "integration_s": cpu, "steps": steps, "rhs_evals": rhs,
                "members_results": rows,
            })
        );
    } else {
        println!(
            "{}: ensemble of {} members ({} states per call, seed {}) to t = {} s in {wall:.2} s \
             ({cpu:.3} s integrating): {finished} finished, {} stopped early or failed; {steps} \
             steps, {rhs} right-hand sides ({:.3e} state-steps/s integrating)",
            sys.name,
            s.n,
            s.width,
            s.seed,
            o.t_end,
            s.n - finished,
            steps as f64 / cpu.max(1e-12)
        );
        // Mean and standard deviation of the final state over the
        // finished members.
        let done: Vec<&crate::lanes::LaneOutcome> = outcomes
            .iter()
            .filter(|r| matches!(r.stop, Stop::Finished))
            .collect();
        if !done.is_empty() {
            println!("final state over the finished members: mean ± standard deviation");
            let state_names = crate::lanes::state_names(sys);
            for (j, n) in state_names.iter().enumerate() {
                let xs: Vec<f64> = done.iter().map(|r| nan(r.y[j])).collect();
                let mean = xs.iter().sum::<f64>() / xs.len() as f64;
                let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>()
                    / xs.len().max(2).saturating_sub(1) as f64;
                println!("  {n:>12} = {mean:.6e} ± {:.3e}", var.sqrt());
            }
        }
        for (k, r) in outcomes.iter().enumerate() {
            if !matches!(r.stop, Stop::Finished) {
                println!("member {k}: {}", r.stop);
            }
        }
        if let Some(path) = &o.csv {
            println!("results: {path}");
        }
    }
    Ok(if finished == s.n {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(3)
    })
}
