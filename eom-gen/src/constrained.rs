//! Closed loops in the interpreter: the equations of motion with the cut
//! joints' closure conditions, `M u̇ = τ − b + Jᵀλ`, `J u̇ = γ`
//! (Lagrange multipliers; Wittenburg 5.6, Shabana 5.9–5.12), solved per
//! right-hand side through the Schur complement `J M⁻¹ Jᵀ λ = γ̃ − J M⁻¹ (τ − b)`
//! with a pseudo-inverse, so redundant equations (Bricard) get the
//! minimum-norm `λ`.
//!
//! Drift of `Φ` and `Φ̇` is controlled either by Baumgarte stabilisation,
//! `γ̃ = γ − 2α Φ̇ − β² Φ` with `α = β = 10 s⁻¹`, or by projection after
//! every accepted step: Newton with minimum-norm corrections onto `Φ = 0`,
//! then the speeds onto `J u + Φ_t = 0` (`Φ_t` is `Φ̇` at `u = 0`).

use crate::interpret::{Point, run};
use crate::mech::Formulation;
use crate::sym::Program;
use crate::system::System;
use nalgebra::{DMatrix, DVector};
use std::cell::Cell;

/// How constraint drift is handled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stabilization {
    /// Baumgarte terms in the acceleration equation.
    Baumgarte,
    /// Projection of positions and speeds after each step.
    Projection,
}

/// Baumgarte's `α` and `β`, s⁻¹.
pub const BAUMGARTE: (f64, f64) = (10.0, 10.0);

/// The constrained equations of motion as an `OdeSystem` on `y = (q, u)`.
pub struct Constrained<'a, const N: usize> {
    f: &'a Formulation,
    sys: &'a System,
    closure: &'a Program,
    nq: usize,
    nu: usize,
    quaternions: Vec<usize>,
    mode: Stabilization,
    /// Largest `max |Φ|` seen at accepted steps.
    pub max_residual: Cell<f64>,
    /// Rank of `J` at the last accepted step.
    pub rank: Cell<usize>,
}

struct Closure {
    phi: Vec<f64>,
    phidot: Vec<f64>,
    gamma: Vec<f64>,
    j: DMatrix<f64>,
}

impl<'a, const N: usize> Constrained<'a, N> {
    /// The constrained system of `f` (which must have closure conditions).
    pub fn new(f: &'a Formulation, sys: &'a System, mode: Stabilization) -> Option<Self> {
        let closure = f.constraints.as_ref()?;
        let quaternions = sys.quaternion_indices();
        Some(Constrained {
            f,
            sys,
            closure,
            nq: sys.nq(),
            nu: sys.nu(),
            quaternions,
            mode,
            max_residual: Cell::new(0.0),
            rank: Cell::new(0),
        })
    }

    fn point<'p>(&'p self, q: &'p [f64], u: &'p [f64], t: f64) -> Point<'p> {
        Point {
            sys: self.sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            t,
        }
    }

    fn closure(&self, q: &[f64], u: &[f64], t: f64) -> Closure {
        let values = run(self.closure, &self.point(q, u, t));
        let m = self
            .closure
            .outputs
            .iter()
            .filter(|(n, _)| n.starts_with("gamma"))
            .count();
        let (mut phi, mut phidot, mut gamma) = (Vec::new(), Vec::new(), Vec::new());
        let mut j = DMatrix::zeros(m, self.nu);
        for ((name, _), v) in self.closure.outputs.iter().zip(values) {
            if let Some(rest) = name.strip_prefix("J_") {
                let mut it = rest.split('_').filter_map(|s| s.parse::<usize>().ok());
                if let (Some(r), Some(c)) = (it.next(), it.next())
                    && r < m
                    && c < self.nu
                {
                    j[(r, c)] = v;
                }
            } else if name.starts_with("phidot") {
                phidot.push(v);
            } else if name.starts_with("phi") {
                phi.push(v);
            } else if name.starts_with("gamma") {
                gamma.push(v);
            }
        }
        Closure {
            phi,
            phidot,
            gamma,
            j,
        }
    }

    fn mass_and_bias(&self, q: &[f64], u: &[f64], t: f64) -> (DMatrix<f64>, DVector<f64>) {
        let x = self.point(q, u, t);
        let lower = self
            .f
            .mass_matrix
            .as_ref()
            .map(|p| run(p, &x))
            .unwrap_or_default();
        let mut m = DMatrix::zeros(self.nu, self.nu);
        let mut k = 0;
        for i in 0..self.nu {
            for j in 0..=i {
                let v = lower.get(k).copied().unwrap_or(f64::NAN);
                m[(i, j)] = v;
                m[(j, i)] = v;
                k += 1;
            }
        }
        let b = self.f.bias.as_ref().map(|p| run(p, &x)).unwrap_or_default();
        (m, DVector::from_vec(b))
    }

    fn pinv_solve(a: &DMatrix<f64>, r: &DVector<f64>) -> (DVector<f64>, usize) {
        let svd = a.clone().svd(true, true);
        let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
        let eps = 1e-10 * largest.max(1e-300);
        let rank = svd.singular_values.iter().filter(|&&s| s > eps).count();
        match svd.solve(r, eps) {
            Ok(x) => (x, rank),
            Err(_) => (DVector::zeros(a.ncols()), rank),
        }
    }

    fn normalize(&self, q: &mut [f64]) {
        for &a in &self.quaternions {
            if let Some(quat) = q.get_mut(a..a + 4) {
                let n = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                if n > 0.0 && n.is_finite() {
                    quat.iter_mut().for_each(|x| *x /= n);
                }
            }
        }
    }
}

