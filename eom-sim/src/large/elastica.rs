//! Reference solutions of the planar elastica (a cantilever clamped at the
//! origin along `+x`, a dead force at its free end), for tests and
//! benchmarks of the ANCF elements:
//!
//! - [`extensible_cantilever`]: the extensible elastica (Reissner's planar
//!   beam without shear: axial strain `ε = N/EA`, moment `EI κ` with `κ`
//!   the rotation's rate per reference length), the same strain measures
//!   as Gerstmayr and Irschik's cable, solved as a boundary value problem
//!   by shooting on the root moment with DOP853 at tolerance 1e-13;
//! - [`extensible_cantilever_distributed`]: the same under a uniform dead
//!   load per unit reference length (shooting as above);
//! - [`mattiasson`]: the inextensible elastica under a transverse end load
//!   in closed form by elliptic integrals (Mattiasson 1981), with the
//!   incomplete integrals by Carlson's symmetric forms.
//!
//! Equations of the extensible elastica, `X` the reference arc length,
//! `θ` the section's rotation, `F` the end force (constant section force):
//! `θ' = m/EI`, `m' = (1 + ε) (F_x sin θ − F_y cos θ)`,
//! `x' = (1 + ε) cos θ`, `y' = (1 + ε) sin θ`, `ε = (F_x cos θ + F_y sin θ)/EA`;
//! `θ(0) = x(0) = y(0) = 0`, `m(L) = 0`.

use crate::{Dop853, FnSystem, SolveOptions, StopReason, integrate};

/// Tip of a cantilever.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tip {
    /// Tip position `x`.
    pub x: f64,
    /// Tip position `y`.
    pub y: f64,
    /// Tip rotation (rad, counter-clockwise).
    pub theta: f64,
    /// Root moment `m(0)`.
    pub root_moment: f64,
}

fn shoot(l: f64, ea: f64, ei: f64, f: [f64; 2], m0: f64) -> Option<[f64; 4]> {
    let sys = FnSystem(move |_x: f64, y: &[f64; 4], dy: &mut [f64; 4]| {
        let (s, c) = y[0].sin_cos();
        let eps = if ea.is_finite() {
            (f[0] * c + f[1] * s) / ea
        } else {
            0.0
        };
        dy[0] = y[1] / ei;
        dy[1] = (1.0 + eps) * (f[0] * s - f[1] * c);
        dy[2] = (1.0 + eps) * c;
        dy[3] = (1.0 + eps) * s;
    });
    let mut method = Dop853::new(1e-13, 1e-15);
    let opts = SolveOptions {
        record_steps: false,
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut method,
        &sys,
        0.0,
        [0.0, m0, 0.0, 0.0],
        l,
        &opts,
        &mut [],
    );
    matches!(sol.stop, StopReason::Finished).then_some(sol.y_final)
}

fn secant(l: f64, ea: f64, ei: f64, f: [f64; 2], guess: f64) -> Option<f64> {
    let scale = (f[0].abs() + f[1].abs()) * l;
    let mut m_a = guess;
    let mut r_a = shoot(l, ea, ei, f, m_a)?[1];
    let mut m_b = guess * (1.0 + 1e-3) + 1e-6 * scale;
    let mut r_b = shoot(l, ea, ei, f, m_b)?[1];
    for _ in 0..100 {
        if r_b.abs() <= 1e-14 * scale || r_b == r_a {
            break;
        }
        let m_c = m_b - r_b * (m_b - m_a) / (r_b - r_a);
        let r_c = shoot(l, ea, ei, f, m_c)?[1];
        (m_a, r_a, m_b, r_b) = (m_b, r_b, m_c, r_c);
    }
    (r_b.abs() <= 1e-10 * scale).then_some(m_b)
}

/// The extensible elastica: tip of a cantilever of length `l`, axial
/// stiffness `ea` (`f64::INFINITY`: inextensible), bending stiffness `ei`,
/// under the end force `f`. The load is applied in steps (continuation of
/// the root moment), each solved by the secant method. `None` if shooting
/// fails.
pub fn extensible_cantilever(l: f64, ea: f64, ei: f64, f: [f64; 2]) -> Option<Tip> {
    let load = (f[0].abs() + f[1].abs()) * l * l / ei;
    let steps = (2.0 * load).ceil().max(1.0) as usize;
    let mut m = 0.0;
    for k in 1..=steps {
        let s = k as f64 / steps as f64;
        let fk = [s * f[0], s * f[1]];
        let guess = if k == 1 {
            fk[1] * l
        } else {
            m * k as f64 / (k - 1) as f64
        };
        m = secant(l, ea, ei, fk, guess)?;
    }
    let y = shoot(l, ea, ei, f, m)?;
    Some(Tip {
        x: y[2],
        y: y[3],
        theta: y[0],
        root_moment: m,
    })
}

