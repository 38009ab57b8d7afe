//! Joints and the graph they make: parent and child, type, axes, names
//! and initial values of coordinates and speeds, the spanning tree and
//! coordinate assignment, loop closure at the initial state, and the
//! Grübler–Kutzbach count.

use super::{CLOSURE_TOL, Ctx, Scope, TOL, f, i, is_ident, join};
use crate::diag::{did_you_mean, list_names};
use crate::expr::Ast;
use crate::graph::{Arc, Graph, GraphError, JointId};
use crate::mech::initial::{Gap, Pose, closure_gaps};
use crate::model::locate::Seg;
use crate::model::spec::{self, Num, Spec};
use crate::system::*;
use std::collections::HashMap;

impl Ctx<'_> {
    /// The joints that are right, and whether all are.
    pub(super) fn joints(&mut self, spec: &Spec, bodies: &[BodyInfo]) -> (Vec<JointInfo>, bool) {
        let mut seen: HashMap<&str, usize> = HashMap::new();
        let mut out = Vec::new();
        let mut ok = true;
        for (k, j) in spec.joints.iter().enumerate() {
            let path = [f("joints"), i(k)];
            let name_path = join(&path, &[f("name")]);
            if !is_ident(&j.name) {
                self.error(
                    &name_path,
                    format!("joint name `{}` is not an identifier", j.name),
                    "use letters, digits and `_`, starting with a letter or `_`",
                );
            } else if seen.insert(&j.name, k).is_some() {
                self.error(
                    &name_path,
                    format!("joint `{}` is defined twice", j.name),
                    "joint names must be unique; rename one of them",
                );
            }
            let parent = self.body_ref(bodies, &j.parent, &join(&path, &[f("parent")]), "parent");
            let child = self.body_ref(bodies, &j.child, &join(&path, &[f("child")]), "child");
            let parent_node = match (&j.parent_node, parent) {
                (Some(node), Some(p)) => {
                    let written = spec.bodies.iter().find(|b| b.name == j.parent);
                    let n = self.node_ref(
                        node,
                        &j.parent,
                        written.and_then(|b| b.flexible.as_ref()),
                        bodies[p].flexible.as_deref(),
                        &join(&path, &[f("parent_node")]),
                        &format!("joint `{}`", j.name),
                    );
                    n.map(Some).ok_or(())
                }
                _ => Ok(None),
            };
            let child_node = match (&j.child_node, child) {
                (Some(node), Some(c)) => {
                    let written = spec.bodies.iter().find(|b| b.name == j.child);
                    let n = self.node_ref(
                        node,
                        &j.child,
                        written.and_then(|b| b.flexible.as_ref()),
                        bodies[c].flexible.as_deref(),
                        &join(&path, &[f("child_node")]),
                        &format!("joint `{}`", j.name),
                    );
                    n.map(Some).ok_or(())
                }
                _ => Ok(None),
            };
            match (self.joint(j, &path, parent, child), parent_node, child_node) {
                (Some(mut info), Ok(node), Ok(child_node)) => {
                    info.parent_node = node;
                    info.child_node = child_node;
                    out.push(info)
                }
                _ => {
                    self.failed_joints.insert(j.name.clone());
                    ok = false;
                }
            }
        }
        (out, ok)
    }

    pub(super) fn body_ref(
        &mut self,
        bodies: &[BodyInfo],
        name: &str,
        path: &[Seg<'static>],
        role: &str,
    ) -> Option<usize> {
        if let Some(b) = bodies.iter().position(|b| b.name == name) {
            return Some(b);
        }
        let names = bodies.iter().map(|b| b.name.as_str());
        let help = match did_you_mean(name, names.clone()) {
            Some(best) => format!("did you mean `{best}`?"),
            None => format!("bodies are {}", list_names(names)),
        };
        self.error(path, format!("unknown {role} body `{name}`"), help);
        None
    }

    pub(super) fn joint(
        &mut self,
        j: &spec::Joint,
        path: &[Seg<'static>],
        parent: Option<usize>,
        child: Option<usize>,
    ) -> Option<JointInfo> {
        let kp = join(path, &[f("kind")]);
        let kind = match &j.kind {
            spec::JointKind::Revolute { axis } => self
                .axis(axis, &join(&kp, &[f("axis")]), "joint axis")
                .map(JointType::Revolute),
            spec::JointKind::Prismatic { axis } => self
                .axis(axis, &join(&kp, &[f("axis")]), "joint axis")
                .map(JointType::Prismatic),
            spec::JointKind::Cylindrical { axis } => self
                .axis(axis, &join(&kp, &[f("axis")]), "joint axis")
                .map(JointType::Cylindrical),
            spec::JointKind::Universal { axis1, axis2 } => {
                let a = self.axis(axis1, &join(&kp, &[f("axis1")]), "first axis");
                let b = self.axis(axis2, &join(&kp, &[f("axis2")]), "second axis");
                match (a, b) {
                    (Some(a), Some(b)) if a.unit.cross(&b.unit).norm() < 1e-6 => {
                        self.error(
                            &join(&kp, &[f("axis2")]),
                            format!("the axes of universal joint `{}` are parallel", j.name),
                            "a Cardan joint needs two non-parallel (usually perpendicular) axes",
                        );
                        None
                    }
                    (Some(a), Some(b)) => Some(JointType::Universal(a, b)),
                    _ => None,
                }
            }
            spec::JointKind::Spherical => Some(JointType::Spherical),
            spec::JointKind::Planar => Some(JointType::Planar),
            spec::JointKind::Free => Some(JointType::Free),
            spec::JointKind::Screw { axis, pitch } => {
                let a = self.axis(axis, &join(&kp, &[f("axis")]), "joint axis");
                let p = self.quantity(pitch, &join(&kp, &[f("pitch")]), Scope::Params);
                Some(JointType::Screw(a?, p?))
            }
            spec::JointKind::Fixed => Some(JointType::Fixed),
        };
        let parent_frame = self.frame(&j.parent_frame, &join(path, &[f("parent_frame")]));
        let child_frame = self.frame(&j.child_frame, &join(path, &[f("child_frame")]));
        let (nq, nu) = j.kind.dims();
        let quaternion_at = match j.kind {
            spec::JointKind::Spherical => Some(0),
            spec::JointKind::Free => Some(3),
            _ => None,
        };
        let kind_name = j.kind.name();

        let coordinate_names = self.names(
            j.coordinates.as_ref(),
            default_coordinate_names(&j.name, &j.kind),
            &join(path, &[f("coordinates")]),
            "coordinate",
            nq,
            &j.name,
        );
        let default_speeds = match j.kind {
            spec::JointKind::Spherical => ["wx", "wy", "wz"]
                .map(|s| format!("{}_{s}", j.name))
                .to_vec(),
            spec::JointKind::Free => ["vx", "vy", "vz", "wx", "wy", "wz"]
                .map(|s| format!("{}_{s}", j.name))
                .to_vec(),
            _ => coordinate_names
                .iter()
                .flatten()
                .map(|c| format!("{c}_dot"))
                .collect(),
        };
        let speed_names = self.names(
            j.speeds.as_ref(),
            default_speeds,
            &join(path, &[f("speeds")]),
            "speed",
            nu,
            &j.name,
        );

        let q0 = self.initial(j.q0.as_ref(), path, "q0", nq, &j.name, quaternion_at);
        let u0 = self.initial(j.u0.as_ref(), path, "u0", nu, &j.name, None);
        let mut motion = Motion::Free;
        if let Some(pres) = &j.prescribed {
            let ppath = join(path, &[f("prescribed")]);
            if j.locked {
                self.error(
                    &ppath,
                    format!("joint `{}` is both locked and prescribed", j.name),
                    "remove `locked: true` to drive the joint, or remove `prescribed` to hold it at `q0`",
                );
            } else if quaternion_at.is_some() {
                self.error(
                    &ppath,
                    format!(
                        "prescribed motion of {kind_name} joint `{}` is not supported",
                        j.name
                    ),
                    "prescribe the motion of a chain of revolute joints instead",
                );
            } else if pres.len() != nq {
                self.error(
                    &ppath,
                    format!(
                        "joint `{}` has {nq} coordinate(s) but `prescribed` has {} expression(s)",
                        j.name,
                        pres.len()
                    ),
                    format!("give one expression of `t` per coordinate ({nq})"),
                );
            } else {
                let values: Vec<Option<Quantity>> = pres
                    .iter()
                    .enumerate()
                    .map(|(k, p)| self.quantity(p, &join(&ppath, &[i(k)]), Scope::Time))
                    .collect();
                motion = Motion::Prescribed(values.into_iter().collect::<Option<_>>()?);
            }
        } else if j.locked {
            motion = Motion::Locked;
        }
        // Values that would be dropped without a word.
        let ignored = match motion {
            Motion::Locked if j.u0.is_some() => Some(("u0", "locked", "it does not move")),
            Motion::Prescribed(_) if j.q0.is_some() || j.u0.is_some() => Some((
                if j.q0.is_some() { "q0" } else { "u0" },
                "prescribed",
                "its position and speed follow `prescribed` from t = 0",
            )),
            _ => None,
        };
        if let Some((field, what, why)) = ignored {
            self.warning(
                &join(path, &[f(field)]),
                format!("`{field}` of {what} joint `{}` is ignored", j.name),
                format!("{why}; remove `{field}`"),
            );
        }
        Some(JointInfo {
            name: j.name.clone(),
            label: j.label.clone(),
            kind: kind?,
            parent: parent?,
            child: child?,
            parent_frame: parent_frame?,
            child_frame: child_frame?,
            parent_node: None,
            child_node: None,
            coordinate_names: coordinate_names?,
            speed_names: speed_names?,
            q0: q0?,
            u0: u0?,
            motion,
            q_index: 0,
            u_index: 0,
            span: self.span(path),
        })
    }

    /// Coordinate or speed names: given or default, right count, unique.
    pub(super) fn names(
        &mut self,
        given: Option<&Vec<String>>,
        default: Vec<String>,
        path: &[Seg<'static>],
        what: &'static str,
        count: usize,
        joint: &str,
    ) -> Option<Vec<String>> {
        let names = match given {
            Some(names) if names.len() != count => {
                self.error(
                    path,
                    format!(
                        "joint `{joint}` has {count} {what}(s) but {} name(s) are given",
                        names.len()
                    ),
                    format!(
                        "give {count} name(s), or leave the field out for {}",
                        list_names(default.iter().map(String::as_str))
                    ),
                );
                // Still names: their uses are not unknown names.
                for name in names.iter().filter(|n| is_ident(n)) {
                    self.state_names.entry(name.clone()).or_insert(what);
                }
                return None;
            }
            Some(names) => names.clone(),
            None => default,
        };
        let mut ok = true;
        for (k, name) in names.iter().enumerate() {
            let at = if given.is_some() {
                join(path, &[i(k)])
            } else {
                path.to_vec()
            };
            if self.check_symbol_name(name, &at, what) {
                self.state_names.insert(name.clone(), what);
            } else {
                ok = false;
            }
        }
        ok.then_some(names)
    }

    pub(super) fn initial(
        &mut self,
        given: Option<&Vec<Num>>,
        path: &[Seg<'static>],
        field: &'static str,
        count: usize,
        joint: &str,
        quaternion_at: Option<usize>,
    ) -> Option<Vec<Quantity>> {
        let fpath = join(path, &[f(field)]);
        let Some(given) = given else {
            let mut v = vec![0.0; count];
            if let Some(k) = quaternion_at {
                v[k] = 1.0;
            }
            let span = self.span(path);
            return Some(
                v.into_iter()
                    .map(|x| Quantity {
                        expr: Ast::Num(x),
                        value: x,
                        span,
                    })
                    .collect(),
            );
        };
        if given.len() != count {
            let layout = match (quaternion_at, field) {
                (Some(0), "q0") => " (a unit quaternion w, x, y, z)",
                (Some(_), "q0") => " (position x, y, z, then a unit quaternion w, x, y, z)",
                _ => "",
            };
            self.error(
                &fpath,
                format!(
                    "joint `{joint}` needs {count} value(s) in `{field}`{layout}, got {}",
                    given.len()
                ),
                format!(
                    "write {count} value(s), one per {}",
                    if field == "q0" { "coordinate" } else { "speed" }
                ),
            );
            return None;
        }
        let values: Vec<Option<Quantity>> = given
            .iter()
            .enumerate()
            .map(|(k, n)| self.quantity(n, &join(&fpath, &[i(k)]), Scope::Params))
            .collect();
        let values: Vec<Quantity> = values.into_iter().collect::<Option<_>>()?;
        if let Some(k) = quaternion_at {
            let norm = values[k..k + 4]
                .iter()
                .map(|q| q.value * q.value)
                .sum::<f64>()
                .sqrt();
            if (norm - 1.0).abs() > TOL {
                self.error(
                    &join(&fpath, &[i(k)]),
                    format!("initial quaternion of joint `{joint}` has norm {norm:.12}, not 1"),
                    "write a unit quaternion (w, x, y, z), e.g. (cos(a/2), sin(a/2), 0, 0) for angle a about x",
                );
                return None;
            }
        }
        Some(values)
    }

    pub(super) fn graph(&mut self, spec: &Spec, bodies: &[BodyInfo]) -> Option<Graph> {
        // Built from the body names alone, so that graph errors are found
        // even when other fields of the joints are wrong. Unknown names
        // are reported by `joints`.
        let id = |name: &str| bodies.iter().position(|b| b.name == name);
        let arcs: Vec<Arc> = spec
            .joints
            .iter()
            .map(|s| {
                Some(Arc {
                    parent: id(&s.parent)?,
                    child: id(&s.child)?,
                    prefer_cut: s.cut,
                })
            })
            .collect::<Option<_>>()?;
        match Graph::new(bodies.len(), arcs) {
            Ok(g) => {
                for (k, s) in spec.joints.iter().enumerate() {
                    if s.cut && g.is_tree_joint(k) {
                        self.warning(
                            &[f("joints"), i(k), f("cut")],
                            format!(
                                "joint `{}` is marked `cut` but body `{}` hangs from it alone, so it stays in the tree",
                                s.name, s.child
                            ),
                            "only a joint that closes a loop can be cut; remove `cut: true`",
                        );
                    }
                }
                Some(g)
            }
            Err(errors) => {
                for e in errors {
                    match e {
                        GraphError::SelfLoop(j) => self.error(
                            &[f("joints"), i(j), f("child")],
                            format!("joint `{}` joins body `{}` to itself", spec.joints[j].name, spec.joints[j].child),
                            "a joint connects two different bodies",
                        ),
                        GraphError::Disconnected(b) => self.error(
                            &[f("bodies"), i(b - 1), f("name")],
                            format!("body `{}` is not connected to ground", bodies[b].name),
                            format!(
                                "add a joint with `child: \"{}\"` and a `parent` that is `ground` or a body connected to it",
                                bodies[b].name
                            ),
                        ),
                        GraphError::OnlyReversed { body, joint } => self.error(
                            &[f("joints"), i(joint), f("parent")],
                            format!(
                                "body `{}` is reached only through joint `{}`, where it is the parent",
                                bodies[body].name, spec.joints[joint].name
                            ),
                            "joints point away from ground: swap `parent` and `child` (and the two joint frames)",
                        ),
                    }
                }
                None
            }
        }
    }

    /// Numbers coordinates along the tree (a flexible body's elastic
    /// coordinates right after its joint's); reports cut joints that were
    /// locked, prescribed or given initial values.
    pub(super) fn assign_coordinates(
        &mut self,
        spec: &Spec,
        graph: &Graph,
        joints: &mut [JointInfo],
        bodies: &mut [BodyInfo],
    ) {
        let (mut q, mut u) = (0, 0);
        for &j in graph.tree_joints() {
            let joint = &mut joints[j];
            joint.q_index = q;
            joint.u_index = u;
            if joint.motion == Motion::Free {
                q += joint.kind.nq();
                u += joint.kind.nu();
            }
            if let Some(flex) = bodies[joint.child].flexible.as_deref_mut() {
                flex.q_index = q;
                flex.u_index = u;
                q += flex.count();
                u += flex.count();
            }
        }
        for (j, s) in spec.joints.iter().enumerate() {
            if s.child_node.is_some() && graph.is_tree_joint(j) {
                self.error(
                    &[f("joints"), i(j), f("child_node")],
                    format!(
                        "joint `{}` attaches its child side at a node, but it is a tree joint: body `{}` hangs from it",
                        s.name, s.child
                    ),
                    "only a cut joint (one that closes a loop) may attach its child at a node; turn the joint round \
                     (the flexible body as `parent` with `parent_node`) or let it close a loop with `cut: true`",
                );
            }
        }
        for &j in graph.cut_joints() {
            let s = &spec.joints[j];
            let path = [f("joints"), i(j)];
            if s.locked || s.prescribed.is_some() {
                self.error(
                    &join(&path, &[f(if s.locked { "locked" } else { "prescribed" })]),
                    format!(
                        "joint `{}` closes a loop and is cut, so it cannot be locked or prescribed",
                        s.name
                    ),
                    "mark another joint of the loop with `cut: true`",
                );
            }
            if s.q0.is_some() || s.u0.is_some() {
                self.warning(
                    &join(&path, &[f(if s.q0.is_some() { "q0" } else { "u0" })]),
                    format!("initial values of cut joint `{}` are ignored", s.name),
                    "a cut joint has no coordinates; give initial values on the tree joints of its loop",
                );
            }
            joints[j].motion = Motion::Cut;
            // Its names were reserved while parsing; they name nothing.
            for n in joints[j]
                .coordinate_names
                .iter()
                .chain(&joints[j].speed_names)
            {
                self.state_names.remove(n);
            }
        }
        for j in joints.iter() {
            if matches!(j.motion, Motion::Locked | Motion::Prescribed(_)) {
                for n in j.coordinate_names.iter().chain(&j.speed_names) {
                    self.state_names.remove(n);
                }
            }
        }
    }

    pub(super) fn joint_ref(
        &mut self,
        joints: &[JointInfo],
        name: &str,
        path: &[Seg<'static>],
    ) -> Option<JointId> {
        if let Some(j) = joints.iter().position(|j| j.name == name) {
            return Some(j);
        }
        if self.failed_joints.contains(name) {
            return None;
        }
        let names = joints.iter().map(|j| j.name.as_str());
        let help = match did_you_mean(name, names.clone()) {
            Some(best) => format!("did you mean `{best}`?"),
            None => format!("joints are {}", list_names(names)),
        };
        self.error(path, format!("unknown joint `{name}`"), help);
        None
    }

    /// A joint whose coordinates a force can act on.
    pub(super) fn driven_joint(
        &mut self,
        joints: &[JointInfo],
        name: &str,
        path: &[Seg<'static>],
        what: &str,
    ) -> Option<JointId> {
        let j = self.joint_ref(joints, name, path)?;
        let joint = &joints[j];
        let problem = match joint.motion {
            Motion::Cut => {
                Some("is cut to close a loop, so its coordinates are not coordinates of the system")
            }
            Motion::Locked => Some("is locked"),
            Motion::Prescribed(_) => Some("has prescribed motion"),
            Motion::Free if joint.kind.nu() == 0 => Some("is fixed"),
            Motion::Free => None,
        };
        if let Some(problem) = problem {
            self.error(
                path,
                format!("{what} on joint `{name}`, which {problem}"),
                if joint.motion == Motion::Cut {
                    "mark another joint of the loop with `cut: true` so this one stays in the tree"
                } else {
                    "apply it to a joint with free coordinates"
                },
            );
            return None;
        }
        Some(j)
    }

    /// Warns about cut joints whose two frames do not meet at the initial
    /// state, which simulation closes by assembling the loop; if assembly
    /// cannot close them (Newton on the closure equations stalls above
    /// [`eom_sim::ASSEMBLY_TOL`]: the loop cannot close anywhere near, say
    /// a link too short to reach), each open cut joint is an error with the
    /// smallest residual reached.
    pub(super) fn check_closure(&mut self, sys: &System, poses: &[Pose<f64>]) {
        let open: Vec<(usize, Gap)> = sys
            .graph
            .cut_joints()
            .iter()
            .zip(closure_gaps(sys, poses))
            .filter(|(_, gap)| gap.position > CLOSURE_TOL || gap.angle > CLOSURE_TOL)
            .map(|(&j, gap)| (j, gap))
            .collect();
        if open.is_empty() {
            return;
        }
        let stalled = crate::mech::Numeric::new(sys)
            .ok()
            .and_then(|num| num.assemble(&sys.q0(), &sys.u0(), 0.0).ok())
            .filter(|a| a.residual.is_nan() || a.residual > eom_sim::ASSEMBLY_TOL);
        for (j, gap) in open {
            let joint = &sys.joints[j];
            let at = format!(
                "its frames are {:.3e} m apart and their axes {:.3e} rad out of line",
                gap.position, gap.angle
            );
            match &stalled {
                None => self.warning(
                    &[f("joints"), i(j)],
                    format!("cut joint `{}` is open at the initial state: {at}", joint.name),
                    "check the joint frames and the initial values of the loop's tree joints; simulation starts by assembling the loop",
                ),
                Some(a) => self.error(
                    &[f("joints"), i(j)],
                    format!(
                        "cut joint `{}` cannot be closed: at the initial state {at}, and assembling the loop stalls with max |Φ| {:.3e} (the smallest reached, after {} Newton step(s); tolerance {:e})",
                        joint.name,
                        a.residual,
                        a.iterations,
                        eom_sim::ASSEMBLY_TOL
                    ),
                    "no configuration of the loop's joints near the initial state closes it: check the joint frames and the lengths of the loop's links",
                ),
            }
        }
    }
}

pub(super) fn default_coordinate_names(joint: &str, kind: &spec::JointKind) -> Vec<String> {
    use spec::JointKind as K;
    let suffixes: &[&str] = match kind {
        K::Revolute { .. } | K::Prismatic { .. } | K::Screw { .. } => {
            return vec![joint.to_string()];
        }
        K::Cylindrical { .. } => &["angle", "s"],
        K::Universal { .. } => &["1", "2"],
        K::Planar => &["x", "y", "angle"],
        K::Spherical => &["qw", "qx", "qy", "qz"],
        K::Free => &["x", "y", "z", "qw", "qx", "qy", "qz"],
        K::Fixed => &[],
    };
    suffixes.iter().map(|s| format!("{joint}_{s}")).collect()
}
