//! The same slender beam by the absolute nodal coordinates (ANCF,
//! `Cable2D` assembled by `eom_sim::large`, issue #18) and by the floating
//! frame of reference (a `Flexible` `Beam` body on a `Fixed` joint to the
//! ground, the recursive dynamics of issue #17): two independent
//! formulations and code paths.
//!
//! - **Free vibration**: the first bending frequency of the clamped beam.
//!   Linearised about the straight state both are the cubic Hermite
//!   (Euler–Bernoulli) finite element with the consistent mass, so with
//!   the same mesh they agree to round-off (measured 1.6e-12), and both
//!   are within the FE error of `ω₁ = 1.8751² √(EI/(ρA L⁴))`, falling as
//!   h⁴ with the ANCF mesh.
//! - **Static deflection under the beam's own weight**: for a small load
//!   both give Euler–Bernoulli's `wL⁴/(8EI)` (nodally exact for cubic
//!   elements with the consistent load). As the load grows they part: the
//!   floating frame here is linear in its elastic coordinates (its tip
//!   moves straight down, `wL⁴/(8EI)` for every load), the ANCF cable
//!   follows the large deflection (the tip swings in and the beam
//!   stiffens against the lateral load). The relative difference of the
//!   tip deflections grows as the square of the load parameter `wL³/EI`
//!   (the first geometric correction of a transversely loaded cantilever
//!   is cubic in the load): measured 2.9e-9, 2.9e-7, 2.9e-5, 2.9e-3,
//!   2.5e-2 for `wL³/EI` = 4.8e-4 … 1.44 (tip 6e-5 L … 0.18 L), checked.

use eom_gen::System;
use eom_gen::functions::{Function, FunctionSet};
use eom_gen::mech::{Numeric, formulate};
use eom_gen::model::{Source, check};
use eom_sim::large::ancf::{Chain, ChainSpec, Section, Support, chain};
use eom_sim::large::{SparseMatrix, StaticOptions, solve_static};
use nalgebra::{DMatrix, DVector};

const L: f64 = 2.0;
const RHO_A: f64 = 3.0;
const EA: f64 = 5.0e5;
/// In-plane bending stiffness (the floating frame's `ei_z`, bending in y).
const EI: f64 = 500.0;
/// Out-of-plane bending, stiffer, so that the lowest mode is in-plane.
const EI_Y: f64 = 800.0;
const ELEMENTS: usize = 4;
/// All modes of the four-element clamped beam: the full FE space.
const K: usize = 24;

fn ffr_model(g: f64) -> String {
    format!(
        r#"Model(
    name: "cantilever",
    gravity: (0, -{g}, 0),
    bodies: [(name: "beam", flexible: Beam(length: {L}, rho_a: {RHO_A}, rho_ip: 0.01,
        ea: {EA}, ei_y: {EI_Y}, ei_z: {EI}, gj: 300, elements: {ELEMENTS},
        reference: Clamped, modes: {K}))],
    joints: [(name: "clamp", kind: Fixed, parent: "ground", child: "beam")],
    outputs: [NodePosition(body: "beam", node: {ELEMENTS})],
)"#
    )
}

