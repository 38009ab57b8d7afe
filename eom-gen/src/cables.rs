//! A checked model whose cables hang at markers of its rigid bodies, as
//! one large model of `eom_sim::large::mixed`: the cable built by its
//! kernel's name, its ends held at the markers by attachment constraints,
//! and the rigid part from the generated functions (`mass_matrix`, `bias`,
//! `energy`, `attachments`), interpreted or compiled.
//!
//! A rigid part with constraint equations of its own (cut joints closing
//! loops, the model's holonomic `constraints:`, rheonomic ones included)
//! brings their position-level rows `Φ_r(q, t) = 0` and `Φ_q` from the
//! generated `constraints` function (`J = Φ_q` as `q̇ = u`): more rows of
//! the mixed model's constraint block ([`RigidPart::constraints`]). Its
//! start is assembled onto the loops ([`rigid_start`]). Speed-level
//! (nonholonomic) equations, such as a rolling disk's no-slip
//! conditions, are refused by name: the index-3 method holds positions.

use crate::functions::Function;
use crate::mech::Formulation;
use crate::system::System;
use eom_sim::large::ancf::chain;
use eom_sim::large::{ByName, MixedModel, RigidPart};

/// A mixed model and how to read its cable.
pub struct Mixed<'r> {
    /// The model.
    pub model: MixedModel<'r>,
    /// The cable's name.
    pub cable: String,
    /// Its kernel's name.
    pub kernel: &'static str,
    /// Dimension of positions (2 or 3).
    pub dim: usize,
    /// Coordinates per node.
    pub node_coords: usize,
    /// Number of nodes.
    pub nodes: usize,
}

impl Mixed<'_> {
    /// Position of `node` in the structure's full coordinates (`z = 0`
    /// when planar).
    pub fn node_position(&self, q_full: &[f64], node: usize) -> [f64; 3] {
        let mut p = [0.0; 3];
        for (k, pk) in p.iter_mut().enumerate().take(self.dim) {
            *pk = q_full[node * self.node_coords + k];
        }
        p
    }
}

/// True if a cable end is held at a marker of a rigid body.
pub fn has_mounts(sys: &System) -> bool {
    !sys.cable_mounts().is_empty()
}

/// Why the rigid part of `sys` cannot join its cables, or `Ok`: the large
/// runtime needs `q̇ = u` (no quaternions, no speeds other than the
/// coordinates' rates), constraint equations of its own only at the
/// position level (holonomic: cut joints, `Holonomic` constraints), one
/// cable.
pub fn check_rigid(sys: &System, f: &Formulation) -> Result<(), String> {
    let mounted: Vec<usize> = sys.cable_mounts().iter().map(|(c, _, _)| *c).collect();
    if sys.cables.len() != 1 {
        return Err(format!(
            "model `{}` has {} cables and rigid bodies holding cable ends: one cable per such model for now",
            sys.name,
            sys.cables.len()
        ));
    }
    if mounted.is_empty() {
        return Err(format!(
            "no cable end of model `{}` is held at a marker (`start_at`/`end_at`)",
            sys.name
        ));
    }
    if f.constraint_names.len() > f.n_holonomic {
        return Err(format!(
            "the rigid part of `{}` has speed-level (nonholonomic) constraint equations ({}): beside cables the index-3 method holds positions only, `Φ(q, t) = 0` (cut joints, `Holonomic` constraints); a rolling contact's no-slip conditions have no position form",
            sys.name,
            f.constraint_names[f.n_holonomic..].join(", ")
        ));
    }
    let (nq, nu) = (sys.nq(), sys.nu());
    if nq != nu || !sys.quaternion_indices().is_empty() {
        return Err(format!(
            "the rigid part of `{}` has {nq} coordinates and {nu} speeds: cables join rigid parts whose speeds are the coordinates' rates (revolute, prismatic joints)",
            sys.name
        ));
    }
    // q̇ = u at a generic state.
    let q: Vec<f64> = sys
        .q0()
        .iter()
        .enumerate()
        .map(|(i, x)| x + 0.1 + 0.01 * i as f64)
        .collect();
    let u: Vec<f64> = (0..nu).map(|i| 0.3 + 0.7 * i as f64).collect();
    let x = crate::interpret::Point {
        sys,
        q: &q,
        u: &u,
        udot: &[],
        tau: &[],
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.0,
    };
    let qdot = crate::interpret::evaluate_function(f, Function::Qdot, &x).unwrap_or_default();
    if qdot.len() != nu
        || qdot
            .iter()
            .zip(&u)
            .any(|(a, b)| (a - b).abs() > 1e-12 * (1.0 + b.abs()))
    {
        return Err(format!(
            "the rigid part of `{}` has speeds that are not the coordinates' rates (q̇ ≠ u): cables join revolute and prismatic chains",
            sys.name
        ));
    }
    Ok(())
}

