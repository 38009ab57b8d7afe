//! Unilateral contacts at run time (issue #26; Wittenburg ch. 6, Pfeiffer
//! and Glocker, *Multibody Dynamics with Unilateral Contacts*).
//!
//! The model's generated `contacts` gives, per gap row, `g(q)`,
//! `ġ = wᵀ u`, `γ` (`g̈ = wᵀ u̇ − γ`), Newton's `e`, Coulomb's `μ` and the
//! row `w`. A run with contacts is a sequence of smooth segments, each
//! integrated by the run's integrator with the closing of every open
//! contact (`g` falling through 0) and the release of every sustained one
//! (its force `λ` falling through 0) located on the dense output as
//! terminal events; so is the turning point (`ġ` falling through 0) of a
//! contact that has just separated, so that a rebound shorter than one step
//! is not crossed twice unseen. Between segments, at the located time:
//!
//! 1. **Impact** — if a closed contact (`g ≤` [`GAP_TOL`]) approaches
//!    (`ġ < 0`): the generalised Newton law on all closed contacts,
//!    `M (u⁺ − u⁻) = Wᵀ Λ` (with the model's loop constraints held at
//!    velocity level, `J u⁺ = J u⁻`), `Λ ≥ 0`, `ġ⁺ + e ġ⁻ ≥ 0`,
//!    complementary: the linear complementarity problem
//!    `ξ = W M⁻¹ Wᵀ Λ + (1 + e) ġ⁻` solved exactly by [`lcp`].
//! 2. **Rest** — a closed contact whose speed after the impact would lift
//!    it less than the absolute tolerance (`ġ² ≤ 2 |g̈| atol`: the tail of
//!    an accumulating — Zeno — bounce sequence, or any contact with
//!    `e = 0`) loses that speed by a plastic impulse and becomes a
//!    sustained unilateral constraint: `g̈ = 0` with `λ ≥ 0` (again an
//!    LCP, on the accelerations), kept until its force `λ` falls through
//!    zero (**release**). In a model with loop constraints the contact
//!    forces act through the inverse that holds the loops, on top of the
//!    run's constrained ODE (its projection included).
//! 3. **Friction** — a row with Coulomb's `μ > 0` (plane contacts; the
//!    generated `friction` gives its tangential rows `W_t`): at an impact
//!    the Newton–Coulomb law (stick, `v_t⁺ = 0`, if the impulse fits the
//!    cone `‖Λ_t‖ ≤ μ Λ`, else slide with `Λ_t = −μ Λ s`); in sustained
//!    contact a [`Slide`], stick (`v_t = 0` held, `‖λ_t‖ ≤ μ λ`) or slip
//!    (`λ_t = −μ λ s` along the sliding direction), with the stop of a
//!    slide (**stick**) and the break of a stick (**slip**) located as
//!    events. Each is one [`Problem`]: the normal rows complementary, the
//!    tangential ones by their mode (Pfeiffer and Glocker's formulation
//!    with the modes enumerated, not a regularised friction law).
//! 4. **Redundant contacts** — several rows on few speeds (a box on four
//!    corners: 12 rows, rank 6): a mode's speeds are unique, its impulses
//!    (forces) a set; the mode is feasible if some member fits the signs
//!    and cones, and the one of minimum norm is reported (see
//!    `redundant.rs`).
//!
//! Every event is reported ([`ContactEvent`]): time, kind, per contact row
//! the normal speeds before and after and the impulse, the energy before and
//! after, the generalised impulse `M Δu` — per speed, the impulse each
//! joint's free directions receive — and every tree joint's impulse
//! (Wittenburg's joint impulses: from the generated `joint_impulses`, the
//! inverse dynamics of the velocity jump with the contact impulses as
//! loads).

use super::impulse::{Problem, Slide, Solved, impact, norm2, resting_forces};
use super::{Simulate, energy};
use crate::constrained::{ConstraintValues, DMatrix, DVector};
use crate::integrate::Stats;
use crate::integrate::by_name::{Settings, solve_with_events};
use crate::integrate::driver::{Direction, Event, EventAction, Solution, SolveOptions};
use crate::integrate::system::OdeSystem;
use crate::model::Point;

#[cfg(feature = "serde")]
use serde::{Deserialize, Serialize};

/// The generated function the runtime reads.
pub(super) const CONTACTS: &str = "contacts";

/// The generated function of the joints' impulses.
const IMPULSES: &str = "joint_impulses";

/// The generated function of the contacts' tangential rows (friction).
const FRICTION: &str = "friction";

/// A contact row counts as closed when its gap is at most this (m or rad):
/// located crossings end a few ulps past `g = 0`.
pub const GAP_TOL: f64 = 1e-9;

/// Largest set of closed contacts the exact enumeration of [`lcp`] solves
/// (`2^16` candidate active sets).
pub const MAX_LCP: usize = 16;

/// Consecutive contact events without the time advancing after which a run
/// stops (contacts that cannot be resolved).
const MAX_STALLED: usize = 64;

/// What happened at a contact event.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum ContactEventKind {
    /// Velocities jumped by the generalised Newton law.
    Impact,
    /// Contacts came to rest (a plastic impulse took their remaining
    /// normal speed) and are held as sustained unilateral constraints.
    Rest,
    /// Sustained contacts whose force fell to zero, released.
    Release,
    /// A sliding contact stopped and is held by friction (`v_t = 0`,
    /// `‖λ_t‖ ≤ μ λ`); a tangential impulse takes what is left of its
    /// sliding speed (below the slip speed, see `Run::settle`). Located
    /// where the slide's speed falls through half its slip speed, or
    /// where it reverses (`v_t · s` falling through zero).
    Stick,
    /// A sticking contact starts to slide: the friction force it needs
    /// reached the cone `‖λ_t‖ = μ λ`.
    Slip,
}

