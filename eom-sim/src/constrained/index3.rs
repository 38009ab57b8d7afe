//! [`Index3System`]: a constrained model as the index-3 DAE in
//! `(q, u, λ)` for [`Radau5`](crate::Radau5).

use super::stats::{Recorder, weighted_singular_ratio};
use super::system::ConstrainedSystem;
use super::{ConstraintStats, ConstraintValues, DMatrix, DVector, Dynamics, Method, Refusal};
use crate::{OdeSystem, SMatrix};

/// [`Method::Index3`] refuses to go on when `σ_r/σ_1` of `J M^{-1/2}` falls
/// below this at an accepted state: near a rank drop of `J` the index-3
/// DAE's multipliers are undetermined along the vanishing direction, and
/// RADAU5 either crosses to another motion (the four-bar at loose
/// tolerances: energy off by 3e-4) or its Newton iteration fails (at
/// tight ones).
pub const INDEX3_SINGULAR_LIMIT: f64 = 5e-2;

/// The index-3 DAE `q̇ = N(q) u`, `u̇ = M⁻¹(Jᵀλ − b)`, `0 = Φ(q, t)` (and
/// `0 = Φ̇` for nonholonomic rows) for [`Radau5`](crate::Radau5) with the
/// mass matrix `diag(I, I, 0)`, on `y = (q, u, λ_nonholonomic, λ_holonomic)`;
/// `N = n_q + n_u + m`. Set the integrator's index variables with
/// [`Index3System::index_vars`]. Redundant equations make its Newton
/// matrix singular: use a multiplier method for them.
pub struct Index3System<'a, D: ?Sized> {
    d: &'a D,
    stats: Recorder,
    start_rank: std::cell::Cell<Option<usize>>,
    derivatives: Option<&'a Derivatives<'a>>,
}

/// The generated derivatives of forward dynamics at an extra force `τ`:
/// `(t, q, u, τ, out)` fills `out` with `∂u̇/∂q`, `∂u̇/∂u` and `∂u̇/∂τ =
/// M⁻¹` (each `NU × NU` by rows, then any input block), `false` if they
/// cannot be evaluated.
pub type Derivatives<'a> = dyn Fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> bool + 'a;

impl<'a, D: Dynamics + ?Sized> Index3System<'a, D> {
    /// The DAE of `d`.
    pub fn new(d: &'a D) -> Self {
        Index3System {
            d,
            stats: Recorder::new(),
            start_rank: std::cell::Cell::new(None),
            derivatives: None,
        }
    }

    /// The same DAE with its Jacobian from the generated derivatives of
    /// forward dynamics instead of differences of the right-hand side, where
    /// [`Index3System::has_generated_jacobian`] holds (see
    /// [`OdeSystem::jacobian`] below).
    pub fn with_derivatives(mut self, derivatives: &'a Derivatives<'a>) -> Self {
        self.derivatives = Some(derivatives);
        self
    }

    /// Whether a model of this shape can have the generated Jacobian: every
    /// constraint holonomic and `q̇ = u` (no quaternions).
    pub fn has_generated_jacobian(d: &D) -> bool {
        d.nc() == d.n_holonomic() && d.nq() == d.nu() && d.quaternions().is_empty()
    }

    /// Why the run was stopped, if the DAE refused to go on (near a
    /// singular configuration, see [`INDEX3_SINGULAR_LIMIT`]).
    pub fn refusal(&self) -> Option<Refusal> {
        self.stats.0.borrow().0.refusal.clone()
    }

    /// (index-2 variables, index-3 variables) for
    /// [`Radau5::index2_vars`](crate::Radau5::index2_vars) and
    /// [`Radau5::index3_vars`](crate::Radau5::index3_vars).
    pub fn index_vars(&self) -> (usize, usize) {
        let (nu, nc, nh) = (self.d.nu(), self.d.nc(), self.d.n_holonomic());
        let speeds = if nh > 0 { nu } else { 0 };
        (speeds + nc - nh, nh)
    }

