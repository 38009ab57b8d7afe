//! A `sin_cos` in vectors over lanes: fdlibm's kernels (as in musl's
//! `__sin`, `__cos`) after a Cody–Waite reduction by `π/2`, the quadrant
//! chosen by bit operations, with no branches but two tests a vector
//! (the reduction's range, and whether its first round is enough). The
//! reduction is fdlibm's medium path: its first round (π/2 to 85 bits)
//! where that cancels fewer than 15 bits of the argument, else, for every
//! lane of a vector that has such a lane next to a multiple of π/2, all
//! four parts of the constants of fdlibm's `__rem_pio2` with exact error
//! terms, good to 151 bits (the same choice lane by lane in the scalar
//! kernel). Where the build targets FMA the kernels' polynomials run as
//! fused multiply-adds (one rounding each; arm7's eight-lane forward
//! dynamics 2 893 → 2 845 instructions), else as fdlibm writes them.
//! Within 1 ulp of the C library for `|x| < 10⁶`; lanes outside that range
//! (and non-finite ones) are computed by `f64::sin_cos`, so the whole
//! range is covered (`tests/sincos.rs`). In optimised builds the lanes run
//! in `wide`'s `f64x8` or `f64x4` (the quadrant's bits through `bytemuck`
//! casts), bit for bit the scalar [`sin_cos_reduced`] on every lane: one
//! generic text of the algorithm serves both.

use core::ops::{Add, Mul, Neg, Sub};

/// Above this magnitude the reduction's `n · π/2₁` would no longer be
/// exact (`n < 2²⁰`); such lanes go to `f64::sin_cos`.
pub const REDUCTION_LIMIT: f64 = 1.0e6;

/// Below this magnitude `sin x` rounds to `x`.
const TINY: f64 = 1.0 / 67_108_864.0;
const TOINT: f64 = 1.5 / f64::EPSILON;
const INVPIO2: f64 = core::f64::consts::FRAC_2_PI;
// The constants as fdlibm writes them (hex words of the doubles).
const PIO2_1: f64 = f64::from_bits(0x3ff921fb54400000); // 1.5707963267341256
const PIO2_2: f64 = f64::from_bits(0x3dd0b4611a600000); // 6.077100506303966e-11
const PIO2_3: f64 = f64::from_bits(0x3ba3198a2e000000); // 2.0222662487111665e-21
const PIO2_3T: f64 = f64::from_bits(0x397b839a252049c1); // 8.4784276603689e-32
/// `π/2 − P₁` rounded (fdlibm's `pio2_1t`): with `P₁`, the first round of
/// fdlibm's medium path, π/2 to 85 bits.
const PIO2_1T: f64 = f64::from_bits(0x3dd0b4611a626331); // 6.077100506506192e-11
/// The first round is enough where it cancels fewer than 15 bits of `x`,
/// `|y₀| > 2⁻¹⁵ |x|` (fdlibm takes a second round where the exponents of
/// `x` and `y₀` differ by more than 16).
const FIRST_ROUND_CANCELS: f64 = 1.0 / 32_768.0;
/// Below this `|x|` (under π/4) `n = 0`: nothing to reduce, the first
/// round is exact.
const NOTHING_TO_REDUCE: f64 = 0.78;

const S1: f64 = f64::from_bits(0xbfc5555555555549); // -0.16666666666666632
const S2: f64 = f64::from_bits(0x3f8111111110f8a6); // 0.00833333333332249
const S3: f64 = f64::from_bits(0xbf2a01a019c161d5); // -0.0001984126982985795
const S4: f64 = f64::from_bits(0x3ec71de357b1fe7d); // 2.7557313707070068e-06
const S5: f64 = f64::from_bits(0xbe5ae5e68a2b9ceb); // -2.5050760253406863e-08
const S6: f64 = f64::from_bits(0x3de5d93a5acfd57c); // 1.58969099521155e-10

const C1: f64 = f64::from_bits(0x3fa555555555554c); // 0.0416666666666666
const C2: f64 = f64::from_bits(0xbf56c16c16c15177); // -0.001388888888887411
const C3: f64 = f64::from_bits(0x3efa01a019cb1590); // 2.480158728947673e-05
const C4: f64 = f64::from_bits(0xbe927e4f809c52ad); // -2.7557314351390663e-07
const C5: f64 = f64::from_bits(0x3e21ee9ebdb4b1c4); // 2.087572321298175e-09
const C6: f64 = f64::from_bits(0xbda8fae9be8838d4); // -1.1359647557788195e-11

