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
    /// Print the generated Rust source of a model.
    Dump {
        /// The model file (`.ron`).
        model: String,
        /// Write to this file instead of standard output.
        #[arg(short, long)]
        output: Option<String>,
    },
    /// Operation counts of the generated functions and generation time.
    Stats {
        /// The model file (`.ron`).
        model: String,
        /// Print one JSON object (the only format).
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Check { model, json } => check(&model, json),
        Command::Dump { model, output } => dump(&model, output.as_deref()),
        Command::Stats { model, json: _ } => stats(&model),
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

fn generated(path: &str) -> Result<eom_gen::Generated, ExitCode> {
    eom_gen::generate_file(path).map_err(|e| {
        eprint!("{e}");
        if !e.to_string().ends_with('\n') {
            eprintln!();
        }
        ExitCode::from(1)
    })
}

fn dump(path: &str, output: Option<&str>) -> ExitCode {
    let g = match generated(path) {
        Ok(g) => g,
        Err(code) => return code,
    };
    eprint!("{}", g.checked.source.render_all(&g.checked.warnings));
    match output {
        None => {
            print!("{}", g.source);
            ExitCode::SUCCESS
        }
        Some(file) => match std::fs::write(file, &g.source) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: cannot write `{file}`: {e}");
                ExitCode::from(1)
            }
        },
    }
}

fn stats(path: &str) -> ExitCode {
    let g = match generated(path) {
        Ok(g) => g,
        Err(code) => return code,
    };
    let f = &g.formulation;
    let ops = |p: &Option<eom_gen::sym::Program>| p.as_ref().map(|p| op_json(&p.op_count()));
    let candidates: serde_json::Map<String, serde_json::Value> = f
        .fd_candidates
        .iter()
        .map(|(form, c)| (format!("{form:?}"), op_json(c)))
        .collect();
    let v = serde_json::json!({
        "name": g.checked.system.name,
        "formulation": format!("{}", f.fd_form),
        "forward_dynamics_candidates": candidates,
        "ops": {
            "qdot": op_json(&f.qdot.op_count()),
            "forward_dynamics": ops(&f.forward_dynamics),
            "inverse_dynamics": ops(&f.inverse_dynamics),
            "mass_matrix": ops(&f.mass_matrix),
            "bias": ops(&f.bias),
            "energy": ops(&f.energy),
            "momentum": ops(&f.momentum),
        },
        "generation_ms": f.seconds * 1e3,
        "source_bytes": g.source.len(),
    });
    println!("{v}");
    ExitCode::SUCCESS
}

fn op_json(c: &eom_gen::sym::OpCount) -> serde_json::Value {
    serde_json::json!({
        "add": c.adds, "mul": c.muls, "div": c.divs, "neg": c.negs,
        "sqrt": c.sqrts, "trig": c.trig, "other": c.other, "total": c.total(),
    })
}
