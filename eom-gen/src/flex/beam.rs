//! A straight 3-D beam along the body `x` axis, Euler–Bernoulli or (with
//! [`Shear`]) Timoshenko, discretised with two-node elements: the consistent
//! mass and stiffness matrices of Przemieniecki (*Theory of Matrix Structural
//! Analysis*, §5.6 and §11.3; Shabana, *Dynamics of Multibody Systems*,
//! ch. 6), assembled.
//!
//! Every node carries six degrees of freedom in the body frame, in this order
//! ([`NodeDof`]): the translations `u_x, u_y, u_z` and the small rotations
//! `θ_x, θ_y, θ_z`. Node `i` sits at `x_i = i L / n`; its degrees of freedom
//! are `6 i .. 6 i + 6` of the assembled vectors.
//!
//! In an element of length `l` with `ξ = (x − x_a) / l ∈ [0, 1]`
//! ([`Beam::interpolation`]):
//!
//! ```text
//! u_x = (1−ξ) u_xa + ξ u_xb                     axial, linear
//! θ_x = (1−ξ) θ_xa + ξ θ_xb                     torsion, linear
//! u_y = N1 u_ya + l N2 θ_za + N3 u_yb + l N4 θ_zb   bending in x–y, θ_z =  u_y'
//! u_z = N1 u_za − l N2 θ_ya + N3 u_zb − l N4 θ_yb   bending in x–z, θ_y = −u_z'
//! N1 = 1 − 3ξ² + 2ξ³   N2 = ξ − 2ξ² + ξ³   N3 = 3ξ² − 2ξ³   N4 = ξ³ − ξ²
//! ```
//!
//! The element matrices are the integrals (Shabana 6.1, the consistent mass)
//!
//! ```text
//! M_e = ∫ ρA Nᵀ N + ρI_p N_θxᵀ N_θx dx
//! K_e = ∫ EA N_ux'ᵀ N_ux' + GJ N_θx'ᵀ N_θx' + EI_z N_uy''ᵀ N_uy'' + EI_y N_uz''ᵀ N_uz'' dx
//! K_G = ∫ P(x) (N_uy'ᵀ N_uy' + N_uz'ᵀ N_uz') dx          axial force P, tension positive
//! ```
//!
//! taken with the 4-point Gauss rule, exact for these polynomials of degree
//! ≤ 6 (and for `K_G` when `P` is a polynomial of degree ≤ 3). They equal
//! Przemieniecki's closed forms (`ρA l/420 [156, 22l, 54, −13l; …]`,
//! `EI/l³ [12, 6l, −12, 6l; …]`, `P/(30 l) [36, 3l, −36, 3l; …]`); the
//! unit tests check that. Bending rotary inertia is neglected
//! (Euler–Bernoulli); torsion has the polar mass moment `ρI_p`.
//!
//! ## Timoshenko
//!
//! With [`Shear`] the sections rotate by `ψ` independently of the axis'
//! slope `v'`: the bending strain energy is `½ ∫ EI ψ'² + κGA (v' − ψ)² dx`
//! and the nodal rotations `θ_z = ψ_xy`, `θ_y = −ψ_xz` are the **section
//! rotations** (what node attachments turn with), not the slopes. The
//! element is the interdependent interpolation element (IIE: Friedman and
//! Kosmatka, *Comput. Struct.* 47 (1993) 473; Reddy 1997), whose shape
//! functions solve the homogeneous static Timoshenko equations
//! `(EI ψ')' + κGA (v' − ψ) = 0`, `(κGA (v' − ψ))' = 0` (so the element is
//! exact for end-loaded static beams and cannot lock), with
//! `Φ = 12 EI / (κGA l²)` and `p = 1/(1 + Φ)`:
//!
//! ```text
//! v = p [2ξ³ − 3ξ² − Φξ + 1 + Φ] v_a + p l [ξ³ − (2 + Φ/2)ξ² + (1 + Φ/2)ξ] ψ_a
//!   + p [−2ξ³ + 3ξ² + Φξ] v_b     + p l [ξ³ − (1 − Φ/2)ξ² − (Φ/2)ξ] ψ_b
//! ψ = p 6(ξ² − ξ)/l v_a + p [3ξ² − (4 + Φ)ξ + 1 + Φ] ψ_a
//!   − p 6(ξ² − ξ)/l v_b + p [3ξ² − (2 − Φ)ξ] ψ_b
//! ```
//!
//! (`Φ_xy = 12 EI_z/(κGA_y l²)` in `x–y`, `Φ_xz = 12 EI_y/(κGA_z l²)` in
//! `x–z` with the signs of `θ_y` above). The shear strain `v' − ψ =
//! p Φ [−1/l, −1/2, 1/l, −1/2]·(v_a, ψ_a, v_b, ψ_b)` is constant per element.
//! The element matrices are the same integrals with these shapes,
//!
//! ```text
//! M_e += ∫ ρI_y N_θyᵀ N_θy + ρI_z N_θzᵀ N_θz dx        rotary inertia of the sections
//! K_e  = ∫ … + EI_z N_ψxy'ᵀ N_ψxy' + κGA_y γ_xyᵀ γ_xy + (x–z alike) dx
//! ```
//!
//! (degree ≤ 6, exact with the 4-point rule): the stiffness is
//! Przemieniecki's `EI/((1+Φ) l³) [12, 6l, −12, 6l; 6l, (4+Φ)l², −6l,
//! (2−Φ)l²; …]` and the mass the consistent Timoshenko mass of the same
//! shapes (translational and rotary parts). `Φ = 0` takes the Hermite
//! cubics above, so a beam without [`Shear`] is the Euler–Bernoulli beam bit
//! for bit. `K_G` uses the slope `v'` of the axis (the foreshortening of the
//! centroid line; the model format refuses stiffening with shear, see
//! `docs/model-format.md`).

