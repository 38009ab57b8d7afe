//! Closure conditions of cut joints: they vanish at every bundled model's
//! initial state, and the rank of their Jacobian gives the true mobility —
//! 1 for Bricard's over-constrained loop although Grübler–Kutzbach says 0.

use eom_gen::mech::Numeric;
use eom_gen::{System, check_file};

fn system(name: &str) -> System {
    let path = format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    check_file(&path).unwrap_or_else(|r| panic!("{r}")).system
}

#[test]
fn closure_conditions_vanish_at_the_initial_state() {
    for (name, equations) in [
        // Planar loops keep only the two in-plane equations per hinge.
        ("fourbar", 2),
        ("slider_crank", 2),
        ("slider_crank_driven", 2),
        ("andrews", 6),
        // Spatial hinge: 3 position + 2 axis-alignment equations.
        ("bricard", 5),
        // Five cut ball joints: 3 each.
        ("stewart", 15),
        ("stewart_driven", 15),
    ] {
        let sys = system(name);
        let num = Numeric::new(&sys).expect("numeric");
        let phi = num.constraints(&sys.q0(), 0.0).expect("phi");
        assert_eq!(phi.len(), equations, "{name}: number of closure equations");
        for (k, x) in phi.iter().enumerate() {
            assert!(
                x.abs() < 1e-12,
                "{name}: Φ[{k}] = {x:e} at the initial state"
            );
        }
    }
}

#[test]
fn jacobian_rank_gives_the_true_mobility() {
    for (name, grubler, mobility) in [
        ("fourbar", 1, 1),
        ("slider_crank", 1, 1),
        ("slider_crank_driven", 0, 0),
        ("andrews", 1, 1),
        ("bricard", 0, 1),
        ("stewart", 6, 6),
        ("stewart_driven", 0, 0),
    ] {
        let sys = system(name);
        assert_eq!(sys.grubler.dof, grubler, "{name}: Grübler–Kutzbach");
        let num = Numeric::new(&sys).expect("numeric");
        let m = num.mobility(&sys.q0(), 0.0).expect("mobility");
        assert_eq!(
            m.dof, mobility,
            "{name}: mobility from the rank of Φ_q ({m:?})"
        );
    }
}

/// Runs the generated closure program at (q, u, t): (Φ, Φ̇, γ, J).
type Closure = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<Vec<f64>>);

fn closure(p: &eom_gen::sym::Program, sys: &System, q: &[f64], u: &[f64], t: f64) -> Closure {
    let x = eom_gen::interpret::Point {
        sys,
        q,
        u,
        udot: &[],
        tau: &[],
        inputs: &[],
        params: &[],
        t,
    };
    let values = eom_gen::interpret::run(p, &x);
    let mut out: Closure = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for ((name, _), v) in p.outputs.iter().zip(values) {
        if name.starts_with("phidot") {
            out.1.push(v);
        } else if name.starts_with("phi") {
            out.0.push(v);
        } else if name.starts_with("gamma") {
            out.2.push(v);
        } else if let Some(rest) = name.strip_prefix("J_") {
            let i: usize = rest
                .split('_')
                .next()
                .and_then(|s| s.parse().ok())
                .unwrap_or(0);
            if out.3.len() <= i {
                out.3.resize(i + 1, Vec::new());
            }
            out.3[i].push(v);
        }
    }
    out
}

