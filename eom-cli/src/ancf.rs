//! Models with ANCF chains (`cables:` in the model file, issue #18): the
//! element kernels are compiled into `eom-sim` once, so these commands
//! build each chain at run time (`eom_sim::large::ancf::chain`) and solve
//! it with the large-model runtime; nothing is generated or compiled per
//! model.
//!
//! - `solve-static`: Newton with load stepping, per chain, with the
//!   residual history of every load step.
//! - `simulate` on a model with cables: generalized-α (fixed step `--dt`,
//!   `--rho-inf`) or RK4.
//!
//! A model whose cables hang at markers of its rigid bodies (`start_at`,
//! `end_at`) runs as one mixed model (`eom_sim::large::mixed`): every cable
//! in one structure (those held at no marker too), the rigid part's
//! generated functions through the interpreter, the attachments as
//! constraints, index-3 generalized-α (`rk4` refuses it); `solve-static`
//! solves its equilibrium by Newton on the KKT system
//! (`crate::mixed_static`). Its CSV has, per cable, the first and last
//! node (`CABLE.first.x`, …, `CABLE.last.z`); its JSON, per cable, every
//! node at the end. Rigid bodies beside cables none of which hangs at
//! them are refused.

use crate::error::Error;
use eom_gen::Checked;
use eom_sim::Integrator;
use eom_sim::large::ancf::{Chain, chain};
use eom_sim::large::{
    AlphaOptions, GeneralizedAlpha, MixedAlpha, State, StaticOptions, StepControl, integrate_rk4,
    solve_static,
};
use serde_json::json;
use std::fmt::Write;

/// True if the model has ANCF chains.
pub fn has_cables(checked: &Checked) -> bool {
    !checked.system.cables.is_empty()
}

fn build(checked: &Checked) -> Result<Vec<(String, Chain)>, Error> {
    let sys = &checked.system;
    if sys.cables.is_empty() {
        return Err(Error::Refused(format!(
            "model `{}` has no cables: solve-static solves the equilibrium of ANCF chains (`cables:`)",
            sys.name
        )));
    }
    if eom_gen::cables::has_mounts(sys) {
        return Err(Error::Refused(format!(
            "model `{}` hangs cables at rigid bodies: it runs as one mixed model, not chain by chain",
            sys.name
        )));
    }
    if sys.bodies.len() > 1 {
        return Err(Error::Refused(format!(
            "model `{}` mixes rigid bodies and cables that do not hang at them: \
             hold a cable end at a marker (`start_at`/`end_at`), or solve the cables in a model of their own",
            sys.name
        )));
    }
    sys.cables
        .iter()
        .map(|c| {
            chain(&eom_gen::cables::chain_spec(c))
                .map(|mut ch| {
                    if c.distributed_load != [0.0; 3] {
                        ch.model.add_distributed_load(c.distributed_load);
                    }
                    for &(node, f) in &c.node_forces {
                        for (k, &fk) in f.iter().enumerate().take(ch.dim) {
                            let i = ch.position_index(node, k);
                            ch.model.add_point_load(i, fk);
                        }
                    }
                    (c.name.clone(), ch)
                })
                .map_err(|e| Error::Refused(format!("cable `{}`: {e}", c.name)))
        })
        .collect()
}

/// `eom-gen solve-static` on cables that hang at no rigid body (a mixed
/// model is `crate::mixed_static`'s).
pub fn solve_static_cmd(
    checked: &Checked,
    opts: &StaticOptions,
    json_out: bool,
) -> Result<String, Error> {
    let chains = build(checked)?;
    let mut text = String::new();
    let mut report = Vec::new();
    for (name, ch) in &chains {
        let m = &ch.model;
        let start = std::time::Instant::now();
        let sol =
            solve_static(m, opts).map_err(|e| Error::Refused(format!("cable `{name}`: {e}")))?;
        let cpu = start.elapsed().as_secs_f64();
        let tip0 = ch.node_position(m.q0(), ch.nodes - 1);
        let tip = ch.node_position(&sol.q, ch.nodes - 1);
        let disp = [tip[0] - tip0[0], tip[1] - tip0[1], tip[2] - tip0[2]];
        let _ = writeln!(
            text,
            "cable {name}: {} × {}, {} coordinates ({} free), {} load steps ({} halved), {} factorisations, {:.3} ms",
            ch.nodes - 1,
            ch.kernel,
            m.n_full(),
            m.n_free(),
            sol.steps.len(),
            sol.cuts,
            sol.factorizations,
            cpu * 1e3
        );
        write_load_steps(&mut text, &sol.steps);
        let _ = writeln!(
            text,
            "  end node at ({:.9}, {:.9}, {:.9}) m, displaced by ({:.9}, {:.9}, {:.9}) m",
            tip[0], tip[1], tip[2], disp[0], disp[1], disp[2]
        );
        report.push(json!({
            "cable": name,
            "element": ch.kernel.name(),
            "elements": ch.nodes - 1,
            "coordinates": m.n_full(),
            "free": m.n_free(),
            "cuts": sol.cuts,
            "factorizations": sol.factorizations,
            "cpu_seconds": cpu,
            "steps": sol.steps.iter().map(|s| json!({
                "lambda": s.lambda,
                "iterations": s.iterations(),
                "residuals": s.residuals,
            })).collect::<Vec<_>>(),
            "end_position": tip,
            "end_displacement": disp,
            "nodes": (0..ch.nodes).map(|j| ch.node_position(&sol.q, j)).collect::<Vec<_>>(),
        }));
    }
    if json_out {
        Ok(format!(
            "{}\n",
            json!({ "model": checked.system.name, "cables": report })
        ))
    } else {
        Ok(text)
    }
}

