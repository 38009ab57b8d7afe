//! Lowering to a [`Program`]: straight-line SSA with common subexpressions
//! computed once, dead code removed and operations counted.
//!
//! Lowering walks the nodes reachable from all outputs together in
//! ascending id order (children first), so hash-consing already shares
//! every equal subexpression across outputs; a value-numbering table on the
//! emitted instructions additionally shares the partial sums and products
//! that n-ary nodes expand into (`x·y` inside `x·y·z` and `2·x·y`). Sums
//! become chains of `+` and `−` (terms with a negative coefficient are
//! subtracted), products split into numerator and denominator with a single
//! division, integer powers use square-and-multiply, and `sin x`/`cos x` of
//! one argument that are both needed become one `SinCos` instruction.
//!
//! Two further rounds work on the program:
//! - [`Program::optimize`] (on by default): constant propagation, algebraic
//!   identities (`x − x = 0`, `x·1`, `x·0`, …), value numbering with
//!   canonical operand order, and dead-code elimination, repeated until
//!   nothing changes. It catches temporaries that become constant only once
//!   common subexpressions are named. With it, shared divisors become one
//!   reciprocal ([`Program::share_reciprocals`]) and common factors leave
//!   sums (`a·x + a·y → a·(x + y)`, [`Program::factor_sums`]) while that
//!   lowers the count.
//! - [`Program::resimplify`] (opt-in, `LowerOptions::second_round`): read the
//!   program back into a fresh arena, so every assignment is canonicalised by
//!   the smart constructors with its operands named, and lower again.

use super::arena::Arena;
use super::node::{Id, SymId, Symbol, View};
use super::num::Num;
use rustc_hash::{FxHashMap, FxHashSet};
use std::fmt;

/// An instruction operand.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Operand {
    /// A constant.
    Const(Num),
    /// Program input `i` (see [`Program::inputs`]).
    Var(u32),
    /// Temporary `i`, assigned by an earlier instruction.
    Tmp(u32),
}

/// An operation; its result goes to the instruction's `dst` temporary.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum Op {
    /// `a + b`
    Add(Operand, Operand),
    /// `a - b`
    Sub(Operand, Operand),
    /// `a * b`
    Mul(Operand, Operand),
    /// `a / b`
    Div(Operand, Operand),
    /// `-a`
    Neg(Operand),
    /// `sqrt(a)`
    Sqrt(Operand),
    /// `sin(a)`
    Sin(Operand),
    /// `cos(a)`
    Cos(Operand),
    /// `sin(a)` into `dst` and `cos(a)` into `dst + 1`, computed together.
    SinCos(Operand),
    /// `tan(a)`
    Tan(Operand),
    /// `atan2(y, x)`
    Atan2(Operand, Operand),
    /// `exp(a)`
    Exp(Operand),
    /// `ln(a)`
    Ln(Operand),
    /// `|a|`
    Abs(Operand),
    /// `if c > 0 { a } else { b }`
    Select(Operand, Operand, Operand),
}

impl Op {
    /// The operands read, in order.
    pub fn operands(&self) -> impl Iterator<Item = Operand> {
        let v: [Option<Operand>; 3] = match *self {
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) | Op::Atan2(a, b) => {
                [Some(a), Some(b), None]
            }
            Op::Neg(a)
            | Op::Sqrt(a)
            | Op::Sin(a)
            | Op::Cos(a)
            | Op::SinCos(a)
            | Op::Tan(a)
            | Op::Exp(a)
            | Op::Ln(a)
            | Op::Abs(a) => [Some(a), None, None],
            Op::Select(c, a, b) => [Some(c), Some(a), Some(b)],
        };
        v.into_iter().flatten()
    }

    /// The same operation on `f` of each operand.
    pub fn map(self, f: impl Fn(Operand) -> Operand) -> Op {
        match self {
            Op::Add(a, b) => Op::Add(f(a), f(b)),
            Op::Sub(a, b) => Op::Sub(f(a), f(b)),
            Op::Mul(a, b) => Op::Mul(f(a), f(b)),
            Op::Div(a, b) => Op::Div(f(a), f(b)),
            Op::Atan2(a, b) => Op::Atan2(f(a), f(b)),
            Op::Neg(a) => Op::Neg(f(a)),
            Op::Sqrt(a) => Op::Sqrt(f(a)),
            Op::Sin(a) => Op::Sin(f(a)),
            Op::Cos(a) => Op::Cos(f(a)),
            Op::SinCos(a) => Op::SinCos(f(a)),
            Op::Tan(a) => Op::Tan(f(a)),
            Op::Exp(a) => Op::Exp(f(a)),
            Op::Ln(a) => Op::Ln(f(a)),
            Op::Abs(a) => Op::Abs(f(a)),
            Op::Select(c, a, b) => Op::Select(f(c), f(a), f(b)),
        }
    }

    /// Number of temporaries written (2 for `SinCos`).
    pub fn results(&self) -> u32 {
        if matches!(self, Op::SinCos(_)) { 2 } else { 1 }
    }
}

/// One assignment `dst = op`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Instr {
    /// The temporary assigned (and `dst + 1` for `SinCos`).
    pub dst: u32,
    /// What is computed.
    pub op: Op,
}

/// Operation counts of a program. A `SinCos` counts as one trig operation.
#[derive(Clone, Copy, PartialEq, Eq, Default, Debug)]
pub struct OpCount {
    /// Additions and subtractions.
    pub adds: usize,
    /// Multiplications.
    pub muls: usize,
    /// Divisions.
    pub divs: usize,
    /// Negations.
    pub negs: usize,
    /// Square roots.
    pub sqrts: usize,
    /// sin, cos, sin_cos, tan, atan2.
    pub trig: usize,
    /// exp, ln, abs, select.
    pub other: usize,
}

impl OpCount {
    /// Sum of all counts.
    pub fn total(&self) -> usize {
        self.adds + self.muls + self.divs + self.negs + self.sqrts + self.trig + self.other
    }
}

