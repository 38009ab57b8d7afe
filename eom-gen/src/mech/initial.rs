//! The system at its initial state, on `f64`: the world pose of every body
//! (free joints at `q0`, locked ones at `q0`, prescribed ones at `t = 0`)
//! and how far each cut joint is from closing there.
//!
//! The validator uses these to warn about open loops and to recognise
//! planar systems (the Grübler–Kutzbach count), the constraint formulation
//! to find the plane normal, and `check` to print the gaps. The joint
//! transforms are [`JointModel::transform`], the same code that builds the
//! generated kinematics.
//!
//! A body's pose is `X_parent · F_parent · J(q) · F_child⁻¹`, with `F` the
//! joint frames and `J` the joint transform.

use super::joint::JointModel;
pub use super::spatial::Pose;
use crate::sym::{Mat3, Vec3};
use crate::system::{FrameInfo, JointType, Motion, System, values};
use nalgebra::{Matrix3, Vector3};

/// The joint model of `kind` on `f64`, with its axes (and screw pitch) at
/// the default parameters.
pub fn joint_model(kind: &JointType) -> JointModel<f64> {
    let v = |a: &crate::system::Axis| Vec3::new(a.unit.x, a.unit.y, a.unit.z);
    match kind {
        JointType::Revolute(a) => JointModel::Revolute(v(a)),
        JointType::Prismatic(a) => JointModel::Prismatic(v(a)),
        JointType::Cylindrical(a) => JointModel::Cylindrical(v(a)),
        JointType::Universal(a, b) => JointModel::Universal(v(a), v(b)),
        JointType::Spherical => JointModel::Spherical,
        JointType::Planar => JointModel::Planar,
        JointType::Free => JointModel::Free,
        JointType::Screw(a, pitch) => JointModel::Screw(v(a), pitch.value),
        JointType::Fixed => JointModel::Fixed,
    }
}

/// The joint transform `J(q)` of `kind` at the default parameters. `q` is
/// padded with zeros to the joint's `nq`, and a quaternion is normalised
/// first (initial values are only checked to be close to unit).
pub fn joint_transform(kind: &JointType, q: &[f64]) -> Pose<f64> {
    let model = joint_model(kind);
    let mut q: Vec<f64> = (0..model.nq())
        .map(|k| q.get(k).copied().unwrap_or(0.0))
        .collect();
    if let Some(at) = model.quaternion_at() {
        let quat = &mut q[at..at + 4];
        let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n > 0.0 {
            quat.iter_mut().for_each(|x| *x /= n);
        }
    }
    model.transform(&q)
}

/// A joint frame as a pose in its body, at the default parameters.
pub fn frame_pose(frame: &FrameInfo) -> Pose<f64> {
    let m = &frame.matrix;
    Pose {
        e: Mat3(std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))),
        r: Vec3::from(values(&frame.position)),
    }
}

/// A joint's frame on its parent at the initial state: at a node of a
/// flexible parent, relative to the node's undeformed place (the elastic
/// coordinates start at zero).
pub fn parent_frame_pose(sys: &System, joint: &crate::system::JointInfo) -> Pose<f64> {
    let fp = frame_pose(&joint.parent_frame);
    match (
        joint.parent_node,
        sys.bodies[joint.parent].flexible.as_deref(),
    ) {
        (Some(n), Some(flex)) => Pose {
            e: Mat3::identity(),
            r: Vec3(flex.node_place(n)),
        }
        .then(&fp),
        _ => fp,
    }
}

/// A cut joint's frame on its child at the initial state: at a node of a
/// flexible child, relative to the node's undeformed place.
pub fn child_frame_pose(sys: &System, joint: &crate::system::JointInfo) -> Pose<f64> {
    let fc = frame_pose(&joint.child_frame);
    match (
        joint.child_node,
        sys.bodies[joint.child].flexible.as_deref(),
    ) {
        (Some(n), Some(flex)) => Pose {
            e: Mat3::identity(),
            r: Vec3(flex.node_place(n)),
        }
        .then(&fc),
        _ => fc,
    }
}

