//! The flexible-body foundation (`eom_gen::flex`): the FE beam against the
//! Euler–Bernoulli closed forms, and the floating-frame mass matrix and
//! quadratic velocity vector against a brute-force body of rigid particles.

use eom_gen::flex::invariants::modal_geometric_stiffness;
use eom_gen::flex::{
    self, Beam, Deformation, Invariants, Modes, NodeDof, Reference, ffr, normal_modes,
};
use nalgebra::{Cholesky, DMatrix, DVector, Matrix3, Matrix3xX, Rotation3, RowDVector, Vector3};
use std::f64::consts::PI;

/// β_j L of a clamped–free beam: cos βL cosh βL = −1.
const CLAMPED_FREE: [f64; 3] = [
    1.875_104_068_711_961,
    4.694_091_132_974_175,
    7.854_757_438_237_613,
];
/// β_j L of a free–free beam: cos βL cosh βL = 1.
const FREE_FREE: [f64; 2] = [4.730_040_744_862_704, 7.853_204_624_095_838];

/// A beam whose four deformations have distinct frequencies (EI_y ≠ EI_z).
fn test_beam(n: usize) -> Beam {
    Beam::new(2.0, 3.0, 0.05, 7.0e6, 2.0e3, 5.0e3, 1.5e3, n).unwrap()
}

/// All natural frequencies of one deformation kind, ascending.
fn frequencies(beam: &Beam, reference: &Reference, kind: Deformation) -> Vec<f64> {
    let modes = normal_modes(beam, reference, beam.dofs() - 6).unwrap();
    (0..modes.count())
        .filter(|&i| beam.classify(&modes.shapes.column(i).into_owned()) == kind)
        .map(|i| modes.frequencies[i])
        .collect()
}

/// Euler–Bernoulli closed forms for the first few modes of each kind.
fn closed_form(beam: &Beam, reference: &Reference, kind: Deformation) -> Vec<f64> {
    let l = beam.length;
    let bending = |ei: f64, beta_l: &[f64]| -> Vec<f64> {
        beta_l
            .iter()
            .map(|b| b * b / (l * l) * (ei / beam.rho_a).sqrt())
            .collect()
    };
    // Rods: fixed–free (2j−1)π/2L, free–free jπ/L.
    let rod = |stiff: f64, inertia: f64, free_free: bool| -> Vec<f64> {
        (1..=3)
            .map(|j| {
                let kl = if free_free {
                    j as f64 * PI
                } else {
                    (2 * j - 1) as f64 * PI / 2.0
                };
                kl / l * (stiff / inertia).sqrt()
            })
            .collect()
    };
    let pinned: Vec<f64> = (1..=3).map(|j| j as f64 * PI).collect();
    let ff = *reference == Reference::MeanAxis;
    let beta: &[f64] = match reference {
        Reference::Clamped => &CLAMPED_FREE,
        Reference::PinnedPinned => &pinned,
        _ => &FREE_FREE,
    };
    match kind {
        Deformation::BendingXy => bending(beam.ei_z, beta),
        Deformation::BendingXz => bending(beam.ei_y, beta),
        Deformation::Axial => rod(beam.ea, beam.rho_a, ff),
        Deformation::Torsion => rod(beam.gj, beam.rho_ip, ff),
    }
}

/// Relative frequency errors for n = 2, 4, 8, 16 elements: `[n][kind][mode]`.
fn convergence(reference: &Reference) -> Vec<Vec<Vec<f64>>> {
    let kinds = [
        Deformation::BendingXy,
        Deformation::BendingXz,
        Deformation::Axial,
        Deformation::Torsion,
    ];
    [2, 4, 8, 16]
        .iter()
        .map(|&n| {
            let beam = test_beam(n);
            kinds
                .iter()
                .map(|&kind| {
                    let got = frequencies(&beam, reference, kind);
                    let want = closed_form(&beam, reference, kind);
                    want.iter().zip(&got).map(|(w, g)| (g - w) / w).collect()
                })
                .collect()
        })
        .collect()
}

