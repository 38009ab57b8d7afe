//! The rewrite runner: repeated bottom-up passes over a DAG with limits and a
//! typed stop reason (after egg's `Runner`).
//!
//! Each iteration rebuilds every node reachable from the roots, children
//! first, through the smart constructors (so the construction-time
//! [`RuleSet`] is re-applied to graphs built under other rules, e.g. raw
//! ones), then tries each named [`Rewrite`] on the rebuilt node. Work is
//! incremental: a node whose children did not change is not rebuilt if the
//! arena built it under the same rules, and is skipped altogether once it is
//! known to be a fixed point of the rebuild and the rewrites. The run
//! stops when an iteration changes no root ([`StopReason::Saturated`]) or
//! a limit is hit. With the cost guard on (default), an iteration is only
//! kept if it does not raise [`Arena::op_estimate`], so the runner never
//! makes the generated code bigger by that measure.
//!
//! Named rewrites (beyond the construction rules; see [`rewrites`]):
//! - `factor`: pull the factor shared by most terms out of a sum,
//!   `a·x + b·x + c = (a + b)·x + c` (symbolic `a`, `b`), when at least two
//!   terms share it. Saves one multiplication per extra term. Terms that are
//!   used elsewhere in the DAG ([`Uses`]) are not factored, since they are
//!   computed anyway and factoring them would only add work. Uses
//!   `x^a · x^-a = 1` (assumes the factor is nonzero where it divides out,
//!   which holds since it multiplied every term it is removed from).

use super::arena::Arena;
use super::node::{Id, View};
use super::rules::RuleSet;
use rustc_hash::{FxHashMap, FxHashSet};
use std::time::{Duration, Instant};

/// How many parents use each node of the DAG being simplified (counted
/// over the nodes reachable from the roots, plus one per root). Rewrites use
/// it to avoid destroying sharing: a subexpression used elsewhere is
/// computed anyway, so rewriting it away here saves nothing.
#[derive(Clone, Debug, Default)]
pub struct Uses(FxHashMap<Id, u32>);

impl Uses {
    /// Number of uses of `id`; nodes not seen count as used once.
    pub fn get(&self, id: Id) -> u32 {
        self.0.get(&id).copied().unwrap_or(1)
    }
}

/// A named rewrite: returns the replacement of a (canonical) node, or
/// `None` if it does not apply.
#[derive(Clone, Copy)]
pub struct Rewrite {
    /// Name used in reports.
    pub name: &'static str,
    /// The rewrite, given the use counts of the rebuilt DAG's nodes.
    pub apply: fn(&mut Arena, Id, &Uses) -> Option<Id>,
}

impl std::fmt::Debug for Rewrite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// The default named rewrites, in the order they are tried.
pub fn rewrites() -> Vec<Rewrite> {
    vec![Rewrite {
        name: "factor",
        apply: factor_common,
    }]
}

/// Why a run stopped.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum StopReason {
    /// An iteration changed nothing.
    Saturated,
    /// `iter_limit` iterations ran.
    IterLimit,
    /// The arena grew beyond `node_limit` nodes.
    NodeLimit,
    /// `time_limit` elapsed.
    TimeLimit,
    /// The last iteration raised the estimated operation count
    /// ([`Arena::op_estimate`]); its result was discarded.
    NoImprovement,
}

/// Limits and rules of a simplification run.
#[derive(Clone, Debug)]
pub struct Runner {
    /// Maximum number of iterations.
    pub iter_limit: usize,
    /// Stop when the arena has more nodes than this.
    pub node_limit: usize,
    /// Stop when a run has taken longer than this (checked between nodes).
    pub time_limit: Duration,
    /// Construction-time rules in force during the run.
    pub rules: RuleSet,
    /// Extra rewrites tried on each rebuilt node.
    pub rewrites: Vec<Rewrite>,
    /// Keep an iteration's result only if it does not raise the estimated
    /// operation count; otherwise stop with [`StopReason::NoImprovement`].
    pub cost_guard: bool,
}

impl Default for Runner {
    fn default() -> Self {
        Runner {
            iter_limit: 8,
            node_limit: 10_000_000,
            time_limit: Duration::from_secs(10),
            rules: RuleSet::ALL,
            rewrites: rewrites(),
            cost_guard: true,
        }
    }
}

