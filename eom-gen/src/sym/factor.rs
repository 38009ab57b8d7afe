//! Factoring common multipliers out of sums after lowering:
//! `a·x + a·y − a·z → a·(x + y − z)`.
//!
//! The smart constructors keep sums flat with a coefficient on every term,
//! so `0.3·(v₁ + v₂)` reaches the program as `0.3·v₁ + 0.3·v₂`: two
//! multiplications where one would do, and the sum `v₁ + v₂`, often
//! already computed elsewhere, is not shared. This pass regroups each sum
//! tree of the program (additions, subtractions and negations whose
//! intermediate results are used only inside the tree) by the factors of
//! its single-use product terms, then value numbering shares the new inner
//! sums. Exact over the reals (distributivity); the rounding differs from
//! the expanded sum by a few ulps. Deterministic: ties go to the factor
//! met first in program order.

use super::num::Num;
use super::program::{Instr, Op, Operand, Program};

/// One term of a sum tree: `sign · value`.
#[derive(Clone, Copy)]
pub(super) struct Term {
    pub(super) neg: bool,
    pub(super) value: Operand,
}

impl Program {
    /// Regroups sums by common factors of their product terms (see the
    /// module comment); returns the number of multiplications saved before
    /// the clean-up that follows ([`Program::optimize`]).
    pub fn factor_sums(&mut self) -> usize {
        let SumTrees { uses, def, folded } = SumTrees::of(self);
        let single = |o: Operand| matches!(o, Operand::Tmp(t) if uses[t as usize] == 1);
        let is_sum = |op: &Op| matches!(op, Op::Add(..) | Op::Sub(..) | Op::Neg(_));
        let mut out: Vec<Instr> = Vec::with_capacity(self.instrs.len());
        let mut saved = 0;
        for ins in &self.instrs {
            if !is_sum(&ins.op) || folded[ins.dst as usize] {
                out.push(*ins);
                continue;
            }
            let mut terms = Vec::new();
            collect(&def, &single, Operand::Tmp(ins.dst), false, &mut terms);
            match regroup(&def, &single, &terms) {
                Some((groups, rest)) => {
                    saved += groups.iter().map(|(_, g)| g.len() - 1).sum::<usize>();
                    let mut next = self.n_tmps;
                    let mut fresh = |op: Op, out: &mut Vec<Instr>| {
                        let dst = next;
                        next += 1;
                        out.push(Instr { dst, op });
                        Operand::Tmp(dst)
                    };
                    let mut all: Vec<Term> = rest;
                    for (k, g) in groups {
                        let (s, neg) = signed_sum(&g, &mut out, &mut fresh);
                        let p = fresh(Op::Mul(k, s), &mut out);
                        all.push(Term { neg, value: p });
                    }
                    // The root keeps its temporary: the last operation of
                    // the rebuilt sum is written to it.
                    let op = sum_op(&all, &mut out, &mut fresh);
                    self.n_tmps = next;
                    out.push(Instr { dst: ins.dst, op });
                }
                None => out.push(*ins),
            }
        }
        self.instrs = out;
        saved
    }
}

/// A program's sum trees: the uses of each temporary (outputs count
/// twice, so they are never folded into a tree), each temporary's
/// definition, and which sums are folded into a bigger one (not roots).
pub(super) struct SumTrees {
    pub(super) uses: Vec<usize>,
    pub(super) def: Vec<Option<Op>>,
    pub(super) folded: Vec<bool>,
}

impl SumTrees {
    pub(super) fn of(p: &Program) -> SumTrees {
        let n = p.n_tmps as usize;
        let mut uses = vec![0usize; n + 1];
        for ins in &p.instrs {
            for o in ins.op.operands() {
                if let Operand::Tmp(t) = o {
                    uses[t as usize] += 1;
                }
            }
        }
        for (_, o) in &p.outputs {
            if let Operand::Tmp(t) = o {
                // Outputs are never folded into a tree.
                uses[*t as usize] += 2;
            }
        }
        let mut def: Vec<Option<Op>> = vec![None; n + 1];
        for ins in &p.instrs {
            def[ins.dst as usize] = Some(ins.op);
        }
        let single = |o: Operand| matches!(o, Operand::Tmp(t) if uses[t as usize] == 1);
        let is_sum = |op: &Op| matches!(op, Op::Add(..) | Op::Sub(..) | Op::Neg(_));
        // A tree's root is a sum not folded into a bigger one: a sum whose
        // result is read by anything but a single-use sum context.
        let mut folded = vec![false; n + 1];
        for ins in &p.instrs {
            if is_sum(&ins.op) {
                for o in ins.op.operands() {
                    if let Operand::Tmp(t) = o
                        && single(o)
                        && def[t as usize].as_ref().is_some_and(is_sum)
                    {
                        folded[t as usize] = true;
                    }
                }
            }
        }
        SumTrees { uses, def, folded }
    }
}

