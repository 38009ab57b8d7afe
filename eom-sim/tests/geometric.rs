//! Projection hook and geometric integrators.

// Reference values keep their published digits; loops mirror the formulas.
#![allow(clippy::excessive_precision, clippy::needless_range_loop)]

use eom_sim::{
    Dopri5, ImplicitMidpoint, OdeSystem, Rk4, SecondOrderSystem, SolveOptions, StopReason,
    integrate, stormer_verlet,
};

/// Quaternion kinematics q' = ½ q ⊗ (0, ω(t)) with a time-varying body rate
/// ω(t) = (sin t, cos 1.3t, 0.5). The exact flow keeps |q| = 1; a general
/// Runge–Kutta method does not (|q|² is a quadratic invariant, preserved
/// only by symplectic RK methods such as the implicit midpoint rule).
struct Quat {
    project: bool,
}

impl OdeSystem<4> for Quat {
    fn rhs(&self, t: f64, q: &[f64; 4], dq: &mut [f64; 4]) {
        let (wx, wy, wz) = (t.sin(), (1.3 * t).cos(), 0.5);
        let [w, x, y, z] = *q;
        dq[0] = 0.5 * (-x * wx - y * wy - z * wz);
        dq[1] = 0.5 * (w * wx + y * wz - z * wy);
        dq[2] = 0.5 * (w * wy + z * wx - x * wz);
        dq[3] = 0.5 * (w * wz + x * wy - y * wx);
    }
    fn project(&self, _t: f64, q: &mut [f64; 4]) -> bool {
        if !self.project {
            return false;
        }
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        for v in q.iter_mut() {
            *v /= n;
        }
        true
    }
}

