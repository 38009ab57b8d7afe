//! URDF import: a URDF robot description → an eom model ([`Spec`]).
//!
//! The XML is read with `roxmltree`, which is small, has no dependencies,
//! and keeps the byte range of every element and attribute, so each problem
//! in a URDF is reported at its `file:line:col` exactly as for RON models.
//! (`urdf-rs` deserialises into plain structs and loses those positions.)
//!
//! The mapping (see `docs/model-format.md`, "URDF"):
//!
//! - each URDF link frame is the frame of an eom body; a joint's `origin`
//!   is the joint frame on the parent (`parent_frame`), the child frame is
//!   the child link frame (`child_frame` identity);
//! - `revolute` and `continuous` → `Revolute`, `prismatic` → `Prismatic`,
//!   `floating` → `Free`, `planar` → `Planar` (joint frames turned so that
//!   their z axis is the URDF `axis`, the plane normal), `fixed` → merged:
//!   links joined by fixed joints become one rigid body with the composite
//!   inertia, so the generated code does no work for them;
//! - the link that is never a child (the root) is welded to `ground`: it and
//!   the links fixed to it are part of the ground. A link named `world` is
//!   the ground itself, so `world` → `floating` → `base` is a free base,
//!   and so is a `floating` joint without `<parent>`;
//! - `inertial`: mass, centre of mass from `origin xyz`, the tensor turned
//!   into link axes (`R I Rᵀ`) when the `origin rpy` is not zero;
//! - `mimic` → a holonomic constraint `q - multiplier·q_other - offset = 0`;
//! - `dynamics damping` → a `JointSpringDamper` with zero stiffness;
//!   Coulomb `friction` has no place in the model format and is listed in
//!   the notes (and in the header comment of the RON text); the `lower`
//!   and `upper` `limit`s of revolute and prismatic joints become
//!   `JointLimit` contacts (plastic stops, `e = 0`; not when `q = 0` lies
//!   outside them), unless `Options::joint_limits` is off
//!   (`--no-urdf-limits`); other limits and `effort`, `velocity` are
//!   listed in the notes;
//! - gravity is `(0, 0, -9.81)` (URDF has none), initial state zero.
//!
//! Every problem is reported at once: XML syntax, unknown joint types,
//! missing or duplicate links and joints, links with two parents, cycles,
//! several roots, bad numbers, inertia that is not positive definite, and
//! massless links that move.

use super::read::Format;
use super::spec::{
    Body, Constraint, Contact, Force, Frame, Geometry, Inertia, InertiaPolicy, Joint, JointKind,
    Num, Orientation, Spec, V3,
};
use crate::diag::did_you_mean;
use crate::diag::{Diagnostic, Report, Source, Span};
use crate::expr::Func;
use nalgebra::{Matrix3, Rotation3, SymmetricEigen, Vector3};
use roxmltree::Node;
use std::collections::HashMap;

/// Suffix of the path of a converted model's [`Source`]: `robot.urdf (converted)`.
pub const CONVERTED: &str = " (converted)";

/// Gravity given to imported models (URDF has none), m/s².
pub const GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

/// A converted URDF.
#[derive(Clone, Debug)]
pub struct Import {
    /// The model.
    pub spec: Spec,
    /// The model as RON text (with the notes as a header comment), with the
    /// path `<urdf path> (converted)`.
    pub source: Source,
    /// What the conversion did that the user should know: merged links,
    /// ignored geometry, limits and friction that were dropped, renamed items.
    pub notes: Vec<String>,
    /// Warnings, located in the URDF: physically inconsistent inertias of
    /// moving links, kept as written (see [`Options`]).
    pub warnings: Vec<Diagnostic>,
}

/// How a URDF is imported (see `docs/model-format.md`, "Inertia policy").
/// The default imports the joint limits and leaves the inertias as
/// written (warnings).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Fix physically inconsistent inertias of moving links instead of
    /// warning (like MuJoCo's `balanceinertia`): negative principal moments
    /// become zero, then the smallest is raised until each is at most the
    /// sum of the other two. Each fix is listed in the notes.
    pub balance_inertia: bool,
    /// Turn the warnings into errors.
    pub strict: bool,
    /// Import the `<limit lower upper>` of revolute and prismatic joints
    /// as joint-limit contacts (`JointLimit`, `e = 0`, issue #26; the
    /// default); `false` lists them in the notes and leaves them off.
    pub joint_limits: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            balance_inertia: false,
            strict: false,
            joint_limits: true,
        }
    }
}

/// True if `path` ends in `.urdf` (any case; see [`Format::of`]).
pub fn is_urdf(path: &str) -> bool {
    Format::of(path, "") == Format::Urdf
}

/// Reads and converts a URDF file (whatever its name), with the notes of
/// the conversion; `model::load` does the same for a `.urdf` file.
pub fn import_file(path: &str) -> Result<Import, Report> {
    convert(&super::read::read(path)?)
}

/// [`import_file`] with [`Options`].
pub fn import_file_with(path: &str, options: &Options) -> Result<Import, Report> {
    convert_with(&super::read(path)?, options)
}

/// Where a URDF `<origin>` (or a chain of them) puts a frame: a rigid
/// transform that remembers the URDF `rpy` when the rotation is exactly one
/// (so that simple files convert to exact numbers). Not a kinematic pose:
/// those are [`crate::mech::Pose`].
#[derive(Clone, Debug)]
struct Placement {
    rot: Matrix3<f64>,
    pos: Vector3<f64>,
    rpy: Option<[f64; 3]>,
}

impl Placement {
    fn identity() -> Self {
        Placement {
            rot: Matrix3::identity(),
            pos: Vector3::zeros(),
            rpy: Some([0.0; 3]),
        }
    }

    fn is_rot_identity(&self) -> bool {
        self.rpy == Some([0.0; 3])
    }

    /// `self ∘ other`: `other` is expressed in `self`'s frame.
    fn then(&self, other: &Placement) -> Placement {
        let rpy = if other.is_rot_identity() {
            self.rpy
        } else if self.is_rot_identity() {
            other.rpy
        } else {
            None
        };
        Placement {
            rot: self.rot * other.rot,
            pos: self.pos + self.rot * other.pos,
            rpy,
        }
    }

    fn frame(&self) -> Frame {
        let orientation = match self.rpy {
            Some([0.0, 0.0, 0.0]) => Orientation::Identity,
            Some([r, p, y]) => Orientation::Rpy(r.into(), p.into(), y.into()),
            None => {
                let m = &self.rot;
                let row = |i: usize| V3(m[(i, 0)].into(), m[(i, 1)].into(), m[(i, 2)].into());
                Orientation::Matrix(row(0), row(1), row(2))
            }
        };
        Frame {
            position: v3(&self.pos),
            orientation,
        }
    }
}

fn v3(v: &Vector3<f64>) -> V3 {
    V3(v.x.into(), v.y.into(), v.z.into())
}

fn rpy_matrix(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    Rotation3::from_euler_angles(r, p, y).into_inner()
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
    Floating,
    Planar,
}

impl Kind {
    fn parse(s: &str) -> Option<Kind> {
        Some(match s {
            "revolute" => Kind::Revolute,
            "continuous" => Kind::Continuous,
            "prismatic" => Kind::Prismatic,
            "fixed" => Kind::Fixed,
            "floating" => Kind::Floating,
            "planar" => Kind::Planar,
            _ => return None,
        })
    }

    fn one_dof(self) -> bool {
        matches!(self, Kind::Revolute | Kind::Continuous | Kind::Prismatic)
    }
}

