//! The vectorised `sin_cos` against the C library's (`f64::sin_cos`):
//! within 1 ulp over the whole range, exact signs of zero, the identity
//! `sin² + cos² = 1`, and lanes outside the reduction range handed to the
//! library unchanged.

use eom_lanes::Lanes;
use eom_lanes::sincos::REDUCTION_LIMIT;

/// Distance in units in the last place between two finite doubles (the
/// number of representable doubles between them).
fn ulps(a: f64, b: f64) -> u64 {
    let key = |x: f64| {
        let bits = x.to_bits() as i64;
        if bits < 0 { i64::MIN - bits } else { bits }
    };
    key(a).abs_diff(key(b))
}

/// A small deterministic generator (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Checks 8 arguments at once (lanes of different values) against libm.
fn check(xs: [f64; 8], worst: &mut (u64, f64)) {
    let (s, c) = Lanes(xs).sin_cos();
    for (l, &x) in xs.iter().enumerate() {
        let (ws, wc) = f64::sin_cos(x);
        for (got, want, what) in [(s.0[l], ws, "sin"), (c.0[l], wc, "cos")] {
            if want.is_nan() {
                assert!(got.is_nan(), "{what}({x:e}): got {got:e}, want NaN");
                continue;
            }
            let d = ulps(got, want);
            assert!(
                d <= 1,
                "{what}({x:e}) = {got:e}, libm {want:e}: {d} ulp apart"
            );
            if d > worst.0 {
                *worst = (d, x);
            }
        }
    }
}

#[test]
fn sin_cos_is_within_one_ulp_of_libm_over_the_whole_range() {
    let mut rng = Rng(0x5eed);
    let mut worst = (0, 0.0);
    // Magnitudes 2⁻⁶⁰ … 2⁶⁰ (log-uniform), both signs: tiny arguments,
    // the reduced range, the reduction's range and beyond it.
    for _ in 0..40_000 {
        let xs = std::array::from_fn(|_| {
            let e = rng.unit() * 120.0 - 60.0;
            let sign = if rng.next() & 1 == 0 { 1.0 } else { -1.0 };
            sign * e.exp2()
        });
        check(xs, &mut worst);
    }
    // Uniform over the angles joints actually take.
    for _ in 0..40_000 {
        let xs = std::array::from_fn(|_| (rng.unit() - 0.5) * 40.0);
        check(xs, &mut worst);
    }
    // Near multiples of π/2 (the reduction's hardest cases: large
    // cancellation), up to the reduction limit, and the doubles around them.
    let mut k = 1.0f64;
    while k * std::f64::consts::FRAC_PI_2 < REDUCTION_LIMIT {
        let x = k * std::f64::consts::FRAC_PI_2;
        let xs = std::array::from_fn(|i| {
            let bits = x.to_bits() as i64 + (i as i64 - 4);
            let v = f64::from_bits(bits as u64);
            if i % 2 == 0 { v } else { -v }
        });
        check(xs, &mut worst);
        k = (k * 1.07).ceil();
    }
    // Within 2⁻⁶⁰ … 2⁻¹ (relative) of n·π/2, |n| up to 10⁵: both sides of
    // where the reduction's first round stops being enough (it cancels
    // more than 15 bits, |y₀| ≤ 2⁻¹⁵ |x|), lanes of either kind in one
    // vector, so that a vector takes the full reduction for some lanes
    // and keeps the first round for the others.
    for _ in 0..40_000 {
        let xs = std::array::from_fn(|_| {
            let n = (rng.next() % 200_001) as f64 - 100_000.0;
            let m = n * std::f64::consts::FRAC_PI_2;
            let off = m.abs().max(1.0) * (-(rng.unit() * 60.0)).exp2();
            if rng.next() & 1 == 0 {
                m + off
            } else {
                m - off
            }
        });
        check(xs, &mut worst);
    }
    // Special values.
    check(
        [
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            -5e-324,
            REDUCTION_LIMIT,
            f64::INFINITY,
            f64::NAN,
            f64::MAX,
        ],
        &mut worst,
    );
    eprintln!("largest difference: {} ulp at {:e}", worst.0, worst.1);
}

#[test]
fn signs_of_zero_and_the_pythagorean_identity() {
    let (s, c) = Lanes([0.0, -0.0, 1e-300, -1e-300]).sin_cos();
    assert_eq!(s.0[0].to_bits(), 0.0f64.to_bits(), "sin(+0) = +0");
    assert_eq!(s.0[1].to_bits(), (-0.0f64).to_bits(), "sin(−0) = −0");
    assert_eq!(s.0[2], 1e-300);
    assert_eq!(s.0[3], -1e-300);
    assert!(c.0.iter().all(|&x| x == 1.0), "cos of tiny arguments is 1");
    let mut rng = Rng(7);
    for _ in 0..10_000 {
        let xs: [f64; 4] = std::array::from_fn(|_| (rng.unit() - 0.5) * 1e4);
        let (s, c) = Lanes(xs).sin_cos();
        for (x, (s, c)) in xs.iter().zip(s.0.iter().zip(c.0)) {
            let one = s * s + c * c;
            assert!(
                (one - 1.0).abs() <= 4.0 * f64::EPSILON,
                "sin² + cos² at {x} = {one}"
            );
        }
    }
}

#[test]
fn lanes_outside_the_reduction_range_are_the_library_values() {
    let xs = [1.0, 2e6, -3e15, 0.5];
    let (s, c) = Lanes(xs).sin_cos();
    for l in [1, 2] {
        let (ws, wc) = f64::sin_cos(xs[l]);
        assert_eq!((s.0[l], c.0[l]), (ws, wc), "lane {l}");
    }
}
