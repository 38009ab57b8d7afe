//! S-expressions: printing and parsing, so tests read as text.
//!
//! Grammar: an atom is a number (`3`, `-1/2`, `0.25`, `1e-7`, `inf`, `NaN`)
//! or a symbol name; a list is `(op arg…)` with
//! `+ * - / ^ sqrt sin cos tan atan2 exp ln abs select`.
//! `(- a)` is negation, `(- a b c)` is `a − b − c`; `(/ a)` is `1/a`,
//! `(/ a b)` is `a/b`; `(^ x n)` needs an integer `n`;
//! `(select c a b)` is `if c > 0 { a } else { b }`.
//!
//! Printing is faithful to the stored (canonical) form: `a − b` prints as
//! `(+ a (* -1 b))`. Parsing goes through the smart constructors, so parsing
//! a printed expression into an arena with the same rules gives the same
//! node. Printing expands the DAG into a tree (exponential in the worst
//! case): it is meant for tests and small expressions.

use super::arena::{Arena, SymError};
use super::node::{Id, View};
use super::num::Num;
use std::fmt;
use std::str::FromStr;

/// A parsed s-expression tree, independent of any arena.
#[derive(Clone, PartialEq, Eq, Debug)]
pub enum SExpr {
    /// A number or a name, with its byte offset in the source.
    Atom(String, usize),
    /// A parenthesised list, with the byte offset of its `(`.
    List(Vec<SExpr>, usize),
}

impl SExpr {
    fn offset(&self) -> usize {
        match self {
            SExpr::Atom(_, o) | SExpr::List(_, o) => *o,
        }
    }
}

impl fmt::Display for SExpr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SExpr::Atom(s, _) => f.write_str(s),
            SExpr::List(xs, _) => {
                f.write_str("(")?;
                for (i, x) in xs.iter().enumerate() {
                    if i > 0 {
                        f.write_str(" ")?;
                    }
                    write!(f, "{x}")?;
                }
                f.write_str(")")
            }
        }
    }
}

/// Deepest nesting the parser accepts (building and dropping the tree recurse).
pub const MAX_DEPTH: usize = 1000;

fn perr(offset: usize, message: impl Into<String>) -> SymError {
    SymError::Parse {
        offset,
        message: message.into(),
    }
}

impl FromStr for SExpr {
    type Err = SymError;
    fn from_str(s: &str) -> Result<SExpr, SymError> {
        let bytes = s.as_bytes();
        let mut stack: Vec<(Vec<SExpr>, usize)> = Vec::new();
        let mut done: Option<SExpr> = None;
        let mut i = 0;
        while i < bytes.len() {
            let c = bytes[i];
            if c.is_ascii_whitespace() {
                i += 1;
                continue;
            }
            if done.is_some() {
                return Err(perr(i, "unexpected text after the expression"));
            }
            let item = match c {
                b'(' => {
                    if stack.len() >= MAX_DEPTH {
                        return Err(perr(i, format!("nested deeper than {MAX_DEPTH} levels")));
                    }
                    stack.push((Vec::new(), i));
                    i += 1;
                    continue;
                }
                b')' => {
                    let (xs, o) = stack.pop().ok_or_else(|| perr(i, "unmatched `)`"))?;
                    i += 1;
                    if xs.is_empty() {
                        return Err(perr(o, "empty list `()`"));
                    }
                    SExpr::List(xs, o)
                }
                _ => {
                    let start = i;
                    while i < bytes.len()
                        && !bytes[i].is_ascii_whitespace()
                        && bytes[i] != b'('
                        && bytes[i] != b')'
                    {
                        i += 1;
                    }
                    SExpr::Atom(s[start..i].to_string(), start)
                }
            };
            match stack.last_mut() {
                Some((xs, _)) => xs.push(item),
                None => done = Some(item),
            }
        }
        if let Some((_, o)) = stack.last() {
            return Err(perr(*o, "unclosed `(`"));
        }
        done.ok_or_else(|| perr(0, "empty input"))
    }
}

