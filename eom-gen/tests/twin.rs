//! Numeric twins: every generated program, run by the evaluator, equals the
//! `f64` run of the same algorithm at random states, for every bundled
//! model (closed loops as their spanning trees). Also: the chosen forward
//! dynamics form is the cheaper one, and op counts grow linearly with the
//! number of bodies.

use eom_gen::functions::FunctionSet;
use eom_gen::mech::{FdForm, Numeric, formulate};
use eom_gen::model::builder::n_link_chain;
use eom_gen::model::{Source, check};
use eom_gen::sym::{Program, SymKind};
use eom_gen::testkit::{Rng, random_state};
use eom_gen::{System, check_file};

fn system(name: &str) -> System {
    let path = format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    check_file(&path).unwrap_or_else(|r| panic!("{r}")).system
}

const MODELS: [&str; 13] = [
    "pendulum",
    "double_pendulum",
    "arm7",
    "heavy_top",
    "free_body",
    "fourbar",
    "slider_crank",
    "slider_crank_driven",
    "andrews",
    "bricard",
    "stewart",
    "stewart_driven",
    "rolling_disk",
];

/// The value given to the k-th model input in these tests.
fn input_value(k: usize) -> f64 {
    0.37 * (k as f64 + 1.0)
}

struct Point {
    params: Vec<(String, f64)>,
    q: Vec<f64>,
    u: Vec<f64>,
    ud: Vec<f64>,
    tau: Vec<f64>,
    t: f64,
}

fn random_point(sys: &System, rng: &mut Rng) -> Point {
    let (q, u) = random_state(sys, rng);
    let nu = sys.nu();
    Point {
        params: Vec::new(),
        q,
        u,
        ud: rng.vec(nu, 1.0),
        tau: rng.vec(nu, 1.0),
        t: rng.uniform().abs(),
    }
}

/// Runs a program with its inputs taken from the state (the evaluator of
/// `eom-gen eval --interpret`).
fn run(p: &Program, sys: &System, x: &Point) -> Vec<f64> {
    let inputs: Vec<f64> = (0..sys.inputs.len()).map(input_value).collect();
    let point = eom_gen::interpret::Point {
        sys,
        q: &x.q,
        u: &x.u,
        udot: &x.ud,
        tau: &x.tau,
        inputs: &inputs,
        params: &x.params,
        multipliers: &[],
        t: x.t,
    };
    eom_gen::interpret::run(p, &point)
}

fn assert_close(what: &str, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    let scale = want.iter().map(|x| x.abs()).fold(1.0, f64::max);
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= 1e-10 * scale,
            "{what}[{k}]: generated {g}, f64 algorithm {w}"
        );
    }
}

#[test]
fn generated_programs_equal_the_f64_algorithms() {
    let mut rng = Rng(0x1234_5678_9ABC_DEF1);
    for name in MODELS {
        let sys = system(name);
        let f =
            formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let num = Numeric::new(&sys).expect("numeric");
        for _ in 0..4 {
            let x = random_point(&sys, &mut rng);
            let what = |s: &str| format!("{name} {s}");
            let fd = num
                .forward_dynamics(&x.q, &x.u, x.t, &x.tau, &[])
                .expect("fd");
            assert_close(
                &what("forward dynamics"),
                &run(
                    f.program(eom_gen::functions::Function::ForwardDynamics)
                        .expect("fd"),
                    &sys,
                    &x,
                ),
                &fd,
            );
            let terms = num.terms(&x.q, &x.u, x.t, &[]).expect("terms");
            let lower: Vec<f64> = (0..sys.nu())
                .flat_map(|i| (0..=i).map(move |j| (i, j)))
                .map(|(i, j)| terms.mass_matrix[i][j])
                .collect();
            assert_close(
                &what("mass matrix"),
                &run(
                    f.program(eom_gen::functions::Function::MassMatrix)
                        .expect("M"),
                    &sys,
                    &x,
                ),
                &lower,
            );
            assert_close(
                &what("bias"),
                &run(
                    f.program(eom_gen::functions::Function::Bias).expect("b"),
                    &sys,
                    &x,
                ),
                &terms.bias,
            );
            let id = num
                .inverse_dynamics(&x.q, &x.u, &x.ud, x.t, &[])
                .expect("id");
            assert_close(
                &what("inverse dynamics"),
                &run(
                    f.program(eom_gen::functions::Function::InverseDynamics)
                        .expect("id"),
                    &sys,
                    &x,
                ),
                &id,
            );
            assert_close(
                &what("qdot"),
                &run(
                    f.program(eom_gen::functions::Function::Qdot).expect("qdot"),
                    &sys,
                    &x,
                ),
                &num.qdot(&x.q, &x.u),
            );
            let (t, v) = num.energy(&x.q, &x.u, x.t).expect("energy");
            assert_close(
                &what("energy"),
                &run(
                    f.program(eom_gen::functions::Function::Energy).expect("E"),
                    &sys,
                    &x,
                ),
                &[t, v],
            );
            let h = num.momentum(&x.q, &x.u, x.t).expect("momentum");
            let want = [h.n.0[0], h.n.0[1], h.n.0[2], h.f.0[0], h.f.0[1], h.f.0[2]];
            assert_close(
                &what("momentum"),
                &run(
                    f.program(eom_gen::functions::Function::Momentum)
                        .expect("h"),
                    &sys,
                    &x,
                ),
                &want,
            );
        }
    }
}

