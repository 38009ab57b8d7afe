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
    let tip = &cable["last_node"];
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
    let steps = v["load_steps"].as_array().map_or(0, Vec::len);
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
fn simulate_runs_the_pendulum_and_a_mixed_model_and_refuses_one_without_inertia() {
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
    // The common run report: counters under `stats`, the energy at both
    // ends, the cables' nodes under `cables`; `rho_inf` says generalized-α.
    let c = &v["cables"][0];
    assert_eq!(v["stats"]["accepted"], 50);
    assert_eq!(v["rho_inf"], 1.0);
    // Energy kept: kinetic + strain + gravity (scale m g L = 140 J).
    let (e0, e1) = (
        v["energy"][0].as_f64().unwrap_or(f64::NAN),
        v["energy"][1].as_f64().unwrap_or(f64::NAN),
    );
    assert!((e1 - e0).abs() < 1e-3, "{e0} {e1}");
    // The soft rod bends at once: its tip falls freely at first, g t²/2 =
    // 1.23 cm in 0.05 s (a rigid rod's tip would fall 1.5 times as far).
    let y = c["last_node"][1].as_f64().unwrap_or(f64::NAN);
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
    // Rigid bodies and cables in one model run as one mixed model, hung
    // at each other or not; one whose body has no inertia is refused with
    // the reason.
    let path = write(
        "mixed.ron",
        r#"Model(name: "mixed", bodies: [(name: "b", mass: 1)],
  joints: [(name: "j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "b")],
  cables: [Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 2,
                 young: 1e9, density: 1000, width: 0.01, height: 0.01, start: Clamped)])"#,
    );
    let out = eom_gen(&["simulate", &path, "--t-end", "0.01"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("the motion of joint `j` (speed `j_dot`) has no inertia"),
        "{err}"
    );
    // A free wire dropped on a cart rolling at 1 m/s (no cable hangs at
    // the cart): both end at the shared speed m_c v₀/(m_c + m_w) = 0.8.
    let out = eom_gen(&[
        "simulate",
        "models/ancf/wire_on_cart.ron",
        "--t-end",
        "1",
        "--dt",
        "2e-3",
        "--rho-inf",
        "0.8",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let u = v["u"][0].as_f64().unwrap_or(f64::NAN);
    assert!((u - 0.8).abs() < 1e-6, "the cart at {u} m/s");
    // Its free wire has no static equilibrium: refused with the reason.
    let out = eom_gen(&["solve-static", "models/ancf/wire_on_cart.ron"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("a mechanism"), "{err}");
    // The pendulum beside its peg hangs straight down, θ = −π/2.
    let out = eom_gen(&["solve-static", "models/ancf/pendulum_peg.ron", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let theta = v["q"][0].as_f64().unwrap_or(f64::NAN);
    assert!(
        (theta + std::f64::consts::FRAC_PI_2).abs() < 1e-9,
        "θ = {theta}"
    );
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
    assert_eq!(v["stats"]["accepted"], 100);
    // `q` holds the rigid part's coordinates (`theta`), the cables' state
    // is under `cables`.
    assert_eq!(v["q"].as_array().map(Vec::len), Some(1));
    let num = |x: &serde_json::Value| x.as_f64().unwrap_or(f64::NAN);
    // The rod's first node stays at the link's tip (a = 0.3 m).
    let theta = num(&v["q"][0]);
    let first = [
        num(&v["cables"][0]["first_node"][0]),
        num(&v["cables"][0]["first_node"][1]),
    ];
    assert!(
        (first[0] - 0.3 * theta.cos()).abs() < 1e-9 && (first[1] - 0.3 * theta.sin()).abs() < 1e-9,
        "{first:?} at θ = {theta}"
    );
    assert!(num(&v["largest_constraint_residual"]) < 1e-9);
    // Energy (scale: the rod's weight times its length, 140 J) kept.
    assert!((num(&v["energy"][1]) - num(&v["energy"][0])).abs() < 1e-3);
    // The explicit method refuses, with the reason (statics:
    // tests/ancf_mixed_statics_cli.rs).
    let out = eom_gen(&[
        "simulate",
        "models/ancf/pendulum_rod.ron",
        "--t-end",
        "0.01",
        "--integrator",
        "rk4",
    ]);
    // An integrator that does not apply is a usage error (exit 2).
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("index-3"));
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

#[test]
fn check_stats_and_dump_report_the_cables() {
    // The bundled cantilever: one Cable2D chain of 16 elements clamped at
    // one end (17 nodes × 4 = 68 coordinates, 64 free).
    let model = "models/ancf/cantilever.ron";
    let out = eom_gen(&["check", model]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("Cable2D × 16 elements, 17 nodes × 4 = 68 coordinates (64 free)")
            && text.contains("kernel eom_elements::Cable2D")
            && text.contains("rule: "),
        "{text}"
    );
    let out = eom_gen(&["check", model, "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let c = &v["cables"][0];
    assert_eq!(c["element"], "Cable2D");
    assert_eq!(c["coordinates"], 68);
    assert_eq!(c["free_coordinates"], 64);
    assert_eq!(c["kernel_file"], "elements/src/cable2d.rs");
    assert!(
        c["rule"].as_str().is_some_and(|r| r.contains("Gauss")),
        "{c}"
    );

    // stats: the kernel's operation counts (those in the generated file's
    // documentation) and the chain's ops per force evaluation.
    let out = eom_gen(&["stats", model, "--json"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let k = &v["cables"]["kernels"]["Cable2D"];
    let forces = k["internal_forces"]["total"].as_u64().unwrap_or(0);
    let file = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../elements/src/cable2d.rs"
    ))
    .expect("the generated kernel");
    assert!(
        forces > 0 && file.contains(&format!("`internal_forces`: {forces} ops")),
        "{forces}"
    );
    assert_eq!(
        v["cables"]["cables"][0]["forces_ops"].as_u64(),
        Some(16 * forces)
    );
    let out = eom_gen(&["stats", model]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Cable2D::internal_jacobians"), "{text}");

    // dump: the source has no cable kernels, and says so.
    let out = eom_gen(&["dump", model]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("model-independent") && err.contains("elements/src/cable2d.rs"),
        "{err}"
    );
}

#[test]
fn distributed_load_in_the_model_format() {
    // A nearly inextensible cantilever (EI = 1 N m², EA = 1e6 N, L = 1 m)
    // under a dead load of 3 N/m (wL³/EI = 3): `solve-static` against the
    // extensible elastica under the same distributed load (shooting); 32
    // elements are within 1e-6 m of it (measured 7e-7).
    let path = write(
        "distributed.ron",
        r#"Model(name: "distributed", bodies: [], joints: [], cables: [
    Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 32,
          young: 1, density: 1, area: 1e6, second_moment: 1, start: Clamped,
          distributed_load: (0, -3, 0)),
])"#,
    );
    let out = eom_gen(&["solve-static", &path, "--json", "--load-steps", "20"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let tip = &v["cables"][0]["last_node"];
    let (x, y) = (
        tip[0].as_f64().unwrap_or(f64::NAN),
        tip[1].as_f64().unwrap_or(f64::NAN),
    );
    let reference =
        eom_sim::large::elastica::extensible_cantilever_distributed(1.0, 1e6, 1.0, [0.0, -3.0])
            .unwrap_or_else(|| panic!("the elastica reference failed"));
    let err = ((x - reference.x).powi(2) + (y - reference.y).powi(2)).sqrt();
    assert!(err < 1e-6, "({x}, {y}) vs {reference:?}");

    // Out of the plane of a planar cable, and not a vector: errors at the field.
    let path = write(
        "bad_distributed.ron",
        r#"Model(name: "bad", bodies: [], joints: [], cables: [
    Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 4,
          young: 1, density: 1, area: 1, second_moment: 1, start: Clamped,
          distributed_load: (0, -3, 1)),
    Cable(name: "d", element: Cable3D, from: (0, 0, 0), to: (1, 0, 0), elements: 4,
          young: 1, density: 1, area: 1, second_moment: 1, start: Clamped,
          distributed_load: (0, "w", 1)),
])"#,
    );
    let out = eom_gen(&["check", &path]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    for needle in [
        "bad_distributed.ron:4:29: error: `Cable2D` cable `c` has a distributed load out of its plane (z = 1)",
        "bad_distributed.ron:7:",
        "`w`",
    ] {
        assert!(err.contains(needle), "{needle} in\n{err}");
    }
}

#[test]
fn node_forces_in_the_model_format() {
    // A force P at the middle node of a cantilever (EI = 1 N m², L = 1 m,
    // 4 elements, P = 1e-4 N): Euler–Bernoulli's tip deflection
    // 5PL³/(48EI), nodally exact for the cubic elements; beside it the
    // same force on the tip gives PL³/(3EI).
    let model = |node: usize| {
        format!(
            r#"Model(name: "node_force", bodies: [], joints: [], cables: [
    Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 4,
          young: 1, density: 1, area: 1e6, second_moment: 1, start: Clamped,
          node_forces: [(node: {node}, force: (0, -1e-4, 0))]),
])"#
        )
    };
    for (node, want) in [(2usize, 5.0 / 48.0 * 1e-4), (4, 1e-4 / 3.0)] {
        let path = write(&format!("node_force_{node}.ron"), &model(node));
        let out = eom_gen(&["solve-static", &path, "--json"]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
        let y = v["cables"][0]["last_node"][1].as_f64().unwrap_or(f64::NAN);
        assert!((-y / want - 1.0).abs() < 1e-6, "node {node}: {y} vs {want}");
    }
    // A node the cable does not have, and a planar cable loaded out of its
    // plane: both errors at their fields.
    let path = write(
        "bad_node_force.ron",
        r#"Model(name: "bad", bodies: [], joints: [], cables: [
    Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 4,
          young: 1, density: 1, area: 1, second_moment: 1, start: Clamped,
          node_forces: [(node: 5, force: (0, -1, 0)), (node: 1, force: (0, 0, 2))]),
])"#,
    );
    let out = eom_gen(&["check", &path]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    for needle in [
        "bad_node_force.ron:4:32: error: cable `c` has no node 5 (its nodes are 0 to 4)",
        "bad_node_force.ron:4:72: error: `Cable2D` cable `c` has a node force out of its plane (z = 2)",
    ] {
        assert!(err.contains(needle), "{needle} in\n{err}");
    }
}

#[test]
fn simulate_names_every_cable_of_a_mixed_model() {
    // models/ancf/trapeze.ron: a bar hanging by two ropes.
    let csv = write("trapeze.csv", "");
    let out = eom_gen(&[
        "simulate",
        "models/ancf/trapeze.ron",
        "--t-end",
        "0.05",
        "--dt",
        "1e-3",
        "--json",
        "--csv",
        &csv,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let num = |x: &serde_json::Value| x.as_f64().unwrap_or(f64::NAN);
    assert_eq!(v["cables"][0]["cable"], "left_rope");
    assert_eq!(v["cables"][1]["cable"], "right_rope");
    assert_eq!(v["mounts"][0]["attachment"], "left_rope.end");
    assert_eq!(v["mounts"][1]["attachment"], "right_rope.end");
    // Each rope's last node is at its marker on the bar, (x ∓ a, y) with
    // the bar level; every node is listed (4 elements: 5 nodes).
    let (x, y) = (num(&v["q"][0]), num(&v["q"][1]));
    for (k, side) in [(0, -0.25), (1, 0.25)] {
        let rope = &v["cables"][k];
        assert_eq!(rope["nodes"].as_array().map(|a| a.len()), Some(5));
        let last = [num(&rope["last_node"][0]), num(&rope["last_node"][1])];
        assert!(
            (last[0] - x - side).abs() < 1e-9 && (last[1] - y).abs() < 1e-9,
            "{last:?} against ({x}, {y})"
        );
    }
    let text = std::fs::read_to_string(&csv).expect("the CSV");
    let header = text.lines().next().unwrap_or_default();
    // The common CSV: t, the rigid coordinates and speeds, every node of
    // every cable, the energy.
    let nodes = |rope: &str| {
        (0..5)
            .flat_map(|k| ["x", "y", "z"].map(|a| format!("{rope}.node{k}.{a}")))
            .collect::<Vec<_>>()
            .join(",")
    };
    assert_eq!(
        header,
        format!(
            "t,x,y,theta,x_dot,y_dot,theta_dot,{},{},energy",
            nodes("left_rope"),
            nodes("right_rope")
        )
    );
    assert_eq!(
        text.lines().count(),
        52,
        "a header, the start (t = 0) and 50 steps"
    );
}

/// `eval` on a model with a cable says that the generated functions are
/// the rigid part's alone, and gives the whole model's consistent
/// accelerations at the state: for `pendulum_rod` (link released
/// horizontal, rod pinned at its tip, straight and at rest) the link's θ̈
/// with the rod differs from the bare link's, and it is what `simulate`
/// does: over the first millisecond θ(t) = ½ θ̈ t² (to O(t)), and the
/// rod's free end, with no elastic force yet, falls as a free particle,
/// y = −½ g t².
#[test]
fn eval_of_a_model_with_a_cable_says_its_scope_and_gives_the_whole_model() {
    let out = eom_gen(&["eval", "--interpret", "models/ancf/pendulum_rod.ron"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("rigid part alone") && err.contains("`rod`"),
        "{err}"
    );
    let v: serde_json::Value = match serde_json::from_slice(&out.stdout) {
        Ok(v) => v,
        Err(e) => panic!("eval JSON: {e}"),
    };
    let bare = v["udot"][0].as_f64().unwrap_or(f64::NAN);
    let whole = v["cables"]["whole_model"]["udot"][0]
        .as_f64()
        .unwrap_or(f64::NAN);
    assert!((bare + 49.05).abs() < 1e-9, "bare link θ̈ = {bare}");
    assert!(
        whole.is_finite() && (whole - bare).abs() > 1.0,
        "θ̈ with rod {whole}"
    );

    let t = 1e-3;
    let out = eom_gen(&[
        "simulate",
        "models/ancf/pendulum_rod.ron",
        "--t-end",
        "1e-3",
        "--dt",
        "1e-5",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value = match serde_json::from_slice(&out.stdout) {
        Ok(v) => v,
        Err(e) => panic!("simulate JSON: {e}"),
    };
    let theta = s["q"][0].as_f64().unwrap_or(f64::NAN);
    let observed = 2.0 * theta / (t * t);
    assert!(
        ((observed - whole) / whole).abs() < 1e-2,
        "θ̈ from simulate {observed}, eval {whole}"
    );
    let y_end = s["cables"][0]["last_node"][1].as_f64().unwrap_or(f64::NAN);
    assert!(
        ((y_end + 0.5 * 9.81 * t * t) / (0.5 * 9.81 * t * t)).abs() < 1e-2,
        "free end y = {y_end}"
    );
}

/// The results of a sweep: header and rows (the quoted `stop` last).
fn sweep_results(dir: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(format!("{dir}/results.csv")).unwrap_or_default();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| {
            let (numbers, stop) = l.split_once(",\"").unwrap_or((l, ""));
            numbers
                .split(',')
                .map(String::from)
                .chain([stop.trim_end_matches('"').to_string()])
                .collect()
        })
        .collect();
    (header, rows)
}

fn cell(header: &[String], row: &[String], name: &str) -> f64 {
    let Some(k) = header.iter().position(|h| h == name) else {
        panic!("no column `{name}` in {header:?}")
    };
    row[k].parse().unwrap_or(f64::NAN)
}

/// `sweep` of cables alone: a free cable in uniform gravity falls as a
/// rigid body, every node by g t²/2 without deformation, whatever its
/// stiffness and density; generalized-α with ρ∞ = 1 (the trapezoidal
/// rule on a constant acceleration) reaches it to round-off. Each case's
/// chain is assembled from its own values (`young`, `density` swept); a
/// value the check refuses is a row with the reason, exit 3.
#[test]
fn sweep_of_a_falling_cable_is_free_fall_for_every_case() {
    let path = write(
        "falling.ron",
        r#"Model(name: "falling", gravity: (0, -9.81, 0),
            parameters: [(name: "E", value: 1e9), (name: "rho", value: 1000)],
            bodies: [], joints: [], cables: [
            Cable(name: "c", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0), elements: 3,
                  young: "E", density: "rho", width: 0.01, height: 0.01, start: Free)])"#,
    );
    let dir = format!("{path}.sweep");
    let out = eom_gen(&[
        "sweep",
        &path,
        "--param",
        "E=1e7,1e9",
        "--param",
        "rho=-1,1000,3000",
        "--t-end",
        "0.1",
        "--dt",
        "0.01",
        "--jobs",
        "2",
        "--out",
        &dir,
    ]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (h, rows) = sweep_results(&dir);
    assert_eq!(rows.len(), 6);
    let fall = -0.5 * 9.81 * 0.1 * 0.1;
    for r in &rows {
        let stop = r.last().map(String::as_str).unwrap_or_default();
        if cell(&h, r, "rho") < 0.0 {
            assert!(
                stop.starts_with("failed: ") && stop.contains("density"),
                "{stop}"
            );
            assert!(cell(&h, r, "c.node0.y").is_nan());
            continue;
        }
        assert_eq!(stop, "finished");
        assert!(
            (cell(&h, r, "t") - 0.1).abs() < 1e-12,
            "t = {}",
            cell(&h, r, "t")
        );
        for k in 0..4 {
            let (x, y) = (
                cell(&h, r, &format!("c.node{k}.x")),
                cell(&h, r, &format!("c.node{k}.y")),
            );
            assert!(
                (y - fall).abs() < 1e-10 && (x - k as f64 / 3.0).abs() < 1e-10,
                "case {}, node {k}: ({x}, {y}), free fall ({}, {fall})",
                r[0],
                k as f64 / 3.0
            );
        }
    }
    // Shards of the study merge into the same cases (study.json records
    // generalized-α's ρ∞ with the run options).
    let mut shards = Vec::new();
    for i in 0..2 {
        let shard = format!("{dir}.{i}");
        let _ = eom_gen(&[
            "sweep",
            &path,
            "--param",
            "E=1e7,1e9",
            "--param",
            "rho=-1,1000,3000",
            "--t-end",
            "0.1",
            "--dt",
            "0.01",
            "--shard",
            &format!("{i}/2"),
            "--out",
            &shard,
        ]);
        shards.push(shard);
    }
    let merged = format!("{dir}.all");
    let out = eom_gen(&["sweep", "--merge", &shards[0], &shards[1], "--out", &merged]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (hm, merged_rows) = sweep_results(&merged);
    assert_eq!(hm, h);
    let cells = |r: &[String]| -> Vec<String> {
        let cpu = h.iter().position(|c| c == "cpu_s").unwrap_or(0);
        r.iter()
            .enumerate()
            .filter(|(k, _)| *k != cpu)
            .map(|(_, c)| c.clone())
            .collect()
    };
    assert_eq!(
        merged_rows.iter().map(|r| cells(r)).collect::<Vec<_>>(),
        rows.iter().map(|r| cells(r)).collect::<Vec<_>>()
    );
    let study = std::fs::read_to_string(format!("{merged}/study.json")).unwrap_or_default();
    assert!(study.contains("\"rho_inf\": 1.0"), "{study}");
    for d in shards.iter().chain([&merged, &dir]) {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// `sweep` of a mixed model (the bundled rod on a pendulum link): the
/// rigid part formulated once with `m` tunable, the rod's chain from each
/// case's `L`; every finished row equals `simulate --param` of that case
/// (the model checked and formulated with the values inlined) to
/// round-off, a negative mass is a row with the reason; options that do
/// not apply are refused (exit 2).
#[test]
fn sweep_of_a_mixed_model_equals_runs_one_by_one() {
    let dir = write("mixed.sweep", "");
    let _ = std::fs::remove_file(&dir);
    let model = "models/ancf/pendulum_rod.ron";
    let out = eom_gen(&[
        "sweep",
        model,
        "--param",
        "m=-1,0.5,0.8",
        "--param",
        "L=1.0,1.2",
        "--t-end",
        "0.02",
        "--out",
        &dir,
    ]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (h, rows) = sweep_results(&dir);
    assert_eq!(rows.len(), 6);
    let mut compared = 0;
    for r in &rows {
        let (m, l) = (cell(&h, r, "m"), cell(&h, r, "L"));
        let stop = r.last().map(String::as_str).unwrap_or_default();
        if m < 0.0 {
            assert!(stop.contains("mass of body `link` is -1 kg"), "{stop}");
            continue;
        }
        assert_eq!(stop, "finished");
        let out = eom_gen(&[
            "simulate",
            model,
            "--t-end",
            "0.02",
            "--json",
            "--param",
            &format!("m={m}"),
            "--param",
            &format!("L={l}"),
        ]);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap_or_default();
        let (theta, want) = (cell(&h, r, "theta"), v["q"][0].as_f64().unwrap_or(f64::NAN));
        assert!(
            theta != 0.0 && (theta - want).abs() < 1e-12,
            "m = {m}, L = {l}: sweep {theta}, simulate {want}"
        );
        let last = v["cables"][0]["last_node"][0].as_f64().unwrap_or(f64::NAN);
        assert!(
            (cell(&h, r, "rod.node8.x") - last).abs() < 1e-12,
            "m = {m}, L = {l}"
        );
        compared += 1;
    }
    assert_eq!(compared, 4);
    let _ = std::fs::remove_dir_all(&dir);
    for (extra, says) in [
        (&["--integrator", "rk4"][..], "index-3"),
        (&["--max-steps", "10"][..], "--max-steps does not apply"),
        (&["--output", "x"][..], "--output does not apply"),
    ] {
        let mut args = vec![
            "sweep", model, "--param", "m=1", "--t-end", "0.01", "--out", &dir,
        ];
        args.extend(extra);
        let out = eom_gen(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(says), "{extra:?}: {err}");
    }
    let out = eom_gen(&[
        "sweep",
        "models/pendulum.ron",
        "--param",
        "m=1",
        "--t-end",
        "0.01",
        "--rho-inf",
        "0.5",
        "--out",
        &dir,
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("--rho-inf sets generalized-α"), "{err}");
}

/// `eom-gen simulate models/ancf/MODEL.ron --t-end T --dt 1e-3 --rho-inf
/// 0.5 --json --events-csv F`, which must succeed: its JSON report and
/// the events CSV's path.
fn simulate_with_events(model: &str, t_end: &str) -> (serde_json::Value, String) {
    simulate_file_with_events(&format!("models/ancf/{model}.ron"), model, t_end)
}

/// [`simulate_with_events`] on the model file `path`, the events CSV
/// named after `label`.
fn simulate_file_with_events(path: &str, label: &str, t_end: &str) -> (serde_json::Value, String) {
    let events = write(&format!("{label}_events.csv"), "");
    let out = eom_gen(&[
        "simulate",
        path,
        "--t-end",
        t_end,
        "--dt",
        "1e-3",
        "--rho-inf",
        "0.5",
        "--json",
        "--events-csv",
        &events,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (serde_json::from_slice(&out.stdout).expect("JSON"), events)
}

/// `simulate` on the bundled wire dropped onto a floor (contacts at cable
/// nodes, issue #26): the events in the JSON report as for rigid models —
/// the first an impact of all five nodes at once at `t₁ = √(2h₀/g)` —, the
/// same events as CSV with `--events-csv`, and at the end the held nodes'
/// normal forces carrying the wire's weight `ρ A L g`.
#[test]
fn simulate_reports_the_contact_events_of_a_cable_dropped_on_a_floor() {
    let (r, events) = simulate_with_events("cable_drop", "0.6");
    let ev = r["contact_events"].as_array().expect("contact events");
    let t1 = (2.0 * 0.2 / 9.81_f64).sqrt();
    assert_eq!(ev[0]["kind"], "impact");
    assert!((ev[0]["t"].as_f64().unwrap_or(f64::NAN) - t1).abs() < 1e-9);
    assert_eq!(ev[0]["contacts"].as_array().map(Vec::len), Some(5));
    let weight = 7850.0 * 8e-6 * 9.81;
    let sum: f64 = r["contact_forces"]
        .as_array()
        .expect("the held nodes' forces")
        .iter()
        .filter_map(|c| c["force"].as_f64())
        .sum();
    assert!(
        (sum - weight).abs() < 1e-3 * weight,
        "{sum} N, want {weight} N"
    );
    let csv = std::fs::read_to_string(&events).expect("the events CSV");
    let mut lines = csv.lines();
    let header = lines.next().unwrap_or_default();
    assert!(
        header.starts_with("t,kind,energy_before,energy_after,n0.impulse,n0.speed_before"),
        "{header}"
    );
    assert_eq!(lines.count(), ev.len(), "one row per event");
}

/// `simulate` on the bundled block dropped onto its clamped arm's node 0
/// (`models/ancf/block_drop.ron`: a contact at a cable node in a model
/// whose cable hangs at a rigid body, issue #26): the first event an
/// impact at `t₁ = √(2h₀/g)` with `ġ⁺ = −e ġ⁻` and the block's mass in the
/// impulse, `Λ = (1 + e) M |ġ⁻|` (`M` between the block's 1 kg and the
/// block with its arm, 1.0002 kg); the hops accumulate and the node rests,
/// its force carrying block and arm at the end; the events CSV names the
/// rigid part's speed after the cables' coordinates.
#[test]
fn simulate_reports_the_contact_events_of_a_cable_node_at_a_rigid_body() {
    let (r, events) = simulate_with_events("block_drop", "0.5");
    block_drop_events(&r, &events, "foot");
}

/// The same block dropped on its rail's lower limit instead of its arm's
/// node: a rigid body's contact in a model with a cable, the same events
/// and closed forms through the CLI.
#[test]
fn simulate_reports_the_contact_events_of_a_body_beside_a_cable() {
    let bundled = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/block_drop.ron"
    ))
    .expect("the bundled block_drop");
    let node = r#"Plane(name: "foot", at: (body: "arm", node: 0), point: (0, "-h0", 0), normal: (0, 1, 0), e: "e"),"#;
    assert!(bundled.contains(node), "the bundled contact");
    let path = write(
        "block_on_rail.ron",
        &bundled.replace(
            node,
            r#"JointLimit(name: "foot", joint: "rail", lower: "-h0", e: "e"),"#,
        ),
    );
    let (r, events) = simulate_file_with_events(&path, "block_on_rail", "0.5");
    block_drop_events(&r, &events, "foot.lower");
}

/// The bundled block drop's first impact by its closed forms, its rest on
/// the row `contact` carrying block and arm, and the events CSV.
fn block_drop_events(r: &serde_json::Value, events: &str, contact: &str) {
    let ev = r["contact_events"].as_array().expect("contact events");
    let (h0, e) = (0.05, 0.5);
    let t1 = (2.0 * h0 / 9.81_f64).sqrt();
    let v1 = (2.0 * 9.81 * h0).sqrt();
    assert_eq!(ev[0]["kind"], "impact");
    assert!((ev[0]["t"].as_f64().unwrap_or(f64::NAN) - t1).abs() < 1e-9);
    let c = &ev[0]["contacts"][0];
    let (before, after) = (
        c["speed_before"].as_f64().unwrap_or(f64::NAN),
        c["speed_after"].as_f64().unwrap_or(f64::NAN),
    );
    assert!((before + v1).abs() < 1e-9, "ġ⁻ {before}");
    assert!((after + e * before).abs() < 1e-9, "ġ⁺ {after}");
    let m = c["impulse"].as_f64().unwrap_or(f64::NAN) / ((1.0 + e) * v1);
    assert!((1.0..=1.0002).contains(&m), "Λ/((1 + e)|ġ⁻|) = {m} kg");
    let weight = (1.0 + 2e-4) * 9.81;
    let forces = r["contact_forces"]
        .as_array()
        .expect("the held node's force");
    let sum: f64 = forces.iter().filter_map(|c| c["force"].as_f64()).sum();
    assert!(
        (sum - weight).abs() < 1e-3 * weight,
        "{sum} N, want {weight} N"
    );
    assert_eq!(c["contact"], contact);
    let csv = std::fs::read_to_string(events).expect("the events CSV");
    let mut lines = csv.lines();
    let header = lines.next().unwrap_or_default();
    assert!(
        header.starts_with(&format!(
            "t,kind,energy_before,energy_after,{contact}.impulse"
        )),
        "{header}"
    );
    // The generalised impulse: the arm's free coordinates, then the
    // block's speed `y_dot` (the rail's).
    assert!(header.contains(",impulse_y1,"), "{header}");
    assert!(header.ends_with(",impulse_y_dot"), "{header}");
    assert_eq!(lines.count(), ev.len(), "one row per event");
}

/// Statics and linearisation hold no contacts. The bundled pendulum
/// (0.3 m) with a cable hanging from its tip (`pendulum_cable.ron`)
/// hangs, without contacts, with its tip at `y = −0.3`: with a floor at `y = −0.28` under the tip (a body's contact)
/// or under the cable's node 0 pinned there (a node's), that equilibrium
/// goes 2 cm through the floor. `solve-static` used to report it, stable,
/// and `linearize` its modes, both exiting 0; both now refuse it (exit 1),
/// naming the contact and the penetration. With the floor at `y = −0.35`
/// the hanging equilibrium leaves it open and both run.
#[test]
fn statics_and_linearize_refuse_an_equilibrium_through_a_contact() {
    let bundled = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/pendulum_cable.ron"
    ))
    .expect("the bundled pendulum_cable");
    let node = r#"at: (body: "rope", node: 2), point: (0, -0.25, 0)"#;
    assert!(bundled.contains(node), "the bundled contact");
    let pendulum = |at: &str, floor: f64| {
        bundled.replace(node, &format!("at: {at}, point: (0, {floor:?}, 0)"))
    };
    for (label, at) in [
        ("tip", r#"(body: "link", marker: "tip")"#),
        ("node", r#"(body: "rope", node: 0)"#),
    ] {
        let through = write(
            &format!("statics_{label}_through.ron"),
            &pendulum(at, -0.28),
        );
        let out = eom_gen(&["solve-static", &through]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{label}: {err}");
        assert!(
            err.contains("the equilibrium found goes through contact(s) `floor` by 2.000e-2"),
            "{label}: {err}"
        );
        let out = eom_gen(&["linearize", &through]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{label}: {err}");
        assert!(
            err.contains("unilateral contact(s) closed at this state (`floor` gap -2.000e-2)"),
            "{label}: {err}"
        );
        let open = write(&format!("statics_{label}_open.ron"), &pendulum(at, -0.35));
        for command in ["solve-static", "linearize"] {
            let out = eom_gen(&[command, &open]);
            assert!(
                out.status.success(),
                "{label} {command}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
}

/// The bundled block braking by Coulomb friction on a table (a rigid
/// body's contact, `mu: 0.3`) with a rope hanging from it
/// (`models/ancf/block_rope.ron`), through the CLI: the
/// run finishes, the block's stop is a `stick` event in the JSON report
/// with the block at rest after it, and the events CSV carries every
/// contact row's tangential impulses (`table.impulse_t1`, `…_t2`) as the
/// rigid runtime's does — the stick's own among them.
#[test]
fn simulate_reports_the_stick_of_a_body_braking_beside_a_cable() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/ancf/block_rope.ron");
    let (r, events) = simulate_file_with_events(path, "block_rope", "0.6");
    let ev = r["contact_events"].as_array().expect("contact events");
    let stick = ev
        .iter()
        .find(|e| e["kind"] == "stick")
        .unwrap_or_else(|| panic!("the block stops: {ev:?}"));
    let t = stick["t"].as_f64().unwrap_or(f64::NAN);
    assert!(t > 0.2 && t < 0.4, "stops at {t} s (v0/(μ g) = 0.34 s)");
    assert_eq!(stick["contacts"][0]["contact"], "table");
    let lt = stick["contacts"][0]["tangential_impulse"][0]
        .as_f64()
        .unwrap_or(f64::NAN);
    let csv = std::fs::read_to_string(events).expect("the events CSV");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name}: {header:?}"))
    };
    let (kind, t1) = (col("kind"), col("table.impulse_t1"));
    col("table.impulse_t2");
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), ev.len(), "one row per event");
    let stick_row = rows
        .iter()
        .find(|r| r[kind] == 3.0)
        .expect("the stick's row");
    assert!(
        lt != 0.0 && (stick_row[t1] - lt).abs() <= 1e-12 * lt.abs(),
        "the stick's Λ_t1: {} in the CSV, {lt} in the report",
        stick_row[t1]
    );
    let u = r["u"].as_array().expect("speeds");
    assert!(
        u.iter()
            .take(3)
            .all(|x| x.as_f64().is_some_and(|x| x.abs() < 1e-9)),
        "the block at rest at the end: {u:?}"
    );
}

/// The bundled wire dropped onto a peg (`models/ancf/wire_on_peg.ron`: a
/// cable node's sphere against a sphere fixed in the world, with
/// friction), through the CLI: its first event is the node's impact on
/// the peg's top at `t₁ = √(2h/g)`, `h = 0.19 m` (the wire starts left
/// by what it slides until then), with `ġ⁻ = −√(2gh)` (to 1e-9),
/// `ġ⁺ = −e ġ⁻`, and a tangential impulse inside the cone
/// against the slide; the events CSV names the contact's columns.
#[test]
fn simulate_reports_a_cable_nodes_impact_on_a_peg() {
    let (r, events) = simulate_with_events("wire_on_peg", "0.4");
    let ev = r["contact_events"].as_array().expect("contact events");
    let first = &ev[0];
    assert_eq!(first["kind"], "impact");
    let h = 0.19_f64;
    let t = first["t"].as_f64().unwrap_or(f64::NAN);
    assert!(
        (t - (2.0 * h / 9.81).sqrt()).abs() < 1e-9,
        "impact at {t} s"
    );
    let c = &first["contacts"][0];
    assert_eq!(c["contact"], "peg");
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    let (before, after) = (num(&c["speed_before"]), num(&c["speed_after"]));
    assert!(
        (before + (2.0 * 9.81 * h).sqrt()).abs() < 1e-9,
        "ġ⁻ {before}"
    );
    assert!((after + 0.5 * before).abs() < 1e-9, "ġ⁺ {after}");
    let (lam, lt, vt) = (
        num(&c["impulse"]),
        num(&c["tangential_impulse"][0]),
        num(&c["tangential_speed_before"][0]),
    );
    assert!(
        lt != 0.0 && lt.abs() <= 0.3 * lam * (1.0 + 1e-12) && lt * vt < 0.0,
        "Λ {lam}, Λ_t {lt}, v_t {vt}"
    );
    let csv = std::fs::read_to_string(events).expect("the events CSV");
    let header = csv.lines().next().unwrap_or_default();
    assert!(
        header.contains("peg.impulse,peg.speed_before,peg.speed_after,peg.impulse_t1"),
        "{header}"
    );
}
