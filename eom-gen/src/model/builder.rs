//! Building a [`Spec`] in Rust, for parameterised models (an n-link chain,
//! a robot from a table), and writing it back to RON.
//!
//! ```
//! use eom_gen::model::builder::ModelBuilder;
//! use eom_gen::model::spec::{Body, Joint, JointKind};
//!
//! let spec = ModelBuilder::new("pendulum")
//!     .gravity((0.0, -9.81, 0.0))
//!     .parameter("l", 1.0)
//!     .body(Body::new("bob", 1.0).com((0.0, "-l", 0.0)))
//!     .joint(Joint::new("theta", JointKind::revolute((0.0, 0.0, 1.0)), "ground", "bob").q0(["pi/2"]))
//!     .build();
//! let text = spec.to_ron();
//! assert!(text.contains("Revolute"));
//! ```

use super::spec::*;

/// Builds a [`Spec`] step by step.
#[derive(Clone, Debug)]
pub struct ModelBuilder {
    spec: Spec,
}

impl ModelBuilder {
    /// An empty model called `name`.
    pub fn new(name: impl Into<String>) -> Self {
        ModelBuilder {
            spec: Spec {
                name: name.into(),
                gravity: None,
                parameters: Vec::new(),
                bodies: Vec::new(),
                joints: Vec::new(),
                forces: Vec::new(),
                constraints: Vec::new(),
                outputs: Vec::new(),
                inertia_policy: Default::default(),
                cables: Vec::new(),
                contacts: Vec::new(),
                ground_geometry: Vec::new(),
            },
        }
    }

    /// Sets gravity (world axes, m/s²).
    pub fn gravity(mut self, g: impl Into<V3>) -> Self {
        self.spec.gravity = Some(g.into());
        self
    }

    /// Adds a fixed parameter (inlined into generated code).
    pub fn parameter(mut self, name: impl Into<String>, value: impl Into<Num>) -> Self {
        self.spec.parameters.push(Parameter {
            name: name.into(),
            value: value.into(),
            tunable: false,
            doc: None,
        });
        self
    }

    /// Adds a tunable parameter (a runtime field).
    pub fn tunable(mut self, name: impl Into<String>, value: impl Into<Num>) -> Self {
        self = self.parameter(name, value);
        if let Some(p) = self.spec.parameters.last_mut() {
            p.tunable = true;
        }
        self
    }

    /// Adds a body.
    pub fn body(mut self, body: Body) -> Self {
        self.spec.bodies.push(body);
        self
    }

    /// Adds a joint.
    pub fn joint(mut self, joint: Joint) -> Self {
        self.spec.joints.push(joint);
        self
    }

    /// Adds a force element.
    pub fn force(mut self, force: Force) -> Self {
        self.spec.forces.push(force);
        self
    }

    /// Adds a constraint.
    pub fn constraint(mut self, constraint: Constraint) -> Self {
        self.spec.constraints.push(constraint);
        self
    }

    /// Requests an output.
    pub fn output(mut self, output: Output) -> Self {
        self.spec.outputs.push(output);
        self
    }

    /// The finished specification.
    pub fn build(self) -> Spec {
        self.spec
    }
}

impl Spec {
    /// The model as RON text, readable and parseable by [`super::parse`].
    pub fn to_ron(&self) -> String {
        let config = ron::ser::PrettyConfig::new()
            .struct_names(false)
            .indentor("    ".to_string())
            .extensions(ron::extensions::Extensions::IMPLICIT_SOME);
        // Serialising plain data with string keys cannot fail.
        ron::ser::to_string_pretty(self, config).unwrap_or_else(|e| format!("// {e}\n"))
    }
}

impl Body {
    /// A body with its mass (kg), centre of mass at its origin, point mass.
    pub fn new(name: impl Into<String>, mass: impl Into<Num>) -> Self {
        Body {
            name: name.into(),
            label: None,
            mass: Some(mass.into()),
            com: V3::default(),
            inertia: None,
            markers: Vec::new(),
            flexible: None,
            geometry: Vec::new(),
        }
    }

    /// Adds a shape drawn by `eom-gen animate`.
    pub fn geometry(mut self, g: Geometry) -> Self {
        self.geometry.push(g);
        self
    }

    /// Centre of mass in body axes.
    pub fn com(mut self, com: impl Into<V3>) -> Self {
        self.com = com.into();
        self
    }

    /// Principal moments of inertia about the centre of mass.
    pub fn inertia_diag(
        mut self,
        ixx: impl Into<Num>,
        iyy: impl Into<Num>,
        izz: impl Into<Num>,
    ) -> Self {
        self.inertia = Some(Inertia::Diag(ixx.into(), iyy.into(), izz.into()));
        self
    }

    /// A named point on the body.
    pub fn marker(mut self, name: impl Into<String>, position: impl Into<V3>) -> Self {
        self.markers.push(Marker {
            name: name.into(),
            position: position.into(),
            orientation: Orientation::Identity,
            node: None,
        });
        self
    }

