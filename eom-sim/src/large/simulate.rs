//! One run of a model with elements — cables alone (a [`StructuralModel`]
//! of every cable) or cables hung at markers of a rigid part (a
//! [`MixedModel`]) — into the same [`RunReport`] and [`Table`] as a
//! compiled or interpreted rigid model's run (`crate::run::simulate`):
//! the same [`Stop`] when a run ends early (the report up to the last
//! accepted step, never an error), the same counters, the same energy
//! line, the same CSV writer. What only such models have is the report's
//! [`ElementReport`]: each cable's nodes and each marker's force at the
//! end.
//!
//! Integrators: generalized-α (fixed step, or step-size control with
//! [`ElementRun::control`]) on both; RK4 (fixed step) on a structure
//! alone (a mixed model's attachments are an index-3 system, which an
//! explicit method does not solve).

use super::alpha::GeneralizedAlpha;
use super::contact::{ContactRun, Frame, Gaps, Impacts, NodeContact};
use super::dynamics::integrate_rk4;
use super::mixed::MixedModel;
use super::mixed::statics::{MixedStaticError, Stability, solve_static_mixed};
use super::model::StructuralModel;
use super::run::{AlphaOptions, DynamicsError, DynamicsStats, State, StepControl};
use super::statics::{LoadStep, StaticError, StaticOptions, solve_static};
use crate::Integrator;
use crate::constrained::{DMatrix, DVector};
use crate::run::ContactForce;
use crate::run::contact::Rows;
use crate::run::{
    CableState, ElementReport, LoadStepReport, MountForce, RunError, RunReport, RunStats,
    StabilityReport, StaticReport, Stop,
};
use crate::table::Table;
use std::time::Instant;

/// Where one cable's nodes sit in a structure's full coordinates.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CableLayout {
    /// The cable's name.
    pub name: String,
    /// Its element type's name.
    pub kernel: &'static str,
    /// Dimension of positions (2 or 3).
    pub dim: usize,
    /// Coordinates per node.
    pub node_coords: usize,
    /// Number of nodes.
    pub nodes: usize,
    /// Full structural index of its first node's first coordinate (node
    /// `j`'s coordinates start at `offset + j · node_coords`).
    pub offset: usize,
}

impl CableLayout {
    /// Position of `node` in the structure's full coordinates (`z = 0`
    /// when planar).
    pub fn node_position(&self, q_full: &[f64], node: usize) -> [f64; 3] {
        let mut p = [0.0; 3];
        for (k, pk) in p.iter_mut().enumerate().take(self.dim) {
            *pk = q_full[self.offset + node * self.node_coords + k];
        }
        p
    }

    /// The cable at `q_full`, as reported.
    fn state(&self, q_full: &[f64]) -> CableState {
        let nodes: Vec<[f64; 3]> = (0..self.nodes)
            .map(|j| self.node_position(q_full, j))
            .collect();
        CableState {
            cable: self.name.clone(),
            element: self.kernel.to_string(),
            elements: self.nodes.saturating_sub(1),
            first_node: nodes.first().copied().unwrap_or_default(),
            last_node: nodes.last().copied().unwrap_or_default(),
            nodes,
        }
    }
}

/// How a model with elements is integrated.
#[derive(Clone, Debug)]
pub struct ElementRun {
    /// [`Integrator::GeneralizedAlpha`], or [`Integrator::Rk4`] on cables
    /// alone.
    pub integrator: Integrator,
    /// End time, s.
    pub t_end: f64,
    /// Step, s (with [`ElementRun::control`], the first step); rounded so
    /// that a whole number of steps reaches `t_end`.
    pub dt: f64,
    /// Spectral radius at infinite frequency of generalized-α, in `[0, 1]`.
    pub rho_inf: f64,
    /// Step-size control of generalized-α; `None`: the fixed step.
    pub control: Option<StepControl>,
    /// Record the trajectory (the start, then every accepted step, or
    /// the samples of [`ElementRun::every`]).
    pub record: bool,
    /// Sample the trajectory every this many seconds (from t = 0; the end
    /// of the run is the last row) by cubic Hermite interpolation of the
    /// positions between accepted steps (their speeds the interpolant's
    /// derivative); `None`: every accepted step.
    pub every: Option<f64>,
}

