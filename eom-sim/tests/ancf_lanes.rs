//! The lane (SIMD) and elastic variants of the generated ANCF kernels, and
//! the batched assembly of the large-model runtime, against the scalar
//! kernels they replace.
//!
//! Checked:
//! - a `W`-lane kernel gives, lane by lane, exactly (bit for bit: the same
//!   IEEE operations in the same order) what the scalar kernel gives for
//!   that lane's element;
//! - the elastic kernels are the full kernels without damping: at zero
//!   damping parameters `∂U/∂q` equals `f_int` and `∂²U/∂q²` equals `K`
//!   (to rounding: a different but equivalent sequence of operations), the
//!   elastic stiffness is symmetric (it is a Hessian), and
//!   `DAMPING_PARAMS` names exactly the damping parameters;
//! - the runtime's batched assembly (lanes, the elastic kernels where the
//!   group is undamped, padding of the last batch) gives the same forces
//!   and Jacobian as the element-by-element scalar path, for chains whose
//!   element count is not a multiple of the lane count, damped and not.

use eom_sim::elements::{Beam2D, Cable2D, Cable2DGreen, Cable3D, ElementKernel, Lanes};
use eom_sim::large::{Elements, ModelBuilder, SparseMatrix};

/// A deterministic pseudo-random sequence in [−1, 1].
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// Element `e`'s straight reference (length `l` along x; gradients the unit
/// tangent, and for the beam the unit normal) deformed by 5 %, with rates.
fn state<const N: usize>(dim: usize, l: f64, beam: bool, rng: &mut Rng) -> ([f64; N], [f64; N]) {
    let mut q = [0.0; N];
    let nc = N / 2;
    for node in 0..2 {
        let b = node * nc;
        q[b] = node as f64 * l;
        q[b + dim] = 1.0;
        if beam {
            q[b + 2 * dim + 1] = 1.0;
        }
    }
    let mut qd = [0.0; N];
    for k in 0..N {
        q[k] += 0.05 * rng.next();
        qd[k] = rng.next();
    }
    (q, qd)
}

fn max_abs(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |m, x| m.max(x.abs()))
}