const KINDS: &str = "`revolute`, `continuous`, `prismatic`, `fixed`, `floating` or `planar`";

struct Inertial {
    /// Where the tensor is written (`<inertia>`, else `<inertial>`).
    span: Span,
    mass: f64,
    origin: Placement,
    /// About the centre of mass, in the inertial frame.
    inertia: Matrix3<f64>,
}

struct Link {
    raw: String,
    name: String,
    span: Span,
    inertial: Option<Inertial>,
    /// Its `<visual>` shapes, each in the link frame.
    visuals: Vec<Visual>,
}

/// A `<visual>`: where it sits on its link and the shape (its `frame`
/// field is filled in once the link's place on its body is known).
struct Visual {
    origin: Placement,
    shape: Geometry,
}

struct Mimic {
    joint: String,
    span: Span,
    multiplier: f64,
    offset: f64,
}

struct UJoint {
    raw: String,
    name: String,
    span: Span,
    kind: Option<Kind>,
    parent: Option<(String, Span)>,
    child: Option<(String, Span)>,
    origin: Placement,
    axis: Vector3<f64>,
    mimic: Option<Mimic>,
    damping: f64,
    friction: f64,
    limit: Vec<(String, f64)>,
}

struct Ctx {
    diags: Vec<Diagnostic>,
    notes: Vec<String>,
    warnings: Vec<Diagnostic>,
}

fn span(r: std::ops::Range<usize>) -> Span {
    Span::new(r.start, r.end)
}

/// The span of an element's tag name (`<link` → `link`).
fn tag_span(n: Node<'_, '_>) -> Span {
    let s = n.range().start;
    Span::new(s + 1, s + 1 + n.tag_name().name().len())
}

fn child<'a, 'i>(n: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    n.children()
        .find(|c| c.is_element() && c.tag_name().name() == tag)
}

impl Ctx {
    fn error(&mut self, at: Span, msg: String, help: impl Into<String>) {
        self.diags.push(Diagnostic::error(at, msg).with_help(help));
    }

    fn attr_span(&self, n: Node<'_, '_>, name: &str) -> Span {
        n.attribute_node(name)
            .map_or_else(|| tag_span(n), |a| span(a.range_value()))
    }

    fn numbers(&mut self, n: Node<'_, '_>, name: &str, count: usize) -> Option<Vec<f64>> {
        let text = n.attribute(name)?;
        let at = self.attr_span(n, name);
        let parsed: Result<Vec<f64>, _> = text.split_whitespace().map(str::parse::<f64>).collect();
        match parsed {
            Ok(v) if v.len() == count && v.iter().all(|x| x.is_finite()) => Some(v),
            Ok(v) if v.len() == count => {
                self.error(
                    at,
                    format!("`{name}` has a value that is not finite: `{text}`"),
                    "write finite numbers",
                );
                None
            }
            _ if text.contains(',') => {
                self.error(
                    at,
                    format!("`{name}` has numbers separated by commas: `{text}`"),
                    format!(
                        "URDF numbers are separated by spaces (urdfdom rejects commas too): write `{name}=\"{}\"`",
                        text.split(',').map(str::trim).collect::<Vec<_>>().join(" ")
                    ),
                );
                None
            }
            _ => {
                let what = if count == 1 {
                    "a number".to_string()
                } else {
                    format!("{count} numbers separated by spaces")
                };
                self.error(
                    at,
                    format!("`{name}` must be {what}, found `{text}`"),
                    format!("write e.g. `{name}=\"{}\"`", vec!["0"; count].join(" ")),
                );
                None
            }
        }
    }

    fn number(&mut self, n: Node<'_, '_>, name: &str, default: f64) -> f64 {
        self.numbers(n, name, 1).map_or(default, |v| v[0])
    }

    fn vec3(&mut self, n: Node<'_, '_>, name: &str, default: Vector3<f64>) -> Vector3<f64> {
        self.numbers(n, name, 3)
            .map_or(default, |v| Vector3::new(v[0], v[1], v[2]))
    }

    /// The `<origin xyz rpy>` child of `n` (identity if absent).
    fn origin(&mut self, n: Node<'_, '_>) -> Placement {
        let Some(o) = child(n, "origin") else {
            return Placement::identity();
        };
        let pos = self.vec3(o, "xyz", Vector3::zeros());
        let rpy = self.vec3(o, "rpy", Vector3::zeros());
        Placement {
            rot: rpy_matrix(rpy.x, rpy.y, rpy.z),
            pos,
            rpy: Some([rpy.x, rpy.y, rpy.z]),
        }
    }

    fn required(&mut self, n: Node<'_, '_>, name: &str, what: &str) -> Option<String> {
        match n.attribute(name) {
            Some(v) if !v.trim().is_empty() => Some(v.to_string()),
            _ => {
                self.error(
                    tag_span(n),
                    format!("`<{}>` has no `{name}`", n.tag_name().name()),
                    format!("add `{name}=\"…\"` ({what})"),
                );
                None
            }
        }
    }

    fn inertial(&mut self, link: &str, n: Node<'_, '_>) -> Option<Inertial> {
        let origin = self.origin(n);
        let mass = match child(n, "mass") {
            Some(m) if m.attribute("value").is_some() => {
                let v = self.number(m, "value", 0.0);
                if v < 0.0 {
                    self.error(
                        self.attr_span(m, "value"),
                        format!("mass of link `{link}` is negative ({v})"),
                        "a mass is zero or positive, in kg",
                    );
                }
                v
            }
            Some(m) => {
                self.error(
                    tag_span(m),
                    format!("`<mass>` of link `{link}` has no `value`"),
                    "write `<mass value=\"1.0\"/>` (kg)",
                );
                0.0
            }
            None => {
                self.error(
                    tag_span(n),
                    format!("`<inertial>` of link `{link}` has no `<mass>`"),
                    "add `<mass value=\"1.0\"/>` (kg)",
                );
                0.0
            }
        };
        let mut inertia = Matrix3::zeros();
        if let Some(i) = child(n, "inertia") {
            let mut g = |name: &str| self.number(i, name, 0.0);
            let (xx, xy, xz, yy, yz, zz) =
                (g("ixx"), g("ixy"), g("ixz"), g("iyy"), g("iyz"), g("izz"));
            inertia = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
        }
        Some(Inertial {
            span: child(n, "inertia").map_or_else(|| tag_span(n), tag_span),
            mass,
            origin,
            inertia,
        })
    }
}

/// The text with an XML declaration that follows leading blank lines or
/// comments replaced by spaces (byte offsets unchanged). XML wants the
/// declaration first; urdfdom (TinyXML) and so ROS and Pinocchio accept it
/// after a comment, so eom does too. The declaration says nothing eom
/// needs: the text is already UTF-8.
fn blank_xml_declaration(text: &str) -> std::borrow::Cow<'_, str> {
    let mut at = 0;
    loop {
        let rest = &text[at..];
        let trimmed = rest.trim_start();
        at += rest.len() - trimmed.len();
        if trimmed.starts_with("<!--") {
            match trimmed.find("-->") {
                Some(end) => at += end + 3,
                None => return text.into(),
            }
        } else if trimmed.starts_with("<?xml")
            && trimmed[5..].starts_with(|c: char| c.is_whitespace() || c == '?')
        {
            let Some(end) = trimmed.find("?>") else {
                return text.into();
            };
            let mut out = String::with_capacity(text.len());
            out.push_str(&text[..at]);
            // One space per byte (newlines kept): offsets and lines unchanged.
            for c in trimmed[..end + 2].chars() {
                if c == '\n' {
                    out.push('\n');
                } else {
                    out.extend(std::iter::repeat_n(' ', c.len_utf8()));
                }
            }
            out.push_str(&trimmed[end + 2..]);
            return out.into();
        } else {
            return text.into();
        }
    }
}

