//! Generated code as [`Dynamics`]: [`Generated`] copies between the slices
//! the solvers work on and the model's fixed-size vectors.

use super::{ConstrainedModel, ConstraintValues, DMatrix, DVector, Dynamics};
use crate::model::Vector;

/// Generated code as [`Dynamics`].
pub struct Generated<'a, M>(pub &'a M);

pub(crate) fn load<V: Vector>(src: &[f64]) -> V {
    let mut v = V::ZERO;
    for (d, s) in v.as_mut().iter_mut().zip(src) {
        *d = *s;
    }
    v
}

impl<M: ConstrainedModel> Dynamics for Generated<'_, M> {
    fn nq(&self) -> usize {
        M::NQ
    }
    fn nu(&self) -> usize {
        M::NU
    }
    fn nc(&self) -> usize {
        M::NC
    }
    fn n_holonomic(&self) -> usize {
        M::NHOLONOMIC
    }
    fn quaternions(&self) -> &[usize] {
        M::QUATERNIONS
    }
    fn qdot(&self, q: &[f64], u: &[f64], qdot: &mut [f64]) {
        let mut out = M::Q::ZERO;
        self.0.qdot(&load(q), &load(u), &mut out);
        for (d, s) in qdot.iter_mut().zip(out.as_ref()) {
            *d = *s;
        }
    }
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut DMatrix<f64>) {
        let mut out = M::MASS_ZERO;
        self.0.mass_matrix(t, &load(q), &mut out);
        for (i, row) in out.as_ref().iter().enumerate() {
            for (j, v) in row.as_ref().iter().enumerate() {
                if i < m.nrows() && j < m.ncols() {
                    m[(i, j)] = *v;
                }
            }
        }
    }
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut DVector<f64>) {
        let mut out = M::U::ZERO;
        self.0.bias(t, &load(q), &load(u), &mut out);
        for (d, s) in b.iter_mut().zip(out.as_ref()) {
            *d = *s;
        }
    }
    fn constraints(&self, t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues) {
        let (mut phi, mut phidot, mut gamma) = (
            M::Constraints::ZERO,
            M::Constraints::ZERO,
            M::Constraints::ZERO,
        );
        let mut jac = M::ConstraintJacobian::ZERO;
        self.0.constraints(
            t,
            &load(q),
            &load(u),
            &mut phi,
            &mut phidot,
            &mut gamma,
            &mut jac,
        );
        for (d, s) in c.phi.iter_mut().zip(phi.as_ref()) {
            *d = *s;
        }
        for (d, s) in c.phidot.iter_mut().zip(phidot.as_ref()) {
            *d = *s;
        }
        for (d, s) in c.gamma.iter_mut().zip(gamma.as_ref()) {
            *d = *s;
        }
        let nu = M::NU;
        for (k, v) in jac.as_ref().iter().enumerate() {
            let (r, col) = (k / nu.max(1), k % nu.max(1));
            if r < c.jacobian.nrows() && col < c.jacobian.ncols() {
                c.jacobian[(r, col)] = *v;
            }
        }
    }
}
