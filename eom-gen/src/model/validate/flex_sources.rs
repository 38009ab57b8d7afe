//! Validation of the flexible bodies that are not the built-in beam's normal
//! modes: assumed modes (shape expressions of `x`), imported modal data (a
//! file next to the model), and a beam's `Fixed([...])` reference
//! conditions. Each problem is reported at its field (a modal file's
//! problems at the model's `file` field, with their `file:line:col` in the
//! modal file).

use super::{Ctx, Scope, f, i, join};
use crate::diag::{Diagnostic, Span};
use crate::expr::Ast;
use crate::flex::assumed::{AssumedError, Part, ShapeExprs, assumed_modes};
use crate::flex::imported;
use crate::flex::ritz::RitzError;
use crate::flex::{Beam, Dof, NodeDof, Reference};
use crate::model::locate::{Seg, string_contents_start};
use crate::model::spec::{self, Num};
use crate::system::{FlexInfo, FlexSource, Quantity};
use nalgebra::Vector3;

type Path = Vec<Seg<'static>>;

/// Relative difference between an imported file's modal mass and the lumped
/// one above which `check` warns.
const MODAL_MASS_TOL: f64 = 0.01;

/// The section fields shared by the beam and assumed modes:
/// (field, unit, what).
const SECTION: [(&str, &str, &str); 7] = [
    ("length", "m", "length"),
    ("rho_a", "kg/m", "mass per length"),
    ("rho_ip", "kg m", "polar mass moment per length"),
    ("ea", "N", "axial stiffness"),
    ("ei_y", "N m²", "bending stiffness"),
    ("ei_z", "N m²", "bending stiffness"),
    ("gj", "N m²", "torsional stiffness"),
];

/// A shape part: its expression and first two derivatives in `x`.
struct Parsed {
    d: [Ast; 3],
}

