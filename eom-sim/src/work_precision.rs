//! Work-precision: error against CPU time over a sweep of tolerances or
//! step sizes, per integrator and constraint solver (Hairer & Wanner's
//! work-precision diagrams).
//!
//! A [`Runner`] integrates one system from its initial state with given
//! [`Settings`] and returns the positions at the end and at sample times.
//! [`reference`] integrates it at a much tighter tolerance with DOP853 and
//! checks that solution with a second method (DOPRI5 at the same
//! tolerance); [`point`] runs one setting, measures its error against the
//! reference — at the end time and the largest along the path (dense
//! output at the sample times) — and its CPU time, the median of repeated
//! runs without output.
//!
//! Errors are measured on the positions `q` (the coordinates a user
//! reads), relative to the reference's largest coordinate:
//! `‖q − q_ref‖∞ / ‖q_ref‖∞` at the end, and the largest such difference
//! along the path over the largest reference coordinate along the path.
//! Significant correct digits are `−log10(error)`.

use crate::constrained::{ConstrainedModel, ConstrainedSystem, Generated, Index3System, Method};
use crate::integrate::by_name::{Settings, solve};
use crate::integrate::driver::SolveOptions;
use crate::integrate::system::OdeSystem;
use crate::integrate::{Stats, StopReason};
use crate::run::Integrator;
#[cfg(feature = "serde")]
use serde::Serialize;
use std::time::Instant;

/// The positions of one run at its end and at the sample times.
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// Time where the run stopped.
    pub t_final: f64,
    /// Positions at `t_final`.
    pub q_final: Vec<f64>,
    /// Positions at the sample times reached (dense output).
    pub samples: Vec<Vec<f64>>,
    /// The integrator's counters.
    pub stats: Stats,
    /// Why the run stopped.
    pub stop: StopReason,
}

/// Something that can be integrated from its initial state.
pub trait Runner {
    /// Integrates to `t_end` with `settings` (and `method` for constrained
    /// systems), recording the positions at `t_eval` if `t_eval` is not
    /// empty; `None` for an unknown integrator or a combination that does
    /// not apply (the index-3 DAE without RADAU5).
    fn run(
        &self,
        settings: &Settings,
        method: Method,
        t_end: f64,
        t_eval: &[f64],
    ) -> Option<Trajectory>;
}

/// The positions part of a solution.
fn trajectory<const K: usize>(sol: crate::Solution<K>, nq: usize) -> Trajectory {
    let nq = nq.min(K);
    Trajectory {
        t_final: sol.t_final,
        q_final: sol.y_final[..nq].to_vec(),
        samples: sol.y_out.iter().map(|y| y[..nq].to_vec()).collect(),
        stats: sol.stats,
        stop: sol.stop,
    }
}

fn options(t_eval: &[f64]) -> SolveOptions {
    SolveOptions {
        max_steps: 10_000_000,
        record_steps: false,
        t_eval: t_eval.to_vec(),
    }
}

/// A first-order system whose first `nq` components are the positions.
pub struct OdeRunner<'a, S, const N: usize> {
    /// The system.
    pub sys: &'a S,
    /// Initial state.
    pub y0: [f64; N],
    /// Number of position components (the first ones).
    pub nq: usize,
}

impl<S: OdeSystem<N>, const N: usize> Runner for OdeRunner<'_, S, N> {
    fn run(
        &self,
        settings: &Settings,
        _: Method,
        t_end: f64,
        t_eval: &[f64],
    ) -> Option<Trajectory> {
        Some(trajectory(
            solve(settings, self.sys, 0.0, self.y0, t_end, &options(t_eval)),
            self.nq,
        ))
    }
}

/// A generated model from its initial state; `N = n_q + n_u` and
/// `NC = N + m` (the index-3 DAE's state). Constrained models are
/// assembled first (the same assembly for every run).
pub struct ModelRunner<'a, M, const N: usize, const NC: usize> {
    model: &'a M,
    q0: Vec<f64>,
    u0: Vec<f64>,
}

