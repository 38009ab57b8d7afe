//! Joint models: the transform `J(q)` from the child joint frame `C` to the
//! parent joint frame `P`, the motion subspace `S(q)` (relative twist of `C`
//! in `C` coordinates per unit speed), its apparent derivative `S̊ u`
//! (Featherstone's `c_J`, §4.4), and the kinematic map `q̇ = N(q) u`.
//!
//! Speeds are the coordinate rates except for quaternion joints: spherical
//! joints use the angular velocity in child axes, free joints the velocity
//! of the child frame origin and the angular velocity, both in child axes
//! (MODELS.md). Axes are unit vectors in joint-frame coordinates.

use super::spatial::{Motion, Pose};
use crate::sym::{Axis, Mat3, Scalar, Vec3};

/// A joint kind with its geometry.
#[derive(Clone, Copy, Debug)]
pub enum JointModel<S> {
    /// Rotation about `axis`.
    Revolute(Vec3<S>),
    /// Translation along `axis`.
    Prismatic(Vec3<S>),
    /// Rotation about and translation along `axis`: (angle, displacement).
    Cylindrical(Vec3<S>),
    /// Rotation about the first axis, then about the second as carried.
    Universal(Vec3<S>, Vec3<S>),
    /// Unit quaternion, angular velocity in child axes.
    Spherical,
    /// (x, y, angle about z); speeds are the coordinate rates.
    Planar,
    /// Translation (parent axes) and quaternion; speeds in child axes.
    Free,
    /// Rotation about the axis with `pitch · angle` along it.
    Screw(Vec3<S>, S),
    /// No motion.
    Fixed,
}

fn zero_motion<S: Scalar>() -> Motion<S> {
    Motion::zero()
}

/// `q ⊗ (0, ω) / 2`: the rate of a unit quaternion `(w, x, y, z)` turning
/// with angular velocity `ω` in body axes.
pub fn quaternion_rate<S: Scalar>(q: [S; 4], w: Vec3<S>) -> [S; 4] {
    let half = S::from_ratio(1, 2);
    let v = Vec3::new(q[1], q[2], q[3]);
    let vec = w.scale(q[0]) + v.cross(w);
    [
        -(v.dot(w)) * half,
        vec.0[0] * half,
        vec.0[1] * half,
        vec.0[2] * half,
    ]
}

impl<S: Scalar> JointModel<S> {
    /// Number of position coordinates.
    pub fn nq(&self) -> usize {
        match self {
            JointModel::Revolute(_) | JointModel::Prismatic(_) | JointModel::Screw(..) => 1,
            JointModel::Cylindrical(_) | JointModel::Universal(..) => 2,
            JointModel::Planar => 3,
            JointModel::Spherical => 4,
            JointModel::Free => 7,
            JointModel::Fixed => 0,
        }
    }

    /// Number of speeds.
    pub fn nu(&self) -> usize {
        match self {
            JointModel::Spherical => 3,
            JointModel::Free => 6,
            _ => self.nq(),
        }
    }

    /// `J(q)`: pose of the child joint frame in the parent joint frame.
    pub fn transform(&self, q: &[S]) -> Pose<S> {
        let mut p = Pose::identity();
        match *self {
            JointModel::Revolute(a) => p.e = Mat3::from_axis_angle(a, q[0]),
            JointModel::Prismatic(a) => p.r = a.scale(q[0]),
            JointModel::Cylindrical(a) => {
                p.e = Mat3::from_axis_angle(a, q[0]);
                p.r = a.scale(q[1]);
            }
            JointModel::Universal(a, b) => {
                p.e = Mat3::from_axis_angle(a, q[0]) * Mat3::from_axis_angle(b, q[1]);
            }
            JointModel::Spherical => p.e = Mat3::from_quaternion([q[0], q[1], q[2], q[3]]),
            JointModel::Planar => {
                p.e = Mat3::rot(Axis::Z, q[2]);
                p.r = Vec3::new(q[0], q[1], S::zero());
            }
            JointModel::Free => {
                p.r = Vec3::new(q[0], q[1], q[2]);
                p.e = Mat3::from_quaternion([q[3], q[4], q[5], q[6]]);
            }
            JointModel::Screw(a, h) => {
                p.e = Mat3::from_axis_angle(a, q[0]);
                p.r = a.scale(h * q[0]);
            }
            JointModel::Fixed => {}
        }
        p
    }

