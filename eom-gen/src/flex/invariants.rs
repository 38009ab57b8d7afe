//! The inertia shape integrals of a reduced flexible body (Shabana 5.2;
//! Wallrapp's standard input data, SID; Adams' I1…I9 are the same integrals
//! grouped differently).
//!
//! The body is the beam's line of mass `ρA` at `ū₀ = (x, 0, 0)`, displaced by
//! `ū_f = S(x) q_f` with `S = N(x) Φ` (the element interpolation times the
//! nodal shapes), plus the torsion inertia `ρI_p` of each section spinning
//! about the body `x` axis at `ω_x + θ̇_x`, `θ_x = φ_x(x) q_f`:
//!
//! ```text
//! T = ½ ∫ ρA |Ṙ + A(ω̃ (ū₀ + S q_f) + S q̇_f)|² dx  +  ½ ∫ ρI_p (ω_x + φ_x q̇_f)² dx
//! ```
//!
//! (bending rotary inertia is left out, as in the Euler–Bernoulli FE mass).
//! A Timoshenko beam ([`super::beam::Shear`]) adds the rotary inertia of its
//! sections in bending, `½ ∫ ρI_y (ω_y + φ_y q̇_f)² + ρI_z (ω_z + φ_z q̇_f)² dx`
//! with `θ_y = φ_y q_f`, `θ_z = φ_z q_f` the section rotations `ψ` (not the
//! slopes): `J_r = (∫ρI_y, ∫ρI_z)` joins `Ī` about `y` and `z`, `c_r =
//! (∫ρI_y φ_yᵀ, ∫ρI_z φ_zᵀ)` joins rows `y`, `z` of `Ī_θf`, `M_r` joins
//! `M_ff` (so `M_ff = Φᵀ M Φ` with the Timoshenko consistent mass), and
//! the frame's moment equation gets `ω × (c_r q̇_f)` as it gets `ω × e_x
//! (c_p · q̇_f)`. `S` is then the IIE displacement field of the axis.
//! The integrals below are taken element by element with the 4-point Gauss
//! rule of the FE matrices; the integrands are polynomials of degree ≤ 6, so
//! they are exact, and `M_ff` equals `Φᵀ M Φ` with the consistent mass:
//!
//! ```text
//! m      = ∫ρ dV                        mass
//! I₁     = ∫ρ ū₀ dV                     first moment (3)
//! J₀     = ∫ρ ū₀ ū₀ᵀ dV                 second moment (3×3)
//! Ī      = ∫ρ ũ₀ᵀ ũ₀ dV + J_p e_x e_xᵀ   inertia tensor of the undeformed body (3×3)
//! S̄      = ∫ρ S dV                      (3×k)
//! S̄_ij   = ∫ρ S_iᵀ S_j dV               i, j ∈ {x, y, z} (k×k), S_i the rows of S
//! X_ij   = ∫ρ ū₀_i S_j dV               (k), the first-order coupling
//! Ī_θf⁰  = ∫ρ ũ₀ S dV + e_x c_pᵀ         coupling at q_f = 0 (3×k)
//! J_p    = ∫ρI_p dx,  c_p = ∫ρI_p φ_xᵀ dx,  M_p = ∫ρI_p φ_xᵀ φ_x dx
//! M_ff   = Σ_i S̄_ii + M_p               modal mass (k×k)
//! K_ff   = Φᵀ K Φ                        modal stiffness (k×k)
//! ```
//!
//! From these, at any `q_f` (Shabana 5.2, the deformed-body integrals):
//! `∫ρ ū dV = I₁ + S̄ q_f`, `∫ρ ū ūᵀ dV = J₀ + X(q_f) + X(q_f)ᵀ + Q(q_f)`
//! with `X_ij = X_ij · q_f`, `Q_ij = q_fᵀ S̄_ij q_f`, and the inertia tensor
//! `Ī_θθ = tr(∫ρūūᵀ) 1 − ∫ρūūᵀ + J_p e_x e_xᵀ`.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use super::beam::GAUSS4;
use super::{Beam, Modes};

