//! Contacts at the nodes of cables (issue #26) on the vector runtime: a
//! cable node (a point, or a sphere about it) against a plane fixed in the
//! world. The gap is linear in the node's position coordinates,
//! `g = n·x_j − n·p − r`, so its row `w = ∂g/∂y` is constant and exact.
//!
//! The run is the one contact run of `crate::run::contact`, written over
//! the vector state: the same [`ContactEvent`]s, the same impact map
//! (`impact`, the generalised Newton law on all closed rows with its
//! exact LCP, `M` the structure's constant mass matrix) and the same
//! sustained unilateral constraints with `λ ≥ 0` (the force problem solved
//! by [`lcp`]). Between events generalized-α integrates the structure with
//! the sustained rows as index-3 constraints ([`Held`]: `g = 0` appended to
//! the model's own constraint rows). After every accepted step the gaps of
//! the open rows and the forces of the sustained ones are checked; the
//! first to cross zero is located on the step's cubic Hermite interpolant
//! (positions and speeds at both ends: the gap's own cubic) or, for a
//! force, linearly between the step's ends; the run restarts there with
//! consistent accelerations.
//!
//! Not here: Coulomb friction at cable nodes (the validator refuses
//! `mu > 0`), and cables hung at rigid bodies (the impact map would need
//! the rigid part's mass matrix and constraints at velocity level; the
//! validator refuses node contacts there).

use super::alpha::{AlphaModel, GeneralizedAlpha};
use super::run::{AlphaOptions, DynamicsError, DynamicsStats, State};
use crate::constrained::{DMatrix, DVector};
use crate::run::contact::Rows;
use crate::run::impulse::impact;
use crate::run::{ContactEvent, ContactEventKind, ContactImpulse, GAP_TOL, MAX_LCP, lcp};
use nalgebra::Dyn;
use nalgebra::linalg::LU;

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
}

/// The contacts' rows on a model's free coordinates (`y`, the structure's
/// free coordinates first): fixed coordinates folded into the level.
#[derive(Clone, Debug)]
pub(super) struct Gaps {
    pub names: Vec<String>,
    pub rows: Vec<Vec<(usize, f64)>>,
    pub level: Vec<f64>,
    pub e: Vec<f64>,
}

impl Gaps {
    /// `free_index` maps a full structural index to its free one (`None`:
    /// fixed at `q0_full`).
    pub fn new(
        contacts: &[NodeContact],
        free_index: impl Fn(usize) -> Option<usize>,
        q0_full: &[f64],
    ) -> Gaps {
        let mut g = Gaps {
            names: Vec::new(),
            rows: Vec::new(),
            level: Vec::new(),
            e: Vec::new(),
        };
        for c in contacts {
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
        }
        g
    }

    pub fn len(&self) -> usize {
        self.rows.len()
    }

    fn dot(&self, i: usize, x: &[f64]) -> f64 {
        self.rows[i].iter().map(|&(k, a)| a * x[k]).sum()
    }

    /// The gap of row `i` at coordinates `y`.
    pub fn gap(&self, i: usize, y: &[f64]) -> f64 {
        self.dot(i, y) - self.level[i]
    }

    /// The contact rows at `s` in the runtime's [`Rows`] (frictionless,
    /// `γ = 0`: the rows are constant).
    fn at(&self, s: &State) -> Rows {
        let (nk, n) = (self.len(), s.v.len());
        let mut w = DMatrix::zeros(nk, n);
        for (i, row) in self.rows.iter().enumerate() {
            for &(k, a) in row {
                w[(i, k)] += a;
            }
        }
        Rows {
            g: (0..nk).map(|i| self.gap(i, &s.q)).collect(),
            gdot: (0..nk).map(|i| self.dot(i, &s.v)).collect(),
            gamma: vec![0.0; nk],
            e: self.e.clone(),
            mu: vec![0.0; nk],
            w,
            vt: vec![[0.0; 2]; nk],
            gamma_t: vec![[0.0; 2]; nk],
            wt: DMatrix::zeros(2 * nk, n),
        }
    }
}

