//! eom-sim: the runtime side of eom.
//!
//! Generated code implements this crate's model trait; integrators and
//! constraint solvers run on it. It depends on `nalgebra`, never on
//! `eom-gen`. The trait and the integrators land with the emission and
//! integrator issues; until then this crate holds no API.
