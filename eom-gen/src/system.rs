//! The validated multibody system: typed, index-based and immutable.
//!
//! Built only by [`crate::model::check`], so every name resolves, every
//! number is finite, and the graph has a spanning tree. Quantities keep
//! their expression (tunable parameters stay symbolic for the formulation
//! stage), their value at the parameters' defaults, and their span in the
//! model file; parameters, bodies, joints, forces and constraints keep the
//! span of their definition (so later stages can still point at the line
//! that caused a problem).
//!
//! Below the model in the pipeline: it uses only the leaf modules
//! [`crate::diag`] (spans), [`crate::expr`] (expressions), [`crate::flex`]
//! (the numeric beam, modes and invariants of flexible bodies) and the
//! [`crate::graph`].

use crate::diag::Span;
use crate::expr::Ast;
use crate::flex::{Beam, Invariants, Modes, Reference};
use crate::graph::{BodyId, Graph, JointId};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// An expression from the model with its value at the default parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Quantity {
    /// The expression, over parameter names (and `t` or coordinates where
    /// the field allows them).
    pub expr: Ast,
    /// Its value with every parameter at its default (and `t`, coordinates
    /// and speeds at zero where they occur).
    pub value: f64,
    /// Where it is written.
    pub span: Span,
}

/// A 3-vector of quantities.
pub type Vec3Q = [Quantity; 3];

/// Values of a vector of quantities.
pub fn values(v: &Vec3Q) -> Vector3<f64> {
    Vector3::new(v[0].value, v[1].value, v[2].value)
}

/// A named parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Name.
    pub name: String,
    /// Value or defining expression (over earlier parameters).
    pub value: Quantity,
    /// A runtime field (`true`) or inlined (`false`).
    pub tunable: bool,
    /// The model's `doc` text (for the generated field's doc comment).
    pub doc: Option<String>,
    /// Where its name is written.
    pub span: Span,
}

/// An orientation as written, with its rotation matrix at the defaults.
#[derive(Clone, Debug, PartialEq)]
pub enum Rotation {
    /// No rotation.
    Identity,
    /// `angle` about the unit vector along `axis`.
    AxisAngle {
        /// Axis as written (any length).
        axis: Vec3Q,
        /// Angle, rad.
        angle: Quantity,
    },
    /// `Rz(yaw) Ry(pitch) Rx(roll)`.
    Rpy([Quantity; 3]),
    /// Rows of the matrix.
    Matrix([Vec3Q; 3]),
}

/// A frame on a body.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameInfo {
    /// Origin in body axes.
    pub position: Vec3Q,
    /// Orientation as written.
    pub rotation: Rotation,
    /// Rotation matrix at the defaults (columns: frame axes in body axes).
    pub matrix: Matrix3<f64>,
}

/// A marker on a body.
#[derive(Clone, Debug, PartialEq)]
pub struct MarkerInfo {
    /// Name.
    pub name: String,
    /// The frame.
    pub frame: FrameInfo,
    /// On a flexible body, the beam node it is attached to (its frame is
    /// then relative to the node's deformed frame).
    pub node: Option<usize>,
}

/// The deformable part of a flexible body (floating frame of reference,
/// Shabana ch. 5–6): the beam, its reduced modes and their inertia shape
/// integrals, all computed at the parameters' defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct FlexInfo {
    /// The beam's data as written (length, `ρA`, `ρI_p`, `EA`, `EI_y`,
    /// `EI_z`, `GJ`), in that order; then a Timoshenko beam's shear data
    /// as written; then for a beam its named nodes' `x`, for assumed modes
    /// the shape expressions; none for imported data. The six section data
    /// may be tunable (see `shares`) unless the beam is a Timoshenko beam;
    /// the length, the shear data, the nodes and the shapes may not.
    pub written: Vec<Quantity>,
    /// The shares of the reduced matrices per section datum, which make
    /// tunable section data exact for the kept basis (`None` for imported
    /// data, which have no section data).
    pub shares: Option<crate::flex::invariants::Shares>,
    /// Where the shape functions come from. `beam`, `reference` and
    /// `modes.shapes` describe a built-in beam only for [`FlexSource::Beam`].
    pub source: FlexSource,
    /// The beam at the defaults (for assumed modes the section data, with
    /// `elements` 1; for imported data a placeholder: see `source`).
    pub beam: Beam,
    /// Its reference conditions.
    pub reference: Reference,
    /// The reduced basis (normal modes).
    pub modes: Modes,
    /// The inertia shape integrals of the reduced body.
    pub invariants: Invariants,
    /// Modal damping ratio `ζ`: `D_ff = 2 ζ diag(ω_i)` (mass-normalised modes).
    pub damping: Quantity,
    /// Geometric stiffening by the centrifugal axial load.
    pub stiffening: bool,
    /// Named nodes `(name, node index)`, where markers and joints attach.
    pub nodes: Vec<(String, usize)>,
    /// Names of the elastic coordinates (`<body>_f1 …`).
    pub coordinate_names: Vec<String>,
    /// Names of their rates (`<body>_f1_dot …`).
    pub speed_names: Vec<String>,
    /// First index into the system's `q`.
    pub q_index: usize,
    /// First index into the system's `u`.
    pub u_index: usize,
    /// Where `flexible` is written.
    pub span: Span,
}

impl FlexInfo {
    /// Number of elastic coordinates `k`.
    pub fn count(&self) -> usize {
        self.modes.count()
    }

