//! eom-gen: a symbolic equation-of-motion generator for multibody systems.
//!
//! The pipeline runs one way (see `DESIGN.md`):
//! [`model`] (parse and check a RON file) → [`System`] (validated, with its
//! [`graph`]: spanning tree and cut joints) → `mech` (kinematics and
//! dynamics as [`sym`] expressions) → `emit` (Rust source).

pub mod bench;
pub mod builder;
pub mod compiled;
pub mod diag;
pub mod emit;
pub mod expr;
pub mod generate;
pub mod graph;
pub mod interpret;
pub mod mech;
pub mod model;
pub mod plot;
pub mod summary;
pub mod sym;
pub mod system;
pub mod testkit;
pub mod work_precision;

pub use builder::{BuildError, Builder};
pub use emit::EmitOptions;
pub use generate::{
    GenerateError, Generated, generate, generate_checked, generate_file, generate_file_with,
    generate_tokens, generate_tokens_checked, generate_tokens_in, generate_with,
};
pub use model::{
    Checked, Diagnostic, Format, Loaded, Report, Source, Spec, check, check_file, load, urdf,
};
pub use system::System;
pub use urdf::{Import, import_file, load_model};
