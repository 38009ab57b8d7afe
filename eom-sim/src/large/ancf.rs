//! Chains of ANCF elements between two points, built into a
//! [`StructuralModel`]: nodes equally spaced on the straight line, each
//! node's coordinates its position and its position gradients (the unit
//! tangent; for the planar beam also the unit normal), element `e` between
//! nodes `e` and `e + 1`, supports eliminating coordinates.
//!
//! The kernels are model-independent, so a model file's chain is built
//! here at run time by the kernel's name ([`chain`]); nothing is compiled
//! per model.
//!
//! Several chains go into one structure with [`chains`] (a model with
//! several cables): each chain's nodes at its own offset in the full
//! coordinates ([`ChainPart`]), each its own element group, supports, end
//! mass and end force; the chains share no coordinate.

use super::model::{ElementGroup, Elements, ModelBuilder, StructuralModel};
use crate::elements::{Element, ElementKernel, with_element};
use nalgebra::Vector3;
use std::fmt;

/// Builds a chain of the element type its spec names.
pub fn chain(spec: &ChainSpec) -> Result<Chain, ChainError> {
    with_element!(spec.kernel, |K, N, P| build_chain::<K, N, P>(spec))
}

/// How an end of the chain is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Support {
    /// Not held.
    Free,
    /// Position fixed, free to rotate (the position coordinates of the
    /// end node are eliminated).
    Pinned,
    /// Position and orientation fixed (every coordinate of the end node
    /// eliminated: position and gradients keep their reference values;
    /// for the fully parameterised beam the position and the section
    /// vector `∂r/∂y`, the axial gradient left free: the face may shear).
    Clamped,
}

/// Cross-section and material data. Kernels take what they need by
/// parameter name: `L` (element length), `EA`, `EI`, `rhoA`, `d_a`, `d_b`,
/// `E`, `nu`, `rho`, `A`, `I`, `b`, `h`, `mu`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Section {
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
    /// Axial Kelvin–Voigt damping, N s (force per unit strain rate).
    pub damping_axial: f64,
    /// Bending Kelvin–Voigt damping, N m² s (moment per unit curvature rate).
    pub damping_bending: f64,
    /// Kelvin–Voigt retardation time of the continuum beam, s.
    pub retardation: f64,
}

impl Section {
    /// The value of a kernel parameter, for elements of length `le`.
    pub fn param(&self, name: &str, le: f64) -> Option<f64> {
        Some(match name {
            "L" => le,
            "EA" => self.e * self.area,
            "EI" => self.e * self.inertia,
            "rhoA" => self.rho * self.area,
            "d_a" => self.damping_axial,
            "d_b" => self.damping_bending,
            "E" => self.e,
            "nu" => self.nu,
            "rho" => self.rho,
            "A" => self.area,
            "I" => self.inertia,
            "b" => self.b,
            "h" => self.h,
            "mu" => self.retardation,
            _ => return None,
        })
    }
}

/// A chain of elements.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainSpec {
    /// Element type.
    pub kernel: Element,
    /// First end (planar kernels use `x`, `y`; `z` must be 0).
    pub start: [f64; 3],
    /// Second end.
    pub end: [f64; 3],
    /// Number of elements.
    pub elements: usize,
    /// Section and material.
    pub section: Section,
    /// Support of the first end.
    pub start_support: Support,
    /// Support of the second end.
    pub end_support: Support,
    /// A constant force on the second end's position, N.
    pub end_force: [f64; 3],
    /// A point mass (a rigid particle, no rotary inertia) on the second
    /// end, kg; it takes its weight under `gravity`.
    pub end_mass: f64,
    /// Gravity, m/s².
    pub gravity: [f64; 3],
}

/// Why a chain cannot be built.
#[derive(Clone, Debug, PartialEq)]
pub enum ChainError {
    /// Zero elements asked for.
    NoElements,
    /// The two ends are one point (or not finite).
    EndsCoincide {
        /// The distance between them.
        length: f64,
    },
    /// A planar element type with an end off the plane `z = 0`.
    OffPlane {
        /// The element type.
        element: Element,
    },
    /// The section lacks a parameter the element type needs.
    MissingParameter {
        /// The element type.
        element: Element,
        /// The parameter's name.
        name: &'static str,
    },
}

impl fmt::Display for ChainError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ChainError::NoElements => f.write_str("a chain needs at least one element"),
            ChainError::EndsCoincide { length } => {
                write!(f, "the chain's ends coincide (length {length})")
            }
            ChainError::OffPlane { element } => {
                write!(
                    f,
                    "{element} is planar: its ends must lie in the plane z = 0"
                )
            }
            ChainError::MissingParameter { element, name } => write!(
                f,
                "{element} needs the parameter `{name}`, which the section does not give"
            ),
        }
    }
}

