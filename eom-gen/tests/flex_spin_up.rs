//! The spin-up of a flexible beam (`models/spin_up.ron`; Kane, Ryan and
//! Banerjee 1987; Simo and Vu-Quoc 1986): the hub's angle is prescribed to
//! spin up smoothly to 6 rad/s in 15 s, above the beam's first bending
//! frequency (3.80 rad/s). With geometric stiffening the tip deflection
//! follows the quasi-static deflection under the angular-acceleration load
//! and stays bounded over the whole run; without it the linear floating
//! frame model loses its in-plane stiffness once Ω > ω₁ and diverges.

use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use eom_sim::{Dop853, OdeSystem, SolveOptions, integrate};

const N: usize = 6;

fn model_text() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/spin_up.ron");
    std::fs::read_to_string(path).expect("models/spin_up.ron")
}

struct Ode<'a> {
    num: &'a Numeric,
}

impl OdeSystem<12> for Ode<'_> {
    fn rhs(&self, t: f64, y: &[f64; 12], dy: &mut [f64; 12]) {
        let (q, u) = y.split_at(N);
        let ud = self
            .num
            .forward_dynamics(q, u, t, &[0.0; N], &[])
            .unwrap_or_else(|_| vec![f64::NAN; N]);
        dy[..N].copy_from_slice(&self.num.qdot(q, u));
        dy[N..].copy_from_slice(&ud);
    }
}