impl<'a, M: ConstrainedModel + OdeSystem<N>, const N: usize, const NC: usize>
    ModelRunner<'a, M, N, NC>
{
    /// The runner of `model` from its `q0`, `u0` (assembled onto the
    /// constraints, if any).
    pub fn new(model: &'a M) -> Self {
        let (q0, u0) = (model.q0(), model.u0());
        let (mut q0, mut u0) = (q0.as_ref().to_vec(), u0.as_ref().to_vec());
        if M::NC > 0 {
            let a = crate::constrained::assemble(&Generated(model), &q0, &u0, 0.0);
            (q0, u0) = (a.q, a.u);
        }
        ModelRunner { model, q0, u0 }
    }

    fn y0(&self) -> [f64; N] {
        let mut y = [0.0; N];
        for (d, s) in y.iter_mut().zip(self.q0.iter().chain(&self.u0)) {
            *d = *s;
        }
        y
    }
}

impl<M: ConstrainedModel + OdeSystem<N>, const N: usize, const NC: usize> Runner
    for ModelRunner<'_, M, N, NC>
{
    fn run(
        &self,
        settings: &Settings,
        method: Method,
        t_end: f64,
        t_eval: &[f64],
    ) -> Option<Trajectory> {
        let finish = |sol: crate::Solution<N>| trajectory(sol, M::NQ);
        if M::NC == 0 {
            return Some(finish(solve(
                settings,
                self.model,
                0.0,
                self.y0(),
                t_end,
                &options(t_eval),
            )));
        }
        let d = Generated(self.model);
        if method == Method::Index3 {
            if settings.integrator != Integrator::Radau5 {
                return None;
            }
            let dae = Index3System::new(&d);
            let y0 = dae.initial::<NC>(0.0, &self.q0, &self.u0)?;
            let s = Settings {
                index_vars: dae.index_vars(),
                ..settings.clone()
            };
            return Some(trajectory(
                solve(&s, &dae, 0.0, y0, t_end, &options(t_eval)),
                M::NQ,
            ));
        }
        let sys = ConstrainedSystem::new(&d, method);
        Some(finish(solve(
            settings,
            &sys,
            0.0,
            self.y0(),
            t_end,
            &options(t_eval),
        )))
    }
}

/// `‖a − b‖∞`; infinite if a difference is NaN or the lengths differ.
fn difference(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(
            0.0,
            |m: f64, d| if d.is_nan() { f64::INFINITY } else { m.max(d) },
        )
}

fn norm(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m: f64, x| m.max(x.abs()))
}

/// The error at the end: `‖q − q_ref‖∞ / ‖q_ref‖∞`.
pub fn end_error(q: &[f64], q_ref: &[f64]) -> f64 {
    difference(q, q_ref) / norm(q_ref).max(f64::MIN_POSITIVE)
}

/// The largest error along the path: `max_k ‖q(t_k) − q_ref(t_k)‖∞` over
/// `max_k ‖q_ref(t_k)‖∞`; infinite if the run stopped before the last
/// sample.
pub fn path_error(samples: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
    if samples.len() != reference.len() {
        return f64::INFINITY;
    }
    let scale = reference.iter().map(|r| norm(r)).fold(0.0, f64::max);
    let worst = samples
        .iter()
        .zip(reference)
        .map(|(s, r)| difference(s, r))
        .fold(0.0, f64::max);
    worst / scale.max(f64::MIN_POSITIVE)
}

/// Significant correct digits of a relative error (`−log10`), 0 at or
/// above 1.
pub fn digits(error: f64) -> f64 {
    if error.is_finite() && error > 0.0 {
        (-error.log10()).max(0.0)
    } else if error == 0.0 {
        16.0
    } else {
        0.0
    }
}

/// `n + 1` sample times `k·t_end/n`, the last exactly `t_end`.
pub fn sample_times(t_end: f64, n: usize) -> Vec<f64> {
    let n = n.max(1);
    let mut t: Vec<f64> = (0..=n).map(|k| t_end * k as f64 / n as f64).collect();
    t[n] = t_end;
    t
}

/// The reference solution and how well a second method confirms it.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The reference run (DOP853).
    pub run: Trajectory,
    /// Its tolerance (`rtol = atol`).
    pub tol: f64,
    /// The sample times.
    pub t_eval: Vec<f64>,
    /// The constraint method of the reference (constrained systems).
    pub method: Method,
    /// End error of the check run (DOPRI5 at the same tolerance) against
    /// the reference.
    pub check_end_error: f64,
    /// Path error of the check run against the reference.
    pub check_path_error: f64,
}

