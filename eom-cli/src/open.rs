//! Opening a model once per run: the file is read (a URDF converted with
//! this run's options), the names `--param` and `--input` give are
//! checked against it (usage errors, exit 2), and it is checked with the
//! parameter values; the checked model is handed down to the command,
//! which generates from it ([`generate`]) without reading the file again.

use crate::args::Vary;
use eom_gen::Checked;
use std::process::ExitCode;

/// A model read and checked, with the input values in the model's order
/// (zero where not set).
pub struct Opened {
    /// The path as the user gave it (for messages).
    pub path: String,
    /// The checked model, parameter values applied, inputs not yet driven.
    pub checked: Checked,
    /// The values of the inputs `--input NAME=VALUE` holds, in the model's
    /// order after the driven ones left it.
    pub inputs: Vec<f64>,
}

/// Prints a model's report and gives exit status 1.
fn report(r: &eom_gen::Report) -> ExitCode {
    eprint!("{r}");
    if !r.to_string().ends_with('\n') {
        eprintln!();
    }
    ExitCode::from(1)
}

/// Reads and checks `path` with `vary`'s parameter values. An invalid file
/// is reported (exit 1); an unknown parameter or input name, or an input
/// given twice, is a usage error with the closest name (exit 2).
pub fn open(path: &str, urdf: &eom_gen::urdf::Options, vary: &Vary) -> Result<Opened, ExitCode> {
    let loaded = eom_gen::model::load_with(path, urdf).map_err(|r| report(&r))?;
    let root = std::path::Path::new("");
    if vary.names_nothing() {
        let checked = loaded.check_with(root, &[]).map_err(|r| report(&r))?;
        return Ok(Opened {
            path: path.to_string(),
            checked,
            inputs: Vec::new(),
        });
    }
    // The names are checked against the model as the file has it, so a
    // misspelt one is a usage error rather than the model's.
    let base = loaded.check_with(root, &[]).map_err(|r| report(&r))?;
    let inputs = resolve(vary, &base, path)?;
    let checked = if vary.params.is_empty() {
        base
    } else {
        loaded
            .check_with(root, &vary.params)
            .map_err(|r| report(&r))?
    };
    Ok(Opened {
        path: path.to_string(),
        checked,
        inputs,
    })
}

