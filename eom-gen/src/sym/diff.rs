//! Symbolic derivatives: partial derivatives (memoised per node and
//! variable), Jacobians, and total time derivatives along `q̇`, `u̇`.
//!
//! One forward-mode sweep does both: a *seed* gives the derivative of each
//! symbol (`δ_{s,v}` for a partial derivative, the symbol's rate for a time
//! derivative), and every node's derivative is built from its children's
//! in ascending id order (no recursion, so deep graphs are fine). Nodes whose
//! children all have derivative zero get zero without building anything.
//!
//! Rules: sum, product (`Σ_i c_i' Π_{j≠i} c_j`), power `(x^n)' = n x^(n-1) x'`,
//! `sqrt' = x'/(2 sqrt x)`, `sin' = cos·x'`, `cos' = −sin·x'`,
//! `tan' = (1 + tan²)·x'`, `exp' = exp·x'`, `ln' = x'/x`,
//! `atan2(y, x)' = (x y' − y x')/(x² + y²)`. Non-smooth nodes use their
//! derivative away from the kink: `|x|' = select(x, x', −x')` and
//! `select(c, a, b)' = select(c, a', b')` (the condition is treated as
//! locally constant).

use super::arena::{Arena, SymError};
use super::node::{Id, SymId, SymKind, View};
use super::num::Num;
use rustc_hash::FxHashMap;

type Seed<'s> = dyn FnMut(&mut Arena, SymId) -> Result<Id, SymError> + 's;

/// Forward-mode derivative of `root` with the given seed and memo table.
fn derive(
    arena: &mut Arena,
    root: Id,
    seed: &mut Seed<'_>,
    memo: &mut FxHashMap<Id, Id>,
) -> Result<Id, SymError> {
    if let Some(&d) = memo.get(&root) {
        return Ok(d);
    }
    let zero = arena.num_node(Num::ZERO);
    let order = arena.reachable(&[root], |id| memo.contains_key(&id));
    for id in order {
        if memo.contains_key(&id) {
            continue;
        }
        let d = |c: Id| memo[&c];
        let v = arena.view(id);
        if !matches!(v, View::Sym(_)) && v.children().all(|c| d(c) == zero) {
            memo.insert(id, zero);
            continue;
        }
        let out = match v {
            View::Num(_) => zero,
            View::Sym(s) => seed(arena, s)?,
            View::Add(cs) => {
                let ds: Vec<Id> = cs.iter().map(|&c| d(c)).filter(|&x| x != zero).collect();
                arena.add(&ds)
            }
            View::Mul(cs) => {
                let cs = cs.to_vec();
                let mut terms = Vec::new();
                for i in 0..cs.len() {
                    let di = d(cs[i]);
                    if di == zero {
                        continue;
                    }
                    let mut fs: Vec<Id> = cs
                        .iter()
                        .enumerate()
                        .filter(|&(j, _)| j != i)
                        .map(|(_, &c)| c)
                        .collect();
                    fs.push(di);
                    terms.push(arena.mul(&fs));
                }
                arena.add(&terms)
            }
            View::Pow(x, n) => {
                let dx = d(x);
                let k = arena.num_node(Num::int(n));
                let p = arena.pow(x, n - 1);
                arena.mul(&[k, p, dx])
            }
            View::Sqrt(x) => {
                let dx = d(x);
                let half = arena.num_node(Num::Rat(1, 2));
                let r = arena.recip(id);
                arena.mul(&[half, r, dx])
            }
            View::Sin(x) => {
                let dx = d(x);
                let c = arena.cos(x);
                arena.mul(&[c, dx])
            }
            View::Cos(x) => {
                let dx = d(x);
                let s = arena.sin(x);
                let m = arena.num_node(Num::MINUS_ONE);
                arena.mul(&[m, s, dx])
            }
            View::Tan(x) => {
                let dx = d(x);
                let t2 = arena.pow(id, 2);
                let one = arena.num_node(Num::ONE);
                let f = arena.add(&[one, t2]);
                arena.mul(&[f, dx])
            }
            View::Exp(x) => {
                let dx = d(x);
                arena.mul(&[id, dx])
            }
            View::Ln(x) => {
                let dx = d(x);
                arena.div(dx, x)
            }
            View::Abs(x) => {
                let dx = d(x);
                let ndx = arena.neg(dx);
                arena.select(x, dx, ndx)
            }
            View::Atan2(y, x) => {
                let (dy, dx) = (d(y), d(x));
                let a = arena.mul(&[x, dy]);
                let b = arena.mul(&[y, dx]);
                let num = arena.sub(a, b);
                let x2 = arena.pow(x, 2);
                let y2 = arena.pow(y, 2);
                let den = arena.add(&[x2, y2]);
                arena.div(num, den)
            }
            View::Select(c, a, b) => {
                let (da, db) = (d(a), d(b));
                arena.select(c, da, db)
            }
        };
        memo.insert(id, out);
    }
    Ok(memo[&root])
}

impl Arena {
    /// Partial derivative `∂e/∂s`, memoised per `(node, s)` for the life of
    /// the arena (repeated and overlapping requests reuse earlier work).
    pub fn diff(&mut self, e: Id, s: SymId) -> Id {
        let mut memo = self.diff_memo.remove(&s).unwrap_or_default();
        let one = self.num_node(Num::ONE);
        let zero = self.num_node(Num::ZERO);
        let mut seed = |_: &mut Arena, v: SymId| -> Result<Id, SymError> {
            Ok(if v == s { one } else { zero })
        };
        let d =
            derive(self, e, &mut seed, &mut memo).expect("partial derivative seeds cannot fail");
        self.diff_memo.insert(s, memo);
        d
    }

