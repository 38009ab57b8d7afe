//! Every class of model error, pinned: the exact `file:line:col` message,
//! the source line with its underline, and the `help:` line. Each case
//! starts from a valid two-link model and breaks one thing (or several, to
//! show they are all reported at once).

use eom_gen::model::{Source, check};

const BASE: &str = r#"// A valid model; each test breaks it.
Model(
    name: "two_link",
    gravity: (0, 0, "-g"),
    parameters: [
        (name: "g", value: 9.81),
        (name: "m", value: 1.5),
        (name: "l", value: 0.3),
    ],
    bodies: [
        (name: "link1", mass: "m", com: (0, 0, "l/2"), inertia: Diag(0.02, 0.02, 0.005)),
        (name: "link2", mass: "m", com: (0, 0, "l/2"), inertia: Diag(0.02, 0.02, 0.005), markers: [(name: "tip", position: (0, 0, "l"))]),
    ],
    joints: [
        (name: "j1", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "link1", coordinates: ["q1"], q0: [0.1]),
        (name: "j2", kind: Revolute(axis: (0, 1, 0)), parent: "link1", child: "link2", parent_frame: (position: (0, 0, "l")), coordinates: ["q2"]),
    ],
    forces: [JointSpringDamper(name: "spring", joint: "j2", stiffness: 10, damping: 0.1)],
    outputs: [Position(body: "link2", marker: "tip")],
)
"#;

/// The rendered diagnostics of `BASE` with each `(from, to)` replaced.
fn diagnose(edits: &[(&str, &str)]) -> String {
    let mut text = BASE.to_string();
    for (from, to) in edits {
        assert!(
            text.contains(from),
            "test setup: `{from}` is not in the base model"
        );
        text = text.replacen(from, to, 1);
    }
    match check(&Source::new("models/two_link.ron", text)) {
        Ok(c) => format!("valid\n{}", c.source.render_all(&c.warnings)),
        Err(report) => {
            assert!(
                report.diagnostics.iter().all(|d| d.span.is_some()),
                "every diagnostic has a location"
            );
            report.to_string()
        }
    }
}

#[test]
fn base_model_is_valid() {
    assert_eq!(diagnose(&[]), "valid\n");
}

macro_rules! pin {
    ($name:ident, $($from:expr => $to:expr),+ $(,)?) => {
        #[test]
        fn $name() {
            insta::assert_snapshot!(diagnose(&[$(($from, $to)),+]));
        }
    };
}

// Syntax and types (reported by the RON reader, one at a time).
pin!(syntax_error, "(name: \"l\", value: 0.3)," => "(name: \"l\" value: 0.3),");
pin!(unknown_field, "com: (0, 0, \"l/2\"), inertia" => "cmo: (0, 0, \"l/2\"), inertia");
pin!(missing_field, "(name: \"link1\", mass: \"m\", " => "(name: \"link1\", ");
pin!(missing_field_of_joint, "kind: Revolute(axis: (0, 0, 1)), parent" => "parent");
pin!(unknown_joint_kind, "Revolute(axis: (0, 1, 0))" => "Revolve(axis: (0, 1, 0))");
pin!(wrong_type, "value: 1.5" => "value: [1.5]");
pin!(vector_of_two, "com: (0, 0, \"l/2\"), inertia" => "com: (0, 0), inertia");

// Unknown fields inside enum variants (issue #14): each one at its name,
// all of them at once.
pin!(
    spring_damper_rest_len,
    "forces: [" => "forces: [SpringDamper(name: \"cord\", a: (body: \"ground\"), b: (body: \"link2\", marker: \"tip\"), stiffness: 5, rest_len: 1.0), "
);
pin!(joint_spring_damper_misspelled_fields, "damping: 0.1" => "dampnig: 1.0, rest_angle: 0.3");
pin!(revolute_misspelled_axis, "Revolute(axis: (0, 1, 0))" => "Revolute(axis: (0, 1, 0), axsi: (1, 0, 0))");
pin!(
    rolling_disk_centre,
    "    outputs:" => "    constraints: [RollingDisk(name: \"wheel\", body: \"link2\", radius: 0.1, axis: (0, 1, 0), centre: (0, 0, \"l\"))],\n    outputs:"
);

