//! `W` values of `f64` treated as one: the lane type of eom's ANCF element
//! kernels (`eom-elements`) and of the batched functions of generated
//! models (`NAME_lanes`, a pack of `W` states per call). Every operation
//! is lane-wise on a fixed-size array, which LLVM vectorises; `sin_cos` is
//! a branch-free polynomial ([`sincos`]) so that it vectorises too.

pub mod sincos;

/// `W` values of `f64` treated as one: the element kernels are generic in
/// `W` and evaluate `W` elements at once, one per lane, by the same
/// straight-line code. Every operation is lane-wise on a fixed-size array,
/// which the compiler vectorises (SSE2 by default on x86-64: two lanes per
/// instruction; with `-C target-cpu=x86-64-v3` or `native`, AVX2: four).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanes<const W: usize>(pub [f64; W]);

impl<const W: usize> Default for Lanes<W> {
    fn default() -> Self {
        Lanes([0.0; W])
    }
}

impl<const W: usize> Lanes<W> {
    /// Every lane `x`.
    #[inline(always)]
    pub fn splat(x: f64) -> Self {
        Lanes([x; W])
    }
    /// `f` of every lane.
    #[inline(always)]
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        let mut o = self.0;
        for v in &mut o {
            *v = f(*v);
        }
        Lanes(o)
    }
    /// `f` of every pair of lanes.
    #[inline(always)]
    pub fn zip(self, b: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let mut o = self.0;
        for (v, w) in o.iter_mut().zip(b.0) {
            *v = f(*v, w);
        }
        Lanes(o)
    }
    /// Lane-wise square root.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        self.map(f64::sqrt)
    }
    /// Every lane `f(l)` of its index `l` (a gather).
    #[inline(always)]
    pub fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        Lanes(core::array::from_fn(f))
    }
    /// Lane-wise sine (see [`Lanes::sin_cos`]).
    #[inline(always)]
    pub fn sin(self) -> Self {
        self.sin_cos().0
    }
    /// Lane-wise cosine (see [`Lanes::sin_cos`]).
    #[inline(always)]
    pub fn cos(self) -> Self {
        self.sin_cos().1
    }
    /// Lane-wise sine and cosine by a branch-free polynomial that
    /// vectorises ([`sincos::sin_cos_lanes`]): within 1 ulp of the C
    /// library's over the whole range.
    #[inline(always)]
    pub fn sin_cos(self) -> (Self, Self) {
        let (s, c) = sincos::sin_cos_lanes(self.0);
        (Lanes(s), Lanes(c))
    }
    /// Lane-wise `a · b + c` with one rounding (`f64::mul_add`: a fused
    /// multiply-add where the target has one, else a library call).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // four arrays by one index
    pub fn mul_add(a: Self, b: Self, c: Self) -> Self {
        let mut o = c.0;
        for i in 0..W {
            o[i] = f64::mul_add(a.0[i], b.0[i], c.0[i]);
        }
        Lanes(o)
    }
    /// Lane-wise tangent.
    #[inline(always)]
    pub fn tan(self) -> Self {
        self.map(f64::tan)
    }
    /// Lane-wise exponential.
    #[inline(always)]
    pub fn exp(self) -> Self {
        self.map(f64::exp)
    }
    /// Lane-wise natural logarithm.
    #[inline(always)]
    pub fn ln(self) -> Self {
        self.map(f64::ln)
    }
    /// Lane-wise absolute value.
    #[inline(always)]
    pub fn abs(self) -> Self {
        self.map(f64::abs)
    }
    /// Lane-wise `atan2(y, x)`.
    #[inline(always)]
    pub fn atan2(y: Self, x: Self) -> Self {
        y.zip(x, f64::atan2)
    }
    /// Lane-wise `if c > 0 { a } else { b }`.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // three arrays by one index
    pub fn select(c: Self, a: Self, b: Self) -> Self {
        let mut o = b.0;
        for i in 0..W {
            if c.0[i] > 0.0 {
                o[i] = a.0[i];
            }
        }
        Lanes(o)
    }
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<const W: usize> core::ops::$tr for Lanes<W> {
            type Output = Self;
            #[inline(always)]
            // One indexed loop for all four operators (the form measured
            // in BENCHMARKS.md, vectorised by LLVM).
            #[allow(clippy::assign_op_pattern, clippy::needless_range_loop)]
            fn $f(self, b: Self) -> Self {
                let mut o = self.0;
                for i in 0..W {
                    o[i] = o[i] $op b.0[i];
                }
                Lanes(o)
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl<const W: usize> core::ops::Neg for Lanes<W> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        self.map(|x| -x)
    }
}
