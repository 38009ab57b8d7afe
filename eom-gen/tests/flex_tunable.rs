//! Tunable section data of flexible bodies (issue #17): `ρA`, `ρI_p`,
//! `EA`, `EI_y`, `EI_z`, `GJ` as runtime parameters.
//!
//! The physics checked: for a fixed basis every reduced matrix of the
//! floating-frame body is linear in the section data, so the model with
//! tunable data at runtime values `p` is exactly the model generated with
//! `p` fixed. For assumed modes the coordinates are the same (the written
//! shapes); for the beam the normal modes of each decoupled deformation
//! (axial, two bending planes, torsion) have shapes independent of the
//! scale of that block's stiffness and mass, so the beam generated at `p`
//! has the same shapes, normalised to its own mass: `q_f` differs per mode
//! by `√(m/m₀)` of its block (`ρA` or `ρI_p`), and `M`, `b` and the
//! accelerations transform with that scaling. Also: the frequency scales as
//! `√(EI/ρA)`, energy is conserved at changed values, and the fields that
//! cannot be tunable are refused at their place in the file.

use eom_gen::System;
use eom_gen::flex::{Basis, Deformation};
use eom_gen::functions::{Function, FunctionSet};
use eom_gen::mech::{Numeric, NumericEnv, formulate};
use eom_gen::model::{Source, check};
use eom_sim::{Dop853, OdeSystem, SolveOptions, integrate};
use nalgebra::DMatrix;

/// Section data in the order `ρA`, `ρI_p`, `EA`, `EI_y`, `EI_z`, `GJ`.
type Data = [f64; 6];

const NAMES: [&str; 6] = ["rho_a", "rho_ip", "ea", "ei_y", "ei_z", "gj"];

/// The defaults: L = 2 m; the six kept clamped modes are bending x–y and
/// x–z (12.4, 14.3 rad/s), torsion (17.5, 52.6), axial (64) and the second
/// x–y bending mode (78); the next (torsion 88, bending x–z 90) are left out.
const DEFAULTS: Data = [1.5, 0.002, 1.0e4, 400.0, 300.0, 1.0];

/// Runtime values: every datum changed, each block's frequency by 2–4 %,
/// so the same six modes are the lowest (checked in `kept_blocks`).
const RUNTIME: Data = [1.95, 0.0025, 1.2e4, 540.0, 375.0, 1.3];

/// A hub turning about z carrying, through a revolute about y at 0.3 m,
/// a flexible body (`flexible` is its text; section data by the
/// parameters named in `NAMES`), with gravity. `tunable`: the section
/// parameters are runtime fields; `data` their values (defaults).
fn model(flexible: &str, data: &Data, tunable: bool, zeta: f64) -> String {
    let params: Vec<String> = NAMES
        .iter()
        .zip(data)
        .map(|(n, v)| format!("(name: \"{n}\", value: {v:e}, tunable: {tunable})"))
        .collect();
    format!(
        r#"Model(
    name: "hub_beam",
    gravity: (0, 0, -9.81),
    parameters: [{params}, (name: "zeta", value: {zeta}, tunable: {tunable})],
    bodies: [
        (name: "hub", mass: 2.0, inertia: Diag(0.25, 0.25, 0.5)),
        (name: "beam", flexible: {flexible}),
    ],
    joints: [
        (name: "hub_j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "hub"),
        (name: "beam_j", kind: Revolute(axis: (0, 1, 0)), parent: "hub", child: "beam",
         parent_frame: (position: (0.3, 0, 0))),
    ],
)"#,
        params = params.join(", "),
    )
}

const SECTION: &str = "rho_a: \"rho_a\", rho_ip: \"rho_ip\", ea: \"ea\", ei_y: \"ei_y\", \
                       ei_z: \"ei_z\", gj: \"gj\"";

/// The built-in beam: six elements, six clamped modes, stiffening.
fn beam() -> String {
    format!(
        "Beam(length: 2.0, {SECTION}, elements: 6, reference: Clamped, modes: 6, \
         stiffening: true, damping: \"zeta\")"
    )
}

