//! Closure conditions of cut joints (Wittenburg ch. 5.6, Shabana ch. 3):
//! `Φ(q, t) = 0`, written once over any [`Scalar`].
//!
//! For a cut joint between bodies P and C with joint frames `F_P`, `F_C`,
//! let `d` be the vector from the parent joint frame's origin to the child
//! joint frame's origin and `M = R_Pᵀ R_C` the relative rotation, both in
//! parent-joint-frame axes. Each joint kind constrains what it does not
//! allow (`b₁, b₂` complete the joint axis `a` to an orthonormal triad):
//!
//! | kind | equations |
//! |---|---|
//! | revolute | `d` (3), `b₁·Ma`, `b₂·Ma` |
//! | spherical | `d` (3) |
//! | universal | `d` (3), `a₁·Ma₂` |
//! | prismatic | `b₁·d`, `b₂·d`, `e₁·Me₂`, `e₂·Me₃`, `e₃·Me₁` |
//! | cylindrical | `b₁·d`, `b₂·d`, `b₁·Ma`, `b₂·Ma` |
//! | planar | `z·d`, `x·Mz`, `y·Mz` |
//! | fixed | `d` (3), `e₁·Me₂`, `e₂·Me₃`, `e₃·Me₁` |
//!
//! In a planar system (all motion in planes normal to `n`) only the
//! independent in-plane equations are kept: a revolute cut joint about `n`
//! gives the two in-plane components of `d`; a prismatic one the in-plane
//! offset across its axis and the relative angle about `n`. Redundant
//! equations of spatial loops (Bricard's) are kept; the solvers handle the
//! rank deficiency.

use super::env::Env;
use super::error::MechError;
use super::kinematics::Kinematics;
use super::lower::{Lowering, snap};
use super::spatial::Pose;
use super::tree::TreeModel;
use crate::sym::{Scalar, Vec3};
use crate::system::{JointType, System};
use nalgebra::{Matrix3, Vector3};

/// A cut joint as the constraint equations see it.
#[derive(Clone, Debug)]
pub struct CutJoint<S> {
    /// Joint name.
    pub name: String,
    /// Tree index of the parent body (`None`: ground).
    pub parent: Option<usize>,
    /// On a flexible parent: the beam node the joint is attached to
    /// (`frame_parent` is relative to the node's deformed frame).
    pub parent_node: Option<usize>,
    /// Tree index of the child body (`None`: ground).
    pub child: Option<usize>,
    /// On a flexible child: the node the joint is attached to
    /// (`frame_child` is relative to the node's deformed frame).
    pub child_node: Option<usize>,
    /// Joint frame on the parent.
    pub frame_parent: Pose<S>,
    /// Joint frame on the child.
    pub frame_child: Pose<S>,
    /// Which equations, as unit vectors in joint-frame axes.
    pub equations: Vec<Equation>,
}

/// One scalar closure condition.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Equation {
    /// `v · d`: the offset of the child frame's origin along `v`.
    Offset([f64; 3]),
    /// `v · M w`: orientation coupling of directions `v` (parent) and `w` (child).
    Align([f64; 3], [f64; 3]),
}

fn unit(v: Vector3<f64>) -> [f64; 3] {
    let v = v.normalize();
    [snap(v.x), snap(v.y), snap(v.z)]
}

/// Two unit vectors completing `a` to a right-handed orthonormal triad.
fn complete(a: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let a = a.normalize();
    let trial = if a.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let b1 = (trial - a * a.dot(&trial)).normalize();
    (b1, a.cross(&b1))
}

