//! The force elements of a system resolved to the tree ([`Applied`]):
//! point-to-point spring-dampers between sites, and generalised forces on
//! single speeds (joint springs, joint forces, actuator inputs).

use super::env::Env;
use super::error::MechError;
use super::lower::Lowering;
use super::tree::TreeModel;
use crate::sym::{Scalar, Vec3};
use crate::system::{ForceElement, System};

/// A point on a tree body or on one of its nodes.
#[derive(Clone, Copy, Debug)]
pub struct Site<S> {
    /// Tree index of the body (`None`: ground).
    pub body: Option<usize>,
    /// On a flexible body: the beam node the point moves with.
    pub node: Option<usize>,
    /// The point in body coordinates (at a node: node coordinates).
    pub point: Vec3<S>,
}

/// A point-to-point spring-damper, resolved to tree bodies.
#[derive(Clone, Debug)]
pub struct SpringModel<S> {
    /// Each end.
    pub ends: [Site<S>; 2],
    /// Stiffness, damping, rest length.
    pub k: S,
    /// Damping.
    pub c: S,
    /// Rest length.
    pub l0: S,
}

/// A generalised force on one speed.
#[derive(Clone, Debug)]
pub enum GenForce<S> {
    /// `−k (q − rest) − c u` on coordinate `q` / speed `u`.
    Spring {
        /// Coordinate index.
        q: usize,
        /// Speed index.
        u: usize,
        /// Stiffness.
        k: S,
        /// Damping.
        c: S,
        /// Rest position.
        rest: S,
    },
    /// A known value (expression of parameters, `t`, coordinates, speeds).
    Value {
        /// Speed index.
        u: usize,
        /// The expression.
        expr: crate::expr::Ast,
        /// Where it is written.
        span: crate::diag::Span,
    },
    /// A runtime input.
    Input {
        /// Speed index.
        u: usize,
        /// Input index.
        input: usize,
    },
}

/// The force elements of a system.
#[derive(Clone, Debug)]
pub struct Applied<S> {
    /// Point-to-point spring-dampers.
    pub springs: Vec<SpringModel<S>>,
    /// Generalised forces.
    pub generalized: Vec<GenForce<S>>,
    /// Coordinate names, for expressions.
    pub coordinate_names: Vec<String>,
    /// Speed names, for expressions.
    pub speed_names: Vec<String>,
}

impl<S: Scalar> Applied<S> {
    /// The force elements of `sys` on the tree `tree`.
    pub fn new(sys: &System, tree: &TreeModel<S>, env: &dyn Env<S>) -> Result<Self, MechError> {
        let low = Lowering::new(env);
        let mut springs = Vec::new();
        let mut generalized = Vec::new();
        for force in &sys.forces {
            match &force.element {
                ForceElement::SpringDamper {
                    a,
                    b,
                    stiffness,
                    damping,
                    rest_length,
                } => springs.push(SpringModel {
                    ends: [
                        Site {
                            body: tree.index_of_body[a.body],
                            node: a.node,
                            point: low.vec3(&a.position)?,
                        },
                        Site {
                            body: tree.index_of_body[b.body],
                            node: b.node,
                            point: low.vec3(&b.position)?,
                        },
                    ],
                    k: low.quantity(stiffness)?,
                    c: low.quantity(damping)?,
                    l0: low.quantity(rest_length)?,
                }),
                ForceElement::JointSpringDamper {
                    joint,
                    stiffness,
                    damping,
                    rest,
                } => {
                    let j = &sys.joints[*joint];
                    for k in 0..j.kind.nu() {
                        generalized.push(GenForce::Spring {
                            q: j.q_index + k,
                            u: j.u_index + k,
                            k: low.quantity(stiffness)?,
                            c: low.quantity(damping)?,
                            rest: low.quantity(rest)?,
                        });
                    }
                }
                ForceElement::JointForce { joint, values } => {
                    let j = &sys.joints[*joint];
                    for (k, v) in values.iter().enumerate() {
                        generalized.push(GenForce::Value {
                            u: j.u_index + k,
                            expr: v.expr.clone(),
                            span: v.span,
                        });
                    }
                }
                ForceElement::Actuator { joint, inputs } => {
                    let j = &sys.joints[*joint];
                    for (k, input) in inputs.iter().enumerate() {
                        let Some(input) = *input else { continue };
                        generalized.push(GenForce::Input {
                            u: j.u_index + k,
                            input,
                        });
                    }
                }
            }
        }
        Ok(Applied {
            springs,
            generalized,
            coordinate_names: sys
                .coordinate_names()
                .iter()
                .map(|s| s.to_string())
                .collect(),
            speed_names: sys.speed_names().iter().map(|s| s.to_string()).collect(),
        })
    }
}
