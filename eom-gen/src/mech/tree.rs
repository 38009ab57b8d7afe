//! The mechanism as the recursive algorithms see it: bodies in tree order
//! with their joint models, constant frame transforms and inertias, over
//! any [`Scalar`].
//!
//! Built from a validated [`System`] and an [`Env`] that says what each
//! parameter is: on `f64` every parameter is a number (the reference
//! numerics); symbolically, fixed parameters are inlined as constants (so
//! zeros and ones vanish from the generated code) and tunable ones are
//! symbols. Quantities that use only fixed parameters are taken at their
//! value, so the symbolic graph never sees their arithmetic.

use super::flexible::FlexModel;
use super::joint::JointModel;
use super::spatial::{Pose, RigidInertia};
use crate::diag::{Diagnostic, Span};
use crate::expr::{Ast, BinOp, Func};
use crate::graph::{BodyId, JointId};
use crate::sym::{Mat3, Scalar, Vec3};
use crate::system::{
    FrameInfo, JointType, Motion as JointMotion, Quantity, Rotation, System, Vec3Q,
};
use std::fmt;

/// What names in model expressions stand for.
pub trait Env<S> {
    /// The value or symbol of parameter `name` (`None` if unknown).
    fn param(&self, name: &str) -> Option<S>;
    /// True if the parameter is tunable (kept symbolic when generating).
    fn is_tunable(&self, name: &str) -> bool;
}

/// Parameters as numbers: defaults, optionally overridden.
#[derive(Clone, Debug, Default)]
pub struct NumericEnv {
    values: Vec<(String, f64)>,
    tunable: Vec<String>,
}

impl NumericEnv {
    /// Every parameter of `sys` at its default (derived parameters are
    /// recomputed from the others, in file order).
    pub fn defaults(sys: &System) -> Self {
        Self::with(sys, &[])
    }

    /// Defaults with some tunable parameters set to other values.
    pub fn with(sys: &System, overrides: &[(&str, f64)]) -> Self {
        let mut env = NumericEnv::default();
        for p in &sys.parameters {
            let given = overrides
                .iter()
                .find(|(n, _)| *n == p.name)
                .map(|(_, v)| *v);
            let value = given.unwrap_or_else(|| {
                p.value
                    .expr
                    .eval(&|n: &str| env.param(n))
                    .unwrap_or(p.value.value)
            });
            env.values.push((p.name.clone(), value));
            if p.tunable {
                env.tunable.push(p.name.clone());
            }
        }
        env
    }
}

impl Env<f64> for NumericEnv {
    fn param(&self, name: &str) -> Option<f64> {
        self.values
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    }
    fn is_tunable(&self, name: &str) -> bool {
        self.tunable.iter().any(|n| n == name)
    }
}

/// Why a system cannot be formulated, with the span in the model file of
/// what caused it.
#[derive(Clone, Debug, PartialEq)]
pub enum MechError {
    /// An expression uses a name with no value here.
    UnknownName {
        /// The name.
        name: String,
        /// The expression that uses it.
        span: Span,
    },
    /// A joint axis depends on a tunable parameter (axes are inlined).
    TunableAxis {
        /// The joint.
        joint: String,
        /// The axis component that uses a tunable parameter.
        span: Span,
    },
    /// A field of a flexible body that cannot follow a tunable parameter
    /// (the mesh, the shapes: the basis is built once; the modal damping
    /// of a basis that is not the beam's normal modes).
    TunableFlex {
        /// The body.
        body: String,
        /// The field as written (`length`, `shapes`, `damping`).
        field: &'static str,
        /// Why it must be fixed.
        why: &'static str,
        /// The field that uses a tunable parameter.
        span: Span,
    },
}

impl MechError {
    /// Where in the model file.
    pub fn span(&self) -> Span {
        match self {
            MechError::UnknownName { span, .. }
            | MechError::TunableAxis { span, .. }
            | MechError::TunableFlex { span, .. } => *span,
        }
    }

