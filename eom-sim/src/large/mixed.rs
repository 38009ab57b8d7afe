//! Rigid bodies and ANCF chains in one model: the rigid part's coordinates
//! appended to the structural free vector, its mass matrix as a dense
//! block in the sparse Newton matrix, and each cable end held at a marker
//! of a rigid body as constraints with multipliers, integrated by the
//! index-3 generalized-α method of Arnold and Brüls (2007).
//!
//! Unknowns `y = (x, q_r)`: the structure's free coordinates `x` and the
//! rigid part's coordinates `q_r` (with `q̇_r = u_r`, which the rigid part
//! guarantees). At `t_{n+1}` the step solves
//!
//! ```text
//! M_s ẍ + f_int(x, ẋ) − f_ext + Φ_xᵀ λ = 0
//! M_r(q_r) q̈_r + b(q_r, q̇_r, t) + Φ_qᵀ λ = 0
//! Φ(x, q_r, t) / β' = 0
//! ```
//!
//! by Newton on the accelerations and `λ` with the matrix
//! `[[S, Φ_yᵀ], [Φ_y, 0]]`, `S = M + γ' D + β' K` (`β' = h² β (1−α_f)/(1−α_m)`).
//! Dividing the constraint rows by `β'` (Bottasso, Bauchau and Cardona
//! 2007; Arnold and Brüls 2007 §4) makes them act on the acceleration
//! correction with the unit Jacobian `Φ_y`: both blocks of the matrix are
//! then of order one in `h`, and `λ` is the physical constraint force.
//! The rigid part's tangent (`∂(M_r q̈ + b + Φ_qᵀλ)/∂q_r`, `∂b/∂q̇_r`) is
//! taken by forward differences (a handful of columns); the coupling of a
//! clamp's multiplier with the node gradient and the body's rotation is
//! exact.
//!
//! The attachment constraints (mount `k` at world position `p(q_r, t)`,
//! normals `n₁`, `n₂` of the clamp's axis in world axes):
//! - pinned: `r_node − p = 0` (`dim` rows);
//! - clamped: also `r'_node · n₁ = 0` (planar) or `r'_node · n₁ = 0`,
//!   `r'_node · n₂ = 0` (spatial): the end's tangent stays along the axis
//!   (its length, the axial strain, stays free).
//!
//! Several cables are one structure ([`super::ancf::chains`]: each chain
//! at its own offset, [`super::ancf::ChainPart::attachment`] for its ends),
//! so a model with several cables is one `MixedModel` like any other.
//!
//! The rigid part's own holonomic equations `Φ_r(q_r, t) = 0`
//! ([`RigidPart::constraints`]: cut joints closing loops, the model's
//! `constraints:`, rheonomic ones included) are more rows of the same
//! block, after the attachments, scaled by `1/β'` alike: their multipliers
//! are the loop's constraint forces, the consistent initial acceleration
//! takes them in, and the residual check covers them. Only the position
//! level is used (the index-3 method); speed-level (nonholonomic)
//! equations have no place here and are refused by the caller. The start
//! must close the loops (`|Φ| ≤ 1e-8`) with speeds along them
//! (`|dΦ_r/dt| ≤ 1e-7 (1 + |u_r|)`): [`MixedAlpha::new`] refuses anything
//! else, naming the equation.
//!
//! The explicit path ([`super::integrate_rk4`]) does not run these models:
//! they are differential-algebraic (index 3).

pub mod statics;

use super::alpha::{AlphaModel, GeneralizedAlpha};
use super::model::StructuralModel;
use super::norm_inf;
use super::run::{DynamicsError, State, Violation};
use super::sparse::{FaerLu, Pattern, SparseMatrix, SparseSolver};
use crate::constrained::{DMatrix, DVector};
use crate::model::Point;
use std::fmt;
use std::sync::Arc;

