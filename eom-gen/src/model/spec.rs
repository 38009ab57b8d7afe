//! The model file format: serde types that mirror the RON text one to one.
//!
//! Nothing here is checked beyond types; [`super::check`] turns a [`Spec`]
//! into a validated [`crate::System`]. Field-by-field documentation with
//! units is in `docs/model-format.md`; the doc comments here are the same
//! text in short.

use serde::de::{self, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// A number or an arithmetic expression over parameters (`"l/2"`).
#[derive(Clone, Debug, PartialEq)]
pub enum Num {
    /// A plain number.
    Value(f64),
    /// An expression, parsed during validation.
    Expr(String),
}

impl Default for Num {
    fn default() -> Self {
        Num::Value(0.0)
    }
}

impl From<f64> for Num {
    fn from(v: f64) -> Self {
        Num::Value(v)
    }
}

impl From<&str> for Num {
    fn from(s: &str) -> Self {
        Num::Expr(s.to_string())
    }
}

impl Num {
    /// True for the literal number zero.
    pub fn is_zero(&self) -> bool {
        matches!(self, Num::Value(v) if *v == 0.0)
    }
}

impl Serialize for Num {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Num::Value(v) => s.serialize_f64(*v),
            Num::Expr(e) => s.serialize_str(e),
        }
    }
}

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct NumVisitor;
        impl Visitor<'_> for NumVisitor {
            type Value = Num;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number or an expression string such as \"l/2\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Num, E> {
                Ok(Num::Value(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Num, E> {
                Ok(Num::Value(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Num, E> {
                Ok(Num::Value(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Num, E> {
                Ok(Num::Expr(v.to_string()))
            }
        }
        d.deserialize_any(NumVisitor)
    }
}

/// A 3-vector `(x, y, z)` of numbers or expressions.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct V3(pub Num, pub Num, pub Num);

impl V3 {
    /// The three components.
    pub fn components(&self) -> [&Num; 3] {
        [&self.0, &self.1, &self.2]
    }

    /// True if all three are literal zeros.
    pub fn is_zero(&self) -> bool {
        self.components().iter().all(|n| n.is_zero())
    }
}

impl<A: Into<Num>, B: Into<Num>, C: Into<Num>> From<(A, B, C)> for V3 {
    fn from((a, b, c): (A, B, C)) -> Self {
        V3(a.into(), b.into(), c.into())
    }
}

/// A whole model file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Model", deny_unknown_fields)]
pub struct Spec {
    /// Model name: a Rust identifier, used for generated items.
    pub name: String,
    /// Gravitational acceleration in world axes, m/s²; absent = no gravity.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<V3>,
    /// Named constants, in order; later ones may use earlier ones.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parameters: Vec<Parameter>,
    /// The rigid bodies (the inertial body is `ground`, never listed).
    pub bodies: Vec<Body>,
    /// The joints; together with `ground` and the bodies they form the
    /// system graph.
    pub joints: Vec<Joint>,
    /// Force elements.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub forces: Vec<Force>,
    /// Constraints that are not joints.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<Constraint>,
    /// What the scene wants computed besides the equations of motion.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub outputs: Vec<Output>,
    /// How masses and inertia tensors are checked (default `Strict`).
    #[serde(default, skip_serializing_if = "InertiaPolicy::is_strict")]
    pub inertia_policy: InertiaPolicy,
    /// Chains of absolute-nodal-coordinate (ANCF) elements: cables and
    /// beams that bend far (issue #18).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cables: Vec<Cable>,
    /// Unilateral contacts (gaps `g(q) ≥ 0` with Newton restitution and
    /// Coulomb friction; issue #26): joint limits, spheres or points
    /// against world planes, spheres against spheres.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub contacts: Vec<Contact>,
    /// Shapes drawn fixed to the ground by `eom-gen animate` (world axes;
    /// a URDF's links welded to the ground).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ground_geometry: Vec<Geometry>,
}

/// A unilateral contact: a gap `g(q) ≥ 0` that the motion may close, then
/// an impact by Newton's law `ġ⁺ = −e ġ⁻` and, if it stays closed, a
/// contact force `λ ≥ 0`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Contact {
    /// End stops of a revolute (rad) or prismatic (m) joint:
    /// `g = q − lower` and `g = upper − q`; at least one of them.
    JointLimit {
        /// Unique contact name.
        name: String,
        /// The joint (revolute or prismatic).
        joint: String,
        /// Lower limit of the joint coordinate.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        lower: Option<Num>,
        /// Upper limit of the joint coordinate.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        upper: Option<Num>,
        /// Newton's coefficient of restitution, `0 ≤ e ≤ 1`.
        e: Num,
        /// Coulomb friction coefficient, `μ ≥ 0` (default 0).
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        mu: Num,
    },
    /// A point (or a sphere of `radius` about it) on a body against a plane
    /// fixed in the world: `g = n·(x − point) − radius`, `n` the unit
    /// normal pointing to the free side.
    Plane {
        /// Unique contact name.
        name: String,
        /// The sphere's centre (or the point): a body point or marker.
        at: Anchor,
        /// Radius of the sphere, m (default 0: a point).
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        radius: Num,
        /// A point of the plane, world axes (or `on`'s), m (default the
        /// origin).
        #[serde(default, skip_serializing_if = "V3::is_zero")]
        point: V3,
        /// The plane's normal, world axes (or `on`'s), towards the free
        /// side.
        normal: V3,
        /// The body the plane is fixed on (default the ground): then
        /// `point` and `normal` are in that body's axes and the plane moves
        /// with it.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        on: Option<String>,
        /// Newton's coefficient of restitution, `0 ≤ e ≤ 1`.
        e: Num,
        /// Coulomb friction coefficient, `μ ≥ 0` (default 0).
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        mu: Num,
    },
    /// Two spheres: `g = |x_a − x_b| − radius_a − radius_b`.
    Spheres {
        /// Unique contact name.
        name: String,
        /// Centre of the first sphere: a body point or marker.
        a: Anchor,
        /// Centre of the second sphere (`ground` allowed).
        b: Anchor,
        /// Radius of the first sphere, m.
        radius_a: Num,
        /// Radius of the second sphere, m.
        radius_b: Num,
        /// Newton's coefficient of restitution, `0 ≤ e ≤ 1`.
        e: Num,
        /// Coulomb friction coefficient, `μ ≥ 0` (default 0).
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        mu: Num,
    },
}

impl Contact {
    /// The contact's name.
    pub fn name(&self) -> &str {
        match self {
            Contact::JointLimit { name, .. }
            | Contact::Plane { name, .. }
            | Contact::Spheres { name, .. } => name,
        }
    }
}

/// A chain of ANCF elements on the straight line between two points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cable {
    /// Unique name.
    pub name: String,
    /// The element type (the generated kernel).
    pub element: crate::ancf::Kind,
    /// First end, world axes, m.
    pub from: V3,
    /// Second end, world axes, m.
    pub to: V3,
    /// Number of elements (nodes `0..=elements`).
    pub elements: usize,
    /// Young's modulus `E`, Pa.
    pub young: Num,
    /// Density `ρ`, kg/m³.
    pub density: Num,
    /// Section area `A`, m² (default `width · height`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area: Option<Num>,
    /// Second moment of area `I` for bending, m⁴ (default
    /// `width · height³ / 12`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub second_moment: Option<Num>,
    /// Width of a rectangular section (out of the bending plane), m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<Num>,
    /// Height of a rectangular section (in the bending plane), m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<Num>,
    /// Poisson's ratio (the continuum beam `Beam2D`).
    #[serde(default, skip_serializing_if = "Num::is_zero")]
    pub poisson: Num,
    /// Axial Kelvin–Voigt damping (cables), N s.
    #[serde(default, skip_serializing_if = "Num::is_zero")]
    pub damping_axial: Num,
    /// Bending Kelvin–Voigt damping (cables), N m² s.
    #[serde(default, skip_serializing_if = "Num::is_zero")]
    pub damping_bending: Num,
    /// Kelvin–Voigt retardation time (`Beam2D`), s.
    #[serde(default, skip_serializing_if = "Num::is_zero")]
    pub retardation: Num,
    /// How the first end is held.
    pub start: CableEnd,
    /// How the second end is held.
    #[serde(default, skip_serializing_if = "CableEnd::is_free")]
    pub end: CableEnd,
    /// The first end held (as `start` says: pinned or clamped) at a marker
    /// of a rigid body instead of to ground.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_at: Option<CableMount>,
    /// The second end held at a marker of a rigid body.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_at: Option<CableMount>,
    /// A constant force on the second end, world axes, N.
    #[serde(default, skip_serializing_if = "V3::is_zero")]
    pub end_force: V3,
    /// A point mass on the second end (a bob), kg.
    #[serde(default, skip_serializing_if = "Num::is_zero")]
    pub end_mass: Num,
    /// A dead load per unit reference length on every element, world
    /// axes, N/m (besides gravity's `ρ A g`).
    #[serde(default, skip_serializing_if = "V3::is_zero")]
    pub distributed_load: V3,
    /// Constant (dead) forces on nodes of the chain, world axes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub node_forces: Vec<NodeForce>,
    /// Initial velocity: the cable starts as a rigid body moving with
    /// this velocity of its `from` point, world axes, m/s.
    #[serde(default, skip_serializing_if = "V3::is_zero")]
    pub velocity: V3,
    /// Initial angular velocity of that rigid motion about the `from`
    /// point, world axes, rad/s.
    #[serde(default, skip_serializing_if = "V3::is_zero")]
    pub angular_velocity: V3,
}

/// A constant force on one node of a cable.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeForce {
    /// The node, `0..=elements` (node `j` at `from + j/elements · (to − from)`).
    pub node: usize,
    /// The force, world axes, N.
    pub force: V3,
}

/// Where a cable end is held on a rigid body: a marker, and for a clamped
/// end the direction (marker axes) along which the cable leaves it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CableMount {
    /// The rigid body.
    pub body: String,
    /// Its marker: the end node stays at the marker's origin.
    pub marker: String,
    /// Clamped ends: the cable's tangent at the end, in the marker's axes
    /// (it stays parallel to this direction as the body turns).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<V3>,
}

/// How an end of a cable is held.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum CableEnd {
    /// Not held.
    #[default]
    Free,
    /// Held in place, free to turn.
    Pinned,
    /// Held in place and in direction.
    Clamped,
}

