//! Flexible bodies: the beam (mesh, section, shear), the reference
//! conditions and modes, elastic coordinates, and references to their
//! nodes (by index or name, on beams, assumed modes and modal data; the
//! other shape sources in `flex_sources`).

use super::{Ctx, Scope, f, i, join};
use crate::diag::{did_you_mean, list_names};
use crate::model::locate::Seg;
use crate::model::spec::{self, Num};
use crate::system::*;

/// A beam's named nodes, `(name, node index)`.
type NamedNodes = Vec<(String, usize)>;

impl Ctx<'_> {
    /// A flexible body's beam: its numbers checked, its modes and inertia
    /// shape integrals computed at the defaults, its elastic coordinates
    /// named (`<body>_f1 …`, rates `<body>_f1_dot …`).
    pub(super) fn flexible(
        &mut self,
        flex: &spec::Flexible,
        body: &str,
        path: &[Seg<'static>],
    ) -> Option<Box<FlexInfo>> {
        let spec::Flexible::Beam {
            length,
            rho_a,
            rho_ip,
            ea,
            ei_y,
            ei_z,
            gj,
            elements,
            reference,
            modes,
            stiffening,
            damping,
            nodes: named_nodes,
            craig_bampton,
            shear,
        } = flex
        else {
            return self.flexible_source(flex, body, path);
        };
        let fpath = join(path, &[f("flexible")]);
        let fields: [(&'static str, &Num, &str, &str); 7] = [
            ("length", length, "m", "length"),
            ("rho_a", rho_a, "kg/m", "mass per length"),
            ("rho_ip", rho_ip, "kg m", "polar mass moment per length"),
            ("ea", ea, "N", "axial stiffness"),
            ("ei_y", ei_y, "N m²", "bending stiffness"),
            ("ei_z", ei_z, "N m²", "bending stiffness"),
            ("gj", gj, "N m²", "torsional stiffness"),
        ];
        let mut written = Vec::new();
        for (name, num, unit, what) in fields {
            let at = join(&fpath, &[f(name)]);
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
                    format!("a beam needs a positive {what} ({unit})"),
                );
                continue;
            }
            written.extend(q);
        }
        if *elements == 0 {
            self.error(
                &join(&fpath, &[f("elements")]),
                format!("flexible body `{body}` has no elements"),
                "a beam needs at least one finite element; a few per mode kept is typical",
            );
        }
        if *modes == 0 && (!*craig_bampton || named_nodes.is_empty()) {
            self.error(
                &join(&fpath, &[f("modes")]),
                format!("flexible body `{body}` keeps no modes"),
                "keep at least one mode, or leave out `flexible` to make the body rigid",
            );
        }
        let damping = self.nonnegative(
            damping,
            &join(&fpath, &[f("damping")]),
            "damping ratio",
            body,
        );
        let sheared = match shear {
            None => Some(None),
            Some(sh) => self
                .beam_shear(sh, &written, *stiffening, body, &fpath)
                .map(Some),
        };
        let (true, Some(damping), Some(sheared)) = (written.len() == 7, damping, sheared) else {
            return None;
        };
        let (shear, shear_written) = match sheared {
            Some((sh, q)) => (Some(sh), q),
            None => (None, Vec::new()),
        };
        if *craig_bampton && named_nodes.is_empty() {
            self.error(
                &join(&fpath, &[f("craig_bampton")]),
                format!("flexible body `{body}` asks for Craig–Bampton modes but names no nodes"),
                "the boundary of a Craig–Bampton basis is the named nodes: add `nodes: [(name: \"tip\", x: …)]`, or leave out `craig_bampton`",
            );
            return None;
        }
        if *elements == 0 || (*modes == 0 && !*craig_bampton) {
            return None;
        }
        let (nodes, places) = self.beam_nodes(named_nodes, &written[0], *elements, body, &fpath)?;
        let beam = crate::flex::Beam {
            length: written[0].value,
            rho_a: written[1].value,
            rho_ip: written[2].value,
            ea: written[3].value,
            ei_y: written[4].value,
            ei_z: written[5].value,
            gj: written[6].value,
            elements: *elements,
            shear,
        };
        written.extend(shear_written);
        let reference = match reference {
            spec::BeamReference::Clamped => crate::flex::Reference::Clamped,
            spec::BeamReference::PinnedPinned => crate::flex::Reference::PinnedPinned,
            spec::BeamReference::MeanAxis => crate::flex::Reference::MeanAxis,
            spec::BeamReference::Fixed(nodes) => {
                self.fixed_reference(nodes, *elements, body, &fpath)?
            }
        };
        let reduced = if *craig_bampton {
            let boundary: Vec<usize> = nodes.iter().map(|(_, n)| *n).collect();
            crate::flex::craig_bampton(&beam, &reference, &boundary, *modes)
        } else {
            crate::flex::normal_modes(&beam, &reference, *modes)
        };
        let reduced = match reduced {
            Ok(m) => m,
            Err(e) => {
                use crate::flex::FlexError;
                let (field, help) = match &e {
                    FlexError::TooManyModes { .. } => (
                        "modes",
                        "each element adds six nodal degrees of freedom".to_string(),
                    ),
                    FlexError::FrameUndefined(_) | FlexError::NeedsNodalReference => (
                        "reference",
                        "`Clamped`, `PinnedPinned` and `MeanAxis` each fix the frame".to_string(),
                    ),
                    _ => ("elements", "check the beam's data".to_string()),
                };
                self.error(
                    &join(&fpath, &[f(field)]),
                    format!("flexible body `{body}`: {e}"),
                    help,
                );
                return None;
            }
        };
        let invariants = crate::flex::Invariants::new(&beam, &reduced);
        let shares = crate::flex::invariants::Shares::of_beam(&beam, &reduced);
        let (coordinate_names, speed_names) = self.elastic_names(body, path, reduced.count())?;
        // After the seven section data, the nodes' places (none may be tunable).
        written.extend(places);
        Some(Box::new(FlexInfo {
            written,
            shares: Some(shares),
            source: crate::system::FlexSource::Beam,
            beam,
            reference,
            modes: reduced,
            invariants,
            damping,
            stiffening: *stiffening,
            nodes,
            coordinate_names,
            speed_names,
            q_index: 0,
            u_index: 0,
            span: self.span(&fpath),
        }))
    }

    /// A beam's Timoshenko data (`shear`), checked: positive shear
    /// stiffnesses, rotary inertias zero or positive (absent: `ρA EI / EA`
    /// of a homogeneous section, from `written`, the seven beam numbers when
    /// all are valid), and no stiffening. The data and the quantities as
    /// written, or `None` when something is wrong (reported).
    pub(super) fn beam_shear(
        &mut self,
        shear: &spec::BeamShear,
        written: &[Quantity],
        stiffening: bool,
        body: &str,
        fpath: &[Seg<'static>],
    ) -> Option<(crate::flex::beam::Shear, Vec<Quantity>)> {
        let spec::BeamShear::Timoshenko {
            kga_y,
            kga_z,
            rho_iy,
            rho_iz,
        } = shear;
        let spath = join(fpath, &[f("shear")]);
        let mut ok = true;
        if stiffening {
            self.error(
                &join(fpath, &[f("stiffening")]),
                format!(
                    "flexible body `{body}` asks for geometric stiffening of a Timoshenko beam (`shear`)"
                ),
                "stiffening is only built for Euler–Bernoulli beams: with shear the axial load's \
                 geometric stiffness is not unique (Engesser's and Haringx's forms differ), and eom's \
                 foreshortening terms are checked for Euler–Bernoulli only; leave out `stiffening` or `shear`",
            );
            ok = false;
        }
        let mut quantities = Vec::new();
        let mut values = [0.0; 4];
        for (slot, (name, num)) in [("kga_y", kga_y), ("kga_z", kga_z)].into_iter().enumerate() {
            let at = join(&spath, &[f(name)]);
            match self.quantity(num, &at, Scope::Params) {
                Some(q) if q.value <= 0.0 => {
                    self.error(
                        &at,
                        format!(
                            "shear stiffness `{name}` of flexible body `{body}` is {} N",
                            q.value
                        ),
                        "a Timoshenko beam needs a positive shear stiffness κGA (N); \
                         for a rectangle κ = 5/6, for a solid circle κ = 0.9 (or 6/7)",
                    );
                    ok = false;
                }
                Some(q) => {
                    values[slot] = q.value;
                    quantities.push(q);
                }
                None => ok = false,
            }
        }
        // Written index of the bending stiffness of each rotary inertia: ei_y, ei_z.
        for (slot, (name, num, ei)) in [("rho_iy", rho_iy, 4), ("rho_iz", rho_iz, 5)]
            .into_iter()
            .enumerate()
        {
            match num {
                Some(num) => {
                    let what = "rotary inertia per length";
                    match self.nonnegative(num, &join(&spath, &[f(name)]), what, body) {
                        Some(q) => {
                            values[2 + slot] = q.value;
                            quantities.push(q);
                        }
                        None => ok = false,
                    }
                }
                None if written.len() == 7 => {
                    values[2 + slot] = written[1].value * written[ei].value / written[3].value;
                }
                None => {}
            }
        }
        ok.then_some((
            crate::flex::beam::Shear {
                kga_y: values[0],
                kga_z: values[1],
                rho_iy: values[2],
                rho_iz: values[3],
            },
            quantities,
        ))
    }

    /// The names of a flexible body's `k` elastic coordinates
    /// (`<body>_f1 …`) and their rates (`<body>_f1_dot …`), registered.
    pub(super) fn elastic_names(
        &mut self,
        body: &str,
        path: &[Seg<'static>],
        k: usize,
    ) -> Option<(Vec<String>, Vec<String>)> {
        let mut names = |suffix: &str, what: &'static str| -> Option<Vec<String>> {
            let names: Vec<String> = (1..=k).map(|n| format!("{body}_f{n}{suffix}")).collect();
            let mut ok = true;
            for name in &names {
                if self.check_symbol_name(name, path, what) {
                    self.state_names.insert(name.clone(), what);
                } else {
                    ok = false;
                }
            }
            ok.then_some(names)
        };
        let coordinates = names("", "elastic coordinate")?;
        let speeds = names("_dot", "elastic speed")?;
        Some((coordinates, speeds))
    }

    /// A beam's named nodes: unique names, each at a finite-element node
    /// (`x = i · length / elements`), as `(name, node index)`, and their
    /// `x` as written.
    pub(super) fn beam_nodes(
        &mut self,
        named: &[spec::BeamNode],
        length: &Quantity,
        elements: usize,
        body: &str,
        fpath: &[Seg<'static>],
    ) -> Option<(NamedNodes, Vec<Quantity>)> {
        let mut out: Vec<(String, usize)> = Vec::new();
        let mut places = Vec::new();
        let mut ok = true;
        let l = length.value;
        let h = l / elements as f64;
        for (k, node) in named.iter().enumerate() {
            let npath = join(fpath, &[f("nodes"), i(k)]);
            if out.iter().any(|(n, _)| *n == node.name) {
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
            let at = (x.value / h).round();
            if !(0.0..=elements as f64).contains(&at) || (x.value - at * h).abs() > 1e-9 * l {
                let below = (x.value / h).floor().clamp(0.0, elements as f64) as usize;
                let above = (below + 1).min(elements);
                let near = if below == above || x.value <= 0.0 {
                    format!("node {below} at x = {}", short(below as f64 * h))
                } else {
                    format!(
                        "node {below} at x = {} and node {above} at x = {}",
                        short(below as f64 * h),
                        short(above as f64 * h)
                    )
                };
                self.error(
                    &xpath,
                    format!(
                        "node `{}` of flexible body `{body}` at x = {} m is not a finite-element node",
                        node.name,
                        short(x.value)
                    ),
                    format!(
                        "nodes sit at x = i·length/{elements} (every {} m, from 0 to {}); the nearest: {near}",
                        short(h),
                        short(l)
                    ),
                );
                ok = false;
                continue;
            }
            out.push((node.name.clone(), at as usize));
            places.push(x);
        }
        ok.then_some((out, places))
    }

    /// The finite-element node index that `node` names on body `body`
    /// (`spec_flexible`: the body is flexible as written; `info`: its
    /// checked data, `None` if it failed and was reported already).
    pub(super) fn node_ref(
        &mut self,
        node: &spec::NodeRef,
        body: &str,
        spec_flexible: Option<&spec::Flexible>,
        info: Option<&FlexInfo>,
        path: &[Seg<'static>],
        what: &str,
    ) -> Option<usize> {
        let elements = match spec_flexible {
            Some(spec::Flexible::Beam { elements, .. }) => elements,
            Some(spec::Flexible::Modal { file, .. }) => {
                return self.modal_node_ref(node, body, file, info, path, what);
            }
            Some(spec::Flexible::AssumedModes { nodes: written, .. }) => {
                return self.assumed_node_ref(node, body, written, info, path, what);
            }
            None => {
                self.error(
                    path,
                    format!("{what} names node {node}, but body `{body}` is rigid"),
                    "only a flexible body has nodes to attach to; leave the node out",
                );
                return None;
            }
        };
        match node {
            spec::NodeRef::Index(n) if *n > *elements => {
                self.error(
                    path,
                    format!(
                        "{what}: {}",
                        crate::flex::FlexError::UnknownNode {
                            node: *n,
                            nodes: elements + 1
                        }
                    ),
                    format!(
                        "node i sits at x = i·length/{elements}; use a node from 0 to {elements}"
                    ),
                );
                None
            }
            spec::NodeRef::Index(n) => Some(*n),
            spec::NodeRef::Name(name) => {
                if let Some((_, n)) = info.and_then(|f| f.nodes.iter().find(|(n, _)| n == name)) {
                    return Some(*n);
                }
                let Some(spec::Flexible::Beam { nodes: written, .. }) = spec_flexible else {
                    return None;
                };
                if written.iter().any(|n| &n.name == name) {
                    // Named, but the node or its body has an error (reported).
                    return None;
                }
                let names = written.iter().map(|n| n.name.as_str());
                let help = match did_you_mean(name, names.clone()) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None if written.is_empty() => format!(
                        "name nodes in the beam's `nodes: [(name: \"{name}\", x: …)]`, or give a node index 0..={elements}"
                    ),
                    None => format!(
                        "its nodes are {}; or give a node index 0..={elements}",
                        list_names(names)
                    ),
                };
                self.error(
                    path,
                    format!("{what}: flexible body `{body}` has no node `{name}`"),
                    help,
                );
                None
            }
        }
    }

    /// The node of an assumed-modes body that `node` names: a name from its
    /// `nodes`, or an index into them.
    pub(super) fn assumed_node_ref(
        &mut self,
        node: &spec::NodeRef,
        body: &str,
        written: &[spec::BeamNode],
        info: Option<&FlexInfo>,
        path: &[Seg<'static>],
        what: &str,
    ) -> Option<usize> {
        let names = written.iter().map(|n| n.name.as_str());
        let list = if written.is_empty() {
            "name nodes in the body's `nodes: [(name: \"tip\", x: …)]` (assumed modes have no others)".to_string()
        } else {
            format!("its nodes are {}", list_names(names.clone()))
        };
        match node {
            spec::NodeRef::Index(n) if *n < written.len() => info.is_some().then_some(*n),
            spec::NodeRef::Index(n) => {
                self.error(
                    path,
                    format!(
                        "{what} names node {n}, but body `{body}` (assumed modes) has {} named node{}",
                        written.len(),
                        if written.len() == 1 { "" } else { "s" }
                    ),
                    list,
                );
                None
            }
            spec::NodeRef::Name(name) => {
                if let Some((_, n)) = info.and_then(|f| f.nodes.iter().find(|(n, _)| n == name)) {
                    return Some(*n);
                }
                if written.iter().any(|n| &n.name == name) {
                    // Named, but the node or its body has an error (reported).
                    return None;
                }
                let help = match did_you_mean(name, names) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None => list,
                };
                self.error(
                    path,
                    format!("{what}: flexible body `{body}` has no node `{name}`"),
                    help,
                );
                None
            }
        }
    }

    /// The node of an imported modal body that `node` names: an index into
    /// the file's `nodes`, or a name one of them carries.
    pub(super) fn modal_node_ref(
        &mut self,
        node: &spec::NodeRef,
        body: &str,
        file: &str,
        info: Option<&FlexInfo>,
        path: &[Seg<'static>],
        what: &str,
    ) -> Option<usize> {
        // The file failed to load or check: reported already.
        let Some(FlexSource::Modal {
            positions, names, ..
        }) = info.map(|x| &x.source)
        else {
            return None;
        };
        match node {
            spec::NodeRef::Index(n) if *n < positions.len() => Some(*n),
            spec::NodeRef::Index(n) => {
                self.error(
                    path,
                    format!(
                        "{what}: node {n} does not exist: `{file}` has nodes 0..={}",
                        positions.len().saturating_sub(1)
                    ),
                    "nodes are numbered from 0 in the order of the file's `nodes`",
                );
                None
            }
            spec::NodeRef::Name(name) => {
                if let Some(n) = names
                    .iter()
                    .position(|x| x.as_deref() == Some(name.as_str()))
                {
                    return Some(n);
                }
                let written = names.iter().flatten().map(String::as_str);
                let help = match did_you_mean(name, written.clone()) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None if names.iter().all(Option::is_none) => format!(
                        "`{file}` names no nodes: give a node index 0..={}, or a `name` in the file",
                        positions.len().saturating_sub(1)
                    ),
                    None => format!("its named nodes are {}", list_names(written)),
                };
                self.error(
                    path,
                    format!("{what}: flexible body `{body}` (`{file}`) has no node `{name}`"),
                    help,
                );
                None
            }
        }
    }
}

/// A length for messages: at most nine decimals, trailing zeros dropped.
pub(super) fn short(x: f64) -> String {
    let s = format!("{x:.9}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}
