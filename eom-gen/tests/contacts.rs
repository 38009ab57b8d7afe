//! Unilateral contacts (issue #26): the model format's checks (every error
//! at once, located, with what would be right) and the generated function
//! `contacts` — its rows `w` are the partial derivatives of `ġ` and `ġ` is
//! the time derivative of the gap `g` along the motion (finite differences
//! of `g`), `γ` the second derivative's velocity part, and the evaluator
//! agrees with the numeric twin.

use eom_gen::System;
use eom_gen::functions::{Function, FunctionSet};
use eom_gen::interpret::{Point, evaluate_function};
use eom_gen::mech::{Numeric, formulate};
use eom_gen::model::{Source, check};

/// A double pendulum in the x–y plane (gravity −y) with a ball on a slider
/// below it: every kind of contact.
const BASE: &str = r#"Model(
    name: "contact_zoo",
    gravity: (0, "-g", 0),
    parameters: [(name: "g", value: 9.81), (name: "l", value: 1.0)],
    bodies: [
        (name: "upper", mass: 1, com: (0, "-l/2", 0), inertia: Diag(0.1, 0.1, 0.1), markers: [(name: "end", position: (0, "-l", 0))]),
        (name: "lower", mass: 1, com: (0, "-l/2", 0), inertia: Diag(0.1, 0.1, 0.1), markers: [(name: "tip", position: (0, "-l", 0))]),
        (name: "ball", mass: 2, inertia: Diag(0.01, 0.01, 0.01)),
    ],
    joints: [
        (name: "shoulder", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "upper", coordinates: ["q1"], q0: [0.3]),
        (name: "elbow", kind: Revolute(axis: (0, 0, 1)), parent: "upper", child: "lower", parent_frame: (position: (0, "-l", 0)), coordinates: ["q2"], q0: [0.2]),
        (name: "slide", kind: Prismatic(axis: (1, 0, 0)), parent: "ground", child: "ball", parent_frame: (position: (0, -3, 0)), coordinates: ["x"], q0: [0.5]),
    ],
    contacts: [
        JointLimit(name: "elbow_stop", joint: "elbow", lower: -1.5, upper: 1.5, e: 0.5),
        Plane(name: "wall", at: (body: "lower", marker: "tip"), radius: 0.05, point: (1.5, 0, 0), normal: (-1, 0, 0), e: 0.3, mu: 0.2),
        Spheres(name: "knock", a: (body: "lower", marker: "tip"), b: (body: "ball"), radius_a: 0.05, radius_b: 0.2, e: 1),
        JointLimit(name: "rail", joint: "slide", upper: 2, e: 0),
    ],
)
"#;

fn diagnose(edits: &[(&str, &str)]) -> String {
    let mut text = BASE.to_string();
    for (from, to) in edits {
        assert!(
            text.contains(from),
            "test setup: `{from}` is not in the model"
        );
        text = text.replacen(from, to, 1);
    }
    eom_gen::testkit::diagnose("models/contact_zoo.ron", &text)
}