/// Assumed modes clamped at x = 0: two bending shapes per plane, one
/// axial, one torsion.
fn assumed() -> String {
    format!(
        "AssumedModes(length: 2.0, {SECTION}, stiffening: true, shapes: [\
         (v: \"(x/2)^2\"), (v: \"(x/2)^3\"), (w: \"(x/2)^2\"), (w: \"(x/2)^3 - (x/2)^2\"), \
         (u: \"x/2\"), (phi: \"x/2\")])"
    )
}

fn system(text: String) -> System {
    check(&Source::new("hub_beam.ron", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

/// The tunable system at the runtime values.
fn at_runtime(sys: &System, data: &Data) -> Numeric {
    let values: Vec<(&str, f64)> = NAMES.iter().copied().zip(data.iter().copied()).collect();
    Numeric::with_env(sys, NumericEnv::with(sys, &values)).unwrap_or_else(|e| panic!("{e}"))
}

/// A reproducible pseudo-random number in `[-1, 1)`.
fn rand(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// The deformation of each kept mode of the beam of `sys` (body 2).
fn kept_blocks(sys: &System) -> Vec<Deformation> {
    let flex = sys.bodies[2].flexible.as_deref().expect("flexible");
    (0..flex.count())
        .map(|j| {
            flex.beam
                .classify(&flex.modes.shapes.column(j).into_owned())
        })
        .collect()
}

/// `q_f(fixed) = s q_f(tunable)` per coordinate: 1 for the joints, `±√(m/m₀)`
/// of each mode's block for the elastic coordinates, the sign that of the
/// fixed model's shape against the tunable one's (the convention "largest
/// entry positive" may pick either sign where two entries tie).
/// With Craig–Bampton, the constraint modes (unit boundary motions, not
/// mass-normalised) keep their scale: 1.
fn scaling(tun: &System, fix: &System, runtime: &Data) -> Vec<f64> {
    let (ft, ff) = (
        tun.bodies[2].flexible.as_deref().unwrap(),
        fix.bodies[2].flexible.as_deref().unwrap(),
    );
    let static_modes = match &ft.modes.basis {
        Basis::CraigBampton {
            constraint_modes, ..
        } => *constraint_modes,
        Basis::Normal => 0,
    };
    let mut s = vec![1.0, 1.0];
    for (j, d) in kept_blocks(tun).into_iter().enumerate() {
        let m = if d == Deformation::Torsion { 1 } else { 0 };
        let sign = ft
            .modes
            .shapes
            .column(j)
            .dot(&ff.modes.shapes.column(j))
            .signum();
        let size = if j < static_modes {
            1.0
        } else {
            (runtime[m] / DEFAULTS[m]).sqrt()
        };
        s.push(sign * size);
    }
    s
}

fn assert_close(what: &str, got: &[f64], want: &[f64], rel: f64) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    let scale = want.iter().map(|x| x.abs()).fold(0.0, f64::max);
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= rel * scale,
            "{what}[{k}]: got {g}, want {w} (difference {:e} of {scale:e})",
            (g - w).abs()
        );
    }
}

/// The beam with tunable section data at runtime values is the beam
/// generated with those values fixed, in coordinates scaled per mode by
/// `s = √(m/m₀)`: with `T = diag(s)`, `M_tun(q) = T M_fix(Tq) T`,
/// `b_tun(q, u) = T b_fix(Tq, Tu)` and `u̇_tun = T⁻¹ u̇_fix(Tq, Tu, T⁻¹τ)`,
/// at random deformed states (gravity, stiffening, modal damping with a
/// tunable ratio). The fixed model's shapes are the tunable one's divided
/// by `s` (the shapes do not depend on the scale of a block's data).
#[test]
fn flex_tunable_beam_equals_the_beam_generated_at_those_values() {
    tunable_equals_fixed(&beam(), 0.02);
}

/// Craig–Bampton alike (undamped): the constraint modes are unit boundary
/// motions with interior shapes `−K_ii⁻¹ K_ib` of their own deformation,
/// independent of the data's scale; the fixed-interface modes scale as
/// normal modes. And the outputs (section forces, strain energy) follow
/// the runtime stiffness.
#[test]
fn flex_tunable_craig_bampton_and_outputs_equal_those_generated_at_those_values() {
    let cb = beam().replace(
        "modes: 6,",
        "modes: 3, nodes: [(name: \"tip\", x: 2.0)], craig_bampton: true,",
    );
    tunable_equals_fixed(&cb, 0.0);
    let with_outputs = |text: String| {
        text.replace(
            "    joints: [",
            "    outputs: [SectionForces(name: \"a\", body: \"beam\", x: 0.5), \
             SectionForces(name: \"b\", body: \"beam\", x: 1.25), \
             ElasticEnergy(body: \"beam\")],\n    joints: [",
        )
    };
    let tun = system(with_outputs(model(&beam(), &DEFAULTS, true, 0.0)));
    let fix = system(with_outputs(model(&beam(), &RUNTIME, false, 0.0)));
    let s = scaling(&tun, &fix, &RUNTIME);
    let runtime: Vec<(String, f64)> = NAMES
        .iter()
        .zip(RUNTIME)
        .map(|(n, v)| (n.to_string(), v))
        .collect();
    let run = |sys: &System, q: &[f64], params: &[(String, f64)]| {
        let f = formulate(sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
        let zero = vec![0.0; 8];
        let point = eom_gen::interpret::Point {
            sys,
            q,
            u: &zero,
            udot: &zero,
            tau: &zero,
            inputs: &[],
            params,
            multipliers: &[],
            t: 0.0,
        };
        eom_gen::interpret::run(f.program(Function::Outputs).expect("outputs"), &point)
    };
    let mut seed = 31;
    let q: Vec<f64> = (0..8).map(|_| 0.01 * rand(&mut seed)).collect();
    let tq: Vec<f64> = q.iter().zip(&s).map(|(x, s)| x * s).collect();
    let (a, b) = (run(&tun, &q, &runtime), run(&fix, &tq, &[]));
    assert_eq!(a.len(), 13, "two sections of six and the strain energy");
    assert_close("outputs", &a, &b, 1e-10);
    // And they differ from the defaults' (the stiffness is read at run time).
    let d = run(&tun, &q, &[]);
    assert!(
        (d[5] - a[5]).abs() > 1e-3 * a[5].abs(),
        "M_z at a: defaults {}, runtime {}",
        d[5],
        a[5]
    );
}

/// The model of `flexible` with tunable section data at [`RUNTIME`] is the
/// model generated with [`RUNTIME`] fixed, in coordinates scaled by
/// [`scaling`]; `zeta` the damping ratio of both.
fn tunable_equals_fixed(flexible: &str, zeta: f64) {
    let tun = system(model(flexible, &DEFAULTS, true, zeta));
    let fix = system(model(flexible, &RUNTIME, false, zeta));
    assert_eq!(
        kept_blocks(&tun),
        kept_blocks(&fix),
        "test setup: kept modes"
    );
    let s = scaling(&tun, &fix, &RUNTIME);
    let (ft, ff) = (
        tun.bodies[2].flexible.as_deref().unwrap(),
        fix.bodies[2].flexible.as_deref().unwrap(),
    );
    let k = ft.count();
    for j in 0..k {
        let a = ft.modes.shapes.column(j) / s[2 + j];
        let b = ff.modes.shapes.column(j);
        let rel = (&a - b).amax() / b.amax();
        assert!(rel < 1e-9, "shape {j}: relative difference {rel:e}");
    }
    let tn = at_runtime(&tun, &RUNTIME);
    let fx = Numeric::new(&fix).unwrap();
    let n = 2 + k;
    let mut seed = 17;
    for _ in 0..5 {
        let q: Vec<f64> = (0..n).map(|_| 0.3 * rand(&mut seed)).collect();
        let u: Vec<f64> = (0..n).map(|_| 2.0 * rand(&mut seed)).collect();
        let tau: Vec<f64> = (0..n).map(|_| rand(&mut seed)).collect();
        let tq: Vec<f64> = q.iter().zip(&s).map(|(x, s)| x * s).collect();
        let tu: Vec<f64> = u.iter().zip(&s).map(|(x, s)| x * s).collect();
        let a = tn.terms(&q, &u, 0.0, &[]).unwrap();
        let b = fx.terms(&tq, &tu, 0.0, &[]).unwrap();
        let m_t: Vec<f64> = a.mass_matrix.iter().flatten().copied().collect();
        let m_f: Vec<f64> = (0..n)
            .flat_map(|r| (0..n).map(move |c| (r, c)))
            .map(|(r, c)| s[r] * b.mass_matrix[r][c] * s[c])
            .collect();
        assert_close("M", &m_t, &m_f, 1e-10);
        let b_f: Vec<f64> = b.bias.iter().zip(&s).map(|(x, s)| x * s).collect();
        assert_close("b", &a.bias, &b_f, 1e-10);
        let tau_f: Vec<f64> = tau.iter().zip(&s).map(|(x, s)| x / s).collect();
        let ud_t = tn.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap();
        let ud_f: Vec<f64> = fx
            .forward_dynamics(&tq, &tu, 0.0, &tau_f, &[])
            .unwrap()
            .iter()
            .zip(&s)
            .map(|(x, s)| x / s)
            .collect();
        assert_close("u̇", &ud_t, &ud_f, 1e-10);
        let (et, ef) = (
            tn.energy(&q, &u, 0.0).unwrap(),
            fx.energy(&tq, &tu, 0.0).unwrap(),
        );
        assert_close("T, V", &[et.0, et.1], &[ef.0, ef.1], 1e-12);
    }
}

/// The generated programs take the section data as runtime parameters
/// (symbols, not constants) and, interpreted at the runtime values, equal
/// the `f64` algorithms there.
#[test]
fn flex_tunable_programs_take_the_data_at_run_time() {
    use eom_gen::sym::SymKind;
    for (what, flexible) in [("beam", beam()), ("assumed modes", assumed())] {
        let zeta = if what == "beam" { 0.02 } else { 0.0 };
        let sys = system(model(&flexible, &DEFAULTS, true, zeta));
        let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
        let mass = f.program(Function::MassMatrix).expect("requested");
        let bias = f.program(Function::Bias).expect("requested");
        let params = |p: &eom_gen::sym::Program| -> Vec<String> {
            p.inputs
                .iter()
                .filter(|s| s.kind == SymKind::Param)
                .map(|s| s.name.clone())
                .collect()
        };
        let (pm, pb) = (params(mass), params(bias));
        for name in ["rho_a", "rho_ip"] {
            assert!(
                pm.iter().any(|p| p == name),
                "{what}: M lacks `{name}`: {pm:?}"
            );
        }
        for name in ["rho_a", "ea", "ei_y", "ei_z", "gj"] {
            assert!(
                pb.iter().any(|p| p == name),
                "{what}: b lacks `{name}`: {pb:?}"
            );
        }
        let num = at_runtime(&sys, &RUNTIME);
        let runtime: Vec<(String, f64)> = NAMES
            .iter()
            .zip(RUNTIME)
            .map(|(n, v)| (n.to_string(), v))
            .collect();
        let n = sys.nu();
        let mut seed = 23;
        for _ in 0..3 {
            let q: Vec<f64> = (0..n).map(|_| 0.3 * rand(&mut seed)).collect();
            let u: Vec<f64> = (0..n).map(|_| 2.0 * rand(&mut seed)).collect();
            let tau: Vec<f64> = (0..n).map(|_| rand(&mut seed)).collect();
            let point = eom_gen::interpret::Point {
                sys: &sys,
                q: &q,
                u: &u,
                udot: &[],
                tau: &tau,
                inputs: &[],
                params: &runtime,
                multipliers: &[],
                t: 0.0,
            };
            let run = |function: Function| {
                eom_gen::interpret::run(f.program(function).expect("requested"), &point)
            };
            let terms = num.terms(&q, &u, 0.0, &[]).unwrap();
            let lower: Vec<f64> = (0..n)
                .flat_map(|i| (0..=i).map(move |j| (i, j)))
                .map(|(i, j)| terms.mass_matrix[i][j])
                .collect();
            assert_close(
                &format!("{what}: M"),
                &run(Function::MassMatrix),
                &lower,
                1e-12,
            );
            assert_close(
                &format!("{what}: b"),
                &run(Function::Bias),
                &terms.bias,
                1e-12,
            );
            assert_close(
                &format!("{what}: u̇"),
                &run(Function::ForwardDynamics),
                &num.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap(),
                1e-11,
            );
            let (t, v) = num.energy(&q, &u, 0.0).unwrap();
            assert_close(
                &format!("{what}: energy"),
                &run(Function::Energy),
                &[t, v],
                1e-12,
            );
        }
    }
}

/// Assumed modes keep their written coordinates: with tunable section data
/// at runtime values they equal the body generated with those values fixed,
/// entry by entry (M, b, u̇ at random deformed states).
#[test]
fn flex_tunable_assumed_modes_equal_those_generated_at_those_values() {
    let tun = at_runtime(&system(model(&assumed(), &DEFAULTS, true, 0.0)), &RUNTIME);
    let fix = Numeric::new(&system(model(&assumed(), &RUNTIME, false, 0.0))).unwrap();
    let n = 8;
    let mut seed = 29;
    for _ in 0..5 {
        let q: Vec<f64> = (0..n).map(|_| 0.3 * rand(&mut seed)).collect();
        let u: Vec<f64> = (0..n).map(|_| 2.0 * rand(&mut seed)).collect();
        let tau: Vec<f64> = (0..n).map(|_| rand(&mut seed)).collect();
        let (a, b) = (
            tun.terms(&q, &u, 0.0, &[]).unwrap(),
            fix.terms(&q, &u, 0.0, &[]).unwrap(),
        );
        let flat = |m: &[Vec<f64>]| m.iter().flatten().copied().collect::<Vec<f64>>();
        assert_close("M", &flat(&a.mass_matrix), &flat(&b.mass_matrix), 1e-12);
        assert_close("b", &a.bias, &b.bias, 1e-12);
        assert_close(
            "u̇",
            &tun.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap(),
            &fix.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap(),
            1e-10,
        );
    }
}

/// `ω₁` of the beam with both joints locked from `M` and `K = ∂b/∂q` at
/// rest (no gravity; `b` is linear in `q_f` at zero speed, so one
/// difference is exact).
fn lowest_frequency(num: &Numeric, n: usize) -> f64 {
    let zero = vec![0.0; n];
    let m = num.terms(&zero, &zero, 0.0, &[]).unwrap().mass_matrix;
    let m = DMatrix::from_fn(n, n, |r, c| m[r][c]);
    let b0 = num.terms(&zero, &zero, 0.0, &[]).unwrap().bias;
    let k = DMatrix::from_fn(n, n, |r, c| {
        let mut q = zero.clone();
        q[c] = 1e-3;
        (num.terms(&q, &zero, 0.0, &[]).unwrap().bias[r] - b0[r]) / 1e-3
    });
    let l = m.cholesky().expect("M positive definite").l();
    let li = l.try_inverse().unwrap();
    let a = &li * k * li.transpose();
    let a = (&a + a.transpose()) * 0.5;
    a.symmetric_eigenvalues()
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

/// Bending frequencies scale as `√(EI/ρA)` at run time: the first mode
/// (bending x–y, `EI_z`) with both `EI` × 0.64 and `ρA` × 1.21 moves by
/// `√(0.64/1.21) = 0.8/1.1`, to round-off (the kept shapes are that
/// block's exact FE modes at any scale; it stays the lowest).
#[test]
fn flex_tunable_frequency_scales_as_the_root_of_ei_over_rho_a() {
    let text = model(&beam(), &DEFAULTS, true, 0.0)
        .replace("gravity: (0, 0, -9.81),", "")
        .replace("child: \"hub\")", "child: \"hub\", locked: true)")
        .replace(
            "parent_frame: (position: (0.3, 0, 0))",
            "parent_frame: (position: (0.3, 0, 0)), locked: true",
        );
    let sys = system(text);
    assert_eq!(sys.nu(), 6, "test setup: only the six elastic speeds");
    let w0 = lowest_frequency(&at_runtime(&sys, &DEFAULTS), 6);
    let mut changed = DEFAULTS;
    changed[0] *= 1.21;
    changed[3] *= 0.64;
    changed[4] *= 0.64;
    let w1 = lowest_frequency(&at_runtime(&sys, &changed), 6);
    let want = 0.8 / 1.1;
    eprintln!("ω₁ = {w0} → {w1}, ratio {} want {want}", w1 / w0);
    assert!(
        (w1 / w0 / want - 1.0).abs() < 1e-10,
        "ω₁ ratio {}, want 0.8/1.1 = {want}",
        w1 / w0
    );
    // And the default is the clamped–free Euler–Bernoulli value (FE error).
    let eb = 1.875_104_068_711_961_f64.powi(2) * (DEFAULTS[4] / DEFAULTS[0]).sqrt() / 4.0;
    assert!(
        (w0 / eb - 1.0).abs() < 1e-5,
        "ω₁ = {w0}, Euler–Bernoulli {eb}"
    );
}

/// `ẏ = (q̇, u̇)` by the articulated-body algorithm.
struct Ode<'a> {
    num: &'a Numeric,
    n: usize,
}

impl<const N: usize> OdeSystem<N> for Ode<'_> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let n = self.n;
        let (q, u) = y.split_at(n);
        let ud = self
            .num
            .forward_dynamics(q, u, t, &vec![0.0; n], &[])
            .unwrap_or_else(|_| vec![f64::NAN; n]);
        dy[..n].copy_from_slice(&self.num.qdot(q, u));
        dy[n..].copy_from_slice(&ud);
    }
}

