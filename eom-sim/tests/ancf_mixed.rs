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
//! - **Several chains in one structure** (`ancf::chains`): chains of three
//!   kernels (a planar cable with an end mass and force, a spatial cable,
//!   a planar beam) laid out one after the other give exactly (bitwise)
//!   each chain's own initial coordinates, loads, mass matrix, internal
//!   forces and tangent as diagonal blocks, and nothing between them; a
//!   chain with a gravity of its own keeps it; a chain that cannot be
//!   built is named by its index.
//! - **Independent subsystems in one mixed model move as each alone**: two
//!   rigid links, one with a soft rod pinned at its tip, one with a stiffer
//!   rod of the Green-strain kernel clamped at its tip, and a spatial cable
//!   pinned to ground, all in one model (one structure, one rigid part of
//!   two coordinates, three attachments), against each in a model of its
//!   own: the step equations are the same block-diagonal system, so with
//!   full Newton the states agree to round-off (1e-12).

use eom_sim::large::ancf::{Chain, ChainSpec, Section, Support, chain, chains};
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
        kernel: eom_sim::elements::Element::Cable2D,
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

/// A small deterministic generator for test states.
struct Lcg(u64);

impl Lcg {
    /// Uniform in `[-1, 1)`.
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// The three chains of the layout test: a planar cable pinned at its start
/// with an end mass and an end force, a spatial cable clamped at its
/// start, a planar beam clamped at both ends.
fn three_chains() -> Vec<ChainSpec> {
    let mut a = cable([0.0; 3], [1.2, 0.0, 0.0], 5, berzeri_section());
    a.start_support = Support::Pinned;
    a.end_mass = 0.3;
    a.end_force = [0.5, 2.0, 0.0];
    let mut b = cable([0.0, 1.0, 0.5], [0.6, 1.5, 0.1], 3, berzeri_section());
    b.kernel = eom_sim::elements::Element::Cable3D;
    b.start_support = Support::Clamped;
    let section = Section {
        e: 1e7,
        nu: 0.3,
        rho: 1000.0,
        b: 0.05,
        h: 0.02,
        area: 0.001,
        inertia: 0.05 * 0.02_f64.powi(3) / 12.0,
        ..Section::default()
    };
    let mut c = cable([-1.0, 0.0, 0.0], [-1.0, -1.0, 0.0], 4, section);
    c.kernel = eom_sim::elements::Element::Beam2D;
    c.start_support = Support::Clamped;
    c.end_support = Support::Clamped;
    vec![a, b, c]
}

#[test]
fn chains_in_one_structure_are_each_chain_alone_block_by_block() {
    let specs = three_chains();
    let all = chains(&specs).unwrap_or_else(|e| panic!("{e}"));
    let alone: Vec<Chain> = specs.iter().map(build).collect();
    let m = &all.model;
    assert_eq!(
        m.n_full(),
        alone.iter().map(|c| c.model.n_full()).sum::<usize>()
    );
    assert_eq!(
        m.n_free(),
        alone.iter().map(|c| c.model.n_free()).sum::<usize>()
    );
    assert_eq!(
        m.mass().pattern().nnz(),
        alone
            .iter()
            .map(|c| c.model.mass().pattern().nnz())
            .sum::<usize>(),
        "no entry couples two chains"
    );
    // A deformed state and velocities, the same for the whole and the parts.
    let mut rng = Lcg(7);
    let q: Vec<f64> = m.q0().iter().map(|x| x + 0.05 * rng.next()).collect();
    let qd: Vec<f64> = (0..m.n_full()).map(|_| rng.next()).collect();
    let x = m.restrict(&q);
    let xd = m.restrict(&qd);
    let (q, qd) = (m.expand(&x), m.expand_rate(&xd));
    let mut f_all = vec![0.0; m.n_free()];
    m.internal(&q, &qd, &mut vec![0.0; m.n_full()], &mut f_all);
    let mut k_all = eom_sim::large::SparseMatrix::zeros(m.pattern().clone());
    m.jacobian(&q, &qd, 0.7, 0.3, 1.1, &mut k_all);
    let (mut full_at, mut free_at) = (0, 0);
    for (k, (part, ch)) in all.parts.iter().zip(&alone).enumerate() {
        let cm = &ch.model;
        let (nf, nx) = (cm.n_full(), cm.n_free());
        assert_eq!(part.offset, full_at, "chain {k}'s offset");
        assert_eq!((part.kernel, part.nodes), (ch.kernel, ch.nodes));
        let full = full_at..full_at + nf;
        assert_eq!(&m.q0()[full.clone()], cm.q0(), "chain {k}: q0");
        assert_eq!(
            &m.load_full()[full.clone()],
            cm.load_full(),
            "chain {k}: loads"
        );
        let (qk, qdk) = (&q[full.clone()], &qd[full.clone()]);
        let mut f = vec![0.0; nx];
        cm.internal(qk, qdk, &mut vec![0.0; nf], &mut f);
        assert_eq!(&f_all[free_at..free_at + nx], &f[..], "chain {k}: forces");
        let mut kk = eom_sim::large::SparseMatrix::zeros(cm.pattern().clone());
        cm.jacobian(qk, qdk, 0.7, 0.3, 1.1, &mut kk);
        for (i, j, slot) in cm.pattern().entries() {
            let (gi, gj) = (free_at + i, free_at + j);
            assert_eq!(
                m.mass().get(gi, gj),
                cm.mass().values[slot],
                "chain {k}: M[{i}][{j}]"
            );
            assert_eq!(k_all.get(gi, gj), kk.values[slot], "chain {k}: K[{i}][{j}]");
        }
        // The node reader: node j of the chain is node j of the part.
        for j in 0..ch.nodes {
            assert_eq!(part.node_position(&q, j), ch.node_position(qk, j));
        }
        full_at += nf;
        free_at += nx;
    }
    let strain: f64 = alone
        .iter()
        .zip(&all.parts)
        .map(|(c, p)| {
            c.model
                .strain_energy(&q[p.offset..p.offset + c.model.n_full()])
        })
        .sum();
    assert!((m.strain_energy(&q) - strain).abs() <= 1e-12 * strain.abs());
    // A chain with a gravity of its own keeps it, and a distributed load
    // goes on its chain only.
    let mut specs2 = specs.clone();
    specs2[1].gravity = [0.0, 0.0, -3.0];
    let mut two = chains(&specs2).unwrap_or_else(|e| panic!("{e}"));
    two.add_distributed_load(2, [0.0, -4.0, 0.0]);
    let mut mid = build(&specs2[1]);
    let mut last = build(&specs2[2]);
    last.model.add_distributed_load([0.0, -4.0, 0.0]);
    mid.model.add_distributed_load([0.0; 3]);
    for (part, ch) in two.parts.iter().zip([&alone[0], &mid, &last]) {
        let n = ch.model.n_full();
        let got = &two.model.load_full()[part.offset..part.offset + n];
        for (g, w) in got.iter().zip(ch.model.load_full()) {
            assert!((g - w).abs() <= 1e-15 * (1.0 + w.abs()), "{g} against {w}");
        }
    }
    // The second chain cannot be built: it is named.
    let mut bad = specs;
    bad[1].elements = 0;
    let Err(e) = chains(&bad) else {
        panic!("a chain without elements was accepted")
    };
    assert_eq!(e.chain, 1);
    assert!(
        e.to_string()
            .contains("chain 1: a chain needs at least one element")
    );
}

/// Two rigid parts side by side as one: coordinates `(q_a, q_b)`, block-
/// diagonal mass, the mounts of `a` (rows `rows_a`) then those of `b`.
struct Both<A, B> {
    a: A,
    b: B,
    rows_a: usize,
    rows_b: usize,
}

impl<A: RigidPart, B: RigidPart> RigidPart for Both<A, B> {
    fn n(&self) -> usize {
        self.a.n() + self.b.n()
    }
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut [f64]) {
        let (na, nb, n) = (self.a.n(), self.b.n(), self.n());
        let (mut ma, mut mb) = (vec![0.0; na * na], vec![0.0; nb * nb]);
        self.a.mass_matrix(t, &q[..na], &mut ma);
        self.b.mass_matrix(t, &q[na..], &mut mb);
        m.fill(0.0);
        for i in 0..na {
            m[i * n..i * n + na].copy_from_slice(&ma[i * na..(i + 1) * na]);
        }
        for i in 0..nb {
            m[(na + i) * n + na..(na + i + 1) * n].copy_from_slice(&mb[i * nb..(i + 1) * nb]);
        }
    }
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut [f64]) {
        let na = self.a.n();
        self.a.bias(t, &q[..na], &u[..na], &mut b[..na]);
        self.b.bias(t, &q[na..], &u[na..], &mut b[na..]);
    }
    fn energy(&self, t: f64, q: &[f64], u: &[f64]) -> f64 {
        let na = self.a.n();
        self.a.energy(t, &q[..na], &u[..na]) + self.b.energy(t, &q[na..], &u[na..])
    }
    fn attachments(&self, t: f64, q: &[f64], out: &mut [f64]) {
        let (na, nb, n) = (self.a.n(), self.b.n(), self.n());
        let mut ra = vec![0.0; self.rows_a * (1 + na)];
        let mut rb = vec![0.0; self.rows_b * (1 + nb)];
        self.a.attachments(t, &q[..na], &mut ra);
        self.b.attachments(t, &q[na..], &mut rb);
        out.fill(0.0);
        for r in 0..self.rows_a {
            out[r * (1 + n)..r * (1 + n) + 1 + na]
                .copy_from_slice(&ra[r * (1 + na)..(r + 1) * (1 + na)]);
        }
        for r in 0..self.rows_b {
            let at = (self.rows_a + r) * (1 + n);
            let from = &rb[r * (1 + nb)..(r + 1) * (1 + nb)];
            out[at] = from[0];
            out[at + 1 + na..at + 1 + n].copy_from_slice(&from[1..]);
        }
    }
}