/// Parse a number atom: `3`, `-1/2`, `0.25`, `1e-7`, `inf`, `-inf`, `NaN`.
pub(crate) fn parse_num(s: &str) -> Option<Num> {
    if let Some((p, q)) = s.split_once('/') {
        let (p, q): (i64, i64) = (p.parse().ok()?, q.parse().ok()?);
        return Num::ratio(p, q);
    }
    let first = s.bytes().next()?;
    let numeric = first.is_ascii_digit()
        || ((first == b'-' || first == b'+' || first == b'.') && s.len() > 1)
        || matches!(s, "inf" | "NaN");
    if !numeric {
        return None;
    }
    s.parse::<f64>().ok().map(Num::from_f64)
}

impl Arena {
    /// Parse an s-expression and build it with this arena's smart
    /// constructors. Unknown names become symbols by the naming convention
    /// (see [`Arena::sym_named`]).
    pub fn parse(&mut self, s: &str) -> Result<Id, SymError> {
        let e: SExpr = s.parse()?;
        self.from_sexpr(&e)
    }

    /// Build an [`SExpr`] in this arena.
    pub fn from_sexpr(&mut self, e: &SExpr) -> Result<Id, SymError> {
        match e {
            SExpr::Atom(a, o) => {
                if let Some(n) = parse_num(a) {
                    return Ok(self.num_node(n));
                }
                if a.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+') {
                    return Err(perr(*o, format!("`{a}` is not a number")));
                }
                self.sym_named(a).map_err(|err| perr(*o, err.to_string()))
            }
            SExpr::List(xs, o) => {
                let SExpr::Atom(op, _) = &xs[0] else {
                    return Err(perr(*o, "a list must start with an operator"));
                };
                let rest = &xs[1..];
                let arity = |n: usize| -> Result<(), SymError> {
                    if rest.len() == n {
                        Ok(())
                    } else {
                        Err(perr(
                            *o,
                            format!("`{op}` takes {n} argument(s), got {}", rest.len()),
                        ))
                    }
                };
                if op == "^" {
                    arity(2)?;
                    let SExpr::Atom(n, no) = &rest[1] else {
                        return Err(perr(
                            rest[1].offset(),
                            "exponent must be an integer literal",
                        ));
                    };
                    let n: i32 = n
                        .parse()
                        .map_err(|_| perr(*no, format!("exponent `{n}` is not an integer")))?;
                    let b = self.from_sexpr(&rest[0])?;
                    return Ok(self.pow(b, n));
                }
                let args = rest
                    .iter()
                    .map(|x| self.from_sexpr(x))
                    .collect::<Result<Vec<Id>, _>>()?;
                let unary =
                    |arena: &mut Arena, f: fn(&mut Arena, Id) -> Id| -> Result<Id, SymError> {
                        arity(1)?;
                        Ok(f(arena, args[0]))
                    };
                match op.as_str() {
                    "+" if !args.is_empty() => Ok(self.add(&args)),
                    "*" if !args.is_empty() => Ok(self.mul(&args)),
                    "-" if args.len() == 1 => Ok(self.neg(args[0])),
                    "-" if args.len() > 1 => {
                        let mut terms = vec![args[0]];
                        for &a in &args[1..] {
                            terms.push(self.neg(a));
                        }
                        Ok(self.add(&terms))
                    }
                    "/" if args.len() == 1 => Ok(self.recip(args[0])),
                    "/" if args.len() > 1 => {
                        let mut fs = vec![args[0]];
                        for &a in &args[1..] {
                            fs.push(self.recip(a));
                        }
                        Ok(self.mul(&fs))
                    }
                    "sqrt" => unary(self, Arena::sqrt),
                    "sin" => unary(self, Arena::sin),
                    "cos" => unary(self, Arena::cos),
                    "tan" => unary(self, Arena::tan),
                    "exp" => unary(self, Arena::exp),
                    "ln" => unary(self, Arena::ln),
                    "abs" => unary(self, Arena::abs),
                    "atan2" => {
                        arity(2)?;
                        Ok(self.atan2(args[0], args[1]))
                    }
                    "select" => {
                        arity(3)?;
                        Ok(self.select(args[0], args[1], args[2]))
                    }
                    "+" | "*" | "-" | "/" => {
                        Err(perr(*o, format!("`{op}` needs at least one argument")))
                    }
                    _ => Err(perr(*o, format!("unknown operator `{op}`"))),
                }
            }
        }
    }

    /// A printable s-expression view of node `id`.
    pub fn display(&self, id: Id) -> Display<'_> {
        Display { arena: self, id }
    }

    /// The s-expression text of node `id`.
    pub fn to_sexpr_string(&self, id: Id) -> String {
        self.display(id).to_string()
    }
}

