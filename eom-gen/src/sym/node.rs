//! Node ids, the stored node enum, the borrowed [`View`] of a node, and
//! symbols (the leaves that are variables).

use super::num::Num;
use std::hash::{Hash, Hasher};

/// Index of a node in an [`Arena`](super::Arena). Children always have
/// smaller ids than their parents, so ascending id order is a topological
/// order.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct Id(pub(crate) u32);

impl Id {
    /// The position of the node in the arena.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Index of a [`Symbol`] in an arena's symbol table.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct SymId(pub(crate) u32);

impl SymId {
    /// The position of the symbol in the arena's symbol table.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a variable stands for.
///
/// Coordinates, speeds and their rates carry the index the caller gave them;
/// the printed name is derived from it (`q3`, `u3`, `qd3`, `ud3`).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum SymKind {
    /// A tunable model parameter (fixed parameters are inlined as constants by the caller).
    Param,
    /// An external input (actuator command, force); constant in time unless a rate is given.
    Input,
    /// Time `t`.
    Time,
    /// Generalised coordinate `q_i`.
    Coord(u32),
    /// Generalised speed `u_i`.
    Speed(u32),
    /// Coordinate rate `q̇_i` (printed `qd_i`).
    CoordRate(u32),
    /// Speed rate `u̇_i` (printed `ud_i`).
    SpeedRate(u32),
    /// Extra generalised force `τ_i` on speed `i` (printed `tau_i`).
    Tau(u32),
    /// Constraint multiplier `λ_i` (printed `λ_i`).
    Multiplier(u32),
}

impl std::fmt::Display for SymKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SymKind::Param => write!(f, "parameter"),
            SymKind::Input => write!(f, "input"),
            SymKind::Time => write!(f, "time"),
            SymKind::Coord(i) => write!(f, "coordinate q{i}"),
            SymKind::Speed(i) => write!(f, "speed u{i}"),
            SymKind::CoordRate(i) => write!(f, "coordinate rate qd{i}"),
            SymKind::SpeedRate(i) => write!(f, "speed rate ud{i}"),
            SymKind::Tau(i) => write!(f, "generalised force tau{i}"),
            SymKind::Multiplier(i) => write!(f, "multiplier λ{i}"),
        }
    }
}

/// A named variable: a leaf of the expression graph.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub struct Symbol {
    /// What the variable stands for.
    pub kind: SymKind,
    /// Its printed name (unique within an arena).
    pub name: String,
}

impl Symbol {
    /// The conventional name of an indexed kind (`q3`, `ud0`, `t`); `None`
    /// for parameters and inputs, which are named by the caller.
    pub fn conventional_name(kind: SymKind) -> Option<String> {
        match kind {
            SymKind::Param | SymKind::Input => None,
            SymKind::Time => Some("t".into()),
            SymKind::Coord(i) => Some(format!("q{i}")),
            SymKind::Speed(i) => Some(format!("u{i}")),
            SymKind::CoordRate(i) => Some(format!("qd{i}")),
            SymKind::SpeedRate(i) => Some(format!("ud{i}")),
            SymKind::Tau(i) => Some(format!("tau{i}")),
            SymKind::Multiplier(i) => Some(format!("λ{i}")),
        }
    }

    /// The kind implied by a name under the naming convention: `t`, `q<i>`,
    /// `u<i>`, `qd<i>`, `ud<i>`, `tau<i>`, `λ<i>`; anything else is a
    /// parameter.
    pub fn kind_from_name(name: &str) -> SymKind {
        let idx = |prefix: &str| -> Option<u32> {
            let rest = name.strip_prefix(prefix)?;
            if rest.is_empty() || !rest.bytes().all(|b| b.is_ascii_digit()) {
                return None;
            }
            if rest.len() > 1 && rest.starts_with('0') {
                return None;
            }
            rest.parse().ok()
        };
        if name == "t" {
            SymKind::Time
        } else if let Some(i) = idx("qd") {
            SymKind::CoordRate(i)
        } else if let Some(i) = idx("ud") {
            SymKind::SpeedRate(i)
        } else if let Some(i) = idx("q") {
            SymKind::Coord(i)
        } else if let Some(i) = idx("u") {
            SymKind::Speed(i)
        } else if let Some(i) = idx("tau") {
            SymKind::Tau(i)
        } else if let Some(i) = idx("λ") {
            SymKind::Multiplier(i)
        } else {
            SymKind::Param
        }
    }
}

