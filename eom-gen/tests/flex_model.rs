//! Flexible bodies in the model format and in the `f64` dynamics
//! (issue #17): a beam in the floating frame of reference inside the
//! recursive algorithms, checked against the FFR equations of one free body
//! (`flex::ffr`, itself checked against rigid particles in `flex_beam.rs`),
//! against Euler–Bernoulli frequencies, against the rigid rod it becomes with
//! its elastic coordinates at rest, and by energy conservation.

use eom_gen::System;
use eom_gen::flex::{ffr, invariants::Invariants};
use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use eom_sim::{Dop853, OdeSystem, SolveOptions, integrate};
use nalgebra::{DMatrix, DVector, Matrix3, UnitQuaternion, Vector3};

/// The beam of these tests: L = 2 m, ρA = 1.5 kg/m, bending stiffer about
/// `y` than about `z`, axial and torsion modes far above the bending ones.
const L: f64 = 2.0;
const RHO_A: f64 = 1.5;
const RHO_IP: f64 = 0.002;
const EI_Y: f64 = 400.0;
const EI_Z: f64 = 300.0;

/// How a test model is built.
#[derive(Clone, Copy)]
struct Opts {
    /// A flexible beam (`true`) or the rigid rod of the same mass and inertia.
    flexible: bool,
    /// The joint between hub and beam (`"Fixed"`: clamped to the hub).
    beam_joint: &'static str,
    /// The hub's joint.
    hub_joint: &'static str,
    /// Hold the hub joint.
    locked: bool,
    /// Gravity along −z.
    gravity: bool,
    /// Elements and modes kept.
    elements: usize,
    modes: usize,
    /// The hub's inertia about its axis, kg m².
    hub_inertia: f64,
}

const HUB_BEAM: Opts = Opts {
    flexible: true,
    beam_joint: "Fixed",
    hub_joint: "Revolute(axis: (0, 0, 1))",
    locked: false,
    gravity: false,
    elements: 6,
    modes: 4,
    hub_inertia: 0.5,
};

/// A hub on `hub_joint` from ground carrying a beam (or rod) along its
/// local x, through `beam_joint` at 0.3 m from the hub axis.
fn model(o: Opts) -> String {
    let beam = if o.flexible {
        format!(
            "flexible: Beam(length: \"L\", rho_a: \"rho_a\", rho_ip: {RHO_IP}, ea: 1e6, \
             ei_y: {EI_Y}, ei_z: {EI_Z}, gj: 200, elements: {}, reference: Clamped, modes: {}),",
            o.elements, o.modes
        )
    } else {
        // The rigid rod: m = ρA L at L/2, I = diag(ρI_p L, m L²/12, m L²/12).
        format!(
            "mass: \"rho_a*L\", com: (\"L/2\", 0, 0), \
             inertia: Diag({}, \"rho_a*L^3/12\", \"rho_a*L^3/12\"),",
            RHO_IP * L
        )
    };
    let j = o.hub_inertia;
    format!(
        r#"Model(
    name: "hub_beam",
    {gravity}
    parameters: [(name: "L", value: {L}), (name: "rho_a", value: {RHO_A})],
    bodies: [
        (name: "hub", mass: 2.0, inertia: Diag({h}, {h}, {j})),
        (name: "beam", {beam}),
    ],
    joints: [
        (name: "hub_j", kind: {hub}, parent: "ground", child: "hub", locked: {locked}),
        (name: "beam_j", kind: {bj}, parent: "hub", child: "beam",
         parent_frame: (position: (0.3, 0, 0))),
    ],
)"#,
        gravity = if o.gravity {
            "gravity: (0, 0, -9.81),"
        } else {
            ""
        },
        h = j / 2.0,
        hub = o.hub_joint,
        locked = o.locked,
        bj = o.beam_joint,
    )
}

