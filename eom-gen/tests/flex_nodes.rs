//! Attachments at the nodes of a flexible body (issue #17): bodies, joints,
//! markers and force elements that move with a node's translation and small
//! rotation.
//!
//! The node frame sits at `ū₀ + S_n q_f` in the flexible body's frame,
//! turned by `R = R_z(θ_z) R_y(θ_y) R_x(θ_x)` with `θ = Φ_n q_f` (the
//! convention of `mech::flexible`, equal to `1 + θ̃` to first order). The
//! tests check a rigid body hung at the tip of a flexible beam against an
//! independent reference (the body's pose computed here from the nodal mode
//! shapes, its kinetic and potential energy, Lagrange's equations by
//! central differences, added to the beam-and-hub system without it), the
//! rigid model at zero deformation, forward against inverse dynamics, the
//! generated programs against the `f64` algorithms, energy conservation
//! (with a spring at a node marker) and a closed loop through a node.

use eom_gen::System;
use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use eom_gen::testkit::Rng;
use eom_sim::{Dop853, OdeSystem, SolveOptions, integrate};
use nalgebra::{DMatrix, Matrix3, Rotation3, Vector3};

const L: f64 = 1.2;
const RHO_A: f64 = 2.0;
const RHO_IP: f64 = 0.003;
const ELEMENTS: usize = 6;
const MODES: usize = 4;
const G: f64 = 9.81;

/// The tip body: mass, centre of mass and inertia about it (its axes).
const TIP_MASS: f64 = 0.7;
const TIP_COM: [f64; 3] = [0.05, 0.02, -0.03];
const TIP_INERTIA: [f64; 3] = [0.01, 0.02, 0.015];
/// Its joint frame relative to the tip node's frame: position and roll,
/// pitch, yaw.
const TIP_AT: [f64; 3] = [0.1, 0.0, 0.02];
const TIP_RPY: [f64; 3] = [0.1, -0.2, 0.3];

#[derive(Clone, Copy)]
struct Opts {
    /// A flexible beam, or the rigid rod of its mass and inertia at rest
    /// (the tip body then on the rod's frame at `(L, 0, 0)`).
    flexible: bool,
    /// Hang the tip body (at the tip node).
    tip: bool,
    /// A spring from ground to a marker at the tip node.
    spring: bool,
}

const FLEX: Opts = Opts {
    flexible: true,
    tip: true,
    spring: false,
};

/// A hub turning about z carries, 0.2 m out, a beam on a revolute about
/// y (clamped reference: the tangent frame); a rigid body hangs at the
/// beam's tip node on a revolute about y (as seen in its joint frame),
/// under gravity along −z.
fn model(o: Opts) -> String {
    let beam = if o.flexible {
        format!(
            "flexible: Beam(length: \"L\", rho_a: \"rho_a\", rho_ip: {RHO_IP}, ea: 2e5, \
             ei_y: 60, ei_z: 40, gj: 30, elements: {ELEMENTS}, reference: Clamped, \
             modes: {MODES}, nodes: [(name: \"tip\", x: \"L\"), (name: \"mid\", x: 0.6)]),
             markers: [(name: \"mark\", node: \"tip\", position: (0.05, 0.02, 0))],"
        )
    } else {
        format!(
            "mass: \"rho_a*L\", com: (\"L/2\", 0, 0), \
             inertia: Diag({}, \"rho_a*L^3/12\", \"rho_a*L^3/12\"),
             markers: [(name: \"mark\", position: (\"L + 0.05\", 0.02, 0))],",
            RHO_IP * L
        )
    };
    let node = if o.flexible {
        "parent_node: \"tip\","
    } else {
        ""
    };
    let at_x = if o.flexible {
        format!("{}", TIP_AT[0])
    } else {
        format!("\"L + {}\"", TIP_AT[0])
    };
    let [cx, cy, cz] = TIP_COM;
    let [ix, iy, iz] = TIP_INERTIA;
    let [r, p, y] = TIP_RPY;
    let tip_body = if o.tip {
        format!(
            "(name: \"tip\", mass: {TIP_MASS}, com: ({cx}, {cy}, {cz}), inertia: Diag({ix}, {iy}, {iz})),"
        )
    } else {
        String::new()
    };
    let tip_joint = if o.tip {
        format!(
            "(name: \"tip_j\", kind: Revolute(axis: (0, 1, 0)), parent: \"beam\", {node} child: \"tip\",
              parent_frame: (position: ({at_x}, 0, {}), orientation: Rpy({r}, {p}, {y}))),",
            TIP_AT[2]
        )
    } else {
        String::new()
    };
    let spring = if o.spring {
        r#"forces: [SpringDamper(name: "pull", a: (body: "ground", point: (1.0, 0.5, 0.3)),
            b: (body: "beam", marker: "mark"), stiffness: 80, rest_length: 0.4)],"#
    } else {
        ""
    };
    format!(
        r#"Model(
    name: "tip_body",
    gravity: (0, 0, -{G}),
    parameters: [(name: "L", value: {L}), (name: "rho_a", value: {RHO_A})],
    bodies: [
        (name: "hub", mass: 2.0, inertia: Diag(0.2, 0.2, 0.3)),
        (name: "beam", {beam}),
        {tip_body}
    ],
    joints: [
        (name: "hub_j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "hub"),
        (name: "beam_j", kind: Revolute(axis: (0, 1, 0)), parent: "hub", child: "beam",
         parent_frame: (position: (0.2, 0, 0))),
        {tip_joint}
    ],
    {spring}
    outputs: [Position(body: "beam", marker: "mark"), Velocity(body: "beam", marker: "mark")],
)"#
    )
}

fn system(o: Opts) -> System {
    check(&Source::new("tip_body.ron", model(o)))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

/// The tip body's world rotation and centre of mass at `q`
/// (`hub, beam, q_f…, tip`), computed from the nodal shapes `shape`
/// (6 × k at the tip node) as the convention above says.
fn tip_pose(q: &[f64], shape: &DMatrix<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    let k = shape.ncols();
    let rot = |axis: Vector3<f64>, a: f64| {
        *Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), a).matrix()
    };
    let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
    let qf = &q[2..2 + k];
    let mut d = Vector3::new(L, 0.0, 0.0);
    let mut theta = Vector3::zeros();
    for (j, &qj) in qf.iter().enumerate() {
        for r in 0..3 {
            d[r] += shape[(r, j)] * qj;
            theta[r] += shape[(3 + r, j)] * qj;
        }
    }
    let node_r = rot(z, theta.z) * rot(y, theta.y) * rot(x, theta.x);
    let beam_r = rot(z, q[0]) * rot(y, q[1]);
    let beam_o = rot(z, q[0]) * Vector3::new(0.2, 0.0, 0.0);
    let [r, p, yaw] = TIP_RPY;
    let frame_r = rot(z, yaw) * rot(y, p) * rot(x, r);
    let frame_o = Vector3::from(TIP_AT);
    let tip_r = beam_r * node_r * frame_r * rot(y, q[2 + k]);
    let tip_o = beam_o + beam_r * (d + node_r * frame_o);
    (tip_r, tip_o + tip_r * Vector3::from(TIP_COM))
}

