//! Geometric stiffening of imported modal bodies (issue #17): the modal
//! file's optional `geometric_stiffness` block carries the foreshortening
//! matrices `K₁ = Φᵀ K_G(N₁) Φ`, `K₂ = Φᵀ K_G(N₂) Φ` that the stiffening
//! needs (`mech/stiffening.rs`), which an FE user exports as the geometric
//! stiffness of the body's two unit axial inertia loads.
//!
//! Checked: the built-in beam exported as a generic FE model (nodes,
//! assembled mass, stiffness and the two geometric stiffness matrices)
//! through `examples/modal_export.py` gives the beam's own `K₁`, `K₂`
//! (`flex::invariants::foreshortening`), and the stiffening terms the
//! imported body adds to `M` and `b` equal the stiffened beam's at random
//! spinning, deformed states; `stiffening: true` without the block, and a
//! malformed block, are errors at their place.

use eom_gen::System;
use eom_gen::flex::imported::{GeometricStiffness, ModalData, ModalNode, ModeShape};
use eom_gen::flex::invariants::modal_geometric_stiffness;
use eom_gen::flex::{Beam, Reference, normal_modes};
use eom_gen::mech::Numeric;
use eom_gen::model::{Source, check};
use nalgebra::DMatrix;
use std::path::{Path, PathBuf};

const L: f64 = 2.0;
const RHO_A: f64 = 1.5;
const RHO_IP: f64 = 0.002;
const EA: f64 = 1e6;
const EI_Y: f64 = 400.0;
const EI_Z: f64 = 300.0;
const GJ: f64 = 200.0;
const ELEMENTS: usize = 8;
const MODES: usize = 4;

fn beam() -> Beam {
    Beam::new(L, RHO_A, RHO_IP, EA, EI_Y, EI_Z, GJ, ELEMENTS).unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "eom-flex-modal-stiffening-{}-{name}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
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

/// The geometric stiffness matrices of the two unit axial loads:
/// `N₁ = ρA (L² − x²)/2` (unit `Ω²` about the root) and `N₂ = ρA (L − x)`.
fn geometric(b: &Beam) -> (DMatrix<f64>, DMatrix<f64>) {
    (
        b.geometric_stiffness(&|x| b.centrifugal_force(0.0, x)),
        b.geometric_stiffness(&|x| b.rho_a * (b.length - x)),
    )
}

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|r| (0..m.ncols()).map(|c| m[(r, c)]).collect())
        .collect()
}

/// The clamped beam exported through `examples/modal_export.py` with its
/// geometric stiffness matrices (or, without `python3`, the same file
/// written here: row-sum lumping and `Φᵀ K_G Φ`). Returns the file name and
/// whether Python wrote it.
fn export(dir: &Path) -> (String, bool) {
    let b = beam();
    let (m, kk) = (b.mass(), b.stiffness());
    let (g1, g2) = geometric(&b);
    let nodes: String = (0..b.nodes())
        .map(|i| format!("{}, 0, 0\n", b.node_x(i)))
        .collect();
    std::fs::write(dir.join("nodes.csv"), format!("x, y, z\n{nodes}")).unwrap();
    write_mtx(&dir.join("mass.mtx"), &m);
    write_mtx(&dir.join("stiffness.mtx"), &kk);
    write_mtx(&dir.join("kg1.mtx"), &g1);
    write_mtx(&dir.join("kg2.mtx"), &g2);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/modal_export.py");
    let name = "beam.modal.ron".to_string();
    let run = std::process::Command::new("python3")
        .arg(&script)
        .args(["--nodes", "nodes.csv", "--mass", "mass.mtx"])
        .args(["--stiffness", "stiffness.mtx", "--fix", "0:all"])
        .args(["--modes-kept", &MODES.to_string()])
        .args([
            "--geometric-centrifugal",
            "kg1.mtx",
            "--geometric-axial",
            "kg2.mtx",
        ])
        .args(["-o", &name])
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
    let modes = normal_modes(&b, &Reference::Clamped, MODES).unwrap();
    let sum = |r: usize, dof: usize| (0..b.nodes()).map(|j| m[(r, 6 * j + dof)]).sum::<f64>();
    let project = |g: &DMatrix<f64>| {
        let p = modes.shapes.transpose() * g * &modes.shapes;
        rows(&((&p + p.transpose()) * 0.5))
    };
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
        modes: (0..MODES)
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
        consistent: None,
        geometric_stiffness: Some(GeometricStiffness {
            centrifugal: project(&g1),
            axial: project(&g2),
        }),
    };
    let name = "beam.modal.json".to_string();
    std::fs::write(dir.join(&name), serde_json::to_string(&data).unwrap()).unwrap();
    (name, false)
}

