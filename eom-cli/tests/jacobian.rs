//! Issue #27: `simulate --jacobian` chooses where RADAU5 and the implicit
//! midpoint rule get `∂(q̇, u̇)/∂(q, u)`: the generated derivatives or
//! forward differences of the right-hand side; it is refused where it does
//! not apply.

use std::process::{Command, Output};

fn eom_gen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs")
}

fn temp_path(name: &str) -> String {
    std::env::temp_dir()
        .join(format!("eom-jacobian-{}-{name}", std::process::id()))
        .to_string_lossy()
        .into_owned()
}

/// The double pendulum with a stiff, overdamped elbow spring (`k = 10⁵
/// N·m/rad`, `c = 10⁴ N·m·s`: modes near `−10/s` and `−10⁴/s`).
fn stiff_double_pendulum() -> String {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/double_pendulum.ron"
    ))
    .expect("the bundled model");
    let text = text.replacen(
        "outputs: [",
        "forces: [JointSpringDamper(name: \"s\", joint: \"elbow\", stiffness: 1e5, damping: 1e4, rest: 0)],\n    outputs: [",
        1,
    );
    let path = temp_path("stiff_double_pendulum.ron");
    std::fs::write(&path, text).expect("temp file");
    path
}

/// RADAU5 with the generated Jacobian and with differences: the same run
/// (steps within one in a hundred — the Jacobian also filters RADAU5's
/// error estimate, so the differenced one's `√ε` error moves a step now and
/// then — and the same end state within the tolerance), the generated one
/// in fewer right-hand sides: none for its Jacobians, where differences
/// cost `N = 4` each. The report says which was used.
#[test]
fn radau5_generated_and_differenced_jacobians_take_the_same_steps() {
    let model = stiff_double_pendulum();
    let run = |jacobian: &str| {
        let out = eom_gen(&[
            "simulate",
            &model,
            "--t-end",
            "1",
            "--integrator",
            "radau5",
            "--rtol",
            "1e-8",
            "--atol",
            "1e-8",
            "--interpret",
            "--jacobian",
            jacobian,
            "--json",
        ]);
        assert!(
            out.status.success(),
            "--jacobian {jacobian}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice::<serde_json::Value>(&out.stdout).expect("one JSON object")
    };
    let (g, d) = (run("generated"), run("differences"));
    assert_eq!(g["stats"]["jacobian"], "generated", "{g}");
    assert_eq!(d["stats"]["jacobian"], "differences", "{d}");
    let count = |v: &serde_json::Value, k: &str| v["stats"][k].as_u64().expect(k) as usize;
    let near = |x: usize, y: usize| x.abs_diff(y) <= 1 + x / 100;
    for k in ["accepted", "rejected"] {
        assert!(near(count(&d, k), count(&g, k)), "{k}: {g} / {d}");
    }
    let (rg, rd, jd) = (
        count(&g, "rhs_evals"),
        count(&d, "rhs_evals"),
        count(&d, "jacobian_evals"),
    );
    assert!(
        rg < rd && rd - rg >= 3 * jd,
        "right-hand sides: generated {rg}, differences {rd} ({jd} Jacobians)"
    );
    let state = |v: &serde_json::Value| -> Vec<f64> {
        ["q", "u"]
            .iter()
            .flat_map(|k| v[k].as_array().expect(k).clone())
            .map(|x| x.as_f64().expect("finite"))
            .collect()
    };
    for (x, y) in state(&d).iter().zip(state(&g)) {
        assert!(
            (x - y).abs() <= 1e-7 * (1.0 + x.abs()),
            "end states {x} / {y}"
        );
    }
    // `auto` (the default) takes the generated one on this small model.
    let out = eom_gen(&[
        "simulate",
        &model,
        "--t-end",
        "0.01",
        "--integrator",
        "midpoint",
        "--dt",
        "1e-3",
        "--interpret",
        "--json",
    ]);
    let a: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(a["stats"]["jacobian"], "generated", "{a}");
    let _ = std::fs::remove_file(model);
}

/// `--jacobian` where it cannot apply is a usage error (exit 2) naming
/// why and what would apply: an explicit integrator (also rk4 on a model
/// with cables), `generated` on a model with loops or with quaternions.
#[test]
fn jacobian_where_it_does_not_apply_is_refused() {
    let cases: [(&[&str], &str); 5] = [
        (
            &[
                "simulate",
                "models/pendulum.ron",
                "--t-end",
                "1",
                "--jacobian",
                "generated",
            ],
            "dopri5 uses none",
        ),
        (
            &[
                "simulate",
                "models/fourbar.ron",
                "--t-end",
                "1",
                "--integrator",
                "radau5",
                "--jacobian",
                "generated",
            ],
            "the model has constraints",
        ),
        (
            &[
                "simulate",
                "models/heavy_top.ron",
                "--t-end",
                "1",
                "--integrator",
                "radau5",
                "--jacobian",
                "generated",
            ],
            "quaternion",
        ),
        (
            &[
                "simulate",
                "models/ancf/pendulum_rod.ron",
                "--t-end",
                "1",
                "--integrator",
                "rk4",
                "--jacobian",
                "differences",
            ],
            "--jacobian does not apply to rk4",
        ),
        (
            &[
                "simulate",
                "models/pendulum.ron",
                "--t-end",
                "1",
                "--integrator",
                "radau5",
                "--jacobian",
                "fd",
            ],
            "did you mean `differences`",
        ),
    ];
    for (args, says) in cases {
        let out = eom_gen(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    // Differences on a model with loops and on quaternions: allowed.
    for model in ["models/fourbar.ron", "models/heavy_top.ron"] {
        let out = eom_gen(&[
            "simulate",
            model,
            "--t-end",
            "0.01",
            "--integrator",
            "radau5",
            "--jacobian",
            "differences",
            "--interpret",
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{model}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
        assert_eq!(v["stats"]["jacobian"], "differences", "{model}: {v}");
    }
}

/// Models with cables: `--jacobian` sets where generalized-α's Newton
/// matrix takes the elements' tangent. The generated kernels and forward
/// differences of the element forces give the same run (same steps and
/// Newton iterations, the same tip within 1e-9 m: the modified Newton
/// iteration converges to its tolerance either way), the differenced one
/// paying force evaluations for each tangent; the report says which. With
/// step control (a tangent at nearly every step) on the cable alone and on
/// the rigid link carrying a rod (mixed model).
#[test]
fn cables_generated_and_differenced_tangents_take_the_same_steps() {
    for model in ["models/ancf/pendulum.ron", "models/ancf/pendulum_rod.ron"] {
        let run = |jacobian: &str| {
            let out = eom_gen(&[
                "simulate",
                model,
                "--t-end",
                "0.2",
                "--rtol",
                "1e-5",
                "--atol",
                "1e-5",
                "--jacobian",
                jacobian,
                "--json",
            ]);
            assert!(
                out.status.success(),
                "{model} --jacobian {jacobian}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            serde_json::from_slice::<serde_json::Value>(&out.stdout).expect("one JSON object")
        };
        let (g, d) = (run("generated"), run("differences"));
        assert_eq!(g["stats"]["jacobian"], "generated", "{g}");
        assert_eq!(d["stats"]["jacobian"], "differences", "{d}");
        for key in ["steps", "rejected", "newton_iterations", "jacobian_evals"] {
            assert_eq!(g["stats"][key], d["stats"][key], "{model}: {key}");
        }
        let rhs = |v: &serde_json::Value| v["stats"]["rhs_evals"].as_u64().unwrap_or(0);
        assert!(
            rhs(&d) > rhs(&g),
            "{model}: {} against {}",
            rhs(&d),
            rhs(&g)
        );
        let tip = |v: &serde_json::Value| v["cables"][0]["last_node"].clone();
        for k in 0..2 {
            let (a, b) = (tip(&g)[k].as_f64(), tip(&d)[k].as_f64());
            let (Some(a), Some(b)) = (a, b) else {
                panic!("{model}: no tip in the report: {g}");
            };
            assert!((a - b).abs() < 1e-9, "{model}: tip {a} against {b}");
        }
    }
}
