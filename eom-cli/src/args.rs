//! The arguments several commands share, declared once (`#[command(flatten)]`):
//! the URDF import options, `--param`/`--input`, `--q0`/`--u0`; and the
//! parsing of their values into a [`Vary`].

use clap::Args;
use std::process::ExitCode;

/// How URDF files are imported (global: before or after the command).
#[derive(Args, Clone, Copy, Debug, Default)]
pub struct UrdfArgs {
    /// URDF import: inconsistent inertias of moving links are errors, not
    /// warnings (see docs/model-format.md, "Inertia policy").
    #[arg(long, global = true)]
    pub strict_inertia: bool,
    /// URDF import: fix inconsistent inertias of moving links (negative
    /// principal moments to zero, then the triangle inequality), each fix
    /// listed in the notes (like MuJoCo's `balanceinertia`).
    #[arg(long, global = true)]
    pub balance_inertia: bool,
    /// URDF import: leave the `<limit lower upper>` of revolute and
    /// prismatic joints off (listed in the notes); by default they become
    /// joint-limit contacts (plastic stops, `e = 0`).
    #[arg(long, global = true, conflicts_with = "urdf_limits")]
    pub no_urdf_limits: bool,
    /// URDF import: import the joint limits (the default; kept so that
    /// scripts written when it was needed still run).
    #[arg(long, global = true)]
    pub urdf_limits: bool,
}

impl UrdfArgs {
    /// The importer's options.
    pub fn options(&self) -> eom_gen::urdf::Options {
        eom_gen::urdf::Options {
            balance_inertia: self.balance_inertia,
            strict: self.strict_inertia,
            joint_limits: !self.no_urdf_limits,
        }
    }
}

/// `--param NAME=VALUE`.
#[derive(Args, Clone, Debug, Default)]
pub struct ParamArgs {
    /// Set a parameter of the model: `NAME=VALUE` (repeatable); the
    /// code is regenerated with the value.
    #[arg(long = "param", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    pub params: Vec<String>,
}

/// `--input NAME=VALUE|EXPR`.
#[derive(Args, Clone, Debug, Default)]
pub struct InputArgs {
    /// Hold a runtime input of the model at a value, `NAME=VALUE`, or
    /// drive it by an expression of parameters, `t`, coordinates and
    /// speeds, `NAME=EXPR` (regenerates; repeatable; default zero).
    #[arg(
        long = "input",
        value_name = "NAME=VALUE|EXPR",
        allow_hyphen_values = true
    )]
    pub inputs: Vec<String>,
}

/// `--q0`, `--u0`: the initial state.
#[derive(Args, Clone, Debug, Default)]
pub struct InitialArgs {
    /// Initial positions, comma-separated (default: the model's q0).
    #[arg(long, allow_hyphen_values = true)]
    pub q0: Option<String>,
    /// Initial speeds, comma-separated (default: the model's u0).
    #[arg(long, allow_hyphen_values = true)]
    pub u0: Option<String>,
}

/// `--q`, `--u`, `--t`: the state a function is evaluated or linearised at.
#[derive(Args, Clone, Debug, Default)]
pub struct StateArgs {
    /// Positions, comma-separated (default: the model's q0).
    #[arg(long, allow_hyphen_values = true)]
    pub q: Option<String>,
    /// Speeds, comma-separated (default: the model's u0).
    #[arg(long, allow_hyphen_values = true)]
    pub u: Option<String>,
    /// Time.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub t: f64,
}

/// What `--param`, `--input` (and `bench`'s `--q0`/`--u0`) set.
#[derive(Clone, Debug, Default)]
pub struct Vary {
    /// Parameter values, by name.
    pub params: Vec<(String, f64)>,
    /// Input values, by name.
    pub inputs: Vec<(String, f64)>,
    /// Inputs driven by expressions (`--input NAME=EXPR`), by name.
    pub drives: Vec<(String, String)>,
    /// The model's initial positions replaced (`bench --q0`; regenerates).
    pub q0: Option<Vec<f64>>,
    /// The model's initial speeds replaced (`bench --u0`; regenerates).
    pub u0: Option<Vec<f64>>,
}