/// The inertia shape integrals of one reduced flexible body, in its body frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Invariants {
    /// `m = ∫ρ dV`.
    pub mass: f64,
    /// `I₁ = ∫ρ ū₀ dV`.
    pub first_moment: Vector3<f64>,
    /// `J₀ = ∫ρ ū₀ ū₀ᵀ dV`.
    pub second_moment: Matrix3<f64>,
    /// `Ī = ∫ρ ũ₀ᵀ ũ₀ dV + J_p e_x e_xᵀ`, the undeformed body's inertia tensor about the frame origin.
    pub inertia: Matrix3<f64>,
    /// `S̄ = ∫ρ S dV` (3×k).
    pub s_bar: DMatrix<f64>,
    /// `S̄_ij = ∫ρ S_iᵀ S_j dV` (k×k), indexed `[i][j]`.
    pub s_ij: [[DMatrix<f64>; 3]; 3],
    /// `X_ij = ∫ρ ū₀_i S_j dV` (k), indexed `[i][j]`.
    pub x_s: [[DVector<f64>; 3]; 3],
    /// `Ī_θf⁰ = ∫ρ ũ₀ S dV + e_x c_pᵀ` (3×k), the rotation–deformation coupling at `q_f = 0`.
    pub coupling: DMatrix<f64>,
    /// `J_p = ∫ρI_p dx`, the sections' torsion inertia.
    pub spin_inertia: f64,
    /// `c_p = ∫ρI_p φ_xᵀ dx` (k).
    pub spin_modes: DVector<f64>,
    /// `J_r = (∫ρI_y dx, ∫ρI_z dx)`, the sections' rotary inertia in bending
    /// (Timoshenko beams; zero otherwise).
    pub rotary_inertia: [f64; 2],
    /// `c_r`: rows `∫ρI_y φ_yᵀ dx` and `∫ρI_z φ_zᵀ dx` (2×k; zero without
    /// rotary inertia).
    pub rotary_modes: DMatrix<f64>,
    /// `M_ff` (k×k).
    pub modal_mass: DMatrix<f64>,
    /// `K_ff` (k×k).
    pub modal_stiffness: DMatrix<f64>,
}

