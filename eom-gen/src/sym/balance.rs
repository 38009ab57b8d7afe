//! Sums rebuilt as trees of least depth after lowering.
//!
//! Lowering writes a sum of n terms as a chain `((t₁ + t₂) + t₃) + …`, so
//! its result waits for n − 1 additions one after the other, and IEEE
//! arithmetic forbids the compiler to reassociate it. The dynamics are
//! made of such sums inside recursions (the articulated inertias and bias
//! forces of one body wait for the next body's), so one state's forward
//! dynamics is bound by the latency of its longest chain rather than by
//! the number of its operations (issue #28).
//!
//! This pass rebuilds every sum tree of the program (as
//! [`Program::factor_sums`] sees them: additions, subtractions and
//! negations whose intermediate results are read only inside the tree) in
//! the way of Huffman's construction: the two terms that are ready first
//! are combined, their sum joins the others with its own ready time, until
//! one is left. Ready times come from a latency model of the operations
//! (cycles of a current x86-64 core; only their ratios matter), taken
//! along the program as rebuilt so far. For terms all ready at once the
//! tree is balanced (depth ⌈log₂ n⌉); a term that comes late (the child
//! body's contribution) is added last, after the others have been summed
//! while it was computed.
//!
//! Signs travel with the terms: two terms of one sign are added, terms of
//! opposite signs subtracted, so the number of additions and subtractions
//! is the tree's own and a negation read only by the tree is absorbed
//! (one operation fewer); a negation remains only where every term is
//! negative. Exact over the reals; the rounding is that of another order
//! of summation (pairwise summation's error bound is the smaller).
//! Deterministic: ties go to the term met first.

