//! `eom-gen bench MODEL --work-precision` and `eom-gen bench --suite`:
//! error against CPU time of the compiled model, per integrator and
//! constraint solver, over a sweep of tolerances (adaptive methods) or step
//! sizes (fixed-step methods).
//!
//! A runner program is written around the model's generated source and
//! built in release mode in the cache shared with `eom-gen eval` (see
//! [`crate::compiled`]); the sweep itself is
//! [`eom_sim::work_precision`]: a reference by DOP853 at a much tighter
//! tolerance checked by DOPRI5, then per point one run with dense output for
//! the errors (at the end time and the largest along the path) and repeated
//! runs without output for the CPU time (median). The runner prints one
//! JSON line per point as it goes, which drives the progress bar; the
//! results are written as a table, JSON, CSV and a log-log SVG plot.

use crate::compiled::{CachedCrate, build_cached, model_module};
use crate::error::Error;
use eom_gen::generate::Generated;
use eom_sim::work_precision::{PointSummary, ReferenceSummary};
use eom_sim::{Integrator, Method};
use serde::Deserialize;
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

/// What to sweep.
#[derive(Clone, Debug)]
pub struct WpOptions {
    /// Integrators.
    pub integrators: Vec<Integrator>,
    /// Constraint methods; only used for models with constraints.
    pub constraints: Vec<Method>,
    /// End time, s.
    pub t_end: f64,
    /// Tolerances `rtol = atol` of the adaptive methods.
    pub tols: Vec<f64>,
    /// Fixed-step methods: `t_end / n` for `n` doubling from the first to
    /// the second number.
    pub fixed_steps: (usize, usize),
    /// Tolerance of the reference (DOP853) and of its check (DOPRI5).
    pub ref_tol: f64,
    /// Dense-output samples along the path (for the path error).
    pub samples: usize,
    /// At least this many timed runs per point.
    pub min_repeats: usize,
    /// Repeat (up to 51 runs) until this much CPU time per point, s.
    pub min_total_s: f64,
}

impl Default for WpOptions {
    fn default() -> Self {
        WpOptions {
            integrators: vec![
                Integrator::Rk4,
                Integrator::Dopri5,
                Integrator::Dop853,
                Integrator::Radau5,
            ],
            constraints: vec![
                Method::Projection,
                Method::Partitioning,
                Method::BAUMGARTE,
                Method::Index3,
            ],
            t_end: 10.0,
            tols: (4..=12).map(|k| 10f64.powi(-k)).collect(),
            fixed_steps: (250, 32_000),
            ref_tol: 1e-13,
            samples: 200,
            min_repeats: 3,
            min_total_s: 0.2,
        }
    }
}

/// A whole sweep of one model.
#[derive(Clone, Debug)]
pub struct WorkPrecision {
    /// The model's name.
    pub model: String,
    /// True if the model has constraints.
    pub constrained: bool,
    /// End time, s.
    pub t_end: f64,
    /// The reference (none for points read back from a CSV file).
    pub reference: Option<ReferenceSummary>,
    /// The points, in sweep order.
    pub points: Vec<PointSummary>,
    /// What the errors measure (the plots' axis label).
    pub error_label: String,
}

/// The error of [`run`]'s points.
pub const RELATIVE_ERROR: &str = "relative error of the positions";

const MAIN: &str = r#"//! Work-precision sweep of the generated model (eom-gen bench
//! --work-precision): one JSON request `{t_end, ref_tol, samples, timing,
//! cases}` on the command line; prints the reference, then one JSON line
//! per point as it is measured.
mod model;
use eom_sim::work_precision::{self as wp, Case, ModelRunner, Timing};
use std::io::Write;

#[derive(serde::Deserialize)]
struct Request {
    t_end: f64,
    ref_tol: f64,
    samples: usize,
    min_repeats: usize,
    min_total_s: f64,
    cases: Vec<(eom_sim::Integrator, eom_sim::Method, f64)>,
}

