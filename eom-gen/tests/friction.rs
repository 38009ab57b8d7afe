//! Coulomb friction at contacts (issue #26), through the one runner on the
//! evaluator: stick and slip as a complementarity problem with the
//! transitions located as events, against closed forms.
//!
//! - a block on an incline of angle `θ` sticks for `tan θ < μ` and slides
//!   with `g (sin θ − μ cos θ)` otherwise;
//! - a block pushed along a floor at `v₀` stops after `v₀²/(2 μ g)`, at
//!   `t = v₀/(μ g)`, and stays there;
//! - a solid ball (`I = 2/5 m r²`) striking a floor obliquely at `(V, −W)`
//!   without spin (Newton–Coulomb): the normal impulse is `m (1 + e) W`;
//!   it rolls off (`v_t⁺ = 0`, `vx⁺ = 5V/7`, `ω⁺ = −5V/(7r)`) when
//!   `2V/7 ≤ μ (1 + e) W`, else slides through the impact with
//!   `Λ_t = −μ Λ` (`vx⁺ = V − μ (1 + e) W`, `ω⁺ = −5 μ (1 + e) W/(2r)`);
//!   the joint of the free ball transmits no impulse (the contact's normal
//!   and friction impulses are its momentum change);
//! - the tangential rows: `v_t` of the touching point and `W_t = ∂v_t/∂u`,
//!   and `γ_t` against differences along the motion.

use eom_gen::System;
use eom_gen::functions::{Function, FunctionSet};
use eom_gen::interpret::{Point, evaluate_function};
use eom_gen::mech::formulate;
use eom_gen::model::{Source, check};
use eom_sim::run::ContactEventKind;
use eom_sim::{RunOptions, RunReport};

const G: f64 = 9.81;

fn from_text(text: &str) -> System {
    check(&Source::new("models/test.ron", text.to_string()))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

fn run(sys: &System, o: &RunOptions) -> RunReport {
    let f = formulate(sys, FunctionSet::all_requested()).expect("formulates");
    eom_gen::interpret::simulate(&f, sys, o).unwrap_or_else(|e| panic!("{e}"))
}

fn options(t_end: f64) -> RunOptions {
    RunOptions {
        t_end,
        rtol: 1e-10,
        atol: 1e-12,
        ..RunOptions::default()
    }
}

/// A 2 kg block on a planar joint (x, y, angle; gravity −y) touching, at its
/// origin, a plane through the origin with normal `(nx, ny, 0)`; friction
/// `mu`; initial speeds `u0`.
fn block(nx: f64, ny: f64, mu: f64, u0: [f64; 3]) -> System {
    from_text(&format!(
        r#"Model(
    name: "block",
    gravity: (0, -{G}, 0),
    bodies: [(name: "block", mass: 2, inertia: Diag(0.1, 0.1, 0.1))],
    joints: [(name: "p", kind: Planar, parent: "ground", child: "block", coordinates: ["x", "y", "a"], q0: [0, 0, 0], u0: [{}, {}, {}])],
    contacts: [Plane(name: "ground_contact", at: (body: "block"), normal: ({nx}, {ny}, 0), e: 0, mu: {mu})],
)"#,
        u0[0], u0[1], u0[2]
    ))
}

/// `tan θ < μ`: the block stays at rest; `tan θ > μ`: it slides down the
/// slope with `a = g (sin θ − μ cos θ)`.
#[test]
fn block_on_an_incline_sticks_below_the_friction_angle_and_slides_above() {
    let theta: f64 = 0.4; // tan θ = 0.4228
    let (s, c) = theta.sin_cos();
    let t_end = 1.0;
    // Sticks: μ = 0.5 > tan θ.
    let report = run(&block(-s, c, 0.5, [0.0; 3]), &options(t_end));
    assert!(report.stop.is_finished(), "{}", report.stop);
    assert!(
        report.q.iter().chain(&report.u).all(|v| v.abs() < 1e-10),
        "sticks: q {:?}, u {:?}",
        report.q,
        report.u
    );
    assert!(
        report
            .contact_events
            .iter()
            .all(|e| e.kind == ContactEventKind::Rest),
        "{:?}",
        report.contact_events
    );
    // Slides: μ = 0.3 < tan θ.
    let mu = 0.3;
    let report = run(&block(-s, c, mu, [0.0; 3]), &options(t_end));
    assert!(report.stop.is_finished(), "{}", report.stop);
    let a = G * (s - mu * c);
    let dist = 0.5 * a * t_end * t_end;
    let (x, y) = (report.q[0], report.q[1]);
    assert!(
        (x + dist * c).abs() < 1e-9 && (y + dist * s).abs() < 1e-9,
        "slid to ({x}, {y}), want {dist} m down the slope: ({}, {})",
        -dist * c,
        -dist * s
    );
    let speed = report.u[0].hypot(report.u[1]);
    assert!(
        (speed - a * t_end).abs() < 1e-9,
        "speed {speed}, want g (sin θ − μ cos θ) t = {}",
        a * t_end
    );
    assert!(report.q[2].abs() < 1e-12, "no turning: {}", report.q[2]);
}

