//! The reduced matrices of a body whose shape functions are given rather than
//! computed as normal modes (assumed modes, imported modal data): checks that
//! they describe independent, elastic deformations, and their normal modes.
//!
//! With `M_ff` and `K_ff` of `k` coordinates (any basis, not necessarily
//! orthogonal), the Rayleigh–Ritz eigenproblem `K_ff φ = ω² M_ff φ` is solved
//! by the Cholesky factor `M_ff = L Lᵀ` and the symmetric eigenproblem of
//! `L⁻¹ K_ff L⁻ᵀ`; `Φ` (mass-normalised, `Φᵀ M_ff Φ = 1`) gives modal damping
//! in the written coordinates,
//!
//! ```text
//! D_ff = M_ff Φ diag(2 ζ_i ω_i) Φᵀ M_ff       (Φᵀ D_ff Φ = diag(2 ζ_i ω_i))
//! ```
//!
//! which is `2 ζ diag(ω_i)` for mass-normalised normal modes, as for the beam.
//!
//! Checks, each a [`RitzError`] naming the coordinates involved:
//! - `M_ff` must be positive definite: a singular one means the shapes are
//!   not independent (some combination carries no kinetic energy, i.e. is
//!   zero, up to `1e-10` of the largest diagonal-scaled eigenvalue);
//! - `K_ff` must be positive definite: a combination with no strain energy is
//!   a rigid-body motion of the whole body (for a straight beam with positive
//!   stiffnesses the only deformations without strain energy are rigid), so
//!   the shapes do not fix the body frame.

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use std::fmt;

/// Relative size (of the largest eigenvalue of the diagonally scaled matrix)
/// below which an eigenvalue counts as zero.
pub const SINGULAR: f64 = 1e-10;

/// What is wrong with a pair of reduced matrices.
#[derive(Clone, Debug, PartialEq)]
pub enum RitzError {
    /// A matrix is not `k × k`, not symmetric (relative `1e-8`) or holds a
    /// number that is not finite.
    Malformed(String),
    /// Coordinate `j` (0-based) has no mass: its shape is zero.
    ZeroShape(usize),
    /// Shapes that are not independent: this combination (coefficients per
    /// coordinate, largest 1) has (next to) no kinetic energy.
    Dependent(Vec<f64>),
    /// The mass matrix has a negative eigenvalue.
    NegativeMass,
    /// This combination of shapes has no strain energy: a rigid-body motion,
    /// so the frame is undefined.
    RigidMotion(Vec<f64>),
    /// The stiffness matrix has a negative eigenvalue.
    NegativeStiffness,
}

/// `1·S_1 − 0.5·S_3` for a combination.
pub fn combination(c: &[f64], name: &str) -> String {
    let mut out = String::new();
    for (j, &x) in c.iter().enumerate() {
        if x.abs() < 1e-6 {
            continue;
        }
        let sign = match (out.is_empty(), x < 0.0) {
            (true, false) => "",
            (true, true) => "−",
            (false, false) => " + ",
            (false, true) => " − ",
        };
        out += &format!("{sign}{:.3}·{name}{}", x.abs(), j + 1);
    }
    out
}

impl fmt::Display for RitzError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RitzError::Malformed(what) => f.write_str(what),
            RitzError::ZeroShape(j) => write!(f, "shape {} is zero everywhere", j + 1),
            RitzError::Dependent(c) => write!(
                f,
                "the shapes are not independent: `{}` is (next to) zero, so the mass matrix is singular",
                combination(c, "S")
            ),
            RitzError::NegativeMass => {
                f.write_str("the modal mass matrix is not positive definite")
            }
            RitzError::RigidMotion(c) => write!(
                f,
                "`{}` has no strain energy: it is a rigid-body motion of the whole body, \
                 so the body frame is undefined",
                combination(c, "S")
            ),
            RitzError::NegativeStiffness => {
                f.write_str("the modal stiffness matrix is not positive definite")
            }
        }
    }
}

impl std::error::Error for RitzError {}

/// The normal modes of a reduced `(M_ff, K_ff)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Ritz {
    /// `ω_i`, rad/s, ascending.
    pub frequencies: Vec<f64>,
    /// `Φ` (k×k), mass-normalised eigenvectors in the written coordinates,
    /// column `i` for `ω_i`.
    pub vectors: DMatrix<f64>,
    /// `M_ff Φ diag(2 ω_i) Φᵀ M_ff`: the damping matrix per unit damping
    /// ratio `ζ` of every mode.
    pub damping_unit: DMatrix<f64>,
}

/// Checks size, finiteness and symmetry of a `k × k` matrix.
pub fn check_square(a: &DMatrix<f64>, k: usize, what: &str) -> Result<(), RitzError> {
    if a.nrows() != k || a.ncols() != k {
        return Err(RitzError::Malformed(format!(
            "{what} is {}×{}, but there are {k} coordinates",
            a.nrows(),
            a.ncols()
        )));
    }
    if let Some(bad) = a.iter().find(|x| !x.is_finite()) {
        return Err(RitzError::Malformed(format!("{what} holds {bad}")));
    }
    let top = a.amax();
    let asym = (a - a.transpose()).amax();
    if asym > 1e-8 * top {
        return Err(RitzError::Malformed(format!(
            "{what} is not symmetric (largest |A − Aᵀ| is {asym:e} of {top:e})"
        )));
    }
    Ok(())
}