    /// For assumed modes and imported data, the damping matrix
    /// `D_ff = ζ D_1 + D_0` as `(D_1, D_0)`: `D_1 = M_ff Φ diag(2 ω_i) Φᵀ M_ff`
    /// damps every normal mode of the reduced body by the ratio `ζ`
    /// ([`crate::flex::ritz`]), `D_0` is the imported file's. `None` for the
    /// beam, whose mass-normalised modes take `D_ff = 2 ζ diag(ω_i)`.
    pub fn damping_matrices(&self) -> Option<(&DMatrix<f64>, Option<&DMatrix<f64>>)> {
        match &self.source {
            FlexSource::Beam => None,
            FlexSource::Assumed { damping_unit, .. } => Some((damping_unit, None)),
            FlexSource::Modal {
                damping_unit,
                damping,
                ..
            } => Some((damping_unit, Some(damping))),
        }
    }

    /// For assumed modes and imported data, the foreshortening matrices
    /// `(K₁, K₂)`: the geometric stiffness per `Ω²` of the centrifugal load
    /// and per unit axial acceleration of the root (the beam's are computed
    /// from its FE model, [`crate::flex::invariants::foreshortening`]; an
    /// imported file's are its `geometric_stiffness`, if given).
    pub fn assumed_geometric_stiffness(&self) -> Option<(&DMatrix<f64>, &DMatrix<f64>)> {
        match &self.source {
            FlexSource::Assumed {
                geometric,
                axial_geometric,
                ..
            } => Some((geometric, axial_geometric)),
            FlexSource::Modal {
                geometric: Some((k1, k2)),
                ..
            } => Some((k1, k2)),
            _ => None,
        }
    }

    /// Translation and small rotation of the section at `x` along the body
    /// axis per elastic coordinate (3×k each): the FE interpolation for a
    /// beam, the shape functions for assumed modes; `None` for imported
    /// data (no sections between nodes; see [`FlexInfo::node_position`] and
    /// `modes.at_node`) and where a shape is not finite.
    pub fn section_at(&self, x: f64) -> Option<crate::flex::Section> {
        match &self.source {
            FlexSource::Beam => Some(self.beam.section(x, &self.modes.shapes)),
            FlexSource::Assumed { shapes, .. } => crate::flex::assumed::section(shapes, x),
            FlexSource::Modal { .. } => None,
        }
    }

    /// Undeformed position of node `node` in body axes: on the beam axis for
    /// a beam and for assumed modes (their named nodes), from the file for
    /// imported data.
    pub fn node_position(&self, node: usize) -> Option<Vector3<f64>> {
        match &self.source {
            FlexSource::Beam => {
                (node < self.beam.nodes()).then(|| Vector3::new(self.beam.node_x(node), 0.0, 0.0))
            }
            FlexSource::Assumed { node_x, .. } => {
                node_x.get(node).map(|&x| Vector3::new(x, 0.0, 0.0))
            }
            FlexSource::Modal { positions, .. } => positions.get(node).copied(),
        }
    }

    /// The undeformed place of node `node` in body axes, m: the beam's
    /// nodes lie along `x`, `length / elements` apart; assumed modes' named
    /// nodes where they are named; imported nodes where the file puts them.
    pub fn node_place(&self, node: usize) -> [f64; 3] {
        match &self.source {
            FlexSource::Modal { positions, .. } => {
                positions.get(node).map_or([0.0; 3], |p| [p.x, p.y, p.z])
            }
            FlexSource::Assumed { node_x, .. } => {
                [node_x.get(node).copied().unwrap_or(0.0), 0.0, 0.0]
            }
            FlexSource::Beam => [
                node as f64 * self.beam.length / self.beam.elements as f64,
                0.0,
                0.0,
            ],
        }
    }
}

/// Where a flexible body's shape functions come from.
#[derive(Clone, Debug, PartialEq)]
pub enum FlexSource {
    /// The built-in beam's normal modes.
    Beam,
    /// Assumed modes (Rayleigh–Ritz): shape functions of `x` written in the
    /// model; `modes.shapes` holds the shapes at the named nodes (`6N × k`,
    /// the beam's layout: `u, v, w, φ, −w', v'`), node `i` the `i`-th named.
    Assumed {
        /// The shapes as functions of `x` (for sections and attachments).
        shapes: Vec<crate::flex::assumed::ShapeExprs>,
        /// Where the named nodes sit on the axis, m, in node order.
        node_x: Vec<f64>,
        /// `K_G1`, the geometric stiffness per `Ω²` (k×k).
        geometric: DMatrix<f64>,
        /// `K₂`, the geometric stiffness per unit axial acceleration (k×k).
        axial_geometric: DMatrix<f64>,
        /// `D_1`: damping per unit ratio ζ (k×k).
        damping_unit: DMatrix<f64>,
    },
    /// Modal data imported from a file; `modes.shapes` holds the nodal
    /// shapes (`6N × k`, the beam's layout).
    Modal {
        /// The file as found (relative to the working directory).
        path: String,
        /// Node positions, body axes, m.
        positions: Vec<Vector3<f64>>,
        /// Node names (`None` where unnamed).
        names: Vec<Option<String>>,
        /// `D_1`: damping per unit ratio ζ (k×k).
        damping_unit: DMatrix<f64>,
        /// `D_0`: the file's damping matrix (k×k, zeros if none).
        damping: DMatrix<f64>,
        /// The file's foreshortening matrices `(K₁, K₂)`, if given.
        geometric: Option<(DMatrix<f64>, DMatrix<f64>)>,
    },
}

/// A body; index 0 is ground.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyInfo {
    /// Name (`ground` for body 0).
    pub name: String,
    /// The name as written, if the model gives one (`label`).
    pub label: Option<String>,
    /// Mass, kg (zero for ground).
    pub mass: Option<Quantity>,
    /// Centre of mass in body axes, m.
    pub com: Option<Vec3Q>,
    /// Inertia about the centre of mass by rows; `None` for a point mass.
    pub inertia: Option<[Vec3Q; 3]>,
    /// Markers.
    pub markers: Vec<MarkerInfo>,
    /// The deformable part of a flexible body; `None` for a rigid one
    /// (whose `mass`, `com` and `inertia` are then the whole body).
    pub flexible: Option<Box<FlexInfo>>,
    /// What an animation draws of it (for ground: the model's
    /// `ground_geometry`).
    pub geometry: Vec<GeometryInfo>,
    /// Where the body is defined.
    pub span: Span,
}

