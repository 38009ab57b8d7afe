//! Assumed modes (Rayleigh–Ritz; Shabana 5.1): a straight slender body along
//! the body `x` axis, `0 ≤ x ≤ L`, whose deformation is `ū_f = S(x) q_f`
//! with shape functions given as functions of `x` (in the model format,
//! expressions, differentiated exactly by [`crate::expr::Ast::diff`]):
//! per coordinate `j` the axial `u_j(x)`, lateral `v_j(x)` (along `y`),
//! `w_j(x)` (along `z`) and torsion `φ_j(x)`.
//!
//! The section data are the beam's ([`Beam`]: `ρA`, `ρI_p`, `EA`, `EI_y`,
//! `EI_z`, `GJ`), and so are the integrals: the inertia shape integrals of
//! [`Invariants`] with `S = [u; v; w]` and the torsion inertia `ρI_p φ`, and
//! from the strain energy of an Euler–Bernoulli beam
//!
//! ```text
//! K_ff,ij = ∫ EA u_i' u_j' + EI_z v_i'' v_j'' + EI_y w_i'' w_j'' + GJ φ_i' φ_j' dx
//! K_G1,ij = ∫ P(x) (v_i' v_j' + w_i' w_j') dx,   P(x) = ρA (L² − x²)/2
//! ```
//!
//! (`K_G1`: the geometric stiffness per `Ω²` of the centrifugal axial load of
//! a beam spinning about an axis through `x = 0`, Kane, Ryan and Banerjee
//! 1987, as [`Beam::centrifugal_force`] with no hub radius).
//!
//! **Quadrature and its accuracy.** Every integral is taken with the
//! composite 8-point Gauss–Legendre rule on [`INTERVALS`] equal intervals
//! (exact for polynomials of degree ≤ 15 on each interval; for analytic
//! shapes such as a few half-sines the error is at round-off). The same
//! integrals on half as many intervals are compared: if `M_ff` or `K_ff`
//! differ by more than [`TOLERANCE`] of their largest entry, the shapes are
//! too rough (a kink, a singular derivative) and [`AssumedError::Unresolved`]
//! is returned rather than a silently inaccurate body.

use nalgebra::{DMatrix, DVector, Matrix3, Matrix3xX, Vector3};

use super::invariants::Shares;
use super::ritz::{Ritz, RitzError};
use super::{Basis, Beam, Invariants, Modes, Section};
use crate::expr::Ast;

/// Intervals of the composite Gauss–Legendre rule.
pub const INTERVALS: usize = 64;

/// Largest relative change of `M_ff`, `K_ff` between [`INTERVALS`]/2 and
/// [`INTERVALS`] intervals accepted.
pub const TOLERANCE: f64 = 1e-9;

/// 8-point Gauss–Legendre on `[0, 1]`: `(ξ, weight)`.
const GAUSS8: [(f64, f64); 8] = {
    const X: [f64; 4] = [
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const W: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    [
        (0.5 - 0.5 * X[3], 0.5 * W[3]),
        (0.5 - 0.5 * X[2], 0.5 * W[2]),
        (0.5 - 0.5 * X[1], 0.5 * W[1]),
        (0.5 - 0.5 * X[0], 0.5 * W[0]),
        (0.5 + 0.5 * X[0], 0.5 * W[0]),
        (0.5 + 0.5 * X[1], 0.5 * W[1]),
        (0.5 + 0.5 * X[2], 0.5 * W[2]),
        (0.5 + 0.5 * X[3], 0.5 * W[3]),
    ]
};

/// A part of a shape function.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// Axial displacement `u`.
    U,
    /// Displacement along `y`, `v`.
    V,
    /// Displacement along `z`, `w`.
    W,
    /// Torsion angle `φ`.
    Phi,
}

impl Part {
    /// All four, in order.
    pub const ALL: [Part; 4] = [Part::U, Part::V, Part::W, Part::Phi];

    /// The field name in the model format.
    pub fn name(self) -> &'static str {
        ["u", "v", "w", "phi"][self as usize]
    }
}

