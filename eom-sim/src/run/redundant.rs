//! The impulses of a redundant contact block (issue #26; Pfeiffer and
//! Glocker, *Multibody Dynamics with Unilateral Contacts*, ch. 7).
//!
//! A box landing flat on four corners has four normal and eight tangential
//! rows on six speeds: the block `G = W M⁻¹ Wᵀ` of a contact mode (which
//! rows are active, sticking, sliding) is singular. Its equations
//! `G z = −b` are consistent, the speeds after (`Δu = M⁻¹ Wᵀ z`) are
//! unique, but the impulses `z` are not: they form the affine set
//! `z₀ + N y`, `z₀` the minimum-norm solution, `N` an orthonormal basis of
//! the block's null space. The mode is feasible when SOME point of that set
//! satisfies the signs and the cones — per active row `Λ ≥ 0`, and with
//! sticking friction `‖Λ_t‖ ≤ μ Λ`. Of the feasible impulses we report the
//! one of minimum norm (a choice: the physics does not fix it; it spreads
//! the load evenly over symmetric contacts), the projection of the origin
//! onto the intersection of the affine set and the cones. Where the set
//! is a line (a null space of dimension one) it is found in closed form
//! ([`on_a_line`]: each cone holds the line on an interval); otherwise by
//! Dykstra's alternating projections (Boyle and Dykstra 1986; the affine
//! set needs no correction term): both projections are closed-form, the
//! cone's per contact (the second-order cone `‖v‖ ≤ μ x`).

use crate::constrained::{DMatrix, DVector};

/// Alternating projections before a block is declared infeasible.
const MAX_ITER: usize = 20_000;

/// Every this many projections the gap between the two sets is compared
/// with the one before: an empty intersection shows as a gap that no
/// longer shrinks (by 1 %), away from zero.
const STALL_EVERY: usize = 100;

/// The unknowns of one active contact row in the block: its normal
/// impulse's position and, if it sticks, its two tangential ones' and `μ`.
pub(super) struct Cone {
    pub normal: usize,
    pub tangential: Option<([usize; 2], f64)>,
}

/// Projects `z` onto the cones (`with_friction`) or only the signs
/// (`Λ ≥ 0`, tangential impulses free) of `cones`, in place.
pub(super) fn project_cones(z: &mut DVector<f64>, cones: &[Cone], with_friction: bool) {
    for c in cones {
        let x = z[c.normal];
        match c.tangential {
            Some(([a, b], mu)) if with_friction => {
                // The second-order cone K = {‖v‖ ≤ μ x}; its polar is
                // {μ ‖v‖ ≤ −x}; between them onto the ray (1, μ v/‖v‖).
                let nv = z[a].hypot(z[b]);
                if nv <= mu * x {
                    continue;
                }
                if mu * nv <= -x {
                    z[c.normal] = 0.0;
                    z[a] = 0.0;
                    z[b] = 0.0;
                    continue;
                }
                let s = (x + mu * nv) / (1.0 + mu * mu);
                z[c.normal] = s;
                z[a] *= mu * s / nv;
                z[b] *= mu * s / nv;
            }
            _ => z[c.normal] = x.max(0.0),
        }
    }
}

/// Whether `z` satisfies the signs (and the cones: `with_friction`) of
/// `cones` up to the runtime's tolerances (`Λ ≥ −10⁻¹⁰ max |z|`,
/// `‖Λ_t‖ ≤ μ Λ (1 + 10⁻⁹)`).
fn inside(z: &DVector<f64>, cones: &[Cone], with_friction: bool) -> bool {
    let big = z.amax();
    cones.iter().all(|c| {
        let x = z[c.normal];
        x >= -1e-10 * big
            && match c.tangential {
                Some(([a, b], mu)) if with_friction => z[a].hypot(z[b]) <= mu * x * (1.0 + 1e-9),
                _ => true,
            }
    })
}