impl fmt::Display for OpCount {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ops: {} add, {} mul, {} div, {} neg, {} sqrt, {} trig, {} other",
            self.total(),
            self.adds,
            self.muls,
            self.divs,
            self.negs,
            self.sqrts,
            self.trig,
            self.other
        )
    }
}

/// A dense matrix product applied to a program's outputs after its
/// instructions, in place: each block of outputs `B` (`n × cols`,
/// row-major) becomes `−A B`, `A` the `n × n` block of outputs from `a`.
///
/// This is `∂u̇/∂x = −M⁻¹ ∂ID/∂x` of the derivatives (`B` the gradients
/// with respect to `q`, `u` and the inputs): written as straight-line
/// scalar code the product costs `2 n² cols` operations one at a time; as
/// loops along the rows of the blocks it runs in SIMD lanes
/// (two to eight per instruction, as the target allows). Each entry is summed in the order
/// of `k`, one product subtracted at a time from zero, in the interpreter
/// ([`Program::eval`]) and in generated code alike.
#[derive(Clone, PartialEq, Eq, Debug)]
pub struct Product {
    /// First output of `A` (`n × n`, row-major).
    pub a: usize,
    /// Rows and columns of `A`.
    pub n: usize,
    /// The blocks `B`: first output and number of columns of each.
    pub blocks: Vec<(usize, usize)>,
}

impl Product {
    /// Columns of all blocks side by side.
    pub fn width(&self) -> usize {
        self.blocks.iter().map(|&(_, c)| c).sum()
    }

    /// `2 n² width`: a multiplication and a subtraction per term.
    pub fn op_count(&self) -> usize {
        2 * self.n * self.n * self.width()
    }

    /// Where entry `(k, j)` of the blocks side by side is among the
    /// outputs.
    pub fn b_index(&self, k: usize, mut j: usize) -> usize {
        for &(start, cols) in &self.blocks {
            if j < cols {
                return start + k * cols + j;
            }
            j -= cols;
        }
        usize::MAX
    }

    /// Applies the product to `out`, the program's outputs. A product
    /// is built with its program and never reaches past its outputs
    /// (`Program::products`); `out` shorter than that is an internal
    /// error, caught in debug builds and left unchanged in release.
    pub fn apply(&self, out: &mut [f64]) {
        let (n, w) = (self.n, self.width());
        let fits = self.a + n * n <= out.len()
            && self
                .blocks
                .iter()
                .all(|&(start, cols)| start + n * cols <= out.len());
        debug_assert!(fits, "a product past its program's outputs");
        if !fits {
            return;
        }
        // `A` and `B` are read whole before any row of `B` is overwritten.
        let a = out[self.a..self.a + n * n].to_vec();
        let b: Vec<f64> = (0..n * w)
            .map(|i| out[self.b_index(i / w, i % w)])
            .collect();
        let mut row = vec![0.0; w];
        for i in 0..n {
            row.fill(0.0);
            for k in 0..n {
                let m = a[i * n + k];
                for (r, x) in row.iter_mut().zip(&b[k * w..(k + 1) * w]) {
                    *r -= m * x;
                }
            }
            for (j, &r) in row.iter().enumerate() {
                out[self.b_index(i, j)] = r;
            }
        }
    }
}

/// A straight-line program: inputs, SSA assignments in dependency order,
/// named outputs.
#[derive(Clone, PartialEq, Debug)]
pub struct Program {
    /// The variables read, sorted by kind then name; `Operand::Var(i)` is `inputs[i]`.
    pub inputs: Vec<Symbol>,
    /// Assignments; every operand is an input, a constant or an earlier temporary.
    pub instrs: Vec<Instr>,
    /// Output names and values, in the order asked for.
    pub outputs: Vec<(String, Operand)>,
    /// Number of temporaries (`dst` values are `0..n_tmps`).
    pub n_tmps: u32,
    /// Dense products applied to the outputs after the instructions, in
    /// order (see [`Product`]); empty for most programs.
    pub products: Vec<Product>,
}

/// One instruction of a [`Tape`]: the destination, then the operands,
/// as indices into the tape's values.
#[derive(Clone, Copy, Debug)]
enum Step {
    Add(u32, u32, u32),
    Sub(u32, u32, u32),
    Mul(u32, u32, u32),
    Div(u32, u32, u32),
    Neg(u32, u32),
    Sqrt(u32, u32),
    Sin(u32, u32),
    Cos(u32, u32),
    /// `sin` into the destination, `cos` into the next value.
    SinCos(u32, u32),
    Tan(u32, u32),
    Atan2(u32, u32, u32),
    Exp(u32, u32),
    Ln(u32, u32),
    Abs(u32, u32),
    Select(u32, u32, u32, u32),
}

/// A [`Program`] flattened for repeated evaluation ([`Program::tape`]):
/// the interpreter builds one per function once and runs it at every
/// call, instead of matching operands and converting constants per
/// instruction.
#[derive(Clone, Debug)]
pub struct Tape {
    steps: Vec<Step>,
    n_inputs: usize,
    /// Index of the first constant among the values: inputs, then
    /// temporaries, then constants.
    first_const: usize,
    consts: Vec<f64>,
    outputs: Vec<u32>,
    products: Vec<Product>,
}