impl CableEnd {
    /// True for [`CableEnd::Free`].
    pub fn is_free(&self) -> bool {
        *self == CableEnd::Free
    }
}

/// How a model's masses and inertia tensors are checked (see
/// `docs/model-format.md`, "Inertia policy").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum InertiaPolicy {
    /// Every body has a positive mass; a tensor that is not positive
    /// semi-definite or violates the triangle inequality is an error. The
    /// default, for models written by hand.
    #[default]
    Strict,
    /// As measured data comes (the URDF importer writes it): a physically
    /// inconsistent tensor is a warning, a body may have zero mass, and
    /// what must hold — a positive definite mass matrix at the initial
    /// state — is checked numerically.
    Lenient,
}

impl InertiaPolicy {
    /// True for [`InertiaPolicy::Strict`].
    pub fn is_strict(&self) -> bool {
        *self == InertiaPolicy::Strict
    }
}

/// A named constant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Parameter {
    /// Name used in expressions.
    pub name: String,
    /// Value (an expression over earlier parameters is allowed).
    pub value: Num,
    /// `false` (default): fixed, inlined into generated code.
    /// `true`: a runtime field of the generated parameter struct.
    #[serde(default, skip_serializing_if = "is_false")]
    pub tunable: bool,
    /// Free text (units, source).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub doc: Option<String>,
}