/// The impulse of minimum norm in `{z0 + N y} ∩ K` (`null` = `N`, with
/// orthonormal columns; `z0` the minimum-norm solution, orthogonal to
/// them), `K` the cones of `cones` (`with_friction`) or their signs:
/// `(z_K, z_A)`, the point in `K` (the impulses to report) and its
/// projection on the affine set (the one whose speeds to take), within
/// `10⁻¹²` of each other relative to `z0`; `None` if the intersection is
/// empty. A one-dimensional null space (the commonest: a box on four
/// corners, one of them free of friction's rows) is solved in closed
/// form by [`on_a_line`]; a wider one by Dykstra's projections
/// ([`dykstra`]).
pub(super) fn min_norm_feasible(
    z0: &DVector<f64>,
    null: &DMatrix<f64>,
    cones: &[Cone],
    with_friction: bool,
) -> Option<(DVector<f64>, DVector<f64>)> {
    if inside(z0, cones, with_friction) {
        let mut z = z0.clone();
        for c in cones {
            z[c.normal] = z[c.normal].max(0.0);
        }
        return Some((z, z0.clone()));
    }
    if null.ncols() == 1 {
        on_a_line(z0, null, cones, with_friction)
    } else {
        dykstra(z0, null, cones, with_friction)
    }
}

/// `t` with `lo ≤ t ≤ hi` for the points `z0 + t n` of a line that lie
/// in one cone (`normal` row `x`, tangential rows `v`, friction `mu`) or
/// its sign (`mu = None`), each widened by `slack` (`x ≥ −slack`,
/// `‖v‖ ≤ μ x + slack`): the intersection of a line with a convex set is
/// an interval. `None` if it is empty.
fn interval(x: [f64; 2], v: [[f64; 2]; 2], mu: Option<f64>, slack: f64) -> Option<[f64; 2]> {
    // x0 + t xn ≥ −slack.
    let half_line = |x0: f64, xn: f64| -> Option<[f64; 2]> {
        if xn == 0.0 {
            (x0 >= 0.0).then_some([f64::NEG_INFINITY, f64::INFINITY])
        } else if xn > 0.0 {
            Some([-x0 / xn, f64::INFINITY])
        } else {
            Some([f64::NEG_INFINITY, -x0 / xn])
        }
    };
    let Some(mu) = mu else {
        return half_line(x[0] + slack, x[1]);
    };
    // ‖v0 + t vn‖ ≤ μ (x0 + t xn) + slack, i.e. in the cone shifted to
    // the apex −slack/μ: y = x + slack/μ ≥ 0 and q(t) = μ² y² − ‖v‖² ≥ 0.
    let y = [x[0] + slack / mu, x[1]];
    let on = half_line(y[0], y[1])?;
    let (m2, [v0, vn]) = (mu * mu, v);
    let a = m2 * y[1] * y[1] - vn[0] * vn[0] - vn[1] * vn[1];
    let b = 2.0 * (m2 * y[0] * y[1] - v0[0] * vn[0] - v0[1] * vn[1]);
    let c = m2 * y[0] * y[0] - v0[0] * v0[0] - v0[1] * v0[1];
    let big = m2 * y[1] * y[1] + vn[0] * vn[0] + vn[1] * vn[1];
    // Where q ≥ 0 the line is in the cone or in its mirror (y < 0); the
    // cone's part is the piece on `on`'s side (q > 0 never changes sides:
    // y = 0 makes q = −‖v‖² ≤ 0).
    let quad = if a.abs() <= 1e-14 * big {
        // q linear: a half-line (or all or nothing).
        if b == 0.0 {
            if c < 0.0 {
                return None;
            }
            [f64::NEG_INFINITY, f64::INFINITY]
        } else if b > 0.0 {
            [-c / b, f64::INFINITY]
        } else {
            [f64::NEG_INFINITY, -c / b]
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            // q keeps the sign of a: everywhere inside (a > 0), or nowhere.
            if a < 0.0 {
                return None;
            }
            [f64::NEG_INFINITY, f64::INFINITY]
        } else {
            let h = -0.5 * (b + b.signum() * disc.sqrt());
            let (r1, r2) = if h == 0.0 { (0.0, 0.0) } else { (h / a, c / h) };
            let (r1, r2) = (r1.min(r2), r1.max(r2));
            if a < 0.0 {
                [r1, r2]
            } else if y[1] > 0.0 {
                // a > 0 needs μ² y_n² > ‖v_n‖², so y_n ≠ 0: the cone is
                // the piece where y grows, the upper one ...
                [r2, f64::INFINITY]
            } else {
                // ... or, y falling, the lower one.
                [f64::NEG_INFINITY, r1]
            }
        }
    };
    let (lo, hi) = (on[0].max(quad[0]), on[1].min(quad[1]));
    (lo <= hi).then_some([lo, hi])
}