fn main() {
    let arg = std::env::args().nth(1).unwrap_or_default();
    let r: Request = match serde_json::from_str(&arg) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("bad request: {e}");
            std::process::exit(2);
        }
    };
    let timing = Timing { min_repeats: r.min_repeats.max(1), max_repeats: 51, min_total_s: r.min_total_s };
    let m = model::MODEL::default();
    let runner = ModelRunner::<model::MODEL, { model::NY }, { model::NYC }>::new(&m);
    let out = std::io::stdout();
    let Some(reference) = wp::reference(&runner, r.t_end, r.ref_tol, r.samples.max(1)) else {
        eprintln!("the reference run (dop853 at rtol = atol = {:e}) or its check (dopri5) did not reach t = {}", r.ref_tol, r.t_end);
        std::process::exit(1);
    };
    let line = serde_json::json!({ "reference": reference.summary() });
    let _ = writeln!(out.lock(), "{line}");
    for (integrator, method, setting) in r.cases {
        let case = Case { integrator, method, setting };
        let line = match wp::point(&runner, &case, &reference, &timing) {
            Some(p) => serde_json::json!({ "point": p.summary() }),
            None => serde_json::json!({ "skipped": [integrator, method] }),
        };
        let _ = writeln!(out.lock(), "{line}");
    }
}
"#;

/// The cases of a sweep.
fn cases(o: &WpOptions, constrained: bool) -> Vec<(Integrator, Method, f64)> {
    let methods = if constrained {
        o.constraints.clone()
    } else {
        vec![Method::Projection]
    };
    eom_sim::work_precision::cases(&o.integrators, &methods, &o.tols, o.t_end, o.fixed_steps)
        .into_iter()
        .map(|c| (c.integrator, c.method, c.setting))
        .collect()
}

/// Checks the options: known integrators and solvers, positive times and
/// tolerances. Every problem at once.
pub fn validate(o: &WpOptions) -> Result<(), Vec<String>> {
    let mut errors = Vec::new();
    if !(o.t_end.is_finite() && o.t_end > 0.0) {
        errors.push("--t-end must be a positive number of seconds".into());
    }
    if o.tols.iter().any(|t| !(t.is_finite() && *t > 0.0)) {
        errors.push("--tols must be positive numbers".into());
    }
    if !(o.ref_tol.is_finite() && o.ref_tol > 0.0) {
        errors.push("--ref-tol must be a positive number".into());
    }
    if o.integrators.is_empty() {
        errors.push("--integrators is empty".into());
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors)
    }
}