fn system(o: Opts) -> System {
    check(&Source::new("hub_beam.ron", model(o)))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

/// A reproducible pseudo-random number in `[-1, 1)`.
fn rand(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn max_diff(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn flex_coordinates_follow_their_joint_and_are_named_after_the_body() {
    let sys = system(HUB_BEAM);
    assert_eq!(
        sys.coordinate_names(),
        ["hub_j", "beam_f1", "beam_f2", "beam_f3", "beam_f4"]
    );
    assert_eq!(
        sys.speed_names(),
        [
            "hub_j_dot",
            "beam_f1_dot",
            "beam_f2_dot",
            "beam_f3_dot",
            "beam_f4_dot"
        ]
    );
    assert_eq!((sys.nq(), sys.nu()), (5, 5));
    // Right after the joint above the body: here the hub's revolute comes
    // first, the fixed joint has none, then the beam's four.
    let two = system(Opts {
        beam_joint: "Revolute(axis: (0, 1, 0))",
        ..HUB_BEAM
    });
    assert_eq!(
        two.coordinate_names(),
        [
            "hub_j", "beam_j", "beam_f1", "beam_f2", "beam_f3", "beam_f4"
        ]
    );
    let flex = two.bodies[2].flexible.as_deref().expect("beam is flexible");
    assert_eq!((flex.q_index, flex.u_index), (2, 2));
    // The parameters reach the beam: m = ρA L.
    assert!((flex.invariants.mass - RHO_A * L).abs() < 1e-12);
}

/// The free flexible body (a `Free` joint from ground, no gravity) against
/// `flex::ffr`: with speeds `u = (v_b, ω, q̇_f)`, `v_b = Aᵀ Ṙ`, the tree's
/// mass matrix is `Tᵀ M_ffr T`, `T = diag(A, 1, 1)`, and its bias is
/// `−Tᵀ (Q_v − M_ffr (A ω̃ v_b, 0, 0))` (from `R̈ = A (v̇_b + ω × v_b)`).
#[test]
fn flex_free_body_equals_the_ffr_equations_of_one_body() {
    let text = r#"Model(
    name: "free_beam",
    bodies: [(name: "beam", flexible: Beam(length: 1.5, rho_a: 2.0, rho_ip: 0.01, ea: 5e4,
        ei_y: 80, ei_z: 60, gj: 40, elements: 4, reference: PinnedPinned, modes: 5))],
    joints: [(name: "j", kind: Free, parent: "ground", child: "beam")],
)"#;
    let sys = check(&Source::new("free_beam.ron", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let inv: &Invariants = &sys.bodies[1].flexible.as_deref().unwrap().invariants;
    let num = Numeric::new(&sys).unwrap();
    let mut seed = 7;
    for _ in 0..5 {
        let quat = UnitQuaternion::from_scaled_axis(Vector3::from_fn(|_, _| rand(&mut seed)));
        let a: Matrix3<f64> = *quat.to_rotation_matrix().matrix();
        let qf = DVector::from_fn(5, |_, _| 0.05 * rand(&mut seed));
        let vb = Vector3::from_fn(|_, _| rand(&mut seed));
        let w = Vector3::from_fn(|_, _| 2.0 * rand(&mut seed));
        let qfd = DVector::from_fn(5, |_, _| rand(&mut seed));
        let mut q = vec![0.3, -0.2, 0.1, quat.w, quat.i, quat.j, quat.k];
        q.extend(qf.iter());
        let mut u: Vec<f64> = vb.iter().chain(w.iter()).copied().collect();
        u.extend(qfd.iter());
        let terms = num.terms(&q, &u, 0.0, &[]).unwrap();

        let mut t = DMatrix::<f64>::identity(11, 11);
        t.view_mut((0, 0), (3, 3)).copy_from(&a);
        let m_ffr = ffr::mass_matrix(inv, &a, &qf);
        let want_m = t.transpose() * &m_ffr * &t;
        let got_m = DMatrix::from_fn(11, 11, |r, c| terms.mass_matrix[r][c]);
        let dm = (&got_m - &want_m).amax() / want_m.amax();
        assert!(dm < 1e-12, "M: relative difference {dm:e}");

        let qv = ffr::quadratic_velocity(inv, &a, &qf, &w, &qfd);
        let mut shift = DVector::zeros(11);
        shift.rows_mut(0, 3).copy_from(&(a * w.cross(&vb)));
        // With the modal stiffness: b also holds K_ff q_f (as −Q).
        let mut elastic = DVector::zeros(11);
        elastic
            .rows_mut(6, 5)
            .copy_from(&(&inv.modal_stiffness * &qf));
        let want_b = -(t.transpose() * (qv - &m_ffr * shift)) + elastic;
        let got_b = DVector::from_vec(terms.bias.clone());
        let db = (&got_b - &want_b).amax() / want_b.amax();
        assert!(
            db < 1e-11,
            "bias: relative difference {db:e}\n got {got_b}\nwant {want_b}"
        );

        let (kin, _) = num.energy(&q, &u, 0.0).unwrap();
        let u_ffr = &t * DVector::from_vec(u.clone());
        let want_t = ffr::kinetic_energy(inv, &a, &qf, &u_ffr);
        assert!(
            (kin - want_t).abs() < 1e-12 * want_t,
            "T = {kin}, FFR {want_t}"
        );
    }
}

/// With `q_f` and `q̇_f` zero, the rows and columns of the joint speeds,
/// the bias on the joints and the energies are those of the rigid rod
/// (`m = ρA L` at `L/2`, `I = diag(ρI_p L, mL²/12, mL²/12)`), here on a
/// hub and a revolute about y, with gravity, at random angles and rates.
#[test]
fn flex_beam_at_rest_deformation_is_the_rigid_rod() {
    let o = Opts {
        beam_joint: "Revolute(axis: (0, 1, 0))",
        gravity: true,
        ..HUB_BEAM
    };
    let flex = Numeric::new(&system(o)).unwrap();
    let rigid = Numeric::new(&system(Opts {
        flexible: false,
        ..o
    }))
    .unwrap();
    let mut seed = 3;
    for _ in 0..5 {
        let qr = [rand(&mut seed) * 3.0, rand(&mut seed)];
        let ur = [rand(&mut seed) * 2.0, rand(&mut seed) * 2.0];
        let mut q = qr.to_vec();
        q.extend([0.0; 4]);
        let mut u = ur.to_vec();
        u.extend([0.0; 4]);
        let tf = flex.terms(&q, &u, 0.0, &[]).unwrap();
        let tr = rigid.terms(&qr, &ur, 0.0, &[]).unwrap();
        let mf: Vec<Vec<f64>> = tf.mass_matrix[..2]
            .iter()
            .map(|r| r[..2].to_vec())
            .collect();
        let dm = max_diff(&mf, &tr.mass_matrix);
        assert!(dm < 1e-12, "M: got {mf:?}, want {:?}", tr.mass_matrix);
        for k in 0..2 {
            let (got, want) = (tf.bias[k], tr.bias[k]);
            assert!((got - want).abs() < 1e-11, "b[{k}]: got {got}, want {want}");
        }
        let (ef, er) = (
            flex.energy(&q, &u, 0.0).unwrap(),
            rigid.energy(&qr, &ur, 0.0).unwrap(),
        );
        assert!((ef.0 - er.0).abs() < 1e-12 && (ef.1 - er.1).abs() < 1e-11);
    }
}

/// The articulated-body algorithm with the elastic coordinates eliminated
/// at their body agrees with `M u̇ = τ − b` (CRBA + RNEA, tree-sparse
/// `LᵀDL`), and inverse dynamics returns the forces: at deformed states.
#[test]
fn flex_aba_agrees_with_crba_and_rnea() {
    let num = Numeric::new(&system(Opts {
        beam_joint: "Revolute(axis: (0, 1, 0))",
        gravity: true,
        ..HUB_BEAM
    }))
    .unwrap();
    let mut seed = 11;
    for _ in 0..5 {
        let q: Vec<f64> = (0..6).map(|_| rand(&mut seed) * 0.3).collect();
        let u: Vec<f64> = (0..6).map(|_| rand(&mut seed) * 2.0).collect();
        let tau: Vec<f64> = (0..6).map(|_| rand(&mut seed)).collect();
        let aba = num.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap();
        let ltdl = num.forward_dynamics_ltdl(&q, &u, 0.0, &tau, &[]).unwrap();
        for (k, (a, b)) in aba.iter().zip(&ltdl).enumerate() {
            assert!(
                (a - b).abs() < 1e-9 * b.abs().max(1.0),
                "u̇[{k}]: ABA {a}, LᵀDL {b}"
            );
        }
        let back = num.inverse_dynamics(&q, &u, &aba, 0.0, &[]).unwrap();
        for (k, (a, b)) in back.iter().zip(&tau).enumerate() {
            assert!(
                (a - b).abs() < 1e-9,
                "τ[{k}]: inverse dynamics {a}, given {b}"
            );
        }
    }
}

/// Lowest `ω` of the linearised free vibration about `q = 0, u = 0`:
/// `M(0)` and `K = ∂b/∂q` (central differences), `det(K − ω² M) = 0`,
/// skipping rigid (zero-frequency) motions.
fn lowest_frequency(num: &Numeric, n: usize) -> f64 {
    let zero = vec![0.0; n];
    let m = num.terms(&zero, &zero, 0.0, &[]).unwrap().mass_matrix;
    let m = DMatrix::from_fn(n, n, |r, c| m[r][c]);
    let h = 1e-6;
    let mut k = DMatrix::zeros(n, n);
    for c in 0..n {
        let mut qp = zero.clone();
        qp[c] = h;
        let mut qm = zero.clone();
        qm[c] = -h;
        let bp = num.terms(&qp, &zero, 0.0, &[]).unwrap().bias;
        let bm = num.terms(&qm, &zero, 0.0, &[]).unwrap().bias;
        for r in 0..n {
            k[(r, c)] = (bp[r] - bm[r]) / (2.0 * h);
        }
    }
    // M = L Lᵀ, eigenvalues of L⁻¹ K L⁻ᵀ.
    let l = m.cholesky().expect("M positive definite").l();
    let li = l.try_inverse().unwrap();
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

/// The first bending frequency of a cantilever, `ω₁ = (β₁L)² √(EI/(ρA L⁴))`
/// with `β₁L = 1.875104068711961` (clamped–free), in the plane of the hub's
/// rotation (`EI_z`).
fn clamped_free() -> f64 {
    1.875_104_068_711_961_f64.powi(2) * (EI_Z / (RHO_A * L.powi(4))).sqrt()
}

#[test]
fn flex_locked_hub_vibrates_at_the_clamped_free_frequency() {
    // Hub held: the beam is a cantilever; six cubic elements put ω₁ within
    // ~1e-6 of Euler–Bernoulli (the FE error falls as h⁴).
    let locked = system(Opts {
        locked: true,
        ..HUB_BEAM
    });
    let w = lowest_frequency(&Numeric::new(&locked).unwrap(), 4);
    let want = clamped_free();
    eprintln!(
        "locked hub: ω₁ = {w}, Euler–Bernoulli {want}, relative {:e}",
        w / want - 1.0
    );
    assert!((w / want - 1.0).abs() < 1e-5, "ω₁ = {w}, want {want}");

    // A free hub much heavier than the beam (10⁶ × its inertia about the
    // axis) hardly moves: the coupled ω₁ tends to the clamped one from
    // above (relative shift ~ I_beam / J_hub).
    let heavy = system(Opts {
        hub_inertia: 1e6 * RHO_A * (L + 0.3).powi(3) / 3.0,
        ..HUB_BEAM
    });
    let w = lowest_frequency(&Numeric::new(&heavy).unwrap(), 5);
    eprintln!("heavy hub: ω₁ = {w}, relative {:e}", w / want - 1.0);
    assert!(
        w >= want * (1.0 - 1e-5) && (w / want - 1.0).abs() < 1e-4,
        "heavy hub: ω₁ = {w}, clamped {want}"
    );

    // And in time: released from the first mode shape (q_f1 = 1 mm), the
    // locked beam's first coordinate returns to its start after one
    // Euler–Bernoulli period (the FE frequency is ~1e-6 off, a phase error
    // of ~6e-6 rad).
    let num = Numeric::new(&locked).unwrap();
    let sys = Ode { num: &num, n: 4 };
    let mut y0 = [0.0; 8];
    y0[0] = 1e-3;
    let period = 2.0 * std::f64::consts::PI / want;
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-15),
        &sys,
        0.0,
        y0,
        period,
        &SolveOptions::default(),
        &mut [],
    );
    let back = sol.y_final[0];
    assert!(
        (back - 1e-3).abs() < 1e-8 && sol.y_final[4].abs() < 1e-4 * 1e-3 * want,
        "after one clamped–free period q_f1 = {back}, q̇_f1 = {}",
        sol.y_final[4]
    );
}

/// `ẏ = (q̇, u̇)` by the articulated-body algorithm (`q̇ = u` for revolute
/// and elastic coordinates).
struct Ode<'a> {
    num: &'a Numeric,
    n: usize,
}

impl<const N: usize> OdeSystem<N> for Ode<'_> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let n = self.n;
        let (q, u) = y.split_at(n);
        let tau = vec![0.0; n];
        let ud = self
            .num
            .forward_dynamics(q, u, t, &tau, &[])
            .unwrap_or_else(|_| vec![f64::NAN; n]);
        dy[..n].copy_from_slice(&self.num.qdot(q, u));
        dy[n..].copy_from_slice(&ud);
    }
}

