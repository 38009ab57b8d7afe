//! The recursive algorithms on `f64` against each other and against
//! closed forms: ABA = M⁻¹(τ − b) (dense and tree-sparse LᵀDL),
//! RNEA(FD(τ)) = τ, M u = ∂T/∂u, dE/dt = uᵀτ, and the mass matrices and
//! accelerations written out by hand for the double pendulum, the heavy
//! top, the torque-free body and Andrews' mechanism (Hairer & Wanner VII.7).

use eom_gen::mech::Numeric;
use eom_gen::mech::solve_dense;
use eom_gen::testkit::{Rng, random_state};
use eom_gen::{System, check_file};

fn system(name: &str) -> System {
    let path = format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    check_file(&path).unwrap_or_else(|r| panic!("{r}")).system
}

/// Every bundled model; closed loops are evaluated as their spanning trees
/// (cut joints ignored), which is a valid tree system in its own right.
const MODELS: [&str; 13] = [
    "pendulum",
    "double_pendulum",
    "arm7",
    "heavy_top",
    "free_body",
    "fourbar",
    "slider_crank",
    "slider_crank_driven",
    "andrews",
    "bricard",
    "stewart",
    "stewart_driven",
    "rolling_disk",
];

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn scale(a: &[f64]) -> f64 {
    a.iter().map(|x| x.abs()).fold(1.0, f64::max)
}

#[test]
fn aba_equals_mass_matrix_solve_dense_and_sparse() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for name in MODELS {
        let sys = system(name);
        let num = Numeric::new(&sys).unwrap_or_else(|e| panic!("{name}: {e}"));
        for _ in 0..5 {
            let (q, u) = random_state(&sys, &mut rng);
            let tau = rng.vec(sys.nu(), 2.0);
            let t = rng.uniform().abs();
            let aba = num.forward_dynamics(&q, &u, t, &tau, &[]).expect("aba");
            let sparse = num
                .forward_dynamics_ltdl(&q, &u, t, &tau, &[])
                .expect("ltdl");
            let terms = num.terms(&q, &u, t, &[]).expect("terms");
            let rhs: Vec<f64> = tau.iter().zip(&terms.bias).map(|(t, b)| t - b).collect();
            let dense = solve_dense(&terms.mass_matrix, rhs);
            let tol = 1e-9 * scale(&aba);
            assert!(
                max_abs_diff(&aba, &dense) < tol,
                "{name}: ABA {aba:?} vs M⁻¹(τ − b) {dense:?}"
            );
            assert!(
                max_abs_diff(&aba, &sparse) < tol,
                "{name}: ABA {aba:?} vs LᵀDL {sparse:?}"
            );
        }
    }
}

