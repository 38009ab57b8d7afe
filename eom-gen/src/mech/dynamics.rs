//! The recursive algorithms, each written once over any [`Scalar`]
//! (Featherstone, *Rigid Body Dynamics Algorithms*, 2008):
//!
//! - [`Evaluator::kinematics`]: poses, subspaces and velocities, root to leaves;
//! - [`Evaluator::rnea`]: inverse dynamics by recursive Newton–Euler (§5.3);
//! - [`Evaluator::crba`]: the joint-space mass matrix by composite rigid
//!   bodies (§6.2);
//! - [`Evaluator::aba`]: forward dynamics in O(n) by articulated bodies (§7.3);
//! - [`ltdl`] / [`ltdl_solve`]: the sparse `LᵀDL` factorisation of the mass
//!   matrix that follows the tree (§6.5), the other forward-dynamics route;
//! - energies and momenta, force elements.
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

use super::flexible::{FlexState, NodeState};
use super::joint::JointModel;
use super::spatial::{Force, Inertia6, Motion, Pose, RigidInertia};
use super::tree::{Coords, Env, Lowering, MechError, TreeModel};
use crate::sym::{Mat3, Scalar, Vec3};
use crate::system::{ForceElement, System};
use std::ops::{Add, Sub};

/// Base rotation, axis and summed angle of a run of revolute joints.
type AngleChain<S> = (Mat3<S>, Vec3<S>, S);

/// A flexible body's elastic equations in the articulated-body algorithm,
/// `D q̈_f = u − Uᵀ a`: `D⁻¹`, `u` and the columns of `U`.
type Elimination<S> = (Vec<Vec<S>>, Vec<S>, Vec<Force<S>>);

/// Of a body hung at a node: its pose in the node frame, and its own
/// joint's bias `c_J` and velocity `v_J` (its coordinates).
type NodeJoint<S> = (Pose<S>, Motion<S>, Motion<S>);

