//! `models/hub_beam.ron`: a cantilever clamped on the axis of a free hub.
//! The period of free vibration in a simulation against the closed form
//! (the frequency equation of a cantilever on a free rigid hub), and energy
//! and angular momentum conservation without damping.

use eom_gen::System;
use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use eom_sim::{Dop853, OdeSystem, SolveOptions, integrate};
use nalgebra::{DMatrix, Matrix3};

const N: usize = 5;
const L: f64 = 1.0;
const RHO_A: f64 = 0.78;
const EI_Z: f64 = 43.75;
const J_HUB: f64 = 0.05;

fn system() -> System {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/hub_beam.ron");
    let text = std::fs::read_to_string(path).expect("models/hub_beam.ron");
    check(&Source::new("models/hub_beam.ron", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

struct Ode<'a> {
    num: &'a Numeric,
}

impl OdeSystem<10> for Ode<'_> {
    fn rhs(&self, t: f64, y: &[f64; 10], dy: &mut [f64; 10]) {
        let (q, u) = y.split_at(N);
        let ud = self
            .num
            .forward_dynamics(q, u, t, &[0.0; N], &[])
            .unwrap_or_else(|_| vec![f64::NAN; N]);
        dy[..N].copy_from_slice(&self.num.qdot(q, u));
        dy[N..].copy_from_slice(&ud);
    }
}

/// The lowest frequency of a uniform cantilever (root on the axis) clamped
/// to a rigid hub of inertia `J_h` that turns freely: with
/// `y = A (cosh βx − cos βx) + B sinh βx + D sin βx` (so `y(0) = 0`),
/// `ω² = EI β⁴/ρA`, the hub's equation `−J_h ω² y'(0) = EI y''(0)` and the
/// free end `y''(L) = y'''(L) = 0` give
///
/// ```text
/// | 2            j      j     |
/// | ch + c       sh     −s    | = 0,   j = J_h β³/ρA,  ch = cosh βL, …
/// | sh − s       ch     −c    |
/// ```
///
/// (`J_h → ∞`: the clamped–free equation; `J_h → 0`: pinned–free). The
/// lowest root `β > 0` by a scan and bisection.
fn hub_cantilever() -> f64 {
    let det = |b: f64| {
        let (ch, sh, c, s) = ((b * L).cosh(), (b * L).sinh(), (b * L).cos(), (b * L).sin());
        let j = J_HUB * b.powi(3) / RHO_A;
        Matrix3::new(2.0, j, j, ch + c, sh, -s, sh - s, ch, -c).determinant()
    };
    let mut lo = 0.5;
    while det(lo) * det(lo + 0.001) > 0.0 {
        lo += 0.001;
    }
    let mut hi = lo + 0.001;
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if det(lo) * det(mid) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let beta = 0.5 * (lo + hi);
    beta * beta * (EI_Z / RHO_A).sqrt()
}

#[test]
fn hub_beam_vibrates_at_the_free_hub_frequency() {
    let num = Numeric::new(&system()).unwrap();
    // The lowest elastic mode of the linearised model (M and ∂b/∂q at
    // rest) gives the initial shape; its frequency is then measured in the
    // simulation, from the zero crossings of the first elastic coordinate.
    let zero = [0.0; N];
    let m = num.terms(&zero, &zero, 0.0, &[]).unwrap().mass_matrix;
    let m = DMatrix::from_fn(N, N, |r, c| m[r][c]);
    let h = 1e-6;
    let mut k = DMatrix::zeros(N, N);
    for c in 0..N {
        let (mut qp, mut qm) = (zero, zero);
        qp[c] = h;
        qm[c] = -h;
        let bp = num.terms(&qp, &zero, 0.0, &[]).unwrap().bias;
        let bm = num.terms(&qm, &zero, 0.0, &[]).unwrap().bias;
        for r in 0..N {
            k[(r, c)] = (bp[r] - bm[r]) / (2.0 * h);
        }
    }
    let l = m.clone().cholesky().unwrap().l();
    let li = l.clone().try_inverse().unwrap();
    let a = &li * &k * li.transpose();
    let eig = ((&a + a.transpose()) * 0.5).symmetric_eigen();
    let (i1, w2) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .filter(|(_, w2)| **w2 > 1.0)
        .min_by(|a, b| a.1.total_cmp(b.1))
        .unwrap();
    let linear = w2.sqrt();
    let shape = li.transpose() * eig.eigenvectors.column(i1);
    let shape = &shape * (1e-3 / shape[1]);
    let want = hub_cantilever();
    let clamped = 1.875_104_068_711_961_f64.powi(2) * (EI_Z / (RHO_A * L.powi(4))).sqrt();
    let mut y0 = [0.0; 10];
    for i in 0..N {
        y0[i] = shape[i];
    }
    let period = 2.0 * std::f64::consts::PI / want;
    let dt = period / 400.0;
    let times: Vec<f64> = (1..=4000).map(|k| dt * k as f64).collect();
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-15),
        &Ode { num: &num },
        0.0,
        y0,
        times[times.len() - 1],
        &SolveOptions {
            t_eval: times.clone(),
            ..SolveOptions::default()
        },
        &mut [],
    );
    assert_eq!(sol.y_out.len(), times.len(), "stopped: {:?}", sol.stop);
    // Downward zero crossings of q_f1 (linear interpolation; the dense
    // output is exact to the tolerance, the interpolation error of a sine
    // sampled 400 times a period is ~1e-6 of a period).
    let mut crossings = Vec::new();
    let (mut tp, mut yp) = (0.0, y0[1]);
    for (&t, y) in times.iter().zip(&sol.y_out) {
        if yp > 0.0 && y[1] <= 0.0 {
            crossings.push(tp + dt * yp / (yp - y[1]));
        }
        (tp, yp) = (t, y[1]);
    }
    let n = crossings.len() - 1;
    let got = 2.0 * std::f64::consts::PI * n as f64 / (crossings[n] - crossings[0]);
    eprintln!(
        "free hub: ω₁ simulated {got:.7} rad/s over {n} periods, frequency equation {want:.7} \
         (relative {:+.1e}); linearised model {linear:.7} ({:+.1e}); clamped–free {clamped:.4}",
        got / want - 1.0,
        got / linear - 1.0
    );
    assert!(n >= 9, "{n} periods");
    assert!(
        got > clamped * 1.01,
        "the free hub raises ω₁ above {clamped}"
    );
    // The simulation oscillates at the linearised model's frequency (1 mm
    // amplitude: the nonlinearity and the sampling shift it by < 2e-6),
    // and that is a Ritz approximation of the exact one from above: the
    // hub-coupled mode built from three in-plane clamped modes, 9e-6 high.
    assert!(
        (got / linear - 1.0).abs() < 2e-6,
        "ω₁ = {got}, linearised {linear}"
    );
    assert!(
        (0.0..2e-5).contains(&(linear / want - 1.0)),
        "linearised ω₁ = {linear}, frequency equation {want}"
    );
}

