//! Model expressions and quantities as scalars: [`lower_ast`] turns an
//! expression into any [`Scalar`], [`Lowering`] takes a quantity at its
//! value when it uses only fixed parameters and keeps tunable ones symbolic.

use super::env::Env;
use super::error::MechError;
use super::spatial::Pose;
use crate::diag::Span;
use crate::expr::{Ast, BinOp, Func};
use crate::sym::{Mat3, Scalar, Vec3};
use crate::system::{FrameInfo, Quantity, Rotation, Vec3Q};

/// Turns a model expression written at `span` into a scalar; `lookup`
/// gives every name but `pi`. `asin`, `acos` and `atan` become `atan2`,
/// non-integer powers `exp(b ln a)`.
pub fn lower_ast<S: Scalar>(
    ast: &Ast,
    span: Span,
    lookup: &dyn Fn(&str) -> Option<S>,
) -> Result<S, MechError> {
    let lower = |a: &Ast| lower_ast(a, span, lookup);
    Ok(match ast {
        Ast::Num(v) => S::from_f64(*v),
        Ast::Var(name, _) if name == "pi" => S::from_f64(std::f64::consts::PI),
        Ast::Var(name, _) => lookup(name).ok_or_else(|| MechError::UnknownName {
            name: name.clone(),
            span,
        })?,
        Ast::Neg(a) => -lower(a)?,
        Ast::Bin(op, a, b) => {
            let x = lower(a)?;
            if let (BinOp::Pow, Ast::Num(n)) = (op, &**b)
                && n.fract() == 0.0
                && n.abs() <= 64.0
            {
                return Ok(x.powi(*n as i32));
            }
            let y = lower(b)?;
            match op {
                BinOp::Add => x + y,
                BinOp::Sub => x - y,
                BinOp::Mul => x * y,
                BinOp::Div => x / y,
                BinOp::Pow => (y * x.ln()).exp(),
            }
        }
        Ast::Call(Func::Select, args, _) => {
            let arg = |k: usize| args.get(k).map_or(Ok(S::zero()), lower);
            S::select(arg(0)?, arg(1)?, arg(2)?)
        }
        Ast::Call(f, args, _) => {
            let x = lower(&args[0])?;
            let one = S::one();
            match f {
                Func::Sin => x.sin(),
                Func::Cos => x.cos(),
                Func::Tan => x.tan(),
                Func::Asin => x.atan2((one - x * x).sqrt()),
                Func::Acos => (one - x * x).sqrt().atan2(x),
                Func::Atan => x.atan2(one),
                Func::Atan2 => {
                    let y = match args.get(1) {
                        Some(a) => lower(a)?,
                        None => one,
                    };
                    x.atan2(y)
                }
                Func::Sqrt => x.sqrt(),
                Func::Exp => x.exp(),
                Func::Ln => x.ln(),
                Func::Abs => x.abs(),
                Func::Select => x, // handled above
            }
        }
    })
}
/// Values of quantities under an environment.
pub struct Lowering<'a, S> {
    env: &'a dyn Env<S>,
}

impl<'a, S: Scalar> Lowering<'a, S> {
    /// Lowering with `env`.
    pub fn new(env: &'a dyn Env<S>) -> Self {
        Lowering { env }
    }

    /// True if `ast` uses a tunable parameter.
    pub fn uses_tunable(&self, ast: &Ast) -> bool {
        ast.names().iter().any(|(n, _)| self.env.is_tunable(n))
    }

    /// A parameter-only quantity: its value if it uses only fixed
    /// parameters, else its expression over the tunable ones.
    pub fn quantity(&self, q: &Quantity) -> Result<S, MechError> {
        if !self.uses_tunable(&q.expr) && q.value.is_finite() {
            return Ok(S::from_f64(q.value));
        }
        lower_ast(&q.expr, q.span, &|n| self.env.param(n))
    }

    /// An expression written at `span` that may use `extra` names besides
    /// parameters.
    pub fn expr(
        &self,
        ast: &Ast,
        span: Span,
        extra: &dyn Fn(&str) -> Option<S>,
    ) -> Result<S, MechError> {
        lower_ast(ast, span, &|n| extra(n).or_else(|| self.env.param(n)))
    }

    /// A vector of quantities.
    pub fn vec3(&self, v: &Vec3Q) -> Result<Vec3<S>, MechError> {
        Ok(Vec3::new(
            self.quantity(&v[0])?,
            self.quantity(&v[1])?,
            self.quantity(&v[2])?,
        ))
    }

    /// A frame as a pose. Fixed rotation matrices are inlined with entries
    /// within 1e-14 of 0 or ±1 snapped to them, so `cos(π/2)` is an exact
    /// zero in the generated code.
    pub fn frame(&self, f: &FrameInfo) -> Result<Pose<S>, MechError> {
        let symbolic = match &f.rotation {
            Rotation::Identity => false,
            Rotation::AxisAngle { axis, angle } => {
                axis.iter().any(|a| self.uses_tunable(&a.expr)) || self.uses_tunable(&angle.expr)
            }
            Rotation::Rpy(a) => a.iter().any(|x| self.uses_tunable(&x.expr)),
            Rotation::Matrix(rows) => rows.iter().flatten().any(|x| self.uses_tunable(&x.expr)),
        };
        let e = if symbolic {
            match &f.rotation {
                Rotation::AxisAngle { axis, angle } => {
                    let k = self.vec3(axis)?;
                    Mat3::from_axis_angle(k.scale(S::one() / k.norm()), self.quantity(angle)?)
                }
                Rotation::Rpy([r, p, y]) => {
                    use crate::sym::Axis::{X, Y, Z};
                    Mat3::from_euler(
                        [Z, Y, X],
                        [self.quantity(y)?, self.quantity(p)?, self.quantity(r)?],
                    )
                }
                Rotation::Matrix(rows) => Mat3::from_rows([
                    self.vec3(&rows[0])?,
                    self.vec3(&rows[1])?,
                    self.vec3(&rows[2])?,
                ]),
                Rotation::Identity => Mat3::identity(),
            }
        } else {
            Mat3(std::array::from_fn(|i| {
                std::array::from_fn(|j| S::from_f64(snap(f.matrix[(i, j)])))
            }))
        };
        Ok(Pose {
            e,
            r: self.vec3(&f.position)?,
        })
    }
}

/// Snaps values within 1e-14 of 0, 1 or −1 to them.
pub fn snap(x: f64) -> f64 {
    for target in [0.0, 1.0, -1.0] {
        if (x - target).abs() < 1e-14 {
            return target;
        }
    }
    x
}
