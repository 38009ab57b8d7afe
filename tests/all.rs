//! The end-to-end tests: one module per file of this folder, built and
//! linked as one binary so that a test of one file runs beside a test of
//! another on the second core (BENCHMARKS.md "CI"). One file's tests:
//! `cargo test --test all physics::`.

#[path = "batched.rs"]
mod batched;
#[path = "conservation.rs"]
mod conservation;
#[path = "derivatives_compiled.rs"]
mod derivatives_compiled;
#[path = "generated.rs"]
mod generated;
#[path = "hard_cases.rs"]
mod hard_cases;
#[path = "loops.rs"]
mod loops;
#[path = "models.rs"]
mod models;
#[path = "physics.rs"]
mod physics;
#[path = "scene_macro.rs"]
mod scene_macro;
#[path = "singular_loops.rs"]
mod singular_loops;
