//! A branch-free `sin_cos` that vectorises over lanes: fdlibm's kernels
//! (as in musl's `__sin`, `__cos`) after a Cody–Waite reduction by `π/2`
//! in four parts (the constants of fdlibm's `__rem_pio2`, whose medium
//! path needs at most three rounds; here every lane takes all of them,
//! with exact error terms, good to 151 bits), the quadrant chosen by bit
//! operations. Where the build targets FMA the kernels' polynomials run as
//! fused multiply-adds (one rounding each; arm7's eight-lane forward
//! dynamics 2 893 → 2 845 instructions), else as fdlibm writes them.
//! Within 1 ulp of the C library for `|x| < 10⁶`; lanes outside that range
//! (and non-finite ones) are computed by `f64::sin_cos`, so the whole
//! range is covered (`tests/sincos.rs`).

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

/// `a + b` as `(s, e)` with `s + e = a + b` exactly (Knuth's TwoSum; no
/// condition on the magnitudes).
#[inline(always)]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `a − b` as `(d, e)` with `d + e = a − b` exactly.
#[inline(always)]
fn two_diff(a: f64, b: f64) -> (f64, f64) {
    two_sum(a, -b)
}

/// `a · b + c`: one fused multiply-add where the target has FMA (one
/// rounding, and one instruction instead of two), else the product and
/// the sum rounded separately as fdlibm writes them (`f64::mul_add`
/// without FMA is a library call).
#[inline(always)]
fn fma(a: f64, b: f64, c: f64) -> f64 {
    if cfg!(target_feature = "fma") {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `sin(x + y)` for `|x + y| ≤ π/4`, `y` the tail of the reduced argument.
#[inline(always)]
fn kernel_sin(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = fma(z * w, fma(z, S6, S5), fma(z, fma(z, S4, S3), S2));
    let v = z * x;
    x - fma(-v, S1, fma(z, fma(-v, r, 0.5 * y), -y))
}

/// `cos(x + y)` for `|x + y| ≤ π/4`.
#[inline(always)]
fn kernel_cos(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = fma(
        w * w,
        fma(z, fma(z, C6, C5), C4),
        z * fma(z, fma(z, C3, C2), C1),
    );
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + fma(z, r, -(x * y)))
}

/// `(sin x, cos x)` for `|x| < REDUCTION_LIMIT`, without branches (the
/// result for larger or non-finite `x` is meaningless: see
/// [`sin_cos_lanes`]).
#[inline(always)]
pub fn sin_cos_reduced(x: f64) -> (f64, f64) {
    // n = round(x · 2/π); the low bits of `k`'s significand are n (mod 4).
    let k = x * INVPIO2 + TOINT;
    let n = k - TOINT;
    let quadrant = k.to_bits();
    // x − n π/2 with π/2 = P₁ + P₂ + P₃ + P₃ₜ (33 bits each in the first
    // three, so every `n Pᵢ` is exact for n < 2²⁰): r₁ exact, then two
    // subtractions with their rounding errors kept (TwoSum), the error
    // terms and `n P₃ₜ` summed into the tail; (y₀, y₁) is the reduced
    // argument as a double-double. Same 151 bits as fdlibm's third round.
    let r1 = x - n * PIO2_1;
    let (r2, e2) = two_diff(r1, n * PIO2_2);
    let (r3, e3) = two_diff(r2, n * PIO2_3);
    let tail = (e2 + e3) - n * PIO2_3T;
    let (y0, y1) = two_sum(r3, tail);
    let s = kernel_sin(y0, y1);
    let c = kernel_cos(y0, y1);
    // Quadrant: odd n swaps sine and cosine; n ≡ 2, 3 negates the sine,
    // n ≡ 1, 2 the cosine.
    let odd = quadrant & 1 == 1;
    let (s, c) = if odd { (c, s) } else { (s, c) };
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = (quadrant.wrapping_add(1) & 2) << 62;
    let s = f64::from_bits(s.to_bits() ^ sin_sign);
    // sin x = x below 2⁻²⁶ (as fdlibm), which also keeps the sign of −0.
    let s = if x.abs() < TINY { x } else { s };
    (s, f64::from_bits(c.to_bits() ^ cos_sign))
}

/// `|x| < REDUCTION_LIMIT`, false for NaN.
#[inline(always)]
fn reducible(x: f64) -> bool {
    x.abs() < REDUCTION_LIMIT
}

/// `(sin x, cos x)` of every lane: [`sin_cos_reduced`] on all lanes (one
/// vectorised pass), then `f64::sin_cos` on any lane outside its range.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // three arrays by one index
pub fn sin_cos_lanes<const W: usize>(x: [f64; W]) -> ([f64; W], [f64; W]) {
    let mut s = [0.0; W];
    let mut c = [0.0; W];
    for i in 0..W {
        (s[i], c[i]) = sin_cos_reduced(x[i]);
    }
    let mut outside = false;
    for v in x {
        outside |= !reducible(v);
    }
    if outside {
        for i in 0..W {
            if !reducible(x[i]) {
                (s[i], c[i]) = f64::sin_cos(x[i]);
            }
        }
    }
    (s, c)
}
