//! Every bundled model passes `check` with the counts its physics implies
//! (MODELS.md), its loops close at the initial state, and it survives a
//! round trip through the builder's RON writer.

use eom_gen::model::{Source, check, check_file, closure_gaps, initial_poses, parse};
use std::f64::consts::PI;

const MODELS: [&str; 14] = [
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
    "whipple",
];

fn path(name: &str) -> String {
    format!("{}/models/{name}.ron", env!("CARGO_MANIFEST_DIR"))
}

/// (nq, nu, cut joints, Grübler count, planar?) for each model.
fn expected(name: &str) -> (usize, usize, &'static [&'static str], i64, bool) {
    match name {
        "pendulum" => (1, 1, &[], 1, true),
        "double_pendulum" => (2, 2, &[], 2, true),
        "arm7" => (7, 7, &[], 7, false),
        // Unit quaternion: four coordinates, three speeds.
        "heavy_top" => (4, 3, &[], 3, false),
        "free_body" => (7, 6, &[], 6, false),
        // 3 bodies, 4 hinges: 3·3 − 4·2 = 1.
        "fourbar" => (3, 3, &["c"], 1, true),
        "slider_crank" => (3, 3, &["slider_pin"], 1, true),
        // The crank is prescribed: its coordinate leaves q and its freedom the count.
        "slider_crank_driven" => (2, 2, &["slider_pin"], 0, true),
        // 7 bodies, 10 hinges: 3·7 − 10·2 = 1.
        "andrews" => (7, 7, &["E3", "E4", "E6"], 1, true),
        // 5 bodies, 6 hinges in space: 6·5 − 6·5 = 0, although the mechanism moves.
        "bricard" => (5, 5, &["J6"], 0, false),
        // 13 bodies, 6 U (2), 6 P (1), 6 S (3): 78 − 6·(4 + 5 + 3) = 6.
        "stewart" => (22, 21, &["S2", "S3", "S4", "S5", "S6"], 6, false),
        "stewart_driven" => (16, 15, &["S2", "S3", "S4", "S5", "S6"], 0, false),
        // Free joint minus the holonomic contact condition.
        "rolling_disk" => (7, 6, &[], 5, false),
        // Free joint and three hinges minus the two contact conditions.
        "whipple" => (10, 9, &[], 7, false),
        other => panic!("no expectation for {other}"),
    }
}

#[test]
fn every_bundled_model_checks_with_the_expected_counts() {
    for name in MODELS {
        let checked = check_file(&path(name)).unwrap_or_else(|r| panic!("{name}:\n{r}"));
        let sys = &checked.system;
        let (nq, nu, cut, dof, planar) = expected(name);
        assert_eq!(sys.name, name);
        assert_eq!((sys.nq(), sys.nu()), (nq, nu), "{name}: (nq, nu)");
        assert_eq!(sys.coordinate_names().len(), nq, "{name}");
        assert_eq!(sys.speed_names().len(), nu, "{name}");
        assert_eq!(sys.cut_joint_names(), cut, "{name}: cut joints");
        assert_eq!(sys.grubler.dof, dof, "{name}: Grübler–Kutzbach count");
        assert_eq!(sys.grubler.planar, planar, "{name}: planar");
        assert!(
            checked.warnings.is_empty(),
            "{name}: {}",
            checked.source.render_all(&checked.warnings)
        );
    }
}

#[test]
fn every_loop_closes_at_the_initial_state() {
    for name in MODELS {
        let checked = check_file(&path(name)).unwrap_or_else(|r| panic!("{name}:\n{r}"));
        let sys = &checked.system;
        for (j, gap) in sys
            .cut_joint_names()
            .iter()
            .zip(closure_gaps(sys, &initial_poses(sys)))
        {
            assert!(
                gap.position < 1e-12 && gap.angle < 1e-12,
                "{name}: cut joint {j} open by {gap:?}"
            );
        }
    }
}

