//! Running generated programs without a compiler: the evaluator behind
//! `eom-gen eval --interpret` (and later `simulate --interpret`).

use crate::mech::Formulation;
use crate::sym::{Program, SymKind};
use crate::system::System;

/// A state at which to evaluate, with the model's inputs and parameters.
#[derive(Clone, Debug)]
pub struct Point<'a> {
    /// The system (for parameter defaults and input names).
    pub sys: &'a System,
    /// Positions.
    pub q: &'a [f64],
    /// Speeds.
    pub u: &'a [f64],
    /// Speed rates (inverse dynamics, reactions).
    pub udot: &'a [f64],
    /// Extra generalised forces.
    pub tau: &'a [f64],
    /// Runtime inputs, in the model's order.
    pub inputs: &'a [f64],
    /// Tunable parameters set away from their defaults.
    pub params: &'a [(String, f64)],
    /// Constraint multipliers `λ` (joint reactions in closed loops).
    pub multipliers: &'a [f64],
    /// Time.
    pub t: f64,
}

/// Runs `p` at `x`; symbols with no value are NaN.
pub fn run(p: &Program, x: &Point<'_>) -> Vec<f64> {
    let at = |v: &[f64], i: u32| v.get(i as usize).copied().unwrap_or(f64::NAN);
    let inputs: Vec<f64> = p
        .inputs
        .iter()
        .map(|s| match s.kind {
            SymKind::Coord(i) => at(x.q, i),
            SymKind::Speed(i) => at(x.u, i),
            SymKind::SpeedRate(i) => at(x.udot, i),
            SymKind::CoordRate(_) => f64::NAN,
            SymKind::Time => x.t,
            SymKind::Input => match x.sys.inputs.iter().position(|n| *n == s.name) {
                Some(k) => x.inputs.get(k).copied().unwrap_or(0.0),
                None if s.name.starts_with(crate::mech::formulate::MULTIPLIER) => s
                    .name
                    .strip_prefix(crate::mech::formulate::MULTIPLIER)
                    .and_then(|k| k.parse::<usize>().ok())
                    .map_or(f64::NAN, |k| x.multipliers.get(k).copied().unwrap_or(0.0)),
                None => s
                    .name
                    .strip_prefix("tau")
                    .and_then(|k| k.parse::<usize>().ok())
                    .map_or(f64::NAN, |k| x.tau.get(k).copied().unwrap_or(0.0)),
            },
            SymKind::Param => x
                .params
                .iter()
                .find(|(n, _)| *n == s.name)
                .map(|(_, v)| *v)
                .or_else(|| {
                    x.sys
                        .parameters
                        .iter()
                        .find(|p| p.name == s.name)
                        .map(|p| p.value.value)
                })
                .unwrap_or(f64::NAN),
        })
        .collect();
    p.eval(&inputs)
}

/// What `eval` reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// `q̇`.
    pub qdot: Vec<f64>,
    /// `u̇` from forward dynamics.
    pub udot: Vec<f64>,
    /// Mass matrix, full.
    pub mass_matrix: Vec<Vec<f64>>,
    /// Bias `b`.
    pub bias: Vec<f64>,
    /// Kinetic energy.
    pub kinetic_energy: f64,
    /// Potential energy.
    pub potential_energy: f64,
}

/// The mass matrix at `x.q`, `x.t`, full: from its program, or (when the
/// scene leaves it out) column `i` = `ID(q, 0, e_i) − ID(q, 0, 0)`,
/// symmetrised — as the generated code derives it. NaN without either.
pub fn mass_matrix(f: &Formulation, x: &Point<'_>) -> Vec<Vec<f64>> {
    let nu = x.sys.nu();
    if let Some(p) = &f.mass_matrix {
        let lower = run(p, x);
        // Lower triangle row by row: entry (i, j), j ≤ i, is at i(i+1)/2 + j.
        return (0..nu)
            .map(|i| {
                (0..nu)
                    .map(|j| {
                        let (r, c) = if j <= i { (i, j) } else { (j, i) };
                        lower.get(r * (r + 1) / 2 + c).copied().unwrap_or(f64::NAN)
                    })
                    .collect()
            })
            .collect();
    }
    let Some(id) = &f.inverse_dynamics else {
        return vec![vec![f64::NAN; nu]; nu];
    };
    let zero = vec![0.0; nu];
    let at = |udot: &[f64]| {
        let y = Point {
            u: &zero,
            udot,
            ..x.clone()
        };
        run(id, &y)
    };
    let tau0 = at(&zero);
    let columns: Vec<Vec<f64>> = (0..nu)
        .map(|i| {
            let mut e = zero.clone();
            e[i] = 1.0;
            at(&e).iter().zip(&tau0).map(|(c, c0)| c - c0).collect()
        })
        .collect();
    let entry = |i: usize, j: usize| -> f64 {
        columns
            .get(j)
            .and_then(|c| c.get(i))
            .copied()
            .unwrap_or(f64::NAN)
    };
    (0..nu)
        .map(|i| (0..nu).map(|j| 0.5 * (entry(i, j) + entry(j, i))).collect())
        .collect()
}

