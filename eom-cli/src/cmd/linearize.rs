//! `eom-gen linearize`: the state-space model `ẏ ≈ A y + B w` about a
//! state (default: the model's initial state), from the generated
//! derivatives of forward dynamics (interpreted: no compiler needed), with
//! its eigenvalues, natural frequencies and damping ratios (see
//! `eom_gen::linearize`).

use crate::args::{InputArgs, ParamArgs, StateArgs, Vary, parse_list};
use crate::error::Error;
use clap::Args;
use eom_gen::functions::Function;
use eom_gen::linearize::{Eigenvalue, InputKind, Linearization, LinearizeError};
use eom_gen::mech::Formulation;
use std::cell::OnceCell;
use std::process::ExitCode;

/// Linearise a model about a state: `A`, `B` of the first-order system
/// `y = (q, u)` (quaternions in the tangent space; holonomic loops about
/// equilibria in minimal coordinates), eigenvalues, natural frequencies and
/// damping ratios.
#[derive(Args)]
pub struct LinearizeArgs {
    /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
    pub model: String,
    #[command(flatten)]
    pub state: StateArgs,
    #[command(flatten)]
    pub params: ParamArgs,
    #[command(flatten)]
    pub inputs: InputArgs,
    /// Print one JSON object instead of the tables.
    #[arg(long)]
    pub json: bool,
    /// Write the eigenvalues to this CSV file (`re,im,natural_frequency,damping_ratio`;
    /// with --sweep `NAME,k,re,im,natural_frequency,damping_ratio`).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<String>,
    /// The eigenvalues against a parameter: `NAME=a:b:n` (n equally spaced
    /// values; the model checked at each, its initial state too; its
    /// equations derived once, the parameter kept as a symbol).
    #[arg(long, value_name = "NAME=a:b:n", allow_hyphen_values = true)]
    pub sweep: Option<String>,
    /// With --sweep: draw the real and imaginary parts against the
    /// parameter into this SVG file.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<String>,
}

/// One linearisation: the model as checked at this point, `A`, `B`, the
/// eigenvalues and the state.
struct At {
    sys: eom_gen::System,
    lin: Linearization,
    eig: Vec<Eigenvalue>,
    q: Vec<f64>,
    u: Vec<f64>,
}

/// A sweep's parameter and the formulation its points share: derived at
/// the first point with the parameter kept as a symbol (tunable), then
/// evaluated at each value, so a sweep costs one derivation, not one per
/// point (the Whipple bicycle's `v=3:7:3` with its two crossings bisected:
/// 64 s → 2.1 s in a debug build). `None` in the cell: that derivation
/// failed, and each point derives its own.
struct Swept<'a> {
    name: &'a str,
    value: f64,
    shared: &'a OnceCell<Option<Formulation>>,
}

/// Why a point was not linearised.
enum Fail {
    /// Already reported (the model, the arguments): this exit status.
    Exit(ExitCode),
    /// Not linearised at this point: why, and whether it is a usage error
    /// (exit 2) rather than a refusal (exit 1).
    Point(String, bool),
}

