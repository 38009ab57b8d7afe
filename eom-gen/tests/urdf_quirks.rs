//! What real robot descriptions do (issue 15), pinned by small URDFs in
//! `tests/fixtures/urdf/` and through the library only: names that are not
//! Rust identifiers, placeholder and inconsistent inertias, massless
//! virtual links, massless fixed links with inertia, zero-DOF robots, and
//! urdfdom's parsing quirks.

use eom_gen::{Source, generate};
use proptest::prelude::*;

/// A one-link pendulum named `name` with one tunable parameter `param`.
fn ron_model(name: &str, param: &str) -> String {
    format!(
        "Model(name: {name:?}, gravity: (0, 0, -9.81), parameters: [(name: {param:?}, value: 1.5, tunable: true)],
          bodies: [(name: \"b\", mass: {param:?}, inertia: Diag(1, 1, 1))],
          joints: [(name: \"j\", kind: Revolute(axis: (1, 0, 0)), parent: \"ground\", child: \"b\")])"
    )
}

/// Generates `src`: a model error is fine (a name that is not allowed);
/// generated code must parse.
fn generates_parsable(src: &Source) -> Result<(), TestCaseError> {
    if let Ok(g) = generate(src) {
        prop_assert!(
            syn::parse_file(&g.source).is_ok(),
            "does not parse:\n{}",
            g.source
        );
    }
    Ok(())
}

const KEYWORDS: &[&str] = &[
    "self",
    "Self",
    "super",
    "crate",
    "_",
    "type",
    "fn",
    "gen",
    "async",
    "Default",
    "Some",
    "r#x",
    "2dof_planar",
    "",
    "é",
    "a b",
];

fn name() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<String>(),
        "[a-zA-Z_0-9]{0,8}",
        proptest::sample::select(KEYWORDS).prop_map(str::to_string),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn any_model_and_parameter_name_generates_parsable_code(model in name(), param in name()) {
        let src = Source::new("names.ron", ron_model(&model, &param));
        generates_parsable(&src)?;
    }

    #[test]
    fn any_robot_name_generates_parsable_code(robot in name()) {
        let text = format!(
            r#"<robot name="{}"><link name="base"/><link name="arm"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
               <joint name="j" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/></joint></robot>"#,
            robot.replace('&', "&amp;").replace('<', "&lt;").replace('"', "&quot;")
        );
        let src = Source::new("names.urdf", text);
        if let Ok(g) = generate(&src) {
            prop_assert!(syn::parse_file(&g.source).is_ok(), "does not parse:\n{}", g.source);
        }
    }
}

#[test]
fn keyword_and_digit_led_names_generate_parsable_code() {
    for (model, param, ty) in [
        ("self", "type", "SelfModel"),
        ("Self", "gen", "SelfModel"),
        ("_", "fn", "Model"),
        ("crate", "self_", "Crate"),
        ("default", "x", "DefaultModel"),
    ] {
        let src = Source::new("names.ron", ron_model(model, param));
        let g = generate(&src).unwrap_or_else(|e| panic!("{model}/{param}: {e}"));
        assert!(syn::parse_file(&g.source).is_ok(), "{}", g.source);
        assert!(
            g.source.contains(&format!("pub struct {ty} ")),
            "{}",
            g.source
        );
        assert!(
            g.source
                .contains(&format!("const NAME: &'static str = {model:?};"))
        );
    }
}

fn fixture(name: &str) -> String {
    format!("{}/tests/fixtures/urdf/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Checks a fixture, panicking with the report on an error.
fn check_ok(name: &str) -> eom_gen::Checked {
    eom_gen::check_file(&fixture(name)).unwrap_or_else(|r| panic!("{name}:\n{r}"))
}

/// The rendered errors of a fixture that must not load.
fn check_err(name: &str) -> String {
    match eom_gen::check_file(&fixture(name)) {
        Ok(_) => panic!("{name} loaded"),
        Err(r) => r.to_string(),
    }
}

#[test]
fn xml_declaration_after_a_leading_comment_is_accepted() {
    let c = check_ok("leading_comment.urdf");
    assert_eq!(c.system.coordinate_names(), ["shoulder"]);
}

#[test]
fn numbers_separated_by_commas_are_located_errors() {
    let r = check_err("commas.urdf");
    assert!(
        r.contains("commas.urdf:6:20: error: `xyz` has numbers separated by commas"),
        "{r}"
    );
    assert!(
        r.contains("commas.urdf:14:16: error: `xyz` has numbers separated by commas"),
        "{r}"
    );
    assert!(r.contains("write `xyz=\"0 0 1\"`"), "{r}");
}

#[test]
fn unexpanded_xacro_is_a_located_error() {
    let r = check_err("xacro.urdf");
    assert!(
        r.contains("xacro.urdf:3:4: error: unexpanded xacro element `<xacro:property>`"),
        "{r}"
    );
    assert!(
        r.contains("xacro.urdf:7:24: error: unexpanded xacro expression in `xyz`"),
        "{r}"
    );
    assert!(
        r.contains("xacro.urdf:8:20: error: unexpanded xacro expression in `value`"),
        "{r}"
    );
    assert!(r.contains("expand it first"), "{r}");
}