fn max_norm_drift(ys: &[[f64; 4]]) -> f64 {
    ys.iter()
        .map(|q| (q.iter().map(|v| v * v).sum::<f64>().sqrt() - 1.0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn quaternion_projection_keeps_unit_norm() {
    let q0 = [1.0, 0.0, 0.0, 0.0];
    let t_end = 2000.0;
    let opts = SolveOptions::default();
    let mut free = Dopri5::<4>::new(1e-6, 1e-6);
    let a = integrate(
        &mut free,
        &Quat { project: false },
        0.0,
        q0,
        t_end,
        &opts,
        &mut [],
    );
    let mut proj = Dopri5::<4>::new(1e-6, 1e-6);
    let b = integrate(
        &mut proj,
        &Quat { project: true },
        0.0,
        q0,
        t_end,
        &opts,
        &mut [],
    );
    assert_eq!(a.stop, StopReason::Finished);
    assert_eq!(b.stop, StopReason::Finished);
    let (da, db) = (max_norm_drift(&a.y), max_norm_drift(&b.y));
    eprintln!("| |q| - 1 | over t ∈ [0, {t_end}]: without projection {da:.3e}, with {db:.3e}");
    eprintln!("  stats without {:?}\n  stats with {:?}", a.stats, b.stats);
    assert!(
        da > 1e-6,
        "without projection the norm should drift: got {da:e} want > 1e-6"
    );
    assert!(
        db < 4.0 * f64::EPSILON,
        "with projection: got {db:e} want round-off (< 4 eps)"
    );
    // Projection triggers a fresh FSAL evaluation per accepted step.
    assert_eq!(b.stats.rhs_evals, 6 * b.stats.steps + 2 + b.stats.accepted);
}

#[test]
fn implicit_midpoint_preserves_quaternion_norm_without_projection() {
    // |q|² is a quadratic invariant of the linear system q' = A(t) q with
    // A skew-symmetric: the implicit midpoint rule keeps it to round-off.
    let mut m = ImplicitMidpoint::<4>::new(0.05);
    let s = integrate(
        &mut m,
        &Quat { project: false },
        0.0,
        [1.0, 0.0, 0.0, 0.0],
        500.0,
        &SolveOptions::default(),
        &mut [],
    );
    assert_eq!(s.stop, StopReason::Finished);
    let d = max_norm_drift(&s.y);
    eprintln!("implicit midpoint 10 000 steps: max | |q| - 1 | = {d:.3e}");
    assert!(d < 1e-13, "got {d:e} want < 1e-13");
}

/// Free rigid body (Euler's equations for the angular momentum m in the
/// body frame, inertia I = (2, 1, 2/3)): m' = m × (I^{-1} m). Both |m|²
/// and the energy ½ mᵀ I^{-1} m are quadratic invariants, so the implicit
/// midpoint rule preserves both to round-off; RK4 does not.
struct RigidBody;
const INV_I: [f64; 3] = [0.5, 1.0, 1.5];

impl OdeSystem<3> for RigidBody {
    fn rhs(&self, _t: f64, m: &[f64; 3], dm: &mut [f64; 3]) {
        let w = [m[0] * INV_I[0], m[1] * INV_I[1], m[2] * INV_I[2]];
        dm[0] = m[1] * w[2] - m[2] * w[1];
        dm[1] = m[2] * w[0] - m[0] * w[2];
        dm[2] = m[0] * w[1] - m[1] * w[0];
    }
}

fn invariants(m: &[f64; 3]) -> (f64, f64) {
    let c = m.iter().map(|v| v * v).sum::<f64>();
    let e = 0.5 * (0..3).map(|i| m[i] * m[i] * INV_I[i]).sum::<f64>();
    (c, e)
}

#[test]
fn implicit_midpoint_conserves_quadratic_invariants_to_roundoff() {
    let m0 = [(0.9f64).cos(), 0.0, (0.9f64).sin()];
    let (c0, e0) = invariants(&m0);
    let opts = SolveOptions::default();
    let mut mid = ImplicitMidpoint::<3>::new(0.1);
    let s = integrate(&mut mid, &RigidBody, 0.0, m0, 2000.0, &opts, &mut []);
    let mut rk = Rk4::<3>::new(0.1);
    let r = integrate(&mut rk, &RigidBody, 0.0, m0, 2000.0, &opts, &mut []);
    let worst = |ys: &[[f64; 3]]| {
        ys.iter().fold((0.0f64, 0.0f64), |(dc, de), m| {
            let (c, e) = invariants(m);
            (dc.max((c - c0).abs()), de.max((e - e0).abs()))
        })
    };
    let (mc, me) = worst(&s.y);
    let (rc, re) = worst(&r.y);
    eprintln!(
        "20 000 steps h = 0.1: midpoint |Δ|m|²| {mc:.2e} |ΔE| {me:.2e}; RK4 {rc:.2e} {re:.2e}"
    );
    assert!(
        mc < 1e-13 && me < 1e-13,
        "midpoint invariants drift: got {mc:e}, {me:e} want < 1e-13"
    );
    assert!(
        rc > 1e-9,
        "RK4 was expected to drift (sanity of the test): got {rc:e}"
    );
}

/// Pendulum θ'' = -sin θ with the implicit midpoint rule: energy is not a
/// quadratic invariant, but its error stays bounded (no drift) over long
/// times; RK4 at the same step drifts (it is dissipative on this problem).
struct Pendulum;
impl OdeSystem<2> for Pendulum {
    fn rhs(&self, _t: f64, y: &[f64; 2], dy: &mut [f64; 2]) {
        dy[0] = y[1];
        dy[1] = -y[0].sin();
    }
}

#[test]
fn implicit_midpoint_energy_error_is_bounded_on_pendulum() {
    let energy = |y: &[f64; 2]| 0.5 * y[1] * y[1] - y[0].cos();
    let y0 = [2.0, 0.0];
    let e0 = energy(&y0);
    let opts = SolveOptions::default();
    let t_end = 10_000.0;
    let mut mid = ImplicitMidpoint::<2>::new(0.2);
    let s = integrate(&mut mid, &Pendulum, 0.0, y0, t_end, &opts, &mut []);
    let n = s.y.len();
    let err_in = |ys: &[[f64; 2]]| {
        ys.iter()
            .map(|y| (energy(y) - e0).abs())
            .fold(0.0, f64::max)
    };
    let first = err_in(&s.y[..n / 10]);
    let last = err_in(&s.y[n - n / 10..]);
    let mut rk = Rk4::<2>::new(0.2);
    let r = integrate(&mut rk, &Pendulum, 0.0, y0, t_end, &opts, &mut []);
    let rk_end = (energy(&r.y_final) - e0).abs();
    eprintln!(
        "pendulum h = 0.2, t = 1e4: midpoint max|ΔE| first 10% {first:.3e}, last 10% {last:.3e}; RK4 |ΔE(end)| {rk_end:.3e}"
    );
    assert!(
        last < 1.5 * first + 1e-12,
        "midpoint energy error grows: first {first:e} last {last:e}"
    );
    assert!(
        last < 1e-2,
        "midpoint energy error got {last:e} want < 1e-2"
    );
    assert!(
        rk_end > 3.0 * last,
        "RK4 expected to drift beyond midpoint's bounded error: {rk_end:e}"
    );
}

/// Kepler problem q'' = -q/|q|³, eccentricity 0.6, with Störmer–Verlet:
/// angular momentum q × v is conserved exactly (to round-off) and the
/// energy error stays bounded over 1000 periods.
struct Kepler;
impl SecondOrderSystem<2> for Kepler {
    fn accel(&self, _t: f64, q: &[f64; 2], a: &mut [f64; 2]) {
        let r3 = (q[0] * q[0] + q[1] * q[1]).powf(1.5);
        a[0] = -q[0] / r3;
        a[1] = -q[1] / r3;
    }
}

#[test]
fn stormer_verlet_kepler_momentum_exact_energy_bounded() {
    let e: f64 = 0.6;
    let q0 = [1.0 - e, 0.0];
    let v0 = [0.0, ((1.0 + e) / (1.0 - e)).sqrt()];
    let energy = |q: &[f64; 2], v: &[f64; 2]| {
        0.5 * (v[0] * v[0] + v[1] * v[1]) - 1.0 / (q[0] * q[0] + q[1] * q[1]).sqrt()
    };
    let ang = |q: &[f64; 2], v: &[f64; 2]| q[0] * v[1] - q[1] * v[0];
    let (e0, l0) = (energy(&q0, &v0), ang(&q0, &v0));
    let period = 2.0 * std::f64::consts::PI;
    let s = stormer_verlet(&Kepler, 0.0, q0, v0, 1000.0 * period, 0.005, 10);
    assert_eq!(s.stop, StopReason::Finished);
    let n = s.t.len();
    let mut max_dl: f64 = 0.0;
    let de: Vec<f64> = (0..n)
        .map(|k| {
            max_dl = max_dl.max((ang(&s.q[k], &s.v[k]) - l0).abs());
            (energy(&s.q[k], &s.v[k]) - e0).abs()
        })
        .collect();
    let first = de[..n / 10].iter().cloned().fold(0.0, f64::max);
    let last = de[n - n / 10..].iter().cloned().fold(0.0, f64::max);
    eprintln!(
        "Kepler e=0.6, 1000 periods, h=0.005: |ΔL| {max_dl:.2e}, max|ΔE| first 10% {first:.2e}, last 10% {last:.2e}, {} accel evals",
        s.stats.rhs_evals
    );
    assert!(
        max_dl < 1e-11,
        "angular momentum got drift {max_dl:e} want round-off"
    );
    assert!(
        last < 1.5 * first,
        "energy error grows: first {first:e} last {last:e}"
    );
    assert!(last < 1e-3, "energy error got {last:e}");
}