/// Pushed at `v₀` along a floor: decelerates at `μ g`, stops after
/// `v₀²/(2 μ g)` at `t = v₀/(μ g)` (a located `stick` event) and stays.
#[test]
fn block_pushed_along_a_floor_stops_after_v0_squared_over_2_mu_g() {
    let (v0, mu) = (2.0, 0.3);
    let report = run(&block(0.0, 1.0, mu, [v0, 0.0, 0.0]), &options(1.5));
    assert!(report.stop.is_finished(), "{}", report.stop);
    let want = v0 * v0 / (2.0 * mu * G);
    assert!(
        (report.q[0] - want).abs() < 1e-9,
        "stopped at {}, want v0²/(2 μ g) = {want}",
        report.q[0]
    );
    assert!(
        report.u.iter().all(|v| v.abs() < 1e-12) && report.q[1].abs() < 1e-12,
        "at rest on the floor: q {:?}, u {:?}",
        report.q,
        report.u
    );
    let stick = report
        .contact_events
        .iter()
        .find(|e| e.kind == ContactEventKind::Stick)
        .unwrap_or_else(|| panic!("a stick event: {:?}", report.contact_events));
    let t_stop = v0 / (mu * G);
    assert!(
        (stick.t - t_stop).abs() < 1e-9,
        "stopped at t = {}, want v0/(μ g) = {t_stop}",
        stick.t
    );
    // Nothing after it: the block stays stuck.
    assert_eq!(
        report.contact_events.last().map(|e| e.kind),
        Some(ContactEventKind::Stick)
    );
}

/// A solid ball of radius `r` on a planar joint (x, y, spin), gravity −y,
/// striking the floor `y = 0` from `(V, −W0)` at height `h`.
fn ball(mu: f64, e: f64) -> System {
    from_text(&format!(
        r#"Model(
    name: "ball",
    gravity: (0, -{G}, 0),
    parameters: [(name: "m", value: 1.5), (name: "r", value: 0.2)],
    bodies: [(name: "ball", mass: "m", inertia: Diag("2/5*m*r^2", "2/5*m*r^2", "2/5*m*r^2"))],
    joints: [(name: "p", kind: Planar, parent: "ground", child: "ball", coordinates: ["x", "y", "a"], q0: [0, 0.3, 0], u0: [1, -2, 0])],
    contacts: [Plane(name: "floor", at: (body: "ball"), radius: "r", normal: (0, 1, 0), e: {e}, mu: {mu})],
)"#
    ))
}

#[test]
fn oblique_ball_impact_rolls_off_or_slides_by_newton_coulomb() {
    let (m, r, e, v) = (1.5, 0.2, 0.5, 1.0);
    for (mu, sticks) in [(0.5, true), (0.05, false)] {
        let report = run(&ball(mu, e), &options(0.07));
        let impact = report
            .contact_events
            .iter()
            .find(|ev| ev.kind == ContactEventKind::Impact)
            .unwrap_or_else(|| panic!("mu {mu}: an impact: {:?}", report.contact_events));
        let c = &impact.contacts[0];
        let w = -c.speed_before;
        assert!(w > 0.0, "closing: {w}");
        let ln = m * (1.0 + e) * w;
        assert!(
            (c.impulse - ln).abs() < 1e-10 * ln,
            "mu {mu}: normal impulse {}, want m (1 + e) W = {ln}",
            c.impulse
        );
        assert_eq!(sticks, 2.0 * v / 7.0 <= mu * (1.0 + e) * w, "test setup");
        // The impulse per speed: m Δvx = Λ_t, I Δω = r Λ_t.
        let (lt, vx, om) = if sticks {
            (-2.0 * m * v / 7.0, 5.0 * v / 7.0, -5.0 * v / (7.0 * r))
        } else {
            let lt = -mu * ln;
            (lt, v + lt / m, 5.0 * lt / (2.0 * m * r))
        };
        // t1 = x for the normal +y; the touching point moves at vx + r ω.
        assert!(
            (c.tangential_impulse[0] - lt).abs() < 1e-10 && c.tangential_impulse[1].abs() < 1e-12,
            "mu {mu}: tangential impulse {:?}, want ({lt}, 0)",
            c.tangential_impulse
        );
        let gi = &impact.generalized_impulse;
        let i = 0.4 * m * r * r;
        assert!(
            (gi[0] / m + v - vx).abs() < 1e-10 && (gi[2] / i - om).abs() < 1e-9,
            "mu {mu}: after the impact vx = {}, ω = {}; want {vx}, {om}",
            gi[0] / m + v,
            gi[2] / i
        );
        let slip = c.tangential_speed_after[0];
        if sticks {
            assert!(slip.abs() < 1e-10, "rolls off: v_t⁺ = {slip}");
        } else {
            assert!(
                (slip - (vx + r * om)).abs() < 1e-10 && slip > 0.0,
                "slides through: v_t⁺ = {slip}"
            );
        }
        // Energy: never gained.
        assert!(impact.energy_after <= impact.energy_before + 1e-12);
        // Wittenburg's joint impulse of the planar joint: the ball's
        // momentum change is the contact's impulse (normal and friction,
        // the friction's moment about the centre included), so the joint,
        // free in the plane, transmits nothing.
        let ji = &impact.joint_impulses;
        assert_eq!(ji.len(), 1, "{ji:?}");
        assert!(
            ji[0]
                .force
                .iter()
                .chain(&ji[0].torque)
                .all(|x| x.abs() < 1e-10),
            "mu {mu}: {:?}",
            ji[0]
        );
    }
}

