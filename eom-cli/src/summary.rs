//! What `eom-gen check` prints: a human summary and a JSON object.

use eom_gen::model::{Checked, closure_gaps, initial_poses};
use eom_gen::system::{Motion, System};
use serde_json::{Value, json};

/// The `check --json` object.
pub fn json(checked: &Checked) -> Value {
    let sys = &checked.system;
    let gaps = closure_gaps(sys, &initial_poses(sys));
    let mobility = mobility(sys);
    let names = |pred: &dyn Fn(&Motion) -> bool| -> Vec<&str> {
        sys.joints
            .iter()
            .filter(|j| pred(&j.motion))
            .map(|j| j.name.as_str())
            .collect()
    };
    json!({
        "name": sys.name,
        "valid": true,
        "bodies": sys.bodies.len() - 1,
        "joints": sys.joints.len(),
        "nq": sys.nq(),
        "nu": sys.nu(),
        "coordinate_names": sys.coordinate_names(),
        // The coordinates as the user wrote them (a URDF joint `joint_0.0`
        // made the identifier `joint_0_0`); the same as `coordinate_names`
        // when nothing was renamed.
        "coordinate_labels": sys.coordinate_labels(),
        "speed_names": sys.speed_names(),
        "q0": sys.q0(),
        "u0": sys.u0(),
        "cut_joints": sys.cut_joint_names(),
        "cables": crate::cable_report::check_json(sys),
        "constraints": sys.constraints.iter().map(|c| c.name.as_str()).collect::<Vec<_>>(),
        "grubler_dof": sys.grubler.dof,
        "grubler_elastic": sys.grubler.elastic,
        "grubler_space": if sys.grubler.planar { "planar" } else { "spatial" },
        "body_names": sys.bodies.iter().skip(1).map(|b| b.name.as_str()).collect::<Vec<_>>(),
        // Every renamed coordinate, body and joint: identifier → as written.
        "original_names": sys.renamed().into_iter().map(|(kind, name, label)| json!({
            "kind": kind, "name": name, "original": label,
        })).collect::<Vec<_>>(),
        "tree": sys.graph.tree_joints().iter().map(|&j| {
            let joint = &sys.joints[j];
            json!({
                "joint": joint.name,
                "kind": joint.kind.name(),
                "parent": sys.bodies[joint.parent].name,
                "child": sys.bodies[joint.child].name,
            })
        }).collect::<Vec<_>>(),
        "locked_joints": names(&|m| *m == Motion::Locked),
        "prescribed_joints": names(&|m| matches!(m, Motion::Prescribed(_))),
        "inputs": sys.inputs,
        "parameters": sys.parameters.iter().map(|p| json!({
            "name": p.name, "value": p.value.value, "tunable": p.tunable,
        })).collect::<Vec<_>>(),
        "loop_closure": sys.graph.cut_joints().iter().zip(&gaps).map(|(&j, g)| json!({
            "joint": sys.joints[j].name, "position_gap": g.position, "angle_gap": g.angle,
        })).collect::<Vec<_>>(),
        // The URDF importer's warnings (inconsistent inertias, …) count too.
        "warnings": checked.warnings.len()
            + checked.urdf_warnings.as_ref().map_or(0, |w| w.diagnostics.len()),
        "constraint_equations": mobility.map(|(m, _)| m.equations),
        "constraint_rank": mobility.map(|(m, _)| m.rank),
        "mobility": mobility.map_or(sys.grubler.dof, |(m, _)| m.dof as i64),
        "assembly": mobility.map(|(_, a)| json!({
            "residual": a.0, "velocity_residual": a.1, "iterations": a.2,
        })),
    })
}

/// Rank of the constraint equations (closure conditions, the model's own
/// holonomic and nonholonomic constraints) at the assembled initial state,
/// if there are any: the speeds' degrees of freedom.
/// With it, the assembly's `max |Φ|`, `max |J u + Φ_t|` and Newton
/// iterations.
fn mobility(sys: &System) -> Option<(eom_gen::mech::numeric::Mobility, (f64, f64, usize))> {
    if sys.graph.cut_joints().is_empty() && sys.constraints.is_empty() {
        return None;
    }
    let num = eom_gen::mech::Numeric::new(sys).ok()?;
    let a = num.assemble(&sys.q0(), &sys.u0(), 0.0).ok()?;
    let m = num.mobility(&a.q, 0.0).ok()?;
    Some((m, (a.residual, a.velocity_residual, a.iterations)))
}

