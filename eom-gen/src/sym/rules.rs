//! The construction-time simplification rules as a named set of flags
//! ([`RuleSet`]): which rewrites the arena's smart constructors apply, and
//! what each assumes.

use std::ops::BitOr;

/// A set of construction-time simplification rules (bit flags).
///
/// Rules and what they assume (all rewrites assume real arithmetic on the
/// domain where both sides are defined; "finite" means not inf/NaN):
///
/// | rule | rewrites | assumes |
/// |---|---|---|
/// | `FOLD` | operations on constants; exact for rationals, `f64` otherwise, folded only if the result is finite | — |
/// | `IDENTITY` | `x + 0 = x`, `1·x = x`, `0·x = 0`, `x^0 = 1`, `x^1 = x`, `select(c, a, a) = a` | `0·x = 0`: x finite |
/// | `COLLECT` | like terms `a·x + b·x = (a+b)·x` for numeric `a, b`; so `x - x = 0` | x finite |
/// | `POWERS` | `x^a·x^b = x^(a+b)` (so `x/x = 1`), `(x^a)^b = x^(ab)`, `(xy)^n = x^n y^n`, `sqrt(x)^2k = x^k`, `abs(x)^2k = x^2k`, `sqrt(x^2k) = abs(x)^k` | `x/x = 1`, `x^a x^-a = 1`: x ≠ 0; `sqrt(x)^2 = x`: x ≥ 0 |
/// | `DISTRIBUTE` | numeric coefficient over a sum: `c·(a + b) = c·a + c·b` | — |
/// | `SIGN` | `sin(-x) = -sin x`, `cos(-x) = cos x`, `tan(-x) = -tan x`, `abs(-x) = abs x`; "negative" is decided on a negation-invariant key; acts only together with `FOLD` (and on sums only with `DISTRIBUTE`) so that it terminates | — |
/// | `PYTHAGORAS` | `k sin²x R + k cos²x R = k R`, `k - k sin²x = k cos²x`, `k - k cos²x = k sin²x` | — |
/// | `ANGLE_SUM` | `k cos a cos b R ∓ k sin a sin b R = k cos(a ± b) R`, `k sin a cos b R ± k cos a sin b R = k sin(a ± b) R` | — |
/// | `ELEMENTARY` | `exp(ln x) = x`, `ln(exp x) = x`, `abs(abs x) = abs x`, `abs(sqrt x) = sqrt x`, `abs(exp x) = exp x`, `abs(x^2k) = x^2k` | `exp(ln x) = x`: x > 0 |
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct RuleSet(pub u32);

impl RuleSet {
    /// No simplification: only flattening, canonical order and hash-consing.
    pub const NONE: RuleSet = RuleSet(0);
    /// Constant folding.
    pub const FOLD: RuleSet = RuleSet(1);
    /// 0 and 1 identities.
    pub const IDENTITY: RuleSet = RuleSet(1 << 1);
    /// Like-term collection in sums.
    pub const COLLECT: RuleSet = RuleSet(1 << 2);
    /// Like-factor merging and power rules.
    pub const POWERS: RuleSet = RuleSet(1 << 3);
    /// Numeric coefficients distribute over sums.
    pub const DISTRIBUTE: RuleSet = RuleSet(1 << 4);
    /// Sign normalisation of odd/even functions.
    pub const SIGN: RuleSet = RuleSet(1 << 5);
    /// `sin² + cos² = 1` in sums.
    pub const PYTHAGORAS: RuleSet = RuleSet(1 << 6);
    /// Angle-sum contraction in sums.
    pub const ANGLE_SUM: RuleSet = RuleSet(1 << 7);
    /// Inverse-function and `abs` identities.
    pub const ELEMENTARY: RuleSet = RuleSet(1 << 8);
    /// Every rule.
    pub const ALL: RuleSet = RuleSet((1 << 9) - 1);

    /// Named rules, for reports and tests.
    pub const NAMED: [(&'static str, RuleSet); 9] = [
        ("fold", RuleSet::FOLD),
        ("identity", RuleSet::IDENTITY),
        ("collect", RuleSet::COLLECT),
        ("powers", RuleSet::POWERS),
        ("distribute", RuleSet::DISTRIBUTE),
        ("sign", RuleSet::SIGN),
        ("pythagoras", RuleSet::PYTHAGORAS),
        ("angle_sum", RuleSet::ANGLE_SUM),
        ("elementary", RuleSet::ELEMENTARY),
    ];

    /// Does this set contain all rules of `other`?
    pub fn has(self, other: RuleSet) -> bool {
        self.0 & other.0 == other.0
    }
    /// This set without the rules of `other`.
    pub fn without(self, other: RuleSet) -> RuleSet {
        RuleSet(self.0 & !other.0)
    }
}

impl BitOr for RuleSet {
    type Output = RuleSet;
    fn bitor(self, rhs: RuleSet) -> RuleSet {
        RuleSet(self.0 | rhs.0)
    }
}