/// Runs the spin-up from rest over 30 s (DOP853, rtol 1e-10): the times
/// and tip deflections `u_y(L)` in the rotating frame (every 0.05 s), and
/// how the integration stopped.
fn run(stiffening: bool) -> (Vec<f64>, Vec<f64>, String) {
    let text = model_text().replace(
        "stiffening: true",
        if stiffening {
            "stiffening: true"
        } else {
            "stiffening: false"
        },
    );
    let sys = check(&Source::new("models/spin_up.ron", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    assert_eq!(sys.nq(), N, "{:?}", sys.coordinate_names());
    let flex = sys.bodies[1].flexible.as_deref().expect("flexible beam");
    let tip = flex.beam.section(flex.beam.length, &flex.modes.shapes);
    let tip_y: Vec<f64> = (0..N).map(|j| tip.translation[(1, j)]).collect();
    let num = Numeric::new(&sys).unwrap();
    let times: Vec<f64> = (1..=600).map(|k| 0.05 * k as f64).collect();
    let sol = integrate(
        &mut Dop853::new(1e-10, 1e-12),
        &Ode { num: &num },
        0.0,
        [0.0; 12],
        30.0,
        &SolveOptions {
            t_eval: times.clone(),
            ..SolveOptions::default()
        },
        &mut [],
    );
    let tips: Vec<f64> = sol
        .y_out
        .iter()
        .map(|y| (0..N).map(|j| tip_y[j] * y[j]).sum())
        .collect();
    (
        times[..tips.len()].to_vec(),
        tips,
        format!("{:?}", sol.stop),
    )
}

/// The quasi-static tip deflection under the hub's angular acceleration
/// `α(t)`: the inertia load `−ρA α x` on a cantilever gives
/// `u_y(L) = −11 ρA α L⁵ / (120 EI)` (a linearly varying load,
/// `11 q₀ L⁴/(120 EI)` with `q₀ = ρA α L`), reduced by the in-plane
/// centrifugal stiffening of the first mode, `ω₁² → ω₁² + (κ − 1) Ω²`
/// (Southwell, κ = 1.1933).
fn quasi_static(t: f64) -> f64 {
    let (l, rho_a, ei, w_s, t_s) = (10.0_f64, 1.2, 1.4e4, 6.0, 15.0);
    let phase = 2.0 * std::f64::consts::PI * t / t_s;
    let (alpha, omega) = if t < t_s {
        (
            w_s / t_s * (1.0 - phase.cos()),
            w_s / t_s * (t - phase.sin() * t_s / (2.0 * std::f64::consts::PI)),
        )
    } else {
        (0.0, w_s)
    };
    let w1 = 3.516_015 * (ei / (rho_a * l.powi(4))).sqrt();
    let stiffer = 1.0 + 0.1933 * omega * omega / (w1 * w1);
    -11.0 * rho_a * alpha * l.powi(5) / (120.0 * ei) / stiffer
}

#[test]
fn spin_up_with_stiffening_stays_bounded_and_quasi_static() {
    let (t, tip, stop) = run(true);
    assert_eq!(tip.len(), 600, "stopped early: {stop}");
    let peak = tip.iter().fold(0.0_f64, |a, &b| a.max(b.abs()));
    let k_mid = t.iter().position(|&x| (x - 7.5).abs() < 1e-9).unwrap();
    let late = tip[t.iter().position(|&x| x >= 20.0).unwrap()..]
        .iter()
        .fold(0.0_f64, |a, &b| a.max(b.abs()));
    eprintln!(
        "with stiffening: peak |u_y(L)| = {peak:.5} m; at 7.5 s {:.5} m (quasi-static {:.5}); \
         after 20 s |u_y(L)| ≤ {late:.2e} m",
        tip[k_mid],
        quasi_static(7.5)
    );
    if let Ok(path) = std::env::var("SPIN_UP_CSV") {
        let (_, free, _) = run(false);
        let mut csv = String::from("t,tip_stiffening,tip_linear,quasi_static\n");
        for (k, (&tk, &y)) in t.iter().zip(&tip).enumerate() {
            let f = free.get(k).copied().unwrap_or(f64::NAN);
            csv += &format!("{tk},{y},{f},{}\n", quasi_static(tk));
        }
        std::fs::write(&path, csv).expect("write CSV");
    }
    // During the spin-up the beam lags behind the hub by the quasi-static
    // deflection (the load changes slowly against the 1.65 s period):
    // within 5 % of the closed form at the peak of the acceleration.
    let qs = quasi_static(7.5);
    assert!(
        (tip[k_mid] / qs - 1.0).abs() < 0.05,
        "u_y(L) at 7.5 s = {}, quasi-static {qs}",
        tip[k_mid]
    );
    // Bounded over the whole run: never beyond the static deflection
    // under the largest acceleration without stiffening (0.63 m, 6 % of L).
    let bound = -quasi_static(7.5) * (1.0 + 0.1933 * 9.0 / 14.42);
    assert!(
        peak <= bound * 1.05,
        "peak |u_y(L)| = {peak}, bound {bound}"
    );
    // At constant speed the beam vibrates freely about its straight shape
    // with the little energy the end of the spin-up leaves (under 1 % of
    // the peak), and that vibration does not grow (no damping: the
    // amplitude of 15–20 s is that of 20–30 s).
    let settling = tip
        [t.iter().position(|&x| x >= 15.0).unwrap()..t.iter().position(|&x| x >= 20.0).unwrap()]
        .iter()
        .fold(0.0_f64, |a, &b| a.max(b.abs()));
    assert!(
        late < 0.01 * peak,
        "after the spin-up |u_y(L)| reaches {late}"
    );
    assert!(
        late < 1.05 * settling,
        "the free vibration grows: {settling} → {late}"
    );
}

#[test]
fn spin_up_without_stiffening_diverges() {
    // Without the foreshortening terms the in-plane stiffness is
    // K − Ω² M_ff: ω₁² − Ω² < 0 once Ω > 3.80 rad/s (t ≈ 8.5 s), and the
    // first mode grows like exp(√(Ω² − ω₁²) t) (rate 4.6 /s at 6 rad/s):
    // the tip deflection passes the beam's length (a linear model far out
    // of its range: it has diverged) before the end of the run.
    let (t, tip, stop) = run(false);
    let crossed = t.iter().zip(&tip).find(|(_, y)| y.abs() > 10.0);
    eprintln!(
        "without stiffening: |u_y(L)| > L at t = {:?} (stop: {stop}), last {:e} m",
        crossed.map(|c| c.0),
        tip.last().copied().unwrap_or(f64::NAN)
    );
    let (tc, _) = crossed.expect("the linear model's tip passes L = 10 m");
    // Ω(t) = (ω_s/T_s)(t − (T_s/2π) sin(2πt/T_s)) reaches ω₁ at:
    let w1 = 3.516_015 * (1.4e4_f64 / 1.2e4).sqrt();
    let omega = |t: f64| {
        0.4 * (t - 15.0 / (2.0 * std::f64::consts::PI)
            * (2.0 * std::f64::consts::PI * t / 15.0).sin())
    };
    let t1 = (0..1500)
        .map(|k| 0.01 * k as f64)
        .find(|&t| omega(t) >= w1)
        .unwrap();
    eprintln!("Ω = ω₁ at t = {t1} s");
    assert!(
        *tc > t1,
        "diverged at {tc} s, before Ω reached ω₁ at {t1} s"
    );
    // With stiffening the same run stays below 0.6 m (the test above).
}
