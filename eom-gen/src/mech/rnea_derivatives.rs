//! Derivatives of inverse dynamics by recursion over the tree (Carpentier
//! and Mansard, "Analytical Derivatives of Rigid Body Dynamics
//! Algorithms", RSS 2018): `∂τ/∂q` (tangent space) and `∂τ/∂u` of the
//! recursive Newton–Euler forces `M u̇ + C + g` in one forward and one
//! backward pass and one pass over pairs of joints, instead of
//! differentiating the straight-line expressions of Newton–Euler.
//!
//! Everything is in world coordinates at the world origin (spatial
//! vectors, Featherstone ch. 2). A tangent step `ε` along column `s` of
//! joint `j` (speed `u_j`, see [`super::derivatives`]) moves the subtree
//! of `j` rigidly by `exp(ε s)`: every quantity attached to a body of
//! that subtree (its subspace `S_k`, inertia `Y_k`) changes by `s ×`
//! (`δS_k = s × S_k`, `δY_k = s ×* Y_k − Y_k s ×`). With `λ` the parent
//! of `j` (`v_λ = 0`, `a_λ = −g` at the ground), `v̄_k = v_k − v_λ`:
//!
//! ```text
//! δv_k = s × v̄_k
//! δa_k = s × (a_k − a_λ) + w × v̄_k,             w = v_λ × s
//! δf_k = s ×* f_k + Y_k ψ + B_k w,               ψ = a_λ × s − w × v_λ
//! B_k x = Ẏ_k x + x ×* h_k,                      Ẏ_k = v_k ×* Y_k − Y_k v_k ×,  h_k = Y_k v_k
//! ```
//!
//! and, for the speed `u_j` itself, `δv_k = s`, `δa_k = s × v_k + β`,
//! `β = (v_λ + v_j) × s`, `δf_k = Y_k β + B_k s`. Summed over a subtree
//! these need only the composite `Y`, `Ẏ` (itself a rigid inertia of
//! zero mass), momentum `H` and force `F`. With `τ_i = S_i · F_i`, and
//! `(s × S_i)·F_i + S_i·(s ×* F_i) = 0`:
//!
//! ```text
//! i in the subtree of j:   ∂τ_i/∂q_j = P_i·ψ + Q_i·w,   ∂τ_i/∂u_j = P_i·β + Q_i·s
//! i an ancestor of j:      ∂τ_i/∂q_j = S_i·(s ×* F_j + Yc_j ψ + Bc_j w)
//!                          ∂τ_i/∂u_j = S_i·(Yc_j β + Bc_j s)
//! P_i = Yc_i S_i,   Q_i = Bc_iᵀ S_i = Ẏc_i S_i − S_i ×* Hc_i
//! ```
//!
//! (zero otherwise). The per-pair work is two 6-vector dot products. The
//! same `P_i` give the mass matrix, `M_ij = S_j·P_i` for `i` in the subtree
//! of `j` (Featherstone §6.2), one more dot product per pair: `M⁻¹` can then
//! come from its `LᵀDL` factors ([`super::ltdl::ltdl_inverse`]).
//!
//! Body axes ([`Axes::Body`]): the formulas hold in any axes, as every
//! term (`×`, `×*`, `Ẏ`, `B`) transforms with the frame. In a body's own
//! axes its inertia is constant and a joint's subspace column a unit axis
//! (for a coordinate axis `s × x` is a permutation of `x`, and `Yc s` a
//! column of `Yc`); the composites add after the usual transform to the
//! parent (`Xᵀ Y X`, eq. 2.66, with the joint's pose, itself sparse), and
//! `v_λ`, `a_λ` are the parent's velocity and acceleration in the child's
//! axes, which Newton–Euler builds anyway. Only the per-pair dot products
//! need common axes: each column's `s`, `w`, `ψ`, `β`, `P`, `Q` and the
//! two ancestor terms are brought to them once (eight transforms per
//! column), to the root body's own axes where the tree has a single root
//! (poses one joint shorter than the world's), else to world axes; pairs
//! of columns of one body (a column with itself included) stay in its
//! own axes. [`Axes::Paths`] needs no common axes at all: every pair is
//! one body and one of its ancestors (or itself), so each column's force
//! terms (`P`, `Q` and the two ancestor terms) are carried up its path one
//! joint at a time (each a sparse pose), and the pair is taken in the
//! ancestor's own axes, where its column's `s`, `w`, `β` are still sparse
//! and `S_i ·` picks one entry (arm7's forward dynamics derivatives: 6 081
//! operations with common axes, 5 414 along the paths, counted before
//! sums were factored a second time; the formulation keeps whichever
//! counts fewer). [`Axes::World`] instead brings each
//! body's velocity, acceleration, inertia, its rate, momentum and force to
//! world axes and does the rest there (dense).
//!
//! The recursion covers joints whose subspace is constant in body axes
//! (revolute, prismatic, cylindrical, screw, spherical, free, fixed) on
//! rigid bodies; [`Evaluator::rnea_derivatives`] returns `None` for trees
//! with other joints or flexible bodies. Forces of the model's force
//! elements (`Jᵀ f_ext`, generalised forces) are not part of it:
//! [`Evaluator::load_torques`] gives them as expressions to differentiate
//! directly.

