//! Step-size control of the one generalized-α (`eom_sim::large::alpha`),
//! on Berzeri and Shabana's falling ANCF pendulum (L = 1.2 m,
//! A = 0.0018 m², I = 1.215e-8 m⁴, ρ = 5540 kg/m³, E = 0.7e6 Pa, pinned at
//! the origin, released horizontal; 8 `Cable2D` elements).
//!
//! Physics and numerics checked:
//! - The tip against a fixed-step reference (h = 1e-4 s, whose own O(h²)
//!   error, estimated from h = 2e-4 s by Richardson, is stated and must be
//!   well below every error compared), measured as the largest distance
//!   over the run, the tip sampled every 10 ms (cubic Hermite
//!   interpolation between accepted steps). The tip at 1 s alone is a
//!   poor measure: the fixed steps' errors there are not monotone in h
//!   (5e-4 and 2.5e-4 s are within 20 % of each other, a phase crossing of
//!   the tip's oscillation).
//! - The controlled run lands on `t_end` exactly, counts its rejected
//!   steps, and its error falls with the tolerance: by at least a factor
//!   two per decade.
//! - Issue #25's acceptance, against the fixed step's work-precision
//!   curve (log–log between its points): at every tolerance the
//!   controlled run needs fewer accepted steps than the fixed step of
//!   equal error; counting its rejected steps too, it needs fewer at 1e-5
//!   and 1e-6, and more at 1e-3 and 1e-4 (a quarter to a third of its
//!   steps rejected), which the test prints.
//! - The fixed-step path is unchanged (exactly `t_end / h` steps, none
//!   rejected).

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
    /// The tip at t = k · SAMPLE, by cubic Hermite interpolation between
    /// accepted steps.
    samples: Vec<[f64; 2]>,
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
    let tip = |q: &[f64]| {
        let p = ch.node_position(q, ch.nodes - 1);
        [p[0], p[1]]
    };
    let mut prev = (0.0, tip(m.q0()), tip(&m.expand_rate(&ga.state().v)));
    let mut samples = vec![prev.1];
    ga.run_to(t_end, |s, q| {
        worst = worst.max((m.energy(q, &s.v) - e0).abs() / scale);
        let now = (s.t, tip(q), tip(&m.expand_rate(&s.v)));
        loop {
            let t = samples.len() as f64 * SAMPLE;
            if t > now.0 + 1e-12 {
                break;
            }
            let h = now.0 - prev.0;
            let x = (t - prev.0) / h;
            let (x2, x3) = (x * x, x * x * x);
            let w = [
                2.0 * x3 - 3.0 * x2 + 1.0,
                (x3 - 2.0 * x2 + x) * h,
                -2.0 * x3 + 3.0 * x2,
                (x3 - x2) * h,
            ];
            samples.push(
                [0, 1].map(|k| {
                    w[0] * prev.1[k] + w[1] * prev.2[k] + w[2] * now.1[k] + w[3] * now.2[k]
                }),
            );
        }
        prev = now;
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        (ga.state().t - t_end).abs() < 1e-12,
        "ended at {} instead of {t_end}",
        ga.state().t
    );
    Run {
        tip: ch.node_position(ga.q_full(), ch.nodes - 1),
        samples,
        steps: ga.stats.steps,
        rejected: ga.stats.rejected,
        energy: worst,
    }
}

fn rho() -> f64 {
    std::env::var("RHO")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0)
}

fn fixed(h: f64) -> AlphaOptions {
    AlphaOptions {
        h,
        rho_inf: rho(),
        ..AlphaOptions::default()
    }
}

fn controlled(tol: f64) -> AlphaOptions {
    AlphaOptions {
        h: 1e-4,
        rho_inf: rho(),
        control: Some(StepControl::new(tol, tol)),
        ..AlphaOptions::default()
    }
}

/// Sampling interval of the tip, s.
const SAMPLE: f64 = 0.01;

