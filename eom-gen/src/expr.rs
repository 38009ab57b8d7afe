//! The arithmetic written in model files: `"m*l^2/12"`, `"2*pi*t"`,
//! `"sd*cos(gamma) + sc*sin(gamma) + xb"`.
//!
//! Grammar (usual precedence, `^` binds tighter than unary minus and is
//! right-associative, so `-x^2 = -(x^2)` and `2^3^2 = 2^9`):
//!
//! ```text
//! sum     = product (("+" | "-") product)*
//! product = unary (("*" | "/") unary)*
//! unary   = "-" unary | "+" unary | power
//! power   = atom ("^" unary)?
//! atom    = number | name | name "(" sum ("," sum)* ")" | "(" sum ")"
//! ```
//! Names are parameters, coordinates, `t` or the constant `pi`, depending
//! on where the expression stands; functions are listed in [`Func`].
//!
//! `select(c, a, b)` is piecewise: `a` where `c > 0`, else `b` (as the
//! symbolic `select`; NaN conditions take `b`). Its derivative is
//! `select(c, a', b')`, the derivative away from the switch, so a
//! prescribed motion written piecewise gets its `q̇(t)` and `q̈(t)`
//! piecewise too; making the pieces meet smoothly is the writer's task.
//!
//! A leaf module below the pipeline: the validator parses the expressions,
//! the validated [`crate::System`] keeps them as [`Ast`]s, and the
//! formulation lowers them to scalars.

use std::fmt;

/// Deepest nesting accepted (parentheses, unary signs, powers).
const MAX_DEPTH: usize = 64;

/// A parsed expression. Offsets are byte offsets into the expression text.
#[derive(Clone, Debug, PartialEq)]
pub enum Ast {
    /// A number literal.
    Num(f64),
    /// A name, with its offset.
    Var(String, usize),
    /// `-a`.
    Neg(Box<Ast>),
    /// `a op b`.
    Bin(BinOp, Box<Ast>, Box<Ast>),
    /// `f(args…)`, with the offset of the function name.
    Call(Func, Vec<Ast>, usize),
}

/// Binary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `^`
    Pow,
}

/// The functions a model expression may call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Func {
    /// sine (radians)
    Sin,
    /// cosine
    Cos,
    /// tangent
    Tan,
    /// arcsine
    Asin,
    /// arccosine
    Acos,
    /// arctangent
    Atan,
    /// `atan2(y, x)`
    Atan2,
    /// square root
    Sqrt,
    /// exponential
    Exp,
    /// natural logarithm
    Ln,
    /// absolute value
    Abs,
    /// `select(c, a, b)`: `a` if `c > 0`, else `b` (piecewise definitions)
    Select,
}

impl Func {
    /// Every function, for lookups and help messages.
    pub const ALL: [Func; 12] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Atan2,
        Func::Sqrt,
        Func::Exp,
        Func::Ln,
        Func::Abs,
        Func::Select,
    ];

    /// The name as written in a model.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Atan2 => "atan2",
            Func::Sqrt => "sqrt",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Abs => "abs",
            Func::Select => "select",
        }
    }

    /// Number of arguments.
    pub fn arity(self) -> usize {
        match self {
            Func::Atan2 => 2,
            Func::Select => 3,
            _ => 1,
        }
    }

    fn from_name(name: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// A syntax error at a byte offset of the expression text.
#[derive(Clone, Debug, PartialEq)]
pub struct ParseError {
    /// Byte offset into the expression.
    pub offset: usize,
    /// What is wrong.
    pub message: String,
    /// What would be right.
    pub help: String,
}

/// Why an expression could not be evaluated.
#[derive(Clone, Debug, PartialEq)]
pub enum EvalError {
    /// A name with no value; offset into the expression.
    Unknown(String, usize),
    /// The result is NaN or infinite (e.g. `sqrt(-1)`, `1/0`).
    NotFinite,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "at byte {}: {} ({})",
            self.offset, self.message, self.help
        )
    }
}

