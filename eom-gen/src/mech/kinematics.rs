//! Kinematics: poses, motion subspaces and velocities of every body, root
//! to leaves (Featherstone §4.4, Table 4.4), over any [`Scalar`]; the
//! [`Evaluator`] that runs the recursive algorithms of one tree (RNEA in
//! `rnea.rs`, CRBA in `crba.rs`, ABA in `aba.rs`) and `q̇ = N(q) u`.
//!
//! Conventions: all spatial quantities of body `i` are in its own
//! coordinates at its origin; ground is the world frame; gravity enters as
//! the base acceleration `a₀ = −g` (§5.3). The equations of motion are
//! `M(q) u̇ = τ − b(q, u, t)`, where `b = C + g − Jᵀf_ext − Q` collects
//! velocity products, gravity, point forces and the model's generalised
//! forces `Q` (joint springs, joint forces, actuator inputs); `τ` is any
//! extra generalised force.

// Index loops over small dense matrices read like the textbook formulas.
#![allow(clippy::needless_range_loop)]

use super::applied::{Applied, Site};
use super::env::Env;
use super::error::MechError;
use super::flex_state::{FlexState, NodeState};
use super::joint::JointModel;
use super::lower::Lowering;
use super::spatial::{Motion, Pose, RigidInertia};
use super::tree::{Coords, TreeModel};
use crate::sym::{Mat3, Scalar, Vec3};
use std::ops::{Add, Sub};

/// Base rotation, axis and summed angle of a run of revolute joints.
type AngleChain<S> = (Mat3<S>, Vec3<S>, S);

/// Of a body hung at a node: its pose in the node frame, and its own
/// joint's bias `c_J` and velocity `v_J` (its coordinates).
type NodeJoint<S> = (Pose<S>, Motion<S>, Motion<S>);

/// A joint's positions, speeds and (if known) accelerations.
type JointValues<S> = (Vec<S>, Vec<S>, Option<Vec<S>>);

/// The state at which the algorithms are evaluated.
#[derive(Clone, Copy, Debug)]
pub struct State<'a, S> {
    /// Positions (`nq`).
    pub q: &'a [S],
    /// Speeds (`nu`).
    pub u: &'a [S],
    /// Time.
    pub t: S,
    /// Runtime inputs.
    pub inputs: &'a [S],
}

/// Per-evaluation kinematics (the "data" to the model's "model").
#[derive(Clone, Debug)]
pub struct Kinematics<S> {
    /// Pose of each body in its parent.
    pub x: Vec<Pose<S>>,
    /// Pose of each body in the world.
    pub world: Vec<Pose<S>>,
    /// Motion subspace columns in body coordinates.
    pub s: Vec<Vec<Motion<S>>>,
    /// `S̊ u` in body coordinates.
    pub c: Vec<Motion<S>>,
    /// Joint velocity `S u`.
    pub vj: Vec<Motion<S>>,
    /// Body velocity.
    pub v: Vec<Motion<S>>,
    /// Known joint accelerations (locked and prescribed joints).
    pub known_ud: Vec<Option<Vec<S>>>,
    /// Inertia of each body about its origin at this state (a flexible
    /// body's depends on its deformation).
    pub inertia: Vec<RigidInertia<S>>,
    /// The deformable part of each flexible body at this state.
    pub flex: Vec<Option<FlexState<S>>>,
    /// The attached nodes of each flexible body at this state (by slot).
    pub nodes: Vec<Vec<NodeState<S>>>,
    /// Of a body hung at a node: the node's motion columns (body
    /// coordinates), whose speeds are the parent's elastic rates.
    pub node_s: Vec<Vec<Motion<S>>>,
    /// Of a body hung at a node: its pose in the node frame and its own
    /// joint's bias and velocity (for the articulated-body algorithm).
    pub node_joint: Vec<Option<NodeJoint<S>>>,
}

/// Runs the algorithms of one tree.
pub struct Evaluator<'a, S> {
    /// The tree.
    pub tree: &'a TreeModel<S>,
    /// Its force elements.
    pub applied: &'a Applied<S>,
    /// Parameter values or symbols.
    pub env: &'a dyn Env<S>,
}

impl<'a, S: Scalar> Evaluator<'a, S> {
    /// An evaluator.
    pub fn new(tree: &'a TreeModel<S>, applied: &'a Applied<S>, env: &'a dyn Env<S>) -> Self {
        Evaluator { tree, applied, env }
    }

    fn time_lookup(&self, t: S) -> impl Fn(&str) -> Option<S> {
        move |n: &str| (n == "t").then_some(t)
    }

