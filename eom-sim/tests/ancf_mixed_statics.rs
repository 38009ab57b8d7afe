//! Static equilibrium of rigid parts and ANCF chains in one model
//! (`large::mixed::statics`), with rigid parts written by hand (closed
//! forms), so that the solver is checked apart from the generator.
//!
//! Physics checked:
//! - **A cable hanging from a sprung pendulum, against the closed form**:
//!   a uniform link (pivot at the origin, torsion spring `k`) carries at
//!   its tip a pinned Cable2D chain with an end mass. A pinned cable
//!   transmits no moment, and as a free body in equilibrium it hangs
//!   vertically with the marker carrying its whole weight, `W = (ρ A L +
//!   m_e) g`, at the tip. So `k θ + (m g a/2 + W a) cos θ = 0`, which a
//!   scalar Newton solves to round-off; the chain's stretch is the hanging
//!   bar's, `(m_e g L + ρ A g L²/2)/(EA)`, which cubic elements represent
//!   exactly (the axial strain is linear along a vertical cable). The same
//!   with a spatial `Cable3D` rope (free to swing out of the plane too).
//! - **The equilibrium is a fixed point of the dynamics**: the index-3
//!   generalized-α started there at rest stays there; its consistent
//!   multipliers are the static reactions.
//! - **Agreement with the pure-structure statics**: a cable pinned between
//!   the tip of a link held by a very stiff spring and a ground pin takes
//!   the shape of the same cable pinned between two fixed points (the
//!   structure-only solver `solve_static`); the difference is the link's
//!   rotation under the cable's pull, falling as `1/k`.
//! - **A stiff rod clamped to a sprung link is the rigid compound**: a
//!   steel rod clamped at the link's tip along its axis; the angle tends
//!   to the one of the rigid link-and-rod, `k θ + (m g a/2 + μ L g (a +
//!   L/2)) cos θ = 0`, with a difference that falls in proportion to the
//!   rod's compliance `1/E`; Newton takes a few iterations per load step.
//! - **Stability**: a link standing upright on a torsion spring is stable
//!   when `k > (m g a/2 + W a)` and unstable below; the solver reports the
//!   sign of the reduced tangent's smallest eigenvalue on either side.
//! - **A mechanism is refused**: a cart on a frictionless horizontal rail
//!   holding a hanging cable can move sideways without any force: the
//!   solve refuses and names the cart's coordinate; the same cart on a
//!   spring solves.

use eom_sim::large::ancf::{Chain, ChainSpec, Section, Support, chain};
use eom_sim::large::{
    AlphaOptions, MixedAlpha, MixedModel, MixedStaticError, RigidPart, Stability, State,
    StaticOptions, solve_static, solve_static_mixed,
};

const G: f64 = 9.81;

/// A uniform link of length `a` and mass `m` pivoted at the origin, `θ`
/// from +x towards +y, gravity along −y, a torsion spring `k (θ − rest)`;
/// one mount at its tip (pinned, or clamped along the link).
struct SprungLink {
    a: f64,
    m: f64,
    k: f64,
    rest: f64,
    clamped: bool,
}