#[test]
fn flex_free_hub_beam_conserves_energy() {
    // Hub and beam swinging under gravity on two revolute joints, the beam
    // released bent and twisting (no damping): T + V (gravity and strain)
    // stays constant to DOP853's tolerance over 2 s (~5 periods of the first
    // bending mode, with the hub and the rigid swing exchanging energy).
    let num = Numeric::new(&system(Opts {
        beam_joint: "Revolute(axis: (0, 1, 0))",
        gravity: true,
        ..HUB_BEAM
    }))
    .unwrap();
    let y0 = [
        0.2, 0.4, 0.02, -0.01, 0.005, 0.002, // q: hub, beam, 4 elastic
        1.0, -0.5, 0.3, 0.2, -0.1, 0.05, // u
    ];
    let energy = |y: &[f64; 12]| {
        let (t, v) = num.energy(&y[..6], &y[6..], 0.0).unwrap();
        t + v
    };
    let e0 = energy(&y0);
    let sys = Ode { num: &num, n: 6 };
    let opts = SolveOptions {
        t_eval: (1..=20).map(|k| 0.1 * k as f64).collect(),
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &sys,
        0.0,
        y0,
        2.0,
        &opts,
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 20, "stopped: {:?}", sol.stop);
    let scale = {
        let (t, v) = num.energy(&y0[..6], &y0[6..], 0.0).unwrap();
        t.abs() + v.abs()
    };
    let drift = sol
        .y_out
        .iter()
        .map(|y| (energy(y) - e0).abs() / scale)
        .fold(0.0, f64::max);
    eprintln!(
        "relative energy drift {drift:e}, {} steps",
        sol.stats.accepted
    );
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    // The beam did deform and exchange energy: q_f1 changed sign.
    assert!(
        sol.y_out.iter().any(|y| y[2] < 0.0),
        "q_f1 never swung back"
    );
}