pub fn run(a: &LinearizeArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let mut problems = Vec::new();
    if !a.state.t.is_finite() {
        problems.push(format!("--t must be a finite number, got {}", a.state.t));
    }
    let sweep = match a.sweep.as_deref().map(parse_sweep).transpose() {
        Ok(s) => s,
        Err(e) => {
            problems.push(e);
            None
        }
    };
    if a.svg.is_some() && a.sweep.is_none() {
        problems.push("--svg draws a --sweep; give --sweep NAME=a:b:n".into());
    }
    let vary = match Vary::parse(&a.params.params, &a.inputs.inputs) {
        Ok(v) => v,
        Err(p) => {
            problems.extend(p);
            Vary::default()
        }
    };
    if let Some((name, _)) = &sweep
        && vary.params.iter().any(|(n, _)| n == name)
    {
        problems.push(format!(
            "--sweep sets parameter `{name}`; do not also give it with --param"
        ));
    }
    if !problems.is_empty() {
        return crate::output::fail(&Error::Usage(problems));
    }
    let Some((name, values)) = sweep else {
        return single(a, urdf, &vary);
    };
    let shared = OnceCell::new();
    let swept = |value| Swept {
        name: &name,
        value,
        shared: &shared,
    };
    let mut points: Vec<(f64, Result<Vec<Eigenvalue>, String>)> = Vec::new();
    for value in values {
        let mut vary = vary.clone();
        vary.params.push((name.clone(), value));
        match at(a, urdf, &vary, Some(swept(value))) {
            Ok(p) => points.push((value, Ok(p.eig))),
            Err(Fail::Exit(code)) => return code,
            Err(Fail::Point(why, _)) => {
                eprintln!("{name} = {value}: {why}");
                points.push((value, Err(why)));
            }
        }
    }
    let relinearize = |value: f64| {
        let mut vary = vary.clone();
        vary.params.push((name.clone(), value));
        at(a, urdf, &vary, Some(swept(value))).ok().map(|p| p.eig)
    };
    let crossings = crate::linearize_sweep::crossings(&points, &relinearize);
    crate::linearize_sweep::report(
        &name,
        &points,
        &crossings,
        a.json,
        a.csv.as_deref(),
        a.svg.as_deref(),
        &a.model,
    )
}

/// `NAME=a:b:n`: `n ≥ 2` equally spaced values from `a` to `b`.
fn parse_sweep(text: &str) -> Result<(String, Vec<f64>), String> {
    let bad = || {
        format!(
            "--sweep `{text}`: expected NAME=a:b:n (finite a, b; n ≥ 2 points), e.g. `--sweep v=0:10:51`"
        )
    };
    let (name, range) = text.split_once('=').ok_or_else(bad)?;
    let parts: Vec<&str> = range.split(':').collect();
    let [a, b, n] = parts.as_slice() else {
        return Err(bad());
    };
    let (a, b): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    let n: usize = n.trim().parse().map_err(|_| bad())?;
    if name.trim().is_empty() || !a.is_finite() || !b.is_finite() || !(2..=100_000).contains(&n) {
        return Err(bad());
    }
    let values = (0..n)
        .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
        .collect();
    Ok((name.trim().to_string(), values))
}

/// One point, printed.
fn single(a: &LinearizeArgs, urdf: &eom_gen::urdf::Options, vary: &Vary) -> ExitCode {
    let p = match at(a, urdf, vary, None) {
        Ok(p) => p,
        Err(Fail::Exit(code)) => return code,
        Err(Fail::Point(why, true)) => return crate::output::fail(&Error::Usage(vec![why])),
        Err(Fail::Point(why, false)) => return crate::output::fail(&Error::Refused(why)),
    };
    let shapes = mode_shapes(&p.lin, &p.eig);
    if let Some(path) = &a.csv
        && let Err(code) = crate::output::write_file(path, &csv(&p.eig))
    {
        return code;
    }
    if a.json {
        println!(
            "{}",
            json(&p.sys, &p.lin, &p.eig, &shapes, &p.q, &p.u, a.state.t)
        );
    } else {
        print!("{}", text(&p.sys, &p.lin, &p.eig, &shapes));
    }
    ExitCode::SUCCESS
}

