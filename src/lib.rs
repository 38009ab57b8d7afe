//! The `eom` root package: it owns the end-to-end tests in `tests/` and the
//! examples in `examples/`. The tools themselves live in `eom-gen`,
//! `eom-macros` and `eom-sim`.