#[test]
fn the_cheaper_forward_dynamics_form_is_chosen() {
    for name in ["pendulum", "arm7", "heavy_top", "stewart"] {
        let f = formulate(&system(name), FunctionSet::all_requested()).expect("formulates");
        let chosen = f
            .fd_candidates
            .iter()
            .find(|(form, _)| *form == f.fd_form)
            .map(|(_, c)| c.total());
        let best = f.fd_candidates.iter().map(|(_, c)| c.total()).min();
        assert_eq!(chosen, best, "{name}: {:?}", f.fd_candidates);
        assert_eq!(f.fd_candidates.len(), 2);
        let _ = FdForm::Aba;
    }
}

#[test]
fn requested_outputs_equal_the_f64_kinematics() {
    // Marker positions and velocities, their Jacobians (∂v/∂u, so J u = v),
    // and joint reactions at the accelerations of forward dynamics.
    let mut rng = Rng(0x0F0F_1234_ABCD_9876);
    for name in ["pendulum", "double_pendulum", "heavy_top", "rolling_disk"] {
        let sys = system(name);
        let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
        let num = Numeric::new(&sys).expect("numeric");
        let outputs = f
            .program(eom_gen::functions::Function::Outputs)
            .expect("the model requests outputs");
        for _ in 0..3 {
            let mut x = random_point(&sys, &mut rng);
            x.tau = vec![0.0; sys.nu()];
            x.ud = num
                .forward_dynamics(&x.q, &x.u, x.t, &x.tau, &[])
                .expect("fd");
            let got = run(outputs, &sys, &x);
            let mut want = Vec::new();
            let mut velocities = Vec::new();
            for out in &sys.outputs {
                match *out {
                    eom_gen::system::OutputKind::Position(b, m) => {
                        let p = &sys.bodies[b].markers[m].frame.position;
                        let (pos, vel) = num
                            .point(b, [p[0].value, p[1].value, p[2].value], &x.q, &x.u, x.t)
                            .expect("point");
                        want.extend(pos);
                        velocities.push(vel);
                    }
                    eom_gen::system::OutputKind::JointReaction(j) => {
                        let r = num
                            .joint_reaction(j, &x.q, &x.u, &x.ud, x.t)
                            .expect("reaction")
                            .expect("tree joint");
                        want.extend(r.f.0);
                        want.extend(r.n.0);
                    }
                    _ => {}
                }
            }
            assert_close(&format!("{name} outputs"), &got, &want);
            let jac = run(
                f.program(eom_gen::functions::Function::MarkerJacobians)
                    .expect("jacobians"),
                &sys,
                &x,
            );
            let nu = sys.nu();
            let jv: Vec<f64> = jac
                .chunks(nu)
                .map(|row| row.iter().zip(&x.u).map(|(j, u)| j * u).sum())
                .collect();
            let v: Vec<f64> = velocities.iter().flatten().copied().collect();
            assert_close(&format!("{name} J u"), &jv, &v);
        }
    }
}

#[test]
fn pendulum_hinge_carries_the_tension_m_l_thetadot2_plus_m_g_cos_theta() {
    // A massless link transmits only tension along itself (body y here):
    // f = (0, m (l θ̇² + g cos θ), 0), no moment.
    let sys = system("pendulum");
    let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
    let num = Numeric::new(&sys).expect("numeric");
    for (th, w) in [(0.3, 1.2), (2.0, -0.5), (-1.0, 3.0)] {
        let ud = num
            .forward_dynamics(&[th], &[w], 0.0, &[0.0], &[])
            .expect("fd");
        let x = Point {
            params: Vec::new(),
            q: vec![th],
            u: vec![w],
            ud,
            tau: vec![0.0],
            t: 0.0,
        };
        let got = run(
            f.program(eom_gen::functions::Function::Outputs)
                .expect("outputs"),
            &sys,
            &x,
        );
        // Outputs: tip position (3), hinge force (3), hinge moment (3).
        let want = [0.0, w * w + 9.81 * f64::cos(th), 0.0, 0.0, 0.0, 0.0];
        for (k, (g, w)) in got[3..].iter().zip(want).enumerate() {
            assert!((g - w).abs() < 1e-12, "reaction[{k}] = {g}, want {w}");
        }
    }
}

