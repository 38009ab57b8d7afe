//! The command line's errors: what went wrong, for a person, and the exit
//! status it gives.

use std::fmt;

/// Why a command failed.
#[derive(Clone, Debug, PartialEq)]
pub enum Error {
    /// Arguments that do not make sense, each a sentence (exit 2).
    Usage(Vec<String>),
    /// A file or directory could not be read, written or created.
    Io {
        /// The path, as the user gave it or as it was derived.
        path: String,
        /// What the system said.
        message: String,
    },
    /// Building the generated code failed (the crate is kept for a look).
    Build(String),
    /// A compiled model's program could not be started, stopped abnormally
    /// or replied with something unexpected.
    Program(String),
    /// The runtime refused the run (its own message).
    Refused(String),
    /// A file in the wrong format (work-precision CSV for `--plot`).
    Format(String),
    /// Drawing a plot failed.
    Plot(String),
}

impl Error {
    /// The exit status: 2 for usage errors, 1 for everything else.
    pub fn exit_code(&self) -> u8 {
        match self {
            Error::Usage(_) => 2,
            _ => 1,
        }
    }

    /// An I/O error at `path`.
    pub fn io(path: impl fmt::Display, e: impl fmt::Display) -> Error {
        Error::Io {
            path: path.to_string(),
            message: e.to_string(),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Usage(problems) => f.write_str(&problems.join("; ")),
            Error::Io { path, message } => write!(f, "`{path}`: {message}"),
            Error::Build(m)
            | Error::Program(m)
            | Error::Refused(m)
            | Error::Format(m)
            | Error::Plot(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Error {}