    /// Joint positions, speeds and (if known) accelerations of body `i`.
    fn joint_state(&self, i: usize, st: &State<'_, S>) -> Result<JointValues<S>, MechError> {
        let body = &self.tree.bodies[i];
        let (nq, nu) = (body.kind.nq(), body.kind.nu());
        let low = Lowering::new(self.env);
        Ok(match &body.coords {
            Coords::Free { q, u } => (st.q[*q..q + nq].to_vec(), st.u[*u..u + nu].to_vec(), None),
            Coords::Locked(q0) => (
                q0.iter().map(|&v| S::from_f64(v)).collect(),
                vec![S::zero(); nu],
                Some(vec![S::zero(); nu]),
            ),
            Coords::Prescribed { q, qd, qdd, spans } => {
                let tl = self.time_lookup(st.t);
                let lower = |v: &Vec<crate::expr::Ast>| -> Result<Vec<S>, MechError> {
                    v.iter()
                        .zip(spans)
                        .map(|(a, &span)| low.expr(a, span, &tl))
                        .collect()
                };
                (lower(q)?, lower(qd)?, Some(lower(qdd)?))
            }
        })
    }

    /// Poses, subspaces and velocities, from ground outwards.
    pub fn kinematics(&self, st: &State<'_, S>) -> Result<Kinematics<S>, MechError> {
        let n = self.tree.bodies.len();
        let mut k = Kinematics {
            x: Vec::with_capacity(n),
            world: Vec::with_capacity(n),
            s: Vec::with_capacity(n),
            c: Vec::with_capacity(n),
            vj: Vec::with_capacity(n),
            v: Vec::with_capacity(n),
            known_ud: Vec::with_capacity(n),
            inertia: Vec::with_capacity(n),
            flex: Vec::with_capacity(n),
            nodes: Vec::with_capacity(n),
            node_s: Vec::with_capacity(n),
            node_joint: Vec::with_capacity(n),
        };
        // Per body: (base rotation, axis, summed angle) of a run of revolute
        // joints about one axis ending at it.
        let mut chain: Vec<Option<AngleChain<S>>> = Vec::with_capacity(n);
        // Forward pass over bodies (Featherstone Table 5.1, first loop).
        for (i, body) in self.tree.bodies.iter().enumerate() {
            let (q, u, known) = self.joint_state(i, st)?;
            let fc = body.frame_child;
            let mut x = body
                .frame_parent
                .then(&body.kind.transform(&q))
                .then(&fc.inverse());
            let s: Vec<Motion<S>> = body
                .kind
                .subspace(&q)
                .into_iter()
                .map(|m| fc.motion_to_parent(m))
                .collect();
            let mut c = fc.motion_to_parent(body.kind.bias(&q, &u));
            let mut vj = s
                .iter()
                .zip(&u)
                .fold(Motion::zero(), |acc, (col, &uk)| acc.add(col.scale(uk)));
            // Hung at a node N of a flexible parent: the node's motion comes
            // first, as a joint from the parent frame with speeds q̇_f
            // (two joints in series across a massless frame): X = X_J X_N, the
            // node's columns and velocity w carried into this body, and the
            // bias c = X_J c_N − v_J × w + c_J.
            let mut node_s = Vec::new();
            let mut node_joint = None;
            if let (Some(slot), Some(p)) = (body.node, body.parent) {
                node_joint = Some((x, c, vj));
                let ns = &k.nodes[p][slot];
                let w = x.motion_to_child(ns.velocity);
                c = x.motion_to_child(ns.bias).add(c).sub(vj.cross_motion(w));
                node_s = ns.columns.iter().map(|m| x.motion_to_child(*m)).collect();
                vj = vj.add(w);
                x = ns.pose.then(&x);
            }
            let (v, mut world) = match body.parent {
                Some(p) => (x.motion_to_child(k.v[p]).add(vj), k.world[p].then(&x)),
                None => (vj, x),
            };
            // Consecutive revolute joints about one axis (Wittenburg's
            // specialisation): the world rotation is the chain's base
            // rotation turned by the summed angle, one sin/cos instead of a
            // matrix product per body.
            let summed = match (&body.kind, body.parent.and_then(|p| chain[p])) {
                _ if body.node.is_some() => None,
                (JointModel::Revolute(a), Some((base, axis, angle)))
                    if (0..3).all(|c| (axis.0[c] - a.0[c]).is_zero())
                        && is_identity(&body.frame_parent.e)
                        && is_identity(&fc.e) =>
                {
                    Some((base, axis, angle + q[0]))
                }
                (JointModel::Revolute(a), _) if is_identity(&fc.e) => {
                    let base = body
                        .parent
                        .map_or(body.frame_parent.e, |p| k.world[p].e * body.frame_parent.e);
                    Some((base, *a, q[0]))
                }
                _ => None,
            };
            if let Some((base, axis, angle)) = &summed {
                world.e = *base * Mat3::from_axis_angle(*axis, *angle);
            }
            chain.push(summed);
            // A flexible body's inertia and velocity terms at its deformation.
            let (inertia, flex, nodes) = match &body.flex {
                Some(fm) => {
                    let m = fm.count();
                    let (qf, qfd) = (&st.q[fm.q..fm.q + m], &st.u[fm.u..fm.u + m]);
                    let fs = fm.state(qf, qfd, v);
                    let nodes = (0..fm.nodes.len())
                        .map(|slot| fm.node_state(slot, qf, qfd))
                        .collect();
                    (body.inertia.add(fs.inertia), Some(fs), nodes)
                }
                None => (body.inertia, None, Vec::new()),
            };
            k.inertia.push(inertia);
            k.flex.push(flex);
            k.nodes.push(nodes);
            k.node_s.push(node_s);
            k.node_joint.push(node_joint);
            k.x.push(x);
            k.world.push(world);
            k.s.push(s);
            k.c.push(c);
            k.vj.push(vj);
            k.v.push(v);
            k.known_ud.push(known);
        }
        Ok(k)
    }