/// A body: rigid, or flexible with a rigid part carried by its frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// Unique name (`ground` is reserved).
    pub name: String,
    /// The name as the user wrote it, when `name` had to become an
    /// identifier (a URDF's `link 1`): shown by `check --json` and
    /// animations.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// Mass, kg (> 0); required for a rigid body, for a flexible one the
    /// mass of a rigid part fixed to its frame (default none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<Num>,
    /// Centre of mass in body axes, m.
    #[serde(default, skip_serializing_if = "V3::is_zero")]
    pub com: V3,
    /// Inertia tensor about the centre of mass in body axes, kg m²;
    /// absent = a point mass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<Inertia>,
    /// Named points and frames on the body.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub markers: Vec<Marker>,
    /// The body deforms: a floating frame of reference with elastic
    /// coordinates (issue #17); absent = rigid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flexible: Option<Flexible>,
    /// What `eom-gen animate` draws of the body (no dynamics: the mass and
    /// inertia are the fields above); absent = links between its joint
    /// frames and centre of mass.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub geometry: Vec<Geometry>,
}

/// A shape drawn for a body by `eom-gen animate`, in a frame of the body
/// (no dynamics). Lengths in m.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Geometry {
    /// A box centred on the frame's origin with edge lengths `size` along
    /// its axes.
    Box {
        /// Edge lengths along the frame's x, y, z (each > 0), m.
        size: V3,
        /// Where the box sits on the body (default: the body frame).
        #[serde(default, skip_serializing_if = "Frame::is_identity")]
        frame: Frame,
        /// Colour `(r, g, b)`, each in `[0, 1]`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        color: Option<(f64, f64, f64)>,
    },
    /// A cylinder along the frame's z axis, centred on its origin.
    Cylinder {
        /// Radius (> 0), m.
        radius: Num,
        /// Length along z (> 0), m.
        length: Num,
        /// Where the cylinder sits on the body (default: the body frame).
        #[serde(default, skip_serializing_if = "Frame::is_identity")]
        frame: Frame,
        /// Colour `(r, g, b)`, each in `[0, 1]`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        color: Option<(f64, f64, f64)>,
    },
    /// A sphere centred on the frame's origin.
    Sphere {
        /// Radius (> 0), m.
        radius: Num,
        /// Where the sphere sits on the body (default: the body frame).
        #[serde(default, skip_serializing_if = "Frame::is_identity")]
        frame: Frame,
        /// Colour `(r, g, b)`, each in `[0, 1]`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        color: Option<(f64, f64, f64)>,
    },
    /// A triangle mesh read from a file (STL binary or ASCII, OBJ, COLLADA
    /// `.dae` with its unit and up axis applied), its vertices in the
    /// frame's axes times `scale`.
    Mesh {
        /// The mesh file, relative to this model file (a URDF's
        /// `package://` paths are resolved on import).
        file: String,
        /// Scale per axis (each ≠ 0; default `(1, 1, 1)`): a mesh in mm
        /// is scaled by 0.001.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        scale: Option<V3>,
        /// Where the mesh's origin sits on the body (default: the body
        /// frame).
        #[serde(default, skip_serializing_if = "Frame::is_identity")]
        frame: Frame,
        /// Colour `(r, g, b)`, each in `[0, 1]`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        color: Option<(f64, f64, f64)>,
    },
}

