//! Numeric constants: exact small rationals, falling back to `f64`.
//!
//! Coefficients such as `1/2` or `1/12` (inertia of a rod) must stay exact so
//! that `x/2 + x/2` collects to exactly `x`. A [`Num`] is either a reduced
//! rational `p/q` with `i32` numerator and positive `i32` denominator, or a
//! finite-or-not `f64`. Arithmetic on two rationals is exact whenever the
//! result still fits; otherwise it is done in `f64`. A float that happens to be
//! a small dyadic rational (an integer, `0.5`, `0.375`, …) is normalised back
//! to a rational, so `Num::from_f64(2.0) == Num::int(2)`.
//!
//! Folding policy: an operation on constants is folded only when its result is
//! finite. Division by an exact zero, `sqrt` of a negative number or `ln` of a
//! non-positive number are *not* folded; the node stays symbolic and evaluates
//! to the IEEE result (inf/NaN) at run time. So folding never silently creates
//! a NaN or an infinity.

use std::cmp::Ordering;
use std::fmt;

/// A numeric constant: an exact reduced rational or an `f64`.
#[derive(Clone, Copy, Debug)]
pub enum Num {
    /// `p / q` with `q > 0` and `gcd(p, q) = 1`.
    Rat(i32, i32),
    /// A float that is not a small dyadic rational.
    Float(f64),
}

impl PartialEq for Num {
    fn eq(&self, other: &Self) -> bool {
        match (*self, *other) {
            (Num::Rat(a, b), Num::Rat(c, d)) => a == c && b == d,
            (Num::Float(a), Num::Float(b)) => a.to_bits() == b.to_bits(),
            _ => false,
        }
    }
}
impl Eq for Num {}

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

impl Num {
    /// Exact zero.
    pub const ZERO: Num = Num::Rat(0, 1);
    /// Exact one.
    pub const ONE: Num = Num::Rat(1, 1);
    /// Exact minus one.
    pub const MINUS_ONE: Num = Num::Rat(-1, 1);

    /// An exact integer.
    pub fn int(n: i32) -> Num {
        Num::Rat(n, 1)
    }

    /// An exact rational `p/q`, reduced; `None` if `q == 0` or it does not fit.
    pub fn ratio(p: i64, q: i64) -> Option<Num> {
        Num::ratio_wide(p as i128, q as i128)
    }

    /// [`Num::ratio`] on 128-bit integers (no intermediate overflow).
    fn ratio_wide(p: i128, q: i128) -> Option<Num> {
        if q == 0 {
            return None;
        }
        let g = gcd(p, q).max(1);
        let (mut p, mut q) = (p / g, q / g);
        if q < 0 {
            p = -p;
            q = -q;
        }
        match (i32::try_from(p), i32::try_from(q)) {
            (Ok(p), Ok(q)) => Some(Num::Rat(p, q)),
            _ => None,
        }
    }

    /// A constant from an `f64`; small dyadic rationals (integers, halves,
    /// quarters, … up to `2^-20`) become exact rationals.
    pub fn from_f64(x: f64) -> Num {
        if x.is_finite() && x.abs() < 2147483647.0 {
            let mut scaled = x;
            let mut den: i64 = 1;
            while den <= 1 << 20 {
                if scaled == scaled.trunc()
                    && scaled.abs() < 2147483647.0
                    && let Some(n) = Num::ratio(scaled as i64, den)
                {
                    return n;
                }
                scaled *= 2.0;
                den *= 2;
            }
        }
        Num::Float(x)
    }

    /// The value as `f64` (`p as f64 / q as f64` for rationals).
    pub fn to_f64(self) -> f64 {
        match self {
            Num::Rat(p, q) => p as f64 / q as f64,
            Num::Float(x) => x,
        }
    }

    /// Is this exactly zero?
    pub fn is_zero(self) -> bool {
        self == Num::ZERO
    }
    /// Is this exactly one?
    pub fn is_one(self) -> bool {
        self == Num::ONE
    }
    /// Is this strictly negative?
    pub fn is_negative(self) -> bool {
        self.to_f64() < 0.0
    }
    /// Is this an exact integer? Returns it.
    pub fn as_int(self) -> Option<i32> {
        match self {
            Num::Rat(p, 1) => Some(p),
            _ => None,
        }
    }

    /// Keep a float result only if it is finite (see the folding policy).
    fn finite(x: f64) -> Option<Num> {
        x.is_finite().then(|| Num::from_f64(x))
    }

    /// `self + other`, exact for rationals when it fits.
    pub fn checked_add(self, other: Num) -> Option<Num> {
        if let (Num::Rat(a, b), Num::Rat(c, d)) = (self, other) {
            let (a, b, c, d) = (a as i128, b as i128, c as i128, d as i128);
            if let Some(n) = Num::ratio_wide(a * d + c * b, b * d) {
                return Some(n);
            }
        }
        Num::finite(self.to_f64() + other.to_f64())
    }

    /// `self * other`, exact for rationals when it fits.
    pub fn checked_mul(self, other: Num) -> Option<Num> {
        if let (Num::Rat(a, b), Num::Rat(c, d)) = (self, other)
            && let Some(n) = Num::ratio_wide(a as i128 * c as i128, b as i128 * d as i128)
        {
            return Some(n);
        }
        Num::finite(self.to_f64() * other.to_f64())
    }

    /// `-self` (always exact).
    pub fn negated(self) -> Num {
        match self {
            Num::Rat(p, q) => {
                Num::ratio(-(p as i64), q as i64).unwrap_or(Num::Float(-self.to_f64()))
            }
            Num::Float(x) => Num::Float(-x),
        }
    }

