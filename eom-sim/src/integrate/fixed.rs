//! Fixed-step explicit methods: explicit Euler (teaching baseline) and the
//! classical fourth-order Runge–Kutta method.
//!
//! Both take `n = ceil(|t_end - t0| / h)` equal steps of size
//! `(t_end - t0) / n` (so the run ends exactly on `t_end`; `n` is rounded
//! instead when `|t_end - t0| / h` is within 1e-9 of an integer).

use super::driver::Stepper;
use super::system::OdeSystem;
use super::{Stats, StopReason};

/// Number of equal steps and their signed size.
pub(crate) fn uniform_steps(t0: f64, t_end: f64, h: f64) -> (usize, f64) {
    let r = ((t_end - t0) / h).abs();
    let n = if (r - r.round()).abs() <= 1e-9 * r.max(1.0) {
        r.round()
    } else {
        r.ceil()
    }
    .max(1.0) as usize;
    (n, (t_end - t0) / n as f64)
}

/// Cubic Hermite interpolation on `[t0, t0 + h]` from values and
/// derivatives at both ends (local error O(h^4)).
#[inline]
#[allow(clippy::too_many_arguments)]
pub(crate) fn hermite<const N: usize>(
    t0: f64,
    h: f64,
    y0: &[f64; N],
    f0: &[f64; N],
    y1: &[f64; N],
    f1: &[f64; N],
    t: f64,
    out: &mut [f64; N],
) {
    let s = (t - t0) / h;
    let s2 = s * s;
    let s3 = s2 * s;
    let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    let h10 = s3 - 2.0 * s2 + s;
    let h01 = -2.0 * s3 + 3.0 * s2;
    let h11 = s3 - s2;
    for i in 0..N {
        out[i] = h00 * y0[i] + h * h10 * f0[i] + h01 * y1[i] + h * h11 * f1[i];
    }
}

/// The classical fourth-order Runge–Kutta step of `y' = f(t, y)`, written
/// once for every storage: `[f64; N]` (compiled models, where it inlines to
/// the same straight loops) and `Vec<f64>` (element models,
/// [`crate::large::integrate_rk4`]).
///
/// The step runs from `t0` to `t1`; `k1 = f(t0, y0)` is given; `k` receives `k2, k3, k4`, `yt` is scratch,
/// and `y` receives `y(t0 + h)`. Three calls of `f`.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn rk4_tableau<V: AsRef<[f64]> + AsMut<[f64]>>(
    t0: f64,
    t1: f64,
    y0: &V,
    k1: &V,
    k: &mut [V; 3],
    yt: &mut V,
    y: &mut V,
    mut f: impl FnMut(f64, &V, &mut V),
) {
    let stage = |yt: &mut V, a: f64, ki: &V| {
        for ((t, y), k) in yt.as_mut().iter_mut().zip(y0.as_ref()).zip(ki.as_ref()) {
            *t = y + a * k;
        }
    };
    let h = t1 - t0;
    let [k2, k3, k4] = k;
    stage(yt, 0.5 * h, k1);
    f(t0 + 0.5 * h, yt, k2);
    stage(yt, 0.5 * h, k2);
    f(t0 + 0.5 * h, yt, k3);
    stage(yt, h, k3);
    f(t1, yt, k4);
    let (k1, k2, k3, k4) = (k1.as_ref(), k2.as_ref(), k3.as_ref(), k4.as_ref());
    for (i, yi) in y.as_mut().iter_mut().enumerate() {
        *yi = y0.as_ref()[i] + h / 6.0 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
    }
}

/// State shared by the fixed-step explicit methods.
#[derive(Debug, Clone)]
struct FixedState<const N: usize> {
    t0: f64,
    h: f64,
    n: usize,
    k: usize,
    t: f64,
    t_prev: f64,
    y: [f64; N],
    y_prev: [f64; N],
    f: [f64; N],
    f_prev: [f64; N],
}

impl<const N: usize> FixedState<N> {
    fn new() -> Self {
        FixedState {
            t0: 0.0,
            h: 0.0,
            n: 0,
            k: 0,
            t: 0.0,
            t_prev: 0.0,
            y: [0.0; N],
            y_prev: [0.0; N],
            f: [0.0; N],
            f_prev: [0.0; N],
        }
    }

