//! Inverse dynamics by the recursive Newton–Euler algorithm (Featherstone
//! §5.3): `τ = M u̇ + C + g − Jᵀ f_ext` in one forward and one backward
//! pass over the bodies.

// Index loops over small dense matrices read like the textbook formulas.
#![allow(clippy::needless_range_loop)]

use super::kinematics::{Evaluator, Kinematics};
use super::spatial::{Force, Motion, is_zero_force};
use super::tree::Coords;
use crate::sym::{Scalar, Vec3};
use std::ops::{Add, Sub};

impl<'a, S: Scalar> Evaluator<'a, S> {
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

    pub(super) fn joint_ud(&self, i: usize, k: &Kinematics<S>, ud: &[S]) -> Vec<S> {
        match (&self.tree.bodies[i].coords, &k.known_ud[i]) {
            (Coords::Free { u, .. }, _) => ud[*u..*u + k.s[i].len()].to_vec(),
            (_, Some(known)) => known.clone(),
            _ => vec![S::zero(); k.s[i].len()],
        }
    }
}
