//! Modal data imported from an external finite-element model: the file
//! format ([`ModalData`], RON or JSON) and the inertia shape integrals of
//! the body it describes.
//!
//! The file gives `N` nodes (undeformed position `r_n` in body axes, lumped
//! mass `m_n`, optionally a rotary inertia `J_n` about the node), `k` mode
//! shapes at the nodes (translation `Φ_n` and small rotation `Ψ_n`, each
//! `3 × k`) and the modal matrices `M_ff`, `K_ff` (and `D_ff`) of the FE
//! model. The body is the FE model's lumped mass: each node a small rigid
//! body that translates with `Φ_n q_f` and turns with `Ψ_n q_f`. Its points
//! `r_n + ρ` move by `(Φ_n − ρ̃ Ψ_n) q_f`, so every integral of
//! [`Invariants`] is a sum over nodes of integrals over `ρ` that are at most
//! quadratic in `ρ`: they need only the node's mass, zero first moment and
//! second moment `C_n = ½ tr(J_n) 1 − J_n`. They are summed exactly with a
//! seven-point rule per node (the node, and `±d_a e_a` along the
//! eigenvectors of `C_n` with signed weights; exact for every polynomial of
//! degree ≤ 3 in `ρ`). Hence (Shabana 5.2 with `∫ρ dV → Σ_n`):
//!
//! ```text
//! m = Σ m_n     I₁ = Σ m_n r_n     J₀ = Σ m_n r_n r_nᵀ + C_n
//! S̄ = Σ m_n Φ_n     S̄_ij = Σ m_n Φ_niᵀ Φ_nj + (ρ̃Ψ)_iᵀ C-weighted (ρ̃Ψ)_j
//! Ī_θf⁰ = Σ m_n r̃_n Φ_n + J_n Ψ_n     Σ_i S̄_ii = Σ m_n Φ_nᵀ Φ_n + Ψ_nᵀ J_n Ψ_n
//! ```
//!
//! **The lumped-mass approximation.** These are the integrals of the lumped
//! mass, not of the FE model's consistent mass: for a beam of `n` elements,
//! `m` and `I₁` are exact, `S̄`, `Ī_θf⁰` and `Ī` off by `O(h²)` (`h = L/n`;
//! see `BENCHMARKS.md`). The modal mass used is the lumped one too,
//! `M_ff = Σ_i S̄_ii`, so the body is one consistent system of particles and
//! its mass matrix is positive definite in every state. Mixing in the FE
//! model's own modal mass instead would not be: a free body whose modes are
//! clamped at the frame is mostly rigid motion, the part of `M_ff` not
//! explained by the frame's motion (the Schur complement
//! `M_ff − Pᵀ M_rr⁻¹ P`) is small, and the `O(h²)` mismatch between a
//! consistent `M_ff` and lumped couplings `P` makes it indefinite (measured:
//! a 6-element clamped beam on a free joint). The file's `modal_mass`, when
//! given, is compared with the lumped one ([`Imported::file_modal_mass`]).
//! The natural frequencies of `(K_ff, M_ff)` therefore differ from the FE
//! model's by the lumped-mass error, `O(h²)`.
//!
//! **Consistent first-order invariants.** A file may also carry
//! ([`Consistent`]) the first-order invariants of the FE model's consistent
//! mass matrix `M` — `m`, `I₁`, `Ī = R_rᵀ M R_r`, `S̄ = R_tᵀ M Φ`,
//! `Ī_θf⁰ = R_rᵀ M Φ` with `R_t`, `R_r` the nodal vectors of the rigid
//! motions — and then its `modal_mass` `Φᵀ M Φ` is used too. These replace
//! the lumped values ([`build`]): together they make the mass matrix at
//! `q_f = 0` the Gram matrix of the rigid motions and the modes under `M`,
//! exactly the FE model's and positive definite, and the natural
//! frequencies are the FE model's. The second-order terms (the inertia
//! tensor's change with `q_f`: the symmetric part of `X_ab`, and `S̄_ab`)
//! stay lumped. Every such tuple of invariants is the moment tuple (up to
//! second order in position and shape) of some signed mass distribution,
//! so the FFR equations remain Lagrange's equations of a kinetic energy and
//! conserve energy.

use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};
use std::fmt;