fn check<const N: usize, const P: usize, E: ElementKernel<N, P>, const W: usize>(
    p: [f64; P],
    damping: &[&str],
) {
    let beam = E::NAME == "Beam2D";
    let mut rng = Rng(17);
    let states: Vec<([f64; N], [f64; N])> = (0..W)
        .map(|_| state::<N>(E::DIM, p[0], beam, &mut rng))
        .collect();
    // Lanes against scalar, bit for bit.
    let mut ql = [Lanes::<W>::default(); N];
    let mut qdl = [Lanes::<W>::default(); N];
    for (l, (q, qd)) in states.iter().enumerate() {
        for i in 0..N {
            ql[i].0[l] = q[i];
            qdl[i].0[l] = qd[i];
        }
    }
    let pl = p.map(Lanes::<W>::splat);
    let mut fl = [Lanes::<W>::default(); N];
    let mut kl = [[Lanes::<W>::default(); N]; N];
    let mut dl = [[Lanes::<W>::default(); N]; N];
    E::forces_lanes(&ql, &qdl, &pl, &mut fl);
    E::jacobians_lanes(&ql, &qdl, &pl, &mut kl, &mut dl);
    let mut efl = [Lanes::<W>::default(); N];
    let mut ekl = [[Lanes::<W>::default(); N]; N];
    E::elastic_forces_lanes(&ql, &pl, &mut efl);
    E::elastic_stiffness_lanes(&ql, &pl, &mut ekl);
    for (l, (q, qd)) in states.iter().enumerate() {
        let (mut f, mut k, mut d) = ([0.0; N], [[0.0; N]; N], [[0.0; N]; N]);
        E::internal_forces(q, qd, &p, &mut f);
        E::internal_jacobians(q, qd, &p, &mut k, &mut d);
        let (mut ef, mut ek) = ([0.0; N], [[0.0; N]; N]);
        E::elastic_forces(q, &p, &mut ef);
        E::elastic_stiffness(q, &p, &mut ek);
        for i in 0..N {
            assert_eq!(
                fl[i].0[l].to_bits(),
                f[i].to_bits(),
                "{} f[{i}] lane {l}",
                E::NAME
            );
            assert_eq!(
                efl[i].0[l].to_bits(),
                ef[i].to_bits(),
                "{} elastic f",
                E::NAME
            );
            for j in 0..N {
                assert_eq!(kl[i][j].0[l].to_bits(), k[i][j].to_bits(), "{} K", E::NAME);
                assert_eq!(dl[i][j].0[l].to_bits(), d[i][j].to_bits(), "{} D", E::NAME);
                assert_eq!(
                    ekl[i][j].0[l].to_bits(),
                    ek[i][j].to_bits(),
                    "{} elastic K",
                    E::NAME
                );
            }
        }
        // Elastic = full at zero damping; symmetric stiffness.
        let mut p0 = p;
        let Some(dp) = E::DAMPING_PARAMS else {
            panic!(
                "{}: generated kernels name their damping parameters",
                E::NAME
            );
        };
        let names: Vec<&str> = dp.iter().map(|&i| E::PARAMS[i]).collect();
        assert_eq!(names, damping, "{}", E::NAME);
        assert!(!E::is_undamped(&p), "{}", E::NAME);
        for &i in dp {
            p0[i] = 0.0;
        }
        assert!(E::is_undamped(&p0));
        E::internal_forces(q, qd, &p0, &mut f);
        E::internal_jacobians(q, qd, &p0, &mut k, &mut d);
        let fs = max_abs(f);
        let ks = max_abs(k.iter().flatten().copied());
        let df = max_abs(f.iter().zip(&ef).map(|(a, b)| a - b));
        let dk = max_abs(
            k.iter()
                .flatten()
                .zip(ek.iter().flatten())
                .map(|(a, b)| a - b),
        );
        let asym = max_abs(
            (0..N)
                .flat_map(|i| (0..N).map(move |j| (i, j)))
                .map(|(i, j)| ek[i][j] - ek[j][i]),
        );
        assert!(
            df <= 1e-11 * fs,
            "{}: elastic forces differ by {df:e} (scale {fs:e})",
            E::NAME
        );
        assert!(
            dk <= 1e-11 * ks,
            "{}: elastic K differs by {dk:e} (scale {ks:e})",
            E::NAME
        );
        assert!(
            asym <= 1e-12 * ks,
            "{}: elastic K asymmetric by {asym:e}",
            E::NAME
        );
        assert_eq!(
            max_abs(d.iter().flatten().copied()),
            0.0,
            "{}: D at zero damping",
            E::NAME
        );
    }
}

#[test]
fn lane_kernels_are_the_scalar_kernels_and_elastic_kernels_the_undamped_ones() {
    let (e, a, i) = (2.07e11, 0.01, 0.1f64.powi(4) / 12.0);
    let cable = [0.25, e * a, e * i, 7800.0 * a, 1e-3 * e * a, 1e-3 * e * i];
    let beam = [0.25, e, 0.3, 7800.0, 0.1, 0.1, 1e-3];
    check::<8, 6, Cable2D, 4>(cable, &["d_a", "d_b"]);
    check::<8, 6, Cable2D, 2>(cable, &["d_a", "d_b"]);
    check::<8, 6, Cable2D, 8>(cable, &["d_a", "d_b"]);
    check::<8, 6, Cable2DGreen, 4>(cable, &["d_a", "d_b"]);
    check::<12, 6, Cable3D, 4>(cable, &["d_a", "d_b"]);
    check::<12, 7, Beam2D, 4>(beam, &["mu"]);
}