    /// The initial state `(q, u, λ)` from a consistent `(q, u)`, with `λ`
    /// from the multipliers; `None` if `N` is not `n_q + n_u + m` or `M` is
    /// singular.
    pub fn initial<const N: usize>(&self, t: f64, q: &[f64], u: &[f64]) -> Option<[f64; N]> {
        let (nq, nu, nc, nh) = (self.d.nq(), self.d.nu(), self.d.nc(), self.d.n_holonomic());
        if N != nq + nu + nc {
            return None;
        }
        let sys = ConstrainedSystem::new(self.d, Method::Projection);
        let (_, lambda) = sys.accelerations(t, q, u)?;
        let mut y = [0.0; N];
        y[..nq].copy_from_slice(q.get(..nq)?);
        y[nq..nq + nu].copy_from_slice(u.get(..nu)?);
        for (k, l) in lambda.iter().enumerate() {
            y[self.slot(k, nq + nu, nc, nh)] = *l;
        }
        Some(y)
    }

    /// Where `λ_k` sits in `y`.
    fn slot(&self, k: usize, base: usize, nc: usize, nh: usize) -> usize {
        if k < nh {
            base + nc - nh + k
        } else {
            base + k - nh
        }
    }

    /// `λ` in the model's equation order from a state.
    pub fn multipliers<const N: usize>(&self, y: &[f64; N]) -> Vec<f64> {
        let (nq, nu, nc, nh) = (self.d.nq(), self.d.nu(), self.d.nc(), self.d.n_holonomic());
        (0..nc)
            .map(|k| {
                y.get(self.slot(k, nq + nu, nc, nh))
                    .copied()
                    .unwrap_or(f64::NAN)
            })
            .collect()
    }

    /// What was seen along the run so far.
    pub fn stats(&self) -> ConstraintStats {
        self.stats.stats()
    }
}

