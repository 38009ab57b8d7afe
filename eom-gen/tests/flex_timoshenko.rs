//! The built-in beam as a Timoshenko beam (issue #17: "a straight
//! Euler–Bernoulli (and optionally Timoshenko) beam"): shear deformation and
//! rotary inertia with the interdependent interpolation element (IIE) of
//! `flex::beam`, checked against
//!
//! - the exact static cantilever (`PL³/3EI + PL/κGA`, one element suffices:
//!   the IIE shapes solve the static Timoshenko equations);
//! - Przemieniecki's closed-form Timoshenko stiffness and the Euler–Bernoulli
//!   element it becomes as `Φ → 0`;
//! - the closed-form frequency equation of the simply supported Timoshenko
//!   beam (shear and rotary inertia), converging with the element count;
//! - the clamped–free frequency equation, solved here by the transfer
//!   matrix `exp(A(ω) L)` of the Timoshenko ODEs and bisection;
//! - the FE mass itself: the invariants (`S̄`, `Ī`, `Ī_θf`, `M_ff`) equal the
//!   rigid-motion nodal vectors' products with the consistent mass (the
//!   same kinetic energy computed two ways), and the FFR terms inside the
//!   recursive algorithms equal `flex::ffr` of one free body;
//! - energy conservation of a free swing, and a positive definite mass
//!   matrix from the generated programs.
//!
//! The frequency table printed by `pinned_pinned_frequencies_converge_to_the_closed_form`
//! (`cargo test -p eom-gen --test all flex_timoshenko:: -- --nocapture`) is the
//! one in BENCHMARKS.md.

use eom_gen::System;
use eom_gen::flex::{Beam, Deformation, Invariants, Reference, Shear, ffr, normal_modes};
use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use eom_sim::{Dop853, OdeSystem, SolveOptions, integrate};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix4, UnitQuaternion, Vector3};

/// A thick steel bar (E = 210 GPa, G = E/2.6, ρ = 7850 kg/m³) of rectangular
/// section, `B = 0.10 m` along `y`, `H = 0.06 m` along `z`, `κ = 5/6`
/// (Timoshenko's value for a rectangle), `L = 0.6 m`: `L/B = 6`, so shear
/// and rotary inertia change the bending frequencies by percents.
const E: f64 = 210.0e9;
const G: f64 = E / 2.6;
const RHO: f64 = 7850.0;
const KAPPA: f64 = 5.0 / 6.0;
const B: f64 = 0.10;
const H: f64 = 0.06;
const L: f64 = 0.6;

fn area() -> f64 {
    B * H
}
/// `I_y = ∫z² dA` (bending in `x–z`), `I_z = ∫y² dA` (bending in `x–y`).
fn i_y() -> f64 {
    B * H.powi(3) / 12.0
}
fn i_z() -> f64 {
    H * B.powi(3) / 12.0
}

fn shear() -> Shear {
    Shear {
        kga_y: KAPPA * G * area(),
        kga_z: KAPPA * G * area(),
        rho_iy: RHO * i_y(),
        rho_iz: RHO * i_z(),
    }
}

/// The bar with `n` elements, Timoshenko (`shear`) or Euler–Bernoulli (`None`).
fn bar(n: usize, shear: Option<Shear>) -> Beam {
    let beam = Beam {
        length: L,
        rho_a: RHO * area(),
        rho_ip: RHO * (i_y() + i_z()),
        ea: E * area(),
        ei_y: E * i_y(),
        ei_z: E * i_z(),
        gj: G * 0.229 * B * H.powi(3),
        elements: n,
        shear,
    };
    beam.check().unwrap();
    beam
}

/// The data of one bending plane: `(EI, κGA, ρA, ρI)`.
type Plane = (f64, f64, f64, f64);

fn plane(beam: &Beam, kind: Deformation) -> Plane {
    let s = beam.shear.unwrap();
    match kind {
        Deformation::BendingXy => (beam.ei_z, s.kga_y, beam.rho_a, s.rho_iz),
        _ => (beam.ei_y, s.kga_z, beam.rho_a, s.rho_iy),
    }
}

/// All natural frequencies of one deformation kind, ascending (rad/s).
fn frequencies(beam: &Beam, reference: &Reference, kind: Deformation) -> Vec<f64> {
    let modes = normal_modes(beam, reference, beam.dofs() - 6).unwrap();
    (0..modes.count())
        .filter(|&i| beam.classify(&modes.shapes.column(i).into_owned()) == kind)
        .map(|i| modes.frequencies[i])
        .collect()
}