    /// What would be right.
    pub fn help(&self) -> &'static str {
        match self {
            MechError::UnknownName { .. } => {
                "this field may use parameters, and where the field allows them `t`, coordinates and speeds"
            }
            MechError::TunableAxis { .. } => {
                "make the parameters in the axis fixed (`tunable: false`, or `fixed` in a scene)"
            }
            MechError::TunableFlex {
                field: "damping", ..
            } => {
                "give `damping: 0`, or make the section data fixed (`tunable: false`, or `fixed` in a scene)"
            }
            MechError::TunableFlex {
                field: "section data of a Timoshenko beam",
                ..
            } => {
                "make the beam's parameters fixed (`tunable: false`, or `fixed` in a scene), or drop `shear` (an Euler–Bernoulli beam's section data may be tunable)"
            }
            MechError::TunableFlex { .. } => {
                "make this field's parameters fixed (`tunable: false`, or `fixed` in a scene); the section data `rho_a`, `rho_ip`, `ea`, `ei_y`, `ei_z`, `gj` and the `damping` ratio may be tunable"
            }
        }
    }

    /// The error as a diagnostic at its span.
    pub fn diagnostic(&self) -> Diagnostic {
        Diagnostic::error(self.span(), self.to_string()).with_help(self.help())
    }
}

impl fmt::Display for MechError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MechError::UnknownName { name, .. } => {
                write!(f, "`{name}` has no value in this expression")
            }
            MechError::TunableAxis { joint, .. } => write!(
                f,
                "the axis of joint `{joint}` depends on a tunable parameter; joint axes must be fixed"
            ),
            MechError::TunableFlex {
                body,
                field: "damping",
                why,
                ..
            } => write!(
                f,
                "the `damping` of flexible body `{body}` cannot be kept with tunable section data: {why}"
            ),
            MechError::TunableFlex {
                body, field, why, ..
            } => write!(
                f,
                "`{field}` of flexible body `{body}` depends on a tunable parameter: {why}"
            ),
        }
    }
}

impl std::error::Error for MechError {}

/// Turns a model expression written at `span` into a scalar; `lookup`
/// gives every name but `pi`. `asin`, `acos` and `atan` become `atan2`,
/// non-integer powers `exp(b ln a)`.
pub fn lower_ast<S: Scalar>(
    ast: &Ast,
    span: Span,
    lookup: &dyn Fn(&str) -> Option<S>,
) -> Result<S, MechError> {
    let lower = |a: &Ast| lower_ast(a, span, lookup);
    Ok(match ast {
        Ast::Num(v) => S::from_f64(*v),
        Ast::Var(name, _) if name == "pi" => S::from_f64(std::f64::consts::PI),
        Ast::Var(name, _) => lookup(name).ok_or_else(|| MechError::UnknownName {
            name: name.clone(),
            span,
        })?,
        Ast::Neg(a) => -lower(a)?,
        Ast::Bin(op, a, b) => {
            let x = lower(a)?;
            if let (BinOp::Pow, Ast::Num(n)) = (op, &**b)
                && n.fract() == 0.0
                && n.abs() <= 64.0
            {
                return Ok(x.powi(*n as i32));
            }
            let y = lower(b)?;
            match op {
                BinOp::Add => x + y,
                BinOp::Sub => x - y,
                BinOp::Mul => x * y,
                BinOp::Div => x / y,
                BinOp::Pow => (y * x.ln()).exp(),
            }
        }
        Ast::Call(Func::Select, args, _) => {
            let arg = |k: usize| args.get(k).map_or(Ok(S::zero()), lower);
            S::select(arg(0)?, arg(1)?, arg(2)?)
        }
        Ast::Call(f, args, _) => {
            let x = lower(&args[0])?;
            let one = S::one();
            match f {
                Func::Sin => x.sin(),
                Func::Cos => x.cos(),
                Func::Tan => x.tan(),
                Func::Asin => x.atan2((one - x * x).sqrt()),
                Func::Acos => (one - x * x).sqrt().atan2(x),
                Func::Atan => x.atan2(one),
                Func::Atan2 => {
                    let y = match args.get(1) {
                        Some(a) => lower(a)?,
                        None => one,
                    };
                    x.atan2(y)
                }
                Func::Sqrt => x.sqrt(),
                Func::Exp => x.exp(),
                Func::Ln => x.ln(),
                Func::Abs => x.abs(),
                Func::Select => x, // handled above
            }
        }
    })
}