/// No rigid body at all (a structure alone through the mixed runtime).
struct Nothing;

impl RigidPart for Nothing {
    fn n(&self) -> usize {
        0
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], _m: &mut [f64]) {}
    fn bias(&self, _t: f64, _q: &[f64], _u: &[f64], _b: &mut [f64]) {}
    fn energy(&self, _t: f64, _q: &[f64], _u: &[f64]) -> f64 {
        0.0
    }
    fn attachments(&self, _t: f64, _q: &[f64], _out: &mut [f64]) {}
}

/// The subsystems of the independence test: a soft rod pinned at the tip
/// of link 1 (a = 0.3 m), a stiffer Green-strain rod clamped at the tip of
/// link 2 (a = 0.2 m), a spatial cable pinned to ground.
fn independent_chains() -> (Vec<ChainSpec>, Link, Link) {
    let a = cable([0.3, 0.0, 0.0], [1.5, 0.0, 0.0], 6, berzeri_section());
    let mut b = cable(
        [0.2, 0.0, 0.0],
        [0.7, 0.0, 0.0],
        4,
        Section {
            e: 2e8,
            rho: 2700.0,
            area: 1e-4,
            inertia: 1e-8 / 12.0,
            ..Section::default()
        },
    );
    b.kernel = eom_sim::elements::Element::Cable2DGreen;
    let mut c = cable([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 4, berzeri_section());
    c.kernel = eom_sim::elements::Element::Cable3D;
    c.start_support = Support::Pinned;
    c.gravity = [0.0, -G, 0.0];
    let l1 = Link {
        a: 0.3,
        m: 0.5,
        clamped: false,
    };
    let l2 = Link {
        a: 0.2,
        m: 0.4,
        clamped: true,
    };
    (vec![a, b, c], l1, l2)
}

#[test]
fn independent_subsystems_in_one_mixed_model_move_as_each_alone() {
    let (h, t_end) = (1e-3, 0.3);
    let full_newton = AlphaOptions {
        h,
        rho_inf: 0.9,
        reuse_matrix: false,
        ..AlphaOptions::default()
    };
    let run = |mixed: &MixedModel<'_>, q_r: &[f64]| {
        let u = vec![0.0; q_r.len()];
        let state = mixed.initial_state(0.0, q_r, &u);
        let mut ma =
            MixedAlpha::new(mixed, state, full_newton.clone()).unwrap_or_else(|e| panic!("{e}"));
        ma.run_to(t_end, |_, _| {})
            .unwrap_or_else(|e| panic!("{e}"));
        (ma.state().clone(), ma.stats.max_constraint_residual)
    };
    // Each alone.
    let (specs, l1, l2) = independent_chains();
    let c1 = build(&specs[0]);
    let at1 = c1.attachment("a.start", false, false);
    let m1 = MixedModel::new(c1.model, Box::new(l1), vec![at1]).unwrap_or_else(|e| panic!("{e}"));
    let c2 = build(&specs[1]);
    let at2 = c2.attachment("b.start", false, true);
    let m2 = MixedModel::new(c2.model, Box::new(l2), vec![at2]).unwrap_or_else(|e| panic!("{e}"));
    let c3 = build(&specs[2]);
    let m3 = MixedModel::new(c3.model, Box::new(Nothing), vec![]).unwrap_or_else(|e| panic!("{e}"));
    let (s1, _) = run(&m1, &[0.0]);
    let (s2, _) = run(&m2, &[0.0]);
    let (s3, _) = run(&m3, &[]);
    // All in one.
    let (specs, l1, l2) = independent_chains();
    let all = chains(&specs).unwrap_or_else(|e| panic!("{e}"));
    let ats = vec![
        all.parts[0].attachment("a.start", false, false),
        all.parts[1].attachment("b.start", false, true),
    ];
    let both = Both {
        a: l1,
        b: l2,
        rows_a: 3,
        rows_b: 9,
    };
    let m = MixedModel::new(all.model, Box::new(both), ats).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.n_constraints(), m1.n_constraints() + m2.n_constraints());
    let (s, residual) = run(&m, &[0.0, 0.0]);
    // y = (x₁, x₂, x₃, θ₁, θ₂) against (x₁, θ₁), (x₂, θ₂), (x₃).
    let (n1, n2, n3) = (m1.n_structural(), m2.n_structural(), m3.n_structural());
    let mut want_q = Vec::new();
    let mut want_v = Vec::new();
    for (st, n) in [(&s1, n1), (&s2, n2), (&s3, n3)] {
        want_q.extend_from_slice(&st.q[..n]);
        want_v.extend_from_slice(&st.v[..n]);
    }
    for st in [&s1, &s2] {
        want_q.push(st.q[st.q.len() - 1]);
        want_v.push(st.v[st.v.len() - 1]);
    }
    let dq =
        s.q.iter()
            .zip(&want_q)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
    let dv =
        s.v.iter()
            .zip(&want_v)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
    let (th1, th2) = (s.q[n1 + n2 + n3], s.q[n1 + n2 + n3 + 1]);
    println!(
        "after {t_end} s: θ₁ = {th1:.9}, θ₂ = {th2:.9}; one model against each alone: max |Δq| {dq:.1e}, max |Δv| {dv:.1e}; max |Φ| {residual:.1e}"
    );
    assert!(th1 < -0.1 && th2 < -0.1, "the links fell: {th1}, {th2}");
    // A position difference δ comes with a velocity difference of up to
    // γ/(β h) δ (the Newmark update): about 2000 δ here.
    let (gamma, beta) = (
        0.5 + 0.9 / 1.9 - 0.8 / 1.9,
        0.25 * (1.0 + 0.9 / 1.9 - 0.8 / 1.9_f64).powi(2),
    );
    assert!(dq < 1e-12, "Δq {dq:e}");
    assert!(dv < gamma / (beta * h) * 1e-12, "Δv {dv:e}");
    assert!(residual < 1e-9);
}

