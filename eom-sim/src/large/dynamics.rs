//! Time integration of `M q̈ + f_int(q, q̇) = f_ext` for large structural
//! models (free coordinates, constant sparse `M`): the structure's side of the generalized-α contract
//! ([`super::alpha::AlphaModel`]: the iteration matrix `M + γ' D + β' K`
//! assembled sparse and factored by LU, [`super::sparse::AutoLu`], banded
//! when the pattern is, else sparse with the symbolic analysis reused),
//! and [`integrate_rk4`], the classical explicit Runge–Kutta method, fixed
//! step, for non-stiff cases (soft structures, short runs), `M` factored
//! once by sparse Cholesky.

use super::alpha::AlphaModel;
use super::model::StructuralModel;
use super::run::{DynamicsError, DynamicsStats, State};
use super::sparse::{AutoLu, FactorError, FaerCholesky, SparseMatrix, SparseSolver};
use crate::integrate::fixed::rk4_tableau;

/// The structure's scratch for [`super::GeneralizedAlpha`]: the load, the
/// iteration matrix and its LU, the expanded coordinates.
pub struct StructuralWork {
    load: Vec<f64>,
    iteration: SparseMatrix,
    lu: AutoLu,
    q_full: Vec<f64>,
    v_full: Vec<f64>,
    scratch: Vec<f64>,
}

/// Consistent initial accelerations `M q̈ = f_ext − f_int(q, v)`.
fn initial_acceleration(
    model: &StructuralModel,
    q_full: &[f64],
    v_full: &[f64],
    load: &[f64],
) -> Result<Vec<f64>, FactorError> {
    let n = model.n_free();
    let mut scratch = vec![0.0; model.n_full()];
    let mut f = vec![0.0; n];
    model.internal(q_full, v_full, &mut scratch, &mut f);
    let mut rhs: Vec<f64> = load.iter().zip(&f).map(|(a, b)| a - b).collect();
    let mut chol = FaerCholesky::default();
    chol.factor(model.mass())?;
    chol.solve(&mut rhs);
    Ok(rhs)
}

/// A structure alone: `M q̈ + f_int(q, q̇) − f_ext = 0` on the free
/// coordinates, no constraint rows.
impl AlphaModel for StructuralModel {
    type Work = StructuralWork;

    fn n(&self) -> usize {
        self.n_free()
    }

    fn n_constraints(&self) -> usize {
        0
    }

    fn work(&self, state: &State) -> StructuralWork {
        StructuralWork {
            load: self.load_free(),
            iteration: SparseMatrix::zeros(self.pattern().clone()),
            lu: AutoLu::default(),
            q_full: self.expand(&state.q),
            v_full: self.expand_rate(&state.v),
            scratch: vec![0.0; self.n_full()],
        }
    }

    fn start(
        &self,
        w: &mut StructuralWork,
        state: &State,
        acc: &mut [f64],
        _lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let a = initial_acceleration(self, &w.q_full, &w.v_full, &w.load)
            .map_err(|reason| DynamicsError::Singular { t: state.t, reason })?;
        acc.copy_from_slice(&a);
        Ok(())
    }

    fn residual(
        &self,
        w: &mut StructuralWork,
        _t: f64,
        y: &[f64],
        v: &[f64],
        acc: &[f64],
        _lambda: &[f64],
        r: &mut [f64],
    ) {
        self.expand_into(y, &mut w.q_full);
        self.expand_into(v, &mut w.v_full);
        // r = M q̈ + f_int(q, v) − f_ext.
        self.internal(&w.q_full, &w.v_full, &mut w.scratch, r);
        for (ri, fi) in r.iter_mut().zip(&w.load) {
            *ri -= fi;
        }
        self.mass().sym_mul_add(1.0, acc, r);
    }

    fn factor(
        &self,
        w: &mut StructuralWork,
        t: f64,
        _y: &[f64],
        _v: &[f64],
        _acc: &[f64],
        _lambda: &[f64],
        bp: f64,
        gp: f64,
    ) -> Result<(), DynamicsError> {
        self.jacobian(&w.q_full, &w.v_full, bp, gp, 1.0, &mut w.iteration);
        w.lu.factor(&w.iteration)
            .map_err(|reason| DynamicsError::Singular { t, reason })
    }

    fn solve(&self, w: &mut StructuralWork, r: &mut [f64]) {
        w.lu.solve(r);
    }

    fn accepted(&self, w: &mut StructuralWork, state: &State) -> f64 {
        self.expand_into(&state.q, &mut w.q_full);
        self.expand_into(&state.v, &mut w.v_full);
        0.0
    }

    fn full<'w>(&self, w: &'w StructuralWork) -> &'w [f64] {
        &w.q_full
    }
}

/// Fixed-step classical Runge–Kutta (order 4, the tableau the compiled
/// models run, [`rk4_tableau`]) from `state` to `t_end` in
/// `steps` steps, `M` factored once (sparse Cholesky); `observe` after every
/// step gets the state and the full coordinates.
pub fn integrate_rk4(
    model: &StructuralModel,
    mut state: State,
    t_end: f64,
    steps: usize,
    mut observe: impl FnMut(&State, &[f64]),
) -> Result<(State, DynamicsStats), DynamicsError> {
    let n = model.n_free();
    let mut chol = FaerCholesky::default();
    chol.factor(model.mass())
        .map_err(|reason| DynamicsError::Singular { t: state.t, reason })?;
    let load = model.load_free();
    let mut q_full = model.expand(&state.q);
    let mut v_full = model.expand_rate(&state.v);
    let mut scratch = vec![0.0; model.n_full()];
    let mut f = vec![0.0; n];
    let mut stats = DynamicsStats {
        factorizations: 1,
        ..DynamicsStats::default()
    };
    let h = (t_end - state.t) / steps.max(1) as f64;
    // y = [q; v], y' = [v; M⁻¹ (f_ext − f_int(q, v))].
    let mut rhs = |y: &Vec<f64>, out: &mut Vec<f64>| {
        let (q, v) = y.split_at(n);
        model.expand_into(q, &mut q_full);
        model.expand_into(v, &mut v_full);
        model.internal(&q_full, &v_full, &mut scratch, &mut f);
        let (dq, dv) = out.split_at_mut(n);
        dq.copy_from_slice(v);
        for ((a, l), fi) in dv.iter_mut().zip(&load).zip(&f) {
            *a = l - fi;
        }
        chol.solve(dv);
    };
    let mut y = [state.q.as_slice(), state.v.as_slice()].concat();
    let (mut y0, mut k1, mut yt) = (y.clone(), vec![0.0; 2 * n], vec![0.0; 2 * n]);
    let mut k = [vec![0.0; 2 * n], vec![0.0; 2 * n], vec![0.0; 2 * n]];
    for _ in 0..steps {
        let t0 = state.t;
        y0.copy_from_slice(&y);
        rhs(&y0, &mut k1);
        rk4_tableau(
            t0,
            t0 + h,
            &y0,
            &k1,
            &mut k,
            &mut yt,
            &mut y,
            |_, y, out| rhs(y, out),
        );
        stats.force_evaluations += 4;
        if y.iter().any(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite { t: t0 + h });
        }
        state.q.copy_from_slice(&y[..n]);
        state.v.copy_from_slice(&y[n..]);
        state.t = t0 + h;
        stats.steps += 1;
        let qf = model.expand(&state.q);
        observe(&state, &qf);
    }
    Ok((state, stats))
}