/// Issue #14: `rest_len` for `rest_length` was accepted, and the spring's
/// rest length silently became 0 (a wrong bias force).
#[test]
fn regression_spring_damper_rest_len_is_rejected_not_a_zero_rest_length() {
    let out = diagnose(&[(
        "forces: [",
        "forces: [SpringDamper(name: \"cord\", a: (body: \"ground\"), b: (body: \"link2\", marker: \"tip\"), stiffness: 5, rest_len: 1.0), ",
    )]);
    let first = out.lines().next().unwrap_or("");
    assert_eq!(
        first, "models/two_link.ron:18:111: error: unknown field `rest_len` of `SpringDamper`",
        "got:\n{out}"
    );
    assert!(out.contains("did you mean `rest_length`?"), "got:\n{out}");
}

// Geometry (drawn by `animate`): every bad value at once, each at its
// place; an unknown field inside a shape; a mesh file that is not there
// is a warning (the dynamics do not need it).
pin!(
    geometry_bad_values,
    "inertia: Diag(0.02, 0.02, 0.005), markers" => "inertia: Diag(0.02, 0.02, 0.005), geometry: [Box(size: (0.1, 0, \"l\")), Cylinder(radius: -1, length: \"l\"), Mesh(file: \"link.step\"), Mesh(file: \"link.stl\", scale: (1, 0, 1)), Sphere(radius: 0.05, color: (2, 0, 0))], markers"
);
pin!(geometry_unknown_field, "inertia: Diag(0.02, 0.02, 0.005), markers" => "inertia: Diag(0.02, 0.02, 0.005), geometry: [Sphere(radius: 0.05, colour: (1, 0, 0))], markers");
pin!(geometry_missing_mesh, "inertia: Diag(0.02, 0.02, 0.005), markers" => "inertia: Diag(0.02, 0.02, 0.005), geometry: [Mesh(file: \"meshes/link2.stl\")], markers");

// Names.
pin!(unknown_body, "child: \"link2\"" => "child: \"lnk2\"");
pin!(duplicate_body, "(name: \"link2\", mass" => "(name: \"link1\", mass");
pin!(duplicate_joint, "(name: \"j2\"" => "(name: \"j1\"");
pin!(duplicate_parameter, "(name: \"l\", value: 0.3)" => "(name: \"m\", value: 0.3)");
pin!(duplicate_coordinate, "coordinates: [\"q2\"]" => "coordinates: [\"q1\"]");
pin!(coordinate_named_like_a_parameter, "coordinates: [\"q2\"]" => "coordinates: [\"g\"]");
pin!(reserved_name, "(name: \"g\", value: 9.81)" => "(name: \"pi\", value: 9.81)");
pin!(ground_defined, "(name: \"link1\", mass" => "(name: \"ground\", mass");
pin!(unknown_marker, "marker: \"tip\"" => "marker: \"top\"");
pin!(unknown_joint_in_force, "joint: \"j2\"" => "joint: \"j3\"");

// Expressions.
pin!(unknown_parameter_in_expression, "com: (0, 0, \"l/2\"), inertia: Diag(0.02, 0.02, 0.005), markers" => "com: (0, 0, \"L/2\"), inertia: Diag(0.02, 0.02, 0.005), markers");
pin!(unparsable_expression, "com: (0, 0, \"l/2\"), inertia: Diag(0.02, 0.02, 0.005))," => "com: (0, 0, \"l/*2\"), inertia: Diag(0.02, 0.02, 0.005)),");
pin!(parameter_used_before_defined, "(name: \"m\", value: 1.5)" => "(name: \"m\", value: \"5*l\")");
pin!(time_in_geometry, "parent_frame: (position: (0, 0, \"l\"))" => "parent_frame: (position: (0, 0, \"l*t\"))");
pin!(not_finite, "(name: \"l\", value: 0.3)" => "(name: \"l\", value: \"sqrt(-0.3)\")");

