//! [`Expr`]: a `Copy` expression handle with arithmetic operators, for
//! generic algorithms.
//!
//! Design: a [`Context`] owns the [`Arena`] in a `RefCell`; an `Expr<'cx>`
//! is either a context-free constant or a node id plus `&'cx Context`.
//! Operators borrow the arena mutably only for the duration of one smart
//! constructor call, so handles can be freely copied, stored in
//! `Vec3`/`Mat3`, and combined with `+ - * /`. The lifetime ties handles to
//! their context (no `Rc`, no thread-local state, several contexts can
//! coexist; mixing handles of two contexts panics).
//!
//! Constants without a context (`Expr::from_f64`, `Scalar::zero()`) fold
//! among themselves with exact rational arithmetic; an operation on two
//! constants whose result is not finite (`1/0`) falls back to the IEEE
//! `f64` result, since there is no arena to keep it symbolic. `0·x`, `1·x`,
//! `0 + x` short-cut without touching the arena, so structural zeros of
//! vectors and matrices cost nothing.
//!
//! For bulk work prefer the `&mut Arena` methods on [`Id`]s (no `RefCell`).

use super::arena::{Arena, SymError};
use super::diff::TimeDerivative;
use super::node::{Id, SymId};
use super::num::Num;
use super::program::{LowerOptions, Program};
use super::rules::RuleSet;
use super::scalar::Scalar;
use std::cell::{Ref, RefCell, RefMut};
use std::fmt;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Owner of an arena for [`Expr`] handles.
#[derive(Default)]
pub struct Context {
    arena: RefCell<Arena>,
}

/// A symbolic scalar: a constant, or a node of a [`Context`].
#[derive(Clone, Copy)]
pub enum Expr<'cx> {
    /// A constant not (yet) in any arena.
    Const(Num),
    /// A node of a context's arena.
    Node(Id, &'cx Context),
}