/// The generated tangential rows: `v_t = W_t u` of the touching point (for
/// the ball on the floor `vx + r ω` and 0), and `γ_t` against differences of
/// `v_t` along the motion at `u̇ = 0`.
#[test]
fn tangential_rows_are_the_touching_points_speeds() {
    let sys = ball(0.3, 0.5);
    let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
    let eval = |q: &[f64], u: &[f64]| {
        let x = Point {
            sys: &sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        evaluate_function(&f, Function::Friction, &x).expect("friction")
    };
    let (q, u) = ([0.3, 0.5, 0.7], [1.1, -0.4, 2.5]);
    let v = eval(&q, &u);
    assert_eq!(v.len(), 4 + 2 * 3);
    assert!(
        (v[0] - (u[0] + 0.2 * u[2])).abs() < 1e-14,
        "v_t1 = {}",
        v[0]
    );
    assert!(v[1].abs() < 1e-14, "v_t2 = {}", v[1]);
    assert_eq!(&v[4..7], &[1.0, 0.0, 0.2]);
    // γ_t: −d v_t/dt at u̇ = 0 along q̇ = u (here v_t does not depend on q).
    let h = 1e-5;
    let qs: Vec<f64> = q.iter().zip(&u).map(|(a, b)| a + h * b).collect();
    let dv = (eval(&qs, &u)[0] - v[0]) / h;
    assert!((dv + v[2]).abs() < 1e-8, "γ_t1 {} vs −dv/dt {}", v[2], -dv);
}

/// Ball `a` (m = 1.5 kg, r_a = 0.2 m, solid) on a planar joint, touching at
/// the start from above ball `b` (r_b = 0.3 m): on its own planar joint
/// (M = 2 kg, solid) or fixed in the world (`b` on the ground). `a` moves
/// at `(V, −W)`, `b` at rest; gravity −y; friction `mu` between them.
fn two_spheres(mu: f64, e: f64, b_free: bool, v: f64, w: f64) -> System {
    let (body_b, joint_b, anchor_b) = if b_free {
        (
            r#"(name: "b", mass: 2, inertia: Diag(0.072, 0.072, 0.072)),"#,
            r#"(name: "pb", kind: Planar, parent: "ground", child: "b", coordinates: ["xb", "yb", "ab"], q0: [0, -0.3, 0]),"#,
            r#"(body: "b")"#,
        )
    } else {
        ("", "", r#"(body: "ground", point: (0, -0.3, 0))"#)
    };
    from_text(&format!(
        r#"Model(
    name: "two_spheres",
    gravity: (0, -{G}, 0),
    bodies: [(name: "a", mass: 1.5, inertia: Diag(0.024, 0.024, 0.024)), {body_b}],
    joints: [
        (name: "pa", kind: Planar, parent: "ground", child: "a", coordinates: ["xa", "ya", "aa"], q0: [0, 0.2, 0], u0: [{v}, -{w}, 0]),
        {joint_b}
    ],
    contacts: [Spheres(name: "knock", a: (body: "a"), b: {anchor_b}, radius_a: 0.2, radius_b: 0.3, e: {e}, mu: {mu})],
)"#
    ))
}

/// Two spheres striking obliquely (Newton–Coulomb on the line of centres
/// `n = +y` at the impact, `t₁ = +x`): the normal impulse is
/// `(1 + e) W/(1/m + 1/M)` (`M = ∞` for the fixed sphere); the touching
/// points slide at `s = v_xa + r_a ω_a − v_xb + r_b ω_b`, which a
/// tangential impulse `Λ_t` changes by `k_t Λ_t`,
/// `k_t = 7/(2m) + 7/(2M)` (each solid ball `1/m + r²/I`). They leave
/// without sliding (`Λ_t = −s⁻/k_t`) when that fits the cone
/// `|Λ_t| ≤ μ Λ`, else slide through with `Λ_t = −μ Λ sign s⁻`. The
/// generalised impulse is then `(Λ_t, Λ, r_a Λ_t)` on `a` and
/// `(−Λ_t, −Λ, r_b Λ_t)` on `b`: the linear momentum of the pair is kept.
#[test]
fn two_spheres_strike_obliquely_by_newton_coulomb() {
    let (m, ra, rb, e, v, w) = (1.5, 0.2, 0.3, 0.5, 1.0, 2.0);
    for b_free in [false, true] {
        let big_m = if b_free { 2.0 } else { f64::INFINITY };
        let ln = (1.0 + e) * w / (1.0 / m + 1.0 / big_m);
        let kt = 3.5 / m + 3.5 / big_m;
        for (mu, sticks) in [(0.5, true), (0.05, false)] {
            let report = run(&two_spheres(mu, e, b_free, v, w), &options(1e-3));
            let impact = report
                .contact_events
                .iter()
                .find(|ev| ev.kind == ContactEventKind::Impact)
                .unwrap_or_else(|| panic!("an impact: {:?}", report.contact_events));
            assert!(impact.t.abs() < 1e-12, "at the start: {}", impact.t);
            let c = &impact.contacts[0];
            assert!(
                (c.speed_before + w).abs() < 1e-12,
                "ġ⁻ = {}",
                c.speed_before
            );
            assert!(
                (c.impulse - ln).abs() < 1e-10 * ln,
                "b free {b_free}, mu {mu}: normal impulse {}, want {ln}",
                c.impulse
            );
            assert!(
                (c.tangential_speed_before[0] - v).abs() < 1e-12
                    && c.tangential_speed_before[1].abs() < 1e-12,
                "s⁻ = {:?}, want ({v}, 0)",
                c.tangential_speed_before
            );
            assert_eq!(sticks, v / kt <= mu * ln, "test setup");
            let lt = if sticks { -v / kt } else { -mu * ln };
            assert!(
                (c.tangential_impulse[0] - lt).abs() < 1e-10
                    && c.tangential_impulse[1].abs() < 1e-12
                    && c.tangential_impulse[0].abs() <= mu * c.impulse * (1.0 + 1e-12),
                "b free {b_free}, mu {mu}: tangential impulse {:?}, want ({lt}, 0) inside μΛ = {}",
                c.tangential_impulse,
                mu * c.impulse
            );
            let s_after = v + kt * lt;
            assert!(
                (c.tangential_speed_after[0] - s_after).abs() < 1e-10,
                "s⁺ = {:?}, want {s_after}",
                c.tangential_speed_after
            );
            let mut want = vec![lt, ln, ra * lt];
            if b_free {
                want.extend([-lt, -ln, rb * lt]);
            }
            let gi = &impact.generalized_impulse;
            assert_eq!(gi.len(), want.len());
            for (k, (got, want)) in gi.iter().zip(&want).enumerate() {
                assert!(
                    (got - want).abs() < 1e-10,
                    "b free {b_free}, mu {mu}: generalised impulse {k}: got {got}, want {want}"
                );
            }
            assert!(impact.energy_after <= impact.energy_before + 1e-12);
        }
    }
}

/// A point (radius 0) on a planar joint resting on a fixed sphere of
/// radius 1 at the angle `θ` from its top (gravity −y): sustained contact
/// with friction between spheres. Like a block on an incline of angle `θ`,
/// it sticks for `tan θ < μ` (and stays put); otherwise it starts sliding
/// down the tangent with `g (sin θ − μ cos θ)` (at rest the normal force
/// is `m g cos θ`), so over a short `τ` it covers `½ a τ²`.
#[test]
fn a_point_on_a_sphere_sticks_below_the_friction_angle_and_slides_above() {
    let theta: f64 = 0.4;
    let (s, c) = theta.sin_cos();
    for mu in [0.6, 0.2] {
        let sys = from_text(&format!(
            r#"Model(
    name: "on_a_sphere",
    gravity: (0, -{G}, 0),
    bodies: [(name: "p", mass: 2, inertia: Diag(0.1, 0.1, 0.1))],
    joints: [(name: "pl", kind: Planar, parent: "ground", child: "p", coordinates: ["x", "y", "a"], q0: [{:.17e}, {:.17e}, 0])],
    contacts: [Spheres(name: "cap", a: (body: "p"), b: (body: "ground"), radius_a: 0, radius_b: 1, e: 0, mu: {mu})],
)"#,
            s, c
        ));
        let tau = 1e-3;
        let report = run(&sys, &options(tau));
        assert!(report.stop.is_finished(), "{}", report.stop);
        let moved = ((report.q[0] - s).powi(2) + (report.q[1] - c).powi(2)).sqrt();
        if theta.tan() < mu {
            assert!(moved < 1e-12, "mu {mu}: sticks, moved {moved}");
        } else {
            let want = 0.5 * G * (s - mu * c) * tau * tau;
            assert!(
                (moved - want).abs() < 1e-2 * want,
                "mu {mu}: slid {moved}, want ½ g (sin θ − μ cos θ) τ² = {want}"
            );
            // Along the tangent, down the sphere, still on it.
            let r = (report.q[0].powi(2) + report.q[1].powi(2)).sqrt();
            assert!(
                (r - 1.0).abs() < 1e-9 && report.q[0] > s,
                "r = {r}, x = {}",
                report.q[0]
            );
        }
    }
}