use nalgebra::{DMatrix, DVector, Matrix3xX, SMatrix, SVector};

use super::FlexError;

/// A 12×12 element matrix.
pub type ElementMatrix = SMatrix<f64, 12, 12>;

/// Gauss–Legendre points and weights on `[0, 1]`, 4 points (exact to degree 7).
pub const GAUSS4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// The six degrees of freedom of a node, in their order in the assembled vectors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NodeDof {
    /// Axial translation `u_x`.
    Ux,
    /// Transverse translation `u_y`.
    Uy,
    /// Transverse translation `u_z`.
    Uz,
    /// Torsion `θ_x`.
    Rx,
    /// Bending rotation `θ_y = −∂u_z/∂x`.
    Ry,
    /// Bending rotation `θ_z = ∂u_y/∂x`.
    Rz,
}

impl NodeDof {
    /// All six, in order.
    pub const ALL: [NodeDof; 6] = [
        NodeDof::Ux,
        NodeDof::Uy,
        NodeDof::Uz,
        NodeDof::Rx,
        NodeDof::Ry,
        NodeDof::Rz,
    ];

    /// Offset within the node's six.
    pub fn offset(self) -> usize {
        self as usize
    }

    /// The name used in messages (`u_x`, …, `θ_z`).
    pub fn name(self) -> &'static str {
        ["u_x", "u_y", "u_z", "θ_x", "θ_y", "θ_z"][self as usize]
    }
}

/// The deformation a beam mode belongs to (a straight beam decouples them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Deformation {
    /// Axial (`u_x`).
    Axial,
    /// Torsion (`θ_x`).
    Torsion,
    /// Bending in the `x–y` plane (`u_y`, `θ_z`; stiffness `EI_z`).
    BendingXy,
    /// Bending in the `x–z` plane (`u_z`, `θ_y`; stiffness `EI_y`).
    BendingXz,
}

/// A straight beam along the body `x` axis from `x = 0` to `x = length`.
///
/// Units are SI and consistent: lengths in m, `rho_a` in kg/m, `rho_ip` in
/// kg m, `ea` in N, `ei_y`, `ei_z` and `gj` in N m².
#[derive(Clone, Debug, PartialEq)]
pub struct Beam {
    /// Length `L`.
    pub length: f64,
    /// Mass per length `ρA`.
    pub rho_a: f64,
    /// Polar mass moment per length `ρI_p` (torsion inertia).
    pub rho_ip: f64,
    /// Axial stiffness `EA`.
    pub ea: f64,
    /// Bending stiffness about `y` (bending in the `x–z` plane), `EI_y`.
    pub ei_y: f64,
    /// Bending stiffness about `z` (bending in the `x–y` plane), `EI_z`.
    pub ei_z: f64,
    /// Torsional stiffness `GJ`.
    pub gj: f64,
    /// Number of elements `n`.
    pub elements: usize,
    /// Shear deformation and rotary inertia (Timoshenko); `None` is the
    /// Euler–Bernoulli beam.
    pub shear: Option<Shear>,
}

