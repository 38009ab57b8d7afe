//! The `build.rs` route: `eom_gen::Builder` writes the generated module into
//! `OUT_DIR`, and this crate `include!`s it. Simulates the chaotic double
//! pendulum for 10 s with DOP853 and reports the energy drift.

mod double_pendulum {
    include!(concat!(env!("OUT_DIR"), "/double_pendulum.rs"));
}

use double_pendulum::DoublePendulum;
use eom_sim::{Dop853, Model, SolveOptions, integrate};

fn main() {
    let model = DoublePendulum::default();
    let (q0, u0) = (model.q0(), model.u0());
    let y0 = [q0[0], q0[1], u0[0], u0[1]];
    let energy = |y: &[f64; 4]| {
        model
            .energy(0.0, &[y[0], y[1]], &[y[2], y[3]])
            .iter()
            .sum::<f64>()
    };
    let mut method = Dop853::new(1e-10, 1e-10);
    let sol = integrate(
        &mut method,
        &model,
        0.0,
        y0,
        10.0,
        &SolveOptions::default(),
        &mut [],
    );
    let (e0, e1) = (energy(&y0), energy(&sol.y_final));
    println!("double pendulum, 10 s with DOP853 at 1e-10: {:?}", sol.stop);
    println!(
        "  q = ({:.6}, {:.6}), relative energy drift {:.2e}",
        sol.y_final[0],
        sol.y_final[1],
        (e1 - e0).abs() / e0.abs()
    );
    println!("  {:?}", sol.stats);
}
