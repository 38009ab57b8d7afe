//! Scenes: a scene selects outputs, locks joints and overrides which
//! parameters are inlined. The two arm7 scenes in `models/scenes/` are
//! pinned here: the end-effector scene is strictly cheaper than the full
//! one, and its forward dynamics is the full model's restricted to the
//! free joints (rows and columns of `M` and rows of `b` of the free speeds,
//! with the locked joints at their lock values and at rest).

use eom_gen::interpret::{Point, evaluate, run};
use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use eom_gen::{Generated, generate, generate_file};
use nalgebra::{DMatrix, DVector};

const MODELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../models");

fn scene(name: &str) -> Generated {
    let path = format!("{MODELS}/scenes/{name}.scene.ron");
    generate_file(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn total(p: Option<&eom_gen::sym::Program>) -> usize {
    p.map_or(0, |p| p.op_count().total())
}

#[test]
fn end_effector_scene_is_strictly_cheaper_than_the_full_scene() {
    let (full, ee) = (scene("arm7_full"), scene("arm7_ee"));
    let (ff, fe) = (&full.formulation, &ee.formulation);
    assert_eq!(full.checked.system.nu(), 7);
    assert_eq!(ee.checked.system.nu(), 5);
    let (a, b) = (
        total(ff.program(eom_gen::functions::Function::ForwardDynamics)),
        total(fe.program(eom_gen::functions::Function::ForwardDynamics)),
    );
    assert!(
        b < a,
        "forward dynamics: got {b} ops with j5, j7 locked, want < {a}"
    );
    let (a, b) = (
        total(ff.program(eom_gen::functions::Function::Outputs)),
        total(fe.program(eom_gen::functions::Function::Outputs)),
    );
    assert!(
        b < a,
        "outputs: got {b} ops for the tip position, want < {a}"
    );
    let (a, b) = (
        total(ff.program(eom_gen::functions::Function::MassMatrix)),
        total(fe.program(eom_gen::functions::Function::MassMatrix)),
    );
    assert!(b < a, "mass matrix: got {b}, want < {a}");
    let names = |g: &Generated| -> Vec<String> { g.formulation.output_names.clone() };
    assert_eq!(names(&ee), ["link7_tip_x", "link7_tip_y", "link7_tip_z"]);
    assert_eq!(names(&full).len(), 6 + 7 * 6, "tip x, v and 7 reactions");
}

/// Solves `A x = b` (small dense systems).
fn solve(a: Vec<Vec<f64>>, b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    let m = DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let x = m
        .lu()
        .solve(&DVector::from_vec(b))
        .expect("mass matrix is regular");
    x.iter().copied().collect()
}

#[test]
fn locked_scene_forward_dynamics_is_the_full_models_restricted_to_the_free_joints() {
    let ee = scene("arm7_ee");
    let full = eom_gen::check_file(&format!("{MODELS}/arm7.ron")).expect("arm7 is valid");
    let numeric = Numeric::new(&full.system).expect("numeric model");
    // Free speeds of the scene in the full model: q1, q2, q3, q4, q6.
    let free = [0usize, 1, 2, 3, 5];
    let sys = &ee.checked.system;
    assert_eq!(sys.coordinate_names(), ["q1", "q2", "q3", "q4", "q6"]);
    let mut seed = 7u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    for _ in 0..20 {
        let q: Vec<f64> = (0..5).map(|_| 3.0 * rnd()).collect();
        let u: Vec<f64> = (0..5).map(|_| 2.0 * rnd()).collect();
        let tau: Vec<f64> = (0..5).map(|_| rnd()).collect();
        // The full model with j5 and j7 at their lock values (0) and at rest.
        let mut qf = vec![0.0; 7];
        let mut uf = vec![0.0; 7];
        for (k, &i) in free.iter().enumerate() {
            qf[i] = q[k];
            uf[i] = u[k];
        }
        let terms = numeric.terms(&qf, &uf, 0.0, &[]).expect("terms");
        let m: Vec<Vec<f64>> = free
            .iter()
            .map(|&i| free.iter().map(|&j| terms.mass_matrix[i][j]).collect())
            .collect();
        let rhs: Vec<f64> = free
            .iter()
            .enumerate()
            .map(|(k, &i)| tau[k] - terms.bias[i])
            .collect();
        let want = solve(m, rhs);
        let point = Point {
            sys,
            q: &q,
            u: &u,
            udot: &[],
            tau: &tau,
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        let got = evaluate(&ee.formulation, &point).udot();
        for k in 0..5 {
            assert!(
                (got[k] - want[k]).abs() <= 1e-9 * (1.0 + want[k].abs()),
                "u̇[{k}] at q = {q:?}: got {} want {}",
                got[k],
                want[k]
            );
        }
        // The tip position agrees with the full model's kinematics too.
        let tip = run(
            ee.formulation
                .program(eom_gen::functions::Function::Outputs)
                .expect("outputs"),
            &point,
        );
        let link7 = full.system.body_id("link7").expect("link7");
        let (x, _) = numeric
            .point(link7, [0.0, 0.0, 0.3], &qf, &uf, 0.0)
            .expect("point");
        for a in 0..3 {
            assert!(
                (tip[a] - x[a]).abs() < 1e-12,
                "tip[{a}]: got {} want {}",
                tip[a],
                x[a]
            );
        }
    }
}

#[test]
fn a_lock_without_at_holds_the_joint_at_its_initial_value() {
    let text = r#"Scene(model: "../arm7.ron", lock: [(joint: "j7")])"#;
    let c = check(&Source::new(format!("{MODELS}/scenes/x.scene.ron"), text)).expect("valid");
    let j7 = &c.system.joints[c.system.joint_id("j7").expect("j7")];
    assert_eq!(j7.motion, eom_gen::system::Motion::Locked);
    assert_eq!(j7.q0[0].value, 0.05, "arm7's q0 of j7");
    assert_eq!(c.system.nq(), 6);
    assert_eq!(c.system.name, "arm7", "the model's name by default");
    // Coordinates after the locked joint are numbered again.
    assert_eq!(c.system.q0().len(), 6);
}

#[test]
fn tunable_and_fixed_override_the_model() {
    let path = format!("{MODELS}/scenes/pendulum_tunable.scene.ron");
    let text = r#"Scene(model: "../pendulum.ron", name: "pendulum_l", tunable: ["l", "m"])"#;
    let g = generate(&Source::new(path.clone(), text)).expect("valid scene");
    assert!(
        g.source.contains("pub l: f64") && g.source.contains("pub m: f64"),
        "tunable parameters are fields of the parameter struct"
    );
    // Each field carries the model's `doc` text of the parameter.
    assert!(
        g.source
            .contains("/// `l` (default 1): length of the link, m"),
        "{}",
        g.source
    );
    assert!(g.source.contains("pub struct PendulumL"));
    let params = &g.checked.system.parameters;
    assert!(
        params
            .iter()
            .find(|p| p.name == "g")
            .is_some_and(|p| !p.tunable)
    );
    // And back: a parameter the model makes tunable is inlined by `fixed`,
    // giving the same code as the model with `tunable: false`.
    let dir = std::env::temp_dir().join(format!("eom-scene-fixed-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let pendulum = std::fs::read_to_string(format!("{MODELS}/pendulum.ron")).expect("pendulum");
    let tunable = pendulum.replacen(
        "(name: \"l\", value: 1.0",
        "(name: \"l\", value: 1.0, tunable: true",
        1,
    );
    assert_ne!(tunable, pendulum, "test setup: `l` made tunable");
    let model_path = dir.join("p.ron");
    std::fs::write(&model_path, &tunable).expect("write");
    let scene_path = dir.join("p.scene.ron").display().to_string();
    let fixed = generate(&Source::new(
        scene_path,
        r#"Scene(model: "p.ron", fixed: ["l"])"#,
    ))
    .expect("valid scene");
    let as_tunable = generate_file(&model_path.display().to_string()).expect("model");
    let as_fixed = generate_file(&format!("{MODELS}/pendulum.ron")).expect("pendulum");
    assert!(as_tunable.source.contains("pub l: f64"));
    assert!(!fixed.source.contains("pub l: f64"));
    let ops = |g: &Generated| {
        total(
            g.formulation
                .program(eom_gen::functions::Function::ForwardDynamics),
        )
    };
    assert_eq!(ops(&fixed), ops(&as_fixed), "inlined again");
    assert!(ops(&fixed) <= ops(&as_tunable));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_content_hash_covers_scene_and_model() {
    let a = scene("arm7_ee");
    let text =
        std::fs::read_to_string(format!("{MODELS}/scenes/arm7_ee.scene.ron")).expect("scene");
    let b = generate(&Source::new(
        format!("{MODELS}/scenes/arm7_ee.scene.ron"),
        text.replace("doc: \"", "doc: \"(edited) "),
    ))
    .expect("valid");
    assert_ne!(a.source, b.source, "an edit of the scene changes the hash");
}

#[test]
fn builder_takes_scene_files() {
    let dir = std::env::temp_dir().join(format!("eom-scene-builder-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let written = eom_gen::Builder::new()
        .model(format!("{MODELS}/scenes/arm7_ee.scene.ron"))
        .out_dir(&dir)
        .compile()
        .expect("builds");
    assert_eq!(written, [dir.join("arm7_ee.rs")]);
    let text = std::fs::read_to_string(&written[0]).expect("written");
    assert!(text.contains("pub struct Arm7Ee"));
    assert!(text.contains("Locked joints: `j5`, `j7`"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The generated code of a virtual scene of `model` (in `models/`) that
/// asks for `functions` only.
fn functions_scene(model: &str, functions: &str) -> Generated {
    let text =
        format!("Scene(model: \"../{model}.ron\", name: \"{model}_f\", functions: [{functions}])");
    generate(&Source::new(
        format!("{MODELS}/scenes/virtual.scene.ron"),
        text,
    ))
    .unwrap_or_else(|e| panic!("{model} [{functions}]: {e}"))
}

fn close(got: f64, want: f64) -> bool {
    (got - want).abs() <= 1e-9 * (1.0 + want.abs())
}

#[test]
fn functions_a_scene_leaves_out_are_derived_and_equal_the_generated_ones() {
    // Mass matrix by columns of inverse dynamics at zero speed, bias as
    // inverse dynamics at zero acceleration, inverse dynamics as M u̇ + b:
    // all three identities of M u̇ + b = ID(q, u, u̇), checked against the
    // full model's symbolic programs at random states (times, prescribed
    // motion, springs, quaternions and loops' tree dynamics included;
    // fourbar's forward dynamics is M with LᵀDL, built although the ID
    // scene does not emit M).
    let mut seed = 11u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    for model in [
        "double_pendulum",
        "heavy_top",
        "arm7",
        "slider_crank_driven",
        "andrews",
        "fourbar",
    ] {
        let full = eom_gen::generate_file(&format!("{MODELS}/{model}.ron"))
            .unwrap_or_else(|e| panic!("{model}: {e}"));
        let id_only = functions_scene(model, "ForwardDynamics, InverseDynamics");
        let mb_only = functions_scene(model, "ForwardDynamics, MassMatrix, Bias");
        let f = &id_only.formulation;
        assert!(
            f.program(eom_gen::functions::Function::MassMatrix)
                .is_none()
                && f.program(eom_gen::functions::Function::Bias).is_none()
                && f.program(eom_gen::functions::Function::InverseDynamics)
                    .is_some(),
            "{model}: the ID scene generates ID only"
        );
        let g = &mb_only.formulation;
        assert!(
            g.program(eom_gen::functions::Function::MassMatrix)
                .is_some()
                && g.program(eom_gen::functions::Function::Bias).is_some()
                && g.program(eom_gen::functions::Function::InverseDynamics)
                    .is_none(),
            "{model}: the M, b scene generates M and b only"
        );
        assert!(
            f.program(eom_gen::functions::Function::Energy).is_some()
                && f.program(eom_gen::functions::Function::Momentum).is_some()
                && g.program(eom_gen::functions::Function::Energy).is_some(),
            "{model}: energy and momentum are always generated"
        );
        assert_eq!(
            (f.fd_form, g.fd_form),
            (full.formulation.fd_form, full.formulation.fd_form),
            "{model}: forward dynamics chooses its form as the full model does"
        );
        let sys = &full.checked.system;
        let (nq, nu) = (sys.nq(), sys.nu());
        for _ in 0..5 {
            let mut q: Vec<f64> = (0..nq).map(|_| rnd()).collect();
            for &a in &sys.quaternion_indices() {
                let n = q[a..a + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
                q[a..a + 4].iter_mut().for_each(|x| *x /= n);
            }
            let u: Vec<f64> = (0..nu).map(|_| 2.0 * rnd()).collect();
            let udot: Vec<f64> = (0..nu).map(|_| 3.0 * rnd()).collect();
            let tau: Vec<f64> = (0..nu).map(|_| rnd()).collect();
            let t = rnd().abs();
            let point = |sys| Point {
                sys,
                q: &q,
                u: &u,
                udot: &udot,
                tau: &tau,
                inputs: &[],
                params: &[],
                multipliers: &[],
                t,
            };
            let x = point(sys);
            let want_m = eom_gen::interpret::mass_matrix(&full.formulation, &x);
            let want_b = eom_gen::interpret::bias(&full.formulation, &x);
            let want_id = eom_gen::interpret::inverse_dynamics(&full.formulation, &x);
            let want_fd = evaluate(&full.formulation, &x).udot();
            for (name, s) in [("ID", &id_only), ("M, b", &mb_only)] {
                let y = point(&s.checked.system);
                let got_m = eom_gen::interpret::mass_matrix(&s.formulation, &y);
                let got_b = eom_gen::interpret::bias(&s.formulation, &y);
                let got_id = eom_gen::interpret::inverse_dynamics(&s.formulation, &y);
                let got_fd = evaluate(&s.formulation, &y).udot();
                for i in 0..nu {
                    for j in 0..nu {
                        assert!(
                            close(got_m[i][j], want_m[i][j]),
                            "{model} [{name}]: M[{i}][{j}] got {} want {}",
                            got_m[i][j],
                            want_m[i][j]
                        );
                    }
                    for (what, got, want) in [
                        ("b", &got_b, &want_b),
                        ("ID", &got_id, &want_id),
                        ("FD", &got_fd, &want_fd),
                    ] {
                        assert!(
                            close(got[i], want[i]),
                            "{model} [{name}]: {what}[{i}] got {} want {}",
                            got[i],
                            want[i]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn the_dynamics_scene_generates_less_code_than_the_full_model() {
    let full = eom_gen::generate_file(&format!("{MODELS}/arm7.ron")).expect("arm7");
    let dynamics = scene("arm7_dynamics");
    let f = &dynamics.formulation;
    assert!(
        f.program(eom_gen::functions::Function::MassMatrix)
            .is_none()
            && f.program(eom_gen::functions::Function::Bias).is_none()
    );
    assert!(
        f.program(eom_gen::functions::Function::Outputs).is_none(),
        "the scene asks for no outputs"
    );
    assert!(
        dynamics.source.len() < full.source.len(),
        "source: got {} bytes, want < {} (the full model's)",
        dynamics.source.len(),
        full.source.len()
    );
    assert!(
        dynamics
            .source
            .contains("column `i` is `ID(q, 0, e_i) − ID(q, 0, 0)`"),
        "the derived mass matrix says how it is computed"
    );
}

#[test]
fn a_scene_sets_parameter_values_and_the_initial_state() {
    // The pendulum with l = 2 m, released at θ = 0.3 rad with θ̇ = −1 rad/s:
    // the values reach the checked model (a fixed parameter inlined with
    // the scene's value), and the bob's potential energy is −m g l cos θ.
    let path = format!("{MODELS}/scenes/x.scene.ron");
    let text = r#"Scene(
        model: "../pendulum.ron",
        parameters: {"l": 2.0, "m": 3.0},
        q0: {"theta": 0.3},
        u0: {"theta_dot": -1.0},
    )"#;
    let c = check(&Source::new(path.clone(), text)).expect("valid scene");
    let sys = &c.system;
    assert_eq!(sys.q0(), [0.3]);
    assert_eq!(sys.u0(), [-1.0]);
    let g = generate(&Source::new(path.clone(), text)).expect("generates");
    let e = evaluate(
        &g.formulation,
        &Point {
            sys: &g.checked.system,
            q: &[0.3],
            u: &[-1.0],
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        },
    );
    let energy = e.get("energy");
    let (m, l, gr) = (3.0, 2.0, 9.81);
    assert!((energy[0] - 0.5 * m * l * l).abs() < 1e-12, "{energy:?}");
    assert!(
        (energy[1] + m * gr * l * 0.3f64.cos()).abs() < 1e-12,
        "{energy:?}"
    );

    // Every wrong name at once, each with the closest one.
    let bad = r#"Scene(
        model: "../pendulum.ron",
        parameters: {"len": 2.0},
        q0: {"thetta": 0.3},
        u0: {"phi": 1.0},
    )"#;
    let r = check(&Source::new(path.clone(), bad)).expect_err("unknown parameter");
    let text = r.to_string();
    assert!(text.contains("unknown parameter `len`"), "{text}");
    // The parameter is checked against the model first; then the names
    // of coordinates and speeds.
    let bad = r#"Scene(model: "../pendulum.ron", q0: {"thetta": 0.3}, u0: {"phi": 1.0})"#;
    let r = check(&Source::new(path, bad)).expect_err("unknown coordinate");
    let text = r.to_string();
    assert!(
        text.contains("unknown coordinate `thetta` in `q0`")
            && text.contains("did you mean `theta`?")
            && text.contains("unknown speed `phi` in `u0`"),
        "{text}"
    );
}

#[test]
fn a_scene_drives_an_input_by_an_expression() {
    // The pendulum with a motor at its hinge whose torque is given by the
    // scene as m g l sin θ: gravity is cancelled at every angle (θ̈ = 0),
    // and the motor's input leaves the model.
    let dir = std::env::temp_dir().join(format!("eom-scene-drive-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let pendulum = std::fs::read_to_string(format!("{MODELS}/pendulum.ron")).expect("pendulum");
    let actuated = pendulum.replacen(
        "    outputs:",
        "    forces: [Actuator(name: \"motor\", joint: \"hinge\")],\n    outputs:",
        1,
    );
    std::fs::write(dir.join("p.ron"), &actuated).expect("write");
    let scene = dir.join("p.scene.ron").display().to_string();
    let text = r#"Scene(model: "p.ron", inputs: {"motor": "g*m*l*sin(theta)"})"#;
    let g = generate(&Source::new(scene.clone(), text)).expect("valid scene");
    let sys = &g.checked.system;
    assert!(sys.inputs.is_empty(), "{:?}", sys.inputs);
    for theta in [0.3, 1.2, std::f64::consts::FRAC_PI_2] {
        let e = evaluate(
            &g.formulation,
            &Point {
                sys,
                q: &[theta],
                u: &[0.7],
                udot: &[],
                tau: &[0.0],
                inputs: &[],
                params: &[],
                multipliers: &[],
                t: 0.0,
            },
        );
        assert!(e.udot()[0].abs() < 1e-12, "θ = {theta}: {:?}", e.udot());
    }
    // Unknown inputs and names, at the scene's `inputs`.
    let bad = r#"Scene(model: "p.ron", inputs: {"motr": 1.0})"#;
    let r = check(&Source::new(scene.clone(), bad)).expect_err("unknown input");
    assert!(r.to_string().contains("did you mean `motor`?"), "{r}");
    let bad = r#"Scene(model: "p.ron", inputs: {"motor": "k*theta"})"#;
    let r = check(&Source::new(scene, bad)).expect_err("unknown name");
    assert!(
        r.to_string()
            .contains("unknown name `k` in the expression for input `motor`"),
        "{r}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
