//! A cable's initial motion from the model file (`velocity`,
//! `angular_velocity`: a rigid motion about the cable's `from` point).
//!
//! Physics checked:
//! - **A wire thrown under gravity flies on its parabola**: a rigid
//!   translation does not strain the wire, so every node follows
//!   `r₀ + v t + ½ g t²` and keeps its tangent; generalized-α is exact for
//!   a constant acceleration, so to round-off.
//! - **A wire set spinning about its end**: the cubic Hermite shape
//!   functions reproduce the linear velocity field `ω × (x − x₀)`, so the
//!   initial kinetic energy is the rigid body's `½ (ρ A L³/3) ω²` to
//!   round-off; free of forces, its centre then moves at
//!   `ω × (L/2) x̂` and the chord turns at `ω` (a steel wire stretches by a
//!   part in 10⁵ under the centrifugal load).
//! - **Located refusals**: a motion that moves an end pinned or clamped to
//!   the ground (or turns a clamped one), a planar cable moving out of its
//!   plane, an initial motion in a model with rigid bodies; a motion that
//!   vanishes at a held end is accepted.

use eom_gen::model::{Source, check};
use eom_sim::Integrator;
use eom_sim::large::{ElementRun, simulate_structure};

const RHO_A: f64 = 7850.0 * 8e-6;

fn wire(gravity: &str, start: &str, motion: &str) -> String {
    format!(
        r#"Model(
    name: "thrown",
    gravity: {gravity},
    bodies: [],
    joints: [],
    cables: [Cable(name: "wire", element: Cable2D, from: (0, 1, 0), to: (1, 1, 0),
        elements: 4, young: 2e9, density: 7850, area: 8e-6, second_moment: 5e-12,
        start: {start}{motion})],
)"#
    )
}

fn diagnose(text: &str) -> String {
    eom_gen::testkit::diagnose("models/thrown.ron", text)
}

fn simulate(text: &str, t_end: f64) -> eom_sim::RunReport {
    let sys = match check(&Source::new("thrown.ron", text.to_string())) {
        Ok(c) => c.system,
        Err(r) => panic!("{r}"),
    };
    let (built, cables) = eom_gen::cables::structure(&sys).expect("structure");
    let run = ElementRun {
        integrator: Integrator::GeneralizedAlpha,
        t_end,
        dt: 1e-3,
        rho_inf: 1.0,
        control: None,
        record: false,
        every: None,
    };
    let (report, _) =
        simulate_structure(&built.model, &cables, &[], &run, &mut |_| {}).expect("runs");
    assert_eq!(report.stop, eom_sim::Stop::Finished, "{:?}", report.stop);
    report
}

#[test]
fn a_thrown_wire_flies_on_its_parabola() {
    let (v, g, t) = ([2.0, 3.0], -9.81, 0.5);
    let report = simulate(
        &wire(
            "(0, -9.81, 0)",
            "Free",
            &format!(", velocity: ({}, {}, 0)", v[0], v[1]),
        ),
        t,
    );
    let nodes = &report.elements.as_ref().expect("element report").cables[0].nodes;
    for (j, r) in nodes.iter().enumerate() {
        let want = [j as f64 / 4.0 + v[0] * t, 1.0 + v[1] * t + 0.5 * g * t * t];
        for a in 0..2 {
            assert!(
                (r[a] - want[a]).abs() < 1e-10,
                "node {j} axis {a}: {} against the parabola's {}",
                r[a],
                want[a]
            );
        }
    }
}

#[test]
fn a_wire_spun_about_its_end_starts_with_the_rigid_energy_and_turns_at_omega() {
    let (w, t) = (2.0, 1.0);
    let report = simulate(
        &wire(
            "(0, 0, 0)",
            "Free",
            &format!(", angular_velocity: (0, 0, {w})"),
        ),
        t,
    );
    let rigid = 0.5 * (RHO_A * 1.0 / 3.0) * w * w;
    assert!(
        (report.energy[0] - rigid).abs() < 1e-12 * rigid,
        "initial energy {} against ½ (ρAL³/3) ω² = {rigid}",
        report.energy[0]
    );
    let cable = &report.elements.as_ref().expect("element report").cables[0];
    let (a, b) = (cable.first_node, cable.last_node);
    let centre = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    // The centre starts at (0.5, 1) moving at ω × (L/2) x̂ = (0, ω/2).
    let want = [0.5, 1.0 + w / 2.0 * t];
    for k in 0..2 {
        assert!(
            (centre[k] - want[k]).abs() < 1e-5,
            "centre {centre:?} against {want:?}"
        );
    }
    let angle = (b[1] - a[1]).atan2(b[0] - a[0]);
    let turned = (w * t + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
        - std::f64::consts::PI;
    assert!(
        (angle - turned).abs() < 1e-4,
        "chord at {angle} rad, want ω t = {turned} rad"
    );
    let length = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
    assert!((length - 1.0).abs() < 1e-4, "chord {length} m");
}

#[test]
fn initial_motions_that_move_a_held_end_or_leave_the_plane_are_refused_where_written() {
    let pinned = diagnose(&wire("(0, -9.81, 0)", "Pinned", ", velocity: (1, 0, 0)"));
    assert!(
        pinned.contains("models/thrown.ron:")
            && pinned.contains("the start of cable `wire` is pinned to the ground")
            && pinned.contains("(1.000000, 0.000000, 0.000000) m/s"),
        "{pinned}"
    );
    let clamped = diagnose(&wire(
        "(0, -9.81, 0)",
        "Clamped",
        ", angular_velocity: (0, 0, 1)",
    ));
    assert!(
        clamped.contains("clamped to the ground") && clamped.contains("turns it"),
        "{clamped}"
    );
    let out_of_plane = diagnose(&wire("(0, -9.81, 0)", "Free", ", velocity: (0, 0, 1)"));
    assert!(
        out_of_plane.contains("would leave its plane: initial velocity z = 1"),
        "{out_of_plane}"
    );
    let tilted = diagnose(&wire(
        "(0, -9.81, 0)",
        "Free",
        ", angular_velocity: (1, 0, 0)",
    ));
    assert!(tilted.contains("turns about z only"), "{tilted}");
    // A pinned start turning about itself, and a wire pinned at its far
    // end turning about that end, are fine.
    assert_eq!(
        diagnose(&wire(
            "(0, -9.81, 0)",
            "Pinned",
            ", angular_velocity: (0, 0, 1)"
        )),
        "valid"
    );
    assert_eq!(
        diagnose(&wire(
            "(0, -9.81, 0)",
            "Free, end: Pinned",
            ", velocity: (0, -1, 0), angular_velocity: (0, 0, 1)"
        )),
        "valid"
    );
    let mixed = r#"Model(
    name: "mixed",
    gravity: (0, -9.81, 0),
    bodies: [(name: "link", mass: 1, com: (0.5, 0, 0), inertia: Diag(0, 0.1, 0.1),
        markers: [(name: "tip", position: (1, 0, 0))])],
    joints: [(name: "j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "link")],
    cables: [Cable(name: "wire", element: Cable2D, from: (1, 0, 0), to: (2, 0, 0),
        elements: 2, young: 2e9, density: 7850, area: 8e-6, second_moment: 5e-12,
        start: Pinned, start_at: (body: "link", marker: "tip"), velocity: (1, 0, 0))],
)"#;
    let mixed = diagnose(mixed);
    assert!(mixed.contains("in a model with rigid bodies"), "{mixed}");
}