impl std::error::Error for ParseError {}

impl fmt::Display for EvalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EvalError::Unknown(name, offset) => {
                write!(f, "`{name}` (at byte {offset}) has no value here")
            }
            EvalError::NotFinite => write!(f, "the value is not a finite number"),
        }
    }
}

impl std::error::Error for EvalError {}

impl Ast {
    /// Parses an expression.
    pub fn parse(text: &str) -> Result<Ast, ParseError> {
        let mut p = Parser {
            s: text.as_bytes(),
            i: 0,
            depth: 0,
        };
        p.skip_ws();
        if p.peek().is_none() {
            return Err(ParseError {
                offset: 0,
                message: "empty expression".into(),
                help: "write a number or an expression such as `l/2`".into(),
            });
        }
        let ast = p.sum()?;
        p.skip_ws();
        match p.peek() {
            None => Ok(ast),
            Some(c) => Err(p.error(
                format!("unexpected `{}`", char::from(c)),
                "expected an operator (`+ - * / ^`) or the end of the expression",
            )),
        }
    }

    /// Every name used, with its offset, in order of appearance.
    pub fn names(&self) -> Vec<(&str, usize)> {
        let mut out = Vec::new();
        self.collect_names(&mut out);
        out
    }

    fn collect_names<'a>(&'a self, out: &mut Vec<(&'a str, usize)>) {
        match self {
            Ast::Num(_) => {}
            Ast::Var(name, off) => out.push((name, *off)),
            Ast::Neg(a) => a.collect_names(out),
            Ast::Bin(_, a, b) => {
                a.collect_names(out);
                b.collect_names(out);
            }
            Ast::Call(_, args, _) => args.iter().for_each(|a| a.collect_names(out)),
        }
    }

