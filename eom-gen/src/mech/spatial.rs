//! Spatial (6-D) algebra over any [`Scalar`], in Featherstone's notation
//! (*Rigid Body Dynamics Algorithms*, 2008, ch. 2), with vectors kept as
//! pairs of 3-vectors so that structural zeros stay visible.
//!
//! - A motion vector `(ω, v)`: angular velocity and the velocity of the
//!   point at the frame origin.
//! - A force vector `(n, f)`: moment about the frame origin and force.
//! - A [`Pose`] `(E, r)` of a child frame in its parent: `x_p = E x_c + r`.
//!   Motions go from parent to child coordinates (`X`, eq. 2.24), forces
//!   from child to parent (`Xᵀ`, eq. 2.25).
//! - A [`RigidInertia`] `(m, h, Ī)`: mass, first moment `h = m c` and
//!   rotational inertia about the frame origin (eq. 2.62).

use crate::sym::{Mat3, Scalar, Vec3};
use std::ops::{Add, Sub};

/// A spatial motion vector.
#[derive(Clone, Copy, Debug)]
pub struct Motion<S> {
    /// Angular part.
    pub w: Vec3<S>,
    /// Linear part (velocity of the point at the origin).
    pub v: Vec3<S>,
}

/// A spatial force vector.
#[derive(Clone, Copy, Debug)]
pub struct Force<S> {
    /// Moment about the origin.
    pub n: Vec3<S>,
    /// Force.
    pub f: Vec3<S>,
}

/// A rigid transform: `x_parent = e · x_child + r`.
#[derive(Clone, Copy, Debug)]
pub struct Pose<S> {
    /// Rotation (columns: child axes in parent coordinates).
    pub e: Mat3<S>,
    /// Child origin in parent coordinates.
    pub r: Vec3<S>,
}

/// Inertia of a rigid body (or a composite) about a frame origin.
#[derive(Clone, Copy, Debug)]
pub struct RigidInertia<S> {
    /// Mass.
    pub m: S,
    /// First moment of mass `m c`.
    pub h: Vec3<S>,
    /// Rotational inertia about the origin.
    pub i: Mat3<S>,
}

impl<S: Scalar> Motion<S> {
    /// Zero motion.
    pub fn zero() -> Self {
        Motion {
            w: Vec3::zero(),
            v: Vec3::zero(),
        }
    }

    /// `k · self`.
    pub fn scale(self, k: S) -> Self {
        Motion {
            w: self.w.scale(k),
            v: self.v.scale(k),
        }
    }

    /// Motion cross product `self ×ₘ m` (eq. 2.31).
    pub fn cross_motion(self, m: Self) -> Self {
        Motion {
            w: self.w.cross(m.w),
            v: self.w.cross(m.v) + self.v.cross(m.w),
        }
    }

    /// Force cross product `self ×* f` (eq. 2.32).
    pub fn cross_force(self, f: Force<S>) -> Force<S> {
        Force {
            n: self.w.cross(f.n) + self.v.cross(f.f),
            f: self.w.cross(f.f),
        }
    }

    /// Power `fᵀ m`.
    pub fn dot(self, f: Force<S>) -> S {
        self.w.dot(f.n) + self.v.dot(f.f)
    }
}

impl<S: Scalar> Force<S> {
    /// Zero force.
    pub fn zero() -> Self {
        Force {
            n: Vec3::zero(),
            f: Vec3::zero(),
        }
    }

    /// `k · self`.
    pub fn scale(self, k: S) -> Self {
        Force {
            n: self.n.scale(k),
            f: self.f.scale(k),
        }
    }
}

impl<S: Scalar> Pose<S> {
    /// The identity.
    pub fn identity() -> Self {
        Pose {
            e: Mat3::identity(),
            r: Vec3::zero(),
        }
    }

    /// `self ∘ inner`: the pose of `inner`'s child in `self`'s parent.
    pub fn then(&self, inner: &Pose<S>) -> Pose<S> {
        Pose {
            e: self.e * inner.e,
            r: self.r + self.e.mul_vec(inner.r),
        }
    }

    /// The inverse pose.
    pub fn inverse(&self) -> Pose<S> {
        let et = self.e.transpose();
        Pose {
            e: et,
            r: -et.mul_vec(self.r),
        }
    }

    /// Maps a point from child to parent coordinates.
    pub fn point(&self, x: Vec3<S>) -> Vec3<S> {
        self.r + self.e.mul_vec(x)
    }

    /// A parent-frame motion in child coordinates: `X m`.
    pub fn motion_to_child(&self, m: Motion<S>) -> Motion<S> {
        Motion {
            w: self.e.tr_mul_vec(m.w),
            v: self.e.tr_mul_vec(m.v + m.w.cross(self.r)),
        }
    }

    /// A child-frame force in parent coordinates: `Xᵀ f`.
    pub fn force_to_parent(&self, f: Force<S>) -> Force<S> {
        let ef = self.e.mul_vec(f.f);
        Force {
            n: self.e.mul_vec(f.n) + self.r.cross(ef),
            f: ef,
        }
    }