/// The tip body's mass matrix `m J_vᵀ J_v + J_ωᵀ I J_ω` (central
/// differences of its pose) and potential energy.
fn tip_terms(q: &[f64], shape: &DMatrix<f64>) -> (DMatrix<f64>, f64) {
    let n = q.len();
    let h = 1e-5;
    let (r0, c0) = tip_pose(q, shape);
    let mut jv = DMatrix::zeros(3, n);
    let mut jw = DMatrix::zeros(3, n);
    for j in 0..n {
        let mut qp = q.to_vec();
        let mut qm = q.to_vec();
        qp[j] += h;
        qm[j] -= h;
        let ((rp, cp), (rm, cm)) = (tip_pose(&qp, shape), tip_pose(&qm, shape));
        let dc = (cp - cm) / (2.0 * h);
        // Body angular velocity per unit rate: (Rᵀ dR/dq)^∨.
        let w = r0.transpose() * (rp - rm) / (2.0 * h);
        for r in 0..3 {
            jv[(r, j)] = dc[r];
        }
        jw[(0, j)] = 0.5 * (w[(2, 1)] - w[(1, 2)]);
        jw[(1, j)] = 0.5 * (w[(0, 2)] - w[(2, 0)]);
        jw[(2, j)] = 0.5 * (w[(1, 0)] - w[(0, 1)]);
    }
    let inertia = Matrix3::from_diagonal(&Vector3::from(TIP_INERTIA));
    let inertia = DMatrix::from_fn(3, 3, |r, c| inertia[(r, c)]);
    let m = jv.transpose() * &jv * TIP_MASS + jw.transpose() * inertia * jw;
    (m, TIP_MASS * G * c0.z)
}

fn tip_shape(sys: &System) -> DMatrix<f64> {
    sys.bodies
        .iter()
        .find_map(|b| b.flexible.as_deref())
        .expect("a flexible body")
        .modes
        .at_node(ELEMENTS)
}

#[test]
fn flex_node_body_follows_lagranges_equations() {
    // M and b of hub + beam + tip body equal those of hub + beam alone
    // (checked against rigid particles in flex_model.rs / flex_beam.rs)
    // plus the tip body's: its mass matrix from its pose's derivatives, its
    // velocity terms C_i = Σ_jk (∂M_ij/∂q_k − ½ ∂M_jk/∂q_i) q̇_j q̇_k and
    // gravity ∂V/∂q, all by central differences at random states with
    // deformations of a few centimetres.
    let sys = system(FLEX);
    let base = Numeric::new(&system(Opts { tip: false, ..FLEX })).unwrap();
    let num = Numeric::new(&sys).unwrap();
    let shape = tip_shape(&sys);
    let n = 3 + MODES;
    let mut rng = Rng(0x5eed_0001);
    for _ in 0..4 {
        let mut q = rng.vec(n, 0.8);
        for x in &mut q[2..2 + MODES] {
            *x *= 0.05;
        }
        let u = rng.vec(n, 2.0);
        let terms = num.terms(&q, &u, 0.0, &[]).unwrap();
        let bt = base.terms(&q[..n - 1], &u[..n - 1], 0.0, &[]).unwrap();
        let (m_tip, _) = tip_terms(&q, &shape);
        let mut want_m = m_tip.clone();
        for r in 0..n - 1 {
            for c in 0..n - 1 {
                want_m[(r, c)] += bt.mass_matrix[r][c];
            }
        }
        let got_m = DMatrix::from_fn(n, n, |r, c| terms.mass_matrix[r][c]);
        let dm = (&got_m - &want_m).amax() / want_m.amax();
        eprintln!("M: relative difference {dm:e}");
        assert!(
            dm < 1e-8,
            "M: relative difference {dm:e}\n got {got_m}\nwant {want_m}"
        );

        // ∂M/∂q_k and ∂V/∂q_k of the tip body.
        let h = 1e-4;
        let mut dmdq = Vec::with_capacity(n);
        let mut dv = vec![0.0; n];
        for k in 0..n {
            let mut qp = q.clone();
            let mut qm = q.clone();
            qp[k] += h;
            qm[k] -= h;
            let ((mp, vp), (mm, vm)) = (tip_terms(&qp, &shape), tip_terms(&qm, &shape));
            dmdq.push((mp - mm) / (2.0 * h));
            dv[k] = (vp - vm) / (2.0 * h);
        }
        let mut want_b = vec![0.0; n];
        for i in 0..n {
            let mut c = dv[i];
            for j in 0..n {
                for k in 0..n {
                    c += (dmdq[k][(i, j)] - 0.5 * dmdq[i][(j, k)]) * u[j] * u[k];
                }
            }
            want_b[i] = c + if i < n - 1 { bt.bias[i] } else { 0.0 };
        }
        let scale = want_b.iter().fold(1.0_f64, |a, b| a.max(b.abs()));
        let db = terms
            .bias
            .iter()
            .zip(&want_b)
            .map(|(g, w)| (g - w).abs() / scale)
            .fold(0.0, f64::max);
        eprintln!("b: relative difference {db:e}");
        for (i, (g, w)) in terms.bias.iter().zip(&want_b).enumerate() {
            assert!(
                (g - w).abs() < 1e-6 * scale,
                "b[{i}] = {g}, Lagrange {w} (scale {scale})"
            );
        }
    }
}