/// A joint's positions, speeds and (if known) accelerations.
type JointValues<S> = (Vec<S>, Vec<S>, Option<Vec<S>>);

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

    /// Spatial forces of the point spring-dampers on each body (body
    /// coordinates, at the body origin) and node (node coordinates, see
    /// [`TreeModel::loads`]), and their potential energy.
    pub fn point_forces(&self, k: &Kinematics<S>) -> (Vec<Force<S>>, S) {
        let mut f = vec![Force::zero(); self.tree.loads()];
        let mut energy = S::zero();
        for s in &self.applied.springs {
            let (xa, va) = self.site(k, &s.ends[0]);
            let (xb, vb) = self.site(k, &s.ends[1]);
            let d = xb - xa;
            let len = d.norm();
            let e = d.scale(S::one() / len);
            let stretch = len - s.l0;
            // Tension: k (L − L0) + c L̇, pulling the ends together.
            let tension = s.k * stretch + s.c * e.dot(vb - va);
            energy = energy + S::from_ratio(1, 2) * s.k * stretch * stretch;
            for (end, sign) in [(0, S::one()), (1, -S::one())] {
                let site = &s.ends[end];
                if let Some(i) = site.body {
                    let fw = e.scale(tension * sign);
                    let (slot, frame) = match site.node {
                        Some(node) => match self.tree.node_load(i, node) {
                            Some(slot) => (slot, self.node_frame(k, i, node).map(|x| x.0)),
                            None => (i, None),
                        },
                        None => (i, None),
                    };
                    let fb = frame.unwrap_or(k.world[i]).e.tr_mul_vec(fw);
                    f[slot] = f[slot].add(Force {
                        n: site.point.cross(fb),
                        f: fb,
                    });
                }
            }
        }
        (f, energy)
    }

    /// Generalised forces `Q` of joint springs, joint forces and inputs
    /// (one per speed), and the joint springs' potential energy.
    pub fn generalized_forces(&self, st: &State<'_, S>) -> Result<(Vec<S>, S), MechError> {
        let mut q_out = vec![S::zero(); self.tree.nu];
        let mut energy = S::zero();
        let low = Lowering::new(self.env);
        let names = &self.applied;
        let lookup = |n: &str| -> Option<S> {
            if n == "t" {
                return Some(st.t);
            }
            if let Some(i) = names.coordinate_names.iter().position(|c| c == n) {
                return st.q.get(i).copied();
            }
            names
                .speed_names
                .iter()
                .position(|c| c == n)
                .and_then(|i| st.u.get(i).copied())
        };
        for g in &self.applied.generalized {
            match g {
                GenForce::Spring { q, u, k, c, rest } => {
                    let stretch = st.q[*q] - *rest;
                    q_out[*u] = q_out[*u] - *k * stretch - *c * st.u[*u];
                    energy = energy + S::from_ratio(1, 2) * *k * stretch * stretch;
                }
                GenForce::Value { u, expr, span } => {
                    q_out[*u] = q_out[*u] + low.expr(expr, *span, &lookup)?
                }
                GenForce::Input { u, input } => {
                    q_out[*u] = q_out[*u] + st.inputs.get(*input).copied().unwrap_or(S::zero())
                }
            }
        }
        // Elastic forces −K_ff q_f − D_ff q̇_f of flexible bodies.
        for fm in self.tree.bodies.iter().filter_map(|b| b.flex.as_ref()) {
            let m = fm.count();
            let (qf, strain) = fm.elastic_forces(&st.q[fm.q..fm.q + m], &st.u[fm.u..fm.u + m]);
            for (j, x) in qf.into_iter().enumerate() {
                q_out[fm.u + j] = q_out[fm.u + j] + x;
            }
            energy = energy + strain;
        }
        Ok((q_out, energy))
    }

    /// Recursive Newton–Euler (Featherstone §5.3): the generalised forces
    /// `M u̇ + C + g − Jᵀ f_ext` for the given accelerations of the free
    /// speeds (known accelerations of locked and prescribed joints are
    /// used as they are), and the spatial force each joint transmits to
    /// its child (child coordinates).
    pub fn rnea(&self, k: &Kinematics<S>, ud: &[S], fext: &[Force<S>]) -> (Vec<S>, Vec<Force<S>>) {
        let n = self.tree.bodies.len();
        let base = Motion {
            w: Vec3::zero(),
            v: -self.tree.gravity,
        };
        let mut a: Vec<Motion<S>> = Vec::with_capacity(n);
        let mut f: Vec<Force<S>> = Vec::with_capacity(n);
        let mut tau = vec![S::zero(); self.tree.nu];
        // Forward pass over bodies: accelerations and net forces.
        for (i, body) in self.tree.bodies.iter().enumerate() {
            let ap = body.parent.map_or(base, |p| a[p]);
            let udj = self.joint_ud(i, k, ud);
            let mut ai = k.x[i]
                .motion_to_child(ap)
                .add(k.c[i])
                .add(k.v[i].cross_motion(k.vj[i]));
            for (col, &x) in k.s[i].iter().zip(&udj) {
                ai = ai.add(col.scale(x));
            }
            if let Some(uf) = self.node_speeds(i) {
                for (col, &x) in k.node_s[i].iter().zip(&ud[uf..]) {
                    ai = ai.add(col.scale(x));
                }
            }
            let inertia = &k.inertia[i];
            let mut fi = inertia
                .mul_motion(ai)
                .add(k.v[i].cross_force(inertia.mul_motion(k.v[i])))
                .sub(fext[i]);
            // A flexible body: f += b + P q̈_f, τ_f = Pᵀ a + M_ff q̈_f + b_f.
            if let (Some(fm), Some(fs)) = (&body.flex, &k.flex[i]) {
                let qdd = &ud[fm.u..fm.u + fm.count()];
                fi = fi.add(fs.bias);
                let mq = fm.modal_mass_times(qdd);
                for (j, p) in fs.coupling.iter().enumerate() {
                    fi = fi.add(p.scale(qdd[j]));
                    tau[fm.u + j] = ai.dot(*p) + mq[j] + fs.elastic_bias[j];
                }
            }
            a.push(ai);
            f.push(fi);
        }
        // Backward pass over bodies: project on the joints, pass to parents.
        for i in (0..n).rev() {
            let body = &self.tree.bodies[i];
            // Loads on the nodes of a flexible body: on its elastic
            // coordinates through the node's columns, and on its frame.
            if let Some(fm) = &body.flex {
                for (slot, ns) in k.nodes[i].iter().enumerate() {
                    let load = fext[body.node_loads + slot];
                    if is_zero_force(&load) {
                        continue;
                    }
                    for (kk, col) in ns.columns.iter().enumerate() {
                        tau[fm.u + kk] = tau[fm.u + kk] - col.dot(load);
                    }
                    f[i] = f[i].sub(ns.pose.force_to_parent(load));
                }
            }
            if let Coords::Free { u, .. } = body.coords {
                for (kk, col) in k.s[i].iter().enumerate() {
                    tau[u + kk] = col.dot(f[i]);
                }
            }
            if let Some(uf) = self.node_speeds(i) {
                for (kk, col) in k.node_s[i].iter().enumerate() {
                    tau[uf + kk] = tau[uf + kk] + col.dot(f[i]);
                }
            }
            if let Some(p) = self.tree.bodies[i].parent {
                let fp = k.x[i].force_to_parent(f[i]);
                f[p] = f[p].add(fp);
            }
        }
        (tau, f)
    }

    /// Of a body hung at a node: the first elastic speed of its parent
    /// (the speeds of its node columns).
    pub fn node_speeds(&self, i: usize) -> Option<usize> {
        let b = &self.tree.bodies[i];
        b.node?;
        self.tree.bodies[b.parent?].flex.as_ref().map(|f| f.u)
    }

    /// The free motion columns of body `i` with their speeds: its joint's
    /// (if free) and, hung at a node, the node's.
    fn columns(&self, k: &Kinematics<S>, i: usize) -> Vec<(usize, Motion<S>)> {
        let mut out = Vec::new();
        if let Coords::Free { u, .. } = self.tree.bodies[i].coords {
            out.extend(k.s[i].iter().enumerate().map(|(j, c)| (u + j, *c)));
        }
        if let Some(uf) = self.node_speeds(i) {
            out.extend(k.node_s[i].iter().enumerate().map(|(j, c)| (uf + j, *c)));
        }
        out
    }

    fn joint_ud(&self, i: usize, k: &Kinematics<S>, ud: &[S]) -> Vec<S> {
        match (&self.tree.bodies[i].coords, &k.known_ud[i]) {
            (Coords::Free { u, .. }, _) => ud[*u..*u + k.s[i].len()].to_vec(),
            (_, Some(known)) => known.clone(),
            _ => vec![S::zero(); k.s[i].len()],
        }
    }

    /// Composite-rigid-body algorithm (Featherstone §6.2): the mass matrix
    /// over the free speeds, as a dense symmetric `nu × nu` matrix.
    pub fn crba(&self, k: &Kinematics<S>) -> Vec<Vec<S>> {
        let n = self.tree.bodies.len();
        let nu = self.tree.nu;
        let mut m = vec![vec![S::zero(); nu]; nu];
        let mut ic: Vec<_> = k.inertia.clone();
        // Backward pass over bodies: composite inertias.
        for i in (0..n).rev() {
            if let Some(p) = self.tree.bodies[i].parent {
                let moved = ic[i].to_parent(&k.x[i]);
                ic[p] = ic[p].add(moved);
            }
        }
        // Each body's free columns with their speeds (a body hung at a
        // node also has the node's, with its parent's elastic speeds,
        // shared with its siblings there: entries accumulate).
        let cols: Vec<Vec<(usize, Motion<S>)>> = (0..n).map(|i| self.columns(k, i)).collect();
        let add = |m: &mut Vec<Vec<S>>, r: usize, c: usize, x: S| {
            if !x.is_zero() {
                m[r][c] = if m[r][c].is_zero() { x } else { m[r][c] + x };
            }
        };
        // Elastic columns of flexible bodies: M_ff, and the momentum P of
        // unit q̇_f carried up the tree (bodies on the frame ride it, so
        // their rows are zero; those at nodes enter through their columns).
        for i in 0..n {
            let (Some(fm), Some(fs)) = (&self.tree.bodies[i].flex, &k.flex[i]) else {
                continue;
            };
            let uf = fm.u;
            for (a, row) in fm.modal_mass.iter().enumerate() {
                for (b, x) in row.iter().enumerate() {
                    add(&mut m, uf + a, uf + b, *x);
                }
            }
            for (a, p) in fs.coupling.iter().enumerate() {
                let mut force = *p;
                let mut j = i;
                loop {
                    for &(ub, col2) in &cols[j] {
                        let x = col2.dot(force);
                        add(&mut m, ub, uf + a, x);
                        add(&mut m, uf + a, ub, x);
                    }
                    let Some(p) = self.tree.bodies[j].parent else {
                        break;
                    };
                    force = k.x[j].force_to_parent(force);
                    j = p;
                }
            }
        }
        for i in 0..n {
            for &(ua, col) in &cols[i] {
                let mut force = ic[i].mul_motion(col);
                for &(ub, col2) in &cols[i] {
                    add(&mut m, ub, ua, col2.dot(force));
                }
                // Up the tree: M[j][i] = S_jᵀ (X…ᵀ F).
                let mut j = i;
                while let Some(p) = self.tree.bodies[j].parent {
                    force = k.x[j].force_to_parent(force);
                    j = p;
                    for &(ub, col2) in &cols[j] {
                        let x = col2.dot(force);
                        add(&mut m, ub, ua, x);
                        add(&mut m, ua, ub, x);
                    }
                }
            }
        }
        m
    }

    /// Articulated-body algorithm (Featherstone §7.3, Table 7.1): `u̇` for
    /// generalised forces `tau` (one per free speed) and loads `fext` (see
    /// [`TreeModel::loads`]). Locked and prescribed joints move with their
    /// known accelerations.
    ///
    /// A flexible body's elastic coordinates are eliminated at the body,
    /// together with the subtrees hung at its nodes: with the articulated
    /// inertia `I_N` and bias `p_N` of the subtrees at node `N` (node
    /// coordinates, less the node's load), its columns `m_N`, pose `X_N`
    /// and velocity product `c_N`, the elastic equations read
    /// `D q̈_f = u − Uᵀ a` with `D = M_ff + Σ m_Nᵀ I_N m_N`,
    /// `U = P + Σ X_Nᵀ I_N m_N` and `u = τ_f − b_f − Σ m_Nᵀ (p_N + I_N c_N)`,
    /// so the body passes on `IA − U D⁻¹ Uᵀ` and `pA + U D⁻¹ u` (both with
    /// the node subtrees' `X_Nᵀ I_N X_N` and `X_Nᵀ (p_N + I_N c_N)` added).
    pub fn aba(&self, k: &Kinematics<S>, tau: &[S], fext: &[Force<S>]) -> Vec<S> {
        let n = self.tree.bodies.len();
        let mut ia: Vec<Inertia6<S>> = k.inertia.iter().map(Inertia6::from_rigid).collect();
        let mut pa: Vec<Force<S>> = (0..n)
            .map(|i| {
                let inertia = &k.inertia[i];
                let p = k.v[i].cross_force(inertia.mul_motion(k.v[i])).sub(fext[i]);
                match &k.flex[i] {
                    Some(fs) => p.add(fs.bias),
                    None => p,
                }
            })
            .collect();
        // The subtrees hung at each node (node coordinates).
        let mut node_ia: Vec<Vec<Option<Inertia6<S>>>> =
            k.nodes.iter().map(|ns| vec![None; ns.len()]).collect();
        let mut node_pa: Vec<Vec<Force<S>>> = k
            .nodes
            .iter()
            .map(|ns| vec![Force::zero(); ns.len()])
            .collect();
        // Velocity products of the node frames: c_N + v_N ×ₘ w_N.
        let node_cv: Vec<Vec<Motion<S>>> = (0..n)
            .map(|i| {
                k.nodes[i]
                    .iter()
                    .map(|ns| {
                        let vn = ns.pose.motion_to_child(k.v[i]).add(ns.velocity);
                        ns.bias.add(vn.cross_motion(ns.velocity))
                    })
                    .collect()
            })
            .collect();
        // Flexible bodies' elastic equations, kept for the last pass.
        let mut elastic: Vec<Option<Elimination<S>>> = vec![None; n];
        // U_i, D_i⁻¹ and u_i of the free joints, kept for the last pass.
        let mut uu: Vec<Vec<Force<S>>> = vec![Vec::new(); n];
        let mut dinv: Vec<Vec<Vec<S>>> = vec![Vec::new(); n];
        let mut small_u: Vec<Vec<S>> = vec![Vec::new(); n];
        // Velocity-product accelerations c_i = S̊ u + v_i ×ₘ v_J (eq. 7.34),
        // of a body at a node with its own joint's terms (the node's are in
        // `node_cv`).
        let cv: Vec<Motion<S>> = (0..n)
            .map(|i| match &k.node_joint[i] {
                Some((_, c, vj)) => c.add(k.v[i].cross_motion(*vj)),
                None => k.c[i].add(k.v[i].cross_motion(k.vj[i])),
            })
            .collect();
        // Backward pass over bodies: articulated inertias and bias forces.
        for i in (0..n).rev() {
            let body = &self.tree.bodies[i];
            let s = &k.s[i];
            // Eliminate a flexible body's elastic coordinates first, with
            // the subtrees at its nodes.
            if let (Some(fm), Some(fs)) = (&body.flex, &k.flex[i]) {
                let mut d = fm.modal_mass.clone();
                let mut ucols = fs.coupling.clone();
                let mut rhs: Vec<S> = (0..fm.count())
                    .map(|j| tau[fm.u + j] - fs.elastic_bias[j])
                    .collect();
                for (slot, ns) in k.nodes[i].iter().enumerate() {
                    let load = fext[body.node_loads + slot];
                    let inode = node_ia[i][slot];
                    if inode.is_none() && is_zero_force(&load) {
                        continue;
                    }
                    let mut p_eff = node_pa[i][slot].sub(load);
                    if let Some(inn) = &inode {
                        p_eff = p_eff.add(inn.mul_motion(node_cv[i][slot]));
                    }
                    for (kk, col) in ns.columns.iter().enumerate() {
                        rhs[kk] = rhs[kk] - col.dot(p_eff);
                    }
                    pa[i] = pa[i].add(ns.pose.force_to_parent(p_eff));
                    if let Some(inn) = &inode {
                        ia[i] = ia[i].add(inn.to_parent(&ns.pose));
                        let f_cols: Vec<Force<S>> =
                            ns.columns.iter().map(|m| inn.mul_motion(*m)).collect();
                        for (r, mr) in ns.columns.iter().enumerate() {
                            for (c, fc) in f_cols.iter().enumerate() {
                                d[r][c] = d[r][c] + mr.dot(*fc);
                            }
                        }
                        for (c, fc) in f_cols.iter().enumerate() {
                            ucols[c] = ucols[c].add(ns.pose.force_to_parent(*fc));
                        }
                    }
                }
                let di = invert_spd(d);
                for (r, ur) in ucols.iter().enumerate() {
                    for (c, uc) in ucols.iter().enumerate() {
                        ia[i] = ia[i].sub_outer(ur, uc, di[r][c]);
                    }
                    let w = (0..rhs.len()).fold(S::zero(), |acc, c| acc + di[r][c] * rhs[c]);
                    pa[i] = pa[i].add(ur.scale(w));
                }
                elastic[i] = Some((di, rhs, ucols));
            }
            let (ia_a, pa_a) = match (&body.coords, &k.known_ud[i]) {
                (Coords::Free { u, .. }, _) => {
                    let ucols: Vec<Force<S>> = s.iter().map(|col| ia[i].mul_motion(*col)).collect();
                    let d: Vec<Vec<S>> = s
                        .iter()
                        .map(|sr| ucols.iter().map(|uc| sr.dot(*uc)).collect())
                        .collect();
                    let di = invert_spd(d);
                    let ui: Vec<S> = s
                        .iter()
                        .enumerate()
                        .map(|(r, col)| tau[u + r] - col.dot(pa[i]))
                        .collect();
                    // Ia = IA − U D⁻¹ Uᵀ,  pa = pA + Ia c + U D⁻¹ u  (Table 7.1).
                    let mut inner = ia[i];
                    for r in 0..s.len() {
                        for c in 0..s.len() {
                            inner = inner.sub_outer(&ucols[r], &ucols[c], di[r][c]);
                        }
                    }
                    let mut p = pa[i].add(inner.mul_motion(cv[i]));
                    for r in 0..s.len() {
                        let w = (0..s.len()).fold(S::zero(), |acc, c| acc + di[r][c] * ui[c]);
                        p = p.add(ucols[r].scale(w));
                    }
                    uu[i] = ucols;
                    dinv[i] = di;
                    small_u[i] = ui;
                    (inner, p)
                }
                (_, known) => {
                    // Known acceleration: the joint transmits everything.
                    let mut acc = cv[i];
                    if let Some(kud) = known {
                        for (col, &x) in s.iter().zip(kud) {
                            acc = acc.add(col.scale(x));
                        }
                    }
                    (ia[i], pa[i].add(ia[i].mul_motion(acc)))
                }
            };
            match (body.node, body.parent, &k.node_joint[i]) {
                // Hung at a node: to the node's subtree sums.
                (Some(slot), Some(p), Some((xj, _, _))) => {
                    let moved = ia_a.to_parent(xj);
                    node_ia[p][slot] = Some(match node_ia[p][slot] {
                        Some(prev) => prev.add(moved),
                        None => moved,
                    });
                    node_pa[p][slot] = node_pa[p][slot].add(xj.force_to_parent(pa_a));
                }
                (_, Some(p), _) => {
                    let moved = ia_a.to_parent(&k.x[i]);
                    ia[p] = ia[p].add(moved);
                    let fp = k.x[i].force_to_parent(pa_a);
                    pa[p] = pa[p].add(fp);
                }
                _ => {}
            }
        }
        // Forward pass over bodies: accelerations.
        let base = Motion {
            w: Vec3::zero(),
            v: -self.tree.gravity,
        };
        let mut a: Vec<Motion<S>> = Vec::with_capacity(n);
        // Accelerations of the node frames, once their body's are known.
        let mut a_node: Vec<Vec<Motion<S>>> = vec![Vec::new(); n];
        let mut ud = vec![S::zero(); self.tree.nu];
        for i in 0..n {
            let body = &self.tree.bodies[i];
            let mut ai = match (body.node, body.parent, &k.node_joint[i]) {
                (Some(slot), Some(p), Some((xj, _, _))) => {
                    xj.motion_to_child(a_node[p][slot]).add(cv[i])
                }
                _ => {
                    let ap = body.parent.map_or(base, |p| a[p]);
                    k.x[i].motion_to_child(ap).add(cv[i])
                }
            };
            match (&body.coords, &k.known_ud[i]) {
                (Coords::Free { u, .. }, _) => {
                    let m = k.s[i].len();
                    let rhs: Vec<S> = (0..m).map(|r| small_u[i][r] - ai.dot(uu[i][r])).collect();
                    for r in 0..m {
                        let x = (0..m).fold(S::zero(), |acc, c| acc + dinv[i][r][c] * rhs[c]);
                        ud[u + r] = x;
                        ai = ai.add(k.s[i][r].scale(x));
                    }
                }
                (_, Some(known)) => {
                    for (col, &x) in k.s[i].iter().zip(known) {
                        ai = ai.add(col.scale(x));
                    }
                }
                _ => {}
            }
            if let (Some(fm), Some((di, rhs, ucols))) = (&body.flex, &elastic[i]) {
                let r: Vec<S> = (0..rhs.len()).map(|j| rhs[j] - ai.dot(ucols[j])).collect();
                let qdd: Vec<S> = (0..r.len())
                    .map(|j| (0..r.len()).fold(S::zero(), |acc, c| acc + di[j][c] * r[c]))
                    .collect();
                ud[fm.u..fm.u + qdd.len()].copy_from_slice(&qdd);
                a_node[i] = k.nodes[i]
                    .iter()
                    .zip(&node_cv[i])
                    .map(|(ns, c)| {
                        let mut an = ns.pose.motion_to_child(ai).add(*c);
                        for (col, &x) in ns.columns.iter().zip(&qdd) {
                            an = an.add(col.scale(x));
                        }
                        an
                    })
                    .collect();
            }
            a.push(ai);
        }
        ud
    }

    /// Kinetic energy `½ Σ vᵢᵀ Iᵢ vᵢ` (of a flexible body plus
    /// `vᵀ P q̇_f + ½ q̇_fᵀ M_ff q̇_f`).
    pub fn kinetic_energy(&self, k: &Kinematics<S>) -> S {
        let half = S::from_ratio(1, 2);
        (0..self.tree.bodies.len()).fold(S::zero(), |acc, i| {
            let v = k.v[i];
            let rigid = acc + half * v.dot(k.inertia[i].mul_motion(v));
            match (&self.tree.bodies[i].flex, &k.flex[i]) {
                (Some(fm), Some(fs)) => rigid + fm.elastic_kinetic(fs, v),
                _ => rigid,
            }
        })
    }

    /// Gravitational potential energy `−Σ mᵢ g · cᵢ` (world origin at zero).
    pub fn gravity_potential(&self, k: &Kinematics<S>) -> S {
        k.inertia
            .iter()
            .zip(&k.world)
            .fold(S::zero(), |acc, (inertia, w)| {
                // m c in world coordinates: E h + m r.
                let mc = w.e.mul_vec(inertia.h) + w.r.scale(inertia.m);
                acc - self.tree.gravity.dot(mc)
            })
    }

    /// Spatial momentum about the world origin, in world coordinates:
    /// `(angular, linear)`.
    pub fn momentum(&self, k: &Kinematics<S>) -> Force<S> {
        (0..self.tree.bodies.len()).fold(Force::zero(), |acc, i| {
            let mut h = k.inertia[i].mul_motion(k.v[i]);
            if let (Some(fm), Some(fs)) = (&self.tree.bodies[i].flex, &k.flex[i]) {
                h = h.add(fm.elastic_momentum(fs));
            }
            acc.add(k.world[i].force_to_parent(h))
        })
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

    /// Speed-level parent array for [`ltdl`]: the previous free speed on
    /// the path to ground (`None` at the root).
    pub fn speed_parents(&self) -> Vec<Option<usize>> {
        let mut lambda = vec![None; self.tree.nu];
        let mut last: Vec<Option<usize>> = vec![None; self.tree.bodies.len()];
        // The last elastic speed of each flexible body: above its nodes.
        let mut last_elastic: Vec<Option<usize>> = vec![None; self.tree.bodies.len()];
        for (i, b) in self.tree.bodies.iter().enumerate() {
            let above = match (b.node, b.parent) {
                (Some(_), Some(p)) => last_elastic[p],
                _ => b.parent.and_then(|p| last[p]),
            };
            last[i] = above;
            if let Coords::Free { u, .. } = b.coords {
                for k in 0..b.kind.nu() {
                    lambda[u + k] = if k == 0 { above } else { Some(u + k - 1) };
                }
                if b.kind.nu() > 0 {
                    last[i] = Some(u + b.kind.nu() - 1);
                }
            }
            // Elastic speeds: a branch of their own below the joint's
            // (bodies carried by the frame do not couple to them; bodies
            // at nodes hang below them).
            if let Some(fm) = &b.flex {
                for j in 0..fm.count() {
                    lambda[fm.u + j] = if j == 0 { last[i] } else { Some(fm.u + j - 1) };
                }
                last_elastic[i] = fm.count().checked_sub(1).map(|j| fm.u + j).or(last[i]);
            }
        }
        lambda
    }
}

