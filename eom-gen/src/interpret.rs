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