/// A rod (m = 1 kg, L = 1 m, `I = m L²/3` about its pin) pinned at one end
/// about y, whose tip touches a floor at the start at `θ₀` below the
/// horizontal, swinging down at `θ̇⁻` (gravity −z). The tip can only move
/// across the rod, so leaving without sliding would stop it (`v_t⁺ = 0`
/// means `θ̇⁺ = 0`, against `ġ⁺ = −e ġ⁻`): Newton–Coulomb makes it slide
/// through the impact. One coordinate: `θ̇⁺ = −e θ̇⁻`, the tip's slide
/// after, `v_t⁺ = e sin θ₀ θ̇⁻ > 0` (along `t₁ = +x`), sets
/// `Λ_t = −μ Λ`, and `I (θ̇⁺ − θ̇⁻) = (−cos θ₀) Λ + (−sin θ₀) Λ_t` gives
/// `Λ = I (1 + e) θ̇⁻/(cos θ₀ − μ sin θ₀)`. A regression: the impact used to
/// have "no solution" because it first tried sticking and gave up.
#[test]
fn pinned_rod_striking_a_floor_slides_through_the_impact() {
    let (theta0, om, e, mu, i) = (0.3f64, 2.0, 0.5, 0.5, 1.0 / 3.0);
    let sys = from_text(&format!(
        r#"Model(
    name: "rod_floor",
    gravity: (0, 0, -{G}),
    bodies: [(name: "rod", mass: 1, com: (0.5, 0, 0), inertia: Diag(0.001, "1/12", "1/12"), markers: [(name: "tip", position: (1, 0, 0))])],
    joints: [(name: "pin", kind: Revolute(axis: (0, 1, 0)), parent: "ground", child: "rod", q0: [{theta0}], u0: [{om}])],
    contacts: [Plane(name: "floor", at: (body: "rod", marker: "tip"), point: (0, 0, {:.17e}), normal: (0, 0, 1), e: {e}, mu: {mu})],
)"#,
        -theta0.sin()
    ));
    let report = run(&sys, &options(1e-3));
    let impact = report
        .contact_events
        .iter()
        .find(|ev| ev.kind == ContactEventKind::Impact)
        .unwrap_or_else(|| panic!("an impact: {}, {:?}", report.stop, report.contact_events));
    let c = &impact.contacts[0];
    let (s, co) = theta0.sin_cos();
    assert!((c.speed_before + co * om).abs() < 1e-12, "{c:?}");
    assert!((c.speed_after - e * co * om).abs() < 1e-12, "{c:?}");
    let ln = i * (1.0 + e) * om / (co - mu * s);
    assert!(
        (c.impulse - ln).abs() < 1e-10 * ln,
        "Λ: got {}, want I (1 + e) θ̇⁻/(cos θ₀ − μ sin θ₀) = {ln}",
        c.impulse
    );
    assert!(
        (c.tangential_impulse[0] + mu * ln).abs() < 1e-10 * ln && c.tangential_impulse[1] == 0.0,
        "Λ_t: got {:?}, want (−μΛ, 0)",
        c.tangential_impulse
    );
    assert!(
        (c.tangential_speed_before[0] + s * om).abs() < 1e-12
            && (c.tangential_speed_after[0] - e * s * om).abs() < 1e-12,
        "{c:?}"
    );
    assert!((impact.generalized_impulse[0] + i * (1.0 + e) * om).abs() < 1e-10);
    assert!(impact.energy_after < impact.energy_before);
}