/// The rigid part of a mixed model, with dynamic sizes: what the
/// generated code of the rigid bodies gives (`mass_matrix`, `bias`,
/// `energy`, `attachments`), compiled or interpreted.
pub trait RigidPart {
    /// Number of coordinates, equal to the number of speeds (`q̇ = u`).
    fn n(&self) -> usize;
    /// `M(q, t)`, `n × n` by rows.
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut [f64]);
    /// `b(q, u, t)` of `M u̇ = τ − b` (gravity, springs, velocity terms).
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut [f64]);
    /// Kinetic plus potential energy.
    fn energy(&self, t: f64, q: &[f64], u: &[f64]) -> f64;
    /// The size of the energies [`RigidPart::energy`] sums, `|T| + |V|`
    /// (what its error is measured against: the sum alone can cancel, a
    /// pendulum's `T + V` staying near zero as it swings); `|T + V|` by
    /// default.
    fn energy_scale(&self, t: f64, q: &[f64], u: &[f64]) -> f64 {
        self.energy(t, q, u).abs()
    }
    /// The mounts, flat: for each mount in order, the rows `p_x, p_y, p_z`
    /// (world position of the marker) and for a clamped mount also
    /// `n₁` and `n₂` (unit normals of the clamp's axis, world axes); each
    /// row its value followed by its `n` partial derivatives `∂/∂q_k`.
    fn attachments(&self, t: f64, q: &[f64], out: &mut [f64]);
    /// Number of the rigid part's own holonomic constraint equations
    /// `Φ_r(q, t) = 0` (cut joints closing loops, `constraints:` of the
    /// model); none by default.
    fn n_constraints(&self) -> usize {
        0
    }
    /// Names of those equations (`joint.k`, the constraint's name), for
    /// reports; empty by default.
    fn constraint_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// `Φ_r(q, t)` and its Jacobian, flat as [`RigidPart::attachments`]:
    /// for each equation its value followed by its `n` partial
    /// derivatives `∂Φ_r/∂q_k` (`n_constraints() · (1 + n)` values).
    /// Position level only: the index-3 method needs nothing else (the
    /// rows are divided by `β'` as the attachments are); a rheonomic
    /// `Φ_r(q, t)` is fine. Does nothing by default.
    fn constraints(&self, t: f64, q: &[f64], out: &mut [f64]) {
        let _ = (t, q, out);
    }
    /// Names of the rigid part's unilateral contacts (joint limits,
    /// markers against planes, spheres: the rows of the generated
    /// `contacts`); none by default.
    fn contact_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// The generated `contacts` at `(t, q, u)`, flat: `g`, `ġ`, `γ`
    /// (`g̈ = wᵀ u̇ − γ`), `e` and `μ`, one each per contact, then the rows
    /// `w` (`n` each); `false` if it cannot be evaluated. `false` by
    /// default (no contacts).
    fn contacts(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) -> bool {
        let _ = (t, q, u, out);
        false
    }
    /// The generated `friction` at `(t, q, u)`, flat: the tangential
    /// speeds `v_t1`, `v_t2`, then `γ_t1`, `γ_t2` (`v̇_t = W_t u̇ − γ_t`),
    /// one each per contact, then the rows `W_t1` (`n` each, per contact)
    /// and `W_t2`; `false` if it cannot be evaluated or the part has no
    /// friction (every contact's `μ = 0`). `false` by default.
    fn friction(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) -> bool {
        let _ = (t, q, u, out);
        false
    }
    /// Number of frames of the generated `contact_frames` (the bodies'
    /// points cable nodes touch); none by default.
    fn n_frames(&self) -> usize {
        0
    }
    /// The generated `contact_frames` at `(t, q, u)`, flat: per frame its
    /// point's world position `p`, the body's axes by rows, `ṗ`, `ω`,
    /// their rates at `u̇ = 0`, then the rows `∂ṗ/∂u` and `∂ω/∂u`
    /// (`24 + 6 n` values); `false` if it cannot be evaluated. `false` by
    /// default.
    fn frames(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) -> bool {
        let _ = (t, q, u, out);
        false
    }
    /// What can feed energy into the rigid part (an actuator, a force
    /// given as a function, a prescribed motion, a constraint that moves
    /// with time), named; `None` if nothing can: gravity and springs are in
    /// [`RigidPart::energy`], dampers only take energy out, and a run of
    /// the model whose energy rises refuses to go on
    /// (`DynamicsError::EnergyRose`). By default the rigid part's forces
    /// are not known, and no run is refused.
    fn energy_source(&self) -> Option<String> {
        Some("a rigid part whose forces the runtime does not know".into())
    }
}

/// A rigid part from the generated functions by name (`mass_matrix`,
/// `bias`, `energy`, `attachments`): compiled code through
/// `eom_sim::Model::evaluate`, the interpreter through its own `evaluate`.
/// A function that cannot be evaluated gives NaN, which stops the run.
pub struct ByName<F> {
    n: usize,
    mounts: usize,
    evaluate: F,
    /// Names of the holonomic constraint equations (see
    /// [`ByName::with_constraints`]).
    constraint_names: Vec<String>,
    /// See [`ByName::with_energy_source`].
    energy_source: Option<String>,
    /// All equations of the generated `constraints` function.
    nc_all: usize,
    /// See [`ByName::with_contacts`].
    contact_names: Vec<String>,
    /// See [`ByName::with_frames`].
    frames: usize,
}

impl<F: Fn(&str, &Point<'_>, &mut [f64]) -> bool> ByName<F> {
    /// A rigid part of `n` coordinates (`q̇ = u`) whose `attachments`
    /// result is `mount_len` long, evaluated by `evaluate(name, at, out)`.
    pub fn new(n: usize, mount_len: usize, evaluate: F) -> Self {
        ByName {
            n,
            mounts: mount_len,
            evaluate,
            constraint_names: Vec::new(),
            nc_all: 0,
            energy_source: Some("generated functions whose forces are not stated".into()),
            contact_names: Vec::new(),
            frames: 0,
        }
    }

    /// The same with `count` frames of the generated `contact_frames`
    /// ([`RigidPart::frames`]: bodies' points cable nodes touch).
    pub fn with_frames(mut self, count: usize) -> Self {
        self.frames = count;
        self
    }

    /// The same with unilateral contacts of its own, named `names`, from
    /// the generated `contacts` ([`RigidPart::contacts`]).
    pub fn with_contacts(mut self, names: Vec<String>) -> Self {
        self.contact_names = names;
        self
    }

    /// States what can feed energy into the rigid part
    /// ([`RigidPart::energy_source`]; `None`: nothing can, its energy never
    /// rises). Unstated, a run is never refused for its energy.
    pub fn with_energy_source(mut self, source: Option<String>) -> Self {
        self.energy_source = source;
        self
    }

    /// The same with constraint equations of its own from the generated
    /// `constraints` function (`Φ`, `Φ̇`, `γ`, each `nc_all`, then `J`,
    /// `nc_all × n`, with `J = Φ_q` as `q̇ = u`): the first
    /// `holonomic.len()` equations, named `holonomic`, are the rigid
    /// part's [`RigidPart::constraints`]. The caller refuses speed-level
    /// (nonholonomic) equations, which come after them.
    pub fn with_constraints(mut self, nc_all: usize, holonomic: Vec<String>) -> Self {
        // More names than equations: the result is too short for them,
        // the evaluation fails and gives NaN, which stops the run.
        self.nc_all = nc_all.max(holonomic.len());
        self.constraint_names = holonomic;
        self
    }

    fn call(&self, name: &str, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) -> bool {
        let at = Point {
            t,
            q,
            u,
            udot: &[],
            tau: &[],
            lambda: &[],
        };
        let done = (self.evaluate)(name, &at, out);
        if !done {
            out.fill(f64::NAN);
        }
        done
    }
}

