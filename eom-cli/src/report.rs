//! What `simulate` prints for every model kind: one [`RunReport`] (from a
//! compiled or interpreted rigid model, or from the element runtime for
//! cables and mixed models), as JSON or as the human summary, and one
//! exit status (0 when the run reached its end time, 3 with the reason
//! when it stopped early).

use eom_sim::run::{CableState, ContactEvent, ContactEventKind, MountForce, StaticReport};
use eom_sim::{Integrator, RunReport};
use std::fmt::Write;
use std::process::ExitCode;

/// A run that did not reach its end time: exit status 3.
pub const EXIT_RUN_STOPPED: u8 = 3;

/// How a run was integrated, for its summary.
pub struct Setting<'a> {
    /// The integrator.
    pub integrator: Integrator,
    /// Its settings in words ("rtol 1e-8, atol 1e-10", "step 1e-3 s", …).
    pub detail: String,
    /// The CSV the trajectory went to.
    pub csv: Option<&'a str>,
    /// The CSV the contact events went to.
    pub events_csv: Option<&'a str>,
}

/// Prints the report (`json`: one object; else the summary) and returns
/// the exit status.
pub fn finish(
    name: &str,
    coordinates: &[&str],
    setting: &Setting<'_>,
    t_end: f64,
    r: &RunReport,
    json: bool,
) -> ExitCode {
    if json {
        match serde_json::to_string(r) {
            Ok(text) => println!("{text}"),
            Err(e) => {
                eprintln!("error: cannot encode the report: {e}");
                return ExitCode::from(1);
            }
        }
    } else {
        print!("{}", summary(name, coordinates, setting, r));
    }
    if r.stop.is_finished() {
        ExitCode::SUCCESS
    } else {
        eprintln!("error: the run stopped before t = {t_end}: {}", r.stop);
        ExitCode::from(EXIT_RUN_STOPPED)
    }
}

/// The human summary of a run.
pub fn summary(name: &str, coordinates: &[&str], o: &Setting<'_>, r: &RunReport) -> String {
    let mut s = String::new();
    let stop = if r.stop.is_finished() {
        "\"finished\"".to_string()
    } else {
        r.stop.to_string()
    };
    let _ = writeln!(
        s,
        "{name}: {} to t = {:?} s ({}): {stop}",
        o.integrator, r.t, o.detail
    );
    let mut counts = format!(
        "  {} steps ({} rejected), {} right-hand sides",
        r.stats.steps, r.stats.rejected, r.stats.rhs_evals
    );
    if r.stats.newton_iterations > 0 || r.stats.lu_decompositions > 0 {
        let _ = write!(
            counts,
            ", {} Newton iterations, {} factorisations",
            r.stats.newton_iterations, r.stats.lu_decompositions
        );
    }
    let _ = writeln!(s, "{counts}, {:.3} ms", r.cpu_s * 1e3);
    if !r.q.is_empty() {
        let q: Vec<String> =
            r.q.iter()
                .zip(coordinates)
                .map(|(x, n)| format!("{n} = {x:.6}"))
                .collect();
        let _ = writeln!(s, "  final {}", q.join(", "));
    }
    if let Some(e) = &r.elements {
        write_elements(&mut s, &e.cables, &e.mounts);
        if !e.mounts.is_empty() || e.largest_constraint_residual > 0.0 {
            let _ = writeln!(
                s,
                "  largest constraint residual |Φ|∞ {:.3e}",
                e.largest_constraint_residual
            );
        }
    }
    let [e0, e1] = r.energy;
    let _ = writeln!(
        s,
        "  energy {e0:.9} → {e1:.9} J{}",
        energy_change(e0, e1, r.energy_scale)
    );
    if let Some(c) = &r.constrained {
        let m = &c.summary;
        let _ = writeln!(
            s,
            "  constraints ({}): max |Φ| {:.1e}, max |Φ̇| {:.1e}, rank {} of {}, smallest σ_r/σ_1 of J {:.1e}",
            c.constraints,
            m.max_constraint_residual,
            m.max_velocity_residual,
            m.constraint_rank,
            c.constraint_names.len(),
            m.min_singular_ratio
        );
        if m.min_singular_ratio < 1e-2 {
            let _ = writeln!(
                s,
                "  note: J came near losing rank: the run passed close to a singular configuration, \
                 where the constraint forces are ill-conditioned and accuracy is limited; compare \
                 with a tighter tolerance or another --constraints method"
            );
        }
    }
    write_contact_events(&mut s, &r.contact_events);
    if let Some(csv) = o.csv {
        let _ = writeln!(s, "  trajectory written to {csv}");
    }
    if let Some(csv) = o.events_csv {
        let _ = writeln!(s, "  contact events written to {csv}");
    }
    s
}

