//! Rigid parts and ANCF chains in one model (`large::mixed`), with rigid
//! parts written by hand (closed forms), so that the runtime is checked
//! apart from the generator.
//!
//! Physics checked:
//! - **Agreement with the point mass at a cable end**: a Berzeri–Shabana
//!   cable pinned at the origin whose free end is pinned to a rigid
//!   particle (two coordinates, `M = m I`) moves as the same cable with an
//!   `end_mass` (the particle eliminated into the node): the two
//!   formulations are algebraically the same system.
//! - **A stiff rod clamped to a rigid pendulum moves as the rigid
//!   compound pendulum**: a rigid link pivoted at the origin carries a
//!   steel ANCF rod clamped at its tip along its axis; the angle follows
//!   the one-degree-of-freedom compound pendulum (total inertia about the
//!   pivot, total gravity moment), with a difference that falls in
//!   proportion to the rod's compliance `1/E`.
//! - **Energy of a free mixed system without damping**: the rigid link
//!   with a soft Berzeri–Shabana rod pinned at its tip; generalized-α with
//!   `ρ∞ = 1` keeps the total energy (rigid kinetic and potential, cable
//!   kinetic, strain and gravity) up to an O(h²) error: it falls by about
//!   4 when `h` halves.
//! - **Constraint residual**: the index-3 method keeps `Φ` at the Newton
//!   tolerance at every step.

use eom_sim::large::ancf::{Chain, ChainSpec, Section, Support, chain};
use eom_sim::large::{AlphaOptions, GeneralizedAlpha, MixedAlpha, MixedModel, RigidPart, State};

const G: f64 = 9.81;

/// A rigid particle moving in the plane, `q = (x, y)`, under gravity;
/// one pinned mount at the particle.
struct Particle {
    m: f64,
}

impl RigidPart for Particle {
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
        // Rows p_x, p_y, p_z, each value then ∂/∂x, ∂/∂y.
        out.copy_from_slice(&[q[0], 1.0, 0.0, q[1], 0.0, 1.0, 0.0, 0.0, 0.0]);
    }
}

/// A uniform rigid link of length `a` and mass `m` pivoted at the origin,
/// `θ` from +x towards +y, gravity along −y; one mount at its tip, the
/// clamp's axis along the link.
struct Link {
    a: f64,
    m: f64,
    clamped: bool,
}

