//! The large-model runtime (`eom_sim::large`) on systems with closed forms,
//! through the same element interface the ANCF kernels use: a chain of
//! linear springs with lumped masses and optional dashpots (a 1-D "element"
//! of two coordinates).
//!
//! Physics checked:
//! - statics: a chain fixed at one end under a tip force stretches every
//!   spring by `F/k` (exact; linear, so one Newton iteration per step);
//!   under its own weight the spring `j` carries the weight below it;
//! - dynamics: free vibration of the chain against its modal solution
//!   `q(t) = Σ φ_k (a_k cos ω_k t + b_k sin ω_k t)` (eigenpairs of
//!   `M⁻½ K M⁻½`), generalized-α converging at order 2 for `ρ∞ = 1` and
//!   `ρ∞ = 0.7`, RK4 at order 4;
//! - the trapezoidal rule (`ρ∞ = 1`) keeps the energy of the linear
//!   undamped chain to round-off; `ρ∞ < 1` and dashpots dissipate it.

use eom_sim::elements::ElementKernel;
use eom_sim::large::{
    AlphaOptions, Elements, GeneralizedAlpha, ModelBuilder, State, StaticOptions, StructuralModel,
    integrate_rk4, solve_static,
};
use nalgebra::{DMatrix, DVector};

/// A linear spring of rest length `L` and stiffness `k` with a dashpot `c`
/// and lumped mass `rhoA L` split over its two ends.
struct Spring;

