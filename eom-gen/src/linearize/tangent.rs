//! The chart of the tangent-space displacements `δq` (one per speed) about a
//! configuration `q*`, in which the linearisation is written:
//!
//! - a coordinate with `q̇ = u` (revolute, prismatic, …, elastic): `q = q* + δq`;
//! - a quaternion `Q` (spherical and free joints): `Q = Q* ⊗ Exp(δθ)`, `δθ`
//!   a rotation vector in body (child joint-frame) axes;
//! - a free joint's position `p`: `p = p* + R(Q*) δp`, `δp` in body axes.
//!
//! At `δq = 0` this is the map `dq = N(q*) δq` (`q̇ = N(q) u`) that the
//! generated derivatives use (`∂u̇/∂δq = ∂u̇/∂q N`), and its rates are, to
//! first order in `δq`,
//!
//! ```text
//! δθ̇ = J_r⁻¹(δθ) ω ≈ ω + ½ δθ × ω,     δṗ = Exp(δθ) v ≈ v + δθ × v,
//! ```
//!
//! so `∂δq̇/∂u = I` and `∂δq̇/∂δq` is `−½[ω]×` on a rotation and `−[v]×`
//! from a free joint's rotation to its position: zero at rest, not zero
//! where the joint moves (a rolling vehicle's rear frame).

use crate::system::{Block, JointType, System};
use nalgebra::DMatrix;

/// What one tangent direction (one speed) moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Direction {
    /// The coordinate at this index (`q̇ = u`).
    Plain(usize),
    /// A free joint's position along body axis `axis`; `p` and `quat` are
    /// the indices of its position and quaternion.
    Translation { p: usize, quat: usize, axis: usize },
    /// A rotation about body axis `axis` of the quaternion at `quat`.
    Rotation { quat: usize, axis: usize },
}

/// The chart of a model's coordinates, one direction per speed.
#[derive(Clone, Debug)]
pub(super) struct Chart {
    directions: Vec<Direction>,
}

/// `[a]×`: the matrix of `a × ·`.
fn cross(a: [f64; 3]) -> [[f64; 3]; 3] {
    [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]]
}

