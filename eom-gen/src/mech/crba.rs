//! The joint-space mass matrix by the composite-rigid-body algorithm
//! (Featherstone §6.2): composite inertias in a backward pass, then one
//! column pair per free speed.

// Index loops over small dense matrices read like the textbook formulas.
#![allow(clippy::needless_range_loop)]

use super::kinematics::{Evaluator, Kinematics};
use super::spatial::Motion;
use super::tree::Coords;
use crate::sym::Scalar;
use std::ops::Add;

impl<'a, S: Scalar> Evaluator<'a, S> {
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
}
