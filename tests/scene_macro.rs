//! `#[multibody]` takes a scene: the arm7 end-effector scene compiles onto a
//! struct with five coordinates and the tip position as its only output, and
//! its compiled forward dynamics and outputs equal the interpreted programs.
//! Scenes that leave functions out compile to derived ones that equal the
//! full model's symbolic functions.

use eom_gen::interpret::{Point, evaluate, run};
use eom_macros::multibody;
use eom_sim::Model;

#[multibody(model = "models/scenes/arm7_ee.scene.ron")]
pub struct ArmTip;

/// Inverse dynamics generated; `M` and `b` derived from it.
#[multibody(model = "models/scenes/arm7_dynamics.scene.ron")]
pub struct ArmDynamics;

/// `M` and `b` generated; inverse dynamics derived from them.
#[multibody(model = "tests/scenes/arm7_mass_bias.scene.ron")]
pub struct ArmMassBias;

fn close(got: f64, want: f64) -> bool {
    (got - want).abs() <= 1e-10 * (1.0 + want.abs())
}

/// `M`, `b`, `ID` and `FD` of a scene model equal the full model's
/// (all generated symbolically) at `n` pseudo-random states: the derived
/// functions use `M u̇ + b = ID(q, u, u̇)` and `FD` inverts it.
fn agrees_with_full_arm7<M>(m: &M, label: &str)
where
    M: Model<Q = [f64; 7], U = [f64; 7], MassMatrix = [[f64; 7]; 7]>,
{
    let full = eom_generated::arm7::Arm7::default();
    let mut seed = 3u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    for _ in 0..10 {
        let (mut q, mut u, mut udot, mut tau) = ([0.0; 7], [0.0; 7], [0.0; 7], [0.0; 7]);
        for k in 0..7 {
            (q[k], u[k], udot[k], tau[k]) = (3.0 * rnd(), 2.0 * rnd(), 4.0 * rnd(), rnd());
        }
        let t = 0.3;
        let (mut got_m, mut want_m) = ([[0.0; 7]; 7], [[0.0; 7]; 7]);
        m.mass_matrix(t, &q, &mut got_m);
        full.mass_matrix(t, &q, &mut want_m);
        let (mut got_b, mut want_b) = ([0.0; 7], [0.0; 7]);
        m.bias(t, &q, &u, &mut got_b);
        full.bias(t, &q, &u, &mut want_b);
        let (mut got_id, mut want_id) = ([0.0; 7], [0.0; 7]);
        m.inverse_dynamics(t, &q, &u, &udot, &mut got_id);
        full.inverse_dynamics(t, &q, &u, &udot, &mut want_id);
        let (mut got_fd, mut want_fd) = ([0.0; 7], [0.0; 7]);
        m.forward_dynamics(t, &q, &u, &tau, &mut got_fd);
        full.forward_dynamics(t, &q, &u, &tau, &mut want_fd);
        for i in 0..7 {
            for j in 0..7 {
                assert!(
                    close(got_m[i][j], want_m[i][j]),
                    "{label}: M[{i}][{j}] got {} want {}",
                    got_m[i][j],
                    want_m[i][j]
                );
                assert_eq!(got_m[i][j], got_m[j][i], "{label}: M is symmetric");
            }
            for (what, got, want) in [
                ("b", got_b[i], want_b[i]),
                ("ID", got_id[i], want_id[i]),
                ("FD", got_fd[i], want_fd[i]),
            ] {
                assert!(
                    close(got, want),
                    "{label}: {what}[{i}] got {got} want {want}"
                );
            }
        }
    }
}

#[test]
fn scene_with_inverse_dynamics_only_derives_mass_matrix_and_bias() {
    agrees_with_full_arm7(&ArmDynamics::default(), "arm7_dynamics");
}

#[test]
fn scene_with_mass_matrix_and_bias_derives_inverse_dynamics() {
    agrees_with_full_arm7(&ArmMassBias::default(), "arm7_mass_bias");
}

#[test]
fn macro_scene_matches_the_interpreted_scene() {
    assert_eq!(ArmTip::NQ, 5);
    assert_eq!(ArmTip::COORDINATE_NAMES, ["q1", "q2", "q3", "q4", "q6"]);
    assert_eq!(
        ArmTip::OUTPUT_NAMES,
        ["link7_tip_x", "link7_tip_y", "link7_tip_z"]
    );
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/scenes/arm7_ee.scene.ron"
    );
    let g = eom_gen::generate_file(path).unwrap_or_else(|e| panic!("{e}"));
    let m = ArmTip::default();
    let (q, u, tau) = (
        [0.3, 2.0, -0.4, 0.7, 0.2],
        [0.5, -0.2, 0.1, 0.3, -0.6],
        [0.1, 0.0, -0.2, 0.0, 0.05],
    );
    let mut udot = [0.0; 5];
    m.forward_dynamics(0.0, &q, &u, &tau, &mut udot);
    let mut out = [0.0; 3];
    m.outputs(0.0, &q, &u, &udot, &mut out);
    let point = Point {
        sys: &g.checked.system,
        q: &q,
        u: &u,
        udot: &udot,
        tau: &tau,
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.0,
    };
    let want = evaluate(&g.formulation, &point).udot();
    let want_out = run(
        g.formulation
            .program(eom_gen::functions::Function::Outputs)
            .expect("outputs"),
        &point,
    );
    for k in 0..5 {
        assert!(
            (udot[k] - want[k]).abs() < 1e-10,
            "u̇[{k}]: got {} want {}",
            udot[k],
            want[k]
        );
    }
    for k in 0..3 {
        assert!(
            (out[k] - want_out[k]).abs() < 1e-12,
            "tip[{k}]: got {} want {}",
            out[k],
            want_out[k]
        );
    }
}
