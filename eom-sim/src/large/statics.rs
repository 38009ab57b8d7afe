//! Static equilibrium `f_int(q, 0) = λ f_ext` by Newton's method with load
//! stepping ([`load_stepping`], the frame the mixed model's statics share,
//! [`super::mixed::statics`]): the load factor `λ` goes from 0 to 1 in steps; each step is
//! solved by Newton from the secant extrapolation of the last two
//! equilibria (full Newton by default; modified Newton on request; the tangent
//! `∂f_int/∂q` assembled from the element Jacobians, factored by LU,
//! banded when the pattern is, else sparse with the symbolic analysis
//! reused: [`super::sparse::AutoLu`]); a step that does not converge is
//! halved, down to a smallest step, after which the solve refuses.

use super::model::StructuralModel;
use super::norm_inf;
use super::sparse::{AutoLu, FactorError, SparseMatrix, SparseSolver};
use std::fmt;

/// Settings of [`solve_static`].
#[derive(Clone, Debug)]
pub struct StaticOptions {
    /// Number of equal load steps to begin with.
    pub load_steps: usize,
    /// Newton iterations allowed per load step.
    pub max_iterations: usize,
    /// A load step has converged when the residual `r = f_int − λ f_ext`
    /// satisfies `‖r‖∞ ≤ rtol · ‖λ f_ext‖∞ + atol + floor`, where
    /// `floor = 4 ε ‖K‖∞ ‖q‖∞` is the round-off in evaluating `f_int`
    /// (`ε` the machine epsilon, `K` the last tangent): a stiff axial term
    /// (`EA/L_e` of 1e11 N/m) leaves residuals of 1e-5 N that no iteration
    /// removes.
    pub rtol: f64,
    /// Absolute residual tolerance (force units).
    pub atol: f64,
    /// How many times a load step may be halved before the solve refuses.
    pub max_cuts: usize,
    /// The first tangent's condition number estimate (`‖K‖∞ ‖K⁻¹‖`, the
    /// latter by inverse iteration) above which the solve refuses: an
    /// unsupported structure has a singular tangent that rounding makes
    /// merely huge, and Newton would "converge" to a rigid drift.
    pub max_condition: f64,
    /// Modified Newton: keep the factored tangent while each residual is
    /// at most a quarter of the one before (a load step that fails so is
    /// retried with full Newton before it is halved). Default `false`
    /// (full Newton): on the Gerstmayr–Irschik cantilever the kept tangent
    /// needed more iterations and retries, and ran 5–7× slower.
    pub reuse_tangent: bool,
}

impl Default for StaticOptions {
    fn default() -> Self {
        StaticOptions {
            load_steps: 10,
            max_iterations: 25,
            rtol: 1e-10,
            atol: 1e-12,
            max_cuts: 8,
            max_condition: 1e13,
            reuse_tangent: false,
        }
    }
}

/// One accepted load step.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadStep {
    /// Load factor reached.
    pub lambda: f64,
    /// The residual tolerance of the step (with the round-off floor).
    pub tolerance: f64,
    /// `‖r‖∞` before each Newton correction and after the last one.
    pub residuals: Vec<f64>,
}

impl LoadStep {
    /// Newton iterations taken.
    pub fn iterations(&self) -> usize {
        self.residuals.len().saturating_sub(1)
    }
}

/// A static solution.
#[derive(Clone, Debug)]
pub struct StaticSolution {
    /// Full coordinates at equilibrium under the whole load.
    pub q: Vec<f64>,
    /// The accepted load steps in order.
    pub steps: Vec<LoadStep>,
    /// Load steps that failed and were halved.
    pub cuts: usize,
    /// Numeric factorisations of the tangent.
    pub factorizations: usize,
}

/// Why a static solve gave up.
#[derive(Clone, Debug, PartialEq)]
pub enum StaticError {
    /// Newton did not converge at the smallest load step allowed.
    NoConvergence {
        /// Last load factor reached in equilibrium.
        lambda_reached: f64,
        /// Load factor tried.
        lambda_tried: f64,
        /// Residual history of the last attempt.
        residuals: Vec<f64>,
        /// Steps accepted before.
        steps: Vec<LoadStep>,
    },
    /// The tangent could not be factored (singular: a mechanism, a free
    /// rigid motion without support).
    Singular {
        /// Load factor tried.
        lambda: f64,
        /// The solver's reason.
        reason: FactorError,
    },
    /// The tangent factors, but its condition number estimate is above
    /// [`StaticOptions::max_condition`] (nearly a mechanism).
    IllConditioned {
        /// Load factor tried.
        lambda: f64,
        /// The estimate (NaN where it could not be formed).
        condition: f64,
    },
    /// The equilibrium found goes through contacts, which statics does not
    /// hold: each with its gap (negative; NaN where it could not be
    /// evaluated).
    Penetrated(Vec<(String, f64)>),
}