/// The table printed with `--nocapture`, and the rates asserted: bending
/// (cubic Hermite, consistent mass) converges as h⁴, so each doubling of n
/// divides the frequency error by about 16; axial and torsion (linear
/// elements) as h², about 4. Consistent mass errs high (Rayleigh–Ritz).
fn check_convergence(name: &str, reference: &Reference) {
    let errors = convergence(reference);
    let kinds = ["bending x–y", "bending x–z", "axial", "torsion"];
    for (k, kind) in kinds.iter().enumerate() {
        for mode in 0..errors[0][k].len().min(3) {
            let row: Vec<String> = errors
                .iter()
                .map(|e| e[k].get(mode).map_or("—".into(), |v| format!("{v:.2e}")))
                .collect();
            eprintln!("| {name} | {kind} {} | {} |", mode + 1, row.join(" | "));
        }
        let first: Vec<f64> = errors.iter().map(|e| e[k][0]).collect();
        for (i, e) in first.iter().enumerate() {
            assert!(
                *e > -1e-12,
                "{name} {kind}: consistent mass errs high, got {e:e} at step {i}"
            );
        }
        let (lo, hi) = if k < 2 { (13.0, 17.0) } else { (3.7, 4.1) };
        // From n = 4 on (n = 2 is not yet asymptotic for bending).
        for w in first.windows(2).skip(1) {
            let ratio = w[0] / w[1];
            assert!(
                (lo..hi).contains(&ratio),
                "{name} {kind} mode 1: error ratio per doubling got {ratio:.2}, want {lo}..{hi} ({first:?})"
            );
        }
        let tol = if k < 2 { 1e-5 } else { 2e-3 };
        assert!(
            first[3] < tol,
            "{name} {kind}: error at n = 16 got {:e}",
            first[3]
        );
    }
}

#[test]
fn clamped_free_frequencies_converge_to_euler_bernoulli() {
    // Tangent frame: β L = 1.8751, 4.6941, 7.8548; rods (2j−1)π/2L.
    check_convergence("clamped–free", &Reference::Clamped);
}

#[test]
fn pinned_pinned_frequencies_converge_to_euler_bernoulli() {
    // Chord frame: bending β L = jπ; axial and torsion fixed at x = 0 only, so fixed–free.
    check_convergence("pinned–pinned", &Reference::PinnedPinned);
}

#[test]
fn free_free_frequencies_converge_to_euler_bernoulli() {
    // Mean axis: β L = 4.7300, 7.8532; rods jπ/L.
    check_convergence("free–free", &Reference::MeanAxis);
}

#[test]
fn simo_vu_quoc_beam_first_bending_frequency() {
    // Simo and Vu-Quoc (1986): L = 10 m, EA = 2.8e7 N, EI = 1.4e4 N m², ρA = 1.2 kg/m.
    // Clamped–free: ω₁ = 1.87510² / L² · √(EI/ρA) = 3.7977 rad/s (0.6044 Hz).
    // (GJ and ρI_p are not in the data and do not touch bending.)
    let want = CLAMPED_FREE[0].powi(2) / 100.0 * (1.4e4_f64 / 1.2).sqrt();
    assert!((want - 3.797_68).abs() < 1e-4, "closed form {want}");
    for (n, tol) in [(5, 2e-5), (10, 2e-6)] {
        let beam = Beam::new(10.0, 1.2, 1.0e-3, 2.8e7, 1.4e4, 1.4e4, 1.0e4, n).unwrap();
        let modes = normal_modes(&beam, &Reference::Clamped, 2).unwrap();
        // EI_y = EI_z: the first frequency is a pair, one per bending plane.
        for got in &modes.frequencies {
            let rel = (got - want) / want;
            eprintln!("Simo–Vu-Quoc n = {n}: ω₁ got {got:.9} rad/s, want {want:.9}, rel {rel:.2e}");
            assert!(
                (0.0..tol).contains(&rel),
                "n = {n}: ω₁ got {got}, want {want}"
            );
        }
    }
}

