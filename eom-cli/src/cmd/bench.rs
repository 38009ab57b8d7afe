//! `eom-gen bench`: per-call cost of the compiled functions
//! (`crate::bench`), work-precision sweeps of one model or of every
//! bundled one (`crate::sweep`), and plots of their CSV files.

use crate::args::{
    InitialArgs, InputArgs, ParamArgs, Vary, numbers, parse_assignments, parse_names,
};
use crate::error::Error;
use crate::output::{create_out_dir, fail, write_file};
use crate::sweep as wp;
use clap::Args;
use std::process::ExitCode;

/// Measure the compiled model: `--per-call` gives ns per call of
/// forward dynamics, mass matrix and inverse dynamics over random states;
/// `--work-precision` gives error against CPU time per integrator (and
/// constraint solver) over a sweep of tolerances or step sizes;
/// `--suite` runs the work-precision sweep on every bundled model.
#[derive(Args)]
pub struct BenchArgs {
    /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`); not with `--suite`.
    pub model: Option<String>,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub inputs: InputArgs,
    // `--q0`/`--u0`: the start of the work-precision runs (regenerates).
    #[command(flatten)]
    pub initial: InitialArgs,
    /// Per-call cost of the generated functions.
    #[arg(long)]
    pub per_call: bool,
    /// Work-precision: error against CPU time over a sweep.
    #[arg(long)]
    pub work_precision: bool,
    /// Work-precision of every model in `--models`, written to `--out`.
    #[arg(long)]
    pub suite: bool,
    /// Random states per repetition (`--per-call`; default 1024).
    #[arg(long)]
    pub states: Option<usize>,
    /// Timed repetitions; the median is reported (`--per-call`; default 31).
    #[arg(long)]
    pub reps: Option<usize>,
    /// Seed of the random states (`--per-call`; default 1).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Build the timing program with `-C target-cpu=native` (`--per-call`);
    /// the generated code then fuses `a·b + c` into `mul_add` where the
    /// machine has FMA.
    #[arg(long)]
    pub native: bool,
    /// With --native: keep `a·b + c` unfused (to measure what FMA gives).
    #[arg(long)]
    pub no_fma: bool,
    /// Also generate and time `forward_dynamics_derivatives` (`--per-call`;
    /// reported as `forward_dynamics_derivatives_ns`).
    #[arg(long)]
    pub derivatives: bool,
    /// Also time the batched forward dynamics, `W` states per call in SIMD
    /// lanes for W = 2, 4, 8, 16 (`--per-call`; reported as
    /// `batched_forward_dynamics_ns`, ns per state at the fastest width);
    /// with `--derivatives` the batched derivatives too, W = 4, 8
    /// (`batched_forward_dynamics_derivatives_ns`).
    #[arg(long)]
    pub batch: bool,
    /// Integrators to sweep, comma-separated (default rk4,dopri5,dop853,radau5).
    #[arg(long, value_delimiter = ',')]
    pub integrators: Vec<String>,
    /// Constraint methods to sweep for models with constraints
    /// (default projection,partitioning,baumgarte,index3).
    #[arg(long, value_delimiter = ',')]
    pub constraints: Vec<String>,
    /// End time, s (`--work-precision`; default 10).
    #[arg(long, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Tolerances rtol = atol of the adaptive methods, comma-separated
    /// (default 1e-4,1e-5,…,1e-12).
    #[arg(long, value_delimiter = ',')]
    pub tols: Vec<f64>,
    /// Fixed-step methods: step t_end/N for N doubling from the first to the second number.
    #[arg(long, value_delimiter = ',', num_args = 1)]
    pub steps: Vec<usize>,
    /// Tolerance of the reference run (DOP853) and its check (DOPRI5).
    #[arg(long, default_value_t = 1e-13)]
    pub ref_tol: f64,
    /// Dense-output samples along the path for the path error.
    #[arg(long, default_value_t = 200)]
    pub samples: usize,
    /// Repeat each timed run until this much CPU time per point, s (at least 3 runs).
    #[arg(long, default_value_t = 0.2)]
    pub min_time: f64,
    /// Write the points as CSV to this file (`--work-precision`).
    #[arg(long)]
    pub csv: Option<String>,
    /// Write the log-log work-precision diagram as SVG to this file (`--work-precision`).
    #[arg(long)]
    pub svg: Option<String>,
    /// The models of `--suite`.
    #[arg(long, default_value = "models")]
    pub models: String,
    /// Where `--suite` writes `MODEL.csv`, `MODEL.svg` and `suite.md`.
    #[arg(long, default_value = "bench/results")]
    pub out: String,
    /// Plot work-precision CSV files (comma-separated; the format
    /// `--csv` writes) to `--svg`, one diagram per model.
    #[arg(long, value_delimiter = ',')]
    pub plot: Vec<String>,
    /// The error axis label of `--plot`.
    #[arg(long)]
    pub error_label: Option<String>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: BenchArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    if !a.plot.is_empty() {
        if a.model.is_some() || a.per_call || a.work_precision || a.suite {
            eprintln!(
                "error: --plot draws CSV files; give no MODEL, --per-call, --work-precision or --suite"
            );
            return ExitCode::from(2);
        }
        let Some(svg) = a.svg else {
            eprintln!("error: --plot needs --svg FILE");
            return ExitCode::from(2);
        };
        return plot(&a.plot, &svg, a.error_label.as_deref());
    }
    let mut o = wp::WpOptions {
        ref_tol: a.ref_tol,
        samples: a.samples,
        min_total_s: a.min_time,
        ..Default::default()
    };
    let mut problems = Vec::new();
    if !a.integrators.is_empty() {
        o.integrators = parse_names(&a.integrators, &mut problems);
    }
    if !a.constraints.is_empty() {
        o.constraints = parse_names(&a.constraints, &mut problems);
    }
    if let Some(t) = a.t_end {
        o.t_end = t;
    }
    if !a.tols.is_empty() {
        o.tols = a.tols.clone();
    }
    match a.steps.as_slice() {
        [] => {}
        [n0, n1] => o.fixed_steps = (*n0, *n1),
        _ => {
            eprintln!("error: --steps takes two numbers, N0,N1");
            return ExitCode::from(2);
        }
    }
    if (a.work_precision || a.suite)
        && let Err(e) = wp::validate(&o)
    {
        problems.extend(e);
    }
    let params = match parse_assignments("param", &a.params.params) {
        Ok(p) => p,
        Err(e) => {
            problems.extend(e);
            Vec::new()
        }
    };
    // Every input is driven (a value is a constant torque): the
    // timing and sweep programs run the model as generated.
    let mut drives = Vec::new();
    for item in &a.inputs.inputs {
        match item.split_once('=') {
            Some((n, v)) if !n.trim().is_empty() && !v.trim().is_empty() => {
                drives.push((n.trim().to_string(), v.trim().to_string()));
            }
            _ => problems.push(format!(
                "--input `{item}`: expected NAME=VALUE or NAME=EXPR, e.g. `--input motor=\"2*sin(3*t)\"`"
            )),
        }
    }
    let mut initial = |what: &str, text: Option<String>| match text.map(|t| numbers(what, &t)) {
        Some(Ok(v)) => Some(v),
        Some(Err(e)) => {
            problems.push(e);
            None
        }
        None => None,
    };
    let (q0, u0) = (
        initial("q0", a.initial.q0.clone()),
        initial("u0", a.initial.u0.clone()),
    );
    if (q0.is_some() || u0.is_some()) && !a.work_precision {
        problems.push(
            "--q0 and --u0 set the start of the --work-precision runs; --per-call times random states".into(),
        );
    }
    if a.per_call && !a.work_precision && !a.suite {
        // The sweep's options measure nothing per call.
        for (option, given) in [
            ("--integrators", !a.integrators.is_empty()),
            ("--constraints", !a.constraints.is_empty()),
            ("--t-end", a.t_end.is_some()),
            ("--tols", !a.tols.is_empty()),
            ("--steps", !a.steps.is_empty()),
            ("--csv", a.csv.is_some()),
            ("--svg", a.svg.is_some()),
        ] {
            if given {
                problems.push(format!(
                    "{option} sets the --work-precision sweep; --per-call times the generated \
                     functions at random states (its options: --states, --reps, --seed, --native, --derivatives, --batch, --json)"
                ));
            }
        }
    }
    if a.derivatives && !a.per_call {
        problems.push(
            "--derivatives times the derivatives with --per-call; not with --work-precision or --suite"
                .into(),
        );
    }
    if a.batch && !a.per_call {
        problems.push(
            "--batch times the batched forward dynamics with --per-call; not with --work-precision or --suite"
                .into(),
        );
    }
    if a.batch && a.states.is_some_and(|n| n < 16) {
        problems
            .push("--batch packs the states up to 16 per call: give --states 16 or more".into());
    }
    if a.no_fma && !a.native {
        eprintln!("error: --no-fma goes with --native (without it the code has no mul_add)");
        return ExitCode::from(2);
    }
    if a.native && !a.per_call {
        problems.push(
            "--native builds the --per-call timing program; not with --work-precision or --suite"
                .into(),
        );
    }
    if a.work_precision || a.suite {
        for (option, given) in [
            ("--states", a.states.is_some()),
            ("--reps", a.reps.is_some()),
            ("--seed", a.seed.is_some()),
        ] {
            if given {
                problems.push(format!(
                    "{option} sets the --per-call timing at random states; the --work-precision \
                     sweep runs from the model's start (its options: --integrators, --constraints, \
                     --t-end, --tols, --steps, --q0, --u0, --csv, --svg)"
                ));
            }
        }
    }
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    if a.suite && !(params.is_empty() && drives.is_empty()) {
        eprintln!("error: --param and --input set values of one model; not with --suite");
        return ExitCode::from(2);
    }
    let vary = Vary {
        params,
        drives,
        q0,
        u0,
        ..Vary::default()
    };
    if a.suite {
        if a.model.is_some() || a.per_call || a.work_precision {
            eprintln!(
                "error: --suite runs every model in --models; give no MODEL, --per-call or --work-precision"
            );
            return ExitCode::from(2);
        }
        return suite(&a.models, &a.out, &o, a.t_end.is_some(), urdf);
    }
    let Some(model) = a.model.clone() else {
        eprintln!(
            "error: which model? `eom-gen bench MODEL --per-call|--work-precision`, or `eom-gen bench --suite`"
        );
        return ExitCode::from(2);
    };
    if a.work_precision {
        if a.per_call {
            eprintln!("error: choose one of --per-call and --work-precision");
            return ExitCode::from(2);
        }
        return work_precision(&model, urdf, &vary, &o, &a);
    }
    let o = crate::bench::PerCallOptions {
        states: a.states.unwrap_or(1024),
        reps: a.reps.unwrap_or(31),
        seed: a.seed.unwrap_or(1),
        native: a.native,
        fma: a.native && !a.no_fma && crate::compiled::native_fma(),
        derivatives: a.derivatives,
        batch: a.batch,
    };
    per_call(&model, urdf, &vary, a.per_call, &o, a.json)
}

