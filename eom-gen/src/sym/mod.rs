//! Symbolic engine: hash-consed expression DAG, simplification, derivatives,
//! lowering to straight-line programs, and an evaluator.
