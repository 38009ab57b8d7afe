//! In-place LU decomposition with partial pivoting on statically sized
//! matrices, real or complex (Hairer's DEC/SOL and DECC/SOLC).
//!
//! nalgebra's `LU` on `SMatrix<T, N, N>` needs `Const<N>: ToTypenum`
//! bounds that would leak into every generic signature of this crate, and
//! its dynamic variant allocates per decomposition; this small routine
//! factors in place with no allocation and no extra bounds.

use nalgebra::{ComplexField, SMatrix};

/// `P A = L U` stored in place (unit lower `L` below the diagonal).
#[derive(Debug, Clone)]
pub(crate) struct Lu<T: ComplexField<RealField = f64> + Copy, const N: usize> {
    /// The matrix to factor; after [`Lu::factor`] its LU factors.
    pub a: SMatrix<T, N, N>,
    piv: [usize; N],
}

impl<T: ComplexField<RealField = f64> + Copy, const N: usize> Lu<T, N> {
    /// A zero matrix, to be filled and factored.
    pub fn zeros() -> Self {
        Lu {
            a: SMatrix::from_element(T::zero()),
            piv: [0; N],
        }
    }

    /// Factors `a` in place; returns `false` on a zero pivot (singular) or a
    /// non-finite entry.
    pub fn factor(&mut self) -> bool {
        let a = &mut self.a;
        for k in 0..N {
            let mut p = k;
            let mut pmax = a[(k, k)].norm1();
            for i in k + 1..N {
                let v = a[(i, k)].norm1();
                if v > pmax {
                    pmax = v;
                    p = i;
                }
            }
            self.piv[k] = p;
            if pmax == 0.0 || !pmax.is_finite() {
                return false;
            }
            if p != k {
                a.swap_rows(p, k);
            }
            let inv = T::one() / a[(k, k)];
            for i in k + 1..N {
                a[(i, k)] *= inv;
            }
            for j in k + 1..N {
                let akj = a[(k, j)];
                if akj != T::zero() {
                    for i in k + 1..N {
                        let lik = a[(i, k)];
                        a[(i, j)] -= lik * akj;
                    }
                }
            }
        }
        true
    }

    /// Solves `A x = b` in place with the factors.
    pub fn solve(&self, b: &mut [T; N]) {
        let a = &self.a;
        for k in 0..N {
            let p = self.piv[k];
            if p != k {
                b.swap(p, k);
            }
        }
        for j in 0..N {
            let bj = b[j];
            if bj != T::zero() {
                for i in j + 1..N {
                    b[i] -= a[(i, j)] * bj;
                }
            }
        }
        for j in (0..N).rev() {
            b[j] /= a[(j, j)];
            let bj = b[j];
            for i in 0..j {
                b[i] -= a[(i, j)] * bj;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Complex;

    #[test]
    fn solves_real_and_complex_systems() {
        // A = [[0, 2, 1], [1, 1, 0], [3, 0, 1]] needs pivoting (a11 = 0).
        let rows = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]];
        let x = [1.0, -2.0, 3.0];
        let mut lu = Lu::<f64, 3>::zeros();
        let mut b = [0.0; 3];
        for i in 0..3 {
            for j in 0..3 {
                lu.a[(i, j)] = rows[i][j];
                b[i] += rows[i][j] * x[j];
            }
        }
        assert!(lu.factor());
        lu.solve(&mut b);
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-14, "got {b:?} want {x:?}");
        }
        // Complex: (A + i I) z = (A + i I) x_c.
        let xc = [
            Complex::new(1.0, 1.0),
            Complex::new(0.0, -2.0),
            Complex::new(3.0, 0.5),
        ];
        let mut luc = Lu::<Complex<f64>, 3>::zeros();
        let mut bc = [Complex::new(0.0, 0.0); 3];
        for i in 0..3 {
            for j in 0..3 {
                let aij = Complex::new(rows[i][j], if i == j { 1.0 } else { 0.0 });
                luc.a[(i, j)] = aij;
                bc[i] += aij * xc[j];
            }
        }
        assert!(luc.factor());
        luc.solve(&mut bc);
        for i in 0..3 {
            assert!((bc[i] - xc[i]).norm() < 1e-14, "got {bc:?} want {xc:?}");
        }
        // Singular matrix is reported.
        let mut s = Lu::<f64, 2>::zeros();
        s.a[(0, 0)] = 1.0;
        s.a[(0, 1)] = 2.0;
        s.a[(1, 0)] = 2.0;
        s.a[(1, 1)] = 4.0;
        assert!(!s.factor(), "singular matrix factored");
    }
}