impl<F: Fn(&str, &Point<'_>, &mut [f64]) -> bool> RigidPart for ByName<F> {
    fn energy_source(&self) -> Option<String> {
        self.energy_source.clone()
    }
    fn n(&self) -> usize {
        self.n
    }
    fn mass_matrix(&self, t: f64, q: &[f64], m: &mut [f64]) {
        self.call("mass_matrix", t, q, &[], m);
    }
    fn bias(&self, t: f64, q: &[f64], u: &[f64], b: &mut [f64]) {
        self.call("bias", t, q, u, b);
    }
    fn energy(&self, t: f64, q: &[f64], u: &[f64]) -> f64 {
        let mut e = [0.0; 2];
        self.call("energy", t, q, u, &mut e);
        e[0] + e[1]
    }
    fn energy_scale(&self, t: f64, q: &[f64], u: &[f64]) -> f64 {
        let mut e = [0.0; 2];
        self.call("energy", t, q, u, &mut e);
        e[0].abs() + e[1].abs()
    }
    fn attachments(&self, t: f64, q: &[f64], out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.mounts);
        self.call("attachments", t, q, &[], out);
    }
    fn n_constraints(&self) -> usize {
        self.constraint_names.len()
    }
    fn constraint_names(&self) -> Vec<String> {
        self.constraint_names.clone()
    }
    fn contact_names(&self) -> Vec<String> {
        self.contact_names.clone()
    }
    fn contacts(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) -> bool {
        !self.contact_names.is_empty() && self.call("contacts", t, q, u, out)
    }
    fn friction(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) -> bool {
        !self.contact_names.is_empty() && self.call("friction", t, q, u, out)
    }
    fn n_frames(&self) -> usize {
        self.frames
    }
    fn frames(&self, t: f64, q: &[f64], u: &[f64], out: &mut [f64]) -> bool {
        self.frames > 0 && self.call("contact_frames", t, q, u, out)
    }
    fn constraints(&self, t: f64, q: &[f64], out: &mut [f64]) {
        let (n, nc, nh) = (self.n, self.nc_all, self.constraint_names.len());
        if nh == 0 {
            return;
        }
        // Φ, Φ̇, γ, then J by rows; Φ does not depend on u.
        let mut all = vec![0.0; 3 * nc + nc * n];
        let u = vec![0.0; n];
        self.call("constraints", t, q, &u, &mut all);
        for i in 0..nh {
            let row = &mut out[i * (1 + n)..(i + 1) * (1 + n)];
            row[0] = all[i];
            row[1..].copy_from_slice(&all[3 * nc + i * n..3 * nc + (i + 1) * n]);
        }
    }
}

/// A cable end held at a mount of the rigid part.
#[derive(Clone, Debug, PartialEq)]
pub struct Attachment {
    /// A name for reports (`cable.start`).
    pub name: String,
    /// Dimension of positions, 2 or 3.
    pub dim: usize,
    /// Full structural indices of the end node's position coordinates.
    pub position: Vec<usize>,
    /// Clamped ends: full structural indices of the node's gradient `r'`.
    pub gradient: Option<Vec<usize>>,
}

impl Attachment {
    /// Rows of the rigid part's [`RigidPart::attachments`] for this mount.
    fn mount_rows(&self) -> usize {
        if self.gradient.is_some() { 9 } else { 3 }
    }

    /// Constraint equations.
    fn equations(&self) -> usize {
        self.dim + self.gradient.as_ref().map_or(0, |_| self.dim - 1)
    }
}

/// Why a mixed model cannot be built.
#[derive(Clone, Debug, PartialEq)]
pub enum MixedError {
    /// An attachment whose positions have other than 2 or 3 components.
    Dimension {
        /// The attachment.
        attachment: String,
        /// Its components.
        dim: usize,
    },
    /// An attachment holding a node coordinate a support already fixes.
    FixedNode {
        /// The attachment.
        attachment: String,
        /// The structure's full coordinate.
        coordinate: usize,
    },
    /// The rigid part names other than one name per constraint equation.
    ConstraintNames {
        /// Its equations.
        equations: usize,
        /// Its names.
        names: usize,
    },
}

impl fmt::Display for MixedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MixedError::Dimension { attachment, dim } => write!(
                f,
                "attachment `{attachment}`: positions have 2 or 3 components, not {dim}"
            ),
            MixedError::FixedNode {
                attachment,
                coordinate,
            } => write!(
                f,
                "attachment `{attachment}`: node coordinate {coordinate} is fixed by a support; an end held at a marker must be free in the chain"
            ),
            MixedError::ConstraintNames { equations, names } => write!(
                f,
                "the rigid part has {equations} constraint equations but {names} names"
            ),
        }
    }
}

impl std::error::Error for MixedError {}

