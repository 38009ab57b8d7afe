//! The `eom-gen` command-line tool: the application on top of the
//! generator library (`eom_gen`) and the runtime (`eom_sim`).

mod ancf;
mod bench;
mod cable_report;
mod compiled;
mod error;
mod mixed_static;
mod plot;
mod summary;
mod sweep;

use clap::{Parser, Subcommand};
use eom_gen::functions::{Function, Layout, TABLE};
use eom_gen::model::{Report, Severity};
use eom_sim::{Integrator, Method, RunOptions, RunReport};
use error::Error;
use std::process::ExitCode;

/// Symbolic equation-of-motion generator for multibody systems.
#[derive(Parser)]
#[command(name = "eom-gen", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// URDF import: inconsistent inertias of moving links are errors, not
    /// warnings (see docs/model-format.md, "Inertia policy").
    #[arg(long, global = true)]
    strict_inertia: bool,
    /// URDF import: fix inconsistent inertias of moving links (negative
    /// principal moments to zero, then the triangle inequality), each fix
    /// listed in the notes (like MuJoCo's `balanceinertia`).
    #[arg(long, global = true)]
    balance_inertia: bool,
}

/// How this run imports URDF files (`--strict-inertia`, `--balance-inertia`).
static URDF_OPTIONS: std::sync::OnceLock<eom_gen::urdf::Options> = std::sync::OnceLock::new();

/// Loads and checks a model file of any format with this run's URDF
/// options and parameter values.
fn load_checked(path: &str, values: &[(String, f64)]) -> Result<eom_gen::Checked, eom_gen::Report> {
    let options = URDF_OPTIONS.get().copied().unwrap_or_default();
    eom_gen::model::load_with(path, &options)?.check_with(std::path::Path::new(""), values)
}