impl ContactEventKind {
    /// The snake-case name (`impact`, `rest`, `release`).
    pub fn name(self) -> &'static str {
        match self {
            ContactEventKind::Impact => "impact",
            ContactEventKind::Rest => "rest",
            ContactEventKind::Release => "release",
            ContactEventKind::Stick => "stick",
            ContactEventKind::Slip => "slip",
        }
    }
}

/// One contact row at an event.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct ContactImpulse {
    /// The contact row (`floor`, `stop.lower`).
    pub contact: String,
    /// Normal speed `ġ` before (m/s or rad/s; negative: closing).
    pub speed_before: f64,
    /// Normal speed `ġ` after.
    pub speed_after: f64,
    /// Normal impulse `Λ` (N s, or N m s for a joint limit): `≥ 0` at an
    /// impact; at a contact coming to rest the impulse that takes its
    /// remaining speed (below the rest speed), of either sign.
    pub impulse: f64,
    /// Tangential (friction) impulse along the contact's tangent axes
    /// `t1`, `t2` (N s; zero without friction).
    #[cfg_attr(feature = "serde", serde(default))]
    pub tangential_impulse: [f64; 2],
    /// Tangential speeds `v_t` of the touching point, along `t1` and `t2`,
    /// before (m/s; zero without friction).
    #[cfg_attr(feature = "serde", serde(default))]
    pub tangential_speed_before: [f64; 2],
    /// Tangential speeds after.
    #[cfg_attr(feature = "serde", serde(default))]
    pub tangential_speed_after: [f64; 2],
}

/// The impulse a tree joint transmits to the bodies it carries in an
/// impact (Wittenburg's joint impulse), in the child joint frame's axes at
/// its origin.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct JointImpulse {
    /// The joint.
    pub joint: String,
    /// Force impulse, N s.
    pub force: [f64; 3],
    /// Torque impulse about the child joint frame's origin, N m s.
    pub torque: [f64; 3],
}

/// A contact event of a run.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, Deserialize))]
pub struct ContactEvent {
    /// Time, s.
    pub t: f64,
    /// What happened.
    pub kind: ContactEventKind,
    /// The contact rows involved (for an impact every closed row, also
    /// those that carry no impulse).
    pub contacts: Vec<ContactImpulse>,
    /// Total energy before, J.
    pub energy_before: f64,
    /// Total energy after, J.
    pub energy_after: f64,
    /// `M (u⁺ − u⁻) = Wᵀ Λ (+ Jᵀ Π)`: the generalised impulse per speed
    /// (N s or N m s).
    pub generalized_impulse: Vec<f64>,
    /// Every tree joint's impulse (empty for a release; cut joints' are
    /// not reported).
    #[cfg_attr(feature = "serde", serde(default))]
    pub joint_impulses: Vec<JointImpulse>,
}

/// One evaluation of the generated `contacts` (and `friction`, if the
/// model has it).
pub(crate) struct Rows {
    pub g: Vec<f64>,
    pub gdot: Vec<f64>,
    pub gamma: Vec<f64>,
    pub e: Vec<f64>,
    pub mu: Vec<f64>,
    /// `nk × nu`.
    pub w: DMatrix<f64>,
    /// Tangential speeds `v_t` per row (zero without friction).
    pub vt: Vec<[f64; 2]>,
    /// `γ_t` with `v̇_t = W_t u̇ − γ_t`, per row.
    pub gamma_t: Vec<[f64; 2]>,
    /// `2 nk × nu`: row `2 i + a` is row `i`'s `W_t` along tangent `a`.
    pub wt: DMatrix<f64>,
}

impl Rows {
    /// The rows of `nk` contacts on `nu` speeds from the generated
    /// `contacts`, flat: `g`, `ġ`, `γ`, `e`, `μ` (each `nk`), then `w` by
    /// rows (`nk × nu`); frictionless (`v_t`, `γ_t`, `W_t` zero).
    pub(crate) fn of_contacts(nk: usize, nu: usize, v: &[f64]) -> Rows {
        let part = |k: usize| v[k * nk..(k + 1) * nk].to_vec();
        Rows {
            g: part(0),
            gdot: part(1),
            gamma: part(2),
            e: part(3),
            mu: part(4),
            w: DMatrix::from_row_slice(nk, nu, &v[5 * nk..5 * nk + nk * nu]),
            vt: vec![[0.0; 2]; nk],
            gamma_t: vec![[0.0; 2]; nk],
            wt: DMatrix::zeros(2 * nk, nu),
        }
    }

    /// Sets the tangential rows from the generated `friction` `f` of these
    /// rows' `nk` contacts on `nu` speeds (`v_t1`, `v_t2`, `γ_t1`, `γ_t2`,
    /// each `nk`, then `W_t1` and `W_t2` by rows), its speeds at columns
    /// `col..col + nu` of `wt`.
    pub(crate) fn set_friction(&mut self, f: &[f64], nu: usize, col: usize) {
        let nk = self.g.len();
        for i in 0..nk {
            for a in 0..2 {
                self.vt[i][a] = f[a * nk + i];
                self.gamma_t[i][a] = f[(2 + a) * nk + i];
                for k in 0..nu {
                    self.wt[(2 * i + a, col + k)] = f[4 * nk + a * nk * nu + i * nu + k];
                }
            }
        }
    }