/// The shape functions: `value(j, part, order, x)` is the `order`-th
/// derivative (0, 1 or 2) of part `part` of shape `j` at `x`, `None` if it is
/// not a finite number there. Parts that are absent are `Some(0.0)`.
pub type ShapeFn<'a> = dyn Fn(usize, Part, usize, f64) -> Option<f64> + 'a;

/// What can go wrong with assumed modes.
#[derive(Clone, Debug, PartialEq)]
pub enum AssumedError {
    /// A part or derivative is not finite at `x` (shape `j`, 0-based).
    NotFinite {
        /// The shape.
        shape: usize,
        /// The part.
        part: Part,
        /// Derivative order.
        order: usize,
        /// Where.
        x: f64,
    },
    /// The quadrature does not resolve the shapes (relative change).
    Unresolved(f64),
    /// The reduced matrices fail their checks.
    Reduced(RitzError),
}

impl std::fmt::Display for AssumedError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AssumedError::NotFinite {
                shape,
                part,
                order,
                x,
            } => {
                let d = ["", "′", "″"][(*order).min(2)];
                write!(
                    f,
                    "shape {}: `{}{d}` is not a finite number at x = {x}",
                    shape + 1,
                    part.name()
                )
            }
            AssumedError::Unresolved(rel) => write!(
                f,
                "the shape integrals do not converge (they change by {rel:.1e} between {} and {INTERVALS} \
                 Gauss–Legendre intervals): the shapes or their derivatives are not smooth",
                INTERVALS / 2
            ),
            AssumedError::Reduced(e) => e.fmt(f),
        }
    }
}

impl std::error::Error for AssumedError {}

/// One shape's parts as expressions of `x` alone (parameters replaced by
/// their values): value and first derivative of `u`, `v`, `w`, `φ` (in
/// [`Part`] order), `None` where absent.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeExprs {
    /// `[value, d/dx]` per part.
    pub parts: [Option<[Ast; 2]>; 4],
}

/// Translation `(u, v, w)` and small rotation `(φ, −w', v')` at `x` of each
/// shape (the section of a beam: `θ_y = −∂w/∂x`, `θ_z = ∂v/∂x`); `None` if a
/// value is not finite there.
pub fn section(shapes: &[ShapeExprs], x: f64) -> Option<Section> {
    let k = shapes.len();
    let mut out = Section {
        translation: Matrix3xX::zeros(k),
        rotation: Matrix3xX::zeros(k),
    };
    let lookup = |n: &str| (n == "x").then_some(x);
    for (j, s) in shapes.iter().enumerate() {
        let at = |p: Part, d: usize| -> Option<f64> {
            match &s.parts[p as usize] {
                None => Some(0.0),
                Some(e) => e[d].eval(&lookup).ok(),
            }
        };
        out.translation[(0, j)] = at(Part::U, 0)?;
        out.translation[(1, j)] = at(Part::V, 0)?;
        out.translation[(2, j)] = at(Part::W, 0)?;
        out.rotation[(0, j)] = at(Part::Phi, 0)?;
        out.rotation[(1, j)] = -at(Part::W, 1)?;
        out.rotation[(2, j)] = at(Part::V, 1)?;
    }
    Some(out)
}

/// A slender body reduced to assumed modes.
#[derive(Clone, Debug, PartialEq)]
pub struct Assumed {
    /// The inertia shape integrals (with `M_ff` and `K_ff`).
    pub invariants: Invariants,
    /// `K_G1` per `Ω²` (k×k): the foreshortening's first moment
    /// `∫ρA (L² − x²)/2 (v'v'ᵀ + w'w'ᵀ) dx`.
    pub geometric: DMatrix<f64>,
    /// `K₂` per unit axial acceleration of the root (k×k):
    /// `∫ρA (L − x) (v'v'ᵀ + w'w'ᵀ) dx` ([`crate::flex::invariants::foreshortening`]).
    pub axial_geometric: DMatrix<f64>,
    /// The reduced matrices' normal modes.
    pub ritz: Ritz,
    /// The shares of `M_ff` and `K_ff` per section datum (tunable data).
    pub shares: Shares,
}

