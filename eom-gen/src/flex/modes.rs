//! Reference conditions and modal reduction.
//!
//! The floating frame is defined by reference conditions (Shabana 6.2):
//! conditions on the deformation that no rigid-body motion of the whole body
//! can satisfy, so the frame's motion and the deformation are unique. Once
//! they hold, the stiffness on the remaining degrees of freedom is positive
//! definite; conditions that leave a rigid motion free are an error
//! ([`FlexError::FrameUndefined`]) that names the motion.
//!
//! The lowest modes of the constrained `(K, M)` come from the Cholesky factor
//! of `K = L Lᵀ` and the symmetric eigenproblem `L⁻¹ M L⁻ᵀ v = μ v`,
//! `μ = 1/ω²`: the lowest frequencies are the largest `μ`, found to full
//! relative precision however stiff the axial modes are (the idea of shift
//! and invert). Shapes are mass-normalised, `φᵀ M φ = 1`, `φᵀ K φ = ω²`,
//! with their largest entry positive. The solves are dense (`O(N³)` in the
//! `N = 6(n+1)` nodal degrees of freedom), meant for beams of up to a few
//! hundred elements.

use nalgebra::{Cholesky, DMatrix, SymmetricEigen};

use super::{Beam, FlexError, NodeDof};

/// One nodal degree of freedom.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Dof {
    /// Node index (`0..=n`).
    pub node: usize,
    /// Which of its six.
    pub dof: NodeDof,
}

/// Reference conditions: what fixes the body frame in the deforming beam.
#[derive(Clone, Debug, PartialEq)]
pub enum Reference {
    /// The tangent frame: node 0 (at `x = 0`, the joint) neither moves nor
    /// rotates. Natural modes are the clamped–free ones.
    Clamped,
    /// The chord frame: the end nodes do not move transversely and node 0 not
    /// axially, so the frame's `x` axis is the chord. The roll about the chord
    /// is fixed by `θ_x = 0` at node 0; without it the rotation about `x`
    /// stays free. Bending modes are the pinned–pinned ones; axial and
    /// torsion modes are fixed–free.
    PinnedPinned,
    /// The mean axis (free–free; Agrawal and Shabana 1985): the deformation is
    /// mass-orthogonal to the six rigid-body motions, `Rᵀ M u = 0`, so the
    /// linear and angular momentum of the deformation vanish
    /// (`∫ρ S dV = 0`, `∫ρ ũ₀ S dV = 0`). The modes are the elastic free–free
    /// ones.
    MeanAxis,
    /// These degrees of freedom are zero.
    Fixed(Vec<Dof>),
}

impl Reference {
    /// The degrees of freedom fixed, or `None` for the mean axis.
    pub fn fixed(&self, beam: &Beam) -> Option<Vec<Dof>> {
        let end = beam.elements;
        let at = |node, dof| Dof { node, dof };
        match self {
            Reference::Clamped => Some(NodeDof::ALL.iter().map(|&d| at(0, d)).collect()),
            Reference::PinnedPinned => Some(vec![
                at(0, NodeDof::Ux),
                at(0, NodeDof::Uy),
                at(0, NodeDof::Uz),
                at(0, NodeDof::Rx),
                at(end, NodeDof::Uy),
                at(end, NodeDof::Uz),
            ]),
            Reference::MeanAxis => None,
            Reference::Fixed(dofs) => Some(dofs.clone()),
        }
    }
}

/// How the reduced basis was made.
#[derive(Clone, Debug, PartialEq)]
pub enum Basis {
    /// Normal modes of the constrained beam, lowest first.
    Normal,
    /// Craig–Bampton: first one static constraint mode per boundary degree of
    /// freedom (`boundary` nodes, those not fixed by the reference), then the
    /// fixed-interface normal modes.
    CraigBampton {
        /// The boundary nodes.
        boundary: Vec<usize>,
        /// Number of constraint modes (the first columns).
        constraint_modes: usize,
    },
}

/// A reduced basis: nodal shapes and the reduced matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct Modes {
    /// Nodal vectors, one column per elastic coordinate (`6(n+1) × k`): the
    /// translations and small rotations of every node, zero where fixed.
    pub shapes: DMatrix<f64>,
    /// Reduced mass `Φᵀ M Φ` (identity for normal modes).
    pub mass: DMatrix<f64>,
    /// Reduced stiffness `Φᵀ K Φ` (`diag(ω²)` for normal modes).
    pub stiffness: DMatrix<f64>,
    /// Natural frequencies of the reduced `(K, M)` in rad/s, ascending.
    pub frequencies: Vec<f64>,
    /// How the basis was made.
    pub basis: Basis,
}