    /// Make the body flexible; its `mass`, `com` and `inertia` are then a
    /// rigid part carried by its frame.
    pub fn flexible(mut self, flexible: Flexible) -> Self {
        self.flexible = Some(flexible);
        self
    }
}

impl JointKind {
    /// Revolute about `axis`.
    pub fn revolute(axis: impl Into<V3>) -> Self {
        JointKind::Revolute { axis: axis.into() }
    }

    /// Prismatic along `axis`.
    pub fn prismatic(axis: impl Into<V3>) -> Self {
        JointKind::Prismatic { axis: axis.into() }
    }
}

impl Joint {
    /// A joint of `kind` from `parent` to `child`, frames at the body origins.
    pub fn new(
        name: impl Into<String>,
        kind: JointKind,
        parent: impl Into<String>,
        child: impl Into<String>,
    ) -> Self {
        Joint {
            name: name.into(),
            label: None,
            kind,
            parent: parent.into(),
            child: child.into(),
            parent_frame: Frame::default(),
            parent_node: None,
            child_frame: Frame::default(),
            child_node: None,
            coordinates: None,
            speeds: None,
            q0: None,
            u0: None,
            locked: false,
            prescribed: None,
            cut: false,
        }
    }

    /// Places the joint frame on the parent at `position` (parent axes).
    pub fn at_parent(mut self, position: impl Into<V3>) -> Self {
        self.parent_frame.position = position.into();
        self
    }

    /// Places the joint frame on the child at `position` (child axes).
    pub fn at_child(mut self, position: impl Into<V3>) -> Self {
        self.child_frame.position = position.into();
        self
    }

    /// Names the coordinates.
    pub fn coordinates<S: Into<String>>(mut self, names: impl IntoIterator<Item = S>) -> Self {
        self.coordinates = Some(names.into_iter().map(Into::into).collect());
        self
    }

    /// Initial positions.
    pub fn q0<N: Into<Num>>(mut self, q0: impl IntoIterator<Item = N>) -> Self {
        self.q0 = Some(q0.into_iter().map(Into::into).collect());
        self
    }

    /// Initial speeds.
    pub fn u0<N: Into<Num>>(mut self, u0: impl IntoIterator<Item = N>) -> Self {
        self.u0 = Some(u0.into_iter().map(Into::into).collect());
        self
    }

    /// Prescribed motion, one expression of `t` per coordinate.
    pub fn prescribed<N: Into<Num>>(mut self, q: impl IntoIterator<Item = N>) -> Self {
        self.prescribed = Some(q.into_iter().map(Into::into).collect());
        self
    }

    /// Holds the joint at its initial position.
    pub fn locked(mut self) -> Self {
        self.locked = true;
        self
    }

    /// Prefers this joint as the cut joint of its loop.
    pub fn cut(mut self) -> Self {
        self.cut = true;
        self
    }
}

/// An n-link chain of uniform rods (1 kg, 0.5 m, centre of mass mid-link)
/// standing on ground: at `q = 0` the links point along +z and gravity
/// along −z, so from its initial state (every joint at 0.1 rad) the chain
/// falls over and swings chaotically. `spatial` alternates the joint axes
/// z, y, z, … (as in arm7), otherwise all hinge about y (planar). Links are
/// numbered from 1; coordinates are `q1 … qn`.
pub fn n_link_chain(n: usize, spatial: bool) -> Spec {
    let mut b = ModelBuilder::new(if spatial {
        "spatial_chain"
    } else {
        "planar_chain"
    })
    .gravity((0.0, 0.0, -9.81))
    .parameter("m", 1.0)
    .parameter("l", 0.5)
    .parameter("r", 0.02);
    for k in 1..=n {
        let link = format!("link{k}");
        let parent = if k == 1 {
            "ground".to_string()
        } else {
            format!("link{}", k - 1)
        };
        let axis = if spatial && k % 2 == 1 {
            (0.0, 0.0, 1.0)
        } else {
            (0.0, 1.0, 0.0)
        };
        let body = Body::new(link.clone(), "m")
            .com((0.0, 0.0, "l/2"))
            .inertia_diag("m*(3*r^2 + l^2)/12", "m*(3*r^2 + l^2)/12", "m*r^2/2");
        let joint = Joint::new(format!("j{k}"), JointKind::revolute(axis), parent, link)
            .at_parent((
                0.0,
                0.0,
                if k == 1 {
                    Num::Value(0.0)
                } else {
                    Num::from("l")
                },
            ))
            .coordinates([format!("q{k}")])
            .q0([0.1]);
        b = b.body(body).joint(joint);
    }
    b.build()
}