impl ElementRun {
    /// What is wrong with these settings, each a sentence (empty: none).
    pub fn problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        if !(self.t_end > 0.0 && self.t_end.is_finite()) {
            problems.push(format!("--t-end must be positive, not {}", self.t_end));
        }
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            problems.push(format!("--dt must be positive, not {}", self.dt));
        }
        if let Some(e) = self.every
            && !(e > 0.0 && e.is_finite())
        {
            problems.push(format!("--every must be positive, not {e}"));
        }
        if !(0.0..=1.0).contains(&self.rho_inf) {
            problems.push(format!("--rho-inf lies in [0, 1], not {}", self.rho_inf));
        }
        if let Some(c) = &self.control
            && !(c.rtol > 0.0 && c.atol > 0.0 && c.rtol.is_finite() && c.atol.is_finite())
        {
            problems.push(format!(
                "--rtol and --atol must be positive, not {} and {}",
                c.rtol, c.atol
            ));
        }
        match self.integrator {
            Integrator::GeneralizedAlpha => {}
            Integrator::Rk4 if self.control.is_some() => problems.push(
                "--rtol/--atol control generalized-α's step; rk4 on cables takes the fixed step --dt"
                    .to_string(),
            ),
            Integrator::Rk4 => {}
            other => problems.push(format!(
                "integrator `{other}` does not run models with elements: use one of {}",
                Integrator::names_where(Integrator::runs_element_models)
            )),
        }
        problems
    }

    /// Steps of the fixed step size.
    pub fn steps(&self) -> usize {
        (self.t_end / self.dt).round().max(1.0) as usize
    }

    fn alpha_options(&self) -> AlphaOptions {
        AlphaOptions {
            h: self.t_end / self.steps() as f64,
            rho_inf: self.rho_inf,
            control: self.control,
            ..AlphaOptions::default()
        }
    }
}

/// A vector model as a run reports it.
trait Reported: Impacts {
    /// The rigid part's coordinates and speeds at the end of `y`, `v`
    /// (none for a structure alone).
    fn rigid_len(&self) -> usize;
    /// Total energy and the size of the energies it is measured against
    /// (`|T| + |V|` of the structure plus the rigid part's `|E|`).
    fn energies(&self, s: &State) -> (f64, f64);
    /// The structure's full coordinates of the state's `y`.
    fn full_of(&self, y: &[f64]) -> Vec<f64>;
    /// The markers' forces on the cable ends from the multipliers, named.
    fn mounts(&self, lambda: &[f64]) -> Vec<MountForce>;
    /// The structure of the cables.
    fn structural(&self) -> &StructuralModel;
    /// What can feed energy into the model, or `None` if nothing can
    /// ([`RigidPart::energy_source`]); a structure alone has constant loads
    /// and fixed supports.
    fn energy_source(&self) -> Option<String>;
}

/// The share of the energies a passive model is made of by which its
/// energy may rise before the run refuses: integration error stays far
/// below it (the cable tests' runs lose energy or keep it to 1e-6 of it),
/// a run gone wrong passes it by orders of magnitude (the pendulum's stiff
/// cable before its restarts were fixed: 684 J from −0.02 J).
const ENERGY_RISE: f64 = 1e-2;

/// A rise of at most this many joules is never refused: the round-off of
/// a model at rest, whose energies are all zero (a wire lying on a floor
/// at its datum: 1e-29 J from 0 J).
const ENERGY_FLOOR: f64 = 1e-9;

/// Accepted steps between two checks of [`EnergyGuard`]: an energy
/// costs about one step (the strain energy's quadrature against modified
/// Newton's one or two force evaluations), so a check every step doubled
/// a cable's run (the falling ANCF pendulum, 2 s: 54 → 107 ms); a run
/// gone wrong stays wrong for many steps (the pendulum's cable: hundreds
/// of joules over tens of steps).
const GUARD_EVERY: usize = 16;

/// Stops a run of a model that can gain no energy when its energy rises
/// above the start by more than [`ENERGY_RISE`] of the energies it is made
/// of (`|T| + |V|`, the largest of the run's checks so far): checked every
/// [`GUARD_EVERY`] accepted steps, at every event and at the end. A model
/// with an energy source (an actuator, a given force, a prescribed motion)
/// is not checked.
struct EnergyGuard {
    /// The start's energy and the largest scale so far, if the model is
    /// passive.
    start: Option<(f64, f64)>,
    /// Accepted steps since the last check.
    steps: usize,
}

impl EnergyGuard {
    fn new<M: Reported + ?Sized>(m: &M, s: &State) -> Self {
        EnergyGuard {
            start: m.energy_source().is_none().then(|| m.energies(s)),
            steps: 0,
        }
    }

    /// After an accepted step: checks every [`GUARD_EVERY`]-th.
    fn step<M: Reported + ?Sized>(&mut self, m: &M, s: &State) -> Result<(), DynamicsError> {
        self.steps += 1;
        if self.steps < GUARD_EVERY {
            return Ok(());
        }
        self.check(m, s)
    }

    fn check<M: Reported + ?Sized>(&mut self, m: &M, s: &State) -> Result<(), DynamicsError> {
        self.steps = 0;
        let Some((e0, largest)) = &mut self.start else {
            return Ok(());
        };
        let e0 = *e0;
        let (e, scale) = m.energies(s);
        *largest = largest.max(scale);
        let scale = *largest;
        if e - e0 > (ENERGY_RISE * scale).max(ENERGY_FLOOR) || !e.is_finite() {
            return Err(DynamicsError::EnergyRose {
                t: s.t,
                start: e0,
                reached: e,
                scale,
            });
        }
        Ok(())
    }
}