/// The simply supported Timoshenko beam, mode `j`: with `v = a sin kx`,
/// `ψ = b cos kx`, `k = jπ/L` the equations `ρA v̈ = κGA (v'' − ψ')`,
/// `ρI ψ̈ = EI ψ'' + κGA (v' − ψ)` give
/// `ρA ρI ω⁴ − [ρA (EI k² + κGA) + ρI κGA k²] ω² + κGA EI k⁴ = 0`; the lower
/// root is the bending branch (Timoshenko 1921; Han, Benaroya and Wei 1999).
fn pinned_pinned_exact((ei, kga, rho_a, rho_i): Plane, j: usize) -> f64 {
    let k = j as f64 * std::f64::consts::PI / L;
    let a = rho_a * rho_i;
    let b = rho_a * (ei * k * k + kga) + rho_i * kga * k * k;
    let c = kga * ei * k.powi(4);
    (2.0 * c / (b + (b * b - 4.0 * a * c).sqrt())).sqrt()
}

/// The clamped–free frequency equation of the Timoshenko beam. In
/// `x̂ = x/L` and the state `z = (v/L, ψ, M L/EI, Q L²/EI)` (moment
/// `M = EI ψ'`, shear force `Q = κGA (v' − ψ)`) the free vibration at `ω`
/// is `z' = Â z` with
///
/// ```text
/// (v/L)' = ψ + s² Q̂,   ψ' = M̂,   M̂' = −Q̂ − r² b² ψ,   Q̂' = −b² v/L,
/// b² = ρA ω² L⁴/EI,   s² = EI/(κGA L²),   r² = ρI/(ρA L²)
/// ```
///
/// (from `ρA v̈ = Q'`, `ρI ψ̈ = M' + Q`). Clamped at 0 (`v = ψ = 0`) leaves
/// `M̂(0)`, `Q̂(0)`; free at `L` needs `M̂(1) = Q̂(1) = 0`: the 2×2 block of
/// `exp(Â)` vanishes in determinant at the natural frequencies (the
/// transcendental equation of Huang 1961, evaluated without its closed form;
/// the scaling keeps `Â` moderate, so `exp` is accurate).
fn clamped_free_determinant((ei, kga, rho_a, rho_i): Plane, w: f64) -> f64 {
    let b2 = rho_a * w * w * L.powi(4) / ei;
    let s2 = ei / (kga * L * L);
    let r2 = rho_i / (rho_a * L * L);
    #[rustfmt::skip]
    let a = Matrix4::new(
        0.0, 1.0,       0.0, s2,
        0.0, 0.0,       1.0, 0.0,
        0.0, -r2 * b2,  0.0, -1.0,
        -b2, 0.0,       0.0, 0.0,
    );
    let t = a.exp();
    t[(2, 2)] * t[(3, 3)] - t[(2, 3)] * t[(3, 2)]
}

/// The roots of the clamped–free determinant below `top`: sign changes on a
/// fine grid, then bisection to round-off.
fn clamped_free_exact(p: Plane, top: f64) -> Vec<f64> {
    let steps = 4000;
    let f = |w: f64| clamped_free_determinant(p, w);
    let mut roots = Vec::new();
    let mut prev = (top * 1e-4, f(top * 1e-4));
    for s in 1..=steps {
        let w = top * s as f64 / steps as f64;
        let fw = f(w);
        if prev.1.signum() != fw.signum() {
            let (mut lo, mut hi) = (prev.0, w);
            let flo = prev.1;
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if f(mid).signum() == flo.signum() {
                    lo = mid;
                } else {
                    hi = mid;
                }
                if hi - lo <= 1e-15 * hi {
                    break;
                }
            }
            roots.push(0.5 * (lo + hi));
        }
        prev = (w, fw);
    }
    roots
}

