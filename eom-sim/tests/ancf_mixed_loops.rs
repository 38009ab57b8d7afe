//! A rigid part with constraint equations of its own beside an ANCF cable
//! (`large::mixed`, [`RigidPart::constraints`]), with rigid parts written
//! by hand, so that the runtime is checked apart from the generator.
//!
//! Physics checked:
//! - **Two coordinate choices of one system agree to second order**: a
//!   point mass `m` on a massless link of length `a` (a pendulum), carrying
//!   Berzeri and Shabana's soft rod pinned at the mass, written once in its
//!   angle `θ` (no constraint) and once in Cartesian coordinates `(x, y)`
//!   held on the circle by its own equation `x² + y² − a² = 0`. Both are
//!   integrated by the index-3 generalized-α; their difference is the
//!   method's discretisation error and falls by about 4 when `h` halves;
//!   the circle holds at the Newton tolerance at every step.
//! - **Refusals by name**: a start off the circle, and speeds that leave
//!   it.

use eom_sim::large::ancf::{ChainSpec, Section, Support, chain};
use eom_sim::large::{AlphaOptions, MixedAlpha, MixedModel, RigidPart};

const G: f64 = 9.81;

/// A point mass `m` at distance `a` from the origin, angle `θ` from +x
/// towards +y; one pinned mount at the mass.
struct Angle {
    a: f64,
    m: f64,
}

impl RigidPart for Angle {
    fn n(&self) -> usize {
        1
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], m: &mut [f64]) {
        m[0] = self.m * self.a * self.a;
    }
    fn bias(&self, _t: f64, q: &[f64], _u: &[f64], b: &mut [f64]) {
        b[0] = self.m * G * self.a * q[0].cos();
    }
    fn energy(&self, _t: f64, q: &[f64], u: &[f64]) -> f64 {
        0.5 * self.m * self.a * self.a * u[0] * u[0] + self.m * G * self.a * q[0].sin()
    }
    fn attachments(&self, _t: f64, q: &[f64], out: &mut [f64]) {
        let (s, c) = q[0].sin_cos();
        let a = self.a;
        out.copy_from_slice(&[a * c, -a * s, a * s, a * c, 0.0, 0.0]);
    }
}

/// The same mass in `(x, y)`, held on the circle of radius `a` by its own
/// constraint `x² + y² − a² = 0`.
struct Cartesian {
    a: f64,
    m: f64,
}

impl RigidPart for Cartesian {
    fn n(&self) -> usize {
        2
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], m: &mut [f64]) {
        m.copy_from_slice(&[self.m, 0.0, 0.0, self.m]);
    }
    fn bias(&self, _t: f64, _q: &[f64], _u: &[f64], b: &mut [f64]) {
        b.copy_from_slice(&[0.0, self.m * G]);
    }
    fn energy(&self, _t: f64, q: &[f64], u: &[f64]) -> f64 {
        0.5 * self.m * (u[0] * u[0] + u[1] * u[1]) + self.m * G * q[1]
    }
    fn attachments(&self, _t: f64, q: &[f64], out: &mut [f64]) {
        out.copy_from_slice(&[q[0], 1.0, 0.0, q[1], 0.0, 1.0, 0.0, 0.0, 0.0]);
    }
    fn n_constraints(&self) -> usize {
        1
    }
    fn constraint_names(&self) -> Vec<String> {
        vec!["circle".into()]
    }
    fn constraints(&self, _t: f64, q: &[f64], out: &mut [f64]) {
        out.copy_from_slice(&[
            q[0] * q[0] + q[1] * q[1] - self.a * self.a,
            2.0 * q[0],
            2.0 * q[1],
        ]);
    }
}

const A: f64 = 0.3;
const M: f64 = 0.5;

/// Berzeri and Shabana's soft rod from the mass at `(a, 0)` along +x.
fn rod() -> ChainSpec {
    ChainSpec {
        kernel: eom_sim::elements::Element::Cable2D,
        start: [A, 0.0, 0.0],
        end: [A + 1.2, 0.0, 0.0],
        elements: 8,
        section: Section {
            e: 0.7e6,
            rho: 5540.0,
            area: 0.0018,
            inertia: 1.215e-8,
            ..Section::default()
        },
        start_support: Support::Free,
        end_support: Support::Free,
        end_force: [0.0; 3],
        end_mass: 0.0,
        gravity: [0.0, -G, 0.0],
    }
}