/// Prints a node as an s-expression; see [`Arena::display`].
pub struct Display<'a> {
    arena: &'a Arena,
    id: Id,
}

impl Display<'_> {
    fn write(&self, id: Id, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.arena;
        let list = |f: &mut fmt::Formatter<'_>, op: &str, cs: &[Id]| -> fmt::Result {
            write!(f, "({op}")?;
            for &c in cs {
                f.write_str(" ")?;
                self.write(c, f)?;
            }
            f.write_str(")")
        };
        match a.view(id) {
            View::Num(n) => write!(f, "{n}"),
            View::Sym(s) => f.write_str(&a.symbol(s).name),
            View::Add(cs) => list(f, "+", cs),
            View::Mul(cs) => list(f, "*", cs),
            View::Pow(x, n) => {
                f.write_str("(^ ")?;
                self.write(x, f)?;
                write!(f, " {n})")
            }
            View::Sqrt(x) => list(f, "sqrt", &[x]),
            View::Sin(x) => list(f, "sin", &[x]),
            View::Cos(x) => list(f, "cos", &[x]),
            View::Tan(x) => list(f, "tan", &[x]),
            View::Exp(x) => list(f, "exp", &[x]),
            View::Ln(x) => list(f, "ln", &[x]),
            View::Abs(x) => list(f, "abs", &[x]),
            View::Atan2(y, x) => list(f, "atan2", &[y, x]),
            View::Select(c, x, y) => list(f, "select", &[c, x, y]),
        }
    }
}

impl fmt::Display for Display<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write(self.id, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sym::RuleSet;

    fn round(s: &str) -> String {
        let mut a = Arena::with_rules(RuleSet::NONE);
        let id = a.parse(s).unwrap();
        a.to_sexpr_string(id)
    }

    #[test]
    fn parse_and_print_raw() {
        assert_eq!(round("(sin q1)"), "(sin q1)");
        assert_eq!(round("(^ x 2)"), "(^ x 2)");
        assert_eq!(round("1/2"), "1/2");
        assert_eq!(round("0.1"), "0.1");
        assert_eq!(round("(select (- x) 1 2)"), "(select (* -1 x) 1 2)");
        assert_eq!(round("(atan2 y x)"), "(atan2 y x)");
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_stack_overflow() {
        let src = "(- ".repeat(100_000) + "x" + &")".repeat(100_000);
        match Arena::new().parse(&src) {
            Err(SymError::Parse { message, .. }) => {
                assert!(message.contains("deeper"), "got {message}")
            }
            other => panic!("got {other:?} want a parse error"),
        }
        let ok = "(- ".repeat(500) + "x" + &")".repeat(500);
        let mut a = Arena::new();
        let e = a.parse(&ok).unwrap();
        assert_eq!(a.to_sexpr_string(e), "x", "an even number of negations");
    }

    #[test]
    fn errors_have_offsets() {
        let mut a = Arena::new();
        let cases = [
            ("(+ x", 0, "unclosed"),
            ("(foo x)", 0, "unknown operator `foo`"),
            ("(sin x y)", 0, "takes 1"),
            ("(^ x 1.5)", 5, "not an integer"),
            ("x )", 2, "unexpected text"),
            ("(+ 1x 2)", 3, "not a number"),
            ("()", 0, "empty list"),
            ("", 0, "empty input"),
            ("((sin) x)", 0, "must start with an operator"),
        ];
        for (src, off, msg) in cases {
            match a.parse(src) {
                Err(SymError::Parse { offset, message }) => {
                    assert_eq!(offset, off, "{src}: got offset {offset} want {off}");
                    assert!(message.contains(msg), "{src}: got {message:?} want …{msg}…");
                }
                other => panic!("{src}: got {other:?} want a parse error"),
            }
        }
    }
}
