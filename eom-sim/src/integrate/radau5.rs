//! RADAU5: the 3-stage Radau IIA method of order 5 for stiff systems and
//! index-1 DAEs `M y' = f(t, y)`, following Hairer's `radau5.f` (Hairer &
//! Wanner, *Solving ODEs II*, IV.8): simplified Newton iteration on the
//! transformed stage system (one real and one complex linear system, via
//! the eigen-decomposition `T^{-1} A^{-1} T` of the Radau IIA matrix),
//! embedded error estimate filtered by `(I - h γ0 J)^{-1}`, Gustafsson's
//! predictive step control, and reuse of the Jacobian and of the LU
//! factors when the step size barely changes.
//!
//! The linear algebra is an in-place partial-pivoting LU on statically
//! sized nalgebra matrices (`SMatrix<f64, N, N>` and
//! `SMatrix<Complex<f64>, N, N>`), stored in a box allocated at `init`: no
//! heap allocation per step. The complex system is solved in complex
//! arithmetic, not as a real `2N × 2N` system.

// Coefficients are kept with all the digits Hairer published.
#![allow(clippy::excessive_precision)]

use nalgebra::{Complex, SMatrix};

use super::lu::Lu;

use super::driver::Stepper;
use super::system::OdeSystem;
use super::{Stats, StopReason, UROUND, first_non_finite};

// Transformation matrices T and T^{-1} of radau5.f (T32 = 1, T33 = 0).
const T11: f64 = 9.1232394870892942792e-02;
const T12: f64 = -0.14125529502095420843;
const T13: f64 = -3.0029194105147424492e-02;
const T21: f64 = 0.24171793270710701896;
const T22: f64 = 0.20412935229379993199;
const T23: f64 = 0.38294211275726193779;
const T31: f64 = 0.96604818261509293619;
const TI11: f64 = 4.3255798900631553510;
const TI12: f64 = 0.33919925181580986954;
const TI13: f64 = 0.54177053993587487119;
const TI21: f64 = -4.1787185915519047273;
const TI22: f64 = -0.32768282076106238708;
const TI23: f64 = 0.47662355450055045196;
const TI31: f64 = -0.50287263494578687595;
const TI32: f64 = 2.5719269498556054292;
const TI33: f64 = -0.59603920482822492497;

/// Method constants computed from `sqrt(6)` and cube roots as in radau5.f.
#[derive(Debug, Clone, Copy)]
struct Consts {
    c1: f64,
    c2: f64,
    c1m1: f64,
    c2m1: f64,
    c1mc2: f64,
    dd1: f64,
    dd2: f64,
    dd3: f64,
    /// 1/γ: the real eigenvalue of A^{-1}.
    u1: f64,
    /// α ± iβ: the complex eigenvalues of A^{-1}.
    alph: f64,
    beta: f64,
}

impl Consts {
    fn new() -> Self {
        let sq6 = 6f64.sqrt();
        let c1 = (4.0 - sq6) / 10.0;
        let c2 = (4.0 + sq6) / 10.0;
        let cb81 = 81f64.cbrt();
        let cb9 = 9f64.cbrt();
        let u1 = (6.0 + cb81 - cb9) / 30.0;
        let alph = (12.0 - cb81 + cb9) / 60.0;
        let beta = (cb81 + cb9) * 3f64.sqrt() / 60.0;
        let cno = alph * alph + beta * beta;
        Consts {
            c1,
            c2,
            c1m1: c1 - 1.0,
            c2m1: c2 - 1.0,
            c1mc2: c1 - c2,
            dd1: -(13.0 + 7.0 * sq6) / 3.0,
            dd2: (-13.0 + 7.0 * sq6) / 3.0,
            dd3: -1.0 / 3.0,
            u1: 1.0 / u1,
            alph: alph / cno,
            beta: beta / cno,
        }
    }
}

type Mat<const N: usize> = SMatrix<f64, N, N>;