#[test]
fn flex_node_at_rest_deformation_is_the_rigid_model() {
    // With q_f = 0 and q̇_f = 0 the node frame is the body frame moved to
    // (L, 0, 0): the joint rows of M and b, the energies and the marker's
    // position and velocity are those of the rigid rod carrying the same
    // body and marker at (L, 0, 0).
    let flex = Numeric::new(&system(FLEX)).unwrap();
    let rigid = Numeric::new(&system(Opts {
        flexible: false,
        ..FLEX
    }))
    .unwrap();
    let n = 3 + MODES;
    let joints = [0, 1, n - 1];
    let mut rng = Rng(0x5eed_0002);
    for _ in 0..4 {
        let qr = rng.vec(3, 1.5);
        let ur = rng.vec(3, 2.0);
        let mut q = vec![0.0; n];
        let mut u = vec![0.0; n];
        for (r, &j) in joints.iter().enumerate() {
            q[j] = qr[r];
            u[j] = ur[r];
        }
        let (tf, tr) = (
            flex.terms(&q, &u, 0.0, &[]).unwrap(),
            rigid.terms(&qr, &ur, 0.0, &[]).unwrap(),
        );
        for (r, &jr) in joints.iter().enumerate() {
            for (c, &jc) in joints.iter().enumerate() {
                let (a, b) = (tf.mass_matrix[jr][jc], tr.mass_matrix[r][c]);
                assert!(
                    (a - b).abs() < 1e-12,
                    "M[{r}][{c}]: flexible {a}, rigid {b}"
                );
            }
            let (a, b) = (tf.bias[jr], tr.bias[r]);
            assert!((a - b).abs() < 1e-11, "b[{r}]: flexible {a}, rigid {b}");
        }
        let (ef, er) = (
            flex.energy(&q, &u, 0.0).unwrap(),
            rigid.energy(&qr, &ur, 0.0).unwrap(),
        );
        assert!((ef.0 - er.0).abs() < 1e-12 && (ef.1 - er.1).abs() < 1e-12);
        let (xf, vf) = flex
            .node_point(2, ELEMENTS, [0.05, 0.02, 0.0], &q, &u, 0.0)
            .unwrap();
        let (xr, vr) = rigid
            .point(2, [L + 0.05, 0.02, 0.0], &qr, &ur, 0.0)
            .unwrap();
        for a in 0..3 {
            assert!((xf[a] - xr[a]).abs() < 1e-14 && (vf[a] - vr[a]).abs() < 1e-13);
        }
    }
}

#[test]
fn flex_node_marker_moves_with_the_node() {
    // The marker at the tip node, 5 cm along and 2 cm across the beam:
    // its world position is R_beam (ū₀ + S q_f + R_node p) and its velocity
    // the time derivative of that (central differences along q̇ = u).
    let sys = system(FLEX);
    let num = Numeric::new(&sys).unwrap();
    let shape = tip_shape(&sys);
    let n = 3 + MODES;
    let p = Vector3::new(0.05, 0.02, 0.0);
    let mut rng = Rng(0x5eed_0003);
    let place = |q: &[f64]| {
        let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
        let rot = |a: Vector3<f64>, t: f64| {
            *Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(a), t).matrix()
        };
        let mut d = Vector3::new(L, 0.0, 0.0);
        let mut th = Vector3::zeros();
        for j in 0..MODES {
            for r in 0..3 {
                d[r] += shape[(r, j)] * q[2 + j];
                th[r] += shape[(3 + r, j)] * q[2 + j];
            }
        }
        let node = rot(z, th.z) * rot(y, th.y) * rot(x, th.x);
        rot(z, q[0]) * (Vector3::new(0.2, 0.0, 0.0) + rot(y, q[1]) * (d + node * p))
    };
    for _ in 0..4 {
        let mut q = rng.vec(n, 1.0);
        for x in &mut q[2..2 + MODES] {
            *x *= 0.1;
        }
        let u = rng.vec(n, 2.0);
        let (x, v) = num.node_point(2, ELEMENTS, p.into(), &q, &u, 0.0).unwrap();
        let want = place(&q);
        let h = 1e-6;
        let step = |s: f64| -> Vec<f64> { q.iter().zip(&u).map(|(a, b)| a + s * b).collect() };
        let want_v = (place(&step(h)) - place(&step(-h))) / (2.0 * h);
        for a in 0..3 {
            assert!((x[a] - want[a]).abs() < 1e-14, "x: {x:?}, want {want}");
            assert!((v[a] - want_v[a]).abs() < 1e-8, "v: {v:?}, want {want_v}");
        }
    }
}

