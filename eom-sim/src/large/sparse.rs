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
        (0..self.n).flat_map(move |j| self.entries_of(j).map(move |(i, k)| (i, j, k)))
    }

    /// The stored entries of column `col` as `(row, slot)`.
    pub fn entries_of(&self, col: usize) -> impl Iterator<Item = (usize, usize)> + '_ {
        (self.col_ptr[col]..self.col_ptr[col + 1]).map(move |k| (self.row_idx[k], k))
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

    /// `y += a A x` for a symmetric `A` (e.g. the mass matrix): column `j`
    /// of `A` is its row `j`, so each `y_j` is one gathered dot product
    /// instead of scattered updates.
    pub fn sym_mul_add(&self, a: f64, x: &[f64], y: &mut [f64]) {
        let p = &self.pattern;
        for (j, yj) in y.iter_mut().enumerate().take(p.n) {
            let (s, e) = (p.col_ptr[j], p.col_ptr[j + 1]);
            let mut acc = 0.0;
            for (v, &i) in self.values[s..e].iter().zip(&p.row_idx[s..e]) {
                acc += v * x[i];
            }
            *yj += a * acc;
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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FactorError {
    /// The symbolic analysis of the pattern failed (out of memory or an
    /// index overflow in `faer`).
    Symbolic,
    /// A zero or non-finite pivot: the matrix is singular (or holds a NaN),
    /// in column `column` where the solver tells.
    Singular {
        /// The pivot's column, if known.
        column: Option<usize>,
    },
    /// Cholesky met a non-positive pivot: the matrix is not positive
    /// definite.
    NotPositiveDefinite,
}

impl fmt::Display for FactorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FactorError::Symbolic => {
                f.write_str("the symbolic analysis of the sparse pattern failed")
            }
            FactorError::Singular { column: Some(k) } => {
                write!(f, "zero or non-finite pivot in column {k}")
            }
            FactorError::Singular { column: None } => f.write_str("zero or non-finite pivot"),
            FactorError::NotPositiveDefinite => f.write_str("not positive definite"),
        }
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
                Some(SymbolicLu::try_new(a.symbolic()).map_err(|_| FactorError::Symbolic)?);
        }
        let Some(sym) = self.symbolic.clone() else {
            return Err(FactorError::Symbolic);
        };
        let lu = Lu::try_new_with_symbolic(sym, a)
            .map_err(|_| FactorError::Singular { column: None })?;
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
                    .map_err(|_| FactorError::Symbolic)?,
            );
        }
        let Some(sym) = self.symbolic.clone() else {
            return Err(FactorError::Symbolic);
        };
        let llt = Llt::try_new_with_symbolic(sym, a, Side::Lower)
            .map_err(|_| FactorError::NotPositiveDefinite)?;
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

/// LU with partial pivoting of a banded matrix (LAPACK's `gbtrf` scheme,
/// rows stored densely across the band widened by the lower bandwidth for
/// the row exchanges): `n · kl · (kl + ku)` operations to factor and
/// `n · (2 kl + ku)` to solve, against the general sparse LU's symbolic
/// bookkeeping. The bandwidths `kl`, `ku` come from the pattern (a chain of
/// elements with node-ordered coordinates has both equal to
/// `2 · coordinates per node − 1`).
#[derive(Clone, Debug, Default)]
pub struct BandedLu {
    n: usize,
    kl: usize,
    ku: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
    ext: Vec<usize>,
    count: usize,
    factored: bool,
}

impl BandedLu {
    /// Lower and upper bandwidth of a pattern.
    pub fn bandwidths(p: &Pattern) -> (usize, usize) {
        let (mut kl, mut ku) = (0, 0);
        for j in 0..p.n {
            for &i in &p.row_idx[p.col_ptr[j]..p.col_ptr[j + 1]] {
                kl = kl.max(i.saturating_sub(j));
                ku = ku.max(j.saturating_sub(i));
            }
        }
        (kl, ku)
    }

    /// Width of a stored row.
    fn width(&self) -> usize {
        2 * self.kl + self.ku + 1
    }
}

