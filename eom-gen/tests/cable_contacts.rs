//! Contacts at the nodes of ANCF cables (issue #26): a cable node against
//! a plane fixed in the world, run by the large-model runtime through the
//! rigid runtime's impact map and contact events.
//!
//! Physics checked:
//! - **A straight free wire dropped flat onto a floor**: every node strikes
//!   at `t₁ = √(2h₀/g)` with `ġ⁻ = −√(2gh₀)` (free fall is exact for
//!   generalized-α and the gap's cubic interpolant); the five rows form one
//!   simultaneous impact (an LCP). With `e = 1` every node leaves with
//!   `ġ⁺ = −ġ⁻`, the energy is kept through the impact, and the impulses
//!   are those of the Newton law solved independently,
//!   `Λ = (1 + e) (W M⁻¹ Wᵀ)⁻¹ (−ġ⁻)`. With `e = 0` the nodes come to rest
//!   and are held: the sustained normal forces carry the wire's weight
//!   `ρ A L g`.
//! - **A cable pendulum whose tip node strikes a floor**: the impulse against
//!   `Λ = −(1 + e) ġ⁻ / (wᵀ M⁻¹ w)` and the energy lost against Carnot's
//!   `½ (1 − e²) ġ⁻² / (wᵀ M⁻¹ w)`, with `M⁻¹` inverted here.
//! - **Coulomb friction at the nodes** (μ = 0.5 unless said; the weight
//!   `m g` lumped at the nodes, so that the straight wire stays straight
//!   and each node carries its share — with gravity distributed the spans
//!   sag between the nodes and the end nodes unload, BENCHMARKS.md): the
//!   wire lying on the floor on all its nodes, launched along it at `v₀`,
//!   slides as a rigid body — friction `μ m g` stops it after
//!   `v₀²/(2 μ g)` at `t = v₀/(μ g)` (to 1e-5 and 1e-9: the slide is
//!   uniformly decelerated, its stop located linearly; the nodes' friction
//!   strains the wire axially by a part in 10⁵) —, then sticks and stays;
//!   on a floor tilted by `θ` (the loads turned by `θ`) it sticks for
//!   `tan θ < μ` and slides with `g (sin θ − μ cos θ)` otherwise; dropped flat while moving sideways at `u₀` (e = 0.5,
//!   μ = 0.3), every node's impulse lies in the cone and, sliding on,
//!   `Λ_t = −μ Λ v̂_t⁺` (Newton–Coulomb), so every node leaves at
//!   `u₀ − μ (1 + e) √(2 g h₀)` (the x and y blocks of `M` are equal) and
//!   the energy is not gained; the nodes leave the floor rising and land
//!   again (a rebound is never taken as a rest); with the weight distributed (gravity
//!   turned by θ, tan θ = 0.3 < μ) the nodes stick and slip in turn as the
//!   spans sag and the wire vibrates, each slip's stick force on the cone,
//!   no event gaining energy, and the wire only creeps.
//! - **Spheres at nodes**: a falling wire's middle node (a sphere) striking
//!   a fixed sphere at its top, at `t₁ = √(2h/g)` with
//!   `Λ = (1 + e)|ġ⁻|/(wᵀ M⁻¹ w)` and Carnot's energy, the same impact as
//!   the tangent plane's (with friction too: Newton–Coulomb's impulses),
//!   and the same run as a sphere about a node pinned at that centre;
//!   two cables' end nodes striking head-on, `wᵀ M⁻¹ w` over both.
//! - **No event pulls**: in every run of this file every normal impulse
//!   is a push, `Λ ≥ 0` (a rest's plastic impulse with `Λ < 0` would
//!   mean the contact separates).
//! - **Located refusals**: a node inside its plane at the start (with the
//!   penetration), a negative friction coefficient, a node the cable does not
//!   have, a cable that does not exist, a plane on a body. (A node contact
//!   in a model whose cable hangs at a body is a model:
//!   `cable_contacts_mixed.rs`.)

use eom_gen::model::{Source, check};
use eom_sim::Integrator;
use eom_sim::large::{ElementRun, StructuralModel, simulate_structure};
use eom_sim::run::ContactEventKind;
use nalgebra::{DMatrix, DVector};

const G: f64 = 9.81;
const H0: f64 = 0.2;
/// The wire: steel, 1 m, A = 8 mm².
const RHO_A: f64 = 7850.0 * 8e-6;

fn system(text: &str) -> eom_gen::System {
    match check(&Source::new("drop.ron", text.to_string())) {
        Ok(c) => c.system,
        Err(r) => panic!("{r}"),
    }
}

fn diagnose(text: &str) -> String {
    eom_gen::testkit::diagnose("models/drop.ron", text)
}

/// A free wire of `n` elements, level at height `h`, above the floor
/// `y = 0`, a contact at every node with restitution `e` (and `extra`
/// appended to each contact). Its bending damping (Kelvin–Voigt, about
/// critical for the lowest span mode once it rests on its nodes) lets the
/// sag set after it lands; a rigid translation does not strain it.
fn wire_drop(n: usize, h: f64, e: f64, extra: &str) -> String {
    let contacts: Vec<String> = (0..=n)
        .map(|k| {
            format!(
                r#"Plane(name: "n{k}", at: (body: "wire", node: {k}), normal: (0, 1, 0), e: {e}{extra})"#
            )
        })
        .collect();
    format!(
        r#"Model(
    name: "wire_drop",
    gravity: (0, -9.81, 0),
    bodies: [],
    joints: [],
    cables: [Cable(name: "wire", element: Cable2D, from: (0, {h}, 0), to: (1, {h}, 0),
        elements: {n}, young: 2e9, density: 7850, area: 8e-6, second_moment: 5e-12,
        damping_bending: 2e-4, start: Free)],
    contacts: [{}],
)"#,
        contacts.join(",\n        ")
    )
}

fn run(t_end: f64, dt: f64, rho_inf: f64) -> ElementRun {
    ElementRun {
        integrator: Integrator::GeneralizedAlpha,
        t_end,
        dt,
        rho_inf,
        control: None,
        record: false,
        every: None,
    }
}

/// The structure's mass matrix on its free coordinates, dense.
fn dense_mass(m: &StructuralModel) -> DMatrix<f64> {
    let n = m.n_free();
    let mut out = DMatrix::zeros(n, n);
    for j in 0..n {
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        let mut col = vec![0.0; n];
        m.mass().sym_mul_add(1.0, &e, &mut col);
        for i in 0..n {
            out[(i, j)] = col[i];
        }
    }
    out
}

/// Runs `text` and returns the report and the structure.
fn simulate(
    text: &str,
    r: &ElementRun,
) -> (
    eom_sim::RunReport,
    StructuralModel,
    Vec<eom_sim::large::CableLayout>,
) {
    let sys = system(text);
    let (built, cables) = eom_gen::cables::structure(&sys).expect("structure");
    let contacts = eom_gen::cables::node_contacts(&sys, &cables);
    assert_eq!(contacts.len(), sys.cable_contacts.len());
    let (report, _) =
        simulate_structure(&built.model, &cables, &contacts, r, &mut |_| {}).expect("runs");
    eom_gen::testkit::no_event_pulls(&report, false);
    (report, built.model, cables)
}

/// The free index of node `node`'s coordinate `axis`.
fn free(m: &StructuralModel, c: &eom_sim::large::CableLayout, node: usize, axis: usize) -> usize {
    m.free_index(c.offset + node * c.node_coords + axis)
        .expect("a free coordinate")
}

