//! Generated source of every bundled model, one module per model, committed
//! so readers can see what eom-gen emits. A test fails when a file is stale;
//! refresh with `cargo run -p eom-gen --example regenerate`.

pub mod andrews;
pub mod arm7;
pub mod bricard;
pub mod double_pendulum;
pub mod fourbar;
pub mod free_body;
pub mod heavy_top;
pub mod pendulum;
pub mod rolling_disk;
pub mod slider_crank;
pub mod slider_crank_driven;
pub mod stewart;
pub mod stewart_driven;