/// Carlson's `R_F(x, y, z)`.
fn carlson_rf(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    for _ in 0..100 {
        let l = (x * y).sqrt() + (y * z).sqrt() + (z * x).sqrt();
        x = 0.25 * (x + l);
        y = 0.25 * (y + l);
        z = 0.25 * (z + l);
        let a = (x + y + z) / 3.0;
        let d = [(a - x) / a, (a - y) / a, (a - z) / a];
        if d.iter().all(|v| v.abs() < 1e-4) {
            let e2 = d[0] * d[1] - d[2] * d[2];
            let e3 = d[0] * d[1] * d[2];
            return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0)
                / a.sqrt();
        }
    }
    f64::NAN
}

/// Carlson's `R_D(x, y, z)`.
fn carlson_rd(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    let mut sum = 0.0;
    let mut fac = 1.0;
    for _ in 0..100 {
        let l = (x * y).sqrt() + (y * z).sqrt() + (z * x).sqrt();
        sum += fac / (z.sqrt() * (z + l));
        fac *= 0.25;
        x = 0.25 * (x + l);
        y = 0.25 * (y + l);
        z = 0.25 * (z + l);
        let a = (x + y + 3.0 * z) / 5.0;
        let d = [(a - x) / a, (a - y) / a, (a - z) / a];
        if d.iter().all(|v| v.abs() < 1e-4) {
            let ea = d[0] * d[1];
            let eb = d[2] * d[2];
            let ec = ea - eb;
            let ed = ea - 6.0 * eb;
            let ee = ed + ec + ec;
            let s = 1.0
                + ed * (-3.0 / 14.0 + 9.0 / 88.0 * ed - 4.5 / 26.0 * d[2] * ee)
                + d[2] * (ee / 6.0 + d[2] * (-9.0 / 22.0 * ec + 1.5 / 26.0 * d[2] * ea));
            return 3.0 * sum + fac * s / (a * a.sqrt());
        }
    }
    f64::NAN
}

/// Incomplete elliptic integrals of the first and second kind
/// `(F(φ, k), E(φ, k))`, `0 ≤ φ ≤ π/2`, `k < 1`.
pub fn elliptic_fe(phi: f64, k: f64) -> (f64, f64) {
    let (s, c) = phi.sin_cos();
    let q = 1.0 - k * k * s * s;
    let rf = carlson_rf(c * c, q, 1.0);
    let rd = carlson_rd(c * c, q, 1.0);
    (s * rf, s * rf - k * k * s * s * s * rd / 3.0)
}

/// Mattiasson's elliptic-integral solution of the inextensible cantilever
/// under a transverse end load, `alpha = P L²/EI`: `(u/L, w/L, θ)` with `u`
/// the horizontal shortening, `w` the deflection, `θ` the tip rotation
/// (positive in the load's sense).
///
/// With `k² = (1 + sin θ)/2`, `sin φ₁ = 1/(k√2)`:
/// `√α = F(π/2, k) − F(φ₁, k)`, `w/L = 1 − 2 (E(π/2, k) − E(φ₁, k))/√α`,
/// `1 − u/L = √(2 sin θ / α)`.
pub fn mattiasson(alpha: f64) -> (f64, f64, f64) {
    let sa = alpha.sqrt();
    let g = |k: f64| {
        let phi1 = (1.0 / (k * std::f64::consts::SQRT_2)).min(1.0).asin();
        let (f1, e1) = elliptic_fe(phi1, k);
        let (fk, ek) = elliptic_fe(std::f64::consts::FRAC_PI_2, k);
        (fk - f1, ek - e1)
    };
    // F(π/2) − F(φ₁) grows from 0 (k = 1/√2) without bound (k → 1).
    let (mut lo, mut hi) = (std::f64::consts::FRAC_1_SQRT_2, 1.0 - 1e-15);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid).0 < sa {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let k = 0.5 * (lo + hi);
    let (_, de) = g(k);
    let theta = (2.0 * k * k - 1.0).asin();
    let w = 1.0 - 2.0 * de / sa;
    let u = 1.0 - (2.0 * theta.sin() / alpha).sqrt();
    (u, w, theta)
}

