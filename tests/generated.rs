//! The committed generated code (`generated/`), compiled: every function
//! equals the `f64` reference algorithms at random states (1e-12 relative),
//! the files are fresh (regenerating gives the same bytes), and generation
//! is deterministic.

use eom_gen::mech::Numeric;
use eom_gen::testkit::Rng;
use eom_gen::{Source, System, check_file, generate};
use eom_generated as g;
use eom_sim::{Model, Vector};

// `generated_files`: the modules of `generated/src/`, as the regenerate
// example writes them.
include!("../generated/files.rs");

fn path(name: &str) -> String {
    format!("{}/models/{name}.ron", env!("CARGO_MANIFEST_DIR"))
}

fn system(name: &str) -> System {
    check_file(&path(name))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

fn vector<V: Vector>(values: &[f64]) -> V {
    let mut v = V::ZERO;
    v.as_mut().copy_from_slice(values);
    v
}

fn close(what: &str, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    let scale = want.iter().map(|x| x.abs()).fold(1.0, f64::max);
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= 1e-12 * scale,
            "{what}[{k}]: compiled {g}, f64 algorithm {w}"
        );
    }
}

/// Compares every function of a compiled model with the reference numerics.
fn compare<M: Model + Default>(name: &str) {
    let sys = system(name);
    let num = Numeric::new(&sys).expect("numeric");
    let formulation =
        eom_gen::mech::formulate(&sys, eom_gen::functions::FunctionSet::all_requested())
            .expect("formulates");
    let model = M::default();
    assert_eq!((M::NQ, M::NU), (sys.nq(), sys.nu()), "{name}: sizes");
    assert_eq!(M::COORDINATE_NAMES, sys.coordinate_names().as_slice());
    close(&format!("{name} q0"), model.q0().as_ref(), &sys.q0());
    let mut rng = Rng(0xC0FF_EE00_1234_5678);
    // Elastic coordinates of flexible bodies (modal amplitudes of a linear
    // model of small deformation) get millimetre-sized offsets, the joint
    // coordinates up to 0.8.
    let mut amplitude = vec![0.8; sys.nq()];
    for (_, flex) in sys.flexible_bodies() {
        amplitude[flex.q_index..flex.q_index + flex.count()].fill(1e-3);
    }
    for _ in 0..5 {
        let mut qv: Vec<f64> = sys
            .q0()
            .iter()
            .zip(&amplitude)
            .map(|(q, a)| q + a * rng.uniform())
            .collect();
        let mut q: M::Q = vector(&qv);
        model.normalize(&mut q);
        qv = q.as_ref().to_vec();
        let uv: Vec<f64> = (0..M::NU).map(|_| 1.5 * rng.uniform()).collect();
        let tauv: Vec<f64> = (0..M::NU).map(|_| rng.uniform()).collect();
        let t = rng.uniform().abs();
        let (u, tau): (M::U, M::U) = (vector(&uv), vector(&tauv));
        let mut out_u = M::U::ZERO;
        model.forward_dynamics(t, &q, &u, &tau, &mut out_u);
        let fd = num.forward_dynamics(&qv, &uv, t, &tauv, &[]).expect("fd");
        close(&format!("{name} forward dynamics"), out_u.as_ref(), &fd);
        let terms = num.terms(&qv, &uv, t, &[]).expect("terms");
        let mut tau_back = M::U::ZERO;
        model.inverse_dynamics(t, &q, &u, &vector::<M::U>(&fd), &mut tau_back);
        // τ = M u̇ + b: the round trip τ → u̇ → τ cancels M u̇ against b, so
        // its rounding error is relative to the largest of τ, M u̇ and b (a
        // stiff elastic mode at a random deformation has |K q_f| ~ 1e5 for
        // |τ| ~ 1); for rigid models all three are of the size of τ.
        let m_ud = terms
            .mass_matrix
            .iter()
            .map(|row| row.iter().zip(&fd).map(|(m, a)| m * a).sum::<f64>().abs())
            .fold(1.0, f64::max);
        let tau_scale = tauv
            .iter()
            .chain(&terms.bias)
            .map(|x| x.abs())
            .fold(m_ud, f64::max);
        for (k, (g, w)) in tau_back.as_ref().iter().zip(&tauv).enumerate() {
            assert!(
                (g - w).abs() <= 1e-12 * tau_scale,
                "{name} inverse dynamics[{k}]: compiled {g}, τ {w} (scale {tau_scale})"
            );
        }
        let mut m = M::MASS_ZERO;
        model.mass_matrix(t, &q, &mut m);
        for (i, row) in m.as_ref().iter().enumerate() {
            close(
                &format!("{name} M row {i}"),
                row.as_ref(),
                &terms.mass_matrix[i],
            );
        }
        let mut b = M::U::ZERO;
        model.bias(t, &q, &u, &mut b);
        close(&format!("{name} bias"), b.as_ref(), &terms.bias);
        let mut qd = M::Q::ZERO;
        model.qdot(&q, &u, &mut qd);
        close(&format!("{name} qdot"), qd.as_ref(), &num.qdot(&qv, &uv));
        let (ke, pe) = num.energy(&qv, &uv, t).expect("energy");
        close(
            &format!("{name} energy"),
            &model.energy(t, &q, &u),
            &[ke, pe],
        );
        // Outputs (markers, reactions) against the same programs run by the
        // evaluator (which the numeric twins check against the f64 algorithms).
        let mut out = M::Outputs::ZERO;
        model.outputs(t, &q, &u, &vector::<M::U>(&fd), &mut out);
        if let Some(p) = formulation.program(eom_gen::functions::Function::Outputs) {
            let x = eom_gen::interpret::Point {
                sys: &sys,
                q: &qv,
                u: &uv,
                udot: &fd,
                tau: &[],
                inputs: &[],
                params: &[],
                multipliers: &[],
                t,
            };
            close(
                &format!("{name} outputs"),
                out.as_ref(),
                &eom_gen::interpret::run(p, &x),
            );
        }
        let h = num.momentum(&qv, &uv, t).expect("momentum");
        let want = [h.n.0[0], h.n.0[1], h.n.0[2], h.f.0[0], h.f.0[1], h.f.0[2]];
        close(
            &format!("{name} momentum"),
            &model.momentum(t, &q, &u),
            &want,
        );
    }
}