/// The model generated with `vary`, every problem printed.
fn generated(
    path: &str,
    urdf: &eom_gen::urdf::Options,
    vary: &Vary,
) -> Result<eom_gen::Generated, ExitCode> {
    let opened = crate::open::open(path, urdf, vary)?;
    crate::open::generate(&opened, vary, &Default::default())
}

fn per_call(
    path: &str,
    urdf: &eom_gen::urdf::Options,
    vary: &Vary,
    per_call: bool,
    o: &crate::bench::PerCallOptions,
    json: bool,
) -> ExitCode {
    if !per_call {
        eprintln!("error: say what to measure: --per-call, --work-precision or --suite");
        return ExitCode::from(2);
    }
    if o.states == 0 || o.reps == 0 {
        eprintln!("error: --states and --reps must be at least 1");
        return ExitCode::from(2);
    }
    let opened = match crate::open::open(path, urdf, vary) {
        Ok(o) => o,
        Err(code) => return code,
    };
    if let Some(code) = crate::open::cables_only_refusal(&opened.checked, "bench --per-call") {
        return code;
    }
    let also = if o.derivatives {
        eom_gen::functions::FunctionSet::default()
            .with(eom_gen::functions::Function::ForwardDynamicsDerivatives)
    } else {
        eom_gen::functions::FunctionSet::default()
    };
    let emit = eom_gen::EmitOptions {
        lanes: o.batch,
        fma: o.fma,
        ..Default::default()
    };
    let g = match crate::open::generate_asking(&opened, vary, &emit, also) {
        Ok(g) => g,
        Err(code) => return code,
    };
    eprint!("{}", g.checked.render_warnings());
    if let Some(note) = crate::ancf::scope_note(&g.checked, "bench --per-call") {
        eprintln!(
            "{note}; the kernels' ns per element: `cargo run --release -p eom-sim --example ancf_bench -- kernels`"
        );
    }
    match crate::bench::per_call(&g, o) {
        Ok(r) if json => {
            println!("{}", crate::bench::json(&g, o, &r));
            ExitCode::SUCCESS
        }
        Ok(r) => {
            print!("{}", crate::bench::table(&g, o, &r));
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

/// A progress bar over the points of one sweep (hidden when stderr is not
/// a terminal).
fn progress(label: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(0);
    let style = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} points, {elapsed} {msg}",
    )
    .map(|s| s.progress_chars("=> "))
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_prefix(label.to_string());
    bar
}

fn sweep(
    g: &eom_gen::Generated,
    o: &wp::WpOptions,
    bar: &indicatif::ProgressBar,
) -> Result<wp::WorkPrecision, Error> {
    wp::run(g, o, &mut |done, total, p| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        if let Some(p) = p {
            bar.set_message(format!(
                "{} {:.0e}: {}",
                p.integrator,
                p.setting,
                p.digits
                    .map_or_else(|| p.stop.clone(), |d| format!("{d:.1} digits"))
            ));
        }
    })
}

