//! Closure conditions of cut joints: they vanish at every bundled model's
//! initial state, and the rank of their Jacobian gives the true mobility —
//! 1 for Bricard's over-constrained loop although Grübler–Kutzbach says 0.

use eom_gen::mech::Numeric;
use eom_gen::{System, check_file};

fn system(name: &str) -> System {
    let path = format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    check_file(&path).unwrap_or_else(|r| panic!("{r}")).system
}

#[test]
fn closure_conditions_vanish_at_the_initial_state() {
    for (name, equations) in [
        // Planar loops keep only the two in-plane equations per hinge.
        ("fourbar", 2),
        ("slider_crank", 2),
        ("slider_crank_driven", 2),
        ("andrews", 6),
        // Spatial hinge: 3 position + 2 axis-alignment equations.
        ("bricard", 5),
        // Five cut ball joints: 3 each.
        ("stewart", 15),
        ("stewart_driven", 15),
    ] {
        let sys = system(name);
        let num = Numeric::new(&sys).expect("numeric");
        let phi = num.constraints(&sys.q0(), 0.0).expect("phi");
        assert_eq!(phi.len(), equations, "{name}: number of closure equations");
        for (k, x) in phi.iter().enumerate() {
            assert!(
                x.abs() < 1e-12,
                "{name}: Φ[{k}] = {x:e} at the initial state"
            );
        }
    }
}

#[test]
fn jacobian_rank_gives_the_true_mobility() {
    for (name, grubler, mobility) in [
        ("fourbar", 1, 1),
        ("slider_crank", 1, 1),
        ("slider_crank_driven", 0, 0),
        ("andrews", 1, 1),
        ("bricard", 0, 1),
        ("stewart", 6, 6),
        ("stewart_driven", 0, 0),
    ] {
        let sys = system(name);
        assert_eq!(sys.grubler.dof, grubler, "{name}: Grübler–Kutzbach");
        let num = Numeric::new(&sys).expect("numeric");
        let m = num.mobility(&sys.q0(), 0.0).expect("mobility");
        assert_eq!(
            m.dof, mobility,
            "{name}: mobility from the rank of Φ_q ({m:?})"
        );
    }
}
