//! Geometric stiffening of a flexible beam (Kane, Ryan and Banerjee 1987),
//! over any [`Scalar`], added to a [`FlexState`].
//!
//! The linear floating-frame model lets a bent beam keep its length along
//! the axis, so the axial inertia loads (centrifugal force, the frame's
//! axial acceleration, gravity along the beam) do no work on the bending:
//! a spinning beam softens by `−Ω²` in the plane of rotation and nothing
//! stiffens it, and past its first bending frequency the model diverges.
//! Bending shortens the projection of a beam on its axis: to second order
//! the section at `x` moves back by `½ q_fᵀ G(x) q_f`, `G(x) = ∫₀ˣ S'ᵀ S' dξ`
//! (both bending planes). Keeping this foreshortening in the kinetic and
//! gravitational energy to second order in `q_f`
//! ([`crate::flex::invariants::foreshortening`]: `K₁ = ∫ρA x G dx`,
//! `K₂ = ∫ρA G dx`) changes the body's terms as follows (`e_x` the beam
//! axis, body coordinates, frame velocity `v = (ω, v_O)`):
//!
//! ```text
//! first moment     h   += −½ (q_fᵀ K₂ q_f) e_x
//! inertia tensor   Ī   += −(q_fᵀ K₁ q_f) diag(0, 1, 1)
//! momentum of q̇_j  P_j += (0, −(K₂ q_f)_j e_x)
//! frame bias       b   += (−2 (q_fᵀ K₁ q̇_f) diag(0, 1, 1) ω,
//!                          −2 (q_fᵀ K₂ q̇_f) ω × e_x − (q̇_fᵀ K₂ q̇_f) e_x)
//! elastic bias     b_f += (ω_y² + ω_z²) K₁ q_f − (ω × v_O)_x K₂ q_f
//! ```
//!
//! (`b = İ v + Ṗ q̇_f + v ×* P q̇_f` and `b_f = Ṗᵀ v − ∂T/∂q_f` of the
//! added kinetic energy). With `P_jᵀ a` in the elastic equations the
//! stiffness that results is the geometric stiffness of the axial force
//!
//! ```text
//! N(x) = (ω_y² + ω_z²) ρA (L² − x²)/2 − ρA (L − x) (a_O − g)_x
//! ```
//!
//! with `a_O` the absolute acceleration of the frame origin: the
//! centrifugal load about any axis (a hub radius `r` enters through
//! `(ω × v_O)_x = −Ω² r`), the frame's axial acceleration and gravity's
//! component along the beam (gravity is the base acceleration, so `a`
//! holds `−g`). The axial acceleration makes the stiffening depend on
//! accelerations; added to the elastic equations alone it would make the
//! mass matrix non-symmetric (the `−(K₂ q_f) e_xᵀ` block of Wallrapp and
//! Schwertassek's load-dependent `K_G`). Derived from the energy, its
//! transpose appears in the frame's equations (`P` holds it), the mass
//! matrix stays symmetric, and a free system conserves `T + V` exactly:
//! the equations are Lagrange's for the second-order kinetic energy.
//!
//! Left out (third order in `q_f`, or terms the model does not hold):
//! the foreshortening's share of `M_ff` and of `P`'s moments, torsion
//! coupled to bending, and axial loads applied by bodies or forces
//! attached to the beam (bodies carried by the frame load the frame, not
//! the beam's sections). Terms of order `q_f³` are the error of the
//! second-order kinetic energy: relative `(q_f/L)²`.
//!
//! The second-order kinetic energy is not positive definite for every
//! `q_f`: `Ī` loses `q_fᵀ K₁ q_f` about the lateral axes while the
//! coupling `P` keeps its moments. When the clamped modes reproduce a
//! rotation about the root almost entirely (a beam on a revolute joint at
//! its root with nothing else on that joint: the modes miss ~0.5 % of its
//! `ρA L³/3`), a large deformation (tip deflection ~7 % of `L` in the
//! test that found it) makes the mass matrix singular and the integrator
//! stops. A hub's own inertia on the joint, or smaller deformation, keeps
//! it definite; the exact foreshortening (fourth-order terms) would too.

use super::flex_state::FlexState;
use super::spatial::Motion;
use crate::flex::invariants::foreshortening;
use crate::sym::{Mat3, Scalar, Vec3};
use crate::system::FlexInfo;