/// A shape drawn for a body (`eom-gen animate`; no dynamics), at the
/// parameters' defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct GeometryInfo {
    /// The shape.
    pub shape: Shape,
    /// Where it sits on the body.
    pub frame: FrameInfo,
    /// Colour `(r, g, b)` in `[0, 1]`, if given.
    pub color: Option<[f64; 3]>,
}

/// A shape of [`GeometryInfo`], lengths in m.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Edge lengths along the frame's axes, centred.
    Box([f64; 3]),
    /// Radius and length along the frame's z, centred.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Length.
        length: f64,
    },
    /// Radius, centred.
    Sphere(f64),
    /// A mesh file.
    Mesh {
        /// The path as written in the model.
        file: String,
        /// The path to read it from (relative to the model file's
        /// directory, or as a URDF import resolved it).
        path: std::path::PathBuf,
        /// Scale per axis.
        scale: [f64; 3],
    },
}

/// A joint kind with its unit axes (as written and normalised at defaults).
#[derive(Clone, Debug, PartialEq)]
pub enum JointType {
    /// Rotation about an axis.
    Revolute(Axis),
    /// Translation along an axis.
    Prismatic(Axis),
    /// Rotation about and translation along an axis.
    Cylindrical(Axis),
    /// Rotation about `0`, then about `1` as carried by the first.
    Universal(Axis, Axis),
    /// Unit quaternion.
    Spherical,
    /// x, y and angle about z of the joint frame.
    Planar,
    /// Translation and quaternion.
    Free,
    /// Rotation about the axis with `pitch * angle` along it.
    Screw(Axis, Quantity),
    /// Rigid connection.
    Fixed,
}

/// A joint axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// As written.
    pub written: Vec3Q,
    /// Unit vector at the defaults.
    pub unit: Vector3<f64>,
}

impl JointType {
    /// Number of position coordinates.
    pub fn nq(&self) -> usize {
        match self {
            JointType::Revolute(_) | JointType::Prismatic(_) | JointType::Screw(..) => 1,
            JointType::Cylindrical(_) | JointType::Universal(..) => 2,
            JointType::Planar => 3,
            JointType::Spherical => 4,
            JointType::Free => 7,
            JointType::Fixed => 0,
        }
    }

    /// Number of speeds (degrees of freedom).
    pub fn nu(&self) -> usize {
        match self {
            JointType::Spherical => 3,
            JointType::Free => 6,
            _ => self.nq(),
        }
    }

    /// Lower-case name as in the model format.
    pub fn name(&self) -> &'static str {
        match self {
            JointType::Revolute(_) => "revolute",
            JointType::Prismatic(_) => "prismatic",
            JointType::Cylindrical(_) => "cylindrical",
            JointType::Universal(..) => "universal",
            JointType::Spherical => "spherical",
            JointType::Planar => "planar",
            JointType::Free => "free",
            JointType::Screw(..) => "screw",
            JointType::Fixed => "fixed",
        }
    }
}

/// How a joint's coordinates are determined.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// Coordinates of the system (tree joints only).
    Free,
    /// Held at `q0`.
    Locked,
    /// Known functions of time, one per coordinate.
    Prescribed(Vec<Quantity>),
    /// A cut joint: its relative motion is constrained, not a coordinate.
    Cut,
}

/// A joint.
#[derive(Clone, Debug, PartialEq)]
pub struct JointInfo {
    /// Name.
    pub name: String,
    /// The name as written, if the model gives one (`label`).
    pub label: Option<String>,
    /// Kind and axes.
    pub kind: JointType,
    /// Parent body.
    pub parent: BodyId,
    /// Child body.
    pub child: BodyId,
    /// Joint frame on the parent (on a node of a flexible parent: relative
    /// to the node's deformed frame).
    pub parent_frame: FrameInfo,
    /// On a flexible parent, the beam node the joint is attached to.
    pub parent_node: Option<usize>,
    /// On a flexible child of a cut joint, the node the joint is attached
    /// to (`child_frame` relative to the node's deformed frame).
    pub child_node: Option<usize>,
    /// Joint frame on the child.
    pub child_frame: FrameInfo,
    /// Names of the joint's position coordinates.
    pub coordinate_names: Vec<String>,
    /// Names of its speeds.
    pub speed_names: Vec<String>,
    /// Initial positions.
    pub q0: Vec<Quantity>,
    /// Initial speeds.
    pub u0: Vec<Quantity>,
    /// Free, locked, prescribed or cut.
    pub motion: Motion,
    /// First index into the system's `q` (meaningful when `motion` is `Free`).
    pub q_index: usize,
    /// First index into the system's `u`.
    pub u_index: usize,
    /// Where the joint is defined.
    pub span: Span,
}

/// What [`System::set_initial_value`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitialValue {
    /// The value was set.
    Set,
    /// The name belongs to a locked, prescribed or cut joint, which has no
    /// coordinates of the model.
    NotFree,
    /// No joint has that coordinate or speed (an elastic coordinate of a
    /// flexible body, or a name the model does not have).
    Unknown,
}

/// A point on a body.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// The body.
    pub body: BodyId,
    /// Position in body axes (at a node: relative to the node's deformed
    /// frame).
    pub position: Vec3Q,
    /// On a flexible body, the beam node the point moves with.
    pub node: Option<usize>,
}

