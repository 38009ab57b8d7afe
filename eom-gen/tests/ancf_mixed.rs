//! Rigid bodies and ANCF cables in one model file (issue #18): the cable
//! ends held at markers (`start_at`, `end_at`), the generated
//! `attachments` function, and the mixed model built from them
//! (`eom_gen::cables`) with the rigid part interpreted.
//!
//! Physics checked:
//! - **Located errors** for every wrong attachment at once: an unknown
//!   marker (with the nearest name), ground as the body, a clamped end
//!   without an axis, a pinned end with one, a free end held at a marker.
//! - **The generated `attachments` against its numeric twin**: positions
//!   and clamp normals from the `f64` run of the same scalar-generic code
//!   (`Numeric::mounts`), the Jacobians against central differences of it,
//!   at random states of a two-coordinate rigid part.
//! - **A stiff rod clamped to a link swings as eom's own rigid model**:
//!   the mixed model (link interpreted, steel ANCF rod clamped at its tip)
//!   against the purely rigid model of the link with the rod welded on
//!   (`Fixed` joint), integrated by DOP853; the difference falls with the
//!   rod's compliance.
//! - **The bundled `models/ancf/pendulum_rod.ron`** (the Berzeri–Shabana
//!   rod pinned to a rigid link) keeps its energy to second order in the
//!   step and its constraint residual at the Newton tolerance.
//! - **The bundled `models/ancf/trapeze.ron`** (a rigid bar hanging by two
//!   ANCF ropes, several cables in one mixed model): without damping its
//!   energy is kept to second order in the step (halving `h` cuts the
//!   largest drift about 4×); released as a tilted parallelogram it swings
//!   with the bar level — by symmetry the two ropes pull equally, so the
//!   bar's angle stays at round-off and the right rope is the left one
//!   moved by the pivots' spacing — and as the rigid parallelogram (the
//!   compound pendulum of the bar and two uniform rods), up to the ropes'
//!   compliance.
//! - **Independent subsystems in one model file move as each in a file of
//!   its own**: two links each holding a cable (one pinned, one clamped,
//!   of two kernels) and a spatial cable held to ground only (it joins the
//!   same structure), against the two links' models alone: the same
//!   block-diagonal step equations, so with full Newton the states agree
//!   to round-off (1e-12).
//! - **A planar cable on a marker that leaves the plane** is refused,
//!   naming the cable and the marker; the same rope as a `Cable3D` runs.
//! - **Each cable's own loads in the mixed structure**: a node force lands
//!   on exactly its node's position coordinates, a distributed load only
//!   on its cable, with the total `w L`.

use eom_gen::functions::{Function, FunctionSet};
use eom_gen::mech::{Numeric, formulate};
use eom_gen::model::{Source, check};
use eom_sim::large::{AlphaOptions, MixedAlpha};

fn system(name: &str, text: &str) -> eom_gen::System {
    match check(&Source::new(name, text.to_string())) {
        Ok(c) => c.system,
        Err(r) => panic!("{r}"),
    }
}

fn diagnose(text: &str) -> String {
    eom_gen::testkit::diagnose("models/mix.ron", text)
}

/// A link on a cart (`x`, `theta`) with a rod clamped at the link's tip.
const CART_LINK: &str = r#"
Model(
    name: "cart_link",
    gravity: (0, -9.81, 0),
    parameters: [(name: "a", value: 0.3), (name: "E", value: 2e9)],
    bodies: [
        (name: "cart", mass: 2.0),
        (name: "link", mass: 1.0, com: ("a/2", 0, 0), inertia: Diag(0, 0.0075, 0.0075),
         markers: [(name: "tip", position: ("a", 0, 0)), (name: "mid", position: ("a/2", 0, 0))]),
    ],
    joints: [
        (name: "rail", kind: Prismatic(axis: (1, 0, 0)), parent: "ground", child: "cart", coordinates: ["x"]),
        (name: "pivot", kind: Revolute(axis: (0, 0, 1)), parent: "cart", child: "link", coordinates: ["theta"]),
    ],
    cables: [
        Cable(name: "rod", element: Cable2D, from: ("a", 0, 0), to: ("a + 0.5", 0, 0), elements: 4,
              young: "E", density: 7800, width: 0.02, height: 0.02,
              start: Clamped, start_at: (body: "link", marker: "tip", axis: (1, 0, 0))),
    ],
)
"#;

