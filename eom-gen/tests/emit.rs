//! Pinned emitted source (insta) for the smallest bundled model; the
//! committed `generated/` crate pins every other model (see the root
//! `tests/generated.rs`, which also compiles and runs it).

use eom_gen::functions::{Function, FunctionSet};
use eom_gen::{Source, generate};

/// The checked system of the model `text` (named `name`) and its
/// formulation of `request`.
fn formulated(
    name: &str,
    text: &str,
    request: FunctionSet,
) -> (eom_gen::System, eom_gen::mech::Formulation) {
    let sys = eom_gen::model::check(&Source::new(name, text.to_string()))
        .unwrap_or_else(|r| panic!("{r}"))
        .system;
    let f = eom_gen::mech::formulate(&sys, request).unwrap_or_else(|e| panic!("{e}"));
    (sys, f)
}

/// No `let` of `source` is nested deeper than a block (rustc overflows its
/// stack on about 2 950 nested `let`s with debug info).
fn assert_nested_no_deeper_than_a_block(source: &str) {
    let (deepest, _) = eom_gen::testkit::deepest_lets(source);
    assert!(
        deepest <= eom_gen::emit::BLOCK_LIMIT + 1,
        "{deepest} nested `let`s"
    );
}

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

/// arm7's forward-dynamics derivatives (5 330 operations, most of them
/// before the product `−M⁻¹ G`) are written one state at a
/// time as one function, depth first, not in parts: in blocks of at most
/// `BLOCK_LIMIT` instructions (rustc overflows its stack on about 2 950
/// nested `let`s with debug info; BENCHMARKS.md "One function or parts",
/// "Depth-first order for the derivatives"); their lane version, bound by
/// throughput, keeps its parts.
#[test]
fn arm7s_derivatives_are_one_function_in_blocks() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/arm7.ron");
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let request = FunctionSet::default().with(Function::ForwardDynamicsDerivatives);
    let (sys, f) = formulated("models/arm7.ron", &text, request);
    let len = f
        .program(Function::ForwardDynamicsDerivatives)
        .map_or(0, |p| p.instrs.len());
    assert!(
        len > 2 * eom_gen::emit::BLOCK_LIMIT && len <= eom_gen::emit::ONE_PART_LIMIT,
        "{len} instructions"
    );
    let opts = eom_gen::EmitOptions {
        lanes: true,
        ..Default::default()
    };
    let source = eom_gen::emit::emit_with(&sys, &f, &text, &opts);
    assert!(source.contains("fn forward_dynamics_derivatives("));
    assert!(!source.contains("fn forward_dynamics_derivatives_part"));
    assert!(source.contains("fn forward_dynamics_derivatives_lanes_part0"));
    assert_nested_no_deeper_than_a_block(&source);
}

/// The spatial 10-link chain's forward-dynamics derivatives (8 612
/// instructions, more than forward dynamics may have written whole) are
/// one function one state at a time, depth first in blocks (BENCHMARKS.md
/// "Depth-first order for the derivatives"), nested no deeper than a block.
#[test]
fn long_derivatives_are_one_function_in_blocks() {
    let text = eom_gen::model::builder::n_link_chain(10, true).to_ron();
    let request = FunctionSet::default().with(Function::ForwardDynamicsDerivatives);
    let (sys, f) = formulated("chain10.ron", &text, request);
    let len = f
        .program(Function::ForwardDynamicsDerivatives)
        .map_or(0, |p| p.instrs.len());
    assert!(
        len > eom_gen::emit::ONE_PART_LIMIT && len <= eom_gen::emit::DERIVATIVES_ONE_PART_LIMIT,
        "{len} instructions"
    );
    let source = eom_gen::emit::emit_with(&sys, &f, &text, &eom_gen::EmitOptions::default());
    assert!(source.contains("fn forward_dynamics_derivatives("));
    assert!(!source.contains("fn forward_dynamics_derivatives_part"));
    assert_nested_no_deeper_than_a_block(&source);
}

/// The spatial 20-link chain's forward and inverse dynamics (5 618 and
/// 2 924 instructions) are each one late-scheduled function one state at a
/// time, in blocks (BENCHMARKS.md "One function or parts": the inverse
/// dynamics about 15 % faster than in parts); its mass matrix (3 624), which
/// was slower in one part on talos, keeps its parts, as do the lane
/// versions.
#[test]
fn forward_and_inverse_dynamics_up_to_the_limit_are_one_function() {
    let text = eom_gen::model::builder::n_link_chain(20, true).to_ron();
    // A model without a scene derives `M` from inverse dynamics; ask for it.
    let request = FunctionSet::all_requested().with(Function::MassMatrix);
    let (sys, f) = formulated("chain20.ron", &text, request);
    for function in [
        Function::ForwardDynamics,
        Function::InverseDynamics,
        Function::MassMatrix,
    ] {
        let len = f.program(function).map_or(0, |p| p.instrs.len());
        assert!(
            len > eom_gen::emit::PART_LIMIT && len <= eom_gen::emit::ONE_PART_LIMIT,
            "{function:?}: {len} instructions, want between the two limits"
        );
    }
    let opts = eom_gen::EmitOptions {
        lanes: true,
        loops: eom_gen::LoopChoice::Never,
        ..Default::default()
    };
    let source = eom_gen::emit::emit_with(&sys, &f, &text, &opts);
    for whole in ["forward_dynamics", "inverse_dynamics"] {
        assert!(source.contains(&format!("fn {whole}(")), "{whole}");
        assert!(
            !source.contains(&format!("fn {whole}_part")),
            "{whole} in parts"
        );
        assert!(
            source.contains(&format!("fn {whole}_lanes_part0")),
            "{whole}_lanes"
        );
    }
    assert!(
        source.contains("fn mass_matrix_part0"),
        "the mass matrix in parts"
    );
    assert_nested_no_deeper_than_a_block(&source);
}

/// One state at a time, a function in parts (the 20-link chain's mass
/// matrix) or in blocks (its forward and inverse dynamics) stores each
/// output where its value is computed: the parts that compute outputs take
/// the function's output array, and no output is copied out of the scratch
/// array at the end (BENCHMARKS.md, "The instruction cache"). Their lane
/// versions still pass outputs through it.
#[test]
fn outputs_are_stored_where_they_are_computed() {
    let text = eom_gen::model::builder::n_link_chain(20, true).to_ron();
    let request = FunctionSet::all_requested().with(Function::MassMatrix);
    let (sys, f) = formulated("chain20.ron", &text, request);
    let opts = eom_gen::EmitOptions {
        loops: eom_gen::LoopChoice::Never,
        ..Default::default()
    };
    let source = eom_gen::emit::emit_with(&sys, &f, &text, &opts);
    let flat: String = source.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        flat.contains("m: &mut [[f64; 20]; 20]) {"),
        "a part of the mass matrix takes its output array"
    );
    assert!(
        !flat.contains("] = s["),
        "an output copied from the scratch array"
    );
    // Every entry of the lower triangle is stored (and mirrored), in the
    // parts or, for constants, in the function.
    for i in 0..20 {
        for j in 0..=i {
            assert!(flat.contains(&format!("m[{i}][{j}] = ")), "M[{i}][{j}]");
        }
    }
    for k in 0..20 {
        assert!(flat.contains(&format!("udot[{k}] = ")), "udot[{k}]");
        assert!(flat.contains(&format!("tau[{k}] = ")), "tau[{k}]");
    }
}