impl Reported for StructuralModel {
    fn rigid_len(&self) -> usize {
        0
    }
    fn energies(&self, s: &State) -> (f64, f64) {
        let q = self.expand(&s.q);
        let (t, v) = (
            self.kinetic_energy(&s.v),
            self.strain_energy(&q) + self.load_potential(&q),
        );
        (t + v, t.abs() + v.abs())
    }
    fn full_of(&self, y: &[f64]) -> Vec<f64> {
        self.expand(y)
    }
    fn mounts(&self, _: &[f64]) -> Vec<MountForce> {
        Vec::new()
    }
    fn structural(&self) -> &StructuralModel {
        self
    }
    fn energy_source(&self) -> Option<String> {
        None
    }
}

impl Reported for MixedModel<'_> {
    fn structural(&self) -> &StructuralModel {
        self.structure()
    }
    fn energy_source(&self) -> Option<String> {
        self.rigid().energy_source()
    }
    fn rigid_len(&self) -> usize {
        self.n() - self.n_structural()
    }
    fn energies(&self, s: &State) -> (f64, f64) {
        let ns = self.n_structural();
        let st = self.structure();
        let q = self.structural_full(&s.q);
        let (t, v) = (
            st.kinetic_energy(&s.v[..ns]),
            st.strain_energy(&q) + st.load_potential(&q),
        );
        let (qr, vr) = (&s.q[ns..], &s.v[ns..]);
        let rigid = self.rigid().energy(s.t, qr, vr);
        let scale = self.rigid().energy_scale(s.t, qr, vr);
        (t + v + rigid, t.abs() + v.abs() + scale)
    }
    fn full_of(&self, y: &[f64]) -> Vec<f64> {
        self.structural_full(y)
    }
    fn mounts(&self, lambda: &[f64]) -> Vec<MountForce> {
        self.attachments()
            .iter()
            .zip(self.mount_forces(lambda))
            .map(|(a, force)| MountForce {
                attachment: a.name.clone(),
                force,
            })
            .collect()
    }
}

/// The structure's mass matrix on its free coordinates, dense.
fn structural_mass(st: &StructuralModel) -> DMatrix<f64> {
    let n = st.n_free();
    let mut m = DMatrix::zeros(n, n);
    let mut e = vec![0.0; n];
    let mut col = vec![0.0; n];
    for j in 0..n {
        e[j] = 1.0;
        col.fill(0.0);
        st.mass().sym_mul_add(1.0, &e, &mut col);
        e[j] = 0.0;
        for (i, c) in col.iter().enumerate() {
            m[(i, j)] = *c;
        }
    }
    m
}

impl Impacts for StructuralModel {
    fn dense_mass(&self, _: &State) -> Option<DMatrix<f64>> {
        Some(structural_mass(self))
    }
    fn free_acceleration(&self, s: &State) -> Option<DVector<f64>> {
        let (q, v) = (self.expand(&s.q), self.expand_rate(&s.v));
        let mut scratch = vec![0.0; self.n_full()];
        let mut f = vec![0.0; self.n_free()];
        self.internal(&q, &v, &mut scratch, &mut f);
        let rhs =
            DVector::from_iterator(f.len(), self.load_free().iter().zip(&f).map(|(a, b)| a - b));
        structural_mass(self).cholesky().map(|c| c.solve(&rhs))
    }
    fn total_energy(&self, s: &State) -> f64 {
        self.energies(s).0
    }
}

