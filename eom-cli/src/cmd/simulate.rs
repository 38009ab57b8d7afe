//! `eom-gen simulate`: integrate a model from its initial state, compiled
//! (built once, cached) or interpreted; models with cables on the
//! large-model runtime (`crate::ancf`).

use crate::args::{
    InitialArgs, InputArgs, ParamArgs, Vary, numbers, parse_names, unread_step_options,
};
use crate::error::Error;
use crate::output::fail;
use crate::report::{Setting, finish};
use clap::Args;
use eom_sim::{Integrator, Method, RunOptions, RunReport};
use std::process::ExitCode;

/// Integrate the compiled model from its initial state.
#[derive(Args)]
pub struct SimulateArgs {
    /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
    pub model: String,
    /// End time, s.
    #[arg(long, allow_hyphen_values = true)]
    pub t_end: f64,
    /// rk4, dopri5, dop853, radau5, midpoint or euler (default dopri5);
    /// models with cables: generalized-alpha (default) or rk4.
    #[arg(long)]
    pub integrator: Option<String>,
    /// Relative tolerance (adaptive methods; default 1e-8).
    #[arg(long, allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// Absolute tolerance (adaptive methods; default 1e-10).
    #[arg(long, allow_hyphen_values = true)]
    pub atol: Option<f64>,
    /// Step size, s (fixed-step methods: rk4, euler, midpoint; with
    /// cables generalized-α's step, its first one under --rtol/--atol;
    /// default 1e-3).
    #[arg(long, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Most attempted steps; a run that needs more stops (exit 3;
    /// default 100000).
    #[arg(long)]
    pub max_steps: Option<usize>,
    #[command(flatten)]
    pub initial: InitialArgs,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub inputs: InputArgs,
    /// Write the trajectory (t, q, u) to this CSV file.
    #[arg(long)]
    pub csv: Option<String>,
    /// Plot the run as SVG: the coordinates, the energy drift and the
    /// constraint residuals (where the model has constraints); adds the
    /// energy and residual columns to the CSV.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<String>,
    /// Write the motion as one self-contained HTML page that plays it in
    /// 3-D (orbit, zoom, play/pause, time slider, speed); its frames are
    /// the CSV's rows (`--every` sets their interval).
    #[arg(long, value_name = "FILE.html")]
    pub html: Option<String>,
    /// Output interval of the CSV, using dense output (default: every step).
    #[arg(long, allow_hyphen_values = true)]
    pub every: Option<f64>,
    /// Models with contacts: write the contact events (impacts, rest,
    /// release: time, kind, energies, per contact row the impulse and the
    /// normal speeds before and after, the generalised impulse per speed)
    /// to this CSV file.
    #[arg(long)]
    pub events_csv: Option<String>,
    /// Run the programs in the evaluator instead of compiled code.
    #[arg(long)]
    pub interpret: bool,
    /// Closed loops and constraints: `projection` (of positions and
    /// speeds after each step), `baumgarte` (multipliers with Baumgarte
    /// stabilisation, α = β = 10/s), `partitioning` (dependent
    /// coordinates from independent ones, Wehage–Haug), `index3` (the
    /// index-3 DAE, with radau5) or `augmented-lagrangian` (Bayo and
    /// Ledesma; well-posed through singular and redundant constraints).
    /// Default projection.
    #[arg(long)]
    pub constraints: Option<String>,
    /// Where radau5 and midpoint get the Jacobian `∂(q̇, u̇)/∂(q, u)`:
    /// `generated` (the symbolic derivatives, generated for the run;
    /// unconstrained models without quaternions), `differences` (forward
    /// differences of the right-hand side) or `auto` (generated where it
    /// applies and the model has at most 12 speeds; the default). Models
    /// with cables: where generalized-α's Newton matrix takes the
    /// elements' tangent, `generated` (their kernels; `auto` is the same)
    /// or `differences` (of their forces).
    #[arg(long)]
    pub jacobian: Option<String>,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Spectral radius at infinity of generalized-α (models with
    /// cables; 1 = no numerical damping; default 1).
    #[arg(long, allow_hyphen_values = true)]
    pub rho_inf: Option<f64>,
    /// Run N perturbed copies of the initial state, compiled, several per
    /// call in SIMD lanes (rk4 or dopri5; models without constraints,
    /// contacts or cables); --csv then gets one row per member (final
    /// state and statistics), --json the same as JSON.
    #[arg(long, value_name = "N")]
    pub ensemble: Option<usize>,
    /// Seed of --ensemble's draws (default 0).
    #[arg(long)]
    pub seed: Option<u64>,
    /// --ensemble: standard deviations of the Gaussian perturbations of
    /// every initial position and speed, `q=σ,u=σ` (unit quaternions
    /// renormalised; default 0).
    #[arg(long, value_name = "q=σ,u=σ")]
    pub perturb: Option<String>,
    /// --ensemble: a parameter drawn per member, Gaussian about its value
    /// with this standard deviation (made tunable: one build); repeatable.
    #[arg(long = "param-spread", value_name = "NAME=σ")]
    pub param_spread: Vec<String>,
    /// --ensemble: states per call, 1, 4 or 8 (default 8 with --native on
    /// a CPU with AVX-512, else 4).
    #[arg(long, value_name = "W")]
    pub lanes: Option<usize>,
    /// --ensemble: build with `-C target-cpu=native` (wider SIMD lanes;
    /// the binary runs only on this kind of CPU).
    #[arg(long)]
    pub native: bool,
}

pub fn run(a: SimulateArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    // Every problem with the arguments is reported together, before
    // anything is generated or built.
    let mut problems = Vec::new();
    let ensemble = a.ensemble_args();
    let vary = Vary::parse(&a.params.params, &a.inputs.inputs).unwrap_or_else(|p| {
        problems.extend(p);
        Vary::default()
    });
    let mut list = |what: &str, text: &Option<String>| -> Option<Vec<f64>> {
        match text.as_deref().map(|t| numbers(what, t)) {
            Some(Ok(v)) => Some(v),
            Some(Err(e)) => {
                problems.push(e);
                None
            }
            None => None,
        }
    };
    let (q0, u0) = (list("q0", &a.initial.q0), list("u0", &a.initial.u0));
    let opened = match crate::open::open(&a.model, urdf, &vary) {
        Ok(o) => o,
        Err(code) => {
            return if problems.is_empty() {
                code
            } else {
                fail(&Error::Usage(problems))
            };
        }
    };
    // `--every` samples the recorded trajectory: without a CSV, a page
    // or a plot nothing is recorded.
    if a.every.is_some() && a.csv.is_none() && a.html.is_none() && a.plot.is_none() {
        problems.push(
            "--every sets the interval of the recorded trajectory's rows; nothing is recorded \
             without --csv, --html or --plot"
                .into(),
        );
    }
    // Models with cables run on the large-model runtime.
    if crate::ancf::has_cables(&opened.checked) {
        return simulate_cables(&opened, a, problems);
    }
    if a.rho_inf.is_some() {
        problems.push(
            "--rho-inf sets generalized-α, which runs models with cables; this model has none (its integrators: --integrator)".into(),
        );
    }
    let integrator = parse_names(
        &[a.integrator.unwrap_or_else(|| "dopri5".into())],
        &mut problems,
    )
    .pop()
    .unwrap_or(Integrator::Dopri5);
    problems.extend(unread_step_options(
        integrator,
        a.dt.is_some(),
        a.rtol.is_some() || a.atol.is_some(),
    ));
    let sys = &opened.checked.system;
    if a.constraints.is_some() && sys.graph.cut_joints().is_empty() && sys.constraints.is_empty() {
        problems.push(format!(
            "--constraints chooses how closed loops and constraints are kept; `{}` has none \
             (its options: --integrator, --rtol, --atol, --dt)",
            sys.name
        ));
    }
    let constraints = parse_names(
        &[a.constraints.unwrap_or_else(|| "projection".into())],
        &mut problems,
    )
    .pop()
    .unwrap_or(Method::Projection);
    let jacobian = parse_names(
        &[a.jacobian.unwrap_or_else(|| "auto".into())],
        &mut problems,
    )
    .pop()
    .unwrap_or_default();
    let o = RunOptions {
        integrator,
        rtol: a.rtol.unwrap_or(1e-8),
        atol: a.atol.unwrap_or(1e-10),
        dt: a.dt.unwrap_or(1e-3),
        t_end: a.t_end,
        max_steps: a.max_steps.unwrap_or(100_000),
        method: constraints,
        q0,
        u0,
        csv: a.csv,
        every: a.every,
        energy_columns: false,
        momentum_columns: false,
        constraint_columns: false,
        events_csv: a.events_csv,
        jacobian,
    };
    if o.events_csv.is_some() && sys.contacts.is_empty() {
        problems.push(format!(
            "--events-csv writes the contact events; `{}` has no contacts",
            sys.name
        ));
    }
    problems.extend(o.problems());
    if let Some(why) = jacobian_problem(sys, &o) {
        problems.push(why);
    }
    for (what, given, names) in [
        ("q0", &o.q0, sys.coordinate_names()),
        ("u0", &o.u0, sys.speed_names()),
    ] {
        if let Some(v) = given
            && v.len() != names.len()
        {
            problems.push(format!(
                "--{what} has {} value(s); `{}` has {}: {}",
                v.len(),
                sys.name,
                names.len(),
                names.join(", ")
            ));
        }
    }
    let spread = ensemble_options(&ensemble, &opened.checked, &o, &mut problems);
    if ensemble.ensemble.is_some() && !vary.drives.is_empty() {
        problems.push(
            "--input NAME=EXPR drives an input by an expression; --ensemble takes constant \
             inputs only (--input NAME=VALUE)"
                .into(),
        );
    }
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    if let Some(spread) = spread {
        eprint!("{}", opened.checked.render_warnings());
        return match crate::ensemble::run(&opened, &o, &spread, a.json) {
            Ok(code) => code,
            Err(e) => fail(&e),
        };
    }
    let pictures = Pictures {
        plot: a.plot.as_deref(),
        html: a.html.as_deref(),
    };
    simulate(&opened, &vary, &o, a.json, a.interpret, &pictures)
}

/// `simulate` on a model with cables: the options of the large-model
/// runtime honoured, every other one a usage error naming what applies.
fn simulate_cables(
    opened: &crate::open::Opened,
    a: SimulateArgs,
    mut problems: Vec<String>,
) -> ExitCode {
    let checked = &opened.checked;
    let integrator = parse_names::<Integrator>(
        &[a.integrator
            .clone()
            .unwrap_or_else(|| "generalized-alpha".to_string())],
        &mut problems,
    )
    .pop()
    .unwrap_or(Integrator::GeneralizedAlpha);
    if a.events_csv.is_some()
        && checked.system.cable_contacts.is_empty()
        && checked.system.contacts.is_empty()
    {
        problems.push(format!(
            "--events-csv writes the contact events; `{}` has no contacts",
            checked.system.name
        ));
    }
    let refused: [(&str, bool); 13] = [
        ("--ensemble", a.ensemble.is_some()),
        ("--seed", a.seed.is_some()),
        ("--perturb", a.perturb.is_some()),
        ("--param-spread", !a.param_spread.is_empty()),
        ("--lanes", a.lanes.is_some()),
        ("--native", a.native),
        ("--plot", a.plot.is_some()),
        ("--max-steps", a.max_steps.is_some()),
        ("--constraints", a.constraints.is_some()),
        ("--q0", a.initial.q0.is_some()),
        ("--u0", a.initial.u0.is_some()),
        ("--input", !a.inputs.inputs.is_empty()),
        ("--interpret", a.interpret),
    ];
    for (option, given) in refused {
        if given {
            problems.push(format!(
                "{option} does not apply to `{}`, a model with cables: it runs generalized-α \
                 (fixed step, or step control with --rtol/--atol) or rk4 (fixed step); its \
                 options are --t-end, --dt, --rtol, --atol, --integrator generalized-alpha|rk4, \
                 --rho-inf, --jacobian, --param, --csv, --every, --events-csv, --html and --json",
                checked.system.name
            ));
        }
    }
    // Generalized-α's Newton matrix: the elements' generated tangent, or
    // differences of their forces (to compare the two).
    let tangent = parse_names::<eom_sim::Jacobian>(
        &[a.jacobian.clone().unwrap_or_else(|| "auto".into())],
        &mut problems,
    )
    .pop()
    .unwrap_or_default();
    if a.jacobian.is_some() && integrator == Integrator::Rk4 {
        problems.push(format!(
            "--jacobian does not apply to rk4, which is explicit: it sets where generalized-α's \
             Newton matrix for `{}` takes the elements' tangent from (generated or differences)",
            checked.system.name
        ));
    }
    if !integrator.runs_element_models() {
        problems.push(format!(
            "--integrator {integrator} does not run `{}`, a model with cables: use \
             generalized-alpha (implicit, fixed step or step control with --rtol/--atol; the \
             default) or rk4 (explicit, fixed step)",
            checked.system.name
        ));
    }
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    eprint!("{}", checked.render_warnings());
    let run = eom_sim::large::ElementRun {
        integrator,
        t_end: a.t_end,
        dt: a.dt.unwrap_or(1e-3),
        rho_inf: a.rho_inf.unwrap_or(1.0),
        control: (a.rtol.is_some() || a.atol.is_some()).then(|| {
            let rtol = a.rtol.unwrap_or(1e-6);
            eom_sim::large::StepControl::new(rtol, a.atol.unwrap_or(rtol))
        }),
        record: a.csv.is_some() || a.html.is_some(),
        every: a.every,
    };
    // The page reads the nodes back from the CSV (a temporary one when
    // the user asked for none).
    let csv = a.csv.clone().or_else(|| {
        a.html.as_ref().map(|_| {
            std::env::temp_dir()
                .join(format!(
                    "eom-html-{}-{}.csv",
                    checked.system.name,
                    std::process::id()
                ))
                .display()
                .to_string()
        })
    });
    let code = match crate::ancf::simulate_cmd(
        checked,
        &run,
        tangent,
        (csv.as_deref(), a.events_csv.as_deref()),
        a.json,
    ) {
        Ok(code) => code,
        Err(e) => return fail(&e),
    };
    let drawn = match (&a.html, &csv) {
        (Some(html), Some(path)) => animate_run(path, html, &checked.system, &[]),
        _ => Ok(()),
    };
    if a.csv.is_none()
        && let Some(path) = &csv
    {
        let _ = std::fs::remove_file(path);
    }
    match drawn {
        Ok(()) => code,
        Err(code) => code,
    }
}

fn simulate(
    opened: &crate::open::Opened,
    vary: &Vary,
    o: &RunOptions,
    json: bool,
    interpret: bool,
    pictures: &Pictures<'_>,
) -> ExitCode {
    let plot = pictures.plot;
    let inputs = &opened.inputs;
    // RADAU5 and the implicit midpoint rule get the generated Jacobian
    // where it applies (`eom_sim::Jacobian`): its derivatives are generated
    // for the run.
    let sys = &opened.checked.system;
    let derivatives = o.integrator.uses_jacobian()
        && (o.jacobian == eom_sim::Jacobian::Generated
            || (o.jacobian == eom_sim::Jacobian::Auto && sys.nu() <= AUTO_DERIVATIVES_MAX_NU))
        && jacobian_problem(
            sys,
            &RunOptions {
                jacobian: eom_sim::Jacobian::Generated,
                ..o.clone()
            },
        )
        .is_none();
    let also = if derivatives {
        eom_gen::functions::FunctionSet::default()
            .with(eom_gen::functions::Function::ForwardDynamicsDerivatives)
    } else {
        eom_gen::functions::FunctionSet::default()
    };
    let g = match crate::open::generate_asking(opened, vary, &Default::default(), also) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let sys = &g.checked.system;
    let mut o = o.clone();
    // Every requested output goes into the CSV: energy and momentum
    // next to the marker and reaction outputs.
    o.energy_columns = sys.outputs.contains(&eom_gen::system::OutputKind::Energy);
    o.momentum_columns = sys.outputs.contains(&eom_gen::system::OutputKind::Momentum);
    // A plot and an animation read the trajectory back from the CSV (a
    // temporary one when the user asked for none); a plot with the
    // energy and residuals.
    let user_csv = o.csv.clone();
    if plot.is_some() {
        o.energy_columns = true;
        o.constraint_columns = true;
    }
    let plot_csv = (plot.is_some() || pictures.html.is_some()).then(|| {
        user_csv.clone().unwrap_or_else(|| {
            std::env::temp_dir()
                .join(format!("eom-plot-{}-{}.csv", sys.name, std::process::id()))
                .display()
                .to_string()
        })
    });
    o.csv = plot_csv.clone().or(o.csv);
    let o = &o;
    let result = if interpret {
        eom_gen::interpret::simulate_with_inputs(&g.formulation, sys, o, inputs)
            .map_err(|e| Error::Refused(e.to_string()))
    } else {
        crate::compiled::simulate(&sys.name, &g.source, sys.nq(), sys.nu(), o, inputs)
    };
    let r: RunReport = match result {
        Ok(r) => r,
        Err(e) => return fail(&e),
    };
    if let Some(csv) = &plot_csv {
        let mut drawn = match plot {
            Some(svg) => plot_run(csv, svg, sys),
            None => Ok(()),
        };
        if let (Ok(()), Some(html)) = (&drawn, pictures.html) {
            drawn = animate_run(csv, html, sys, &r.contact_events);
        }
        if user_csv.is_none() {
            let _ = std::fs::remove_file(csv);
        }
        if let Err(code) = drawn {
            return code;
        }
    }
    let mut detail = if o.integrator.is_adaptive() {
        format!("rtol {:e}, atol {:e}", o.rtol, o.atol)
    } else {
        format!("step {:e} s", o.dt)
    };
    if let Some(j) = r.stats.jacobian {
        detail.push_str(&format!(", {j} Jacobian"));
    }
    let setting = Setting {
        integrator: o.integrator,
        detail,
        csv: user_csv.as_deref(),
        events_csv: o.events_csv.as_deref(),
    };
    finish(
        &sys.name,
        &sys.coordinate_names(),
        &setting,
        o.t_end,
        &r,
        json,
    )
}

/// The `--ensemble` options and the others they meet.
pub struct EnsembleArgs {
    ensemble: Option<usize>,
    seed: Option<u64>,
    perturb: Option<String>,
    param_spread: Vec<String>,
    lanes: Option<usize>,
    native: bool,
    others: Vec<(&'static str, bool)>,
}

impl SimulateArgs {
    fn ensemble_args(&self) -> EnsembleArgs {
        EnsembleArgs {
            ensemble: self.ensemble,
            seed: self.seed,
            perturb: self.perturb.clone(),
            param_spread: self.param_spread.clone(),
            lanes: self.lanes,
            native: self.native,
            others: vec![
                ("--interpret", self.interpret),
                ("--plot", self.plot.is_some()),
                ("--html", self.html.is_some()),
                ("--every", self.every.is_some()),
                ("--events-csv", self.events_csv.is_some()),
                ("--jacobian", self.jacobian.is_some()),
                ("--constraints", self.constraints.is_some()),
            ],
        }
    }
}

/// `--ensemble`'s settings, or the problems with them (every option of
/// it without `--ensemble`, every option that does not apply with it).
fn ensemble_options(
    a: &EnsembleArgs,
    checked: &eom_gen::Checked,
    o: &RunOptions,
    problems: &mut Vec<String>,
) -> Option<crate::ensemble::Spread> {
    let Some(n) = a.ensemble else {
        for (name, given) in [
            ("--seed", a.seed.is_some()),
            ("--perturb", a.perturb.is_some()),
            ("--param-spread", !a.param_spread.is_empty()),
            ("--lanes", a.lanes.is_some()),
            ("--native", a.native),
        ] {
            if given {
                problems.push(format!("{name} sets up --ensemble N; give --ensemble"));
            }
        }
        return None;
    };
    let before = problems.len();
    if n == 0 {
        problems.push("--ensemble N: N must be at least 1".into());
    }
    for (name, given) in &a.others {
        if *given {
            problems.push(format!(
                "{name} does not apply to --ensemble (final states of many runs in lanes; its                  options: --seed, --perturb, --param-spread, --lanes, --csv, --json and the run's                  --t-end, --integrator, --rtol, --atol, --dt, --max-steps, --q0, --u0, --param,                  --input)"
            ));
        }
    }
    if let Some(why) = crate::lanes::refusal(checked) {
        problems.push(format!("--ensemble: {why}"));
    }
    problems.extend(crate::lanes::integrator_refusal(o.integrator));
    let width = a
        .lanes
        .unwrap_or_else(|| crate::lanes::default_width(a.native));
    if !crate::lanes::WIDTHS.contains(&width) {
        problems.push(format!(
            "--lanes {width}: the ensemble is built for {:?} states per call",
            crate::lanes::WIDTHS
        ));
    }
    let (q, u) = match a.perturb.as_deref().map(crate::ensemble::parse_perturb) {
        Some(Ok(p)) => p,
        Some(Err(e)) => {
            problems.push(e);
            (0.0, 0.0)
        }
        None => (0.0, 0.0),
    };
    let mut params = Vec::new();
    for p in &a.param_spread {
        match crate::ensemble::parse_param_spread(p) {
            Ok(p) if params.iter().any(|(n, _)| *n == p.0) => {
                problems.push(format!("--param-spread `{}` is given twice", p.0));
            }
            Ok(p) => params.push(p),
            Err(e) => problems.push(e),
        }
    }
    (problems.len() == before).then_some(crate::ensemble::Spread {
        n,
        seed: a.seed.unwrap_or(0),
        q,
        u,
        params,
        width,
        native: a.native,
    })
}

/// The pictures `simulate` draws of a run, each to its file.
pub struct Pictures<'a> {
    /// `--plot FILE.svg`.
    pub plot: Option<&'a str>,
    /// `--html FILE.html` (and `eom-gen animate -o`).
    pub html: Option<&'a str>,
}

/// `simulate --html`: the animation page of the run's CSV.
fn animate_run(
    csv: &str,
    html: &str,
    sys: &eom_gen::system::System,
    events: &[eom_sim::run::ContactEvent],
) -> Result<(), ExitCode> {
    let text = std::fs::read_to_string(csv)
        .map_err(|e| fail(&Error::io(csv, format!("cannot read the trajectory: {e}"))))?;
    let table = eom_sim::table::Table::from_csv(&text)
        .map_err(|e| fail(&Error::Format(format!("{csv}: {e}"))))?;
    let page = crate::animate::html(sys, &table, events).map_err(|e| fail(&e))?;
    crate::output::write_file(html, &page)?;
    eprintln!(
        "animation written to {html} ({} frames, {} bytes)",
        table.rows.len(),
        page.len()
    );
    Ok(())
}

/// `simulate --plot`: the default panels of the run's CSV drawn to `svg`.
fn plot_run(csv: &str, svg: &str, sys: &eom_gen::system::System) -> Result<(), ExitCode> {
    let text = std::fs::read_to_string(csv)
        .map_err(|e| fail(&Error::io(csv, format!("cannot read the trajectory: {e}"))))?;
    let mut table = eom_sim::table::Table::from_csv(&text)
        .map_err(|e| fail(&Error::Format(format!("{csv}: {e}"))))?;
    crate::history::derive_columns(&mut table);
    let units = crate::history::model_units(sys);
    let panels = crate::history::default_panels(&table, &sys.coordinate_names(), &units);
    let labels = crate::history::model_labels(sys);
    let text =
        crate::history::svg(&table, &panels, &units, &labels, &sys.name).map_err(|e| fail(&e))?;
    crate::output::write_file(svg, &text)?;
    eprintln!("plot written to {svg}");
    Ok(())
}

/// The most speeds for which `--jacobian auto` generates the derivatives:
/// their program grows about as `NU³` (arm7, 7 speeds: 12 780 operations,
/// 1.6 s more formulation in a debug build), forward differences cost `2 NU`
/// right-hand sides per Jacobian, and an implicit run evaluates few
/// Jacobians; above this `--jacobian generated` asks for them.
const AUTO_DERIVATIVES_MAX_NU: usize = 12;

/// Why `--jacobian` does not apply to this run, if it does not: asked for
/// an integrator that uses no Jacobian, or `generated` where there is none
/// (the library's run refuses the same; here it is said before anything is
/// generated, with the other usage problems).
fn jacobian_problem(sys: &eom_gen::system::System, o: &RunOptions) -> Option<String> {
    // The run's own rule (`eom_sim::jacobian_choice`), asked before
    // generation: the derivatives are generated for the run when it can
    // use them.
    let shape = eom_sim::JacobianShape {
        constrained: !sys.constraints.is_empty() || !sys.graph.cut_joints().is_empty(),
        nonholonomic: sys.constraints.iter().any(|c| c.equations().1 > 0),
        quaternions: sys.nq() != sys.nu(),
        derivatives: true,
    };
    eom_sim::jacobian_choice(shape, o).err()
}