#[test]
fn inverse_dynamics_inverts_forward_dynamics() {
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    for name in MODELS {
        let sys = system(name);
        let num = Numeric::new(&sys).unwrap_or_else(|e| panic!("{name}: {e}"));
        for _ in 0..5 {
            let (q, u) = random_state(&sys, &mut rng);
            let tau = rng.vec(sys.nu(), 2.0);
            let ud = num.forward_dynamics(&q, &u, 0.3, &tau, &[]).expect("fd");
            let back = num.inverse_dynamics(&q, &u, &ud, 0.3, &[]).expect("id");
            assert!(
                max_abs_diff(&back, &tau) < 1e-9 * scale(&tau).max(scale(&ud)),
                "{name}: RNEA(FD(τ)) = {back:?}, want τ = {tau:?}"
            );
        }
    }
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_and_gives_the_momentum() {
    // M u = ∂T/∂u (generalised momentum), by central differences of T.
    // (Not for prescribed motion: there T also holds the driven speeds.)
    let mut rng = Rng(0x94D0_49BB_1331_11EB);
    for name in MODELS.into_iter().filter(|n| !n.ends_with("_driven")) {
        let sys = system(name);
        let num = Numeric::new(&sys).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (q, u) = random_state(&sys, &mut rng);
        let m = num.terms(&q, &u, 0.0, &[]).expect("terms").mass_matrix;
        for i in 0..m.len() {
            for j in 0..m.len() {
                assert!(
                    (m[i][j] - m[j][i]).abs() < 1e-12 * scale(&m[i]),
                    "{name}: M not symmetric at ({i}, {j})"
                );
            }
            assert!(m[i][i] > 0.0, "{name}: M[{i}][{i}] = {}", m[i][i]);
        }
        for k in 0..u.len() {
            let h = 1e-6;
            let mut up = u.clone();
            let mut um = u.clone();
            up[k] += h;
            um[k] -= h;
            let t = |u: &[f64]| num.energy(&q, u, 0.0).expect("energy").0;
            let dt_du = (t(&up) - t(&um)) / (2.0 * h);
            let mu: f64 = (0..u.len()).map(|j| m[k][j] * u[j]).sum();
            assert!(
                (dt_du - mu).abs() < 1e-6 * (1.0 + mu.abs()),
                "{name}: (M u)[{k}] = {mu}, ∂T/∂u = {dt_du}"
            );
        }
    }
}

/// One classical Runge–Kutta step of the equations of motion.
fn rk4(num: &Numeric, q: &[f64], u: &[f64], t: f64, h: f64, tau: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let f = |q: &[f64], u: &[f64], t: f64| {
        (
            num.qdot(q, u),
            num.forward_dynamics(q, u, t, tau, &[]).expect("fd"),
        )
    };
    let add = |a: &[f64], b: &[f64], s: f64| -> Vec<f64> {
        a.iter().zip(b).map(|(a, b)| a + s * b).collect()
    };
    let (k1q, k1u) = f(q, u, t);
    let (k2q, k2u) = f(&add(q, &k1q, h / 2.0), &add(u, &k1u, h / 2.0), t + h / 2.0);
    let (k3q, k3u) = f(&add(q, &k2q, h / 2.0), &add(u, &k2u, h / 2.0), t + h / 2.0);
    let (k4q, k4u) = f(&add(q, &k3q, h), &add(u, &k3u, h), t + h);
    let comb = |x: &[f64], a: &[f64], b: &[f64], c: &[f64], d: &[f64]| -> Vec<f64> {
        (0..x.len())
            .map(|i| x[i] + h / 6.0 * (a[i] + 2.0 * b[i] + 2.0 * c[i] + d[i]))
            .collect()
    };
    (
        comb(q, &k1q, &k2q, &k3q, &k4q),
        comb(u, &k1u, &k2u, &k3u, &k4u),
    )
}

#[test]
fn energy_rate_is_the_power_of_the_applied_forces() {
    // dE/dt = uᵀ τ for the conservative models driven by an extra τ; for
    // Andrews also + mom·β̇ (the drive torque). Central difference over two
    // RK4 steps of ±h; the O(h²) error is far below the tolerance.
    let mut rng = Rng(0xBF58_476D_1CE4_E5B9);
    for name in [
        "pendulum",
        "double_pendulum",
        "arm7",
        "heavy_top",
        "free_body",
        "fourbar",
        "bricard",
        "andrews",
    ] {
        let sys = system(name);
        let num = Numeric::new(&sys).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (q, u) = random_state(&sys, &mut rng);
        let tau = rng.vec(sys.nu(), 1.0);
        let h = if name == "andrews" { 1e-6 } else { 1e-4 };
        let energy = |(q, u): (Vec<f64>, Vec<f64>)| {
            let (t, v) = num.energy(&q, &u, 0.0).expect("energy");
            t + v
        };
        let rate = (energy(rk4(&num, &q, &u, 0.0, h, &tau))
            - energy(rk4(&num, &q, &u, 0.0, -h, &tau)))
            / (2.0 * h);
        let mut power: f64 = u.iter().zip(&tau).map(|(u, t)| u * t).sum();
        if name == "andrews" {
            power += 0.033 * u[0];
        }
        assert!(
            (rate - power).abs() < 1e-6 * (1.0 + power.abs() + rate.abs()),
            "{name}: dE/dt = {rate}, power = {power}"
        );
    }
}

#[test]
fn double_pendulum_mass_matrix_and_pendulum_acceleration_in_closed_form() {
    // M11 = (m1 + m2) l1² + m2 l2² + 2 m2 l1 l2 cos q2, M12 = m2 l2² + m2 l1 l2 cos q2, M22 = m2 l2².
    let sys = system("double_pendulum");
    let num = Numeric::new(&sys).expect("numeric");
    for q2 in [-2.0, 0.3, 1.7] {
        let m = num
            .terms(&[0.4, q2], &[0.0, 0.0], 0.0, &[])
            .expect("terms")
            .mass_matrix;
        let want = [
            [3.0 + 2.0 * q2.cos(), 1.0 + q2.cos()],
            [1.0 + q2.cos(), 1.0],
        ];
        for i in 0..2 {
            for j in 0..2 {
                assert!(
                    (m[i][j] - want[i][j]).abs() < 1e-14,
                    "M[{i}][{j}] = {}, want {}",
                    m[i][j],
                    want[i][j]
                );
            }
        }
    }
    // Pendulum: θ̈ = −(g/l) sin θ.
    let num = Numeric::new(&system("pendulum")).expect("numeric");
    for th in [0.1, 1.0, 2.5] {
        let ud = num
            .forward_dynamics(&[th], &[0.7], 0.0, &[0.0], &[])
            .expect("fd")[0];
        assert!(
            (ud + 9.81 * th.sin()).abs() < 1e-13,
            "θ̈ = {ud}, want {}",
            -9.81 * th.sin()
        );
    }
}

#[test]
fn heavy_top_and_free_body_follow_euler_equations() {
    // Heavy top about the fixed pivot: I_O ω̇ + ω × I_O ω = m c × Rᵀ g,
    // with I_O = I_c + m (|c|² 1 − c cᵀ), c = (0, 1, 0), g = (0, 0, −9.81).
    let num = Numeric::new(&system("heavy_top")).expect("numeric");
    let (a, b, m) = (0.234375, 0.46875, 15.0);
    let io = [a + m, b, a + m];
    let q = {
        let v = [0.8, 0.3, -0.4, 0.2];
        let n = v.iter().map(|x: &f64| x * x).sum::<f64>().sqrt();
        v.map(|x| x / n)
    };
    let w = [0.4, 150.0, -4.61538];
    let ud = num
        .forward_dynamics(&q, &w, 0.0, &[0.0; 3], &[])
        .expect("fd");
    // Rᵀ g for the quaternion (w, x, y, z): third row of R times −9.81.
    let [qw, qx, qy, qz] = q;
    let r_row3 = [
        2.0 * (qx * qz - qw * qy),
        2.0 * (qy * qz + qw * qx),
        1.0 - 2.0 * (qx * qx + qy * qy),
    ];
    let g_body = r_row3.map(|x| -9.81 * x);
    let c = [0.0, 1.0, 0.0];
    let torque = [
        m * (c[1] * g_body[2] - c[2] * g_body[1]),
        m * (c[2] * g_body[0] - c[0] * g_body[2]),
        m * (c[0] * g_body[1] - c[1] * g_body[0]),
    ];
    let iw = [io[0] * w[0], io[1] * w[1], io[2] * w[2]];
    let gyro = [
        w[1] * iw[2] - w[2] * iw[1],
        w[2] * iw[0] - w[0] * iw[2],
        w[0] * iw[1] - w[1] * iw[0],
    ];
    for k in 0..3 {
        let want = (torque[k] - gyro[k]) / io[k];
        assert!(
            (ud[k] - want).abs() < 1e-9 * want.abs().max(1.0),
            "ω̇[{k}] = {}, want {want}",
            ud[k]
        );
    }
    // Torque-free body with speeds (v, ω) in body axes: I ω̇ = −ω × I ω, v̇ = −ω × v.
    let num = Numeric::new(&system("free_body")).expect("numeric");
    let q = [0.1, -0.2, 0.3, 0.5, 0.5, 0.5, 0.5];
    let u = [0.3, -0.1, 0.2, 0.01, 1.0, 0.4];
    let ud = num
        .forward_dynamics(&q, &u, 0.0, &[0.0; 6], &[])
        .expect("fd");
    let (v, w, i) = ([u[0], u[1], u[2]], [u[3], u[4], u[5]], [1.0, 2.0, 3.0]);
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let wv = cross(w, v);
    let wiw = cross(w, [i[0] * w[0], i[1] * w[1], i[2] * w[2]]);
    for k in 0..3 {
        assert!(
            (ud[k] + wv[k]).abs() < 1e-14,
            "v̇[{k}] = {}, want {}",
            ud[k],
            -wv[k]
        );
        assert!(
            (ud[3 + k] + wiw[k] / i[k]).abs() < 1e-14,
            "ω̇[{k}] = {}, want {}",
            ud[3 + k],
            -wiw[k] / i[k]
        );
    }
}

#[test]
fn andrews_mass_matrix_matches_the_literature() {
    // Hairer & Wanner VII.7 with the literature's order (β, Θ, γ, Φ, δ, Ω, ε);
    // our tree numbers them (β, Θ, γ, δ, Φ, ε, Ω).
    let sys = system("andrews");
    let p = |n: &str| {
        sys.parameters
            .iter()
            .find(|p| p.name == n)
            .map_or(f64::NAN, |p| p.value.value)
    };
    let num = Numeric::new(&sys).expect("numeric");
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let ours_of_lit = [0, 1, 2, 4, 3, 6, 5];
    for _ in 0..5 {
        let q = rng.vec(7, 3.0);
        let m = num
            .terms(&q, &[0.0; 7], 0.0, &[])
            .expect("terms")
            .mass_matrix;
        let (th, ph, om) = (q[1], q[4], q[6]);
        let (m1, m2, m3, m4, m5, m6, m7) = (
            p("m1"),
            p("m2"),
            p("m3"),
            p("m4"),
            p("m5"),
            p("m6"),
            p("m7"),
        );
        let (i1, i2, i3, i4, i5, i6, i7) = (
            p("i1"),
            p("i2"),
            p("i3"),
            p("i4"),
            p("i5"),
            p("i6"),
            p("i7"),
        );
        let (ra, rr, da, sa, sb, e, ea) =
            (p("ra"), p("rr"), p("da"), p("sa"), p("sb"), p("e"), p("ea"));
        let (zt, ta, tb, zf, fa, u, ua, ub) = (
            p("zt"),
            p("ta"),
            p("tb"),
            p("zf"),
            p("fa"),
            p("u"),
            p("ua"),
            p("ub"),
        );
        let mut lit = [[0.0; 7]; 7];
        lit[0][0] = m1 * ra * ra + m2 * (rr * rr - 2.0 * da * rr * th.cos() + da * da) + i1 + i2;
        lit[1][0] = m2 * (da * da - da * rr * th.cos()) + i2;
        lit[1][1] = m2 * da * da + i2;
        lit[2][2] = m3 * (sa * sa + sb * sb) + i3;
        lit[3][3] = m4 * (e - ea).powi(2) + i4;
        lit[4][3] = m4 * ((e - ea).powi(2) + zt * (e - ea) * ph.sin()) + i4;
        lit[4][4] = m4 * (zt * zt + 2.0 * zt * (e - ea) * ph.sin() + (e - ea).powi(2))
            + m5 * (ta * ta + tb * tb)
            + i4
            + i5;
        lit[5][5] = m6 * (zf - fa).powi(2) + i6;
        lit[6][5] = m6 * ((zf - fa).powi(2) - u * (zf - fa) * om.sin()) + i6;
        lit[6][6] = m6 * ((zf - fa).powi(2) - 2.0 * u * (zf - fa) * om.sin() + u * u)
            + m7 * (ua * ua + ub * ub)
            + i6
            + i7;
        for r in 0..7 {
            for c in 0..7 {
                let want = if r >= c { lit[r][c] } else { lit[c][r] };
                let got = m[ours_of_lit[r]][ours_of_lit[c]];
                assert!(
                    (got - want).abs() < 1e-15,
                    "M{}{} = {got:e}, literature {want:e}",
                    r + 1,
                    c + 1
                );
            }
        }
    }
}