/// The largest distance between two runs' sampled tips.
fn max_distance(a: &Run, b: &Run) -> f64 {
    a.samples
        .iter()
        .zip(&b.samples)
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

#[test]
fn step_size_control_error_falls_with_the_tolerance() {
    let ch = pendulum(8);
    let t_end = 1.0;
    let h_ref: f64 = std::env::var("HREF")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1e-4);
    let reference = fall(&ch, fixed(h_ref), t_end);
    let coarser = fall(&ch, fixed(2.0 * h_ref), t_end);
    println!(
        "reference max-over-run own error ≈ {:.1e} m",
        max_distance(&reference, &coarser) / 3.0
    );
    // Richardson: the reference's own error is a third of its distance to
    // the run at twice the step.
    let reference_error = distance(reference.tip, coarser.tip) / 3.0;
    println!(
        "reference (h = 1e-4): tip {:?}, own error ≈ {reference_error:.1e} m",
        reference.tip
    );
    let reference_max = max_distance(&reference, &coarser) / 3.0;
    // The fixed step's work-precision curve: steps against the largest
    // tip error over the run (sampled every 10 ms).
    let mut curve = Vec::new();
    for h in [4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4] {
        let r = fall(&ch, fixed(h), t_end);
        let err = distance(r.tip, reference.tip);
        let max = max_distance(&r, &reference);
        println!(
            "fixed h = {h:.1e}: {} steps, tip error at 1 s {err:.2e} m, largest over the run {max:.2e} m, energy {:.1e}",
            r.steps, r.energy
        );
        curve.push((r.steps as f64, max));
    }
    // Steps the fixed step needs for `err`, log–log between the two
    // points of the curve around it.
    let fixed_steps_for = |err: f64| -> f64 {
        let w = curve
            .windows(2)
            .find(|w| w[0].1 >= err && err >= w[1].1)
            .unwrap_or_else(|| panic!("{err:e} outside the fixed-step curve {curve:?}"));
        let ((n0, e0), (n1, e1)) = (w[0], w[1]);
        let x = (err / e0).ln() / (e1 / e0).ln();
        (n0.ln() + x * (n1 / n0).ln()).exp()
    };
    let mut controlled_runs = Vec::new();
    for tol in [1e-3, 1e-4, 1e-5, 1e-6] {
        let r = fall(&ch, controlled(tol), t_end);
        let err = distance(r.tip, reference.tip);
        let max = max_distance(&r, &reference);
        let equal = fixed_steps_for(max);
        println!(
            "tol {tol:.0e}: {} steps ({} rejected), tip error at 1 s {err:.2e} m, largest over the run {max:.2e} m \
             (the fixed step needs {equal:.0} steps for it), energy {:.1e}",
            r.steps, r.rejected, r.energy
        );
        assert!(
            max > 3.0 * reference_max,
            "tol {tol:e}: error {max:e} is within the reference's own {reference_max:e}; refine the reference"
        );
        // Issue #25's acceptance: fewer steps than the fixed step of
        // equal error. Accepted steps: at every tolerance. Attempted steps
        // (rejected ones included, each as costly): at 1e-5 and 1e-6; at
        // 1e-3 and 1e-4 the controller rejects a quarter to a third of its
        // steps and loses (BENCHMARKS.md), which is printed, not hidden.
        assert!(
            (r.steps as f64) < equal,
            "tol {tol:e}: {} accepted steps for {max:.2e} m, the fixed step needs {equal:.0}",
            r.steps
        );
        let attempted = (r.steps + r.rejected) as f64;
        if tol <= 1e-5 {
            assert!(
                attempted < equal,
                "tol {tol:e}: {attempted} attempted steps for {max:.2e} m, the fixed step needs {equal:.0}"
            );
        } else if attempted >= equal {
            println!(
                "  tol {tol:e}: {attempted} attempted steps against {equal:.0}: the rejections lose it"
            );
        }
        controlled_runs.push((tol, r.steps, max));
    }
    for w in controlled_runs.windows(2) {
        let (tol_a, steps_a, err_a) = w[0];
        let (tol_b, steps_b, err_b) = w[1];
        assert!(
            err_b < err_a / 2.0,
            "a decade of tolerance ({tol_a:e} → {tol_b:e}) took the error only from {err_a:.2e} to {err_b:.2e}"
        );
        assert!(
            steps_b > steps_a,
            "a tighter tolerance took no more steps: {steps_a} → {steps_b}"
        );
    }
}

#[test]
fn a_fixed_step_run_is_the_same_integrator_as_before() {
    // Without control the run takes exactly t_end/h steps and rejects none.
    let ch = pendulum(4);
    let r = fall(&ch, fixed(1e-3), 0.2);
    assert_eq!((r.steps, r.rejected), (200, 0));
}
