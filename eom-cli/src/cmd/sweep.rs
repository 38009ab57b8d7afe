//! `eom-gen sweep MODEL --param k=10:100:10 --param m=1,2 --t-end T --out
//! DIR`: a parameter study on every core (rayon), with a progress bar.
//!
//! The model is checked and formulated once with the swept parameters
//! made tunable (kept as symbols), and every case is run by the evaluator
//! (`eom_gen::interpret`) with its values: no code is generated or
//! compiled per case. Each case's values are still checked against the
//! model (a case the model forbids, such as a negative mass, is a failed
//! row with the reason); a case whose values change something the check
//! computes from them (a parameter defined through a swept one, the
//! initial state) is formulated on its own, so every row is what
//! `simulate --interpret --param …` gives. Results: `study::Results`.

use crate::args::parse_names;
use crate::error::Error;
use crate::output::fail;
use crate::study::{self, Results, Study};
use clap::Args;
use eom_gen::interpret::Interpreted;
use eom_sim::{Integrator, Method, RunOptions, Simulate, Stop};
use rayon::prelude::*;
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Run a model over a grid or random samples of its parameters, on every core.
#[derive(Args)]
pub struct SweepArgs {
    /// The model file (`.ron`, `.urdf`) or scene; not with --merge.
    pub model: Option<String>,
    /// A swept parameter: `NAME=a:b:step` (grid from a to b), `NAME=v1,v2,…`,
    /// `NAME=v`, or `NAME=a:b` (uniform, with --samples); repeatable: the
    /// grid is the cartesian product.
    #[arg(long = "param", value_name = "NAME=SPEC", allow_hyphen_values = true)]
    pub params: Vec<String>,
    /// Draw this many random cases instead of the grid.
    #[arg(long)]
    pub samples: Option<usize>,
    /// Seed of --samples (default 0).
    #[arg(long)]
    pub seed: Option<u64>,
    /// End time of every case, s.
    #[arg(long, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// rk4, dopri5 (default), dop853, radau5, midpoint or euler.
    #[arg(long)]
    pub integrator: Option<String>,
    /// Relative tolerance (adaptive methods; default 1e-8).
    #[arg(long, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// Absolute tolerance (adaptive methods; default 1e-10).
    #[arg(long, allow_hyphen_values = true)]
    pub atol: Option<f64>,
    /// Step size (fixed-step methods; default 1e-3).
    #[arg(long, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Most attempted steps per case (default 100000).
    #[arg(long)]
    pub max_steps: Option<usize>,
    /// How closed loops are kept (as `simulate --constraints`).
    #[arg(long)]
    pub constraints: Option<String>,
    /// Spectral radius at infinity of generalized-α (models with cables;
    /// default 1).
    #[arg(long, allow_hyphen_values = true)]
    pub rho_inf: Option<f64>,
    /// Outputs of the model recorded at the end time (comma-separated
    /// names of `simulate --csv` columns after the speeds; models without
    /// constraints).
    #[arg(long, value_delimiter = ',')]
    pub output: Vec<String>,
    /// Run slice I of N (0 ≤ I < N) of the cases: every N-th from I.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Worker threads (default: every core).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// The directory for results.csv and study.json (created).
    #[arg(long)]
    pub out: String,
    /// Run the cases compiled, `--lanes` at a time in SIMD lanes (the
    /// ensemble integrator; rk4 or dopri5; models without constraints,
    /// contacts or cables): the model is built once with its swept
    /// parameters tunable (cached), no recompiling per case.
    #[arg(long)]
    pub compiled: bool,
    /// With --compiled: states per call, 1, 4 or 8 (default 8 with
    /// --native on a CPU with AVX-512, else 4).
    #[arg(long, value_name = "W")]
    pub lanes: Option<usize>,
    /// With --compiled: build with `-C target-cpu=native` (wider SIMD
    /// lanes; the binary runs only on this kind of CPU).
    #[arg(long)]
    pub native: bool,
    /// Join the shards in these directories into --out instead of running.
    #[arg(long, num_args = 1.., value_name = "DIR")]
    pub merge: Vec<String>,
}