#[derive(Subcommand)]
enum Command {
    /// Validate a model and print a summary (bodies, joints, coordinates,
    /// cut joints, Grübler count). Exit 0 if valid, 1 if not.
    Check {
        /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
        model: String,
        /// Print one JSON object instead of the summary.
        #[arg(long)]
        json: bool,
    },
    /// Print the generated Rust source of a model.
    Dump {
        /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
        model: String,
        /// Write to this file instead of standard output.
        #[arg(short, long)]
        output: Option<String>,
        /// Emit `f64::mul_add` for `a·b + c` (compile with FMA enabled).
        #[arg(long)]
        fma: bool,
    },
    /// Evaluate the equations of motion at a state (default: the model's
    /// initial state), compiled (built once, cached) or interpreted.
    Eval {
        /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
        model: String,
        /// Positions, comma-separated (default: the model's q0).
        #[arg(long, allow_hyphen_values = true)]
        q: Option<String>,
        /// Speeds, comma-separated (default: the model's u0).
        #[arg(long, allow_hyphen_values = true)]
        u: Option<String>,
        /// Extra generalised forces, one per speed (default: zero).
        #[arg(long, allow_hyphen_values = true)]
        tau: Option<String>,
        /// Time.
        #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
        t: f64,
        /// Set a parameter of the model: `NAME=VALUE` (repeatable); the
        /// code is regenerated with the value.
        #[arg(long = "param", value_name = "NAME=VALUE", allow_hyphen_values = true)]
        params: Vec<String>,
        /// Hold a runtime input of the model at a value, `NAME=VALUE`, or
        /// drive it by an expression of parameters, `t`, coordinates and
        /// speeds, `NAME=EXPR` (regenerates; repeatable; default zero).
        #[arg(
            long = "input",
            value_name = "NAME=VALUE|EXPR",
            allow_hyphen_values = true
        )]
        inputs: Vec<String>,
        /// Use the evaluator instead of compiled code (no compiler needed).
        #[arg(long)]
        interpret: bool,
        /// Print one JSON object (the only format).
        #[arg(long)]
        json: bool,
    },
    /// Integrate the compiled model from its initial state.
    Simulate {
        /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
        model: String,
        /// End time, s.
        #[arg(long)]
        t_end: f64,
        /// rk4, dopri5, dop853, radau5, midpoint or euler.
        #[arg(long, default_value = "dopri5")]
        integrator: String,
        /// Relative tolerance (adaptive methods).
        #[arg(long, default_value_t = 1e-8, allow_hyphen_values = true)]
        rtol: f64,
        /// Absolute tolerance (adaptive methods).
        #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
        atol: f64,
        /// Step size (fixed-step methods).
        #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
        dt: f64,
        /// Most attempted steps; a run that needs more stops (exit 3).
        #[arg(long, default_value_t = 100_000)]
        max_steps: usize,
        /// Initial positions, comma-separated (default: the model's q0).
        #[arg(long, allow_hyphen_values = true)]
        q0: Option<String>,
        /// Initial speeds, comma-separated (default: the model's u0).
        #[arg(long, allow_hyphen_values = true)]
        u0: Option<String>,
        /// Set a parameter of the model: `NAME=VALUE` (repeatable); the
        /// code is regenerated with the value.
        #[arg(long = "param", value_name = "NAME=VALUE", allow_hyphen_values = true)]
        params: Vec<String>,
        /// Hold a runtime input of the model at a value, `NAME=VALUE`, or
        /// drive it by an expression of parameters, `t`, coordinates and
        /// speeds, `NAME=EXPR` (regenerates; repeatable; default zero).
        #[arg(
            long = "input",
            value_name = "NAME=VALUE|EXPR",
            allow_hyphen_values = true
        )]
        inputs: Vec<String>,
        /// Write the trajectory (t, q, u) to this CSV file.
        #[arg(long)]
        csv: Option<String>,
        /// Output interval of the CSV, using dense output (default: every step).
        #[arg(long, allow_hyphen_values = true)]
        every: Option<f64>,
        /// Run the programs in the evaluator instead of compiled code.
        #[arg(long)]
        interpret: bool,
        /// Closed loops and constraints: `projection` (of positions and
        /// speeds after each step), `baumgarte` (multipliers with Baumgarte
        /// stabilisation, α = β = 10/s), `partitioning` (dependent
        /// coordinates from independent ones, Wehage–Haug), `index3` (the
        /// index-3 DAE, with radau5) or `augmented-lagrangian` (Bayo and
        /// Ledesma; well-posed through singular and redundant constraints).
        #[arg(long, default_value = "projection")]
        constraints: String,
        /// Print one JSON object instead of the summary.
        #[arg(long)]
        json: bool,
        /// Spectral radius at infinity of generalized-α (models with
        /// cables; 1 = no numerical damping).
        #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
        rho_inf: f64,
    },
    /// Convert a URDF robot description into an eom model (RON).
    Import {
        /// The URDF file.
        urdf: String,
        /// Write the model to this file instead of standard output.
        #[arg(short, long)]
        output: Option<String>,
    },
    /// Measure the compiled model: `--per-call` gives ns per call of
    /// forward dynamics, mass matrix and inverse dynamics over random states;
    /// `--work-precision` gives error against CPU time per integrator (and
    /// constraint solver) over a sweep of tolerances or step sizes;
    /// `--suite` runs the work-precision sweep on every bundled model.
    Bench {
        /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`); not with `--suite`.
        model: Option<String>,
        /// Set a parameter of the model: `NAME=VALUE` (repeatable); the
        /// code is regenerated with the value.
        #[arg(long = "param", value_name = "NAME=VALUE", allow_hyphen_values = true)]
        params: Vec<String>,
        /// Drive an input of the model by a value or an expression of
        /// parameters, `t`, coordinates and speeds: `NAME=VALUE|EXPR`
        /// (repeatable; the code is regenerated with it).
        #[arg(
            long = "input",
            value_name = "NAME=VALUE|EXPR",
            allow_hyphen_values = true
        )]
        inputs: Vec<String>,
        /// Initial positions of the work-precision runs, comma-separated
        /// (default: the model's q0; the code is regenerated with them).
        #[arg(long, allow_hyphen_values = true)]
        q0: Option<String>,
        /// Initial speeds of the work-precision runs, comma-separated.
        #[arg(long, allow_hyphen_values = true)]
        u0: Option<String>,
        /// Per-call cost of the generated functions.
        #[arg(long)]
        per_call: bool,
        /// Work-precision: error against CPU time over a sweep.
        #[arg(long)]
        work_precision: bool,
        /// Work-precision of every model in `--models`, written to `--out`.
        #[arg(long)]
        suite: bool,
        /// Random states per repetition (`--per-call`).
        #[arg(long, default_value_t = 1024)]
        states: usize,
        /// Timed repetitions; the median is reported (`--per-call`).
        #[arg(long, default_value_t = 31)]
        reps: usize,
        /// Seed of the random states (`--per-call`).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Build the timing program with `-C target-cpu=native` (`--per-call`).
        #[arg(long)]
        native: bool,
        /// Integrators to sweep, comma-separated (default rk4,dopri5,dop853,radau5).
        #[arg(long, value_delimiter = ',')]
        integrators: Vec<String>,
        /// Constraint methods to sweep for models with constraints
        /// (default projection,partitioning,baumgarte,index3).
        #[arg(long, value_delimiter = ',')]
        constraints: Vec<String>,
        /// End time, s (`--work-precision`; default 10).
        #[arg(long, allow_hyphen_values = true)]
        t_end: Option<f64>,
        /// Tolerances rtol = atol of the adaptive methods, comma-separated
        /// (default 1e-4,1e-5,…,1e-12).
        #[arg(long, value_delimiter = ',')]
        tols: Vec<f64>,
        /// Fixed-step methods: step t_end/N for N doubling from the first to the second number.
        #[arg(long, value_delimiter = ',', num_args = 1)]
        steps: Vec<usize>,
        /// Tolerance of the reference run (DOP853) and its check (DOPRI5).
        #[arg(long, default_value_t = 1e-13)]
        ref_tol: f64,
        /// Dense-output samples along the path for the path error.
        #[arg(long, default_value_t = 200)]
        samples: usize,
        /// Repeat each timed run until this much CPU time per point, s (at least 3 runs).
        #[arg(long, default_value_t = 0.2)]
        min_time: f64,
        /// Write the points as CSV to this file (`--work-precision`).
        #[arg(long)]
        csv: Option<String>,
        /// Write the log-log work-precision diagram as SVG to this file (`--work-precision`).
        #[arg(long)]
        svg: Option<String>,
        /// The models of `--suite`.
        #[arg(long, default_value = "models")]
        models: String,
        /// Where `--suite` writes `MODEL.csv`, `MODEL.svg` and `suite.md`.
        #[arg(long, default_value = "bench/results")]
        out: String,
        /// Plot work-precision CSV files (comma-separated; the format
        /// `--csv` writes) to `--svg`, one diagram per model.
        #[arg(long, value_delimiter = ',')]
        plot: Vec<String>,
        /// The error axis label of `--plot`.
        #[arg(long)]
        error_label: Option<String>,
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
    },
    /// Static equilibrium of a model's cables (ANCF chains): Newton with
    /// load stepping, the residual of every iteration reported. A model
    /// whose cable hangs at markers of rigid bodies is solved as one
    /// (rigid coordinates, attachment forces, stability reported). Exit 0
    /// in equilibrium; 1 if the model is invalid or the solve refuses (no
    /// convergence at the smallest load step, a singular tangent, a
    /// mechanism); 2 for bad arguments.
    SolveStatic {
        /// The model file (`.ron`) with `cables:`.
        model: String,
        /// Equal load steps to begin with (halved where Newton fails).
        #[arg(long, default_value_t = 10)]
        load_steps: usize,
        /// Newton iterations allowed per load step.
        #[arg(long, default_value_t = 25)]
        max_iterations: usize,
        /// Relative residual tolerance: `|r|∞ ≤ rtol · |λ f_ext|∞ + atol`.
        #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
        rtol: f64,
        /// Absolute residual tolerance, N.
        #[arg(long, default_value_t = 1e-12, allow_hyphen_values = true)]
        atol: f64,
        /// Set a parameter of the model: `NAME=VALUE` (repeatable).
        #[arg(long = "param", value_name = "NAME=VALUE", allow_hyphen_values = true)]
        params: Vec<String>,
        /// Print one JSON object (with every node's position).
        #[arg(long)]
        json: bool,
    },
    /// Operation counts of the generated functions and generation time.
    Stats {
        /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
        model: String,
        /// Print one JSON object instead of the table.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let _ = URDF_OPTIONS.set(eom_gen::urdf::Options {
        balance_inertia: cli.balance_inertia,
        strict: cli.strict_inertia,
    });
    match cli.command {
        Command::Check { model, json } => check(&model, json),
        Command::Import { urdf, output } => import(&urdf, output.as_deref()),
        Command::Dump { model, output, fma } => dump(&model, output.as_deref(), fma),
        Command::Stats { model, json } => stats(&model, json),
        Command::SolveStatic {
            model,
            load_steps,
            max_iterations,
            rtol,
            atol,
            params,
            json,
        } => {
            let vary = match Vary::parse(&params, &[]) {
                Ok(v) => v,
                Err(code) => return code,
            };
            let mut problems = Vec::new();
            if load_steps == 0 {
                problems.push("--load-steps must be at least 1".to_string());
            }
            if !(rtol >= 0.0 && atol >= 0.0) {
                problems.push("--rtol and --atol must not be negative".to_string());
            }
            if !problems.is_empty() {
                return fail(&Error::Usage(problems));
            }
            let checked = match load_checked(&model, &vary.params) {
                Ok(c) => c,
                Err(report) => {
                    eprint!("{report}");
                    return ExitCode::from(1);
                }
            };
            eprint!("{}", checked.render_warnings());
            let opts = eom_sim::large::StaticOptions {
                load_steps,
                max_iterations,
                rtol,
                atol,
                ..Default::default()
            };
            match ancf::solve_static_cmd(&checked, &opts, json) {
                Ok(text) => {
                    print!("{text}");
                    ExitCode::SUCCESS
                }
                Err(e) => fail(&e),
            }
        }
        Command::Bench {
            model,
            per_call,
            work_precision,
            suite,
            states,
            reps,
            seed,
            native,
            integrators,
            constraints,
            t_end,
            tols,
            steps,
            ref_tol,
            samples,
            min_time,
            csv,
            svg,
            models,
            out,
            plot,
            error_label,
            json,
            params,
            inputs,
            q0,
            u0,
        } => {
            if !plot.is_empty() {
                if model.is_some() || per_call || work_precision || suite {
                    eprintln!(
                        "error: --plot draws CSV files; give no MODEL, --per-call, --work-precision or --suite"
                    );
                    return ExitCode::from(2);
                }
                let Some(svg) = svg else {
                    eprintln!("error: --plot needs --svg FILE");
                    return ExitCode::from(2);
                };
                return bench_plot(&plot, &svg, error_label.as_deref());
            }
            let mut wp = crate::sweep::WpOptions {
                ref_tol,
                samples,
                min_total_s: min_time,
                ..Default::default()
            };
            let mut problems = Vec::new();
            if !integrators.is_empty() {
                wp.integrators = parse_names(&integrators, &mut problems);
            }
            if !constraints.is_empty() {
                wp.constraints = parse_names(&constraints, &mut problems);
            }
            if let Some(t) = t_end {
                wp.t_end = t;
            }
            if !tols.is_empty() {
                wp.tols = tols;
            }
            match steps.as_slice() {
                [] => {}
                [a, b] => wp.fixed_steps = (*a, *b),
                _ => {
                    eprintln!("error: --steps takes two numbers, N0,N1");
                    return ExitCode::from(2);
                }
            }
            if (work_precision || suite)
                && let Err(e) = crate::sweep::validate(&wp)
            {
                problems.extend(e);
            }
            let params = match parse_assignments("param", &params) {
                Ok(p) => p,
                Err(e) => {
                    problems.extend(e);
                    Vec::new()
                }
            };
            // Every input is driven (a value is a constant torque): the
            // timing and sweep programs run the model as generated.
            let mut drives = Vec::new();
            for item in &inputs {
                match item.split_once('=') {
                    Some((n, v)) if !n.trim().is_empty() && !v.trim().is_empty() => {
                        drives.push((n.trim().to_string(), v.trim().to_string()));
                    }
                    _ => problems.push(format!(
                        "--input `{item}`: expected NAME=VALUE or NAME=EXPR, e.g. `--input motor=\"2*sin(3*t)\"`"
                    )),
                }
            }
            let mut initial =
                |what: &str, text: Option<String>| match text.map(|t| numbers(what, &t)) {
                    Some(Ok(v)) => Some(v),
                    Some(Err(e)) => {
                        problems.push(e);
                        None
                    }
                    None => None,
                };
            let (q0, u0) = (initial("q0", q0), initial("u0", u0));
            if (q0.is_some() || u0.is_some()) && !work_precision {
                problems.push(
                    "--q0 and --u0 set the start of the --work-precision runs; --per-call times random states".into(),
                );
            }
            if !problems.is_empty() {
                return fail(&Error::Usage(problems));
            }
            if suite && !(params.is_empty() && drives.is_empty()) {
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
            if suite {
                if model.is_some() || per_call || work_precision {
                    eprintln!(
                        "error: --suite runs every model in --models; give no MODEL, --per-call or --work-precision"
                    );
                    return ExitCode::from(2);
                }
                return bench_suite(&models, &out, &wp, t_end.is_some());
            }
            let Some(model) = model else {
                eprintln!(
                    "error: which model? `eom-gen bench MODEL --per-call|--work-precision`, or `eom-gen bench --suite`"
                );
                return ExitCode::from(2);
            };
            if work_precision {
                if per_call {
                    eprintln!("error: choose one of --per-call and --work-precision");
                    return ExitCode::from(2);
                }
                return bench_work_precision(
                    &model,
                    &vary,
                    &wp,
                    csv.as_deref(),
                    svg.as_deref(),
                    json,
                );
            }
            let o = crate::bench::PerCallOptions {
                states,
                reps,
                seed,
                native,
            };
            bench(&model, &vary, per_call, &o, json)
        }
        Command::Simulate {
            model,
            t_end,
            integrator,
            rtol,
            atol,
            dt,
            max_steps,
            q0,
            u0,
            csv,
            every,
            interpret,
            constraints,
            json,
            params,
            inputs,
            rho_inf,
        } => {
            let vary = match Vary::parse(&params, &inputs) {
                Ok(v) => v,
                Err(code) => return code,
            };
            // Models with cables run on the large-model runtime.
            if let Ok(checked) = load_checked(&model, &vary.params)
                && ancf::has_cables(&checked)
            {
                eprint!("{}", checked.render_warnings());
                let integrator = if integrator == "dopri5" {
                    "generalized-alpha".to_string()
                } else {
                    integrator
                };
                let run = ancf::CableRun {
                    integrator,
                    t_end,
                    dt,
                    rho_inf,
                    csv,
                };
                return match ancf::simulate_cmd(&checked, &run, json) {
                    Ok(text) => {
                        print!("{text}");
                        ExitCode::SUCCESS
                    }
                    Err(e) => fail(&e),
                };
            }
            let list = |what: &str, text: Option<String>| -> Result<Option<Vec<f64>>, String> {
                text.map(|t| numbers(what, &t)).transpose()
            };
            let (q0, u0) = match (list("q0", q0), list("u0", u0)) {
                (Ok(q), Ok(u)) => (q, u),
                (Err(e), _) | (_, Err(e)) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            let mut problems = Vec::new();
            let integrator = parse_names(&[integrator], &mut problems)
                .pop()
                .unwrap_or(Integrator::Dopri5);
            let constraints = parse_names(&[constraints], &mut problems)
                .pop()
                .unwrap_or(Method::Projection);
            if !problems.is_empty() {
                return fail(&Error::Usage(problems));
            }
            let o = RunOptions {
                integrator,
                rtol,
                atol,
                dt,
                t_end,
                max_steps,
                method: constraints,
                q0,
                u0,
                csv,
                every,
                energy_columns: false,
                momentum_columns: false,
            };
            simulate(&model, &vary, &o, json, interpret)
        }
        Command::Eval {
            model,
            q,
            u,
            tau,
            t,
            interpret,
            json: _,
            params,
            inputs,
        } => eval(
            &model,
            &match Vary::parse(&params, &inputs) {
                Ok(v) => v,
                Err(code) => return code,
            },
            q.as_deref(),
            u.as_deref(),
            tau.as_deref(),
            t,
            interpret,
        ),
    }
}