/// Work space of a run (boxed: it holds four N×N matrices).
struct Work<const N: usize> {
    k: Consts,
    rtol: f64,
    atol: f64,
    fnewt: f64,
    posneg: f64,
    hmaxn: f64,
    t: f64,
    t_prev: f64,
    h: f64,
    hold: f64,
    y: [f64; N],
    fy: [f64; N],
    scal: [f64; N],
    scal_base: [f64; N],
    /// First index-2 and first index-3 component.
    i2: usize,
    i3: usize,
    z1: [f64; N],
    z2: [f64; N],
    z3: [f64; N],
    f1: [f64; N],
    f2: [f64; N],
    f3: [f64; N],
    cont: [[f64; N]; 4],
    jac: Mat<N>,
    mass: Option<Mat<N>>,
    lu1: Lu<f64, N>,
    lu2: Lu<Complex<f64>, N>,
    first: bool,
    reject: bool,
    last: bool,
    caljac: bool,
    need_jac: bool,
    need_lu: bool,
    faccon: f64,
    theta: f64,
    hacc: f64,
    erracc: f64,
    nsing: usize,
    nonfinite: Option<usize>,
}

/// Hairer's RADAU5: implicit Runge–Kutta (Radau IIA, 3 stages, order 5,
/// stage order 3, L-stable) with step-size control for stiff ODEs and
/// index-1 DAEs `M y' = f` (constant `M` from
/// [`OdeSystem::mass_matrix`]).
///
/// Tolerances are transformed internally as in radau5.f:
/// `rtol' = 0.1 rtol^(2/3)`, `atol' = rtol' atol / rtol`.
pub struct Radau5<const N: usize> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// Initial step size; `0.0` means Hairer's default `1e-6`.
    pub h0: f64,
    /// Maximal step size; infinite means `|t_end - t0|`.
    pub hmax: f64,
    /// Maximal Newton iterations per step (`NIT`, 7).
    pub nit: usize,
    /// Safety factor (`SAFE`, 0.9).
    pub safety: f64,
    /// Recompute the Jacobian only when the Newton contraction exceeds this
    /// (`THET`, 0.001).
    pub thet: f64,
    /// Newton stopping tolerance (`FNEWT`); `0.0` means
    /// `max(10 uround / rtol', min(0.03, sqrt(rtol')))`.
    pub fnewt: f64,
    /// Keep step size (and LU) if `h_new / h` lies in `[quot1, quot2]`
    /// (1.0, 1.2).
    pub quot1: f64,
    /// See [`Radau5::quot1`].
    pub quot2: f64,
    /// `h_new / h >= 1 / facl` (`FACL`, 5).
    pub facl: f64,
    /// `h_new / h <= 1 / facr` (`FACR`, 1/8).
    pub facr: f64,
    /// Gustafsson's predictive controller (default) or the classical one.
    pub gustafsson: bool,
    /// Start Newton from zero instead of extrapolating the collocation
    /// polynomial (`STARTN`, false).
    pub zero_start: bool,
    /// Number of index-2 variables of a DAE (`NIND2`): the components
    /// `N - index2_vars - index3_vars .. N - index3_vars`. Their error
    /// weights are divided by `|h|` (Hairer & Wanner II, VII.8).
    pub index2_vars: usize,
    /// Number of index-3 variables (`NIND3`): the last `index3_vars`
    /// components. Their error weights are divided by `h²`.
    pub index3_vars: usize,
    idle: [f64; N],
    w: Option<Box<Work<N>>>,
}

impl<const N: usize> Radau5<N> {
    /// RADAU5 with Hairer's defaults and the given scalar tolerances.
    pub fn new(rtol: f64, atol: f64) -> Self {
        Radau5 {
            rtol,
            atol,
            h0: 0.0,
            hmax: f64::INFINITY,
            nit: 7,
            safety: 0.9,
            thet: 0.001,
            fnewt: 0.0,
            quot1: 1.0,
            quot2: 1.2,
            facl: 5.0,
            facr: 0.125,
            gustafsson: true,
            zero_start: false,
            index2_vars: 0,
            index3_vars: 0,
            idle: [0.0; N],
            w: None,
        }
    }
}

/// Outcome of the simplified Newton iteration.
enum Newton {
    Converged {
        newt: usize,
    },
    /// Too slow: retry with the reduced step (already set).
    Restart,
    /// Divergence, too many iterations or non-finite values.
    Fail,
}

