//! Contacts at cable nodes in mixed models (issue #26): rigid bodies with
//! cables hung at their markers, a cable node against a plane fixed in the
//! world. The impact map is the rigid runtime's, on the mixed model's
//! coordinates `y = (x, q_r)` (the cables' free nodal coordinates, then the
//! rigid part's): `M (u⁺ − u⁻) = Wᵀ Λ + Jᵀ μ`, `M = diag(M_s, M_r(q_r))`,
//! with the attachments (and the rigid part's loops) held at the speed
//! level, `J (u⁺ − u⁻) = 0`, and `ġ⁺ = −e ġ⁻`.
//!
//! Physics checked:
//! - **A block on a vertical rail with a light arm clamped at it, dropped
//!   on the arm's node 0** (the node held at the block): block and arm fall
//!   freely and strike at `t₁ = √(2h₀/g)` with `ġ⁻ = −√(2gh₀)`; the
//!   impulse carries the block's mass through the clamp,
//!   `Λ = (1 + e) M_eff |ġ⁻|` with `M_b ≤ M_eff ≤ M_b + m_arm` (a part in
//!   5000 here), and the energy lost is Carnot's
//!   `½ (1 − e²) M_eff ġ⁻²`; every impact has `ġ⁺ = −e ġ⁻` to 1e-9. With
//!   `e = 0.5` the block hops, its hops shrink until they accumulate, and
//!   it rests: the sustained force then carries block and arm,
//!   `(M_b + m_arm) g`. With `e = 0` it rests at the first strike. Neither
//!   run takes more steps than its fixed step's count and a few per event
//!   (no endless run of tiny steps), and the attachment residual stays at
//!   the Newton tolerance through the impacts.
//! - **A pendulum with a short stiff cable hanging from its tip whose end
//!   node strikes a floor** (e = 0.5): every impact has `ġ⁺ = −e ġ⁻` to
//!   1e-9, never raises the energy, and loses `½ (1 − e) Λ |ġ⁻|` (the work
//!   of the impulse: Carnot's law for one row, the attachments doing no
//!   work at the speed level); the attachment residual stays at its
//!   tolerance.
//! - **The same pendulum with Coulomb friction** (μ = 0.3): impacts, rest,
//!   stick, slip and release; every impact keeps `ġ⁺ = −e ġ⁻`, does not
//!   raise the energy, and has its tangential impulse in the cone.
//! - **A rigid loop beside the cable**: the bundled four-bar whose coupler
//!   carries a hanging cable, its end node striking a floor — the loop's
//!   rows and the attachment held together through every impulse, the
//!   same Newton, energy and Carnot checks.
//! - **Coulomb friction at a body's contact beside cables**: a block
//!   beside the pendulum sticks on an incline for `tan θ < μ`, slides with
//!   `g (sin θ − μ cos θ)` for `tan θ > μ`, and pushed along a floor stops
//!   after `v₀²/(2 μ g)` at `v₀/(μ g)` (all to 1e-9), while the cable
//!   strikes beside it; a block braking on a table with a rope hanging
//!   from it is the same motion with the table's contact at the block or
//!   at the rope's node pinned there.
//! - **No event pulls**: every normal impulse is a push, `Λ ≥ 0`.

use eom_gen::functions::FunctionSet;
use eom_gen::mech::formulate;
use eom_gen::model::{Source, check};
use eom_sim::Integrator;
use eom_sim::large::{ElementRun, simulate_mixed};
use eom_sim::run::ContactEventKind;

const G: f64 = 9.81;