#[test]
fn generated_closure_conditions_and_their_derivatives_are_consistent() {
    // Φ equals the f64 algorithm; Φ̇ is the derivative of Φ along
    // q̇ = N(q) u (and t); J u + Φ_t = Φ̇ with Φ_t = Φ̇ at u = 0; and
    // γ = −dΦ̇/dt at fixed u, all by central differences.
    use eom_gen::mech::{Request, formulate};
    use eom_gen::testkit::{Rng, random_state};
    let mut rng = Rng(0xABCD_EF01_2345_6789);
    for name in [
        "fourbar",
        "slider_crank_driven",
        "andrews",
        "bricard",
        "stewart",
    ] {
        let sys = system(name);
        let f = formulate(&sys, Request::default()).expect("formulates");
        let p = f
            .constraints
            .as_ref()
            .expect("loops give closure conditions");
        let num = Numeric::new(&sys).expect("numeric");
        for _ in 0..3 {
            let (q, u) = random_state(&sys, &mut rng);
            let t = 0.3;
            let (phi, phidot, gamma, jac) = closure(p, &sys, &q, &u, t);
            let want = num.constraints(&q, t).expect("phi");
            for (a, b) in phi.iter().zip(&want) {
                assert!((a - b).abs() < 1e-12, "{name}: Φ generated {a}, f64 {b}");
            }
            let h = 1e-6;
            let qd = num.qdot(&q, &u);
            let moved =
                |s: f64| -> Vec<f64> { q.iter().zip(&qd).map(|(q, d)| q + s * d).collect() };
            let (pp, pm) = (
                num.constraints(&moved(h), t + h).expect("phi"),
                num.constraints(&moved(-h), t - h).expect("phi"),
            );
            let zero = vec![0.0; u.len()];
            let (_, phi_t, _, _) = closure(p, &sys, &q, &zero, t);
            for i in 0..phi.len() {
                let fd = (pp[i] - pm[i]) / (2.0 * h);
                assert!(
                    (phidot[i] - fd).abs() < 1e-6 * (1.0 + fd.abs()),
                    "{name}: Φ̇[{i}] {} vs differences {fd}",
                    phidot[i]
                );
                let ju: f64 = jac[i].iter().zip(&u).map(|(j, u)| j * u).sum::<f64>() + phi_t[i];
                assert!(
                    (ju - phidot[i]).abs() < 1e-9 * (1.0 + ju.abs()),
                    "{name}: J u + Φ_t = {ju}, Φ̇ = {}",
                    phidot[i]
                );
            }
            let (_, dp, _, _) = closure(p, &sys, &moved(h), &u, t + h);
            let (_, dm, _, _) = closure(p, &sys, &moved(-h), &u, t - h);
            for i in 0..phi.len() {
                let fd = -(dp[i] - dm[i]) / (2.0 * h);
                assert!(
                    (gamma[i] - fd).abs() < 1e-5 * (1.0 + fd.abs()),
                    "{name}: γ[{i}] {} vs differences {fd}",
                    gamma[i]
                );
            }
        }
    }
}

#[test]
fn assembly_closes_perturbed_loops_and_makes_speeds_consistent() {
    // From a perturbed guess, Newton with minimum-norm steps brings Φ to
    // round-off; then the speeds satisfy J u + Φ_t = 0 (with the driven
    // crank, Φ_t ≠ 0). Bricard's redundant equation does not stop it.
    use eom_gen::testkit::Rng;
    let mut rng = Rng(0x7777_1234_5555_0001);
    for name in [
        "fourbar",
        "slider_crank",
        "slider_crank_driven",
        "andrews",
        "bricard",
        "stewart",
    ] {
        let sys = system(name);
        let num = Numeric::new(&sys).expect("numeric");
        let scale = if name == "andrews" { 0.02 } else { 0.1 };
        let q: Vec<f64> = sys.q0().iter().map(|q| q + scale * rng.uniform()).collect();
        let u: Vec<f64> = (0..sys.nu()).map(|_| rng.uniform()).collect();
        let a = num.assemble(&q, &u, 0.0).expect("assembles");
        assert!(
            a.residual < 1e-12,
            "{name}: |Φ| = {:e} after {} iterations",
            a.residual,
            a.iterations
        );
        assert!(
            a.velocity_residual < 1e-8,
            "{name}: |J u + Φ_t| = {:e}",
            a.velocity_residual
        );
        let phi = num.constraints(&a.q, 0.0).expect("phi");
        assert!(phi.iter().all(|x| x.abs() < 1e-12), "{name}: Φ = {phi:?}");
        let moved =
            a.q.iter()
                .zip(&q)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
        assert!(
            moved < 10.0 * scale,
            "{name}: assembly moved a coordinate by {moved}"
        );
    }
}