#[test]
fn invariants_are_the_consistent_mass_split_by_direction() {
    // M_ff = Σ_i S̄_ii + M_p is Φᵀ M Φ with the FE mass; the undeformed body is a
    // uniform rod: m = ρA L, ∫ρ x = ρA L²/2, I_yy = I_zz = ρA L³/3, I_xx = ρI_p L.
    let beam = test_beam(6);
    let modes = normal_modes(&beam, &Reference::Clamped, 8).unwrap();
    let inv = Invariants::new(&beam, &modes);
    let fe = modes.shapes.transpose() * beam.mass() * &modes.shapes;
    let err = (&inv.modal_mass - &fe).amax();
    assert!(err < 1e-12, "M_ff − ΦᵀMΦ: got {err:e}");
    assert!((&inv.modal_mass - DMatrix::identity(8, 8)).amax() < 1e-10);
    let (l, ra) = (beam.length, beam.rho_a);
    let close = |got: f64, want: f64, what: &str| {
        assert!(
            (got - want).abs() < 1e-12 * want,
            "{what}: got {got}, want {want}"
        )
    };
    close(inv.mass, ra * l, "m");
    close(inv.first_moment.x, ra * l * l / 2.0, "∫ρ x");
    close(inv.inertia[(1, 1)], ra * l.powi(3) / 3.0, "I_yy");
    close(inv.inertia[(2, 2)], ra * l.powi(3) / 3.0, "I_zz");
    close(inv.inertia[(0, 0)], beam.rho_ip * l, "I_xx");
}

#[test]
fn mean_axis_modes_carry_no_momentum() {
    // Free–free modes are mass-orthogonal to the rigid motions: ∫ρ S dV = 0 and
    // ∫ρ ũ₀ S dV + e_x c_pᵀ = 0 (the mean-axis conditions).
    let beam = test_beam(8);
    let modes = normal_modes(&beam, &Reference::MeanAxis, 10).unwrap();
    let inv = Invariants::new(&beam, &modes);
    assert!(inv.s_bar.amax() < 1e-12, "S̄ got {:e}", inv.s_bar.amax());
    assert!(
        inv.coupling.amax() < 1e-12,
        "Ī_θf⁰ got {:e}",
        inv.coupling.amax()
    );
    // And a clamped beam's modes do carry momentum.
    let clamped = Invariants::new(&beam, &normal_modes(&beam, &Reference::Clamped, 2).unwrap());
    assert!(clamped.s_bar.amax() > 0.1);
}

// ---------- the brute-force body: rigid particles ----------

/// A rigid particle of the beam: mass `m` at `ū₀ = (x, 0, 0)`, spin inertia `j`
/// about the section normal, deformation `S q` and twist `φ_x q` by the FE
/// interpolation of the nodal shapes.
struct Particle {
    x: f64,
    m: f64,
    j: f64,
    s: Matrix3xX<f64>,
    phi_x: RowDVector<f64>,
}

fn particle(beam: &Beam, shapes: &DMatrix<f64>, x: f64, weight: f64) -> Particle {
    let section = beam.section(x, shapes);
    Particle {
        x,
        m: beam.rho_a * weight,
        j: beam.rho_ip * weight,
        s: section.translation,
        phi_x: section.rotation.row(0).into_owned(),
    }
}

/// Each element cut into `sub` pieces with four Gauss particles each: sums over
/// them are exact for the polynomial integrands.
fn gauss_particles(beam: &Beam, shapes: &DMatrix<f64>, sub: usize) -> Vec<Particle> {
    let h = beam.length / (beam.elements * sub) as f64;
    let mut out = Vec::new();
    for piece in 0..beam.elements * sub {
        for (xi, w) in flex::beam::GAUSS4 {
            out.push(particle(beam, shapes, (piece as f64 + xi) * h, w * h));
        }
    }
    out
}

/// `count` equal particles at the midpoints of equal pieces (midpoint rule, O(h²)).
fn midpoint_particles(beam: &Beam, shapes: &DMatrix<f64>, count: usize) -> Vec<Particle> {
    let h = beam.length / count as f64;
    (0..count)
        .map(|i| particle(beam, shapes, (i as f64 + 0.5) * h, h))
        .collect()
}

/// A state of the free body: orientation, elastic coordinates, speeds (Ṙ, ω̄, q̇_f).
struct State {
    a: Matrix3<f64>,
    q: DVector<f64>,
    speeds: DVector<f64>,
}

impl State {
    fn random(k: usize, seed: u64) -> State {
        // A small deterministic generator (xorshift) for reproducible states.
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut next = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let axis = Vector3::new(next(), next(), next()) * 1.5;
        State {
            a: Rotation3::from_scaled_axis(axis).into_inner(),
            q: DVector::from_fn(k, |_, _| 0.2 * next()),
            speeds: DVector::from_fn(6 + k, |_, _| next()),
        }
    }
    fn omega(&self) -> Vector3<f64> {
        Vector3::new(self.speeds[3], self.speeds[4], self.speeds[5])
    }
    fn qd(&self) -> DVector<f64> {
        self.speeds.rows(6, self.speeds.len() - 6).into_owned()
    }
}