use super::ritz::{Ritz, RitzError, check_square};
use super::{Basis, Invariants, Modes};
use crate::diag::Span;
use crate::model::locate::{self, Kind, Node};

/// A modal data file (`ModalData(…)` in RON, an object in JSON).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "ModalData")]
pub struct ModalData {
    /// Free text: where the data come from, units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub doc: Option<String>,
    /// The FE nodes, in the order of the mode shapes.
    pub nodes: Vec<ModalNode>,
    /// The mode shapes, one per elastic coordinate.
    pub modes: Vec<ModeShape>,
    /// `M_ff` (k×k) of the FE model, kg per unit coordinate²; optional,
    /// only compared with the lumped mass's (which eom uses, module docs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub modal_mass: Option<Vec<Vec<f64>>>,
    /// `K_ff` (k×k), N/m per unit coordinate².
    pub modal_stiffness: Vec<Vec<f64>>,
    /// `D_ff` (k×k), N s/m per unit coordinate²; default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub modal_damping: Option<Vec<Vec<f64>>>,
    /// The first-order inertia invariants of the FE model's consistent mass
    /// matrix `M` (optional; with it, `modal_mass` is required and used).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub consistent: Option<Consistent>,
    /// The foreshortening matrices of geometric stiffening (optional;
    /// needed for `stiffening: true` on the body).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub geometric_stiffness: Option<GeometricStiffness>,
}

/// The modal geometric stiffness of a slender body along the body `x`
/// axis under its two unit axial inertia loads (Kane, Ryan and Banerjee
/// 1987; [`crate::flex::invariants::foreshortening`]): `Φᵀ K_G(N) Φ` with
/// `K_G(N)` the FE geometric stiffness under the axial force `N(x)` (tension
/// positive) of the sections beyond `x`, tip free. With `μ(x)` the mass per
/// length, `N₁(x) = ∫ₓᴸ μ ξ dξ` (spinning at unit `Ω` about an axis through
/// `x = 0` normal to the body) and `N₂(x) = ∫ₓᴸ μ dξ` (unit axial
/// acceleration of the root).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeometricStiffness {
    /// `K₁ = Φᵀ K_G(N₁) Φ` (k×k, kg m per unit coordinate²: N/m per (rad/s)²).
    pub centrifugal: Vec<Vec<f64>>,
    /// `K₂ = Φᵀ K_G(N₂) Φ` (k×k, kg per unit coordinate²: N/m per m/s²).
    pub axial: Vec<Vec<f64>>,
}

/// First-order inertia invariants of the consistent mass matrix `M`, with
/// `R_t`, `R_r` the nodal vectors of unit rigid translations and rotations
/// about the body origin (Adams I¹, I², I⁷, I³, I⁴).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Consistent {
    /// `m` (kg).
    pub mass: f64,
    /// `I₁ = ∫ρ ū₀ dV` (kg m).
    pub first_moment: [f64; 3],
    /// `Ī = R_rᵀ M R_r`, the undeformed inertia about the origin (kg m²), by rows.
    pub inertia: [[f64; 3]; 3],
    /// Per mode, `S̄ φ_j = R_tᵀ M φ_j` (3 each).
    pub s_bar: Vec<[f64; 3]>,
    /// Per mode, `Ī_θf⁰ φ_j = R_rᵀ M φ_j` (3 each).
    pub coupling: Vec<[f64; 3]>,
}

/// One FE node.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModalNode {
    /// A name markers can use; unique.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Undeformed position in body axes, m.
    pub position: [f64; 3],
    /// Lumped mass, kg (≥ 0).
    pub mass: f64,
    /// Rotary inertia about the node in body axes, kg m², by rows
    /// (symmetric, positive semi-definite); default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<[[f64; 3]; 3]>,
}

/// One mode shape at the nodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModeShape {
    /// Free text (e.g. `"1st bending, 12.3 Hz"`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Translation of each node per unit coordinate, m, body axes.
    pub translation: Vec<[f64; 3]>,
    /// Small rotation of each node per unit coordinate, rad; default zero.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation: Option<Vec<[f64; 3]>>,
}

/// A problem in a modal file, at a line and column of it (1-based) when
/// known.
#[derive(Clone, Debug, PartialEq)]
pub struct ModalError {
    /// `(line, column)` in the modal file.
    pub at: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
    /// What would be right.
    pub help: String,
}