/// One body `rod` on a revolute about z from ground: `flexible` as given.
fn model(flexible: &str) -> String {
    format!(
        r#"Model(
    name: "rod",
    gravity: (0, 0, -9.81),
    bodies: [(name: "rod", flexible: {flexible})],
    joints: [(name: "j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "rod",
              parent_frame: (position: (0.2, 0, 0), orientation: Rpy(0, 0.3, 0)))],
)"#
    )
}

fn beam_text(stiffening: bool) -> String {
    format!(
        "Beam(length: {L}, rho_a: {RHO_A}, rho_ip: {RHO_IP}, ea: {EA}, ei_y: {EI_Y}, \
         ei_z: {EI_Z}, gj: {GJ}, elements: {ELEMENTS}, reference: Clamped, modes: {MODES}, \
         stiffening: {stiffening})"
    )
}

fn system(dir: &Path, text: String) -> System {
    let path = dir.join("rod.ron");
    check(&Source::new(path.to_str().unwrap(), text))
        .unwrap_or_else(|r| panic!("{r}"))
        .system
}

fn rand(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// The exported beam's `K₁`, `K₂` are the beam's foreshortening matrices
/// (to the file's 17 significant digits and the sign of each mode), and
/// the imported body's stiffening adds to `M` and `b` what the stiffened
/// beam's adds, at random deformed, spinning and tilting states: those
/// terms depend only on `K₁`, `K₂` and the state.
#[test]
fn flex_imported_stiffening_equals_the_stiffened_beam() {
    let dir = scratch("equal");
    let (file, python) = export(&dir);
    eprintln!(
        "modal file written by {}",
        if python { "modal_export.py" } else { "Rust" }
    );
    let modal = |stiff: bool| format!("Modal(file: \"{file}\", stiffening: {stiff})");
    let (bs, b0, is, i0) = (
        system(&dir, model(&beam_text(true))),
        system(&dir, model(&beam_text(false))),
        system(&dir, model(&modal(true))),
        system(&dir, model(&modal(false))),
    );
    let (fb, fi) = (
        bs.bodies[1].flexible.as_deref().unwrap(),
        is.bodies[1].flexible.as_deref().unwrap(),
    );
    // Each imported mode is ± the beam's (a tie in "largest entry positive").
    let sign: Vec<f64> = (0..MODES)
        .map(|j| {
            let (a, b) = (fb.modes.shapes.column(j), fi.modes.shapes.column(j));
            let s = a.dot(&b).signum();
            let rel = (a * s - b).amax() / a.amax();
            assert!(rel < 1e-9, "mode {j}: shapes differ by {rel:e}");
            s
        })
        .collect();
    let (k1, k2) = fi.assumed_geometric_stiffness().expect("the file's block");
    let want = eom_gen::flex::invariants::foreshortening(&fb.beam, &fb.modes);
    for (what, got, want) in [("K₁", k1, &want.0), ("K₂", k2, &want.1)] {
        let top = want.amax();
        for r in 0..MODES {
            for c in 0..MODES {
                let w = sign[r] * sign[c] * want[(r, c)];
                assert!(
                    (got[(r, c)] - w).abs() <= 1e-10 * top,
                    "{what}[{r}][{c}]: file {}, beam {w}",
                    got[(r, c)]
                );
            }
        }
    }
    // And the geometric stiffness of the centrifugal load is K₁ (as the
    // beam's modal geometric stiffness under N₁).
    let kg1 =
        modal_geometric_stiffness(&fb.beam, &fb.modes, &|x| fb.beam.centrifugal_force(0.0, x));
    assert!((&kg1 - &want.0).amax() <= 1e-12 * kg1.amax());

    let nums = [&bs, &b0, &is, &i0].map(|s| Numeric::new(s).unwrap());
    let n = 1 + MODES;
    let mut seed = 41;
    for _ in 0..5 {
        let q: Vec<f64> = (0..n).map(|_| 0.05 * rand(&mut seed)).collect();
        let u: Vec<f64> = (0..n).map(|_| 3.0 * rand(&mut seed)).collect();
        let flip = |x: &[f64]| -> Vec<f64> {
            x.iter()
                .enumerate()
                .map(|(i, v)| if i == 0 { *v } else { v * sign[i - 1] })
                .collect()
        };
        let (qi, ui) = (flip(&q), flip(&u));
        let t: Vec<_> = nums
            .iter()
            .zip([(&q, &u), (&q, &u), (&qi, &ui), (&qi, &ui)])
            .map(|(num, (q, u))| num.terms(q, u, 0.0, &[]).unwrap())
            .collect();
        let s = |i: usize| if i == 0 { 1.0 } else { sign[i - 1] };
        let dm_beam: Vec<f64> = (0..n)
            .flat_map(|r| (0..n).map(move |c| (r, c)))
            .map(|(r, c)| t[0].mass_matrix[r][c] - t[1].mass_matrix[r][c])
            .collect();
        let dm_imp: Vec<f64> = (0..n)
            .flat_map(|r| (0..n).map(move |c| (r, c)))
            .map(|(r, c)| s(r) * s(c) * (t[2].mass_matrix[r][c] - t[3].mass_matrix[r][c]))
            .collect();
        let db_beam: Vec<f64> = (0..n).map(|r| t[0].bias[r] - t[1].bias[r]).collect();
        let db_imp: Vec<f64> = (0..n)
            .map(|r| s(r) * (t[2].bias[r] - t[3].bias[r]))
            .collect();
        for (what, got, want) in [("ΔM", &dm_imp, &dm_beam), ("Δb", &db_imp, &db_beam)] {
            let top = want.iter().map(|x| x.abs()).fold(0.0, f64::max);
            assert!(top > 0.0, "{what}: the stiffening adds nothing");
            for (k, (g, w)) in got.iter().zip(want.iter()).enumerate() {
                assert!(
                    (g - w).abs() <= 1e-9 * top,
                    "{what}[{k}]: imported {g}, beam {w} (of {top:e})"
                );
            }
        }
    }
}

/// `stiffening: true` on a modal body whose file has no
/// `geometric_stiffness` is an error at `stiffening`; a block of the wrong
/// size or not positive semi-definite is an error at its place in the file.
#[test]
fn flex_imported_stiffening_needs_a_valid_block() {
    let dir = scratch("errors");
    let (file, _) = export(&dir);
    let text = std::fs::read_to_string(dir.join(&file)).unwrap();
    let report = |modal: &str| {
        let path = dir.join("rod.ron");
        match check(&Source::new(path.to_str().unwrap(), model(modal))) {
            Ok(_) => "valid".to_string(),
            Err(r) => r.to_string(),
        }
    };
    // Without the block.
    let mut data: ModalData = if file.ends_with(".json") {
        serde_json::from_str(&text).unwrap()
    } else {
        eom_gen::flex::imported::parse(&file, &text).unwrap()
    };
    let good = data.geometric_stiffness.take().unwrap();
    std::fs::write(
        dir.join("plain.json"),
        serde_json::to_string(&data).unwrap(),
    )
    .unwrap();
    let r = report("Modal(file: \"plain.json\", stiffening: true)");
    assert!(
        r.contains("rod.ron:4:") && r.contains("has no `geometric_stiffness`"),
        "{r}"
    );
    // Wrong size, and softening (negative definite) data.
    let mut small = good.clone();
    small.centrifugal.pop();
    data.geometric_stiffness = Some(small);
    std::fs::write(
        dir.join("small.json"),
        serde_json::to_string_pretty(&data).unwrap(),
    )
    .unwrap();
    let r = report("Modal(file: \"small.json\", stiffening: true)");
    assert!(
        r.contains("small.json:") && r.contains("`geometric_stiffness.centrifugal` must be 4×4"),
        "{r}"
    );
    let mut negative = good;
    negative.axial = negative
        .axial
        .iter()
        .map(|row| row.iter().map(|x| -x).collect())
        .collect();
    data.geometric_stiffness = Some(negative);
    std::fs::write(
        dir.join("neg.json"),
        serde_json::to_string_pretty(&data).unwrap(),
    )
    .unwrap();
    let r = report("Modal(file: \"neg.json\", stiffening: true)");
    assert!(
        r.contains("neg.json:")
            && r.contains("`geometric_stiffness.axial` is not positive semi-definite"),
        "{r}"
    );
}