impl Modes {
    /// Number of elastic coordinates `k`.
    pub fn count(&self) -> usize {
        self.shapes.ncols()
    }

    /// The shapes at one node (`6 × k`: `u_x, u_y, u_z, θ_x, θ_y, θ_z`), as a
    /// joint or marker attached there moves.
    pub fn at_node(&self, node: usize) -> DMatrix<f64> {
        self.shapes.rows(6 * node, 6).into_owned()
    }
}

const MOTIONS: [&str; 6] = [
    "translation along x",
    "translation along y",
    "translation along z",
    "rotation about x",
    "rotation about y",
    "rotation about z",
];

/// Fixed-dof mask, checked: unknown nodes, and rigid motions the conditions leave free.
fn fixed_mask(beam: &Beam, fixed: &[Dof]) -> Result<Vec<bool>, FlexError> {
    let mut mask = vec![false; beam.dofs()];
    for d in fixed {
        if d.node >= beam.nodes() {
            return Err(FlexError::UnknownNode {
                node: d.node,
                nodes: beam.nodes(),
            });
        }
        mask[beam.dof(d.node, d.dof)] = true;
    }
    // The rigid motions (rotations scaled by L to be commensurate) restricted to
    // the fixed dofs; a null vector is a rigid motion that satisfies them all.
    let mut rigid = beam.rigid_modes();
    for c in 3..6 {
        rigid.column_mut(c).scale_mut(beam.length);
    }
    let mut c = DMatrix::<f64>::zeros(6, 6);
    for (i, _) in mask.iter().enumerate().filter(|(_, f)| **f) {
        let row = rigid.row(i);
        c += row.transpose() * row;
    }
    let eig = SymmetricEigen::new(c);
    let top = eig.eigenvalues.amax().max(1.0);
    let mut free = Vec::new();
    for (j, &val) in eig.eigenvalues.iter().enumerate() {
        if val <= 1e-10 * top {
            free.push(describe(eig.eigenvectors.column(j).iter().copied()));
        }
    }
    if free.is_empty() {
        Ok(mask)
    } else {
        free.sort();
        Err(FlexError::FrameUndefined(free))
    }
}

/// A rigid motion in words: `rotation about x`, or a signed combination
/// scaled so its largest part is 1 and its first is positive (rotations in
/// units of `1/L`).
fn describe(v: impl Iterator<Item = f64>) -> String {
    let v: Vec<f64> = v.collect();
    let top = v.iter().fold(0.0_f64, |a, &b| a.max(b.abs()));
    // A motion and its opposite are the same line: lead with a positive term.
    let lead = v
        .iter()
        .find(|c| c.abs() > 1e-6 * top)
        .copied()
        .unwrap_or(1.0);
    let big = top.copysign(lead);
    let mut out = String::new();
    for (c, name) in v.iter().map(|c| c / big).zip(MOTIONS) {
        if c.abs() <= 1e-6 {
            continue;
        }
        let sign = match (out.is_empty(), c < 0.0) {
            (true, false) => "",
            (true, true) => "−",
            (false, false) => " + ",
            (false, true) => " − ",
        };
        if (c.abs() - 1.0).abs() < 1e-9 {
            out += &format!("{sign}{name}");
        } else {
            out += &format!("{sign}{:.3} {name}", c.abs());
        }
    }
    format!("`{out}`")
}

/// Symmetric part, to keep round-off from breaking symmetry.
fn sym(a: DMatrix<f64>) -> DMatrix<f64> {
    (&a + a.transpose()) * 0.5
}