impl Vary {
    /// Both lists of `NAME=VALUE`; an input's value may be an expression
    /// (`NAME=EXPR`, which drives it); every malformed one is a problem.
    pub fn parse(params: &[String], inputs: &[String]) -> Result<Vary, Vec<String>> {
        let p = parse_assignments("param", params);
        let (constant, driven): (Vec<String>, Vec<String>) =
            inputs.iter().cloned().partition(|i| {
                i.split_once('=')
                    .is_none_or(|(_, v)| v.trim().parse::<f64>().is_ok())
            });
        let i = parse_assignments("input", &constant);
        let drives: Vec<(String, String)> = driven
            .iter()
            .filter_map(|i| i.split_once('='))
            .map(|(n, v)| (n.trim().to_string(), v.trim().to_string()))
            .collect();
        let mut empty: Vec<String> = drives
            .iter()
            .filter(|(n, v)| n.is_empty() || v.is_empty())
            .map(|(n, v)| format!("--input `{n}={v}`: expected NAME=VALUE or NAME=EXPR, e.g. `--input motor=\"2*sin(3*t)\"`"))
            .collect();
        match (p, i) {
            (Ok(params), Ok(inputs)) if empty.is_empty() => Ok(Vary {
                params,
                inputs,
                drives,
                ..Vary::default()
            }),
            (p, i) => Err(p
                .err()
                .into_iter()
                .chain(i.err())
                .flatten()
                .chain(empty.drain(..))
                .collect()),
        }
    }

    /// [`Vary::parse`] with the problems printed (exit 2).
    pub fn parse_or_exit(params: &[String], inputs: &[String]) -> Result<Vary, ExitCode> {
        Vary::parse(params, inputs).map_err(|problems| {
            for e in problems {
                eprintln!("error: {e}");
            }
            ExitCode::from(2)
        })
    }

    /// True if nothing is varied by name.
    pub fn names_nothing(&self) -> bool {
        self.params.is_empty() && self.inputs.is_empty() && self.drives.is_empty()
    }
}

/// `NAME=VALUE` pairs of `--what`; every malformed one is a problem.
pub fn parse_assignments(what: &str, items: &[String]) -> Result<Vec<(String, f64)>, Vec<String>> {
    let mut out = Vec::new();
    let mut problems = Vec::new();
    for item in items {
        let parsed = item.split_once('=').and_then(|(n, v)| {
            let v: f64 = v.trim().parse().ok()?;
            (!n.trim().is_empty() && v.is_finite()).then(|| (n.trim().to_string(), v))
        });
        match parsed {
            Some(p) => out.push(p),
            None => problems.push(format!(
                "--{what} `{item}`: expected NAME=VALUE with a finite number, e.g. `--{what} m=2.5`"
            )),
        }
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        Err(problems)
    }
}

/// A comma-separated list of `n` numbers, or the default.
pub fn parse_list(
    what: &str,
    text: Option<&str>,
    n: usize,
    default: Vec<f64>,
) -> Result<Vec<f64>, String> {
    let Some(text) = text else { return Ok(default) };
    match numbers(what, text) {
        Ok(v) if v.iter().any(|x| !x.is_finite()) => {
            Err(format!("--{what} must be finite numbers, got `{text}`"))
        }
        Ok(v) if v.len() == n => Ok(v),
        Ok(v) => Err(format!(
            "--{what} has {} value(s), the model has {n}",
            v.len()
        )),
        Err(e) => Err(e),
    }
}

/// The numbers of a comma-separated list; an empty (or blank) list has
/// none, which is what a model without coordinates takes (`--q ""`).
pub fn numbers(what: &str, text: &str) -> Result<Vec<f64>, String> {
    if text.trim().is_empty() {
        return Ok(Vec::new());
    }
    text.split(',')
        .map(|x| {
            x.trim()
                .parse::<f64>()
                .map_err(|e| format!("--{what}: `{}`: {e}", x.trim()))
        })
        .collect()
}

/// The names parsed (integrators, constraint methods); each unknown one
/// is a problem.
pub fn parse_names<T: std::str::FromStr>(names: &[String], problems: &mut Vec<String>) -> Vec<T>
where
    T::Err: std::fmt::Display,
{
    names
        .iter()
        .filter_map(|n| {
            n.trim()
                .parse()
                .map_err(|e: T::Err| problems.push(e.to_string()))
                .ok()
        })
        .collect()
}

/// A step size or tolerances that `integrator` (of the models without
/// cables) would not read, each an error naming the integrators it
/// applies to: `--dt` (`dt`) is the fixed-step methods' step, `--rtol`
/// and `--atol` (`tolerances`) the adaptive methods' control.
pub fn unread_step_options(
    integrator: eom_sim::Integrator,
    dt: bool,
    tolerances: bool,
) -> Vec<String> {
    let mut problems = Vec::new();
    if integrator.is_adaptive() && dt {
        problems.push(format!(
            "--dt sets the step of the fixed-step integrators ({}); {integrator} chooses its own \
             steps by --rtol and --atol",
            eom_sim::Integrator::names_where(|i| i.runs_odes() && !i.is_adaptive())
        ));
    }
    if !integrator.is_adaptive() && integrator.runs_odes() && tolerances {
        problems.push(format!(
            "--rtol and --atol control the steps of the adaptive integrators ({}); {integrator} \
             takes fixed steps of --dt",
            eom_sim::Integrator::names_where(eom_sim::Integrator::is_adaptive)
        ));
    }
    problems
}