    /// Evaluates with `lookup` giving the value of every name but `pi`.
    pub fn eval(&self, lookup: &dyn Fn(&str) -> Option<f64>) -> Result<f64, EvalError> {
        let v = self.eval_raw(lookup)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(EvalError::NotFinite)
        }
    }

    fn eval_raw(&self, lookup: &dyn Fn(&str) -> Option<f64>) -> Result<f64, EvalError> {
        Ok(match self {
            Ast::Num(v) => *v,
            Ast::Var(name, off) => {
                if name == "pi" {
                    std::f64::consts::PI
                } else {
                    lookup(name).ok_or_else(|| EvalError::Unknown(name.clone(), *off))?
                }
            }
            Ast::Neg(a) => -a.eval_raw(lookup)?,
            Ast::Bin(op, a, b) => {
                let (a, b) = (a.eval_raw(lookup)?, b.eval_raw(lookup)?);
                match op {
                    BinOp::Add => a + b,
                    BinOp::Sub => a - b,
                    BinOp::Mul => a * b,
                    BinOp::Div => a / b,
                    BinOp::Pow => a.powf(b),
                }
            }
            Ast::Call(Func::Select, args, _) => {
                let arg = |k: usize| args.get(k).map_or(Ok(f64::NAN), |a| a.eval_raw(lookup));
                let (c, a, b) = (arg(0)?, arg(1)?, arg(2)?);
                if c > 0.0 { a } else { b }
            }
            Ast::Call(f, args, _) => {
                let x = args.first().map_or(Ok(f64::NAN), |a| a.eval_raw(lookup))?;
                match f {
                    Func::Sin => x.sin(),
                    Func::Cos => x.cos(),
                    Func::Tan => x.tan(),
                    Func::Asin => x.asin(),
                    Func::Acos => x.acos(),
                    Func::Atan => x.atan(),
                    Func::Atan2 => {
                        let y = args.get(1).map_or(Ok(f64::NAN), |a| a.eval_raw(lookup))?;
                        x.atan2(y)
                    }
                    Func::Sqrt => x.sqrt(),
                    Func::Exp => x.exp(),
                    Func::Ln => x.ln(),
                    Func::Abs => x.abs(),
                    Func::Select => f64::NAN,
                }
            }
        })
    }

    /// The derivative with respect to the name `var` (used for prescribed
    /// motion: `q(t)` gives `q̇(t)` and `q̈(t)`). Exact zeros and ones are
    /// folded so repeated differentiation stays small.
    pub fn diff(&self, var: &str) -> Ast {
        use Ast::*;
        let num = |v: f64| Num(v);
        let add = |a: Ast, b: Ast| match (&a, &b) {
            (Num(x), _) if *x == 0.0 => b,
            (_, Num(y)) if *y == 0.0 => a,
            _ => Bin(BinOp::Add, Box::new(a), Box::new(b)),
        };
        let mul = |a: Ast, b: Ast| match (&a, &b) {
            (Num(x), _) | (_, Num(x)) if *x == 0.0 => Num(0.0),
            (Num(x), _) if *x == 1.0 => b,
            (_, Num(y)) if *y == 1.0 => a,
            _ => Bin(BinOp::Mul, Box::new(a), Box::new(b)),
        };
        let neg = |a: Ast| match a {
            Num(x) => Num(-x),
            a => Neg(Box::new(a)),
        };
        let div = |a: Ast, b: Ast| match &a {
            Num(x) if *x == 0.0 => Num(0.0),
            _ => Bin(BinOp::Div, Box::new(a), Box::new(b)),
        };
        let call = |f: Func, a: &Ast| Call(f, vec![a.clone()], 0);
        match self {
            Num(_) => num(0.0),
            Var(name, _) => num(if name == var { 1.0 } else { 0.0 }),
            Neg(a) => neg(a.diff(var)),
            Bin(op, a, b) => {
                let (da, db) = (a.diff(var), b.diff(var));
                let (a, b) = ((**a).clone(), (**b).clone());
                match op {
                    BinOp::Add => add(da, db),
                    BinOp::Sub => add(da, neg(db)),
                    BinOp::Mul => add(mul(da, b), mul(a, db)),
                    // (a/b)' = a'/b − a b' / b²
                    BinOp::Div => add(
                        div(da, b.clone()),
                        neg(div(
                            mul(a, db),
                            Bin(BinOp::Pow, Box::new(b), Box::new(Num(2.0))),
                        )),
                    ),
                    BinOp::Pow => match &b {
                        // (a^n)' = n a^(n−1) a'
                        Num(n) => mul(
                            mul(
                                Num(*n),
                                Bin(BinOp::Pow, Box::new(a), Box::new(Num(n - 1.0))),
                            ),
                            da,
                        ),
                        // (a^b)' = a^b (b' ln a + b a'/a)
                        _ => mul(
                            self.clone(),
                            add(mul(db, call(Func::Ln, &a)), div(mul(b, da), a)),
                        ),
                    },
                }
            }
            // Away from the switch: select(c, a, b)' = select(c, a', b').
            Call(Func::Select, args, off) => {
                let mut d: Vec<Ast> = args.iter().map(|a| a.diff(var)).collect();
                d[0] = args[0].clone();
                match (&d[1], &d[2]) {
                    (Num(x), Num(y)) if x == y => Num(*x),
                    _ => Call(Func::Select, d, *off),
                }
            }
            Call(f, args, _) => {
                let a = &args[0];
                let da = a.diff(var);
                let one_minus_sq = || {
                    add(
                        Num(1.0),
                        neg(Bin(BinOp::Pow, Box::new(a.clone()), Box::new(Num(2.0)))),
                    )
                };
                let inner = match f {
                    Func::Sin => call(Func::Cos, a),
                    Func::Cos => neg(call(Func::Sin, a)),
                    Func::Tan => add(
                        Num(1.0),
                        Bin(BinOp::Pow, Box::new(call(Func::Tan, a)), Box::new(Num(2.0))),
                    ),
                    Func::Asin => div(Num(1.0), call(Func::Sqrt, &one_minus_sq())),
                    Func::Acos => neg(div(Num(1.0), call(Func::Sqrt, &one_minus_sq()))),
                    Func::Atan => div(
                        Num(1.0),
                        add(
                            Num(1.0),
                            Bin(BinOp::Pow, Box::new(a.clone()), Box::new(Num(2.0))),
                        ),
                    ),
                    Func::Sqrt => div(Num(0.5), call(Func::Sqrt, a)),
                    Func::Exp => call(Func::Exp, a),
                    Func::Ln => div(Num(1.0), a.clone()),
                    Func::Abs => div(a.clone(), call(Func::Abs, a)),
                    Func::Select => Num(0.0), // handled above
                    Func::Atan2 => {
                        // atan2(y, x)' = (x y' − y x') / (x² + y²)
                        let (y, x) = (a.clone(), args.get(1).cloned().unwrap_or(Num(1.0)));
                        let dx = x.diff(var);
                        let den = add(
                            Bin(BinOp::Pow, Box::new(x.clone()), Box::new(Num(2.0))),
                            Bin(BinOp::Pow, Box::new(y.clone()), Box::new(Num(2.0))),
                        );
                        return div(add(mul(x, da), neg(mul(y, dx))), den);
                    }
                };
                mul(inner, da)
            }
        }
    }

    /// Replaces every name for which `f` gives an expression.
    pub fn substitute(&self, f: &dyn Fn(&str) -> Option<Ast>) -> Ast {
        match self {
            Ast::Num(_) => self.clone(),
            Ast::Var(name, _) => f(name).unwrap_or_else(|| self.clone()),
            Ast::Neg(a) => Ast::Neg(Box::new(a.substitute(f))),
            Ast::Bin(op, a, b) => {
                Ast::Bin(*op, Box::new(a.substitute(f)), Box::new(b.substitute(f)))
            }
            Ast::Call(func, args, off) => {
                Ast::Call(*func, args.iter().map(|a| a.substitute(f)).collect(), *off)
            }
        }
    }
}

