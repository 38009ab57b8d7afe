//! The generated derivatives of forward dynamics
//! (`forward_dynamics_derivatives`: `∂u̇/∂q` in the tangent space,
//! `∂u̇/∂u`, `∂u̇/∂τ`, `∂u̇/∂(inputs)`):
//!
//! - the pendulum's against the hand derivation, `θ̈ = −(g/l) sin θ + τ/(m l²)`;
//! - the double pendulum's about the hanging equilibrium against the hand
//!   linearisation `∂q̈/∂q = −M⁻¹K` in relative angles, and the normal-mode
//!   frequencies of that `A` against their closed form;
//! - every bundled model's (rigid, and with flexible bodies; not cables)
//!   against central differences of the `f64`
//!   forward dynamics (the numeric twin, not the generated program) at
//!   random states, coordinates moved along the tangent directions
//!   `N(q) e_j` (quaternions kept on the unit sphere);
//!   — both forms (forward dynamics differentiated, and `−M⁻¹ ∂ID/∂x`
//!   from differentiated Newton–Euler), as some models keep each;
//! - the third form (`−M⁻¹ ∂ID/∂x` with `∂ID/∂(q, u)` by the recursion of
//!   Carpentier and Mansard) against the other two on every bundled model
//!   it applies to, and refused (not a candidate) where it does not;
//! - the same recursion in body axes against the world-axis one and
//!   central differences (revolute, spherical, free and prismatic joints);
//! - inputs: `∂u̇/∂(inputs)` of an actuator;
//! - `inverse_dynamics_derivatives` (`∂τ/∂q`, `∂τ/∂u`, `∂τ/∂u̇ = M`,
//!   `∂τ/∂(inputs)`) against central differences of the `f64` inverse
//!   dynamics and `∂τ/∂u̇` against the `f64` mass matrix, every model;
//! - generated only when asked: a model without the request does not get it.

use eom_gen::functions::{Function, FunctionSet};
use eom_gen::interpret::{Point, run};
use eom_gen::mech::derivatives::DerivativeForm;
use eom_gen::mech::{Formulation, Numeric, formulate};
use eom_gen::model::{Source, check};
use eom_gen::testkit::{Rng, random_state};
use eom_gen::{System, check_file};

fn models_dir() -> String {
    format!("{}/../models", env!("CARGO_MANIFEST_DIR"))
}

fn system(name: &str) -> System {
    check_file(&format!("{}/{name}.ron", models_dir()))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

/// The formulation with the derivatives asked for.
fn with_derivatives(sys: &System, what: &str) -> Formulation {
    formulate(
        sys,
        FunctionSet::default().with(Function::ForwardDynamicsDerivatives),
    )
    .unwrap_or_else(|e| panic!("{what}: {e}"))
}

/// The derivative blocks at a state: `(∂u̇/∂q, ∂u̇/∂u, ∂u̇/∂τ, ∂u̇/∂inputs)`,
/// each by rows.
struct Blocks {
    dq: Vec<Vec<f64>>,
    du: Vec<Vec<f64>>,
    dtau: Vec<Vec<f64>>,
    dinput: Vec<Vec<f64>>,
}

fn blocks(f: &Formulation, x: &Point<'_>) -> Blocks {
    program_blocks(
        f.program(Function::ForwardDynamicsDerivatives)
            .expect("derivatives generated"),
        x,
    )
}

/// The blocks of one program of the derivatives at a state.
fn program_blocks(p: &eom_gen::sym::Program, x: &Point<'_>) -> Blocks {
    let nu = x.sys.nu();
    let ni = x.sys.inputs.len();
    let flat = run(p, x);
    assert_eq!(flat.len(), 3 * nu * nu + nu * ni, "result length");
    let rows = |start: usize, cols: usize| -> Vec<Vec<f64>> {
        (0..nu)
            .map(|i| flat[start + i * cols..start + (i + 1) * cols].to_vec())
            .collect()
    };
    Blocks {
        dq: rows(0, nu),
        du: rows(nu * nu, nu),
        dtau: rows(2 * nu * nu, nu),
        dinput: rows(3 * nu * nu, ni),
    }
}

fn point<'a>(sys: &'a System, q: &'a [f64], u: &'a [f64], tau: &'a [f64]) -> Point<'a> {
    Point {
        sys,
        q,
        u,
        udot: &[],
        tau,
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.0,
    }
}

fn check_close(what: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol * (1.0 + want.abs()),
        "{what}: got {got}, want {want}"
    );
}