/// The message of an equilibrium found through the contacts `through`.
pub(crate) fn penetrated_message(through: &[(String, f64)]) -> String {
    let list: Vec<String> = through
        .iter()
        .map(|(c, g)| format!("`{c}` by {:.3e}", -g))
        .collect();
    format!(
        "the equilibrium found goes through contact(s) {}: statics holds no contacts (unilateral, they would carry a force there); it is an equilibrium only where every contact is open or touching: simulate the model to its rest instead, with a damper if it swings",
        list.join(", ")
    )
}

impl fmt::Display for StaticError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StaticError::Penetrated(through) => f.write_str(&penetrated_message(through)),
            StaticError::NoConvergence {
                lambda_reached,
                lambda_tried,
                residuals,
                ..
            } => write!(
                f,
                "Newton did not converge: equilibrium reached up to load factor {lambda_reached}, \
                 the step to {lambda_tried} failed after halving (residuals {:?}); \
                 try more load steps or check the supports",
                residuals
                    .iter()
                    .map(|r| format!("{r:.3e}"))
                    .collect::<Vec<_>>()
            ),
            StaticError::Singular { lambda, reason } => write!(
                f,
                "the tangent stiffness is singular at load factor {lambda} ({reason}): \
                 is the structure supported against rigid motion?"
            ),
            StaticError::IllConditioned { lambda, condition } => write!(
                f,
                "the tangent stiffness is singular at load factor {lambda} (condition number \
                 estimate {condition:.1e}): is the structure supported against rigid motion?"
            ),
        }
    }
}

impl std::error::Error for StaticError {}

/// `‖K‖∞`, the largest absolute row sum.
fn inf_norm(k: &SparseMatrix) -> f64 {
    let n = k.pattern().n();
    let mut row_sums = vec![0.0; n];
    let ones = vec![1.0; n];
    let mut abs = k.clone();
    abs.values.iter_mut().for_each(|v| *v = v.abs());
    abs.mul_add(1.0, &ones, &mut row_sums);
    norm_inf(&row_sums)
}

/// `‖K‖∞ · ‖K⁻¹‖₂`-estimate: a few steps of inverse iteration with the
/// factored `K` from a fixed start vector.
fn condition_estimate(k: &SparseMatrix, lu: &AutoLu) -> f64 {
    let n = k.pattern().n();
    let knorm = inf_norm(k);
    let mut x: Vec<f64> = (0..n)
        .map(|i| 1.0 + ((i * 7919) % 13) as f64 / 13.0)
        .collect();
    let mut growth = 0.0;
    for _ in 0..6 {
        let nx = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        x.iter_mut().for_each(|v| *v /= nx);
        lu.solve(&mut x);
        growth = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !growth.is_finite() {
            return f64::INFINITY;
        }
    }
    knorm * growth
}

/// What one load step's Newton solve reports to [`load_stepping`].
pub(crate) enum Newton<F> {
    /// Equilibrium at the target load factor, within `tolerance`.
    Converged {
        /// The step's residual tolerance (with the round-off floor).
        tolerance: f64,
        /// `‖r‖∞` before each correction and after the last one.
        residuals: Vec<f64>,
    },
    /// No equilibrium from this start: the step is halved; `F` says what
    /// the last attempt saw, for the error if halving runs out.
    Failed(F),
}

/// Where load stepping gave up: the last equilibrium and the step tried.
pub(crate) struct Stalled {
    /// Last load factor reached in equilibrium.
    pub lambda_reached: f64,
    /// Load factor tried.
    pub lambda_tried: f64,
    /// Steps accepted before.
    pub steps: Vec<LoadStep>,
}

/// The load-stepping frame written once for every static solve (a
/// structure alone and a mixed model): the load factor goes from 0 to 1 in
/// `opts.load_steps` equal steps; each step's Newton solve (`newton`, given
/// the target factor and the secant extrapolation of the last two
/// equilibria, which it improves in place) converges or fails; a failed
/// step is halved up to `opts.max_cuts` times in a row, after which
/// `stalled` makes the error. Returns the accepted steps and the number of
/// halvings; `x` ends at the equilibrium under the whole load.
pub(crate) fn load_stepping<F, E>(
    opts: &StaticOptions,
    x: &mut Vec<f64>,
    mut newton: impl FnMut(f64, &mut Vec<f64>) -> Result<Newton<F>, E>,
    stalled: impl FnOnce(Stalled, F) -> E,
) -> Result<(Vec<LoadStep>, usize), E> {
    let mut steps = Vec::new();
    let mut cuts = 0usize;
    let mut lambda = 0.0;
    let mut dl = 1.0 / opts.load_steps.max(1) as f64;
    let mut halvings = 0usize;
    let mut previous: Option<(Vec<f64>, f64)> = None;
    while lambda < 1.0 {
        let mut target = lambda + dl;
        if target > 1.0 - 1e-12 {
            target = 1.0;
        }
        // Secant predictor: extrapolate the last two equilibria.
        let mut xt = x.clone();
        if let Some((x_prev, l_prev)) = &previous
            && lambda > *l_prev
        {
            let s = (target - lambda) / (lambda - l_prev);
            for ((a, b), c) in xt.iter_mut().zip(x.iter()).zip(x_prev) {
                *a = b + s * (b - c);
            }
        }
        match newton(target, &mut xt)? {
            Newton::Converged {
                tolerance,
                residuals,
            } => {
                previous = Some((std::mem::replace(x, xt), lambda));
                lambda = target;
                steps.push(LoadStep {
                    lambda: target,
                    tolerance,
                    residuals,
                });
                halvings = 0;
            }
            Newton::Failed(failure) => {
                if halvings >= opts.max_cuts {
                    let at = Stalled {
                        lambda_reached: lambda,
                        lambda_tried: target,
                        steps,
                    };
                    return Err(stalled(at, failure));
                }
                halvings += 1;
                cuts += 1;
                dl *= 0.5;
            }
        }
    }
    Ok((steps, cuts))
}

