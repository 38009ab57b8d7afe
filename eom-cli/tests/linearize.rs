//! `eom-gen linearize`: `A`, `B` and the eigenvalues against hand
//! derivations (pendulum upright and hanging, with a damper and with a
//! proportional drive; the double pendulum's normal modes), the JSON keys
//! and CSV; holonomic loops about equilibria in minimal coordinates (the
//! parallelogram four-bar's single mode, a mass held on a circle by a
//! constraint, whose stiffness is the constraint force's alone); and the
//! refusals (constrained states that are neither equilibria nor steady
//! motions, or not assembled; a state given to a model with cables;
//! malformed arguments: exit 2, naming what applies); models with cables
//! about their static equilibrium (a cantilever's bending frequencies
//! against Euler–Bernoulli, the trapeze's swing against its static
//! stability and the pendulum with heavy ropes); the Whipple bicycle's sweep over speed finds the weave
//! and capsize speeds of the benchmark (Meijaard et al. 2007).

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
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

fn temp_path(name: &str) -> String {
    std::env::temp_dir()
        .join(format!("eom-linearize-{}-{name}", std::process::id()))
        .to_string_lossy()
        .into_owned()
}

fn matrix(v: &serde_json::Value, key: &str) -> Vec<Vec<f64>> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("{key} in {v}"))
        .iter()
        .map(|r| {
            r.as_array()
                .expect("row")
                .iter()
                .map(|x| x.as_f64().expect("number"))
                .collect()
        })
        .collect()
}

fn close(what: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol * (1.0 + want.abs()),
        "{what}: got {got}, want {want}"
    );
}

/// `(re, im)` of every eigenvalue.
fn eigenvalues(v: &serde_json::Value) -> Vec<(f64, f64)> {
    matrix(v, "eigenvalues")
        .into_iter()
        .map(|p| (p[0], p[1]))
        .collect()
}

/// The bundled pendulum (point mass `m = 1 kg`, `l = 1 m`, `g = 9.81`):
/// `θ̈ = −(g/l) sin θ + τ/(m l²)`, so `A = [[0, 1], [−(g/l) cos θ, 0]]`,
/// `B = [[0], [1/(m l²)]]`. Hanging (`θ = 0`): `λ = ±i √(g/l)`, `ζ = 0`;
/// upright (`θ = π`): `λ = ±√(g/l)`, one unstable.
#[test]
fn pendulum_a_b_and_eigenvalues_are_the_hand_derivation() {
    let g: f64 = 9.81;
    for theta in [0.0f64, 0.3, 2.0] {
        let v = json(&[
            "linearize",
            "models/pendulum.ron",
            "--q",
            &theta.to_string(),
            "--u",
            "0.7",
            "--json",
        ]);
        let a = matrix(&v, "A");
        let b = matrix(&v, "B");
        close("A[0][0]", a[0][0], 0.0, 1e-15);
        close("A[0][1]", a[0][1], 1.0, 1e-15);
        close("A[1][0] = −(g/l) cos θ", a[1][0], -g * theta.cos(), 1e-14);
        close("A[1][1]", a[1][1], 0.0, 1e-15);
        close("B[0][0]", b[0][0], 0.0, 1e-15);
        close("B[1][0] = 1/(m l²)", b[1][0], 1.0, 1e-14);
    }
    let hanging = json(&["linearize", "models/pendulum.ron", "--q", "0", "--json"]);
    let w = g.sqrt();
    let eig = eigenvalues(&hanging);
    assert_eq!(eig.len(), 2);
    close("hanging: λ₁ = −i ω", eig[0].1, -w, 1e-12);
    close("hanging: λ₂ = +i ω", eig[1].1, w, 1e-12);
    for (re, _) in &eig {
        close("hanging: Re λ", *re, 0.0, 1e-12);
    }
    for n in hanging["natural_frequencies"].as_array().expect("list") {
        close("ω_n = √(g/l)", n.as_f64().expect("number"), w, 1e-12);
    }
    let upright = json(&[
        "linearize",
        "models/pendulum.ron",
        "--q",
        &std::f64::consts::PI.to_string(),
        "--json",
    ]);
    let mut re: Vec<f64> = eigenvalues(&upright).iter().map(|e| e.0).collect();
    re.sort_by(f64::total_cmp);
    close("upright: λ = −√(g/l)", re[0], -w, 1e-12);
    close("upright: λ = +√(g/l) (unstable)", re[1], w, 1e-12);
}

