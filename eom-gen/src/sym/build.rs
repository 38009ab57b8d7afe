//! Smart constructors: every node is built through these, and each applies
//! the construction-time rules of the arena's [`RuleSet`] before
//! hash-consing.
//!
//! Canonical form (whatever the rules):
//! - sums and products are n-ary and flat (`(+ a (+ b c))` is `(+ a b c)`);
//! - their children are ordered by id, constants first;
//! - `a - b` is `(+ a (* -1 b))`, `-a` is `(* -1 a)`, `a / b` is
//!   `(* a (^ b -1))`.
//!
//! The rules and what each assumes are listed on [`RuleSet`].

use super::arena::Arena;
use super::node::{Id, View};
use super::num::Num;
use super::rules::RuleSet;

/// A term of a sum: `coef · Π fs` with `fs` sorted by id.
#[derive(Clone, Debug)]
pub(crate) struct Term {
    pub(crate) coef: Num,
    pub(crate) fs: Vec<Id>,
    /// The node this term came from, if it is unchanged.
    pub(crate) orig: Option<Id>,
}

fn sort_canonical(a: &Arena, v: &mut [Id]) {
    v.sort_unstable_by(|&x, &y| a.canonical_cmp(x, y));
}

impl Arena {
    // ---- sums ------------------------------------------------------------

    /// Split a node into `coef · Π factors` (the coefficient is the leading
    /// constant of a product when `COLLECT` is on).
    pub(crate) fn term_of(&self, id: Id) -> Term {
        if self.rules.has(RuleSet::COLLECT) {
            if let Some(n) = self.num(id) {
                return Term {
                    coef: n,
                    fs: Vec::new(),
                    orig: Some(id),
                };
            }
            if let View::Mul(cs) = self.view(id) {
                if let Some(c) = self.num(cs[0]) {
                    return Term {
                        coef: c,
                        fs: cs[1..].to_vec(),
                        orig: Some(id),
                    };
                }
                return Term {
                    coef: Num::ONE,
                    fs: cs.to_vec(),
                    orig: Some(id),
                };
            }
        }
        Term {
            coef: Num::ONE,
            fs: vec![id],
            orig: Some(id),
        }
    }

    /// The node for a term.
    pub(crate) fn term_node(&mut self, t: &Term) -> Id {
        if let Some(id) = t.orig {
            return id;
        }
        if t.fs.is_empty() {
            return self.num_node(t.coef);
        }
        if t.coef.is_one() && t.fs.len() == 1 {
            return t.fs[0];
        }
        let mut cs = Vec::with_capacity(t.fs.len() + 1);
        if !t.coef.is_one() {
            cs.push(self.num_node(t.coef));
        }
        cs.extend_from_slice(&t.fs);
        if cs.len() == 1 {
            return cs[0];
        }
        // A coefficient times a single sum is distributed by `mul`.
        if cs.len() == 2 && matches!(self.view(cs[1]), View::Add(_)) {
            return self.mul(&cs);
        }
        self.intern(View::Mul(&cs))
    }

    /// Sort terms by factors and merge like terms; drop zero terms.
    pub(crate) fn merge_terms(&self, terms: &mut Vec<Term>) {
        terms.sort_by(|a, b| a.fs.cmp(&b.fs));
        let fold = self.rules.has(RuleSet::FOLD);
        let mut out: Vec<Term> = Vec::with_capacity(terms.len());
        for t in terms.drain(..) {
            if let Some(last) = out.last_mut()
                && last.fs == t.fs
                && (fold || !t.fs.is_empty())
                && let Some(c) = last.coef.checked_add(t.coef)
            {
                last.coef = c;
                last.orig = None;
                continue;
            }
            out.push(t);
        }
        let identity = self.rules.has(RuleSet::IDENTITY);
        out.retain(|t| !(t.coef.is_zero() && (identity || !t.fs.is_empty())));
        *terms = out;
    }