#[test]
fn a_wire_dropped_flat_rebounds_elastically_with_every_node_at_once() {
    let n = 4;
    let (report, model, cables) = simulate(&wire_drop(n, H0, 1.0, ""), &run(0.25, 1e-3, 1.0));
    assert!(
        matches!(report.stop, eom_sim::Stop::Finished),
        "{:?}",
        report.stop
    );
    let t1 = (2.0 * H0 / G).sqrt();
    let v1 = (2.0 * G * H0).sqrt();
    let ev = report
        .contact_events
        .first()
        .expect("the wire strikes the floor");
    assert_eq!(ev.kind, ContactEventKind::Impact);
    assert!(
        (ev.t - t1).abs() < 1e-9,
        "impact at t = {}, want √(2h₀/g) = {t1}",
        ev.t
    );
    assert_eq!(ev.contacts.len(), n + 1, "all nodes strike at once");
    for c in &ev.contacts {
        assert!(
            (c.speed_before + v1).abs() < 1e-8,
            "{}: ġ⁻ = {}, want −√(2gh₀) = {}",
            c.contact,
            c.speed_before,
            -v1
        );
        assert!(
            (c.speed_after - v1).abs() < 1e-8,
            "{}: ġ⁺ = {}, want −ġ⁻ = {v1} (e = 1)",
            c.contact,
            c.speed_after
        );
    }
    let scale = ev.energy_before.abs().max(RHO_A * G * H0);
    assert!(
        (ev.energy_after - ev.energy_before).abs() < 1e-10 * scale,
        "energy before {} after {}: an elastic impact keeps it",
        ev.energy_before,
        ev.energy_after
    );
    // The Newton law solved here: Λ = (1 + e) (W M⁻¹ Wᵀ)⁻¹ v₁ 1 (every
    // row active, so the LCP's answer is the linear solve's).
    let m = dense_mass(&model);
    let nf = model.n_free();
    let w = DMatrix::from_fn(n + 1, nf, |k, j| {
        if j == free(&model, &cables[0], k, 1) {
            1.0
        } else {
            0.0
        }
    });
    let minv = m.try_inverse().expect("M is invertible");
    let a = &w * &minv * w.transpose();
    let lam = a
        .lu()
        .solve(&DVector::from_element(n + 1, 2.0 * v1))
        .expect("W M⁻¹ Wᵀ is invertible");
    for (k, c) in ev.contacts.iter().enumerate() {
        assert!(lam[k] > 0.0, "every node pushes");
        assert!(
            (c.impulse - lam[k]).abs() < 1e-9 * lam.amax(),
            "{}: Λ = {}, want {}",
            c.contact,
            c.impulse,
            lam[k]
        );
    }
}

#[test]
fn a_wire_dropped_flat_with_e_0_comes_to_rest_on_its_nodes() {
    let n = 4;
    let (report, _, _) = simulate(&wire_drop(n, H0, 0.0, ""), &run(0.6, 1e-3, 0.5));
    assert!(
        matches!(report.stop, eom_sim::Stop::Finished),
        "{:?}",
        report.stop
    );
    let t1 = (2.0 * H0 / G).sqrt();
    let kinds: Vec<_> = report.contact_events.iter().map(|e| e.kind).collect();
    assert_eq!(
        kinds[..2],
        [ContactEventKind::Impact, ContactEventKind::Rest],
        "{kinds:?}"
    );
    let impact = &report.contact_events[0];
    assert!((impact.t - t1).abs() < 1e-9);
    for c in &impact.contacts {
        assert!(c.speed_after.abs() < 1e-9, "e = 0: {} stops", c.contact);
    }
    // The plastic impact stops the nodes but jolts the end slopes, and the
    // spans start to sag: nodes lift off (released) and land again while
    // the wire settles. The problem is mirror-symmetric about the middle,
    // so every event takes node `k` with node `n − k`.
    for ev in &report.contact_events {
        let rows: Vec<String> = ev.contacts.iter().map(|c| c.contact.clone()).collect();
        for r in &rows {
            let k: usize = r[1..].parse().expect("n<k>");
            assert!(
                rows.contains(&format!("n{}", n - k)),
                "{:?} at t = {}: {rows:?} is not symmetric",
                ev.kind,
                ev.t
            );
        }
    }
    let el = report.elements.as_ref().expect("an element report");
    assert_eq!(
        el.contact_forces.len(),
        n + 1,
        "every node is held at the end"
    );
    let weight = RHO_A * 1.0 * G;
    let sum: f64 = el.contact_forces.iter().map(|c| c.force).sum();
    for c in &el.contact_forces {
        assert!(c.force > 0.0, "{} pushes: {}", c.contact, c.force);
    }
    assert!(
        (sum - weight).abs() < 1e-3 * weight,
        "the normal forces sum to {sum} N, want the weight ρ A L g = {weight} N"
    );
}

/// A cable pendulum: pinned at the origin, level along +x, falling under
/// gravity; its tip (node `n`) strikes the floor `y = −depth`.
fn pendulum(n: usize, depth: f64, e: f64) -> String {
    format!(
        r#"Model(
    name: "cable_pendulum",
    gravity: (0, -9.81, 0),
    bodies: [],
    joints: [],
    cables: [Cable(name: "rod", element: Cable2D, from: (0, 0, 0), to: (1, 0, 0),
        elements: {n}, young: 2e9, density: 7850, area: 8e-6, second_moment: 5e-12, start: Pinned)],
    contacts: [Plane(name: "stop", at: (body: "rod", node: {n}), point: (0, -{depth}, 0), normal: (0, 1, 0), e: {e})],
)"#
    )
}

#[test]
fn a_cable_pendulum_striking_a_stop_loses_carnots_energy() {
    let (n, e) = (4, 0.5);
    let (report, model, cables) = simulate(&pendulum(n, 0.6, e), &run(0.35, 1e-3, 1.0));
    let ev = report
        .contact_events
        .iter()
        .find(|x| x.kind == ContactEventKind::Impact)
        .expect("the tip strikes the floor");
    let c = &ev.contacts[0];
    assert_eq!(c.contact, "stop");
    assert!(c.speed_before < 0.0, "approaching");
    // wᵀ M⁻¹ w with w the tip's y coordinate, M inverted here.
    let m = dense_mass(&model);
    let minv = m.try_inverse().expect("M is invertible");
    let k = free(&model, &cables[0], n, 1);
    let wmw = minv[(k, k)];
    let want = -(1.0 + e) * c.speed_before / wmw;
    assert!(
        (c.impulse - want).abs() < 1e-9 * want,
        "Λ = {}, want −(1 + e) ġ⁻ / (wᵀ M⁻¹ w) = {want}",
        c.impulse
    );
    assert!(
        (c.speed_after + e * c.speed_before).abs() < 1e-9 * c.speed_before.abs(),
        "ġ⁺ = {}, want −e ġ⁻",
        c.speed_after
    );
    let lost = ev.energy_before - ev.energy_after;
    let carnot = 0.5 * (1.0 - e * e) * c.speed_before * c.speed_before / wmw;
    assert!(
        (lost - carnot).abs() < 1e-9 * carnot,
        "energy lost {lost}, want Carnot's ½ (1 − e²) ġ⁻² / (wᵀ M⁻¹ w) = {carnot}"
    );
}