impl Assumed {
    /// The reduced basis in the form the beam path has: no nodal shapes
    /// (`0 × k`), the reduced matrices and their frequencies.
    pub fn modes(&self) -> Modes {
        let k = self.invariants.modes();
        Modes {
            shapes: DMatrix::zeros(0, k),
            mass: self.invariants.modal_mass.clone(),
            stiffness: self.invariants.modal_stiffness.clone(),
            frequencies: self.ritz.frequencies.clone(),
            basis: Basis::Normal,
        }
    }
}

/// Integrals on `intervals` equal intervals.
fn integrate(
    section: &Beam,
    k: usize,
    shape: &ShapeFn<'_>,
    intervals: usize,
) -> Result<(Invariants, DMatrix<f64>, DMatrix<f64>, Shares), AssumedError> {
    let h = section.length / intervals as f64;
    let zk = || DMatrix::<f64>::zeros(k, k);
    let zv = || DVector::<f64>::zeros(k);
    let mut inv = Invariants {
        mass: 0.0,
        first_moment: Vector3::zeros(),
        second_moment: Matrix3::zeros(),
        inertia: Matrix3::zeros(),
        s_bar: DMatrix::zeros(3, k),
        s_ij: std::array::from_fn(|_| std::array::from_fn(|_| zk())),
        x_s: std::array::from_fn(|_| std::array::from_fn(|_| zv())),
        coupling: DMatrix::zeros(3, k),
        spin_inertia: 0.0,
        spin_modes: zv(),
        rotary_inertia: [0.0; 2],
        rotary_modes: DMatrix::zeros(2, k),
        modal_mass: zk(),
        modal_stiffness: zk(),
    };
    let mut spin_mass = zk();
    let mut stiffness: [DMatrix<f64>; 4] = std::array::from_fn(|_| zk());
    let mut geometric = zk();
    let mut axial_geometric = zk();
    let at = |j: usize, part: Part, order: usize, x: f64| {
        shape(j, part, order, x).ok_or(AssumedError::NotFinite {
            shape: j,
            part,
            order,
            x,
        })
    };
    let row = |part: Part, order: usize, x: f64| -> Result<DVector<f64>, AssumedError> {
        let mut r = DVector::zeros(k);
        for j in 0..k {
            r[j] = at(j, part, order, x)?;
        }
        Ok(r)
    };
    for e in 0..intervals {
        for (xi, w) in GAUSS8 {
            let x = (e as f64 + xi) * h;
            let (u, v, ww, phi) = (
                row(Part::U, 0, x)?,
                row(Part::V, 0, x)?,
                row(Part::W, 0, x)?,
                row(Part::Phi, 0, x)?,
            );
            let (du, dv, dw, dphi) = (
                row(Part::U, 1, x)?,
                row(Part::V, 1, x)?,
                row(Part::W, 1, x)?,
                row(Part::Phi, 1, x)?,
            );
            let (ddv, ddw) = (row(Part::V, 2, x)?, row(Part::W, 2, x)?);
            let s = [&u, &v, &ww];
            let u0 = Vector3::new(x, 0.0, 0.0);
            let dx = w * h;
            let dm = section.rho_a * dx;
            let dj = section.rho_ip * dx;
            inv.mass += dm;
            inv.first_moment += u0 * dm;
            inv.second_moment += u0 * u0.transpose() * dm;
            for i in 0..3 {
                for (j, sij) in s[i].iter().enumerate() {
                    inv.s_bar[(i, j)] += sij * dm;
                }
                for c in 0..3 {
                    inv.s_ij[i][c] += s[i] * s[c].transpose() * dm;
                    inv.x_s[i][c] += s[c] * (u0[i] * dm);
                }
            }
            inv.spin_inertia += dj;
            inv.spin_modes += &phi * dj;
            spin_mass += &phi * phi.transpose() * dj;
            // K_ff's shares of EA, EI_y, EI_z, GJ.
            let parts = [
                &du * du.transpose() * (section.ea * dx),
                &ddw * ddw.transpose() * (section.ei_y * dx),
                &ddv * ddv.transpose() * (section.ei_z * dx),
                &dphi * dphi.transpose() * (section.gj * dx),
            ];
            for (total, part) in stiffness.iter_mut().zip(parts) {
                inv.modal_stiffness += &part;
                *total += part;
            }
            let bending = &dv * dv.transpose() + &dw * dw.transpose();
            geometric += &bending * (section.centrifugal_force(0.0, x) * dx);
            axial_geometric += bending * (section.rho_a * (section.length - x) * dx);
        }
    }
    let ex = Vector3::x();
    let c = inv.second_moment;
    inv.inertia = Matrix3::identity() * c.trace() - c + ex * ex.transpose() * inv.spin_inertia;
    inv.coupling = inv.coupling_at(&DVector::zeros(k));
    inv.modal_mass = &inv.s_ij[0][0] + &inv.s_ij[1][1] + &inv.s_ij[2][2] + &spin_mass;
    let sym = |a: &DMatrix<f64>| (a + a.transpose()) * 0.5;
    inv.modal_mass = sym(&inv.modal_mass);
    inv.modal_stiffness = sym(&inv.modal_stiffness);
    let shares = Shares {
        spin_mass: sym(&spin_mass),
        stiffness: stiffness.map(|k| sym(&k)),
    };
    Ok((inv, sym(&geometric), sym(&axial_geometric), shares))
}

