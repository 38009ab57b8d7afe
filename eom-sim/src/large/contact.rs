//! Contacts at the nodes of cables (issue #26) on the vector runtime: a
//! cable node (a point, or a sphere about it) against a plane fixed in the
//! world — the gap is linear in the node's position coordinates,
//! `g = n·x_j − n·p − r`, so its row `w = ∂g/∂y` is constant and exact —
//! or a sphere about a node against a sphere fixed in the world or about
//! another node ([`NodeSphere`]: `g = ‖x_a − x_b‖ − r`, its row `±n`
//! evaluated at every state).
//!
//! The run is the one contact run of `crate::run::contact`, written over
//! the vector state: the same [`ContactEvent`]s, the same impact map
//! (`impact`, the generalised Newton law on all closed rows with its
//! exact LCP, `M` the structure's constant mass matrix) and the same
//! sustained unilateral constraints with `λ ≥ 0` (the force problem solved
//! by [`lcp`], or with friction by the rigid runtime's [`Problem`]).
//! Between events generalized-α integrates the structure with the
//! sustained rows as index-3 constraints ([`Held`]: `g = 0` appended to
//! the model's own constraint rows). After every accepted step the gaps of
//! the open rows and the forces of the sustained ones are checked; the
//! first to cross zero is located on the step's cubic Hermite interpolant
//! (positions and speeds at both ends: the gap's own cubic) or, for a
//! force, linearly between the step's ends; the run restarts there with
//! consistent accelerations.
//!
//! **Coulomb friction** (`mu > 0`): the plane's tangent axes `t1`, `t2`
//! applied to the node's position coordinates are the tangential rows
//! `W_t`, constant and exact like the normal one. An impact is the rigid
//! runtime's Newton–Coulomb law (`impact` with every rough row starting to
//! stick: `v_t⁺ = 0` if `‖Λ_t‖ ≤ μ Λ`, else `Λ_t = −μ Λ v̂_t⁺`); a
//! sustained row is a [`Slide`]: sticking, its tangential position held
//! as two more index-3 rows `t_a·y = c_a` (friction `λ_t` their
//! multipliers), or sliding, `λ_t = −μ λ s` in its force column. The
//! transitions are events as in the rigid runtime: a slide stops (`v_t·s`
//! falling through 0, located linearly between the step's ends; **stick**,
//! a tangential impulse takes the speed left), a stick breaks
//! (`μ λ − ‖λ_t‖` falling through 0, refined on the retaken steps'
//! multipliers to a part in 10⁹; **slip**), a force falls through 0
//! (**release**).
//!
//! **Cables hung at rigid bodies** (a [`super::mixed::MixedModel`]): the
//! same run over `y = (x, q_r)`, the model giving through [`Impacts`] its
//! mass `diag(M_s, M_r(q_r))`, the Jacobian `J` of its attachments and
//! loops, and its free accelerations with those constraints held. Every
//! impulse problem holds them at the speed level (`J Δu = 0`, the rigid
//! runtime's loop rows), after the speeds have been brought onto them
//! (`J u + Φ_t = 0`: the index-3 integrator leaves them off by its drift,
//! and the constraints would otherwise work in the impulse); an event
//! state from the step's interpolant is first brought onto `Φ = 0`.
//!
//! **The rigid part's own contacts** (joint limits, markers and spheres
//! against planes, spheres: [`Impacts::body_rows`], from the generated
//! `contacts` and, with friction, `friction`) come after the node rows in
//! the same run. Their rows are not constant: they are evaluated at each
//! state (gaps, speeds, `γ` of `g̈ = wᵀ a − γ`, and the tangential `v_t`,
//! `γ_t`, `W_t`), and while one is held [`Held`] re-evaluates its `g` and
//! `w` at every Newton iterate (the change of `w` with `y` times the force
//! left out of the matrix). A sliding one has `w − μ sᵀ W_t` in its force
//! column; a sticking one holds its tangential rows step by step,
//! `W_t(ȳ)·(y − y_n) = 0` at the midpoint `ȳ` of the step from `y_n`
//! (they need not be the gradient of a position: a rolling or pivoting
//! contact point). A
//! closing gap is located as a node's: its value on the step's cubic
//! Hermite interpolant of the state, then on the retaken steps.
//!
//! Not here: a sliding row's direction is not differentiated in
//! generalized-α's Newton matrix (exact for a slide along a fixed
//! direction, a quasi-Newton one for a curving slide).

use super::alpha::{AlphaModel, GeneralizedAlpha};
use super::run::{AlphaOptions, DynamicsError, DynamicsStats, State};
use crate::constrained::{DMatrix, DVector};
use crate::run::contact::Rows;
use crate::run::impulse::{
    Slide, Solved, effective_inverse, impact, norm2, onto_constraints, resting_forces,
};
use crate::run::{ContactEvent, ContactEventKind, ContactImpulse, GAP_TOL, MAX_LCP, lcp};
use nalgebra::Dyn;
use nalgebra::linalg::LU;
use std::cell::OnceCell;

/// A contact of one cable node against a plane fixed in the world, over
/// the structure's full coordinates: `g = Σ c_i y_i − level`.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeContact {
    /// The contact's name (its row in the events).
    pub name: String,
    /// `(full structural index, coefficient)`: the node's position
    /// coordinates and the plane's unit normal.
    pub row: Vec<(usize, f64)>,
    /// `n·p + r`: the plane's offset and the sphere's radius, m.
    pub level: f64,
    /// Newton's coefficient of restitution, `0 ≤ e ≤ 1`.
    pub e: f64,
    /// Coulomb's friction coefficient, `μ ≥ 0` (0: frictionless).
    pub mu: f64,
    /// The rows of the plane's tangent axes `t1`, `t2` on the node's
    /// position coordinates, as `row` (an empty row: no coordinate along
    /// that axis, as `t2 = z` of a planar cable).
    pub tangents: [Vec<(usize, f64)>; 2],
    /// A sphere about the node against a sphere fixed in the world or
    /// about another node (`Spheres`); `None` for a plane (`row`, `level`
    /// and `tangents`, which a sphere leaves empty).
    pub sphere: Option<NodeSphere>,
    /// The node (or a sphere about it) against a plane or sphere on a
    /// rigid body; `row`, `level` and `tangents` are then empty and
    /// `sphere` is `None`.
    pub body: Option<NodeOnBody>,
}

/// A cable node against a body's plane or sphere: the body's frame at the
/// plane's point (the sphere's centre) comes from the rigid part's
/// generated `contact_frames` at every state ([`Frame`]), and the rows are
/// evaluated from it: with `d = x − p` (the node from the frame's point),
/// the relative speed `s = ẋ − ṗ − ω × d`,
/// - a plane, normal `n = E n_b` (turning with the body): `g = n·d − r_a`;
/// - a sphere: `n = d/‖d‖`, `g = ‖d‖ − r_a − r_b`;
///
/// `ġ = n·s`, the row `w = n` on the node's coordinates and
/// `−J_pᵀ n − J_ωᵀ (d × n)` on the rigid part's, and
/// `γ = −ṅ·s + n·(a₀ + α₀ × d + ω × ḋ)` (`a₀`, `α₀` the frame's
/// accelerations at `u̇ = 0`). With friction the tangential speeds are of
/// the node's touching point against the body's material point there
/// (`x − r_a n` on the plane, `p + r_b n` on the sphere).
#[derive(Clone, Debug, PartialEq)]
pub struct NodeOnBody {
    /// The node's position coordinates, one per axis (2 for a planar
    /// cable, 3), as full structural indices.
    pub a: Vec<usize>,
    /// The frame's index in the rigid part's `contact_frames`.
    pub frame: usize,
    /// A plane's unit normal and tangent axes `t1`, `t2` in the body's
    /// axes; `None`: a sphere about the frame's point.
    pub plane: Option<[[f64; 3]; 3]>,
    /// The radius of the sphere about the node, m.
    pub radius_a: f64,
    /// The body's sphere's radius, m (0 for a plane).
    pub radius_b: f64,
    /// A sphere's reference axis for its tangent axes (world axes), as
    /// for rigid spheres: `t1 = (a − (a·n) n)/‖…‖`, `t2 = n × t1`.
    pub reference: [f64; 3],
}

/// A rigid body's frame at a state (one block of the generated
/// `contact_frames`, world axes), its rows on a model's free coordinates:
/// the point `p`, the body's axes `e` (by rows), `ṗ`, `ω`, their
/// accelerations at `u̇ = 0` `a₀`, `α₀`, and per rigid speed `k` the
/// columns `∂ṗ/∂u_k`, `∂ω/∂u_k` (the rigid speeds from free index
/// `offset`).
#[derive(Clone, Debug)]
pub(super) struct Frame {
    p: [f64; 3],
    e: [[f64; 3]; 3],
    v: [f64; 3],
    w: [f64; 3],
    a0: [f64; 3],
    al0: [f64; 3],
    jp: Vec<[f64; 3]>,
    jw: Vec<[f64; 3]>,
    offset: usize,
}

impl Frame {
    /// The number of values of one frame of `contact_frames` for a rigid
    /// part of `nr` speeds.
    pub(super) fn len(nr: usize) -> usize {
        24 + 6 * nr
    }

    /// The frames of a flat `contact_frames` result (`nr` rigid speeds,
    /// the first at free index `offset`).
    pub(super) fn parse(out: &[f64], nr: usize, offset: usize) -> Vec<Frame> {
        out.chunks(Self::len(nr))
            .map(|b| {
                let v3 = |i: usize| [b[i], b[i + 1], b[i + 2]];
                let col = |r: usize, k: usize| [0, 1, 2].map(|i| b[24 + (r + i) * nr + k]);
                Frame {
                    p: v3(0),
                    e: [v3(3), v3(6), v3(9)],
                    v: v3(12),
                    w: v3(15),
                    a0: v3(18),
                    al0: v3(21),
                    jp: (0..nr).map(|k| col(0, k)).collect(),
                    jw: (0..nr).map(|k| col(3, k)).collect(),
                    offset,
                }
            })
            .collect()
    }

    /// `v` in the body's axes, in world axes.
    fn turn(&self, v: [f64; 3]) -> [f64; 3] {
        self.e.map(|row| dot3(row, v))
    }

    /// Adds `−(∂ṗ/∂u)ᵀ dir − (∂ω/∂u)ᵀ (arm × dir)` to row `row` of `m`:
    /// the row of `dir·(ṗ + ω × arm)` with its sign turned.
    fn put(&self, m: &mut DMatrix<f64>, row: usize, dir: [f64; 3], arm: [f64; 3]) {
        let moment = cross3(arm, dir);
        for (k, (jp, jw)) in self.jp.iter().zip(&self.jw).enumerate() {
            m[(row, self.offset + k)] -= dot3(*jp, dir) + dot3(*jw, moment);
        }
    }
}

/// The sphere of a [`NodeContact`]: `g = ‖x_a − x_b‖ − radius` with
/// `x_a` the node's position and `x_b` another node's or a fixed centre,
/// normal `n = (x_a − x_b)/‖x_a − x_b‖` (from `b` to `a`). Not constant:
/// the run evaluates its rows at every state (`w = ±n` on the two nodes'
/// coordinates, `γ = −ṅ·(ẋ_a − ẋ_b)`), as a rigid body's.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeSphere {
    /// The node's position coordinates, one per axis (2 for a planar
    /// cable, 3), as full structural indices.
    pub a: Vec<usize>,
    /// The other node's, the same way; empty: a sphere fixed in the world
    /// at `centre`.
    pub b: Vec<usize>,
    /// The fixed sphere's centre, world axes, m (with `b` empty).
    pub centre: [f64; 3],
    /// The sum of both radii, m.
    pub radius: f64,
    /// The world axis the friction's tangent axes are taken from in
    /// space, `t1 = (a − (a·n) n)/‖a − (a·n) n‖`, `t2 = n × t1` (the axis
    /// least aligned with the line of centres at the start, as for rigid
    /// spheres); `None` where both centres stay in the x–y plane (planar
    /// cables), whose `t1 = n × z` turns in that plane (`t2 = z` has no
    /// coordinate).
    pub reference: Option<[f64; 3]>,
}

/// A [`NodeSphere`] on a model's free coordinates: per axis the free index
/// of the coordinate, or its fixed value.
#[derive(Clone, Debug)]
struct SphereRow {
    a: Vec<(Option<usize>, f64)>,
    b: Vec<(Option<usize>, f64)>,
    centre: [f64; 3],
    radius: f64,
    reference: Option<[f64; 3]>,
}

impl SphereRow {
    /// Position and speed of a centre given by `coords`.
    fn centre_of(coords: &[(Option<usize>, f64)], y: &[f64], v: &[f64]) -> ([f64; 3], [f64; 3]) {
        let (mut x, mut xd) = ([0.0; 3], [0.0; 3]);
        for (k, &(free, fixed)) in coords.iter().enumerate().take(3) {
            match free {
                Some(i) => {
                    x[k] = y[i];
                    xd[k] = v[i];
                }
                None => x[k] = fixed,
            }
        }
        (x, xd)
    }