fn work_precision(
    path: &str,
    urdf: &eom_gen::urdf::Options,
    vary: &Vary,
    o: &wp::WpOptions,
    a: &BenchArgs,
) -> ExitCode {
    let (csv, svg, json) = (a.csv.as_deref(), a.svg.as_deref(), a.json);
    let constraints_given = !a.constraints.is_empty();
    if let Err(errors) = wp::validate(o) {
        for e in errors {
            eprintln!("error: {e}");
        }
        return ExitCode::from(2);
    }
    let opened = match crate::open::open(path, urdf, vary) {
        Ok(o) => o,
        Err(code) => return code,
    };
    let sys = &opened.checked.system;
    if !sys.cables.is_empty() {
        eprintln!(
            "error: `{}` has cables: --work-precision sweeps the integrators of rigid models; \
             a model with cables runs generalized-α with a fixed step (compare `simulate --dt` runs)",
            sys.name
        );
        return ExitCode::from(2);
    }
    if constraints_given && sys.graph.cut_joints().is_empty() && sys.constraints.is_empty() {
        eprintln!(
            "error: --constraints chooses the constraint methods to sweep; `{}` has no loops or constraints",
            sys.name
        );
        return ExitCode::from(2);
    }
    let g = match crate::open::generate(&opened, vary, &Default::default()) {
        Ok(g) => g,
        Err(code) => return code,
    };
    eprint!("{}", g.checked.render_warnings());
    let bar = progress(&g.checked.system.name);
    let result = sweep(&g, o, &bar);
    bar.finish_and_clear();
    let w = match result {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(1);
        }
    };
    if let Some(f) = csv
        && let Err(code) = write_file(f, &wp::csv(&w))
    {
        return code;
    }
    if let Some(f) = svg {
        match wp::svg(&w) {
            Ok(text) => {
                if let Err(code) = write_file(f, &text) {
                    return code;
                }
            }
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(1);
            }
        }
    }
    if json {
        println!("{}", wp::json(&w));
    } else {
        print!("{}", wp::table(&w));
    }
    ExitCode::SUCCESS
}

