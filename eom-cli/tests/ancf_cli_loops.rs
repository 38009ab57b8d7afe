//! `eom-gen simulate` on a mixed model whose rigid part closes a loop
//! (issue #18): the bundled `models/ancf/fourbar_cable.ron`, a crank-rocker
//! four-bar (cut joint) whose coupler carries a hanging cable. Checked from
//! the JSON report: the loop closes at the end (crank tip plus coupler
//! reaches the rocker's tip) and the cable's first node sits at the
//! coupler's middle, both to the Newton tolerance; energy kept; initial
//! values that open the loop are refused with the coordinate named.

use std::process::{Command, Output};

fn eom_gen(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eom-gen"))
        .args(args)
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
        .output()
        .expect("eom-gen runs")
}

#[test]
fn simulate_runs_the_fourbar_with_a_cable_and_refuses_an_open_loop() {
    let out = eom_gen(&[
        "simulate",
        "models/ancf/fourbar_cable.ron",
        "--t-end",
        "0.3",
        "--dt",
        "1e-3",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(v["stats"]["accepted"], 300);
    let num = |x: &serde_json::Value| x.as_f64().unwrap_or(f64::NAN);
    let q: Vec<f64> = (0..3).map(|k| num(&v["q"][k])).collect();
    let (a, c, d) = (0.2, 0.5, 0.6_f64);
    let b = (d * d + (c - a) * (c - a)).sqrt();
    let (t1, t12, t3) = (q[0], q[0] + q[1], q[2]);
    // Crank tip + coupler = rocker tip: the cut joint holds.
    let coupler_end = [a * t1.cos() + b * t12.cos(), a * t1.sin() + b * t12.sin()];
    let rocker_tip = [d + c * t3.cos(), c * t3.sin()];
    let gap = (coupler_end[0] - rocker_tip[0]).hypot(coupler_end[1] - rocker_tip[1]);
    // The cable's first node at the coupler's middle.
    let mid = [
        a * t1.cos() + 0.5 * b * t12.cos(),
        a * t1.sin() + 0.5 * b * t12.sin(),
    ];
    let node = &v["cables"][0]["first_node"];
    let first = [num(&node[0]), num(&node[1])];
    let off = (first[0] - mid[0]).hypot(first[1] - mid[1]);
    println!("q = {q:?}: loop gap {gap:.1e} m, first node off the coupler's middle {off:.1e} m");
    assert!(gap < 1e-9 && off < 1e-9, "gap {gap:e}, off {off:e}");
    // The crank moved.
    assert!(
        (q[0] - (std::f64::consts::FRAC_PI_2 - 0.2)).abs() > 0.1,
        "{q:?}"
    );
    assert!(num(&v["largest_constraint_residual"]) < 1e-9);
    // Energy (scale: about 3 J of potential released) kept without damping.
    assert!((num(&v["energy"][1]) - num(&v["energy"][0])).abs() < 1e-3);
    // Initial values that do not close the loop.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/fourbar_cable.ron"
    ))
    .expect("the bundled model");
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../target/ancf-cli-tests");
    std::fs::create_dir_all(dir).expect("a scratch directory");
    let path = format!("{dir}/open_loop.ron");
    std::fs::write(&path, text.replace("q0: [\"r0\"]", "q0: [\"r0 + 0.01\"]"))
        .expect("write the model");
    let out = eom_gen(&["simulate", &path, "--t-end", "0.01"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("do not close its loops (C.0, C.1)") && err.contains("`phi3` from"),
        "{err}"
    );
}