    /// Row `j` of `r` (and its tangential rows `2j`, `2j + 1`) at `(y, v)`:
    /// `g`, `ġ = n·v_rel`, `γ = −ṅ·v_rel`, `w = ±n`, and with friction
    /// `v_t = t·v_rel`, `γ_t = −ṫ·v_rel`, `W_t = ±t`. `false` if the
    /// centres coincide (no normal).
    fn fill(&self, y: &[f64], v: &[f64], rough: bool, j: usize, r: &mut Rows) -> bool {
        let (xa, va) = Self::centre_of(&self.a, y, v);
        let (xb, vb) = if self.b.is_empty() {
            (self.centre, [0.0; 3])
        } else {
            Self::centre_of(&self.b, y, v)
        };
        let d: [f64; 3] = std::array::from_fn(|k| xa[k] - xb[k]);
        let vr: [f64; 3] = std::array::from_fn(|k| va[k] - vb[k]);
        let dist = dot3(d, d).sqrt();
        if dist.is_nan() || dist <= 0.0 {
            return false;
        }
        let n = d.map(|x| x / dist);
        let nv = dot3(n, vr);
        let ndot: [f64; 3] = std::array::from_fn(|k| (vr[k] - n[k] * nv) / dist);
        r.g[j] = dist - self.radius;
        r.gdot[j] = nv;
        r.gamma[j] = -dot3(ndot, vr);
        let put = |m: &mut DMatrix<f64>, row: usize, dir: [f64; 3]| {
            for (k, &(free, _)) in self.a.iter().enumerate() {
                if let Some(i) = free {
                    m[(row, i)] += dir[k];
                }
            }
            for (k, &(free, _)) in self.b.iter().enumerate() {
                if let Some(i) = free {
                    m[(row, i)] -= dir[k];
                }
            }
        };
        put(&mut r.w, j, n);
        if rough {
            let (t, tdot) = self.tangents(n, ndot);
            for a in 0..2 {
                r.vt[j][a] = dot3(t[a], vr);
                r.gamma_t[j][a] = -dot3(tdot[a], vr);
                put(&mut r.wt, 2 * j + a, t[a]);
            }
        }
        true
    }

    /// The tangent axes at normal `n` turning at `ṅ`, and their rates.
    fn tangents(&self, n: [f64; 3], ndot: [f64; 3]) -> ([[f64; 3]; 2], [[f64; 3]; 2]) {
        let Some(a) = self.reference else {
            // Planar: `t1 = n × z` in the plane, `t2 = −z`, as a node's
            // plane has them.
            let t1 = [n[1], -n[0], 0.0];
            let t1d = [ndot[1], -ndot[0], 0.0];
            return ([t1, [0.0, 0.0, -1.0]], [t1d, [0.0; 3]]);
        };
        sphere_axes(a, n, ndot)
    }
}

/// A [`NodeOnBody`] on a model's free coordinates (the node's coordinates
/// free or fixed, as [`SphereRow`]'s).
#[derive(Clone, Debug)]
struct BodyRow {
    a: Vec<(Option<usize>, f64)>,
    frame: usize,
    plane: Option<[[f64; 3]; 3]>,
    radius_a: f64,
    radius_b: f64,
    reference: [f64; 3],
}

impl BodyRow {
    /// Row `j` of `r` (and its tangential rows `2j`, `2j + 1`) at
    /// `(y, v)` with the body's frame `f` at that state (see
    /// [`NodeOnBody`]); `false` if a sphere's centres coincide.
    fn fill(&self, f: &Frame, y: &[f64], v: &[f64], rough: bool, j: usize, r: &mut Rows) -> bool {
        let (x, xv) = SphereRow::centre_of(&self.a, y, v);
        let d: [f64; 3] = std::array::from_fn(|k| x[k] - f.p[k]);
        let dd: [f64; 3] = std::array::from_fn(|k| xv[k] - f.v[k]);
        let (n, ndot, g) = match &self.plane {
            Some([nb, ..]) => {
                let n = f.turn(*nb);
                (n, cross3(f.w, n), dot3(n, d) - self.radius_a)
            }
            None => {
                let dist = dot3(d, d).sqrt();
                if dist.is_nan() || dist <= 0.0 {
                    return false;
                }
                let n = d.map(|x| x / dist);
                let nd = dot3(n, dd);
                let ndot = std::array::from_fn(|k| (dd[k] - n[k] * nd) / dist);
                (n, ndot, dist - self.radius_a - self.radius_b)
            }
        };
        // The speed of the node against the body's material point at
        // `p + arm`, and (`arm` turning at `arm_dot`) the acceleration term
        // of `dir·(that speed)` at `u̇ = 0`, `dir` turning at `dir_dot`.
        let against = |arm: [f64; 3]| -> [f64; 3] {
            let wa = cross3(f.w, arm);
            std::array::from_fn(|k| dd[k] - wa[k])
        };
        let gamma = |dir: [f64; 3], dir_dot: [f64; 3], arm: [f64; 3], arm_dot: [f64; 3]| {
            let (aa, wa) = (cross3(f.al0, arm), cross3(f.w, arm_dot));
            let rate: [f64; 3] = std::array::from_fn(|k| f.a0[k] + aa[k] + wa[k]);
            -dot3(dir_dot, against(arm)) + dot3(dir, rate)
        };
        let node = |m: &mut DMatrix<f64>, row: usize, dir: [f64; 3]| {
            for (k, &(free, _)) in self.a.iter().enumerate() {
                if let Some(i) = free {
                    m[(row, i)] += dir[k];
                }
            }
        };
        r.g[j] = g;
        r.gdot[j] = dot3(n, against(d));
        r.gamma[j] = gamma(n, ndot, d, dd);
        node(&mut r.w, j, n);
        f.put(&mut r.w, j, n, d);
        if rough {
            // The touching point's arm from `p` and its rate; the axes.
            let (arm, arm_dot, t, tdot) = match &self.plane {
                Some([_, t1, t2]) => {
                    let t = [f.turn(*t1), f.turn(*t2)];
                    (
                        std::array::from_fn(|k| d[k] - self.radius_a * n[k]),
                        std::array::from_fn(|k| dd[k] - self.radius_a * ndot[k]),
                        t,
                        t.map(|t| cross3(f.w, t)),
                    )
                }
                None => {
                    let (t, tdot) = sphere_axes(self.reference, n, ndot);
                    (
                        n.map(|x| self.radius_b * x),
                        ndot.map(|x| self.radius_b * x),
                        t,
                        tdot,
                    )
                }
            };
            for a in 0..2 {
                r.vt[j][a] = dot3(t[a], against(arm));
                r.gamma_t[j][a] = gamma(t[a], tdot[a], arm, arm_dot);
                node(&mut r.wt, 2 * j + a, t[a]);
                f.put(&mut r.wt, 2 * j + a, t[a], arm);
            }
        }
        true
    }
}