/// Position and orientation of a particle at time `t` along the motion with
/// constant speeds `u` from the state (`A(t) = A exp(ω̃ t)`, `q(t) = q + q̇ t`).
fn pose(p: &Particle, st: &State, u: &DVector<f64>, t: f64) -> (Vector3<f64>, Matrix3<f64>) {
    let k = st.q.len();
    let rd = Vector3::new(u[0], u[1], u[2]);
    let w = Vector3::new(u[3], u[4], u[5]);
    let q = &st.q + u.rows(6, k) * t;
    let a = st.a * Rotation3::from_scaled_axis(w * t).into_inner();
    let s = &p.s * &q;
    let r = Vector3::new(0.4, -0.2, 1.0) + rd * t + a * (Vector3::new(p.x, 0.0, 0.0) + s);
    let twist = (&p.phi_x * &q)[0];
    (
        r,
        a * Rotation3::from_scaled_axis(Vector3::x() * twist).into_inner(),
    )
}

/// Sixth-order central difference: the first derivative at 0.
fn d1<F: Fn(f64) -> V, V: std::ops::Mul<f64, Output = V> + std::ops::Add<Output = V>>(
    f: F,
    h: f64,
) -> V {
    let c = [
        (-3.0, -1.0),
        (-2.0, 9.0),
        (-1.0, -45.0),
        (1.0, 45.0),
        (2.0, -9.0),
        (3.0, 1.0),
    ];
    let mut acc = f(0.0) * 0.0;
    for (i, w) in c {
        acc = acc + f(i * h) * (w / (60.0 * h));
    }
    acc
}

/// Sixth-order central difference: the second derivative at 0.
fn d2<F: Fn(f64) -> V, V: std::ops::Mul<f64, Output = V> + std::ops::Add<Output = V>>(
    f: F,
    h: f64,
) -> V {
    let c = [2.0, -27.0, 270.0, -490.0, 270.0, -27.0, 2.0];
    let mut acc = f(0.0) * 0.0;
    for (i, w) in c.iter().enumerate() {
        acc = acc + f((i as f64 - 3.0) * h) * (w / (180.0 * h * h));
    }
    acc
}

/// `vee` of a skew matrix.
fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) * 0.5
}

/// The brute-force `M` and `Q_v` by d'Alembert–Jourdain over the particles:
/// `M = Σ m Lᵀ L + Σ L_ωᵀ J L_ω` and `Q_v = −Σ m Lᵀ γ − Σ L_ωᵀ ḣ`, where the
/// columns of `L` and `L_ω` are the particle velocity and angular velocity
/// (differentiated numerically from the positions and orientations) for a unit
/// speed, `γ` the particle acceleration at `u̇ = 0` and `ḣ` the rate of its
/// angular momentum at `u̇ = 0`, both differentiated numerically along the motion.
fn brute_force(particles: &[Particle], st: &State) -> (DMatrix<f64>, DVector<f64>) {
    let n = st.speeds.len();
    let mut m = DMatrix::zeros(n, n);
    let mut qv = DVector::zeros(n);
    let h = 1e-2;
    for p in particles {
        let mut l = Matrix3xX::zeros(n);
        let mut lw = Matrix3xX::zeros(n);
        let a_s = pose(p, st, &st.speeds, 0.0).1;
        for i in 0..n {
            let mut e = DVector::zeros(n);
            e[i] = 1.0;
            l.set_column(i, &d1(|t| pose(p, st, &e, t).0, h));
            let ad = d1(|t| pose(p, st, &e, t).1, h);
            lw.set_column(i, &vee(&(ad * a_s.transpose())));
        }
        let gamma = d2(|t| pose(p, st, &st.speeds, t).0, h);
        // Spin inertia about the section normal, in inertial coordinates.
        let inertia = |a: &Matrix3<f64>| {
            let ex = a * Vector3::x();
            ex * ex.transpose() * p.j
        };
        let hdot = d1(
            |t| {
                let (_, a_s) = pose(p, st, &st.speeds, t);
                let w_in = vee(&(d1(|s| pose(p, st, &st.speeds, t + s).1, h) * a_s.transpose()));
                inertia(&a_s) * w_in
            },
            h,
        );
        let j_in = inertia(&a_s);
        m += l.transpose() * &l * p.m + lw.transpose() * j_in * &lw;
        qv -= l.transpose() * gamma * p.m + lw.transpose() * hdot;
    }
    (m, qv)
}

