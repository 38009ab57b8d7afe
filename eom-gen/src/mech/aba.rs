//! Forward dynamics in O(n) by the articulated-body algorithm
//! (Featherstone §7.3), flexible bodies' elastic coordinates eliminated at
//! their body together with the subtrees hung at its nodes.

// Index loops over small dense matrices read like the textbook formulas.
#![allow(clippy::needless_range_loop)]

use super::dense::invert_spd;
use super::kinematics::{Evaluator, Kinematics};
use super::spatial::{Force, Inertia6, Motion, is_zero_force};
use super::tree::Coords;
use crate::sym::{Scalar, Vec3};
use std::ops::{Add, Sub};

/// A flexible body's elastic equations in the articulated-body algorithm,
/// `D q̈_f = u − Uᵀ a`: `D⁻¹`, `u` and the columns of `U`.
type Elimination<S> = (Vec<Vec<S>>, Vec<S>, Vec<Force<S>>);

impl<'a, S: Scalar> Evaluator<'a, S> {
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
}