/// Opens, generates the derivatives and linearises at the state `a` gives
/// (default: the model's initial state with these parameter values); in a
/// sweep, with the formulation the points share.
fn at(
    a: &LinearizeArgs,
    urdf: &eom_gen::urdf::Options,
    vary: &Vary,
    swept: Option<Swept<'_>>,
) -> Result<At, Fail> {
    let opened = crate::open::open(&a.model, urdf, vary).map_err(Fail::Exit)?;
    let mut checked = opened.checked.clone();
    if !checked.system.cables.is_empty() {
        // About the static equilibrium, from the element runtime.
        let given: Vec<&str> = [
            (a.state.q.is_some(), "--q"),
            (a.state.u.is_some(), "--u"),
            (
                !vary.drives.is_empty() || !opened.inputs.is_empty(),
                "--input",
            ),
        ]
        .into_iter()
        .filter_map(|(g, name)| g.then_some(name))
        .collect();
        if !given.is_empty() {
            return Err(Fail::Exit(crate::output::fail(&Error::Usage(vec![
                format!(
                    "{}: a model with cables is linearised about its static equilibrium, which `linearize` finds itself (as `solve-static` does); leave out {}",
                    given.join(", "),
                    given.join(", ")
                ),
            ]))));
        }
        let (lin, q, u) =
            crate::ancf::linearize_cmd(&checked).map_err(|e| Fail::Point(e.to_string(), false))?;
        let eig = eom_gen::linearize::eigenvalues(&lin.a).ok_or_else(|| {
            Fail::Point(
                "the eigenvalue iteration (real Schur form of A) did not converge".into(),
                false,
            )
        })?;
        return Ok(At {
            sys: checked.system.clone(),
            lin,
            eig,
            q,
            u,
        });
    }
    // Checked by `open` (exit 2); driven inputs leave the model.
    if let Err(errors) = eom_gen::model::drive_inputs(&mut checked, &vary.drives) {
        return Err(Fail::Exit(crate::output::fail(&Error::Usage(
            errors
                .iter()
                .map(|e| format!("--input {}: {e}", e.input))
                .collect(),
        ))));
    }
    let sys = checked.system.clone();
    let mut problems = Vec::new();
    let mut list = |what: &str, text: Option<&str>, n: usize, default: Vec<f64>| {
        parse_list(what, text, n, default).unwrap_or_else(|e| {
            problems.push(e);
            Vec::new()
        })
    };
    let q = list("q", a.state.q.as_deref(), sys.nq(), sys.q0());
    let u = list("u", a.state.u.as_deref(), sys.nu(), sys.u0());
    if !problems.is_empty() {
        return Err(Fail::Exit(crate::output::fail(&Error::Usage(problems))));
    }
    // The default state of a constrained model is the assembled initial
    // state (where `simulate` starts); a state given is used as given.
    let (q, u) = if (a.state.q.is_none() || a.state.u.is_none())
        && (!sys.graph.cut_joints().is_empty() || !sys.constraints.is_empty())
    {
        match eom_gen::mech::Numeric::new(&sys).and_then(|n| n.assemble(&q, &u, a.state.t)) {
            Ok(asm) => (
                if a.state.q.is_none() { asm.q } else { q },
                if a.state.u.is_none() { asm.u } else { u },
            ),
            Err(_) => (q, u),
        }
    } else {
        (q, u)
    };
    let request = checked.request().with(Function::ForwardDynamicsDerivatives);
    let formulate = |sys: &eom_gen::System| {
        eom_gen::mech::formulate(sys, request).map_err(|e| {
            let report = eom_gen::Report {
                source: checked.source.clone(),
                diagnostics: vec![e.diagnostic()],
            };
            eprint!("{report}");
            Fail::Exit(ExitCode::from(1))
        })
    };
    // A sweep's points share one derivation with the parameter as a
    // symbol; where that derivation fails, each point derives its own.
    let shared = swept.as_ref().and_then(|s| {
        s.shared
            .get_or_init(|| {
                let mut symbolic = sys.clone();
                for p in &mut symbolic.parameters {
                    p.tunable |= p.name == s.name;
                }
                eom_gen::mech::formulate(&symbolic, request).ok()
            })
            .as_ref()
            .map(|f| (f, vec![(s.name.to_string(), s.value)]))
    });
    let own;
    let (f, params) = match shared {
        Some(shared) => shared,
        None => {
            own = formulate(&sys)?;
            (&own, Vec::new())
        }
    };
    let point = eom_gen::interpret::Point {
        sys: &sys,
        q: &q,
        u: &u,
        udot: &[],
        tau: &[],
        inputs: &opened.inputs,
        params: &params,
        multipliers: &[],
        t: a.state.t,
    };
    let lin = eom_gen::linearize::linearize(f, &point).map_err(|e| {
        let usage = !matches!(e, LinearizeError::NotFinite);
        Fail::Point(e.to_string(), usage)
    })?;
    let eig = eom_gen::linearize::eigenvalues(&lin.a).ok_or_else(|| {
        Fail::Point(
            "the eigenvalue iteration (real Schur form of A) did not converge".into(),
            false,
        )
    })?;
    Ok(At {
        sys,
        lin,
        eig,
        q,
        u,
    })
}