pub fn run(a: &SweepArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    if !a.merge.is_empty() {
        return merge(a);
    }
    let mut problems = Vec::new();
    let Some(model) = a.model.clone() else {
        return fail(&Error::Usage(vec![
            "give a MODEL to sweep, or --merge DIR… to join shards".into(),
        ]));
    };
    let axes: Vec<(String, study::Axis)> = a
        .params
        .iter()
        .filter_map(|p| study::parse_axis(p).map_err(|e| problems.push(e)).ok())
        .collect();
    if a.params.is_empty() {
        problems.push("--param NAME=SPEC: a sweep needs at least one parameter".into());
    }
    for (k, (n, _)) in axes.iter().enumerate() {
        if axes[..k].iter().any(|(m, _)| m == n) {
            problems.push(format!("--param `{n}` is given twice"));
        }
    }
    if a.seed.is_some() && a.samples.is_none() {
        problems
            .push("--seed seeds --samples; without --samples the grid has no randomness".into());
    }
    let Some(t_end) = a.t_end else {
        problems.push("--t-end T: the end time of every case".into());
        return fail(&Error::Usage(problems));
    };
    let shard = match a.shard.as_deref().map(study::parse_shard) {
        Some(Ok(s)) => s,
        Some(Err(e)) => {
            problems.push(e);
            (0, 1)
        }
        None => (0, 1),
    };
    if a.jobs == Some(0) {
        problems.push("--jobs must be at least 1".into());
    }
    let integrator = parse_names(
        &[a.integrator.clone().unwrap_or_else(|| "dopri5".into())],
        &mut problems,
    )
    .pop()
    .unwrap_or(Integrator::Dopri5);
    let method = parse_names(
        &[a.constraints.clone().unwrap_or_else(|| "projection".into())],
        &mut problems,
    )
    .pop()
    .unwrap_or(Method::Projection);
    let options = RunOptions {
        integrator,
        rtol: a.rtol.unwrap_or(1e-8),
        atol: a.atol.unwrap_or(1e-10),
        dt: a.dt.unwrap_or(1e-3),
        t_end,
        max_steps: a.max_steps.unwrap_or(100_000),
        method,
        ..RunOptions::default()
    };
    let all = match study::cases(&axes, a.samples, a.seed.unwrap_or(0)) {
        Ok(c) => c,
        Err(e) => {
            problems.push(e);
            Vec::new()
        }
    };
    // The model as the file has it; the swept names checked against it.
    let names: Vec<String> = axes.iter().map(|(n, _)| n.clone()).collect();
    let opened = match crate::open::open(&model, urdf, &crate::args::Vary::default()) {
        Ok(o) => o,
        Err(code) if problems.is_empty() => return code,
        Err(_) => return fail(&Error::Usage(problems)),
    };
    {
        let sys = &opened.checked.system;
        let known: Vec<&str> = sys.parameters.iter().map(|p| p.name.as_str()).collect();
        for n in &names {
            if !known.contains(&n.as_str()) {
                let hint = match eom_gen::diag::did_you_mean(n, known.iter().copied()) {
                    Some(m) => format!(" (did you mean `{m}`?)"),
                    None => format!("; its parameters: {}", known.join(", ")),
                };
                problems.push(format!("`{model}` has no parameter `{n}`{hint}"));
            }
        }
    }
    // Models with cables: the large-model runtime (`crate::cable_sweep`).
    if crate::ancf::has_cables(&opened.checked) {
        if !problems.is_empty() {
            return fail(&Error::Usage(problems));
        }
        let indices = study::shard(all.len(), shard);
        let plan = crate::cable_sweep::Plan {
            model: &model,
            checked: &opened.checked,
            urdf,
            names: &names,
            all: &all,
            indices: &indices,
            t_end,
        };
        return crate::cable_sweep::run(a, &plan);
    }
    problems.extend(options.problems());
    problems.extend(crate::args::unread_step_options(
        integrator,
        a.dt.is_some(),
        a.rtol.is_some() || a.atol.is_some(),
    ));
    let sys = &opened.checked.system;
    if a.rho_inf.is_some() {
        problems.push(format!(
            "--rho-inf sets generalized-α, which runs models with cables; `{}` has none (its \
             integrators: --integrator)",
            sys.name
        ));
    }
    if a.constraints.is_some() && sys.graph.cut_joints().is_empty() && sys.constraints.is_empty() {
        problems.push(format!(
            "--constraints chooses how closed loops are kept; `{}` has none",
            sys.name
        ));
    }
    problems.extend(lanes_problems(a, &opened.checked, integrator));
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    if let Err(code) = crate::output::create_out_dir(&a.out) {
        return code;
    }
    eprint!("{}", opened.checked.render_warnings());

    // One formulation, the swept parameters kept as symbols.
    let mut shared = opened.checked.clone();
    for p in &mut shared.system.parameters {
        if names.contains(&p.name) {
            p.tunable = true;
        }
    }
    let formulation = match eom_gen::generate::formulate_request(&shared, shared.request()) {
        Ok(f) => f,
        Err(e) => {
            eprint!("{e}");
            return ExitCode::from(1);
        }
    };
    let constrained = !formulation.constraint_names.is_empty();
    let mut outputs = Vec::new();
    for o in &a.output {
        match formulation.output_names.iter().position(|n| n == o) {
            Some(k) => outputs.push(k),
            None => problems.push(format!(
                "--output `{o}`: `{}` has no such output; its outputs: {}",
                sys.name,
                formulation.output_names.join(", ")
            )),
        }
    }
    if constrained && !a.output.is_empty() {
        problems.push(format!(
            "--output records outputs at the end time of models without constraints; `{}` has \
             constraints (its final state is in the table)",
            sys.name
        ));
    }
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    let loaded = match eom_gen::model::load_with(&model, urdf) {
        Ok(l) => l,
        Err(r) => {
            eprint!("{r}");
            return ExitCode::from(1);
        }
    };
    let ctx = Context {
        loaded: &loaded,
        shared: &shared,
        formulation: &formulation,
        inputs: &opened.inputs,
        names: &names,
        outputs: &outputs,
        options: &options,
    };
    let indices = study::shard(all.len(), shard);
    let study = Study {
        model: model.clone(),
        params: a.params.clone(),
        samples: a.samples,
        seed: a.seed.unwrap_or(0),
        run: options.clone(),
        outputs: a.output.clone(),
        cases: all.len(),
        rho_inf: None,
    };
    let bar = progress(indices.len(), &sys.name);
    let reformulated = AtomicUsize::new(0);
    let started = std::time::Instant::now();
    let rows = if a.compiled {
        let threads = a.jobs.unwrap_or_else(rayon::current_num_threads);
        ctx.lane_rows(
            &indices,
            &all,
            (
                a.lanes
                    .unwrap_or_else(|| crate::lanes::default_width(a.native)),
                a.native,
            ),
            threads,
            &bar,
            &reformulated,
        )
    } else {
        on_threads(a.jobs, || {
            indices
                .par_iter()
                .map(|&i| {
                    let row = ctx.case(i, &all[i], &reformulated);
                    bar.inc(1);
                    row
                })
                .collect()
        })
    };
    bar.finish_and_clear();
    let rows = match rows {
        Ok(rows) => rows,
        Err(e) => return fail(&e),
    };
    let done = Done {
        name: &sys.name,
        cases: all.len(),
        wall: started.elapsed().as_secs_f64(),
        reformulated: reformulated.load(Ordering::Relaxed),
    };
    finish(a, results(ctx.header(), &rows), &rows, &study, &done)
}

