//! 3-vectors and 3×3 matrices over any [`Scalar`], with cross products, skew
//! matrices and rotation matrices.
//!
//! Over [`Expr`](super::Expr) every entry is built by the smart
//! constructors and constants stay free of the arena, so exact structural
//! zeros and ones survive: [`Mat3::rot`] about a coordinate axis has exactly
//! four entries that are not 0 or 1, and so does [`Mat3::from_axis_angle`]
//! with a coordinate unit axis (Rodrigues' formula collapses to the same
//! matrix).
//!
//! Convention (MODELS.md): a rotation matrix `R` maps child-frame
//! components to parent-frame components, `v_parent = R · v_child`;
//! quaternions are `(w, x, y, z)`.

use super::scalar::Scalar;
use std::ops::{Add, Index, Mul, Neg, Sub};

/// A column 3-vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3<S>(pub [S; 3]);

/// A 3×3 matrix, row-major: `m.0[row][col]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mat3<S>(pub [[S; 3]; 3]);

/// A coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// x
    X,
    /// y
    Y,
    /// z
    Z,
}

impl Axis {
    /// 0, 1 or 2.
    pub fn index(self) -> usize {
        self as usize
    }
}

impl<S: Scalar> Vec3<S> {
    /// `(x, y, z)`.
    pub fn new(x: S, y: S, z: S) -> Self {
        Vec3([x, y, z])
    }
    /// The zero vector.
    pub fn zero() -> Self {
        Vec3([S::zero(); 3])
    }
    /// The unit vector along `axis`.
    pub fn unit(axis: Axis) -> Self {
        let mut v = Self::zero();
        v.0[axis.index()] = S::one();
        v
    }
    /// From `f64` components.
    pub fn from_f64(v: [f64; 3]) -> Self {
        Vec3(v.map(S::from_f64))
    }
    /// Apply `f` to each component.
    pub fn map<T>(self, f: impl FnMut(S) -> T) -> Vec3<T> {
        Vec3(self.0.map(f))
    }
    /// Dot product.
    pub fn dot(self, o: Self) -> S {
        self.0[0] * o.0[0] + self.0[1] * o.0[1] + self.0[2] * o.0[2]
    }
    /// Cross product `self × o`.
    pub fn cross(self, o: Self) -> Self {
        let [a, b, c] = self.0;
        let [x, y, z] = o.0;
        Vec3([b * z - c * y, c * x - a * z, a * y - b * x])
    }
    /// `k · self`.
    pub fn scale(self, k: S) -> Self {
        self.map(|x| x * k)
    }
    /// Squared Euclidean norm.
    pub fn norm_squared(self) -> S {
        self.dot(self)
    }
    /// Euclidean norm.
    pub fn norm(self) -> S {
        self.norm_squared().sqrt()
    }
    /// The skew-symmetric matrix `[v]×` with `[v]× w = v × w`.
    pub fn skew(self) -> Mat3<S> {
        let [x, y, z] = self.0;
        let o = S::zero();
        Mat3([[o, -z, y], [z, o, -x], [-y, x, o]])
    }
}

impl<S> Index<usize> for Vec3<S> {
    type Output = S;
    fn index(&self, i: usize) -> &S {
        &self.0[i]
    }
}