/// Mode shapes: per eigenvalue the displacements over the model's
/// coordinates (the tangent displacements for quaternion models, `Z z`
/// for loops), largest entry 1; with the names they are over.
struct Shapes {
    over: Vec<String>,
    shapes: Vec<Option<Vec<nalgebra::Complex<f64>>>>,
}

/// Mode shapes are computed for the lowest this many eigenvalues (by
/// natural frequency); the rest are `null` in JSON and `—` in text.
const MODE_SHAPES: usize = 24;

fn mode_shapes(lin: &Linearization, eig: &[Eigenvalue]) -> Shapes {
    let dof = lin.positions;
    let over = match &lin.basis {
        Some(_) => lin.basis_rows.clone(),
        None => lin.states[..dof].to_vec(),
    };
    // The lowest modes only: a structure of cables has hundreds.
    let shapes = eig
        .iter()
        .enumerate()
        .map(|(k, l)| {
            (k < MODE_SHAPES)
                .then(|| eom_gen::linearize::mode_shape(&lin.a, l, dof, lin.basis.as_ref()))
                .flatten()
        })
        .collect();
    Shapes { over, shapes }
}

fn rows(m: &nalgebra::DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
        .collect()
}

/// `null` for a NaN (JSON has none).
fn number(x: f64) -> serde_json::Value {
    if x.is_finite() {
        serde_json::json!(x)
    } else {
        serde_json::Value::Null
    }
}

fn json(
    sys: &eom_gen::System,
    lin: &Linearization,
    eig: &[Eigenvalue],
    shapes: &Shapes,
    q: &[f64],
    u: &[f64],
    t: f64,
) -> serde_json::Value {
    let dof = lin.positions;
    let mut v = serde_json::json!({
        "model": sys.name,
        "q": q,
        "u": u,
        "t": t,
        "states": lin.states,
        "coordinates": lin.states[..dof],
        "speeds": lin.states[dof..],
        "inputs": lin.inputs,
        "input_kind": match lin.input_kind {
            InputKind::Inputs => "inputs",
            InputKind::GeneralizedForces => "generalized_forces",
        },
        "A": rows(&lin.a),
        "B": rows(&lin.b),
        "outputs": lin.outputs,
        "C": rows(&lin.c),
        "D": rows(&lin.d),
        "eigenvalues": eig.iter().map(|e| [e.re, e.im]).collect::<Vec<_>>(),
        "natural_frequencies": eig.iter().map(|e| number(e.natural_frequency)).collect::<Vec<_>>(),
        "damping_ratios": eig.iter().map(|e| number(e.damping_ratio)).collect::<Vec<_>>(),
    });
    v["mode_coordinates"] = serde_json::json!(shapes.over);
    v["mode_shapes"] = serde_json::json!(
        shapes
            .shapes
            .iter()
            .map(|s| s
                .as_ref()
                .map(|s| s.iter().map(|c| [c.re, c.im]).collect::<Vec<_>>()))
            .collect::<Vec<_>>()
    );
    if let Some(z) = &lin.basis {
        v["basis"] = serde_json::json!(rows(z));
        v["basis_rows"] = serde_json::json!(lin.basis_rows);
    }
    v["cyclic"] = serde_json::json!(lin.cyclic);
    v
}

