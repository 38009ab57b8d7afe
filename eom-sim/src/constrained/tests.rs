//! Every method on a Cartesian pendulum against the pendulum equation
//! integrated in the angle: assembly, [`ConstrainedSystem`] and
//! [`Index3System`] together.

use super::*;
use crate::{Settings, SolveOptions, StopReason, solve};

/// A point mass on a massless rod of length `L` in the vertical plane,
/// in Cartesian coordinates: `Φ = (x² + y² − L²)/2`, `J = (x, y)`,
/// `γ = −(ẋ² + ẏ²)`; the same motion as `θ̈ = −(g/L) sin θ`.
struct CartesianPendulum;

const G: f64 = 9.81;
const L: f64 = 1.5;

impl Dynamics for CartesianPendulum {
    fn nq(&self) -> usize {
        2
    }
    fn nu(&self) -> usize {
        2
    }
    fn nc(&self) -> usize {
        1
    }
    fn n_holonomic(&self) -> usize {
        1
    }
    fn quaternions(&self) -> &[usize] {
        &[]
    }
    fn qdot(&self, _q: &[f64], u: &[f64], qdot: &mut [f64]) {
        qdot.copy_from_slice(u);
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], m: &mut DMatrix<f64>) {
        m.fill(0.0);
        m[(0, 0)] = 2.0;
        m[(1, 1)] = 2.0;
    }
    fn bias(&self, _t: f64, _q: &[f64], _u: &[f64], b: &mut DVector<f64>) {
        b[0] = 0.0;
        b[1] = 2.0 * G;
    }
    fn constraints(&self, _t: f64, q: &[f64], u: &[f64], c: &mut ConstraintValues) {
        c.phi[0] = (q[0] * q[0] + q[1] * q[1] - L * L) / 2.0;
        c.phidot[0] = q[0] * u[0] + q[1] * u[1];
        c.gamma[0] = -(u[0] * u[0] + u[1] * u[1]);
        c.jacobian[(0, 0)] = q[0];
        c.jacobian[(0, 1)] = q[1];
    }
}

fn angle_reference(theta0: f64, t_end: f64) -> f64 {
    let sys = crate::FnSystem(|_t: f64, y: &[f64; 2], dy: &mut [f64; 2]| {
        dy[0] = y[1];
        dy[1] = -(G / L) * y[0].sin();
    });
    let s = Settings {
        integrator: crate::Integrator::Dop853,
        rtol: 1e-13,
        atol: 1e-13,
        dt: 0.0,
        index_vars: (0, 0),
    };
    let sol = solve(
        &s,
        &sys,
        0.0,
        [theta0, 0.0],
        t_end,
        &SolveOptions::default(),
    );
    sol.y_final[0]
}

#[test]
fn every_method_reproduces_the_pendulum() {
    // Released from 1 rad (x = L sin θ, y = −L cos θ) and run 3 s: the
    // angle atan2(x, −y) follows the pendulum equation integrated in θ.
    let theta0 = 1.0f64;
    let t_end = 3.0;
    let want = angle_reference(theta0, t_end);
    let (q0, u0) = ([L * theta0.sin(), -L * theta0.cos()], [0.0, 0.0]);
    let d = CartesianPendulum;
    let a = assemble(&d, &q0, &u0, 0.0);
    assert!(a.residual < 1e-15 && a.velocity_residual == 0.0);
    let settings = |integrator: &str| Settings {
        integrator: integrator.parse().expect("a known integrator"),
        rtol: 1e-11,
        atol: 1e-11,
        dt: 0.0,
        index_vars: (0, 0),
    };
    for method in [Method::BAUMGARTE, Method::Projection, Method::Partitioning] {
        let sys = ConstrainedSystem::new(&d, method);
        let y0 = [q0[0], q0[1], 0.0, 0.0];
        let sol = solve(
            &settings("dop853"),
            &sys,
            0.0,
            y0,
            t_end,
            &SolveOptions::default(),
        );
        assert_eq!(sol.stop, StopReason::Finished);
        let got = sol.y_final[0].atan2(-sol.y_final[1]);
        assert!(
            (got - want).abs() < 1e-8,
            "{method:?}: θ = {got}, want {want}"
        );
        let s = sys.stats();
        assert_eq!(s.rank, 1);
        if method != Method::BAUMGARTE {
            assert!(s.max_position_residual < 1e-12, "{method:?}: {s:?}");
        }
    }
    let dae = Index3System::new(&d);
    let y0: [f64; 5] = dae.initial(0.0, &q0, &u0).expect("initial");
    // At rest, the rod carries the weight's radial part: λ L = −m g cos θ0
    // with M u̇ = −b + Jᵀλ and J = (x, y) (so the rod force is λ (x, y)).
    assert!(
        (y0[4] * L + 2.0 * G * theta0.cos()).abs() < 1e-12,
        "λ0 = {}",
        y0[4]
    );
    let s = Settings {
        index_vars: dae.index_vars(),
        ..settings("radau5")
    };
    assert_eq!(dae.index_vars(), (2, 1));
    let sol = solve(&s, &dae, 0.0, y0, t_end, &SolveOptions::default());
    assert_eq!(sol.stop, StopReason::Finished);
    let got = sol.y_final[0].atan2(-sol.y_final[1]);
    assert!((got - want).abs() < 1e-7, "index-3: θ = {got}, want {want}");
}