// Index loops over small dense matrices read like the textbook formulas.
#![allow(clippy::needless_range_loop)]

use super::joint::JointModel;
use super::kinematics::{Evaluator, Kinematics};
use super::spatial::{Force, Motion, Pose, RigidInertia};
use super::tree::Coords;
use crate::sym::{Mat3, Scalar, Vec3};
use std::ops::{Add, Sub};

/// `∂τ/∂q` (tangent space) and `∂τ/∂u` of Newton–Euler, and the mass
/// matrix `M = ∂τ/∂u̇` from the same composites, each `nu × nu` by rows.
pub struct RneaDerivatives<S> {
    /// `∂τ/∂q` in the tangent space.
    pub dq: Vec<Vec<S>>,
    /// `∂τ/∂u`.
    pub du: Vec<Vec<S>>,
    /// `M`, `M_ij = S_i · Yc_k S_j` with `k` the deeper of the two joints'
    /// bodies (zero where neither is an ancestor of the other): the
    /// composite-rigid-body mass matrix (Featherstone §6.2) in the pairs'
    /// common axes, from the recursion's `P_k = Yc_k S_k`, exactly symmetric.
    pub m: Vec<Vec<S>>,
}

/// Where [`Evaluator::rnea_derivatives`] does its per-body and per-column
/// algebra (the pass over pairs is in common axes either way).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axes {
    /// World axes throughout: the composites add as they are.
    World,
    /// Body axes, where inertias are constant and subspace columns unit
    /// axes; each column's terms brought to common axes once (a single
    /// root body's, else the world's).
    Body,
    /// Body axes throughout, no common axes: for the pairs, each column's
    /// force terms (`P`, `Q`, and the ancestor terms) are carried joint by
    /// joint up its path to the root, and every pair is taken in the axes
    /// of the shallower body, where that column's motion terms are still
    /// sparse (a unit axis `s`, `w` and `β` with four entries) and the
    /// shallower row's `S_i ·` of the ancestor terms picks one entry.
    /// Four force transforms per column and ancestor, each by a joint's
    /// own pose (a rotation about one axis and an offset), instead of eight
    /// dense transforms per column and dense dot products.
    Paths,
}

/// The terms of one free column `j` of the recursion (rows are the same
/// speeds) in some axes: the subspace column `s` and `w`, `ψ`, `β`
/// (motions), `P = Yc s`, `Q = Ẏc s − s ×* Hc` (its row's terms), and the
/// terms its ancestors' rows take, `s ×* F + Yc ψ + Bc w` and `Yc β + Bc s`.
#[derive(Clone, Copy)]
struct Terms<S> {
    s: Motion<S>,
    w: Motion<S>,
    psi: Motion<S>,
    beta: Motion<S>,
    p: Force<S>,
    q: Force<S>,
    dq: Force<S>,
    du: Force<S>,
}

impl<S: Scalar> Terms<S> {
    /// The terms in the parent axes of `pose` (for a body's world pose, in
    /// world axes).
    fn to_parent(self, pose: &Pose<S>) -> Self {
        Terms {
            s: pose.motion_to_parent(self.s),
            w: pose.motion_to_parent(self.w),
            psi: pose.motion_to_parent(self.psi),
            beta: pose.motion_to_parent(self.beta),
            p: pose.force_to_parent(self.p),
            q: pose.force_to_parent(self.q),
            dq: pose.force_to_parent(self.dq),
            du: pose.force_to_parent(self.du),
        }
    }
}

/// One free column: its body, speed index and terms in the axes common
/// to all columns, and in its body's own axes (for pairs of columns of the
/// same body).
struct Column<S> {
    body: usize,
    index: usize,
    common: Terms<S>,
    own: Terms<S>,
}

