//! Parameters and the quantities written with them: values and
//! expressions in their scope, vectors, axes, frames and orientations,
//! nonnegative data, and the names models may define.

use super::{Ctx, RESERVED, Scope, TOL, f, i, is_ident, join};
use crate::diag::{Diagnostic, Span, did_you_mean, list_names};
use crate::expr::{Ast, EvalError, Func};
use crate::model::locate::{Seg, string_contents_start};
use crate::model::rotation;
use crate::model::spec::{self, Num, Orientation, Spec, V3};
use crate::system::*;
use nalgebra::Matrix3;

impl Ctx<'_> {
    /// Checks that `name` is a usable identifier for an expression name.
    pub(super) fn check_symbol_name(
        &mut self,
        name: &str,
        path: &[Seg<'static>],
        what: &'static str,
    ) -> bool {
        if !is_ident(name) {
            self.error(
                path,
                format!("{what} name `{name}` is not an identifier"),
                "use letters, digits and `_`, starting with a letter or `_`",
            );
            return false;
        }
        if RESERVED.contains(&name) || Func::ALL.iter().any(|f| f.name() == name) {
            self.error(
                path,
                format!("{what} name `{name}` is reserved in expressions"),
                "`t`, `pi` and the function names cannot be redefined; choose another name",
            );
            return false;
        }
        if self.param_value(name).is_some() || self.state_names.contains_key(name) {
            let other = self.state_names.get(name).copied().unwrap_or("parameter");
            if other == what {
                self.error(
                    path,
                    format!("{what} `{name}` is defined twice"),
                    format!("{what} names must be unique; rename one of them"),
                );
                return false;
            }
            self.error(
                path,
                format!("{what} name `{name}` is already used by a {other}"),
                "parameters, coordinates, speeds and inputs share one namespace; rename one of them",
            );
            return false;
        }
        true
    }

    /// Parses and evaluates a number field.
    pub(super) fn quantity(
        &mut self,
        num: &Num,
        path: &[Seg<'static>],
        scope: Scope,
    ) -> Option<Quantity> {
        let span = self.span(path);
        let (expr, text) = match num {
            Num::Value(v) => (Ast::Num(*v), None),
            Num::Expr(text) => {
                let base = string_contents_start(&self.src.text, span);
                match Ast::parse(text) {
                    Ok(ast) => (ast, Some(base)),
                    Err(e) => {
                        let at = Span::new(base + e.offset, base + e.offset + 1);
                        self.diags.push(
                            Diagnostic::error(at, format!("in expression `{text}`: {}", e.message))
                                .with_help(e.help),
                        );
                        return None;
                    }
                }
            }
        };
        let mut ok = true;
        for (name, offset) in expr.names() {
            if name == "pi" || self.param_value(name).is_some() {
                continue;
            }
            if self.failed_params.contains(name) {
                ok = false;
                continue;
            }
            let allowed = match self.state_names.get(name) {
                _ if name == "t" => scope != Scope::Params,
                Some(_) => scope == Scope::State,
                None => false,
            };
            if allowed {
                continue;
            }
            ok = false;
            let at = text.map_or(span, |base| {
                Span::new(base + offset, base + offset + name.len())
            });
            if let Some(later) = self.later_params.iter().find(|p| p.as_str() == name) {
                let at = text.map_or(span, |base| {
                    Span::new(base + offset, base + offset + name.len())
                });
                self.diags.push(
                    Diagnostic::error(at, format!("parameter `{later}` is used before it is defined"))
                        .with_help("parameters may use only parameters defined above them: move its definition up"),
                );
                continue;
            }
            let message = match (name, self.state_names.get(name)) {
                ("t", _) => "time `t` cannot be used here".to_string(),
                (_, Some(kind)) => format!("{kind} `{name}` cannot be used here"),
                _ => format!("unknown name `{name}` in expression"),
            };
            let mut candidates: Vec<&str> = self.params.iter().map(|(n, _)| n.as_str()).collect();
            if scope == Scope::State {
                candidates.extend(self.state_names.keys().map(String::as_str));
            }
            candidates.sort_unstable();
            let help = match did_you_mean(name, candidates.iter().copied()) {
                Some(best) => format!("did you mean `{best}`?"),
                None => match scope {
                    Scope::Params => format!(
                        "this field may use parameters defined above it and `pi`; parameters: {}",
                        list_names(candidates.iter().copied())
                    ),
                    Scope::Time => "prescribed motion may use parameters, `pi` and time `t`".into(),
                    Scope::State => {
                        "forces and constraints may use parameters, `pi`, `t`, coordinates and speeds"
                            .into()
                    }
                },
            };
            self.diags
                .push(Diagnostic::error(at, message).with_help(help));
        }
        if !ok {
            return None;
        }
        let lookup = |n: &str| {
            self.param_value(n)
                .or_else(|| (n == "t" || self.state_names.contains_key(n)).then_some(0.0))
        };
        match expr.eval(&lookup) {
            Ok(value) => Some(Quantity { expr, value, span }),
            Err(EvalError::NotFinite) if scope == Scope::Params => {
                self.error(
                    path,
                    match num {
                        Num::Expr(text) => {
                            format!("`{text}` is not a finite number at the default parameters")
                        }
                        Num::Value(v) => format!("`{v}` is not a finite number"),
                    },
                    "check for division by zero, `sqrt` or `ln` of a negative value",
                );
                None
            }
            // With time or state at zero a singular value is not an error
            // of the model: the value is only a placeholder.
            Err(_) => Some(Quantity {
                expr,
                value: f64::NAN,
                span,
            }),
        }
    }

    pub(super) fn vec3(&mut self, v: &V3, path: &[Seg<'static>], scope: Scope) -> Option<Vec3Q> {
        let [a, b, c] = v.components();
        let x = self.quantity(a, &join(path, &[i(0)]), scope);
        let y = self.quantity(b, &join(path, &[i(1)]), scope);
        let z = self.quantity(c, &join(path, &[i(2)]), scope);
        Some([x?, y?, z?])
    }

    pub(super) fn axis(&mut self, v: &V3, path: &[Seg<'static>], what: &str) -> Option<Axis> {
        let written = self.vec3(v, path, Scope::Params)?;
        let raw = values(&written);
        let norm = raw.norm();
        if norm < 1e-12 || !norm.is_finite() {
            self.error(
                path,
                format!("{what} has zero length"),
                "give a direction such as `(0, 0, 1)`",
            );
            return None;
        }
        Some(Axis {
            written,
            unit: raw / norm,
        })
    }

    pub(super) fn frame(
        &mut self,
        frame: &spec::Frame,
        path: &[Seg<'static>],
    ) -> Option<FrameInfo> {
        let position = self.vec3(
            &frame.position,
            &join(path, &[f("position")]),
            Scope::Params,
        );
        let rot = self.orientation(&frame.orientation, &join(path, &[f("orientation")]));
        let (rotation, matrix) = rot?;
        Some(FrameInfo {
            position: position?,
            rotation,
            matrix,
        })
    }

    pub(super) fn orientation(
        &mut self,
        o: &Orientation,
        path: &[Seg<'static>],
    ) -> Option<(Rotation, Matrix3<f64>)> {
        match o {
            Orientation::Identity => Some((Rotation::Identity, Matrix3::identity())),
            Orientation::AxisAngle { axis, angle } => {
                let a = self.axis(axis, &join(path, &[f("axis")]), "rotation axis");
                let angle = self.quantity(angle, &join(path, &[f("angle")]), Scope::Params);
                let (a, angle) = (a?, angle?);
                let m = rotation::axis_angle(&a.unit, angle.value);
                Some((
                    Rotation::AxisAngle {
                        axis: a.written,
                        angle,
                    },
                    m,
                ))
            }
            Orientation::Rpy(r, p, y) => {
                let r = self.quantity(r, &join(path, &[i(0)]), Scope::Params);
                let p = self.quantity(p, &join(path, &[i(1)]), Scope::Params);
                let y = self.quantity(y, &join(path, &[i(2)]), Scope::Params);
                let (r, p, y) = (r?, p?, y?);
                let m = rotation::rpy(r.value, p.value, y.value);
                Some((Rotation::Rpy([r, p, y]), m))
            }
            Orientation::Matrix(a, b, c) => {
                let rows = [
                    self.vec3(a, &join(path, &[i(0)]), Scope::Params),
                    self.vec3(b, &join(path, &[i(1)]), Scope::Params),
                    self.vec3(c, &join(path, &[i(2)]), Scope::Params),
                ];
                let [Some(a), Some(b), Some(c)] = rows else {
                    return None;
                };
                let m = Matrix3::from_rows(&[
                    values(&a).transpose(),
                    values(&b).transpose(),
                    values(&c).transpose(),
                ]);
                let (err, det) = rotation::orthonormality(&m);
                if err > TOL {
                    self.error(
                        path,
                        format!("rotation matrix is not orthonormal (largest entry of RᵀR − I is {err:.3e})"),
                        "rows must be unit vectors at right angles to each other; or write `AxisAngle(axis: …, angle: …)` or `Rpy(roll, pitch, yaw)`",
                    );
                    return None;
                }
                if det < 0.0 {
                    self.error(
                        path,
                        "rotation matrix is a reflection (determinant −1)".into(),
                        "negate one row to make it a proper rotation",
                    );
                    return None;
                }
                Some((Rotation::Matrix([a, b, c]), m))
            }
        }
    }

    pub(super) fn parameters(&mut self, spec: &Spec) -> Option<Vec<Parameter>> {
        let mut out = Vec::new();
        let mut ok = true;
        for (k, p) in spec.parameters.iter().enumerate() {
            self.later_params = spec.parameters[k..]
                .iter()
                .map(|p| p.name.clone())
                .collect();
            let path = [f("parameters"), i(k)];
            let named = self.check_symbol_name(&p.name, &join(&path, &[f("name")]), "parameter");
            // Later parameters are not visible yet: a forward reference is
            // reported as an unknown name with the definition order in help.
            match self.quantity(&p.value, &join(&path, &[f("value")]), Scope::Params) {
                Some(value) => {
                    if p.tunable && !matches!(value.expr, Ast::Num(_)) {
                        self.warning(
                            &join(&path, &[f("value")]),
                            format!("tunable parameter `{}` is given by an expression", p.name),
                            "its default is the expression's value; at run time it is set directly",
                        );
                    }
                    if named {
                        self.params.push((p.name.clone(), value.value));
                    }
                    out.push(Parameter {
                        name: p.name.clone(),
                        value,
                        tunable: p.tunable,
                        doc: p.doc.clone(),
                        span: self.span(&join(&path, &[f("name")])),
                    });
                }
                None => {
                    self.failed_params.insert(p.name.clone());
                    ok = false;
                }
            }
        }
        self.later_params.clear();
        ok.then_some(out)
    }

    pub(super) fn nonnegative(
        &mut self,
        n: &Num,
        path: &[Seg<'static>],
        what: &str,
        owner: &str,
    ) -> Option<Quantity> {
        let q = self.quantity(n, path, Scope::Params)?;
        if q.value < 0.0 {
            self.error(
                path,
                format!("{what} of `{owner}` is negative ({})", q.value),
                format!("a {what} is zero or positive"),
            );
            return None;
        }
        Some(q)
    }
}