/// The equations of a cut joint of `kind` (`planar_normal`: the system's
/// plane normal in this joint's frame, if the system is planar).
pub fn equations(kind: &JointType, planar_normal: Option<Vector3<f64>>) -> Vec<Equation> {
    let (ex, ey, ez) = (Vector3::x(), Vector3::y(), Vector3::z());
    let offsets = |vs: &[Vector3<f64>]| {
        vs.iter()
            .map(|v| Equation::Offset(unit(*v)))
            .collect::<Vec<_>>()
    };
    let rotation3 = || {
        vec![
            Equation::Align(unit(ex), unit(ey)),
            Equation::Align(unit(ey), unit(ez)),
            Equation::Align(unit(ez), unit(ex)),
        ]
    };
    match (kind, planar_normal) {
        (JointType::Revolute(a), Some(_)) => {
            let (b1, b2) = complete(a.unit);
            offsets(&[b1, b2])
        }
        (JointType::Revolute(a), None) => {
            let (b1, b2) = complete(a.unit);
            let mut e = offsets(&[ex, ey, ez]);
            e.push(Equation::Align(unit(b1), unit(a.unit)));
            e.push(Equation::Align(unit(b2), unit(a.unit)));
            e
        }
        (JointType::Prismatic(a), Some(n)) => {
            let across = n.cross(&a.unit);
            vec![
                Equation::Offset(unit(across)),
                Equation::Align(unit(across), unit(a.unit)),
            ]
        }
        (JointType::Prismatic(a), None) => {
            let (b1, b2) = complete(a.unit);
            let mut e = offsets(&[b1, b2]);
            e.extend(rotation3());
            e
        }
        (JointType::Cylindrical(a), _) | (JointType::Screw(a, _), _) => {
            let (b1, b2) = complete(a.unit);
            let mut e = offsets(&[b1, b2]);
            e.push(Equation::Align(unit(b1), unit(a.unit)));
            e.push(Equation::Align(unit(b2), unit(a.unit)));
            e
        }
        (JointType::Spherical, _) => offsets(&[ex, ey, ez]),
        (JointType::Universal(a1, a2), _) => {
            let mut e = offsets(&[ex, ey, ez]);
            e.push(Equation::Align(unit(a1.unit), unit(a2.unit)));
            e
        }
        (JointType::Planar, Some(_)) => Vec::new(),
        (JointType::Planar, None) => vec![
            Equation::Offset(unit(ez)),
            Equation::Align(unit(ex), unit(ez)),
            Equation::Align(unit(ey), unit(ez)),
        ],
        (JointType::Fixed, Some(n)) => {
            let (b1, b2) = complete(n);
            vec![
                Equation::Offset(unit(b1)),
                Equation::Offset(unit(b2)),
                Equation::Align(unit(b1), unit(b2)),
            ]
        }
        (JointType::Fixed, None) => {
            let mut e = offsets(&[ex, ey, ez]);
            e.extend(rotation3());
            e
        }
        (JointType::Free, _) => Vec::new(),
    }
}

/// The cut joints of `sys` over the tree `tree`.
pub fn cut_joints<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
) -> Result<Vec<CutJoint<S>>, MechError> {
    let low = Lowering::new(env);
    let poses = super::initial::initial_poses(sys);
    let normal = planar_normal(sys);
    sys.graph
        .cut_joints()
        .iter()
        .map(|&j| {
            let joint = &sys.joints[j];
            // The plane normal in this joint's parent frame.
            let n = normal.map(|n| {
                (Matrix3::from(poses[joint.parent].e) * joint.parent_frame.matrix).transpose() * n
            });
            Ok(CutJoint {
                name: joint.name.clone(),
                parent: tree.index_of_body[joint.parent],
                parent_node: joint.parent_node,
                child: tree.index_of_body[joint.child],
                child_node: joint.child_node,
                frame_parent: low.frame(&joint.parent_frame)?,
                frame_child: low.frame(&joint.child_frame)?,
                equations: equations(&joint.kind, n),
            })
        })
        .collect()
}

/// The common plane normal (world axes) of a planar system.
fn planar_normal(sys: &System) -> Option<Vector3<f64>> {
    if !sys.grubler.planar {
        return None;
    }
    let poses = super::initial::initial_poses(sys);
    sys.joints.iter().find_map(|j| match &j.kind {
        JointType::Revolute(a) => {
            Some(Matrix3::from(poses[j.parent].e) * j.parent_frame.matrix * a.unit)
        }
        JointType::Planar => {
            Some(Matrix3::from(poses[j.parent].e) * j.parent_frame.matrix * Vector3::z())
        }
        _ => None,
    })
}

/// World pose of the frame a cut joint's parent side is fixed to: the
/// parent body's, or that of its node.
fn parent_base<S: Scalar>(tree: &TreeModel<S>, k: &Kinematics<S>, c: &CutJoint<S>) -> Pose<S> {
    let Some(i) = c.parent else {
        return Pose::identity();
    };
    c.parent_node
        .and_then(|n| tree.bodies[i].flex.as_ref()?.node_slot(n))
        .map_or(k.world[i], |slot| k.world[i].then(&k.nodes[i][slot].pose))
}

/// World pose of the frame a cut joint's child side is fixed to: the child
/// body's, or that of its node.
fn child_base<S: Scalar>(tree: &TreeModel<S>, k: &Kinematics<S>, c: &CutJoint<S>) -> Pose<S> {
    let Some(i) = c.child else {
        return Pose::identity();
    };
    c.child_node
        .and_then(|n| tree.bodies[i].flex.as_ref()?.node_slot(n))
        .map_or(k.world[i], |slot| k.world[i].then(&k.nodes[i][slot].pose))
}

