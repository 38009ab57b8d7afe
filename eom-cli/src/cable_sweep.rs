//! `eom-gen sweep` on models with cables: cables alone, and cables hung
//! at markers of rigid bodies (mixed), on the large-model runtime
//! (`eom_sim::large::simulate`), into the same results table as the
//! rigid, looped and flexible sweeps (`crate::study::Results`).
//!
//! One formulation: the rigid part of a mixed model is formulated once
//! with the swept parameters kept as symbols (tunable) and interpreted
//! with each case's values, as the rigid sweep does; the cables'
//! element kernels are model-independent (compiled into `eom-sim`), and
//! each case's chains are assembled from its own checked values (section,
//! length, density, loads: every cable datum is tunable, nothing is
//! generated or compiled per case). A case whose values the check
//! refuses, whose rigid part does not assemble, or whose run fails or
//! stops early is a row with `NaN` and the reason; the others run on.
//!
//! Columns: `case`, the swept parameters, `t`, the rigid part's
//! coordinates and speeds (none for cables alone), `energy_start`,
//! `energy_end`, `constraint_residual` (largest `‖Φ‖∞` of the attachments
//! and loops after a step; 0 for cables alone), every node of every cable
//! at the end (`CABLE.nodeK.x/y/z`, as `simulate --csv` names them), then
//! `steps`, `rejected`, `rhs_evals`, `cpu_s`, and `stop`.

use crate::cmd::sweep::{Done, Row, SweepArgs, finish, on_threads, results};
use crate::error::Error;
use crate::output::fail;
use crate::study::Study;
use eom_gen::Checked;
use eom_gen::cables::CableError;
use eom_gen::mech::Formulation;
use eom_gen::system::System;
use eom_sim::large::{ByName, ElementRun, RigidPart, StepControl};
use eom_sim::{Integrator, RunOptions, Stop};
use rayon::prelude::*;
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The run options of a cable sweep from the arguments (generalized-α by
/// default; `--rtol`/`--atol` turn on its step control), and every
/// option that does not apply, as `simulate` on such a model says.
pub fn element_run(a: &SweepArgs, t_end: f64, mixed: bool) -> Result<ElementRun, Vec<String>> {
    let mut problems = Vec::new();
    let integrator = crate::args::parse_names::<Integrator>(
        &[a.integrator
            .clone()
            .unwrap_or_else(|| "generalized-alpha".to_string())],
        &mut problems,
    )
    .pop()
    .unwrap_or(Integrator::GeneralizedAlpha);
    let name = a.model.as_deref().unwrap_or("the model");
    for (option, given) in [
        ("--max-steps", a.max_steps.is_some()),
        ("--constraints", a.constraints.is_some()),
        ("--output", !a.output.is_empty()),
        ("--compiled", a.compiled),
        ("--lanes", a.lanes.is_some()),
        ("--native", a.native),
    ] {
        if given {
            problems.push(format!(
                "{option} does not apply to `{name}`, a model with cables: its sweep runs \
                 generalized-α (fixed step, or step control with --rtol/--atol) or rk4 (cables \
                 alone, fixed step); its options are --param, --samples, --seed, --t-end, --dt, \
                 --rtol, --atol, --integrator generalized-alpha|rk4, --rho-inf, --shard, --jobs \
                 and --out"
            ));
        }
    }
    if !integrator.runs_element_models() {
        problems.push(format!(
            "--integrator {integrator} does not run `{name}`, a model with cables: use \
             generalized-alpha (the default) or rk4 (cables alone)"
        ));
    } else if mixed && integrator == Integrator::Rk4 {
        problems.push(format!(
            "--integrator rk4 does not run `{name}`: its cables hang at rigid bodies, an index-3 \
             system an explicit method does not solve; use generalized-alpha"
        ));
    }
    let run = ElementRun {
        integrator,
        t_end,
        dt: a.dt.unwrap_or(1e-3),
        rho_inf: a.rho_inf.unwrap_or(1.0),
        control: (a.rtol.is_some() || a.atol.is_some()).then(|| {
            let rtol = a.rtol.unwrap_or(1e-6);
            StepControl::new(rtol, a.atol.unwrap_or(rtol))
        }),
        record: false,
        every: None,
    };
    if integrator == Integrator::Rk4 && run.control.is_some() {
        problems.push(
            "--rtol/--atol set generalized-α's step control; rk4 runs a fixed step (--dt)".into(),
        );
    }
    problems.extend(run.problems());
    if problems.is_empty() {
        Ok(run)
    } else {
        Err(problems)
    }
}

/// The study's record of the run options (`study.json`; shards of one
/// study carry the same).
pub fn study_options(run: &ElementRun) -> RunOptions {
    RunOptions {
        integrator: run.integrator,
        rtol: run.control.as_ref().map_or(0.0, |c| c.rtol),
        atol: run.control.as_ref().map_or(0.0, |c| c.atol),
        dt: run.dt,
        t_end: run.t_end,
        ..RunOptions::default()
    }
}

/// What every case shares.
pub struct CableSweep<'a> {
    /// The model as read (each case is checked with its values).
    pub loaded: &'a eom_gen::model::Loaded,
    /// The model checked at its defaults, swept parameters tunable.
    pub shared: &'a Checked,
    /// The rigid part's one formulation (mixed models).
    pub formulation: Option<&'a Formulation>,
    /// The swept parameters' names.
    pub names: &'a [String],
    /// How each case runs.
    pub run: &'a ElementRun,
    /// Node counts per cable (the columns), from the shared model.
    pub nodes: Vec<(String, usize)>,
}