/// [`min_norm_feasible`] on a line `z0 + t n` (`null` one unit column
/// `n ⊥ z0`), exactly: each cone holds the line on an interval of `t`
/// ([`interval`]), and of their intersection the `t` of least `|t|`
/// gives the least `‖z‖² = ‖z0‖² + t²`. The cones are widened by
/// `10⁻¹²` of `z0`, the tolerance [`dykstra`] closes its gap to, so a
/// line that touches a cone's boundary (a corner with no load, a row on
/// the edge of sticking) is found feasible as it is by the projections;
/// the point found is then projected onto the cones themselves.
fn on_a_line(
    z0: &DVector<f64>,
    null: &DMatrix<f64>,
    cones: &[Cone],
    with_friction: bool,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let n = null.column(0);
    let slack = 1e-12 * z0.amax().max(f64::MIN_POSITIVE);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for c in cones {
        let x = [z0[c.normal], n[c.normal]];
        let [l, h] = match c.tangential {
            Some(([p, q], mu)) if with_friction => {
                interval(x, [[z0[p], z0[q]], [n[p], n[q]]], Some(mu), slack)?
            }
            _ => interval(x, [[0.0; 2]; 2], None, slack)?,
        };
        (lo, hi) = (lo.max(l), hi.min(h));
        if lo > hi || lo.is_nan() || hi.is_nan() {
            return None;
        }
    }
    let t = 0f64.clamp(lo, hi);
    let mut zk = z0 + n * t;
    project_cones(&mut zk, cones, with_friction);
    if !zk.iter().all(|v| v.is_finite()) {
        return None;
    }
    let za = z0 + n * (n.dot(&(&zk - z0)));
    Some((zk, za))
}