/// A few lines for people.
pub fn human(checked: &Checked) -> String {
    let sys: &System = &checked.system;
    let mut out = format!("model `{}` ({}): valid\n", sys.name, checked.source.path);
    let bodies: Vec<&str> = sys.bodies.iter().skip(1).map(|b| b.name.as_str()).collect();
    if bodies.is_empty() && !sys.cables.is_empty() {
        // Cables only: no rigid part to count (the cables follow).
        out += &format!(
            "  cables       {}: {}; {} free coordinates in all, no rigid bodies or joints\n",
            sys.cables.len(),
            sys.cables
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            cable_free_coordinates(sys).map_or("?".into(), |n| n.to_string())
        );
        return out;
    }
    out += &format!("  bodies       {}: {}\n", bodies.len(), bodies.join(", "));
    let cut = sys.cut_joint_names();
    out += &format!(
        "  joints       {}: {} in the tree, {} cut{}\n",
        sys.joints.len(),
        sys.graph.tree_joints().len(),
        cut.len(),
        if cut.is_empty() {
            String::new()
        } else {
            format!(" ({})", cut.join(", "))
        }
    );
    out += &format!(
        "  coordinates  nq = {}: {}\n",
        sys.nq(),
        sys.coordinate_names().join(", ")
    );
    out += &format!(
        "  speeds       nu = {}: {}\n",
        sys.nu(),
        sys.speed_names().join(", ")
    );
    let locked: Vec<&str> = sys
        .joints
        .iter()
        .filter(|j| j.motion == Motion::Locked)
        .map(|j| j.name.as_str())
        .collect();
    let prescribed: Vec<&str> = sys
        .joints
        .iter()
        .filter(|j| matches!(j.motion, Motion::Prescribed(_)))
        .map(|j| j.name.as_str())
        .collect();
    if !locked.is_empty() {
        out += &format!("  locked       {}\n", locked.join(", "));
    }
    if !prescribed.is_empty() {
        out += &format!("  prescribed   {}\n", prescribed.join(", "));
    }
    if !sys.inputs.is_empty() {
        out += &format!("  inputs       {}\n", sys.inputs.join(", "));
    }
    if !sys.constraints.is_empty() {
        let c: Vec<&str> = sys.constraints.iter().map(|c| c.name.as_str()).collect();
        out += &format!("  constraints  {}\n", c.join(", "));
    }
    if !sys.cables.is_empty() {
        out += &format!(
            "  cables       {}: {}; {} free coordinates besides the rigid part's (below)\n",
            sys.cables.len(),
            sys.cables
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            cable_free_coordinates(sys).map_or("?".into(), |n| n.to_string())
        );
    }
    out += &format!(
        "  Grübler–Kutzbach ({}{}): {} degree(s) of freedom{}\n",
        if sys.grubler.planar {
            "planar"
        } else {
            "spatial"
        },
        if sys.cables.is_empty() {
            ""
        } else {
            ", rigid part alone"
        },
        sys.grubler.dof,
        match sys.grubler.elastic {
            0 => String::new(),
            k => format!(
                " ({} of the rigid bodies and joints + {k} elastic coordinate{} of flexible bodies)",
                sys.grubler.dof - k,
                if k == 1 { "" } else { "s" }
            ),
        }
    );
    if let Some((m, (residual, velocity_residual, iterations))) = mobility(sys) {
        out += &format!(
            "  mobility     {} (rank {} of {} constraint equations{}, assembled initial state)\n",
            m.dof,
            m.rank,
            m.equations,
            match sys
                .constraints
                .iter()
                .map(|c| c.equations().1)
                .sum::<usize>()
            {
                0 => String::new(),
                n => format!(", {n} of them nonholonomic"),
            }
        );
        out += &format!(
            "  assembly     max |Φ| {residual:.1e}, max |J u + Φ_t| {velocity_residual:.1e} after {iterations} Newton step(s)\n"
        );
    }
    out
}

/// The free coordinates of every cable (their chains' unknowns once the
/// clamped and pinned ones are removed); `None` if a chain cannot be built.
fn cable_free_coordinates(sys: &System) -> Option<usize> {
    sys.cables
        .iter()
        .map(|c| {
            eom_sim::large::ancf::chain(&eom_gen::cables::chain_spec(c))
                .ok()
                .map(|ch| ch.model.n_free())
        })
        .sum()
}