#[test]
fn timoshenko_element_is_przemienieckis_closed_form() {
    // Przemieniecki (1968) §5.6 with shear: K = EI/((1+Φ) l³) ·
    // [12, 6l, −12, 6l; 6l, (4+Φ)l², −6l, (2−Φ)l²; …], Φ = 12 EI/(κGA l²),
    // in both planes (x–z with θ_y = −ψ: the signs of u_z–θ_y flip).
    let b = bar(3, Some(shear()));
    let l = b.element_length();
    let k = b.element_stiffness();
    let (pxy, pxz) = b.shear_parameters();
    assert!(pxy > 0.1 && pxz > 0.01, "a thick bar: Φ = {pxy}, {pxz}");
    let close = |got: f64, want: f64, what: &str| {
        assert!(
            (got - want).abs() <= 1e-10 * want.abs(),
            "{what}: got {got}, want {want}"
        );
    };
    let c = b.ei_z / ((1.0 + pxy) * l.powi(3));
    close(k[(1, 1)], 12.0 * c, "k(u_y,u_y)");
    close(k[(1, 5)], 6.0 * l * c, "k(u_y,θ_z)");
    close(k[(1, 7)], -12.0 * c, "k(u_ya,u_yb)");
    close(k[(5, 5)], (4.0 + pxy) * l * l * c, "k(θ_z,θ_z)");
    close(k[(5, 11)], (2.0 - pxy) * l * l * c, "k(θ_za,θ_zb)");
    let c = b.ei_y / ((1.0 + pxz) * l.powi(3));
    close(k[(2, 2)], 12.0 * c, "k(u_z,u_z)");
    close(k[(2, 4)], -6.0 * l * c, "k(u_z,θ_y)");
    close(k[(4, 4)], (4.0 + pxz) * l * l * c, "k(θ_y,θ_y)");
    close(k[(4, 10)], (2.0 - pxz) * l * l * c, "k(θ_ya,θ_yb)");
    // Rigid motions (the IIE shapes hold them exactly) cost no strain energy.
    let kr = b.stiffness() * b.rigid_modes();
    assert!(
        kr.amax() < 1e-12 * b.stiffness().amax(),
        "K·rigid = {}",
        kr.amax()
    );
}

#[test]
fn slender_limit_is_the_euler_bernoulli_element() {
    // Φ → 0: the IIE shapes tend to the Hermite cubics, so with κGA → ∞ and
    // no rotary inertia the element matrices tend to Euler–Bernoulli's,
    // the difference of order Φ; without `shear` they are identical.
    let eb = bar(4, None);
    let (me, ke) = (eb.element_mass(), eb.element_stiffness());
    for scale in [1e3, 1e6, 1e9] {
        let t = bar(
            4,
            Some(Shear {
                kga_y: scale * KAPPA * G * area(),
                kga_z: scale * KAPPA * G * area(),
                rho_iy: 0.0,
                rho_iz: 0.0,
            }),
        );
        let (pxy, _) = t.shear_parameters();
        let dm = (t.element_mass() - me).amax() / me.amax();
        let dk = (t.element_stiffness() - ke).amax() / ke.amax();
        eprintln!("Φ_xy = {pxy:.1e}: |ΔM|/|M| = {dm:.1e}, |ΔK|/|K| = {dk:.1e}");
        assert!(dm < 2.0 * pxy && dk < 2.0 * pxy, "Φ {pxy}: {dm:e}, {dk:e}");
    }
    // The slender bar's frequencies then equal Euler–Bernoulli's.
    let t = bar(
        8,
        Some(Shear {
            kga_y: 1e9 * KAPPA * G * area(),
            kga_z: 1e9 * KAPPA * G * area(),
            rho_iy: 0.0,
            rho_iz: 0.0,
        }),
    );
    for kind in [Deformation::BendingXy, Deformation::BendingXz] {
        let (a, b) = (
            frequencies(&t, &Reference::Clamped, kind),
            frequencies(&eb_with(8), &Reference::Clamped, kind),
        );
        for (x, y) in a.iter().zip(&b).take(4) {
            assert!((x - y).abs() < 1e-7 * y, "{kind:?}: {x} vs {y}");
        }
    }
    // And without `shear`: bit for bit the Euler–Bernoulli interpolation.
    let s = Beam::interpolation_sheared(0.3, 0.37, 0.0, 0.0);
    assert_eq!(s, Beam::interpolation(0.3, 0.37));
    assert_eq!(
        eb.element_interpolation(0.37),
        Beam::interpolation(0.15, 0.37)
    );
}

fn eb_with(n: usize) -> Beam {
    bar(n, None)
}

