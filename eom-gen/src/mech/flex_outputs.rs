//! Outputs of flexible beams over any [`Scalar`]: the deformation and the
//! stress resultants at a section from the finite-element interpolation of
//! the mode shapes, and the undeformed-plus-elastic place of a node.
//!
//! At `x` in element `e` (`ξ = (x − x_e)/l`), the rows `N(ξ)` of
//! [`Beam::interpolation`] times the element's nodal shapes give the
//! section's translation, small rotation, axial strain `u_x'`, twist
//! `θ_x'`, curvatures `u_y''`, `u_z''`; the third derivatives of the
//! Hermite cubics (constant in an element: `12/l³, 6/l², −12/l³, 6/l²`)
//! give the shear forces. With cubic elements the moments are linear and
//! the shear forces constant per element: exact for end loads, and for a
//! distributed load `q` off by the element's fixed-end values
//! (`q l²/12` in the moment, `q l/2` in the shear at an element end).

use crate::flex::Beam;
use crate::sym::{Scalar, Vec3};
use crate::system::FlexInfo;
use nalgebra::{DMatrix, SVector};

/// `row · Φ_local · q` for a 12-vector row of the element at `x`.
fn combine<S: Scalar>(row: &SVector<f64, 12>, local: &DMatrix<f64>, q: &[S]) -> S {
    let coeffs = row.transpose() * local;
    let top = coeffs.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
    coeffs
        .iter()
        .zip(q)
        .filter(|(c, _)| c.abs() > 1e-13 * top)
        .fold(S::zero(), |acc, (&c, &qj)| acc + S::from_f64(c) * qj)
}

/// The element at `x`, its rows and its nodal shapes (12 × k).
fn element(flex: &FlexInfo, x: f64) -> (f64, crate::flex::beam::Interpolation, DMatrix<f64>) {
    let beam = &flex.beam;
    let (e, xi) = beam.locate(x);
    let l = beam.element_length();
    let local = flex.modes.shapes.rows(6 * e, 12).into_owned();
    (l, Beam::interpolation(l, xi), local)
}

/// `(u_x, u_y, u_z, θ_x, θ_y, θ_z)` of the section at `x` (body axes).
pub fn deformation<S: Scalar>(flex: &FlexInfo, x: f64, q: &[S]) -> [S; 6] {
    let (_, s, local) = element(flex, x);
    std::array::from_fn(|r| {
        let row = if r < 3 {
            s.translation.row(r).transpose()
        } else {
            s.rotation.row(r - 3).transpose()
        };
        combine(&row, &local, q)
    })
}

/// `(N, Q_y, Q_z, M_x, M_y, M_z)` at the section `x`, acting on the part
/// `[0, x]` from the part beyond, body axes: `N = EA u_x'`,
/// `Q_y = −EI_z u_y'''`, `Q_z = −EI_y u_z'''`, `M_x = GJ θ_x'`,
/// `M_y = −EI_y u_z''`, `M_z = EI_z u_y''`, with `stiffness` the section's
/// `EA`, `EI_y`, `EI_z`, `GJ` (runtime fields where tunable).
pub fn section_forces<S: Scalar>(flex: &FlexInfo, stiffness: &[S; 4], x: f64, q: &[S]) -> [S; 6] {
    let [ea, ei_y, ei_z, gj] = *stiffness;
    let (l, s, local) = element(flex, x);
    let ddd = [
        12.0 / l.powi(3),
        6.0 / (l * l),
        -12.0 / l.powi(3),
        6.0 / (l * l),
    ];
    let (xy, xz, sz) = ([1, 5, 7, 11], [2, 4, 8, 10], [1.0, -1.0, 1.0, -1.0]);
    let mut vy = SVector::<f64, 12>::zeros();
    let mut vz = SVector::<f64, 12>::zeros();
    for a in 0..4 {
        vy[xy[a]] = ddd[a];
        vz[xz[a]] = sz[a] * ddd[a];
    }
    [
        ea * combine(&s.axial_strain, &local, q),
        -ei_z * combine(&vy, &local, q),
        -ei_y * combine(&vz, &local, q),
        gj * combine(&s.twist, &local, q),
        -ei_y * combine(&s.curvature_xz, &local, q),
        ei_z * combine(&s.curvature_xy, &local, q),
    ]
}

/// The place of node `node` in body axes: `(x_node, 0, 0) + ū_f`.
pub fn node_point<S: Scalar>(flex: &FlexInfo, node: usize, q: &[S]) -> Vec3<S> {
    let x = flex.beam.node_x(node);
    let d = deformation(flex, x, q);
    Vec3::new(S::from_f64(x) + d[0], d[1], d[2])
}