fn check(path: &str, json: bool) -> ExitCode {
    match load_checked(path, &[]) {
        Ok(checked) => {
            eprint!("{}", checked.render_warnings());
            let notes = checked.urdf_notes.clone().unwrap_or_default();
            if json {
                let mut v = crate::summary::json(&checked);
                if let Some(notes) = &checked.urdf_notes {
                    v["urdf_notes"] = serde_json::json!(notes);
                }
                if let Some(s) = &checked.scene {
                    v["scene"] = serde_json::json!({
                        "path": s.source.path,
                        "model": s.model_path.display().to_string(),
                        "functions": generated_functions(&checked.request()),
                    });
                }
                println!("{v}");
            } else {
                print!("{}", crate::summary::human(&checked));
                print!("{}", cable_report::check_lines(&checked.system));
                if let Some(s) = &checked.scene {
                    println!("  scene        {}", s.source.path);
                    if s.spec.functions.is_some() {
                        println!(
                            "  generated    {} (the others derived)",
                            generated_functions(&checked.request()).join(", ")
                        );
                    }
                }
                if !notes.is_empty() {
                    println!("  urdf import:");
                    for n in &notes {
                        println!("    - {n}");
                    }
                }
            }
            ExitCode::SUCCESS
        }
        Err(report) => {
            eprint!("{report}");
            if json {
                println!("{}", diagnostics_json(&report));
            }
            let errors = report.diagnostics.iter().filter(|d| d.is_error()).count();
            eprintln!("error: `{path}` has {errors} error(s)");
            ExitCode::from(1)
        }
    }
}