impl Invariants {
    /// The invariants of a beam reduced to `modes`.
    pub fn new(beam: &Beam, modes: &Modes) -> Invariants {
        let k = modes.count();
        let l = beam.element_length();
        let zk = || DMatrix::<f64>::zeros(k, k);
        let zv = || DVector::<f64>::zeros(k);
        let mut inv = Invariants {
            mass: 0.0,
            first_moment: Vector3::zeros(),
            second_moment: Matrix3::zeros(),
            inertia: Matrix3::zeros(),
            s_bar: DMatrix::zeros(3, k),
            s_ij: std::array::from_fn(|_| std::array::from_fn(|_| zk())),
            x_s: std::array::from_fn(|_| std::array::from_fn(|_| zv())),
            coupling: DMatrix::zeros(3, k),
            spin_inertia: 0.0,
            spin_modes: zv(),
            rotary_inertia: [0.0; 2],
            rotary_modes: DMatrix::zeros(2, k),
            modal_mass: zk(),
            modal_stiffness: modes.stiffness.clone(),
        };
        let mut spin_mass = zk();
        let rotary = beam.shear.map_or([0.0; 2], |s| [s.rho_iy, s.rho_iz]);
        for e in 0..beam.elements {
            let local = modes.shapes.rows(6 * e, 12);
            for (xi, w) in GAUSS4 {
                let interp = beam.element_interpolation(xi);
                let s = interp.translation * local; // 3×k
                let phi_x = interp.rotation.row(0) * local; // 1×k
                let u0 = Vector3::new(beam.node_x(e) + xi * l, 0.0, 0.0);
                let dm = beam.rho_a * w * l;
                let dj = beam.rho_ip * w * l;
                inv.mass += dm;
                inv.first_moment += u0 * dm;
                inv.second_moment += u0 * u0.transpose() * dm;
                inv.s_bar += &s * dm;
                for i in 0..3 {
                    for j in 0..3 {
                        inv.s_ij[i][j] += s.row(i).transpose() * s.row(j) * dm;
                        inv.x_s[i][j] += s.row(j).transpose() * (u0[i] * dm);
                    }
                }
                inv.spin_inertia += dj;
                inv.spin_modes += phi_x.transpose() * dj;
                spin_mass += phi_x.transpose() * phi_x * dj;
                for (r, rho_i) in rotary.iter().enumerate() {
                    if *rho_i == 0.0 {
                        continue;
                    }
                    let phi = interp.rotation.row(1 + r) * local; // 1×k
                    let dr = rho_i * w * l;
                    inv.rotary_inertia[r] += dr;
                    let mut row = inv.rotary_modes.row_mut(r);
                    row += &phi * dr;
                    spin_mass += phi.transpose() * phi * dr;
                }
            }
        }
        inv.inertia = inertia_from(&inv.second_moment) + inv.section_inertia();
        inv.coupling = inv.coupling_at(&DVector::zeros(k));
        inv.modal_mass = &inv.s_ij[0][0] + &inv.s_ij[1][1] + &inv.s_ij[2][2] + spin_mass;
        inv
    }

    /// Number of elastic coordinates `k`.
    pub fn modes(&self) -> usize {
        self.s_bar.ncols()
    }

    /// `∫ρ ū dV = I₁ + S̄ q_f`, the first moment of the deformed body.
    pub fn first_moment_at(&self, q: &DVector<f64>) -> Vector3<f64> {
        let sq = &self.s_bar * q;
        self.first_moment + Vector3::new(sq[0], sq[1], sq[2])
    }

    /// `∫ρ ū wᵀ dV` with `ū = ū₀ + S q` and `w = S v`:
    /// `[X_ij · v + qᵀ S̄_ij v]`; `second_moment_at` is the case with `ū₀` in `w` too.
    fn moment_with(&self, q: &DVector<f64>, v: &DVector<f64>) -> Matrix3<f64> {
        Matrix3::from_fn(|i, j| self.x_s[i][j].dot(v) + q.dot(&(&self.s_ij[i][j] * v)))
    }

    /// `∫ρ ū ūᵀ dV = J₀ + X(q) + X(q)ᵀ + Q(q)`.
    pub fn second_moment_at(&self, q: &DVector<f64>) -> Matrix3<f64> {
        let x = Matrix3::from_fn(|i, j| self.x_s[i][j].dot(q));
        let quad = Matrix3::from_fn(|i, j| q.dot(&(&self.s_ij[i][j] * q)));
        self.second_moment + x + x.transpose() + quad
    }