/// The constraint values and Jacobian at one state.
#[derive(Clone, Debug, Default)]
struct ConstraintEval {
    /// `Φ`.
    phi: Vec<f64>,
    /// `(row, column of y, ∂Φ_row/∂y_col)`.
    jac: Vec<(usize, usize, f64)>,
    /// Clamps: `(row, y column of r'_i, y column of q_j, ∂n_i/∂q_j)`, the
    /// coupling `∂²Φ_row/∂r'_i∂q_j`.
    cross: Vec<(usize, usize, usize, f64)>,
}

/// Structure, rigid part and attachments over one unknown vector.
pub struct MixedModel<'r> {
    structure: StructuralModel,
    rigid: Box<dyn RigidPart + 'r>,
    attachments: Vec<Attachment>,
    n_s: usize,
    n_r: usize,
    m: usize,
    mount_len: usize,
    /// The rigid part's own constraint equations (the last rows).
    nc_r: usize,
    pattern: Arc<Pattern>,
    /// Structural pattern slot → slot of the combined pattern.
    s_map: Vec<usize>,
}

impl<'r> MixedModel<'r> {
    /// Joins `structure` and `rigid` by `attachments` (whose node
    /// coordinates must be free in `structure`).
    pub fn new(
        structure: StructuralModel,
        rigid: Box<dyn RigidPart + 'r>,
        attachments: Vec<Attachment>,
    ) -> Result<MixedModel<'r>, MixedError> {
        let (n_s, n_r) = (structure.n_free(), rigid.n());
        let mut entries: Vec<(usize, usize)> = structure
            .pattern()
            .entries()
            .map(|(i, j, _)| (i, j))
            .collect();
        for i in 0..n_r {
            for j in 0..n_r {
                entries.push((n_s + i, n_s + j));
            }
        }
        let mut row = n_s + n_r;
        let mut mount_len = 0;
        for a in &attachments {
            if a.dim != 2 && a.dim != 3 {
                return Err(MixedError::Dimension {
                    attachment: a.name.clone(),
                    dim: a.dim,
                });
            }
            let free = |i: usize| {
                structure
                    .free_index(i)
                    .ok_or_else(|| MixedError::FixedNode {
                        attachment: a.name.clone(),
                        coordinate: i,
                    })
            };
            let pos: Vec<usize> = a
                .position
                .iter()
                .map(|&i| free(i))
                .collect::<Result<_, _>>()?;
            let grad: Vec<usize> = match &a.gradient {
                Some(g) => g.iter().map(|&i| free(i)).collect::<Result<_, _>>()?,
                None => Vec::new(),
            };
            let mut cols: Vec<usize> = (n_s..n_s + n_r).collect();
            cols.extend(&pos);
            cols.extend(&grad);
            for _ in 0..a.equations() {
                for &c in &cols {
                    entries.push((row, c));
                    entries.push((c, row));
                }
                row += 1;
            }
            for &g in &grad {
                for j in n_s..n_s + n_r {
                    entries.push((g, j));
                    entries.push((j, g));
                }
            }
            mount_len += a.mount_rows() * (1 + n_r);
        }
        // The rigid part's own equations Φ_r(q_r, t) = 0, after the
        // attachments: they touch the rigid coordinates only.
        let nc_r = rigid.n_constraints();
        if rigid.constraint_names().len() != nc_r {
            return Err(MixedError::ConstraintNames {
                equations: nc_r,
                names: rigid.constraint_names().len(),
            });
        }
        for _ in 0..nc_r {
            for c in n_s..n_s + n_r {
                entries.push((row, c));
                entries.push((c, row));
            }
            row += 1;
        }
        let m = row - n_s - n_r;
        let pattern = Arc::new(Pattern::new(n_s + n_r + m, entries));
        let s_map = structure
            .pattern()
            .entries()
            .map(|(i, j, _)| pattern.slot(i, j).unwrap_or(usize::MAX))
            .collect();
        Ok(MixedModel {
            structure,
            rigid,
            attachments,
            n_s,
            n_r,
            m,
            mount_len,
            nc_r,
            pattern,
            s_map,
        })
    }

    /// The structure.
    pub fn structure(&self) -> &StructuralModel {
        &self.structure
    }

    /// Where the structure's tangent comes from
    /// ([`StructuralModel::set_tangent`]); the rigid part's block is by
    /// differences always.
    pub fn set_tangent(&mut self, tangent: crate::run::Jacobian) {
        self.structure.set_tangent(tangent);
    }

    /// The rigid part.
    pub fn rigid(&self) -> &(dyn RigidPart + 'r) {
        self.rigid.as_ref()
    }

    /// The attachments.
    pub fn attachments(&self) -> &[Attachment] {
        &self.attachments
    }

    /// Unknowns (structural free coordinates, then rigid coordinates).
    pub fn n(&self) -> usize {
        self.n_s + self.n_r
    }

    /// Structural free coordinates (the first entries of `y`).
    pub fn n_structural(&self) -> usize {
        self.n_s
    }

    /// Constraint equations (multipliers): the attachments' rows, then
    /// [`MixedModel::rigid_constraint_rows`].
    pub fn n_constraints(&self) -> usize {
        self.m
    }

    /// The rows of `Φ` (and of the multipliers) that are the rigid part's
    /// own equations [`RigidPart::constraints`] (loops closed by cut
    /// joints, `constraints:`): the last ones.
    pub fn rigid_constraint_rows(&self) -> std::ops::Range<usize> {
        self.m - self.nc_r..self.m
    }

    /// Length of the scratch the constraints are evaluated into: the
    /// attachments, then the rigid part's equations.
    fn buffer_len(&self) -> usize {
        self.mount_len + self.nc_r * (1 + self.n_r)
    }

    /// The starting state: the structure at its reference, the rigid part
    /// at `q_r`, `u_r`, the structure at rest.
    pub fn initial_state(&self, t: f64, q_r: &[f64], u_r: &[f64]) -> State {
        let mut q = self.structure.restrict(self.structure.q0());
        q.extend_from_slice(q_r);
        let mut v = vec![0.0; self.n_s];
        v.extend_from_slice(u_r);
        State { t, q, v }
    }

    /// The structure's full coordinates of `y`.
    pub fn structural_full(&self, y: &[f64]) -> Vec<f64> {
        self.structure.expand(&y[..self.n_s])
    }

    /// Total energy: the structure's (kinetic, strain, loads) and the
    /// rigid part's.
    pub fn energy(&self, s: &State) -> f64 {
        let q_full = self.structural_full(&s.q);
        self.structure.energy(&q_full, &s.v[..self.n_s])
            + self.rigid.energy(s.t, &s.q[self.n_s..], &s.v[self.n_s..])
    }

    /// `Φ(y, t)` (the attachment constraints, then the rigid part's own
    /// equations; unscaled).
    pub fn constraint_residual(&self, t: f64, y: &[f64]) -> Vec<f64> {
        let q_full = self.structural_full(y);
        let mut c = ConstraintEval::default();
        let mut mounts = vec![0.0; self.buffer_len()];
        self.constraints(t, &q_full, &y[self.n_s..], &mut mounts, &mut c);
        c.phi
    }

    /// `Φ_y(y, t)`, dense (`n_constraints × n`: the attachment rows, then
    /// the rigid part's own); it acts on the speeds as on the coordinates'
    /// rates (`q̇ = u`).
    pub(super) fn constraint_jacobian(&self, t: f64, y: &[f64]) -> DMatrix<f64> {
        let q_full = self.structural_full(y);
        let mut c = ConstraintEval::default();
        let mut mounts = vec![0.0; self.buffer_len()];
        self.constraints(t, &q_full, &y[self.n_s..], &mut mounts, &mut c);
        let mut j = DMatrix::zeros(self.m, self.n());
        for &(row, col, v) in &c.jac {
            if row < self.m && col < self.n() {
                j[(row, col)] += v;
            }
        }
        j
    }

    /// `dΦ/dt = Φ_y v + Φ_t` at `s`, `j` the Jacobian `Φ_y` at `s`
    /// ([`MixedModel::constraint_jacobian`]): `Φ_t` by a central
    /// difference in time at fixed `y` (zero for the attachments and for
    /// scleronomic loops).
    pub(super) fn rates_of_constraints(&self, s: &State, j: &DMatrix<f64>) -> DVector<f64> {
        let eps = 1e-6 * (1.0 + s.t.abs());
        let (plus, minus) = (
            DVector::from_vec(self.constraint_residual(s.t + eps, &s.q)),
            DVector::from_vec(self.constraint_residual(s.t - eps, &s.q)),
        );
        j * DVector::from_column_slice(&s.v) + (plus - minus) / (2.0 * eps)
    }

    /// The accelerations at `s` without forces beyond the model's own
    /// (no contacts), the constraints held: `[[M, Φ_yᵀ], [Φ_y, 0]] (a, λ)
    /// = (f_ext − f_int − b, γ)`, as at a start.
    pub(super) fn constrained_acceleration(&self, s: &State) -> Result<Vec<f64>, DynamicsError> {
        let mut w = self.work(s);
        let mut acc = vec![0.0; self.n()];
        let mut lambda = vec![0.0; self.m];
        self.initial_acceleration(&mut w, s, &mut acc, &mut lambda)?;
        Ok(acc)
    }

    /// `Φ` with its Jacobian and the clamps' coupling terms.
    fn constraints(
        &self,
        t: f64,
        q_full: &[f64],
        q_r: &[f64],
        mounts: &mut [f64],
        c: &mut ConstraintEval,
    ) {
        let (n_s, n_r) = (self.n_s, self.n_r);
        let (mounts, own) = mounts.split_at_mut(self.mount_len);
        self.rigid.attachments(t, q_r, mounts);
        c.phi.clear();
        c.jac.clear();
        c.cross.clear();
        let stride = 1 + n_r;
        let mut at = 0;
        let free = |i: usize| self.structure.free_index(i).unwrap_or(usize::MAX);
        for a in &self.attachments {
            let rows = &mounts[at..at + a.mount_rows() * stride];
            at += a.mount_rows() * stride;
            // r_node − p = 0.
            for k in 0..a.dim {
                let row = c.phi.len();
                let p = &rows[k * stride..(k + 1) * stride];
                c.phi.push(q_full[a.position[k]] - p[0]);
                c.jac.push((row, free(a.position[k]), 1.0));
                for j in 0..n_r {
                    c.jac.push((row, n_s + j, -p[1 + j]));
                }
            }
            // r'_node · n_l = 0.
            if let Some(g) = &a.gradient {
                for l in 0..a.dim - 1 {
                    let row = c.phi.len();
                    let base = (3 + 3 * l) * stride;
                    let normal = |i: usize| &rows[base + i * stride..base + (i + 1) * stride];
                    let mut phi = 0.0;
                    for (i, &gi) in g.iter().enumerate() {
                        phi += q_full[gi] * normal(i)[0];
                        c.jac.push((row, free(gi), normal(i)[0]));
                    }
                    for j in 0..n_r {
                        let d: f64 = g
                            .iter()
                            .enumerate()
                            .map(|(i, &gi)| q_full[gi] * normal(i)[1 + j])
                            .sum();
                        c.jac.push((row, n_s + j, d));
                        for (i, &gi) in g.iter().enumerate() {
                            c.cross.push((row, free(gi), n_s + j, normal(i)[1 + j]));
                        }
                    }
                    c.phi.push(phi);
                }
            }
        }
        // The rigid part's own equations: Φ_r and ∂Φ_r/∂q_r.
        if self.nc_r > 0 {
            self.rigid.constraints(t, q_r, own);
            for r in own.chunks(stride) {
                let row = c.phi.len();
                c.phi.push(r[0]);
                for j in 0..n_r {
                    c.jac.push((row, n_s + j, r[1 + j]));
                }
            }
        }
    }

    /// The rigid rows of the residual, `M_r a + b + Φ_qᵀ λ`, at `q_r`.
    #[allow(clippy::too_many_arguments)]
    fn rigid_residual(
        &self,
        t: f64,
        q_full: &[f64],
        q_r: &[f64],
        u_r: &[f64],
        a_r: &[f64],
        lambda: &[f64],
        scratch: &mut RigidScratch,
        out: &mut [f64],
    ) {
        let n_r = self.n_r;
        self.rigid.mass_matrix(t, q_r, &mut scratch.mass);
        self.rigid.bias(t, q_r, u_r, out);
        for (o, row) in out.iter_mut().zip(scratch.mass.chunks(n_r.max(1))) {
            *o += row.iter().zip(a_r).map(|(m, a)| m * a).sum::<f64>();
        }
        self.constraints(t, q_full, q_r, &mut scratch.mounts, &mut scratch.c);
        for &(row, col, v) in &scratch.c.jac {
            if col >= self.n_s {
                out[col - self.n_s] += v * lambda[row];
            }
        }
    }
}

