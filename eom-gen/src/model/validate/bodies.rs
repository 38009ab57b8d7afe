//! Rigid bodies: names, markers, mass and inertia (a tensor about the
//! centre of mass, checked for symmetry, positive definiteness and the
//! triangle inequalities, or warned about when lenient).

use super::{Ctx, Scope, TOL, f, i, is_ident, join};
use crate::diag::Span;
use crate::expr::Ast;
use crate::model::locate::Seg;
use crate::model::spec::{self, Spec};
use crate::system::*;
use nalgebra::{Matrix3, SymmetricEigen};
use std::collections::{HashMap, HashSet};

impl Ctx<'_> {
    pub(super) fn bodies(&mut self, spec: &Spec) -> Vec<BodyInfo> {
        let mut bodies = vec![BodyInfo {
            name: "ground".into(),
            label: None,
            mass: None,
            com: None,
            inertia: None,
            markers: Vec::new(),
            flexible: None,
            geometry: Vec::new(),
            span: Span::default(),
        }];
        bodies[0].geometry =
            self.geometries(&spec.ground_geometry, &[f("ground_geometry")], "ground");
        let mut seen: HashMap<&str, usize> = HashMap::new();
        for (k, b) in spec.bodies.iter().enumerate() {
            let path = [f("bodies"), i(k)];
            let name_path = join(&path, &[f("name")]);
            if b.name == "ground" {
                self.error(
                    &name_path,
                    "`ground` is the inertial body and cannot be defined".into(),
                    "refer to it as a joint's `parent` without listing it; rename this body",
                );
            } else if !is_ident(&b.name) {
                self.error(
                    &name_path,
                    format!("body name `{}` is not an identifier", b.name),
                    "use letters, digits and `_`, starting with a letter or `_`",
                );
            } else if let Some(prev) = seen.insert(&b.name, k) {
                self.error(
                    &name_path,
                    format!("body `{}` is defined twice", b.name),
                    format!(
                        "the first definition is body number {}; rename one of them",
                        prev + 1
                    ),
                );
            }
            let flexible = b
                .flexible
                .as_ref()
                .and_then(|fl| self.flexible(fl, &b.name, &path));
            let mass = match &b.mass {
                Some(m) => self.quantity(m, &join(&path, &[f("mass")]), Scope::Params),
                None if b.flexible.is_none() => {
                    self.error(
                        &path,
                        format!("body `{}` has no `mass`", b.name),
                        "give a rigid body its mass in kg (`mass: 1.0`); only a flexible body may leave it out",
                    );
                    None
                }
                None => None,
            };
            if let Some(m) = &mass
                && (m.value < 0.0 || (m.value == 0.0 && !self.lenient && b.flexible.is_none()))
            {
                self.error(
                    &join(&path, &[f("mass")]),
                    format!("mass of body `{}` is {} kg", b.name, m.value),
                    "a body needs a positive mass; model a massless link by placing the next joint's frame on the previous body",
                );
            }
            let com = self.vec3(&b.com, &join(&path, &[f("com")]), Scope::Params);
            let inertia = b
                .inertia
                .as_ref()
                .and_then(|ine| self.inertia(ine, &b.name, &join(&path, &[f("inertia")])));
            let mut markers = Vec::new();
            let mut marker_names = HashSet::new();
            for (m, marker) in b.markers.iter().enumerate() {
                let mpath = join(&path, &[f("markers"), i(m)]);
                if !marker_names.insert(marker.name.as_str()) {
                    self.error(
                        &join(&mpath, &[f("name")]),
                        format!(
                            "marker `{}` is defined twice on body `{}`",
                            marker.name, b.name
                        ),
                        "marker names must be unique on their body",
                    );
                }
                let frame = spec::Frame {
                    position: marker.position.clone(),
                    orientation: marker.orientation.clone(),
                };
                let node = marker.node.as_ref().map(|node| {
                    self.node_ref(
                        node,
                        &b.name,
                        b.flexible.as_ref(),
                        flexible.as_deref(),
                        &join(&mpath, &[f("node")]),
                        &format!("marker `{}`", marker.name),
                    )
                });
                if node == Some(None) {
                    self.failed_markers
                        .insert((b.name.clone(), marker.name.clone()));
                    continue;
                }
                match self.frame(&frame, &mpath) {
                    Some(frame) => markers.push(MarkerInfo {
                        name: marker.name.clone(),
                        frame,
                        node: node.flatten(),
                    }),
                    None => {
                        self.failed_markers
                            .insert((b.name.clone(), marker.name.clone()));
                    }
                }
            }
            bodies.push(BodyInfo {
                name: b.name.clone(),
                label: b.label.clone(),
                mass,
                com,
                inertia,
                markers,
                flexible,
                geometry: self.geometries(&b.geometry, &join(&path, &[f("geometry")]), &b.name),
                span: self.span(&path),
            });
        }
        bodies
    }

    pub(super) fn inertia(
        &mut self,
        ine: &spec::Inertia,
        body: &str,
        path: &[Seg<'static>],
    ) -> Option<[Vec3Q; 3]> {
        let rows = match ine {
            spec::Inertia::Diag(a, b, c) => {
                let d = [
                    self.quantity(a, &join(path, &[i(0)]), Scope::Params),
                    self.quantity(b, &join(path, &[i(1)]), Scope::Params),
                    self.quantity(c, &join(path, &[i(2)]), Scope::Params),
                ];
                let [Some(a), Some(b), Some(c)] = d else {
                    return None;
                };
                let zero = |s: Span| Quantity {
                    expr: Ast::Num(0.0),
                    value: 0.0,
                    span: s,
                };
                let (sa, sb, sc) = (a.span, b.span, c.span);
                [
                    [a, zero(sa), zero(sa)],
                    [zero(sb), b, zero(sb)],
                    [zero(sc), zero(sc), c],
                ]
            }
            spec::Inertia::Matrix(a, b, c) => {
                let rows = [
                    self.vec3(a, &join(path, &[i(0)]), Scope::Params),
                    self.vec3(b, &join(path, &[i(1)]), Scope::Params),
                    self.vec3(c, &join(path, &[i(2)]), Scope::Params),
                ];
                let [Some(a), Some(b), Some(c)] = rows else {
                    return None;
                };
                [a, b, c]
            }
        };
        let m = Matrix3::from_fn(|r, c| rows[r][c].value);
        let scale = m.amax().max(f64::MIN_POSITIVE);
        let asym = (m - m.transpose()).amax();
        if asym > TOL * scale {
            self.error(
                path,
                format!("inertia of body `{body}` is not symmetric (largest |I_ij − I_ji| = {asym:.3e})"),
                "an inertia tensor is symmetric: make the entry below the diagonal equal the one above it",
            );
            return None;
        }
        let mut eig: Vec<f64> = SymmetricEigen::new(m).eigenvalues.iter().copied().collect();
        eig.sort_by(f64::total_cmp);
        if eig[0] < -TOL * scale {
            if self.lenient {
                self.warning(
                    path,
                    format!(
                        "inertia of body `{body}` is not positive semi-definite (principal moments {:.6}, {:.6}, {:.6})",
                        eig[0], eig[1], eig[2]
                    ),
                    "kept as written (`inertia_policy: Lenient`): the mass matrix is checked instead; principal moments of inertia cannot be negative",
                );
                return Some(rows);
            }
            self.error(
                path,
                format!(
                    "inertia of body `{body}` is not positive semi-definite (principal moments {:.6}, {:.6}, {:.6})",
                    eig[0], eig[1], eig[2]
                ),
                "principal moments of inertia cannot be negative; check signs (off-diagonal entries are tensor entries, minus the products of inertia)",
            );
            return None;
        }
        if eig[0] + eig[1] < eig[2] - TOL * scale {
            if self.lenient {
                self.warning(
                    path,
                    format!(
                        "inertia of body `{body}` violates the triangle inequality: {:.6} + {:.6} < {:.6}",
                        eig[0], eig[1], eig[2]
                    ),
                    "kept as written (`inertia_policy: Lenient`): no mass distribution has these principal moments",
                );
                return Some(rows);
            }
            self.error(
                path,
                format!(
                    "inertia of body `{body}` violates the triangle inequality: {:.6} + {:.6} < {:.6}",
                    eig[0], eig[1], eig[2]
                ),
                "no mass distribution has these principal moments: each must be at most the sum of the other two",
            );
            return None;
        }
        Some(rows)
    }
}
