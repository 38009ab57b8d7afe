//! Sparse matrices with a pattern fixed once (compressed columns) and the
//! linear solvers behind a trait, implemented with `faer`'s sparse LU and
//! Cholesky: the symbolic analysis (fill-reducing ordering, elimination
//! tree) is done on the first factorisation and reused for every later one.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};
use std::fmt;
use std::sync::Arc;

/// The pattern of a square sparse matrix in compressed columns (row indices
/// sorted within each column).
#[derive(Clone, Debug)]
pub struct Pattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

impl Pattern {
    /// The pattern holding every `(row, col)` in `entries` (duplicates
    /// merged) and the whole diagonal.
    pub fn new(n: usize, entries: impl IntoIterator<Item = (usize, usize)>) -> Pattern {
        let mut cols: Vec<Vec<usize>> = (0..n).map(|j| vec![j]).collect();
        for (i, j) in entries {
            cols[j].push(i);
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for c in &mut cols {
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        Pattern {
            n,
            col_ptr,
            row_idx,
        }
    }

    /// Dimension.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The position of `(row, col)` in the value array, if stored.
    pub fn slot(&self, row: usize, col: usize) -> Option<usize> {
        let (a, b) = (self.col_ptr[col], self.col_ptr[col + 1]);
        self.row_idx[a..b].binary_search(&row).ok().map(|k| a + k)
    }

    /// Every stored entry as `(row, col, slot)`, column by column.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        (0..self.n).flat_map(move |j| {
            (self.col_ptr[j]..self.col_ptr[j + 1]).map(move |k| (self.row_idx[k], j, k))
        })
    }

    fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

/// A square sparse matrix: a shared [`Pattern`] and its values.
#[derive(Clone, Debug)]
pub struct SparseMatrix {
    pattern: Arc<Pattern>,
    /// The values, in the pattern's order.
    pub values: Vec<f64>,
}

impl SparseMatrix {
    /// A zero matrix of the pattern.
    pub fn zeros(pattern: Arc<Pattern>) -> SparseMatrix {
        let values = vec![0.0; pattern.nnz()];
        SparseMatrix { pattern, values }
    }

    /// The pattern.
    pub fn pattern(&self) -> &Arc<Pattern> {
        &self.pattern
    }

    /// Sets every value to zero.
    pub fn clear(&mut self) {
        self.values.fill(0.0);
    }

    /// `y += a · self · x`.
    pub fn mul_add(&self, a: f64, x: &[f64], y: &mut [f64]) {
        let p = &self.pattern;
        for (j, &xj) in x.iter().enumerate().take(p.n) {
            if xj == 0.0 {
                continue;
            }
            for k in p.col_ptr[j]..p.col_ptr[j + 1] {
                y[p.row_idx[k]] += a * self.values[k] * xj;
            }
        }
    }

    /// `xᵀ · self · x`.
    pub fn quadratic_form(&self, x: &[f64]) -> f64 {
        let mut y = vec![0.0; x.len()];
        self.mul_add(1.0, x, &mut y);
        x.iter().zip(&y).map(|(a, b)| a * b).sum()
    }

    /// The entry `(row, col)` (zero if not stored).
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.pattern.slot(row, col).map_or(0.0, |k| self.values[k])
    }

    fn as_faer(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(self.pattern.symbolic(), &self.values)
    }
}

/// Why a factorisation failed.
#[derive(Clone, Debug, PartialEq)]
pub struct FactorError(pub String);

impl fmt::Display for FactorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "sparse factorisation failed: {}", self.0)
    }
}

impl std::error::Error for FactorError {}

/// A sparse direct solver: factor a matrix of a fixed pattern (the symbolic
/// analysis is kept from the first call), then solve with it.
pub trait SparseSolver {
    /// Factors `m` (same pattern on every call).
    fn factor(&mut self, m: &SparseMatrix) -> Result<(), FactorError>;
    /// Overwrites `rhs` with `m⁻¹ rhs` for the last factored `m`.
    fn solve(&self, rhs: &mut [f64]);
    /// Numeric factorisations done so far.
    fn factorizations(&self) -> usize;
}