/// The terms of the sum tree at `o` (single-use sums expanded).
pub(super) fn collect(
    def: &[Option<Op>],
    single: &dyn Fn(Operand) -> bool,
    o: Operand,
    neg: bool,
    terms: &mut Vec<Term>,
) {
    let expand = |x: Operand| single(x);
    let Operand::Tmp(t) = o else {
        terms.push(Term { neg, value: o });
        return;
    };
    match def[t as usize] {
        Some(Op::Add(a, b)) => {
            for x in [a, b] {
                if expand(x) && is_sum_def(def, x) {
                    collect(def, single, x, neg, terms);
                } else {
                    terms.push(Term { neg, value: x });
                }
            }
        }
        Some(Op::Sub(a, b)) => {
            for (x, n) in [(a, neg), (b, !neg)] {
                if expand(x) && is_sum_def(def, x) {
                    collect(def, single, x, n, terms);
                } else {
                    terms.push(Term { neg: n, value: x });
                }
            }
        }
        Some(Op::Neg(a)) => {
            if expand(a) && is_sum_def(def, a) {
                collect(def, single, a, !neg, terms);
            } else {
                terms.push(Term {
                    neg: !neg,
                    value: a,
                });
            }
        }
        _ => terms.push(Term { neg, value: o }),
    }
}

fn is_sum_def(def: &[Option<Op>], x: Operand) -> bool {
    matches!(x, Operand::Tmp(t) if matches!(def[t as usize], Some(Op::Add(..) | Op::Sub(..) | Op::Neg(_))))
}

/// A factor common to two or more single-use product terms, greedily by
/// group size: the groups `(factor, terms of the cofactors)` and the terms
/// left. `None` when no factor is shared.
type Groups = (Vec<(Operand, Vec<Term>)>, Vec<Term>);

fn regroup(def: &[Option<Op>], single: &dyn Fn(Operand) -> bool, terms: &[Term]) -> Option<Groups> {
    // Each term's factors, if it is a single-use product.
    let factors: Vec<Option<(Operand, Operand)>> = terms
        .iter()
        .map(|t| match t.value {
            Operand::Tmp(i) if single(t.value) => match def[i as usize] {
                Some(Op::Mul(a, b)) => Some((a, b)),
                _ => None,
            },
            _ => None,
        })
        .collect();
    let mut taken = vec![false; terms.len()];
    let mut groups = Vec::new();
    loop {
        // Candidate factors in order of first appearance, with counts.
        let mut cands: Vec<(Operand, usize)> = Vec::new();
        for (i, f) in factors.iter().enumerate() {
            let Some((a, b)) = f else { continue };
            if taken[i] {
                continue;
            }
            for x in if a == b { vec![*a] } else { vec![*a, *b] } {
                match cands.iter_mut().find(|(c, _)| *c == x) {
                    Some((_, k)) => *k += 1,
                    None => cands.push((x, 1)),
                }
            }
        }
        let Some(&(best, count)) = cands
            .iter()
            .fold(None, |acc: Option<&(Operand, usize)>, c| match acc {
                Some(a) if a.1 >= c.1 => Some(a),
                _ => Some(c),
            })
        else {
            break;
        };
        if count < 2 {
            break;
        }
        let mut g = Vec::new();
        for (i, f) in factors.iter().enumerate() {
            let Some((a, b)) = f else { continue };
            if taken[i] {
                continue;
            }
            let other = if *a == best {
                *b
            } else if *b == best {
                *a
            } else {
                continue;
            };
            taken[i] = true;
            g.push(Term {
                neg: terms[i].neg,
                value: other,
            });
        }
        groups.push((best, g));
    }
    if groups.is_empty() {
        return None;
    }
    let rest = terms
        .iter()
        .zip(&taken)
        .filter(|(_, t)| !**t)
        .map(|(t, _)| *t)
        .collect();
    Some((groups, rest))
}

/// `Σ ±x` as one operand and whether it carries a leading minus (all
/// terms negative: `−(Σ x)` is returned as `(Σ x, true)`).
fn signed_sum(
    terms: &[Term],
    out: &mut Vec<Instr>,
    fresh: &mut dyn FnMut(Op, &mut Vec<Instr>) -> Operand,
) -> (Operand, bool) {
    let all_neg = terms.iter().all(|t| t.neg);
    let flipped: Vec<Term> = terms
        .iter()
        .map(|t| Term {
            neg: t.neg != all_neg,
            value: t.value,
        })
        .collect();
    if flipped.len() == 1 {
        return (flipped[0].value, all_neg);
    }
    let op = sum_op(&flipped, out, fresh);
    (fresh(op, out), all_neg)
}

/// The last operation of `Σ ±x` (the earlier ones emitted): positive
/// terms added first, negative ones subtracted; all negative is `−(Σ x)`.
pub(super) fn sum_op(
    terms: &[Term],
    out: &mut Vec<Instr>,
    fresh: &mut dyn FnMut(Op, &mut Vec<Instr>) -> Operand,
) -> Op {
    let pos: Vec<Operand> = terms.iter().filter(|t| !t.neg).map(|t| t.value).collect();
    let neg: Vec<Operand> = terms.iter().filter(|t| t.neg).map(|t| t.value).collect();
    let all_neg = pos.is_empty();
    let (first, steps): (Operand, Vec<(bool, Operand)>) = if all_neg {
        (neg[0], neg[1..].iter().map(|&x| (false, x)).collect())
    } else {
        let steps = pos[1..]
            .iter()
            .map(|&x| (false, x))
            .chain(neg.iter().map(|&x| (true, x)))
            .collect();
        (pos[0], steps)
    };
    let mut acc = first;
    for (k, &(sub, x)) in steps.iter().enumerate() {
        let op = if sub {
            Op::Sub(acc, x)
        } else {
            Op::Add(acc, x)
        };
        if k + 1 == steps.len() && !all_neg {
            return op;
        }
        acc = fresh(op, out);
    }
    if all_neg {
        Op::Neg(acc)
    } else {
        // One positive term: `x + 0`, folded away by optimisation.
        Op::Add(acc, Operand::Const(Num::ZERO))
    }
}