/// `models/<name>.ron` with textual edits, checked.
fn variant(name: &str, edits: &[(&str, &str)]) -> System {
    let path = format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    let mut text = std::fs::read_to_string(path).unwrap_or_default();
    for (from, to) in edits {
        assert!(text.contains(from), "test setup: `{from}` not in {name}");
        text = text.replacen(from, to, 1);
    }
    check(&Source::new(name, text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

#[test]
fn tunable_parameters_locked_joints_springs_and_inputs_agree_with_f64() {
    use eom_gen::mech::NumericEnv;
    type Case = (&'static str, System, Vec<(&'static str, f64)>);
    let cases: Vec<Case> = vec![
        // Tunable length and gravity: symbols in the generated code, set at run time.
        (
            "tunable",
            variant(
                "double_pendulum",
                &[
                    (
                        "(name: \"l2\", value: 1.0,",
                        "(name: \"l2\", value: 1.0, tunable: true,",
                    ),
                    (
                        "(name: \"g\", value: 9.8,",
                        "(name: \"g\", value: 9.8, tunable: true,",
                    ),
                ],
            ),
            vec![("l2", 0.7), ("g", 3.5)],
        ),
        // A locked elbow makes one rigid compound pendulum.
        (
            "locked",
            variant(
                "double_pendulum",
                &[("q0: [\"-13*pi/18\"],", "q0: [\"-13*pi/18\"], locked: true,")],
            ),
            vec![],
        ),
        // Joint spring-dampers and actuator inputs on arm7.
        (
            "springs+inputs",
            variant(
                "arm7",
                &[(
                    "outputs: [Energy],",
                    "forces: [JointSpringDamper(name: \"s2\", joint: \"j2\", stiffness: 20, damping: 0.5, rest: 3), Actuator(name: \"m4\", joint: \"j4\"), Actuator(name: \"m6\", joint: \"j6\")], outputs: [Energy],",
                )],
            ),
            vec![],
        ),
    ];
    let mut rng = Rng(0x5555_AAAA_3333_CCCC);
    for (what, sys, params) in cases {
        let f =
            formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{what}: {e}"));
        let num = Numeric::with_env(&sys, NumericEnv::with(&sys, &params)).expect("numeric");
        let inputs: Vec<f64> = (0..sys.inputs.len()).map(input_value).collect();
        for _ in 0..3 {
            let mut x = random_point(&sys, &mut rng);
            x.params = params.iter().map(|(n, v)| (n.to_string(), *v)).collect();
            let fd = num
                .forward_dynamics(&x.q, &x.u, x.t, &x.tau, &inputs)
                .expect("fd");
            assert_close(
                &format!("{what} forward dynamics"),
                &run(
                    f.program(eom_gen::functions::Function::ForwardDynamics)
                        .expect("fd"),
                    &sys,
                    &x,
                ),
                &fd,
            );
            let terms = num.terms(&x.q, &x.u, x.t, &inputs).expect("terms");
            assert_close(
                &format!("{what} bias"),
                &run(
                    f.program(eom_gen::functions::Function::Bias).expect("b"),
                    &sys,
                    &x,
                ),
                &terms.bias,
            );
            let (t, v) = num.energy(&x.q, &x.u, x.t).expect("energy");
            assert_close(
                &format!("{what} energy"),
                &run(
                    f.program(eom_gen::functions::Function::Energy).expect("E"),
                    &sys,
                    &x,
                ),
                &[t, v],
            );
        }
        if what == "tunable" {
            let fd = f
                .program(eom_gen::functions::Function::ForwardDynamics)
                .expect("fd");
            let params: Vec<&str> = fd
                .inputs
                .iter()
                .filter(|s| s.kind == SymKind::Param)
                .map(|s| s.name.as_str())
                .collect();
            assert_eq!(params, ["g", "l2"], "tunable parameters stay symbols");
        }
        if what == "locked" {
            assert_eq!(sys.nu(), 1);
        }
    }
}

fn chain_fd(n: usize, spatial: bool) -> eom_gen::mech::Formulation {
    let text = n_link_chain(n, spatial).to_ron();
    let sys = check(&Source::new("chain", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let request: FunctionSet = [eom_gen::functions::Function::ForwardDynamics]
        .into_iter()
        .collect();
    formulate(&sys, request).expect("formulates")
}

fn chain_ops(n: usize, spatial: bool) -> usize {
    chain_fd(n, spatial)
        .program(eom_gen::functions::Function::ForwardDynamics)
        .map_or(0, |p| p.op_count().total())
}

#[test]
fn forward_dynamics_op_count_grows_linearly() {
    // Op counts are exact, so this is a test, not a benchmark:
    // ops(200)/ops(100) ≤ 2.1 for planar and spatial chains.
    for spatial in [false, true] {
        let (a, b) = (chain_ops(100, spatial), chain_ops(200, spatial));
        let ratio = b as f64 / a as f64;
        assert!(
            ratio <= 2.1,
            "spatial={spatial}: ops(200)/ops(100) = {b}/{a} = {ratio:.3}"
        );
    }
}

#[test]
#[ignore = "prints the op counts of chains; run with --ignored --nocapture"]
fn print_chain_ops() {
    for spatial in [false, true] {
        for n in [5, 10, 25, 50, 100, 200] {
            let f = chain_fd(n, spatial);
            let c: Vec<_> = f
                .fd_candidates
                .iter()
                .map(|(form, c)| (*form, c.total()))
                .collect();
            println!("spatial={spatial} n={n}: {c:?} {:.3}s", f.seconds);
        }
    }
}

/// The interpreter flattens each program once per model
/// (`Interpreted`'s tapes, `Program::tape`, its parameters resolved then)
/// and runs the flat program at every call; a one-off evaluation
/// (`evaluate_function`) flattens on the spot. Both must give the same
/// bits, for every function the table offers (the derived ones included),
/// at random states, with inputs set and with tunable parameters set after
/// the tapes were filled (`with_params` flattens again).
#[test]
fn the_interpreters_flat_programs_give_the_bits_of_one_off_evaluation() {
    use eom_gen::functions::{TABLE, When};
    use eom_gen::interpret::{Interpreted, Point, evaluate_function};
    use eom_sim::Simulate;
    let tunable = variant(
        "double_pendulum",
        &[
            (
                "(name: \"l2\", value: 1.0,",
                "(name: \"l2\", value: 1.0, tunable: true,",
            ),
            (
                "(name: \"g\", value: 9.8,",
                "(name: \"g\", value: 9.8, tunable: true,",
            ),
        ],
    );
    let mut cases: Vec<(String, System)> = [
        "arm7",
        "heavy_top",
        "fourbar",
        "slider_crank_driven",
        "stewart_driven",
    ]
    .iter()
    .map(|n| (n.to_string(), system(n)))
    .collect();
    cases.push(("tunable double_pendulum".into(), tunable));
    for (name, sys) in &cases {
        let f = formulate(sys, FunctionSet::all_requested()).expect("formulates");
        let params: Vec<(String, f64)> = if name.starts_with("tunable") {
            vec![("l2".into(), 0.7), ("g".into(), 3.5)]
        } else {
            Vec::new()
        };
        let inputs: Vec<f64> = (0..sys.inputs.len()).map(input_value).collect();
        let mut rng = Rng(11);
        let (q, u) = random_state(sys, &mut rng);
        let udot = rng.vec(sys.nu(), 1.0);
        let tau = rng.vec(sys.nu(), 1.0);
        let lambda = rng.vec(f.constraint_names.len(), 1.0);
        let at = eom_sim::Point {
            t: 0.3,
            q: &q,
            u: &u,
            udot: &udot,
            tau: &tau,
            lambda: &lambda,
        };
        let one_off = |function, params: &[(String, f64)]| {
            let x = Point {
                sys,
                q: &q,
                u: &u,
                udot: &udot,
                tau: &tau,
                inputs: &inputs,
                params,
                multipliers: &lambda,
                t: 0.3,
            };
            evaluate_function(&f, function, &x)
        };
        let check = |model: &Interpreted<'_>, params: &[(String, f64)]| {
            let mut checked = 0;
            for e in TABLE
                .iter()
                .filter(|e| f.program(e.function).is_some() || e.when == When::Requested)
            {
                let Some(want) = one_off(e.function, params) else {
                    continue;
                };
                let mut got = vec![f64::NAN; want.len()];
                assert!(model.evaluate(e.name, &at, &mut got), "{name}: {}", e.name);
                for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert!(
                        g.to_bits() == w.to_bits() || (g.is_nan() && w.is_nan()),
                        "{name}: {}[{k}]: flat {g:e}, one-off {w:e}",
                        e.name
                    );
                }
                checked += 1;
            }
            checked
        };
        // Fill the tapes with the defaults first, then set the parameters.
        let model = Interpreted::new(&f, sys).with_inputs(&inputs);
        let mut checked = check(&model, &[]);
        checked += check(&model.with_params(&params), &params);
        assert!(checked >= 12, "{name}: only {checked} functions compared");
        if !params.is_empty() {
            // The parameters reached the flat programs: u̇ moved.
            let a = one_off(eom_gen::functions::Function::ForwardDynamics, &[]);
            let b = one_off(eom_gen::functions::Function::ForwardDynamics, &params);
            assert_ne!(a, b, "{name}: l2 and g change u̇");
        }
    }
}