    /// A child-frame motion in parent coordinates: `X⁻¹ m`.
    pub fn motion_to_parent(&self, m: Motion<S>) -> Motion<S> {
        let w = self.e.mul_vec(m.w);
        Motion {
            w,
            v: self.e.mul_vec(m.v) + self.r.cross(w),
        }
    }
}

impl<S: Scalar> RigidInertia<S> {
    /// A body of mass `m`, centre of mass `c` and inertia `ic` about it.
    pub fn from_com(m: S, c: Vec3<S>, ic: Mat3<S>) -> Self {
        // Parallel axes: Ī = I_c − m [c×][c×] (eq. 2.63).
        let cx = c.skew();
        RigidInertia {
            m,
            h: c.scale(m),
            i: ic - (cx * cx).scale(m),
        }
    }

    /// `I m`: the momentum of a body moving with `m` (eq. 2.62).
    pub fn mul_motion(&self, m: Motion<S>) -> Force<S> {
        Force {
            n: self.i.mul_vec(m.w) + self.h.cross(m.v),
            f: m.v.scale(self.m) - self.h.cross(m.w),
        }
    }

    /// The same inertia expressed in the parent frame of `pose`
    /// (`Xᵀ I X`, eq. 2.66): rotate, then shift the origin by `r`.
    pub fn to_parent(&self, pose: &Pose<S>) -> Self {
        let e = pose.e;
        let h = e.mul_vec(self.h);
        let rot = congruence_sym(&e, &self.i);
        let (rx, hx) = (pose.r.skew(), h.skew());
        // Ī_p = E Ī Eᵀ − m [r×]² − [r×][h×] − [h×][r×], then h_p = E h + m r.
        let i = rot - (rx * rx).scale(self.m) - rx * hx - hx * rx;
        RigidInertia {
            m: self.m,
            h: h + pose.r.scale(self.m),
            i,
        }
    }
}

/// A general symmetric 6×6 matrix (articulated-body inertia), as blocks
/// `[[A, B], [Bᵀ, C]]` acting on motions `(ω, v)` to give forces `(n, f)`.
#[derive(Clone, Copy, Debug)]
pub struct Inertia6<S> {
    /// Angular–angular block.
    pub a: Mat3<S>,
    /// Angular–linear block.
    pub b: Mat3<S>,
    /// Linear–linear block.
    pub c: Mat3<S>,
}

impl<S: Scalar> Inertia6<S> {
    /// The spatial inertia of a rigid body.
    pub fn from_rigid(r: &RigidInertia<S>) -> Self {
        let hx = r.h.skew();
        Inertia6 {
            a: r.i,
            b: hx,
            c: Mat3::identity().scale(r.m),
        }
    }

    /// `I m`.
    pub fn mul_motion(&self, m: Motion<S>) -> Force<S> {
        Force {
            n: self.a.mul_vec(m.w) + self.b.mul_vec(m.v),
            f: self.b.tr_mul_vec(m.w) + self.c.mul_vec(m.v),
        }
    }

    /// `self − Σ_k u_k u_kᵀ · w_k`: the rank-one updates of the
    /// articulated-body algorithm (Featherstone eq. 7.41 with `U D⁻¹ Uᵀ`).
    pub fn sub_outer(&self, u: &Force<S>, v: &Force<S>, w: S) -> Self {
        let outer = |x: Vec3<S>, y: Vec3<S>| {
            Mat3([0, 1, 2].map(|i| [0, 1, 2].map(|j| x.0[i] * y.0[j] * w)))
        };
        Inertia6 {
            a: self.a - outer(u.n, v.n),
            b: self.b - outer(u.n, v.f),
            c: self.c - outer(u.f, v.f),
        }
    }

    /// The same inertia in the parent frame of `pose`: `Xᵀ I X`.
    pub fn to_parent(&self, pose: &Pose<S>) -> Self {
        // In rotated coordinates: A' = E A Eᵀ, B' = E B Eᵀ, C' = E C Eᵀ;
        // then the shift of origin by r (X = [[1, 0], [−r×, 1]] on motions
        // expressed at the parent origin): with R = [r×],
        // A'' = A' + R B'ᵀ − B' R − R C' R,  B'' = B' + R C',  C'' = C'.
        // A, C and A'' are symmetric: their upper triangles are computed
        // and mirrored (the lower ones are the same numbers, written as
        // different sums).
        let e = pose.e;
        let a = congruence_sym(&e, &self.a);
        let b = e * self.b * e.transpose();
        let c = congruence_sym(&e, &self.c);
        let rx = pose.r.skew();
        let rc = rx * c;
        // R B'ᵀ − B' R = M + Mᵀ with M = R B'ᵀ (R is skew).
        let m = rx * b.transpose();
        let rcr = rc * rx;
        Inertia6 {
            a: sym_from_upper(|i, j| a.0[i][j] + m.0[i][j] + m.0[j][i] - rcr.0[i][j]),
            b: b + rc,
            c,
        }
    }
}

