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
    #[arg(long)]
    pub t_end: f64,
    /// rk4, dopri5, dop853, radau5, midpoint or euler.
    #[arg(long, default_value = "dopri5")]
    pub integrator: String,
    /// Relative tolerance (adaptive methods).
    #[arg(long, default_value_t = 1e-8, allow_hyphen_values = true)]
    pub rtol: f64,
    /// Absolute tolerance (adaptive methods).
    #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
    pub atol: f64,
    /// Step size (fixed-step methods).
    #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
    pub dt: f64,
    /// Most attempted steps; a run that needs more stops (exit 3).
    #[arg(long, default_value_t = 100_000)]
    pub max_steps: usize,
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
    #[arg(long, default_value = "projection")]
    pub constraints: String,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
    /// Spectral radius at infinity of generalized-α (models with
    /// cables; 1 = no numerical damping).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub rho_inf: f64,
}

/// A run that did not reach its end time: exit status 3.
const EXIT_RUN_STOPPED: u8 = 3;

pub fn run(a: SimulateArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let vary = match Vary::parse_or_exit(&a.params.params, &a.inputs.inputs) {
        Ok(v) => v,
        Err(code) => return code,
    };
    let opened = match crate::open::open(&a.model, urdf, &vary) {
        Ok(o) => o,
        Err(code) => return code,
    };
    // Models with cables run on the large-model runtime.
    if crate::ancf::has_cables(&opened.checked) {
        let checked = &opened.checked;
        eprint!("{}", checked.render_warnings());
        let integrator = if a.integrator == "dopri5" {
            "generalized-alpha".to_string()
        } else {
            a.integrator
        };
        let run = crate::ancf::CableRun {
            integrator,
            t_end: a.t_end,
            dt: a.dt,
            rho_inf: a.rho_inf,
            csv: a.csv,
        };
        return match crate::ancf::simulate_cmd(checked, &run, a.json) {
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
    let (q0, u0) = match (list("q0", a.initial.q0), list("u0", a.initial.u0)) {
        (Ok(q), Ok(u)) => (q, u),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let mut problems = Vec::new();
    let integrator = parse_names(&[a.integrator], &mut problems)
        .pop()
        .unwrap_or(Integrator::Dopri5);
    let constraints = parse_names(&[a.constraints], &mut problems)
        .pop()
        .unwrap_or(Method::Projection);
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    let o = RunOptions {
        integrator,
        rtol: a.rtol,
        atol: a.atol,
        dt: a.dt,
        t_end: a.t_end,
        max_steps: a.max_steps,
        method: constraints,
        q0,
        u0,
        csv: a.csv,
        every: a.every,
        energy_columns: false,
        momentum_columns: false,
    };
    simulate(&opened, &vary, &o, a.json, a.interpret)
}

fn simulate(
    opened: &crate::open::Opened,
    vary: &Vary,
    o: &RunOptions,
    json: bool,
    interpret: bool,
) -> ExitCode {
    let problems = o.problems();
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
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