/// A parameter sets the point: on Mars (`g = 3.71`) the hanging pendulum's
/// `A[1][0] = −g/l`; the default state is the model's `θ₀ = π/2`, where
/// `A[1][0] = −g cos θ₀ = 0`.
#[test]
fn parameters_and_the_default_state_set_the_point() {
    let v = json(&[
        "linearize",
        "models/pendulum.ron",
        "--q",
        "0",
        "--param",
        "g=3.71",
        "--json",
    ]);
    close("A[1][0] = −3.71", matrix(&v, "A")[1][0], -3.71, 1e-14);
    let v = json(&["linearize", "models/pendulum.ron", "--json"]);
    assert_eq!(v["q"][0].as_f64(), Some(std::f64::consts::FRAC_PI_2));
    close("A[1][0] at θ₀ = π/2", matrix(&v, "A")[1][0], 0.0, 1e-14);
    for key in [
        "A",
        "B",
        "eigenvalues",
        "coordinates",
        "speeds",
        "inputs",
        "natural_frequencies",
        "damping_ratios",
    ] {
        assert!(!v[key].is_null(), "`{key}` in {v}");
    }
    assert_eq!(v["coordinates"], serde_json::json!(["theta"]));
    assert_eq!(v["speeds"], serde_json::json!(["theta_dot"]));
    assert_eq!(v["inputs"], serde_json::json!(["tau(theta_dot)"]));
}

/// The double pendulum (`m1 = m2 = 1 kg`, `l1 = l2 = 1 m`, `g = 9.8`)
/// hanging: undamped normal modes `λ = ±iω`, `ω² = g (2 ∓ √2)`
/// (`m1 l1 l2 ω⁴ − (m1+m2) g (l1+l2) ω² + (m1+m2) g² = 0`), `ζ = 0`.
#[test]
fn double_pendulum_normal_modes() {
    let v = json(&[
        "linearize",
        "models/double_pendulum.ron",
        "--q",
        "0,0",
        "--u",
        "0,0",
        "--json",
    ]);
    let g: f64 = 9.8;
    let (slow, fast) = (
        (g * (2.0 - 2f64.sqrt())).sqrt(),
        (g * (2.0 + 2f64.sqrt())).sqrt(),
    );
    let eig = eigenvalues(&v);
    let want = [-slow, slow, -fast, fast];
    assert_eq!(eig.len(), 4);
    for ((re, im), w) in eig.iter().zip(want) {
        close("Re λ", *re, 0.0, 1e-12);
        close("Im λ = ±ω", *im, w, 1e-12);
    }
    for z in v["damping_ratios"].as_array().expect("list") {
        close("ζ", z.as_f64().expect("number"), 0.0, 1e-12);
    }
    // Mode shapes: in absolute angles φ2/φ1 = ±√2 (slow, fast), so in the
    // relative ones q2/q1 = φ2/φ1 − 1 = √2 − 1 and −(√2 + 1); scaled to a
    // largest entry of 1: (1, √2 − 1) and (−(√2 − 1), 1), real.
    let r = 2f64.sqrt() - 1.0;
    let shapes = v["mode_shapes"].as_array().expect("mode_shapes");
    for (k, want) in [(0, [1.0, r]), (1, [1.0, r]), (2, [-r, 1.0]), (3, [-r, 1.0])] {
        let shape = shapes[k].as_array().expect("a shape");
        for (i, w) in want.iter().enumerate() {
            let c = shape[i].as_array().expect("[re, im]");
            let (re, im) = (c[0].as_f64().expect("re"), c[1].as_f64().expect("im"));
            close(&format!("mode {k} q{} re", i + 1), re, *w, 1e-9);
            close(&format!("mode {k} q{} im", i + 1), im, 0.0, 1e-9);
        }
    }
    assert_eq!(v["mode_coordinates"], serde_json::json!(["q1", "q2"]));
}