#[test]
fn initial_states_follow_models_md() {
    let q0 = |name: &str| {
        check_file(&path(name))
            .map(|c| c.system.q0())
            .unwrap_or_default()
    };
    let u0 = |name: &str| {
        check_file(&path(name))
            .map(|c| c.system.u0())
            .unwrap_or_default()
    };
    assert_eq!(q0("pendulum"), vec![PI / 2.0]);
    assert_eq!(
        q0("double_pendulum"),
        vec![2.0 * PI / 3.0, -13.0 * PI / 18.0]
    );
    let mut arm = vec![0.05; 7];
    arm[1] = PI + 0.05;
    assert_eq!(q0("arm7"), arm);
    assert_eq!(q0("heavy_top"), vec![1.0, 0.0, 0.0, 0.0]);
    assert_eq!(u0("heavy_top"), vec![0.0, 150.0, -4.61538]);
    assert_eq!(u0("free_body"), vec![0.0, 0.0, 0.0, 0.01, 1.0, 0.0]);
    // Fourbar: crank tip at +1 m/s along x means the cranks turn at −1 rad/s.
    assert_eq!(u0("fourbar"), vec![-1.0, 1.0, -1.0]);
    let andrews = check_file(&path("andrews")).unwrap_or_else(|r| panic!("{r}"));
    assert_eq!(
        andrews.system.coordinate_names(),
        ["beta", "theta", "gamma", "delta", "phi", "epsilon", "omega"]
    );
}

#[test]
fn andrews_loops_match_the_literature_constraints() {
    // Hairer & Wanner VII.7: g1 … g6 vanish at the published initial values.
    // Our cut joints close there to round-off (tested above); here we also
    // check the literature's own formulas with the model's parameters, so a
    // typo in the parameter table cannot hide.
    let checked = check_file(&path("andrews")).unwrap_or_else(|r| panic!("{r}"));
    let p = |n: &str| {
        checked
            .system
            .parameters
            .iter()
            .find(|p| p.name == n)
            .map(|p| p.value.value)
            .unwrap_or(f64::NAN)
    };
    let q = checked.system.q0();
    let (be, th, ga, de, ph, ep, om) = (q[0], q[1], q[2], q[3], q[4], q[5], q[6]);
    let (rr, d, ss, e, zt, zf, u) = (p("rr"), p("d"), p("ss"), p("e"), p("zt"), p("zf"), p("u"));
    let (xa, ya, xb, yb) = (p("xa"), p("ya"), p("xb"), p("yb"));
    let g = [
        rr * be.cos() - d * (be + th).cos() - ss * ga.sin() - xb,
        rr * be.sin() - d * (be + th).sin() + ss * ga.cos() - yb,
        rr * be.cos() - d * (be + th).cos() - e * (ph + de).sin() - zt * de.cos() - xa,
        rr * be.sin() - d * (be + th).sin() + e * (ph + de).cos() - zt * de.sin() - ya,
        rr * be.cos() - d * (be + th).cos() - zf * (om + ep).cos() - u * ep.sin() - xa,
        rr * be.sin() - d * (be + th).sin() - zf * (om + ep).sin() + u * ep.cos() - ya,
    ];
    for (k, gk) in g.iter().enumerate() {
        assert!(gk.abs() < 1e-15, "g{} = {gk:e}, want 0", k + 1);
    }
}

#[test]
fn every_bundled_model_round_trips_through_the_ron_writer() {
    for name in MODELS {
        let text = std::fs::read_to_string(path(name)).unwrap_or_default();
        let spec = parse(&Source::new(name, text)).unwrap_or_else(|r| panic!("{r}"));
        let written = spec.to_ron();
        let again =
            parse(&Source::new(name, written.clone())).unwrap_or_else(|r| panic!("{r}\n{written}"));
        assert_eq!(again, spec, "{name} after writing:\n{written}");
        // And the written text is itself a valid model.
        check(&Source::new(name, written)).unwrap_or_else(|r| panic!("{name}:\n{r}"));
    }
}
