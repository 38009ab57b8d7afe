//! Issue #30: every run that exits 0 answers what was asked, and every
//! option either applies or is refused. Each test here failed on the code
//! before the fix.

use std::process::{Command, Output};

/// `eom-gen ARGS` from the workspace root with the test cache of compiled
/// models (`target/eom-cache`, shared by the tests that compile).
fn eom_gen(args: &[&str]) -> Output {
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

fn ok_json(args: &[&str]) -> serde_json::Value {
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
        .join(format!("eom-honest-{}-{name}", std::process::id()))
        .to_string_lossy()
        .into_owned()
}

fn numbers(v: &serde_json::Value) -> Vec<Option<f64>> {
    v.as_array()
        .map(|a| a.iter().map(serde_json::Value::as_f64).collect())
        .unwrap_or_default()
}

/// The pendulum released at rest, horizontal, is in free fall at t = 0:
/// a point mass on a massless link, gravity all tangential, so the hinge
/// carries no force. `eval` evaluates its outputs at the model's own
/// accelerations, as `simulate` writes its first CSV row; `--udot 0`
/// (given) is the held pendulum, reaction m·g = 9.81 N upwards.
#[test]
fn eval_outputs_are_simulates_first_row() {
    for interpret in [true, false] {
        let mode = if interpret { "interpreted" } else { "compiled" };
        let mut args = vec!["eval", "models/pendulum.ron", "--json"];
        if interpret {
            args.push("--interpret");
        }
        let v = ok_json(&args);
        assert_eq!(v["udot_source"], "forward_dynamics", "{mode}: {v}");
        let outputs = numbers(&v["functions"]["outputs"]);
        let csv = temp_path(&format!("pendulum-{mode}.csv"));
        let mut sim = vec![
            "simulate",
            "models/pendulum.ron",
            "--t-end",
            "0.01",
            "--csv",
            &csv,
        ];
        if interpret {
            sim.push("--interpret");
        }
        let out = eom_gen(&sim);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(&csv).unwrap_or_default();
        let _ = std::fs::remove_file(&csv);
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
        let row: Vec<f64> = lines
            .next()
            .unwrap_or_default()
            .split(',')
            .filter_map(|x| x.parse().ok())
            .collect();
        assert_eq!(
            row.first().copied(),
            Some(0.0),
            "{mode}: the first row is t = 0"
        );
        // The outputs follow t, q and u in the CSV, in the model's order.
        let first = 1 + 2;
        for (k, got) in outputs.iter().enumerate() {
            let want = row.get(first + k).copied();
            let column = header.get(first + k).copied().unwrap_or("?");
            let (Some(got), Some(want)) = (*got, want) else {
                panic!("{mode} output {k} ({column}): got {got:?}, want {want:?}");
            };
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "{mode} output {k} ({column}): eval got {got}, simulate's first row {want}"
            );
        }
        // The hinge reaction's force: zero in free fall.
        let free = hinge_max(&header, first, &outputs);
        assert!(
            free < 1e-12,
            "{mode}: hinge force got {free}, want 0 in free fall"
        );
        // Held (u̇ = 0 given): the hinge carries the weight, 9.81 N.
        let mut held = args.clone();
        held.extend(["--udot", "0"]);
        let v = ok_json(&held);
        assert_eq!(v["udot_source"], "given", "{mode}: {v}");
        let outputs = numbers(&v["functions"]["outputs"]);
        let largest = hinge_max(&header, first, &outputs);
        assert!(
            (largest - 9.81).abs() < 1e-9,
            "{mode}: held, the hinge force got {largest}, want m g = 9.81 N"
        );
    }
}

/// The largest hinge force component among the outputs (the CSV header
/// names them `hinge_fx`, `hinge_fy`, `hinge_fz`).
fn hinge_max(header: &[&str], first: usize, outputs: &[Option<f64>]) -> f64 {
    let forces: Vec<f64> = header
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with("hinge_f"))
        .map(|(c, _)| {
            c.checked_sub(first)
                .and_then(|k| outputs.get(k).copied().flatten())
                .unwrap_or(f64::NAN)
        })
        .collect();
    assert_eq!(forces.len(), 3, "hinge force columns in {header:?}");
    forces.iter().fold(
        0.0,
        |m, f| if f.is_nan() { f64::NAN } else { m.max(f.abs()) },
    )
}