fn rel(got: &DMatrix<f64>, want: &DMatrix<f64>) -> f64 {
    (got - want).amax() / want.amax()
}

fn check_against_particles(beam: &Beam, modes: &Modes, what: &str) {
    let inv = Invariants::new(beam, modes);
    let particles = gauss_particles(beam, &modes.shapes, 2);
    for seed in 1..=3 {
        let st = State::random(modes.count(), seed);
        let m = ffr::mass_matrix(&inv, &st.a, &st.q);
        let qv = ffr::quadratic_velocity(&inv, &st.a, &st.q, &st.omega(), &st.qd());
        let (m_bf, qv_bf) = brute_force(&particles, &st);
        let (em, eq) = (rel(&m, &m_bf), (&qv - &qv_bf).amax() / qv_bf.amax());
        eprintln!("{what} seed {seed}: M rel err {em:.1e}, Q_v rel err {eq:.1e}");
        assert!(em < 1e-9, "{what}: M(q) against particles, rel err {em:e}");
        assert!(eq < 1e-8, "{what}: Q_v against particles, rel err {eq:e}");
    }
}

#[test]
fn ffr_mass_matrix_and_quadratic_velocity_match_rigid_particles_normal_modes() {
    // Clamped modes (bending both planes and torsion among the lowest six), a
    // rotated frame, deformations of ~10 % of L, random speeds: the invariants'
    // M(q) and Q_v are the particle sums, to the finite differences' accuracy.
    let beam = test_beam(4);
    let modes = normal_modes(&beam, &Reference::Clamped, 6).unwrap();
    let kinds: Vec<Deformation> = (0..6)
        .map(|i| beam.classify(&modes.shapes.column(i).into_owned()))
        .collect();
    assert!(kinds.contains(&Deformation::Torsion), "{kinds:?}");
    check_against_particles(&beam, &modes, "normal modes");
}

#[test]
fn ffr_mass_matrix_and_quadratic_velocity_match_rigid_particles_craig_bampton() {
    // Craig–Bampton with the tip as boundary: six constraint modes (axial, torsion,
    // both bending planes, non-orthogonal) plus three fixed-interface modes.
    let beam = test_beam(4);
    let modes = flex::craig_bampton(&beam, &Reference::Clamped, &[4], 3).unwrap();
    assert_eq!(modes.count(), 9);
    check_against_particles(&beam, &modes, "Craig–Bampton");
}

#[test]
fn ffr_particle_sums_converge_at_the_midpoint_rate() {
    // Equal particles at piece midpoints: the error in M(q) falls as h², by about
    // 4 each time the particle count doubles.
    let beam = test_beam(4);
    let modes = normal_modes(&beam, &Reference::Clamped, 4).unwrap();
    let inv = Invariants::new(&beam, &modes);
    let st = State::random(4, 7);
    let m = ffr::mass_matrix(&inv, &st.a, &st.q);
    let errors: Vec<f64> = [16, 32, 64]
        .iter()
        .map(|&count| {
            rel(
                &brute_force(&midpoint_particles(&beam, &modes.shapes, count), &st).0,
                &m,
            )
        })
        .collect();
    eprintln!("midpoint particles 16/32/64: M rel err {errors:?}");
    for w in errors.windows(2) {
        let ratio = w[0] / w[1];
        assert!(
            (3.5..4.5).contains(&ratio),
            "ratio got {ratio}, want ≈ 4 ({errors:?})"
        );
    }
}

#[test]
fn ffr_energy_rate_is_minus_speeds_dot_quadratic_velocity() {
    // Along a motion with u̇ = 0, dT/dt = Σ m v·a = −uᵀ Q_v: Q_v is consistent
    // with the kinetic energy T = ½ uᵀ M(q) u of the same invariants.
    let beam = test_beam(4);
    let modes = flex::craig_bampton(&beam, &Reference::Clamped, &[4], 2).unwrap();
    let inv = Invariants::new(&beam, &modes);
    for seed in 1..=3 {
        let st = State::random(modes.count(), seed);
        let w = st.omega();
        let t_of = |t: f64| {
            let a = st.a * Rotation3::from_scaled_axis(w * t).into_inner();
            let q = &st.q + st.qd() * t;
            ffr::kinetic_energy(&inv, &a, &q, &st.speeds)
        };
        let got = d1(t_of, 1e-2);
        let qv = ffr::quadratic_velocity(&inv, &st.a, &st.q, &w, &st.qd());
        let want = -st.speeds.dot(&qv);
        assert!(
            (got - want).abs() < 1e-9 * want.abs().max(1.0),
            "dT/dt got {got}, want −uᵀQ_v = {want}"
        );
    }
}