impl<const N: usize> Work<N> {
    fn jacobian<S: OdeSystem<N>>(&mut self, sys: &S, stats: &mut Stats) {
        stats.jac_evals += 1;
        if !sys.jacobian(self.t, &self.y, &mut self.jac) {
            // Forward differences with Hairer's increment.
            let mut yp = self.y;
            let mut fp = [0.0; N];
            for i in 0..N {
                let ysafe = yp[i];
                let delt = (UROUND * 1e-5f64.max(ysafe.abs())).sqrt();
                yp[i] = ysafe + delt;
                sys.rhs(self.t, &yp, &mut fp);
                for j in 0..N {
                    self.jac[(j, i)] = (fp[j] - self.fy[j]) / delt;
                }
                yp[i] = ysafe;
            }
            stats.rhs_evals += N;
        }
        self.caljac = true;
        self.need_jac = false;
        self.need_lu = true;
    }

    /// E1 = (γ0/h)^{-1} M - J (real), E2 = (α + iβ)/h M - J (complex).
    /// Returns false if either is singular.
    fn decompose(&mut self, stats: &mut Stats) -> bool {
        stats.lu_decomps += 1;
        self.need_lu = false;
        let fac1 = self.k.u1 / self.h;
        let alphn = self.k.alph / self.h;
        let betan = self.k.beta / self.h;
        let e1 = &mut self.lu1.a;
        let e2 = &mut self.lu2.a;
        for j in 0..N {
            for i in 0..N {
                let m = match &self.mass {
                    None => {
                        if i == j {
                            1.0
                        } else {
                            0.0
                        }
                    }
                    Some(m) => m[(i, j)],
                };
                let jij = self.jac[(i, j)];
                e1[(i, j)] = fac1 * m - jij;
                e2[(i, j)] = Complex::new(alphn * m - jij, betan * m);
            }
        }
        let ok1 = self.lu1.factor();
        let ok2 = self.lu2.factor();
        ok1 && ok2
    }

    fn solve_real(&self, v: &mut [f64; N]) {
        self.lu1.solve(v);
    }

    /// `v ← M v` (identity if there is no mass matrix).
    fn mass_mul(&self, v: &[f64; N]) -> [f64; N] {
        match &self.mass {
            None => *v,
            Some(m) => {
                let mut out = [0.0; N];
                for i in 0..N {
                    let mut s = 0.0;
                    for j in 0..N {
                        s += m[(i, j)] * v[j];
                    }
                    out[i] = s;
                }
                out
            }
        }
    }

    /// Hairer's SLVRAD: solves for the Newton increments of the
    /// transformed stage values; on entry z1..z3 hold `T^{-1} F(Z)`.
    fn slvrad(&mut self) {
        let fac1 = self.k.u1 / self.h;
        let alphn = self.k.alph / self.h;
        let betan = self.k.beta / self.h;
        let mf1 = self.mass_mul(&self.f1);
        let mf2 = self.mass_mul(&self.f2);
        let mf3 = self.mass_mul(&self.f3);
        for i in 0..N {
            let s2 = -mf2[i];
            let s3 = -mf3[i];
            self.z1[i] -= mf1[i] * fac1;
            self.z2[i] += s2 * alphn - s3 * betan;
            self.z3[i] += s3 * alphn + s2 * betan;
        }
        let mut z1 = self.z1;
        self.solve_real(&mut z1);
        self.z1 = z1;
        let mut b = [Complex::new(0.0, 0.0); N];
        for i in 0..N {
            b[i] = Complex::new(self.z2[i], self.z3[i]);
        }
        self.lu2.solve(&mut b);
        for i in 0..N {
            self.z2[i] = b[i].re;
            self.z3[i] = b[i].im;
        }
    }

    fn scaled_norm(&self, v: &[f64; N]) -> f64 {
        let mut s = 0.0;
        for i in 0..N {
            s += (v[i] / self.scal[i]).powi(2);
        }
        (s / N.max(1) as f64).sqrt()
    }

