//! Shared test problems and helpers.
#![allow(dead_code)]
// Published constants keep all their digits.
#![allow(clippy::excessive_precision)]

use eom_sim::{Dop853, Dopri5, ExplicitConfig, OdeSystem, Radau5};

/// Least-squares slope of log(err) against log(h).
pub fn slope(h: &[f64], err: &[f64]) -> f64 {
    let n = h.len() as f64;
    let x: Vec<f64> = h.iter().map(|v| v.ln()).collect();
    let y: Vec<f64> = err.iter().map(|v| v.ln()).collect();
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

/// y' = -y + sin t, y(0) = 1; exact y = 3/2 e^{-t} + (sin t - cos t)/2.
pub struct Forced;

impl OdeSystem<1> for Forced {
    fn rhs(&self, t: f64, y: &[f64; 1], dy: &mut [f64; 1]) {
        dy[0] = -y[0] + t.sin();
    }
}

pub fn forced_exact(t: f64) -> f64 {
    1.5 * (-t).exp() + 0.5 * (t.sin() - t.cos())
}

/// Arenstorf orbit (Hairer–Nørsett–Wanner I, II.0), periodic with period
/// `ARENSTORF_T`.
pub struct Arenstorf;

pub const ARENSTORF_MU: f64 = 0.012277471;
pub const ARENSTORF_Y0: [f64; 4] = [0.994, 0.0, 0.0, -2.00158510637908252240537862224];
pub const ARENSTORF_T: f64 = 17.0652165601579625588917206249;

impl OdeSystem<4> for Arenstorf {
    fn rhs(&self, _t: f64, y: &[f64; 4], dy: &mut [f64; 4]) {
        let mu = ARENSTORF_MU;
        let mup = 1.0 - mu;
        let r1 = ((y[0] + mu).powi(2) + y[1] * y[1]).powf(1.5);
        let r2 = ((y[0] - mup).powi(2) + y[1] * y[1]).powf(1.5);
        dy[0] = y[2];
        dy[1] = y[3];
        dy[2] = y[0] + 2.0 * y[3] - mup * (y[0] + mu) / r1 - mu * (y[0] - mup) / r2;
        dy[3] = y[1] - 2.0 * y[2] - mup * y[1] / r1 - mu * y[1] / r2;
    }
}

/// Van der Pol in Hairer's scaled form: y1' = y2, ε y2' = (1 - y1²) y2 - y1.
pub struct VanDerPol {
    pub eps: f64,
    pub analytic_jacobian: bool,
}

impl OdeSystem<2> for VanDerPol {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        dy[0] = y[1];
        dy[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / self.eps;
    }
    fn jacobian(&self, _t: f64, y: &[f64; 2], j: &mut nalgebra::SMatrix<f64, 2, 2>) -> bool {
        if !self.analytic_jacobian {
            return false;
        }
        j[(0, 0)] = 0.0;
        j[(0, 1)] = 1.0;
        j[(1, 0)] = (-2.0 * y[0] * y[1] - 1.0) / self.eps;
        j[(1, 1)] = (1.0 - y[0] * y[0]) / self.eps;
        true
    }
}

/// Robertson's chemical kinetics (k1 = 0.04, k2 = 3e7, k3 = 1e4).
pub struct Robertson;

impl OdeSystem<3> for Robertson {
    fn rhs(&self, _t: f64, y: &[f64; 3], dy: &mut [f64; 3]) {
        let a = 0.04 * y[0];
        let b = 1e4 * y[1] * y[2];
        let c = 3e7 * y[1] * y[1];
        dy[0] = -a + b;
        dy[1] = a - b - c;
        dy[2] = c;
    }
}

/// DOPRI5 forced to constant steps `h` (tolerances huge, h_new/h pinned to 1).
pub fn dopri5_fixed<const N: usize>(h: f64) -> Dopri5<N> {
    let mut cfg = ExplicitConfig::dopri5(1e10, 1e10);
    cfg.h0 = h;
    cfg.hmax = h;
    cfg.fac_min = 1.0;
    cfg.fac_max = 1.0;
    cfg.nstiff = 0;
    Dopri5::with_config(cfg)
}

/// DOP853 forced to constant steps `h`.
pub fn dop853_fixed<const N: usize>(h: f64) -> Dop853<N> {
    let mut cfg = ExplicitConfig::dop853(1e10, 1e10);
    cfg.h0 = h;
    cfg.hmax = h;
    cfg.fac_min = 1.0;
    cfg.fac_max = 1.0;
    cfg.nstiff = 0;
    Dop853::with_config(cfg)
}

/// RADAU5 forced to constant steps `h` (quot pinned to 1, Newton iterated
/// to 1e-13 so the iteration error does not pollute the discretisation
/// error).
pub fn radau5_fixed<const N: usize>(h: f64) -> Radau5<N> {
    let mut r = Radau5::new(1.0, 1.0);
    r.h0 = h;
    r.hmax = h;
    r.facl = 1.0;
    r.facr = 1.0;
    r.fnewt = 1e-12;
    r.nit = 30;
    r
}