/// The tangent axes of two spheres touching along the unit normal `n`
/// turning at `ṅ`, from the world axis `a` (`t1 = (a − (a·n) n)/‖…‖`,
/// `t2 = n × t1`), and their rates.
fn sphere_axes(a: [f64; 3], n: [f64; 3], ndot: [f64; 3]) -> ([[f64; 3]; 2], [[f64; 3]; 2]) {
    let an = dot3(a, n);
    let u: [f64; 3] = std::array::from_fn(|k| a[k] - an * n[k]);
    let len = dot3(u, u).sqrt();
    let t1 = u.map(|x| x / len);
    let and = dot3(a, ndot);
    let ud: [f64; 3] = std::array::from_fn(|k| -and * n[k] - an * ndot[k]);
    let along = dot3(t1, ud);
    let t1d: [f64; 3] = std::array::from_fn(|k| (ud[k] - t1[k] * along) / len);
    let t2 = cross3(n, t1);
    let t2d: [f64; 3] = std::array::from_fn(|k| cross3(ndot, t1)[k] + cross3(n, t1d)[k]);
    ([t1, t2], [t1d, t2d])
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The contacts' rows on a model's free coordinates (`y`, the structure's
/// free coordinates first): the cable nodes' planes first, constant,
/// fixed coordinates folded into the level; then the rows evaluated at
/// each state (their `row`, `level` and `tangents` here are empty): the
/// nodes' spheres, then the model's own contacts (a mixed model's rigid
/// part's, [`Impacts::body_rows`]).
#[derive(Clone, Debug)]
pub(super) struct Gaps {
    pub names: Vec<String>,
    pub rows: Vec<Vec<(usize, f64)>>,
    pub level: Vec<f64>,
    pub e: Vec<f64>,
    pub mu: Vec<f64>,
    pub tangents: Vec<[Vec<(usize, f64)>; 2]>,
    /// The number of constant rows (the nodes' planes, the first ones).
    nodes: usize,
    /// The nodes' spheres and their contacts with bodies (the rows after
    /// the planes, in the contacts' order).
    spheres: Vec<NodeRow>,
}

/// A node's row evaluated at every state.
#[derive(Clone, Debug)]
enum NodeRow {
    /// Against a fixed sphere or another node's.
    Sphere(SphereRow),
    /// Against a body's plane or sphere.
    Body(BodyRow),
}

impl Gaps {
    /// `free_index` maps a full structural index to its free one (`None`:
    /// fixed at `q0_full`).
    pub fn new(
        contacts: &[NodeContact],
        free_index: impl Fn(usize) -> Option<usize>,
        q0_full: &[f64],
    ) -> Gaps {
        let planes = contacts
            .iter()
            .filter(|c| c.sphere.is_none() && c.body.is_none());
        let mut g = Gaps {
            names: Vec::new(),
            rows: Vec::new(),
            level: Vec::new(),
            e: Vec::new(),
            mu: Vec::new(),
            tangents: Vec::new(),
            nodes: planes.clone().count(),
            spheres: Vec::new(),
        };
        for c in planes {
            let mut row = Vec::new();
            let mut level = c.level;
            for &(i, a) in &c.row {
                match free_index(i) {
                    Some(k) => row.push((k, a)),
                    None => level -= a * q0_full.get(i).copied().unwrap_or(0.0),
                }
            }
            g.names.push(c.name.clone());
            g.rows.push(row);
            g.level.push(level);
            g.e.push(c.e);
            g.mu.push(c.mu);
            // A tangential row's fixed coordinates move neither the speed
            // nor (held from where a stick starts) the anchored position.
            g.tangents.push(c.tangents.clone().map(|t| {
                t.iter()
                    .filter_map(|&(i, a)| Some((free_index(i)?, a)))
                    .collect()
            }));
        }
        let coords = |idx: &[usize]| -> Vec<(Option<usize>, f64)> {
            idx.iter()
                .map(|&i| (free_index(i), q0_full.get(i).copied().unwrap_or(0.0)))
                .collect()
        };
        for c in contacts {
            let row = match (&c.sphere, &c.body) {
                (Some(sp), _) => NodeRow::Sphere(SphereRow {
                    a: coords(&sp.a),
                    b: coords(&sp.b),
                    centre: sp.centre,
                    radius: sp.radius,
                    reference: sp.reference,
                }),
                (None, Some(b)) => NodeRow::Body(BodyRow {
                    a: coords(&b.a),
                    frame: b.frame,
                    plane: b.plane,
                    radius_a: b.radius_a,
                    radius_b: b.radius_b,
                    reference: b.reference,
                }),
                (None, None) => continue,
            };
            g.names.push(c.name.clone());
            g.rows.push(Vec::new());
            g.level.push(0.0);
            g.e.push(c.e);
            g.mu.push(c.mu);
            g.tangents.push([Vec::new(), Vec::new()]);
            g.spheres.push(row);
        }
        g
    }

    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// The same with the model's own contacts `names` after the node rows
    /// ([`Impacts::body_rows`]), their `e` and `μ` from their rows at `s`.
    pub fn with_bodies<M: Impacts + ?Sized>(
        mut self,
        m: &M,
        names: &[String],
        s: &State,
    ) -> Result<Gaps, String> {
        if names.is_empty() {
            return Ok(self);
        }
        let r = m
            .body_rows(s.t, &s.q, &s.v)
            .filter(|r| r.g.len() == names.len())
            .ok_or("the rigid part's contacts cannot be evaluated at the start")?;
        for (b, name) in names.iter().enumerate() {
            self.names.push(name.clone());
            self.rows.push(Vec::new());
            self.level.push(0.0);
            self.e.push(r.e[b]);
            self.mu.push(r.mu[b]);
            self.tangents.push([Vec::new(), Vec::new()]);
        }
        Ok(self)
    }

    /// Row `i` is a node's plane (constant, on `rows`).
    fn node(&self, i: usize) -> bool {
        i < self.nodes
    }

    /// The rows evaluated per state at `(t, y, v)` (the nodes' spheres,
    /// then the model's own contacts), row `k` of the result being row
    /// `nodes + k`; `None` if there are none, `Some(None)` if they cannot
    /// be evaluated.
    fn evaluated<M: Impacts + ?Sized>(
        &self,
        m: &M,
        t: f64,
        y: &[f64],
        v: &[f64],
    ) -> Option<Option<Rows>> {
        let k = self.len() - self.nodes;
        if k == 0 {
            return None;
        }
        let (ns, n) = (self.spheres.len(), v.len());
        if ns == 0 {
            // The model's own rows alone: as it gives them.
            return Some(m.body_rows(t, y, v));
        }
        let mut r = Rows {
            g: vec![0.0; k],
            gdot: vec![0.0; k],
            gamma: vec![0.0; k],
            e: self.e[self.nodes..].to_vec(),
            mu: self.mu[self.nodes..].to_vec(),
            w: DMatrix::zeros(k, n),
            vt: vec![[0.0; 2]; k],
            gamma_t: vec![[0.0; 2]; k],
            wt: DMatrix::zeros(2 * k, n),
        };
        // The bodies' frames, where a node touches a body.
        let on_bodies = self.spheres.iter().any(|x| matches!(x, NodeRow::Body(_)));
        let frames = match on_bodies {
            true => match m.body_frames(t, y, v) {
                Some(f) => f,
                None => return Some(None),
            },
            false => Vec::new(),
        };
        for (j, sp) in self.spheres.iter().enumerate() {
            let rough = self.rough(self.nodes + j);
            let done = match sp {
                NodeRow::Sphere(x) => x.fill(y, v, rough, j, &mut r),
                NodeRow::Body(x) => frames
                    .get(x.frame)
                    .is_some_and(|f| x.fill(f, y, v, rough, j, &mut r)),
            };
            if !done {
                return Some(None);
            }
        }
        if k > ns {
            let Some(b) = m.body_rows(t, y, v) else {
                return Some(None);
            };
            for (x, j) in (ns..k).enumerate() {
                copy_row(&mut r, j, &b, x);
            }
        }
        Some(Some(r))
    }

    /// The gap of row `i` at `s` (NaN if it cannot be evaluated).
    fn gap_at<M: Impacts + ?Sized>(&self, m: &M, i: usize, s: &State) -> f64 {
        if self.node(i) {
            return self.gap(i, &s.q);
        }
        self.evaluated(m, s.t, &s.q, &s.v)
            .flatten()
            .map_or(f64::NAN, |r| r.g[i - self.nodes])
    }

    /// The gaps of all rows at `s` (the model's own NaN if they cannot be
    /// evaluated).
    pub fn gaps_at<M: Impacts + ?Sized>(&self, m: &M, s: &State) -> Vec<f64> {
        let mut g: Vec<f64> = (0..self.len()).map(|i| self.gap(i, &s.q)).collect();
        if let Some(b) = self.evaluated(m, s.t, &s.q, &s.v) {
            for (k, x) in g[self.nodes..].iter_mut().enumerate() {
                *x = b.as_ref().map_or(f64::NAN, |r| r.g[k]);
            }
        }
        g
    }

    /// The normal speed `ġ` of row `i` at `s` (NaN if it cannot be
    /// evaluated).
    fn speed_at<M: Impacts + ?Sized>(&self, m: &M, i: usize, s: &State) -> f64 {
        if self.node(i) {
            return self.dot(i, &s.v);
        }
        self.evaluated(m, s.t, &s.q, &s.v)
            .flatten()
            .map_or(f64::NAN, |r| r.gdot[i - self.nodes])
    }

    fn dot(&self, i: usize, x: &[f64]) -> f64 {
        self.rows[i].iter().map(|&(k, a)| a * x[k]).sum()
    }

    /// Row `i`'s tangent axis `a` dotted with `x`.
    fn tdot(&self, i: usize, a: usize, x: &[f64]) -> f64 {
        self.tangents[i][a].iter().map(|&(k, c)| c * x[k]).sum()
    }

    /// Row `i`'s tangential speeds at speeds `v`.
    fn vt(&self, i: usize, v: &[f64]) -> [f64; 2] {
        [0, 1].map(|a| self.tdot(i, a, v))
    }

    /// Row `i` has Coulomb friction.
    fn rough(&self, i: usize) -> bool {
        self.mu[i] > 0.0
    }

    /// The gap of row `i` at coordinates `y`.
    pub fn gap(&self, i: usize, y: &[f64]) -> f64 {
        self.dot(i, y) - self.level[i]
    }

    /// The contact rows at `s` in the runtime's [`Rows`] (a node's
    /// `γ = γ_t = 0`: its normal and tangential rows are constant; the
    /// model's own from [`Impacts::body_rows`]).
    fn at<M: Impacts + ?Sized>(&self, m: &M, s: &State) -> Result<Rows, DynamicsError> {
        let (nk, n) = (self.len(), s.v.len());
        let mut w = DMatrix::zeros(nk, n);
        let mut wt = DMatrix::zeros(2 * nk, n);
        for i in 0..self.nodes {
            for &(k, a) in &self.rows[i] {
                w[(i, k)] += a;
            }
            for a in 0..2 {
                for &(k, c) in &self.tangents[i][a] {
                    wt[(2 * i + a, k)] += c;
                }
            }
        }
        let mut r = Rows {
            g: (0..nk).map(|i| self.gap(i, &s.q)).collect(),
            gdot: (0..nk).map(|i| self.dot(i, &s.v)).collect(),
            gamma: vec![0.0; nk],
            e: self.e.clone(),
            mu: self.mu.clone(),
            w,
            vt: (0..nk).map(|i| self.vt(i, &s.v)).collect(),
            gamma_t: vec![[0.0; 2]; nk],
            wt,
        };
        if let Some(b) = self.evaluated(m, s.t, &s.q, &s.v) {
            let b = b.ok_or_else(|| failed(s.t, UNEVALUATED.into()))?;
            for (k, i) in (self.nodes..nk).enumerate() {
                copy_row(&mut r, i, &b, k);
            }
        }
        Ok(r)
    }
}

/// Copies row `k` of `from` (normal and tangential, with `e` and `μ`)
/// into row `i` of `to` (both on the same speeds).
fn copy_row(to: &mut Rows, i: usize, from: &Rows, k: usize) {
    to.g[i] = from.g[k];
    to.gdot[i] = from.gdot[k];
    to.gamma[i] = from.gamma[k];
    to.e[i] = from.e[k];
    to.mu[i] = from.mu[k];
    to.w.row_mut(i).copy_from(&from.w.row(k));
    to.vt[i] = from.vt[k];
    to.gamma_t[i] = from.gamma_t[k];
    for a in 0..2 {
        to.wt.row_mut(2 * i + a).copy_from(&from.wt.row(2 * k + a));
    }
}

/// The sliding direction at tangential speeds `vt` of a slide that
/// started along `s0`: `v̂_t` while `v_t · s0 > 0`, else `s0` (as the
/// rigid runtime).
fn direction(vt: [f64; 2], s0: [f64; 2]) -> [f64; 2] {
    let nv = norm2(vt);
    if nv > 0.0 && vt[0] * s0[0] + vt[1] * s0[1] > 0.0 {
        [vt[0] / nv, vt[1] / nv]
    } else {
        s0
    }
}

/// One held row of [`Held`]: a sustained contact's normal row `g = 0`,
/// or a sticking one's tangent axis `a`: a node's held at its anchor
/// `t_a·y = c`; the rows evaluated per state (a node's sphere, the model's
/// own contacts), whose tangential rows `W_t,a(y)` need not be the
/// gradient of any position (a rolling or pivoting contact point), held
/// step by step, `W_t,a(ȳ)·(y − y_n) = 0` with `ȳ = (y + y_n)/2` the
/// step's midpoint (the tangential displacement over each step zero to
/// third order: for a row that is a gradient `∇φ`, `φ(y) − φ(y_n)` to
/// `O(‖y − y_n‖³)`; for a constant row the anchor's own condition). The
/// row at the step's end instead, `W_t(y)`, errs by `½ Δyᵀ H Δy`, which
/// makes the held tangential acceleration `2 γ_t` where it is `γ_t`: a
/// box pivoting on its sticking corner gained energy and left its cone
/// at once.
#[derive(Clone, Copy, Debug)]
enum Hold {
    Normal(usize),
    Tangent(usize, usize, f64),
}

/// Which of the model's own contacts' rows a hold is: the normal row `b`
/// or the tangential row `j = 2b + a` (of `Rows::wt`).
#[derive(Clone, Copy, Debug)]
enum Own {
    Normal(usize),
    Tangent(usize),
}

/// A vector model with the sustained contact rows `active` held as
/// index-3 constraints `g = 0` after its own rows: multipliers `μ`, the
/// normal force of a row `λ = −μ` (the residual's `+wᵀ μ`). A sticking
/// row (Coulomb friction, [`Slide::Stick`]) holds its tangential position
/// too, `t_a·y = c_a` from where the stick started (friction force
/// `λ_t,a = −μ_a`); a sliding one ([`Slide::Slip`]) has its friction
/// `λ_t = −μ λ s` in its column, `w − μ sᵀ W_t` (`s` the sliding
/// direction at the iterate's speeds, not differentiated). The iteration
/// matrix is the model's, bordered by the rows and solved by their Schur
/// complement `S = C A⁻¹ D` (a few rows; `A` the model's factored matrix,
/// `C` the held rows, `D` their force columns).
pub(super) struct Held<'m, M: ?Sized> {
    pub inner: &'m M,
    gaps: &'m Gaps,
    /// The active rows' normal holds first, then the sticking rows'
    /// tangential ones.
    holds: Vec<Hold>,
    active: Vec<usize>,
    /// Per contact row (all of them).
    slides: Vec<Option<Slide>>,
}

/// [`Held`]'s scratch: the model's, and the bordered solve's `A⁻¹ D`
/// columns with the factored `S` (and the model's own contact rows `C`
/// it was built with, if it has any).
pub(super) struct HeldWork<W> {
    inner: W,
    x: Vec<Vec<f64>>,
    s: Option<LU<f64, Dyn, Dyn>>,
    rows: Option<Rows>,
    /// The step's start `y_n` (the last accepted coordinates), from which
    /// a body's sticking tangential rows hold the displacement at zero.
    base: Vec<f64>,
    /// Per contact row, the direction a sliding row's friction opposes
    /// over the step: its `v̂_t` at the step's start (`s0` where it starts
    /// at rest, or has turned from `s0` by a right angle or more; zero for
    /// the rows not sliding). Frozen over the step's Newton iterations:
    /// taken at each iterate, a slide starting from rest (`v_t` within
    /// the iterations' corrections of zero) turned its friction from
    /// iterate to iterate, and Newton stalled (a rod spinning on a floor
    /// stopped by friction, its tip slipping again as the rod rang).
    dirs: Vec<[f64; 2]>,
}

impl<'m, M: Impacts + ?Sized> Held<'m, M> {
    /// `slides` and `anchors` per contact row (`None`: frictionless or not
    /// held), starting at `s` (where a body's sticking row's tangential
    /// rows are looked at: an axis without a coordinate, as `t2` of a
    /// planar motion, is not held).
    pub fn new(
        inner: &'m M,
        gaps: &'m Gaps,
        active: &[usize],
        slides: &[Option<Slide>],
        anchors: &[[f64; 2]],
        s: &State,
    ) -> Self {
        let mut holds: Vec<Hold> = active.iter().map(|&i| Hold::Normal(i)).collect();
        let sticks = |i: usize| slides.get(i) == Some(&Some(Slide::Stick));
        let body = active
            .iter()
            .any(|&i| sticks(i) && !gaps.node(i))
            .then(|| gaps.evaluated(inner, s.t, &s.q, &s.v).flatten())
            .flatten();
        for &i in active.iter().filter(|&&i| sticks(i)) {
            if gaps.node(i) {
                for (a, row) in gaps.tangents[i].iter().enumerate() {
                    if !row.is_empty() {
                        holds.push(Hold::Tangent(i, a, anchors[i][a]));
                    }
                }
            } else if let Some(r) = &body {
                let b = i - gaps.nodes;
                for a in 0..2 {
                    if r.wt.row(2 * b + a).amax() > 0.0 {
                        holds.push(Hold::Tangent(i, a, 0.0));
                    }
                }
            }
        }
        Held {
            inner,
            gaps,
            holds,
            active: active.to_vec(),
            slides: slides.to_vec(),
        }
    }

    /// The constant row of hold `h` (empty for the rows evaluated per
    /// state, the nodes' spheres and the model's own contacts, whose rows
    /// are `body`'s).
    fn row(&self, h: Hold) -> &[(usize, f64)] {
        match h {
            Hold::Normal(i) => &self.gaps.rows[i],
            Hold::Tangent(i, a, _) => &self.gaps.tangents[i][a],
        }
    }

    /// Hold `h`'s row among the rows evaluated per state `body` (at the
    /// iterate: the nodes' spheres, then the model's own contacts), if it
    /// is one of them.
    fn own<'b>(&self, h: Hold, body: Option<&'b Rows>) -> Option<(Own, &'b Rows)> {
        match h {
            Hold::Normal(i) if !self.gaps.node(i) => {
                Some((Own::Normal(i - self.gaps.nodes), body?))
            }
            Hold::Tangent(i, a, _) if !self.gaps.node(i) => {
                Some((Own::Tangent(2 * (i - self.gaps.nodes) + a), body?))
            }
            _ => None,
        }
    }

    /// Hold `h` is on a row evaluated per state (a node's sphere or one of
    /// the model's own contacts).
    fn on_a_body(&self, h: Hold) -> bool {
        match h {
            Hold::Normal(i) | Hold::Tangent(i, _, _) => !self.gaps.node(i),
        }
    }

    /// A hold is one of the model's own contacts.
    fn holds_a_body(&self) -> bool {
        self.holds.iter().any(|&h| self.on_a_body(h))
    }

    /// The rows evaluated per state at the midpoint of the step from
    /// `base` to `y` if a sticking row's tangential rows are held among
    /// them.
    fn mid_at(&self, t: f64, y: &[f64], base: &[f64], v: &[f64]) -> Option<Rows> {
        let tangent = self
            .holds
            .iter()
            .any(|&h| matches!(h, Hold::Tangent(..)) && self.on_a_body(h));
        if !tangent || base.len() != y.len() {
            return None;
        }
        let mid: Vec<f64> = y.iter().zip(base).map(|(a, b)| 0.5 * (a + b)).collect();
        self.gaps.evaluated(self.inner, t, &mid, v).flatten()
    }

    /// The rows evaluated per state (nodes' spheres, the model's own
    /// contacts) at `(t, y, v)` if a hold is one of them.
    fn body_at(&self, t: f64, y: &[f64], v: &[f64]) -> Option<Rows> {
        if self.holds_a_body() {
            self.gaps.evaluated(self.inner, t, y, v).flatten()
        } else {
            None
        }
    }

    /// Hold `h`'s residual at `y` (`body`: the rows evaluated per state at
    /// `y`; `mid`: the same at the step's midpoint, with `base` the step's
    /// start).
    fn value(
        &self,
        h: Hold,
        y: &[f64],
        body: Option<&Rows>,
        (base, mid): (&[f64], Option<&Rows>),
    ) -> f64 {
        if self.on_a_body(h) {
            return match self.own(h, body) {
                Some((Own::Normal(b), r)) => r.g[b],
                Some((Own::Tangent(_), _)) => match self.own(h, mid) {
                    Some((Own::Tangent(j), m)) => (0..y.len())
                        .map(|k| m.wt[(j, k)] * (y[k] - base.get(k).copied().unwrap_or(y[k])))
                        .sum(),
                    _ => f64::NAN,
                },
                None => f64::NAN,
            };
        }
        match h {
            Hold::Normal(i) => self.gaps.gap(i, y),
            Hold::Tangent(i, a, c) => self.gaps.tdot(i, a, y) - c,
        }
    }

    /// `C_h x`.
    fn dot(&self, h: Hold, x: &[f64], body: Option<&Rows>) -> f64 {
        match self.own(h, body) {
            Some((Own::Normal(b), r)) => (0..x.len()).map(|k| r.w[(b, k)] * x[k]).sum(),
            Some((Own::Tangent(j), r)) => (0..x.len()).map(|k| r.wt[(j, k)] * x[k]).sum(),
            None => self.row(h).iter().map(|&(k, a)| a * x[k]).sum(),
        }
    }

    /// `γ_h` of `C_h a = γ_h` (`g̈ = 0`, `v̇_t = 0`): a node's rows are
    /// constant.
    fn gamma(&self, h: Hold, body: Option<&Rows>) -> f64 {
        match self.own(h, body) {
            Some((Own::Normal(b), r)) => r.gamma[b],
            Some((Own::Tangent(j), r)) => r.gamma_t[j / 2][j % 2],
            None => 0.0,
        }
    }

    /// Adds `scale` times hold `h`'s force column to `r` (a sliding row's
    /// with its friction, `w − μ sᵀ W_t`, `s` its direction `dirs`).
    fn add_column(
        &self,
        h: Hold,
        dirs: &[[f64; 2]],
        body: Option<&Rows>,
        scale: f64,
        r: &mut [f64],
    ) {
        let slip = match h {
            Hold::Normal(i) => match self.slides.get(i) {
                Some(Some(Slide::Slip(s0))) => Some((i, dirs.get(i).copied().unwrap_or(*s0))),
                _ => None,
            },
            Hold::Tangent(..) => None,
        };
        if let Some((o, rows)) = self.own(h, body) {
            let j = match o {
                Own::Normal(b) => b,
                Own::Tangent(j) => j,
            };
            let row = match o {
                Own::Normal(_) => rows.w.row(j),
                Own::Tangent(_) => rows.wt.row(j),
            };
            for (k, x) in r.iter_mut().enumerate() {
                *x += row[k] * scale;
            }
            if let (Own::Normal(b), Some((i, s))) = (o, slip) {
                let mu = self.gaps.mu[i];
                for (a, sa) in s.iter().enumerate() {
                    for (k, x) in r.iter_mut().enumerate() {
                        *x -= mu * sa * rows.wt[(2 * b + a, k)] * scale;
                    }
                }
            }
            return;
        }
        for &(c, a) in self.row(h) {
            r[c] += a * scale;
        }
        if let Some((i, s)) = slip {
            let mu = self.gaps.mu[i];
            for (a, sa) in s.iter().enumerate() {
                for &(c, t) in &self.gaps.tangents[i][a] {
                    r[c] -= mu * sa * t * scale;
                }
            }
        }
    }

    /// The normal forces of the active rows from the multipliers.
    pub fn forces(&self, lambda: &[f64]) -> Vec<f64> {
        let mi = self.inner.n_constraints();
        (0..self.active.len()).map(|k| -lambda[mi + k]).collect()
    }

    /// Per active row, `μ λ − ‖λ_t‖` for a sticking row (its distance to
    /// the friction cone), `None` for the others.
    pub fn cone_margins(&self, lambda: &[f64]) -> Vec<Option<f64>> {
        let mi = self.inner.n_constraints();
        self.active
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                (self.slides[i] == Some(Slide::Stick)).then(|| {
                    let mut lt = [0.0; 2];
                    for (b, h) in self.holds.iter().enumerate() {
                        if let Hold::Tangent(j, a, _) = *h
                            && j == i
                        {
                            lt[a] = -lambda[mi + b];
                        }
                    }
                    self.gaps.mu[i] * (-lambda[mi + k]) - norm2(lt)
                })
            })
            .collect()
    }

    /// Per active row, `v_t · s0` at `s` for a sliding row that started
    /// along `s0` (falls through zero when the slide stops), `None` for
    /// the others (NaN: a body's row that cannot be evaluated).
    pub fn slip_speeds(&self, s: &State) -> Vec<Option<f64>> {
        let vt = self.sliding_speeds(s);
        self.active
            .iter()
            .map(|&i| match (self.slides[i], vt[i]) {
                (Some(Slide::Slip(s0)), Some(v)) => Some(v[0] * s0[0] + v[1] * s0[1]),
                _ => None,
            })
            .collect()
    }

    /// Per contact row, the tangential speeds `v_t` at `s` of a sliding
    /// row, `None` for the others (NaN: a body's row that cannot be
    /// evaluated).
    fn sliding_speeds(&self, s: &State) -> Vec<Option<[f64; 2]>> {
        let slides = |i: usize| matches!(self.slides[i], Some(Slide::Slip(_)));
        // The rows evaluated per state only where one of them slides.
        let evaluated_slides = self.active.iter().any(|&i| !self.gaps.node(i) && slides(i));
        let body = evaluated_slides
            .then(|| self.body_at(s.t, &s.q, &s.v))
            .flatten();
        let mut out = vec![None; self.gaps.len()];
        for &i in self.active.iter().filter(|&&i| slides(i)) {
            out[i] = Some(if self.gaps.node(i) {
                self.gaps.vt(i, &s.v)
            } else {
                body.as_ref()
                    .map_or([f64::NAN; 2], |r| r.vt[i - self.gaps.nodes])
            });
        }
        out
    }

    /// The friction directions of the step starting at `s` (see
    /// [`HeldWork::dirs`]).
    fn directions(&self, s: &State) -> Vec<[f64; 2]> {
        self.sliding_speeds(s)
            .into_iter()
            .enumerate()
            .map(|(i, vt)| match (self.slides[i], vt) {
                (Some(Slide::Slip(s0)), Some(v)) => direction(v, s0),
                _ => [0.0; 2],
            })
            .collect()
    }

    /// `A⁻¹ [D; 0]` and `S` at the matrix just factored, at `(t, y, v)`.
    fn border(
        &self,
        w: &mut HeldWork<M::Work>,
        t: f64,
        y: &[f64],
        v: &[f64],
    ) -> Result<(), DynamicsError> {
        let (n, mi, k) = (self.inner.n(), self.inner.n_constraints(), self.holds.len());
        w.rows = self.body_at(t, y, v);
        if w.rows.is_none() && self.holds_a_body() {
            return Err(failed(t, UNEVALUATED.into()));
        }
        let body = w.rows.as_ref();
        w.x.clear();
        for &h in &self.holds {
            let mut col = vec![0.0; n + mi];
            self.add_column(h, &w.dirs, body, 1.0, &mut col[..n]);
            self.inner.solve(&mut w.inner, &mut col);
            w.x.push(col);
        }
        let s = DMatrix::from_fn(k, k, |a, b| self.dot(self.holds[a], &w.x[b][..n], body));
        let lu = s.lu();
        if !lu.is_invertible() {
            return Err(failed(
                t,
                "the sustained contact rows are dependent (two rows on one node's coordinates along one normal?)".into(),
            ));
        }
        w.s = Some(lu);
        Ok(())
    }
}

