//! Geometric integrators for long conservative runs.
//!
//! * [`ImplicitMidpoint`]: `y1 = y0 + h f(t0 + h/2, (y0 + y1)/2)`. Order 2,
//!   symmetric, symplectic for Hamiltonian systems, and it preserves every
//!   quadratic invariant `yᵀ C y` of `y' = f(y)` exactly (up to round-off
//!   and the Newton tolerance): angular momentum of a rigid body, the norm
//!   of a quaternion under `q' = ½ q ⊗ ω`, `L = q × p` for central forces.
//!   Energy (not quadratic in general) is not conserved exactly but its
//!   error stays bounded over exponentially long times (backward error
//!   analysis, Hairer–Lubich–Wanner, *Geometric Numerical Integration*).
//! * [`stormer_verlet`]: velocity Verlet for `q'' = a(t, q)`. Order 2,
//!   explicit, symmetric and symplectic for separable `H = ½|v|² + V(q)`;
//!   conserves linear and angular momentum exactly when the force does,
//!   and has bounded energy error.

use nalgebra::SMatrix;

use super::driver::Stepper;
use super::fixed::{hermite, uniform_steps};
use super::lu::Lu;
use super::system::OdeSystem;
use super::{Stats, StopReason, UROUND, first_non_finite};

/// The implicit midpoint rule with fixed step, solved by simplified Newton
/// iterations on the midpoint `w = (y0 + y1)/2`,
/// `(I - h/2 J) Δ = -(w - y0 - h/2 f(t0 + h/2, w))`, with `J` (analytic or
/// finite differences) evaluated once per step at `y0`, iterated to
/// round-off. Dense output: cubic Hermite.
pub struct ImplicitMidpoint<const N: usize> {
    /// Nominal step size (see [`Rk4`](crate::Rk4) for how it is fitted to
    /// the interval).
    pub h: f64,
    /// Maximal Newton iterations per step (default 50).
    pub max_iter: usize,
    n: usize,
    k: usize,
    t0: f64,
    hs: f64,
    t: f64,
    t_prev: f64,
    y: [f64; N],
    y_prev: [f64; N],
    f: [f64; N],
    f_prev: [f64; N],
    jac: Option<Box<SMatrix<f64, N, N>>>,
    lu: Option<Box<Lu<f64, N>>>,
}

impl<const N: usize> ImplicitMidpoint<N> {
    /// Implicit midpoint with nominal step `h`.
    pub fn new(h: f64) -> Self {
        ImplicitMidpoint {
            h,
            max_iter: 50,
            n: 0,
            k: 0,
            t0: 0.0,
            hs: 0.0,
            t: 0.0,
            t_prev: 0.0,
            y: [0.0; N],
            y_prev: [0.0; N],
            f: [0.0; N],
            f_prev: [0.0; N],
            jac: None,
            lu: None,
        }
    }
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| m.max(x.abs()))
}

impl<const N: usize> Stepper<N> for ImplicitMidpoint<N> {
    fn init<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t0: f64,
        y0: &[f64; N],
        t_end: f64,
        _dense: bool,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        if !(self.h.is_finite() && self.h != 0.0) {
            return Err(StopReason::StepSizeTooSmall { t: t0, h: self.h });
        }
        let (n, hs) = uniform_steps(t0, t_end, self.h);
        self.n = n;
        self.hs = hs;
        self.k = 0;
        self.t0 = t0;
        self.t = t0;
        self.t_prev = t0;
        self.y = *y0;
        self.y_prev = *y0;
        sys.rhs(t0, y0, &mut self.f);
        stats.rhs_evals += 1;
        if let Some(component) = first_non_finite(&self.f) {
            return Err(StopReason::NonFinite { t: t0, component });
        }
        self.f_prev = self.f;
        self.jac = Some(Box::new(SMatrix::zeros()));
        self.lu = Some(Box::new(Lu::zeros()));
        Ok(())
    }

    fn step<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t_end: f64,
        max_steps: usize,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        if stats.steps >= max_steps {
            return Err(StopReason::MaxSteps { t: self.t });
        }
        stats.steps += 1;
        let t0 = self.t;
        let t1 = if self.k + 1 == self.n {
            t_end
        } else {
            self.t0 + (self.k + 1) as f64 * self.hs
        };
        let h = t1 - t0;
        let tm = t0 + 0.5 * h;
        let y0 = self.y;
        let jac = self.jac.get_or_insert_with(|| Box::new(SMatrix::zeros()));
        stats.jac_evals += 1;
        if !sys.jacobian(t0, &y0, jac) {
            let mut yp = y0;
            let mut fp = [0.0; N];
            for i in 0..N {
                let delt = (UROUND * 1e-5f64.max(y0[i].abs())).sqrt();
                yp[i] = y0[i] + delt;
                sys.rhs(t0, &yp, &mut fp);
                for j in 0..N {
                    jac[(j, i)] = (fp[j] - self.f[j]) / delt;
                }
                yp[i] = y0[i];
            }
            stats.rhs_evals += N;
        }
        let lu = self.lu.get_or_insert_with(|| Box::new(Lu::zeros()));
        for j in 0..N {
            for i in 0..N {
                lu.a[(i, j)] = if i == j { 1.0 } else { 0.0 } - 0.5 * h * jac[(i, j)];
            }
        }
        stats.lu_decomps += 1;
        if !lu.factor() {
            return Err(StopReason::ConvergenceFailure { t: t0 });
        }
        // Midpoint w, started from an explicit Euler half step.
        let mut w = [0.0; N];
        for i in 0..N {
            w[i] = y0[i] + 0.5 * h * self.f[i];
        }
        let mut fw = [0.0; N];
        let mut prev = f64::INFINITY;
        let mut converged = false;
        for it in 0..self.max_iter.max(1) {
            sys.rhs(tm, &w, &mut fw);
            stats.rhs_evals += 1;
            stats.newton_iters += 1;
            if let Some(component) = first_non_finite(&fw) {
                return Err(StopReason::NonFinite { t: t0, component });
            }
            let mut r = [0.0; N];
            for i in 0..N {
                r[i] = -(w[i] - y0[i] - 0.5 * h * fw[i]);
            }
            lu.solve(&mut r);
            for i in 0..N {
                w[i] += r[i];
            }
            let d = max_abs(&r);
            let scale = max_abs(&w).max(1.0);
            // Converged at round-off, or stagnating at round-off level.
            if d <= 2.0 * UROUND * scale || (it >= 2 && d >= prev && d <= 1e-10 * scale) {
                converged = true;
                break;
            }
            prev = d;
        }
        if !converged {
            return Err(StopReason::ConvergenceFailure { t: t0 });
        }
        self.y_prev = y0;
        self.f_prev = self.f;
        for i in 0..N {
            self.y[i] = 2.0 * w[i] - y0[i];
        }
        if let Some(component) = first_non_finite(&self.y) {
            return Err(StopReason::NonFinite { t: t0, component });
        }
        sys.rhs(t1, &self.y, &mut self.f);
        stats.rhs_evals += 1;
        stats.accepted += 1;
        self.t_prev = t0;
        self.t = t1;
        self.k += 1;
        Ok(())
    }

    fn t(&self) -> f64 {
        self.t
    }

    fn t_prev(&self) -> f64 {
        self.t_prev
    }

    fn y(&self) -> &[f64; N] {
        &self.y
    }

    fn dense(&self, t: f64, out: &mut [f64; N]) {
        hermite(
            self.t_prev,
            self.t - self.t_prev,
            &self.y_prev,
            &self.f_prev,
            &self.y,
            &self.f,
            t,
            out,
        );
    }

    fn reset_state<S: OdeSystem<N>>(&mut self, sys: &S, y: &[f64; N], stats: &mut Stats) {
        self.y = *y;
        sys.rhs(self.t, y, &mut self.f);
        stats.rhs_evals += 1;
    }
}