impl Tape {
    /// Run the program; `inputs[i]` is the value of input `i` (missing
    /// ones are NaN). Returns the outputs in order.
    pub fn eval(&self, inputs: &[f64]) -> Vec<f64> {
        let mut v = vec![0.0; self.first_const + self.consts.len()];
        for (d, s) in v[..self.n_inputs]
            .iter_mut()
            .zip(inputs.iter().chain(std::iter::repeat(&f64::NAN)))
        {
            *d = *s;
        }
        v[self.first_const..].copy_from_slice(&self.consts);
        for &st in &self.steps {
            match st {
                Step::Add(d, a, b) => v[d as usize] = v[a as usize] + v[b as usize],
                Step::Sub(d, a, b) => v[d as usize] = v[a as usize] - v[b as usize],
                Step::Mul(d, a, b) => v[d as usize] = v[a as usize] * v[b as usize],
                Step::Div(d, a, b) => v[d as usize] = v[a as usize] / v[b as usize],
                Step::Neg(d, a) => v[d as usize] = -v[a as usize],
                Step::Sqrt(d, a) => v[d as usize] = v[a as usize].sqrt(),
                Step::Sin(d, a) => v[d as usize] = v[a as usize].sin(),
                Step::Cos(d, a) => v[d as usize] = v[a as usize].cos(),
                Step::SinCos(d, a) => {
                    let (s, c) = v[a as usize].sin_cos();
                    v[d as usize] = s;
                    v[d as usize + 1] = c;
                }
                Step::Tan(d, a) => v[d as usize] = v[a as usize].tan(),
                Step::Atan2(d, y, x) => v[d as usize] = v[y as usize].atan2(v[x as usize]),
                Step::Exp(d, a) => v[d as usize] = v[a as usize].exp(),
                Step::Ln(d, a) => v[d as usize] = v[a as usize].ln(),
                Step::Abs(d, a) => v[d as usize] = v[a as usize].abs(),
                Step::Select(d, c, a, b) => {
                    v[d as usize] =
                        super::eval::ops::select(v[c as usize], v[a as usize], v[b as usize])
                }
            }
        }
        let mut out: Vec<f64> = self.outputs.iter().map(|&i| v[i as usize]).collect();
        for p in &self.products {
            p.apply(&mut out);
        }
        out
    }
}

impl Program {
    /// True if a constant operand is infinite or NaN: the program divides
    /// by a structural zero (or overflows) for every value of its inputs.
    pub fn has_non_finite_constant(&self) -> bool {
        let bad = |o: Operand| matches!(o, Operand::Const(n) if !n.to_f64().is_finite());
        self.instrs.iter().any(|i| i.op.operands().any(bad))
            || self.outputs.iter().any(|(_, o)| bad(*o))
    }
}

/// Options for [`Arena::lower`].
#[derive(Clone, Copy, Debug)]
pub struct LowerOptions {
    /// Share common subexpressions (off expands the DAG into a tree: only for
    /// testing, exponential on deep DAGs).
    pub cse: bool,
    /// Run [`Program::optimize`] afterwards.
    pub optimize: bool,
    /// Then also try [`Program::resimplify`] and keep its result if it has
    /// fewer operations. Off by default: on graphs built with every rule on,
    /// the benchmarks found nothing for it to remove (see BENCHMARKS.md),
    /// while it doubles lowering time; it pays off on graphs built raw or
    /// with fewer rules.
    pub second_round: bool,
    /// With `optimize`, rebuild sums and products as trees of least
    /// latency ([`Program::balance_sums`]): what one call at a time waits
    /// on. Off for code that only runs in lanes and is bound by throughput
    /// (the ANCF element kernels), where the wider trees keep more values
    /// live and cost spills (BENCHMARKS.md, "Sums as trees").
    pub balance: bool,
}

impl Default for LowerOptions {
    fn default() -> Self {
        LowerOptions {
            cse: true,
            optimize: true,
            second_round: false,
            balance: true,
        }
    }
}

impl LowerOptions {
    /// No CSE, no optimisation: the tree as written (for tests).
    pub const PLAIN: LowerOptions = LowerOptions {
        cse: false,
        optimize: false,
        second_round: false,
        balance: false,
    };
}

struct Lowerer<'a> {
    arena: &'a Arena,
    cse: bool,
    /// Operand of each lowered node, indexed by id.
    memo: Vec<Option<Operand>>,
    vn: FxHashMap<Op, Operand>,
    instrs: Vec<Instr>,
    next: u32,
    input_of: FxHashMap<SymId, u32>,
    /// Is the node (by id) reachable from the outputs?
    reach: Vec<bool>,
    /// Negative powers that are factors of two or more reachable products:
    /// computed once as reciprocals and multiplied first.
    shared_recip: FxHashSet<Id>,
}

fn commutative_key(o: &Operand) -> (u8, u64) {
    match *o {
        Operand::Const(n) => (0, n.to_f64().to_bits()),
        Operand::Var(i) => (1, i as u64),
        Operand::Tmp(i) => (2, i as u64),
    }
}

/// Put the operands of `+` and `*` in a canonical order.
fn canonical(op: Op) -> Op {
    match op {
        Op::Add(a, b) if commutative_key(&b) < commutative_key(&a) => Op::Add(b, a),
        Op::Mul(a, b) if commutative_key(&b) < commutative_key(&a) => Op::Mul(b, a),
        _ => op,
    }
}