#[test]
fn ffr_without_modes_is_the_rigid_body() {
    // k = 0: M = [m 1, −A c̃; A c̃ᵀ… , Ī] and Q_v = −(A ω̃ω̃ c, ω̃ Ī ω), with
    // c = (ρA L²/2, 0, 0), Ī = diag(ρI_p L, ρA L³/3, ρA L³/3) — a uniform rod.
    let beam = test_beam(3);
    let modes = normal_modes(&beam, &Reference::Clamped, 0).unwrap();
    let inv = Invariants::new(&beam, &modes);
    let (l, ra) = (beam.length, beam.rho_a);
    let m = ra * l;
    let c = Vector3::new(ra * l * l / 2.0, 0.0, 0.0);
    let ibar = Matrix3::from_diagonal(&Vector3::new(
        beam.rho_ip * l,
        ra * l.powi(3) / 3.0,
        ra * l.powi(3) / 3.0,
    ));
    let st = State::random(0, 3);
    let a = st.a;
    let mut want = DMatrix::zeros(6, 6);
    want.view_mut((0, 0), (3, 3))
        .copy_from(&(Matrix3::identity() * m));
    let m_rt = -a * c.cross_matrix();
    want.view_mut((0, 3), (3, 3)).copy_from(&m_rt);
    want.view_mut((3, 0), (3, 3)).copy_from(&m_rt.transpose());
    want.view_mut((3, 3), (3, 3)).copy_from(&ibar);
    let got = ffr::mass_matrix(&inv, &a, &DVector::zeros(0));
    assert!(rel(&got, &want) < 1e-14, "M got {got}, want {want}");
    let w = st.omega();
    let qv = ffr::quadratic_velocity(&inv, &a, &DVector::zeros(0), &w, &DVector::zeros(0));
    let want_r = -a * w.cross(&w.cross(&c));
    let want_t = -w.cross(&(ibar * w));
    for i in 0..3 {
        assert!((qv[i] - want_r[i]).abs() < 1e-12 * m * l, "Q_v,R[{i}]");
        assert!(
            (qv[3 + i] - want_t[i]).abs() < 1e-12 * m * l * l,
            "Q_v,θ[{i}]"
        );
    }
    // With modes but q_f and q̇_f locked at zero, the reference block is the same.
    let modes = normal_modes(&beam, &Reference::Clamped, 4).unwrap();
    let inv = Invariants::new(&beam, &modes);
    let (q0, qd0) = (DVector::zeros(4), DVector::zeros(4));
    let got = ffr::mass_matrix(&inv, &a, &q0)
        .view((0, 0), (6, 6))
        .into_owned();
    assert!(rel(&got, &want) < 1e-14, "locked M got {got}, want {want}");
    let qv = ffr::quadratic_velocity(&inv, &a, &q0, &w, &qd0);
    for i in 0..3 {
        assert!(
            (qv[i] - want_r[i]).abs() < 1e-12 * m * l,
            "locked Q_v,R[{i}]"
        );
        assert!(
            (qv[3 + i] - want_t[i]).abs() < 1e-12 * m * l * l,
            "locked Q_v,θ[{i}]"
        );
    }
}

// ---------- Craig–Bampton and geometric stiffness ----------