impl ModalError {
    /// The message prefixed by `path:line:col:`.
    pub fn located(&self, path: &str) -> String {
        match self.at {
            Some((l, c)) => format!("{path}:{l}:{c}: {}", self.message),
            None => format!("{path}: {}", self.message),
        }
    }
}

impl fmt::Display for ModalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// One step of a path into the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step<'a> {
    Field(&'a str),
    Index(usize),
}

/// The body described by a modal file.
#[derive(Clone, Debug, PartialEq)]
pub struct Imported {
    /// The inertia shape integrals of the lumped mass (`M_ff = Σ_i S̄_ii`).
    pub invariants: Invariants,
    /// The file's `modal_mass` (the FE model's), if given: for comparison.
    pub file_modal_mass: Option<DMatrix<f64>>,
    /// `D_ff` from the file (zeros if none).
    pub damping: DMatrix<f64>,
    /// The normal modes of `(M_ff, K_ff)`.
    pub ritz: Ritz,
    /// Nodal shapes, `6N × k` (`u_x, u_y, u_z, θ_x, θ_y, θ_z` per node, as
    /// [`Modes::shapes`] of the beam).
    pub shapes: DMatrix<f64>,
    /// Node positions.
    pub positions: Vec<Vector3<f64>>,
    /// Node names (`None` where unnamed).
    pub names: Vec<Option<String>>,
    /// The file's foreshortening matrices `(K₁, K₂)`, if given.
    pub geometric: Option<(DMatrix<f64>, DMatrix<f64>)>,
}

impl Imported {
    /// Largest relative difference between the file's modal mass and the
    /// lumped one (relative to the largest entry), if the file has one.
    pub fn modal_mass_mismatch(&self) -> Option<f64> {
        let file = self.file_modal_mass.as_ref()?;
        let top = file.amax();
        Some((file - &self.invariants.modal_mass).amax() / top)
    }

    /// The reduced basis in the form the beam path has.
    pub fn modes(&self) -> Modes {
        Modes {
            shapes: self.shapes.clone(),
            mass: self.invariants.modal_mass.clone(),
            stiffness: self.invariants.modal_stiffness.clone(),
            frequencies: self.ritz.frequencies.clone(),
            basis: Basis::Normal,
        }
    }
}

/// Byte offset to 1-based line and column.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = 1 + before.bytes().filter(|&b| b == b'\n').count();
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, 1 + before[start..].chars().count())
}