#[test]
fn compiled_models_equal_the_f64_algorithms() {
    compare::<g::pendulum::Pendulum>("pendulum");
    compare::<g::double_pendulum::DoublePendulum>("double_pendulum");
    compare::<g::arm7::Arm7>("arm7");
    compare::<g::heavy_top::HeavyTop>("heavy_top");
    compare::<g::free_body::FreeBody>("free_body");
    compare::<g::fourbar::Fourbar>("fourbar");
    compare::<g::slider_crank::SliderCrank>("slider_crank");
    compare::<g::slider_crank_driven::SliderCrankDriven>("slider_crank_driven");
    compare::<g::andrews::Andrews>("andrews");
    compare::<g::bricard::Bricard>("bricard");
    compare::<g::stewart::Stewart>("stewart");
    compare::<g::stewart_driven::StewartDriven>("stewart_driven");
    compare::<g::rolling_disk::RollingDisk>("rolling_disk");
    compare::<g::arm7_flex::Arm7Flex>("arm7_flex");
    compare::<g::slider_crank_flex::SliderCrankFlex>("slider_crank_flex");
    compare::<g::slider_crank_simeon::SliderCrankSimeon>("slider_crank_simeon");
    compare::<g::spin_up::SpinUp>("spin_up");
    compare::<g::hub_beam::HubBeam>("hub_beam");
}

