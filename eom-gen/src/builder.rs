//! `build.rs` support, in the manner of `prost-build`: generate one module
//! per model into `OUT_DIR` and tell cargo to rerun when a model changes.
//!
//! In `build.rs`:
//! ```no_run
//! eom_gen::Builder::new()
//!     .model("models/double_pendulum.ron")
//!     .compile()
//!     .unwrap_or_else(|e| panic!("{e}"));
//! ```
//! and in the crate: `include!(concat!(env!("OUT_DIR"), "/double_pendulum.rs"));`
//! (see `examples/build_rs`).

use crate::{GenerateError, generate_file_with};
use std::fmt;
use std::path::PathBuf;

/// Generates Rust modules from model files at build time.
#[derive(Clone, Debug, Default)]
pub struct Builder {
    models: Vec<String>,
    out_dir: Option<PathBuf>,
    fma: bool,
    fma_if_target_has_it: bool,
    lanes: bool,
}

/// Why a build step failed.
#[derive(Debug)]
pub enum BuildError {
    /// A model could not be generated (diagnostics with positions).
    Generate(GenerateError),
    /// No output directory (`OUT_DIR` unset outside build scripts).
    NoOutDir,
    /// Writing the generated file failed.
    Io(String, std::io::Error),
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BuildError::Generate(e) => write!(f, "{e}"),
            BuildError::NoOutDir => write!(
                f,
                "OUT_DIR is not set: call `Builder::out_dir` outside build scripts"
            ),
            BuildError::Io(path, e) => write!(f, "cannot write `{path}`: {e}"),
        }
    }
}

impl std::error::Error for BuildError {}

impl Builder {
    /// A builder with no models.
    pub fn new() -> Self {
        Builder::default()
    }

    /// Adds a model file, `.ron` or `.urdf`, or a scene file (`.scene.ron`,
    /// whose model is relative to it); paths relative to the crate being built.
    pub fn model(mut self, path: impl Into<String>) -> Self {
        self.models.push(path.into());
        self
    }

    /// Writes into `dir` instead of `OUT_DIR`.
    pub fn out_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.out_dir = Some(dir.into());
        self
    }

    /// Emits `f64::mul_add` for `a·b + c` (see [`crate::EmitOptions::fma`]).
    pub fn fma(mut self, on: bool) -> Self {
        self.fma = on;
        self
    }

    /// Emits `f64::mul_add` for `a·b + c` when the crate is built for a
    /// target with FMA (`-C target-cpu=native` on a machine that has it,
    /// or `-C target-feature=+fma`), read from cargo's
    /// `CARGO_CFG_TARGET_FEATURE`; elsewhere `mul_add` would be a libm call,
    /// so the code stays unfused.
    pub fn fma_if_target_has_it(mut self) -> Self {
        self.fma_if_target_has_it = true;
        self
    }

    /// Also emits every function over lanes, `W` states per call (see
    /// [`crate::EmitOptions::lanes`] and `eom_sim::batch`).
    pub fn lanes(mut self, on: bool) -> Self {
        self.lanes = on;
        self
    }

    /// Generates every model into `<out_dir>/<model name>.rs` and prints
    /// `cargo:rerun-if-changed=<model>` for each (and for a scene's model). Reports the first model
    /// that fails, with all of its diagnostics.
    pub fn compile(self) -> Result<Vec<PathBuf>, BuildError> {
        let dir = match self.out_dir {
            Some(d) => d,
            None => PathBuf::from(std::env::var_os("OUT_DIR").ok_or(BuildError::NoOutDir)?),
        };
        let fma = self.fma || (self.fma_if_target_has_it && target_has_fma());
        let mut written = Vec::new();
        for path in &self.models {
            println!("cargo:rerun-if-changed={path}");
            let opts = crate::EmitOptions {
                fma,
                lanes: self.lanes,
                ..Default::default()
            };
            let g = generate_file_with(path, &opts).map_err(BuildError::Generate)?;
            if let Some(scene) = &g.checked.scene {
                println!("cargo:rerun-if-changed={}", scene.model_path.display());
            }
            let file = dir.join(format!("{}.rs", g.checked.system.name));
            std::fs::write(&file, &g.source)
                .map_err(|e| BuildError::Io(file.display().to_string(), e))?;
            written.push(file);
        }
        Ok(written)
    }
}

/// Is the crate being built for a target with FMA? (cargo's
/// `CARGO_CFG_TARGET_FEATURE`, set for build scripts.)
fn target_has_fma() -> bool {
    std::env::var("CARGO_CFG_TARGET_FEATURE").is_ok_and(|f| f.split(',').any(|x| x == "fma"))
}