    /// World pose of node `node` of tree body `i` and its spatial velocity
    /// (node coordinates); `None` if nothing attaches there.
    pub fn node_frame(
        &self,
        k: &Kinematics<S>,
        i: usize,
        node: usize,
    ) -> Option<(Pose<S>, Motion<S>)> {
        let slot = self.tree.bodies[i].flex.as_ref()?.node_slot(node)?;
        let ns = &k.nodes[i][slot];
        Some((
            k.world[i].then(&ns.pose),
            ns.pose.motion_to_child(k.v[i]).add(ns.velocity),
        ))
    }

    /// World position and velocity of a site.
    pub fn site(&self, k: &Kinematics<S>, s: &Site<S>) -> (Vec3<S>, Vec3<S>) {
        match (s.body, s.node) {
            (Some(i), Some(node)) => match self.node_frame(k, i, node) {
                Some((pose, v)) => {
                    let vel = v.v + v.w.cross(s.point);
                    (pose.point(s.point), pose.e.mul_vec(vel))
                }
                None => self.point(k, s.body, s.point),
            },
            _ => self.point(k, s.body, s.point),
        }
    }

    /// World position and velocity of a point fixed on tree body `b`
    /// (`None` = ground).
    pub fn point(&self, k: &Kinematics<S>, b: Option<usize>, p: Vec3<S>) -> (Vec3<S>, Vec3<S>) {
        match b {
            None => (p, Vec3::zero()),
            Some(i) => {
                let w = &k.world[i];
                let vel = k.v[i].v + k.v[i].w.cross(p);
                (w.point(p), w.e.mul_vec(vel))
            }
        }
    }

    /// Of a body hung at a node: the first elastic speed of its parent
    /// (the speeds of its node columns).
    pub fn node_speeds(&self, i: usize) -> Option<usize> {
        let b = &self.tree.bodies[i];
        b.node?;
        self.tree.bodies[b.parent?].flex.as_ref().map(|f| f.u)
    }

    /// `q̇ = N(q) u` for the whole system.
    pub fn qdot(&self, st: &State<'_, S>) -> Vec<S> {
        let mut out = vec![S::zero(); self.tree.nq];
        for b in &self.tree.bodies {
            if let Coords::Free { q, u } = b.coords {
                let (nq, nu) = (b.kind.nq(), b.kind.nu());
                let d = b.kind.qdot(&st.q[q..q + nq], &st.u[u..u + nu]);
                out[q..q + nq].copy_from_slice(&d);
            }
            if let Some(fm) = &b.flex {
                let m = fm.count();
                out[fm.q..fm.q + m].copy_from_slice(&st.u[fm.u..fm.u + m]);
            }
        }
        out
    }
}

/// Is this joint model one with a quaternion?
pub fn has_quaternion<S: Scalar>(j: &JointModel<S>) -> bool {
    j.quaternion_at().is_some()
}

/// Is `m` structurally the identity (exact zeros and ones)?
fn is_identity<S: Scalar>(m: &Mat3<S>) -> bool {
    (0..3).all(|i| {
        (0..3).all(|j| {
            if i == j {
                m.0[i][j].is_one()
            } else {
                m.0[i][j].is_zero()
            }
        })
    })
}
