//! `eom-gen eval`: every generated function at one state, compiled or
//! interpreted, as one JSON object.

use crate::args::{InputArgs, ParamArgs, Vary, parse_list};
use clap::Args;
use eom_gen::functions::{Function, Layout};
use std::process::ExitCode;

/// Evaluate the equations of motion at a state (default: the model's
/// initial state), compiled (built once, cached) or interpreted.
#[derive(Args)]
pub struct EvalArgs {
    /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
    pub model: String,
    /// Positions, comma-separated (default: the model's q0).
    #[arg(long, allow_hyphen_values = true)]
    pub q: Option<String>,
    /// Speeds, comma-separated (default: the model's u0).
    #[arg(long, allow_hyphen_values = true)]
    pub u: Option<String>,
    /// Extra generalised forces, one per speed (default: zero).
    #[arg(long, allow_hyphen_values = true)]
    pub tau: Option<String>,
    /// Time.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub t: f64,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub inputs: InputArgs,
    /// Use the evaluator instead of compiled code (no compiler needed).
    #[arg(long)]
    pub interpret: bool,
    /// Print one JSON object (the only format).
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &EvalArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let vary = match Vary::parse_or_exit(&a.params.params, &a.inputs.inputs) {
        Ok(v) => v,
        Err(code) => return code,
    };
    let opened = match crate::open::open(&a.model, urdf, &vary) {
        Ok(o) => o,
        Err(code) => return code,
    };
    let g = match crate::open::generate(&opened, &vary, &Default::default()) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let inputs = &opened.inputs;
    let sys = &g.checked.system;
    let (nq, nu) = (sys.nq(), sys.nu());
    let parsed = (|| -> Result<_, String> {
        Ok((
            parse_list("q", a.q.as_deref(), nq, sys.q0())?,
            parse_list("u", a.u.as_deref(), nu, sys.u0())?,
            parse_list("tau", a.tau.as_deref(), nu, vec![0.0; nu])?,
        ))
    })();
    let (q, u, tau) = match parsed {
        Ok(v) => v,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let t = a.t;
    let result = if a.interpret {
        let point = eom_gen::interpret::Point {
            sys,
            q: &q,
            u: &u,
            udot: &[],
            tau: &tau,
            inputs,
            params: &[],
            multipliers: &[],
            t,
        };
        Ok(eom_gen::interpret::evaluate(&g.formulation, &point))
    } else {
        crate::compiled::evaluate(&sys.name, &g.source, &q, &u, &tau, t, inputs)
    };
    match result {
        Ok(e) => {
            let mut v = serde_json::json!({
                "coordinate_names": sys.coordinate_names(),
                "speed_names": sys.speed_names(),
                "q": q, "u": u, "t": t,
                "mode": if a.interpret { "interpreted" } else { "compiled" },
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