impl std::error::Error for ChainError {}

/// A built chain: the model and how to read node positions off it.
pub struct Chain {
    /// The structural model.
    pub model: StructuralModel,
    /// Element type.
    pub kernel: Element,
    /// Dimension of positions (2 or 3).
    pub dim: usize,
    /// Coordinates per node.
    pub node_coords: usize,
    /// Number of nodes (`elements + 1`).
    pub nodes: usize,
}

impl Chain {
    /// Position of `node` in full coordinates `q` (`z = 0` when planar).
    pub fn node_position(&self, q: &[f64], node: usize) -> [f64; 3] {
        let mut p = [0.0; 3];
        for (k, pk) in p.iter_mut().enumerate().take(self.dim) {
            *pk = q[node * self.node_coords + k];
        }
        p
    }

    /// The attachment of the first (`end == false`) or last node to a
    /// mount of a rigid part ([`super::mixed`]): its position, and when
    /// `clamped` its gradient `r'` (the chain must leave that end free).
    pub fn attachment(&self, name: &str, end: bool, clamped: bool) -> super::mixed::Attachment {
        let node = if end { self.nodes - 1 } else { 0 };
        let base = node * self.node_coords;
        super::mixed::Attachment {
            name: name.to_string(),
            dim: self.dim,
            position: (0..self.dim).map(|k| base + k).collect(),
            gradient: clamped.then(|| (0..self.dim).map(|k| base + self.dim + k).collect()),
        }
    }

    /// Full coordinate index of `node`'s position component `k`.
    pub fn position_index(&self, node: usize, k: usize) -> usize {
        node * self.node_coords + k
    }
}

/// Builds a chain of kernel `E`.
pub fn build_chain<E: ElementKernel<N, P> + 'static, const N: usize, const P: usize>(
    spec: &ChainSpec,
) -> Result<Chain, ChainError> {
    let laid = lay_out::<E, N, P>(spec, 0, 0)?;
    let mut b = ModelBuilder::new(laid.q0).gravity(spec.gravity);
    for &i in &laid.fixed {
        b = b.fix(i);
    }
    for &(i, f) in &laid.point_loads {
        b = b.point_load(i, f);
    }
    for &(i, m) in &laid.point_masses {
        b = b.point_mass(i, m);
    }
    let model = b.boxed_elements(laid.group).build();
    let p = laid.part;
    Ok(Chain {
        model,
        kernel: p.kernel,
        dim: p.dim,
        node_coords: p.node_coords,
        nodes: p.nodes,
    })
}

/// One chain laid out in a structure's full coordinates: its initial
/// coordinates, its element group, its fixed coordinates, point masses and
/// point loads (full indices), and where it sits.
struct Laid {
    q0: Vec<f64>,
    group: Box<dyn ElementGroup>,
    fixed: Vec<usize>,
    point_masses: Vec<(usize, f64)>,
    point_loads: Vec<(usize, f64)>,
    part: ChainPart,
}