/// The box of `bench/contact/friction/box4.ron`: 2 kg, `I = diag(0.02,
/// 0.03, 0.04)`, four bottom corners at `(±0.2, ±0.15, −0.05)` with spheres
/// of 1 cm on the floor `z = 0` (each corner touches at `h = 0.06` below
/// the centre), restitution `e`, friction `mu`; free joint from the
/// orientation `quat` at height 0.3 m with speeds `u0` (`v`, then `ω`).
fn box4(mu: f64, e: f64, quat: [f64; 4], u0: [f64; 6]) -> System {
    let corners = [(0.2, 0.15), (-0.2, 0.15), (-0.2, -0.15), (0.2, -0.15)];
    let markers: Vec<String> = corners
        .iter()
        .enumerate()
        .map(|(k, (x, y))| format!(r#"(name: "c{}", position: ({x}, {y}, -0.05))"#, k + 1))
        .collect();
    let contacts: Vec<String> = (1..=4)
        .map(|k| {
            format!(
                r#"Plane(name: "k{k}", at: (body: "box", marker: "c{k}"), radius: 0.01, normal: (0, 0, 1), e: {e}, mu: {mu})"#
            )
        })
        .collect();
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.17e}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    from_text(&format!(
        r#"Model(
    name: "box4",
    gravity: (0, 0, -{G}),
    bodies: [(name: "box", mass: 2, inertia: Diag(0.02, 0.03, 0.04), markers: [{}])],
    joints: [(name: "f", kind: Free, parent: "ground", child: "box", q0: [0, 0, 0.3, {}], u0: [{}])],
    contacts: [{}],
)"#,
        markers.join(", "),
        list(&quat),
        list(&u0),
        contacts.join(", ")
    ))
}

/// The first impact of a run.
fn first_impact(report: &RunReport) -> &eom_sim::run::ContactEvent {
    report
        .contact_events
        .iter()
        .find(|ev| ev.kind == ContactEventKind::Impact)
        .unwrap_or_else(|| panic!("an impact: {}, {:?}", report.stop, report.contact_events))
}

/// A box dropped flat (`v⁻ = √(1 + 2 g 0.24)` down, no spin) onto its four
/// frictional corners (μ = 0.5): four normal and eight tangential rows on
/// six speeds, a redundant block whose impulses are not unique though the
/// speeds after are: a pure vertical rebound, `v⁺ = e v⁻` up, no rotation,
/// no slide. The normal impulses sum to `m (1 + e) v⁻`; the minimum-norm
/// choice shares them equally (the symmetry), with no tangential impulse;
/// the kinetic energy after is `e²` times the one before. The box then
/// comes to rest flat and stays: its four resting forces carry `m g`. A
/// regression: "the impact of 4 contact(s) has no solution" (the
/// enumeration took three corners, one of them outside its cone, and the
/// sliding directions never settled).
#[test]
fn box_landing_flat_on_four_sticking_corners_rebounds_vertically() {
    let m = 2.0;
    let v = (1.0 + 2.0 * G * 0.24f64).sqrt();
    for e in [0.0, 0.5] {
        let sys = box4(
            0.5,
            e,
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, -1.0, 0.0, 0.0, 0.0],
        );
        let report = run(&sys, &options(1.5));
        assert!(report.stop.is_finished(), "e {e}: {}", report.stop);
        let impact = first_impact(&report);
        assert_eq!(impact.contacts.len(), 4, "e {e}: {impact:?}");
        let total = m * (1.0 + e) * v;
        let sum: f64 = impact.contacts.iter().map(|c| c.impulse).sum();
        assert!(
            (sum - total).abs() < 1e-10 * total,
            "e {e}: Σ Λ = {sum}, want m (1 + e) v⁻ = {total}"
        );
        for c in &impact.contacts {
            assert!(
                (c.speed_before + v).abs() < 1e-9 && (c.speed_after - e * v).abs() < 1e-9,
                "e {e}: {}: ġ {} → {}, want {} → {}",
                c.contact,
                c.speed_before,
                c.speed_after,
                -v,
                e * v
            );
            assert!(
                (c.impulse - total / 4.0).abs() < 1e-10 * total,
                "e {e}: {}: Λ = {}, want the minimum-norm share m (1 + e) v⁻/4 = {}",
                c.contact,
                c.impulse,
                total / 4.0
            );
            let lt = c.tangential_impulse;
            let vt = c.tangential_speed_after;
            assert!(
                norm(lt) < 1e-10 && norm(vt) < 1e-10,
                "e {e}: {}: Λ_t = {lt:?}, v_t⁺ = {vt:?}, want zero",
                c.contact
            );
        }
        // M Δu = (0, 0, m (1 + e) v⁻, 0, 0, 0): a pure vertical rebound.
        let gi = &impact.generalized_impulse;
        let want = [0.0, 0.0, total, 0.0, 0.0, 0.0];
        assert!(
            gi.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-10),
            "e {e}: M Δu = {gi:?}, want {want:?}"
        );
        let lost = impact.energy_before - impact.energy_after;
        let want = 0.5 * m * v * v * (1.0 - e * e);
        assert!(
            (lost - want).abs() < 1e-9,
            "e {e}: energy lost {lost}, want ½ m v⁻² (1 − e²) = {want}"
        );
        // At rest, flat, the corners' spheres on the floor: the resting
        // forces hold m g (nothing moves, nothing is released after).
        let (q, u) = (&report.q, &report.u);
        assert!(
            (q[2] - 0.06).abs() < 1e-9
                && q[0].abs() < 1e-12
                && q[1].abs() < 1e-12
                && (q[3] - 1.0).abs() < 1e-12
                && u.iter().all(|x| x.abs() < 1e-9),
            "e {e}: at rest on its corners: q {q:?}, u {u:?}"
        );
        let rest = report
            .contact_events
            .iter()
            .rposition(|ev| ev.kind == ContactEventKind::Rest)
            .unwrap_or_else(|| panic!("e {e}: comes to rest: {:?}", report.contact_events));
        assert!(
            report.contact_events[rest + 1..].is_empty(),
            "e {e}: nothing after the rest: {:?}",
            &report.contact_events[rest..]
        );
    }
}

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