/// A symmetric 3×3 matrix from its upper triangle `f(r, c)`, `r ≤ c`
/// (each entry built once).
fn symmetric<S: Scalar>(f: impl Fn(usize, usize) -> S) -> Mat3<S> {
    let mut m = Mat3::zero();
    for r in 0..3 {
        for c in r..3 {
            let x = f(r, c);
            m.0[r][c] = x;
            m.0[c][r] = x;
        }
    }
    m
}

/// `Xᵀ Y X`: a rigid inertia about the body origin in the parent frame
/// of `pose` (eq. 2.66), built for symmetry: with `h' = E h`,
/// `Ī' = E Ī Eᵀ − m([r×]²) − [r×][h'×] − [h'×][r×]` and
/// `[a×][b×] = b aᵀ − (a·b) 1`.
fn inertia_to_parent<S: Scalar>(y: &RigidInertia<S>, pose: &Pose<S>) -> RigidInertia<S> {
    let (e, r) = (pose.e, pose.r);
    let h = e.mul_vec(y.h);
    let ei = e * y.i;
    let (rr, rh) = (r.dot(r), r.dot(h));
    let i = symmetric(|a, b| {
        let rot = (0..3).fold(S::zero(), |acc, k| acc + ei.0[a][k] * e.0[b][k]);
        let outer = (r.0[a] * r.0[b]) * y.m + h.0[a] * r.0[b] + r.0[a] * h.0[b];
        let diag = if a == b {
            rr * y.m + rh + rh
        } else {
            S::zero()
        };
        rot - outer + diag
    });
    RigidInertia {
        m: y.m,
        h: h + r.scale(y.m),
        i,
    }
}

/// `Ẏ = v ×* Y − Y v ×` of a rigid inertia `Y` moving with `v` (same
/// frame): a rigid inertia of zero mass, first moment `ω × h + m ν` and
/// rotational part `ω×Ī − Īω× − ν×h× − h×ν×`.
fn inertia_rate<S: Scalar>(y: &RigidInertia<S>, v: Motion<S>) -> RigidInertia<S> {
    let (w, nu, h) = (v.w, v.v, y.h);
    let m = w.skew() * y.i;
    // ω×Ī − Īω× = M + Mᵀ; [ν×][h×] = h νᵀ − (ν·h) 1, plus its transpose.
    let nh = nu.dot(h);
    let i = symmetric(|r, c| {
        let outer = h.0[r] * nu.0[c] + nu.0[r] * h.0[c];
        let diag = if r == c { nh + nh } else { S::zero() };
        m.0[r][c] + m.0[c][r] - outer + diag
    });
    RigidInertia {
        m: S::zero(),
        h: w.cross(h) + nu.scale(y.m),
        i,
    }
}

impl<'a, S: Scalar> Evaluator<'a, S> {
    /// Does [`Self::rnea_derivatives`] cover this tree?
    pub fn recursive_derivatives_apply(&self) -> bool {
        self.tree.bodies.iter().all(|b| {
            b.flex.is_none()
                && b.node.is_none()
                && matches!(
                    b.kind,
                    JointModel::Revolute(_)
                        | JointModel::Prismatic(_)
                        | JointModel::Cylindrical(_)
                        | JointModel::Screw(..)
                        | JointModel::Spherical
                        | JointModel::Free
                        | JointModel::Fixed
                )
        })
    }

    /// `∂τ/∂q` (tangent space) and `∂τ/∂u` of the Newton–Euler forces
    /// `M u̇ + C + g` at the accelerations `ud` (force elements left out),
    /// by the recursion of the module documentation in `axes`; `None`
    /// where it does not apply ([`Self::recursive_derivatives_apply`]).
    pub fn rnea_derivatives(
        &self,
        k: &Kinematics<S>,
        ud: &[S],
        axes: Axes,
    ) -> Option<RneaDerivatives<S>> {
        if !self.recursive_derivatives_apply() {
            return None;
        }
        Some(match axes {
            Axes::World => self.rnea_derivatives_world_axes(k, ud),
            Axes::Body => self.rnea_derivatives_body_axes(k, ud, false),
            Axes::Paths => self.rnea_derivatives_body_axes(k, ud, true),
        })
    }