/// The mixed model's impact map: `M = diag(M_s, M_r(q_r))` on
/// `y = (x, q_r)`, the attachments and the rigid part's loops as the
/// constraint rows kept at the speed level.
impl Impacts for MixedModel<'_> {
    fn dense_mass(&self, s: &State) -> Option<DMatrix<f64>> {
        let (ns, n) = (self.n_structural(), self.n());
        let nr = n - ns;
        let mut m = DMatrix::zeros(n, n);
        m.view_mut((0, 0), (ns, ns))
            .copy_from(&structural_mass(self.structure()));
        let mut mr = vec![0.0; nr * nr];
        self.rigid().mass_matrix(s.t, &s.q[ns..], &mut mr);
        for i in 0..nr {
            for j in 0..nr {
                m[(ns + i, ns + j)] = mr[i * nr + j];
            }
        }
        m.iter().all(|x| x.is_finite()).then_some(m)
    }
    fn constraint_rows(&self, s: &State) -> Option<DMatrix<f64>> {
        let j = self.constraint_jacobian(s.t, &s.q);
        (j.nrows() > 0).then_some(j)
    }
    fn constraint_rates(&self, s: &State, j: &DMatrix<f64>) -> Option<DVector<f64>> {
        (j.nrows() > 0).then(|| self.rates_of_constraints(s, j))
    }
    fn free_acceleration(&self, s: &State) -> Option<DVector<f64>> {
        let a = self.constrained_acceleration(s).ok()?;
        Some(DVector::from_vec(a))
    }
    fn total_energy(&self, s: &State) -> f64 {
        self.energies(s).0
    }
    fn body_rows(&self, t: f64, y: &[f64], v: &[f64]) -> Option<Rows> {
        let (ns, n) = (self.n_structural(), self.n());
        let nr = n - ns;
        let nk = self.rigid().contact_names().len();
        let mut out = vec![0.0; nk * (5 + nr)];
        if nk == 0 || !self.rigid().contacts(t, &y[ns..], &v[ns..], &mut out) {
            return None;
        }
        // The rigid part's rows on `q_r`, after the structure's columns.
        let own = Rows::of_contacts(nk, nr, &out);
        let mut w = DMatrix::zeros(nk, n);
        w.view_mut((0, ns), (nk, nr)).copy_from(&own.w);
        let mut r = Rows {
            w,
            wt: DMatrix::zeros(2 * nk, n),
            ..own
        };
        // With friction, the tangential rows of the generated `friction`
        // (a rough row without them cannot be evaluated).
        if r.mu.iter().any(|&mu| mu != 0.0) {
            let mut f = vec![0.0; nk * (4 + 2 * nr)];
            if !self.rigid().friction(t, &y[ns..], &v[ns..], &mut f) {
                return None;
            }
            r.set_friction(&f, nr, ns);
        }
        Some(r)
    }
    fn body_frames(&self, t: f64, y: &[f64], v: &[f64]) -> Option<Vec<Frame>> {
        let (ns, n) = (self.n_structural(), self.n());
        let nr = n - ns;
        let nf = self.rigid().n_frames();
        let mut out = vec![0.0; nf * Frame::len(nr)];
        if nf == 0 || !self.rigid().frames(t, &y[ns..], &v[ns..], &mut out) {
            return None;
        }
        Some(Frame::parse(&out, nr, ns))
    }
    fn onto_constraints(&self, s: &mut State) -> Result<(), DynamicsError> {
        // Within a thousandth of the start's tolerance (`1e-8`): a state
        // of the integrator's own is left as it is.
        let worst = |s: &State| super::norm_inf(&self.constraint_residual(s.t, &s.q));
        if worst(s) <= 1e-11 {
            return Ok(());
        }
        let off = |s: &State, why: &str| DynamicsError::Contact {
            t: s.t,
            message: format!(
                "the event's state cannot be brought onto the model's constraints ({why})"
            ),
        };
        let m = Impacts::dense_mass(self, s).ok_or_else(|| off(s, "no mass matrix"))?;
        for _ in 0..10 {
            if worst(s) <= 1e-12 {
                break;
            }
            let phi = DVector::from_vec(self.constraint_residual(s.t, &s.q));
            let j = self.constraint_jacobian(s.t, &s.q);
            let dy = crate::run::impulse::onto_constraints(&m, &j, &phi)
                .ok_or_else(|| off(s, "a singular mass matrix"))?;
            for (y, d) in s.q.iter_mut().zip(dy.iter()) {
                *y += d;
            }
        }
        let left = worst(s);
        if left.is_nan() || left > 1e-10 {
            return Err(off(s, "Newton on the positions does not converge"));
        }
        let j = self.constraint_jacobian(s.t, &s.q);
        let d = self.rates_of_constraints(s, &j);
        let du = crate::run::impulse::onto_constraints(&m, &j, &d)
            .ok_or_else(|| off(s, "a singular mass matrix"))?;
        for (v, x) in s.v.iter_mut().zip(du.iter()) {
            *v += x;
        }
        Ok(())
    }
}

/// The CSV of a run: `t`, the rigid part's coordinates and speeds, every
/// node of every cable (`CABLE.nodeK.x|y|z`), the total energy; at every
/// accepted step, or at the samples `k · every`.
struct Recorder<'a> {
    cables: &'a [CableLayout],
    table: Option<Table>,
    every: Option<f64>,
    /// The next sample's index `k`.
    next: usize,
    /// The last accepted state.
    prev: Option<State>,
}

impl<'a> Recorder<'a> {
    fn new(
        cables: &'a [CableLayout],
        (coordinates, speeds): (&[String], &[String]),
        run: &ElementRun,
    ) -> Self {
        let table = run.record.then(|| {
            let mut header = vec!["t".to_string()];
            header.extend(coordinates.iter().chain(speeds).cloned());
            for c in cables {
                for k in 0..c.nodes {
                    header.extend(["x", "y", "z"].map(|a| format!("{}.node{k}.{a}", c.name)));
                }
            }
            header.push("energy".into());
            Table::new(header)
        });
        Recorder {
            cables,
            table,
            every: run.every,
            next: 0,
            prev: None,
        }
    }

    /// An accepted state (the start first).
    fn record<M: Reported + ?Sized>(&mut self, m: &M, s: &State, q_full: &[f64]) {
        if self.table.is_none() {
            return;
        }
        let Some(every) = self.every else {
            self.row(m, s, q_full);
            return;
        };
        let eps = 1e-9 * every;
        loop {
            let t = self.next as f64 * every;
            if t > s.t + eps {
                break;
            }
            self.next += 1;
            match &self.prev {
                Some(p) if (t - s.t).abs() > eps => {
                    let at = hermite(p, s, t);
                    let q = m.full_of(&at.q);
                    self.row(m, &at, &q);
                }
                _ => self.row(m, s, q_full),
            }
        }
        self.prev = Some(s.clone());
    }

