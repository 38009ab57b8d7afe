//! The derivatives of forward dynamics compiled (`#[multibody]` on scenes
//! that ask for `ForwardDynamicsDerivatives`): the inherent method and
//! `Model::evaluate("forward_dynamics_derivatives")` equal the interpreted
//! program at pseudo-random states (1e-12 relative: the same program, two
//! evaluators), for arm7 (seven hinges) and the heavy top (a quaternion,
//! derivatives in the tangent space: 3 × 3 blocks, not 3 × 4); arm7's
//! `inverse_dynamics_derivatives` likewise, and its `∂τ/∂u̇` equals the
//! compiled mass matrix.

use eom_gen::interpret::{Point, evaluate_function};
use eom_macros::multibody;
use eom_sim::Model;

#[multibody(model = "tests/scenes/arm7_derivatives.scene.ron")]
pub struct ArmDerivatives;

#[multibody(model = "tests/scenes/heavy_top_derivatives.scene.ron")]
pub struct TopDerivatives;

fn rng(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// Compiled (both entry points) against interpreted at `q`, `u`, `tau`.
fn agree<M: Model>(scene: &str, m: &M, compiled: &[f64], q: &[f64], u: &[f64], tau: &[f64]) {
    let path = format!("{}/tests/scenes/{scene}", env!("CARGO_MANIFEST_DIR"));
    let g = eom_gen::generate_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let sys = &g.checked.system;
    let nu = sys.nu();
    let point = Point {
        sys,
        q,
        u,
        udot: &[],
        tau,
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.2,
    };
    let want = evaluate_function(
        &g.formulation,
        eom_gen::functions::Function::ForwardDynamicsDerivatives,
        &point,
    )
    .expect("the scene asks for the derivatives");
    assert_eq!(want.len(), 3 * nu * nu, "{scene}: three NU × NU blocks");
    let mut through_evaluate = vec![0.0; want.len()];
    let at = eom_sim::Point {
        t: 0.2,
        q,
        u,
        tau,
        udot: &[],
        lambda: &[],
    };
    assert!(
        m.evaluate("forward_dynamics_derivatives", &at, &mut through_evaluate),
        "{scene}: Model::evaluate offers the derivatives"
    );
    for (k, w) in want.iter().enumerate() {
        let close = |g: f64| (g - w).abs() <= 1e-12 * (1.0 + w.abs());
        assert!(
            close(compiled[k]),
            "{scene}[{k}]: compiled {} interpreted {w}",
            compiled[k]
        );
        assert!(
            close(through_evaluate[k]),
            "{scene}[{k}]: Model::evaluate {} interpreted {w}",
            through_evaluate[k]
        );
    }
}

#[test]
fn arm7_derivatives_compiled_equal_interpreted() {
    let m = ArmDerivatives::default();
    let mut seed = 27;
    for _ in 0..5 {
        let (mut q, mut u, mut tau) = ([0.0; 7], [0.0; 7], [0.0; 7]);
        for k in 0..7 {
            (q[k], u[k], tau[k]) = (3.0 * rng(&mut seed), 2.0 * rng(&mut seed), rng(&mut seed));
        }
        let mut out = [0.0; 147];
        m.forward_dynamics_derivatives(0.2, &q, &u, &tau, &mut out);
        inverse_agree(&m, &q, &u, &tau);
        agree("arm7_derivatives.scene.ron", &m, &out, &q, &u, &tau);
    }
}

#[test]
fn heavy_top_derivatives_compiled_equal_interpreted() {
    let m = TopDerivatives::default();
    let mut seed = 2027;
    for _ in 0..5 {
        let mut q = [0.0; 4];
        q.iter_mut().for_each(|x| *x = rng(&mut seed));
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        q.iter_mut().for_each(|x| *x /= n);
        let (mut u, mut tau) = ([0.0; 3], [0.0; 3]);
        for k in 0..3 {
            (u[k], tau[k]) = (5.0 * rng(&mut seed), rng(&mut seed));
        }
        let mut out = [0.0; 27];
        m.forward_dynamics_derivatives(0.2, &q, &u, &tau, &mut out);
        agree("heavy_top_derivatives.scene.ron", &m, &out, &q, &u, &tau);
    }
}

/// arm7's `inverse_dynamics_derivatives`, compiled, against interpreted at
/// `(q, u, u̇ = ud)`, and `∂τ/∂u̇` against the compiled `M(q)`.
fn inverse_agree(m: &ArmDerivatives, q: &[f64; 7], u: &[f64; 7], ud: &[f64; 7]) {
    let path = format!(
        "{}/tests/scenes/arm7_derivatives.scene.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let g = eom_gen::generate_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let point = Point {
        sys: &g.checked.system,
        q,
        u,
        udot: ud,
        tau: &[],
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.2,
    };
    let want = evaluate_function(
        &g.formulation,
        eom_gen::functions::Function::InverseDynamicsDerivatives,
        &point,
    )
    .expect("the scene asks for them");
    let mut got = [0.0; 147];
    m.inverse_dynamics_derivatives(0.2, q, u, ud, &mut got);
    let mut mass = [[0.0; 7]; 7];
    m.mass_matrix(0.2, q, &mut mass);
    for (k, w) in want.iter().enumerate() {
        assert!(
            (got[k] - w).abs() <= 1e-12 * (1.0 + w.abs()),
            "inverse_dynamics_derivatives[{k}]: compiled {} interpreted {w}",
            got[k]
        );
    }
    for (i, row) in mass.iter().enumerate() {
        for (j, m) in row.iter().enumerate() {
            let d = got[2 * 49 + i * 7 + j];
            assert!(
                (d - m).abs() <= 1e-12 * (1.0 + d.abs()),
                "∂τ/∂u̇[{i}][{j}] = {d}, M = {m}"
            );
        }
    }
}
