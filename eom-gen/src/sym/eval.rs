//! The numeric twin: evaluate expressions on `f64` values.
//!
//! Values of variables are given as a slice indexed by [`SymId`]
//! (`values[s.index()]`); symbols beyond its end evaluate to NaN, so a
//! forgotten input is visible rather than silently zero. Evaluation walks the
//! reachable nodes in ascending id order (children first) without recursion.
//! [`Program::eval`](super::Program::eval) evaluates lowered programs.

use super::arena::Arena;
use super::node::{Id, SymId, View};

/// The IEEE semantics of each operation, shared by expression and program
/// evaluation.
pub(crate) mod ops {
    /// `if c > 0 { a } else { b }` (NaN conditions take `b`).
    pub fn select(c: f64, a: f64, b: f64) -> f64 {
        if c > 0.0 { a } else { b }
    }
}

impl Arena {
    /// Value of one expression.
    pub fn eval(&self, root: Id, values: &[f64]) -> f64 {
        self.eval_many(&[root], values)[0]
    }

    /// Values of several expressions, sharing common subexpressions.
    pub fn eval_many(&self, roots: &[Id], values: &[f64]) -> Vec<f64> {
        let Some(max) = roots.iter().max() else {
            return Vec::new();
        };
        let mut val = vec![f64::NAN; max.index() + 1];
        for id in self.reachable(roots, |_| false) {
            let v = |c: Id| val[c.index()];
            let x = match self.view(id) {
                View::Num(n) => n.to_f64(),
                View::Sym(s) => values.get(s.index()).copied().unwrap_or(f64::NAN),
                View::Add(cs) => cs.iter().map(|&c| v(c)).fold(0.0, |a, b| a + b),
                View::Mul(cs) => cs.iter().map(|&c| v(c)).fold(1.0, |a, b| a * b),
                View::Pow(a, n) => v(a).powi(n),
                View::Sqrt(a) => v(a).sqrt(),
                View::Sin(a) => v(a).sin(),
                View::Cos(a) => v(a).cos(),
                View::Tan(a) => v(a).tan(),
                View::Exp(a) => v(a).exp(),
                View::Ln(a) => v(a).ln(),
                View::Abs(a) => v(a).abs(),
                View::Atan2(y, x) => v(y).atan2(v(x)),
                View::Select(c, a, b) => ops::select(v(c), v(a), v(b)),
            };
            val[id.index()] = x;
        }
        roots.iter().map(|r| val[r.index()]).collect()
    }

    /// A value vector for [`Arena::eval`] from `(name, value)` pairs; symbols
    /// not named get NaN. Unknown names are ignored.
    pub fn values(&self, named: &[(&str, f64)]) -> Vec<f64> {
        let mut v = vec![f64::NAN; self.symbols().len()];
        for &(name, x) in named {
            if let Some(s) = self.find_symbol(name) {
                v[s.index()] = x;
            }
        }
        v
    }

    /// The value vector giving symbol `s` the value `f(s)`.
    pub fn values_with(&self, f: impl Fn(SymId) -> f64) -> Vec<f64> {
        (0..self.symbols().len())
            .map(|i| f(SymId(i as u32)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evaluates_text() {
        let mut a = Arena::new();
        let e = a.parse("(+ (* 2 (sin q1)) l)").unwrap();
        let v = a.values(&[("q1", 0.5), ("l", 3.0)]);
        let got = a.eval(e, &v);
        let want = 2.0 * 0.5f64.sin() + 3.0;
        assert!((got - want).abs() < 1e-15, "got {got} want {want}");
    }

    #[test]
    fn missing_value_is_nan() {
        let mut a = Arena::new();
        let e = a.parse("(+ x 1)").unwrap();
        assert!(a.eval(e, &[]).is_nan());
    }

    #[test]
    fn select_picks_by_sign() {
        let mut a = Arena::new();
        let e = a.parse("(select x 1 2)").unwrap();
        assert_eq!(a.eval(e, &a.values(&[("x", 0.5)])), 1.0);
        assert_eq!(a.eval(e, &a.values(&[("x", 0.0)])), 2.0);
    }
}
