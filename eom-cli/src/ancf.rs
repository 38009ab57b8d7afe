//! Models with ANCF chains (`cables:` in the model file): the element
//! kernels are compiled into `eom-sim` (feature `cables`) once, so nothing
//! is generated or compiled per model.
//!
//! - `simulate`: cables alone run as one structure of every cable
//!   (generalized-α, fixed step or step control, or RK4); cables hung at
//!   markers of rigid bodies (`start_at`, `end_at`) as one mixed model
//!   (`eom_sim::large::mixed`: the rigid part's generated functions
//!   through the interpreter, the attachments as constraints, index-3
//!   generalized-α). Both through `eom_sim::large::simulate` into the
//!   common `RunReport`, summary (`crate::report`) and CSV (`t`, the rigid
//!   coordinates and speeds, every node of every cable, the energy).
//! - `solve-static`: Newton with load stepping, per chain, with the
//!   residual history of every load step; a mixed model's equilibrium by
//!   Newton on the KKT system.
//!
//! Rigid bodies beside cables none of which hangs at them are refused.

use crate::error::Error;
use crate::report::{Setting, finish};
use eom_gen::Checked;
use eom_sim::Integrator;
use eom_sim::RunError;
use eom_sim::large::{
    AlphaOptions, ElementRun, MixedAlpha, MixedStaticError, StaticOptions, equilibrium_mixed,
    equilibrium_structure, simulate_mixed, simulate_structure,
};
use serde_json::json;
use std::process::ExitCode;

/// True if the model has ANCF chains.
pub fn has_cables(checked: &Checked) -> bool {
    !checked.system.cables.is_empty()
}

/// The rigid part of a model whose cables hang at its markers, formulated
/// and checked for the element runtime.
fn rigid_part(sys: &eom_gen::system::System) -> Result<eom_gen::mech::Formulation, String> {
    let f = eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested())
        .map_err(|e| format!("model `{}`: {e}", sys.name))?;
    eom_gen::cables::check_rigid(sys, &f).map_err(|e| e.to_string())?;
    Ok(f)
}

/// The mixed model of `sys`: every cable in one structure, the rigid part
/// `f` interpreted.
fn mixed_model<'a>(
    sys: &'a eom_gen::system::System,
    f: &'a eom_gen::mech::Formulation,
) -> Result<eom_gen::cables::Mixed<'a>, String> {
    eom_gen::cables::mixed(sys, eom_gen::cables::interpreted_rigid(f, sys))
        .map_err(|e| e.to_string())
}

/// The refusal of a mixed static solve, with the rigid coordinates named.
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

/// `eom-gen solve-static`: cables alone as one structure of every cable
/// (Newton with load stepping), cables hung at markers as one mixed model
/// (Newton on the KKT system, with the equilibrium's stability), both
/// into the one `StaticReport`.
pub fn solve_static_cmd(
    checked: &Checked,
    opts: &StaticOptions,
    json_out: bool,
) -> Result<String, Error> {
    let sys = &checked.system;
    if sys.cables.is_empty() {
        return Err(Error::Refused(format!(
            "model `{}` has no cables: solve-static solves the equilibrium of ANCF chains (`cables:`)",
            sys.name
        )));
    }
    let refused = |e: eom_gen::cables::CableError| Error::Refused(e.to_string());
    let coordinates = sys.coordinate_names();
    let report = if eom_gen::cables::has_rigid_part(sys) {
        let f = rigid_part(sys).map_err(Error::Refused)?;
        let mixed = mixed_model(sys, &f).map_err(Error::Refused)?;
        let (q0, _) = eom_gen::cables::rigid_start(sys, &f).map_err(refused)?;
        let contacts = eom_gen::cables::node_contacts(sys, &mixed.cables);
        equilibrium_mixed(&mixed.model, &mixed.cables, &contacts, &q0, opts)
            .map_err(|e| refusal(&sys.name, &coordinates, &e))?
    } else {
        let (built, cables) = eom_gen::cables::structure(sys).map_err(refused)?;
        let contacts = eom_gen::cables::node_contacts(sys, &cables);
        equilibrium_structure(&built.model, &cables, &contacts, opts)
            .map_err(|e| Error::Refused(format!("model `{}`: {e}", sys.name)))?
    };
    if json_out {
        serde_json::to_string(&report)
            .map(|t| t + "\n")
            .map_err(|e| Error::Refused(format!("cannot encode the report: {e}")))
    } else {
        Ok(crate::report::static_summary(
            &sys.name,
            &coordinates,
            &report,
        ))
    }
}