/// A force element, resolved.
#[derive(Clone, Debug, PartialEq)]
pub enum ForceElement {
    /// Point-to-point spring-damper.
    SpringDamper {
        /// First end.
        a: Point,
        /// Second end.
        b: Point,
        /// N/m.
        stiffness: Quantity,
        /// N s/m.
        damping: Quantity,
        /// m.
        rest_length: Quantity,
    },
    /// Spring-damper on every coordinate of a joint.
    JointSpringDamper {
        /// The joint.
        joint: JointId,
        /// Stiffness.
        stiffness: Quantity,
        /// Damping.
        damping: Quantity,
        /// Rest position.
        rest: Quantity,
    },
    /// Known generalised forces, one per speed of the joint.
    JointForce {
        /// The joint.
        joint: JointId,
        /// Values.
        values: Vec<Quantity>,
    },
    /// Runtime inputs, one per speed of the joint.
    Actuator {
        /// The joint.
        joint: JointId,
        /// Indices into the system's inputs, one per speed; `None` where
        /// the input is driven by an expression instead (see
        /// [`crate::model::drive_inputs`]; a `JointForce` carries it).
        inputs: Vec<Option<usize>>,
    },
}

/// A named force element.
#[derive(Clone, Debug, PartialEq)]
pub struct Force {
    /// Name.
    pub name: String,
    /// What it does.
    pub element: ForceElement,
    /// Where it is defined.
    pub span: Span,
}

/// A constraint that is not a joint.
#[derive(Clone, Debug, PartialEq)]
pub enum ConstraintKind {
    /// Disk rolling without slipping on `z = 0`: one holonomic contact
    /// condition and two nonholonomic no-slip conditions.
    RollingDisk {
        /// The disk.
        body: BodyId,
        /// Radius.
        radius: Quantity,
        /// Disk axis in body axes.
        axis: Axis,
        /// Centre in body axes.
        center: Vec3Q,
    },
    /// `expr(q, t) = 0`.
    Holonomic(Quantity),
}

/// A named constraint.
#[derive(Clone, Debug, PartialEq)]
pub struct Constraint {
    /// Name.
    pub name: String,
    /// What it constrains.
    pub kind: ConstraintKind,
    /// Where it is defined.
    pub span: Span,
}

impl Constraint {
    /// (holonomic, nonholonomic) equation counts.
    pub fn equations(&self) -> (usize, usize) {
        match self.kind {
            ConstraintKind::RollingDisk { .. } => (1, 2),
            ConstraintKind::Holonomic(_) => (1, 0),
        }
    }
}

/// A requested output.
#[derive(Clone, Debug, PartialEq)]
pub enum OutputKind {
    /// World position of a marker.
    Position(BodyId, usize),
    /// World velocity of a marker.
    Velocity(BodyId, usize),
    /// Reaction in a joint.
    JointReaction(JointId),
    /// Kinetic and potential energy.
    Energy,
    /// Linear and angular momentum.
    Momentum,
    /// Elastic displacement and small rotation of a beam section (body axes).
    Deformation {
        /// The flexible body.
        body: BodyId,
        /// Where along the beam, m.
        x: f64,
        /// Prefix of the output names.
        name: String,
    },
    /// Stress resultants at a beam section (body axes).
    SectionForces {
        /// The flexible body.
        body: BodyId,
        /// Where along the beam, m.
        x: f64,
        /// Prefix of the output names.
        name: String,
    },
    /// World position of a beam node, deformation included.
    NodePosition {
        /// The flexible body.
        body: BodyId,
        /// The node.
        node: usize,
    },
    /// Strain energy of a flexible body.
    ElasticEnergy(BodyId),
}

/// The Grübler–Kutzbach count of degrees of freedom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grubler {
    /// `dof = λ (n_bodies) − Σ (λ − f_j) − n_holonomic + n_elastic`,
    /// λ = 6 or 3: the rigid-body count plus the flexible bodies' elastic
    /// coordinates.
    pub dof: i64,
    /// `n_elastic`: the elastic coordinates of flexible bodies in `dof`
    /// (each is a degree of freedom of its own).
    pub elastic: i64,
    /// True if every joint keeps the motion in one plane (λ = 3).
    pub planar: bool,
}

/// A validated system.
#[derive(Clone, Debug)]
pub struct System {
    /// Model name.
    pub name: String,
    /// Gravity in world axes, if any.
    pub gravity: Option<Vec3Q>,
    /// Parameters in file order.
    pub parameters: Vec<Parameter>,
    /// Bodies; 0 is ground.
    pub bodies: Vec<BodyInfo>,
    /// Joints in file order.
    pub joints: Vec<JointInfo>,
    /// Graph and spanning tree.
    pub graph: Graph,
    /// Force elements.
    pub forces: Vec<Force>,
    /// Runtime input names (from actuators), in order.
    pub inputs: Vec<String>,
    /// Constraints.
    pub constraints: Vec<Constraint>,
    /// Requested outputs.
    pub outputs: Vec<OutputKind>,
    /// Grübler–Kutzbach count.
    pub grubler: Grubler,
    /// Chains of ANCF elements (issue #18), in file order: solved by the
    /// large-model runtime through `eom_gen::cables` (`chain_spec`), not by generated code.
    pub cables: Vec<CableInfo>,
    /// Unilateral contacts (issue #26), in file order.
    pub contacts: Vec<ContactInfo>,
    /// Contacts at cable nodes (issue #26), in file order: run by the
    /// large-model runtime (`eom_gen::cables::node_contacts`), not by
    /// generated code.
    pub cable_contacts: Vec<CableContactInfo>,
}

