//! Inputs found by the fuzz targets of `fuzz/` (`bash bench/fuzz/run.sh`),
//! minimized, each pinned with what it was and what it gives now: a located
//! diagnostic, never a panic.

use eom_gen::model::{self, Checked, Report, Source, urdf};
use eom_gen::{EmitOptions, generate_checked};

/// Checks `src` (any format) and, if it checks, generates it; returns the
/// diagnostics' rendering, or `None` when the model generated.
fn run(src: &Source) -> Option<String> {
    let checked: Result<Checked, Report> = model::check(src);
    match checked {
        Err(report) => {
            assert!(
                !report.diagnostics.is_empty(),
                "an error without diagnostics"
            );
            Some(report.to_string())
        }
        Ok(checked) => match generate_checked(checked, &EmitOptions::default()) {
            Ok(_) => None,
            Err(e) => Some(e.to_string()),
        },
    }
}

/// `fuzz/artifacts/urdf/crash-62908fe4…`: a URDF link with a mass and a
/// mangled `<inertia>` (so none) on a revolute joint through its origin:
/// a point mass on the hinge's axis. The model checked (strict policy: every
/// body has mass), the tree's mass matrix was the constant 0, forward
/// dynamics folded `1/0` to infinity, and emission panicked in
/// `proc_macro2::Literal::f64_unsuffixed` ("assertion failed:
/// f.is_finite()"). Now formulation refuses a program with a non-finite
/// constant, with an error at the joint whose motion has no inertia
/// (`FormulateError::NotFinite`); emission writes `f64::INFINITY` rather
/// than panic, should one get through.
#[test]
fn point_mass_on_a_hinge_axis_urdf() {
    let text = r#"<robot name="r">
  <link name="base"/>
  <link name="arm">
    <inertial>
      <mass value="1"/>
     is xyrtia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>
    </inertial>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/>
    <child link="arm"/>
    <axis xyz="0 0 1"/>
  </joint>
</robot>
"#;
    let src = Source::new("r.urdf", text);
    // The URDF importer checks the mass matrix of every robot and rejects
    // a motion without inertia at every state, at the joint in the URDF.
    let err = urdf::convert(&src)
        .map(|_| ())
        .expect_err("rejected at import");
    let out = err.to_string();
    assert!(
        out.contains("r.urdf:9:")
            && out.contains("the mass matrix is singular")
            && out.contains("joint `shoulder`"),
        "got:\n{out}"
    );
    assert!(run(&src).is_some(), "and so is its generation");
}

/// The same point mass written as a RON model (strict policy).
#[test]
fn point_mass_on_a_hinge_axis_ron() {
    let text = r#"Model(
    name: "m",
    bodies: [(name: "arm", mass: 1.0)],
    joints: [(name: "hinge", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "arm")],
)
"#;
    let out = run(&Source::new("m.ron", text)).expect("an error");
    assert!(
        out.contains("m.ron:4:")
            && out.contains("the mass matrix is singular for every state")
            && out.contains("joint `hinge` (speed `hinge_dot`)"),
        "got:\n{out}"
    );
    // Off the axis it is a pendulum, and generates.
    let moved = text.replace("mass: 1.0", "mass: 1.0, com: (1, 0, 0)");
    assert_eq!(run(&Source::new("m.ron", moved)), None);
}