/// How a tree joint's coordinates are known.
#[derive(Clone, Debug)]
pub enum Coords {
    /// System coordinates `q[q..q+nq]`, speeds `u[u..u+nu]`.
    Free {
        /// First coordinate index.
        q: usize,
        /// First speed index.
        u: usize,
    },
    /// Held at constant values.
    Locked(Vec<f64>),
    /// Known functions of time: position, rate and acceleration per coordinate.
    Prescribed {
        /// `q(t)`.
        q: Vec<Ast>,
        /// `q̇(t)`.
        qd: Vec<Ast>,
        /// `q̈(t)`.
        qdd: Vec<Ast>,
        /// Where each `q(t)` is written.
        spans: Vec<Span>,
    },
}

/// One body of the tree with the joint above it.
#[derive(Clone, Debug)]
pub struct TreeBody<S> {
    /// The body in the [`System`].
    pub body: BodyId,
    /// The joint above it in the [`System`].
    pub joint: JointId,
    /// Index of the parent in the tree order (`None`: ground).
    pub parent: Option<usize>,
    /// The joint.
    pub kind: JointModel<S>,
    /// Joint frame on the parent, in parent body coordinates.
    pub frame_parent: Pose<S>,
    /// Joint frame on the child, in child body coordinates.
    pub frame_child: Pose<S>,
    /// Inertia about the body origin in body coordinates (of a flexible
    /// body: the rigid part its frame carries).
    pub inertia: RigidInertia<S>,
    /// How its coordinates are known.
    pub coords: Coords,
    /// The deformable part of a flexible body.
    pub flex: Option<FlexModel<S>>,
    /// On a flexible parent: the slot in its [`FlexModel::nodes`] of the
    /// node the joint is attached to.
    pub node: Option<usize>,
    /// Index in the load vectors of this body's first node slot (loads
    /// on the bodies come first, then those on nodes; see
    /// [`TreeModel::loads`]).
    pub node_loads: usize,
}

/// The tree over scalar `S`.
#[derive(Clone, Debug)]
pub struct TreeModel<S> {
    /// Bodies in tree order (parents before children).
    pub bodies: Vec<TreeBody<S>>,
    /// Gravity in world coordinates.
    pub gravity: Vec3<S>,
    /// Tree index of each system body (`None` for ground).
    pub index_of_body: Vec<Option<usize>>,
    /// Number of position coordinates.
    pub nq: usize,
    /// Number of speeds.
    pub nu: usize,
}

impl<S: Scalar> TreeModel<S> {
    /// Length of a load vector (`fext`): one spatial force per body (body
    /// coordinates at its origin), then one per attached node of each
    /// flexible body (node coordinates at the node), in tree order.
    pub fn loads(&self) -> usize {
        self.bodies.len()
            + self
                .bodies
                .iter()
                .filter_map(|b| b.flex.as_ref())
                .map(|f| f.nodes.len())
                .sum::<usize>()
    }

    /// True if a marker or a joint attaches to a node of a flexible body.
    pub fn has_nodes(&self) -> bool {
        self.bodies
            .iter()
            .any(|b| b.flex.as_ref().is_some_and(|f| !f.nodes.is_empty()))
    }

    /// The load slot of beam node `node` on tree body `i`, if attached.
    pub fn node_load(&self, i: usize, node: usize) -> Option<usize> {
        let b = &self.bodies[i];
        b.flex
            .as_ref()
            .and_then(|f| f.node_slot(node))
            .map(|s| b.node_loads + s)
    }
}

/// Values of quantities under an environment.
pub struct Lowering<'a, S> {
    env: &'a dyn Env<S>,
}