impl Lowerer<'_> {
    fn emit(&mut self, op: Op) -> Operand {
        let op = canonical(op);
        if self.cse
            && let Some(&o) = self.vn.get(&op)
        {
            return o;
        }
        let dst = self.next;
        self.next += op.results();
        self.instrs.push(Instr { dst, op });
        let o = Operand::Tmp(dst);
        if self.cse {
            self.vn.insert(op, o);
        }
        o
    }

    fn mul_opt(&mut self, acc: Option<Operand>, x: Operand) -> Option<Operand> {
        Some(match acc {
            None => x,
            Some(a) => self.emit(Op::Mul(a, x)),
        })
    }

    /// `x^n` for `n >= 1` by square-and-multiply.
    fn powi(&mut self, x: Operand, n: u32) -> Operand {
        let mut acc: Option<Operand> = None;
        let mut base = x;
        let mut e = n;
        loop {
            if e & 1 == 1 {
                acc = self.mul_opt(acc, base);
            }
            e >>= 1;
            if e == 0 {
                break;
            }
            base = self.emit(Op::Mul(base, base));
        }
        acc.expect("n >= 1")
    }

    /// `coef · Π factors`, numerator and denominator apart.
    fn product(&mut self, coef: Num, factors: &[Id]) -> Operand {
        let mut coef = coef;
        let mut numer: Option<Operand> = None;
        let mut denom: Option<Operand> = None;
        // A reciprocal shared with other products leads the chain, so the
        // partial products `(1/d)·x` are shared too: the entries
        // `uᵢ uⱼ / D` of a rank-one update cost one multiplication each
        // after the six `uᵢ / D`, not two.
        for &f in factors {
            if self.shared_recip.contains(&f) {
                let o = self.node(f);
                numer = self.mul_opt(numer, o);
            }
        }
        for &f in factors {
            match self.arena.view(f) {
                _ if self.shared_recip.contains(&f) => {}
                View::Pow(b, e) if e < 0 => {
                    let ob = self.node(b);
                    let p = self.powi(ob, e.unsigned_abs());
                    denom = self.mul_opt(denom, p);
                }
                _ => {
                    let o = self.node(f);
                    numer = self.mul_opt(numer, o);
                }
            }
        }
        let r = match (numer, denom) {
            (Some(n), Some(d)) => self.emit(Op::Div(n, d)),
            (Some(n), None) => n,
            (None, Some(d)) => {
                let c = std::mem::replace(&mut coef, Num::ONE);
                self.emit(Op::Div(Operand::Const(c), d))
            }
            (None, None) => return Operand::Const(coef),
        };
        if coef.is_one() {
            r
        } else if coef == Num::MINUS_ONE {
            self.emit(Op::Neg(r))
        } else {
            self.emit(Op::Mul(Operand::Const(coef), r))
        }
    }

    /// Split a product node into its leading constant and the rest.
    fn split_coef(&self, cs: &[Id]) -> (Num, usize) {
        match self.arena.num(cs[0]) {
            Some(c) => (c, 1),
            None => (Num::ONE, 0),
        }
    }

    fn node(&mut self, id: Id) -> Operand {
        if self.cse
            && let Some(o) = self.memo[id.index()]
        {
            return o;
        }
        let o = self.compute(id);
        if self.cse {
            self.memo[id.index()] = Some(o);
        }
        o
    }

    fn trig(&mut self, x: Id, is_sin: bool) -> Operand {
        let partner = if is_sin { View::Cos(x) } else { View::Sin(x) };
        let paired = self.cse
            && self
                .arena
                .lookup(&partner)
                .is_some_and(|p| self.reach[p.index()]);
        let a = self.node(x);
        if !paired {
            return self.emit(if is_sin { Op::Sin(a) } else { Op::Cos(a) });
        }
        let Operand::Tmp(t) = self.emit(Op::SinCos(a)) else {
            unreachable!("emit returns a temporary")
        };
        if let Some(p) = self.arena.lookup(&partner) {
            let (s, c) = (Operand::Tmp(t), Operand::Tmp(t + 1));
            self.memo[p.index()] = Some(if is_sin { c } else { s });
            return if is_sin { s } else { c };
        }
        unreachable!("partner checked above")
    }

    fn compute(&mut self, id: Id) -> Operand {
        match self.arena.view(id) {
            View::Num(n) => Operand::Const(n),
            View::Sym(s) => Operand::Var(self.input_of[&s]),
            View::Add(cs) => {
                let mut pos: Vec<Operand> = Vec::new();
                let mut neg: Vec<Operand> = Vec::new();
                for &c in cs {
                    match self.arena.view(c) {
                        View::Num(n) if n.is_negative() => neg.push(Operand::Const(n.negated())),
                        View::Mul(ms) if self.arena.num(ms[0]).is_some_and(|k| k.is_negative()) => {
                            let (k, skip) = self.split_coef(ms);
                            let o = self.product(k.negated(), &ms[skip..]);
                            neg.push(o);
                        }
                        _ => {
                            let o = self.node(c);
                            pos.push(o);
                        }
                    }
                }
                let sum = |l: &mut Self, xs: &[Operand]| {
                    xs[1..]
                        .iter()
                        .fold(xs[0], |acc, &x| l.emit(Op::Add(acc, x)))
                };
                if pos.is_empty() {
                    let s = sum(self, &neg);
                    return self.emit(Op::Neg(s));
                }
                let mut acc = sum(self, &pos);
                for n in neg {
                    acc = self.emit(Op::Sub(acc, n));
                }
                acc
            }
            View::Mul(cs) => {
                let (k, skip) = self.split_coef(cs);
                self.product(k, &cs[skip..])
            }
            View::Pow(b, n) => {
                if n == 0 {
                    return Operand::Const(Num::ONE);
                }
                let ob = self.node(b);
                let p = self.powi(ob, n.unsigned_abs());
                if n < 0 {
                    self.emit(Op::Div(Operand::Const(Num::ONE), p))
                } else {
                    p
                }
            }
            View::Sin(x) => self.trig(x, true),
            View::Cos(x) => self.trig(x, false),
            View::Sqrt(x) => self.unary(x, Op::Sqrt),
            View::Tan(x) => self.unary(x, Op::Tan),
            View::Exp(x) => self.unary(x, Op::Exp),
            View::Ln(x) => self.unary(x, Op::Ln),
            View::Abs(x) => self.unary(x, Op::Abs),
            View::Atan2(y, x) => {
                let (a, b) = (self.node(y), self.node(x));
                self.emit(Op::Atan2(a, b))
            }
            View::Select(c, a, b) => {
                let (c, a, b) = (self.node(c), self.node(a), self.node(b));
                self.emit(Op::Select(c, a, b))
            }
        }
    }

    fn unary(&mut self, x: Id, f: fn(Operand) -> Op) -> Operand {
        let a = self.node(x);
        self.emit(f(a))
    }
}

/// Multiplications in `x^n` by square-and-multiply.
fn powi_muls(n: u32) -> usize {
    (31 - n.leading_zeros() + n.count_ones() - 1) as usize
}