    /// The last state of the run, as the last row if no sample fell on it.
    fn finish<M: Reported + ?Sized>(&mut self, m: &M, s: &State) {
        let last = self
            .table
            .as_ref()
            .and_then(|t| t.rows.last())
            .map(|r| r[0]);
        if self.every.is_some() && last.is_some_and(|t| t < s.t) {
            self.row(m, s, &m.full_of(&s.q));
        }
    }

    fn row<M: Reported + ?Sized>(&mut self, m: &M, s: &State, q_full: &[f64]) {
        let Some(table) = &mut self.table else {
            return;
        };
        let nr = m.rigid_len();
        let mut row = vec![s.t];
        row.extend_from_slice(&s.q[s.q.len() - nr..]);
        row.extend_from_slice(&s.v[s.v.len() - nr..]);
        for c in self.cables {
            for k in 0..c.nodes {
                row.extend(c.node_position(q_full, k));
            }
        }
        row.push(m.energies(s).0);
        table.push(row);
    }
}

/// The state at `t` between the accepted states `a` and `b`: the cubic
/// Hermite interpolant of the positions through `(q, v)` at both ends
/// (error `O(h⁴)` in the positions), its derivative as the speeds
/// (`O(h³)`).
pub(super) fn hermite(a: &State, b: &State, t: f64) -> State {
    let h = b.t - a.t;
    let x = (t - a.t) / h;
    let (x2, x3) = (x * x, x * x * x);
    let (h00, h10, h01, h11) = (
        2.0 * x3 - 3.0 * x2 + 1.0,
        x3 - 2.0 * x2 + x,
        -2.0 * x3 + 3.0 * x2,
        x3 - x2,
    );
    let (d00, d10, d01, d11) = (
        (6.0 * x2 - 6.0 * x) / h,
        3.0 * x2 - 4.0 * x + 1.0,
        (-6.0 * x2 + 6.0 * x) / h,
        3.0 * x2 - 2.0 * x,
    );
    let mut q = Vec::with_capacity(a.q.len());
    let mut v = Vec::with_capacity(a.v.len());
    for i in 0..a.q.len() {
        let (q0, q1, v0, v1) = (a.q[i], b.q[i], a.v[i], b.v[i]);
        q.push(h00 * q0 + h10 * h * v0 + h01 * q1 + h11 * h * v1);
        v.push(d00 * q0 + d10 * v0 + d01 * q1 + d11 * v1);
    }
    State { t, q, v }
}

/// The report of a run from `start` that ended at `end` (why: `stop`).
#[allow(clippy::too_many_arguments)]
fn report<M: Reported + ?Sized>(
    m: &M,
    cables: &[CableLayout],
    start: &State,
    end: &State,
    lambda: &[f64],
    stop: Stop,
    stats: &DynamicsStats,
    cpu_s: f64,
    rho_inf: f64,
) -> RunReport {
    let nr = m.rigid_len();
    let (e0, s0) = m.energies(start);
    let (e1, s1) = m.energies(end);
    let q_full = m.full_of(&end.q);
    RunReport {
        t: end.t,
        q: end.q[end.q.len() - nr..].to_vec(),
        u: end.v[end.v.len() - nr..].to_vec(),
        energy: [e0, e1],
        energy_scale: s0.max(s1),
        stop,
        stats: RunStats {
            steps: stats.steps + stats.rejected,
            accepted: stats.steps,
            rejected: stats.rejected,
            rhs_evals: stats.force_evaluations,
            jacobian_evals: stats.factorizations,
            // Set by generalized-α's runs (`run_alpha`): the elements'
            // tangent; a rigid part's block is by differences always.
            jacobian: None,
            lu_decompositions: stats.factorizations,
            newton_iterations: stats.newton_iterations,
            stiffness_detections: 0,
            constraints: None,
        },
        cpu_s,
        constrained: None,
        elements: Some(ElementReport {
            rho_inf,
            largest_constraint_residual: stats.max_constraint_residual,
            cables: cables.iter().map(|c| c.state(&q_full)).collect(),
            mounts: m.mounts(lambda),
            contact_forces: Vec::new(),
        }),
        contact_events: Vec::new(),
    }
}

/// A run's stop from the error it ended with (the start's errors are
/// [`RunError::Elements`]).
fn stop_of(e: DynamicsError) -> Stop {
    match e {
        DynamicsError::StepTooSmall { t, h, .. } => Stop::StepSizeTooSmall { t, h },
        DynamicsError::NonFinite { t } => Stop::NonFinite {
            t,
            coordinate: "a coordinate of the model".into(),
        },
        DynamicsError::NewtonFailed { t, .. }
        | DynamicsError::Singular { t, .. }
        | DynamicsError::Inconsistent { t, .. }
        | DynamicsError::Contact { t, .. }
        | DynamicsError::EnergyRose { t, .. } => Stop::Failed {
            t,
            message: e.to_string(),
        },
    }
}

