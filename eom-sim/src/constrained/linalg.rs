//! Dense linear algebra of the constraint solvers: numerical rank and
//! minimum-norm solves by the SVD, the accelerations and multipliers
//! through the Schur complement, the mass-weighted (damped) minimum-norm
//! solve, the augmented Lagrangian iteration, and Gaussian elimination with
//! complete pivoting for the coordinate partition.

use super::{DMatrix, DVector};

/// Singular values below this fraction of the largest count as zero.
const RANK_TOL: f64 = 1e-10;

/// How many singular values (largest first) are above [`RANK_TOL`] of the
/// largest.
pub(super) fn numerical_rank(sigma: &[f64]) -> usize {
    let largest = sigma.first().copied().unwrap_or(0.0);
    sigma
        .iter()
        .filter(|&&x| x > RANK_TOL * largest.max(1e-300))
        .count()
}

/// Singular values of `a`, largest first (none for an empty matrix).
pub(super) fn singular_values(a: &DMatrix<f64>) -> Vec<f64> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return Vec::new();
    }
    // nalgebra's SVD panics on NaN; a non-finite J has no singular values.
    if !a.iter().all(|x| x.is_finite()) {
        return vec![f64::NAN; a.nrows().min(a.ncols())];
    }
    let mut s: Vec<f64> = a.clone().singular_values().iter().copied().collect();
    s.sort_by(|x, y| y.total_cmp(x));
    s
}

/// Minimum-norm solution of `a x = r` via the SVD, and the numerical rank
/// (singular values below `1e-10` of the largest dropped).
pub fn min_norm_solve(a: &DMatrix<f64>, r: &DVector<f64>) -> (DVector<f64>, usize) {
    if a.nrows() == 0 || a.ncols() == 0 {
        return (DVector::zeros(a.ncols()), 0);
    }
    // nalgebra's SVD panics on NaN: a non-finite system has no solution.
    if !(a.iter().all(|x| x.is_finite()) && r.iter().all(|x| x.is_finite())) {
        return (DVector::from_element(a.ncols(), f64::NAN), 0);
    }
    let svd = a.clone().svd(true, true);
    let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let eps = RANK_TOL * largest.max(1e-300);
    let rank = svd.singular_values.iter().filter(|&&s| s > eps).count();
    match svd.solve(r, eps) {
        Ok(x) => (x, rank),
        Err(_) => (DVector::zeros(a.ncols()), rank),
    }
}

/// `u̇` and `λ` of `M u̇ = −b + Jᵀλ + τ`, `J u̇ = γ`, and the rank of the
/// Schur complement; `None` if `M` is not positive definite.
pub fn accelerations(
    m: &DMatrix<f64>,
    force: &DVector<f64>,
    jacobian: &DMatrix<f64>,
    gamma: &DVector<f64>,
) -> Option<(DVector<f64>, DVector<f64>, usize)> {
    let chol = m.clone().cholesky()?;
    let free = chol.solve(force);
    if jacobian.nrows() == 0 {
        return Some((free, DVector::zeros(0), 0));
    }
    let minv_jt = chol.solve(&jacobian.transpose());
    let schur = jacobian * &minv_jt;
    let rhs = gamma - jacobian * &free;
    // Well-conditioned (the usual case): Cholesky. Its pivots bound the
    // eigenvalues' spread from below, so a pivot ratio above the cut means
    // the Schur complement is far from a rank drop and the weighted SVD
    // would give the same λ.
    if let Some(chol) = schur.clone().cholesky() {
        let d = chol.l_dirty().diagonal();
        let (lo, hi) = d.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
            (lo.min(x * x), hi.max(x * x))
        });
        if lo > FAST_PIVOT_RATIO * hi {
            let lambda = chol.solve(&rhs);
            let udot = free + minv_jt * &lambda;
            return Some((udot, lambda, jacobian.nrows()));
        }
    }
    let l = m.clone().cholesky()?.l();
    let (x, lambda, rank) = weighted_min_norm(&l, jacobian, &rhs, RANK_TOL)?;
    Some((free + x, lambda, rank))
}

/// The Schur complement's Cholesky factor is used when its smallest squared
/// pivot is above this fraction of the largest (singular-value ratio of
/// `J M^{-1/2}` above about 1e-2); nearer a rank drop, the weighted SVD.
pub(super) const FAST_PIVOT_RATIO: f64 = 1e-4;

/// Singular values of `J L⁻ᵀ` below this fraction of the largest are
/// round-off of exactly redundant equations and dropped.
const NOISE_TOL: f64 = 1e-13;

