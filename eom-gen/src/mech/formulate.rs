//! Symbolic formulation: the recursive algorithms run on [`Expr`], lowered
//! to straight-line [`Program`]s, one per generated function.
//!
//! Fixed parameters are inlined as constants and tunable ones stay symbols;
//! quantities that use only fixed parameters enter as numbers, so their
//! arithmetic never reaches the graph. Forward dynamics is built both ways —
//! articulated bodies (O(n)) and the mass matrix with its tree-sparse `LᵀDL`
//! factorisation — and the form with fewer counted operations is kept.

use super::applied::Applied;
use super::env::{Env, NumericEnv};
use super::error::MechError;
use super::kinematics::{Evaluator, Kinematics, State};
use super::looped::{ChainLoops, LOOP_MIN_OPS, LOOPED};
use super::ltdl::{ltdl, ltdl_inverse, ltdl_solve};
use super::spatial::Force;
use super::tree::TreeModel;
use crate::diag::{Diagnostic, Span};
use crate::functions::{Function, FunctionSet, Layout};
use crate::sym::{Context, Expr, LowerOptions, OpCount, Program, Scalar, SymError};
use crate::system::{ForceElement, OutputKind, System};
use std::collections::BTreeMap;
use std::fmt;
use std::time::Instant;

/// How forward dynamics is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FdForm {
    /// Articulated-body algorithm (Featherstone §7.3).
    Aba,
    /// Composite-rigid-body mass matrix, tree-sparse `LᵀDL`, substitution
    /// (Featherstone §6.2, §6.5).
    MassMatrix,
}

impl fmt::Display for FdForm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            FdForm::Aba => "articulated-body algorithm",
            FdForm::MassMatrix => "mass matrix + tree-sparse LTDL",
        })
    }
}

/// Why formulation failed.
#[derive(Debug)]
pub enum FormulateError {
    /// A mechanics problem (with its span).
    Mech(MechError),
    /// A symbol could not be created (a parameter or input named like a
    /// state symbol).
    Sym {
        /// What went wrong.
        error: SymError,
        /// Where the name is defined in the model file, when known.
        span: Option<Span>,
    },
    /// A generated function holds an infinite or NaN constant: it divides
    /// by a structural zero for every state, as forward dynamics does when
    /// a joint's motion has no inertia (a point mass on a hinge's axis).
    NotFinite {
        /// The function.
        function: Function,
        /// The joint whose motion has no inertia at the initial state and
        /// its speed, when the mass matrix shows one.
        joint: Option<(String, String)>,
        /// Where: that joint, else none.
        span: Option<Span>,
    },
}

impl FormulateError {
    /// Where in the model file, when known.
    pub fn span(&self) -> Option<Span> {
        match self {
            FormulateError::Mech(e) => Some(e.span()),
            FormulateError::Sym { span, .. } | FormulateError::NotFinite { span, .. } => *span,
        }
    }

    /// The error as a diagnostic at its span (without one: about the file).
    pub fn diagnostic(&self) -> Diagnostic {
        match self {
            FormulateError::Mech(e) => e.diagnostic(),
            FormulateError::Sym { error, span } => {
                let d = match span {
                    Some(s) => Diagnostic::error(*s, error.to_string()),
                    None => Diagnostic::file_error(error.to_string()),
                };
                d.with_help("rename it in the model file")
            }
            FormulateError::NotFinite { span, joint, .. } => {
                let d = match span {
                    Some(s) => Diagnostic::error(*s, self.to_string()),
                    None => Diagnostic::file_error(self.to_string()),
                };
                d.with_help(match joint {
                    Some(_) => "give the body this joint carries mass and inertia for its motion (off the axis), or lock or remove the joint",
                    None => "look for a zero mass, length or radius that the model divides by",
                })
            }
        }
    }
}

impl fmt::Display for FormulateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FormulateError::Mech(e) => write!(f, "{e}"),
            FormulateError::Sym { error, .. } => write!(f, "{error}"),
            FormulateError::NotFinite {
                function,
                joint: Some((joint, speed)),
                ..
            } => write!(
                f,
                "the mass matrix is singular for every state: the motion of joint `{joint}` (speed `{speed}`) has no inertia, and `{}` would divide by zero",
                function.name()
            ),
            FormulateError::NotFinite {
                function,
                joint: None,
                ..
            } => write!(
                f,
                "`{}` divides by zero for every state (a constant of the generated code is not finite)",
                function.name()
            ),
        }
    }
}

impl std::error::Error for FormulateError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            FormulateError::Mech(e) => Some(e),
            FormulateError::Sym { error, .. } => Some(error),
            FormulateError::NotFinite { .. } => None,
        }
    }
}

impl From<MechError> for FormulateError {
    fn from(e: MechError) -> Self {
        FormulateError::Mech(e)
    }
}

impl From<SymError> for FormulateError {
    fn from(error: SymError) -> Self {
        FormulateError::Sym { error, span: None }
    }
}

/// The first program with a non-finite constant, as an error at the joint
/// whose motion has no inertia (found by fuzzing: a point mass on a hinge's
/// axis made forward dynamics `τ / 0`, which emission cannot write).
fn not_finite(sys: &System, programs: &BTreeMap<Function, Program>) -> Result<(), FormulateError> {
    let Some((&function, _)) = programs.iter().find(|(_, p)| p.has_non_finite_constant()) else {
        return Ok(());
    };
    let found = super::numeric::singular_joint(sys).map(|s| {
        let j = &sys.joints[s.joint];
        let speed = j
            .speed_names
            .get(s.speed - j.u_index)
            .cloned()
            .unwrap_or_default();
        ((j.name.clone(), speed), j.span)
    });
    Err(FormulateError::NotFinite {
        function,
        span: found.as_ref().map(|(_, s)| *s),
        joint: found.map(|(j, _)| j),
    })
}