    /// [`Self::rnea_derivatives`] in world axes throughout.
    fn rnea_derivatives_world_axes(&self, k: &Kinematics<S>, ud: &[S]) -> RneaDerivatives<S> {
        let bodies = &self.tree.bodies;
        let n = bodies.len();
        let base = Motion {
            w: Vec3::zero(),
            v: -self.tree.gravity,
        };
        // Forward pass over bodies: accelerations (body axes), then the
        // world-axis subspace, velocity, acceleration, inertia, its rate,
        // momentum and net force.
        let mut a_body: Vec<Motion<S>> = Vec::with_capacity(n);
        let mut sw: Vec<Vec<Motion<S>>> = Vec::with_capacity(n);
        let (mut vw, mut aw) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let (mut yc, mut ydc) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let (mut hc, mut fc) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for (i, body) in bodies.iter().enumerate() {
            let ap = body.parent.map_or(base, |p| a_body[p]);
            let mut ai = k.x[i]
                .motion_to_child(ap)
                .add(k.c[i])
                .add(k.v[i].cross_motion(k.vj[i]));
            for (col, &x) in k.s[i].iter().zip(&self.joint_ud(i, k, ud)) {
                ai = ai.add(col.scale(x));
            }
            a_body.push(ai);
            let pose = &k.world[i];
            let inertia = &k.inertia[i];
            let h = inertia.mul_motion(k.v[i]);
            let f = inertia.mul_motion(ai).add(k.v[i].cross_force(h));
            let (v, y) = (
                pose.motion_to_parent(k.v[i]),
                inertia_to_parent(inertia, pose),
            );
            sw.push(k.s[i].iter().map(|c| pose.motion_to_parent(*c)).collect());
            vw.push(v);
            aw.push(pose.motion_to_parent(ai));
            ydc.push(inertia_rate(&y, v));
            yc.push(y);
            hc.push(pose.force_to_parent(h));
            fc.push(pose.force_to_parent(f));
        }
        // Backward pass over bodies: composites (world axes, so they add).
        for i in (0..n).rev() {
            if let Some(p) = bodies[i].parent {
                yc[p] = yc[p] + yc[i];
                ydc[p] = ydc[p] + ydc[i];
                hc[p] = hc[p].add(hc[i]);
                fc[p] = fc[p].add(fc[i]);
            }
        }
        // Per free column: `S`, `w`, `ψ`, `β`, `P`, `Q` and the ancestor
        // terms, all in world axes.
        let mut cols: Vec<Column<S>> = Vec::new();
        for (j, body) in bodies.iter().enumerate() {
            let Coords::Free { u, .. } = body.coords else {
                continue;
            };
            let parent = body.parent;
            let (vl, al) = parent.map_or((Motion::zero(), base), |p| (vw[p], aw[p]));
            for (c, &s) in sw[j].iter().enumerate() {
                let w = vl.cross_motion(s);
                let psi = al.cross_motion(s).sub(w.cross_motion(vl));
                let beta = vl.add(vw[j]).cross_motion(s);
                let bc = |x: Motion<S>| ydc[j].mul_motion(x).add(x.cross_force(hc[j]));
                let world = Terms {
                    s,
                    w,
                    psi,
                    beta,
                    p: yc[j].mul_motion(s),
                    q: ydc[j].mul_motion(s).sub(s.cross_force(hc[j])),
                    dq: s.cross_force(fc[j]).add(yc[j].mul_motion(psi)).add(bc(w)),
                    du: yc[j].mul_motion(beta).add(bc(s)),
                };
                cols.push(Column {
                    body: j,
                    index: u + c,
                    common: world,
                    own: world,
                });
            }
        }
        self.pairs(&cols)
    }