/// The lowest `count` modes of `(k, m)`: mass-normalised shapes and `ω²`.
fn lowest(
    k: &DMatrix<f64>,
    m: &DMatrix<f64>,
    count: usize,
    what: &str,
) -> Result<(DMatrix<f64>, Vec<f64>), FlexError> {
    let n = k.nrows();
    if count == 0 {
        return Ok((DMatrix::zeros(n, 0), Vec::new()));
    }
    let chol = Cholesky::new(k.clone())
        .ok_or_else(|| FlexError::NotPositiveDefinite(format!("the stiffness of {what}")))?;
    let l = chol.l();
    let not_pd = || FlexError::NotPositiveDefinite(format!("the stiffness of {what}"));
    // B = L⁻¹ M L⁻ᵀ = L⁻¹ (L⁻¹ M)ᵀ.
    let x = l.solve_lower_triangular(m).ok_or_else(not_pd)?;
    let b = sym(l
        .solve_lower_triangular(&x.transpose())
        .ok_or_else(not_pd)?);
    let eig = SymmetricEigen::new(b);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &c| eig.eigenvalues[c].total_cmp(&eig.eigenvalues[a]));
    let mut shapes = DMatrix::zeros(n, count);
    let mut omega2 = Vec::with_capacity(count);
    for (col, &j) in order.iter().take(count).enumerate() {
        let mu = eig.eigenvalues[j];
        if mu <= 0.0 {
            return Err(FlexError::NotPositiveDefinite(format!(
                "the mass of {what}"
            )));
        }
        let y = l
            .tr_solve_lower_triangular(&eig.eigenvectors.column(j).into_owned())
            .ok_or_else(not_pd)?;
        // Sign convention (for reproducible output): the largest entry is positive.
        let big = y
            .iter()
            .fold(0.0_f64, |a, &b| if b.abs() > a.abs() { b } else { a });
        shapes.set_column(col, &(y * (big.signum() / mu.sqrt())));
        omega2.push(1.0 / mu);
    }
    Ok((shapes, omega2))
}

/// The deformation a nodal degree of freedom belongs to: 0 axial (`u_x`),
/// 1 bending x–y (`u_y`, `θ_z`), 2 bending x–z (`u_z`, `θ_y`), 3 torsion
/// (`θ_x`). A straight beam's mass and stiffness do not couple them.
pub fn dof_block(dof: usize) -> usize {
    [0, 1, 2, 3, 2, 1][dof % 6]
}

/// Makes every mode of a degenerate group (equal `ω²` to 1e-9 relative,
/// e.g. the two bending planes of a round section) belong to one
/// deformation ([`dof_block`]), so each kept shape scales with its own
/// block's stiffness and mass (tunable section data,
/// `mech::flexible`). The mass-normalised columns `cols` of the nodal
/// `shapes` (ascending `omega2`) are turned within each group by the
/// eigenvectors of `Cᵀ W C`, `W` the mass weighted by block number, which
/// separates the blocks (ordered axial, x–y, x–z, torsion) and keeps
/// `Cᵀ M C = 1`. Non-degenerate modes are already pure and are left as
/// they are.
fn separate_blocks(
    shapes: &mut DMatrix<f64>,
    cols: std::ops::Range<usize>,
    omega2: &[f64],
    m: &DMatrix<f64>,
) {
    let n = m.nrows();
    let mut start = 0;
    while start < omega2.len() {
        let mut end = start + 1;
        while end < omega2.len() && (omega2[end] - omega2[start]).abs() <= 1e-9 * omega2[end].abs()
        {
            end += 1;
        }
        if end - start > 1 {
            let c = shapes.columns(cols.start + start, end - start).into_owned();
            let w = DMatrix::from_fn(n, n, |i, j| {
                if dof_block(i) == dof_block(j) {
                    m[(i, j)] * (dof_block(i) + 1) as f64
                } else {
                    0.0
                }
            });
            let eig = SymmetricEigen::new(sym(c.transpose() * w * &c));
            let mut order: Vec<usize> = (0..end - start).collect();
            order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
            for (slot, &j) in order.iter().enumerate() {
                let y = &c * eig.eigenvectors.column(j);
                let big = y
                    .iter()
                    .fold(0.0_f64, |a, &b| if b.abs() > a.abs() { b } else { a });
                shapes.set_column(cols.start + start + slot, &(y * big.signum()));
            }
        }
        start = end;
    }
}