/// The model's errors at their `file:line:col`, every one at once.
fn errors(edits: &[(&str, &str)]) -> String {
    let mut text = model(HUB_BEAM);
    for (from, to) in edits {
        assert!(text.contains(from), "test setup: `{from}` not in the model");
        text = text.replacen(from, to, 1);
    }
    match check(&Source::new("hub_beam.ron", text)) {
        Ok(_) => "valid".to_string(),
        Err(report) => report.to_string(),
    }
}

#[test]
fn flex_validation_errors_are_located() {
    // Non-positive stiffness and mass per length, zero modes: all at once,
    // each at its value (line 7 is the `beam` body).
    let report = errors(&[
        ("ea: 1e6", "ea: -1e6"),
        ("rho_a: \"rho_a\"", "rho_a: \"rho_a - 1.5\""),
        ("modes: 4", "modes: 0"),
    ]);
    for want in [
        "hub_beam.ron:7:",
        "axial stiffness `ea` of flexible body `beam` is -1000000 N",
        "mass per length `rho_a` of flexible body `beam` is 0 kg/m",
        "flexible body `beam` keeps no modes",
    ] {
        assert!(report.contains(want), "want `{want}` in:\n{report}");
    }
    assert_eq!(report.matches("error").count(), 3, "{report}");

    // More modes than the constrained beam has: 2 elements, 12 dofs.
    let report = errors(&[(
        "elements: 6, reference: Clamped, modes: 4",
        "elements: 2, reference: Clamped, modes: 13",
    )]);
    assert!(
        report.contains("hub_beam.ron:7:")
            && report.contains(
                "13 modes asked for, but the constrained beam has only 12 degrees of freedom"
            ),
        "{report}"
    );

    // A rigid body without mass; a marker naming a node of a rigid body,
    // and one past the last node of the beam.
    let report = errors(&[
        (
            "(name: \"hub\", mass: 2.0, ",
            "(name: \"hub\", markers: [(name: \"m\", node: 1)], ",
        ),
        (
            "modes: 4),",
            "modes: 4), markers: [(name: \"tip\", node: 7)],",
        ),
    ]);
    for want in [
        "hub_beam.ron:6:9",
        "body `hub` has no `mass`",
        "marker `m` names node 1, but body `hub` is rigid",
        "marker `tip`: node 7 does not exist: the beam has nodes 0..=6",
    ] {
        assert!(report.contains(want), "want `{want}` in:\n{report}");
    }

    // A body carried by the beam rides its frame: a warning at `parent`.
    let text = model(HUB_BEAM).replace(
        "    ],\n    joints: [",
        "        (name: \"tip_mass\", mass: 0.1),\n    ],\n    joints: [\n        (name: \"tip_j\", kind: Fixed, parent: \"beam\", child: \"tip_mass\"),",
    );
    let c = check(&Source::new("hub_beam.ron", text)).unwrap_or_else(|r| panic!("{r}"));
    let warning = c.source.render_all(&c.warnings);
    assert!(
        warning
            .contains("joint `tip_j` is attached to the reference frame of flexible body `beam`"),
        "{warning}"
    );
}