/// The symmetric matrix whose upper triangle (`i ≤ j`) is `f(i, j)`.
fn sym_from_upper<S: Scalar>(f: impl Fn(usize, usize) -> S) -> Mat3<S> {
    let mut out = Mat3::zero();
    for i in 0..3 {
        for j in i..3 {
            let x = f(i, j);
            out.0[i][j] = x;
            out.0[j][i] = x;
        }
    }
    out
}

/// `E M Eᵀ` of a symmetric `M`: `(E M)` once, then the upper triangle of
/// its products with the rows of `E`, mirrored.
fn congruence_sym<S: Scalar>(e: &Mat3<S>, m: &Mat3<S>) -> Mat3<S> {
    let em = *e * *m;
    sym_from_upper(|i, j| em.row(i).dot(e.row(j)))
}

impl<S: Scalar> Add for Motion<S> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Motion {
            w: self.w + o.w,
            v: self.v + o.v,
        }
    }
}

impl<S: Scalar> Sub for Motion<S> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Motion {
            w: self.w - o.w,
            v: self.v - o.v,
        }
    }
}

impl<S: Scalar> Add for Force<S> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Force {
            n: self.n + o.n,
            f: self.f + o.f,
        }
    }
}

impl<S: Scalar> Sub for Force<S> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Force {
            n: self.n - o.n,
            f: self.f - o.f,
        }
    }
}

/// Inertias about the same origin add.
impl<S: Scalar> Add for RigidInertia<S> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        RigidInertia {
            m: self.m + o.m,
            h: self.h + o.h,
            i: self.i + o.i,
        }
    }
}

impl<S: Scalar> Add for Inertia6<S> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Inertia6 {
            a: self.a + o.a,
            b: self.b + o.b,
            c: self.c + o.c,
        }
    }
}

/// Is `f` structurally zero?
pub(crate) fn is_zero_force<S: Scalar>(f: &Force<S>) -> bool {
    f.n.0.iter().chain(&f.f.0).all(|x| x.is_zero())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3<f64> {
        Vec3::new(x, y, z)
    }

    fn pose() -> Pose<f64> {
        Pose {
            e: Mat3::from_axis_angle(v(1.0, 2.0, 2.0).scale(1.0 / 3.0), 0.7),
            r: v(0.3, -0.2, 0.5),
        }
    }

    fn close(a: Vec3<f64>, b: Vec3<f64>) -> bool {
        (a - b).norm() < 1e-12
    }

    #[test]
    fn power_is_invariant_under_change_of_frame() {
        // fᵀm is the same in both frames: (Xᵀ f)·m_p = f·(X m_p).
        let p = pose();
        let m = Motion {
            w: v(0.1, 0.4, -0.3),
            v: v(1.0, -2.0, 0.5),
        };
        let f = Force {
            n: v(0.3, 0.1, 0.2),
            f: v(-1.0, 0.5, 2.0),
        };
        let lhs = m.dot(p.force_to_parent(f));
        let rhs = p.motion_to_child(m).dot(f);
        assert!((lhs - rhs).abs() < 1e-12, "got {lhs}, want {rhs}");
        let back = p.motion_to_parent(p.motion_to_child(m));
        assert!(close(back.w, m.w) && close(back.v, m.v));
    }

    #[test]
    fn inertia_transform_matches_kinetic_energy() {
        // ½ mᵀ I m is a scalar: the same with the inertia moved to the parent.
        let p = pose();
        let body = RigidInertia::from_com(2.0, v(0.1, 0.2, -0.3), Mat3::diag(v(0.3, 0.4, 0.5)));
        let m_child = Motion {
            w: v(0.1, 0.4, -0.3),
            v: v(1.0, -2.0, 0.5),
        };
        let m_parent = p.motion_to_parent(m_child);
        let t_child = m_child.dot(body.mul_motion(m_child));
        let rigid_parent = body.to_parent(&p);
        let t_parent = m_parent.dot(rigid_parent.mul_motion(m_parent));
        assert!(
            (t_child - t_parent).abs() < 1e-12,
            "got {t_parent}, want {t_child}"
        );
        let six = Inertia6::from_rigid(&body).to_parent(&p);
        let t_six = m_parent.dot(six.mul_motion(m_parent));
        assert!(
            (t_child - t_six).abs() < 1e-12,
            "got {t_six}, want {t_child}"
        );
    }

    #[test]
    fn cross_products_are_duals() {
        // (v ×* f)·m = −f·(v ×ₘ m).
        let a = Motion {
            w: v(0.2, -0.1, 0.3),
            v: v(0.5, 0.1, -0.4),
        };
        let m = Motion {
            w: v(0.1, 0.4, -0.3),
            v: v(1.0, -2.0, 0.5),
        };
        let f = Force {
            n: v(0.3, 0.1, 0.2),
            f: v(-1.0, 0.5, 2.0),
        };
        let lhs = m.dot(a.cross_force(f));
        let rhs = -a.cross_motion(m).dot(f);
        assert!((lhs - rhs).abs() < 1e-12, "got {lhs}, want {rhs}");
    }
}
