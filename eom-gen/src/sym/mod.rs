//! Symbolic engine: hash-consed expression DAG, simplification, derivatives,
//! lowering to straight-line programs, and an evaluator.
//!
//! # Pieces
//! - [`Arena`]: one per generation. Nodes ([`View`]) live in a flat vector,
//!   children before parents, addressed by `u32` [`Id`]s; structurally equal
//!   nodes are one node (hash-consing with a deterministic `FxHasher`, so
//!   ids, printed text and programs are byte-identical run to run). Leaves
//!   are constants ([`Num`]: exact small rationals or `f64`) and symbols
//!   ([`SymKind`]: parameters, inputs, `t`, `q_i`, `u_i`, `qd_i`, `ud_i`).
//! - Smart constructors (`Arena::add`, `mul`, `pow`, `sin`, …) simplify while
//!   building; the rules are a named [`RuleSet`] (the table in the `build`
//!   docs below lists each rule and what it assumes). [`Runner`] re-applies
//!   them plus named [`Rewrite`]s over a whole DAG with limits and a typed
//!   [`StopReason`].
//! - `Display`/`FromStr`: s-expressions, `(+ (* 2 (sin q1)) l)`
//!   ([`Arena::parse`], [`Arena::display`], [`SExpr`]).
//! - Derivatives: [`Arena::diff`] (memoised per node and variable),
//!   [`Arena::jacobian`], [`TimeDerivative`] (total `d/dt` along `q̇`, `u̇`);
//!   [`Arena::substitute`] replaces symbols (fixed parameters, `q̇ = u`);
//!   [`Arena::expand`] multiplies out products of sums (opt-in).
//! - [`Vec3`], [`Mat3`]: generic over [`Scalar`], with rotations from
//!   axis–angle, Euler/Bryan angles and unit quaternions; structural zeros
//!   stay exact.
//! - Lowering: [`Arena::lower`] gives a [`Program`] (SSA, CSE across all
//!   outputs, `SinCos` pairs, dead code removed, [`OpCount`]);
//!   [`Program::optimize`] is the second round (constant propagation,
//!   identities, value numbering).
//! - Evaluation: [`Arena::eval`] and [`Program::eval`], the numeric twin.
//!
//! # The scalar abstraction
//! Recursive algorithms (kinematics, Newton–Euler, ABA) are written once,
//! generic over [`Scalar`], and run on `f64` and on [`Expr`]. An `Expr<'cx>`
//! is a `Copy` handle: either a context-free constant or a node id plus a
//! `&'cx` [`Context`] that owns the arena in a `RefCell`. Operators borrow
//! the arena only inside one constructor call. Constants need no context
//! (`S::zero()`, `S::from_ratio(1, 12)`), so generic code never has to pass
//! an arena around, and `0·x`, `1·x`, `0 + x` short-cut without touching the
//! arena. The lifetime (instead of `Rc` or a thread-local) keeps several
//! generations independent and makes a handle outliving its arena a compile
//! error. Bulk work that does not need generic code uses the `&mut Arena`
//! methods on ids directly.
//!
//! # Example
//! ```
//! use eom_gen::sym::{Arena, LowerOptions};
//! let mut a = Arena::new();
//! let e = a.parse("(+ (* l (^ (sin q1) 2)) (* l (^ (cos q1) 2)))").unwrap();
//! assert_eq!(a.display(e).to_string(), "l");
//! let q1 = a.find_symbol("q1").unwrap();
//! let x = a.parse("(* l (sin q1))").unwrap();
//! let dx = a.diff(x, q1);
//! let p = a.lower(&[("x", x), ("dx", dx)], LowerOptions::default());
//! assert_eq!(p.op_count().trig, 1); // one sin_cos for both outputs
//! ```

mod arena;
mod balance;
mod build;
mod diff;
mod eval;
mod expand;
mod expr;
mod factor;
mod linalg;
mod node;
mod num;
mod program;
mod pythagoras;
mod reimport;
mod rules;
mod scalar;
mod schedule;
mod sexpr;
mod simplify;
mod subst;
mod trig;

pub use arena::{Arena, DEFAULT_FLATTEN_LIMIT, MemoryStats, SymError};
pub use diff::TimeDerivative;
pub use expand::MAX_EXPAND_POWER;
pub use expr::{Context, Expr};
pub use linalg::{Axis, Mat3, Vec3};
pub use node::{ChildIter, Id, SymId, SymKind, Symbol, View};
pub use num::Num;
pub use program::{Instr, LowerOptions, Op, OpCount, Operand, Product, Program, Tape};
pub use rules::RuleSet;
pub use scalar::Scalar;
pub use sexpr::{Display, MAX_DEPTH, SExpr};
pub use simplify::{Rewrite, Runner, SimplifyReport, StopReason, Uses, factor_common, rewrites};