/// `θ̈ = −(g/l) sin θ + τ/(m l²)` for the bundled pendulum (a point mass
/// `m = 1 kg` on a massless link `l = 1 m`, `g = 9.81`, so `l_eff = l`):
/// `∂θ̈/∂θ = −(g/l) cos θ`, `∂θ̈/∂θ̇ = 0`, `∂θ̈/∂τ = 1/(m l²)`.
#[test]
fn pendulum_derivatives_are_the_hand_derivation() {
    let sys = system("pendulum");
    let f = with_derivatives(&sys, "pendulum");
    let (g, m, l) = (9.81, 1.0, 1.0);
    for (theta, omega, tau) in [(0.0, 0.0, 0.0), (0.3, -1.2, 0.5), (2.0, 3.0, -1.0)] {
        let (q, u, tau) = ([theta], [omega], [tau]);
        let b = blocks(&f, &point(&sys, &q, &u, &tau));
        let at = format!("θ = {theta}, θ̇ = {omega}");
        check_close(
            &format!("∂θ̈/∂θ at {at}"),
            b.dq[0][0],
            -(g / l) * f64::cos(theta),
            1e-14,
        );
        check_close(&format!("∂θ̈/∂θ̇ at {at}"), b.du[0][0], 0.0, 1e-14);
        check_close(
            &format!("∂θ̈/∂τ at {at}"),
            b.dtau[0][0],
            1.0 / (m * l * l),
            1e-14,
        );
    }
}

/// `2 × 2` inverse.
fn inv2(a: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    [
        [a[1][1] / det, -a[0][1] / det],
        [-a[1][0] / det, a[0][0] / det],
    ]
}

fn mul2(a: [[f64; 2]; 2], b: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    let mut c = [[0.0; 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j];
        }
    }
    c
}

/// The double pendulum (point masses `m1 = m2 = 1 kg` on rods
/// `l1 = l2 = 1 m`, `g = 9.8`) about the hanging equilibrium `q = 0`, in
/// its relative angles `q1 = φ1`, `q2 = φ2 − φ1` (`φ = S q`,
/// `S = [[1, 0], [1, 1]]`): in absolute angles
/// `M_φ = [[(m1+m2) l1², m2 l1 l2], [m2 l1 l2, m2 l2²]]` and
/// `K_φ = diag((m1+m2) g l1, m2 g l2)`; in relative ones `M = Sᵀ M_φ S`,
/// `K = Sᵀ K_φ S`, and `M q̈ + K q = 0`, so `∂q̈/∂q = −M⁻¹K`,
/// `∂q̈/∂q̇ = 0`, `∂q̈/∂τ = M⁻¹`. The eigenvalues of the first-order
/// `A = [[0, I], [−M⁻¹K, 0]]` are `±iω` with
/// `m1 l1 l2 ω⁴ − (m1+m2) g (l1+l2) ω² + (m1+m2) g² = 0`, here
/// `ω² = g (2 ∓ √2)`: the eigenvalues of `−∂q̈/∂q` are `ω²`.
#[test]
fn double_pendulum_about_hanging_is_minus_m_inverse_k() {
    let sys = system("double_pendulum");
    let f = with_derivatives(&sys, "double_pendulum");
    let (g, m1, m2, l1, l2) = (9.8, 1.0, 1.0, 1.0, 1.0);
    let m_phi = [
        [(m1 + m2) * l1 * l1, m2 * l1 * l2],
        [m2 * l1 * l2, m2 * l2 * l2],
    ];
    let k_phi = [[(m1 + m2) * g * l1, 0.0], [0.0, m2 * g * l2]];
    let s = [[1.0, 0.0], [1.0, 1.0]];
    let st = [[1.0, 1.0], [0.0, 1.0]];
    let m = mul2(st, mul2(m_phi, s));
    let k = mul2(st, mul2(k_phi, s));
    let minv = inv2(m);
    let minv_k = mul2(minv, k);
    let b = blocks(&f, &point(&sys, &[0.0, 0.0], &[0.0, 0.0], &[0.0, 0.0]));
    for i in 0..2 {
        for j in 0..2 {
            check_close(
                &format!("∂q̈{i}/∂q{j} (−M⁻¹K)"),
                b.dq[i][j],
                -minv_k[i][j],
                1e-13,
            );
            check_close(&format!("∂q̈{i}/∂q̇{j}"), b.du[i][j], 0.0, 1e-13);
            check_close(
                &format!("∂q̈{i}/∂τ{j} (M⁻¹)"),
                b.dtau[i][j],
                minv[i][j],
                1e-13,
            );
        }
    }
    // ω² are the eigenvalues of −∂q̈/∂q (trace and determinant of 2 × 2).
    let a = [[-b.dq[0][0], -b.dq[0][1]], [-b.dq[1][0], -b.dq[1][1]]];
    let (tr, det) = (a[0][0] + a[1][1], a[0][0] * a[1][1] - a[0][1] * a[1][0]);
    let disc = (tr * tr / 4.0 - det).sqrt();
    let (slow, fast) = (tr / 2.0 - disc, tr / 2.0 + disc);
    // Roots of m1 l1 l2 x² − (m1+m2) g (l1+l2) x + (m1+m2) g² = 0.
    let (qa, qb, qc) = (m1 * l1 * l2, -(m1 + m2) * g * (l1 + l2), (m1 + m2) * g * g);
    let root = (qb * qb - 4.0 * qa * qc).sqrt();
    let (want_slow, want_fast) = ((-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa));
    check_close("ω² slow mode", slow, want_slow, 1e-12);
    check_close("ω² fast mode", fast, want_fast, 1e-12);
    check_close("ω² slow = g(2 − √2)", slow, g * (2.0 - 2f64.sqrt()), 1e-12);
    check_close("ω² fast = g(2 + √2)", fast, g * (2.0 + 2f64.sqrt()), 1e-12);
}