impl<M: Impacts + ?Sized> AlphaModel for Held<'_, M> {
    type Work = HeldWork<M::Work>;

    fn n(&self) -> usize {
        self.inner.n()
    }

    fn n_constraints(&self) -> usize {
        self.inner.n_constraints() + self.holds.len()
    }

    fn work(&self, state: &State) -> Self::Work {
        HeldWork {
            inner: self.inner.work(state),
            x: Vec::new(),
            s: None,
            rows: None,
            base: state.q.clone(),
            dirs: self.directions(state),
        }
    }

    fn start(
        &self,
        w: &mut Self::Work,
        state: &State,
        acc: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let (n, mi) = (self.inner.n(), self.inner.n_constraints());
        w.base.clone_from(&state.q);
        w.dirs = self.directions(state);
        self.inner
            .start(&mut w.inner, state, acc, &mut lambda[..mi])?;
        if self.holds.is_empty() {
            return Ok(());
        }
        // The held rows' accelerations `C a = γ` (`g̈ = 0`; a node's `γ`
        // is 0, its rows constant): `[a; λ] −= A⁻¹ D μ` with
        // `S μ = C a₀ − γ`, `A` the model's matrix at `β' = γ' = 0` (`M`
        // with its own constraint rows).
        let mut r = vec![0.0; n + mi];
        self.inner.residual(
            &mut w.inner,
            state.t,
            &state.q,
            &state.v,
            acc,
            &lambda[..mi],
            &mut r,
        );
        self.inner.factor(
            &mut w.inner,
            state.t,
            &state.q,
            &state.v,
            acc,
            &lambda[..mi],
            0.0,
            0.0,
        )?;
        self.border(w, state.t, &state.q, &state.v)?;
        let body = w.rows.as_ref();
        let rhs = DVector::from_fn(self.holds.len(), |a, _| {
            let h = self.holds[a];
            self.dot(h, acc, body) - self.gamma(h, body)
        });
        let Some(mu) = w.s.as_ref().and_then(|s| s.solve(&rhs)) else {
            return Err(failed(
                state.t,
                "the sustained contact rows are dependent".into(),
            ));
        };
        for (b, x) in w.x.iter().enumerate() {
            for i in 0..n {
                acc[i] -= x[i] * mu[b];
            }
            for c in 0..mi {
                lambda[c] -= x[n + c] * mu[b];
            }
            lambda[mi + b] = mu[b];
        }
        Ok(())
    }

    fn residual(
        &self,
        w: &mut Self::Work,
        t: f64,
        y: &[f64],
        v: &[f64],
        acc: &[f64],
        lambda: &[f64],
        r: &mut [f64],
    ) {
        let (n, mi) = (self.inner.n(), self.inner.n_constraints());
        self.inner
            .residual(&mut w.inner, t, y, v, acc, &lambda[..mi], &mut r[..n + mi]);
        let body = self.body_at(t, y, v);
        let mid = self.mid_at(t, y, &w.base, v);
        for (b, &h) in self.holds.iter().enumerate() {
            self.add_column(h, &w.dirs, body.as_ref(), lambda[mi + b], &mut r[..n]);
            r[n + mi + b] = self.value(h, y, body.as_ref(), (&w.base, mid.as_ref()));
        }
    }

    fn factor(
        &self,
        w: &mut Self::Work,
        t: f64,
        y: &[f64],
        v: &[f64],
        acc: &[f64],
        lambda: &[f64],
        bp: f64,
        gp: f64,
    ) -> Result<(), DynamicsError> {
        let mi = self.inner.n_constraints();
        self.inner
            .factor(&mut w.inner, t, y, v, acc, &lambda[..mi], bp, gp)?;
        if self.holds.is_empty() {
            return Ok(());
        }
        self.border(w, t, y, v)
    }

    fn solve(&self, w: &mut Self::Work, r: &mut [f64]) {
        let (n, mi) = (self.inner.n(), self.inner.n_constraints());
        self.inner.solve(&mut w.inner, &mut r[..n + mi]);
        let k = self.holds.len();
        let Some(s) = w.s.as_ref().filter(|_| k > 0) else {
            return;
        };
        // `μ = S⁻¹ (C A⁻¹ r₁ − r₂)`, `x = A⁻¹ r₁ − A⁻¹ D μ`.
        let body = w.rows.as_ref();
        let rhs = DVector::from_fn(k, |a, _| {
            self.dot(self.holds[a], &r[..n], body) - r[n + mi + a]
        });
        let mu = s
            .solve(&rhs)
            .unwrap_or_else(|| DVector::from_element(k, f64::NAN));
        for (b, x) in w.x.iter().enumerate() {
            for (ri, xi) in r[..n + mi].iter_mut().zip(x) {
                *ri -= xi * mu[b];
            }
            r[n + mi + b] = mu[b];
        }
    }

    fn accepted(&self, w: &mut Self::Work, state: &State) -> f64 {
        let own = self.inner.accepted(&mut w.inner, state);
        let body = self.body_at(state.t, &state.q, &state.v);
        let mid = self.mid_at(state.t, &state.q, &w.base, &state.v);
        let worst = self
            .holds
            .iter()
            .map(|&h| {
                self.value(h, &state.q, body.as_ref(), (&w.base, mid.as_ref()))
                    .abs()
            })
            // NaN (a body's row that cannot be evaluated) is kept.
            .fold(own, |a, x| {
                if a.is_nan() || x.is_nan() {
                    f64::NAN
                } else {
                    a.max(x)
                }
            });
        // The next step starts here.
        w.base.clone_from(&state.q);
        w.dirs = self.directions(state);
        worst
    }

    fn full<'w>(&self, w: &'w Self::Work) -> &'w [f64] {
        self.inner.full(&w.inner)
    }
}