/// The mass-weighted minimum-norm solution of `J x = r`: `x` minimises
/// `xᵀ M x` (`M = L Lᵀ`, `l` the lower Cholesky factor), `x = M⁻¹ Jᵀ y`
/// with `y = (J M⁻¹ Jᵀ)⁺ r`; and the numerical rank.
///
/// It goes through the SVD `J L⁻ᵀ = U Σ Vᵀ`: `x = L⁻ᵀ V Σ⁺ Uᵀ r`, one
/// division by each `σ` (the Schur complement's eigendecomposition divides
/// by `σ²` and needs the cut-off at `σ ≈ 1e-5 σ₁`). The pseudo-inverse is
/// damped (Tikhonov) with `μ = RANK_TOL σ₁`: `σ⁺ = σ / (σ² + μ²)`, so `x`
/// is continuous through a rank drop (the four-bar's change point, where
/// `Uᵀ r` and `σ` vanish together and their ratio is the finite
/// acceleration that keeps the branch) and equal to the exact solution to
/// `(μ/σ)²` away from it; singular values at round-off (`NOISE_TOL σ₁`,
/// exactly redundant equations) are dropped, which gives the minimum-norm
/// `y` there. The rank counts `σ > μ`.
pub fn weighted_min_norm(
    l: &DMatrix<f64>,
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    damping: f64,
) -> Option<(DVector<f64>, DVector<f64>, usize)> {
    let (m, n) = j.shape();
    if m == 0 || n == 0 {
        return Some((DVector::zeros(n), DVector::zeros(m), 0));
    }
    let at = l.solve_lower_triangular(&j.transpose())?;
    let svd = at.transpose().svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let s = &svd.singular_values;
    let largest = s.iter().copied().fold(0.0, f64::max);
    if !(largest > 0.0 && largest.is_finite()) {
        return Some((DVector::zeros(n), DVector::zeros(m), 0));
    }
    let mu = damping.max(RANK_TOL) * largest;
    let mu4 = mu.powi(4);
    let mut w = DVector::zeros(n);
    let mut y = DVector::zeros(m);
    let mut rank = 0;
    for (k, &sk) in s.iter().enumerate() {
        if sk > RANK_TOL * largest {
            rank += 1;
        }
        if sk <= NOISE_TOL * largest {
            continue;
        }
        let c = u.column(k).dot(r);
        let s2 = sk * sk;
        let den = s2 * s2 + mu4;
        w += vt.row(k).transpose() * (c * sk * s2 / den);
        y += u.column(k) * (c * s2 / den);
    }
    let x = l.tr_solve_lower_triangular(&w)?;
    (x.iter().chain(y.iter()).all(|v| v.is_finite())).then_some((x, y, rank))
}

/// `min ½ xᵀMx − fᵀx` subject to `J x = r` by the augmented Lagrangian
/// iteration of [`Method::AugmentedLagrangian`]: `x` and `λ` (`M x = f +
/// Jᵀλ`), or `None` if `M + αJᵀJ` is not positive definite. With `f = 0`
/// it is the mass-orthogonal projection `x = M⁻¹Jᵀ(JM⁻¹Jᵀ)⁻¹r`. Each
/// iteration contracts the error along an eigenvector of `J M⁻¹ Jᵀ` with
/// eigenvalue `e` by `1/(1 + αe)`: at once where `J` is regular, and not
/// at all in a direction that a rank drop of `J` takes away (the four-bar's
/// change point), so `x` stays bounded and continuous through it.
///
/// [`Method::AugmentedLagrangian`]: super::Method::AugmentedLagrangian
pub fn al_solve(
    m: &DMatrix<f64>,
    f: &DVector<f64>,
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    penalty: f64,
    iterations: usize,
) -> Option<(DVector<f64>, DVector<f64>)> {
    al_iterate(m, f, j, r, penalty, iterations).map(|(x, lambda, _)| (x, lambda))
}