    /// Hairer's ESTRAD: `err = ‖(I - h γ0 J)^{-1}-filtered (γ0 h f(y0) +
    /// Σ e_i Z_i)‖`, with a second filtering at `f(y0 + err)` on the first
    /// step and after rejections (to suppress the stiff components).
    fn estrad<S: OdeSystem<N>>(&mut self, sys: &S, stats: &mut Stats) -> f64 {
        let hee1 = self.k.dd1 / self.h;
        let hee2 = self.k.dd2 / self.h;
        let hee3 = self.k.dd3 / self.h;
        let mut f1 = [0.0; N];
        for i in 0..N {
            f1[i] = hee1 * self.z1[i] + hee2 * self.z2[i] + hee3 * self.z3[i];
        }
        let f2 = self.mass_mul(&f1);
        let mut cont = [0.0; N];
        for i in 0..N {
            cont[i] = f2[i] + self.fy[i];
        }
        self.solve_real(&mut cont);
        let mut err = self.scaled_norm(&cont).max(1e-10);
        if err >= 1.0 && (self.first || self.reject) {
            for i in 0..N {
                cont[i] += self.y[i];
            }
            let mut fc = [0.0; N];
            sys.rhs(self.t, &cont, &mut fc);
            stats.rhs_evals += 1;
            for i in 0..N {
                cont[i] = fc[i] + f2[i];
            }
            self.solve_real(&mut cont);
            err = self.scaled_norm(&cont).max(1e-10);
        }
        if err.is_nan() { f64::INFINITY } else { err }
    }

    fn update_scal(&mut self) {
        for i in 0..N {
            self.scal_base[i] = self.atol + self.rtol * self.y[i].abs();
        }
        self.scale_for_index();
    }

    /// Error weights of index-2 / index-3 variables scaled by `1/|h|` and
    /// `1/h²` for the current step size.
    fn scale_for_index(&mut self) {
        let h = self.h.abs();
        for i in 0..N {
            self.scal[i] = if i >= self.i3 {
                self.scal_base[i] / (h * h)
            } else if i >= self.i2 {
                self.scal_base[i] / h
            } else {
                self.scal_base[i]
            };
        }
    }

    fn newton<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        nit: usize,
        thet: f64,
        stats: &mut Stats,
    ) -> Newton {
        let k = self.k;
        let t = self.t;
        let h = self.h;
        let mut newt = 0;
        self.faccon = self.faccon.max(UROUND).powf(0.8);
        self.theta = thet.abs();
        let mut dynold = 0.0;
        let mut thqold = 0.0;
        let mut yt = [0.0; N];
        loop {
            if newt >= nit {
                return Newton::Fail;
            }
            let mut fz1 = [0.0; N];
            let mut fz2 = [0.0; N];
            let mut fz3 = [0.0; N];
            for i in 0..N {
                yt[i] = self.y[i] + self.z1[i];
            }
            sys.rhs(t + k.c1 * h, &yt, &mut fz1);
            for i in 0..N {
                yt[i] = self.y[i] + self.z2[i];
            }
            sys.rhs(t + k.c2 * h, &yt, &mut fz2);
            for i in 0..N {
                yt[i] = self.y[i] + self.z3[i];
            }
            sys.rhs(t + h, &yt, &mut fz3);
            stats.rhs_evals += 3;
            if let Some(c) = first_non_finite(&fz1)
                .or_else(|| first_non_finite(&fz2))
                .or_else(|| first_non_finite(&fz3))
            {
                self.nonfinite = Some(c);
                return Newton::Fail;
            }
            for i in 0..N {
                let (a1, a2, a3) = (fz1[i], fz2[i], fz3[i]);
                self.z1[i] = TI11 * a1 + TI12 * a2 + TI13 * a3;
                self.z2[i] = TI21 * a1 + TI22 * a2 + TI23 * a3;
                self.z3[i] = TI31 * a1 + TI32 * a2 + TI33 * a3;
            }
            self.slvrad();
            stats.newton_iters += 1;
            newt += 1;
            let mut dyno = 0.0;
            for i in 0..N {
                let d = self.scal[i];
                dyno +=
                    (self.z1[i] / d).powi(2) + (self.z2[i] / d).powi(2) + (self.z3[i] / d).powi(2);
            }
            let dyno = (dyno / (3 * N).max(1) as f64).sqrt();
            if !dyno.is_finite() {
                return Newton::Fail;
            }
            if newt > 1 && newt < nit {
                let thq = dyno / dynold;
                self.theta = if newt == 2 {
                    thq
                } else {
                    (thq * thqold).sqrt()
                };
                thqold = thq;
                if self.theta < 0.99 {
                    self.faccon = self.theta / (1.0 - self.theta);
                    let dyth =
                        self.faccon * dyno * self.theta.powi((nit - 1 - newt) as i32) / self.fnewt;
                    if dyth >= 1.0 {
                        // Convergence too slow for the remaining iterations:
                        // shrink the step by the predicted factor.
                        let qnewt = dyth.clamp(1e-4, 20.0);
                        let hhfac = 0.8 * qnewt.powf(-1.0 / (4.0 + nit as f64 - 1.0 - newt as f64));
                        self.h *= hhfac;
                        self.reject = true;
                        self.last = false;
                        return Newton::Restart;
                    }
                } else {
                    return Newton::Fail;
                }
            }
            dynold = dyno.max(UROUND);
            for i in 0..N {
                let f1i = self.f1[i] + self.z1[i];
                let f2i = self.f2[i] + self.z2[i];
                let f3i = self.f3[i] + self.z3[i];
                self.f1[i] = f1i;
                self.f2[i] = f2i;
                self.f3[i] = f3i;
                self.z1[i] = T11 * f1i + T12 * f2i + T13 * f3i;
                self.z2[i] = T21 * f1i + T22 * f2i + T23 * f3i;
                self.z3[i] = T31 * f1i + f2i;
            }
            if self.faccon * dyno <= self.fnewt {
                return Newton::Converged { newt };
            }
        }
    }
}