impl Arena {
    /// Estimated operation count of lowering `roots`, computed on the DAG
    /// without building a program: an n-ary sum costs n−1, a product one
    /// multiplication per extra factor plus one for a coefficient ≠ ±1 and
    /// one division for all negative powers, `x^n` square-and-multiply,
    /// every other node one; `sin x` and `cos x` of one argument count once.
    /// It ignores the sharing of partial sums and products that lowering
    /// finds, so it is an upper bound of the same shape as [`OpCount::total`].
    pub fn op_estimate(&self, roots: &[Id]) -> usize {
        let mut n = 0;
        let mut trig_args: FxHashSet<Id> = FxHashSet::default();
        for id in self.reachable(roots, |_| false) {
            n += match self.view(id) {
                View::Num(_) | View::Sym(_) => 0,
                View::Add(cs) => cs.len() - 1,
                View::Mul(cs) => {
                    let mut c = cs.len() - 1;
                    let mut div = false;
                    for &f in cs {
                        match self.view(f) {
                            View::Num(k) if k == Num::ONE || k == Num::MINUS_ONE => {
                                c = c.saturating_sub(1)
                            }
                            View::Pow(_, e) if e < 0 => div = true,
                            _ => {}
                        }
                    }
                    c + div as usize
                }
                View::Pow(_, e) => powi_muls(e.unsigned_abs().max(1)) + (e < 0) as usize,
                View::Sin(x) | View::Cos(x) => trig_args.insert(x) as usize,
                _ => 1,
            };
        }
        n
    }

    /// The negative powers among `order` that are factors of at least two
    /// products of `order`.
    fn shared_reciprocals(&self, order: &[Id]) -> FxHashSet<Id> {
        let mut seen: FxHashMap<Id, usize> = FxHashMap::default();
        for &id in order {
            if let View::Mul(cs) = self.view(id) {
                for &f in cs {
                    if matches!(self.view(f), View::Pow(_, e) if e < 0) {
                        *seen.entry(f).or_default() += 1;
                    }
                }
            }
        }
        seen.into_iter()
            .filter(|&(_, n)| n >= 2)
            .map(|(f, _)| f)
            .collect()
    }

    /// Lower named outputs to one [`Program`] (CSE across all outputs).
    pub fn lower(&self, outputs: &[(&str, Id)], opts: LowerOptions) -> Program {
        let roots: Vec<Id> = outputs.iter().map(|&(_, id)| id).collect();
        let order = self.reachable(&roots, |_| false);
        let mut syms: Vec<SymId> = order.iter().filter_map(|&id| self.as_sym(id)).collect();
        syms.sort_by(|&a, &b| {
            let (sa, sb) = (self.symbol(a), self.symbol(b));
            (sa.kind, &sa.name).cmp(&(sb.kind, &sb.name))
        });
        let mut l = Lowerer {
            arena: self,
            cse: opts.cse,
            memo: vec![None; self.len()],
            vn: FxHashMap::default(),
            instrs: Vec::new(),
            next: 0,
            input_of: syms
                .iter()
                .enumerate()
                .map(|(i, &s)| (s, i as u32))
                .collect(),
            reach: {
                let mut r = vec![false; self.len()];
                for &id in &order {
                    r[id.index()] = true;
                }
                r
            },
            shared_recip: if opts.cse {
                self.shared_reciprocals(&order)
            } else {
                FxHashSet::default()
            },
        };
        if opts.cse {
            for &id in &order {
                l.node(id);
            }
        }
        let outs: Vec<(String, Operand)> = outputs
            .iter()
            .map(|&(name, id)| (name.to_string(), l.node(id)))
            .collect();
        let mut p = Program {
            inputs: syms.iter().map(|&s| self.symbol(s).clone()).collect(),
            instrs: l.instrs,
            outputs: outs,
            n_tmps: l.next,
            products: Vec::new(),
        };
        if opts.optimize {
            p.optimize();
            p.share_reciprocals();
            // `x·c² + y·s² → x + (y − x)·s²`, kept if it pays.
            p = p.with_pythagoras();
            // Common factors out of sums, kept while they pay.
            p = p.factored(false);
            // Sums as trees of least latency: same operations, shorter chains.
            if opts.balance {
                p.balance_products();
                p.balance_sums();
                p.optimize();
                // Balanced sums hold pairs with a common factor that the
                // factoring above left apart (arm7: `0.6·x − 0.6·y`, read
                // by three sums, where `y − x` is computed elsewhere):
                // factor again, balance again, while it pays (arm7's
                // forward dynamics 1 175 → 1 151 operations).
                p = p.factored(true);
            }
        } else {
            p.remove_dead();
        }
        if opts.second_round {
            let q = p.resimplify();
            if q.op_count().total() < p.op_count().total() {
                return q;
            }
        }
        p
    }
}

/// Fold an operation on constants; `None` unless the result is finite.
fn fold(op: &Op) -> Option<Num> {
    let c = |o: &Operand| match o {
        Operand::Const(n) => Some(*n),
        _ => None,
    };
    match *op {
        Op::Add(a, b) => c(&a)?.checked_add(c(&b)?),
        Op::Sub(a, b) => c(&a)?.checked_add(c(&b)?.negated()),
        Op::Mul(a, b) => c(&a)?.checked_mul(c(&b)?),
        Op::Div(a, b) => c(&a)?.checked_mul(c(&b)?.recip()?),
        Op::Neg(a) => Some(c(&a)?.negated()),
        Op::Sqrt(a) => c(&a)?.sqrt(),
        Op::Sin(a) => c(&a)?.map(f64::sin),
        Op::Cos(a) => c(&a)?.map(f64::cos),
        Op::Tan(a) => c(&a)?.map(f64::tan),
        Op::Exp(a) => c(&a)?.map(f64::exp),
        Op::Ln(a) => c(&a)?.map(f64::ln),
        Op::Abs(a) => c(&a)?.map(f64::abs),
        Op::Atan2(y, x) => {
            let x = c(&x)?.to_f64();
            c(&y)?.map(|y| y.atan2(x))
        }
        Op::SinCos(_) | Op::Select(..) => None,
    }
}