/// The two foreshortening matrices of a flexible beam, inlined.
#[derive(Clone, Debug)]
pub struct Stiffening<S> {
    /// `K₁ = ∫ρA x G(x) dx` (k×k): the centrifugal geometric stiffness per
    /// `Ω²`, and the foreshortening's second moment.
    pub centrifugal: Vec<Vec<S>>,
    /// `K₂ = ∫ρA G(x) dx` (k×k): the geometric stiffness per unit axial
    /// acceleration, and the foreshortening's first moment.
    pub axial: Vec<Vec<S>>,
}

fn dot<S: Scalar>(a: &[S], b: &[S]) -> S {
    a.iter()
        .zip(b)
        .filter(|(x, y)| !x.is_zero() && !y.is_zero())
        .fold(S::zero(), |acc, (&x, &y)| acc + x * y)
}

fn mat_vec<S: Scalar>(m: &[Vec<S>], x: &[S]) -> Vec<S> {
    m.iter().map(|row| dot(row, x)).collect()
}

/// Entries below `1e-13` of the largest are exact zeros (the bending
/// planes decouple, axial and torsion modes have no slope); the others go
/// through `to`.
fn matrix<S: Scalar>(m: &nalgebra::DMatrix<f64>, to: &dyn Fn(f64) -> S) -> Vec<Vec<S>> {
    let top = m.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
    (0..m.nrows())
        .map(|r| {
            (0..m.ncols())
                .map(|c| {
                    let x = m[(r, c)];
                    to(if x.abs() <= 1e-13 * top { 0.0 } else { x })
                })
                .collect()
        })
        .collect()
}

impl<S: Scalar> Stiffening<S> {
    /// The matrices of `flex` (its beam and modes at the defaults), each
    /// entry through `rho_a`: both are linear in `ρA`, which scales them
    /// when it is tunable ([`super::flex_tunable`]).
    pub fn new(flex: &FlexInfo, rho_a: &dyn Fn(f64) -> S) -> Self {
        // Assumed modes integrate their own shapes; a beam its FE model.
        let (k1, k2) = match flex.assumed_geometric_stiffness() {
            Some((k1, k2)) => (k1.clone(), k2.clone()),
            None => foreshortening(&flex.beam, &flex.modes),
        };
        Stiffening {
            centrifugal: matrix(&k1, rho_a),
            axial: matrix(&k2, rho_a),
        }
    }

    /// Adds the foreshortening terms (module docs) to the body's state at
    /// elastic coordinates `q`, rates `qd` and frame velocity `v`.
    pub fn apply(&self, q: &[S], qd: &[S], v: Motion<S>, st: &mut FlexState<S>) {
        let (zero, two, half) = (S::zero(), S::from_f64(2.0), S::from_f64(0.5));
        let w = v.w;
        let k1q = mat_vec(&self.centrifugal, q);
        let k2q = mat_vec(&self.axial, q);
        let k2qd = mat_vec(&self.axial, qd);
        let c = dot(q, &k1q);
        let c_rate = dot(&k1q, qd);
        let s = dot(q, &k2q);
        let s_rate = dot(&k2q, qd);
        let qd_k2_qd = dot(qd, &k2qd);
        let lateral = Mat3::diag(Vec3::new(zero, S::one(), S::one()));
        st.inertia.h = st.inertia.h + Vec3::new(-(half * s), zero, zero);
        st.inertia.i = st.inertia.i - lateral.scale(c);
        for (p, &x) in st.coupling.iter_mut().zip(&k2q) {
            p.f = p.f + Vec3::new(-x, zero, zero);
        }
        let ex = Vec3::new(S::one(), zero, zero);
        st.bias.n = st.bias.n - lateral.mul_vec(w).scale(two * c_rate);
        st.bias.f = st.bias.f - w.cross(ex).scale(two * s_rate) - ex.scale(qd_k2_qd);
        let spin2 = w.0[1] * w.0[1] + w.0[2] * w.0[2];
        let axial_acc = w.cross(v.v).0[0];
        for ((b, &x1), &x2) in st.elastic_bias.iter_mut().zip(&k1q).zip(&k2q) {
            if !x1.is_zero() {
                *b = *b + spin2 * x1;
            }
            if !x2.is_zero() {
                *b = *b - axial_acc * x2;
            }
        }
    }
}