/// A vector model with the sustained contact rows `active` held as
/// index-3 constraints `g = 0` after its own rows: multipliers `μ`, the
/// normal force of a row `λ = −μ` (the residual's `+wᵀ μ`). The iteration
/// matrix is the model's, bordered by the rows and solved by their Schur
/// complement `S = C A⁻¹ Cᵀ` (a few rows; `A` the model's factored
/// matrix).
pub(super) struct Held<'m, M: ?Sized> {
    pub inner: &'m M,
    gaps: &'m Gaps,
    active: Vec<usize>,
}

/// [`Held`]'s scratch: the model's, and the bordered solve's `A⁻¹ Cᵀ`
/// columns with the factored `S`.
pub(super) struct HeldWork<W> {
    inner: W,
    x: Vec<Vec<f64>>,
    s: Option<LU<f64, Dyn, Dyn>>,
}

impl<'m, M: AlphaModel + ?Sized> Held<'m, M> {
    pub fn new(inner: &'m M, gaps: &'m Gaps, active: &[usize]) -> Self {
        Held {
            inner,
            gaps,
            active: active.to_vec(),
        }
    }

    /// The normal forces of the held rows from the multipliers.
    pub fn forces(&self, lambda: &[f64]) -> Vec<f64> {
        let mi = self.inner.n_constraints();
        (0..self.active.len()).map(|k| -lambda[mi + k]).collect()
    }