impl<S: Scalar> Add for Vec3<S> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Vec3([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}

impl<S: Scalar> Sub for Vec3<S> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Vec3([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}

impl<S: Scalar> Neg for Vec3<S> {
    type Output = Self;
    fn neg(self) -> Self {
        self.map(|x| -x)
    }
}

impl From<Vec3<f64>> for nalgebra::Vector3<f64> {
    fn from(v: Vec3<f64>) -> Self {
        nalgebra::Vector3::new(v.0[0], v.0[1], v.0[2])
    }
}

impl From<nalgebra::Vector3<f64>> for Vec3<f64> {
    fn from(v: nalgebra::Vector3<f64>) -> Self {
        Vec3([v.x, v.y, v.z])
    }
}

impl From<Mat3<f64>> for nalgebra::Matrix3<f64> {
    fn from(m: Mat3<f64>) -> Self {
        nalgebra::Matrix3::from_fn(|i, j| m.0[i][j])
    }
}

impl<S: Scalar> Mat3<S> {
    /// The zero matrix.
    pub fn zero() -> Self {
        Mat3([[S::zero(); 3]; 3])
    }
    /// The identity.
    pub fn identity() -> Self {
        let mut m = Self::zero();
        for i in 0..3 {
            m.0[i][i] = S::one();
        }
        m
    }
    /// From rows.
    pub fn from_rows(r: [Vec3<S>; 3]) -> Self {
        Mat3([r[0].0, r[1].0, r[2].0])
    }
    /// From columns.
    pub fn from_cols(c: [Vec3<S>; 3]) -> Self {
        Mat3::from_rows(c).transpose()
    }
    /// From `f64` entries (row-major).
    pub fn from_f64(m: [[f64; 3]; 3]) -> Self {
        Mat3(m.map(|r| r.map(S::from_f64)))
    }
    /// The diagonal matrix `diag(d)`.
    pub fn diag(d: Vec3<S>) -> Self {
        let mut m = Self::zero();
        for i in 0..3 {
            m.0[i][i] = d.0[i];
        }
        m
    }
    /// Apply `f` to each entry.
    pub fn map<T>(self, mut f: impl FnMut(S) -> T) -> Mat3<T> {
        Mat3(self.0.map(|r| r.map(&mut f)))
    }
    /// Row `i`.
    pub fn row(&self, i: usize) -> Vec3<S> {
        Vec3(self.0[i])
    }
    /// Column `j`.
    pub fn col(&self, j: usize) -> Vec3<S> {
        Vec3([self.0[0][j], self.0[1][j], self.0[2][j]])
    }
    /// Transpose.
    pub fn transpose(&self) -> Self {
        let m = &self.0;
        Mat3([0, 1, 2].map(|i| [m[0][i], m[1][i], m[2][i]]))
    }
    /// `self · v`.
    pub fn mul_vec(&self, v: Vec3<S>) -> Vec3<S> {
        Vec3([0, 1, 2].map(|i| self.row(i).dot(v)))
    }
    /// `selfᵀ · v` (without building the transpose).
    pub fn tr_mul_vec(&self, v: Vec3<S>) -> Vec3<S> {
        Vec3([0, 1, 2].map(|j| self.col(j).dot(v)))
    }
    /// `k · self`.
    pub fn scale(&self, k: S) -> Self {
        self.map(|x| x * k)
    }
    /// Trace.
    pub fn trace(&self) -> S {
        self.0[0][0] + self.0[1][1] + self.0[2][2]
    }
    /// Determinant.
    pub fn det(&self) -> S {
        self.row(0).dot(self.row(1).cross(self.row(2)))
    }

    /// Rotation by `angle` about a coordinate axis (right-hand rule).
    pub fn rot(axis: Axis, angle: S) -> Self {
        let (s, c) = angle.sin_cos();
        let (o, l) = (S::zero(), S::one());
        match axis {
            Axis::X => Mat3([[l, o, o], [o, c, -s], [o, s, c]]),
            Axis::Y => Mat3([[c, o, s], [o, l, o], [-s, o, c]]),
            Axis::Z => Mat3([[c, -s, o], [s, c, o], [o, o, l]]),
        }
    }

    /// Rotation by `angle` about the unit vector `k` (Rodrigues):
    /// `R = I + sin θ [k]× + (1 − cos θ) [k]×²`.
    pub fn from_axis_angle(k: Vec3<S>, angle: S) -> Self {
        let (s, c) = angle.sin_cos();
        let kx = k.skew();
        let kx2 = kx * kx;
        let one_c = S::one() - c;
        let mut r = Self::identity();
        for i in 0..3 {
            for j in 0..3 {
                r.0[i][j] = r.0[i][j] + s * kx.0[i][j] + one_c * kx2.0[i][j];
            }
        }
        r
    }

    /// Rotation from three intrinsic angles about `axes`:
    /// `R = R_{a1}(θ1) · R_{a2}(θ2) · R_{a3}(θ3)`. Classical Euler angles are
    /// `[Z, X, Z]`, Bryan (Cardan) angles `[X, Y, Z]`.
    pub fn from_euler(axes: [Axis; 3], angles: [S; 3]) -> Self {
        Mat3::rot(axes[0], angles[0])
            * Mat3::rot(axes[1], angles[1])
            * Mat3::rot(axes[2], angles[2])
    }

    /// Rotation from a unit quaternion `(w, x, y, z)` (Euler–Rodrigues
    /// parameters); the formula assumes `w² + x² + y² + z² = 1`.
    pub fn from_quaternion(q: [S; 4]) -> Self {
        let [w, x, y, z] = q;
        let two = S::from_f64(2.0);
        let l = S::one();
        let (xx, yy, zz) = (x * x, y * y, z * z);
        let (xy, xz, yz) = (x * y, x * z, y * z);
        let (wx, wy, wz) = (w * x, w * y, w * z);
        Mat3([
            [l - two * (yy + zz), two * (xy - wz), two * (xz + wy)],
            [two * (xy + wz), l - two * (xx + zz), two * (yz - wx)],
            [two * (xz - wy), two * (yz + wx), l - two * (xx + yy)],
        ])
    }
}

impl<S: Scalar> Mul for Mat3<S> {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Mat3([0, 1, 2].map(|i| [0, 1, 2].map(|j| self.row(i).dot(o.col(j)))))
    }
}

impl<S: Scalar> Add for Mat3<S> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Mat3([0, 1, 2].map(|i| [0, 1, 2].map(|j| self.0[i][j] + o.0[i][j])))
    }
}

