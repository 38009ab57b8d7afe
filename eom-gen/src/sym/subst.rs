//! Substitution of symbols by expressions (inlining fixed parameters,
//! evaluating at an operating point, replacing `q̇` by `u`).

use super::arena::Arena;
use super::node::{Id, SymId};
use rustc_hash::FxHashMap;

impl Arena {
    /// Replace each symbol `s` for which `map(s)` is `Some(e)` by `e` in all
    /// `roots` (pass `|s| table.get(&s).copied()` for a hash map), rebuilding
    /// every node above a replaced symbol through the smart constructors (so
    /// e.g. substituting `0` for an angle folds `sin 0`, and the zeros
    /// propagate). Nodes that do not depend on a replaced symbol are reused.
    pub fn substitute(&mut self, roots: &[Id], map: impl Fn(SymId) -> Option<Id>) -> Vec<Id> {
        let mut new: FxHashMap<Id, Id> = FxHashMap::default();
        for id in self.reachable(roots, |_| false) {
            let r = match self.as_sym(id).and_then(&map) {
                Some(to) => to,
                None if self.view(id).children().all(|c| new[&c] == c) => id,
                None => self.rebuild(id, |c| new[&c]),
            };
            new.insert(id, r);
        }
        roots.iter().map(|r| new[r]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_parameters_fold_away() {
        let mut a = Arena::new();
        let e = a
            .parse("(+ (* l (sin q1)) (* d (cos q1)) (* d l))")
            .unwrap();
        let (l, d) = (a.find_symbol("l").unwrap(), a.find_symbol("d").unwrap());
        let mut map = FxHashMap::default();
        map.insert(d, a.constant(0.0));
        map.insert(l, a.ratio(1, 2));
        let got = a.substitute(&[e], |s| map.get(&s).copied())[0];
        let want = a.parse("(* 1/2 (sin q1))").unwrap();
        assert_eq!(got, want, "got {} want {}", a.display(got), a.display(want));
    }

    #[test]
    fn substituting_expressions() {
        let mut a = Arena::new();
        let e = a.parse("(* qd1 (cos q1))").unwrap();
        let qd1 = a.find_symbol("qd1").unwrap();
        let mut map = FxHashMap::default();
        map.insert(qd1, a.u(1));
        let got = a.substitute(&[e], |s| map.get(&s).copied())[0];
        let want = a.parse("(* u1 (cos q1))").unwrap();
        assert_eq!(got, want, "got {} want {}", a.display(got), a.display(want));
        let unrelated = a.parse("(sin q2)").unwrap();
        assert_eq!(
            a.substitute(&[unrelated], |s| map.get(&s).copied())[0],
            unrelated
        );
    }
}
