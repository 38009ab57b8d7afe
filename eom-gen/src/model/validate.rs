//! Validation: [`Spec`] → [`System`], collecting every problem at once.
//!
//! Each check reports at the span of the offending value (found by its
//! path through the [`locate`](super::locate) tree), names it in backticks
//! and says what would be right. Checks go on after a failure wherever the
//! remaining ones still make sense, so one run reports everything.

use super::flex_outputs::{self, FlexOutput};
use super::locate::{Node, Seg, string_contents_start};
use super::rotation;
use super::spec::{self, Num, Orientation, Spec, V3};
use crate::diag::{Diagnostic, Source, Span, did_you_mean, list_names};
use crate::expr::{Ast, EvalError, Func};
use crate::graph::{Arc, Graph, GraphError, JointId};
use crate::mech::initial::{Pose, closure_gaps, initial_poses};
use crate::system::*;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
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

mod flex_sources;

/// A beam's named nodes, `(name, node index)`.
type NamedNodes = Vec<(String, usize)>;

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

/// A length for messages: at most nine decimals, trailing zeros dropped.
fn short(x: f64) -> String {
    let s = format!("{x:.9}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
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

    /// Checks that `name` is a usable identifier for an expression name.
    fn check_symbol_name(&mut self, name: &str, path: &[Seg<'static>], what: &'static str) -> bool {
        if !is_ident(name) {
            self.error(
                path,
                format!("{what} name `{name}` is not an identifier"),
                "use letters, digits and `_`, starting with a letter or `_`",
            );
            return false;
        }
        if RESERVED.contains(&name) || Func::ALL.iter().any(|f| f.name() == name) {
            self.error(
                path,
                format!("{what} name `{name}` is reserved in expressions"),
                "`t`, `pi` and the function names cannot be redefined; choose another name",
            );
            return false;
        }
        if self.param_value(name).is_some() || self.state_names.contains_key(name) {
            let other = self.state_names.get(name).copied().unwrap_or("parameter");
            if other == what {
                self.error(
                    path,
                    format!("{what} `{name}` is defined twice"),
                    format!("{what} names must be unique; rename one of them"),
                );
                return false;
            }
            self.error(
                path,
                format!("{what} name `{name}` is already used by a {other}"),
                "parameters, coordinates, speeds and inputs share one namespace; rename one of them",
            );
            return false;
        }
        true
    }

    /// Parses and evaluates a number field.
    fn quantity(&mut self, num: &Num, path: &[Seg<'static>], scope: Scope) -> Option<Quantity> {
        let span = self.span(path);
        let (expr, text) = match num {
            Num::Value(v) => (Ast::Num(*v), None),
            Num::Expr(text) => {
                let base = string_contents_start(&self.src.text, span);
                match Ast::parse(text) {
                    Ok(ast) => (ast, Some(base)),
                    Err(e) => {
                        let at = Span::new(base + e.offset, base + e.offset + 1);
                        self.diags.push(
                            Diagnostic::error(at, format!("in expression `{text}`: {}", e.message))
                                .with_help(e.help),
                        );
                        return None;
                    }
                }
            }
        };
        let mut ok = true;
        for (name, offset) in expr.names() {
            if name == "pi" || self.param_value(name).is_some() {
                continue;
            }
            if self.failed_params.contains(name) {
                ok = false;
                continue;
            }
            let allowed = match self.state_names.get(name) {
                _ if name == "t" => scope != Scope::Params,
                Some(_) => scope == Scope::State,
                None => false,
            };
            if allowed {
                continue;
            }
            ok = false;
            let at = text.map_or(span, |base| {
                Span::new(base + offset, base + offset + name.len())
            });
            if let Some(later) = self.later_params.iter().find(|p| p.as_str() == name) {
                let at = text.map_or(span, |base| {
                    Span::new(base + offset, base + offset + name.len())
                });
                self.diags.push(
                    Diagnostic::error(at, format!("parameter `{later}` is used before it is defined"))
                        .with_help("parameters may use only parameters defined above them: move its definition up"),
                );
                continue;
            }
            let message = match (name, self.state_names.get(name)) {
                ("t", _) => "time `t` cannot be used here".to_string(),
                (_, Some(kind)) => format!("{kind} `{name}` cannot be used here"),
                _ => format!("unknown name `{name}` in expression"),
            };
            let mut candidates: Vec<&str> = self.params.iter().map(|(n, _)| n.as_str()).collect();
            if scope == Scope::State {
                candidates.extend(self.state_names.keys().map(String::as_str));
            }
            candidates.sort_unstable();
            let help = match did_you_mean(name, candidates.iter().copied()) {
                Some(best) => format!("did you mean `{best}`?"),
                None => match scope {
                    Scope::Params => format!(
                        "this field may use parameters defined above it and `pi`; parameters: {}",
                        list_names(candidates.iter().copied())
                    ),
                    Scope::Time => "prescribed motion may use parameters, `pi` and time `t`".into(),
                    Scope::State => {
                        "forces and constraints may use parameters, `pi`, `t`, coordinates and speeds"
                            .into()
                    }
                },
            };
            self.diags
                .push(Diagnostic::error(at, message).with_help(help));
        }
        if !ok {
            return None;
        }
        let lookup = |n: &str| {
            self.param_value(n)
                .or_else(|| (n == "t" || self.state_names.contains_key(n)).then_some(0.0))
        };
        match expr.eval(&lookup) {
            Ok(value) => Some(Quantity { expr, value, span }),
            Err(EvalError::NotFinite) if scope == Scope::Params => {
                self.error(
                    path,
                    match num {
                        Num::Expr(text) => {
                            format!("`{text}` is not a finite number at the default parameters")
                        }
                        Num::Value(v) => format!("`{v}` is not a finite number"),
                    },
                    "check for division by zero, `sqrt` or `ln` of a negative value",
                );
                None
            }
            // With time or state at zero a singular value is not an error
            // of the model: the value is only a placeholder.
            Err(_) => Some(Quantity {
                expr,
                value: f64::NAN,
                span,
            }),
        }
    }

    fn vec3(&mut self, v: &V3, path: &[Seg<'static>], scope: Scope) -> Option<Vec3Q> {
        let [a, b, c] = v.components();
        let x = self.quantity(a, &join(path, &[i(0)]), scope);
        let y = self.quantity(b, &join(path, &[i(1)]), scope);
        let z = self.quantity(c, &join(path, &[i(2)]), scope);
        Some([x?, y?, z?])
    }

    fn axis(&mut self, v: &V3, path: &[Seg<'static>], what: &str) -> Option<Axis> {
        let written = self.vec3(v, path, Scope::Params)?;
        let raw = values(&written);
        let norm = raw.norm();
        if norm < 1e-12 || !norm.is_finite() {
            self.error(
                path,
                format!("{what} has zero length"),
                "give a direction such as `(0, 0, 1)`",
            );
            return None;
        }
        Some(Axis {
            written,
            unit: raw / norm,
        })
    }

    fn frame(&mut self, frame: &spec::Frame, path: &[Seg<'static>]) -> Option<FrameInfo> {
        let position = self.vec3(
            &frame.position,
            &join(path, &[f("position")]),
            Scope::Params,
        );
        let rot = self.orientation(&frame.orientation, &join(path, &[f("orientation")]));
        let (rotation, matrix) = rot?;
        Some(FrameInfo {
            position: position?,
            rotation,
            matrix,
        })
    }

    fn orientation(
        &mut self,
        o: &Orientation,
        path: &[Seg<'static>],
    ) -> Option<(Rotation, Matrix3<f64>)> {
        match o {
            Orientation::Identity => Some((Rotation::Identity, Matrix3::identity())),
            Orientation::AxisAngle { axis, angle } => {
                let a = self.axis(axis, &join(path, &[f("axis")]), "rotation axis");
                let angle = self.quantity(angle, &join(path, &[f("angle")]), Scope::Params);
                let (a, angle) = (a?, angle?);
                let m = rotation::axis_angle(&a.unit, angle.value);
                Some((
                    Rotation::AxisAngle {
                        axis: a.written,
                        angle,
                    },
                    m,
                ))
            }
            Orientation::Rpy(r, p, y) => {
                let r = self.quantity(r, &join(path, &[i(0)]), Scope::Params);
                let p = self.quantity(p, &join(path, &[i(1)]), Scope::Params);
                let y = self.quantity(y, &join(path, &[i(2)]), Scope::Params);
                let (r, p, y) = (r?, p?, y?);
                let m = rotation::rpy(r.value, p.value, y.value);
                Some((Rotation::Rpy([r, p, y]), m))
            }
            Orientation::Matrix(a, b, c) => {
                let rows = [
                    self.vec3(a, &join(path, &[i(0)]), Scope::Params),
                    self.vec3(b, &join(path, &[i(1)]), Scope::Params),
                    self.vec3(c, &join(path, &[i(2)]), Scope::Params),
                ];
                let [Some(a), Some(b), Some(c)] = rows else {
                    return None;
                };
                let m = Matrix3::from_rows(&[
                    values(&a).transpose(),
                    values(&b).transpose(),
                    values(&c).transpose(),
                ]);
                let (err, det) = rotation::orthonormality(&m);
                if err > TOL {
                    self.error(
                        path,
                        format!("rotation matrix is not orthonormal (largest entry of RᵀR − I is {err:.3e})"),
                        "rows must be unit vectors at right angles to each other; or write `AxisAngle(axis: …, angle: …)` or `Rpy(roll, pitch, yaw)`",
                    );
                    return None;
                }
                if det < 0.0 {
                    self.error(
                        path,
                        "rotation matrix is a reflection (determinant −1)".into(),
                        "negate one row to make it a proper rotation",
                    );
                    return None;
                }
                Some((Rotation::Matrix([a, b, c]), m))
            }
        }
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
        };
        if self.diags.iter().any(Diagnostic::is_error) {
            return None;
        }
        let poses = initial_poses(&system);
        system.grubler = grubler(&system, &poses);
        self.check_closure(&system, &poses);
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

    fn parameters(&mut self, spec: &Spec) -> Option<Vec<Parameter>> {
        let mut out = Vec::new();
        let mut ok = true;
        for (k, p) in spec.parameters.iter().enumerate() {
            self.later_params = spec.parameters[k..]
                .iter()
                .map(|p| p.name.clone())
                .collect();
            let path = [f("parameters"), i(k)];
            let named = self.check_symbol_name(&p.name, &join(&path, &[f("name")]), "parameter");
            // Later parameters are not visible yet: a forward reference is
            // reported as an unknown name with the definition order in help.
            match self.quantity(&p.value, &join(&path, &[f("value")]), Scope::Params) {
                Some(value) => {
                    if p.tunable && !matches!(value.expr, Ast::Num(_)) {
                        self.warning(
                            &join(&path, &[f("value")]),
                            format!("tunable parameter `{}` is given by an expression", p.name),
                            "its default is the expression's value; at run time it is set directly",
                        );
                    }
                    if named {
                        self.params.push((p.name.clone(), value.value));
                    }
                    out.push(Parameter {
                        name: p.name.clone(),
                        value,
                        tunable: p.tunable,
                        doc: p.doc.clone(),
                        span: self.span(&join(&path, &[f("name")])),
                    });
                }
                None => {
                    self.failed_params.insert(p.name.clone());
                    ok = false;
                }
            }
        }
        self.later_params.clear();
        ok.then_some(out)
    }

    fn bodies(&mut self, spec: &Spec) -> Vec<BodyInfo> {
        let mut bodies = vec![BodyInfo {
            name: "ground".into(),
            mass: None,
            com: None,
            inertia: None,
            markers: Vec::new(),
            flexible: None,
            span: Span::default(),
        }];
        let mut seen: HashMap<&str, usize> = HashMap::new();
        for (k, b) in spec.bodies.iter().enumerate() {
            let path = [f("bodies"), i(k)];
            let name_path = join(&path, &[f("name")]);
            if b.name == "ground" {
                self.error(
                    &name_path,
                    "`ground` is the inertial body and cannot be defined".into(),
                    "refer to it as a joint's `parent` without listing it; rename this body",
                );
            } else if !is_ident(&b.name) {
                self.error(
                    &name_path,
                    format!("body name `{}` is not an identifier", b.name),
                    "use letters, digits and `_`, starting with a letter or `_`",
                );
            } else if let Some(prev) = seen.insert(&b.name, k) {
                self.error(
                    &name_path,
                    format!("body `{}` is defined twice", b.name),
                    format!(
                        "the first definition is body number {}; rename one of them",
                        prev + 1
                    ),
                );
            }
            let flexible = b
                .flexible
                .as_ref()
                .and_then(|fl| self.flexible(fl, &b.name, &path));
            let mass = match &b.mass {
                Some(m) => self.quantity(m, &join(&path, &[f("mass")]), Scope::Params),
                None if b.flexible.is_none() => {
                    self.error(
                        &path,
                        format!("body `{}` has no `mass`", b.name),
                        "give a rigid body its mass in kg (`mass: 1.0`); only a flexible body may leave it out",
                    );
                    None
                }
                None => None,
            };
            if let Some(m) = &mass
                && (m.value < 0.0 || (m.value == 0.0 && !self.lenient && b.flexible.is_none()))
            {
                self.error(
                    &join(&path, &[f("mass")]),
                    format!("mass of body `{}` is {} kg", b.name, m.value),
                    "a body needs a positive mass; model a massless link by placing the next joint's frame on the previous body",
                );
            }
            let com = self.vec3(&b.com, &join(&path, &[f("com")]), Scope::Params);
            let inertia = b
                .inertia
                .as_ref()
                .and_then(|ine| self.inertia(ine, &b.name, &join(&path, &[f("inertia")])));
            let mut markers = Vec::new();
            let mut marker_names = HashSet::new();
            for (m, marker) in b.markers.iter().enumerate() {
                let mpath = join(&path, &[f("markers"), i(m)]);
                if !marker_names.insert(marker.name.as_str()) {
                    self.error(
                        &join(&mpath, &[f("name")]),
                        format!(
                            "marker `{}` is defined twice on body `{}`",
                            marker.name, b.name
                        ),
                        "marker names must be unique on their body",
                    );
                }
                let frame = spec::Frame {
                    position: marker.position.clone(),
                    orientation: marker.orientation.clone(),
                };
                let node = marker.node.as_ref().map(|node| {
                    self.node_ref(
                        node,
                        &b.name,
                        b.flexible.as_ref(),
                        flexible.as_deref(),
                        &join(&mpath, &[f("node")]),
                        &format!("marker `{}`", marker.name),
                    )
                });
                if node == Some(None) {
                    self.failed_markers
                        .insert((b.name.clone(), marker.name.clone()));
                    continue;
                }
                match self.frame(&frame, &mpath) {
                    Some(frame) => markers.push(MarkerInfo {
                        name: marker.name.clone(),
                        frame,
                        node: node.flatten(),
                    }),
                    None => {
                        self.failed_markers
                            .insert((b.name.clone(), marker.name.clone()));
                    }
                }
            }
            bodies.push(BodyInfo {
                name: b.name.clone(),
                mass,
                com,
                inertia,
                markers,
                flexible,
                span: self.span(&path),
            });
        }
        bodies
    }

    /// A flexible body's beam: its numbers checked, its modes and inertia
    /// shape integrals computed at the defaults, its elastic coordinates
    /// named (`<body>_f1 …`, rates `<body>_f1_dot …`).
    fn flexible(
        &mut self,
        flex: &spec::Flexible,
        body: &str,
        path: &[Seg<'static>],
    ) -> Option<Box<FlexInfo>> {
        let spec::Flexible::Beam {
            length,
            rho_a,
            rho_ip,
            ea,
            ei_y,
            ei_z,
            gj,
            elements,
            reference,
            modes,
            stiffening,
            damping,
            nodes: named_nodes,
            craig_bampton,
            shear,
        } = flex
        else {
            return self.flexible_source(flex, body, path);
        };
        let fpath = join(path, &[f("flexible")]);
        let fields: [(&'static str, &Num, &str, &str); 7] = [
            ("length", length, "m", "length"),
            ("rho_a", rho_a, "kg/m", "mass per length"),
            ("rho_ip", rho_ip, "kg m", "polar mass moment per length"),
            ("ea", ea, "N", "axial stiffness"),
            ("ei_y", ei_y, "N m²", "bending stiffness"),
            ("ei_z", ei_z, "N m²", "bending stiffness"),
            ("gj", gj, "N m²", "torsional stiffness"),
        ];
        let mut written = Vec::new();
        for (name, num, unit, what) in fields {
            let at = join(&fpath, &[f(name)]);
            let q = self.quantity(num, &at, Scope::Params);
            if let Some(q) = &q
                && q.value <= 0.0
            {
                self.error(
                    &at,
                    format!(
                        "{what} `{name}` of flexible body `{body}` is {} {unit}",
                        q.value
                    ),
                    format!("a beam needs a positive {what} ({unit})"),
                );
                continue;
            }
            written.extend(q);
        }
        if *elements == 0 {
            self.error(
                &join(&fpath, &[f("elements")]),
                format!("flexible body `{body}` has no elements"),
                "a beam needs at least one finite element; a few per mode kept is typical",
            );
        }
        if *modes == 0 && (!*craig_bampton || named_nodes.is_empty()) {
            self.error(
                &join(&fpath, &[f("modes")]),
                format!("flexible body `{body}` keeps no modes"),
                "keep at least one mode, or leave out `flexible` to make the body rigid",
            );
        }
        let damping = self.nonnegative(
            damping,
            &join(&fpath, &[f("damping")]),
            "damping ratio",
            body,
        );
        let sheared = match shear {
            None => Some(None),
            Some(sh) => self
                .beam_shear(sh, &written, *stiffening, body, &fpath)
                .map(Some),
        };
        let (true, Some(damping), Some(sheared)) = (written.len() == 7, damping, sheared) else {
            return None;
        };
        let (shear, shear_written) = match sheared {
            Some((sh, q)) => (Some(sh), q),
            None => (None, Vec::new()),
        };
        if *craig_bampton && named_nodes.is_empty() {
            self.error(
                &join(&fpath, &[f("craig_bampton")]),
                format!("flexible body `{body}` asks for Craig–Bampton modes but names no nodes"),
                "the boundary of a Craig–Bampton basis is the named nodes: add `nodes: [(name: \"tip\", x: …)]`, or leave out `craig_bampton`",
            );
            return None;
        }
        if *elements == 0 || (*modes == 0 && !*craig_bampton) {
            return None;
        }
        let (nodes, places) = self.beam_nodes(named_nodes, &written[0], *elements, body, &fpath)?;
        let beam = crate::flex::Beam {
            length: written[0].value,
            rho_a: written[1].value,
            rho_ip: written[2].value,
            ea: written[3].value,
            ei_y: written[4].value,
            ei_z: written[5].value,
            gj: written[6].value,
            elements: *elements,
            shear,
        };
        written.extend(shear_written);
        let reference = match reference {
            spec::BeamReference::Clamped => crate::flex::Reference::Clamped,
            spec::BeamReference::PinnedPinned => crate::flex::Reference::PinnedPinned,
            spec::BeamReference::MeanAxis => crate::flex::Reference::MeanAxis,
            spec::BeamReference::Fixed(nodes) => {
                self.fixed_reference(nodes, *elements, body, &fpath)?
            }
        };
        let reduced = if *craig_bampton {
            let boundary: Vec<usize> = nodes.iter().map(|(_, n)| *n).collect();
            crate::flex::craig_bampton(&beam, &reference, &boundary, *modes)
        } else {
            crate::flex::normal_modes(&beam, &reference, *modes)
        };
        let reduced = match reduced {
            Ok(m) => m,
            Err(e) => {
                use crate::flex::FlexError;
                let (field, help) = match &e {
                    FlexError::TooManyModes { .. } => (
                        "modes",
                        "each element adds six nodal degrees of freedom".to_string(),
                    ),
                    FlexError::FrameUndefined(_) | FlexError::NeedsNodalReference => (
                        "reference",
                        "`Clamped`, `PinnedPinned` and `MeanAxis` each fix the frame".to_string(),
                    ),
                    _ => ("elements", "check the beam's data".to_string()),
                };
                self.error(
                    &join(&fpath, &[f(field)]),
                    format!("flexible body `{body}`: {e}"),
                    help,
                );
                return None;
            }
        };
        let invariants = crate::flex::Invariants::new(&beam, &reduced);
        let shares = crate::flex::invariants::Shares::of_beam(&beam, &reduced);
        let (coordinate_names, speed_names) = self.elastic_names(body, path, reduced.count())?;
        // After the seven section data, the nodes' places (none may be tunable).
        written.extend(places);
        Some(Box::new(FlexInfo {
            written,
            shares: Some(shares),
            source: crate::system::FlexSource::Beam,
            beam,
            reference,
            modes: reduced,
            invariants,
            damping,
            stiffening: *stiffening,
            nodes,
            coordinate_names,
            speed_names,
            q_index: 0,
            u_index: 0,
            span: self.span(&fpath),
        }))
    }

    /// A beam's Timoshenko data (`shear`), checked: positive shear
    /// stiffnesses, rotary inertias zero or positive (absent: `ρA EI / EA`
    /// of a homogeneous section, from `written`, the seven beam numbers when
    /// all are valid), and no stiffening. The data and the quantities as
    /// written, or `None` when something is wrong (reported).
    fn beam_shear(
        &mut self,
        shear: &spec::BeamShear,
        written: &[Quantity],
        stiffening: bool,
        body: &str,
        fpath: &[Seg<'static>],
    ) -> Option<(crate::flex::beam::Shear, Vec<Quantity>)> {
        let spec::BeamShear::Timoshenko {
            kga_y,
            kga_z,
            rho_iy,
            rho_iz,
        } = shear;
        let spath = join(fpath, &[f("shear")]);
        let mut ok = true;
        if stiffening {
            self.error(
                &join(fpath, &[f("stiffening")]),
                format!(
                    "flexible body `{body}` asks for geometric stiffening of a Timoshenko beam (`shear`)"
                ),
                "stiffening is only built for Euler–Bernoulli beams: with shear the axial load's \
                 geometric stiffness is not unique (Engesser's and Haringx's forms differ), and eom's \
                 foreshortening terms are checked for Euler–Bernoulli only; leave out `stiffening` or `shear`",
            );
            ok = false;
        }
        let mut quantities = Vec::new();
        let mut values = [0.0; 4];
        for (slot, (name, num)) in [("kga_y", kga_y), ("kga_z", kga_z)].into_iter().enumerate() {
            let at = join(&spath, &[f(name)]);
            match self.quantity(num, &at, Scope::Params) {
                Some(q) if q.value <= 0.0 => {
                    self.error(
                        &at,
                        format!(
                            "shear stiffness `{name}` of flexible body `{body}` is {} N",
                            q.value
                        ),
                        "a Timoshenko beam needs a positive shear stiffness κGA (N); \
                         for a rectangle κ = 5/6, for a solid circle κ = 0.9 (or 6/7)",
                    );
                    ok = false;
                }
                Some(q) => {
                    values[slot] = q.value;
                    quantities.push(q);
                }
                None => ok = false,
            }
        }
        // Written index of the bending stiffness of each rotary inertia: ei_y, ei_z.
        for (slot, (name, num, ei)) in [("rho_iy", rho_iy, 4), ("rho_iz", rho_iz, 5)]
            .into_iter()
            .enumerate()
        {
            match num {
                Some(num) => {
                    let what = "rotary inertia per length";
                    match self.nonnegative(num, &join(&spath, &[f(name)]), what, body) {
                        Some(q) => {
                            values[2 + slot] = q.value;
                            quantities.push(q);
                        }
                        None => ok = false,
                    }
                }
                None if written.len() == 7 => {
                    values[2 + slot] = written[1].value * written[ei].value / written[3].value;
                }
                None => {}
            }
        }
        ok.then_some((
            crate::flex::beam::Shear {
                kga_y: values[0],
                kga_z: values[1],
                rho_iy: values[2],
                rho_iz: values[3],
            },
            quantities,
        ))
    }

    /// The names of a flexible body's `k` elastic coordinates
    /// (`<body>_f1 …`) and their rates (`<body>_f1_dot …`), registered.
    fn elastic_names(
        &mut self,
        body: &str,
        path: &[Seg<'static>],
        k: usize,
    ) -> Option<(Vec<String>, Vec<String>)> {
        let mut names = |suffix: &str, what: &'static str| -> Option<Vec<String>> {
            let names: Vec<String> = (1..=k).map(|n| format!("{body}_f{n}{suffix}")).collect();
            let mut ok = true;
            for name in &names {
                if self.check_symbol_name(name, path, what) {
                    self.state_names.insert(name.clone(), what);
                } else {
                    ok = false;
                }
            }
            ok.then_some(names)
        };
        let coordinates = names("", "elastic coordinate")?;
        let speeds = names("_dot", "elastic speed")?;
        Some((coordinates, speeds))
    }

    /// A beam's named nodes: unique names, each at a finite-element node
    /// (`x = i · length / elements`), as `(name, node index)`, and their
    /// `x` as written.
    fn beam_nodes(
        &mut self,
        named: &[spec::BeamNode],
        length: &Quantity,
        elements: usize,
        body: &str,
        fpath: &[Seg<'static>],
    ) -> Option<(NamedNodes, Vec<Quantity>)> {
        let mut out: Vec<(String, usize)> = Vec::new();
        let mut places = Vec::new();
        let mut ok = true;
        let l = length.value;
        let h = l / elements as f64;
        for (k, node) in named.iter().enumerate() {
            let npath = join(fpath, &[f("nodes"), i(k)]);
            if out.iter().any(|(n, _)| *n == node.name) {
                self.error(
                    &join(&npath, &[f("name")]),
                    format!("node `{}` is named twice on body `{body}`", node.name),
                    "node names must be unique on their body",
                );
                ok = false;
                continue;
            }
            let xpath = join(&npath, &[f("x")]);
            let Some(x) = self.quantity(&node.x, &xpath, Scope::Params) else {
                ok = false;
                continue;
            };
            let at = (x.value / h).round();
            if !(0.0..=elements as f64).contains(&at) || (x.value - at * h).abs() > 1e-9 * l {
                let below = (x.value / h).floor().clamp(0.0, elements as f64) as usize;
                let above = (below + 1).min(elements);
                let near = if below == above || x.value <= 0.0 {
                    format!("node {below} at x = {}", short(below as f64 * h))
                } else {
                    format!(
                        "node {below} at x = {} and node {above} at x = {}",
                        short(below as f64 * h),
                        short(above as f64 * h)
                    )
                };
                self.error(
                    &xpath,
                    format!(
                        "node `{}` of flexible body `{body}` at x = {} m is not a finite-element node",
                        node.name,
                        short(x.value)
                    ),
                    format!(
                        "nodes sit at x = i·length/{elements} (every {} m, from 0 to {}); the nearest: {near}",
                        short(h),
                        short(l)
                    ),
                );
                ok = false;
                continue;
            }
            out.push((node.name.clone(), at as usize));
            places.push(x);
        }
        ok.then_some((out, places))
    }

    /// The finite-element node index that `node` names on body `body`
    /// (`spec_flexible`: the body is flexible as written; `info`: its
    /// checked data, `None` if it failed and was reported already).
    fn node_ref(
        &mut self,
        node: &spec::NodeRef,
        body: &str,
        spec_flexible: Option<&spec::Flexible>,
        info: Option<&FlexInfo>,
        path: &[Seg<'static>],
        what: &str,
    ) -> Option<usize> {
        let elements = match spec_flexible {
            Some(spec::Flexible::Beam { elements, .. }) => elements,
            Some(spec::Flexible::Modal { file, .. }) => {
                return self.modal_node_ref(node, body, file, info, path, what);
            }
            Some(spec::Flexible::AssumedModes { nodes: written, .. }) => {
                return self.assumed_node_ref(node, body, written, info, path, what);
            }
            None => {
                self.error(
                    path,
                    format!("{what} names node {node}, but body `{body}` is rigid"),
                    "only a flexible body has nodes to attach to; leave the node out",
                );
                return None;
            }
        };
        match node {
            spec::NodeRef::Index(n) if *n > *elements => {
                self.error(
                    path,
                    format!(
                        "{what}: {}",
                        crate::flex::FlexError::UnknownNode {
                            node: *n,
                            nodes: elements + 1
                        }
                    ),
                    format!(
                        "node i sits at x = i·length/{elements}; use a node from 0 to {elements}"
                    ),
                );
                None
            }
            spec::NodeRef::Index(n) => Some(*n),
            spec::NodeRef::Name(name) => {
                if let Some((_, n)) = info.and_then(|f| f.nodes.iter().find(|(n, _)| n == name)) {
                    return Some(*n);
                }
                let Some(spec::Flexible::Beam { nodes: written, .. }) = spec_flexible else {
                    return None;
                };
                if written.iter().any(|n| &n.name == name) {
                    // Named, but the node or its body has an error (reported).
                    return None;
                }
                let names = written.iter().map(|n| n.name.as_str());
                let help = match did_you_mean(name, names.clone()) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None if written.is_empty() => format!(
                        "name nodes in the beam's `nodes: [(name: \"{name}\", x: …)]`, or give a node index 0..={elements}"
                    ),
                    None => format!(
                        "its nodes are {}; or give a node index 0..={elements}",
                        list_names(names)
                    ),
                };
                self.error(
                    path,
                    format!("{what}: flexible body `{body}` has no node `{name}`"),
                    help,
                );
                None
            }
        }
    }

    /// The node of an assumed-modes body that `node` names: a name from its
    /// `nodes`, or an index into them.
    fn assumed_node_ref(
        &mut self,
        node: &spec::NodeRef,
        body: &str,
        written: &[spec::BeamNode],
        info: Option<&FlexInfo>,
        path: &[Seg<'static>],
        what: &str,
    ) -> Option<usize> {
        let names = written.iter().map(|n| n.name.as_str());
        let list = if written.is_empty() {
            "name nodes in the body's `nodes: [(name: \"tip\", x: …)]` (assumed modes have no others)".to_string()
        } else {
            format!("its nodes are {}", list_names(names.clone()))
        };
        match node {
            spec::NodeRef::Index(n) if *n < written.len() => info.is_some().then_some(*n),
            spec::NodeRef::Index(n) => {
                self.error(
                    path,
                    format!(
                        "{what} names node {n}, but body `{body}` (assumed modes) has {} named node{}",
                        written.len(),
                        if written.len() == 1 { "" } else { "s" }
                    ),
                    list,
                );
                None
            }
            spec::NodeRef::Name(name) => {
                if let Some((_, n)) = info.and_then(|f| f.nodes.iter().find(|(n, _)| n == name)) {
                    return Some(*n);
                }
                if written.iter().any(|n| &n.name == name) {
                    // Named, but the node or its body has an error (reported).
                    return None;
                }
                let help = match did_you_mean(name, names) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None => list,
                };
                self.error(
                    path,
                    format!("{what}: flexible body `{body}` has no node `{name}`"),
                    help,
                );
                None
            }
        }
    }

    /// The node of an imported modal body that `node` names: an index into
    /// the file's `nodes`, or a name one of them carries.
    fn modal_node_ref(
        &mut self,
        node: &spec::NodeRef,
        body: &str,
        file: &str,
        info: Option<&FlexInfo>,
        path: &[Seg<'static>],
        what: &str,
    ) -> Option<usize> {
        // The file failed to load or check: reported already.
        let Some(FlexSource::Modal {
            positions, names, ..
        }) = info.map(|x| &x.source)
        else {
            return None;
        };
        match node {
            spec::NodeRef::Index(n) if *n < positions.len() => Some(*n),
            spec::NodeRef::Index(n) => {
                self.error(
                    path,
                    format!(
                        "{what}: node {n} does not exist: `{file}` has nodes 0..={}",
                        positions.len().saturating_sub(1)
                    ),
                    "nodes are numbered from 0 in the order of the file's `nodes`",
                );
                None
            }
            spec::NodeRef::Name(name) => {
                if let Some(n) = names
                    .iter()
                    .position(|x| x.as_deref() == Some(name.as_str()))
                {
                    return Some(n);
                }
                let written = names.iter().flatten().map(String::as_str);
                let help = match did_you_mean(name, written.clone()) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None if names.iter().all(Option::is_none) => format!(
                        "`{file}` names no nodes: give a node index 0..={}, or a `name` in the file",
                        positions.len().saturating_sub(1)
                    ),
                    None => format!("its named nodes are {}", list_names(written)),
                };
                self.error(
                    path,
                    format!("{what}: flexible body `{body}` (`{file}`) has no node `{name}`"),
                    help,
                );
                None
            }
        }
    }

    fn inertia(
        &mut self,
        ine: &spec::Inertia,
        body: &str,
        path: &[Seg<'static>],
    ) -> Option<[Vec3Q; 3]> {
        let rows = match ine {
            spec::Inertia::Diag(a, b, c) => {
                let d = [
                    self.quantity(a, &join(path, &[i(0)]), Scope::Params),
                    self.quantity(b, &join(path, &[i(1)]), Scope::Params),
                    self.quantity(c, &join(path, &[i(2)]), Scope::Params),
                ];
                let [Some(a), Some(b), Some(c)] = d else {
                    return None;
                };
                let zero = |s: Span| Quantity {
                    expr: Ast::Num(0.0),
                    value: 0.0,
                    span: s,
                };
                let (sa, sb, sc) = (a.span, b.span, c.span);
                [
                    [a, zero(sa), zero(sa)],
                    [zero(sb), b, zero(sb)],
                    [zero(sc), zero(sc), c],
                ]
            }
            spec::Inertia::Matrix(a, b, c) => {
                let rows = [
                    self.vec3(a, &join(path, &[i(0)]), Scope::Params),
                    self.vec3(b, &join(path, &[i(1)]), Scope::Params),
                    self.vec3(c, &join(path, &[i(2)]), Scope::Params),
                ];
                let [Some(a), Some(b), Some(c)] = rows else {
                    return None;
                };
                [a, b, c]
            }
        };
        let m = Matrix3::from_fn(|r, c| rows[r][c].value);
        let scale = m.amax().max(f64::MIN_POSITIVE);
        let asym = (m - m.transpose()).amax();
        if asym > TOL * scale {
            self.error(
                path,
                format!("inertia of body `{body}` is not symmetric (largest |I_ij − I_ji| = {asym:.3e})"),
                "an inertia tensor is symmetric: make the entry below the diagonal equal the one above it",
            );
            return None;
        }
        let mut eig: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
        eig.sort_by(f64::total_cmp);
        if eig[0] < -TOL * scale {
            if self.lenient {
                self.warning(
                    path,
                    format!(
                        "inertia of body `{body}` is not positive semi-definite (principal moments {:.6}, {:.6}, {:.6})",
                        eig[0], eig[1], eig[2]
                    ),
                    "kept as written (`inertia_policy: Lenient`): the mass matrix is checked instead; principal moments of inertia cannot be negative",
                );
                return Some(rows);
            }
            self.error(
                path,
                format!(
                    "inertia of body `{body}` is not positive semi-definite (principal moments {:.6}, {:.6}, {:.6})",
                    eig[0], eig[1], eig[2]
                ),
                "principal moments of inertia cannot be negative; check signs (off-diagonal entries are tensor entries, minus the products of inertia)",
            );
            return None;
        }
        if eig[0] + eig[1] < eig[2] - TOL * scale {
            if self.lenient {
                self.warning(
                    path,
                    format!(
                        "inertia of body `{body}` violates the triangle inequality: {:.6} + {:.6} < {:.6}",
                        eig[0], eig[1], eig[2]
                    ),
                    "kept as written (`inertia_policy: Lenient`): no mass distribution has these principal moments",
                );
                return Some(rows);
            }
            self.error(
                path,
                format!(
                    "inertia of body `{body}` violates the triangle inequality: {:.6} + {:.6} < {:.6}",
                    eig[0], eig[1], eig[2]
                ),
                "no mass distribution has these principal moments: each must be at most the sum of the other two",
            );
            return None;
        }
        Some(rows)
    }

    /// The joints that are right, and whether all are.
    fn joints(&mut self, spec: &Spec, bodies: &[BodyInfo]) -> (Vec<JointInfo>, bool) {
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

    fn body_ref(
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

    fn joint(
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
    fn names(
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

    fn initial(
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

    fn graph(&mut self, spec: &Spec, bodies: &[BodyInfo]) -> Option<Graph> {
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
    fn assign_coordinates(
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

    fn joint_ref(
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
    fn driven_joint(
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

    fn anchor(
        &mut self,
        a: &spec::Anchor,
        bodies: &[BodyInfo],
        path: &[Seg<'static>],
    ) -> Option<Point> {
        let body = self.body_ref(bodies, &a.body, &join(path, &[f("body")]), "anchor")?;
        match (&a.point, &a.marker) {
            (Some(_), Some(_)) => {
                self.error(
                    path,
                    "an anchor has both `point` and `marker`".into(),
                    "give one of them",
                );
                None
            }
            (Some(p), None) => Some(Point {
                body,
                position: self.vec3(p, &join(path, &[f("point")]), Scope::Params)?,
                node: None,
            }),
            (None, Some(m)) => {
                let Some(marker) = bodies[body].markers.iter().find(|x| &x.name == m) else {
                    if self.failed_markers.contains(&(a.body.clone(), m.clone())) {
                        return None;
                    }
                    let names = bodies[body].markers.iter().map(|x| x.name.as_str());
                    self.error(
                        &join(path, &[f("marker")]),
                        format!("body `{}` has no marker `{m}`", a.body),
                        format!("its markers are {}", list_names(names)),
                    );
                    return None;
                };
                Some(Point {
                    body,
                    position: marker.frame.position.clone(),
                    node: marker.node,
                })
            }
            (None, None) => {
                let zero = Quantity {
                    expr: Ast::Num(0.0),
                    value: 0.0,
                    span: self.span(path),
                };
                Some(Point {
                    body,
                    position: [zero.clone(), zero.clone(), zero],
                    node: None,
                })
            }
        }
    }

    fn forces(
        &mut self,
        spec: &Spec,
        bodies: &[BodyInfo],
        joints: &[JointInfo],
    ) -> (Option<Vec<Force>>, Vec<String>) {
        let mut out = Vec::new();
        let mut inputs = Vec::new();
        let mut ok = true;
        let mut names = HashSet::new();
        for (k, force) in spec.forces.iter().enumerate() {
            let path = [f("forces"), i(k)];
            let name = match force {
                spec::Force::SpringDamper { name, .. }
                | spec::Force::JointSpringDamper { name, .. }
                | spec::Force::JointForce { name, .. }
                | spec::Force::Actuator { name, .. } => name,
            };
            if !names.insert(name.as_str()) {
                self.error(
                    &join(&path, &[f("name")]),
                    format!("force `{name}` is defined twice"),
                    "force names must be unique",
                );
            }
            let element = match force {
                spec::Force::SpringDamper {
                    a,
                    b,
                    stiffness,
                    damping,
                    rest_length,
                    ..
                } => {
                    let a = self.anchor(a, bodies, &join(&path, &[f("a")]));
                    let b = self.anchor(b, bodies, &join(&path, &[f("b")]));
                    let k =
                        self.quantity(stiffness, &join(&path, &[f("stiffness")]), Scope::Params);
                    let c =
                        self.nonnegative(damping, &join(&path, &[f("damping")]), "damping", name);
                    let l = self.nonnegative(
                        rest_length,
                        &join(&path, &[f("rest_length")]),
                        "rest length",
                        name,
                    );
                    (|| {
                        Some(ForceElement::SpringDamper {
                            a: a?,
                            b: b?,
                            stiffness: k?,
                            damping: c?,
                            rest_length: l?,
                        })
                    })()
                }
                spec::Force::JointSpringDamper {
                    joint,
                    stiffness,
                    damping,
                    rest,
                    ..
                } => {
                    let jp = join(&path, &[f("joint")]);
                    let j = self.driven_joint(joints, joint, &jp, "a joint spring-damper");
                    if let Some(j) = j
                        && matches!(joints[j].kind, JointType::Spherical | JointType::Free)
                    {
                        self.error(
                            &jp,
                            format!("a joint spring-damper on {} joint `{joint}` is not supported", joints[j].kind.name()),
                            "its coordinates include a quaternion; use point-to-point spring-dampers instead",
                        );
                        ok = false;
                    }
                    let k =
                        self.quantity(stiffness, &join(&path, &[f("stiffness")]), Scope::Params);
                    let c =
                        self.nonnegative(damping, &join(&path, &[f("damping")]), "damping", name);
                    let r = self.quantity(rest, &join(&path, &[f("rest")]), Scope::Params);
                    (|| {
                        Some(ForceElement::JointSpringDamper {
                            joint: j?,
                            stiffness: k?,
                            damping: c?,
                            rest: r?,
                        })
                    })()
                }
                spec::Force::JointForce { joint, values, .. } => {
                    let j = self.driven_joint(
                        joints,
                        joint,
                        &join(&path, &[f("joint")]),
                        "a joint force",
                    );
                    let vpath = join(&path, &[f("values")]);
                    match j {
                        Some(j) if values.len() != joints[j].kind.nu() => {
                            self.error(
                                &vpath,
                                format!(
                                    "joint `{joint}` has {} speed(s) but {} force value(s) are given",
                                    joints[j].kind.nu(),
                                    values.len()
                                ),
                                format!("give one generalised force per speed: {}", list_names(joints[j].speed_names.iter().map(String::as_str))),
                            );
                            None
                        }
                        Some(j) => {
                            let v: Vec<Option<Quantity>> = values
                                .iter()
                                .enumerate()
                                .map(|(k, v)| {
                                    self.quantity(v, &join(&vpath, &[i(k)]), Scope::State)
                                })
                                .collect();
                            v.into_iter()
                                .collect::<Option<Vec<_>>>()
                                .map(|values| ForceElement::JointForce { joint: j, values })
                        }
                        None => None,
                    }
                }
                spec::Force::Actuator {
                    joint,
                    inputs: given,
                    ..
                } => {
                    let j = self.driven_joint(
                        joints,
                        joint,
                        &join(&path, &[f("joint")]),
                        "an actuator",
                    );
                    match j {
                        Some(j) => {
                            let nu = joints[j].kind.nu();
                            let default = if nu == 1 {
                                vec![name.clone()]
                            } else {
                                (1..=nu).map(|k| format!("{name}_{k}")).collect()
                            };
                            let names = self.input_names(
                                given.as_ref(),
                                default,
                                &join(&path, &[f("inputs")]),
                                nu,
                                name,
                            );
                            names.map(|names| {
                                let first = inputs.len();
                                inputs.extend(names);
                                ForceElement::Actuator {
                                    joint: j,
                                    inputs: (first..inputs.len()).map(Some).collect(),
                                }
                            })
                        }
                        None => None,
                    }
                }
            };
            match element {
                Some(element) => out.push(Force {
                    name: name.clone(),
                    element,
                    span: self.span(&path),
                }),
                None => ok = false,
            }
        }
        (ok.then_some(out), inputs)
    }

    fn input_names(
        &mut self,
        given: Option<&Vec<String>>,
        default: Vec<String>,
        path: &[Seg<'static>],
        count: usize,
        actuator: &str,
    ) -> Option<Vec<String>> {
        let names = match given {
            Some(n) if n.len() != count => {
                self.error(
                    path,
                    format!("actuator `{actuator}` drives {count} speed(s) but {} input name(s) are given", n.len()),
                    format!("give {count} name(s), or leave `inputs` out"),
                );
                return None;
            }
            Some(n) => n.clone(),
            None => default,
        };
        let mut ok = true;
        for (k, n) in names.iter().enumerate() {
            let at = if given.is_some() {
                join(path, &[i(k)])
            } else {
                path.to_vec()
            };
            if self.check_symbol_name(n, &at, "input") {
                self.state_names.insert(n.clone(), "input");
            } else {
                ok = false;
            }
        }
        ok.then_some(names)
    }

    fn nonnegative(
        &mut self,
        n: &Num,
        path: &[Seg<'static>],
        what: &str,
        owner: &str,
    ) -> Option<Quantity> {
        let q = self.quantity(n, path, Scope::Params)?;
        if q.value < 0.0 {
            self.error(
                path,
                format!("{what} of `{owner}` is negative ({})", q.value),
                format!("a {what} is zero or positive"),
            );
            return None;
        }
        Some(q)
    }

    fn constraints(&mut self, spec: &Spec, bodies: &[BodyInfo]) -> Option<Vec<Constraint>> {
        let mut out = Vec::new();
        let mut ok = true;
        let mut names = HashSet::new();
        for (k, c) in spec.constraints.iter().enumerate() {
            let path = [f("constraints"), i(k)];
            let name = match c {
                spec::Constraint::RollingDisk { name, .. }
                | spec::Constraint::Holonomic { name, .. } => name,
            };
            if !names.insert(name.as_str()) {
                self.error(
                    &join(&path, &[f("name")]),
                    format!("constraint `{name}` is defined twice"),
                    "constraint names must be unique",
                );
            }
            let kind = match c {
                spec::Constraint::RollingDisk {
                    body,
                    radius,
                    axis,
                    center,
                    ..
                } => {
                    let b = self.body_ref(bodies, body, &join(&path, &[f("body")]), "disk");
                    if b == Some(0) {
                        self.error(
                            &join(&path, &[f("body")]),
                            "the ground cannot roll".into(),
                            "name the disk's body",
                        );
                    }
                    let r = self.quantity(radius, &join(&path, &[f("radius")]), Scope::Params);
                    if let Some(r) = &r
                        && r.value <= 0.0
                    {
                        self.error(
                            &join(&path, &[f("radius")]),
                            format!("radius of rolling disk `{name}` is {} m", r.value),
                            "a disk's radius is positive",
                        );
                    }
                    let a = self.axis(axis, &join(&path, &[f("axis")]), "disk axis");
                    let ctr = self.vec3(center, &join(&path, &[f("center")]), Scope::Params);
                    (|| {
                        Some(ConstraintKind::RollingDisk {
                            body: b.filter(|&b| b != 0)?,
                            radius: r.filter(|r| r.value > 0.0)?,
                            axis: a?,
                            center: ctr?,
                        })
                    })()
                }
                spec::Constraint::Holonomic { expr, .. } => {
                    let epath = join(&path, &[f("expr")]);
                    let q = self.quantity(&Num::Expr(expr.clone()), &epath, Scope::State);
                    if let Some(q) = &q {
                        let uses_q = q
                            .expr
                            .names()
                            .iter()
                            .any(|(n, _)| self.state_names.get(*n) == Some(&"coordinate"));
                        if !uses_q {
                            self.error(
                                &epath,
                                format!("constraint `{name}` does not depend on any coordinate"),
                                "a holonomic constraint restricts positions: write it in terms of coordinate names",
                            );
                        }
                        let uses_speed = q
                            .expr
                            .names()
                            .iter()
                            .find(|(n, _)| {
                                matches!(self.state_names.get(*n), Some(&"speed" | &"input"))
                            })
                            .map(|(n, _)| n.to_string());
                        if let Some(n) = uses_speed {
                            self.error(
                                &epath,
                                format!("holonomic constraint `{name}` uses `{n}`"),
                                "a holonomic constraint may use coordinates, parameters and `t` only",
                            );
                        }
                    }
                    q.map(ConstraintKind::Holonomic)
                }
            };
            match kind {
                Some(kind) => out.push(Constraint {
                    name: name.clone(),
                    kind,
                    span: self.span(&path),
                }),
                None => ok = false,
            }
        }
        ok.then_some(out)
    }

    /// A flexible-body output on body `b`, its problems reported at `path`.
    fn flex_output(
        &mut self,
        want: FlexOutput<'_>,
        b: usize,
        body: &BodyInfo,
        path: &[Seg<'static>],
    ) -> Option<OutputKind> {
        match flex_outputs::resolve(want, b, body) {
            Ok(kind) => Some(kind),
            Err(problems) => {
                for p in problems {
                    self.error(&join(path, &[f(p.field)]), p.message, p.help);
                }
                None
            }
        }
    }

    fn outputs(
        &mut self,
        spec: &Spec,
        bodies: &[BodyInfo],
        joints: &[JointInfo],
    ) -> Option<Vec<OutputKind>> {
        let mut out = Vec::new();
        let mut ok = true;
        for (k, o) in spec.outputs.iter().enumerate() {
            let path = [f("outputs"), i(k)];
            let kind = match o {
                spec::Output::Position { body, marker }
                | spec::Output::Velocity { body, marker } => {
                    let b = self.body_ref(bodies, body, &join(&path, &[f("body")]), "output");
                    let m = b.and_then(|b| {
                        let found = bodies[b].markers.iter().position(|x| &x.name == marker);
                        let failed = self
                            .failed_markers
                            .contains(&(body.clone(), marker.clone()));
                        if found.is_none() && !failed {
                            let names = bodies[b].markers.iter().map(|x| x.name.as_str());
                            self.error(
                                &join(&path, &[f("marker")]),
                                format!("body `{body}` has no marker `{marker}`"),
                                format!("its markers are {}", list_names(names)),
                            );
                        }
                        found
                    });
                    match (b, m, o) {
                        (Some(b), Some(m), spec::Output::Position { .. }) => {
                            Some(OutputKind::Position(b, m))
                        }
                        (Some(b), Some(m), _) => Some(OutputKind::Velocity(b, m)),
                        _ => None,
                    }
                }
                spec::Output::JointReaction { joint } => self
                    .joint_ref(joints, joint, &join(&path, &[f("joint")]))
                    .map(OutputKind::JointReaction),
                spec::Output::Energy => Some(OutputKind::Energy),
                spec::Output::Momentum => Some(OutputKind::Momentum),
                spec::Output::Deformation { name, body, x }
                | spec::Output::SectionForces { name, body, x } => {
                    let b = self.body_ref(bodies, body, &join(&path, &[f("body")]), "output");
                    let x = self.quantity(x, &join(&path, &[f("x")]), Scope::Params);
                    match (b, x) {
                        (Some(b), Some(x)) => {
                            let want = if matches!(o, spec::Output::Deformation { .. }) {
                                FlexOutput::Deformation(name, x.value)
                            } else {
                                FlexOutput::SectionForces(name, x.value)
                            };
                            self.flex_output(want, b, &bodies[b], &path)
                        }
                        _ => None,
                    }
                }
                spec::Output::NodePosition { body, node } => self
                    .body_ref(bodies, body, &join(&path, &[f("body")]), "output")
                    .and_then(|b| {
                        self.flex_output(FlexOutput::NodePosition(*node), b, &bodies[b], &path)
                    }),
                spec::Output::ElasticEnergy { body } => self
                    .body_ref(bodies, body, &join(&path, &[f("body")]), "output")
                    .and_then(|b| {
                        self.flex_output(FlexOutput::ElasticEnergy, b, &bodies[b], &path)
                    }),
            };
            match kind {
                Some(kind) => out.push(kind),
                None => ok = false,
            }
        }
        ok.then_some(out)
    }

    /// Warns about cut joints whose two frames do not meet at the initial state.
    fn check_closure(&mut self, sys: &System, poses: &[Pose<f64>]) {
        for (&j, gap) in sys.graph.cut_joints().iter().zip(closure_gaps(sys, poses)) {
            let joint = &sys.joints[j];
            if gap.position > CLOSURE_TOL || gap.angle > CLOSURE_TOL {
                self.warning(
                    &[f("joints"), i(j)],
                    format!(
                        "cut joint `{}` is open at the initial state: its frames are {:.3e} m apart and their axes {:.3e} rad out of line",
                        joint.name, gap.position, gap.angle
                    ),
                    "check the joint frames and the initial values of the loop's tree joints; simulation starts by assembling the loop",
                );
            }
        }
    }
}

fn default_coordinate_names(joint: &str, kind: &spec::JointKind) -> Vec<String> {
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

/// Grübler–Kutzbach count, planar (λ = 3) if every joint keeps the motion
/// in planes normal to one direction, else spatial (λ = 6).
pub(crate) fn grubler(sys: &System, poses: &[Pose<f64>]) -> Grubler {
    let planar_normal = planar_normal(sys, poses);
    let lambda: i64 = if planar_normal.is_some() { 3 } else { 6 };
    let n = (sys.bodies.len() - 1) as i64;
    let mut dof = lambda * n;
    for j in &sys.joints {
        let f = match (&j.motion, planar_normal.is_some()) {
            (Motion::Locked | Motion::Prescribed(_), _) => 0,
            (_, true) => match j.kind {
                JointType::Planar => 3,
                JointType::Fixed => 0,
                _ => 1,
            },
            (_, false) => j.kind.nu() as i64,
        };
        dof -= lambda - f;
    }
    for c in &sys.constraints {
        dof -= c.equations().0 as i64;
    }
    // Every elastic coordinate of a flexible body is a freedom of its own.
    let elastic: i64 = sys
        .bodies
        .iter()
        .filter_map(|b| b.flexible.as_deref())
        .map(|f| f.count() as i64)
        .sum();
    Grubler {
        dof: dof + elastic,
        elastic,
        planar: planar_normal.is_some(),
    }
}

/// The common normal of a planar system, if it is one.
fn planar_normal(sys: &System, poses: &[Pose<f64>]) -> Option<Vector3<f64>> {
    if sys
        .constraints
        .iter()
        .any(|c| matches!(c.kind, ConstraintKind::RollingDisk { .. }))
    {
        return None;
    }
    let mut normal: Option<Vector3<f64>> = None;
    let mut in_plane: Vec<Vector3<f64>> = Vec::new();
    for j in &sys.joints {
        let frame = Matrix3::from(poses[j.parent].e) * j.parent_frame.matrix;
        let n = match &j.kind {
            JointType::Revolute(a) => frame * a.unit,
            JointType::Planar => frame * Vector3::z(),
            JointType::Prismatic(a) => {
                in_plane.push(frame * a.unit);
                continue;
            }
            JointType::Fixed => continue,
            _ => return None,
        };
        match normal {
            None => normal = Some(n),
            Some(m) if m.cross(&n).norm() < 1e-9 => {}
            Some(_) => return None,
        }
    }
    let n = normal?;
    in_plane.iter().all(|a| a.dot(&n).abs() < 1e-9).then_some(n)
}

impl Ctx<'_> {
    /// The ANCF chains: names, element types, geometry, section and
    /// material, supports, end force; every problem reported.
    fn cables(
        &mut self,
        spec: &Spec,
        gravity: Option<&Vec3Q>,
        bodies: &[BodyInfo],
    ) -> Option<Vec<CableInfo>> {
        use crate::system::{CableSection, ChainInfo, Support};
        let g = gravity.map_or([0.0; 3], |g| [g[0].value, g[1].value, g[2].value]);
        let mut out = Vec::new();
        let mut ok = true;
        let mut names = HashSet::new();
        for (k, c) in spec.cables.iter().enumerate() {
            let path = [f("cables"), i(k)];
            let at = |field: &'static str| join(&path, &[f(field)]);
            let name = c.name.as_str();
            if !is_ident(name) {
                self.error(
                    &at("name"),
                    format!("cable name `{name}` is not an identifier"),
                    "use letters, digits and `_`",
                );
                ok = false;
            } else if !names.insert(name) {
                self.error(
                    &at("name"),
                    format!("cable `{name}` is defined twice"),
                    "give every cable its own name",
                );
                ok = false;
            }
            let kernel = c.element.name();
            if c.elements == 0 {
                self.error(
                    &at("elements"),
                    format!("cable `{name}` has no elements"),
                    "a cable needs at least one element (the tests converge from 4 to 64)",
                );
                ok = false;
            }
            let from = self.vec3(&c.from, &at("from"), Scope::Params);
            let to = self.vec3(&c.to, &at("to"), Scope::Params);
            let end_force = self.vec3(&c.end_force, &at("end_force"), Scope::Params);
            let distributed =
                self.vec3(&c.distributed_load, &at("distributed_load"), Scope::Params);
            let positive = |cx: &mut Self, n: &Num, field: &'static str, what: &str, unit: &str| {
                let q = cx.quantity(n, &at(field), Scope::Params)?;
                if q.value.is_nan() || q.value <= 0.0 {
                    cx.error(
                        &at(field),
                        format!("{what} `{field}` of cable `{name}` is {} {unit}", q.value),
                        format!("a cable needs a positive {what} ({unit})"),
                    );
                    return None;
                }
                Some(q.value)
            };
            let young = positive(self, &c.young, "young", "Young's modulus", "Pa");
            let density = positive(self, &c.density, "density", "density", "kg/m³");
            let width = c
                .width
                .as_ref()
                .map(|n| positive(self, n, "width", "section width", "m"));
            let height = c
                .height
                .as_ref()
                .map(|n| positive(self, n, "height", "section height", "m"));
            let area = c
                .area
                .as_ref()
                .map(|n| positive(self, n, "area", "section area", "m²"));
            let second = c
                .second_moment
                .as_ref()
                .map(|n| positive(self, n, "second_moment", "second moment of area", "m⁴"));
            let rect = match (width, height) {
                (Some(Some(b)), Some(Some(h))) => Some((b, h)),
                (Some(_), None) | (None, Some(_)) => {
                    let missing = if c.width.is_none() { "width" } else { "height" };
                    self.error(
                        &path,
                        format!("cable `{name}` gives one side of a rectangular section but not `{missing}`"),
                        "give both `width` and `height`, or `area` and `second_moment`",
                    );
                    None
                }
                _ => None,
            };
            let area = match area {
                Some(a) => a,
                None => rect.map(|(b, h)| b * h),
            };
            let second = match second {
                Some(s) => s,
                None => rect.map(|(b, h)| b * h * h * h / 12.0),
            };
            if c.area.is_none() && c.width.is_none() {
                self.error(
                    &path,
                    format!("cable `{name}` has no section area"),
                    "give `area` and `second_moment`, or `width` and `height` of a rectangular section",
                );
            }
            if c.second_moment.is_none() && c.width.is_none() {
                self.error(
                    &path,
                    format!("cable `{name}` has no second moment of area"),
                    "give `second_moment` (m⁴), or `width` and `height` of a rectangular section",
                );
            }
            if c.element == crate::ancf::Kind::Beam2D && rect.is_none() && c.width.is_none() {
                self.error(
                    &at("element"),
                    format!("`Beam2D` cable `{name}` needs a rectangular section"),
                    "the continuum beam integrates over the section: give `width` and `height`",
                );
            }
            let poisson = self.quantity(&c.poisson, &at("poisson"), Scope::Params);
            if let Some(p) = &poisson
                && !(0.0..0.5).contains(&p.value)
            {
                self.error(
                    &at("poisson"),
                    format!("Poisson's ratio of cable `{name}` is {}", p.value),
                    "it lies in [0, 0.5)",
                );
            }
            let da = self.nonnegative(
                &c.damping_axial,
                &at("damping_axial"),
                "axial damping",
                name,
            );
            let db = self.nonnegative(
                &c.damping_bending,
                &at("damping_bending"),
                "bending damping",
                name,
            );
            let mu = self.nonnegative(&c.retardation, &at("retardation"), "retardation time", name);
            let end_mass = self.nonnegative(&c.end_mass, &at("end_mass"), "end mass", name);
            let planar = c.element != crate::ancf::Kind::Cable3D;
            if let (Some(a), Some(b)) = (&from, &to) {
                let (a, b) = (values(a), values(b));
                if (a - b).norm() <= 0.0 {
                    self.error(
                        &at("to"),
                        format!("the ends of cable `{name}` coincide"),
                        "`from` and `to` are the two ends of the straight reference line",
                    );
                    ok = false;
                }
                if planar && (a.z != 0.0 || b.z != 0.0) {
                    self.error(
                        &at(if a.z != 0.0 { "from" } else { "to" }),
                        format!("`{kernel}` cable `{name}` leaves the plane z = 0"),
                        "planar elements move in the x–y plane: give z = 0, or use `Cable3D`",
                    );
                    ok = false;
                }
            }
            if let Some(d) = &distributed {
                let d = values(d);
                if !(d.x.is_finite() && d.y.is_finite() && d.z.is_finite()) {
                    self.error(
                        &at("distributed_load"),
                        format!("the distributed load of cable `{name}` is not finite"),
                        "give a load per unit length in N/m",
                    );
                    ok = false;
                } else if planar && d.z != 0.0 {
                    self.error(
                        &at("distributed_load"),
                        format!(
                            "`{kernel}` cable `{name}` has a distributed load out of its plane (z = {})",
                            d.z
                        ),
                        "planar elements carry loads in the x–y plane: give z = 0, or use `Cable3D`",
                    );
                    ok = false;
                }
            }
            let mut node_forces = Vec::new();
            for (j, nf) in c.node_forces.iter().enumerate() {
                let here = |field: &'static str| join(&path, &[f("node_forces"), i(j), f(field)]);
                if nf.node > c.elements {
                    self.error(
                        &here("node"),
                        format!(
                            "cable `{name}` has no node {} (its nodes are 0 to {})",
                            nf.node, c.elements
                        ),
                        "node j lies at from + j/elements · (to − from)",
                    );
                    ok = false;
                }
                let Some(force) = self.vec3(&nf.force, &here("force"), Scope::Params) else {
                    ok = false;
                    continue;
                };
                let fv = values(&force);
                if !(fv.x.is_finite() && fv.y.is_finite() && fv.z.is_finite()) {
                    self.error(
                        &here("force"),
                        format!("a node force of cable `{name}` is not finite"),
                        "give a force in N",
                    );
                    ok = false;
                } else if planar && fv.z != 0.0 {
                    self.error(
                        &here("force"),
                        format!(
                            "`{kernel}` cable `{name}` has a node force out of its plane (z = {})",
                            fv.z
                        ),
                        "planar elements carry loads in the x–y plane: give z = 0, or use `Cable3D`",
                    );
                    ok = false;
                }
                node_forces.push((nf.node, [fv.x, fv.y, fv.z]));
            }
            if planar && g[2] != 0.0 {
                self.warning(
                    &[f("gravity")],
                    format!("gravity has a z component that planar cable `{name}` does not feel"),
                    "planar elements move in the x–y plane",
                );
            }
            if c.start.is_free() && c.end.is_free() {
                self.warning(
                    &at("start"),
                    format!("cable `{name}` is held at neither end"),
                    "it can move freely (dynamics); a static solve will refuse it",
                );
            }
            let start_at = c.start_at.as_ref().map(|m| {
                self.cable_mount(m, c.start, &at("start_at"), "start", name, planar, bodies)
            });
            let end_at = c
                .end_at
                .as_ref()
                .map(|m| self.cable_mount(m, c.end, &at("end_at"), "end", name, planar, bodies));
            let (start_at, end_at) = match (start_at, end_at) {
                (Some(None), _) | (_, Some(None)) => {
                    ok = false;
                    (None, None)
                }
                (a, b) => (a.flatten(), b.flatten()),
            };
            // An end held at a marker is free in the chain: the attachment
            // constraint holds it.
            let support = |e: spec::CableEnd, mounted: bool| match e {
                _ if mounted => Support::Free,
                spec::CableEnd::Free => Support::Free,
                spec::CableEnd::Pinned => Support::Pinned,
                spec::CableEnd::Clamped => Support::Clamped,
            };
            let (
                Some(from),
                Some(to),
                Some(end_force),
                Some(young),
                Some(density),
                Some(area),
                Some(second),
                Some(poisson),
                Some(da),
                Some(db),
                Some(mu),
                Some(end_mass),
                Some(distributed),
            ) = (
                from,
                to,
                end_force,
                young,
                density,
                area,
                second,
                poisson,
                da,
                db,
                mu,
                end_mass,
                distributed,
            )
            else {
                ok = false;
                continue;
            };
            let v = |q: &Vec3Q| [q[0].value, q[1].value, q[2].value];
            let (b, h) = rect.unwrap_or((0.0, 0.0));
            out.push(CableInfo {
                name: name.to_string(),
                chain: ChainInfo {
                    element: c.element,
                    start: v(&from),
                    end: v(&to),
                    elements: c.elements,
                    section: CableSection {
                        e: young,
                        nu: poisson.value,
                        rho: density,
                        area,
                        inertia: second,
                        b,
                        h,
                        damping_axial: da.value,
                        damping_bending: db.value,
                        retardation: mu.value,
                    },
                    start_support: support(c.start, start_at.is_some()),
                    end_support: support(c.end, end_at.is_some()),
                    end_force: v(&end_force),
                    end_mass: end_mass.value,
                    gravity: g,
                },
                start_at,
                end_at,
                distributed_load: v(&distributed),
                node_forces,
            });
        }
        ok.then_some(out)
    }

    /// A cable end held at a marker of a rigid body: the body and marker
    /// exist, the body is rigid and not ground, the end is pinned or
    /// clamped, a clamped end gives its `axis` (in the cable's plane for
    /// planar elements), a pinned one none. `None` inside: an error was
    /// reported.
    #[allow(clippy::too_many_arguments)]
    fn cable_mount(
        &mut self,
        m: &spec::CableMount,
        how: spec::CableEnd,
        path: &[Seg<'static>],
        end: &str,
        cable: &str,
        planar: bool,
        bodies: &[BodyInfo],
    ) -> Option<CableMountInfo> {
        let span = self.span(path);
        let body = self.body_ref(bodies, &m.body, &join(path, &[f("body")]), "mount");
        let mut ok = body.is_some();
        if let Some(b) = body {
            if b == 0 {
                self.error(
                    &join(path, &[f("body")]),
                    format!("the {end} of cable `{cable}` is held at a marker of `ground`"),
                    format!("hold it to ground with `{end}: Pinned` or `{end}: Clamped` alone (at the `from`/`to` point), or name a rigid body"),
                );
                ok = false;
            } else if bodies[b].flexible.is_some() {
                self.error(
                    &join(path, &[f("body")]),
                    format!(
                        "the {end} of cable `{cable}` is held at flexible body `{}`",
                        m.body
                    ),
                    "cables attach to markers of rigid bodies only",
                );
                ok = false;
            }
        }
        let marker = body.filter(|&b| b != 0).and_then(|b| {
            let found = bodies[b].markers.iter().position(|x| x.name == m.marker);
            if found.is_none() {
                let names = bodies[b].markers.iter().map(|x| x.name.as_str());
                let help = match did_you_mean(&m.marker, names.clone()) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None => format!("its markers are {}", list_names(names)),
                };
                self.error(
                    &join(path, &[f("marker")]),
                    format!("body `{}` has no marker `{}`", m.body, m.marker),
                    help,
                );
            }
            found
        });
        ok &= marker.is_some();
        let axis = match (how, &m.axis) {
            (spec::CableEnd::Free, _) => {
                self.error(
                    path,
                    format!("the {end} of cable `{cable}` is `Free` but held at marker `{}.{}`", m.body, m.marker),
                    format!("say how the marker holds it: `{end}: Pinned` (position) or `{end}: Clamped` (position and direction, with `axis`)"),
                );
                ok = false;
                None
            }
            (spec::CableEnd::Clamped, None) => {
                self.error(
                    path,
                    format!(
                        "the {end} of cable `{cable}` is clamped at marker `{}.{}` without an `axis`",
                        m.body, m.marker
                    ),
                    "give `axis: (1, 0, 0)`: the direction, in the marker's axes, along which the cable leaves the marker",
                );
                ok = false;
                None
            }
            (spec::CableEnd::Pinned, Some(_)) => {
                self.error(
                    &join(path, &[f("axis")]),
                    format!("the {end} of cable `{cable}` is pinned: it turns freely, so `axis` means nothing"),
                    format!("remove `axis`, or clamp the end (`{end}: Clamped`)"),
                );
                ok = false;
                None
            }
            (spec::CableEnd::Pinned, None) => None,
            (spec::CableEnd::Clamped, Some(a)) => {
                let ap = join(path, &[f("axis")]);
                match self.axis(a, &ap, "the clamp's axis") {
                    Some(a) if planar && a.unit.z.abs() > 1e-12 => {
                        self.error(
                            &ap,
                            format!("the clamp's axis of planar cable `{cable}` leaves the x–y plane"),
                            "give an axis with z = 0 (in the marker's axes; planar models turn about z)",
                        );
                        ok = false;
                        None
                    }
                    Some(a) => Some([a.unit.x, a.unit.y, a.unit.z]),
                    None => {
                        ok = false;
                        None
                    }
                }
            }
        };
        let (Some(body), Some(marker), true) = (body, marker, ok) else {
            return None;
        };
        Some(CableMountInfo {
            body,
            marker,
            axis,
            span,
        })
    }
}
