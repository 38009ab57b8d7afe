//! Validation: [`Spec`] → [`System`], collecting every problem at once.
//!
//! Each check reports at the span of the offending value (found by its
//! path through the [`locate`](super::locate) tree), names it in backticks
//! and says what would be right. Checks go on after a failure wherever the
//! remaining ones still make sense, so one run reports everything.
//!
//! One file per concern, each adding its checks to the shared `Ctx`:
//! `quantities` (parameters, expressions, frames), `bodies`, `flexible`
//! (and `flex_sources` for assumed modes and modal files), `joints` (and
//! the graph), `mobility` (Grübler–Kutzbach), `forces`, `constraints`,
//! `outputs`, `cables`, `contacts`. `Ctx::system` runs them in order.

use super::locate::{Node, Seg};
use super::spec::Spec;
use crate::diag::{Diagnostic, Source, Span};
use crate::mech::initial::initial_poses;
use crate::system::*;
use std::collections::{HashMap, HashSet};

/// Relative tolerance of the numeric checks (symmetry, orthonormality,
/// unit quaternions, triangle inequalities).
const TOL: f64 = 1e-9;
/// Loop closure gap (m, rad) at the initial state above which `check` warns.
const CLOSURE_TOL: f64 = 1e-6;

type Path = Vec<Seg<'static>>;

fn f(name: &'static str) -> Seg<'static> {
    Seg::Field(name)
}
fn i(index: usize) -> Seg<'static> {
    Seg::Index(index)
}
fn join(path: &[Seg<'static>], more: &[Seg<'static>]) -> Path {
    path.iter().chain(more).copied().collect()
}

mod bodies;
mod cables;
mod constraints;
mod contacts;
mod flex_sources;
mod flexible;
mod forces;
mod geometry;
mod joints;
mod mobility;
mod outputs;
mod quantities;

pub(crate) use mobility::grubler;

/// Which names an expression may use.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Scope {
    /// Parameters only (geometry, masses, initial values).
    Params,
    /// Parameters and time (prescribed motion).
    Time,
    /// Parameters, time, coordinates and speeds (forces, constraints).
    State,
}

/// Validates `spec` (read from `src`, whose span tree is `root`), with or
/// without the check of the mass matrix (which a lenient inertia policy
/// asks for). Returns the system when there is no error, and every
/// diagnostic.
pub fn check_with(
    src: &Source,
    spec: &Spec,
    root: Option<&Node>,
    mass_matrix: bool,
) -> (Option<System>, Vec<Diagnostic>) {
    check_in_dir(src, spec, root, mass_matrix, std::path::Path::new(""))
}

/// [`check_with`] for a model whose path is relative to the directory
/// `dir` (files the model names, such as modal data, are read from there).
pub fn check_in_dir(
    src: &Source,
    spec: &Spec,
    root: Option<&Node>,
    mass_matrix: bool,
    dir: &std::path::Path,
) -> (Option<System>, Vec<Diagnostic>) {
    let mut cx = Ctx {
        dir,
        mass_matrix,
        src,
        root,
        lenient: !spec.inertia_policy.is_strict(),
        diags: Vec::new(),
        params: Vec::new(),
        state_names: HashMap::new(),
        later_params: Vec::new(),
        failed_params: HashSet::new(),
        failed_joints: HashSet::new(),
        failed_markers: HashSet::new(),
    };
    let system = cx.system(spec);
    let mut diags = cx.diags;
    diags.sort_by_key(|d| (d.span.map(|s| s.start), d.severity));
    let system = if diags.iter().any(Diagnostic::is_error) {
        None
    } else {
        system
    };
    (system, diags)
}

struct Ctx<'a> {
    /// What the model's path is relative to.
    dir: &'a std::path::Path,
    src: &'a Source,
    root: Option<&'a Node>,
    /// `inertia_policy: Lenient`: inconsistent tensors are warnings and
    /// masses may be zero.
    lenient: bool,
    /// Check the mass matrix (when lenient).
    mass_matrix: bool,
    diags: Vec<Diagnostic>,
    /// Parameters defined so far, with their default values.
    params: Vec<(String, f64)>,
    /// Coordinates, speeds and inputs: name → what it is (for messages).
    state_names: HashMap<String, &'static str>,
    /// Parameters not defined yet (while parameters are being read).
    later_params: Vec<String>,
    /// Parameters whose value was wrong (already reported): uses of them
    /// fail silently rather than as unknown names.
    failed_params: HashSet<String>,
    /// Joints with an error (already reported): references to them fail
    /// silently rather than as unknown joints.
    failed_joints: HashSet<String>,
    /// Markers `(body, marker)` with an error (already reported), likewise.
    failed_markers: HashSet<(String, String)>,
}

