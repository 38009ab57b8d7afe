//! Running generated programs without a compiler: the evaluator behind
//! `eom-gen eval --interpret` and `simulate --interpret`.
//!
//! [`Interpreted`] is a formulation as an `eom_sim` model: the runtime's
//! one runner ([`eom_sim::simulate`]) integrates it exactly as it does
//! compiled code, and [`evaluate_function`] gives every function of the
//! table ([`crate::functions`]) with the layout the generated
//! `Model::evaluate` has.

use crate::functions::{Function, Layout, TABLE, When};
use crate::mech::Formulation;
use crate::sym::{Program, SymKind, Tape};
use crate::system::System;
use std::sync::OnceLock;

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

/// Runs `p` at `x`; symbols with no value are NaN (`u̇`, `τ`, `λ` and
/// inputs not given are zero, as the generated `Model::evaluate` takes
/// them).
pub fn run(p: &Program, x: &Point<'_>) -> Vec<f64> {
    p.eval(&inputs(&sources(p, x), x))
}

/// Where each input of a program comes from at a point.
#[derive(Clone, Copy, Debug)]
enum Source {
    Q(usize),
    U(usize),
    Udot(usize),
    Tau(usize),
    Multiplier(usize),
    Input(usize),
    Time,
    /// A parameter's value (or NaN: a symbol with no value).
    Value(f64),
}

/// The sources of `p`'s inputs: parameters resolved from `x.params`, else
/// their defaults; inputs by their place among the model's.
fn sources(p: &Program, x: &Point<'_>) -> Vec<Source> {
    p.inputs
        .iter()
        .map(|s| match s.kind {
            SymKind::Coord(i) => Source::Q(i as usize),
            SymKind::Speed(i) => Source::U(i as usize),
            SymKind::SpeedRate(i) => Source::Udot(i as usize),
            SymKind::CoordRate(_) => Source::Value(f64::NAN),
            SymKind::Time => Source::Time,
            SymKind::Tau(i) => Source::Tau(i as usize),
            SymKind::Multiplier(i) => Source::Multiplier(i as usize),
            SymKind::Input => match x.sys.inputs.iter().position(|n| *n == s.name) {
                Some(k) => Source::Input(k),
                None => Source::Value(f64::NAN),
            },
            SymKind::Param => Source::Value(
                x.params
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
            ),
        })
        .collect()
}

/// The values of `sources` at `x`.
fn inputs(sources: &[Source], x: &Point<'_>) -> Vec<f64> {
    let at = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(f64::NAN);
    let or_zero = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0);
    sources
        .iter()
        .map(|s| match *s {
            Source::Q(i) => at(x.q, i),
            Source::U(i) => at(x.u, i),
            Source::Udot(i) => or_zero(x.udot, i),
            Source::Tau(i) => or_zero(x.tau, i),
            Source::Multiplier(i) => or_zero(x.multipliers, i),
            Source::Input(k) => or_zero(x.inputs, k),
            Source::Time => x.t,
            Source::Value(v) => v,
        })
        .collect()
}

/// The programs of a formulation flattened once ([`Program::tape`]) with
/// their inputs' sources, for a model evaluated at many points with the
/// same parameters ([`Interpreted`]): each filled at its first call.
struct Tapes(Vec<(Function, OnceLock<Flat>)>);

/// A program flattened, and the sources of its inputs.
type Flat = (Tape, Vec<Source>);

impl Tapes {
    fn new(f: &Formulation) -> Tapes {
        Tapes(
            TABLE
                .iter()
                .filter(|e| f.program(e.function).is_some())
                .map(|e| (e.function, OnceLock::new()))
                .collect(),
        )
    }
}

/// Runs the program of a function at a point: through the tapes of an
/// [`Interpreted`] model, or flattening it on the spot.
#[derive(Clone, Copy)]
struct Runner<'r>(Option<&'r Tapes>);

impl Runner<'_> {
    fn run(self, function: Function, p: &Program, x: &Point<'_>) -> Vec<f64> {
        let cached = self
            .0
            .and_then(|t| t.0.iter().find(|(g, _)| *g == function))
            .map(|(_, cell)| cell.get_or_init(|| (p.tape(), sources(p, x))));
        match cached {
            Some((tape, sources)) => tape.eval(&inputs(sources, x)),
            None => run(p, x),
        }
    }
}