    /// Motion subspace in child-joint-frame coordinates: one relative twist
    /// per unit speed.
    pub fn subspace(&self, q: &[S]) -> Vec<Motion<S>> {
        let ang = |w: Vec3<S>| Motion { w, v: Vec3::zero() };
        let lin = |v: Vec3<S>| Motion { w: Vec3::zero(), v };
        match *self {
            JointModel::Revolute(a) => vec![ang(a)],
            JointModel::Prismatic(a) => vec![lin(a)],
            JointModel::Cylindrical(a) => vec![ang(a), lin(a)],
            JointModel::Universal(a, b) => {
                // ω_C = R(b, q2)ᵀ a q̇1 + b q̇2.
                let r2 = Mat3::from_axis_angle(b, q[1]);
                vec![ang(r2.tr_mul_vec(a)), ang(b)]
            }
            JointModel::Spherical => [Axis::X, Axis::Y, Axis::Z]
                .map(|k| ang(Vec3::unit(k)))
                .to_vec(),
            JointModel::Planar => {
                // v_C = Rz(φ)ᵀ (ẋ, ẏ, 0), ω_C = φ̇ e_z.
                let r = Mat3::rot(Axis::Z, q[2]);
                vec![
                    lin(r.tr_mul_vec(Vec3::unit(Axis::X))),
                    lin(r.tr_mul_vec(Vec3::unit(Axis::Y))),
                    ang(Vec3::unit(Axis::Z)),
                ]
            }
            JointModel::Free => {
                let mut s: Vec<Motion<S>> = [Axis::X, Axis::Y, Axis::Z]
                    .map(|k| lin(Vec3::unit(k)))
                    .to_vec();
                s.extend([Axis::X, Axis::Y, Axis::Z].map(|k| ang(Vec3::unit(k))));
                s
            }
            JointModel::Screw(a, h) => vec![Motion {
                w: a,
                v: a.scale(h),
            }],
            JointModel::Fixed => Vec::new(),
        }
    }

    /// `S̊ u`: the apparent derivative of the subspace in child-joint-frame
    /// coordinates times the speeds (zero where `S` is constant there).
    pub fn bias(&self, q: &[S], u: &[S]) -> Motion<S> {
        match *self {
            JointModel::Universal(a, b) => {
                // d/dt (R2ᵀ a) = −q̇2 b × (R2ᵀ a).
                let r2a = Mat3::from_axis_angle(b, q[1]).tr_mul_vec(a);
                Motion {
                    w: b.cross(r2a).scale(-(u[0] * u[1])),
                    v: Vec3::zero(),
                }
            }
            JointModel::Planar => {
                // d/dt (Rz(φ)ᵀ w) = −φ̇ e_z × (Rz(φ)ᵀ w).
                let r = Mat3::rot(Axis::Z, q[2]);
                let v = r.tr_mul_vec(Vec3::new(u[0], u[1], S::zero()));
                Motion {
                    w: Vec3::zero(),
                    v: Vec3::unit(Axis::Z).cross(v).scale(-u[2]),
                }
            }
            _ => zero_motion(),
        }
    }

    /// `q̇ = N(q) u`.
    pub fn qdot(&self, q: &[S], u: &[S]) -> Vec<S> {
        match *self {
            JointModel::Spherical => {
                quaternion_rate([q[0], q[1], q[2], q[3]], Vec3::new(u[0], u[1], u[2])).to_vec()
            }
            JointModel::Free => {
                let quat = [q[3], q[4], q[5], q[6]];
                let pdot = Mat3::from_quaternion(quat).mul_vec(Vec3::new(u[0], u[1], u[2]));
                let mut out = pdot.0.to_vec();
                out.extend(quaternion_rate(quat, Vec3::new(u[3], u[4], u[5])));
                out
            }
            _ => u.to_vec(),
        }
    }

