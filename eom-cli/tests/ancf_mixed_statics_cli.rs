//! `eom-gen solve-static` on models whose cables hang at markers of rigid
//! bodies (mixed models): the rigid part interpreted from the model file,
//! the equilibrium by Newton on the KKT system with load stepping.
//!
//! Physics checked:
//! - **The bundled `models/ancf/crane_rope.ron`** (a pinned rope with an
//!   end mass hanging from a sprung boom): a pinned rope transmits no
//!   moment and hangs vertically, so the boom carries its whole weight
//!   `W = (ρ A L + m_e) g` at the tip, `k θ + (m g a/2 + W a) cos θ = 0`;
//!   the rope is the hanging bar, stretched by `(m_e g L + ρ A g L²/2)/EA`.
//! - **The bundled `models/ancf/pendulum_rod.ron`** (no spring, released
//!   horizontal): the link and the Berzeri–Shabana rod hang straight down,
//!   `θ = −π/2`, the rod stretched by its own weight, `ρ A g L²/(2 EA)`.
//! - **Stability**: the boom standing upright on a spring weaker than
//!   gravity's negative stiffness `m g a/2 + W a` is in equilibrium but
//!   reported unstable.
//! - **Several cables** (`trapeze`) and **a rigid loop beside a cable**
//!   (`fourbar_cable`): closed forms in their tests.
//! - **Refusals** with the reason and exit status 1: a cart on a
//!   frictionless rail (a mechanism, its coordinate named), and Newton
//!   that cannot converge.

use std::process::{Command, Output};

fn eom_gen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs")
}