impl RigidPart for SprungLink {
    fn n(&self) -> usize {
        1
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], m: &mut [f64]) {
        m[0] = self.m * self.a * self.a / 3.0;
    }
    fn bias(&self, _t: f64, q: &[f64], _u: &[f64], b: &mut [f64]) {
        b[0] = self.m * G * 0.5 * self.a * q[0].cos() + self.k * (q[0] - self.rest);
    }
    fn energy(&self, _t: f64, q: &[f64], u: &[f64]) -> f64 {
        0.5 * self.m * self.a * self.a / 3.0 * u[0] * u[0]
            + self.m * G * 0.5 * self.a * q[0].sin()
            + 0.5 * self.k * (q[0] - self.rest).powi(2)
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

/// A cart on a horizontal rail (`x`), a spring `k x` (possibly 0); the
/// rail carries its weight; one pinned mount at the cart.
struct Cart {
    m: f64,
    k: f64,
}

impl RigidPart for Cart {
    fn n(&self) -> usize {
        1
    }
    fn mass_matrix(&self, _t: f64, _q: &[f64], m: &mut [f64]) {
        m[0] = self.m;
    }
    fn bias(&self, _t: f64, q: &[f64], _u: &[f64], b: &mut [f64]) {
        b[0] = self.k * q[0];
    }
    fn energy(&self, _t: f64, q: &[f64], u: &[f64]) -> f64 {
        0.5 * self.m * u[0] * u[0] + 0.5 * self.k * q[0] * q[0]
    }
    fn attachments(&self, _t: f64, q: &[f64], out: &mut [f64]) {
        out.copy_from_slice(&[q[0], 1.0, 0.0, 0.0, 0.0, 0.0]);
    }
}

/// A soft steel-like cable (stretch of millimetres under its weight).
fn section() -> Section {
    Section {
        e: 2e7,
        rho: 7800.0,
        area: 1e-4,
        inertia: 1e-9,
        ..Section::default()
    }
}

fn cable(start: [f64; 3], end: [f64; 3], elements: usize) -> ChainSpec {
    ChainSpec {
        kernel: eom_sim::elements::Element::Cable2D,
        start,
        end,
        elements,
        section: section(),
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

/// `k θ + S cos θ = k rest` by Newton (`S` the gravity moment at θ = 0).
fn closed_form_angle(k: f64, rest: f64, s: f64) -> f64 {
    let mut th = rest;
    for _ in 0..100 {
        let f = k * (th - rest) + s * th.cos();
        let df = k - s * th.sin();
        th -= f / df;
    }
    th
}

const A: f64 = 0.5;
const M_LINK: f64 = 1.0;
const L: f64 = 1.0;
const M_END: f64 = 0.5;

/// The link on a spring `k` at angle `theta0` with the cable hanging from
/// its tip (8 elements, end mass).
fn hanging(k: f64, rest: f64, theta0: f64) -> (MixedModel<'static>, Chain) {
    hanging_kernel("Cable2D", k, rest, theta0)
}

/// [`hanging`] with the cable's kernel named.
fn hanging_kernel(kernel: &str, k: f64, rest: f64, theta0: f64) -> (MixedModel<'static>, Chain) {
    let tip = [A * theta0.cos(), A * theta0.sin(), 0.0];
    let mut spec = cable(tip, [tip[0], tip[1] - L, 0.0], 8);
    spec.kernel = kernel.parse().unwrap_or_else(|e| panic!("{e}"));
    spec.end_mass = M_END;
    let reader = build(&spec);
    let ch = build(&spec);
    let at = ch.attachment("rope.start", false, false);
    let link = SprungLink {
        a: A,
        m: M_LINK,
        k,
        rest,
        clamped: false,
    };
    let model =
        MixedModel::new(ch.model, Box::new(link), vec![at]).unwrap_or_else(|e| panic!("{e}"));
    (model, reader)
}

fn weight() -> f64 {
    let s = section();
    (s.rho * s.area * L + M_END) * G
}

#[test]
fn a_cable_hanging_from_a_sprung_pendulum_meets_the_closed_form() {
    let (k, rest) = (20.0, 0.0);
    let (model, ch) = hanging(k, rest, 0.0);
    let sol = solve_static_mixed(&model, 0.0, &[0.0], &StaticOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let w = weight();
    let want = closed_form_angle(k, rest, M_LINK * G * A / 2.0 + w * A);
    let theta = sol.y[model.n_structural()];
    let top = ch.node_position(&sol.q_full, 0);
    let bottom = ch.node_position(&sol.q_full, 8);
    let s = section();
    let ea = s.e * s.area;
    let stretch = (M_END * G * L + s.rho * s.area * G * L * L / 2.0) / ea;
    let reaction = sol.reactions(&model)[0];
    println!(
        "θ = {theta:.12} (closed form {want:.12}, Δ {:.2e}); {} load steps, {} regularised steps, {} factorisations; \
         reaction ({:.9}, {:.9}) N, W = {w:.9} N; stretch {:.9e} m (closed form {stretch:.9e}); |Φ| {:.1e}; {}",
        theta - want,
        sol.steps.len(),
        sol.regularized,
        sol.factorizations,
        reaction[0],
        reaction[1],
        top[1] - bottom[1] - L,
        sol.constraint_residual,
        sol.stability
    );
    for s in &sol.steps {
        println!("  λ = {:.2}: {:?}", s.lambda, s.residuals);
    }
    // Round-off of the force balance (residual tolerance 1e-10 of the
    // loads) and of the rigid block's forward differences.
    assert!((theta - want).abs() < 1e-9, "θ {theta} vs {want}");
    // The marker carries the whole weight, straight up.
    assert!(reaction[0].abs() < 1e-8 && (reaction[1] - w).abs() < 1e-8 * w);
    // The cable hangs vertically from the tip, stretched as the bar.
    assert!((top[0] - A * theta.cos()).abs() < 1e-10 && (top[1] - A * theta.sin()).abs() < 1e-10);
    assert!((bottom[0] - top[0]).abs() < 1e-10, "{top:?} {bottom:?}");
    assert!((top[1] - bottom[1] - L - stretch).abs() < 1e-9 * L);
    assert!(sol.constraint_residual < 1e-12);
    assert!(matches!(sol.stability, Stability::Stable { .. }));
}

#[test]
fn a_spatial_cable_hangs_from_the_pendulum_as_the_planar_one() {
    // Cable3D: the rope may also swing out of the plane, which its tension
    // stiffens; the equilibrium is the planar one (the closed form).
    let (k, rest) = (20.0, 0.0);
    let (model, ch) = hanging_kernel("Cable3D", k, rest, 0.0);
    let sol = solve_static_mixed(&model, 0.0, &[0.0], &StaticOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let want = closed_form_angle(k, rest, M_LINK * G * A / 2.0 + weight() * A);
    let theta = sol.y[model.n_structural()];
    let bottom = ch.node_position(&sol.q_full, 8);
    let reaction = sol.reactions(&model)[0];
    println!(
        "Cable3D: θ = {theta:.12} (closed form {want:.12}); {} regularised; bottom {bottom:?}; reaction {reaction:?}; {}",
        sol.regularized, sol.stability
    );
    assert_eq!(model.n_constraints(), 3);
    assert!((theta - want).abs() < 1e-9, "θ {theta} vs {want}");
    assert!(bottom[2].abs() < 1e-12 && (bottom[0] - A * theta.cos()).abs() < 1e-10);
    assert!((reaction[1] - weight()).abs() < 1e-8 * weight() && reaction[2].abs() < 1e-10);
    assert!(matches!(sol.stability, Stability::Stable { .. }));
}

#[test]
fn the_equilibrium_is_a_fixed_point_of_the_dynamics() {
    let (model, _) = hanging(20.0, 0.0, 0.0);
    let sol = solve_static_mixed(&model, 0.0, &[0.0], &StaticOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let n = model.n();
    let state = State {
        t: 0.0,
        q: sol.y.clone(),
        v: vec![0.0; n],
    };
    let opts = AlphaOptions {
        h: 1e-3,
        rho_inf: 0.8,
        // The integrator's own Newton stops at corrections of `tol` in q,
        // which leave speeds of about `tol γ/(β h)`: tight, so that what
        // is seen is the static residual.
        tol: 1e-14,
        ..AlphaOptions::default()
    };
    let mut ga = MixedAlpha::new(&model, state, opts).unwrap_or_else(|e| panic!("{e}"));
    // The consistent multipliers at rest are the static ones.
    let dl = ga
        .multipliers()
        .iter()
        .zip(&sol.lambda)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let mut drift = 0.0_f64;
    let mut speed = 0.0_f64;
    ga.run_to(0.2, |s, _| {
        for (q, y) in s.q.iter().zip(&sol.y) {
            drift = drift.max((q - y).abs());
        }
        speed = speed.max(s.v.iter().fold(0.0, |m, v| m.max(v.abs())));
    })
    .unwrap_or_else(|e| panic!("{e}"));
    println!("over 0.2 s at rest: |Δy| ≤ {drift:.2e}, |v| ≤ {speed:.2e}; |Δλ| at start {dl:.2e}");
    // The static residual (≤ 1e-10 of the weights, 1e-9 N) over the
    // lightest node mass (a quarter of ρ A L/8 ≈ 0.025 kg) accelerates by
    // at most 4e-8 m/s²: in 0.2 s a node gains less than 1e-8 m/s and
    // moves less than 1e-9 m.
    assert!(drift < 1e-9, "drift {drift}");
    assert!(speed < 1e-8, "speed {speed}");
    assert!(dl < 1e-8 * weight(), "Δλ {dl}");
}

#[test]
fn a_cable_between_a_stiffly_held_link_and_a_pin_takes_the_pure_structures_shape() {
    let ne = 8;
    let (start, end) = ([A, 0.0, 0.0], [A + 1.0, 0.0, 0.0]);
    // The structure alone, pinned at both points.
    let mut spec = cable(start, end, ne);
    spec.start_support = Support::Pinned;
    spec.end_support = Support::Pinned;
    let pure = build(&spec);
    let reference =
        solve_static(&pure.model, &StaticOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let shape = |ch: &Chain, q: &[f64]| -> Vec<[f64; 3]> {
        (0..=ne).map(|j| ch.node_position(q, j)).collect()
    };
    let want = shape(&pure, &reference.q);
    let sag = want.iter().fold(0.0_f64, |m, p| m.max(-p[1]));
    // Mixed: the first end pinned at the tip of a link on a stiff spring.
    let mut errors = Vec::new();
    for k in [1e4, 1e5] {
        let mut spec = cable(start, end, ne);
        spec.end_support = Support::Pinned;
        let ch = build(&spec);
        let reader = build(&spec);
        let at = ch.attachment("rope.start", false, false);
        let link = SprungLink {
            a: A,
            m: M_LINK,
            k,
            rest: 0.0,
            clamped: false,
        };
        let model =
            MixedModel::new(ch.model, Box::new(link), vec![at]).unwrap_or_else(|e| panic!("{e}"));
        let sol = solve_static_mixed(&model, 0.0, &[0.0], &StaticOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let got = shape(&reader, &sol.q_full);
        let err = got
            .iter()
            .zip(&want)
            .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt())
            .fold(0.0, f64::max);
        let theta = sol.y[model.n_structural()];
        println!(
            "k = {k:e}: θ = {theta:.3e}, largest node distance {err:.3e} m (sag {sag:.6} m), tip moved {:.3e} m",
            A * theta.abs()
        );
        // The spring balances the link's weight and the cable's pull at
        // the tip (the marker's force F on the cable, so −F on the link,
        // whose generalized force is ∂p/∂θ · (−F)).
        let f = sol.reactions(&model)[0];
        let (sn, cs) = theta.sin_cos();
        let want_theta = (-M_LINK * G * A / 2.0 * cs + A * sn * f[0] - A * cs * f[1]) / k;
        assert!(
            (theta - want_theta).abs() < 1e-9 * theta.abs(),
            "θ {theta} vs {want_theta}"
        );
        errors.push((err, A * theta.abs()));
    }
    // The difference is the link's give: its tip's displacement (the
    // first node moves with it, the rest of the cable less), ten times
    // smaller for a ten times stiffer spring.
    let (e1, e2) = (errors[0].0, errors[1].0);
    assert!(sag > 0.05, "the cable sags ({sag} m)");
    for (e, tip) in &errors {
        assert!(*e <= 1.001 * tip, "{e} vs the tip's {tip}");
    }
    assert!(e2 < 5e-4 * sag, "{e2}");
    assert!(e1 / e2 > 9.0 && e1 / e2 < 11.0, "ratio {}", e1 / e2);
}

#[test]
fn an_upright_link_is_stable_only_on_a_stiff_enough_spring() {
    // Upright (θ = π/2) is an equilibrium for any k (no gravity moment);
    // gravity's negative stiffness there is (m g a/2 + W a).
    let up = std::f64::consts::FRAC_PI_2;
    let critical = M_LINK * G * A / 2.0 + weight() * A;
    for (factor, stable) in [(2.0, true), (0.5, false)] {
        let (model, _) = hanging(factor * critical, up, up);
        let sol = solve_static_mixed(&model, 0.0, &[up], &StaticOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let theta = sol.y[model.n_structural()];
        println!(
            "k = {factor} × {critical:.4}: θ = {theta:.12}; {}",
            sol.stability
        );
        assert!((theta - up).abs() < 1e-9);
        match (&sol.stability, stable) {
            (Stability::Stable { .. }, true) => {}
            (Stability::Unstable { negative: 1, .. }, false) => {}
            (s, _) => panic!("k = {factor} × critical: {s}"),
        }
    }
}

#[test]
fn a_cart_on_a_frictionless_rail_is_a_mechanism_and_is_refused() {
    let mut spec = cable([0.0; 3], [0.0, -L, 0.0], 8);
    spec.end_mass = M_END;
    for k in [0.0, 50.0] {
        let ch = build(&spec);
        let at = ch.attachment("rope.start", false, false);
        let model = MixedModel::new(ch.model, Box::new(Cart { m: 2.0, k }), vec![at])
            .unwrap_or_else(|e| panic!("{e}"));
        let result = solve_static_mixed(&model, 0.0, &[0.0], &StaticOptions::default());
        if k == 0.0 {
            let Err(e) = result else {
                panic!("a cart without a spring has no isolated equilibrium");
            };
            println!("k = 0: {e}");
            assert!(matches!(e, MixedStaticError::Mechanism { .. }), "{e}");
            let free = e.free_rigid_coordinates();
            assert_eq!(free.first().map(|f| f.0), Some(0), "{free:?}");
            assert!(e.to_string().contains("rigid coordinate 0"));
        } else {
            let sol = result.unwrap_or_else(|e| panic!("{e}"));
            let x = sol.y[model.n_structural()];
            println!("k = {k}: x = {x:.3e}, {}", sol.stability);
            assert!(x.abs() < 1e-12);
        }
    }
}

#[test]
fn a_stiff_rod_clamped_to_a_sprung_link_rests_as_the_rigid_compound() {
    let (l, side, rho, k) = (0.5_f64, 0.02_f64, 7800.0, 20.0);
    let mu = rho * side * side;
    let want = closed_form_angle(k, 0.0, M_LINK * G * A / 2.0 + mu * l * G * (A + l / 2.0));
    let mut diffs = Vec::new();
    for e in [2e9, 2e10] {
        let section = Section {
            e,
            rho,
            area: side * side,
            inertia: side.powi(4) / 12.0,
            ..Section::default()
        };
        let mut spec = cable([A, 0.0, 0.0], [A + l, 0.0, 0.0], 4);
        spec.section = section;
        let ch = build(&spec);
        let at = ch.attachment("rod.start", false, true);
        let link = SprungLink {
            a: A,
            m: M_LINK,
            k,
            rest: 0.0,
            clamped: true,
        };
        let model =
            MixedModel::new(ch.model, Box::new(link), vec![at]).unwrap_or_else(|e| panic!("{e}"));
        let sol = solve_static_mixed(&model, 0.0, &[0.0], &StaticOptions::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let theta = sol.y[model.n_structural()];
        let most = sol.steps.iter().map(|s| s.iterations()).max().unwrap_or(0);
        println!(
            "E = {e:e}: θ = {theta:.12} (rigid compound {want:.12}, Δ {:.2e}); at most {most} iterations per step, {} regularised; {}",
            theta - want,
            sol.regularized,
            sol.stability
        );
        for s in &sol.steps {
            println!(
                "  λ = {:.2}: {} (tol {:.1e})",
                s.lambda,
                s.residuals
                    .iter()
                    .map(|r| format!("{r:.2e}"))
                    .collect::<Vec<_>>()
                    .join(" → "),
                s.tolerance
            );
        }
        // A few Newton iterations per step (the tangent, clamp coupling
        // included, is the residual's exact Jacobian: the unit test in
        // `mixed::statics`); the last ones approach the round-off floor of
        // the stiff axial term (EA = 8e6 N at E = 2e10: the tolerance's
        // floor is near 1e-7 N), where the residual falls more slowly.
        assert!(most <= 6, "{most} iterations");
        assert_eq!(sol.regularized, 0);
        assert!(sol.constraint_residual < 1e-12);
        diffs.push((theta - want).abs());
    }
    let (d1, d2) = (diffs[0], diffs[1]);
    assert!(d2 < 1e-3 * want.abs(), "Δ {d2}");
    assert!(d1 / d2 > 8.0 && d1 / d2 < 12.0, "ratio {}", d1 / d2);
}