impl Ctx<'_> {
    /// A flexible body given by assumed modes or imported modal data.
    pub(super) fn flexible_source(
        &mut self,
        flex: &spec::Flexible,
        body: &str,
        path: &[Seg<'static>],
    ) -> Option<Box<FlexInfo>> {
        let fpath = join(path, &[f("flexible")]);
        match flex {
            spec::Flexible::Beam { .. } => None,
            spec::Flexible::AssumedModes {
                length,
                rho_a,
                rho_ip,
                ea,
                ei_y,
                ei_z,
                gj,
                shapes,
                stiffening,
                damping,
                nodes,
            } => self.assumed(
                [length, rho_a, rho_ip, ea, ei_y, ei_z, gj],
                shapes,
                nodes,
                *stiffening,
                damping,
                body,
                path,
                &fpath,
            ),
            spec::Flexible::Modal {
                file,
                damping,
                stiffening,
            } => self.modal(file, damping, *stiffening, body, path, &fpath),
        }
    }

    /// `Fixed([...])` reference conditions of a beam: nodes checked at
    /// their field (the frame's definiteness is checked with the modes).
    pub(super) fn fixed_reference(
        &mut self,
        nodes: &[spec::FixedNode],
        elements: usize,
        body: &str,
        fpath: &[Seg<'static>],
    ) -> Option<Reference> {
        let mut dofs = Vec::new();
        let mut ok = true;
        for (n, fixed) in nodes.iter().enumerate() {
            if fixed.node > elements {
                ok = false;
                self.error(
                    &join(fpath, &[f("reference"), i(0), i(n), f("node")]),
                    format!(
                        "flexible body `{body}`: reference node {} does not exist: the beam has nodes 0..={elements}",
                        fixed.node
                    ),
                    format!("node i sits at x = i·length/{elements}; use a node from 0 to {elements}"),
                );
            }
            for d in &fixed.dofs {
                let dof = match d {
                    spec::NodeDofName::Ux => NodeDof::Ux,
                    spec::NodeDofName::Uy => NodeDof::Uy,
                    spec::NodeDofName::Uz => NodeDof::Uz,
                    spec::NodeDofName::Rx => NodeDof::Rx,
                    spec::NodeDofName::Ry => NodeDof::Ry,
                    spec::NodeDofName::Rz => NodeDof::Rz,
                };
                dofs.push(Dof {
                    node: fixed.node,
                    dof,
                });
            }
        }
        ok.then_some(Reference::Fixed(dofs))
    }

    /// The seven section numbers, each positive.
    fn section(
        &mut self,
        nums: [&Num; 7],
        body: &str,
        fpath: &[Seg<'static>],
    ) -> Option<Vec<Quantity>> {
        let mut written = Vec::new();
        for ((name, unit, what), num) in SECTION.into_iter().zip(nums) {
            let at = join(fpath, &[f(name)]);
            let q = self.quantity(num, &at, Scope::Params);
            if let Some(q) = &q
                && q.value <= 0.0
            {
                self.error(
                    &at,
                    format!(
                        "{what} `{name}` of flexible body `{body}` is {} {unit}",
                        q.value
                    ),
                    format!("a slender body needs a positive {what} ({unit})"),
                );
                continue;
            }
            written.extend(q);
        }
        (written.len() == 7).then_some(written)
    }

    /// A shape expression of `x` and the parameters, and its derivatives.
    fn shape_expr(&mut self, num: &Num, at: &[Seg<'static>]) -> Option<(Parsed, Quantity)> {
        let span = self.span(at);
        let (ast, base) = match num {
            Num::Value(v) => (Ast::Num(*v), None),
            Num::Expr(text) => {
                let base = string_contents_start(&self.src.text, span);
                match Ast::parse(text) {
                    Ok(a) => (a, Some(base)),
                    Err(e) => {
                        let s = Span::new(base + e.offset, base + e.offset + 1);
                        self.diags.push(
                            Diagnostic::error(s, format!("in expression `{text}`: {}", e.message))
                                .with_help(e.help),
                        );
                        return None;
                    }
                }
            }
        };
        let mut ok = true;
        for (name, offset) in ast.names() {
            if name == "x" || name == "pi" || self.param_value(name).is_some() {
                continue;
            }
            ok = false;
            let s = base.map_or(span, |b| Span::new(b + offset, b + offset + name.len()));
            self.diags.push(
                Diagnostic::error(s, format!("unknown name `{name}` in a shape function"))
                    .with_help(
                        "a shape function may use the body coordinate `x` (m), `pi` and parameters",
                    ),
            );
        }
        if !ok {
            return None;
        }
        let d1 = ast.diff("x");
        let d2 = d1.diff("x");
        let q = Quantity {
            expr: ast.clone(),
            value: f64::NAN,
            span,
        };
        Some((Parsed { d: [ast, d1, d2] }, q))
    }

    #[allow(clippy::too_many_arguments)]
    fn assumed(
        &mut self,
        nums: [&Num; 7],
        shapes: &[spec::AssumedShape],
        nodes: &[spec::BeamNode],
        stiffening: bool,
        damping: &Num,
        body: &str,
        path: &[Seg<'static>],
        fpath: &Path,
    ) -> Option<Box<FlexInfo>> {
        let written = self.section(nums, body, fpath);
        let zeta = self.nonnegative(
            damping,
            &join(fpath, &[f("damping")]),
            "damping ratio",
            body,
        );
        let spath = join(fpath, &[f("shapes")]);
        if shapes.is_empty() {
            self.error(
                &spath,
                format!("flexible body `{body}` has no shapes"),
                "give at least one shape, e.g. `(v: \"sin(pi*x/L)\")`",
            );
        }
        let mut parsed: Vec<[Option<Parsed>; 4]> = Vec::new();
        let mut exprs = Vec::new();
        let mut ok = true;
        for (j, s) in shapes.iter().enumerate() {
            let parts = [&s.u, &s.v, &s.w, &s.phi];
            if parts.iter().all(|p| p.is_none()) {
                ok = false;
                self.error(
                    &join(&spath, &[i(j)]),
                    format!("shape {} of flexible body `{body}` is empty", j + 1),
                    "give at least one of `u`, `v`, `w`, `phi` (expressions of `x`)",
                );
            }
            let mut row: [Option<Parsed>; 4] = [None, None, None, None];
            for (p, part) in parts.into_iter().enumerate() {
                if let Some(num) = part {
                    match self.shape_expr(num, &join(&spath, &[i(j), f(Part::ALL[p].name())])) {
                        Some((e, q)) => {
                            row[p] = Some(e);
                            exprs.push(q);
                        }
                        None => ok = false,
                    }
                }
            }
            parsed.push(row);
        }
        let (Some(mut written), Some(zeta)) = (written, zeta) else {
            return None;
        };
        if !ok || shapes.is_empty() {
            return None;
        }
        let v = |k: usize| written[k].value;
        let section = Beam {
            length: v(0),
            rho_a: v(1),
            rho_ip: v(2),
            ea: v(3),
            ei_y: v(4),
            ei_z: v(5),
            gj: v(6),
            elements: 1,
            shear: None,
        };
        let shape = |j: usize, part: Part, order: usize, x: f64| -> Option<f64> {
            match &parsed[j][part as usize] {
                None => Some(0.0),
                Some(p) => p.d[order]
                    .eval(&|n| {
                        if n == "x" {
                            Some(x)
                        } else {
                            self.param_value(n)
                        }
                    })
                    .ok(),
            }
        };
        let result = assumed_modes(&section, shapes.len(), &shape);
        let reduced = match result {
            Ok(r) => r,
            Err(e) => {
                let at = match &e {
                    AssumedError::NotFinite { shape, part, .. } => {
                        join(&spath, &[i(*shape), f(part.name())])
                    }
                    _ => spath.clone(),
                };
                let help = match &e {
                    AssumedError::Reduced(RitzError::RigidMotion(_)) => {
                        "shapes must not contain a rigid motion of the whole body: make them vanish (and, \
                         for a tangent frame, their slope) where the frame is fixed, e.g. `sin(pi*x/L)` \
                         (chord frame) or `(x/L)^2` (clamped at x = 0)"
                    }
                    AssumedError::Reduced(_) => "every shape must be independent of the others",
                    AssumedError::NotFinite { .. } => {
                        "shapes and their first two derivatives must be finite on 0 ≤ x ≤ length"
                    }
                    AssumedError::Unresolved(_) => {
                        "use smooth shapes (polynomials, sines); a kink or a singular derivative cannot be integrated accurately"
                    }
                };
                self.error(&at, format!("flexible body `{body}`: {e}"), help);
                return None;
            }
        };
        // The shapes as functions of x alone, for sections and attachments.
        let fixed = |a: &Ast| {
            a.substitute(&|n| {
                if n == "x" {
                    None
                } else {
                    self.param_value(n).map(Ast::Num)
                }
            })
        };
        let shape_exprs: Vec<ShapeExprs> = parsed
            .iter()
            .map(|row| ShapeExprs {
                parts: std::array::from_fn(|p| {
                    row[p].as_ref().map(|e| [fixed(&e.d[0]), fixed(&e.d[1])])
                }),
            })
            .collect();
        let mut modes = reduced.modes();
        let (named, node_x, at_nodes) =
            self.assumed_nodes(nodes, &section, &shape_exprs, body, fpath)?;
        modes.shapes = at_nodes;
        let (coordinate_names, speed_names) = self.elastic_names(body, path, modes.count())?;
        written.extend(exprs);
        Some(Box::new(FlexInfo {
            nodes: named,
            written,
            shares: Some(reduced.shares.clone()),
            source: FlexSource::Assumed {
                shapes: shape_exprs,
                node_x,
                geometric: reduced.geometric.clone(),
                axial_geometric: reduced.axial_geometric.clone(),
                damping_unit: reduced.ritz.damping_unit.clone(),
            },
            beam: section,
            reference: Reference::Fixed(Vec::new()),
            modes,
            invariants: reduced.invariants,
            damping: zeta,
            stiffening,
            coordinate_names,
            speed_names,
            q_index: 0,
            u_index: 0,
            span: self.span(fpath),
        }))
    }

    /// The named nodes of an assumed-modes body: unique names, each on the
    /// axis (`0 ≤ x ≤ length`), as `(name, node index)`, their places, and
    /// the shapes there (`6N × k`: `u, v, w, φ, −w', v'` per node).
    #[allow(clippy::type_complexity)]
    fn assumed_nodes(
        &mut self,
        named: &[spec::BeamNode],
        section: &Beam,
        shapes: &[ShapeExprs],
        body: &str,
        fpath: &[Seg<'static>],
    ) -> Option<(Vec<(String, usize)>, Vec<f64>, nalgebra::DMatrix<f64>)> {
        let k = shapes.len();
        let mut out: Vec<(String, usize)> = Vec::new();
        let mut places = Vec::new();
        let mut columns = nalgebra::DMatrix::zeros(6 * named.len(), k);
        let mut ok = true;
        let l = section.length;
        for (n, node) in named.iter().enumerate() {
            let npath = join(fpath, &[f("nodes"), i(n)]);
            if out.iter().any(|(m, _)| *m == node.name) {
                self.error(
                    &join(&npath, &[f("name")]),
                    format!("node `{}` is named twice on body `{body}`", node.name),
                    "node names must be unique on their body",
                );
                ok = false;
                continue;
            }
            let xpath = join(&npath, &[f("x")]);
            let Some(x) = self.quantity(&node.x, &xpath, Scope::Params) else {
                ok = false;
                continue;
            };
            let x = x.value;
            if !(0.0..=l).contains(&x) {
                self.error(
                    &xpath,
                    format!(
                        "node `{}` of flexible body `{body}` at x = {x} m is not on the body, which runs from 0 to {l} m",
                        node.name
                    ),
                    format!("give 0 ≤ x ≤ {l}"),
                );
                ok = false;
                continue;
            }
            let Some(at) = crate::flex::assumed::section(shapes, x) else {
                self.error(
                    &xpath,
                    format!(
                        "the shapes of flexible body `{body}` or their slopes are not finite at node `{}` (x = {x} m)",
                        node.name
                    ),
                    "shapes and their first derivatives must be finite where a node sits",
                );
                ok = false;
                continue;
            };
            let row = 6 * out.len();
            for j in 0..k {
                for r in 0..3 {
                    columns[(row + r, j)] = at.translation[(r, j)];
                    columns[(row + 3 + r, j)] = at.rotation[(r, j)];
                }
            }
            out.push((node.name.clone(), out.len()));
            places.push(x);
        }
        ok.then(|| {
            let rows = 6 * out.len();
            (out, places, columns.rows(0, rows).into_owned())
        })
    }

    fn modal(
        &mut self,
        file: &str,
        damping: &Num,
        stiffening: bool,
        body: &str,
        path: &[Seg<'static>],
        fpath: &Path,
    ) -> Option<Box<FlexInfo>> {
        let zeta = self.nonnegative(
            damping,
            &join(fpath, &[f("damping")]),
            "damping ratio",
            body,
        );
        let at = join(fpath, &[f("file")]);
        let shown = std::path::Path::new(&self.src.path)
            .parent()
            .unwrap_or(std::path::Path::new(""))
            .join(file);
        let shown_str = shown.display().to_string();
        let text = match std::fs::read_to_string(self.dir.join(&shown)) {
            Ok(t) => t,
            Err(e) => {
                self.error(
                    &at,
                    format!("flexible body `{body}`: cannot read modal file `{file}` (`{shown_str}`): {e}"),
                    "`file` is the path of a `.ron` or `.json` modal data file, relative to this model file",
                );
                return None;
            }
        };
        let data = match imported::parse(&shown_str, &text) {
            Ok(d) => d,
            Err(e) => {
                self.error(
                    &at,
                    format!("flexible body `{body}`: {}", e.located(&shown_str)),
                    e.help,
                );
                return None;
            }
        };
        let body_data = match imported::build(&data, &text) {
            Ok(b) => b,
            Err(errors) => {
                for e in errors {
                    self.error(
                        &at,
                        format!("flexible body `{body}`: {}", e.located(&shown_str)),
                        e.help,
                    );
                }
                return None;
            }
        };
        let zeta = zeta?;
        if stiffening && body_data.geometric.is_none() {
            self.error(
                &join(fpath, &[f("stiffening")]),
                format!(
                    "flexible body `{body}` asks for geometric stiffening, but modal file `{file}` has no `geometric_stiffness`"
                ),
                "add `geometric_stiffness: (centrifugal: […], axial: […])` to the modal file (`examples/modal_export.py --geometric-centrifugal … --geometric-axial …`), or leave out `stiffening`",
            );
            return None;
        }
        if let Some(d) = body_data.modal_mass_mismatch()
            && d > MODAL_MASS_TOL
        {
            self.warning(
                &at,
                format!(
                    "flexible body `{body}`: the lumped nodal masses give a modal mass that differs from the file's `modal_mass` by {:.1} % (of its largest entry); eom uses the lumped one",
                    100.0 * d
                ),
                "the frequencies follow the lumped mass: refine the FE mesh (the difference falls as h²) or check the nodal masses and mode shapes",
            );
        }
        let modes = body_data.modes();
        let (coordinate_names, speed_names) = self.elastic_names(body, path, modes.count())?;
        // A placeholder beam spanning the nodes along x (see `FlexInfo::beam`).
        let extent = body_data
            .positions
            .iter()
            .map(|p| p.x)
            .fold(0.0_f64, f64::max);
        let length = if extent > 0.0 { extent } else { 1.0 };
        let inv = body_data.invariants;
        let beam = Beam {
            length,
            rho_a: inv.mass / length,
            rho_ip: 0.0,
            ea: 0.0,
            ei_y: 0.0,
            ei_z: 0.0,
            gj: 0.0,
            elements: body_data.positions.len().saturating_sub(1).max(1),
            shear: None,
        };
        let positions: Vec<Vector3<f64>> = body_data.positions;
        let named: Vec<(String, usize)> = body_data
            .names
            .iter()
            .enumerate()
            .filter_map(|(i, n)| n.clone().map(|n| (n, i)))
            .collect();
        Some(Box::new(FlexInfo {
            nodes: named,
            written: Vec::new(),
            shares: None,
            source: FlexSource::Modal {
                path: shown_str,
                positions,
                names: body_data.names,
                damping_unit: body_data.ritz.damping_unit.clone(),
                damping: body_data.damping,
                geometric: body_data.geometric,
            },
            beam,
            reference: Reference::Fixed(Vec::new()),
            modes,
            invariants: inv,
            damping: zeta,
            stiffening,
            coordinate_names,
            speed_names,
            q_index: 0,
            u_index: 0,
            span: self.span(fpath),
        }))
    }
}
