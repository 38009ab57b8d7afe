//! Outputs of flexible bodies (issue #17): deformation, stress resultants
//! at a section, node positions and strain energy, against the closed
//! forms of a cantilever under its own weight at static equilibrium, and
//! their validation errors.

use eom_gen::System;
use eom_gen::functions::{Function, FunctionSet};
use eom_gen::mech::{Numeric, formulate};
use eom_gen::model::{Source, check};
use nalgebra::{DMatrix, DVector};

const L: f64 = 2.0;
const RHO_A: f64 = 3.0;
const EA: f64 = 5.0e5;
const EI_Y: f64 = 800.0;
const EI_Z: f64 = 500.0;
const G: f64 = 9.81;
/// Four elements, all 24 modes of the clamped beam: the full FE space.
const ELEMENTS: usize = 4;
const K: usize = 24;

fn model(gravity: &str, outputs: &str) -> String {
    format!(
        r#"Model(
    name: "cantilever",
    gravity: {gravity},
    bodies: [(name: "beam", flexible: Beam(length: {L}, rho_a: {RHO_A}, rho_ip: 0.01,
        ea: {EA}, ei_y: {EI_Y}, ei_z: {EI_Z}, gj: 300, elements: {ELEMENTS},
        reference: Clamped, modes: {K}))],
    joints: [(name: "clamp", kind: Fixed, parent: "ground", child: "beam")],
    outputs: [{outputs}],
)"#
    )
}