/// Generalized-α on `m` from `state`; with contacts at cable nodes
/// (`gaps`), through their events ([`ContactRun`]).
fn run_alpha<M: Reported>(
    m: &M,
    cables: &[CableLayout],
    state: State,
    names: (&[String], &[String]),
    run: &ElementRun,
    gaps: &Gaps,
    progress: &mut dyn FnMut(f64),
) -> Result<(RunReport, Option<Table>), RunError> {
    let st = m.structural();
    let before = st.differenced_evaluations();
    let mut out = if gaps.len() > 0 {
        run_contacts(m, cables, state, names, run, gaps, progress)?
    } else {
        run_free(m, cables, state, names, run, progress)?
    };
    // The Newton matrix's tangent: the elements' generated kernels, or
    // differences whose force evaluations count as right-hand sides (as
    // the rigid integrators count theirs).
    out.0.stats.jacobian = Some(st.tangent());
    out.0.stats.rhs_evals += st.differenced_evaluations() - before;
    Ok(out)
}

/// Generalized-α on `m` without contacts.
fn run_free<M: Reported>(
    m: &M,
    cables: &[CableLayout],
    state: State,
    names: (&[String], &[String]),
    run: &ElementRun,
    progress: &mut dyn FnMut(f64),
) -> Result<(RunReport, Option<Table>), RunError> {
    let clock = Instant::now();
    let start = state.clone();
    let mut ga =
        GeneralizedAlpha::new(m, state, run.alpha_options()).map_err(RunError::Elements)?;
    let mut rec = Recorder::new(cables, names, run);
    rec.record(m, &start, &m.full_of(&start.q));
    let mut guard = EnergyGuard::new(m, &start);
    let result = ga
        .run_to_checked(run.t_end, |s, q| {
            progress(s.t);
            rec.record(m, s, q);
            guard.step(m, s)
        })
        .and_then(|()| guard.check(m, ga.state()));
    let cpu = clock.elapsed().as_secs_f64();
    rec.finish(m, ga.state());
    let stop = result.map_or_else(stop_of, |()| Stop::Finished);
    let r = report(
        m,
        cables,
        &start,
        ga.state(),
        ga.multipliers(),
        stop,
        &ga.stats,
        cpu,
        run.rho_inf,
    );
    Ok((r, rec.table))
}

/// [`run_alpha`] through the contact events of `gaps`: the report's
/// `contact_events` and the sustained contacts' forces at the end.
fn run_contacts<M: Reported>(
    m: &M,
    cables: &[CableLayout],
    state: State,
    names: (&[String], &[String]),
    run: &ElementRun,
    gaps: &Gaps,
    progress: &mut dyn FnMut(f64),
) -> Result<(RunReport, Option<Table>), RunError> {
    let clock = Instant::now();
    let start = state.clone();
    let mut rec = Recorder::new(cables, names, run);
    let mut contacts = ContactRun::new(gaps);
    let mut guard = EnergyGuard::new(m, &start);
    let (end, error) = contacts.run(m, state, &run.alpha_options(), run.t_end, |s, q| {
        progress(s.t);
        match q {
            Some(q) => {
                rec.record(m, s, q);
                guard.step(m, s)
            }
            None => {
                rec.record(m, s, &m.full_of(&s.q));
                guard.check(m, s)
            }
        }
    });
    let error = error.or_else(|| guard.check(m, &end).err());
    let cpu = clock.elapsed().as_secs_f64();
    rec.finish(m, &end);
    let stop = error.map_or(Stop::Finished, stop_of);
    let mut r = report(
        m,
        cables,
        &start,
        &end,
        &contacts.multipliers,
        stop,
        &contacts.stats,
        cpu,
        run.rho_inf,
    );
    if let Some(el) = &mut r.elements {
        el.contact_forces = contacts
            .active
            .iter()
            .zip(&contacts.forces)
            .map(|(&i, &force)| ContactForce {
                contact: gaps.names[i].clone(),
                force,
            })
            .collect();
    }
    r.contact_events = contacts.events;
    Ok((r, rec.table))
}