/// What the kernel needs of a lane type: `f64` itself and `wide`'s
/// vectors, so that one text of the algorithm serves the scalar function
/// and every width, with the same operations in the same order on each
/// lane (the same bits). A mask is a value whose lanes are all ones or all
/// zeros, as the vector comparisons make them.
trait Lane:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    fn splat(x: f64) -> Self;
    /// `a · b + c` with one rounding.
    fn fused(self, b: Self, c: Self) -> Self;
    fn abs(self) -> Self;
    /// The mask of the lanes where `self < b`.
    fn less(self, b: Self) -> Self;
    /// `mask ? a : b`, lane by lane.
    fn select(mask: Self, a: Self, b: Self) -> Self;
    /// The quadrant's masks from `k = x · 2/π + 1.5 · 2⁵²`, whose low
    /// significand bits are `n (mod 4)`: the lanes where `n` is odd, and
    /// the sign bits of the sine (`n ≡ 2, 3`) and of the cosine
    /// (`n ≡ 1, 2`).
    fn quadrant(k: Self) -> (Self, Self, Self);
    /// The bits of `self` exclusive-or those of `b`.
    fn xor(self, b: Self) -> Self;
    /// Is every lane of the mask `self` set?
    fn all(self) -> bool;
}

impl Lane for f64 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn fused(self, b: Self, c: Self) -> Self {
        self.mul_add(b, c)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn less(self, b: Self) -> Self {
        if self < b {
            f64::from_bits(u64::MAX)
        } else {
            0.0
        }
    }
    #[inline(always)]
    fn select(mask: Self, a: Self, b: Self) -> Self {
        if mask.to_bits() != 0 { a } else { b }
    }
    #[inline(always)]
    fn quadrant(k: Self) -> (Self, Self, Self) {
        let q = k.to_bits();
        let odd = if q & 1 == 1 {
            f64::from_bits(u64::MAX)
        } else {
            0.0
        };
        let sin_sign = f64::from_bits((q & 2) << 62);
        let cos_sign = f64::from_bits((q.wrapping_add(1) & 2) << 62);
        (odd, sin_sign, cos_sign)
    }
    #[inline(always)]
    fn xor(self, b: Self) -> Self {
        f64::from_bits(self.to_bits() ^ b.to_bits())
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.to_bits() != 0
    }
}

macro_rules! vector_lane {
    ($f:ty, $u:ty) => {
        impl Lane for $f {
            #[inline(always)]
            fn splat(x: f64) -> Self {
                <$f>::splat(x)
            }
            #[inline(always)]
            fn fused(self, b: Self, c: Self) -> Self {
                self.mul_add(b, c)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$f>::abs(self)
            }
            #[inline(always)]
            fn less(self, b: Self) -> Self {
                self.simd_lt(b)
            }
            #[inline(always)]
            fn select(mask: Self, a: Self, b: Self) -> Self {
                wide::Select::select(mask, a, b)
            }
            #[inline(always)]
            fn quadrant(k: Self) -> (Self, Self, Self) {
                let q: $u = bytemuck::cast(k);
                let (one, two) = (<$u>::splat(1), <$u>::splat(2));
                // 0 − (q & 1): all ones where n is odd (a subtraction, which
                // every x86-64 has; a 64-bit comparison needs SSE4.1).
                let odd = bytemuck::cast(<$u>::splat(0) - (q & one));
                let sin_sign = bytemuck::cast((q & two) << 62u32);
                let cos_sign = bytemuck::cast(((q + one) & two) << 62u32);
                (odd, sin_sign, cos_sign)
            }
            #[inline(always)]
            fn xor(self, b: Self) -> Self {
                self ^ b
            }
            #[inline(always)]
            fn all(self) -> bool {
                <$f>::all(self)
            }
        }
    };
}
vector_lane!(wide::f64x8, wide::u64x8);
vector_lane!(wide::f64x4, wide::u64x4);

/// A [`Lane`] of `N` doubles in one vector, to and from an array.
trait Vector<const N: usize>: Lane {
    fn from_array(a: [f64; N]) -> Self;
    fn to_array(self) -> [f64; N];
}

macro_rules! vector_array {
    ($f:ty, $n:literal) => {
        impl Vector<$n> for $f {
            #[inline(always)]
            fn from_array(a: [f64; $n]) -> Self {
                <$f>::new(a)
            }
            #[inline(always)]
            fn to_array(self) -> [f64; $n] {
                <$f>::to_array(self)
            }
        }
    };
}

vector_array!(wide::f64x8, 8);
vector_array!(wide::f64x4, 4);

