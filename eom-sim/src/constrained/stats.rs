//! What the constraint methods report along a run: [`ConstraintStats`],
//! [`Refusal`], the recorder that gathers them at the accepted states, and
//! the singular-value ratio of `J M^{-1/2}` the refusals watch.

use super::linalg::{max_abs, numerical_rank, singular_values};
use super::{ConstraintValues, DMatrix, Dynamics};
use std::cell::RefCell;

/// What the solver saw along a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConstraintStats {
    /// Largest `|Φ|` (holonomic rows) at the accepted states.
    pub max_position_residual: f64,
    /// Largest `|Φ̇|` at the accepted states.
    pub max_velocity_residual: f64,
    /// Numerical rank of `J` (at the last accepted state).
    pub rank: usize,
    /// Smallest rank seen.
    pub min_rank: usize,
    /// Changes of the coordinate partition ([`Method::Partitioning`]).
    ///
    /// [`Method::Partitioning`]: super::Method::Partitioning
    pub repartitions: usize,
    /// Smallest `σ_r / σ_1` of `J` at the accepted states, `r` the rank at
    /// the first of them: how near the run came to a singular
    /// configuration (of order 1 far from one, towards 0 at one, such as
    /// the four-bar's change point, where the rank drops between steps
    /// without any step landing on it); 1 if nothing was recorded.
    pub min_singular_ratio: f64,
    /// Why the method stopped the run, if it refused to go on (the
    /// right-hand side is NaN from then on, so the integrator stops with
    /// [`StopReason::NonFinite`](crate::StopReason::NonFinite)).
    pub refusal: Option<Refusal>,
}

/// A method's refusal to continue a run it cannot get right.
#[derive(Clone, Debug, PartialEq)]
pub enum Refusal {
    /// Near a singular configuration (a rank drop of `J`, where the
    /// mobility changes: the four-bar's collinear change point).
    SingularConfiguration {
        /// The method's `--constraints` name.
        method: &'static str,
        /// Time of the state that came too near.
        t: f64,
        /// `σ_r / σ_1` of `J M^{-1/2}` there, `r` the rank at the start.
        singular_ratio: f64,
        /// Methods that pass such configurations.
        recommended: &'static str,
    },
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::SingularConfiguration {
                method,
                t,
                singular_ratio,
                recommended,
            } => write!(
                f,
                "--constraints {method} stopped at t = {t} s near a singular configuration: the \
                 constraint Jacobian is losing rank (σ_r/σ_1 = {singular_ratio:.1e}; links \
                 aligned, the mobility changes there), where this method's multipliers are \
                 undetermined along the vanishing direction and would corrupt the motion; use \
                 --constraints {recommended}"
            ),
        }
    }
}

/// [`ConstraintStats`] gathered at the accepted states of a run, and the
/// rank of `J` at the first of them (which singular value to watch).
pub(super) struct Recorder(pub(super) RefCell<(ConstraintStats, Option<usize>)>);

impl Recorder {
    pub(super) fn new() -> Self {
        Recorder(RefCell::new((
            ConstraintStats {
                min_rank: usize::MAX,
                min_singular_ratio: 1.0,
                ..ConstraintStats::default()
            },
            None,
        )))
    }

    /// Residuals of the first `nh` (holonomic) rows and of all speed rows,
    /// the rank of `J` and how near it is to losing it, at an accepted state.
    pub(super) fn record(&self, nh: usize, c: &ConstraintValues) {
        let sigma = singular_values(&c.jacobian);
        let largest = sigma.first().copied().unwrap_or(0.0);
        let rank = numerical_rank(&sigma);
        let (s, first_rank) = &mut *self.0.borrow_mut();
        s.max_position_residual = s.max_position_residual.max(max_abs(c.phi.iter().take(nh)));
        s.max_velocity_residual = s.max_velocity_residual.max(max_abs(c.phidot.iter()));
        let watched = *first_rank.get_or_insert(rank);
        if watched > 0 && largest > 0.0 {
            let ratio = sigma.get(watched - 1).copied().unwrap_or(0.0) / largest;
            s.min_singular_ratio = s.min_singular_ratio.min(ratio);
        }
        s.rank = rank;
        s.min_rank = s.min_rank.min(rank);
    }

    pub(super) fn stats(&self) -> ConstraintStats {
        let mut s = self.0.borrow().0.clone();
        if s.min_rank == usize::MAX {
            s.min_rank = s.rank;
        }
        s
    }

    pub(super) fn repartitioned(&self) {
        self.0.borrow_mut().0.repartitions += 1;
    }
}

/// `σ_r / σ_1` of `J M^{-1/2}` at `(t, q)`, `r` the rank at the first state
/// asked about (kept in `start_rank`); 1 without constraints, 0 where `M`
/// is not positive definite.
pub(super) fn weighted_singular_ratio<D: Dynamics + ?Sized>(
    d: &D,
    t: f64,
    q: &[f64],
    start_rank: &std::cell::Cell<Option<usize>>,
) -> f64 {
    let (nu, nc) = (d.nu(), d.nc());
    let mut m = DMatrix::zeros(nu, nu);
    let mut c = ConstraintValues::zeros(nc, nu);
    d.mass_matrix(t, q, &mut m);
    d.constraints(t, q, &vec![0.0; nu], &mut c);
    let Some(l) = m.cholesky().map(|c| c.l()) else {
        return 0.0;
    };
    let Some(at) = l.solve_lower_triangular(&c.jacobian.transpose()) else {
        return 0.0;
    };
    let sigma = singular_values(&at);
    let r = match start_rank.get() {
        Some(r) => r,
        None => {
            let r = numerical_rank(&sigma);
            start_rank.set(Some(r));
            r
        }
    };
    match (r, sigma.first()) {
        (0, _) | (_, None) => 1.0,
        (r, Some(&s1)) => sigma.get(r - 1).copied().unwrap_or(0.0) / s1.max(f64::MIN_POSITIVE),
    }
}