    /// Index of the quaternion's first entry within the joint's coordinates.
    pub fn quaternion_at(&self) -> Option<usize> {
        match self {
            JointModel::Spherical => Some(0),
            JointModel::Free => Some(3),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ops::Add;

    fn unit(x: f64, y: f64, z: f64) -> Vec3<f64> {
        let v = Vec3::new(x, y, z);
        v.scale(1.0 / v.norm())
    }

    fn joints() -> Vec<(JointModel<f64>, Vec<f64>, Vec<f64>)> {
        let a = unit(1.0, 2.0, -0.5);
        let b = unit(-0.3, 0.4, 1.0);
        let quat = {
            let n = (0.9f64 * 0.9 + 0.1 + 0.04 + 0.09).sqrt();
            vec![0.9 / n, 0.1f64.sqrt() / n, -0.2 / n, 0.3 / n]
        };
        let mut free_q = vec![0.3, -0.2, 0.5];
        free_q.extend(&quat);
        vec![
            (JointModel::Revolute(a), vec![0.7], vec![1.3]),
            (JointModel::Prismatic(a), vec![0.4], vec![-0.8]),
            (JointModel::Cylindrical(a), vec![0.7, 0.2], vec![1.1, -0.4]),
            (JointModel::Universal(a, b), vec![0.6, -0.9], vec![0.8, 1.7]),
            (JointModel::Spherical, quat.clone(), vec![0.3, -1.2, 0.7]),
            (
                JointModel::Planar,
                vec![0.2, -0.1, 0.8],
                vec![0.5, -0.3, 1.4],
            ),
            (
                JointModel::Free,
                free_q,
                vec![0.4, 0.1, -0.6, 0.3, -1.2, 0.7],
            ),
            (JointModel::Screw(a, 0.05), vec![0.7], vec![1.3]),
        ]
    }

    /// Relative twist of C in C coordinates by differentiating J(q(t)):
    /// ω× = Rᵀ Ṙ, v = Rᵀ ṗ, with q(t + h) from q̇ = N(q) u.
    fn twist_by_differences(j: &JointModel<f64>, q: &[f64], u: &[f64], h: f64) -> Motion<f64> {
        let qd = j.qdot(q, u);
        let at = |s: f64| -> Pose<f64> {
            let qs: Vec<f64> = q.iter().zip(&qd).map(|(q, d)| q + s * d).collect();
            j.transform(&qs)
        };
        let (p1, p0, pm) = (at(h), at(0.0), at(-h));
        let rdot = (p1.e - pm.e).scale(1.0 / (2.0 * h));
        let wx = p0.e.transpose() * rdot;
        let w = Vec3::new(wx.0[2][1], wx.0[0][2], wx.0[1][0]);
        let v = p0.e.tr_mul_vec((p1.r - pm.r).scale(1.0 / (2.0 * h)));
        Motion { w, v }
    }

    #[test]
    fn subspace_times_speeds_is_the_derivative_of_the_transform() {
        for (j, q, u) in joints() {
            let s = j.subspace(&q);
            assert_eq!(s.len(), j.nu());
            let twist = s
                .iter()
                .zip(&u)
                .fold(Motion::zero(), |acc, (col, &uk)| acc.add(col.scale(uk)));
            let want = twist_by_differences(&j, &q, &u, 1e-6);
            let err = (twist.w - want.w).norm() + (twist.v - want.v).norm();
            assert!(
                err < 1e-8,
                "{j:?}: S u = {twist:?}, finite differences give {want:?}"
            );
        }
    }

    #[test]
    fn bias_is_the_apparent_derivative_of_the_subspace() {
        // S̊ u = Σ_k (d/dt S_k) u_k with q moving along q̇ = N(q) u.
        for (j, q, u) in joints() {
            let h = 1e-6;
            let qd = j.qdot(&q, &u);
            let shifted =
                |s: f64| -> Vec<f64> { q.iter().zip(&qd).map(|(q, d)| q + s * d).collect() };
            let (sp, sm) = (j.subspace(&shifted(h)), j.subspace(&shifted(-h)));
            let mut want = Motion::zero();
            for k in 0..j.nu() {
                let d = sp[k].add(sm[k].scale(-1.0)).scale(u[k] / (2.0 * h));
                want = want.add(d);
            }
            let got = j.bias(&q, &u);
            let err = (got.w - want.w).norm() + (got.v - want.v).norm();
            assert!(err < 1e-7, "{j:?}: got {got:?}, want {want:?}");
        }
    }
}