/// [`min_norm_feasible`] for a null space of any width, by Dykstra's
/// alternating projections from the origin (`None` when the gap stalls,
/// see [`STALL_EVERY`], or is not closed within [`MAX_ITER`]
/// projections).
fn dykstra(
    z0: &DVector<f64>,
    null: &DMatrix<f64>,
    cones: &[Cone],
    with_friction: bool,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let affine = |z: &DVector<f64>| z0 + null * (null.transpose() * (z - z0));
    let tol = 1e-12 * z0.amax().max(f64::MIN_POSITIVE);
    // Dykstra from the origin: y = P_A(x), x' = P_K(y + q), q' = y + q − x'.
    let mut x = DVector::zeros(z0.len());
    let mut q = DVector::zeros(z0.len());
    let mut last = f64::INFINITY;
    for it in 1..=MAX_ITER {
        let y = affine(&x);
        let mut next = &y + &q;
        project_cones(&mut next, cones, with_friction);
        q += &y - &next;
        let (gap, moved) = ((&next - &y).amax(), (&next - &x).amax());
        x = next;
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        if gap <= tol && moved <= tol {
            let y = affine(&x);
            return Some((x, y));
        }
        if it % STALL_EVERY == 0 {
            if gap > 1e3 * tol && gap >= 0.99 * last {
                return None;
            }
            last = gap;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two equal rows `z₁ + z₂ = 2` (a load on two redundant supports):
    /// the minimum-norm impulses `(1, 1)` are feasible and kept. One row
    /// `z₁ − z₂ = 4`: its minimum-norm solution `(2, −2)` is not, the
    /// feasible one of minimum norm is `(4, 0)`; with `z₁ + z₂ = 0` held
    /// too, none is.
    #[test]
    fn two_redundant_supports_share_the_load() {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let null = DMatrix::from_column_slice(2, 1, &[s, -s]);
        let cones = [
            Cone {
                normal: 0,
                tangential: None,
            },
            Cone {
                normal: 1,
                tangential: None,
            },
        ];
        let z0 = DVector::from_vec(vec![1.0, 1.0]);
        let (z, _) = min_norm_feasible(&z0, &null, &cones, true).expect("feasible");
        assert_eq!(z.as_slice(), &[1.0, 1.0]);
        let null = DMatrix::from_column_slice(2, 1, &[s, s]);
        let z0 = DVector::from_vec(vec![2.0, -2.0]);
        let (z, y) = min_norm_feasible(&z0, &null, &cones, true).expect("feasible");
        assert!((z[0] - 4.0).abs() < 1e-10 && z[1].abs() < 1e-10, "{z}");
        assert!((y[0] - y[1] - 4.0).abs() < 1e-12, "{y}");
        let null = DMatrix::zeros(2, 0);
        assert!(min_norm_feasible(&z0, &null, &cones, true).is_none());
    }

    /// A sticking row `(Λ, Λ_t)` with `Λ_t = 1` fixed and `Λ` free: the
    /// cone `|Λ_t| ≤ μ Λ` with `μ = 0.5` needs `Λ ≥ 2`.
    #[test]
    fn the_cone_sets_the_least_normal_impulse() {
        let null = DMatrix::from_column_slice(3, 1, &[1.0, 0.0, 0.0]);
        let z0 = DVector::from_vec(vec![0.0, 1.0, 0.0]);
        let cones = [Cone {
            normal: 0,
            tangential: Some(([1, 2], 0.5)),
        }];
        let (z, _) = min_norm_feasible(&z0, &null, &cones, true).expect("feasible");
        assert!(
            (z[0] - 2.0).abs() < 1e-10 && (z[1] - 1.0).abs() < 1e-10,
            "{z}"
        );
        // Without friction's cone only Λ ≥ 0: z0 itself.
        let (z, _) = min_norm_feasible(&z0, &null, &cones, false).expect("feasible");
        assert_eq!(z.as_slice(), z0.as_slice());
    }

    /// The closed form on a line against Dykstra's projections, on random
    /// lines through three cones (two with friction's rows). Every point
    /// the line finds is in the cones, on the line, and the least: a point
    /// a millionth nearer `z0` is outside. Where both find a point it is
    /// the same; the line never misses a point the projections find. The
    /// projections miss some (they stall on lines at a small angle to a
    /// cone's face, and are then declared empty): counted, and printed.
    /// A small linear congruential generator keeps the cases fixed.
    #[test]
    fn the_line_agrees_with_the_projections() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let (mut both, mut neither, mut missed) = (0, 0, 0);
        for case in 0..400 {
            let mu = [0.2 + 1.8 * next().abs(), 0.2 + 1.8 * next().abs()];
            let cones = [
                Cone {
                    normal: 0,
                    tangential: Some(([1, 2], mu[0])),
                },
                Cone {
                    normal: 3,
                    tangential: Some(([4, 5], mu[1])),
                },
                Cone {
                    normal: 6,
                    tangential: None,
                },
            ];
            let n = DVector::from_fn(7, |_, _| next()).normalize();
            let z = DVector::from_fn(7, |_, _| next());
            let z0 = &z - &n * n.dot(&z);
            let null = DMatrix::from_column_slice(7, 1, n.as_slice());
            for with_friction in [true, false] {
                let what = format!("case {case} (friction {with_friction})");
                let line = on_a_line(&z0, &null, &cones, with_friction);
                if let Some((zl, al)) = &line {
                    let t = n.dot(&(zl - &z0));
                    assert!(inside(zl, &cones, with_friction), "{what}: {zl}");
                    assert!((zl - al).amax() < 1e-10, "{what}: {zl} vs {al}");
                    assert!((al - (&z0 + &n * t)).amax() < 1e-12, "{what}: {al}");
                    if t.abs() > 1e-9 {
                        let nearer = &z0 + &n * (t * (1.0 - 1e-6));
                        assert!(!inside(&nearer, &cones, with_friction), "{what}: t = {t}");
                    }
                }
                match (&line, dykstra(&z0, &null, &cones, with_friction)) {
                    (Some((zl, _)), Some((zp, _))) => {
                        both += 1;
                        assert!(
                            (zl - &zp).amax() < 1e-6 * zp.amax(),
                            "{what}: line {zl}, projections {zp}"
                        );
                    }
                    (None, None) => neither += 1,
                    (Some(_), None) => missed += 1,
                    (None, Some((zp, _))) => panic!("{what}: the line missed {zp}"),
                }
            }
        }
        eprintln!("{both} found by both, {neither} by neither, {missed} by the line only");
        assert!(both > 50 && neither > 50, "{both} / {neither}");
    }
}