/// A box landing flat with a horizontal speed `V` along x. With μ = 0.1
/// it slides through the impact on all four corners: each `Λ_t = −μ Λ`
/// along x (on its cone), `Σ Λ = m (1 + e) W` (`W` the speed down), and
/// `V⁺ = V − μ (1 + e) W` (> 0, no reversal), no rotation; the friction
/// below the centre (`h = 0.06`) is balanced by the front corners carrying
/// more, `0.4 (Λ_front − Λ_back) = μ h Σ Λ` (front and back pairs each
/// equal: the minimum-norm choice). With μ = 0.5 (the bench's box4, e =
/// 0.9) the corners stick: `V⁺ = 0`, `Λ_t = −m V/4` each, inside the cone,
/// and `0.4 (Λ_front − Λ_back) = h m V`.
#[test]
fn box_landing_flat_with_a_horizontal_speed_slides_or_sticks_on_four_corners() {
    let (m, h, big_v) = (2.0, 0.06, 1.0);
    let w = (1.0 + 2.0 * G * 0.24f64).sqrt();
    for (mu, e, sticks) in [(0.1, 0.5, false), (0.5, 0.9, true)] {
        let sys = box4(
            mu,
            e,
            [1.0, 0.0, 0.0, 0.0],
            [big_v, 0.0, -1.0, 0.0, 0.0, 0.0],
        );
        let report = run(&sys, &options(0.2));
        assert!(report.stop.is_finished(), "mu {mu}: {}", report.stop);
        let impact = first_impact(&report);
        assert_eq!(impact.contacts.len(), 4, "mu {mu}: {impact:?}");
        assert_eq!(sticks, mu * (1.0 + e) * w >= big_v, "test setup");
        let total = m * (1.0 + e) * w;
        let sum: f64 = impact.contacts.iter().map(|c| c.impulse).sum();
        assert!(
            (sum - total).abs() < 1e-10 * total,
            "mu {mu}: Σ Λ = {sum}, want m (1 + e) W = {total}"
        );
        let vx = if sticks {
            0.0
        } else {
            big_v - mu * (1.0 + e) * w
        };
        let (front, back) = if sticks {
            let d = h * m * big_v / 0.4;
            ((total / 2.0 + d) / 2.0, (total / 2.0 - d) / 2.0)
        } else {
            let d = mu * h * total / 0.4;
            ((total / 2.0 + d) / 2.0, (total / 2.0 - d) / 2.0)
        };
        for (k, c) in impact.contacts.iter().enumerate() {
            let want = if k == 0 || k == 3 { front } else { back };
            assert!(
                (c.impulse - want).abs() < 1e-9,
                "mu {mu}: {}: Λ = {}, want {want}",
                c.contact,
                c.impulse
            );
            let lt = c.tangential_impulse;
            assert!(
                norm(lt) <= mu * c.impulse * (1.0 + 1e-9) && lt[1].abs() < 1e-10,
                "mu {mu}: {}: Λ_t = {lt:?} outside the cone μ Λ = {}",
                c.contact,
                mu * c.impulse
            );
            let want_lt = if sticks {
                -m * big_v / 4.0
            } else {
                -mu * c.impulse
            };
            assert!(
                (lt[0] - want_lt).abs() < 1e-9,
                "mu {mu}: {}: Λ_t = {lt:?}, want ({want_lt}, 0)",
                c.contact
            );
            let vt = c.tangential_speed_after;
            assert!(
                (vt[0] - vx).abs() < 1e-9 && vt[1].abs() < 1e-10,
                "mu {mu}: {}: v_t⁺ = {vt:?}, want ({vx}, 0)",
                c.contact
            );
            assert!(
                (c.speed_after - e * w).abs() < 1e-9,
                "mu {mu}: {}: ġ⁺ = {}, want e W = {}",
                c.contact,
                c.speed_after,
                e * w
            );
        }
        let gi = &impact.generalized_impulse;
        let want = [m * (vx - big_v), 0.0, total, 0.0, 0.0, 0.0];
        assert!(
            gi.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9),
            "mu {mu}: M Δu = {gi:?}, want {want:?}"
        );
    }
}