#[test]
fn cantilever_tip_deflection_is_exact_with_one_element() {
    // A cantilever with a tip load P: u(L) = PL³/(3EI) + PL/(κGA) (bending
    // plus shear) and the section's rotation ψ(L) = PL²/(2EI), exactly, with
    // one element and with five (the IIE shapes solve the static equations),
    // in both planes. The Euler–Bernoulli beam misses the shear part.
    let p = 1.0e5;
    for n in [1, 5] {
        let b = bar(n, Some(shear()));
        let s = b.shear.unwrap();
        let k = b.stiffness();
        let free = b.dofs() - 6;
        let kff = k.view((6, 6), (free, free)).into_owned();
        let mut f = DVector::zeros(free);
        let tip = 6 * n; // node n, minus the clamped node's six
        f[tip - 6 + 1] = p; // u_y
        f[tip - 6 + 2] = p; // u_z
        let u = kff.lu().solve(&f).unwrap();
        let want_y = p * L.powi(3) / (3.0 * b.ei_z) + p * L / s.kga_y;
        let want_z = p * L.powi(3) / (3.0 * b.ei_y) + p * L / s.kga_z;
        let rel = |got: f64, want: f64| (got - want).abs() / want.abs();
        assert!(
            rel(u[tip - 6 + 1], want_y) < 1e-12,
            "n={n} u_y {}",
            u[tip - 5]
        );
        assert!(
            rel(u[tip - 6 + 2], want_z) < 1e-12,
            "n={n} u_z {}",
            u[tip - 4]
        );
        // θ_z = ψ_xy = PL²/2EI_z; θ_y = −ψ_xz = −PL²/2EI_y.
        assert!(rel(u[tip - 6 + 5], p * L * L / (2.0 * b.ei_z)) < 1e-12);
        assert!(rel(u[tip - 6 + 4], -p * L * L / (2.0 * b.ei_y)) < 1e-12);
        // Shear is 2 % of the x–y deflection here, which Euler–Bernoulli misses.
        let shear_share = (p * L / s.kga_y) / want_y;
        assert!(
            shear_share > 0.02,
            "shear is {shear_share} of the deflection"
        );
    }
}

#[test]
fn pinned_pinned_frequencies_converge_to_the_closed_form() {
    // Bending frequencies of the simply supported bar (the chord frame:
    // v = 0 at both ends, sections free to turn) against the Timoshenko
    // frequency equation, modes 1–3 in both planes, n = 2 … 32 elements.
    // The IIE's shear strain is constant per element while a mode's varies
    // (`γ ∝ cos kx`): its best fit is off by O(h) in the energy norm, so
    // the frequencies (Rayleigh–Ritz with the consistent mass: error ~ the
    // energy norm squared) converge as h². (Euler–Bernoulli's
    // Hermite cubics converge as h⁴; as Φ → 0 the IIE does too.)
    println!("pinned–pinned Timoshenko bar, relative error of ω_j (FE vs closed form):");
    println!("| plane | n | ω₁ error | ω₂ error | ω₃ error |");
    let mut errors = Vec::new();
    for kind in [Deformation::BendingXy, Deformation::BendingXz] {
        let mut row_errors = Vec::new();
        for n in [2, 4, 8, 16, 32] {
            let b = bar(n, Some(shear()));
            let fe = frequencies(&b, &Reference::PinnedPinned, kind);
            let e: Vec<f64> = (1..=3)
                .map(|j| {
                    let want = pinned_pinned_exact(plane(&b, kind), j);
                    (fe[j - 1] - want).abs() / want
                })
                .collect();
            println!(
                "| {kind:?} | {n} | {:.2e} | {:.2e} | {:.2e} |",
                e[0], e[1], e[2]
            );
            row_errors.push(e);
        }
        errors.push(row_errors);
    }
    let b = bar(32, Some(shear()));
    for kind in [Deformation::BendingXy, Deformation::BendingXz] {
        let p = plane(&b, kind);
        let eb = |j: usize| (j as f64 * std::f64::consts::PI / L).powi(2) * (p.0 / p.2).sqrt();
        println!(
            "{kind:?}: closed form ω₁..₃ = {:.1}, {:.1}, {:.1} rad/s; Euler–Bernoulli {:.1}, {:.1}, {:.1}",
            pinned_pinned_exact(p, 1),
            pinned_pinned_exact(p, 2),
            pinned_pinned_exact(p, 3),
            eb(1),
            eb(2),
            eb(3)
        );
        // Shear and rotary inertia matter here: ω₃ is ≥ 12 % below Euler–Bernoulli's.
        assert!(pinned_pinned_exact(p, 3) < 0.88 * eb(3));
    }
    for plane_errors in &errors {
        // From 8 elements on, halving h divides every mode's error by 3.9
        // to 4.4 (order 2); at 32 elements mode 1 is within 3e-5 and
        // mode 3 within 1.3e-3.
        for pair in plane_errors[2..].windows(2) {
            for (j, (coarse, fine)) in pair[0].iter().zip(&pair[1]).enumerate() {
                let ratio = coarse / fine;
                assert!((3.9..4.4).contains(&ratio), "mode {} ratio {ratio}", j + 1);
            }
        }
        assert!(plane_errors[4][0] < 3e-5 && plane_errors[4][2] < 1.3e-3);
    }
}

