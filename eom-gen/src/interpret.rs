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

/// Evaluates every program of `f` at `x` (forward dynamics with `x.tau`).
pub fn evaluate(f: &Formulation, x: &Point<'_>) -> Evaluation {
    let nu = x.u.len();
    let get = |p: &Option<Program>| p.as_ref().map(|p| run(p, x)).unwrap_or_default();
    let lower = get(&f.mass_matrix);
    // Lower triangle row by row: entry (i, j), j ≤ i, is at i(i+1)/2 + j.
    let m: Vec<Vec<f64>> = (0..nu)
        .map(|i| {
            (0..nu)
                .map(|j| {
                    let (r, c) = if j <= i { (i, j) } else { (j, i) };
                    lower.get(r * (r + 1) / 2 + c).copied().unwrap_or(f64::NAN)
                })
                .collect()
        })
        .collect();
    let energy = get(&f.energy);
    Evaluation {
        qdot: run(&f.qdot, x),
        udot: get(&f.forward_dynamics),
        mass_matrix: m,
        bias: get(&f.bias),
        kinetic_energy: energy.first().copied().unwrap_or(f64::NAN),
        potential_energy: energy.get(1).copied().unwrap_or(f64::NAN),
    }
}

/// The equations of motion run by the evaluator, as a first-order system
/// `y = (q, u)` of `N` states.
struct Interpreted<'a, const N: usize> {
    f: &'a Formulation,
    sys: &'a System,
    nq: usize,
    quaternions: Vec<usize>,
}

impl<const N: usize> eom_sim::OdeSystem<N> for Interpreted<'_, N> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let (q, u) = y.split_at(self.nq);
        let zero = vec![0.0; u.len()];
        let x = Point {
            sys: self.sys,
            q,
            u,
            udot: &[],
            tau: &zero,
            inputs: &[],
            params: &[],
            t,
        };
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
        for &a in &self.quaternions {
            if let Some(quat) = y.get_mut(a..a + 4) {
                let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                if n > 0.0 && n.is_finite() {
                    quat.iter_mut().for_each(|x| *x /= n);
                }
            }
        }
        !self.quaternions.is_empty()
    }
}

/// Largest state (`nq + nu`) the interpreter integrates; the integrators
/// are sized at compile time, one instance per size.
pub const MAX_STATES: usize = 32;

/// Integrates the formulation with the evaluator from the initial state;
/// the JSON matches `eom-gen simulate --json` on compiled code.
pub fn simulate(
    f: &Formulation,
    sys: &System,
    o: &crate::compiled::SimOptions,
) -> Result<serde_json::Value, String> {
    macro_rules! sized {
        ($($n:literal)*) => {
            match sys.nq() + sys.nu() {
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
        Dop853, Dopri5, Euler, ImplicitMidpoint, Radau5, Rk4, SolveOptions, StopReason, integrate,
    };
    let nq = sys.nq();
    let quaternions = sys.quaternion_indices();
    let model = Interpreted::<N> {
        f,
        sys,
        nq,
        quaternions,
    };
    let mut y0 = [0.0; N];
    let (mut q0, mut u0) = (sys.q0(), sys.u0());
    if f.constraints.is_some() {
        // Start from a consistent state (assembly).
        let num = crate::mech::Numeric::new(sys).map_err(|e| e.to_string())?;
        let a = num.assemble(&q0, &u0, 0.0).map_err(|e| e.to_string())?;
        (q0, u0) = (a.q, a.u);
    }
    for (d, v) in y0.iter_mut().zip(q0.iter().chain(&u0)) {
        *d = *v;
    }
    let mode = if o.constraints == "multipliers" {
        crate::constrained::Stabilization::Baumgarte
    } else {
        crate::constrained::Stabilization::Projection
    };
    let constrained = crate::constrained::Constrained::<N>::new(f, sys, mode);

    let opts = if o.every > 0.0 {
        SolveOptions::every(0.0, o.t_end, o.every)
    } else {
        SolveOptions::default()
    };
    let start = std::time::Instant::now();
    macro_rules! with_system {
        ($sys:expr) => {
            match o.integrator.as_str() {
                "euler" => integrate(
                    &mut Euler::new(o.dt),
                    $sys,
                    0.0,
                    y0,
                    o.t_end,
                    &opts,
                    &mut [],
                ),
                "rk4" => integrate(&mut Rk4::new(o.dt), $sys, 0.0, y0, o.t_end, &opts, &mut []),
                "midpoint" => integrate(
                    &mut ImplicitMidpoint::new(o.dt),
                    $sys,
                    0.0,
                    y0,
                    o.t_end,
                    &opts,
                    &mut [],
                ),
                "dop853" => integrate(
                    &mut Dop853::new(o.rtol, o.atol),
                    $sys,
                    0.0,
                    y0,
                    o.t_end,
                    &opts,
                    &mut [],
                ),
                "radau5" => integrate(
                    &mut Radau5::new(o.rtol, o.atol),
                    $sys,
                    0.0,
                    y0,
                    o.t_end,
                    &opts,
                    &mut [],
                ),
                _ => integrate(
                    &mut Dopri5::new(o.rtol, o.atol),
                    $sys,
                    0.0,
                    y0,
                    o.t_end,
                    &opts,
                    &mut [],
                ),
            }
        };
    }
    let sol = match &constrained {
        Some(c) => with_system!(c),
        None => with_system!(&model),
    };
    let cpu = start.elapsed().as_secs_f64();
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
                    t: *t,
                };
                let udot = f
                    .forward_dynamics
                    .as_ref()
                    .map(|fd| run(fd, &x))
                    .unwrap_or_default();
                x.udot = &udot;
                row.extend(run(p, &x).iter().map(|v| format!("{v:?}")));
            }
            text += &format!("{t:?},{}\n", row.join(","));
        }
        std::fs::write(csv, text).map_err(|e| format!("cannot write {csv}: {e}"))?;
    }
    let energy = |y: &[f64; N], t: f64| -> f64 {
        let (q, u) = y.split_at(nq);
        let x = Point {
            sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
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
            "reason": "non-finite state", "t": t, "coordinate": names.get(component).copied().unwrap_or("?"),
        }),
        other => serde_json::json!(format!("{other:?}")),
    };
    let s = &sol.stats;
    Ok(serde_json::json!({
        "t": sol.t_final,
        "q": &sol.y_final[..nq],
        "u": &sol.y_final[nq..],
        "energy": [energy(&y0, 0.0), energy(&sol.y_final, sol.t_final)],
        "stop": stop,
        "stats": {
            "steps": s.steps, "accepted": s.accepted, "rejected": s.rejected, "rhs_evals": s.rhs_evals,
            "jacobian_evals": s.jac_evals, "lu_decompositions": s.lu_decomps,
            "newton_iterations": s.newton_iters, "stiffness_detections": s.stiffness_detections,
        },
        "cpu_s": cpu,
        "max_constraint_residual": constrained.as_ref().map(|c| c.max_residual.get()),
        "constraint_rank": constrained.as_ref().map(|c| c.rank.get()),
        "constraints": constrained.as_ref().map(|_| o.constraints.as_str()),
    }))
}
