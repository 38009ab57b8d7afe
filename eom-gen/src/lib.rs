//! eom-gen: a symbolic equation-of-motion generator for multibody systems.
//!
//! This crate is the generator only; the `eom-gen` command line is the
//! `eom-cli` crate, and `docs/ARCHITECTURE.md` maps the whole.
//!
//! The pipeline runs one way:
//! [`model`] (load a RON model, scene or URDF with [`load`], parse and
//! check it) → [`System`] (validated, with its [`graph`]: spanning tree and
//! cut joints) → [`mech`] (kinematics and dynamics as [`sym`] expressions)
//! → [`emit`] (Rust source); [`generate`] runs it all.
//!
//! [`linearize`] turns the generated derivatives of forward dynamics
//! into a state-space model `A`, `B` about a state, with its eigenvalues.
//!
//! [`flex`] holds the numeric foundation of flexible bodies (FE beam, modes,
//! inertia shape integrals, the floating-frame mass matrix), not yet part of
//! the pipeline.
//!
//! Each stage imports only the ones after it and the leaf modules below
//! them all: [`diag`] (spans, diagnostics, reports) and [`expr`] (the
//! arithmetic of model files). So [`System`] and [`mech`] never import
//! [`model`], yet an error found while formulating still names its
//! `file:line:col` ([`GenerateError`] renders a [`Report`]).

pub mod ancf;
pub mod builder;
#[cfg(feature = "cables")]
pub mod cables;
pub mod diag;
pub mod emit;
pub mod expr;
pub mod flex;
pub mod functions;
pub mod generate;
pub mod graph;
pub mod interpret;
pub mod linearize;
pub mod mech;
pub mod model;
pub mod sym;
pub mod system;
pub mod testkit;

pub use builder::{BuildError, Builder};
pub use emit::{EmitOptions, LoopChoice};
pub use generate::{
    GenerateError, Generated, generate, generate_checked, generate_checked_for, generate_file,
    generate_file_with, generate_file_with_values, generate_tokens, generate_tokens_checked,
    generate_tokens_in, generate_with,
};
pub use model::load_model;
pub use model::{
    Checked, Diagnostic, Format, Loaded, Report, Source, Spec, check, check_file, load, load_with,
    urdf,
};
pub use system::System;
pub use urdf::{Import, import_file};