/// A model file next to the bundled pendulum with a hinge damper
/// (`c = 0.5 N·m·s`) and an actuator `motor` at the hinge.
fn damped_actuated_pendulum() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/pendulum.ron");
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let from = "outputs: [";
    assert!(text.contains(from), "test setup");
    let text = text.replacen(
        from,
        "forces: [JointSpringDamper(name: \"d\", joint: \"hinge\", stiffness: 0, damping: 0.5, rest: 0), Actuator(name: \"motor\", joint: \"hinge\")],\n    outputs: [",
        1,
    );
    let model = temp_path("damped_pendulum.ron");
    std::fs::write(&model, text).expect("temp model");
    model
}

/// With the damper, `θ̈ = −g sin θ − c θ̇ + motor` (`m = l = 1`): hanging,
/// `A = [[0, 1], [−g, −c]]`, `B = [[0], [1]]` (the input's column), and
/// `λ = −c/2 ± i √(g − c²/4)`, `ω_n = √g`, `ζ = c/(2√g)`. Driving the
/// motor by `−k θ` (a proportional controller, `k = 5`) stiffens it:
/// `A[1][0] = −(g + k)`, and the input leaves `B` (τ's column instead).
#[test]
fn damping_inputs_and_drives() {
    let model = damped_actuated_pendulum();
    let (g, c, k): (f64, f64, f64) = (9.81, 0.5, 5.0);
    let v = json(&["linearize", &model, "--q", "0", "--json"]);
    let a = matrix(&v, "A");
    close("A[1][0] = −g", a[1][0], -g, 1e-14);
    close("A[1][1] = −c", a[1][1], -c, 1e-14);
    assert_eq!(v["inputs"], serde_json::json!(["motor"]));
    assert_eq!(v["input_kind"], "inputs");
    close("B[1][0] = 1/(m l²)", matrix(&v, "B")[1][0], 1.0, 1e-14);
    let eig = eigenvalues(&v);
    for (re, im) in &eig {
        close("Re λ = −c/2", *re, -c / 2.0, 1e-12);
        close(
            "|Im λ| = √(g − c²/4)",
            im.abs(),
            (g - c * c / 4.0).sqrt(),
            1e-12,
        );
    }
    for z in v["damping_ratios"].as_array().expect("list") {
        close(
            "ζ = c/(2√g)",
            z.as_f64().expect("number"),
            c / (2.0 * g.sqrt()),
            1e-12,
        );
    }
    let v = json(&[
        "linearize",
        &model,
        "--q",
        "0",
        "--input",
        &format!("motor=-{k}*theta"),
        "--json",
    ]);
    close(
        "driven: A[1][0] = −(g + k)",
        matrix(&v, "A")[1][0],
        -(g + k),
        1e-14,
    );
    assert_eq!(v["input_kind"], "generalized_forces");
    // A held input is an operating point: `A` is that of the free motor.
    let v = json(&[
        "linearize",
        &model,
        "--q",
        "0",
        "--input",
        "motor=2",
        "--json",
    ]);
    close("held: A[1][0] = −g", matrix(&v, "A")[1][0], -g, 1e-14);
    let _ = std::fs::remove_file(&model);
}