/// Solves `f_int(q, 0) = f_ext` from the model's initial coordinates.
pub fn solve_static(
    model: &StructuralModel,
    opts: &StaticOptions,
) -> Result<StaticSolution, StaticError> {
    let n = model.n_free();
    let load = model.load_free();
    let zero_full = vec![0.0; model.n_full()];
    let mut scratch = vec![0.0; model.n_full()];
    let mut q_full = model.q0().to_vec();
    let mut x = model.restrict(&q_full);
    let mut tangent = SparseMatrix::zeros(model.pattern().clone());
    let mut lu = AutoLu::default();
    let mut r = vec![0.0; n];
    let mut full_newton = false;
    let newton = |target: f64, xt: &mut Vec<f64>| {
        let start = xt.clone();
        let base_tol = opts.rtol * target * norm_inf(&load) + opts.atol;
        loop {
            let mut tol = base_tol;
            let mut residuals = Vec::new();
            let mut converged = false;
            // Modified Newton: the factored tangent is kept (across load
            // steps too) while each residual is at most a quarter of the
            // one before.
            let mut refresh = full_newton || !opts.reuse_tangent || lu.factorizations() == 0;
            let mut fresh = false;
            let mut stale_used = false;
            for it in 0..=opts.max_iterations {
                model.expand_into(xt, &mut q_full);
                model.internal(&q_full, &zero_full, &mut scratch, &mut r);
                for (ri, fi) in r.iter_mut().zip(&load) {
                    *ri -= target * fi;
                }
                let rn = norm_inf(&r);
                residuals.push(rn);
                if !rn.is_finite() {
                    break;
                }
                if rn <= tol {
                    converged = true;
                    break;
                }
                if it == opts.max_iterations {
                    break;
                }
                if let [.., before, last] = residuals[..]
                    && last > 0.25 * before
                    && !fresh
                {
                    refresh = true;
                }
                fresh = false;
                if !refresh {
                    stale_used = true;
                    lu.solve(&mut r);
                    for (a, d) in xt.iter_mut().zip(&r) {
                        *a -= d;
                    }
                    continue;
                }
                refresh = full_newton || !opts.reuse_tangent;
                fresh = true;
                model.jacobian(&q_full, &zero_full, 1.0, 0.0, 0.0, &mut tangent);
                tol = base_tol + 4.0 * f64::EPSILON * inf_norm(&tangent) * norm_inf(&q_full);
                if let Err(reason) = lu.factor(&tangent) {
                    return Err(StaticError::Singular {
                        lambda: target,
                        reason,
                    });
                }
                if lu.factorizations() == 1 {
                    let cond = condition_estimate(&tangent, &lu);
                    if cond.is_nan() || cond >= opts.max_condition {
                        return Err(StaticError::IllConditioned {
                            lambda: target,
                            condition: cond,
                        });
                    }
                }
                lu.solve(&mut r);
                for (a, d) in xt.iter_mut().zip(&r) {
                    *a -= d;
                }
            }
            if !converged && stale_used && !full_newton {
                // Retry the step with full Newton before halving it.
                full_newton = true;
                xt.copy_from_slice(&start);
                continue;
            }
            full_newton = false;
            return Ok(if converged {
                Newton::Converged {
                    tolerance: tol,
                    residuals,
                }
            } else {
                Newton::Failed(residuals)
            });
        }
    };
    let (steps, cuts) = load_stepping(opts, &mut x, newton, |at, residuals| {
        StaticError::NoConvergence {
            lambda_reached: at.lambda_reached,
            lambda_tried: at.lambda_tried,
            residuals,
            steps: at.steps,
        }
    })?;
    model.expand_into(&x, &mut q_full);
    Ok(StaticSolution {
        q: q_full,
        steps,
        cuts,
        factorizations: lu.factorizations(),
    })
}
