//! `eom-gen import`: a URDF robot description converted into an eom
//! model (RON), itself checked.

use clap::Args;
use std::process::ExitCode;

/// Convert a URDF robot description into an eom model (RON).
#[derive(Args)]
pub struct ImportArgs {
    /// The URDF file.
    pub urdf: String,
    /// Write the model to this file instead of standard output.
    #[arg(short, long)]
    pub output: Option<String>,
}

pub fn run(a: &ImportArgs, options: &eom_gen::urdf::Options) -> ExitCode {
    let path = a.urdf.as_str();
    let import = match eom_gen::urdf::import_file_with(path, options) {
        Ok(i) => i,
        Err(report) => {
            eprint!("{report}");
            let errors = report.diagnostics.iter().filter(|d| d.is_error()).count();
            eprintln!("error: `{path}` has {errors} error(s)");
            return ExitCode::from(1);
        }
    };
    // The converted model must itself be valid; report it if not.
    let checked = match eom_gen::check(&import.source) {
        Ok(c) => c,
        Err(report) => {
            eprint!("{report}");
            eprintln!("error: the model converted from `{path}` is invalid");
            return ExitCode::from(1);
        }
    };
    eprint!("{}", checked.render_warnings());
    let sys = &checked.system;
    eprintln!(
        "imported `{path}`: model `{}`, {} bodies, {} joints, nq = {} ({})",
        sys.name,
        sys.bodies.len() - 1,
        sys.joints.len(),
        sys.nq(),
        sys.coordinate_names().join(", ")
    );
    for n in &import.notes {
        eprintln!("  - {n}");
    }
    crate::output::emit(&import.source.text, a.output.as_deref())
}
