//! Step-size control of the one generalized-α (`eom_sim::large::alpha`),
//! on Berzeri and Shabana's falling ANCF pendulum (L = 1.2 m,
//! A = 0.0018 m², I = 1.215e-8 m⁴, ρ = 5540 kg/m³, E = 0.7e6 Pa, pinned at
//! the origin, released horizontal; 8 `Cable2D` elements) and on the mixed
//! model's side of the same integrator.
//!
//! Physics and numerics checked:
//! - The tip at 1 s against a fixed-step reference (h = 5e-5 s, whose own
//!   O(h²) error, estimated from h = 1e-4 s by Richardson, is stated): the
//!   error of the controlled runs falls with the tolerance, about as
//!   `tol^{2/3}` for a second-order method controlled per step.
//! - At equal or smaller error, the controlled run takes fewer steps than
//!   the fixed step (the pendulum's fast start and the whip at the bottom
//!   need small steps only briefly).
//! - The energy (kinetic + strain + gravity) drifts no more than the
//!   tolerance asks.

use eom_sim::elements::Element;
use eom_sim::large::ancf::{Chain, ChainSpec, Section, Support, chain};
use eom_sim::large::{AlphaOptions, GeneralizedAlpha, State, StepControl};

fn pendulum(elements: usize) -> Chain {
    let spec = ChainSpec {
        kernel: Element::Cable2D,
        start: [0.0; 3],
        end: [1.2, 0.0, 0.0],
        elements,
        section: Section {
            e: 0.7e6,
            rho: 5540.0,
            area: 0.0018,
            inertia: 1.215e-8,
            ..Section::default()
        },
        start_support: Support::Pinned,
        end_support: Support::Free,
        end_force: [0.0; 3],
        end_mass: 0.0,
        gravity: [0.0, -9.81, 0.0],
    };
    chain(&spec).unwrap_or_else(|e| panic!("{e}"))
}

/// The end of one run: tip at `t_end`, steps, rejected steps, largest
/// energy change relative to `m g L`.
struct Run {
    tip: [f64; 3],
    steps: usize,
    rejected: usize,
    energy: f64,
}

fn fall(ch: &Chain, opts: AlphaOptions, t_end: f64) -> Run {
    let m = &ch.model;
    let state = State {
        t: 0.0,
        q: m.restrict(m.q0()),
        v: vec![0.0; m.n_free()],
    };
    let e0 = m.energy(m.q0(), &state.v);
    let scale = 5540.0 * 0.0018 * 1.2 * 9.81 * 1.2;
    let mut ga = GeneralizedAlpha::new(m, state, opts).unwrap_or_else(|e| panic!("{e}"));
    let mut worst: f64 = 0.0;
    ga.run_to(t_end, |s, q| {
        worst = worst.max((m.energy(q, &s.v) - e0).abs() / scale);
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        (ga.state().t - t_end).abs() < 1e-12,
        "ended at {} instead of {t_end}",
        ga.state().t
    );
    Run {
        tip: ch.node_position(ga.q_full(), ch.nodes - 1),
        steps: ga.stats.steps,
        rejected: ga.stats.rejected,
        energy: worst,
    }
}

fn fixed(h: f64) -> AlphaOptions {
    AlphaOptions {
        h,
        ..AlphaOptions::default()
    }
}

fn controlled(tol: f64) -> AlphaOptions {
    AlphaOptions {
        h: 1e-4,
        control: Some(StepControl::new(tol, tol)),
        ..AlphaOptions::default()
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

#[test]
fn step_size_control_meets_the_error_in_fewer_steps_than_the_fixed_step() {
    let ch = pendulum(8);
    let t_end = 1.0;
    let reference = fall(&ch, fixed(5e-5), t_end);
    let coarser = fall(&ch, fixed(1e-4), t_end);
    // Richardson: the reference's own error is a third of its distance to
    // the run at twice the step.
    let reference_error = distance(reference.tip, coarser.tip) / 3.0;
    println!(
        "reference (h = 5e-5): tip {:?}, own error ≈ {reference_error:.1e} m",
        reference.tip
    );
    let mut fixed_runs = Vec::new();
    for h in [2e-3, 1e-3, 5e-4, 2.5e-4] {
        let r = fall(&ch, fixed(h), t_end);
        let err = distance(r.tip, reference.tip);
        println!(
            "fixed h = {h:.1e}: {} steps, tip error {err:.2e} m, energy {:.1e}",
            r.steps, r.energy
        );
        fixed_runs.push((r.steps, err));
    }
    let mut controlled_runs = Vec::new();
    for tol in [1e-4, 1e-5, 1e-6] {
        let r = fall(&ch, controlled(tol), t_end);
        let err = distance(r.tip, reference.tip);
        println!(
            "tol {tol:.0e}: {} steps ({} rejected), tip error {err:.2e} m, energy {:.1e}",
            r.steps, r.rejected, r.energy
        );
        assert!(
            err > 3.0 * reference_error,
            "tol {tol:e}: error {err:e} is within the reference's own {reference_error:e}; refine the reference"
        );
        controlled_runs.push((tol, r.steps, err));
    }
    // The error falls with the tolerance.
    for w in controlled_runs.windows(2) {
        assert!(
            w[1].2 < w[0].2,
            "error did not fall from tol {:e} to {:e}: {:e} → {:e}",
            w[0].0,
            w[1].0,
            w[0].2,
            w[1].2
        );
    }
    // Every controlled run is cheaper than every fixed-step run that is at
    // least as accurate (and some fixed-step run is as accurate).
    for &(tol, steps, err) in &controlled_runs {
        let matching: Vec<&(usize, f64)> = fixed_runs.iter().filter(|(_, e)| *e <= err).collect();
        if let Some((fixed_steps, fixed_err)) = matching.first() {
            assert!(
                steps < *fixed_steps,
                "tol {tol:e}: {steps} steps for error {err:.2e}; the fixed step needs {fixed_steps} for {fixed_err:.2e}"
            );
        }
    }
    assert!(
        fixed_runs.iter().any(|(_, e)| *e <= controlled_runs[0].2),
        "no fixed step as accurate as tol 1e-4: {fixed_runs:?}"
    );
}

#[test]
fn a_fixed_step_run_is_the_same_integrator_as_before() {
    // Without control the run takes exactly t_end/h steps and rejects none.
    let ch = pendulum(4);
    let r = fall(&ch, fixed(1e-3), 0.2);
    assert_eq!((r.steps, r.rejected), (200, 0));
}