impl RigidPart for Link {
    fn n(&self) -> usize {
        1
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], m: &mut [f64]) {
        m[0] = self.m * self.a * self.a / 3.0;
    }
    fn bias(&self, _t: f64, q: &[f64], _u: &[f64], b: &mut [f64]) {
        b[0] = self.m * G * 0.5 * self.a * q[0].cos();
    }
    fn energy(&self, _t: f64, q: &[f64], u: &[f64]) -> f64 {
        0.5 * self.m * self.a * self.a / 3.0 * u[0] * u[0] + self.m * G * 0.5 * self.a * q[0].sin()
    }
    fn attachments(&self, _t: f64, q: &[f64], out: &mut [f64]) {
        let (s, c) = q[0].sin_cos();
        let a = self.a;
        let mut rows = vec![a * c, -a * s, a * s, a * c, 0.0, 0.0];
        if self.clamped {
            // n1 = z × axis = (−sin, cos, 0), n2 = z.
            rows.extend([-s, -c, c, -s, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        }
        out.copy_from_slice(&rows);
    }
}

/// Berzeri and Shabana's (2000) soft rod.
fn berzeri_section() -> Section {
    Section {
        e: 0.7e6,
        rho: 5540.0,
        area: 0.0018,
        inertia: 1.215e-8,
        ..Section::default()
    }
}

fn cable(start: [f64; 3], end: [f64; 3], elements: usize, section: Section) -> ChainSpec {
    ChainSpec {
        kernel: "Cable2D".into(),
        start,
        end,
        elements,
        section,
        start_support: Support::Free,
        end_support: Support::Free,
        end_force: [0.0; 3],
        end_mass: 0.0,
        gravity: [0.0, -G, 0.0],
    }
}

fn build(spec: &ChainSpec) -> Chain {
    chain(spec).unwrap_or_else(|e| panic!("{e}"))
}

fn opts(h: f64, rho_inf: f64) -> AlphaOptions {
    AlphaOptions {
        h,
        rho_inf,
        ..AlphaOptions::default()
    }
}

#[test]
fn a_cable_pinned_to_a_rigid_particle_moves_as_one_with_an_end_mass() {
    let (l, m, ne, h, t_end) = (1.2, 0.5, 8, 1e-3, 0.4);
    // Reference: the end mass eliminated into the node.
    let mut spec = cable([0.0; 3], [l, 0.0, 0.0], ne, berzeri_section());
    spec.start_support = Support::Pinned;
    spec.end_mass = m;
    let reference = build(&spec);
    let rm = &reference.model;
    let state = State {
        t: 0.0,
        q: rm.restrict(rm.q0()),
        v: vec![0.0; rm.n_free()],
    };
    let mut ga = GeneralizedAlpha::new(rm, state, opts(h, 1.0)).unwrap_or_else(|e| panic!("{e}"));
    ga.run_to(t_end, |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let want = reference.node_position(ga.q_full(), ne);
    // Mixed: the same cable, its end pinned to a particle of mass m.
    spec.end_mass = 0.0;
    let ch = build(&spec);
    let at = ch.attachment("rod.end", true, false);
    let mixed = MixedModel::new(ch.model, Box::new(Particle { m }), vec![at])
        .unwrap_or_else(|e| panic!("{e}"));
    let state = mixed.initial_state(0.0, &[l, 0.0], &[0.0, 0.0]);
    let mut ma = MixedAlpha::new(&mixed, state, opts(h, 1.0)).unwrap_or_else(|e| panic!("{e}"));
    ma.run_to(t_end, |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    let q = mixed.structural_full(&ma.state().q);
    let got = [q[ne * 4], q[ne * 4 + 1]];
    let particle = &ma.state().q[mixed.n_structural()..];
    let err = ((got[0] - want[0]).powi(2) + (got[1] - want[1]).powi(2)).sqrt();
    println!(
        "tip at {t_end} s: mixed ({:.9}, {:.9}), end mass ({:.9}, {:.9}), |Δ| {err:.2e} m; particle ({:.9}, {:.9}); max |Φ| {:.2e}",
        got[0],
        got[1],
        want[0],
        want[1],
        particle[0],
        particle[1],
        ma.stats.max_constraint_residual
    );
    // Both solve the same equations to the Newton tolerance (1e-10).
    assert!(err < 1e-8, "got {got:?}, want {want:?}");
    assert!((particle[0] - got[0]).abs() < 1e-9 && (particle[1] - got[1]).abs() < 1e-9);
    assert!(ma.stats.max_constraint_residual < 1e-9);
}

/// The compound pendulum's angle at `t_end` (RK4 with a fine step):
/// `I θ̈ = −g S cos θ`, released at rest from `θ = 0`.
fn compound_angle(inertia: f64, moment: f64, t_end: f64) -> f64 {
    let n = 20_000;
    let h = t_end / n as f64;
    let f = |th: f64| -G * moment * th.cos() / inertia;
    let (mut th, mut w) = (0.0_f64, 0.0_f64);
    for _ in 0..n {
        let (k1t, k1w) = (w, f(th));
        let (k2t, k2w) = (w + 0.5 * h * k1w, f(th + 0.5 * h * k1t));
        let (k3t, k3w) = (w + 0.5 * h * k2w, f(th + 0.5 * h * k2t));
        let (k4t, k4w) = (w + h * k3w, f(th + h * k3t));
        th += h / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t);
        w += h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
    }
    th
}

/// The link's angle at `t_end` with a steel rod of modulus `e` clamped at
/// its tip, and the largest constraint residual.
fn link_with_rod(e: f64, t_end: f64) -> (f64, f64) {
    let (a, m_link, l, side): (f64, f64, f64, f64) = (0.3, 1.0, 0.5, 0.02);
    let section = Section {
        e,
        rho: 7800.0,
        area: side * side,
        inertia: side.powi(4) / 12.0,
        ..Section::default()
    };
    let ch = build(&cable([a, 0.0, 0.0], [a + l, 0.0, 0.0], 4, section));
    let at = ch.attachment("rod.start", false, true);
    let link = Link {
        a,
        m: m_link,
        clamped: true,
    };
    let mixed =
        MixedModel::new(ch.model, Box::new(link), vec![at]).unwrap_or_else(|e| panic!("{e}"));
    let state = mixed.initial_state(0.0, &[0.0], &[0.0]);
    let mut ma = MixedAlpha::new(&mixed, state, opts(1e-3, 0.9)).unwrap_or_else(|e| panic!("{e}"));
    ma.run_to(t_end, |_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    (
        ma.state().q[mixed.n_structural()],
        ma.stats.max_constraint_residual,
    )
}

#[test]
fn a_stiff_rod_clamped_to_a_rigid_link_swings_as_the_rigid_compound() {
    let (a, m_link, l, side, rho): (f64, f64, f64, f64, f64) = (0.3, 1.0, 0.5, 0.02, 7800.0);
    let mu = rho * side * side;
    // About the pivot: the link (m a²/3) and the rod from a to a + L.
    let inertia = m_link * a * a / 3.0 + mu * ((a + l).powi(3) - a.powi(3)) / 3.0;
    let moment = m_link * a / 2.0 + mu * l * (a + l / 2.0);
    let t_end = 0.3;
    let want = compound_angle(inertia, moment, t_end);
    let (soft, r1) = link_with_rod(2e9, t_end);
    let (stiff, r2) = link_with_rod(2e10, t_end);
    let (d1, d2) = ((soft - want).abs(), (stiff - want).abs());
    println!(
        "θ({t_end}) compound {want:.9}, E = 2e9: {soft:.9} (Δ {d1:.2e}), E = 2e10: {stiff:.9} (Δ {d2:.2e}); max |Φ| {r1:.1e}, {r2:.1e}"
    );
    // The flexible model's difference from the rigid compound is the rod's
    // compliance: ten times stiffer, about ten times closer (the
    // integrator's own error, O(h²) at h = 1e-3, is far below).
    assert!(d2 < 2e-3 * want.abs(), "Δ {d2} at E = 2e10");
    assert!(d1 / d2 > 5.0 && d1 / d2 < 20.0, "ratio {}", d1 / d2);
    assert!(r1 < 1e-9 && r2 < 1e-9, "{r1} {r2}");
}

/// Largest energy error over `[0, t_end]` of the link with a soft rod
/// pinned at its tip, step `h`, no damping, `ρ∞ = 1`.
fn energy_error(h: f64, t_end: f64) -> (f64, f64) {
    let a = 0.3;
    let ch = build(&cable(
        [a, 0.0, 0.0],
        [a + 1.2, 0.0, 0.0],
        8,
        berzeri_section(),
    ));
    let at = ch.attachment("rod.start", false, false);
    let link = Link {
        a,
        m: 0.5,
        clamped: false,
    };
    let mixed =
        MixedModel::new(ch.model, Box::new(link), vec![at]).unwrap_or_else(|e| panic!("{e}"));
    let state = mixed.initial_state(0.0, &[0.0], &[0.0]);
    let e0 = mixed.energy(&state);
    let mut ma = MixedAlpha::new(&mixed, state, opts(h, 1.0)).unwrap_or_else(|e| panic!("{e}"));
    let mut worst: f64 = 0.0;
    ma.run_to(t_end, |s, _| {
        worst = worst.max((mixed.energy(s) - e0).abs());
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (worst, ma.stats.max_constraint_residual)
}

#[test]
fn a_free_mixed_system_keeps_its_energy_to_second_order() {
    let t_end = 0.5;
    let (e1, r1) = energy_error(2e-3, t_end);
    let (e2, r2) = energy_error(1e-3, t_end);
    let order = (e1 / e2).log2();
    println!(
        "max |ΔE| over {t_end} s: h = 2e-3 {e1:.3e} J, h = 1e-3 {e2:.3e} J, order {order:.2}; max |Φ| {r1:.1e}, {r2:.1e}"
    );
    // The energy released by the fall is about (m_link a/2 + ρA L (a + L/2)) g
    // sin θ ~ 10 J; the error is a small fraction and second order.
    assert!(e2 < 1e-2, "{e2}");
    assert!(order > 1.7 && order < 2.5, "order {order}");
    assert!(r1 < 1e-9 && r2 < 1e-9, "{r1} {r2}");
}

#[test]
fn a_start_off_the_marker_is_refused() {
    let ch = build(&cable(
        [0.31, 0.0, 0.0],
        [1.5, 0.0, 0.0],
        4,
        berzeri_section(),
    ));
    let at = ch.attachment("rod.start", false, false);
    let link = Link {
        a: 0.3,
        m: 0.5,
        clamped: false,
    };
    let mixed =
        MixedModel::new(ch.model, Box::new(link), vec![at]).unwrap_or_else(|e| panic!("{e}"));
    let state = mixed.initial_state(0.0, &[0.0], &[0.0]);
    let Err(e) = MixedAlpha::new(&mixed, state, opts(1e-3, 1.0)) else {
        panic!("a cable end 1 cm from its marker was accepted");
    };
    let text = e.to_string();
    assert!(
        text.contains("`rod.start` is 1.000e-2 m from its marker"),
        "{text}"
    );
}
