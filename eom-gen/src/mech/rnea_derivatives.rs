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
    /// composite-rigid-body mass matrix (Featherstone §6.2) in world axes,
    /// from the recursion's `P_k = Yc_k S_k`, exactly symmetric.
    pub m: Vec<Vec<S>>,
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
    /// by the recursion of the module documentation; `None` where it does
    /// not apply ([`Self::recursive_derivatives_apply`]).
    pub fn rnea_derivatives(&self, k: &Kinematics<S>, ud: &[S]) -> Option<RneaDerivatives<S>> {
        if !self.recursive_derivatives_apply() {
            return None;
        }
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
        // The free columns: (body, speed index, S in world axes).
        let mut cols: Vec<(usize, usize, Motion<S>)> = Vec::new();
        for (i, body) in bodies.iter().enumerate() {
            if let Coords::Free { u, .. } = body.coords {
                cols.extend(sw[i].iter().enumerate().map(|(c, s)| (i, u + c, *s)));
            }
        }
        // Per row: P = Yc S, Q = Ẏc S − S ×* Hc.
        let pq: Vec<(Force<S>, Force<S>)> = cols
            .iter()
            .map(|&(i, _, s)| {
                let q = ydc[i].mul_motion(s).sub(s.cross_force(hc[i]));
                (yc[i].mul_motion(s), q)
            })
            .collect();
        let nu = self.tree.nu;
        let mut dq = vec![vec![S::zero(); nu]; nu];
        let mut du = vec![vec![S::zero(); nu]; nu];
        let mut m = vec![vec![S::zero(); nu]; nu];
        // Per column: the pass over the rows.
        for &(j, col, s) in &cols {
            let parent = bodies[j].parent;
            let (vl, al) = parent.map_or((Motion::zero(), base), |p| (vw[p], aw[p]));
            let w = vl.cross_motion(s);
            let psi = al.cross_motion(s).sub(w.cross_motion(vl));
            let beta = vl.add(vw[j]).cross_motion(s);
            let bc = |x: Motion<S>| ydc[j].mul_motion(x).add(x.cross_force(hc[j]));
            let dq_j = s.cross_force(fc[j]).add(yc[j].mul_motion(psi)).add(bc(w));
            let du_j = yc[j].mul_motion(beta).add(bc(s));
            for (&(i, row, si), &(p, q)) in cols.iter().zip(&pq) {
                if self.descends(i, j) {
                    dq[row][col] = psi.dot(p) + w.dot(q);
                    du[row][col] = beta.dot(p) + s.dot(q);
                    let mij = s.dot(p);
                    m[row][col] = mij;
                    m[col][row] = mij;
                } else if self.descends(j, i) {
                    dq[row][col] = si.dot(dq_j);
                    du[row][col] = si.dot(du_j);
                }
            }
        }
        Some(RneaDerivatives { dq, du, m })
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
