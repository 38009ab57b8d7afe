//! `eom-gen solve-static` and `simulate` on models with cables (ANCF
//! chains): exit statuses, the report, and the physics of the bundled
//! Gerstmayr–Irschik cantilever (its tip against the extensible elastica).

use std::process::{Command, Output};

fn eom_gen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs")
}

fn write(name: &str, text: &str) -> String {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/ancf-cli-tests");
    std::fs::create_dir_all(dir).expect("a scratch directory");
    let path = format!("{dir}/{name}");
    std::fs::write(&path, text).expect("write the model");
    path
}

#[test]
fn solve_static_cantilever_reaches_the_elastica() {
    let out = eom_gen(&["solve-static", "models/ancf/cantilever.ron", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let cable = &v["cables"][0];
    assert_eq!(cable["element"], "Cable2D");
    assert_eq!(cable["elements"], 16);
    let tip = &cable["end_position"];
    // The extensible elastica (eom_sim::large::elastica): (1.491462696,
    // −1.207239855); 16 elements are within 1.1e-6 of it.
    let (x, y) = (
        tip[0].as_f64().unwrap_or(f64::NAN),
        tip[1].as_f64().unwrap_or(f64::NAN),
    );
    assert!(
        ((x - 1.491_462_696).powi(2) + (y + 1.207_239_855).powi(2)).sqrt() < 2e-6,
        "{x} {y}"
    );
    // Every load step reports its residual history, ending below tolerance.
    let steps = cable["steps"].as_array().map_or(0, Vec::len);
    assert_eq!(steps, 10);
    // Text report: one line per load step.
    let out = eom_gen(&[
        "solve-static",
        "models/ancf/cantilever.ron",
        "--load-steps",
        "4",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    assert_eq!(
        text.lines().filter(|l| l.contains("λ =")).count(),
        4,
        "{text}"
    );
}

#[test]
fn solve_static_refuses_clearly() {
    // Newton cannot converge in 1 iteration per step with no halving.
    let out = eom_gen(&[
        "solve-static",
        "models/ancf/cantilever.ron",
        "--load-steps",
        "1",
        "--max-iterations",
        "1",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("did not converge"), "{err}");
    // A model without cables.
    let out = eom_gen(&["solve-static", "models/pendulum.ron"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("has no cables"));
    // A free-floating cable: the tangent is singular.
    let path = write(
        "free.ron",
        r#"Model(name: "free", bodies: [], joints: [], cables: [
            Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 4,
                  young: 1e9, density: 1000, width: 0.01, height: 0.01, start: Free,
                  end_force: (0, -1, 0))])"#,
    );
    let out = eom_gen(&["solve-static", &path]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("singular") || err.contains("did not converge"),
        "{err}"
    );
    // Bad arguments: exit 2.
    let out = eom_gen(&[
        "solve-static",
        "models/ancf/cantilever.ron",
        "--load-steps",
        "0",
    ]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn bad_cables_are_reported_at_once_with_their_places() {
    let path = write(
        "bad.ron",
        r#"Model(name: "bad", bodies: [], joints: [], cables: [
    Cable(name: "a", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0.5), elements: 0,
          young: -1, density: 1000, width: 0.01, start: Clamped),
])"#,
    );
    let out = eom_gen(&["check", &path]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    for needle in [
        "bad.ron:2:61: error: `Cable2D` cable `a` leaves the plane z = 0",
        "bad.ron:2:84: error: cable `a` has no elements",
        "bad.ron:3:18: error: Young's modulus `young` of cable `a` is -1 Pa",
        "not `height`",
    ] {
        assert!(err.contains(needle), "{needle} in\n{err}");
    }
}

#[test]
fn simulate_runs_the_pendulum_and_refuses_a_mixed_model() {
    let out = eom_gen(&[
        "simulate",
        "models/ancf/pendulum.ron",
        "--t-end",
        "0.05",
        "--dt",
        "1e-3",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let c = &v["cables"][0];
    assert_eq!(c["steps"], 50);
    assert_eq!(c["integrator"], "generalized-alpha");
    // Energy kept: kinetic + strain + gravity (scale m g L = 140 J).
    let (e0, e1) = (
        c["energy_start"].as_f64().unwrap_or(f64::NAN),
        c["energy_end"].as_f64().unwrap_or(f64::NAN),
    );
    assert!((e1 - e0).abs() < 1e-3, "{e0} {e1}");
    // The soft rod bends at once: its tip falls freely at first, g t²/2 =
    // 1.23 cm in 0.05 s (a rigid rod's tip would fall 1.5 times as far).
    let y = c["end_position"][1].as_f64().unwrap_or(f64::NAN);
    assert!((y + 9.81 * 0.05 * 0.05 / 2.0).abs() < 1e-4, "{y}");
    // An unknown integrator for cables is a usage error.
    let out = eom_gen(&[
        "simulate",
        "models/ancf/pendulum.ron",
        "--t-end",
        "0.01",
        "--integrator",
        "radau5",
    ]);
    assert_eq!(out.status.code(), Some(2));
    // Rigid bodies and cables in one model: refused with the reason.
    let path = write(
        "mixed.ron",
        r#"Model(name: "mixed", bodies: [(name: "b", mass: 1)],
  joints: [(name: "j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "b")],
  cables: [Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 2,
                 young: 1e9, density: 1000, width: 0.01, height: 0.01, start: Clamped)])"#,
    );
    let out = eom_gen(&["simulate", &path, "--t-end", "0.01"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("mixes rigid bodies and cables"));
}

#[test]
fn simulate_runs_a_cable_held_by_a_rigid_link_and_refuses_what_it_cannot() {
    // The Berzeri–Shabana rod pinned to a rigid link (models/ancf/pendulum_rod.ron).
    let out = eom_gen(&[
        "simulate",
        "models/ancf/pendulum_rod.ron",
        "--t-end",
        "0.1",
        "--dt",
        "1e-3",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(v["steps"], 100);
    assert_eq!(v["coordinates"][0], "theta");
    let num = |x: &serde_json::Value| x.as_f64().unwrap_or(f64::NAN);
    // The rod's first node stays at the link's tip (a = 0.3 m).
    let theta = num(&v["q"][0]);
    let first = [num(&v["first_node"][0]), num(&v["first_node"][1])];
    assert!(
        (first[0] - 0.3 * theta.cos()).abs() < 1e-9 && (first[1] - 0.3 * theta.sin()).abs() < 1e-9,
        "{first:?} at θ = {theta}"
    );
    assert!(num(&v["max_constraint_residual"]) < 1e-9);
    // Energy (scale: the rod's weight times its length, 140 J) kept.
    assert!((num(&v["energy_end"]) - num(&v["energy_start"])).abs() < 1e-3);
    // The explicit method and statics refuse, with the reason.
    let out = eom_gen(&[
        "simulate",
        "models/ancf/pendulum_rod.ron",
        "--t-end",
        "0.01",
        "--integrator",
        "rk4",
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("index-3"));
    let out = eom_gen(&["solve-static", "models/ancf/pendulum_rod.ron"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("solve-static does not solve mixed models")
    );
    // A cable end that is not at its marker at the start.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/pendulum_rod.ron"
    ))
    .expect("the bundled model");
    let path = write(
        "off_marker.ron",
        &text.replace("from: (\"a\", 0, 0)", "from: (\"a + 0.01\", 0, 0)"),
    );
    let out = eom_gen(&["simulate", &path, "--t-end", "0.01"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("`rod.start` is 1.000e-2 m from its marker"),
        "{err}"
    );
}
