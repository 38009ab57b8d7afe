//! The `#[multibody]` route: the pendulum's equations are generated at
//! compile time onto `Pendulum`; simulate a swing with DOPRI5 and compare
//! the half period with the exact large-amplitude value.

use eom_macros::multibody;
use eom_sim::{Direction, Dopri5, Event, EventAction, Model, SolveOptions, StopReason, integrate};

/// IFToMM A01 simple pendulum, from `models/pendulum.ron`.
#[multibody(model = "models/pendulum.ron")]
pub struct Pendulum;

fn main() {
    let p = Pendulum::default();
    let (q0, u0) = (p.q0(), p.u0());
    // Released horizontally (θ0 = π/2): stop when θ crosses zero moving back up.
    let mut events = [Event::new(
        |_t, y: &[f64; 2]| y[0],
        Direction::Falling,
        EventAction::Stop,
    )];
    let mut method = Dopri5::new(1e-12, 1e-12);
    let sol = integrate(
        &mut method,
        &p,
        0.0,
        [q0[0], u0[0]],
        10.0,
        &SolveOptions::default(),
        &mut events,
    );
    let StopReason::EventStop { t, .. } = sol.stop else {
        eprintln!("no zero crossing: {:?}", sol.stop);
        std::process::exit(1);
    };
    // Quarter period for amplitude π/2: K(sin(π/4)) sqrt(l/g), K = 1.854074677301372.
    let want = 1.854_074_677_301_372 * (1.0f64 / 9.81).sqrt();
    println!(
        "θ = 0 at t = {t:.12} s; exact quarter period {want:.12} s; error {:.1e}",
        (t - want).abs()
    );
}