/// The extensible elastica under a uniform dead load `w` per unit
/// reference length (instead of an end force): the section force at `X`
/// is the resultant of the load beyond it, `F(X) = w (L − X)`, in the
/// equations above. Tip of the cantilever clamped at the origin along
/// `+x`; the load applied in steps (continuation of the root moment).
/// `None` if shooting fails.
pub fn extensible_cantilever_distributed(l: f64, ea: f64, ei: f64, w: [f64; 2]) -> Option<Tip> {
    let shoot_w = |w: [f64; 2], m0: f64| -> Option<[f64; 4]> {
        let sys = FnSystem(move |x: f64, y: &[f64; 4], dy: &mut [f64; 4]| {
            let f = [w[0] * (l - x), w[1] * (l - x)];
            let (s, c) = y[0].sin_cos();
            let eps = if ea.is_finite() {
                (f[0] * c + f[1] * s) / ea
            } else {
                0.0
            };
            dy[0] = y[1] / ei;
            dy[1] = (1.0 + eps) * (f[0] * s - f[1] * c);
            dy[2] = (1.0 + eps) * c;
            dy[3] = (1.0 + eps) * s;
        });
        let mut method = Dop853::new(1e-13, 1e-15);
        let opts = SolveOptions {
            record_steps: false,
            ..SolveOptions::default()
        };
        let sol = integrate(
            &mut method,
            &sys,
            0.0,
            [0.0, m0, 0.0, 0.0],
            l,
            &opts,
            &mut [],
        );
        matches!(sol.stop, StopReason::Finished).then_some(sol.y_final)
    };
    let secant_w = |w: [f64; 2], guess: f64| -> Option<f64> {
        let scale = (w[0].abs() + w[1].abs()) * l * l;
        let mut m_a = guess;
        let mut r_a = shoot_w(w, m_a)?[1];
        let mut m_b = guess * (1.0 + 1e-3) + 1e-6 * scale;
        let mut r_b = shoot_w(w, m_b)?[1];
        for _ in 0..100 {
            if r_b.abs() <= 1e-14 * scale || r_b == r_a {
                break;
            }
            let m_c = m_b - r_b * (m_b - m_a) / (r_b - r_a);
            let r_c = shoot_w(w, m_c)?[1];
            (m_a, r_a, m_b, r_b) = (m_b, r_b, m_c, r_c);
        }
        (r_b.abs() <= 1e-10 * scale).then_some(m_b)
    };
    let load = (w[0].abs() + w[1].abs()) * l * l * l / ei;
    let steps = (2.0 * load).ceil().max(1.0) as usize;
    let mut m = 0.0;
    for k in 1..=steps {
        let s = k as f64 / steps as f64;
        let wk = [s * w[0], s * w[1]];
        let guess = if k == 1 {
            0.5 * wk[1] * l * l
        } else {
            m * k as f64 / (k - 1) as f64
        };
        m = secant_w(wk, guess)?;
    }
    let y = shoot_w(w, m)?;
    Some(Tip {
        x: y[2],
        y: y[3],
        theta: y[0],
        root_moment: m,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elliptic_integrals_match_known_values() {
        // K(k = sin 45°) = 1.854074677301372, E = 1.350643881047675.
        let (f, e) = elliptic_fe(std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_1_SQRT_2);
        assert!((f - 1.854_074_677_301_372).abs() < 1e-14, "{f}");
        assert!((e - 1.350_643_881_047_675).abs() < 1e-14, "{e}");
    }

    #[test]
    fn mattiasson_agrees_with_shooting_and_his_table() {
        // Two independent solutions of the inextensible elastica: the
        // elliptic integrals and shooting on the ODE with EA = ∞.
        for alpha in [0.5, 1.0, 2.0, 5.0, 10.0] {
            let (u, w, th) = mattiasson(alpha);
            let tip = extensible_cantilever(1.0, f64::INFINITY, 1.0, [0.0, -alpha])
                .unwrap_or_else(|| panic!("shooting failed at {alpha}"));
            assert!(
                (1.0 - tip.x - u).abs() < 1e-10,
                "{alpha}: {} {u}",
                1.0 - tip.x
            );
            assert!((-tip.y - w).abs() < 1e-10, "{alpha}: {} {w}", -tip.y);
            assert!(
                (-tip.theta - th).abs() < 1e-10,
                "{alpha}: {} {th}",
                -tip.theta
            );
        }
        // Mattiasson (1981), table 1, PL²/EI = 1: w/L = 0.30172,
        // u/L = 0.05643, θ = 0.46135; PL²/EI = 10: 0.81061, 0.55500.
        let (u, w, th) = mattiasson(1.0);
        assert!(
            (w - 0.30172).abs() < 5e-6 && (u - 0.05643).abs() < 5e-6,
            "{u} {w}"
        );
        assert!((th - 0.46135).abs() < 5e-6, "{th}");
        let (u, w, _) = mattiasson(10.0);
        assert!(
            (w - 0.81061).abs() < 5e-6 && (u - 0.55500).abs() < 5e-6,
            "{u} {w}"
        );
    }

    #[test]
    fn small_load_is_the_linear_cantilever() {
        // P L³/(3 EI) and the extensible shortening vanish for small P.
        let (l, ei, ea) = (2.0, 1.0e6, 2.0e9);
        let p = 1e-3;
        let tip = extensible_cantilever(l, ea, ei, [0.0, -p]).unwrap_or_else(|| panic!("shoot"));
        let lin = p * l * l * l / (3.0 * ei);
        assert!((-tip.y - lin).abs() < 1e-9 * lin, "{} {lin}", -tip.y);
        // An axial pull stretches by P L/EA.
        let tip = extensible_cantilever(l, ea, ei, [1e5, 0.0]).unwrap_or_else(|| panic!("shoot"));
        assert!((tip.x - l - 1e5 * l / ea).abs() < 1e-14, "{}", tip.x);
    }
}