pub(crate) fn is_ident(s: &str) -> bool {
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

const RESERVED: [&str; 2] = ["t", "pi"];

impl Ctx<'_> {
    fn span(&self, path: &[Seg<'static>]) -> Span {
        self.root.map_or(Span::default(), |r| r.span_of(path))
    }

    fn error(&mut self, path: &[Seg<'static>], message: String, help: impl Into<String>) {
        let d = Diagnostic::error(self.span(path), message).with_help(help);
        self.diags.push(d);
    }

    fn warning(&mut self, path: &[Seg<'static>], message: String, help: impl Into<String>) {
        let d = Diagnostic::warning(self.span(path), message).with_help(help);
        self.diags.push(d);
    }

    fn param_value(&self, name: &str) -> Option<f64> {
        self.params
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    }

    fn system(&mut self, spec: &Spec) -> Option<System> {
        if !is_ident(&spec.name) {
            self.error(
                &[f("name")],
                format!("model name `{}` is not an identifier", spec.name),
                "generated code is named after the model: use letters, digits and `_`",
            );
        }
        let parameters = self.parameters(spec);
        let gravity = spec
            .gravity
            .as_ref()
            .and_then(|g| self.vec3(g, &[f("gravity")], Scope::Params));
        let mut bodies = self.bodies(spec);
        let (mut joints, joints_ok) = self.joints(spec, &bodies);
        let graph = self.graph(spec, &bodies);
        if let (Some(graph), true) = (&graph, joints_ok) {
            self.assign_coordinates(spec, graph, &mut joints, &mut bodies);
            for (k, j) in joints.iter().enumerate() {
                if bodies[j.parent].flexible.is_some() && j.parent_node.is_none() {
                    self.warning(
                        &[f("joints"), i(k), f("parent")],
                        format!(
                            "joint `{}` is attached to the reference frame of flexible body `{}`: it does not move with the deformation",
                            j.name, bodies[j.parent].name
                        ),
                        "attach it to a node with `parent_node: \"tip\"` (a named node) or `parent_node: 3` (a node index) to move with the deformation; the frame is exact only where the reference conditions hold the beam (node 0 when clamped)",
                    );
                }
            }
        }
        // Forces, constraints and outputs are checked even when a joint or
        // the graph is wrong, against the joints that are right (without
        // the checks that need the tree: forces on cut joints), so that
        // one run reports every independent error.
        let (forces, inputs) = self.forces(spec, &bodies, &joints);
        let constraints = self.constraints(spec, &bodies);
        let outputs = self.outputs(spec, &bodies, &joints);
        let cables = self.cables(spec, gravity.as_ref(), &bodies);
        let contacts = self.contacts(spec, &bodies, &joints);
        let (Some(graph), true) = (graph, joints_ok) else {
            return None;
        };
        let mut system = System {
            name: spec.name.clone(),
            gravity,
            parameters: parameters?,
            bodies,
            joints,
            graph,
            forces: forces?,
            inputs,
            constraints: constraints?,
            outputs: outputs?,
            grubler: Grubler {
                dof: 0,
                elastic: 0,
                planar: false,
            },
            cables: cables?,
            contacts: contacts.0?,
            cable_contacts: contacts.1?,
        };
        if self.diags.iter().any(Diagnostic::is_error) {
            return None;
        }
        let poses = initial_poses(&system);
        system.grubler = grubler(&system, &poses);
        self.check_closure(&system, &poses);
        self.check_contacts_open(&system);
        self.check_cable_contacts_open(&system);
        self.orient_spheres(&mut system);
        if self.diags.iter().any(Diagnostic::is_error) {
            return None;
        }
        if self.lenient && self.mass_matrix {
            self.check_mass_matrix(&system);
        }
        Some(system)
    }

    /// The mass matrix at the initial state must be positive definite:
    /// otherwise the first joint whose motion has no inertia is an error.
    fn check_mass_matrix(&mut self, system: &System) {
        let Some(s) = crate::mech::numeric::singular_joint(system) else {
            return;
        };
        let j = &system.joints[s.joint];
        let body = system.bodies.get(j.child).map_or("?", |b| b.name.as_str());
        let speed = j
            .speed_names
            .get(s.speed - j.u_index)
            .map_or("?", String::as_str);
        let message = format!(
            "the mass matrix is singular at the initial state: the motion of joint `{}` (speed `{speed}`) has no inertia",
            j.name
        );
        self.diags.push(if s.everywhere {
            Diagnostic::error(j.span, message).with_help(format!(
                "give body `{body}` or the bodies it carries mass and inertia for this motion, or lock or remove the joint"
            ))
        } else {
            Diagnostic::warning(j.span, format!("{message} there (it has elsewhere)")).with_help(
                "two joint axes line up at the initial state; simulations starting there fail: start elsewhere (`q0`, `--q0`)",
            )
        });
    }
}
