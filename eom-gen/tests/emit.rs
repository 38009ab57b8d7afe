//! Pinned emitted source (insta) for the smallest bundled model; the
//! committed `generated/` crate pins every other model (see the root
//! `tests/generated.rs`, which also compiles and runs it).

use eom_gen::{Source, generate};

#[test]
fn pendulum_source_is_pinned() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/pendulum.ron");
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let g = generate(&Source::new("models/pendulum.ron", text)).unwrap_or_else(|e| panic!("{e}"));
    insta::assert_snapshot!(g.source);
}

#[test]
fn parameters_marked_tunable_become_fields_with_defaults() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/pendulum.ron");
    let text = std::fs::read_to_string(path).unwrap_or_default().replace(
        "(name: \"l\", value: 1.0,",
        "(name: \"l\", value: 1.0, tunable: true,",
    );
    let g = generate(&Source::new("pendulum.ron", text)).unwrap_or_else(|e| panic!("{e}"));
    assert!(g.source.contains("pub l: f64,"), "{}", g.source);
    assert!(
        g.source.contains("PendulumParams { l: 1.0 }"),
        "{}",
        g.source
    );
    assert!(
        g.source.contains("self.params.l"),
        "the length is read at run time"
    );
}

#[test]
fn arm7_source_is_pinned() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/arm7.ron");
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let g = generate(&Source::new("models/arm7.ron", text)).unwrap_or_else(|e| panic!("{e}"));
    insta::assert_snapshot!(g.source);
}
