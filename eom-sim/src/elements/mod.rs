//! Elements of absolute nodal coordinates (ANCF; Shabana ch. 7): the kernels
//! eom-gen derives symbolically once per element type and emits as
//! straight-line code (files beside this one, written by
//! `cargo run -p eom-gen --example regenerate`; do not edit them by hand),
//! and the interface the large-model runtime assembles them through.
//!
//! Sign convention: an element's equations are
//! `M q̈ + f_int(q, q̇) = f_ext`, with `f_int = ∂U/∂q + D(q) q̇` (elastic
//! force from the strain energy `U`, plus material damping).

/// One element type's generated kernels. `N` coordinates per element (two
/// nodes), `P` parameters per element in the order of [`ElementKernel::PARAMS`].
pub trait ElementKernel<const N: usize, const P: usize> {
    /// Element type name as written in models (e.g. `"Cable2D"`).
    const NAME: &'static str;
    /// Coordinates per node (`N / 2`).
    const NODE_COORDS: usize;
    /// Dimension of positions (2 planar, 3 spatial).
    const DIM: usize;
    /// Names of the per-element parameters (e.g. `["L", "EA", "EI", "rhoA", "d_a", "d_b"]`).
    const PARAMS: [&'static str; P];
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
}

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