/// Every model in `dir` (`*.ron`, sorted), swept with its suite settings;
/// `MODEL.csv`, `MODEL.svg` and a summary `suite.md` in `out`.
fn suite(
    dir: &str,
    out: &str,
    o: &wp::WpOptions,
    t_end_given: bool,
    urdf: &eom_gen::urdf::Options,
) -> ExitCode {
    let mut models: Vec<std::path::PathBuf> = match std::fs::read_dir(dir) {
        Ok(entries) => entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "ron"))
            .collect(),
        Err(e) => {
            eprintln!("error: cannot read `{dir}`: {e}");
            return ExitCode::from(2);
        }
    };
    models.sort();
    if let Err(code) = create_out_dir(out) {
        return code;
    }
    let bars = indicatif::MultiProgress::new();
    let overall = bars.add(indicatif::ProgressBar::new(models.len() as u64));
    if let Ok(s) = indicatif::ProgressStyle::with_template(
        "suite [{bar:30}] {pos}/{len} models, {elapsed} {msg}",
    ) {
        overall.set_style(s.progress_chars("=> "));
    }
    let mut summary =
        format!("# Work-precision suite\n\n`eom-gen bench --suite --models {dir} --out {out}`\n\n");
    let mut failed = Vec::new();
    let mut rows = String::new();
    let mut sections = String::new();
    for path in &models {
        let p = path.display().to_string();
        let g = match bars.suspend(|| generated(&p, urdf, &Vary::default())) {
            Ok(g) => g,
            Err(_) => {
                failed.push(p);
                overall.inc(1);
                continue;
            }
        };
        let name = g.checked.system.name.clone();
        overall.set_message(name.clone());
        let mut opts = wp::suite_options(&name, o);
        if t_end_given {
            opts.t_end = o.t_end;
        }
        let bar = bars.add(progress(&name));
        let result = sweep(&g, &opts, &bar);
        bar.finish_and_clear();
        overall.inc(1);
        let w = match result {
            Ok(w) => w,
            Err(e) => {
                bars.suspend(|| eprintln!("error: {name}: {e}"));
                failed.push(p);
                continue;
            }
        };
        let base = std::path::Path::new(out).join(&name);
        let svg = match wp::svg(&w) {
            Ok(s) => s,
            Err(e) => {
                bars.suspend(|| eprintln!("error: {e}"));
                failed.push(p);
                continue;
            }
        };
        for (ext, text) in [("csv", wp::csv(&w)), ("svg", svg)] {
            if write_file(&format!("{}.{ext}", base.display()), &text).is_err() {
                return ExitCode::from(1);
            }
        }
        bars.suspend(|| {
            eprintln!(
                "{name}: {} points → {}.{{csv,svg}}",
                w.points.len(),
                base.display()
            )
        });
        rows += &wp::summary_rows(&w);
        sections += &format!("## {name}\n\n![{name}]({name}.svg)\n\n{}\n", wp::table(&w));
    }
    overall.finish_and_clear();
    summary += "CPU time of one run (median) of the cheapest setting whose end error is at most 1e-6 and 1e-9, and the most significant digits reached, per method:\n\n";
    summary += "| model | t_end | method | ≤ 1e-6: CPU ms | ≤ 1e-9: CPU ms | best digits |\n|---|---|---|---|---|---|\n";
    summary += &rows;
    summary += "\n";
    summary += &sections;
    if write_file(&format!("{out}/suite.md"), &summary).is_err() {
        return ExitCode::from(1);
    }
    if failed.is_empty() {
        println!("suite: {} models → {out}/suite.md", models.len());
        ExitCode::SUCCESS
    } else {
        eprintln!(
            "error: {} model(s) failed: {}",
            failed.len(),
            failed.join(", ")
        );
        ExitCode::from(1)
    }
}

