//! Models with cables about a static equilibrium: the structure's (or the
//! mixed model's) linear equations `M δÿ + D δẏ + K δy + Gᵀ δλ = 0`,
//! `G δy = 0` from the element runtime's residual
//! ([`eom_sim::large::second_order`]), in minimal coordinates `δy = Z z`
//! (`Z` an orthonormal basis of the null space of `G`, the attachments):
//!
//! ```text
//! A = [[0, I], [−(ZᵀMZ)⁻¹ ZᵀKZ, −(ZᵀMZ)⁻¹ ZᵀDZ]],
//! ```
//!
//! whose eigenvalues are the natural frequencies (and damping) of the
//! structure about its equilibrium, geometric stiffness included. A state
//! that is not at rest in equilibrium is refused.

use super::{InputKind, Linearization, LinearizeError};
use eom_sim::large::SecondOrder;
use nalgebra::DMatrix;

/// The linearisation of `eq` (about a state with speeds `v`) over the
/// coordinates named `coordinates`.
pub fn linearize(
    model: &str,
    eq: &SecondOrder,
    v: &[f64],
    coordinates: Vec<String>,
) -> Result<Linearization, LinearizeError> {
    let n = eq.m.nrows();
    let speed = v.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    let acceleration = eq.acc.iter().fold(0.0f64, |s, x| s.max(x.abs()));
    // The static solver's tolerance leaves accelerations of about a
    // millionth of gravity, and the rounding of stiff elastic forces (EA
    // times a strain of order ε) of order ε K/M; an unbalanced load
    // leaves far more.
    let rounding = 1e-12 * eq.k.amax() / eq.m.amax().max(1e-300) + 1e-5;
    if speed != 0.0 || acceleration.is_nan() || acceleration > rounding {
        return Err(LinearizeError::NotStatic {
            model: model.to_string(),
            speed,
            acceleration,
        });
    }
    let finite = |m: &DMatrix<f64>| m.iter().all(|x| x.is_finite());
    if !(finite(&eq.m) && finite(&eq.k) && finite(&eq.d) && finite(&eq.g)) {
        return Err(LinearizeError::NotFinite);
    }
    // Z: the null space of G (all coordinates without attachments).
    let z = if eq.g.nrows() == 0 {
        DMatrix::identity(n, n)
    } else {
        super::null_space(&eq.g)
    };
    let f = z.ncols();
    let zt = z.transpose();
    let mr = &zt * &eq.m * &z;
    // The structure's mass matrix is symmetric; a mixed model's too.
    let lu = mr.clone().lu();
    let (Some(stiffness), Some(damping)) =
        (lu.solve(&(&zt * &eq.k * &z)), lu.solve(&(&zt * &eq.d * &z)))
    else {
        return Err(LinearizeError::NotFinite);
    };
    let mut a = DMatrix::<f64>::zeros(2 * f, 2 * f);
    a.view_mut((0, f), (f, f))
        .copy_from(&DMatrix::identity(f, f));
    a.view_mut((f, 0), (f, f)).copy_from(&(-stiffness));
    a.view_mut((f, f), (f, f)).copy_from(&(-damping));
    if !finite(&a) {
        return Err(LinearizeError::NotFinite);
    }
    let reduced = eq.g.nrows() > 0;
    let states: Vec<String> = if reduced {
        (1..=f)
            .map(|k| format!("z{k}"))
            .chain((1..=f).map(|k| format!("z{k}_dot")))
            .collect()
    } else {
        coordinates
            .iter()
            .cloned()
            .chain(coordinates.iter().map(|c| format!("{c}_dot")))
            .collect()
    };
    let mut state_basis = DMatrix::<f64>::zeros(2 * n, 2 * f);
    state_basis.view_mut((0, 0), (n, f)).copy_from(&z);
    state_basis.view_mut((n, f), (n, f)).copy_from(&z);
    Ok(Linearization {
        a,
        b: DMatrix::zeros(2 * f, 0),
        states,
        positions: f,
        inputs: Vec::new(),
        input_kind: InputKind::GeneralizedForces,
        basis: reduced.then_some(z),
        basis_rows: if reduced { coordinates } else { Vec::new() },
        cyclic: Vec::new(),
        state_basis,
        outputs: Vec::new(),
        c: DMatrix::zeros(0, 2 * f),
        d: DMatrix::zeros(0, 0),
    })
}