fn import(path: &str, output: Option<&str>) -> ExitCode {
    let options = URDF_OPTIONS.get().copied().unwrap_or_default();
    let import = match eom_gen::urdf::import_file_with(path, &options) {
        Ok(i) => i,
        Err(report) => {
            eprint!("{report}");
            let errors = report.diagnostics.iter().filter(|d| d.is_error()).count();
            eprintln!("error: `{path}` has {errors} error(s)");
            return ExitCode::from(1);
        }
    };
    // The converted model must itself be valid; report it if not.
    let checked = match eom_gen::check(&import.source) {
        Ok(c) => c,
        Err(report) => {
            eprint!("{report}");
            eprintln!("error: the model converted from `{path}` is invalid");
            return ExitCode::from(1);
        }
    };
    eprint!("{}", checked.render_warnings());
    let sys = &checked.system;
    eprintln!(
        "imported `{path}`: model `{}`, {} bodies, {} joints, nq = {} ({})",
        sys.name,
        sys.bodies.len() - 1,
        sys.joints.len(),
        sys.nq(),
        sys.coordinate_names().join(", ")
    );
    for n in &import.notes {
        eprintln!("  - {n}");
    }
    match output {
        None => {
            print!("{}", import.source.text);
            ExitCode::SUCCESS
        }
        Some(file) => match write_file(file, &import.source.text) {
            Ok(()) => ExitCode::SUCCESS,
            Err(code) => code,
        },
    }
}

fn diagnostics_json(report: &Report) -> serde_json::Value {
    let items: Vec<serde_json::Value> = report
        .diagnostics
        .iter()
        .map(|d| {
            let lc = d.span.map(|s| report.source.line_col(s.start));
            serde_json::json!({
                "severity": if d.severity == Severity::Error { "error" } else { "warning" },
                "line": lc.map(|l| l.line),
                "col": lc.map(|l| l.col),
                "message": d.message,
                "help": d.help,
            })
        })
        .collect();
    serde_json::json!({ "valid": false, "diagnostics": items })
}