/// What `eval` reports: every function the model offers, flat, in table
/// order (see [`evaluate_function`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Evaluation {
    /// `(name, flat result)` per function.
    pub functions: Vec<(String, Vec<f64>)>,
}

impl Evaluation {
    /// The flat result of the function named `name` (empty if absent).
    pub fn get(&self, name: &str) -> &[f64] {
        self.functions
            .iter()
            .find(|(n, _)| n == name)
            .map_or(&[], |(_, v)| v.as_slice())
    }

    /// `u̇` from forward dynamics.
    pub fn udot(&self) -> Vec<f64> {
        self.get("forward_dynamics").to_vec()
    }
}

/// The mass matrix at `x.q`, `x.t`, full: from its program, or (when the
/// scene leaves it out) column `i` = `ID(q, 0, e_i) − ID(q, 0, 0)`,
/// symmetrised — as the generated code derives it. NaN without either.
pub fn mass_matrix(f: &Formulation, x: &Point<'_>) -> Vec<Vec<f64>> {
    mass_matrix_by(f, x, Runner(None))
}

fn mass_matrix_by(f: &Formulation, x: &Point<'_>, r: Runner<'_>) -> Vec<Vec<f64>> {
    let nu = x.sys.nu();
    if let Some(p) = f.program(Function::MassMatrix) {
        let lower = r.run(Function::MassMatrix, p, x);
        return (0..nu)
            .map(|i| (0..nu).map(|j| lower_triangle(&lower, i, j)).collect())
            .collect();
    }
    let Some(id) = f.program(Function::InverseDynamics) else {
        return vec![vec![f64::NAN; nu]; nu];
    };
    let zero = vec![0.0; nu];
    let at = |udot: &[f64]| {
        let y = Point {
            u: &zero,
            udot,
            ..x.clone()
        };
        r.run(Function::InverseDynamics, id, &y)
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

/// Entry `(i, j)` of a symmetric matrix stored as its lower triangle row by
/// row ([`Layout::LowerTriangle`]).
fn lower_triangle(lower: &[f64], i: usize, j: usize) -> f64 {
    let (r, c) = if j <= i { (i, j) } else { (j, i) };
    lower.get(r * (r + 1) / 2 + c).copied().unwrap_or(f64::NAN)
}

/// The bias at `x`: from its program, or `ID(q, u, 0)`.
pub fn bias(f: &Formulation, x: &Point<'_>) -> Vec<f64> {
    bias_by(f, x, Runner(None))
}

fn bias_by(f: &Formulation, x: &Point<'_>, r: Runner<'_>) -> Vec<f64> {
    if let Some(p) = f.program(Function::Bias) {
        return r.run(Function::Bias, p, x);
    }
    let zero = vec![0.0; x.sys.nu()];
    match f.program(Function::InverseDynamics) {
        Some(id) => r.run(
            Function::InverseDynamics,
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
    inverse_dynamics_by(f, x, Runner(None))
}

fn inverse_dynamics_by(f: &Formulation, x: &Point<'_>, r: Runner<'_>) -> Vec<f64> {
    if let Some(p) = f.program(Function::InverseDynamics) {
        return r.run(Function::InverseDynamics, p, x);
    }
    let m = mass_matrix_by(f, x, r);
    let b = bias_by(f, x, r);
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

/// The flat result of `function` at `x`, laid out as the generated
/// `Model::evaluate` lays it out; `None` if the model has no such function.
/// Functions a scene leaves out are derived as the generated code does.
pub fn evaluate_function(f: &Formulation, function: Function, x: &Point<'_>) -> Option<Vec<f64>> {
    evaluate_function_by(f, function, x, Runner(None))
}

fn evaluate_function_by(
    f: &Formulation,
    function: Function,
    x: &Point<'_>,
    r: Runner<'_>,
) -> Option<Vec<f64>> {
    let e = function.entry();
    match (f.program(function), function) {
        (_, Function::MassMatrix) => Some(mass_matrix_by(f, x, r).concat()),
        (None, Function::Bias) => Some(bias_by(f, x, r)),
        (None, Function::InverseDynamics) => Some(inverse_dynamics_by(f, x, r)),
        (None, _) => None,
        (Some(p), _) => {
            let values = r.run(function, p, x);
            Some(match e.layout {
                Layout::Vector => values,
                Layout::LowerTriangle => {
                    let nu = x.sys.nu();
                    (0..nu * nu)
                        .map(|k| lower_triangle(&values, k / nu, k % nu))
                        .collect()
                }
                Layout::Constraints => {
                    // Φ_i, Φ̇_i, γ_i interleaved, then J: regroup.
                    let nc = f.constraint_names.len();
                    let (rows, jacobian) = values.split_at((3 * nc).min(values.len()));
                    (0..3)
                        .flat_map(|a| rows.iter().skip(a).step_by(3).copied())
                        .chain(jacobian.iter().copied())
                        .collect()
                }
            })
        }
    }
}

/// Evaluates every function the model offers at `x` (forward dynamics
/// with `x.tau`).
pub fn evaluate(f: &Formulation, x: &Point<'_>) -> Evaluation {
    Evaluation {
        functions: TABLE
            .iter()
            .filter(|e| f.program(e.function).is_some() || e.when == When::Requested)
            .filter_map(|e| evaluate_function(f, e.function, x).map(|v| (e.name.to_string(), v)))
            .collect(),
    }
}

/// The equations of motion run by the evaluator: an `eom_sim` model for
/// the runtime's runner and constraint solvers.
pub struct Interpreted<'a> {
    f: &'a Formulation,
    sys: &'a System,
    nq: usize,
    nu: usize,
    quaternions: Vec<usize>,
    inputs: Vec<f64>,
    params: Vec<(String, f64)>,
    /// The programs flattened at their first call (with `params`).
    tapes: Tapes,
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
            inputs: vec![0.0; sys.inputs.len()],
            params: Vec::new(),
            tapes: Tapes::new(f),
        }
    }

    /// The same with tunable parameters set away from their defaults
    /// (`eom-gen sweep`: one formulation, a value per case). A name that
    /// is not a tunable parameter of the formulation changes nothing.
    pub fn with_params(mut self, params: &[(String, f64)]) -> Self {
        self.params = params.to_vec();
        // The tapes resolved the parameters: flatten again.
        self.tapes = Tapes::new(self.f);
        self
    }

    /// The same with the model's runtime inputs set (in `System::inputs`
    /// order; missing ones are zero).
    pub fn with_inputs(mut self, inputs: &[f64]) -> Self {
        for (d, s) in self.inputs.iter_mut().zip(inputs) {
            *d = *s;
        }
        self
    }

    fn point<'p>(&'p self, q: &'p [f64], u: &'p [f64], t: f64) -> Point<'p> {
        Point {
            sys: self.sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &self.inputs,
            params: &self.params,
            multipliers: &[],
            t,
        }
    }

    fn fill(&self, function: Function, x: &Point<'_>, out: &mut [f64]) {
        let v = evaluate_function_by(self.f, function, x, Runner(Some(&self.tapes)))
            .unwrap_or_default();
        out.iter_mut()
            .zip(v.iter().chain(std::iter::repeat(&f64::NAN)))
            .for_each(|(d, s)| *d = *s);
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
        self.fill(Function::Qdot, &self.point(q, u, 0.0), qdot);
    }
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut nalgebra::DMatrix<f64>) {
        let full = mass_matrix_by(self.f, &self.point(q, &[], t), Runner(Some(&self.tapes)));
        for (i, row) in full.iter().enumerate().take(m.nrows()) {
            for (j, v) in row.iter().enumerate().take(m.ncols()) {
                m[(i, j)] = *v;
            }
        }
    }
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut nalgebra::DVector<f64>) {
        let v = bias_by(self.f, &self.point(q, u, t), Runner(Some(&self.tapes)));
        b.iter_mut().zip(v).for_each(|(d, s)| *d = s);
    }
    fn constraints(&self, t: f64, q: &[f64], u: &[f64], c: &mut eom_sim::ConstraintValues) {
        let Some(v) = evaluate_function_by(
            self.f,
            Function::Constraints,
            &self.point(q, u, t),
            Runner(Some(&self.tapes)),
        ) else {
            return;
        };
        let nc = self.nc();
        let (rows, jacobian) = v.split_at((3 * nc).min(v.len()));
        for (target, chunk) in [&mut c.phi, &mut c.phidot, &mut c.gamma]
            .into_iter()
            .zip(rows.chunks(nc.max(1)))
        {
            target.iter_mut().zip(chunk).for_each(|(d, s)| *d = *s);
        }
        for (k, v) in jacobian.iter().enumerate() {
            let (r, col) = (k / self.nu.max(1), k % self.nu.max(1));
            if r < c.jacobian.nrows() && col < c.jacobian.ncols() {
                c.jacobian[(r, col)] = *v;
            }
        }
    }
}

