//! Pythagoras with unequal coefficients after lowering:
//! `x·cos²θ + y·sin²θ → x + (y − x)·sin²θ`.
//!
//! A congruence `E A Eᵀ` by a rotation about one axis leaves sums such as
//! `0.005·c² + 0.3775·s² + 0.005` in the program (issue #28); with
//! `s² + c² = 1` that is `0.01 + 0.3725·s²`, one multiplication and one
//! addition fewer, and the other square often dies. The rule applies to one
//! sum tree at a time (as [`Program::factor_sums`]), to pairs of terms
//! `±x·c²` and `±y·s²` of the same angle whose products are used only in
//! the tree; the constant terms of a rewritten tree are added up. Exact over
//! the reals; the rounding differs by a few ulps (`fl(s²) + fl(c²)` is
//! within an ulp or two of 1).

use super::factor::{SumTrees, Term};
use super::num::Num;
use super::program::{Op, Operand, Program};

/// A term `±coef·sq` where `sq` is the square of `sin` or `cos` of `angle`.
#[derive(Clone, Copy)]
struct Square {
    term: usize,
    angle: Operand,
    is_sin: bool,
    sq: Operand,
    coef: Operand,
}

impl Program {
    /// Rewrites `x·c² + y·s²` of one angle in every sum tree (see the
    /// module comment); returns the number of pairs rewritten, before the
    /// clean-up that follows ([`Program::optimize`]).
    pub fn pythagoras(&mut self) -> usize {
        // sin or cos of which angle each temporary holds.
        let mut trig: Vec<Option<(Operand, bool)>> = vec![None; self.n_tmps as usize + 1];
        for ins in &self.instrs {
            let d = ins.dst as usize;
            match ins.op {
                Op::SinCos(a) => {
                    trig[d] = Some((a, true));
                    trig[d + 1] = Some((a, false));
                }
                Op::Sin(a) => trig[d] = Some((a, true)),
                Op::Cos(a) => trig[d] = Some((a, false)),
                _ => {}
            }
        }
        let mut pairs = 0;
        self.rewrite_sums(|trees, terms, emit| {
            let found = pairs_in(trees, &trig, terms);
            if found.is_empty() {
                return None;
            }
            pairs += found.len();
            let mut gone = vec![false; terms.len()];
            let mut new_terms: Vec<Term> = Vec::new();
            for (c, s) in found {
                gone[c.term] = true;
                gone[s.term] = true;
                // Keep the square read more often: the other may die.
                let sq_uses = |o: Operand| match o {
                    Operand::Tmp(t) => trees.uses[t as usize],
                    Operand::Const(_) | Operand::Var(_) => 0,
                };
                let (drop, keep) = if sq_uses(c.sq) > sq_uses(s.sq) {
                    (s, c)
                } else {
                    (c, s)
                };
                let (n_drop, n_keep) = (terms[drop.term].neg, terms[keep.term].neg);
                // ±x·(1 − q) ± y·q = ±x + (±y ∓ x)·q.
                let d = if n_drop == n_keep {
                    emit.op(Op::Sub(keep.coef, drop.coef))
                } else {
                    emit.op(Op::Add(keep.coef, drop.coef))
                };
                let prod = emit.op(Op::Mul(d, keep.sq));
                new_terms.push(Term {
                    neg: n_drop,
                    value: drop.coef,
                });
                new_terms.push(Term {
                    neg: n_keep,
                    value: prod,
                });
            }
            let all: Vec<Term> = terms
                .iter()
                .zip(&gone)
                .filter(|(_, g)| !**g)
                .map(|(t, _)| *t)
                .chain(new_terms)
                .collect();
            Some(add_constants(all))
        });
        pairs
    }
}

/// The pairs of a `cos²` term and a `sin²` term of one angle among a sum
/// tree's `terms` (squares, or single-use multiples of one); `trig` says
/// which angle's sine or cosine each temporary holds.
fn pairs_in(
    trees: &SumTrees,
    trig: &[Option<(Operand, bool)>],
    terms: &[Term],
) -> Vec<(Square, Square)> {
    let square = |o: Operand| -> Option<(Operand, bool)> {
        let Operand::Tmp(t) = o else { return None };
        match trees.def.get(t as usize).copied().flatten() {
            Some(Op::Mul(Operand::Tmp(a), Operand::Tmp(b))) if a == b => trig[a as usize],
            _ => None,
        }
    };
    let squares: Vec<Square> = terms
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            if let Some((angle, is_sin)) = square(t.value) {
                return Some(Square {
                    term: i,
                    angle,
                    is_sin,
                    sq: t.value,
                    coef: Operand::Const(Num::ONE),
                });
            }
            let Operand::Tmp(p) = t.value else {
                return None;
            };
            let Some(Op::Mul(a, b)) = trees.def[p as usize] else {
                return None;
            };
            if !trees.single(t.value) {
                return None;
            }
            [(b, a), (a, b)].into_iter().find_map(|(sq, coef)| {
                square(sq).map(|(angle, is_sin)| Square {
                    term: i,
                    angle,
                    is_sin,
                    sq,
                    coef,
                })
            })
        })
        .collect();
    let mut taken = vec![false; squares.len()];
    let mut found = Vec::new();
    for (i, c) in squares.iter().enumerate() {
        if c.is_sin || taken[i] {
            continue;
        }
        if let Some(j) = (0..squares.len())
            .find(|&j| !taken[j] && squares[j].is_sin && squares[j].angle == c.angle)
        {
            taken[i] = true;
            taken[j] = true;
            found.push((*c, squares[j]));
        }
    }
    found
}

/// The constant terms of a sum added into one, put first (unless the sum
/// would overflow or the constants cancel out and other terms remain).
fn add_constants(terms: Vec<Term>) -> Vec<Term> {
    let mut total = Num::ZERO;
    let mut rest = Vec::with_capacity(terms.len());
    for t in terms {
        match t.value {
            Operand::Const(c) => {
                let c = if t.neg { c.negated() } else { c };
                match total.checked_add(c) {
                    Some(s) => total = s,
                    None => rest.push(t),
                }
            }
            _ => rest.push(t),
        }
    }
    if total.is_zero() && !rest.is_empty() {
        return rest;
    }
    let mut all = vec![Term {
        neg: false,
        value: Operand::Const(total),
    }];
    all.extend(rest);
    all
}