// Physical values.
pin!(negative_mass, "(name: \"m\", value: 1.5)" => "(name: \"m\", value: -1.5)");
pin!(zero_mass, "(name: \"link1\", mass: \"m\"" => "(name: \"link1\", mass: 0");
pin!(inertia_not_symmetric, "inertia: Diag(0.02, 0.02, 0.005))," => "inertia: Matrix((0.02, 0.001, 0), (0, 0.02, 0), (0, 0, 0.005))),");
pin!(inertia_not_positive, "inertia: Diag(0.02, 0.02, 0.005))," => "inertia: Diag(0.02, -0.02, 0.005)),");
pin!(inertia_triangle_inequality, "inertia: Diag(0.02, 0.02, 0.005))," => "inertia: Diag(0.01, 0.01, 0.05)),");
pin!(zero_axis, "Revolute(axis: (0, 0, 1))" => "Revolute(axis: (0, 0, 0))");
pin!(non_finite_axis, "Revolute(axis: (0, 0, 1))" => "Revolute(axis: (0, 0, \"1/0\"))");
pin!(rotation_not_orthonormal, "parent_frame: (position: (0, 0, \"l\"))" => "parent_frame: (position: (0, 0, \"l\"), orientation: Matrix((1, 0, 0), (0, 1, 0.1), (0, 0, 1)))");
pin!(rotation_reflection, "parent_frame: (position: (0, 0, \"l\"))" => "parent_frame: (position: (0, 0, \"l\"), orientation: Matrix((1, 0, 0), (0, 1, 0), (0, 0, -1)))");
pin!(negative_damping, "damping: 0.1" => "damping: -0.1");

// Joints and the graph.
pin!(body_not_connected_to_ground, "parent: \"link1\", child: \"link2\"" => "parent: \"link2\", child: \"link2\"");
pin!(body_only_reached_reversed, "parent: \"ground\", child: \"link1\"" => "parent: \"link1\", child: \"ground\"");
pin!(wrong_number_of_initial_values, "q0: [0.1]" => "q0: [0.1, 0.2]");
pin!(wrong_number_of_speeds, "q0: [0.1])" => "q0: [0.1], u0: [])");
pin!(wrong_number_of_coordinate_names, "coordinates: [\"q1\"]" => "coordinates: [\"q1\", \"q1b\"]");
pin!(prescribed_and_locked, "q0: [0.1])" => "q0: [0.1], locked: true, prescribed: [\"sin(t)\"])");
pin!(non_unit_quaternion, "Revolute(axis: (0, 0, 1)), parent: \"ground\", child: \"link1\", coordinates: [\"q1\"], q0: [0.1]" => "Spherical, parent: \"ground\", child: \"link1\", q0: [1, 0, 0, 0.1]");
pin!(parallel_universal_axes, "Revolute(axis: (0, 1, 0))" => "Universal(axis1: (0, 1, 0), axis2: (0, 2, 0))");
pin!(speeds_of_locked_joint_ignored, "coordinates: [\"q2\"])" => "coordinates: [\"q2\"], locked: true, u0: [1])", "forces: [JointSpringDamper(name: \"spring\", joint: \"j2\", stiffness: 10, damping: 0.1)]," => "");
pin!(initial_values_of_prescribed_joint_ignored, "q0: [0.1])" => "q0: [0.1], prescribed: [\"sin(t)\"])");
pin!(spring_on_locked_joint, "coordinates: [\"q2\"])" => "coordinates: [\"q2\"], locked: true)");

// An unknown body and an unknown parameter (in a force, checked after the
// joints) in one report, not one run after the other.
pin!(
    unknown_body_and_unknown_parameter,
    "child: \"link2\"" => "child: \"lnk2\"",
    "stiffness: 10" => "stiffness: \"k\"",
);

