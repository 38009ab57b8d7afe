//! Trigonometric identities applied to the terms of a sum while it is built.
//!
//! Both rules look for a *partner term* that differs from a given term only
//! in its trigonometric factors. Partners are found without creating nodes:
//! the partner's factor (e.g. `cos²x` for `sin²x`) is looked up in the hash
//! table, and if it does not exist no term can contain it.
//!
//! - Pythagoras: `k·sin²x·R + k·cos²x·R = k·R` (any product `R`, including
//!   `R = 1` and nested forms, since sums and products are flat), and
//!   `k − k·sin²x = k·cos²x`, `k − k·cos²x = k·sin²x`.
//! - Angle sums (addition theorems):
//!   `cos a cos b − sin a sin b = cos(a+b)`, `cos a cos b + sin a sin b = cos(a−b)`,
//!   `sin a cos b + cos a sin b = sin(a+b)`, `sin a cos b − cos a sin b = sin(a−b)`,
//!   each scaled by `k·R`. Counting a sin/cos pair of one argument as one
//!   trig evaluation (the lowering computes them together), the contraction
//!   replaces two terms (`2|R| + 3` multiplications and one addition) by one
//!   term (`|R| + 1` multiplications), one addition for the new argument and
//!   at most one new trig evaluation; and it keeps chains of parallel-axis
//!   rotations from swelling (`cos(q1+q2+q3)` instead of a product expansion).
//!
//! Neither identity assumes anything about its arguments.

use super::arena::Arena;
use super::build::Term;
use super::node::{Id, View};
use super::rules::RuleSet;

const MAX_ROUNDS: usize = 16;
const MAX_FACTORS: usize = 8;

/// `fs` without the factors at `drop`, plus `add`, in canonical order.
fn replace_sorted(a: &Arena, fs: &[Id], drop: &[usize], add: &[Id]) -> Vec<Id> {
    let mut v: Vec<Id> = fs
        .iter()
        .enumerate()
        .filter(|(i, _)| !drop.contains(i))
        .map(|(_, &f)| f)
        .collect();
    v.extend_from_slice(add);
    v.sort_unstable_by(|&x, &y| a.canonical_cmp(x, y));
    v
}

impl Arena {
    /// Apply the Pythagorean and angle-sum identities to merged terms,
    /// re-merging after each success (bounded number of rounds).
    pub(crate) fn trig_terms(&mut self, terms: &mut Vec<Term>) {
        let pyth = self.rules.has(RuleSet::PYTHAGORAS);
        let angle = self.rules.has(RuleSet::ANGLE_SUM);
        for _ in 0..MAX_ROUNDS {
            let changed = (pyth && self.pythagoras(terms)) || (angle && self.angle_sum(terms));
            if !changed {
                break;
            }
            self.merge_terms(terms);
        }
    }

    fn remove_pair(terms: &mut Vec<Term>, i: usize, j: usize) {
        let (hi, lo) = if i > j { (i, j) } else { (j, i) };
        terms.swap_remove(hi);
        terms.swap_remove(lo);
    }

    fn pythagoras(&mut self, terms: &mut Vec<Term>) -> bool {
        for i in 0..terms.len() {
            if terms[i].fs.len() > MAX_FACTORS {
                continue;
            }
            for fi in 0..terms[i].fs.len() {
                let f = terms[i].fs[fi];
                let View::Pow(s, 2) = self.view(f) else {
                    continue;
                };
                let partner = match self.view(s) {
                    View::Sin(x) => View::Cos(x),
                    View::Cos(x) => View::Sin(x),
                    _ => continue,
                };
                let coef = terms[i].coef;
                let p2 = self
                    .lookup(&partner)
                    .and_then(|p| self.lookup(&View::Pow(p, 2)));
                if let Some(p2) = p2 {
                    let pfs = replace_sorted(self, &terms[i].fs, &[fi], &[p2]);
                    if let Some(j) = terms.iter().position(|t| t.coef == coef && t.fs == pfs) {
                        let rest = replace_sorted(self, &terms[i].fs, &[fi], &[]);
                        Self::remove_pair(terms, i, j);
                        terms.push(Term {
                            coef,
                            fs: rest,
                            orig: None,
                        });
                        return true;
                    }
                }
                // k - k sin²x = k cos²x (and with sin, cos swapped).
                if terms[i].fs.len() == 1 {
                    let k = coef.negated();
                    if let Some(j) = terms.iter().position(|t| t.fs.is_empty() && t.coef == k) {
                        let p = self.intern(partner);
                        let p2 = self.pow(p, 2);
                        Self::remove_pair(terms, i, j);
                        terms.push(Term {
                            coef: k,
                            fs: vec![p2],
                            orig: None,
                        });
                        return true;
                    }
                }
            }
        }
        false
    }

    fn angle_sum(&mut self, terms: &mut Vec<Term>) -> bool {
        for i in 0..terms.len() {
            let n = terms[i].fs.len();
            if !(2..=MAX_FACTORS).contains(&n) {
                continue;
            }
            for ai in 0..n {
                for bi in 0..n {
                    if ai == bi {
                        continue;
                    }
                    let (f, g) = (terms[i].fs[ai], terms[i].fs[bi]);
                    // (is_cos_cos, a, b, partner factors)
                    let (cc, a, b, p) = match (self.view(f), self.view(g)) {
                        (View::Cos(a), View::Cos(b)) if ai < bi => {
                            (true, a, b, [View::Sin(a), View::Sin(b)])
                        }
                        (View::Sin(a), View::Cos(b)) => (false, a, b, [View::Cos(a), View::Sin(b)]),
                        _ => continue,
                    };
                    if a == b {
                        continue;
                    }
                    let (Some(p1), Some(p2)) = (self.lookup(&p[0]), self.lookup(&p[1])) else {
                        continue;
                    };
                    let pfs = replace_sorted(self, &terms[i].fs, &[ai, bi], &[p1, p2]);
                    let k = terms[i].coef;
                    let Some(j) = terms
                        .iter()
                        .position(|t| t.fs == pfs && (t.coef == k || t.coef == k.negated()))
                    else {
                        continue;
                    };
                    let same = terms[j].coef == k;
                    // cos: partner -k → a+b, +k → a-b; sin: partner +k → a+b, -k → a-b.
                    let plus = if cc { !same } else { same };
                    let arg = if plus {
                        self.add2(a, b)
                    } else {
                        self.sub(a, b)
                    };
                    let trig = if cc { self.cos(arg) } else { self.sin(arg) };
                    let rest = replace_sorted(self, &terms[i].fs, &[ai, bi], &[]);
                    let mut cs = vec![self.num_node(k), trig];
                    cs.extend_from_slice(&rest);
                    let node = self.mul(&cs);
                    Self::remove_pair(terms, i, j);
                    match self.view(node) {
                        View::Add(ts) => {
                            let ts = ts.to_vec();
                            terms.extend(ts.into_iter().map(|t| self.term_of(t)));
                        }
                        _ => terms.push(self.term_of(node)),
                    }
                    return true;
                }
            }
        }
        false
    }
}