struct RigidScratch {
    mass: Vec<f64>,
    mounts: Vec<f64>,
    c: ConstraintEval,
}

/// A mixed model's scratch for [`GeneralizedAlpha`]: the load, the
/// structure's tangent, the KKT matrix and its LU, the expanded structural
/// coordinates, the rigid part's scratch.
pub struct MixedWork {
    load: Vec<f64>,
    s_matrix: SparseMatrix,
    matrix: SparseMatrix,
    lu: FaerLu,
    q_full: Vec<f64>,
    v_full: Vec<f64>,
    scratch: Vec<f64>,
    rs: RigidScratch,
}

/// Index-3 generalized-α (Arnold and Brüls 2007) on a [`MixedModel`]: the
/// one [`GeneralizedAlpha`], on the mixed model's side of its contract.
pub type MixedAlpha<'m, 'r> = GeneralizedAlpha<'m, MixedModel<'r>>;

impl MixedAlpha<'_, '_> {
    /// The force each mount applies to its cable end, world axes (`−λ` of
    /// the position rows; `z = 0` when planar).
    pub fn reactions(&self) -> Vec<[f64; 3]> {
        self.model().mount_forces(self.multipliers())
    }
}

impl MixedModel<'_> {
    /// The force each mount applies to its cable end, world axes, from
    /// the multipliers `lambda` (`−λ` of the position rows; `z = 0` when
    /// planar).
    pub fn mount_forces(&self, lambda: &[f64]) -> Vec<[f64; 3]> {
        debug_assert!(
            lambda.len() >= self.m,
            "{} multipliers for {} constraint rows",
            lambda.len(),
            self.m
        );
        let mut out = Vec::new();
        let mut row = 0;
        for a in &self.attachments {
            let mut f = [0.0; 3];
            for (k, fk) in f.iter_mut().enumerate().take(a.dim) {
                *fk = -lambda.get(row + k).copied().unwrap_or(f64::NAN);
            }
            out.push(f);
            row += a.equations();
        }
        out
    }
}