/// How a flexible body deforms (floating frame of reference, Shabana ch. 5–6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Flexible {
    /// A straight Euler–Bernoulli beam along the body `x` axis from the
    /// origin to `x = length`, discretised by `elements` finite elements and
    /// reduced to its `modes` lowest normal modes under `reference`.
    Beam {
        /// Length `L`, m.
        length: Num,
        /// Mass per length `ρA`, kg/m.
        rho_a: Num,
        /// Polar mass moment per length `ρI_p`, kg m (torsion inertia).
        rho_ip: Num,
        /// Axial stiffness `EA`, N.
        ea: Num,
        /// Bending stiffness about `y` (bending in the `x–z` plane), N m².
        ei_y: Num,
        /// Bending stiffness about `z` (bending in the `x–y` plane), N m².
        ei_z: Num,
        /// Torsional stiffness `GJ`, N m².
        gj: Num,
        /// Number of finite elements (nodes `0..=elements`).
        elements: usize,
        /// What fixes the body frame in the deforming beam.
        reference: BeamReference,
        /// Number of elastic coordinates `k` (lowest modes kept).
        modes: usize,
        /// Geometric stiffening by the centrifugal axial load.
        #[serde(default, skip_serializing_if = "is_false")]
        stiffening: bool,
        /// Modal damping ratio `ζ` of every mode (dimensionless).
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        damping: Num,
        /// Named nodes, where markers and joints may attach (each at a
        /// finite-element node).
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        nodes: Vec<BeamNode>,
        /// Craig–Bampton reduction: one static constraint mode per free
        /// degree of freedom of each named node, then `modes`
        /// fixed-interface normal modes (instead of `modes` normal modes).
        #[serde(default, skip_serializing_if = "is_false")]
        craig_bampton: bool,
        /// Shear deformation and rotary inertia of the sections
        /// (Timoshenko); absent = Euler–Bernoulli.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        shear: Option<BeamShear>,
    },
    /// Assumed modes (Rayleigh–Ritz; Shabana 5.1): a straight slender body
    /// along the body `x` axis from the origin to `x = length`, whose
    /// deformation is `Σ_j q_fj S_j(x)` with shape functions written as
    /// expressions of the body coordinate `x` (and parameters).
    AssumedModes {
        /// Length `L`, m.
        length: Num,
        /// Mass per length `ρA`, kg/m.
        rho_a: Num,
        /// Polar mass moment per length `ρI_p`, kg m (torsion inertia).
        rho_ip: Num,
        /// Axial stiffness `EA`, N.
        ea: Num,
        /// Bending stiffness about `y` (bending in the `x–z` plane), N m².
        ei_y: Num,
        /// Bending stiffness about `z` (bending in the `x–y` plane), N m².
        ei_z: Num,
        /// Torsional stiffness `GJ`, N m².
        gj: Num,
        /// The shape functions, one per elastic coordinate.
        shapes: Vec<AssumedShape>,
        /// Geometric stiffening by the centrifugal axial load.
        #[serde(default, skip_serializing_if = "is_false")]
        stiffening: bool,
        /// Damping ratio `ζ` of every normal mode of the reduced body.
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        damping: Num,
        /// Named nodes, where markers and joints may attach: any place
        /// `0 ≤ x ≤ length` on the axis (node `i` is the `i`-th listed).
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        nodes: Vec<BeamNode>,
    },
    /// Modal data imported from an external finite-element model: a RON or
    /// JSON file (`ModalData(…)`, see `docs/model-format.md`) with nodes,
    /// lumped masses, mode shapes at the nodes and the modal matrices.
    Modal {
        /// The file, relative to the model file's directory.
        file: String,
        /// Damping ratio `ζ` of every normal mode of the reduced body, on top
        /// of the file's damping matrix.
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        damping: Num,
        /// Geometric stiffening by the axial inertia loads, from the file's
        /// `geometric_stiffness` (required then).
        #[serde(default, skip_serializing_if = "is_false")]
        stiffening: bool,
    },
}

