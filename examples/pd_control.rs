//! A control loop closed around a generated model: the 7-joint arm
//! (`models/arm7.ron`, generated in `eom-generated`) driven to a target pose
//! by computed torque, `τ = M(q) (K_p e − K_d u) + b(q, u)` with `e = q* − q`.
//! The generated `mass_matrix` and `bias` are called inside the right-hand
//! side of an `FnSystem`, the controller's torques go into the generated
//! `forward_dynamics`, and the state is packed and unpacked with
//! `eom_sim::state`.
//!
//! With exact model knowledge every joint's error obeys `ë + 2ω ė + ω² e =
//! 0` (`K_p = ω²`, `K_d = 2ω`: critically damped), so
//! `e(t) = e₀ (1 + ωt) e^{−ωt}` from rest; the example prints the largest
//! deviation from that closed form and exits non-zero above 1e-6 rad.
//!
//! `cargo run --example pd_control`

use eom_generated::arm7::Arm7;
use eom_sim::state::{pack, unpack};
use eom_sim::{Dopri5, FnSystem, Model, SolveOptions, integrate};
use std::process::ExitCode;

/// Joints of the arm.
const N: usize = 7;

fn main() -> ExitCode {
    let arm = Arm7::default();
    let omega = 4.0; // rad/s: closed-loop bandwidth
    let (kp, kd) = (omega * omega, 2.0 * omega);
    let target: [f64; N] = [0.5, -0.3, 0.2, 1.0, -0.4, 0.6, 0.1];
    let q0 = arm.q0();
    let u0 = [0.0; N];

    // The closed loop: controller and plant in one right-hand side.
    let closed_loop = FnSystem(|t: f64, y: &[f64; 2 * N], dy: &mut [f64; 2 * N]| {
        let (q, u): ([f64; N], [f64; N]) = unpack(y);
        let mut m = Arm7::MASS_ZERO;
        let mut b = [0.0; N];
        arm.mass_matrix(t, &q, &mut m);
        arm.bias(t, &q, &u, &mut b);
        let mut tau = b;
        for (i, row) in m.iter().enumerate() {
            for j in 0..N {
                tau[i] += row[j] * (kp * (target[j] - q[j]) - kd * u[j]);
            }
        }
        let (mut qdot, mut udot) = ([0.0; N], [0.0; N]);
        arm.qdot(&q, &u, &mut qdot);
        arm.forward_dynamics(t, &q, &u, &tau, &mut udot);
        *dy = pack(&qdot, &udot);
    });

    let t_end = 3.0;
    let mut method = Dopri5::new(1e-11, 1e-11);
    let sol = integrate(
        &mut method,
        &closed_loop,
        0.0,
        pack(&q0, &u0),
        t_end,
        &SolveOptions::default(),
        &mut [],
    );
    let mut worst: f64 = 0.0;
    for (t, y) in sol.t.iter().zip(&sol.y) {
        let (q, _): ([f64; N], [f64; N]) = unpack(y);
        for j in 0..N {
            let e0 = target[j] - q0[j];
            let want = e0 * (1.0 + omega * t) * (-omega * t).exp();
            worst = worst.max(((target[j] - q[j]) - want).abs());
        }
    }
    let (q, _): ([f64; N], [f64; N]) = unpack(&sol.y_final);
    let err = (0..N).map(|j| (target[j] - q[j]).abs()).fold(0.0, f64::max);
    println!(
        "computed torque, ω = {omega} rad/s: |e| = {err:.2e} rad at t = {t_end} s \
         ({} steps); largest deviation from e₀(1 + ωt)e^(−ωt): {worst:.1e} rad",
        sol.stats.accepted
    );
    if worst > 1e-6 || sol.stop != eom_sim::StopReason::Finished {
        eprintln!(
            "the closed loop does not follow its closed form: {:?}",
            sol.stop
        );
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}
