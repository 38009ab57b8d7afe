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
//! Rigid bodies and cables in one model are refused for now (the chains
//! would need attachment constraints to the rigid part; see
//! `docs/model-format.md`, "Cables").

use crate::error::Error;
use eom_gen::Checked;
use eom_sim::large::ancf::{Chain, chain};
use eom_sim::large::{
    AlphaOptions, GeneralizedAlpha, State, StaticOptions, integrate_rk4, solve_static,
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
    if sys.bodies.len() > 1 {
        return Err(Error::Refused(format!(
            "model `{}` mixes rigid bodies and cables: attaching ANCF chains to rigid bodies is not supported yet; \
             solve the cables in a model of their own",
            sys.name
        )));
    }
    sys.cables
        .iter()
        .map(|c| {
            chain(&c.chain)
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

/// `eom-gen solve-static`.
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
        for s in &sol.steps {
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
        let _ = writeln!(
            text,
            "  end node at ({:.9}, {:.9}, {:.9}) m, displaced by ({:.9}, {:.9}, {:.9}) m",
            tip[0], tip[1], tip[2], disp[0], disp[1], disp[2]
        );
        report.push(json!({
            "cable": name,
            "element": ch.kernel,
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
    /// `generalized-alpha` or `rk4`.
    pub integrator: String,
    /// End time, s.
    pub t_end: f64,
    /// Step, s.
    pub dt: f64,
    /// Spectral radius at infinity (generalized-α).
    pub rho_inf: f64,
    /// CSV of `t`, end-node positions and energy per cable.
    pub csv: Option<String>,
}

/// `eom-gen simulate` on a model with cables.
pub fn simulate_cmd(checked: &Checked, run: &CableRun, json_out: bool) -> Result<String, Error> {
    let chains = build(checked)?;
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
    let explicit = match run.integrator.as_str() {
        "generalized-alpha" => false,
        "rk4" => true,
        other => {
            problems.push(format!(
                "integrator `{other}` does not run ANCF models: use `generalized-alpha` (implicit, fixed step) or `rk4` (explicit, fixed step)"
            ));
            false
        }
    };
    if !problems.is_empty() {
        return Err(Error::Usage(problems));
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
        let mut record = |s: &State, q: &[f64]| {
            if run.csv.is_some() {
                let p = ch.node_position(q, ch.nodes - 1);
                rows.push(vec![s.t, p[0], p[1], p[2], m.energy(q, &s.v)]);
            }
        };
        let start = std::time::Instant::now();
        let (end, stats) = if explicit {
            integrate_rk4(m, state, run.t_end, steps, &mut record)
                .map_err(|e| Error::Refused(format!("cable `{name}`: {e}")))?
        } else {
            let opts = AlphaOptions {
                h: run.t_end / steps as f64,
                rho_inf: run.rho_inf,
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
            "cable {name}: {} × {}, {} free coordinates, {} to t = {} in {} steps of {:e} s, {:.3} s CPU",
            ch.nodes - 1,
            ch.kernel,
            n,
            if explicit { "rk4" } else { "generalized-alpha" },
            end.t,
            stats.steps,
            run.t_end / steps as f64,
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
            "element": ch.kernel,
            "elements": ch.nodes - 1,
            "integrator": if explicit { "rk4" } else { "generalized-alpha" },
            "t": end.t,
            "steps": stats.steps,
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
            .flat_map(|(n, _)| ["x", "y", "z", "energy"].map(|c| format!("{n}.{c}")))
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
