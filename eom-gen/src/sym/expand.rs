//! Expansion: multiply out products of sums and small powers of sums.
//!
//! Not part of the default simplification, since multiplying out usually
//! adds operations; but after expansion the construction rules see every
//! term at once, so `sin²+cos²` and angle sums that were hidden inside
//! products cancel. The mechanics layer can expand small quantities (e.g.
//! mass-matrix entries of a few bodies) and keep the smaller form by
//! comparing [`Arena::op_estimate`].
//!
//! `(a + b)·c = a·c + b·c` and `(a + b)^n` for `2 ≤ n ≤ 4` are exact (up to
//! floating-point rounding); a product whose expansion would have more than
//! `max_terms` terms is left as it is.

use super::arena::Arena;
use super::node::{Id, View};
use rustc_hash::FxHashMap;

/// Largest integer power of a sum that [`Arena::expand`] multiplies out.
pub const MAX_EXPAND_POWER: i32 = 4;

impl Arena {
    /// Expand all `roots` (see the module docs); products that would expand
    /// to more than `max_terms` terms are kept.
    pub fn expand(&mut self, roots: &[Id], max_terms: usize) -> Vec<Id> {
        let mut new: FxHashMap<Id, Id> = FxHashMap::default();
        for id in self.reachable(roots, |_| false) {
            let r = match self.view(id) {
                View::Mul(cs) => {
                    let cs: Vec<Id> = cs.iter().map(|c| new[c]).collect();
                    self.expand_product(&cs, max_terms)
                }
                View::Pow(b, n) if (2..=MAX_EXPAND_POWER).contains(&n) => {
                    let b = new[&b];
                    self.expand_product(&vec![b; n as usize], max_terms)
                }
                _ => self.rebuild(id, |c| new[&c]),
            };
            new.insert(id, r);
        }
        roots.iter().map(|r| new[r]).collect()
    }

    /// `Π factors`, multiplied out over the sums among them if that gives at
    /// most `max_terms` terms.
    fn expand_product(&mut self, factors: &[Id], max_terms: usize) -> Id {
        let mut size: usize = 1;
        for &f in factors {
            if let View::Add(ts) = self.view(f) {
                size = size.saturating_mul(ts.len());
            }
        }
        if size == 1 || size > max_terms {
            return self.mul(factors);
        }
        let mut terms: Vec<Id> = vec![self.constant(1.0)];
        for &f in factors {
            let parts: Vec<Id> = match self.view(f) {
                View::Add(ts) => ts.to_vec(),
                _ => vec![f],
            };
            let mut next = Vec::with_capacity(terms.len() * parts.len());
            for &t in &terms {
                for &p in &parts {
                    next.push(self.mul2(t, p));
                }
            }
            terms = next;
        }
        self.add(&terms)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binomial() {
        let mut a = Arena::new();
        let e = a.parse("(^ (+ x y) 2)").unwrap();
        let got = a.expand(&[e], 64)[0];
        let want = a.parse("(+ (^ x 2) (* 2 x y) (^ y 2))").unwrap();
        assert_eq!(got, want, "got {} want {}", a.display(got), a.display(want));
    }

    #[test]
    fn too_many_terms_are_kept() {
        let mut a = Arena::new();
        let e = a.parse("(* (+ a b c) (+ d e f))").unwrap();
        assert_eq!(a.expand(&[e], 8)[0], e);
        let got = a.expand(&[e], 9)[0];
        assert!(
            matches!(a.view(got), View::Add(ts) if ts.len() == 9),
            "got {}",
            a.display(got)
        );
    }
}