fn model(rigid: Box<dyn RigidPart>) -> MixedModel<'static> {
    let ch = chain(&rod()).unwrap_or_else(|e| panic!("{e}"));
    let at = ch.attachment("rod.start", false, false);
    MixedModel::new(ch.model, rigid, vec![at]).unwrap_or_else(|e| panic!("{e}"))
}

fn opts(h: f64) -> AlphaOptions {
    AlphaOptions {
        h,
        rho_inf: 0.9,
        ..AlphaOptions::default()
    }
}

/// The mass's position at `t_end` in the Cartesian and the angle
/// formulation, and the largest circle residual over the run.
fn both(h: f64, t_end: f64) -> ([f64; 2], [f64; 2], f64) {
    let angle = model(Box::new(Angle { a: A, m: M }));
    let mut ga = MixedAlpha::new(&angle, angle.initial_state(0.0, &[0.0], &[0.0]), opts(h))
        .unwrap_or_else(|e| panic!("{e}"));
    ga.run_to(t_end, |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let th = ga.state().q[angle.n_structural()];
    let want = [A * th.cos(), A * th.sin()];
    let cart = model(Box::new(Cartesian { a: A, m: M }));
    assert_eq!(cart.rigid_constraint_rows(), 2..3);
    let mut gc = MixedAlpha::new(
        &cart,
        cart.initial_state(0.0, &[A, 0.0], &[0.0, 0.0]),
        opts(h),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut worst = 0.0_f64;
    gc.run_to(t_end, |s, _| {
        let phi = cart.constraint_residual(s.t, &s.q);
        worst = worst.max(phi[2].abs());
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let ns = cart.n_structural();
    let got = [gc.state().q[ns], gc.state().q[ns + 1]];
    (got, want, worst)
}

#[test]
fn a_mass_held_on_a_circle_by_its_own_constraint_moves_as_the_pendulum_in_its_angle() {
    let t_end = 0.5;
    let mut diffs = Vec::new();
    for h in [2e-3, 1e-3, 5e-4] {
        let (got, want, worst) = both(h, t_end);
        let d = ((got[0] - want[0]).powi(2) + (got[1] - want[1]).powi(2)).sqrt();
        println!(
            "h = {h:e}: Cartesian ({:.9}, {:.9}), angle ({:.9}, {:.9}), |Δ| {d:.3e} m; circle |Φ| {worst:.1e}",
            got[0], got[1], want[0], want[1]
        );
        assert!(worst < 1e-10, "circle residual {worst:e}");
        diffs.push(d);
    }
    // The mass fell: more than 10 cm below its start.
    let (_, want, _) = both(5e-4, t_end);
    assert!(want[1] < -0.1, "{want:?}");
    for w in diffs.windows(2) {
        let order = (w[0] / w[1]).log2();
        println!("order {order:.2}");
        assert!(order > 1.7 && order < 2.5, "order {order}");
    }
}

#[test]
fn a_start_off_the_circle_or_leaving_it_is_refused_by_name() {
    let cart = model(Box::new(Cartesian { a: A, m: M }));
    // The mass 1 mm off the circle (and the rod's start with it).
    let mut state = cart.initial_state(0.0, &[A, 0.0], &[0.0, 0.0]);
    let ns = cart.n_structural();
    state.q[ns + 1] = 1e-3;
    state.q[1] = 1e-3;
    let Err(e) = MixedAlpha::new(&cart, state, opts(1e-3)) else {
        panic!("a start off the circle was accepted");
    };
    let text = e.to_string();
    println!("{text}");
    assert!(
        text.contains("the rigid part's constraint `circle` is 1.000e-6 off"),
        "{text}"
    );
    // On the circle, moving off it radially at 1 m/s.
    let state = cart.initial_state(0.0, &[A, 0.0], &[1.0, 0.0]);
    let Err(e) = MixedAlpha::new(&cart, state, opts(1e-3)) else {
        panic!("speeds leaving the circle were accepted");
    };
    let text = e.to_string();
    println!("{text}");
    assert!(text.contains("`circle` changes at 6.000e-1/s"), "{text}");
}