impl Reference {
    /// What a report shows of the reference.
    pub fn summary(&self) -> ReferenceSummary {
        ReferenceSummary {
            integrator: Integrator::Dop853,
            check: Integrator::Dopri5,
            tol: self.tol,
            constraints: self.method,
            t_end: self.run.t_final,
            samples: self.t_eval.len(),
            rhs_evals: self.run.stats.rhs_evals,
            q_final: self.run.q_final.clone(),
            check_end_error: self.check_end_error,
            check_path_error: self.check_path_error,
        }
    }
}

/// The reference as a report shows it.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, serde::Deserialize))]
pub struct ReferenceSummary {
    /// The reference's integrator (DOP853).
    pub integrator: Integrator,
    /// The check's integrator (DOPRI5).
    pub check: Integrator,
    /// `rtol = atol` of both.
    pub tol: f64,
    /// Constraint method of both (constrained models).
    pub constraints: Method,
    /// End time reached.
    pub t_end: f64,
    /// Dense samples along the path.
    pub samples: usize,
    /// Right-hand sides of the reference run.
    pub rhs_evals: usize,
    /// Positions at the end.
    pub q_final: Vec<f64>,
    /// End error of the check against the reference.
    pub check_end_error: f64,
    /// Path error of the check against the reference.
    pub check_path_error: f64,
}

fn adaptive(integrator: Integrator, tol: f64) -> Settings {
    Settings {
        integrator,
        rtol: tol,
        atol: tol,
        dt: 0.0,
        index_vars: (0, 0),
    }
}

/// The reference: DOP853 at `rtol = atol = tol` (constrained systems with
/// projection), checked by DOPRI5 at the same tolerance; `None` if either
/// run does not finish.
pub fn reference<R: Runner + ?Sized>(
    r: &R,
    t_end: f64,
    tol: f64,
    samples: usize,
) -> Option<Reference> {
    let t_eval = sample_times(t_end, samples);
    let method = Method::Projection;
    let run = r.run(&adaptive(Integrator::Dop853, tol), method, t_end, &t_eval)?;
    let check = r.run(&adaptive(Integrator::Dopri5, tol), method, t_end, &t_eval)?;
    if run.stop != StopReason::Finished || check.stop != StopReason::Finished {
        return None;
    }
    Some(Reference {
        check_end_error: end_error(&check.q_final, &run.q_final),
        check_path_error: path_error(&check.samples, &run.samples),
        run,
        tol,
        t_eval,
        method,
    })
}

/// One setting of one method: tolerance for the adaptive methods, step
/// size for the fixed-step ones.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// The integrator.
    pub integrator: Integrator,
    /// Constraint method (ignored for unconstrained systems).
    pub method: Method,
    /// `rtol = atol` (adaptive) or the step size (fixed-step).
    pub setting: f64,
}

impl Case {
    /// True for the fixed-step methods (the setting is a step size).
    pub fn fixed_step(&self) -> bool {
        !self.integrator.is_adaptive()
    }

    fn settings(&self) -> Settings {
        if self.fixed_step() {
            Settings {
                dt: self.setting,
                ..adaptive(self.integrator, 0.0)
            }
        } else {
            adaptive(self.integrator, self.setting)
        }
    }
}

/// One point of a work-precision diagram.
#[derive(Clone, Debug)]
pub struct Point {
    /// What was run.
    pub case: Case,
    /// Median CPU time of one run, s.
    pub cpu_s: f64,
    /// How many timed runs the median is over.
    pub repeats: usize,
    /// Right-hand-side evaluations of one run.
    pub rhs_evals: usize,
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Error at the end time (see the module docs).
    pub end_error: f64,
    /// Largest error along the path.
    pub path_error: f64,
    /// Why the run stopped.
    pub stop: StopReason,
}

impl Point {
    /// Significant correct digits at the end time.
    pub fn digits(&self) -> f64 {
        digits(self.end_error)
    }

    /// What a report shows of the point.
    pub fn summary(&self) -> PointSummary {
        let finite = |x: f64| x.is_finite().then_some(x);
        PointSummary {
            integrator: self.case.integrator,
            constraints: self.case.method,
            fixed_step: self.case.fixed_step(),
            setting: self.case.setting,
            cpu_s: self.cpu_s,
            repeats: self.repeats,
            rhs_evals: self.rhs_evals,
            accepted: self.accepted,
            rejected: self.rejected,
            end_error: finite(self.end_error),
            path_error: finite(self.path_error),
            digits: finite(self.end_error).map(digits),
            // In words, as `simulate` says it.
            stop: crate::run::Stop::from_solver(self.stop, &[]).to_string(),
        }
    }
}