/// Hub and beam swinging under gravity with every section datum changed at
/// run time and no damping: `T + V` (gravity, strain with the runtime
/// `K_ff`) stays constant to DOP853's tolerance over 2 s.
#[test]
fn flex_tunable_beam_conserves_energy_at_changed_values() {
    let sys = system(model(&beam(), &DEFAULTS, true, 0.0));
    let num = at_runtime(&sys, &RUNTIME);
    let mut y0 = [0.0; 16];
    let q0 = [0.2, 0.4, 0.02, -0.01, 0.005, 0.002, 1e-4, 0.001];
    let u0 = [1.0, -0.5, 0.3, 0.2, -0.1, 0.05, 0.01, 0.02];
    y0[..8].copy_from_slice(&q0);
    y0[8..].copy_from_slice(&u0);
    let energy = |y: &[f64; 16]| {
        let (t, v) = num.energy(&y[..8], &y[8..], 0.0).unwrap();
        (t + v, t.abs() + v.abs())
    };
    let (e0, scale) = energy(&y0);
    let opts = SolveOptions {
        t_eval: (1..=20).map(|k| 0.1 * k as f64).collect(),
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &Ode { num: &num, n: 8 },
        0.0,
        y0,
        2.0,
        &opts,
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 20, "stopped: {:?}", sol.stop);
    let drift = sol
        .y_out
        .iter()
        .map(|y| (energy(y).0 - e0).abs() / scale)
        .fold(0.0, f64::max);
    eprintln!(
        "relative energy drift {drift:e}, {} steps",
        sol.stats.accepted
    );
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    // The strain energy is the runtime one: at q0 it differs from the
    // defaults' (every stiffness changed).
    let at_defaults = at_runtime(&sys, &DEFAULTS).energy(&q0, &u0, 0.0).unwrap().1;
    assert!((num.energy(&q0, &u0, 0.0).unwrap().1 - at_defaults).abs() > 1e-6);
}

