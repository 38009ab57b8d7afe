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
//!    zero (**release**).
//!
//! Every event is reported ([`ContactEvent`]): time, kind, per contact row
//! the normal speeds before and after and the impulse, the energy before and
//! after, the generalised impulse `M Δu` — per speed, the impulse each
//! joint's free directions receive — and every tree joint's impulse
//! (Wittenburg's joint impulses: from the generated `joint_impulses`, the
//! inverse dynamics of the velocity jump with the contact impulses as
//! loads).

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
}

impl ContactEventKind {
    /// The snake-case name (`impact`, `rest`, `release`).
    pub fn name(self) -> &'static str {
        match self {
            ContactEventKind::Impact => "impact",
            ContactEventKind::Rest => "rest",
            ContactEventKind::Release => "release",
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

/// Solves the linear complementarity problem `ξ = A x + b`, `x ≥ 0`,
/// `ξ ≥ 0`, `xᵀ ξ = 0` exactly by enumerating the active sets, smallest
/// first (at most [`MAX_LCP`] unknowns). For the impact and contact
/// problems `A = W M⁻¹ Wᵀ` is symmetric positive semi-definite, and a
/// solution exists whenever the problem is feasible; `None` if none is
/// found (or too many unknowns).
pub fn lcp(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    let n = b.len();
    if n == 0 {
        return Some(DVector::zeros(0));
    }
    if n > MAX_LCP || a.nrows() != n || a.ncols() != n {
        return None;
    }
    let scale = b.amax().max(f64::MIN_POSITIVE);
    let mut masks: Vec<u32> = (0..1u32 << n).collect();
    masks.sort_by_key(|m| (m.count_ones(), *m));
    for mask in masks {
        let idx: Vec<usize> = (0..n).filter(|i| mask >> i & 1 == 1).collect();
        let mut x = DVector::zeros(n);
        if !idx.is_empty() {
            let k = idx.len();
            let sub = DMatrix::from_fn(k, k, |i, j| a[(idx[i], idx[j])]);
            let rhs = DVector::from_fn(k, |i, _| -b[idx[i]]);
            let Some(sol) = sub.lu().solve(&rhs) else {
                continue;
            };
            let big = sol.amax();
            if sol.iter().any(|v| !v.is_finite() || *v < -1e-10 * big) {
                continue;
            }
            // A singular block solved by round-off: check the equations.
            let check = DMatrix::from_fn(k, k, |i, j| a[(idx[i], idx[j])]) * &sol - &rhs;
            if check.amax() > 1e-9 * scale {
                continue;
            }
            for (i, &r) in idx.iter().enumerate() {
                x[r] = sol[i].max(0.0);
            }
        }
        let xi = a * &x + b;
        if (0..n).all(|i| mask >> i & 1 == 1 || xi[i] >= -1e-10 * scale) {
            return Some(x);
        }
    }
    None
}

/// One evaluation of the generated `contacts`.
pub(super) struct Rows {
    pub g: Vec<f64>,
    pub gdot: Vec<f64>,
    pub gamma: Vec<f64>,
    pub e: Vec<f64>,
    pub mu: Vec<f64>,
    /// `nk × nu`.
    pub w: DMatrix<f64>,
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
    let part = |k: usize| v[k * nk..(k + 1) * nk].to_vec();
    Some(Rows {
        g: part(0),
        gdot: part(1),
        gamma: part(2),
        e: part(3),
        mu: part(4),
        w: DMatrix::from_row_slice(nk, nu, &v[5 * nk..]),
    })
}

/// `M⁻¹ R` with the loop constraints `J Δu = 0` held: the first `n_u`
/// rows of `[[M, Jᵀ], [J, 0]]⁻¹ [R; 0]` (least squares on redundant
/// constraints).
fn effective_inverse(
    m: &DMatrix<f64>,
    j: Option<&DMatrix<f64>>,
    r: &DMatrix<f64>,
) -> Option<DMatrix<f64>> {
    let nu = m.nrows();
    let x = match j.filter(|j| j.nrows() > 0) {
        None => m.clone().cholesky().map(|c| c.solve(r))?,
        Some(j) => {
            let nc = j.nrows();
            let mut k = DMatrix::zeros(nu + nc, nu + nc);
            k.view_mut((0, 0), (nu, nu)).copy_from(m);
            k.view_mut((nu, 0), (nc, nu)).copy_from(j);
            k.view_mut((0, nu), (nu, nc)).copy_from(&j.transpose());
            let mut rhs = DMatrix::zeros(nu + nc, r.ncols());
            rhs.view_mut((0, 0), (nu, r.ncols())).copy_from(r);
            let eps = 1e-12 * k.amax().max(f64::MIN_POSITIVE);
            let x = k.svd(true, true).solve(&rhs, eps).ok()?;
            x.rows(0, nu).into_owned()
        }
    };
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// The generalised Newton law on the contact rows `set`: `Δu` and the
/// impulses `Λ` (one per row of `set`) with `ġ⁺ + e ġ⁻ ≥ 0`, or with
/// `equality` `ġ⁺ = −e ġ⁻` on every row.
fn impact_map(
    m: &DMatrix<f64>,
    j: Option<&DMatrix<f64>>,
    r: &Rows,
    set: &[usize],
    e: &dyn Fn(usize) -> f64,
    equality: bool,
) -> Option<(DVector<f64>, DVector<f64>)> {
    let nu = m.nrows();
    let w = DMatrix::from_fn(set.len(), nu, |i, k| r.w[(set[i], k)]);
    let x = effective_inverse(m, j, &w.transpose())?;
    let g = &w * &x;
    let b = DVector::from_fn(set.len(), |i, _| (1.0 + e(set[i])) * r.gdot[set[i]]);
    let lambda = if equality {
        // Contacts coming to rest: ġ⁺ = 0 exactly on every row of `set`,
        // an impulse of either sign (see `Run::settle`).
        g.lu().solve(&(-b))?
    } else {
        lcp(&g, &b)?
    };
    Some((&x * &lambda, lambda))
}

/// A model whose sustained contacts `active` hold `g̈ = 0`:
/// `M u̇ = τ − b + W_Aᵀ λ` (models without loop constraints).
struct Contacting<'a, S: ?Sized> {
    model: &'a S,
    nk: usize,
    active: Vec<usize>,
}

impl<S: Simulate + ?Sized> Contacting<'_, S> {
    /// `u̇` and the forces `λ` of the active rows.
    fn accelerations(&self, t: f64, q: &[f64], u: &[f64]) -> Option<(DVector<f64>, DVector<f64>)> {
        let nu = self.model.nu();
        let mut free = vec![0.0; nu];
        self.model.forward_dynamics(t, q, u, &mut free);
        let free = DVector::from_vec(free);
        let r = rows(self.model, self.nk, t, q, u)?;
        let mut m = DMatrix::zeros(nu, nu);
        self.model.mass_matrix(t, q, &mut m);
        let set = &self.active;
        let w = DMatrix::from_fn(set.len(), nu, |i, k| r.w[(set[i], k)]);
        let x = effective_inverse(&m, None, &w.transpose())?;
        let a = &w * &x;
        let rhs = DVector::from_fn(set.len(), |i, _| r.gamma[set[i]]) - &w * &free;
        let lambda = a.lu().solve(&rhs)?;
        Some((free + x * &lambda, lambda))
    }
}

impl<const N: usize, S: Simulate + ?Sized> OdeSystem<N> for Contacting<'_, S> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let (nq, nu) = (self.model.nq(), self.model.nu());
        let (q, u) = y.split_at(nq);
        let (dq, du) = dy.split_at_mut(nq);
        self.model.qdot(q, &u[..nu], dq);
        match self.accelerations(t, q, &u[..nu]) {
            Some((a, _)) => du[..nu].copy_from_slice(a.as_slice()),
            None => du.iter_mut().for_each(|x| *x = f64::NAN),
        }
    }
    fn project(&self, _t: f64, y: &mut [f64; N]) -> bool {
        self.model.normalize(&mut y[..self.model.nq()]);
        !self.model.quaternions().is_empty()
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

/// How a run with contacts goes: the model, its rows, the ODE without
/// sustained contacts, whether sustained contacts are possible (no loop
/// constraints), the rest height.
pub(super) struct Run<'a, S: ?Sized> {
    pub model: &'a S,
    pub names: &'a [String],
    /// The tree joints of `joint_impulses`.
    pub joints: &'a [String],
    pub nk: usize,
    /// Sustained contacts (and so contacts coming to rest) are supported:
    /// models without loop constraints.
    pub sustained: bool,
    /// The height below which a rebound is a contact at rest, m or rad.
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
        let (nc, nu) = (self.model.nc(), self.model.nu());
        (nc > 0).then(|| {
            let mut c = ConstraintValues::zeros(nc, nu);
            self.model.constraints(t, q, u, &mut c);
            c.jacobian
        })
    }

    /// Resolves the contacts at `(t, y)`: impacts, contacts coming to rest
    /// and released; updates `y`'s speeds and the active set.
    fn settle<const N: usize>(
        &self,
        t: f64,
        y: &mut [f64; N],
        active: &mut Vec<usize>,
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
        let mut r = read(y)?;
        let closed: Vec<usize> = (0..nk).filter(|&i| r.g[i] <= GAP_TOL).collect();
        let jump = |y: &mut [f64; N],
                    r: &Rows,
                    set: &[usize],
                    e: &dyn Fn(usize) -> f64,
                    kind: ContactEventKind,
                    events: &mut Vec<ContactEvent>|
         -> Result<(), String> {
            let m = mass(y);
            let j = self.jacobian(t, &y[..nq], &y[nq..nq + nu]);
            let before = energy(self.model, t, &y[..]);
            let equality = kind == ContactEventKind::Rest;
            let (du, lambda) = impact_map(&m, j.as_ref(), r, set, e, equality).ok_or_else(|| {
                fail(&format!(
                    "the impact of {} contact(s) has no solution (a singular mass matrix, or more than {MAX_LCP} contacts closed at once)",
                    set.len()
                ))
            })?;
            let mut full = vec![0.0; nk];
            for (&i, &l) in set.iter().zip(lambda.iter()) {
                full[i] = l;
            }
            let joint_impulses = self.joint_impulses(t, y, du.as_slice(), &full);
            for k in 0..nu {
                y[nq + k] += du[k];
            }
            let after = read(y)?;
            events.push(ContactEvent {
                t,
                kind,
                contacts: set
                    .iter()
                    .zip(lambda.iter())
                    .map(|(&i, &l)| ContactImpulse {
                        contact: self.name(i),
                        speed_before: r.gdot[i],
                        speed_after: after.gdot[i],
                        impulse: l,
                    })
                    .collect(),
                energy_before: before,
                energy_after: energy(self.model, t, &y[..]),
                generalized_impulse: (&m * &du).as_slice().to_vec(),
                joint_impulses,
            });
            Ok(())
        };
        if closed
            .iter()
            .any(|&i| r.gdot[i] < 0.0 && !active.contains(&i))
        {
            let e = |i: usize| r.e[i];
            jump(y, &r, &closed, &e, ContactEventKind::Impact, events)?;
            r = read(y)?;
        }
        // Contacts at rest: closed rows too slow to lift off by more than
        // the rest height against their acceleration.
        let (q, u) = (y[..nq].to_vec(), y[nq..nq + nu].to_vec());
        let mut free = vec![0.0; nu];
        self.model.forward_dynamics(t, &q, &u, &mut free);
        let free = DVector::from_vec(free);
        let resting: Vec<usize> = closed
            .iter()
            .copied()
            .filter(|&i| {
                let acc: f64 = (0..nu).map(|k| r.w[(i, k)] * free[k]).sum::<f64>() - r.gamma[i];
                r.gdot[i] * r.gdot[i] <= 2.0 * acc.abs() * self.rest_height
            })
            .collect();
        if resting.is_empty() {
            if !active.is_empty() {
                self.release(t, y, std::mem::take(active), events);
            }
            return Ok(());
        }
        if !self.sustained {
            return Err(fail(&format!(
                "contact `{}` comes to rest (its rebounds lift it less than {:e}); sustained contact in models with loop constraints is not implemented",
                self.name(resting[0]),
                self.rest_height
            )));
        }
        // The force problem: g̈ = W M⁻¹ Wᵀ λ + (W u̇_free − γ) ≥ 0, λ ≥ 0.
        let m = mass(y);
        let w = DMatrix::from_fn(resting.len(), nu, |i, k| r.w[(resting[i], k)]);
        let x = effective_inverse(&m, None, &w.transpose())
            .ok_or_else(|| fail("the mass matrix is singular"))?;
        let a = &w * &x;
        let b = &w * &free - DVector::from_fn(resting.len(), |i, _| r.gamma[resting[i]]);
        let lambda = lcp(&a, &b).ok_or_else(|| {
            fail(&format!(
                "the contact forces of {} resting contact(s) have no solution",
                resting.len()
            ))
        })?;
        let scale = lambda.amax().max(f64::MIN_POSITIVE);
        let now: Vec<usize> = resting
            .iter()
            .zip(lambda.iter())
            .filter(|(_, l)| **l > 1e-12 * scale && **l > 0.0)
            .map(|(&i, _)| i)
            .collect();
        let released: Vec<usize> = active
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
            .filter(|i| !active.contains(i))
            .collect();
        if !arriving.is_empty() {
            // The remaining normal speed of the arriving contacts (below
            // the rest speed, of either sign: the tail of a Zeno sequence,
            // whose bounces would exchange that momentum with the floor)
            // taken by one impulse; the sustained ones keep ġ = 0.
            let plastic = |_: usize| 0.0;
            jump(y, &r, &now, &plastic, ContactEventKind::Rest, events)?;
        }
        *active = now;
        Ok(())
    }

    fn release<const N: usize>(
        &self,
        t: f64,
        y: &[f64; N],
        rows_released: Vec<usize>,
        events: &mut Vec<ContactEvent>,
    ) {
        let (nq, nu) = (self.model.nq(), self.model.nu());
        let speeds = rows(self.model, self.nk, t, &y[..nq], &y[nq..nq + nu])
            .map_or_else(|| vec![f64::NAN; self.nk], |r| r.gdot);
        let e = energy(self.model, t, &y[..]);
        events.push(ContactEvent {
            t,
            kind: ContactEventKind::Release,
            contacts: rows_released
                .iter()
                .map(|&i| ContactImpulse {
                    contact: self.name(i),
                    speed_before: speeds[i],
                    speed_after: speeds[i],
                    impulse: 0.0,
                })
                .collect(),
            energy_before: e,
            energy_after: e,
            generalized_impulse: vec![0.0; nu],
            joint_impulses: Vec::new(),
        });
    }

    /// The tree joints' impulses of the jump `du` at `(t, y)` (before it)
    /// from the contact impulses `lambda` (one per row), by the generated
    /// `joint_impulses`; empty if the model has none.
    fn joint_impulses<const N: usize>(
        &self,
        t: f64,
        y: &[f64; N],
        du: &[f64],
        lambda: &[f64],
    ) -> Vec<JointImpulse> {
        let (nq, nu, nk, nj) = (self.model.nq(), self.model.nu(), self.nk, self.joints.len());
        let len = 6 * nj * (1 + nk);
        if nj == 0 || self.model.function_len(IMPULSES) != Some(len) {
            return Vec::new();
        }
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
        (0..nj)
            .map(|j| {
                let c: Vec<f64> = (0..6)
                    .map(|a| {
                        v[6 * j + a]
                            + (0..nk)
                                .map(|r| lambda[r] * v[6 * nj * (1 + r) + 6 * j + a])
                                .sum::<f64>()
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
        let mut active: Vec<usize> = Vec::new();
        let mut t = 0.0;
        let mut stalled = 0;
        let mut opts = opts.clone();
        loop {
            if let Err(message) = self.settle(t, &mut y, &mut active, &mut events) {
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
            let contacting = Contacting {
                model: self.model,
                nk,
                active: active.clone(),
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
            for pos in 0..active.len() {
                let c = &contacting;
                list.push(Event::new(
                    move |t: f64, y: &[f64; N]| {
                        c.accelerations(t, &y[..nq], &y[nq..nq + nu])
                            .map_or(f64::NAN, |(_, l)| l[pos])
                    },
                    Direction::Falling,
                    EventAction::Stop,
                ));
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
