//! The floating-frame mass matrix and quadratic velocity vector of one free
//! flexible body, numerically (Shabana 5.5), from its [`Invariants`].
//!
//! Coordinates: the frame origin `R` (inertial), its orientation `A`
//! (body → inertial), the elastic coordinates `q_f`. Speeds
//! `u = (Ṙ, ω̄, q̇_f)` with `ω̄` the frame's angular velocity in body
//! coordinates (`Ȧ = A ω̃̄`): Shabana's blocks with `Ḡ = 1`, so `m_θθ = Ī_θθ`
//! instead of `Ḡᵀ Ī_θθ Ḡ`. A point at `ū = ū₀ + S q_f` moves with
//!
//! ```text
//! v = L u,         L = [ 1,  −A ũ,  A S ]
//! a = L u̇ + γ,     γ = A (ω̃ ω̃ ū + 2 ω̃ S q̇_f)
//! ```
//!
//! and the equations are `M(q) u̇ = Q_v + Q_e − (0, 0, K_ff q_f)` with
//! `M = ∫ρ Lᵀ L dV` and `Q_v = −∫ρ Lᵀ γ dV` (plus the section spin, see
//! [`invariants`](super::invariants)):
//!
//! ```text
//!        ⎡ m 1    −A ũ_t      A S̄    ⎤      ũ_t = skew(I₁ + S̄ q_f)
//! M(q) = ⎢        Ī_θθ(q_f)   Ī_θf(q_f)⎥
//!        ⎣ sym                 M_ff   ⎦
//!
//! Q_v,R = −A (ω̃ ω̃ (I₁ + S̄ q_f) + 2 ω̃ S̄ q̇_f)
//! Q_v,θ = −ω̃ Ī_θθ ω − 2 (tr C_v 1 − C_vᵀ) ω − ω̃ c_s q̇_f,   C_v = ∫ρ ū (S q̇_f)ᵀ dV
//! Q_v,f = −∫ρ Sᵀ ω̃ ω̃ ū dV − 2 ∫ρ Sᵀ ω̃ S dV q̇_f
//!       = −Σ_ij (ω̃ω̃)_ij (X_ji + S̄_ij q_f) − 2 Σ_ij ω̃_ij S̄_ij q̇_f
//! ```
//!
//! (`u × (ω × w) = ω (u·w) − w (u·ω)` gives `Q_v,θ`'s middle term; the first
//! is `Σ m ũ ω̃ ω̃ ū = ω̃ Ī ω`; `c_s q̇_f = (c_p · q̇_f, c_r q̇_f)` is the
//! sections' own angular momentum from the deformation rate: torsion, and
//! the rotary inertia of Timoshenko beams.) With `k = 0` this is the rigid body's
//! `[m 1, −A c̃; ·, Ī]` and `−(A ω̃ ω̃ c, ω̃ Ī ω)`.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use super::Invariants;

/// `ṽ`, the cross-product matrix (`ṽ w = v × w`).
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    v.cross_matrix()
}

/// The FFR mass matrix `M(q)` (`6 + k` square) for speeds `(Ṙ, ω̄, q̇_f)`.
pub fn mass_matrix(inv: &Invariants, a: &Matrix3<f64>, q: &DVector<f64>) -> DMatrix<f64> {
    let k = inv.modes();
    let mut m = DMatrix::zeros(6 + k, 6 + k);
    let m_rt = -a * skew(&inv.first_moment_at(q));
    let m_rf = a * &inv.s_bar;
    let m_tf = inv.coupling_at(q);
    m.view_mut((0, 0), (3, 3))
        .copy_from(&(Matrix3::identity() * inv.mass));
    m.view_mut((0, 3), (3, 3)).copy_from(&m_rt);
    m.view_mut((3, 0), (3, 3)).copy_from(&m_rt.transpose());
    m.view_mut((3, 3), (3, 3)).copy_from(&inv.inertia_at(q));
    m.view_mut((0, 6), (3, k)).copy_from(&m_rf);
    m.view_mut((6, 0), (k, 3)).copy_from(&m_rf.transpose());
    m.view_mut((3, 6), (3, k)).copy_from(&m_tf);
    m.view_mut((6, 3), (k, 3)).copy_from(&m_tf.transpose());
    m.view_mut((6, 6), (k, k)).copy_from(&inv.modal_mass);
    m
}

/// The quadratic velocity vector `Q_v` (`6 + k`): minus the inertia forces
/// quadratic in the speeds, for `ω̄` in body coordinates and `q̇_f`.
pub fn quadratic_velocity(
    inv: &Invariants,
    a: &Matrix3<f64>,
    q: &DVector<f64>,
    omega: &Vector3<f64>,
    qd: &DVector<f64>,
) -> DVector<f64> {
    let k = inv.modes();
    let w = skew(omega);
    let ww = w * w;
    let sq = &inv.s_bar * qd;
    let sqd = Vector3::new(sq[0], sq[1], sq[2]);
    let q_r = -a * (ww * inv.first_moment_at(q) + 2.0 * w * sqd);
    let cv = inv.rate_moment(q, qd);
    let q_t = -w * (inv.inertia_at(q) * omega)
        - 2.0 * (Matrix3::identity() * cv.trace() - cv.transpose()) * omega
        - w * inv.section_rate(qd);
    let q_f = -inv.modal_load(&ww, q) - inv.modal_quadratic(&w) * qd * 2.0;
    let mut out = DVector::zeros(6 + k);
    out.rows_mut(0, 3).copy_from(&q_r);
    out.rows_mut(3, 3).copy_from(&q_t);
    out.rows_mut(6, k).copy_from(&q_f);
    out
}

/// Kinetic energy `T = ½ uᵀ M(q) u`.
pub fn kinetic_energy(
    inv: &Invariants,
    a: &Matrix3<f64>,
    q: &DVector<f64>,
    speeds: &DVector<f64>,
) -> f64 {
    0.5 * speeds.dot(&(mass_matrix(inv, a, q) * speeds))
}