impl<const N: usize, D: Dynamics + ?Sized> OdeSystem<N> for Index3System<'_, D> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        if self.stats.0.borrow().0.refusal.is_some() {
            // Refused (see `project`): the run stops here.
            dy.iter_mut().for_each(|d| *d = f64::NAN);
            return;
        }
        let d = self.d;
        let (nq, nu, nc, nh) = (d.nq(), d.nu(), d.nc(), d.n_holonomic());
        let q = &y[..nq];
        let u = &y[nq..nq + nu];
        let lambda = DVector::from_iterator(nc, self.multipliers(y));
        let mut m = DMatrix::zeros(nu, nu);
        let mut b = DVector::zeros(nu);
        let mut c = ConstraintValues::zeros(nc, nu);
        d.mass_matrix(t, q, &mut m);
        d.bias(t, q, u, &mut b);
        d.constraints(t, q, u, &mut c);
        d.qdot(q, u, &mut dy[..nq]);
        let force = c.jacobian.transpose() * lambda - b;
        match m.cholesky() {
            Some(chol) => {
                let a = chol.solve(&force);
                dy[nq..nq + nu]
                    .iter_mut()
                    .zip(a.iter())
                    .for_each(|(d, s)| *d = *s);
            }
            None => dy[nq..nq + nu].iter_mut().for_each(|d| *d = f64::NAN),
        }
        for k in 0..nc {
            let residual = if k < nh { c.phi[k] } else { c.phidot[k] };
            dy[self.slot(k, nq + nu, nc, nh)] = residual;
        }
    }

    /// `∂f/∂y` of `f = (u, M⁻¹(Jᵀλ − b), Φ)` on `y = (q, u, λ)` from the
    /// generated derivatives, for models with holonomic constraints only and
    /// `q̇ = u`:
    ///
    /// ```text
    ///        q                       u          λ
    /// q̇   [  0                       I          0        ]
    /// u̇   [  D_q(τ) + M⁻¹ ∂(Jᵀλ)/∂q  D_u(τ)     M⁻¹ Jᵀ   ]
    /// Φ   [  J                       0          0        ]
    /// ```
    ///
    /// with `D_q`, `D_u`, `M⁻¹` the generated `forward_dynamics_derivatives`
    /// at `τ = Jᵀλ`, and `∂(Jᵀλ)/∂q` (the constraints' curvature, `Σ λ_k
    /// ∂²Φ_k/∂q²`) by central differences of the generated `J`, `2 n_q`
    /// evaluations of the constraints. `false` (RADAU5 then differences the
    /// right-hand side) without derivatives or where they fail.
    fn jacobian(&self, t: f64, y: &[f64; N], jac: &mut SMatrix<f64, N, N>) -> bool {
        let Some(derivatives) = self.derivatives else {
            return false;
        };
        let d = self.d;
        let (nq, nu, nc) = (d.nq(), d.nu(), d.nc());
        if !Self::has_generated_jacobian(d) || N != nq + nu + nc {
            return false;
        }
        let q = &y[..nq];
        let u = &y[nq..nq + nu];
        let lambda = DVector::from_iterator(nc, self.multipliers(y));
        let mut c = ConstraintValues::zeros(nc, nu);
        d.constraints(t, q, u, &mut c);
        let tau = c.jacobian.transpose() * &lambda;
        let mut flat = vec![0.0; 3 * nu * nu];
        if !derivatives(t, q, u, tau.as_slice(), &mut flat) || flat.iter().any(|x| !x.is_finite()) {
            return false;
        }
        let block =
            |k: usize| DMatrix::from_row_slice(nu, nu, &flat[k * nu * nu..(k + 1) * nu * nu]);
        let (dq, du, minv) = (block(0), block(1), block(2));
        // ∂(Jᵀλ)/∂q by central differences of J.
        let mut curvature = DMatrix::zeros(nu, nq);
        let mut qh = q.to_vec();
        let mut cp = ConstraintValues::zeros(nc, nu);
        for j in 0..nq {
            let h = f64::EPSILON.cbrt() * q[j].abs().max(1.0);
            qh[j] = q[j] + h;
            d.constraints(t, &qh, u, &mut cp);
            let plus = cp.jacobian.transpose() * &lambda;
            qh[j] = q[j] - h;
            d.constraints(t, &qh, u, &mut cp);
            let minus = cp.jacobian.transpose() * &lambda;
            qh[j] = q[j];
            curvature.set_column(j, &((plus - minus) / (2.0 * h)));
        }
        let dq = dq + &minv * curvature;
        let dlambda = &minv * c.jacobian.transpose();
        jac.fill(0.0);
        for i in 0..nu {
            jac[(i, nq + i)] = 1.0;
            for j in 0..nq {
                jac[(nq + i, j)] = dq[(i, j)];
            }
            for j in 0..nu {
                jac[(nq + i, nq + j)] = du[(i, j)];
            }
            for k in 0..nc {
                jac[(nq + i, self.slot(k, nq + nu, nc, nc))] = dlambda[(i, k)];
            }
        }
        for k in 0..nc {
            let row = self.slot(k, nq + nu, nc, nc);
            for j in 0..nq {
                jac[(row, j)] = c.jacobian[(k, j)];
            }
        }
        jac.iter().all(|x| x.is_finite())
    }

    fn mass_matrix(&self, m: &mut SMatrix<f64, N, N>) -> bool {
        let n = self.d.nq() + self.d.nu();
        m.fill(0.0);
        for i in 0..n.min(N) {
            m[(i, i)] = 1.0;
        }
        true
    }

    fn project(&self, t: f64, y: &mut [f64; N]) -> bool {
        let d = self.d;
        let (nq, nu) = (d.nq(), d.nu());
        d.normalize(&mut y[..nq]);
        let mut c = ConstraintValues::zeros(d.nc(), nu);
        d.constraints(t, &y[..nq], &y[nq..nq + nu], &mut c);
        self.stats.record(d.n_holonomic(), &c);
        if d.nc() > 0 && self.stats.0.borrow().0.refusal.is_none() {
            let ratio = weighted_singular_ratio(d, t, &y[..nq], &self.start_rank);
            if ratio < INDEX3_SINGULAR_LIMIT {
                self.stats.0.borrow_mut().0.refusal = Some(Refusal::SingularConfiguration {
                    method: "index3",
                    t,
                    singular_ratio: ratio,
                    recommended: "projection or partitioning",
                });
            }
        }
        !d.quaternions().is_empty()
    }
}