impl Program {
    /// Second round: constant propagation, identities, value numbering and
    /// dead-code elimination until nothing changes. Returns the number of
    /// instructions removed.
    ///
    /// Identities used: `x ± 0 = x`, `0 − x = −x`, `x − x = 0`, `x·1 = x`,
    /// `x·(−1) = −x`, `x·0 = 0` (assumes x finite), `x/1 = x`, `−(−x) = x`,
    /// `select(c, a, a) = a`.
    pub fn optimize(&mut self) -> usize {
        let before = self.instrs.len();
        for _ in 0..8 {
            let changed = self.propagate();
            self.remove_dead();
            if !changed {
                break;
            }
        }
        before - self.instrs.len()
    }

    /// One forward pass; returns whether any instruction was replaced.
    fn propagate(&mut self) -> bool {
        let n = self.n_tmps as usize;
        let mut subst: Vec<Option<Operand>> = vec![None; n];
        let mut vn: FxHashMap<Op, Operand> = FxHashMap::default();
        vn.reserve(self.instrs.len());
        let mut negs: Vec<Option<Operand>> = vec![None; n];
        let mut changed = false;
        let mut out = Vec::with_capacity(self.instrs.len());
        let zero = Operand::Const(Num::ZERO);
        let one = Operand::Const(Num::ONE);
        for ins in &self.instrs {
            let op = canonical(ins.op.map(|o| match o {
                Operand::Tmp(t) => subst[t as usize].unwrap_or(o),
                _ => o,
            }));
            let simpler: Option<Operand> = fold(&op).map(Operand::Const).or_else(|| match op {
                Op::Add(a, b) if a == zero => Some(b),
                Op::Add(a, b) if b == zero => Some(a),
                Op::Sub(a, b) if b == zero => Some(a),
                Op::Sub(a, b) if a == b => Some(zero),
                Op::Mul(a, b) if a == one => Some(b),
                Op::Mul(a, b) if b == one => Some(a),
                Op::Mul(a, b) if a == zero || b == zero => Some(zero),
                Op::Div(a, b) if b == one => Some(a),
                Op::Neg(Operand::Tmp(t)) => negs[t as usize],
                Op::Select(_, a, b) if a == b => Some(a),
                _ => None,
            });
            if let Some(s) = simpler {
                subst[ins.dst as usize] = Some(s);
                changed = true;
                continue;
            }
            // A negated operand folds into the operation (exact in IEEE
            // arithmetic, so the results are unchanged bit for bit).
            let negated = |o: Operand| match o {
                Operand::Tmp(t) => negs[t as usize],
                _ => None,
            };
            let op = match op {
                Op::Add(a, b) => match (negated(a), negated(b)) {
                    (_, Some(nb)) => Op::Sub(a, nb),
                    (Some(na), None) => Op::Sub(b, na),
                    (None, None) => op,
                },
                Op::Sub(a, b) => negated(b).map_or(op, |nb| Op::Add(a, nb)),
                Op::Mul(Operand::Const(k), b) => {
                    negated(b).map_or(op, |nb| Op::Mul(Operand::Const(k.negated()), nb))
                }
                _ => op,
            };
            let op = canonical(op);
            let op = match op {
                Op::Sub(a, b) if a == zero => Op::Neg(b),
                Op::Mul(Operand::Const(m), b) if m == Num::MINUS_ONE => Op::Neg(b),
                _ => op,
            };
            // `b − a` when `a − b` is known: its negation.
            let op = match op {
                Op::Sub(a, b) => match vn.get(&Op::Sub(b, a)) {
                    Some(&prev) => Op::Neg(prev),
                    None => op,
                },
                _ => op,
            };
            if let Op::Neg(Operand::Tmp(t)) = op
                && let Some(x) = negs[t as usize]
            {
                subst[ins.dst as usize] = Some(x);
                changed = true;
                continue;
            }
            if let Some(&prev) = vn.get(&op) {
                subst[ins.dst as usize] = Some(prev);
                if let (Op::SinCos(_), Operand::Tmp(p)) = (op, prev) {
                    subst[ins.dst as usize + 1] = Some(Operand::Tmp(p + 1));
                }
                changed = true;
                continue;
            }
            vn.insert(op, Operand::Tmp(ins.dst));
            if let Op::Neg(a) = op {
                negs[ins.dst as usize] = Some(a);
            }
            changed |= op != ins.op;
            out.push(Instr { dst: ins.dst, op });
        }
        for (_, o) in &mut self.outputs {
            if let Operand::Tmp(t) = *o
                && let Some(s) = subst[t as usize]
            {
                *o = s;
            }
        }
        self.instrs = out;
        changed
    }

    /// Divisions by one value, used at least twice, become one reciprocal
    /// and multiplications: `a/d, b/d, c/d` → `r = 1/d; a·r, b·r, c·r`. A
    /// division costs several multiplications' time (the articulated-body
    /// algorithm divides every column of `U` by the same `D`); the result
    /// differs from the quotient by at most one rounding (`a·fl(1/d)` against
    /// `fl(a/d)`). Returns the number of divisions replaced.
    pub fn share_reciprocals(&mut self) -> usize {
        let mut uses: FxHashMap<Operand, usize> = FxHashMap::default();
        for ins in &self.instrs {
            if let Op::Div(a, b) = ins.op
                && !matches!(b, Operand::Const(_))
                && a != Operand::Const(Num::ONE)
            {
                *uses.entry(b).or_default() += 1;
            }
        }
        let mut recip: FxHashMap<Operand, Operand> = FxHashMap::default();
        let mut out = Vec::with_capacity(self.instrs.len() + uses.len());
        let mut replaced = 0;
        for ins in &self.instrs {
            match ins.op {
                Op::Div(a, b)
                    if a != Operand::Const(Num::ONE) && uses.get(&b).is_some_and(|&n| n >= 2) =>
                {
                    let r = *recip.entry(b).or_insert_with(|| {
                        let t = self.n_tmps;
                        self.n_tmps += 1;
                        out.push(Instr {
                            dst: t,
                            op: Op::Div(Operand::Const(Num::ONE), b),
                        });
                        Operand::Tmp(t)
                    });
                    out.push(Instr {
                        dst: ins.dst,
                        op: Op::Mul(a, r),
                    });
                    replaced += 1;
                }
                _ => out.push(*ins),
            }
        }
        self.instrs = out;
        if replaced > 0 {
            // An existing `1/d` further down now repeats the new one.
            self.optimize();
        }
        replaced
    }