#[test]
fn contacts_at_cable_nodes_refused_with_their_locations() {
    // Inside the floor at the start: the penetration and what opens it.
    let text = wire_drop(2, -0.01, 0.5, "");
    let out = diagnose(&text);
    assert!(
        out.contains("node 0 of cable `wire` penetrates its plane by 1.000000e-2 m"),
        "{out}"
    );
    assert!(out.contains("further along the plane's normal"), "{out}");
    // Friction at a cable node is a model (issue #26); a negative
    // coefficient is not.
    assert_eq!(diagnose(&wire_drop(2, H0, 0.5, ", mu: 0.3")), "valid");
    let out = diagnose(&wire_drop(2, H0, 0.5, ", mu: -0.3"));
    assert!(
        out.contains("`mu` of contact `n0` is -0.3, negative"),
        "{out}"
    );
    assert!(out.contains("a Coulomb friction coefficient is 0"), "{out}");
    assert!(out.contains("models/drop.ron:"), "located: {out}");
    // A node the cable does not have, and a cable that does not exist.
    let bad = wire_drop(2, H0, 0.5, "")
        .replace("node: 2)", "node: 7)")
        .replace(r#"(body: "wire", node: 1)"#, r#"(body: "rope", node: 1)"#);
    let out = diagnose(&bad);
    assert!(
        out.contains("contact `n2` is at node 7 of cable `wire`, whose nodes are 0..=2"),
        "{out}"
    );
    assert!(
        out.contains("contact `n1` is at node 1 of `rope`, which is no cable"),
        "{out}"
    );
    // A plane on a body the model does not have (a plane on a body it
    // has is a contact: `eom-gen/tests/cable_contacts_mixed.rs`).
    let on = wire_drop(1, H0, 0.5, r#", on: "table""#);
    let out = diagnose(&on);
    assert!(out.contains("unknown plane body `table`"), "{out}");
    assert!(out.contains("models/drop.ron:9:"), "located: {out}");
}

#[test]
fn a_cable_pendulum_bounces_and_slides_on_its_stop_for_a_whole_second() {
    // The same pendulum over 1 s: the tip strikes, bounces, comes to rest
    // and is released again (about a hundred events; the run used to stop
    // at t = 0.4957 s with Newton failing), and the very flexible rod bends
    // to pass the floor 0.6 m below its 1 m length. Every impact keeps
    // Newton's law ġ⁺ = −e ġ⁻ and loses energy; the tip never sinks into
    // the floor by more than the gap tolerance at any step. (Between
    // events the energy is not a conserved quantity of the discrete run:
    // the rod's axial modes, ωh ≈ 4 at this step, make it swing by up to
    // 10 % of |T| + |V| — BENCHMARKS.md.)
    let (n, e, depth) = (4, 0.5, 0.6);
    let mut r = run(1.0, 1e-3, 1.0);
    r.record = true;
    let sys = system(&pendulum(n, depth, e));
    let (built, cables) = eom_gen::cables::structure(&sys).expect("structure");
    let contacts = eom_gen::cables::node_contacts(&sys, &cables);
    let (report, table) =
        simulate_structure(&built.model, &cables, &contacts, &r, &mut |_| {}).expect("runs");
    assert_eq!(report.stop, eom_sim::Stop::Finished, "{:?}", report.stop);
    assert!((report.t - 1.0).abs() < 1e-12);
    eom_gen::testkit::no_event_pulls(&report, false);
    let count = |k: ContactEventKind| report.contact_events.iter().filter(|x| x.kind == k).count();
    let (impacts, rests, releases) = (
        count(ContactEventKind::Impact),
        count(ContactEventKind::Rest),
        count(ContactEventKind::Release),
    );
    assert!(impacts >= 10 && rests >= 1 && releases >= 1);
    let scale = report.energy_scale;
    for ev in &report.contact_events {
        assert!(
            ev.energy_after <= ev.energy_before + 1e-12 * scale,
            "{:?} at {}: energy {} → {}",
            ev.kind,
            ev.t,
            ev.energy_before,
            ev.energy_after
        );
        if ev.kind == ContactEventKind::Impact {
            for c in ev.contacts.iter().filter(|c| c.impulse > 0.0) {
                assert!(
                    (c.speed_after + e * c.speed_before).abs() <= 1e-9 * c.speed_before.abs(),
                    "impact at {}: ġ⁺ = {}, want −e ġ⁻ = {}",
                    ev.t,
                    c.speed_after,
                    -e * c.speed_before
                );
            }
        }
    }
    let table = table.expect("recorded");
    // At every step and every event's state: the tip above the floor to
    // the gap tolerance (1e-9 m; 2.7e-4 m before the located impact state
    // was brought onto the integrator's own step), and the energy never
    // above its start.
    let tip = table.column(&format!("rod.node{n}.y")).expect("tip column");
    let lowest = tip.iter().fold(f64::INFINITY, |a, &y| a.min(y));
    eprintln!(
        "{impacts} impacts, {rests} rests, {releases} releases; the tip's lowest {:e} m below the floor",
        -depth - lowest
    );
    assert!(lowest >= -depth - 2e-9, "the tip sank to {lowest}");
    let energy = table.column("energy").expect("energy column");
    let highest = energy.iter().fold(f64::NEG_INFINITY, |a, &x| a.max(x));
    assert!(
        highest <= energy[0] + 1e-9 * scale,
        "the energy rose to {highest} from {}",
        energy[0]
    );
    assert!(report.energy[1] < report.energy[0], "{:?}", report.energy);
}

/// The wire of [`wire_drop`] at height `h` with friction `mu`, every node
/// moving along x at `u0` at the start: the report, the recorded table and
/// the nodes' initial x. Its weight `W = ρ A L g` turned by `theta` about
/// z (a floor tilted by `theta`, downhill along +x) is, if `lumped`, `n + 1`
/// equal dead loads `W/(n + 1)` at the nodes with gravity off — the loads
/// of a rigid wire on its nodes, so that the straight wire stays straight
/// and every node carries `W cos θ/(n + 1)` —, else gravity, distributed:
/// then the spans sag between the nodes (through the floor, which touches
/// the nodes only) and the end nodes unload as the end spans swing down.
#[allow(clippy::too_many_arguments)]
fn sliding(
    n: usize,
    h: f64,
    e: f64,
    mu: f64,
    theta: f64,
    u0: f64,
    lumped: bool,
    r: &ElementRun,
) -> (eom_sim::RunReport, eom_sim::table::Table, Vec<f64>) {
    let (gx, gy) = (G * theta.sin(), -G * theta.cos());
    let text = wire_drop(n, h, e, &format!(", mu: {mu}"));
    let text = if lumped {
        let per = RHO_A * 1.0 / (n + 1) as f64;
        let loads: Vec<String> = (0..=n)
            .map(|k| format!("(node: {k}, force: ({:e}, {:e}, 0))", per * gx, per * gy))
            .collect();
        text.replace("gravity: (0, -9.81, 0)", "gravity: (0, 0, 0)")
            .replace(
                "start: Free)",
                &format!("start: Free, node_forces: [{}])", loads.join(", ")),
            )
    } else {
        text.replace(
            "gravity: (0, -9.81, 0)",
            &format!("gravity: ({gx:e}, {gy:e}, 0)"),
        )
    };
    let sys = system(&text);
    let (mut built, cables) = eom_gen::cables::structure(&sys).expect("structure");
    let contacts = eom_gen::cables::node_contacts(&sys, &cables);
    let c = &cables[0];
    let mut v0 = vec![0.0; built.model.n_full()];
    for k in 0..=n {
        v0[c.offset + k * c.node_coords] = u0;
    }
    built.model.set_initial_velocity(v0);
    let x0 = (0..=n)
        .map(|k| built.model.q0()[c.offset + k * c.node_coords])
        .collect();
    let mut r = r.clone();
    r.record = true;
    let (report, table) =
        simulate_structure(&built.model, &cables, &contacts, &r, &mut |_| {}).expect("runs");
    assert_eq!(report.stop, eom_sim::Stop::Finished, "{:?}", report.stop);
    eom_gen::testkit::no_event_pulls(&report, false);
    (report, table.expect("recorded"), x0)
}

/// Node `k`'s x over the run.
fn xs(table: &eom_sim::table::Table, k: usize) -> Vec<f64> {
    table
        .column(&format!("wire.node{k}.x"))
        .expect("a node column")
}

#[test]
fn a_wire_sliding_on_the_floor_stops_after_v0_squared_over_2_mu_g_and_sticks() {
    let (n, mu, u0) = (4, 0.5, 1.0);
    let (report, table, x0) = sliding(n, 0.0, 0.0, mu, 0.0, u0, true, &run(0.4, 1e-3, 0.5));
    let (t_stop, d_stop) = (u0 / (mu * G), u0 * u0 / (2.0 * mu * G));
    let kinds: Vec<_> = report.contact_events.iter().map(|e| e.kind).collect();
    assert_eq!(kinds[0], ContactEventKind::Rest, "{kinds:?}");
    assert!(
        !kinds.contains(&ContactEventKind::Slip) && !kinds.contains(&ContactEventKind::Release),
        "a slide that stops and sticks: {kinds:?}"
    );
    // Every node stops (a stick event per node, or several at once).
    let stuck: Vec<(String, f64)> = report
        .contact_events
        .iter()
        .filter(|e| e.kind == ContactEventKind::Stick)
        .flat_map(|e| e.contacts.iter().map(move |c| (c.contact.clone(), e.t)))
        .collect();
    for k in 0..=n {
        let name = format!("n{k}");
        let t = stuck
            .iter()
            .filter(|(c, _)| *c == name)
            .map(|&(_, t)| t)
            .fold(0.0, f64::max);
        assert!(
            (t - t_stop).abs() < 1e-9 * t_stop,
            "{name} sticks at t = {t}, want v₀/(μ g) = {t_stop}"
        );
    }
    let time = table.column("t").expect("t");
    for (k, &start) in x0.iter().enumerate() {
        let x = xs(&table, k);
        let moved = x[x.len() - 1] - start;
        assert!(
            (moved - d_stop).abs() < 1e-5 * d_stop,
            "node {k} slid {moved} m, want v₀²/(2 μ g) = {d_stop}"
        );
        // Stuck: after the stop (and a step) it does not move.
        let after: Vec<f64> = time
            .iter()
            .zip(&x)
            .filter(|&(&t, _)| t > t_stop * 1.01)
            .map(|(_, &x)| x)
            .collect();
        assert!(after.len() > 100, "recorded after the stop");
        let spread = after.iter().fold(f64::NEG_INFINITY, |a, &x| a.max(x))
            - after.iter().fold(f64::INFINITY, |a, &x| a.min(x));
        assert!(
            spread < 1e-8,
            "node {k} moves by {spread} m while it sticks"
        );
    }
    let el = report.elements.as_ref().expect("an element report");
    assert_eq!(el.contact_forces.len(), n + 1, "every node held at the end");
    let weight = RHO_A * 1.0 * G;
    let sum: f64 = el.contact_forces.iter().map(|c| c.force).sum();
    assert!(
        (sum - weight).abs() < 1e-3 * weight,
        "the normal forces sum to {sum} N, want ρ A L g = {weight} N"
    );
}

#[test]
fn a_wire_on_a_tilted_floor_sticks_below_the_friction_angle_and_slides_above() {
    let (n, mu, t_end) = (4, 0.5, 0.3);
    // tan θ = 0.3 < μ: it sticks from the start and stays.
    let (report, table, x0) = sliding(
        n,
        0.0,
        0.0,
        mu,
        0.3_f64.atan(),
        0.0,
        true,
        &run(t_end, 1e-3, 0.5),
    );
    let kinds: Vec<_> = report.contact_events.iter().map(|e| e.kind).collect();
    assert_eq!(kinds, [ContactEventKind::Rest], "{kinds:?}");
    for (k, &start) in x0.iter().enumerate() {
        let x = xs(&table, k);
        let spread = x.iter().fold(0.0_f64, |a, &v| a.max((v - start).abs()));
        assert!(spread < 1e-8, "tan θ < μ: node {k} moves by {spread} m");
    }
    // tan θ = 0.7 > μ: it slides from the start with a = g (sin θ − μ cos θ).
    let theta = 0.7_f64.atan();
    let a = G * (theta.sin() - mu * theta.cos());
    let (report, table, x0) = sliding(n, 0.0, 0.0, mu, theta, 0.0, true, &run(t_end, 1e-3, 0.5));
    let kinds: Vec<_> = report.contact_events.iter().map(|e| e.kind).collect();
    assert_eq!(kinds, [ContactEventKind::Rest], "{kinds:?}");
    let want = 0.5 * a * t_end * t_end;
    for (k, &start) in x0.iter().enumerate() {
        let x = xs(&table, k);
        let moved = x[x.len() - 1] - start;
        assert!(
            (moved - want).abs() < 1e-5 * want,
            "tan θ > μ: node {k} slid {moved} m in {t_end} s, want ½ g (sin θ − μ cos θ) t² = {want}"
        );
    }
}

/// The impact and the rebound. Every node leaves the floor rising,
/// `ġ⁺ = −e ġ⁻ = 0.99 m/s`, and its next event is a landing (an impact
/// approaching the floor), never a rest: the wire's elastic accelerations
/// just after the impact (|g̈| ≈ 10²–10⁴ m/s²) once made the rest rule
/// `ġ ≤ |g̈| h` take the rebound as arriving at rest and pull the nodes
/// back onto the floor by plastic impulses of the wrong sign (−5.6e-5 …
/// −1.1e-2 N s, issue #26). No event pulls, and none gains energy.
#[test]
fn a_wire_dropped_flat_while_moving_sideways_takes_coulomb_impulses() {
    let (n, e, mu, u0) = (4, 0.5, 0.3, 2.0);
    let (report, table, _) = sliding(n, H0, e, mu, 0.0, u0, false, &run(0.25, 1e-3, 1.0));
    for k in 0..=n {
        let name = format!("n{k}");
        let mut mine = report
            .contact_events
            .iter()
            .filter(|ev| ev.contacts.iter().any(|c| c.contact == name));
        let first = mine.next().expect("the node strikes");
        let c = first
            .contacts
            .iter()
            .find(|c| c.contact == name)
            .expect("row");
        assert!(
            c.speed_after > 0.0,
            "{name} leaves rising: ġ⁺ = {}",
            c.speed_after
        );
        let next = mine.next().expect("the node lands again");
        let d = next
            .contacts
            .iter()
            .find(|c| c.contact == name)
            .expect("row");
        assert!(
            next.kind == ContactEventKind::Impact && d.speed_before < 0.0,
            "{name}: after rising at {} m/s its next event is {:?} at {} with ġ⁻ = {}, want a landing",
            c.speed_after,
            next.kind,
            next.t,
            d.speed_before
        );
    }
    let count = |k: ContactEventKind| report.contact_events.iter().filter(|x| x.kind == k).count();
    eprintln!(
        "{} impacts, {} rests, {} releases, {} sticks, {} slips",
        count(ContactEventKind::Impact),
        count(ContactEventKind::Rest),
        count(ContactEventKind::Release),
        count(ContactEventKind::Stick),
        count(ContactEventKind::Slip)
    );
    // The energy never rises above its start, at any step or event.
    let energy = table.column("energy").expect("energy column");
    let highest = energy.iter().fold(f64::NEG_INFINITY, |a, &x| a.max(x));
    eprintln!("energy {} → highest {highest}", energy[0]);
    assert!(
        highest <= energy[0] + 1e-9 * report.energy_scale,
        "the energy rose to {highest} from {}",
        energy[0]
    );
    let t1 = (2.0 * H0 / G).sqrt();
    let v1 = (2.0 * G * H0).sqrt();
    let ev = report.contact_events.first().expect("the wire strikes");
    assert_eq!(ev.kind, ContactEventKind::Impact);
    assert!((ev.t - t1).abs() < 1e-9, "impact at {}, want {t1}", ev.t);
    assert_eq!(ev.contacts.len(), n + 1, "all nodes strike at once");
    let after = u0 - mu * (1.0 + e) * v1;
    for c in &ev.contacts {
        let (l, lt) = (c.impulse, c.tangential_impulse);
        assert!(l > 0.0, "{}: Λ = {l}", c.contact);
        assert!(
            lt[0].hypot(lt[1]) <= mu * l * (1.0 + 1e-9),
            "{}: ‖Λ_t‖ = {} outside the cone μ Λ = {}",
            c.contact,
            lt[0].hypot(lt[1]),
            mu * l
        );
        // Sliding on (v_t⁺ > 0): Λ_t = −μ Λ v̂_t⁺.
        let vt = c.tangential_speed_after;
        assert!(vt[0] > 0.0 && vt[1] == 0.0, "{}: v_t⁺ = {vt:?}", c.contact);
        assert!(
            (lt[0] + mu * l).abs() < 1e-9 * l && lt[1].abs() < 1e-12 * l,
            "{}: Λ_t = {lt:?}, want −μ Λ v̂_t⁺ = ({}, 0)",
            c.contact,
            -mu * l
        );
        assert!(
            (vt[0] - after).abs() < 1e-9 * u0,
            "{}: v_t⁺ = {}, want u₀ − μ (1 + e) √(2 g h₀) = {after}",
            c.contact,
            vt[0]
        );
        assert!(
            (c.tangential_speed_before[0] - u0).abs() < 1e-12,
            "{}: v_t⁻ = {:?}",
            c.contact,
            c.tangential_speed_before
        );
        assert!(
            (c.speed_after + e * c.speed_before).abs() < 1e-9 * v1,
            "{}: ġ⁺ = {}, want −e ġ⁻",
            c.contact,
            c.speed_after
        );
    }
    assert!(
        ev.energy_after < ev.energy_before,
        "energy {} → {}: friction and e < 1 take energy",
        ev.energy_before,
        ev.energy_after
    );
    for ev in &report.contact_events {
        assert!(
            ev.energy_after <= ev.energy_before + 1e-12 * report.energy_scale,
            "{:?} at {}: energy {} → {}",
            ev.kind,
            ev.t,
            ev.energy_before,
            ev.energy_after
        );
    }
}

#[test]
fn a_wire_with_its_weight_distributed_inside_the_friction_angle_creeps_by_stick_slip_only() {
    // The wire's weight on its elements (gravity turned by θ, tan θ = 0.3
    // < μ = 0.5): the spans sag between the held nodes and the end nodes
    // unload as the end spans swing down, so the nodes stick and slip in
    // turn while the wire vibrates (hundreds of events; the run used to
    // stop at t = 0.024 s with 64 events at one time). The total friction
    // a stick needs, m g sin θ, is inside μ m g cos θ: the wire does not
    // slide away, the nodes only creep — by far less than the 8.0 mm it
    // slides in the same 0.1 s at tan θ = 0.7 —; at a slip the stick force
    // is on the cone, and no event gains energy.
    let (n, mu) = (4, 0.5);
    let (report, table, x0) = sliding(
        n,
        0.0,
        0.0,
        mu,
        0.3_f64.atan(),
        0.0,
        false,
        &run(0.1, 1e-3, 0.5),
    );
    let slips: Vec<_> = report
        .contact_events
        .iter()
        .filter(|e| e.kind == ContactEventKind::Slip)
        .collect();
    assert!(!slips.is_empty(), "the end nodes slip");
    for ev in &slips {
        for c in &ev.contacts {
            let l = c.tangential_impulse[0].hypot(c.tangential_impulse[1]);
            assert!(
                c.impulse > 0.0 && l >= mu * c.impulse * (1.0 - 1e-3),
                "slip of {} at {}: ‖λ_t‖ = {l}, μ λ = {}",
                c.contact,
                ev.t,
                mu * c.impulse
            );
        }
    }
    for ev in &report.contact_events {
        assert!(
            ev.energy_after <= ev.energy_before + 1e-12 * report.energy_scale,
            "{:?} at {}: energy {} → {}",
            ev.kind,
            ev.t,
            ev.energy_before,
            ev.energy_after
        );
    }
    for (k, &start) in x0.iter().enumerate() {
        let x = xs(&table, k);
        let creep = x[x.len() - 1] - start;
        assert!(
            creep.abs() < 1e-4,
            "node {k} crept {creep} m inside the friction angle"
        );
    }
}

/// The wire of [`wire_drop`] (4 elements, at `H0`, no contacts of its
/// own) with its middle node (x = 0.5) a sphere of radius 0.01 above
/// `target`'s contact `touch`: a fixed sphere of radius 0.05 centred at
/// (0.5, −0.05, 0) (its top at y = 0), the same sphere about node 0 of a
/// stub pinned there (its node fixed, the rest hanging free below), or
/// the plane y = 0 under that node alone. The node strikes each at the
/// same point with the same normal (0, 1, 0).
fn wire_on_a_sphere(target: &str, e: f64) -> String {
    wire_on_a_sphere_with(target, e, "", ("", 0.0))
}

/// [`wire_on_a_sphere`] with `contact` appended to the contact's fields
/// and `cable` to the wire's, the wire starting `shift` m to the left.
fn wire_on_a_sphere_with(
    target: &str,
    e: f64,
    contact: &str,
    (cable, shift): (&str, f64),
) -> String {
    let (x0, x1) = (-shift, 1.0 - shift);
    let (stub, touch) = match target {
        "sphere" => (
            "",
            format!(
                r#"Spheres(name: "touch", a: (body: "wire", node: 2), b: (body: "ground", point: (0.5, -0.05, 0)), radius_a: 0.01, radius_b: 0.05, e: {e}{contact})"#
            ),
        ),
        "node" => (
            r#",
        Cable(name: "stub", element: Cable2D, from: (0.5, -0.05, 0), to: (0.5, -0.25, 0),
        elements: 2, young: 2e9, density: 7850, area: 8e-6, second_moment: 5e-12, start: Pinned)"#,
            format!(
                r#"Spheres(name: "touch", a: (body: "wire", node: 2), b: (body: "stub", node: 0), radius_a: 0.01, radius_b: 0.05, e: {e}{contact})"#
            ),
        ),
        _ => (
            "",
            format!(
                r#"Plane(name: "touch", at: (body: "wire", node: 2), radius: 0.01, normal: (0, 1, 0), e: {e}{contact})"#
            ),
        ),
    };
    format!(
        r#"Model(
    name: "wire_on_a_sphere",
    gravity: (0, -9.81, 0),
    bodies: [],
    joints: [],
    cables: [Cable(name: "wire", element: Cable2D, from: ({x0}, {H0}, 0), to: ({x1}, {H0}, 0),
        elements: 4, young: 2e9, density: 7850, area: 8e-6, second_moment: 5e-12,
        damping_bending: 2e-4, start: Free{cable}){stub}],
    contacts: [{touch}],
)"#
    )
}

/// A cable node's sphere against a sphere (issue #26: spheres at the
/// nodes of flexible bodies). The free wire falls flat and its middle
/// node strikes a fixed sphere at its top: at `t₁ = √(2h/g)`,
/// `h = H0 − 0.01`, with `ġ⁻ = −√(2gh)` (free fall, exact for
/// generalized-α), `ġ⁺ = −e ġ⁻`, the impulse `Λ = (1 + e)|ġ⁻|/(wᵀ M⁻¹ w)`
/// with `w` the node's y coordinate and `M⁻¹` inverted here, and Carnot's
/// energy `½ (1 − e²) ġ⁻²/(wᵀ M⁻¹ w)`; the plane tangent to the sphere
/// there gives the same impact. Afterwards the wire pivots on the sphere
/// (the normal turns with the node: the row is evaluated at every state,
/// `γ = −ṅ·v`), hops and slides off; the same sphere about node 0 of a
/// stub pinned at its centre is the same contact over the whole run
/// (a node's fixed coordinates stand for the centre): the same events at
/// the same times and impulses. No event raises the energy.
#[test]
fn a_wire_striking_a_sphere_at_a_node_obeys_newton_and_carnot() {
    let e = 0.5;
    let r = run(0.5, 1e-3, 0.8);
    let (sphere, model, cables) = simulate(&wire_on_a_sphere("sphere", e), &r);
    let (plane, _, _) = simulate(&wire_on_a_sphere("plane", e), &r);
    let (node, _, _) = simulate(&wire_on_a_sphere("node", e), &r);
    finished_without_gaining(
        &[("sphere", &sphere), ("plane", &plane), ("node", &node)],
        1e-12,
    );
    let h = H0 - 0.01;
    let (t1, v1) = ((2.0 * h / G).sqrt(), (2.0 * G * h).sqrt());
    let first = |rep: &eom_sim::RunReport| rep.contact_events[0].clone();
    let ev = first(&sphere);
    assert_eq!(ev.kind, ContactEventKind::Impact);
    assert!((ev.t - t1).abs() < 1e-9, "impact at {}, want {t1}", ev.t);
    let c = &ev.contacts[0];
    assert!(
        (c.speed_before + v1).abs() < 1e-8,
        "ġ⁻ = {}",
        c.speed_before
    );
    assert!(
        (c.speed_after + e * c.speed_before).abs() < 1e-9,
        "ġ⁺ = {}",
        c.speed_after
    );
    let minv = dense_mass(&model).try_inverse().expect("M is invertible");
    let k = free(&model, &cables[0], 2, 1);
    let want = (1.0 + e) * c.speed_before.abs() / minv[(k, k)];
    assert!(
        (c.impulse - want).abs() < 1e-9 * want,
        "Λ = {}, want (1 + e)|ġ⁻|/(wᵀ M⁻¹ w) = {want}",
        c.impulse
    );
    let carnot = 0.5 * (1.0 - e * e) * c.speed_before.powi(2) / minv[(k, k)];
    let lost = ev.energy_before - ev.energy_after;
    assert!(
        (lost - carnot).abs() < 1e-9 * carnot,
        "lost {lost}, want Carnot's {carnot}"
    );
    let p = first(&plane);
    assert!(
        (p.t - ev.t).abs() < 1e-12 && (p.contacts[0].impulse - c.impulse).abs() < 1e-12 * want,
        "the tangent plane's impact: {} s, {} N s",
        p.t,
        p.contacts[0].impulse
    );
    // The sphere's run goes on differently from the plane's: the wire
    // pivots off the sphere.
    assert!(
        sphere.contact_events.len() >= 2,
        "{:?}",
        sphere.contact_events
    );
    assert_eq!(
        sphere.contact_events.len(),
        node.contact_events.len(),
        "the fixed sphere and the pinned node: the same events"
    );
    for (a, b) in sphere.contact_events.iter().zip(&node.contact_events) {
        assert_eq!(a.kind, b.kind, "at {}", a.t);
        assert!(
            (a.t - b.t).abs() < 1e-9,
            "{:?} at {} and {}",
            a.kind,
            a.t,
            b.t
        );
        let (x, y) = (a.contacts[0].impulse, b.contacts[0].impulse);
        assert!(
            (x - y).abs() <= 1e-9 * want,
            "{:?} at {}: Λ {x} and {y}",
            a.kind,
            a.t
        );
    }
    println!(
        "sphere: {:?}",
        sphere
            .contact_events
            .iter()
            .map(|e| (e.kind, e.t, e.contacts[0].impulse))
            .collect::<Vec<_>>()
    );
}

/// Two free wires (Cable2D, 0.5 m each, steel) on one line, without
/// gravity: `a` moving along it at 1 m/s, `b` at rest, the end node of
/// `a` and the start node of `b` spheres of 0.01 m, 0.03 m apart.
fn wires_head_on(e: f64, mu: f64) -> String {
    format!(
        r#"Model(
    name: "wires_head_on",
    gravity: (0, 0, 0),
    bodies: [],
    joints: [],
    cables: [
        Cable(name: "a", element: Cable2D, from: (-0.55, 0, 0), to: (-0.05, 0, 0), elements: 2,
              young: 2e9, density: 7850, area: 8e-6, second_moment: 5e-12, start: Free, velocity: (1, 0, 0)),
        Cable(name: "b", element: Cable2D, from: (0, 0, 0), to: (0.5, 0, 0), elements: 2,
              young: 2e9, density: 7850, area: 8e-6, second_moment: 5e-12, start: Free),
    ],
    contacts: [Spheres(name: "knock", a: (body: "a", node: 2), b: (body: "b", node: 0), radius_a: 0.01, radius_b: 0.01, e: {e}, mu: {mu})],
)"#
    )
}