#[test]
fn hub_beam_conserves_energy_and_angular_momentum() {
    // The hub spinning at 5 rad/s with the beam bent and vibrating (no
    // damping, stiffening on): T + V and the angular momentum about z are
    // first integrals, kept to DOP853's tolerance over 2 s (~9 periods of
    // the first mode).
    let num = Numeric::new(&system()).unwrap();
    let y0 = [0.0, 0.02, -0.004, 0.003, 0.001, 5.0, 0.3, 0.5, -0.2, 0.1];
    let first = |y: &[f64; 10]| {
        let (t, v) = num.energy(&y[..N], &y[N..], 0.0).unwrap();
        let h = num.momentum(&y[..N], &y[N..], 0.0).unwrap();
        (t + v, t.abs() + v.abs(), h.n.0[2])
    };
    let (e0, scale, h0) = first(&y0);
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &Ode { num: &num },
        0.0,
        y0,
        2.0,
        &SolveOptions {
            t_eval: (1..=40).map(|k| 0.05 * k as f64).collect(),
            ..SolveOptions::default()
        },
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 40, "stopped: {:?}", sol.stop);
    let (mut de, mut dh) = (0.0_f64, 0.0_f64);
    for y in &sol.y_out {
        let (e, _, h) = first(y);
        de = de.max((e - e0).abs() / scale);
        dh = dh.max((h - h0).abs() / h0.abs());
    }
    eprintln!(
        "relative drift over 2 s: energy {de:e}, angular momentum {dh:e} ({} steps)",
        sol.stats.accepted
    );
    assert!(de < 1e-9 && dh < 1e-9, "energy {de:e}, momentum {dh:e}");
}
