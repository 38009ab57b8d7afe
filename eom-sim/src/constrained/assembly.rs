//! Assembly: a consistent state (`Φ = 0`, `J u + Φ_t = 0`) near a guess.

use super::linalg::{max_abs, min_norm_solve};
use super::{Assemble, ConstraintValues};

/// A consistent state near a guess.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// Positions with `Φ(q, t) = 0`.
    pub q: Vec<f64>,
    /// Speeds with `J u + Φ_t = 0`.
    pub u: Vec<f64>,
    /// `max |Φ|` reached.
    pub residual: f64,
    /// `max |J u + Φ_t|` reached.
    pub velocity_residual: f64,
    /// Newton iterations on the positions.
    pub iterations: usize,
}

/// Assembly: Newton with minimum-norm steps and backtracking onto the
/// holonomic equations `Φ = 0`, then the smallest change of the speeds that
/// satisfies every speed equation `J u + Φ_t = 0`.
pub fn assemble<D: Assemble + ?Sized>(d: &D, q0: &[f64], u0: &[f64], t: f64) -> Assembly {
    let (nu, nh) = (d.speeds(), d.holonomic());
    let mut c = ConstraintValues::zeros(d.equations(), nu);
    let zero = vec![0.0; nu];
    let mut q = q0.to_vec();
    d.unit_quaternions(&mut q);
    let holonomic_residual = |q: &[f64], c: &mut ConstraintValues| {
        d.closure(t, q, &zero, c);
        max_abs(c.phi.iter().take(nh))
    };
    let mut residual = holonomic_residual(&q, &mut c);
    let mut iterations = 0;
    let mut dq = vec![0.0; q.len()];
    while residual > 1e-13 && iterations < 50 {
        iterations += 1;
        let jh = c.jacobian.rows(0, nh).into_owned();
        let minus_phi = -c.phi.rows(0, nh).into_owned();
        let (du, _) = min_norm_solve(&jh, &minus_phi);
        d.rates(&q, du.as_slice(), &mut dq);
        let mut step = 1.0;
        let mut improved = false;
        while step > 1e-6 {
            let mut trial: Vec<f64> = q.iter().zip(&dq).map(|(q, d)| q + step * d).collect();
            d.unit_quaternions(&mut trial);
            let r = holonomic_residual(&trial, &mut c);
            if r < residual {
                q = trial;
                residual = r;
                improved = true;
                break;
            }
            step /= 2.0;
        }
        if !improved {
            break;
        }
    }
    d.closure(t, &q, u0, &mut c);
    let (du, _) = min_norm_solve(&c.jacobian, &-c.phidot.clone());
    let u: Vec<f64> = u0.iter().zip(du.iter()).map(|(u, d)| u + d).collect();
    d.closure(t, &q, &u, &mut c);
    Assembly {
        velocity_residual: max_abs(c.phidot.iter()),
        residual: max_abs(c.phi.iter().take(nh)),
        q,
        u,
        iterations,
    }
}