/// Plots work-precision CSV files: one SVG per model (`FILE.svg`, or
/// `FILE-MODEL.svg` when the files hold several models).
fn plot(files: &[String], svg: &str, error_label: Option<&str>) -> ExitCode {
    let mut all: Vec<wp::WorkPrecision> = Vec::new();
    let mut errors = Vec::new();
    for f in files {
        match std::fs::read_to_string(f)
            .map_err(|e| Error::io(f, e))
            .and_then(|text| wp::from_csv(&text, f))
        {
            Ok(models) => {
                for m in models {
                    match all.iter_mut().find(|w| w.model == m.model) {
                        Some(w) => {
                            w.constrained |= m.constrained;
                            w.points.extend(m.points);
                        }
                        None => all.push(m),
                    }
                }
            }
            Err(e) => errors.push(e),
        }
    }
    if !errors.is_empty() {
        for e in errors {
            eprintln!("error: {e}");
        }
        return ExitCode::from(1);
    }
    let path = std::path::Path::new(svg);
    let stem = path.with_extension("");
    for w in &mut all {
        if let Some(label) = error_label {
            w.error_label = label.to_string();
        }
    }
    let several = all.len() > 1;
    for w in &all {
        let file = if several {
            format!("{}-{}.svg", stem.display(), w.model)
        } else {
            svg.to_string()
        };
        let text = match wp::svg(w) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(1);
            }
        };
        if let Err(code) = write_file(&file, &text) {
            return code;
        }
        eprintln!("{}: {} points → {file}", w.model, w.points.len());
    }
    ExitCode::SUCCESS
}