impl fmt::Display for Ast {
    /// Prints with full parentheses around compound operands, so that
    /// printing and parsing round-trip.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn operand(a: &Ast, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            match a {
                Ast::Num(v) if *v >= 0.0 => write!(f, "{a}"),
                Ast::Var(..) | Ast::Call(..) => write!(f, "{a}"),
                _ => write!(f, "({a})"),
            }
        }
        match self {
            Ast::Num(v) => write!(f, "{v:?}"),
            Ast::Var(name, _) => f.write_str(name),
            Ast::Neg(a) => {
                f.write_str("-")?;
                operand(a, f)
            }
            Ast::Bin(op, a, b) => {
                operand(a, f)?;
                let s = match op {
                    BinOp::Add => " + ",
                    BinOp::Sub => " - ",
                    BinOp::Mul => "*",
                    BinOp::Div => "/",
                    BinOp::Pow => "^",
                };
                f.write_str(s)?;
                operand(b, f)
            }
            Ast::Call(func, args, _) => {
                write!(f, "{}(", func.name())?;
                for (k, a) in args.iter().enumerate() {
                    if k > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{a}")?;
                }
                f.write_str(")")
            }
        }
    }
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    depth: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn skip_ws(&mut self) {
        while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
            self.i += 1;
        }
    }

    fn error(&self, message: impl Into<String>, help: impl Into<String>) -> ParseError {
        ParseError {
            offset: self.i,
            message: message.into(),
            help: help.into(),
        }
    }

    fn enter(&mut self) -> Result<(), ParseError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            Err(self.error(
                format!("expression nested deeper than {MAX_DEPTH} levels"),
                "split it with intermediate parameters",
            ))
        } else {
            Ok(())
        }
    }

    fn sum(&mut self) -> Result<Ast, ParseError> {
        self.enter()?;
        let mut lhs = self.product()?;
        loop {
            self.skip_ws();
            let op = match self.peek() {
                Some(b'+') => BinOp::Add,
                Some(b'-') => BinOp::Sub,
                _ => break,
            };
            self.i += 1;
            let rhs = self.product()?;
            lhs = Ast::Bin(op, Box::new(lhs), Box::new(rhs));
        }
        self.depth -= 1;
        Ok(lhs)
    }

    fn product(&mut self) -> Result<Ast, ParseError> {
        let mut lhs = self.unary()?;
        loop {
            self.skip_ws();
            let op = match self.peek() {
                Some(b'*') => BinOp::Mul,
                Some(b'/') => BinOp::Div,
                _ => break,
            };
            self.i += 1;
            let rhs = self.unary()?;
            lhs = Ast::Bin(op, Box::new(lhs), Box::new(rhs));
        }
        Ok(lhs)
    }

    fn unary(&mut self) -> Result<Ast, ParseError> {
        self.enter()?;
        self.skip_ws();
        let ast = match self.peek() {
            Some(b'-') => {
                self.i += 1;
                Ast::Neg(Box::new(self.unary()?))
            }
            Some(b'+') => {
                self.i += 1;
                self.unary()?
            }
            _ => self.power()?,
        };
        self.depth -= 1;
        Ok(ast)
    }

    fn power(&mut self) -> Result<Ast, ParseError> {
        let base = self.atom()?;
        self.skip_ws();
        if self.peek() == Some(b'^') {
            self.i += 1;
            let exp = self.unary()?;
            return Ok(Ast::Bin(BinOp::Pow, Box::new(base), Box::new(exp)));
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Ast, ParseError> {
        self.skip_ws();
        let start = self.i;
        match self.peek() {
            None => Err(self.error(
                "expression ends too early",
                "complete the expression after the last operator",
            )),
            Some(b'(') => {
                self.i += 1;
                let inner = self.sum()?;
                self.skip_ws();
                if self.peek() != Some(b')') {
                    return Err(self.error("expected `)`", "close the parenthesis opened earlier"));
                }
                self.i += 1;
                Ok(inner)
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => self.number(start),
            Some(c) if c.is_ascii_alphabetic() || c == b'_' => {
                while self
                    .peek()
                    .is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_')
                {
                    self.i += 1;
                }
                let name = String::from_utf8_lossy(&self.s[start..self.i]).into_owned();
                let after = self.i;
                self.skip_ws();
                if self.peek() != Some(b'(') {
                    self.i = after;
                    return Ok(Ast::Var(name, start));
                }
                let Some(func) = Func::from_name(&name) else {
                    self.i = start;
                    let names: Vec<&str> = Func::ALL.iter().map(|f| f.name()).collect();
                    return Err(self.error(
                        format!("unknown function `{name}`"),
                        format!("functions are {}", crate::diag::list_names(names)),
                    ));
                };
                self.i += 1;
                let mut args = vec![self.sum()?];
                loop {
                    self.skip_ws();
                    match self.peek() {
                        Some(b',') => {
                            self.i += 1;
                            args.push(self.sum()?);
                        }
                        Some(b')') => {
                            self.i += 1;
                            break;
                        }
                        _ => {
                            return Err(self.error(
                                "expected `,` or `)` in the argument list",
                                format!("`{name}` takes {} argument(s)", func.arity()),
                            ));
                        }
                    }
                }
                if args.len() != func.arity() {
                    return Err(ParseError {
                        offset: start,
                        message: format!(
                            "`{name}` takes {} argument(s), got {}",
                            func.arity(),
                            args.len()
                        ),
                        help: if func == Func::Atan2 {
                            "write `atan2(y, x)`".into()
                        } else if func == Func::Select {
                            "write `select(c, a, b)`: `a` where `c > 0`, else `b`".into()
                        } else {
                            format!("write `{name}(x)`")
                        },
                    });
                }
                Ok(Ast::Call(func, args, start))
            }
            Some(c) => Err(self.error(
                format!("unexpected `{}`", char::from(c)),
                "expected a number, a name, a function call or `(`",
            )),
        }
    }

    fn number(&mut self, start: usize) -> Result<Ast, ParseError> {
        while self.peek().is_some_and(|c| c.is_ascii_digit() || c == b'.') {
            self.i += 1;
        }
        if matches!(self.peek(), Some(b'e' | b'E')) {
            let save = self.i;
            self.i += 1;
            if matches!(self.peek(), Some(b'+' | b'-')) {
                self.i += 1;
            }
            if self.peek().is_some_and(|c| c.is_ascii_digit()) {
                while self.peek().is_some_and(|c| c.is_ascii_digit()) {
                    self.i += 1;
                }
            } else {
                self.i = save;
            }
        }
        let text = String::from_utf8_lossy(&self.s[start..self.i]);
        text.parse::<f64>().map(Ast::Num).map_err(|_| ParseError {
            offset: start,
            message: format!("malformed number `{text}`"),
            help: "write numbers like `0.5`, `2` or `1.5e-3`".into(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(text: &str) -> f64 {
        let lookup = |n: &str| match n {
            "l" => Some(2.0),
            "m" => Some(3.0),
            _ => None,
        };
        Ast::parse(text)
            .unwrap_or_else(|e| panic!("{text}: {e:?}"))
            .eval(&lookup)
            .unwrap_or_else(|e| panic!("{text}: {e:?}"))
    }

    #[test]
    fn precedence_and_associativity() {
        assert_eq!(eval("1 + 2*3"), 7.0);
        assert_eq!(eval("-l^2"), -4.0, "unary minus binds looser than ^");
        assert_eq!(eval("2^3^2"), 512.0, "^ is right-associative");
        assert_eq!(eval("8/2/2"), 2.0, "/ is left-associative");
        assert_eq!(eval("m*l^2/12"), 1.0);
        assert_eq!(eval("2^-1"), 0.5);
        assert_eq!(eval("1.5e-3*1e3"), 1.5);
        assert_eq!(eval("atan2(1, 1)*4"), std::f64::consts::PI);
        assert!((eval("sin(pi/6)") - 0.5).abs() < 1e-15);
    }

    #[test]
    fn errors_have_offsets_and_help() {
        let e = Ast::parse("l/2 +").expect_err("incomplete");
        assert_eq!(e.offset, 5);
        let e = Ast::parse("sinh(x)").expect_err("unknown function");
        assert_eq!(
            (e.offset, e.message.as_str()),
            (0, "unknown function `sinh`")
        );
        let e = Ast::parse("atan2(1)").expect_err("arity");
        assert!(e.message.contains("takes 2"), "{}", e.message);
        let e = Ast::parse("(1 + 2").expect_err("unclosed");
        assert_eq!(e.offset, 6);
        let e = Ast::parse("1 2").expect_err("juxtaposition");
        assert_eq!(e.offset, 2);
        assert!(
            Ast::parse(&"(".repeat(10_000)).is_err(),
            "deep nesting is an error, not a stack overflow"
        );
        assert!(Ast::parse(&"-".repeat(10_000)).is_err());
    }

    #[test]
    fn unknown_names_and_non_finite_results() {
        let ast = Ast::parse("2*k + l").expect("parses");
        let lookup = |n: &str| (n == "l").then_some(1.0);
        assert_eq!(ast.eval(&lookup), Err(EvalError::Unknown("k".into(), 2)));
        let ast = Ast::parse("1/(l - 1)").expect("parses");
        assert_eq!(ast.eval(&lookup), Err(EvalError::NotFinite));
        assert_eq!(ast.names(), vec![("l", 3)]);
    }

    #[test]
    fn derivatives_match_central_differences() {
        let cases = [
            "pi/2 + 2*pi*t",
            "0.3*sin(3*t)^2 - t^3/(1 + t^2)",
            "sqrt(1 + t^2)*exp(-t)*cos(t)",
            "atan2(sin(t), 2 + cos(t)) + asin(t/3) + acos(t/4) + atan(t) + ln(2 + t) + tan(t/2)",
            "abs(t - 0.1) + (1 + t)^t + -t",
            "select(t - 0.5, t^2/2, sin(t)) + select(1 - t, 3, t^3)",
        ];
        for text in cases {
            let ast = Ast::parse(text).expect("parses");
            let d = ast.diff("t");
            let at = |a: &Ast, t: f64| a.eval(&|n: &str| (n == "t").then_some(t)).expect("finite");
            for t in [0.37, 0.81, 1.3] {
                let h = 1e-6;
                let want = (at(&ast, t + h) - at(&ast, t - h)) / (2.0 * h);
                let got = at(&d, t);
                assert!(
                    (got - want).abs() < 1e-7 * (1.0 + want.abs()),
                    "d/dt {text} at {t}: got {got}, want {want}"
                );
            }
        }
    }

    #[test]
    fn select_is_piecewise_with_piecewise_derivatives() {
        // a where c > 0, else b (c = 0 and NaN take b, as the symbolic select).
        assert_eq!(eval("select(l - 1, 10, 20)"), 10.0);
        assert_eq!(eval("select(1 - l, 10, 20)"), 20.0);
        assert_eq!(eval("select(l - 2, 10, 20)"), 20.0);
        assert_eq!(eval("2*select(m, l, 0) + 1"), 5.0);
        let e = Ast::parse("select(t, 1)").expect_err("arity");
        assert!(e.message.contains("takes 3") && e.help.contains("select(c, a, b)"));
        // The spin-up profile's angle: θ̈ = (ω_s/T)(1 − cos(2πt/T)) before T, 0 after.
        let theta = Ast::parse(
            "select(T - t, w/T*(t^2/2 + (T/(2*pi))^2*(cos(2*pi*t/T) - 1)), w*(t - T/2))",
        )
        .expect("parses");
        let (w, tt) = (6.0, 15.0);
        let acc = theta.diff("t").diff("t");
        for t in [1.0, 7.5, 14.0, 16.0, 30.0] {
            let lookup = |n: &str| match n {
                "t" => Some(t),
                "T" => Some(tt),
                "w" => Some(w),
                _ => None,
            };
            let want = if t < tt {
                w / tt * (1.0 - (2.0 * std::f64::consts::PI * t / tt).cos())
            } else {
                0.0
            };
            let got = acc.eval(&lookup).expect("finite");
            assert!((got - want).abs() < 1e-12, "θ̈({t}) = {got}, want {want}");
        }
        // Both pieces and their rates meet at T: θ = ω_s T/2, θ̇ = ω_s.
        let at = |a: &Ast, t: f64| {
            a.eval(&|n: &str| match n {
                "t" => Some(t),
                "T" => Some(tt),
                "w" => Some(w),
                _ => None,
            })
            .expect("finite")
        };
        let rate = theta.diff("t");
        for (a, want) in [(&theta, w * tt / 2.0), (&rate, w)] {
            for t in [tt - 1e-9, tt + 1e-9] {
                assert!((at(a, t) - want).abs() < 1e-7, "at {t}: {}", at(a, t));
            }
        }
    }

    #[test]
    fn display_round_trips() {
        for text in [
            "-l^2",
            "(1 + 2)*3",
            "2^(3^2)",
            "-(a - b)/c",
            "atan2(y, -x)",
            "select(t - 1, -a, b^2)",
            "a - (b - c)",
            "-2*x",
        ] {
            let ast = Ast::parse(text).expect("parses");
            let again = Ast::parse(&ast.to_string()).expect("printed form parses");
            assert_eq!(strip(&again), strip(&ast), "{text} printed as {ast}");
        }
    }

    /// Offsets differ after printing; compare structure only.
    fn strip(a: &Ast) -> Ast {
        match a {
            Ast::Var(n, _) => Ast::Var(n.clone(), 0),
            Ast::Num(_) => a.clone(),
            Ast::Neg(x) => Ast::Neg(Box::new(strip(x))),
            Ast::Bin(op, x, y) => Ast::Bin(*op, Box::new(strip(x)), Box::new(strip(y))),
            Ast::Call(f, args, _) => Ast::Call(*f, args.iter().map(strip).collect(), 0),
        }
    }
}