/// What the contact run needs of a vector model beyond [`AlphaModel`]:
/// the impact map `M (u⁺ − u⁻) = Wᵀ Λ + Jᵀ μ` with the model's own
/// constraints kept at the speed level, `J (u⁺ − u⁻) = 0`, and the
/// sustained contact forces on the accelerations those constraints allow.
pub(super) trait Impacts: AlphaModel {
    /// The mass matrix on the free coordinates at `s`, dense (`None`: this
    /// model has no impact map).
    fn dense_mass(&self, s: &State) -> Option<DMatrix<f64>>;
    /// The Jacobian `J = Φ_y` of the model's own constraint rows at `s`
    /// on the free coordinates (`q̇ = u`: it acts on the speeds), held
    /// through every impulse and force problem; `None`: no constraints.
    fn constraint_rows(&self, s: &State) -> Option<DMatrix<f64>> {
        let _ = s;
        None
    }
    /// The rates of the model's own constraints at `s`, `dΦ/dt = J u + Φ_t`
    /// with `j` their Jacobian at `s` ([`Impacts::constraint_rows`]; zero
    /// on consistent speeds; an index-3 integrator leaves them at its
    /// drift); `None`: no constraints.
    fn constraint_rates(&self, s: &State, j: &DMatrix<f64>) -> Option<DVector<f64>> {
        let _ = (s, j);
        None
    }
    /// The accelerations without contact forces at `s`, the model's own
    /// constraints held (`J a = γ`, their forces included).
    fn free_acceleration(&self, s: &State) -> Option<DVector<f64>>;
    /// Total energy at `s`.
    fn total_energy(&self, s: &State) -> f64;
    /// The rows of the model's own contacts (a mixed model's rigid part's:
    /// joint limits, markers against planes, spheres) at `(t, y, v)`, on
    /// all the free coordinates; `None` if they cannot be evaluated. None
    /// by default (no contacts of its own).
    fn body_rows(&self, t: f64, y: &[f64], v: &[f64]) -> Option<Rows> {
        let _ = (t, y, v);
        None
    }
    /// The frames of the bodies cable nodes touch at `(t, y, v)` (the
    /// rigid part's generated `contact_frames`), their rows on all the
    /// free coordinates; `None` if they cannot be evaluated. None by
    /// default (no bodies).
    fn body_frames(&self, t: f64, y: &[f64], v: &[f64]) -> Option<Vec<Frame>> {
        let _ = (t, y, v);
        None
    }
    /// Brings an event's state onto the model's own constraints where it
    /// is off them (a state from the step's interpolant, not from the
    /// integrator): positions `Φ = 0`, then speeds `J u + Φ_t = 0`, each
    /// by the least change in the mass metric. Nothing to do by default.
    fn onto_constraints(&self, s: &mut State) -> Result<(), DynamicsError> {
        let _ = s;
        Ok(())
    }
}

/// The normal speed below which a contact's own impulse counts as
/// round-off, m/s: a rest impulse that takes more than this from a
/// row's speed by pulling it (`Λ < 0`) is of the wrong sign, and a row
/// leaving an impact faster than this flies.
const REST_SPEED: f64 = 1e-9;

/// A sliding speed `v_t · s0` below zero by more than this (m/s) at the
/// end of a slide's first step turned the wrong way (round-off is far
/// below it).
const SLIP_ROUND_OFF: f64 = 1e-12;

/// Why a run stops when its rows evaluated per state give none.
const UNEVALUATED: &str = "the contacts evaluated per state cannot be evaluated (the rigid part's generated `contacts` or `friction` failed, or two spheres' centres coincide)";

/// Why a contact event could not be resolved.
fn failed(t: f64, what: String) -> DynamicsError {
    DynamicsError::Contact { t, message: what }
}

/// The contacts between segments: the sustained rows and the events so
/// far, with the run's counters over its segments.
pub(super) struct ContactRun<'g> {
    pub gaps: &'g Gaps,
    pub active: Vec<usize>,
    pub events: Vec<ContactEvent>,
    pub stats: DynamicsStats,
    /// The sustained rows' normal forces at the last accepted step.
    pub forces: Vec<f64>,
    /// The model's own multipliers (a mixed model's mount forces) at the
    /// last accepted step.
    pub multipliers: Vec<f64>,
    /// Per contact row, its [`Slide`] while active with friction.
    pub slides: Vec<Option<Slide>>,
    /// Per contact row, the tangential position `t_a·y` a stick holds.
    pub anchors: Vec<[f64; 2]>,
    /// Sticking rows whose force was located leaving the cone.
    breaking: Vec<usize>,
    /// Held rows whose force was located falling through zero at the
    /// start of a step (released by the next `settle`).
    releasing: Vec<usize>,
    /// Per contact row, when it last left its plane (an impact it left
    /// rising, or a release), while it flies.
    left: Vec<Option<f64>>,
    /// Per contact row, the duration of its last hop (from leaving its
    /// plane to landing again), while it hops.
    hops: Vec<Option<f64>>,
    /// Per contact row, it left its plane rising from an impact: its
    /// landing is located at the level it left from.
    bounced: Vec<bool>,
}

/// The first crossing of `f` from `≥ 0` at `a` to `< 0` at `b` (bisection
/// to round-off).
fn locate(f: impl Fn(f64) -> f64, mut a: f64, mut b: f64) -> f64 {
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        if f(m) < 0.0 {
            b = m;
        } else {
            a = m;
        }
    }
    b
}

/// The state where a closing gap meets its level on the integrator's own
/// step: `step(τ)` is the step from the bracket's start `a` to `τ`, `gap`
/// its gap above the level, positive at `a` and negative at `b`. Regula
/// falsi (Illinois) from the interpolant's crossing `guess` until the gap
/// is within `tol` (half of [`GAP_TOL`] for a gap — a few steps retaken,
/// where the cubic interpolant of a flexible cable's step missed by up to
/// 0.3 mm —; for a stick's distance to its cone, a force, a part in 10⁹
/// of its friction force), or `None` if a retaken step fails.
///
/// A state within `tol` is taken only where `closing` says the row meets
/// its level there; one that does not (a node that left an impact rising,
/// still within `tol` of its plane a few picoseconds on, whose step ends
/// below it because it comes back down) lies before the crossing, and the
/// bracket is halved from it. Taken, it gave an event with nothing to do
/// and the same crossing again, each a retaken step of picoseconds.
fn on_the_steps<T>(
    guess: f64,
    ((mut a, mut fa), (mut b, mut fb)): ((f64, f64), (f64, f64)),
    tol: f64,
    step: impl Fn(f64) -> Option<T>,
    gap: impl Fn(&T) -> f64,
    closing: impl Fn(&T) -> bool,
) -> Option<T> {
    let mut t = guess;
    let mut side = 0;
    for _ in 0..60 {
        let s = step(t)?;
        let f = gap(&s);
        if b - a <= 4.0 * f64::EPSILON * b.abs().max(1.0) {
            return Some(s);
        }
        if f.abs() <= tol {
            if closing(&s) {
                return Some(s);
            }
            (a, fa) = (t, fa.max(tol));
            side = 0;
            t = 0.5 * (a + b);
            continue;
        }
        if f > 0.0 {
            (a, fa) = (t, f);
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        } else {
            (b, fb) = (t, f);
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        }
        // `fa > 0 > fb` throughout: the secant of the bracket.
        t = (a * fb - b * fa) / (fb - fa);
        if !(t > a && t < b) {
            t = 0.5 * (a + b);
        }
    }
    step(t)
}

impl<'g> ContactRun<'g> {
    /// A run on the rows `gaps`, no contact sustained yet.
    pub fn new(gaps: &'g Gaps) -> Self {
        ContactRun {
            gaps,
            active: Vec::new(),
            events: Vec::new(),
            stats: DynamicsStats::default(),
            forces: Vec::new(),
            multipliers: Vec::new(),
            slides: vec![None; gaps.len()],
            anchors: vec![[0.0; 2]; gaps.len()],
            breaking: Vec::new(),
            releasing: Vec::new(),
            left: vec![None; gaps.len()],
            hops: vec![None; gaps.len()],
            bounced: vec![false; gaps.len()],
        }
    }

    /// Row `i` landing at `t` ends a Zeno accumulation of hops: the hops
    /// it made since it last left its plane shrink (the last hop `τ`
    /// shorter than the one before, ratio `q = τ/τ₋₁`) and the geometric
    /// series of the hops still to come, `τ q/(1 − q)`, sums to at most
    /// one step `h`. It then comes to rest at that landing (the limit of
    /// the series, `ġ⁺ = 0`: a plastic impulse, if it carries a force).
    /// Records the hop.
    fn accumulates(&mut self, i: usize, t: f64, h: f64) -> bool {
        let Some(left) = self.left[i].take() else {
            return false;
        };
        let tau = t - left;
        let shrinks = self.hops[i].is_some_and(|p| tau < p);
        let q = self.hops[i].map_or(1.0, |p| tau / p);
        self.hops[i] = Some(tau);
        shrinks && tau * q <= h * (1.0 - q)
    }

    /// Records the release of the rows `rows` at `s` (no impulse, no jump;
    /// nothing if `rows` is empty).
    fn release<M: Impacts + ?Sized>(&mut self, m: &M, s: &State, rows: &[usize], r: &Rows) {
        if rows.is_empty() {
            return;
        }
        let e = m.total_energy(s);
        let zeros = vec![0.0; rows.len()];
        let ev = self.event(
            s.t,
            ContactEventKind::Release,
            rows,
            (r, e),
            (r, e),
            (&zeros, &[]),
            vec![0.0; s.v.len()],
        );
        self.events.push(ev);
    }

    /// The event record of the impulses `(ln, lt)` on the rows `set`.
    #[allow(clippy::too_many_arguments)]
    fn event(
        &self,
        t: f64,
        kind: ContactEventKind,
        set: &[usize],
        before: (&Rows, f64),
        after: (&Rows, f64),
        (ln, lt): (&[f64], &[[f64; 2]]),
        generalized: Vec<f64>,
    ) -> ContactEvent {
        ContactEvent {
            t,
            kind,
            contacts: set
                .iter()
                .enumerate()
                .map(|(k, &i)| ContactImpulse {
                    contact: self.gaps.names[i].clone(),
                    speed_before: before.0.gdot[i],
                    speed_after: after.0.gdot[i],
                    impulse: ln[k],
                    tangential_impulse: lt.get(k).copied().unwrap_or([0.0; 2]),
                    tangential_speed_before: before.0.vt[i],
                    tangential_speed_after: after.0.vt[i],
                })
                .collect(),
            energy_before: before.1,
            energy_after: after.1,
            generalized_impulse: generalized,
            joint_impulses: Vec::new(),
        }
    }

    /// Applies the velocity jump `sol` on the rows `set` to `s` and records
    /// it as a `kind` event; returns the rows after it.
    fn jump<M: Impacts + ?Sized>(
        &mut self,
        m: &M,
        s: &mut State,
        kind: ContactEventKind,
        set: &[usize],
        (r, mm): (&Rows, &DMatrix<f64>),
        sol: &Solved,
    ) -> Result<Rows, DynamicsError> {
        let e0 = m.total_energy(s);
        for (v, d) in s.v.iter_mut().zip(sol.du.iter()) {
            *v += d;
        }
        let after = self.gaps.at(m, s)?;
        let ln: Vec<f64> = sol.ln.iter().copied().collect();
        let ev = self.event(
            s.t,
            kind,
            set,
            (r, e0),
            (&after, m.total_energy(s)),
            (&ln, &sol.lt),
            (mm * &sol.du).as_slice().to_vec(),
        );
        self.events.push(ev);
        Ok(after)
    }