/// Reports xacro that was not expanded (`${…}`, `$(…)` in attributes,
/// `xacro:` elements), each at its place; false if there is any.
fn xacro_leftovers(cx: &mut Ctx, robot: Node<'_, '_>) -> bool {
    let before = cx.diags.len();
    let help = "this is a xacro file: expand it first, e.g. `xacro robot.urdf.xacro > robot.urdf` (ROS: `ros2 run xacro xacro …`), and load the result";
    for n in robot.descendants().filter(|n| n.is_element()) {
        let ns = n.tag_name().namespace().unwrap_or("");
        if ns.contains("xacro") {
            cx.error(
                tag_span(n),
                format!("unexpanded xacro element `<xacro:{}>`", n.tag_name().name()),
                help,
            );
            continue;
        }
        for a in n.attributes() {
            let v = a.value();
            if let Some(k) = v.find("${").or_else(|| v.find("$(")) {
                let start = a.range_value().start;
                // Offsets within the value hold when it has no entities.
                let end = if a.range_value().len() == v.len() {
                    start + k + v[k..].find(['}', ')']).map_or(2, |e| e + 1)
                } else {
                    a.range_value().end
                };
                let from = if a.range_value().len() == v.len() {
                    start + k
                } else {
                    start
                };
                cx.error(
                    Span::new(from, end.max(from + 1)),
                    format!("unexpanded xacro expression in `{}`: `{v}`", a.name()),
                    help,
                );
            }
        }
    }
    cx.diags.len() == before
}

/// Turns `name` into an identifier usable in eom models (letters, digits,
/// `_`; not `t`, `pi`, a function name or `ground`).
fn identifier(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    let reserved =
        ["t", "pi", "ground"].contains(&s.as_str()) || Func::ALL.iter().any(|f| f.name() == s);
    if reserved {
        s.push('_');
    }
    s
}

/// Unique identifiers for `raw` names (later duplicates get `_2`, `_3`…).
fn unique_names<'a>(raws: impl Iterator<Item = &'a str>, taken: &mut Vec<String>) -> Vec<String> {
    raws.map(|raw| {
        let base = identifier(raw);
        let mut name = base.clone();
        let mut k = 2;
        while taken.contains(&name) {
            name = format!("{base}_{k}");
            k += 1;
        }
        taken.push(name.clone());
        name
    })
    .collect()
}

fn fmt_num(x: f64) -> String {
    if x < 0.0 {
        format!("({x:?})")
    } else {
        format!("{x:?}")
    }
}

/// Converts URDF text into an eom model, reporting every problem at once.
pub fn convert(src: &Source) -> Result<Import, Report> {
    convert_with(src, &Options::default())
}