impl eom_sim::Simulate for Interpreted<'_> {
    fn names(&self) -> eom_sim::run::Names {
        let own = |v: Vec<&str>| v.into_iter().map(String::from).collect();
        eom_sim::run::Names {
            coordinates: own(self.sys.coordinate_names()),
            speeds: own(self.sys.speed_names()),
            outputs: self.f.output_names.clone(),
            constraints: self.f.constraint_names.clone(),
            cut_joints: self.f.cut_joints.clone(),
            contacts: self.f.contact_rows.clone(),
            impulse_joints: self.f.impulse_joints.clone(),
        }
    }
    fn initial_state(&self) -> (Vec<f64>, Vec<f64>) {
        (self.sys.q0(), self.sys.u0())
    }
    fn forward_dynamics(&self, t: f64, q: &[f64], u: &[f64], udot: &mut [f64]) {
        self.fill(Function::ForwardDynamics, &self.point(q, u, t), udot);
    }
    fn evaluate(&self, name: &str, at: &eom_sim::Point<'_>, out: &mut [f64]) -> bool {
        let Ok(function) = name.parse::<Function>() else {
            return false;
        };
        let x = Point {
            sys: self.sys,
            q: at.q,
            u: at.u,
            udot: at.udot,
            tau: at.tau,
            inputs: &self.inputs,
            params: &self.params,
            multipliers: at.lambda,
            t: at.t,
        };
        match evaluate_function_by(self.f, function, &x, Runner(Some(&self.tapes))) {
            Some(v) if v.len() == out.len() => {
                out.copy_from_slice(&v);
                true
            }
            _ => false,
        }
    }
    fn function_len(&self, name: &str) -> Option<usize> {
        let function = name.parse::<Function>().ok()?;
        self.f
            .program(function)
            .map(|_| self.f.result_len(function, self.nu))
    }
}