impl<'a, S: Scalar> Lowering<'a, S> {
    /// Lowering with `env`.
    pub fn new(env: &'a dyn Env<S>) -> Self {
        Lowering { env }
    }

    /// True if `ast` uses a tunable parameter.
    pub fn uses_tunable(&self, ast: &Ast) -> bool {
        ast.names().iter().any(|(n, _)| self.env.is_tunable(n))
    }

    /// A parameter-only quantity: its value if it uses only fixed
    /// parameters, else its expression over the tunable ones.
    pub fn quantity(&self, q: &Quantity) -> Result<S, MechError> {
        if !self.uses_tunable(&q.expr) && q.value.is_finite() {
            return Ok(S::from_f64(q.value));
        }
        lower_ast(&q.expr, q.span, &|n| self.env.param(n))
    }

    /// An expression written at `span` that may use `extra` names besides
    /// parameters.
    pub fn expr(
        &self,
        ast: &Ast,
        span: Span,
        extra: &dyn Fn(&str) -> Option<S>,
    ) -> Result<S, MechError> {
        lower_ast(ast, span, &|n| extra(n).or_else(|| self.env.param(n)))
    }

    /// A vector of quantities.
    pub fn vec3(&self, v: &Vec3Q) -> Result<Vec3<S>, MechError> {
        Ok(Vec3::new(
            self.quantity(&v[0])?,
            self.quantity(&v[1])?,
            self.quantity(&v[2])?,
        ))
    }

    /// A frame as a pose. Fixed rotation matrices are inlined with entries
    /// within 1e-14 of 0 or ±1 snapped to them, so `cos(π/2)` is an exact
    /// zero in the generated code.
    pub fn frame(&self, f: &FrameInfo) -> Result<Pose<S>, MechError> {
        let symbolic = match &f.rotation {
            Rotation::Identity => false,
            Rotation::AxisAngle { axis, angle } => {
                axis.iter().any(|a| self.uses_tunable(&a.expr)) || self.uses_tunable(&angle.expr)
            }
            Rotation::Rpy(a) => a.iter().any(|x| self.uses_tunable(&x.expr)),
            Rotation::Matrix(rows) => rows.iter().flatten().any(|x| self.uses_tunable(&x.expr)),
        };
        let e = if symbolic {
            match &f.rotation {
                Rotation::AxisAngle { axis, angle } => {
                    let k = self.vec3(axis)?;
                    Mat3::from_axis_angle(k.scale(S::one() / k.norm()), self.quantity(angle)?)
                }
                Rotation::Rpy([r, p, y]) => {
                    use crate::sym::Axis::{X, Y, Z};
                    Mat3::from_euler(
                        [Z, Y, X],
                        [self.quantity(y)?, self.quantity(p)?, self.quantity(r)?],
                    )
                }
                Rotation::Matrix(rows) => Mat3::from_rows([
                    self.vec3(&rows[0])?,
                    self.vec3(&rows[1])?,
                    self.vec3(&rows[2])?,
                ]),
                Rotation::Identity => Mat3::identity(),
            }
        } else {
            Mat3(std::array::from_fn(|i| {
                std::array::from_fn(|j| S::from_f64(snap(f.matrix[(i, j)])))
            }))
        };
        Ok(Pose {
            e,
            r: self.vec3(&f.position)?,
        })
    }
}

/// Snaps values within 1e-14 of 0, 1 or −1 to them.
pub fn snap(x: f64) -> f64 {
    for target in [0.0, 1.0, -1.0] {
        if (x - target).abs() < 1e-14 {
            return target;
        }
    }
    x
}