/// One assumed shape function: the axial, lateral and torsional parts of
/// the deformation it describes, each an expression of `x` (m) and the
/// parameters; absent parts are zero.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AssumedShape {
    /// Axial displacement `u(x)`, m per unit coordinate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u: Option<Num>,
    /// Lateral displacement along `y`, `v(x)` (bending with `EI_z`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v: Option<Num>,
    /// Lateral displacement along `z`, `w(x)` (bending with `EI_y`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub w: Option<Num>,
    /// Torsion angle `φ(x)` about `x`, rad per unit coordinate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phi: Option<Num>,
}

/// One of the six degrees of freedom of a beam node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum NodeDofName {
    /// Axial translation `u_x`.
    Ux,
    /// Translation `u_y`.
    Uy,
    /// Translation `u_z`.
    Uz,
    /// Torsion `θ_x`.
    Rx,
    /// Bending rotation `θ_y`.
    Ry,
    /// Bending rotation `θ_z`.
    Rz,
}

/// Degrees of freedom of one beam node held at zero (a `Fixed` reference).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixedNode {
    /// The node, `0..=elements`.
    pub node: usize,
    /// Its degrees of freedom that do not deform.
    pub dofs: Vec<NodeDofName>,
}

/// A named node of a built-in beam.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamNode {
    /// Name, unique on its body.
    pub name: String,
    /// Place along the beam, m from the body origin; must be a
    /// finite-element node, `i · length / elements`.
    pub x: Num,
}

/// A node of a flexible body: by name (`"tip"`, from the beam's `nodes`)
/// or by finite-element index (`3`; node `i` at `x = i · length / elements`).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum NodeRef {
    /// A finite-element node index.
    Index(usize),
    /// A named node.
    Name(String),
}

impl std::fmt::Display for NodeRef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NodeRef::Index(i) => write!(f, "{i}"),
            NodeRef::Name(n) => write!(f, "`{n}`"),
        }
    }
}

