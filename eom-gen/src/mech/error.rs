//! Why a system cannot be formulated ([`MechError`]), with the span in the
//! model file of what caused it.

use crate::diag::{Diagnostic, Span};
use std::fmt;

/// Why a system cannot be formulated, with the span in the model file of
/// what caused it.
#[derive(Clone, Debug, PartialEq)]
pub enum MechError {
    /// An expression uses a name with no value here.
    UnknownName {
        /// The name.
        name: String,
        /// The expression that uses it.
        span: Span,
    },
    /// A joint axis depends on a tunable parameter (axes are inlined).
    TunableAxis {
        /// The joint.
        joint: String,
        /// The axis component that uses a tunable parameter.
        span: Span,
    },
    /// A field of a flexible body that cannot follow a tunable parameter
    /// (the mesh, the shapes: the basis is built once; the modal damping
    /// of a basis that is not the beam's normal modes).
    TunableFlex {
        /// The body.
        body: String,
        /// The field as written (`length`, `shapes`, `damping`).
        field: &'static str,
        /// Why it must be fixed.
        why: &'static str,
        /// The field that uses a tunable parameter.
        span: Span,
    },
}

impl MechError {
    /// Where in the model file.
    pub fn span(&self) -> Span {
        match self {
            MechError::UnknownName { span, .. }
            | MechError::TunableAxis { span, .. }
            | MechError::TunableFlex { span, .. } => *span,
        }
    }

    /// What would be right.
    pub fn help(&self) -> &'static str {
        match self {
            MechError::UnknownName { .. } => {
                "this field may use parameters, and where the field allows them `t`, coordinates and speeds"
            }
            MechError::TunableAxis { .. } => {
                "make the parameters in the axis fixed (`tunable: false`, or `fixed` in a scene)"
            }
            MechError::TunableFlex {
                field: "damping", ..
            } => {
                "give `damping: 0`, or make the section data fixed (`tunable: false`, or `fixed` in a scene)"
            }
            MechError::TunableFlex {
                field: "section data of a Timoshenko beam",
                ..
            } => {
                "make the beam's parameters fixed (`tunable: false`, or `fixed` in a scene), or drop `shear` (an Euler–Bernoulli beam's section data may be tunable)"
            }
            MechError::TunableFlex { .. } => {
                "make this field's parameters fixed (`tunable: false`, or `fixed` in a scene); the section data `rho_a`, `rho_ip`, `ea`, `ei_y`, `ei_z`, `gj` and the `damping` ratio may be tunable"
            }
        }
    }

    /// The error as a diagnostic at its span.
    pub fn diagnostic(&self) -> Diagnostic {
        Diagnostic::error(self.span(), self.to_string()).with_help(self.help())
    }
}

impl fmt::Display for MechError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MechError::UnknownName { name, .. } => {
                write!(f, "`{name}` has no value in this expression")
            }
            MechError::TunableAxis { joint, .. } => write!(
                f,
                "the axis of joint `{joint}` depends on a tunable parameter; joint axes must be fixed"
            ),
            MechError::TunableFlex {
                body,
                field: "damping",
                why,
                ..
            } => write!(
                f,
                "the `damping` of flexible body `{body}` cannot be kept with tunable section data: {why}"
            ),
            MechError::TunableFlex {
                body, field, why, ..
            } => write!(
                f,
                "`{field}` of flexible body `{body}` depends on a tunable parameter: {why}"
            ),
        }
    }
}

impl std::error::Error for MechError {}