/// An orthonormal basis `Z` (columns) of the deformations allowed by the
/// reference conditions: the free dofs, or the mass-orthogonal complement of
/// the rigid motions for the mean axis.
fn allowed(
    beam: &Beam,
    reference: &Reference,
    m: &DMatrix<f64>,
) -> Result<DMatrix<f64>, FlexError> {
    let n = beam.dofs();
    match reference.fixed(beam) {
        Some(fixed) => {
            let mask = fixed_mask(beam, &fixed)?;
            let free: Vec<usize> = (0..n).filter(|&i| !mask[i]).collect();
            let mut z = DMatrix::zeros(n, free.len());
            for (c, &i) in free.iter().enumerate() {
                z[(i, c)] = 1.0;
            }
            Ok(z)
        }
        None => {
            // QR of [M R | I]: Q's first six columns span M R, the rest its complement.
            let mr = m * beam.rigid_modes();
            let mut a = DMatrix::zeros(n, n + 6);
            a.columns_mut(0, 6).copy_from(&mr);
            a.columns_mut(6, n).fill_with_identity();
            let q = a.qr().q();
            Ok(q.columns(6, n - 6).into_owned())
        }
    }
}

/// The lowest `k` normal modes of the beam under the reference conditions,
/// mass-normalised.
pub fn normal_modes(beam: &Beam, reference: &Reference, k: usize) -> Result<Modes, FlexError> {
    beam.check()?;
    let (m, kk) = (beam.mass(), beam.stiffness());
    let z = allowed(beam, reference, &m)?;
    if k > z.ncols() {
        return Err(FlexError::TooManyModes {
            asked: k,
            available: z.ncols(),
        });
    }
    let mz = sym(z.transpose() * &m * &z);
    let kz = sym(z.transpose() * &kk * &z);
    let (phi, omega2) = lowest(&kz, &mz, k, "the constrained beam")?;
    let mut shapes = &z * phi;
    separate_blocks(&mut shapes, 0..k, &omega2, &m);
    Ok(Modes {
        mass: sym(shapes.transpose() * &m * &shapes),
        stiffness: sym(shapes.transpose() * &kk * &shapes),
        frequencies: omega2.iter().map(|w| w.sqrt()).collect(),
        shapes,
        basis: Basis::Normal,
    })
}