    fn init<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t0: f64,
        y0: &[f64; N],
        t_end: f64,
        h: f64,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        if !(h.is_finite() && h != 0.0) {
            return Err(StopReason::StepSizeTooSmall { t: t0, h });
        }
        let (n, h) = uniform_steps(t0, t_end, h);
        self.t0 = t0;
        self.h = h;
        self.n = n;
        self.k = 0;
        self.t = t0;
        self.t_prev = t0;
        self.y = *y0;
        self.y_prev = *y0;
        sys.rhs(t0, y0, &mut self.f);
        stats.rhs_evals += 1;
        self.f_prev = self.f;
        Ok(())
    }

    /// Time after step `k` (exact at the end).
    fn time(&self, k: usize, t_end: f64) -> f64 {
        if k == self.n {
            t_end
        } else {
            self.t0 + k as f64 * self.h
        }
    }
}

/// Explicit Euler, `y1 = y0 + h f(t0, y0)`: order 1. Only a teaching
/// baseline. Dense output: cubic Hermite.
#[derive(Debug, Clone)]
pub struct Euler<const N: usize> {
    /// Nominal step size.
    pub h: f64,
    st: FixedState<N>,
}

impl<const N: usize> Euler<N> {
    /// Explicit Euler with nominal step `h`.
    pub fn new(h: f64) -> Self {
        Euler {
            h,
            st: FixedState::new(),
        }
    }
}

/// Classical Runge–Kutta method of order 4 (stages at 0, 1/2, 1/2, 1;
/// weights 1/6, 1/3, 1/3, 1/6). Four `f` evaluations per step (the last
/// one is reused as the next step's first stage and for the cubic Hermite
/// dense output of order 3).
#[derive(Debug, Clone)]
pub struct Rk4<const N: usize> {
    /// Nominal step size.
    pub h: f64,
    st: FixedState<N>,
}

impl<const N: usize> Rk4<N> {
    /// RK4 with nominal step `h`.
    pub fn new(h: f64) -> Self {
        Rk4 {
            h,
            st: FixedState::new(),
        }
    }
}

macro_rules! fixed_common {
    () => {
        fn init<S: OdeSystem<N>>(
            &mut self,
            sys: &S,
            t0: f64,
            y0: &[f64; N],
            t_end: f64,
            _dense: bool,
            stats: &mut Stats,
        ) -> Result<(), StopReason> {
            self.st.init(sys, t0, y0, t_end, self.h, stats)
        }
        fn t(&self) -> f64 {
            self.st.t
        }
        fn t_prev(&self) -> f64 {
            self.st.t_prev
        }
        fn y(&self) -> &[f64; N] {
            &self.st.y
        }
        fn dense(&self, t: f64, out: &mut [f64; N]) {
            let s = &self.st;
            hermite(
                s.t_prev,
                s.t - s.t_prev,
                &s.y_prev,
                &s.f_prev,
                &s.y,
                &s.f,
                t,
                out,
            );
        }
        fn reset_state<S: OdeSystem<N>>(&mut self, sys: &S, y: &[f64; N], stats: &mut Stats) {
            self.st.y = *y;
            sys.rhs(self.st.t, y, &mut self.st.f);
            stats.rhs_evals += 1;
        }
    };
}

impl<const N: usize> Stepper<N> for Euler<N> {
    fixed_common!();

    fn step<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t_end: f64,
        max_steps: usize,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        let s = &mut self.st;
        if stats.steps >= max_steps {
            return Err(StopReason::MaxSteps { t: s.t });
        }
        let t1 = s.time(s.k + 1, t_end);
        let h = t1 - s.t;
        s.y_prev = s.y;
        s.f_prev = s.f;
        for i in 0..N {
            s.y[i] += h * s.f[i];
        }
        sys.rhs(t1, &s.y, &mut s.f);
        stats.rhs_evals += 1;
        stats.steps += 1;
        stats.accepted += 1;
        s.t_prev = s.t;
        s.t = t1;
        s.k += 1;
        Ok(())
    }
}

impl<const N: usize> Stepper<N> for Rk4<N> {
    fixed_common!();

    fn step<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t_end: f64,
        max_steps: usize,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        let s = &mut self.st;
        if stats.steps >= max_steps {
            return Err(StopReason::MaxSteps { t: s.t });
        }
        let t0 = s.t;
        let t1 = s.time(s.k + 1, t_end);
        let y0 = s.y;
        let k1 = s.f;
        let mut k = [[0.0; N]; 3];
        let mut yt = [0.0; N];
        rk4_tableau(t0, t1, &y0, &k1, &mut k, &mut yt, &mut s.y, |t, y, f| {
            sys.rhs(t, y, f)
        });
        s.y_prev = y0;
        s.f_prev = k1;
        sys.rhs(t1, &s.y, &mut s.f);
        stats.rhs_evals += 4;
        stats.steps += 1;
        stats.accepted += 1;
        s.t_prev = t0;
        s.t = t1;
        s.k += 1;
        Ok(())
    }
}