/// [`convert`] with [`Options`].
pub fn convert_with(src: &Source, options: &Options) -> Result<Import, Report> {
    let fail = |diagnostics: Vec<Diagnostic>| Report {
        source: src.clone(),
        diagnostics,
    };
    let text = blank_xml_declaration(&src.text);
    let doc = roxmltree::Document::parse(&text).map_err(|e| {
        let p = e.pos();
        let at = src.offset_of(p.row as usize, p.col as usize);
        fail(vec![
            Diagnostic::error(Span::new(at, at + 1), format!("invalid XML: {e}"))
                .with_help("a URDF is an XML file with a `<robot>` root element"),
        ])
    })?;
    let robot_el = doc.root_element();
    let mut cx = Ctx {
        diags: Vec::new(),
        notes: Vec::new(),
        warnings: Vec::new(),
    };
    if !xacro_leftovers(&mut cx, robot_el) {
        return Err(fail(cx.diags));
    }
    if robot_el.tag_name().name() != "robot" {
        cx.error(
            tag_span(robot_el),
            format!(
                "the root element is `<{}>`, not `<robot>`",
                robot_el.tag_name().name()
            ),
            "a URDF file is `<robot name=\"…\"> <link …/> <joint …/> … </robot>`",
        );
        return Err(fail(cx.diags));
    }
    let robot_raw = robot_el.attribute("name").unwrap_or("robot");
    let robot = identifier(robot_raw);

    // Links.
    let mut links: Vec<Link> = Vec::new();
    let mut link_nodes = Vec::new();
    let mut ignored: HashMap<String, usize> = HashMap::new();
    let mut joint_nodes = Vec::new();
    for n in robot_el.children().filter(|n| n.is_element()) {
        match n.tag_name().name() {
            "link" => link_nodes.push(n),
            "joint" => joint_nodes.push(n),
            "material" => {} // named colours, read below
            other => *ignored.entry(format!("<{other}>")).or_default() += 1,
        }
    }
    // Named colours: `<material name><color rgba/></material>` under `<robot>`.
    let materials: HashMap<String, (f64, f64, f64)> = robot_el
        .children()
        .filter(|n| n.is_element() && n.tag_name().name() == "material")
        .filter_map(|m| Some((m.attribute("name")?.to_string(), rgb(m)?)))
        .collect();
    let mut taken = Vec::new();
    let mut link_index: HashMap<String, usize> = HashMap::new();
    for n in &link_nodes {
        let Some(raw) = cx.required(*n, "name", "the link's name") else {
            continue;
        };
        if link_index.contains_key(&raw) {
            cx.error(
                cx.attr_span(*n, "name"),
                format!("link `{raw}` is defined twice"),
                "give each link a unique name",
            );
            continue;
        }
        let count = n
            .children()
            .filter(|c| c.is_element() && c.tag_name().name() == "collision")
            .count();
        if count > 0 {
            *ignored.entry("<collision>".to_string()).or_default() += count;
        }
        let visuals = n
            .children()
            .filter(|c| c.is_element() && c.tag_name().name() == "visual")
            .filter_map(|v| cx.visual(&raw, v, &materials, &src.path))
            .collect();
        let inertial = child(*n, "inertial").and_then(|i| cx.inertial(&raw, i));
        link_index.insert(raw.clone(), links.len());
        links.push(Link {
            raw,
            name: String::new(),
            span: cx.attr_span(*n, "name"),
            inertial,
            visuals,
        });
    }
    let names = unique_names(links.iter().map(|l| l.raw.as_str()), &mut taken);
    for (l, name) in links.iter_mut().zip(names) {
        if name != l.raw {
            cx.notes.push(format!(
                "link `{}` is named `{name}` (not an identifier)",
                l.raw
            ));
        }
        l.name = name;
    }

    // Joints.
    let mut joints: Vec<UJoint> = Vec::new();
    let mut joint_index: HashMap<String, usize> = HashMap::new();
    for n in &joint_nodes {
        let Some(joint) = read_joint(&mut cx, *n, &links, &link_index) else {
            continue;
        };
        let raw = joint.raw.clone();
        if joint_index.contains_key(&raw) {
            cx.error(
                cx.attr_span(*n, "name"),
                format!("joint `{raw}` is defined twice"),
                "give each joint a unique name",
            );
            continue;
        }
        joint_index.insert(raw, joints.len());
        joints.push(joint);
    }
    // Joint names are a namespace of their own (a joint may share a link's name).
    let names = unique_names(joints.iter().map(|j| j.raw.as_str()), &mut Vec::new());
    for (j, name) in joints.iter_mut().zip(names) {
        if name != j.raw {
            cx.notes.push(format!(
                "joint `{}` is named `{name}` (not an identifier)",
                j.raw
            ));
        }
        j.name = name;
    }

    // Tree: each link has at most one parent joint; one root.
    let world = usize::MAX;
    let link_id = |l: &str| -> usize {
        if l == "world" {
            world
        } else {
            link_index.get(l).copied().unwrap_or(world)
        }
    };
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    let mut children: HashMap<usize, Vec<usize>> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        let (Some((p, _)), Some((c, cs))) = (&j.parent, &j.child) else {
            continue;
        };
        let (p, c) = (link_id(p), link_id(c));
        if c == world {
            cx.error(
                *cs,
                format!("joint `{}` has `world` as its child", j.raw),
                "`world` is the fixed ground: it can only be a parent",
            );
            continue;
        }
        if p == c {
            cx.error(
                *cs,
                format!("joint `{}` joins link `{}` to itself", j.raw, links[c].raw),
                "parent and child must be different links",
            );
            continue;
        }
        if let Some(first) = parent_joint[c] {
            cx.error(
                *cs,
                format!(
                    "link `{}` is the child of both `{}` and `{}`",
                    links[c].raw, joints[first].raw, j.raw
                ),
                "a URDF is a tree: each link has one parent joint (closed loops cannot be written in URDF)",
            );
            continue;
        }
        parent_joint[c] = Some(k);
        children.entry(p).or_default().push(k);
    }
    let world_used = link_index.contains_key("world") || children.contains_key(&world);
    let roots: Vec<usize> = (0..links.len())
        .filter(|&l| parent_joint[l].is_none() && links[l].raw != "world")
        .collect();
    let mut root = world;
    if world_used {
        for &l in &roots {
            cx.error(
                links[l].span,
                format!("link `{}` is not connected to `world`", links[l].raw),
                "join it to the tree with a `<joint>`, or remove it (a URDF has one root)",
            );
        }
    } else if roots.len() > 1 {
        let list: Vec<String> = roots
            .iter()
            .map(|&l| format!("`{}`", links[l].raw))
            .collect();
        for &l in &roots {
            cx.error(
                links[l].span,
                format!(
                    "the URDF has {} roots ({}); link `{}` is never a child",
                    roots.len(),
                    list.join(", "),
                    links[l].raw
                ),
                "join the roots with joints so that exactly one link is never a child",
            );
        }
    } else if let Some(&r) = roots.first() {
        root = r;
    } else if !links.is_empty() {
        cx.error(
            tag_span(robot_el),
            "every link is a child: the joints form a cycle".to_string(),
            "a URDF is a tree with one root link that is never a child",
        );
    } else {
        cx.error(
            tag_span(robot_el),
            "the URDF has no links".to_string(),
            "add `<link name=\"…\">` elements",
        );
    }

    // Depth-first from the root, children in document order; assign each
    // link to a body (None = ground) and its pose in that body.
    let mut assign: Vec<Option<(Option<usize>, Placement)>> = vec![None; links.len()];
    let mut order: Vec<usize> = Vec::new(); // movable joints in tree order
    let mut bodies: Vec<usize> = Vec::new(); // head link of each body
    let mut merged: Vec<(String, String)> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let push_children = |p: usize, stack: &mut Vec<usize>| {
        if let Some(ks) = children.get(&p) {
            stack.extend(ks.iter().rev());
        }
    };
    if root != world {
        assign[root] = Some((None, Placement::identity()));
        cx.notes.push(format!(
            "root link `{}` is fixed to the ground; it and the links fixed to it do not move (for a free base add `<link name=\"world\"/>` and a `floating` joint from it)",
            links[root].raw
        ));
    }
    if root != world || world_used {
        push_children(root, &mut stack);
    }
    while let Some(k) = stack.pop() {
        let j = &joints[k];
        let (Some((p, _)), Some((c, _))) = (&j.parent, &j.child) else {
            continue;
        };
        let (p, c) = (link_id(p), link_id(c));
        let (pb, pose) = if p == world {
            (None, Placement::identity())
        } else {
            match &assign[p] {
                Some(a) => a.clone(),
                None => continue,
            }
        };
        let at = pose.then(&j.origin);
        if j.kind == Some(Kind::Fixed) || j.kind.is_none() {
            merged.push((
                links[c].raw.clone(),
                pb.map_or("ground".to_string(), |b| links[bodies[b]].raw.clone()),
            ));
            assign[c] = Some((pb, at));
        } else {
            assign[c] = Some((Some(bodies.len()), Placement::identity()));
            bodies.push(c);
            order.push(k);
        }
        push_children(c, &mut stack);
    }
    // Links that no root reaches hang on a cycle.
    let mut reached = vec![false; links.len()];
    let mut todo: Vec<usize> = roots.clone();
    todo.push(world);
    while let Some(l) = todo.pop() {
        if l != world {
            reached[l] = true;
        }
        for &k in children.get(&l).map_or(&[][..], Vec::as_slice) {
            if let Some((c, _)) = &joints[k].child {
                let c = link_id(c);
                if c != world && !reached[c] {
                    todo.push(c);
                }
            }
        }
    }
    {
        for (k, j) in joints.iter().enumerate() {
            if let Some((c, _)) = &j.child
                && let Some(&c) = link_index.get(c)
                && !reached[c]
                && parent_joint[c] == Some(k)
            {
                cx.error(
                    j.span,
                    format!(
                        "joint `{}` is part of a cycle: link `{}` cannot be reached from the root",
                        j.raw, links[c].raw
                    ),
                    "a URDF is a tree; remove one joint of the cycle",
                );
            }
        }
    }

    // The inertia policy: links fixed to the ground are not checked.
    for l in 0..links.len() {
        let on_ground = matches!(assign[l], Some((None, _)));
        check_inertia(&mut cx, &mut links[l], on_ground, options);
    }

    // Composite inertia of each body.
    let mut parts: Vec<Vec<Part>> = (0..bodies.len()).map(|_| Vec::new()).collect();
    let mut ground_mass = 0.0;
    for (l, link) in links.iter().enumerate() {
        let (Some((b, pose)), Some(i)) = (&assign[l], &link.inertial) else {
            continue;
        };
        // A massless link keeps its rotational inertia (as in Pinocchio).
        if i.mass <= 0.0 && i.inertia == Matrix3::zeros() {
            continue;
        }
        let Some(b) = b else {
            ground_mass += i.mass.max(0.0);
            continue;
        };
        let frame = pose.then(&i.origin);
        parts[*b].push(Part {
            mass: i.mass,
            com: frame.pos,
            inertia: {
                let turned = frame.rot * i.inertia * frame.rot.transpose();
                (turned + turned.transpose()) / 2.0
            },
        });
    }
    if ground_mass > 0.0 {
        cx.notes.push(format!(
            "{ground_mass} kg of links fixed to the ground do not enter the dynamics"
        ));
    }
    let mut spec_bodies = Vec::new();
    for (b, &l) in bodies.iter().enumerate() {
        let ps = &parts[b];
        let mass: f64 = ps.iter().map(|p| p.mass).sum();
        // A massless moving link (a virtual link of a multi-DOF joint) is
        // fine when the mass matrix stays positive definite: checked below.
        let mass = if mass > 0.0 { mass } else { 0.0 };
        let (com, inertia) = composite(ps, mass);
        spec_bodies.push(Body {
            name: links[l].name.clone(),
            label: (links[l].name != links[l].raw).then(|| links[l].raw.clone()),
            mass: Some(mass.into()),
            com: v3(&com),
            inertia: inertia_spec(&inertia),
            markers: Vec::new(),
            flexible: None,
            geometry: Vec::new(),
        });
    }
    // Visuals: on the body their link is part of, or on the ground.
    let mut ground_geometry = Vec::new();
    for (l, link) in links.iter().enumerate() {
        let Some((b, pose)) = &assign[l] else {
            continue;
        };
        for v in &link.visuals {
            let g = with_frame(&v.shape, pose.then(&v.origin).frame());
            match b {
                Some(b) => spec_bodies[*b].geometry.push(g),
                None => ground_geometry.push(g),
            }
        }
    }

    // Joints, forces, constraints.
    let body_name =
        |b: Option<usize>| b.map_or("ground".to_string(), |b| links[bodies[b]].name.clone());
    let mut spec_joints = Vec::new();
    let mut forces = Vec::new();
    let mut constraints = Vec::new();
    let mut limits = Vec::new();
    let mut contacts = Vec::new();
    for &k in &order {
        let j = &joints[k];
        let (Some((p, _)), Some((c, _)), Some(kind)) = (&j.parent, &j.child, j.kind) else {
            continue;
        };
        let (p, c) = (link_id(p), link_id(c));
        let (pb, pose) = if p == world {
            (None, Placement::identity())
        } else {
            match &assign[p] {
                Some(a) => a.clone(),
                None => continue,
            }
        };
        let mut parent_frame = pose.then(&j.origin);
        let mut child_frame = Placement::identity();
        let axis = if j.axis.norm() > 0.0 {
            j.axis / j.axis.norm()
        } else {
            Vector3::x()
        };
        let kind_spec = match kind {
            Kind::Revolute | Kind::Continuous => JointKind::Revolute { axis: v3(&axis) },
            Kind::Prismatic => JointKind::Prismatic { axis: v3(&axis) },
            Kind::Floating => JointKind::Free,
            Kind::Planar => {
                if axis != Vector3::z() {
                    let r = Rotation3::rotation_between(&Vector3::z(), &axis)
                        .unwrap_or_else(|| {
                            Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
                        })
                        .into_inner();
                    let turn = Placement {
                        rot: r,
                        pos: Vector3::zeros(),
                        rpy: None,
                    };
                    parent_frame = parent_frame.then(&turn);
                    child_frame = turn;
                }
                JointKind::Planar
            }
            Kind::Fixed => continue,
        };
        spec_joints.push(Joint {
            name: j.name.clone(),
            label: (j.name != j.raw).then(|| j.raw.clone()),
            kind: kind_spec,
            parent: body_name(pb),
            child: links[c].name.clone(),
            parent_frame: parent_frame.frame(),
            parent_node: None,
            child_frame: child_frame.frame(),
            child_node: None,
            coordinates: None,
            speeds: None,
            q0: None,
            u0: None,
            locked: false,
            prescribed: None,
            cut: false,
        });
        if j.damping > 0.0 {
            if kind.one_dof() {
                forces.push(Force::JointSpringDamper {
                    name: format!("{}_damping", j.name),
                    joint: j.name.clone(),
                    stiffness: 0.0.into(),
                    damping: j.damping.into(),
                    rest: Num::default(),
                });
            } else {
                cx.notes.push(format!(
                    "damping of {} joint `{}` is ignored (only 1-DOF joints carry URDF damping)",
                    kind_name(kind),
                    j.raw
                ));
            }
        }
        if j.friction != 0.0 {
            cx.notes.push(format!(
                "friction {} of joint `{}` is ignored (the model format has no Coulomb friction)",
                j.friction, j.raw
            ));
        }
        let bound = |a: &str| j.limit.iter().find(|(n, _)| n == a).map(|(_, v)| *v);
        let stops = matches!(kind, Kind::Revolute | Kind::Prismatic)
            .then(|| bound("lower").zip(bound("upper")))
            .flatten()
            .filter(|(lo, hi)| lo < hi);
        match stops {
            // The import starts at q = 0: a limit that excludes it would
            // be a contact closed at the start.
            Some((lo, hi)) if options.joint_limits && lo <= 0.0 && 0.0 <= hi => {
                let rest: Vec<String> = j
                    .limit
                    .iter()
                    .filter(|(a, _)| a != "lower" && a != "upper")
                    .map(|(a, v)| format!("{a} {v}"))
                    .collect();
                cx.notes.push(format!(
                    "limits [{lo}, {hi}] of joint `{}` imported as the plastic joint-limit contact `{}_limit` (e = 0; leave them off with `--no-urdf-limits`, `Options::joint_limits: false`){}",
                    j.raw,
                    j.name,
                    if rest.is_empty() {
                        String::new()
                    } else {
                        format!("; ignored: {}", rest.join(", "))
                    }
                ));
                contacts.push(Contact::JointLimit {
                    name: format!("{}_limit", j.name),
                    joint: j.name.clone(),
                    lower: Some(lo.into()),
                    upper: Some(hi.into()),
                    e: 0.0.into(),
                    mu: Num::default(),
                });
            }
            Some((lo, hi)) if options.joint_limits => cx.notes.push(format!(
                "limits [{lo}, {hi}] of joint `{}` are not imported: the initial state q = 0 lies outside them",
                j.raw
            )),
            _ if !j.limit.is_empty() => {
                let l: Vec<String> = j.limit.iter().map(|(a, v)| format!("{a} {v}")).collect();
                limits.push(format!("`{}`: {}", j.raw, l.join(", ")));
            }
            _ => {}
        }
        if let Some(m) = &j.mimic {
            match joint_index.get(&m.joint).map(|&o| &joints[o]) {
                None => {
                    // urdfdom (and so Pinocchio and ROS) load such a file and
                    // ignore the mimic: a warning, an error when strict.
                    let help = match did_you_mean(&m.joint, joints.iter().map(|j| j.raw.as_str())) {
                        Some(b) => format!("did you mean `{b}`?"),
                        None => "name a revolute, continuous or prismatic joint".to_string(),
                    };
                    let message = format!(
                        "mimic of joint `{}` names unknown joint `{}`",
                        j.raw, m.joint
                    );
                    if options.strict {
                        cx.error(m.span, message, help);
                    } else {
                        cx.warnings.push(
                            Diagnostic::warning(
                                m.span,
                                format!("{message}; ignored: `{}` moves on its own", j.raw),
                            )
                            .with_help(format!(
                                "{help} (urdfdom ignores it too; `strict` rejects it)"
                            )),
                        );
                    }
                }
                Some(o)
                    if !o.kind.is_some_and(Kind::one_dof) || !kind.one_dof() || o.raw == j.raw =>
                {
                    cx.error(
                        m.span,
                        format!("joint `{}` cannot mimic joint `{}`", j.raw, o.raw),
                        "mimic couples two different revolute, continuous or prismatic joints",
                    );
                }
                Some(o) => constraints.push(Constraint::Holonomic {
                    name: format!("{}_mimic", j.name),
                    expr: format!(
                        "{} - {}*{} - {}",
                        j.name,
                        fmt_num(m.multiplier),
                        o.name,
                        fmt_num(m.offset)
                    ),
                }),
            }
        }
    }
    for j in &joints {
        if j.kind == Some(Kind::Fixed) && j.mimic.is_some() {
            cx.notes
                .push(format!("mimic of fixed joint `{}` is ignored", j.raw));
        }
    }

    if cx.diags.iter().any(Diagnostic::is_error) {
        // Every problem at once: the warnings too.
        cx.diags.append(&mut cx.warnings);
        cx.diags.sort_by_key(|d| d.span.map(|s| s.start));
        return Err(fail(cx.diags));
    }

    let lenient =
        !cx.warnings.is_empty() || spec_bodies.iter().any(|b| b.mass == Some(Num::Value(0.0)));
    let spec = Spec {
        name: robot.clone(),
        gravity: Some(V3(GRAVITY[0].into(), GRAVITY[1].into(), GRAVITY[2].into())),
        parameters: Vec::new(),
        bodies: spec_bodies,
        joints: spec_joints,
        forces,
        constraints,
        outputs: Vec::new(),
        cables: Vec::new(),
        contacts,
        inertia_policy: if lenient {
            InertiaPolicy::Lenient
        } else {
            InertiaPolicy::Strict
        },
        ground_geometry,
    };
    // Always: positive masses do not make it positive definite (a point
    // mass on a joint axis).
    {
        check_mass_matrix(&mut cx, src, &spec, &links, &joints, options.strict);
        if cx.diags.iter().any(Diagnostic::is_error) {
            cx.diags.append(&mut cx.warnings);
            cx.diags.sort_by_key(|d| d.span.map(|s| s.start));
            return Err(fail(cx.diags));
        }
    }

    // Notes.
    let mut notes = Vec::new();
    if !merged.is_empty() {
        let list: Vec<String> = merged
            .iter()
            .map(|(c, p)| format!("`{c}` into `{p}`"))
            .collect();
        notes.push(format!(
            "{} link(s) joined by fixed joints merged into one rigid body each (composite inertia; no work for them in the generated code): {}",
            merged.len(),
            list.join(", ")
        ));
    }
    notes.append(&mut cx.notes);
    if !spec.constraints.is_empty() {
        notes.push(format!(
            "{} mimic joint(s) became holonomic constraints",
            spec.constraints.len()
        ));
    }
    if !limits.is_empty() {
        notes.push(format!(
            "joint limits are not imported ({}): {}",
            if options.joint_limits {
                "only revolute and prismatic joints with both bounds are"
            } else {
                "left off by `--no-urdf-limits`, `Options::joint_limits: false`"
            },
            limits.join("; ")
        ));
    }
    let mut ign: Vec<_> = ignored.into_iter().collect();
    ign.sort();
    if !ign.is_empty() {
        let list: Vec<String> = ign.iter().map(|(t, n)| format!("{n} {t}")).collect();
        notes.push(format!("ignored (no dynamics): {}", list.join(", ")));
    }
    notes.push("gravity (0, 0, -9.81) m/s² (URDF has none); initial state zero".to_string());

    let mut text = format!("// Converted by eom-gen from the URDF `{}`.\n", src.path);
    for n in &notes {
        text += &format!("// - {n}\n");
    }
    text += &spec.to_ron();
    if !text.ends_with('\n') {
        text.push('\n');
    }
    Ok(Import {
        spec,
        source: Source::new(format!("{}{CONVERTED}", src.path), text),
        notes,
        warnings: cx.warnings,
    })
}

