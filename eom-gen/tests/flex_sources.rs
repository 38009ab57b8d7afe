//! The other two ways to give a flexible body's shape functions (issue
//! #17), and a beam's `Fixed([...])` reference conditions:
//!
//! - **assumed modes** (Rayleigh–Ritz): `sin(nπx/L)` is the exact mode shape
//!   of a pinned–pinned Euler–Bernoulli beam, so assumed sine modes give
//!   its frequencies `(nπ/L)² √(EI/ρA)` exactly; polynomial clamped–free
//!   shapes give Rayleigh–Ritz upper bounds that fall monotonically to the
//!   closed form `(β_iL)² √(EI/(ρA L⁴))` as shapes are added;
//! - **imported modal data**: the built-in beam's own FE model, exported as a
//!   generic FE user would (nodes, assembled mass and stiffness matrices) and
//!   turned into a modal file by `examples/modal_export.py` (or, without
//!   Python, the same lumping in Rust), reproduces the beam's frequencies
//!   exactly (the file carries its modal matrices) and its inertia shape
//!   integrals to the lumped-mass approximation, whose error falls as `h²`;
//! - a free body of each kind conserves energy;
//! - every validation error at its `file:line:col`.

use eom_gen::System;
use eom_gen::flex::imported::{Consistent, ModalData, ModalNode, ModeShape};
use eom_gen::flex::{Beam, Reference, normal_modes};
use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use eom_sim::{Dop853, OdeSystem, SolveOptions, integrate};
use nalgebra::DMatrix;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

const L: f64 = 2.0;
const RHO_A: f64 = 1.5;
const RHO_IP: f64 = 0.002;
const EA: f64 = 1e6;
const EI_Y: f64 = 400.0;
const EI_Z: f64 = 300.0;
const GJ: f64 = 200.0;

/// A model of one flexible body `rod` on `joint` from ground.
fn model(flexible: &str, joint: &str) -> String {
    format!(
        r#"Model(
    name: "rod",
    parameters: [(name: "L", value: {L}), (name: "rho_a", value: {RHO_A})],
    bodies: [(
        name: "rod",
        flexible: {flexible},
    )],
    joints: [(name: "j", kind: {joint}, parent: "ground", child: "rod")],
)"#
    )
}

/// An `AssumedModes(…)` body with these shapes.
fn assumed(shapes: &[&str]) -> String {
    format!(
        "AssumedModes(length: \"L\", rho_a: \"rho_a\", rho_ip: {RHO_IP}, ea: {EA}, ei_y: {EI_Y}, \
         ei_z: {EI_Z}, gj: {GJ},\n            shapes: [{}])",
        shapes.join(", ")
    )
}

