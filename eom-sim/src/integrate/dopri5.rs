//! DOPRI5: the Dormand–Prince 5(4) pair with Hairer's step-size control,
//! stiffness detection and Shampine's 4th-order dense output, following
//! Hairer's `dopri5.f` (Hairer, Nørsett & Wanner, *Solving ODEs I*, II.4,
//! II.5, II.6 and IV.2 for the stiffness test).

use super::driver::Stepper;
use super::system::OdeSystem;
use super::{ExplicitConfig, Stats, StopReason, UROUND, first_non_finite, hinit, weight};

// Butcher tableau (Dormand & Prince 1980), as in dopri5.f.
pub(crate) const C2: f64 = 0.2;
pub(crate) const C3: f64 = 0.3;
pub(crate) const C4: f64 = 0.8;
pub(crate) const C5: f64 = 8.0 / 9.0;
pub(crate) const A21: f64 = 0.2;
pub(crate) const A31: f64 = 3.0 / 40.0;
pub(crate) const A32: f64 = 9.0 / 40.0;
pub(crate) const A41: f64 = 44.0 / 45.0;
pub(crate) const A42: f64 = -56.0 / 15.0;
pub(crate) const A43: f64 = 32.0 / 9.0;
pub(crate) const A51: f64 = 19372.0 / 6561.0;
pub(crate) const A52: f64 = -25360.0 / 2187.0;
pub(crate) const A53: f64 = 64448.0 / 6561.0;
pub(crate) const A54: f64 = -212.0 / 729.0;
pub(crate) const A61: f64 = 9017.0 / 3168.0;
pub(crate) const A62: f64 = -355.0 / 33.0;
pub(crate) const A63: f64 = 46732.0 / 5247.0;
pub(crate) const A64: f64 = 49.0 / 176.0;
pub(crate) const A65: f64 = -5103.0 / 18656.0;
pub(crate) const A71: f64 = 35.0 / 384.0;
pub(crate) const A73: f64 = 500.0 / 1113.0;
pub(crate) const A74: f64 = 125.0 / 192.0;
pub(crate) const A75: f64 = -2187.0 / 6784.0;
pub(crate) const A76: f64 = 11.0 / 84.0;
// Error coefficients b - b̂ (5th minus 4th order weights).
pub(crate) const E1: f64 = 71.0 / 57600.0;
pub(crate) const E3: f64 = -71.0 / 16695.0;
pub(crate) const E4: f64 = 71.0 / 1920.0;
pub(crate) const E5: f64 = -17253.0 / 339200.0;
pub(crate) const E6: f64 = 22.0 / 525.0;
pub(crate) const E7: f64 = -1.0 / 40.0;
// Dense output of Shampine (1986).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

impl ExplicitConfig {
    /// Hairer's DOPRI5 defaults: safety 0.9, `h_new/h` in [0.2, 10],
    /// beta 0.04, stiffness test every 1000 steps.
    pub fn dopri5(rtol: f64, atol: f64) -> Self {
        ExplicitConfig {
            rtol,
            atol,
            h0: 0.0,
            hmax: f64::INFINITY,
            safety: 0.9,
            fac_min: 0.2,
            fac_max: 10.0,
            beta: 0.04,
            nstiff: 1000,
            stop_on_stiffness: false,
        }
    }

    /// Hairer's DOP853 defaults: safety 0.9, `h_new/h` in [0.333, 6],
    /// beta 0, stiffness test every 1000 steps.
    pub fn dop853(rtol: f64, atol: f64) -> Self {
        ExplicitConfig {
            fac_min: 0.333,
            fac_max: 6.0,
            beta: 0.0,
            ..ExplicitConfig::dopri5(rtol, atol)
        }
    }
}