/// Builds (once, cached) the runner of a generated model and sweeps;
/// `progress(done, total, point)` is called after every point.
pub fn run(
    g: &Generated,
    o: &WpOptions,
    progress: &mut dyn FnMut(usize, usize, Option<&PointSummary>),
) -> Result<WorkPrecision, Error> {
    let sys = &g.checked.system;
    let constrained = !sys.graph.cut_joints().is_empty() || !sys.constraints.is_empty();
    let model = model_module(&sys.name, &g.source, sys.nq(), sys.nu());
    let exe = build_cached(&CachedCrate {
        prefix: "eom-wp",
        name: &sys.name,
        main: MAIN,
        model: &model,
        rustflags: None,
    })?;
    let cases = cases(o, constrained);
    let total = cases.len();
    let request = serde_json::json!({
        "t_end": o.t_end, "ref_tol": o.ref_tol, "samples": o.samples,
        "min_repeats": o.min_repeats, "min_total_s": o.min_total_s, "cases": cases,
    });
    let mut child = Command::new(&exe)
        .arg(request.to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| Error::Program(format!("cannot run {}: {e}", exe.display())))?;
    let stdout = child
        .stdout
        .take()
        .ok_or_else(|| Error::Program(format!("no output from {}", exe.display())))?;
    let mut reference = None;
    let mut points = Vec::new();
    let mut done = 0;
    progress(0, total, None);
    for line in BufReader::new(stdout).lines() {
        let line = line.map_err(|e| Error::Program(format!("reading {}: {e}", exe.display())))?;
        let v: serde_json::Value = serde_json::from_str(&line).map_err(|e| {
            Error::Program(format!(
                "unexpected output of {}: {e}: {line}",
                exe.display()
            ))
        })?;
        if let Some(r) = v.get("reference") {
            reference = Some(ReferenceSummary::deserialize(r).map_err(|e| {
                Error::Program(format!("unexpected reference from {}: {e}", exe.display()))
            })?);
        } else if let Some(p) = v.get("point") {
            let p = PointSummary::deserialize(p).map_err(|e| {
                Error::Program(format!("unexpected point from {}: {e}", exe.display()))
            })?;
            done += 1;
            progress(done, total, Some(&p));
            points.push(p);
        } else {
            done += 1;
            progress(done, total, None);
        }
    }
    let out = child
        .wait_with_output()
        .map_err(|e| Error::Program(format!("waiting for {}: {e}", exe.display())))?;
    if !out.status.success() {
        return Err(Error::Program(format!(
            "the work-precision runner failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    let reference = Some(
        reference
            .ok_or_else(|| Error::Program(format!("{} printed no reference", exe.display())))?,
    );
    Ok(WorkPrecision {
        model: sys.name.clone(),
        constrained,
        t_end: o.t_end,
        reference,
        points,
        error_label: RELATIVE_ERROR.into(),
    })
}

/// Work-precision points read back from CSV files in the format [`csv`]
/// writes (so results of several runs, or of other tools, can be plotted
/// together), one [`WorkPrecision`] per `model` in order of appearance.
/// Needed columns: `model`, `integrator`, `setting_kind` (`tol` or
/// `step`), `setting`, `cpu_ms`, `end_error`; optional: `constraints`,
/// `path_error`, `rhs_evals`, `accepted`, `rejected`, `repeats`, `stop`.
/// Empty errors mean the run did not finish. The reference is unknown
/// (its fields are NaN).
pub fn from_csv(text: &str, file: &str) -> Result<Vec<WorkPrecision>, Error> {
    read_csv(text, file).map_err(Error::Format)
}

fn read_csv(text: &str, file: &str) -> Result<Vec<WorkPrecision>, String> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(format!("{file}: empty"));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let col = |n: &str| names.iter().position(|c| *c == n);
    let need = [
        "model",
        "integrator",
        "setting_kind",
        "setting",
        "cpu_ms",
        "end_error",
    ];
    let missing: Vec<&str> = need.iter().copied().filter(|n| col(n).is_none()).collect();
    if !missing.is_empty() {
        return Err(format!(
            "{file}:1: missing column(s) {}; the header needs {}",
            missing.join(", "),
            need.join(", ")
        ));
    }
    let mut out: Vec<WorkPrecision> = Vec::new();
    for (k, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let get = |n: &str| col(n).and_then(|i| cells.get(i)).copied().unwrap_or("");
        let num = |n: &str| -> Result<Option<f64>, String> {
            let c = get(n);
            if c.is_empty() {
                return Ok(None);
            }
            c.parse::<f64>()
                .map(Some)
                .map_err(|_| format!("{file}:{}: `{n}` is `{c}`, not a number", k + 1))
        };
        let count = |n: &str| get(n).parse::<usize>().unwrap_or(0);
        let setting = num("setting")?.ok_or_else(|| format!("{file}:{}: no `setting`", k + 1))?;
        let cpu_ms = num("cpu_ms")?.ok_or_else(|| format!("{file}:{}: no `cpu_ms`", k + 1))?;
        let end_error = num("end_error")?;
        let line_no = k + 1;
        let integrator = get("integrator")
            .parse()
            .map_err(|e| format!("{file}:{line_no}: {e}"))?;
        let constraints = match get("constraints") {
            "" => None,
            c => Some(c.parse().map_err(|e| format!("{file}:{line_no}: {e}"))?),
        };
        let point = PointSummary {
            integrator,
            constraints: constraints.unwrap_or_default(),
            fixed_step: get("setting_kind") == "step",
            setting,
            cpu_s: cpu_ms * 1e-3,
            repeats: count("repeats"),
            rhs_evals: count("rhs_evals"),
            accepted: count("accepted"),
            rejected: count("rejected"),
            end_error,
            path_error: num("path_error")?,
            digits: end_error.map(eom_sim::work_precision::digits),
            stop: match get("stop") {
                "" => "finished".to_string(),
                s => s.to_string(),
            },
        };
        let model = get("model");
        let w = match out.iter_mut().find(|w| w.model == model) {
            Some(w) => w,
            None => {
                out.push(WorkPrecision {
                    model: model.to_string(),
                    constrained: false,
                    t_end: f64::NAN,
                    reference: None,
                    points: Vec::new(),
                    error_label: RELATIVE_ERROR.into(),
                });
                let n = out.len() - 1;
                &mut out[n]
            }
        };
        w.constrained |= constraints.is_some();
        w.points.push(point);
    }
    if out.is_empty() {
        return Err(format!("{file}: no points"));
    }
    Ok(out)
}

fn fmt_opt(x: Option<f64>, f: impl Fn(f64) -> String) -> String {
    x.map_or_else(|| "-".into(), f)
}

/// CSV, one row per point:
/// `model,integrator,constraints,setting_kind,setting,cpu_ms,repeats,rhs_evals,accepted,rejected,end_error,path_error,digits,stop`.
pub fn csv(w: &WorkPrecision) -> String {
    let mut s = String::from(
        "model,integrator,constraints,setting_kind,setting,cpu_ms,repeats,rhs_evals,accepted,rejected,end_error,path_error,digits,stop\n",
    );
    for p in &w.points {
        let e = |x: Option<f64>| x.map_or_else(String::new, |x| format!("{x:e}"));
        s += &format!(
            "{},{},{},{},{:e},{:.6},{},{},{},{},{},{},{},{}\n",
            w.model,
            p.integrator,
            if w.constrained {
                p.constraints.name()
            } else {
                ""
            },
            if p.fixed_step { "step" } else { "tol" },
            p.setting,
            p.cpu_s * 1e3,
            p.repeats,
            p.rhs_evals,
            p.accepted,
            p.rejected,
            e(p.end_error),
            e(p.path_error),
            p.digits.map_or_else(String::new, |d| format!("{d:.2}")),
            p.stop.replace(',', ";"),
        );
    }
    s
}

/// A Markdown table of the points with the reference's line above it.
pub fn table(w: &WorkPrecision) -> String {
    let mut s = match &w.reference {
        Some(r) => format!(
            "{}: work-precision to t = {} s; reference {} at rtol = atol = {:e} ({} rhs{}), checked by {}: end {:.1e}, path {:.1e}\n\n",
            w.model,
            w.t_end,
            r.integrator,
            r.tol,
            r.rhs_evals,
            if w.constrained {
                format!(", {}", r.constraints)
            } else {
                String::new()
            },
            r.check,
            r.check_end_error,
            r.check_path_error
        ),
        None => format!("{}: work-precision\n\n", w.model),
    };
    s += "| method | tol / step | rhs | CPU ms | end error | path error | digits | stop |\n";
    s += "|---|---|---:|---:|---:|---:|---:|---|\n";
    for p in &w.points {
        s += &format!(
            "| {} | {} | {} | {:.3} | {} | {} | {} | {} |\n",
            p.series(w.constrained),
            if p.fixed_step {
                format!("h = {:.2e}", p.setting)
            } else {
                format!("{:.0e}", p.setting)
            },
            p.rhs_evals,
            p.cpu_s * 1e3,
            fmt_opt(p.end_error, |x| format!("{x:.1e}")),
            fmt_opt(p.path_error, |x| format!("{x:.1e}")),
            fmt_opt(p.digits, |x| format!("{x:.1}")),
            p.stop
        );
    }
    s
}

/// The whole sweep as one JSON object:
/// `{"model", "constrained", "t_end", "reference": {…}, "points": [{…}]}`.
pub fn json(w: &WorkPrecision) -> serde_json::Value {
    // The constraint method means something for constrained models only.
    let strip = |mut v: serde_json::Value| {
        if !w.constrained
            && let Some(o) = v.as_object_mut()
        {
            o.insert("constraints".into(), serde_json::Value::Null);
        }
        v
    };
    fn value<T: serde::Serialize>(x: &T) -> serde_json::Value {
        serde_json::to_value(x).unwrap_or_default()
    }
    serde_json::json!({
        "model": w.model,
        "constrained": w.constrained,
        "t_end": w.t_end,
        "reference": w.reference.as_ref().map(|r| strip(value(r))),
        "points": w.points.iter().map(|p| strip(value(p))).collect::<Vec<_>>(),
    })
}

pub use crate::plot::svg;

/// The suite's settings for a bundled model (end time, integrators,
/// constraint solvers), the rest from `base`; models not in the table get
/// `base` as it is.
///
/// | model | t_end | integrators | constraint solvers |
/// |---|---|---|---|
/// | pendulum, double_pendulum, arm7, heavy_top | 10 s | rk4, dopri5, dop853, radau5 | — |
/// | free_body | 25 s (one Dzhanibekov flip) | rk4, dopri5, dop853, radau5 | — |
/// | fourbar | 0.5 s (before the first singular position) | dopri5, dop853, radau5 | all four |
/// | slider_crank, slider_crank_driven | 2 s | dopri5, dop853, radau5 | all four |
/// | andrews | 0.03 s (the IVP test set's end) | dop853, radau5 | all four |
/// | bricard | 2 s | dop853 | projection, partitioning, baumgarte (redundant: no index-3) |
/// | stewart, stewart_driven | 1 s | dop853 | projection, partitioning, baumgarte |
/// | rolling_disk | 5 s | dopri5, dop853 | projection, partitioning, baumgarte |
pub fn suite_options(model: &str, base: &WpOptions) -> WpOptions {
    use Integrator::{Dop853, Dopri5, Radau5, Rk4};
    use Method::{Index3, Partitioning, Projection};
    const BAUMGARTE: Method = Method::BAUMGARTE;
    let (t_end, integrators, constraints): (f64, &[Integrator], &[Method]) = match model {
        "pendulum" | "double_pendulum" | "arm7" | "heavy_top" => {
            (10.0, &[Rk4, Dopri5, Dop853, Radau5], &[])
        }
        "free_body" => (25.0, &[Rk4, Dopri5, Dop853, Radau5], &[]),
        "fourbar" => (
            0.5,
            &[Dopri5, Dop853, Radau5],
            &[Projection, Partitioning, BAUMGARTE, Index3],
        ),
        "slider_crank" | "slider_crank_driven" => (
            2.0,
            &[Dopri5, Dop853, Radau5],
            &[Projection, Partitioning, BAUMGARTE, Index3],
        ),
        "andrews" => (
            0.03,
            &[Dop853, Radau5],
            &[Projection, Partitioning, BAUMGARTE, Index3],
        ),
        "bricard" => (2.0, &[Dop853], &[Projection, Partitioning, BAUMGARTE]),
        "stewart" | "stewart_driven" => (1.0, &[Dop853], &[Projection, Partitioning, BAUMGARTE]),
        "rolling_disk" => (
            5.0,
            &[Dopri5, Dop853],
            &[Projection, Partitioning, BAUMGARTE],
        ),
        _ => return base.clone(),
    };
    WpOptions {
        t_end,
        integrators: integrators.to_vec(),
        constraints: if constraints.is_empty() {
            base.constraints.clone()
        } else {
            constraints.to_vec()
        },
        ..base.clone()
    }
}

/// Per series, the cheapest finished run (least CPU time) whose end error
/// is at most `threshold`, in series order; `None` where no run reached it.
pub fn cheapest(w: &WorkPrecision, threshold: f64) -> Vec<(String, Option<&PointSummary>)> {
    let mut out: Vec<(String, Option<&PointSummary>)> = Vec::new();
    for p in &w.points {
        let name = p.series(w.constrained);
        let ok = p.end_error.is_some_and(|e| e <= threshold);
        let slot = match out.iter_mut().find(|(n, _)| *n == name) {
            Some(s) => s,
            None => {
                out.push((name, None));
                let k = out.len() - 1;
                &mut out[k]
            }
        };
        if ok && slot.1.is_none_or(|b| p.cpu_s < b.cpu_s) {
            slot.1 = Some(p);
        }
    }
    out
}

/// One Markdown row per model for the suite summary: for each series the
/// CPU time (ms) of the cheapest run reaching an end error of 1e-6 and of
/// 1e-9, and the most digits reached.
pub fn summary_rows(w: &WorkPrecision) -> String {
    let at = |t: f64| cheapest(w, t);
    let (six, nine) = (at(1e-6), at(1e-9));
    let mut s = String::new();
    for ((name, a), (_, b)) in six.iter().zip(&nine) {
        let best = w
            .points
            .iter()
            .filter(|p| p.series(w.constrained) == *name)
            .filter_map(|p| p.digits)
            .fold(0.0, f64::max);
        let cell = |p: &Option<&PointSummary>| {
            p.map_or_else(
                || "—".to_string(),
                |p| format!("{:.3} ({} rhs)", p.cpu_s * 1e3, p.rhs_evals),
            )
        };
        s += &format!(
            "| {} | {} s | {name} | {} | {} | {best:.1} |\n",
            w.model,
            w.t_end,
            cell(a),
            cell(b)
        );
    }
    s
}
