//! Outputs of flexible beams over any [`Scalar`]: the deformation and the
//! stress resultants at a section from the finite-element interpolation of
//! the mode shapes, and the undeformed-plus-elastic place of a node.
//!
//! At `x` in element `e` (`ξ = (x − x_e)/l`), the rows `N(ξ)` of
//! [`crate::flex::Beam::element_interpolation`] times the element's nodal shapes give the
//! section's translation, small rotation, axial strain `u_x'`, twist
//! `θ_x'`, curvatures `u_y''`, `u_z''`; the third derivatives of the
//! Hermite cubics (constant in an element: `12/l³, 6/l², −12/l³, 6/l²`)
//! give the shear forces. A Timoshenko beam's sections turn by `ψ`
//! (its nodal rotations): its rotation output is `ψ`, its moments
//! `EI ψ'` and its shear forces `κGA (v' − ψ)`. With cubic elements the
//! moments are linear and the shear forces constant per element: exact for end loads, and for a
//! distributed load `q` off by the element's fixed-end values
//! (`q l²/12` in the moment, `q l/2` in the shear at an element end).

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
    (l, beam.element_interpolation(xi), local)
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
/// `EA`, `EI_y`, `EI_z`, `GJ` (runtime fields where tunable). For a
/// Timoshenko beam the moments are those of the section rotations,
/// `M_y = EI_y θ_y'`, `M_z = EI_z θ_z'`, and the shear forces those of the
/// shear strains, `Q_y = κGA_y (u_y' − θ_z)`, `Q_z = κGA_z (u_z' + θ_y)`
/// (constant per element, equal to `−M_z'` and `M_y'`).
pub fn section_forces<S: Scalar>(flex: &FlexInfo, stiffness: &[S; 4], x: f64, q: &[S]) -> [S; 6] {
    let [ea, ei_y, ei_z, gj] = *stiffness;
    let beam = &flex.beam;
    let (_, s, local) = element(flex, x);
    let k = |c: f64| S::from_f64(c);
    let (qy, qz) = match &beam.shear {
        None => (
            -ei_z * combine(&s.curvature_rate.row(0).transpose(), &local, q),
            -ei_y * combine(&s.curvature_rate.row(1).transpose(), &local, q),
        ),
        Some(sh) => {
            let gxy = (s.slope.row(0) - s.rotation.row(2)).transpose();
            let gxz = (s.slope.row(1) + s.rotation.row(1)).transpose();
            (
                k(sh.kga_y) * combine(&gxy, &local, q),
                k(sh.kga_z) * combine(&gxz, &local, q),
            )
        }
    };
    [
        ea * combine(&s.axial_strain, &local, q),
        qy,
        qz,
        gj * combine(&s.twist, &local, q),
        -ei_y * combine(&s.curvature_xz, &local, q),
        ei_z * combine(&s.curvature_xy, &local, q),
    ]
}

/// The place of node `node` in body axes: `(x_node, 0, 0) + ū_f`.
pub fn node_point<S: Scalar>(flex: &FlexInfo, node: usize, q: &[S]) -> Vec3<S> {
    if !matches!(flex.source, crate::system::FlexSource::Beam) {
        // Assumed modes and imported data: the place of the node plus its
        // translational shapes (`modes.shapes`, six rows per node).
        let p = flex.node_place(node);
        let shapes = &flex.modes.shapes;
        return Vec3(std::array::from_fn(|r| {
            let row = 6 * node + r;
            (0..shapes.ncols().min(q.len())).fold(S::from_f64(p[r]), |acc, j| {
                let c = shapes.get((row, j)).copied().unwrap_or(0.0);
                if c == 0.0 {
                    acc
                } else {
                    acc + S::from_f64(c) * q[j]
                }
            })
        }));
    }
    let x = flex.beam.node_x(node);
    let d = deformation(flex, x, q);
    Vec3::new(S::from_f64(x) + d[0], d[1], d[2])
}
