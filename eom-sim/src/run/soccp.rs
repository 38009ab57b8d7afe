//! The frictional impact as a second-order-cone complementarity problem
//! (issue #26; Alart and Curnier 1991, De Saxcé and Feng 1998, Acary and
//! Brogliato ch. 12).
//!
//! On the Delassus operator `G = W M⁻¹ Wᵀ` of the closed rows (normal and
//! tangential, the loop constraints held), with `ξ = G z + b`, per contact
//! `(Λ, Λ_t)` of `z` and `(ξ_n, ξ_t)` of `ξ` (for an impact
//! `ξ_n = ġ⁺ + e ġ⁻`, `ξ_t = v_t⁺`), Newton–Coulomb is
//!
//! - `Λ ≥ 0`, `ξ_n ≥ 0`, `Λ ξ_n = 0` (Newton's law, or separation);
//! - `‖Λ_t‖ ≤ μ Λ`; `ξ_t = 0` (stick) or `Λ_t = −μ Λ ξ_t/‖ξ_t‖` (slide).
//!
//! Both are the zeros of Alart–Curnier's augmented-Lagrangian function,
//! per contact with `ρ > 0`,
//!
//! `Φ_n = Λ − max(0, Λ − ρ ξ_n)`,
//! `Φ_t = Λ_t − P_{B(μ max(0, Λ − ρ ξ_n))}(Λ_t − ρ ξ_t)`
//!
//! (`P_B` the projection onto the disk of that radius), which is
//! piecewise smooth: [`solve`] runs a damped semismooth Newton method on
//! it, an element of its generalized Jacobian per step and an Armijo line
//! search on `½ ‖Φ‖²` (where the Newton direction does not descend, as on
//! the singular Jacobians of redundant blocks, its least-squares one,
//! then a Levenberg–Marquardt one), and falls back on De Saxcé's projected fixed point
//! `z ← P_K(z − ρ (ξ_n + μ ‖ξ_t‖, ξ_t))` (K the Coulomb cones), which it
//! then polishes with Newton again. Unlike the iteration of the sliding
//! direction in [`super::impulse::impact`], a slide that stops exactly on
//! the cone (`ξ_t = 0`, `‖Λ_t‖ = μ Λ`) is a point like any other here. An
//! answer is returned only if [`check`] accepts it.

use super::redundant::{Cone, project_cones};
use crate::constrained::{DMatrix, DVector};

/// Newton steps per start.
const NEWTON_STEPS: usize = 200;

/// Sweeps of the projected fixed point before it hands over to Newton.
const FIXED_POINT_SWEEPS: usize = 20_000;

/// Relative tolerance of [`check`].
pub(super) const TOL: f64 = 1e-9;

/// The per-contact `ρ` of the Alart–Curnier function: the inverse of the
/// largest diagonal entry of the contact's block of `G` (1 if none).
fn rhos(g: &DMatrix<f64>, cones: &[Cone]) -> Vec<f64> {
    cones
        .iter()
        .map(|c| {
            let mut d = g[(c.normal, c.normal)];
            if let Some(([a, b], _)) = c.tangential {
                d = d.max(g[(a, a)]).max(g[(b, b)]);
            }
            if d > 0.0 && d.is_finite() {
                1.0 / d
            } else {
                1.0
            }
        })
        .collect()
}

