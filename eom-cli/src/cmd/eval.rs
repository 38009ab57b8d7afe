//! `eom-gen eval`: every generated function at one state, compiled or
//! interpreted, as one JSON object.

use crate::args::{InputArgs, ParamArgs, StateArgs, Vary, parse_list};
use clap::Args;
use eom_gen::functions::{Function, Layout};
use std::process::ExitCode;

/// Evaluate the equations of motion at a state (default: the model's
/// initial state), compiled (built once, cached) or interpreted.
#[derive(Args)]
pub struct EvalArgs {
    /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
    pub model: String,
    #[command(flatten)]
    pub state: StateArgs,
    /// Extra generalised forces, one per speed (default: zero).
    #[arg(long, allow_hyphen_values = true)]
    pub tau: Option<String>,
    /// Accelerations, one per speed, at which inverse dynamics and the
    /// outputs that depend on accelerations (reactions) are evaluated
    /// (default: the model's own, from forward dynamics at the state).
    #[arg(long, allow_hyphen_values = true)]
    pub udot: Option<String>,
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
    if let Some(code) = crate::open::cables_only_refusal(&opened.checked, "eval") {
        return code;
    }
    let g = match crate::open::generate(&opened, &vary, &Default::default()) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let inputs = &opened.inputs;
    let sys = &g.checked.system;
    let (nq, nu) = (sys.nq(), sys.nu());
    // Every malformed list is reported, not only the first.
    let mut problems = Vec::new();
    let mut list = |what: &str, text: Option<&str>, default: Vec<f64>| {
        parse_list(what, text, if what == "q" { nq } else { nu }, default).unwrap_or_else(|e| {
            problems.push(e);
            Vec::new()
        })
    };
    let q = list("q", a.state.q.as_deref(), sys.q0());
    let u = list("u", a.state.u.as_deref(), sys.u0());
    let tau = list("tau", a.tau.as_deref(), vec![0.0; nu]);
    let udot = a
        .udot
        .as_deref()
        .map(|text| list("udot", Some(text), Vec::new()));
    if !problems.is_empty() {
        return crate::output::fail(&crate::error::Error::Usage(problems));
    }
    let t = a.state.t;
    // Inverse dynamics and the outputs that depend on accelerations
    // (reactions) are evaluated at the model's own accelerations, with its
    // constraint forces, unless given: what `simulate` writes at a state.
    let evaluate = |udot: &[f64], lambda: &[f64]| {
        if a.interpret {
            let point = eom_gen::interpret::Point {
                sys,
                q: &q,
                u: &u,
                udot,
                tau: &tau,
                inputs,
                params: &[],
                multipliers: lambda,
                t,
            };
            Ok(eom_gen::interpret::evaluate(&g.formulation, &point))
        } else {
            let at = eom_sim::Point {
                t,
                q: &q,
                u: &u,
                tau: &tau,
                udot,
                lambda,
            };
            crate::compiled::evaluate(&sys.name, &g.source, &at, inputs)
        }
    };
    let (udot_source, result, multipliers) = match &udot {
        Some(given) => ("given", evaluate(given, &[]), None),
        None => match evaluate(&[], &[]) {
            Ok(first) => match own_accelerations(&first, &tau) {
                Some((udot, lambda)) => {
                    let again = evaluate(&udot, &lambda);
                    (
                        "forward_dynamics",
                        again,
                        (!lambda.is_empty()).then_some(lambda),
                    )
                }
                None => ("forward_dynamics", Ok(first), None),
            },
            Err(e) => ("forward_dynamics", Err(e), None),
        },
    };
    match result {
        Ok(e) => {
            let mut v = serde_json::json!({
                "coordinate_names": sys.coordinate_names(),
                "speed_names": sys.speed_names(),
                "q": q, "u": u, "t": t,
                "mode": if a.interpret { "interpreted" } else { "compiled" },
                "udot_source": udot_source,
            });
            if let Some(lambda) = &multipliers {
                v["multipliers"] = serde_json::json!(lambda);
            }
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

/// The model's own accelerations at an evaluation: `M u̇ = τ − b + Jᵀλ`
/// with `J u̇ = γ` for models with constraints (the multipliers `λ` as the
/// runtime solves them), `M u̇ = τ − b` without; `None` where the mass
/// matrix is not positive definite or a function is missing (then the
/// generated forward dynamics stand).
fn own_accelerations(
    e: &eom_gen::interpret::Evaluation,
    tau: &[f64],
) -> Option<(Vec<f64>, Vec<f64>)> {
    use eom_sim::constrained::{DMatrix, DVector, accelerations};
    let nu = tau.len();
    let (m, b, c) = (e.get("mass_matrix"), e.get("bias"), e.get("constraints"));
    if m.len() != nu * nu || b.len() != nu {
        return None;
    }
    // Constraints: Φ, Φ̇ and γ (nc each), then J (nc × nu), row-major.
    let nc = c.len() / (3 + nu);
    if nc * (3 + nu) != c.len() {
        return None;
    }
    let m = DMatrix::from_row_slice(nu, nu, m);
    let force = DVector::from_iterator(nu, tau.iter().zip(b).map(|(t, b)| t - b));
    let gamma = DVector::from_row_slice(&c[2 * nc..3 * nc]);
    let jacobian = DMatrix::from_row_slice(nc, nu, &c[3 * nc..]);
    let (udot, lambda, _) = accelerations(&m, &force, &jacobian, &gamma)?;
    let finite = |v: &DVector<f64>| v.iter().all(|x| x.is_finite());
    (finite(&udot) && finite(&lambda))
        .then(|| (udot.as_slice().to_vec(), lambda.as_slice().to_vec()))
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