/// `work` on `jobs` threads, or on rayon's global pool (every core) when
/// not given.
pub(crate) fn on_threads<R: Send>(
    jobs: Option<usize>,
    work: impl FnOnce() -> R + Send,
) -> Result<R, Error> {
    match jobs {
        Some(n) => match rayon::ThreadPoolBuilder::new().num_threads(n).build() {
            Ok(pool) => Ok(pool.install(work)),
            Err(e) => Err(Error::Refused(format!("cannot start {n} threads: {e}"))),
        },
        None => Ok(work()),
    }
}

/// How a sweep's cases ran, for its summary line.
pub(crate) struct Done<'a> {
    /// The model's name.
    pub name: &'a str,
    /// Cases in the whole study (all shards).
    pub cases: usize,
    /// Wall time of the cases, s.
    pub wall: f64,
    /// Cases formulated on their own (a swept value changed what the
    /// check derives).
    pub reformulated: usize,
}

/// The end of every sweep: the table and `study.json` written to `--out`,
/// one summary line, the files written, and exit status 3 when a case
/// stopped early or failed.
pub(crate) fn finish(
    a: &SweepArgs,
    results: Results,
    rows: &[Row],
    study: &Study,
    done: &Done<'_>,
) -> ExitCode {
    let written = match results.write(std::path::Path::new(&a.out), study) {
        Ok(w) => w,
        Err(e) => return fail(&Error::io(&a.out, e)),
    };
    let failed = rows.iter().filter(|r| r.stop != "finished").count();
    let shard_text = match a.shard.as_deref().map(study::parse_shard) {
        Some(Ok((i, n))) => format!(" (shard {i}/{n} of {})", done.cases),
        _ => String::new(),
    };
    println!(
        "{}: {} cases{shard_text} in {:.2} s ({:.1} cases/s on {} threads), {} finished, {failed} stopped early or failed{}",
        done.name,
        rows.len(),
        done.wall,
        rows.len() as f64 / done.wall.max(1e-9),
        a.jobs.unwrap_or_else(rayon::current_num_threads),
        rows.len() - failed,
        match done.reformulated {
            0 => String::new(),
            n => format!(
                "; {n} formulated on their own (values the check derives from a swept parameter changed)"
            ),
        }
    );
    println!("results: {}", written.join(", "));
    if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(3)
    }
}