/// Runs cables alone: `model` holds every cable (`cables` says where),
/// from its reference configuration, at rest unless its initial speeds are
/// set ([`StructuralModel::set_initial_velocity`]).
pub fn simulate_structure(
    model: &StructuralModel,
    cables: &[CableLayout],
    contacts: &[NodeContact],
    run: &ElementRun,
    progress: &mut dyn FnMut(f64),
) -> Result<(RunReport, Option<Table>), RunError> {
    let mut problems = run.problems();
    if !contacts.is_empty() && run.integrator == Integrator::Rk4 {
        problems.push(
            "contacts at cable nodes run on generalized-α (sustained contacts are index-3 constraints): use --integrator generalized-alpha"
                .to_string(),
        );
    }
    if !problems.is_empty() {
        return Err(RunError::Options(problems));
    }
    let state = State {
        t: 0.0,
        q: model.restrict(model.q0()),
        v: model.initial_velocity(),
    };
    if run.integrator != Integrator::Rk4 {
        let gaps = Gaps::new(contacts, |i| model.free_index(i), model.q0());
        return run_alpha(model, cables, state, (&[], &[]), run, &gaps, progress);
    }
    let clock = Instant::now();
    let start = state.clone();
    let mut rec = Recorder::new(cables, (&[], &[]), run);
    rec.record(model, &start, model.q0());
    let (mut last, mut taken) = (start.clone(), 0);
    let result = integrate_rk4(model, state, run.t_end, run.steps(), |s, q| {
        progress(s.t);
        rec.record(model, s, q);
        last.clone_from(s);
        taken += 1;
    });
    let cpu = clock.elapsed().as_secs_f64();
    let (end, stats, stop) = match result {
        Ok((end, stats)) => (end, stats, Stop::Finished),
        Err(e) => {
            // The steps before the one that failed, and that one's four
            // stages.
            let stats = DynamicsStats {
                steps: taken,
                force_evaluations: 4 * (taken + 1),
                factorizations: 1,
                ..DynamicsStats::default()
            };
            (last, stats, stop_of(e))
        }
    };
    rec.finish(model, &end);
    let r = report(
        model,
        cables,
        &start,
        &end,
        &[],
        stop,
        &stats,
        cpu,
        f64::NAN,
    );
    Ok((r, rec.table))
}

/// Runs a rigid part with cables hung at its markers from the rigid
/// coordinates `q0` and speeds `u0` (the cables at their reference, at
/// rest); `coordinates` and `speeds` name the rigid part's.
pub fn simulate_mixed(
    model: &MixedModel<'_>,
    cables: &[CableLayout],
    contacts: &[NodeContact],
    (q0, u0): (&[f64], &[f64]),
    names: (&[String], &[String]),
    run: &ElementRun,
    progress: &mut dyn FnMut(f64),
) -> Result<(RunReport, Option<Table>), RunError> {
    let mut problems = run.problems();
    if run.integrator == Integrator::Rk4 {
        problems.push(
            "the cables hang at rigid bodies: the attachments are constraints (an index-3 \
             differential-algebraic system), which rk4 does not solve; use --integrator \
             generalized-alpha"
                .to_string(),
        );
    }
    if !problems.is_empty() {
        return Err(RunError::Options(problems));
    }
    let state = model.initial_state(0.0, q0, u0);
    // The structure's free coordinates come first in `y`: its free
    // indices are the mixed model's.
    let st = model.structure();
    let gaps = Gaps::new(contacts, |i| st.free_index(i), st.q0())
        .with_bodies(model, &model.rigid().contact_names(), &state)
        .map_err(|e| RunError::Options(vec![e]))?;
    run_alpha(model, cables, state, names, run, &gaps, progress)
}

fn load_steps(steps: &[LoadStep]) -> Vec<LoadStepReport> {
    steps
        .iter()
        .map(|s| LoadStepReport {
            lambda: s.lambda,
            iterations: s.iterations(),
            residuals: s.residuals.clone(),
        })
        .collect()
}

/// The gaps of every contact of `m` at rest at its free coordinates `y`:
/// the cable nodes' `contacts` (`gaps`: planes, then spheres), then the
/// model's own (`bodies`, a mixed model's rigid part's), named; NaN where
/// they cannot be evaluated.
fn gaps_at_rest<M: Impacts + ?Sized>(
    m: &M,
    gaps: &Gaps,
    bodies: &[String],
    y: &[f64],
) -> Vec<(String, f64)> {
    let s = State {
        t: 0.0,
        q: y.to_vec(),
        v: vec![0.0; y.len()],
    };
    match gaps.clone().with_bodies(m, bodies, &s) {
        Ok(all) => all.names.iter().cloned().zip(all.gaps_at(m, &s)).collect(),
        // The model's own contacts cannot be evaluated here.
        Err(_) => gaps
            .names
            .iter()
            .cloned()
            .zip(gaps.gaps_at(m, &s))
            .chain(bodies.iter().map(|b| (b.clone(), f64::NAN)))
            .collect(),
    }
}

/// The gaps of the contacts of cables alone (`contacts`, at their nodes)
/// at the free coordinates `y`, named: what statics and linearisation,
/// which hold no contacts, check their equilibrium against.
pub fn contact_gaps_structure(
    model: &StructuralModel,
    contacts: &[NodeContact],
    y: &[f64],
) -> Vec<(String, f64)> {
    let gaps = Gaps::new(contacts, |i| model.free_index(i), model.q0());
    gaps_at_rest(model, &gaps, &[], y)
}

/// The gaps of a mixed model's contacts at its free coordinates `y` at
/// rest, named: the cable nodes' (`contacts`), then the rigid part's own
/// (its generated `contacts`); NaN where they cannot be evaluated.
pub fn contact_gaps_mixed(
    model: &MixedModel<'_>,
    contacts: &[NodeContact],
    y: &[f64],
) -> Vec<(String, f64)> {
    let st = model.structure();
    let gaps = Gaps::new(contacts, |i| st.free_index(i), st.q0());
    gaps_at_rest(model, &gaps, &model.rigid().contact_names(), y)
}