/// Generates with a progress line on a terminal when it takes longer
/// than half a second (large models).
fn generate_with_progress(
    path: &str,
    vary: &Vary,
) -> Result<eom_gen::Generated, eom_gen::GenerateError> {
    let (params, drives) = (&vary.params, &vary.drives);
    use std::io::{IsTerminal, Write};
    use std::sync::mpsc;
    use std::time::{Duration, Instant};
    let generate = || {
        let options = eom_gen::EmitOptions::default();
        let mut checked = load_checked(path, params).map_err(eom_gen::GenerateError::Model)?;
        // Checked by `Vary::resolve` before (exit 2), reported again here.
        if let Err(errors) = eom_gen::model::drive_inputs(&mut checked, drives) {
            return Err(eom_gen::GenerateError::Model(eom_gen::Report {
                source: checked.source.clone(),
                diagnostics: errors
                    .into_iter()
                    .map(|e| eom_gen::Diagnostic::file_error(e.message).with_help(e.help))
                    .collect(),
            }));
        }
        if let Err(e) =
            eom_gen::model::set_initial(&mut checked, vary.q0.as_deref(), vary.u0.as_deref())
        {
            return Err(eom_gen::GenerateError::Model(eom_gen::Report {
                source: checked.source.clone(),
                diagnostics: vec![eom_gen::Diagnostic::file_error(e)],
            }));
        }
        eom_gen::generate_checked(checked, &options)
    };
    if !std::io::stderr().is_terminal() {
        return generate();
    }
    let (done, wait) = mpsc::channel::<()>();
    let label = path.to_string();
    let spinner = std::thread::spawn(move || {
        let start = Instant::now();
        let frames = ['|', '/', '-', '\\'];
        let mut k = 0;
        let mut shown = false;
        while wait.recv_timeout(Duration::from_millis(120)).is_err() {
            if start.elapsed() > Duration::from_millis(500) {
                eprint!(
                    "\r{} generating `{label}` … {:.1} s",
                    frames[k % 4],
                    start.elapsed().as_secs_f64()
                );
                let _ = std::io::stderr().flush();
                shown = true;
                k += 1;
            }
        }
        if shown {
            eprintln!(
                "\rgenerated `{label}` in {:.1} s        ",
                start.elapsed().as_secs_f64()
            );
        }
    });
    let result = generate();
    let _ = done.send(());
    let _ = spinner.join();
    result
}

fn generated(path: &str) -> Result<eom_gen::Generated, ExitCode> {
    generated_with(path, &Vary::default())
}

/// What `--param` and `--input` set.
#[derive(Clone, Debug, Default)]
struct Vary {
    /// Parameter values, by name.
    params: Vec<(String, f64)>,
    /// Input values, by name.
    inputs: Vec<(String, f64)>,
    /// Inputs driven by expressions (`--input NAME=EXPR`), by name.
    drives: Vec<(String, String)>,
    /// The model's initial positions replaced (`bench --q0`; regenerates).
    q0: Option<Vec<f64>>,
    /// The model's initial speeds replaced (`bench --u0`; regenerates).
    u0: Option<Vec<f64>>,
}

impl Vary {
    /// Both lists of `NAME=VALUE`; an input's value may be an expression
    /// (`NAME=EXPR`, which drives it); every malformed one is a usage error.
    fn parse(params: &[String], inputs: &[String]) -> Result<Vary, ExitCode> {
        let p = parse_assignments("param", params);
        let (constant, driven): (Vec<String>, Vec<String>) =
            inputs.iter().cloned().partition(|i| {
                i.split_once('=')
                    .is_none_or(|(_, v)| v.trim().parse::<f64>().is_ok())
            });
        let i = parse_assignments("input", &constant);
        let drives: Vec<(String, String)> = driven
            .iter()
            .filter_map(|i| i.split_once('='))
            .map(|(n, v)| (n.trim().to_string(), v.trim().to_string()))
            .collect();
        let mut empty: Vec<String> = drives
            .iter()
            .filter(|(n, v)| n.is_empty() || v.is_empty())
            .map(|(n, v)| format!("--input `{n}={v}`: expected NAME=VALUE or NAME=EXPR, e.g. `--input motor=\"2*sin(3*t)\"`"))
            .collect();
        match (p, i) {
            (Ok(params), Ok(inputs)) if empty.is_empty() => Ok(Vary {
                params,
                inputs,
                drives,
                ..Vary::default()
            }),
            (p, i) => {
                for e in p
                    .err()
                    .into_iter()
                    .chain(i.err())
                    .flatten()
                    .chain(empty.drain(..))
                {
                    eprintln!("error: {e}");
                }
                Err(ExitCode::from(2))
            }
        }
    }

