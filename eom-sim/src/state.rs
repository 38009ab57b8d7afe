//! Packing a model's positions and speeds into the integrators' state
//! `y = (q, u)` and back.
//!
//! ```
//! use eom_sim::state::{pack, unpack};
//! let (q0, u0) = ([1.0, 2.0], [3.0]);
//! let y: [f64; 3] = pack(&q0, &u0);
//! assert_eq!(y, [1.0, 2.0, 3.0]);
//! let (q, u): ([f64; 2], [f64; 1]) = unpack(&y);
//! assert_eq!((q, u), (q0, u0));
//! ```

use crate::model::Vector;

/// `y = (q, u)`: the positions, then the speeds. Entries beyond `N` are
/// dropped and missing ones are zero (the lengths are the model's, so
/// `N = NQ + NU` for a model's own `q0()` and `u0()`).
pub fn pack<const N: usize>(q: &[f64], u: &[f64]) -> [f64; N] {
    let mut y = [0.0; N];
    for (d, s) in y.iter_mut().zip(q.iter().chain(u)) {
        *d = *s;
    }
    y
}

/// `(q, u)` from a state `y = (q, u, …)`: the first `Q`'s length of
/// entries, then `U`'s (zero where `y` is short). With a model `M`:
/// `let (q, u): (M::Q, M::U) = unpack(&y);`.
pub fn unpack<Q: Vector, U: Vector>(y: &[f64]) -> (Q, U) {
    let (mut q, mut u) = (Q::ZERO, U::ZERO);
    let nq = q.as_ref().len();
    for (d, s) in q.as_mut().iter_mut().zip(y) {
        *d = *s;
    }
    for (d, s) in u.as_mut().iter_mut().zip(y.iter().skip(nq)) {
        *d = *s;
    }
    (q, u)
}