/// The Alart–Curnier function `Φ(z)` (see the module docs) and, with
/// `jacobian`, one element of its generalized Jacobian.
fn alart_curnier(
    g: &DMatrix<f64>,
    b: &DVector<f64>,
    cones: &[Cone],
    rho: &[f64],
    z: &DVector<f64>,
    jacobian: bool,
) -> (DVector<f64>, Option<DMatrix<f64>>) {
    let n = z.len();
    let xi = g * z + b;
    let mut phi = DVector::zeros(n);
    let mut jac = jacobian.then(|| DMatrix::zeros(n, n));
    for (c, &r) in cones.iter().zip(rho) {
        let k = c.normal;
        let y = z[k] - r * xi[k];
        // Φ_n and the radius μ max(0, y) of the disk.
        let pressing = y > 0.0;
        phi[k] = z[k] - y.max(0.0);
        if let Some(jm) = jac.as_mut() {
            if pressing {
                for col in 0..n {
                    jm[(k, col)] = r * g[(k, col)];
                }
            } else {
                jm[(k, k)] = 1.0;
            }
        }
        let Some(([a, bb], mu)) = c.tangential else {
            continue;
        };
        let radius = mu * y.max(0.0);
        let yt = [z[a] - r * xi[a], z[bb] - r * xi[bb]];
        let ny = yt[0].hypot(yt[1]);
        let inside = ny <= radius;
        let p = if inside {
            yt
        } else {
            [radius * yt[0] / ny, radius * yt[1] / ny]
        };
        phi[a] = z[a] - p[0];
        phi[bb] = z[bb] - p[1];
        let Some(jm) = jac.as_mut() else {
            continue;
        };
        // d y_t = E_t − ρ G_t; d radius = μ (e_n − ρ G_n) while pressing.
        let dyt = |row: usize, col: usize| f64::from(u8::from(col == row)) - r * g[(row, col)];
        let drad = |col: usize| {
            if pressing {
                mu * (f64::from(u8::from(col == k)) - r * g[(k, col)])
            } else {
                0.0
            }
        };
        let rows = [a, bb];
        for (i, &row) in rows.iter().enumerate() {
            for col in 0..n {
                let dp = if inside {
                    dyt(row, col)
                } else if ny > 0.0 {
                    // P = R ŷ: dP = ŷ dR + (R/‖y‖)(I − ŷ ŷᵀ) dy.
                    let h = [yt[0] / ny, yt[1] / ny];
                    let proj: f64 = (0..2)
                        .map(|m| (f64::from(u8::from(i == m)) - h[i] * h[m]) * dyt(rows[m], col))
                        .sum();
                    h[i] * drad(col) + radius / ny * proj
                } else {
                    0.0
                };
                jm[(row, col)] = f64::from(u8::from(col == row)) - dp;
            }
        }
    }
    (phi, jac)
}

/// `½ ‖Φ(z)‖²`.
fn merit(g: &DMatrix<f64>, b: &DVector<f64>, cones: &[Cone], rho: &[f64], z: &DVector<f64>) -> f64 {
    0.5 * alart_curnier(g, b, cones, rho, z, false).0.norm_squared()
}

/// The damped semismooth Newton method from `z`: `Some` of the point it
/// stops at (converged or not; the caller checks).
fn newton(
    g: &DMatrix<f64>,
    b: &DVector<f64>,
    cones: &[Cone],
    rho: &[f64],
    mut z: DVector<f64>,
) -> DVector<f64> {
    let floor = (1e-15 * b.amax()).powi(2);
    for _ in 0..NEWTON_STEPS {
        // (nalgebra's SVD panics on NaN: a non-finite point stops here)
        if !z.iter().all(|v| v.is_finite()) {
            break;
        }
        let (phi, jac) = alart_curnier(g, b, cones, rho, &z, true);
        if !phi.iter().all(|v| v.is_finite()) {
            break;
        }
        let theta = 0.5 * phi.norm_squared();
        if theta <= floor {
            break;
        }
        let Some(jac) = jac.filter(|j| j.iter().all(|v| v.is_finite())) else {
            break;
        };
        // Directions, each tried with an Armijo line search on ½‖Φ‖²
        // (slope `Φᵀ J d`): Newton's (LU), its least-squares solution (a
        // singular Jacobian: redundant rows), and Levenberg–Marquardt's
        // `(JᵀJ + λ I) d = −Jᵀ Φ`, a descent direction wherever `JᵀΦ ≠ 0`.
        let rhs = -&phi;
        let nz = z.len();
        let jtj = jac.transpose() * &jac;
        let lambda = 1e-8 * jtj.diagonal().amax().max(f64::MIN_POSITIVE);
        let newton_dir = jac.clone().lu().solve(&rhs);
        let eps = 1e-13 * jac.amax().max(f64::MIN_POSITIVE);
        let lsq = || jac.clone().svd(true, true).solve(&rhs, eps).ok();
        let lm = || {
            let a = &jtj + DMatrix::from_diagonal_element(nz, nz, lambda);
            a.cholesky().map(|c| c.solve(&(jac.transpose() * &rhs)))
        };
        let mut moved = false;
        for d in [newton_dir, lsq(), lm()].into_iter().flatten() {
            if !d.iter().all(|v| v.is_finite()) {
                continue;
            }
            let slope = phi.dot(&(&jac * &d));
            if slope >= 0.0 {
                continue;
            }
            let mut t = 1.0;
            while t > 1e-12 {
                let trial = &z + t * &d;
                if merit(g, b, cones, rho, &trial) <= theta + 1e-4 * t * slope {
                    z = trial;
                    moved = true;
                    break;
                }
                t *= 0.5;
            }
            if moved {
                break;
            }
        }
        if !moved {
            break;
        }
    }
    z
}

