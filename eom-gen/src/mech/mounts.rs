//! Where cable ends are held on rigid bodies (issue #18): per mount (a
//! cable end at a marker, `System::cable_mounts`) the marker's world
//! position and, for a clamped end, the two unit normals of the clamp's
//! axis in world axes. Written once over [`Scalar`]: on `f64` it is the
//! numeric twin ([`super::Numeric::mounts`]), on `Expr` the generated
//! function `attachments` (with the Jacobians `∂/∂q` the large-model
//! runtime's attachment constraints need).

use super::env::Env;
use super::error::MechError;
use super::kinematics::Kinematics;
use super::lower::Lowering;
use super::spatial::Pose;
use super::tree::TreeModel;
use crate::sym::{Scalar, Vec3};
use crate::system::System;

/// Two unit normals of the unit axis `a`, constant in marker axes:
/// `n₁ = (ẑ × a)/|ẑ × a|` (in the x–y plane when `a` is; `x̂ × a` when `a`
/// is along `ẑ`) and `n₂ = a × n₁`.
pub fn clamp_normals(a: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let norm = |u: [f64; 3]| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
    let mut n1 = cross([0.0, 0.0, 1.0], a);
    if norm(n1) < 1e-6 {
        n1 = cross([1.0, 0.0, 0.0], a);
    }
    let l = norm(n1);
    let n1 = n1.map(|x| x / l);
    let n2 = cross(a, n1);
    // Exact zeros stay exact in the generated code.
    let snap = |u: [f64; 3]| u.map(|x| if x.abs() < 1e-15 { 0.0 } else { x });
    (snap(n1), snap(n2))
}

/// Number of rows of mount values: 3 for a pinned end, 9 for a clamped
/// one (position, `n₁`, `n₂`).
pub fn mount_rows(sys: &System) -> usize {
    sys.cable_mounts()
        .iter()
        .map(|(_, _, m)| if m.axis.is_some() { 9 } else { 3 })
        .sum()
}

/// The mount values in order: per mount its marker's world position, and
/// for a clamped end `n₁`, `n₂` in world axes (see [`clamp_normals`]).
pub fn mount_values<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    k: &Kinematics<S>,
) -> Result<Vec<S>, MechError> {
    let low = Lowering::new(env);
    let mut out = Vec::new();
    for (_, _, m) in sys.cable_mounts() {
        let marker = &sys.bodies[m.body].markers[m.marker];
        let pose = low.frame(&marker.frame)?;
        let world: Pose<S> = match tree.index_of_body[m.body] {
            Some(i) => k.world[i].then(&pose),
            None => pose,
        };
        out.extend(world.r.0);
        if let Some(a) = m.axis {
            let (n1, n2) = clamp_normals(a);
            for n in [n1, n2] {
                out.extend(world.e.mul_vec(Vec3(n.map(S::from_f64))).0);
            }
        }
    }
    Ok(out)
}

/// The values per frame of [`frame_values`]: the point's position (3),
/// the body's axes by rows (9), the point's velocity (3) and the body's
/// angular velocity (3), world axes.
pub const FRAME_VALUES: usize = 18;

/// The frames of the bodies cable nodes touch (`System::cable_frames`), in
/// order, [`FRAME_VALUES`] each: the point's world position `p`, the
/// body's axes `e` in the world by rows, the point's velocity `ṗ` and the
/// body's angular velocity `ω` (world axes); a point at a flexible body's
/// node moves and turns with that node. On `f64` the numeric twin
/// ([`super::Numeric::contact_frames`]); on `Expr` the generated
/// `contact_frames` adds their rates at `u̇ = 0` and the rows `∂ṗ/∂u`,
/// `∂ω/∂u`.
pub fn frame_values<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &super::kinematics::Evaluator<'_, S>,
    k: &Kinematics<S>,
) -> Result<Vec<S>, MechError> {
    let low = Lowering::new(env);
    let mut out = Vec::new();
    for at in sys.cable_frames() {
        let point = low.vec3(&at.position)?;
        let body = tree.index_of_body[at.body];
        // The frame the point is fixed in, world pose and its spatial
        // velocity in its own axes (the ground: at rest).
        let (pose, motion) = match body {
            None => (Pose::identity(), super::spatial::Motion::zero()),
            Some(i) => at
                .node
                .and_then(|node| ev.node_frame(k, i, node))
                .unwrap_or((k.world[i], k.v[i])),
        };
        let p = pose.point(point);
        let v = pose.e.mul_vec(motion.v + motion.w.cross(point));
        let w = pose.e.mul_vec(motion.w);
        out.extend(p.0);
        for row in pose.e.0 {
            out.extend(row);
        }
        out.extend(v.0);
        out.extend(w.0);
    }
    Ok(out)
}

/// The frames of the bodies cable nodes touch at the initial state, in the
/// order of `System::cable_frames` (empty if they cannot be evaluated: the
/// model's own errors say why).
pub fn frames_at_start(sys: &System) -> Vec<crate::system::BodyFrame> {
    if sys.cable_frames().is_empty() {
        return Vec::new();
    }
    let Ok(num) = super::Numeric::new(sys) else {
        return Vec::new();
    };
    let Ok(values) = num.contact_frames(sys, &sys.q0(), &sys.u0(), 0.0) else {
        return Vec::new();
    };
    values
        .chunks(FRAME_VALUES)
        .map(|v| crate::system::BodyFrame {
            p: [v[0], v[1], v[2]],
            e: [[v[3], v[4], v[5]], [v[6], v[7], v[8]], [v[9], v[10], v[11]]],
        })
        .collect()
}
