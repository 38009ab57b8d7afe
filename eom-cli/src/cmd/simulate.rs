//! `eom-gen simulate`: integrate a model from its initial state, compiled
//! (built once, cached) or interpreted; models with cables on the
//! large-model runtime (`crate::ancf`).

use crate::args::{InitialArgs, InputArgs, ParamArgs, Vary, numbers, parse_names};
use crate::error::Error;
use crate::output::fail;
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
    /// Step size (fixed-step methods).
    #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
    pub dt: f64,
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
    /// Output interval of the CSV, using dense output (default: every step).
    #[arg(long, allow_hyphen_values = true)]
    pub every: Option<f64>,
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
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Spectral radius at infinity of generalized-α (models with
    /// cables; 1 = no numerical damping; default 1).
    #[arg(long, allow_hyphen_values = true)]
    pub rho_inf: Option<f64>,
}

/// A run that did not reach its end time: exit status 3.
const EXIT_RUN_STOPPED: u8 = 3;

pub fn run(a: SimulateArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    // Every problem with the arguments is reported together, before
    // anything is generated or built.
    let mut problems = Vec::new();
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
    let o = RunOptions {
        integrator,
        rtol: a.rtol.unwrap_or(1e-8),
        atol: a.atol.unwrap_or(1e-10),
        dt: a.dt,
        t_end: a.t_end,
        max_steps: a.max_steps.unwrap_or(100_000),
        method: constraints,
        q0,
        u0,
        csv: a.csv,
        every: a.every,
        energy_columns: false,
        momentum_columns: false,
    };
    problems.extend(o.problems());
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
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    simulate(&opened, &vary, &o, a.json, a.interpret)
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
    let refused: [(&str, bool); 7] = [
        ("--max-steps", a.max_steps.is_some()),
        ("--constraints", a.constraints.is_some()),
        ("--q0", a.initial.q0.is_some()),
        ("--u0", a.initial.u0.is_some()),
        ("--input", !a.inputs.inputs.is_empty()),
        ("--every", a.every.is_some()),
        ("--interpret", a.interpret),
    ];
    for (option, given) in refused {
        if given {
            problems.push(format!(
                "{option} does not apply to `{}`, a model with cables: it runs generalized-α \
                 (fixed step, or step control with --rtol/--atol) or rk4 (fixed step); its \
                 options are --t-end, --dt, --rtol, --atol, --integrator generalized-alpha|rk4, \
                 --rho-inf, --param, --csv and --json",
                checked.system.name
            ));
        }
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
    let run = crate::ancf::CableRun {
        integrator,
        t_end: a.t_end,
        dt: a.dt,
        rho_inf: a.rho_inf.unwrap_or(1.0),
        control: (a.rtol.is_some() || a.atol.is_some()).then(|| {
            let rtol = a.rtol.unwrap_or(1e-6);
            eom_sim::large::StepControl::new(rtol, a.atol.unwrap_or(rtol))
        }),
        csv: a.csv,
    };
    match crate::ancf::simulate_cmd(checked, &run, a.json) {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => fail(&e),
    }
}

fn simulate(
    opened: &crate::open::Opened,
    vary: &Vary,
    o: &RunOptions,
    json: bool,
    interpret: bool,
) -> ExitCode {
    let inputs = &opened.inputs;
    let g = match crate::open::generate(opened, vary, &Default::default()) {
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
        eom_gen::interpret::simulate_with_inputs(&g.formulation, sys, o, inputs)
            .map_err(|e| Error::Refused(e.to_string()))
    } else {
        crate::compiled::simulate(&sys.name, &g.source, sys.nq(), sys.nu(), o, inputs)
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
        print!("{}", summary(&sys.name, &sys.coordinate_names(), o, &r));
    }
    if r.stop.is_finished() {
        ExitCode::SUCCESS
    } else {
        eprintln!("error: the run stopped before t = {}: {}", o.t_end, r.stop);
        ExitCode::from(EXIT_RUN_STOPPED)
    }
}

/// The human summary of a run.
fn summary(name: &str, coordinates: &[&str], o: &RunOptions, r: &RunReport) -> String {
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
        "  energy {e0:.9} → {e1:.9} J{}",
        energy_change(e0, e1, r.energy_scale)
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

/// The energy change for people: relative to the size of the energies
/// (`|T| + |V|`, the larger at the start and at the end), which is
/// meaningful when the total is near zero; absolute when they are all zero.
fn energy_change(e0: f64, e1: f64, scale: f64) -> String {
    let change = (e1 - e0).abs();
    if !change.is_finite() {
        String::new()
    } else if scale.is_finite() && scale > 0.0 {
        format!(
            ", change {change:.1e} J = {:.1e} of |T| + |V| ({scale:.3e} J)",
            change / scale
        )
    } else {
        format!(", change {change:.1e} J")
    }
}