/// [`al_solve`], and whether `J x = r` was reached to round-off within
/// `iterations`.
fn al_iterate(
    m: &DMatrix<f64>,
    f: &DVector<f64>,
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    penalty: f64,
    iterations: usize,
) -> Option<(DVector<f64>, DVector<f64>, bool)> {
    let (nc, nu) = j.shape();
    let mut lambda = DVector::zeros(nc);
    if nc == 0 {
        return Some((m.clone().cholesky()?.solve(f), lambda, true));
    }
    let jtj = j.transpose() * j;
    let mmax = m.diagonal().iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let jmax = jtj.diagonal().iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let alpha = if jmax > 0.0 {
        penalty * mmax / jmax
    } else {
        0.0
    };
    let chol = (m + &jtj * alpha).cholesky()?;
    let scale = max_abs(r.iter()).max(f64::MIN_POSITIVE);
    let mut x = DVector::zeros(nu);
    let mut res = r.clone();
    for _ in 0..iterations.max(1) {
        // The step in residual form, `(M + αJᵀJ) δx = f + Jᵀ(λ + α(r −
        // J x)) − M x`: the same iterates as solving for `x` itself, but
        // the factor's rounding (relative `α‖JᵀJ‖/‖M‖ · ε`, 1e-11 at the
        // default penalty) falls on the correction, not on `x`; solved for
        // `x` directly it biased every acceleration along the motion and
        // set a floor under the error of a run that the tolerance could
        // not lower (tests/singular_loops.rs).
        let rhs = f + j.transpose() * (&lambda + &res * alpha) - m * &x;
        x += chol.solve(&rhs);
        res = r - j * &x;
        lambda += &res * alpha;
        let xs = max_abs(x.iter());
        if max_abs(res.iter()) <= 1e-15 * (scale + jmax.sqrt() * xs) {
            return Some((x, lambda, true));
        }
    }
    Some((x, lambda, false))
}