/// How `simulate` integrates a model with cables.
#[derive(Clone, Debug)]
pub struct CableRun {
    /// [`Integrator::GeneralizedAlpha`] or [`Integrator::Rk4`].
    pub integrator: Integrator,
    /// End time, s.
    pub t_end: f64,
    /// Step, s.
    pub dt: f64,
    /// Spectral radius at infinity (generalized-α).
    pub rho_inf: f64,
    /// Step-size control of generalized-α (`--rtol`/`--atol`); `None` for
    /// the fixed step `dt` (with control, `dt` is the first step).
    pub control: Option<StepControl>,
    /// CSV of `t`, end-node positions and energy per cable.
    pub csv: Option<String>,
}

/// The problems of `run`'s settings; `true` for the explicit method.
fn run_problems(run: &CableRun) -> Result<bool, Error> {
    let mut problems = Vec::new();
    if !(run.t_end > 0.0 && run.t_end.is_finite()) {
        problems.push(format!("--t-end must be positive, not {}", run.t_end));
    }
    if !(run.dt > 0.0 && run.dt.is_finite()) {
        problems.push(format!("--dt must be positive, not {}", run.dt));
    }
    if !(0.0..=1.0).contains(&run.rho_inf) {
        problems.push(format!("--rho-inf lies in [0, 1], not {}", run.rho_inf));
    }
    if let Some(c) = &run.control
        && !(c.rtol > 0.0 && c.atol > 0.0 && c.rtol.is_finite() && c.atol.is_finite())
    {
        problems.push(format!(
            "--rtol and --atol must be positive, not {} and {}",
            c.rtol, c.atol
        ));
    }
    let explicit = match run.integrator {
        Integrator::GeneralizedAlpha => false,
        Integrator::Rk4 if run.control.is_some() => {
            problems.push(
                "--rtol/--atol control generalized-α's step; rk4 on cables takes the fixed step --dt"
                    .to_string(),
            );
            true
        }
        Integrator::Rk4 => true,
        other => {
            problems.push(format!(
                "integrator `{other}` does not run ANCF models: use one of {}",
                Integrator::names_where(Integrator::runs_element_models)
            ));
            false
        }
    };
    if !problems.is_empty() {
        return Err(Error::Usage(problems));
    }
    Ok(explicit)
}

/// How a run stepped: "N steps of h s" or "N steps (R rejected), step
/// control rtol …, atol …".
fn stepping(run: &CableRun, steps: usize, stats: &eom_sim::large::DynamicsStats) -> String {
    match &run.control {
        Some(c) => format!(
            "{} steps ({} rejected), step control rtol {:e}, atol {:e}",
            stats.steps, stats.rejected, c.rtol, c.atol
        ),
        None => format!("{} steps of {:e} s", stats.steps, run.t_end / steps as f64),
    }
}

