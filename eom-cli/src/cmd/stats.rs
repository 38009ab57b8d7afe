//! `eom-gen stats`: operation counts of the generated functions and the
//! generation time.

use crate::args::Vary;
use clap::Args;
use eom_gen::functions::{Function, TABLE};
use std::process::ExitCode;

/// Operation counts of the generated functions and generation time.
#[derive(Args)]
pub struct StatsArgs {
    /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
    pub model: String,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Also formulate and count `forward_dynamics_derivatives` and
    /// `inverse_dynamics_derivatives` (generated only when asked for: a
    /// scene's `functions`, `linearize`).
    #[arg(long)]
    pub derivatives: bool,
}

pub fn run(a: &StatsArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let vary = Vary::default();
    let g = match crate::open::open(&a.model, urdf, &vary)
        .and_then(|o| crate::open::generate(&o, &vary, &Default::default()))
    {
        Ok(g) => g,
        Err(code) => return code,
    };
    let f = &g.formulation;
    // The derivatives, when asked for here and the model does not have them.
    let asked = if a.derivatives
        && (f.program(Function::ForwardDynamicsDerivatives).is_none()
            || f.program(Function::InverseDynamicsDerivatives).is_none())
    {
        let request = g
            .checked
            .request()
            .with(Function::ForwardDynamicsDerivatives)
            .with(Function::InverseDynamicsDerivatives);
        match eom_gen::mech::formulate(&g.checked.system, request) {
            Ok(d) => Some(d),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(1);
            }
        }
    } else {
        None
    };
    let with_derivatives = asked.as_ref().unwrap_or(f);
    let program = |function: Function| match function {
        Function::ForwardDynamicsDerivatives | Function::InverseDynamicsDerivatives => {
            with_derivatives.program(function)
        }
        _ => f.program(function),
    };
    let derivative_candidates: serde_json::Map<String, serde_json::Value> = with_derivatives
        .derivative_candidates
        .iter()
        .map(|(form, c)| (format!("{form:?}"), op_json(c)))
        .collect();
    let id_derivative_candidates: serde_json::Map<String, serde_json::Value> = with_derivatives
        .id_derivative_candidates
        .iter()
        .map(|(form, c)| (format!("{form:?}"), op_json(c)))
        .collect();
    // Every function of the table, `null` where not generated.
    let ops: serde_json::Map<String, serde_json::Value> = TABLE
        .iter()
        .map(|e| {
            let v = program(e.function).map_or(serde_json::Value::Null, |p| op_json(&p.op_count()));
            (e.name.to_string(), v)
        })
        .collect();
    let candidates: serde_json::Map<String, serde_json::Value> = f
        .fd_candidates
        .iter()
        .map(|(form, c)| (format!("{form:?}"), op_json(c)))
        .collect();
    // Functions emitted as loops over a long chain's bodies (`emit`'s
    // default choice, `ChainLoops::pays`).
    let looped: Vec<(Function, &eom_gen::mech::looped::Loop)> = f
        .loops
        .as_ref()
        .map(|cl| {
            cl.loops
                .iter()
                .filter(|(g, _)| {
                    f.program(**g)
                        .is_some_and(|p| cl.pays(**g, p.op_count().total()))
                })
                .map(|(g, l)| (*g, l))
                .collect()
        })
        .unwrap_or_default();
    let loops_json: serde_json::Map<String, serde_json::Value> = looped
        .iter()
        .map(|(g, l)| {
            let v = serde_json::json!({
                "ops_per_call": l.ops(),
                "steps": l.steps(),
                "step_ops": l.code_ops(),
            });
            (g.name().to_string(), v)
        })
        .collect();
    let (cable_text, cable_json) = crate::cable_report::stats(&g.checked.system);
    let v = serde_json::json!({
        "loops": loops_json,
        "name": g.checked.system.name,
        "cables": cable_json,
        "formulation": format!("{}", f.fd_form),
        "forward_dynamics_candidates": candidates,
        "derivative_form": with_derivatives.derivative_form.map(|d| format!("{d:?}")),
        "derivative_candidates": derivative_candidates,
        "id_derivative_form": with_derivatives.id_derivative_form.map(|d| format!("{d:?}")),
        "id_derivative_candidates": id_derivative_candidates,
        "ops": ops,
        "nq": g.checked.system.nq(),
        "nu": g.checked.system.nu(),
        "output_names": f.output_names,
        "generation_ms": f.seconds * 1e3,
        "source_bytes": g.source.len(),
    });
    let sys = &g.checked.system;
    if a.json {
        println!("{v}");
    } else if sys.bodies.len() <= 1 && !sys.cables.is_empty() {
        // Cables alone: nothing is generated per model (a table of zeros
        // would measure nothing); the kernels are what runs.
        println!(
            "{}: cables alone, no rigid part: nothing is generated per model; the cables run these kernels",
            sys.name
        );
        print!("{cable_text}");
    } else {
        print!("{}", table(&g, &program));
        for (g, l) in &looped {
            println!(
                "  {} emitted as loops over the bodies: {} operations per call, {} body steps of {} operations",
                g.name(),
                l.ops(),
                l.steps(),
                l.code_ops()
            );
        }
        for (form, c) in &with_derivatives.derivative_candidates {
            let chosen = with_derivatives.derivative_form == Some(*form);
            println!(
                "  derivatives by {form}: {} operations{}",
                c.total(),
                if chosen { " (kept)" } else { "" }
            );
        }
        for (form, c) in &with_derivatives.id_derivative_candidates {
            let chosen = with_derivatives.id_derivative_form == Some(*form);
            println!(
                "  inverse dynamics derivatives by {form}: {} operations{}",
                c.total(),
                if chosen { " (kept)" } else { "" }
            );
        }
        print!("{cable_text}");
    }
    ExitCode::SUCCESS
}

/// `stats` for people: one row of operation counts per generated function.
fn table<'a>(
    g: &eom_gen::Generated,
    program: &dyn Fn(Function) -> Option<&'a eom_gen::sym::Program>,
) -> String {
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
        "  {:<28} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6} {:>6} {:>8}",
        "function", "add", "mul", "div", "neg", "sqrt", "trig", "other", "total"
    );
    for e in TABLE {
        match program(e.function) {
            Some(p) => {
                let c = p.op_count();
                let _ = writeln!(
                    s,
                    "  {:<28} {:>8} {:>8} {:>6} {:>6} {:>6} {:>6} {:>6} {:>8}",
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
                let _ = writeln!(s, "  {:<28} {:>8}", e.name, "—");
            }
        }
    }
    if !f.output_names.is_empty() {
        let _ = writeln!(s, "  outputs: {}", f.output_names.join(", "));
    }
    s
}

fn op_json(c: &eom_gen::sym::OpCount) -> serde_json::Value {
    serde_json::json!({
        "add": c.adds, "mul": c.muls, "div": c.divs, "neg": c.negs,
        "sqrt": c.sqrts, "trig": c.trig, "other": c.other, "total": c.total(),
    })
}
