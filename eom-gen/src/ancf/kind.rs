//! The ANCF element types: the one list that the model format
//! (`cables: [(element: …)]`), validation, the derivation in `ancf` and the
//! generated kernels' files read. A new element type is one variant here,
//! its arms in [`Kind::name`] and [`Kind::dim`], and its derivation in
//! `ancf::define`.

use serde::{Deserialize, Serialize};

/// An element type (the kernels generated once per type).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Kind {
    /// Planar cable, axial strain `|r'| − 1` and material curvature
    /// (Gerstmayr and Irschik 2008).
    Cable2D,
    /// Planar cable, Green axial strain and the polynomial curvature `r' × r''`.
    Cable2DGreen,
    /// Spatial cable, axial strain and curvature, no torsion.
    Cable3D,
    /// Planar fully parameterised beam (continuum Green–Lagrange strain).
    Beam2D,
}

impl Kind {
    /// Every element type, in the order the files are written.
    pub const ALL: [Kind; 4] = [
        Kind::Cable2D,
        Kind::Cable2DGreen,
        Kind::Cable3D,
        Kind::Beam2D,
    ];

    /// The type's name, as written in models and of the generated kernel.
    pub fn name(&self) -> &'static str {
        match self {
            Kind::Cable2D => "Cable2D",
            Kind::Cable2DGreen => "Cable2DGreen",
            Kind::Cable3D => "Cable3D",
            Kind::Beam2D => "Beam2D",
        }
    }

    /// Dimension of positions (2: planar, in the `x`–`y` plane; 3).
    pub fn dim(&self) -> usize {
        match self {
            Kind::Cable2D | Kind::Cable2DGreen | Kind::Beam2D => 2,
            Kind::Cable3D => 3,
        }
    }

    /// The element type named `name`.
    pub fn from_name(name: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| k.name() == name)
    }
}