/// General sparse LU (`faer`, supernodal or simplicial by size, with
/// partial pivoting); for the Newton iteration matrices.
#[derive(Default)]
pub struct FaerLu {
    symbolic: Option<SymbolicLu<usize>>,
    lu: Option<Lu<usize, f64>>,
    count: usize,
}

impl SparseSolver for FaerLu {
    fn factor(&mut self, m: &SparseMatrix) -> Result<(), FactorError> {
        let a = m.as_faer();
        if self.symbolic.is_none() {
            self.symbolic =
                Some(SymbolicLu::try_new(a.symbolic()).map_err(|e| FactorError(format!("{e:?}")))?);
        }
        let Some(sym) = self.symbolic.clone() else {
            return Err(FactorError("no symbolic factorisation".into()));
        };
        let lu = Lu::try_new_with_symbolic(sym, a).map_err(|e| FactorError(format!("{e:?}")))?;
        self.lu = Some(lu);
        self.count += 1;
        Ok(())
    }

    fn solve(&self, rhs: &mut [f64]) {
        if let Some(lu) = &self.lu {
            lu.solve_in_place(MatMut::from_column_major_slice_mut(rhs, rhs.len(), 1));
        }
    }

    fn factorizations(&self) -> usize {
        self.count
    }
}

/// Sparse Cholesky `L Lᵀ` (`faer`) for symmetric positive definite
/// matrices (the mass matrix); the lower triangle is read.
#[derive(Default)]
pub struct FaerCholesky {
    symbolic: Option<SymbolicLlt<usize>>,
    llt: Option<Llt<usize, f64>>,
    count: usize,
}

impl SparseSolver for FaerCholesky {
    fn factor(&mut self, m: &SparseMatrix) -> Result<(), FactorError> {
        let a = m.as_faer();
        if self.symbolic.is_none() {
            self.symbolic = Some(
                SymbolicLlt::try_new(a.symbolic(), Side::Lower)
                    .map_err(|e| FactorError(format!("{e:?}")))?,
            );
        }
        let Some(sym) = self.symbolic.clone() else {
            return Err(FactorError("no symbolic factorisation".into()));
        };
        let llt = Llt::try_new_with_symbolic(sym, a, Side::Lower)
            .map_err(|e| FactorError(format!("not positive definite ({e:?})")))?;
        self.llt = Some(llt);
        self.count += 1;
        Ok(())
    }

    fn solve(&self, rhs: &mut [f64]) {
        if let Some(llt) = &self.llt {
            llt.solve_in_place(MatMut::from_column_major_slice_mut(rhs, rhs.len(), 1));
        }
    }

    fn factorizations(&self) -> usize {
        self.count
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lu_and_cholesky_solve_a_tridiagonal_system() {
        // The 1-D Laplacian tridiag(-1, 2, -1): A x = b for x = (1, 2, …, n).
        let n = 50;
        let entries = (0..n - 1).flat_map(|i| [(i, i + 1), (i + 1, i)]);
        let p = Arc::new(Pattern::new(n, entries));
        let mut a = SparseMatrix::zeros(p.clone());
        for i in 0..n {
            let s = p.slot(i, i).unwrap_or(usize::MAX);
            a.values[s] = 2.0;
            if i + 1 < n {
                for (r, c) in [(i, i + 1), (i + 1, i)] {
                    let s = p.slot(r, c).unwrap_or(usize::MAX);
                    a.values[s] = -1.0;
                }
            }
        }
        let x: Vec<f64> = (1..=n).map(|i| i as f64).collect();
        let mut b = vec![0.0; n];
        a.mul_add(1.0, &x, &mut b);
        for solver in [
            &mut FaerLu::default() as &mut dyn SparseSolver,
            &mut FaerCholesky::default(),
        ] {
            solver.factor(&a).unwrap_or_else(|e| panic!("{e}"));
            solver.factor(&a).unwrap_or_else(|e| panic!("{e}"));
            let mut y = b.clone();
            solver.solve(&mut y);
            let err = y
                .iter()
                .zip(&x)
                .map(|(u, v)| (u - v).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-10, "{err}");
            assert_eq!(solver.factorizations(), 2);
        }
    }
}