/// `Φ` of every cut joint, in order, at the kinematics `k`.
pub fn phi<S: Scalar>(tree: &TreeModel<S>, k: &Kinematics<S>, cuts: &[CutJoint<S>]) -> Vec<S> {
    let v = |a: [f64; 3]| Vec3::from_f64(a);
    let mut out = Vec::new();
    for c in cuts {
        let p = parent_base(tree, k, c).then(&c.frame_parent);
        let ch = child_base(tree, k, c).then(&c.frame_child);
        let d = p.e.tr_mul_vec(ch.r - p.r);
        let m = p.e.transpose() * ch.e;
        for e in &c.equations {
            out.push(match *e {
                Equation::Offset(a) => v(a).dot(d),
                Equation::Align(a, b) => v(a).dot(m.mul_vec(v(b))),
            });
        }
    }
    out
}

/// The force and torque a cut joint's multipliers `λ` (its rows, in
/// order) apply to the joint's child body at the child joint frame's
/// origin, in parent-joint-frame axes; the parent gets the opposite.
///
/// An offset row `a · d` contributes the force `λ a`; an orientation row
/// `v · M w` (relative rotation `M`) the torque `λ (M w) × v`: both are the
/// rows of `Jᵀ` read as a spatial force on the child.
pub fn cut_reaction<S: Scalar>(
    tree: &TreeModel<S>,
    k: &Kinematics<S>,
    cut: &CutJoint<S>,
    lambda: &[S],
) -> (Vec3<S>, Vec3<S>) {
    let p = parent_base(tree, k, cut).then(&cut.frame_parent);
    let ch = child_base(tree, k, cut).then(&cut.frame_child);
    let m = p.e.transpose() * ch.e;
    let (mut force, mut torque) = (Vec3::zero(), Vec3::zero());
    for (e, &l) in cut.equations.iter().zip(lambda) {
        match *e {
            Equation::Offset(a) => force = force + Vec3::from_f64(a).scale(l),
            Equation::Align(v, w) => {
                let mw = m.mul_vec(Vec3::from_f64(w));
                torque = torque + mw.cross(Vec3::from_f64(v)).scale(l);
            }
        }
    }
    (force, torque)
}

/// The constraint forces `Jᵀλ` as spatial forces on the tree's bodies
/// (body axes, at the body origin), for joint reactions in closed loops:
/// each cut joint's force and torque ([`cut_reaction`]) on its child and
/// their opposite on its parent, and each rolling disk's contact force
/// `(λ_slip_x, λ_slip_y, λ_contact)` (world axes) at its lowest point.
/// `lambda` is in the order of [`Formulation::constraint_names`](super::Formulation):
/// cut-joint rows, the model's holonomic rows, then its nonholonomic rows.
#[allow(clippy::too_many_arguments)]
pub fn constraint_body_forces<S: Scalar>(
    constraints: &[crate::system::Constraint],
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    k: &Kinematics<S>,
    cuts: &[CutJoint<S>],
    lambda: &[S],
) -> Result<Vec<super::spatial::Force<S>>, MechError> {
    use super::spatial::Force;
    use crate::system::ConstraintKind;
    let mut out = vec![Force::zero(); tree.loads()];
    let at = |i: usize| lambda.get(i).copied().unwrap_or(S::zero());
    // A world-axes force `fw` and torque `nw` at world point `x` on body
    // `b` (or on its node `node`: a node load, see `TreeModel::loads`).
    let mut apply =
        |b: Option<usize>, node: Option<usize>, x: Vec3<S>, fw: Vec3<S>, nw: Vec3<S>| {
            if let Some(b) = b {
                let at_node = node.and_then(|n| {
                    let slot = tree.bodies[b].flex.as_ref()?.node_slot(n)?;
                    Some((
                        tree.bodies[b].node_loads + slot,
                        k.world[b].then(&k.nodes[b][slot].pose),
                    ))
                });
                let (i, pose) = at_node.unwrap_or((b, k.world[b]));
                let pose = &pose;
                let (f, n) = (pose.e.tr_mul_vec(fw), pose.e.tr_mul_vec(nw));
                let r = pose.e.tr_mul_vec(x - pose.r);
                out[i] = out[i]
                    + Force {
                        n: r.cross(f) + n,
                        f,
                    };
            }
        };
    let mut row = 0;
    for c in cuts {
        let n = c.equations.len();
        let l: Vec<S> = (row..row + n).map(at).collect();
        row += n;
        let (f, m) = cut_reaction(tree, k, c, &l);
        let p = parent_base(tree, k, c).then(&c.frame_parent);
        let ch = child_base(tree, k, c).then(&c.frame_child);
        let (fw, mw) = (p.e.mul_vec(f), p.e.mul_vec(m));
        apply(c.child, c.child_node, ch.r, fw, mw);
        apply(c.parent, c.parent_node, ch.r, -fw, -mw);
    }
    let n_holonomic = row + constraints.iter().map(|c| c.equations().0).sum::<usize>();
    let mut nonholonomic = n_holonomic;
    let low = Lowering::new(env);
    for c in constraints {
        match &c.kind {
            ConstraintKind::Holonomic(_) => row += 1,
            ConstraintKind::RollingDisk {
                body,
                radius,
                axis,
                center,
            } => {
                let contact = at(row);
                let (sx, sy) = (at(nonholonomic), at(nonholonomic + 1));
                row += 1;
                nonholonomic += 2;
                let Some(i) = tree.index_of_body.get(*body).copied().flatten() else {
                    continue;
                };
                let (to_contact, _) = disk_contact(k, i, axis, low.quantity(radius)?);
                let point = k.world[i].point(low.vec3(center)?) + to_contact;
                apply(
                    Some(i),
                    None,
                    point,
                    Vec3::new(sx, sy, contact),
                    Vec3::zero(),
                );
            }
        }
    }
    Ok(out)
}

