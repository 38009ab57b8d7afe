//! The `eom-gen` command-line tool.

use clap::{Parser, Subcommand};
use eom_gen::model::{Report, Severity};
use std::process::ExitCode;

/// Symbolic equation-of-motion generator for multibody systems.
#[derive(Parser)]
#[command(name = "eom-gen", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Validate a model and print a summary (bodies, joints, coordinates,
    /// cut joints, Grübler count). Exit 0 if valid, 1 if not.
    Check {
        /// The model file (`.ron`).
        model: String,
        /// Print one JSON object instead of the summary.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check { model, json } => check(&model, json),
    }
}

fn check(path: &str, json: bool) -> ExitCode {
    match eom_gen::check_file(path) {
        Ok(checked) => {
            eprint!("{}", checked.source.render_all(&checked.warnings));
            if json {
                println!("{}", eom_gen::summary::json(&checked));
            } else {
                print!("{}", eom_gen::summary::human(&checked));
            }
            ExitCode::SUCCESS
        }
        Err(report) => {
            eprint!("{report}");
            if json {
                println!("{}", diagnostics_json(&report));
            }
            let errors = report.diagnostics.iter().filter(|d| d.is_error()).count();
            eprintln!("error: `{path}` has {errors} error(s)");
            ExitCode::from(1)
        }
    }
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