    /// n-ary sum.
    pub fn add(&mut self, xs: &[Id]) -> Id {
        let mut flat: Vec<Id> = Vec::with_capacity(xs.len() + 2);
        for &x in xs {
            match self.view(x) {
                View::Add(cs) if cs.len() <= self.flatten_limit => flat.extend_from_slice(cs),
                _ => flat.push(x),
            }
        }
        let rules = self.rules;
        let mut out: Vec<Id>;
        if rules.has(RuleSet::COLLECT) {
            let mut terms: Vec<Term> = flat.iter().map(|&x| self.term_of(x)).collect();
            self.merge_terms(&mut terms);
            if rules.has(RuleSet::PYTHAGORAS) || rules.has(RuleSet::ANGLE_SUM) {
                self.trig_terms(&mut terms);
            }
            out = Vec::with_capacity(terms.len());
            for t in &terms {
                let id = self.term_node(t);
                out.push(id);
            }
        } else {
            out = flat;
            if rules.has(RuleSet::FOLD) {
                let mut acc = Num::ZERO;
                let mut folded = 0;
                let mut rest = Vec::with_capacity(out.len());
                for &x in &out {
                    match self.num(x).and_then(|n| acc.checked_add(n)) {
                        Some(s) => {
                            acc = s;
                            folded += 1;
                        }
                        None => rest.push(x),
                    }
                }
                if folded > 0 && (!acc.is_zero() || !rules.has(RuleSet::IDENTITY)) {
                    rest.push(self.num_node(acc));
                }
                out = rest;
            }
            if rules.has(RuleSet::IDENTITY) {
                out.retain(|&x| self.num(x) != Some(Num::ZERO));
            }
        }
        match out.len() {
            0 => self.num_node(Num::ZERO),
            1 => out[0],
            _ => {
                sort_canonical(self, &mut out);
                self.intern(View::Add(&out))
            }
        }
    }

    /// `a + b`.
    pub fn add2(&mut self, a: Id, b: Id) -> Id {
        self.add(&[a, b])
    }

    /// `a - b`.
    pub fn sub(&mut self, a: Id, b: Id) -> Id {
        let nb = self.neg(b);
        self.add(&[a, nb])
    }

    /// `-a`, as `(* -1 a)`.
    pub fn neg(&mut self, a: Id) -> Id {
        let m1 = self.num_node(Num::MINUS_ONE);
        self.mul(&[m1, a])
    }

    // ---- products --------------------------------------------------------

    /// n-ary product.
    pub fn mul(&mut self, xs: &[Id]) -> Id {
        let rules = self.rules;
        let (fold, identity, powers) = (
            rules.has(RuleSet::FOLD),
            rules.has(RuleSet::IDENTITY),
            rules.has(RuleSet::POWERS),
        );
        let mut coef = Num::ONE;
        let mut consts: Vec<Id> = Vec::new();
        let mut factors: Vec<(Id, i32)> = Vec::with_capacity(xs.len() + 2);
        let mut push = |a: &Arena, x: Id, coef: &mut Num, consts: &mut Vec<Id>| {
            if let Some(n) = a.num(x) {
                if fold && let Some(c) = coef.checked_mul(n) {
                    *coef = c;
                    return;
                }
                consts.push(x);
                return;
            }
            match a.view(x) {
                View::Pow(b, e) if powers => factors.push((b, e)),
                _ => factors.push((x, 1)),
            }
        };
        for &x in xs {
            match self.view(x) {
                View::Mul(cs) => {
                    for &c in cs {
                        push(self, c, &mut coef, &mut consts);
                    }
                }
                _ => push(self, x, &mut coef, &mut consts),
            }
        }
        if identity {
            if coef.is_zero() || consts.iter().any(|&c| self.num(c) == Some(Num::ZERO)) {
                return self.num_node(Num::ZERO);
            }
            consts.retain(|&c| self.num(c) != Some(Num::ONE));
        }
        let mut out: Vec<Id> = Vec::with_capacity(factors.len() + 1);
        if powers {
            factors.sort_unstable();
            let mut merged: Vec<(Id, i32)> = Vec::with_capacity(factors.len());
            for (b, e) in factors {
                if let Some(last) = merged.last_mut()
                    && last.0 == b
                    && let Some(s) = last.1.checked_add(e)
                {
                    last.1 = s;
                    continue;
                }
                merged.push((b, e));
            }
            let mut reflatten = false;
            for (b, e) in merged {
                if e == 0 && identity {
                    continue;
                }
                let p = self.pow(b, e);
                reflatten |= matches!(self.view(p), View::Mul(_) | View::Num(_));
                out.push(p);
            }
            if reflatten {
                let c = self.num_node(coef);
                out.push(c);
                out.extend_from_slice(&consts);
                return self.mul(&out);
            }
        } else {
            out.extend(factors.iter().map(|&(b, _)| b));
        }
        if rules.has(RuleSet::DISTRIBUTE)
            && !coef.is_one()
            && consts.is_empty()
            && out.len() == 1
            && let View::Add(ts) = self.view(out[0])
            && ts.len() <= self.flatten_limit
        {
            let ts = ts.to_vec();
            let c = self.num_node(coef);
            let scaled: Vec<Id> = ts.iter().map(|&t| self.mul(&[c, t])).collect();
            return self.add(&scaled);
        }
        if !coef.is_one() {
            let c = self.num_node(coef);
            consts.push(c);
        }
        out.extend_from_slice(&consts);
        match out.len() {
            0 => self.num_node(Num::ONE),
            1 => out[0],
            _ => {
                sort_canonical(self, &mut out);
                self.intern(View::Mul(&out))
            }
        }
    }

