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
//! onto the intersection of the affine set and the cones, found by
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
/// empty (the gap stalls, see [`STALL_EVERY`], or is not closed within
/// [`MAX_ITER`] projections).
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
}
