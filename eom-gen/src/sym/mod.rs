//! Symbolic engine: hash-consed expression DAG, simplification, derivatives,
//! lowering to straight-line programs, and an evaluator.

mod arena;
mod build;
mod eval;
mod node;
mod num;
mod sexpr;
mod trig;

pub use arena::{Arena, MemoryStats, SymError};
pub use build::RuleSet;
pub use node::{ChildIter, Id, SymId, SymKind, Symbol, View};
pub use num::Num;
pub use sexpr::{Display, SExpr};
