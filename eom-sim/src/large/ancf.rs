//! Chains of ANCF elements between two points, built into a
//! [`StructuralModel`]: nodes equally spaced on the straight line, each
//! node's coordinates its position and its position gradients (the unit
//! tangent; for the planar beam also the unit normal), element `e` between
//! nodes `e` and `e + 1`, supports eliminating coordinates.
//!
//! The kernels are model-independent, so a model file's chain is built
//! here at run time by the kernel's name ([`chain`]); nothing is compiled
//! per model.

use super::model::{ElementGroup, Elements, ModelBuilder, StructuralModel};
use crate::elements::{Beam2D, Cable2D, Cable2DGreen, Cable3D, ElementKernel};
use std::fmt;

/// Element types whose kernels this build has (their `NAME`s).
pub const KERNELS: &[&str] = &[
    Cable2D::NAME,
    Cable2DGreen::NAME,
    Cable3D::NAME,
    Beam2D::NAME,
];

/// Builds a chain by its kernel's name.
pub fn chain(spec: &ChainSpec) -> Result<Chain, ChainError> {
    match spec.kernel.as_str() {
        Cable2D::NAME => build_chain::<Cable2D, 8, 6>(spec),
        Cable2DGreen::NAME => build_chain::<Cable2DGreen, 8, 6>(spec),
        Cable3D::NAME => build_chain::<Cable3D, 12, 6>(spec),
        Beam2D::NAME => build_chain::<Beam2D, 12, 7>(spec),
        other => Err(ChainError(format!(
            "no kernel `{other}` in this build (available: {KERNELS:?})"
        ))),
    }
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
    /// Kernel name (`Cable2D`, `Cable2DGreen`, `Cable3D`, `Beam2D`).
    pub kernel: String,
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
pub struct ChainError(pub String);

impl fmt::Display for ChainError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ChainError {}

/// A built chain: the model and how to read node positions off it.
pub struct Chain {
    /// The structural model.
    pub model: StructuralModel,
    /// Kernel name.
    pub kernel: &'static str,
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
    let (dim, nc) = (E::DIM, E::NODE_COORDS);
    let ne = spec.elements;
    if ne == 0 {
        return Err(ChainError("a chain needs at least one element".into()));
    }
    let d: Vec<f64> = (0..3).map(|k| spec.end[k] - spec.start[k]).collect();
    let len = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return Err(ChainError(format!(
            "the chain's ends coincide (length {len})"
        )));
    }
    if dim == 2 && (spec.start[2] != 0.0 || spec.end[2] != 0.0) {
        return Err(ChainError(format!(
            "{} is planar: its ends must lie in the plane z = 0",
            E::NAME
        )));
    }
    let t: Vec<f64> = d.iter().map(|x| x / len).collect();
    let le = len / ne as f64;
    let mut params = [0.0; P];
    for (v, name) in params.iter_mut().zip(E::PARAMS) {
        *v = spec.section.param(name, le).ok_or_else(|| {
            ChainError(format!(
                "{} needs the parameter `{name}`, which the section does not give",
                E::NAME
            ))
        })?;
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
        for (i, c) in conn.iter_mut().enumerate() {
            *c = e * nc + i;
        }
        let mut reference = [0.0; N];
        for (r, &c) in reference.iter_mut().zip(&conn) {
            *r = q0[c];
        }
        els.push(conn, params, reference);
    }
    let mut b = ModelBuilder::new(q0).gravity(spec.gravity);
    for (node, support) in [(0, spec.start_support), (ne, spec.end_support)] {
        let fixed = match support {
            Support::Free => 0,
            Support::Pinned => dim,
            Support::Clamped => nc,
        };
        for k in 0..fixed {
            // A clamped face of the fully parameterised beam holds
            // `r(0, y) = r₀ + y r,ᵧ`: position and section vector; its
            // `r,ₓ` stays free (the face may shear, as Timoshenko's clamp;
            // holding it too would force zero shear strain at the face).
            if support == Support::Clamped && nc == 3 * dim && (dim..2 * dim).contains(&k) {
                continue;
            }
            b = b.fix(node * nc + k);
        }
    }
    for k in 0..dim {
        let f = spec.end_force[k] + spec.end_mass * spec.gravity[k];
        if f != 0.0 {
            b = b.point_load(ne * nc + k, f);
        }
        if spec.end_mass > 0.0 {
            b = b.point_mass(ne * nc + k, spec.end_mass);
        }
    }
    let group: Box<dyn ElementGroup> = Box::new(els);
    let model = b.boxed_elements(group).build();
    Ok(Chain {
        model,
        kernel: E::NAME,
        dim,
        node_coords: nc,
        nodes,
    })
}
