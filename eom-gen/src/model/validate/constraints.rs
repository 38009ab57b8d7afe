//! Constraints written in the model: holonomic and nonholonomic
//! equations, rolling disks.

use super::{Ctx, Scope, f, i, join};
use crate::model::spec::{self, Num, Spec};
use crate::system::*;
use std::collections::HashSet;

impl Ctx<'_> {
    pub(super) fn constraints(
        &mut self,
        spec: &Spec,
        bodies: &[BodyInfo],
    ) -> Option<Vec<Constraint>> {
        let mut out = Vec::new();
        let mut ok = true;
        let mut names = HashSet::new();
        for (k, c) in spec.constraints.iter().enumerate() {
            let path = [f("constraints"), i(k)];
            let name = match c {
                spec::Constraint::RollingDisk { name, .. }
                | spec::Constraint::Holonomic { name, .. } => name,
            };
            if !names.insert(name.as_str()) {
                self.error(
                    &join(&path, &[f("name")]),
                    format!("constraint `{name}` is defined twice"),
                    "constraint names must be unique",
                );
            }
            let kind = match c {
                spec::Constraint::RollingDisk {
                    body,
                    radius,
                    axis,
                    center,
                    ..
                } => {
                    let b = self.body_ref(bodies, body, &join(&path, &[f("body")]), "disk");
                    if b == Some(0) {
                        self.error(
                            &join(&path, &[f("body")]),
                            "the ground cannot roll".into(),
                            "name the disk's body",
                        );
                    }
                    let r = self.quantity(radius, &join(&path, &[f("radius")]), Scope::Params);
                    if let Some(r) = &r
                        && r.value <= 0.0
                    {
                        self.error(
                            &join(&path, &[f("radius")]),
                            format!("radius of rolling disk `{name}` is {} m", r.value),
                            "a disk's radius is positive",
                        );
                    }
                    let a = self.axis(axis, &join(&path, &[f("axis")]), "disk axis");
                    let ctr = self.vec3(center, &join(&path, &[f("center")]), Scope::Params);
                    (|| {
                        Some(ConstraintKind::RollingDisk {
                            body: b.filter(|&b| b != 0)?,
                            radius: r.filter(|r| r.value > 0.0)?,
                            axis: a?,
                            center: ctr?,
                        })
                    })()
                }
                spec::Constraint::Holonomic { expr, .. } => {
                    let epath = join(&path, &[f("expr")]);
                    let q = self.quantity(&Num::Expr(expr.clone()), &epath, Scope::State);
                    if let Some(q) = &q {
                        let uses_q = q
                            .expr
                            .names()
                            .iter()
                            .any(|(n, _)| self.state_names.get(*n) == Some(&"coordinate"));
                        if !uses_q {
                            self.error(
                                &epath,
                                format!("constraint `{name}` does not depend on any coordinate"),
                                "a holonomic constraint restricts positions: write it in terms of coordinate names",
                            );
                        }
                        let uses_speed = q
                            .expr
                            .names()
                            .iter()
                            .find(|(n, _)| {
                                matches!(self.state_names.get(*n), Some(&"speed" | &"input"))
                            })
                            .map(|(n, _)| n.to_string());
                        if let Some(n) = uses_speed {
                            self.error(
                                &epath,
                                format!("holonomic constraint `{name}` uses `{n}`"),
                                "a holonomic constraint may use coordinates, parameters and `t` only",
                            );
                        }
                    }
                    q.map(ConstraintKind::Holonomic)
                }
            };
            match kind {
                Some(kind) => out.push(Constraint {
                    name: name.clone(),
                    kind,
                    span: self.span(&path),
                }),
                None => ok = false,
            }
        }
        ok.then_some(out)
    }
}