/// `--csv` writes one row per eigenvalue; the text form prints `A`, `B`
/// and the eigenvalues.
#[test]
fn csv_and_text() {
    let csv = temp_path("eig.csv");
    let out = eom_gen(&[
        "linearize",
        "models/pendulum.ron",
        "--q",
        "0",
        "--csv",
        &csv,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    for want in ["A\n", "B\n", "eigenvalues", "theta_dot", "ζ"] {
        assert!(text.contains(want), "`{want}` in {text}");
    }
    let written = std::fs::read_to_string(&csv).unwrap_or_default();
    let lines: Vec<&str> = written.lines().collect();
    assert_eq!(lines[0], "re,im,natural_frequency,damping_ratio");
    assert_eq!(lines.len(), 3, "{written}");
    let _ = std::fs::remove_file(&csv);
}

/// What is not linearised is refused by name with exit status 2, and
/// nothing is printed on standard output: never a wrong `A`.
#[test]
fn refusals_name_what_is_supported() {
    let cases: [(&[&str], &str); 8] = [
        // Moving, on a curved constraint manifold (the parallelogram
        // four-bar's is flat: it is linearised about any state).
        (
            &["linearize", "models/slider_crank.ron"],
            "neither an equilibrium nor a steady motion",
        ),
        (
            &[
                "linearize",
                "models/fourbar.ron",
                "--q",
                "0.1,0,0",
                "--u",
                "0,0,0",
            ],
            "does not satisfy the constraints",
        ),
        // At rest but not at equilibrium: the platform falls.
        (
            &["linearize", "models/stewart.ron"],
            "neither an equilibrium nor a steady motion",
        ),
        // Leaning by 1e-3 rad, and its spin carried in the free joint's
        // quaternion (periodic body-axis speeds, not a cyclic angle).
        (
            &["linearize", "models/rolling_disk.ron", "--param", "lean=0"],
            "neither an equilibrium nor a steady motion",
        ),
        (
            &["linearize", "models/ancf/crane_rope.ron", "--q", "0"],
            "linearised about its static equilibrium",
        ),
        (
            &["linearize", "models/pendulum.ron", "--q", "0,1"],
            "--q has 2 value(s), the model has 1",
        ),
        (
            &["linearize", "models/pendulum.ron", "--param", "gg=1"],
            "has no parameter `gg`",
        ),
        (&["linearize", "models/pendulum.ron", "--u", "x"], "--u"),
    ];
    for (args, want) in cases {
        let out = eom_gen(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: `{want}` in {err}");
        assert!(out.stdout.is_empty(), "{args:?}: nothing on stdout");
    }
}

/// A quaternion model at rest is linearised in the tangent space: the heavy
/// top has 4 coordinates but 3 speeds, so `A` is 6 × 6 with `∂δq̇/∂u = I`.
#[test]
fn quaternions_at_rest_in_the_tangent_space() {
    let v = json(&[
        "linearize",
        "models/heavy_top.ron",
        "--u",
        "0,0,0",
        "--json",
    ]);
    let a = matrix(&v, "A");
    assert_eq!(a.len(), 6);
    for (i, row) in a.iter().take(3).enumerate() {
        for (j, x) in row.iter().enumerate() {
            let want = if j == i + 3 { 1.0 } else { 0.0 };
            close(&format!("A[{i}][{j}]"), *x, want, 0.0);
        }
    }
    assert_eq!(v["coordinates"].as_array().map(Vec::len), Some(3));
}

/// The bundled parallelogram four-bar (three uniform rods, `m = 1 kg`,
/// `L = 1 m`, `g = 9.81`) hanging (`φ1 = φ3 = π`, `φ2 = −π`): one degree
/// of freedom, the crank angle `θ`; the cranks turn about their pivots
/// (`m L²/3` each) and the coupler translates (`m L²`), so
/// `T = ½ (5/3) m L² θ̇²`; the centres sink by `L/2`, `L`, `L/2` times
/// `cos θ`, so `V = −2 m g L cos θ`. `θ̈ = −(6g/5L) θ`: `λ = ±i √(6g/5L)`.
/// Upright (all zero) the same with `λ = ±√(6g/5L)`.
#[test]
fn fourbar_single_mode_in_minimal_coordinates() {
    let pi = std::f64::consts::PI;
    let w2 = 6.0 * 9.81 / 5.0;
    let hanging = format!("{pi},{},{pi}", -pi);
    let v = json(&[
        "linearize",
        "models/fourbar.ron",
        "--q",
        &hanging,
        "--u",
        "0,0,0",
        "--json",
    ]);
    assert_eq!(v["states"], serde_json::json!(["z1", "z1_dot"]), "one mode");
    let a = matrix(&v, "A");
    close("A[1][0] = −6g/5L", a[1][0], -w2, 1e-9);
    close("A[1][1] = 0", a[1][1], 0.0, 1e-9);
    for (re, im) in eigenvalues(&v) {
        close("Re λ", re, 0.0, 1e-9);
        close("|Im λ| = √(6g/5L)", im.abs(), w2.sqrt(), 1e-9);
    }
    // δq = Z z: the cranks turn together and the coupler against them;
    // the mode shape over (φ1, φ2, φ3) is (1, −1, 1).
    let z: Vec<f64> = matrix(&v, "basis").iter().map(|r| r[0]).collect();
    let third = (1.0f64 / 3.0).sqrt();
    for (k, want) in [third, -third, third].into_iter().enumerate() {
        close(&format!("Z[{k}]"), z[k], want, 1e-9);
    }
    for shape in v["mode_shapes"].as_array().expect("mode_shapes") {
        for (i, want) in [1.0, -1.0, 1.0].into_iter().enumerate() {
            let re = shape[i][0].as_f64().expect("re");
            close(&format!("mode shape φ{}", i + 1), re, want, 1e-9);
        }
    }
    let v = json(&[
        "linearize",
        "models/fourbar.ron",
        "--q",
        "0,0,0",
        "--u",
        "0,0,0",
        "--json",
    ]);
    let mut re: Vec<f64> = eigenvalues(&v).iter().map(|e| e.0).collect();
    re.sort_by(f64::total_cmp);
    close("upright: λ = −√(6g/5L)", re[0], -w2.sqrt(), 1e-9);
    close("upright: λ = +√(6g/5L)", re[1], w2.sqrt(), 1e-9);
}

/// A bob (`m = 2 kg`) on a carriage (`m_c = 1 kg`) sliding along x, the bob
/// sliding along y on it, held on the circle `x² + y² = l²` (`l = 0.5 m`)
/// by a holonomic constraint. In these Cartesian coordinates gravity has
/// no stiffness: the restoring force is the constraint force's turning
/// (`∂(Jᵀλ₀)/∂q`, `λ₀` carrying the bob's weight). Hanging, `x` is the
/// free direction: `T = ½ (m_c + m) ẋ²`, `V = −m g √(l² − x²) ≈ m g x²/(2l)`,
/// so `ω² = m g / (l (m_c + m))` = 13.08 /s².
#[test]
fn constraint_forces_stiffen_a_mass_on_a_circle() {
    let text = r#"Model(
    name: "circle_pendulum",
    gravity: (0, "-g", 0),
    parameters: [
        (name: "g", value: 9.81),
        (name: "m", value: 2.0),
        (name: "mc", value: 1.0),
        (name: "l", value: 0.5),
    ],
    bodies: [(name: "carriage", mass: "mc"), (name: "bob", mass: "m")],
    joints: [
        (name: "jx", kind: Prismatic(axis: (1, 0, 0)), parent: "ground", child: "carriage", coordinates: ["x"], q0: [0]),
        (name: "jy", kind: Prismatic(axis: (0, 1, 0)), parent: "carriage", child: "bob", coordinates: ["y"], q0: ["-l"]),
    ],
    constraints: [Holonomic(name: "rod", expr: "x^2 + y^2 - l^2")],
)
"#;
    let model = temp_path("circle_pendulum.ron");
    std::fs::write(&model, text).expect("temp model");
    let v = json(&["linearize", &model, "--json"]);
    let (g, m, mc, l) = (9.81, 2.0, 1.0, 0.5);
    let w2 = m * g / (l * (mc + m));
    close(
        "A[1][0] = −m g/(l (m_c + m))",
        matrix(&v, "A")[1][0],
        -w2,
        1e-8,
    );
    for (re, im) in eigenvalues(&v) {
        close("Re λ", re, 0.0, 1e-8);
        close("|Im λ| = ω", im.abs(), w2.sqrt(), 1e-8);
    }
    let _ = std::fs::remove_file(&model);
}

/// `--sweep g=1:9:5`: the hanging pendulum's `λ = ±i √(g/l)` at each of
/// the five values (the model regenerated at each); `--csv` has one row per
/// eigenvalue and value, `--svg` draws them; points that cannot be
/// linearised are named with why (exit 3), malformed sweeps are usage
/// errors (exit 2).
#[test]
fn sweep_gives_the_eigenvalues_against_a_parameter() {
    let csv = temp_path("sweep.csv");
    let svg = temp_path("sweep.svg");
    let v = json(&[
        "linearize",
        "models/pendulum.ron",
        "--q",
        "0",
        "--sweep",
        "g=1:9:5",
        "--csv",
        &csv,
        "--svg",
        &svg,
        "--json",
    ]);
    let values: Vec<f64> = v["values"]
        .as_array()
        .expect("values")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect();
    assert_eq!(values, [1.0, 3.0, 5.0, 7.0, 9.0]);
    for (g, eig) in values
        .iter()
        .zip(v["eigenvalues"].as_array().expect("list"))
    {
        for l in eig.as_array().expect("eigenvalues") {
            let (re, im) = (l[0].as_f64().expect("re"), l[1].as_f64().expect("im"));
            close(&format!("g = {g}: Re λ"), re, 0.0, 1e-12);
            close(&format!("g = {g}: |Im λ| = √g"), im.abs(), g.sqrt(), 1e-12);
        }
    }
    let rows = std::fs::read_to_string(&csv).unwrap_or_default();
    assert_eq!(rows.lines().count(), 1 + 5 * 2, "{rows}");
    assert!(rows.starts_with("g,k,re,im,natural_frequency,damping_ratio\n"));
    let drawn = std::fs::read_to_string(&svg).unwrap_or_default();
    assert!(drawn.contains("<svg") && drawn.contains("Re λ"), "an SVG");
    let _ = std::fs::remove_file(&csv);
    let _ = std::fs::remove_file(&svg);
    // The slider-crank moving at its initial state is no steady motion at
    // any rod length.
    let out = eom_gen(&[
        "linearize",
        "models/slider_crank.ron",
        "--sweep",
        "l=0.3:0.4:2",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(3));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert!(
        v["errors"][0]
            .as_str()
            .is_some_and(|e| e.contains("neither an equilibrium nor a steady motion"))
    );
    for args in [
        &["linearize", "models/pendulum.ron", "--sweep", "g=1:2"][..],
        &["linearize", "models/pendulum.ron", "--sweep", "g=1:2:1"],
        &[
            "linearize",
            "models/pendulum.ron",
            "--sweep",
            "g=1:2:3",
            "--param",
            "g=2",
        ],
        &["linearize", "models/pendulum.ron", "--svg", "x.svg"],
    ] {
        let out = eom_gen(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
}

/// `models/whipple.ron` swept over its forward speed: the stability
/// boundaries are located by bisection and a secant step on the crossing
/// eigenvalue — the weave speed (the weave pair enters the left
/// half-plane, at ±3.435 rad/s) and the capsize speed (a real eigenvalue
/// leaves it) — against the values of the benchmark's published matrices,
/// 4.2923825363 and 6.0242620154 m/s (the paper: 4.292 382 5 and
/// 6.024 262 0).
#[test]
fn whipple_sweep_finds_the_weave_and_capsize_speeds() {
    let v = json(&[
        "linearize",
        "models/whipple.ron",
        "--sweep",
        "v=3:7:3",
        "--json",
    ]);
    let crossings = v["crossings"].as_array().expect("crossings");
    assert_eq!(crossings.len(), 2, "{v}");
    let field = |k: usize, key: &str| crossings[k][key].as_f64().expect("number");
    close("weave speed", field(0, "value"), 4.2923825363, 1e-10);
    close("weave frequency", field(0, "frequency"), 3.435034, 1e-6);
    assert_eq!(crossings[0]["unstable_below"], 2);
    assert_eq!(crossings[0]["unstable_above"], 0);
    close("capsize speed", field(1, "value"), 6.0242620154, 1e-10);
    assert_eq!(field(1, "frequency"), 0.0);
    assert_eq!(crossings[1]["unstable_above"], 1);
}

/// A clamped steel cantilever of ANCF cables (L = 2 m, 0.1 m square,
/// E = 207 GPa, ρ = 7800 kg/m³), unloaded, linearised about its straight
/// equilibrium: its bending frequencies converge to Euler–Bernoulli's
/// `ω_n = (β_n L)² √(EI/(ρA L⁴))` (`β₁L = 1.8751`, `β₂L = 4.6941`), the
/// error falling by more than 8× from 4 to 8 elements, and its first axial
/// frequency to the bar's `π/(2L) √(E/ρ)` at first order in the element
/// length: the error halves (`Clamped` holds the gradient's length at the
/// root too, so the axial strain there is held at zero — BENCHMARKS.md).
#[test]
fn cable_cantilever_frequencies_converge_to_the_beam_and_bar() {
    let frequencies = |elements: usize| -> Vec<f64> {
        let path = temp_path(&format!("cantilever{elements}.ron"));
        let text = format!(
            r#"Model(
    name: "free_cantilever",
    bodies: [],
    joints: [],
    cables: [Cable(name: "beam", element: Cable2D, from: (0, 0, 0), to: (2, 0, 0),
        elements: {elements}, young: 2.07e11, density: 7800, width: 0.1, height: 0.1,
        start: Clamped)],
)"#
        );
        std::fs::write(&path, text).expect("writes");
        let v = json(&["linearize", &path, "--json"]);
        let _ = std::fs::remove_file(&path);
        let mut w: Vec<f64> = eigenvalues(&v)
            .iter()
            .filter(|(re, im)| *im > 0.0 && re.abs() < 1e-6 * im)
            .map(|(_, im)| *im)
            .collect();
        w.sort_by(f64::total_cmp);
        w
    };
    let (e, rho, l, b) = (2.07e11f64, 7800.0f64, 2.0f64, 0.1f64);
    let (area, inertia) = (b * b, b.powi(4) / 12.0);
    let bending = |bl: f64| bl * bl * (e * inertia / (rho * area * l.powi(4))).sqrt();
    let axial = std::f64::consts::PI / (2.0 * l) * (e / rho).sqrt();
    let (w4, w8) = (frequencies(4), frequencies(8));
    // Bending 1 and 2, then the axial mode (below bending 4).
    for (k, exact) in [
        (0, bending(1.875_104_068_711_961)),
        (1, bending(4.694_091_132_974_175)),
    ] {
        let (e4, e8) = ((w4[k] - exact).abs(), (w8[k] - exact).abs());
        assert!(e8 < 1e-4 * exact, "bending {}: {} vs {exact}", k + 1, w8[k]);
        assert!(
            e4 > 8.0 * e8,
            "bending {}: errors {e4:.3e}, {e8:.3e}",
            k + 1
        );
    }
    let nearest = |w: &[f64]| {
        w.iter()
            .copied()
            .min_by(|x, y| (x - axial).abs().total_cmp(&(y - axial).abs()))
            .expect("modes")
    };
    let (a4, a8) = (nearest(&w4) - axial, nearest(&w8) - axial);
    assert!(a8 > 0.0 && a8 < 0.02 * axial, "axial {a8:.3e} off {axial}");
    assert!(
        (a4 / a8 - 2.0).abs() < 0.2,
        "first order: {a4:.3e}, {a8:.3e}"
    );
}

/// `models/ancf/trapeze.ron` (a 2 kg bar hanging from two 1 m ropes of
/// 32 g): about the equilibrium `linearize` finds, the lowest ω² is the
/// smallest ω² of the reduced tangent that `solve-static` reports for the
/// same equilibrium (an independent computation: the statics' KKT
/// matrix), and near the pendulum with heavy ropes,
/// `ω² = g (M + m_r/2) / (L (M + m_r/3))` (m_r both ropes, the ropes'
/// 0.35 mm stretch aside).
#[test]
fn trapeze_swing_about_its_equilibrium() {
    let v = json(&["linearize", "models/ancf/trapeze.ron", "--json"]);
    let lowest = eigenvalues(&v)
        .iter()
        .map(|(re, im)| re.hypot(*im))
        .filter(|w| *w > 1e-6)
        .fold(f64::INFINITY, f64::min);
    let s = json(&["solve-static", "models/ancf/trapeze.ron", "--json"]);
    let omega2 = s["stability"]["omega2_min"]
        .as_f64()
        .unwrap_or_else(|| panic!("omega2_min in {}", s["stability"]));
    close("ω² against the statics", lowest * lowest, omega2, 1e-7);
    let (g, big_m, l) = (9.81f64, 2.0f64, 1.0f64);
    let rope = 2.0 * 1150.0 * std::f64::consts::PI * 0.006f64.powi(2) / 4.0 * l;
    let pendulum = g * (big_m + rope / 2.0) / (l * (big_m + rope / 3.0));
    close(
        "ω² against the heavy-rope pendulum",
        lowest * lowest,
        pendulum,
        1e-3,
    );
}