/// The body of `k` assumed shapes over `section` (its `elements` unused):
/// the integrals, checked for convergence, and the checks of [`Ritz`].
pub fn assumed_modes(
    section: &Beam,
    k: usize,
    shape: &ShapeFn<'_>,
) -> Result<Assumed, AssumedError> {
    let (inv, geometric, axial_geometric, shares) = integrate(section, k, shape, INTERVALS)?;
    let (coarse, _, _, _) = integrate(section, k, shape, INTERVALS / 2)?;
    let change = |a: &DMatrix<f64>, b: &DMatrix<f64>| {
        let top = a.amax();
        if top == 0.0 {
            0.0
        } else {
            (a - b).amax() / top
        }
    };
    let rel = change(&inv.modal_mass, &coarse.modal_mass)
        .max(change(&inv.modal_stiffness, &coarse.modal_stiffness));
    if rel > TOLERANCE {
        return Err(AssumedError::Unresolved(rel));
    }
    let ritz = Ritz::new(&inv.modal_mass, &inv.modal_stiffness).map_err(AssumedError::Reduced)?;
    Ok(Assumed {
        invariants: inv,
        geometric,
        axial_geometric,
        ritz,
        shares,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn assumed_sine_is_the_exact_pinned_pinned_mode() {
        // v = sin(πx/L): M = ρA L/2, K = EI_z (π/L)⁴ L/2, ω = (π/L)² √(EI/ρA).
        let b = Beam::new(2.0, 3.0, 0.01, 1e6, 50.0, 70.0, 10.0, 1).unwrap();
        let l = b.length;
        let f = move |_: usize, p: Part, o: usize, x: f64| {
            let a = PI / l;
            Some(match (p, o) {
                (Part::V, 0) => (a * x).sin(),
                (Part::V, 1) => a * (a * x).cos(),
                (Part::V, 2) => -a * a * (a * x).sin(),
                _ => 0.0,
            })
        };
        let body = assumed_modes(&b, 1, &f).unwrap();
        let want = (PI / l).powi(2) * (b.ei_z / b.rho_a).sqrt();
        let got = body.ritz.frequencies[0];
        assert!((got / want - 1.0).abs() < 1e-13, "ω = {got}, want {want}");
        assert!((body.invariants.modal_mass[(0, 0)] - b.rho_a * l / 2.0).abs() < 1e-13);
        // S̄_y = ∫ρA sin = 2 ρA L/π.
        assert!((body.invariants.s_bar[(1, 0)] - 2.0 * b.rho_a * l / PI).abs() < 1e-13);
    }
}