/// The differenced tangent (`set_tangent(Differences)`: forward
/// differences of the internal forces, columns sharing no row perturbed
/// together) is the elements' generated tangent to the differences'
/// accuracy, `a ∂f/∂q + b ∂f/∂q̇ + c M`, at a deformed and moving state of
/// three chains of three kernels, with Kelvin–Voigt damping in one; and it
/// counts its force evaluations: one at the point and one per colour and
/// block, a few per chain's bandwidth, not one per coordinate.
#[test]
fn the_differenced_tangent_is_the_generated_one_to_the_differences_accuracy() {
    let mut specs = three_chains();
    specs[0].section.damping_axial = 0.7;
    specs[0].section.damping_bending = 0.02;
    let mut all = chains(&specs).unwrap_or_else(|e| panic!("{e}"));
    let mut rng = Lcg(11);
    let m = &all.model;
    let x: Vec<f64> = m
        .restrict(m.q0())
        .iter()
        .map(|x| x + 0.05 * rng.next())
        .collect();
    let xd: Vec<f64> = (0..m.n_free()).map(|_| rng.next()).collect();
    let (q, qd) = (m.expand(&x), m.expand_rate(&xd));
    let (a, b, c) = (0.7, 0.3, 1.1);
    let mut generated = eom_sim::large::SparseMatrix::zeros(m.pattern().clone());
    m.jacobian(&q, &qd, a, b, c, &mut generated);
    all.model.set_tangent(eom_sim::Jacobian::Differences);
    let m = &all.model;
    let mut differenced = eom_sim::large::SparseMatrix::zeros(m.pattern().clone());
    m.jacobian(&q, &qd, a, b, c, &mut differenced);
    let scale = generated.values.iter().fold(0.0_f64, |s, v| s.max(v.abs()));
    for (i, j, slot) in m.pattern().entries() {
        let (g, d) = (generated.values[slot], differenced.values[slot]);
        assert!(
            (g - d).abs() <= 1e-6 * scale,
            "K[{i}][{j}]: generated {g}, differenced {d} (largest entry {scale})"
        );
    }
    let evaluations = m.differenced_evaluations();
    assert!(
        evaluations < m.n_free(),
        "{evaluations} force evaluations for {} coordinates",
        m.n_free()
    );
}