/// Positive definiteness with diagonal scaling; on failure the null
/// combination (largest coefficient 1) or `None` for a clearly negative
/// eigenvalue.
fn definite(a: &DMatrix<f64>) -> Result<(), Option<Vec<f64>>> {
    let k = a.nrows();
    let d: Vec<f64> = (0..k).map(|i| a[(i, i)]).collect();
    if d.iter().any(|&x| x <= 0.0) {
        let j = d.iter().position(|&x| x <= 0.0).unwrap_or(0);
        let mut c = vec![0.0; k];
        c[j] = 1.0;
        return Err(if d[j] < 0.0 { None } else { Some(c) });
    }
    let s = DMatrix::from_fn(k, k, |r, c| a[(r, c)] / (d[r] * d[c]).sqrt());
    let eig = SymmetricEigen::new((&s + s.transpose()) * 0.5);
    let top = eig.eigenvalues.amax();
    let (j, low) = eig
        .eigenvalues
        .iter()
        .copied()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0, 1.0));
    if low > SINGULAR * top {
        return Ok(());
    }
    if low < -SINGULAR * top {
        return Err(None);
    }
    // Back to unscaled coordinates, largest coefficient 1 and positive.
    let v: Vec<f64> = (0..k)
        .map(|r| eig.eigenvectors[(r, j)] / d[r].sqrt())
        .collect();
    let big = v
        .iter()
        .fold(0.0_f64, |a, &b| if b.abs() > a.abs() { b } else { a });
    Err(Some(v.iter().map(|x| x / big).collect()))
}

impl Ritz {
    /// Checks `(mass, stiffness)` (both `k × k`) and solves for the normal modes.
    pub fn new(mass: &DMatrix<f64>, stiffness: &DMatrix<f64>) -> Result<Ritz, RitzError> {
        let k = mass.nrows();
        check_square(mass, k, "the modal mass matrix")?;
        check_square(stiffness, k, "the modal stiffness matrix")?;
        if let Some(j) = (0..k).find(|&j| mass[(j, j)] == 0.0) {
            return Err(RitzError::ZeroShape(j));
        }
        match definite(mass) {
            Ok(()) => {}
            Err(Some(c)) => return Err(RitzError::Dependent(c)),
            Err(None) => return Err(RitzError::NegativeMass),
        }
        match definite(stiffness) {
            Ok(()) => {}
            Err(Some(c)) => return Err(RitzError::RigidMotion(c)),
            Err(None) => return Err(RitzError::NegativeStiffness),
        }
        let m = (mass + mass.transpose()) * 0.5;
        let kk = (stiffness + stiffness.transpose()) * 0.5;
        let l = m.clone().cholesky().ok_or(RitzError::NegativeMass)?.l();
        let x = l
            .solve_lower_triangular(&kk)
            .ok_or(RitzError::NegativeMass)?;
        let a = l
            .solve_lower_triangular(&x.transpose())
            .ok_or(RitzError::NegativeMass)?;
        let eig = SymmetricEigen::new((&a + a.transpose()) * 0.5);
        let mut order: Vec<usize> = (0..k).collect();
        order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        let mut vectors = DMatrix::zeros(k, k);
        let mut frequencies = Vec::with_capacity(k);
        for (col, &j) in order.iter().enumerate() {
            let w2 = eig.eigenvalues[j];
            if w2 <= 0.0 {
                return Err(RitzError::NegativeStiffness);
            }
            let y: DVector<f64> = l
                .tr_solve_lower_triangular(&eig.eigenvectors.column(j).into_owned())
                .ok_or(RitzError::NegativeMass)?;
            let big = y
                .iter()
                .fold(0.0_f64, |a, &b| if b.abs() > a.abs() { b } else { a });
            vectors.set_column(col, &(y * big.signum()));
            frequencies.push(w2.sqrt());
        }
        let two_w = DMatrix::from_diagonal(&DVector::from_iterator(
            k,
            frequencies.iter().map(|w| 2.0 * w),
        ));
        let mphi = &m * &vectors;
        let d = &mphi * two_w * mphi.transpose();
        Ok(Ritz {
            frequencies,
            vectors,
            damping_unit: (&d + d.transpose()) * 0.5,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ritz_diagonal_pair_gives_its_frequencies_and_damping() {
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![2.0, 1.0]));
        let k = DMatrix::from_diagonal(&DVector::from_vec(vec![8.0, 9.0]));
        let r = Ritz::new(&m, &k).unwrap();
        assert!((r.frequencies[0] - 2.0).abs() < 1e-12 && (r.frequencies[1] - 3.0).abs() < 1e-12);
        // D = M Φ 2Ω Φᵀ M: for diagonal M, K it is diag(2 ω_i m_i).
        let want = DMatrix::from_diagonal(&DVector::from_vec(vec![8.0, 6.0]));
        assert!(
            (&r.damping_unit - want).amax() < 1e-12,
            "{}",
            r.damping_unit
        );
    }

    #[test]
    fn ritz_names_dependent_and_rigid_combinations() {
        // S_2 = 2 S_1: M = [[1, 2], [2, 4]].
        let m = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]);
        let k = DMatrix::identity(2, 2);
        let RitzError::Dependent(c) = Ritz::new(&m, &k).unwrap_err() else {
            panic!("want Dependent")
        };
        assert!(
            (c[0] - 1.0).abs() < 1e-6 && (c[1] + 0.5).abs() < 1e-6,
            "{c:?}"
        );
        let k = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        let err = Ritz::new(&DMatrix::identity(2, 2), &k).unwrap_err();
        assert!(
            err.to_string().contains("1.000·S1 − 1.000·S2")
                || err.to_string().contains("−1.000·S1 + 1.000·S2"),
            "{err}"
        );
    }
}
