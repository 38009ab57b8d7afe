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