/// The box tilted by 0.1 rad about `(1, 1, 0)/√2`, moving at 0.5 m/s
/// along x, lands on one corner (`k4`, e = 0.5): a regular (one-row)
/// block, which the treatment of redundant blocks leaves as it was. Pinned:
/// the runtime before it (bd2ef6f; `eom-gen simulate … --events-csv`, the
/// same first impacts to the last bit before and after) for μ = 2 (the
/// corner sticks: `v_t⁺ = 0`, inside the cone) and μ = 0.05 (it slides:
/// `‖Λ_t‖ = μ Λ`).
#[test]
fn tilted_box_landing_on_one_corner_keeps_its_impulses() {
    let (c, s) = (0.05f64.cos(), 0.05f64.sin() / 2f64.sqrt());
    let o = RunOptions {
        t_end: 0.135,
        rtol: 1e-8,
        atol: 1e-10,
        ..RunOptions::default()
    };
    for (mu, ln, lt) in [
        (
            2.0,
            1.8806573741722912,
            [-1.9235330905490144, 1.3344060506042486],
        ),
        (
            0.05,
            1.2338698204219887,
            [-0.0533001221614621, 0.03106740755106055],
        ),
    ] {
        let sys = box4(mu, 0.5, [c, s, s, 0.0], [0.5, 0.0, -1.0, 0.0, 0.0, 0.0]);
        let report = run(&sys, &o);
        let impact = first_impact(&report);
        assert_eq!(impact.contacts.len(), 1, "mu {mu}: {impact:?}");
        let k = &impact.contacts[0];
        assert_eq!(k.contact, "k4");
        assert!(
            (k.speed_after + 0.5 * k.speed_before).abs() < 1e-12,
            "mu {mu}: ġ⁺ = −e ġ⁻: {k:?}"
        );
        let got = k.tangential_impulse;
        assert!(
            (k.impulse - ln).abs() < 1e-12 * ln && (0..2).all(|a| (got[a] - lt[a]).abs() < 1e-12),
            "mu {mu}: Λ = {}, Λ_t = {got:?}; want {ln}, {lt:?}",
            k.impulse
        );
        if mu > 1.0 {
            assert!(norm(k.tangential_speed_after) < 1e-12, "sticks: {k:?}");
        } else {
            assert!((norm(got) - mu * k.impulse).abs() < 1e-12, "slides: {k:?}");
        }
    }
}

/// The same tilted landing with μ = 0.5: the corner slides through the
/// impact while friction turns the box, and the plain iteration of the
/// sliding direction, `s ← v_t⁺/‖v_t⁺‖`, swung between two directions for
/// ever ("the impact of 1 contact(s) has no solution", before the
/// relaxed iteration). Newton–Coulomb: `ġ⁺ = −e ġ⁻`, `Λ_t = −μ Λ s` on
/// the cone with `s` the direction of the slide after, energy not gained.
#[test]
fn tilted_box_sliding_through_a_one_corner_impact_settles_its_direction() {
    let (c, s) = (0.05f64.cos(), 0.05f64.sin() / 2f64.sqrt());
    let mu = 0.5;
    let sys = box4(mu, 0.5, [c, s, s, 0.0], [0.5, 0.0, -1.0, 0.0, 0.0, 0.0]);
    let report = run(&sys, &options(0.135));
    assert!(report.stop.is_finished(), "{}", report.stop);
    let impact = first_impact(&report);
    let k = &impact.contacts[0];
    assert!(
        (k.speed_after + 0.5 * k.speed_before).abs() < 1e-12,
        "ġ⁺ = −e ġ⁻: {k:?}"
    );
    let (lt, vt) = (k.tangential_impulse, k.tangential_speed_after);
    assert!(norm(vt) > 0.1, "slides: {k:?}");
    let want = [0, 1].map(|a| -mu * k.impulse * vt[a] / norm(vt));
    assert!(
        (0..2).all(|a| (lt[a] - want[a]).abs() < 1e-9 * k.impulse),
        "Λ_t = {lt:?}, want −μ Λ v_t⁺/‖v_t⁺‖ = {want:?}"
    );
    assert!(impact.energy_after < impact.energy_before);
}