// Several problems at once: all of them are reported, in file order.
pin!(
    every_error_at_once,
    "(name: \"m\", value: 1.5)" => "(name: \"m\", value: -1.5)",
    "child: \"link2\"" => "child: \"lnk2\"",
    "Revolute(axis: (0, 0, 1))" => "Revolute(axis: (0, 0, 0))",
    "marker: \"tip\"" => "marker: \"top\"",
);

// Scenes: checked against the base model (written to a temporary directory
// as `two_link.ron`); every problem of the scene at once, in the scene file.

const SCENE: &str = r#"// A valid scene of the base model; each test breaks it.
Scene(
    model: "../two_link.ron",
    name: "two_link_tip",
    outputs: [Position(body: "link2", marker: "tip"), JointReaction(joint: "j1")],
    lock: [(joint: "j1", at: ["l/3"])],
    fixed: ["g"],
    tunable: ["m"],
)
"#;

/// The rendered diagnostics of `SCENE` with each `(from, to)` replaced.
fn diagnose_scene(edits: &[(&str, &str)]) -> String {
    let mut text = SCENE.to_string();
    for (from, to) in edits {
        assert!(
            text.contains(from),
            "test setup: `{from}` is not in the base scene"
        );
        text = text.replacen(from, to, 1);
    }
    let root = std::env::temp_dir().join(format!(
        "eom-scene-diagnostics-{}-{:x}",
        std::process::id(),
        eom_gen::emit::fnv1a(text.as_bytes())
    ));
    let _ = std::fs::create_dir_all(&root);
    std::fs::write(root.join("two_link.ron"), BASE).expect("write the base model");
    let broken = BASE
        .replacen("(name: \"m\", value: 1.5)", "(name: \"m\", value: -1.5)", 1)
        .replacen("child: \"link2\"", "child: \"lnk2\"", 1);
    std::fs::write(root.join("broken.ron"), broken).expect("write the broken model");
    let _ = std::fs::create_dir_all(root.join("scenes"));
    std::fs::write(root.join("scenes/tip.scene.ron"), &text).expect("write the scene");
    let src = Source::new("scenes/tip.scene.ron", text);
    let out = match eom_gen::model::check_in(&src, &root) {
        Ok(c) => format!("valid\n{}", c.render_warnings()),
        Err(report) => {
            assert!(
                report.diagnostics.iter().all(|d| d.span.is_some()),
                "every diagnostic has a location"
            );
            report.to_string()
        }
    };
    let _ = std::fs::remove_dir_all(&root);
    out
}

#[test]
fn base_scene_is_valid() {
    assert_eq!(diagnose_scene(&[]), "valid\n");
}

macro_rules! pin_scene {
    ($name:ident, $($from:expr => $to:expr),+ $(,)?) => {
        #[test]
        fn $name() {
            insta::assert_snapshot!(diagnose_scene(&[$(($from, $to)),+]));
        }
    };
}