/// The bias at `x`: from its program, or `ID(q, u, 0)`.
pub fn bias(f: &Formulation, x: &Point<'_>) -> Vec<f64> {
    if let Some(p) = &f.bias {
        return run(p, x);
    }
    let zero = vec![0.0; x.sys.nu()];
    match &f.inverse_dynamics {
        Some(id) => run(
            id,
            &Point {
                udot: &zero,
                ..x.clone()
            },
        ),
        None => vec![f64::NAN; zero.len()],
    }
}

/// Inverse dynamics at `x` (accelerations `x.udot`): from its program, or
/// `M u̇ + b`.
pub fn inverse_dynamics(f: &Formulation, x: &Point<'_>) -> Vec<f64> {
    if let Some(p) = &f.inverse_dynamics {
        return run(p, x);
    }
    let m = mass_matrix(f, x);
    let b = bias(f, x);
    let at = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(f64::NAN);
    m.iter()
        .enumerate()
        .map(|(i, row)| {
            at(&b, i)
                + row
                    .iter()
                    .enumerate()
                    .map(|(j, mij)| mij * at(x.udot, j))
                    .sum::<f64>()
        })
        .collect()
}

/// Evaluates every program of `f` at `x` (forward dynamics with `x.tau`);
/// functions the scene leaves out are derived as the generated code does.
pub fn evaluate(f: &Formulation, x: &Point<'_>) -> Evaluation {
    let get = |p: &Option<Program>| p.as_ref().map(|p| run(p, x)).unwrap_or_default();
    let energy = get(&f.energy);
    Evaluation {
        qdot: run(&f.qdot, x),
        udot: get(&f.forward_dynamics),
        mass_matrix: mass_matrix(f, x),
        bias: bias(f, x),
        kinetic_energy: energy.first().copied().unwrap_or(f64::NAN),
        potential_energy: energy.get(1).copied().unwrap_or(f64::NAN),
    }
}

/// The equations of motion run by the evaluator: a first-order system
/// `y = (q, u)` and, for the constraint solvers, [`eom_sim::Dynamics`].
pub struct Interpreted<'a> {
    f: &'a Formulation,
    sys: &'a System,
    nq: usize,
    nu: usize,
    quaternions: Vec<usize>,
}

impl<'a> Interpreted<'a> {
    /// The evaluator's view of `f`.
    pub fn new(f: &'a Formulation, sys: &'a System) -> Self {
        Interpreted {
            f,
            sys,
            nq: sys.nq(),
            nu: sys.nu(),
            quaternions: sys.quaternion_indices(),
        }
    }

    fn point<'p>(&'p self, q: &'p [f64], u: &'p [f64], t: f64) -> Point<'p> {
        Point {
            sys: self.sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t,
        }
    }
}