impl SparseSolver for BandedLu {
    fn factor(&mut self, m: &SparseMatrix) -> Result<(), FactorError> {
        let p = &m.pattern;
        let n = p.n;
        let (kl, ku) = Self::bandwidths(p);
        self.n = n;
        self.kl = kl;
        self.ku = ku;
        let w = self.width();
        self.a.clear();
        self.a.resize(n * w, 0.0);
        self.piv.clear();
        self.piv.resize(n, 0);
        self.factored = false;
        let a = &mut self.a;
        let ext = &mut self.ext;
        // Row i holds columns i − kl … i + ku + kl at i·w + (j + kl − i).
        let at = |i: usize, j: usize| i * w + j + kl - i;
        for j in 0..n {
            for k in p.col_ptr[j]..p.col_ptr[j + 1] {
                let i = p.row_idx[k];
                a[at(i, j)] = m.values[k];
            }
        }
        // Last stored column of each row's nonzeros: `i + ku` at first,
        // growing only where a pivot row with a longer reach is swapped in
        // or eliminated into it (usually never: then U keeps bandwidth ku).
        ext.clear();
        ext.extend((0..n).map(|i| (i + ku).min(n - 1)));
        for k in 0..n {
            let last_row = (k + kl).min(n - 1);
            let mut piv = k;
            let mut big = a[at(k, k)].abs();
            for i in k + 1..=last_row {
                let v = a[at(i, k)].abs();
                if v > big {
                    big = v;
                    piv = i;
                }
            }
            if big == 0.0 || !big.is_finite() {
                return Err(FactorError::Singular { column: Some(k) });
            }
            self.piv[k] = piv;
            if piv != k {
                for j in k..=ext[k].max(ext[piv]) {
                    a.swap(at(k, j), at(piv, j));
                }
                ext.swap(k, piv);
            }
            let inv = 1.0 / a[at(k, k)];
            let (base_k, len) = (at(k, k + 1), ext[k] - k);
            for i in k + 1..=last_row {
                let l = a[at(i, k)] * inv;
                a[at(i, k)] = l;
                if l != 0.0 {
                    let base_i = at(i, k + 1);
                    let (head, tail) = a.split_at_mut(base_i);
                    for (x, y) in tail[..len].iter_mut().zip(&head[base_k..base_k + len]) {
                        *x -= l * y;
                    }
                    ext[i] = ext[i].max(ext[k]);
                }
            }
        }
        self.factored = true;
        self.count += 1;
        Ok(())
    }

    fn solve(&self, rhs: &mut [f64]) {
        if !self.factored {
            return;
        }
        let (n, kl, w, a) = (self.n, self.kl, self.width(), &self.a);
        let at = |i: usize, j: usize| i * w + j + kl - i;
        for k in 0..n {
            rhs.swap(k, self.piv[k]);
            let bk = rhs[k];
            if bk != 0.0 {
                for i in k + 1..=(k + kl).min(n - 1) {
                    rhs[i] -= a[at(i, k)] * bk;
                }
            }
        }
        for k in (0..n).rev() {
            let len = self.ext[k] - k;
            let base = at(k, k + 1);
            let (head, tail) = rhs.split_at_mut(k + 1);
            let (row, x) = (&a[base..base + len], &tail[..len]);
            // Four partial sums: the dot product is latency-bound otherwise.
            let mut acc = [0.0; 4];
            let (rc, xc) = (row.chunks_exact(4), x.chunks_exact(4));
            let (rr, xr) = (rc.remainder(), xc.remainder());
            for (r4, x4) in rc.zip(xc) {
                for t in 0..4 {
                    acc[t] += r4[t] * x4[t];
                }
            }
            let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
            for (r, v) in rr.iter().zip(xr) {
                s += r * v;
            }
            head[k] = (head[k] - s) / a[at(k, k)];
        }
    }

    fn factorizations(&self) -> usize {
        self.count
    }
}

/// LU by [`BandedLu`] when the pattern is banded (the band, widened for
/// pivoting, stores at most 8 times the pattern's entries), otherwise by
/// faer's sparse LU ([`FaerLu`]); decided at the first factorisation.
#[derive(Default)]
pub struct AutoLu {
    banded: Option<BandedLu>,
    general: FaerLu,
    decided: bool,
}

impl AutoLu {
    /// True once the banded solver has been chosen.
    pub fn is_banded(&self) -> bool {
        self.banded.is_some()
    }
}

impl SparseSolver for AutoLu {
    fn factor(&mut self, m: &SparseMatrix) -> Result<(), FactorError> {
        if !self.decided {
            let p = &m.pattern;
            let (kl, ku) = BandedLu::bandwidths(p);
            if p.n * (2 * kl + ku + 1) <= 8 * p.nnz() {
                self.banded = Some(BandedLu::default());
            }
            self.decided = true;
        }
        match &mut self.banded {
            Some(b) => b.factor(m),
            None => self.general.factor(m),
        }
    }

    fn solve(&self, rhs: &mut [f64]) {
        match &self.banded {
            Some(b) => b.solve(rhs),
            None => self.general.solve(rhs),
        }
    }

    fn factorizations(&self) -> usize {
        match &self.banded {
            Some(b) => b.factorizations(),
            None => self.general.factorizations(),
        }
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
            &mut BandedLu::default(),
            &mut AutoLu::default(),
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
