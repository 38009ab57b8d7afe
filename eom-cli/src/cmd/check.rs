//! `eom-gen check`: validate a model and print its summary (exit 0 if
//! valid, 1 if not).

use crate::cable_report;
use clap::Args;
use eom_gen::model::{Report, Severity};
use std::process::ExitCode;

/// Validate a model and print a summary (bodies, joints, coordinates,
/// cut joints, Grübler count). Exit 0 if valid, 1 if not.
#[derive(Args)]
pub struct CheckArgs {
    /// The model file (`.ron`, or `.urdf` converted on the fly), or a scene (`.scene.ron`).
    pub model: String,
    /// Print one JSON object instead of the summary.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &CheckArgs, urdf: &eom_gen::urdf::Options) -> ExitCode {
    let path = a.model.as_str();
    let checked = eom_gen::model::load_with(path, urdf)
        .and_then(|l| l.check_with(std::path::Path::new(""), &[]));
    match checked {
        Ok(checked) => {
            eprint!("{}", checked.render_warnings());
            let notes = checked.urdf_notes.clone().unwrap_or_default();
            if a.json {
                let mut v = crate::summary::json(&checked);
                if let Some(notes) = &checked.urdf_notes {
                    v["urdf_notes"] = serde_json::json!(notes);
                }
                if let Some(s) = &checked.scene {
                    v["scene"] = serde_json::json!({
                        "path": s.source.path,
                        "model": s.model_path.display().to_string(),
                        "functions": generated_functions(&checked.request()),
                    });
                }
                println!("{v}");
            } else {
                print!("{}", crate::summary::human(&checked));
                print!("{}", cable_report::check_lines(&checked.system));
                if let Some(s) = &checked.scene {
                    println!("  scene        {}", s.source.path);
                    if s.spec.functions.is_some() {
                        println!(
                            "  generated    {} (the others derived)",
                            generated_functions(&checked.request()).join(", ")
                        );
                    }
                }
                if !notes.is_empty() {
                    println!("  urdf import:");
                    for n in &notes {
                        println!("    - {n}");
                    }
                }
            }
            ExitCode::SUCCESS
        }
        Err(report) => {
            eprint!("{report}");
            if a.json {
                println!("{}", diagnostics_json(&report));
            }
            let errors = report.diagnostics.iter().filter(|d| d.is_error()).count();
            eprintln!("error: `{path}` has {errors} error(s)");
            ExitCode::from(1)
        }
    }
}

/// The names of the functions a request generates symbolically.
fn generated_functions(r: &eom_gen::functions::FunctionSet) -> Vec<&'static str> {
    use eom_gen::functions::Function;
    std::iter::once(Function::Qdot.name())
        .chain(r.iter().map(Function::name))
        .collect()
}

fn diagnostics_json(report: &Report) -> serde_json::Value {
    let items: Vec<serde_json::Value> = report
        .diagnostics
        .iter()
        .map(|d| {
            let lc = d.span.map(|s| report.source.line_col(s.start));
            serde_json::json!({
                "severity": if d.severity == Severity::Error { "error" } else { "warning" },
                "line": lc.map(|l| l.line),
                "col": lc.map(|l| l.col),
                "message": d.message,
                "help": d.help,
            })
        })
        .collect();
    serde_json::json!({ "valid": false, "diagnostics": items })
}