/// The symbolic path: the same recursive algorithms over the symbolic
/// scalar (the invariants inlined as constants) give programs whose
/// interpretation equals the `f64` run, at random deformed states, for
/// every function of the table.
#[test]
fn flex_generated_programs_equal_the_f64_algorithms() {
    use eom_gen::functions::{Function, FunctionSet};
    use eom_gen::mech::formulate;
    let sys = system(Opts {
        beam_joint: "Revolute(axis: (0, 1, 0))",
        gravity: true,
        ..HUB_BEAM
    });
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let num = Numeric::new(&sys).unwrap();
    let mut seed = 5;
    for _ in 0..4 {
        let q: Vec<f64> = (0..6).map(|_| rand(&mut seed) * 0.3).collect();
        let u: Vec<f64> = (0..6).map(|_| rand(&mut seed) * 2.0).collect();
        let ud: Vec<f64> = (0..6).map(|_| rand(&mut seed)).collect();
        let tau: Vec<f64> = (0..6).map(|_| rand(&mut seed)).collect();
        let point = eom_gen::interpret::Point {
            sys: &sys,
            q: &q,
            u: &u,
            udot: &ud,
            tau: &tau,
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        let run = |function: Function| {
            eom_gen::interpret::run(f.program(function).expect("requested"), &point)
        };
        let close = |what: &str, got: &[f64], want: &[f64]| {
            assert_eq!(got.len(), want.len(), "{what}: lengths");
            let scale = want.iter().map(|x| x.abs()).fold(1.0, f64::max);
            for (k, (g, w)) in got.iter().zip(want).enumerate() {
                assert!(
                    (g - w).abs() <= 1e-12 * scale,
                    "{what}[{k}]: generated {g}, f64 algorithm {w}"
                );
            }
        };
        let terms = num.terms(&q, &u, 0.0, &[]).unwrap();
        let lower: Vec<f64> = (0..6)
            .flat_map(|i| (0..=i).map(move |j| (i, j)))
            .map(|(i, j)| terms.mass_matrix[i][j])
            .collect();
        close("mass matrix", &run(Function::MassMatrix), &lower);
        close("bias", &run(Function::Bias), &terms.bias);
        close(
            "forward dynamics",
            &run(Function::ForwardDynamics),
            &num.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap(),
        );
        close(
            "inverse dynamics",
            &run(Function::InverseDynamics),
            &num.inverse_dynamics(&q, &u, &ud, 0.0, &[]).unwrap(),
        );
        close("qdot", &run(Function::Qdot), &num.qdot(&q, &u));
        let (t, v) = num.energy(&q, &u, 0.0).unwrap();
        close("energy", &run(Function::Energy), &[t, v]);
        let h = num.momentum(&q, &u, 0.0).unwrap();
        close(
            "momentum",
            &run(Function::Momentum),
            &[h.n.0[0], h.n.0[1], h.n.0[2], h.f.0[0], h.f.0[1], h.f.0[2]],
        );
    }
}

/// The mesh is built once at the defaults: a beam whose length uses a
/// tunable parameter is refused (at the field), not silently frozen; a
/// tunable damping ratio is fine (tunable section data:
/// `tests/flex_tunable.rs`).
#[test]
fn flex_tunable_beam_data_are_refused_at_the_field() {
    let text = model(HUB_BEAM).replace(
        "(name: \"L\", value: 2)",
        "(name: \"L\", value: 2, tunable: true)",
    );
    assert!(text.contains("tunable: true"), "test setup");
    let src = Source::new("hub_beam.ron", text);
    let sys = check(&src).unwrap_or_else(|r| panic!("{r}")).system;
    let err = Numeric::new(&sys).expect_err("a tunable length is refused");
    let at = src.line_col(err.span().start);
    // At `length: "L"` on the beam's line.
    assert_eq!((at.line, at.col), (7, 47), "{err}");
    assert!(err.to_string().contains("flexible body `beam`"), "{err}");

    let damped = model(HUB_BEAM)
        .replace(
            "(name: \"rho_a\", value: 1.5)",
            "(name: \"rho_a\", value: 1.5), (name: \"zeta\", value: 0.02, tunable: true)",
        )
        .replace("modes: 4)", "modes: 4, damping: \"zeta\")");
    let sys = check(&Source::new("hub_beam.ron", damped))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    // −D q̇ = −2 ζ ω₁ q̇₁ on the first elastic speed.
    let num = Numeric::new(&sys).unwrap();
    let w1 = sys.bodies[2].flexible.as_deref().unwrap().modes.frequencies[0];
    let zero = [0.0; 5];
    let u = [0.0, 1.0, 0.0, 0.0, 0.0];
    let (b0, b1) = (
        num.terms(&zero, &zero, 0.0, &[]).unwrap().bias[1],
        num.terms(&zero, &u, 0.0, &[]).unwrap().bias[1],
    );
    let want = 2.0 * 0.02 * w1;
    assert!(
        (b1 - b0 - want).abs() < 1e-12 * want,
        "damping force {}, want {want}",
        b1 - b0
    );
}
