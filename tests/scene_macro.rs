//! `#[multibody]` takes a scene: the arm7 end-effector scene compiles onto a
//! struct with five coordinates and the tip position as its only output, and
//! its compiled forward dynamics and outputs equal the interpreted programs.

use eom_gen::interpret::{Point, evaluate, run};
use eom_macros::multibody;
use eom_sim::Model;

#[multibody(model = "models/scenes/arm7_ee.scene.ron")]
pub struct ArmTip;

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
    let want = evaluate(&g.formulation, &point).udot;
    let want_out = run(g.formulation.outputs.as_ref().expect("outputs"), &point);
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