/// Shear deformation of a built-in beam.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum BeamShear {
    /// Timoshenko's beam: sections rotate independently of the axis' slope,
    /// resisted by the shear stiffnesses, and carry rotary inertia.
    Timoshenko {
        /// Effective shear stiffness for shear along `y` (bending in the
        /// `x–y` plane, with `ei_z`), `κ_y G A`, N.
        kga_y: Num,
        /// Effective shear stiffness for shear along `z` (bending in the
        /// `x–z` plane, with `ei_y`), `κ_z G A`, N.
        kga_z: Num,
        /// Rotary inertia per length about `y`, `ρI_y`, kg m (≥ 0);
        /// absent = `rho_a · ei_y / ea` (a homogeneous section).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rho_iy: Option<Num>,
        /// Rotary inertia per length about `z`, `ρI_z`, kg m (≥ 0);
        /// absent = `rho_a · ei_z / ea` (a homogeneous section).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rho_iz: Option<Num>,
    },
}

/// Reference conditions of a built-in beam (Shabana 6.2).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum BeamReference {
    /// The tangent frame: node 0 neither moves nor rotates (clamped–free modes).
    Clamped,
    /// The chord frame: both ends pinned, node 0 fixed axially and in torsion.
    PinnedPinned,
    /// The mean axis: the deformation carries no linear or angular momentum
    /// (free–free modes).
    MeanAxis,
    /// These nodal degrees of freedom are zero; they must leave no rigid
    /// motion of the whole beam free.
    Fixed(Vec<FixedNode>),
}

/// An inertia tensor about the centre of mass, in body axes, kg m².
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Inertia {
    /// Principal moments `(Ixx, Iyy, Izz)` along the body axes.
    Diag(Num, Num, Num),
    /// The full symmetric tensor by rows (off-diagonal entries are tensor
    /// entries, i.e. minus the products of inertia).
    Matrix(V3, V3, V3),
}

/// A named point (and frame) on a body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Marker {
    /// Name, unique on its body.
    pub name: String,
    /// Position in body axes, m.
    #[serde(default, skip_serializing_if = "V3::is_zero")]
    pub position: V3,
    /// Orientation of the marker frame relative to the body.
    #[serde(default, skip_serializing_if = "Orientation::is_identity")]
    pub orientation: Orientation,
    /// On a flexible body: the node the marker is attached to (it moves
    /// with that node's deformation: its translation and small rotation);
    /// `position` and `orientation` are then relative to the node's
    /// deformed frame (axes parallel to the body's when undeformed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node: Option<NodeRef>,
}

/// A rotation: how a frame's axes sit in its reference frame's axes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Orientation {
    /// No rotation.
    #[default]
    Identity,
    /// Right-handed rotation by `angle` (rad) about `axis` (any length > 0).
    AxisAngle {
        /// The axis.
        axis: V3,
        /// The angle, rad.
        angle: Num,
    },
    /// Roll, pitch, yaw (rad) about fixed x, y, z: `R = Rz(yaw) Ry(pitch) Rx(roll)`,
    /// as in URDF.
    Rpy(Num, Num, Num),
    /// Rotation matrix by rows; its columns are the frame's axes in the
    /// reference frame. Must be orthonormal with determinant +1.
    Matrix(V3, V3, V3),
}

impl Orientation {
    /// True for [`Orientation::Identity`].
    pub fn is_identity(&self) -> bool {
        *self == Orientation::Identity
    }
}

/// A frame fixed on a body: position and orientation in body axes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frame {
    /// Origin in body axes, m.
    #[serde(default, skip_serializing_if = "V3::is_zero")]
    pub position: V3,
    /// Orientation relative to the body axes.
    #[serde(default, skip_serializing_if = "Orientation::is_identity")]
    pub orientation: Orientation,
}

impl Frame {
    /// True for the body frame itself.
    pub fn is_identity(&self) -> bool {
        self.position.is_zero() && self.orientation.is_identity()
    }
}

/// The kind of a joint, with its axes in joint-frame axes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum JointKind {
    /// Rotation about `axis`: one coordinate, the angle (rad).
    Revolute {
        /// Rotation axis.
        axis: V3,
    },
    /// Translation along `axis`: one coordinate, the displacement (m).
    Prismatic {
        /// Translation axis.
        axis: V3,
    },
    /// Rotation about and translation along `axis`: (angle, displacement).
    Cylindrical {
        /// The common axis.
        axis: V3,
    },
    /// Cardan joint: rotation about `axis1`, then about `axis2` as carried
    /// by the first rotation: (angle1, angle2).
    Universal {
        /// First axis (fixed in the parent joint frame).
        axis1: V3,
        /// Second axis (fixed in the child joint frame).
        axis2: V3,
    },
    /// Ball joint: unit quaternion `(w, x, y, z)`, angular velocity in child axes.
    Spherical,
    /// Translation along joint-frame x and y, rotation about z: (x, y, angle).
    Planar,
    /// Six degrees of freedom: translation (parent axes) then quaternion;
    /// speeds are linear then angular velocity, both in child axes.
    Free,
    /// Rotation about `axis` with translation `pitch * angle` along it.
    Screw {
        /// The screw axis.
        axis: V3,
        /// Lead per radian, m/rad.
        pitch: Num,
    },
    /// No relative motion.
    Fixed,
}