/// Lays out a chain of kernel `E` whose nodes start at full coordinate
/// `offset`, as element group `group` of its structure.
fn lay_out<E: ElementKernel<N, P> + 'static, const N: usize, const P: usize>(
    spec: &ChainSpec,
    offset: usize,
    group: usize,
) -> Result<Laid, ChainError> {
    let (dim, nc) = (E::DIM, E::NODE_COORDS);
    // The registry's entry of `E` (a kernel outside the registry, used
    // through the generic entry points, goes by the spec's).
    let element = Element::from_name(E::NAME).unwrap_or(spec.kernel);
    let ne = spec.elements;
    if ne == 0 {
        return Err(ChainError::NoElements);
    }
    let d: Vec<f64> = (0..3).map(|k| spec.end[k] - spec.start[k]).collect();
    let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return Err(ChainError::EndsCoincide { length: len });
    }
    if dim == 2 && (spec.start[2] != 0.0 || spec.end[2] != 0.0) {
        return Err(ChainError::OffPlane { element });
    }
    let t: Vec<f64> = d.iter().map(|x| x / len).collect();
    let le = len / ne as f64;
    let mut params = [0.0; P];
    for (v, name) in params.iter_mut().zip(E::PARAMS) {
        *v = spec
            .section
            .param(name, le)
            .ok_or(ChainError::MissingParameter { element, name })?;
    }
    // Node coordinates: position, tangent, (normal).
    let nodes = ne + 1;
    let mut q0 = vec![0.0; nodes * nc];
    for j in 0..nodes {
        let s = j as f64 / ne as f64;
        let base = j * nc;
        for k in 0..dim {
            q0[base + k] = spec.start[k] + s * d[k];
        }
        if nc >= 2 * dim {
            q0[base + dim..base + 2 * dim].copy_from_slice(&t[..dim]);
        }
        if nc >= 3 * dim && dim == 2 {
            q0[base + 4] = -t[1];
            q0[base + 5] = t[0];
        }
    }
    let mut els = Elements::<E, N, P>::new();
    for e in 0..ne {
        let mut conn = [0; N];
        let mut reference = [0.0; N];
        for (i, (c, r)) in conn.iter_mut().zip(&mut reference).enumerate() {
            *r = q0[e * nc + i];
            *c = offset + e * nc + i;
        }
        els.push(conn, params, reference);
    }
    let mut fixed = Vec::new();
    for (node, support) in [(0, spec.start_support), (ne, spec.end_support)] {
        let n_fixed = match support {
            Support::Free => 0,
            Support::Pinned => dim,
            Support::Clamped => nc,
        };
        for k in 0..n_fixed {
            // A clamped face of the fully parameterised beam holds
            // `r(0, y) = r₀ + y r,ᵧ`: position and section vector; its
            // `r,ₓ` stays free (the face may shear, as Timoshenko's clamp;
            // holding it too would force zero shear strain at the face).
            if support == Support::Clamped && nc == 3 * dim && (dim..2 * dim).contains(&k) {
                continue;
            }
            fixed.push(offset + node * nc + k);
        }
    }
    let (mut point_loads, mut point_masses) = (Vec::new(), Vec::new());
    for k in 0..dim {
        let f = spec.end_force[k] + spec.end_mass * spec.gravity[k];
        if f != 0.0 {
            point_loads.push((offset + ne * nc + k, f));
        }
        if spec.end_mass > 0.0 {
            point_masses.push((offset + ne * nc + k, spec.end_mass));
        }
    }
    Ok(Laid {
        q0,
        group: Box::new(els),
        fixed,
        point_masses,
        point_loads,
        part: ChainPart {
            kernel: element,
            dim,
            node_coords: nc,
            nodes,
            offset,
            group,
        },
    })
}

/// Lays out a chain of the element type its spec names.
fn lay_out_by_name(spec: &ChainSpec, offset: usize, group: usize) -> Result<Laid, ChainError> {
    with_element!(spec.kernel, |K, N, P| lay_out::<K, N, P>(
        spec, offset, group
    ))
}

/// Where one chain of a [`Chains`] structure sits: its kernel, node layout,
/// the full index of its first coordinate, its element group.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChainPart {
    /// Element type.
    pub kernel: Element,
    /// Dimension of positions (2 or 3).
    pub dim: usize,
    /// Coordinates per node.
    pub node_coords: usize,
    /// Number of nodes (`elements + 1`).
    pub nodes: usize,
    /// Full coordinate index of the chain's first node's first coordinate:
    /// node `j`'s coordinates are `offset + j · node_coords + …`.
    pub offset: usize,
    /// Index of its element group in [`StructuralModel::groups`].
    pub group: usize,
}

impl ChainPart {
    /// Full coordinate index of `node`'s position component `k`.
    pub fn position_index(&self, node: usize, k: usize) -> usize {
        self.offset + node * self.node_coords + k
    }

    /// Position of `node` in the structure's full coordinates `q` (`z = 0`
    /// when planar).
    pub fn node_position(&self, q: &[f64], node: usize) -> [f64; 3] {
        let mut p = [0.0; 3];
        for (k, pk) in p.iter_mut().enumerate().take(self.dim) {
            *pk = q[self.position_index(node, k)];
        }
        p
    }

    /// The attachment of the first (`end == false`) or last node to a
    /// mount of a rigid part, as [`Chain::attachment`].
    pub fn attachment(&self, name: &str, end: bool, clamped: bool) -> super::mixed::Attachment {
        let node = if end { self.nodes - 1 } else { 0 };
        let base = self.position_index(node, 0);
        super::mixed::Attachment {
            name: name.to_string(),
            dim: self.dim,
            position: (0..self.dim).map(|k| base + k).collect(),
            gradient: clamped.then(|| (0..self.dim).map(|k| base + self.dim + k).collect()),
        }
    }
}

/// Several chains built into one structure ([`chains`]).
pub struct Chains {
    /// The structural model: every chain's nodes, one after the other.
    pub model: StructuralModel,
    /// Per chain, in the order given, where it sits.
    pub parts: Vec<ChainPart>,
}