pin_scene!(scene_unknown_field, "fixed: [\"g\"]" => "fixd: [\"g\"]");
pin_scene!(scene_missing_model, "../two_link.ron" => "../two_lnk.ron");
pin_scene!(scene_model_with_errors, "../two_link.ron" => "../broken.ron");
pin_scene!(scene_model_is_a_scene, "../two_link.ron" => "tip.scene.ron");
pin_scene!(scene_unknown_lock_joint, "(joint: \"j1\", at" => "(joint: \"j11\", at");
pin_scene!(scene_wrong_number_of_lock_values, "at: [\"l/3\"]" => "at: [0.1, 0.2]");
pin_scene!(scene_unknown_name_in_lock_value, "at: [\"l/3\"]" => "at: [\"L/3\"]");
pin_scene!(scene_lock_joint_with_spring, "(joint: \"j1\", at: [\"l/3\"])" => "(joint: \"j2\")");
pin_scene!(scene_lock_twice, "(joint: \"j1\", at: [\"l/3\"])" => "(joint: \"j1\"), (joint: \"j1\", at: [0])");
pin_scene!(scene_unknown_parameter, "fixed: [\"g\"]" => "fixed: [\"gg\"]");
pin_scene!(scene_fixed_and_tunable, "fixed: [\"g\"]" => "fixed: [\"g\", \"m\"]");
pin_scene!(scene_unknown_marker, "marker: \"tip\"" => "marker: \"tpi\"");
pin_scene!(scene_marker_on_body_without_markers, "body: \"link2\"" => "body: \"link1\"");
pin_scene!(scene_name_not_identifier, "\"two_link_tip\"" => "\"two-link tip\"");
pin_scene!(
    scene_functions_without_inverse_dynamics,
    "tunable: [\"m\"]," => "tunable: [\"m\"],\n    functions: [ForwardDynamics, MassMatrix, Energy],"
);
pin_scene!(
    scene_functions_none_derivable,
    "tunable: [\"m\"]," => "tunable: [\"m\"],\n    functions: [],"
);
pin_scene!(
    scene_functions_listed_twice,
    "tunable: [\"m\"]," => "tunable: [\"m\"],\n    functions: [InverseDynamics, InverseDynamics],"
);
pin_scene!(
    scene_unknown_function,
    "tunable: [\"m\"]," => "tunable: [\"m\"],\n    functions: [MassMatrx],"
);
pin_scene!(
    scene_functions_error_with_others,
    "fixed: [\"g\"]" => "fixed: [\"gg\"]",
    "tunable: [\"m\"]," => "tunable: [\"m\"],\n    functions: [Bias],"
);
pin_scene!(
    scene_every_error_at_once,
    "\"two_link_tip\"" => "\"two-link tip\"",
    "marker: \"tip\"" => "marker: \"tpi\"",
    "JointReaction(joint: \"j1\")" => "JointReaction(joint: \"j3\")",
    "(joint: \"j1\", at: [\"l/3\"])" => "(joint: \"j2\", at: [\"L/3\"])",
    "fixed: [\"g\"]" => "fixed: [\"g\", \"m\", \"k\"]",
);

/// The rendered error of generating `BASE` with the edits: problems that
/// only formulation finds.
fn generate_error(edits: &[(&str, &str)]) -> String {
    let mut text = BASE.to_string();
    for (from, to) in edits {
        assert!(
            text.contains(from),
            "test setup: `{from}` is not in the base model"
        );
        text = text.replacen(from, to, 1);
    }
    match eom_gen::generate(&Source::new("models/two_link.ron", text)) {
        Ok(_) => panic!("the model generated, but should fail to formulate"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn formulation_error_names_the_axis_at_its_location() {
    // Valid to the checker; joint axes are inlined, so formulation refuses.
    let got = generate_error(&[
        (
            "(name: \"l\", value: 0.3),",
            "(name: \"l\", value: 0.3),\n        (name: \"ay\", value: 1.0, tunable: true),",
        ),
        (
            "Revolute(axis: (0, 1, 0))",
            "Revolute(axis: (0, \"ay\", 0))",
        ),
    ]);
    assert!(
        got.starts_with("models/two_link.ron:17:47: error: the axis of joint `j2` depends on a tunable parameter"),
        "got:\n{got}"
    );
    assert!(
        got.contains("= help: make the parameters in the axis fixed"),
        "got:\n{got}"
    );
}

#[test]
fn formulation_error_names_a_parameter_named_like_a_state_symbol() {
    // `q7` is no coordinate of the model, but the generated code names its
    // coordinates `q0`, `q1`, …: a tunable parameter cannot be called that.
    let got = generate_error(&[(
        "(name: \"l\", value: 0.3),",
        "(name: \"l\", value: 0.3),\n        (name: \"q7\", value: 1.0, tunable: true),",
    )]);
    assert!(
        got.starts_with("models/two_link.ron:9:16: error: name `q7` is reserved"),
        "got:\n{got}"
    );
}