    /// Row `i` has Coulomb friction.
    fn rough(&self, i: usize) -> bool {
        self.mu[i] > 0.0
    }

    /// `W_n` of the rows `set` (`set.len() × nu`).
    fn normal(&self, set: &[usize]) -> DMatrix<f64> {
        DMatrix::from_fn(set.len(), self.w.ncols(), |i, k| self.w[(set[i], k)])
    }

    /// `W_t,a` of row `i` dotted with `x`.
    pub(crate) fn tangential_dot(&self, i: usize, a: usize, x: &DVector<f64>) -> f64 {
        (0..self.wt.ncols())
            .map(|k| self.wt[(2 * i + a, k)] * x[k])
            .sum()
    }
}

/// The number of contact rows of `model` (0 without contacts).
pub(super) fn count<S: Simulate + ?Sized>(model: &S) -> usize {
    let nu = model.nu();
    model.function_len(CONTACTS).map_or(0, |len| len / (5 + nu))
}

/// The contact rows at `(t, q, u)`.
pub(super) fn rows<S: Simulate + ?Sized>(
    model: &S,
    nk: usize,
    t: f64,
    q: &[f64],
    u: &[f64],
) -> Option<Rows> {
    let nu = model.nu();
    let mut v = vec![0.0; 5 * nk + nk * nu];
    let at = Point {
        t,
        q,
        u,
        ..Point::default()
    };
    if !model.evaluate(CONTACTS, &at, &mut v) {
        return None;
    }
    let mut r = Rows::of_contacts(nk, nu, &v);
    let len = nk * (4 + 2 * nu);
    if model.function_len(FRICTION) == Some(len) {
        let mut f = vec![0.0; len];
        if !model.evaluate(FRICTION, &at, &mut f) {
            return None;
        }
        r.set_friction(&f, nu, 0);
    }
    Some(r)
}

/// A model whose sustained contacts `active` hold `g̈ = 0`, those with
/// friction by their [`Slide`]: the run's ODE `free` (the tree, or the
/// tree with its loop constraints and their projection) plus the contact
/// forces, `u̇ = u̇_free + M⁻¹ (Wᵀ λ + W_tᵀ λ_t)` with `M⁻¹` the inverse
/// that holds the loops (`J Δu̇ = 0`).
struct Contacting<'a, S: ?Sized, O> {
    model: &'a S,
    free: &'a O,
    nk: usize,
    active: Vec<usize>,
    /// Per active row (`None`: frictionless); a sliding row's direction is
    /// the one it started with, followed by `v_t` while `v_t · s > 0`.
    slides: Vec<Option<Slide>>,
}

/// The speeds' rates of the ODE `free` at `(t, y)`.
fn free_rates<const N: usize, S: Simulate + ?Sized, O: OdeSystem<N>>(
    model: &S,
    free: &O,
    t: f64,
    y: &[f64; N],
) -> DVector<f64> {
    let (nq, nu) = (model.nq(), model.nu());
    let mut dy = [0.0; N];
    free.rhs(t, y, &mut dy);
    DVector::from_column_slice(&dy[nq..nq + nu])
}

/// The loop constraints' Jacobian of `model` at `(t, q, u)`, if it has any.
fn loop_jacobian<S: Simulate + ?Sized>(
    model: &S,
    t: f64,
    q: &[f64],
    u: &[f64],
) -> Option<DMatrix<f64>> {
    let (nc, nu) = (model.nc(), model.nu());
    (nc > 0).then(|| {
        let mut c = ConstraintValues::zeros(nc, nu);
        model.constraints(t, q, u, &mut c);
        c.jacobian
    })
}

impl<S: Simulate + ?Sized, O> Contacting<'_, S, O> {
    /// `u̇`, the normal forces `λ` of the active rows and their friction
    /// forces `λ_t`, and the rows.
    fn accelerations<const N: usize>(
        &self,
        t: f64,
        y: &[f64; N],
    ) -> Option<(DVector<f64>, Solved, Rows)>
    where
        O: OdeSystem<N>,
    {
        let (nq, nu) = (self.model.nq(), self.model.nu());
        let (q, u) = (&y[..nq], &y[nq..nq + nu]);
        let free = free_rates(self.model, self.free, t, y);
        let j = loop_jacobian(self.model, t, q, u);
        let r = rows(self.model, self.nk, t, q, u)?;
        let mut m = DMatrix::zeros(nu, nu);
        self.model.mass_matrix(t, q, &mut m);
        let slide: Vec<Option<Slide>> = self
            .active
            .iter()
            .zip(&self.slides)
            .map(|(&i, s)| match s {
                Some(Slide::Slip(s0)) => {
                    let v = r.vt[i];
                    let nv = norm2(v);
                    Some(Slide::Slip(
                        if nv > 0.0 && v[0] * s0[0] + v[1] * s0[1] > 0.0 {
                            [v[0] / nv, v[1] / nv]
                        } else {
                            *s0
                        },
                    ))
                }
                other => *other,
            })
            .collect();
        let set = &self.active;
        let wn = r.normal(set);
        let b = &wn * &free - DVector::from_fn(set.len(), |k, _| r.gamma[set[k]]);
        let bt = set
            .iter()
            .map(|&i| [0, 1].map(|a| r.tangential_dot(i, a, &free) - r.gamma_t[i][a]))
            .collect();
        let sol = Problem {
            m: &m,
            j: j.as_ref(),
            r: &r,
            set,
            slide: &slide,
            b,
            bt,
            held: true,
        }
        .solve()?;
        Some((free + &sol.du, sol, r))
    }
}

