//! Energies and momentum at one state: kinetic energy (with the flexible
//! bodies' elastic terms), gravitational potential, spatial momentum.

use super::kinematics::{Evaluator, Kinematics};
use super::spatial::Force;
use crate::sym::Scalar;
use std::ops::Add;

impl<'a, S: Scalar> Evaluator<'a, S> {
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
}
