//! The sparse `LᵀDL` factorisation of a mass matrix that follows the tree
//! (Featherstone §6.5, Tables 6.3–6.4), the forward-dynamics route through
//! the CRBA mass matrix, and the speed-level parent array it follows.

// Index loops over small dense matrices read like the textbook formulas.
#![allow(clippy::needless_range_loop)]

use super::kinematics::Evaluator;
use super::tree::Coords;
use crate::sym::Scalar;

impl<'a, S: Scalar> Evaluator<'a, S> {
    /// Speed-level parent array for [`ltdl`]: the previous free speed on
    /// the path to ground (`None` at the root).
    pub fn speed_parents(&self) -> Vec<Option<usize>> {
        let mut lambda = vec![None; self.tree.nu];
        let mut last: Vec<Option<usize>> = vec![None; self.tree.bodies.len()];
        // The last elastic speed of each flexible body: above its nodes.
        let mut last_elastic: Vec<Option<usize>> = vec![None; self.tree.bodies.len()];
        for (i, b) in self.tree.bodies.iter().enumerate() {
            let above = match (b.node, b.parent) {
                (Some(_), Some(p)) => last_elastic[p],
                _ => b.parent.and_then(|p| last[p]),
            };
            last[i] = above;
            if let Coords::Free { u, .. } = b.coords {
                for k in 0..b.kind.nu() {
                    lambda[u + k] = if k == 0 { above } else { Some(u + k - 1) };
                }
                if b.kind.nu() > 0 {
                    last[i] = Some(u + b.kind.nu() - 1);
                }
            }
            // Elastic speeds: a branch of their own below the joint's
            // (bodies carried by the frame do not couple to them; bodies
            // at nodes hang below them).
            if let Some(fm) = &b.flex {
                for j in 0..fm.count() {
                    lambda[fm.u + j] = if j == 0 { last[i] } else { Some(fm.u + j - 1) };
                }
                last_elastic[i] = fm.count().checked_sub(1).map(|j| fm.u + j).or(last[i]);
            }
        }
        lambda
    }
}

/// In-place `LᵀDL` factorisation of a mass matrix that follows the tree
/// (Featherstone Table 6.3): afterwards the diagonal holds `D` and the
/// entries `(k, i)` with `i` an ancestor of `k` hold `L`. No fill-in
/// outside the ancestor pattern.
pub fn ltdl<S: Scalar>(m: &mut [Vec<S>], lambda: &[Option<usize>]) {
    for k in (0..m.len()).rev() {
        let mut i = lambda[k];
        while let Some(ii) = i {
            let a = m[k][ii] / m[k][k];
            let mut j = Some(ii);
            while let Some(jj) = j {
                m[ii][jj] = m[ii][jj] - a * m[k][jj];
                j = lambda[jj];
            }
            m[k][ii] = a;
            i = lambda[ii];
        }
    }
}

/// Solves `M x = b` with `M` factorised by [`ltdl`] (Featherstone Table 6.4).
pub fn ltdl_solve<S: Scalar>(f: &[Vec<S>], lambda: &[Option<usize>], mut b: Vec<S>) -> Vec<S> {
    let n = b.len();
    for i in (0..n).rev() {
        let mut j = lambda[i];
        while let Some(jj) = j {
            b[jj] = b[jj] - f[i][jj] * b[i];
            j = lambda[jj];
        }
    }
    for i in 0..n {
        b[i] = b[i] / f[i][i];
    }
    for i in 0..n {
        let mut j = lambda[i];
        while let Some(jj) = j {
            b[i] = b[i] - f[i][jj] * b[jj];
            j = lambda[jj];
        }
    }
    b
}

/// `M⁻¹` from the factors of [`ltdl`] (`M = Lᵀ D L`, `L` unit lower
/// triangular along the tree): column `c` solves `Lᵀ y = e_c` (nonzero only
/// at `c` and its ancestors), scales by `D⁻¹` (each `1 / D_k` formed once)
/// and solves `L x = y` for the rows `i ≤ c` only; the lower triangle is the
/// upper's mirror, so the result is exactly symmetric. About `n³/3`
/// multiply-adds for a chain, fewer along a tree.
pub fn ltdl_inverse<S: Scalar>(f: &[Vec<S>], lambda: &[Option<usize>]) -> Vec<Vec<S>> {
    let n = f.len();
    let dinv: Vec<S> = (0..n).map(|k| S::one() / f[k][k]).collect();
    let mut inv = vec![vec![S::zero(); n]; n];
    for c in 0..n {
        // Lᵀ y = e_c: only c and its ancestors are reached.
        let mut y = vec![S::zero(); n];
        y[c] = S::one();
        let mut i = Some(c);
        while let Some(ii) = i {
            let mut j = lambda[ii];
            while let Some(jj) = j {
                y[jj] = y[jj] - f[ii][jj] * y[ii];
                j = lambda[jj];
            }
            i = lambda[ii];
        }
        // D⁻¹, then L x = y for the rows up to c.
        let mut x = vec![S::zero(); n];
        for i in 0..=c {
            let mut xi = y[i] * dinv[i];
            let mut j = lambda[i];
            while let Some(jj) = j {
                xi = xi - f[i][jj] * x[jj];
                j = lambda[jj];
            }
            x[i] = xi;
        }
        for i in 0..=c {
            inv[i][c] = x[i];
            inv[c][i] = x[i];
        }
    }
    inv
}
