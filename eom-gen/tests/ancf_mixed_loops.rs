//! Rigid parts with constraint equations of their own beside ANCF cables
//! (issue #18): the loop of a four-bar closed by a cut joint, a rheonomic
//! holonomic constraint, as rows of the mixed model's constraint block
//! (`eom_sim::large::mixed`, index-3 generalized-α), the rigid part
//! interpreted.
//!
//! Physics checked:
//! - **A very stiff short rod with a tip mass clamped to the rocker moves
//!   as the rigid four-bar carrying that rod and mass** (eom's own rigid
//!   model, the rod and mass welded on, integrated by DOP853 with
//!   projection at 1e-12): the difference is the method's discretisation
//!   error, second order, shown by halving `h` twice.
//! - **Energy**: the bundled `models/ancf/fourbar_cable.ron` (a soft cable
//!   hanging from the coupler) without damping (`ρ∞ = 1`) keeps its energy
//!   to second order in the step.
//! - **The loop holds through the dead points**: the same model's crank
//!   revolves and passes both positions where crank and coupler line up;
//!   the loop's constraint residual stays at the Newton tolerance at every
//!   step.
//! - **A rheonomic constraint** `θ − θ₀ sin ωt = 0` drives a link carrying
//!   a cable: the link follows the prescribed angle to the Newton
//!   tolerance, and the cable moves as under the same motion given by a
//!   prescribed joint (no rigid coordinate, no multiplier for the drive).
//! - **Refusals, by name**: a rolling disk's no-slip (speed-level)
//!   equations beside a cable; initial values that do not close the loop.

use eom_gen::functions::FunctionSet;
use eom_gen::mech::formulate;
use eom_gen::model::{Source, check};
use eom_sim::large::{AlphaOptions, MixedAlpha, MixedModel, State};

fn system(name: &str, text: &str) -> eom_gen::System {
    match check(&Source::new(name, text.to_string())) {
        Ok(c) => c.system,
        Err(r) => panic!("{r}"),
    }
}