/// The link of [`Link`] driven by a torque `c θ̇` that its `energy` does
/// not count (a negative damper: it feeds energy in), stating an energy
/// source or claiming to have none.
struct Pumped {
    link: Link,
    c: f64,
    claims_passive: bool,
}

impl RigidPart for Pumped {
    fn n(&self) -> usize {
        1
    }
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut [f64]) {
        self.link.mass_matrix(t, q, m);
    }
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut [f64]) {
        self.link.bias(t, q, u, b);
        b[0] -= self.c * u[0];
    }
    fn energy(&self, t: f64, q: &[f64], u: &[f64]) -> f64 {
        self.link.energy(t, q, u)
    }
    fn attachments(&self, t: f64, q: &[f64], out: &mut [f64]) {
        self.link.attachments(t, q, out);
    }
    fn energy_source(&self) -> Option<String> {
        (!self.claims_passive).then(|| "the pump".to_string())
    }
}

/// The link with the soft rod pinned at its tip (as [`energy_error`]),
/// its rigid part pumped by `c θ̇`, run for 0.5 s by `simulate_mixed` at
/// `ρ∞ = 1`.
fn pumped_run(c: f64, claims_passive: bool) -> eom_sim::RunReport {
    let a = 0.3;
    let ch = build(&cable(
        [a, 0.0, 0.0],
        [a + 1.2, 0.0, 0.0],
        8,
        berzeri_section(),
    ));
    let at = ch.attachment("rod.start", false, false);
    let rigid = Pumped {
        link: Link {
            a,
            m: 0.5,
            clamped: false,
        },
        c,
        claims_passive,
    };
    let mixed =
        MixedModel::new(ch.model, Box::new(rigid), vec![at]).unwrap_or_else(|e| panic!("{e}"));
    let layout = eom_sim::large::CableLayout {
        name: "rod".into(),
        kernel: "Cable2D",
        dim: 2,
        node_coords: 4,
        nodes: 9,
        offset: 0,
    };
    let run = eom_sim::large::ElementRun {
        integrator: eom_sim::Integrator::GeneralizedAlpha,
        t_end: 0.5,
        dt: 1e-3,
        rho_inf: 1.0,
        control: None,
        record: false,
        every: None,
    };
    let names = (vec!["theta".to_string()], vec!["theta_dot".to_string()]);
    let (report, _) = eom_sim::large::simulate_mixed(
        &mixed,
        &[layout],
        &[],
        (&[0.0], &[0.0]),
        (&names.0, &names.1),
        &run,
        &mut |_| {},
    )
    .unwrap_or_else(|e| panic!("{e}"));
    report
}