impl Chains {
    /// Adds a dead load `w` per unit reference length (N/m, world axes) on
    /// every element of chain `k` only.
    pub fn add_distributed_load(&mut self, k: usize, w: [f64; 3]) {
        self.model
            .add_group_distributed_load(self.parts[k].group, w);
    }

    /// Chain `k`'s full coordinate speeds in a rigid motion from its
    /// reference configuration: its first node moving at `v` (m/s), the
    /// whole turning at `w` (rad/s) about that node, world axes. A node's
    /// position moves at `v + w × (r − r₀)`, each of its direction vectors
    /// (the gradient `∂r/∂x`, and `∂r/∂y` of `Beam2D`) turns at `w × d`;
    /// a planar chain keeps its x and y components (`w` about z). Returns
    /// `(full index, speed)` for every coordinate of the chain.
    pub fn rigid_velocity(&self, k: usize, v: [f64; 3], w: [f64; 3]) -> Vec<(usize, f64)> {
        let part = &self.parts[k];
        let q0 = self.model.q0();
        let r0 = Vector3::from(part.node_position(q0, 0));
        let (v, w) = (Vector3::from(v), Vector3::from(w));
        let mut out = Vec::with_capacity(part.nodes * part.node_coords);
        for node in 0..part.nodes {
            let base = part.position_index(node, 0);
            for chunk in 0..part.node_coords / part.dim {
                let first = base + chunk * part.dim;
                let d = Vector3::from_fn(|a, _| if a < part.dim { q0[first + a] } else { 0.0 });
                let rate = if chunk == 0 {
                    v + w.cross(&(d - r0))
                } else {
                    w.cross(&d)
                };
                out.extend((0..part.dim).map(|a| (first + a, rate[a])));
            }
        }
        out
    }
}

/// Why one chain of several cannot be built: its index and the reason.
#[derive(Clone, Debug, PartialEq)]
pub struct ChainsError {
    /// The chain's index in the list given to [`chains`].
    pub chain: usize,
    /// Why.
    pub error: ChainError,
}

impl fmt::Display for ChainsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "chain {}: {}", self.chain, self.error)
    }
}

impl std::error::Error for ChainsError {}

/// Builds several chains, each by its kernel's name, into one
/// [`StructuralModel`]: chain `k`'s nodes follow chain `k − 1`'s in the
/// full coordinates (its [`ChainPart::offset`]), each chain one element
/// group with its supports, end mass and end force; gravity on every
/// group as its chain says. Kernels may differ (a planar `Cable2D` beside
/// a spatial `Cable3D`: the chains share no coordinate, so each keeps its
/// own dimension). The chains are not coupled: the model's mass matrix,
/// tangent and forces are block-diagonal, each block the chain's as
/// [`chain`] builds it alone. Every chain is checked; the first that
/// cannot be built is named.
pub fn chains(specs: &[ChainSpec]) -> Result<Chains, ChainsError> {
    let mut laid = Vec::with_capacity(specs.len());
    let mut offset = 0;
    for (k, spec) in specs.iter().enumerate() {
        let l =
            lay_out_by_name(spec, offset, k).map_err(|error| ChainsError { chain: k, error })?;
        offset += l.q0.len();
        laid.push(l);
    }
    let q0: Vec<f64> = laid.iter().flat_map(|l| l.q0.iter().copied()).collect();
    let n = q0.len();
    let same_gravity = specs.windows(2).all(|w| w[0].gravity == w[1].gravity);
    let mut b = ModelBuilder::new(q0);
    if same_gravity && let Some(s) = specs.first() {
        b = b.gravity(s.gravity);
    }
    let mut parts = Vec::with_capacity(laid.len());
    let mut gravity_loads = Vec::new();
    for (l, spec) in laid.into_iter().zip(specs) {
        for &i in &l.fixed {
            b = b.fix(i);
        }
        if !same_gravity && spec.gravity != [0.0; 3] {
            // Each chain's own gravity on its own group.
            let mut g = vec![0.0; n];
            l.group.add_gravity(spec.gravity, &mut g);
            gravity_loads.extend(g.into_iter().enumerate().filter(|(_, f)| *f != 0.0));
        }
        for &(i, f) in &l.point_loads {
            b = b.point_load(i, f);
        }
        for &(i, m) in &l.point_masses {
            b = b.point_mass(i, m);
        }
        b = b.boxed_elements(l.group);
        parts.push(l.part);
    }
    let mut model = b.build();
    for (i, f) in gravity_loads {
        model.add_point_load(i, f);
    }
    Ok(Chains { model, parts })
}