    /// [`Self::rnea_derivatives`] with the recursion in body axes (the
    /// same formulas; see the module documentation, "Body axes"); the pairs
    /// in common axes, or with `paths` along the tree's paths
    /// ([`Axes::Paths`]).
    fn rnea_derivatives_body_axes(
        &self,
        k: &Kinematics<S>,
        ud: &[S],
        paths: bool,
    ) -> RneaDerivatives<S> {
        let bodies = &self.tree.bodies;
        let n = bodies.len();
        let base = Motion {
            w: Vec3::zero(),
            v: -self.tree.gravity,
        };
        // Forward pass over bodies (body axes): the parent's velocity and
        // acceleration in this body's axes (`v_λ`, `a_λ`; at the ground 0
        // and `−g`), the acceleration, momentum, net force and inertia rate.
        let mut a_body: Vec<Motion<S>> = Vec::with_capacity(n);
        let (mut vl, mut al) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let (mut yc, mut ydc) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let (mut hc, mut fc) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for (i, body) in bodies.iter().enumerate() {
            let (vp, ap) = match body.parent {
                Some(p) => (
                    k.x[i].motion_to_child(k.v[p]),
                    k.x[i].motion_to_child(a_body[p]),
                ),
                None => (Motion::zero(), k.x[i].motion_to_child(base)),
            };
            let mut ai = ap.add(k.c[i]).add(k.v[i].cross_motion(k.vj[i]));
            for (col, &x) in k.s[i].iter().zip(&self.joint_ud(i, k, ud)) {
                ai = ai.add(col.scale(x));
            }
            a_body.push(ai);
            let inertia = &k.inertia[i];
            let h = inertia.mul_motion(k.v[i]);
            fc.push(inertia.mul_motion(ai).add(k.v[i].cross_force(h)));
            hc.push(h);
            ydc.push(inertia_rate(inertia, k.v[i]));
            yc.push(*inertia);
            vl.push(vp);
            al.push(ap);
        }
        // Backward pass over bodies: composites in body axes (a child's
        // brought over by its joint's pose, Featherstone eq. 2.66).
        for i in (0..n).rev() {
            if let Some(p) = bodies[i].parent {
                let x = &k.x[i];
                yc[p] = yc[p] + inertia_to_parent(&yc[i], x);
                ydc[p] = ydc[p] + inertia_to_parent(&ydc[i], x);
                hc[p] = hc[p].add(x.force_to_parent(hc[i]));
                fc[p] = fc[p].add(x.force_to_parent(fc[i]));
            }
        }
        // The common axes of the pairs: a single root body's own (its
        // descendants' poses in it are one joint shorter than in the
        // world, its own terms need no transform), else the world's.
        let roots = bodies.iter().filter(|b| b.parent.is_none()).count();
        let common: Vec<Pose<S>> = if paths {
            Vec::new()
        } else if roots == 1 {
            let mut poses: Vec<Pose<S>> = Vec::with_capacity(n);
            for (i, body) in bodies.iter().enumerate() {
                let pose = body
                    .parent
                    .map_or_else(Pose::identity, |p| poses[p].then(&k.x[i]));
                poses.push(pose);
            }
            poses
        } else {
            k.world.clone()
        };
        // Per free column, in body axes then once to the common axes: `S`,
        // `w`, `ψ`, `β` (motions), `P`, `Q`, and the ancestor terms (forces).
        let mut cols: Vec<Column<S>> = Vec::new();
        for (j, body) in bodies.iter().enumerate() {
            let Coords::Free { u, .. } = body.coords else {
                continue;
            };
            let (v, a) = (vl[j], al[j]);
            for (c, &s) in k.s[j].iter().enumerate() {
                let w = v.cross_motion(s);
                let psi = a.cross_motion(s).sub(w.cross_motion(v));
                let beta = v.add(k.v[j]).cross_motion(s);
                let bc = |x: Motion<S>| ydc[j].mul_motion(x).add(x.cross_force(hc[j]));
                let dq = s.cross_force(fc[j]).add(yc[j].mul_motion(psi)).add(bc(w));
                let du = yc[j].mul_motion(beta).add(bc(s));
                let own = Terms {
                    s,
                    w,
                    psi,
                    beta,
                    p: yc[j].mul_motion(s),
                    q: ydc[j].mul_motion(s).sub(s.cross_force(hc[j])),
                    dq,
                    du,
                };
                cols.push(Column {
                    body: j,
                    index: u + c,
                    // (Along the paths there are no common axes, and
                    // `common` is not read.)
                    common: common.get(j).map_or(own, |pose| own.to_parent(pose)),
                    own,
                });
            }
        }
        if paths {
            self.pairs_along_paths(k, &cols)
        } else {
            self.pairs(&cols)
        }
    }