    /// `1 / self`; `None` for zero (never folded, see module docs).
    pub fn recip(self) -> Option<Num> {
        match self {
            Num::Rat(0, _) => None,
            Num::Rat(p, q) => {
                Num::ratio(q as i64, p as i64).or_else(|| Num::finite(q as f64 / p as f64))
            }
            Num::Float(x) => Num::finite(1.0 / x),
        }
    }

    /// `self ^ n` for an integer `n`; exact for rationals when it fits,
    /// `None` for `0^n` with `n < 0` or a non-finite result.
    pub fn powi(self, n: i32) -> Option<Num> {
        if n < 0 {
            return self.recip()?.powi(n.checked_neg()?);
        }
        let mut acc = Num::ONE;
        let mut base = self;
        let mut e = n as u32;
        while e > 0 {
            if e & 1 == 1 {
                acc = acc.checked_mul(base)?;
            }
            e >>= 1;
            if e > 0 {
                base = base.checked_mul(base)?;
            }
        }
        Some(acc)
    }

    /// Apply an `f64` function, keeping the result only if finite.
    pub fn map(self, f: impl Fn(f64) -> f64) -> Option<Num> {
        Num::finite(f(self.to_f64()))
    }

    /// Exact square root of a rational perfect square (`sqrt(9/4) = 3/2`),
    /// else the `f64` square root if finite.
    pub fn sqrt(self) -> Option<Num> {
        if self.is_negative() {
            return None;
        }
        if let Num::Rat(p, q) = self {
            let (sp, sq) = (
                (p as f64).sqrt().round() as i64,
                (q as f64).sqrt().round() as i64,
            );
            if sp * sp == p as i64 && sq * sq == q as i64 {
                return Num::ratio(sp, sq);
            }
        }
        Num::finite(self.to_f64().sqrt())
    }

    /// A total order used for canonical sorting (by value, then exactness).
    pub fn total_cmp(self, other: Num) -> Ordering {
        self.to_f64()
            .total_cmp(&other.to_f64())
            .then_with(|| matches!(self, Num::Float(_)).cmp(&matches!(other, Num::Float(_))))
    }
}

impl fmt::Display for Num {
    /// Rationals print as `3`, `-1/2`; floats use Rust's shortest round-trip
    /// form (`0.1`, `1e-7`), so printing then parsing gives the same bits.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Num::Rat(p, 1) => write!(f, "{p}"),
            Num::Rat(p, q) => write!(f, "{p}/{q}"),
            Num::Float(x) => write!(f, "{x:?}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_are_exact() {
        let h = Num::ratio(1, 2).unwrap();
        assert_eq!(h.checked_add(h), Some(Num::ONE), "1/2 + 1/2");
        assert_eq!(Num::from_f64(0.5), h);
        assert_eq!(Num::from_f64(-3.0), Num::int(-3));
        assert!(matches!(Num::from_f64(0.1), Num::Float(_)));
    }

    #[test]
    fn twelfths_are_exact() {
        let a = Num::ratio(1, 12).unwrap();
        let got = a.checked_mul(Num::int(12)).unwrap();
        assert_eq!(got, Num::ONE, "got {got} want 1");
        assert_eq!(
            Num::ratio(1, 3)
                .unwrap()
                .checked_add(Num::ratio(1, 6).unwrap()),
            Num::ratio(1, 2)
        );
    }

    #[test]
    fn no_silent_nonfinite() {
        assert_eq!(Num::ZERO.recip(), None);
        assert_eq!(Num::ZERO.powi(-2), None);
        assert_eq!(Num::int(-4).sqrt(), None);
        assert_eq!(Num::Float(1e300).checked_mul(Num::Float(1e300)), None);
        assert_eq!(Num::ratio(9, 4).unwrap().sqrt(), Num::ratio(3, 2));
    }

    #[test]
    fn overflow_falls_back_to_float() {
        let big = Num::int(i32::MAX);
        let got = big.checked_mul(big).unwrap();
        assert!(matches!(got, Num::Float(_)), "got {got:?}");
        assert_eq!(got.to_f64(), (i32::MAX as f64).powi(2));
    }

    #[test]
    fn extremes_do_not_overflow() {
        let (max, min) = (Num::int(i32::MAX), Num::int(i32::MIN));
        let h = Num::ratio(1, i32::MAX as i64).unwrap();
        for (a, b) in [(max, max), (min, min), (min, max), (h, min), (min, h)] {
            let want = a.to_f64() + b.to_f64();
            let got = a.checked_add(b).unwrap().to_f64();
            assert!(
                (got - want).abs() <= 1e-15 * want.abs(),
                "{a} + {b}: got {got} want {want}"
            );
            let want = a.to_f64() * b.to_f64();
            let got = a.checked_mul(b).unwrap().to_f64();
            assert!(
                (got - want).abs() <= 1e-15 * want.abs(),
                "{a} * {b}: got {got} want {want}"
            );
        }
        assert_eq!(Num::ratio(i64::MIN, -1), None);
        assert_eq!(min.negated(), Num::Float(2147483648.0));
    }

    #[test]
    fn display_round_trips() {
        for n in [
            Num::int(3),
            Num::ratio(-1, 2).unwrap(),
            Num::Float(0.1),
            Num::Float(1e-7),
        ] {
            let s = n.to_string();
            let back = if let Some((p, q)) = s.split_once('/') {
                Num::ratio(p.parse().unwrap(), q.parse().unwrap()).unwrap()
            } else {
                Num::from_f64(s.parse().unwrap())
            };
            assert_eq!(back, n, "printed {s}");
        }
    }
}
