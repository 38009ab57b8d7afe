//! Linearisation of models that move and of constrained models
//! (`eom_gen::linearize`), against closed forms and a published benchmark:
//!
//! - **The Whipple bicycle** (`models/whipple.ron`, built from bodies,
//!   joints and two rolling wheels): about its steady upright motion at
//!   forward speed `v` the linearisation in independent coordinates has the
//!   eigenvalues of the benchmark's linear equations
//!   `M q̈ + v C₁ q̇ + (g K₀ + v² K₂) q = 0` (Meijaard, Papadopoulos, Ruina
//!   and Schwab 2007, their matrices to 14 digits) at every speed from 0
//!   to 10 m/s, plus one zero (the forward speed, conserved); the weave
//!   and capsize speeds, where the bicycle becomes self-stable and stops
//!   being so, found by bisection on each, agree with the benchmark's.
//! - **A free rigid body spinning** about a principal axis (a tree whose
//!   quaternion moves): the Euler equations' exponents
//!   `±Ω √((I₂−I₁)(I₃−I₂)/(I₁I₃))` about the intermediate axis (unstable)
//!   and `±iΩ √((I₃−I₁)(I₃−I₂)/(I₁I₂))` about the major one, with the
//!   chart's own `0, ±iΩ/2` of the attitude.
//! - **A disk rolling upright** (Appell, Korteweg; built with its spin on
//!   a revolute joint, so that the spin angle is cyclic): the lean
//!   oscillates at `ω² = (A(A + mR²)Ω² − B m g R) / (B(B + mR²))` above
//!   the critical spin and diverges below it (the thin disk's `Ω² = g/3R`).
//! - **Outputs** `δh = C y + D w`: the pendulum's tip and hinge
//!   reaction against the hand derivation (the reaction's tangential
//!   component `τ/l` depends on the input alone, `D = 1/l`).
//! - A constrained state that is no steady motion is refused; so is a
//!   state with a unilateral contact closed (the ball on the floor), while
//!   the ball in flight is free fall.

use eom_gen::functions::{Function, FunctionSet};
use eom_gen::interpret::Point;
use eom_gen::linearize::{Eigenvalue, LinearizeError, eigenvalues, linearize};
use eom_gen::mech::{Formulation, formulate};
use eom_gen::model::{Source, check};
use eom_gen::{System, check_file};
use nalgebra::{Complex, DMatrix};