/// Refuses a linearisation about an equilibrium with a contact closed (a
/// gap at or below `GAP_TOL`), as for rigid models: a sustained contact's
/// constraint is not part of it (and the equilibrium, found without the
/// contacts, may go through one).
fn closed(model: &str, gaps: Vec<(String, f64)>) -> Result<(), Error> {
    let closed: Vec<(String, f64)> = gaps
        .into_iter()
        .filter(|(_, g)| g.is_nan() || *g <= eom_sim::run::GAP_TOL)
        .collect();
    if closed.is_empty() {
        return Ok(());
    }
    Err(Error::Refused(
        eom_gen::linearize::LinearizeError::ClosedContacts {
            model: model.to_string(),
            rows: closed,
        }
        .to_string(),
    ))
}

/// `eom-gen linearize` on a model with cables: about the static
/// equilibrium (as `solve-static` finds it, default options), the element
/// runtime's linear equations (`eom_sim::large::second_order`) in minimal
/// coordinates (`eom_gen::linearize::structural`). Returns the
/// linearisation and the state (`q` the structure's free coordinates, then
/// a mixed model's rigid ones; `u` zero).
pub fn linearize_cmd(
    checked: &Checked,
) -> Result<(eom_gen::linearize::Linearization, Vec<f64>, Vec<f64>), Error> {
    use eom_sim::large::{
        State, contact_gaps_mixed, contact_gaps_structure, second_order, solve_static,
        solve_static_mixed,
    };
    let sys = &checked.system;
    let refused = |e: eom_gen::cables::CableError| Error::Refused(e.to_string());
    let dynamics = |e: eom_sim::large::DynamicsError| {
        Error::Refused(format!("model `{}` at its equilibrium: {e}", sys.name))
    };
    let opts = StaticOptions::default();
    let (eq, state, names) = if eom_gen::cables::has_rigid_part(sys) {
        let f = rigid_part(sys).map_err(Error::Refused)?;
        let mixed = mixed_model(sys, &f).map_err(Error::Refused)?;
        let (q0, _) = eom_gen::cables::rigid_start(sys, &f).map_err(refused)?;
        let coordinates = sys.coordinate_names();
        let sol = solve_static_mixed(&mixed.model, 0.0, &q0, &opts)
            .map_err(|e| refusal(&sys.name, &coordinates, &e))?;
        let contacts = eom_gen::cables::node_contacts(sys, &mixed.cables);
        closed(
            &sys.name,
            contact_gaps_mixed(&mixed.model, &contacts, &sol.y),
        )?;
        let n = sol.y.len();
        let state = State {
            t: 0.0,
            q: sol.y,
            v: vec![0.0; n],
        };
        let eq = second_order(&mixed.model, &state).map_err(dynamics)?;
        let rigid = coordinates.len().min(n);
        let names: Vec<String> = (1..=n - rigid)
            .map(|k| format!("y{k}"))
            .chain(coordinates.iter().map(|c| c.to_string()))
            .collect();
        (eq, state, names)
    } else {
        let (built, cables) = eom_gen::cables::structure(sys).map_err(refused)?;
        let sol = solve_static(&built.model, &opts)
            .map_err(|e| Error::Refused(format!("model `{}`: {e}", sys.name)))?;
        let q = built.model.restrict(&sol.q);
        let contacts = eom_gen::cables::node_contacts(sys, &cables);
        closed(
            &sys.name,
            contact_gaps_structure(&built.model, &contacts, &q),
        )?;
        let n = q.len();
        let state = State {
            t: 0.0,
            q,
            v: vec![0.0; n],
        };
        let eq = second_order(&built.model, &state).map_err(dynamics)?;
        (eq, state, (1..=n).map(|k| format!("y{k}")).collect())
    };
    let lin = eom_gen::linearize::structural::linearize(&sys.name, &eq, &state.v, names)
        .map_err(|e| Error::Refused(e.to_string()))?;
    Ok((lin, state.q, state.v))
}

