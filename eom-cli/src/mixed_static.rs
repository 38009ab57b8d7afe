//! `eom-gen solve-static` on a model whose cables hang at markers of its
//! rigid bodies: the mixed model of `eom_gen::cables` (rigid part
//! interpreted) solved by `eom_sim::large::solve_static_mixed` (Newton on
//! the KKT system with load stepping). The report: the residual history
//! of every load step, the rigid coordinates, each cable's end nodes, the
//! force of each marker on its cable end, the constraint residual and the
//! stability of the equilibrium (the smallest eigenvalue of the reduced
//! tangent). A mechanism (a rigid coordinate that nothing holds) and a
//! failed Newton are refused with the reason.

use crate::error::Error;
use eom_gen::Checked;
use eom_sim::large::{MixedStaticError, Stability, StaticOptions, solve_static_mixed};
use serde_json::json;
use std::fmt::Write;

/// The refusal of `e`, with the rigid coordinates named.
fn refusal(model: &str, coords: &[&str], e: &MixedStaticError) -> Error {
    let mut text = e.to_string();
    let mut free = e.free_rigid_coordinates();
    // Longest indices first, so that `1` does not rewrite `10`.
    free.sort_by_key(|f| std::cmp::Reverse(f.0));
    for (i, _) in free {
        if let Some(name) = coords.get(i) {
            text = text.replace(
                &format!("rigid coordinate {i} ("),
                &format!("coordinate `{name}` ("),
            );
        }
    }
    Error::Refused(format!("model `{model}`: {text}"))
}

/// `solve-static` on a mixed model.
pub fn solve_static_mixed_cmd(
    checked: &Checked,
    opts: &StaticOptions,
    json_out: bool,
) -> Result<String, Error> {
    let sys = &checked.system;
    let f = eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested())
        .map_err(|e| Error::Refused(format!("model `{}`: {e}", sys.name)))?;
    eom_gen::cables::check_rigid(sys, &f).map_err(|e| Error::Refused(e.to_string()))?;
    let mixed = eom_gen::cables::mixed(sys, eom_gen::cables::interpreted_rigid(&f, sys))
        .map_err(|e| Error::Refused(e.to_string()))?;
    let m = &mixed.model;
    let coords: Vec<&str> = sys.coordinate_names();
    let (q0, _) =
        eom_gen::cables::rigid_start(sys, &f).map_err(|e| Error::Refused(e.to_string()))?;
    let start = std::time::Instant::now();
    let sol = solve_static_mixed(m, 0.0, &q0, opts).map_err(|e| refusal(&sys.name, &coords, &e))?;
    let cpu = start.elapsed().as_secs_f64();
    let ns = m.n_structural();
    let rigid_q = &sol.y[ns..];
    let reactions = sol.reactions(m);
    let names: Vec<String> = m.attachments().iter().map(|a| a.name.clone()).collect();
    let iterations: usize = sol.steps.iter().map(|s| s.iterations()).sum();
    let mut text = String::new();
    let _ = writeln!(
        text,
        "model {}: rigid part of {} coordinates ({}) + {}: {} unknowns, {} constraint equations",
        sys.name,
        rigid_q.len(),
        coords.join(", "),
        mixed
            .cables
            .iter()
            .map(|c| format!("cable {}: {} × {}", c.name, c.nodes - 1, c.kernel))
            .collect::<Vec<_>>()
            .join(", "),
        m.n(),
        m.n_constraints()
    );
    let _ = writeln!(
        text,
        "  static equilibrium: {} load steps ({} halved), {iterations} Newton iterations ({} regularised: singular tangent), {} factorisations, {:.3} ms",
        sol.steps.len(),
        sol.cuts,
        sol.regularized,
        sol.factorizations,
        cpu * 1e3
    );
    crate::ancf::write_load_steps(&mut text, &sol.steps);
    let cables = crate::ancf::write_mixed_state(
        &mut text,
        &coords,
        rigid_q,
        &mixed.cables,
        &sol.q_full,
        &names,
        &reactions,
    );
    let _ = writeln!(
        text,
        "  constraint residual |Φ|∞ {:.3e}; condition estimate of the KKT matrix {:.2e}",
        sol.constraint_residual, sol.condition
    );
    let _ = writeln!(text, "  {}", sol.stability);
    if json_out {
        let stability = match &sol.stability {
            Stability::Stable { omega2_min } => {
                json!({ "stable": true, "omega2_min": omega2_min })
            }
            Stability::Unstable {
                omega2_min,
                negative,
            } => json!({ "stable": false, "omega2_min": omega2_min, "negative": negative }),
            Stability::NotChecked { reason } => {
                json!({ "stable": null, "reason": reason.to_string() })
            }
        };
        Ok(format!(
            "{}\n",
            json!({
                "model": sys.name,
                "cables": cables,
                "unknowns": m.n(),
                "constraints": m.n_constraints(),
                "cuts": sol.cuts,
                "factorizations": sol.factorizations,
                "regularized": sol.regularized,
                "cpu_seconds": cpu,
                "steps": sol.steps.iter().map(|s| json!({
                    "lambda": s.lambda,
                    "iterations": s.iterations(),
                    "residuals": s.residuals,
                })).collect::<Vec<_>>(),
                "coordinates": coords,
                "q": rigid_q,
                "attachments": names,
                "reactions": reactions,
                "constraint_residual": sol.constraint_residual,
                "condition": sol.condition,
                "stability": stability,
            })
        ))
    } else {
        Ok(text)
    }
}
