//! `eom-gen plot`, `simulate --plot` and `eom-gen sweep`: time histories
//! drawn from a run's CSV (the energy drift of a conservative four-bar and
//! its constraint residuals, which projection keeps at round-off), unknown
//! columns named with the ones there are; sweeps of a pendulum against the
//! same runs made one by one with `--param`, a failed case a row with its
//! reason, and shards merged equal to one run; `animate` writing its page
//! of poses, and refusing what does not apply.

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
        .join(format!("eom-plot-sweep-{}-{name}", std::process::id()))
        .to_string_lossy()
        .into_owned()
}

fn ok(args: &[&str]) -> Output {
    let out = eom_gen(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Rows of a CSV by column name.
fn column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let k = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no column `{name}` in {header:?}"));
    lines
        .map(|l| {
            l.split(',')
                .nth(k)
                .and_then(|x| x.parse().ok())
                .unwrap_or(f64::NAN)
        })
        .collect()
}

#[test]
fn simulate_plot_draws_coordinates_energy_drift_and_residuals() {
    // The four-bar is conservative: T + V stays at its initial value to
    // the integrator's tolerance, and projection keeps |Φ| and |Φ̇| at
    // round-off; both are drawn, with the coordinates in rad.
    let (csv, svg) = (temp_path("fourbar.csv"), temp_path("fourbar.svg"));
    ok(&[
        "simulate",
        "models/fourbar.ron",
        "--t-end",
        "1",
        "--interpret",
        "--every",
        "0.05",
        "--csv",
        &csv,
        "--plot",
        &svg,
    ]);
    let text = std::fs::read_to_string(&csv).expect("csv");
    let (t, v) = (
        column(&text, "kinetic_energy"),
        column(&text, "potential_energy"),
    );
    let e0 = t[0] + v[0];
    for (a, b) in t.iter().zip(&v) {
        assert!(
            ((a + b) - e0).abs() < 1e-5 * e0.abs(),
            "energy {} vs {e0}",
            a + b
        );
    }
    for c in ["constraint_residual", "velocity_constraint_residual"] {
        let worst = column(&text, c).iter().fold(0.0f64, |m, x| m.max(*x));
        assert!(worst < 1e-10, "{c}: got {worst}, want round-off");
    }
    let svg_text = std::fs::read_to_string(&svg).expect("svg");
    for label in ["phi1", "energy_drift", "constraint_residual", "rad", "t, s"] {
        assert!(svg_text.contains(label), "no `{label}` in the plot");
    }
    let _ = std::fs::remove_file(csv);
    let _ = std::fs::remove_file(svg);
}

#[test]
fn plot_draws_named_columns_and_names_the_ones_there_are() {
    let (csv, svg) = (temp_path("pendulum.csv"), temp_path("pendulum.svg"));
    ok(&[
        "simulate",
        "models/pendulum.ron",
        "--t-end",
        "0.5",
        "--interpret",
        "--every",
        "0.05",
        "--csv",
        &csv,
    ]);
    ok(&[
        "plot",
        &csv,
        "--y",
        "theta+theta_dot,energy",
        "-o",
        &svg,
        "--model",
        "models/pendulum.ron",
    ]);
    let s = std::fs::read_to_string(&svg).expect("svg");
    for label in ["theta, rad", "theta_dot, rad/s", "energy", "\nJ\n"] {
        assert!(s.contains(label), "no `{label}` in the plot");
    }
    let out = eom_gen(&["plot", &csv, "--y", "theta,q9", "-o", &svg]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("no column `q9`"), "{err}");
    assert!(err.contains("t, theta, theta_dot"), "{err}");
    let _ = std::fs::remove_file(csv);
    let _ = std::fs::remove_file(svg);
}

/// The results of a sweep: header and rows (the quoted `stop` last).
fn results(dir: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(format!("{dir}/results.csv")).expect("results.csv");
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| {
            let (numbers, stop) = l.split_once(",\"").unwrap_or((l, ""));
            numbers
                .split(',')
                .map(String::from)
                .chain([stop.trim_end_matches('"').to_string()])
                .collect()
        })
        .collect();
    (header, rows)
}

fn value(header: &[String], row: &[String], name: &str) -> f64 {
    let k = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no `{name}`"));
    row[k].parse().unwrap_or(f64::NAN)
}