/// The `rgb` of a `<material>`'s `<color rgba>` (None if absent or bad:
/// colour is decoration).
fn rgb(m: Node<'_, '_>) -> Option<(f64, f64, f64)> {
    let text = child(m, "color")?.attribute("rgba")?;
    let v: Vec<f64> = text
        .split_whitespace()
        .map(str::parse::<f64>)
        .collect::<Result<_, _>>()
        .ok()?;
    match v[..] {
        [r, g, b, _] if [r, g, b].iter().all(|c| (0.0..=1.0).contains(c)) => Some((r, g, b)),
        _ => None,
    }
}

/// `g` with its frame replaced by `frame`.
fn with_frame(g: &Geometry, frame: Frame) -> Geometry {
    let mut g = g.clone();
    match &mut g {
        Geometry::Box { frame: f, .. }
        | Geometry::Cylinder { frame: f, .. }
        | Geometry::Sphere { frame: f, .. }
        | Geometry::Mesh { frame: f, .. } => *f = frame,
    }
    g
}

/// A URDF mesh `filename` as a path relative to the URDF's directory
/// (`urdf_dir`, as given): `package://PKG/REST` is `REST` under the
/// nearest directory, going up from the URDF's, that is named `PKG` or
/// has a subdirectory `PKG` (the layout of a ROS package and of
/// example-robot-data); `file://PATH` is `PATH`; anything else is
/// relative to the URDF already. `Err` says why a package path does not
/// resolve.
pub fn resolve_mesh(filename: &str, urdf_dir: &std::path::Path) -> Result<String, String> {
    if let Some(p) = filename.strip_prefix("file://") {
        return Ok(p.to_string());
    }
    let Some(rest) = filename.strip_prefix("package://") else {
        return Ok(filename.to_string());
    };
    let (pkg, rel) = rest.split_once('/').unwrap_or((rest, ""));
    let start = if urdf_dir.as_os_str().is_empty() {
        std::path::Path::new(".")
    } else {
        urdf_dir
    };
    let abs = std::fs::canonicalize(start)
        .map_err(|e| format!("the URDF's directory `{}`: {e}", start.display()))?;
    let mut up = String::new();
    for dir in abs.ancestors() {
        let found = if dir.file_name().is_some_and(|n| n == pkg) {
            Some(format!("{up}{rel}"))
        } else if dir.join(pkg).is_dir() {
            Some(format!("{up}{pkg}/{rel}"))
        } else {
            None
        };
        if let Some(found) = found
            && urdf_dir.join(&found).is_file()
        {
            return Ok(found);
        }
        up += "../";
    }
    Err(format!(
        "no directory `{pkg}` holding `{rel}` at or above `{}`, nor beside one of those directories",
        abs.display()
    ))
}

