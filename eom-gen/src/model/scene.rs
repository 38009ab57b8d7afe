//! Scenes: what one simulation needs from a model.
//!
//! A scene file names a model and says which outputs to generate, which
//! joints to hold still (and where), and which parameters to inline
//! (`fixed`) or keep as runtime fields (`tunable`). [`check`] validates the
//! model, then the scene against it — every problem of the scene at once,
//! each at its `file:line:col` in the scene file — and returns the model's
//! [`System`] with the scene applied, so formulation, emission, the compiled
//! and interpreted runs, the [`Builder`](crate::Builder) and `#[multibody]`
//! all see only what the scene asks for. The format is in
//! `docs/model-format.md` ("Scenes").

use super::Checked;
use super::flex_outputs::FlexOutput;
use super::locate::{self, Node, Seg, string_contents_start};
use super::read::Format;
use super::spec::{Num, Output};
use crate::diag::{Diagnostic, Report, Source, Span, did_you_mean, list_names};
use crate::expr::Ast;
pub use crate::functions::Function;
use crate::functions::{FunctionSet, When};
use crate::graph::JointId;
use crate::system::{
    ConstraintKind, ForceElement, InitialValue, JointType, Motion, OutputKind, Parameter, Quantity,
    System,
};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashSet};
use std::path::{Component, Path, PathBuf};

/// A scene file, as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Scene", deny_unknown_fields)]
pub struct SceneSpec {
    /// The model file (`.ron` or `.urdf`), relative to the scene file.
    pub model: String,
    /// Name of the generated model (default: the model's name).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Free text: what the scene is for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub doc: Option<String>,
    /// The outputs to generate, replacing the model's (absent: the model's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outputs: Option<Vec<Output>>,
    /// Joints held still.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lock: Vec<Lock>,
    /// Parameters inlined as constants (overrides the model's `tunable`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fixed: Vec<String>,
    /// Parameters kept as runtime fields (overrides the model's `tunable`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tunable: Vec<String>,
    /// The functions generated symbolically (absent: all of them); the
    /// others are computed from these (see [`Function`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub functions: Option<Vec<Function>>,
    /// Parameter values replacing the model's before it is checked, as
    /// `eom-gen simulate --param NAME=VALUE` does (a fixed parameter is
    /// inlined with the value, a tunable one defaults to it).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, f64>,
    /// Initial positions by coordinate name, replacing the model's `q0`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub q0: BTreeMap<String, f64>,
    /// Initial speeds by speed name, replacing the model's `u0`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub u0: BTreeMap<String, f64>,
    /// Actuator inputs driven by a number or an expression of parameters,
    /// `pi`, `t`, coordinates and speeds (see
    /// [`drive_inputs`](super::drive_inputs)); they leave the model's
    /// runtime inputs.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub inputs: BTreeMap<String, Num>,
}

impl SceneSpec {
    /// What to formulate for this scene: the listed functions, and those
    /// that cannot be derived (see [`crate::functions`]); without a list,
    /// every function.
    pub fn request(&self) -> FunctionSet {
        match &self.functions {
            None => FunctionSet::all_requested(),
            Some(list) => list.iter().copied().collect::<FunctionSet>().derivable(),
        }
    }
}

/// A joint held at fixed coordinates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lock {
    /// The joint.
    pub joint: String,
    /// Its coordinates, one per coordinate (parameters allowed);
    /// default: the joint's `q0`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<Vec<Num>>,
}

/// The scene part of a [`Checked`] model: the scene file and its warnings.
#[derive(Clone, Debug)]
pub struct SceneInfo {
    /// The scene file.
    pub source: Source,
    /// The parsed scene.
    pub spec: SceneSpec,
    /// Warnings found in the scene file (never errors).
    pub warnings: Vec<Diagnostic>,
    /// The model file as read (the scene's directory joined with `model`).
    pub model_path: PathBuf,
}