/// Is this joint model one with a quaternion?
pub fn has_quaternion<S: Scalar>(j: &JointModel<S>) -> bool {
    j.quaternion_at().is_some()
}

/// Inverse of a small symmetric positive definite matrix by `LDLᵀ`
/// (no pivoting: articulated joint inertias are positive definite).
pub fn invert_spd<S: Scalar>(d: Vec<Vec<S>>) -> Vec<Vec<S>> {
    let n = d.len();
    if n == 1 {
        return vec![vec![S::one() / d[0][0]]];
    }
    (0..n)
        .map(|c| {
            let mut e = vec![S::zero(); n];
            e[c] = S::one();
            solve_dense(&d, e)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .enumerate()
        .fold(vec![vec![S::zero(); n]; n], |mut inv, (c, col)| {
            for (r, x) in col.into_iter().enumerate() {
                inv[r][c] = x;
            }
            inv
        })
}

/// Solves `A x = b` for symmetric positive definite `A` by `LDLᵀ`.
pub fn solve_dense<S: Scalar>(a: &[Vec<S>], mut b: Vec<S>) -> Vec<S> {
    let n = a.len();
    let mut l = a.to_vec();
    // Factor: l holds L below the diagonal and D on it.
    for j in 0..n {
        for k in 0..j {
            let ljk = l[j][k];
            l[j][j] = l[j][j] - ljk * ljk * l[k][k];
        }
        for i in j + 1..n {
            let mut x = l[i][j];
            for k in 0..j {
                x = x - l[i][k] * l[j][k] * l[k][k];
            }
            l[i][j] = x / l[j][j];
        }
    }
    for i in 0..n {
        for k in 0..i {
            b[i] = b[i] - l[i][k] * b[k];
        }
    }
    for i in 0..n {
        b[i] = b[i] / l[i][i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            b[i] = b[i] - l[k][i] * b[k];
        }
    }
    b
}

/// In-place `LᵀDL` factorisation of a mass matrix that follows the tree
/// (Featherstone Table 6.3): afterwards the diagonal holds `D` and the
/// entries `(k, i)` with `i` an ancestor of `k` hold `L`. No fill-in
/// outside the ancestor pattern.
pub fn ltdl<S: Scalar>(m: &mut [Vec<S>], lambda: &[Option<usize>]) {
    for k in (0..m.len()).rev() {
        let mut i = lambda[k];
        while let Some(ii) = i {
            let a = m[k][ii] / m[k][k];
            let mut j = Some(ii);
            while let Some(jj) = j {
                m[ii][jj] = m[ii][jj] - a * m[k][jj];
                j = lambda[jj];
            }
            m[k][ii] = a;
            i = lambda[ii];
        }
    }
}

/// Solves `M x = b` with `M` factorised by [`ltdl`] (Featherstone Table 6.4).
pub fn ltdl_solve<S: Scalar>(f: &[Vec<S>], lambda: &[Option<usize>], mut b: Vec<S>) -> Vec<S> {
    let n = b.len();
    for i in (0..n).rev() {
        let mut j = lambda[i];
        while let Some(jj) = j {
            b[jj] = b[jj] - f[i][jj] * b[i];
            j = lambda[jj];
        }
    }
    for i in 0..n {
        b[i] = b[i] / f[i][i];
    }
    for i in 0..n {
        let mut j = lambda[i];
        while let Some(jj) = j {
            b[i] = b[i] - f[i][jj] * b[jj];
            j = lambda[jj];
        }
    }
    b
}

/// Is `f` structurally zero?
fn is_zero_force<S: Scalar>(f: &Force<S>) -> bool {
    f.n.0.iter().chain(&f.f.0).all(|x| x.is_zero())
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
