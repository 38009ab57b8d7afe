//! What every command does with its results and errors: errors printed
//! with their exit status, files written only where the user said.

use crate::error::Error;
use std::process::ExitCode;

/// Prints an error (each usage problem on its own line) and gives its
/// exit status.
pub fn fail(e: &Error) -> ExitCode {
    match e {
        Error::Usage(problems) => problems.iter().for_each(|p| eprintln!("error: {p}")),
        e => eprintln!("error: {e}"),
    }
    ExitCode::from(e.exit_code())
}

/// Writes `text` to `path`; its directory must exist (nothing is created
/// that the user did not name). The error, naming the path, is printed
/// and the exit status returned.
pub fn write_file(path: &str, text: &str) -> Result<(), ExitCode> {
    let fail = |why: String| {
        eprintln!("error: cannot write `{path}`: {why}");
        ExitCode::from(1)
    };
    if let Some(dir) = std::path::Path::new(path).parent()
        && !dir.as_os_str().is_empty()
        && !dir.is_dir()
    {
        return Err(fail(format!(
            "the directory `{}` does not exist",
            dir.display()
        )));
    }
    std::fs::write(path, text).map_err(|e| fail(e.to_string()))
}

/// Creates the output directory the user named (`bench --suite --out`).
pub fn create_out_dir(dir: &str) -> Result<(), ExitCode> {
    std::fs::create_dir_all(dir).map_err(|e| {
        eprintln!("error: cannot create the output directory `{dir}`: {e}");
        ExitCode::from(1)
    })
}

/// Writes `text` to `output`, or to standard output without one.
pub fn emit(text: &str, output: Option<&str>) -> ExitCode {
    match output {
        None => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Some(file) => match write_file(file, text) {
            Ok(()) => ExitCode::SUCCESS,
            Err(code) => code,
        },
    }
}