/// The Timoshenko data of a beam: shear stiffnesses and the sections'
/// rotary inertia in bending. Units: N for the shear stiffnesses, kg m for
/// the rotary inertias (mass moment per length).
///
/// The element is the interdependent interpolation element (IIE; see the
/// module docs), with the shear parameters
/// `Φ_xy = 12 EI_z / (κGA_y l²)` (bending in `x–y`, shear force `Q_y`) and
/// `Φ_xz = 12 EI_y / (κGA_z l²)` (bending in `x–z`, shear force `Q_z`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shear {
    /// Effective shear stiffness for shear along `y`, `κ_y G A` (bending in `x–y`).
    pub kga_y: f64,
    /// Effective shear stiffness for shear along `z`, `κ_z G A` (bending in `x–z`).
    pub kga_z: f64,
    /// Rotary inertia per length about `y`, `ρI_y` (bending in `x–z`); 0 leaves it out.
    pub rho_iy: f64,
    /// Rotary inertia per length about `z`, `ρI_z` (bending in `x–y`); 0 leaves it out.
    pub rho_iz: f64,
}

/// Translation and small rotation of a section, per coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// Translation `ū_f = S q` (3 × columns).
    pub translation: Matrix3xX<f64>,
    /// Small rotation `θ = S_θ q` (3 × columns).
    pub rotation: Matrix3xX<f64>,
}

/// The rows of the element interpolation at one point (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Interpolation {
    /// Translations `(u_x, u_y, u_z)` from the element's 12 values.
    pub translation: SMatrix<f64, 3, 12>,
    /// Small rotations `(θ_x, θ_y, θ_z)`.
    pub rotation: SMatrix<f64, 3, 12>,
    /// `∂u_x/∂x`, the axial strain.
    pub axial_strain: SVector<f64, 12>,
    /// `∂θ_x/∂x`, the twist.
    pub twist: SVector<f64, 12>,
    /// Curvature in `x–y`: `∂θ_z/∂x` (`= ∂²u_y/∂x²` for Euler–Bernoulli).
    pub curvature_xy: SVector<f64, 12>,
    /// Curvature in `x–z`: `−∂θ_y/∂x` (`= ∂²u_z/∂x²` for Euler–Bernoulli).
    pub curvature_xz: SVector<f64, 12>,
    /// Slopes of the axis `(∂u_y/∂x, ∂u_z/∂x)` (rows 0, 1): for
    /// Euler–Bernoulli `θ_z` and `−θ_y`, for Timoshenko the section rotation
    /// plus the shear strain.
    pub slope: SMatrix<f64, 2, 12>,
    /// Derivatives of the curvatures, `∂(curvature_xy)/∂x` and
    /// `∂(curvature_xz)/∂x` (rows 0, 1), constant in an element: the shear
    /// forces are `Q_y = −EI_z ·` row 0 and `Q_z = −EI_y ·` row 1
    /// (for Timoshenko equal to `κGA_y (u_y' − θ_z)` and `κGA_z (u_z' + θ_y)`).
    pub curvature_rate: SMatrix<f64, 2, 12>,
}

