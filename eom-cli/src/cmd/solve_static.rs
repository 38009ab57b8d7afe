//! `eom-gen solve-static`: the static equilibrium of a model's cables,
//! alone or hung at rigid bodies (`crate::ancf`).

use crate::args::{ParamArgs, Vary};
use crate::error::Error;
use crate::output::fail;
use clap::Args;
use std::process::ExitCode;

/// Static equilibrium of a model's cables (ANCF chains): Newton with
/// load stepping, the residual of every iteration reported. A model
/// whose cable hangs at markers of rigid bodies is solved as one
/// (rigid coordinates, attachment forces, stability reported). Exit 0
/// in equilibrium; 1 if the model is invalid or the solve refuses (no
/// convergence at the smallest load step, a singular tangent, a
/// mechanism); 2 for bad arguments.
#[derive(Args)]
pub struct SolveStaticArgs {
    /// The model file (`.ron`) with `cables:`.
    pub model: String,
    /// Equal load steps to begin with (halved where Newton fails).
    #[arg(long, default_value_t = 10)]
    pub load_steps: usize,
    /// Newton iterations allowed per load step.
    #[arg(long, default_value_t = 25)]
    pub max_iterations: usize,
    /// Relative residual tolerance: `|r|∞ ≤ rtol · |λ f_ext|∞ + atol`.
    #[arg(long, default_value_t = 1e-10, allow_hyphen_values = true)]
    pub rtol: f64,
    /// Absolute residual tolerance, N.
    #[arg(long, default_value_t = 1e-12, allow_hyphen_values = true)]
    pub atol: f64,
    #[command(flatten)]
    pub params: ParamArgs,
    /// Print one JSON object (with every node's position).
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &SolveStaticArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let vary = match Vary::parse_or_exit(&a.params.params, &[]) {
        Ok(v) => v,
        Err(code) => return code,
    };
    let mut problems = Vec::new();
    if a.load_steps == 0 {
        problems.push("--load-steps must be at least 1".to_string());
    }
    if !(a.rtol >= 0.0 && a.atol >= 0.0) {
        problems.push("--rtol and --atol must not be negative".to_string());
    }
    if !problems.is_empty() {
        return fail(&Error::Usage(problems));
    }
    let checked = match crate::open::open(&a.model, urdf, &vary) {
        Ok(o) => o.checked,
        Err(code) => return code,
    };
    eprint!("{}", checked.render_warnings());
    let opts = eom_sim::large::StaticOptions {
        load_steps: a.load_steps,
        max_iterations: a.max_iterations,
        rtol: a.rtol,
        atol: a.atol,
        ..Default::default()
    };
    match crate::ancf::solve_static_cmd(&checked, &opts, a.json) {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => fail(&e),
    }
}
