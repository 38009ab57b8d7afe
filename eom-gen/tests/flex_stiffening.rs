//! Geometric stiffening of flexible beams (issue #17; Kane, Ryan and
//! Banerjee 1987): the foreshortening terms of `mech::stiffening` against
//! the rotating-cantilever frequencies of an independent power-series
//! solution of the Euler–Bernoulli equation with centrifugal tension,
//! Southwell's coefficient, Euler's buckling load of a column under its own
//! weight (gravity along the beam), and energy conservation.

use eom_gen::System;
use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use eom_sim::{Dop853, OdeSystem, SolveOptions, integrate};
use nalgebra::DMatrix;

/// Kane, Ryan and Banerjee's beam (also Simo and Vu-Quoc's): L = 10 m,
/// ρA = 1.2 kg/m, EI = 1.4e4 N m² in both planes, EA = 2.8e7 N; the twelve
/// lowest modes are the first six bending modes of each plane (the first
/// axial mode is at 759 rad/s, above the sixth bending mode's 322 rad/s).
const L: f64 = 10.0;
const RHO_A: f64 = 1.2;
const EI: f64 = 1.4e4;

/// A beam clamped to a hub at `radius` from the hub's axis `z`; the hub
/// turns as `hub` says (`prescribed: ["…"]`, `locked: true`, or free).
fn model(hub: &str, stiffening: bool, modes: usize, extra: &str) -> String {
    model_with(hub, stiffening, modes, extra, 2.8e7, 1e4)
}

/// [`model`] with the axial and torsional stiffness given (to move axial and
/// torsion modes above the bending modes kept).
fn model_with(hub: &str, stiffening: bool, modes: usize, extra: &str, ea: f64, gj: f64) -> String {
    format!(
        r#"Model(
    name: "rotating_beam",
    {extra}
    bodies: [
        (name: "hub", mass: 1.0, inertia: Diag(1, 1, 1)),
        (name: "beam", flexible: Beam(length: {L}, rho_a: {RHO_A}, rho_ip: 1e-4, ea: {ea},
            ei_y: {EI}, ei_z: {EI}, gj: {gj}, elements: 20, reference: Clamped,
            modes: {modes}, stiffening: {stiffening})),
    ],
    joints: [
        (name: "spin", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "hub", {hub}),
        (name: "clamp", kind: Fixed, parent: "hub", child: "beam"),
    ],
)"#
    )
}