impl Context {
    /// A context with all simplification rules on.
    pub fn new() -> Context {
        Context::default()
    }
    /// A context with the given construction rules.
    pub fn with_rules(rules: RuleSet) -> Context {
        Context::from_arena(Arena::with_rules(rules))
    }
    /// Wrap an existing arena.
    pub fn from_arena(arena: Arena) -> Context {
        Context {
            arena: RefCell::new(arena),
        }
    }
    /// Take the arena back.
    pub fn into_arena(self) -> Arena {
        self.arena.into_inner()
    }
    /// Borrow the arena.
    pub fn arena(&self) -> Ref<'_, Arena> {
        self.arena.borrow()
    }
    /// Borrow the arena mutably (do not hold across `Expr` operations).
    pub fn arena_mut(&self) -> RefMut<'_, Arena> {
        self.arena.borrow_mut()
    }
    /// The handle of node `id`.
    pub fn expr(&self, id: Id) -> Expr<'_> {
        Expr::Node(id, self)
    }
    /// The node id of `e`, interning a constant if needed.
    pub fn id(&self, e: Expr<'_>) -> Id {
        match e {
            Expr::Const(n) => self.arena_mut().num_node(n),
            Expr::Node(id, cx) => {
                assert!(std::ptr::eq(cx, self), "expression from another context");
                id
            }
        }
    }
    /// Coordinate `q_i`.
    pub fn q(&self, i: u32) -> Expr<'_> {
        let id = self.arena_mut().q(i);
        self.expr(id)
    }
    /// Speed `u_i`.
    pub fn u(&self, i: u32) -> Expr<'_> {
        let id = self.arena_mut().u(i);
        self.expr(id)
    }
    /// Coordinate rate `q̇_i`.
    pub fn qd(&self, i: u32) -> Expr<'_> {
        let id = self.arena_mut().qd(i);
        self.expr(id)
    }
    /// Speed rate `u̇_i`.
    pub fn ud(&self, i: u32) -> Expr<'_> {
        let id = self.arena_mut().ud(i);
        self.expr(id)
    }
    /// Extra generalised force `τ_i`.
    pub fn tau(&self, i: u32) -> Expr<'_> {
        let id = self.arena_mut().tau(i);
        self.expr(id)
    }
    /// Constraint multiplier `λ_i`.
    pub fn multiplier(&self, i: u32) -> Expr<'_> {
        let id = self.arena_mut().multiplier(i);
        self.expr(id)
    }
    /// Time `t`.
    pub fn t(&self) -> Expr<'_> {
        let id = self.arena_mut().t();
        self.expr(id)
    }
    /// A tunable parameter.
    pub fn param(&self, name: &str) -> Result<Expr<'_>, SymError> {
        let id = self.arena_mut().param(name)?;
        Ok(self.expr(id))
    }
    /// An input.
    pub fn input(&self, name: &str) -> Result<Expr<'_>, SymError> {
        let id = self.arena_mut().input(name)?;
        Ok(self.expr(id))
    }
    /// Parse an s-expression.
    pub fn parse(&self, s: &str) -> Result<Expr<'_>, SymError> {
        let id = self.arena_mut().parse(s)?;
        Ok(self.expr(id))
    }
    /// `∂e/∂v`; `v` must be a symbol (a non-symbol gives derivative zero).
    pub fn diff<'a>(&'a self, e: Expr<'a>, v: Expr<'a>) -> Expr<'a> {
        let (e, v) = (self.id(e), self.id(v));
        let mut a = self.arena_mut();
        match a.as_sym(v) {
            Some(s) => {
                let d = a.diff(e, s);
                drop(a);
                self.expr(d)
            }
            None => Expr::Const(Num::ZERO),
        }
    }
    /// Jacobian `J[i][j] = ∂es[i]/∂vars[j]`; each `vars[j]` must be a symbol
    /// (a non-symbol column is zero).
    pub fn jacobian<'a>(&'a self, es: &[Expr<'a>], vars: &[Expr<'a>]) -> Vec<Vec<Expr<'a>>> {
        es.iter()
            .map(|&e| vars.iter().map(|&v| self.diff(e, v)).collect())
            .collect()
    }
    /// Total time derivative `de/dt` with the rates of `td` (see [`TimeDerivative`]).
    pub fn time_derivative<'a>(
        &'a self,
        td: &mut TimeDerivative,
        e: Expr<'a>,
    ) -> Result<Expr<'a>, SymError> {
        let id = self.id(e);
        let d = td.apply(&mut self.arena_mut(), id)?;
        Ok(self.expr(d))
    }
    /// Lower named outputs to a [`Program`].
    pub fn lower(&self, outputs: &[(&str, Expr<'_>)], opts: LowerOptions) -> Program {
        let ids: Vec<(&str, Id)> = outputs.iter().map(|&(n, e)| (n, self.id(e))).collect();
        self.arena().lower(&ids, opts)
    }
    /// Evaluate with values per symbol id (see [`Arena::eval`]).
    pub fn eval(&self, e: Expr<'_>, values: &[f64]) -> f64 {
        match e {
            Expr::Const(n) => n.to_f64(),
            Expr::Node(id, _) => self.arena().eval(id, values),
        }
    }
    /// The symbol id of a symbol expression.
    pub fn sym_id(&self, e: Expr<'_>) -> Option<SymId> {
        match e {
            Expr::Node(id, _) => self.arena().as_sym(id),
            Expr::Const(_) => None,
        }
    }
}

impl<'cx> Expr<'cx> {
    /// The node id, if this is a node.
    pub fn id(self) -> Option<Id> {
        match self {
            Expr::Node(id, _) => Some(id),
            Expr::Const(_) => None,
        }
    }
    /// The constant value, if this is a constant (in or out of an arena).
    pub fn as_num(self) -> Option<Num> {
        match self {
            Expr::Const(n) => Some(n),
            Expr::Node(id, cx) => cx.arena().num(id),
        }
    }

    fn cx(self) -> Option<&'cx Context> {
        match self {
            Expr::Node(_, cx) => Some(cx),
            Expr::Const(_) => None,
        }
    }

    /// Apply a unary smart constructor (or fold a free constant).
    fn unary(
        self,
        fold: impl Fn(Num) -> Option<Num>,
        raw: fn(f64) -> f64,
        build: fn(&mut Arena, Id) -> Id,
    ) -> Expr<'cx> {
        match self {
            Expr::Const(n) => Expr::Const(fold(n).unwrap_or(Num::Float(raw(n.to_f64())))),
            Expr::Node(id, cx) => {
                let r = build(&mut cx.arena_mut(), id);
                Expr::Node(r, cx)
            }
        }
    }

    /// Apply an n-ary smart constructor to handles, at least one of them a node.
    fn nary(xs: &[Expr<'cx>], build: impl FnOnce(&mut Arena, &[Id]) -> Id) -> Option<Expr<'cx>> {
        let cx = xs.iter().find_map(|x| x.cx())?;
        let mut a = cx.arena_mut();
        let ids: Vec<Id> = xs
            .iter()
            .map(|x| match *x {
                Expr::Const(n) => a.num_node(n),
                Expr::Node(id, c) => {
                    assert!(std::ptr::eq(c, cx), "expressions from two contexts");
                    id
                }
            })
            .collect();
        let r = build(&mut a, &ids);
        Some(Expr::Node(r, cx))
    }

    fn binary(
        self,
        rhs: Expr<'cx>,
        fold: fn(Num, Num) -> Option<Num>,
        raw: fn(f64, f64) -> f64,
        build: fn(&mut Arena, Id, Id) -> Id,
    ) -> Expr<'cx> {
        match (self, rhs) {
            (Expr::Const(a), Expr::Const(b)) => {
                Expr::Const(fold(a, b).unwrap_or(Num::Float(raw(a.to_f64(), b.to_f64()))))
            }
            _ => Expr::nary(&[self, rhs], |a, ids| build(a, ids[0], ids[1]))
                .expect("one operand is a node"),
        }
    }

    fn is_num(self, n: Num) -> bool {
        matches!(self, Expr::Const(m) if m == n)
    }
}