/// `eom-gen simulate` on a model with cables.
pub fn simulate_cmd(checked: &Checked, run: &CableRun, json_out: bool) -> Result<String, Error> {
    if eom_gen::cables::has_mounts(&checked.system) {
        return simulate_mixed(checked, run, json_out);
    }
    let chains = build(checked)?;
    let explicit = run_problems(run)?;
    if chains.len() > 1 && run.control.is_some() && run.csv.is_some() {
        // Each cable of a cable-only model is its own run: with step
        // control their steps differ and share no rows.
        return Err(Error::Usage(vec![format!(
            "--csv with --rtol/--atol on `{}`: its {} cables are separate runs whose controlled \
             steps differ, so they share no table; give a fixed step (--dt, without --rtol/--atol) \
             for the CSV",
            checked.system.name,
            chains.len()
        )]));
    }
    let steps = (run.t_end / run.dt).round().max(1.0) as usize;
    let mut text = String::new();
    let mut report = Vec::new();
    let mut csv = String::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    for (name, ch) in &chains {
        let m = &ch.model;
        let n = m.n_free();
        let state = State {
            t: 0.0,
            q: m.restrict(m.q0()),
            v: vec![0.0; n],
        };
        let e0 = m.energy(m.q0(), &state.v);
        let mut rows = Vec::new();
        // Every node's position, then the energy; the first row is the
        // start, t = 0.
        let mut record = |s: &State, q: &[f64]| {
            if run.csv.is_some() {
                let mut row = vec![s.t];
                for node in 0..ch.nodes {
                    row.extend(ch.node_position(q, node));
                }
                row.push(m.energy(q, &s.v));
                rows.push(row);
            }
        };
        record(&state, m.q0());
        let start = std::time::Instant::now();
        let (end, stats) = if explicit {
            integrate_rk4(m, state, run.t_end, steps, &mut record)
                .map_err(|e| Error::Refused(format!("cable `{name}`: {e}")))?
        } else {
            let opts = AlphaOptions {
                h: run.t_end / steps as f64,
                rho_inf: run.rho_inf,
                control: run.control,
                ..AlphaOptions::default()
            };
            let mut ga = GeneralizedAlpha::new(m, state, opts)
                .map_err(|e| Error::Refused(format!("cable `{name}`: {e}")))?;
            ga.run_to(run.t_end, &mut record)
                .map_err(|e| Error::Refused(format!("cable `{name}`: {e}")))?;
            (ga.state().clone(), ga.stats.clone())
        };
        let cpu = start.elapsed().as_secs_f64();
        let q = m.expand(&end.q);
        let tip = ch.node_position(&q, ch.nodes - 1);
        let e1 = m.energy(&q, &end.v);
        let _ = writeln!(
            text,
            "cable {name}: {} × {}, {} free coordinates, {} to t = {} in {}, {:.3} s CPU",
            ch.nodes - 1,
            ch.kernel,
            n,
            if explicit { "rk4" } else { "generalized-alpha" },
            end.t,
            stepping(run, steps, &stats),
            cpu
        );
        let _ = writeln!(
            text,
            "  {} Newton iterations, {} factorisations, {} force evaluations",
            stats.newton_iterations, stats.factorizations, stats.force_evaluations
        );
        let _ = writeln!(
            text,
            "  end node at ({:.9}, {:.9}, {:.9}) m; energy {e0:.9e} → {e1:.9e} J (change {:.3e})",
            tip[0],
            tip[1],
            tip[2],
            e1 - e0
        );
        report.push(json!({
            "cable": name,
            "element": ch.kernel.name(),
            "elements": ch.nodes - 1,
            "integrator": if explicit { "rk4" } else { "generalized-alpha" },
            "t": end.t,
            "steps": stats.steps,
            "rejected": stats.rejected,
            "newton_iterations": stats.newton_iterations,
            "factorizations": stats.factorizations,
            "force_evaluations": stats.force_evaluations,
            "cpu_seconds": cpu,
            "end_position": tip,
            "energy_start": e0,
            "energy_end": e1,
        }));
        if columns.is_empty() {
            columns = rows;
        } else {
            for (c, r) in columns.iter_mut().zip(rows) {
                c.extend_from_slice(&r[1..]);
            }
        }
    }
    if let Some(path) = &run.csv {
        let names: Vec<String> = chains
            .iter()
            .flat_map(|(n, ch)| {
                (0..ch.nodes)
                    .flat_map(move |k| ["x", "y", "z"].map(|c| format!("{n}.node{k}.{c}")))
                    .chain([format!("{n}.energy")])
            })
            .collect();
        let _ = writeln!(csv, "t,{}", names.join(","));
        for r in &columns {
            let line: Vec<String> = r.iter().map(|v| format!("{v:e}")).collect();
            let _ = writeln!(csv, "{}", line.join(","));
        }
        std::fs::write(path, csv).map_err(|e| Error::io(path, e))?;
    }
    if json_out {
        Ok(format!(
            "{}\n",
            json!({ "model": checked.system.name, "cables": report })
        ))
    } else {
        Ok(text)
    }
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

/// `simulate` on a model whose cables hang at markers of its rigid
/// bodies: the rigid part interpreted, index-3 generalized-α.
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
    if eom_gen::cables::has_mounts(sys) {
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
    let f = eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested())
        .map_err(|e| format!("model `{}`: {e}", sys.name))?;
    eom_gen::cables::check_rigid(sys, &f).map_err(|e| e.to_string())?;
    let mixed = eom_gen::cables::mixed(sys, eom_gen::cables::interpreted_rigid(&f, sys))
        .map_err(|e| e.to_string())?;
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

fn simulate_mixed(checked: &Checked, run: &CableRun, json_out: bool) -> Result<String, Error> {
    let sys = &checked.system;
    if run_problems(run)? {
        return Err(Error::Refused(format!(
            "model `{}` hangs cables at rigid bodies: the attachments are constraints (an index-3 differential-algebraic system), which rk4 does not solve; use `--integrator generalized-alpha`",
            sys.name
        )));
    }
    let f = eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested())
        .map_err(|e| Error::Refused(format!("model `{}`: {e}", sys.name)))?;
    eom_gen::cables::check_rigid(sys, &f).map_err(|e| Error::Refused(e.to_string()))?;
    let mixed = eom_gen::cables::mixed(sys, eom_gen::cables::interpreted_rigid(&f, sys))
        .map_err(|e| Error::Refused(e.to_string()))?;
    let m = &mixed.model;
    let (q0, u0) =
        eom_gen::cables::rigid_start(sys, &f).map_err(|e| Error::Refused(e.to_string()))?;
    let state = m.initial_state(0.0, &q0, &u0);
    let e0 = m.energy(&state);
    let steps = (run.t_end / run.dt).round().max(1.0) as usize;
    let opts = AlphaOptions {
        h: run.t_end / steps as f64,
        rho_inf: run.rho_inf,
        control: run.control,
        ..AlphaOptions::default()
    };
    let refused =
        |e: eom_sim::large::DynamicsError| Error::Refused(format!("model `{}`: {e}", sys.name));
    let start = std::time::Instant::now();
    let mut ga = MixedAlpha::new(m, state, opts).map_err(refused)?;
    // With step control the count is not known ahead: the bar then
    // counts thousandths of the run's time.
    let (bar, per_time) = match run.control {
        Some(_) => (step_progress(&sys.name, 1000), true),
        None => (step_progress(&sys.name, steps), false),
    };
    let ns = m.n_structural();
    let cables = &mixed.cables;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut record = |s: &State, q: &[f64]| {
        if run.csv.is_some() {
            let mut row = vec![s.t];
            row.extend_from_slice(&s.q[ns..]);
            for c in cables {
                for node in [0, c.nodes - 1] {
                    row.extend(c.node_position(q, node));
                }
            }
            row.push(m.energy(s));
            rows.push(row);
        }
    };
    // The first row is the start, t = 0.
    record(ga.state(), &m.structural_full(&ga.state().q));
    let result = ga.run_to(run.t_end, |s, q| {
        if per_time {
            bar.set_position((1000.0 * s.t / run.t_end) as u64);
        } else {
            bar.inc(1);
        }
        record(s, q);
    });
    bar.finish_and_clear();
    result.map_err(refused)?;
    let cpu = start.elapsed().as_secs_f64();
    let end = ga.state().clone();
    let q_full = m.structural_full(&end.q);
    let e1 = m.energy(&end);
    let stats = &ga.stats;
    let coords: Vec<&str> = sys.coordinate_names();
    let rigid_q = &end.q[ns..];
    let reactions = ga.reactions();
    let names: Vec<String> = m.attachments().iter().map(|a| a.name.clone()).collect();
    let mut text = String::new();
    let described: Vec<String> = cables
        .iter()
        .map(|c| format!("{}: {} × {}", c.name, c.nodes - 1, c.kernel))
        .collect();
    let _ = writeln!(
        text,
        "model {}: rigid part of {} coordinates ({}) + {} {} ({}), {} unknowns, {} constraint equations",
        sys.name,
        rigid_q.len(),
        coords.join(", "),
        cables.len(),
        if cables.len() == 1 { "cable" } else { "cables" },
        described.join("; "),
        m.n(),
        m.n_constraints()
    );
    let own = m.rigid().constraint_names();
    if !own.is_empty() {
        let _ = writeln!(
            text,
            "  the rigid part's own equations ({}) held with the attachments; their largest |Φ| at the end {:.3e}",
            own.join(", "),
            m.constraint_residual(end.t, &end.q)[m.rigid_constraint_rows()]
                .iter()
                .fold(0.0_f64, |a, x| a.max(x.abs()))
        );
    }
    let _ = writeln!(
        text,
        "  generalized-alpha (index 3, rho_inf = {}) to t = {} in {}, {:.3} s wall",
        run.rho_inf,
        end.t,
        stepping(run, steps, stats),
        cpu
    );
    let _ = writeln!(
        text,
        "  {} Newton iterations, {} factorisations, {} force evaluations",
        stats.newton_iterations, stats.factorizations, stats.force_evaluations
    );
    let cable_report = write_mixed_state(
        &mut text, &coords, rigid_q, cables, &q_full, &names, &reactions,
    );
    let _ = writeln!(
        text,
        "  energy {e0:.9e} → {e1:.9e} J (change {:.3e}); largest constraint residual |Φ|∞ {:.3e}",
        e1 - e0,
        stats.max_constraint_residual
    );
    if let Some(path) = &run.csv {
        let mut csv = String::new();
        let mut header = vec!["t".to_string()];
        header.extend(coords.iter().map(|c| c.to_string()));
        for c in cables {
            for node in ["first", "last"] {
                header.extend(["x", "y", "z"].map(|k| format!("{}.{node}.{k}", c.name)));
            }
        }
        header.push("energy".into());
        let _ = writeln!(csv, "{}", header.join(","));
        for r in &rows {
            let line: Vec<String> = r.iter().map(|v| format!("{v:e}")).collect();
            let _ = writeln!(csv, "{}", line.join(","));
        }
        std::fs::write(path, csv).map_err(|e| Error::io(path, e))?;
    }
    if json_out {
        Ok(format!(
            "{}\n",
            json!({
                "model": sys.name,
                "cables": cable_report,
                "integrator": "generalized-alpha",
                "t": end.t,
                "steps": stats.steps,
                "rejected": stats.rejected,
                "newton_iterations": stats.newton_iterations,
                "factorizations": stats.factorizations,
                "force_evaluations": stats.force_evaluations,
                "wall_seconds": cpu,
                "coordinates": coords,
                "q": rigid_q,
                "attachments": names,
                "reactions": reactions,
                "energy_start": e0,
                "energy_end": e1,
                "max_constraint_residual": stats.max_constraint_residual,
            })
        ))
    } else {
        Ok(text)
    }
}

