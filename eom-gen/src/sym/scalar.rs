//! The scalar abstraction: write a recursive algorithm once, run it on `f64`
//! (reference numerics) and on [`Expr`](super::Expr) (code generation).
//!
//! Constants are made without a context (`S::from_f64(9.81)`, `S::zero()`),
//! so generic code needs no handle to an arena; a symbolic constant only
//! enters an arena when it meets a symbolic operand.

use std::fmt::Debug;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A real scalar: `f64` or a symbolic expression.
///
/// Semantics follow `f64`: `select(c, a, b)` is `if c > 0 { a } else { b }`,
/// `powi` is an integer power, `atan2` is the four-quadrant arctangent of
/// `self / x`.
pub trait Scalar:
    Copy
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// A constant (small dyadic rationals are exact for symbolic scalars).
    fn from_f64(x: f64) -> Self;
    /// The rational `p/q`, exact for symbolic scalars (`1/12` of a rod's inertia).
    fn from_ratio(p: i32, q: i32) -> Self;
    /// 0.
    fn zero() -> Self {
        Self::from_f64(0.0)
    }
    /// 1.
    fn one() -> Self {
        Self::from_f64(1.0)
    }
    /// Sine.
    fn sin(self) -> Self;
    /// Cosine.
    fn cos(self) -> Self;
    /// Sine and cosine together.
    fn sin_cos(self) -> (Self, Self) {
        (self.sin(), self.cos())
    }
    /// Tangent.
    fn tan(self) -> Self;
    /// Four-quadrant arctangent of `self / x`.
    fn atan2(self, x: Self) -> Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Exponential.
    fn exp(self) -> Self;
    /// Natural logarithm.
    fn ln(self) -> Self;
    /// Absolute value.
    fn abs(self) -> Self;
    /// Integer power.
    fn powi(self, n: i32) -> Self;
    /// `if cond > 0 { a } else { b }`.
    fn select(cond: Self, a: Self, b: Self) -> Self;
    /// Is this exactly (structurally, for expressions) zero? Algorithms may
    /// skip work on exact zeros.
    fn is_zero(&self) -> bool;
    /// Is this exactly (structurally) one?
    fn is_one(&self) -> bool;
}

impl Scalar for f64 {
    fn from_f64(x: f64) -> f64 {
        x
    }
    fn from_ratio(p: i32, q: i32) -> f64 {
        p as f64 / q as f64
    }
    fn sin(self) -> f64 {
        f64::sin(self)
    }
    fn cos(self) -> f64 {
        f64::cos(self)
    }
    fn sin_cos(self) -> (f64, f64) {
        f64::sin_cos(self)
    }
    fn tan(self) -> f64 {
        f64::tan(self)
    }
    fn atan2(self, x: f64) -> f64 {
        f64::atan2(self, x)
    }
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    fn exp(self) -> f64 {
        f64::exp(self)
    }
    fn ln(self) -> f64 {
        f64::ln(self)
    }
    fn abs(self) -> f64 {
        f64::abs(self)
    }
    fn powi(self, n: i32) -> f64 {
        f64::powi(self, n)
    }
    fn select(cond: f64, a: f64, b: f64) -> f64 {
        super::eval::ops::select(cond, a, b)
    }
    fn is_zero(&self) -> bool {
        *self == 0.0
    }
    fn is_one(&self) -> bool {
        *self == 1.0
    }
}