/// `eval --interpret` gives every function as numbers: inverse dynamics
/// (at the model's accelerations) is `τ` and equals the given `--tau`,
/// never `null`.
#[test]
fn eval_interpret_gives_inverse_dynamics() {
    for model in [
        "models/pendulum.ron",
        "models/double_pendulum.ron",
        "models/arm7.ron",
    ] {
        let v = ok_json(&["eval", model, "--interpret", "--json"]);
        let functions = v["functions"].as_object().cloned().unwrap_or_default();
        assert!(!functions.is_empty(), "{model}: {v}");
        for (name, values) in &functions {
            for (k, x) in numbers(values).iter().enumerate() {
                assert!(x.is_some(), "{model} {name}[{k}]: got null, want a number");
            }
        }
        // At u̇ from forward dynamics with τ = 0, inverse dynamics is 0.
        for (k, x) in numbers(&v["functions"]["inverse_dynamics"])
            .iter()
            .enumerate()
        {
            let x = x.unwrap_or(f64::NAN);
            assert!(
                x.abs() < 1e-8,
                "{model} inverse_dynamics[{k}]: got {x}, want 0 (τ of its own accelerations)"
            );
        }
    }
}

/// The four-bar whose second ground pivot is 4 m away (links of 1 m):
/// `check` exits 1 naming the cut joint with its place in the file and the
/// smallest residual reached, never "valid … assembled"; `simulate`
/// refuses instead of integrating with the loop open.
#[test]
fn a_loop_that_cannot_close_is_refused() {
    let model = "fuzz/seeds/ron_model/fourbar_impossible.ron";
    let out = eom_gen(&["check", model]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert_eq!(out.status.code(), Some(1), "check: {stdout}{stderr}");
    assert!(
        stderr.contains("cut joint `c` cannot be closed") && stderr.contains("max |Φ|"),
        "check: got {stderr}"
    );
    assert!(
        stderr.contains("fourbar_impossible.ron:"),
        "check: got {stderr}, want the place in the file"
    );
    assert!(!stdout.contains("assembled"), "check: got {stdout}");
    for interpret in [true, false] {
        let mut args = vec!["simulate", model, "--t-end", "0.1"];
        if interpret {
            args.push("--interpret");
        }
        let out = eom_gen(&args);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_ne!(out.status.code(), Some(0), "simulate: got {stdout}");
        assert!(!stdout.contains("finished"), "simulate: got {stdout}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains("cannot be closed"),
            "simulate: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// The pendulum released horizontally has total energy 0 at the start
/// (V = 0 at the pivot's height), so a change relative to the total is
/// meaningless (it printed 1.4e8). The change is stated against
/// |T| + |V| (here about m g l = 9.81 J at the bottom), and small.
#[test]
fn energy_change_is_relative_to_a_meaningful_energy() {
    let out = eom_gen(&[
        "simulate",
        "models/pendulum.ron",
        "--interpret",
        "--t-end",
        "1",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("energy"))
        .unwrap_or_default();
    let relative: Option<f64> = line
        .split(" = ")
        .nth(1)
        .and_then(|r| r.split(" of |T| + |V|").next())
        .and_then(|x| x.trim().parse().ok());
    let Some(relative) = relative else {
        panic!("got `{line}`, want the change as a fraction of |T| + |V|");
    };
    assert!(
        relative < 1e-6,
        "got a relative change of {relative:e} in `{line}`, want < 1e-6 (rtol 1e-8)"
    );
}

/// A model of cables alone: `check` reports the cables and their free
/// coordinates, not "bodies 0" and a Grübler count of 0; `eval` and
/// `bench --per-call`, which work on a rigid part's generated functions,
/// refuse it (exit 2) naming what applies; `stats` shows the kernels, not
/// a table of zeros.
#[test]
fn cables_alone_are_described_not_zeroed() {
    let model = "models/ancf/cantilever.ron";
    let out = eom_gen(&["check", model]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        !text.contains("bodies       0") && !text.contains("Grübler"),
        "check: got {text}, want no rigid-part counts"
    );
    assert!(
        text.contains("64 free coordinates"),
        "check: got {text}, want the cable's 64 free coordinates"
    );
    for args in [
        &["eval", model, "--interpret"][..],
        &["bench", model, "--per-call"],
    ] {
        let out = eom_gen(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("cables alone") && err.contains("simulate"),
            "{args:?}: got {err}"
        );
    }
    let out = eom_gen(&["stats", model]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        !text.contains("forward_dynamics") && text.contains("Cable2D::internal_forces"),
        "stats: got {text}, want the kernels and no table of zeros"
    );
}

/// An option that does not apply to a model with cables is a usage error
/// naming the ones that do, instead of being ignored (`--integrator
/// dopri5` ran generalized-α). `--rtol`/`--atol` apply to generalized-α
/// (step-size control) and are refused with rk4's fixed step.
#[test]
fn options_that_do_not_apply_to_cables_are_refused() {
    let model = "models/ancf/pendulum.ron";
    for extra in [
        &["--integrator", "dopri5"][..],
        &["--rtol", "1e-6", "--integrator", "rk4"],
        &["--constraints", "baumgarte"],
        &["--max-steps", "10"],
    ] {
        let mut args = vec!["simulate", model, "--t-end", "0.05", "--dt", "1e-3"];
        args.extend_from_slice(extra);
        let out = eom_gen(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.contains(extra[0]) || err.contains(extra[1]),
            "{extra:?}: got {err}, want the option named"
        );
    }
    // What applies runs.
    let out = eom_gen(&[
        "simulate",
        model,
        "--t-end",
        "0.05",
        "--dt",
        "1e-3",
        "--integrator",
        "generalized-alpha",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Step-size control: the run lands on t_end and says how it stepped.
    let out = eom_gen(&[
        "simulate", model, "--t-end", "0.05", "--dt", "1e-3", "--rtol", "1e-6",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("to t = 0.05 s (step control rtol 1e-6") && text.contains(" rejected)"),
        "got {text}"
    );
}

/// Argument mistakes are usage errors (exit 2) found before anything is
/// generated or compiled, all reported together: a wrong-length `--q0`
/// (it exited 1 after building a crate), a negative `--t-end` (clap's
/// "use '-- -5'" tip) and an unknown integrator.
#[test]
fn argument_mistakes_are_reported_together_before_building() {
    let cache = temp_path("never-built");
    let out = Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args([
            "simulate",
            "models/double_pendulum.ron",
            "--t-end",
            "-5",
            "--integrator",
            "dopri6",
            "--q0",
            "0.1,0.2,0.3",
        ])
        .env("EOM_CACHE_DIR", &cache)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for says in ["--t-end", "dopri6", "--q0 has 3 value(s)"] {
        assert!(
            err.contains(says),
            "got {err}, want `{says}` among the problems"
        );
    }
    assert!(!err.contains("'-- -5'"), "got clap's tip: {err}");
    assert!(
        !std::path::Path::new(&cache).exists(),
        "a crate was built for a run that cannot start"
    );
}

/// `models/hub_beam.ron` shows what it is for: the hub starts spinning
/// at 5 rad/s, so `simulate` moves it (it printed zeros: at rest, nothing
/// acting). The beam stays straight (a steady spin), so the hub turns at
/// its initial speed: θ(0.1 s) = 0.5 rad.
#[test]
fn hub_beam_moves() {
    let v = ok_json(&[
        "simulate",
        "models/hub_beam.ron",
        "--interpret",
        "--t-end",
        "0.1",
        "--json",
    ]);
    let theta = v["q"][0].as_f64().unwrap_or(f64::NAN);
    assert!(
        (theta - 0.5).abs() < 1e-6,
        "hub angle at 0.1 s: got {theta}, want 5 rad/s × 0.1 s = 0.5 rad"
    );
}

/// Every bundled model: `eval` at the state of `simulate`'s first CSV row
/// gives that row's outputs (markers, reactions at the model's own
/// accelerations and constraint forces). Interpreted, so nothing is
/// compiled; the compiled path runs the same functions
/// (`tests/generated.rs` holds compiled and interpreted equal).
#[test]
fn eval_outputs_equal_simulates_first_row_for_every_bundled_model() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../models");
    let mut models: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.ends_with(".ron"))
                .collect()
        })
        .unwrap_or_default();
    models.sort();
    assert!(models.len() > 10, "got {models:?}");
    let mut compared = 0;
    for name in &models {
        let model = format!("models/{name}");
        let check = ok_json(&["check", &model, "--json"]);
        let (nq, nu) = (
            check["nq"].as_u64().unwrap_or(0) as usize,
            check["nu"].as_u64().unwrap_or(0) as usize,
        );
        // The interpreter integrates up to 32 states (stewart has 43);
        // compiling it here would build a crate for one row.
        if nq + nu > 32 {
            continue;
        }
        let csv = temp_path(&format!("first-{name}.csv"));
        let out = eom_gen(&[
            "simulate",
            &model,
            "--interpret",
            "--t-end",
            "1e-4",
            "--csv",
            &csv,
        ]);
        assert!(
            out.status.success(),
            "{model}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(&csv).unwrap_or_default();
        let _ = std::fs::remove_file(&csv);
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
        let row: Vec<f64> = lines
            .next()
            .unwrap_or_default()
            .split(',')
            .filter_map(|x| x.parse().ok())
            .collect();
        let join = |v: &[f64]| {
            v.iter()
                .map(|x| format!("{x:e}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        assert!(row.len() > nq + nu, "{model}: first row {row:?}");
        let (q, u) = (join(&row[1..1 + nq]), join(&row[1 + nq..1 + nq + nu]));
        let t = format!("{:e}", row[0]);
        let v = ok_json(&[
            "eval",
            &model,
            "--interpret",
            "--q",
            &q,
            "--u",
            &u,
            "--t",
            &t,
        ]);
        let outputs = numbers(&v["functions"]["outputs"]);
        for (k, got) in outputs.iter().enumerate() {
            let c = 1 + nq + nu + k;
            let want = row.get(c).copied().unwrap_or(f64::NAN);
            let got = got.unwrap_or(f64::NAN);
            assert!(
                (got - want).abs() <= 1e-7 * want.abs().max(1.0),
                "{model} output {} ({}): eval got {got}, simulate's first row {want}",
                k,
                header.get(c).copied().unwrap_or("?")
            );
        }
        compared += usize::from(!outputs.is_empty());
    }
    assert!(
        compared >= 5,
        "only {compared} models with outputs compared"
    );
}

/// One `Integrator` names every method: generalized-α is one of them, and
/// a rigid model refuses it before anything is built (it integrates
/// element models, not the rigid model's ODE), naming the ones that apply.
#[test]
fn generalized_alpha_on_a_rigid_model_is_refused() {
    let out = eom_gen(&[
        "simulate",
        "models/double_pendulum.ron",
        "--t-end",
        "1",
        "--integrator",
        "generalized-alpha",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("generalized-alpha runs models with cables") && err.contains("dopri5"),
        "got {err}"
    );
}

/// `bench`: an option of the other mode is a usage error naming it (the
/// per-call options with the sweep, the sweep's with `--per-call`), found
/// before anything is built.
#[test]
fn bench_options_of_the_other_mode_are_refused() {
    let model = "models/pendulum.ron";
    for (mode, extra) in [
        ("--work-precision", "--states"),
        ("--work-precision", "--reps"),
        ("--work-precision", "--seed"),
        ("--per-call", "--tols"),
    ] {
        let value = if extra == "--tols" { "1e-6" } else { "3" };
        let out = eom_gen(&["bench", model, mode, extra, value]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{mode} {extra}: {err}");
        assert!(err.contains(extra), "{mode} {extra}: got {err}");
    }
}

/// A cable's CSV starts at t = 0 (it began after the first step) and holds
/// every node (it held the end node only): the first row is the cable
/// straight and at rest, as in the model file (8 elements from (0, 0) to
/// (0.6, 0), nodes 0.075 m apart).
#[test]
fn cable_csv_starts_at_t0_with_every_node() {
    let csv = temp_path("cable.csv");
    let out = eom_gen(&[
        "simulate",
        "models/ancf/pendulum.ron",
        "--t-end",
        "0.01",
        "--dt",
        "1e-3",
        "--csv",
        &csv,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap_or_default();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 12, "a header, t = 0 and 10 steps: {text}");
    let header: Vec<&str> = lines[0].split(',').collect();
    let nodes = header.iter().filter(|h| h.ends_with(".x")).count();
    assert!(nodes > 2, "every node, not the end node alone: {header:?}");
    let first: Vec<f64> = lines[1]
        .split(',')
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    assert_eq!(first[0], 0.0, "the first row is t = 0");
    let spacing = first[4] - first[1];
    for k in 0..nodes {
        let (x, y) = (first[1 + 3 * k], first[2 + 3 * k]);
        assert!(
            (x - k as f64 * spacing).abs() < 1e-12 && y.abs() < 1e-12,
            "node {k} at ({x}, {y}) at t = 0"
        );
    }
}

/// `--every` on a cable model samples the run at `k · every` from t = 0
/// to the end by cubic Hermite interpolation between the accepted steps
/// of step-size control (it was refused): the samples agree with a fixed
/// step run that lands on them (h = 2e-4 s, itself 3.8e-8 m from
/// h = 1e-5 s) to the scale of the tolerance (rtol = atol = 1e-6 on
/// coordinates of about 1 m: measured 9.6e-7 m).
#[test]
fn cable_every_samples_the_run_by_interpolation() {
    let model = "models/ancf/pendulum.ron";
    let rows = |extra: &[&str], name: &str| -> Vec<Vec<f64>> {
        let csv = temp_path(name);
        let mut args = vec!["simulate", model, "--t-end", "0.05", "--csv", &csv];
        args.extend_from_slice(extra);
        let out = eom_gen(&args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(&csv).expect("the CSV");
        text.lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect()
    };
    let sampled = rows(&["--rtol", "1e-6", "--every", "0.01"], "every.csv");
    let times: Vec<f64> = sampled.iter().map(|r| r[0]).collect();
    assert_eq!(times, vec![0.0, 0.01, 0.02, 0.03, 0.04, 0.05]);
    let fixed = rows(&["--dt", "2e-4"], "every_ref.csv");
    let mut worst = 0.0_f64;
    for r in &sampled {
        let g = fixed
            .iter()
            .min_by(|a, b| (a[0] - r[0]).abs().total_cmp(&(b[0] - r[0]).abs()))
            .expect("reference rows");
        assert!((g[0] - r[0]).abs() < 1e-9, "{} vs {}", g[0], r[0]);
        // Node coordinates (the energy, last, aside).
        for (a, b) in r[1..r.len() - 1].iter().zip(&g[1..g.len() - 1]) {
            worst = worst.max((a - b).abs());
        }
    }
    println!("largest node difference {worst:.2e} m");
    assert!(worst < 5e-6, "{worst:e}");
}

/// Contacts through the command line (issue #26): the JSON report lists the
/// contact events, `--events-csv` writes them (one row per event), and the
/// option is refused on a model without contacts.
#[test]
fn contact_events_in_the_report_and_the_events_csv() {
    let csv = temp_path("ball-events.csv");
    let v = ok_json(&[
        "simulate",
        "models/bouncing_ball.ron",
        "--interpret",
        "--t-end",
        "1.2",
        "--events-csv",
        &csv,
        "--json",
    ]);
    let events = v["contact_events"].as_array().cloned().unwrap_or_default();
    assert_eq!(events.len(), 2, "two impacts before 1.2 s: {v}");
    assert_eq!(events[0]["kind"], "impact");
    assert_eq!(events[0]["contacts"][0]["contact"], "floor");
    assert_eq!(events[0]["joint_impulses"][0]["joint"], "drop");
    let text = std::fs::read_to_string(&csv).unwrap_or_default();
    let _ = std::fs::remove_file(&csv);
    let mut lines = text.lines();
    let header = lines.next().unwrap_or_default();
    assert!(
        header.starts_with("t,kind,energy_before,energy_after,floor.impulse,"),
        "{header}"
    );
    assert_eq!(lines.count(), 2, "{text}");
    let out = eom_gen(&[
        "simulate",
        "models/pendulum.ron",
        "--interpret",
        "--t-end",
        "0.1",
        "--events-csv",
        &csv,
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("`pendulum` has no contacts"));
}

/// The bundled `models/ancf/pendulum_cable.ron`: a pendulum (0.3 m,
/// 0.5 kg) with a short stiff steel cable hanging from its tip whose end
/// node strikes a floor, e = 0.5: nothing in it can feed energy in. At `--rho-inf 1` (no damping of the modes the step does not
/// resolve) and `--dt 1.5e-3` its run gains energy from 0 J after the
/// first impacts; it exits 3 naming the rise, where it used to go on (to
/// hundreds of joules, or until Newton failed). At `--rho-inf 0.8` and
/// `--dt 1e-3` it finishes, its energy below its start (issue #26,
/// session 44).
#[test]
fn a_passive_cable_run_whose_energy_rises_is_refused() {
    let path = "models/ancf/pendulum_cable.ron";
    let out = eom_gen(&[
        "simulate",
        path,
        "--t-end",
        "0.25",
        "--dt",
        "1.5e-3",
        "--rho-inf",
        "1",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("the energy rose from") && err.contains("can gain none"),
        "{err}"
    );
    let v = ok_json(&[
        "simulate",
        path,
        "--t-end",
        "0.25",
        "--dt",
        "1e-3",
        "--rho-inf",
        "0.8",
        "--json",
    ]);
    assert_eq!(v["stop"], "finished", "{v}");
    let e = numbers(&v["energy"]);
    assert!(
        matches!(e[..], [Some(e0), Some(e1)] if e1 < e0),
        "energy {e:?}"
    );
}
