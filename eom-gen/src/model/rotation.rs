//! Rotation matrices on `f64`, used by validation: joint and marker frames
//! at the default parameters, and the orthonormality check of written
//! matrices. (Poses and joint transforms at the initial state are in
//! [`crate::mech::initial`].)

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};

/// Rotation by `angle` about the unit vector `axis` (Rodrigues).
pub fn axis_angle(axis: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Unit::new_normalize(*axis), angle).into_inner()
}

/// `Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn rpy(roll: f64, pitch: f64, yaw: f64) -> Matrix3<f64> {
    Rotation3::from_euler_angles(roll, pitch, yaw).into_inner()
}

/// Largest deviation of `RᵀR` from the identity, and the determinant.
pub fn orthonormality(r: &Matrix3<f64>) -> (f64, f64) {
    let e = r.transpose() * r - Matrix3::identity();
    (e.amax(), r.determinant())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_is_yaw_after_pitch_after_roll() {
        let (r, p, y) = (0.3, -0.7, 1.1);
        let want = axis_angle(&Vector3::z(), y)
            * axis_angle(&Vector3::y(), p)
            * axis_angle(&Vector3::x(), r);
        assert!((rpy(r, p, y) - want).amax() < 1e-15);
    }

    #[test]
    fn rotations_are_orthonormal() {
        let r = axis_angle(&Vector3::new(1.0, -1.0, 0.5), 0.4);
        let (err, det) = orthonormality(&r);
        assert!(err < 1e-15 && (det - 1.0).abs() < 1e-15);
    }
}