/// Generated straight-line programs of one system, one per generated
/// function (see [`crate::functions`]); each program's outputs are in the
/// order of its function's [`Layout`](crate::functions::Layout).
#[derive(Clone, Debug)]
pub struct Formulation {
    /// The programs, by function; functions the request leaves out (and
    /// those the model has nothing for) have none.
    pub programs: BTreeMap<Function, Program>,
    /// The form chosen for forward dynamics.
    pub fd_form: FdForm,
    /// Operation counts of both forward-dynamics forms.
    pub fd_candidates: Vec<(FdForm, OpCount)>,
    /// The form chosen for `forward_dynamics_derivatives`, when generated.
    pub derivative_form: Option<super::derivatives::DerivativeForm>,
    /// Operation counts of every form of the derivatives that applies,
    /// when generated.
    pub derivative_candidates: Vec<(super::derivatives::DerivativeForm, OpCount)>,
    /// The programs of the forms not kept (to check one form against
    /// another).
    pub derivative_alternatives: Vec<(super::derivatives::DerivativeForm, Program)>,
    /// The form chosen for `inverse_dynamics_derivatives`, when generated.
    pub id_derivative_form: Option<super::derivatives::IdDerivativeForm>,
    /// Operation counts of every form of inverse dynamics' derivatives that
    /// applies, when generated.
    pub id_derivative_candidates: Vec<(super::derivatives::IdDerivativeForm, OpCount)>,
    /// Names of the constraint equations (`joint.k`, the constraint's name,
    /// `disk.contact` / `disk.slip_x` / `disk.slip_y`); holonomic first.
    pub constraint_names: Vec<String>,
    /// How many of them are holonomic.
    pub n_holonomic: usize,
    /// Names of the model's requested outputs, in order.
    pub output_names: Vec<String>,
    /// Names of the marker Jacobians' rows (`body_marker_axis`).
    pub jacobian_rows: Vec<String>,
    /// The cut joints, in the order of `cut_joint_reactions`.
    pub cut_joints: Vec<String>,
    /// The cable mounts, in the order of `attachments` (`cable.start`,
    /// `cable.end`).
    pub mounts: Vec<String>,
    /// The contacts at cable nodes against a body's plane or sphere, in
    /// the order of `contact_frames`.
    pub frames: Vec<String>,
    /// The contacts' gap rows, in the order of `contacts` (`stop.lower`,
    /// `ball_floor`).
    pub contact_rows: Vec<String>,
    /// The tree joints, in the order of `joint_impulses`.
    pub impulse_joints: Vec<String>,
    /// The model's forward dynamics, mass matrix, bias and inverse
    /// dynamics as loops over body steps, when it is a chain
    /// ([`super::looped`]) whose straight-line programs are long enough
    /// for loops to pay ([`ChainLoops::pays`]); emission chooses per
    /// function.
    pub loops: Option<ChainLoops>,
    /// Wall time of formulation and lowering, seconds.
    pub seconds: f64,
}

impl Formulation {
    /// The program of `f`, if generated.
    pub fn program(&self, f: Function) -> Option<&Program> {
        self.programs.get(&f)
    }

    /// The functions generated, in table order.
    pub fn functions(&self) -> impl Iterator<Item = Function> + '_ {
        self.programs.keys().copied()
    }

    /// Length of the flat result of `f` for a system with `nu` speeds.
    pub fn result_len(&self, f: Function, nu: usize) -> usize {
        let outputs = self.program(f).map_or(0, |p| p.outputs.len());
        match f.entry().layout {
            Layout::Vector => outputs,
            Layout::LowerTriangle => nu * nu,
            Layout::Constraints => {
                let nc = self.constraint_names.len();
                3 * nc + nc * nu
            }
        }
    }

    /// The names of the groups of the flat result of `f` (see
    /// `eom_sim::FunctionInfo::labels`).
    pub fn labels(&self, f: Function) -> &[String] {
        match f {
            Function::Outputs => &self.output_names,
            Function::MarkerJacobians => &self.jacobian_rows,
            Function::CutJointReactions => &self.cut_joints,
            Function::Constraints => &self.constraint_names,
            Function::Attachments => &self.mounts,
            Function::ContactFrames => &self.frames,
            Function::Contacts => &self.contact_rows,
            Function::JointImpulses => &self.impulse_joints,
            Function::Friction => &self.contact_rows,
            _ => &[],
        }
    }
}

/// The names of `sys`'s coordinates, owned.
fn coordinate_names(sys: &System) -> Vec<String> {
    sys.coordinate_names()
        .into_iter()
        .map(String::from)
        .collect()
}

/// The constraint program with its equation names.
struct ConstraintProgram {
    program: Program,
    names: Vec<String>,
    n_holonomic: usize,
}

/// Parameters as the generator sees them: fixed ones as numbers, tunable
/// ones as symbols of `cx`.
pub(crate) struct SymEnv<'cx> {
    cx: &'cx Context,
    numeric: NumericEnv,
}

impl<'cx> SymEnv<'cx> {
    /// The environment of `sys`, its tunable parameters declared in `cx`.
    pub(crate) fn new(cx: &'cx Context, sys: &System) -> Result<Self, FormulateError> {
        for p in sys.parameters.iter().filter(|p| p.tunable) {
            cx.param(&p.name).map_err(|error| FormulateError::Sym {
                error,
                span: Some(p.span),
            })?;
        }
        Ok(SymEnv {
            cx,
            numeric: NumericEnv::defaults(sys),
        })
    }
}

impl<'cx> Env<Expr<'cx>> for SymEnv<'cx> {
    fn param(&self, name: &str) -> Option<Expr<'cx>> {
        if self.numeric.is_tunable(name) {
            self.cx.param(name).ok()
        } else {
            self.numeric.param(name).map(Expr::from_f64)
        }
    }
    fn is_tunable(&self, name: &str) -> bool {
        self.numeric.is_tunable(name)
    }
}

/// Multiplications, subtractions and divisions of the `LᵀDL` factorisation
/// for the parent array `lambda` if no entry were zero (Featherstone §6.5:
/// for each speed `k` and each ancestor `i`, one division and two
/// operations per ancestor of `i`).
pub fn ltdl_flops(lambda: &[Option<usize>]) -> usize {
    let depth: Vec<usize> = {
        let mut d = vec![0; lambda.len()];
        for k in 0..lambda.len() {
            d[k] = lambda[k].map_or(1, |p| d[p] + 1);
        }
        d
    };
    (0..lambda.len())
        .map(|k| {
            let mut ops = 0;
            let mut i = lambda[k];
            while let Some(ii) = i {
                ops += 1 + 2 * depth[ii];
                i = lambda[ii];
            }
            ops
        })
        .sum()
}

/// Where runtime input `k` is defined: its actuator.
fn input_span(sys: &System, k: usize) -> Option<Span> {
    sys.forces.iter().find_map(|f| match &f.element {
        ForceElement::Actuator { inputs, .. } if inputs.contains(&Some(k)) => Some(f.span),
        _ => None,
    })
}

/// A form and its program.
type Formed<F> = (F, Program);

/// The operation counts of `programs` (forms and their programs, in the
/// order of preference on a tie), and the cheapest, taken out of the list.
fn cheapest<F: Copy>(programs: &mut Vec<(F, Program)>) -> (Vec<(F, OpCount)>, Option<Formed<F>>) {
    let counts: Vec<(F, OpCount)> = programs.iter().map(|(f, p)| (*f, p.op_count())).collect();
    let best = (0..programs.len()).min_by_key(|&i| (counts[i].1.total(), i));
    (counts, best.map(|i| programs.remove(i)))
}