/// A cable node (a point, or a sphere of `radius` about it) against a plane
/// fixed in the world, `g = n·(x_node − point) − radius`, or against a
/// sphere fixed in the world or about another node,
/// `g = ‖x_node − x_other‖ − radius` ([`CableTarget`]).
#[derive(Clone, Debug, PartialEq)]
pub struct CableContactInfo {
    /// Name.
    pub name: String,
    /// The cable (index into `System::cables`).
    pub cable: usize,
    /// Its node, `0..=elements`.
    pub node: usize,
    /// Radius of the sphere about the node (for spheres, the sum of both
    /// radii), m.
    pub radius: f64,
    /// What the node touches.
    pub against: CableTarget,
    /// Newton's coefficient of restitution.
    pub e: f64,
    /// Coulomb's friction coefficient, `μ ≥ 0` (0: frictionless).
    pub mu: f64,
    /// Where it is defined.
    pub span: Span,
}

impl CableContactInfo {
    /// The node's position at the start (the cable straight from `from`
    /// to `to`) and the other centre's (a plane's point for a plane).
    /// The node's position at the start (the cable straight from `from`
    /// to `to`), the other centre's (a plane's point for a plane) and the
    /// plane's normal, world axes; `frame` is the body's frame at the start
    /// for a body's plane or sphere (`None` there: not known).
    fn centres_at_start(&self, sys: &System, frame: Option<&BodyFrame>) -> Option<Centres> {
        let x = sys.cable_node_start(self.cable, self.node)?;
        Some(match &self.against {
            CableTarget::Plane { point, normal } => (x, *point, Some(*normal)),
            CableTarget::Sphere { centre } => (x, *centre, None),
            CableTarget::Node { cable, node } => (x, sys.cable_node_start(*cable, *node)?, None),
            CableTarget::BodyPlane { normal, .. } => {
                let f = frame?;
                (x, f.p, Some(f.turn(*normal)))
            }
            CableTarget::BodySphere { .. } => (x, frame?.p, None),
        })
    }

    /// The gap at the start, m (`None` for a cable or node the model does
    /// not have, or a body's geometry without its `frame` at the start).
    pub fn gap_at_start(&self, sys: &System, frame: Option<&BodyFrame>) -> Option<f64> {
        let (x, o, normal) = self.centres_at_start(sys, frame)?;
        let d: [f64; 3] = std::array::from_fn(|k| x[k] - o[k]);
        Some(match normal {
            Some(n) => (0..3).map(|k| n[k] * d[k]).sum::<f64>() - self.radius,
            None => d.iter().map(|x| x * x).sum::<f64>().sqrt() - self.radius,
        })
    }

    /// The line of centres at the start, from the other centre to the
    /// node (the plane's normal for a plane), world axes.
    pub fn line_at_start(&self, sys: &System, frame: Option<&BodyFrame>) -> Option<[f64; 3]> {
        let (x, o, normal) = self.centres_at_start(sys, frame)?;
        Some(normal.unwrap_or_else(|| std::array::from_fn(|k| x[k] - o[k])))
    }
}

/// The node's position, the other centre (a plane's point) and a plane's
/// normal, world axes ([`CableContactInfo::centres_at_start`]).
type Centres = ([f64; 3], [f64; 3], Option<[f64; 3]>);

/// A body's frame at a state, world axes: the world position `p` of a
/// point on the body and the body's axes `e` (`e[i][j]`: world component
/// `i` of body axis `j`), as the generated `contact_frames` gives them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyFrame {
    /// The point's world position, m.
    pub p: [f64; 3],
    /// The body's axes in the world, by rows.
    pub e: [[f64; 3]; 3],
}

impl BodyFrame {
    /// A vector given in the body's axes, in world axes.
    pub fn turn(&self, v: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| (0..3).map(|j| self.e[i][j] * v[j]).sum())
    }
}

/// What a cable node's contact touches.
#[derive(Clone, Debug, PartialEq)]
pub enum CableTarget {
    /// A plane fixed in the world: a point of it (world axes, m) and its
    /// unit normal towards the free side.
    Plane {
        /// A point of the plane, m.
        point: [f64; 3],
        /// The unit normal.
        normal: [f64; 3],
    },
    /// A sphere fixed in the world (`Spheres` with `b` on the ground),
    /// centred at `centre` (world axes, m).
    Sphere {
        /// The centre, m.
        centre: [f64; 3],
    },
    /// A sphere about another cable node (`Spheres` with both at nodes).
    Node {
        /// The other cable (index into `System::cables`).
        cable: usize,
        /// Its node.
        node: usize,
    },
    /// A plane fixed on a body (`Plane` with `on`): a point of it and its
    /// unit normal towards the free side, both in the body's axes; it
    /// moves and turns with the body ([`System::cable_frames`]).
    BodyPlane {
        /// The point of the plane on its body (the frame's point).
        at: Point,
        /// The unit normal, body axes.
        normal: [f64; 3],
    },
    /// A sphere on a body (`Spheres` with `b` on a body): its centre (the
    /// frame's point) and its own radius, m (the contact's `radius` is
    /// the sum of both).
    BodySphere {
        /// The sphere's centre on its body.
        at: Point,
        /// The body's sphere's radius, m.
        radius: f64,
    },
}

impl CableTarget {
    /// The point on a body this target moves with (`None`: fixed in the
    /// world, or a cable node).
    pub fn on_body(&self) -> Option<&Point> {
        match self {
            CableTarget::BodyPlane { at, .. } | CableTarget::BodySphere { at, .. } => Some(at),
            _ => None,
        }
    }
}