#[test]
fn wrong_attachments_are_located_errors_all_at_once() {
    assert_eq!(diagnose(CART_LINK), "valid");
    let two_cables = CART_LINK.replace(
        "    ],\n)",
        r#"        Cable(name: "b", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 2,
              young: 1e6, density: 1000, width: 0.01, height: 0.01,
              start: Pinned, start_at: (body: "link", marker: "tipp"),
              end: Clamped, end_at: (body: "link", marker: "mid")),
        Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 2,
              young: 1e6, density: 1000, width: 0.01, height: 0.01,
              start: Pinned, start_at: (body: "ground", marker: "o", axis: (1, 0, 0)),
              end: Free, end_at: (body: "cart", marker: "m")),
    ],
)"#,
    );
    let text = diagnose(&two_cables);
    println!("{text}");
    for want in [
        // The unknown marker, with the nearest name.
        "models/mix.ron:21:63: error: body `link` has no marker `tipp`",
        "did you mean `tip`?",
        // Clamped at a marker without an axis.
        "models/mix.ron:22:37: error: the end of cable `b` is clamped at marker `link.mid` without an `axis`",
        "give `axis: (1, 0, 0)`",
        // Ground is not a rigid body to hold a cable.
        "models/mix.ron:25:47: error: the start of cable `c` is held at a marker of `ground`",
        // A free end held at a marker.
        "models/mix.ron:26:34: error: the end of cable `c` is `Free` but held at marker `cart.m`",
        "models/mix.ron:26:57: error: body `cart` has no marker `m`",
    ] {
        assert!(text.contains(want), "missing `{want}` in\n{text}");
    }
    let pinned_axis = CART_LINK.replace(
        "start: Clamped, start_at: (body: \"link\", marker: \"tip\", axis: (1, 0, 0))",
        "start: Pinned, start_at: (body: \"link\", marker: \"tip\", axis: (0, 0, 1))",
    );
    let text = diagnose(&pinned_axis);
    assert!(
        text.contains(
            "models/mix.ron:18:76: error: the start of cable `rod` is pinned: it turns freely"
        ),
        "{text}"
    );
    let off_plane = CART_LINK.replace("axis: (1, 0, 0)", "axis: (1, 0, 1)");
    let text = diagnose(&off_plane);
    assert!(text.contains("leaves the x–y plane"), "{text}");
    let unknown_field = CART_LINK.replace("marker: \"tip\",", "marker: \"tip\", angle: 0,");
    assert!(diagnose(&unknown_field).contains("angle"));
}

#[test]
fn generated_attachments_agree_with_the_numeric_twin() {
    let sys = system("cart_link.ron", CART_LINK);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let num = Numeric::new(&sys).unwrap_or_else(|e| panic!("{e}"));
    let mut rng = eom_gen::testkit::Rng(18);
    let nq = sys.nq();
    assert_eq!(f.mounts, vec!["rod.start".to_string()]);
    for _ in 0..5 {
        let q = rng.vec(nq, 2.0);
        let t = rng.uniform();
        let x = eom_gen::interpret::Point {
            sys: &sys,
            q: &q,
            u: &[0.0, 0.0],
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t,
        };
        let got = eom_gen::interpret::evaluate_function(&f, Function::Attachments, &x)
            .unwrap_or_else(|| panic!("no attachments"));
        let want = num.mounts(&sys, &q, t).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(want.len(), 9, "position, n1, n2");
        assert_eq!(got.len(), want.len() * (1 + nq));
        // Closed form: the tip at (x + a cos θ, a sin θ), n1 = (−sin θ, cos θ).
        let (s, c) = q[1].sin_cos();
        let closed = [q[0] + 0.3 * c, 0.3 * s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0];
        for r in 0..want.len() {
            let value = got[r * (1 + nq)];
            assert!(
                (value - want[r]).abs() < 1e-13,
                "row {r}: got {value}, twin {}",
                want[r]
            );
            assert!(
                (value - closed[r]).abs() < 1e-13,
                "row {r}: got {value}, closed form {}",
                closed[r]
            );
            for k in 0..nq {
                let e = 1e-6;
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[k] += e;
                qm[k] -= e;
                let fd = (num.mounts(&sys, &qp, t).unwrap_or_default()[r]
                    - num.mounts(&sys, &qm, t).unwrap_or_default()[r])
                    / (2.0 * e);
                let d = got[r * (1 + nq) + 1 + k];
                assert!(
                    (d - fd).abs() < 1e-8,
                    "∂(row {r})/∂q{k}: got {d}, differences {fd}"
                );
            }
        }
    }
    // The emitted code has the function, documented by its row.
    let src = eom_gen::generate(&Source::new("cart_link.ron", CART_LINK.to_string()))
        .map(|g| g.source)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        src.contains("pub fn attachments("),
        "no attachments in the emitted code"
    );
}