/// A stored node: 12 bytes. Sums and products keep their children in the
/// arena's side vector as `(start, len)`, a select its three children at
/// `start`; a float constant is an index into the arena's float vector.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Node {
    Rat(i32, i32),
    Float(u32),
    Sym(SymId),
    Add(u32, u32),
    Mul(u32, u32),
    Pow(Id, i32),
    Sqrt(Id),
    Sin(Id),
    Cos(Id),
    Tan(Id),
    Exp(Id),
    Ln(Id),
    Abs(Id),
    Atan2(Id, Id),
    Select(u32),
}

/// A borrowed, structural view of a node, as returned by
/// [`Arena::view`](super::Arena::view).
///
/// Semantics: `Add` is the n-ary sum and `Mul` the n-ary product of their
/// children; `Pow(x, n)` is `x^n` for an integer `n` (so `x/y` is
/// `(* x (^ y -1))` and `-x` is `(* -1 x)`); `Select(c, a, b)` is
/// `if c > 0 { a } else { b }`; `Atan2(y, x)` is the four-quadrant arctangent.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub enum View<'a> {
    /// A numeric constant.
    Num(Num),
    /// A variable.
    Sym(SymId),
    /// n-ary sum (at least two children, canonically ordered).
    Add(&'a [Id]),
    /// n-ary product (at least two children, constant coefficient first).
    Mul(&'a [Id]),
    /// Integer power `x^n`.
    Pow(Id, i32),
    /// Square root.
    Sqrt(Id),
    /// Sine.
    Sin(Id),
    /// Cosine.
    Cos(Id),
    /// Tangent.
    Tan(Id),
    /// Exponential.
    Exp(Id),
    /// Natural logarithm.
    Ln(Id),
    /// Absolute value.
    Abs(Id),
    /// `atan2(y, x)`.
    Atan2(Id, Id),
    /// `if c > 0 { a } else { b }`.
    Select(Id, Id, Id),
}

impl Hash for Num {
    fn hash<H: Hasher>(&self, state: &mut H) {
        match *self {
            Num::Rat(p, q) => {
                0u8.hash(state);
                p.hash(state);
                q.hash(state);
            }
            Num::Float(x) => {
                1u8.hash(state);
                x.to_bits().hash(state);
            }
        }
    }
}

impl<'a> View<'a> {
    /// The direct children of the node, in order.
    pub fn children(&self) -> ChildIter<'a> {
        let (small, slice): ([Option<Id>; 3], &'a [Id]) = match *self {
            View::Num(_) | View::Sym(_) => ([None; 3], &[]),
            View::Add(s) | View::Mul(s) => ([None; 3], s),
            View::Pow(a, _)
            | View::Sqrt(a)
            | View::Sin(a)
            | View::Cos(a)
            | View::Tan(a)
            | View::Exp(a)
            | View::Ln(a)
            | View::Abs(a) => ([Some(a), None, None], &[]),
            View::Atan2(a, b) => ([Some(a), Some(b), None], &[]),
            View::Select(a, b, c) => ([Some(a), Some(b), Some(c)], &[]),
        };
        ChildIter {
            small,
            pos: 0,
            slice,
        }
    }

    /// The constant, if this is one.
    pub fn num(&self) -> Option<Num> {
        match *self {
            View::Num(n) => Some(n),
            _ => None,
        }
    }
}

/// Iterator over the children of a [`View`].
pub struct ChildIter<'a> {
    small: [Option<Id>; 3],
    pos: usize,
    slice: &'a [Id],
}

impl Iterator for ChildIter<'_> {
    type Item = Id;
    fn next(&mut self) -> Option<Id> {
        if self.pos < 3 {
            if let Some(id) = self.small[self.pos] {
                self.pos += 1;
                return Some(id);
            }
            self.pos = 3;
        }
        let (first, rest) = self.slice.split_first()?;
        self.slice = rest;
        Some(*first)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_is_12_bytes() {
        let got = std::mem::size_of::<Node>();
        assert!(got <= 12, "got {got} bytes want <= 12");
    }

    #[test]
    fn naming_convention() {
        assert_eq!(Symbol::kind_from_name("q12"), SymKind::Coord(12));
        assert_eq!(Symbol::kind_from_name("qd0"), SymKind::CoordRate(0));
        assert_eq!(Symbol::kind_from_name("u3"), SymKind::Speed(3));
        assert_eq!(Symbol::kind_from_name("ud3"), SymKind::SpeedRate(3));
        assert_eq!(Symbol::kind_from_name("t"), SymKind::Time);
        assert_eq!(Symbol::kind_from_name("q01"), SymKind::Param);
        assert_eq!(Symbol::kind_from_name("l"), SymKind::Param);
        assert_eq!(Symbol::kind_from_name("qx"), SymKind::Param);
    }
}