impl<const N: usize> Stepper<N> for Radau5<N> {
    fn init<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t0: f64,
        y0: &[f64; N],
        t_end: f64,
        _dense: bool,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        // Tolerance transformation of radau5.f.
        let expm = 2.0 / 3.0;
        let quot = self.atol / self.rtol;
        let rtol = 0.1 * self.rtol.powf(expm);
        let atol = rtol * quot;
        let fnewt = if self.fnewt > 0.0 {
            self.fnewt
        } else {
            (10.0 * UROUND / rtol).max(0.03f64.min(rtol.sqrt()))
        };
        let posneg = if t_end >= t0 { 1.0 } else { -1.0 };
        let hmaxn = if self.hmax.is_finite() {
            self.hmax.abs().min((t_end - t0).abs())
        } else {
            (t_end - t0).abs()
        };
        let mut h = if self.h0.abs() <= 10.0 * UROUND {
            1e-6
        } else {
            self.h0.abs()
        };
        h = h.min(hmaxn) * posneg;
        let mut last = false;
        if (t0 + h * 1.0001 - t_end) * posneg >= 0.0 {
            h = t_end - t0;
            last = true;
        }
        let mut mass = Mat::<N>::zeros();
        let mass = if sys.mass_matrix(&mut mass) {
            Some(mass)
        } else {
            None
        };
        let mut w = Box::new(Work {
            k: Consts::new(),
            rtol,
            atol,
            fnewt,
            posneg,
            hmaxn,
            t: t0,
            t_prev: t0,
            h,
            hold: h,
            y: *y0,
            fy: [0.0; N],
            scal: [0.0; N],
            scal_base: [0.0; N],
            i3: N - self.index3_vars.min(N),
            i2: N - (self.index2_vars + self.index3_vars).min(N),
            z1: [0.0; N],
            z2: [0.0; N],
            z3: [0.0; N],
            f1: [0.0; N],
            f2: [0.0; N],
            f3: [0.0; N],
            cont: [[0.0; N]; 4],
            jac: Mat::<N>::zeros(),
            mass,
            lu1: Lu::zeros(),
            lu2: Lu::zeros(),
            first: true,
            reject: false,
            last,
            caljac: false,
            need_jac: true,
            need_lu: true,
            faccon: 1.0,
            theta: 0.0,
            hacc: 0.0,
            erracc: 0.0,
            nsing: 0,
            nonfinite: None,
        });
        w.cont[0] = *y0;
        w.update_scal();
        sys.rhs(t0, y0, &mut w.fy);
        stats.rhs_evals += 1;
        if let Some(component) = first_non_finite(&w.fy) {
            return Err(StopReason::NonFinite { t: t0, component });
        }
        self.w = Some(w);
        Ok(())
    }

    fn step<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t_end: f64,
        max_steps: usize,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        let Some(w) = self.w.as_deref_mut() else {
            return Err(StopReason::Finished);
        };
        let nit = self.nit.max(1);
        let cfac = self.safety * (1 + 2 * nit) as f64;
        loop {
            if w.need_jac {
                w.jacobian(sys, stats);
            }
            if w.need_lu && !w.decompose(stats) {
                // Singular iteration matrix: halve the step (label 78).
                w.nsing += 1;
                if w.nsing >= 5 {
                    return Err(StopReason::ConvergenceFailure { t: w.t });
                }
                w.h *= 0.5;
                w.reject = true;
                w.last = false;
                w.need_lu = true;
                w.need_jac = !w.caljac;
                stats.rejected += 1;
                if 0.1 * w.h.abs() <= w.t.abs() * UROUND {
                    return Err(StopReason::StepSizeTooSmall { t: w.t, h: w.h });
                }
                continue;
            }
            if stats.steps >= max_steps {
                return Err(StopReason::MaxSteps { t: w.t });
            }
            if 0.1 * w.h.abs() <= w.t.abs() * UROUND || w.h == 0.0 || !w.h.is_finite() {
                if let Some(component) = w.nonfinite {
                    return Err(StopReason::NonFinite { t: w.t, component });
                }
                return Err(StopReason::StepSizeTooSmall { t: w.t, h: w.h });
            }
            stats.steps += 1;
            if w.i2 < N {
                w.scale_for_index();
            }
            let h = w.h;
            let t = w.t;
            let tph = t + h;
            // Starting values: zero, or the previous collocation polynomial
            // extrapolated to the new stage times.
            if w.first || self.zero_start {
                w.z1 = [0.0; N];
                w.z2 = [0.0; N];
                w.z3 = [0.0; N];
                w.f1 = [0.0; N];
                w.f2 = [0.0; N];
                w.f3 = [0.0; N];
            } else {
                let k = w.k;
                let c3q = h / w.hold;
                let c1q = k.c1 * c3q;
                let c2q = k.c2 * c3q;
                for i in 0..N {
                    let ak1 = w.cont[1][i];
                    let ak2 = w.cont[2][i];
                    let ak3 = w.cont[3][i];
                    let z1i = c1q * (ak1 + (c1q - k.c2m1) * (ak2 + (c1q - k.c1m1) * ak3));
                    let z2i = c2q * (ak1 + (c2q - k.c2m1) * (ak2 + (c2q - k.c1m1) * ak3));
                    let z3i = c3q * (ak1 + (c3q - k.c2m1) * (ak2 + (c3q - k.c1m1) * ak3));
                    w.z1[i] = z1i;
                    w.z2[i] = z2i;
                    w.z3[i] = z3i;
                    w.f1[i] = TI11 * z1i + TI12 * z2i + TI13 * z3i;
                    w.f2[i] = TI21 * z1i + TI22 * z2i + TI23 * z3i;
                    w.f3[i] = TI31 * z1i + TI32 * z2i + TI33 * z3i;
                }
            }
            let newt = match w.newton(sys, nit, self.thet, stats) {
                Newton::Converged { newt } => newt,
                Newton::Restart => {
                    stats.rejected += 1;
                    w.need_lu = true;
                    w.need_jac = !w.caljac;
                    continue;
                }
                Newton::Fail => {
                    // Unexpected rejection (label 78): halve the step.
                    stats.rejected += 1;
                    w.h *= 0.5;
                    w.reject = true;
                    w.last = false;
                    w.need_lu = true;
                    w.need_jac = !w.caljac;
                    continue;
                }
            };
            w.nonfinite = None;
            let err = w.estrad(sys, stats);
            // h_new = h / quot with quot = clamp(err^(1/4) / fac, facr, facl).
            let fac = self.safety.min(cfac / (newt + 2 * nit) as f64);
            let mut quot = self.facr.max(self.facl.min(err.powf(0.25) / fac));
            let mut hnew = h / quot;
            if err < 1.0 {
                w.first = false;
                stats.accepted += 1;
                if self.gustafsson {
                    // Predictive controller of Gustafsson (1994).
                    if stats.accepted > 1 {
                        let facgus = (w.hacc / h) * (err * err / w.erracc).powf(0.25) / self.safety;
                        let facgus = self.facr.max(self.facl.min(facgus));
                        quot = quot.max(facgus);
                        hnew = h / quot;
                    }
                    w.hacc = h;
                    w.erracc = err.max(1e-2);
                }
                let k = w.k;
                w.t_prev = t;
                w.hold = h;
                w.t = if w.last { t_end } else { tph };
                for i in 0..N {
                    w.y[i] += w.z3[i];
                    let z1i = w.z1[i];
                    let z2i = w.z2[i];
                    w.cont[1][i] = (z2i - w.z3[i]) / k.c2m1;
                    let ak = (z1i - z2i) / k.c1mc2;
                    let acont3 = (ak - z1i / k.c1) / k.c2;
                    w.cont[2][i] = (ak - w.cont[1][i]) / k.c1m1;
                    w.cont[3][i] = w.cont[2][i] - acont3;
                }
                w.cont[0] = w.y;
                w.update_scal();
                w.caljac = false;
                if w.last {
                    return Ok(());
                }
                let (tt, yy) = (w.t, w.y);
                sys.rhs(tt, &yy, &mut w.fy);
                stats.rhs_evals += 1;
                hnew = w.posneg * hnew.abs().min(w.hmaxn);
                if w.reject {
                    hnew = w.posneg * hnew.abs().min(h.abs());
                }
                w.reject = false;
                if (w.t + hnew / self.quot1 - t_end) * w.posneg >= 0.0 {
                    w.h = t_end - w.t;
                    w.last = true;
                } else {
                    let qt = hnew / h;
                    if w.theta <= self.thet && qt >= self.quot1 && qt <= self.quot2 {
                        // Keep h, Jacobian and LU factors.
                        return Ok(());
                    }
                    w.h = hnew;
                }
                w.need_lu = true;
                w.need_jac = w.theta > self.thet;
                return Ok(());
            } else {
                w.reject = true;
                w.last = false;
                w.h = if w.first { h * 0.1 } else { hnew };
                stats.rejected += 1;
                w.need_lu = true;
                w.need_jac = !w.caljac;
            }
        }
    }

    fn t(&self) -> f64 {
        self.w.as_ref().map_or(0.0, |w| w.t)
    }

    fn t_prev(&self) -> f64 {
        self.w.as_ref().map_or(0.0, |w| w.t_prev)
    }

    fn y(&self) -> &[f64; N] {
        self.w.as_ref().map_or(&self.idle, |w| &w.y)
    }

    /// Collocation polynomial of the last step, with `s = (t - t_new) / h`:
    /// `c0 + s(c1 + (s - c2 + 1)(c2' + (s - c1 + 1) c3))`.
    fn dense(&self, t: f64, out: &mut [f64; N]) {
        let Some(w) = &self.w else { return };
        let s = (t - w.t) / w.hold;
        let k = &w.k;
        for i in 0..N {
            out[i] = w.cont[0][i]
                + s * (w.cont[1][i] + (s - k.c2m1) * (w.cont[2][i] + (s - k.c1m1) * w.cont[3][i]));
        }
    }

    fn reset_state<S: OdeSystem<N>>(&mut self, sys: &S, y: &[f64; N], stats: &mut Stats) {
        if let Some(w) = self.w.as_deref_mut() {
            w.y = *y;
            w.update_scal();
            let t = w.t;
            sys.rhs(t, y, &mut w.fy);
            stats.rhs_evals += 1;
        }
    }
}