    /// The pass over pairs of columns (module documentation): `∂τ/∂q`,
    /// `∂τ/∂u` and `M` from the columns' terms.
    fn pairs(&self, cols: &[Column<S>]) -> RneaDerivatives<S> {
        let nu = self.tree.nu;
        let mut dq = vec![vec![S::zero(); nu]; nu];
        let mut du = vec![vec![S::zero(); nu]; nu];
        let mut m = vec![vec![S::zero(); nu]; nu];
        for cj in cols {
            let col = cj.index;
            for ci in cols {
                let row = ci.index;
                // Dot products in any common axes: a body's own where
                // both columns are its.
                let (tj, ti) = if ci.body == cj.body {
                    (&cj.own, &ci.own)
                } else {
                    (&cj.common, &ci.common)
                };
                if self.descends(ci.body, cj.body) {
                    dq[row][col] = tj.psi.dot(ti.p) + tj.w.dot(ti.q);
                    du[row][col] = tj.beta.dot(ti.p) + tj.s.dot(ti.q);
                    let mij = tj.s.dot(ti.p);
                    m[row][col] = mij;
                    m[col][row] = mij;
                } else if self.descends(cj.body, ci.body) {
                    dq[row][col] = ti.s.dot(tj.dq);
                    du[row][col] = ti.s.dot(tj.du);
                }
            }
        }
        RneaDerivatives { dq, du, m }
    }

    /// The pass over pairs along the tree's paths ([`Axes::Paths`]): the
    /// same entries as [`Self::pairs`], each pair in the axes of the
    /// shallower column's body. Every column `d` carries its force terms
    /// `P_d`, `Q_d` and its ancestor terms up its path, one joint's pose at
    /// a time; at each body `b` on the way (its own first), for every column
    /// `a` of `b`:
    ///
    /// ```text
    /// ∂τ_d/∂q_a = ψ_a·P_d + w_a·Q_d,   ∂τ_d/∂u_a = β_a·P_d + s_a·Q_d,   M_da = M_ad = s_a·P_d
    /// ∂τ_a/∂q_d = s_a·(ancestor term ∂q of d),   ∂τ_a/∂u_d = s_a·(… ∂u of d)   (b above d's body)
    /// ```
    ///
    /// (a dot product of a force and a motion does not depend on the axes
    /// both are in).
    fn pairs_along_paths(&self, k: &Kinematics<S>, cols: &[Column<S>]) -> RneaDerivatives<S> {
        let nu = self.tree.nu;
        let mut dq = vec![vec![S::zero(); nu]; nu];
        let mut du = vec![vec![S::zero(); nu]; nu];
        let mut m = vec![vec![S::zero(); nu]; nu];
        for deep in cols {
            let d = deep.index;
            let own = &deep.own;
            let (mut p, mut q, mut fq, mut fu) = (own.p, own.q, own.dq, own.du);
            let mut b = deep.body;
            loop {
                for anc in cols.iter().filter(|c| c.body == b) {
                    let (a, t) = (anc.index, &anc.own);
                    dq[d][a] = t.psi.dot(p) + t.w.dot(q);
                    du[d][a] = t.beta.dot(p) + t.s.dot(q);
                    let mda = t.s.dot(p);
                    m[d][a] = mda;
                    m[a][d] = mda;
                    if b != deep.body {
                        dq[a][d] = t.s.dot(fq);
                        du[a][d] = t.s.dot(fu);
                    }
                }
                let Some(parent) = self.tree.bodies[b].parent else {
                    break;
                };
                let x = &k.x[b];
                (p, q) = (x.force_to_parent(p), x.force_to_parent(q));
                (fq, fu) = (x.force_to_parent(fq), x.force_to_parent(fu));
                b = parent;
            }
        }
        RneaDerivatives { dq, du, m }
    }

    /// Is body `i` body `j` or in its subtree?
    fn descends(&self, mut i: usize, j: usize) -> bool {
        loop {
            if i == j {
                return true;
            }
            match self.tree.bodies[i].parent {
                Some(p) => i = p,
                None => return false,
            }
        }
    }

    /// `−Jᵀ f_ext`: the generalised forces of the loads `fext` (one per
    /// body, body axes) on the free speeds, with the sign they have in
    /// inverse dynamics; for trees [`Self::rnea_derivatives`] covers.
    pub fn load_torques(&self, k: &Kinematics<S>, fext: &[Force<S>]) -> Vec<S> {
        let bodies = &self.tree.bodies;
        let mut f: Vec<Force<S>> = fext[..bodies.len()].to_vec();
        let mut tau = vec![S::zero(); self.tree.nu];
        // Backward pass over bodies: project on the joints, pass to parents.
        for i in (0..bodies.len()).rev() {
            if let Coords::Free { u, .. } = bodies[i].coords {
                for (c, col) in k.s[i].iter().enumerate() {
                    tau[u + c] = -col.dot(f[i]);
                }
            }
            if let Some(p) = bodies[i].parent {
                let fp = k.x[i].force_to_parent(f[i]);
                f[p] = f[p].add(fp);
            }
        }
        tau
    }
}