/// The structure, the rigid part and the attachments as one index-3
/// system: `y = (x, q_r)`, the attachment rows then the rigid part's own.
/// [`GeneralizedAlpha::new`] on it refuses a start whose constraint
/// residual exceeds `1e-8` (the cable ends are not at their markers, a
/// clamp's axis is not along the cable, or the rigid part's loop is open)
/// and a start whose rigid speeds leave the rigid part's own constraints
/// (`|dΦ_r/dt| > 1e-7 (1 + |u_r|∞)`).
impl AlphaModel for MixedModel<'_> {
    type Work = MixedWork;

    fn n(&self) -> usize {
        self.n_s + self.n_r
    }

    fn n_constraints(&self) -> usize {
        self.m
    }

    fn work(&self, state: &State) -> MixedWork {
        let st = &self.structure;
        let n_s = self.n_s;
        MixedWork {
            load: st.load_free(),
            s_matrix: SparseMatrix::zeros(st.pattern().clone()),
            matrix: SparseMatrix::zeros(self.pattern.clone()),
            lu: FaerLu::default(),
            q_full: st.expand(&state.q[..n_s]),
            v_full: st.expand_rate(&state.v[..n_s]),
            scratch: vec![0.0; st.n_full()],
            rs: RigidScratch {
                mass: vec![0.0; self.n_r * self.n_r],
                mounts: vec![0.0; self.buffer_len()],
                c: ConstraintEval::default(),
            },
        }
    }

    fn start(
        &self,
        w: &mut MixedWork,
        state: &State,
        acc: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let phi0 = self.constraint_residual(state.t, &state.q);
        let worst = norm_inf(&phi0);
        if worst.is_nan() || worst > 1e-8 {
            return Err(DynamicsError::Inconsistent {
                t: state.t,
                residual: worst,
                violations: self.violations(&phi0),
            });
        }
        self.check_rigid_speeds(state)?;
        self.initial_acceleration(w, state, acc, lambda)
    }

    fn residual(
        &self,
        w: &mut MixedWork,
        t: f64,
        y: &[f64],
        v: &[f64],
        acc: &[f64],
        lambda: &[f64],
        r: &mut [f64],
    ) {
        let (n_s, n_r, n, m) = (self.n_s, self.n_r, self.n(), self.m);
        self.structure.expand_into(&y[..n_s], &mut w.q_full);
        self.structure.expand_into(&v[..n_s], &mut w.v_full);
        // Structural rows: M a + f_int − f_ext.
        let mut f = vec![0.0; n_s];
        self.structure
            .internal(&w.q_full, &w.v_full, &mut w.scratch, &mut f);
        for i in 0..n_s {
            r[i] = f[i] - w.load[i];
        }
        self.structure
            .mass()
            .mul_add(1.0, &acc[..n_s], &mut r[..n_s]);
        // Rigid rows, constraint forces, and Φ.
        let mut rr = vec![0.0; n_r];
        self.rigid_residual(
            t,
            &w.q_full,
            &y[n_s..],
            &v[n_s..],
            &acc[n_s..],
            lambda,
            &mut w.rs,
            &mut rr,
        );
        r[n_s..n].copy_from_slice(&rr);
        for &(row, col, val) in &w.rs.c.jac {
            if col < n_s {
                r[col] += val * lambda[row];
            }
        }
        r[n..n + m].copy_from_slice(&w.rs.c.phi[..m]);
    }

    fn factor(
        &self,
        w: &mut MixedWork,
        t: f64,
        y: &[f64],
        v: &[f64],
        acc: &[f64],
        lambda: &[f64],
        bp: f64,
        gp: f64,
    ) -> Result<(), DynamicsError> {
        self.assemble_at(w, y, v, acc, lambda, t, bp, gp)
    }

    fn solve(&self, w: &mut MixedWork, r: &mut [f64]) {
        w.lu.solve(r);
    }

    fn accepted(&self, w: &mut MixedWork, state: &State) -> f64 {
        let n_s = self.n_s;
        self.structure.expand_into(&state.q[..n_s], &mut w.q_full);
        self.structure.expand_into(&state.v[..n_s], &mut w.v_full);
        norm_inf(&self.constraint_residual(state.t, &state.q))
    }

    fn full<'w>(&self, w: &'w MixedWork) -> &'w [f64] {
        &w.q_full
    }
}

