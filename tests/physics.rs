//! Closed-form physics of the bundled tree models, checked by integrating
//! the reference (`f64`) dynamics with classical RK4 at small steps:
//! the pendulum's small-amplitude period, the heavy symmetric top's
//! nutation bounds from energy and its two conserved momenta, and the
//! torque-free body's conservation laws and intermediate-axis flip.

use eom_gen::mech::Numeric;
use eom_gen::{System, check_file};

fn system(name: &str) -> System {
    let path = format!("{}/models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    check_file(&path).unwrap_or_else(|r| panic!("{r}")).system
}

/// One RK4 step of q̇ = N(q) u, u̇ = FD(q, u); quaternions renormalised.
fn step(num: &Numeric, quats: &[usize], q: &mut [f64], u: &mut [f64], h: f64) {
    let zero = vec![0.0; u.len()];
    let f = |q: &[f64], u: &[f64]| {
        (
            num.qdot(q, u),
            num.forward_dynamics(q, u, 0.0, &zero, &[]).expect("fd"),
        )
    };
    let add = |a: &[f64], b: &[f64], s: f64| -> Vec<f64> {
        a.iter().zip(b).map(|(a, b)| a + s * b).collect()
    };
    let (k1q, k1u) = f(q, u);
    let (k2q, k2u) = f(&add(q, &k1q, h / 2.0), &add(u, &k1u, h / 2.0));
    let (k3q, k3u) = f(&add(q, &k2q, h / 2.0), &add(u, &k2u, h / 2.0));
    let (k4q, k4u) = f(&add(q, &k3q, h), &add(u, &k3u, h));
    for i in 0..q.len() {
        q[i] += h / 6.0 * (k1q[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + k4q[i]);
    }
    for i in 0..u.len() {
        u[i] += h / 6.0 * (k1u[i] + 2.0 * k2u[i] + 2.0 * k3u[i] + k4u[i]);
    }
    for &a in quats {
        let n = q[a..a + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
        q[a..a + 4].iter_mut().for_each(|x| *x /= n);
    }
}

#[test]
fn pendulum_small_amplitude_period_is_two_pi_sqrt_l_over_g() {
    let sys = system("pendulum");
    let num = Numeric::new(&sys).expect("numeric");
    let (mut q, mut u) = (vec![1e-3], vec![0.0]);
    let h = 1e-3;
    let mut t = 0.0;
    // Times of downward zero crossings of θ, interpolated linearly.
    let mut crossings = Vec::new();
    while crossings.len() < 3 {
        let before = q[0];
        step(&num, &[], &mut q, &mut u, h);
        t += h;
        if before > 0.0 && q[0] <= 0.0 {
            crossings.push(t - h * q[0] / (q[0] - before));
        }
    }
    let period = (crossings[2] - crossings[0]) / 2.0;
    // Amplitude correction θ0²/16 ≈ 6e-8 is far below the tolerance.
    let want = 2.0 * std::f64::consts::PI * (1.0f64 / 9.81).sqrt();
    assert!(
        (period - want).abs() < 1e-6,
        "period {period}, want 2π√(l/g) = {want}"
    );
}

#[test]
fn heavy_top_nutates_between_the_roots_of_its_energy_cubic() {
    // Lagrange top about a fixed pivot: symmetry axis body y, u = cos θ its
    // vertical component. With a = p_φ (vertical angular momentum),
    // b = p_ψ = I3 ω_y (spin momentum) and E' = E − b²/(2 I3) conserved,
    // u̇² = f(u) = (1 − u²)(2E' − 2 m g l u)/I1 − (a − b u)²/I1².
    // u starts at a root (u̇ = 0, axis horizontal) and stays between the two
    // roots of f that bracket the motion.
    let sys = system("heavy_top");
    let num = Numeric::new(&sys).expect("numeric");
    let (m, g, l, a_c, c_c) = (15.0, 9.81, 1.0, 0.234375, 0.46875);
    let (i1, i3) = (a_c + m * l * l, c_c);
    let (mut q, mut u) = (sys.q0(), sys.u0());
    let axis_z = |q: &[f64]| 2.0 * (q[2] * q[3] + q[0] * q[1]); // (R ŷ)·ẑ
    let invariants = |q: &[f64], u: &[f64]| {
        let (t, v) = num.energy(q, u, 0.0).expect("energy");
        let h = num.momentum(q, u, 0.0).expect("momentum");
        (t + v, h.n.0[2], i3 * u[1])
    };
    let (e0, pa, pb) = invariants(&q, &u);
    let e_prime = e0 - pb * pb / (2.0 * i3);
    let f = |x: f64| {
        (1.0 - x * x) * (2.0 * e_prime - 2.0 * m * g * l * x) / i1
            - (pa - pb * x).powi(2) / (i1 * i1)
    };
    let u0 = axis_z(&q);
    assert!(
        f(u0).abs() < 1e-6,
        "the start is a turning point: f(u0) = {}",
        f(u0)
    );
    // The other root below u0: scan down to where f changes sign, bisect.
    let mut hi = u0 - 1e-6;
    assert!(f(hi) > 0.0, "f > 0 just below the start");
    let mut lo = hi;
    while f(lo) > 0.0 && lo > -1.0 {
        hi = lo;
        lo = (lo - 1e-4).max(-1.0);
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 { hi = mid } else { lo = mid }
    }
    let u_low = 0.5 * (lo + hi);
    let h = 2e-5;
    let (mut umin, mut umax) = (u0, u0);
    for _ in 0..20_000 {
        step(&num, &[0], &mut q, &mut u, h);
        let z = axis_z(&q);
        umin = umin.min(z);
        umax = umax.max(z);
    }
    let (e1, pa1, pb1) = invariants(&q, &u);
    assert!((e1 - e0).abs() < 1e-6 * e0.abs(), "energy {e0} → {e1}");
    assert!(
        (pa1 - pa).abs() < 1e-6 * pa.abs().max(1.0),
        "p_φ {pa} → {pa1}"
    );
    assert!((pb1 - pb).abs() < 1e-6 * pb.abs(), "p_ψ {pb} → {pb1}");
    assert!(
        umax <= u0 + 1e-6,
        "cos θ rose to {umax} above the start {u0}"
    );
    assert!(
        umin >= u_low - 1e-6,
        "cos θ fell to {umin}, below the root {u_low}"
    );
    assert!(
        umin <= u_low + 1e-4 * (u0 - u_low).abs().max(1e-6) + 1e-7,
        "cos θ reached only {umin}, the root is {u_low}"
    );
}

#[test]
fn torque_free_body_conserves_energy_and_momentum_and_flips() {
    // Spin about the intermediate axis is unstable (Dzhanibekov): ω_y changes
    // sign after about 20.75 s; T and the world angular momentum are constant.
    let sys = system("free_body");
    let num = Numeric::new(&sys).expect("numeric");
    let (mut q, mut u) = (sys.q0(), sys.u0());
    let (t0, _) = num.energy(&q, &u, 0.0).expect("energy");
    let l0 = num.momentum(&q, &u, 0.0).expect("momentum").n;
    let h = 2e-3;
    let mut sign_changes = Vec::new();
    for k in 1..=25_000 {
        let before = u[4];
        step(&num, &[3], &mut q, &mut u, h);
        if before.signum() != u[4].signum() {
            sign_changes.push(k as f64 * h);
        }
    }
    let (t1, _) = num.energy(&q, &u, 0.0).expect("energy");
    let l1 = num.momentum(&q, &u, 0.0).expect("momentum").n;
    assert!((t1 - t0).abs() < 1e-9 * t0, "T {t0} → {t1}");
    assert!((l1 - l0).norm() < 1e-9 * l0.norm(), "L {l0:?} → {l1:?}");
    println!("ω_y changes sign at {sign_changes:?} s");
    assert!(
        sign_changes.len() >= 2,
        "ω_y flips at least twice in 50 s: {sign_changes:?}"
    );
    let interval = sign_changes[1] - sign_changes[0];
    assert!(
        (interval - 20.75).abs() < 0.5,
        "flips {interval} s apart, want about 20.75 s"
    );
}