/// Step-size controller state shared by DOPRI5 and DOP853 (Hairer's PI
/// controller with Lund stabilisation and the stiffness counter).
#[derive(Debug, Clone)]
pub(crate) struct Control {
    pub posneg: f64,
    pub hmax: f64,
    pub h: f64,
    pub facold: f64,
    pub reject: bool,
    pub last: bool,
    pub iasti: usize,
    pub nonsti: usize,
    pub nonfinite: Option<usize>,
}

/// Outcome of the error test.
pub(crate) enum Verdict {
    Accept { hnew: f64 },
    Reject,
}

impl Control {
    pub fn new() -> Self {
        Control {
            posneg: 1.0,
            hmax: 0.0,
            h: 0.0,
            facold: 1e-4,
            reject: false,
            last: false,
            iasti: 0,
            nonsti: 0,
            nonfinite: None,
        }
    }

    /// Checks before an attempt; clamps the step to land on `t_end`.
    pub fn pre_step(
        &mut self,
        t: f64,
        t_end: f64,
        max_steps: usize,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        if stats.steps >= max_steps {
            return Err(StopReason::MaxSteps { t });
        }
        if 0.1 * self.h.abs() <= t.abs() * UROUND || self.h == 0.0 || !self.h.is_finite() {
            if let Some(component) = self.nonfinite {
                return Err(StopReason::NonFinite { t, component });
            }
            return Err(StopReason::StepSizeTooSmall { t, h: self.h });
        }
        if (t + 1.01 * self.h - t_end) * self.posneg > 0.0 {
            self.h = t_end - t;
            self.last = true;
        }
        stats.steps += 1;
        Ok(())
    }

    /// Hairer's controller: `fac11 = err^expo1`, `fac = fac11 / facold^beta`,
    /// `h_new = h / clamp(fac / safe, 1/fac_max, 1/fac_min)`; on rejection
    /// `h_new = h / min(1/fac_min, fac11 / safe)`.
    pub fn decide(
        &mut self,
        err: f64,
        expo1: f64,
        cfg: &ExplicitConfig,
        stats: &mut Stats,
    ) -> Verdict {
        let facc1 = 1.0 / cfg.fac_min;
        let facc2 = 1.0 / cfg.fac_max;
        let err = if err.is_nan() { f64::INFINITY } else { err };
        let fac11 = err.powf(expo1);
        if err <= 1.0 {
            let fac = fac11 / self.facold.powf(cfg.beta);
            let fac = facc2.max(facc1.min(fac / cfg.safety));
            let mut hnew = self.h / fac;
            self.facold = err.max(1e-4);
            if hnew.abs() > self.hmax {
                hnew = self.posneg * self.hmax;
            }
            if self.reject {
                hnew = self.posneg * hnew.abs().min(self.h.abs());
            }
            self.reject = false;
            self.nonfinite = None;
            stats.accepted += 1;
            Verdict::Accept { hnew }
        } else {
            self.h /= facc1.min(fac11 / cfg.safety);
            self.reject = true;
            self.last = false;
            stats.rejected += 1;
            Verdict::Reject
        }
    }

    /// Hairer's stiffness test: `h λ ≈ h |Δf| / |Δy|` between the last two
    /// stages at `t + h`; stiff after 15 consecutive values above the
    /// stability-boundary threshold, cleared after 6 below.
    pub fn stiffness(
        &mut self,
        hlamb: f64,
        threshold: f64,
        t: f64,
        cfg: &ExplicitConfig,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        if hlamb > threshold {
            self.nonsti = 0;
            self.iasti += 1;
            if self.iasti == 15 {
                stats.stiffness_detections += 1;
                if stats.stiff_at.is_none() {
                    stats.stiff_at = Some(t);
                }
                self.iasti = 0;
                if cfg.stop_on_stiffness {
                    return Err(StopReason::StiffnessDetected { t });
                }
            }
        } else {
            self.nonsti += 1;
            if self.nonsti == 6 {
                self.iasti = 0;
            }
        }
        Ok(())
    }