/// Two cables' nodes striking head-on (both moving after the impact):
/// at `t = 0.03 s` (the gap over the speed), `ġ⁻ = −1 m/s`, the impulse
/// `Λ = (1 + e)|ġ⁻|/(wᵀ M⁻¹ w)` with `w = +1` on `a`'s end x and `−1` on
/// `b`'s start x (so `wᵀ M⁻¹ w = M⁻¹_aa + M⁻¹_bb − 2 M⁻¹_ab`, `M⁻¹`
/// inverted here), Carnot's energy lost, `ġ⁺ = −e ġ⁻`; with `e = 1` the
/// energy is kept through the impact. With friction (μ = 0.3) a head-on
/// impact has no tangential speed and takes no tangential impulse.
#[test]
fn two_cables_nodes_strike_head_on_by_the_generalised_newton_law() {
    for (e, mu) in [(0.5, 0.0), (1.0, 0.0), (0.5, 0.3)] {
        let (rep, model, cables) = simulate(&wires_head_on(e, mu), &run(0.1, 1e-3, 0.8));
        assert!(
            matches!(rep.stop, eom_sim::Stop::Finished),
            "e = {e}, μ = {mu}: {:?}",
            rep.stop
        );
        let ev = &rep.contact_events[0];
        assert_eq!(ev.kind, ContactEventKind::Impact);
        assert!((ev.t - 0.03).abs() < 1e-9, "impact at {}", ev.t);
        let c = &ev.contacts[0];
        assert!(
            (c.speed_before + 1.0).abs() < 1e-9,
            "ġ⁻ = {}",
            c.speed_before
        );
        assert!(
            (c.speed_after - e).abs() < 1e-9,
            "ġ⁺ = {}, want {e}",
            c.speed_after
        );
        let minv = dense_mass(&model).try_inverse().expect("M is invertible");
        let (ka, kb) = (
            free(&model, &cables[0], 2, 0),
            free(&model, &cables[1], 0, 0),
        );
        let wmw = minv[(ka, ka)] + minv[(kb, kb)] - 2.0 * minv[(ka, kb)];
        let want = (1.0 + e) / wmw;
        assert!(
            (c.impulse - want).abs() < 1e-9 * want,
            "e = {e}: Λ = {}, want {want}",
            c.impulse
        );
        let lost = ev.energy_before - ev.energy_after;
        let carnot = 0.5 * (1.0 - e * e) / wmw;
        assert!(
            (lost - carnot).abs() < 1e-9 * ev.energy_before,
            "e = {e}: lost {lost}, want Carnot's {carnot}"
        );
        assert!(
            c.tangential_impulse.iter().all(|x| x.abs() < 1e-12 * want),
            "head-on: no tangential impulse, {:?}",
            c.tangential_impulse
        );
    }
}