/// The N-four-bar of IFToMM benchmark A02: `n + 1` cranks pinned to ground
/// one link length apart along +x and `n` couplers joining their tips; all
/// rods uniform, 1 kg and 1 m (`m`, `L`; inertia `m L²/12` about the
/// centre, none about the rod's axis); hinges about z; gravity `g` along
/// −y. It starts with the cranks vertical and every crank tip moving at
/// `v0` along +x (cranks at `−v0/L`, couplers at `+v0/L` relative to their
/// crank). Tree: ground → `crank0` → `coupler1`, ground → `crank1` →
/// `coupler2`, …, ground → `crankN`; the joint between `coupler{j}` and the
/// tip of `crank{j}` is cut (`n` loops). Coordinates in tree order:
/// `crank0, coupler1, crank1, …, crankN` (`n = 1` has the layout of
/// `models/fourbar.ron`). Grübler–Kutzbach counts `3(2n + 1) − 2(3n + 1)
/// = 1`, the rank of `J` gives mobility 1 too, but twice a turn all
/// `2n + 1` links are collinear and the mobility jumps to `n + 1`.
pub fn n_fourbar(n: usize) -> Spec {
    let mut b = ModelBuilder::new(format!("fourbar_n{n}"))
        .gravity((0.0, "-g", 0.0))
        .parameter("g", 9.81)
        .parameter("m", 1.0)
        .parameter("L", 1.0)
        .parameter("v0", 1.0);
    let crank = |k: usize| format!("crank{k}");
    let coupler = |j: usize| format!("coupler{j}");
    for k in 0..=n {
        b = b.body(Body::new(crank(k), "m").inertia_diag("m*L^2/12", 0.0, "m*L^2/12"));
        if k < n {
            b = b.body(Body::new(coupler(k + 1), "m").inertia_diag(0.0, "m*L^2/12", "m*L^2/12"));
        }
    }
    for k in 0..=n {
        let x = if k == 0 {
            Num::Value(0.0)
        } else {
            Num::from(format!("{k}*L").as_str())
        };
        b = b.joint(
            Joint::new(
                format!("a{k}"),
                JointKind::revolute((0.0, 0.0, 1.0)),
                "ground",
                crank(k),
            )
            .at_parent((x, 0.0, 0.0))
            .at_child((0.0, "-L/2", 0.0))
            .coordinates([crank(k)])
            .u0(["-v0/L"]),
        );
        if k < n {
            b = b.joint(
                Joint::new(
                    format!("b{}", k + 1),
                    JointKind::revolute((0.0, 0.0, 1.0)),
                    crank(k),
                    coupler(k + 1),
                )
                .at_parent((0.0, "L/2", 0.0))
                .at_child(("-L/2", 0.0, 0.0))
                .coordinates([coupler(k + 1)])
                .u0(["v0/L"]),
            );
        }
    }
    for j in 1..=n {
        b = b.joint(
            Joint::new(
                format!("c{j}"),
                JointKind::revolute((0.0, 0.0, 1.0)),
                coupler(j),
                crank(j),
            )
            .at_parent(("L/2", 0.0, 0.0))
            .at_child((0.0, "L/2", 0.0))
            .cut(),
        );
    }
    b.output(Output::Energy).build()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Source, check, parse};

    #[test]
    fn builder_output_round_trips_through_ron() {
        let spec = n_link_chain(4, true);
        let text = spec.to_ron();
        let back = parse(&Source::new("chain.ron", text.clone()))
            .unwrap_or_else(|r| panic!("{r}\n{text}"));
        assert_eq!(back, spec, "RON text:\n{text}");
    }

    #[test]
    fn n_fourbar_has_n_loops_and_mobility_one() {
        // 2n + 1 rods, 3n + 1 hinges in the plane: Grübler 3(2n+1) − 2(3n+1) = 1.
        for n in [1, 2, 4] {
            let text = n_fourbar(n).to_ron();
            let checked =
                check(&Source::new("fourbar_n.ron", text)).unwrap_or_else(|r| panic!("{r}"));
            let sys = &checked.system;
            assert_eq!((sys.nq(), sys.nu()), (2 * n + 1, 2 * n + 1), "N = {n}");
            assert_eq!(sys.graph.cut_joints().len(), n, "N = {n}");
        }
    }

    #[test]
    fn chain_validates_with_the_expected_counts() {
        for n in [1, 5, 50] {
            let text = n_link_chain(n, n % 2 == 1).to_ron();
            let checked = check(&Source::new("chain.ron", text)).unwrap_or_else(|r| panic!("{r}"));
            let sys = &checked.system;
            assert_eq!((sys.nq(), sys.nu()), (n, n), "chain of {n}");
            assert_eq!(
                sys.coordinate_names().last().copied(),
                Some(format!("q{n}").as_str())
            );
            assert_eq!(sys.grubler.dof, n as i64);
            assert!(checked.warnings.is_empty(), "{:?}", checked.warnings);
        }
    }
}
