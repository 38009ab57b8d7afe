//! The 200-link hard case: a spatial chain of 200 revolute links (axes
//! alternating z and y) through a scene that asks only for what simulation
//! needs — forward and inverse dynamics, energy — so the O(n²) mass matrix
//! (409 254 operations, 27 MB of source with it) is derived from inverse
//! dynamics instead of generated. Generation, the release build of the
//! cached crate (`eom-gen eval`/`simulate`, as a user runs them) and a
//! DOPRI5 run must succeed, and the physics must hold:
//!
//! - compiled forward dynamics (ABA, generated) equals the f64 reference
//!   algorithm (`eom_gen::mech::Numeric`) at a random state;
//! - the derived mass matrix equals the reference composite-rigid-body one,
//!   and `M u̇ + b = τ` with the derived `M`, `b` and the generated `u̇`
//!   (two independent algorithms agree);
//! - energy is kept while the chain falls: the change of the total is a tiny
//!   fraction of the kinetic energy gained.
//!
//! The first run compiles the generated code (about 7 MB) in release mode
//! into `target/eom-cache`; later runs reuse it.

use eom_gen::mech::Numeric;
use eom_gen::model::Source;
use eom_gen::model::builder::n_link_chain;
use eom_gen::model::spec::Num;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};

const LINKS: usize = 200;

const SCENE: &str = r#"// Everything `eom-gen simulate` needs, nothing more: M and b are derived.
Scene(
    model: "chain200.ron",
    name: "chain200",
    doc: "200-link spatial chain for simulation",
    outputs: [],
    functions: [ForwardDynamics, InverseDynamics, Energy],
)
"#;

/// The chain bent slightly at every joint, at rest: it falls from there.
fn chain_text() -> String {
    let mut spec = n_link_chain(LINKS, true);
    for (k, j) in spec.joints.iter_mut().enumerate() {
        j.q0 = Some(vec![Num::Value(0.02 * (1.0 + (k % 3) as f64))]);
    }
    spec.to_ron()
}

/// Writes model and scene to a fixed directory (a stable path keeps the
/// generated source, and so the cached build, the same between runs).
fn files() -> (PathBuf, PathBuf) {
    let dir = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../target/eom-cache/chain200"
    ));
    std::fs::create_dir_all(&dir).expect("create the chain's directory");
    let model = dir.join("chain200.ron");
    let scene = dir.join("chain200.scene.ron");
    let text = chain_text();
    if std::fs::read_to_string(&model).ok().as_deref() != Some(text.as_str()) {
        std::fs::write(&model, &text).expect("write the chain");
    }
    if std::fs::read_to_string(&scene).ok().as_deref() != Some(SCENE) {
        std::fs::write(&scene, SCENE).expect("write the scene");
    }
    (model, scene)
}

/// `eom-gen ARGS`, started (its output piped) so that the test can work
/// while it runs.
fn start(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .env(
            "EOM_CACHE_DIR",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../target/eom-cache"),
        )
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("eom-gen runs")
}