impl<const N: usize> eom_sim::OdeSystem<N> for Interpreted<'_> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let (q, u) = y.split_at(self.nq);
        let (dq, du) = dy.split_at_mut(self.nq);
        eom_sim::Dynamics::qdot(self, q, &u[..self.nu], dq);
        eom_sim::Simulate::forward_dynamics(self, t, q, &u[..self.nu], du);
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

/// Integrates the formulation with the evaluator through the runtime's
/// runner ([`eom_sim::simulate`]), exactly as compiled code runs.
pub fn simulate(
    f: &Formulation,
    sys: &System,
    options: &eom_sim::RunOptions,
) -> Result<eom_sim::RunReport, InterpretError> {
    simulate_with_inputs(f, sys, options, &[])
}

/// [`simulate`] with the model's runtime inputs held at `inputs` (in
/// `System::inputs` order).
pub fn simulate_with_inputs(
    f: &Formulation,
    sys: &System,
    options: &eom_sim::RunOptions,
    inputs: &[f64],
) -> Result<eom_sim::RunReport, InterpretError> {
    simulate_model(&Interpreted::new(f, sys).with_inputs(inputs), options)
}

/// Integrates an [`Interpreted`] model (inputs and tunable parameters
/// set) through the runtime's runner.
pub fn simulate_model(
    model: &Interpreted<'_>,
    options: &eom_sim::RunOptions,
) -> Result<eom_sim::RunReport, InterpretError> {
    let sys = model.sys;
    let n = eom_sim::run::state_len(model, options);
    macro_rules! sized {
        ($($n:literal)*) => {
            match n {
                $($n => eom_sim::simulate::<$n, _>(model, options).map_err(InterpretError::Run),)*
                n => Err(InterpretError::TooLarge { model: sys.name.clone(), states: n }),
            }
        };
    }
    sized!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32)
}

/// Why the evaluator could not run a model.
#[derive(Clone, Debug, PartialEq)]
pub enum InterpretError {
    /// More states than [`MAX_STATES`].
    TooLarge {
        /// The model.
        model: String,
        /// Its state size.
        states: usize,
    },
    /// The runner refused (options, state sizes, a singular mass matrix).
    Run(eom_sim::RunError),
}

impl std::fmt::Display for InterpretError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            InterpretError::TooLarge { model, states } => write!(
                f,
                "the interpreter integrates up to {MAX_STATES} states, `{model}` has {states}; run it compiled (`simulate` without --interpret, `sweep --compiled`)"
            ),
            InterpretError::Run(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for InterpretError {}