/// De Saxcé's projected fixed point, contact by contact (Gauss–Seidel):
/// `z_c ← P_K(z_c − ρ_c (ξ_n + μ ‖ξ_t‖, ξ_t))`, from `z`.
fn fixed_point(
    g: &DMatrix<f64>,
    b: &DVector<f64>,
    cones: &[Cone],
    rho: &[f64],
    mut z: DVector<f64>,
) -> DVector<f64> {
    let tol = 1e-15 * b.amax().max(f64::MIN_POSITIVE);
    for _ in 0..FIXED_POINT_SWEEPS {
        let mut moved: f64 = 0.0;
        for (c, &r) in cones.iter().zip(rho) {
            let xi = |row: usize, z: &DVector<f64>| g.row(row).dot(&z.transpose()) + b[row];
            let k = c.normal;
            let mut local = DVector::zeros(z.len());
            local[k] = z[k] - r * xi(k, &z);
            let one = [Cone {
                normal: k,
                tangential: c.tangential,
            }];
            if let Some(([a, bb], mu)) = c.tangential {
                let xt = [xi(a, &z), xi(bb, &z)];
                local[k] -= r * mu * xt[0].hypot(xt[1]);
                local[a] = z[a] - r * xt[0];
                local[bb] = z[bb] - r * xt[1];
            }
            project_cones(&mut local, &one, true);
            let mut rows = vec![k];
            if let Some(([a, bb], _)) = c.tangential {
                rows.extend([a, bb]);
            }
            for row in rows {
                moved = moved.max((local[row] - z[row]).abs());
                z[row] = local[row];
            }
        }
        if !z.iter().all(|v| v.is_finite()) {
            break;
        }
        if moved <= tol * (1.0 + z.amax()) {
            break;
        }
    }
    z
}

/// Solves the SOCCP `(G, b)` on `cones` (every unknown of `z` belongs to
/// one): semismooth Newton on the Alart–Curnier function from the origin
/// and from each of `starts`, then De Saxcé's fixed point polished by
/// Newton; the first point that [`check`] accepts, else `None`.
pub(super) fn solve(
    g: &DMatrix<f64>,
    b: &DVector<f64>,
    cones: &[Cone],
    starts: &[DVector<f64>],
) -> Option<DVector<f64>> {
    let n = b.len();
    if g.nrows() != n || g.ncols() != n || !g.iter().chain(b.iter()).all(|v| v.is_finite()) {
        return None;
    }
    let rho = rhos(g, cones);
    let zero = DVector::zeros(n);
    for start in std::iter::once(&zero).chain(starts) {
        if start.len() != n {
            continue;
        }
        let z = newton(g, b, cones, &rho, start.clone());
        if check(g, b, cones, &z).is_ok() {
            return Some(z);
        }
    }
    let z = fixed_point(g, b, cones, &rho, zero);
    if check(g, b, cones, &z).is_ok() {
        return Some(z);
    }
    let z = newton(g, b, cones, &rho, z);
    check(g, b, cones, &z).is_ok().then_some(z)
}