#[test]
fn craig_bampton_reproduces_static_tip_response_and_bounds_frequencies() {
    // Constraint modes make the static response to a tip load exact; the reduced
    // frequencies are Rayleigh–Ritz bounds from above of the full model's, within
    // 1 % here (torsion rests on its static constraint mode alone: +0.4 %).
    let beam = test_beam(8);
    let cb = flex::craig_bampton(&beam, &Reference::Clamped, &[8], 4).unwrap();
    let full = normal_modes(&beam, &Reference::Clamped, 4).unwrap();
    let tip = beam.dof(8, NodeDof::Uy);
    let free: Vec<usize> = (6..beam.dofs()).collect();
    let kc = DMatrix::from_fn(free.len(), free.len(), |i, j| {
        beam.stiffness()[(free[i], free[j])]
    });
    let mut f = DVector::zeros(free.len());
    f[tip - 6] = 100.0;
    let u_full = Cholesky::new(kc).unwrap().solve(&f);
    let fr = cb.shapes.rows(6, free.len()).transpose() * &f;
    let q = Cholesky::new(cb.stiffness.clone()).unwrap().solve(&fr);
    let u_cb = cb.shapes.rows(6, free.len()) * q;
    let err = (&u_cb - &u_full).amax() / u_full.amax();
    assert!(err < 1e-10, "static tip response: rel err {err:e}");
    // Tip deflection P L³ / 3 EI_z of a cantilever (exact for cubic elements).
    let want = 100.0 * beam.length.powi(3) / (3.0 * beam.ei_z);
    assert!((u_full[tip - 6] - want).abs() < 1e-10 * want);
    for (i, (c, w)) in cb.frequencies.iter().zip(&full.frequencies).enumerate() {
        assert!(
            *c >= w * (1.0 - 1e-12) && (c - w) / w < 1e-2,
            "mode {i}: CB got {c}, full {w}"
        );
    }
}

#[test]
fn geometric_stiffness_buckles_a_cantilever_at_eulers_load() {
    // A clamped–free column under compression P buckles when K − P K_G(1) is
    // singular: P_cr = π² EI / (4 L²), the weaker plane (EI_y) first.
    let beam = test_beam(8);
    let free: Vec<usize> = (6..beam.dofs()).collect();
    let pick =
        |a: &DMatrix<f64>| DMatrix::from_fn(free.len(), free.len(), |i, j| a[(free[i], free[j])]);
    let k = pick(&beam.stiffness());
    let g = pick(&beam.geometric_stiffness(&|_| 1.0));
    let l = Cholesky::new(k).unwrap().l();
    let x = l.solve_lower_triangular(&g).unwrap();
    let b = l.solve_lower_triangular(&x.transpose()).unwrap();
    let mu = b.symmetric_eigenvalues().max();
    let got = 1.0 / mu;
    let want = PI * PI * beam.ei_y / (4.0 * beam.length.powi(2));
    assert!(
        ((got - want) / want).abs() < 1e-5,
        "P_cr got {got}, want {want}"
    );
}

#[test]
fn spin_stiffening_raises_the_flapping_frequency_by_southwells_coefficient() {
    // A cantilever spinning at Ω about an axis through its root (hub radius 0):
    // ω₁² = ω₁₀² + κ Ω², κ = ∫ ½(L² − x²) φ'² dx / ∫ φ² dx for the exact first
    // mode φ (first-order perturbation). κ ≈ 1.193 (Southwell's coefficient).
    let beam = test_beam(16);
    let modes = normal_modes(&beam, &Reference::Clamped, 1).unwrap();
    let kg1 = modal_geometric_stiffness(&beam, &modes, &|x| beam.centrifugal_force(0.0, x));
    let got = kg1[(0, 0)] / modes.mass[(0, 0)];
    let (l, b) = (beam.length, CLAMPED_FREE[0] / beam.length);
    let sigma = ((b * l).cosh() + (b * l).cos()) / ((b * l).sinh() + (b * l).sin());
    let phi = |x: f64| (b * x).cosh() - (b * x).cos() - sigma * ((b * x).sinh() - (b * x).sin());
    let dphi =
        |x: f64| b * ((b * x).sinh() + (b * x).sin() - sigma * ((b * x).cosh() - (b * x).cos()));
    let simpson = |f: &dyn Fn(f64) -> f64| {
        let n = 2000;
        let h = l / n as f64;
        (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * f(i as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0
    };
    let kappa =
        simpson(&|x| 0.5 * (l * l - x * x) * dphi(x).powi(2)) / simpson(&|x| phi(x).powi(2));
    eprintln!("Southwell κ: FE {got:.6}, exact mode {kappa:.6}");
    assert!((kappa - 1.193).abs() < 1e-3, "κ of the exact mode {kappa}");
    assert!(
        ((got - kappa) / kappa).abs() < 1e-5,
        "κ got {got}, want {kappa}"
    );
}