/// The span of the value at `path` (RON fields or JSON object keys), or of
/// the deepest ancestor found.
fn span_of(text: &str, root: &Node, path: &[Step<'_>]) -> Span {
    let mut node = root;
    for step in path {
        let next = match (step, &node.kind) {
            (Step::Field(f), Kind::Fields(fields)) => {
                fields.iter().find(|x| x.name == *f).map(|x| &x.value)
            }
            (Step::Field(f), Kind::Map(entries)) => entries
                .iter()
                .find(|(k, _)| {
                    text.get(k.span.start..k.span.end)
                        .is_some_and(|s| s.trim_matches('"') == *f)
                })
                .map(|(_, v)| v),
            (Step::Index(i), Kind::Items(items)) => items.get(*i),
            _ => None,
        };
        match next {
            Some(n) => node = unwrap_some(n),
            None => break,
        }
    }
    node.span
}

fn unwrap_some(n: &Node) -> &Node {
    match (&n.name, &n.kind) {
        (Some(s), Kind::Items(items)) if s == "Some" && items.len() == 1 => unwrap_some(&items[0]),
        _ => n,
    }
}

/// Parses a modal file (`.json`: JSON, anything else RON); syntax and type
/// errors at their line and column.
pub fn parse(path: &str, text: &str) -> Result<ModalData, ModalError> {
    if path.to_ascii_lowercase().ends_with(".json") {
        serde_json::from_str(text).map_err(|e| {
            let full = e.to_string();
            let message = full
                .rfind(" at line ")
                .map_or(full.clone(), |i| full[..i].to_string());
            ModalError {
                at: Some((e.line(), e.column())),
                message,
                help: "a JSON modal file is an object with `nodes`, `modes`, `modal_stiffness` \
                       (and `modal_mass`, `modal_damping`): see docs/model-format.md"
                    .to_string(),
            }
        })
    } else {
        ron::Options::default()
            .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
            .from_str(text)
            .map_err(|e| ModalError {
                at: Some((e.span.start.line, e.span.start.col)),
                message: e.code.to_string(),
                help: "a RON modal file is `ModalData(nodes: […], modes: […], modal_stiffness: […])`: \
                       see docs/model-format.md"
                    .to_string(),
            })
    }
}

/// A `k × k` matrix from rows, or `None` if the rows are ragged.
fn matrix(rows: &[Vec<f64>], k: usize) -> Option<DMatrix<f64>> {
    (rows.len() == k && rows.iter().all(|r| r.len() == k))
        .then(|| DMatrix::from_fn(k, k, |r, c| rows[r][c]))
}

/// Checks a parsed file and computes its body: every problem at once, each
/// at its place in `text`.
pub fn build(data: &ModalData, text: &str) -> Result<Imported, Vec<ModalError>> {
    let root = locate::parse(text).unwrap_or_default();
    let root = unwrap_some(&root);
    let mut errors = Vec::new();
    let err = |errors: &mut Vec<ModalError>, path: &[Step<'_>], message: String, help: &str| {
        let s = span_of(text, root, path);
        errors.push(ModalError {
            at: Some(line_col(text, s.start)),
            message,
            help: help.to_string(),
        });
    };
    use Step::{Field as F, Index as I};
    let n = data.nodes.len();
    let k = data.modes.len();
    if n == 0 {
        err(
            &mut errors,
            &[F("nodes")],
            "the file has no nodes".into(),
            "list the FE nodes with their positions and lumped masses",
        );
    }
    if k == 0 {
        err(
            &mut errors,
            &[F("modes")],
            "the file has no modes".into(),
            "give at least one mode shape",
        );
    }
    let mut names = std::collections::HashSet::new();
    for (i, node) in data.nodes.iter().enumerate() {
        if node.position.iter().any(|x| !x.is_finite()) {
            err(
                &mut errors,
                &[F("nodes"), I(i), F("position")],
                format!("node {i}: position is not finite"),
                "positions are in m, body axes",
            );
        }
        if !(node.mass.is_finite() && node.mass >= 0.0) {
            err(
                &mut errors,
                &[F("nodes"), I(i), F("mass")],
                format!("node {i}: mass is {} kg", node.mass),
                "a lumped nodal mass is zero or positive (kg)",
            );
        }
        if let Some(name) = &node.name
            && !names.insert(name.as_str())
        {
            err(
                &mut errors,
                &[F("nodes"), I(i), F("name")],
                format!("node name `{name}` is used twice"),
                "node names are unique",
            );
        }
        if let Some(j) = node.inertia {
            let m = Matrix3::from_fn(|r, c| j[r][c]);
            let top = m.amax();
            if m.iter().any(|x| !x.is_finite()) {
                err(
                    &mut errors,
                    &[F("nodes"), I(i), F("inertia")],
                    format!("node {i}: rotary inertia is not finite"),
                    "kg m², by rows",
                );
            } else if (m - m.transpose()).amax() > 1e-9 * top {
                err(
                    &mut errors,
                    &[F("nodes"), I(i), F("inertia")],
                    format!("node {i}: rotary inertia is not symmetric"),
                    "an inertia tensor is symmetric",
                );
            } else if SymmetricEigen::new(m).eigenvalues.min() < -1e-12 * top {
                err(
                    &mut errors,
                    &[F("nodes"), I(i), F("inertia")],
                    format!("node {i}: rotary inertia is not positive semi-definite"),
                    "an inertia tensor has no negative principal moment",
                );
            }
        }
    }
    let total: f64 = data.nodes.iter().map(|x| x.mass).sum();
    if n > 0 && total <= 0.0 && data.nodes.iter().all(|x| x.mass >= 0.0) {
        err(
            &mut errors,
            &[F("nodes")],
            format!("the nodes' total mass is {total} kg"),
            "a flexible body needs a positive mass",
        );
    }
    for (j, mode) in data.modes.iter().enumerate() {
        if mode.translation.len() != n {
            err(
                &mut errors,
                &[F("modes"), I(j), F("translation")],
                format!(
                    "mode {}: {} translations for {n} nodes",
                    j + 1,
                    mode.translation.len()
                ),
                "one `(u_x, u_y, u_z)` per node, in the order of `nodes`",
            );
        } else if mode.translation.iter().flatten().any(|x| !x.is_finite()) {
            err(
                &mut errors,
                &[F("modes"), I(j), F("translation")],
                format!("mode {}: a translation is not finite", j + 1),
                "mode shapes are finite numbers",
            );
        }
        if let Some(rot) = &mode.rotation {
            if rot.len() != n {
                err(
                    &mut errors,
                    &[F("modes"), I(j), F("rotation")],
                    format!("mode {}: {} rotations for {n} nodes", j + 1, rot.len()),
                    "one `(θ_x, θ_y, θ_z)` per node, in the order of `nodes`",
                );
            } else if rot.iter().flatten().any(|x| !x.is_finite()) {
                err(
                    &mut errors,
                    &[F("modes"), I(j), F("rotation")],
                    format!("mode {}: a rotation is not finite", j + 1),
                    "mode shapes are finite numbers",
                );
            }
        }
    }
    let square = |rows: &Option<&Vec<Vec<f64>>>,
                  field: &'static str|
     -> Result<Option<DMatrix<f64>>, String> {
        match rows {
            None => Ok(None),
            Some(rows) => match matrix(rows, k) {
                Some(m) => check_square(&m, k, &format!("`{field}`"))
                    .map(|_| Some(m))
                    .map_err(|e| e.to_string()),
                None => Err(format!(
                    "`{field}` must be {k}×{k} (one row of {k} per mode)"
                )),
            },
        }
    };
    let file_mass = square(&data.modal_mass.as_ref(), "modal_mass");
    let stiffness = square(&Some(&data.modal_stiffness), "modal_stiffness");
    let damping = square(&data.modal_damping.as_ref(), "modal_damping");
    let mut geometric = None;
    if let Some(g) = &data.geometric_stiffness {
        let mut pair = Vec::new();
        for (field, rows) in [("centrifugal", &g.centrifugal), ("axial", &g.axial)] {
            let m = match matrix(rows, k) {
                Some(m) => check_square(&m, k, &format!("`geometric_stiffness.{field}`"))
                    .map(|_| m)
                    .map_err(|e| e.to_string()),
                None => Err(format!(
                    "`geometric_stiffness.{field}` must be {k}×{k} (one row of {k} per mode)"
                )),
            };
            match m {
                Ok(m) if SymmetricEigen::new(m.clone()).eigenvalues.min() < -1e-9 * m.amax() => {
                    err(
                        &mut errors,
                        &[F("geometric_stiffness"), F(field)],
                        format!(
                            "`geometric_stiffness.{field}` is not positive semi-definite: a tensile axial load cannot soften the body"
                        ),
                        "Φᵀ K_G Φ under the axial force of the unit load (tension positive, tip free)",
                    );
                }
                Ok(m) => pair.push((&m + m.transpose()) * 0.5),
                Err(e) => err(
                    &mut errors,
                    &[F("geometric_stiffness"), F(field)],
                    e,
                    "a symmetric matrix by rows, in the order of `modes`",
                ),
            }
        }
        if let [k1, k2] = &pair[..] {
            geometric = Some((k1.clone(), k2.clone()));
        }
    }
    for (field, r) in [
        ("modal_mass", &file_mass),
        ("modal_stiffness", &stiffness),
        ("modal_damping", &damping),
    ] {
        if let Err(e) = r {
            err(
                &mut errors,
                &[F(field)],
                e.clone(),
                "a symmetric matrix by rows, in the order of `modes`",
            );
        }
    }
    if let Ok(Some(d)) = &damping
        && SymmetricEigen::new(d.clone()).eigenvalues.min() < -1e-12 * d.amax()
    {
        err(
            &mut errors,
            &[F("modal_damping")],
            "`modal_damping` is not positive semi-definite: it would feed energy in".into(),
            "modal damping is `diag(2 ζ_i ω_i)` for mass-normalised modes, ζ_i ≥ 0",
        );
    }
    if !errors.is_empty() || n == 0 || k == 0 {
        return Err(errors);
    }
    let (Ok(file_mass), Ok(Some(stiffness)), Ok(damping)) = (file_mass, stiffness, damping) else {
        return Err(errors);
    };
    // Nodal shapes, 6N × k.
    let mut shapes = DMatrix::zeros(6 * n, k);
    for (j, mode) in data.modes.iter().enumerate() {
        for i in 0..n {
            for a in 0..3 {
                shapes[(6 * i + a, j)] = mode.translation[i][a];
                if let Some(rot) = &mode.rotation {
                    shapes[(6 * i + 3 + a, j)] = rot[i][a];
                }
            }
        }
    }
    let positions: Vec<Vector3<f64>> = data
        .nodes
        .iter()
        .map(|x| Vector3::from(x.position))
        .collect();
    let (mut inv, lumped) = lumped_invariants(data, &positions, &shapes);
    // Shapes that are dependent at the nodes, and the matrices' own checks.
    let fail = |errors: &mut Vec<ModalError>, field: &'static str, e: RitzError| {
        let help = match &e {
            RitzError::RigidMotion(_) => {
                "drop the rigid-body modes (zero frequency) of a free–free FE model: the body frame carries the rigid motion"
            }
            RitzError::Dependent(_) | RitzError::ZeroShape(_) => {
                "every mode shape must be independent of the others"
            }
            _ => "check the FE export",
        };
        err(errors, &[F(field)], e.to_string(), help);
    };
    if let Err(e) = Ritz::new(&lumped, &stiffness) {
        match e {
            RitzError::Dependent(_) | RitzError::ZeroShape(_) | RitzError::NegativeMass => {
                fail(&mut errors, "modes", e)
            }
            _ => {}
        }
    }
    let ritz = match Ritz::new(&lumped, &stiffness) {
        Ok(r) => Some(r),
        Err(e) => {
            let field = match e {
                RitzError::RigidMotion(_) | RitzError::NegativeStiffness => "modal_stiffness",
                _ => "modes",
            };
            if errors.is_empty() {
                fail(&mut errors, field, e);
            }
            None
        }
    };
    let Some(ritz) = ritz.filter(|_| errors.is_empty()) else {
        return Err(errors);
    };
    inv.modal_stiffness = stiffness;
    let mut file_mass = file_mass;
    if let Some(c) = &data.consistent {
        let Some(mass) = file_mass.take() else {
            err(
                &mut errors,
                &[F("consistent")],
                "`consistent` invariants need the FE model's `modal_mass`".into(),
                "give `modal_mass` = Φᵀ M Φ of the same consistent mass matrix",
            );
            return Err(errors);
        };
        if let Some(e) = apply_consistent(&mut inv, c, mass) {
            err(
                &mut errors,
                &[F("consistent")],
                e,
                "the consistent invariants, `modal_mass` and the mode shapes must come from one mass matrix",
            );
            return Err(errors);
        }
    }
    let ritz = if data.consistent.is_some() {
        match Ritz::new(&inv.modal_mass, &inv.modal_stiffness) {
            Ok(r) => r,
            Err(e) => {
                fail(&mut errors, "modal_mass", e);
                return Err(errors);
            }
        }
    } else {
        ritz
    };
    Ok(Imported {
        invariants: inv,
        file_modal_mass: file_mass,
        damping: damping.unwrap_or_else(|| DMatrix::zeros(k, k)),
        ritz,
        shapes,
        positions,
        names: data.nodes.iter().map(|x| x.name.clone()).collect(),
        geometric,
    })
}