/// From a disk's centre to its lowest point (world axes), `−R ê`, and
/// `√(1 − n_z²)` (see [`user_constraints`]); the disk is tree body `i`.
fn disk_contact<S: Scalar>(
    k: &Kinematics<S>,
    i: usize,
    axis: &crate::system::Axis,
    r: S,
) -> (Vec3<S>, S) {
    let n = k.world[i].e.mul_vec(Vec3::from_f64(unit(axis.unit)));
    let nz = n.0[2];
    let s = (S::one() - nz * nz).sqrt();
    let down = Vec3::new(-nz * n.0[0], -nz * n.0[1], S::one() - nz * n.0[2]);
    (down.scale(-r / s), s)
}

/// The model's own constraints (not joints) at the kinematics `k`:
/// holonomic conditions `Φ(q, t)` and nonholonomic speed conditions
/// `A(q) u + b(q, t)`, each with its name.
///
/// A disk of radius `R` with unit axis `n` (world axes) and centre `c`
/// rolls on the plane `z = 0`: its lowest point is `p = c − R ê` with
/// `ê = (e_z − n_z n) / √(1 − n_z²)`, so the contact condition is
/// `c_z − R √(1 − n_z²) = 0`, and the material point at `p` is at rest in
/// the plane: the x and y components of `v_c + ω × (p − c)` vanish.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn user_constraints<S: Scalar>(
    constraints: &[crate::system::Constraint],
    coordinate_names: &[String],
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &super::kinematics::Evaluator<'_, S>,
    k: &Kinematics<S>,
    q: &[S],
    t: S,
) -> Result<(Vec<(String, S)>, Vec<(String, S)>), MechError> {
    use crate::system::ConstraintKind;
    let low = Lowering::new(env);
    let lookup = |n: &str| -> Option<S> {
        if n == "t" {
            return Some(t);
        }
        coordinate_names
            .iter()
            .position(|c| c == n)
            .and_then(|i| q.get(i).copied())
    };
    let (mut holonomic, mut nonholonomic) = (Vec::new(), Vec::new());
    for c in constraints {
        match &c.kind {
            ConstraintKind::Holonomic(expr) => {
                holonomic.push((c.name.clone(), low.expr(&expr.expr, expr.span, &lookup)?));
            }
            ConstraintKind::RollingDisk {
                body,
                radius,
                axis,
                center,
            } => {
                let Some(i) = tree.index_of_body.get(*body).copied().flatten() else {
                    continue;
                };
                let centre = low.vec3(center)?;
                let (to_contact, s) = disk_contact(k, i, axis, low.quantity(radius)?);
                let (c_pos, c_vel) = ev.point(k, Some(i), centre);
                let omega = k.world[i].e.mul_vec(k.v[i].w);
                let slip = c_vel + omega.cross(to_contact);
                let r = low.quantity(radius)?;
                holonomic.push((format!("{}.contact", c.name), c_pos.0[2] - r * s));
                nonholonomic.push((format!("{}.slip_x", c.name), slip.0[0]));
                nonholonomic.push((format!("{}.slip_y", c.name), slip.0[1]));
            }
        }
    }
    Ok((holonomic, nonholonomic))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn completing_triads_are_orthonormal_and_right_handed() {
        for a in [
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            Vector3::new(1.0, -2.0, 0.5),
        ] {
            let (b1, b2) = complete(a);
            let a = a.normalize();
            assert!(
                a.dot(&b1).abs() < 1e-15 && a.dot(&b2).abs() < 1e-15 && b1.dot(&b2).abs() < 1e-15
            );
            assert!((a.cross(&b1) - b2).norm() < 1e-15);
        }
    }
}