fn write(name: &str, text: &str) -> String {
    let dir = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../target/ancf-mixed-statics-tests"
    );
    std::fs::create_dir_all(dir).expect("a scratch directory");
    let path = format!("{dir}/{name}");
    std::fs::write(&path, text).expect("write the model");
    path
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = eom_gen(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

fn num(x: &serde_json::Value) -> f64 {
    x.as_f64().unwrap_or(f64::NAN)
}

const G: f64 = 9.81;

#[test]
fn the_crane_rope_meets_the_closed_form() {
    let v = json(&["solve-static", "models/ancf/crane_rope.ron", "--json"]);
    let (a, m, k, l, m_end) = (0.5, 1.0, 20.0, 1.0, 0.5);
    let (rho_a, ea) = (7800.0 * 1e-4, 2e7 * 1e-4);
    let w = (rho_a * l + m_end) * G;
    let s = m * G * a / 2.0 + w * a;
    let mut want = 0.0_f64;
    for _ in 0..100 {
        want -= (k * want + s * want.cos()) / (k - s * want.sin());
    }
    let theta = num(&v["q"][0]);
    println!("θ = {theta:.12}, closed form {want:.12}");
    assert_eq!(v["q"].as_array().map(Vec::len), Some(1));
    assert!((theta - want).abs() < 1e-9, "{theta} vs {want}");
    // The marker holds the whole weight, straight up.
    let f = &v["mounts"][0]["force"];
    assert!(num(&f[0]).abs() < 1e-8 && (num(&f[1]) - w).abs() < 1e-8 * w);
    // Vertical below the tip, stretched as the hanging bar.
    let (first, last) = (&v["cables"][0]["first_node"], &v["cables"][0]["last_node"]);
    assert!((num(&first[0]) - a * theta.cos()).abs() < 1e-9);
    assert!((num(&last[0]) - num(&first[0])).abs() < 1e-9);
    let stretch = (m_end * G * l + rho_a * G * l * l / 2.0) / ea;
    assert!((num(&first[1]) - num(&last[1]) - l - stretch).abs() < 1e-9);
    assert_eq!(v["stability"]["stable"], true);
    assert!(num(&v["constraint_residual"]) < 1e-12);
    // The text report: one line per load step, the rigid coordinates,
    // the marker's force, the stability.
    let out = eom_gen(&[
        "solve-static",
        "models/ancf/crane_rope.ron",
        "--load-steps",
        "4",
    ]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    println!("{text}");
    assert_eq!(text.lines().filter(|l| l.contains("λ =")).count(), 4);
    for needle in [
        "rigid part: theta = -0.40178114",
        "force of the marker on rope.start: (",
        "stable (smallest ω²",
    ] {
        assert!(text.contains(needle), "`{needle}` in\n{text}");
    }
}

#[test]
fn the_pendulum_rod_hangs_straight_down() {
    let v = json(&["solve-static", "models/ancf/pendulum_rod.ron", "--json"]);
    let theta = num(&v["q"][0]);
    let (rho_a, ea, l) = (5540.0 * 0.0018, 0.7e6 * 0.0018, 1.2);
    let stretch = rho_a * G * l * l / 2.0 / ea;
    let (first, last) = (&v["cables"][0]["first_node"], &v["cables"][0]["last_node"]);
    println!(
        "θ = {theta:.12}; rod from {first} to {last}; stretch {stretch:.9}; {}",
        v["stability"]
    );
    assert!(
        (theta + std::f64::consts::FRAC_PI_2).abs() < 1e-9,
        "{theta}"
    );
    assert!((num(&first[1]) + 0.3).abs() < 1e-9 && num(&last[0]).abs() < 1e-9);
    assert!((num(&first[1]) - num(&last[1]) - l - stretch).abs() < 1e-9);
    assert!((num(&v["mounts"][0]["force"][1]) - rho_a * l * G).abs() < 1e-8);
    assert_eq!(v["stability"]["stable"], true);
}

#[test]
fn an_upright_boom_on_a_weak_spring_is_reported_unstable() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/crane_rope.ron"
    ))
    .expect("the bundled model");
    // Upright: the boom along +y, the rope hanging from (0, a).
    let upright = text
        .replace(
            "coordinates: [\"theta\"],",
            "coordinates: [\"theta\"], q0: [\"pi/2\"],",
        )
        .replace("stiffness: \"k\")", "stiffness: \"k\", rest: \"pi/2\")")
        .replace("from: (\"a\", 0, 0)", "from: (0, \"a\", 0)")
        .replace("to: (\"a\", \"-L\", 0)", "to: (0, \"a - L\", 0)");
    let path = write("upright.ron", &upright);
    // Gravity's negative stiffness upright: m g a/2 + W a = 8.7309 N m/rad.
    for (k, stable) in [("4", false), ("20", true)] {
        let v = json(&[
            "solve-static",
            &path,
            "--param",
            &format!("k={k}"),
            "--json",
        ]);
        let theta = num(&v["q"][0]);
        println!("k = {k}: θ = {theta:.12}, {}", v["stability"]);
        assert!((theta - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert_eq!(v["stability"]["stable"], stable);
    }
    let out = eom_gen(&["solve-static", &path, "--param", "k=4"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("UNSTABLE"));
}

#[test]
fn a_mechanism_and_a_failed_newton_are_refused() {
    let path = write(
        "cart.ron",
        r#"Model(name: "cart", gravity: (0, -9.81, 0),
  bodies: [(name: "cart", mass: 2, markers: [(name: "hook", position: (0, 0, 0))])],
  joints: [(name: "rail", kind: Prismatic(axis: (1, 0, 0)), parent: "ground", child: "cart",
            coordinates: ["x"])],
  cables: [Cable(name: "rope", element: Cable2D, from: (0, 0, 0), to: (0, -1, 0), elements: 4,
                 young: 2e7, density: 7800, area: 1e-4, second_moment: 1e-9, start: Pinned,
                 start_at: (body: "cart", marker: "hook"), end_mass: 0.5)])"#,
    );
    let out = eom_gen(&["solve-static", &path]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    println!("{err}");
    assert!(
        err.contains("model `cart`: the equilibrium is not isolated")
            && err.contains("the free direction moves coordinate `x`"),
        "{err}"
    );
    // Newton with one iteration per step and no halving cannot converge.
    let out = eom_gen(&[
        "solve-static",
        "models/ancf/crane_rope.ron",
        "--load-steps",
        "1",
        "--max-iterations",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    println!("{err}");
    assert!(err.contains("did not converge"), "{err}");
}

fn solve_json(model: &str) -> serde_json::Value {
    let out = eom_gen(&["solve-static", model, "--json"]);
    assert!(
        out.status.success(),
        "{model}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    match serde_json::from_slice(&out.stdout) {
        Ok(v) => v,
        Err(e) => panic!("{model}: JSON: {e}"),
    }
}

/// **Several cables**: the bundled trapeze (bar of mass m = 2 kg on two
/// pinned ropes of length L = 1 m, E = 1 GPa, d = 6 mm, ρ = 1150) rests
/// level under its pivots, each marker holding half the bar's weight,
/// each rope the hanging bar stretched by `(m g/2) L/EA + ρ g L²/(2E)`.
#[test]
fn trapeze_rests_level_on_two_ropes_each_stretched_as_a_hanging_bar() {
    let v = solve_json("models/ancf/trapeze.ron");
    let (m, g, l, e, rho) = (2.0, 9.81, 1.0, 1e9, 1150.0);
    let area = std::f64::consts::PI * 0.006f64.powi(2) / 4.0;
    let stretch = 0.5 * m * g * l / (e * area) + rho * g * l * l / (2.0 * e);
    let q = &v["q"];
    // The sideways sway is held by gravity alone (stiffness m g / L =
    // 19.6 N/m), so Newton's force tolerance leaves x at ~1e-11 m.
    assert!(num(&q[0]).abs() < 1e-9 && num(&q[2]).abs() < 1e-12, "{q}");
    assert!(
        (num(&q[1]) + l + stretch).abs() < 1e-9 * stretch.max(1.0),
        "y = {}, closed form {}",
        num(&q[1]),
        -(l + stretch)
    );
    for r in v["mounts"].as_array().into_iter().flatten() {
        let r = &r["force"];
        assert!((num(&r[1]) + 0.5 * m * g).abs() < 1e-9, "marker force {r}");
    }
    assert_eq!(v["cables"].as_array().map(Vec::len), Some(2));
    assert_eq!(v["stability"]["stable"], serde_json::json!(true));
}

/// **A rigid loop beside a cable**: the bundled four-bar (links of 1 kg/m,
/// crank a = 0.2 m, rocker c = 0.5 m) with a pinned cable (ρ = 1500,
/// 0.02 × 0.02 m, L = 0.4 m, E = 1 MPa) at the coupler's middle rests with
/// crank and rocker upright: both tips then move horizontally, so do the
/// coupler's points, and no weight does virtual work (a maximum of the
/// potential: unstable). The cable hangs straight, the marker carries its
/// weight `ρ A L g`, its free end lies `L + ρ g L²/(2E)` below the marker.
#[test]
fn fourbar_with_a_cable_rests_with_crank_and_rocker_upright_unstable() {
    let v = solve_json("models/ancf/fourbar_cable.ron");
    let q = &v["q"];
    let half_pi = std::f64::consts::FRAC_PI_2;
    assert!(
        (num(&q[0]) - half_pi).abs() < 1e-9 && (num(&q[2]) - half_pi).abs() < 1e-9,
        "crank and rocker at {q}"
    );
    assert!(num(&v["constraint_residual"]) < 1e-12);
    let (rho, area, lc, e, g) = (1500.0, 0.02 * 0.02, 0.4, 1e6, 9.81);
    let r = &v["mounts"][0]["force"];
    assert!(
        (num(&r[1]) - rho * area * lc * g).abs() < 1e-9,
        "marker force {r}"
    );
    let c = &v["cables"][0];
    let drop = num(&c["first_node"][1]) - num(&c["last_node"][1]);
    let expected = lc + rho * g * lc * lc / (2.0 * e);
    assert!(
        (drop - expected).abs() < 1e-9,
        "drop {drop}, closed form {expected}"
    );
    assert!(
        (num(&c["first_node"][0]) - num(&c["last_node"][0])).abs() < 1e-12,
        "hangs straight"
    );
    assert_eq!(v["stability"]["stable"], serde_json::json!(false));
}