impl MixedModel<'_> {
    /// What does not hold in `phi`.
    fn violations(&self, phi: &[f64]) -> Vec<Violation> {
        let mut out = Vec::new();
        let mut row = 0;
        for a in &self.attachments {
            let rows = &phi[row..row + a.equations()];
            row += a.equations();
            let gap = rows[..a.dim].iter().map(|x| x * x).sum::<f64>().sqrt();
            if gap > 1e-8 {
                out.push(Violation::Gap {
                    attachment: a.name.clone(),
                    gap,
                });
            }
            if rows[a.dim..].iter().any(|x| x.abs() > 1e-8) {
                out.push(Violation::ClampAxis {
                    attachment: a.name.clone(),
                });
            }
        }
        let names = self.rigid.constraint_names();
        for (k, name) in self.rigid_constraint_rows().zip(&names) {
            if phi[k].is_nan() || phi[k].abs() > 1e-8 {
                out.push(Violation::RigidPosition {
                    constraint: name.clone(),
                    value: phi[k],
                });
            }
        }
        out
    }

    /// The rigid part's own equations at the speed level, `dΦ_r/dt` along
    /// the motion by a central difference: refuses speeds that leave the
    /// loop (the index-3 method would jump onto it in the first step).
    fn check_rigid_speeds(&self, state: &State) -> Result<(), DynamicsError> {
        let rows = self.rigid_constraint_rows();
        if rows.is_empty() {
            return Ok(());
        }
        let (t, n_s) = (state.t, self.n_s);
        let eps = 1e-5;
        let shifted = |s: f64| -> Vec<f64> {
            let y: Vec<f64> = state
                .q
                .iter()
                .zip(&state.v)
                .enumerate()
                .map(|(i, (q, v))| if i < n_s { *q } else { q + s * v })
                .collect();
            self.constraint_residual(t + s, &y)
        };
        let (plus, minus) = (shifted(eps), shifted(-eps));
        let speed = norm_inf(&state.v[n_s..]);
        let names = self.rigid.constraint_names();
        let mut bad = Vec::new();
        for (k, name) in rows.zip(&names) {
            let rate = (plus[k] - minus[k]) / (2.0 * eps);
            if rate.is_nan() || rate.abs() > 1e-7 * (1.0 + speed) {
                bad.push(Violation::RigidSpeed {
                    constraint: name.clone(),
                    rate,
                });
            }
        }
        if bad.is_empty() {
            Ok(())
        } else {
            Err(DynamicsError::Inconsistent {
                t,
                residual: 0.0,
                violations: bad,
            })
        }
    }

    /// `[[M, Φ_yᵀ], [Φ_y, 0]] (q̈, λ) = (f_ext − f_int − b, γ)` with
    /// `γ = −d²Φ/dt²` at `q̈ = 0`, by a central second difference along
    /// the motion.
    fn initial_acceleration(
        &self,
        w: &mut MixedWork,
        state: &State,
        acc: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let (n_s, n_r, n) = (self.n_s, self.n_r, self.n());
        let t = state.t;
        let mut rhs = vec![0.0; n + self.m];
        let mut f = vec![0.0; n_s];
        self.structure
            .internal(&w.q_full, &w.v_full, &mut w.scratch, &mut f);
        for i in 0..n_s {
            rhs[i] = w.load[i] - f[i];
        }
        let mut b = vec![0.0; n_r];
        let (q_r, u_r) = (&state.q[n_s..], &state.v[n_s..]);
        self.rigid.bias(t, q_r, u_r, &mut b);
        for i in 0..n_r {
            rhs[n_s + i] = -b[i];
        }
        let eps = 1e-4;
        let shifted = |s: f64| -> Vec<f64> {
            let y: Vec<f64> = state
                .q
                .iter()
                .zip(&state.v)
                .map(|(q, v)| q + s * v)
                .collect();
            self.constraint_residual(t + s, &y)
        };
        let (plus, zero, minus) = (shifted(eps), shifted(0.0), shifted(-eps));
        for k in 0..self.m {
            rhs[n + k] = -(plus[k] - 2.0 * zero[k] + minus[k]) / (eps * eps);
        }
        // At the start: λ = 0 and q̈ = 0 in the (unused) tangent terms.
        let zeros = vec![0.0; n];
        let no_lambda = vec![0.0; self.m];
        self.assemble_at(w, &state.q, &state.v, &zeros, &no_lambda, t, 0.0, 0.0)?;
        w.lu.solve(&mut rhs);
        if rhs.iter().any(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite { t });
        }
        acc.copy_from_slice(&rhs[..n]);
        lambda.copy_from_slice(&rhs[n..]);
        Ok(())
    }
    /// Builds and factors `[[M + γ' D + β' K, Φ_yᵀ], [Φ_y, 0]]` at the
    /// current iterate (`w.q_full`, `w.v_full`, `w.rs`'s rigid
    /// state from `y`, `v`, `a`, `λ` given).
    #[allow(clippy::too_many_arguments)]
    fn assemble_at(
        &self,
        w: &mut MixedWork,
        y: &[f64],
        v: &[f64],
        a: &[f64],
        lambda: &[f64],
        t: f64,
        bp: f64,
        gp: f64,
    ) -> Result<(), DynamicsError> {
        let model = self;
        let (n_s, n_r, n) = (model.n_s, model.n_r, model.n());
        w.matrix.clear();
        model
            .structure
            .jacobian(&w.q_full, &w.v_full, bp, gp, 1.0, &mut w.s_matrix);
        for (k, &slot) in model.s_map.iter().enumerate() {
            if slot != usize::MAX {
                w.matrix.values[slot] += w.s_matrix.values[k];
            }
        }
        let (q_r, u_r, a_r) = (&y[n_s..], &v[n_s..], &a[n_s..]);
        // Rigid block: M_r + β' ∂g/∂q + γ' ∂b/∂u by forward differences
        // of g = M_r a + b + Φ_qᵀ λ.
        let mut g0 = vec![0.0; n_r];
        model.rigid_residual(t, &w.q_full, q_r, u_r, a_r, lambda, &mut w.rs, &mut g0);
        let mass = w.rs.mass.clone();
        let mut g1 = vec![0.0; n_r];
        let mut b0 = vec![0.0; n_r];
        let mut b1 = vec![0.0; n_r];
        model.rigid.bias(t, q_r, u_r, &mut b0);
        let mut qp = q_r.to_vec();
        let mut up = u_r.to_vec();
        for j in 0..n_r {
            let mut col = vec![0.0; n_r];
            if bp != 0.0 {
                let e = 1e-7 * (1.0 + q_r[j].abs());
                qp[j] = q_r[j] + e;
                model.rigid_residual(t, &w.q_full, &qp, u_r, a_r, lambda, &mut w.rs, &mut g1);
                qp[j] = q_r[j];
                for i in 0..n_r {
                    col[i] += bp * (g1[i] - g0[i]) / e;
                }
            }
            if gp != 0.0 {
                let e = 1e-7 * (1.0 + u_r[j].abs());
                up[j] = u_r[j] + e;
                model.rigid.bias(t, q_r, &up, &mut b1);
                up[j] = u_r[j];
                for i in 0..n_r {
                    col[i] += gp * (b1[i] - b0[i]) / e;
                }
            }
            for i in 0..n_r {
                let v = mass[i * n_r + j] + col[i];
                if let Some(s) = model.pattern.slot(n_s + i, n_s + j) {
                    w.matrix.values[s] += v;
                }
            }
        }
        // Constraint rows and columns, and the clamps' coupling.
        let mut c = std::mem::take(&mut w.rs.c);
        model.constraints(t, &w.q_full, q_r, &mut w.rs.mounts, &mut c);
        for &(row, col, val) in &c.jac {
            for (i, j) in [(n + row, col), (col, n + row)] {
                if let Some(s) = model.pattern.slot(i, j) {
                    w.matrix.values[s] += val;
                }
            }
        }
        if bp != 0.0 {
            for &(row, gi, qj, d) in &c.cross {
                let v = bp * lambda[row] * d;
                for (i, j) in [(gi, qj), (qj, gi)] {
                    if let Some(s) = model.pattern.slot(i, j) {
                        w.matrix.values[s] += v;
                    }
                }
            }
        }
        w.rs.c = c;
        w.lu.factor(&w.matrix)
            .map_err(|reason| DynamicsError::Singular { t, reason })?;
        Ok(())
    }
}
