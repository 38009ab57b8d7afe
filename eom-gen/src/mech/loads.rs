//! The force elements at one state: the spatial forces of the point
//! spring-dampers on bodies and nodes, and the generalised forces `Q` of
//! joint springs, joint forces and inputs, with their potential energies.

use super::applied::GenForce;
use super::error::MechError;
use super::kinematics::{Evaluator, Kinematics, State};
use super::lower::Lowering;
use super::spatial::Force;
use crate::sym::Scalar;
use std::ops::Add;

impl<'a, S: Scalar> Evaluator<'a, S> {
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
}