    /// Resolves the contacts at `s` (as the rigid runtime's `settle`):
    /// the impact of the closed rows if one approaches (Newton–Coulomb on
    /// the rows with friction), then the force problem of the rows at rest
    /// (held ones, and closed ones not leaving, `ġ ≤` [`REST_SPEED`]):
    /// those that carry a force `λ > 0` are held (those arriving lose
    /// their remaining speed by a plastic impulse, never one that pulls),
    /// the others released. Rest is decided on the steps, not on the
    /// instantaneous `g̈` (a flexible node's elastic accelerations, 10²–10⁴
    /// m/s² just after an impact, cannot tell its bounce from a Zeno
    /// tail): a row leaving an impact rising flies, its landing is located
    /// on the steps, and the landing that ends a series of shrinking hops
    /// whose remainder sums to at most one step `h` is plastic
    /// ([`ContactRun::accumulates`]), after which it rests. A row
    /// with friction slides along `v_t` if faster than its slip speed (as
    /// the rigid runtime's: a slide that would stop within the gap
    /// tolerance against its friction and drive,
    /// `‖v_t‖² ≤ 2 (‖t·a‖ + μ |w·a|) GAP_TOL`, `a` the free accelerations;
    /// a slide's stop is located, so it arrives there at round-off speed),
    /// else sticks if the force it needs fits the cone (those that stop
    /// lose what is left of their sliding speed by the same plastic
    /// impulse), else slides the way that force would push it.
    pub fn settle<M: Impacts + ?Sized>(
        &mut self,
        m: &M,
        s: &mut State,
        h: f64,
    ) -> Result<(), DynamicsError> {
        let t = s.t;
        let nk = self.gaps.len();
        let breaking = std::mem::take(&mut self.breaking);
        let releasing = std::mem::take(&mut self.releasing);
        let mut r = self.gaps.at(m, s)?;
        let closed: Vec<usize> = (0..nk).filter(|&i| r.g[i] <= GAP_TOL).collect();
        // The mass matrix and the model's own constraint rows at the
        // event's positions (an impulse jumps the speeds only), each
        // evaluated once when first needed.
        let at = s.clone();
        let (mass_at, rows_at) = (OnceCell::new(), OnceCell::new());
        let mass = || {
            mass_at
                .get_or_init(|| m.dense_mass(&at))
                .clone()
                .ok_or_else(|| failed(t, "this model has no impact map for its contacts".into()))
        };
        let jac = || rows_at.get_or_init(|| m.constraint_rows(&at)).as_ref();
        // `M⁻¹ R` with the model's constraints held (`J Δ = 0`).
        let inverse = |mm: &DMatrix<f64>, rhs: &DMatrix<f64>| {
            effective_inverse(mm, jac(), rhs).ok_or_else(|| {
                failed(
                    t,
                    "the mass matrix with the model's constraints is singular".into(),
                )
            })
        };
        let no_solution = |n: usize| {
            failed(
                t,
                format!(
                    "the impact of {n} contact(s) in a model with cables has no solution (more than {MAX_LCP} contacts closed at once, a singular mass matrix, or sliding directions that do not settle)"
                ),
            )
        };
        // Impulses keep the model's own constraints at the speed level,
        // `J (u⁺ − u⁻) = 0`: the speeds are first brought onto them
        // (`J u + Φ_t = 0`, the least change in kinetic energy; the
        // index-3 integrator's speeds miss them by its drift), so that
        // `J u⁺ + Φ_t = 0` after every impulse and the constraints do no
        // work in it. The event's speeds and energy before are these.
        if !closed.is_empty()
            && let Some(j) = jac()
            && let Some(d) = m.constraint_rates(s, j)
            && d.amax() > 0.0
        {
            let mm = mass()?;
            let du = onto_constraints(&mm, j, &d).ok_or_else(|| {
                failed(
                    t,
                    "the speeds cannot be brought onto the model's constraints (a singular mass matrix)".into(),
                )
            })?;
            for (v, x) in s.v.iter_mut().zip(du.iter()) {
                *v += x;
            }
            r = self.gaps.at(m, s)?;
        }
        // The held rows are constraints while held: their speeds are
        // brought onto `ġ = 0` (and a sticking row's onto `v_t = 0`) the
        // same way, with the model's constraints kept. The index-3
        // integrator holds their `g` (and a stick's anchor), not their
        // speeds, and a restart's first step turns a held row's speed over
        // (`w·(y₁ − y₀) = 0` with Newmark's `β = ½`, `γ = 1`): left in, a
        // drift off the plane made the plastic impulse that sticks the row
        // a pull (2.5e-6 m/s at the pendulum cable's stick).
        // Rows of the projection: held rows' normals, and a sticking row's
        // tangents (held by its anchors), each with its speed.
        let mut held: Vec<(DVector<f64>, f64)> = Vec::new();
        for &i in self.active.iter().filter(|i| closed.contains(i)) {
            held.push((r.w.row(i).transpose(), r.gdot[i]));
            if matches!(self.slides[i], Some(Slide::Stick)) {
                for a in 0..2 {
                    let row = r.wt.row(2 * i + a).transpose();
                    if row.amax() > 0.0 {
                        held.push((row, r.vt[i][a]));
                    }
                }
            }
        }
        if held.iter().any(|(_, v)| *v != 0.0) {
            let mm = mass()?;
            let wn = DMatrix::from_fn(held.len(), s.v.len(), |a, k| held[a].0[k]);
            let x = inverse(&mm, &wn.transpose())?;
            let drift = DVector::from_fn(held.len(), |a, _| -held[a].1);
            let nu = (&wn * &x).lu().solve(&drift).ok_or_else(|| {
                failed(
                    t,
                    "the sustained contact rows are dependent (their speeds cannot be held)".into(),
                )
            })?;
            let dv = x * nu;
            for (v, d) in s.v.iter_mut().zip(dv.iter()) {
                *v += d;
            }
            r = self.gaps.at(m, s)?;
        }
        if closed
            .iter()
            .any(|&i| r.gdot[i] < 0.0 && !self.active.contains(&i))
        {
            let mm = mass()?;
            // A landing that ends a Zeno series of shrinking hops takes no
            // Newton impact: the row comes to rest there (the series' limit,
            // `ġ⁺ = 0`), by the rest's plastic impulse below if it carries
            // a force.
            let landing: Vec<usize> = closed
                .iter()
                .copied()
                .filter(|&i| r.gdot[i] < 0.0 && !self.active.contains(&i))
                .collect();
            let zeno: Vec<usize> = landing
                .iter()
                .copied()
                .filter(|&i| self.accumulates(i, t, h))
                .collect();
            for &i in &zeno {
                self.bounced[i] = false;
            }
            if landing.iter().any(|i| !zeno.contains(i)) {
                let set: Vec<usize> = closed
                    .iter()
                    .copied()
                    .filter(|i| !zeno.contains(i))
                    .collect();
                let slides: Vec<Option<Slide>> = set
                    .iter()
                    .map(|&i| self.gaps.rough(i).then_some(Slide::Stick))
                    .collect();
                let e = |i: usize| r.e[i];
                let sol = impact(&mm, jac(), &r, &set, &e, false, &slides)
                    .ok_or_else(|| no_solution(set.len()))?;
                r = self.jump(m, s, ContactEventKind::Impact, &set, (&r, &mm), &sol)?;
                // Rows leaving rising fly: their landing is located at the
                // level they leave from (not below it: a hop's landing
                // GAP_TOL below its take-off ratchets a hopping node into
                // its plane).
                for &i in &set {
                    if r.gdot[i] > REST_SPEED {
                        self.left[i] = Some(t);
                        self.bounced[i] = true;
                    }
                }
            }
        }
        let free = m
            .free_acceleration(s)
            .ok_or_else(|| failed(t, "no accelerations at the contact event".into()))?;
        // Each row's `g̈` and `v̇_t` without contact forces.
        let acc_of: Vec<f64> = (0..nk)
            .map(|i| r.w.row(i).transpose().dot(&free) - r.gamma[i])
            .collect();
        let tacc_of: Vec<[f64; 2]> = (0..nk)
            .map(|i| [0, 1].map(|a| r.tangential_dot(i, a, &free) - r.gamma_t[i][a]))
            .collect();
        let acc = |i: usize| acc_of[i];
        let tacc = |i: usize| tacc_of[i];
        let resting: Vec<usize> = closed
            .iter()
            .copied()
            .filter(|&i| self.active.contains(&i) || r.gdot[i] <= REST_SPEED)
            .filter(|i| !releasing.contains(i))
            .collect();
        let rough = resting.iter().any(|&i| self.gaps.rough(i));
        // The force problem: g̈ = W M⁻¹ (Wᵀ λ + W_tᵀ λ_t) + W a_free ≥ 0,
        // λ ≥ 0 (without friction the LCP of the normal rows alone).
        let mut slides: Vec<Option<Slide>> = resting
            .iter()
            .map(|&i| {
                self.gaps.rough(i).then(|| {
                    let v = r.vt[i];
                    let nv = norm2(v);
                    let slip = (2.0 * (norm2(tacc(i)) + r.mu[i] * acc(i).abs()) * GAP_TOL).sqrt();
                    if nv > slip {
                        Slide::Slip([v[0] / nv, v[1] / nv])
                    } else {
                        Slide::Stick
                    }
                })
            })
            .collect();
        let mut now: Vec<usize>;
        let mut forces: Option<Solved> = None;
        let mut carrying: Vec<usize> = Vec::new();
        if resting.is_empty() {
            now = Vec::new();
        } else if !rough {
            let mm = mass()?;
            let wn = DMatrix::from_fn(resting.len(), free.len(), |a, k| r.w[(resting[a], k)]);
            let minv_wt = inverse(&mm, &wn.transpose())?;
            let a = &wn * minv_wt;
            let b = DVector::from_fn(resting.len(), |k, _| acc(resting[k]));
            let lambda = lcp(&a, &b).ok_or_else(|| no_solution(resting.len()))?;
            let scale = lambda.amax().max(f64::MIN_POSITIVE);
            carrying = (0..resting.len())
                .filter(|&k| lambda[k] > 1e-12 * scale)
                .collect();
            now = carrying.iter().map(|&k| resting[k]).collect();
        } else {
            let mm = mass()?;
            let b = DVector::from_fn(resting.len(), |k, _| acc(resting[k]));
            let bt: Vec<[f64; 2]> = resting.iter().map(|&i| tacc(i)).collect();
            // A stick located breaking leaves the cone at once (the
            // located time is that of the step's linear force).
            let margin = |k: usize| {
                if breaking.contains(&resting[k]) {
                    1e-3
                } else {
                    1e-6
                }
            };
            forces = resting_forces(&mm, jac(), &r, &resting, &mut slides, &b, &bt, &margin);
            let Some(f) = forces.as_ref() else {
                return Err(failed(
                    t,
                    format!(
                        "the contact forces of {} resting contact(s) in a model with cables have no solution",
                        resting.len()
                    ),
                ));
            };
            let scale = f.ln.amax().max(f64::MIN_POSITIVE);
            carrying = (0..resting.len())
                .filter(|&k| f.ln[k] > 1e-12 * scale && f.ln[k] > 0.0)
                .collect();
            now = carrying.iter().map(|&k| resting[k]).collect();
        }
        let mut now_slides: Vec<Option<Slide>> = carrying.iter().map(|&k| slides[k]).collect();
        let released: Vec<usize> = self
            .active
            .iter()
            .copied()
            .filter(|i| !now.contains(i))
            .collect();
        self.release(m, s, &released, &r);
        let mut arriving: Vec<usize> = now
            .iter()
            .copied()
            .filter(|i| !self.active.contains(i))
            .collect();
        // Rows that stay and change between sticking and sliding.
        let (mut to_stick, mut to_slip) = (Vec::new(), Vec::new());
        for (k, &i) in now.iter().enumerate() {
            if !self.active.contains(&i) {
                continue;
            }
            match (self.slides[i], now_slides[k]) {
                (Some(Slide::Slip(_)), Some(Slide::Stick)) => to_stick.push(i),
                (Some(Slide::Stick), Some(Slide::Slip(_))) => to_slip.push(i),
                _ => {}
            }
        }
        if !arriving.is_empty() || !to_stick.is_empty() {
            // Their remaining normal speed and the remaining sliding speed
            // of the sticking ones taken by one plastic impulse; the
            // sustained ones keep ġ = 0. A row whose plastic impulse would
            // pull it (`Λ < 0`, taking away more than [`REST_SPEED`] of
            // its own speed) separates: an arriving one flies instead
            // (its landing is located and its hops run until they
            // accumulate, [`ContactRun::accumulates`]), a sticking one is
            // released, and a sustained one keeps its speed (its drift).
            let mm = mass()?;
            // `w M⁻¹ wᵀ` of each row of `now`, the constraints held.
            let wn = DMatrix::from_fn(s.v.len(), now.len(), |k, a| r.w[(now[a], k)]);
            let minv_wt = inverse(&mm, &wn)?;
            let own_of: Vec<(usize, f64)> = now
                .iter()
                .enumerate()
                .map(|(a, &i)| (i, wn.column(a).dot(&minv_wt.column(a))))
                .collect();
            let own = |i: usize| {
                own_of
                    .iter()
                    .find(|&&(j, _)| j == i)
                    .map_or(0.0, |&(_, x)| x)
            };
            // The speed row `set[k]` loses by its own impulse if that
            // pulls (> 0: a pull).
            let pull = |sol: &Solved, k: usize, i: usize| -sol.ln[k] * own(i);
            let plastic = |_: usize| 0.0;
            // The rows the impulse acts on: `now`, less arriving rows that
            // fly and held ones it would pull (a held row's `ġ > 0` is the
            // index-3 integrator's drift at velocity level: it stays held
            // at `g = 0` without an impulse).
            let mut set = now.clone();
            let slides_of = |set: &[usize], now: &[usize], now_slides: &[Option<Slide>]| {
                set.iter()
                    .map(|i| now.iter().position(|j| j == i).and_then(|k| now_slides[k]))
                    .collect::<Vec<_>>()
            };
            let plastic_on = |set: &[usize], now: &[usize], now_slides: &[Option<Slide>]| {
                impact(
                    &mm,
                    jac(),
                    &r,
                    set,
                    &plastic,
                    true,
                    &slides_of(set, now, now_slides),
                )
                .ok_or_else(|| no_solution(set.len()))
            };
            let mut sol = plastic_on(&set, &now, &now_slides)?;
            // Sticking rows the impulse would pull: stopping their slide
            // lifts them (the pendulum cable's node, by 3e-9 m/s through
            // the cable). With no normal impulse the cone allows no
            // tangential one: they leave their plane, released, and their
            // landing is located as any other.
            let mut lifted: Vec<usize> = Vec::new();
            loop {
                let pulled: Vec<usize> = set
                    .iter()
                    .enumerate()
                    .filter(|&(k, &i)| pull(&sol, k, i) > REST_SPEED)
                    .map(|(_, &i)| i)
                    .collect();
                if pulled.is_empty() {
                    break;
                }
                let leaves = |i: &usize| {
                    pulled.contains(i) && (arriving.contains(i) || to_stick.contains(i))
                };
                let keep: Vec<bool> = now.iter().map(|i| !leaves(i)).collect();
                let mut k = 0;
                now_slides.retain(|_| {
                    k += 1;
                    keep[k - 1]
                });
                lifted.extend(to_stick.iter().copied().filter(|i| pulled.contains(i)));
                now.retain(|i| !leaves(i));
                arriving.retain(|i| !pulled.contains(i));
                to_stick.retain(|i| !pulled.contains(i));
                set.retain(|i| !pulled.contains(i));
                if arriving.is_empty() && to_stick.is_empty() {
                    break;
                }
                sol = plastic_on(&set, &now, &now_slides)?;
            }
            self.release(m, s, &lifted, &r);
            if !arriving.is_empty() || !to_stick.is_empty() {
                let kind = if arriving.is_empty() {
                    ContactEventKind::Stick
                } else {
                    ContactEventKind::Rest
                };
                r = self.jump(m, s, kind, &set, (&r, &mm), &sol)?;
            }
        }
        if !to_slip.is_empty() {
            // The start of a slide: no jump; the forces at its start.
            let e = m.total_energy(s);
            let f = forces.as_ref();
            let pick = |i: usize| {
                let k = carrying.iter().position(|&k| resting[k] == i);
                match (f, k) {
                    (Some(f), Some(k)) => (f.ln[carrying[k]], f.lt[carrying[k]]),
                    _ => (0.0, [0.0; 2]),
                }
            };
            let ln: Vec<f64> = to_slip.iter().map(|&i| pick(i).0).collect();
            let lt: Vec<[f64; 2]> = to_slip.iter().map(|&i| pick(i).1).collect();
            let ev = self.event(
                t,
                ContactEventKind::Slip,
                &to_slip,
                (&r, e),
                (&r, e),
                (&ln, &lt),
                vec![0.0; s.v.len()],
            );
            self.events.push(ev);
        }
        for &i in &released {
            self.left[i] = Some(t);
            self.hops[i] = None;
            self.bounced[i] = false;
        }
        for &i in &now {
            self.left[i] = None;
            self.hops[i] = None;
            self.bounced[i] = false;
        }
        self.slides = vec![None; nk];
        for (&i, sl) in now.iter().zip(&now_slides) {
            self.slides[i] = *sl;
            self.anchors[i] = [0, 1].map(|a| self.gaps.tdot(i, a, &s.q));
        }
        self.active = now;
        Ok(())
    }

