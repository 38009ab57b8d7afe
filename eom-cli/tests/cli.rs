//! `eom-gen check`: exit status 0 / 1 / 2, the summary, and the JSON keys
//! other tools rely on.

use std::process::{Command, Output};

fn eom_gen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs")
}

fn json(args: &[&str]) -> serde_json::Value {
    let out = eom_gen(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

/// `eom-gen ARGS` from the workspace root with the test cache of compiled
/// models (`target/eom-cache`, shared by the tests that compile).
fn cached(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .env(
            "EOM_CACHE_DIR",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../target/eom-cache"),
        )
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs")
}

#[test]
fn check_json_has_the_documented_keys() {
    let v = json(&["check", "models/heavy_top.ron", "--json"]);
    for key in [
        "name",
        "bodies",
        "joints",
        "nq",
        "nu",
        "coordinate_names",
        "speed_names",
        "cut_joints",
        "constraints",
        "grubler_dof",
    ] {
        assert!(v.get(key).is_some(), "missing key `{key}` in {v}");
    }
    assert_eq!(v["name"], "heavy_top");
    assert_eq!((v["nq"].as_u64(), v["nu"].as_u64()), (Some(4), Some(3)));
    assert_eq!(
        v["coordinate_names"],
        serde_json::json!(["qw", "qx", "qy", "qz"])
    );
}

#[test]
fn check_reports_cut_joints_of_closed_loops() {
    let v = json(&["check", "models/andrews.ron", "--json"]);
    assert_eq!(v["bodies"], 7);
    assert_eq!(v["cut_joints"], serde_json::json!(["E3", "E4", "E6"]));
    assert_eq!(v["grubler_dof"], 1);
    // Bricard: Grübler–Kutzbach 0, true mobility 1 (one redundant equation).
    let v = json(&["check", "models/bricard.ron", "--json"]);
    assert_eq!(
        (v["grubler_dof"].as_i64(), v["mobility"].as_i64()),
        (Some(0), Some(1)),
        "{v}"
    );
    assert_eq!(
        (
            v["constraint_equations"].as_u64(),
            v["constraint_rank"].as_u64()
        ),
        (Some(5), Some(4))
    );
    let v = json(&["check", "models/fourbar.ron", "--json"]);
    assert_eq!(
        (v["nq"].as_u64(), v["cut_joints"].as_array().map(Vec::len)),
        (Some(3), Some(1))
    );
}

#[test]
fn check_prints_a_summary() {
    let out = eom_gen(&["check", "models/double_pendulum.ron"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("model `double_pendulum`"), "{text}");
    assert!(text.contains("nq = 2: q1, q2"), "{text}");
}

#[test]
fn invalid_model_exits_1_with_located_errors() {
    let dir = std::env::temp_dir().join(format!("eom-cli-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("bad.ron");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/pendulum.ron"
    ))
    .unwrap_or_default()
    .replace("mass: \"m\"", "mass: -2")
    .replace("child: \"bob\"", "child: \"bbo\"");
    let _ = std::fs::write(&path, text);
    let path = path.to_string_lossy().into_owned();
    let out = eom_gen(&["check", &path]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("{path}:18:29: error: mass")), "{err}");
    assert!(err.contains("mass of body `bob` is -2 kg"), "{err}");
    assert!(err.contains("unknown child body `bbo`"), "{err}");
    assert!(err.contains("has 2 error(s)"), "{err}");
    // --json still exits 1 and lists the diagnostics with positions.
    let out = eom_gen(&["check", &path, "--json"]);
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["valid"], false);
    assert_eq!(v["diagnostics"].as_array().map(Vec::len), Some(2));
    assert!(v["diagnostics"][0]["line"].as_u64().is_some());
}

#[test]
fn missing_file_exits_1_and_usage_errors_exit_2() {
    assert_eq!(
        eom_gen(&["check", "models/nope.ron"]).status.code(),
        Some(1)
    );
    assert_eq!(eom_gen(&["check"]).status.code(), Some(2));
    assert_eq!(
        eom_gen(&["check", "models/pendulum.ron", "--bogus"])
            .status
            .code(),
        Some(2)
    );
    assert_eq!(eom_gen(&["frobnicate"]).status.code(), Some(2));
}

#[test]
fn eval_compiled_and_interpreted_agree() {
    // The compiled path builds a cached crate once (release); both paths
    // must give the same numbers at a state away from the initial one.
    let cache = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/eom-cache");
    for (model, q, u) in [
        ("models/double_pendulum.ron", "0.3,-1.2", "0.5,2.0"),
        ("models/heavy_top.ron", "0.8,0.2,-0.4,0.4", "1.0,150,-4.6"),
    ] {
        let mut values = Vec::new();
        for interpret in [true, false] {
            let mut args = vec!["eval", model, "--q", q, "--u", u, "--t", "0.1", "--json"];
            if interpret {
                args.push("--interpret");
            }
            let out = Command::new(env!("CARGO_BIN_EXE_eom-gen"))
                .args(&args)
                .env("EOM_CACHE_DIR", cache)
                .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
                .output()
                .expect("eom-gen runs");
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
            values.push(v);
        }
        for key in [
            "qdot",
            "udot",
            "bias",
            "mass_matrix",
            "kinetic_energy",
            "potential_energy",
        ] {
            let flat = |v: &serde_json::Value| -> Vec<f64> {
                match v {
                    serde_json::Value::Array(a) => a
                        .iter()
                        .flat_map(|x| x.as_array().cloned().unwrap_or_else(|| vec![x.clone()]))
                        .filter_map(|x| x.as_f64())
                        .collect(),
                    x => x.as_f64().into_iter().collect(),
                }
            };
            let (a, b) = (flat(&values[0][key]), flat(&values[1][key]));
            assert_eq!(a.len(), b.len(), "{model} {key}");
            for (x, y) in a.iter().zip(&b) {
                assert!(
                    (x - y).abs() <= 1e-12 * x.abs().max(1.0),
                    "{model} {key}: interpreted {x}, compiled {y}"
                );
            }
        }
        assert_eq!(values[1]["mode"], "compiled");
    }
}

#[test]
fn stats_and_dump_describe_the_generated_code() {
    let out = eom_gen(&["stats", "models/arm7.ron", "--json"]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    for key in ["forward_dynamics", "inverse_dynamics", "mass_matrix"] {
        assert!(
            v["ops"][key]["total"].as_u64().is_some_and(|n| n > 0),
            "{key} in {v}"
        );
    }
    assert!(v["formulation"].as_str().is_some());
    let out = eom_gen(&["dump", "models/pendulum.ron"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("impl ::eom_sim::Model for Pendulum"),
        "{text}"
    );
}

#[test]
fn simulate_runs_the_compiled_model_and_reports_statistics() {
    let cache = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/eom-cache");
    let csv = std::env::temp_dir().join(format!("eom-sim-{}.csv", std::process::id()));
    let csv = csv.to_string_lossy().into_owned();
    let out = Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args([
            "simulate",
            "models/pendulum.ron",
            "--t-end",
            "2",
            "--integrator",
            "dop853",
            "--rtol",
            "1e-10",
            "--csv",
            &csv,
            "--every",
            "0.5",
            "--json",
        ])
        .env("EOM_CACHE_DIR", cache)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["t"], 2.0);
    assert_eq!(v["stop"], "finished");
    for key in [
        "steps",
        "accepted",
        "rejected",
        "rhs_evals",
        "jacobian_evals",
        "lu_decompositions",
    ] {
        assert!(v["stats"][key].as_u64().is_some(), "stats.{key} in {v}");
    }
    assert!(v["cpu_s"].as_f64().is_some_and(|s| s >= 0.0));
    let (e0, e1) = (
        v["energy"][0].as_f64().unwrap_or(f64::NAN),
        v["energy"][1].as_f64().unwrap_or(f64::NAN),
    );
    assert!((e1 - e0).abs() < 1e-8, "energy {e0} → {e1}");
    let text = std::fs::read_to_string(&csv).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    // Coordinates, speeds, then the model's outputs (tip position, hinge
    // reaction, and the energies it requests with `Energy`).
    assert_eq!(
        lines.first().copied(),
        Some(
            "t,theta,theta_dot,bob_tip_x,bob_tip_y,bob_tip_z,hinge_fx,hinge_fy,hinge_fz,hinge_nx,hinge_ny,hinge_nz,kinetic_energy,potential_energy"
        )
    );
    // At t = 0 (horizontal, at rest) the tip is at (1, 0, 0) and the link is slack.
    let first: Vec<f64> = lines[1].split(',').filter_map(|x| x.parse().ok()).collect();
    assert!(
        (first[3] - 1.0).abs() < 1e-12 && first[4].abs() < 1e-12,
        "{}",
        lines[1]
    );
    assert!(first[7].abs() < 1e-12, "tension at release: {}", lines[1]);
    assert_eq!(lines.len(), 1 + 5, "samples at 0, 0.5, …, 2: {text}");
    // Constraint methods: an unknown one, or the index-3 DAE with an
    // explicit integrator, is a usage error (exit 2) that says what works.
    for (method, integrator, says) in [
        ("lagrange", "dopri5", "partitioning"),
        ("index3", "dopri5", "radau5"),
    ] {
        let out = eom_gen(&[
            "simulate",
            "models/fourbar.ron",
            "--t-end",
            "1",
            "--constraints",
            method,
            "--integrator",
            integrator,
        ]);
        assert_eq!(out.status.code(), Some(2), "{method}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(says),
            "{method}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert_eq!(
        eom_gen(&[
            "simulate",
            "models/pendulum.ron",
            "--t-end",
            "1",
            "--integrator",
            "leapfrog"
        ])
        .status
        .code(),
        Some(2)
    );
}

#[test]
fn simulate_interpreted_and_compiled_agree() {
    // Same programs, same integrator: the same steps and the same state.
    let cache = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/eom-cache");
    let mut runs = Vec::new();
    for interpret in [true, false] {
        let mut args = vec![
            "simulate",
            "models/heavy_top.ron",
            "--t-end",
            "0.5",
            "--integrator",
            "dop853",
            "--rtol",
            "1e-10",
            "--json",
        ];
        if interpret {
            args.push("--interpret");
        }
        let out = Command::new(env!("CARGO_BIN_EXE_eom-gen"))
            .args(&args)
            .env("EOM_CACHE_DIR", cache)
            .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
            .output()
            .expect("eom-gen runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        runs.push(serde_json::from_slice::<serde_json::Value>(&out.stdout).expect("JSON"));
    }
    assert_eq!(runs[0]["stats"]["steps"], runs[1]["stats"]["steps"]);
    for key in ["q", "u"] {
        let (a, b) = (
            runs[0][key].as_array().cloned().unwrap_or_default(),
            runs[1][key].as_array().cloned().unwrap_or_default(),
        );
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            let (x, y) = (
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
            );
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(1.0),
                "{key}: interpreted {x}, compiled {y}"
            );
        }
    }
}

/// `--batch --derivatives` times the batched derivatives beside the
/// batched forward dynamics, per state at each of their pack widths.
#[test]
fn bench_batch_with_derivatives_reports_batched_derivatives() {
    let out = cached(&[
        "bench",
        "models/pendulum.ron",
        "--per-call",
        "--derivatives",
        "--batch",
        "--states",
        "16",
        "--reps",
        "3",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let positive = |x: &serde_json::Value| x.as_f64().is_some_and(|x| x.is_finite() && x > 0.0);
    for key in [
        "forward_dynamics_derivatives_ns",
        "batched_forward_dynamics_ns",
        "batched_forward_dynamics_derivatives_ns",
    ] {
        assert!(positive(&v[key]), "{key} in {v}");
    }
    let by_width = &v["batched_forward_dynamics_derivatives_ns_by_width"];
    assert!(positive(&by_width["4"]) && positive(&by_width["8"]), "{v}");
    let w = v["batched_derivatives_width"].to_string();
    assert!(
        by_width[w.as_str()] == v["batched_forward_dynamics_derivatives_ns"],
        "the reported width is the fastest: {v}"
    );
    let s = &v["spread"]["batched_forward_dynamics_derivatives"];
    assert!(
        s["min"].as_f64() <= s["max"].as_f64() && positive(&s["min"]),
        "{v}"
    );
}

#[test]
fn bench_per_call_reports_positive_times_and_op_counts() {
    let run = cached;
    let out = run(&[
        "bench",
        "models/pendulum.ron",
        "--per-call",
        "--states",
        "16",
        "--reps",
        "3",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["model"], "pendulum");
    assert_eq!(v["fd_form"], "Aba", "{v}");
    assert_eq!(
        (v["states"].as_u64(), v["reps"].as_u64()),
        (Some(16), Some(3))
    );
    for f in ["forward_dynamics", "mass_matrix", "inverse_dynamics"] {
        let ns = v[format!("{f}_ns")].as_f64();
        assert!(
            ns.is_some_and(|x| x.is_finite() && x > 0.0),
            "{f}_ns in {v}"
        );
        assert!(v["ops"][f].as_u64().is_some(), "ops.{f} in {v}");
        let s = &v["spread"][f];
        let get = |k: &str| s[k].as_f64().unwrap_or(f64::NAN);
        assert!(
            get("min") <= get("q1") && get("q1") <= get("q3") && get("q3") <= get("max"),
            "spread of {f} in {v}"
        );
    }
    // The pendulum's forward dynamics is `τ − 9.81 sin θ`: 3 operations.
    assert_eq!(v["ops"]["forward_dynamics"], 3, "{v}");
    // Invalid models give the usual diagnostics and exit 1; usage errors 2.
    let out = run(&["bench", "models/nope.ron", "--per-call", "--json"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope.ron"));
    assert_eq!(
        run(&["bench", "models/pendulum.ron"]).status.code(),
        Some(2)
    );
    assert_eq!(
        run(&["bench", "models/pendulum.ron", "--per-call", "--reps", "0"])
            .status
            .code(),
        Some(2)
    );
}

#[test]
fn scenes_are_accepted_wherever_a_model_is() {
    let v = json(&["check", "models/scenes/arm7_ee.scene.ron", "--json"]);
    assert_eq!(v["name"], "arm7_ee");
    assert_eq!(v["nq"], 5);
    assert_eq!(v["locked_joints"], serde_json::json!(["j5", "j7"]));
    assert_eq!(v["scene"]["model"], "models/arm7.ron");
    let full = json(&["stats", "models/scenes/arm7_full.scene.ron", "--json"]);
    let ee = json(&["stats", "models/scenes/arm7_ee.scene.ron", "--json"]);
    for f in ["forward_dynamics", "outputs"] {
        let (a, b) = (&full["ops"][f]["total"], &ee["ops"][f]["total"]);
        assert!(
            b.as_u64() < a.as_u64(),
            "{f}: got {b} ops in arm7_ee, want fewer than arm7_full's {a}"
        );
    }
    assert_eq!(ee["output_names"].as_array().map(Vec::len), Some(3));
}

#[test]
fn stats_print_null_for_functions_a_scene_leaves_out() {
    let v = json(&["stats", "models/scenes/arm7_dynamics.scene.ron", "--json"]);
    for f in ["mass_matrix", "bias", "outputs"] {
        assert!(v["ops"][f].is_null(), "{f}: got {}, want null", v["ops"][f]);
    }
    for f in ["forward_dynamics", "inverse_dynamics", "energy", "momentum"] {
        assert!(
            v["ops"][f]["total"].as_u64().is_some_and(|n| n > 0),
            "{f}: got {}, want an operation count",
            v["ops"][f]
        );
    }
    let c = json(&["check", "models/scenes/arm7_dynamics.scene.ron", "--json"]);
    assert_eq!(
        c["scene"]["functions"],
        serde_json::json!([
            "qdot",
            "forward_dynamics",
            "inverse_dynamics",
            "energy",
            "momentum"
        ])
    );
}

#[test]
fn a_bad_scene_exits_1_with_its_location() {
    let dir = std::env::temp_dir().join(format!("eom-cli-scene-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let models = concat!(env!("CARGO_MANIFEST_DIR"), "/../models");
    let scene = dir.join("bad.scene.ron");
    let text =
        format!("Scene(\n    model: \"{models}/arm7.ron\",\n    lock: [(joint: \"j8\")],\n)\n");
    std::fs::write(&scene, text).expect("write");
    let path = scene.display().to_string();
    let out = eom_gen(&["check", &path]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(&format!("{path}:3:20: error: unknown joint `j8`")),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bench_work_precision_sweeps_and_writes_csv_and_svg() {
    // The pendulum to t = 2 s: RK4's error falls 16-fold per halved step
    // (order 4), DOP853's with the tolerance, and the reference (DOP853 at
    // 1e-13) agrees with its check (DOPRI5 at 1e-13) far below every point.
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/wp-test");
    // Output files go into an existing directory (eom-gen creates none).
    std::fs::create_dir_all(dir).expect("test directory");
    let (csv, svg) = (format!("{dir}/pendulum.csv"), format!("{dir}/pendulum.svg"));
    let run = cached;
    let out = run(&[
        "bench",
        "models/pendulum.ron",
        "--work-precision",
        "--t-end",
        "2",
        "--integrators",
        "rk4,dop853",
        "--tols",
        "1e-5,1e-8,1e-11",
        "--steps",
        "50,400",
        "--min-time",
        "0",
        "--csv",
        &csv,
        "--svg",
        &svg,
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["model"], "pendulum");
    assert_eq!(v["constrained"], false);
    let check = v["reference"]["check_end_error"].as_f64().unwrap_or(1.0);
    assert!(
        check < 1e-11,
        "reference check: got {check:e}, want < 1e-11"
    );
    let points = v["points"].as_array().cloned().unwrap_or_default();
    // rk4 at 50, 100, 200, 400 steps; dop853 at three tolerances.
    assert_eq!(points.len(), 7, "{v}");
    let err = |p: &serde_json::Value| p["end_error"].as_f64().unwrap_or(f64::NAN);
    for w in points[..4].windows(2) {
        let ratio = err(&w[0]) / err(&w[1]);
        assert!(
            (10.0..25.0).contains(&ratio),
            "RK4 error ratio per halved step: got {ratio}, want ≈ 16 (order 4): {v}"
        );
    }
    for w in points[4..].windows(2) {
        assert!(
            err(&w[1]) < err(&w[0]) * 0.1,
            "DOP853 errors must fall: {v}"
        );
    }
    for p in &points {
        assert_eq!(p["stop"], "finished");
        assert!(p["cpu_s"].as_f64().is_some_and(|t| t > 0.0), "{p}");
        assert!(err(p) > check, "every point above the reference floor: {p}");
        let digits = p["digits"].as_f64().unwrap_or(f64::NAN);
        assert!((digits + err(p).log10()).abs() < 1e-9, "{p}");
    }
    let csv = std::fs::read_to_string(&csv).expect("CSV written");
    assert_eq!(csv.lines().count(), 8, "header + 7 points:\n{csv}");
    assert!(csv.starts_with("model,integrator,constraints,setting_kind,setting,cpu_ms"));
    let svg = std::fs::read_to_string(&svg).expect("SVG written");
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    for label in [
        "rk4",
        "dop853",
        "error at the end time",
        "largest error along the path",
    ] {
        assert!(svg.contains(label), "SVG lacks `{label}`");
    }
    // The CSV plots again (`--plot`), with a label of our choosing; a file
    // without the needed columns is an error naming them.
    let replot = format!("{dir}/replot.svg");
    let out = run(&[
        "bench",
        "--plot",
        &format!("{dir}/pendulum.csv"),
        "--svg",
        &replot,
        "--error-label",
        "my error",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(&replot).expect("re-plotted SVG");
    assert!(svg.contains("my error") && svg.contains("dop853") && svg.contains("rk4"));
    let bad = format!("{dir}/bad.csv");
    std::fs::write(&bad, "model,integrator,setting\npendulum,rk4,0.1\n").expect("write");
    let out = run(&["bench", "--plot", &bad, "--svg", &replot]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("setting_kind") && err.contains("end_error"),
        "{err}"
    );
    // Usage errors exit 2, with every problem named.
    let out = run(&[
        "bench",
        "models/pendulum.ron",
        "--work-precision",
        "--integrators",
        "rk5,dop853",
        "--t-end",
        "-1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("`rk5`") && err.contains("--t-end"), "{err}");
    assert_eq!(
        run(&["bench", "models/pendulum.ron", "--suite"])
            .status
            .code(),
        Some(2)
    );
}

#[test]
fn bench_work_precision_sweeps_constraint_solvers_of_a_loop() {
    // The four-bar to 0.5 s (before its singular position): projection and
    // partitioning keep the same constraint manifold, so at one tolerance
    // their errors agree in magnitude, and both fall with the tolerance.
    let out = cached(&[
        "bench",
        "models/fourbar.ron",
        "--work-precision",
        "--t-end",
        "0.5",
        "--integrators",
        "dop853",
        "--constraints",
        "projection,partitioning",
        "--tols",
        "1e-6,1e-10",
        "--min-time",
        "0",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(v["constrained"], true);
    assert_eq!(v["reference"]["constraints"], "projection");
    let points = v["points"].as_array().cloned().unwrap_or_default();
    let solvers: Vec<&str> = points
        .iter()
        .filter_map(|p| p["constraints"].as_str())
        .collect();
    assert_eq!(
        solvers,
        ["projection", "projection", "partitioning", "partitioning"]
    );
    let err = |k: usize| points[k]["end_error"].as_f64().unwrap_or(f64::NAN);
    assert!(err(1) < err(0) * 1e-2 && err(3) < err(2) * 1e-2, "{v}");
    for k in [0, 1] {
        let ratio = err(k) / err(k + 2);
        assert!(
            (0.1..10.0).contains(&ratio),
            "projection vs partitioning at one tolerance: {} vs {}",
            err(k),
            err(k + 2)
        );
    }
}

#[test]
fn bench_suite_writes_a_csv_and_svg_per_model_and_a_summary() {
    // A models directory with the pendulum and a broken model: the
    // pendulum's results are written, the broken one is named and the
    // suite exits 1.
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/wp-suite-test");
    let (models, out) = (format!("{root}/models"), format!("{root}/out"));
    let _ = std::fs::remove_dir_all(root);
    std::fs::create_dir_all(&models).expect("temp dir");
    let pendulum = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/pendulum.ron");
    std::fs::copy(pendulum, format!("{models}/pendulum.ron")).expect("copy");
    std::fs::write(format!("{models}/broken.ron"), "Model(name: \"broken\"").expect("write");
    let out_run = cached(&[
        "bench",
        "--suite",
        "--models",
        &models,
        "--out",
        &out,
        "--t-end",
        "1",
        "--tols",
        "1e-6,1e-9",
        "--steps",
        "100,200",
        "--min-time",
        "0",
    ]);
    let stderr = String::from_utf8_lossy(&out_run.stderr);
    assert_eq!(out_run.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("broken.ron"), "{stderr}");
    let csv = std::fs::read_to_string(format!("{out}/pendulum.csv")).expect("pendulum.csv");
    // rk4 at two steps, dopri5, dop853 and radau5 at two tolerances each.
    assert_eq!(csv.lines().count(), 1 + 8, "{csv}");
    let svg = std::fs::read_to_string(format!("{out}/pendulum.svg")).expect("pendulum.svg");
    assert!(svg.contains("radau5"));
    let md = std::fs::read_to_string(format!("{out}/suite.md")).expect("suite.md");
    assert!(
        md.contains("## pendulum") && md.contains("![pendulum](pendulum.svg)"),
        "{md}"
    );
    // The summary: one row per method, the cheapest run to 1e-6 found.
    for method in ["rk4", "dopri5", "dop853", "radau5"] {
        let row = md
            .lines()
            .find(|l| l.starts_with(&format!("| pendulum | 1 s | {method} |")))
            .unwrap_or_else(|| panic!("no summary row for {method}:\n{md}"));
        assert!(row.contains(" rhs)"), "{row}");
    }
}

#[test]
fn simulate_says_when_a_loop_passed_near_a_singular_configuration() {
    // The four-bar passes its collinear change points (J loses rank there)
    // within 2 s; the slider-crank's dead centres leave J regular. The
    // smallest σ₂/σ₁ of J at the accepted steps shows it (how near depends
    // on where the steps fall: 4e-3 to 6e-2 for the four-bar at 1e-8 to
    // 1e-11, 0.36 for the slider-crank), and the summary adds a note when it
    // fell below 1e-2.
    let run = |model: &str, json: bool| {
        let mut args = vec![
            "simulate",
            model,
            "--t-end",
            "2",
            "--integrator",
            "dop853",
            "--rtol",
            "1e-10",
            "--atol",
            "1e-10",
        ];
        if json {
            args.push("--json");
        }
        let out = cached(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    for (model, near) in [
        ("models/fourbar.ron", true),
        ("models/slider_crank.ron", false),
    ] {
        let v: serde_json::Value = serde_json::from_str(&run(model, true)).expect("JSON");
        let ratio = v["min_singular_ratio"].as_f64().unwrap_or(f64::NAN);
        assert_eq!(v["stats"]["min_singular_ratio"], v["min_singular_ratio"]);
        if near {
            assert!(ratio < 0.1, "{model}: smallest σ₂/σ₁ {ratio:e}, want < 0.1");
        } else {
            assert!(ratio > 0.1, "{model}: smallest σ₂/σ₁ {ratio:e}, want > 0.1");
        }
        let text = run(model, false);
        assert!(text.contains("smallest σ_r/σ_1 of J"), "{text}");
        assert_eq!(
            text.contains("singular configuration"),
            ratio < 1e-2,
            "{model}: the note goes with a ratio below 1e-2 ({ratio:e}):\n{text}"
        );
    }
}

/// A fresh path in the temporary directory, unique to this test process.
fn temp_path(name: &str) -> String {
    std::env::temp_dir()
        .join(format!("eom-cli-{}-{name}", std::process::id()))
        .to_string_lossy()
        .into_owned()
}

/// The `t` column of a CSV written by `simulate --csv`.
fn csv_times(path: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    text.lines()
        .skip(1)
        .filter_map(|l| l.split(',').next()?.parse().ok())
        .collect()
}

#[test]
fn simulate_rejects_bad_numbers_up_front_with_exit_2() {
    // Each is a usage error (exit 2) whose message names the option, and
    // nothing runs: no model is compiled (the model path does not exist).
    for (args, says) in [
        (&["--rtol=-1"][..], "--rtol"),
        (&["--atol=-1e-3"], "--atol"),
        (&["--rtol", "nan"], "--rtol"),
        (&["--dt=-0.1", "--integrator", "rk4"], "--dt"),
        (&["--dt=-0.1"], "--dt"),
        (&["--dt", "0", "--integrator", "rk4"], "--dt"),
        (&["--every", "0"], "--every"),
        (&["--every", "-1"], "--every"),
        (&["--rtol", "0", "--atol", "0"], "cannot both be zero"),
        (&["--max-steps", "0"], "--max-steps"),
        (&["--t-end", "0"], "--t-end"),
        (&["--q0", "1,x"], "--q0"),
        (&["--u0", "nan"], "--u0"),
    ] {
        let mut all = vec!["simulate", "models/pendulum.ron", "--t-end", "1"];
        all.extend_from_slice(args);
        let out = eom_gen(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?} should name `{says}`: {err}");
    }
    // Several problems are reported together.
    let out = eom_gen(&[
        "simulate",
        "models/pendulum.ron",
        "--t-end",
        "1",
        "--rtol=-1",
        "--every",
        "0",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(err.contains("--rtol") && err.contains("--every"), "{err}");
}

/// An option the run would not read is a usage error (exit 2) that
/// names it and what it applies to, never silently ignored: a step size
/// for an adaptive integrator, tolerances for a fixed-step one, a CSV
/// interval with nothing recorded (rigid and cable models alike). Nothing
/// runs: each is refused before anything is built.
#[test]
fn simulate_refuses_options_its_integrator_does_not_read() {
    for (model, args, says) in [
        (
            "models/pendulum.ron",
            &["--dt", "1e-3"][..],
            "dopri5 chooses its own steps",
        ),
        (
            "models/pendulum.ron",
            &["--integrator", "dop853", "--dt", "1e-3"],
            "--dt sets the step of the fixed-step integrators (euler, rk4, midpoint)",
        ),
        (
            "models/pendulum.ron",
            &["--integrator", "rk4", "--rtol", "1e-6"],
            "rk4 takes fixed steps of --dt",
        ),
        (
            "models/pendulum.ron",
            &["--integrator", "euler", "--atol", "1e-9"],
            "--rtol and --atol control the steps of the adaptive integrators (dopri5",
        ),
        (
            "models/pendulum.ron",
            &["--every", "0.1"],
            "nothing is recorded without --csv, --html or --plot",
        ),
        (
            "models/ancf/pendulum.ron",
            &["--every", "0.1"],
            "nothing is recorded without --csv, --html or --plot",
        ),
    ] {
        let mut all = vec!["simulate", model, "--t-end", "0.01"];
        all.extend_from_slice(args);
        let out = eom_gen(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?} should say `{says}`: {err}");
    }
    // `sweep` runs the same integrators by the same rule.
    let out = eom_gen(&[
        "sweep",
        "models/pendulum.ron",
        "--param",
        "l=1,2",
        "--t-end",
        "0.01",
        "--dt",
        "1e-3",
        "--out",
        "/nonexistent/never",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "sweep --dt: {err}");
    assert!(err.contains("dopri5 chooses its own steps"), "{err}");
    // What applies runs: a fixed step for rk4, tolerances for dopri5.
    for args in [
        &["--integrator", "rk4", "--dt", "1e-3"][..],
        &["--rtol", "1e-6", "--atol", "1e-9"],
    ] {
        let mut all = vec![
            "simulate",
            "models/pendulum.ron",
            "--t-end",
            "0.01",
            "--interpret",
        ];
        all.extend_from_slice(args);
        let out = eom_gen(&all);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn simulate_csv_always_ends_with_the_final_state() {
    let csv = temp_path("final.csv");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "simulate",
            "models/pendulum.ron",
            "--t-end",
            "1",
            "--interpret",
            "--csv",
            &csv,
        ];
        args.extend_from_slice(extra);
        let out = eom_gen(&args);
        assert!(
            out.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        csv_times(&csv)
    };
    // An interval longer than the run: the start and the end.
    assert_eq!(run(&["--every", "5"]), vec![0.0, 1.0]);
    // An interval that does not divide the run: …, 0.9, then t = 1 itself.
    let t = run(&["--every", "0.3"]);
    assert_eq!(t.len(), 5, "{t:?}");
    assert!((t[3] - 0.9).abs() < 1e-12, "{t:?}");
    assert_eq!(t.last().copied(), Some(1.0), "{t:?}");
    // Every step: the last one is the end time.
    let t = run(&[]);
    assert!(t.len() > 3 && t[0] == 0.0, "{t:?}");
    assert_eq!(t.last().copied(), Some(1.0), "{t:?}");
    let _ = std::fs::remove_file(&csv);
}

#[test]
fn a_run_that_stops_early_exits_3_with_a_structured_stop() {
    let csv = temp_path("stopped.csv");
    let args = |interpret: bool| {
        let mut a = vec![
            "simulate",
            "models/double_pendulum.ron",
            "--t-end",
            "10",
            "--max-steps",
            "10",
            "--json",
            "--csv",
            csv.as_str(),
        ];
        if interpret {
            a.push("--interpret");
        }
        a
    };
    for interpret in [true, false] {
        let out = cached(&args(interpret));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "interpret {interpret}: {err}");
        assert!(err.contains("stopped before t = 10"), "{err}");
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        let stop = &v["stop"];
        assert_eq!(stop["reason"], "max_steps", "{v}");
        let t = stop["t"].as_f64().unwrap_or(f64::NAN);
        assert!(t > 0.0 && t < 10.0, "{stop}");
        assert!(
            stop["message"]
                .as_str()
                .is_some_and(|m| m.contains("--max-steps"))
        );
        assert_eq!(v["t"].as_f64(), Some(t));
        assert_eq!(v["stats"]["steps"], 10);
        // The CSV ends where the run stopped.
        assert_eq!(csv_times(&csv).last().copied(), Some(t));
    }
    // The summary (no --json) says the same.
    let out = eom_gen(&[
        "simulate",
        "models/pendulum.ron",
        "--t-end",
        "10",
        "--max-steps",
        "5",
        "--interpret",
    ]);
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stdout).contains("step limit"));
    let _ = std::fs::remove_file(&csv);
}

#[test]
fn simulate_starts_from_q0_and_u0() {
    let run = |extra: &[&str]| {
        let mut args = vec![
            "simulate",
            "models/pendulum.ron",
            "--t-end",
            "0.001",
            "--interpret",
            "--json",
        ];
        args.extend_from_slice(extra);
        json(&args)
    };
    // At the bottom at rest it stays there; pushed, it moves.
    let v = run(&["--q0", "0", "--u0", "0"]);
    assert!(v["q"][0].as_f64().is_some_and(|q| q.abs() < 1e-15), "{v}");
    let v = run(&["--q0", "0", "--u0", "1"]);
    let q = v["q"][0].as_f64().unwrap_or(f64::NAN);
    assert!((q - 0.001).abs() < 1e-6, "{v}");
    // The wrong number of values is a usage error naming the counts.
    let out = eom_gen(&[
        "simulate",
        "models/pendulum.ron",
        "--t-end",
        "1",
        "--interpret",
        "--q0",
        "1,2",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(0), "{err}");
    assert!(err.contains("--q0 has 2 value(s)"), "{err}");
}

#[test]
fn eval_rejects_non_finite_numbers() {
    for args in [
        &["--q", "1,nan"][..],
        &["--u", "inf,0"],
        &["--tau", "0,NaN"],
        &["--q", "1"],
    ] {
        let mut all = vec!["eval", "models/double_pendulum.ron", "--interpret"];
        all.extend_from_slice(args);
        let out = eom_gen(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(args[0]), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

#[test]
fn unknown_fields_are_all_reported_at_once() {
    let path = temp_path("typos.ron");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/pendulum.ron"
    ))
    .unwrap_or_default()
    .replacen("com:", "cmo:", 1)
    .replacen("axis:", "axsi:", 1);
    let _ = std::fs::write(&path, text);
    let out = eom_gen(&["check", &path]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("`cmo`") && err.contains("`axsi`"), "{err}");
    assert!(err.contains("has 2 error(s)"), "{err}");
    assert!(err.contains("did you mean"), "{err}");
    let _ = std::fs::remove_file(&path);
}

#[test]
fn output_paths_are_never_created_silently_and_errors_name_them() {
    let dir = temp_path("no-such-dir");
    let file = format!("{dir}/x.rs");
    for args in [
        vec!["dump", "models/pendulum.ron", "-o", file.as_str()],
        vec![
            "import",
            "eom-gen/tests/urdf/arm2.urdf",
            "-o",
            file.as_str(),
        ],
    ] {
        let out = eom_gen(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains(&format!("cannot write `{file}`")) && err.contains("does not exist"),
            "{args:?}: {err}"
        );
        assert!(!std::path::Path::new(&dir).exists(), "{dir} was created");
    }
    // Into a directory that exists, it writes.
    let ok = temp_path("dump.rs");
    let out = eom_gen(&["dump", "models/pendulum.ron", "-o", &ok]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::read_to_string(&ok).is_ok_and(|t| t.contains("impl ::eom_sim::Model")));
    let _ = std::fs::remove_file(&ok);
}

#[test]
fn a_binary_file_is_named_not_echoed() {
    let path = temp_path("binary.ron");
    let mut bytes = b"Model(\x00\x01\x02\x1b[31m".to_vec();
    bytes.extend([0xff, 0xfe, 0x00, 0x7f, 0x1b, b'c']);
    let _ = std::fs::write(&path, &bytes);
    let out = eom_gen(&["check", &path]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&path) && err.contains("not a text file"),
        "{err}"
    );
    assert!(
        !out.stderr.iter().any(|b| *b == 0x1b || *b == 0),
        "raw bytes reached the terminal: {err:?}"
    );
    // A text file with one stray byte is shown where it is.
    let _ = std::fs::write(&path, b"Model(name: \"p\xe9\")\n");
    let err = String::from_utf8_lossy(&eom_gen(&["check", &path]).stderr).into_owned();
    assert!(
        err.contains(&format!("{path}:1:15")) && err.contains("not valid UTF-8"),
        "{err}"
    );
    let _ = std::fs::remove_file(&path);
}

#[test]
fn stats_prints_a_table_without_json() {
    let out = eom_gen(&["stats", "models/pendulum.ron"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.trim_start().starts_with('{'), "{text}");
    assert!(
        text.contains("function") && text.contains("total"),
        "{text}"
    );
    assert!(
        text.contains("forward_dynamics") && text.contains("mass_matrix"),
        "{text}"
    );
}

#[test]
fn requested_energy_and_momentum_are_in_the_csv() {
    let csv = temp_path("energy.csv");
    for (model, has_momentum) in [
        ("models/pendulum.ron", false),
        ("models/heavy_top.ron", true),
    ] {
        let out = eom_gen(&[
            "simulate",
            model,
            "--t-end",
            "0.5",
            "--interpret",
            "--csv",
            &csv,
            "--every",
            "0.1",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(&csv).unwrap_or_default();
        let header: Vec<&str> = text.lines().next().unwrap_or("").split(',').collect();
        let col = |name: &str| header.iter().position(|h| *h == name);
        let (Some(k), Some(p)) = (col("kinetic_energy"), col("potential_energy")) else {
            panic!("{model}: no energy columns in {header:?}");
        };
        assert_eq!(
            col("linear_momentum_z").is_some(),
            has_momentum,
            "{header:?}"
        );
        // Conserved: the total is the same on every row.
        let totals: Vec<f64> = text
            .lines()
            .skip(1)
            .map(|l| {
                let v: Vec<f64> = l.split(',').filter_map(|x| x.parse().ok()).collect();
                v[k] + v[p]
            })
            .collect();
        assert_eq!(totals.len(), 6, "{text}");
        for e in &totals {
            assert!(
                (e - totals[0]).abs() < 1e-6 * totals[0].abs().max(1.0),
                "{model}: {totals:?}"
            );
        }
    }
    // A model without `Energy` among its outputs has no such columns.
    let plain = temp_path("plain.ron");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/pendulum.ron"
    ))
    .unwrap_or_default()
    .replace(", Energy]", "]");
    let _ = std::fs::write(&plain, text);
    let out = eom_gen(&[
        "simulate",
        &plain,
        "--t-end",
        "0.1",
        "--interpret",
        "--csv",
        &csv,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap_or_default();
    let header = text.lines().next().unwrap_or("");
    assert!(header.ends_with("hinge_nz"), "{header}");
    let _ = std::fs::remove_file(&plain);
    let _ = std::fs::remove_file(&csv);
}

/// The pendulum with an actuator `motor` at the hinge and `l` tunable.
fn actuated_pendulum(file: &str) -> String {
    let path = temp_path(file);
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/pendulum.ron"
    ))
    .unwrap_or_default()
    .replace(
        "(name: \"l\", value: 1.0,",
        "(name: \"l\", value: 1.0, tunable: true,",
    )
    .replace(
        "    outputs:",
        "    forces: [Actuator(name: \"motor\", joint: \"hinge\")],\n    outputs:",
    );
    let _ = std::fs::write(&path, text);
    path
}

/// `udot` of `eval` with `args`.
fn udot(args: &[&str]) -> f64 {
    let v = json(args);
    v["udot"][0].as_f64().unwrap_or(f64::NAN)
}

#[test]
fn params_and_inputs_are_set_from_the_command_line() {
    let model = actuated_pendulum("actuated.ron");
    let eval = |extra: &[&str]| {
        let mut args = vec!["eval", model.as_str(), "--interpret"];
        args.extend_from_slice(extra);
        udot(&args)
    };
    // Horizontal at rest: u̇ = (τ − m g l)/(m l²).
    assert!((eval(&[]) + 9.81).abs() < 1e-12);
    // A fixed parameter (regenerated) and a tunable one.
    assert!((eval(&["--param", "g=1.5"]) + 1.5).abs() < 1e-12);
    assert!((eval(&["--param", "l=2"]) + 9.81 / 2.0).abs() < 1e-12);
    assert!((eval(&["--param", "l=2", "--param", "g=4"]) + 2.0).abs() < 1e-12);
    // The input: a torque at the hinge.
    assert!((eval(&["--input", "motor=2"]) + 7.81).abs() < 1e-12);
    assert!((eval(&["--input", "motor=9.81"])).abs() < 1e-12);
    // A simulation held by the motor stays where it is.
    for interpret in [true, false] {
        let mut args = vec![
            "simulate",
            model.as_str(),
            "--t-end",
            "1",
            "--input",
            "motor=4.905",
            "--param",
            "m=0.5",
            "--json",
        ];
        if interpret {
            args.push("--interpret");
        }
        let out = cached(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        let q = v["q"][0].as_f64().unwrap_or(f64::NAN);
        assert!(
            (q - std::f64::consts::FRAC_PI_2).abs() < 1e-9,
            "interpret {interpret}: {v}"
        );
    }
    // Compiled eval agrees.
    let out = cached(&["eval", &model, "--input", "motor=2", "--param", "l=2"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let a = v["udot"][0].as_f64().unwrap_or(f64::NAN);
    assert!((a - (2.0 - 9.81 * 2.0) / 4.0).abs() < 1e-12, "{v}");
    // Unknown names and malformed values are usage errors.
    for (args, says) in [
        (&["--param", "G=1"][..], "did you mean `g`"),
        (&["--param", "length=1"], "has no parameter `length`"),
        (&["--input", "motr=1"], "did you mean `motor`"),
        (&["--param", "g"], "NAME=VALUE"),
        (&["--param", "g=nan"], "NAME=VALUE"),
        (
            &["--input", "motor=x"],
            "unknown name `x` in the expression for input `motor`",
        ),
        (
            &["--input", "motor=2*"],
            "in expression `2*` for input `motor`",
        ),
        (
            &["--input", "motor=1", "--input", "motor=t"],
            "a value and an expression",
        ),
    ] {
        let mut all = vec!["eval", model.as_str(), "--interpret"];
        all.extend_from_slice(args);
        let out = eom_gen(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    let out = eom_gen(&[
        "simulate",
        "models/pendulum.ron",
        "--t-end",
        "1",
        "--input",
        "u=1",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("has none"), "{err}");
    let _ = std::fs::remove_file(&model);
}

#[test]
fn an_input_driven_by_an_expression_of_time_and_state() {
    // `--input motor=EXPR` replaces the runtime input by a known torque:
    // here one that cancels gravity, m g l sin θ, plus 6 m l² t, so that
    // θ̈ = 6 t and θ(t) = π/2 + t³ from rest at θ = π/2 (a cubic, which
    // DOPRI5 integrates exactly). Compiled and interpreted.
    let model = actuated_pendulum("driven.ron");
    let law = "motor=g*m*l*sin(theta) + 6*m*l*l*t";
    for interpret in [true, false] {
        let mut args = vec![
            "simulate",
            model.as_str(),
            "--t-end",
            "1",
            "--input",
            law,
            "--param",
            "m=2",
            "--json",
        ];
        if interpret {
            args.push("--interpret");
        }
        let out = cached(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        let q = v["q"][0].as_f64().unwrap_or(f64::NAN);
        assert!(
            (q - std::f64::consts::FRAC_PI_2 - 1.0).abs() < 1e-9,
            "interpret {interpret}: {v}"
        );
    }
    let _ = std::fs::remove_file(&model);
}

#[test]
fn bench_takes_the_initial_state_and_driven_inputs() {
    // The work-precision reference starts where --q0/--u0 say: the
    // pendulum hanging at rest is an equilibrium (θ stays 0), and with the
    // motor cancelling gravity (--input motor=m g l sin θ) it turns at its
    // initial rate, θ(t) = π/2 + u0 t.
    let model = actuated_pendulum("bench_driven.ron");
    let sweep = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "bench",
            model.as_str(),
            "--work-precision",
            "--t-end",
            "0.5",
            "--integrators",
            "dop853",
            "--tols",
            "1e-8",
            "--min-time",
            "0",
            "--json",
        ];
        args.extend_from_slice(extra);
        let out = cached(&args);
        assert!(
            out.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).expect("JSON")
    };
    let q_final = |v: &serde_json::Value| v["reference"]["q_final"][0].as_f64().unwrap_or(f64::NAN);
    let v = sweep(&["--q0", "0", "--u0", "0"]);
    assert_eq!(q_final(&v), 0.0, "{v}");
    let v = sweep(&["--u0", "1", "--input", "motor=g*m*l*sin(theta)"]);
    assert!(
        (q_final(&v) - std::f64::consts::FRAC_PI_2 - 0.5).abs() < 1e-10,
        "{v}"
    );
    // --q0 with --per-call, and a wrong number of values, are refused.
    let out = eom_gen(&["bench", &model, "--per-call", "--q0", "0"]);
    assert_eq!(out.status.code(), Some(2));
    let out = cached(&["bench", &model, "--work-precision", "--q0", "0,1"]);
    assert_ne!(out.status.code(), Some(0));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("q0 has 2 value(s); the model has 1"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_file(&model);
}

#[test]
fn check_counts_the_elastic_coordinates_of_flexible_bodies() {
    // hub_beam: a hub on a revolute joint and a beam clamped to it with 4
    // modes. The rigid count is 1 (planar: 3·2 − 2 − 3); every elastic
    // coordinate is a freedom of its own, so Grübler–Kutzbach says 1 + 4 = 5
    // = nu (a tree: no constraint removes any).
    let v = json(&["check", "models/hub_beam.ron", "--json"]);
    assert_eq!(
        (
            v["grubler_dof"].as_i64(),
            v["grubler_elastic"].as_i64(),
            v["nu"].as_i64()
        ),
        (Some(5), Some(4), Some(5)),
        "{v}"
    );
    let out = eom_gen(&["check", "models/hub_beam.ron"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(
            "5 degree(s) of freedom (1 of the rigid bodies and joints + 4 elastic coordinates of flexible bodies)"
        ),
        "{text}"
    );
}

/// The README's first command prints what the README shows (all but the
/// CPU time), and says on standard error what it builds the first time
/// and that it is cached; a second run builds nothing and says nothing.
#[test]
fn the_readme_quick_start_is_what_a_user_sees() {
    let readme = include_str!("../../README.md");
    let command = "cargo run -p eom-cli -- simulate models/double_pendulum.ron --t-end 10";
    assert!(
        readme.contains(command),
        "the README's first command changed"
    );
    let shown: Vec<&str> = readme
        .split("```text\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("the README shows the output in a text block")
        .lines()
        .collect();
    let args = ["simulate", "models/double_pendulum.ron", "--t-end", "10"];
    let first = cached(&args);
    let err = String::from_utf8_lossy(&first.stderr);
    assert!(first.status.success(), "{err}");
    if err.contains("building the generated code") {
        assert!(
            err.contains("built `double_pendulum` in") && err.contains("; cached"),
            "{err}"
        );
    }
    let again = cached(&args);
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(again.status.success(), "{err}");
    assert!(
        !err.contains("building"),
        "a cached model was built again: {err}"
    );
    let out = String::from_utf8_lossy(&again.stdout);
    let printed: Vec<&str> = out.lines().collect();
    assert_eq!(
        printed.len(),
        shown.len(),
        "README:\n{shown:#?}\nprinted:\n{out}"
    );
    // The CPU time (the last field of the second line) differs run to run.
    let without_time = |l: &str| {
        l.rsplit_once(", ")
            .map_or(l.to_string(), |(a, _)| a.to_string())
    };
    for (i, (p, s)) in printed.iter().zip(&shown).enumerate() {
        if i == 1 {
            assert_eq!(without_time(p), without_time(s));
        } else {
            assert_eq!(p, s);
        }
    }
}