fn bundled() -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/fourbar_cable.ron"
    );
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Runs the mixed model of `text` (rigid part interpreted, assembled
/// start) to `t_end` at step `h`, calling `observe` after every step;
/// returns the final rigid coordinates and the largest constraint
/// residual of the loop's rows over the run.
fn run_mixed(
    text: &str,
    h: f64,
    rho_inf: f64,
    t_end: f64,
    mut observe: impl FnMut(&MixedModel<'_>, &State),
) -> (Vec<f64>, f64) {
    let sys = system("mixed.ron", text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &mixed.model;
    let (q0, u0) = eom_gen::cables::rigid_start(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let state = m.initial_state(0.0, &q0, &u0);
    observe(m, &state);
    let opts = AlphaOptions {
        h,
        rho_inf,
        ..AlphaOptions::default()
    };
    let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    let rows = m.rigid_constraint_rows();
    assert!(!rows.is_empty(), "the rigid part has constraint rows");
    let mut worst = 0.0_f64;
    ga.run_to(t_end, |s, _| {
        let phi = m.constraint_residual(s.t, &s.q);
        worst = phi[rows.clone()].iter().fold(worst, |a, x| a.max(x.abs()));
        observe(m, s);
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (ga.state().q[m.n_structural()..].to_vec(), worst)
}

/// The bundled model with a steel-like rod (modulus `E`) of length `l`
/// and a tip mass `M` clamped along the rocker at its tip instead of the
/// hanging cable.
fn with_rod(text: &str) -> String {
    let at = text
        .find("    cables: [")
        .unwrap_or_else(|| panic!("no cables"));
    let mut out = text[..at].replace(
        "(name: \"Lc\", value: 0.4, doc: \"cable length, m\"),",
        "(name: \"Lc\", value: 0.4, doc: \"cable length, m\"),
        (name: \"l\", value: 0.1), (name: \"M\", value: 0.5), (name: \"E\", value: 2e13),
        (name: \"mr\", value: \"7800*0.02^2*l\"),",
    );
    out.push_str(
        r#"    cables: [
        Cable(name: "rod", element: Cable2D, elements: 2,
              from: ("d + c*cos(r0)", "c*sin(r0)", 0), to: ("d + (c + l)*cos(r0)", "(c + l)*sin(r0)", 0),
              young: "E", density: 7800, width: 0.02, height: 0.02, end_mass: "M",
              start: Clamped, start_at: (body: "rocker", marker: "tip", axis: (1, 0, 0))),
    ],
)
"#,
    );
    out
}

/// The same rod and mass as rigid bodies welded to the rocker.
fn rigid_rod(text: &str) -> String {
    let rod = with_rod(text);
    let at = rod
        .find("    cables: [")
        .unwrap_or_else(|| panic!("no cables"));
    let head = &rod[..at];
    let bodies_end = head
        .find("    ],\n    joints: [")
        .unwrap_or_else(|| panic!("no joints"));
    let joints_end = head.rfind("    ],\n").unwrap_or_else(|| panic!("no end"));
    format!(
        "{}{}{}{}{})\n",
        &head[..bodies_end],
        r#"        (name: "rod", mass: "mr", com: ("l/2", 0, 0), inertia: Diag(0, "mr*l^2/12", "mr*l^2/12")),
        (name: "bob", mass: "M", inertia: Diag(0, 0, 0)),
"#,
        &head[bodies_end..joints_end],
        r#"        (name: "weld", kind: Fixed, parent: "rocker", child: "rod", parent_frame: (position: ("c", 0, 0))),
        (name: "weld2", kind: Fixed, parent: "rod", child: "bob", parent_frame: (position: ("l", 0, 0))),
"#,
        "    ],\n"
    )
}

/// The rod's compliance is far below the discretisation error: its tip
/// gives way by `δ ≈ F l³ / (3 E I)` with `F ≲ M (g + 30 m/s²) ≈ 20 N`,
/// `l = 0.1 m`, `E I = 2e13 · 1.33e-8 ≈ 2.7e5 N m²`: `δ ≈ 2.5e-8 m`, an
/// angle of about `5e-8` rad against `1.5e-4` at the smallest step.
#[test]
fn a_stiff_rod_on_the_rocker_moves_as_the_rigid_mechanism_to_second_order() {
    let t_end = 0.4;
    let text = bundled();
    let rigid_text = rigid_rod(&text);
    let rigid = system("fourbar_rigid_rod.ron", &rigid_text);
    let f = formulate(&rigid, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let o = eom_sim::RunOptions {
        integrator: "dop853".parse().unwrap_or_else(|e| panic!("{e:?}")),
        method: eom_sim::Method::Projection,
        rtol: 1e-12,
        atol: 1e-12,
        t_end,
        ..Default::default()
    };
    let report = eom_gen::interpret::simulate(&f, &rigid, &o).unwrap_or_else(|e| panic!("{e}"));
    let want = report.q.clone();
    let rod = with_rod(&text);
    let mut errors = Vec::new();
    for h in [4e-3, 2e-3, 1e-3] {
        let (q, residual) = run_mixed(&rod, h, 0.8, t_end, |_, _| {});
        let err = q
            .iter()
            .zip(&want)
            .fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()));
        println!("h = {h:e}: q {q:?}, rigid {want:?}, |Δq|∞ {err:.3e}, loop |Φ| {residual:.1e}");
        assert!(residual < 1e-10, "loop residual {residual:e}");
        errors.push(err);
    }
    // The mechanism moved: the crank turned by more than half a radian.
    let turned = (want[0] - std::f64::consts::FRAC_PI_2 + 0.2).abs();
    assert!(turned > 0.5, "crank turned {turned}");
    for w in errors.windows(2) {
        let order = (w[0] / w[1]).log2();
        println!("order {order:.2}");
        assert!(order > 1.8 && order < 2.3, "order {order}");
    }
}

/// The largest energy error of the bundled model over `[0, t_end]` at step
/// `h` without damping (`ρ∞ = 1`).
fn bundled_energy(h: f64, t_end: f64) -> f64 {
    let mut e0 = None;
    let mut worst = 0.0_f64;
    run_mixed(&bundled(), h, 1.0, t_end, |m, s| {
        let e = m.energy(s);
        let e0 = *e0.get_or_insert(e);
        worst = worst.max((e - e0).abs());
    });
    worst
}

#[test]
fn the_bundled_fourbar_cable_keeps_its_energy_to_second_order() {
    let t_end = 0.5;
    let (e1, e2) = (bundled_energy(2e-3, t_end), bundled_energy(1e-3, t_end));
    let order = (e1 / e2).log2();
    println!(
        "fourbar_cable, max |ΔE| over {t_end} s: h = 2e-3 {e1:.3e} J, 1e-3 {e2:.3e} J, order {order:.2}"
    );
    assert!(order > 1.7 && order < 2.5, "order {order}");
}

#[test]
fn the_loop_holds_at_the_newton_tolerance_through_the_dead_points() {
    // φ2 = kπ: crank and coupler in line (the rocker's dead points).
    let pi = std::f64::consts::PI;
    let mut lineups: Vec<(f64, f64)> = Vec::new();
    let mut closest = f64::INFINITY;
    let mut last: Option<f64> = None;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let t_end = 1.5;
    let (_, worst) = run_mixed(&bundled(), 1e-3, 1.0, t_end, |m, s| {
        let (phi1, phi2) = (s.q[m.n_structural()], s.q[m.n_structural() + 1]);
        (lo, hi) = (lo.min(phi1), hi.max(phi1));
        closest = closest.min((phi2 - (phi2 / pi).round() * pi).abs());
        let side = (phi2 / pi).floor();
        if let Some(before) = last
            && side != before
        {
            // The multiple of π crossed, and when.
            lineups.push((s.t, before.max(side)));
        }
        last = Some(side);
    });
    println!(
        "crank between {lo:.3} and {hi:.3} rad over {t_end} s; crank and coupler in line at (t, φ2/π) = {lineups:?} (closest |φ2 − kπ| {closest:.1e}); loop |Φ|∞ over the run {worst:.1e}"
    );
    let mut kinds: Vec<i64> = lineups.iter().map(|(_, k)| *k as i64).collect();
    kinds.sort();
    kinds.dedup();
    assert!(kinds.len() >= 2, "both dead points passed: {lineups:?}");
    assert!(worst < 1e-10, "loop residual {worst:e}");
}

/// A link pivoted at the origin whose angle is prescribed by a holonomic
/// constraint, a cable hanging from its tip.
const DRIVEN_LINK: &str = r#"
Model(
    name: "driven_link",
    gravity: (0, -9.81, 0),
    bodies: [(name: "link", mass: 1.0, com: (0.15, 0, 0), inertia: Diag(0, 0.0075, 0.0075),
              markers: [(name: "tip", position: (0.3, 0, 0))])],
    joints: [(name: "pivot", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "link",
              coordinates: ["theta"], u0: [1.0])],
    constraints: [Holonomic(name: "drive", expr: "theta - 0.5*sin(2*t)")],
    cables: [Cable(name: "rope", element: Cable2D, from: (0.3, 0, 0), to: (0.3, -0.5, 0), elements: 4,
                   young: 1e7, density: 1000, width: 0.01, height: 0.01,
                   start: Pinned, start_at: (body: "link", marker: "tip"))],
)
"#;

/// The same link moved by a prescribed joint (no rigid coordinate).
const PRESCRIBED_LINK: &str = r#"
Model(
    name: "prescribed_link",
    gravity: (0, -9.81, 0),
    bodies: [(name: "link", mass: 1.0, com: (0.15, 0, 0), inertia: Diag(0, 0.0075, 0.0075),
              markers: [(name: "tip", position: (0.3, 0, 0))])],
    joints: [(name: "pivot", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "link",
              prescribed: ["0.5*sin(2*t)"])],
    cables: [Cable(name: "rope", element: Cable2D, from: (0.3, 0, 0), to: (0.3, -0.5, 0), elements: 4,
                   young: 1e7, density: 1000, width: 0.01, height: 0.01,
                   start: Pinned, start_at: (body: "link", marker: "tip"))],
)
"#;

/// The cable's coordinates (the structure's free vector) of the mixed
/// model of `text` at `t_end`.
fn cable_at(text: &str, h: f64, t_end: f64) -> Vec<f64> {
    let sys = system("mixed.ron", text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &mixed.model;
    let (q0, u0) = eom_gen::cables::rigid_start(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let opts = AlphaOptions {
        h,
        rho_inf: 0.9,
        ..AlphaOptions::default()
    };
    let mut ga =
        MixedAlpha::new(m, m.initial_state(0.0, &q0, &u0), opts).unwrap_or_else(|e| panic!("{e}"));
    ga.run_to(t_end, |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    ga.state().q[..m.n_structural()].to_vec()
}

#[test]
fn a_rheonomic_constraint_drives_the_link_as_a_prescribed_joint_does() {
    // θ − 0.5 sin 2t = 0 as the rigid part's own (rheonomic) equation.
    let mut worst = 0.0_f64;
    let (q, residual) = run_mixed(DRIVEN_LINK, 1e-3, 0.9, 1.0, |m, s| {
        let theta = s.q[m.n_structural()];
        worst = worst.max((theta - 0.5 * (2.0 * s.t).sin()).abs());
    });
    println!(
        "θ(1) = {:.12}, prescribed {:.12}; max |θ − θ(t)| {worst:.1e}; |Φ| {residual:.1e}",
        q[0],
        0.5 * 2.0_f64.sin()
    );
    assert!(worst < 1e-10 && residual < 1e-10);
    // The cable sees the same marker motion at every step either way: its
    // motion agrees with the prescribed joint's to the Newton tolerance.
    let driven = cable_at(DRIVEN_LINK, 1e-3, 1.0);
    let prescribed = cable_at(PRESCRIBED_LINK, 1e-3, 1.0);
    let d = driven
        .iter()
        .zip(&prescribed)
        .fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()));
    let swing = driven
        .iter()
        .zip(&prescribed)
        .fold(0.0_f64, |a, (x, _)| a.max(x.abs()));
    println!(
        "cable coordinates at 1 s: driven and prescribed differ by {d:.1e} (scale {swing:.2})"
    );
    assert!(d < 1e-10, "{d:e}");
}

fn refusal(text: &str) -> String {
    let sys = system("refused.ron", text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    match eom_gen::cables::check_rigid(&sys, &f)
        .and_then(|()| eom_gen::cables::rigid_start(&sys, &f).map(|_| ()))
    {
        Ok(()) => "accepted".into(),
        Err(e) => e.to_string(),
    }
}

/// A disk rolling on `z = 0` (prismatic x, y, z, then yaw, lean and spin)
/// with a cable hanging from its centre.
const ROLLING_DISK_CABLE: &str = r#"
Model(
    name: "disk_cable",
    gravity: (0, 0, -9.81),
    bodies: [
        (name: "px", mass: 0.1), (name: "py", mass: 0.1), (name: "pz", mass: 0.1),
        (name: "yaw", mass: 0.1), (name: "lean", mass: 0.1),
        (name: "disk", mass: 1.0, inertia: Diag(0.0025, 0.005, 0.0025), markers: [(name: "center")]),
    ],
    joints: [
        (name: "jx", kind: Prismatic(axis: (1, 0, 0)), parent: "ground", child: "px", coordinates: ["x"]),
        (name: "jy", kind: Prismatic(axis: (0, 1, 0)), parent: "px", child: "py", coordinates: ["y"]),
        (name: "jz", kind: Prismatic(axis: (0, 0, 1)), parent: "py", child: "pz", coordinates: ["z"], q0: [0.1]),
        (name: "jyaw", kind: Revolute(axis: (0, 0, 1)), parent: "pz", child: "yaw", coordinates: ["psi"]),
        (name: "jlean", kind: Revolute(axis: (1, 0, 0)), parent: "yaw", child: "lean", coordinates: ["chi"]),
        (name: "jspin", kind: Revolute(axis: (0, 1, 0)), parent: "lean", child: "disk", coordinates: ["spin"]),
    ],
    constraints: [RollingDisk(name: "rolling", body: "disk", radius: 0.1, axis: (0, 1, 0))],
    cables: [Cable(name: "rope", element: Cable3D, from: (0, 0, 0.1), to: (0, 0, -0.4), elements: 2,
                   young: 1e7, density: 1000, width: 0.01, height: 0.01,
                   start: Pinned, start_at: (body: "disk", marker: "center"))],
)
"#;

#[test]
fn speed_level_constraints_and_open_loops_are_refused_by_name() {
    let text = refusal(ROLLING_DISK_CABLE);
    println!("{text}");
    for want in [
        "speed-level (nonholonomic)",
        "rolling.slip_x, rolling.slip_y",
        "index-3 method holds positions only",
    ] {
        assert!(text.contains(want), "missing `{want}` in {text}");
    }
    // The crank 0.01 rad off the closed start.
    let open = bundled().replace("q0: [\"phi0\"]", "q0: [\"phi0 + 0.01\"]");
    let text = refusal(&open);
    println!("{text}");
    for want in [
        "the initial values of `fourbar_cable` do not close its loops (C.0, C.1)",
        "assembly moves `phi1`",
    ] {
        assert!(text.contains(want), "missing `{want}` in {text}");
    }
}