/// A second-order system `q'' = a(t, q)` with `D` coordinates (forces
/// independent of velocity), for [`stormer_verlet`].
pub trait SecondOrderSystem<const D: usize> {
    /// Writes the acceleration `a(t, q)`.
    fn accel(&self, t: f64, q: &[f64; D], a: &mut [f64; D]);
}

/// Result of [`stormer_verlet`].
#[derive(Debug, Clone)]
pub struct VerletSolution<const D: usize> {
    /// Recorded times.
    pub t: Vec<f64>,
    /// Positions at [`VerletSolution::t`].
    pub q: Vec<[f64; D]>,
    /// Velocities at [`VerletSolution::t`].
    pub v: Vec<[f64; D]>,
    /// Counters (`rhs_evals` counts acceleration evaluations).
    pub stats: Stats,
    /// Why the run stopped.
    pub stop: StopReason,
}

/// Störmer–Verlet (velocity Verlet) with fixed step `h` (fitted to the
/// interval as for [`Rk4`](crate::Rk4)):
/// `v½ = v + h/2 a(t, q)`, `q1 = q + h v½`, `v1 = v½ + h/2 a(t + h, q1)`.
/// One acceleration evaluation per step. Records every `record_every`-th
/// step (and the last); stops with [`StopReason::NonFinite`] on overflow.
pub fn stormer_verlet<const D: usize, S: SecondOrderSystem<D>>(
    sys: &S,
    t0: f64,
    q0: [f64; D],
    v0: [f64; D],
    t_end: f64,
    h: f64,
    record_every: usize,
) -> VerletSolution<D> {
    let mut out = VerletSolution {
        t: vec![t0],
        q: vec![q0],
        v: vec![v0],
        stats: Stats::default(),
        stop: StopReason::Finished,
    };
    if t_end == t0 {
        return out;
    }
    if !(h.is_finite() && h != 0.0) {
        out.stop = StopReason::StepSizeTooSmall { t: t0, h };
        return out;
    }
    let (n, hs) = uniform_steps(t0, t_end, h);
    let every = record_every.max(1);
    let (mut q, mut v) = (q0, v0);
    let mut a = [0.0; D];
    sys.accel(t0, &q, &mut a);
    out.stats.rhs_evals += 1;
    let mut t = t0;
    for k in 1..=n {
        let t1 = if k == n { t_end } else { t0 + k as f64 * hs };
        let hk = t1 - t;
        for i in 0..D {
            v[i] += 0.5 * hk * a[i];
            q[i] += hk * v[i];
        }
        sys.accel(t1, &q, &mut a);
        for i in 0..D {
            v[i] += 0.5 * hk * a[i];
        }
        out.stats.rhs_evals += 1;
        out.stats.steps += 1;
        out.stats.accepted += 1;
        t = t1;
        if let Some(component) =
            first_non_finite(&q).or_else(|| first_non_finite(&v).map(|i| i + D))
        {
            out.stop = StopReason::NonFinite { t, component };
            return out;
        }
        if k % every == 0 || k == n {
            out.t.push(t);
            out.q.push(q);
            out.v.push(v);
        }
    }
    out
}