/// What cannot be tunable is refused at its field, naming the field, the
/// body and what may be tunable: the length (the mesh), a node's place, a
/// shape expression, any datum of a Timoshenko beam (its element's shapes
/// depend on `EI/κGA`), and a damping ratio on a basis whose normal modes change with the data
/// (assumed modes, Craig–Bampton).
#[test]
fn flex_tunable_fields_that_cannot_follow_are_refused_where_written() {
    let cases = [
        (
            "a tunable length",
            model(&beam(), &DEFAULTS, true, 0.0)
                .replace("length: 2.0", "length: \"L\"")
                .replace(
                    "parameters: [",
                    "parameters: [(name: \"L\", value: 2, tunable: true), ",
                ),
            "length: \"L\"",
            "`length` of flexible body `beam`",
        ),
        (
            "a tunable node",
            model(&beam(), &DEFAULTS, true, 0.0)
                .replace(
                    "modes: 6,",
                    "modes: 6, nodes: [(name: \"tip\", x: \"xt\")],",
                )
                .replace(
                    "parameters: [",
                    "parameters: [(name: \"xt\", value: 2, tunable: true), ",
                ),
            "x: \"xt\"",
            "`nodes` of flexible body `beam`",
        ),
        (
            "a tunable shape",
            model(&assumed(), &DEFAULTS, true, 0.0).replace("(x/2)^3\"), (w", "(x/2)^3*gj\"), (w"),
            "(v: \"(x/2)^3*gj\")",
            "`shapes` of flexible body `beam`",
        ),
        (
            "damped assumed modes",
            model(&assumed(), &DEFAULTS, true, 0.02).replace(
                "stiffening: true, shapes",
                "stiffening: true, damping: \"zeta\", shapes",
            ),
            "damping: \"zeta\"",
            "the `damping` of flexible body `beam` cannot be kept with tunable section data",
        ),
        (
            "damped Craig–Bampton modes",
            model(&beam(), &DEFAULTS, true, 0.0)
                .replace(
                    "modes: 6,",
                    "modes: 3, nodes: [(name: \"tip\", x: 2.0)], craig_bampton: true,",
                )
                .replace("damping: \"zeta\"", "damping: 0.02"),
            "damping: 0.02",
            "the `damping` of flexible body `beam` cannot be kept with tunable section data",
        ),
        (
            "a Timoshenko beam",
            model(&beam(), &DEFAULTS, true, 0.0).replace(
                "stiffening: true,",
                "stiffening: false, shear: Timoshenko(kga_y: 1e6, kga_z: 1e6),",
            ),
            "rho_a: \"rho_a\"",
            "`section data of a Timoshenko beam` of flexible body `beam`",
        ),
    ];
    for (what, text, at, message) in cases {
        let src = Source::new("hub_beam.ron", text.clone());
        let sys = check(&src).unwrap_or_else(|r| panic!("{what}: {r}")).system;
        let err = Numeric::new(&sys).expect_err(what);
        let d = err.diagnostic();
        let shown = src.render_all(&[d]);
        eprintln!("{what}:\n{shown}");
        let start = text
            .find(at)
            .unwrap_or_else(|| panic!("{what}: test setup"));
        let span = err.span();
        assert!(
            span.start >= start && span.start < start + at.len(),
            "{what}: error at {}, want within `{at}`",
            span.start
        );
        assert!(shown.contains(message), "{what}: {shown}");
        assert!(shown.contains("tunable"), "{what}: {shown}");
        // The generator refuses alike.
        assert!(
            formulate(&sys, FunctionSet::all_requested()).is_err(),
            "{what}"
        );
    }
    // Undamped Craig–Bampton modes are fine (constraint modes are unit
    // boundary motions, the fixed-interface modes pure per block).
    let cb = model(&beam(), &DEFAULTS, true, 0.0).replace(
        "modes: 6,",
        "modes: 3, nodes: [(name: \"tip\", x: 2.0)], craig_bampton: true,",
    );
    Numeric::new(&system(cb)).expect("undamped Craig–Bampton with tunable data");
}

/// The emitted Rust reads the section data from the parameter struct at
/// run time (fields with the defaults; the modal damping as
/// `2 ζ √(K_ii M_ii)`), and leaves them inlined when they are fixed.
#[test]
fn flex_tunable_section_data_are_fields_of_the_generated_struct() {
    let g = eom_gen::generate(&Source::new(
        "hub_beam.ron",
        model(&beam(), &DEFAULTS, true, 0.02),
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    for name in NAMES.iter().chain(&["zeta"]) {
        assert!(
            g.source.contains(&format!("pub {name}: f64,")),
            "field `{name}`"
        );
        assert!(
            g.source.contains(&format!("self.params.{name}")),
            "`{name}` is read at run time"
        );
    }
    assert!(
        g.source.contains("sqrt"),
        "the modal damping's √(K_ii M_ii)"
    );
    let fixed = eom_gen::generate(&Source::new(
        "hub_beam.ron",
        model(&beam(), &DEFAULTS, false, 0.02),
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !fixed.source.contains("self.params.rho_a"),
        "fixed data are inlined"
    );
}