/// The rigid part of `sys` run by the interpreter (see [`check_rigid`]).
pub fn interpreted_rigid<'a>(f: &'a Formulation, sys: &'a System) -> Box<dyn RigidPart + 'a> {
    let interp = crate::interpret::Interpreted::new(f, sys);
    let len = crate::mech::mounts::mount_rows(sys) * (1 + sys.nq());
    Box::new(
        ByName::new(sys.nu(), len, move |name, at, out| {
            eom_sim::Simulate::evaluate(&interp, name, at, out)
        })
        .with_constraints(f.constraint_names.len(), holonomic_names(f)),
    )
}

/// The names of the rigid part's holonomic equations (the rows
/// [`RigidPart::constraints`] gives), for [`ByName::with_constraints`].
pub fn holonomic_names(f: &Formulation) -> Vec<String> {
    f.constraint_names[..f.n_holonomic.min(f.constraint_names.len())].to_vec()
}

/// The rigid part's starting coordinates and speeds: the model's `q0`,
/// `u0`, and when it has constraint equations of its own, assembled onto
/// them (`eom_sim::constrained::assemble`: Newton onto `Φ(q, t) = 0`, then
/// the smallest change of the speeds onto `J u + Φ_t = 0`). The cables'
/// reference lines are given in the file, at the markers of `q0`: an
/// assembly that has to move a coordinate by more than `1e-8` is refused,
/// naming the coordinate and the value that closes the loop.
pub fn rigid_start(sys: &System, f: &Formulation) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (q0, u0) = (sys.q0(), sys.u0());
    if f.constraint_names.is_empty() {
        return Ok((q0, u0));
    }
    let interp = crate::interpret::Interpreted::new(f, sys);
    let a = eom_sim::constrained::assemble(&interp, &q0, &u0, 0.0);
    if a.residual.is_nan() || a.residual > 1e-10 {
        return Err(format!(
            "the rigid part of `{}` does not close its loops near the initial values: |Φ| = {:.3e} after assembly ({}); check the joint frames and the initial values of the loop's joints",
            sys.name,
            a.residual,
            f.constraint_names.join(", ")
        ));
    }
    let names = sys.coordinate_names();
    let moved: Vec<String> = q0
        .iter()
        .zip(&a.q)
        .zip(&names)
        .filter(|((x, y), _)| (*x - *y).is_nan() || (*x - *y).abs() > 1e-8)
        .map(|((x, y), n)| format!("`{n}` from {x} to {y}"))
        .collect();
    if !moved.is_empty() {
        return Err(format!(
            "the initial values of `{}` do not close its loops ({}): assembly moves {}; give the closed values (the cables' `from`/`to` must meet their markers there)",
            sys.name,
            f.constraint_names.join(", "),
            moved.join(", ")
        ));
    }
    Ok((a.q, a.u))
}

/// The model's one cable joined to the rigid part `rigid` at its mounts.
pub fn mixed<'r>(sys: &System, rigid: Box<dyn RigidPart + 'r>) -> Result<Mixed<'r>, String> {
    let Some(c) = sys.cables.first() else {
        return Err(format!("model `{}` has no cables", sys.name));
    };
    let ch = chain(&c.chain).map_err(|e| format!("cable `{}`: {e}", c.name))?;
    let mut attachments = Vec::new();
    for (end, mount) in [(false, &c.start_at), (true, &c.end_at)] {
        if let Some(m) = mount {
            let name = format!("{}.{}", c.name, if end { "end" } else { "start" });
            attachments.push(ch.attachment(&name, end, m.axis.is_some()));
        }
    }
    let (kernel, dim, node_coords, nodes) = (ch.kernel, ch.dim, ch.node_coords, ch.nodes);
    let model = MixedModel::new(ch.model, rigid, attachments)
        .map_err(|e| format!("cable `{}`: {e}", c.name))?;
    Ok(Mixed {
        model,
        cable: c.name.clone(),
        kernel,
        dim,
        node_coords,
        nodes,
    })
}