impl<S: Scalar> TreeModel<S> {
    /// The tree of `sys` with parameters from `env`.
    pub fn new(sys: &System, env: &dyn Env<S>) -> Result<Self, MechError> {
        let low = Lowering::new(env);
        let mut index_of_body = vec![None; sys.bodies.len()];
        let mut bodies: Vec<TreeBody<S>> = Vec::new();
        for &j in sys.graph.tree_joints() {
            let joint = &sys.joints[j];
            let axis = |a: &crate::system::Axis| -> Result<Vec3<S>, MechError> {
                if let Some(x) = a.written.iter().find(|x| low.uses_tunable(&x.expr)) {
                    return Err(MechError::TunableAxis {
                        joint: joint.name.clone(),
                        span: x.span,
                    });
                }
                Ok(Vec3::from_f64([
                    snap(a.unit.x),
                    snap(a.unit.y),
                    snap(a.unit.z),
                ]))
            };
            let kind = match &joint.kind {
                JointType::Revolute(a) => JointModel::Revolute(axis(a)?),
                JointType::Prismatic(a) => JointModel::Prismatic(axis(a)?),
                JointType::Cylindrical(a) => JointModel::Cylindrical(axis(a)?),
                JointType::Universal(a, b) => JointModel::Universal(axis(a)?, axis(b)?),
                JointType::Spherical => JointModel::Spherical,
                JointType::Planar => JointModel::Planar,
                JointType::Free => JointModel::Free,
                JointType::Screw(a, p) => JointModel::Screw(axis(a)?, low.quantity(p)?),
                JointType::Fixed => JointModel::Fixed,
            };
            let body = &sys.bodies[joint.child];
            let mass = body
                .mass
                .as_ref()
                .map_or(Ok(S::zero()), |m| low.quantity(m))?;
            let com = body
                .com
                .as_ref()
                .map_or(Ok(Vec3::zero()), |c| low.vec3(c))?;
            let ic = match &body.inertia {
                Some(rows) => Mat3::from_rows([
                    low.vec3(&rows[0])?,
                    low.vec3(&rows[1])?,
                    low.vec3(&rows[2])?,
                ]),
                None => Mat3::zero(),
            };
            let coords = match &joint.motion {
                JointMotion::Free => Coords::Free {
                    q: joint.q_index,
                    u: joint.u_index,
                },
                JointMotion::Locked => Coords::Locked(joint.q0.iter().map(|q| q.value).collect()),
                JointMotion::Prescribed(p) => {
                    let q: Vec<Ast> = p.iter().map(|x| x.expr.clone()).collect();
                    let qd: Vec<Ast> = q.iter().map(|a| a.diff("t")).collect();
                    let qdd: Vec<Ast> = qd.iter().map(|a| a.diff("t")).collect();
                    let spans = p.iter().map(|x| x.span).collect();
                    Coords::Prescribed { q, qd, qdd, spans }
                }
                JointMotion::Cut => continue,
            };
            let parent: Option<usize> = index_of_body[joint.parent];
            let node = match (joint.parent_node, parent) {
                (Some(n), Some(p)) => {
                    let slot = bodies[p].flex.as_ref().and_then(|f| f.node_slot(n));
                    debug_assert!(slot.is_some(), "validated: the node is attached");
                    slot
                }
                _ => None,
            };
            let flex = body
                .flexible
                .as_deref()
                .map(|f| FlexModel::new(f, &body.name, &sys.attached_nodes(joint.child), &low))
                .transpose()?;
            index_of_body[joint.child] = Some(bodies.len());
            bodies.push(TreeBody {
                body: joint.child,
                joint: j,
                parent,
                kind,
                frame_parent: low.frame(&joint.parent_frame)?,
                frame_child: low.frame(&joint.child_frame)?,
                inertia: RigidInertia::from_com(mass, com, ic),
                coords,
                flex,
                node,
                node_loads: 0,
            });
        }
        let mut next = bodies.len();
        for b in &mut bodies {
            b.node_loads = next;
            next += b.flex.as_ref().map_or(0, |f| f.nodes.len());
        }
        let gravity = match &sys.gravity {
            Some(g) => low.vec3(g)?,
            None => Vec3::zero(),
        };
        Ok(TreeModel {
            bodies,
            gravity,
            index_of_body,
            nq: sys.nq(),
            nu: sys.nu(),
        })
    }
}
