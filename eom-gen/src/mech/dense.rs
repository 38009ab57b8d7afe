//! Small dense symmetric positive definite systems by `LDLᵀ` without
//! pivoting (articulated joint inertias, a flexible body's elastic block).

// Index loops over small dense matrices read like the textbook formulas.
#![allow(clippy::needless_range_loop)]

use crate::sym::Scalar;

/// Inverse of a small symmetric positive definite matrix by `LDLᵀ`
/// (no pivoting: articulated joint inertias are positive definite).
pub fn invert_spd<S: Scalar>(d: Vec<Vec<S>>) -> Vec<Vec<S>> {
    let n = d.len();
    if n == 1 {
        return vec![vec![S::one() / d[0][0]]];
    }
    (0..n)
        .map(|c| {
            let mut e = vec![S::zero(); n];
            e[c] = S::one();
            solve_dense(&d, e)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .enumerate()
        .fold(vec![vec![S::zero(); n]; n], |mut inv, (c, col)| {
            for (r, x) in col.into_iter().enumerate() {
                inv[r][c] = x;
            }
            inv
        })
}

/// Solves `A x = b` for symmetric positive definite `A` by `LDLᵀ`.
pub fn solve_dense<S: Scalar>(a: &[Vec<S>], mut b: Vec<S>) -> Vec<S> {
    let n = a.len();
    let mut l = a.to_vec();
    // Factor: l holds L below the diagonal and D on it.
    for j in 0..n {
        for k in 0..j {
            let ljk = l[j][k];
            l[j][j] = l[j][j] - ljk * ljk * l[k][k];
        }
        for i in j + 1..n {
            let mut x = l[i][j];
            for k in 0..j {
                x = x - l[i][k] * l[j][k] * l[k][k];
            }
            l[i][j] = x / l[j][j];
        }
    }
    for i in 0..n {
        for k in 0..i {
            b[i] = b[i] - l[i][k] * b[k];
        }
    }
    for i in 0..n {
        b[i] = b[i] / l[i][i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            b[i] = b[i] - l[k][i] * b[k];
        }
    }
    b
}
