//! Long runs of the compiled models with the runtime's integrators:
//! conservative models keep their energy (drift < 1e-10 relative to
//! |T| + |V| over 100 s at rtol = atol = 1e-12, DOP853), the torque-free body also its
//! angular momentum, and the quaternion stays unit through the projection
//! hook.

use eom_generated as g;
use eom_sim::{Dop853, Model, SolveOptions, StopReason, Vector, integrate};

/// Integrates `M` over `t_end` and returns (relative energy drift, final state).
fn drift<M: Model + Default + eom_sim::OdeSystem<N>, const N: usize>(
    t_end: f64,
    tol: f64,
) -> (f64, [f64; N], M) {
    let m = M::default();
    let (q0, u0) = (m.q0(), m.u0());
    let mut y0 = [0.0; N];
    y0[..M::NQ].copy_from_slice(q0.as_ref());
    y0[M::NQ..].copy_from_slice(u0.as_ref());
    let opts = SolveOptions {
        record_steps: false,
        max_steps: 10_000_000,
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut Dop853::new(tol, tol),
        &m,
        0.0,
        y0,
        t_end,
        &opts,
        &mut [],
    );
    assert_eq!(
        sol.stop,
        StopReason::Finished,
        "{}: {:?}",
        M::NAME,
        sol.stop
    );
    let energy = |y: &[f64; N]| {
        let (mut q, mut u) = (M::Q::ZERO, M::U::ZERO);
        q.as_mut().copy_from_slice(&y[..M::NQ]);
        u.as_mut().copy_from_slice(&y[M::NQ..]);
        m.energy(0.0, &q, &u)
    };
    let ([t0, v0], [t1, v1]) = (energy(&y0), energy(&sol.y_final));
    // Relative to the energy's size, |T| + |V| (the total may be near zero,
    // as for the pendulum released horizontally).
    let scale = (t0.abs() + v0.abs()).max(t1.abs() + v1.abs());
    (((t1 + v1) - (t0 + v0)).abs() / scale, sol.y_final, m)
}

#[test]
fn conservative_models_keep_their_energy_over_100_s() {
    let (d, _, _) = drift::<g::pendulum::Pendulum, 2>(100.0, 1e-12);
    assert!(d < 1e-10, "pendulum: relative energy drift {d:e}");
    let (d, _, _) = drift::<g::double_pendulum::DoublePendulum, 4>(100.0, 1e-12);
    assert!(d < 1e-10, "double pendulum: relative energy drift {d:e}");
    let (d, y, _) = drift::<g::heavy_top::HeavyTop, 7>(100.0, 1e-12);
    assert!(d < 1e-10, "heavy top: relative energy drift {d:e}");
    let norm = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2] + y[3] * y[3]).sqrt();
    assert!(
        (norm - 1.0).abs() < 1e-14,
        "heavy top quaternion norm {norm}"
    );
}

#[test]
fn torque_free_body_keeps_energy_and_angular_momentum() {
    let (d, y, m) = drift::<g::free_body::FreeBody, 13>(100.0, 1e-12);
    assert!(d < 1e-10, "free body: relative energy drift {d:e}");
    let (mut q, mut u) = ([0.0; 7], [0.0; 6]);
    q.copy_from_slice(&y[..7]);
    u.copy_from_slice(&y[7..]);
    let h = m.momentum(0.0, &q, &u);
    let h0 = m.momentum(0.0, &m.q0(), &m.u0());
    for k in 0..3 {
        assert!(
            (h[k] - h0[k]).abs() < 1e-10 * 2.0,
            "angular momentum[{k}] {} → {}",
            h0[k],
            h[k]
        );
    }
}