impl<const N: usize, S: Simulate + ?Sized, O: OdeSystem<N>> OdeSystem<N> for Contacting<'_, S, O> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let (nq, nu) = (self.model.nq(), self.model.nu());
        let (q, u) = y.split_at(nq);
        let (dq, du) = dy.split_at_mut(nq);
        self.model.qdot(q, &u[..nu], dq);
        match self.accelerations(t, y) {
            Some((a, _, _)) => du[..nu].copy_from_slice(a.as_slice()),
            None => du.iter_mut().for_each(|x| *x = f64::NAN),
        }
    }
    fn project(&self, t: f64, y: &mut [f64; N]) -> bool {
        // The free system's projection: quaternion norms, and for models
        // with loops their position and velocity constraints.
        self.free.project(t, y)
    }
}

/// Appends segment `s` to the run `all`.
fn append<const N: usize>(all: &mut Solution<N>, s: Solution<N>) {
    all.t.extend(s.t);
    all.y.extend(s.y);
    all.t_out.extend(s.t_out);
    all.y_out.extend(s.y_out);
    let (a, b) = (&mut all.stats, &s.stats);
    *a = Stats {
        steps: a.steps + b.steps,
        accepted: a.accepted + b.accepted,
        rejected: a.rejected + b.rejected,
        rhs_evals: a.rhs_evals + b.rhs_evals,
        jac_evals: a.jac_evals + b.jac_evals,
        lu_decomps: a.lu_decomps + b.lu_decomps,
        newton_iters: a.newton_iters + b.newton_iters,
        stiffness_detections: a.stiffness_detections + b.stiffness_detections,
        stiff_at: a.stiff_at.or(b.stiff_at),
    };
    all.t_final = s.t_final;
    all.y_final = s.y_final;
    all.stop = s.stop;
}

/// The sustained contacts between segments: the active rows and, per
/// contact row, its [`Slide`] while active with friction.
pub(super) struct Sustained {
    active: Vec<usize>,
    slides: Vec<Option<Slide>>,
}

/// How a run with contacts goes: the model, its rows, the rest height.
pub(super) struct Run<'a, S: ?Sized> {
    pub model: &'a S,
    pub names: &'a [String],
    /// The tree joints of `joint_impulses`.
    pub joints: &'a [String],
    pub nk: usize,
    /// The height below which a rebound is a contact at rest, m or rad;
    /// likewise the distance below which a slide is a contact sticking.
    pub rest_height: f64,
}

