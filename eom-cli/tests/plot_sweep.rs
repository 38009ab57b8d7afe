//! `eom-gen plot`, `simulate --plot` and `eom-gen sweep`: time histories
//! drawn from a run's CSV (the energy drift of a conservative four-bar and
//! its constraint residuals, which projection keeps at round-off), unknown
//! columns named with the ones there are; sweeps of a pendulum against the
//! same runs made one by one with `--param`, a failed case a row with its
//! reason, and shards merged equal to one run.

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
        .map(|l| l.split(',').nth(k).and_then(|x| x.parse().ok()).unwrap_or(f64::NAN))
        .collect()
}

#[test]
fn simulate_plot_draws_coordinates_energy_drift_and_residuals() {
    // The four-bar is conservative: T + V stays at its initial value to
    // the integrator's tolerance, and projection keeps |Φ| and |Φ̇| at
    // round-off; both are drawn, with the coordinates in rad.
    let (csv, svg) = (temp_path("fourbar.csv"), temp_path("fourbar.svg"));
    ok(&[
        "simulate", "models/fourbar.ron", "--t-end", "1", "--interpret", "--every", "0.05",
        "--csv", &csv, "--plot", &svg,
    ]);
    let text = std::fs::read_to_string(&csv).expect("csv");
    let (t, v) = (column(&text, "kinetic_energy"), column(&text, "potential_energy"));
    let e0 = t[0] + v[0];
    for (a, b) in t.iter().zip(&v) {
        assert!(((a + b) - e0).abs() < 1e-5 * e0.abs(), "energy {} vs {e0}", a + b);
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
        "simulate", "models/pendulum.ron", "--t-end", "0.5", "--interpret", "--every", "0.05",
        "--csv", &csv,
    ]);
    ok(&["plot", &csv, "--y", "theta+theta_dot,energy", "-o", &svg, "--model", "models/pendulum.ron"]);
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