/// Coulomb friction at a node's sphere: the wire of
/// [`wire_on_a_sphere`] falling while it moves sideways at 0.5 m/s onto
/// the fixed sphere with μ = 0.3, e = 0.5. At the sphere's top its tangent
/// plane is the floor y = 0, so the impact is Newton–Coulomb's on that
/// plane: the same normal and tangential impulses as the plane twin (to
/// 1e-12 of the normal one), the tangential one in the cone `‖Λ_t‖ ≤ μ Λ`
/// and against the slide; then the node slides over the curving sphere
/// (its tangent axis `t1 = n × z` turning with the line of centres) and
/// no event raises the energy.
#[test]
fn a_sliding_wire_striking_a_sphere_takes_coulombs_impulse_at_the_node() {
    let (e, mu) = (0.5, 0.3);
    let r = run(0.4, 1e-3, 0.8);
    // Started to the left by what it slides until it strikes.
    let shift = 0.5 * (2.0 * (H0 - 0.01) / G).sqrt();
    let text = |target: &str| {
        wire_on_a_sphere_with(
            target,
            e,
            &format!(", mu: {mu}"),
            (", velocity: (0.5, 0, 0)", shift),
        )
    };
    let (sphere, _, _) = simulate(&text("sphere"), &r);
    let (plane, _, _) = simulate(&text("plane"), &r);
    finished_without_gaining(&[("sphere", &sphere), ("plane", &plane)], 1e-12);
    let (a, b) = (&sphere.contact_events[0], &plane.contact_events[0]);
    assert_eq!(a.kind, ContactEventKind::Impact);
    let (ca, cb) = (&a.contacts[0], &b.contacts[0]);
    assert!(
        ca.tangential_speed_before[0].abs() > 0.4,
        "sliding in: {ca:?}"
    );
    let lt = ca.tangential_impulse[0].hypot(ca.tangential_impulse[1]);
    assert!(
        lt > 0.0 && lt <= mu * ca.impulse * (1.0 + 1e-12),
        "cone: {ca:?}"
    );
    assert!(
        ca.tangential_impulse[0] * ca.tangential_speed_before[0] < 0.0,
        "against the slide: {ca:?}"
    );
    let tol = 1e-12 * ca.impulse;
    assert!(
        (a.t - b.t).abs() < 1e-12
            && (ca.impulse - cb.impulse).abs() < tol
            && (ca.tangential_impulse[0] - cb.tangential_impulse[0]).abs() < tol,
        "sphere {ca:?}\nplane {cb:?}"
    );
    println!(
        "sliding onto the sphere: {:?}",
        sphere
            .contact_events
            .iter()
            .map(|e| (e.kind, e.t))
            .collect::<Vec<_>>()
    );
}