impl<S: Simulate + ?Sized> Run<'_, S> {
    fn name(&self, i: usize) -> String {
        self.names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("contact row {i}"))
    }

    /// The loop constraints' Jacobian at `(t, q, u)`, if the model has any.
    fn jacobian(&self, t: f64, q: &[f64], u: &[f64]) -> Option<DMatrix<f64>> {
        loop_jacobian(self.model, t, q, u)
    }

    /// The event record of a jump `sol` on the rows `set` from `y` (before
    /// it) to `after`.
    #[allow(clippy::too_many_arguments)]
    fn record<const N: usize>(
        &self,
        t: f64,
        kind: ContactEventKind,
        set: &[usize],
        before: (&Rows, &[f64; N]),
        after: (&Rows, &[f64; N]),
        sol: &Solved,
        m: &DMatrix<f64>,
    ) -> ContactEvent {
        let nk = self.nk;
        let mut ln = vec![0.0; nk];
        let mut lt = vec![[0.0; 2]; nk];
        for (k, &i) in set.iter().enumerate() {
            ln[i] = sol.ln[k];
            lt[i] = sol.lt[k];
        }
        ContactEvent {
            t,
            kind,
            contacts: set
                .iter()
                .enumerate()
                .map(|(k, &i)| ContactImpulse {
                    contact: self.name(i),
                    speed_before: before.0.gdot[i],
                    speed_after: after.0.gdot[i],
                    impulse: sol.ln[k],
                    tangential_impulse: sol.lt[k],
                    tangential_speed_before: before.0.vt[i],
                    tangential_speed_after: after.0.vt[i],
                })
                .collect(),
            energy_before: energy(self.model, t, &before.1[..]),
            energy_after: energy(self.model, t, &after.1[..]),
            generalized_impulse: (m * &sol.du).as_slice().to_vec(),
            joint_impulses: self.joint_impulses(t, before.1, sol.du.as_slice(), &ln, &lt),
        }
    }

    /// The slip speed of row `i`: a slide slower than this would stop
    /// within the rest height against its friction and drive, so the row is
    /// tested for sticking (`v_t² ≤ 2 a h`).
    fn slip_speed(&self, r: &Rows, i: usize, free: &DVector<f64>) -> f64 {
        let drive = norm2([0, 1].map(|a| r.tangential_dot(i, a, free) - r.gamma_t[i][a]));
        let normal: f64 = (0..free.len()).map(|k| r.w[(i, k)] * free[k]).sum::<f64>() - r.gamma[i];
        (2.0 * (drive + r.mu[i] * normal.abs()) * self.rest_height).sqrt()
    }

    /// Resolves the contacts at `(t, y)`: impacts, contacts coming to rest,
    /// sticking, slipping and released; updates `y`'s speeds and the
    /// sustained contacts.
    fn settle<const N: usize, O: OdeSystem<N>>(
        &self,
        free_ode: &O,
        t: f64,
        y: &mut [f64; N],
        state: &mut Sustained,
        events: &mut Vec<ContactEvent>,
    ) -> Result<(), String> {
        let (nq, nu, nk) = (self.model.nq(), self.model.nu(), self.nk);
        let fail = |what: &str| format!("{what} at t = {t} s");
        let read = |y: &[f64; N]| {
            rows(self.model, nk, t, &y[..nq], &y[nq..nq + nu])
                .ok_or_else(|| fail("the generated `contacts` could not be evaluated"))
        };
        let mass = |y: &[f64; N]| {
            let mut m = DMatrix::zeros(nu, nu);
            self.model.mass_matrix(t, &y[..nq], &mut m);
            m
        };
        let no_solution = |n: usize| {
            fail(&format!(
                "the impact of {n} contact(s) has no solution (a singular mass matrix, more than {MAX_LCP} contacts closed at once, or no impulse satisfying Newton–Coulomb found by the mode search or the cone solver)"
            ))
        };
        let mut r = read(y)?;
        let closed: Vec<usize> = (0..nk).filter(|&i| r.g[i] <= GAP_TOL).collect();
        if closed
            .iter()
            .any(|&i| r.gdot[i] < 0.0 && !state.active.contains(&i))
        {
            let m = mass(y);
            let j = self.jacobian(t, &y[..nq], &y[nq..nq + nu]);
            let slides: Vec<Option<Slide>> = closed
                .iter()
                .map(|&i| r.rough(i).then_some(Slide::Stick))
                .collect();
            let e = |i: usize| r.e[i];
            let sol = impact(&m, j.as_ref(), &r, &closed, &e, false, &slides)
                .ok_or_else(|| no_solution(closed.len()))?;
            let before = *y;
            for k in 0..nu {
                y[nq + k] += sol.du[k];
            }
            let after = read(y)?;
            events.push(self.record(
                t,
                ContactEventKind::Impact,
                &closed,
                (&r, &before),
                (&after, y),
                &sol,
                &m,
            ));
            r = after;
        }
        // Contacts at rest: closed rows too slow to lift off by more than
        // the rest height against their acceleration.
        let free = free_rates(self.model, free_ode, t, y);
        let resting: Vec<usize> = closed
            .iter()
            .copied()
            .filter(|&i| {
                let acc: f64 = (0..nu).map(|k| r.w[(i, k)] * free[k]).sum::<f64>() - r.gamma[i];
                r.gdot[i] * r.gdot[i] <= 2.0 * acc.abs() * self.rest_height
            })
            .collect();
        if resting.is_empty() {
            if !state.active.is_empty() {
                self.release(t, y, std::mem::take(&mut state.active), events);
            }
            return Ok(());
        }
        // The force problem: g̈ = W M⁻¹ (Wᵀ λ + W_tᵀ λ_t) + (W u̇_free − γ)
        // ≥ 0, λ ≥ 0; rows with friction slide along v_t if faster than
        // their slip speed, else stick if the force they need fits the
        // cone (with a margin, so that a stick that has just broken is not
        // taken up again), else slide the way that force would push them.
        let m = mass(y);
        let j = self.jacobian(t, &y[..nq], &y[nq..nq + nu]);
        let mut slides: Vec<Option<Slide>> = resting
            .iter()
            .map(|&i| {
                r.rough(i).then(|| {
                    let v = r.vt[i];
                    let nv = norm2(v);
                    if nv > self.slip_speed(&r, i, &free) {
                        Slide::Slip([v[0] / nv, v[1] / nv])
                    } else {
                        Slide::Stick
                    }
                })
            })
            .collect();
        let wn = r.normal(&resting);
        let b = &wn * &free - DVector::from_fn(resting.len(), |k, _| r.gamma[resting[k]]);
        let bt: Vec<[f64; 2]> = resting
            .iter()
            .map(|&i| [0, 1].map(|a| r.tangential_dot(i, a, &free) - r.gamma_t[i][a]))
            .collect();
        let Some(forces) =
            resting_forces(&m, j.as_ref(), &r, &resting, &mut slides, &b, &bt, &|_| {
                1e-6
            })
        else {
            return Err(fail(&format!(
                "the contact forces of {} resting contact(s) have no solution",
                resting.len()
            )));
        };
        let scale = forces.ln.amax().max(f64::MIN_POSITIVE);
        let carrying: Vec<usize> = (0..resting.len())
            .filter(|&k| forces.ln[k] > 1e-12 * scale && forces.ln[k] > 0.0)
            .collect();
        let now: Vec<usize> = carrying.iter().map(|&k| resting[k]).collect();
        let now_slides: Vec<Option<Slide>> = carrying.iter().map(|&k| slides[k]).collect();
        let released: Vec<usize> = state
            .active
            .iter()
            .copied()
            .filter(|i| !now.contains(i))
            .collect();
        if !released.is_empty() {
            self.release(t, y, released, events);
        }
        let arriving: Vec<usize> = now
            .iter()
            .copied()
            .filter(|i| !state.active.contains(i))
            .collect();
        // Rows that stay and change between sticking and sliding.
        let mut to_stick = Vec::new();
        let mut to_slip = Vec::new();
        for (k, &i) in now.iter().enumerate() {
            if !state.active.contains(&i) {
                continue;
            }
            match (state.slides[i], now_slides[k]) {
                (Some(Slide::Slip(_)), Some(Slide::Stick)) => to_stick.push(i),
                (Some(Slide::Stick), Some(Slide::Slip(_))) => to_slip.push(i),
                _ => {}
            }
        }
        if !arriving.is_empty() || !to_stick.is_empty() {
            // The remaining normal speed of the arriving contacts (below
            // the rest speed, of either sign: the tail of a Zeno sequence,
            // whose bounces would exchange that momentum with the floor)
            // and the remaining sliding speed of the sticking ones taken by
            // one impulse; the sustained ones keep ġ = 0.
            let plastic = |_: usize| 0.0;
            let sol = impact(&m, j.as_ref(), &r, &now, &plastic, true, &now_slides)
                .ok_or_else(|| no_solution(now.len()))?;
            let before = *y;
            for k in 0..nu {
                y[nq + k] += sol.du[k];
            }
            let after = read(y)?;
            let kind = if arriving.is_empty() {
                ContactEventKind::Stick
            } else {
                ContactEventKind::Rest
            };
            events.push(self.record(t, kind, &now, (&r, &before), (&after, y), &sol, &m));
        }
        if !to_slip.is_empty() {
            let mut ev = self.quiet(t, y, &to_slip, ContactEventKind::Slip);
            for c in ev.contacts.iter_mut() {
                if let Some(k) = now.iter().position(|&i| self.name(i) == c.contact) {
                    c.impulse = forces.ln[carrying[k]];
                    c.tangential_impulse = forces.lt[carrying[k]];
                }
            }
            events.push(ev);
        }
        state.slides = vec![None; nk];
        for (&i, s) in now.iter().zip(&now_slides) {
            state.slides[i] = *s;
        }
        state.active = now;
        Ok(())
    }

    /// An event without a velocity jump on the rows `set` (a release, the
    /// start of a slide): impulses zero.
    fn quiet<const N: usize>(
        &self,
        t: f64,
        y: &[f64; N],
        set: &[usize],
        kind: ContactEventKind,
    ) -> ContactEvent {
        let (nq, nu) = (self.model.nq(), self.model.nu());
        let r = rows(self.model, self.nk, t, &y[..nq], &y[nq..nq + nu]);
        let e = energy(self.model, t, &y[..]);
        ContactEvent {
            t,
            kind,
            contacts: set
                .iter()
                .map(|&i| {
                    let (gd, vt) = r
                        .as_ref()
                        .map_or((f64::NAN, [f64::NAN; 2]), |r| (r.gdot[i], r.vt[i]));
                    ContactImpulse {
                        contact: self.name(i),
                        speed_before: gd,
                        speed_after: gd,
                        impulse: 0.0,
                        tangential_impulse: [0.0; 2],
                        tangential_speed_before: vt,
                        tangential_speed_after: vt,
                    }
                })
                .collect(),
            energy_before: e,
            energy_after: e,
            generalized_impulse: vec![0.0; nu],
            joint_impulses: Vec::new(),
        }
    }

    fn release<const N: usize>(
        &self,
        t: f64,
        y: &[f64; N],
        rows_released: Vec<usize>,
        events: &mut Vec<ContactEvent>,
    ) {
        events.push(self.quiet(t, y, &rows_released, ContactEventKind::Release));
    }

    /// The tree joints' impulses of the jump `du` at `(t, y)` (before it)
    /// from the contact impulses `ln` and, with friction, `lt` (one per
    /// row), by the generated `joint_impulses`; empty if the model has
    /// none.
    fn joint_impulses<const N: usize>(
        &self,
        t: f64,
        y: &[f64; N],
        du: &[f64],
        ln: &[f64],
        lt: &[[f64; 2]],
    ) -> Vec<JointImpulse> {
        let (nq, nu, nk, nj) = (self.model.nq(), self.model.nu(), self.nk, self.joints.len());
        let plain = 6 * nj * (1 + nk);
        let rough = 6 * nj * (1 + 3 * nk);
        let len = match self.model.function_len(IMPULSES) {
            Some(l) if nj > 0 && (l == plain || l == rough) => l,
            _ => return Vec::new(),
        };
        let mut v = vec![0.0; len];
        let at = Point {
            t,
            q: &y[..nq],
            u: &y[nq..nq + nu],
            udot: du,
            ..Point::default()
        };
        if !self.model.evaluate(IMPULSES, &at, &mut v) {
            return Vec::new();
        }
        let block = |b: usize, j: usize, a: usize| v[6 * nj * b + 6 * j + a];
        (0..nj)
            .map(|j| {
                let c: Vec<f64> = (0..6)
                    .map(|a| {
                        let mut x = block(0, j, a)
                            + (0..nk).map(|r| ln[r] * block(1 + r, j, a)).sum::<f64>();
                        if len == rough {
                            x += (0..2)
                                .flat_map(|d| (0..nk).map(move |r| (d, r)))
                                .map(|(d, r)| lt[r][d] * block(1 + nk + d * nk + r, j, a))
                                .sum::<f64>();
                        }
                        x
                    })
                    .collect();
                JointImpulse {
                    joint: self.joints[j].clone(),
                    force: [c[0], c[1], c[2]],
                    torque: [c[3], c[4], c[5]],
                }
            })
            .collect()
    }

    /// Integrates from `(0, y0)` to `t_end` through every contact event.
    /// `free` is the ODE without sustained contacts. Returns the run as one
    /// solution, its events, and the reason it could not go on, if any.
    pub fn run<const N: usize, O: OdeSystem<N>>(
        &self,
        free: &O,
        settings: &Settings,
        mut y: [f64; N],
        t_end: f64,
        opts: &SolveOptions,
    ) -> (Solution<N>, Vec<ContactEvent>, Option<(f64, String)>) {
        let (nq, nu, nk) = (self.model.nq(), self.model.nu(), self.nk);
        let mut all = Solution {
            t: Vec::new(),
            y: Vec::new(),
            t_out: Vec::new(),
            y_out: Vec::new(),
            events: Vec::new(),
            t_final: 0.0,
            y_final: y,
            stats: Stats::default(),
            stop: crate::integrate::StopReason::Finished,
        };
        let mut events = Vec::new();
        let mut state = Sustained {
            active: Vec::new(),
            slides: vec![None; nk],
        };
        let mut t = 0.0;
        let mut stalled = 0;
        let mut opts = opts.clone();
        loop {
            if let Err(message) = self.settle(free, t, &mut y, &mut state, &mut events) {
                all.t_final = t;
                all.y_final = y;
                return (all, events, Some((t, message)));
            }
            // Samples already written stay written.
            opts.t_eval.retain(|&s| s > t || (t == 0.0 && s == 0.0));
            let gap = |i: usize| {
                move |t: f64, y: &[f64; N]| {
                    rows(self.model, nk, t, &y[..nq], &y[nq..nq + nu]).map_or(f64::NAN, |r| r.g[i])
                }
            };
            let active = state.active.clone();
            let contacting = Contacting {
                model: self.model,
                free,
                nk,
                active: active.clone(),
                slides: active.iter().map(|&i| state.slides[i]).collect(),
            };
            let mut list: Vec<Event<'_, N>> = (0..nk)
                .filter(|i| !active.contains(i))
                .map(|i| Event::new(gap(i), Direction::Falling, EventAction::Stop))
                .collect();
            // A contact leaving (closed, separating) is watched until its
            // speed turns: a rebound shorter than one step would otherwise
            // cross g = 0 twice inside it, unseen.
            let start = rows(self.model, nk, t, &y[..nq], &y[nq..nq + nu]);
            for i in (0..nk).filter(|i| !active.contains(i)) {
                if start
                    .as_ref()
                    .is_some_and(|r| r.g[i] <= GAP_TOL && r.gdot[i] > 0.0)
                {
                    list.push(Event::new(
                        move |t: f64, y: &[f64; N]| {
                            rows(self.model, nk, t, &y[..nq], &y[nq..nq + nu])
                                .map_or(f64::NAN, |r| r.gdot[i])
                        },
                        Direction::Falling,
                        EventAction::Stop,
                    ));
                }
            }
            for (pos, &i) in active.iter().enumerate() {
                let c = &contacting;
                // Release: the normal force falls through zero.
                list.push(Event::new(
                    move |t: f64, y: &[f64; N]| {
                        c.accelerations(t, y)
                            .map_or(f64::NAN, |(_, s, _)| s.ln[pos])
                    },
                    Direction::Falling,
                    EventAction::Stop,
                ));
                match state.slides[i] {
                    // Slip: the friction force the stick needs reaches
                    // the cone, μ λ − ‖λ_t‖ falls through zero.
                    Some(Slide::Stick) => list.push(Event::new(
                        move |t: f64, y: &[f64; N]| {
                            c.accelerations(t, y).map_or(f64::NAN, |(_, s, r)| {
                                r.mu[i] * s.ln[pos] - norm2(s.lt[pos])
                            })
                        },
                        Direction::Falling,
                        EventAction::Stop,
                    )),
                    // A slide reverses (or turns by more than a right
                    // angle): v_t · s falls through zero.
                    Some(Slide::Slip(s0)) => {
                        list.push(Event::new(
                            move |t: f64, y: &[f64; N]| {
                                rows(self.model, nk, t, &y[..nq], &y[nq..nq + nu])
                                    .map_or(f64::NAN, |r| r.vt[i][0] * s0[0] + r.vt[i][1] * s0[1])
                            },
                            Direction::Falling,
                            EventAction::Stop,
                        ));
                        // A slide stops: its speed falls through half its
                        // slip speed (below which `settle` tests it for
                        // sticking). A slide whose direction turns as it
                        // slows (friction turns the body: one corner of a
                        // box) reaches v_t = 0 with v_t · s > 0, and
                        // without this event the integrator would follow
                        // it into v_t = 0, where the sliding direction is
                        // undefined, in steps of picoseconds.
                        list.push(Event::new(
                            move |t: f64, y: &[f64; N]| {
                                rows(self.model, nk, t, &y[..nq], &y[nq..nq + nu]).map_or(
                                    f64::NAN,
                                    |r| {
                                        let free = free_rates(self.model, free, t, y);
                                        norm2(r.vt[i]) - 0.5 * self.slip_speed(&r, i, &free)
                                    },
                                )
                            },
                            Direction::Falling,
                            EventAction::Stop,
                        ));
                    }
                    None => {}
                }
            }
            let seg = if active.is_empty() {
                solve_with_events(settings, free, t, y, t_end, &opts, &mut list)
            } else {
                solve_with_events(settings, &contacting, t, y, t_end, &opts, &mut list)
            };
            drop(list);
            let (t_new, y_new, stop) = (seg.t_final, seg.y_final, seg.stop);
            append(&mut all, seg);
            if !matches!(stop, crate::integrate::StopReason::EventStop { .. }) {
                return (all, events, None);
            }
            all.stop = crate::integrate::StopReason::Finished;
            stalled = if t_new - t <= 4.0 * f64::EPSILON * t.abs().max(1.0) {
                stalled + 1
            } else {
                0
            };
            if stalled > MAX_STALLED {
                let message = format!(
                    "{MAX_STALLED} contact events at t = {t_new} s without the time advancing (contacts that cannot be resolved)"
                );
                return (all, events, Some((t_new, message)));
            }
            t = t_new;
            y = y_new;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.81;

    /// A free box (m = 2 kg, `I = diag(0.02, 0.03, 0.04)`, speeds `v`, `ω`
    /// in the world axes) on its four corners `(±0.2, ±0.15, −0.06)` on the
    /// floor `z = 0`, μ = 0.5, e = 0.5, at the speeds `u` (`γ = 0`: no
    /// spin): the mass matrix and the rows.
    fn box_rows(u: [f64; 6]) -> (DMatrix<f64>, Rows) {
        let h = -0.06;
        let corners = [(0.2, 0.15), (-0.2, 0.15), (-0.2, -0.15), (0.2, -0.15)];
        // Rows of v + ω × r, r = (x, y, h): along z, then x and y.
        let w: Vec<f64> = corners
            .iter()
            .flat_map(|&(x, y)| [0.0, 0.0, 1.0, y, -x, 0.0])
            .collect();
        let wt: Vec<f64> = corners
            .iter()
            .flat_map(|&(x, y)| [1.0, 0.0, 0.0, 0.0, h, -y, 0.0, 1.0, 0.0, -h, 0.0, x])
            .collect();
        let (w, wt) = (
            DMatrix::from_row_slice(4, 6, &w),
            DMatrix::from_row_slice(8, 6, &wt),
        );
        let u = DVector::from_row_slice(&u);
        let (gdot, vt) = (&w * &u, &wt * &u);
        let m = DMatrix::from_diagonal(&DVector::from_vec(vec![2.0, 2.0, 2.0, 0.02, 0.03, 0.04]));
        let rows = Rows {
            g: vec![0.0; 4],
            gdot: gdot.as_slice().to_vec(),
            gamma: vec![0.0; 4],
            e: vec![0.5; 4],
            mu: vec![0.5; 4],
            w,
            vt: (0..4).map(|k| [vt[2 * k], vt[2 * k + 1]]).collect(),
            gamma_t: vec![[0.0; 2]; 4],
            wt,
        };
        (m, rows)
    }

    /// At rest under gravity (`u̇_free = (0, 0, −g, 0, 0, 0)`), pushed
    /// along x by `p` N: the force problem `settle` solves (sticking rows,
    /// complementary normals) and the held one of the sustained motion.
    /// The four normal forces carry `m g`, the friction forces `−p`, and
    /// the box does not accelerate; without a push the minimum-norm forces
    /// are `m g/4` each and no friction. A redundant block (4 + 8 rows on
    /// 6 speeds).
    #[test]
    fn resting_box_on_four_corners_carries_m_g() {
        let set = [0, 1, 2, 3];
        let slide = [Some(Slide::Stick); 4];
        for p in [0.0, 5.0] {
            let (m, r) = box_rows([0.0; 6]);
            let free = DVector::from_vec(vec![p / 2.0, 0.0, -G, 0.0, 0.0, 0.0]);
            let b = r.normal(&set) * &free;
            let bt: Vec<[f64; 2]> = set
                .iter()
                .map(|&i| [0, 1].map(|a| r.tangential_dot(i, a, &free)))
                .collect();
            for held in [false, true] {
                let sol = Problem {
                    m: &m,
                    j: None,
                    r: &r,
                    set: &set,
                    slide: &slide,
                    b: b.clone(),
                    bt: bt.clone(),
                    held,
                }
                .solve()
                .unwrap_or_else(|| panic!("p {p}, held {held}: no solution"));
                let sum: f64 = sol.ln.iter().sum();
                let fx: f64 = sol.lt.iter().map(|l| l[0]).sum();
                let fy: f64 = sol.lt.iter().map(|l| l[1]).sum();
                assert!(
                    (sum - 2.0 * G).abs() < 1e-12 && (fx + p).abs() < 1e-12 && fy.abs() < 1e-12,
                    "p {p}, held {held}: Σ λ = {sum}, want m g = {}; Σ λ_t = ({fx}, {fy}), want ({}, 0)",
                    2.0 * G,
                    -p
                );
                let acc = &free + &sol.du;
                assert!(acc.amax() < 1e-12, "p {p}, held {held}: u̇ = {acc}");
                for k in 0..4 {
                    assert!(
                        sol.ln[k] > 0.0 && norm2(sol.lt[k]) <= 0.5 * sol.ln[k],
                        "p {p}, held {held}: row {k}: λ = {}, λ_t = {:?}",
                        sol.ln[k],
                        sol.lt[k]
                    );
                    if p == 0.0 {
                        assert!(
                            (sol.ln[k] - 2.0 * G / 4.0).abs() < 1e-12 && norm2(sol.lt[k]) < 1e-12,
                            "held {held}: row {k}: λ = {}, λ_t = {:?}; want m g/4, 0",
                            sol.ln[k],
                            sol.lt[k]
                        );
                    }
                }
            }
        }
    }

    /// Dropped flat at 2 m/s onto four sticking corners (e = 0.5): the
    /// impact map's impulses are `m (1 + e) v⁻/4 = 1.5` N s each (the
    /// minimum-norm choice) and the box rebounds at `e v⁻` without turning.
    #[test]
    fn box_dropped_flat_gets_four_equal_impulses() {
        let (m, r) = box_rows([0.0, 0.0, -2.0, 0.0, 0.0, 0.0]);
        let set = [0, 1, 2, 3];
        let slides = [Some(Slide::Stick); 4];
        let sol = impact(&m, None, &r, &set, &|i| r.e[i], false, &slides).expect("solvable");
        for k in 0..4 {
            assert!(
                (sol.ln[k] - 1.5).abs() < 1e-12 && norm2(sol.lt[k]) < 1e-12,
                "row {k}: Λ = {}, Λ_t = {:?}; want 1.5, 0",
                sol.ln[k],
                sol.lt[k]
            );
        }
        let want = [0.0, 0.0, 3.0, 0.0, 0.0, 0.0];
        assert!(
            sol.du.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12),
            "Δu = {}, want {want:?}",
            sol.du
        );
    }
}