impl Ctx {
    /// One `<visual>` of link `link` (None if it has no shape eom draws;
    /// bad numbers are errors).
    fn visual(
        &mut self,
        link: &str,
        v: Node<'_, '_>,
        materials: &HashMap<String, (f64, f64, f64)>,
        urdf_path: &str,
    ) -> Option<Visual> {
        let origin = self.origin(v);
        let color = child(v, "material")
            .and_then(|m| rgb(m).or_else(|| materials.get(m.attribute("name")?).copied()));
        let Some(g) = child(v, "geometry") else {
            self.notes.push(format!(
                "a `<visual>` of link `{link}` has no `<geometry>`: not drawn"
            ));
            return None;
        };
        let Some(shape) = g.children().find(|c| c.is_element()) else {
            self.notes.push(format!(
                "a `<visual>` of link `{link}` has an empty `<geometry>`: not drawn"
            ));
            return None;
        };
        let frame = Frame::default();
        let positive = |cx: &mut Ctx, name: &str| -> Option<f64> {
            let x = cx.numbers(shape, name, 1)?[0];
            if x > 0.0 {
                Some(x)
            } else {
                cx.error(
                    cx.attr_span(shape, name),
                    format!("`{name}` of a `<visual>` of link `{link}` is {x}"),
                    format!("a {name} is positive, in m"),
                );
                None
            }
        };
        let missing = |cx: &mut Ctx, name: &str| {
            if shape.attribute(name).is_none() {
                cx.error(
                    tag_span(shape),
                    format!("`<{}>` has no `{name}`", shape.tag_name().name()),
                    format!("add `{name}=\"…\"` (see the URDF specification)"),
                );
            }
        };
        let geometry = match shape.tag_name().name() {
            "box" => {
                missing(self, "size");
                let size = self.numbers(shape, "size", 3)?;
                if size.iter().any(|x| *x <= 0.0) {
                    self.error(
                        self.attr_span(shape, "size"),
                        format!("`size` of a `<visual>` box of link `{link}` is not positive"),
                        "a box's edge lengths are positive, in m",
                    );
                    return None;
                }
                Geometry::Box {
                    size: V3(size[0].into(), size[1].into(), size[2].into()),
                    frame,
                    color,
                }
            }
            "cylinder" => {
                missing(self, "radius");
                missing(self, "length");
                let (r, l) = (positive(self, "radius"), positive(self, "length"));
                Geometry::Cylinder {
                    radius: r?.into(),
                    length: l?.into(),
                    frame,
                    color,
                }
            }
            "sphere" => {
                missing(self, "radius");
                Geometry::Sphere {
                    radius: positive(self, "radius")?.into(),
                    frame,
                    color,
                }
            }
            "mesh" => {
                let file = self.required(shape, "filename", "the mesh file")?;
                let scale = match shape.attribute("scale") {
                    None => None,
                    Some(_) => {
                        let s = self.numbers(shape, "scale", 3)?;
                        if s.contains(&0.0) {
                            self.error(
                                self.attr_span(shape, "scale"),
                                format!("`scale` of a `<visual>` mesh of link `{link}` has a 0"),
                                "each scale factor is a number other than 0",
                            );
                            return None;
                        }
                        Some(V3(s[0].into(), s[1].into(), s[2].into()))
                    }
                };
                let dir = std::path::Path::new(urdf_path)
                    .parent()
                    .unwrap_or(std::path::Path::new(""));
                let file = match resolve_mesh(&file, dir) {
                    Ok(f) => f,
                    Err(why) => {
                        self.warnings.push(
                            Diagnostic::warning(
                                self.attr_span(shape, "filename"),
                                format!("mesh `{file}` of link `{link}` does not resolve: {why}"),
                            )
                            .with_help(
                                "`eom-gen animate` refuses the model until it does: `package://PKG/…` is looked up in the directories at and above the URDF's, each itself named PKG or holding PKG (docs/model-format.md, URDF)",
                            ),
                        );
                        file
                    }
                };
                Geometry::Mesh {
                    file,
                    scale,
                    frame,
                    color,
                }
            }
            other => {
                self.notes.push(format!(
                    "a `<visual>` `<{other}>` of link `{link}` is not drawn (boxes, cylinders, spheres and meshes are)"
                ));
                return None;
            }
        };
        Some(Visual {
            origin,
            shape: geometry,
        })
    }
}