#[test]
fn clamped_free_frequencies_match_the_transcendental_equation() {
    // The cantilever's bending frequencies against the roots of the
    // clamped–free Timoshenko frequency equation, modes 1–3, both planes.
    // The determinant's slender limit is checked first: with κGA → ∞ and
    // ρI → 0 its first root is Euler–Bernoulli's 1.875104068711961² √(EI/ρA L⁴).
    let b = bar(32, Some(shear()));
    let p = plane(&b, Deformation::BendingXy);
    let slender = (p.0, 1e6 * p.1, p.2, 1e-9 * p.3);
    let eb1 = 1.875_104_068_711_961_f64.powi(2) * (p.0 / (p.2 * L.powi(4))).sqrt();
    let root = clamped_free_exact(slender, 1.5 * eb1)[0];
    assert!(
        (root - eb1).abs() < 1e-5 * eb1,
        "slender limit {root} vs {eb1}"
    );
    for kind in [Deformation::BendingXy, Deformation::BendingXz] {
        let p = plane(&b, kind);
        let fe16 = frequencies(&bar(16, Some(shear())), &Reference::Clamped, kind);
        let fe = frequencies(&b, &Reference::Clamped, kind);
        let exact = clamped_free_exact(p, 1.2 * fe[2]);
        assert!(exact.len() >= 3, "{kind:?}: roots {exact:?}");
        for j in 0..3 {
            let (e16, e32) = (
                (fe16[j] - exact[j]).abs() / exact[j],
                (fe[j] - exact[j]).abs() / exact[j],
            );
            println!(
                "clamped–free {kind:?} ω{} = {:.3} rad/s: error {e16:.1e} (16 el.), {e32:.1e} (32 el.)",
                j + 1,
                exact[j]
            );
            // Order 2 as for pinned–pinned (the shear strain is constant per element).
            let ratio = e16 / e32;
            assert!(
                e32 < 2e-3 && (3.9..4.4).contains(&ratio),
                "mode {}: {e16:e} {e32:e}",
                j + 1
            );
        }
    }
}

/// The kinetic energy of the reduced Timoshenko body two ways: the
/// invariants (line of mass along the IIE displacement field plus the
/// sections' rotary inertia in `ψ`) against the consistent FE mass `M`
/// with the nodal vectors `R` of the rigid motions (exact in the IIE
/// shapes): `S̄ = R_tᵀ M Φ`, `Ī_θf(0) = R_rᵀ M Φ`, `Ī = R_rᵀ M R_r`,
/// `M_ff = Φᵀ M Φ = 1`.
#[test]
fn invariants_are_the_consistent_mass_of_the_rigid_motions() {
    for reference in [Reference::Clamped, Reference::PinnedPinned] {
        let b = bar(6, Some(shear()));
        let modes = normal_modes(&b, &reference, 8).unwrap();
        let inv = Invariants::new(&b, &modes);
        let m = b.mass();
        let r = b.rigid_modes();
        let rt = r.columns(0, 3).into_owned();
        let rr = r.columns(3, 3).into_owned();
        let phi = &modes.shapes;
        let rel = |a: &DMatrix<f64>, b: &DMatrix<f64>| (a - b).amax() / b.amax().max(1e-300);
        let s_bar = rt.transpose() * &m * phi;
        assert!(rel(&inv.s_bar, &s_bar) < 1e-12, "S̄");
        let coupling = rr.transpose() * &m * phi;
        assert!(rel(&inv.coupling, &coupling) < 1e-12, "Ī_θf");
        let inertia = rr.transpose() * &m * &rr;
        let got = DMatrix::from_column_slice(3, 3, inv.inertia.as_slice());
        assert!(rel(&got, &inertia) < 1e-12, "Ī");
        let eye = DMatrix::identity(8, 8);
        assert!((&inv.modal_mass - eye).amax() < 1e-10, "M_ff");
        assert!(inv.rotary_inertia[1] > 0.0 && inv.rotary_modes.amax() > 0.0);
    }
}

