//! The model's outputs linearised with the state: `δh = C y + D w`.
//!
//! An output `h(q, u, u̇, λ)` (marker positions and velocities, energy,
//! joint reactions, …) depends on the state directly and, through the
//! accelerations and multipliers, on the state and the inputs. `C` and `D`
//! are fourth-order central differences of that composite — positions
//! moved along the chart of [`super::tangent`], `u̇` and `λ` from the
//! generated mass matrix, bias and constraints at each point (the KKT
//! system of the runtime) — mapped onto the linearisation's states by its
//! basis `T` (`C = ∂h/∂y_full · T`).

use super::tangent::Chart;
use super::{InputKind, LinearizeError, central, mass_and_force};
use crate::functions::Function;
use crate::interpret::{Point, evaluate_function};
use crate::mech::Formulation;
use nalgebra::{DMatrix, DVector};

/// The outputs at `x` with the accelerations and multipliers of its
/// forward dynamics.
fn outputs_at(f: &Formulation, x: &Point<'_>) -> Option<DVector<f64>> {
    let nu = x.sys.nu();
    let nc = f.constraint_names.len();
    let (m, force) = mass_and_force(f, x)?;
    let (j, gamma) = if nc > 0 {
        let c = evaluate_function(f, Function::Constraints, x)?;
        (
            DMatrix::from_row_slice(nc, nu, c.get(3 * nc..)?),
            DVector::from_column_slice(c.get(2 * nc..3 * nc)?),
        )
    } else {
        (DMatrix::zeros(0, nu), DVector::zeros(0))
    };
    let (udot, lambda, _) = eom_sim::constrained::accelerations(&m, &force, &j, &gamma)?;
    let values = evaluate_function(
        f,
        Function::Outputs,
        &Point {
            udot: udot.as_slice(),
            multipliers: lambda.as_slice(),
            ..x.clone()
        },
    )?;
    values
        .iter()
        .all(|v| v.is_finite())
        .then(|| DVector::from_vec(values))
}

/// `C` and `D`.
type OutputMatrices = (DMatrix<f64>, DMatrix<f64>);

/// `(C, D)` at `x` for states `y = T z` (`basis`: `2 NU × N`) and inputs
/// of `kind`; `None` when the model has no outputs.
pub(super) fn linearize(
    f: &Formulation,
    x: &Point<'_>,
    basis: &DMatrix<f64>,
    kind: InputKind,
) -> Result<Option<OutputMatrices>, LinearizeError> {
    if f.output_names.is_empty() {
        return Ok(None);
    }
    let nu = x.sys.nu();
    let ny = f.output_names.len();
    let chart = Chart::new(x.sys);
    let step = |v: f64| 1e-3 * v.abs().max(1.0);
    let mut full = DMatrix::<f64>::zeros(ny, 2 * nu);
    for k in 0..nu {
        let column = central(1e-3, |s| {
            let q = chart.displaced(x.q, k, s);
            outputs_at(f, &Point { q: &q, ..x.clone() })
        })?;
        full.set_column(k, &column);
        let column = central(step(x.u[k]), |s| {
            let mut u = x.u.to_vec();
            u[k] += s;
            outputs_at(f, &Point { u: &u, ..x.clone() })
        })?;
        full.set_column(nu + k, &column);
    }
    let (nw, tau0): (usize, Vec<f64>) = match kind {
        InputKind::Inputs => (x.inputs.len(), Vec::new()),
        InputKind::GeneralizedForces => (
            nu,
            (0..nu)
                .map(|k| x.tau.get(k).copied().unwrap_or(0.0))
                .collect(),
        ),
    };
    let mut d = DMatrix::<f64>::zeros(ny, nw);
    for k in 0..nw {
        let column = match kind {
            InputKind::Inputs => central(step(x.inputs[k]), |s| {
                let mut w = x.inputs.to_vec();
                w[k] += s;
                outputs_at(
                    f,
                    &Point {
                        inputs: &w,
                        ..x.clone()
                    },
                )
            })?,
            InputKind::GeneralizedForces => central(step(tau0[k]), |s| {
                let mut w = tau0.clone();
                w[k] += s;
                outputs_at(
                    f,
                    &Point {
                        tau: &w,
                        ..x.clone()
                    },
                )
            })?,
        };
        d.set_column(k, &column);
    }
    let c = full * basis;
    if c.iter().chain(d.iter()).any(|v| !v.is_finite()) {
        return Err(LinearizeError::NotFinite);
    }
    Ok(Some((c, d)))
}