impl<S: Scalar> Sub for Mat3<S> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Mat3([0, 1, 2].map(|i| [0, 1, 2].map(|j| self.0[i][j] - o.0[i][j])))
    }
}

impl<S: Scalar> Neg for Mat3<S> {
    type Output = Self;
    fn neg(self) -> Self {
        self.map(|x| -x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sym::{Context, Expr};

    fn count_not_0_1(m: &Mat3<Expr<'_>>) -> usize {
        m.0.iter()
            .flatten()
            .filter(|e| !e.is_zero() && !e.is_one())
            .count()
    }

    #[test]
    fn axis_rotation_has_four_nontrivial_entries() {
        let cx = Context::new();
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            let r = Mat3::rot(axis, cx.q(0));
            assert_eq!(count_not_0_1(&r), 4, "rot about {axis:?}: {r:?}");
            let k = Vec3::unit(axis);
            let rr = Mat3::from_axis_angle(k, cx.q(0));
            assert_eq!(rr, r, "Rodrigues about {axis:?}: got {rr:?} want {r:?}");
        }
    }

    #[test]
    fn parallel_axis_chain_contracts() {
        let cx = Context::new();
        let r = Mat3::rot(Axis::Z, cx.q(1)) * Mat3::rot(Axis::Z, cx.q(2));
        let want = Mat3::rot(Axis::Z, cx.parse("(+ q1 q2)").unwrap());
        assert_eq!(r, want, "got {r:?} want {want:?}");
    }

    #[test]
    fn rotation_is_orthogonal_symbolically() {
        let cx = Context::new();
        let r = Mat3::from_euler([Axis::Z, Axis::X, Axis::Z], [cx.q(0), cx.q(1), cx.q(2)]);
        let rtr = r.transpose() * r;
        // Not every entry reduces structurally; check numerically.
        let vals = cx.arena().values(&[("q0", 0.3), ("q1", -1.1), ("q2", 2.0)]);
        for i in 0..3 {
            for j in 0..3 {
                let got = cx.eval(rtr.0[i][j], &vals);
                let want = if i == j { 1.0 } else { 0.0 };
                assert!(
                    (got - want).abs() < 1e-14,
                    "RᵀR[{i}][{j}]: got {got} want {want}"
                );
            }
        }
    }

    #[test]
    fn quaternion_matches_axis_angle() {
        let (k, th) = (Vec3::<f64>::new(1.0, 2.0, 2.0).scale(1.0 / 3.0), 0.7f64);
        let (s, c) = (th / 2.0).sin_cos();
        let q = [c, s * k[0], s * k[1], s * k[2]];
        let a = Mat3::from_quaternion(q);
        let b = Mat3::from_axis_angle(k, th);
        for i in 0..3 {
            for j in 0..3 {
                assert!(
                    (a.0[i][j] - b.0[i][j]).abs() < 1e-15,
                    "[{i}][{j}]: got {} want {}",
                    a.0[i][j],
                    b.0[i][j]
                );
            }
        }
    }

    #[test]
    fn cross_and_skew_agree() {
        let a = Vec3::new(1.0, -2.0, 0.5);
        let b = Vec3::new(0.3, 4.0, -1.0);
        assert_eq!(a.skew().mul_vec(b), a.cross(b));
        assert_eq!(a.cross(b).dot(a), 0.0);
    }
}
