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
        let mut saved = 0;
        self.rewrite_sums(|trees, terms, emit| {
            let (groups, mut all) = regroup(trees, terms)?;
            saved += groups.iter().map(|(_, g)| g.len() - 1).sum::<usize>();
            for (k, g) in groups {
                let (s, neg) = signed_sum(&g, emit);
                let value = emit.op(Op::Mul(k, s));
                all.push(Term { neg, value });
            }
            Some(all)
        });
        saved
    }

    /// Rewrites every sum tree of the program (additions, subtractions and
    /// negations whose intermediate results are read only inside the tree):
    /// `rewrite` gets the tree's terms and returns the terms of the sum
    /// that replaces it, emitting what they need through [`Emit`], or
    /// `None` to keep the tree. The root keeps its temporary: the last
    /// operation of the rebuilt sum is written to it, so every reader of
    /// the tree reads the new sum. What the old tree no longer needs is
    /// left for [`Program::optimize`] to remove.
    pub(super) fn rewrite_sums(
        &mut self,
        mut rewrite: impl FnMut(&SumTrees, &[Term], &mut Emit) -> Option<Vec<Term>>,
    ) {
        let trees = SumTrees::of(self);
        let mut out: Vec<Instr> = Vec::with_capacity(self.instrs.len());
        let mut next = self.n_tmps;
        for ins in &self.instrs {
            if !trees.is_root(ins) {
                out.push(*ins);
                continue;
            }
            let terms = trees.terms(ins.dst);
            let mut emit = Emit {
                next,
                out: &mut out,
            };
            let op = rewrite(&trees, &terms, &mut emit).map(|all| sum_op(&all, &mut emit));
            next = emit.next;
            out.push(Instr {
                dst: ins.dst,
                op: op.unwrap_or(ins.op),
            });
        }
        self.n_tmps = next;
        self.instrs = out;
    }
}

/// Where a rewrite emits its new temporaries: before the root of the tree
/// it rewrites, numbered after the program's own.
pub(super) struct Emit<'a> {
    next: u32,
    out: &'a mut Vec<Instr>,
}

impl Emit<'_> {
    /// Emits `op` into a new temporary and returns it.
    pub(super) fn op(&mut self, op: Op) -> Operand {
        let dst = self.next;
        self.next += 1;
        self.out.push(Instr { dst, op });
        Operand::Tmp(dst)
    }
}

/// A program's sum trees: the uses of each temporary (outputs count
/// twice, so they are never folded into a tree), each temporary's
/// definition, and which sums are folded into a bigger one (not roots).
pub(super) struct SumTrees {
    pub(super) uses: Vec<usize>,
    pub(super) def: Vec<Option<Op>>,
    folded: Vec<bool>,
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
        let mut trees = SumTrees {
            uses,
            def,
            folded: vec![false; n + 1],
        };
        // A tree's root is a sum not folded into a bigger one: a sum whose
        // result is read by anything but a single-use sum context.
        for ins in &p.instrs {
            if is_sum(&ins.op) {
                for o in ins.op.operands() {
                    if let Operand::Tmp(t) = o
                        && trees.single(o)
                        && trees.is_sum(o)
                    {
                        trees.folded[t as usize] = true;
                    }
                }
            }
        }
        trees
    }

    /// Whether `o` is a temporary read exactly once (and not an output).
    pub(super) fn single(&self, o: Operand) -> bool {
        matches!(o, Operand::Tmp(t) if self.uses[t as usize] == 1)
    }

    /// Whether `o` is a temporary defined by a sum.
    pub(super) fn is_sum(&self, o: Operand) -> bool {
        matches!(o, Operand::Tmp(t) if self.def[t as usize].as_ref().is_some_and(is_sum))
    }

    /// Whether `ins` is the root of a sum tree.
    pub(super) fn is_root(&self, ins: &Instr) -> bool {
        is_sum(&ins.op) && !self.folded[ins.dst as usize]
    }

    /// The terms of the sum tree rooted at temporary `root`.
    pub(super) fn terms(&self, root: u32) -> Vec<Term> {
        let mut terms = Vec::new();
        self.collect(Operand::Tmp(root), false, &mut terms);
        terms
    }

    /// The terms of `neg · o`, single-use sums expanded.
    fn collect(&self, o: Operand, neg: bool, terms: &mut Vec<Term>) {
        let Operand::Tmp(t) = o else {
            terms.push(Term { neg, value: o });
            return;
        };
        let parts: &[(Operand, bool)] = match self.def[t as usize] {
            Some(Op::Add(a, b)) => &[(a, neg), (b, neg)],
            Some(Op::Sub(a, b)) => &[(a, neg), (b, !neg)],
            Some(Op::Neg(a)) => &[(a, !neg)],
            _ => {
                terms.push(Term { neg, value: o });
                return;
            }
        };
        for &(x, n) in parts {
            if self.single(x) && self.is_sum(x) {
                self.collect(x, n, terms);
            } else {
                terms.push(Term { neg: n, value: x });
            }
        }
    }
}

fn is_sum(op: &Op) -> bool {
    matches!(op, Op::Add(..) | Op::Sub(..) | Op::Neg(_))
}

/// A factor common to two or more single-use product terms, greedily by
/// group size: the groups `(factor, terms of the cofactors)` and the terms
/// left. `None` when no factor is shared.
type Groups = (Vec<(Operand, Vec<Term>)>, Vec<Term>);

fn regroup(trees: &SumTrees, terms: &[Term]) -> Option<Groups> {
    // Each term's factors, if it is a single-use product.
    let factors: Vec<Option<(Operand, Operand)>> = terms
        .iter()
        .map(|t| match t.value {
            Operand::Tmp(i) if trees.single(t.value) => match trees.def[i as usize] {
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
fn signed_sum(terms: &[Term], emit: &mut Emit) -> (Operand, bool) {
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
    let op = sum_op(&flipped, emit);
    (emit.op(op), all_neg)
}

/// The last operation of `Σ ±x` (the earlier ones emitted): positive
/// terms added first, negative ones subtracted; all negative is `−(Σ x)`.
fn sum_op(terms: &[Term], emit: &mut Emit) -> Op {
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
        acc = emit.op(op);
    }
    if all_neg {
        Op::Neg(acc)
    } else {
        // One positive term: `x + 0`, folded away by optimisation.
        Op::Add(acc, Operand::Const(Num::ZERO))
    }
}