/// Replaces the first-order invariants by the consistent ones: `m`, `I₁`,
/// `J₀ = ½ tr(Ī) 1 − Ī`, `S̄`, the antisymmetric part of `X_ab` (which
/// makes `Ī_θf⁰`; the symmetric part, the first-order change of the inertia
/// tensor, stays lumped) and `M_ff`. Any such tuple is the moment tuple of
/// some (signed) mass distribution, so the FFR equations stay Lagrange's
/// and conserve energy; the mass matrix at `q_f = 0` is the Gram matrix of
/// the rigid motions and the modes under `M`, positive definite (checked:
/// the error message if not).
fn apply_consistent(inv: &mut Invariants, c: &Consistent, mass: DMatrix<f64>) -> Option<String> {
    let k = inv.modes();
    if c.s_bar.len() != k || c.coupling.len() != k {
        return Some(format!(
            "`consistent` has {} `s_bar` and {} `coupling` entries for {k} modes",
            c.s_bar.len(),
            c.coupling.len()
        ));
    }
    let ine = Matrix3::from_fn(|r, col| c.inertia[r][col]);
    let all = [c.mass]
        .into_iter()
        .chain(c.first_moment)
        .chain(ine.iter().copied())
        .chain(c.s_bar.iter().flatten().copied())
        .chain(c.coupling.iter().flatten().copied());
    if all.into_iter().any(|x| !x.is_finite()) || c.mass <= 0.0 {
        return Some("`consistent` needs a positive `mass` and finite numbers".into());
    }
    let ine = (ine + ine.transpose()) * 0.5;
    inv.mass = c.mass;
    inv.first_moment = Vector3::from(c.first_moment);
    inv.second_moment = Matrix3::identity() * (0.5 * ine.trace()) - ine;
    inv.inertia = ine;
    for j in 0..k {
        for a in 0..3 {
            inv.s_bar[(a, j)] = c.s_bar[j][a];
        }
        // Row a of Ī_θf⁰ is X_bc − X_cb for (a, b, c) cyclic.
        for (a, b, cc) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
            let now = inv.x_s[b][cc][j] - inv.x_s[cc][b][j];
            let d = 0.5 * (c.coupling[j][a] - now);
            inv.x_s[b][cc][j] += d;
            inv.x_s[cc][b][j] -= d;
        }
    }
    inv.coupling = inv.coupling_at(&DVector::zeros(k));
    inv.modal_mass = mass;
    // M(0) for the speeds (ω, v_O, q̇_f): [[Ī, h̃, C], [h̃ᵀ, m 1, S̄], [Cᵀ, S̄ᵀ, M_ff]].
    let n = 6 + k;
    let mut m = DMatrix::zeros(n, n);
    let h = inv.first_moment.cross_matrix();
    m.view_mut((0, 0), (3, 3)).copy_from(&inv.inertia);
    m.view_mut((0, 3), (3, 3)).copy_from(&h);
    m.view_mut((3, 0), (3, 3)).copy_from(&h.transpose());
    m.view_mut((3, 3), (3, 3))
        .copy_from(&(Matrix3::identity() * inv.mass));
    m.view_mut((0, 6), (3, k)).copy_from(&inv.coupling);
    m.view_mut((6, 0), (k, 3))
        .copy_from(&inv.coupling.transpose());
    m.view_mut((3, 6), (3, k)).copy_from(&inv.s_bar);
    m.view_mut((6, 3), (k, 3)).copy_from(&inv.s_bar.transpose());
    m.view_mut((6, 6), (k, k)).copy_from(&inv.modal_mass);
    let m = (&m + m.transpose()) * 0.5;
    let eig = SymmetricEigen::new(m);
    let (low, top) = (eig.eigenvalues.min(), eig.eigenvalues.amax());
    (low <= 1e-12 * top).then(|| {
        format!(
            "the consistent invariants and `modal_mass` make a mass matrix that is not positive \
             definite (smallest eigenvalue {low:.3e} of {top:.3e})"
        )
    })
}