#[test]
fn flex_node_inverse_of_forward_dynamics_is_identity_and_programs_agree() {
    // Forward dynamics by the articulated-body algorithm (the elastic
    // coordinates eliminated with the subtree at the tip node) equals
    // M⁻¹(τ − b) by CRBA, RNEA and the tree-sparse LᵀDL (bodies at nodes
    // below the elastic speeds), and RNEA inverts it; the generated
    // programs (interpreted) equal the f64 algorithms, outputs of the node
    // marker included.
    use eom_gen::functions::{Function, FunctionSet};
    use eom_gen::mech::formulate;
    let sys = system(Opts {
        spring: true,
        ..FLEX
    });
    let num = Numeric::new(&sys).unwrap();
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eprintln!("forward dynamics: {:?} of {:?}", f.fd_form, f.fd_candidates);
    let n = 3 + MODES;
    let mut rng = Rng(0x5eed_0004);
    for _ in 0..4 {
        let mut q = rng.vec(n, 1.0);
        for x in &mut q[2..2 + MODES] {
            *x *= 0.05;
        }
        let u = rng.vec(n, 2.0);
        let tau = rng.vec(n, 3.0);
        let ud = num.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap();
        let ud_m = num.forward_dynamics_ltdl(&q, &u, 0.0, &tau, &[]).unwrap();
        let ud_scale = ud_m.iter().fold(1.0_f64, |a, b| a.max(b.abs()));
        for (i, (a, m)) in ud.iter().zip(&ud_m).enumerate() {
            assert!(
                (a - m).abs() < 1e-10 * ud_scale,
                "u̇[{i}]: articulated bodies {a}, mass matrix {m}"
            );
        }
        let back = num.inverse_dynamics(&q, &u, &ud, 0.0, &[]).unwrap();
        let scale = tau.iter().fold(1.0_f64, |a, b| a.max(b.abs()));
        for (i, (b, t)) in back.iter().zip(&tau).enumerate() {
            assert!((b - t).abs() < 1e-10 * scale, "τ[{i}]: {t} → {b}");
        }
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
                    (g - w).abs() <= 1e-11 * scale,
                    "{what}[{k}]: generated {g}, f64 algorithm {w}"
                );
            }
        };
        let terms = num.terms(&q, &u, 0.0, &[]).unwrap();
        let lower: Vec<f64> = (0..n)
            .flat_map(|i| (0..=i).map(move |j| (i, j)))
            .map(|(i, j)| terms.mass_matrix[i][j])
            .collect();
        close("mass matrix", &run(Function::MassMatrix), &lower);
        close("bias", &run(Function::Bias), &terms.bias);
        close("forward dynamics", &run(Function::ForwardDynamics), &ud);
        close("inverse dynamics", &run(Function::InverseDynamics), &tau);
        let (t, v) = num.energy(&q, &u, 0.0).unwrap();
        close("energy", &run(Function::Energy), &[t, v]);
        let (x, xv) = num
            .node_point(2, ELEMENTS, [0.05, 0.02, 0.0], &q, &u, 0.0)
            .unwrap();
        let want: Vec<f64> = x.iter().chain(&xv).copied().collect();
        close("outputs", &run(Function::Outputs), &want);
    }
}

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
fn flex_node_body_conserves_energy() {
    // Hub, beam and tip body swinging under gravity, the beam released bent
    // and a spring (no damping) pulling at the tip-node marker: T + V
    // (gravity, strain, spring) stays constant to DOP853's tolerance over
    // 1.5 s, while the tip body exchanges energy with the beam's modes.
    let num = Numeric::new(&system(Opts {
        spring: true,
        ..FLEX
    }))
    .unwrap();
    const N: usize = 14;
    let n = N / 2;
    let y0: [f64; N] = [
        0.2, 0.4, 0.02, -0.01, 0.005, 0.002, 0.3, // q
        1.0, -0.5, 0.3, 0.2, -0.1, 0.05, 1.5, // u
    ];
    let energy = |y: &[f64; N]| {
        let (t, v) = num.energy(&y[..n], &y[n..], 0.0).unwrap();
        (t + v, t.abs() + v.abs())
    };
    let (e0, scale) = energy(&y0);
    let sys = Ode { num: &num, n };
    let opts = SolveOptions {
        t_eval: (1..=15).map(|k| 0.1 * k as f64).collect(),
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &sys,
        0.0,
        y0,
        1.5,
        &opts,
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 15, "stopped: {:?}", sol.stop);
    let drift = sol
        .y_out
        .iter()
        .map(|y| (energy(y).0 - e0).abs() / scale)
        .fold(0.0, f64::max);
    eprintln!(
        "tip body at a node: relative energy drift {drift:e}, {} steps",
        sol.stats.accepted
    );
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    assert!(
        sol.y_out.iter().any(|y| y[2] < 0.0),
        "q_f1 never swung back"
    );
}

