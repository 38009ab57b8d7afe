//! Rotations and joint transforms on `f64`, used by validation: frame
//! matrices at the default parameters, and poses at the initial state to
//! check that loops close and to recognise planar systems.
//!
//! Conventions (also those of the formulation stage): a pose `(R, p)` maps
//! coordinates in a frame to its reference frame, `x_ref = p + R x`; a
//! child body's pose is `X_parent · F_parent · J(q) · F_child⁻¹`, with `F`
//! the joint frames and `J` the joint transform below.

use crate::system::JointType;
use nalgebra::{Matrix3, Quaternion, Rotation3, Unit, UnitQuaternion, Vector3};

/// A rigid transform `x_ref = p + R x`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Rotation.
    pub r: Matrix3<f64>,
    /// Translation.
    pub p: Vector3<f64>,
}

impl Pose {
    /// The identity.
    pub fn identity() -> Self {
        Pose {
            r: Matrix3::identity(),
            p: Vector3::zeros(),
        }
    }

    /// `self ∘ other`: first `other`, then `self`.
    pub fn then(&self, other: &Pose) -> Pose {
        Pose {
            r: self.r * other.r,
            p: self.p + self.r * other.p,
        }
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Pose {
        let rt = self.r.transpose();
        Pose {
            r: rt,
            p: -(rt * self.p),
        }
    }

    /// Maps a point.
    pub fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        self.p + self.r * x
    }
}

/// Rotation by `angle` about the unit vector `axis` (Rodrigues).
pub fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Unit::new_normalize(*axis), angle).into_inner()
}

/// `Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn rpy(roll: f64, pitch: f64, yaw: f64) -> Matrix3<f64> {
    Rotation3::from_euler_angles(roll, pitch, yaw).into_inner()
}

/// Rotation matrix of the unit quaternion `(w, x, y, z)` (normalised first).
pub fn quaternion(w: f64, x: f64, y: f64, z: f64) -> Matrix3<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z))
        .to_rotation_matrix()
        .into_inner()
}

/// The joint transform `J(q)` from the child joint frame to the parent
/// joint frame (see the module docs). `q` has the joint's `nq` entries.
pub fn joint_transform(kind: &JointType, q: &[f64]) -> Pose {
    let at = |k: usize| q.get(k).copied().unwrap_or(0.0);
    let mut pose = Pose::identity();
    match kind {
        JointType::Revolute(a) => pose.r = axis_angle(&a.unit, at(0)),
        JointType::Prismatic(a) => pose.p = a.unit * at(0),
        JointType::Cylindrical(a) => {
            pose.r = axis_angle(&a.unit, at(0));
            pose.p = a.unit * at(1);
        }
        JointType::Universal(a, b) => {
            pose.r = axis_angle(&a.unit, at(0)) * axis_angle(&b.unit, at(1));
        }
        JointType::Spherical => pose.r = quaternion(at(0), at(1), at(2), at(3)),
        JointType::Planar => {
            pose.r = axis_angle(&Vector3::z(), at(2));
            pose.p = Vector3::new(at(0), at(1), 0.0);
        }
        JointType::Free => {
            pose.p = Vector3::new(at(0), at(1), at(2));
            pose.r = quaternion(at(3), at(4), at(5), at(6));
        }
        JointType::Screw(a, pitch) => {
            pose.r = axis_angle(&a.unit, at(0));
            pose.p = a.unit * (pitch.value * at(0));
        }
        JointType::Fixed => {}
    }
    pose
}

/// Largest deviation of `RᵀR` from the identity, and the determinant.
pub fn orthonormality(r: &Matrix3<f64>) -> (f64, f64) {
    let e = r.transpose() * r - Matrix3::identity();
    (e.amax(), r.determinant())
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
        let got = pose.apply(&Vector3::x());
        assert!(
            (got - Vector3::y()).norm() < 1e-15,
            "got {got}, want (0, 1, 0)"
        );
    }

    #[test]
    fn rpy_is_yaw_after_pitch_after_roll() {
        let (r, p, y) = (0.3, -0.7, 1.1);
        let want = axis_angle(&Vector3::z(), y)
            * axis_angle(&Vector3::y(), p)
            * axis_angle(&Vector3::x(), r);
        assert!((rpy(r, p, y) - want).amax() < 1e-15);
    }

    #[test]
    fn quaternion_matches_axis_angle() {
        let (angle, a): (f64, _) = (0.8, Vector3::new(1.0, 2.0, 2.0) / 3.0);
        let (s, c) = (angle / 2.0).sin_cos();
        let got = quaternion(c, s * a.x, s * a.y, s * a.z);
        assert!((got - axis_angle(&a, angle)).amax() < 1e-15);
    }

    #[test]
    fn pose_inverse_and_composition() {
        let a = Pose {
            r: axis_angle(&Vector3::new(1.0, -1.0, 0.5), 0.4),
            p: Vector3::new(0.1, 0.2, 0.3),
        };
        let id = a.then(&a.inverse());
        assert!((id.r - Matrix3::identity()).amax() < 1e-15 && id.p.norm() < 1e-15);
        let (err, det) = orthonormality(&a.r);
        assert!(err < 1e-15 && (det - 1.0).abs() < 1e-15);
    }
}