/// The runtime's batched assembly against the scalar kernels element by
/// element, on a chain of `ne` elements (node-sharing, the first node
/// clamped), each with its own parameters, deformed and moving.
fn assembly_matches<const N: usize, const P: usize, E: ElementKernel<N, P> + 'static>(
    base: [f64; P],
    ne: usize,
    damped: bool,
) {
    let nc = N / 2;
    let beam = E::NAME == "Beam2D";
    let mut rng = Rng(5);
    let mut q0 = vec![0.0; (ne + 1) * nc];
    for node in 0..=ne {
        q0[node * nc] = node as f64 * base[0];
        q0[node * nc + E::DIM] = 1.0;
        if beam {
            q0[node * nc + 2 * E::DIM + 1] = 1.0;
        }
    }
    let mut els = Elements::<E, N, P>::new();
    let mut params = Vec::new();
    for e in 0..ne {
        let mut p = base;
        p[1] *= 1.0 + 0.1 * e as f64;
        if !damped {
            for &i in E::DAMPING_PARAMS.unwrap_or(&[]) {
                p[i] = 0.0;
            }
        }
        let conn: [usize; N] = std::array::from_fn(|i| e * nc + i);
        let reference: [f64; N] = std::array::from_fn(|i| q0[e * nc + i]);
        els.push(conn, p, reference);
        params.push((conn, p));
    }
    let mut b = ModelBuilder::new(q0.clone()).elements(els);
    for k in 0..nc {
        b = b.fix(k);
    }
    let m = b.build();
    let mut q = q0.clone();
    let mut qd = vec![0.0; q.len()];
    for (x, v) in q.iter_mut().zip(qd.iter_mut()) {
        *x += 0.02 * rng.next();
        *v = rng.next();
    }
    for moving in [true, false] {
        let qdv = if moving {
            qd.clone()
        } else {
            vec![0.0; q.len()]
        };
        let mut scratch = vec![0.0; q.len()];
        let mut out = vec![0.0; m.n_free()];
        m.internal(&q, &qdv, &mut scratch, &mut out);
        let (a, bb, cm) = (0.7, if moving { 0.3 } else { 0.0 }, 1.1);
        let mut jac = SparseMatrix::zeros(m.pattern().clone());
        m.jacobian(&q, &qdv, a, bb, cm, &mut jac);
        // Reference: scalar full kernels, element by element.
        let mut f = vec![0.0; q.len()];
        let mut reference = SparseMatrix::zeros(m.pattern().clone());
        for (conn, p) in &params {
            let qe: [f64; N] = std::array::from_fn(|i| q[conn[i]]);
            let qde: [f64; N] = std::array::from_fn(|i| qdv[conn[i]]);
            let (mut fe, mut k, mut d) = ([0.0; N], [[0.0; N]; N], [[0.0; N]; N]);
            E::internal_forces(&qe, &qde, p, &mut fe);
            E::internal_jacobians(&qe, &qde, p, &mut k, &mut d);
            for i in 0..N {
                f[conn[i]] += fe[i];
                for j in 0..N {
                    if let (Some(fi), Some(fj)) = (m.free_index(conn[i]), m.free_index(conn[j])) {
                        let s = m.pattern().slot(fi, fj).unwrap_or_else(|| panic!("slot"));
                        reference.values[s] += a * k[i][j] + bb * d[i][j];
                    }
                }
            }
        }
        for (r, mv) in reference.values.iter_mut().zip(&m.mass().values) {
            *r += cm * mv;
        }
        let fr = m.restrict(&f);
        let scale = max_abs(fr.iter().copied());
        let diff = max_abs(out.iter().zip(&fr).map(|(x, y)| x - y));
        let what = format!("{} ne {ne} damped {damped} moving {moving}", E::NAME);
        assert!(
            diff <= 1e-11 * scale,
            "{what}: forces {diff:e} of {scale:e}"
        );
        let scale = max_abs(reference.values.iter().copied());
        let diff = max_abs(jac.values.iter().zip(&reference.values).map(|(x, y)| x - y));
        assert!(
            diff <= 1e-11 * scale,
            "{what}: Jacobian {diff:e} of {scale:e}"
        );
    }
}

#[test]
fn batched_assembly_is_the_element_by_element_assembly() {
    let (e, a, i) = (2.07e11, 0.01, 0.1f64.powi(4) / 12.0);
    let cable = [0.25, e * a, e * i, 7800.0 * a, 1e-3 * e * a, 1e-3 * e * i];
    let beam = [0.25, e, 0.3, 7800.0, 0.1, 0.1, 1e-3];
    for ne in [1, 2, 5, 7, 8] {
        for damped in [true, false] {
            assembly_matches::<8, 6, Cable2D>(cable, ne, damped);
            assembly_matches::<12, 7, Beam2D>(beam, ne, damped);
        }
    }
}
