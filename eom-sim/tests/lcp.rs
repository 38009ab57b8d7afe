//! The exact linear complementarity solver of the impact map
//! (`eom_sim::run::lcp`): `ξ = A x + b`, `x ≥ 0`, `ξ ≥ 0`, `xᵀ ξ = 0`,
//! checked on hand-solved cases and, for random symmetric positive definite
//! `A` (the impact problem's `W M⁻¹ Wᵀ`), by the three conditions; for such
//! `A` the solution is unique, so it must also minimise `½ xᵀ A x + bᵀ x`
//! over `x ≥ 0` (checked against projected Gauss–Seidel).

use eom_sim::constrained::{DMatrix, DVector};
use eom_sim::run::lcp;

fn conditions(a: &DMatrix<f64>, b: &DVector<f64>, x: &DVector<f64>) {
    let xi = a * x + b;
    let scale = 1.0 + b.amax();
    for i in 0..b.len() {
        assert!(x[i] >= 0.0, "x[{i}] = {}", x[i]);
        assert!(xi[i] >= -1e-9 * scale, "ξ[{i}] = {}", xi[i]);
        assert!((x[i] * xi[i]).abs() < 1e-9 * scale * scale, "x ξ [{i}]");
    }
}

#[test]
fn hand_solved_cases() {
    // Newton's cradle, e = 1: A = [[2, −1], [−1, 2]], b = (−2v, 0).
    let v = 1.5;
    let a = DMatrix::from_row_slice(2, 2, &[2.0, -1.0, -1.0, 2.0]);
    let x = lcp(&a, &DVector::from_vec(vec![-2.0 * v, 0.0])).expect("solvable");
    assert!((x[0] - 4.0 * v / 3.0).abs() < 1e-14 && (x[1] - 2.0 * v / 3.0).abs() < 1e-14);
    // Separating contacts carry nothing.
    let x = lcp(&a, &DVector::from_vec(vec![1.0, 2.0])).expect("solvable");
    assert_eq!(x.as_slice(), &[0.0, 0.0]);
    // The first contact closes, the second separates: x = (1, 0),
    // ξ₂ = −1 · 1 + 3 = 2 > 0.
    let x = lcp(&a, &DVector::from_vec(vec![-2.0, 3.0])).expect("solvable");
    assert!((x[0] - 1.0).abs() < 1e-14 && x[1] == 0.0, "{x}");
    // Redundant contacts (two equal rows): a singular A, solved by one.
    let a = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
    let b = DVector::from_vec(vec![-1.0, -1.0]);
    let x = lcp(&a, &b).expect("solvable");
    conditions(&a, &b, &x);
    // Infeasible: A = 0 and b < 0.
    assert!(lcp(&DMatrix::zeros(1, 1), &DVector::from_vec(vec![-1.0])).is_none());
    // Too many unknowns for the enumeration: refused, not a hang.
    let n = eom_sim::run::MAX_LCP + 1;
    assert!(lcp(&DMatrix::identity(n, n), &DVector::from_element(n, -1.0)).is_none());
}

#[test]
fn random_positive_definite_problems() {
    let mut seed = 0x2600_u64;
    let mut r = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % 2_000_001) as f64 / 1_000_000.0 - 1.0
    };
    for n in 1..=7 {
        for _ in 0..20 {
            let l = DMatrix::from_fn(n, n + 2, |_, _| r());
            let a = &l * l.transpose() + DMatrix::identity(n, n) * 0.1;
            let b = DVector::from_fn(n, |_, _| r());
            let x = lcp(&a, &b).expect("a P-matrix problem has a solution");
            conditions(&a, &b, &x);
            // Projected Gauss–Seidel converges to the same unique solution.
            let mut y = DVector::zeros(n);
            for _ in 0..20_000 {
                for i in 0..n {
                    let s: f64 = (0..n).filter(|&j| j != i).map(|j| a[(i, j)] * y[j]).sum();
                    y[i] = (-(b[i] + s) / a[(i, i)]).max(0.0);
                }
            }
            assert!((&x - &y).amax() < 1e-8, "n = {n}: {x} vs {y}");
        }
    }
}