fn system(text: &str) -> System {
    check(&Source::new("rotating_beam.ron", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

/// Frequencies (rad/s, ascending) of small vibrations about `q = 0`,
/// `u = 0` of the free coordinates at time `t`: `M(0)` and the stiffness
/// `K = ∂b/∂q` by central differences, `det(K − ω² M) = 0`.
fn frequencies(num: &Numeric, n: usize, t: f64) -> Vec<f64> {
    let zero = vec![0.0; n];
    let m = num.terms(&zero, &zero, t, &[]).unwrap().mass_matrix;
    let m = DMatrix::from_fn(n, n, |r, c| m[r][c]);
    let h = 1e-6;
    let mut k = DMatrix::zeros(n, n);
    for c in 0..n {
        let (mut qp, mut qm) = (zero.clone(), zero.clone());
        qp[c] = h;
        qm[c] = -h;
        let bp = num.terms(&qp, &zero, t, &[]).unwrap().bias;
        let bm = num.terms(&qm, &zero, t, &[]).unwrap().bias;
        for r in 0..n {
            k[(r, c)] = (bp[r] - bm[r]) / (2.0 * h);
        }
    }
    let asym = (&k - k.transpose()).amax() / k.amax();
    assert!(asym < 1e-6, "stiffness not symmetric: {asym:e}");
    let l = m.cholesky().expect("M positive definite").l();
    let li = l.try_inverse().unwrap();
    let a = &li * k * li.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let mut w2: Vec<f64> = a.symmetric_eigenvalues().iter().copied().collect();
    w2.sort_by(f64::total_cmp);
    w2.into_iter()
        .map(|x| x.signum() * x.abs().sqrt())
        .collect()
}

/// The first flapping frequency `μ = ω √(ρA L⁴/EI)` of a uniform cantilever
/// spinning at `λ = Ω √(ρA L⁴/EI)` about an axis through its root, normal to
/// it, from the exact equation (no finite elements, no modes):
/// `w'''' − (λ²/2) ((1 − ξ²) w')' = μ² w` on `ξ ∈ [0, 1]`, clamped at 0
/// (`w = w' = 0`), free at 1 (`w'' = w''' = 0`; the tension vanishes there).
/// Power series `w = Σ a_n ξⁿ` with `a₀ = a₁ = 0`:
/// `(n+4)(n+3)(n+2)(n+1) a_{n+4} = (λ²/2) ((n+2)(n+1) a_{n+2} − n(n+1) a_n) + μ² a_n`;
/// the two solutions from `a₂` and `a₃` give a 2×2 determinant at `ξ = 1`
/// whose lowest root in `μ` is found by bisection.
fn rotating_cantilever(lambda: f64) -> f64 {
    let det = |mu: f64| {
        let ends = |a2: f64, a3: f64| {
            let n_terms = 160;
            let mut a = vec![0.0_f64; n_terms + 4];
            a[2] = a2;
            a[3] = a3;
            for n in 0..n_terms {
                let nf = n as f64;
                let rhs = 0.5
                    * lambda
                    * lambda
                    * ((nf + 2.0) * (nf + 1.0) * a[n + 2] - nf * (nf + 1.0) * a[n])
                    + mu * mu * a[n];
                a[n + 4] = rhs / ((nf + 4.0) * (nf + 3.0) * (nf + 2.0) * (nf + 1.0));
            }
            let d2: f64 = (2..a.len()).map(|n| (n * (n - 1)) as f64 * a[n]).sum();
            let d3: f64 = (3..a.len())
                .map(|n| (n * (n - 1) * (n - 2)) as f64 * a[n])
                .sum();
            (d2, d3)
        };
        let (p2, p3) = ends(1.0, 0.0);
        let (r2, r3) = ends(0.0, 1.0);
        p2 * r3 - p3 * r2
    };
    // Bracket the first sign change above μ = 1, then bisect.
    let mut lo = 1.0;
    let step = 0.01;
    while det(lo) * det(lo + step) > 0.0 {
        lo += step;
    }
    let mut hi = lo + step;
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if det(lo) * det(mid) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Southwell's coefficient of the first flapping mode of a uniform
/// cantilever spinning about its root, `κ = dμ²/dλ²` at `λ = 0`, from the
/// exact non-rotating mode φ (first-order perturbation):
/// `κ = ∫ ½(1 − ξ²) φ'² dξ / ∫ φ² dξ = 1.1933` (Simpson, 4000 panels).
fn southwell() -> f64 {
    let b = 1.875_104_068_711_961_f64;
    let sigma = (b.cosh() + b.cos()) / (b.sinh() + b.sin());
    let phi = |x: f64| (b * x).cosh() - (b * x).cos() - sigma * ((b * x).sinh() - (b * x).sin());
    let dphi =
        |x: f64| b * ((b * x).sinh() + (b * x).sin() - sigma * ((b * x).cosh() - (b * x).cos()));
    let simpson = |f: &dyn Fn(f64) -> f64| {
        let n = 4000;
        let h = 1.0 / n as f64;
        (0..=n)
            .map(|i| {
                let w = match i {
                    0 => 1.0,
                    _ if i == n => 1.0,
                    _ if i % 2 == 1 => 4.0,
                    _ => 2.0,
                };
                w * f(i as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0
    };
    simpson(&|x| 0.5 * (1.0 - x * x) * dphi(x).powi(2)) / simpson(&|x| phi(x).powi(2))
}

#[test]
fn stiffening_spinning_cantilever_matches_the_exact_rotating_beam() {
    // The hub turns at constant Ω (prescribed), the beam's root on the
    // axis. Out of the plane of rotation (flapping, bending in x–z) the
    // centrifugal tension stiffens the beam: μ_flap(λ) of the exact
    // equation (power series). In the plane (lead–lag, x–y) the same
    // tension acts, but the centrifugal load also pulls the bent beam
    // outwards, softening it by Ω²: ω_lag² = ω_flap² − Ω² exactly for a
    // uniform beam. The FFR model with twelve non-rotating modes is a
    // Ritz approximation of these (from above, converging with the modes).
    let scale = (EI / (RHO_A * L.powi(4))).sqrt(); // ω = μ · scale
    let kappa = southwell();
    eprintln!("Southwell κ = {kappa:.6}");
    assert!((kappa - 1.1933).abs() < 1e-4, "κ = {kappa}");
    // The power series against the published values (Hodges and Rutkowski
    // 1981, Wright et al. 1982): μ = 3.5160 at rest, 13.1702 at λ = 12.
    for (lambda, want) in [(0.0, 3.5160), (12.0, 13.1702)] {
        let got = rotating_cantilever(lambda);
        assert!(
            (got - want).abs() < 1e-4,
            "μ(λ = {lambda}) = {got}, published {want}"
        );
    }
    let mut worst: f64 = 0.0;
    for lambda in [0.0, 1.0, 2.0, 4.0, 8.0, 12.0] {
        let omega = lambda * scale;
        let hub = format!("prescribed: [\"{omega}*t\"]");
        let sys = system(&model_with(&hub, true, 16, "", 2.8e10, 1e7));
        let w = frequencies(&Numeric::new(&sys).unwrap(), 16, 0.7);
        let flap = rotating_cantilever(lambda) * scale;
        let lag = (flap * flap - omega * omega).sqrt();
        let (e_lag, e_flap) = (w[0] / lag - 1.0, w[1] / flap - 1.0);
        eprintln!(
            "λ = {lambda:4}: lag {:.6} (exact {lag:.6}, {e_lag:+.1e}), flap {:.6} \
             (exact {flap:.6}, {e_flap:+.1e}); Southwell's line {:.6}",
            w[0],
            w[1],
            (3.516_015_f64.powi(2) + kappa * lambda * lambda).sqrt() * scale
        );
        // Ritz: from above; in the mode space the lag problem is the flap
        // problem shifted by −Ω², so both carry the same error in ω², at
        // most 2e-4 of ω_flap² with eight modes per plane at λ = 12.
        for (got, want) in [(w[0], lag), (w[1], flap)] {
            let e2 = (got * got - want * want) / (flap * flap);
            assert!(
                (-1e-9..2e-4).contains(&e2),
                "λ = {lambda}: lag {} want {lag}, flap {} want {flap} (error in ω² {e2:e})",
                w[0],
                w[1]
            );
        }
        worst = worst.max(e_lag.abs()).max(e_flap.abs());
    }
    eprintln!("largest relative error {worst:e}");

    // One flapping mode (the non-rotating one) gives Southwell's line
    // exactly: ω² = ω₀² + κ Ω², with κ from the exact mode (the FE mode
    // and ω₀ are within ~1e-7 of it with 20 elements).
    let w0 = 1.875_104_068_711_961_f64.powi(2) * scale;
    for lambda in [1.0, 5.0, 12.0] {
        let omega = lambda * scale;
        let sys = system(&model(&format!("prescribed: [\"{omega}*t\"]"), true, 2, ""));
        let w = frequencies(&Numeric::new(&sys).unwrap(), 2, 0.0);
        let want = (w0 * w0 + kappa * omega * omega).sqrt();
        let want_lag = (w0 * w0 + (kappa - 1.0) * omega * omega).sqrt();
        assert!(
            (w[1] / want - 1.0).abs() < 1e-6 && (w[0] / want_lag - 1.0).abs() < 1e-6,
            "λ = {lambda}: one mode gives {w:?}, Southwell {want_lag}, {want}"
        );
    }
}

#[test]
fn stiffening_off_the_linear_model_softens_and_loses_stability_past_the_first_frequency() {
    // Without stiffening the linear FFR model has only the in-plane
    // softening: ω_lag² = ω₀² − Ω² (with the first mode), negative once
    // Ω > ω₀ ≈ 3.80 rad/s for this beam; flapping keeps ω₀ at any speed.
    let scale = (EI / (RHO_A * L.powi(4))).sqrt();
    let w0 = 1.875_104_068_711_961_f64.powi(2) * scale;
    for omega in [2.0, 6.0] {
        let sys = system(&model(
            &format!("prescribed: [\"{omega}*t\"]"),
            false,
            2,
            "",
        ));
        let w = frequencies(&Numeric::new(&sys).unwrap(), 2, 0.0);
        let lag2 = w0 * w0 - omega * omega;
        let got2 = w[0].signum() * w[0] * w[0];
        assert!(
            (got2 - lag2).abs() < 1e-6 * w0 * w0 && (w[1] / w0 - 1.0).abs() < 1e-6,
            "Ω = {omega}: {w:?}, want ω_lag² = {lag2}, ω_flap = {w0}"
        );
    }
}

#[test]
fn stiffening_by_gravity_along_a_hanging_beam_and_buckling_of_a_standing_one() {
    // Gravity along the beam is an axial load ρA g (L − x): tension when
    // the beam hangs (frequencies rise), compression when it stands. A
    // column clamped at its foot buckles under its own weight at
    // q L³ / EI = 7.837 (Greenhill 1881; Timoshenko and Gere §2.10):
    // at g_cr = 7.837 EI / (ρA L³) the lowest frequency of the standing
    // beam reaches zero. Here the beam stands along +x with gravity
    // along −x (locked hub), without spin.
    let g_cr = 7.837_347 * EI / (RHO_A * L.powi(3));
    let at = |g: f64, stiffening: bool| {
        let gravity = format!("gravity: ({g}, 0, 0),");
        let sys = system(&model("locked: true", stiffening, 12, &gravity));
        frequencies(&Numeric::new(&sys).unwrap(), 12, 0.0)[0]
    };
    let w_free = at(0.0, true);
    let below = at(-0.99 * g_cr, true);
    let above = at(-1.01 * g_cr, true);
    eprintln!(
        "standing column: ω₁ = {w_free} unloaded, {below} at 0.99 g_cr, {above} at 1.01 g_cr"
    );
    assert!(
        below > 0.0 && above < 0.0,
        "ω₁ {below} below, {above} above g_cr"
    );
    // Hanging (gravity along +x pulls the beam out): stiffer; and the
    // linear model without stiffening ignores gravity's axial part.
    let hanging = at(9.81, true);
    assert!(hanging > w_free, "hanging ω₁ {hanging} ≤ unloaded {w_free}");
    assert!((at(9.81, false) / w_free - 1.0).abs() < 1e-9);
}

/// `ẏ = (q̇, u̇)` by the articulated-body algorithm.
struct Ode<'a> {
    num: &'a Numeric,
    n: usize,
}

impl<const N: usize> OdeSystem<N> for Ode<'_> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let n = self.n;
        let (q, u) = y.split_at(n);
        let tau = vec![0.0; n];
        let ud = self
            .num
            .forward_dynamics(q, u, t, &tau, &[])
            .unwrap_or_else(|_| vec![f64::NAN; n]);
        dy[..n].copy_from_slice(&self.num.qdot(q, u));
        dy[n..].copy_from_slice(&ud);
    }
}

#[test]
fn stiffening_keeps_m_symmetric_aba_exact_and_energy_conserved() {
    // A free hub on a revolute joint about z carries the beam on a
    // revolute joint about its y axis, with gravity along −z: the beam
    // swings, spins, stretches and bends, so every foreshortening term is
    // exercised (centrifugal, hub radius, axial acceleration, gravity
    // along the beam). No damping: T + V is a first integral of the
    // second-order Lagrangian the terms come from, so it is conserved to
    // the integrator's tolerance; ABA equals M⁻¹(τ − b) and the generated
    // programs equal the f64 run.
    let text = r#"Model(
    name: "swinging_beam",
    gravity: (0, 0, -9.81),
    bodies: [
        (name: "hub", mass: 2.0, inertia: Diag(0.3, 0.3, 0.5)),
        (name: "beam", flexible: Beam(length: 2, rho_a: 1.5, rho_ip: 0.002, ea: 1e5,
            ei_y: 400, ei_z: 300, gj: 20, elements: 6, reference: Clamped, modes: 5,
            stiffening: true)),
    ],
    joints: [
        (name: "hub_j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "hub"),
        (name: "beam_j", kind: Revolute(axis: (0, 1, 0)), parent: "hub", child: "beam",
         parent_frame: (position: (0.3, 0, 0))),
    ],
)"#;
    let sys = system(text);
    let num = Numeric::new(&sys).unwrap();
    let n = 7;
    let y0 = [
        0.0, 0.3, 0.05, -0.04, 0.02, 0.01, 0.005, // q: hub, beam, 5 elastic
        3.0, -1.0, 0.5, 0.4, -0.2, 0.1, 0.05, // u
    ];
    // M symmetric, ABA = LᵀDL solve, at the start.
    let terms = num.terms(&y0[..n], &y0[n..], 0.0, &[]).unwrap();
    let m = &terms.mass_matrix;
    for (r, row) in m.iter().enumerate() {
        for (c, &x) in row.iter().enumerate() {
            assert!(
                (x - m[c][r]).abs() < 1e-12 * row[r].abs().max(1.0),
                "M[{r}][{c}] = {x} but M[{c}][{r}] = {}",
                m[c][r]
            );
        }
    }
    let tau = vec![0.0; n];
    let aba = num
        .forward_dynamics(&y0[..n], &y0[n..], 0.0, &tau, &[])
        .unwrap();
    let ltdl = num
        .forward_dynamics_ltdl(&y0[..n], &y0[n..], 0.0, &tau, &[])
        .unwrap();
    for (k, (a, b)) in aba.iter().zip(&ltdl).enumerate() {
        assert!(
            (a - b).abs() < 1e-9 * b.abs().max(1.0),
            "u̇[{k}]: ABA {a}, LᵀDL {b}"
        );
    }
    let energy = |y: &[f64; 14]| {
        let (t, v) = num.energy(&y[..n], &y[n..], 0.0).unwrap();
        (t + v, t.abs() + v.abs())
    };
    let (e0, scale) = energy(&y0);
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &Ode { num: &num, n },
        0.0,
        y0,
        3.0,
        &SolveOptions {
            t_eval: (1..=30).map(|k| 0.1 * k as f64).collect(),
            ..SolveOptions::default()
        },
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 30, "stopped: {:?}", sol.stop);
    let drift = sol
        .y_out
        .iter()
        .map(|y| (energy(y).0 - e0).abs() / scale)
        .fold(0.0, f64::max);
    eprintln!(
        "relative energy drift {drift:e} over 3 s, {} steps",
        sol.stats.accepted
    );
    assert!(drift < 1e-8, "relative energy drift {drift:e}");

    // The symbolic path gives the same numbers.
    use eom_gen::functions::{Function, FunctionSet};
    let f = eom_gen::mech::formulate(&sys, FunctionSet::all_requested())
        .unwrap_or_else(|e| panic!("{e}"));
    let point = eom_gen::interpret::Point {
        sys: &sys,
        q: &y0[..n],
        u: &y0[n..],
        udot: &aba,
        tau: &tau,
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.0,
    };
    let run = |function: Function| {
        eom_gen::interpret::run(f.program(function).expect("requested"), &point)
    };
    let fd = run(Function::ForwardDynamics);
    for (k, (g, w)) in fd.iter().zip(&aba).enumerate() {
        assert!(
            (g - w).abs() < 1e-10 * w.abs().max(1.0),
            "u̇[{k}]: generated {g}, f64 {w}"
        );
    }
    let (t, v) = num.energy(&y0[..n], &y0[n..], 0.0).unwrap();
    let e = run(Function::Energy);
    assert!((e[0] - t).abs() < 1e-10 * t && (e[1] - v).abs() < 1e-10 * v.abs().max(1.0));
}