/// Reads one `<joint>` (None without a name; every problem is reported).
fn read_joint(
    cx: &mut Ctx,
    n: Node<'_, '_>,
    links: &[Link],
    link_index: &HashMap<String, usize>,
) -> Option<UJoint> {
    let raw = cx.required(n, "name", "the joint's name");
    let kind = match n.attribute("type") {
        None => {
            cx.error(
                tag_span(n),
                "`<joint>` has no `type`".to_string(),
                format!("add `type=\"…\"`: one of {KINDS}"),
            );
            None
        }
        Some(t) => {
            let k = Kind::parse(t);
            if k.is_none() {
                let known = [
                    "revolute",
                    "continuous",
                    "prismatic",
                    "fixed",
                    "floating",
                    "planar",
                ];
                let help = match did_you_mean(t, known) {
                    Some(b) => format!("did you mean `{b}`? URDF joint types are {KINDS}"),
                    None => format!("URDF joint types are {KINDS}"),
                };
                cx.error(
                    cx.attr_span(n, "type"),
                    format!("unknown joint type `{t}`"),
                    help,
                );
            }
            k
        }
    };
    let link_ref = |tag: &str, cx: &mut Ctx| -> Option<(String, Span)> {
        let Some(e) = child(n, tag) else {
            cx.error(
                tag_span(n),
                format!("joint `{}` has no `<{tag}>`", raw.as_deref().unwrap_or("?")),
                format!("add `<{tag} link=\"…\"/>`"),
            );
            return None;
        };
        let l = cx.required(e, "link", "a link name")?;
        let at = cx.attr_span(e, "link");
        if l != "world" && !link_index.contains_key(&l) {
            let help = match did_you_mean(&l, links.iter().map(|l| l.raw.as_str())) {
                Some(b) => format!("did you mean `{b}`?"),
                None => "define it with `<link name=\"…\"/>`".to_string(),
            };
            cx.error(at, format!("link `{l}` is not defined"), help);
            return None;
        }
        Some((l, at))
    };
    // A `floating` joint without `<parent>` hangs off the ground (free base).
    let parent = if kind == Some(Kind::Floating) && child(n, "parent").is_none() {
        Some(("world".to_string(), tag_span(n)))
    } else {
        link_ref("parent", cx)
    };
    let child_link = link_ref("child", cx);
    let origin = cx.origin(n);
    let mut axis = Vector3::x();
    if let Some(a) = child(n, "axis") {
        axis = cx.vec3(a, "xyz", Vector3::x());
        if axis.norm() < 1e-12 && kind.is_some_and(|k| k != Kind::Fixed && k != Kind::Floating) {
            cx.error(
                cx.attr_span(a, "xyz"),
                "the joint axis is zero".to_string(),
                "give a direction, e.g. `xyz=\"0 0 1\"`",
            );
            axis = Vector3::x();
        }
    }
    let mimic = child(n, "mimic").and_then(|m| {
        let j = cx.required(m, "joint", "the name of the joint to follow")?;
        Some(Mimic {
            span: cx.attr_span(m, "joint"),
            joint: j,
            multiplier: cx.number(m, "multiplier", 1.0),
            offset: cx.number(m, "offset", 0.0),
        })
    });
    let (mut damping, mut friction) = (0.0, 0.0);
    if let Some(d) = child(n, "dynamics") {
        damping = cx.number(d, "damping", 0.0);
        friction = cx.number(d, "friction", 0.0);
        if damping < 0.0 {
            cx.error(
                cx.attr_span(d, "damping"),
                format!("negative damping ({damping})"),
                "damping is zero or positive (N m s/rad or N s/m)",
            );
        }
    }
    let mut limit = Vec::new();
    if let Some(l) = child(n, "limit") {
        for a in ["lower", "upper", "effort", "velocity"] {
            if l.attribute(a).is_some() {
                limit.push((a.to_string(), cx.number(l, a, 0.0)));
            }
        }
    }
    Some(UJoint {
        span: cx.attr_span(n, "name"),
        raw: raw?,
        name: String::new(),
        kind,
        parent,
        child: child_link,
        origin,
        axis,
        mimic,
        damping,
        friction,
        limit,
    })
}

/// Principal moments (ascending) and axes of a symmetric tensor.
fn principal(i: &Matrix3<f64>) -> ([f64; 3], Matrix3<f64>) {
    let e = SymmetricEigen::new(*i);
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
    let p = order.map(|k| e.eigenvalues[k]);
    let v = Matrix3::from_columns(&order.map(|k| e.eigenvectors.column(k).into_owned()));
    (p, v)
}