/// Builds the programs `request` asks for, completed by
/// [`FunctionSet::derivable`], and those the model needs (outputs,
/// constraints, reactions); programs not asked for are absent. The mass
/// matrix and bias are built symbolically only when asked for or when
/// forward dynamics may use them (the `LᵀDL` form).
pub fn formulate(sys: &System, request: FunctionSet) -> Result<Formulation, FormulateError> {
    let request = request.derivable();
    let start = Instant::now();
    let cx = Context::new();
    let env = SymEnv::new(&cx, sys)?;
    let tree = TreeModel::new(sys, &env)?;
    let applied = Applied::new(sys, &tree, &env)?;
    let ev = Evaluator::new(&tree, &applied, &env);
    let (nq, nu) = (tree.nq, tree.nu);
    let q: Vec<Expr> = (0..nq).map(|i| cx.q(i as u32)).collect();
    let u: Vec<Expr> = (0..nu).map(|i| cx.u(i as u32)).collect();
    let inputs: Vec<Expr> = sys
        .inputs
        .iter()
        .enumerate()
        .map(|(k, n)| {
            cx.input(n).map_err(|error| FormulateError::Sym {
                error,
                span: input_span(sys, k),
            })
        })
        .collect::<Result<_, _>>()?;
    let tau: Vec<Expr> = (0..nu).map(|i| cx.tau(i as u32)).collect();
    let st = State {
        q: &q,
        u: &u,
        t: cx.t(),
        inputs: &inputs,
    };
    let k = ev.kinematics(&st)?;
    let (fext, spring_energy) = ev.point_forces(&k);
    let (generalized, joint_spring_energy) = ev.generalized_forces(&st)?;
    let opts = LowerOptions::default();
    let named = |prefix: &str, v: &[Expr<'_>]| -> Vec<(String, usize)> {
        (0..v.len()).map(|i| (format!("{prefix}{i}"), i)).collect()
    };
    let lower = |prefix: &str, v: &[Expr<'_>]| -> Program {
        let names = named(prefix, v);
        let outs: Vec<(&str, Expr<'_>)> = names.iter().map(|(n, i)| (n.as_str(), v[*i])).collect();
        cx.lower(&outs, opts)
    };

    let qdot = lower("qdot", &ev.qdot(&st));
    let zero = vec![Expr::zero(); nu];
    // Built here when asked for (first, as the arena numbers them in
    // order), else on demand for the `LᵀDL` form only.
    let crba = || ev.crba(&k);
    let rnea_bias = || -> Vec<Expr> {
        let (c, _) = ev.rnea(&k, &zero, &fext);
        c.iter().zip(&generalized).map(|(&c, &g)| c - g).collect()
    };
    let mut mass = request.contains(Function::MassMatrix).then(crba);
    let mut bias = request.contains(Function::Bias).then(rnea_bias);

    // The chosen form's expressions are kept for the derivatives.
    let (forward_dynamics, fd_form, fd_candidates, udot) =
        if request.contains(Function::ForwardDynamics) {
            let drive: Vec<Expr> = generalized.iter().zip(&tau).map(|(&g, &t)| g + t).collect();
            let lambda = ev.speed_parents();
            let aba_exprs = ev.aba(&k, &drive, &fext);
            let aba = lower("udot", &aba_exprs);
            let mut candidates = vec![(FdForm::Aba, aba.op_count())];
            // The mass-matrix route costs at least its factorisation; skip
            // building it when that alone exceeds the articulated-body count
            // (long chains, where M is dense and LᵀDL is cubic).
            if ltdl_flops(&lambda) >= aba.op_count().total() {
                (Some(aba), FdForm::Aba, candidates, aba_exprs)
            } else {
                let (mut m, b) = (
                    mass.get_or_insert_with(crba).clone(),
                    bias.get_or_insert_with(rnea_bias).clone(),
                );
                ltdl(&mut m, &lambda);
                let rhs: Vec<Expr> = tau.iter().zip(&b).map(|(&t, &b)| t - b).collect();
                let sparse_exprs = ltdl_solve(&m, &lambda, rhs);
                let sparse = lower("udot", &sparse_exprs);
                candidates.push((FdForm::MassMatrix, sparse.op_count()));
                if sparse.op_count().total() < aba.op_count().total() {
                    (Some(sparse), FdForm::MassMatrix, candidates, sparse_exprs)
                } else {
                    (Some(aba), FdForm::Aba, candidates, aba_exprs)
                }
            }
        } else {
            (None, FdForm::Aba, Vec::new(), Vec::new())
        };
    // Inverse dynamics at a symbolic `u̇`, less the generalised forces.
    let inverse_at_symbolic_ud = || {
        let ud: Vec<Expr> = (0..nu).map(|i| cx.ud(i as u32)).collect();
        let (t, _) = ev.rnea(&k, &ud, &fext);
        let inverse: Vec<Expr> = t.iter().zip(&generalized).map(|(&t, &g)| t - g).collect();
        (ud, inverse)
    };
    // What both derivative blocks start from: that, `q̇`, and (where the
    // recursion applies) the loads `load torques − generalised forces`.
    let derivative_basis = || {
        let (ud, inverse) = inverse_at_symbolic_ud();
        let qdot = ev.qdot(&st);
        let loads: Option<Vec<Expr>> = ev.recursive_derivatives_apply().then(|| {
            ev.load_torques(&k, &fext)
                .iter()
                .zip(&generalized)
                .map(|(&l, &g)| l - g)
                .collect()
        });
        (ud, qdot, inverse, loads)
    };
    // Every way that applies, the one with fewer counted operations kept
    // (the first listed on a tie: differentiated forward dynamics, then
    // differentiated Newton–Euler, then its recursion in world axes, then
    // in body axes).
    let (fd_derivatives, derivative_candidates, derivative_alternatives) = if request
        .contains(Function::ForwardDynamicsDerivatives)
    {
        use super::derivatives::{
            DerivativeForm, forward_dynamics_derivatives, forward_dynamics_derivatives_recursive,
            forward_dynamics_derivatives_rnea,
        };
        use super::rnea_derivatives::Axes;
        let (ud, qdot, inverse, loads) = derivative_basis();
        let direct = forward_dynamics_derivatives(&cx, &udot, &qdot, &q, &u, &tau, &inputs, opts);
        let via_rnea = forward_dynamics_derivatives_rnea(
            &cx, &udot, &inverse, &ud, &qdot, &q, &u, &tau, &inputs, opts,
        );
        let mut programs = vec![
            (DerivativeForm::ForwardDynamics, direct),
            (DerivativeForm::InverseDynamics, via_rnea),
        ];
        if let Some(loads) = loads {
            // `∂ID/∂u` by the recursion, or differentiated (Newton–Euler
            // without the loads; free of `u̇`, as `ID` is affine in `u̇`
            // with `M(q)`): whichever counts fewer, with `M⁻¹ = ∂FD/∂τ`.
            let no_loads = vec![Force::zero(); fext.len()];
            let (inertial, _) = ev.rnea(&k, &ud, &no_loads);
            let gu_differentiated = cx.jacobian(&inertial, &u);
            let minv_fd = cx.jacobian(&udot, &tau);
            let lower_with = |minv: &[Vec<Expr>], gq: Vec<Vec<Expr>>, gu: Vec<Vec<Expr>>| {
                forward_dynamics_derivatives_recursive(
                    &cx,
                    minv,
                    (gq, gu),
                    &loads,
                    &qdot,
                    &q,
                    &u,
                    &inputs,
                    opts,
                )
            };
            let lambda = ev.speed_parents();
            let bias_rhs: Vec<Expr> = tau.iter().zip(rnea_bias()).map(|(&t, b)| t - b).collect();
            // The recursion's form in `axes`, the cheapest of its variants.
            let recursive = |axes: Axes| -> Option<Program> {
                let rd = ev.rnea_derivatives(&k, &udot, axes)?;
                let by_recursion = lower_with(&minv_fd, rd.dq.clone(), rd.du.clone());
                let mixed = lower_with(&minv_fd, rd.dq.clone(), gu_differentiated.clone());
                let (mut p, gu) = if mixed.op_count().total() < by_recursion.op_count().total() {
                    (mixed, gu_differentiated.clone())
                } else {
                    (by_recursion, rd.du.clone())
                };
                // Then `M⁻¹` from the `LᵀDL` factors of the recursion's own `M`
                // (`S_i · Yc S_j`) instead of `∂FD/∂τ`; and also `u̇` itself
                // through the same factors, `u̇ = M⁻¹ (τ − b)` with `b`
                // Newton–Euler at `u̇ = 0` (Featherstone §6.5), in place of the
                // forward dynamics kept above: each if it counts fewer.
                let mut m = rd.m.clone();
                ltdl(&mut m, &lambda);
                let minv_ltdl = ltdl_inverse(&m, &lambda);
                let factored = lower_with(&minv_ltdl, rd.dq.clone(), gu.clone());
                if factored.op_count().total() < p.op_count().total() {
                    p = factored;
                }
                let udot_ltdl = ltdl_solve(&m, &lambda, bias_rhs.clone());
                if let Some(at_ltdl) = ev.rnea_derivatives(&k, &udot_ltdl, axes) {
                    let all_ltdl = lower_with(&minv_ltdl, at_ltdl.dq, gu);
                    if all_ltdl.op_count().total() < p.op_count().total() {
                        p = all_ltdl;
                    }
                }
                Some(p)
            };
            for (form, axes) in [
                (DerivativeForm::Recursive, Axes::World),
                (DerivativeForm::RecursiveBodyAxes, Axes::Body),
                (DerivativeForm::RecursivePaths, Axes::Paths),
            ] {
                if let Some(p) = recursive(axes) {
                    programs.push((form, p));
                }
            }
        }
        let (candidates, kept) = cheapest(&mut programs);
        (kept.map(|(form, p)| (p, form)), candidates, programs)
    } else {
        (None, Vec::new(), Vec::new())
    };
    // Inverse dynamics' derivatives: differentiated Newton–Euler, or
    // `∂ID/∂(q, u)` by the recursion with `∂ID/∂u̇ = M` from its composite
    // inertias (world or body axes), whichever counts fewer operations
    // (the first listed on a tie).
    let (id_derivatives, id_derivative_candidates) =
        if request.contains(Function::InverseDynamicsDerivatives) {
            use super::derivatives::{IdDerivativeForm, inverse_dynamics_derivatives_recursive};
            use super::rnea_derivatives::Axes;
            let (ud, qdot, inverse, loads) = derivative_basis();
            let mut programs = vec![(
                IdDerivativeForm::Differentiated,
                super::derivatives::inverse_dynamics_derivatives(
                    &cx, &inverse, &ud, &qdot, &q, &u, &inputs, opts,
                ),
            )];
            if let Some(loads) = loads {
                for (form, axes) in [
                    (IdDerivativeForm::Recursive, Axes::World),
                    (IdDerivativeForm::RecursiveBodyAxes, Axes::Body),
                    (IdDerivativeForm::RecursivePaths, Axes::Paths),
                ] {
                    if let Some(rd) = ev.rnea_derivatives(&k, &ud, axes) {
                        let p = inverse_dynamics_derivatives_recursive(
                            &cx, rd, &loads, &qdot, &q, &u, &inputs, opts,
                        );
                        programs.push((form, p));
                    }
                }
            }
            let (candidates, kept) = cheapest(&mut programs);
            (kept.map(|(form, p)| (p, form)), candidates)
        } else {
            (None, Vec::new())
        };
    let (id_derivatives, id_derivative_form) = match id_derivatives {
        Some((p, form)) => (Some(p), Some(form)),
        None => (None, None),
    };
    let (fd_derivatives, derivative_form) = match fd_derivatives {
        Some((p, form)) => (Some(p), Some(form)),
        None => (None, None),
    };

    let mass_matrix = request.contains(Function::MassMatrix).then(|| {
        let m = mass.get_or_insert_with(crba).clone();
        let names: Vec<String> = (0..nu)
            .flat_map(|i| (0..=i).map(move |j| format!("m_{i}_{j}")))
            .collect();
        let vals: Vec<Expr> = (0..nu)
            .flat_map(|i| (0..=i).map(move |j| (i, j)))
            .map(|(i, j)| m[i][j])
            .collect();
        let outs: Vec<(&str, Expr<'_>)> = names.iter().map(String::as_str).zip(vals).collect();
        cx.lower(&outs, opts)
    });
    let bias_program = request
        .contains(Function::Bias)
        .then(|| lower("b", &bias.get_or_insert_with(rnea_bias).clone()));
    let inverse_dynamics = request.contains(Function::InverseDynamics).then(|| {
        let (_, tau) = inverse_at_symbolic_ud();
        lower("tau", &tau)
    });
    let energy = request.contains(Function::Energy).then(|| {
        let kinetic = ev.kinetic_energy(&k);
        let potential = ev.gravity_potential(&k) + spring_energy + joint_spring_energy;
        cx.lower(&[("kinetic", kinetic), ("potential", potential)], opts)
    });
    let momentum = request.contains(Function::Momentum).then(|| {
        let h = ev.momentum(&k);
        let outs = [
            ("lx", h.n.0[0]),
            ("ly", h.n.0[1]),
            ("lz", h.n.0[2]),
            ("px", h.f.0[0]),
            ("py", h.f.0[1]),
            ("pz", h.f.0[2]),
        ];
        cx.lower(&outs, opts)
    });
    let qdot_exprs = ev.qdot(&st);
    let closure = closure(sys, &cx, &tree, &env, &ev, &k, &q, &u, &qdot_exprs, opts)?;
    let (constraints, constraint_names, n_holonomic) = match closure {
        Some(c) => (Some(c.program), c.names, c.n_holonomic),
        None => (None, Vec::new(), 0),
    };
    // In closed loops the joint reactions include the constraint forces
    // Jᵀλ; the multipliers enter the outputs as inputs `λ<i>`.
    let reactions = sys
        .outputs
        .iter()
        .any(|o| matches!(o, OutputKind::JointReaction(_)));
    let fext_outputs = if reactions && !constraint_names.is_empty() {
        let lambda: Vec<Expr> = (0..constraint_names.len())
            .map(|i| cx.multiplier(i as u32))
            .collect();
        let cuts = super::constraints::cut_joints(sys, &tree, &env)?;
        let loads = super::constraints::constraint_body_forces(
            &sys.constraints,
            &tree,
            &env,
            &k,
            &cuts,
            &lambda,
        )?;
        fext.iter().zip(loads).map(|(&a, b)| a + b).collect()
    } else {
        fext.clone()
    };
    let out = outputs(sys, &cx, &ev, &tree, &k, &fext_outputs, opts)?;
    // The cut joints' reactions from the multipliers of their rows (the
    // cut joints' equations come first).
    let cuts = super::constraints::cut_joints(sys, &tree, &env)?;
    let (cut_reactions, cut_joints) = if cuts.is_empty() {
        (None, Vec::new())
    } else {
        let mut names = Vec::new();
        let mut values = Vec::new();
        let mut row = 0;
        for c in &cuts {
            let n = c.equations.len();
            let lambda: Vec<Expr> = (row..row + n).map(|r| cx.multiplier(r as u32)).collect();
            row += n;
            let (f, m) = super::constraints::cut_reaction(&tree, &k, c, &lambda);
            for (a, &e) in ["fx", "fy", "fz", "nx", "ny", "nz"]
                .iter()
                .zip(f.0.iter().chain(&m.0))
            {
                names.push(format!("{}_{a}", c.name));
                values.push(e);
            }
        }
        let outs: Vec<(&str, Expr<'_>)> = names.iter().map(String::as_str).zip(values).collect();
        (
            Some(cx.lower(&outs, opts)),
            cuts.iter().map(|c| c.name.clone()).collect(),
        )
    };
    // The markers holding cable ends: values and their Jacobians ∂/∂q.
    let (attachments, mounts) = if sys.cable_mounts().is_empty() {
        (None, Vec::new())
    } else {
        let values = super::mounts::mount_values(sys, &tree, &env, &k)?;
        let mut names = Vec::new();
        let mut exprs = Vec::new();
        for (r, &v) in values.iter().enumerate() {
            names.push(format!("a{r}"));
            exprs.push(v);
            for (kk, &qk) in q.iter().enumerate() {
                names.push(format!("a{r}_q{kk}"));
                exprs.push(cx.diff(v, qk));
            }
        }
        let outs: Vec<(&str, Expr<'_>)> = names.iter().map(String::as_str).zip(exprs).collect();
        let labels = sys
            .cable_mounts()
            .iter()
            .map(|(c, end, _)| {
                format!(
                    "{}.{}",
                    sys.cables[*c].name,
                    if *end { "end" } else { "start" }
                )
            })
            .collect();
        (Some(cx.lower(&outs, opts)), labels)
    };
    let contact_frames = contact_frames(sys, &cx, &tree, &env, &ev, &k, &q, &u, &qdot_exprs, opts)?;
    let contacts = contacts(sys, &cx, &tree, &env, &ev, &k, &q, &u, &qdot_exprs, opts)?;
    let friction = friction(sys, &cx, &tree, &env, &ev, &k, &q, &u, &qdot_exprs, opts)?;
    let (joint_impulses, impulse_joints) = joint_impulses(sys, &cx, &tree, &env, &ev, &k, opts)?;
    let programs: BTreeMap<Function, Program> = [
        (Function::Qdot, Some(qdot)),
        (Function::ForwardDynamics, forward_dynamics),
        (Function::MassMatrix, mass_matrix),
        (Function::Bias, bias_program),
        (Function::InverseDynamics, inverse_dynamics),
        (Function::Energy, energy),
        (Function::Momentum, momentum),
        (Function::Outputs, out.outputs),
        (Function::MarkerJacobians, out.jacobians),
        (Function::Constraints, constraints),
        (Function::CutJointReactions, cut_reactions),
        (Function::Attachments, attachments),
        (Function::Contacts, contacts),
        (Function::ContactFrames, contact_frames),
        (Function::JointImpulses, joint_impulses),
        (Function::Friction, friction),
        (Function::ForwardDynamicsDerivatives, fd_derivatives),
        (Function::InverseDynamicsDerivatives, id_derivatives),
    ]
    .into_iter()
    .filter_map(|(f, p)| p.map(|p| (f, p)))
    .collect();
    not_finite(sys, &programs)?;
    // Loops only where some straight-line program outgrows the cache.
    let long = LOOPED.iter().any(|f| {
        programs
            .get(f)
            .is_some_and(|p| p.op_count().total() >= LOOP_MIN_OPS)
    });
    let loops = if long {
        ChainLoops::build(sys, request)?
    } else {
        None
    };
    Ok(Formulation {
        programs,
        fd_form,
        fd_candidates,
        derivative_form,
        derivative_candidates,
        derivative_alternatives,
        id_derivative_form,
        id_derivative_candidates,
        constraint_names,
        n_holonomic,
        output_names: out.names,
        jacobian_rows: out.jacobian_rows,
        cut_joints,
        mounts,
        frames: sys
            .cable_contacts
            .iter()
            .filter(|c| c.against.on_body().is_some())
            .map(|c| c.name.clone())
            .collect(),
        contact_rows: sys.contact_rows().into_iter().map(|(_, r)| r).collect(),
        impulse_joints,
        loops,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// A flexible body's data, its state and its index in the tree.
fn flex_of<'a, 'cx>(
    sys: &'a System,
    tree: &TreeModel<Expr<'cx>>,
    k: &'a Kinematics<Expr<'cx>>,
    body: usize,
) -> Option<(
    &'a crate::system::FlexInfo,
    &'a super::flex_state::FlexState<Expr<'cx>>,
    usize,
)> {
    let i = tree.index_of_body[body]?;
    Some((
        sys.bodies[body].flexible.as_deref()?,
        k.flex[i].as_ref()?,
        i,
    ))
}

/// The programs of the outputs and marker Jacobians, with their names.
struct OutputPrograms {
    outputs: Option<Program>,
    jacobians: Option<Program>,
    names: Vec<String>,
    jacobian_rows: Vec<String>,
}

/// Programs for the model's requested outputs and marker Jacobians.
fn outputs<'cx>(
    sys: &System,
    cx: &'cx Context,
    ev: &Evaluator<'_, Expr<'cx>>,
    tree: &TreeModel<Expr<'cx>>,
    k: &Kinematics<Expr<'cx>>,
    fext: &[Force<Expr<'cx>>],
    opts: LowerOptions,
) -> Result<OutputPrograms, FormulateError> {
    if sys.outputs.is_empty() {
        return Ok(OutputPrograms {
            outputs: None,
            jacobians: None,
            names: Vec::new(),
            jacobian_rows: Vec::new(),
        });
    }
    let low = super::lower::Lowering::new(ev.env);
    let mut names: Vec<String> = Vec::new();
    let mut values: Vec<Expr<'cx>> = Vec::new();
    let mut jac_names: Vec<String> = Vec::new();
    let mut jac_values: Vec<Expr<'cx>> = Vec::new();
    let mut jac_rows: Vec<String> = Vec::new();
    let mut reactions: Option<Vec<Force<Expr<'cx>>>> = None;
    let axes = ["x", "y", "z"];
    for out in &sys.outputs {
        match *out {
            OutputKind::Position(b, m) | OutputKind::Velocity(b, m) => {
                let marker = &sys.bodies[b].markers[m];
                let site = super::applied::Site {
                    body: tree.index_of_body[b],
                    node: marker.node,
                    point: low.vec3(&marker.frame.position)?,
                };
                let (x, v) = ev.site(k, &site);
                let tag = format!("{}_{}", sys.bodies[b].name, marker.name);
                if matches!(out, OutputKind::Position(..)) {
                    for (a, &e) in axes.iter().zip(&x.0) {
                        names.push(format!("{tag}_{a}"));
                        values.push(e);
                    }
                    for (a, &e) in axes.iter().zip(&v.0) {
                        jac_rows.push(format!("{tag}_{a}"));
                        for kk in 0..tree.nu {
                            jac_names.push(format!("J_{tag}_{a}_{kk}"));
                            jac_values.push(cx.diff(e, cx.u(kk as u32)));
                        }
                    }
                } else {
                    for (a, &e) in axes.iter().zip(&v.0) {
                        names.push(format!("{tag}_v{a}"));
                        values.push(e);
                    }
                }
            }
            OutputKind::JointReaction(j) => {
                let joint = &sys.joints[j];
                let Some(i) =
                    tree.index_of_body[joint.child].filter(|&i| tree.bodies[i].joint == j)
                else {
                    // Cut joints transmit the constraint forces λ (closed-loop formulation).
                    continue;
                };
                let f = reactions
                    .get_or_insert_with(|| {
                        let ud: Vec<Expr> = (0..tree.nu).map(|i| cx.ud(i as u32)).collect();
                        ev.rnea(k, &ud, fext).1
                    })
                    .get(i)
                    .copied()
                    .unwrap_or_else(Force::zero);
                // Into the child joint frame C at its origin: n_C = Rᵀ(n − p × f), f_C = Rᵀ f.
                let fc = tree.bodies[i].frame_child;
                let (n, force) = (fc.e.tr_mul_vec(f.n - fc.r.cross(f.f)), fc.e.tr_mul_vec(f.f));
                for (a, &e) in axes.iter().zip(&force.0) {
                    names.push(format!("{}_f{a}", joint.name));
                    values.push(e);
                }
                for (a, &e) in axes.iter().zip(&n.0) {
                    names.push(format!("{}_n{a}", joint.name));
                    values.push(e);
                }
            }
            OutputKind::Energy | OutputKind::Momentum => {}
            OutputKind::Deformation { body, x, ref name }
            | OutputKind::SectionForces { body, x, ref name } => {
                let Some((flex, fs, i)) = flex_of(sys, tree, k, body) else {
                    continue;
                };
                let Some(fm) = &tree.bodies[i].flex else {
                    continue;
                };
                let (vals, tags) = if matches!(out, OutputKind::Deformation { .. }) {
                    (
                        super::flex_outputs::deformation(flex, x, &fs.q),
                        ["ux", "uy", "uz", "rx", "ry", "rz"],
                    )
                } else {
                    (
                        super::flex_outputs::section_forces(flex, &fm.section, x, &fs.q),
                        ["N", "Qy", "Qz", "Mx", "My", "Mz"],
                    )
                };
                for (t, v) in tags.iter().zip(vals) {
                    names.push(format!("{name}_{t}"));
                    values.push(v);
                }
            }
            OutputKind::NodePosition { body, node } => {
                let Some((flex, fs, i)) = flex_of(sys, tree, k, body) else {
                    continue;
                };
                let p = k.world[i].point(super::flex_outputs::node_point(flex, node, &fs.q));
                for (a, &e) in axes.iter().zip(&p.0) {
                    names.push(format!("{}_node{node}_{a}", sys.bodies[body].name));
                    values.push(e);
                }
            }
            OutputKind::ElasticEnergy(body) => {
                let Some((_, fs, i)) = flex_of(sys, tree, k, body) else {
                    continue;
                };
                if let Some(fm) = &tree.bodies[i].flex {
                    names.push(format!("{}_strain_energy", sys.bodies[body].name));
                    values.push(fm.elastic_forces(&fs.q, &fs.qd).1);
                }
            }
        }
    }
    let lower = |names: &[String], values: &[Expr<'cx>]| -> Option<Program> {
        (!names.is_empty()).then(|| {
            let outs: Vec<(&str, Expr<'cx>)> = names
                .iter()
                .map(String::as_str)
                .zip(values.iter().copied())
                .collect();
            cx.lower(&outs, opts)
        })
    };
    Ok(OutputPrograms {
        outputs: lower(&names, &values),
        jacobians: lower(&jac_names, &jac_values),
        names,
        jacobian_rows: jac_rows,
    })
}

/// `Φ`, `Φ̇`, `γ` and `J` of the cut joints and the model's constraints
/// (see [`Formulation::constraints`]), with the equation names and the
/// number of holonomic equations.
#[allow(clippy::too_many_arguments)]
fn closure<'cx>(
    sys: &System,
    cx: &'cx Context,
    tree: &TreeModel<Expr<'cx>>,
    env: &dyn Env<Expr<'cx>>,
    ev: &Evaluator<'_, Expr<'cx>>,
    k: &Kinematics<Expr<'cx>>,
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    opts: LowerOptions,
) -> Result<Option<ConstraintProgram>, FormulateError> {
    use crate::sym::TimeDerivative;
    let cuts = super::constraints::cut_joints(sys, tree, env)?;
    let phi = super::constraints::phi(tree, k, &cuts);
    let mut holonomic: Vec<(String, Expr<'cx>)> = Vec::new();
    let mut row = 0;
    for c in &cuts {
        for e in 0..c.equations.len() {
            holonomic.push((format!("{}.{e}", c.name), phi[row + e]));
        }
        row += c.equations.len();
    }
    let (user_h, user_nh) = super::constraints::user_constraints(
        &sys.constraints,
        &coordinate_names(sys),
        tree,
        env,
        ev,
        k,
        q,
        cx.t(),
    )?;
    holonomic.extend(user_h);
    if holonomic.is_empty() && user_nh.is_empty() {
        return Ok(None);
    }
    // q̇ along the motion: q_i → (N(q) u)_i; for γ also u̇ = 0.
    let mut first = TimeDerivative::new();
    for (qi, qd) in q.iter().zip(qdot) {
        if let Some(s) = cx.sym_id(*qi) {
            first.rate(s, cx.id(*qd));
        }
    }
    let mut second = at_rest_along_the_motion(cx, q, u, qdot);
    let mut names = Vec::new();
    let mut values = Vec::new();
    let mut phidots = Vec::new();
    let n_holonomic = holonomic.len();
    let mut equation_names = Vec::new();
    for (i, (name, p)) in holonomic.iter().chain(&user_nh).enumerate() {
        let (p, pd) = if i < n_holonomic {
            (*p, cx.time_derivative(&mut first, *p)?)
        } else {
            (Expr::zero(), *p)
        };
        let pdd = cx.time_derivative(&mut second, pd)?;
        names.push(format!("phi{i}"));
        values.push(p);
        names.push(format!("phidot{i}"));
        values.push(pd);
        names.push(format!("gamma{i}"));
        values.push(-pdd);
        phidots.push(pd);
        equation_names.push(name.clone());
    }
    for (i, &pd) in phidots.iter().enumerate() {
        for (kk, &uk) in u.iter().enumerate() {
            names.push(format!("J_{i}_{kk}"));
            values.push(cx.diff(pd, uk));
        }
    }
    let outs: Vec<(&str, Expr<'cx>)> = names.iter().map(String::as_str).zip(values).collect();
    Ok(Some(ConstraintProgram {
        program: cx.lower(&outs, opts),
        names: equation_names,
        n_holonomic,
    }))
}

/// `d/dt` along the motion with `u̇ = 0`: `q_i → (N(q) u)_i`, `u_i → 0`;
/// applied to a row's speed `ẋ = w(q) u` it gives `−γ` (`ẍ = wᵀ u̇ − γ`).
fn at_rest_along_the_motion<'cx>(
    cx: &'cx Context,
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
) -> crate::sym::TimeDerivative {
    let mut d = crate::sym::TimeDerivative::new();
    for (qi, qd) in q.iter().zip(qdot) {
        if let Some(s) = cx.sym_id(*qi) {
            d.rate(s, cx.id(*qd));
        }
    }
    let zero = cx.id(Expr::zero());
    for ui in u {
        if let Some(s) = cx.sym_id(*ui) {
            d.rate(s, zero);
        }
    }
    d
}

/// The program of `contacts` (see [`crate::functions`]): per gap row `g`,
/// then per row `ġ`, then per row `γ = −d(ġ)/dt` at `u̇ = 0` (so that
/// `g̈ = wᵀ u̇ − γ`), per row `e` and `μ`, then the rows `w = ∂ġ/∂u`;
/// `None` without contacts.
#[allow(clippy::too_many_arguments)]
fn contacts<'cx>(
    sys: &System,
    cx: &'cx Context,
    tree: &TreeModel<Expr<'cx>>,
    env: &dyn Env<Expr<'cx>>,
    ev: &Evaluator<'_, Expr<'cx>>,
    k: &Kinematics<Expr<'cx>>,
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    opts: LowerOptions,
) -> Result<Option<Program>, FormulateError> {
    if sys.contacts.is_empty() {
        return Ok(None);
    }
    let rows = super::contacts::gaps(sys, tree, env, ev, k, q, u)?;
    // q̇ along the motion: q_i → (N(q) u)_i, and u̇ = 0.
    let mut second = at_rest_along_the_motion(cx, q, u, qdot);
    let mut names = Vec::new();
    let mut values = Vec::new();
    for (i, (g, _)) in rows.iter().enumerate() {
        names.push(format!("g{i}"));
        values.push(*g);
    }
    for (i, (_, gd)) in rows.iter().enumerate() {
        names.push(format!("gdot{i}"));
        values.push(*gd);
    }
    for (i, (_, gd)) in rows.iter().enumerate() {
        names.push(format!("gamma{i}"));
        values.push(-cx.time_derivative(&mut second, *gd)?);
    }
    // The contact laws travel with the model: Newton's `e`, Coulomb's `μ`.
    let laws: Vec<(f64, f64)> = sys
        .contact_rows()
        .iter()
        .map(|(c, _)| (sys.contacts[*c].e, sys.contacts[*c].mu))
        .collect();
    for (i, (e, _)) in laws.iter().enumerate() {
        names.push(format!("e{i}"));
        values.push(Expr::from_f64(*e));
    }
    for (i, (_, mu)) in laws.iter().enumerate() {
        names.push(format!("mu{i}"));
        values.push(Expr::from_f64(*mu));
    }
    for (i, (_, gd)) in rows.iter().enumerate() {
        for (kk, &uk) in u.iter().enumerate() {
            names.push(format!("w_{i}_{kk}"));
            values.push(cx.diff(*gd, uk));
        }
    }
    let outs: Vec<(&str, Expr<'cx>)> = names.iter().map(String::as_str).zip(values).collect();
    Ok(Some(cx.lower(&outs, opts)))
}

/// The program of `contact_frames` (see [`crate::functions`]): per frame
/// of `System::cable_frames` the values of
/// [`super::mounts::frame_values`] (`p`, `e`, `ṗ`, `ω`), then the rates
/// of `ṗ` and `ω` at `u̇ = 0` (`p̈ − J_p u̇`, `ω̇ − J_ω u̇`), then the rows
/// `J_p = ∂ṗ/∂u` (3 × `NU`) and `J_ω = ∂ω/∂u` (3 × `NU`); `None` without
/// such frames.
#[allow(clippy::too_many_arguments)]
fn contact_frames<'cx>(
    sys: &System,
    cx: &'cx Context,
    tree: &TreeModel<Expr<'cx>>,
    env: &dyn Env<Expr<'cx>>,
    ev: &Evaluator<'_, Expr<'cx>>,
    k: &Kinematics<Expr<'cx>>,
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    opts: LowerOptions,
) -> Result<Option<Program>, FormulateError> {
    if sys.cable_frames().is_empty() {
        return Ok(None);
    }
    let values = super::mounts::frame_values(sys, tree, env, ev, k)?;
    let mut second = at_rest_along_the_motion(cx, q, u, qdot);
    let mut names = Vec::new();
    let mut exprs = Vec::new();
    for (f, block) in values.chunks(super::mounts::FRAME_VALUES).enumerate() {
        for (r, &v) in block.iter().enumerate() {
            names.push(format!("f{f}_{r}"));
            exprs.push(v);
        }
        // ṗ and ω, the last six values: their rates, then their rows.
        let speeds = &block[12..];
        for (r, &v) in speeds.iter().enumerate() {
            names.push(format!("f{f}_rate{r}"));
            exprs.push(cx.time_derivative(&mut second, v)?);
        }
        for (r, &v) in speeds.iter().enumerate() {
            for (kk, &uk) in u.iter().enumerate() {
                names.push(format!("f{f}_j{r}_{kk}"));
                exprs.push(cx.diff(v, uk));
            }
        }
    }
    let outs: Vec<(&str, Expr<'cx>)> = names.iter().map(String::as_str).zip(exprs).collect();
    Ok(Some(cx.lower(&outs, opts)))
}

/// The program of `friction` (see [`crate::functions`]): per gap row the
/// tangential speeds `v_t1`, `v_t2` of the touching point, then `γ_t1`,
/// `γ_t2` (`−dv_t/dt` at `u̇ = 0`), then the rows `W_t1 = ∂v_t1/∂u` and
/// `W_t2 = ∂v_t2/∂u`; `None` unless a contact has friction.
#[allow(clippy::too_many_arguments)]
fn friction<'cx>(
    sys: &System,
    cx: &'cx Context,
    tree: &TreeModel<Expr<'cx>>,
    env: &dyn Env<Expr<'cx>>,
    ev: &Evaluator<'_, Expr<'cx>>,
    k: &Kinematics<Expr<'cx>>,
    q: &[Expr<'cx>],
    u: &[Expr<'cx>],
    qdot: &[Expr<'cx>],
    opts: LowerOptions,
) -> Result<Option<Program>, FormulateError> {
    if !super::contacts::has_friction(sys) {
        return Ok(None);
    }
    let rows = super::contacts::tangential_speeds(sys, tree, env, ev, k)?;
    let mut second = at_rest_along_the_motion(cx, q, u, qdot);
    let mut names = Vec::new();
    let mut values = Vec::new();
    for a in 0..2 {
        for (i, v) in rows.iter().enumerate() {
            names.push(format!("vt{}_{i}", a + 1));
            values.push(v[a]);
        }
    }
    for a in 0..2 {
        for (i, v) in rows.iter().enumerate() {
            names.push(format!("gamma_t{}_{i}", a + 1));
            values.push(-cx.time_derivative(&mut second, v[a])?);
        }
    }
    for a in 0..2 {
        for (i, v) in rows.iter().enumerate() {
            for (kk, &uk) in u.iter().enumerate() {
                names.push(format!("wt{}_{i}_{kk}", a + 1));
                values.push(cx.diff(v[a], uk));
            }
        }
    }
    let outs: Vec<(&str, Expr<'cx>)> = names.iter().map(String::as_str).zip(values).collect();
    Ok(Some(cx.lower(&outs, opts)))
}

/// The program of `joint_impulses` (see [`crate::functions`]): the spatial
/// force RNEA's backward pass gives each tree joint for the accelerations
/// `Δu` (the `udot` symbols) minus that at `Δu = 0` — velocity terms and
/// gravity cancel, leaving `Σ I Δv` over the bodies the joint carries —,
/// then per contact row the same difference for a unit normal impulse and
/// no `Δu` (the row's load, with its sign in the transmitted force); all in
/// the child joint frame as `JointReaction`. `None` without contacts.
fn joint_impulses<'cx>(
    sys: &System,
    cx: &'cx Context,
    tree: &TreeModel<Expr<'cx>>,
    env: &dyn Env<Expr<'cx>>,
    ev: &Evaluator<'_, Expr<'cx>>,
    k: &Kinematics<Expr<'cx>>,
    opts: LowerOptions,
) -> Result<(Option<Program>, Vec<String>), FormulateError> {
    if sys.contacts.is_empty() {
        return Ok((None, Vec::new()));
    }
    let zero_loads = vec![Force::zero(); tree.loads()];
    let zero_u = vec![Expr::zero(); tree.nu];
    let du: Vec<Expr> = (0..tree.nu).map(|i| cx.ud(i as u32)).collect();
    let (_, base) = ev.rnea(k, &zero_u, &zero_loads);
    let in_child = |i: usize, f: Force<Expr<'cx>>| -> [Expr<'cx>; 6] {
        let fc = tree.bodies[i].frame_child;
        let (n, force) = (fc.e.tr_mul_vec(f.n - fc.r.cross(f.f)), fc.e.tr_mul_vec(f.f));
        [force.0[0], force.0[1], force.0[2], n.0[0], n.0[1], n.0[2]]
    };
    let mut names = Vec::new();
    let mut values = Vec::new();
    let comps = ["fx", "fy", "fz", "nx", "ny", "nz"];
    let mut block = |tag: &str, loads: &[Force<Expr<'cx>>], ud: &[Expr<'cx>]| {
        let (_, f) = ev.rnea(k, ud, loads);
        for i in 0..tree.bodies.len() {
            let diff = Force {
                n: f[i].n - base[i].n,
                f: f[i].f - base[i].f,
            };
            for (c, v) in comps.iter().zip(in_child(i, diff)) {
                names.push(format!(
                    "{tag}_{}_{c}",
                    sys.joints[tree.bodies[i].joint].name
                ));
                values.push(v);
            }
        }
    };
    block("dh", &zero_loads, &du);
    for (r, loads) in super::contacts::unit_loads(sys, tree, env, ev, k)?
        .iter()
        .enumerate()
    {
        block(&format!("c{r}"), loads, &zero_u);
    }
    // With friction: per row the unit tangential impulses along t₁, t₂.
    if super::contacts::has_friction(sys) {
        let tangential = super::contacts::tangential_unit_loads(sys, tree, env, ev, k)?;
        for a in 0..2 {
            for (r, pair) in tangential.iter().enumerate() {
                block(&format!("t{}_{r}", a + 1), &pair[a], &zero_u);
            }
        }
    }
    let joints = tree
        .bodies
        .iter()
        .map(|b| sys.joints[b.joint].name.clone())
        .collect();
    let outs: Vec<(&str, Expr<'cx>)> = names.iter().map(String::as_str).zip(values).collect();
    Ok((Some(cx.lower(&outs, opts)), joints))
}