/// `eom-gen simulate` on a model with cables: cables alone run as one
/// structure of every cable, cables hung at markers as one mixed model
/// with the rigid part interpreted; both through the element runtime's
/// run (`eom_sim::large::simulate`), into the common report and CSV.
pub fn simulate_cmd(
    checked: &Checked,
    run: &ElementRun,
    tangent: eom_sim::Jacobian,
    (csv, events_csv): (Option<&str>, Option<&str>),
    json_out: bool,
) -> Result<ExitCode, Error> {
    let sys = &checked.system;
    let refused = |e: eom_gen::cables::CableError| Error::Refused(e.to_string());
    let run_error = |e: RunError| match e {
        RunError::Options(p) => Error::Usage(p),
        other => Error::Refused(format!("model `{}`: {other}", sys.name)),
    };
    // With step control the count is not known ahead: the bar then
    // counts thousandths of the run's time.
    let bar = step_progress(&sys.name, 1000);
    let mut progress = |t: f64| bar.set_position((1000.0 * t / run.t_end) as u64);
    let mut coordinates: Vec<&str> = Vec::new();
    let (report, table) = if eom_gen::cables::has_rigid_part(sys) {
        let f = rigid_part(sys).map_err(Error::Refused)?;
        let mut mixed = mixed_model(sys, &f).map_err(Error::Refused)?;
        mixed.model.set_tangent(tangent);
        let (q0, u0) = eom_gen::cables::rigid_start(sys, &f).map_err(refused)?;
        coordinates = sys.coordinate_names();
        let own = |v: Vec<&str>| v.into_iter().map(str::to_string).collect::<Vec<_>>();
        let (qn, un) = (own(sys.coordinate_names()), own(sys.speed_names()));
        let contacts = eom_gen::cables::node_contacts(sys, &mixed.cables);
        simulate_mixed(
            &mixed.model,
            &mixed.cables,
            &contacts,
            (&q0, &u0),
            (&qn, &un),
            run,
            &mut progress,
        )
    } else {
        let (mut built, cables) = eom_gen::cables::structure(sys).map_err(refused)?;
        built.model.set_tangent(tangent);
        let contacts = eom_gen::cables::node_contacts(sys, &cables);
        simulate_structure(&built.model, &cables, &contacts, run, &mut progress)
    }
    .map_err(run_error)?;
    if let Some(path) = events_csv {
        // The node contacts' rows then the rigid bodies' (the run's
        // order), and the structure's free coordinates (then a rigid
        // part's speeds) as the speeds of the generalised impulse.
        let rows: Vec<String> = sys
            .cable_contacts
            .iter()
            .map(|c| c.name.clone())
            .chain(eom_gen::cables::contact_names(sys))
            .collect();
        let n = report
            .contact_events
            .first()
            .map_or(0, |e| e.generalized_impulse.len());
        let rigid: Vec<&str> = if coordinates.is_empty() {
            Vec::new()
        } else {
            sys.speed_names()
        };
        let ns = n.saturating_sub(rigid.len());
        let speeds: Vec<String> = (1..=ns)
            .map(|k| format!("y{k}"))
            .chain(rigid.iter().map(|s| s.to_string()))
            .collect();
        // With friction at any contact, every row's tangential impulses.
        let rough = sys.cable_contacts.iter().any(|c| c.mu > 0.0)
            || eom_gen::mech::contacts::has_friction(sys);
        eom_sim::run::events_table(&rows, &speeds, &[], rough, &report.contact_events)
            .write(path)
            .map_err(|e| Error::io(path, e))?;
    }
    bar.finish_and_clear();
    if let (Some(path), Some(table)) = (csv, &table) {
        table.write(path).map_err(|e| Error::io(path, e))?;
    }
    let mut detail = match &run.control {
        Some(c) => format!("step control rtol {:e}, atol {:e}", c.rtol, c.atol),
        None => format!("step {:e} s", run.t_end / run.steps() as f64),
    };
    if run.integrator == Integrator::GeneralizedAlpha {
        detail += &format!(", rho_inf {}", run.rho_inf);
    }
    let setting = Setting {
        integrator: run.integrator,
        detail,
        csv,
        events_csv,
    };
    Ok(finish(
        &sys.name,
        &coordinates,
        &setting,
        run.t_end,
        &report,
        json_out,
    ))
}