/// The kernel on the angles `x` (at most `N`), padded with zeros to one
/// vector `V`, into `s` and `c` (as long as `x`); whether every angle is
/// within [`REDUCTION_LIMIT`] ([`reducible_all`]).
#[inline(always)]
fn sin_cos_padded<V: Vector<N>, const N: usize>(x: &[f64], s: &mut [f64], c: &mut [f64]) -> bool {
    let n = x.len();
    let mut chunk = [0.0; N];
    chunk[..n].copy_from_slice(x);
    let v = V::from_array(chunk);
    let (vs, vc) = sin_cos_kernel(v);
    s.copy_from_slice(&vs.to_array()[..n]);
    c.copy_from_slice(&vc.to_array()[..n]);
    reducible_all(v)
}

/// Is every lane of `x` within [`REDUCTION_LIMIT`] (false for NaN)? One
/// vector comparison and one test of its mask: a lane-by-lane check of
/// the array after the vectors became a comparison and a branch per lane
/// (arm7's sixteen-lane forward dynamics: 138 scalar comparisons, the
/// vectors stored to the stack for them).
#[inline(always)]
fn reducible_all<V: Lane>(x: V) -> bool {
    x.abs().less(V::splat(REDUCTION_LIMIT)).all()
}

/// `a + b` as `(s, e)` with `s + e = a + b` exactly (Knuth's TwoSum; no
/// condition on the magnitudes).
#[inline(always)]
fn two_sum<V: Lane>(a: V, b: V) -> (V, V) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `a − b` as `(d, e)` with `d + e = a − b` exactly.
#[inline(always)]
fn two_diff<V: Lane>(a: V, b: V) -> (V, V) {
    two_sum(a, -b)
}

/// `a · b + c`: one fused multiply-add where the target has FMA (one
/// rounding, and one instruction instead of two), else the product and
/// the sum rounded separately as fdlibm writes them (`f64::mul_add`
/// without FMA is a library call).
#[inline(always)]
fn fma<V: Lane>(a: V, b: V, c: V) -> V {
    if cfg!(target_feature = "fma") {
        a.fused(b, c)
    } else {
        a * b + c
    }
}

/// `sin(x + y)` for `|x + y| ≤ π/4`, `y` the tail of the reduced argument.
#[inline(always)]
fn kernel_sin<V: Lane>(x: V, y: V) -> V {
    let k = V::splat;
    let z = x * x;
    let w = z * z;
    let r = fma(
        z * w,
        fma(z, k(S6), k(S5)),
        fma(z, fma(z, k(S4), k(S3)), k(S2)),
    );
    let v = z * x;
    x - fma(-v, k(S1), fma(z, fma(-v, r, k(0.5) * y), -y))
}

/// `cos(x + y)` for `|x + y| ≤ π/4`.
#[inline(always)]
fn kernel_cos<V: Lane>(x: V, y: V) -> V {
    let k = V::splat;
    let z = x * x;
    let w = z * z;
    let r = fma(
        w * w,
        fma(z, fma(z, k(C6), k(C5)), k(C4)),
        z * fma(z, fma(z, k(C3), k(C2)), k(C1)),
    );
    let hz = k(0.5) * z;
    let w = k(1.0) - hz;
    w + (((k(1.0) - w) - hz) + fma(z, r, -(x * y)))
}

/// `x − n π/2` from `r₁ = x − n P₁` as a double-double `(y₀, y₁)`, with
/// π/2 = P₁ + P₂ + P₃ + P₃ₜ (33 bits each in the first three, so every
/// `n Pᵢ` is exact for n < 2²⁰): two subtractions with their rounding
/// errors kept (TwoSum), the error terms and `n P₃ₜ` summed into the
/// tail. Same 151 bits as fdlibm's third round: for the lanes next to a
/// multiple of π/2, where the first round cancels too much.
#[inline(always)]
fn full_reduction<V: Lane>(r1: V, n: V) -> (V, V) {
    let c = V::splat;
    let (r2, e2) = two_diff(r1, n * c(PIO2_2));
    let (r3, e3) = two_diff(r2, n * c(PIO2_3));
    let tail = (e2 + e3) - n * c(PIO2_3T);
    two_sum(r3, tail)
}