/// A node's sphere is refused, at its field, where it cannot be run: its
/// node given as `b` only, inside a body's sphere at the start, about the
/// same node twice, at a node the cable
/// does not have, and inside the other sphere at the start (with the
/// penetration and what opens it).
#[test]
fn node_spheres_refused_with_their_locations() {
    let text = wire_on_a_sphere("sphere", 0.5);
    assert_eq!(diagnose(&text), "valid");
    assert_eq!(diagnose(&wire_on_a_sphere("node", 0.5)), "valid");
    let swap = text.replace(
        r#"a: (body: "wire", node: 2), b: (body: "ground", point: (0.5, -0.05, 0))"#,
        r#"a: (body: "ground", point: (0.5, -0.05, 0)), b: (body: "wire", node: 2)"#,
    );
    let out = diagnose(&swap);
    assert!(
        out.contains("contact `touch` has its cable node as `b`") && out.contains("as `a`"),
        "{out}"
    );
    let body = text
        .replace(
            "bodies: [],",
            r#"bodies: [(name: "ball", mass: 1, inertia: Diag(1, 1, 1))],"#,
        )
        .replace(
            "joints: [],",
            r#"joints: [(name: "j", kind: Planar, parent: "ground", child: "ball")],"#,
        )
        .replace(
            r#"b: (body: "ground", point: (0.5, -0.05, 0))"#,
            r#"b: (body: "ball")"#,
        );
    // A body's sphere is a contact (`cable_contacts_mixed.rs`); inside
    // it at the start, the penetration is named.
    assert_eq!(diagnose(&body), "valid");
    let in_ball = body.replace(
        r#"b: (body: "ball")"#,
        &format!(r#"b: (body: "ball", point: (0.5, {H0}, 0))"#),
    );
    let out = diagnose(&in_ball);
    assert!(
        out.contains(
            "node 2 of cable `wire` penetrates the sphere on body `ball` by 6.000000e-2 m"
        ),
        "{out}"
    );
    assert!(
        out.contains("or move the body or shrink the radii"),
        "{out}"
    );
    let twice = text.replace(
        r#"b: (body: "ground", point: (0.5, -0.05, 0))"#,
        r#"b: (body: "wire", node: 2)"#,
    );
    let out = diagnose(&twice);
    assert!(
        out.contains("both spheres of contact `touch` are about node 2"),
        "{out}"
    );
    let far = text.replace(
        r#"a: (body: "wire", node: 2)"#,
        r#"a: (body: "wire", node: 9)"#,
    );
    let out = diagnose(&far);
    assert!(out.contains("whose nodes are 0..=4"), "{out}");
    let inside = text.replace("radius_b: 0.05", "radius_b: 0.3");
    let out = diagnose(&inside);
    assert!(
        out.contains("node 2 of cable `wire` penetrates the fixed sphere by 6.000000e-2 m")
            && out.contains("away from the sphere's centre"),
        "{out}"
    );
    for out in [&swap, &in_ball, &twice, &far, &inside].map(|t| diagnose(t)) {
        assert!(out.contains("models/drop.ron:"), "located: {out}");
        assert_eq!(out.matches("error:").count(), 1, "{out}");
    }
}

/// The same with a spatial wire (`Cable3D`) sliding in at (0.5, 0, 0.3)
/// m/s. The fixed sphere's friction axes come from the world axis least
/// aligned with the line of centres at the start, (−0.098, 0.25, −0.059):
/// z, so at the top `t1 = z`, `t2 = n × t1 = x`; the plane's are
/// `t1 = x`, `t2 = −z`. The first impact is the tangent plane's, both
/// tangential impulses included (the same world vector, to 1e-12 of the
/// normal impulse), in the cone and against the slide; the run goes on
/// over the curving sphere in three dimensions without raising the
/// energy.
#[test]
fn a_spatial_wire_striking_a_sphere_takes_coulombs_impulse_in_both_axes() {
    let (e, mu) = (0.5, 0.3);
    let r = run(0.4, 1e-3, 0.8);
    let t1 = (2.0 * (H0 - 0.01) / G).sqrt();
    let text = |target: &str| {
        wire_on_a_sphere_with(
            target,
            e,
            &format!(", mu: {mu}"),
            (", velocity: (0.5, 0, 0.3)", 0.5 * t1),
        )
        .replace("Cable2D", "Cable3D")
        .replace("(0.5, -0.05, 0)", &format!("(0.5, -0.05, {:?})", 0.3 * t1))
        .replace(
            "normal: (0, 1, 0)",
            &format!("point: (0, 0, {:?}), normal: (0, 1, 0)", 0.3 * t1),
        )
    };
    let (sphere, _, _) = simulate(&text("sphere"), &r);
    let (plane, _, _) = simulate(&text("plane"), &r);
    finished_without_gaining(&[("sphere", &sphere), ("plane", &plane)], 1e-12);
    let (a, b) = (&sphere.contact_events[0], &plane.contact_events[0]);
    let (ca, cb) = (&a.contacts[0], &b.contacts[0]);
    assert_eq!(a.kind, ContactEventKind::Impact);
    let vt = ca.tangential_speed_before;
    assert!(
        (vt[0] - 0.3).abs() < 1e-9 && (vt[1] - 0.5).abs() < 1e-9,
        "v_t along (z, x): {vt:?}; the plane's (x, −z) {:?}",
        cb.tangential_speed_before
    );
    let lt = ca.tangential_impulse[0].hypot(ca.tangential_impulse[1]);
    assert!(
        lt > 0.0 && lt <= mu * ca.impulse * (1.0 + 1e-12),
        "cone: {ca:?}"
    );
    assert!(
        ca.tangential_impulse[0] * vt[0] + ca.tangential_impulse[1] * vt[1] < 0.0,
        "against the slide: {ca:?}"
    );
    let tol = 1e-12 * ca.impulse;
    assert!(
        (a.t - b.t).abs() < 1e-12
            && (ca.impulse - cb.impulse).abs() < tol
            && (ca.tangential_impulse[1] - cb.tangential_impulse[0]).abs() < tol
            && (ca.tangential_impulse[0] + cb.tangential_impulse[1]).abs() < tol,
        "sphere {ca:?}\nplane {cb:?}"
    );
}

/// Every run finished, and no contact event raised its energy (by more
/// than `tol` of the first event's, at least 1 J).
fn finished_without_gaining(runs: &[(&str, &eom_sim::RunReport)], tol: f64) {
    for (label, rep) in runs {
        assert!(
            matches!(rep.stop, eom_sim::Stop::Finished),
            "{label}: {:?}",
            rep.stop
        );
        let e0 = rep.contact_events.first().map_or(0.0, |e| e.energy_before);
        for ev in &rep.contact_events {
            assert!(
                ev.energy_after <= ev.energy_before + tol * e0.abs().max(1.0),
                "{label}: {:?} at {} raises the energy {} → {}",
                ev.kind,
                ev.t,
                ev.energy_before,
                ev.energy_after
            );
        }
    }
}

/// The friction axes of a node's sphere: the planar rule (`t1 = n × z`,
/// no reference axis) only where both centres stay in the x–y plane; a
/// planar cable's node against a fixed sphere off that plane, or against
/// a `Cable3D`'s node, takes the spatial rule (its normal leaves the
/// plane, and `n × z` would not be a unit axis).
#[test]
fn a_node_spheres_friction_axes_are_planar_only_in_the_plane() {
    let reference = |text: &str| {
        let sys = system(text);
        let (_, cables) = eom_gen::cables::structure(&sys).expect("structure");
        let contacts = eom_gen::cables::node_contacts(&sys, &cables);
        contacts[0].sphere.as_ref().expect("a sphere").reference
    };
    let inplane = wire_on_a_sphere_with("sphere", 0.5, ", mu: 0.3", ("", 0.0));
    assert_eq!(reference(&inplane), None);
    let off = inplane.replace("(0.5, -0.05, 0)", "(0.5, -0.05, 0.02)");
    assert_eq!(reference(&off), Some([1.0, 0.0, 0.0]));
    let node = wire_on_a_sphere_with("node", 0.5, ", mu: 0.3", ("", 0.0));
    assert_eq!(reference(&node), None);
    let spatial_stub = node.replace(
        r#"Cable(name: "stub", element: Cable2D"#,
        r#"Cable(name: "stub", element: Cable3D"#,
    );
    assert!(spatial_stub.contains("Cable3D"));
    assert!(reference(&spatial_stub).is_some());
}

/// A stiff rod (`Cable3D`, one element, 0.5 m, 0.05 kg) pinned at the
/// origin, lying on the floor z = 0 on its tip node, spinning about z at
/// 2 rad/s with Coulomb friction μ = 0.3 at the tip, the Kelvin–Voigt
/// bending damping `damping`.
fn spinning_rod(damping: f64) -> String {
    format!(
        r#"Model(
    name: "spinning_rod",
    gravity: (0, 0, -9.81),
    bodies: [],
    joints: [],
    cables: [
        Cable(name: "rod", element: Cable3D, from: (0, 0, 0), to: (0.5, 0, 0), elements: 1,
              young: 2e9, density: 1000, area: 1e-4, second_moment: 1e-9,
              damping_bending: {damping:e}, start: Pinned, angular_velocity: (0, 0, 2)),
    ],
    contacts: [
        Plane(name: "tip", at: (body: "rod", node: 1), normal: (0, 0, 1), e: 0, mu: 0.3),
    ],
)"#
    )
}