/// Checks the Newton–Coulomb conditions of `z` on `(G, b)` (module docs),
/// impulses to `TOL · max |z|` and speeds to `TOL · max(|b|, |G z|)`:
/// `Err` names the first one violated.
pub(super) fn check(
    g: &DMatrix<f64>,
    b: &DVector<f64>,
    cones: &[Cone],
    z: &DVector<f64>,
) -> Result<(), String> {
    if !z.iter().all(|v| v.is_finite()) {
        return Err("an impulse is not finite".into());
    }
    let xi = g * z + b;
    let tz = TOL * z.amax().max(f64::MIN_POSITIVE);
    let tv = TOL * b.amax().max((g * z).amax()).max(f64::MIN_POSITIVE);
    for (i, c) in cones.iter().enumerate() {
        let (l, v) = (z[c.normal], xi[c.normal]);
        if l < -tz {
            return Err(format!("contact {i}: Λ = {l} < 0"));
        }
        if v < -tv {
            return Err(format!("contact {i}: ξ_n = {v} < 0 (penetrating)"));
        }
        if l > tz && v.abs() > tv {
            return Err(format!("contact {i}: Λ = {l} > 0 with ξ_n = {v} ≠ 0"));
        }
        let Some(([a, bb], mu)) = c.tangential else {
            continue;
        };
        let lt = [z[a], z[bb]];
        let vt = [xi[a], xi[bb]];
        let (nl, nv) = (lt[0].hypot(lt[1]), vt[0].hypot(vt[1]));
        if nl > mu * l.max(0.0) + tz {
            return Err(format!("contact {i}: ‖Λ_t‖ = {nl} > μ Λ = {}", mu * l));
        }
        if nv > tv {
            // Sliding: Λ_t = −μ Λ v_t/‖v_t‖.
            let off = (0..2)
                .map(|m| (lt[m] + mu * l.max(0.0) * vt[m] / nv).abs())
                .fold(0.0, f64::max);
            if off > tz {
                return Err(format!(
                    "contact {i}: slides at v_t = {vt:?} with Λ_t = {lt:?}, not −μ Λ v̂_t"
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64: a seeded generator for the random problems.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut x = self.0;
            x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            x ^= x >> 31;
            (x >> 11) as f64 / (1u64 << 53) as f64
        }
        fn signed(&mut self) -> f64 {
            2.0 * self.next() - 1.0
        }
    }

    fn cones(nc: usize, mu: &[f64]) -> Vec<Cone> {
        (0..nc)
            .map(|k| Cone {
                normal: k,
                tangential: Some(([nc + 2 * k, nc + 2 * k + 1], mu[k])),
            })
            .collect()
    }

    /// Random SOCCPs of 1 to 3 contacts, `G = W M⁻¹ Wᵀ` with `W` random on
    /// 6 speeds (positive definite for one and two contacts, singular for
    /// three: nine rows on six speeds), `b` of random speeds before that
    /// close every normal, `e` random in [0, 1) (one per problem; with an
    /// `e` per row one singular problem of these had no answer found,
    /// existence is not guaranteed there). All 300 are solved, and every
    /// answer satisfies `Λ ≥ 0 ⟂ ξ_n ≥ 0`, `‖Λ_t‖ ≤ μ Λ`, and stick
    /// (`ξ_t = 0`) or slide opposite to the slip (`Λ_t = −μ Λ ξ̂_t`),
    /// verified here independently of [`check`].
    #[test]
    fn random_soccps_satisfy_newton_coulomb() {
        let mut rng = Rng(26);
        let mut solved = [0; 3];
        for case in 0..300 {
            let nc = 1 + case % 3;
            let n = 3 * nc;
            let mut w = DMatrix::from_fn(n, 6, |_, _| rng.signed());
            let mdiag: Vec<f64> = (0..6).map(|_| 0.5 + rng.next()).collect();
            let minv = DMatrix::from_fn(6, 6, |i, j| if i == j { 1.0 / mdiag[i] } else { 0.0 });
            let mu: Vec<f64> = (0..nc).map(|_| 0.05 + rng.next()).collect();
            // The speeds before, closing every normal (a normal row that
            // would open is turned round), and `b = ((1 + e) W_n u⁻, W_t u⁻)`.
            let u = DVector::from_fn(6, |_, _| rng.signed());
            for k in 0..nc {
                if w.row(k).dot(&u.transpose()) > 0.0 {
                    w.row_mut(k).neg_mut();
                }
            }
            let g = &w * minv * w.transpose();
            let wu = &w * &u;
            let e = rng.next();
            let b = DVector::from_fn(n, |i, _| if i < nc { (1.0 + e) * wu[i] } else { wu[i] });
            let cs = cones(nc, &mu);
            let Some(z) = solve(&g, &b, &cs, &[]) else {
                panic!("case {case}: no solution for G = {g}, b = {b}, μ = {mu:?}");
            };
            let xi = &g * &z + &b;
            let (tz, tv) = (1e-8 * z.amax(), 1e-8 * b.amax().max((&g * &z).amax()));
            for (k, c) in cs.iter().enumerate() {
                let (l, v) = (z[c.normal], xi[c.normal]);
                assert!(
                    l >= -tz && v >= -tv,
                    "case {case} contact {k}: Λ = {l}, ξ_n = {v}"
                );
                assert!(l.min(v / tv * tz) <= tz, "case {case}: Λ ξ_n ≠ 0: {l}, {v}");
                let ([a, bb], m) = c.tangential.expect("rough");
                let (lt, vt) = ([z[a], z[bb]], [xi[a], xi[bb]]);
                let (nl, nv) = (lt[0].hypot(lt[1]), vt[0].hypot(vt[1]));
                assert!(
                    nl <= m * l + tz,
                    "case {case}: ‖Λ_t‖ = {nl} > μ Λ = {}",
                    m * l
                );
                if nv > tv {
                    assert!(
                        (nl - m * l).abs() <= tz
                            && lt[0] * vt[0] + lt[1] * vt[1] <= -(nl * nv) * (1.0 - 1e-6) + tz * nv,
                        "case {case}: slides with Λ_t = {lt:?}, v_t = {vt:?}"
                    );
                }
            }
            solved[nc - 1] += 1;
        }
        eprintln!("solved of 100 each, 1, 2, 3 contacts: {solved:?}");
        assert_eq!(solved, [100, 100, 100]);
    }

    /// A point mass (`G = I/m` on its normal and two tangents) striking
    /// with `b = ((1 + e) v_n⁻, v_t⁻)`, `v_n⁻ < 0`, built to stop exactly on
    /// the cone: `v_t⁻ = μ (1 + e) |v_n⁻|` gives `Λ = m (1 + e)|v_n⁻|`,
    /// `Λ_t = −μ Λ` along the slip and `v_t⁺ = 0`, both stick and slide
    /// at once — the point a direction iteration cannot represent. Then
    /// both sides of that threshold: slide (`v_t⁺ = v_t⁻ − μ (1+e)|v_n⁻|`)
    /// and stick (`Λ_t = −m v_t⁻`).
    #[test]
    fn a_slide_that_stops_exactly_on_the_cone() {
        let (m, e, mu, vn) = (2.0, 0.5, 0.4, -1.5);
        let g = DMatrix::from_diagonal_element(3, 3, 1.0 / m);
        let cs = cones(1, &[mu]);
        let dir = [0.6, -0.8];
        let edge = mu * (1.0 + e) * -vn;
        for (vt, want_vt) in [(edge, 0.0), (1.5 * edge, 0.5 * edge), (0.5 * edge, 0.0)] {
            let b = DVector::from_vec(vec![(1.0 + e) * vn, vt * dir[0], vt * dir[1]]);
            let z = solve(&g, &b, &cs, &[]).expect("solvable");
            let ln = m * (1.0 + e) * -vn;
            let xi = &g * &z + &b;
            assert!((z[0] - ln).abs() < 1e-12 * ln, "Λ = {}, want {ln}", z[0]);
            let lt_want = if vt >= edge { -mu * ln } else { -m * vt };
            for a in 0..2 {
                assert!(
                    (z[1 + a] - lt_want * dir[a]).abs() < 1e-12 * ln,
                    "v_t⁻ {vt}: Λ_t = {:?}, want {lt_want} along the slip",
                    [z[1], z[2]]
                );
                assert!(
                    (xi[1 + a] - want_vt * dir[a]).abs() < 1e-12,
                    "v_t⁻ {vt}: v_t⁺ = {:?}, want {want_vt} along the slip",
                    [xi[1], xi[2]]
                );
            }
            assert!(xi[0].abs() < 1e-12, "ġ⁺ = −e ġ⁻: {}", xi[0]);
        }
    }
}
