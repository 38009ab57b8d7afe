//! One file per command of `eom-gen`: its arguments (a clap `Args`
//! struct, the shared ones flattened from `crate::args`) and its `run`.

pub mod animate;
pub mod bench;
pub mod check;
pub mod dump;
pub mod eval;
pub mod import;
pub mod linearize;
pub mod plot;
pub mod simulate;
pub mod solve_static;
pub mod stats;
pub mod sweep;