/// The Newton–Coulomb conditions of one impact event with restitution
/// `e` on every row: per row `Λ ≥ 0`, `ġ⁺ ≥ −e ġ⁻` with equality where
/// `Λ > 0`, `‖Λ_t‖ ≤ μ Λ`, and either stick (`v_t⁺ = 0`) or a slide with
/// `Λ_t = −μ Λ v_t⁺/‖v_t⁺‖`; the energy not gained. Impulses to 1e-9 of
/// the largest, speeds to 1e-9 of the fastest before.
///
/// A slide's direction `v̂_t⁺` is defined only where `‖v_t⁺‖` stands above
/// the round-off of the speeds after, and those are sums of the speeds
/// before and of the jumps the impulses make (`ξ = G Λ + b`): a row
/// resting among corners that land carries an impulse whose jumps cancel
/// at its own row to a few 1e-10 m/s. So a row slides here if
/// `‖v_t⁺‖` exceeds 1e-9 of the largest speed before or jump `|ġ⁺ − ġ⁻|`,
/// `‖v_t⁺ − v_t⁻‖` of the event — the scale `soccp::check` accepts the cone
/// solver's answers on (`TOL · max(|b|, |G z|)`); below it the row sticks
/// to round-off, and its `Λ_t` needs only to fit the cone.
fn assert_newton_coulomb(ev: &eom_sim::run::ContactEvent, e: f64, mu: f64, what: &str) {
    let big = ev
        .contacts
        .iter()
        .map(|c| c.impulse.abs())
        .fold(0.0, f64::max);
    let fast = ev
        .contacts
        .iter()
        .map(|c| c.speed_before.abs().max(norm(c.tangential_speed_before)))
        .fold(0.0, f64::max);
    let jump = ev
        .contacts
        .iter()
        .map(|c| {
            let dv = [0, 1].map(|a| c.tangential_speed_after[a] - c.tangential_speed_before[a]);
            (c.speed_after - c.speed_before).abs().max(norm(dv))
        })
        .fold(fast, f64::max);
    let (tz, tv, slides) = (1e-9 * big, 1e-9 * fast, 1e-9 * jump);
    for c in &ev.contacts {
        let (l, lt, vt) = (c.impulse, c.tangential_impulse, c.tangential_speed_after);
        let newton = c.speed_after + e * c.speed_before;
        assert!(l >= -tz, "{what}: Λ = {l} < 0: {c:?}");
        assert!(newton >= -tv, "{what}: ġ⁺ < −e ġ⁻: {c:?}");
        assert!(
            l <= tz || newton.abs() <= tv,
            "{what}: Λ > 0 but ġ⁺ ≠ −e ġ⁻ ({newton}): {c:?}"
        );
        assert!(norm(lt) <= mu * l + tz, "{what}: outside the cone: {c:?}");
        if norm(vt) > slides {
            let want = [0, 1].map(|a| -mu * l * vt[a] / norm(vt));
            assert!(
                (0..2).all(|a| (lt[a] - want[a]).abs() <= tz),
                "{what}: slides with Λ_t = {lt:?}, want −μ Λ v̂_t⁺ = {want:?}: {c:?}"
            );
        }
    }
    assert!(
        ev.energy_after <= ev.energy_before + 1e-12 * ev.energy_before.abs().max(1.0),
        "{what}: energy gained: {} → {}",
        ev.energy_before,
        ev.energy_after
    );
}

/// The tilted box of `tilted_box_landing_on_one_corner_keeps_its_impulses`
/// with μ = 0.2, 0.5, 1 and 2 over a whole second. The iteration of the
/// sliding direction stopped at a later one-corner impact ("the impact of
/// 1 contact(s) has no solution" at t = 0.2849 s and 0.1405 s for μ = 0.2
/// and 0.5): there the impact is solved as a second-order-cone
/// complementarity problem. With μ = 1 the run stopped at t = 0.318 s on
/// the step limit: one corner sliding on the floor slowed to rest while
/// friction turned the box and its sliding direction with it, so
/// `v_t · s₀` never fell through zero, and the integrator followed the
/// slide into `v_t = 0` in 100 000 steps of 2 ps (now the slide's speed
/// falling below half its slip speed is an event: the corner sticks). At
/// every impact the Newton–Coulomb conditions hold
/// ([`assert_newton_coulomb`]) and the energy is never gained; from one
/// contact event to the next the energy never rises (to 1e-9 of the
/// start), and the run ends below its start.
#[test]
fn tilted_box_runs_a_second_through_its_one_corner_impacts() {
    // The four runs are independent: on every core.
    std::thread::scope(|scope| {
        let runs: Vec<_> = [0.2, 0.5, 1.0, 2.0]
            .map(|mu| scope.spawn(move || tilted_box_run(mu)))
            .into_iter()
            .collect();
        for run in runs {
            run.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        }
    });
}

/// One run of [`tilted_box_runs_a_second_through_its_one_corner_impacts`].
fn tilted_box_run(mu: f64) {
    let (c, s) = (0.05f64.cos(), 0.05f64.sin() / 2f64.sqrt());
    let clock = std::time::Instant::now();
    let sys = box4(mu, 0.5, [c, s, s, 0.0], [0.5, 0.0, -1.0, 0.0, 0.0, 0.0]);
    let report = run(&sys, &options(1.0));
    assert!(report.stop.is_finished(), "mu {mu}: {}", report.stop);
    assert!((report.t - 1.0).abs() < 1e-12, "mu {mu}: t = {}", report.t);
    let impacts: Vec<_> = report
        .contact_events
        .iter()
        .filter(|ev| ev.kind == ContactEventKind::Impact)
        .collect();
    eprintln!(
        "mu {mu}: {} impacts, {} events, energy {:?}, {:.2} s, {} steps, {} rhs",
        impacts.len(),
        report.contact_events.len(),
        report.energy,
        clock.elapsed().as_secs_f64(),
        report.stats.steps,
        report.stats.rhs_evals
    );
    assert!(!impacts.is_empty());
    for ev in &impacts {
        assert_newton_coulomb(ev, 0.5, mu, &format!("mu {mu}, t = {}", ev.t));
    }
    let e0 = report.energy[0];
    let mut last = e0;
    for ev in &report.contact_events {
        assert!(
            ev.energy_before <= last + 1e-9 * e0 && ev.energy_after <= ev.energy_before + 1e-9 * e0,
            "mu {mu}, t = {}, {}: energy {last} → {} → {}",
            ev.t,
            ev.kind.name(),
            ev.energy_before,
            ev.energy_after
        );
        last = ev.energy_after;
    }
    assert!(
        report.energy[1] <= last + 1e-9 * e0 && report.energy[1] <= e0 + 1e-9 * e0.abs(),
        "mu {mu}: energy {:?}",
        report.energy
    );
}