/// What a unilateral contact's gap measures.
#[derive(Clone, Debug, PartialEq)]
pub enum ContactKind {
    /// End stops of a one-coordinate joint (revolute, prismatic):
    /// `g = q − lower`, `g = upper − q`.
    JointLimit {
        /// The joint (a tree joint with one coordinate).
        joint: JointId,
        /// Lower limit, if any.
        lower: Option<Quantity>,
        /// Upper limit, if any.
        upper: Option<Quantity>,
    },
    /// A sphere (a point for radius 0) against a plane fixed in the world
    /// or on a body: `g = n·(x − p) − r` (`n`, `p` in world axes).
    Plane {
        /// The sphere's centre.
        at: Point,
        /// Its radius.
        radius: Quantity,
        /// A point of the plane, world axes (or `on`'s).
        point: Vec3Q,
        /// The unit normal towards the free side (at the defaults), world
        /// axes (or `on`'s).
        normal: Axis,
        /// The body the plane is fixed on (0: the ground).
        on: usize,
    },
    /// Two spheres: `g = |x_a − x_b| − r_a − r_b`.
    Spheres {
        /// Centre of the first.
        a: Point,
        /// Centre of the second.
        b: Point,
        /// Radius of the first.
        radius_a: Quantity,
        /// Radius of the second.
        radius_b: Quantity,
        /// The world axis the tangent axes of its friction are taken from
        /// (`t₁ ∝ a − (a·n) n`, `t₂ = n × t₁`, `n` the unit line of centres
        /// from `b` to `a`): the world axis least aligned with `n` at the
        /// initial state (see [`crate::mech::contacts::tangent_axes`]).
        tangent_reference: [f64; 3],
    },
}

/// A validated unilateral contact.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactInfo {
    /// Name.
    pub name: String,
    /// Its gap.
    pub kind: ContactKind,
    /// Newton's coefficient of restitution, in `[0, 1]`.
    pub e: f64,
    /// Coulomb friction coefficient, `≥ 0`.
    pub mu: f64,
    /// Where it is defined.
    pub span: Span,
}

impl ContactInfo {
    /// The names of its gap rows: `name.lower`, `name.upper` for a joint
    /// limit, the contact's name otherwise.
    pub fn rows(&self) -> Vec<String> {
        match &self.kind {
            ContactKind::JointLimit { lower, upper, .. } => [
                lower.as_ref().map(|_| format!("{}.lower", self.name)),
                upper.as_ref().map(|_| format!("{}.upper", self.name)),
            ]
            .into_iter()
            .flatten()
            .collect(),
            _ => vec![self.name.clone()],
        }
    }
}

/// A validated chain of ANCF elements.
#[derive(Clone, Debug, PartialEq)]
pub struct CableInfo {
    /// Its name.
    pub name: String,
    /// Everything the runtime builds it from (values at the parameters'
    /// defaults; gravity from the model). An end held at a marker has the
    /// support `Free` here: the attachment holds it.
    pub chain: ChainInfo,
    /// The first end held at a marker of a rigid body.
    pub start_at: Option<CableMountInfo>,
    /// The second end held at a marker of a rigid body.
    pub end_at: Option<CableMountInfo>,
    /// A dead load per unit reference length on every element, world
    /// axes, N/m (`StructuralModel::add_distributed_load` after building
    /// the chain).
    pub distributed_load: [f64; 3],
    /// Constant forces on nodes: `(node, force)`, world axes, N.
    pub node_forces: Vec<(usize, [f64; 3])>,
    /// The initial rigid motion: velocity of the `from` point (m/s) and
    /// angular velocity about it (rad/s), world axes; zero for rest.
    pub initial_motion: [[f64; 3]; 2],
}

/// A chain of ANCF elements as the runtime builds it (`eom_gen::cables`
/// turns it into the runtime's description).
#[derive(Clone, Debug, PartialEq)]
pub struct ChainInfo {
    /// The element type.
    pub element: crate::ancf::Kind,
    /// First end, world axes, m (planar elements: `z = 0`).
    pub start: [f64; 3],
    /// Second end.
    pub end: [f64; 3],
    /// Number of elements.
    pub elements: usize,
    /// Section and material.
    pub section: CableSection,
    /// Support of the first end.
    pub start_support: Support,
    /// Support of the second end.
    pub end_support: Support,
    /// A constant force on the second end's position, N.
    pub end_force: [f64; 3],
    /// A point mass (no rotary inertia) on the second end, kg.
    pub end_mass: f64,
    /// Gravity, m/s².
    pub gravity: [f64; 3],
}

/// Cross-section and material data of a chain's elements.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CableSection {
    /// Young's modulus, Pa.
    pub e: f64,
    /// Poisson's ratio (the planar beam).
    pub nu: f64,
    /// Density, kg/m³.
    pub rho: f64,
    /// Area, m².
    pub area: f64,
    /// Second moment of area for in-plane bending, m⁴.
    pub inertia: f64,
    /// Section width (out of plane), m, if rectangular (else 0).
    pub b: f64,
    /// Section height (in plane), m, if rectangular (else 0).
    pub h: f64,
    /// Axial Kelvin–Voigt damping, N s.
    pub damping_axial: f64,
    /// Bending Kelvin–Voigt damping, N m² s.
    pub damping_bending: f64,
    /// Kelvin–Voigt retardation time of the continuum beam, s.
    pub retardation: f64,
}

/// How an end of a chain is held by the ground.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Support {
    /// Not held (or held by an attachment to a rigid body).
    Free,
    /// Position fixed, free to rotate.
    Pinned,
    /// Position and orientation fixed.
    Clamped,
}

/// A cable end held at a marker of a rigid body (validated).
#[derive(Clone, Debug, PartialEq)]
pub struct CableMountInfo {
    /// The body (index into `System::bodies`, never ground).
    pub body: usize,
    /// The marker (index into the body's markers).
    pub marker: usize,
    /// Clamped: the unit direction of the cable's tangent in marker axes;
    /// pinned: none.
    pub axis: Option<[f64; 3]>,
    /// Where in the model file.
    pub span: Span,
}