/// `(sin x, cos x)` for `|x| < REDUCTION_LIMIT` on every lane of `x`,
/// without branches but one, to the full reduction where a lane needs it
/// (the result for larger or non-finite lanes is meaningless: see
/// [`sin_cos_lanes`]).
#[inline(always)]
fn sin_cos_kernel<V: Lane>(x: V) -> (V, V) {
    let c = V::splat;
    // n = round(x · 2/π); the low bits of `k`'s significand are n (mod 4).
    let k = x * c(INVPIO2) + c(TOINT);
    let n = k - c(TOINT);
    // x − n π/2, first as fdlibm's medium path does in its first round
    // (π/2 = P₁ + P₁ₜ to 85 bits; `n P₁` exact for n < 2²⁰, so r₁ is):
    // every lane where that cancels few bits of `x`, or has nothing to
    // reduce, keeps it; if any lane of the vector does not, the vector
    // also takes the full reduction and those lanes its result (the same
    // choice lane by lane as the scalar kernel, so the same bits).
    let r1 = x - n * c(PIO2_1);
    let w = n * c(PIO2_1T);
    let y0 = r1 - w;
    let y1 = (r1 - y0) - w;
    // kept = small or cancelling little (a select of masks is their `or`).
    let small = x.abs().less(c(NOTHING_TO_REDUCE));
    let kept = V::select(
        small,
        small,
        (x.abs() * c(FIRST_ROUND_CANCELS)).less(y0.abs()),
    );
    let (y0, y1) = if kept.all() {
        (y0, y1)
    } else {
        core::hint::cold_path();
        let (f0, f1) = full_reduction(r1, n);
        (V::select(kept, y0, f0), V::select(kept, y1, f1))
    };
    let s = kernel_sin(y0, y1);
    let co = kernel_cos(y0, y1);
    // Quadrant: odd n swaps sine and cosine; n ≡ 2, 3 negates the sine,
    // n ≡ 1, 2 the cosine.
    let (odd, sin_sign, cos_sign) = V::quadrant(k);
    let (s, co) = (V::select(odd, co, s), V::select(odd, s, co));
    let s = s.xor(sin_sign);
    // sin x = x below 2⁻²⁶ (as fdlibm), which also keeps the sign of −0.
    let s = V::select(x.abs().less(c(TINY)), x, s);
    (s, co.xor(cos_sign))
}

/// `(sin x, cos x)` for `|x| < REDUCTION_LIMIT` (the result for larger or
/// non-finite `x` is meaningless: see [`sin_cos_lanes`]).
#[inline(always)]
pub fn sin_cos_reduced(x: f64) -> (f64, f64) {
    sin_cos_kernel(x)
}

/// `|x| < REDUCTION_LIMIT`, false for NaN.
#[inline(always)]
fn reducible(x: f64) -> bool {
    x.abs() < REDUCTION_LIMIT
}

/// `(sin x, cos x)` of every lane: [`sin_cos_reduced`] on all lanes (one
/// vectorised pass for `W ≥ 4` in optimised builds: chunks of `wide`'s
/// `f64x8`, the rest in one `f64x4` or `f64x8` padded with zeros; lane by
/// lane for fewer lanes and in debug builds), then `f64::sin_cos` on any
/// lane outside its range.
#[inline(always)]
pub fn sin_cos_lanes<const W: usize>(x: [f64; W]) -> ([f64; W], [f64; W]) {
    sin_cos_chunks(super::VECTORS, x)
}

/// [`sin_cos_lanes`], in vectors if `vectors` (so that the tests take
/// both paths in every build).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // three arrays by one index
fn sin_cos_chunks<const W: usize>(vectors: bool, x: [f64; W]) -> ([f64; W], [f64; W]) {
    let mut s = [0.0; W];
    let mut c = [0.0; W];
    if vectors && W >= 4 {
        // Whole chunks of eight, then what is left in one chunk of four
        // (or eight), padded with zeros where it does not fill it: 12
        // angles are one `f64x8` and one `f64x4`, not three `f64x4`.
        let mut i = 0;
        let mut inside = true;
        while i + 8 <= W {
            let v = super::load8(&x, i);
            let (vs, vc) = sin_cos_kernel(v);
            s[i..i + 8].copy_from_slice(&vs.to_array());
            c[i..i + 8].copy_from_slice(&vc.to_array());
            inside &= reducible_all(v);
            i += 8;
        }
        let n = W - i;
        if n > 4 {
            inside &= sin_cos_padded::<wide::f64x8, 8>(&x[i..], &mut s[i..], &mut c[i..]);
        } else if n > 0 {
            inside &= sin_cos_padded::<wide::f64x4, 4>(&x[i..], &mut s[i..], &mut c[i..]);
        }
        if !inside {
            return lane_by_lane(x);
        }
    } else {
        let mut inside = true;
        for i in 0..W {
            (s[i], c[i]) = sin_cos_reduced(x[i]);
            inside &= reducible(x[i]);
        }
        if !inside {
            return lane_by_lane(x);
        }
    }
    (s, c)
}