    /// Whether the stiffness test runs after this accepted step.
    pub fn test_stiffness(&self, cfg: &ExplicitConfig, stats: &Stats) -> bool {
        cfg.nstiff > 0 && (stats.accepted.is_multiple_of(cfg.nstiff) || self.iasti > 0)
    }

    /// Initial step: user value or HINIT.
    #[allow(clippy::too_many_arguments)]
    pub fn init<const N: usize, S: OdeSystem<N>>(
        &mut self,
        cfg: &ExplicitConfig,
        sys: &S,
        t0: f64,
        y0: &[f64; N],
        f0: &[f64; N],
        t_end: f64,
        order: i32,
        stats: &mut Stats,
    ) {
        *self = Control::new();
        self.posneg = if t_end >= t0 { 1.0 } else { -1.0 };
        self.hmax = if cfg.hmax.is_finite() {
            cfg.hmax.abs()
        } else {
            (t_end - t0).abs()
        };
        self.h = if cfg.h0 != 0.0 {
            cfg.h0.abs().min(self.hmax) * self.posneg
        } else {
            hinit(
                sys,
                t0,
                y0,
                f0,
                self.posneg,
                order,
                self.hmax,
                cfg.rtol,
                cfg.atol,
                stats,
            )
        };
    }
}

/// Hairer's DOPRI5: explicit Runge–Kutta pair of orders 5(4) (Dormand &
/// Prince), FSAL, 6 `f` evaluations per step, local extrapolation, PI step
/// control with `beta = 0.04`, 4th-order dense output at no extra cost,
/// stiffness detection (`|h λ| > 3.25`).
#[derive(Debug, Clone)]
pub struct Dopri5<const N: usize> {
    /// Tolerances and controller parameters.
    pub cfg: ExplicitConfig,
    ctl: Control,
    t: f64,
    t_prev: f64,
    h_prev: f64,
    y: [f64; N],
    k1: [f64; N],
    cont: [[f64; N]; 5],
}

impl<const N: usize> Dopri5<N> {
    /// DOPRI5 with Hairer's defaults and the given scalar tolerances.
    pub fn new(rtol: f64, atol: f64) -> Self {
        Self::with_config(ExplicitConfig::dopri5(rtol, atol))
    }

    /// DOPRI5 with an explicit configuration.
    pub fn with_config(cfg: ExplicitConfig) -> Self {
        Dopri5 {
            cfg,
            ctl: Control::new(),
            t: 0.0,
            t_prev: 0.0,
            h_prev: 0.0,
            y: [0.0; N],
            k1: [0.0; N],
            cont: [[0.0; N]; 5],
        }
    }
}