    /// Generalized-α on `m` from `state` to `t_end` through every contact
    /// event; `observe` sees every accepted state (and each event's state
    /// before its jump), and its error stops the run. Returns the last
    /// state and, if the run stopped early, why.
    pub fn run<M: Impacts + ?Sized>(
        &mut self,
        m: &M,
        mut state: State,
        opts: &AlphaOptions,
        t_end: f64,
        mut observe: impl FnMut(&State, Option<&[f64]>) -> Result<(), DynamicsError>,
    ) -> (State, Option<DynamicsError>) {
        let nk = self.gaps.len();
        let mut opts = opts.clone();
        let eps = 1e-12 * t_end.abs().max(1.0);
        if let Err(e) = self.settle(m, &mut state, opts.h) {
            return (state, Some(e));
        }
        let mut stalled = 0;
        // The run's start is generalized-α's (`a₀ = ÿ₀`); every later
        // segment starts at an event, where the motion changed abruptly,
        // and restarts without exciting the modes the step does not resolve
        // (`GeneralizedAlpha::restarted`).
        let mut at_event = false;
        loop {
            let held = Held::new(
                m,
                self.gaps,
                &self.active,
                &self.slides,
                &self.anchors,
                &state,
            );
            let started = if at_event {
                GeneralizedAlpha::restarted(&held, state.clone(), opts.clone())
            } else {
                GeneralizedAlpha::new(&held, state.clone(), opts.clone())
            };
            at_event = true;
            let mut ga = match started {
                Ok(ga) => ga,
                Err(e) => return (state, Some(e)),
            };
            self.forces = held.forces(ga.multipliers());
            let own = m.n_constraints();
            self.multipliers = ga.multipliers()[..own].to_vec();
            let t_start = state.t;
            // Halvings of a fixed step after a Newton failure, and the
            // small steps left before the run returns to `h`.
            let (mut halvings, mut substeps) = (0u32, 0usize);
            let h_fixed = opts.h;
            // The gaps at the step's start: the last accepted step's end
            // (a body's are an evaluation of the rigid part's contacts).
            let mut gaps0 = self.gaps.gaps_at(m, ga.state());
            let event = loop {
                if ga.state().t >= t_end - eps {
                    break None;
                }
                let before = ga.carried();
                let prev = before.state().clone();
                let f0 = held.forces(ga.multipliers());
                let c0 = held.cone_margins(ga.multipliers());
                let p0 = held.slip_speeds(&prev);
                if let Err(e) = ga.step_within(t_end) {
                    // At a fixed step, a step whose Newton fails (the
                    // violent elastic transient of a wire just after an
                    // impact) is retaken in halves, down to h/64, and the
                    // run goes on at `h` after them. A failed step leaves
                    // the integrator where it was.
                    let retry = opts.control.is_none()
                        && halvings < 6
                        && matches!(e, DynamicsError::NewtonFailed { .. });
                    if !retry {
                        self.add_stats(&ga.stats);
                        return (prev, Some(e));
                    }
                    halvings += 1;
                    substeps = 1usize << halvings;
                    ga.set_step_size(opts.h / f64::from(1u32 << halvings));
                    continue;
                }
                let new = ga.state().clone();
                let f1 = held.forces(ga.multipliers());
                let c1 = held.cone_margins(ga.multipliers());
                let p1 = held.slip_speeds(&new);
                // The first crossing: an open gap falling through 0 on the
                // step's interpolant, a held force falling through 0, a
                // stick's force leaving the cone (`μ λ − ‖λ_t‖` falling
                // through 0), a slide stopping (`v_t · s0` falling through
                // 0); the last three linearly between the step's ends.
                // With the row whose gap closes (and the level it closes
                // at), `None` otherwise, and the stick that breaks.
                type First = (f64, Option<(usize, f64)>, Option<usize>);
                let mut first: Option<First> = None;
                let mut take = |t: f64, row: Option<(usize, f64)>, breaks: Option<usize>| {
                    if first.is_none_or(|(f, _, _)| t < f) {
                        first = Some((t, row, breaks));
                    }
                };
                let gaps1 = self.gaps.gaps_at(m, &new);
                if gaps1.iter().any(|g| g.is_nan()) {
                    self.add_stats(&ga.stats);
                    return (prev, Some(failed(new.t, UNEVALUATED.into())));
                }
                for i in (0..nk).filter(|i| !self.active.contains(i)) {
                    // A row that starts the step at or inside its plane (just
                    // released, or left by a plastic impact) counts as
                    // closing once it sinks GAP_TOL further: the force
                    // problem has found it not pressing. A row that left
                    // an impact rising closes where it left (a hop lands
                    // at its take-off level, not GAP_TOL below it).
                    let g0 = gaps0[i];
                    let level = match (g0 < 0.0, self.bounced[i]) {
                        (false, _) => 0.0,
                        (true, true) => g0,
                        (true, false) => g0 - GAP_TOL,
                    };
                    if gaps1[i] < level {
                        let g = |t: f64| {
                            self.gaps
                                .gap_at(m, i, &super::simulate::hermite(&prev, &new, t))
                                - level
                        };
                        take(locate(g, prev.t, new.t), Some((i, level)), None);
                    }
                }
                let linear = |a: f64, b: f64| prev.t + (new.t - prev.t) * a / (a - b);
                for k in 0..self.active.len() {
                    if f1[k] < 0.0 && f0[k] >= 0.0 {
                        take(linear(f0[k], f1[k]), None, None);
                    } else if f1[k] < 0.0 {
                        take(prev.t, None, None);
                    }
                    if let (Some(a), Some(b)) = (c0[k], c1[k])
                        && b < 0.0
                    {
                        let t = if a >= 0.0 { linear(a, b) } else { prev.t };
                        take(t, None, Some(self.active[k]));
                    }
                    // A slide from rest starts at `v_t · s0 ≤ 0`: only a
                    // slide under way stops. One that starts the step at
                    // rest (its stop linearly within a part in 10⁶ of the
                    // step from its start, as a held force's) and ends it
                    // reversed (an axial vibration turning it within the
                    // step) is taken at the step's end: located at its
                    // start it would be found there again. (A wire creeping
                    // by stick–slip: 9.6e-11 m/s at the start of a
                    // restart's first step, −1.1e-4 m/s at its end.)
                    // A slide that never got under way (`v_t · s0 ≤ 0` at
                    // the step's start, beyond round-off the wrong way at
                    // its end: the node and the body it slides on pulled
                    // apart against `s0`) is taken at the step's end too:
                    // left alone its friction would push the slip on and
                    // feed energy in (a wire ringing axially on a cart).
                    if let (Some(a), Some(b)) = (p0[k], p1[k])
                        && ((a > 0.0 && b <= 0.0) || (a <= 0.0 && b < -SLIP_ROUND_OFF))
                    {
                        let t = if a <= 1e-6 * (a - b) {
                            new.t
                        } else {
                            linear(a, b)
                        };
                        take(t, None, None);
                    }
                }
                match first {
                    None => {
                        gaps0 = gaps1;
                        self.forces = f1;
                        self.multipliers = ga.multipliers()[..own].to_vec();
                        if let Err(e) = observe(&new, Some(ga.q_full())) {
                            self.add_stats(&ga.stats);
                            return (new, Some(e));
                        }
                        if substeps > 0 {
                            substeps -= 1;
                            if substeps == 0 {
                                halvings = 0;
                                ga.set_step_size(opts.h);
                            }
                        }
                    }
                    Some((t, row, breaks)) => {
                        self.breaking.extend(breaks);
                        // A held force that crosses zero within a part in
                        // 10⁶ of the step from its start is zero there (to
                        // that part of the step's change): the row is
                        // released at the start. Held again by the force
                        // problem (its force there, tiny, still positive),
                        // it would cross at once again, with no time
                        // passing (a four-bar's cable node yanked off the
                        // floor: 8e-6 N at the start, −13 N one step on).
                        if row.is_none() && breaks.is_none() {
                            let near = |k: usize| {
                                f1[k] < 0.0 && f0[k] >= 0.0 && f0[k] <= 1e-6 * (f0[k] - f1[k])
                            };
                            self.releasing.extend(
                                (0..self.active.len())
                                    .filter(|&k| near(k))
                                    .map(|k| self.active[k]),
                            );
                        }
                        // Restart at the event: the step retaken from its
                        // start to the located time (an integrator state,
                        // not the interpolant's), the interpolant if that
                        // step fails. For a closing gap the retaken step's
                        // own gap is brought to the level: the interpolant
                        // only guesses where the integrator crosses.
                        // A force's crossing within a part in 10⁶ of the
                        // step from its start is taken at the start: a
                        // retaken step of ~1e-13 s is ill-conditioned for
                        // index-3 generalized-α (its matrix ~ M/(β h²)),
                        // and once returned a wire moving at 10⁷ m/s.
                        let s = if t >= new.t {
                            new
                        } else if t <= prev.t
                            || (row.is_none() && t - prev.t <= 1e-6 * (new.t - prev.t))
                        {
                            // At the step's start (a force already past
                            // zero there): no step to retake.
                            prev
                        } else {
                            // A retaken step is taken only if its speeds
                            // stay within ten times the step's ends' (a
                            // very short retaken step is ill-conditioned
                            // for index-3 generalized-α, and once returned
                            // a wire moving at 10⁷ m/s); else the
                            // interpolant stands for it.
                            let vmax = prev
                                .v
                                .iter()
                                .chain(&new.v)
                                .fold(0.0f64, |a, x| a.max(x.abs()));
                            let sane = |s: &State| s.v.iter().all(|x| x.abs() <= 10.0 * vmax + 1.0);
                            // Retaken from what the integrator carried
                            // at the step's start: the step the run takes.
                            let retake = |t: f64| {
                                let mut g =
                                    GeneralizedAlpha::resume(&held, before.clone(), opts.clone());
                                g.step_within(t)
                                    .ok()
                                    .map(|()| g.state().clone())
                                    .filter(|s| sane(s))
                            };
                            let located = match (row, breaks) {
                                (Some((i, level)), _) => {
                                    let gap = |s: &State| self.gaps.gap_at(m, i, s) - level;
                                    let ends = ((prev.t, gap(&prev)), (new.t, gap(&new)));
                                    let closing =
                                        |s: &State| self.gaps.speed_at(m, i, s) <= REST_SPEED;
                                    on_the_steps(t, ends, 0.5 * GAP_TOL, retake, gap, closing)
                                }
                                // A stick leaving its cone: its distance to
                                // the cone from the retaken step's
                                // multipliers, brought to zero likewise (a
                                // slide's stop stays linear: refined on the
                                // retaken steps too, the oblique drop's
                                // run failed in a later impact).
                                (None, Some(i)) => {
                                    let k = self.active.iter().position(|&j| j == i);
                                    let margin = |x: &(State, Vec<f64>)| {
                                        k.and_then(|k| held.cone_margins(&x.1)[k]).unwrap_or(0.0)
                                    };
                                    let retake_m = |t: f64| {
                                        let mut g = GeneralizedAlpha::resume(
                                            &held,
                                            before.clone(),
                                            opts.clone(),
                                        );
                                        g.step_within(t)
                                            .ok()
                                            .map(|()| (g.state().clone(), g.multipliers().to_vec()))
                                            .filter(|x| sane(&x.0))
                                    };
                                    let (a, b) = k
                                        .and_then(|k| Some((c0[k]?, c1[k]?)))
                                        .unwrap_or((0.0, 0.0));
                                    let tol = 1e-9 * (a.abs() + b.abs());
                                    on_the_steps(
                                        t,
                                        ((prev.t, a), (new.t, b)),
                                        tol,
                                        retake_m,
                                        margin,
                                        |_| true,
                                    )
                                    .map(|x| x.0)
                                }
                                (None, None) => retake(t),
                            };
                            located.unwrap_or_else(|| super::simulate::hermite(&prev, &new, t))
                        };
                        break Some(s);
                    }
                }
            };
            self.add_stats(&ga.stats);
            opts.h = if opts.control.is_none() {
                h_fixed
            } else {
                ga.step_size()
            };
            let Some(mut s) = event else {
                return (ga.state().clone(), None);
            };
            if let Err(e) = m.onto_constraints(&mut s) {
                return (s, Some(e));
            }
            if let Err(e) = observe(&s, None) {
                return (s, Some(e));
            }
            stalled = if s.t - t_start <= 1e-9 * opts.h {
                stalled + 1
            } else {
                0
            };
            if stalled > 64 {
                let t = s.t;
                return (
                    s,
                    Some(failed(
                        t,
                        "64 contact events without the time advancing (contacts that cannot be resolved)".into(),
                    )),
                );
            }
            if let Err(e) = self.settle(m, &mut s, opts.h) {
                return (s, Some(e));
            }
            state = s;
        }
    }