#[test]
fn generated_sources_are_fresh() {
    let mut stale = Vec::new();
    // The regenerate example's list: every model, the mixed models' rigid
    // parts and the scenes.
    let files = generated_files(env!("CARGO_MANIFEST_DIR")).unwrap_or_default();
    assert!(!files.is_empty(), "no models found");
    for (name, path) in &files {
        let text = std::fs::read_to_string(format!("{}/{path}", env!("CARGO_MANIFEST_DIR")))
            .unwrap_or_default();
        let opts = eom_gen::EmitOptions {
            lanes: true,
            ..Default::default()
        };
        let fresh = eom_gen::generate_with(&Source::new(path.clone(), text), &opts)
            .unwrap_or_else(|e| panic!("{e}"))
            .source;
        let committed = std::fs::read_to_string(format!(
            "{}/generated/src/{name}.rs",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap_or_default();
        if fresh != committed {
            stale.push(name.to_string());
        }
    }
    assert!(
        stale.is_empty(),
        "generated/ is stale for {stale:?}; refresh with `cargo run -p eom-gen --example regenerate`"
    );
}

#[test]
fn generation_is_deterministic() {
    for name in ["arm7", "stewart", "andrews"] {
        let text = std::fs::read_to_string(path(name)).unwrap_or_default();
        let a = generate(&Source::new(name, text.clone()))
            .expect("generates")
            .source;
        let b = generate(&Source::new(name, text))
            .expect("generates")
            .source;
        assert!(a == b, "{name}: two generations differ");
    }
}

/// Every function the compiled model offers through `Model::evaluate`
/// (the table of generated functions) against the evaluator running the
/// same programs, and the two functions only the table adds against
/// independent numerics: the marker Jacobians against central differences
/// of the marker positions along `q̇ = N(q) e_k`, the cut joints'
/// reactions against the `f64` reference algorithm (`Numeric::cut_reactions`).
fn evaluate_matches<M: Model + Default>(name: &str) {
    use eom_gen::functions::Function;
    let sys = system(name);
    let num = Numeric::new(&sys).expect("numeric");
    let f = eom_gen::mech::formulate(&sys, eom_gen::functions::FunctionSet::all_requested())
        .expect("formulates");
    let model = M::default();
    let mut rng = Rng(0x5EED_0000_0000_0019);
    for _ in 0..3 {
        let mut q: M::Q = vector(
            &sys.q0()
                .iter()
                .map(|q| q + 0.5 * rng.uniform())
                .collect::<Vec<_>>(),
        );
        model.normalize(&mut q);
        let qv = q.as_ref().to_vec();
        let uv = rng.vec(M::NU, 1.0);
        let udot = rng.vec(M::NU, 1.0);
        let tau = rng.vec(M::NU, 1.0);
        let lambda = rng.vec(f.constraint_names.len(), 1.0);
        let t = 0.25;
        let at = eom_sim::Point {
            t,
            q: &qv,
            u: &uv,
            udot: &udot,
            tau: &tau,
            lambda: &lambda,
        };
        let x = eom_gen::interpret::Point {
            sys: &sys,
            q: &qv,
            u: &uv,
            udot: &udot,
            tau: &tau,
            inputs: &[],
            params: &[],
            multipliers: &lambda,
            t,
        };
        assert!(!M::FUNCTIONS.is_empty());
        for info in M::FUNCTIONS {
            let mut got = vec![f64::NAN; info.len];
            assert!(
                model.evaluate(info.name, &at, &mut got),
                "{name}: {}",
                info.name
            );
            let function: Function = info.name.parse().expect("a function of the table");
            let want = eom_gen::interpret::evaluate_function(&f, function, &x)
                .unwrap_or_else(|| panic!("{name}: the evaluator has no {}", info.name));
            close(&format!("{name} {}", info.name), &got, &want);
        }
        // A wrong length is refused, not a panic.
        assert!(!model.evaluate("qdot", &at, &mut [0.0; 0][..]) || M::NQ == 0);
        assert!(!model.evaluate("no_such_function", &at, &mut []));
        if let Some(info) = M::FUNCTIONS.iter().find(|i| i.name == "marker_jacobians") {
            let mut jac = vec![0.0; info.len];
            model.evaluate("marker_jacobians", &at, &mut jac);
            let positions = |q: &[f64]| -> Vec<f64> {
                let mut out = vec![0.0; M::OUTPUT_NAMES.len()];
                let at = eom_sim::Point { q, u: &uv, ..at };
                model.evaluate("outputs", &at, &mut out);
                // The rows of the Jacobian are the marker positions' outputs.
                M::OUTPUT_NAMES
                    .iter()
                    .zip(out)
                    .filter(|(n, _)| info.labels.contains(n))
                    .map(|(_, v)| v)
                    .collect()
            };
            let h = 1e-6;
            for k in 0..M::NU {
                let mut e = vec![0.0; M::NU];
                e[k] = 1.0;
                let qd = num.qdot(&qv, &e);
                let step =
                    |s: f64| -> Vec<f64> { qv.iter().zip(&qd).map(|(q, d)| q + s * d).collect() };
                let (p, m) = (positions(&step(h)), positions(&step(-h)));
                for (r, (a, b)) in p.iter().zip(&m).enumerate() {
                    let want = (a - b) / (2.0 * h);
                    let got = jac[r * M::NU + k];
                    assert!(
                        (got - want).abs() < 1e-7,
                        "{name}: ∂x/∂u of row {} along u_{k}: got {got}, central difference {want}",
                        info.labels[r]
                    );
                }
            }
        }
        if M::FUNCTIONS.iter().any(|i| i.name == "cut_joint_reactions") {
            let want: Vec<f64> = num
                .cut_reactions(&qv, t, &lambda)
                .expect("reactions")
                .into_iter()
                .flat_map(|(_, f, n)| f.into_iter().chain(n))
                .collect();
            let mut got = vec![0.0; want.len()];
            assert!(model.evaluate("cut_joint_reactions", &at, &mut got));
            close(&format!("{name} cut joint reactions"), &got, &want);
        }
    }
}

#[test]
fn every_function_of_the_table_is_offered_and_right() {
    evaluate_matches::<g::pendulum::Pendulum>("pendulum");
    evaluate_matches::<g::double_pendulum::DoublePendulum>("double_pendulum");
    evaluate_matches::<g::heavy_top::HeavyTop>("heavy_top");
    evaluate_matches::<g::arm7::Arm7>("arm7");
    evaluate_matches::<g::fourbar::Fourbar>("fourbar");
    evaluate_matches::<g::andrews::Andrews>("andrews");
    evaluate_matches::<g::bricard::Bricard>("bricard");
    evaluate_matches::<g::stewart::Stewart>("stewart");
    evaluate_matches::<g::rolling_disk::RollingDisk>("rolling_disk");
}

/// The mixed model `models/ancf/pendulum_rod.ron` (a rigid link holding
/// the Berzeri–Shabana ANCF rod) with its rigid part compiled: the
/// generated `mass_matrix`, `bias`, `energy` and `attachments` through
/// `Model::evaluate` drive the index-3 generalized-α exactly as the
/// interpreted rigid part does (the same state after 0.1 s, to round-off),
/// and the rod's first node stays on the link's tip marker.
#[test]
fn mixed_model_runs_on_its_compiled_rigid_part() {
    use eom_sim::large::{AlphaOptions, ByName, MixedAlpha};
    let sys = system("ancf/pendulum_rod");
    let f = eom_gen::mech::formulate(&sys, eom_gen::functions::FunctionSet::all_requested())
        .unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let compiled = g::pendulum_rod::PendulumRod::default();
    let len = eom_gen::mech::mounts::mount_rows(&sys) * (1 + sys.nq());
    let run = |rigid: Box<dyn eom_sim::large::RigidPart + '_>| {
        let mixed = eom_gen::cables::mixed(&sys, rigid).unwrap_or_else(|e| panic!("{e}"));
        let m = &mixed.model;
        let state = m.initial_state(0.0, &sys.q0(), &sys.u0());
        let opts = AlphaOptions {
            h: 1e-3,
            rho_inf: 0.9,
            ..AlphaOptions::default()
        };
        let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
        let mut worst = 0.0_f64;
        ga.run_to(0.1, |s, _| {
            let r = m.constraint_residual(s.t, &s.q);
            worst = r.iter().fold(worst, |a, x| a.max(x.abs()));
        })
        .unwrap_or_else(|e| panic!("{e}"));
        (ga.state().q.clone(), worst)
    };
    let (q_compiled, residual) = run(Box::new(ByName::new(sys.nu(), len, |name, at, out| {
        compiled.evaluate(name, at, out)
    })));
    let (q_interpreted, _) = run(eom_gen::cables::interpreted_rigid(&f, &sys));
    close("state after 0.1 s", &q_compiled, &q_interpreted);
    assert!(residual < 1e-9, "attachment residual {residual:e}");
    // The link turned: the run is not trivially at rest.
    let theta = q_compiled[q_compiled.len() - 1];
    assert!(theta.abs() > 1e-3, "θ = {theta}");
}

/// The mixed model `models/ancf/fourbar_cable.ron` (a four-bar closed by a
/// cut joint, its coupler carrying a hanging ANCF cable) with its rigid part
/// compiled: the generated `constraints` (the loop's `Φ` and `J = Φ_q`)
/// join `mass_matrix`, `bias`, `energy` and `attachments` through
/// `Model::evaluate`, and the index-3 generalized-α runs exactly as on the
/// interpreted rigid part (the same state after 0.2 s, to round-off), the
/// loop closed at the Newton tolerance.
#[test]
fn mixed_model_with_a_loop_runs_on_its_compiled_rigid_part() {
    use eom_sim::large::{AlphaOptions, ByName, MixedAlpha};
    let sys = system("ancf/fourbar_cable");
    let f = eom_gen::mech::formulate(&sys, eom_gen::functions::FunctionSet::all_requested())
        .unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let compiled = g::fourbar_cable::FourbarCable::default();
    let len = eom_gen::mech::mounts::mount_rows(&sys) * (1 + sys.nq());
    let (q0, u0) = eom_gen::cables::rigid_start(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let run = |rigid: Box<dyn eom_sim::large::RigidPart + '_>| {
        let mixed = eom_gen::cables::mixed(&sys, rigid).unwrap_or_else(|e| panic!("{e}"));
        let m = &mixed.model;
        let state = m.initial_state(0.0, &q0, &u0);
        let opts = AlphaOptions {
            h: 1e-3,
            rho_inf: 0.9,
            ..AlphaOptions::default()
        };
        let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
        let rows = m.rigid_constraint_rows();
        let mut worst = 0.0_f64;
        ga.run_to(0.2, |s, _| {
            let r = m.constraint_residual(s.t, &s.q);
            worst = r[rows.clone()].iter().fold(worst, |a, x| a.max(x.abs()));
        })
        .unwrap_or_else(|e| panic!("{e}"));
        (ga.state().q.clone(), worst, rows.len())
    };
    let (q_compiled, residual, loop_rows) = run(Box::new(
        ByName::new(sys.nu(), len, |name, at, out| {
            compiled.evaluate(name, at, out)
        })
        .with_constraints(
            f.constraint_names.len(),
            eom_gen::cables::holonomic_names(&f),
        ),
    ));
    let (q_interpreted, _, _) = run(eom_gen::cables::interpreted_rigid(&f, &sys));
    close("state after 0.2 s", &q_compiled, &q_interpreted);
    assert_eq!(loop_rows, 2, "the cut joint's two in-plane equations");
    assert!(residual < 1e-10, "loop residual {residual:e}");
    // The crank turned: the run is not trivially at rest.
    let n = q_compiled.len();
    let crank = q_compiled[n - 3];
    assert!(
        (crank - (std::f64::consts::FRAC_PI_2 - 0.2)).abs() > 1e-2,
        "φ1 = {crank}"
    );
}

/// Every bundled model, compiled and interpreted, gives the same numbers
/// for every function of the table at random states, and no function
/// gives NaN (`null` in `eom-gen eval`) where a number belongs: with the
/// accelerations given, and without them (both then take `u̇ = 0`, as
/// `Model::evaluate` documents; `eom-gen eval` passes the model's own).
fn compiled_and_interpreted_agree<M: Model + Default>(path: &str) {
    use eom_gen::functions::Function;
    let sys = check_file(&format!("{}/models/{path}", env!("CARGO_MANIFEST_DIR")))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let f = eom_gen::mech::formulate(&sys, eom_gen::functions::FunctionSet::all_requested())
        .expect("formulates");
    let model = M::default();
    let mut rng = Rng(0x5EED_0000_0000_0030);
    for _ in 0..3 {
        let mut q: M::Q = vector(
            &sys.q0()
                .iter()
                .map(|q| q + 0.3 * rng.uniform())
                .collect::<Vec<_>>(),
        );
        model.normalize(&mut q);
        let qv = q.as_ref().to_vec();
        let uv = rng.vec(M::NU, 1.0);
        let given = rng.vec(M::NU, 1.0);
        let tau = rng.vec(M::NU, 1.0);
        let lambda = rng.vec(f.constraint_names.len(), 1.0);
        for udot in [&given[..], &[]] {
            let at = eom_sim::Point {
                t: 0.25,
                q: &qv,
                u: &uv,
                udot,
                tau: &tau,
                lambda: &lambda,
            };
            let x = eom_gen::interpret::Point {
                sys: &sys,
                q: &qv,
                u: &uv,
                udot,
                tau: &tau,
                inputs: &[],
                params: &[],
                multipliers: &lambda,
                t: 0.25,
            };
            for info in M::FUNCTIONS {
                let what = format!("{path} {} (u̇ given: {})", info.name, !udot.is_empty());
                let mut got = vec![f64::NAN; info.len];
                assert!(model.evaluate(info.name, &at, &mut got), "{what}");
                let function: Function = info.name.parse().expect("a function of the table");
                let want = eom_gen::interpret::evaluate_function(&f, function, &x)
                    .unwrap_or_else(|| panic!("{what}: the evaluator has none"));
                if let Some(k) = want.iter().position(|v| !v.is_finite()) {
                    panic!("{what}[{k}]: interpreted got {}, want a number", want[k]);
                }
                close(&what, &got, &want);
            }
        }
    }
}

#[test]
fn every_bundled_model_compiled_equals_interpreted() {
    compiled_and_interpreted_agree::<g::andrews::Andrews>("andrews.ron");
    compiled_and_interpreted_agree::<g::arm7::Arm7>("arm7.ron");
    compiled_and_interpreted_agree::<g::arm7_flex::Arm7Flex>("arm7_flex.ron");
    compiled_and_interpreted_agree::<g::bouncing_ball::BouncingBall>("bouncing_ball.ron");
    compiled_and_interpreted_agree::<g::bricard::Bricard>("bricard.ron");
    compiled_and_interpreted_agree::<g::double_pendulum::DoublePendulum>("double_pendulum.ron");
    compiled_and_interpreted_agree::<g::fourbar::Fourbar>("fourbar.ron");
    compiled_and_interpreted_agree::<g::fourbar_n2::FourbarN2>("fourbar_n2.ron");
    compiled_and_interpreted_agree::<g::fourbar_n4::FourbarN4>("fourbar_n4.ron");
    compiled_and_interpreted_agree::<g::free_body::FreeBody>("free_body.ron");
    compiled_and_interpreted_agree::<g::heavy_top::HeavyTop>("heavy_top.ron");
    compiled_and_interpreted_agree::<g::hub_beam::HubBeam>("hub_beam.ron");
    compiled_and_interpreted_agree::<g::pendulum::Pendulum>("pendulum.ron");
    compiled_and_interpreted_agree::<g::rolling_disk::RollingDisk>("rolling_disk.ron");
    compiled_and_interpreted_agree::<g::slider_crank::SliderCrank>("slider_crank.ron");
    compiled_and_interpreted_agree::<g::slider_crank_driven::SliderCrankDriven>(
        "slider_crank_driven.ron",
    );
    compiled_and_interpreted_agree::<g::slider_crank_flex::SliderCrankFlex>(
        "slider_crank_flex.ron",
    );
    compiled_and_interpreted_agree::<g::slider_crank_simeon::SliderCrankSimeon>(
        "slider_crank_simeon.ron",
    );
    compiled_and_interpreted_agree::<g::spin_up::SpinUp>("spin_up.ron");
    compiled_and_interpreted_agree::<g::stewart::Stewart>("stewart.ron");
    compiled_and_interpreted_agree::<g::stewart_driven::StewartDriven>("stewart_driven.ron");
    compiled_and_interpreted_agree::<g::pendulum_rod::PendulumRod>("ancf/pendulum_rod.ron");
    compiled_and_interpreted_agree::<g::fourbar_cable::FourbarCable>("ancf/fourbar_cable.ron");
    compiled_and_interpreted_agree::<g::pendulum_peg::PendulumPeg>("ancf/pendulum_peg.ron");
}

/// The bouncing ball compiled runs through the same contact events as
/// interpreted (issue #26): same impacts, same rest time.
#[test]
fn bouncing_ball_compiled_equals_interpreted() {
    let sys = check_file(&format!(
        "{}/models/bouncing_ball.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap_or_else(|r| panic!("{r}"))
    .system;
    let f = eom_gen::mech::formulate(&sys, eom_gen::functions::FunctionSet::all_requested())
        .expect("formulates");
    let o = eom_sim::RunOptions {
        t_end: 5.0,
        ..eom_sim::RunOptions::default()
    };
    let model = g::bouncing_ball::BouncingBall::default();
    let compiled = eom_sim::run::simulate_generated::<_, 2, 2>(&model, &o).expect("runs");
    let interpreted = eom_gen::interpret::simulate(&f, &sys, &o).expect("runs");
    assert_eq!(
        compiled.contact_events.len(),
        interpreted.contact_events.len()
    );
    assert!(compiled.contact_events.len() > 20);
    for (a, b) in compiled
        .contact_events
        .iter()
        .zip(&interpreted.contact_events)
    {
        assert_eq!(a.kind, b.kind);
        assert!((a.t - b.t).abs() < 1e-9, "{} vs {}", a.t, b.t);
    }
}

/// No scope of a committed generated function holds more `let`s than
/// `eom_gen::emit::BLOCK_LIMIT` (one more for the array of values that
/// cross its blocks): rustc overflows its stack on about 2 950 nested
/// `let`s when it writes debug info (the default `dev` profile; CI builds
/// without it, so a debug build would not show it there;
/// `eom_gen::testkit::deepest_lets` counts).
#[test]
fn no_generated_scope_is_too_deep_for_a_debug_build() {
    let files = generated_files(env!("CARGO_MANIFEST_DIR")).unwrap_or_default();
    assert!(!files.is_empty(), "no models found");
    for (name, _) in &files {
        let path = format!("{}/generated/src/{name}.rs", env!("CARGO_MANIFEST_DIR"));
        let source = std::fs::read_to_string(&path).unwrap_or_default();
        let (most, at) = eom_gen::testkit::deepest_lets(&source);
        assert!(
            most <= eom_gen::emit::BLOCK_LIMIT + 1,
            "{name}: {most} nested `let`s in `{at}`, more than {} + 1",
            eom_gen::emit::BLOCK_LIMIT
        );
    }
}