/// The JSON a started `eom-gen` printed, once it has succeeded.
fn finish(child: Child, args: &[&str]) -> serde_json::Value {
    let out = child.wait_with_output().expect("eom-gen finishes");
    assert!(
        out.status.success(),
        "eom-gen {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

fn eom_gen(args: &[&str]) -> serde_json::Value {
    finish(start(args), args)
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
        .unwrap_or_default()
}

fn join(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:?}"))
        .collect::<Vec<_>>()
        .join(",")
}

#[test]
fn chain_of_200_links_generates_compiles_and_simulates() {
    let (_, scene) = files();
    let scene = scene.to_string_lossy().into_owned();

    // A random state, for the compiled functions against the f64 reference.
    let mut seed = 5u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let q: Vec<f64> = (0..LINKS).map(|_| 0.5 * rnd()).collect();
    let u: Vec<f64> = (0..LINKS).map(|_| 0.5 * rnd()).collect();
    let tau: Vec<f64> = (0..LINKS).map(|_| rnd()).collect();
    let (qs, us, taus) = (join(&q), join(&u), join(&tau));
    // `eom-gen eval` generates and builds the cached crate (most of this
    // test's time) while the test generates the scene itself, on the
    // other core.
    let eval_args = [
        "eval", &scene, "--q", &qs, "--u", &us, "--tau", &taus, "--json",
    ];
    let eval = start(&eval_args);

    let text = std::fs::read_to_string(&scene).expect("scene");
    let g = eom_gen::generate(&Source::new(scene.clone(), text)).unwrap_or_else(|e| panic!("{e}"));
    let f = &g.formulation;
    assert!(
        f.program(eom_gen::functions::Function::MassMatrix)
            .is_none()
            && f.program(eom_gen::functions::Function::Bias).is_none(),
        "the scene leaves the mass matrix and the bias out"
    );
    assert!(
        f.program(eom_gen::functions::Function::ForwardDynamics)
            .is_some()
            && f.program(eom_gen::functions::Function::InverseDynamics)
                .is_some()
    );
    eprintln!(
        "chain200 scene: {} bytes of source, generated in {:.2} s",
        g.source.len(),
        f.seconds
    );
    let sys = &g.checked.system;
    assert_eq!(sys.nu(), LINKS);

    let e = finish(eval, &eval_args);
    assert_eq!(e["mode"], "compiled", "{e}");
    let udot = floats(&e["udot"]);
    let bias = floats(&e["bias"]);
    let m: Vec<Vec<f64>> = e["mass_matrix"]
        .as_array()
        .map(|rows| rows.iter().map(floats).collect())
        .unwrap_or_default();
    assert_eq!((udot.len(), bias.len(), m.len()), (LINKS, LINKS, LINKS));

    let numeric = Numeric::new(sys).expect("numeric model");
    let want = numeric
        .forward_dynamics(&q, &u, 0.0, &tau, &[])
        .expect("reference forward dynamics");
    let scale = want.iter().fold(1.0f64, |a, x| a.max(x.abs()));
    for k in 0..LINKS {
        assert!(
            (udot[k] - want[k]).abs() <= 1e-8 * scale,
            "u̇[{k}]: got {} want {} (reference ABA)",
            udot[k],
            want[k]
        );
    }
    let terms = numeric.terms(&q, &u, 0.0, &[]).expect("reference terms");
    let m_scale = terms
        .mass_matrix
        .iter()
        .flatten()
        .fold(0.0f64, |a, x| a.max(x.abs()));
    for i in 0..LINKS {
        for (j, (&got, &want)) in m[i].iter().zip(&terms.mass_matrix[i]).enumerate() {
            assert!(
                (got - want).abs() <= 1e-10 * m_scale,
                "M[{i}][{j}]: got {got} (derived from ID) want {want} (reference CRBA)"
            );
        }
        let b_scale = terms.bias.iter().fold(1.0f64, |a, x| a.max(x.abs()));
        assert!(
            (bias[i] - terms.bias[i]).abs() <= 1e-10 * b_scale,
            "b[{i}]: got {} want {}",
            bias[i],
            terms.bias[i]
        );
        let lhs: f64 = m[i].iter().zip(&udot).map(|(a, b)| a * b).sum::<f64>() + bias[i];
        let size = m[i]
            .iter()
            .zip(&udot)
            .map(|(a, b)| (a * b).abs())
            .sum::<f64>()
            + bias[i].abs();
        assert!(
            (lhs - tau[i]).abs() <= 1e-8 * size.max(1.0),
            "row {i} of M u̇ + b: got {lhs} want τ = {}",
            tau[i]
        );
    }

    // Falling from the bent pose: DOPRI5 keeps the energy.
    let s = eom_gen(&[
        "simulate",
        &scene,
        "--t-end",
        "0.3",
        "--integrator",
        "dopri5",
        "--rtol",
        "1e-10",
        "--atol",
        "1e-10",
        "--json",
    ]);
    assert_eq!(s["stop"], "finished", "{s}");
    let energy = floats(&s["energy"]);
    let (qf, uf) = (floats(&s["q"]), floats(&s["u"]));
    let t_end = s["t"].as_f64().unwrap_or(f64::NAN);
    let (kinetic, _) = numeric
        .energy(&qf, &uf, t_end)
        .expect("reference energy at the end");
    assert!(
        kinetic > 1.0,
        "the chain falls: kinetic energy {kinetic} J at t = 0.3 s"
    );
    let drift = (energy[1] - energy[0]).abs();
    assert!(
        drift <= 1e-6 * kinetic,
        "energy {} → {} J: got a change of {drift:e}, want ≤ 1e-6 of the kinetic energy {kinetic}",
        energy[0],
        energy[1]
    );
    eprintln!(
        "chain200: {} steps, energy change {drift:e} J of {kinetic:.3} J kinetic, {:.3} s CPU",
        s["stats"]["steps"], s["cpu_s"]
    );
}