/// True if `path`/`text` is a scene rather than a model (see
/// [`Format::of`]): the file name ends in `.scene.ron`, or the text's
/// top-level value is `Scene(…)`.
pub fn is_scene(path: &str, text: &str) -> bool {
    Format::of(path, text) == Format::Scene
}

/// Parses scene text: syntax and type errors only (the first one), or
/// every unknown field at once.
pub fn parse(src: &Source) -> Result<SceneSpec, Report> {
    super::fields::read(src)
}

/// A located error at the scene's `model` field.
pub(crate) fn model_error(src: &Source, message: String, help: &str) -> Report {
    let span =
        locate::parse(&src.text).map_or(Span::default(), |r| r.span_of(&[Seg::Field("model")]));
    Report {
        source: src.clone(),
        diagnostics: vec![Diagnostic::error(span, message).with_help(help)],
    }
}

/// Validates a parsed scene against its checked model and applies it
/// (locks, parameters, outputs, functions); `model_path` is where the model
/// was read from.
pub(crate) fn apply(
    src: &Source,
    spec: SceneSpec,
    model_path: PathBuf,
    mut checked: Checked,
) -> Result<Checked, Report> {
    let tree = locate::parse(&src.text);
    let mut cx = Ctx {
        root: tree.as_ref(),
        src,
        diags: Vec::new(),
    };
    cx.apply(&spec, &mut checked);
    let mut diags = cx.diags;
    diags.sort_by_key(|d| (d.span.map(|s| s.start), d.severity));
    if diags.iter().any(Diagnostic::is_error) {
        return Err(Report {
            source: src.clone(),
            diagnostics: diags,
        });
    }
    checked.scene = Some(SceneInfo {
        source: src.clone(),
        spec,
        warnings: diags,
        model_path,
    });
    Ok(checked)
}

/// The scene's `parameters` against the model's (`model` the model's RON
/// text): every unknown name, located at the scene's `parameters` field,
/// and every non-finite value.
pub(crate) fn check_parameter_values(
    src: &Source,
    scene: &SceneSpec,
    model: &Source,
) -> Result<(), Report> {
    if scene.parameters.is_empty() {
        return Ok(());
    }
    // A model that does not parse is reported by its own check.
    let Ok(spec) = super::parse(model) else {
        return Ok(());
    };
    let tree = locate::parse(&src.text);
    let mut cx = Ctx {
        root: tree.as_ref(),
        src,
        diags: Vec::new(),
    };
    let names = || spec.parameters.iter().map(|p| p.name.as_str());
    for (name, value) in &scene.parameters {
        if !names().any(|n| n == name) {
            let help = suggest(name, names(), "the model's parameters");
            cx.error(
                &[f("parameters")],
                format!("unknown parameter `{name}`"),
                help,
            );
        } else if !value.is_finite() {
            cx.error(
                &[f("parameters")],
                format!("parameter `{name}` is set to {value}"),
                "give a finite number",
            );
        }
    }
    if cx.diags.is_empty() {
        Ok(())
    } else {
        Err(Report {
            source: src.clone(),
            diagnostics: cx.diags,
        })
    }
}

/// The model's path as seen from the working directory: the scene's
/// directory joined with `model`, with `.` and `dir/..` removed.
pub fn model_path(scene: &str, model: &str) -> PathBuf {
    let joined = Path::new(scene)
        .parent()
        .unwrap_or(Path::new(""))
        .join(model);
    let mut out: Vec<Component<'_>> = Vec::new();
    for c in joined.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if matches!(out.last(), Some(Component::Normal(_))) => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out.iter().collect()
}

struct Ctx<'a> {
    root: Option<&'a Node>,
    src: &'a Source,
    diags: Vec<Diagnostic>,
}

type Path0 = Vec<Seg<'static>>;