/// The rotation matrix of the unit quaternion `(w, x, y, z)`.
fn rotation(q: [f64; 4]) -> [[f64; 3]; 3] {
    let [w, x, y, z] = q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

impl Chart {
    /// The chart of `sys`'s coordinates (tree joints and elastic
    /// coordinates in the order of `q` and `u`).
    pub(super) fn new(sys: &System) -> Chart {
        let mut directions = Vec::with_capacity(sys.nu());
        let mut q = 0;
        for block in sys.coordinate_blocks() {
            match block {
                Block::Joint(j) => match j.kind {
                    JointType::Spherical => {
                        directions.extend((0..3).map(|axis| Direction::Rotation { quat: q, axis }));
                        q += 4;
                    }
                    JointType::Free => {
                        let (p, quat) = (q, q + 3);
                        directions.extend((0..3).map(|axis| Direction::Translation {
                            p,
                            quat,
                            axis,
                        }));
                        directions.extend((0..3).map(|axis| Direction::Rotation { quat, axis }));
                        q += 7;
                    }
                    ref kind => {
                        directions.extend((q..q + kind.nq()).map(Direction::Plain));
                        q += kind.nq();
                    }
                },
                Block::Elastic(f) => {
                    directions.extend((q..q + f.count()).map(Direction::Plain));
                    q += f.count();
                }
            }
        }
        Chart { directions }
    }

    /// The name of each tangent direction: the coordinate's where `q̇ = u`,
    /// else `d(<speed>)` (a quaternion joint's displacement along that
    /// speed).
    pub(super) fn names(&self, sys: &System) -> Vec<String> {
        let coordinates = sys.coordinate_names();
        let speeds = sys.speed_names();
        self.directions
            .iter()
            .zip(&speeds)
            .map(|(d, s)| match d {
                Direction::Plain(i) => coordinates[*i].to_string(),
                _ => format!("d({s})"),
            })
            .collect()
    }

    /// `q* ⊕ s e_k`: the configuration displaced by `s` along tangent
    /// direction `k`.
    pub(super) fn displaced(&self, q: &[f64], k: usize, s: f64) -> Vec<f64> {
        let mut out = q.to_vec();
        let quaternion = |i: usize| [q[i], q[i + 1], q[i + 2], q[i + 3]];
        match self.directions[k] {
            Direction::Plain(i) => out[i] += s,
            Direction::Translation { p, quat, axis } => {
                let r = rotation(quaternion(quat));
                for (row, r) in r.iter().enumerate() {
                    out[p + row] += r[axis] * s;
                }
            }
            Direction::Rotation { quat, axis } => {
                // Q ⊗ (cos(s/2), sin(s/2) e_axis).
                let [w, x, y, z] = quaternion(quat);
                let (c, h) = ((0.5 * s).cos(), (0.5 * s).sin());
                let e = [w, x, y, z];
                let b = match axis {
                    0 => [c, h, 0.0, 0.0],
                    1 => [c, 0.0, h, 0.0],
                    _ => [c, 0.0, 0.0, h],
                };
                let product = [
                    e[0] * b[0] - e[1] * b[1] - e[2] * b[2] - e[3] * b[3],
                    e[0] * b[1] + e[1] * b[0] + e[2] * b[3] - e[3] * b[2],
                    e[0] * b[2] - e[1] * b[3] + e[2] * b[0] + e[3] * b[1],
                    e[0] * b[3] + e[1] * b[2] - e[2] * b[1] + e[3] * b[0],
                ];
                out[quat..quat + 4].copy_from_slice(&product);
            }
        }
        out
    }

    /// `∂δq̇/∂δq` at `δq = 0` with speeds `u`: `−½[ω]×` on each rotation,
    /// `−[v]×` from a free joint's rotation to its position (see the module
    /// documentation), zero elsewhere.
    pub(super) fn kinematics(&self, u: &[f64]) -> DMatrix<f64> {
        let n = self.directions.len();
        let mut a = DMatrix::<f64>::zeros(n, n);
        let mut k = 0;
        while k < n {
            match self.directions[k] {
                Direction::Plain(_) => k += 1,
                Direction::Translation { .. } => {
                    // A free joint: v = u[k..k+3], ω = u[k+3..k+6].
                    let v = cross([u[k], u[k + 1], u[k + 2]]);
                    let w = cross([u[k + 3], u[k + 4], u[k + 5]]);
                    for i in 0..3 {
                        for j in 0..3 {
                            a[(k + i, k + 3 + j)] = -v[i][j];
                            a[(k + 3 + i, k + 3 + j)] = -0.5 * w[i][j];
                        }
                    }
                    k += 6;
                }
                Direction::Rotation { .. } => {
                    let w = cross([u[k], u[k + 1], u[k + 2]]);
                    for i in 0..3 {
                        for j in 0..3 {
                            a[(k + i, k + j)] = -0.5 * w[i][j];
                        }
                    }
                    k += 3;
                }
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A displacement along a rotation direction keeps the quaternion a
    /// unit one and turns by the angle given: `Q ⊗ Exp(s e_z)` of the
    /// identity is `(cos s/2, 0, 0, sin s/2)`; the rotation matrix of a
    /// quarter turn about z maps x to y.
    #[test]
    fn rotations_and_quaternions() {
        let r = rotation([
            std::f64::consts::FRAC_1_SQRT_2,
            0.0,
            0.0,
            std::f64::consts::FRAC_1_SQRT_2,
        ]);
        assert!((r[1][0] - 1.0).abs() < 1e-15 && r[0][0].abs() < 1e-15);
        let chart = Chart {
            directions: vec![
                Direction::Rotation { quat: 0, axis: 0 },
                Direction::Rotation { quat: 0, axis: 1 },
                Direction::Rotation { quat: 0, axis: 2 },
            ],
        };
        let q = chart.displaced(&[1.0, 0.0, 0.0, 0.0], 2, 0.3);
        assert!((q[0] - 0.15f64.cos()).abs() < 1e-15 && (q[3] - 0.15f64.sin()).abs() < 1e-15);
        let norm: f64 = q.iter().map(|x| x * x).sum();
        assert!((norm - 1.0).abs() < 1e-15);
    }
}