    fn add_stats(&mut self, s: &DynamicsStats) {
        let a = &mut self.stats;
        a.steps += s.steps;
        a.rejected += s.rejected;
        a.force_evaluations += s.force_evaluations;
        a.factorizations += s.factorizations;
        a.newton_iterations += s.newton_iterations;
        a.max_constraint_residual = a.max_constraint_residual.max(s.max_constraint_residual);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows of a node's sphere against central differences along a
    /// motion `y(t) = y + v t + ½ a t²`: `w = ∂g/∂y` (so `ġ = w·v`),
    /// `g̈ = w·a − γ` and `v̇_t = W_t a − γ_t` (`v_t` differentiated along
    /// the motion), for a spatial pair (both centres moving, the tangent
    /// axes from a reference axis) and a planar one against a fixed centre
    /// (`t1 = n × z`), with one of the coordinates fixed.
    #[test]
    fn a_node_spheres_rows_are_the_derivatives_of_its_gap_and_speeds() {
        let spatial = SphereRow {
            a: vec![(Some(0), 0.0), (Some(1), 0.0), (Some(2), 0.0)],
            b: vec![(Some(3), 0.0), (None, -0.2), (Some(4), 0.0)],
            centre: [0.0; 3],
            radius: 0.05,
            reference: Some([0.0, 0.0, 1.0]),
        };
        let planar = SphereRow {
            a: vec![(Some(0), 0.0), (Some(1), 0.0)],
            b: Vec::new(),
            centre: [0.1, -0.3, 0.0],
            radius: 0.05,
            reference: None,
        };
        let y = [0.31, 0.12, -0.07, -0.05, 0.2];
        let v = [0.7, -1.3, 0.4, 0.25, -0.6];
        let acc = [2.0, -9.81, 1.5, -0.4, 3.0];
        for (label, sp) in [("spatial", &spatial), ("planar", &planar)] {
            let n = y.len();
            let at = |t: f64| {
                let yt: Vec<f64> = (0..n)
                    .map(|k| y[k] + v[k] * t + 0.5 * acc[k] * t * t)
                    .collect();
                let vt: Vec<f64> = (0..n).map(|k| v[k] + acc[k] * t).collect();
                let mut r = Rows {
                    g: vec![0.0],
                    gdot: vec![0.0],
                    gamma: vec![0.0],
                    e: vec![0.5],
                    mu: vec![0.3],
                    w: DMatrix::zeros(1, n),
                    vt: vec![[0.0; 2]],
                    gamma_t: vec![[0.0; 2]],
                    wt: DMatrix::zeros(2, n),
                };
                assert!(sp.fill(&yt, &vt, true, 0, &mut r), "{label}");
                r
            };
            let r0 = rows_are_the_derivatives(label, &at, &v, &acc, 1e-6);
            // The tangent axes are unit, orthogonal and normal to `n`.
            let (t, _) = sp.tangents(
                [
                    r0.w[(0, 0)],
                    r0.w[(0, 1)],
                    if n > 2 && sp.a.len() > 2 {
                        r0.w[(0, 2)]
                    } else {
                        0.0
                    },
                ],
                [0.0; 3],
            );
            assert!((dot3(t[0], t[0]) - 1.0).abs() < 1e-14 && dot3(t[0], t[1]).abs() < 1e-14);
        }
    }

    /// A body moving in space (`q_r = (X, Y, Z, θ, φ)`, axes
    /// `E = R_z(θ) R_x(φ)`) with its frame at the body point `r_b`
    /// (`p = X + E r_b`, `ω = θ̇ z + φ̇ R_z(θ) x`), exact: the frame of the
    /// generated `contact_frames`, its rows on the free coordinates from
    /// index `offset`.
    fn spinning_frame(q: &[f64], u: &[f64], offset: usize) -> Frame {
        let rb = [0.1, -0.05, 0.2];
        let (th, ph) = (q[3], q[4]);
        let (c, s, cp, sp) = (th.cos(), th.sin(), ph.cos(), ph.sin());
        let rz = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]];
        let rx = [[1.0, 0.0, 0.0], [0.0, cp, -sp], [0.0, sp, cp]];
        let e: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| rz[i][k] * rx[k][j]).sum())
        });
        let arm: [f64; 3] = std::array::from_fn(|i| dot3(e[i], rb));
        let (z, xr) = ([0.0, 0.0, 1.0], [c, s, 0.0]);
        let jw = vec![[0.0; 3], [0.0; 3], [0.0; 3], z, xr];
        let jp: Vec<[f64; 3]> = (0..5)
            .map(|k| match k {
                0..3 => std::array::from_fn(|i| if i == k { 1.0 } else { 0.0 }),
                _ => cross3(jw[k], arm),
            })
            .collect();
        let w: [f64; 3] = std::array::from_fn(|i| u[3] * z[i] + u[4] * xr[i]);
        let al0 = cross3(w, xr).map(|x| x * u[4]);
        let (wa, aa) = (cross3(w, cross3(w, arm)), cross3(al0, arm));
        Frame {
            p: std::array::from_fn(|i| q[i] + arm[i]),
            e,
            v: std::array::from_fn(|i| u[i] + cross3(w, arm)[i]),
            w,
            a0: std::array::from_fn(|i| wa[i] + aa[i]),
            al0,
            jp,
            jw,
            offset,
        }
    }

    /// A node against a spinning body's plane and its sphere: `ġ` is the
    /// derivative of `g` along the motion, `w·v = ġ`, `g̈ = w·a − γ`,
    /// `W_t v = v_t` and `v̇_t = W_t a − γ_t` (the frame exact, the node
    /// and the body accelerating, one of the node's coordinates fixed).
    #[test]
    fn a_node_against_a_bodys_plane_or_sphere_has_the_derivatives_of_its_gap_as_rows() {
        let node = vec![(Some(0), 0.0), (None, 0.45), (Some(1), 0.0)];
        let plane = BodyRow {
            a: node.clone(),
            frame: 0,
            plane: Some([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]),
            radius_a: 0.03,
            radius_b: 0.0,
            reference: [1.0, 0.0, 0.0],
        };
        let sphere = BodyRow {
            plane: None,
            radius_b: 0.07,
            reference: [0.0, 0.0, 1.0],
            ..plane.clone()
        };
        // Free coordinates: the node's two (x, z), then the body's five.
        let y = [0.31, -0.07, 0.05, 0.1, -0.02, 0.4, -0.3];
        let v = [0.7, 0.4, -0.3, 0.25, 0.6, 1.3, -0.8];
        let acc = [2.0, 1.5, -0.4, 3.0, -9.81, 2.5, 4.0];
        let n = y.len();
        for (label, row) in [("plane", &plane), ("sphere", &sphere)] {
            let at = |t: f64| {
                let yt: Vec<f64> = (0..n)
                    .map(|k| y[k] + v[k] * t + 0.5 * acc[k] * t * t)
                    .collect();
                let vt: Vec<f64> = (0..n).map(|k| v[k] + acc[k] * t).collect();
                let f = spinning_frame(&yt[2..], &vt[2..], 2);
                let mut r = Rows {
                    g: vec![0.0],
                    gdot: vec![0.0],
                    gamma: vec![0.0],
                    e: vec![0.5],
                    mu: vec![0.3],
                    w: DMatrix::zeros(1, n),
                    vt: vec![[0.0; 2]],
                    gamma_t: vec![[0.0; 2]],
                    wt: DMatrix::zeros(2, n),
                };
                assert!(row.fill(&f, &yt, &vt, true, 0, &mut r), "{label}");
                r
            };
            rows_are_the_derivatives(label, &at, &v, &acc, 1e-5);
        }
    }

    /// Row 0 of `at(t)` (the rows along the motion with speeds `v` and
    /// accelerations `acc` at `t = 0`) against central differences of
    /// step `h`: `ġ` the rate of `g`, `w·v = ġ`, `g̈ = w·a − γ`,
    /// `W_t v = v_t` and `v̇_t = W_t a − γ_t`; returns the rows at 0.
    fn rows_are_the_derivatives(
        label: &str,
        at: &dyn Fn(f64) -> Rows,
        v: &[f64],
        acc: &[f64],
        h: f64,
    ) -> Rows {
        let n = v.len();
        let r0 = at(0.0);
        let (rp, rm) = (at(h), at(-h));
        let gdot = (rp.g[0] - rm.g[0]) / (2.0 * h);
        assert!(
            (gdot - r0.gdot[0]).abs() < 1e-8,
            "{label}: ġ {} against {gdot}",
            r0.gdot[0]
        );
        let wv: f64 = (0..n).map(|k| r0.w[(0, k)] * v[k]).sum();
        assert!((wv - r0.gdot[0]).abs() < 1e-14, "{label}: w·v {wv}");
        let gddot = (rp.gdot[0] - rm.gdot[0]) / (2.0 * h);
        let wa: f64 = (0..n).map(|k| r0.w[(0, k)] * acc[k]).sum();
        assert!(
            (wa - r0.gamma[0] - gddot).abs() < 1e-7,
            "{label}: w·a − γ = {} against g̈ {gddot}",
            wa - r0.gamma[0]
        );
        for a in 0..2 {
            let wtv: f64 = (0..n).map(|k| r0.wt[(a, k)] * v[k]).sum();
            assert!((wtv - r0.vt[0][a]).abs() < 1e-14, "{label}: W_t v");
            let dv = (rp.vt[0][a] - rm.vt[0][a]) / (2.0 * h);
            let wta: f64 = (0..n).map(|k| r0.wt[(a, k)] * acc[k]).sum();
            assert!(
                (wta - r0.gamma_t[0][a] - dv).abs() < 1e-7,
                "{label}: W_t{} a − γ_t = {} against v̇_t {dv}",
                a + 1,
                wta - r0.gamma_t[0][a]
            );
        }
        r0
    }
}