    /// Remove instructions whose results are unused, turn a `SinCos` with
    /// one used half into `Sin` or `Cos`, and renumber temporaries densely.
    pub fn remove_dead(&mut self) {
        let mut used = vec![false; self.n_tmps as usize + 1];
        for (_, o) in &self.outputs {
            if let Operand::Tmp(t) = o {
                used[*t as usize] = true;
            }
        }
        // For each kept instruction, the temporary its (first) result is read from.
        let mut keep: Vec<Option<u32>> = vec![None; self.instrs.len()];
        for (i, ins) in self.instrs.iter_mut().enumerate().rev() {
            let (s, c) = (used[ins.dst as usize], used[ins.dst as usize + 1]);
            let live = match ins.op {
                Op::SinCos(a) if s && !c => {
                    ins.op = Op::Sin(a);
                    Some(ins.dst)
                }
                Op::SinCos(a) if c && !s => {
                    ins.op = Op::Cos(a);
                    Some(ins.dst + 1)
                }
                Op::SinCos(_) if s && c => Some(ins.dst),
                _ => s.then_some(ins.dst),
            };
            if live.is_some() {
                keep[i] = live;
                for o in ins.op.operands() {
                    if let Operand::Tmp(t) = o {
                        used[t as usize] = true;
                    }
                }
            }
        }
        let mut renum: Vec<u32> = vec![u32::MAX; self.n_tmps as usize + 1];
        let mut next = 0;
        let mut out = Vec::with_capacity(self.instrs.len());
        for (ins, k) in self.instrs.iter().zip(keep) {
            let Some(from) = k else { continue };
            let op = ins.op.map(|o| match o {
                Operand::Tmp(t) => Operand::Tmp(renum[t as usize]),
                _ => o,
            });
            renum[from as usize] = next;
            if let Op::SinCos(_) = op {
                renum[ins.dst as usize + 1] = next + 1;
            }
            out.push(Instr { dst: next, op });
            next += op.results();
        }
        for (_, o) in &mut self.outputs {
            if let Operand::Tmp(t) = o {
                *o = Operand::Tmp(renum[*t as usize]);
            }
        }
        self.instrs = out;
        self.n_tmps = next;
    }

    /// This program with common factors out of its sums
    /// ([`Program::factor_sums`] and the clean-up, then balanced again if
    /// `balance`), repeated while that lowers the count, at most four
    /// rounds.
    fn factored(self, balance: bool) -> Program {
        let mut p = self;
        for _ in 0..4 {
            let mut q = p.clone();
            if q.factor_sums() == 0 {
                break;
            }
            q.optimize();
            if balance {
                q.balance_products();
                q.balance_sums();
                q.optimize();
            }
            if q.op_count().total() >= p.op_count().total() {
                break;
            }
            p = q;
        }
        p
    }

    /// This program with [`Program::pythagoras`] and the clean-up, if that
    /// has fewer operations; else itself.
    fn with_pythagoras(self) -> Program {
        let mut q = self.clone();
        if q.pythagoras() > 0 {
            q.optimize();
            if q.op_count().total() < self.op_count().total() {
                return q;
            }
        }
        self
    }

    /// Operation counts.
    pub fn op_count(&self) -> OpCount {
        let mut c = OpCount::default();
        for ins in &self.instrs {
            match ins.op {
                Op::Add(..) | Op::Sub(..) => c.adds += 1,
                Op::Mul(..) => c.muls += 1,
                Op::Div(..) => c.divs += 1,
                Op::Neg(_) => c.negs += 1,
                Op::Sqrt(_) => c.sqrts += 1,
                Op::Sin(_) | Op::Cos(_) | Op::SinCos(_) | Op::Tan(_) | Op::Atan2(..) => c.trig += 1,
                Op::Exp(_) | Op::Ln(_) | Op::Abs(_) | Op::Select(..) => c.other += 1,
            }
        }
        for p in &self.products {
            c.muls += p.op_count() / 2;
            c.adds += p.op_count() / 2;
        }
        c
    }

    /// Run the program; `inputs[i]` is the value of `self.inputs[i]`
    /// (missing ones are NaN). Returns the outputs in order. To run one
    /// program many times, flatten it once with [`Program::tape`]: the
    /// tape does the same operations in the same order (the same bits),
    /// but building it costs about as much as one run, so a one-off
    /// evaluation (`linearize`, `eval`) runs the instructions as they are.
    /// (The match below mirrors `Tape::eval`'s on purpose: making each
    /// tape step and running it here, one loop for both, measured 0.49–0.52
    /// s against 0.37–0.41 s for `linearize models/whipple.ron --sweep
    /// v=0:10:201`; BENCHMARKS.md, "The interpreter".)
    pub fn eval(&self, inputs: &[f64]) -> Vec<f64> {
        let mut t = vec![0.0; self.n_tmps as usize];
        let get = |t: &[f64], o: Operand| match o {
            Operand::Const(n) => n.to_f64(),
            Operand::Var(i) => inputs.get(i as usize).copied().unwrap_or(f64::NAN),
            Operand::Tmp(i) => t[i as usize],
        };
        for ins in &self.instrs {
            let g = |o| get(&t, o);
            let d = ins.dst as usize;
            t[d] = match ins.op {
                Op::Add(a, b) => g(a) + g(b),
                Op::Sub(a, b) => g(a) - g(b),
                Op::Mul(a, b) => g(a) * g(b),
                Op::Div(a, b) => g(a) / g(b),
                Op::Neg(a) => -g(a),
                Op::Sqrt(a) => g(a).sqrt(),
                Op::Sin(a) => g(a).sin(),
                Op::Cos(a) => g(a).cos(),
                Op::SinCos(a) => {
                    let (s, c) = g(a).sin_cos();
                    t[d + 1] = c;
                    s
                }
                Op::Tan(a) => g(a).tan(),
                Op::Atan2(y, x) => g(y).atan2(g(x)),
                Op::Exp(a) => g(a).exp(),
                Op::Ln(a) => g(a).ln(),
                Op::Abs(a) => g(a).abs(),
                Op::Select(c, a, b) => super::eval::ops::select(g(c), g(a), g(b)),
            };
        }
        let mut out: Vec<f64> = self.outputs.iter().map(|&(_, o)| get(&t, o)).collect();
        for p in &self.products {
            p.apply(&mut out);
        }
        out
    }

