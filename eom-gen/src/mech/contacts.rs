//! Unilateral contacts (issue #26; Wittenburg ch. 6, Pfeiffer and Glocker):
//! per gap row of [`System::contact_rows`] the gap `g(q)` and its normal
//! speed `ġ = w(q)ᵀ u`. Written once over [`Scalar`]: on `f64` it is the
//! numeric twin ([`super::Numeric::contacts`], which the validator uses to
//! refuse a contact closed at the initial state), on `Expr` the generated
//! function `contacts` (`formulate` adds `w = ∂ġ/∂u` and the acceleration
//! term `γ` with `g̈ = wᵀ u̇ − γ`).

use super::applied::Site;
use super::env::Env;
use super::error::MechError;
use super::kinematics::{Evaluator, Kinematics};
use super::lower::Lowering;
use super::tree::TreeModel;
use crate::sym::{Scalar, Vec3};
use crate::system::{ContactKind, Point, System};
use std::ops::Add;

/// The gap `g` and normal speed `ġ` of every contact row, in the order of
/// [`System::contact_rows`].
pub fn gaps<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
    q: &[S],
    u: &[S],
) -> Result<Vec<(S, S)>, MechError> {
    let low = Lowering::new(env);
    let site = |p: &Point| -> Result<(Vec3<S>, Vec3<S>), MechError> {
        let s = Site {
            body: tree.index_of_body[p.body],
            node: p.node,
            point: low.vec3(&p.position)?,
        };
        Ok(ev.site(k, &s))
    };
    let mut out = Vec::new();
    for c in &sys.contacts {
        match &c.kind {
            ContactKind::JointLimit {
                joint,
                lower,
                upper,
            } => {
                let j = &sys.joints[*joint];
                let (qj, uj) = (q[j.q_index], u[j.u_index]);
                if let Some(l) = lower {
                    out.push((qj - low.quantity(l)?, uj));
                }
                if let Some(h) = upper {
                    out.push((low.quantity(h)? - qj, -uj));
                }
            }
            ContactKind::Plane {
                at,
                radius,
                point,
                normal,
            } => {
                let (x, v) = site(at)?;
                let n = Vec3::from_f64(
                    [normal.unit.x, normal.unit.y, normal.unit.z].map(super::lower::snap),
                );
                let p = low.vec3(point)?;
                out.push((n.dot(x - p) - low.quantity(radius)?, n.dot(v)));
            }
            ContactKind::Spheres {
                a,
                b,
                radius_a,
                radius_b,
            } => {
                let (xa, va) = site(a)?;
                let (xb, vb) = site(b)?;
                let d = xa - xb;
                let dist = d.norm();
                let g = dist - low.quantity(radius_a)? - low.quantity(radius_b)?;
                out.push((g, d.dot(va - vb) / dist));
            }
        }
    }
    Ok(out)
}

/// Per gap row, the loads (in the layout of [`TreeModel::loads`]) of a
/// unit normal impulse `Λ = 1`: along `n` at a plane contact's centre,
/// along `±d̂` at the centres of two spheres (the line of action passes
/// through the contact point, so the centre carries the same moment).
/// Joint limits act inside their joint: no load.
pub fn unit_loads<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
) -> Result<Vec<Vec<super::spatial::Force<S>>>, MechError> {
    use super::spatial::Force;
    let low = Lowering::new(env);
    let mut out = Vec::new();
    // A world force `fw` at body point `p` into `loads`.
    let apply = |loads: &mut Vec<Force<S>>, p: &Point, fw: Vec3<S>| -> Result<(), MechError> {
        let Some(i) = tree.index_of_body[p.body] else {
            return Ok(());
        };
        let point = low.vec3(&p.position)?;
        let (slot, frame) = match p.node {
            Some(node) => match tree.node_load(i, node) {
                Some(slot) => (slot, ev.node_frame(k, i, node).map(|x| x.0)),
                None => (i, None),
            },
            None => (i, None),
        };
        let fb = frame.unwrap_or(k.world[i]).e.tr_mul_vec(fw);
        loads[slot] = loads[slot].add(Force {
            n: point.cross(fb),
            f: fb,
        });
        Ok(())
    };
    for c in &sys.contacts {
        let fresh = || vec![Force::zero(); tree.loads()];
        match &c.kind {
            ContactKind::JointLimit { lower, upper, .. } => {
                for _ in lower.iter().chain(upper) {
                    out.push(fresh());
                }
            }
            ContactKind::Plane { at, normal, .. } => {
                let n = Vec3::from_f64(
                    [normal.unit.x, normal.unit.y, normal.unit.z].map(super::lower::snap),
                );
                let mut l = fresh();
                apply(&mut l, at, n)?;
                out.push(l);
            }
            ContactKind::Spheres { a, b, .. } => {
                let site = |p: &Point| -> Result<Vec3<S>, MechError> {
                    let s = Site {
                        body: tree.index_of_body[p.body],
                        node: p.node,
                        point: low.vec3(&p.position)?,
                    };
                    Ok(ev.site(k, &s).0)
                };
                let d = site(a)? - site(b)?;
                let unit = d.scale(S::one() / d.norm());
                let mut l = fresh();
                apply(&mut l, a, unit)?;
                apply(&mut l, b, -unit)?;
                out.push(l);
            }
        }
    }
    Ok(out)
}
