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
