//! URDF import: mapping, merging of fixed links, free bases, mimic joints,
//! diagnostics, the CLI, and arm7 written as URDF against `models/arm7.ron`.

use eom_gen::interpret::{Point, evaluate};
use eom_gen::mech::Numeric;
use eom_gen::model::spec::{Constraint, Force, Geometry, Inertia, JointKind, Num, Orientation, V3};
use eom_gen::testkit::{Rng, random_state};
use eom_gen::urdf::{Import, convert, import_file};
use eom_gen::{Checked, Source, check};

fn path(name: &str) -> String {
    format!("{}/tests/urdf/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn import(name: &str) -> Import {
    import_file(&path(name)).unwrap_or_else(|r| panic!("{name}:\n{r}"))
}

fn checked(name: &str) -> (Import, Checked) {
    let i = import(name);
    let c = check(&i.source).unwrap_or_else(|r| panic!("{name} (converted):\n{r}"));
    (i, c)
}

fn val(n: &Num) -> f64 {
    match n {
        Num::Value(v) => *v,
        Num::Expr(e) => panic!("expected a number, found `{e}`"),
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn assert_matrix_eq(a: &[Vec<f64>], b: &[Vec<f64>], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: sizes");
    for (i, (ra, rb)) in a.iter().zip(b).enumerate() {
        for (j, (x, y)) in ra.iter().zip(rb).enumerate() {
            assert!(close(*x, *y, tol), "{what}[{i}][{j}]: {x} vs {y}");
        }
    }
}

/// The 2-link arm: its mass matrix written out by hand.
#[test]
fn two_link_arm_mass_matrix_by_hand() {
    let (imp, c) = checked("arm2.urdf");
    let sys = &c.system;
    assert_eq!(sys.coordinate_names(), ["shoulder", "elbow"]);
    // The `elbow` damping became a joint damper; limits, friction and
    // geometry are in the notes.
    assert!(imp.spec.forces.iter().any(|f| matches!(f,
        Force::JointSpringDamper { joint, stiffness, damping, .. }
            if joint == "elbow" && stiffness.is_zero() && val(damping) == 0.1)));
    let notes = imp.notes.join("\n");
    for needle in ["limits", "friction 0.05", "1 <collision>", "-9.81"] {
        assert!(notes.contains(needle), "notes lack `{needle}`:\n{notes}");
    }
    // The upper link's `<visual>` box is drawn.
    assert!(matches!(
        &imp.spec.bodies[0].geometry[..],
        [Geometry::Box { .. }]
    ));
    // The link-2 inertial is turned 0.3 rad about z: I = R diag Rᵀ.
    let fore = &imp.spec.bodies[1];
    let Some(Inertia::Matrix(r0, r1, r2)) = &fore.inertia else {
        panic!("expected a full tensor, got {:?}", fore.inertia)
    };
    let (cs, sn) = (0.3f64.cos(), 0.3f64.sin());
    let (a, b) = (0.012, 0.01);
    assert!(close(val(&r0.0), a * cs * cs + b * sn * sn, 1e-14));
    assert!(close(val(&r0.1), (a - b) * cs * sn, 1e-14));
    assert!(close(val(&r1.1), a * sn * sn + b * cs * cs, 1e-14));
    assert_eq!(val(&r2.2), 0.02);
    assert_eq!((val(&r0.2), val(&r1.2)), (0.0, 0.0));

    let (m1, c1, i1, l1) = (2.0, 0.25, 0.05, 0.5);
    let (m2, c2, i2) = (1.0, 0.2, 0.02);
    let num = Numeric::new(sys).expect("numeric");
    for q in [[0.0f64, 0.0], [0.4, -1.1], [-2.0, 2.5]] {
        let cq = q[1].cos();
        let m11 = i1 + i2 + m1 * c1 * c1 + m2 * (l1 * l1 + c2 * c2 + 2.0 * l1 * c2 * cq);
        let m12 = i2 + m2 * (c2 * c2 + l1 * c2 * cq);
        let m22 = i2 + m2 * c2 * c2;
        let t = num.terms(&q, &[0.0, 0.0], 0.0, &[]).expect("terms");
        assert_matrix_eq(
            &t.mass_matrix,
            &[vec![m11, m12], vec![m12, m22]],
            1e-12,
            "M",
        );
        // Horizontal plane, at rest: no bias.
        assert!(t.bias.iter().all(|b| b.abs() < 1e-12), "{:?}", t.bias);
    }
}

/// Fixed joints merge links into one body with the composite inertia; the
/// coordinates come depth-first in document order.
#[test]
fn branched_tree_merges_fixed_links() {
    let (imp, c) = checked("tree.urdf");
    let sys = &c.system;
    assert_eq!(
        sys.coordinate_names(),
        ["hip", "shoulder_r", "shoulder_l", "elbow_l"]
    );
    let names: Vec<&str> = imp.spec.bodies.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["torso", "right_arm", "left_arm", "left_fore"]);
    // torso (4 kg, com z 0.2) + head (1 kg at z 0.5 + 0.1): 5 kg, com z 0.28.
    let torso = &imp.spec.bodies[0];
    assert_eq!(val(torso.mass.as_ref().expect("a mass")), 5.0);
    assert!(close(val(&torso.com.2), 0.28, 1e-14));
    let Some(Inertia::Diag(ixx, iyy, izz)) = &torso.inertia else {
        panic!("expected a diagonal tensor, got {:?}", torso.inertia)
    };
    let ixx_hand = 0.1 + 4.0 * 0.08 * 0.08 + 0.004 + 1.0 * 0.32 * 0.32;
    assert!(close(val(ixx), ixx_hand, 1e-14) && close(val(iyy), ixx_hand, 1e-14));
    assert!(close(val(izz), 0.024, 1e-14));
    // right_arm hangs off the merged head: frames compose.
    let jr = imp
        .spec
        .joints
        .iter()
        .find(|j| j.name == "shoulder_r")
        .expect("shoulder_r");
    assert_eq!(jr.parent, "torso");
    assert!(close(val(&jr.parent_frame.position.2), 0.4, 1e-15));
    assert_eq!(val(&jr.parent_frame.position.1), -0.2);
    assert!(matches!(&jr.parent_frame.orientation, Orientation::Rpy(r, _, _) if val(r) == 0.3));
    let notes = imp.notes.join("\n");
    assert!(
        notes.contains("`head` into `torso`") && notes.contains("`camera` into `torso`"),
        "{notes}"
    );
    assert!(notes.contains("no work for them"), "{notes}");

    // The same tree written by hand as a RON model gives the same dynamics.
    let ron = r#"Model(name: "tree_ron", gravity: (0, 0, -9.81),
      bodies: [
        (name: "torso", mass: 5, com: (0, 0, 0.28), inertia: Diag(0.232, 0.232, 0.024)),
        (name: "right_arm", mass: 0.8, com: (0, -0.15, 0), inertia: Diag(0.006, 0.001, 0.006)),
        (name: "left_arm", mass: 0.8, com: (0, 0.15, 0), inertia: Diag(0.006, 0.001, 0.006)),
        (name: "left_fore", mass: 0.5, com: (0, 0.1, 0),
         inertia: Matrix((0.002, 0.0001, 0), (0.0001, 0.0005, 0), (0, 0, 0.002))),
      ],
      joints: [
        (name: "hip", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "torso",
         parent_frame: (position: (0, 0, 0.1))),
        (name: "shoulder_r", kind: Revolute(axis: (1, 0, 0)), parent: "torso", child: "right_arm",
         parent_frame: (position: (0, -0.2, 0.4), orientation: Rpy(0.3, 0, 0))),
        (name: "shoulder_l", kind: Revolute(axis: (1, 0, 0)), parent: "torso", child: "left_arm",
         parent_frame: (position: (0, 0.2, 0.4))),
        (name: "elbow_l", kind: Revolute(axis: (1, 0, 0)), parent: "left_arm", child: "left_fore",
         parent_frame: (position: (0, 0.3, 0))),
      ])"#;
    let hand = check(&Source::new("tree_by_hand.ron", ron)).unwrap_or_else(|r| panic!("{r}"));
    compare(sys, &hand.system, 5, 1e-10);
}

/// Mass matrices and biases of two systems at random states.
fn compare(a: &eom_gen::System, b: &eom_gen::System, n: usize, tol: f64) {
    let (na, nb) = (
        Numeric::new(a).expect("numeric"),
        Numeric::new(b).expect("numeric"),
    );
    let mut rng = Rng(0x5eed_1234_abcd);
    for _ in 0..n {
        let (q, u) = random_state(a, &mut rng);
        let (ta, tb) = (
            na.terms(&q, &u, 0.0, &[]).expect("terms"),
            nb.terms(&q, &u, 0.0, &[]).expect("terms"),
        );
        assert_matrix_eq(&ta.mass_matrix, &tb.mass_matrix, tol, "M");
        assert_matrix_eq(&[ta.bias], &[tb.bias], tol, "bias");
    }
}

/// `world` → `floating` → body is a free base.
#[test]
fn floating_base() {
    let (imp, c) = checked("floating.urdf");
    let sys = &c.system;
    assert_eq!(
        sys.coordinate_names(),
        [
            "base_x", "base_y", "base_z", "base_qw", "base_qx", "base_qy", "base_qz", "swing"
        ]
    );
    assert_eq!((sys.nq(), sys.nu()), (8, 7));
    assert!(matches!(imp.spec.joints[0].kind, JointKind::Free));
    assert_eq!(imp.spec.joints[0].parent, "ground");
    // The linear block of the mass matrix is the total mass (speeds are in
    // body axes, so at any orientation).
    let num = Numeric::new(sys).expect("numeric");
    let mut rng = Rng(7);
    let (q, u) = random_state(sys, &mut rng);
    let t = num.terms(&q, &u, 0.0, &[]).expect("terms");
    for i in 0..3 {
        for j in 0..3 {
            let want = if i == j { 3.5 } else { 0.0 };
            assert!(close(t.mass_matrix[i][j], want, 1e-12), "M[{i}][{j}]");
        }
    }
}

/// `mimic` becomes a holonomic constraint over the two coordinates.
#[test]
fn mimic_joint_is_a_constraint() {
    let (imp, c) = checked("mimic.urdf");
    assert_eq!(c.system.coordinate_names(), ["f1", "f2"]);
    assert_eq!(c.system.constraints.len(), 1);
    let [Constraint::Holonomic { name, expr }] = imp.spec.constraints.as_slice() else {
        panic!("{:?}", imp.spec.constraints)
    };
    assert_eq!(name, "f2_mimic");
    assert_eq!(expr, "f2 - 0.5*f1 - (-0.01)");
    assert_eq!(c.system.grubler.dof, 1);
}

fn line_col(text: &str, needle: &str) -> String {
    let at = text
        .find(needle)
        .unwrap_or_else(|| panic!("`{needle}` not in file"));
    let line = 1 + text[..at].matches('\n').count();
    let col = 1 + at - text[..at].rfind('\n').map_or(0, |i| i + 1);
    format!("{line}:{col}")
}

/// Every problem at once, each at its `file:line:col`.
#[test]
fn bad_urdf_reports_everything_with_positions() {
    let p = path("bad.urdf");
    let text = std::fs::read_to_string(&p).expect("read");
    let report = match import_file(&p) {
        Ok(_) => panic!("bad.urdf was accepted"),
        Err(r) => r,
    };
    let out = report.to_string();
    let expect = [
        ("revolut\"", 0, "unknown joint type `revolut`"),
        ("gohst", 0, "link `gohst` is not defined"),
        ("base\"/>\n  <link name=\"arm\"", 0, "2 roots"),
        ("orphan", 0, "2 roots"),
        ("j2\"", 0, "`j2` is part of a cycle"),
        ("j3\"", 0, "`j3` is part of a cycle"),
    ];
    // A tensor that is not positive definite is a warning (issue 15: the
    // mass matrix is checked instead), reported with the errors.
    let lc = line_col(&text, "inertia ixx=\"0.1\" ixy=\"0.5\"");
    assert!(
        out.contains(&format!("{p}:{lc}: warning: inertia of link"))
            && out.contains("is not positive definite"),
        "no warning at {lc} in\n{out}"
    );
    for (needle, shift, message) in expect {
        let lc = line_col(&text, needle);
        let (l, c) = lc.split_once(':').expect("lc");
        let c: usize = c.parse::<usize>().expect("col") + shift;
        let head = format!("{p}:{l}:{c}: error: ");
        assert!(
            out.lines()
                .any(|line| line.starts_with(&head) && line.contains(message)),
            "no `{head}…{message}` in\n{out}"
        );
    }
    assert_eq!(report.diagnostics.len(), 7, "{out}");
    assert!(out.contains("did you mean `revolute`?"), "{out}");
}

/// Other failures: XML syntax, massless moving links, bad numbers, names.
#[test]
fn more_diagnostics() {
    let cases = [
        ("<robot name='x'><link name='a'></robot>", "invalid XML"),
        ("<model/>", "not `<robot>`"),
        (
            "<robot name='x'><link name='a'/><link name='b'/>
             <joint name='j' type='revolute'><parent link='a'/><child link='b'/></joint></robot>",
            "link `b` has no mass but moves",
        ),
        (
            "<robot name='x'><link name='a'/><link name='b'><inertial><mass value='1'/>
             <inertia ixx='1' iyy='1' izz='1'/></inertial></link>
             <joint name='j' type='revolute'><parent link='a'/><child link='b'/>
             <origin xyz='0 0'/><axis xyz='0 0 0'/></joint></robot>",
            "`xyz` must be 3 numbers",
        ),
        (
            "<robot name='x'><link name='a'/><link name='b'/>
             <joint name='j' type='fixed'><parent link='b'/><child link='a'/></joint>
             <joint name='k' type='fixed'><parent link='a'/><child link='b'/></joint></robot>",
            "every link is a child",
        ),
        (
            "<robot name='x'><link name='a'/><link name='a'/></robot>",
            "link `a` is defined twice",
        ),
    ];
    for (text, message) in cases {
        match convert(&Source::new("t.urdf", text)) {
            Ok(i) => panic!("accepted:\n{text}\n{}", i.source.text),
            Err(r) => {
                let out = r.to_string();
                assert!(out.contains(message), "`{message}` not in\n{out}");
                assert!(out.starts_with("t.urdf:"), "{out}");
            }
        }
    }
    // A mimic of an unknown joint is ignored with a warning (as urdfdom
    // ignores it; issue 15).
    let text = "<robot name='x'><link name='a'/><link name='b'><inertial><mass value='1'/>
             <inertia ixx='1' iyy='1' izz='1'/></inertial></link>
             <joint name='j' type='revolute'><parent link='a'/><child link='b'/>
             <mimic joint='nope'/></joint></robot>";
    let i = convert(&Source::new("t.urdf", text)).unwrap_or_else(|r| panic!("{r}"));
    assert!(
        i.warnings
            .iter()
            .any(|w| w.message.contains("names unknown joint `nope`; ignored")),
        "{:?}",
        i.warnings
    );
    assert!(i.spec.constraints.is_empty());
    // Awkward names become identifiers, and say so.
    let text = "<robot name='my-robot'><link name='base link'/><link name='arm/1'><inertial><mass value='1'/>
        <inertia ixx='1' iyy='1' izz='1'/></inertial></link>
        <joint name='sin' type='continuous'><parent link='base link'/><child link='arm/1'/></joint></robot>";
    let i = convert(&Source::new("n.urdf", text)).unwrap_or_else(|r| panic!("{r}"));
    let c = check(&i.source).unwrap_or_else(|r| panic!("{r}"));
    assert_eq!(c.system.name, "my_robot");
    assert_eq!(c.system.coordinate_names(), ["sin_"]);
    assert!(
        i.notes
            .iter()
            .any(|n| n.contains("`arm/1` is named `arm_1`"))
    );
    // Links and joints are separate namespaces: a shared name is kept.
    let text = "<robot name='r'><link name='a'/><link name='b'><inertial><mass value='1'/>
        <inertia ixx='1' iyy='1' izz='1'/></inertial></link>
        <joint name='b' type='prismatic'><parent link='a'/><child link='b'/></joint></robot>";
    let i = convert(&Source::new("s.urdf", text)).unwrap_or_else(|r| panic!("{r}"));
    let c = check(&i.source).unwrap_or_else(|r| panic!("{r}"));
    assert_eq!(c.system.coordinate_names(), ["b"]);
    assert_eq!(i.spec.bodies[0].name, "b");
}

/// arm7 written as URDF: the same generated dynamics as `models/arm7.ron`
/// (the interpreted generated programs and the numeric reference, at random
/// states).
#[test]
fn arm7_urdf_matches_arm7_ron() {
    let (_, u) = checked("arm7.urdf");
    let ron = format!("{}/../models/arm7.ron", env!("CARGO_MANIFEST_DIR"));
    let r = eom_gen::check_file(&ron).unwrap_or_else(|e| panic!("{e}"));
    compare(&u.system, &r.system, 10, 1e-12);

    let gu = eom_gen::generate_file(&path("arm7.urdf")).unwrap_or_else(|e| panic!("{e}"));
    let gr = eom_gen::generate_file(&ron).unwrap_or_else(|e| panic!("{e}"));
    let mut rng = Rng(42);
    for _ in 0..10 {
        let (q, v) = random_state(&gr.checked.system, &mut rng);
        let tau = rng.vec(7, 2.0);
        let at = |g: &eom_gen::Generated| {
            evaluate(
                &g.formulation,
                &Point {
                    sys: &g.checked.system,
                    q: &q,
                    u: &v,
                    udot: &[],
                    tau: &tau,
                    inputs: &[],
                    params: &[],
                    multipliers: &[],
                    t: 0.0,
                },
            )
        };
        let (eu, er) = (at(&gu), at(&gr));
        assert_matrix_eq(
            &[eu.get("mass_matrix").to_vec()],
            &[er.get("mass_matrix").to_vec()],
            1e-12,
            "M",
        );
        assert_matrix_eq(
            &[eu.get("bias").to_vec()],
            &[er.get("bias").to_vec()],
            1e-12,
            "bias",
        );
        assert_matrix_eq(&[eu.udot()], &[er.udot()], 1e-10, "udot");
    }
}

/// `planar` moves in the plane normal to `axis` (here y: the x-z plane).
#[test]
fn planar_joint_about_its_axis() {
    let text = "<robot name='slab'><link name='world'/>
        <link name='slab'><inertial><mass value='2'/>
        <inertia ixx='0.1' iyy='0.2' izz='0.3'/></inertial></link>
        <joint name='p' type='planar'><parent link='world'/><child link='slab'/>
        <origin xyz='0 0 1'/><axis xyz='0 1 0'/></joint></robot>";
    let i = convert(&Source::new("slab.urdf", text)).unwrap_or_else(|r| panic!("{r}"));
    let c = check(&i.source).unwrap_or_else(|r| panic!("{r}\n{}", i.source.text));
    let sys = &c.system;
    assert_eq!(sys.coordinate_names(), ["p_x", "p_y", "p_angle"]);
    let num = Numeric::new(sys).expect("numeric");
    let t = num
        .terms(&[0.3, -0.2, 0.7], &[0.0; 3], 0.0, &[])
        .expect("terms");
    // Two translations (mass 2) and the rotation about y (iyy = 0.2).
    assert_matrix_eq(
        &t.mass_matrix,
        &[
            vec![2.0, 0.0, 0.0],
            vec![0.0, 2.0, 0.0],
            vec![0.0, 0.0, 0.2],
        ],
        1e-12,
        "M",
    );
    // Gravity (−z) lies in the plane: it acts on one translation only.
    let weight = 2.0 * 9.81;
    let b: f64 = t.bias.iter().map(|b| b * b).sum::<f64>().sqrt();
    assert!(close(b, weight, 1e-12), "{:?}", t.bias);
    assert!(t.bias[2].abs() < 1e-12);
}

/// No input makes the importer panic: every truncation and many byte
/// changes of the test files are either converted or reported.
#[test]
fn no_panics_on_broken_files() {
    let mut rng = Rng(99);
    for name in [
        "arm2.urdf",
        "tree.urdf",
        "floating.urdf",
        "mimic.urdf",
        "bad.urdf",
    ] {
        let text = std::fs::read_to_string(path(name)).expect("read");
        let mut variants: Vec<String> = (0..text.len())
            .step_by(7)
            .filter(|&k| text.is_char_boundary(k))
            .map(|k| text[..k].to_string())
            .collect();
        let swaps = [
            "\"", "<", ">", "/", "0", "-1", "nan", "x", " ", "world", "fixed",
        ];
        for _ in 0..300 {
            let at = ((rng.uniform() + 1.0) / 2.0 * text.len() as f64) as usize;
            let s =
                swaps[((rng.uniform() + 1.0) / 2.0 * swaps.len() as f64) as usize % swaps.len()];
            if text.is_char_boundary(at) && text.is_char_boundary((at + 1).min(text.len())) {
                let end = (at + 1).min(text.len());
                variants.push(format!("{}{s}{}", &text[..at], &text[end..]));
            }
        }
        for v in variants {
            if let Ok(i) = convert(&Source::new(name, v.as_str())) {
                let _ = check(&i.source);
            }
        }
    }
}

/// A `floating` joint without `<parent>` (no `world` link) is a free base too.
#[test]
fn parentless_floating_root() {
    let text = "<robot name='drone'><link name='frame'><inertial><mass value='1.2'/>
        <inertia ixx='0.01' iyy='0.01' izz='0.02'/></inertial></link>
        <joint name='fly' type='floating'><child link='frame'/></joint></robot>";
    let i = convert(&Source::new("drone.urdf", text)).unwrap_or_else(|r| panic!("{r}"));
    let c = check(&i.source).unwrap_or_else(|r| panic!("{r}"));
    assert!(matches!(i.spec.joints[0].kind, JointKind::Free));
    assert_eq!(i.spec.joints[0].parent, "ground");
    assert_eq!((c.system.nq(), c.system.nu()), (7, 6));
}

/// `<visual>` shapes reach the model with their frames: on the body their
/// link is part of (a link merged through a fixed joint carries its visual
/// through that joint's origin: R_z(π/2)·(0.1, 0, 0) + (0, 0, −0.3) =
/// (0, 0.1, −0.3)), or on the ground for the welded root; colours inline
/// or by a named `<material>`; `package://visual_pkg/…` resolved to the
/// package directory above the URDF, written relative to the URDF.
#[test]
fn visuals_reach_the_model_with_their_frames() {
    let (imp, c) = checked("visual_pkg/robots/visuals.urdf");
    let v = |x: &V3| [val(&x.0), val(&x.1), val(&x.2)];
    let g = &imp.spec.bodies[0].geometry;
    assert_eq!(g.len(), 4, "{g:?}");
    let Geometry::Cylinder {
        radius,
        length,
        frame,
        color,
    } = &g[0]
    else {
        panic!("{:?}", g[0])
    };
    assert_eq!((val(radius), val(length)), (0.02, 0.5));
    assert_eq!(v(&frame.position), [0.0, 0.0, -0.25]);
    assert_eq!(*color, Some((0.25, 0.45, 0.75)));
    let Geometry::Sphere { color, .. } = &g[1] else {
        panic!("{:?}", g[1])
    };
    assert_eq!(*color, Some((1.0, 0.5, 0.0)), "the named material `orange`");
    let Geometry::Mesh { file, scale, .. } = &g[2] else {
        panic!("{:?}", g[2])
    };
    assert_eq!(file, "../meshes/pyramid.stl");
    assert_eq!(scale.as_ref().map(v), Some([0.001; 3]));
    let Geometry::Mesh { file, frame, .. } = &g[3] else {
        panic!("{:?}", g[3])
    };
    assert_eq!(file, "../meshes/cube.obj");
    let p = v(&frame.position);
    for (a, b) in p.iter().zip([0.0, 0.1, -0.3]) {
        assert!((a - b).abs() < 1e-15, "{p:?}");
    }
    assert!(matches!(
        &imp.spec.ground_geometry[..],
        [Geometry::Box { .. }]
    ));
    // The converted model validates without warnings: every mesh is there.
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    let Some(mesh) = c.system.bodies[1]
        .geometry
        .iter()
        .find_map(|g| match &g.shape {
            eom_gen::system::Shape::Mesh { path, .. } => Some(path.clone()),
            _ => None,
        })
    else {
        panic!("no mesh in the system")
    };
    assert!(mesh.is_file(), "{}", mesh.display());
}

/// A `package://` mesh that does not resolve is a warning at its
/// `filename` (the dynamics do not need it; `animate` refuses); bad sizes
/// of visuals are errors at their attributes, all at once.
#[test]
fn visuals_that_cannot_be_drawn_are_located() {
    let text = r#"<robot name="r">
  <link name="a">
    <inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="package://no_such_pkg/m.stl"/></geometry></visual>
  </link>
  <link name="b"/>
  <joint name="j" type="continuous"><parent link="b"/><child link="a"/></joint>
</robot>"#;
    let imp = convert(&Source::new("robot.urdf", text)).unwrap_or_else(|r| panic!("{r}"));
    let [w] = &imp.warnings[..] else {
        panic!("{:?}", imp.warnings)
    };
    assert!(
        w.message.contains("package://no_such_pkg/m.stl"),
        "{}",
        w.message
    );
    assert!(
        w.message.contains("no directory `no_such_pkg`"),
        "{}",
        w.message
    );
    let at = w.span.map(|s| &text[s.start..s.end]);
    assert_eq!(at, Some("package://no_such_pkg/m.stl"));
    let bad = text.replace(
        r#"<mesh filename="package://no_such_pkg/m.stl"/>"#,
        r#"<box size="1 -1 1"/></geometry></visual><visual><geometry><cylinder radius="0" length="1"/>"#,
    );
    let Err(r) = convert(&Source::new("robot.urdf", bad.clone())) else {
        panic!("bad visuals accepted")
    };
    let at: Vec<&str> = r
        .diagnostics
        .iter()
        .filter_map(|d| d.span.map(|s| &bad[s.start..s.end]))
        .collect();
    assert_eq!(at, ["1 -1 1", "0"], "{r}");
}