fn system() -> System {
    check(&Source::new("models/contact_zoo.ron", BASE.to_string()))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

#[test]
fn the_zoo_is_valid_and_has_five_gap_rows() {
    assert_eq!(diagnose(&[]), "valid");
    let rows: Vec<String> = system()
        .contact_rows()
        .into_iter()
        .map(|(_, r)| r)
        .collect();
    assert_eq!(
        rows,
        [
            "elbow_stop.lower",
            "elbow_stop.upper",
            "wall",
            "knock",
            "rail.upper"
        ]
    );
}

/// Every mistake reported at once, each at its `file:line:col`.
#[test]
fn bad_contacts_are_all_reported_located() {
    let out = diagnose(&[
        (r#"joint: "elbow", lower"#, r#"joint: "elbo", lower"#),
        (
            r#"body: "lower", marker: "tip"), radius: 0.05"#,
            r#"body: "lower", marker: "toe"), radius: 0.05"#,
        ),
        ("normal: (-1, 0, 0), e: 0.3", "normal: (0, 0, 0), e: 1.3"),
        (r#"b: (body: "ball")"#, r#"b: (body: "bal")"#),
        ("upper: 2, e: 0)", "upper: 2, e: 0, mu: -0.2)"),
    ]);
    for want in [
        "models/contact_zoo.ron:16:47: error: unknown joint `elbo`",
        "error: body `lower` has no marker `toe`",
        "error: the plane's normal has zero length",
        "error: `e` of contact `wall` is 1.3, outside [0, 1]",
        "error: unknown anchor body `bal`",
        "error: `mu` of contact `rail` is -0.2, negative",
    ] {
        assert!(out.contains(want), "missing `{want}` in:\n{out}");
    }
    assert_eq!(out.matches("error:").count(), 6, "{out}");
    // Friction where there is no tangent plane (a joint limit) is refused
    // at the field; between two spheres it is allowed.
    let out = diagnose(&[
        ("upper: 2, e: 0)", "upper: 2, e: 0, mu: 0.3)"),
        ("radius_b: 0.2, e: 1)", "radius_b: 0.2, e: 1, mu: 0.1)"),
    ]);
    assert!(
        out.contains("models/contact_zoo.ron:19:70: error: joint limit `rail` has Coulomb friction (mu = 0.3)"),
        "{out}"
    );
    assert_eq!(out.matches("error:").count(), 1, "{out}");
}

/// A model with cables: its runner (generalized-α, sustained contacts
/// held as index-3 rows) handles contacts on bodies beside the cables,
/// with or without friction (`eom-gen/tests/cable_contacts_mixed.rs`;
/// frictionless ones used to be refused, and before that ignored: the
/// stop let the boom through; friction there was refused until session
/// 46), and contacts at cable nodes with or without friction. What is
/// refused anywhere is refused here too: friction on a joint limit, at
/// its `mu`, one error.
#[test]
fn contacts_on_bodies_beside_cables_are_valid_with_friction() {
    let crane = std::fs::read_to_string(format!(
        "{}/../models/ancf/crane_rope.ron",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("model");
    let with = |contacts: &str| {
        let text = crane.replacen(
            "    cables: [",
            &format!("    contacts: [{contacts}],\n    cables: ["),
            1,
        );
        check(&Source::new("models/crane.ron", text))
            .map(|_| "valid".to_string())
            .unwrap_or_else(|r| r.to_string())
    };
    let out = with(r#"JointLimit(name: "stop", joint: "pivot", lower: -0.2, e: 0.5)"#);
    assert_eq!(out, "valid", "a frictionless joint limit beside the rope");
    let out = with(
        r#"Plane(name: "ground", at: (body: "boom", point: (1, 0, 0)), point: (0, -1, 0), normal: (0, 1, 0), e: 0.5, mu: 0.4)"#,
    );
    assert_eq!(out, "valid", "a body's plane with friction beside the rope");
    let out = with(r#"JointLimit(name: "stop", joint: "pivot", lower: -0.2, e: 0.5, mu: 0.4)"#);
    assert!(
        out.contains("models/crane.ron:") && out.contains("`stop`") && out.contains("mu"),
        "friction on a joint limit, located: {out}"
    );
    assert_eq!(out.matches("error:").count(), 1, "{out}");
    let out = with(
        r#"Plane(name: "floor", at: (body: "rope", node: 1), point: (0, -50, 0), normal: (0, 1, 0), e: 0.5, mu: 0.4)"#,
    );
    assert_eq!(
        out, "valid",
        "a node contact with friction on a rope hung at the boom"
    );
}

/// A contact closed at the initial state is refused with its penetration
/// and what would open it; a limit on a joint without one coordinate too.
#[test]
fn closed_at_the_start_is_refused_with_the_penetration() {
    // The wall at x = 0.5: the tip (x = sin 0.3 + sin 0.5 = 0.7749) and its
    // 0.05 m sphere are 0.3249 m through it.
    let out = diagnose(&[("point: (1.5, 0, 0)", "point: (0.5, 0, 0)")]);
    assert!(
        out.contains("error: contact `wall` penetrates its plane by 3.249")
            && out.contains("start body `lower` at least 3.249"),
        "{out}"
    );
    let out = diagnose(&[("q0: [0.2]", "q0: [1.6]")]);
    assert!(
        out.contains("joint limit `elbow_stop.upper` is violated at the initial state: `q2` = 1.6 is 1.000000e-1 rad beyond it"),
        "{out}"
    );
    let out = diagnose(&[("lower: -1.5, upper: 1.5", "lower: 1.5, upper: 1.5")]);
    assert!(out.contains("upper 1.5 is not above lower 1.5"), "{out}");
    let out = diagnose(&[(r#"upper: 2, e: 0"#, "e: 0")]);
    assert!(out.contains("has neither `lower` nor `upper`"), "{out}");
}

/// `w = ∂ġ/∂u`, and `ġ` and `γ` against central differences of `g` along
/// `q(s) = q + s u + s²/2 u̇` (here `q̇ = u`): `ġ = dg/ds`,
/// `g̈ = d²g/ds² = wᵀ u̇ − γ`; the generated program against the numeric
/// twin's `g`, `ġ`.
#[test]
fn generated_rows_are_the_derivatives_of_the_gaps() {
    let sys = system();
    let f = formulate(&sys, FunctionSet::default()).expect("formulate");
    assert_eq!(f.labels(Function::Contacts).len(), 5);
    let num = Numeric::new(&sys).expect("numeric");
    let (nk, nu) = (5, sys.nu());
    let eval = |q: &[f64], u: &[f64]| {
        let x = Point {
            sys: &sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        evaluate_function(&f, Function::Contacts, &x).expect("contacts")
    };
    let q = [0.4, -0.7, 0.9];
    let u = [1.3, -0.6, 0.8];
    let ud = [0.5, 2.0, -1.0];
    let v = eval(&q, &u);
    assert_eq!(v.len(), 5 * nk + nk * nu);
    let twin = num.contacts(&sys, &q, &u, 0.0).expect("twin");
    let h = 1e-4;
    let at = |s: f64| -> Vec<f64> {
        let qs: Vec<f64> = (0..nu)
            .map(|i| q[i] + s * u[i] + 0.5 * s * s * ud[i])
            .collect();
        eval(&qs, &u)[..nk].to_vec()
    };
    let (gp, gm, g0) = (at(h), at(-h), at(0.0));
    for r in 0..nk {
        let w = &v[5 * nk + r * nu..5 * nk + (r + 1) * nu];
        let gdot: f64 = w.iter().zip(&u).map(|(a, b)| a * b).sum();
        assert!(
            (gdot - v[nk + r]).abs() < 1e-12,
            "row {r}: wᵀu {gdot} vs ġ {}",
            v[nk + r]
        );
        let fd1 = (gp[r] - gm[r]) / (2.0 * h);
        assert!(
            (fd1 - v[nk + r]).abs() < 1e-6,
            "row {r}: ġ {} vs dg/ds {fd1}",
            v[nk + r]
        );
        let fd2 = (gp[r] - 2.0 * g0[r] + gm[r]) / (h * h);
        let gdd: f64 = w.iter().zip(&ud).map(|(a, b)| a * b).sum::<f64>() - v[2 * nk + r];
        assert!(
            (fd2 - gdd).abs() < 1e-5,
            "row {r}: g̈ {gdd} vs d²g/ds² {fd2}"
        );
        assert!((twin[r].0 - v[r]).abs() < 1e-13 && (twin[r].1 - v[nk + r]).abs() < 1e-13);
    }
    assert_eq!(
        &v[3 * nk..5 * nk],
        &[0.5, 0.5, 0.3, 1.0, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0]
    );
    // The joint limits' rows are ±1 on their speed.
    assert_eq!(&v[5 * nk..5 * nk + nu], &[0.0, 1.0, 0.0]);
    assert_eq!(&v[5 * nk + 4 * nu..], &[0.0, 0.0, -1.0]);
}

/// The tangential rows of `friction` for the wall (`μ = 0.2`; `n = −x`, so
/// `t1 = +y`, `t2 = n × t1 = −z`): the touching point is the tip shifted
/// by the radius towards the wall, moving at
/// `v_t1 = sin q1 u1 + sin(q1 + q2)(u1 + u2) + 0.05 (u1 + u2)`, `v_t2 = 0`;
/// `v_t = W_t u`, and `γ_t = −dv_t/dt` at `u̇ = 0` against differences
/// along `q + s u`. The frictionless rows are zero.
#[test]
fn tangential_rows_of_the_wall_are_the_touching_points_speed() {
    let sys = system();
    let f = formulate(&sys, FunctionSet::default()).expect("formulate");
    let (nk, nu) = (5, sys.nu());
    let eval = |q: &[f64], u: &[f64]| {
        let x = Point {
            sys: &sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        evaluate_function(&f, Function::Friction, &x).expect("friction")
    };
    let q = [0.4, -0.7, 0.9];
    let u = [1.3, -0.6, 0.8];
    let v = eval(&q, &u);
    assert_eq!(v.len(), 4 * nk + 2 * nk * nu);
    let want = q[0].sin() * u[0] + (q[0] + q[1]).sin() * (u[0] + u[1]) + 0.05 * (u[0] + u[1]);
    assert!((v[2] - want).abs() < 1e-13, "v_t1 {} vs {want}", v[2]);
    assert!(v[nk + 2].abs() < 1e-13, "v_t2 {}", v[nk + 2]);
    for (a, r) in [(0, 2), (1, 2)] {
        let w = &v[4 * nk + a * nk * nu + r * nu..4 * nk + a * nk * nu + (r + 1) * nu];
        let wu: f64 = w.iter().zip(&u).map(|(x, y)| x * y).sum();
        assert!((wu - v[a * nk + r]).abs() < 1e-13, "W_t u along t{}", a + 1);
    }
    let h = 1e-5;
    let at = |s: f64| {
        let qs: Vec<f64> = q.iter().zip(&u).map(|(a, b)| a + s * b).collect();
        eval(&qs, &u)[2]
    };
    let dv = (at(h) - at(-h)) / (2.0 * h);
    assert!(
        (dv + v[2 * nk + 2]).abs() < 1e-7,
        "γ_t1 {} vs −dv_t1/ds {}",
        v[2 * nk + 2],
        -dv
    );
    for r in [0, 1, 3, 4] {
        assert!(
            (0..4).all(|b| v[b * nk + r] == 0.0),
            "row {r} has no friction"
        );
    }
}

/// A plane fixed on a body (`on`): a paddle turning about z carries the
/// plane `y = 0.1` of its axes (normal +y), a ball on a planar joint
/// touches it. `g = n·(x − p) − r` with `n`, `p` turning with the paddle;
/// `ġ` against central differences of `g` along `q + s u` (so it includes
/// the plane's own motion), `w = ∂ġ/∂u` and `γ` as for world planes; a
/// plane on the contact's own body and an unknown `on` body are errors.
#[test]
fn a_plane_on_a_moving_body() {
    let text = r#"Model(
    name: "paddle",
    bodies: [
        (name: "paddle", mass: 1, inertia: Diag(0.1, 0.1, 0.1)),
        (name: "ball", mass: 1, inertia: Diag(0.01, 0.01, 0.01)),
    ],
    joints: [
        (name: "turn", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "paddle", coordinates: ["th"], q0: [0.2]),
        (name: "p", kind: Planar, parent: "ground", child: "ball", coordinates: ["x", "y", "a"], q0: [0.5, 0.8, 0]),
    ],
    contacts: [Plane(name: "hit", at: (body: "ball"), radius: 0.05, point: (0, 0.1, 0), normal: (0, 1, 0), on: "paddle", e: 0.5, mu: 0.3)],
)"#;
    let sys = check(&Source::new("models/paddle.ron", text.to_string()))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let f = formulate(&sys, FunctionSet::default()).expect("formulate");
    let nu = sys.nu();
    let eval = |q: &[f64], u: &[f64], func: Function| {
        let x = Point {
            sys: &sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        evaluate_function(&f, func, &x).expect("evaluates")
    };
    let q = [0.3, 0.4, 0.9, 0.2];
    let u = [1.5, -0.7, 0.4, 2.0];
    let ud = [0.3, -1.0, 0.5, 0.2];
    let v = eval(&q, &u, Function::Contacts);
    // g by hand: n = (−sin θ, cos θ), p = 0.1 n.
    let (s, c) = q[0].sin_cos();
    let g = -s * q[1] + c * q[2] - 0.1 - 0.05;
    assert!((v[0] - g).abs() < 1e-14, "g {} vs {g}", v[0]);
    let h = 1e-4;
    let at = |t: f64| {
        let qs: Vec<f64> = (0..nu)
            .map(|i| q[i] + t * u[i] + 0.5 * t * t * ud[i])
            .collect();
        eval(&qs, &u, Function::Contacts)[0]
    };
    let fd1 = (at(h) - at(-h)) / (2.0 * h);
    assert!((fd1 - v[1]).abs() < 1e-7, "ġ {} vs dg/ds {fd1}", v[1]);
    let w = &v[5..5 + nu];
    let wu: f64 = w.iter().zip(&u).map(|(a, b)| a * b).sum();
    assert!((wu - v[1]).abs() < 1e-13, "wᵀu {wu} vs ġ {}", v[1]);
    let fd2 = (at(h) - 2.0 * at(0.0) + at(-h)) / (h * h);
    let gdd: f64 = w.iter().zip(&ud).map(|(a, b)| a * b).sum::<f64>() - v[2];
    assert!((fd2 - gdd).abs() < 1e-5, "g̈ {gdd} vs {fd2}");
    // Friction: the touching point's speed relative to the paddle, along
    // t1 = the paddle's x axis (for n = +y): W_t u = v_t.
    let t = eval(&q, &u, Function::Friction);
    let wt: f64 = t[4..4 + nu].iter().zip(&u).map(|(a, b)| a * b).sum();
    assert!((wt - t[0]).abs() < 1e-13);
    // By hand: the ball's touching point x_c = x − r n moves at
    // v + ȧ ẑ × (−r n), less the paddle's point there, θ̇ ẑ × x_c; along
    // t1 = (cos θ, sin θ).
    let n = [-s, c];
    let xc = [q[1] - 0.05 * n[0], q[2] - 0.05 * n[1]];
    let vc = [u[1] + 0.05 * u[3] * n[1], u[2] - 0.05 * u[3] * n[0]];
    let vp = [-u[0] * xc[1], u[0] * xc[0]];
    let want = (vc[0] - vp[0]) * c + (vc[1] - vp[1]) * s;
    assert!((t[0] - want).abs() < 1e-13, "v_t1 {} vs {want}", t[0]);
    // Errors at the field.
    let own = text.replace(r#"on: "paddle""#, r#"on: "ball""#);
    let out = check(&Source::new("models/paddle.ron", own))
        .err()
        .map(|r| r.to_string())
        .unwrap_or_default();
    assert!(
        out.contains("contact `hit` touches a plane on its own body `ball`"),
        "{out}"
    );
    let unknown = text.replace(r#"on: "paddle""#, r#"on: "padle""#);
    let out = check(&Source::new("models/paddle.ron", unknown))
        .err()
        .map(|r| r.to_string())
        .unwrap_or_default();
    assert!(out.contains("unknown plane body `padle`"), "{out}");
}
