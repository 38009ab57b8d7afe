//! `sweep --compiled` and `simulate --ensemble`: cases run compiled in
//! SIMD lanes through the ensemble integrator (`eom_sim::integrate_lanes`).
//! DOPRI5 with per-lane error control takes, lane by lane, the steps the
//! single-state run takes, so the compiled table must be the evaluator's:
//! the same counters and the same final states to the rounding of two
//! evaluations of the same equations (asked: 1e-9 absolute on O(1)
//! angles and rates, 10 % of `rtol = 1e-8`, the per-step error target —
//! with identical steps the two agree to ~1e-14). One small model (the
//! pendulum, swept in `l`: one cached release build shared by both tests).

use std::process::{Command, Output};

fn cached(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .env(
            "EOM_CACHE_DIR",
            concat!(env!("CARGO_MANIFEST_DIR"), "/../target/eom-cache"),
        )
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs")
}

fn ok(args: &[&str]) -> Output {
    let out = cached(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The rows of a results CSV: header, then numbers and the quoted `stop`.
fn rows(path: &std::path::Path) -> (String, Vec<(Vec<f64>, String)>) {
    let text = std::fs::read_to_string(path).expect("results written");
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default().to_string();
    let rows = lines
        .map(|l| {
            let (nums, stop) = l.split_once(",\"").expect("quoted stop");
            (
                nums.split(',')
                    .map(|x| x.parse().expect("number"))
                    .collect(),
                stop.trim_end_matches('"').to_string(),
            )
        })
        .collect();
    (header, rows)
}

fn temp(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("eom-lanes-{}-{name}", std::process::id()))
}

#[test]
fn compiled_sweep_in_lanes_is_the_interpreted_sweep() {
    // Five lengths: one full pack of four lanes and a short one; each
    // length takes its own number of steps (the shorter pendulum swings
    // faster), so the lanes step apart.
    let (a, b) = (temp("interp"), temp("lanes"));
    let common = [
        "sweep",
        "models/pendulum.ron",
        "--param",
        "l=0.5,0.8,1.1,1.4,1.7",
        "--t-end",
        "2",
    ];
    let run = |dir: &std::path::Path, extra: &[&str]| {
        let mut args = common.to_vec();
        let d = dir.display().to_string();
        args.extend(["--out", d.as_str()]);
        args.extend(extra);
        ok(&args);
        rows(&dir.join("results.csv"))
    };
    let (h1, r1) = run(&a, &[]);
    let (h2, r2) = run(&b, &["--compiled", "--lanes", "4"]);
    assert_eq!(h1, h2, "the same columns");
    assert_eq!(r1.len(), 5);
    let col = |n: &str| h1.split(',').position(|c| c == n).expect("column");
    let (steps, rhs, cpu) = (col("steps"), col("rhs_evals"), col("cpu_s"));
    for (x, y) in r1.iter().zip(&r2) {
        assert_eq!(x.1, y.1, "stop");
        for (k, (p, q)) in x.0.iter().zip(&y.0).enumerate() {
            if k == cpu {
                continue;
            }
            if k <= rhs && k >= steps {
                assert_eq!(p, q, "counter {k} of case {}", x.0[0]);
            } else {
                assert!(
                    (p - q).abs() <= 1e-9,
                    "column {k} of case {}: interpreted {p}, lanes {q}",
                    x.0[0]
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&a);
    let _ = std::fs::remove_dir_all(&b);
}

#[test]
fn ensemble_is_seeded_and_each_member_is_its_single_run() {
    let ens = |lanes: &str| -> serde_json::Value {
        let out = ok(&[
            "simulate",
            "models/pendulum.ron",
            "--ensemble",
            "5",
            "--seed",
            "7",
            "--perturb",
            "q=0.2,u=0.1",
            "--param-spread",
            "l=0.1",
            "--t-end",
            "1",
            "--lanes",
            lanes,
            "--json",
        ]);
        serde_json::from_slice(&out.stdout).expect("one JSON object")
    };
    let (four, one) = (ens("4"), ens("1"));
    assert_eq!(four["finished"], 5, "{four}");
    let members = |v: &serde_json::Value| -> Vec<serde_json::Value> {
        v["members_results"]
            .as_array()
            .expect("members")
            .iter()
            .map(|m| {
                let mut m = m.clone();
                m["cpu_s"] = serde_json::Value::Null;
                m
            })
            .collect()
    };
    // The draws depend on the seed and the member only, and each lane is
    // its single-state run: the same numbers at any width.
    assert_eq!(members(&four), members(&one));
    // Member 2 against `simulate --interpret` from its drawn state.
    let m = &four["members_results"][2];
    let (q0, u0, l) = (
        m["q0"][0].as_f64().expect("q0"),
        m["u0"][0].as_f64().expect("u0"),
        m["params"]["l"].as_f64().expect("l"),
    );
    assert!(
        (q0 - std::f64::consts::FRAC_PI_2).abs() > 1e-6,
        "perturbed: {q0}"
    );
    let (q0, u0, l) = (format!("{q0}"), format!("{u0}"), format!("l={l}"));
    let out = ok(&[
        "simulate",
        "models/pendulum.ron",
        "--t-end",
        "1",
        "--interpret",
        "--q0",
        &q0,
        "--u0",
        &u0,
        "--param",
        &l,
        "--json",
    ]);
    let single: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(single["stats"]["steps"], m["steps"], "{single} {m}");
    for (key, i) in [("q", 0), ("u", 0)] {
        let (x, y) = (
            single[key][i].as_f64().expect("single"),
            m[key][i].as_f64().expect("member"),
        );
        assert!((x - y).abs() <= 1e-9, "{key}: single {x}, member {y}");
    }
}

#[test]
fn options_that_do_not_apply_to_lanes_are_refused() {
    for (args, says) in [
        (
            vec![
                "simulate",
                "models/fourbar.ron",
                "--t-end",
                "1",
                "--ensemble",
                "4",
            ],
            "closed loops",
        ),
        (
            vec![
                "simulate",
                "models/pendulum.ron",
                "--t-end",
                "1",
                "--ensemble",
                "4",
                "--integrator",
                "radau5",
            ],
            "does not run in lanes",
        ),
        (
            vec![
                "simulate",
                "models/pendulum.ron",
                "--t-end",
                "1",
                "--seed",
                "3",
            ],
            "give --ensemble",
        ),
        (
            vec![
                "simulate",
                "models/pendulum.ron",
                "--t-end",
                "1",
                "--ensemble",
                "4",
                "--interpret",
            ],
            "--interpret does not apply to --ensemble",
        ),
        (
            vec![
                "simulate",
                "models/pendulum.ron",
                "--t-end",
                "1",
                "--ensemble",
                "4",
                "--perturb",
                "x=1",
            ],
            "--perturb `x=1`",
        ),
        (
            vec![
                "sweep",
                "models/pendulum.ron",
                "--param",
                "l=1,2",
                "--t-end",
                "1",
                "--lanes",
                "4",
                "--out",
                "/nonexistent/never",
            ],
            "give --compiled",
        ),
        (
            vec![
                "sweep",
                "models/fourbar.ron",
                "--param",
                "m=1,2",
                "--t-end",
                "1",
                "--compiled",
                "--out",
                "/nonexistent/never",
            ],
            "cannot run in lanes",
        ),
    ] {
        let out = cached(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}