impl<'a> CableSweep<'a> {
    /// The sweep of `shared` (checked, the swept parameters tunable):
    /// the rigid part of a mixed model formulated once, and refused here
    /// when the large runtime cannot join it to its cables (whatever the
    /// values).
    pub fn formulate(shared: &Checked) -> Result<Option<Formulation>, Error> {
        let sys = &shared.system;
        if !eom_gen::cables::has_rigid_part(sys) {
            return Ok(None);
        }
        let f = eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested())
            .map_err(|e| Error::Refused(format!("model `{}`: {e}", sys.name)))?;
        eom_gen::cables::check_rigid(sys, &f).map_err(|e| Error::Refused(e.to_string()))?;
        Ok(Some(f))
    }

    /// The columns of the results.
    pub fn header(&self) -> Vec<String> {
        let sys = &self.shared.system;
        let mut h: Vec<String> = vec!["case".into()];
        h.extend(self.names.iter().cloned());
        h.push("t".into());
        h.extend(sys.coordinate_names().iter().map(|n| n.to_string()));
        h.extend(sys.speed_names().iter().map(|n| n.to_string()));
        h.extend([
            "energy_start".into(),
            "energy_end".into(),
            "constraint_residual".into(),
        ]);
        for (c, n) in &self.nodes {
            for k in 0..*n {
                h.extend(["x", "y", "z"].map(|a| format!("{c}.node{k}.{a}")));
            }
        }
        h.extend(["steps", "rejected", "rhs_evals", "cpu_s"].map(String::from));
        h
    }

    /// Runs case `i` with `values`.
    pub fn case(&self, i: usize, values: &[f64], reformulated: &AtomicUsize) -> Row {
        let width = self.header().len();
        let mut v: Vec<f64> = std::iter::once(i as f64)
            .chain(values.iter().copied())
            .collect();
        let failed = |mut v: Vec<f64>, why: String| {
            v.resize(width, f64::NAN);
            Row {
                values: v,
                stop: format!("failed: {why}"),
            }
        };
        let params: Vec<(String, f64)> = self
            .names
            .iter()
            .cloned()
            .zip(values.iter().copied())
            .collect();
        let checked = match self.loaded.check_with(std::path::Path::new(""), &params) {
            Ok(c) => c,
            Err(r) => {
                let text = r.to_string();
                let why = text
                    .lines()
                    .find(|l| l.contains("error"))
                    .unwrap_or("the model is invalid with these values")
                    .trim();
                return failed(v, why.to_string());
            }
        };
        let sys = &checked.system;
        let shape: Vec<(String, usize)> = sys
            .cables
            .iter()
            .map(|c| (c.name.clone(), c.chain.elements + 1))
            .collect();
        if shape != self.nodes {
            return failed(
                v,
                "these values change the cables' nodes (the table's columns); sweep the \
                 number of elements in studies of their own"
                    .into(),
            );
        }
        let result = match self.formulation {
            None => eom_gen::cables::structure(sys)
                .map_err(|e| e.to_string())
                .and_then(|(built, cables)| {
                    let contacts = eom_gen::cables::node_contacts(sys, &cables);
                    eom_sim::large::simulate_structure(
                        &built.model,
                        &cables,
                        &contacts,
                        self.run,
                        &mut |_| {},
                    )
                    .map(|(r, _)| r)
                    .map_err(|e| e.to_string())
                }),
            Some(shared_f) => {
                // The shared formulation is exact for this case when
                // nothing but the swept parameters differs in what the
                // check computed (as the rigid sweep decides).
                let same = {
                    let b = &self.shared.system;
                    sys.q0() == b.q0()
                        && sys.u0() == b.u0()
                        && sys.parameters.iter().zip(&b.parameters).all(|(x, y)| {
                            self.names.contains(&x.name) || x.value.value == y.value.value
                        })
                };
                let own;
                let (f, rigid_sys, with): (&Formulation, &System, &[(String, f64)]) = if same {
                    (shared_f, &self.shared.system, &params)
                } else {
                    reformulated.fetch_add(1, Ordering::Relaxed);
                    own = match eom_gen::mech::formulate(
                        sys,
                        eom_gen::functions::FunctionSet::all_requested(),
                    ) {
                        Ok(f) => f,
                        Err(e) => return failed(v, e.to_string()),
                    };
                    (&own, sys, &[])
                };
                run_mixed(sys, f, rigid_sys, with, self.run)
            }
        };
        let r = match result {
            Ok(r) => r,
            Err(why) => return failed(v, why),
        };
        v.push(r.t);
        v.extend(&r.q);
        v.extend(&r.u);
        v.extend(r.energy);
        let elements = r.elements.as_ref();
        v.push(elements.map_or(f64::NAN, |e| e.largest_constraint_residual));
        for (name, n) in &self.nodes {
            let cable = elements.and_then(|e| e.cables.iter().find(|c| &c.cable == name));
            for k in 0..*n {
                let p = cable.and_then(|c| c.nodes.get(k)).copied();
                v.extend(p.unwrap_or([f64::NAN; 3]));
            }
        }
        v.extend([
            r.stats.steps as f64,
            r.stats.rejected as f64,
            r.stats.rhs_evals as f64,
            r.cpu_s,
        ]);
        let stop = match r.stop {
            Stop::Finished => "finished".to_string(),
            s => s.to_string(),
        };
        Row { values: v, stop }
    }
}