/// The results table of `rows` under `header`.
pub(crate) fn results(header: Vec<String>, rows: &[Row]) -> Results {
    let mut table = eom_sim::table::Table::new(header);
    let mut stop = Vec::new();
    for r in rows {
        table.push(r.values.clone());
        stop.push(r.stop.clone());
    }
    Results { table, stop }
}

/// One case's numbers and why it stopped (`finished`) or failed.
pub(crate) struct Row {
    /// The row of the results table, `NaN` where a failed case has no value.
    pub values: Vec<f64>,
    /// `finished`, or why the case stopped early or failed.
    pub stop: String,
}

/// What every case shares.
struct Context<'a> {
    loaded: &'a eom_gen::model::Loaded,
    shared: &'a eom_gen::Checked,
    formulation: &'a eom_gen::mech::Formulation,
    inputs: &'a [f64],
    names: &'a [String],
    outputs: &'a [usize],
    options: &'a RunOptions,
}

impl Context<'_> {
    fn header(&self) -> Vec<String> {
        let sys = &self.shared.system;
        let mut h: Vec<String> = vec!["case".into()];
        h.extend(self.names.iter().cloned());
        h.push("t".into());
        h.extend(sys.coordinate_names().iter().map(|n| n.to_string()));
        h.extend(sys.speed_names().iter().map(|n| n.to_string()));
        h.extend(["energy_start".into(), "energy_end".into()]);
        h.extend(
            self.outputs
                .iter()
                .map(|&k| self.formulation.output_names[k].clone()),
        );
        h.extend(
            ["steps", "rejected", "rhs_evals", "cpu_s"]
                .iter()
                .map(|s| s.to_string()),
        );
        h
    }

    /// Runs case `i` with `values`.
    fn case(&self, i: usize, values: &[f64], reformulated: &AtomicUsize) -> Row {
        let width = self.header().len();
        let mut v: Vec<f64> = std::iter::once(i as f64)
            .chain(values.iter().copied())
            .collect();
        let failed = |mut v: Vec<f64>, why: String| {
            v.resize(width, f64::NAN);
            Row {
                values: v,
                stop: why,
            }
        };
        let params: Vec<(String, f64)> = self
            .names
            .iter()
            .cloned()
            .zip(values.iter().copied())
            .collect();
        let checked = match self.loaded.check_with(std::path::Path::new(""), &params) {
            Ok(c) => c,
            Err(r) => {
                let why = r
                    .to_string()
                    .lines()
                    .find(|l| l.contains("error"))
                    .unwrap_or("the model is invalid with these values")
                    .trim()
                    .to_string();
                return failed(v, format!("failed: {why}"));
            }
        };
        // The shared formulation is exact for this case when nothing but
        // the swept parameters differs in what the check computed.
        let same = {
            let (a, b) = (&checked.system, &self.shared.system);
            a.q0() == b.q0()
                && a.u0() == b.u0()
                && a.parameters
                    .iter()
                    .zip(&b.parameters)
                    .all(|(x, y)| self.names.contains(&x.name) || x.value.value == y.value.value)
        };
        let own;
        let (f, sys) = if same {
            (self.formulation, &self.shared.system)
        } else {
            reformulated.fetch_add(1, Ordering::Relaxed);
            own = match eom_gen::generate::formulate_request(&checked, checked.request()) {
                Ok(f) => f,
                Err(e) => return failed(v, format!("failed: {}", e.to_string().trim())),
            };
            (&own, &checked.system)
        };
        let model = Interpreted::new(f, sys)
            .with_inputs(self.inputs)
            .with_params(&params);
        let r = match eom_gen::interpret::simulate_model(&model, self.options) {
            Ok(r) => r,
            Err(e) => return failed(v, format!("failed: {e}")),
        };
        v.push(r.t);
        v.extend(&r.q);
        v.extend(&r.u);
        v.extend(r.energy);
        if !self.outputs.is_empty() {
            let mut udot = vec![0.0; r.u.len()];
            model.forward_dynamics(r.t, &r.q, &r.u, &mut udot);
            let mut out = vec![f64::NAN; f.output_names.len()];
            let at = eom_sim::Point {
                t: r.t,
                q: &r.q,
                u: &r.u,
                udot: &udot,
                ..Default::default()
            };
            model.evaluate("outputs", &at, &mut out);
            v.extend(self.outputs.iter().map(|&k| out[k]));
        }
        v.extend([
            r.stats.steps as f64,
            r.stats.rejected as f64,
            r.stats.rhs_evals as f64,
            r.cpu_s,
        ]);
        let stop = match r.stop {
            Stop::Finished => "finished".to_string(),
            s => s.to_string(),
        };
        Row { values: v, stop }
    }
}