/// A model that can gain no energy and whose energy rises is refused, not
/// reported: the run stops where the rise passes a hundredth of the
/// energies it is made of, with that reason. The same pumped link stating
/// its source runs to the end (gaining energy is its physics), and the
/// passive link (no pump) runs to the end at `ρ∞ = 1`, where
/// generalized-α keeps the energy to about 1e-3 J of its ~10 J
/// ([`a_free_mixed_system_keeps_its_energy_to_second_order`]), far inside
/// the guard.
#[test]
fn a_passive_model_whose_energy_rises_is_refused() {
    // 1 N m s: the stated run gains 5.3 J in 0.5 s; at 0.2 N m s it gains
    // 0.63 J, under a hundredth of the falling rod's ~70 J, and is not
    // refused (the guard's margin, not a proof of passivity).
    let c = 1.0;
    let lying = pumped_run(c, true);
    println!(
        "pumped, claiming passive: {:?}, energy {:?}",
        lying.stop, lying.energy
    );
    match &lying.stop {
        eom_sim::Stop::Failed { t, message } => {
            assert!(message.contains("the energy rose"), "{message}");
            assert!(*t > 0.0 && *t < 0.5, "stopped at {t}");
        }
        other => panic!("a pumped run claiming passivity ran on: {other:?}"),
    }
    let stated = pumped_run(c, false);
    println!(
        "pumped, stated: {:?}, energy {:?}",
        stated.stop, stated.energy
    );
    assert!(
        matches!(stated.stop, eom_sim::Stop::Finished),
        "{:?}",
        stated.stop
    );
    assert!(
        stated.energy[1] > stated.energy[0] + 1.0,
        "the pump feeds energy in: {:?}",
        stated.energy
    );
    let passive = pumped_run(0.0, true);
    assert!(
        matches!(passive.stop, eom_sim::Stop::Finished),
        "{:?}",
        passive.stop
    );
}