/// The angle of the link on a fixed pivot (the cart locked by a stiff rail:
/// here a model of its own) with a steel rod of modulus `e` clamped at its
/// tip, at `t_end`, and the largest constraint residual.
fn mixed_angle(e: f64, t_end: f64) -> (f64, f64) {
    let text = LINK_ROD.replace("E_VALUE", &format!("{e:e}"));
    let sys = system("link_rod.ron", &text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &mixed.model;
    let state = m.initial_state(0.0, &sys.q0(), &sys.u0());
    let opts = AlphaOptions {
        h: 1e-3,
        rho_inf: 0.9,
        ..AlphaOptions::default()
    };
    let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    ga.run_to(t_end, |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    (
        ga.state().q[m.n_structural()],
        ga.stats.max_constraint_residual,
    )
}

const LINK_ROD: &str = r#"
Model(
    name: "link_rod",
    gravity: (0, -9.81, 0),
    parameters: [(name: "a", value: 0.3)],
    bodies: [(name: "link", mass: 1.0, com: ("a/2", 0, 0), inertia: Diag(0, 0.0075, 0.0075),
              markers: [(name: "tip", position: ("a", 0, 0))])],
    joints: [(name: "pivot", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "link", coordinates: ["theta"])],
    cables: [
        Cable(name: "rod", element: Cable2D, from: ("a", 0, 0), to: ("a + 0.5", 0, 0), elements: 4,
              young: E_VALUE, density: 7800, width: 0.02, height: 0.02,
              start: Clamped, start_at: (body: "link", marker: "tip", axis: (1, 0, 0))),
    ],
)
"#;

/// The same link with the rod as a rigid body welded to its tip.
const LINK_RIGID_ROD: &str = r#"
Model(
    name: "link_rigid_rod",
    gravity: (0, -9.81, 0),
    parameters: [(name: "a", value: 0.3), (name: "mr", value: "7800*0.02^2*0.5")],
    bodies: [
        (name: "link", mass: 1.0, com: ("a/2", 0, 0), inertia: Diag(0, 0.0075, 0.0075)),
        (name: "rod", mass: "mr", com: (0.25, 0, 0), inertia: Diag(0, "mr*0.5^2/12", "mr*0.5^2/12")),
    ],
    joints: [
        (name: "pivot", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "link", coordinates: ["theta"]),
        (name: "weld", kind: Fixed, parent: "link", child: "rod", parent_frame: (position: ("a", 0, 0))),
    ],
)
"#;

#[test]
fn a_stiff_rod_clamped_to_a_link_swings_as_eoms_rigid_model() {
    let t_end = 0.3;
    let rigid = system("link_rigid_rod.ron", LINK_RIGID_ROD);
    let f = formulate(&rigid, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let o = eom_sim::RunOptions {
        integrator: "dop853".parse().unwrap_or_else(|e| panic!("{e:?}")),
        rtol: 1e-12,
        atol: 1e-12,
        t_end,
        ..Default::default()
    };
    let report = eom_gen::interpret::simulate(&f, &rigid, &o).unwrap_or_else(|e| panic!("{e}"));
    let want = report.q[0];
    let (soft, r1) = mixed_angle(2e9, t_end);
    let (stiff, r2) = mixed_angle(2e10, t_end);
    let (d1, d2) = ((soft - want).abs(), (stiff - want).abs());
    println!(
        "θ({t_end}) rigid model {want:.9}; mixed, E = 2e9: {soft:.9} (Δ {d1:.2e}); E = 2e10: {stiff:.9} (Δ {d2:.2e}); max |Φ| {r1:.1e}, {r2:.1e}"
    );
    assert!(d2 < 2e-3 * want.abs(), "Δ {d2}");
    // Ten times stiffer, about ten times closer: the difference is the
    // rod's compliance, not the coupling.
    assert!(d1 / d2 > 5.0 && d1 / d2 < 20.0, "ratio {}", d1 / d2);
    assert!(r1 < 1e-9 && r2 < 1e-9);
}

/// The largest energy error of the bundled `pendulum_rod` over
/// `[0, t_end]` at step `h` (no damping, `ρ∞ = 1`), and the largest
/// constraint residual.
fn pendulum_rod_energy(h: f64, t_end: f64) -> (f64, f64) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/pendulum_rod.ron"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let sys = system("pendulum_rod.ron", &text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &mixed.model;
    let state = m.initial_state(0.0, &sys.q0(), &sys.u0());
    let e0 = m.energy(&state);
    let opts = AlphaOptions {
        h,
        ..AlphaOptions::default()
    };
    let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    let mut worst: f64 = 0.0;
    ga.run_to(t_end, |s, _| worst = worst.max((m.energy(s) - e0).abs()))
        .unwrap_or_else(|e| panic!("{e}"));
    (worst, ga.stats.max_constraint_residual)
}

#[test]
fn the_bundled_pendulum_rod_keeps_its_energy_to_second_order() {
    let t_end = 0.5;
    let (e1, r1) = pendulum_rod_energy(2e-3, t_end);
    let (e2, r2) = pendulum_rod_energy(1e-3, t_end);
    let order = (e1 / e2).log2();
    println!(
        "pendulum_rod, max |ΔE| over {t_end} s: h = 2e-3 {e1:.3e} J, 1e-3 {e2:.3e} J, order {order:.2}; max |Φ| {r1:.1e}, {r2:.1e}"
    );
    assert!(order > 1.7 && order < 2.5, "order {order}");
    assert!(r1 < 1e-9 && r2 < 1e-9);
}

/// The quasi-static tip deflection of the spin-up beam at `t < T_s` (see
/// `flex_spin_up.rs`): the inertia load `−ρA α x` on a cantilever,
/// `u_y(L) = −11 ρA α L⁵ / (120 EI)`, reduced by the centrifugal
/// stiffening of the first mode (Southwell, κ = 1.1933).
fn spin_up_quasi_static(t: f64) -> f64 {
    let (l, rho_a, ei, w_s, t_s) = (10.0_f64, 1.2, 1.4e4, 6.0, 15.0);
    let phase = 2.0 * std::f64::consts::PI * t / t_s;
    let alpha = w_s / t_s * (1.0 - phase.cos());
    let omega = w_s / t_s * (t - phase.sin() * t_s / (2.0 * std::f64::consts::PI));
    let w1 = 3.516_015 * (ei / (rho_a * l.powi(4))).sqrt();
    let stiffer = 1.0 + 0.1933 * omega * omega / (w1 * w1);
    -11.0 * rho_a * alpha * l.powi(5) / (120.0 * ei) / stiffer
}

#[test]
fn the_ancf_beam_on_a_prescribed_hub_lags_by_the_quasi_static_deflection() {
    // models/ancf/spin_up_ancf.ron: the rigid part has no free coordinate
    // (the hub's angle is prescribed); the root is clamped to the hub.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/spin_up_ancf.ron"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let sys = system("spin_up_ancf.ron", &text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &mixed.model;
    assert_eq!(m.n(), m.n_structural(), "no rigid coordinate");
    let state = m.initial_state(0.0, &sys.q0(), &sys.u0());
    let opts = AlphaOptions {
        h: 1e-2,
        rho_inf: 0.8,
        ..AlphaOptions::default()
    };
    let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    let t = 7.5;
    ga.run_to(t, |_, _| {}).unwrap_or_else(|e| panic!("{e}"));
    let q = ga.q_full();
    let tip = mixed.node_position(q, 0, mixed.cables[0].nodes - 1);
    // The hub's angle at t, and the tip's deflection across the hub's x axis.
    let (w_s, t_s) = (6.0_f64, 15.0_f64);
    let theta = w_s / t_s
        * (t * t / 2.0
            + (t_s / (2.0 * std::f64::consts::PI)).powi(2)
                * ((2.0 * std::f64::consts::PI * t / t_s).cos() - 1.0));
    let (s, c) = theta.sin_cos();
    let deflection = -s * tip[0] + c * tip[1];
    let want = spin_up_quasi_static(t);
    // The root's tangent stays along the hub's x axis (the clamp).
    let root_tangent = [q[2], q[3]];
    let off_axis = -s * root_tangent[0] + c * root_tangent[1];
    println!(
        "spin-up at {t} s: tip deflection {deflection:.5} m, quasi-static {want:.5} m; root tangent off the axis {off_axis:.1e}; max |Φ| {:.1e}",
        ga.stats.max_constraint_residual
    );
    // The floating-frame model with stiffening meets the same closed form
    // within 5 % (flex_spin_up.rs); the ANCF beam stiffens by itself.
    assert!(
        (deflection / want - 1.0).abs() < 0.05,
        "{deflection} against {want}"
    );
    assert!(off_axis.abs() < 1e-9 && ga.stats.max_constraint_residual < 1e-9);
}

/// Runs the trapeze at step `h` to `t_end` (no damping, `ρ∞ = 1`),
/// calling `observe(mixed, state, q_full)` after every step; returns the
/// largest constraint residual.
fn run_trapeze(
    h: f64,
    t_end: f64,
    observe: impl FnMut(&eom_gen::cables::Mixed<'_>, &eom_sim::large::State, &[f64]),
) -> f64 {
    run_trapeze_with(h, t_end, 1e9, 1.0, observe)
}

/// [`run_trapeze`] with the ropes' Young's modulus `e` and the spectral
/// radius `rho_inf`.
fn run_trapeze_with(
    h: f64,
    t_end: f64,
    e: f64,
    rho_inf: f64,
    mut observe: impl FnMut(&eom_gen::cables::Mixed<'_>, &eom_sim::large::State, &[f64]),
) -> f64 {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/ancf/trapeze.ron");
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let bundled_e = "(name: \"E\", value: 1e9,";
    assert!(text.contains(bundled_e), "the bundled trapeze's E");
    let text = text.replace(bundled_e, &format!("(name: \"E\", value: {e:e},"));
    let sys = system("trapeze.ron", &text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &mixed.model;
    let state = m.initial_state(0.0, &sys.q0(), &sys.u0());
    observe(&mixed, &state, &m.structural_full(&state.q));
    let opts = AlphaOptions {
        h,
        rho_inf,
        ..AlphaOptions::default()
    };
    let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    ga.run_to(t_end, |s, q| observe(&mixed, s, q))
        .unwrap_or_else(|e| panic!("{e}"));
    ga.stats.max_constraint_residual
}

#[test]
fn the_trapeze_keeps_its_energy_to_second_order() {
    let t_end = 0.5;
    let drift = |h: f64| {
        let mut e0 = None;
        let mut worst = 0.0_f64;
        let r = run_trapeze(h, t_end, |mixed, s, _| {
            let e = mixed.model.energy(s);
            let e0 = *e0.get_or_insert(e);
            worst = worst.max((e - e0).abs());
        });
        (worst, r)
    };
    let (e1, r1) = drift(2e-3);
    let (e2, r2) = drift(1e-3);
    let order = (e1 / e2).log2();
    println!(
        "trapeze, max |ΔE| over {t_end} s: h = 2e-3 {e1:.3e} J, 1e-3 {e2:.3e} J, order {order:.2}; max |Φ| {r1:.1e}, {r2:.1e}"
    );
    // The energy exchanged in the swing: m g L (1 − cos φ0) ≈ 0.87 J; the
    // drift is a few millionths of it.
    assert!(e2 < 1e-5, "{e2}");
    assert!(order > 1.7 && order < 2.5, "order {order}");
    assert!(r1 < 1e-9 && r2 < 1e-9);
}

/// The rigid parallelogram: a bar of mass `m` translating on a circle of
/// radius `l` and two uniform rods of `mu` kg/m, angle `φ` from the
/// vertical, `I φ̈ = −g S sin φ` with `I = m l² + 2 μ l³/3`,
/// `S = m l + μ l²`, released at rest from `φ0`: the angle at `h, 2h, …,
/// steps · h` (RK4, 20 substeps a step).
fn parallelogram_angles(m: f64, l: f64, mu: f64, phi0: f64, h: f64, steps: usize) -> Vec<f64> {
    let inertia = m * l * l + 2.0 * mu * l.powi(3) / 3.0;
    let moment = m * l + mu * l * l;
    let f = |p: f64| -9.81 * moment * p.sin() / inertia;
    let sub = 20;
    let k = h / sub as f64;
    let (mut p, mut w) = (phi0, 0.0_f64);
    let mut out = Vec::with_capacity(steps);
    for _ in 0..steps {
        for _ in 0..sub {
            let (k1p, k1w) = (w, f(p));
            let (k2p, k2w) = (w + 0.5 * k * k1w, f(p + 0.5 * k * k1p));
            let (k3p, k3w) = (w + 0.5 * k * k2w, f(p + 0.5 * k * k2p));
            let (k4p, k4w) = (w + k * k3w, f(p + k * k3p));
            p += k / 6.0 * (k1p + 2.0 * k2p + 2.0 * k3p + k4p);
            w += k / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
        }
        out.push(p);
    }
    out
}

/// The largest difference over `[0, t_end]` between the trapeze's rope
/// angle (of the bar's centre about the pivots' midpoint) and the rigid
/// parallelogram's, with ropes of modulus `e`; the largest bar angle, the
/// largest difference between the right rope and the left rope moved by
/// `(2a, 0)`, and the largest constraint residual.
fn trapeze_against_rigid(e: f64, t_end: f64) -> (f64, f64, f64, f64) {
    let (a, m, l, d, phi0, h) = (0.25, 2.0, 1.0, 0.006_f64, 0.3, 1e-3);
    let mu = 1150.0 * std::f64::consts::PI * d * d / 4.0;
    let want = parallelogram_angles(m, l, mu, phi0, h, (t_end / h).round() as usize);
    let (mut off_rigid, mut theta_max, mut shift) = (0.0_f64, 0.0_f64, 0.0_f64);
    let mut step = 0;
    let residual = run_trapeze_with(h, t_end, e, 1.0, |mixed, s, q| {
        let ns = mixed.model.n_structural();
        let (x, y, theta) = (s.q[ns], s.q[ns + 1], s.q[ns + 2]);
        theta_max = theta_max.max(theta.abs());
        let (Some(left), Some(right)) = (mixed.cable("left_rope"), mixed.cable("right_rope"))
        else {
            panic!("the ropes are named left_rope and right_rope")
        };
        for j in 0..mixed.cables[left].nodes {
            let (pl, pr) = (
                mixed.node_position(q, left, j),
                mixed.node_position(q, right, j),
            );
            shift = shift
                .max((pr[0] - pl[0] - 2.0 * a).abs())
                .max((pr[1] - pl[1]).abs());
        }
        if s.t > 0.0 {
            off_rigid = off_rigid.max((x.atan2(-y) - want[step]).abs());
            step += 1;
        }
    });
    (off_rigid, theta_max, shift, residual)
}

#[test]
fn the_trapeze_swings_level_as_the_rigid_parallelogram() {
    let t_end = 1.0;
    // The bundled ropes (E = 1 GPa) and ten times softer ones. (Ten times
    // stiffer ones need a smaller step: at h = 1e-3 Newton fails in the
    // first steps, at 5e-4 it runs.)
    let (d1, theta1, shift1, r1) = trapeze_against_rigid(1e8, t_end);
    let (d2, theta2, shift2, r2) = trapeze_against_rigid(1e9, t_end);
    println!(
        "trapeze over {t_end} s against the rigid parallelogram: max |Δφ| {d1:.2e} rad (E = 1e8), {d2:.2e} rad (E = 1e9); max |θ| {theta1:.1e}, {theta2:.1e} rad; right rope − left rope − (2a, 0): {shift1:.1e}, {shift2:.1e} m; max |Φ| {r1:.1e}, {r2:.1e}"
    );
    // Symmetry: the bar stays level and the ropes move alike, to round-off.
    for (theta, shift) in [(theta1, shift1), (theta2, shift2)] {
        assert!(theta < 1e-12, "bar angle {theta:e}");
        assert!(shift < 1e-12, "ropes differ by {shift:e} m");
    }
    // The swing is the rigid parallelogram's up to the ropes' compliance:
    // at E = 1 GPa they stretch by ε ≈ 3.5e-4 under the bar's weight, which
    // lengthens the period by ε/2, a phase lag of ε/2 · ω t ≈ 5.5e-4 rad
    // at 1 s, or 1.6e-4 rad of angle at the amplitude 0.3 rad. Ten times
    // softer, ten times further.
    assert!(d2 < 3e-4, "{d2}");
    assert!(d1 / d2 > 5.0 && d1 / d2 < 20.0, "ratio {}", d1 / d2);
    assert!(r1 < 1e-9 && r2 < 1e-9);
}

/// Link `a` (pivot at the origin) with the Berzeri–Shabana rod pinned at
/// its tip (Cable2D): body, joint, cable.
const LINK_A: [&str; 3] = [
    r#"(name: "link_a", mass: 0.5, com: (0.15, 0, 0), inertia: Diag(0, 0.00375, 0.00375),
         markers: [(name: "tip", position: (0.3, 0, 0))]),"#,
    r#"(name: "pivot_a", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "link_a", coordinates: ["theta_a"]),"#,
    r#"Cable(name: "rod_a", element: Cable2D, from: (0.3, 0, 0), to: (1.5, 0, 0), elements: 6,
              young: 0.7e6, density: 5540, area: 0.0018, second_moment: 1.215e-8,
              start: Pinned, start_at: (body: "link_a", marker: "tip")),"#,
];

/// Link `b` (pivot at (0, −2)) with a stiffer rod of the Green-strain
/// kernel clamped at its tip.
const LINK_B: [&str; 3] = [
    r#"(name: "link_b", mass: 0.4, com: (0.1, 0, 0), inertia: Diag(0, 0.0013333333333333333, 0.0013333333333333333),
         markers: [(name: "tip", position: (0.2, 0, 0))]),"#,
    r#"(name: "pivot_b", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "link_b", coordinates: ["theta_b"],
         parent_frame: (position: (0, -2, 0))),"#,
    r#"Cable(name: "rod_b", element: Cable2DGreen, from: (0.2, -2, 0), to: (0.7, -2, 0), elements: 4,
              young: 2e8, density: 2700, area: 1e-4, second_moment: 8.333333333333333e-10,
              start: Clamped, start_at: (body: "link_b", marker: "tip", axis: (1, 0, 0))),"#,
];