fn csv(eig: &[Eigenvalue]) -> String {
    let mut s = String::from("re,im,natural_frequency,damping_ratio\n");
    for e in eig {
        s += &format!(
            "{},{},{},{}\n",
            e.re, e.im, e.natural_frequency, e.damping_ratio
        );
    }
    s
}

/// A labelled matrix, one row per line.
fn matrix(title: &str, m: &nalgebra::DMatrix<f64>, rows: &[String], cols: &[String]) -> String {
    use std::fmt::Write;
    let width = rows.iter().map(|r| r.len()).max().unwrap_or(0).max(4);
    let mut s = format!("{title}\n  {:width$}", "");
    for c in cols {
        let _ = write!(s, " {c:>12}");
    }
    s.push('\n');
    for (i, r) in rows.iter().enumerate() {
        let _ = write!(s, "  {r:width$}");
        for j in 0..m.ncols() {
            let _ = write!(s, " {:>12.6}", m[(i, j)]);
        }
        s.push('\n');
    }
    s
}

fn text(sys: &eom_gen::System, lin: &Linearization, eig: &[Eigenvalue], shapes: &Shapes) -> String {
    use std::fmt::Write;
    let mut s = format!(
        "{}: ẏ = A y + B w, y = ({}), w = ({})\n",
        sys.name,
        lin.states.join(", "),
        lin.inputs.join(", ")
    );
    if !lin.cyclic.is_empty() {
        let _ = writeln!(
            s,
            "cyclic coordinates (left out, one zero eigenvalue each): {}",
            lin.cyclic.join(", ")
        );
    }
    if let Some(z) = &lin.basis {
        let columns: Vec<String> = lin.states[..z.ncols()].to_vec();
        s += &matrix(
            "minimal coordinates: δq = Z z, Z",
            z,
            &lin.basis_rows,
            &columns,
        );
    }
    s += &matrix("A", &lin.a, &lin.states, &lin.states);
    s += &matrix("B", &lin.b, &lin.states, &lin.inputs);
    if !lin.outputs.is_empty() {
        s += &matrix(
            "C (outputs: δh = C y + D w)",
            &lin.c,
            &lin.outputs,
            &lin.states,
        );
        s += &matrix("D", &lin.d, &lin.outputs, &lin.inputs);
    }
    let _ = writeln!(
        s,
        "eigenvalues\n  {:>14} {:>14} {:>14} {:>12} {:>10}",
        "re (1/s)", "im (rad/s)", "ω_n (rad/s)", "f_n (Hz)", "ζ"
    );
    for e in eig {
        let _ = writeln!(
            s,
            "  {:>14.6} {:>14.6} {:>14.6} {:>12.6} {:>10.4}",
            e.re,
            e.im,
            e.natural_frequency,
            e.natural_frequency / std::f64::consts::TAU,
            e.damping_ratio
        );
    }
    // One line per eigenvalue with Im λ ≥ 0 (the conjugate's shape is
    // the conjugate).
    let _ = writeln!(
        s,
        "mode shapes (displacements of {}; largest 1)",
        shapes.over.join(", ")
    );
    for (e, shape) in eig.iter().zip(&shapes.shapes) {
        if e.im < 0.0 {
            continue;
        }
        let entries = match shape {
            Some(v) => v
                .iter()
                .map(|c| {
                    // Scaled to a largest entry of 1: parts below 1e-9
                    // are rounding.
                    if c.im.abs() <= 1e-9 {
                        format!("{:.4}", if c.re.abs() <= 1e-9 { 0.0 } else { c.re })
                    } else {
                        format!("{:.4}{:+.4}i", c.re, c.im)
                    }
                })
                .collect::<Vec<_>>()
                .join(", "),
            None => "—".into(),
        };
        let _ = writeln!(s, "  λ = {:.6}{:+.6}i: {entries}", e.re, e.im);
    }
    s
}
