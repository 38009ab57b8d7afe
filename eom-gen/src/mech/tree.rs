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

use super::env::Env;
use super::error::MechError;
use super::flexible::FlexModel;
use super::joint::JointModel;
use super::lower::{Lowering, snap};
use super::spatial::{Pose, RigidInertia};
use crate::diag::Span;
use crate::expr::Ast;
use crate::graph::{BodyId, JointId};
use crate::sym::{Mat3, Scalar, Vec3};
use crate::system::{JointType, Motion as JointMotion, System};

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