fn system(name: &str) -> System {
    check_file(&format!(
        "{}/../models/{name}.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap_or_else(|r| panic!("{r}"))
    .system
}

fn with_derivatives(sys: &System) -> Formulation {
    formulate(
        sys,
        FunctionSet::default().with(Function::ForwardDynamicsDerivatives),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

fn point<'a>(sys: &'a System, q: &'a [f64], u: &'a [f64]) -> Point<'a> {
    Point {
        sys,
        q,
        u,
        udot: &[],
        tau: &[],
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.0,
    }
}

/// The benchmark's linear equations (Meijaard et al. 2007, eq. (5.3)
/// with the matrices of their section 5, to 14 digits), as `ẋ = A x` with
/// `x = (φ, δ, φ̇, δ̇)`: lean and steer.
fn benchmark(v: f64) -> DMatrix<f64> {
    let g = 9.81;
    let m = DMatrix::from_row_slice(
        2,
        2,
        &[
            80.81722,
            2.31941332208709,
            2.31941332208709,
            0.29784188199686,
        ],
    );
    let c1 = DMatrix::from_row_slice(
        2,
        2,
        &[0.0, 33.86641391492494, -0.85035641456978, 1.68540397397560],
    );
    let k0 = DMatrix::from_row_slice(
        2,
        2,
        &[
            -80.95,
            -2.59951685249872,
            -2.59951685249872,
            -0.80329488458618,
        ],
    );
    let k2 = DMatrix::from_row_slice(2, 2, &[0.0, 76.59734589573222, 0.0, 2.65431523794604]);
    let mi = m.try_inverse().expect("M is regular");
    let mut a = DMatrix::<f64>::zeros(4, 4);
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    a.view_mut((2, 0), (2, 2))
        .copy_from(&(-&mi * (k0 * g + k2 * (v * v))));
    a.view_mut((2, 2), (2, 2)).copy_from(&(-&mi * c1 * v));
    a
}

/// The Whipple bicycle's eigenvalues about its steady upright motion at
/// forward speed `v`, from the nonlinear model.
struct Bicycle {
    sys: System,
    f: Formulation,
}

impl Bicycle {
    fn new() -> Bicycle {
        let sys = system("whipple");
        let f = with_derivatives(&sys);
        Bicycle { sys, f }
    }

    /// The steady upright motion at `v`: the rear frame moves along x,
    /// the wheels roll (`rR = 0.3`, `rF = 0.35`).
    fn eigenvalues(&self, v: f64) -> Vec<Eigenvalue> {
        let q = self.sys.q0();
        let u = [v, 0.0, 0.0, 0.0, 0.0, 0.0, v / 0.3, 0.0, v / 0.35];
        let lin = linearize(&self.f, &point(&self.sys, &q, &u)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(lin.a.nrows(), 5, "lean, steer, their rates and the speed");
        eigenvalues(&lin.a).expect("converges")
    }
}

fn complex(l: &Eigenvalue) -> Complex<f64> {
    Complex::new(l.re, l.im)
}

/// The weave speed (the weave's oscillatory pair crosses to the left half
/// plane) and the capsize speed (the capsize's real eigenvalue crosses to
/// the right), by bisection on `f(v)`, the real part of the eigenvalue
/// concerned.
fn bisect(mut lo: f64, mut hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let (flo, fhi) = (f(lo), f(hi));
    assert!(
        flo * fhi < 0.0,
        "no sign change on [{lo}, {hi}]: {flo}, {fhi}"
    );
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if f(mid) * flo > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The largest real part of the complex (oscillatory) eigenvalues.
fn weave(e: &[Complex<f64>]) -> f64 {
    e.iter()
        .filter(|l| l.im.abs() > 1e-6)
        .map(|l| l.re)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The capsize eigenvalue near its crossing (about 6 m/s): the real
/// eigenvalue of smallest magnitude but the structural zero, which is
/// recognised as the one whose eigenvector moves neither lean nor steer
/// (here: of the two smallest real ones, the one the benchmark also has).
fn capsize_benchmark(v: f64) -> f64 {
    let e = eigenvalues(&benchmark(v)).expect("converges");
    e.iter()
        .filter(|l| l.im == 0.0)
        .map(|l| l.re)
        .min_by(|a, b| a.abs().total_cmp(&b.abs()))
        .expect("a real eigenvalue")
}

#[test]
fn whipple_bicycle_matches_the_benchmark_eigenvalues() {
    let bike = Bicycle::new();
    let mut worst = 0.0f64;
    for k in 0..=20 {
        let v = 0.5 * k as f64;
        let ours: Vec<Complex<f64>> = bike.eigenvalues(v).iter().map(complex).collect();
        let want: Vec<Complex<f64>> = eigenvalues(&benchmark(v))
            .expect("converges")
            .iter()
            .map(complex)
            .collect();
        // Each of the benchmark's four has its match; the one left over is
        // the forward speed's zero.
        let mut used = [false; 5];
        for w in &want {
            let (i, d) = ours
                .iter()
                .enumerate()
                .filter(|(i, _)| !used[*i])
                .map(|(i, l)| (i, (l - w).norm()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .expect("an eigenvalue left");
            used[i] = true;
            worst = worst.max(d / w.norm().max(1.0));
            assert!(
                d <= 1e-11 * w.norm().max(1.0),
                "v = {v}: benchmark eigenvalue {w} has nearest {} (off by {d:.2e}); ours {ours:?}",
                ours[i]
            );
        }
        let rest = ours[used.iter().position(|u| !u).expect("one left")];
        assert!(
            rest.norm() < 1e-11,
            "v = {v}: the fifth eigenvalue {rest} is not zero"
        );
    }
    println!("largest eigenvalue difference against the benchmark, 0..10 m/s: {worst:.2e}");
}

#[test]
fn whipple_bicycle_weave_and_capsize_speeds() {
    let bike = Bicycle::new();
    let ours = |v: f64| -> Vec<Complex<f64>> { bike.eigenvalues(v).iter().map(complex).collect() };
    let theirs = |v: f64| -> Vec<Complex<f64>> {
        eigenvalues(&benchmark(v))
            .expect("converges")
            .iter()
            .map(complex)
            .collect()
    };
    let weave_ours = bisect(4.0, 5.0, |v| weave(&ours(v)));
    let weave_theirs = bisect(4.0, 5.0, |v| weave(&theirs(v)));
    // Ours has the speed's zero beside the capsize eigenvalue: take the
    // real eigenvalue nearest the benchmark's at the same speed.
    let capsize_ours = bisect(5.5, 6.5, |v| {
        let want = capsize_benchmark(v);
        ours(v)
            .iter()
            .filter(|l| l.im == 0.0)
            .map(|l| l.re)
            .min_by(|a, b| (a - want).abs().total_cmp(&(b - want).abs()))
            .expect("a real eigenvalue")
    });
    let capsize_theirs = bisect(5.5, 6.5, capsize_benchmark);
    println!("weave speed {weave_ours:.12} m/s (benchmark matrices {weave_theirs:.12})");
    println!("capsize speed {capsize_ours:.12} m/s (benchmark matrices {capsize_theirs:.12})");
    // The paper: v_w = 4.292 382 5, v_c = 6.024 262 0 m/s.
    assert!(
        (weave_ours - weave_theirs).abs() < 1e-10,
        "weave {weave_ours} vs {weave_theirs}"
    );
    assert!(
        (capsize_ours - capsize_theirs).abs() < 1e-10,
        "capsize {capsize_ours} vs {capsize_theirs}"
    );
    assert!((weave_theirs - 4.2923825).abs() < 1e-7);
    assert!((capsize_theirs - 6.0242620).abs() < 1e-7);
}

/// A torque-free body spinning at Ω about a principal axis: a tree whose
/// quaternion moves. The speed block of `A` is the linearised Euler
/// equations; the attitude block is the chart's `−½[ω]×`.
#[test]
fn spinning_free_body_has_the_euler_exponents() {
    let sys = system("free_body");
    let f = with_derivatives(&sys);
    let (i1, i2, i3) = (1.0f64, 2.0f64, 3.0f64);
    let omega = 1.5;
    let q = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
    // About the intermediate axis (y): a real pair ±σ.
    let u = [0.0, 0.0, 0.0, 0.0, omega, 0.0];
    let lin = linearize(&f, &point(&sys, &q, &u)).unwrap_or_else(|e| panic!("{e}"));
    let e: Vec<Complex<f64>> = eigenvalues(&lin.a)
        .expect("converges")
        .iter()
        .map(complex)
        .collect();
    let sigma = omega * ((i2 - i1) * (i3 - i2) / (i1 * i3)).sqrt();
    let half = omega / 2.0;
    for want in [
        Complex::new(sigma, 0.0),
        Complex::new(-sigma, 0.0),
        Complex::new(0.0, half),
        Complex::new(0.0, -half),
    ] {
        let d = e
            .iter()
            .map(|l| (l - want).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(d < 1e-12, "{want} missing from {e:?}");
    }
    // About the major axis (z): an imaginary pair ±iν.
    let u = [0.0, 0.0, 0.0, 0.0, 0.0, omega];
    let lin = linearize(&f, &point(&sys, &q, &u)).unwrap_or_else(|e| panic!("{e}"));
    let e = eigenvalues(&lin.a).expect("converges");
    let nu = omega * ((i3 - i1) * (i3 - i2) / (i1 * i2)).sqrt();
    assert!(
        e.iter()
            .any(|l| l.re.abs() < 1e-12 && (l.im - nu).abs() < 1e-12),
        "iν = {nu} missing from {e:?}"
    );
    assert!(e.iter().all(|l| l.re.abs() < 1e-12), "stable: {e:?}");
}

/// A rolling bicycle leaning but not turning is not a steady motion: it
/// falls. Refused, never a linearisation of the wrong system.
#[test]
fn bicycle_away_from_a_steady_motion_is_refused() {
    let bike = Bicycle::new();
    // Upright, but the wheels roll slower than the frame moves: the state
    // violates the rolling conditions.
    let q = bike.sys.q0();
    let u = [4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 4.0 / 0.35];
    let err = linearize(&bike.f, &point(&bike.sys, &q, &u)).expect_err("not assembled");
    assert!(matches!(err, LinearizeError::NotAssembled { .. }), "{err}");
    // Leaning by 0.1 rad at rest, about the line through both contacts
    // (which keeps both wheels on the ground): a consistent state, not an
    // equilibrium — the bicycle falls.
    let lean = 0.1f64;
    let q = [
        0.0,
        -0.3 * lean.sin(),
        0.3 * lean.cos(),
        (lean / 2.0).cos(),
        (lean / 2.0).sin(),
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    let err = linearize(&bike.f, &point(&bike.sys, &q, &[0.0; 9])).expect_err("falls");
    assert!(matches!(err, LinearizeError::NotSteady { .. }), "{err}");
}

/// A uniform thin disk (m = 1 kg, R = 0.1 m, axial A = mR²/2, diametral
/// B = mR²/4) rolling upright along x with spin Ω: translations, heading,
/// lean and spin as a chain of joints (the links between them weigh
/// 1e-9 kg, which moves the eigenvalues by about 1e-9 relative), so the
/// position and spin angle are cyclic. The lean's exponents:
/// `λ² = −ω²`, `ω² = (A(A + mR²)Ω² − B m g R) / (B(B + mR²))`.
fn rolling_disk(spin: f64) -> (System, Vec<f64>) {
    let text = format!(
        r#"Model(
    name: "upright_disk",
    gravity: (0, 0, -9.81),
    parameters: [(name: "R", value: 0.1), (name: "m", value: 1.0), (name: "e", value: 1e-9)],
    bodies: [
        (name: "sx", mass: "e"), (name: "sy", mass: "e"), (name: "sz", mass: "e"),
        (name: "heading", mass: "e"), (name: "leaning", mass: "e"),
        (name: "disk", mass: "m", inertia: Diag("m*R^2/4", "m*R^2/2", "m*R^2/4")),
    ],
    joints: [
        (name: "x", kind: Prismatic(axis: (1, 0, 0)), parent: "ground", child: "sx", u0: [{v}]),
        (name: "y", kind: Prismatic(axis: (0, 1, 0)), parent: "sx", child: "sy"),
        (name: "z", kind: Prismatic(axis: (0, 0, 1)), parent: "sy", child: "sz", q0: ["R"]),
        (name: "psi", kind: Revolute(axis: (0, 0, 1)), parent: "sz", child: "heading"),
        (name: "phi", kind: Revolute(axis: (1, 0, 0)), parent: "heading", child: "leaning"),
        (name: "spin", kind: Revolute(axis: (0, 1, 0)), parent: "leaning", child: "disk", u0: [{spin}]),
    ],
    constraints: [RollingDisk(name: "contact", body: "disk", radius: "R", axis: (0, 1, 0))],
)"#,
        v = spin * 0.1,
    );
    let sys = check(&Source::new("upright_disk", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let u = sys.u0();
    (sys, u)
}

#[test]
fn upright_rolling_disk_lean_frequency() {
    let (m, r, g) = (1.0f64, 0.1f64, 9.81f64);
    let (a, b) = (m * r * r / 2.0, m * r * r / 4.0);
    let critical = (g / (3.0 * r)).sqrt();
    for spin in [6.86, 10.0, 4.0] {
        let (sys, u) = rolling_disk(spin);
        let f = with_derivatives(&sys);
        let q = sys.q0();
        let lin = linearize(&f, &point(&sys, &q, &u)).unwrap_or_else(|e| panic!("Ω = {spin}: {e}"));
        // The heading is not cyclic here: the rolling conditions in the
        // world-axis speeds ẋ, ẏ depend on it (it stays a state, with a
        // zero eigenvalue).
        assert_eq!(
            lin.cyclic,
            ["x", "y", "spin"],
            "position and spin angle are cyclic"
        );
        let e = eigenvalues(&lin.a).expect("converges");
        let w2 = (a * (a + m * r * r) * spin * spin - b * m * g * r) / (b * (b + m * r * r));
        let want = if w2 > 0.0 {
            Complex::new(0.0, w2.sqrt())
        } else {
            Complex::new((-w2).sqrt(), 0.0)
        };
        assert_eq!(spin > critical, w2 > 0.0);
        let d = e
            .iter()
            .map(|l| (complex(l) - want).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(
            d < 1e-7 * want.norm(),
            "Ω = {spin}: {want} missing from {e:?}"
        );
        // The rest: the lean's partner and zeros (the speed, conserved).
        assert!(
            e.iter()
                .all(|l| l.natural_frequency < 1e-7
                    || (l.natural_frequency - want.norm()).abs() < 1e-6),
            "Ω = {spin}: {e:?}"
        );
    }
}

/// The bundled pendulum (point mass m = 1 kg at l = 1 m, g = 9.81, outputs
/// tip and hinge reaction; the energy is a function of its own, not an
/// output row) at θ = 0.3, θ̇ = 0.7: tip `(l sin θ, −l cos θ)`, so
/// `C = (l cos θ, 0)`, `(l sin θ, 0)`; the hinge's
/// force on the bob in its frame `F = m a − m g` is `(τ/l,
/// m l θ̇² + m g cos θ)` with `θ̈ = −(g/l) sin θ + τ/(m l²)`.
#[test]
fn pendulum_outputs_c_and_d_are_the_hand_derivation() {
    let sys = system("pendulum");
    let f = with_derivatives(&sys);
    let (m, l, g, th, w) = (1.0f64, 1.0f64, 9.81f64, 0.3f64, 0.7f64);
    let lin = linearize(&f, &point(&sys, &[th], &[w])).unwrap_or_else(|e| panic!("{e}"));
    let row = |name: &str| {
        let i = lin
            .outputs
            .iter()
            .position(|o| o == name)
            .unwrap_or_else(|| panic!("{name} in {:?}", lin.outputs));
        (lin.c[(i, 0)], lin.c[(i, 1)], lin.d[(i, 0)])
    };
    let cases = [
        ("bob_tip_x", (l * th.cos(), 0.0, 0.0)),
        ("bob_tip_y", (l * th.sin(), 0.0, 0.0)),
        ("hinge_fx", (0.0, 0.0, 1.0 / l)),
        ("hinge_fy", (-m * g * th.sin(), 2.0 * m * l * w, 0.0)),
    ];
    for (name, want) in cases {
        let got = row(name);
        for (k, (a, b)) in [(got.0, want.0), (got.1, want.1), (got.2, want.2)]
            .into_iter()
            .enumerate()
        {
            assert!((a - b).abs() < 1e-9, "{name} [{k}]: {a} vs {b}");
        }
    }
}

/// `models/bouncing_ball.ron` (a ball of radius 0.1 m on a prismatic joint
/// along z, the floor a unilateral contact): in flight every contact is
/// open and the linearisation is free fall (`A = [[0, 1], [0, 0]]`); resting
/// on the floor (`z = r`, the gap zero) the contact is closed and the state
/// is refused, naming the contact.
#[test]
fn closed_contacts_are_refused_open_ones_left_out() {
    let sys = system("bouncing_ball");
    let f = with_derivatives(&sys);
    let lin = linearize(&f, &point(&sys, &[1.1], &[0.0])).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        lin.a.as_slice(),
        &[0.0, 0.0, 1.0, 0.0],
        "free fall (column-major)"
    );
    let err = linearize(&f, &point(&sys, &[0.1], &[0.0])).expect_err("resting on the floor");
    assert!(
        matches!(&err, LinearizeError::ClosedContacts { rows, .. } if rows.len() == 1),
        "{err}"
    );
    assert!(err.to_string().contains("floor"), "{err}");
}