impl fmt::Display for Expr<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Expr::Const(n) => write!(f, "{n}"),
            Expr::Node(id, cx) => write!(f, "{}", cx.arena().display(id)),
        }
    }
}

impl fmt::Debug for Expr<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl PartialEq for Expr<'_> {
    /// Structural equality (hash-consing makes it an id comparison).
    fn eq(&self, other: &Self) -> bool {
        match (*self, *other) {
            (Expr::Node(a, ca), Expr::Node(b, cb)) => a == b && std::ptr::eq(ca, cb),
            _ => match (self.as_num(), other.as_num()) {
                (Some(a), Some(b)) => a == b,
                _ => false,
            },
        }
    }
}

impl<'cx> Add for Expr<'cx> {
    type Output = Expr<'cx>;
    fn add(self, rhs: Expr<'cx>) -> Expr<'cx> {
        if self.is_num(Num::ZERO) {
            return rhs;
        }
        if rhs.is_num(Num::ZERO) {
            return self;
        }
        self.binary(rhs, Num::checked_add, |a, b| a + b, Arena::add2)
    }
}

impl<'cx> Sub for Expr<'cx> {
    type Output = Expr<'cx>;
    fn sub(self, rhs: Expr<'cx>) -> Expr<'cx> {
        if rhs.is_num(Num::ZERO) {
            return self;
        }
        self.binary(
            rhs,
            |a, b| a.checked_add(b.negated()),
            |a, b| a - b,
            Arena::sub,
        )
    }
}

impl<'cx> Mul for Expr<'cx> {
    type Output = Expr<'cx>;
    fn mul(self, rhs: Expr<'cx>) -> Expr<'cx> {
        if self.is_num(Num::ZERO) || rhs.is_num(Num::ZERO) {
            return Expr::Const(Num::ZERO);
        }
        if self.is_num(Num::ONE) {
            return rhs;
        }
        if rhs.is_num(Num::ONE) {
            return self;
        }
        self.binary(rhs, Num::checked_mul, |a, b| a * b, Arena::mul2)
    }
}

impl<'cx> Div for Expr<'cx> {
    type Output = Expr<'cx>;
    fn div(self, rhs: Expr<'cx>) -> Expr<'cx> {
        if rhs.is_num(Num::ONE) {
            return self;
        }
        self.binary(
            rhs,
            |a, b| a.checked_mul(b.recip()?),
            |a, b| a / b,
            Arena::div,
        )
    }
}

impl<'cx> Neg for Expr<'cx> {
    type Output = Expr<'cx>;
    fn neg(self) -> Expr<'cx> {
        self.unary(|n| Some(n.negated()), |x| -x, Arena::neg)
    }
}

impl<'cx> Scalar for Expr<'cx> {
    fn from_f64(x: f64) -> Self {
        Expr::Const(Num::from_f64(x))
    }
    fn from_ratio(p: i32, q: i32) -> Self {
        Expr::Const(Num::ratio(p as i64, q as i64).unwrap_or(Num::Float(p as f64 / q as f64)))
    }
    fn sin(self) -> Self {
        self.unary(|n| n.map(f64::sin), f64::sin, Arena::sin)
    }
    fn cos(self) -> Self {
        self.unary(|n| n.map(f64::cos), f64::cos, Arena::cos)
    }
    fn tan(self) -> Self {
        self.unary(|n| n.map(f64::tan), f64::tan, Arena::tan)
    }
    fn atan2(self, x: Self) -> Self {
        self.binary(
            x,
            |y, x| y.map(|y| y.atan2(x.to_f64())),
            f64::atan2,
            Arena::atan2,
        )
    }
    fn sqrt(self) -> Self {
        self.unary(Num::sqrt, f64::sqrt, Arena::sqrt)
    }
    fn exp(self) -> Self {
        self.unary(|n| n.map(f64::exp), f64::exp, Arena::exp)
    }
    fn ln(self) -> Self {
        self.unary(|n| n.map(f64::ln), f64::ln, Arena::ln)
    }
    fn abs(self) -> Self {
        self.unary(|n| n.map(f64::abs), f64::abs, Arena::abs)
    }
    fn powi(self, n: i32) -> Self {
        match self {
            Expr::Const(c) => Expr::Const(c.powi(n).unwrap_or(Num::Float(c.to_f64().powi(n)))),
            Expr::Node(id, cx) => {
                let r = cx.arena_mut().pow(id, n);
                Expr::Node(r, cx)
            }
        }
    }
    fn select(cond: Self, a: Self, b: Self) -> Self {
        if let Expr::Const(c) = cond {
            return if c.to_f64() > 0.0 { a } else { b };
        }
        Expr::nary(&[cond, a, b], |ar, ids| ar.select(ids[0], ids[1], ids[2]))
            .expect("condition is a node")
    }
    fn is_zero(&self) -> bool {
        self.as_num() == Some(Num::ZERO)
    }
    fn is_one(&self) -> bool {
        self.as_num() == Some(Num::ONE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn operators_build_canonical_nodes() {
        let cx = Context::new();
        let (q, l) = (cx.q(1), cx.param("l").unwrap());
        let e = Expr::from_f64(2.0) * q.sin() + l;
        assert_eq!(e, cx.parse("(+ (* 2 (sin q1)) l)").unwrap(), "got {e}");
        let s2c2 = q.sin() * q.sin() + q.cos().powi(2);
        assert!(s2c2.is_one(), "got {s2c2} want 1");
    }

    #[test]
    fn jacobian_and_time_derivative_through_the_handle() {
        let cx = Context::new();
        let (q0, q1) = (cx.q(0), cx.q(1));
        let x = q0.cos() * q1;
        let j = cx.jacobian(&[x], &[q0, q1]);
        assert_eq!(
            j[0][0],
            cx.parse("(* -1 q1 (sin q0))").unwrap(),
            "got {}",
            j[0][0]
        );
        assert_eq!(j[0][1], q0.cos());
        let mut td = TimeDerivative::new();
        let v = cx.time_derivative(&mut td, x).unwrap();
        assert_eq!(
            v,
            cx.parse("(- (* qd1 (cos q0)) (* q1 qd0 (sin q0)))")
                .unwrap(),
            "got {v}"
        );
        let dep = cx.arena().depends_on(cx.id(v), cx.sym_id(q1).unwrap());
        assert!(dep);
        let s = cx.sym_id(cx.u(3)).unwrap();
        assert!(!cx.arena().depends_on(cx.id(v), s));
    }

    #[test]
    fn free_constants_fold_exactly() {
        let third = Expr::from_ratio(1, 3);
        let e = third + third + third;
        assert!(e.is_one(), "got {e} want 1");
        let z = Expr::zero() * Expr::from_f64(5.0);
        assert!(z.is_zero());
    }

    #[test]
    fn zero_times_node_does_not_touch_the_arena() {
        let cx = Context::new();
        let q = cx.q(0);
        let n = cx.arena().len();
        let e = Expr::zero() * q.sin().cos() + Expr::zero();
        assert!(e.is_zero());
        // q.sin().cos() was built (2 nodes) but nothing for 0·x or +0
        assert_eq!(cx.arena().len(), n + 2);
    }
}
