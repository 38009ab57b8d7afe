//! `W` values of `f64` treated as one: the lane type of eom's ANCF element
//! kernels (`eom-elements`) and of the batched functions of generated
//! models (`NAME_lanes`, a pack of `W` states per call). Every operation
//! is lane-wise on a fixed-size array; in optimised builds, where `W` is a
//! multiple of 8 or 4, the arithmetic runs in chunks of `wide`'s `f64x8` or `f64x4`, explicit
//! vectors that LLVM keeps whole (one `zmm` or `ymm` instruction an
//! operation where the target has them, pairs of narrower ones where not),
//! instead of arrays its SLP vectoriser must find again in every function,
//! which it gave up on in long ones (BENCHMARKS.md, "Explicit vectors for
//! the lanes, again"). `sin_cos` is a polynomial with two tests a vector
//! ([`sincos`]) so that it vectorises too.

pub mod sincos;

/// `W` values of `f64` treated as one: the element kernels are generic in
/// `W` and evaluate `W` elements at once, one per lane, by the same
/// straight-line code. Every operation is lane-wise on a fixed-size array,
/// in vector instructions (SSE2 by default on x86-64: two lanes per
/// instruction; with `-C target-cpu=x86-64-v3`, AVX2: four; with `native`
/// on an AVX-512 machine, eight for `W` a multiple of 8). The results are
/// those of the same `f64` operations one lane at a time, bit for bit:
/// `+ − × ÷`, negation and the fused `mul_add` are exactly rounded either
/// way.
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
    /// Lane-wise sine and cosine by a polynomial (two tests a vector) that
    /// vectorises ([`sincos::sin_cos_lanes`]): within 1 ulp of the C
    /// library's over the whole range.
    #[inline(always)]
    pub fn sin_cos(self) -> (Self, Self) {
        let (s, c) = sincos::sin_cos_lanes(self.0);
        (Lanes(s), Lanes(c))
    }
    /// Lane-wise `a · b + c` with one rounding: vector fused
    /// multiply-adds where the build targets FMA, else `f64::mul_add` lane
    /// by lane (a library call without FMA).
    #[inline(always)]
    pub fn mul_add(a: Self, b: Self, c: Self) -> Self {
        Lanes(fused(VECTORS, a.0, b.0, c.0))
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

/// Arithmetic in chunks of `wide`'s vectors: in optimised builds. Without
/// optimisation each chunk's vectors are copies on the stack, and the
/// element kernels' functions of thousands of operations, instantiated
/// unoptimised in a caller's debug build, overflowed a test thread's 2 MiB
/// stack; debug builds keep the loops (whose results are the same bits).
pub(crate) const VECTORS: bool = !cfg!(debug_assertions);

/// Lanes `i..i + 8` of `a` as one vector (written out: `array::from_fn`
/// is not inlined in functions this long).
#[inline(always)]
pub(crate) fn load8<const W: usize>(a: &[f64; W], i: usize) -> wide::f64x8 {
    wide::f64x8::new([
        a[i],
        a[i + 1],
        a[i + 2],
        a[i + 3],
        a[i + 4],
        a[i + 5],
        a[i + 6],
        a[i + 7],
    ])
}

/// Lanes `i..i + 4` of `a` as one vector.
#[inline(always)]
pub(crate) fn load4<const W: usize>(a: &[f64; W], i: usize) -> wide::f64x4 {
    wide::f64x4::new([a[i], a[i + 1], a[i + 2], a[i + 3]])
}

/// `a · b + c` with one rounding, lane by lane: in chunks of vector fused
/// multiply-adds with `vectors` where the target has FMA, else
/// `f64::mul_add` one lane at a time.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // four arrays by one index
fn fused<const W: usize>(vectors: bool, a: [f64; W], b: [f64; W], c: [f64; W]) -> [f64; W] {
    let mut o = c;
    let fma = vectors && cfg!(target_feature = "fma");
    if fma && W.is_multiple_of(8) {
        for i in (0..W).step_by(8) {
            let r = load8(&a, i).mul_add(load8(&b, i), load8(&c, i));
            o[i..i + 8].copy_from_slice(&r.to_array());
        }
    } else if fma && W.is_multiple_of(4) {
        for i in (0..W).step_by(4) {
            let r = load4(&a, i).mul_add(load4(&b, i), load4(&c, i));
            o[i..i + 4].copy_from_slice(&r.to_array());
        }
    } else {
        for i in 0..W {
            o[i] = f64::mul_add(a[i], b[i], c[i]);
        }
    }
    o
}

/// `f(a, b)` lane by lane: with `vectors` in chunks of `wide`'s `f64x8`
/// where `W` is a multiple of 8, of `f64x4` where of 4; else one lane at a
/// time.
#[inline(always)]
fn chunked<const W: usize>(
    vectors: bool,
    a: [f64; W],
    b: [f64; W],
    f8: impl Fn(wide::f64x8, wide::f64x8) -> wide::f64x8,
    f4: impl Fn(wide::f64x4, wide::f64x4) -> wide::f64x4,
    f1: impl Fn(f64, f64) -> f64,
) -> [f64; W] {
    let mut o = a;
    if vectors && W.is_multiple_of(8) {
        for i in (0..W).step_by(8) {
            o[i..i + 8].copy_from_slice(&f8(load8(&a, i), load8(&b, i)).to_array());
        }
    } else if vectors && W.is_multiple_of(4) {
        for i in (0..W).step_by(4) {
            o[i..i + 4].copy_from_slice(&f4(load4(&a, i), load4(&b, i)).to_array());
        }
    } else {
        for i in 0..W {
            o[i] = f1(a[i], b[i]);
        }
    }
    o
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl<const W: usize> core::ops::$tr for Lanes<W> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, b: Self) -> Self {
                Lanes(chunked(VECTORS, self.0, b.0, |x, y| x $op y, |x, y| x $op y, |x, y| x $op y))
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
        Lanes(chunked(
            VECTORS,
            self.0,
            self.0,
            |x, _| -x,
            |x, _| -x,
            |x, _| -x,
        ))
    }
}