/// The invariants of the lumped mass (module docs), and `Σ_i S̄_ii`.
fn lumped_invariants(
    data: &ModalData,
    positions: &[Vector3<f64>],
    shapes: &DMatrix<f64>,
) -> (Invariants, DMatrix<f64>) {
    let k = shapes.ncols();
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
        modal_stiffness: zk(),
    };
    for (i, node) in data.nodes.iter().enumerate() {
        let phi = shapes.rows(6 * i, 3).into_owned();
        let psi = shapes.rows(6 * i + 3, 3).into_owned();
        // The seven-point rule: (weight, offset ρ).
        let mut points = vec![(node.mass, Vector3::zeros())];
        if let Some(j) = node.inertia {
            let j = Matrix3::from_fn(|r, c| j[r][c]);
            let c = Matrix3::identity() * (0.5 * j.trace()) - j;
            let eig = SymmetricEigen::new((c + c.transpose()) * 0.5);
            let mu = if node.mass > 0.0 {
                node.mass / 7.0
            } else {
                1.0
            };
            for a in 0..3 {
                let lambda = eig.eigenvalues[a];
                if lambda == 0.0 {
                    continue;
                }
                let d = (lambda.abs() / (2.0 * mu)).sqrt();
                let w = mu * lambda.signum();
                let e: Vector3<f64> = eig.eigenvectors.column(a).into_owned();
                points.push((w, e * d));
                points.push((w, -e * d));
                points[0].0 -= 2.0 * w;
            }
        }
        for (dm, rho) in points {
            let u0 = positions[i] + rho;
            // S = Φ − ρ̃ Ψ.
            let s = &phi - rho.cross_matrix() * &psi;
            inv.mass += dm;
            inv.first_moment += u0 * dm;
            inv.second_moment += u0 * u0.transpose() * dm;
            inv.s_bar += &s * dm;
            for a in 0..3 {
                for b in 0..3 {
                    inv.s_ij[a][b] += s.row(a).transpose() * s.row(b) * dm;
                    inv.x_s[a][b] += s.row(b).transpose() * (u0[a] * dm);
                }
            }
        }
    }
    let c = inv.second_moment;
    inv.inertia = Matrix3::identity() * c.trace() - c;
    inv.coupling = inv.coupling_at(&DVector::zeros(k));
    let m = &inv.s_ij[0][0] + &inv.s_ij[1][1] + &inv.s_ij[2][2];
    let lumped = (&m + m.transpose()) * 0.5;
    inv.modal_mass = lumped.clone();
    (inv, lumped)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ROD: &str = r#"ModalData(
    nodes: [
        (position: (0, 0, 0), mass: 1.0, inertia: ((0.2, 0, 0), (0, 0.1, 0), (0, 0, 0.1))),
        (position: (1, 0, 0), mass: 1.0, name: "tip"),
    ],
    modes: [(translation: [(0, 0, 0), (0, 1, 0)], rotation: [(0, 0, 0.5), (0, 0, 1)])],
    modal_stiffness: [[100.0]],
)"#;

    #[test]
    fn imported_rotary_inertia_enters_exactly() {
        let data = parse("rod.modal.ron", ROD).unwrap();
        let body = build(&data, ROD).unwrap();
        // M_ff = m Φᵀ Φ + Ψᵀ J Ψ = 1·1 + 0.1·0.25; coupling z = J_zz Ψ_z + x m Φ_y = 0.05 + 1.
        let inv = &body.invariants;
        assert!(
            (inv.modal_mass[(0, 0)] - 1.025).abs() < 1e-12,
            "{}",
            inv.modal_mass
        );
        assert!(
            (inv.coupling[(2, 0)] - 1.05).abs() < 1e-12,
            "{}",
            inv.coupling
        );
        // Ī = node inertia + the tip's m x² about y and z.
        let want = Matrix3::new(0.2, 0.0, 0.0, 0.0, 1.1, 0.0, 0.0, 0.0, 1.1);
        assert!((inv.inertia - want).amax() < 1e-12, "{}", inv.inertia);
        assert!((inv.mass - 2.0).abs() < 1e-15 && inv.s_bar[(1, 0)] == 1.0);
    }

    #[test]
    fn imported_errors_are_located_in_the_file() {
        let bad = ROD
            .replace("mass: 1.0, name", "mass: -1.0, name")
            .replace("(0, 1, 0)]", "]");
        let data = parse("rod.modal.ron", &bad).unwrap();
        let errs = build(&data, &bad).unwrap_err();
        let text: Vec<String> = errs.iter().map(|e| e.located("rod.modal.ron")).collect();
        assert!(
            text.iter()
                .any(|e| e.starts_with("rod.modal.ron:4:37: node 1: mass is -1 kg")),
            "{text:?}"
        );
        assert!(
            text.iter()
                .any(|e| e.starts_with("rod.modal.ron:6:27: mode 1: 1 translations for 2 nodes")),
            "{text:?}"
        );
        let e = parse(
            "rod.modal.ron",
            &ROD.replace("mass: 1.0, name", "masss: 1.0, name"),
        )
        .unwrap_err();
        assert_eq!(e.at, Some((4, 31)), "{e:?}"); // at `masss`
        assert!(e.message.contains("masss"), "{e:?}");
    }
}
