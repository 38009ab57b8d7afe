//! Elements of absolute nodal coordinates (ANCF; Shabana ch. 7): the kernels
//! eom-gen derives symbolically once per element type and emits as
//! straight-line code (files beside this one, written by
//! `cargo run -p eom-gen --example regenerate`; do not edit them by hand),
//! and the interface the large-model runtime assembles them through.
//!
//! [`Element`] is the registry of element types: one entry per type, read
//! by the runtime (`eom_sim::large`, which builds chains by it) and the
//! command line. Adding an element type is its derivation in
//! `eom-gen/src/ancf/`, its generated file here, one arm in
//! [`with_element!`] and one variant of [`Element`].
//!
//! Sign convention: an element's equations are
//! `M q̈ + f_int(q, q̇) = f_ext`, with `f_int = ∂U/∂q + D(q) q̇` (elastic
//! force from the strain energy `U`, plus material damping).

/// `W` values of `f64` treated as one (from `eom-lanes`, which the
/// batched functions of generated models use too).
pub use eom_lanes::Lanes;

/// `v` as one lane (`W = 1`).
pub fn one_lane<const N: usize>(v: &[f64; N]) -> [Lanes<1>; N] {
    v.map(|x| Lanes([x]))
}

/// Lane `l` of `v`.
fn lane<const N: usize, const W: usize>(v: &[Lanes<W>; N], l: usize) -> [f64; N] {
    v.map(|x| x.0[l])
}

/// One element type's kernels. `N` coordinates per element (two nodes),
/// `P` parameters per element in the order of [`ElementKernel::PARAMS`].
///
/// The generated kernels implement every function, the `*_lanes` ones
/// generic in the lane count `W` (`W` elements at once, one per lane) and
/// the scalar ones as `W = 1`. A hand-written kernel needs only the
/// scalar functions: the lane functions then default to a loop over the
/// lanes, and the elastic ones to the full kernels at zero velocity (the
/// damping force `D(q) q̇` and its `q`-derivative vanish there).
pub trait ElementKernel<const N: usize, const P: usize> {
    /// Element type name as written in models (e.g. `"Cable2D"`).
    const NAME: &'static str;
    /// Coordinates per node (`N / 2`).
    const NODE_COORDS: usize;
    /// Dimension of positions (2 planar, 3 spatial).
    const DIM: usize;
    /// Names of the per-element parameters (e.g. `["L", "EA", "EI", "rhoA", "d_a", "d_b"]`).
    const PARAMS: [&'static str; P];
    /// Indices of the parameters only the material damping uses, if
    /// known: with all of them zero the element is undamped
    /// ([`ElementKernel::is_undamped`]). `None`: never treated as undamped.
    const DAMPING_PARAMS: Option<&'static [usize]> = None;
    /// `f_int = ∂U/∂q + D(q) q̇`.
    fn internal_forces(q: &[f64; N], qd: &[f64; N], p: &[f64; P], f: &mut [f64; N]);
    /// `∂f_int/∂q` (tangent stiffness, with the damping force's `q`
    /// dependence) into `k`, and `∂f_int/∂q̇` into `d`; `k[i][j] = ∂f_i/∂q_j`.
    fn internal_jacobians(
        q: &[f64; N],
        qd: &[f64; N],
        p: &[f64; P],
        k: &mut [[f64; N]; N],
        d: &mut [[f64; N]; N],
    );
    /// The constant consistent mass matrix (exact).
    fn mass(p: &[f64; P], m: &mut [[f64; N]; N]);
    /// Generalised force of a uniform load `w` per unit reference length
    /// (first `DIM` entries used; e.g. `w = ρA g` for gravity).
    fn uniform_load(p: &[f64; P], w: &[f64; 3], f: &mut [f64; N]);

    /// True if the damping parameters are known and all zero: then
    /// `f_int = ∂U/∂q`, `K = ∂²U/∂q²` and `D = 0`, and the elastic kernels
    /// suffice.
    fn is_undamped(p: &[f64; P]) -> bool {
        Self::DAMPING_PARAMS.is_some_and(|d| d.iter().all(|&i| p[i] == 0.0))
    }
    /// [`ElementKernel::internal_forces`] of `W` elements.
    fn forces_lanes<const W: usize>(
        q: &[Lanes<W>; N],
        qd: &[Lanes<W>; N],
        p: &[Lanes<W>; P],
        f: &mut [Lanes<W>; N],
    ) {
        for l in 0..W {
            let mut fl = [0.0; N];
            Self::internal_forces(&lane(q, l), &lane(qd, l), &lane(p, l), &mut fl);
            for (o, v) in f.iter_mut().zip(fl) {
                o.0[l] = v;
            }
        }
    }
    /// [`ElementKernel::internal_jacobians`] of `W` elements.
    fn jacobians_lanes<const W: usize>(
        q: &[Lanes<W>; N],
        qd: &[Lanes<W>; N],
        p: &[Lanes<W>; P],
        k: &mut [[Lanes<W>; N]; N],
        d: &mut [[Lanes<W>; N]; N],
    ) {
        for l in 0..W {
            let (mut kl, mut dl) = ([[0.0; N]; N], [[0.0; N]; N]);
            Self::internal_jacobians(&lane(q, l), &lane(qd, l), &lane(p, l), &mut kl, &mut dl);
            for i in 0..N {
                for j in 0..N {
                    k[i][j].0[l] = kl[i][j];
                    d[i][j].0[l] = dl[i][j];
                }
            }
        }
    }
    /// The elastic force `∂U/∂q` of `W` elements (no damping terms).
    fn elastic_forces_lanes<const W: usize>(
        q: &[Lanes<W>; N],
        p: &[Lanes<W>; P],
        f: &mut [Lanes<W>; N],
    ) {
        Self::forces_lanes(q, &[Lanes::default(); N], p, f);
    }
    /// The elastic stiffness `∂²U/∂q²` (symmetric; each distinct entry
    /// computed once in the generated kernels) of `W` elements.
    fn elastic_stiffness_lanes<const W: usize>(
        q: &[Lanes<W>; N],
        p: &[Lanes<W>; P],
        k: &mut [[Lanes<W>; N]; N],
    ) {
        let mut d = [[Lanes::default(); N]; N];
        Self::jacobians_lanes(q, &[Lanes::default(); N], p, k, &mut d);
    }
    /// The elastic force `∂U/∂q` (no damping terms).
    fn elastic_forces(q: &[f64; N], p: &[f64; P], f: &mut [f64; N]) {
        let mut out = [Lanes([0.0]); N];
        Self::elastic_forces_lanes(&one_lane(q), &one_lane(p), &mut out);
        *f = out.map(|x| x.0[0]);
    }
    /// The elastic stiffness `∂²U/∂q²` (symmetric).
    fn elastic_stiffness(q: &[f64; N], p: &[f64; P], k: &mut [[f64; N]; N]) {
        let mut kl = [[Lanes([0.0]); N]; N];
        Self::elastic_stiffness_lanes(&one_lane(q), &one_lane(p), &mut kl);
        *k = kl.map(|r| r.map(|x| x.0[0]));
    }
}

mod registry;
pub use registry::{Element, UnknownElement};

#[rustfmt::skip] // generated, formatted by prettyplease; stays byte-identical
pub mod cable2d;
#[rustfmt::skip]
pub mod cable2d_green;
#[rustfmt::skip]
pub mod cable3d;
#[rustfmt::skip]
pub mod beam2d;

pub use beam2d::Beam2D;
pub use cable2d::Cable2D;
pub use cable2d_green::Cable2DGreen;
pub use cable3d::Cable3D;
