//! Tunable section data of flexible bodies: the reduced matrices as
//! expressions of the runtime parameters.
//!
//! The basis (the beam's modes, the assumed shapes) is built once, at the
//! defaults. For that fixed basis every reduced matrix is linear in the
//! section data ([`crate::flex::invariants::Shares`]): the translational
//! integrals in `ρA`, the torsion inertia's in `ρI_p`, `K_ff` a sum over
//! `EA`, `EI_y`, `EI_z`, `GJ`. A datum `p` whose field uses a tunable
//! parameter enters as `(v/p₀) p`, `v` the share's value at the default
//! `p₀`; fixed data stay inlined constants, and zeros stay zeros. The model
//! is then exactly the Ritz model of the kept shapes at the runtime values.
//!
//! For the built-in beam's normal modes this is more: a straight uniform
//! beam's axial, two bending and torsion deformations decouple, and each
//! block's mode shapes do not depend on the scale of its stiffness and
//! mass, so (the modes being kept pure per block, see
//! [`crate::flex::modes`]) the kept shapes stay the beam's normal modes at
//! any positive values: `M_ff` and `K_ff` stay diagonal, the frequencies
//! scale as `√(stiffness/mass)` of their block. Which modes are kept is
//! decided at the defaults; if at run time another block's mode would be
//! lower, the model still holds the kept ones exactly but not the lowest.
//!
//! Not tunable (a located error): the length (the mesh, the nodes, the
//! quadrature interval), a named node's `x`, the shape expressions of
//! assumed modes, and a
//! damping ratio on a basis that is not the beam's normal modes
//! (Craig–Bampton, assumed modes: their modal damping needs the normal
//! modes of the reduced body, which change with the data).

use super::error::MechError;
use super::lower::Lowering;
use crate::sym::Scalar;
use crate::system::{FlexInfo, FlexSource};

/// The section data in the order of [`FlexInfo::written`] after the length.
pub const RHO_A: usize = 0;
/// `ρI_p`.
pub const RHO_IP: usize = 1;
/// `EA`.
pub const EA: usize = 2;
/// `EI_y`.
pub const EI_Y: usize = 3;
/// `EI_z`.
pub const EI_Z: usize = 4;
/// `GJ`.
pub const GJ: usize = 5;

/// How each section datum of a flexible body enters its constants.
#[derive(Clone, Debug)]
pub struct SectionScales<S> {
    /// Per datum, the written field as a scalar and its default, where it
    /// uses a tunable parameter.
    tunable: [Option<(S, f64)>; 6],
    /// Every datum as a scalar (the default where fixed).
    pub values: [S; 6],
}

impl<S: Scalar> SectionScales<S> {
    /// The section data of `flex` on body `body`; errors for the fields
    /// that may not be tunable (length, shapes).
    pub fn new(flex: &FlexInfo, body: &str, low: &Lowering<'_, S>) -> Result<Self, MechError> {
        let refuse = |field, why, span| MechError::TunableFlex {
            body: body.to_string(),
            field,
            why,
            span,
        };
        if let Some(length) = flex.written.first()
            && low.uses_tunable(&length.expr)
        {
            return Err(refuse(
                "length",
                "the finite-element mesh (or the interval the shapes are integrated over) and the nodes are built from it once",
                length.span,
            ));
        }
        if flex.beam.shear.is_some()
            && let Some(q) = flex.written.iter().find(|q| low.uses_tunable(&q.expr))
        {
            return Err(refuse(
                "section data of a Timoshenko beam",
                "the element's shape functions depend on EI/κGA, so the data are fixed at generation",
                q.span,
            ));
        }
        if let Some(q) = flex
            .written
            .iter()
            .skip(7)
            .find(|q| low.uses_tunable(&q.expr))
        {
            return Err(match flex.source {
                FlexSource::Assumed { .. } => refuse(
                    "shapes",
                    "the shape functions are integrated once, at the defaults",
                    q.span,
                ),
                _ => refuse(
                    "nodes",
                    "a node sits at a finite-element node of the mesh built at the defaults",
                    q.span,
                ),
            });
        }
        let b = &flex.beam;
        let defaults = [b.rho_a, b.rho_ip, b.ea, b.ei_y, b.ei_z, b.gj];
        let mut tunable: [Option<(S, f64)>; 6] = std::array::from_fn(|_| None);
        let mut values: [S; 6] = defaults.map(S::from_f64);
        for (d, q) in flex.written.iter().skip(1).take(6).enumerate() {
            if low.uses_tunable(&q.expr) {
                let v = low.quantity(q)?;
                tunable[d] = Some((v, q.value));
                values[d] = v;
            }
        }
        Ok(SectionScales { tunable, values })
    }

    /// Whether any datum is tunable.
    pub fn any(&self) -> bool {
        self.tunable.iter().any(Option::is_some)
    }

    /// Whether datum `d` is tunable.
    pub fn is_tunable(&self, d: usize) -> bool {
        self.tunable[d].is_some()
    }

    /// A share `v` (at the defaults) of datum `d`: `v` if fixed, else
    /// `(v/p₀) p`; zero stays zero.
    pub fn scale(&self, d: usize, v: f64) -> S {
        match &self.tunable[d] {
            _ if v == 0.0 => S::zero(),
            None => S::from_f64(v),
            Some((p, p0)) => S::from_f64(v / p0) * *p,
        }
    }

    /// An entry whose value at the defaults is `total` and whose shares
    /// are `parts` (datum, value), all cleaned by `clean` (which makes
    /// round-off an exact zero): the inlined `clean(total)` when no part is
    /// tunable, else the sum of the scaled parts.
    pub fn entry(&self, total: f64, parts: &[(usize, f64)], clean: &dyn Fn(f64) -> f64) -> S {
        if !parts.iter().any(|&(d, _)| self.is_tunable(d)) {
            return S::from_f64(clean(total));
        }
        if clean(total) == 0.0 {
            return S::zero();
        }
        parts
            .iter()
            .map(|&(d, v)| self.scale(d, clean(v)))
            .filter(|x| !x.is_zero())
            .fold(S::zero(), |acc, x| if acc.is_zero() { x } else { acc + x })
    }
}