/// One point as a report shows it; errors are `None` for a run that did
/// not finish.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(Serialize, serde::Deserialize))]
pub struct PointSummary {
    /// Integrator.
    pub integrator: Integrator,
    /// Constraint method (meaningful for constrained models only).
    pub constraints: Method,
    /// True if `setting` is a step size.
    pub fixed_step: bool,
    /// Tolerance or step size.
    pub setting: f64,
    /// Median CPU time of one run, s.
    pub cpu_s: f64,
    /// Timed runs behind the median.
    pub repeats: usize,
    /// Right-hand sides of one run.
    pub rhs_evals: usize,
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Relative error of the positions at the end.
    pub end_error: Option<f64>,
    /// Largest relative error along the path.
    pub path_error: Option<f64>,
    /// Significant correct digits at the end.
    pub digits: Option<f64>,
    /// `finished` or why the run stopped.
    pub stop: String,
}

impl PointSummary {
    /// The series the point belongs to: the integrator, and the
    /// constraint method for constrained models.
    pub fn series(&self, constrained: bool) -> String {
        if constrained {
            format!("{} + {}", self.integrator, self.constraints)
        } else {
            self.integrator.to_string()
        }
    }
}

/// How long to time each point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// At least this many timed runs.
    pub min_repeats: usize,
    /// At most this many.
    pub max_repeats: usize,
    /// Keep repeating (up to `max_repeats`) until this much CPU time, s.
    pub min_total_s: f64,
}

impl Default for Timing {
    fn default() -> Self {
        Timing {
            min_repeats: 3,
            max_repeats: 51,
            min_total_s: 0.2,
        }
    }
}