impl<const N: usize> eom_sim::OdeSystem<N> for Constrained<'_, N> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let (q, u) = y.split_at(self.nq);
        let qdot = run(&self.f.qdot, &self.point(q, u, t));
        let (m, b) = self.mass_and_bias(q, u, t);
        let c = self.closure(q, u, t);
        let mut gamma = DVector::from_vec(c.gamma);
        if self.mode == Stabilization::Baumgarte {
            let (alpha, beta) = BAUMGARTE;
            for i in 0..gamma.len() {
                gamma[i] -= 2.0 * alpha * c.phidot[i] + beta * beta * c.phi[i];
            }
        }
        let rhs = -b;
        let udot = match m.clone().cholesky() {
            Some(chol) => {
                let minv_f = chol.solve(&rhs);
                let minv_jt = chol.solve(&c.j.transpose());
                let schur = &c.j * &minv_jt;
                let (lambda, _) = Self::pinv_solve(&schur, &(gamma - &c.j * &minv_f));
                minv_f + minv_jt * lambda
            }
            None => DVector::from_element(self.nu, f64::NAN),
        };
        for (d, v) in dy.iter_mut().zip(qdot.iter().chain(udot.iter())) {
            *d = *v;
        }
    }

    fn project(&self, t: f64, y: &mut [f64; N]) -> bool {
        let norm = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let (nq, nu) = (self.nq, self.nu);
        let mut q = y[..nq].to_vec();
        let u = y[nq..].to_vec();
        self.normalize(&mut q);
        let zero = vec![0.0; nu];
        if self.mode == Stabilization::Projection {
            // Positions: Newton with minimum-norm corrections.
            for _ in 0..10 {
                let c = self.closure(&q, &zero, t);
                if norm(&c.phi) < 1e-13 {
                    break;
                }
                let (du, _) = Self::pinv_solve(&c.j, &-DVector::from_vec(c.phi));
                let dq = run(&self.f.qdot, &self.point(&q, du.as_slice(), t));
                for (qi, d) in q.iter_mut().zip(dq) {
                    *qi += d;
                }
                self.normalize(&mut q);
            }
        }
        let c = self.closure(&q, &u, t);
        let (_, rank) = Self::pinv_solve(&c.j, &DVector::zeros(c.j.nrows()));
        self.rank.set(rank);
        self.max_residual
            .set(self.max_residual.get().max(norm(&c.phi)));
        let mut u_new = u.clone();
        if self.mode == Stabilization::Projection {
            // Speeds: the smallest change that makes J u + Φ_t = 0.
            let (du, _) = Self::pinv_solve(&c.j, &-DVector::from_vec(c.phidot));
            for (ui, d) in u_new.iter_mut().zip(du.iter()) {
                *ui += d;
            }
        }
        y[..nq].copy_from_slice(&q);
        y[nq..].copy_from_slice(&u_new);
        true
    }
}