/// The bundled models without cables (rigid, and with flexible bodies
/// when `flexible`), by reading `models/*.ron`.
fn bundled_models(flexible: bool) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(models_dir())
        .expect("models/")
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names.retain(|n| {
        let sys = system(n);
        sys.cables.is_empty() && (sys.flexible_bodies().next().is_some() == flexible)
    });
    names
}

/// The tangent direction `N(q) e_j` of speed `j` (`q̇` is linear in `u`).
fn tangent(num: &Numeric, q: &[f64], nu: usize, j: usize) -> Vec<f64> {
    let mut e = vec![0.0; nu];
    e[j] = 1.0;
    num.qdot(q, &e)
}

/// `q` moved by `h` along `d`, its quaternions back on the unit sphere (to
/// second order that is `q ⊗ (1, h δθ/2)`, the rotation-vector chart).
fn moved(sys: &System, q: &[f64], d: &[f64], h: f64) -> Vec<f64> {
    let mut out: Vec<f64> = q.iter().zip(d).map(|(q, d)| q + h * d).collect();
    for a in sys.quaternion_indices() {
        let n = out[a..a + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
        out[a..a + 4].iter_mut().for_each(|x| *x /= n);
    }
    out
}

/// Checks the derivatives of `sys` against central differences of the
/// `f64` forward dynamics with step `h = 1e-5`. Their error is truncation,
/// `O(h²)`, allowed `1e-6` of the block's largest entry, plus rounding,
/// `κ ε ‖u̇‖/h` with the evaluation's cancellation `κ` taken as 100: the
/// Andrews mechanism's `‖u̇‖ ≈ 2·10⁵` makes its differences good to
/// about `10⁻⁵` only.
fn against_differences(
    name: &str,
    sys: &System,
    rng: &mut Rng,
    states: usize,
) -> Option<DerivativeForm> {
    let f = with_derivatives(sys, name);
    // Both forms counted, the cheaper kept.
    let counts: Vec<usize> = f
        .derivative_candidates
        .iter()
        .map(|(_, c)| c.total())
        .collect();
    assert!(counts.len() >= 2, "{name}: every form counted");
    let kept = f
        .program(Function::ForwardDynamicsDerivatives)
        .map(|p| p.op_count().total());
    assert_eq!(
        kept,
        counts.iter().min().copied(),
        "{name}: the cheaper kept"
    );
    let p = f
        .program(Function::ForwardDynamicsDerivatives)
        .expect("derivatives generated");
    program_against_differences(name, sys, p, rng, states);
    f.derivative_form
}

/// Checks one program of the derivatives of `sys` against central
/// differences of the `f64` forward dynamics (as [`against_differences`]).
fn program_against_differences(
    name: &str,
    sys: &System,
    p: &eom_gen::sym::Program,
    rng: &mut Rng,
    states: usize,
) {
    let num = Numeric::new(sys).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (nu, ni) = (sys.nu(), sys.inputs.len());
    for _ in 0..states {
        let (q, u) = random_state(sys, rng);
        let tau = rng.vec(nu, 1.0);
        let inputs = rng.vec(ni, 1.0);
        let t = rng.uniform().abs();
        let x = Point {
            inputs: &inputs,
            t,
            ..point(sys, &q, &u, &tau)
        };
        let b = program_blocks(p, &x);
        let udot_norm = num
            .forward_dynamics(&q, &u, t, &tau, &inputs)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .iter()
            .fold(0.0f64, |s, x| s.max(x.abs()));
        let fd = |q: &[f64], u: &[f64], tau: &[f64], inputs: &[f64]| {
            num.forward_dynamics(q, u, t, tau, inputs)
                .unwrap_or_else(|e| panic!("{name}: {e}"))
        };
        let h = 1e-5;
        let central = |plus: Vec<f64>, minus: Vec<f64>| -> Vec<f64> {
            plus.iter()
                .zip(&minus)
                .map(|(p, m)| (p - m) / (2.0 * h))
                .collect()
        };
        // Column j of each block by differences.
        let mut want_dq = vec![vec![0.0; nu]; nu];
        let mut want_du = vec![vec![0.0; nu]; nu];
        let mut want_dtau = vec![vec![0.0; nu]; nu];
        let mut want_dinput = vec![vec![0.0; ni]; nu];
        for j in 0..nu {
            let d = tangent(&num, &q, nu, j);
            let c = central(
                fd(&moved(sys, &q, &d, h), &u, &tau, &inputs),
                fd(&moved(sys, &q, &d, -h), &u, &tau, &inputs),
            );
            (0..nu).for_each(|i| want_dq[i][j] = c[i]);
            let shift = |v: &[f64], s: f64| {
                let mut v = v.to_vec();
                v[j] += s;
                v
            };
            let c = central(
                fd(&q, &shift(&u, h), &tau, &inputs),
                fd(&q, &shift(&u, -h), &tau, &inputs),
            );
            (0..nu).for_each(|i| want_du[i][j] = c[i]);
            let c = central(
                fd(&q, &u, &shift(&tau, h), &inputs),
                fd(&q, &u, &shift(&tau, -h), &inputs),
            );
            (0..nu).for_each(|i| want_dtau[i][j] = c[i]);
        }
        for j in 0..ni {
            let shift = |s: f64| {
                let mut v = inputs.clone();
                v[j] += s;
                v
            };
            let c = central(fd(&q, &u, &tau, &shift(h)), fd(&q, &u, &tau, &shift(-h)));
            (0..nu).for_each(|i| want_dinput[i][j] = c[i]);
        }
        for (block, got, want) in [
            ("∂u̇/∂q", &b.dq, &want_dq),
            ("∂u̇/∂u", &b.du, &want_du),
            ("∂u̇/∂τ", &b.dtau, &want_dtau),
            ("∂u̇/∂inputs", &b.dinput, &want_dinput),
        ] {
            let scale = want.iter().flatten().fold(1.0f64, |s, x| s.max(x.abs()));
            let rounding = 100.0 * f64::EPSILON * udot_norm / h;
            for i in 0..nu {
                for (j, (g, w)) in got[i].iter().zip(&want[i]).enumerate() {
                    assert!(
                        (g - w).abs() <= 1e-6 * scale + rounding,
                        "{name} {block}[{i}][{j}] at q = {q:?}, u = {u:?}: generated {g}, central differences {w} (scale {scale})"
                    );
                }
            }
        }
    }
}

/// Every bundled rigid model (closed loops as their spanning trees: the
/// function is the tree's forward dynamics), including quaternion joints
/// (`heavy_top`, `free_body`, `stewart`), at random states.
#[test]
fn derivatives_equal_central_differences_for_every_rigid_model() {
    let names = bundled_models(false);
    assert!(
        names.len() >= 10,
        "expected the bundled rigid models, got {names:?}"
    );
    let mut rng = Rng(0xD1FF_5EED_0000_0027);
    let mut forms = Vec::new();
    for name in &names {
        forms.push(against_differences(name, &system(name), &mut rng, 3));
    }
    // Both forms are checked: some models keep each.
    for form in [
        DerivativeForm::ForwardDynamics,
        DerivativeForm::InverseDynamics,
    ] {
        assert!(
            forms.contains(&Some(form)),
            "no model keeps {form}: {forms:?}"
        );
    }
}

/// Every bundled model with flexible bodies (floating frame: elastic
/// coordinates with `q̇ = u`, bodies at nodes, stiffening), at random
/// states; elastic coordinates are modal amplitudes of up to 0.8 here,
/// large but the functions are smooth there all the same.
#[test]
fn derivatives_equal_central_differences_for_every_flexible_model() {
    let names = bundled_models(true);
    assert!(
        names.len() >= 4,
        "expected the bundled flexible models, got {names:?}"
    );
    let mut rng = Rng(0xF1E7_5EED_0000_0027);
    for name in &names {
        against_differences(name, &system(name), &mut rng, 2);
    }
}

/// The blocks of one program, flat (`dq`, `du`, `dtau`, `dinput`).
fn flat(p: &eom_gen::sym::Program, x: &Point<'_>) -> Vec<f64> {
    run(p, x)
}

/// Every form of the derivatives (kept and not) gives the same numbers,
/// the same mathematical object built three ways: differentiated forward
/// dynamics, differentiated Newton–Euler, and Newton–Euler's derivatives
/// by recursion over the tree; all to 1e-9 of the largest entry. The
/// recursion applies to every rigid tree of joints with subspaces
/// constant in body axes (quaternion joints included: `heavy_top`,
/// `free_body`) and is no candidate for trees with flexible bodies (nor
/// universal or planar joints: `stewart`, not run here for time).
#[test]
fn recursive_derivatives_equal_the_other_forms() {
    // The models of BENCHMARKS.md's table that run in seconds in a debug
    // build, quaternion joints (heavy_top, free_body), a prismatic joint
    // and springs (slider_crank), a flexible body (hub_beam).
    let names = [
        "pendulum",
        "double_pendulum",
        "heavy_top",
        "free_body",
        "slider_crank",
        "andrews",
        "arm7",
        "hub_beam",
    ];
    let mut rng = Rng(0x5EC0_5EED_0000_0036);
    let mut applied = Vec::new();
    for name in names {
        check_forms_agree(name, &system(name), &mut rng, 2, &mut applied);
    }
    check_forms_agree(
        "arm7 with actuators",
        &arm7_with_actuators(),
        &mut rng,
        2,
        &mut applied,
    );
    for must in [
        "pendulum",
        "double_pendulum",
        "heavy_top",
        "free_body",
        "andrews",
        "arm7",
        "arm7 with actuators",
    ] {
        assert!(
            applied.iter().any(|n| n == must),
            "the recursion should apply to {must}: applied to {applied:?}"
        );
    }
    assert!(
        !applied.iter().any(|n| n == "hub_beam"),
        "the recursion cannot cover hub_beam's flexible body"
    );
}

fn check_forms_agree(
    name: &str,
    sys: &System,
    rng: &mut Rng,
    states: usize,
    applied: &mut Vec<String>,
) {
    let f = with_derivatives(sys, name);
    let forms: Vec<DerivativeForm> = f.derivative_candidates.iter().map(|(d, _)| *d).collect();
    if !forms.contains(&DerivativeForm::Recursive) {
        return;
    }
    applied.push(name.to_string());
    let counts: Vec<String> = f
        .derivative_candidates
        .iter()
        .map(|(d, c)| format!("{d}: {}", c.total()))
        .collect();
    println!("{name}: {}", counts.join(", "));
    let kept = f
        .program(Function::ForwardDynamicsDerivatives)
        .expect("derivatives generated");
    let (nu, ni) = (sys.nu(), sys.inputs.len());
    for _ in 0..states {
        let (q, u) = random_state(sys, rng);
        let tau = rng.vec(nu, 1.0);
        let inputs = rng.vec(ni, 1.0);
        let x = Point {
            inputs: &inputs,
            t: rng.uniform().abs(),
            ..point(sys, &q, &u, &tau)
        };
        let want = flat(kept, &x);
        let blocks = [
            ("∂u̇/∂q", 0, nu * nu),
            ("∂u̇/∂u", nu * nu, 2 * nu * nu),
            ("∂u̇/∂τ", 2 * nu * nu, 3 * nu * nu),
            ("∂u̇/∂inputs", 3 * nu * nu, want.len()),
        ];
        for (form, p) in &f.derivative_alternatives {
            let got = flat(p, &x);
            assert_eq!(got.len(), want.len(), "{name} {form}: result length");
            for (block, a, b) in blocks {
                let scale = want[a..b].iter().fold(1.0f64, |s, x| s.max(x.abs()));
                for k in a..b {
                    assert!(
                        (got[k] - want[k]).abs() <= 1e-9 * scale,
                        "{name} {block} entry {k} at q = {q:?}, u = {u:?}: {form} gives {}, {} (kept) {}",
                        got[k],
                        f.derivative_form.map_or(String::new(), |d| d.to_string()),
                        want[k]
                    );
                }
            }
        }
    }
}

/// The recursion in body axes, with its pairs in common axes and along the
/// tree's paths, gives the numbers of the recursion in world axes (to 1e-9
/// of each block's largest entry) and of central differences of the `f64`
/// forward dynamics, at random states: arm7 (a
/// chain of revolute joints about various axes), heavy_top and free_body
/// (a spherical and a free joint, quaternion coordinates), slider_crank
/// (a prismatic joint, springs; as its spanning tree), whipple (a branched
/// tree: the rear frame carries the rear wheel and the front frame, which
/// carries the front wheel) and bricard (the spanning tree of a loop).
#[test]
fn body_axis_recursion_equals_world_axis_and_differences() {
    let mut rng = Rng(0xB0D1_5EED_0000_0027);
    for name in [
        "arm7",
        "heavy_top",
        "free_body",
        "slider_crank",
        "whipple",
        "bricard",
    ] {
        let sys = system(name);
        let f = with_derivatives(&sys, name);
        let form = |d: DerivativeForm| {
            if f.derivative_form == Some(d) {
                f.program(Function::ForwardDynamicsDerivatives)
            } else {
                f.derivative_alternatives
                    .iter()
                    .find(|(a, _)| *a == d)
                    .map(|(_, p)| p)
            }
            .unwrap_or_else(|| panic!("{name}: no {d} form"))
        };
        let world = form(DerivativeForm::Recursive);
        let body_forms = [
            ("body axes", form(DerivativeForm::RecursiveBodyAxes)),
            (
                "pairs along the paths",
                form(DerivativeForm::RecursivePaths),
            ),
        ];
        let (nu, ni) = (sys.nu(), sys.inputs.len());
        for _ in 0..2 {
            let (q, u) = random_state(&sys, &mut rng);
            let tau = rng.vec(nu, 1.0);
            let inputs = rng.vec(ni, 1.0);
            let x = Point {
                inputs: &inputs,
                t: rng.uniform().abs(),
                ..point(&sys, &q, &u, &tau)
            };
            let want = program_blocks(world, &x);
            for (label, body) in body_forms {
                let got = program_blocks(body, &x);
                for (block, w, g) in [
                    ("∂u̇/∂q", &want.dq, &got.dq),
                    ("∂u̇/∂u", &want.du, &got.du),
                    ("∂u̇/∂τ", &want.dtau, &got.dtau),
                    ("∂u̇/∂inputs", &want.dinput, &got.dinput),
                ] {
                    let scale = w.iter().flatten().fold(1.0f64, |s, x| s.max(x.abs()));
                    for (i, (wr, gr)) in w.iter().zip(g).enumerate() {
                        for (j, (a, b)) in wr.iter().zip(gr).enumerate() {
                            assert!(
                                (a - b).abs() <= 1e-9 * scale,
                                "{name} {block}[{i}][{j}] at q = {q:?}, u = {u:?}: {label} {b}, world axes {a}"
                            );
                        }
                    }
                }
            }
        }
        for (_, body) in body_forms {
            program_against_differences(name, &sys, body, &mut rng, 2);
        }
    }
}

/// `∂u̇/∂(inputs)`: arm7 with actuators at two joints and a joint spring;
/// the inputs enter as generalised forces of their joints.
#[test]
fn input_derivatives_equal_central_differences() {
    let sys = arm7_with_actuators();
    assert_eq!(sys.inputs.len(), 2, "two actuator inputs");
    let mut rng = Rng(0x1234_0027);
    against_differences("arm7 with actuators", &sys, &mut rng, 3);
}

/// arm7 with actuators at joints 4 and 6 (inputs `m4`, `m6`) and a joint
/// spring-damper at joint 2.
fn arm7_with_actuators() -> System {
    let path = format!("{}/arm7.ron", models_dir());
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let from = "outputs: [Energy],";
    assert!(text.contains(from), "test setup: `{from}` not in arm7");
    let text = text.replacen(
        from,
        "forces: [JointSpringDamper(name: \"s2\", joint: \"j2\", stiffness: 20, damping: 0.5, rest: 3), Actuator(name: \"m4\", joint: \"j4\"), Actuator(name: \"m6\", joint: \"j6\")], outputs: [Energy],",
        1,
    );
    check(&Source::new("arm7_inputs", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

/// Generated only when asked: a model formulated with its default request
/// (every model without a scene) has no derivative program, so the
/// committed generated code stays as it was.
#[test]
fn derivatives_are_generated_only_when_asked() {
    let sys = system("arm7");
    let f = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
    assert!(f.program(Function::ForwardDynamicsDerivatives).is_none());
    let f = with_derivatives(&sys, "arm7");
    let p = f
        .program(Function::ForwardDynamicsDerivatives)
        .expect("asked for");
    assert_eq!(p.outputs.len(), 3 * 7 * 7, "three 7 × 7 blocks, no inputs");
}

/// RADAU5 uses the generated Jacobian `[[0, I], [∂u̇/∂q, ∂u̇/∂u]]` when
/// the formulation has the derivatives (`eom_sim`'s unconstrained system
/// asks the model for `forward_dynamics_derivatives`), and forward
/// differences of the right-hand side otherwise. On a stiff double
/// pendulum (an overdamped elbow spring, `k = 10⁵ N·m/rad`,
/// `c = 10⁴ N·m·s`: modes near `−10/s` and `−10⁴/s`) the generated one
/// needs fewer right-hand sides (none for the Jacobian) and ends at the
/// same state within the tolerance. The steps are not identical: the
/// Jacobian also enters RADAU5's error estimate (`(I − hγ₀J)⁻¹` filters
/// it), so the differenced Jacobian's `√ε` error moves a step now and then;
/// the counts agree within one step in a hundred.
#[test]
fn radau5_with_the_generated_jacobian_needs_fewer_rhs_for_the_same_run() {
    let path = format!("{}/double_pendulum.ron", models_dir());
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let from = "outputs: [";
    assert!(text.contains(from), "test setup");
    let text = text.replacen(
        from,
        "forces: [JointSpringDamper(name: \"s\", joint: \"elbow\", stiffness: 1e5, damping: 1e4, rest: 0)],\n    outputs: [",
        1,
    );
    let sys = check(&Source::new("stiff_double_pendulum", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let options = eom_sim::RunOptions {
        integrator: "radau5".parse().expect("a known integrator"),
        rtol: 1e-8,
        atol: 1e-8,
        dt: 1e-4,
        t_end: 1.0,
        ..Default::default()
    };
    let run = |request: FunctionSet| {
        let f = formulate(&sys, request).expect("formulates");
        eom_gen::interpret::simulate(&f, &sys, &options).unwrap_or_else(|e| panic!("{e}"))
    };
    let fd = run(FunctionSet::all_requested());
    let generated = run(FunctionSet::all_requested().with(Function::ForwardDynamicsDerivatives));
    let (a, b) = (&fd.stats, &generated.stats);
    eprintln!("finite differences: {a:?}\ngenerated: {b:?}");
    let near = |x: usize, y: usize| x.abs_diff(y) <= 1 + x / 100;
    assert!(
        near(a.accepted, b.accepted) && near(a.rejected, b.rejected),
        "steps: differences {}+{} rejected, generated {}+{}",
        a.accepted,
        a.rejected,
        b.accepted,
        b.rejected
    );
    // The differenced Jacobian costs N = 4 right-hand sides each.
    assert!(
        b.rhs_evals < a.rhs_evals && a.rhs_evals - b.rhs_evals >= 3 * a.jacobian_evals,
        "fewer right-hand sides: generated {}, differences {} ({} Jacobians)",
        b.rhs_evals,
        a.rhs_evals,
        a.jacobian_evals
    );
    for (x, y) in
        fd.q.iter()
            .chain(&fd.u)
            .zip(generated.q.iter().chain(&generated.u))
    {
        assert!(
            (x - y).abs() <= 10.0 * options.rtol * (1.0 + x.abs()),
            "end states: differences {x}, generated {y}"
        );
    }
}

/// The library's run refuses `Jacobian::Generated` where there is none (a
/// formulation without the derivatives, an explicit integrator) with the
/// reason, and reports which Jacobian it used.
#[test]
fn a_generated_jacobian_the_run_cannot_have_is_refused() {
    let sys = system("double_pendulum");
    let radau5 = eom_sim::RunOptions {
        integrator: "radau5".parse().expect("a known integrator"),
        t_end: 0.01,
        jacobian: eom_sim::Jacobian::Generated,
        ..Default::default()
    };
    let without = formulate(&sys, FunctionSet::all_requested()).expect("formulates");
    match eom_gen::interpret::simulate(&without, &sys, &radau5) {
        Err(eom_gen::interpret::InterpretError::Run(eom_sim::RunError::Options(p))) => {
            assert!(p[0].contains("forward_dynamics_derivatives"), "{p:?}")
        }
        other => panic!("no derivatives, yet {other:?}"),
    }
    let dopri5 = eom_sim::RunOptions {
        integrator: eom_sim::Integrator::Dopri5,
        ..radau5.clone()
    };
    assert!(matches!(
        eom_gen::interpret::simulate(&without, &sys, &dopri5),
        Err(eom_gen::interpret::InterpretError::Run(
            eom_sim::RunError::Options(_)
        ))
    ));
    let with = with_derivatives(&sys, "double_pendulum");
    let r = eom_gen::interpret::simulate(&with, &sys, &radau5).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.stats.jacobian, Some(eom_sim::Jacobian::Generated));
    let auto = eom_sim::RunOptions {
        jacobian: eom_sim::Jacobian::Auto,
        ..radau5
    };
    let r = eom_gen::interpret::simulate(&without, &sys, &auto).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.stats.jacobian, Some(eom_sim::Jacobian::Differences));
}

/// `inverse_dynamics_derivatives` of `sys` against central differences of
/// the `f64` inverse dynamics (Newton–Euler run on numbers), coordinates
/// moved along `N(q) e_j` as above, and `∂τ/∂u̇` against the `f64` mass
/// matrix (CRBA), at random states.
fn inverse_against_differences(name: &str, sys: &System, rng: &mut Rng, states: usize) {
    let f = formulate(
        sys,
        FunctionSet::default().with(Function::InverseDynamicsDerivatives),
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"));
    let num = Numeric::new(sys).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (nu, ni) = (sys.nu(), sys.inputs.len());
    for _ in 0..states {
        let (q, u) = random_state(sys, rng);
        let ud = rng.vec(nu, 1.0);
        let inputs = rng.vec(ni, 1.0);
        let t = rng.uniform().abs();
        let x = Point {
            udot: &ud,
            inputs: &inputs,
            t,
            ..point(sys, &q, &u, &[])
        };
        let flat = run(
            f.program(Function::InverseDynamicsDerivatives)
                .expect("asked for"),
            &x,
        );
        assert_eq!(flat.len(), 3 * nu * nu + nu * ni, "{name}: length");
        let id = |q: &[f64], u: &[f64], ud: &[f64], inputs: &[f64]| {
            num.inverse_dynamics(q, u, ud, t, inputs)
                .unwrap_or_else(|e| panic!("{name}: {e}"))
        };
        let tau_norm = id(&q, &u, &ud, &inputs)
            .iter()
            .fold(0.0f64, |s, x| s.max(x.abs()));
        let h = 1e-5;
        let rounding = 100.0 * f64::EPSILON * tau_norm / h;
        let mass = num
            .terms(&q, &u, t, &inputs)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .mass_matrix;
        let central = |p: Vec<f64>, m: Vec<f64>| -> Vec<f64> {
            p.iter().zip(&m).map(|(p, m)| (p - m) / (2.0 * h)).collect()
        };
        let shift = |v: &[f64], j: usize, s: f64| {
            let mut v = v.to_vec();
            v[j] += s;
            v
        };
        let check = |block: &str, i: usize, j: usize, got: f64, want: f64, scale: f64| {
            assert!(
                (got - want).abs() <= 1e-6 * scale + rounding,
                "{name} {block}[{i}][{j}]: generated {got}, reference {want}"
            );
        };
        for j in 0..nu {
            let d = tangent(&num, &q, nu, j);
            let columns = [
                (
                    "∂τ/∂q",
                    0,
                    central(
                        id(&moved(sys, &q, &d, h), &u, &ud, &inputs),
                        id(&moved(sys, &q, &d, -h), &u, &ud, &inputs),
                    ),
                ),
                (
                    "∂τ/∂u",
                    1,
                    central(
                        id(&q, &shift(&u, j, h), &ud, &inputs),
                        id(&q, &shift(&u, j, -h), &ud, &inputs),
                    ),
                ),
                (
                    "∂τ/∂u̇",
                    2,
                    central(
                        id(&q, &u, &shift(&ud, j, h), &inputs),
                        id(&q, &u, &shift(&ud, j, -h), &inputs),
                    ),
                ),
            ];
            for (block, k, want) in columns {
                let scale = want.iter().fold(1.0f64, |s, x| s.max(x.abs()));
                for (i, w) in want.iter().enumerate() {
                    check(block, i, j, flat[k * nu * nu + i * nu + j], *w, scale);
                }
            }
            // ∂τ/∂u̇ is the mass matrix.
            for (i, row) in mass.iter().enumerate() {
                let m = row[j];
                assert!(
                    (flat[2 * nu * nu + i * nu + j] - m).abs() <= 1e-10 * (1.0 + m.abs()),
                    "{name} ∂τ/∂u̇[{i}][{j}] against M"
                );
            }
        }
        for j in 0..ni {
            let want = central(
                id(&q, &u, &ud, &shift(&inputs, j, h)),
                id(&q, &u, &ud, &shift(&inputs, j, -h)),
            );
            for (i, w) in want.iter().enumerate() {
                check("∂τ/∂inputs", i, j, flat[3 * nu * nu + i * ni + j], *w, 1.0);
            }
        }
    }
}

/// Every bundled model without cables, and arm7 with actuators.
#[test]
fn inverse_dynamics_derivatives_equal_central_differences() {
    let mut rng = Rng(0x1D_DE21_0027);
    for name in bundled_models(false).iter().chain(&bundled_models(true)) {
        inverse_against_differences(name, &system(name), &mut rng, 2);
    }
    inverse_against_differences("arm7 with actuators", &arm7_with_actuators(), &mut rng, 2);
}

/// The index-3 DAE's generated Jacobian (RADAU5 with `--constraints
/// index3`: `D_q(τ) + M⁻¹ ∂(Jᵀλ)/∂q`, `D_u(τ)` and `M⁻¹Jᵀ` from the
/// generated derivatives at `τ = Jᵀλ`, `J` for the constraint rows) against
/// central differences of the DAE's right-hand side, on Andrews' squeezing
/// mechanism (7 coordinates, 6 loop equations, stiff spring) at its
/// assembled initial state with consistent multipliers and at a state moved
/// off it (the Jacobian is of the right-hand side everywhere, not only on
/// the manifold).
#[test]
fn index3_generated_jacobian_is_the_differenced_one() {
    use eom_sim::{Index3System, OdeSystem, Simulate};
    const N: usize = 20;
    let sys = system("andrews");
    let f = with_derivatives(&sys, "andrews");
    let model = eom_gen::interpret::Interpreted::new(&f, &sys);
    assert!(Index3System::has_generated_jacobian(&model));
    let len = model
        .function_len("forward_dynamics_derivatives")
        .expect("asked for");
    let derivatives = |t: f64, q: &[f64], u: &[f64], tau: &[f64], out: &mut [f64]| {
        let at = eom_sim::Point {
            t,
            q,
            u,
            tau,
            ..Default::default()
        };
        let mut all = vec![0.0; len];
        let ok = model.evaluate("forward_dynamics_derivatives", &at, &mut all);
        out.iter_mut().zip(&all).for_each(|(d, s)| *d = *s);
        ok
    };
    let dae = Index3System::new(&model).with_derivatives(&derivatives);
    let (q0, u0) = model.initial_state();
    let a = eom_sim::constrained::assemble(&model, &q0, &u0, 0.0);
    let y0: [f64; N] = dae.initial(0.0, &a.q, &a.u).expect("consistent start");
    let mut rng = Rng(0x1DE3_0027);
    let mut off = y0;
    for (i, y) in off.iter_mut().enumerate() {
        *y += 1e-2 * rng.uniform() * if i >= 14 { y.abs().max(1.0) } else { 1.0 };
    }
    for (what, y) in [("assembled", y0), ("off the manifold", off)] {
        let mut jac = eom_sim::SMatrix::<f64, N, N>::zeros();
        assert!(OdeSystem::<N>::jacobian(&dae, 0.0, &y, &mut jac), "{what}");
        let (mut fp, mut fm) = ([0.0; N], [0.0; N]);
        let mut worst = 0.0f64;
        for j in 0..N {
            let h = 1e-6 * y[j].abs().max(1.0);
            let (mut yp, mut ym) = (y, y);
            yp[j] += h;
            ym[j] -= h;
            dae.rhs(0.0, &yp, &mut fp);
            dae.rhs(0.0, &ym, &mut fm);
            for i in 0..N {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                let err = (jac[(i, j)] - fd).abs() / (1.0 + fd.abs());
                worst = worst.max(err);
                assert!(
                    err < 1e-5,
                    "{what}: ∂f_{i}/∂y_{j}: generated {}, differences {fd}",
                    jac[(i, j)]
                );
            }
        }
        eprintln!("{what}: largest relative difference {worst:.1e}");
    }
}

/// The breakdown of the derivatives by part (`fd_passes --derivatives`):
/// its first part is forward dynamics by articulated bodies, as many
/// operations as the generated `forward_dynamics` where that is the form
/// kept (arm7), and `M⁻¹` and the recursion's gradients each add some.
#[test]
fn derivative_parts_start_from_forward_dynamics() {
    let sys = system("arm7");
    let parts = eom_gen::mech::passes::derivative_part_counts(&sys)
        .expect("formulates")
        .expect("a rigid tree the recursion covers");
    let f = formulate(&sys, FunctionSet::default()).expect("formulates");
    assert_eq!(f.fd_form, eom_gen::mech::FdForm::Aba);
    let fd = f
        .program(Function::ForwardDynamics)
        .expect("forward dynamics")
        .op_count()
        .total();
    assert_eq!(parts.len(), 3);
    assert_eq!(parts[0].1.total(), fd, "{}", parts[0].0);
    assert!(
        parts[1].1.total() > 0 && parts[2].1.total() > 0,
        "{parts:?}"
    );
}