/// Runs `case` once with samples for its errors, then times it (runs
/// without output; median). `None` if the case does not apply.
pub fn point<R: Runner + ?Sized>(
    r: &R,
    case: &Case,
    reference: &Reference,
    timing: &Timing,
) -> Option<Point> {
    let s = case.settings();
    let t_end = *reference.t_eval.last()?;
    let first = r.run(&s, case.method, t_end, &reference.t_eval)?;
    let finished = first.stop == StopReason::Finished;
    let (end, path) = if finished {
        (
            end_error(&first.q_final, &reference.run.q_final),
            path_error(&first.samples, &reference.run.samples),
        )
    } else {
        (f64::INFINITY, f64::INFINITY)
    };
    let mut times = Vec::new();
    let mut total = 0.0;
    while times.len() < timing.min_repeats.max(1)
        || (total < timing.min_total_s && times.len() < timing.max_repeats)
    {
        let start = Instant::now();
        let run = r.run(&s, case.method, t_end, &[]);
        let dt = start.elapsed().as_secs_f64();
        std::hint::black_box(&run);
        times.push(dt);
        total += dt;
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    Some(Point {
        case: case.clone(),
        cpu_s: median,
        repeats: times.len(),
        rhs_evals: first.stats.rhs_evals,
        accepted: first.stats.accepted,
        rejected: first.stats.rejected,
        end_error: end,
        path_error: path,
        stop: first.stop,
    })
}

/// The default sweep: tolerances `10^-k` for `k` in `tols`, step sizes
/// `t_end / n` for the fixed-step methods with `n` doubling from
/// `fixed_steps.0` to `fixed_steps.1`.
pub fn cases(
    integrators: &[Integrator],
    methods: &[Method],
    tols: &[f64],
    t_end: f64,
    fixed_steps: (usize, usize),
) -> Vec<Case> {
    let mut out = Vec::new();
    for &m in methods {
        for &i in integrators {
            if m == Method::Index3 && i != Integrator::Radau5 {
                continue;
            }
            if !i.is_adaptive() {
                let mut n = fixed_steps.0.max(1);
                while n <= fixed_steps.1.max(fixed_steps.0) {
                    out.push(Case {
                        integrator: i,
                        method: m,
                        setting: t_end / n as f64,
                    });
                    n *= 2;
                }
            } else {
                for &tol in tols {
                    out.push(Case {
                        integrator: i,
                        method: m,
                        setting: tol,
                    });
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FnSystem;

    /// A point that did not finish says why in words, as `simulate` does
    /// (`bench --work-precision` printed `NonFinite { t: 0.6798…,
    /// component: 0 }`).
    #[test]
    fn failed_points_say_why_in_words() {
        for (stop, says) in [
            (
                StopReason::NonFinite {
                    t: 0.6798,
                    component: 0,
                },
                "0.6798",
            ),
            (
                StopReason::ConvergenceFailure { t: 1.5 },
                "did not converge",
            ),
            (StopReason::MaxSteps { t: 2.0 }, "2"),
        ] {
            let p = Point {
                case: Case {
                    integrator: Integrator::Radau5,
                    method: Method::Projection,
                    setting: 1e-6,
                },
                cpu_s: 0.0,
                repeats: 1,
                rhs_evals: 0,
                accepted: 0,
                rejected: 0,
                end_error: f64::NAN,
                path_error: f64::NAN,
                stop,
            };
            let got = p.summary().stop;
            assert!(
                got.contains(says) && !got.contains('{') && !got.contains("NonFinite"),
                "{stop:?}: got `{got}`, want words naming {says}"
            );
        }
    }

    /// The harmonic oscillator `x'' = −x` from `x = 1` at rest: the
    /// reference must match `cos t`, and a sweep's errors must fall with
    /// the tolerance (adaptive) or as `h⁴` (RK4).
    #[test]
    fn oscillator_reference_and_sweep() {
        let sys = FnSystem(|_t: f64, y: &[f64; 2], dy: &mut [f64; 2]| {
            dy[0] = y[1];
            dy[1] = -y[0];
        });
        let r = OdeRunner {
            sys: &sys,
            y0: [1.0, 0.0],
            nq: 1,
        };
        let t_end = 10.0;
        let Some(reference) = reference(&r, t_end, 1e-13, 50) else {
            panic!("the reference did not finish")
        };
        // Against the closed form x = cos t, at the end and along the path.
        let exact: Vec<Vec<f64>> = reference.t_eval.iter().map(|t| vec![t.cos()]).collect();
        let e = path_error(&reference.run.samples, &exact);
        assert!(
            e < 1e-11,
            "reference path error against cos t: got {e:e}, want < 1e-11"
        );
        assert!(reference.check_end_error < 1e-10, "{reference:?}");
        let timing = Timing {
            min_repeats: 1,
            max_repeats: 1,
            min_total_s: 0.0,
        };
        let pts: Vec<Point> = cases(
            &[Integrator::Dop853, Integrator::Rk4],
            &[Method::Projection],
            &[1e-4, 1e-8],
            t_end,
            (100, 400),
        )
        .iter()
        .filter_map(|c| point(&r, c, &reference, &timing))
        .collect();
        assert_eq!(pts.len(), 5, "2 tolerances + 3 step sizes");
        assert!(
            pts[1].end_error < pts[0].end_error * 1e-2,
            "DOP853: {pts:?}"
        );
        // RK4 halving the step: error ratio 16 (order 4), within 20 %.
        for w in pts[2..].windows(2) {
            let ratio = w[0].path_error / w[1].path_error;
            assert!(
                (12.8..19.2).contains(&ratio),
                "RK4 error ratio per halving: got {ratio}, want ≈ 16"
            );
        }
        assert!(pts.iter().all(|p| p.cpu_s > 0.0 && p.rhs_evals > 0));
        assert_eq!(pts[2].summary().integrator, Integrator::Rk4);
    }

    #[test]
    fn errors_and_digits() {
        assert_eq!(end_error(&[1.0, 2.0], &[1.0, 2.0]), 0.0);
        assert!((end_error(&[1.0, 2.0 + 2e-6], &[1.0, 2.0]) - 1e-6).abs() < 1e-15);
        assert_eq!(end_error(&[f64::NAN], &[1.0]), f64::INFINITY);
        assert_eq!(
            path_error(&[vec![1.0]], &[vec![1.0], vec![2.0]]),
            f64::INFINITY
        );
        assert!((digits(1e-8) - 8.0).abs() < 1e-12);
        assert_eq!(digits(f64::INFINITY), 0.0);
        assert_eq!(sample_times(1.0, 4), vec![0.0, 0.25, 0.5, 0.75, 1.0]);
    }
}