fn f(name: &'static str) -> Seg<'static> {
    Seg::Field(name)
}

fn at(path: &[Seg<'static>], more: &[Seg<'static>]) -> Path0 {
    path.iter().chain(more).copied().collect()
}

fn suggest<'n>(name: &str, names: impl Iterator<Item = &'n str> + Clone, what: &str) -> String {
    match did_you_mean(name, names.clone()) {
        Some(best) => format!("did you mean `{best}`?"),
        None => format!("{what} are {}", list_names(names)),
    }
}

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

    /// Validates `scene` against the checked model and applies it; on any
    /// error the model is left in an unspecified state.
    fn apply(&mut self, scene: &SceneSpec, checked: &mut Checked) {
        let sys = &mut checked.system;
        if let Some(name) = &scene.name {
            if super::validate::is_ident(name) {
                sys.name = name.clone();
                checked.spec.name = name.clone();
            } else {
                self.error(
                    &[f("name")],
                    format!("scene name `{name}` is not an identifier"),
                    "generated code is named after it: use letters, digits and `_`",
                );
            }
        }
        self.parameters(scene, sys);
        if let Some(outputs) = &scene.outputs
            && let Some(kinds) = self.outputs(outputs, sys)
        {
            sys.outputs = kinds;
            checked.spec.outputs = outputs.clone();
        }
        self.locks(scene, sys);
        self.initial(scene, sys);
        if let Some(list) = &scene.functions {
            self.functions(list);
        }
        for lock in &scene.lock {
            if let Some(j) = checked
                .spec
                .joints
                .iter_mut()
                .find(|j| j.name == lock.joint)
            {
                j.locked = true;
                if let Some(values) = &lock.at {
                    j.q0 = Some(values.clone());
                }
            }
        }
        for p in &mut checked.spec.parameters {
            if let Some(sp) = sys.parameters.iter().find(|x| x.name == p.name) {
                p.tunable = sp.tunable;
            }
        }
        let drives: Vec<(String, String)> = scene
            .inputs
            .iter()
            .map(|(name, value)| {
                let text = match value {
                    Num::Value(v) => format!("{v:?}"),
                    Num::Expr(e) => e.clone(),
                };
                (name.clone(), text)
            })
            .collect();
        if let Err(errors) = super::drive_inputs(checked, &drives) {
            for e in errors {
                self.error(&[f("inputs")], e.message, e.help);
            }
        }
    }

    /// `q0` and `u0`: initial values by coordinate and speed name, of the
    /// joints that keep their coordinates (not locked or prescribed).
    fn initial(&mut self, scene: &SceneSpec, sys: &mut System) {
        for (field, map, speeds) in [("q0", &scene.q0, false), ("u0", &scene.u0, true)] {
            for (name, &value) in map {
                let path = [f(field)];
                let what = if speeds { "speed" } else { "coordinate" };
                if !value.is_finite() {
                    self.error(
                        &path,
                        format!("{field} of `{name}` is {value}"),
                        "give a finite number",
                    );
                    continue;
                }
                match sys.set_initial_value(name, speeds, value) {
                    InitialValue::Set => {}
                    InitialValue::NotFree => self.error(
                        &path,
                        format!("{what} `{name}` belongs to a locked, prescribed or cut joint"),
                        "only the coordinates and speeds of the generated model have initial values",
                    ),
                    InitialValue::Unknown => {
                        let names: Vec<&str> = if speeds {
                            sys.speed_names()
                        } else {
                            sys.coordinate_names()
                        };
                        let help = suggest(name, names.iter().copied(), &format!("the model's {what}s"));
                        self.error(&path, format!("unknown {what} `{name}` in `{field}`"), help);
                    }
                }
            }
        }
    }

    /// Checks that every function of the trait can be computed from the
    /// listed ones: inverse dynamics gives the mass matrix and the bias,
    /// and they give it.
    fn functions(&mut self, list: &[Function]) {
        for (k, func) in list.iter().enumerate() {
            if list[..k].contains(func) {
                self.warning(
                    &[f("functions"), Seg::Index(k)],
                    format!("function `{func:?}` is listed twice"),
                    "remove one of them",
                );
            }
        }
        for (k, func) in list.iter().enumerate() {
            if !matches!(func.entry().when, When::Requested | When::Asked) {
                let choices: Vec<String> =
                    Function::selectable().map(|f| format!("`{f:?}`")).collect();
                self.error(
                    &[f("functions"), Seg::Index(k)],
                    format!("function `{func:?}` is not chosen by a scene: it is generated whenever the model needs it"),
                    format!("list only {}", choices.join(", ")),
                );
            }
        }
        let has = |f: Function| list.contains(&f);
        if has(Function::InverseDynamics) {
            return;
        }
        let missing: Vec<&str> = [
            (Function::MassMatrix, "`MassMatrix`"),
            (Function::Bias, "`Bias`"),
        ]
        .into_iter()
        .filter(|(f, _)| !has(*f))
        .map(|(_, n)| n)
        .collect();
        if missing.is_empty() {
            return;
        }
        let what = if missing.len() == 2 {
            "the mass matrix and the bias are"
        } else if !has(Function::MassMatrix) {
            "the mass matrix is"
        } else {
            "the bias is"
        };
        self.error(
            &[f("functions")],
            format!(
                "{what} left out, and so is `InverseDynamics`, from which {} would be derived",
                if missing.len() == 2 { "they" } else { "it" }
            ),
            format!(
                "add `InverseDynamics` (then the mass matrix and the bias can be left out), or add {} (then inverse dynamics is `M u̇ + b`)",
                missing.join(" and ")
            ),
        );
    }

    fn parameters(&mut self, scene: &SceneSpec, sys: &mut System) {
        let mut seen: HashSet<&str> = HashSet::new();
        let lists = [
            (&scene.fixed, "fixed", false),
            (&scene.tunable, "tunable", true),
        ];
        for (list, field, tunable) in lists {
            for (k, name) in list.iter().enumerate() {
                let path = [f(field), Seg::Index(k)];
                if !seen.insert(name) {
                    let both = scene.fixed.contains(name) && scene.tunable.contains(name);
                    self.error(
                        &path,
                        if both {
                            format!("parameter `{name}` is both fixed and tunable")
                        } else {
                            format!("parameter `{name}` is listed twice")
                        },
                        if both {
                            "a parameter is either inlined (`fixed`) or a runtime field (`tunable`): remove it from one list"
                        } else {
                            "remove one of them"
                        },
                    );
                    continue;
                }
                let Some(p) = sys.parameters.iter_mut().find(|p| p.name == *name) else {
                    let names = sys.parameters.iter().map(|p| p.name.as_str());
                    let help = suggest(name, names, "the model's parameters");
                    self.error(&path, format!("unknown parameter `{name}`"), help);
                    continue;
                };
                if tunable && !p.tunable && !matches!(p.value.expr, Ast::Num(_)) {
                    let message = format!(
                        "parameter `{name}` is given by an expression in the model and becomes tunable"
                    );
                    self.warning(
                        &path,
                        message,
                        "its default is the expression's value; at run time it is set directly",
                    );
                }
                p.tunable = tunable;
            }
        }
    }

    fn outputs(&mut self, outputs: &[Output], sys: &System) -> Option<Vec<OutputKind>> {
        let mut kinds = Vec::new();
        let mut ok = true;
        for (k, o) in outputs.iter().enumerate() {
            let path = [f("outputs"), Seg::Index(k)];
            let kind = match o {
                Output::Position { body, marker } | Output::Velocity { body, marker } => {
                    self.marker(sys, body, marker, &path).map(|(b, m)| match o {
                        Output::Position { .. } => OutputKind::Position(b, m),
                        _ => OutputKind::Velocity(b, m),
                    })
                }
                Output::JointReaction { joint } => self
                    .joint(sys, joint, &at(&path, &[f("joint")]))
                    .map(OutputKind::JointReaction),
                Output::Energy => Some(OutputKind::Energy),
                Output::Momentum => Some(OutputKind::Momentum),
                Output::Deformation { name, body, x } | Output::SectionForces { name, body, x } => {
                    let b = self.output_body(sys, body, &path);
                    let x = self.quantity(x, &at(&path, &[f("x")]), sys);
                    match (b, x) {
                        (Some(b), Some(x)) => {
                            let want = if matches!(o, Output::Deformation { .. }) {
                                FlexOutput::Deformation(name, x.value)
                            } else {
                                FlexOutput::SectionForces(name, x.value)
                            };
                            self.flex_output(want, b, sys, &path)
                        }
                        _ => None,
                    }
                }
                Output::NodePosition { body, node } => self
                    .output_body(sys, body, &path)
                    .and_then(|b| self.flex_output(FlexOutput::NodePosition(*node), b, sys, &path)),
                Output::ElasticEnergy { body } => self
                    .output_body(sys, body, &path)
                    .and_then(|b| self.flex_output(FlexOutput::ElasticEnergy, b, sys, &path)),
            };
            match kind {
                Some(kind) if kinds.contains(&kind) => self.warning(
                    &path,
                    "this output is requested twice".into(),
                    "remove one of them",
                ),
                Some(kind) => kinds.push(kind),
                None => ok = false,
            }
        }
        ok.then_some(kinds)
    }

    /// The body an output names, or an error at its `body`.
    fn output_body(&mut self, sys: &System, body: &str, path: &[Seg<'static>]) -> Option<usize> {
        let found = sys.body_id(body);
        if found.is_none() {
            let names = sys.bodies.iter().map(|b| b.name.as_str());
            let help = suggest(body, names, "bodies");
            self.error(
                &at(path, &[f("body")]),
                format!("unknown output body `{body}`"),
                help,
            );
        }
        found
    }

    /// A flexible-body output on body `b`, its problems reported at `path`.
    fn flex_output(
        &mut self,
        want: FlexOutput<'_>,
        b: usize,
        sys: &System,
        path: &[Seg<'static>],
    ) -> Option<OutputKind> {
        match super::flex_outputs::resolve(want, b, &sys.bodies[b]) {
            Ok(kind) => Some(kind),
            Err(problems) => {
                for p in problems {
                    self.error(&at(path, &[f(p.field)]), p.message, p.help);
                }
                None
            }
        }
    }

    fn marker(
        &mut self,
        sys: &System,
        body: &str,
        marker: &str,
        path: &[Seg<'static>],
    ) -> Option<(usize, usize)> {
        let Some(b) = sys.body_id(body) else {
            let names = sys.bodies.iter().map(|b| b.name.as_str());
            let help = suggest(body, names, "bodies");
            self.error(
                &at(path, &[f("body")]),
                format!("unknown output body `{body}`"),
                help,
            );
            return None;
        };
        let markers = &sys.bodies[b].markers;
        match markers.iter().position(|m| m.name == marker) {
            Some(m) => Some((b, m)),
            None => {
                let names = markers.iter().map(|m| m.name.as_str());
                let help = match did_you_mean(marker, names.clone()) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None if markers.is_empty() => format!(
                        "body `{body}` has no markers: add `markers: [(name: \"{marker}\", position: (x, y, z))]` to it in the model"
                    ),
                    None => format!("its markers are {}", list_names(names)),
                };
                self.error(
                    &at(path, &[f("marker")]),
                    format!("body `{body}` has no marker `{marker}`"),
                    help,
                );
                None
            }
        }
    }

    fn joint(&mut self, sys: &System, name: &str, path: &[Seg<'static>]) -> Option<JointId> {
        let found = sys.joint_id(name);
        if found.is_none() {
            let names = sys.joints.iter().map(|j| j.name.as_str());
            let help = suggest(name, names, "joints");
            self.error(path, format!("unknown joint `{name}`"), help);
        }
        found
    }

    fn locks(&mut self, scene: &SceneSpec, sys: &mut System) {
        let mut seen: HashSet<&str> = HashSet::new();
        let mut locked: Vec<JointId> = Vec::new();
        for (k, lock) in scene.lock.iter().enumerate() {
            let path = [f("lock"), Seg::Index(k)];
            let jpath = at(&path, &[f("joint")]);
            let Some(j) = self.joint(sys, &lock.joint, &jpath) else {
                continue;
            };
            if !seen.insert(&lock.joint) {
                self.error(
                    &jpath,
                    format!("joint `{}` is locked twice", lock.joint),
                    "remove one of the two entries",
                );
                continue;
            }
            let joint = &sys.joints[j];
            let problem = match joint.motion {
                Motion::Cut => Some((
                    "closes a loop and is cut, so it has no coordinates to lock",
                    "lock a tree joint of the loop instead, or mark another joint `cut: true` in the model",
                )),
                Motion::Prescribed(_) => Some((
                    "has prescribed motion in the model",
                    "remove `prescribed` from the model, or leave the joint out of `lock`",
                )),
                _ => None,
            };
            if let Some((what, help)) = problem {
                self.error(&jpath, format!("joint `{}` {what}", lock.joint), help);
                continue;
            }
            if joint.kind.nq() == 0 {
                self.warning(
                    &jpath,
                    format!("joint `{}` is fixed: there is nothing to lock", lock.joint),
                    "remove it from `lock`",
                );
                continue;
            }
            if let Some(values) = &lock.at
                && let Some(q0) = self.values(values, &at(&path, &[f("at")]), j, sys)
            {
                sys.joints[j].q0 = q0;
            }
            locked.push(j);
        }
        for &j in &locked {
            self.uses_of_locked(scene, sys, j);
        }
        for &j in &locked {
            sys.joints[j].motion = Motion::Locked;
        }
        renumber(sys);
        let poses = crate::mech::initial::initial_poses(sys);
        sys.grubler = super::validate::grubler(sys, &poses);
    }

    /// The `at` values of a lock: one per coordinate, parameters only,
    /// unit quaternions for spherical and free joints.
    fn values(
        &mut self,
        values: &[Num],
        path: &[Seg<'static>],
        j: JointId,
        sys: &System,
    ) -> Option<Vec<Quantity>> {
        let joint = &sys.joints[j];
        let nq = joint.kind.nq();
        if values.len() != nq {
            self.error(
                path,
                format!(
                    "joint `{}` has {nq} coordinate(s) but `at` has {} value(s)",
                    joint.name,
                    values.len()
                ),
                format!(
                    "give one value per coordinate: {}",
                    list_names(joint.coordinate_names.iter().map(String::as_str))
                ),
            );
            return None;
        }
        let mut out = Vec::new();
        for (k, v) in values.iter().enumerate() {
            out.push(self.quantity(v, &at(path, &[Seg::Index(k)]), sys));
        }
        let out: Vec<Quantity> = out.into_iter().collect::<Option<_>>()?;
        let quaternion_at = match joint.kind {
            JointType::Spherical => Some(0),
            JointType::Free => Some(3),
            _ => None,
        };
        if let Some(k) = quaternion_at {
            let norm = out[k..k + 4]
                .iter()
                .map(|q| q.value * q.value)
                .sum::<f64>()
                .sqrt();
            if (norm - 1.0).abs() > 1e-9 {
                self.error(
                    &at(path, &[Seg::Index(k)]),
                    format!(
                        "quaternion of locked joint `{}` has norm {norm:.12}, not 1",
                        joint.name
                    ),
                    "write a unit quaternion (w, x, y, z), e.g. (1, 0, 0, 0)",
                );
                return None;
            }
        }
        Some(out)
    }

    /// A number or expression over the model's parameters.
    fn quantity(&mut self, num: &Num, path: &[Seg<'static>], sys: &System) -> Option<Quantity> {
        let span = self.span(path);
        let (expr, base) = match num {
            Num::Value(v) => (Ast::Num(*v), span.start),
            Num::Expr(text) => {
                let base = string_contents_start(&self.src.text, span);
                match Ast::parse(text) {
                    Ok(ast) => (ast, base),
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
        let value = |n: &str| -> Option<f64> {
            sys.parameters
                .iter()
                .find(|p| p.name == n)
                .map(|p| p.value.value)
        };
        let mut ok = true;
        for (name, offset) in expr.names() {
            if name == "pi" || value(name).is_some() {
                continue;
            }
            ok = false;
            let names = sys.parameters.iter().map(|p: &Parameter| p.name.as_str());
            let help = match did_you_mean(name, names.clone()) {
                Some(best) => format!("did you mean `{best}`?"),
                None => format!(
                    "a locked position may use the model's parameters and `pi`; parameters: {}",
                    list_names(names)
                ),
            };
            let at = Span::new(base + offset, base + offset + name.len());
            self.diags.push(
                Diagnostic::error(at, format!("unknown name `{name}` in expression"))
                    .with_help(help),
            );
        }
        if !ok {
            return None;
        }
        match expr.eval(&value) {
            Ok(v) => Some(Quantity {
                expr,
                value: v,
                span,
            }),
            Err(_) => {
                self.error(
                    path,
                    "this value is not a finite number at the default parameters".into(),
                    "check for division by zero, `sqrt` or `ln` of a negative value",
                );
                None
            }
        }
    }

    /// Reports forces, constraints and outputs of the model that need the
    /// coordinates of joint `j`, which the scene locks.
    fn uses_of_locked(&mut self, scene: &SceneSpec, sys: &System, j: JointId) {
        let joint = &sys.joints[j];
        let k = scene
            .lock
            .iter()
            .position(|l| l.joint == joint.name)
            .unwrap_or(0);
        let path = [f("lock"), Seg::Index(k), f("joint")];
        let names: HashSet<&str> = joint
            .coordinate_names
            .iter()
            .chain(&joint.speed_names)
            .map(String::as_str)
            .collect();
        let mut users: Vec<String> = Vec::new();
        for force in &sys.forces {
            let acts_on = match &force.element {
                ForceElement::JointSpringDamper { joint, .. }
                | ForceElement::Actuator { joint, .. } => *joint == j,
                ForceElement::JointForce { joint, values } => {
                    *joint == j
                        || values
                            .iter()
                            .any(|v| v.expr.names().iter().any(|(n, _)| names.contains(n)))
                }
                ForceElement::SpringDamper { .. } => false,
            };
            if acts_on {
                users.push(format!("force `{}`", force.name));
            }
        }
        for c in &sys.constraints {
            if let ConstraintKind::Holonomic(q) = &c.kind
                && q.expr.names().iter().any(|(n, _)| names.contains(n))
            {
                users.push(format!("constraint `{}`", c.name));
            }
        }
        if !users.is_empty() {
            self.error(
                &path,
                format!(
                    "joint `{}` cannot be locked: the model's {} need(s) its coordinates",
                    joint.name,
                    users.join(", ")
                ),
                "a locked joint has no coordinates; lock another joint, or remove these from the model",
            );
        }
    }
}

/// Numbers the coordinates along the tree again after a change of motions.
fn renumber(sys: &mut System) {
    let (mut q, mut u) = (0, 0);
    for &j in sys.graph.tree_joints() {
        let joint = &mut sys.joints[j];
        joint.q_index = q;
        joint.u_index = u;
        if joint.motion == Motion::Free {
            q += joint.kind.nq();
            u += joint.kind.nu();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_paths_are_relative_to_the_scene() {
        assert_eq!(
            model_path("models/scenes/a.scene.ron", "../arm7.ron"),
            PathBuf::from("models/arm7.ron")
        );
        assert_eq!(model_path("a.scene.ron", "./m.ron"), PathBuf::from("m.ron"));
        assert_eq!(
            model_path("../x/a.scene.ron", "../../m.ron"),
            PathBuf::from("../../m.ron")
        );
    }

    #[test]
    fn scenes_are_recognised_by_name_or_content() {
        assert!(is_scene("a.scene.ron", ""));
        assert!(is_scene("a.ron", "// c\nScene(model: \"m.ron\")"));
        assert!(!is_scene("a.ron", "Model(name: \"m\")"));
    }
}