/// Why `--compiled` / `--lanes` do not apply, if they do not.
fn lanes_problems(
    a: &SweepArgs,
    checked: &eom_gen::Checked,
    integrator: Integrator,
) -> Vec<String> {
    let mut problems = Vec::new();
    if !a.compiled {
        if a.lanes.is_some() {
            problems.push("--lanes sets the states per call of --compiled; give --compiled".into());
        }
        if a.native {
            problems.push("--native sets how --compiled builds; give --compiled".into());
        }
        return problems;
    }
    if let Some(w) = a.lanes
        && !crate::lanes::WIDTHS.contains(&w)
    {
        problems.push(format!(
            "--lanes {w}: the compiled sweep is built for {:?} states per call",
            crate::lanes::WIDTHS
        ));
    }
    problems.extend(
        crate::lanes::refusal(checked)
            .map(|why| format!("--compiled: {why}; sweep it without --compiled (the evaluator)")),
    );
    problems.extend(crate::lanes::integrator_refusal(integrator));
    problems
}

impl Context<'_> {
    /// `--compiled`: the cases the shared formulation is exact for run in
    /// lanes, `width` per call, on `threads` threads (one build of the
    /// model with the swept parameters tunable, cached); the others (a
    /// value the check derives from a swept parameter changed, or one the
    /// model forbids) as without `--compiled`. The rows are those of the
    /// evaluator's sweep, `cpu_s` a lane's share of its pack's time.
    fn lane_rows(
        &self,
        indices: &[usize],
        all: &[Vec<f64>],
        (width, native): (usize, bool),
        threads: usize,
        bar: &indicatif::ProgressBar,
        reformulated: &AtomicUsize,
    ) -> Result<Vec<Row>, Error> {
        let sys = &self.shared.system;
        let mut rows: Vec<Option<Row>> = Vec::with_capacity(indices.len());
        let mut in_lanes = Vec::new();
        let y0: Vec<f64> = sys.q0().into_iter().chain(sys.u0()).collect();
        // The per-case check is most of a compiled case's cost: on every
        // core.
        let shares: Vec<bool> = indices
            .par_iter()
            .map(|&i| self.shares_formulation(&all[i]))
            .collect();
        for (k, (&i, shares)) in indices.iter().zip(shares).enumerate() {
            if shares {
                in_lanes.push((k, i));
                rows.push(None);
            } else {
                rows.push(Some(self.case(i, &all[i], reformulated)));
                bar.inc(1);
            }
        }
        if !in_lanes.is_empty() {
            let emit = eom_gen::EmitOptions {
                lanes: true,
                fma: native && crate::compiled::native_fma(),
                ..Default::default()
            };
            let source =
                eom_gen::emit::emit_with(sys, self.formulation, &self.shared.content(), &emit);
            let tunable: Vec<String> = sys
                .parameters
                .iter()
                .filter(|p| p.tunable)
                .map(|p| p.name.clone())
                .collect();
            let cases: Vec<crate::lanes::LaneCase> = in_lanes
                .iter()
                .map(|&(_, i)| crate::lanes::LaneCase {
                    p: all[i].clone(),
                    y0: y0.clone(),
                })
                .collect();
            let o = crate::lanes::LaneRun {
                integrator: self.options.integrator,
                rtol: self.options.rtol,
                atol: self.options.atol,
                dt: self.options.dt,
                t_end: self.options.t_end,
                max_steps: self.options.max_steps,
                width,
                threads,
                native,
            };
            let before = bar.position();
            let outcomes = crate::lanes::run(
                sys,
                &source,
                &tunable,
                self.names,
                self.inputs,
                &o,
                &cases,
                &mut |n| bar.set_position(before + n as u64),
            )?;
            for (&(k, i), r) in in_lanes.iter().zip(outcomes) {
                rows[k] = Some(self.lane_row(i, &all[i], &r));
            }
        }
        Ok(rows.into_iter().flatten().collect())
    }

    /// True if case `values` passes the model's check and the shared
    /// formulation is exact for it (what `case` tests).
    fn shares_formulation(&self, values: &[f64]) -> bool {
        let params: Vec<(String, f64)> = self
            .names
            .iter()
            .cloned()
            .zip(values.iter().copied())
            .collect();
        let Ok(checked) = self.loaded.check_with(std::path::Path::new(""), &params) else {
            return false;
        };
        let (a, b) = (&checked.system, &self.shared.system);
        a.q0() == b.q0()
            && a.u0() == b.u0()
            && a.parameters
                .iter()
                .zip(&b.parameters)
                .all(|(x, y)| self.names.contains(&x.name) || x.value.value == y.value.value)
    }

    /// The row of case `i` from its lane's outcome (the columns of `case`).
    fn lane_row(&self, i: usize, values: &[f64], r: &crate::lanes::LaneOutcome) -> Row {
        let nan = |x: Option<f64>| x.unwrap_or(f64::NAN);
        let nq = self.shared.system.nq();
        let y: Vec<f64> = r.y.iter().map(|x| nan(*x)).collect();
        let t = nan(r.t);
        let mut v: Vec<f64> = std::iter::once(i as f64)
            .chain(values.iter().copied())
            .collect();
        v.push(t);
        v.extend(&y);
        v.extend(r.energy.map(nan));
        if !self.outputs.is_empty() {
            let params: Vec<(String, f64)> = self
                .names
                .iter()
                .cloned()
                .zip(values.iter().copied())
                .collect();
            let model = Interpreted::new(self.formulation, &self.shared.system)
                .with_inputs(self.inputs)
                .with_params(&params);
            let (q, u) = y.split_at(nq);
            let mut udot = vec![0.0; u.len()];
            model.forward_dynamics(t, q, u, &mut udot);
            let mut out = vec![f64::NAN; self.formulation.output_names.len()];
            let at = eom_sim::Point {
                t,
                q,
                u,
                udot: &udot,
                ..Default::default()
            };
            model.evaluate("outputs", &at, &mut out);
            v.extend(self.outputs.iter().map(|&k| out[k]));
        }
        v.extend([
            r.steps as f64,
            r.rejected as f64,
            r.rhs_evals as f64,
            r.cpu_s,
        ]);
        let stop = match &r.stop {
            Stop::Finished => "finished".to_string(),
            s => s.to_string(),
        };
        Row { values: v, stop }
    }
}

