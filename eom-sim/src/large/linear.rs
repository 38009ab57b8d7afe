//! The linear equations of a vector model about a state, from its
//! residual alone ([`AlphaModel::residual`], the one function
//! generalized-α solves):
//!
//! ```text
//! M δÿ + D δẏ + K δy + Gᵀ δλ = 0,      G δy = 0,
//! ```
//!
//! `M = ∂r/∂ÿ` (the residual is linear in the accelerations: one
//! difference per column, exact but for rounding), `D = ∂r/∂ẏ`,
//! `K = ∂r/∂y` with the state's multipliers held (so the constraint forces'
//! geometric stiffness `∂(Φ_yᵀλ)/∂y` is in `K`) and `G = Φ_y`, the last
//! three by fourth-order central differences. With the consistent
//! accelerations and multipliers of the state ([`AlphaModel::start`]).
//! About a static equilibrium this gives a structure's (or a mixed
//! model's) natural frequencies and modes.

use super::alpha::AlphaModel;
use super::run::{DynamicsError, State};
use nalgebra::DMatrix;

/// The linear equations about a state (see the module documentation).
#[derive(Clone, Debug)]
pub struct SecondOrder {
    /// Mass matrix `∂r/∂ÿ` (`n × n`).
    pub m: DMatrix<f64>,
    /// Damping `∂r/∂ẏ` (`n × n`).
    pub d: DMatrix<f64>,
    /// Stiffness `∂r/∂y` (`n × n`), geometric stiffness included.
    pub k: DMatrix<f64>,
    /// Constraint Jacobian `Φ_y` (`m × n`).
    pub g: DMatrix<f64>,
    /// The state's consistent accelerations.
    pub acc: Vec<f64>,
    /// And multipliers.
    pub lambda: Vec<f64>,
}

/// The linear equations of `model` about `state`.
pub fn second_order<M: AlphaModel + ?Sized>(
    model: &M,
    state: &State,
) -> Result<SecondOrder, DynamicsError> {
    let (n, nc) = (model.n(), model.n_constraints());
    let mut w = model.work(state);
    let mut acc = vec![0.0; n];
    let mut lambda = vec![0.0; nc];
    model.start(&mut w, state, &mut acc, &mut lambda)?;
    let mut r = vec![0.0; n + nc];
    let mut residual = |y: &[f64], v: &[f64], a: &[f64]| -> Vec<f64> {
        model.residual(&mut w, state.t, y, v, a, &lambda, &mut r);
        r.clone()
    };
    let (y0, v0) = (state.q.as_slice(), state.v.as_slice());
    let base = residual(y0, v0, &acc);
    let mut m = DMatrix::<f64>::zeros(n, n);
    let mut d = DMatrix::<f64>::zeros(n, n);
    let mut k = DMatrix::<f64>::zeros(n, n);
    let mut g = DMatrix::<f64>::zeros(nc, n);
    for j in 0..n {
        // M: the residual is linear in the accelerations.
        let mut a = acc.clone();
        a[j] += 1.0;
        let r1 = residual(y0, v0, &a);
        for i in 0..n {
            m[(i, j)] = r1[i] - base[i];
        }
        // K, G and D: fourth-order central differences.
        let central = |f: &mut dyn FnMut(f64) -> Vec<f64>, h: f64| -> Vec<f64> {
            let (p2, p1, m1, m2) = (f(2.0 * h), f(h), f(-h), f(-2.0 * h));
            (0..p1.len())
                .map(|i| (8.0 * (p1[i] - m1[i]) - (p2[i] - m2[i])) / (12.0 * h))
                .collect()
        };
        let hy = 1e-4 * y0[j].abs().max(1.0);
        let col = central(
            &mut |s| {
                let mut y = y0.to_vec();
                y[j] += s;
                residual(&y, v0, &acc)
            },
            hy,
        );
        for i in 0..n {
            k[(i, j)] = col[i];
        }
        for i in 0..nc {
            g[(i, j)] = col[n + i];
        }
        let hv = 1e-4 * v0[j].abs().max(1.0);
        let col = central(
            &mut |s| {
                let mut v = v0.to_vec();
                v[j] += s;
                residual(y0, &v, &acc)
            },
            hv,
        );
        for i in 0..n {
            d[(i, j)] = col[i];
        }
    }
    Ok(SecondOrder {
        m,
        d,
        k,
        g,
        acc,
        lambda,
    })
}