impl eom_sim::Dynamics for Interpreted<'_> {
    fn nq(&self) -> usize {
        self.nq
    }
    fn nu(&self) -> usize {
        self.nu
    }
    fn nc(&self) -> usize {
        self.f.constraint_names.len()
    }
    fn n_holonomic(&self) -> usize {
        self.f.n_holonomic
    }
    fn quaternions(&self) -> &[usize] {
        &self.quaternions
    }
    fn qdot(&self, q: &[f64], u: &[f64], qdot: &mut [f64]) {
        let v = run(&self.f.qdot, &self.point(q, u, 0.0));
        qdot.iter_mut().zip(v).for_each(|(d, s)| *d = s);
    }
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut nalgebra::DMatrix<f64>) {
        let full = mass_matrix(self.f, &self.point(q, &[], t));
        for (i, row) in full.iter().enumerate().take(m.nrows()) {
            for (j, v) in row.iter().enumerate().take(m.ncols()) {
                m[(i, j)] = *v;
            }
        }
    }
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut nalgebra::DVector<f64>) {
        let v = bias(self.f, &self.point(q, u, t));
        b.iter_mut().zip(v).for_each(|(d, s)| *d = s);
    }
    fn constraints(&self, t: f64, q: &[f64], u: &[f64], c: &mut eom_sim::ConstraintValues) {
        let Some(p) = &self.f.constraints else {
            return;
        };
        let values = run(p, &self.point(q, u, t));
        for ((name, _), v) in p.outputs.iter().zip(values) {
            if let Some(rest) = name.strip_prefix("J_") {
                let mut it = rest.split('_').filter_map(|s| s.parse::<usize>().ok());
                if let (Some(r), Some(k)) = (it.next(), it.next())
                    && r < c.jacobian.nrows()
                    && k < c.jacobian.ncols()
                {
                    c.jacobian[(r, k)] = v;
                }
                continue;
            }
            for (prefix, target) in [
                ("phidot", &mut c.phidot),
                ("phi", &mut c.phi),
                ("gamma", &mut c.gamma),
            ] {
                if let Some(i) = name
                    .strip_prefix(prefix)
                    .and_then(|k| k.parse::<usize>().ok())
                {
                    if let Some(slot) = target.get_mut(i) {
                        *slot = v;
                    }
                    break;
                }
            }
        }
    }
}

impl<const N: usize> eom_sim::OdeSystem<N> for Interpreted<'_> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let (q, u) = y.split_at(self.nq);
        let zero = vec![0.0; u.len()];
        let mut x = self.point(q, u, t);
        x.tau = &zero;
        let qdot = run(&self.f.qdot, &x);
        let udot = self
            .f
            .forward_dynamics
            .as_ref()
            .map(|p| run(p, &x))
            .unwrap_or_default();
        for (d, v) in dy.iter_mut().zip(qdot.iter().chain(&udot)) {
            *d = *v;
        }
    }

    fn project(&self, _t: f64, y: &mut [f64; N]) -> bool {
        eom_sim::Dynamics::normalize(self, &mut y[..self.nq]);
        !self.quaternions.is_empty()
    }
}

/// Largest state (`nq + nu`, plus the multipliers for `index3`) the
/// interpreter integrates; the integrators are sized at compile time, one
/// instance per size.
pub const MAX_STATES: usize = 32;

/// The constraint method named in `o` (`None` without constraints).
fn method(
    f: &Formulation,
    o: &crate::compiled::SimOptions,
) -> Result<Option<eom_sim::Method>, String> {
    if f.constraints.is_none() {
        return Ok(None);
    }
    let m = eom_sim::Method::from_name(&o.constraints).ok_or_else(|| {
        format!(
            "unknown --constraints `{}`; choose multipliers, projection, partitioning or index3",
            o.constraints
        )
    })?;
    if m == eom_sim::Method::Index3 && o.integrator != "radau5" {
        return Err("--constraints index3 solves the index-3 DAE with --integrator radau5".into());
    }
    Ok(Some(m))
}

/// Integrates the formulation with the evaluator from the initial state
/// (assembled, for constrained models); the JSON matches
/// `eom-gen simulate --json` on compiled code.
pub fn simulate(
    f: &Formulation,
    sys: &System,
    o: &crate::compiled::SimOptions,
) -> Result<serde_json::Value, String> {
    let extra = match method(f, o)? {
        Some(eom_sim::Method::Index3) => f.constraint_names.len(),
        _ => 0,
    };
    macro_rules! sized {
        ($($n:literal)*) => {
            match sys.nq() + sys.nu() + extra {
                $($n => simulate_n::<$n>(f, sys, o),)*
                n => Err(format!(
                    "the interpreter integrates up to {MAX_STATES} states, `{}` has {n}; run it compiled (without --interpret)",
                    sys.name
                )),
            }
        };
    }
    sized!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32)
}

