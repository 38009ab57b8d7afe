//! eom-sim's integration tests: one module per file of this folder, built
//! and linked as one binary so that a test of one file runs beside a test
//! of another on the second core (BENCHMARKS.md "CI"). One file's tests:
//! `cargo test -p eom-sim --features cables --test all ancf_cable::`. The
//! modules of the large runtime need the `cables` feature, which `cargo
//! test --workspace` turns on.

#[cfg(feature = "cables")]
#[path = "alpha_control.rs"]
mod alpha_control;
#[cfg(feature = "cables")]
#[path = "alpha_restart.rs"]
mod alpha_restart;
#[cfg(feature = "cables")]
#[path = "ancf_cable.rs"]
mod ancf_cable;
#[cfg(feature = "cables")]
#[path = "ancf_elements_physics.rs"]
mod ancf_elements_physics;
#[cfg(feature = "cables")]
#[path = "ancf_lanes.rs"]
mod ancf_lanes;
#[cfg(feature = "cables")]
#[path = "ancf_mixed.rs"]
mod ancf_mixed;
#[cfg(feature = "cables")]
#[path = "ancf_mixed_loops.rs"]
mod ancf_mixed_loops;
#[cfg(feature = "cables")]
#[path = "ancf_mixed_statics.rs"]
mod ancf_mixed_statics;
/// Test problems and helpers shared by the modules.
mod common;
#[path = "geometric.rs"]
mod geometric;
#[cfg(feature = "cables")]
#[path = "large_runtime.rs"]
mod large_runtime;
#[path = "lcp.rs"]
mod lcp;
#[path = "order.rs"]
mod order;
#[path = "problems.rs"]
mod problems;
#[path = "robustness.rs"]
mod robustness;