/// A bar of cases with the time left, on a terminal.
pub(crate) fn progress(n: usize, name: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(n as u64);
    let style = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} cases, {elapsed} elapsed, {eta} left",
    )
    .map(|s| s.progress_chars("=> "))
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_prefix(name.to_string());
    bar
}

/// `--merge DIR… --out DIR`.
fn merge(a: &SweepArgs) -> ExitCode {
    let given: Vec<&str> = [
        ("MODEL", a.model.is_some()),
        ("--param", !a.params.is_empty()),
        ("--samples", a.samples.is_some()),
        ("--seed", a.seed.is_some()),
        ("--t-end", a.t_end.is_some()),
        ("--shard", a.shard.is_some()),
        ("--output", !a.output.is_empty()),
        ("--integrator", a.integrator.is_some()),
        ("--jobs", a.jobs.is_some()),
        ("--rho-inf", a.rho_inf.is_some()),
        ("--compiled", a.compiled),
        ("--lanes", a.lanes.is_some()),
        ("--native", a.native),
    ]
    .iter()
    .filter(|(_, g)| *g)
    .map(|(n, _)| *n)
    .collect();
    if !given.is_empty() {
        return fail(&Error::Usage(vec![format!(
            "--merge joins finished shards (their study.json says how they ran): {} do(es) not apply; \
             give --merge DIR… --out DIR",
            given.join(", ")
        )]));
    }
    let (study, results) = match study::merge(&a.merge) {
        Ok(m) => m,
        Err(e) => return fail(&Error::Format(e)),
    };
    if let Err(code) = crate::output::create_out_dir(&a.out) {
        return code;
    }
    match results.write(std::path::Path::new(&a.out), &study) {
        Ok(w) => {
            println!(
                "merged {} shard(s): {} cases; results: {}",
                a.merge.len(),
                results.stop.len(),
                w.join(", ")
            );
            ExitCode::SUCCESS
        }
        Err(e) => fail(&Error::io(&a.out, e)),
    }
}
