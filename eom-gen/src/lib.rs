//! eom-gen: a symbolic equation-of-motion generator for multibody systems.
//!
//! The pipeline runs one way (see `DESIGN.md`):
//! `model` (parse and check a RON file) → `graph` (spanning tree, cut joints)
//! → `mech` (kinematics and dynamics as `sym` expressions) → `emit` (Rust).

pub mod sym;