/// The report lines of a static solve's load steps: load factor,
/// iterations, residual history.
pub fn write_load_steps(text: &mut String, steps: &[eom_sim::large::LoadStep]) {
    for s in steps {
        let _ = writeln!(
            text,
            "  λ = {:<8.4} {:>2} iterations, |r|∞: {}",
            s.lambda,
            s.iterations(),
            s.residuals
                .iter()
                .map(|r| format!("{r:.2e}"))
                .collect::<Vec<_>>()
                .join(" → ")
        );
    }
}

/// The state of a mixed model in the report of `simulate` and
/// `solve-static`: the rigid coordinates, each cable's end nodes and the
/// force of each marker on its cable end; returns the JSON `cables`
/// array (per cable its name, element, element count, first, last and
/// every node).
pub fn write_mixed_state(
    text: &mut String,
    coords: &[&str],
    rigid_q: &[f64],
    cables: &[eom_gen::cables::MixedCable],
    q_full: &[f64],
    mounts: &[String],
    reactions: &[[f64; 3]],
) -> Vec<serde_json::Value> {
    let qs: Vec<String> = coords
        .iter()
        .zip(rigid_q)
        .map(|(n, v)| format!("{n} = {v:.9}"))
        .collect();
    if !qs.is_empty() {
        let _ = writeln!(text, "  rigid part: {}", qs.join(", "));
    }
    let mut report = Vec::new();
    for c in cables {
        let nodes: Vec<[f64; 3]> = (0..c.nodes).map(|j| c.node_position(q_full, j)).collect();
        let (first, last) = (nodes[0], nodes[c.nodes - 1]);
        let _ = writeln!(
            text,
            "  cable {} nodes: first at ({:.9}, {:.9}, {:.9}) m, last at ({:.9}, {:.9}, {:.9}) m",
            c.name, first[0], first[1], first[2], last[0], last[1], last[2]
        );
        report.push(json!({
            "cable": c.name,
            "element": c.kernel,
            "elements": c.nodes - 1,
            "first_node": first,
            "last_node": last,
            "nodes": nodes,
        }));
    }
    for (n, f) in mounts.iter().zip(reactions) {
        let _ = writeln!(
            text,
            "  force of the marker on {n}: ({:.6e}, {:.6e}, {:.6e}) N",
            f[0], f[1], f[2]
        );
    }
    report
}