/// A free Timoshenko bar (thick: rotary inertia and shear count), in a
/// model file.
const FREE_BAR: &str = r#"Model(
    name: "free_bar",
    parameters: [(name: "kga", value: 4.0e8)],
    bodies: [(name: "bar", flexible: Beam(length: 0.6, rho_a: 47.1, rho_ip: 0.05, ea: 1.26e9,
        ei_y: 3.78e5, ei_z: 1.05e6, gj: 2.5e5, elements: 4, reference: PinnedPinned, modes: 5,
        shear: Timoshenko(kga_y: "kga", kga_z: "kga", rho_iy: 0.5, rho_iz: 0.8)))],
    joints: [(name: "j", kind: Free, parent: "ground", child: "bar")],
)"#;

/// A reproducible pseudo-random number in `[-1, 1)`.
fn rand(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn system(text: &str) -> System {
    check(&Source::new("bar.ron", text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

#[test]
fn free_timoshenko_body_equals_the_ffr_equations_of_one_body() {
    // M and the velocity terms from the recursive algorithms (with the
    // sections' rotary inertia in Ī, Ī_θf and ω × c_r q̇_f) equal Shabana's
    // FFR equations of one free body from the invariants (`flex::ffr`).
    // The rotary inertia here is large (ρI 0.5, 0.8 kg m) so its terms are
    // not lost in round-off.
    let sys = system(FREE_BAR);
    let flex = sys.bodies[1].flexible.as_deref().unwrap();
    assert!(flex.beam.shear.is_some());
    let inv = &flex.invariants;
    let num = Numeric::new(&sys).unwrap();
    let mut seed = 11;
    for _ in 0..5 {
        let quat = UnitQuaternion::from_scaled_axis(Vector3::from_fn(|_, _| rand(&mut seed)));
        let a: Matrix3<f64> = *quat.to_rotation_matrix().matrix();
        let qf = DVector::from_fn(5, |_, _| 0.01 * rand(&mut seed));
        let vb = Vector3::from_fn(|_, _| rand(&mut seed));
        let w = Vector3::from_fn(|_, _| 3.0 * rand(&mut seed));
        let qfd = DVector::from_fn(5, |_, _| rand(&mut seed));
        let mut q = vec![0.3, -0.2, 0.1, quat.w, quat.i, quat.j, quat.k];
        q.extend(qf.iter());
        let mut u: Vec<f64> = vb.iter().chain(w.iter()).copied().collect();
        u.extend(qfd.iter());
        let terms = num.terms(&q, &u, 0.0, &[]).unwrap();
        let mut t = DMatrix::<f64>::identity(11, 11);
        t.view_mut((0, 0), (3, 3)).copy_from(&a);
        let m_ffr = ffr::mass_matrix(inv, &a, &qf);
        let want_m = t.transpose() * &m_ffr * &t;
        let got_m = DMatrix::from_fn(11, 11, |r, c| terms.mass_matrix[r][c]);
        let dm = (&got_m - &want_m).amax() / want_m.amax();
        assert!(dm < 1e-12, "M: relative difference {dm:e}");
        let qv = ffr::quadratic_velocity(inv, &a, &qf, &w, &qfd);
        let mut shift = DVector::zeros(11);
        shift.rows_mut(0, 3).copy_from(&(a * w.cross(&vb)));
        let mut elastic = DVector::zeros(11);
        elastic
            .rows_mut(6, 5)
            .copy_from(&(&inv.modal_stiffness * &qf));
        let want_b = -(t.transpose() * (qv - &m_ffr * shift)) + elastic;
        let got_b = DVector::from_vec(terms.bias.clone());
        let db = (&got_b - &want_b).amax() / want_b.amax();
        assert!(db < 1e-11, "bias: relative difference {db:e}");
    }
}

struct Ode<'a> {
    num: &'a Numeric,
    n: usize,
}

impl<const N: usize> OdeSystem<N> for Ode<'_> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let n = self.n;
        let (q, u) = y.split_at(n);
        let tau = vec![0.0; n];
        let ud = self
            .num
            .forward_dynamics(q, u, t, &tau, &[])
            .unwrap_or_else(|_| vec![f64::NAN; n]);
        dy[..n].copy_from_slice(&self.num.qdot(q, u));
        dy[n..].copy_from_slice(&ud);
    }
}

/// A hub on a revolute joint about `z` carrying a Timoshenko beam on a
/// revolute joint about `y`, under gravity along −z. The beam is soft in
/// shear (`κGA` comparable to `EI/L²`) with large rotary inertia, so both
/// matter in the motion.
const SWING: &str = r#"Model(
    name: "timoshenko_swing",
    gravity: (0, 0, -9.81),
    bodies: [
        (name: "hub", mass: 2.0, inertia: Diag(0.25, 0.25, 0.5)),
        (name: "beam", flexible: Beam(length: 2.0, rho_a: 1.5, rho_ip: 0.002, ea: 1e6,
            ei_y: 400, ei_z: 300, gj: 200, elements: 6, reference: Clamped, modes: 4,
            shear: Timoshenko(kga_y: 2000, kga_z: 3000, rho_iy: 0.01, rho_iz: 0.02))),
    ],
    joints: [
        (name: "hub_j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "hub"),
        (name: "beam_j", kind: Revolute(axis: (0, 1, 0)), parent: "hub", child: "beam",
         parent_frame: (position: (0.3, 0, 0))),
    ],
)"#;

#[test]
fn timoshenko_swing_conserves_energy() {
    // Hub and Timoshenko beam swinging under gravity, the beam released
    // bent (no damping): T + V (gravity and strain) stays constant to
    // DOP853's tolerance over 2 s, several periods of the first bending mode.
    let sys = system(SWING);
    let flex = sys.bodies[2].flexible.as_deref().unwrap();
    let (pxy, pxz) = flex.beam.shear_parameters();
    assert!(pxy > 1.0 && pxz > 1.0, "shear-soft: Φ = {pxy}, {pxz}");
    let num = Numeric::new(&sys).unwrap();
    let y0 = [
        0.2, 0.4, 0.02, -0.01, 0.005, 0.002, // q: hub, beam, 4 elastic
        1.0, -0.5, 0.3, 0.2, -0.1, 0.05, // u
    ];
    let energy = |y: &[f64; 12]| {
        let (t, v) = num.energy(&y[..6], &y[6..], 0.0).unwrap();
        t + v
    };
    let e0 = energy(&y0);
    let scale = {
        let (t, v) = num.energy(&y0[..6], &y0[6..], 0.0).unwrap();
        t.abs() + v.abs()
    };
    let ode = Ode { num: &num, n: 6 };
    let opts = SolveOptions {
        t_eval: (1..=20).map(|k| 0.1 * k as f64).collect(),
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &ode,
        0.0,
        y0,
        2.0,
        &opts,
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 20, "stopped: {:?}", sol.stop);
    let drift = sol
        .y_out
        .iter()
        .map(|y| (energy(y) - e0).abs() / scale)
        .fold(0.0, f64::max);
    eprintln!(
        "relative energy drift {drift:e}, {} steps",
        sol.stats.accepted
    );
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    assert!(
        sol.y_out.iter().any(|y| y[2] < 0.0),
        "q_f1 never swung back"
    );
}

#[test]
fn generated_mass_matrix_is_positive_definite_and_equals_the_f64_one() {
    // The symbolic programs of the Timoshenko swing, interpreted: the mass
    // matrix equals the f64 algorithms' and is positive definite (Cholesky)
    // at random deformed states.
    use eom_gen::functions::{Function, FunctionSet};
    use eom_gen::mech::formulate;
    let sys = system(SWING);
    let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
    let num = Numeric::new(&sys).unwrap();
    let mut seed = 3;
    for _ in 0..6 {
        let q: Vec<f64> = (0..6).map(|_| rand(&mut seed) * 0.3).collect();
        let u: Vec<f64> = (0..6).map(|_| rand(&mut seed) * 2.0).collect();
        let zeros = vec![0.0; 6];
        let point = eom_gen::interpret::Point {
            sys: &sys,
            q: &q,
            u: &u,
            udot: &zeros,
            tau: &zeros,
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        let lower =
            eom_gen::interpret::run(f.program(Function::MassMatrix).expect("requested"), &point);
        let mut m = DMatrix::zeros(6, 6);
        let mut k = 0;
        for i in 0..6 {
            for j in 0..=i {
                m[(i, j)] = lower[k];
                m[(j, i)] = lower[k];
                k += 1;
            }
        }
        let want = num.terms(&q, &u, 0.0, &[]).unwrap().mass_matrix;
        let want = DMatrix::from_fn(6, 6, |r, c| want[r][c]);
        assert!((&m - &want).amax() <= 1e-12 * want.amax(), "M differs");
        let eig = m.clone().symmetric_eigenvalues();
        let low = eig.iter().copied().fold(f64::INFINITY, f64::min);
        assert!(
            m.cholesky().is_some() && low > 0.0,
            "M not positive definite: {eig}"
        );
    }
}

/// The model's errors as text.
fn errors(from: &str, to: &str) -> String {
    assert!(
        SWING.contains(from),
        "test setup: `{from}` not in the model"
    );
    match check(&Source::new("swing.ron", SWING.replacen(from, to, 1))) {
        Ok(_) => "valid".to_string(),
        Err(report) => report.to_string(),
    }
}

#[test]
fn shear_data_errors_are_located() {
    // Non-positive shear stiffnesses and a negative rotary inertia: all at
    // once, each at its value (line 8 holds `shear`).
    let report = errors(
        "kga_y: 2000, kga_z: 3000, rho_iy: 0.01",
        "kga_y: 0, kga_z: -3000, rho_iy: -0.01",
    );
    for want in [
        "swing.ron:8:",
        "shear stiffness `kga_y` of flexible body `beam` is 0 N",
        "shear stiffness `kga_z` of flexible body `beam` is -3000 N",
        "rotary inertia per length of `beam` is negative (-0.01)",
    ] {
        assert!(report.contains(want), "want `{want}` in:\n{report}");
    }
    assert_eq!(report.matches("error").count(), 3, "{report}");
    // An unknown field in `Timoshenko(…)`, located.
    let report = errors("kga_y: 2000", "kappa: 0.8, kga_y: 2000");
    assert!(
        report.contains("swing.ron:8:") && report.contains("kappa"),
        "{report}"
    );
    // A missing shear stiffness.
    let report = errors("kga_y: 2000, ", "");
    assert!(report.contains("kga_y"), "{report}");
    // Stiffening with shear is refused at `stiffening`, saying why.
    let report = errors("modes: 4,", "modes: 4, stiffening: true,");
    assert!(
        report.contains("swing.ron:7:")
            && report.contains("geometric stiffening of a Timoshenko beam"),
        "{report}"
    );
    // Rotary inertia left out: ρA EI/EA of a homogeneous section.
    let sys = system(&SWING.replace(", rho_iy: 0.01, rho_iz: 0.02", ""));
    let s = sys.bodies[2]
        .flexible
        .as_deref()
        .unwrap()
        .beam
        .shear
        .unwrap();
    assert!((s.rho_iy - 1.5 * 400.0 / 1e6).abs() < 1e-15);
    assert!((s.rho_iz - 1.5 * 300.0 / 1e6).abs() < 1e-15);
}

#[test]
fn section_outputs_turn_with_psi_and_shear_is_kga_gamma() {
    // A clamped Timoshenko cantilever in the model format, deformed
    // statically by a tip load P along y (all modes kept, so the modal
    // static solution is the FE one): the section rotation output is ψ
    // (= PL²/2EI at the tip, not the slope), the bending moment
    // M_z = P (L − x), and the shear force Q_y = κGA_y (u_y' − θ_z) = P.
    let text = SWING.replace("modes: 4", "modes: 36");
    let sys = system(&text);
    let flex = sys.bodies[2].flexible.as_deref().unwrap();
    let s = flex.beam.shear.unwrap();
    let p = 10.0;
    let tip = flex.modes.at_node(6); // 6 × k
    let f = tip.row(1).transpose() * p; // Φ_tipᵀ (0, P, 0, …)
    let q = flex.modes.stiffness.clone().lu().solve(&f).unwrap();
    let q: Vec<f64> = q.iter().copied().collect();
    let l = flex.beam.length;
    let d = eom_gen::mech::flex_outputs::deformation(flex, l, &q);
    let want_v = p * l.powi(3) / (3.0 * 300.0) + p * l / s.kga_y;
    assert!((d[1] - want_v).abs() < 1e-9 * want_v, "u_y(L) {}", d[1]);
    let want_psi = p * l * l / (2.0 * 300.0);
    assert!((d[5] - want_psi).abs() < 1e-9 * want_psi, "θ_z(L) {}", d[5]);
    for x in [0.1, 0.77, 1.5, 1.95] {
        let b = &flex.beam;
        let stiffness = [b.ea, b.ei_y, b.ei_z, b.gj];
        let sf = eom_gen::mech::flex_outputs::section_forces(flex, &stiffness, x, &q);
        assert!((sf[1] - p).abs() < 1e-8 * p, "Q_y({x}) = {}", sf[1]);
        assert!(
            (sf[5] - p * (l - x)).abs() < 1e-8 * p * l,
            "M_z({x}) = {}",
            sf[5]
        );
    }
}