/// What a run did.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SimplifyReport {
    /// The simplified roots, in the order given.
    pub roots: Vec<Id>,
    /// Why it stopped.
    pub stop: StopReason,
    /// Iterations run (including the last, unchanged one when saturated).
    pub iterations: usize,
    /// How often each named rewrite applied.
    pub applied: Vec<(&'static str, usize)>,
    /// DAG size (reachable nodes) before and after.
    pub dag_size: (usize, usize),
}

impl Runner {
    /// Only the construction rules `rules`, no extra rewrites.
    pub fn with_rules(rules: RuleSet) -> Runner {
        Runner {
            rules,
            rewrites: Vec::new(),
            ..Runner::default()
        }
    }

    /// Simplify `roots` in `arena`. The arena's own rules are restored afterwards.
    pub fn run(&self, arena: &mut Arena, roots: &[Id]) -> SimplifyReport {
        let start = Instant::now();
        let saved = arena.rules();
        // Nodes built under the runner's own rules are already canonical:
        // rebuilding one whose children did not change gives it back.
        let canonical = saved == self.rules && arena.rules_uniform();
        arena.set_rules(self.rules);
        // Nodes known to be fixed points of rebuild and rewrites.
        let mut settled: FxHashSet<Id> = FxHashSet::default();
        let before = arena.dag_size(roots);
        let mut applied: Vec<(&'static str, usize)> =
            self.rewrites.iter().map(|r| (r.name, 0)).collect();
        let mut cur: Vec<Id> = roots.to_vec();
        let mut iterations = 0;
        let stop = loop {
            if iterations >= self.iter_limit {
                break StopReason::IterLimit;
            }
            iterations += 1;
            let order = arena.reachable(&cur, |_| false);
            let mut old_uses: FxHashMap<Id, u32> = FxHashMap::default();
            for &r in &cur {
                *old_uses.entry(r).or_default() += 1;
            }
            for &id in &order {
                for c in arena.view(id).children() {
                    *old_uses.entry(c).or_default() += 1;
                }
            }
            let mut uses = Uses::default();
            let mut map: FxHashMap<Id, Id> = FxHashMap::default();
            map.reserve(order.len());
            let mut timed_out = false;
            for (k, &id) in order.iter().enumerate() {
                if k % 1024 == 0 && start.elapsed() > self.time_limit {
                    timed_out = true;
                    break;
                }
                let same_children = arena.view(id).children().all(|c| map[&c] == c);
                let mut new = id;
                if !(same_children && settled.contains(&id)) {
                    if !(same_children && canonical) {
                        new = arena.rebuild(id, |c| map[&c]);
                    }
                    for (i, r) in self.rewrites.iter().enumerate() {
                        if let Some(x) = (r.apply)(arena, new, &uses) {
                            new = x;
                            applied[i].1 += 1;
                        }
                    }
                    if new == id {
                        settled.insert(id);
                    }
                }
                map.insert(id, new);
                *uses.0.entry(new).or_default() += old_uses.get(&id).copied().unwrap_or(1);
            }
            if timed_out {
                break StopReason::TimeLimit;
            }
            let next: Vec<Id> = cur.iter().map(|r| map[r]).collect();
            let changed = next != cur;
            if changed && self.cost_guard && arena.op_estimate(&next) > arena.op_estimate(&cur) {
                break StopReason::NoImprovement;
            }
            cur = next;
            if !changed {
                break StopReason::Saturated;
            }
            if arena.len() > self.node_limit {
                break StopReason::NodeLimit;
            }
            if start.elapsed() > self.time_limit {
                break StopReason::TimeLimit;
            }
        };
        arena.set_rules(saved);
        let after = arena.dag_size(&cur);
        SimplifyReport {
            roots: cur,
            stop,
            iterations,
            applied,
            dag_size: (before, after),
        }
    }
}

/// `factor` rewrite: see the module docs. Terms used elsewhere (shared)
/// are left out, since they are computed anyway.
pub fn factor_common(arena: &mut Arena, id: Id, uses: &Uses) -> Option<Id> {
    let View::Add(cs) = arena.view(id) else {
        return None;
    };
    let (cs, shared): (Vec<Id>, Vec<Id>) = cs.iter().partition(|&&c| uses.get(c) <= 1);
    let terms: Vec<_> = cs.iter().map(|&c| arena.term_of(c)).collect();
    // base -> (number of terms containing it, smallest positive exponent)
    let mut count: FxHashMap<Id, (usize, i32)> = FxHashMap::default();
    for t in &terms {
        for &f in &t.fs {
            let (b, e) = match arena.view(f) {
                View::Pow(b, e) => (b, e),
                _ => (f, 1),
            };
            if e <= 0 {
                continue;
            }
            let entry = count.entry(b).or_insert((0, e));
            entry.0 += 1;
            entry.1 = entry.1.min(e);
        }
    }
    let (&base, &(n, e)) = count
        .iter()
        .filter(|(_, (n, _))| *n >= 2)
        .max_by(|(b1, (n1, _)), (b2, (n2, _))| n1.cmp(n2).then(arena.canonical_cmp(**b2, **b1)))?;
    debug_assert!(n >= 2);
    let f = arena.pow(base, e);
    let inv = arena.pow(base, -e);
    let mut inner = Vec::new();
    let mut rest = shared;
    for (&c, t) in cs.iter().zip(&terms) {
        let has = t
            .fs
            .iter()
            .any(|&x| x == base || matches!(arena.view(x), View::Pow(b, k) if b == base && k >= e));
        if has {
            inner.push(arena.mul(&[c, inv]));
        } else {
            rest.push(c);
        }
    }
    let s = arena.add(&inner);
    let prod = arena.mul(&[f, s]);
    rest.push(prod);
    let out = arena.add(&rest);
    (out != id).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factor_symbolic_coefficients() {
        let mut a = Arena::new();
        let e = a.parse("(+ (* a x) (* b x) c)").unwrap();
        let want = a.parse("(+ (* x (+ a b)) c)").unwrap();
        let r = Runner::default().run(&mut a, &[e]);
        assert_eq!(
            r.roots[0],
            want,
            "got {} want {}",
            a.display(r.roots[0]),
            a.display(want)
        );
        assert_eq!(r.stop, StopReason::Saturated);
        assert_eq!(r.applied, vec![("factor", 1)]);
    }

    #[test]
    fn raw_graph_is_canonicalised() {
        let mut a = Arena::with_rules(RuleSet::NONE);
        let e = a.parse("(+ (^ (sin x) 2) (^ (cos x) 2) (* 0 y))").unwrap();
        assert_eq!(
            a.to_sexpr_string(e),
            "(+ (^ (sin x) 2) (* 0 y) (^ (cos x) 2))"
        );
        let r = Runner::with_rules(RuleSet::ALL).run(&mut a, &[e]);
        assert_eq!(a.to_sexpr_string(r.roots[0]), "1");
        assert_eq!(a.rules(), RuleSet::NONE, "arena rules restored");
    }

    #[test]
    fn limits_stop_with_reason() {
        let mut a = Arena::with_rules(RuleSet::NONE);
        let e = a.parse("(+ x x)").unwrap();
        let r = Runner {
            iter_limit: 1,
            ..Runner::default()
        }
        .run(&mut a, &[e]);
        assert_eq!(r.stop, StopReason::IterLimit);
        let r = Runner {
            node_limit: 0,
            ..Runner::default()
        }
        .run(&mut a, &[e]);
        assert_eq!(r.stop, StopReason::NodeLimit);
        let r = Runner {
            time_limit: Duration::ZERO,
            ..Runner::default()
        }
        .run(&mut a, &[e]);
        assert_eq!(r.stop, StopReason::TimeLimit);
        // A rewrite that only adds work (x → x + 0, kept raw) is discarded.
        fn worse(a: &mut Arena, id: Id, _: &Uses) -> Option<Id> {
            let zero = a.constant(0.0);
            a.as_sym(id).map(|_| a.add2(id, zero))
        }
        let runner = Runner {
            rules: RuleSet::NONE,
            rewrites: vec![Rewrite {
                name: "worse",
                apply: worse,
            }],
            ..Runner::default()
        };
        let r = runner.run(&mut a, &[e]);
        assert_eq!(r.stop, StopReason::NoImprovement);
        assert_eq!(r.roots, vec![e], "result discarded");
    }
}