/// World pose of every body at the initial state (locked joints at `q0`,
/// prescribed ones at `t = 0`), indexed by body; ground is the identity.
pub fn initial_poses(sys: &System) -> Vec<Pose<f64>> {
    let mut poses = vec![Pose::identity(); sys.bodies.len()];
    for &j in sys.graph.tree_joints() {
        let joint = &sys.joints[j];
        let q: Vec<f64> = match &joint.motion {
            Motion::Prescribed(p) => p.iter().map(|x| x.value).collect(),
            _ => joint.q0.iter().map(|x| x.value).collect(),
        };
        let fp = parent_frame_pose(sys, joint);
        let fc = frame_pose(&joint.child_frame);
        let jt = joint_transform(&joint.kind, &q);
        poses[joint.child] = poses[joint.parent].then(&fp).then(&jt).then(&fc.inverse());
    }
    poses
}

/// How far a cut joint is from closing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gap {
    /// Distance between the two joint frames' origins, in the directions
    /// the joint does not allow, m.
    pub position: f64,
    /// Angle between the constrained axes, rad.
    pub angle: f64,
}

/// Gaps of every cut joint at the given poses, in cut-joint order.
pub fn closure_gaps(sys: &System, poses: &[Pose<f64>]) -> Vec<Gap> {
    sys.graph
        .cut_joints()
        .iter()
        .map(|&j| {
            let joint = &sys.joints[j];
            let on_parent = poses[joint.parent].then(&parent_frame_pose(sys, joint));
            let on_child = poses[joint.child].then(&child_frame_pose(sys, joint));
            let (rp, rc) = (Matrix3::from(on_parent.e), Matrix3::from(on_child.e));
            let d = Vector3::from(on_child.r - on_parent.r);
            let angle_between = |a: &Vector3<f64>| {
                let (wa, wb) = (rp * a, rc * a);
                wa.cross(&wb).norm().atan2(wa.dot(&wb))
            };
            let along = |a: &Vector3<f64>| d - (rp * a) * (rp * a).dot(&d);
            match &joint.kind {
                JointType::Revolute(a) => Gap {
                    position: d.norm(),
                    angle: angle_between(&a.unit),
                },
                JointType::Prismatic(a) | JointType::Cylindrical(a) | JointType::Screw(a, _) => {
                    Gap {
                        position: along(&a.unit).norm(),
                        angle: angle_between(&a.unit),
                    }
                }
                JointType::Planar => Gap {
                    position: (rp * Vector3::z()).dot(&d).abs(),
                    angle: angle_between(&Vector3::z()),
                },
                JointType::Universal(..) | JointType::Spherical => Gap {
                    position: d.norm(),
                    angle: 0.0,
                },
                JointType::Fixed => {
                    let rel = rp.transpose() * rc;
                    Gap {
                        position: d.norm(),
                        angle: ((rel.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos(),
                    }
                }
                JointType::Free => Gap {
                    position: 0.0,
                    angle: 0.0,
                },
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::Span;
    use crate::expr::Ast;
    use crate::system::{Axis, Quantity};
    use std::f64::consts::FRAC_PI_2;

    fn axis(v: Vector3<f64>) -> Axis {
        let q = |x: f64| Quantity {
            expr: Ast::Num(x),
            value: x,
            span: Span::default(),
        };
        Axis {
            written: [q(v.x), q(v.y), q(v.z)],
            unit: v.normalize(),
        }
    }

    #[test]
    fn revolute_about_z_turns_x_into_y() {
        let pose = joint_transform(&JointType::Revolute(axis(Vector3::z())), &[FRAC_PI_2]);
        let got = pose.point(Vec3::new(1.0, 0.0, 0.0));
        let err = (got - Vec3::new(0.0, 1.0, 0.0)).norm();
        assert!(err < 1e-15, "got {got:?}, want (0, 1, 0)");
    }

    #[test]
    fn quaternions_are_normalised_and_short_coordinates_padded() {
        // (2, 0, 0, 2) is a quarter turn about z once normalised.
        let got = joint_transform(&JointType::Spherical, &[2.0, 0.0, 0.0, 2.0])
            .point(Vec3::new(1.0, 0.0, 0.0));
        let err = (got - Vec3::new(0.0, 1.0, 0.0)).norm();
        assert!(err < 1e-15, "got {got:?}, want (0, 1, 0)");
        let free = joint_transform(&JointType::Free, &[0.5]);
        assert_eq!(free.r.0, [0.5, 0.0, 0.0], "missing entries are zero");
    }
}