impl System {
    /// The gap rows of the contacts, in order (contact by contact, a joint
    /// limit's lower before its upper): contact index and row name. The
    /// generated `contacts` function has one row per entry, in this order.
    pub fn contact_rows(&self) -> Vec<(usize, String)> {
        self.contacts
            .iter()
            .enumerate()
            .flat_map(|(c, k)| k.rows().into_iter().map(move |r| (c, r)))
            .collect()
    }

    /// Node `node` of cable `cable` at the start (the cable straight from
    /// its `from` to its `to`), world axes, m.
    pub fn cable_node_start(&self, cable: usize, node: usize) -> Option<[f64; 3]> {
        let ch = &self.cables.get(cable)?.chain;
        let s = node as f64 / ch.elements.max(1) as f64;
        Some(std::array::from_fn(|a| {
            ch.start[a] + s * (ch.end[a] - ch.start[a])
        }))
    }

    /// The points on bodies that cable nodes touch (a plane's point, a
    /// sphere's centre), one per contact at a cable node against a body's
    /// plane or sphere, in the order of `cable_contacts`. The generated
    /// `contact_frames` has one block per entry, in this order.
    pub fn cable_frames(&self) -> Vec<&Point> {
        self.cable_contacts
            .iter()
            .filter_map(|c| c.against.on_body())
            .collect()
    }

    /// The cable ends held at markers of rigid bodies, in order (cable by
    /// cable, start before end): cable index, `true` for the second end,
    /// the mount. The generated `attachments` function has one block per
    /// entry, in this order.
    pub fn cable_mounts(&self) -> Vec<(usize, bool, &CableMountInfo)> {
        let mut out = Vec::new();
        for (k, c) in self.cables.iter().enumerate() {
            if let Some(m) = &c.start_at {
                out.push((k, false, m));
            }
            if let Some(m) = &c.end_at {
                out.push((k, true, m));
            }
        }
        out
    }
}

impl System {
    /// Joints whose coordinates are the system's, in coordinate order.
    pub fn free_joints(&self) -> impl Iterator<Item = &JointInfo> {
        self.graph
            .tree_joints()
            .iter()
            .map(|&j| &self.joints[j])
            .filter(|j| j.motion == Motion::Free)
    }