/// The contact events in a few lines: how many of each kind, the first
/// impact and the last event.
fn write_contact_events(s: &mut String, events: &[ContactEvent]) {
    if events.is_empty() {
        return;
    }
    let count = |k: ContactEventKind| events.iter().filter(|e| e.kind == k).count();
    let _ = write!(
        s,
        "  contact events: {} impact(s), {} coming to rest, {} release(s)",
        count(ContactEventKind::Impact),
        count(ContactEventKind::Rest),
        count(ContactEventKind::Release)
    );
    let (stick, slip) = (
        count(ContactEventKind::Stick),
        count(ContactEventKind::Slip),
    );
    if stick + slip > 0 {
        let _ = write!(s, ", {stick} stick(s), {slip} slip(s)");
    }
    let _ = writeln!(s);
    let line = |e: &ContactEvent| {
        let rows: Vec<String> = e
            .contacts
            .iter()
            .map(|c| {
                let mut text = format!(
                    "`{}` Λ = {:.6e}, ġ {:.6e} → {:.6e}",
                    c.contact, c.impulse, c.speed_before, c.speed_after
                );
                if c.tangential_impulse != [0.0; 2] {
                    let [a, b] = c.tangential_impulse;
                    let _ = write!(text, ", Λ_t = ({a:.6e}, {b:.6e})");
                }
                text
            })
            .collect();
        format!(
            "{} at t = {:.9} s: {}; energy {:.9} → {:.9} J",
            e.kind.name(),
            e.t,
            rows.join("; "),
            e.energy_before,
            e.energy_after
        )
    };
    if let Some(first) = events.iter().find(|e| e.kind == ContactEventKind::Impact) {
        let _ = writeln!(s, "    first {}", line(first));
    }
    if let Some(last) = events.last() {
        let _ = writeln!(s, "    last {}", line(last));
    }
}

/// The energy change for people: relative to the size of the energies
/// (`|T| + |V|`, the larger at the start and at the end), which is
/// meaningful when the total is near zero; absolute when they are all zero.
fn energy_change(e0: f64, e1: f64, scale: f64) -> String {
    let change = (e1 - e0).abs();
    if !change.is_finite() {
        String::new()
    } else if scale.is_finite() && scale > 0.0 {
        format!(
            ", change {change:.1e} J = {:.1e} of |T| + |V| ({scale:.3e} J)",
            change / scale
        )
    } else {
        format!(", change {change:.1e} J")
    }
}

/// Each cable's end nodes and each marker's force on its cable end.
fn write_elements(s: &mut String, cables: &[CableState], mounts: &[MountForce]) {
    for c in cables {
        let (a, b) = (c.first_node, c.last_node);
        let _ = writeln!(
            s,
            "  cable {}: {} × {}, first node at ({:.9}, {:.9}, {:.9}) m, last node at ({:.9}, {:.9}, {:.9}) m",
            c.cable, c.elements, c.element, a[0], a[1], a[2], b[0], b[1], b[2]
        );
    }
    for m in mounts {
        let f = m.force;
        let _ = writeln!(
            s,
            "  force of the marker on {}: ({:.6e}, {:.6e}, {:.6e}) N",
            m.attachment, f[0], f[1], f[2]
        );
    }
}

/// The human summary of a static solve: the load steps with their
/// residual histories, the rigid coordinates, the cables' end nodes, the
/// markers' forces, the constraint residual and the stability.
pub fn static_summary(name: &str, coordinates: &[&str], r: &StaticReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{name}: static equilibrium, {} unknowns, {} constraint equations",
        r.unknowns, r.constraints
    );
    let iterations: usize = r.load_steps.iter().map(|l| l.iterations).sum();
    let _ = writeln!(
        s,
        "  {} load steps ({} halved), {iterations} Newton iterations ({} regularised: singular tangent), {} factorisations, {:.3} ms",
        r.load_steps.len(),
        r.cuts,
        r.regularized,
        r.factorizations,
        r.cpu_s * 1e3
    );
    for l in &r.load_steps {
        let _ = writeln!(
            s,
            "  λ = {:<8.4} {:>2} iterations, |r|∞: {}",
            l.lambda,
            l.iterations,
            l.residuals
                .iter()
                .map(|r| format!("{r:.2e}"))
                .collect::<Vec<_>>()
                .join(" → ")
        );
    }
    if !r.q.is_empty() {
        let q: Vec<String> = coordinates
            .iter()
            .zip(&r.q)
            .map(|(n, v)| format!("{n} = {v:.9}"))
            .collect();
        let _ = writeln!(s, "  rigid part: {}", q.join(", "));
    }
    write_elements(&mut s, &r.cables, &r.mounts);
    if r.constraints > 0 {
        let _ = writeln!(
            s,
            "  constraint residual |Φ|∞ {:.3e}; condition estimate of the KKT matrix {:.2e}",
            r.constraint_residual, r.condition
        );
    }
    if let Some(st) = &r.stability {
        let _ = writeln!(s, "  {}", st.summary);
    }
    s
}