use super::factor::{SumTrees, Term};
use super::program::{Instr, Op, Operand, Program};
use rustc_hash::FxHashMap;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Latency of `op` in cycles (a model: additions and multiplications 3,
/// divisions 13, square roots 20, library functions 40).
pub(super) fn latency(op: &Op) -> u32 {
    match op {
        Op::Add(..) | Op::Sub(..) | Op::Mul(..) => 3,
        Op::Neg(_) | Op::Abs(_) => 1,
        Op::Select(..) => 2,
        Op::Div(..) => 13,
        Op::Sqrt(_) => 20,
        Op::Sin(_)
        | Op::Cos(_)
        | Op::SinCos(_)
        | Op::Tan(_)
        | Op::Atan2(..)
        | Op::Exp(_)
        | Op::Ln(_) => 40,
    }
}

impl Program {
    /// The length of the program's longest chain of dependent operations
    /// under the latency model of this module (cycles): what one call
    /// takes at least, however wide the machine.
    pub fn critical_path(&self) -> u32 {
        let mut ready = vec![0u32; self.n_tmps as usize + 2];
        let mut longest = 0;
        for ins in &self.instrs {
            let r = ins.op.operands().map(|o| at(&ready, o)).max().unwrap_or(0) + latency(&ins.op);
            ready[ins.dst as usize] = r;
            ready[ins.dst as usize + 1] = r;
            longest = longest.max(r);
        }
        longest
    }

    /// Rebuilds every sum tree as a tree of least completion time (see the
    /// module comment), then removes what the old trees leave unused.
    /// Returns the number of trees rebuilt.
    pub fn balance_sums(&mut self) -> usize {
        let trees = SumTrees::of(self);
        let mut ready = vec![0u32; self.n_tmps as usize + 1];
        let mut out: Vec<Instr> = Vec::with_capacity(self.instrs.len());
        let mut next = self.n_tmps;
        let mut rebuilt = 0;
        for ins in &self.instrs {
            if !trees.is_root(ins) {
                push(&mut out, &mut ready, *ins);
                continue;
            }
            let terms = trees.terms(ins.dst);
            // A tree of one operation stays as it is, unless it reads a
            // negation the rebuilt tree absorbs.
            let inner = ins
                .op
                .operands()
                .any(|o| trees.single(o) && trees.is_sum(o));
            if terms.len() < 2 || (terms.len() == 2 && !inner) {
                push(&mut out, &mut ready, *ins);
                continue;
            }
            rebuilt += 1;
            let items: Vec<(u32, Term)> = terms.iter().map(|t| (at(&ready, t.value), *t)).collect();
            earliest_first(&items, |a, b, last| {
                let (op, neg) = match (a.neg, b.neg) {
                    (false, true) => (Op::Sub(a.value, b.value), false),
                    (true, false) => (Op::Sub(b.value, a.value), false),
                    (n, _) => (Op::Add(a.value, b.value), n),
                };
                if last && !neg {
                    push(&mut out, &mut ready, Instr { dst: ins.dst, op });
                    return None;
                }
                let dst = next;
                next += 1;
                push(&mut out, &mut ready, Instr { dst, op });
                let value = Operand::Tmp(dst);
                if last {
                    // Every term negative: the sum of their magnitudes, negated.
                    let op = Op::Neg(value);
                    push(&mut out, &mut ready, Instr { dst: ins.dst, op });
                    return None;
                }
                Some((at(&ready, value), Term { neg, value }))
            });
        }
        self.instrs = place_early(out, self.n_tmps);
        self.n_tmps = next;
        self.remove_dead();
        rebuilt
    }

    /// Rebuilds every product tree (multiplications whose intermediate
    /// results are read only by the tree's next multiplication) the same
    /// way: the two factors ready first are multiplied first. Returns the
    /// number of trees rebuilt.
    pub fn balance_products(&mut self) -> usize {
        let n = self.n_tmps as usize + 1;
        let mut uses = vec![0usize; n];
        for ins in &self.instrs {
            for o in ins.op.operands() {
                if let Operand::Tmp(t) = o {
                    uses[t as usize] += 1;
                }
            }
        }
        for (_, o) in &self.outputs {
            if let Operand::Tmp(t) = o {
                uses[*t as usize] += 2;
            }
        }
        let mut def: Vec<Option<Op>> = vec![None; n];
        for ins in &self.instrs {
            def[ins.dst as usize] = Some(ins.op);
        }
        let inner = |o: Operand| match o {
            Operand::Tmp(t) => {
                uses[t as usize] == 1 && matches!(def[t as usize], Some(Op::Mul(..)))
            }
            _ => false,
        };
        let mut folded = vec![false; n];
        for ins in &self.instrs {
            if let Op::Mul(a, b) = ins.op {
                for o in [a, b] {
                    if let Operand::Tmp(t) = o
                        && inner(o)
                    {
                        folded[t as usize] = true;
                    }
                }
            }
        }
        let mut ready = vec![0u32; n];
        let mut out: Vec<Instr> = Vec::with_capacity(self.instrs.len());
        let mut next = self.n_tmps;
        let mut rebuilt = 0;
        for ins in &self.instrs {
            let Op::Mul(a, b) = ins.op else {
                push(&mut out, &mut ready, *ins);
                continue;
            };
            if folded[ins.dst as usize] || !(inner(a) || inner(b)) {
                push(&mut out, &mut ready, *ins);
                continue;
            }
            let mut factors = Vec::new();
            let mut stack = vec![b, a];
            while let Some(o) = stack.pop() {
                match o {
                    Operand::Tmp(t) if inner(o) => {
                        let Some(Op::Mul(x, y)) = def[t as usize] else {
                            unreachable!("an inner factor is a multiplication")
                        };
                        stack.push(y);
                        stack.push(x);
                    }
                    _ => factors.push(o),
                }
            }
            rebuilt += 1;
            let items: Vec<(u32, Operand)> = factors.iter().map(|&f| (at(&ready, f), f)).collect();
            earliest_first(&items, |x, y, last| {
                let op = Op::Mul(x, y);
                if last {
                    push(&mut out, &mut ready, Instr { dst: ins.dst, op });
                    return None;
                }
                let dst = next;
                next += 1;
                push(&mut out, &mut ready, Instr { dst, op });
                let value = Operand::Tmp(dst);
                Some((at(&ready, value), value))
            });
        }
        self.instrs = place_early(out, self.n_tmps);
        self.n_tmps = next;
        self.remove_dead();
        rebuilt
    }
}

/// Huffman's construction on ready times: `items` (ready time, item) are
/// joined two at a time, the two ready first (ties: the one met first),
/// by `join(a, b, last)`, which emits the operation and returns the new
/// item with its ready time, or `None` for the last join (`last`: no
/// other item is left). Needs two or more items.
fn earliest_first<T: Copy>(
    items: &[(u32, T)],
    mut join: impl FnMut(T, T, bool) -> Option<(u32, T)>,
) {
    let mut heap: BinaryHeap<Reverse<(u32, usize)>> = BinaryHeap::new();
    let mut pending: Vec<T> = Vec::with_capacity(2 * items.len());
    for &(r, x) in items {
        heap.push(Reverse((r, pending.len())));
        pending.push(x);
    }
    while let (Some(Reverse((_, i))), Some(Reverse((_, j)))) = (heap.pop(), heap.pop()) {
        let Some((r, x)) = join(pending[i], pending[j], heap.is_empty()) else {
            return;
        };
        heap.push(Reverse((r, pending.len())));
        pending.push(x);
    }
}

/// The instructions with those written by a rebuild (temporaries from
/// `first_new` on) moved up to just after their operands are defined, in
/// dependency order: a rebuilt tree is computed where the chain it
/// replaces was, so a term read across the parts of a long function
/// (`emit::lower`) is not kept alive until the tree's root.
fn place_early(instrs: Vec<Instr>, first_new: u32) -> Vec<Instr> {
    // (position, depth among moved instructions) of each temporary's definition.
    let mut key_of: FxHashMap<u32, (usize, u32)> = FxHashMap::default();
    let mut keys = Vec::with_capacity(instrs.len());
    for (k, ins) in instrs.iter().enumerate() {
        let key = if ins.dst >= first_new {
            ins.op
                .operands()
                .filter_map(|o| match o {
                    Operand::Tmp(t) => key_of.get(&t).copied(),
                    _ => None,
                })
                .fold((0, 1), |(p, d), (q, e)| (p.max(q), d.max(e + 1)))
        } else {
            (k, 0)
        };
        key_of.insert(ins.dst, key);
        if matches!(ins.op, Op::SinCos(_)) {
            key_of.insert(ins.dst + 1, key);
        }
        keys.push((key, k));
    }
    let mut order: Vec<usize> = (0..instrs.len()).collect();
    order.sort_by_key(|&k| keys[k]);
    order.into_iter().map(|k| instrs[k]).collect()
}

/// When `o` is ready (0 for inputs and constants).
pub(super) fn at(ready: &[u32], o: Operand) -> u32 {
    match o {
        Operand::Tmp(t) => ready.get(t as usize).copied().unwrap_or(0),
        _ => 0,
    }
}

/// Appends `ins` to `out` and records when its result is ready.
fn push(out: &mut Vec<Instr>, ready: &mut Vec<u32>, ins: Instr) {
    let r = ins.op.operands().map(|o| at(ready, o)).max().unwrap_or(0) + latency(&ins.op);
    let d = ins.dst as usize;
    if ready.len() < d + 2 {
        ready.resize(d + 2, 0);
    }
    ready[d] = r;
    if matches!(ins.op, Op::SinCos(_)) {
        ready[d + 1] = r;
    }
    out.push(ins);
}