/// The inertia policy for one link's tensor (see `docs/model-format.md`,
/// "Inertia policy"): a negative principal moment or a violated triangle
/// inequality is a warning at the `<inertia>` (the mass matrix is checked
/// instead), an error in strict mode, fixed with `balance_inertia`;
/// rounding-level violations (below `1e-12·(I_max + m·1 m²)`, say a point
/// mass written with `ixz="2.4e-35"`) count as none; links fixed to the
/// ground are not checked (a note says so when their tensor is
/// inconsistent).
fn check_inertia(cx: &mut Ctx, link: &mut Link, on_ground: bool, options: &Options) {
    let Some(i) = link.inertial.as_mut() else {
        return;
    };
    if i.inertia == Matrix3::zeros() {
        return;
    }
    if i.inertia.amax() <= 1e-12 * i.mass {
        // All rounding noise (icub writes a point mass as `ixz="2.4e-35"`,
        // the rest zero): a point mass, as intended.
        cx.notes.push(format!(
            "inertia of link `{}` is rounding noise (largest entry {:.1e} kg m² for {} kg): taken as a point mass",
            link.raw,
            i.inertia.amax(),
            i.mass
        ));
        i.inertia = Matrix3::zeros();
        return;
    }
    let (p, v) = principal(&i.inertia);
    // Rounding noise: relative to the tensor and to the link's mass times
    // 1 m², so that a tensor that is all noise is zero.
    let floor = 1e-12 * (p[0].abs().max(p[2].abs()) + i.mass.abs());
    let negative = p[0] < -floor;
    let triangle = p[0] + p[1] < p[2] * (1.0 - 1e-9) - floor;
    if !negative && !triangle {
        return;
    }
    let what = if negative {
        format!(
            "is not positive definite (principal moments {:.6e}, {:.6e}, {:.6e})",
            p[0], p[1], p[2]
        )
    } else {
        format!(
            "violates the triangle inequality (principal moments {:.6e} + {:.6e} < {:.6e})",
            p[0], p[1], p[2]
        )
    };
    if on_ground {
        cx.notes.push(format!(
            "inertia of link `{}` {what}; not checked: the link is fixed to the ground and does not enter the dynamics",
            link.raw
        ));
        return;
    }
    let help = "ixx, iyy, izz are the moments and ixy, ixz, iyz the tensor entries about the centre of mass; no mass distribution has a negative principal moment or one larger than the sum of the other two";
    if options.balance_inertia {
        let mut q = p.map(|x| x.max(0.0));
        if q[0] + q[1] < q[2] {
            q[0] = q[2] - q[1];
        }
        let fixed = v * Matrix3::from_diagonal(&Vector3::from(q)) * v.transpose();
        i.inertia = (fixed + fixed.transpose()) / 2.0;
        cx.notes.push(format!(
            "inertia of link `{}` {what}; balanced (balance_inertia): principal moments {:.6e}, {:.6e}, {:.6e}",
            link.raw, q[0], q[1], q[2]
        ));
        return;
    }
    let message = format!("inertia of link `{}` {what}", link.raw);
    if options.strict {
        cx.error(
            i.span,
            message,
            format!("{help} (strict mode; `--balance-inertia` or `urdf::Options::balance_inertia` fixes it)"),
        );
    } else {
        cx.warnings.push(
            Diagnostic::warning(i.span, message).with_help(format!(
                "kept as written (the mass matrix is checked instead); import with `--balance-inertia` (`urdf::Options::balance_inertia`) to fix it, or `--strict-inertia` to reject it. {help}"
            )),
        );
    }
}

/// The mass matrix of the converted model must be positive definite at the
/// initial state: otherwise an error at the URDF link whose joint's motion
/// has no inertia, or a warning (an error when `strict`) when it is only a
/// configuration singularity (positive definite at other configurations).
fn check_mass_matrix(
    cx: &mut Ctx,
    src: &Source,
    spec: &Spec,
    links: &[Link],
    joints: &[UJoint],
    strict: bool,
) {
    let text = Source::new(format!("{}{CONVERTED}", src.path), spec.to_ron());
    let (Some(system), _) = super::validate::check_with(&text, spec, None, false) else {
        // Reported when the converted model is checked.
        return;
    };
    let Some(singular) = crate::mech::numeric::singular_joint(&system) else {
        return;
    };
    let name = &system.joints[singular.joint].name;
    let Some(uj) = joints.iter().find(|u| &u.name == name) else {
        return;
    };
    let child = uj
        .child
        .as_ref()
        .and_then(|(c, _)| links.iter().find(|l| &l.raw == c));
    let kind = uj.kind.map_or("?", kind_name);
    let body_mass = spec
        .bodies
        .iter()
        .find(|b| child.is_some_and(|c| c.name == b.name))
        .map(|b| b.mass == Some(Num::Value(0.0)));
    if !singular.everywhere {
        // A configuration singularity (icub's neck: two axes aligned at
        // zero): Pinocchio loads it as well; a warning, an error when strict.
        let message = format!(
            "the mass matrix is singular at the initial state: the motion of joint `{}` ({kind}) has no inertia there (it has at other configurations)",
            uj.raw
        );
        let help = "two joint axes line up at the initial state; simulations starting there fail: start elsewhere (`--q0`)";
        if strict {
            cx.error(uj.span, message, help);
        } else {
            cx.warnings
                .push(Diagnostic::warning(uj.span, message).with_help(help));
        }
        return;
    }
    let (at, message) = match (child, body_mass) {
        (Some(c), Some(true)) => (
            c.span,
            format!(
                "link `{}` has no mass but moves (joint `{}` is {kind}), and nothing it carries gives that motion inertia: the mass matrix is singular at the initial state",
                c.raw, uj.raw
            ),
        ),
        _ => (
            uj.span,
            format!(
                "the motion of joint `{}` ({kind}) has no inertia: the mass matrix is singular at the initial state",
                uj.raw
            ),
        ),
    };
    cx.error(
        at,
        message,
        format!(
            "give the link that joint `{}` moves (or the links below it) an `<inertial>` with mass and inertia for this motion, or make the joint `fixed` to merge the link into its parent",
            uj.raw
        ),
    );
}

fn kind_name(k: Kind) -> &'static str {
    match k {
        Kind::Revolute => "revolute",
        Kind::Continuous => "continuous",
        Kind::Prismatic => "prismatic",
        Kind::Fixed => "fixed",
        Kind::Floating => "floating",
        Kind::Planar => "planar",
    }
}

/// A link's mass, centre of mass and inertia about it, in body axes.
struct Part {
    mass: f64,
    com: Vector3<f64>,
    inertia: Matrix3<f64>,
}

/// Centre of mass and inertia about it of rigidly joined parts of total
/// mass `mass > 0` (parallel-axis theorem; one part is copied exactly).
fn composite(parts: &[Part], mass: f64) -> (Vector3<f64>, Matrix3<f64>) {
    if let [p] = parts {
        return (p.com, p.inertia);
    }
    if parts.is_empty() {
        return (Vector3::zeros(), Matrix3::zeros());
    }
    // Massless parts add their rotational inertia only; without any mass
    // the centre of mass is the first part's (it carries no weight).
    let com = if mass > 0.0 {
        parts.iter().map(|p| p.com * p.mass).sum::<Vector3<f64>>() / mass
    } else {
        parts[0].com
    };
    let mut i = Matrix3::zeros();
    for p in parts {
        let d = p.com - com;
        i += p.inertia + p.mass * (Matrix3::identity() * d.dot(&d) - d * d.transpose());
    }
    (com, i)
}

/// `Diag` when the products of inertia vanish, `Matrix` otherwise, `None`
/// (a point mass) for the zero tensor.
fn inertia_spec(i: &Matrix3<f64>) -> Option<Inertia> {
    let diagonal = [(0, 1), (0, 2), (1, 2)]
        .iter()
        .all(|&(r, c)| i[(r, c)] == 0.0);
    if *i == Matrix3::zeros() {
        None
    } else if diagonal {
        Some(Inertia::Diag(
            i[(0, 0)].into(),
            i[(1, 1)].into(),
            i[(2, 2)].into(),
        ))
    } else {
        let row = |r: usize| V3(i[(r, 0)].into(), i[(r, 1)].into(), i[(r, 2)].into());
        Some(Inertia::Matrix(row(0), row(1), row(2)))
    }
}