impl ElementKernel<2, 4> for Spring {
    const NAME: &'static str = "Spring";
    const NODE_COORDS: usize = 1;
    const DIM: usize = 1;
    const PARAMS: [&'static str; 4] = ["L", "k", "c", "rhoA"];
    fn internal_forces(q: &[f64; 2], qd: &[f64; 2], p: &[f64; 4], f: &mut [f64; 2]) {
        let s = p[1] * (q[1] - q[0] - p[0]) + p[2] * (qd[1] - qd[0]);
        *f = [-s, s];
    }
    fn internal_jacobians(
        _q: &[f64; 2],
        _qd: &[f64; 2],
        p: &[f64; 4],
        k: &mut [[f64; 2]; 2],
        d: &mut [[f64; 2]; 2],
    ) {
        *k = [[p[1], -p[1]], [-p[1], p[1]]];
        *d = [[p[2], -p[2]], [-p[2], p[2]]];
    }
    fn mass(p: &[f64; 4], m: &mut [[f64; 2]; 2]) {
        let h = 0.5 * p[3] * p[0];
        *m = [[h, 0.0], [0.0, h]];
    }
    fn uniform_load(p: &[f64; 4], w: &[f64; 3], f: &mut [f64; 2]) {
        let h = 0.5 * w[0] * p[0];
        *f = [h, h];
    }
}

const L: f64 = 0.5;
const K: f64 = 400.0;
const RHO_A: f64 = 2.0;

/// `n` springs from node 0 (fixed) to node `n`, nodes at `j L`.
fn chain(n: usize, c: f64, tip: f64, g: f64) -> StructuralModel {
    let q0: Vec<f64> = (0..=n).map(|j| j as f64 * L).collect();
    let mut els = Elements::<Spring, 2, 4>::new();
    for j in 0..n {
        els.push([j, j + 1], [L, K, c, RHO_A], [q0[j], q0[j + 1]]);
    }
    ModelBuilder::new(q0)
        .elements(els)
        .fix(0)
        .gravity([g, 0.0, 0.0])
        .point_load(n, tip)
        .build()
}

#[test]
fn static_chain_under_tip_force_and_own_weight() {
    let n = 40;
    let (f, g) = (30.0, 9.81);
    let model = chain(n, 0.0, f, g);
    let sol = solve_static(&model, &StaticOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    // Spring j (between nodes j and j+1) carries the tip force and the
    // weight of the mass below it: lumped half-masses at nodes j+1..n.
    let m = RHO_A * L;
    let mut u = 0.0;
    let mut worst: f64 = 0.0;
    for j in 0..n {
        let below = m * (n - j - 1) as f64 + 0.5 * m;
        u += (f + below * g) / K;
        let err = (sol.q[j + 1] - (j + 1) as f64 * L - u).abs();
        worst = worst.max(err);
    }
    assert!(worst < 1e-12, "{worst}");
    // Linear: the first load step converges in one Newton iteration, the
    // later ones at once from the secant predictor (exact when the
    // response is linear in the load).
    assert_eq!(sol.steps.len(), 10);
    assert_eq!(sol.steps[0].iterations(), 1, "{:?}", sol.steps);
    assert!(
        sol.steps[1..].iter().all(|s| s.iterations() == 0),
        "{:?}",
        sol.steps
    );
    assert_eq!(sol.cuts, 0);
}

#[test]
fn static_refuses_an_unsupported_chain() {
    // Nothing fixed: a free rigid translation makes the tangent singular.
    let n = 4;
    let q0: Vec<f64> = (0..=n).map(|j| j as f64 * L).collect();
    let mut els = Elements::<Spring, 2, 4>::new();
    for j in 0..n {
        els.push([j, j + 1], [L, K, 0.0, RHO_A], [q0[j], q0[j + 1]]);
    }
    let model = ModelBuilder::new(q0)
        .elements(els)
        .point_load(n, 1.0)
        .build();
    let err = solve_static(&model, &StaticOptions::default())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        err.contains("singular") || err.contains("did not converge"),
        "{err}"
    );
}

/// Modal solution of the undamped chain from displacement `u0`, at rest.
fn modal(model: &StructuralModel, u0: &[f64], t: f64) -> Vec<f64> {
    let n = model.n_free();
    let mut m = DMatrix::zeros(n, n);
    let mut k = DMatrix::zeros(n, n);
    let mut scratch = eom_sim::large::SparseMatrix::zeros(model.pattern().clone());
    let q = model.q0().to_vec();
    let zero = vec![0.0; q.len()];
    model.jacobian(&q, &zero, 1.0, 0.0, 0.0, &mut scratch);
    for i in 0..n {
        for j in 0..n {
            m[(i, j)] = model.mass().get(i, j);
            k[(i, j)] = scratch.get(i, j);
        }
    }
    let mh = m.map_diagonal(|x| 1.0 / x.sqrt());
    let mh = DMatrix::from_diagonal(&mh);
    let a = &mh * &k * &mh;
    let eig = a.symmetric_eigen();
    let y0 = DMatrix::from_diagonal(&m.map_diagonal(f64::sqrt)) * DVector::from_column_slice(u0);
    let c = eig.eigenvectors.transpose() * y0;
    let mut y = DVector::zeros(n);
    for (kk, w2) in eig.eigenvalues.iter().enumerate() {
        let w = w2.sqrt();
        y += eig.eigenvectors.column(kk) * c[kk] * (w * t).cos();
    }
    (mh * y).iter().copied().collect()
}

/// Initial displacement: a smooth stretch of the chain.
fn initial(model: &StructuralModel) -> (Vec<f64>, Vec<f64>) {
    let x0 = model.restrict(model.q0());
    let n = x0.len();
    let u0: Vec<f64> = (0..n)
        .map(|i| 0.01 * (std::f64::consts::PI * (i + 1) as f64 / (2.0 * n as f64)).sin())
        .collect();
    let q: Vec<f64> = x0.iter().zip(&u0).map(|(a, b)| a + b).collect();
    (q, u0)
}

fn alpha_error(model: &StructuralModel, rho: f64, h: f64, t_end: f64) -> (f64, f64) {
    let (q, u0) = initial(model);
    let n = q.len();
    let state = State {
        t: 0.0,
        q,
        v: vec![0.0; n],
    };
    let opts = AlphaOptions {
        h,
        rho_inf: rho,
        ..AlphaOptions::default()
    };
    let mut ga = GeneralizedAlpha::new(model, state, opts).unwrap_or_else(|e| panic!("{e}"));
    let e0 = model.energy(ga.q_full(), &ga.state().v);
    let mut drift: f64 = 0.0;
    ga.run_to(t_end, |s, qf| {
        drift = drift.max((model.energy(qf, &s.v) - e0).abs() / e0);
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let exact = modal(model, &u0, t_end);
    let x0 = model.restrict(model.q0());
    let err = (0..n)
        .map(|i| (ga.state().q[i] - x0[i] - exact[i]).abs())
        .fold(0.0, f64::max);
    (err, drift)
}

#[test]
fn generalized_alpha_is_second_order_and_trapezoidal_keeps_energy() {
    let model = chain(12, 0.0, 0.0, 0.0);
    let t_end = 0.4;
    for rho in [1.0, 0.7] {
        let hs = [4e-3, 2e-3, 1e-3];
        let errs: Vec<(f64, f64)> = hs
            .iter()
            .map(|&h| alpha_error(&model, rho, h, t_end))
            .collect();
        for w in errs.windows(2) {
            let order = (w[0].0 / w[1].0).log2();
            assert!(
                (order - 2.0).abs() < 0.15,
                "rho {rho}: order {order} from {errs:?}"
            );
        }
        if rho == 1.0 {
            for (_, drift) in &errs {
                assert!(*drift < 1e-11, "energy drift {drift}");
            }
        } else {
            // Numerical dissipation: the energy changes by far more than
            // round-off (it falls; the smooth mode loses little).
            assert!(errs[0].1 > 1e-8, "{errs:?}");
        }
    }
}

#[test]
fn rk4_is_fourth_order() {
    let model = chain(12, 0.0, 0.0, 0.0);
    let t_end = 0.4;
    let (q, u0) = initial(&model);
    let n = q.len();
    let exact = modal(&model, &u0, t_end);
    let x0 = model.restrict(model.q0());
    let errs: Vec<f64> = [25usize, 50, 100]
        .iter()
        .map(|&steps| {
            let state = State {
                t: 0.0,
                q: q.clone(),
                v: vec![0.0; n],
            };
            let (end, stats) = integrate_rk4(&model, state, t_end, steps, |_, _| {})
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(stats.force_evaluations, 4 * steps);
            (0..n)
                .map(|i| (end.q[i] - x0[i] - exact[i]).abs())
                .fold(0.0, f64::max)
        })
        .collect();
    for w in errs.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!((order - 4.0).abs() < 0.2, "order {order} from {errs:?}");
    }
}

#[test]
fn dashpots_dissipate_exactly_what_they_absorb() {
    // With dashpots the energy falls monotonically; with the trapezoidal
    // rule on a linear system the discrete energy balance is exact:
    // E_{n+1} − E_n = −h v̄ᵀ C v̄ with v̄ the step's mean velocity.
    let model = chain(8, 5.0, 0.0, 0.0);
    let (q, _) = initial(&model);
    let n = q.len();
    let state = State {
        t: 0.0,
        q,
        v: vec![0.0; n],
    };
    let h = 1e-3;
    let opts = AlphaOptions {
        h,
        ..AlphaOptions::default()
    };
    let mut ga = GeneralizedAlpha::new(&model, state, opts).unwrap_or_else(|e| panic!("{e}"));
    let mut c = eom_sim::large::SparseMatrix::zeros(model.pattern().clone());
    let qf = model.q0().to_vec();
    model.jacobian(&qf, &vec![0.0; qf.len()], 0.0, 1.0, 0.0, &mut c);
    let e0 = model.energy(ga.q_full(), &ga.state().v);
    let mut e_prev = e0;
    let mut v_prev = ga.state().v.clone();
    let mut worst: f64 = 0.0;
    for _ in 0..300 {
        ga.step().unwrap_or_else(|e| panic!("{e}"));
        let e = model.energy(ga.q_full(), &ga.state().v);
        let vbar: Vec<f64> = v_prev
            .iter()
            .zip(&ga.state().v)
            .map(|(a, b)| 0.5 * (a + b))
            .collect();
        let diss = h * c.quadratic_form(&vbar);
        assert!(e < e_prev);
        worst = worst.max(((e_prev - e) - diss).abs() / e0);
        e_prev = e;
        v_prev = ga.state().v.clone();
    }
    assert!(worst < 1e-12, "{worst}");
    assert!(e_prev < e0, "{e_prev} {e0}");
}