fn simulate_n<const N: usize>(
    f: &Formulation,
    sys: &System,
    o: &crate::compiled::SimOptions,
) -> Result<serde_json::Value, String> {
    use eom_sim::{
        ConstrainedSystem, Dynamics, Index3System, Method, Settings, SolveOptions, solve,
    };
    let (nq, nu) = (sys.nq(), sys.nu());
    let model = Interpreted::new(f, sys);
    let mut settings = Settings {
        integrator: o.integrator.clone(),
        rtol: o.rtol,
        atol: o.atol,
        dt: o.dt,
        index_vars: (0, 0),
    };
    let opts = if o.every > 0.0 {
        SolveOptions::every(0.0, o.t_end, o.every)
    } else {
        SolveOptions::default()
    };
    let unknown = || format!("unknown integrator `{}`", o.integrator);
    let (q0, u0) = (sys.q0(), sys.u0());
    let Some(method) = method(f, o)? else {
        let mut y0 = [0.0; N];
        for (d, v) in y0.iter_mut().zip(q0.iter().chain(&u0)) {
            *d = *v;
        }
        let start = std::time::Instant::now();
        let sol = solve(&settings, &model, 0.0, y0, o.t_end, &opts).ok_or_else(unknown)?;
        let cpu = start.elapsed().as_secs_f64();
        return report(
            f,
            sys,
            o,
            &sol,
            &y0[..nq + nu],
            cpu,
            serde_json::Map::new(),
            &|_, _| None,
        );
    };
    let a = eom_sim::constrained::assemble(&model, &q0, &u0, 0.0);
    let mut info = serde_json::Map::new();
    info.insert("constraints".into(), serde_json::json!(o.constraints));
    info.insert(
        "constraint_names".into(),
        serde_json::json!(f.constraint_names),
    );
    info.insert(
        "assembly".into(),
        serde_json::json!({"residual": a.residual, "velocity_residual": a.velocity_residual, "iterations": a.iterations}),
    );
    let put = |info: &mut serde_json::Map<String, serde_json::Value>,
               s: eom_sim::ConstraintStats,
               lambda: Vec<f64>| {
        info.insert(
            "max_constraint_residual".into(),
            serde_json::json!(s.max_position_residual),
        );
        info.insert(
            "max_velocity_residual".into(),
            serde_json::json!(s.max_velocity_residual),
        );
        info.insert("constraint_rank".into(), serde_json::json!(s.rank));
        info.insert("min_constraint_rank".into(), serde_json::json!(s.min_rank));
        info.insert(
            "min_singular_ratio".into(),
            serde_json::json!(s.min_singular_ratio),
        );
        info.insert("repartitions".into(), serde_json::json!(s.repartitions));
        info.insert("lambda".into(), serde_json::json!(lambda));
    };
    let start = std::time::Instant::now();
    if method == Method::Index3 {
        let dae = Index3System::new(&model);
        let y0 = dae
            .initial::<N>(0.0, &a.q, &a.u)
            .ok_or("the mass matrix is singular at the initial state")?;
        settings.index_vars = dae.index_vars();
        let sol = solve(&settings, &dae, 0.0, y0, o.t_end, &opts).ok_or_else(unknown)?;
        let cpu = start.elapsed().as_secs_f64();
        put(&mut info, dae.stats(), dae.multipliers(&sol.y_final));
        let outputs_at = ConstrainedSystem::new(&model, Method::Projection);
        report(f, sys, o, &sol, &y0[..nq + nu], cpu, info, &|t, y| {
            outputs_at.accelerations(t, &y[..nq], &y[nq..nq + nu])
        })
    } else {
        let cs = ConstrainedSystem::new(&model, method);
        let mut y0 = [0.0; N];
        for (d, v) in y0.iter_mut().zip(a.q.iter().chain(&a.u)) {
            *d = *v;
        }
        let sol = solve(&settings, &cs, 0.0, y0, o.t_end, &opts).ok_or_else(unknown)?;
        let cpu = start.elapsed().as_secs_f64();
        let (q, u) = sol.y_final[..nq + nu].split_at(nq);
        let lambda = cs
            .accelerations(sol.t_final, q, u)
            .map(|(_, l)| l.as_slice().to_vec())
            .unwrap_or_default();
        put(&mut info, cs.stats(), lambda);
        debug_assert_eq!(model.nc(), f.constraint_names.len());
        report(f, sys, o, &sol, &y0[..nq + nu], cpu, info, &|t, y| {
            cs.accelerations(t, &y[..nq], &y[nq..nq + nu])
        })
    }
}