fn system(text: &str) -> eom_gen::System {
    match check(&Source::new("mixed_drop.ron", text.to_string())) {
        Ok(c) => c.system,
        Err(r) => panic!("{r}"),
    }
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

/// Runs the mixed model `text` (rigid part interpreted) through its
/// contacts at cable nodes; checks that no event pulls.
fn simulate(text: &str, r: &ElementRun) -> eom_sim::RunReport {
    let sys = system(text);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    eom_gen::cables::check_rigid(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let mixed = eom_gen::cables::mixed(&sys, eom_gen::cables::interpreted_rigid(&f, &sys))
        .unwrap_or_else(|e| panic!("{e}"));
    let contacts = eom_gen::cables::node_contacts(&sys, &mixed.cables);
    assert_eq!(contacts.len(), sys.cable_contacts.len());
    let (q0, u0) = eom_gen::cables::rigid_start(&sys, &f).unwrap_or_else(|e| panic!("{e}"));
    let own = |v: Vec<&str>| v.into_iter().map(str::to_string).collect::<Vec<_>>();
    let (qn, un) = (own(sys.coordinate_names()), own(sys.speed_names()));
    let (report, _) = simulate_mixed(
        &mixed.model,
        &mixed.cables,
        &contacts,
        (&q0, &u0),
        (&qn, &un),
        r,
        &mut |_| {},
    )
    .unwrap_or_else(|e| panic!("{e}"));
    eom_gen::testkit::no_event_pulls(&report, true);
    report
}

/// Every impact: `ġ⁺ = −e ġ⁻` to 1e-9 on every row, the energy not
/// raised, and (with `rel`, frictionless) the energy lost
/// `½ (1 − e) Λ |ġ⁻|` (one row; to `rel`).
/// Returns the number of impacts.
fn impacts_obey_newton_and_carnot(report: &eom_sim::RunReport, e: f64, rel: Option<f64>) -> usize {
    let mut n = 0;
    for ev in report
        .contact_events
        .iter()
        .filter(|x| x.kind == ContactEventKind::Impact)
    {
        n += 1;
        // Rounding against the size of the energies (`|T| + |V|`: a
        // pendulum's `T + V` can sit near zero), a part in 10¹¹.
        let scale = ev.energy_before.abs().max(report.energy_scale).max(1e-12);
        assert!(
            ev.energy_after <= ev.energy_before + 1e-11 * scale,
            "impact at {} raises the energy {} → {}",
            ev.t,
            ev.energy_before,
            ev.energy_after
        );
        for c in &ev.contacts {
            let newton = c.speed_after + e * c.speed_before;
            assert!(
                newton.abs() <= 1e-9,
                "impact at {}: ġ⁺ = {}, −e ġ⁻ = {}",
                ev.t,
                c.speed_after,
                -e * c.speed_before
            );
        }
        if let (Some(rel), [c]) = (rel, ev.contacts.as_slice()) {
            let lost = ev.energy_before - ev.energy_after;
            let carnot = 0.5 * (1.0 - e) * c.impulse * (-c.speed_before);
            eprintln!(
                "impact at {:.6} s: ġ⁻ = {:.6e} m/s, Λ = {:.6e} N s, lost {lost:.6e} J, Carnot {carnot:.6e} J",
                ev.t, c.speed_before, c.impulse
            );
            assert!(
                (lost - carnot).abs() <= rel * carnot.abs() + 1e-11 * scale,
                "impact at {}: lost {lost} J, Carnot ½ (1 − e) Λ |ġ⁻| = {carnot} J",
                ev.t
            );
        }
    }
    n
}

/// The bundled block on a rail with its clamped arm, dropped on the arm's
/// node 0 (`models/ancf/block_drop.ron`), at restitution `e`.
fn block_drop(e: f64) -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/ancf/block_drop.ron");
    let text = std::fs::read_to_string(path).unwrap_or_else(|err| panic!("{path}: {err}"));
    text.replace(
        r#"(name: "e", value: 0.5,"#,
        &format!(r#"(name: "e", value: {e:?},"#),
    )
}

/// [`block_drop`] with the floor under the block instead of under its
/// arm's node: the rail's lower limit at `y = −h₀`, a rigid body's contact
/// beside the cable (the node 0 sits at the block's hook, so both gaps are
/// `y + h₀`, and the closed forms are the same).
fn block_drop_on_its_rail(e: f64) -> String {
    let node = r#"Plane(name: "foot", at: (body: "arm", node: 0), point: (0, "-h0", 0), normal: (0, 1, 0), e: "e"),"#;
    let text = block_drop(e);
    assert!(text.contains(node), "the bundled block_drop's contact");
    text.replace(
        node,
        r#"JointLimit(name: "foot", joint: "rail", lower: "-h0", e: "e"),"#,
    )
}

/// Block 1 kg, arm ρ A L = 100 · 1e-5 · 0.2 kg, dropped from 0.05 m.
const M_BLOCK: f64 = 1.0;
const M_ARM: f64 = 100.0 * 1e-5 * 0.2;
const H0: f64 = 0.05;

#[test]
fn a_block_dropped_on_its_arms_held_node_hops_and_comes_to_rest() {
    hops_and_comes_to_rest(&block_drop(0.5), 0.5, "block_drop");
}

/// The same drop on the rail's lower limit: a rigid body's contact in a
/// model with a cable (its row from the rigid part's generated
/// `contacts`, held as an index-3 row while it rests), by the same closed
/// forms.
#[test]
fn a_block_dropped_on_its_rails_limit_beside_its_arm_hops_and_comes_to_rest() {
    hops_and_comes_to_rest(&block_drop_on_its_rail(0.5), 0.5, "block_drop on its rail");
}

fn hops_and_comes_to_rest(text: &str, e: f64, label: &str) {
    let (t_end, dt) = (0.5, 1e-3);
    let report = simulate(text, &run(t_end, dt, 0.5));
    assert!(
        matches!(report.stop, eom_sim::Stop::Finished),
        "{:?}",
        report.stop
    );
    // The first strike: free fall from h₀, the block's mass behind the
    // node through the clamp.
    let t1 = (2.0 * H0 / G).sqrt();
    let v1 = (2.0 * G * H0).sqrt();
    let first = &report.contact_events[0];
    assert_eq!(first.kind, ContactEventKind::Impact);
    let c = &first.contacts[0];
    assert!((first.t - t1).abs() < 1e-9, "t₁ {} want {t1}", first.t);
    assert!(
        (c.speed_before + v1).abs() < 1e-9,
        "ġ⁻ {} want {}",
        c.speed_before,
        -v1
    );
    let m_eff = c.impulse / ((1.0 + e) * v1);
    assert!(
        (M_BLOCK..=M_BLOCK + M_ARM).contains(&m_eff),
        "Λ/((1 + e)|ġ⁻|) = {m_eff} kg, want between the block's {M_BLOCK} and block and arm's {}",
        M_BLOCK + M_ARM
    );
    let lost = first.energy_before - first.energy_after;
    let carnot = 0.5 * (1.0 - e * e) * m_eff * v1 * v1;
    assert!(
        (lost - carnot).abs() < 1e-6 * carnot,
        "lost {lost} J, Carnot {carnot} J"
    );
    let impacts = impacts_obey_newton_and_carnot(&report, e, Some(1e-6));
    // The hops accumulate and the block rests: the node held, its force
    // carrying block and arm.
    let el = report.elements.as_ref().expect("element report");
    let weight = (M_BLOCK + M_ARM) * G;
    let [held] = el.contact_forces.as_slice() else {
        panic!("the node rests at the end: {:?}", el.contact_forces);
    };
    println!(
        "{label} e = {e}: {impacts} impacts, {} events, {} steps; force at the end {} N (weight {weight} N); largest |Φ| {:.1e}",
        report.contact_events.len(),
        report.stats.accepted,
        held.force,
        el.largest_constraint_residual
    );
    assert!(impacts >= 3, "the block hops: {impacts} impacts");
    assert!(
        (held.force - weight).abs() < 1e-3 * weight,
        "{} N, want {weight} N",
        held.force
    );
    assert!(
        el.largest_constraint_residual < 1e-9,
        "attachment residual {:e}",
        el.largest_constraint_residual
    );
    // No endless run of tiny steps: the fixed steps and a few per event.
    let fixed = (t_end / dt).round() as usize;
    assert!(
        report.stats.accepted <= fixed + 4 * report.contact_events.len() + 10,
        "{} steps for {fixed} fixed and {} events",
        report.stats.accepted,
        report.contact_events.len()
    );
}

#[test]
fn a_block_dropped_plastically_rests_at_the_first_strike() {
    rests_at_the_first_strike(&block_drop(0.0), "block_drop");
    rests_at_the_first_strike(&block_drop_on_its_rail(0.0), "block_drop on its rail");
}

fn rests_at_the_first_strike(text: &str, label: &str) {
    let (t_end, dt) = (0.3, 1e-3);
    let report = simulate(text, &run(t_end, dt, 0.5));
    assert!(
        matches!(report.stop, eom_sim::Stop::Finished),
        "{:?}",
        report.stop
    );
    let v1 = (2.0 * G * H0).sqrt();
    let first = &report.contact_events[0];
    assert_eq!(first.kind, ContactEventKind::Impact);
    let c = &first.contacts[0];
    assert!(c.speed_after.abs() < 1e-9, "ġ⁺ {}", c.speed_after);
    let m_eff = c.impulse / v1;
    assert!(
        (M_BLOCK..=M_BLOCK + M_ARM).contains(&m_eff),
        "Λ/|ġ⁻| = {m_eff} kg"
    );
    // Carnot: the whole kinetic energy of the lost speed.
    let lost = first.energy_before - first.energy_after;
    let carnot = 0.5 * m_eff * v1 * v1;
    assert!(
        (lost - carnot).abs() < 1e-6 * carnot,
        "lost {lost} J, Carnot {carnot} J"
    );
    impacts_obey_newton_and_carnot(&report, 0.0, Some(1e-6));
    let el = report.elements.as_ref().expect("element report");
    let weight = (M_BLOCK + M_ARM) * G;
    let [held] = el.contact_forces.as_slice() else {
        panic!("the node rests: {:?}", el.contact_forces);
    };
    println!(
        "{label} e = 0: {} events, {} steps; force {} N (weight {weight} N); largest |Φ| {:.1e}",
        report.contact_events.len(),
        report.stats.accepted,
        held.force,
        el.largest_constraint_residual
    );
    assert!(
        (held.force - weight).abs() < 1e-3 * weight,
        "{} N, want {weight} N",
        held.force
    );
    assert!(el.largest_constraint_residual < 1e-9);
    let fixed = (t_end / dt).round() as usize;
    assert!(report.stats.accepted <= fixed + 4 * report.contact_events.len() + 10);
}

/// The bundled `models/ancf/pendulum_cable.ron`: a uniform link (0.3 m,
/// 0.5 kg) pivoted at the origin about z, starting level along +x at rest,
/// with a short stiff cable (0.15 m, 2 elements) pinned at its tip and
/// hanging straight down; the cable's end node touches the floor
/// `y = −0.25`, here with restitution `e`.
fn pendulum_cable(e: f64) -> String {
    pendulum_cable_with(e, "")
}

/// [`pendulum_cable`] with `extra` appended to the contact.
fn pendulum_cable_with(e: f64, extra: &str) -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/pendulum_cable.ron"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|err| panic!("{path}: {err}"));
    let (param, contact) = (r#"(name: "e", value: 0.5,"#, r#"e: "e"),"#);
    assert!(
        text.contains(param) && text.contains(contact),
        "the bundled pendulum_cable"
    );
    text.replace(param, &format!(r#"(name: "e", value: {e:?},"#))
        .replace(contact, &format!(r#"e: "e"{extra}),"#))
}

/// The pendulum's stiff cable (E = 2e9, `ω h` ≫ 100 for its bending
/// modes) at steps from 0.5e-3 to 2e-3 s, ρ∞ = 0.8: every run finishes,
/// every impact by Newton and Carnot, the energy never above its start
/// (it ends 0.14–0.16 J below it at every step), and the steps taken are
/// the fixed step's count and a few per event. Until session 44, 0.8e-3,
/// 1.1e-3 and 1.2e-3 s stopped ("Newton failed") and the runs that
/// finished passed through 10²–10³ J: generalized-α restarted at
/// `a = ÿ` after each event overshot the cable's unresolved modes
/// (`GeneralizedAlpha::restarted` now starts with Newmark's `β = ½`,
/// `γ = 1` from the predictor `y + h ẏ`), and a node leaving an impact
/// rising had its return located picoseconds after the impact, again and
/// again (`on_the_steps` now takes a located state only where the row
/// closes).
#[test]
fn a_pendulums_hanging_cable_strikes_the_floor_at_every_step_from_5e_4_to_2e_3() {
    let e = 0.5;
    for dt in [
        0.5e-3, 0.7e-3, 0.8e-3, 0.9e-3, 1e-3, 1.1e-3, 1.2e-3, 1.5e-3, 2e-3,
    ] {
        let report = simulate(&pendulum_cable(e), &run(0.25, dt, 0.8));
        let label = format!("pendulum_cable dt = {dt}");
        let impacts = finished_with_impacts_by_newton(&report, e, &label);
        assert!(impacts >= 3, "{label}: the end node strikes the floor");
        let fixed = (0.25 / dt).round() as usize;
        assert!(
            report.stats.accepted <= fixed + 10 * report.contact_events.len(),
            "{label}: {} steps for {fixed} fixed and {} events",
            report.stats.accepted,
            report.contact_events.len()
        );
    }
}

/// A run gone wrong is refused, not reported: the same pendulum at
/// ρ∞ = 1 (no damping of the modes the step does not resolve) and
/// 1.5e-3 s gains hundreds of joules from 0 J by t = 0.134 s; the model
/// has no energy source, so the run stops there with the reason
/// (`DynamicsError::EnergyRose`; the CLI exits 3). At ρ∞ = 1 and 1.2e-3 s
/// it finishes, its energy never above the start.
#[test]
fn a_pendulums_cable_run_gone_wrong_is_refused() {
    let report = simulate(&pendulum_cable(0.5), &run(0.25, 1.5e-3, 1.0));
    match &report.stop {
        eom_sim::Stop::Failed { t, message } => {
            assert!(message.contains("the energy rose"), "{message}");
            println!("ρ∞ = 1, dt = 1.5e-3: stopped at t = {t}: {message}");
        }
        other => panic!(
            "a blown-up run was not refused: {other:?}, energy {:?}",
            report.energy
        ),
    }
    let report = simulate(&pendulum_cable(0.5), &run(0.25, 1.2e-3, 1.0));
    finished_with_impacts_by_newton(&report, 0.5, "pendulum_cable ρ∞ = 1, dt = 1.2e-3");
}

/// The models here are passive (gravity, damping, impacts): the energy
/// before and after every contact event is never above the start by more
/// than 1e-3 of the run's energy scale (generalized-α's energy error over
/// these runs is far smaller: the block drop's largest energy is its start
/// to 1e-16 J, the four-bar's 3.7 J throughout). Impacts checked one by
/// one cannot see energy gained between them.
fn energy_never_rises(report: &eom_sim::RunReport, label: &str) {
    let e0 = report.energy[0];
    let tol = 1e-3 * report.energy_scale.max(e0.abs()).max(1e-12);
    for ev in &report.contact_events {
        for en in [ev.energy_before, ev.energy_after] {
            assert!(
                en <= e0 + tol,
                "{label}: energy {en} J at the event at t = {} above the start {e0} J",
                ev.t
            );
        }
    }
    assert!(
        report.energy[1] <= e0 + tol,
        "{label}: energy {:?}",
        report.energy
    );
}

/// `report` finished, every impact obeys Newton's law with `e` and
/// Carnot's energy loss ([`impacts_obey_newton_and_carnot`]), the energy
/// never rises ([`energy_never_rises`]), and the attachments and loops
/// held to 1e-9 throughout; returns the impacts.
fn finished_with_impacts_by_newton(report: &eom_sim::RunReport, e: f64, label: &str) -> usize {
    assert!(
        matches!(report.stop, eom_sim::Stop::Finished),
        "{:?}",
        report.stop
    );
    let impacts = impacts_obey_newton_and_carnot(report, e, Some(1e-6));
    energy_never_rises(report, label);
    let el = report.elements.as_ref().expect("element report");
    println!(
        "{label} e = {e}: {impacts} impacts, {} events, {} steps; largest |Φ| {:.1e}",
        report.contact_events.len(),
        report.stats.accepted,
        el.largest_constraint_residual
    );
    assert!(
        el.largest_constraint_residual < 1e-9,
        "constraint residual {:e}",
        el.largest_constraint_residual
    );
    impacts
}

/// With Coulomb friction (μ = 0.3) at the end node the same pendulum runs
/// through impacts, a rest, a stick, a slip and a release: every impact
/// still has `ġ⁺ = −e ġ⁻` to 1e-9 and never raises the energy (the
/// tangential impulse works too, so Carnot's one-row law does not apply),
/// its tangential impulse lies in the cone `‖Λ_t‖ ≤ μ Λ`, and no event
/// pulls, and the energy never rises ([`energy_never_rises`]).
///
/// Steps 0.3e-3 to 2e-3 s. (Until session 44 the run at 1e-3 s ended at
/// 1.29 J from 0 J, the defect of the frictionless pendulum's above, and
/// the runs at 0.3e-3 to 0.5e-3 s stopped at the stick at t = 0.1207 s:
/// the tangential impulse that stops the slide lifts the node by 3e-9 m/s
/// through the cable, Λ = −1.1e-11 N s, and a sticking row that would
/// separate was refused. It is released now: with no normal impulse the
/// cone allows no tangential one. At these steps the node lands again and
/// hops before it rests, slips and leaves: 6 impacts in 11 events.)
#[test]
fn a_pendulums_hanging_cable_with_friction_keeps_newton_and_coulomb() {
    let (e, mu) = (0.5, 0.3);
    for dt in [0.3e-3, 0.5e-3, 0.6e-3, 0.8e-3, 1e-3, 1.2e-3, 1.5e-3, 2e-3] {
        friction_run(e, mu, dt);
    }
}

/// One run of [`a_pendulums_hanging_cable_with_friction_keeps_newton_and_coulomb`].
fn friction_run(e: f64, mu: f64, dt: f64) {
    let report = simulate(
        &pendulum_cable_with(e, &format!(", mu: {mu:?}")),
        &run(0.25, dt, 0.8),
    );
    assert!(
        matches!(report.stop, eom_sim::Stop::Finished),
        "{:?}",
        report.stop
    );
    let impacts = impacts_obey_newton_and_carnot(&report, e, None);
    energy_never_rises(&report, &format!("pendulum_cable with friction, dt = {dt}"));
    assert!(impacts >= 1, "the end node strikes the floor");
    for ev in report
        .contact_events
        .iter()
        .filter(|x| x.kind == ContactEventKind::Impact)
    {
        for c in &ev.contacts {
            let lt = c.tangential_impulse[0].hypot(c.tangential_impulse[1]);
            assert!(
                lt <= mu * c.impulse * (1.0 + 1e-9) + 1e-15,
                "impact at {}: ‖Λ_t‖ = {lt} outside μ Λ = {}",
                ev.t,
                mu * c.impulse
            );
        }
    }
    let el = report.elements.as_ref().expect("element report");
    println!(
        "pendulum_cable e = {e}, μ = {mu}, dt = {dt}: {impacts} impacts, {} events, {} steps; largest |Φ| {:.1e}",
        report.contact_events.len(),
        report.stats.accepted,
        el.largest_constraint_residual
    );
    assert!(el.largest_constraint_residual < 1e-9);
}

/// The bundled four-bar with a hanging cable (`models/ancf/fourbar_cable.ron`:
/// a rigid loop closed by a cut joint, the cable pinned at the coupler)
/// with a floor `y = −0.1` under the cable's end node, e = 0.5: the
/// impulses hold the loop's rows and the attachment together at the speed
/// level. Over 1.25 s: every impact `ġ⁺ = −e ġ⁻` to 1e-9, never raising
/// the energy and losing `½ (1 − e) Λ |ġ⁻|` to 1e-6; the constraint
/// residual (loop and attachment) at the Newton tolerance; no pulls. (The
/// run used to stop at t = 1.1934 s with 64 events and no time passing:
/// the resting node's force, 8e-6 N at a step's start and −13 N at its
/// end, crossed zero within a part in 10⁶ of the step, was taken at the
/// start, where the force problem held the node again.)
#[test]
fn a_four_bars_hanging_cable_strikes_the_floor_with_the_loop_held() {
    let e = 0.5;
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/fourbar_cable.ron"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|err| panic!("{path}: {err}"));
    let i = text.rfind(')').expect("the model's closing parenthesis");
    let text = format!(
        r#"{}    contacts: [
        Plane(name: "floor", at: (body: "cable", node: 4), point: (0, -0.1, 0), normal: (0, 1, 0), e: {e:?}),
    ],
)"#,
        &text[..i]
    );
    let report = simulate(&text, &run(1.25, 1e-3, 0.8));
    let impacts = finished_with_impacts_by_newton(&report, e, "fourbar_cable");
    assert!(impacts >= 3, "the end node strikes the floor: {impacts}");
}

/// The pendulum with its cable, the floor `y = −0.28` under the point
/// `at` (`e = 0.5`) instead of under the cable's end node.
fn pendulum_tip_on_the_floor(at: &str) -> String {
    let text = pendulum_cable(0.5);
    let node = r#"at: (body: "rope", node: 2), point: (0, -0.25, 0)"#;
    assert!(text.contains(node), "the pendulum's contact");
    text.replace(node, &format!("at: {at}, point: (0, -0.28, 0)"))
}

/// A rigid body's contact whose row is not constant, beside a cable,
/// against its twin at a cable node. The link's tip strikes the floor
/// `y = −0.28`: `g = 0.3 sin θ + 0.28`, `w = 0.3 cos θ`, `γ = 0.3 sin θ θ̇²`
/// from the rigid part's generated `contacts`, held while it rests as an
/// index-3 row re-evaluated at every Newton iterate. Its twin is the same
/// floor under the cable's node 0, pinned at the tip: a row constant in
/// the node's `y`. On the attachment's manifold the two are one gap and
/// the impact map holds the attachment, so the runs are one motion: the
/// same events at the same times (to 1e-7 s; 5e-9 s measured), the same
/// impulses and resting force (to 1e-6 of each; 3e-8 measured), each
/// impact by Newton and Carnot, the energy never above its start, and the
/// link at rest on the floor at the end.
///
/// At `--dt 1e-3` the run needs `ρ∞ = 0.5`: with `ρ∞ = 0.8` the tip's
/// impact yanks the stiff cable (E = 2e9) whose axial modes the step does
/// not resolve, the energy rises to 10.6 J from 0 J, and both twins are
/// refused by the energy guard at t = 0.2360 s (BENCHMARKS.md, "A body's
/// contact beside a cable"); at `--dt 2e-4` they finish with `ρ∞ = 0.8`.
#[test]
fn a_links_tip_striking_the_floor_beside_its_cable_is_its_pinned_nodes_twin() {
    let r = run(1.0, 1e-3, 0.5);
    let body = simulate(
        &pendulum_tip_on_the_floor(r#"(body: "link", marker: "tip")"#),
        &r,
    );
    let node = simulate(&pendulum_tip_on_the_floor(r#"(body: "rope", node: 0)"#), &r);
    let impacts = finished_with_impacts_by_newton(&body, 0.5, "link tip on the floor");
    finished_with_impacts_by_newton(&node, 0.5, "node 0 on the floor");
    assert!(impacts >= 3, "the tip strikes and hops: {impacts}");
    same_events(&body, &node);
    for (b, n) in body.contact_events.iter().zip(&node.contact_events) {
        for (cb, cn) in b.contacts.iter().zip(&n.contacts) {
            assert!(
                (cb.impulse - cn.impulse).abs() <= 1e-6 * cn.impulse.abs() + 1e-12,
                "{:?} at {} s: Λ {} and {}",
                b.kind,
                b.t,
                cb.impulse,
                cn.impulse
            );
            assert!((cb.speed_before - cn.speed_before).abs() < 1e-6);
        }
    }
    let (fb, fnode) = (resting_force(&body), resting_force(&node));
    assert!(
        fb > 0.0 && (fb - fnode).abs() <= 1e-6 * fnode,
        "{fb} N and {fnode} N"
    );
    assert!(
        (body.q[0] - node.q[0]).abs() < 1e-9,
        "θ {} and {}",
        body.q[0],
        node.q[0]
    );
}

/// The energy guard's premise, read from the model: a pendulum with its
/// cable, gravity and a joint spring-damper can gain no energy; an
/// actuator, a joint force or a prescribed motion can, and each is named
/// (so those runs are never refused for their energy).
#[test]
fn what_can_feed_energy_into_a_mixed_model_is_named() {
    let with_forces = |forces: &str| {
        let text = pendulum_cable(0.5);
        let i = text.rfind(')').expect("the model's closing parenthesis");
        format!("{}    forces: [{forces}],\n)", &text[..i])
    };
    let source = |text: &str| eom_gen::cables::energy_source(&system(text));
    assert_eq!(source(&pendulum_cable(0.5)), None);
    assert_eq!(
        source(&with_forces(
            r#"JointSpringDamper(name: "spring", joint: "pivot", stiffness: 2, damping: 0.1)"#
        )),
        None
    );
    for (forces, named) in [
        (
            r#"Actuator(name: "motor", joint: "pivot")"#,
            "the actuator `motor`",
        ),
        (
            r#"JointForce(name: "push", joint: "pivot", values: ["0.1*sin(t)"])"#,
            "the joint force `push`",
        ),
    ] {
        assert_eq!(source(&with_forces(forces)).as_deref(), Some(named));
    }
    let prescribed = pendulum_cable(0.5).replace(
        r#"coordinates: ["theta"]"#,
        r#"coordinates: ["theta"], prescribed: ["-0.5*t"]"#,
    );
    assert_eq!(
        source(&prescribed).as_deref(),
        Some("the prescribed motion of joint `pivot`")
    );
    let with_constraint = |expr: &str| {
        let text = pendulum_cable(0.5);
        let i = text.rfind(')').expect("the model's closing parenthesis");
        format!(
            "{}    constraints: [Holonomic(name: \"hold\", expr: \"{expr}\")],\n)",
            &text[..i]
        )
    };
    assert_eq!(source(&with_constraint("theta")), None);
    assert_eq!(
        source(&with_constraint("theta + 0.5*t")).as_deref(),
        Some("the constraint `hold`, which moves with t")
    );
}

/// [`pendulum_cable`] (e = 0.5) with a 2 kg block beside it on a planar
/// joint (x, y, angle), touching at its centre of mass a plane through
/// the origin with normal `(nx, ny, 0)`, plastic, friction `mu`, starting
/// at the origin with speeds `u0`. The block and the pendulum share no
/// joint, force or mass: the block moves by its closed forms while the
/// cable strikes its floor beside it.
fn block_beside_the_pendulum(nx: f64, ny: f64, mu: f64, u0: [f64; 3]) -> String {
    let text = pendulum_cable(0.5);
    for list in ["bodies: [", "joints: [", "contacts: ["] {
        assert!(text.contains(list), "the bundled pendulum_cable's {list}");
    }
    text.replace(
        "bodies: [",
        r#"bodies: [
        (name: "block", mass: 2, inertia: Diag(0.1, 0.1, 0.1)),"#,
    )
    .replace(
        "joints: [",
        &format!(
            r#"joints: [
        (name: "p", kind: Planar, parent: "ground", child: "block", coordinates: ["x", "y", "a"], q0: [0, 0, 0], u0: [{:?}, {:?}, {:?}]),"#,
            u0[0], u0[1], u0[2]
        ),
    )
    .replace(
        "contacts: [",
        &format!(
            r#"contacts: [
        Plane(name: "slope", at: (body: "block"), normal: ({nx:?}, {ny:?}, 0), e: 0, mu: {mu:?}),"#
        ),
    )
}

/// The rigid coordinates and speeds of `report` by name.
fn rigid_state(text: &str, report: &eom_sim::RunReport, name: &str) -> (f64, f64) {
    let sys = system(text);
    let k = sys
        .coordinate_names()
        .iter()
        .position(|c| *c == name)
        .unwrap_or_else(|| panic!("no coordinate {name}: {:?}", sys.coordinate_names()));
    (report.q[k], report.u[k])
}

/// Coulomb friction at a rigid body's contact beside cables, against
/// the closed forms of a block (`eom-gen/tests/friction.rs` runs the same
/// block alone through the rigid runtime): on an incline of `θ = 0.4`
/// (`tan θ = 0.4228`) it sticks for `μ = 0.5` (every coordinate and
/// speed stays 0) and slides for `μ = 0.3` with `g (sin θ − μ cos θ)`
/// (distance and speed after 0.6 s to 1e-9); pushed along a level floor
/// at `v₀ = 2 m/s` with `μ = 0.3` it stops after `v₀²/(2 μ g)` at
/// `t = v₀/(μ g)` (a located `stick`, to 1e-9) and stays. Meanwhile the
/// pendulum's cable strikes its own floor, hops and rests: every segment
/// restart and every impact of the cable re-solves the block's contact,
/// which must come out unchanged. The block's rows are the generated
/// `contacts` and `friction` of the rigid part, evaluated per state; a
/// stick holds its tangential row step by step (`W_t (y − y_n) = 0`).
#[test]
fn a_block_beside_a_cable_sticks_slides_and_stops_by_coulomb() {
    let theta: f64 = 0.4;
    let (s, c) = theta.sin_cos();
    let r = run(0.6, 1e-3, 0.8);
    // Sticks.
    let text = block_beside_the_pendulum(-s, c, 0.5, [0.0; 3]);
    let report = simulate(&text, &r);
    finished_with_impacts_by_newton(&report, 0.5, "block stuck beside the pendulum");
    for name in ["x", "y", "a"] {
        let (q, u) = rigid_state(&text, &report, name);
        assert!(
            q.abs() < 1e-10 && u.abs() < 1e-10,
            "sticks: {name} = {q}, speed {u}"
        );
    }
    // Slides.
    let mu = 0.3;
    let text = block_beside_the_pendulum(-s, c, mu, [0.0; 3]);
    let report = simulate(&text, &r);
    finished_with_impacts_by_newton(&report, 0.5, "block sliding beside the pendulum");
    let a = G * (s - mu * c);
    let (t_end, dist) = (0.6, 0.5 * a * 0.36);
    let ((x, vx), (y, vy)) = (
        rigid_state(&text, &report, "x"),
        rigid_state(&text, &report, "y"),
    );
    assert!(
        (x + dist * c).abs() < 1e-9 && (y + dist * s).abs() < 1e-9,
        "slid to ({x}, {y}), want {dist} m down the slope: ({}, {})",
        -dist * c,
        -dist * s
    );
    assert!(
        (vx.hypot(vy) - a * t_end).abs() < 1e-9,
        "speed {}, want g (sin θ − μ cos θ) t = {}",
        vx.hypot(vy),
        a * t_end
    );
    assert!(
        rigid_state(&text, &report, "a").0.abs() < 1e-12,
        "no turning"
    );
    // Pushed along a level floor: stops and stays.
    let v0 = 2.0;
    let text = block_beside_the_pendulum(0.0, 1.0, mu, [v0, 0.0, 0.0]);
    let report = simulate(&text, &run(1.0, 1e-3, 0.8));
    finished_with_impacts_by_newton(&report, 0.5, "block pushed beside the pendulum");
    let want = v0 * v0 / (2.0 * mu * G);
    let (x, vx) = rigid_state(&text, &report, "x");
    assert!(
        (x - want).abs() < 1e-9 && vx.abs() < 1e-12,
        "stopped at {x} (speed {vx}), want v0²/(2 μ g) = {want}"
    );
    // The block's changes between sliding and sticking: its stop, once.
    let changes: Vec<_> = report
        .contact_events
        .iter()
        .filter(|e| matches!(e.kind, ContactEventKind::Stick | ContactEventKind::Slip))
        .filter(|e| e.contacts.iter().any(|c| c.contact == "slope"))
        .collect();
    let t_stop = v0 / (mu * G);
    let [stop] = changes.as_slice() else {
        panic!("the block stops once and stays: {changes:?}");
    };
    assert!(
        stop.kind == ContactEventKind::Stick && (stop.t - t_stop).abs() < 1e-9,
        "{:?} at t = {}, want a stick at v0/(μ g) = {t_stop}",
        stop.kind,
        stop.t
    );
    // Every event of the cable's floor afterwards left the block stuck.
    for ev in report.contact_events.iter().filter(|e| e.t > t_stop) {
        for c in ev.contacts.iter().filter(|c| c.contact == "slope") {
            assert!(
                c.tangential_speed_after[0].abs() < 1e-12,
                "the block moved at {}: {:?}",
                ev.t,
                c
            );
        }
    }
}

/// The bundled block braking on a table with its rope
/// (`models/ancf/block_rope.ron`: 1 kg, pushed at 1 m/s, a 0.3 m rope
/// pinned at its centre and hanging through a slot), the table's contact
/// (plastic, μ = 0.3) `at` the block's hook or the rope's node 0 held
/// there.
fn block_with_a_rope(at: &str) -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/ancf/block_rope.ron");
    let text = std::fs::read_to_string(path).unwrap_or_else(|err| panic!("{path}: {err}"));
    let contact = r#"at: (body: "block", marker: "hook"), normal"#;
    assert!(text.contains(contact), "the bundled block_rope's contact");
    text.replace(contact, &format!("at: {at}, normal"))
}

/// Friction at a body's contact whose motion the cable changes, against
/// its twin at a cable node: the block with its rope (0.03 kg) slides on
/// the table and the rope, swinging back as the block brakes, loads and
/// pulls it until it stops. The table's contact at the block's hook (the
/// rigid part's generated rows, its stick held step by step) and at the
/// rope's node 0 pinned there (constant rows, its stick held at an
/// anchor) are one contact on the attachment's manifold: the same events
/// (rest, the slide's stop, any slip after it) at the same times, the
/// same normal forces, the block at the same place; the stop near
/// `v₀²/(2 μ g)` (the rope's swing changes the normal force by a few
/// per cent).
#[test]
fn a_block_braking_with_its_rope_by_friction_is_its_pinned_nodes_twin() {
    let r = run(0.6, 1e-3, 0.8);
    let body = simulate(&block_with_a_rope(r#"(body: "block", marker: "hook")"#), &r);
    let node = simulate(&block_with_a_rope(r#"(body: "rope", node: 0)"#), &r);
    for (label, rep) in [("hook", &body), ("node 0", &node)] {
        assert!(
            matches!(rep.stop, eom_sim::Stop::Finished),
            "{label}: {:?}",
            rep.stop
        );
        energy_never_rises(rep, label);
        let kinds: Vec<_> = rep.contact_events.iter().map(|e| (e.kind, e.t)).collect();
        println!("{label}: x = {:.9} m, events {kinds:?}", rep.q[0]);
    }
    same_events(&body, &node);
    assert!(
        body.contact_events
            .iter()
            .any(|e| e.kind == ContactEventKind::Stick),
        "the block stops"
    );
    let stop = 1.0 / (2.0 * 0.3 * G);
    assert!(
        (body.q[0] - stop).abs() < 0.1 * stop,
        "stopped at {} m, near v0²/(2 μ g) = {stop} m",
        body.q[0]
    );
    assert!(
        (body.q[0] - node.q[0]).abs() < 1e-9 && (body.q[1] - node.q[1]).abs() < 1e-9,
        "x {} and {}, y {} and {}",
        body.q[0],
        node.q[0],
        body.q[1],
        node.q[1]
    );
    let (fb, fnode) = (resting_force(&body), resting_force(&node));
    assert!(
        fb > 0.0 && (fb - fnode).abs() <= 1e-6 * fnode,
        "{fb} N and {fnode} N"
    );
}

/// Twins: the same contact events, of the same kinds, at the same times
/// (to 1e-7 s).
fn same_events(body: &eom_sim::RunReport, node: &eom_sim::RunReport) {
    assert_eq!(
        body.contact_events.len(),
        node.contact_events.len(),
        "the same events"
    );
    for (b, n) in body.contact_events.iter().zip(&node.contact_events) {
        assert_eq!(b.kind, n.kind, "at {} s", b.t);
        assert!(
            (b.t - n.t).abs() < 1e-7,
            "{:?} at {} s and {} s",
            b.kind,
            b.t,
            n.t
        );
    }
}

/// The normal force of the one contact held at the end of `r`.
fn resting_force(r: &eom_sim::RunReport) -> f64 {
    let el = r.elements.as_ref().expect("element report");
    let [held] = el.contact_forces.as_slice() else {
        panic!("one contact rests at the end: {:?}", el.contact_forces);
    };
    held.force
}

/// A box (0.2 m × 0.1 m, 1 kg, on a planar joint) standing tilted by
/// `a0` on its lower left corner, the contact `corner` (plastic, μ = 2),
/// beside the pendulum and its cable (with `cable`) or alone.
fn tipping_box(cable: bool, a0: f64) -> String {
    let (s, c) = a0.sin_cos();
    // The corner (−0.1, −0.05) in body axes at the world origin.
    let (x, y) = (0.1 * c - 0.05 * s, 0.1 * s + 0.05 * c);
    let body = r#"(name: "box", mass: 1, inertia: Diag(0.0016667, 0.0041667, 0.0041667),
         markers: [(name: "corner", position: (-0.1, -0.05, 0))]),"#;
    let joint = format!(
        r#"(name: "p", kind: Planar, parent: "ground", child: "box", coordinates: ["x", "y", "a"], q0: [{x:?}, {y:?}, {a0:?}]),"#
    );
    let contact = r#"Plane(name: "floor_box", at: (body: "box", marker: "corner"), normal: (0, 1, 0), e: 0, mu: 2),"#;
    if cable {
        // The cable's floor raised to y = −0.2: its end node strikes and
        // rests while the box pivots.
        let floor = "point: (0, -0.25, 0)";
        let text = pendulum_cable(0.5);
        assert!(text.contains(floor), "the bundled pendulum_cable's floor");
        return text
            .replace(floor, "point: (0, -0.2, 0)")
            .replace("bodies: [", &format!("bodies: [\n        {body}"))
            .replace("joints: [", &format!("joints: [\n        {joint}"))
            .replace("contacts: [", &format!("contacts: [\n        {contact}"));
    }
    format!(
        r#"Model(
    name: "tipping_box",
    gravity: (0, -{G}, 0),
    bodies: [{body}],
    joints: [{joint}],
    contacts: [{contact}],
)"#
    )
}

/// A sticking contact whose tangential row is not constant: the box
/// tips over its corner, the corner sticking (μ = 2) while the box turns
/// about it, so the corner's rows `w`, `W_t` turn with the angle (a rigid
/// body's pivoting contact point, which has no tangential coordinate to
/// hold). Beside the cable the stick is held step by step,
/// `W_t(ȳ)·(y − y_n) = 0` at the step's midpoint. Against the rigid
/// runtime on the box alone
/// (DOPRI5 at 1e-10, the stick held exactly at the acceleration level)
/// and against the pivot's closed form: the corner stays where it stuck
/// (8e-9 m measured at 1e-3 s), the angle agrees with the rigid run's
/// (2.3e-6 rad measured), and the energy is the fall's,
/// `½ I_c ω² = m g Δh` about the corner (`I_c = I_zz + m d²`), while the
/// cable beside strikes its floor and rests. With the row at the step's
/// end instead, `W_t(y)·(y − y_n) = 0`, the corner drifted 9.5e-5 m by
/// 0.13 s and the box left its cone at the cable's first restart,
/// gaining 0.02 J in one step (refused by the energy guard). On to 0.2 s
/// the box turns past flat (only this corner touches) and the corner
/// slips: at 0.13202 s against the rigid run's 0.13159 s, and the angle at
/// 0.2 s within 2.2e-6 rad of the rigid run's.
#[test]
fn a_box_tipping_over_its_sticking_corner_beside_a_cable_pivots() {
    let (a0, t_end) = (0.3, 0.1);
    let mixed = tipping_box(true, a0);
    let report = simulate(&mixed, &run(t_end, 1e-3, 0.8));
    finished_with_impacts_by_newton(&report, 0.5, "box tipping beside the pendulum");
    let sys = system(&tipping_box(false, a0));
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let rigid = eom_gen::interpret::simulate(
        &f,
        &sys,
        &eom_sim::RunOptions {
            t_end,
            rtol: 1e-10,
            atol: 1e-12,
            ..eom_sim::RunOptions::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(rigid.stop.is_finished(), "{}", rigid.stop);
    let (x, _) = rigid_state(&mixed, &report, "x");
    let (y, _) = rigid_state(&mixed, &report, "y");
    let (a, w) = rigid_state(&mixed, &report, "a");
    let corner = |x: f64, y: f64, a: f64| {
        let (s, c) = a.sin_cos();
        (x - 0.1 * c + 0.05 * s, y - 0.1 * s - 0.05 * c)
    };
    let (cx, cy) = corner(x, y, a);
    let (rx, ry) = corner(rigid.q[0], rigid.q[1], rigid.q[2]);
    println!(
        "tipping box at {t_end} s: angle {a:.9} (rigid {:.9}), corner ({cx:.3e}, {cy:.3e}) (rigid ({rx:.3e}, {ry:.3e})), ω {w:.9} (rigid {:.9})",
        rigid.q[2], rigid.u[2]
    );
    assert!(a < a0 - 0.05 && a > 0.0, "it tips, not yet flat: {a}");
    assert!(
        cx.abs() < 1e-7 && cy.abs() < 1e-9,
        "the corner stays: ({cx}, {cy})"
    );
    assert!(
        (a - rigid.q[2]).abs() < 1e-5,
        "angle {a} against {}",
        rigid.q[2]
    );
    // The fall about the corner: ½ I_c ω² = m g (h(a0) − h(a)).
    let h = |a: f64| 0.1 * a.sin() + 0.05 * a.cos();
    let ic = 0.0041667 + 0.1 * 0.1 + 0.05 * 0.05;
    let fall = G * (h(a0) - h(a));
    println!(
        "½ I_c ω² − m g Δh = {:.3e} of {fall:.6} J",
        0.5 * ic * w * w - fall
    );
    assert!(
        (0.5 * ic * w * w - fall).abs() < 1e-4 * fall,
        "½ I_c ω² = {} against m g Δh = {fall}",
        0.5 * ic * w * w
    );
    let changes: Vec<_> = report
        .contact_events
        .iter()
        .filter(|e| e.contacts.iter().any(|c| c.contact == "floor_box"))
        .map(|e| (e.kind, e.t))
        .collect();
    assert!(
        !changes.iter().any(|(k, _)| *k == ContactEventKind::Slip),
        "the corner sticks: {changes:?}"
    );
    // On to 0.2 s, through the stick's break: the box (its one corner in
    // contact) turns past flat and its corner slips; the same break and
    // the same motion as the rigid runtime's.
    let t_end = 0.2;
    let report = simulate(&mixed, &run(t_end, 1e-3, 0.8));
    energy_never_rises(&report, "box tipping through its slip");
    let rigid = eom_gen::interpret::simulate(
        &f,
        &sys,
        &eom_sim::RunOptions {
            t_end,
            rtol: 1e-10,
            atol: 1e-12,
            ..eom_sim::RunOptions::default()
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let slip = |events: &[eom_sim::run::ContactEvent]| {
        events
            .iter()
            .find(|e| {
                e.kind == ContactEventKind::Slip
                    && e.contacts.iter().any(|c| c.contact == "floor_box")
            })
            .map(|e| e.t)
    };
    let (a, _) = rigid_state(&mixed, &report, "a");
    let (ts, tr) = (slip(&report.contact_events), slip(&rigid.contact_events));
    println!(
        "through the slip at {t_end} s: angle {a:.9} (rigid {:.9}), slip at {ts:?} (rigid {tr:?})",
        rigid.q[2]
    );
    let (ts, tr) = (
        ts.expect("the corner slips beside the cable"),
        tr.expect("the corner slips alone"),
    );
    // The break is where the stick's force reaches its cone, a difference
    // of two forces that each run has to its own error: 4.3e-4 s apart
    // measured.
    assert!((ts - tr).abs() < 1e-3, "slip at {ts} s and {tr} s");
    assert!(
        (a - rigid.q[2]).abs() < 1e-5,
        "angle {a} against {} at {t_end} s",
        rigid.q[2]
    );
}

/// The bundled pendulum striking a peg (`models/ancf/pendulum_peg.ron`:
/// the link's tip sphere against a sphere about a pinned cable node),
/// its contact replaced by `contact`.
fn pendulum_and_peg(contact: &str) -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/pendulum_peg.ron"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|err| panic!("{path}: {err}"));
    let strike = r#"Spheres(name: "strike", a: (body: "peg", node: 0), b: (body: "link", marker: "tip"),
                radius_a: 0.01, radius_b: 0.02, e: "e", mu: "mu"),"#;
    assert!(text.contains(strike), "the bundled pendulum_peg");
    text.replace(strike, contact)
}

/// A cable node's sphere against a sphere on a moving body (the runtime's
/// rows from the rigid part's generated `contact_frames`: the body's
/// point, axes, velocities, their rates and Jacobians), against its rigid
/// twin. The link's tip carries a sphere (r = 0.02 m) and swings into the
/// peg's node 0 (a sphere of 0.01 m, pinned: a fixed centre); the rigid
/// twin is the rigid runtime's `Spheres` between the tip's sphere and a
/// sphere fixed in the world at the node's place. One contact seen from
/// either side: the same impacts (with `e = 0.5` and `e = 1`), rests and
/// releases at the same times (to 1e-7 s), the same impulses (to 1e-6 of
/// each) and the link at the same angle (to 1e-9 rad) after 0.6 s; every
/// impact by Newton's law and Carnot's energy, and the energy never above
/// its start. With Coulomb friction (μ = 0.4) the same, the tangential
/// impulses equal in size (the two sides' `t2` axes are opposite, `t1`
/// the same).
#[test]
fn a_nodes_sphere_struck_by_a_swinging_links_sphere_is_the_rigid_spheres_twin() {
    let r = run(0.6, 1e-3, 0.5);
    for (e, mu) in [(0.5, 0.0), (1.0, 0.0), (0.5, 0.4)] {
        let node = simulate(
            &pendulum_and_peg(&format!(
                r#"Spheres(name: "strike", a: (body: "peg", node: 0), b: (body: "link", marker: "tip"), radius_a: 0.01, radius_b: 0.02, e: {e:?}, mu: {mu:?}),"#
            )),
            &r,
        );
        let rigid = simulate(
            &pendulum_and_peg(&format!(
                r#"Spheres(name: "strike", a: (body: "link", point: (0.3, 0, 0)), b: (body: "ground", point: (0.14, -0.242487, 0)), radius_a: 0.02, radius_b: 0.01, e: {e:?}, mu: {mu:?}),"#
            )),
            &r,
        );
        let label = format!("e = {e}, μ = {mu}");
        let impacts = if mu == 0.0 {
            finished_with_impacts_by_newton(&node, e, &label)
        } else {
            energy_never_rises(&node, &label);
            impacts_obey_newton_and_carnot(&node, e, None)
        };
        assert!(impacts >= 1, "{label}: the tip strikes the peg");
        same_events(&node, &rigid);
        for (a, b) in node.contact_events.iter().zip(&rigid.contact_events) {
            for (ca, cb) in a.contacts.iter().zip(&b.contacts) {
                assert!(
                    (ca.impulse - cb.impulse).abs() <= 1e-6 * cb.impulse.abs() + 1e-12,
                    "{label}: {:?} at {} s: Λ {} and {}",
                    a.kind,
                    a.t,
                    ca.impulse,
                    cb.impulse
                );
                let (ta, tb) = (norm(ca.tangential_impulse), norm(cb.tangential_impulse));
                assert!(
                    (ta - tb).abs() <= 1e-6 * tb + 1e-12,
                    "{label}: ‖Λ_t‖ {ta} and {tb}"
                );
                assert!(
                    ta <= mu * ca.impulse * (1.0 + 1e-9) + 1e-15,
                    "{label}: in the cone"
                );
            }
        }
        assert!(
            (node.q[0] - rigid.q[0]).abs() < 1e-9,
            "{label}: θ {} and {}",
            node.q[0],
            rigid.q[0]
        );
        let kinds: Vec<_> = node
            .contact_events
            .iter()
            .map(|e| {
                (
                    e.kind,
                    e.t,
                    e.contacts[0].impulse,
                    e.contacts[0].tangential_impulse,
                )
            })
            .collect();
        println!("{label}: θ = {:.9}, events {kinds:?}", node.q[0]);
    }
}

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

/// A block on a vertical rail with an arm clamped at its side (the
/// bundled `block_drop`) beside a `peg`: a short cable pinned to the
/// ground at `(0.1, −0.1)`, hanging down, its node 0 fixed; `contact`
/// holds the block's sole (0.05 m under its hook, 0.1 m along x) above
/// it, 0.05 m apart at the start.
fn block_over_a_peg(contact: &str) -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/ancf/block_drop.ron");
    let text = std::fs::read_to_string(path).unwrap_or_else(|err| panic!("{path}: {err}"));
    let foot = r#"Plane(name: "foot", at: (body: "arm", node: 0), point: (0, "-h0", 0), normal: (0, 1, 0), e: "e"),"#;
    let arm_end = "start_at: (body: \"block\", marker: \"hook\", axis: (1, 0, 0)),\n        ),\n";
    assert!(
        text.contains(foot) && text.contains(arm_end),
        "the bundled block_drop"
    );
    text.replace(foot, contact).replace(
        arm_end,
        &format!(
            "{arm_end}        Cable(name: \"peg\", element: Cable2D, from: (0.1, -0.1, 0), to: (0.1, -0.2, 0), elements: 1,\n              young: 1e9, density: 100, area: 1e-5, second_moment: 1e-10, start: Pinned),\n"
        ),
    )
}

/// A cable node against a plane on a moving body: the block's sole (a
/// plane on the block, normal −y in its axes) falls onto the peg's fixed
/// node 0, against the rigid twin, the block's point against the floor
/// through that node (normal +y). The gaps are one, `y_b + 0.05`: the
/// same hops (e = 0.5, Newton and Carnot) at the same times, the same
/// impulses, the block resting on the peg at the end with the same force.
#[test]
fn a_blocks_sole_falling_on_a_pinned_node_is_the_rigid_floors_twin() {
    let r = run(0.5, 1e-3, 0.5);
    let node = simulate(
        &block_over_a_peg(
            r#"Plane(name: "sole", at: (body: "peg", node: 0), on: "block", point: (0.1, -0.05, 0), normal: (0, -1, 0), e: "e"),"#,
        ),
        &r,
    );
    let rigid = simulate(
        &block_over_a_peg(
            r#"Plane(name: "sole", at: (body: "block", point: (0.1, -0.05, 0)), point: (0.1, -0.1, 0), normal: (0, 1, 0), e: "e"),"#,
        ),
        &r,
    );
    let impacts = finished_with_impacts_by_newton(&node, 0.5, "the sole on the peg");
    assert!(impacts >= 3, "the block hops: {impacts}");
    same_events(&node, &rigid);
    for (a, b) in node.contact_events.iter().zip(&rigid.contact_events) {
        for (ca, cb) in a.contacts.iter().zip(&b.contacts) {
            assert!(
                (ca.impulse - cb.impulse).abs() <= 1e-6 * cb.impulse.abs() + 1e-12,
                "{:?} at {} s: Λ {} and {}",
                a.kind,
                a.t,
                ca.impulse,
                cb.impulse
            );
        }
    }
    let (fa, fb) = (resting_force(&node), resting_force(&rigid));
    assert!(
        fa > 0.0 && (fa - fb).abs() <= 1e-6 * fb,
        "{fa} N and {fb} N"
    );
    assert!(
        (node.q[0] - rigid.q[0]).abs() < 1e-9,
        "y {} and {}",
        node.q[0],
        rigid.q[0]
    );
}

/// The generated `contact_frames` of a spatial double pendulum (about z,
/// then about the upper link's x axis) whose links carry a plane and a
/// sphere that a `Cable3D`'s nodes touch, at random states: its points,
/// axes and velocities equal the numeric twin's (to 1e-12); the velocity
/// is the derivative of the position along `q̇ = u` and the axes turn at
/// `ω` (`Ė = [ω]× E`; central differences, 1e-7); the rows give them,
/// `J_p u = ṗ`, `J_ω u = ω`; and the rates at `u̇ = 0` are the
/// derivatives of `ṗ` and `ω` along the motion at fixed `u` (1e-7).
#[test]
fn contact_frames_are_the_points_and_axes_with_their_derivatives() {
    use eom_gen::functions::Function;
    let text = r#"Model(
    name: "frames",
    gravity: (0, -9.81, 0),
    bodies: [
        (name: "upper", mass: 1, com: (0.15, 0, 0), inertia: Diag(0.01, 0.01, 0.01)),
        (name: "lower", mass: 1, com: (0, 0, 0.1), inertia: Diag(0.01, 0.02, 0.03)),
    ],
    joints: [
        (name: "a", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "upper", coordinates: ["a"]),
        (name: "b", kind: Revolute(axis: (1, 0, 0)), parent: "upper", child: "lower",
         parent_frame: (position: (0.3, 0, 0)), coordinates: ["b"]),
    ],
    cables: [
        Cable(name: "wire", element: Cable3D, from: (1, 1, 1), to: (1.3, 1, 1), elements: 2,
              young: 1e9, density: 1000, area: 1e-5, second_moment: 1e-10, start: Pinned),
    ],
    contacts: [
        Plane(name: "shelf", at: (body: "wire", node: 1), on: "lower", point: (0.1, 0.05, -0.02), normal: (0, 0.6, 0.8), e: 0.5),
        Spheres(name: "knob", a: (body: "wire", node: 2), b: (body: "upper", point: (0.2, 0.03, 0.01)), radius_a: 0.01, radius_b: 0.02, e: 0.5),
    ],
)"#;
    let sys = system(text);
    assert_eq!(sys.cable_frames().len(), 2);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let num = eom_gen::mech::Numeric::new(&sys).unwrap_or_else(|e| panic!("{e}"));
    let nu = sys.nu();
    let block = 24 + 6 * nu;
    let generated = |q: &[f64], u: &[f64]| {
        let x = eom_gen::interpret::Point {
            sys: &sys,
            q,
            u,
            udot: &[],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        eom_gen::interpret::evaluate_function(&f, Function::ContactFrames, &x).expect("evaluated")
    };
    let twin = |q: &[f64], u: &[f64]| num.contact_frames(&sys, q, u, 0.0).expect("twin");
    let close = |what: &str, got: f64, want: f64, tol: f64| {
        assert!(
            (got - want).abs() <= tol * (1.0 + want.abs()),
            "{what}: {got} against {want}"
        );
    };
    for (q, u) in [
        ([0.3, -0.7], [1.1, -0.4]),
        ([-1.2, 2.1], [-0.6, 2.3]),
        ([2.5, 0.4], [0.2, 0.9]),
    ] {
        let out = generated(&q, &u);
        let exact = twin(&q, &u);
        assert_eq!(out.len(), 2 * block);
        let h = 1e-6;
        let shift = |s: f64| -> Vec<f64> { (0..nu).map(|k| q[k] + s * h * u[k]).collect() };
        let (plus, minus) = (twin(&shift(1.0), &u), twin(&shift(-1.0), &u));
        for fr in 0..2 {
            let (o, x, base) = (&out[fr * block..], &exact[fr * 18..], fr * 18);
            for r in 0..18 {
                close(&format!("frame {fr} value {r}"), o[r], x[r], 1e-12);
            }
            let d = |r: usize| (plus[base + r] - minus[base + r]) / (2.0 * h);
            for i in 0..3 {
                close(&format!("frame {fr} ṗ{i}"), o[12 + i], d(i), 1e-7);
                // Ė = [ω]× E, row i column j: (ω × e_j)_i.
                for j in 0..3 {
                    let (w, e) = (&o[15..18], |k: usize| o[3 + 3 * k + j]);
                    let turn = [
                        w[1] * e(2) - w[2] * e(1),
                        w[2] * e(0) - w[0] * e(2),
                        w[0] * e(1) - w[1] * e(0),
                    ];
                    close(
                        &format!("frame {fr} Ė{i}{j}"),
                        turn[i],
                        d(3 + 3 * i + j),
                        1e-7,
                    );
                }
                close(&format!("frame {fr} p̈₀{i}"), o[18 + i], d(12 + i), 1e-7);
                close(&format!("frame {fr} α₀{i}"), o[21 + i], d(15 + i), 1e-7);
                for (r, what) in [(i, "J_p u"), (3 + i, "J_ω u")] {
                    let ju: f64 = (0..nu).map(|k| o[24 + r * nu + k] * u[k]).sum();
                    close(&format!("frame {fr} {what}{i}"), ju, o[12 + r], 1e-13);
                }
            }
        }
    }
}

/// The bundled wire dropped on a moving cart (`models/ancf/wire_on_cart.ron`)
/// with Coulomb friction `mu` at its deck.
fn wire_on_cart(mu: f64) -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/ancf/wire_on_cart.ron"
    );
    let text = std::fs::read_to_string(path).unwrap_or_else(|err| panic!("{path}: {err}"));
    let param = r#"(name: "mu", value: 0.5,"#;
    assert!(text.contains(param), "the bundled wire_on_cart");
    text.replace(param, &format!(r#"(name: "mu", value: {mu:?},"#))
}

/// Cable nodes against a plane on a moving body, in a model whose cable
/// hangs at no body: a free wire (0.5 kg) dropped flat onto a cart (2 kg)
/// rolling at 1 m/s on a level frictionless rail. Nothing horizontal acts
/// from outside, so the horizontal momentum is conserved through the
/// plastic strike, the slide and the stick–slip chatter of the ringing
/// wire: with friction (μ = 0.5) both end at the common speed
/// `m_c v₀/(m_c + m_w) = 0.8` m/s (to 1e-6 after 1 s; the wire no longer
/// moving on the deck), and the energy never rises; without friction the
/// deck's normal force has no horizontal part, and the cart rolls on at
/// `v₀` exactly while the wire lies where it fell.
///
/// Until this session a slide that turned the wrong way in its first
/// step (`v_t · s0` from 0 to below 0: the ringing wire pulled the node
/// back against its slide's direction) was never stopped, and its friction
/// pushed the slip on: the cart sped up again to 0.972 m/s by 1 s and the
/// energy rose from 0.562 to 0.700 J.
#[test]
fn a_wire_dropped_on_a_moving_cart_shares_its_momentum() {
    let r = run(1.0, 1e-3, 0.8);
    let rough = simulate(&wire_on_cart(0.5), &r);
    assert!(
        matches!(rough.stop, eom_sim::Stop::Finished),
        "{:?}",
        rough.stop
    );
    energy_never_rises(&rough, "wire on the cart");
    let common = 2.0 * 1.0 / (2.0 + 0.5);
    assert!(
        (rough.u[0] - common).abs() < 1e-6,
        "the cart at {} m/s, want m_c v₀/(m_c + m_w) = {common}",
        rough.u[0]
    );
    let kinds = |r: &eom_sim::RunReport, k: ContactEventKind| {
        r.contact_events.iter().filter(|e| e.kind == k).count()
    };
    println!(
        "wire on the cart: u = {:.12} m/s, {} events ({} sticks, {} slips)",
        rough.u[0],
        rough.contact_events.len(),
        kinds(&rough, ContactEventKind::Stick),
        kinds(&rough, ContactEventKind::Slip)
    );
    assert!(
        kinds(&rough, ContactEventKind::Stick) >= 1,
        "the wire sticks"
    );
    let smooth = simulate(&wire_on_cart(0.0), &r);
    assert!(
        matches!(smooth.stop, eom_sim::Stop::Finished),
        "{:?}",
        smooth.stop
    );
    assert!(
        (smooth.u[0] - 1.0).abs() < 1e-12 && (smooth.q[0] - 1.0).abs() < 1e-12,
        "without friction the cart rolls on: x = {}, u = {}",
        smooth.q[0],
        smooth.u[0]
    );
}