    /// The blocks of `q` and `u` in order: each free tree joint's
    /// coordinates, and right after the tree joint above a flexible body
    /// (free or not), that body's elastic coordinates.
    pub fn coordinate_blocks(&self) -> impl Iterator<Item = Block<'_>> {
        self.graph.tree_joints().iter().flat_map(move |&j| {
            let joint = &self.joints[j];
            let rigid = (joint.motion == Motion::Free).then_some(Block::Joint(joint));
            let elastic = self.bodies[joint.child]
                .flexible
                .as_deref()
                .filter(|_| joint.motion != Motion::Cut)
                .map(Block::Elastic);
            rigid.into_iter().chain(elastic)
        })
    }

    /// The beam nodes of body `body` that markers or joints attach to,
    /// ascending.
    pub fn attached_nodes(&self, body: BodyId) -> Vec<usize> {
        let mut nodes: Vec<usize> = self.bodies[body]
            .markers
            .iter()
            .filter_map(|m| m.node)
            .chain(
                self.joints
                    .iter()
                    .filter(|j| j.parent == body)
                    .filter_map(|j| j.parent_node),
            )
            .chain(
                self.joints
                    .iter()
                    .filter(|j| j.child == body)
                    .filter_map(|j| j.child_node),
            )
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// Flexible bodies of the tree, with their body indices, in coordinate order.
    pub fn flexible_bodies(&self) -> impl Iterator<Item = (BodyId, &FlexInfo)> {
        self.graph.tree_joints().iter().filter_map(move |&j| {
            let child = self.joints[j].child;
            self.bodies[child].flexible.as_deref().map(|f| (child, f))
        })
    }

    /// Sets the initial value of the joint coordinate `name` (or, with
    /// `speed`, the joint speed `name`) to the number `value`; what became
    /// of it.
    pub fn set_initial_value(&mut self, name: &str, speed: bool, value: f64) -> InitialValue {
        let found = self.joints.iter_mut().find_map(|j| {
            let names = if speed {
                &j.speed_names
            } else {
                &j.coordinate_names
            };
            let k = names.iter().position(|n| n == name)?;
            let free = j.motion == Motion::Free;
            let values = if speed { &mut j.u0 } else { &mut j.q0 };
            Some((free, values.get_mut(k)?))
        });
        match found {
            Some((true, slot)) => {
                *slot = Quantity {
                    expr: Ast::Num(value),
                    value,
                    span: slot.span,
                };
                InitialValue::Set
            }
            Some((false, _)) => InitialValue::NotFree,
            None => InitialValue::Unknown,
        }
    }

    /// The coordinates `q` as the user would name them: a coordinate of
    /// a joint with a `label` (a URDF joint renamed to an identifier) is
    /// named after the label (`joint_0.0` for `joint_0_0`, `base.0_x` for
    /// `base_0_x`), any other by its name.
    pub fn coordinate_labels(&self) -> Vec<String> {
        let mut out = Vec::new();
        for b in self.coordinate_blocks() {
            let names = b.coordinate_names();
            match b {
                Block::Joint(j) => {
                    for n in names {
                        out.push(match (&j.label, n.strip_prefix(j.name.as_str())) {
                            (Some(l), Some(rest)) => format!("{l}{rest}"),
                            _ => n.clone(),
                        });
                    }
                }
                Block::Elastic(_) => out.extend(names.iter().cloned()),
            }
        }
        out
    }

    /// The coordinates, bodies and joints whose names were made
    /// identifiers, with the names as written (`label`s): `(kind, name,
    /// label)`, kind `"coordinate"`, `"body"` or `"joint"`.
    pub fn renamed(&self) -> Vec<(&'static str, String, String)> {
        let mut out = Vec::new();
        for (n, l) in self
            .coordinate_names()
            .into_iter()
            .zip(self.coordinate_labels())
        {
            if n != l {
                out.push(("coordinate", n.to_string(), l));
            }
        }
        for b in &self.bodies {
            if let Some(l) = &b.label {
                out.push(("body", b.name.clone(), l.clone()));
            }
        }
        for j in &self.joints {
            if let Some(l) = &j.label {
                out.push(("joint", j.name.clone(), l.clone()));
            }
        }
        out
    }

    /// Names of the position coordinates `q`, in order.
    pub fn coordinate_names(&self) -> Vec<&str> {
        self.coordinate_blocks()
            .flat_map(|b| b.coordinate_names().iter().map(String::as_str))
            .collect()
    }

    /// Names of the speeds `u`, in order.
    pub fn speed_names(&self) -> Vec<&str> {
        self.coordinate_blocks()
            .flat_map(|b| b.speed_names().iter().map(String::as_str))
            .collect()
    }

    /// Number of position coordinates.
    pub fn nq(&self) -> usize {
        self.coordinate_blocks().map(|b| b.nq()).sum()
    }

    /// Number of speeds.
    pub fn nu(&self) -> usize {
        self.coordinate_blocks().map(|b| b.nu()).sum()
    }

    /// What can feed energy into the rigid bodies, named: actuators, joint
    /// forces, prescribed motions, and constraints that move with `t`.
    /// Empty for a passive model (gravity, springs and dampers, whose data
    /// are constants, joints, constant constraints and rolling without
    /// slipping), whose energy never rises: a run of it whose energy rises
    /// is wrong and refuses (`eom_sim::large`'s energy guard).
    pub fn energy_sources(&self) -> Vec<String> {
        let mut out = Vec::new();
        for f in &self.forces {
            match &f.element {
                ForceElement::Actuator { .. } => out.push(format!("the actuator `{}`", f.name)),
                ForceElement::JointForce { .. } => {
                    out.push(format!("the joint force `{}`", f.name))
                }
                ForceElement::SpringDamper { .. } | ForceElement::JointSpringDamper { .. } => {}
            }
        }
        for j in &self.joints {
            if matches!(j.motion, Motion::Prescribed(_)) {
                out.push(format!("the prescribed motion of joint `{}`", j.name));
            }
        }
        for c in &self.constraints {
            if let ConstraintKind::Holonomic(expr) = &c.kind
                && expr.expr.names().iter().any(|(n, _)| *n == "t")
            {
                out.push(format!("the constraint `{}`, which moves with t", c.name));
            }
        }
        out
    }

    /// Index in `q` of the first entry (`w`) of every unit quaternion
    /// (spherical and free joints), in coordinate order.
    pub fn quaternion_indices(&self) -> Vec<usize> {
        self.free_joints()
            .filter_map(|j| match j.kind {
                JointType::Spherical => Some(j.q_index),
                JointType::Free => Some(j.q_index + 3),
                _ => None,
            })
            .collect()
    }

    /// Initial `q` at the default parameters (elastic coordinates zero).
    pub fn q0(&self) -> Vec<f64> {
        self.coordinate_blocks()
            .flat_map(|b| match b {
                Block::Joint(j) => j.q0.iter().map(|q| q.value).collect(),
                Block::Elastic(f) => vec![0.0; f.count()],
            })
            .collect()
    }

    /// Initial `u` at the default parameters (elastic rates zero).
    pub fn u0(&self) -> Vec<f64> {
        self.coordinate_blocks()
            .flat_map(|b| match b {
                Block::Joint(j) => j.u0.iter().map(|u| u.value).collect(),
                Block::Elastic(f) => vec![0.0; f.count()],
            })
            .collect()
    }

    /// Names of the cut joints.
    pub fn cut_joint_names(&self) -> Vec<&str> {
        self.graph
            .cut_joints()
            .iter()
            .map(|&j| self.joints[j].name.as_str())
            .collect()
    }

    /// Index of the body called `name`.
    pub fn body_id(&self, name: &str) -> Option<BodyId> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Index of the joint called `name`.
    pub fn joint_id(&self, name: &str) -> Option<JointId> {
        self.joints.iter().position(|j| j.name == name)
    }
}

/// A block of consecutive coordinates: a free tree joint's, or the elastic
/// coordinates of a flexible body.
#[derive(Clone, Copy, Debug)]
pub enum Block<'a> {
    /// A free tree joint.
    Joint(&'a JointInfo),
    /// A flexible body's elastic coordinates.
    Elastic(&'a FlexInfo),
}

impl<'a> Block<'a> {
    /// Names of its position coordinates.
    pub fn coordinate_names(&self) -> &'a [String] {
        match self {
            Block::Joint(j) => &j.coordinate_names,
            Block::Elastic(f) => &f.coordinate_names,
        }
    }

    /// Names of its speeds.
    pub fn speed_names(&self) -> &'a [String] {
        match self {
            Block::Joint(j) => &j.speed_names,
            Block::Elastic(f) => &f.speed_names,
        }
    }

    /// Number of position coordinates.
    pub fn nq(&self) -> usize {
        match self {
            Block::Joint(j) => j.kind.nq(),
            Block::Elastic(f) => f.count(),
        }
    }

    /// Number of speeds.
    pub fn nu(&self) -> usize {
        match self {
            Block::Joint(j) => j.kind.nu(),
            Block::Elastic(f) => f.count(),
        }
    }
}