/// A bundled model by file name.
fn bundled(name: &str) -> System {
    eom_gen::check_file(&format!(
        "{}/../models/{name}.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap_or_else(|r| panic!("{r}"))
    .system
}

/// Runs `sys` interpreted; with `csv`, writes its rows every `every` s.
fn simulate(
    sys: &System,
    method: &str,
    integrator: &str,
    tol: (f64, f64),
    t_end: f64,
    csv: Option<(&str, f64)>,
) -> serde_json::Value {
    use eom_gen::functions::FunctionSet;
    use eom_gen::mech::formulate;
    let f = formulate(sys, FunctionSet::all_requested()).expect("formulates");
    let o = eom_sim::RunOptions {
        integrator: integrator.parse().expect("a known integrator"),
        rtol: tol.0,
        atol: tol.1,
        t_end,
        max_steps: 1_000_000,
        method: method.parse().expect("a known method"),
        csv: csv.map(|(path, _)| path.to_string()),
        every: csv.map(|(_, every)| every),
        ..Default::default()
    };
    serde_json::to_value(
        eom_gen::interpret::simulate(&f, sys, &o).unwrap_or_else(|e| panic!("{e}")),
    )
    .expect("JSON")
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
        .unwrap_or_default()
}

/// The rows of a CSV written by a run, and its header.
fn read_csv(path: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).expect("the run wrote its CSV");
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').filter_map(|x| x.parse().ok()).collect())
        .collect();
    (header, rows)
}

/// `|Σ w_k x_k e^{−iωt_k}|` with a Hann window `w`: the windowed spectrum's
/// amplitude at `ω`.
fn spectrum(t: &[f64], x: &[f64], omega: f64) -> f64 {
    let n = t.len() as f64;
    let (mut re, mut im) = (0.0, 0.0);
    for (k, (&tk, &xk)) in t.iter().zip(x).enumerate() {
        let w = 0.5 - 0.5 * (2.0 * std::f64::consts::PI * k as f64 / (n - 1.0)).cos();
        re += w * xk * (omega * tk).cos();
        im -= w * xk * (omega * tk).sin();
    }
    re.hypot(im)
}

#[test]
fn flex_slider_crank_reference_two_ways_and_bending_frequency() {
    // Simeon's slider-crank (models/slider_crank_flex.ron): the loop closes
    // at the rod's tip node. Over one crank revolution (2π/150 s) the run
    // by projection with DOP853 and the index-3 DAE with RADAU5, both at
    // tight tolerances, agree; the rod's first modal coordinate oscillates
    // at its pinned–pinned frequency ω₁ = π² √(EI/(ρA l2⁴)) = 1276.6 rad/s
    // (the FE beam's 1277.0 with 8 elements), shifted by the rod's rotation
    // (|ψ̇_abs| ≤ 75 rad/s: a shift of order ψ̇²/ω₁ ≈ 0.3 %) and not by the
    // axial load (the linear FFR model has no geometric stiffening of the
    // axial force: with it, the rod's compression and tension, of order
    // 500 N against the buckling load π² EI/l2² = 7.5 kN, would move ω₁ by
    // roughly ±N/(2 N_cr) ≈ ±3 % through the revolution).
    let sys = bundled("slider_crank_flex");
    let t_end = 2.0 * std::f64::consts::PI / 150.0;
    let a = simulate(&sys, "projection", "dop853", (1e-12, 1e-15), t_end, None);
    let b = simulate(&sys, "index3", "radau5", (1e-12, 1e-15), t_end, None);
    for v in [&a, &b] {
        assert_eq!(v["stop"], "finished", "{v}");
    }
    let (qa, qb) = (floats(&a["q"]), floats(&b["q"]));
    let qf = qa[1].abs().max(qa[2].abs());
    eprintln!("projection/DOP853: q = {qa:?}\nindex-3/RADAU5:    q = {qb:?}");
    assert!((qa[0] - qb[0]).abs() < 1e-8, "ψ: {} vs {}", qa[0], qb[0]);
    assert!((qa[3] - qb[3]).abs() < 1e-9, "s: {} vs {}", qa[3], qb[3]);
    for k in 1..3 {
        assert!(
            (qa[k] - qb[k]).abs() < 1e-5 * qf,
            "rod_f{k}: {} vs {}",
            qa[k],
            qb[k]
        );
    }
    // The rod's first modal coordinate, sampled every 10 µs over 0.2 s.
    let dir = env!("CARGO_TARGET_TMPDIR");
    let path = format!("{dir}/slider_crank_flex.csv");
    let c = simulate(
        &sys,
        "projection",
        "dop853",
        (1e-10, 1e-13),
        0.2,
        Some((&path, 1e-5)),
    );
    assert_eq!(c["stop"], "finished", "{c}");
    let (header, rows) = read_csv(&path);
    let col = header
        .iter()
        .position(|h| h == "rod_f1")
        .expect("rod_f1 column");
    let t: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let x: Vec<f64> = rows.iter().map(|r| r[col]).collect();
    // The forced part follows the crank (harmonics of 150 rad/s, largest at
    // the first few); remove it with a moving average over one period of
    // the expected free vibration, then find the spectral peak.
    let flex = sys.bodies[2]
        .flexible
        .as_deref()
        .expect("the rod is flexible");
    let w_fe = flex.modes.frequencies[0];
    let beam = &flex.beam;
    let w_closed =
        std::f64::consts::PI.powi(2) * (beam.ei_z / (beam.rho_a * beam.length.powi(4))).sqrt();
    let window = (2.0 * std::f64::consts::PI / w_fe / 1e-5).round() as usize;
    let smooth: Vec<f64> = (0..x.len())
        .map(|k| {
            let (lo, hi) = (
                k.saturating_sub(window / 2),
                (k + window / 2).min(x.len() - 1),
            );
            x[lo..=hi].iter().sum::<f64>() / (hi - lo + 1) as f64
        })
        .collect();
    let free: Vec<f64> = x.iter().zip(&smooth).map(|(a, b)| a - b).collect();
    let (mut best, mut peak) = (0.0, 0.0);
    let mut w = 700.0;
    while w < 2500.0 {
        let s = spectrum(&t, &free, w);
        if s > peak {
            (best, peak) = (w, s);
        }
        w += 0.5;
    }
    eprintln!(
        "rod bending: spectral peak at {best} rad/s; FE {w_fe:.1}, closed form {w_closed:.1} rad/s ({:+.2} %)",
        100.0 * (best / w_closed - 1.0)
    );
    assert!(
        (w_fe / w_closed - 1.0).abs() < 1e-3,
        "FE ω₁ {w_fe}, closed form {w_closed}"
    );
    assert!(
        (best / w_closed - 1.0).abs() < 0.01,
        "peak at {best} rad/s, pinned–pinned {w_closed}"
    );
}

#[test]
fn flex_arm7_with_a_flexible_forearm_is_arm7_at_rest_and_conserves_energy() {
    // models/arm7_flex.ron: link 4 a clamped beam carrying links 5–7 at
    // its tip node. (1) It generates, deterministically. (2) With the
    // elastic coordinates and rates at zero the joint rows of M and b and
    // the energies are arm7's (the forearm's mass, centre and inertia at
    // rest are arm7's link 4; the tip node is where arm7's j5 sits). (3)
    // Released from arm7's start with the forearm bent (no damping), T + V
    // stays constant to DOP853's tolerance over 1 s while the arm falls.
    let path = format!("{}/../models/arm7_flex.ron", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("reads arm7_flex");
    let src = Source::new("models/arm7_flex.ron", text);
    let g1 = eom_gen::generate(&src).unwrap_or_else(|e| panic!("{e}"));
    let g2 = eom_gen::generate(&src).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(g1.source, g2.source, "generation is deterministic");

    let flex = Numeric::new(&bundled("arm7_flex")).unwrap();
    let rigid = Numeric::new(&bundled("arm7")).unwrap();
    // arm7_flex's coordinates: q1..q4, link4_f1, link4_f2, q5..q7.
    let joints = [0, 1, 2, 3, 6, 7, 8];
    let mut rng = Rng(0x5eed_0007);
    for _ in 0..4 {
        let qr = rng.vec(7, 2.0);
        let ur = rng.vec(7, 1.5);
        let mut q = vec![0.0; 9];
        let mut u = vec![0.0; 9];
        for (r, &j) in joints.iter().enumerate() {
            q[j] = qr[r];
            u[j] = ur[r];
        }
        let (tf, tr) = (
            flex.terms(&q, &u, 0.0, &[]).unwrap(),
            rigid.terms(&qr, &ur, 0.0, &[]).unwrap(),
        );
        for (r, &jr) in joints.iter().enumerate() {
            for (c, &jc) in joints.iter().enumerate() {
                let (a, b) = (tf.mass_matrix[jr][jc], tr.mass_matrix[r][c]);
                assert!((a - b).abs() < 1e-12, "M[{r}][{c}]: flexible {a}, arm7 {b}");
            }
            let (a, b) = (tf.bias[jr], tr.bias[r]);
            assert!((a - b).abs() < 1e-11, "b[{r}]: flexible {a}, arm7 {b}");
        }
        let (ef, er) = (
            flex.energy(&q, &u, 0.0).unwrap(),
            rigid.energy(&qr, &ur, 0.0).unwrap(),
        );
        assert!(
            (ef.0 - er.0).abs() < 1e-12 && (ef.1 - er.1).abs() < 1e-11,
            "energies {ef:?}, arm7 {er:?}"
        );
    }

    const N: usize = 18;
    let sys = bundled("arm7_flex");
    let mut y0 = [0.0; N];
    y0[..9].copy_from_slice(&sys.q0());
    y0[4] = 2e-3;
    y0[5] = -1e-3;
    let energy = |y: &[f64; N]| {
        let (t, v) = flex.energy(&y[..9], &y[9..], 0.0).unwrap();
        (t + v, t.abs() + v.abs())
    };
    let (e0, scale) = energy(&y0);
    let opts = SolveOptions {
        t_eval: (1..=10).map(|k| 0.1 * k as f64).collect(),
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &Ode { num: &flex, n: 9 },
        0.0,
        y0,
        1.0,
        &opts,
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 10, "stopped: {:?}", sol.stop);
    let drift = sol
        .y_out
        .iter()
        .map(|y| (energy(y).0 - e0).abs() / scale)
        .fold(0.0, f64::max);
    let fall = sol.y_out.last().map_or(0.0, |y| (y[1] - y0[1]).abs());
    eprintln!(
        "arm7_flex: relative energy drift {drift:e} over 1 s, {} steps; q2 moved {fall:.3} rad",
        sol.stats.accepted
    );
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    assert!(fall > 0.1, "the arm fell: q2 moved {fall} rad");
}

/// A Grashof crank-rocker (crank 0.4 m, coupler 1 m, rocker 0.8 m, ground
/// 1 m; as in constraints.rs) whose coupler is a flexible beam: its frame
/// at the crank pin (clamped reference: the tangent frame there), the loop
/// cut at its tip node, where the rocker hangs; gravity along −y. The tip
/// node moves with the bending (u_y ≠ 0 in the tangent frame), so the
/// closure conditions depend on the elastic coordinates.
const FLEX_CRANK_ROCKER: &str = r#"Model(
    name: "flex_crank_rocker",
    gravity: (0, "-g", 0),
    parameters: [
        (name: "g", value: 9.81),
        (name: "m", value: 1.0),
        (name: "a", value: 0.4),
        (name: "b", value: 1.0),
        (name: "c", value: 0.8),
        (name: "d", value: 1.0),
    ],
    bodies: [
        (name: "crank", mass: "m", inertia: Diag("m*a^2/12", 0, "m*a^2/12")),
        (name: "coupler", flexible: Beam(length: "b", rho_a: 1.0, rho_ip: 1e-4, ea: 1e6,
            ei_y: 20000, ei_z: 200, gj: 500, elements: 6, reference: Clamped, modes: 2,
            nodes: [(name: "end", x: "b")])),
        (name: "rocker", mass: "m", inertia: Diag("m*c^2/12", 0, "m*c^2/12")),
    ],
    joints: [
        (name: "o2", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "crank",
         child_frame: (position: (0, "-a/2", 0)), coordinates: ["phi1"], u0: [3.0]),
        (name: "a_pin", kind: Revolute(axis: (0, 0, 1)), parent: "crank", child: "coupler",
         parent_frame: (position: (0, "a/2", 0)), coordinates: ["phi2"], q0: [0.407]),
        (name: "o4", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "rocker",
         parent_frame: (position: ("d", 0, 0)), child_frame: (position: (0, "-c/2", 0)),
         coordinates: ["phi3"], q0: [0.102]),
        (name: "b_pin", kind: Revolute(axis: (0, 0, 1)), parent: "coupler", parent_node: "end",
         child: "rocker", child_frame: (position: (0, "c/2", 0)), cut: true),
    ],
    outputs: [Energy],
)"#;

#[test]
fn flex_closed_loop_through_a_node() {
    // (1) The generated closure conditions Φ equal the f64 ones, and their
    // Jacobian J (symbolic, through the node's motion) equals central
    // differences of Φ along q̇ = N(q) e_k, at states with the coupler bent.
    // (2) Integrated by projection with DOP853 for 2 s (no damping; the
    // crank, started at 3 rad/s, swings under gravity), the loop stays
    // closed to 1e-9, T + V stays constant, and the coupler bends (the
    // rocker's weight and inertia load its tip).
    use eom_gen::functions::{Function, FunctionSet};
    use eom_gen::mech::formulate;
    let sys = check(&Source::new("flex_crank_rocker.ron", FLEX_CRANK_ROCKER))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    assert_eq!(
        sys.coordinate_names(),
        ["phi1", "phi2", "coupler_f1", "coupler_f2", "phi3"]
    );
    let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
    let p = f.program(Function::Constraints).expect("a loop");
    let num = Numeric::new(&sys).unwrap();
    let mut rng = Rng(0x5eed_0008);
    for _ in 0..3 {
        let mut q = rng.vec(5, 1.0);
        q[2] *= 0.05;
        q[3] *= 0.05;
        let u = rng.vec(5, 2.0);
        let x = eom_gen::interpret::Point {
            sys: &sys,
            q: &q,
            u: &u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        let values = eom_gen::interpret::run(p, &x);
        let phi_f64 = num.constraints(&q, 0.0).unwrap();
        let jac_f64 = num.constraint_jacobian(&q, 0.0).unwrap();
        let mut phi = Vec::new();
        let mut jac = Vec::new();
        for ((name, _), v) in p.outputs.iter().zip(values) {
            if name.starts_with("phi") && !name.starts_with("phidot") {
                phi.push(v);
            } else if name.starts_with("J_") {
                jac.push(v);
            }
        }
        assert_eq!(phi.len(), 2, "two in-plane closure conditions");
        for (a, b) in phi.iter().zip(&phi_f64) {
            assert!((a - b).abs() < 1e-12, "Φ generated {a}, f64 {b}");
        }
        let flat: Vec<f64> = jac_f64.iter().flatten().copied().collect();
        assert_eq!(jac.len(), flat.len());
        for (k, (a, b)) in jac.iter().zip(&flat).enumerate() {
            assert!(
                (a - b).abs() < 1e-7,
                "J[{k}] generated {a}, differences {b}"
            );
        }
        // The elastic columns of J are not zero: the node moves.
        assert!(
            jac_f64.iter().any(|row| row[2].abs() > 1e-3),
            "the tip node's bending enters Φ: {jac_f64:?}"
        );
    }
    let v = simulate(&sys, "projection", "dop853", (1e-10, 1e-12), 2.0, None);
    assert_eq!(v["stop"], "finished", "{v}");
    let e = floats(&v["energy"]);
    let r = v["max_constraint_residual"].as_f64().unwrap_or(f64::NAN);
    let q = floats(&v["q"]);
    eprintln!("flexible crank-rocker: energy {e:?}, max |Φ| {r:e}, q {q:?}");
    assert!((e[1] - e[0]).abs() < 1e-7 * e[0].abs(), "energy {e:?}");
    assert!(r < 1e-9, "max |Φ| = {r:e}");
    assert!((q[0] - 0.0).abs() > 0.3, "the crank moved: φ1 = {}", q[0]);
    assert!(q[2] != 0.0 && q[3] != 0.0, "the coupler bent: {q:?}");
}

#[test]
fn flex_node_errors_are_located_all_at_once() {
    // An unknown node name (with the names there are), a joint at a node
    // of a rigid body, a node off the finite-element grid (the nearest
    // nodes named), a node named twice, a node index past the last, and
    // Craig–Bampton without named nodes: every one at its field.
    let text = model(FLEX)
        .replace(
            "(name: \"mid\", x: 0.6)]",
            "(name: \"mid\", x: 0.55), (name: \"tip\", x: 0)]",
        )
        .replace("node: \"tip\", position", "node: \"tipp\", position")
        .replace(
            "(name: \"hub_j\", kind: Revolute(axis: (0, 0, 1)), parent: \"ground\", child: \"hub\"),",
            "(name: \"hub_j\", kind: Revolute(axis: (0, 0, 1)), parent: \"ground\", child: \"hub\", parent_node: 1),",
        )
        .replace("parent_node: \"tip\",", "parent_node: 9,")
        .replace(
            "(name: \"hub\", mass: 2.0,",
            "(name: \"hub\", mass: 2.0, flexible: Beam(length: 1, rho_a: 1, rho_ip: 1, ea: 1, ei_y: 1, ei_z: 1, gj: 1, elements: 2, reference: Clamped, modes: 1, craig_bampton: true),",
        );
    let report = match check(&Source::new("tip_body.ron", text)) {
        Ok(_) => panic!("the model is invalid"),
        Err(r) => r.to_string(),
    };
    for want in [
        "marker `mark`: flexible body `beam` has no node `tipp`",
        "did you mean `tip`?",
        "joint `hub_j` names node 1, but body `ground` is rigid",
        "node `mid` of flexible body `beam` at x = 0.55 m is not a finite-element node",
        "node 2 at x = 0.4 and node 3 at x = 0.6",
        "node `tip` is named twice on body `beam`",
        "joint `tip_j`: node 9 does not exist: the beam has nodes 0..=6",
        "flexible body `hub` asks for Craig–Bampton modes but names no nodes",
    ] {
        assert!(report.contains(want), "want `{want}` in:\n{report}");
    }
    // Each at a line and column of the file.
    assert!(report.matches("tip_body.ron:").count() >= 6, "{report}");
}

#[test]
fn flex_craig_bampton_modes_at_the_tip_node() {
    // Craig–Bampton with the named nodes (tip and mid) as boundary: 6
    // static constraint modes per node (their six degrees of freedom; the
    // clamped reference fixes node 0 only) plus the fixed-interface modes
    // asked for, so k = 12 + modes elastic coordinates. The basis holds the static
    // response to tip loads exactly, so the cantilever's lowest frequency
    // from it lies just above the normal-mode one (Rayleigh–Ritz: an upper
    // bound) and the tip body's dynamics stay consistent (forward and
    // inverse dynamics agree).
    let text = model(FLEX).replace(
        &format!("modes: {MODES}, nodes"),
        "modes: 2, craig_bampton: true, nodes",
    );
    let sys = check(&Source::new("tip_body.ron", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let cb = sys.bodies[2].flexible.as_deref().expect("flexible");
    assert_eq!(cb.count(), 12 + 2, "elastic coordinates");
    let normal = tip_shape(&system(FLEX));
    assert_eq!(normal.ncols(), MODES);
    let w_normal = system(FLEX).bodies[2]
        .flexible
        .as_deref()
        .map(|f| f.modes.frequencies[0])
        .unwrap_or_default();
    let w_cb = cb.modes.frequencies[0];
    eprintln!("lowest frequency: normal modes {w_normal}, Craig–Bampton {w_cb}");
    assert!(
        w_cb >= w_normal * (1.0 - 1e-12) && w_cb / w_normal - 1.0 < 1e-4,
        "Craig–Bampton ω₁ {w_cb}, normal-mode ω₁ {w_normal}"
    );
    let num = Numeric::new(&sys).unwrap();
    let n = sys.nu();
    let mut rng = Rng(0x5eed_0009);
    let mut q = rng.vec(n, 0.5);
    for x in &mut q[2..n - 1] {
        *x *= 0.01;
    }
    let u = rng.vec(n, 1.0);
    let tau = rng.vec(n, 1.0);
    let ud = num.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap();
    let back = num.inverse_dynamics(&q, &u, &ud, 0.0, &[]).unwrap();
    for (b, t) in back.iter().zip(&tau) {
        assert!((b - t).abs() < 1e-9, "τ {t} → {b}");
    }
}

/// Two flexible beams in series: the second hangs on a revolute at the
/// first's tip node and carries a point mass at its own last node; a
/// spring pulls at a marker on the second beam's middle node.
const TWO_BEAMS: &str = r#"Model(
    name: "two_beams",
    gravity: (0, -9.81, 0),
    bodies: [
        (name: "hub", mass: 1.0, inertia: Diag(0.05, 0.05, 0.08)),
        (name: "b1", flexible: Beam(length: 1.0, rho_a: 1.2, rho_ip: 1e-3, ea: 1e5,
            ei_y: 90, ei_z: 60, gj: 40, elements: 4, reference: Clamped, modes: 3,
            nodes: [(name: "tip", x: 1.0)])),
        (name: "b2", flexible: Beam(length: 0.8, rho_a: 0.8, rho_ip: 1e-3, ea: 1e5,
            ei_y: 50, ei_z: 30, gj: 30, elements: 4, reference: Clamped, modes: 3,
            nodes: [(name: "mid", x: 0.4), (name: "end", x: 0.8)]),
            markers: [(name: "m", node: "mid", position: (0, 0.03, 0.01))]),
        (name: "bob", mass: 0.3, com: (0.02, 0, 0), inertia: Diag(1e-3, 2e-3, 2e-3)),
    ],
    joints: [
        (name: "hub_j", kind: Revolute(axis: (0, 1, 0)), parent: "ground", child: "hub", u0: [1.0]),
        (name: "b1_j", kind: Revolute(axis: (0, 0, 1)), parent: "hub", child: "b1", u0: [0.5]),
        (name: "b2_j", kind: Revolute(axis: (0, 0, 1)), parent: "b1", parent_node: "tip",
         child: "b2", parent_frame: (orientation: Rpy(0.2, 0.1, 0)), u0: [-1.0]),
        (name: "bob_j", kind: Fixed, parent: "b2", parent_node: "end", child: "bob"),
    ],
    forces: [SpringDamper(name: "s", a: (body: "ground", point: (0.5, 1.0, 0.5)),
        b: (body: "b2", marker: "m"), stiffness: 30, rest_length: 0.5)],
)"#;

#[test]
fn flex_node_chain_of_two_beams() {
    // A flexible body hung at a node of another, with a body and a spring
    // at its own nodes: the ABA (two eliminations, the inner one passed to
    // the outer beam's node) equals M⁻¹(τ − b), RNEA inverts it, the
    // generated programs equal the f64 ones, and T + V stays constant over
    // 1 s (DOP853 at 1e-12, no damping).
    use eom_gen::functions::{Function, FunctionSet};
    use eom_gen::mech::formulate;
    let sys = check(&Source::new("two_beams.ron", TWO_BEAMS))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let n = sys.nu();
    assert_eq!(n, 3 + 3 + 3);
    let num = Numeric::new(&sys).unwrap();
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let mut rng = Rng(0x5eed_000a);
    for _ in 0..3 {
        let mut q = rng.vec(n, 1.0);
        let u = rng.vec(n, 1.5);
        for k in [2, 3, 4, 6, 7, 8] {
            q[k] *= 0.05;
        }
        let tau = rng.vec(n, 2.0);
        let ud = num.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap();
        let ud_m = num.forward_dynamics_ltdl(&q, &u, 0.0, &tau, &[]).unwrap();
        let back = num.inverse_dynamics(&q, &u, &ud, 0.0, &[]).unwrap();
        let scale = ud_m.iter().fold(1.0_f64, |a, b| a.max(b.abs()));
        for i in 0..n {
            assert!(
                (ud[i] - ud_m[i]).abs() < 1e-10 * scale,
                "u̇[{i}]: ABA {}, M {}",
                ud[i],
                ud_m[i]
            );
            assert!((back[i] - tau[i]).abs() < 1e-10 * 2.0, "τ[{i}]");
        }
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
        let got = eom_gen::interpret::run(
            f.program(Function::ForwardDynamics).expect("requested"),
            &point,
        );
        for i in 0..n {
            assert!(
                (got[i] - ud[i]).abs() < 1e-11 * scale,
                "generated u̇[{i}] {}, f64 {}",
                got[i],
                ud[i]
            );
        }
    }
    const N: usize = 18;
    let mut y0 = [0.0; N];
    y0[..9].copy_from_slice(&sys.q0());
    y0[9..].copy_from_slice(&sys.u0());
    y0[2] = 0.02;
    y0[7] = -0.01;
    let energy = |y: &[f64; N]| {
        let (t, v) = num.energy(&y[..9], &y[9..], 0.0).unwrap();
        (t + v, t.abs() + v.abs())
    };
    let (e0, scale) = energy(&y0);
    let opts = SolveOptions {
        t_eval: (1..=10).map(|k| 0.1 * k as f64).collect(),
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &Ode { num: &num, n: 9 },
        0.0,
        y0,
        1.0,
        &opts,
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 10, "stopped: {:?}", sol.stop);
    let drift = sol
        .y_out
        .iter()
        .map(|y| (energy(y).0 - e0).abs() / scale)
        .fold(0.0, f64::max);
    eprintln!(
        "two beams in series: relative energy drift {drift:e}, {} steps",
        sol.stats.accepted
    );
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
}