/// [`sin_cos_lanes`] lane by lane, `f64::sin_cos` on the lanes beyond
/// [`REDUCTION_LIMIT`] (and the non-finite ones), [`sin_cos_reduced`] on
/// the others: out of line and cold, for packs with a lane outside the
/// reduction's range, so that the hot path keeps one test of a vector
/// comparison's mask and none of the calls' code.
#[cold]
#[inline(never)]
fn lane_by_lane<const W: usize>(x: [f64; W]) -> ([f64; W], [f64; W]) {
    let (mut s, mut c) = ([0.0; W], [0.0; W]);
    for ((&xl, sl), cl) in x.iter().zip(&mut s).zip(&mut c) {
        (*sl, *cl) = if reducible(xl) {
            sin_cos_reduced(xl)
        } else {
            f64::sin_cos(xl)
        };
    }
    (s, c)
}

/// The vector kernels against the scalar one, lane by lane, bit for bit:
/// tested in every build (debug builds' `Lanes` take the scalar loop, so
/// the vector path is asked for here directly; W = 4 and 8 are one `f64x4`
/// and one `f64x8`), with and without FMA (the CI
/// phase that builds this crate with `+fma`).
#[cfg(test)]
mod tests {
    use super::{REDUCTION_LIMIT, sin_cos_reduced};
    use core::f64::consts::FRAC_PI_2;

    use crate::test_rng::Rng;

    /// Arguments of every kind the reduction meets: log-uniform magnitudes
    /// 2⁻⁶⁰ … 10⁶ of both signs, the doubles next to multiples of π/2 (the
    /// worst cancellations), signed zeros, the tiny threshold's
    /// neighbours, the reduction limit's.
    fn arguments() -> Vec<f64> {
        let mut rng = Rng(0xc0de);
        let mut xs = Vec::new();
        for _ in 0..40_000 {
            let e = -60.0 + rng.unit() * (60.0 + REDUCTION_LIMIT.log2());
            let x = e.exp2();
            xs.push(if rng.next() & 1 == 1 { -x } else { x });
        }
        for n in -2000i32..2000 {
            let m = f64::from(n) * FRAC_PI_2;
            let mut x = m;
            for _ in 0..3 {
                xs.extend([x, -x]);
                x = f64::from_bits(x.to_bits() + 1);
            }
            x = m;
            for _ in 0..3 {
                x = f64::from_bits(x.to_bits().wrapping_sub(1));
                xs.extend([x, -x]);
            }
        }
        let tiny = super::TINY;
        xs.extend([0.0, -0.0, tiny, -tiny, f64::MIN_POSITIVE, 5e-324]);
        xs.extend([
            f64::from_bits(tiny.to_bits() - 1),
            f64::from_bits(tiny.to_bits() + 1),
        ]);
        let below = f64::from_bits(REDUCTION_LIMIT.to_bits() - 1);
        xs.extend([below, -below]);
        xs
    }

    fn same(got: (f64, f64), want: (f64, f64), x: f64, width: &str) {
        assert!(
            got.0.to_bits() == want.0.to_bits() && got.1.to_bits() == want.1.to_bits(),
            "{width}: sin_cos({x:e}) = {got:?}, scalar {want:?}"
        );
    }

    /// Every width's chunks, the padded last one of long arrays included,
    /// give each lane the scalar kernel's bits (and libm's beyond the
    /// reduction limit), in vectors and lane by lane.
    #[test]
    fn chunks_of_every_width_are_the_scalar_kernel_bit_for_bit() {
        fn check<const W: usize>(xs: &[f64]) {
            for chunk in xs.chunks_exact(W) {
                let x: [f64; W] = chunk.try_into().expect("W");
                for vectors in [true, false] {
                    let (s, c) = super::sin_cos_chunks(vectors, x);
                    for (l, &xl) in x.iter().enumerate() {
                        let want = if xl.abs() < REDUCTION_LIMIT {
                            sin_cos_reduced(xl)
                        } else {
                            f64::sin_cos(xl)
                        };
                        same((s[l], c[l]), want, xl, "chunks");
                    }
                }
            }
        }
        let mut xs = arguments();
        xs.extend([
            2.0e6,
            -3.5e7,
            1.0e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ]);
        xs.rotate_left(7);
        check::<1>(&xs[..64]);
        check::<3>(&xs);
        check::<4>(&xs);
        check::<8>(&xs);
        check::<10>(&xs);
        check::<12>(&xs);
        check::<13>(&xs);
        check::<5>(&xs);
        check::<50>(&xs);
        check::<200>(&xs);
    }
}