/// A spatial cable pinned to ground only, hanging at no marker.
const LOOSE: &str = r#"Cable(name: "loose", element: Cable3D, from: (-1, 0, 0), to: (-1, 0, 1), elements: 4,
              young: 0.7e6, density: 5540, area: 0.0018, second_moment: 1.215e-8,
              start: Pinned),"#;

/// A model of the links `links` and the extra cables `extra`.
fn links_model(name: &str, links: &[[&str; 3]], extra: &[&str]) -> String {
    let col = |k: usize| {
        links
            .iter()
            .map(|l| l[k])
            .collect::<Vec<_>>()
            .join("\n        ")
    };
    let mut cables = col(2);
    for e in extra {
        cables.push_str("\n        ");
        cables.push_str(e);
    }
    format!(
        "Model(\n    name: \"{name}\",\n    gravity: (0, -9.81, 0),\n    bodies: [\n        {}\n    ],\n    joints: [\n        {}\n    ],\n    cables: [\n        {cables}\n    ],\n)\n",
        col(0),
        col(1)
    )
}

/// Runs the mixed model of `text` to `t_end` with full Newton; the state.
fn run_full_newton(
    name: &str,
    text: &str,
    t_end: f64,
) -> (eom_sim::large::State, Vec<String>, Vec<usize>) {
    let sys = system(name, text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &mixed.model;
    let state = m.initial_state(0.0, &sys.q0(), &sys.u0());
    let opts = AlphaOptions {
        h: 1e-3,
        rho_inf: 0.9,
        reuse_matrix: false,
        ..AlphaOptions::default()
    };
    let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    ga.run_to(t_end, |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(ga.stats.max_constraint_residual < 1e-9);
    // Free coordinates per cable, in order.
    let s = m.structure();
    let free: Vec<usize> = mixed
        .cables
        .iter()
        .map(|c| {
            (c.offset..c.offset + c.nodes * c.node_coords)
                .filter(|&i| s.free_index(i).is_some())
                .count()
        })
        .collect();
    let names = mixed.cables.iter().map(|c| c.name.clone()).collect();
    (ga.state().clone(), names, free)
}

#[test]
fn independent_links_in_one_model_move_as_each_in_its_own() {
    let t_end = 0.3;
    let two = links_model("two_links", &[LINK_A, LINK_B], &[LOOSE]);
    let (s, names, free) = run_full_newton("two_links.ron", &two, t_end);
    assert_eq!(names, ["rod_a", "rod_b", "loose"]);
    let (sa, na, fa) = run_full_newton("link_a.ron", &links_model("link_a", &[LINK_A], &[]), t_end);
    let (sb, nb, fb) = run_full_newton("link_b.ron", &links_model("link_b", &[LINK_B], &[]), t_end);
    assert_eq!(
        (na, nb),
        (vec!["rod_a".to_string()], vec!["rod_b".to_string()])
    );
    assert_eq!((fa[0], fb[0]), (free[0], free[1]));
    // y = (x_a, x_b, x_loose, θ_a, θ_b) against (x_a, θ_a) and (x_b, θ_b).
    let (xa, xb) = (free[0], free[1]);
    let ns: usize = free.iter().sum();
    let mut worst = 0.0_f64;
    for (got, want) in [
        (&s.q[..xa], &sa.q[..xa]),
        (&s.q[xa..xa + xb], &sb.q[..xb]),
        (&s.q[ns..ns + 1], &sa.q[xa..]),
        (&s.q[ns + 1..], &sb.q[xb..]),
    ] {
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(want) {
            worst = worst.max((g - w).abs());
        }
    }
    // The loose cable fell under its own weight beside them.
    let loose_moved = s.v[xa + xb..ns].iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    println!(
        "two links in one model against each alone after {t_end} s: θ_a = {:.9}, θ_b = {:.9}, max |Δq| {worst:.1e}; the loose cable's fastest speed {loose_moved:.3} m/s",
        s.q[ns],
        s.q[ns + 1]
    );
    assert!(s.q[ns] < -0.1 && s.q[ns + 1] < -0.1, "the links fell");
    assert!(loose_moved > 0.1, "the loose cable moves");
    assert!(worst < 1e-12, "{worst:e}");
}

#[test]
fn a_planar_cable_on_a_marker_leaving_the_plane_is_refused_by_name() {
    // The link turns about y: its tip leaves the x–y plane.
    let text = LINK_ROD
        .replace("E_VALUE", "2e9")
        .replace("Revolute(axis: (0, 0, 1))", "Revolute(axis: (0, 1, 0))")
        .replace(
            "start: Clamped, start_at: (body: \"link\", marker: \"tip\", axis: (1, 0, 0))",
            "start: Pinned, start_at: (body: \"link\", marker: \"tip\")",
        );
    let sys = system("link_rod.ron", &text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let Err(e) = eom_gen::cables::check_rigid(&sys, &f) else {
        panic!("a planar cable on a marker leaving the plane was accepted")
    };
    let e = e.to_string();
    println!("{e}");
    assert!(
        e.contains("cable `rod` is planar (Cable2D) but the marker `link.tip` holding its start leaves the plane z = 0"),
        "{e}"
    );
    assert!(e.contains("use `Cable3D`"), "{e}");
    // The same rope as a spatial cable: accepted, and it runs.
    let spatial = text.replace("element: Cable2D", "element: Cable3D");
    let (s, names, _) = run_full_newton("link_rod.ron", &spatial, 0.05);
    assert_eq!(names, ["rod"]);
    assert!(s.q.iter().all(|x| x.is_finite()));
}

#[test]
fn each_cables_loads_go_on_its_own_nodes_in_the_mixed_structure() {
    // Node force (1, 2, 0) N on node 2 of `rod_b`; a distributed load of
    // −3 N/m along z on the 1 m `loose` cable only.
    let plain = links_model("two_links", &[LINK_A, LINK_B], &[LOOSE]);
    let loaded = plain
        .replace(
            "start: Clamped, start_at: (body: \"link_b\", marker: \"tip\", axis: (1, 0, 0))),",
            "start: Clamped, start_at: (body: \"link_b\", marker: \"tip\", axis: (1, 0, 0)),\n              node_forces: [(node: 2, force: (1, 2, 0))]),",
        )
        .replace(
            "              start: Pinned),",
            "              start: Pinned, distributed_load: (0, 0, -3)),",
        );
    assert_ne!(plain, loaded);
    let loads = |text: &str| {
        let sys = system("two_links.ron", text);
        let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
        let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
            .unwrap_or_else(|e| panic!("{e}"));
        (
            mixed.model.structure().load_full().to_vec(),
            mixed.cables.clone(),
        )
    };
    let (l0, cables) = loads(&plain);
    let (l1, _) = loads(&loaded);
    let diff: Vec<f64> = l1.iter().zip(&l0).map(|(a, b)| a - b).collect();
    let (b, loose) = (&cables[1], &cables[2]);
    let node2 = b.offset + 2 * b.node_coords;
    for (i, d) in diff.iter().enumerate() {
        let want = if i == node2 {
            1.0
        } else if i == node2 + 1 {
            2.0
        } else {
            0.0
        };
        if (loose.offset..loose.offset + loose.nodes * loose.node_coords).contains(&i) {
            continue;
        }
        assert!(
            (d - want).abs() < 1e-15,
            "coordinate {i}: {d} against {want}"
        );
    }
    // On the loose cable: the consistent load of −3 N/m, whose position
    // components along z sum to the total, −3 N, and along x, y to zero.
    for (k, want) in [(0, 0.0), (1, 0.0), (2, -3.0)] {
        let total: f64 = (0..loose.nodes)
            .map(|j| diff[loose.offset + j * loose.node_coords + k])
            .sum();
        assert!((total - want).abs() < 1e-12, "axis {k}: {total}");
    }
}