#[test]
fn sweep_equals_runs_one_by_one_and_keeps_failed_cases() {
    // A pendulum's motion depends on its length, not its mass: rows of
    // equal `l` have equal final angles whatever `m`, and each equals
    // `simulate --interpret --param l=…` (one formulation with `l`, `m`
    // tunable against code regenerated with the values inlined: the same
    // to round-off). `m = -1` is refused by the model's check: a row with
    // the reason, the others run, exit 3.
    let dir = temp_path("sweep");
    let out = eom_gen(&[
        "sweep",
        "models/pendulum.ron",
        "--param",
        "l=0.5:1.5:0.5",
        "--param",
        "m=-1,1,2",
        "--t-end",
        "1",
        "--output",
        "bob_tip_x",
        "--out",
        &dir,
    ]);
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (h, rows) = results(&dir);
    assert_eq!(rows.len(), 9);
    for r in &rows {
        let (l, m) = (value(&h, r, "l"), value(&h, r, "m"));
        let stop = r.last().map(String::as_str).unwrap_or_default();
        if m < 0.0 {
            assert!(stop.contains("mass of body `bob` is -1 kg"), "{stop}");
            assert!(value(&h, r, "theta").is_nan());
            continue;
        }
        assert_eq!(stop, "finished");
        let twin = rows
            .iter()
            .find(|s| value(&h, s, "l") == l && value(&h, s, "m") != m && value(&h, s, "m") > 0.0)
            .expect("the other mass");
        assert_eq!(value(&h, r, "theta"), value(&h, twin, "theta"), "l = {l}");
        let theta = value(&h, r, "theta");
        // The output is the tip's x = l sin θ.
        let x = value(&h, r, "bob_tip_x");
        assert!(
            (x - l * theta.sin()).abs() < 1e-12,
            "x {x}, l sin θ {}",
            l * theta.sin()
        );
        if m == 1.0 {
            let out = ok(&[
                "simulate",
                "models/pendulum.ron",
                "--interpret",
                "--t-end",
                "1",
                "--json",
                "--param",
                &format!("l={l}"),
            ]);
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
            let want = v["q"][0].as_f64().unwrap_or(f64::NAN);
            assert!(
                (theta - want).abs() < 1e-9,
                "l = {l}: sweep {theta}, simulate {want}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn shards_merged_equal_one_run() {
    // Seeded random samples of a double pendulum, run whole and as three
    // shards: the merged table equals the whole one (all but `cpu_s`).
    let args = |out: &str, shard: Option<&str>| {
        let mut v: Vec<String> = [
            "sweep",
            "models/double_pendulum.ron",
            "--param",
            "m1=0.5:2",
            "--param",
            "l2=0.5,1",
            "--samples",
            "7",
            "--seed",
            "3",
            "--t-end",
            "0.5",
            "--out",
            out,
        ]
        .map(String::from)
        .to_vec();
        if let Some(s) = shard {
            v.extend(["--shard".to_string(), s.to_string()]);
        }
        v
    };
    let run = |v: Vec<String>| ok(&v.iter().map(String::as_str).collect::<Vec<_>>());
    let whole = temp_path("whole");
    run(args(&whole, None));
    let shards: Vec<String> = (0..3).map(|i| temp_path(&format!("shard{i}"))).collect();
    for (i, d) in shards.iter().enumerate() {
        run(args(d, Some(&format!("{i}/3"))));
    }
    let merged = temp_path("merged");
    let mut m = vec!["sweep", "--merge"];
    m.extend(shards.iter().map(String::as_str));
    m.extend(["--out", &merged]);
    ok(&m);
    let (h1, r1) = results(&whole);
    let (h2, r2) = results(&merged);
    assert_eq!(h1, h2);
    let cpu = h1.iter().position(|h| h == "cpu_s").expect("cpu_s");
    let strip = |rows: Vec<Vec<String>>| -> Vec<Vec<String>> {
        rows.into_iter()
            .map(|mut r| {
                r.remove(cpu);
                r
            })
            .collect()
    };
    assert_eq!(strip(r1), strip(r2));
    // A shard missing is refused.
    let out = eom_gen(&["sweep", "--merge", &shards[0], &shards[1], "--out", &merged]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("a shard is missing"));
    for d in shards.iter().chain([&whole, &merged]) {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn derived_parameters_follow_the_swept_one() {
    // Bricard's inertias are defined through its mass (`il = m(b²+b²)/12`,
    // `it = m(a²+b²)/12`): a case with another `m` changes them, so it is
    // formulated on its own and equals `simulate --param m=2`. Scaling
    // every mass and inertia by one factor scales M and the gravity
    // forces alike: the motion is the same for m = 1 and m = 2.
    let dir = temp_path("bricard");
    let out = ok(&[
        "sweep",
        "models/bricard.ron",
        "--param",
        "m=1,2",
        "--t-end",
        "0.2",
        "--out",
        &dir,
    ]);
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("1 formulated on their own"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let (h, rows) = results(&dir);
    let single = ok(&[
        "simulate",
        "models/bricard.ron",
        "--interpret",
        "--param",
        "m=2",
        "--t-end",
        "0.2",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&single.stdout).expect("json");
    for k in 1..=5 {
        let name = format!("q{k}");
        let (a, b) = (value(&h, &rows[0], &name), value(&h, &rows[1], &name));
        assert!(
            (a - b).abs() < 1e-10,
            "{name}: m = 1 gives {a}, m = 2 gives {b}"
        );
        let want = v["q"][k - 1].as_f64().unwrap_or(f64::NAN);
        assert!(
            (b - want).abs() < 1e-12,
            "{name}: sweep {b}, simulate {want}"
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn animate_writes_one_page_of_poses() {
    // `animate` is `simulate` writing its page: 1 s every 50 ms is 21
    // frames of two bodies; the CSV asked for alongside is still written.
    let (csv, html) = (temp_path("dp.csv"), temp_path("dp.html"));
    ok(&[
        "animate",
        "models/double_pendulum.ron",
        "--t-end",
        "1",
        "--every",
        "0.05",
        "--interpret",
        "--csv",
        &csv,
        "-o",
        &html,
    ]);
    let page = std::fs::read_to_string(&html).expect("html");
    assert!(page.contains(r#"<script id="eom-data" type="application/json">"#));
    assert!(page.contains("OrbitControls"), "three.js is inlined");
    assert_eq!(
        column(&std::fs::read_to_string(&csv).expect("csv"), "t").len(),
        21
    );
    let _ = std::fs::remove_file(csv);
    let _ = std::fs::remove_file(html);
    // --html is simulate's.
    let out = eom_gen(&[
        "animate",
        "models/pendulum.ron",
        "--t-end",
        "1",
        "--html",
        "a.html",
        "-o",
        "b.html",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("writes its page to -o"), "{err}");
}

/// A cable's deformed shape is in the page: the falling ANCF pendulum
/// (16 elements, 17 nodes, pinned at the origin, released along +x) has
/// its 17 nodes per frame; the pinned node stays at the origin and at
/// t = 0 the nodes lie on the undeformed rod, x = 1.2 k/16, y = z = 0.
#[test]
fn animate_draws_a_cable_deformed() {
    let html = temp_path("cable.html");
    ok(&[
        "animate",
        "models/ancf/pendulum.ron",
        "--t-end",
        "0.1",
        "--dt",
        "1e-3",
        "-o",
        &html,
    ]);
    let page = std::fs::read_to_string(&html).expect("html");
    let _ = std::fs::remove_file(&html);
    let start = page.find(r#"type="application/json">"#).map(|i| i + 24);
    let data = start.and_then(|s| Some(&page[s..s + page[s..].find("</script>")?]));
    let v: serde_json::Value = serde_json::from_str(data.unwrap_or("")).expect("the page's data");
    assert_eq!(
        v["cables"],
        serde_json::json!([{ "name": "rod", "nodes": 17 }])
    );
    let frames = v["cableFrames"].as_array().cloned().unwrap_or_default();
    assert_eq!(frames.len(), v["t"].as_array().map_or(0, Vec::len));
    assert_eq!(frames.len(), 11, "every 10 ms over 0.1 s");
    let at = |f: &serde_json::Value, k: usize| -> Vec<f64> {
        (0..3)
            .map(|c| f[3 * k + c].as_f64().unwrap_or(f64::NAN))
            .collect()
    };
    for k in 0..17 {
        let p = at(&frames[0], k);
        let want = [1.2 * k as f64 / 16.0, 0.0, 0.0];
        for (a, b) in p.iter().zip(want) {
            assert!((a - b).abs() < 1e-6, "node {k} at t = 0: {p:?}");
        }
    }
    for f in &frames {
        assert!(
            at(f, 0).iter().all(|x| x.abs() < 1e-6),
            "the pinned node moved"
        );
    }
    // The tip falls under gravity (−y).
    assert!(at(&frames[10], 16)[1] < -1e-3);
}
