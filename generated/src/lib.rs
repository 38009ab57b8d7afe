//! Generated source of every bundled model (one module per model).
//!
//! Filled by the emitter (`eom-gen dump`); a test fails when it is stale.