    /// `diag(J_p, J_r,y, J_r,z)`: the sections' own inertia (torsion, and
    /// rotary inertia in bending for Timoshenko beams).
    pub fn section_inertia(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(
            self.spin_inertia,
            self.rotary_inertia[0],
            self.rotary_inertia[1],
        ))
    }

    /// `c_s q̇`: the sections' own angular momentum per unit `ω`-free rate,
    /// `(c_p · q̇, c_r,y · q̇, c_r,z · q̇)`.
    pub fn section_rate(&self, qd: &DVector<f64>) -> Vector3<f64> {
        Vector3::new(
            self.spin_modes.dot(qd),
            self.rotary_modes.row(0).transpose().dot(qd),
            self.rotary_modes.row(1).transpose().dot(qd),
        )
    }

    /// `Ī_θθ(q_f) = ∫ρ ũᵀ ũ dV + diag(J_p, J_r)`, the deformed body's inertia tensor.
    pub fn inertia_at(&self, q: &DVector<f64>) -> Matrix3<f64> {
        inertia_from(&self.second_moment_at(q)) + self.section_inertia()
    }

    /// `Ī_θf(q_f) = ∫ρ ũ S dV + e_x c_pᵀ` (3×k), with
    /// `∫ρ ū_b S_c dV = X_bc + S̄_cb q_f`.
    pub fn coupling_at(&self, q: &DVector<f64>) -> DMatrix<f64> {
        let us = |b: usize, c: usize| &self.x_s[b][c] + &self.s_ij[c][b] * q;
        let mut out = DMatrix::zeros(3, self.modes());
        out.row_mut(0).copy_from(&(us(1, 2) - us(2, 1)).transpose());
        out.row_mut(1).copy_from(&(us(2, 0) - us(0, 2)).transpose());
        out.row_mut(2).copy_from(&(us(0, 1) - us(1, 0)).transpose());
        let mut first = out.row_mut(0);
        first += self.spin_modes.transpose();
        let mut bending = out.rows_mut(1, 2);
        bending += &self.rotary_modes;
        out
    }

    /// `∫ρ Sᵀ W ū dV = Σ_ij W_ij (X_ji + S̄_ij q_f)` (k) for a 3×3 `W`.
    pub fn modal_load(&self, w: &Matrix3<f64>, q: &DVector<f64>) -> DVector<f64> {
        let mut out = DVector::zeros(self.modes());
        for i in 0..3 {
            for j in 0..3 {
                if w[(i, j)] != 0.0 {
                    out += (&self.x_s[j][i] + &self.s_ij[i][j] * q) * w[(i, j)];
                }
            }
        }
        out
    }

    /// `∫ρ Sᵀ W S dV = Σ_ij W_ij S̄_ij` (k×k) for a 3×3 `W`.
    pub fn modal_quadratic(&self, w: &Matrix3<f64>) -> DMatrix<f64> {
        let mut out = DMatrix::zeros(self.modes(), self.modes());
        for i in 0..3 {
            for j in 0..3 {
                if w[(i, j)] != 0.0 {
                    out += &self.s_ij[i][j] * w[(i, j)];
                }
            }
        }
        out
    }

    /// `∫ρ ū (S v)ᵀ dV` (3×3), the moment of the deformation rate `v = q̇_f`.
    pub fn rate_moment(&self, q: &DVector<f64>, v: &DVector<f64>) -> Matrix3<f64> {
        self.moment_with(q, v)
    }
}

/// The shares of a reduced body's matrices that each section datum
/// carries, at the defaults: what makes tunable section data exact
/// (`mech::flexible`). For a fixed basis the integrals are linear in the
/// section data: every translational integral (`m`, `I₁`, `J₀`, `S̄`,
/// `S̄_ij`, `X_ij`, the foreshortening `K₁`, `K₂`) in `ρA`, the torsion
/// inertia's (`J_p`, `c_p`, `M_p`) in `ρI_p`, and
/// `K_ff = EA K_EA + EI_y K_EIy + EI_z K_EIz + GJ K_GJ`. So with `p` a
/// datum at run time and `p₀` its default, each share is its value at the
/// defaults times `p/p₀`.
#[derive(Clone, Debug, PartialEq)]
pub struct Shares {
    /// `M_p = ∫ρI_p φ_xᵀ φ_x dx` (k×k), the torsion inertia's share of
    /// `M_ff` (the rest, `Σ_i S̄_ii`, is `ρA`'s).
    pub spin_mass: DMatrix<f64>,
    /// The shares of `K_ff` of `EA`, `EI_y`, `EI_z`, `GJ` (k×k each), in
    /// that order.
    pub stiffness: [DMatrix<f64>; 4],
}