pub(super) fn max_abs<'a>(v: impl IntoIterator<Item = &'a f64>) -> f64 {
    v.into_iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// A choice of dependent speeds: `rows` of `J` solved for the speeds
/// `cols` (Wehage–Haug), with the pivot ratio it was chosen at.
#[derive(Clone, Debug, Default)]
pub(super) struct Partition {
    pub(super) rows: Vec<usize>,
    pub(super) cols: Vec<usize>,
    pub(super) quality: f64,
}

/// Gaussian elimination with complete pivoting on `a`: the pivot rows and
/// columns in order of elimination (the numerical rank many of them, pivots
/// below `1e-10` of the first dropped) and `min |pivot| / max |pivot|`.
pub(super) fn complete_pivoting(a: &DMatrix<f64>) -> Partition {
    let mut a = a.clone();
    let (m, n) = a.shape();
    let mut rows: Vec<usize> = (0..m).collect();
    let mut cols: Vec<usize> = (0..n).collect();
    let mut first = 0.0;
    let mut smallest = f64::INFINITY;
    let mut rank = 0;
    for k in 0..m.min(n) {
        let (mut pi, mut pj, mut best) = (k, k, 0.0);
        for i in k..m {
            for j in k..n {
                if a[(i, j)].abs() > best {
                    (pi, pj, best) = (i, j, a[(i, j)].abs());
                }
            }
        }
        if k == 0 {
            first = best;
        }
        if best <= 1e-10 * first || best == 0.0 {
            break;
        }
        a.swap_rows(k, pi);
        a.swap_columns(k, pj);
        rows.swap(k, pi);
        cols.swap(k, pj);
        for i in k + 1..m {
            let f = a[(i, k)] / a[(k, k)];
            for j in k..n {
                a[(i, j)] -= f * a[(k, j)];
            }
        }
        smallest = smallest.min(best);
        rank += 1;
    }
    rows.truncate(rank);
    cols.truncate(rank);
    Partition {
        rows,
        cols,
        quality: if rank == 0 { 1.0 } else { smallest / first },
    }
}

/// `min |pivot| / max |pivot|` of `J[rows, cols]` by partial pivoting.
pub(super) fn pivot_quality(j: &DMatrix<f64>, p: &Partition) -> f64 {
    let r = p.rows.len();
    let sub = DMatrix::from_fn(r, r, |a, b| j[(p.rows[a], p.cols[b])]);
    let lu = sub.lu();
    let d = lu.u().diagonal();
    let largest = max_abs(d.iter());
    let smallest = d.iter().fold(f64::INFINITY, |m, x| m.min(x.abs()));
    if r == 0 {
        1.0
    } else {
        smallest / largest.max(1e-300)
    }
}

/// [`al_solve`] where its iteration converges; where it does not within
/// `iterations` (near a rank drop of `J`, the only place: the error along
/// an eigenvector of `J M⁻¹ Jᵀ` with eigenvalue `e` contracts by
/// `1/(1 + αe)` per iteration, `e → 0` there), the damped mass-weighted
/// minimum-norm solve ([`weighted_min_norm`], `damping`) instead.
///
/// The truncated iteration is itself a regularisation of the vanishing
/// direction, with the filter `1 − (1 + ασ²)^{−k}` in place of Tikhonov's
/// `σ²/(σ² + μ²)`; its window is wide (`σ² ≲ 35/(kα)`, about 4e-3 σ₁ with
/// the defaults) and its edge steep, and it left the four-bar's crank with
/// an error of about 1e-8 rad that did not fall with the tolerance
/// (issue 16; no choice of penalty and iteration count from 20 to 1000
/// removed it). `None` if `M` (or `M + αJᵀJ`) is not positive definite.
pub(super) fn al_or_weighted(
    m: &DMatrix<f64>,
    f: &DVector<f64>,
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    (penalty, iterations): (f64, usize),
    damping: f64,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let (x, lambda, converged) = al_iterate(m, f, j, r, penalty, iterations)?;
    if converged {
        return Some((x, lambda));
    }
    let chol = m.clone().cholesky()?;
    let free = chol.solve(f);
    let rhs = r - j * &free;
    let (x, lambda, _) = weighted_min_norm(&chol.l(), j, &rhs, damping)?;
    Some((free + x, lambda))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_and_minimum_norm_multipliers_agree_and_redundancy_is_handled() {
        let m = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let force = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let j = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 0.0, 0.0, 1.0, -1.0]);
        let gamma = DVector::from_vec(vec![0.3, -0.7]);
        let (udot, lambda, rank) = accelerations(&m, &force, &j, &gamma).expect("solves");
        assert_eq!(rank, 2);
        // M u̇ = f + Jᵀλ and J u̇ = γ.
        assert!((&m * &udot - &force - j.transpose() * &lambda).norm() < 1e-13);
        assert!((&j * &udot - &gamma).norm() < 1e-13);
        // The same equations written twice (rank 2 of 3): the same motion,
        // and the multipliers split evenly (minimum norm).
        let j2 = DMatrix::from_row_slice(3, 3, &[1.0, 2.0, 0.0, 0.0, 1.0, -1.0, 1.0, 2.0, 0.0]);
        let g2 = DVector::from_vec(vec![0.3, -0.7, 0.3]);
        let (u2, l2, r2) = accelerations(&m, &force, &j2, &g2).expect("solves");
        assert_eq!(r2, 2);
        assert!((&u2 - &udot).norm() < 1e-12);
        assert!((l2[0] - l2[2]).abs() < 1e-12 && (l2[0] + l2[2] - lambda[0]).abs() < 1e-12);
    }

    #[test]
    fn augmented_lagrangian_is_exact_to_round_off_at_any_penalty() {
        // The KKT solution of min ½xᵀMx − fᵀx subject to Jx = r by the
        // Schur complement, against the augmented Lagrangian at penalties
        // that make M + αJᵀJ ill-conditioned (1e5 to 1e10 relative): the
        // residual form of the iteration keeps x to round-off (3e-13 at
        // 1e10), where solving for x itself lost a relative α·ε (4.6e-12
        // at 1e5, 6e-7 at 1e10). The multipliers, accumulated as α·(r −
        // Jx), carry α·ε: that is the method's own accuracy for λ.
        let m = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let f = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let j = DMatrix::from_row_slice(1, 3, &[1.0, 2.0, -0.5]);
        let r = DVector::from_vec(vec![0.3]);
        let (exact, lambda, _) = accelerations(&m, &f, &j, &r).expect("solves");
        for penalty in [1e5, 1e8, 1e10] {
            let (x, l) = al_solve(&m, &f, &j, &r, penalty, 20).expect("solves");
            let dx = (&x - &exact).amax() / exact.amax();
            let dl = (&l - &lambda).amax() / lambda.amax();
            assert!(dx < 1e-12, "α {penalty:e}: x off by {dx:e}");
            assert!(dl < penalty * 1e-14, "α {penalty:e}: λ off by {dl:e}");
        }
    }

    #[test]
    fn complete_pivoting_finds_the_rank_and_a_regular_block() {
        // Row 2 = row 0 + row 1: rank 2; the chosen 2×2 block is regular.
        let a = DMatrix::from_row_slice(
            3,
            4,
            &[1.0, 0.0, 2.0, 0.0, 0.0, 3.0, 0.0, 1.0, 1.0, 3.0, 2.0, 1.0],
        );
        let p = complete_pivoting(&a);
        assert_eq!((p.rows.len(), p.cols.len()), (2, 2));
        let block = DMatrix::from_fn(2, 2, |i, k| a[(p.rows[i], p.cols[k])]);
        assert!(block.determinant().abs() > 1e-6, "{p:?}");
        assert!(pivot_quality(&a, &p) > 0.0 && p.quality > 0.0);
    }
}
