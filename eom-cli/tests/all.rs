//! The command line's integration tests: one module per file of this
//! folder, built and linked as one binary so that a test of one file runs
//! beside a test of another on the second core (BENCHMARKS.md "CI"). One
//! file's tests: `cargo test -p eom-cli --test all chain200::`.

#[path = "ancf_cli.rs"]
mod ancf_cli;
#[path = "ancf_cli_loops.rs"]
mod ancf_cli_loops;
#[path = "ancf_mixed_statics_cli.rs"]
mod ancf_mixed_statics_cli;
#[path = "chain200.rs"]
mod chain200;
#[path = "cli.rs"]
mod cli;
#[path = "honest.rs"]
mod honest;
#[path = "jacobian.rs"]
mod jacobian;
#[path = "lanes_cli.rs"]
mod lanes_cli;
#[path = "linearize.rs"]
mod linearize;
#[path = "plot_sweep.rs"]
mod plot_sweep;
#[path = "urdf_cli.rs"]
mod urdf_cli;