impl Shares {
    /// The shares of a beam reduced to `modes` (`Φᵀ K_b Φ` of the FE
    /// stiffness with one datum kept, `Φᵀ M Φ` of the torsion mass).
    pub fn of_beam(beam: &Beam, modes: &Modes) -> Shares {
        let only = |f: &dyn Fn(&mut Beam)| {
            let mut b = Beam {
                rho_a: 0.0,
                rho_ip: 0.0,
                ea: 0.0,
                ei_y: 0.0,
                ei_z: 0.0,
                gj: 0.0,
                ..beam.clone()
            };
            f(&mut b);
            b
        };
        let phi = &modes.shapes;
        let project = |m: DMatrix<f64>| {
            let r = phi.transpose() * m * phi;
            (&r + r.transpose()) * 0.5
        };
        Shares {
            spin_mass: project(only(&|b| b.rho_ip = beam.rho_ip).mass()),
            stiffness: [
                project(only(&|b| b.ea = beam.ea).stiffness()),
                project(only(&|b| b.ei_y = beam.ei_y).stiffness()),
                project(only(&|b| b.ei_z = beam.ei_z).stiffness()),
                project(only(&|b| b.gj = beam.gj).stiffness()),
            ],
        }
    }
}

/// `∫ρ ũᵀ ũ = tr(C) 1 − C` from the second moment `C = ∫ρ ū ūᵀ`.
pub fn inertia_from(c: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::identity() * c.trace() - c
}

/// Modal geometric stiffness `Φᵀ K_G Φ` (k×k) under the axial force `P(x)`
/// (tension positive). For spin-up stiffening at rate `Ω`, take
/// `P = Ω² · beam.centrifugal_force(r, x)` (Kane, Ryan and Banerjee 1987):
/// the elastic force becomes `(K_ff + Ω² K_G1) q_f`.
pub fn modal_geometric_stiffness(
    beam: &Beam,
    modes: &Modes,
    axial_force: &dyn Fn(f64) -> f64,
) -> DMatrix<f64> {
    let kg = beam.geometric_stiffness(axial_force);
    let g = modes.shapes.transpose() * kg * &modes.shapes;
    (&g + g.transpose()) * 0.5
}

/// The foreshortening integrals of geometric stiffening (Kane, Ryan and
/// Banerjee 1987; Sharf 1996), `k×k`, symmetric.
///
/// A bent beam's sections move back along its axis: to second order in
/// the deformation, the axial displacement of the section at `x` is
/// `S_x(x) q_f − ½ q_fᵀ G(x) q_f` with `G(x) = ∫₀ˣ (S_y'ᵀ S_y' + S_z'ᵀ S_z') dξ`
/// (measured from the frame's section `x = 0`; the axial modes are then the
/// stretch of the arc, not the axial displacement). Its first and second
/// moments along the axis are the two matrices here:
///
/// ```text
/// K₁ = ∫ρA x G(x) dx = ∫ ρA (L² − x²)/2 (S_y'ᵀS_y' + S_z'ᵀS_z') dx   centrifugal
/// K₂ = ∫ρA G(x) dx   = ∫ ρA (L − x)      (S_y'ᵀS_y' + S_z'ᵀS_z') dx   axial acceleration
/// ```
///
/// which are the modal geometric stiffness matrices under the axial forces
/// `ρA (L² − x²)/2` (a unit `Ω²` spinning about the root) and `ρA (L − x)`
/// (a unit axial acceleration of the root; tip free in both). Returns `(K₁, K₂)`.
pub fn foreshortening(beam: &Beam, modes: &Modes) -> (DMatrix<f64>, DMatrix<f64>) {
    let l = beam.length;
    let k1 = modal_geometric_stiffness(beam, modes, &|x| beam.centrifugal_force(0.0, x));
    let k2 = modal_geometric_stiffness(beam, modes, &|x| beam.rho_a * (l - x));
    (k1, k2)
}