    /// `a · b`.
    pub fn mul2(&mut self, a: Id, b: Id) -> Id {
        self.mul(&[a, b])
    }

    /// `a / b`, as `a · b^-1`.
    pub fn div(&mut self, a: Id, b: Id) -> Id {
        let r = self.recip(b);
        self.mul(&[a, r])
    }

    /// `1 / a`, as `a^-1`.
    pub fn recip(&mut self, a: Id) -> Id {
        self.pow(a, -1)
    }

    /// Integer power `a^n`.
    pub fn pow(&mut self, a: Id, n: i32) -> Id {
        let rules = self.rules;
        if rules.has(RuleSet::IDENTITY) {
            if n == 0 {
                return self.num_node(Num::ONE);
            }
            if n == 1 {
                return a;
            }
        }
        if rules.has(RuleSet::FOLD)
            && let Some(v) = self.num(a).and_then(|x| x.powi(n))
        {
            return self.num_node(v);
        }
        if rules.has(RuleSet::POWERS) {
            match self.view(a) {
                View::Pow(b, m) => {
                    if let Some(k) = m.checked_mul(n) {
                        return self.pow(b, k);
                    }
                }
                View::Mul(cs) => {
                    let cs = cs.to_vec();
                    let ps: Vec<Id> = cs.iter().map(|&c| self.pow(c, n)).collect();
                    return self.mul(&ps);
                }
                View::Sqrt(b) if n % 2 == 0 => return self.pow(b, n / 2),
                View::Abs(b) if n % 2 == 0 => return self.pow(b, n),
                _ => {}
            }
        }
        self.intern(View::Pow(a, n))
    }

    // ---- functions -------------------------------------------------------

    /// Is `x` "negative" on a key that negation flips exactly: a negative
    /// constant, a product with a negative coefficient, or a sum whose term
    /// with the smallest factor list has a negative coefficient.
    pub(crate) fn is_negative_leading(&self, x: Id) -> bool {
        match self.view(x) {
            View::Num(n) => n.is_negative(),
            View::Mul(cs) => self.num(cs[0]).is_some_and(|c| c.is_negative()),
            View::Add(cs)
                if self.rules.has(RuleSet::DISTRIBUTE) && cs.len() <= self.flatten_limit =>
            {
                let lead = cs
                    .iter()
                    .map(|&c| self.term_of(c))
                    .min_by(|a, b| self.canonical_cmp_slices(&a.fs, &b.fs));
                lead.is_some_and(|t| t.coef.is_negative())
            }
            _ => false,
        }
    }

    fn fold1(&mut self, a: Id, f: fn(f64) -> f64) -> Option<Id> {
        if !self.rules.has(RuleSet::FOLD) {
            return None;
        }
        let v = self.num(a)?.map(f)?;
        Some(self.num_node(v))
    }

    fn neg_arg(&mut self, a: Id) -> Option<Id> {
        let on = self.rules.has(RuleSet::SIGN | RuleSet::FOLD);
        (on && self.is_negative_leading(a)).then(|| self.neg(a))
    }

    /// `sqrt(a)`.
    pub fn sqrt(&mut self, a: Id) -> Id {
        if self.rules.has(RuleSet::FOLD)
            && let Some(v) = self.num(a).and_then(Num::sqrt)
        {
            return self.num_node(v);
        }
        if self.rules.has(RuleSet::POWERS)
            && let View::Pow(b, n) = self.view(a)
            && n % 2 == 0
        {
            let ab = self.abs(b);
            return self.pow(ab, n / 2);
        }
        self.intern(View::Sqrt(a))
    }