    /// The program flattened for repeated evaluation: every operand an
    /// index into one array of values (inputs, constants converted to
    /// `f64` once, temporaries). [`Program::eval`] runs through it, so the
    /// two give the same bits.
    pub fn tape(&self) -> Tape {
        let n_inputs = self.inputs.len();
        let first_const = n_inputs + self.n_tmps as usize;
        let mut consts = Vec::new();
        // The index of an operand's value: inputs, temporaries, constants.
        let mut s = |o: Operand| -> u32 {
            let i = match o {
                Operand::Var(i) => i as usize,
                Operand::Tmp(i) => n_inputs + i as usize,
                Operand::Const(n) => {
                    consts.push(n.to_f64());
                    first_const + consts.len() - 1
                }
            };
            i as u32
        };
        let mut steps: Vec<Step> = Vec::with_capacity(self.instrs.len());
        for ins in &self.instrs {
            let d = (n_inputs + ins.dst as usize) as u32;
            steps.push(match ins.op {
                Op::Add(a, b) => Step::Add(d, s(a), s(b)),
                Op::Sub(a, b) => Step::Sub(d, s(a), s(b)),
                Op::Mul(a, b) => Step::Mul(d, s(a), s(b)),
                Op::Div(a, b) => Step::Div(d, s(a), s(b)),
                Op::Neg(a) => Step::Neg(d, s(a)),
                Op::Sqrt(a) => Step::Sqrt(d, s(a)),
                Op::Sin(a) => Step::Sin(d, s(a)),
                Op::Cos(a) => Step::Cos(d, s(a)),
                Op::SinCos(a) => Step::SinCos(d, s(a)),
                Op::Tan(a) => Step::Tan(d, s(a)),
                Op::Atan2(y, x) => Step::Atan2(d, s(y), s(x)),
                Op::Exp(a) => Step::Exp(d, s(a)),
                Op::Ln(a) => Step::Ln(d, s(a)),
                Op::Abs(a) => Step::Abs(d, s(a)),
                Op::Select(c, a, b) => Step::Select(d, s(c), s(a), s(b)),
            });
        }
        let outputs: Vec<u32> = self.outputs.iter().map(|&(_, o)| s(o)).collect();
        Tape {
            steps,
            n_inputs,
            first_const,
            consts,
            outputs,
            products: self.products.clone(),
        }
    }

    /// Run the program with values given per arena symbol (as for
    /// [`Arena::eval`]); inputs are matched by name.
    pub fn eval_arena_values(&self, arena: &Arena, values: &[f64]) -> Vec<f64> {
        let ins: Vec<f64> = self
            .inputs
            .iter()
            .map(|s| {
                arena
                    .find_symbol(&s.name)
                    .and_then(|id| values.get(id.index()).copied())
                    .unwrap_or(f64::NAN)
            })
            .collect();
        self.eval(&ins)
    }
}

impl fmt::Display for Operand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Operand::Const(n) => write!(f, "{n}"),
            Operand::Var(i) => write!(f, "in{i}"),
            Operand::Tmp(i) => write!(f, "t{i}"),
        }
    }
}

impl fmt::Display for Program {
    /// A readable listing: inputs, one assignment per line, outputs.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("inputs:")?;
        for (i, s) in self.inputs.iter().enumerate() {
            write!(f, " in{i}={}", s.name)?;
        }
        writeln!(f)?;
        for ins in &self.instrs {
            let d = ins.dst;
            match ins.op {
                Op::Add(a, b) => writeln!(f, "t{d} = {a} + {b}"),
                Op::Sub(a, b) => writeln!(f, "t{d} = {a} - {b}"),
                Op::Mul(a, b) => writeln!(f, "t{d} = {a} * {b}"),
                Op::Div(a, b) => writeln!(f, "t{d} = {a} / {b}"),
                Op::Neg(a) => writeln!(f, "t{d} = -{a}"),
                Op::SinCos(a) => writeln!(f, "(t{d}, t{}) = sin_cos({a})", d + 1),
                Op::Atan2(y, x) => writeln!(f, "t{d} = atan2({y}, {x})"),
                Op::Select(c, a, b) => writeln!(f, "t{d} = select({c}, {a}, {b})"),
                Op::Sqrt(a) => writeln!(f, "t{d} = sqrt({a})"),
                Op::Sin(a) => writeln!(f, "t{d} = sin({a})"),
                Op::Cos(a) => writeln!(f, "t{d} = cos({a})"),
                Op::Tan(a) => writeln!(f, "t{d} = tan({a})"),
                Op::Exp(a) => writeln!(f, "t{d} = exp({a})"),
                Op::Ln(a) => writeln!(f, "t{d} = ln({a})"),
                Op::Abs(a) => writeln!(f, "t{d} = abs({a})"),
            }?;
        }
        for (name, o) in &self.outputs {
            writeln!(f, "{name} = {o}")?;
        }
        Ok(())
    }
}