    /// The input values in the model's order (zero where not set), after
    /// checking every name against the model: an unknown parameter or
    /// input is a usage error (exit 2) with the closest name.
    fn resolve(&self, path: &str) -> Result<Vec<f64>, ExitCode> {
        if self.params.is_empty() && self.inputs.is_empty() && self.drives.is_empty() {
            return Ok(Vec::new());
        }
        // An invalid model is reported by the generation that follows.
        let Ok(mut checked) = load_checked(path, &[]) else {
            return Ok(Vec::new());
        };
        let mut problems: Vec<String> = Vec::new();
        for (name, _) in &self.inputs {
            if self.drives.iter().any(|(d, _)| d == name) {
                problems.push(format!(
                    "input `{name}` is given a value and an expression; give one"
                ));
            }
        }
        // The driven inputs leave the model; the others keep their order.
        if let Err(errors) = eom_gen::model::drive_inputs(&mut checked, &self.drives) {
            problems.extend(errors.iter().map(|e| format!("--input {}: {e}", e.input)));
        }
        let sys = &checked.system;
        let params: Vec<&str> = sys.parameters.iter().map(|p| p.name.as_str()).collect();
        let inputs: Vec<&str> = sys.inputs.iter().map(String::as_str).collect();
        for (what, given, known) in [
            ("parameter", &self.params, &params),
            ("input", &self.inputs, &inputs),
        ] {
            for (name, _) in given {
                if known.contains(&name.as_str()) {
                    continue;
                }
                let hint = match eom_gen::diag::did_you_mean(name, known.iter().copied()) {
                    Some(m) => format!(" (did you mean `{m}`?)"),
                    None if known.is_empty() => format!("; `{}` has none", sys.name),
                    None => format!(
                        "; its {what}s: {}",
                        known
                            .iter()
                            .map(|n| format!("`{n}`"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                };
                problems.push(format!("`{path}` has no {what} `{name}`{hint}"));
            }
        }
        if !problems.is_empty() {
            for p in problems {
                eprintln!("error: {p}");
            }
            return Err(ExitCode::from(2));
        }
        Ok(sys
            .inputs
            .iter()
            .map(|n| {
                self.inputs
                    .iter()
                    .rev()
                    .find(|(m, _)| m == n)
                    .map_or(0.0, |(_, v)| *v)
            })
            .collect())
    }
}

/// `NAME=VALUE` pairs of `--what`; every malformed one is a problem.
fn parse_assignments(what: &str, items: &[String]) -> Result<Vec<(String, f64)>, Vec<String>> {
    let mut out = Vec::new();
    let mut problems = Vec::new();
    for item in items {
        let parsed = item.split_once('=').and_then(|(n, v)| {
            let v: f64 = v.trim().parse().ok()?;
            (!n.trim().is_empty() && v.is_finite()).then(|| (n.trim().to_string(), v))
        });
        match parsed {
            Some(p) => out.push(p),
            None => problems.push(format!(
                "--{what} `{item}`: expected NAME=VALUE with a finite number, e.g. `--{what} m=2.5`"
            )),
        }
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        Err(problems)
    }
}

/// Generates `path` with the parameter values and driven inputs of `vary`.
fn generated_with(path: &str, vary: &Vary) -> Result<eom_gen::Generated, ExitCode> {
    generate_with_progress(path, vary).map_err(|e| {
        eprint!("{e}");
        if !e.to_string().ends_with('\n') {
            eprintln!();
        }
        ExitCode::from(1)
    })
}

fn dump(path: &str, output: Option<&str>, fma: bool) -> ExitCode {
    let g = if fma {
        let opts = eom_gen::EmitOptions {
            type_name: None,
            fma,
        };
        match load_checked(path, &[])
            .map_err(eom_gen::GenerateError::Model)
            .and_then(|c| eom_gen::generate_checked(c, &opts))
        {
            Ok(g) => g,
            Err(e) => {
                eprint!("{e}");
                return ExitCode::from(1);
            }
        }
    } else {
        match generated(path) {
            Ok(g) => g,
            Err(code) => return code,
        }
    };
    eprint!("{}", g.checked.render_warnings());
    eprint!("{}", cable_report::dump_note(&g.checked.system));
    match output {
        None => {
            print!("{}", g.source);
            ExitCode::SUCCESS
        }
        Some(file) => match write_file(file, &g.source) {
            Ok(()) => ExitCode::SUCCESS,
            Err(code) => code,
        },
    }
}

/// The names of the functions a request generates symbolically.
fn generated_functions(r: &eom_gen::functions::FunctionSet) -> Vec<&'static str> {
    std::iter::once(Function::Qdot.name())
        .chain(r.iter().map(Function::name))
        .collect()
}

fn stats(path: &str, json: bool) -> ExitCode {
    let g = match generated(path) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let f = &g.formulation;
    // Every function of the table, `null` where not generated.
    let ops: serde_json::Map<String, serde_json::Value> = TABLE
        .iter()
        .map(|e| {
            let v = f
                .program(e.function)
                .map_or(serde_json::Value::Null, |p| op_json(&p.op_count()));
            (e.name.to_string(), v)
        })
        .collect();
    let candidates: serde_json::Map<String, serde_json::Value> = f
        .fd_candidates
        .iter()
        .map(|(form, c)| (format!("{form:?}"), op_json(c)))
        .collect();
    let (cable_text, cable_json) = cable_report::stats(&g.checked.system);
    let v = serde_json::json!({
        "name": g.checked.system.name,
        "cables": cable_json,
        "formulation": format!("{}", f.fd_form),
        "forward_dynamics_candidates": candidates,
        "ops": ops,
        "nq": g.checked.system.nq(),
        "nu": g.checked.system.nu(),
        "output_names": f.output_names,
        "generation_ms": f.seconds * 1e3,
        "source_bytes": g.source.len(),
    });
    if json {
        println!("{v}");
    } else {
        print!("{}", stats_table(&g));
        print!("{cable_text}");
    }
    ExitCode::SUCCESS
}

/// `stats` for people: one row of operation counts per generated function.
fn stats_table(g: &eom_gen::Generated) -> String {
    use std::fmt::Write;
    let f = &g.formulation;
    let sys = &g.checked.system;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: nq = {}, nu = {}, forward dynamics by {}; generated in {:.1} ms, {} bytes of source",
        sys.name,
        sys.nq(),
        sys.nu(),
        f.fd_form,
        f.seconds * 1e3,
        g.source.len()
    );
    let _ = writeln!(
        s,
        "  {:<20} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6} {:>6} {:>8}",
        "function", "add", "mul", "div", "neg", "sqrt", "trig", "other", "total"
    );
    for e in TABLE {
        match f.program(e.function) {
            Some(p) => {
                let c = p.op_count();
                let _ = writeln!(
                    s,
                    "  {:<20} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6} {:>6} {:>8}",
                    e.name,
                    c.adds,
                    c.muls,
                    c.divs,
                    c.negs,
                    c.sqrts,
                    c.trig,
                    c.other,
                    c.total()
                );
            }
            None => {
                let _ = writeln!(s, "  {:<20} {:>8}", e.name, "—");
            }
        }
    }
    if !f.output_names.is_empty() {
        let _ = writeln!(s, "  outputs: {}", f.output_names.join(", "));
    }
    s
}

fn bench(
    path: &str,
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
    if let Err(code) = vary.resolve(path) {
        return code;
    }
    let g = match generated_with(path, vary) {
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

fn op_json(c: &eom_gen::sym::OpCount) -> serde_json::Value {
    serde_json::json!({
        "add": c.adds, "mul": c.muls, "div": c.divs, "neg": c.negs,
        "sqrt": c.sqrts, "trig": c.trig, "other": c.other, "total": c.total(),
    })
}

/// A comma-separated list of `n` numbers, or the default.
fn parse_list(
    what: &str,
    text: Option<&str>,
    n: usize,
    default: Vec<f64>,
) -> Result<Vec<f64>, String> {
    let Some(text) = text else { return Ok(default) };
    match numbers(what, text) {
        Ok(v) if v.iter().any(|x| !x.is_finite()) => {
            Err(format!("--{what} must be finite numbers, got `{text}`"))
        }
        Ok(v) if v.len() == n => Ok(v),
        Ok(v) => Err(format!(
            "--{what} has {} value(s), the model has {n}",
            v.len()
        )),
        Err(e) => Err(e),
    }
}

/// The numbers of a comma-separated list; an empty (or blank) list has
/// none, which is what a model without coordinates takes (`--q ""`).
fn numbers(what: &str, text: &str) -> Result<Vec<f64>, String> {
    if text.trim().is_empty() {
        return Ok(Vec::new());
    }
    text.split(',')
        .map(|x| {
            x.trim()
                .parse::<f64>()
                .map_err(|e| format!("--{what}: `{}`: {e}", x.trim()))
        })
        .collect()
}

fn eval(
    path: &str,
    vary: &Vary,
    q: Option<&str>,
    u: Option<&str>,
    tau: Option<&str>,
    t: f64,
    interpret: bool,
) -> ExitCode {
    let inputs = match vary.resolve(path) {
        Ok(i) => i,
        Err(code) => return code,
    };
    let g = match generated_with(path, vary) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let sys = &g.checked.system;
    let (nq, nu) = (sys.nq(), sys.nu());
    let parsed = (|| -> Result<_, String> {
        Ok((
            parse_list("q", q, nq, sys.q0())?,
            parse_list("u", u, nu, sys.u0())?,
            parse_list("tau", tau, nu, vec![0.0; nu])?,
        ))
    })();
    let (q, u, tau) = match parsed {
        Ok(v) => v,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let result = if interpret {
        let point = eom_gen::interpret::Point {
            sys,
            q: &q,
            u: &u,
            udot: &[],
            tau: &tau,
            inputs: &inputs,
            params: &[],
            multipliers: &[],
            t,
        };
        Ok(eom_gen::interpret::evaluate(&g.formulation, &point))
    } else {
        crate::compiled::evaluate(&sys.name, &g.source, &q, &u, &tau, t, &inputs)
    };
    match result {
        Ok(e) => {
            let mut v = serde_json::json!({
                "coordinate_names": sys.coordinate_names(),
                "speed_names": sys.speed_names(),
                "q": q, "u": u, "t": t,
                "mode": if interpret { "interpreted" } else { "compiled" },
            });
            for (key, value) in evaluation_json(&e, nu) {
                v[key] = value;
            }
            if let Some(note) = crate::ancf::scope_note(&g.checked, "eval") {
                eprintln!("{note}");
            }
            if let Some(block) = crate::ancf::eval_block(&g.checked, &q, &u, t) {
                v["cables"] = block;
            }
            println!("{v}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

/// How `eval` prints the functions: `qdot`, `udot` (forward dynamics),
/// `mass_matrix` (rows), `bias`, `kinetic_energy` and `potential_energy`,
/// and every function of the table, flat, under `functions`.
fn evaluation_json(
    e: &eom_gen::interpret::Evaluation,
    nu: usize,
) -> Vec<(String, serde_json::Value)> {
    let mut out = Vec::new();
    let mut all = serde_json::Map::new();
    for (name, values) in &e.functions {
        all.insert(name.clone(), serde_json::json!(values));
        let Ok(f) = name.parse::<Function>() else {
            continue;
        };
        match (f, f.entry().layout) {
            (Function::ForwardDynamics, _) => out.push(("udot".into(), serde_json::json!(values))),
            (Function::Energy, _) => {
                let at = |k: usize| values.get(k).copied().unwrap_or(f64::NAN);
                out.push(("kinetic_energy".into(), serde_json::json!(at(0))));
                out.push(("potential_energy".into(), serde_json::json!(at(1))));
            }
            (_, Layout::LowerTriangle) => {
                let rows: Vec<&[f64]> = values.chunks(nu.max(1)).collect();
                out.push((name.clone(), serde_json::json!(rows)));
            }
            (Function::Qdot | Function::Bias, _) => {
                out.push((name.clone(), serde_json::json!(values)))
            }
            _ => {}
        }
    }
    out.push(("functions".into(), serde_json::Value::Object(all)));
    out
}

/// Prints an error (each usage problem on its own line) and gives its
/// exit status.
fn fail(e: &Error) -> ExitCode {
    match e {
        Error::Usage(problems) => problems.iter().for_each(|p| eprintln!("error: {p}")),
        e => eprintln!("error: {e}"),
    }
    ExitCode::from(e.exit_code())
}

/// The names parsed (integrators, constraint methods); each unknown one
/// is a problem.
fn parse_names<T: std::str::FromStr>(names: &[String], problems: &mut Vec<String>) -> Vec<T>
where
    T::Err: std::fmt::Display,
{
    names
        .iter()
        .filter_map(|n| {
            n.trim()
                .parse()
                .map_err(|e: T::Err| problems.push(e.to_string()))
                .ok()
        })
        .collect()
}

/// A run that did not reach its end time: exit status 3.
const EXIT_RUN_STOPPED: u8 = 3;

fn simulate(path: &str, vary: &Vary, o: &RunOptions, json: bool, interpret: bool) -> ExitCode {
    let problems = o.problems();
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    let inputs = match vary.resolve(path) {
        Ok(i) => i,
        Err(code) => return code,
    };
    let g = match generated_with(path, vary) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let sys = &g.checked.system;
    let mut o = o.clone();
    // Every requested output goes into the CSV: energy and momentum
    // next to the marker and reaction outputs.
    o.energy_columns = sys.outputs.contains(&eom_gen::system::OutputKind::Energy);
    o.momentum_columns = sys.outputs.contains(&eom_gen::system::OutputKind::Momentum);
    let o = &o;
    let result = if interpret {
        eom_gen::interpret::simulate_with_inputs(&g.formulation, sys, o, &inputs)
            .map_err(|e| Error::Refused(e.to_string()))
    } else {
        crate::compiled::simulate(&sys.name, &g.source, sys.nq(), sys.nu(), o, &inputs)
    };
    let r: RunReport = match result {
        Ok(r) => r,
        Err(e) => return fail(&e),
    };
    if json {
        match serde_json::to_string(&r) {
            Ok(text) => println!("{text}"),
            Err(e) => {
                eprintln!("error: cannot encode the report: {e}");
                return ExitCode::from(1);
            }
        }
    } else {
        print!(
            "{}",
            simulate_summary(&sys.name, &sys.coordinate_names(), o, &r)
        );
    }
    if r.stop.is_finished() {
        ExitCode::SUCCESS
    } else {
        eprintln!("error: the run stopped before t = {}: {}", o.t_end, r.stop);
        ExitCode::from(EXIT_RUN_STOPPED)
    }
}

/// The human summary of a run.
fn simulate_summary(name: &str, coordinates: &[&str], o: &RunOptions, r: &RunReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let setting = if o.integrator.is_adaptive() {
        format!("rtol {:e}, atol {:e}", o.rtol, o.atol)
    } else {
        format!("step {:e} s", o.dt)
    };
    let stop = if r.stop.is_finished() {
        "\"finished\"".to_string()
    } else {
        r.stop.to_string()
    };
    let _ = writeln!(
        s,
        "{name}: {} to t = {:?} s ({setting}): {stop}",
        o.integrator, r.t
    );
    let _ = writeln!(
        s,
        "  {} steps ({} rejected), {} right-hand sides, {:.3} ms",
        r.stats.steps,
        r.stats.rejected,
        r.stats.rhs_evals,
        r.cpu_s * 1e3
    );
    let q: Vec<String> =
        r.q.iter()
            .zip(coordinates)
            .map(|(x, n)| format!("{n} = {x:.6}"))
            .collect();
    let _ = writeln!(s, "  final {}", q.join(", "));
    let [e0, e1] = r.energy;
    let _ = writeln!(
        s,
        "  energy {e0:.9} → {e1:.9} (relative change {:.1e})",
        ((e1 - e0) / e0.abs().max(1e-300)).abs()
    );
    if let Some(c) = &r.constrained {
        let m = &c.summary;
        let _ = writeln!(
            s,
            "  constraints ({}): max |Φ| {:.1e}, max |Φ̇| {:.1e}, rank {} of {}, smallest σ_r/σ_1 of J {:.1e}",
            c.constraints,
            m.max_constraint_residual,
            m.max_velocity_residual,
            m.constraint_rank,
            c.constraint_names.len(),
            m.min_singular_ratio
        );
        if m.min_singular_ratio < 1e-2 {
            let _ = writeln!(
                s,
                "  note: J came near losing rank: the run passed close to a singular configuration, \
                 where the constraint forces are ill-conditioned and accuracy is limited; compare \
                 with a tighter tolerance or another --constraints method"
            );
        }
    }
    if let Some(csv) = &o.csv {
        let _ = writeln!(s, "  trajectory written to {csv}");
    }
    s
}

/// A progress bar over the points of one sweep (hidden when stderr is not
/// a terminal).
fn wp_progress(label: &str) -> indicatif::ProgressBar {
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

fn wp_sweep(
    g: &eom_gen::Generated,
    o: &crate::sweep::WpOptions,
    bar: &indicatif::ProgressBar,
) -> Result<crate::sweep::WorkPrecision, crate::error::Error> {
    crate::sweep::run(g, o, &mut |done, total, p| {
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

/// Writes `text` to `path`; its directory must exist (nothing is created
/// that the user did not name). The error, naming the path, is printed
/// and the exit status returned.
fn write_file(path: &str, text: &str) -> Result<(), ExitCode> {
    let fail = |why: String| {
        eprintln!("error: cannot write `{path}`: {why}");
        ExitCode::from(1)
    };
    if let Some(dir) = std::path::Path::new(path).parent()
        && !dir.as_os_str().is_empty()
        && !dir.is_dir()
    {
        return Err(fail(format!(
            "the directory `{}` does not exist",
            dir.display()
        )));
    }
    std::fs::write(path, text).map_err(|e| fail(e.to_string()))
}

/// Creates the output directory the user named (`bench --suite --out`).
fn create_out_dir(dir: &str) -> Result<(), ExitCode> {
    std::fs::create_dir_all(dir).map_err(|e| {
        eprintln!("error: cannot create the output directory `{dir}`: {e}");
        ExitCode::from(1)
    })
}

fn bench_work_precision(
    path: &str,
    vary: &Vary,
    o: &crate::sweep::WpOptions,
    csv: Option<&str>,
    svg: Option<&str>,
    json: bool,
) -> ExitCode {
    use crate::sweep as wp;
    if let Err(errors) = wp::validate(o) {
        for e in errors {
            eprintln!("error: {e}");
        }
        return ExitCode::from(2);
    }
    if let Err(code) = vary.resolve(path) {
        return code;
    }
    let g = match generated_with(path, vary) {
        Ok(g) => g,
        Err(code) => return code,
    };
    eprint!("{}", g.checked.render_warnings());
    let bar = wp_progress(&g.checked.system.name);
    let result = wp_sweep(&g, o, &bar);
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
fn bench_suite(dir: &str, out: &str, o: &crate::sweep::WpOptions, t_end_given: bool) -> ExitCode {
    use crate::sweep as wp;
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
        let g = match generate_with_progress(&p, &Vary::default()) {
            Ok(g) => g,
            Err(e) => {
                bars.suspend(|| eprint!("{e}"));
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
        let bar = bars.add(wp_progress(&name));
        let result = wp_sweep(&g, &opts, &bar);
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
fn bench_plot(files: &[String], svg: &str, error_label: Option<&str>) -> ExitCode {
    use crate::sweep as wp;
    let mut all: Vec<wp::WorkPrecision> = Vec::new();
    let mut errors = Vec::new();
    for f in files {
        match std::fs::read_to_string(f)
            .map_err(|e| crate::error::Error::io(f, e))
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
