//! Helpers for tests of generated models: a small deterministic random
//! generator and random states that respect unit quaternions.

use crate::system::System;

/// xorshift64* — deterministic, seedable, no dependencies; uniform in
/// [−1, 1) from [`Rng::uniform`].
#[derive(Clone, Debug)]
pub struct Rng(pub u64);

impl Rng {
    /// The next number in [−1, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (x >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    /// `n` numbers in [−scale, scale).
    pub fn vec(&mut self, n: usize, scale: f64) -> Vec<f64> {
        (0..n).map(|_| scale * self.uniform()).collect()
    }
}

/// Positions within ±0.8 of the initial ones, quaternions normalised, and
/// speeds in ±1.5.
pub fn random_state(sys: &System, rng: &mut Rng) -> (Vec<f64>, Vec<f64>) {
    let mut q: Vec<f64> = sys.q0().iter().map(|q| q + 0.8 * rng.uniform()).collect();
    for a in sys.quaternion_indices() {
        let n = q[a..a + 4].iter().map(|x| x * x).sum::<f64>().sqrt();
        q[a..a + 4].iter_mut().for_each(|x| *x /= n);
    }
    let u = rng.vec(sys.nu(), 1.5);
    (q, u)
}

/// What `eom-gen check` says of a model file's `text` read as `path`:
/// `"valid"`, or the whole report; panics if a diagnostic has no
/// location, since every error in a model file must point at its place.
pub fn diagnose(path: &str, text: &str) -> String {
    match crate::model::check(&crate::model::Source::new(path, text.to_string())) {
        Ok(_) => "valid".into(),
        Err(report) => {
            assert!(
                report.diagnostics.iter().all(|d| d.span.is_some()),
                "every diagnostic has a location"
            );
            report.to_string()
        }
    }
}

/// Every normal impulse of every contact event of `report` is a push,
/// `Λ ≥ 0` (to the round-off of the runtime's rest speed, 1e-9 m/s, on a
/// node's mass): a plastic (rest) impulse with `Λ < 0` would mean the
/// contact separates there. Prints each event with `verbose`, and the
/// count with the lowest impulse.
pub fn no_event_pulls(report: &eom_sim::RunReport, verbose: bool) {
    let mut lowest = f64::INFINITY;
    for ev in &report.contact_events {
        for c in &ev.contacts {
            if verbose {
                eprintln!(
                    "  {:?} at {:.9} s: {} Λ = {:.3e} N s, ġ {:.3e} → {:.3e} m/s",
                    ev.kind, ev.t, c.contact, c.impulse, c.speed_before, c.speed_after
                );
            }
            lowest = lowest.min(c.impulse);
            assert!(
                c.impulse >= -1e-10,
                "{:?} at {}: {} takes Λ = {} N s (ġ {} → {}): a pull",
                ev.kind,
                ev.t,
                c.contact,
                c.impulse,
                c.speed_before,
                c.speed_after
            );
        }
    }
    eprintln!(
        "{} events, lowest normal impulse {lowest:e} N s",
        report.contact_events.len()
    );
}

/// How deep the `let`s of generated `source` nest, as prettyplease writes
/// it, and the function where they nest deepest: per function, the
/// `let`s since its start or since its latest block (a bare `{` line).
/// rustc overflows its stack on about 2 950 nested `let`s when it writes
/// debug info, so emitted code keeps this at most
/// [`crate::emit::BLOCK_LIMIT`] + 1 (the `let` of the array the blocks
/// share).
pub fn deepest_lets(source: &str) -> (usize, &str) {
    let (mut most, mut n, mut at, mut current) = (0, 0, "", "");
    for line in source.lines().map(str::trim) {
        if line.starts_with("fn ") || line.starts_with("pub fn ") {
            (n, current) = (0, line);
        } else if line == "{" {
            n = 0;
        } else if line.starts_with("let ") {
            n += 1;
            if n > most {
                (most, at) = (n, current);
            }
        }
    }
    (most, at)
}
