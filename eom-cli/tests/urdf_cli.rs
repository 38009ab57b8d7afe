//! The command line on URDF files: `import`, and every command taking a
//! `.urdf` directly.

use std::process::Command;

fn path(name: &str) -> String {
    format!(
        "{}/../eom-gen/tests/urdf/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn eom_gen_cli(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .output()
        .expect("run eom-gen")
}

/// `import` writes a RON model that checks on its own; `check --json` takes
/// the URDF directly and lists the coordinates.
#[test]
fn cli_import_and_check() {
    let dir = std::env::temp_dir().join(format!("eom-urdf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let out_file = dir.join("tree.ron");
    let out_path = out_file.to_string_lossy().to_string();
    let o = eom_gen_cli(&["import", &path("tree.urdf"), "-o", &out_path]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("merged"), "{err}");
    let o = eom_gen_cli(&["check", "--json", &out_path]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let o = eom_gen_cli(&["check", "--json", &path("tree.urdf")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(
        v["coordinate_names"],
        serde_json::json!(["hip", "shoulder_r", "shoulder_l", "elbow_l"])
    );
    assert!(
        v["urdf_notes"][0]
            .as_str()
            .is_some_and(|n| n.contains("merged"))
    );

    let o = eom_gen_cli(&["eval", "--interpret", &path("arm2.urdf"), "--q", "0,0"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let o = eom_gen_cli(&["dump", &path("arm2.urdf")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let head = String::from_utf8_lossy(&o.stdout);
    let first = head.lines().next().unwrap_or_default();
    assert!(
        first.contains("arm2.urdf`") && !first.contains("(converted)"),
        "{first}"
    );

    let o = eom_gen_cli(&["check", &path("bad.urdf")]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.urdf:14:26: error: unknown joint type"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A robot whose joints are all fixed has no coordinates: `eval` and
/// `simulate` take empty lists (`--q ""`) as well as the defaults, and an
/// empty list for a model with coordinates names the counts (issue 15:
/// quadrotor_base and iris_simple of example-robot-data failed with
/// "cannot parse float from empty string").
#[test]
fn zero_dof_robot_takes_empty_lists() {
    let zero = format!(
        "{}/../eom-gen/tests/fixtures/urdf/zero_dof.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    for args in [
        &["eval", "--interpret", &zero, "--json"][..],
        &[
            "eval",
            "--interpret",
            &zero,
            "--q",
            "",
            "--u",
            "",
            "--tau",
            " ",
            "--json",
        ],
    ] {
        let o = eom_gen_cli(args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
        assert_eq!(v["udot"], serde_json::json!([]), "{v}");
        assert_eq!(v["mass_matrix"], serde_json::json!([]), "{v}");
        assert_eq!(v["kinetic_energy"], serde_json::json!(0.0), "{v}");
    }
    let o = eom_gen_cli(&[
        "simulate",
        "--interpret",
        &zero,
        "--t-end",
        "1",
        "--q0",
        "",
        "--u0",
        "",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(
        (v["t"].as_f64(), &v["q"]),
        (Some(1.0), &serde_json::json!([])),
        "{v}"
    );

    let o = eom_gen_cli(&["eval", "--interpret", &path("arm2.urdf"), "--q", ""]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--q has 0 value(s), the model has 2"), "{err}");
}

/// `check --json` counts the URDF importer's warnings (an inconsistent
/// inertia of a moving link) with the model's.
#[test]
fn check_json_counts_urdf_warnings() {
    let file = format!(
        "{}/../eom-gen/tests/fixtures/urdf/negative_inertia.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    let o = eom_gen_cli(&["check", "--json", &file]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["warnings"], serde_json::json!(1), "{v}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("warning: inertia of link `thigh`"), "{err}");
}

/// The inertia policy from the command line: a finger whose principal
/// moments break the triangle inequality (1e-6 + 1e-6 < 2.1e-6) loads with
/// a located warning, is an error with `--strict-inertia`, and is balanced
/// with `--balance-inertia` (the fix listed in the notes); the flags work
/// on every command (here `check` and `simulate`).
#[test]
fn inertia_policy_flags() {
    let file = format!(
        "{}/../eom-gen/tests/fixtures/urdf/inconsistent_inertia.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    let o = eom_gen_cli(&["check", &file]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("inconsistent_inertia.urdf:8:8: warning"),
        "{err}"
    );
    let o = eom_gen_cli(&["check", &file, "--strict-inertia"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("inconsistent_inertia.urdf:8:8: error"),
        "{err}"
    );
    let o = eom_gen_cli(&["--balance-inertia", "check", &file]);
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{text}");
    assert!(text.contains("balanced (balance_inertia)"), "{text}");
    assert!(!text.contains("warning"), "{text}");
    let o = eom_gen_cli(&[
        "simulate",
        &file,
        "--t-end",
        "0.1",
        "--interpret",
        "--strict-inertia",
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Joint limits are imported by default (issue #26): `import` writes the
/// shoulder's `JointLimit`; `--no-urdf-limits` leaves it off (a note);
/// `--urdf-limits`, once needed for them, still runs and changes nothing;
/// both together are refused.
#[test]
fn joint_limits_by_default_and_left_off_on_request() {
    let dir = std::env::temp_dir().join(format!("eom-urdf-limits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let file = dir.join("arm2.ron").to_string_lossy().to_string();
    let import = |extra: &[&str]| {
        let mut args = vec!["import", "-o", file.as_str()];
        args.extend_from_slice(extra);
        let p = path("arm2.urdf");
        args.push(p.as_str());
        let o = eom_gen_cli(&args);
        let text = std::fs::read_to_string(&file).unwrap_or_default();
        let _ = std::fs::remove_file(&file);
        (o, text)
    };
    let (o, text) = import(&[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        text.contains("JointLimit(") && text.contains("shoulder_limit"),
        "{text}"
    );
    let (o, same) = import(&["--urdf-limits"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(same, text);
    let (o, text) = import(&["--no-urdf-limits"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!text.contains("JointLimit("), "{text}");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("left off by `--no-urdf-limits`"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let (o, _) = import(&["--urdf-limits", "--no-urdf-limits"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("cannot be used with"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Names as the user wrote them: the URDF's joint `joint_0.0` and link
/// `link 1` are the identifiers `joint_0_0` and `link_1` in the model, and
/// `check --json` gives the originals (`coordinate_labels`,
/// `original_names`); `simulate --plot` names the joint as written in the
/// legend; the animation page labels the body and joint as written.
#[test]
fn renamed_joints_keep_their_names() {
    let urdf = path("visual_pkg/robots/visuals.urdf");
    let o = eom_gen_cli(&["check", "--json", &urdf]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("json");
    assert_eq!(v["coordinate_names"], serde_json::json!(["joint_0_0"]));
    assert_eq!(v["coordinate_labels"], serde_json::json!(["joint_0.0"]));
    let renamed: Vec<(String, String, String)> = v["original_names"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|x| {
                    let s = |k: &str| x[k].as_str().unwrap_or("").to_string();
                    (s("kind"), s("name"), s("original"))
                })
                .collect()
        })
        .unwrap_or_default();
    let want = [
        ("coordinate", "joint_0_0", "joint_0.0"),
        ("body", "link_1", "link 1"),
        ("joint", "joint_0_0", "joint_0.0"),
    ]
    .map(|(a, b, c)| (a.to_string(), b.to_string(), c.to_string()));
    assert_eq!(renamed, want);

    let dir = std::env::temp_dir().join(format!("eom-names-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let svg = dir.join("run.svg").to_string_lossy().to_string();
    let html = dir.join("run.html").to_string_lossy().to_string();
    let o = eom_gen_cli(&[
        "simulate",
        "--interpret",
        &urdf,
        "--q0",
        "1",
        "--t-end",
        "0.2",
        "--plot",
        &svg,
        "--html",
        &html,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let svg = std::fs::read_to_string(&svg).expect("svg");
    assert!(
        svg.contains("joint_0.0"),
        "the legend names the joint as written"
    );
    let page = std::fs::read_to_string(&html).expect("html");
    assert!(
        page.contains(r#""label":"link 1""#),
        "the page labels the body"
    );
    assert!(
        page.contains(r#""jointLabel":"joint_0.0""#),
        "and its joint"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