/// The input values in the model's order (zero where not set), after
/// checking every name against the model: an unknown parameter or input
/// is a usage error (exit 2) with the closest name.
fn resolve(vary: &Vary, checked: &Checked, path: &str) -> Result<Vec<f64>, ExitCode> {
    let mut checked = checked.clone();
    let mut problems: Vec<String> = Vec::new();
    for (name, _) in &vary.inputs {
        if vary.drives.iter().any(|(d, _)| d == name) {
            problems.push(format!(
                "input `{name}` is given a value and an expression; give one"
            ));
        }
    }
    // The driven inputs leave the model; the others keep their order.
    if let Err(errors) = eom_gen::model::drive_inputs(&mut checked, &vary.drives) {
        problems.extend(errors.iter().map(|e| format!("--input {}: {e}", e.input)));
    }
    let sys = &checked.system;
    let params: Vec<&str> = sys.parameters.iter().map(|p| p.name.as_str()).collect();
    let inputs: Vec<&str> = sys.inputs.iter().map(String::as_str).collect();
    for (what, given, known) in [
        ("parameter", &vary.params, &params),
        ("input", &vary.inputs, &inputs),
    ] {
        for (name, _) in given {
            if known.contains(&name.as_str()) {
                continue;
            }
            let hint = match eom_gen::diag::did_you_mean(name, known.iter().copied()) {
                Some(m) => format!(" (did you mean `{m}`?)"),
                None if known.is_empty() => format!("; `{}` has none", sys.name),
                None => format!(
                    "; its {what}s: {}",
                    known
                        .iter()
                        .map(|n| format!("`{n}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            };
            problems.push(format!("`{path}` has no {what} `{name}`{hint}"));
        }
    }
    if !problems.is_empty() {
        for p in problems {
            eprintln!("error: {p}");
        }
        return Err(ExitCode::from(2));
    }
    Ok(sys
        .inputs
        .iter()
        .map(|n| {
            vary.inputs
                .iter()
                .rev()
                .find(|(m, _)| m == n)
                .map_or(0.0, |(_, v)| *v)
        })
        .collect())
}

/// Generates the opened model with `vary`'s driven inputs and initial
/// state, with a progress line on a terminal when it takes longer than
/// half a second (large models). Errors are printed (exit 1).
pub fn generate(
    opened: &Opened,
    vary: &Vary,
    options: &eom_gen::EmitOptions,
) -> Result<eom_gen::Generated, ExitCode> {
    generate_asking(
        opened,
        vary,
        options,
        eom_gen::functions::FunctionSet::default(),
    )
}

/// [`generate`] with the functions of `also` added to the model's request
/// (those generated only when asked for, as the derivatives `bench
/// --per-call --derivatives` times).
pub fn generate_asking(
    opened: &Opened,
    vary: &Vary,
    options: &eom_gen::EmitOptions,
    also: eom_gen::functions::FunctionSet,
) -> Result<eom_gen::Generated, ExitCode> {
    generate_with_progress(opened, vary, options, also).map_err(|e| {
        eprint!("{e}");
        if !e.to_string().ends_with('\n') {
            eprintln!();
        }
        ExitCode::from(1)
    })
}

fn generate_with_progress(
    opened: &Opened,
    vary: &Vary,
    options: &eom_gen::EmitOptions,
    also: eom_gen::functions::FunctionSet,
) -> Result<eom_gen::Generated, eom_gen::GenerateError> {
    use std::io::{IsTerminal, Write};
    use std::sync::mpsc;
    use std::time::{Duration, Instant};
    let generate = || {
        let mut checked = opened.checked.clone();
        // Checked by `open` before (exit 2), reported again here.
        if let Err(errors) = eom_gen::model::drive_inputs(&mut checked, &vary.drives) {
            return Err(eom_gen::GenerateError::Model(eom_gen::Report {
                source: checked.source.clone(),
                diagnostics: errors
                    .into_iter()
                    .map(|e| eom_gen::Diagnostic::file_error(e.message).with_help(e.help))
                    .collect(),
            }));
        }
        if let Err(e) =
            eom_gen::model::set_initial(&mut checked, vary.q0.as_deref(), vary.u0.as_deref())
        {
            return Err(eom_gen::GenerateError::Model(eom_gen::Report {
                source: checked.source.clone(),
                diagnostics: vec![eom_gen::Diagnostic::file_error(e)],
            }));
        }
        let mut request = checked.request();
        for f in also.iter() {
            request.insert(f);
        }
        eom_gen::generate_checked_for(checked, request, options)
    };
    if !std::io::stderr().is_terminal() {
        return generate();
    }
    let (done, wait) = mpsc::channel::<()>();
    let label = opened.path.clone();
    let spinner = std::thread::spawn(move || {
        let start = Instant::now();
        let frames = ['|', '/', '-', '\\'];
        let mut k = 0;
        let mut shown = false;
        while wait.recv_timeout(Duration::from_millis(120)).is_err() {
            if start.elapsed() > Duration::from_millis(500) {
                eprint!(
                    "\r{} generating `{label}` … {:.1} s",
                    frames[k % 4],
                    start.elapsed().as_secs_f64()
                );
                let _ = std::io::stderr().flush();
                shown = true;
                k += 1;
            }
        }
        if shown {
            eprintln!(
                "\rgenerated `{label}` in {:.1} s        ",
                start.elapsed().as_secs_f64()
            );
        }
    });
    let result = generate();
    let _ = done.send(());
    let _ = spinner.join();
    result
}

/// For a model made of cables alone (no rigid bodies): a usage error for
/// `what`, which works on the generated functions of a rigid part, naming
/// the commands that apply; `None` for every other model.
pub fn cables_only_refusal(checked: &Checked, what: &str) -> Option<ExitCode> {
    let sys = &checked.system;
    if sys.cables.is_empty() || sys.bodies.len() > 1 {
        return None;
    }
    let names: Vec<String> = sys.cables.iter().map(|c| format!("`{}`", c.name)).collect();
    eprintln!(
        "error: `{}` is made of cables alone ({}): {what} works on the generated functions of \
         rigid bodies, and this model has none (nothing is generated per model: the cables' \
         elements are model-independent kernels); `simulate` integrates it, `solve-static` \
         finds its equilibrium, `check` and `stats` describe its cables",
        sys.name,
        names.join(", ")
    );
    Some(ExitCode::from(2))
}