/// The rigid part `f` of `rigid_sys` interpreted with the values `with`,
/// as the mixed runtime calls it (`eom_gen::cables::interpreted_rigid`
/// with parameters).
fn rigid_with<'a>(
    f: &'a Formulation,
    rigid_sys: &'a System,
    with: &[(String, f64)],
) -> Box<dyn RigidPart + 'a> {
    let interp = eom_gen::interpret::Interpreted::new(f, rigid_sys).with_params(with);
    let len = eom_gen::mech::mounts::mount_rows(rigid_sys) * (1 + rigid_sys.nq());
    Box::new(
        ByName::new(rigid_sys.nu(), len, move |name, at, out| {
            eom_sim::Simulate::evaluate(&interp, name, at, out)
        })
        .with_constraints(
            f.constraint_names.len(),
            eom_gen::cables::holonomic_names(f),
        )
        .with_energy_source(eom_gen::cables::energy_source(rigid_sys))
        .with_contacts(eom_gen::cables::contact_names(rigid_sys))
        .with_frames(rigid_sys.cable_frames().len()),
    )
}

/// One mixed case: the case's cables `sys` joined to the rigid part `f`
/// (of `rigid_sys`, with the values `with`), its start assembled as
/// `eom_gen::cables::rigid_start` does, run by generalized-α.
fn run_mixed(
    sys: &System,
    f: &Formulation,
    rigid_sys: &System,
    with: &[(String, f64)],
    run: &ElementRun,
) -> Result<eom_sim::RunReport, String> {
    let mixed =
        eom_gen::cables::mixed(sys, rigid_with(f, rigid_sys, with)).map_err(|e| e.to_string())?;
    let (q0, u0) = (sys.q0(), sys.u0());
    let (q0, u0) = if f.constraint_names.is_empty() {
        (q0, u0)
    } else {
        let interp = eom_gen::interpret::Interpreted::new(f, rigid_sys).with_params(with);
        let a = eom_sim::constrained::assemble(&interp, &q0, &u0, 0.0);
        if a.residual.is_nan() || a.residual > 1e-10 {
            return Err(CableError::LoopOpen {
                model: sys.name.clone(),
                residual: a.residual,
                constraints: f.constraint_names.clone(),
            }
            .to_string());
        }
        let names = sys.coordinate_names();
        let moved: Vec<(String, f64, f64)> = q0
            .iter()
            .zip(&a.q)
            .zip(&names)
            .filter(|((x, y), _)| (*x - *y).is_nan() || (*x - *y).abs() > 1e-8)
            .map(|((x, y), n)| (n.to_string(), *x, *y))
            .collect();
        if !moved.is_empty() {
            return Err(CableError::StartMoved {
                model: sys.name.clone(),
                constraints: f.constraint_names.clone(),
                moved,
            }
            .to_string());
        }
        (a.q, a.u)
    };
    let own = |v: Vec<&str>| v.into_iter().map(str::to_string).collect::<Vec<_>>();
    let (qn, un) = (own(sys.coordinate_names()), own(sys.speed_names()));
    let contacts = eom_gen::cables::node_contacts(sys, &mixed.cables);
    eom_sim::large::simulate_mixed(
        &mixed.model,
        &mixed.cables,
        &contacts,
        (&q0, &u0),
        (&qn, &un),
        run,
        &mut |_| {},
    )
    .map(|(r, _)| r)
    .map_err(|e| e.to_string())
}