fn system(text: &str) -> System {
    check(&Source::new("cantilever.ron", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

/// The static equilibrium `b(q, 0) = 0` (`b = K q − Q_g`, linear in `q`).
fn equilibrium(num: &Numeric) -> Vec<f64> {
    let zero = vec![0.0; K];
    let b0 = DVector::from_vec(num.terms(&zero, &zero, 0.0, &[]).unwrap().bias);
    let mut k = DMatrix::zeros(K, K);
    for c in 0..K {
        let mut q = zero.clone();
        q[c] = 1e-3;
        let b = num.terms(&q, &zero, 0.0, &[]).unwrap().bias;
        for r in 0..K {
            k[(r, c)] = (b[r] - b0[r]) / 1e-3;
        }
    }
    let q = k.lu().solve(&(-b0)).expect("K regular");
    q.iter().copied().collect()
}

/// The outputs program at `q`, by name.
fn outputs(sys: &System, q: &[f64]) -> Vec<(String, f64)> {
    let f = formulate(sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let zero = vec![0.0; q.len()];
    let point = eom_gen::interpret::Point {
        sys,
        q,
        u: &zero,
        udot: &zero,
        tau: &zero,
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.0,
    };
    let values = eom_gen::interpret::run(f.program(Function::Outputs).expect("outputs"), &point);
    f.labels(Function::Outputs)
        .iter()
        .cloned()
        .zip(values)
        .collect()
}

fn get(out: &[(String, f64)], name: &str) -> f64 {
    out.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no output `{name}` in {out:?}"))
        .1
}

fn close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol * want.abs().max(1e-12),
        "{what}: got {got}, want {want}"
    );
}

#[test]
fn flex_outputs_of_a_cantilever_under_its_own_weight() {
    // Weight w = ρA g along −y on a cantilever along x, clamped at the
    // origin. Euler–Bernoulli: tip deflection −w L⁴/(8 EI_z), tip slope
    // −w L³/(6 EI_z), root moment M_z = −w L²/2, root shear Q_y = −w L,
    // strain energy w² L⁵/(40 EI_z). With all modes of cubic elements and
    // the consistent load, the nodal values are exact; the section forces
    // from the interpolation are exact up to the element's fixed-end
    // values: M_z(0) = −w L²/2 + w l²/12, Q_y(0) = −w L + w l/2 (l = L/4).
    let outs = "Deformation(name: \"tip\", body: \"beam\", x: 2), \
         SectionForces(name: \"root\", body: \"beam\", x: 0), \
         SectionForces(name: \"mid\", body: \"beam\", x: 0.75), \
         NodePosition(body: \"beam\", node: 4), ElasticEnergy(body: \"beam\"), Energy";
    let sys = system(&model(&format!("(0, -{G}, 0)"), outs));
    let num = Numeric::new(&sys).unwrap();
    let q = equilibrium(&num);
    let out = outputs(&sys, &q);
    let w = RHO_A * G;
    let l = L / ELEMENTS as f64;
    close(
        get(&out, "tip_uy"),
        -w * L.powi(4) / (8.0 * EI_Z),
        1e-9,
        "tip u_y",
    );
    close(
        get(&out, "tip_rz"),
        -w * L.powi(3) / (6.0 * EI_Z),
        1e-9,
        "tip θ_z",
    );
    for n in [
        "tip_ux", "tip_uz", "tip_rx", "tip_ry", "root_N", "root_Qz", "root_My",
    ] {
        assert!(get(&out, n).abs() < 1e-9, "{n} = {}", get(&out, n));
    }
    close(
        get(&out, "root_Mz"),
        -w * L * L / 2.0 + w * l * l / 12.0,
        1e-9,
        "root M_z",
    );
    close(get(&out, "root_Qy"), -w * L + w * l / 2.0, 1e-9, "root Q_y");
    // Mid-element x = 0.75 (ξ = 1/2, where the fixed-end correction of the
    // moment is −w l²/24): M_z = −w (L − x)²/2 − w l²/24 … and Q_y there
    // is the exact −w (L − x) (the particular solution's shear vanishes
    // mid-element).
    let x = 0.75;
    close(
        get(&out, "mid_Mz"),
        -w * (L - x).powi(2) / 2.0 - w * l * l / 24.0,
        1e-9,
        "M_z(0.75)",
    );
    close(get(&out, "mid_Qy"), -w * (L - x), 1e-9, "Q_y(0.75)");
    // The tip node in the world (the frame is the ground's).
    close(get(&out, "beam_node4_x"), L, 1e-12, "tip node x");
    close(
        get(&out, "beam_node4_y"),
        get(&out, "tip_uy"),
        1e-12,
        "tip node y",
    );
    // Strain energy: the output equals ½ q_fᵀ K_ff q_f; and the FE
    // solution, the energy projection of the exact one with the error
    // w_p = w ξ²(l − ξ)²/(24 EI_z) in each element, holds the closed form
    // w² L⁵/(40 EI_z) less n · w² l⁵/(1440 EI_z), the error's energy.
    let kff = &sys.bodies[1]
        .flexible
        .as_deref()
        .unwrap()
        .invariants
        .modal_stiffness;
    let qv = DVector::from_vec(q.clone());
    let strain = 0.5 * qv.dot(&(kff * &qv));
    close(
        get(&out, "beam_strain_energy"),
        strain,
        1e-12,
        "strain energy",
    );
    let exact = w * w * L.powi(5) / (40.0 * EI_Z);
    eprintln!(
        "strain energy {strain:.9} J, Euler–Bernoulli {exact:.9} J ({:+.1e})",
        strain / exact - 1.0
    );
    let fe = exact - ELEMENTS as f64 * w * w * l.powi(5) / (1440.0 * EI_Z);
    close(
        strain,
        fe,
        1e-9,
        "strain energy against w² L⁵/(40 EI) − n w² l⁵/(1440 EI)",
    );
    // The potential energy of `energy()` holds the strain energy: V = U − Σ m g·c.
    let (_, v) = num.energy(&q, &[0.0; K], 0.0).unwrap();
    let first_moment_y = sys.bodies[1]
        .flexible
        .as_deref()
        .unwrap()
        .invariants
        .s_bar
        .row(1)
        * &qv;
    close(v, strain + G * first_moment_y[0], 1e-12, "V = U + m g y_c");
}

#[test]
fn flex_outputs_axial_force_of_a_hanging_beam() {
    // Gravity along +x: the beam hangs from its clamp. N(x) = w (L − x);
    // linear axial elements give the element-average strain, so
    // N_FE(0) = w (L − l/2) exactly, and the tip moves down by
    // w L²/(2 EA) (exact at the nodes).
    let outs = "SectionForces(name: \"root\", body: \"beam\", x: 0), \
         Deformation(name: \"tip\", body: \"beam\", x: 2)";
    let sys = system(&model(&format!("({G}, 0, 0)"), outs));
    let num = Numeric::new(&sys).unwrap();
    let q = equilibrium(&num);
    let out = outputs(&sys, &q);
    let w = RHO_A * G;
    let l = L / ELEMENTS as f64;
    close(get(&out, "root_N"), w * (L - l / 2.0), 1e-9, "root N");
    close(get(&out, "tip_ux"), w * L * L / (2.0 * EA), 1e-9, "tip u_x");
}

#[test]
fn flex_output_errors_are_located() {
    let text = model(
        "(0, -9.81, 0)",
        "Deformation(name: \"2tip\", body: \"beam\", x: 3), NodePosition(body: \"beam\", node: 5), \
         ElasticEnergy(body: \"ground\"), SectionForces(name: \"s\", body: \"bem\", x: 1)",
    );
    let report = match check(&Source::new("cantilever.ron", text)) {
        Ok(_) => panic!("want errors"),
        Err(r) => r.to_string(),
    };
    for want in [
        "output name `2tip` is not an identifier",
        "section x = 3 m is not on beam `beam`, which runs from 0 to 2 m",
        "node 5 does not exist: beam `beam` has nodes 0..=4",
        "output `ElasticEnergy` needs a flexible body, but `ground` is rigid",
        "unknown output body `bem`",
        "cantilever.ron:8:",
    ] {
        assert!(report.contains(want), "want `{want}` in:\n{report}");
    }
}

/// Outputs on an assumed-mode body: a named node's position is its place
/// plus the written shapes there (`x + u(x)`, `v(x)`, `w(x)` at amplitude
/// `q`); sections need the beam's elements and are refused at the field.
#[test]
fn flex_outputs_of_assumed_modes_at_their_nodes() {
    let text = |outputs: &str| {
        format!(
            r#"Model(
    name: "rod",
    gravity: (0, 0, 0),
    bodies: [(name: "rod", flexible: AssumedModes(length: 2, rho_a: 1.2, rho_ip: 1e-4,
        ea: 2.8e7, ei_y: 1.4e4, ei_z: 1.4e4, gj: 1e4,
        shapes: [(v: "sin(pi*x/2)"), (u: "x/2", w: "x*x/4")],
        nodes: [(name: "mid", x: 0.5), (name: "tip", x: 2)]))],
    joints: [(name: "hub", kind: Fixed, parent: "ground", child: "rod")],
    outputs: [{outputs}],
)"#
        )
    };
    let sys = check(&Source::new(
        "rod.ron",
        text("NodePosition(body: \"rod\", node: 0), NodePosition(body: \"rod\", node: 1)"),
    ))
    .unwrap_or_else(|r| panic!("{r}"))
    .system;
    let q = [0.03, -0.02];
    let out = outputs(&sys, &q);
    for (k, x) in [(0usize, 0.5f64), (1, 2.0)] {
        let want = [
            x + q[1] * x / 2.0,
            q[0] * (std::f64::consts::PI * x / 2.0).sin(),
            q[1] * x * x / 4.0,
        ];
        for (c, w) in want.iter().enumerate() {
            let got = out[3 * k + c].1;
            assert!(
                (got - w).abs() < 1e-12,
                "node {k} component {c}: {got} vs {w}"
            );
        }
    }
    let report = match check(&Source::new(
        "rod.ron",
        text(
            "Deformation(name: \"d\", body: \"rod\", x: 1), NodePosition(body: \"rod\", node: 2), \
             SectionForces(name: \"s\", body: \"rod\", x: 1)",
        ),
    )) {
        Ok(_) => panic!("want errors"),
        Err(r) => r.to_string(),
    };
    for want in [
        "rod.ron:9:",
        "output `Deformation` at a section needs the built-in beam's elements, but `rod` has assumed modes",
        "output `SectionForces` at a section needs the built-in beam's elements",
        "node 2 does not exist: `rod` has nodes 0..=1",
    ] {
        assert!(report.contains(want), "want `{want}` in:\n{report}");
    }
}