    /// `A⁻¹ [Cᵀ; 0]` and `S` at the matrix just factored.
    fn border(&self, w: &mut HeldWork<M::Work>, t: f64) -> Result<(), DynamicsError> {
        let (n, mi, k) = (
            self.inner.n(),
            self.inner.n_constraints(),
            self.active.len(),
        );
        w.x.clear();
        for &i in &self.active {
            let mut col = vec![0.0; n + mi];
            for &(c, a) in &self.gaps.rows[i] {
                col[c] += a;
            }
            self.inner.solve(&mut w.inner, &mut col);
            w.x.push(col);
        }
        let s = DMatrix::from_fn(k, k, |a, b| self.gaps.dot(self.active[a], &w.x[b][..n]));
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

impl<M: AlphaModel + ?Sized> AlphaModel for Held<'_, M> {
    type Work = HeldWork<M::Work>;

    fn n(&self) -> usize {
        self.inner.n()
    }

    fn n_constraints(&self) -> usize {
        self.inner.n_constraints() + self.active.len()
    }

    fn work(&self, state: &State) -> Self::Work {
        HeldWork {
            inner: self.inner.work(state),
            x: Vec::new(),
            s: None,
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
        self.inner
            .start(&mut w.inner, state, acc, &mut lambda[..mi])?;
        if self.active.is_empty() {
            return Ok(());
        }
        // The held rows' accelerations `C a = 0` (the rows are constant):
        // `[a; λ] −= A⁻¹ Cᵀ μ` with `S μ = C a₀`, `A` the model's matrix at
        // `β' = γ' = 0` (`M` with its own constraint rows).
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
        self.border(w, state.t)?;
        let rhs = DVector::from_fn(self.active.len(), |a, _| self.gaps.dot(self.active[a], acc));
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
        for (b, &i) in self.active.iter().enumerate() {
            for &(c, a) in &self.gaps.rows[i] {
                r[c] += a * lambda[mi + b];
            }
            r[n + mi + b] = self.gaps.gap(i, y);
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
        if self.active.is_empty() {
            return Ok(());
        }
        self.border(w, t)
    }

    fn solve(&self, w: &mut Self::Work, r: &mut [f64]) {
        let (n, mi) = (self.inner.n(), self.inner.n_constraints());
        self.inner.solve(&mut w.inner, &mut r[..n + mi]);
        let k = self.active.len();
        let Some(s) = w.s.as_ref().filter(|_| k > 0) else {
            return;
        };
        // `μ = S⁻¹ (C A⁻¹ r₁ − r₂)`, `x = A⁻¹ r₁ − A⁻¹ Cᵀ μ`.
        let rhs = DVector::from_fn(k, |a, _| {
            self.gaps.dot(self.active[a], &r[..n]) - r[n + mi + a]
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
        self.active
            .iter()
            .map(|&i| self.gaps.gap(i, &state.q).abs())
            .fold(own, f64::max)
    }

    fn full<'w>(&self, w: &'w Self::Work) -> &'w [f64] {
        self.inner.full(&w.inner)
    }
}

/// What the contact run needs of a vector model beyond [`AlphaModel`].
pub(super) trait Impacts: AlphaModel {
    /// The mass matrix on the free coordinates, dense (`None`: this model
    /// has no impact map).
    fn dense_mass(&self) -> Option<DMatrix<f64>>;
    /// The accelerations without contact forces at `s`.
    fn free_acceleration(&self, s: &State) -> Option<DVector<f64>>;
    /// Total energy at `s`.
    fn total_energy(&self, s: &State) -> f64;
}

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
/// is within half of [`GAP_TOL`] — a few steps retaken, where the cubic
/// interpolant of a flexible cable's step missed by up to 0.3 mm —, or
/// `None` if a retaken step fails.
fn on_the_steps(
    guess: f64,
    ((mut a, mut fa), (mut b, mut fb)): ((f64, f64), (f64, f64)),
    step: impl Fn(f64) -> Option<State>,
    gap: impl Fn(&State) -> f64,
) -> Option<State> {
    let mut t = guess;
    let mut side = 0;
    for _ in 0..60 {
        let s = step(t)?;
        let f = gap(&s);
        if f.abs() <= 0.5 * GAP_TOL || b - a <= 4.0 * f64::EPSILON * b.abs().max(1.0) {
            return Some(s);
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

impl ContactRun<'_> {
    #[allow(clippy::too_many_arguments)]
    fn event(
        &self,
        t: f64,
        kind: ContactEventKind,
        set: &[usize],
        before: (&Rows, f64),
        after: (&Rows, f64),
        ln: &[f64],
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
                    tangential_impulse: [0.0; 2],
                    tangential_speed_before: [0.0; 2],
                    tangential_speed_after: [0.0; 2],
                })
                .collect(),
            energy_before: before.1,
            energy_after: after.1,
            generalized_impulse: generalized,
            joint_impulses: Vec::new(),
        }
    }

    /// Resolves the contacts at `s` (as the rigid runtime's `settle`):
    /// the impact of the closed rows if one approaches, then the force
    /// problem of the rows at rest (a rebound that would land within one
    /// step `h`, `ġ ≤ |g̈| h`): those that carry a force `λ > 0` are held
    /// (those arriving lose their remaining speed by a plastic impulse),
    /// the others released. `released` are rows whose force was located
    /// falling through zero.
    pub fn settle<M: Impacts + ?Sized>(
        &mut self,
        m: &M,
        s: &mut State,
        h: f64,
    ) -> Result<(), DynamicsError> {
        let t = s.t;
        let nk = self.gaps.len();
        let mut r = self.gaps.at(s);
        let closed: Vec<usize> = (0..nk).filter(|&i| r.g[i] <= GAP_TOL).collect();
        let mass = || {
            m.dense_mass().ok_or_else(|| {
                failed(
                    t,
                    "this model has no impact map for contacts at cable nodes".into(),
                )
            })
        };
        let no_solution = |n: usize| {
            failed(
                t,
                format!(
                    "the impact of {n} contact(s) at cable nodes has no solution (more than {MAX_LCP} contacts closed at once, or a singular mass matrix)"
                ),
            )
        };
        if closed
            .iter()
            .any(|&i| r.gdot[i] < 0.0 && !self.active.contains(&i))
        {
            let mm = mass()?;
            let slides = vec![None; closed.len()];
            let e = |i: usize| r.e[i];
            let sol = impact(&mm, None, &r, &closed, &e, false, &slides)
                .ok_or_else(|| no_solution(closed.len()))?;
            let e0 = m.total_energy(s);
            for (v, d) in s.v.iter_mut().zip(sol.du.iter()) {
                *v += d;
            }
            let after = self.gaps.at(s);
            let ln: Vec<f64> = sol.ln.iter().copied().collect();
            let ev = self.event(
                t,
                ContactEventKind::Impact,
                &closed,
                (&r, e0),
                (&after, m.total_energy(s)),
                &ln,
                (&mm * &sol.du).as_slice().to_vec(),
            );
            self.events.push(ev);
            r = after;
        }
        let free = m
            .free_acceleration(s)
            .ok_or_else(|| failed(t, "no accelerations at the contact event".into()))?;
        let acc = |i: usize| -> f64 { (0..free.len()).map(|k| r.w[(i, k)] * free[k]).sum() };
        let resting: Vec<usize> = closed
            .iter()
            .copied()
            .filter(|&i| r.gdot[i] <= acc(i).abs() * h)
            .collect();
        // The force problem: g̈ = W M⁻¹ Wᵀ λ + W a_free ≥ 0, λ ≥ 0.
        let now: Vec<usize> = if resting.is_empty() {
            Vec::new()
        } else {
            let mm = mass()?;
            let wn = DMatrix::from_fn(resting.len(), free.len(), |a, k| r.w[(resting[a], k)]);
            let minv_wt = mm
                .clone()
                .cholesky()
                .map(|c| c.solve(&wn.transpose()))
                .ok_or_else(|| failed(t, "the mass matrix is not positive definite".into()))?;
            let a = &wn * minv_wt;
            let b = DVector::from_fn(resting.len(), |k, _| acc(resting[k]));
            let lambda = lcp(&a, &b).ok_or_else(|| no_solution(resting.len()))?;
            let scale = lambda.amax().max(f64::MIN_POSITIVE);
            (0..resting.len())
                .filter(|&k| lambda[k] > 1e-12 * scale)
                .map(|k| resting[k])
                .collect()
        };
        let released: Vec<usize> = self
            .active
            .iter()
            .copied()
            .filter(|i| !now.contains(i))
            .collect();
        if !released.is_empty() {
            let e = m.total_energy(s);
            let zeros = vec![0.0; released.len()];
            let ev = self.event(
                t,
                ContactEventKind::Release,
                &released,
                (&r, e),
                (&r, e),
                &zeros,
                vec![0.0; s.v.len()],
            );
            self.events.push(ev);
        }
        let arriving: Vec<usize> = now
            .iter()
            .copied()
            .filter(|i| !self.active.contains(i))
            .collect();
        if !arriving.is_empty() {
            // Their remaining normal speed (below the rest speed) taken by
            // one plastic impulse; the sustained ones keep ġ = 0.
            let mm = mass()?;
            let slides = vec![None; now.len()];
            let plastic = |_: usize| 0.0;
            let sol = impact(&mm, None, &r, &now, &plastic, true, &slides)
                .ok_or_else(|| no_solution(now.len()))?;
            let e0 = m.total_energy(s);
            for (v, d) in s.v.iter_mut().zip(sol.du.iter()) {
                *v += d;
            }
            let after = self.gaps.at(s);
            let ln: Vec<f64> = sol.ln.iter().copied().collect();
            let ev = self.event(
                t,
                ContactEventKind::Rest,
                &now,
                (&r, e0),
                (&after, m.total_energy(s)),
                &ln,
                (&mm * &sol.du).as_slice().to_vec(),
            );
            self.events.push(ev);
        }
        self.active = now;
        Ok(())
    }

    /// Generalized-α on `m` from `state` to `t_end` through every contact
    /// event; `observe` sees every accepted state (and each event's state
    /// before its jump). Returns the last state and, if the run stopped
    /// early, why.
    pub fn run<M: Impacts + ?Sized>(
        &mut self,
        m: &M,
        mut state: State,
        opts: &AlphaOptions,
        t_end: f64,
        mut observe: impl FnMut(&State, Option<&[f64]>),
    ) -> (State, Option<DynamicsError>) {
        let nk = self.gaps.len();
        let mut opts = opts.clone();
        let eps = 1e-12 * t_end.abs().max(1.0);
        if let Err(e) = self.settle(m, &mut state, opts.h) {
            return (state, Some(e));
        }
        let mut stalled = 0;
        loop {
            let held = Held::new(m, self.gaps, &self.active);
            let mut ga = match GeneralizedAlpha::new(&held, state.clone(), opts.clone()) {
                Ok(ga) => ga,
                Err(e) => return (state, Some(e)),
            };
            self.forces = held.forces(ga.multipliers());
            let t_start = state.t;
            let event = loop {
                if ga.state().t >= t_end - eps {
                    break None;
                }
                let prev = ga.state().clone();
                let f0 = held.forces(ga.multipliers());
                if let Err(e) = ga.step_within(t_end) {
                    self.add_stats(&ga.stats);
                    return (prev, Some(e));
                }
                let new = ga.state().clone();
                let f1 = held.forces(ga.multipliers());
                // The first crossing: an open gap falling through 0 on the
                // step's interpolant, a held force falling through 0.
                // With the row whose gap closes (and the level it closes
                // at), `None` for a held force.
                let mut first: Option<(f64, Option<(usize, f64)>)> = None;
                let mut take = |t: f64, row: Option<(usize, f64)>| {
                    if first.is_none_or(|(f, _)| t < f) {
                        first = Some((t, row));
                    }
                };
                for i in (0..nk).filter(|i| !self.active.contains(i)) {
                    // A row that starts the step at or inside its plane (just
                    // released, or left by a plastic impact) counts as
                    // closing once it sinks GAP_TOL further: the force
                    // problem has found it not pressing.
                    let g0 = self.gaps.gap(i, &prev.q);
                    let level = if g0 < 0.0 { g0 - GAP_TOL } else { 0.0 };
                    if self.gaps.gap(i, &new.q) < level {
                        let g = |t: f64| {
                            self.gaps
                                .gap(i, &super::simulate::hermite(&prev, &new, t).q)
                                - level
                        };
                        take(locate(g, prev.t, new.t), Some((i, level)));
                    }
                }
                for k in 0..self.active.len() {
                    if f1[k] < 0.0 && f0[k] >= 0.0 {
                        take(prev.t + (new.t - prev.t) * f0[k] / (f0[k] - f1[k]), None);
                    } else if f1[k] < 0.0 {
                        take(prev.t, None);
                    }
                }
                match first {
                    None => {
                        self.forces = f1;
                        observe(&new, Some(ga.q_full()));
                    }
                    Some((t, row)) => {
                        // Restart at the event: the step retaken from its
                        // start to the located time (an integrator state,
                        // not the interpolant's), the interpolant if that
                        // step fails. For a closing gap the retaken step's
                        // own gap is brought to the level: the interpolant
                        // only guesses where the integrator crosses.
                        let s = if t >= new.t {
                            new
                        } else {
                            let retake = |t: f64| {
                                GeneralizedAlpha::new(&held, prev.clone(), opts.clone())
                                    .and_then(|mut g| g.step_within(t).map(|()| g.state().clone()))
                                    .ok()
                            };
                            let located = match row {
                                Some((i, level)) => {
                                    let gap = |s: &State| self.gaps.gap(i, &s.q) - level;
                                    let ends = ((prev.t, gap(&prev)), (new.t, gap(&new)));
                                    on_the_steps(t, ends, retake, gap)
                                }
                                None => retake(t),
                            };
                            located.unwrap_or_else(|| super::simulate::hermite(&prev, &new, t))
                        };
                        break Some(s);
                    }
                }
            };
            self.add_stats(&ga.stats);
            opts.h = ga.step_size();
            let Some(mut s) = event else {
                return (ga.state().clone(), None);
            };
            observe(&s, None);
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