/// `u̇` and `λ` of a constrained model at a state `(q, u, …)`.
type Accelerations<'a> =
    dyn Fn(f64, &[f64]) -> Option<(nalgebra::DVector<f64>, nalgebra::DVector<f64>)> + 'a;

/// The JSON of a run (and its CSV) from the `(q, u)` part of its states;
/// outputs use the constrained accelerations and multipliers when
/// `constrained` gives them.
#[allow(clippy::too_many_arguments)]
fn report<const N: usize>(
    f: &Formulation,
    sys: &System,
    o: &crate::compiled::SimOptions,
    sol: &eom_sim::Solution<N>,
    y0: &[f64],
    cpu: f64,
    extra: serde_json::Map<String, serde_json::Value>,
    constrained: &Accelerations<'_>,
) -> Result<serde_json::Value, String> {
    use eom_sim::StopReason;
    let (nq, nu) = (sys.nq(), sys.nu());
    let names: Vec<&str> = sys
        .coordinate_names()
        .into_iter()
        .chain(sys.speed_names())
        .collect();
    if let Some(csv) = &o.csv {
        let (ts, ys) = if o.every > 0.0 {
            (&sol.t_out, &sol.y_out)
        } else {
            (&sol.t, &sol.y)
        };
        let output_names: Vec<&str> = f
            .outputs
            .as_ref()
            .map(|p| p.outputs.iter().map(|(n, _)| n.as_str()).collect())
            .unwrap_or_default();
        let header: Vec<&str> = names
            .iter()
            .copied()
            .chain(output_names.iter().copied())
            .collect();
        let mut text = format!("t,{}\n", header.join(","));
        for (t, y) in ts.iter().zip(ys) {
            let y = &y[..nq + nu];
            let mut row: Vec<String> = y.iter().map(|x| format!("{x:?}")).collect();
            if let Some(p) = &f.outputs {
                // Outputs at the sample; reactions need u̇ from forward dynamics.
                let (q, u) = y.split_at(nq);
                let zero = vec![0.0; u.len()];
                let mut x = Point {
                    sys,
                    q,
                    u,
                    udot: &[],
                    tau: &zero,
                    inputs: &[],
                    params: &[],
                    multipliers: &[],
                    t: *t,
                };
                let (udot, lambda) = match constrained(*t, y) {
                    Some((a, l)) => (a.as_slice().to_vec(), l.as_slice().to_vec()),
                    None => (
                        f.forward_dynamics
                            .as_ref()
                            .map(|fd| run(fd, &x))
                            .unwrap_or_default(),
                        Vec::new(),
                    ),
                };
                x.udot = &udot;
                x.multipliers = &lambda;
                row.extend(run(p, &x).iter().map(|v| format!("{v:?}")));
            }
            text += &format!("{t:?},{}\n", row.join(","));
        }
        std::fs::write(csv, text).map_err(|e| format!("cannot write {csv}: {e}"))?;
    }
    let energy = |y: &[f64], t: f64| -> f64 {
        let (q, u) = y[..nq + nu].split_at(nq);
        let x = Point {
            sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t,
        };
        f.energy
            .as_ref()
            .map(|p| run(p, &x).iter().sum())
            .unwrap_or(f64::NAN)
    };
    let stop = match sol.stop {
        StopReason::Finished => serde_json::json!("finished"),
        StopReason::NonFinite { t, component } => serde_json::json!({
            "reason": "non-finite state", "t": t, "coordinate": names.get(component).copied().unwrap_or("multiplier"),
        }),
        other => serde_json::json!(format!("{other:?}")),
    };
    let s = &sol.stats;
    let mut v = serde_json::json!({
        "t": sol.t_final,
        "q": &sol.y_final[..nq],
        "u": &sol.y_final[nq..nq + nu],
        "energy": [energy(y0, 0.0), energy(&sol.y_final, sol.t_final)],
        "stop": stop,
        "stats": {
            "steps": s.steps, "accepted": s.accepted, "rejected": s.rejected, "rhs_evals": s.rhs_evals,
            "jacobian_evals": s.jac_evals, "lu_decompositions": s.lu_decomps,
            "newton_iterations": s.newton_iters, "stiffness_detections": s.stiffness_detections,
        },
        "cpu_s": cpu,
    });
    if let Some(obj) = v.as_object_mut() {
        obj.extend(extra);
    }
    Ok(v)
}
