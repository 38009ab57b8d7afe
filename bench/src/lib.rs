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

    /// The 50-link chain is emitted as loops over its bodies (forward
    /// dynamics, mass matrix, bias, inverse dynamics; `eom_gen::mech::looped`,
    /// chosen because its straight-line programs outgrow the instruction
    /// cache): compiled, they give the `f64` algorithms' ABA, CRBA and
    /// RNEA results at random states.
    #[test]
    fn compiled_loops_of_the_50_link_chain_match_the_twin() {
        use eom_gen::model::{Source, check};
        let mut spec = eom_gen::model::builder::n_link_chain(50, true);
        spec.name = "chain50".into();
        let sys = check(&Source::new("chain50", spec.to_ron()))
            .unwrap_or_else(|r| panic!("{r}"))
            .system;
        let twin = eom_gen::mech::Numeric::new(&sys).expect("twin");
        let model = super::chain50::Chain50::default();
        let mut rng = eom_gen::testkit::Rng(3);
        let close = |what: &str, got: &[f64], want: &[f64]| {
            let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            for (k, (g, w)) in got.iter().zip(want).enumerate() {
                assert!(
                    (g - w).abs() <= 1e-10 * scale,
                    "{what}[{k}]: got {g} want {w}"
                );
            }
        };
        for _ in 0..3 {
            let (qv, uv) = eom_gen::testkit::random_state(&sys, &mut rng);
            let (tv, av) = (rng.vec(50, 1.0), rng.vec(50, 1.0));
            let arr = |v: &[f64]| -> [f64; 50] { std::array::from_fn(|k| v[k]) };
            let (q, u, tau, udot) = (arr(&qv), arr(&uv), arr(&tv), arr(&av));
            let mut out = [0.0; 50];
            model.forward_dynamics(0.0, &q, &u, &tau, &mut out);
            let want = twin.forward_dynamics(&qv, &uv, 0.0, &tv, &[]).expect("fd");
            close("u̇", &out, &want);
            model.inverse_dynamics(0.0, &q, &u, &udot, &mut out);
            let want = twin.inverse_dynamics(&qv, &uv, &av, 0.0, &[]).expect("id");
            close("τ", &out, &want);
            let terms = twin.terms(&qv, &uv, 0.0, &[]).expect("terms");
            model.bias(0.0, &q, &u, &mut out);
            close("b", &out, &terms.bias);
            let mut m = [[0.0; 50]; 50];
            model.mass_matrix(0.0, &q, &mut m);
            for (i, row) in m.iter().enumerate() {
                close(&format!("M[{i}]"), row, &terms.mass_matrix[i]);
            }
        }
    }

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