impl Beam {
    /// A beam, checked: every problem at once.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        length: f64,
        rho_a: f64,
        rho_ip: f64,
        ea: f64,
        ei_y: f64,
        ei_z: f64,
        gj: f64,
        elements: usize,
    ) -> Result<Beam, FlexError> {
        let beam = Beam {
            length,
            rho_a,
            rho_ip,
            ea,
            ei_y,
            ei_z,
            gj,
            elements,
            shear: None,
        };
        beam.check()?;
        Ok(beam)
    }

    /// Every problem with the data, at once: non-positive (or non-finite)
    /// length, mass or stiffness, or no elements.
    pub fn check(&self) -> Result<(), FlexError> {
        let mut problems = Vec::new();
        for (name, value, unit) in [
            ("length", self.length, "m"),
            ("rho_a", self.rho_a, "kg/m"),
            ("rho_ip", self.rho_ip, "kg m"),
            ("ea", self.ea, "N"),
            ("ei_y", self.ei_y, "N m²"),
            ("ei_z", self.ei_z, "N m²"),
            ("gj", self.gj, "N m²"),
        ] {
            if !(value.is_finite() && value > 0.0) {
                problems.push(format!(
                    "`{name}` is {value}; it must be a positive number ({unit})"
                ));
            }
        }
        if self.elements == 0 {
            problems.push("`elements` is 0; a beam needs at least one element".to_string());
        }
        if let Some(sh) = &self.shear {
            for (name, value) in [("kga_y", sh.kga_y), ("kga_z", sh.kga_z)] {
                if !(value.is_finite() && value > 0.0) {
                    problems.push(format!(
                        "`{name}` is {value}; a shear stiffness must be a positive number (N)"
                    ));
                }
            }
            for (name, value) in [("rho_iy", sh.rho_iy), ("rho_iz", sh.rho_iz)] {
                if !(value.is_finite() && value >= 0.0) {
                    problems.push(format!(
                        "`{name}` is {value}; a rotary inertia must be zero or positive (kg m)"
                    ));
                }
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(FlexError::InvalidBeam(problems))
        }
    }

    /// Number of nodes, `n + 1`.
    pub fn nodes(&self) -> usize {
        self.elements + 1
    }

    /// Number of nodal degrees of freedom, `6 (n + 1)`.
    pub fn dofs(&self) -> usize {
        6 * self.nodes()
    }

    /// Element length `l = L / n`.
    pub fn element_length(&self) -> f64 {
        self.length / self.elements as f64
    }

    /// Position of node `i` along `x`.
    pub fn node_x(&self, node: usize) -> f64 {
        node as f64 * self.element_length()
    }

    /// Index of a nodal degree of freedom in the assembled vectors.
    pub fn dof(&self, node: usize, dof: NodeDof) -> usize {
        6 * node + dof.offset()
    }

    /// The element containing `x` and the local `ξ` (clamped to the beam).
    pub fn locate(&self, x: f64) -> (usize, f64) {
        let l = self.element_length();
        let x = x.clamp(0.0, self.length);
        let e = ((x / l).floor() as usize).min(self.elements.saturating_sub(1));
        (e, (x - e as f64 * l) / l)
    }

    /// The Euler–Bernoulli interpolation rows of an element of length `l`
    /// at `ξ` (Hermite cubics; the module docs).
    pub fn interpolation(l: f64, xi: f64) -> Interpolation {
        Self::interpolation_sheared(l, xi, 0.0, 0.0)
    }

    /// The shear parameters `(Φ_xy, Φ_xz)` of this beam's elements,
    /// `12 EI_z / (κGA_y l²)` and `12 EI_y / (κGA_z l²)`; `(0, 0)` for
    /// Euler–Bernoulli.
    pub fn shear_parameters(&self) -> (f64, f64) {
        match &self.shear {
            None => (0.0, 0.0),
            Some(s) => {
                let l2 = self.element_length().powi(2);
                (
                    12.0 * self.ei_z / (s.kga_y * l2),
                    12.0 * self.ei_y / (s.kga_z * l2),
                )
            }
        }
    }

    /// The interpolation rows of this beam's elements at `ξ` (Timoshenko's
    /// interdependent interpolation when the beam has [`Shear`]).
    pub fn element_interpolation(&self, xi: f64) -> Interpolation {
        let (pxy, pxz) = self.shear_parameters();
        Self::interpolation_sheared(self.element_length(), xi, pxy, pxz)
    }

    /// The interpolation rows of an element of length `l` at `ξ` with the
    /// shear parameters `Φ_xy`, `Φ_xz` (0: the Hermite cubics of
    /// Euler–Bernoulli, exactly; see the module docs).
    pub fn interpolation_sheared(l: f64, xi: f64, phi_xy: f64, phi_xz: f64) -> Interpolation {
        let pxy = plane_shapes(l, xi, phi_xy);
        let pxz = plane_shapes(l, xi, phi_xz);
        // Element dofs of bending in x–y (u_y, θ_z) and x–z (u_z, θ_y, with −).
        let xy = [1, 5, 7, 11];
        let xz = [2, 4, 8, 10];
        let sz = [1.0, -1.0, 1.0, -1.0];
        let mut t = SMatrix::<f64, 3, 12>::zeros();
        let mut r = SMatrix::<f64, 3, 12>::zeros();
        let mut axial = SVector::<f64, 12>::zeros();
        let mut twist = SVector::<f64, 12>::zeros();
        let mut kxy = SVector::<f64, 12>::zeros();
        let mut kxz = SVector::<f64, 12>::zeros();
        let mut slope = SMatrix::<f64, 2, 12>::zeros();
        let mut rate = SMatrix::<f64, 2, 12>::zeros();
        t[(0, 0)] = 1.0 - xi;
        t[(0, 6)] = xi;
        r[(0, 3)] = 1.0 - xi;
        r[(0, 9)] = xi;
        axial[0] = -1.0 / l;
        axial[6] = 1.0 / l;
        twist[3] = -1.0 / l;
        twist[9] = 1.0 / l;
        for a in 0..4 {
            t[(1, xy[a])] = pxy.v[a];
            t[(2, xz[a])] = sz[a] * pxz.v[a];
            r[(2, xy[a])] = pxy.psi[a]; // θ_z = ψ_xy (= u_y' for Euler–Bernoulli)
            r[(1, xz[a])] = -sz[a] * pxz.psi[a]; // θ_y = −ψ_xz (= −u_z')
            kxy[xy[a]] = pxy.dpsi[a];
            kxz[xz[a]] = sz[a] * pxz.dpsi[a];
            slope[(0, xy[a])] = pxy.dv[a];
            slope[(1, xz[a])] = sz[a] * pxz.dv[a];
            rate[(0, xy[a])] = pxy.ddpsi[a];
            rate[(1, xz[a])] = sz[a] * pxz.ddpsi[a];
        }
        Interpolation {
            translation: t,
            rotation: r,
            axial_strain: axial,
            twist,
            curvature_xy: kxy,
            curvature_xz: kxz,
            slope,
            curvature_rate: rate,
        }
    }

    /// Consistent element mass `M_e = ∫ ρA NᵀN + ρI_p N_θxᵀ N_θx dx`, for
    /// Timoshenko plus the rotary inertia `∫ ρI_y N_θyᵀ N_θy + ρI_z N_θzᵀ N_θz dx`.
    pub fn element_mass(&self) -> ElementMatrix {
        let l = self.element_length();
        let mut m = ElementMatrix::zeros();
        for (xi, w) in GAUSS4 {
            let s = self.element_interpolation(xi);
            let rx = s.rotation.row(0);
            m += (s.translation.transpose() * s.translation) * (self.rho_a * w * l)
                + (rx.transpose() * rx) * (self.rho_ip * w * l);
            if let Some(sh) = &self.shear {
                let (ry, rz) = (s.rotation.row(1), s.rotation.row(2));
                m += (ry.transpose() * ry) * (sh.rho_iy * w * l)
                    + (rz.transpose() * rz) * (sh.rho_iz * w * l);
            }
        }
        m
    }

    /// Element stiffness: axial `EA`, torsion `GJ`, bending `EI_z` (x–y) and
    /// `EI_y` (x–z), for Timoshenko plus the shear `κGA_y γ_xy² + κGA_z γ_xz²`
    /// with `γ_xy = u_y' − θ_z`, `γ_xz = u_z' + θ_y`.
    pub fn element_stiffness(&self) -> ElementMatrix {
        let l = self.element_length();
        let mut k = ElementMatrix::zeros();
        for (xi, w) in GAUSS4 {
            let s = self.element_interpolation(xi);
            k += (s.axial_strain * s.axial_strain.transpose()) * (self.ea * w * l)
                + (s.twist * s.twist.transpose()) * (self.gj * w * l)
                + (s.curvature_xy * s.curvature_xy.transpose()) * (self.ei_z * w * l)
                + (s.curvature_xz * s.curvature_xz.transpose()) * (self.ei_y * w * l);
            if let Some(sh) = &self.shear {
                let gxy = (s.slope.row(0) - s.rotation.row(2)).transpose();
                let gxz = (s.slope.row(1) + s.rotation.row(1)).transpose();
                k += (gxy * gxy.transpose()) * (sh.kga_y * w * l)
                    + (gxz * gxz.transpose()) * (sh.kga_z * w * l);
            }
        }
        k
    }

    /// Geometric stiffness of element `e` under the axial force `P(x)`
    /// (tension positive): `K_G = ∫ P (u_y'ᵀu_y' + u_z'ᵀu_z') dx`. Exact when `P`
    /// is a polynomial of degree ≤ 3 on the element.
    pub fn element_geometric(&self, e: usize, axial_force: &dyn Fn(f64) -> f64) -> ElementMatrix {
        let l = self.element_length();
        let x0 = self.node_x(e);
        let mut k = ElementMatrix::zeros();
        for (xi, w) in GAUSS4 {
            let s = self.element_interpolation(xi);
            let p = axial_force(x0 + xi * l);
            let (vy, vz) = (s.slope.row(0), s.slope.row(1)); // u_y', u_z'
            k += (vy.transpose() * vy + vz.transpose() * vz) * (p * w * l);
        }
        k
    }

    /// Add an element matrix into the assembled one.
    fn scatter(global: &mut DMatrix<f64>, e: usize, local: &ElementMatrix) {
        let mut block = global.view_mut((6 * e, 6 * e), (12, 12));
        block += local;
    }

    /// Assembled consistent mass matrix (`6(n+1)` square).
    pub fn mass(&self) -> DMatrix<f64> {
        let me = self.element_mass();
        let mut m = DMatrix::zeros(self.dofs(), self.dofs());
        for e in 0..self.elements {
            Self::scatter(&mut m, e, &me);
        }
        m
    }

    /// Assembled stiffness matrix (`6(n+1)` square).
    pub fn stiffness(&self) -> DMatrix<f64> {
        let ke = self.element_stiffness();
        let mut k = DMatrix::zeros(self.dofs(), self.dofs());
        for e in 0..self.elements {
            Self::scatter(&mut k, e, &ke);
        }
        k
    }

    /// Assembled geometric stiffness under the axial force `P(x)` (tension positive).
    pub fn geometric_stiffness(&self, axial_force: &dyn Fn(f64) -> f64) -> DMatrix<f64> {
        let mut k = DMatrix::zeros(self.dofs(), self.dofs());
        for e in 0..self.elements {
            Self::scatter(&mut k, e, &self.element_geometric(e, axial_force));
        }
        k
    }

    /// Axial force per unit `Ω²` at `x` in a beam spinning at `Ω` about an axis
    /// normal to it at distance `hub_radius` before `x = 0` (tip free):
    /// `P(x)/Ω² = ρA [r (L − x) + (L² − x²)/2]`. With
    /// [`geometric_stiffness`](Self::geometric_stiffness) this gives the
    /// spin-up stiffening `Ω² K_G` (Kane, Ryan and Banerjee 1987).
    pub fn centrifugal_force(&self, hub_radius: f64, x: f64) -> f64 {
        let l = self.length;
        self.rho_a * (hub_radius * (l - x) + 0.5 * (l * l - x * x))
    }

    /// The six rigid-body motions as nodal vectors (columns: translations along
    /// `x, y, z`, then rotations about `x, y, z`). The kernel of [`stiffness`](Self::stiffness).
    pub fn rigid_modes(&self) -> DMatrix<f64> {
        let mut r = DMatrix::zeros(self.dofs(), 6);
        for i in 0..self.nodes() {
            let x = self.node_x(i);
            for j in 0..3 {
                r[(6 * i + j, j)] = 1.0; // translations
                r[(6 * i + 3 + j, 3 + j)] = 1.0; // rotations
            }
            r[(6 * i + 2, 4)] = -x; // about y: u_z = −x θ
            r[(6 * i + 1, 5)] = x; // about z: u_y = x θ
        }
        r
    }

    /// Translation and small rotation at `x` of each column of `shapes`
    /// (nodal vectors, `6(n+1)` rows): the FE interpolation of the mode shapes.
    pub fn section(&self, x: f64, shapes: &DMatrix<f64>) -> Section {
        let (e, xi) = self.locate(x);
        let s = self.element_interpolation(xi);
        let local = shapes.rows(6 * e, 12);
        Section {
            translation: s.translation * local,
            rotation: s.rotation * local,
        }
    }

    /// Which deformation a nodal vector is (the largest share of its squared
    /// entries, rotations scaled by `L`).
    pub fn classify(&self, shape: &DVector<f64>) -> Deformation {
        let mut share = [0.0_f64; 4];
        for (i, v) in shape.iter().enumerate() {
            let (scale, group) = match i % 6 {
                0 => (1.0, 0),
                3 => (self.length, 1),
                1 => (1.0, 2),
                5 => (self.length, 2),
                2 => (1.0, 3),
                _ => (self.length, 3),
            };
            share[group] += (scale * v).powi(2);
        }
        let best = (0..4)
            .max_by(|&a, &b| share[a].total_cmp(&share[b]))
            .unwrap_or(0);
        [
            Deformation::Axial,
            Deformation::Torsion,
            Deformation::BendingXy,
            Deformation::BendingXz,
        ][best]
    }
}