/// A curving slide stopped by friction: the rod spinning on the floor on
/// its tip. The tip carries half the rod's weight, `N = m g/2`, so
/// friction's moment `μ N L` takes the spin `I ω̇ = −μ N L` with
/// `I = m L²/3`: the tip stops (a located `stick`) at
/// `t = 2 L ω₀/(3 μ g)`, to 1e-4 with the bending vibration the start
/// excites damped (`damping_bending: 1e-2`), and stays stuck. Undamped,
/// the tip's normal force rings with the rod's bending (28 Hz) and the
/// stop moves by 0.7 %; then the released stretch slips the tip again,
/// and the rod's unresolved axial ringing makes it chatter in a slide
/// reversing at every step. That run finishes, its energy never above
/// the start: until this session its Newton stalled at t = 0.2302 s just
/// after the slip (the friction's direction taken at each Newton iterate
/// turned with `v_t` near zero; it is now the slide's direction at the
/// step's start).
#[test]
fn a_spinning_rod_is_stopped_by_friction_at_its_tip() {
    let stop = 2.0 * 0.5 * 2.0 / (3.0 * 0.3 * G);
    for (damping, tol) in [(1e-2, 1e-4), (0.0, 1e-2)] {
        let (report, _, _) = simulate(&spinning_rod(damping), &run(0.4, 1e-3, 0.8));
        assert!(
            matches!(report.stop, eom_sim::Stop::Finished),
            "damping {damping}: {:?}",
            report.stop
        );
        let e0 = report.energy[0];
        for ev in &report.contact_events {
            assert!(
                ev.energy_after <= e0 * (1.0 + 1e-9),
                "damping {damping}: energy {} J at {} s above the start {e0} J",
                ev.energy_after,
                ev.t
            );
        }
        let kinds: Vec<_> = report
            .contact_events
            .iter()
            .map(|e| (e.kind, e.t))
            .collect();
        println!("damping {damping}: {kinds:?}");
        let first = report
            .contact_events
            .iter()
            .find(|e| e.kind == ContactEventKind::Stick)
            .expect("the tip stops");
        assert!(
            (first.t - stop).abs() <= tol * stop,
            "damping {damping}: stopped at {} s, want 2 L ω₀/(3 μ g) = {stop} s",
            first.t
        );
        if damping > 0.0 {
            assert_eq!(
                kinds.len(),
                2,
                "rest at the start, then the stop: {kinds:?}"
            );
        }
    }
}
