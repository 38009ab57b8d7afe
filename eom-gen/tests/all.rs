//! eom-gen's integration tests: one module per file of this folder, built
//! and linked as one binary so that a test of one file runs beside a test
//! of another on the second core (`cargo test` runs test binaries one after
//! another; 37 binaries each linked eom-gen and left a core idle whenever
//! one long test was all that remained, BENCHMARKS.md "CI").
//!
//! One file's tests: `cargo test -p eom-gen --features cables --test all
//! flex_crank::`. The modules of the mixed models (rigid part and cables)
//! need the `cables` feature, which `cargo test --workspace` turns on.
//! `diagnostics` and `emit` stay binaries of their own: their snapshot
//! files are named after the binary.

#[cfg(feature = "cables")]
#[path = "ancf_elements.rs"]
mod ancf_elements;
#[cfg(feature = "cables")]
#[path = "ancf_ffr.rs"]
mod ancf_ffr;
#[cfg(feature = "cables")]
#[path = "ancf_mixed.rs"]
mod ancf_mixed;
#[cfg(feature = "cables")]
#[path = "ancf_mixed_loops.rs"]
mod ancf_mixed_loops;
#[cfg(feature = "cables")]
#[path = "cable_contacts.rs"]
mod cable_contacts;
#[cfg(feature = "cables")]
#[path = "cable_contacts_mixed.rs"]
mod cable_contacts_mixed;
#[cfg(feature = "cables")]
#[path = "cable_motion.rs"]
mod cable_motion;
#[path = "constraints.rs"]
mod constraints;
#[path = "contacts.rs"]
mod contacts;
#[path = "derivatives.rs"]
mod derivatives;
#[path = "dynamics.rs"]
mod dynamics;
#[path = "flex_beam.rs"]
mod flex_beam;
#[path = "flex_crank.rs"]
mod flex_crank;
#[path = "flex_hub_beam.rs"]
mod flex_hub_beam;
#[path = "flex_modal_stiffening.rs"]
mod flex_modal_stiffening;
#[path = "flex_model.rs"]
mod flex_model;
#[path = "flex_nodes.rs"]
mod flex_nodes;
#[path = "flex_outputs.rs"]
mod flex_outputs;
#[path = "flex_sources.rs"]
mod flex_sources;
#[path = "flex_spin_up.rs"]
mod flex_spin_up;
#[path = "flex_stiffening.rs"]
mod flex_stiffening;
#[path = "flex_timoshenko.rs"]
mod flex_timoshenko;
#[path = "flex_tunable.rs"]
mod flex_tunable;
#[path = "friction.rs"]
mod friction;
#[path = "fuzz_findings.rs"]
mod fuzz_findings;
#[path = "impacts.rs"]
mod impacts;
#[path = "linearize.rs"]
mod linearize;
#[path = "loops.rs"]
mod loops;
#[path = "robustness.rs"]
mod robustness;
#[path = "scenes.rs"]
mod scenes;
#[path = "sym_program.rs"]
mod sym_program;
#[path = "sym_props.rs"]
mod sym_props;
#[path = "sym_rules.rs"]
mod sym_rules;
#[path = "twin.rs"]
mod twin;
#[path = "unknown_fields.rs"]
mod unknown_fields;
#[path = "urdf.rs"]
mod urdf;
#[path = "urdf_quirks.rs"]
mod urdf_quirks;