    /// Gradient `[∂e/∂v for v in vars]`.
    pub fn gradient(&mut self, e: Id, vars: &[SymId]) -> Vec<Id> {
        vars.iter().map(|&v| self.diff(e, v)).collect()
    }

    /// Jacobian `J[i][j] = ∂es[i]/∂vars[j]` (row-major).
    pub fn jacobian(&mut self, es: &[Id], vars: &[SymId]) -> Vec<Vec<Id>> {
        es.iter().map(|&e| self.gradient(e, vars)).collect()
    }
}

/// Total time derivative `d/dt` along given rates, memoised across calls.
///
/// Default rates: `q_i → qd_i`, `u_i → ud_i`, `t → 1`, parameters and inputs
/// → 0. `qd_i` and `ud_i` have no default (asking for one is
/// [`SymError::NoRate`]); give rates explicitly with [`TimeDerivative::rate`]
/// (e.g. `q̇ = u` for revolute joints, or quaternion kinematics).
#[derive(Clone, Debug, Default)]
pub struct TimeDerivative {
    rates: FxHashMap<SymId, Id>,
    memo: FxHashMap<Id, Id>,
}

impl TimeDerivative {
    /// Default rates only.
    pub fn new() -> TimeDerivative {
        TimeDerivative::default()
    }

    /// Use `rate` as the time derivative of symbol `s`. Clears the memo.
    pub fn rate(&mut self, s: SymId, rate: Id) -> &mut TimeDerivative {
        self.rates.insert(s, rate);
        self.memo.clear();
        self
    }

    /// `de/dt`.
    pub fn apply(&mut self, arena: &mut Arena, e: Id) -> Result<Id, SymError> {
        let rates = &self.rates;
        let mut seed = |a: &mut Arena, s: SymId| -> Result<Id, SymError> {
            if let Some(&r) = rates.get(&s) {
                return Ok(r);
            }
            Ok(match a.symbol(s).kind {
                SymKind::Coord(i) => a.qd(i),
                SymKind::Speed(i) => a.ud(i),
                SymKind::Time => a.num_node(Num::ONE),
                SymKind::Param | SymKind::Input | SymKind::Tau(_) | SymKind::Multiplier(_) => {
                    a.num_node(Num::ZERO)
                }
                SymKind::CoordRate(_) | SymKind::SpeedRate(_) => {
                    return Err(SymError::NoRate(a.symbol(s).name.clone()));
                }
            })
        };
        derive(arena, e, &mut seed, &mut self.memo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(src: &str, var: &str) -> String {
        let mut a = Arena::new();
        let e = a.parse(src).unwrap();
        let v = a.find_symbol(var).unwrap();
        let de = a.diff(e, v);
        a.to_sexpr_string(de)
    }

    fn same(src: &str, var: &str, want: &str) {
        let mut a = Arena::new();
        let e = a.parse(src).unwrap();
        let w = a.parse(want).unwrap();
        let vn = a.sym_named(var).unwrap();
        let v = a.as_sym(vn).unwrap();
        let got = a.diff(e, v);
        assert_eq!(
            got,
            w,
            "d/d{var} {src}: got {} want {}",
            a.display(got),
            a.display(w)
        );
    }

    #[test]
    fn pinned_derivatives() {
        same("(sin x)", "x", "(cos x)");
        same("(cos x)", "x", "(- (sin x))");
        same("(^ x 3)", "x", "(* 3 (^ x 2))");
        same("(* a x)", "x", "a");
        same("(* a x)", "y", "0");
        same("(ln x)", "x", "(/ x)");
        same("(exp (* 2 x))", "x", "(* 2 (exp (* 2 x)))");
        same("(sqrt x)", "x", "(* 1/2 (/ (sqrt x)))");
        same("(+ (sin (+ q1 q2)) q1)", "q2", "(cos (+ q1 q2))");
        assert_eq!(d("(abs x)", "x"), "(select x 1 -1)");
    }

    #[test]
    fn memoised() {
        let mut a = Arena::new();
        let e = a.parse("(* (sin x) (cos y) (exp x))").unwrap();
        let x = a.find_symbol("x").unwrap();
        let d1 = a.diff(e, x);
        let n = a.len();
        let d2 = a.diff(e, x);
        assert_eq!(d1, d2);
        assert_eq!(a.len(), n, "second request builds nothing");
    }

    #[test]
    fn time_derivative_of_pendulum_position() {
        let mut a = Arena::new();
        let x = a.parse("(* l (sin q0))").unwrap();
        let q0 = a.find_symbol("q0").unwrap();
        let mut td = TimeDerivative::new();
        let v = td.apply(&mut a, x).unwrap();
        let want = a.parse("(* l (cos q0) qd0)").unwrap();
        assert_eq!(v, want, "got {} want {}", a.display(v), a.display(want));
        // with q̇ = u, twice
        let u0 = a.u(0);
        td.rate(q0, u0);
        let v = td.apply(&mut a, x).unwrap();
        let acc = td.apply(&mut a, v).unwrap();
        let want = a
            .parse("(- (* l (cos q0) ud0) (* l (sin q0) (^ u0 2)))")
            .unwrap();
        assert_eq!(acc, want, "got {} want {}", a.display(acc), a.display(want));
        let qd = a.qd(0);
        assert_eq!(td.apply(&mut a, qd), Err(SymError::NoRate("qd0".into())));
    }
}