/// The shape functions of one bending plane on `(v_a, ψ_a, v_b, ψ_b)`
/// (`ψ` the section rotation, `v` the transverse displacement) and their
/// `x`-derivatives.
struct PlaneShapes {
    v: [f64; 4],
    dv: [f64; 4],
    psi: [f64; 4],
    dpsi: [f64; 4],
    ddpsi: [f64; 4],
}

/// Hermite cubics for `Φ = 0` (`ψ = v'`), else the interdependent
/// interpolation of Timoshenko's beam (Friedman and Kosmatka 1993; the
/// module docs), which tends to the Hermite cubics as `Φ → 0`.
fn plane_shapes(l: f64, xi: f64, phi: f64) -> PlaneShapes {
    let (x2, x3) = (xi * xi, xi * xi * xi);
    if phi == 0.0 {
        let d = [
            (-6.0 * xi + 6.0 * x2) / l,
            1.0 - 4.0 * xi + 3.0 * x2,
            (6.0 * xi - 6.0 * x2) / l,
            3.0 * x2 - 2.0 * xi,
        ];
        return PlaneShapes {
            v: [
                1.0 - 3.0 * x2 + 2.0 * x3,
                l * (xi - 2.0 * x2 + x3),
                3.0 * x2 - 2.0 * x3,
                l * (x3 - x2),
            ],
            dv: d,
            psi: d,
            dpsi: [
                (-6.0 + 12.0 * xi) / (l * l),
                (-4.0 + 6.0 * xi) / l,
                (6.0 - 12.0 * xi) / (l * l),
                (-2.0 + 6.0 * xi) / l,
            ],
            ddpsi: [
                12.0 / l.powi(3),
                6.0 / (l * l),
                -12.0 / l.powi(3),
                6.0 / (l * l),
            ],
        };
    }
    let p = 1.0 / (1.0 + phi);
    let h = 0.5 * phi;
    PlaneShapes {
        v: [
            p * (2.0 * x3 - 3.0 * x2 - phi * xi + 1.0 + phi),
            p * l * (x3 - (2.0 + h) * x2 + (1.0 + h) * xi),
            p * (-2.0 * x3 + 3.0 * x2 + phi * xi),
            p * l * (x3 - (1.0 - h) * x2 - h * xi),
        ],
        dv: [
            p * (6.0 * x2 - 6.0 * xi - phi) / l,
            p * (3.0 * x2 - (4.0 + phi) * xi + 1.0 + h),
            p * (-6.0 * x2 + 6.0 * xi + phi) / l,
            p * (3.0 * x2 - (2.0 - phi) * xi - h),
        ],
        psi: [
            p * 6.0 * (x2 - xi) / l,
            p * (3.0 * x2 - (4.0 + phi) * xi + 1.0 + phi),
            -p * 6.0 * (x2 - xi) / l,
            p * (3.0 * x2 - (2.0 - phi) * xi),
        ],
        dpsi: [
            p * 6.0 * (2.0 * xi - 1.0) / (l * l),
            p * (6.0 * xi - 4.0 - phi) / l,
            -p * 6.0 * (2.0 * xi - 1.0) / (l * l),
            p * (6.0 * xi - 2.0 + phi) / l,
        ],
        ddpsi: [
            p * 12.0 / (l * l * l),
            p * 6.0 / (l * l),
            -p * 12.0 / (l * l * l),
            p * 6.0 / (l * l),
        ],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn beam() -> Beam {
        Beam::new(2.0, 3.0, 0.05, 7.0e6, 2.0e3, 5.0e3, 1.5e3, 4).unwrap()
    }

    fn close(got: f64, want: f64, what: &str) {
        assert!(
            (got - want).abs() <= 1e-10 * want.abs().max(1.0),
            "{what}: got {got}, want {want}"
        );
    }

    #[test]
    fn flex_element_matrices_are_przemienieckis_closed_forms() {
        // Przemieniecki §5.6 / §11.3: bending mass ρA l/420 [156, 22l, 54, −13l, 4l², −3l²],
        // bending stiffness EI/l³ [12, 6l, −12, 6l, 4l², 2l²], axial ρA l/6 [2, 1], EA/l [1, −1].
        let b = beam();
        let l = b.element_length();
        let (m, k) = (b.element_mass(), b.element_stiffness());
        let c = b.rho_a * l / 420.0;
        close(m[(1, 1)], 156.0 * c, "m(u_y,u_y)");
        close(m[(1, 5)], 22.0 * l * c, "m(u_y,θ_z)");
        close(m[(1, 7)], 54.0 * c, "m(u_ya,u_yb)");
        close(m[(1, 11)], -13.0 * l * c, "m(u_ya,θ_zb)");
        close(m[(5, 5)], 4.0 * l * l * c, "m(θ_z,θ_z)");
        close(m[(5, 11)], -3.0 * l * l * c, "m(θ_za,θ_zb)");
        close(m[(2, 4)], -22.0 * l * c, "m(u_z,θ_y)");
        close(m[(2, 10)], 13.0 * l * c, "m(u_za,θ_yb)");
        close(m[(0, 0)], b.rho_a * l / 3.0, "m(u_x,u_x)");
        close(m[(0, 6)], b.rho_a * l / 6.0, "m(u_xa,u_xb)");
        close(m[(3, 3)], b.rho_ip * l / 3.0, "m(θ_x,θ_x)");
        let ez = b.ei_z / l.powi(3);
        close(k[(1, 1)], 12.0 * ez, "k(u_y,u_y)");
        close(k[(1, 5)], 6.0 * l * ez, "k(u_y,θ_z)");
        close(k[(5, 11)], 2.0 * l * l * ez, "k(θ_za,θ_zb)");
        let ey = b.ei_y / l.powi(3);
        close(k[(2, 4)], -6.0 * l * ey, "k(u_z,θ_y)");
        close(k[(4, 4)], 4.0 * l * l * ey, "k(θ_y,θ_y)");
        close(k[(0, 6)], -b.ea / l, "k(u_xa,u_xb)");
        close(k[(3, 9)], -b.gj / l, "k(θ_xa,θ_xb)");
        let g = b.element_geometric(0, &|_| 30.0 * l);
        close(g[(1, 1)], 36.0, "k_G(u_y,u_y)");
        close(g[(1, 5)], 3.0 * l, "k_G(u_y,θ_z)");
        close(g[(5, 11)], -l * l, "k_G(θ_za,θ_zb)");
    }

    #[test]
    fn flex_rigid_modes_cost_no_strain_energy() {
        let b = beam();
        let kr = b.stiffness() * b.rigid_modes();
        assert!(kr.amax() < 1e-6, "K·rigid = {}", kr.amax());
    }

    #[test]
    fn flex_section_interpolates_nodal_values_and_classifies() {
        // At a node the interpolation returns that node's six values; a
        // nodal vector with only u_y and θ_z is bending in x–y.
        let b = beam();
        let shapes = DMatrix::from_fn(b.dofs(), 2, |i, j| (i * 7 + j * 3) as f64 * 0.01);
        for node in 0..b.nodes() {
            let s = b.section(b.node_x(node), &shapes);
            for c in 0..2 {
                for r in 0..3 {
                    let (t, q) = (shapes[(6 * node + r, c)], shapes[(6 * node + 3 + r, c)]);
                    assert!(
                        (s.translation[(r, c)] - t).abs() < 1e-12,
                        "node {node} u[{r}]"
                    );
                    assert!((s.rotation[(r, c)] - q).abs() < 1e-12, "node {node} θ[{r}]");
                }
            }
        }
        let mut v = DVector::zeros(b.dofs());
        v[b.dof(2, NodeDof::Uy)] = 1.0;
        v[b.dof(2, NodeDof::Rz)] = 0.3;
        assert_eq!(b.classify(&v), Deformation::BendingXy);
    }

    #[test]
    fn flex_beam_reports_every_problem() {
        let err = Beam::new(-1.0, 0.0, 1.0, 1.0, 1.0, f64::NAN, 1.0, 0).unwrap_err();
        let FlexError::InvalidBeam(problems) = err else {
            panic!("want InvalidBeam")
        };
        assert_eq!(problems.len(), 4, "{problems:?}");
    }
}