impl JointKind {
    /// Numbers of position coordinates and speeds.
    pub fn dims(&self) -> (usize, usize) {
        match self {
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } | JointKind::Screw { .. } => {
                (1, 1)
            }
            JointKind::Cylindrical { .. } | JointKind::Universal { .. } => (2, 2),
            JointKind::Planar => (3, 3),
            JointKind::Spherical => (4, 3),
            JointKind::Free => (7, 6),
            JointKind::Fixed => (0, 0),
        }
    }

    /// Lower-case name.
    pub fn name(&self) -> &'static str {
        match self {
            JointKind::Revolute { .. } => "revolute",
            JointKind::Prismatic { .. } => "prismatic",
            JointKind::Cylindrical { .. } => "cylindrical",
            JointKind::Universal { .. } => "universal",
            JointKind::Spherical => "spherical",
            JointKind::Planar => "planar",
            JointKind::Free => "free",
            JointKind::Screw { .. } => "screw",
            JointKind::Fixed => "fixed",
        }
    }
}

/// A joint between two bodies.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Joint {
    /// Unique name.
    pub name: String,
    /// The name as the user wrote it, when `name` had to become an
    /// identifier (a URDF's `joint_0.0`): shown by `check --json`, plots
    /// and animations.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// Kind and axes.
    pub kind: JointKind,
    /// Parent body (`ground` is the inertial body).
    pub parent: String,
    /// Child body.
    pub child: String,
    /// Joint frame on the parent, in parent body axes.
    #[serde(default, skip_serializing_if = "Frame::is_identity")]
    pub parent_frame: Frame,
    /// On a flexible parent: the node the joint is attached to
    /// (`parent_frame` is then relative to the node's deformed frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parent_node: Option<NodeRef>,
    /// Joint frame on the child, in child body axes; it coincides with the
    /// parent joint frame when all coordinates are zero.
    #[serde(default, skip_serializing_if = "Frame::is_identity")]
    pub child_frame: Frame,
    /// On a flexible child of a cut joint: the node the joint is attached
    /// to (`child_frame` is then relative to the node's deformed frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub child_node: Option<NodeRef>,
    /// Names of the position coordinates (default: derived from the joint name).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coordinates: Option<Vec<String>>,
    /// Names of the speeds (default: derived from the coordinate names).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub speeds: Option<Vec<String>>,
    /// Initial positions, one per coordinate (default: zero, identity quaternion).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub q0: Option<Vec<Num>>,
    /// Initial speeds, one per speed (default: zero).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u0: Option<Vec<Num>>,
    /// Held at `q0`: the joint contributes no coordinates.
    #[serde(default, skip_serializing_if = "is_false")]
    pub locked: bool,
    /// Prescribed motion: one expression of `t` per coordinate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prescribed: Option<Vec<Num>>,
    /// Cut this joint if it closes a loop (otherwise the graph chooses).
    #[serde(default, skip_serializing_if = "is_false")]
    pub cut: bool,
}

/// A point on a body: by position or by marker name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Anchor {
    /// The body (`ground` allowed).
    pub body: String,
    /// Position in body axes, m (default: the body origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<V3>,
    /// A marker of the body instead of `point`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub marker: Option<String>,
    /// A contact's cable node instead: `body` then names a cable and this
    /// is its node, `0..=elements` (as `node_forces` and the CSV's
    /// `CABLE.nodeK` count them).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node: Option<usize>,
}