    /// `sin(a)`.
    pub fn sin(&mut self, a: Id) -> Id {
        if let Some(v) = self.fold1(a, f64::sin) {
            return v;
        }
        if let Some(m) = self.neg_arg(a) {
            let s = self.sin(m);
            return self.neg(s);
        }
        self.intern(View::Sin(a))
    }

    /// `cos(a)`.
    pub fn cos(&mut self, a: Id) -> Id {
        if let Some(v) = self.fold1(a, f64::cos) {
            return v;
        }
        if let Some(m) = self.neg_arg(a) {
            return self.cos(m);
        }
        self.intern(View::Cos(a))
    }

    /// `tan(a)`.
    pub fn tan(&mut self, a: Id) -> Id {
        if let Some(v) = self.fold1(a, f64::tan) {
            return v;
        }
        if let Some(m) = self.neg_arg(a) {
            let s = self.tan(m);
            return self.neg(s);
        }
        self.intern(View::Tan(a))
    }

    /// `atan2(y, x)`.
    pub fn atan2(&mut self, y: Id, x: Id) -> Id {
        if self.rules.has(RuleSet::FOLD)
            && let (Some(a), Some(b)) = (self.num(y), self.num(x))
            && let Some(v) = a.map(|a| a.atan2(b.to_f64()))
        {
            return self.num_node(v);
        }
        self.intern(View::Atan2(y, x))
    }

    /// `exp(a)`.
    pub fn exp(&mut self, a: Id) -> Id {
        if let Some(v) = self.fold1(a, f64::exp) {
            return v;
        }
        if self.rules.has(RuleSet::ELEMENTARY)
            && let View::Ln(b) = self.view(a)
        {
            return b;
        }
        self.intern(View::Exp(a))
    }

    /// `ln(a)` (natural logarithm).
    pub fn ln(&mut self, a: Id) -> Id {
        if let Some(v) = self.fold1(a, f64::ln) {
            return v;
        }
        if self.rules.has(RuleSet::ELEMENTARY)
            && let View::Exp(b) = self.view(a)
        {
            return b;
        }
        self.intern(View::Ln(a))
    }

    /// `|a|`.
    pub fn abs(&mut self, a: Id) -> Id {
        if let Some(v) = self.fold1(a, f64::abs) {
            return v;
        }
        if let Some(m) = self.neg_arg(a) {
            return self.abs(m);
        }
        if self.rules.has(RuleSet::ELEMENTARY) {
            match self.view(a) {
                View::Abs(_) | View::Sqrt(_) | View::Exp(_) => return a,
                View::Pow(_, n) if n % 2 == 0 => return a,
                _ => {}
            }
        }
        self.intern(View::Abs(a))
    }

    /// `if c > 0 { a } else { b }`.
    pub fn select(&mut self, c: Id, a: Id, b: Id) -> Id {
        if self.rules.has(RuleSet::IDENTITY) && a == b {
            return a;
        }
        if self.rules.has(RuleSet::FOLD)
            && let Some(n) = self.num(c)
        {
            return if n.to_f64() > 0.0 { a } else { b };
        }
        self.intern(View::Select(c, a, b))
    }

    /// Rebuild node `id` through the smart constructors with its children
    /// replaced by `map(child)`.
    pub fn rebuild(&mut self, id: Id, map: impl Fn(Id) -> Id) -> Id {
        match self.view(id) {
            View::Num(_) | View::Sym(_) => id,
            View::Add(cs) => {
                let cs: Vec<Id> = cs.iter().map(|&c| map(c)).collect();
                self.add(&cs)
            }
            View::Mul(cs) => {
                let cs: Vec<Id> = cs.iter().map(|&c| map(c)).collect();
                self.mul(&cs)
            }
            View::Pow(a, n) => self.pow(map(a), n),
            View::Sqrt(a) => self.sqrt(map(a)),
            View::Sin(a) => self.sin(map(a)),
            View::Cos(a) => self.cos(map(a)),
            View::Tan(a) => self.tan(map(a)),
            View::Exp(a) => self.exp(map(a)),
            View::Ln(a) => self.ln(map(a)),
            View::Abs(a) => self.abs(map(a)),
            View::Atan2(y, x) => self.atan2(map(y), map(x)),
            View::Select(c, a, b) => self.select(map(c), map(a), map(b)),
        }
    }
}