/// SplitMix64, the unit tests' deterministic generator.
#[cfg(test)]
mod test_rng {
    pub(crate) struct Rng(pub(crate) u64);

    impl Rng {
        pub(crate) fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }

        /// Uniform in [0, 1).
        pub(crate) fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
    }
}

/// `Lanes<W>` arithmetic is the `f64` arithmetic of each lane, bit for bit,
/// whatever the chunks it runs in (`f64x8` for `W` a multiple of 8, `f64x4`
/// of 4, lane by lane otherwise; the vector paths are tested here in every
/// build, also where the operators take the loops): `+ − × ÷`, negation and
/// `mul_add` are each one correctly rounded IEEE operation, so vector and
/// scalar agree exactly, on signed zeros, infinities, subnormals and NaNs.
#[cfg(test)]
mod tests {
    use super::{Lanes, chunked, fused};
    type F8 = wide::f64x8;
    type F4 = wide::f64x4;
    /// An operation's name, its lanes, and each lane one at a time.
    type Case<'a, const W: usize> = (&'a str, Lanes<W>, &'a dyn Fn(usize) -> f64);

    use crate::test_rng::Rng;

    impl Rng {
        /// Mostly ordinary numbers of all magnitudes, some special values.
        fn value(&mut self) -> f64 {
            const SPECIAL: [f64; 10] = [
                0.0,
                -0.0,
                1.0,
                -1.0,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NAN,
                f64::MIN_POSITIVE,
                5e-324,
                f64::MAX,
            ];
            let r = self.next();
            if r.is_multiple_of(8) {
                SPECIAL[(r >> 8) as usize % SPECIAL.len()]
            } else {
                let mantissa = (r >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                mantissa * 2f64.powi(((r >> 3) % 80) as i32 - 40)
            }
        }
    }

    /// The same bits, or both NaN (a NaN's payload is not specified).
    fn same(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    fn check<const W: usize>(rng: &mut Rng) {
        for _ in 0..2000 {
            let [a, b, c]: [[f64; W]; 3] =
                std::array::from_fn(|_| std::array::from_fn(|_| rng.value()));
            let (x, y, z) = (Lanes(a), Lanes(b), Lanes(c));
            let v = |f8: fn(F8, F8) -> F8, f4: fn(F4, F4) -> F4, f1: fn(f64, f64) -> f64| {
                Lanes(chunked(true, a, b, f8, f4, f1))
            };
            let results: [Case<W>; 12] = [
                ("+", x + y, &|l| a[l] + b[l]),
                ("-", x - y, &|l| a[l] - b[l]),
                ("*", x * y, &|l| a[l] * b[l]),
                ("/", x / y, &|l| a[l] / b[l]),
                ("neg", -x, &|l| -a[l]),
                ("mul_add", Lanes::mul_add(x, y, z), &|l| {
                    a[l].mul_add(b[l], c[l])
                }),
                (
                    "+ in vectors",
                    v(|p, q| p + q, |p, q| p + q, |p, q| p + q),
                    &|l| a[l] + b[l],
                ),
                (
                    "- in vectors",
                    v(|p, q| p - q, |p, q| p - q, |p, q| p - q),
                    &|l| a[l] - b[l],
                ),
                (
                    "* in vectors",
                    v(|p, q| p * q, |p, q| p * q, |p, q| p * q),
                    &|l| a[l] * b[l],
                ),
                (
                    "/ in vectors",
                    v(|p, q| p / q, |p, q| p / q, |p, q| p / q),
                    &|l| a[l] / b[l],
                ),
                ("neg in vectors", v(|p, _| -p, |p, _| -p, |p, _| -p), &|l| {
                    -a[l]
                }),
                ("mul_add in vectors", Lanes(fused(true, a, b, c)), &|l| {
                    a[l].mul_add(b[l], c[l])
                }),
            ];
            for (op, lanes, scalar) in results {
                for l in 0..W {
                    assert!(
                        same(lanes.0[l], scalar(l)),
                        "W = {W}, lane {l}: {} {op} {} (c = {}) gave {:e}, one lane at a time {:e}",
                        a[l],
                        b[l],
                        c[l],
                        lanes.0[l],
                        scalar(l)
                    );
                }
            }
        }
    }

    #[test]
    fn lanes_are_the_scalar_operations_bit_for_bit() {
        let mut rng = Rng(7);
        check::<1>(&mut rng);
        check::<2>(&mut rng);
        check::<3>(&mut rng);
        check::<4>(&mut rng);
        check::<6>(&mut rng);
        check::<8>(&mut rng);
        check::<12>(&mut rng);
        check::<16>(&mut rng);
    }
}