fn ffr_system(g: f64) -> System {
    check(&Source::new("cantilever.ron", ffr_model(g)))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

/// `∂b/∂q` at `q = 0, u = 0` by central differences (`b` is linear in
/// `q` here: it is exact).
fn ffr_stiffness(num: &Numeric) -> DMatrix<f64> {
    let zero = vec![0.0; K];
    let mut k = DMatrix::zeros(K, K);
    for c in 0..K {
        let mut qp = zero.clone();
        qp[c] = 1e-4;
        let mut qm = zero.clone();
        qm[c] = -1e-4;
        let bp = num.terms(&qp, &zero, 0.0, &[]).unwrap().bias;
        let bm = num.terms(&qm, &zero, 0.0, &[]).unwrap().bias;
        for r in 0..K {
            k[(r, c)] = (bp[r] - bm[r]) / 2e-4;
        }
    }
    k
}

/// The floating frame's static tip under gravity `g`: `b(q, 0) = 0`
/// solved by Newton on the exact (linear) `b`, and the tip node's world
/// position from the model's outputs.
fn ffr_tip(g: f64) -> [f64; 2] {
    let sys = ffr_system(g);
    let num = Numeric::new(&sys).unwrap();
    let zero = vec![0.0; K];
    let k = ffr_stiffness(&num);
    let lu = k.lu();
    let mut q = zero.clone();
    for _ in 0..3 {
        let b = DVector::from_vec(num.terms(&q, &zero, 0.0, &[]).unwrap().bias);
        let dq = lu.solve(&(-b)).expect("K regular");
        for (x, d) in q.iter_mut().zip(dq.iter()) {
            *x += d;
        }
    }
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let point = eom_gen::interpret::Point {
        sys: &sys,
        q: &q,
        u: &zero,
        udot: &zero,
        tau: &zero,
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.0,
    };
    let values = eom_gen::interpret::run(f.program(Function::Outputs).expect("outputs"), &point);
    let labels = f.labels(Function::Outputs);
    let get = |name: &str| {
        let i = labels
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no output {name} in {labels:?}"));
        values[i]
    };
    let node = format!("beam_node{ELEMENTS}");
    [get(&format!("{node}_x")), get(&format!("{node}_y"))]
}

/// The ANCF cantilever: `Cable2D`, clamped at the origin along x, gravity
/// `g` along −y.
fn ancf(elements: usize, g: f64) -> Chain {
    let spec = ChainSpec {
        kernel: eom_sim::elements::Element::Cable2D,
        start: [0.0; 3],
        end: [L, 0.0, 0.0],
        elements,
        section: Section {
            e: 1.0,
            rho: RHO_A / EA,
            area: EA,
            inertia: EI,
            ..Section::default()
        },
        start_support: Support::Clamped,
        end_support: Support::Free,
        end_force: [0.0; 3],
        end_mass: 0.0,
        gravity: [0.0, -g, 0.0],
    };
    chain(&spec).unwrap_or_else(|e| panic!("{e}"))
}

fn ancf_tip(elements: usize, g: f64) -> [f64; 2] {
    let ch = ancf(elements, g);
    let opts = StaticOptions {
        load_steps: 10,
        ..StaticOptions::default()
    };
    let sol = solve_static(&ch.model, &opts).unwrap_or_else(|e| panic!("{e}"));
    let p = ch.node_position(&sol.q, ch.nodes - 1);
    [p[0], p[1]]
}

/// Lowest nonzero `ω` of `det(K − ω² M) = 0` (`M` positive definite).
fn lowest(m: &DMatrix<f64>, k: &DMatrix<f64>) -> f64 {
    let l = m.clone().cholesky().expect("M positive definite").l();
    let li = l.try_inverse().expect("regular");
    let a = &li * k * li.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let mut w2: Vec<f64> = a.symmetric_eigenvalues().iter().copied().collect();
    w2.sort_by(f64::total_cmp);
    let top = w2.last().copied().unwrap_or(1.0);
    w2.into_iter()
        .find(|&x| x > 1e-9 * top)
        .expect("an elastic mode")
        .sqrt()
}

fn dense(s: &SparseMatrix, n: usize) -> DMatrix<f64> {
    DMatrix::from_fn(n, n, |r, c| s.get(r, c))
}

#[test]
fn ancf_and_floating_frame_have_the_same_first_frequency() {
    let want = 1.875_104_068_711_961_f64.powi(2) * (EI / (RHO_A * L.powi(4))).sqrt();
    // Floating frame: M(0) and ∂b/∂q of the beam alone (no gravity).
    let num = Numeric::new(&ffr_system(0.0)).unwrap();
    let zero = vec![0.0; K];
    let m = num.terms(&zero, &zero, 0.0, &[]).unwrap().mass_matrix;
    let m = DMatrix::from_fn(K, K, |r, c| m[r][c]);
    let w_ffr = lowest(&m, &ffr_stiffness(&num));
    // ANCF, the same mesh: the tangent at the straight reference.
    let ch = ancf(ELEMENTS, 0.0);
    let model = &ch.model;
    let n = model.n_free();
    let q = model.q0().to_vec();
    let mut kt = SparseMatrix::zeros(model.pattern().clone());
    model.jacobian(&q, &vec![0.0; q.len()], 1.0, 0.0, 0.0, &mut kt);
    let w_ancf = lowest(&dense(model.mass(), n), &dense(&kt, n));
    // A finer ANCF mesh, nearer the closed form.
    let ch16 = ancf(16, 0.0);
    let m16 = &ch16.model;
    let q16 = m16.q0().to_vec();
    let mut k16 = SparseMatrix::zeros(m16.pattern().clone());
    m16.jacobian(&q16, &vec![0.0; q16.len()], 1.0, 0.0, 0.0, &mut k16);
    let w16 = lowest(&dense(m16.mass(), m16.n_free()), &dense(&k16, m16.n_free()));
    eprintln!(
        "ω₁: floating frame ({ELEMENTS} elements) {w_ffr:.12}, ANCF ({ELEMENTS}) {w_ancf:.12}, \
         ANCF (16) {w16:.12}, Euler–Bernoulli {want:.12}; FFR/ANCF − 1 = {:.1e}, \
         FE error {:.1e} / {:.1e}",
        w_ffr / w_ancf - 1.0,
        w_ancf / want - 1.0,
        w16 / want - 1.0
    );
    assert!((w_ffr / w_ancf - 1.0).abs() < 1e-8, "{w_ffr} {w_ancf}");
    // The FE error of cubic elements with the consistent mass falls as
    // h⁴: measured 3.3e-5 at 4 elements, 1.3e-7 at 16 (256× less).
    assert!((w_ancf / want - 1.0).abs() < 5e-5, "{w_ancf} {want}");
    let order = ((w_ancf / want - 1.0) / (w16 / want - 1.0)).log(4.0);
    assert!((order - 4.0).abs() < 0.1, "order {order}");
}

#[test]
fn ancf_and_floating_frame_agree_for_small_deflection_and_part_as_it_grows() {
    // Gravity g on ρA = 3 kg/m: load parameter wL³/EI = 0.048 g, the tip
    // deflection by Euler–Bernoulli wL⁴/(8EI) = 1.2e-2 g m on the 2 m beam.
    let mut parting = Vec::new();
    for g in [0.01, 0.1, 1.0, 10.0, 30.0] {
        let w = RHO_A * g;
        let eb = w * L.powi(4) / (8.0 * EI);
        let ffr = ffr_tip(g);
        let an = ancf_tip(16, g);
        let rel = (an[1] - ffr[1]).abs() / ffr[1].abs();
        eprintln!(
            "g = {g:>5}: wL³/EI = {:.4}, EB tip −{eb:.6e} m; FFR tip ({:.9}, {:.9e}), \
             ANCF (16) tip ({:.9}, {:.9e}); |Δy|/|y| = {rel:.2e}",
            w * L.powi(3) / EI,
            ffr[0],
            ffr[1],
            an[0],
            an[1]
        );
        // The floating frame (linear in its elastic coordinates): the
        // Euler–Bernoulli deflection, straight down, at every load.
        assert!((ffr[1] / -eb - 1.0).abs() < 1e-9, "FFR {ffr:?} vs {eb}");
        assert!((ffr[0] - L).abs() < 1e-12, "FFR {ffr:?}");
        parting.push(rel);
    }
    // Small deflection (tip 1.2e-4 m and 1.2e-3 m): the two agree to
    // 1e-5 of the deflection.
    assert!(parting[0] < 1e-7 && parting[1] < 1e-5, "{parting:?}");
    // They part as (wL³/EI)²: 100× per decade of load.
    for w in parting.windows(2).take(3) {
        let slope = (w[1] / w[0]).log10();
        assert!((slope - 2.0).abs() < 0.1, "slope {slope}: {parting:?}");
    }
    // At g = 30 (tip deflection 18 % of L by Euler–Bernoulli) the ANCF tip
    // is more than 1 % above the linear one.
    assert!(parting[4] > 1e-2, "{parting:?}");
}