/// A progress bar over the steps of a run (hidden when stderr is not a
/// terminal).
fn step_progress(label: &str, steps: usize) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(steps as u64);
    let style = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} steps, {elapsed} {msg}",
    )
    .map(|s| s.progress_chars("=> "))
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_prefix(label.to_string());
    bar
}

/// What `eval` and `bench` say of a model with cables: the generated
/// functions are the rigid part's alone (the cables' element kernels are
/// model-independent and assembled at run time), so a note for standard
/// error, and for `eval` the JSON block `cables`: their names, and for
/// cables hung at markers the whole model's consistent accelerations of
/// the rigid coordinates and the mounts' forces at the state, from the
/// same index-3 system that `simulate` starts from (cable straight and at
/// rest as in the model file; a state at which the cable ends are off
/// their markers is refused there, with the reason, under `refused`).
pub fn scope_note(checked: &Checked, what: &str) -> Option<String> {
    let sys = &checked.system;
    if sys.cables.is_empty() {
        return None;
    }
    let names: Vec<String> = sys.cables.iter().map(|c| format!("`{}`", c.name)).collect();
    Some(format!(
        "note: model `{}` has cables ({}): {what} covers the generated functions of the rigid part alone, \
         without the cables' forces; the cables' elements are model-independent kernels \
         (eom_elements) that `simulate` and `solve-static` assemble at run time",
        sys.name,
        names.join(", ")
    ))
}

/// The `cables` block of `eval` (see [`scope_note`]); `None` without
/// cables.
pub fn eval_block(checked: &Checked, q: &[f64], u: &[f64], t: f64) -> Option<serde_json::Value> {
    let sys = &checked.system;
    if sys.cables.is_empty() {
        return None;
    }
    let names: Vec<&str> = sys.cables.iter().map(|c| c.name.as_str()).collect();
    let mut block = json!({
        "names": names,
        "scope": "the functions above are the rigid part's alone, without the cables' forces",
    });
    if eom_gen::cables::has_rigid_part(sys) {
        match whole_model(checked, q, u, t) {
            Ok(v) => block["whole_model"] = v,
            Err(e) => block["refused"] = json!(e),
        }
    }
    Some(block)
}

/// The rigid coordinates' accelerations and the mounts' forces of the
/// whole model (rigid part, cables, attachments) at `(q, u, t)`.
fn whole_model(
    checked: &Checked,
    q: &[f64],
    u: &[f64],
    t: f64,
) -> Result<serde_json::Value, String> {
    let sys = &checked.system;
    let f = rigid_part(sys)?;
    let mixed = mixed_model(sys, &f)?;
    let m = &mixed.model;
    let state = m.initial_state(t, q, u);
    let ga = MixedAlpha::new(m, state, AlphaOptions::default())
        .map_err(|e| format!("the whole model at this state: {e}"))?;
    let ns = m.n_structural();
    let mounts: Vec<serde_json::Value> = m
        .attachments()
        .iter()
        .zip(ga.reactions())
        .map(|(a, r)| json!({ "mount": a.name, "force_on_cable": r }))
        .collect();
    Ok(json!({
        "udot": &ga.acceleration()[ns..],
        "mounts": mounts,
        "cable_state": "straight and at rest, as in the model file",
    }))
}