/// Craig–Bampton modes: one static constraint mode per boundary degree of
/// freedom (all six of each `boundary` node, less those the reference fixes),
/// `Ψ = [I; −K_ii⁻¹ K_ib]`, then the `k` lowest normal modes with the
/// boundary fixed. The static response to loads at the boundary is exact.
pub fn craig_bampton(
    beam: &Beam,
    reference: &Reference,
    boundary: &[usize],
    k: usize,
) -> Result<Modes, FlexError> {
    beam.check()?;
    let fixed = reference
        .fixed(beam)
        .ok_or(FlexError::NeedsNodalReference)?;
    let mask = fixed_mask(beam, &fixed)?;
    if let Some(&node) = boundary.iter().find(|&&b| b >= beam.nodes()) {
        return Err(FlexError::UnknownNode {
            node,
            nodes: beam.nodes(),
        });
    }
    let n = beam.dofs();
    let is_b = |i: usize| boundary.contains(&(i / 6));
    let bset: Vec<usize> = (0..n).filter(|&i| !mask[i] && is_b(i)).collect();
    let iset: Vec<usize> = (0..n).filter(|&i| !mask[i] && !is_b(i)).collect();
    if k > iset.len() {
        return Err(FlexError::TooManyModes {
            asked: k,
            available: iset.len(),
        });
    }
    let (m, kk) = (beam.mass(), beam.stiffness());
    let pick = |a: &DMatrix<f64>, r: &[usize], c: &[usize]| {
        DMatrix::from_fn(r.len(), c.len(), |i, j| a[(r[i], c[j])])
    };
    let kii = pick(&kk, &iset, &iset);
    let psi = if iset.is_empty() {
        DMatrix::zeros(0, bset.len())
    } else {
        let chol = Cholesky::new(kii.clone()).ok_or_else(|| {
            FlexError::NotPositiveDefinite("the interior stiffness `K_ii`".to_string())
        })?;
        -chol.solve(&pick(&kk, &iset, &bset))
    };
    let (phi, fixed_omega2) = lowest(&kii, &pick(&m, &iset, &iset), k, "the fixed-interface beam")?;
    let nb = bset.len();
    let mut shapes = DMatrix::zeros(n, nb + k);
    for (c, &i) in bset.iter().enumerate() {
        shapes[(i, c)] = 1.0;
    }
    for (r, &i) in iset.iter().enumerate() {
        for c in 0..nb {
            shapes[(i, c)] = psi[(r, c)];
        }
        for c in 0..k {
            shapes[(i, nb + c)] = phi[(r, c)];
        }
    }
    separate_blocks(&mut shapes, nb..nb + k, &fixed_omega2, &m);
    let mass = sym(shapes.transpose() * &m * &shapes);
    let stiffness = sym(shapes.transpose() * &kk * &shapes);
    let (_, omega2) = lowest(&stiffness, &mass, nb + k, "the Craig–Bampton basis")?;
    Ok(Modes {
        shapes,
        mass,
        stiffness,
        frequencies: omega2.iter().map(|w| w.sqrt()).collect(),
        basis: Basis::CraigBampton {
            boundary: boundary.to_vec(),
            constraint_modes: nb,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn beam(n: usize) -> Beam {
        Beam::new(1.0, 1.0, 0.01, 1.0e4, 1.0, 2.0, 0.5, n).unwrap()
    }

    #[test]
    fn flex_modes_are_mass_normalised() {
        let modes = normal_modes(&beam(6), &Reference::Clamped, 5).unwrap();
        let eye = DMatrix::<f64>::identity(5, 5);
        assert!((&modes.mass - eye).amax() < 1e-10, "{}", modes.mass);
        let w2 = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
            5,
            modes.frequencies.iter().map(|w| w * w),
        ));
        let rel = (&modes.stiffness - &w2).amax() / w2.amax();
        assert!(rel < 1e-10, "stiffness not diag(ω²): {rel}");
    }

    #[test]
    fn flex_chord_frame_without_roll_leaves_rotation_about_x_free() {
        // Both ends pinned and x = 0 axially fixed, but nothing fixes θ_x:
        // the beam can still turn about its own axis as a rigid body.
        let b = beam(4);
        let at = |node, dof| Dof { node, dof };
        let pins = Reference::Fixed(vec![
            at(0, NodeDof::Ux),
            at(0, NodeDof::Uy),
            at(0, NodeDof::Uz),
            at(4, NodeDof::Uy),
            at(4, NodeDof::Uz),
        ]);
        let err = normal_modes(&b, &pins, 2).unwrap_err();
        assert_eq!(
            err,
            FlexError::FrameUndefined(vec!["`rotation about x`".to_string()])
        );
        assert!(err.to_string().contains("rotation about x"), "{err}");
    }

    #[test]
    fn flex_free_combination_is_named_with_signs() {
        // Node 0 fixed except u_y and θ_z, the tip fixed in u_y: a rigid turn
        // about z through the tip (u_y = θ_z (x − L)) is still free.
        let b = beam(3);
        let at = |node, dof| Dof { node, dof };
        let mut dofs: Vec<Dof> = [NodeDof::Ux, NodeDof::Uz, NodeDof::Rx, NodeDof::Ry]
            .iter()
            .map(|&d| at(0, d))
            .collect();
        dofs.push(at(3, NodeDof::Uy));
        let err = normal_modes(&b, &Reference::Fixed(dofs), 1).unwrap_err();
        assert_eq!(
            err,
            FlexError::FrameUndefined(vec!["`translation along y − rotation about z`".to_string()])
        );
    }

    #[test]
    fn flex_no_reference_leaves_all_six_free() {
        let err = normal_modes(&beam(2), &Reference::Fixed(vec![]), 1).unwrap_err();
        let FlexError::FrameUndefined(free) = err else {
            panic!("want FrameUndefined")
        };
        assert_eq!(free.len(), 6, "{free:?}");
    }

    #[test]
    fn flex_unknown_node_and_too_many_modes() {
        let b = beam(2);
        let far = Reference::Fixed(vec![Dof {
            node: 7,
            dof: NodeDof::Ux,
        }]);
        assert_eq!(
            normal_modes(&b, &far, 1).unwrap_err(),
            FlexError::UnknownNode { node: 7, nodes: 3 }
        );
        assert_eq!(
            normal_modes(&b, &Reference::Clamped, 13).unwrap_err(),
            FlexError::TooManyModes {
                asked: 13,
                available: 12
            }
        );
        assert_eq!(
            craig_bampton(&b, &Reference::MeanAxis, &[2], 1).unwrap_err(),
            FlexError::NeedsNodalReference
        );
    }
}