impl<const N: usize> Stepper<N> for Dopri5<N> {
    fn init<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t0: f64,
        y0: &[f64; N],
        t_end: f64,
        _dense: bool,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        self.t = t0;
        self.t_prev = t0;
        self.y = *y0;
        sys.rhs(t0, y0, &mut self.k1);
        stats.rhs_evals += 1;
        if let Some(component) = first_non_finite(&self.k1) {
            return Err(StopReason::NonFinite { t: t0, component });
        }
        self.ctl
            .init(&self.cfg, sys, t0, y0, &self.k1, t_end, 5, stats);
        self.cont = [*y0; 5];
        Ok(())
    }

    fn step<S: OdeSystem<N>>(
        &mut self,
        sys: &S,
        t_end: f64,
        max_steps: usize,
        stats: &mut Stats,
    ) -> Result<(), StopReason> {
        let cfg = &self.cfg;
        let expo1 = 0.2 - cfg.beta * 0.75;
        let y = self.y;
        let k1 = self.k1;
        let mut k2 = [0.0; N];
        let mut k3 = [0.0; N];
        let mut k4 = [0.0; N];
        let mut k5 = [0.0; N];
        let mut k6 = [0.0; N];
        let mut k7 = [0.0; N];
        let mut y1 = [0.0; N];
        let mut ysti = [0.0; N];
        loop {
            let t = self.t;
            self.ctl.pre_step(t, t_end, max_steps, stats)?;
            let h = self.ctl.h;
            for i in 0..N {
                y1[i] = y[i] + h * A21 * k1[i];
            }
            sys.rhs(t + C2 * h, &y1, &mut k2);
            for i in 0..N {
                y1[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i]);
            }
            sys.rhs(t + C3 * h, &y1, &mut k3);
            for i in 0..N {
                y1[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
            }
            sys.rhs(t + C4 * h, &y1, &mut k4);
            for i in 0..N {
                y1[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
            }
            sys.rhs(t + C5 * h, &y1, &mut k5);
            for i in 0..N {
                ysti[i] = y[i]
                    + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
            }
            let tph = t + h;
            sys.rhs(tph, &ysti, &mut k6);
            for i in 0..N {
                y1[i] = y[i]
                    + h * (A71 * k1[i] + A73 * k3[i] + A74 * k4[i] + A75 * k5[i] + A76 * k6[i]);
            }
            sys.rhs(tph, &y1, &mut k7);
            stats.rhs_evals += 6;
            // err = sqrt(mean((h Σ e_j k_j / (atol + rtol max(|y0|, |y1|)))^2))
            let mut err = 0.0;
            for i in 0..N {
                let e = h
                    * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
                err += (e / weight(cfg.atol, cfg.rtol, y[i], y1[i])).powi(2);
            }
            let mut err = (err / N.max(1) as f64).sqrt();
            if let Some(i) = first_non_finite(&y1).or_else(|| first_non_finite(&k7)) {
                self.ctl.nonfinite = Some(i);
                err = f64::INFINITY;
            }
            match self.ctl.decide(err, expo1, cfg, stats) {
                Verdict::Reject => continue,
                Verdict::Accept { hnew } => {
                    if self.ctl.test_stiffness(cfg, stats) {
                        let mut stnum = 0.0;
                        let mut stden = 0.0;
                        for i in 0..N {
                            stnum += (k7[i] - k6[i]).powi(2);
                            stden += (y1[i] - ysti[i]).powi(2);
                        }
                        if stden > 0.0 {
                            let hlamb = h.abs() * (stnum / stden).sqrt();
                            self.ctl.stiffness(hlamb, 3.25, t, cfg, stats)?;
                        }
                    }
                    for i in 0..N {
                        let ydiff = y1[i] - y[i];
                        let bspl = h * k1[i] - ydiff;
                        self.cont[0][i] = y[i];
                        self.cont[1][i] = ydiff;
                        self.cont[2][i] = bspl;
                        self.cont[3][i] = ydiff - h * k7[i] - bspl;
                        self.cont[4][i] = h
                            * (D1 * k1[i]
                                + D3 * k3[i]
                                + D4 * k4[i]
                                + D5 * k5[i]
                                + D6 * k6[i]
                                + D7 * k7[i]);
                    }
                    self.t_prev = t;
                    self.h_prev = h;
                    self.t = if self.ctl.last { t_end } else { tph };
                    self.y = y1;
                    self.k1 = k7;
                    self.ctl.h = hnew;
                    return Ok(());
                }
            }
        }
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

    /// `y(t_old + θh) = c0 + θ(c1 + (1-θ)(c2 + θ(c3 + (1-θ) c4)))`.
    fn dense(&self, t: f64, out: &mut [f64; N]) {
        let s = (t - self.t_prev) / self.h_prev;
        let s1 = 1.0 - s;
        let c = &self.cont;
        for i in 0..N {
            out[i] = c[0][i] + s * (c[1][i] + s1 * (c[2][i] + s * (c[3][i] + s1 * c[4][i])));
        }
    }

    fn reset_state<S: OdeSystem<N>>(&mut self, sys: &S, y: &[f64; N], stats: &mut Stats) {
        self.y = *y;
        sys.rhs(self.t, y, &mut self.k1);
        stats.rhs_evals += 1;
    }
}
