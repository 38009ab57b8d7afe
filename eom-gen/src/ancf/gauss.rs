//! Gauss–Legendre rules on `[0, 1]`.

/// The `n`-point Gauss–Legendre rule on `[0, 1]`: nodes ascending and
/// weights summing to 1; exact for polynomials of degree `2n − 1`. Nodes
/// are the roots of the Legendre polynomial `P_n` by Newton's method from
/// Tricomi's initial guesses, to full `f64` precision.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        // Root i (descending on [−1, 1]).
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (p, d) = legendre(n, x);
            dp = d;
            let dx = p / d;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let (_, d) = legendre(n, x);
        if d.is_finite() {
            dp = d;
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out.push(((1.0 - x) / 2.0, w / 2.0));
    }
    out
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let n = n as f64;
    (p1, n * (x * p1 - p0) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::gauss_legendre;

    #[test]
    fn exact_to_degree_2n_minus_1() {
        for n in 1..=8 {
            let rule = gauss_legendre(n);
            for deg in 0..2 * n {
                let s: f64 = rule.iter().map(|&(x, w)| w * x.powi(deg as i32)).sum();
                let exact = 1.0 / (deg as f64 + 1.0);
                assert!(
                    (s - exact).abs() < 1e-15,
                    "n {n} degree {deg}: {s} vs {exact}"
                );
            }
        }
    }
}
