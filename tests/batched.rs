//! The batched functions of every bundled model (`NAME_lanes::<W>`, the
//! committed `generated/` code emitted with lanes) against the single-state
//! functions, lane by lane: a pack of different random states (and
//! multipliers), every function of the table, equal to rounding (the
//! lanes' `sin_cos` is a polynomial within 1 ulp of the C library's, so
//! results agree to a few ulp of the result's scale, not bit for bit).
//! The first-order system over lanes (`OdeLanes`) against `OdeSystem`.

use eom_gen::testkit::Rng;
use eom_generated as g;
use eom_sim::{Batched, Lanes, OdeLanes, OdeSystem, PointLanes};

/// Relative agreement asked of every entry, against the largest entry of
/// the single-state result (and at least 1).
const TOL: f64 = 1e-11;

/// One state: `t`, `q`, `u`, `u̇`, `τ`, `λ`.
type State = (f64, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

/// `W` random states of `M` (positions about `q0`, unit quaternions),
/// their pack, and a random pack of every other argument; compares every
/// function lane by lane.
fn lanes_match<M: Batched + Default, const W: usize>(name: &str) {
    lanes_match_but::<M, W>(name, &[]);
}

/// [`lanes_match`] for a scene whose single-state `evaluate` derives the
/// functions in `derived` from others (the mass matrix and the bias
/// from inverse dynamics), which the batched functions do not offer: those are checked
/// to be refused, every other one lane by lane.
fn lanes_match_but<M: Batched + Default, const W: usize>(name: &str, derived: &[&str]) {
    let model = M::default();
    let models = [model; W];
    let mut rng = Rng(0x5EED_0000_0000_0028);
    let nc = M::FUNCTIONS
        .iter()
        .find(|i| i.name == "constraints")
        .map_or(0, |i| {
            // Φ, Φ̇, γ, J: 3 NC + NC NU.
            i.len / (3 + M::NU)
        });
    let q0 = model.q0();
    let mut states = Vec::new();
    for _ in 0..W {
        let mut q = q0;
        for x in q.as_mut() {
            *x += rng.uniform();
        }
        model.normalize(&mut q);
        let v = |rng: &mut Rng, n: usize| rng.vec(n, 2.0);
        states.push((
            rng.uniform(),
            q.as_ref().to_vec(),
            v(&mut rng, M::NU),
            v(&mut rng, M::NU),
            v(&mut rng, M::NU),
            v(&mut rng, nc),
        ));
    }
    let pack = |f: &dyn Fn(&State) -> &Vec<f64>, n: usize| -> Vec<Lanes<W>> {
        (0..n)
            .map(|k| Lanes(std::array::from_fn(|l| f(&states[l])[k])))
            .collect()
    };
    let (q, u) = (pack(&|s| &s.1, M::NQ), pack(&|s| &s.2, M::NU));
    let (udot, tau, lambda) = (
        pack(&|s| &s.3, M::NU),
        pack(&|s| &s.4, M::NU),
        pack(&|s| &s.5, nc),
    );
    let at = PointLanes {
        t: Lanes(std::array::from_fn(|l| states[l].0)),
        q: &q,
        u: &u,
        udot: &udot,
        tau: &tau,
        lambda: &lambda,
    };
    for info in M::FUNCTIONS {
        let mut got = vec![Lanes::<W>::splat(f64::NAN); info.len];
        if derived.contains(&info.name) {
            assert!(
                !M::evaluate_lanes(&models, info.name, &at, &mut got),
                "{name}: `{}` is batched after all",
                info.name
            );
            continue;
        }
        if !M::evaluate_lanes(&models, info.name, &at, &mut got) {
            panic!("{name}: no batched `{}`", info.name);
        }
        for (l, s) in states.iter().enumerate() {
            let one = eom_sim::Point {
                t: s.0,
                q: &s.1,
                u: &s.2,
                udot: &s.3,
                tau: &s.4,
                lambda: &s.5,
            };
            let mut want = vec![f64::NAN; info.len];
            assert!(model.evaluate(info.name, &one, &mut want));
            let scale = want.iter().map(|x| x.abs()).fold(1.0, f64::max);
            for (k, (g, w)) in got.iter().map(|x| x.0[l]).zip(&want).enumerate() {
                assert!(
                    (g - w).abs() <= TOL * scale,
                    "{name} {}[{k}], lane {l} of {W}: batched {g}, single state {w}",
                    info.name
                );
            }
        }
    }
    // Wrong lengths and unknown names are refused, not a panic.
    assert!(!M::evaluate_lanes(
        &models,
        "no_such_function",
        &at,
        &mut []
    ));
    let short = PointLanes { q: &q[..0], ..at };
    assert!(
        M::NQ == 0 || !M::evaluate_lanes(&models, "qdot", &short, &mut [Lanes::splat(0.0); 64])
    );
}

/// `OdeLanes::rhs_lanes` against `OdeSystem::rhs` lane by lane.
fn rhs_match<M, const N: usize, const W: usize>(name: &str)
where
    M: Batched + Default + OdeSystem<N> + OdeLanes<N>,
{
    let model = M::default();
    let mut rng = Rng(0x0DE_0028);
    let ys: Vec<[f64; N]> = (0..W)
        .map(|_| {
            let mut y = [0.0; N];
            y[..M::NQ].copy_from_slice(model.q0().as_ref());
            for x in &mut y {
                *x += rng.uniform();
            }
            y
        })
        .collect();
    let y: [Lanes<W>; N] = std::array::from_fn(|k| Lanes(std::array::from_fn(|l| ys[l][k])));
    let mut dy = [Lanes::splat(f64::NAN); N];
    let t = Lanes::splat(0.5);
    M::rhs_lanes(&[model; W], t, &y, &mut dy);
    for (l, yl) in ys.iter().enumerate() {
        let mut want = [0.0; N];
        model.rhs(0.5, yl, &mut want);
        let scale = want.iter().map(|x| x.abs()).fold(1.0, f64::max);
        for k in 0..N {
            assert!(
                (dy[k].0[l] - want[k]).abs() <= TOL * scale,
                "{name} rhs[{k}], lane {l}: batched {}, single state {}",
                dy[k].0[l],
                want[k]
            );
        }
    }
}

#[test]
fn every_bundled_model_batched_equals_single_state() {
    lanes_match::<g::andrews::Andrews, 4>("andrews");
    lanes_match::<g::arm7::Arm7, 4>("arm7");
    lanes_match::<g::arm7::Arm7, 8>("arm7");
    // With its derivatives: `−M⁻¹ ∂ID/∂x` as a dense product over lanes.
    lanes_match_but::<g::arm7_derivatives::Arm7Derivatives, 4>(
        "arm7_derivatives",
        &["mass_matrix", "bias"],
    );
    lanes_match::<g::arm7_flex::Arm7Flex, 4>("arm7_flex");
    lanes_match::<g::bouncing_ball::BouncingBall, 4>("bouncing_ball");
    lanes_match::<g::bricard::Bricard, 4>("bricard");
    lanes_match::<g::double_pendulum::DoublePendulum, 4>("double_pendulum");
    lanes_match::<g::fourbar::Fourbar, 4>("fourbar");
    lanes_match::<g::fourbar_cable::FourbarCable, 4>("fourbar_cable");
    lanes_match::<g::fourbar_n2::FourbarN2, 4>("fourbar_n2");
    lanes_match::<g::fourbar_n4::FourbarN4, 4>("fourbar_n4");
    lanes_match::<g::free_body::FreeBody, 4>("free_body");
    lanes_match::<g::heavy_top::HeavyTop, 4>("heavy_top");
    lanes_match::<g::hub_beam::HubBeam, 4>("hub_beam");
    lanes_match::<g::pendulum::Pendulum, 4>("pendulum");
    lanes_match::<g::pendulum_rod::PendulumRod, 4>("pendulum_rod");
    lanes_match::<g::rolling_disk::RollingDisk, 4>("rolling_disk");
    lanes_match::<g::slider_crank::SliderCrank, 4>("slider_crank");
    lanes_match::<g::slider_crank_driven::SliderCrankDriven, 4>("slider_crank_driven");
    lanes_match::<g::slider_crank_flex::SliderCrankFlex, 4>("slider_crank_flex");
    lanes_match::<g::slider_crank_simeon::SliderCrankSimeon, 4>("slider_crank_simeon");
    lanes_match::<g::spin_up::SpinUp, 4>("spin_up");
    lanes_match::<g::stewart::Stewart, 4>("stewart");
    lanes_match::<g::stewart_driven::StewartDriven, 4>("stewart_driven");
    lanes_match::<g::whipple::Whipple, 4>("whipple");
}

#[test]
fn batched_first_order_system_equals_single_state() {
    rhs_match::<g::pendulum::Pendulum, 2, 4>("pendulum");
    rhs_match::<g::arm7::Arm7, 14, 8>("arm7");
    rhs_match::<g::heavy_top::HeavyTop, 7, 4>("heavy_top");
    rhs_match::<g::free_body::FreeBody, 13, 4>("free_body");
}