/// What the sweep of a cable model needs from `cmd::sweep`.
pub struct Plan<'a> {
    /// The model file as given.
    pub model: &'a str,
    /// The model checked at its defaults.
    pub checked: &'a Checked,
    /// The URDF options (to read the model again per case).
    pub urdf: &'a eom_gen::urdf::Options,
    /// The swept parameters' names.
    pub names: &'a [String],
    /// Every case's values.
    pub all: &'a [Vec<f64>],
    /// The cases of this shard.
    pub indices: &'a [usize],
    /// The end time.
    pub t_end: f64,
}

/// `eom-gen sweep` on a model with cables (see the module).
pub fn run(a: &SweepArgs, plan: &Plan<'_>) -> ExitCode {
    let sys = &plan.checked.system;
    let run = match element_run(a, plan.t_end, eom_gen::cables::has_rigid_part(sys)) {
        Ok(r) => r,
        Err(p) => return fail(&Error::Usage(p)),
    };
    let mut shared = plan.checked.clone();
    for p in &mut shared.system.parameters {
        if plan.names.contains(&p.name) {
            p.tunable = true;
        }
    }
    let formulation = match CableSweep::formulate(&shared) {
        Ok(f) => f,
        Err(e) => return fail(&e),
    };
    let loaded = match eom_gen::model::load_with(plan.model, plan.urdf) {
        Ok(l) => l,
        Err(r) => {
            eprint!("{r}");
            return ExitCode::from(1);
        }
    };
    if let Err(code) = crate::output::create_out_dir(&a.out) {
        return code;
    }
    eprint!("{}", plan.checked.render_warnings());
    let ctx = CableSweep {
        loaded: &loaded,
        shared: &shared,
        formulation: formulation.as_ref(),
        names: plan.names,
        run: &run,
        nodes: sys
            .cables
            .iter()
            .map(|c| (c.name.clone(), c.chain.elements + 1))
            .collect(),
    };
    let study = Study {
        model: plan.model.to_string(),
        params: a.params.clone(),
        samples: a.samples,
        seed: a.seed.unwrap_or(0),
        run: study_options(&run),
        outputs: Vec::new(),
        cases: plan.all.len(),
        rho_inf: Some(run.rho_inf),
    };
    let bar = crate::cmd::sweep::progress(plan.indices.len(), &sys.name);
    let reformulated = AtomicUsize::new(0);
    let started = std::time::Instant::now();
    let rows = on_threads(a.jobs, || {
        plan.indices
            .par_iter()
            .map(|&i| {
                let row = ctx.case(i, &plan.all[i], &reformulated);
                bar.inc(1);
                row
            })
            .collect::<Vec<Row>>()
    });
    bar.finish_and_clear();
    let rows = match rows {
        Ok(rows) => rows,
        Err(e) => return fail(&e),
    };
    let done = Done {
        name: &sys.name,
        cases: plan.all.len(),
        wall: started.elapsed().as_secs_f64(),
        reformulated: reformulated.load(Ordering::Relaxed),
    };
    finish(a, results(ctx.header(), &rows), &rows, &study, &done)
}