/// The contacts an equilibrium found without them goes through (a gap
/// below `−GAP_TOL`, or one that cannot be evaluated).
fn penetrated(gaps: Vec<(String, f64)>) -> Vec<(String, f64)> {
    gaps.into_iter()
        .filter(|(_, g)| g.is_nan() || *g < -crate::run::GAP_TOL)
        .collect()
}

/// The static equilibrium of cables alone: Newton with load stepping on
/// the structure of every cable (`cables` says where each sits). Statics
/// holds no contacts: an equilibrium through one of the node `contacts`
/// is refused ([`StaticError::Penetrated`]); one that leaves them open or
/// touching is an equilibrium with them.
pub fn equilibrium_structure(
    model: &StructuralModel,
    cables: &[CableLayout],
    contacts: &[NodeContact],
    opts: &StaticOptions,
) -> Result<StaticReport, StaticError> {
    let clock = Instant::now();
    let sol = solve_static(model, opts)?;
    let through = penetrated(contact_gaps_structure(
        model,
        contacts,
        &model.restrict(&sol.q),
    ));
    if !through.is_empty() {
        return Err(StaticError::Penetrated(through));
    }
    let cpu_s = clock.elapsed().as_secs_f64();
    Ok(StaticReport {
        q: Vec::new(),
        unknowns: model.n_free(),
        constraints: 0,
        load_steps: load_steps(&sol.steps),
        cuts: sol.cuts,
        regularized: 0,
        factorizations: sol.factorizations,
        cpu_s,
        constraint_residual: 0.0,
        condition: f64::NAN,
        stability: None,
        cables: cables.iter().map(|c| c.state(&sol.q)).collect(),
        mounts: Vec::new(),
    })
}

/// The static equilibrium of a rigid part with cables hung at its
/// markers, from the rigid coordinates `q0` (Newton on the KKT system
/// with load stepping), with its stability. Statics holds no contacts: an
/// equilibrium through one (the node `contacts`, or the rigid part's own)
/// is refused ([`MixedStaticError::Penetrated`]).
pub fn equilibrium_mixed(
    model: &MixedModel<'_>,
    cables: &[CableLayout],
    contacts: &[NodeContact],
    q0: &[f64],
    opts: &StaticOptions,
) -> Result<StaticReport, MixedStaticError> {
    let clock = Instant::now();
    let sol = solve_static_mixed(model, 0.0, q0, opts)?;
    let through = penetrated(contact_gaps_mixed(model, contacts, &sol.y));
    if !through.is_empty() {
        return Err(MixedStaticError::Penetrated(through));
    }
    let cpu_s = clock.elapsed().as_secs_f64();
    let summary = sol.stability.to_string();
    let stability = match &sol.stability {
        Stability::Stable { omega2_min } => StabilityReport {
            stable: Some(true),
            omega2_min: *omega2_min,
            negative: 0,
            reason: None,
            summary,
        },
        Stability::Unstable {
            omega2_min,
            negative,
        } => StabilityReport {
            stable: Some(false),
            omega2_min: *omega2_min,
            negative: *negative,
            reason: None,
            summary,
        },
        Stability::NotChecked { reason } => StabilityReport {
            stable: None,
            omega2_min: f64::NAN,
            negative: 0,
            reason: Some(reason.to_string()),
            summary,
        },
    };
    Ok(StaticReport {
        q: sol.y[model.n_structural()..].to_vec(),
        unknowns: model.n(),
        constraints: model.n_constraints(),
        load_steps: load_steps(&sol.steps),
        cuts: sol.cuts,
        regularized: sol.regularized,
        factorizations: sol.factorizations,
        cpu_s,
        constraint_residual: sol.constraint_residual,
        condition: sol.condition,
        stability: Some(stability),
        cables: cables.iter().map(|c| c.state(&sol.q_full)).collect(),
        mounts: model.mounts(&sol.lambda),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cubic Hermite interpolant is exact for a cubic motion: its
    /// positions and, as its derivative, its speeds.
    #[test]
    fn hermite_is_exact_for_cubics() {
        let q = |t: f64| 2.0 - 0.5 * t + 3.0 * t * t - 1.25 * t * t * t;
        let v = |t: f64| -0.5 + 6.0 * t - 3.75 * t * t;
        let at = |t: f64| State {
            t,
            q: vec![q(t), -q(t)],
            v: vec![v(t), -v(t)],
        };
        let (a, b) = (at(0.3), at(0.7));
        for t in [0.3, 0.35, 0.5, 0.61, 0.7] {
            let s = hermite(&a, &b, t);
            assert!((s.q[0] - q(t)).abs() < 1e-14 && (s.q[1] + q(t)).abs() < 1e-14);
            assert!((s.v[0] - v(t)).abs() < 1e-13 && (s.v[1] + v(t)).abs() < 1e-13);
        }
    }
}
