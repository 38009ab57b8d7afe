//! Benchmark models: the bundled ones come from `eom-generated`; spatial
//! chains of 10 and 50 links are generated here at build time.

/// Spatial chain of 10 links (axes z, y, z, …).
pub mod chain10 {
    include!(concat!(env!("OUT_DIR"), "/chain10.rs"));
}

/// Spatial chain of 50 links.
pub mod chain50 {
    include!(concat!(env!("OUT_DIR"), "/chain50.rs"));
}

/// The 10-link chain emitted with `f64::mul_add` (`Builder::fma`).
pub mod chain10_fma {
    include!(concat!(env!("OUT_DIR"), "/chain10_fma.rs"));
}

#[cfg(test)]
mod tests {
    use eom_sim::{Model, Vector};

    #[test]
    fn fused_multiply_adds_give_the_same_dynamics() {
        // mul_add rounds once instead of twice: results agree to round-off.
        let (a, b) = (
            super::chain10::Chain10::default(),
            super::chain10_fma::Chain10Fma::default(),
        );
        let mut q = a.q0();
        for (k, x) in q.iter_mut().enumerate() {
            *x += 0.3 * (k as f64).sin();
        }
        let u: [f64; 10] = std::array::from_fn(|k| 0.5 * (k as f64).cos());
        let (mut ua, mut ub) = (<[f64; 10]>::ZERO, <[f64; 10]>::ZERO);
        a.forward_dynamics(0.0, &q, &u, &[0.1; 10], &mut ua);
        b.forward_dynamics(0.0, &q, &u, &[0.1; 10], &mut ub);
        for k in 0..10 {
            assert!(
                (ua[k] - ub[k]).abs() < 1e-11 * ua[k].abs().max(1.0),
                "u̇[{k}]: {} vs {}",
                ua[k],
                ub[k]
            );
        }
    }
}
