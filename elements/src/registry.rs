//! The registry of element types: [`Element`] names every type this crate
//! has a kernel for, and [`with_element!`](crate::with_element) is the one
//! dispatch from an [`Element`] to its kernel type and sizes, so the sizes
//! are written once (in the dispatch arm, which the compiler checks against
//! the kernel's `ElementKernel<N, P>` implementation).

use crate::ElementKernel;
use std::fmt;

/// Runs `$body` with `$k` the kernel type of element `$e` and `$n`, `$p`
/// its coordinate and parameter counts as `const`s:
///
/// ```
/// use eom_elements::{Element, ElementKernel, with_element};
/// fn params<K: ElementKernel<N, P>, const N: usize, const P: usize>() -> usize { P }
/// let e = Element::Cable3D;
/// assert_eq!(with_element!(e, |K, N, P| params::<K, N, P>()), 6);
/// ```
#[macro_export]
macro_rules! with_element {
    ($e:expr, |$k:ident, $n:ident, $p:ident| $body:expr) => {
        match $e {
            $crate::Element::Cable2D => {
                #[allow(dead_code)]
                type $k = $crate::Cable2D;
                #[allow(dead_code)]
                const $n: usize = 8;
                #[allow(dead_code)]
                const $p: usize = 6;
                $body
            }
            $crate::Element::Cable2DGreen => {
                #[allow(dead_code)]
                type $k = $crate::Cable2DGreen;
                #[allow(dead_code)]
                const $n: usize = 8;
                #[allow(dead_code)]
                const $p: usize = 6;
                $body
            }
            $crate::Element::Cable3D => {
                #[allow(dead_code)]
                type $k = $crate::Cable3D;
                #[allow(dead_code)]
                const $n: usize = 12;
                #[allow(dead_code)]
                const $p: usize = 6;
                $body
            }
            $crate::Element::Beam2D => {
                #[allow(dead_code)]
                type $k = $crate::Beam2D;
                #[allow(dead_code)]
                const $n: usize = 12;
                #[allow(dead_code)]
                const $p: usize = 7;
                $body
            }
        }
    };
}

/// An element type with a kernel in this crate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Element {
    /// Planar ANCF cable, Gerstmayr–Irschik strain ([`crate::Cable2D`]).
    Cable2D,
    /// Planar ANCF cable, Green axial strain ([`crate::Cable2DGreen`]).
    Cable2DGreen,
    /// Spatial ANCF cable ([`crate::Cable3D`]).
    Cable3D,
    /// Planar fully parameterised ANCF beam ([`crate::Beam2D`]).
    Beam2D,
}

/// The name of an element type the registry does not have.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownElement(pub String);

impl fmt::Display for UnknownElement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "no element type `{}` (known: ", self.0)?;
        for (i, e) in Element::ALL.iter().enumerate() {
            let sep = if i == 0 { "" } else { ", " };
            write!(f, "{sep}`{}`", e.name())?;
        }
        f.write_str(")")
    }
}

impl std::error::Error for UnknownElement {}

fn name_of<K: ElementKernel<N, P>, const N: usize, const P: usize>() -> &'static str {
    K::NAME
}
fn params_of<K: ElementKernel<N, P>, const N: usize, const P: usize>() -> &'static [&'static str] {
    // `PARAMS` is an associated const array: promoted to 'static.
    &K::PARAMS
}
fn dim_of<K: ElementKernel<N, P>, const N: usize, const P: usize>() -> usize {
    K::DIM
}

impl Element {
    /// Every element type, in the registry's order.
    pub const ALL: [Element; 4] = [
        Element::Cable2D,
        Element::Cable2DGreen,
        Element::Cable3D,
        Element::Beam2D,
    ];

    /// The name models use (`"Cable2D"`, …): the kernel's `NAME`.
    pub fn name(self) -> &'static str {
        with_element!(self, |K, N, P| name_of::<K, N, P>())
    }

    /// The element type named `name`.
    pub fn from_name(name: &str) -> Result<Element, UnknownElement> {
        Element::ALL
            .into_iter()
            .find(|e| e.name() == name)
            .ok_or_else(|| UnknownElement(name.to_owned()))
    }

    /// Coordinates per element (two nodes).
    pub fn coords(self) -> usize {
        with_element!(self, |K, N, P| N)
    }

    /// Coordinates per node.
    pub fn node_coords(self) -> usize {
        self.coords() / 2
    }

    /// Parameters per element, in the kernel's order.
    pub fn params(self) -> &'static [&'static str] {
        with_element!(self, |K, N, P| params_of::<K, N, P>())
    }

    /// Dimension of positions: 2 (planar) or 3 (spatial).
    pub fn dim(self) -> usize {
        with_element!(self, |K, N, P| dim_of::<K, N, P>())
    }
}

impl fmt::Display for Element {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Element {
    type Err = UnknownElement;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Element::from_name(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every entry's sizes agree with its kernel's own constants, and the
    /// names are distinct and found again by `from_name`.
    #[test]
    fn registry_agrees_with_kernels() {
        for e in Element::ALL {
            assert_eq!(Element::from_name(e.name()), Ok(e), "{e}");
            assert_eq!(e.params().len(), with_element!(e, |K, N, P| P), "{e}");
            assert_eq!(e.node_coords() * 2, e.coords(), "{e}");
            assert!(matches!(e.dim(), 2 | 3), "{e}: dim {}", e.dim());
        }
        assert_eq!(
            Element::from_name("Cable4D").map_err(|e| e.to_string()),
            Err(
                "no element type `Cable4D` (known: `Cable2D`, `Cable2DGreen`, `Cable3D`, `Beam2D`)"
                    .to_owned()
            )
        );
    }
}
