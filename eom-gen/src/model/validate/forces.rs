//! Force elements: spring-dampers between anchors, joint springs, joint
//! forces and actuators with their input names.

use super::{Ctx, Scope, f, i, join};
use crate::diag::list_names;
use crate::expr::Ast;
use crate::model::locate::Seg;
use crate::model::spec::{self, Spec};
use crate::system::*;
use std::collections::HashSet;

impl Ctx<'_> {
    pub(super) fn anchor(
        &mut self,
        a: &spec::Anchor,
        bodies: &[BodyInfo],
        path: &[Seg<'static>],
    ) -> Option<Point> {
        if let Some(node) = a.node {
            self.error(
                &join(path, &[f("node")]),
                format!("anchor on `{}` names a cable node ({node})", a.body),
                "a cable node is the marker of a contact (`Plane`'s `at`) only: anchor on a body's point or marker here",
            );
            return None;
        }
        let body = self.body_ref(bodies, &a.body, &join(path, &[f("body")]), "anchor")?;
        match (&a.point, &a.marker) {
            (Some(_), Some(_)) => {
                self.error(
                    path,
                    "an anchor has both `point` and `marker`".into(),
                    "give one of them",
                );
                None
            }
            (Some(p), None) => Some(Point {
                body,
                position: self.vec3(p, &join(path, &[f("point")]), Scope::Params)?,
                node: None,
            }),
            (None, Some(m)) => {
                let Some(marker) = bodies[body].markers.iter().find(|x| &x.name == m) else {
                    if self.failed_markers.contains(&(a.body.clone(), m.clone())) {
                        return None;
                    }
                    let names = bodies[body].markers.iter().map(|x| x.name.as_str());
                    self.error(
                        &join(path, &[f("marker")]),
                        format!("body `{}` has no marker `{m}`", a.body),
                        format!("its markers are {}", list_names(names)),
                    );
                    return None;
                };
                Some(Point {
                    body,
                    position: marker.frame.position.clone(),
                    node: marker.node,
                })
            }
            (None, None) => {
                let zero = Quantity {
                    expr: Ast::Num(0.0),
                    value: 0.0,
                    span: self.span(path),
                };
                Some(Point {
                    body,
                    position: [zero.clone(), zero.clone(), zero],
                    node: None,
                })
            }
        }
    }

    pub(super) fn forces(
        &mut self,
        spec: &Spec,
        bodies: &[BodyInfo],
        joints: &[JointInfo],
    ) -> (Option<Vec<Force>>, Vec<String>) {
        let mut out = Vec::new();
        let mut inputs = Vec::new();
        let mut ok = true;
        let mut names = HashSet::new();
        for (k, force) in spec.forces.iter().enumerate() {
            let path = [f("forces"), i(k)];
            let name = match force {
                spec::Force::SpringDamper { name, .. }
                | spec::Force::JointSpringDamper { name, .. }
                | spec::Force::JointForce { name, .. }
                | spec::Force::Actuator { name, .. } => name,
            };
            if !names.insert(name.as_str()) {
                self.error(
                    &join(&path, &[f("name")]),
                    format!("force `{name}` is defined twice"),
                    "force names must be unique",
                );
            }
            let element = match force {
                spec::Force::SpringDamper {
                    a,
                    b,
                    stiffness,
                    damping,
                    rest_length,
                    ..
                } => {
                    let a = self.anchor(a, bodies, &join(&path, &[f("a")]));
                    let b = self.anchor(b, bodies, &join(&path, &[f("b")]));
                    let k =
                        self.quantity(stiffness, &join(&path, &[f("stiffness")]), Scope::Params);
                    let c =
                        self.nonnegative(damping, &join(&path, &[f("damping")]), "damping", name);
                    let l = self.nonnegative(
                        rest_length,
                        &join(&path, &[f("rest_length")]),
                        "rest length",
                        name,
                    );
                    (|| {
                        Some(ForceElement::SpringDamper {
                            a: a?,
                            b: b?,
                            stiffness: k?,
                            damping: c?,
                            rest_length: l?,
                        })
                    })()
                }
                spec::Force::JointSpringDamper {
                    joint,
                    stiffness,
                    damping,
                    rest,
                    ..
                } => {
                    let jp = join(&path, &[f("joint")]);
                    let j = self.driven_joint(joints, joint, &jp, "a joint spring-damper");
                    if let Some(j) = j
                        && matches!(joints[j].kind, JointType::Spherical | JointType::Free)
                    {
                        self.error(
                            &jp,
                            format!("a joint spring-damper on {} joint `{joint}` is not supported", joints[j].kind.name()),
                            "its coordinates include a quaternion; use point-to-point spring-dampers instead",
                        );
                        ok = false;
                    }
                    let k =
                        self.quantity(stiffness, &join(&path, &[f("stiffness")]), Scope::Params);
                    let c =
                        self.nonnegative(damping, &join(&path, &[f("damping")]), "damping", name);
                    let r = self.quantity(rest, &join(&path, &[f("rest")]), Scope::Params);
                    (|| {
                        Some(ForceElement::JointSpringDamper {
                            joint: j?,
                            stiffness: k?,
                            damping: c?,
                            rest: r?,
                        })
                    })()
                }
                spec::Force::JointForce { joint, values, .. } => {
                    let j = self.driven_joint(
                        joints,
                        joint,
                        &join(&path, &[f("joint")]),
                        "a joint force",
                    );
                    let vpath = join(&path, &[f("values")]);
                    match j {
                        Some(j) if values.len() != joints[j].kind.nu() => {
                            self.error(
                                &vpath,
                                format!(
                                    "joint `{joint}` has {} speed(s) but {} force value(s) are given",
                                    joints[j].kind.nu(),
                                    values.len()
                                ),
                                format!("give one generalised force per speed: {}", list_names(joints[j].speed_names.iter().map(String::as_str))),
                            );
                            None
                        }
                        Some(j) => {
                            let v: Vec<Option<Quantity>> = values
                                .iter()
                                .enumerate()
                                .map(|(k, v)| {
                                    self.quantity(v, &join(&vpath, &[i(k)]), Scope::State)
                                })
                                .collect();
                            v.into_iter()
                                .collect::<Option<Vec<_>>>()
                                .map(|values| ForceElement::JointForce { joint: j, values })
                        }
                        None => None,
                    }
                }
                spec::Force::Actuator {
                    joint,
                    inputs: given,
                    ..
                } => {
                    let j = self.driven_joint(
                        joints,
                        joint,
                        &join(&path, &[f("joint")]),
                        "an actuator",
                    );
                    match j {
                        Some(j) => {
                            let nu = joints[j].kind.nu();
                            let default = if nu == 1 {
                                vec![name.clone()]
                            } else {
                                (1..=nu).map(|k| format!("{name}_{k}")).collect()
                            };
                            let names = self.input_names(
                                given.as_ref(),
                                default,
                                &join(&path, &[f("inputs")]),
                                nu,
                                name,
                            );
                            names.map(|names| {
                                let first = inputs.len();
                                inputs.extend(names);
                                ForceElement::Actuator {
                                    joint: j,
                                    inputs: (first..inputs.len()).map(Some).collect(),
                                }
                            })
                        }
                        None => None,
                    }
                }
            };
            match element {
                Some(element) => out.push(Force {
                    name: name.clone(),
                    element,
                    span: self.span(&path),
                }),
                None => ok = false,
            }
        }
        (ok.then_some(out), inputs)
    }

    pub(super) fn input_names(
        &mut self,
        given: Option<&Vec<String>>,
        default: Vec<String>,
        path: &[Seg<'static>],
        count: usize,
        actuator: &str,
    ) -> Option<Vec<String>> {
        let names = match given {
            Some(n) if n.len() != count => {
                self.error(
                    path,
                    format!("actuator `{actuator}` drives {count} speed(s) but {} input name(s) are given", n.len()),
                    format!("give {count} name(s), or leave `inputs` out"),
                );
                return None;
            }
            Some(n) => n.clone(),
            None => default,
        };
        let mut ok = true;
        for (k, n) in names.iter().enumerate() {
            let at = if given.is_some() {
                join(path, &[i(k)])
            } else {
                path.to_vec()
            };
            if self.check_symbol_name(n, &at, "input") {
                self.state_names.insert(n.clone(), "input");
            } else {
                ok = false;
            }
        }
        ok.then_some(names)
    }
}