fn system_at(path: &str, text: String) -> System {
    check(&Source::new(path, text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

fn errors_at(path: &str, text: String) -> String {
    match check(&Source::new(path, text)) {
        Ok(_) => "valid".to_string(),
        Err(report) => report.to_string(),
    }
}

/// The elastic frequencies of the linearised system about rest, ascending:
/// `M(0)` and `K = ∂bias/∂q` (central differences; the body is clamped to
/// ground, so the bias is `K_ff q` and the differences are exact to
/// round-off).
fn frequencies(sys: &System) -> Vec<f64> {
    let num = Numeric::new(sys).unwrap();
    let n = sys.nq();
    let zero = vec![0.0; n];
    let m = num.terms(&zero, &zero, 0.0, &[]).unwrap().mass_matrix;
    let m = DMatrix::from_fn(n, n, |r, c| m[r][c]);
    let h = 1e-6;
    let mut k = DMatrix::zeros(n, n);
    for c in 0..n {
        let (mut qp, mut qm) = (zero.clone(), zero.clone());
        qp[c] = h;
        qm[c] = -h;
        let bp = num.terms(&qp, &zero, 0.0, &[]).unwrap().bias;
        let bm = num.terms(&qm, &zero, 0.0, &[]).unwrap().bias;
        for r in 0..n {
            k[(r, c)] = (bp[r] - bm[r]) / (2.0 * h);
        }
    }
    let l = m.cholesky().expect("M positive definite").l();
    let li = l.try_inverse().unwrap();
    let a = &li * k * li.transpose();
    let mut w2: Vec<f64> = ((&a + a.transpose()) * 0.5)
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .collect();
    w2.sort_by(f64::total_cmp);
    w2.into_iter().map(f64::sqrt).collect()
}

#[test]
fn assumed_sine_modes_give_the_exact_pinned_pinned_frequencies() {
    // sin(nπx/L) is the exact pinned–pinned mode: ω_n = (nπ/L)² √(EI/ρA),
    // bending in x–y with EI_z, in x–z with EI_y. The integrals are
    // Gauss–Legendre to round-off, so only round-off separates them.
    let text = model(
        &assumed(&[
            "(v: \"sin(pi*x/L)\")",
            "(v: \"sin(2*pi*x/L)\")",
            "(v: \"sin(3*pi*x/L)\")",
            "(w: \"sin(pi*x/L)\")",
        ]),
        "Fixed",
    );
    let sys = system_at("rod.ron", text);
    let flex = sys.bodies[1].flexible.as_deref().unwrap();
    let c = |n: f64, ei: f64| (n * PI / L).powi(2) * (ei / RHO_A).sqrt();
    let mut want = [c(1.0, EI_Z), c(2.0, EI_Z), c(3.0, EI_Z), c(1.0, EI_Y)];
    want.sort_by(f64::total_cmp);
    let ritz = &flex.modes.frequencies;
    let linear = frequencies(&sys);
    for i in 0..4 {
        let (r, p) = (ritz[i] / want[i] - 1.0, linear[i] / want[i] - 1.0);
        eprintln!(
            "ω_{}: want {:.9}, Ritz {r:.1e}, linearised model {p:.1e}",
            i + 1,
            want[i]
        );
        assert!(
            r.abs() < 1e-12,
            "Ritz ω_{} = {}, want {}",
            i + 1,
            ritz[i],
            want[i]
        );
        assert!(
            p.abs() < 1e-7,
            "model ω_{} = {}, want {}",
            i + 1,
            linear[i],
            want[i]
        );
    }
    // Modal mass of sin(πx/L): ρA L/2.
    assert!((flex.invariants.modal_mass[(0, 0)] - RHO_A * L / 2.0).abs() < 1e-12);
    // The section at x: mid-span v₁ = 1 with no slope; at x = 0 the slope
    // θ_z = v₁' = π/L, and the x–z shape turns the section by θ_y = −w' = −π/L.
    let mid = flex.section_at(L / 2.0).unwrap();
    assert!((mid.translation[(1, 0)] - 1.0).abs() < 1e-15 && mid.rotation[(2, 0)].abs() < 1e-15);
    let root = flex.section_at(0.0).unwrap();
    assert!(
        (root.rotation[(2, 0)] - PI / L).abs() < 1e-15,
        "{}",
        root.rotation
    );
    assert!(
        (root.rotation[(1, 3)] + PI / L).abs() < 1e-15,
        "{}",
        root.rotation
    );
}

#[test]
fn assumed_polynomials_bound_the_clamped_free_frequencies_from_above() {
    // (x/L)^2 … (x/L)^(n+1) satisfy the clamped conditions at x = 0: the
    // Rayleigh–Ritz frequencies are upper bounds that fall monotonically to
    // the cantilever's (β₁L = 1.8751…, β₂L = 4.6940…) as shapes are added.
    let exact = |bl: f64| bl * bl * (EI_Z / (RHO_A * L.powi(4))).sqrt();
    let (w1, w2) = (exact(1.875_104_068_711_961), exact(4.694_091_132_974_175));
    let mut last = (f64::INFINITY, f64::INFINITY);
    for n in 1..=6 {
        let shapes: Vec<String> = (2..n + 2).map(|p| format!("(v: \"(x/L)^{p}\")")).collect();
        let refs: Vec<&str> = shapes.iter().map(String::as_str).collect();
        let sys = system_at("rod.ron", model(&assumed(&refs), "Fixed"));
        let f = &sys.bodies[1].flexible.as_deref().unwrap().modes.frequencies;
        let e1 = f[0] / w1 - 1.0;
        let e2 = f.get(1).map(|w| w / w2 - 1.0);
        eprintln!("{n} polynomial shapes: ω₁ error {e1:.3e}, ω₂ error {e2:?}");
        assert!(
            e1 > -1e-12 && f[0] <= last.0,
            "n = {n}: ω₁ = {} not above {w1} and falling",
            f[0]
        );
        if let Some(e2) = e2 {
            assert!(e2 > -1e-12 && f[1] <= last.1, "n = {n}: ω₂ = {}", f[1]);
            last.1 = f[1];
        }
        last.0 = f[0];
    }
    // Six shapes (degree 7): ω₁ within 1e-9, ω₂ within 5e-5. (Seven
    // monomials are refused: their Gram matrix's smallest scaled eigenvalue
    // is below 1e-10, numerically dependent; orthogonal polynomials would
    // go further.)
    assert!(
        last.0 / w1 - 1.0 < 1e-9 && last.1 / w2 - 1.0 < 5e-5,
        "{last:?}"
    );
}

/// A scratch directory of this test process.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("eom-flex-sources-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The built-in beam of `n` elements.
fn beam(n: usize) -> Beam {
    Beam::new(L, RHO_A, RHO_IP, EA, EI_Y, EI_Z, GJ, n).unwrap()
}

fn write_mtx(path: &Path, a: &DMatrix<f64>) {
    let mut out = String::from("%%MatrixMarket matrix coordinate real general\n");
    let nz: Vec<(usize, usize, f64)> = (0..a.nrows())
        .flat_map(|r| (0..a.ncols()).map(move |c| (r, c)))
        .filter(|&(r, c)| a[(r, c)] != 0.0)
        .map(|(r, c)| (r, c, a[(r, c)]))
        .collect();
    out += &format!("{} {} {}\n", a.nrows(), a.ncols(), nz.len());
    for (r, c, v) in nz {
        out += &format!("{} {} {v:e}\n", r + 1, c + 1);
    }
    std::fs::write(path, out).unwrap();
}

/// The clamped beam's modal file: through `examples/modal_export.py` from
/// a generic FE export when `python3` runs, else the script's lumping done
/// here. Returns the file name and whether Python wrote it.
fn export_beam(dir: &Path, n: usize, k: usize, consistent: bool) -> (String, bool) {
    let b = beam(n);
    let (m, kk) = (b.mass(), b.stiffness());
    let nodes: String = (0..b.nodes())
        .map(|i| format!("{}, 0, 0\n", b.node_x(i)))
        .collect();
    std::fs::write(dir.join("nodes.csv"), format!("x, y, z\n{nodes}")).unwrap();
    write_mtx(&dir.join("mass.mtx"), &m);
    write_mtx(&dir.join("stiffness.mtx"), &kk);
    let name = format!("beam{n}.modal.ron");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/modal_export.py");
    let mut cmd = std::process::Command::new("python3");
    cmd.arg(&script);
    if !consistent {
        cmd.arg("--lumped-only");
    }
    let run = cmd
        .args([
            "--nodes",
            "nodes.csv",
            "--mass",
            "mass.mtx",
            "--stiffness",
            "stiffness.mtx",
        ])
        .args([
            "--fix",
            "0:all",
            "--modes-kept",
            &k.to_string(),
            "-o",
            &name,
        ])
        .current_dir(dir)
        .output();
    if let Ok(out) = &run {
        assert!(
            out.status.success(),
            "modal_export.py failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        return (name, true);
    }
    // No Python: the same file from Rust (row-sum lumping, modal matrices
    // of the consistent matrices).
    let modes = normal_modes(&b, &Reference::Clamped, k).unwrap();
    let sum = |r: usize, dof: usize| (0..b.nodes()).map(|j| m[(r, 6 * j + dof)]).sum::<f64>();
    let data = ModalData {
        doc: None,
        nodes: (0..b.nodes())
            .map(|i| ModalNode {
                name: None,
                position: [b.node_x(i), 0.0, 0.0],
                mass: (0..3).map(|d| sum(6 * i + d, d)).sum::<f64>() / 3.0,
                inertia: Some(std::array::from_fn(|r| {
                    std::array::from_fn(|c| sum(6 * i + 3 + r, 3 + c))
                })),
            })
            .collect(),
        modes: (0..k)
            .map(|j| ModeShape {
                name: None,
                translation: (0..b.nodes())
                    .map(|i| std::array::from_fn(|a| modes.shapes[(6 * i + a, j)]))
                    .collect(),
                rotation: Some(
                    (0..b.nodes())
                        .map(|i| std::array::from_fn(|a| modes.shapes[(6 * i + 3 + a, j)]))
                        .collect(),
                ),
            })
            .collect(),
        modal_mass: Some(rows(&modes.mass)),
        modal_stiffness: rows(&modes.stiffness),
        modal_damping: None,
        consistent: consistent.then(|| {
            // The first-order invariants of the consistent mass: R_tᵀ M R_r = −c̃.
            let r = b.rigid_modes();
            let g = r.transpose() * &m * &r;
            let mr = r.transpose() * &m * &modes.shapes;
            Consistent {
                mass: g[(0, 0)],
                first_moment: [g[(1, 5)], g[(2, 3)], g[(0, 4)]],
                inertia: std::array::from_fn(|i| std::array::from_fn(|j| g[(3 + i, 3 + j)])),
                s_bar: (0..k)
                    .map(|j| std::array::from_fn(|d| mr[(d, j)]))
                    .collect(),
                coupling: (0..k)
                    .map(|j| std::array::from_fn(|a| mr[(3 + a, j)]))
                    .collect(),
            }
        }),
        geometric_stiffness: None,
    };
    let name = format!("beam{n}.modal.json");
    std::fs::write(dir.join(&name), serde_json::to_string(&data).unwrap()).unwrap();
    (name, false)
}

fn rows(a: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..a.nrows())
        .map(|r| a.row(r).iter().copied().collect())
        .collect()
}

fn beam_flexible(n: usize, k: usize) -> String {
    format!(
        "Beam(length: \"L\", rho_a: \"rho_a\", rho_ip: {RHO_IP}, ea: {EA}, ei_y: {EI_Y}, \
         ei_z: {EI_Z}, gj: {GJ}, elements: {n}, reference: Clamped, modes: {k})"
    )
}

/// Largest relative difference of two blocks (relative to the largest entry).
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let top = a.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
        / top
}

#[test]
fn imported_beam_data_reproduce_the_beam() {
    // The built-in beam's FE model exported and imported: mass and first
    // moment of the lumped mass are exact (trapezoidal sums of linear
    // integrands); S̄, the coupling Ī_θf⁰, the inertia Ī, the modal mass
    // Σ S̄_ii and with it the frequencies (K_ff is the file's, exact) carry
    // the lumped-mass error, O(h²).
    let k = 4;
    let mut errors = Vec::new();
    for n in [8, 16] {
        let dir = scratch(&format!("beam{n}"));
        let (file, by_python) = export_beam(&dir, n, k, false);
        let model_path = dir.join("rod.ron");
        let imported = system_at(
            model_path.to_str().unwrap(),
            model(&format!("Modal(file: \"{file}\")"), "Fixed"),
        );
        let builtin = system_at("rod.ron", model(&beam_flexible(n, k), "Fixed"));
        let (fi, fb) = (
            imported.bodies[1].flexible.as_deref().unwrap(),
            builtin.bodies[1].flexible.as_deref().unwrap(),
        );
        let df = rel(&fb.modes.frequencies, &fi.modes.frequencies);
        let (lb, li) = (frequencies(&builtin), frequencies(&imported));
        let lin = rel(&fi.modes.frequencies, &li);
        assert!(
            lin < 1e-7,
            "model and Ritz frequencies differ by {lin:e}: {li:?}"
        );
        eprintln!("frequencies: beam {lb:.6?}, imported {li:.6?}");
        // Align signs mode by mode (each side picks its own), then compare.
        let sign: Vec<f64> = (0..k)
            .map(|j| {
                fb.modes
                    .shapes
                    .column(j)
                    .dot(&fi.modes.shapes.column(j))
                    .signum()
            })
            .collect();
        let fix =
            |a: &DMatrix<f64>| DMatrix::from_fn(a.nrows(), a.ncols(), |r, c| a[(r, c)] * sign[c]);
        let (ib, ii) = (&fb.invariants, &fi.invariants);
        let dm = (ib.mass - ii.mass).abs() / ib.mass;
        let d1 = rel(ib.first_moment.as_slice(), ii.first_moment.as_slice());
        let ds = rel(ib.s_bar.as_slice(), fix(&ii.s_bar).as_slice());
        let dc = rel(ib.coupling.as_slice(), fix(&ii.coupling).as_slice());
        let di = rel(ib.inertia.as_slice(), ii.inertia.as_slice());
        let dmm = rel(
            fb.modes.mass.as_slice(),
            fix(&fix(&ii.modal_mass).transpose()).as_slice(),
        );
        eprintln!(
            "{n} elements ({}): frequencies {df:.1e}, mass {dm:.1e}, I₁ {d1:.1e}, S̄ {ds:.2e}, \
             Ī_θf⁰ {dc:.2e}, Ī {di:.2e}, M_ff {dmm:.1e}",
            if by_python {
                "modal_export.py"
            } else {
                "Rust export"
            }
        );
        assert!(dm < 1e-12 && d1 < 1e-12, "mass {dm:e}, first moment {d1:e}");
        errors.push([df, dmm, ds, dc, di]);
        if std::env::var_os("EOM_KEEP_SCRATCH").is_none() {
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
    // Halving h divides the lumped-mass error by ~4.
    let names = ["ω", "M_ff", "S̄", "Ī_θf⁰", "Ī"];
    for (i, name) in names.iter().enumerate() {
        let (coarse, fine) = (errors[0][i], errors[1][i]);
        let ratio = coarse / fine;
        assert!(
            (3.5..4.5).contains(&ratio) && fine < 2e-2,
            "{name}: error {coarse:e} → {fine:e}, ratio {ratio}"
        );
    }
}

#[test]
fn imported_consistent_invariants_reproduce_the_beam_exactly() {
    // With the consistent mass matrix's first-order invariants in the file
    // (mass, I₁, Ī, S̄, Ī_θf⁰ and M_ff = Φᵀ M Φ), the imported body is the
    // built-in beam to round-off at q_f = 0: the same frequencies, clamped
    // and on a free joint (where the lumped M_ff made the mass matrix
    // indefinite), and the same invariants; only the second-order terms
    // (the inertia's change with q_f) stay lumped.
    let (n, k) = (8, 4);
    let dir = scratch("consistent");
    let (file, by_python) = export_beam(&dir, n, k, true);
    eprintln!(
        "written by {}",
        if by_python {
            "modal_export.py"
        } else {
            "the Rust export"
        }
    );
    let path = dir.join("rod.ron");
    for joint in ["Fixed", "Free"] {
        let imported = system_at(
            path.to_str().unwrap(),
            model(&format!("Modal(file: \"{file}\")"), joint),
        );
        let builtin = system_at("rod.ron", model(&beam_flexible(n, k), joint));
        let (fi, fb) = (
            imported.bodies[1].flexible.as_deref().unwrap(),
            builtin.bodies[1].flexible.as_deref().unwrap(),
        );
        let sign: Vec<f64> = (0..k)
            .map(|j| {
                fb.modes
                    .shapes
                    .column(j)
                    .dot(&fi.modes.shapes.column(j))
                    .signum()
            })
            .collect();
        let fix =
            |a: &DMatrix<f64>| DMatrix::from_fn(a.nrows(), a.ncols(), |r, c| a[(r, c)] * sign[c]);
        let (ib, ii) = (&fb.invariants, &fi.invariants);
        let diffs = [
            (
                "ω (Ritz)",
                rel(&fb.modes.frequencies, &fi.modes.frequencies),
            ),
            ("mass", (ib.mass - ii.mass).abs() / ib.mass),
            (
                "I₁",
                rel(ib.first_moment.as_slice(), ii.first_moment.as_slice()),
            ),
            ("Ī", rel(ib.inertia.as_slice(), ii.inertia.as_slice())),
            ("S̄", rel(ib.s_bar.as_slice(), fix(&ii.s_bar).as_slice())),
            (
                "Ī_θf⁰",
                rel(ib.coupling.as_slice(), fix(&ii.coupling).as_slice()),
            ),
            (
                "M_ff",
                rel(ib.modal_mass.as_slice(), ii.modal_mass.as_slice()),
            ),
        ];
        for (what, d) in diffs {
            assert!(d < 1e-9, "{joint}: {what} differs by {d:e}");
        }
        if joint == "Fixed" {
            // The linearised model vibrates at the FE frequencies.
            let (lb, li) = (frequencies(&builtin), frequencies(&imported));
            let dl = rel(&lb, &li);
            eprintln!("{joint}: invariants {diffs:?}, linearised ω {dl:.1e} {li:?}");
            assert!(
                dl < 1e-7,
                "linearised frequencies differ by {dl:e}: {lb:?} vs {li:?}"
            );
        } else {
            // On a free joint: the mass matrix at rest has the same (positive)
            // eigenvalues as the beam's.
            let eig = |sys: &System| {
                let num = Numeric::new(sys).unwrap();
                let mut q = vec![0.0; sys.nq()];
                q[3] = 1.0;
                let m = num
                    .terms(&q, &vec![0.0; sys.nu()], 0.0, &[])
                    .unwrap()
                    .mass_matrix;
                let n = sys.nu();
                let mut e: Vec<f64> = DMatrix::from_fn(n, n, |r, c| m[r][c])
                    .symmetric_eigenvalues()
                    .iter()
                    .copied()
                    .collect();
                e.sort_by(f64::total_cmp);
                e
            };
            let (eb, ei) = (eig(&builtin), eig(&imported));
            eprintln!("{joint}: invariants {diffs:?}, M(0) eigenvalues {ei:?}");
            assert!(
                ei[0] > 0.0 && rel(&eb, &ei) < 1e-9,
                "M(0): {eb:?} vs {ei:?}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `ẏ = (q̇, u̇)` by the articulated-body algorithm.
struct Ode<'a> {
    num: &'a Numeric,
    nq: usize,
}

impl<const N: usize> OdeSystem<N> for Ode<'_> {
    fn rhs(&self, t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        let (q, u) = y.split_at(self.nq);
        let nu = u.len();
        let ud = self
            .num
            .forward_dynamics(q, u, t, &vec![0.0; nu], &[])
            .unwrap_or_else(|_| vec![f64::NAN; nu]);
        dy[..self.nq].copy_from_slice(&self.num.qdot(q, u));
        dy[self.nq..].copy_from_slice(&ud);
    }
}

/// A free body (free joint, no gravity) tumbling and vibrating: relative
/// energy drift over 0.5 s with DOP853 at 1e-12 (the body turns by ~1 rad,
/// its slowest mode swings ~1 period, its axial one ~60).
fn free_drift<const N: usize>(sys: &System) -> f64 {
    let num = Numeric::new(sys).unwrap();
    let (nq, nu) = (sys.nq(), sys.nu());
    assert_eq!(nq + nu, N);
    let k = nq - 7;
    let mut y0 = [0.0; N];
    y0[3] = 1.0; // identity quaternion
    for j in 0..k {
        y0[7 + j] = 2e-3 * (j as f64 + 1.0).recip();
        y0[nq + 6 + j] = 0.05 * if j % 2 == 0 { 1.0 } else { -1.0 };
    }
    y0[nq..nq + 6].copy_from_slice(&[0.1, -0.05, 0.02, 0.4, 0.3, 2.0]);
    let energy = |y: &[f64; N]| {
        let (t, v) = num.energy(&y[..nq], &y[nq..], 0.0).unwrap();
        t + v
    };
    let e0 = energy(&y0);
    let opts = SolveOptions {
        t_eval: (1..=10).map(|i| 0.05 * i as f64).collect(),
        ..SolveOptions::default()
    };
    let sol = integrate(
        &mut Dop853::new(1e-12, 1e-12),
        &Ode { num: &num, nq },
        0.0,
        y0,
        0.5,
        &opts,
        &mut [],
    );
    assert_eq!(sol.y_out.len(), 10, "stopped: {:?}", sol.stop);
    sol.y_out
        .iter()
        .map(|y| (energy(y) - e0).abs() / e0.abs())
        .fold(0.0, f64::max)
}

#[test]
fn free_bodies_of_each_kind_conserve_energy() {
    // No damping, no gravity: T + V (strain energy ½ q_fᵀ K_ff q_f)
    // is constant along the exact motion; DOP853 at 1e-12 keeps it to ~1e-10.
    let shapes = assumed(&[
        "(v: \"(x/L)^2\")",
        "(w: \"(x/L)^2\", phi: \"x/L\")",
        "(u: \"x/L\", v: \"(x/L)^3\")",
    ]);
    let sys = system_at("rod.ron", model(&shapes, "Free"));
    let d = free_drift::<19>(&sys);
    eprintln!("assumed modes: relative energy drift {d:.1e}");
    assert!(d < 1e-8, "assumed modes: relative energy drift {d:e}");

    let dir = scratch("free");
    let (file, _) = export_beam(&dir, 6, 4, true);
    let path = dir.join("rod.ron");
    let sys = system_at(
        path.to_str().unwrap(),
        model(&format!("Modal(file: \"{file}\")"), "Free"),
    );
    let d = free_drift::<21>(&sys);
    eprintln!("imported modal data: relative energy drift {d:.1e}");
    assert!(d < 1e-8, "imported: relative energy drift {d:e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn fixed_reference_at_the_root_is_the_clamped_beam() {
    // Fixing all six degrees of freedom of node 0 is `Clamped`.
    let fixed = beam_flexible(6, 4).replace(
        "reference: Clamped",
        "reference: Fixed([(node: 0, dofs: [Ux, Uy, Uz, Rx, Ry, Rz])])",
    );
    let a = system_at("rod.ron", model(&fixed, "Fixed"));
    let b = system_at("rod.ron", model(&beam_flexible(6, 4), "Fixed"));
    let (fa, fb) = (
        &a.bodies[1].flexible.as_deref().unwrap().modes.frequencies,
        &b.bodies[1].flexible.as_deref().unwrap().modes.frequencies,
    );
    assert!(rel(fb, fa) < 1e-14, "{fa:?} vs {fb:?}");
}

#[test]
fn flex_source_errors_are_located() {
    let assumed_err = |shapes: &[&str]| errors_at("rod.ron", model(&assumed(shapes), "Fixed"));
    // Dependent shapes, at `shapes` (line 7).
    let r = assumed_err(&["(v: \"sin(pi*x/L)\")", "(v: \"2*sin(pi*x/L)\")"]);
    assert!(
        r.contains(
            "rod.ron:7:21: error: flexible body `rod`: the shapes are not independent: \
             `1.000·S1 − 0.500·S2` is (next to) zero"
        ),
        "{r}"
    );
    // A rigid motion among the shapes: the frame is undefined.
    let r = assumed_err(&["(v: \"(x/L)^2\")", "(v: \"x/L + (x/L)^2\")"]);
    assert!(
        r.contains("rod.ron:7:21: error: flexible body `rod`: `")
            && r.contains(
                "is a rigid-body motion of the whole body, so the body frame is undefined"
            ),
        "{r}"
    );
    // Unknown name, empty shape, a derivative that is not finite: all at once.
    let r = assumed_err(&["(v: \"sin(pi*x/Lx)\")", "()"]);
    assert!(
        r.contains("rod.ron:7:36: error: unknown name `Lx` in a shape function"),
        "{r}"
    );
    assert!(
        r.contains("rod.ron:7:43: error: shape 2 of flexible body `rod` is empty"),
        "{r}"
    );
    let r = assumed_err(&["(v: \"(x/L)^2 * ln(x - 1)\")"]);
    assert!(
        r.contains(
            "rod.ron:7:26: error: flexible body `rod`: shape 1: `v` is not a finite number at x = "
        ),
        "{r}"
    );
    // A kink: the integrals do not converge.
    let r = assumed_err(&["(v: \"(x/L)^2\")", "(v: \"abs(x - 0.7)^2.5\")"]);
    assert!(r.contains("the shape integrals do not converge"), "{r}");
    // Non-positive section data, at their values (line 6).
    let r = errors_at(
        "rod.ron",
        model(
            &assumed(&["(v: \"(x/L)^2\")"]).replace("ea: 1000000", "ea: -1"),
            "Fixed",
        ),
    );
    assert!(
        r.contains("rod.ron:6:")
            && r.contains("axial stiffness `ea` of flexible body `rod` is -1 N"),
        "{r}"
    );
    // A node marker on an assumed-mode body that names no nodes.
    let r = errors_at(
        "rod.ron",
        model(&assumed(&["(v: \"(x/L)^2\")"]), "Fixed").replace(
            "        flexible:",
            "        markers: [(name: \"tip\", node: 3)],\n        flexible:",
        ),
    );
    assert!(
        r.contains("marker `tip` names node 3, but body `rod` (assumed modes) has 0 named nodes"),
        "{r}"
    );

    // The beam's Fixed reference: an unknown node at its field, a free rigid
    // motion at `reference`.
    let r = errors_at(
        "rod.ron",
        model(
            &beam_flexible(6, 2).replace(
                "reference: Clamped",
                "reference: Fixed([(node: 9, dofs: [Ux])])",
            ),
            "Fixed",
        ),
    );
    assert!(
        r.contains("rod.ron:6:")
            && r.contains("reference node 9 does not exist: the beam has nodes 0..=6"),
        "{r}"
    );
    let r = errors_at(
        "rod.ron",
        model(
            &beam_flexible(6, 2).replace(
                "reference: Clamped",
                "reference: Fixed([(node: 0, dofs: [Ux, Uy, Uz]), (node: 6, dofs: [Uy, Uz])])",
            ),
            "Fixed",
        ),
    );
    assert!(
        r.contains("rod.ron:6:")
            && r.contains(
                "the rigid-body motion `rotation about x` of the whole beam satisfies them"
            ),
        "{r}"
    );
}

#[test]
fn modal_file_errors_are_located_in_the_file() {
    let dir = scratch("errors");
    let model_path = dir.join("rod.ron");
    let model_str = model_path.to_str().unwrap().to_string();
    let shown = |name: &str| dir.join(name).display().to_string();
    let with = |name: &str, text: &str| {
        std::fs::write(dir.join(name), text).unwrap();
        errors_at(
            &model_str,
            model(&format!("Modal(file: \"{name}\")"), "Fixed"),
        )
    };
    // Missing file: at `file` (line 6).
    let r = errors_at(
        &model_str,
        model("Modal(file: \"nope.modal.ron\")", "Fixed"),
    );
    assert!(
        r.contains(":6:31: error: flexible body `rod`: cannot read modal file `nope.modal.ron`"),
        "{r}"
    );
    let good = "ModalData(\n    nodes: [\n        (position: (0, 0, 0), mass: 1.0),\n        (position: (1, 0, 0), mass: 1.0),\n    ],\n    modes: [\n        (translation: [(0, 0, 0), (0, 1, 0)]),\n        (translation: [(0, 0, 0), (0, 0, 1)]),\n    ],\n    modal_stiffness: [[100, 0], [0, 200]],\n)\n";
    assert_eq!(with("ok.modal.ron", good), "valid");
    // Unparsable: the modal file's line and column.
    let r = with("typo.modal.ron", &good.replace("mass: 1.0)", "masss: 1.0)"));
    assert!(
        r.contains(&format!(
            "{}:3:31: Unexpected field named `masss` in `ModalNode`",
            shown("typo.modal.ron")
        )),
        "{r}"
    );
    // Inconsistent sizes and a negative mass, all at once, each located.
    let r = with(
        "sizes.modal.ron",
        &good
            .replace("(0, 0, 0), (0, 0, 1)", "(0, 0, 1)")
            .replace("(1, 0, 0), mass: 1.0", "(1, 0, 0), mass: -1.0")
            .replace("[[100, 0], [0, 200]]", "[[100, 0]]"),
    );
    let p = shown("sizes.modal.ron");
    for want in [
        format!("{p}:4:37: node 1: mass is -1 kg"),
        format!("{p}:8:23: mode 2: 1 translations for 2 nodes"),
        format!("{p}:10:22: `modal_stiffness` must be 2×2"),
    ] {
        assert!(r.contains(&want), "want `{want}` in\n{r}");
    }
    // Dependent modes (the second twice the first).
    let r = with("dep.modal.ron", &good.replace("(0, 0, 1)]", "(0, 2, 0)]"));
    assert!(r.contains("the shapes are not independent"), "{r}");
    // A rigid mode (zero stiffness): the frame is undefined.
    let r = with("rigid.modal.ron", &good.replace("[0, 200]", "[0, 0]"));
    assert!(
        r.contains(&format!(
            "{}:10:22: `0.000·S1 + 1.000·S2` has no strain energy",
            shown("rigid.modal.ron")
        )) || r.contains("has no strain energy"),
        "{r}"
    );
    assert!(r.contains("drop the rigid-body modes"), "{r}");
    // Consistent invariants: without the modal mass they belong to, with
    // the wrong number of modes, or making an indefinite mass matrix.
    let block = "    consistent: (mass: 2.0, first_moment: (1, 0, 0), inertia: ((0.1, 0, 0), (0, 1, 0), (0, 0, 1)),\n        s_bar: [(0, 1, 0), (0, 0, 1)], coupling: [(0, 0, 1), (0, -1, 0)]),\n)\n";
    let with_block = |b: &str| good.replace(")\n", "").trim_end().to_string() + "\n" + b;
    let r = with("c1.modal.ron", &with_block(block));
    assert!(
        r.contains(&format!(
            "{}:11:17: `consistent` invariants need the FE model's `modal_mass`",
            shown("c1.modal.ron")
        )),
        "{r}"
    );
    let mm = "    modal_mass: [[1, 0], [0, 1]],\n";
    let r = with(
        "c2.modal.ron",
        &with_block(&(mm.to_string() + &block.replace("(0, 1, 0), (0, 0, 1)]", "(0, 1, 0)]"))),
    );
    assert!(
        r.contains("`consistent` has 1 `s_bar` and 2 `coupling` entries for 2 modes"),
        "{r}"
    );
    // S̄ of mode 1 twice as large: its momentum 2 exceeds what m = 2 and
    // M_ff = 1 allow (1 − 2²/2 < 0), the mass matrix is indefinite.
    let r = with(
        "c3.modal.ron",
        &with_block(&(mm.to_string() + &block.replace("s_bar: [(0, 1, 0)", "s_bar: [(0, 2, 0)"))),
    );
    assert!(
        r.contains("make a mass matrix that is not positive definite"),
        "{r}"
    );
    assert_eq!(
        with(
            "c4.modal.ron",
            &with_block(
                &(mm.to_string()
                    + &block
                        .replace("(0, 1, 0), (0, 0, 1)]", "(0, 0.5, 0), (0, 0, 0.5)]")
                        .replace(
                            "coupling: [(0, 0, 1), (0, -1, 0)]",
                            "coupling: [(0, 0, 0.5), (0, -0.5, 0)]"
                        ))
            )
        ),
        "valid"
    );
    // JSON: a problem at its place, and a syntax error at its line and column.
    let json = "{\n  \"nodes\": [\n    {\"position\": [0, 0, 0], \"mass\": 1.0},\n    {\"position\": [1, 0, 0], \"mass\": -2.0}\n  ],\n  \"modes\": [{\"translation\": [[0, 0, 0], [0, 1, 0]]}],\n  \"modal_stiffness\": [[100]]\n}\n";
    let r = with("neg.modal.json", json);
    assert!(
        r.contains(&format!(
            "{}:4:37: node 1: mass is -2 kg",
            shown("neg.modal.json")
        )),
        "{r}"
    );
    assert_eq!(with("ok.modal.json", &json.replace("-2.0", "2.0")), "valid");
    let r = with(
        "bad.modal.json",
        "{\n  \"nodes\": [\n    {\"position\": [0, 0, 0], \"mass\": 1.0,}\n  ]\n}\n",
    );
    assert!(
        r.contains(&format!("{}:3:41:", shown("bad.modal.json"))),
        "{r}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn assumed_damping_and_stiffening_have_their_closed_forms() {
    // Damping ζ on assumed (non-orthogonal) shapes damps every normal mode
    // of the reduced body by ζ: Φᵀ D Φ = diag(2 ζ ω_i). Probe D through the
    // bias: with the body clamped to ground, bias(q̇) − bias(0) = D q̇.
    let text = model(
        &assumed(&["(v: \"(x/L)^2\")", "(v: \"(x/L)^3\")"])
            .replace("shapes:", "damping: 0.03, shapes:"),
        "Fixed",
    );
    let sys = system_at("rod.ron", text);
    let num = Numeric::new(&sys).unwrap();
    let flex = sys.bodies[1].flexible.as_deref().unwrap();
    let (m, w) = (&flex.invariants.modal_mass, &flex.modes.frequencies);
    // The normal modes of (K, M), mass-normalised.
    let k = &flex.invariants.modal_stiffness;
    let l = m.clone().cholesky().unwrap().l();
    let li = l.clone().try_inverse().unwrap();
    let eig = (&li * k * li.transpose()).symmetric_eigen();
    let mut order: Vec<usize> = (0..2).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let phi = DMatrix::from_fn(2, 2, |r, c| {
        (li.transpose() * &eig.eigenvectors)[(r, order[c])]
    });
    let zero = [0.0; 2];
    let b0 = num.terms(&zero, &zero, 0.0, &[]).unwrap().bias;
    let mut d = DMatrix::zeros(2, 2);
    for c in 0..2 {
        let qd: Vec<f64> = phi.column(c).iter().copied().collect();
        let b = num.terms(&zero, &qd, 0.0, &[]).unwrap().bias;
        for r in 0..2 {
            d[(r, c)] = b[r] - b0[r];
        }
    }
    let modal = phi.transpose() * d;
    for i in 0..2 {
        let zeta = modal[(i, i)] / (2.0 * w[i]);
        assert!((zeta - 0.03).abs() < 1e-10, "mode {}: ζ = {zeta}", i + 1);
    }
    assert!(modal[(0, 1)].abs() < 1e-10 * modal[(1, 1)], "{modal}");

    // Stiffening of v = sin(πx/L) spinning about z through x = 0:
    // K_G1 = ∫ ρA (L² − x²)/2 (π/L)² cos²(πx/L) dx = ρA π² L (1/3 − 1/(4π²))/2.
    let text = model(
        &assumed(&["(v: \"sin(pi*x/L)\")"]).replace("shapes:", "stiffening: true, shapes:"),
        "Fixed",
    );
    let sys = system_at("rod.ron", text);
    let flex = sys.bodies[1].flexible.as_deref().unwrap();
    let g = flex
        .assumed_geometric_stiffness()
        .expect("assumed modes keep K_G1")
        .0[(0, 0)];
    let want = RHO_A * PI * PI * L * (1.0 / 3.0 - 1.0 / (4.0 * PI * PI)) / 2.0;
    assert!((g / want - 1.0).abs() < 1e-13, "K_G1 = {g}, want {want}");
}

#[test]
fn generated_programs_of_assumed_and_imported_bodies_equal_the_f64_algorithms() {
    // The symbolic path: the same recursive algorithms over the symbolic
    // scalar, the invariants inlined; a tunable damping ratio stays a
    // parameter. Each body hangs from a hub on a revolute joint, under
    // gravity, with stiffening (assumed) and the file's damping (imported).
    use eom_gen::functions::{Function, FunctionSet};
    use eom_gen::mech::formulate;
    let dir = scratch("programs");
    let (file, _) = export_beam(&dir, 4, 3, true);
    let path = dir.join("rod.ron");
    for flexible in [
        assumed(&[
            "(v: \"(x/L)^2\")",
            "(w: \"(x/L)^2\", phi: \"x/L\")",
            "(u: \"x/L\")",
        ])
        .replace("shapes:", "stiffening: true, damping: \"zeta\", shapes:"),
        format!("Modal(file: \"{file}\", damping: \"zeta\")"),
    ] {
        let text = model(&flexible, "Revolute(axis: (0, 1, 0))")
            .replace(
                "(name: \"rho_a\", value: 1.5)",
                "(name: \"rho_a\", value: 1.5), (name: \"zeta\", value: 0.02, tunable: true)",
            )
            .replace(
                "Model(\n    name: \"rod\",\n",
                "Model(\n    name: \"rod\",\n    gravity: (0, 0, -9.81),\n",
            );
        assert!(
            text.contains("gravity") && text.contains("tunable"),
            "test setup"
        );
        let sys = system_at(path.to_str().unwrap(), text);
        let f = formulate(&sys, FunctionSet::all_requested()).unwrap_or_else(|e| panic!("{e}"));
        let num = Numeric::new(&sys).unwrap();
        let n = sys.nq();
        let mut seed = 11_u64;
        let mut rand = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        for _ in 0..3 {
            let q: Vec<f64> = (0..n).map(|_| rand() * 0.05).collect();
            let u: Vec<f64> = (0..n).map(|_| rand() * 2.0).collect();
            let ud: Vec<f64> = (0..n).map(|_| rand()).collect();
            let tau: Vec<f64> = (0..n).map(|_| rand()).collect();
            let point = eom_gen::interpret::Point {
                sys: &sys,
                q: &q,
                u: &u,
                udot: &ud,
                tau: &tau,
                inputs: &[],
                params: &[("zeta".to_string(), 0.02)],
                multipliers: &[],
                t: 0.0,
            };
            let run = |function: Function| {
                eom_gen::interpret::run(f.program(function).expect("requested"), &point)
            };
            let close = |what: &str, got: &[f64], want: &[f64]| {
                assert_eq!(got.len(), want.len(), "{what}: lengths");
                let scale = want.iter().map(|x| x.abs()).fold(1.0, f64::max);
                for (k, (g, w)) in got.iter().zip(want).enumerate() {
                    assert!(
                        (g - w).abs() <= 1e-11 * scale,
                        "{what}[{k}]: generated {g}, f64 {w}"
                    );
                }
            };
            let terms = num.terms(&q, &u, 0.0, &[]).unwrap();
            close("bias", &run(Function::Bias), &terms.bias);
            close(
                "forward dynamics",
                &run(Function::ForwardDynamics),
                &num.forward_dynamics(&q, &u, 0.0, &tau, &[]).unwrap(),
            );
            let (t, v) = num.energy(&q, &u, 0.0).unwrap();
            close("energy", &run(Function::Energy), &[t, v]);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tunable_shapes_and_unknown_nodes_are_refused_at_their_field() {
    // The shape integrals are computed once: a shape using a tunable
    // parameter is refused where it is written, not silently frozen.
    let text = model(&assumed(&["(v: \"a*(x/L)^2\")"]), "Fixed").replace(
        "(name: \"rho_a\", value: 1.5)",
        "(name: \"rho_a\", value: 1.5), (name: \"a\", value: 2.0, tunable: true)",
    );
    let src = Source::new("rod.ron", text);
    let sys = check(&src).unwrap_or_else(|r| panic!("{r}")).system;
    let err = Numeric::new(&sys).expect_err("a tunable shape is refused");
    let at = src.line_col(err.span().start);
    assert_eq!((at.line, at.col), (7, 26), "{err}");
    assert!(err.to_string().contains("flexible body `rod`"), "{err}");

    // A marker on a node the modal file does not have.
    let dir = scratch("nodes");
    let (file, _) = export_beam(&dir, 2, 1, false);
    let path = dir.join("rod.ron");
    let r = errors_at(
        path.to_str().unwrap(),
        model(&format!("Modal(file: \"{file}\")"), "Fixed").replace(
            "        flexible:",
            "        markers: [(name: \"tip\", node: 3)],\n        flexible:",
        ),
    );
    assert!(
        r.contains(":6:39: error: marker `tip`: node 3 does not exist: `")
            && r.contains("` has nodes 0..=2"),
        "{r}"
    );
    // Two elements lump the beam coarsely: the lumped modal mass is 24 %
    // off the FE model's, and `check` says so (at `file`).
    let c = check(&Source::new(
        path.to_str().unwrap(),
        model(&format!("Modal(file: \"{file}\")"), "Fixed"),
    ))
    .unwrap_or_else(|r| panic!("{r}"));
    let w = c.render_warnings();
    assert!(
        w.contains(":6:31: warning: flexible body `rod`: the lumped nodal masses give a modal mass that differs from the file's `modal_mass` by 23.8 %"),
        "{w}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_point_at_an_imported_node_moves_as_at_the_beams_node() {
    // The beam's own FE model exported (8 elements, 4 clamped modes) and
    // read back: a point at the tip node, offset from it, must move with
    // the node's translation and small rotation exactly as at the built-in
    // beam's node 8 (the file's mode shapes are the beam's, up to sign),
    // position and velocity, at a deformed and moving state.
    let (n, k) = (8, 4);
    let dir = scratch("node_point");
    let (file, _) = export_beam(&dir, n, k, true);
    let path = dir.join("rod.ron");
    let joint = "Revolute(axis: (0, 1, 0))";
    let imported = system_at(
        path.to_str().unwrap(),
        model(&format!("Modal(file: \"{file}\")"), joint),
    );
    let builtin = system_at("rod.ron", model(&beam_flexible(n, k), joint));
    let (fi, fb) = (
        imported.bodies[1].flexible.as_deref().unwrap(),
        builtin.bodies[1].flexible.as_deref().unwrap(),
    );
    let sign: Vec<f64> = (0..k)
        .map(|j| {
            fb.modes
                .shapes
                .column(j)
                .dot(&fi.modes.shapes.column(j))
                .signum()
        })
        .collect();
    let (ni, nb) = (
        Numeric::new(&imported).unwrap(),
        Numeric::new(&builtin).unwrap(),
    );
    let qf = [0.03, -0.02, 0.01, 0.004];
    let qfd = [0.5, 0.3, -0.2, 0.1];
    let mut qb = vec![0.4];
    let mut ub = vec![1.3];
    qb.extend(qf);
    ub.extend(qfd);
    let qi: Vec<f64> = std::iter::once(qb[0])
        .chain((0..k).map(|j| qf[j] * sign[j]))
        .collect();
    let ui: Vec<f64> = std::iter::once(ub[0])
        .chain((0..k).map(|j| qfd[j] * sign[j]))
        .collect();
    let offset = [0.01, 0.02, -0.03];
    let (xb, vb) = nb.node_point(1, n, offset, &qb, &ub, 0.0).unwrap();
    let (xi, vi) = ni.node_point(1, n, offset, &qi, &ui, 0.0).unwrap();
    let dx = rel(&xb, &xi);
    let dv = rel(&vb, &vi);
    eprintln!("tip point: position {dx:.1e}, velocity {dv:.1e}; {xb:?} {vb:?}");
    assert!(dx < 1e-9 && dv < 1e-9, "{xb:?} vs {xi:?}; {vb:?} vs {vi:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