/// A force element.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Force {
    /// Linear spring and damper between two points:
    /// `F = k (L - rest_length) + c dL/dt` along the line.
    SpringDamper {
        /// Unique force name.
        name: String,
        /// First end.
        a: Anchor,
        /// Second end.
        b: Anchor,
        /// Stiffness k, N/m.
        stiffness: Num,
        /// Damping c, N s/m.
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        damping: Num,
        /// Rest length, m.
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        rest_length: Num,
    },
    /// Spring and damper on every coordinate of a joint:
    /// `τ = -k (q - rest) - c q̇` (N m/rad or N/m).
    JointSpringDamper {
        /// Unique force name.
        name: String,
        /// The joint.
        joint: String,
        /// Stiffness.
        stiffness: Num,
        /// Damping.
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        damping: Num,
        /// Rest position.
        #[serde(default, skip_serializing_if = "Num::is_zero")]
        rest: Num,
    },
    /// Known generalised forces on a joint, one per speed: expressions of
    /// parameters, `t`, coordinates and speeds.
    JointForce {
        /// Unique force name.
        name: String,
        /// The joint.
        joint: String,
        /// One value per speed of the joint.
        values: Vec<Num>,
    },
    /// Runtime inputs acting as generalised forces on a joint, one per speed.
    Actuator {
        /// Unique force name.
        name: String,
        /// The joint.
        joint: String,
        /// Input names (default: `<name>` for one speed, `<name>_<k>` for more).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        inputs: Option<Vec<String>>,
    },
}

/// A constraint that is not a joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Constraint {
    /// A thin disk or wheel rolling without slipping on the ground plane
    /// `z = 0` (world +z up): contact point at rest (nonholonomic).
    RollingDisk {
        /// Unique constraint name.
        name: String,
        /// The disk's body.
        body: String,
        /// Radius, m.
        radius: Num,
        /// Disk axis (normal of the disk plane) in body axes.
        axis: V3,
        /// Disk centre in body axes (default: the body origin).
        #[serde(default, skip_serializing_if = "V3::is_zero")]
        center: V3,
    },
    /// `expr = 0`, an expression of coordinates, parameters and `t`.
    Holonomic {
        /// Unique constraint name.
        name: String,
        /// The constraint function.
        expr: String,
    },
}

/// A quantity the scene wants computed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Output {
    /// Position of a marker in world axes.
    Position {
        /// The body.
        body: String,
        /// The marker.
        marker: String,
    },
    /// Velocity of a marker in world axes.
    Velocity {
        /// The body.
        body: String,
        /// The marker.
        marker: String,
    },
    /// Reaction force and torque transmitted by a joint.
    JointReaction {
        /// The joint.
        joint: String,
    },
    /// Kinetic and potential energy.
    Energy,
    /// Linear and angular momentum (about the world origin).
    Momentum,
    /// Elastic displacement `(u_x, u_y, u_z)` and small rotation
    /// `(θ_x, θ_y, θ_z)` of the section at `x` of a flexible beam, in its
    /// body axes: outputs `<name>_ux … <name>_rz`.
    Deformation {
        /// Prefix of the output names (an identifier).
        name: String,
        /// The flexible body.
        body: String,
        /// Where along the beam, m (`0 ≤ x ≤ L`; parameters only).
        x: Num,
    },
    /// Stress resultants at the section `x` of a flexible beam from the FE
    /// interpolation, body axes, acting on the part `[0, x]` from the part
    /// beyond: `N = EA u_x'`, `Q_y = −EI_z u_y'''`, `Q_z = −EI_y u_z'''`,
    /// `M_x = GJ θ_x'`, `M_y = −EI_y u_z''`, `M_z = EI_z u_y''`; outputs
    /// `<name>_N, <name>_Qy, <name>_Qz, <name>_Mx, <name>_My, <name>_Mz`.
    SectionForces {
        /// Prefix of the output names (an identifier).
        name: String,
        /// The flexible body.
        body: String,
        /// Where along the beam, m (`0 ≤ x ≤ L`; parameters only).
        x: Num,
    },
    /// World position of a node of a flexible beam, deformation included:
    /// outputs `<body>_node<k>_x`, `_y`, `_z`.
    NodePosition {
        /// The flexible body.
        body: String,
        /// The node (0 at the body origin … `elements` at the tip).
        node: usize,
    },
    /// Strain energy `½ q_fᵀ K_ff q_f` of a flexible body (J): output
    /// `<body>_strain_energy` (the potential energy of `Energy` includes it).
    ElasticEnergy {
        /// The flexible body.
        body: String,
    },
}

fn is_false(b: &bool) -> bool {
    !*b
}
