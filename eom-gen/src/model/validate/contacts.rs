//! Unilateral contacts (issue #26): joint limits, spheres against world
//! planes and against spheres, their restitution and friction
//! coefficients, and no contact closed at the initial state.

use super::{Ctx, Scope, f, i, join};
use crate::model::spec::{self, Num, Spec};
use crate::system::*;
use std::collections::HashSet;

/// Penetration (m or rad) at the initial state above which `check`
/// refuses a contact.
const PENETRATION_TOL: f64 = 1e-9;

impl Ctx<'_> {
    /// A coefficient in `[lo, hi]` (`hi` infinite: no upper bound).
    fn coefficient(
        &mut self,
        n: &Num,
        path: &[crate::model::locate::Seg<'static>],
        what: &str,
        contact: &str,
        hi: f64,
    ) -> Option<f64> {
        let q = self.quantity(n, path, Scope::Params)?;
        let v = q.value;
        if !(0.0..=hi).contains(&v) {
            let (range, help) = if hi.is_finite() {
                (
                    "outside [0, 1]",
                    "Newton's coefficient of restitution is 0 (plastic: the contact stays closed) to 1 (elastic: no energy lost)",
                )
            } else {
                (
                    "negative",
                    "a Coulomb friction coefficient is 0 (frictionless) or positive",
                )
            };
            self.error(
                path,
                format!("{what} of contact `{contact}` is {v}, {range}"),
                help,
            );
            return None;
        }
        Some(v)
    }

    /// The model's contacts: those of its bodies (generated), and those at
    /// cable nodes (run by the large-model runtime).
    pub(super) fn contacts(
        &mut self,
        spec: &Spec,
        bodies: &[BodyInfo],
        joints: &[JointInfo],
    ) -> (Option<Vec<ContactInfo>>, Option<Vec<CableContactInfo>>) {
        let mut out = Vec::new();
        let mut at_nodes = Vec::new();
        let mut ok = true;
        let mut nodes_ok = true;
        let mut names = HashSet::new();
        for (k, c) in spec.contacts.iter().enumerate() {
            let path = [f("contacts"), i(k)];
            let name = c.name();
            if !names.insert(name) {
                self.error(
                    &join(&path, &[f("name")]),
                    format!("contact `{name}` is defined twice"),
                    "contact names must be unique",
                );
            }
            if let spec::Contact::Plane { at, .. } = c
                && at.node.is_some()
            {
                match self.cable_contact(spec, bodies, c, &path) {
                    Some(info) => at_nodes.push(info),
                    None => nodes_ok = false,
                }
                continue;
            }
            if let spec::Contact::Spheres { a, b, .. } = c
                && (a.node.is_some() || b.node.is_some())
            {
                match self.cable_sphere(spec, bodies, c, &path) {
                    Some(info) => at_nodes.push(info),
                    None => nodes_ok = false,
                }
                continue;
            }
            let (e, mu) = match c {
                spec::Contact::JointLimit { e, mu, .. }
                | spec::Contact::Plane { e, mu, .. }
                | spec::Contact::Spheres { e, mu, .. } => (e, mu),
            };
            let e = self.coefficient(e, &join(&path, &[f("e")]), "`e`", name, 1.0);
            let mu = self.coefficient(mu, &join(&path, &[f("mu")]), "`mu`", name, f64::INFINITY);
            let kind = match c {
                spec::Contact::JointLimit {
                    joint,
                    lower,
                    upper,
                    ..
                } => self.joint_limit(joints, &path, name, joint, lower, upper),
                spec::Contact::Plane {
                    at,
                    radius,
                    point,
                    normal,
                    on,
                    ..
                } => {
                    let at = self.contact_anchor(at, bodies, &join(&path, &[f("at")]), name);
                    let on = match on {
                        None => Some(0),
                        Some(b) => self.body_ref(bodies, b, &join(&path, &[f("on")]), "plane"),
                    };
                    if let (Some(a), Some(b)) = (&at, on)
                        && b != 0
                        && a.body == b
                    {
                        self.error(
                            &join(&path, &[f("on")]),
                            format!(
                                "contact `{name}` touches a plane on its own body `{}`",
                                bodies[b].name
                            ),
                            "a contact is between two bodies: fix the plane on another body (or leave `on` out for the ground)",
                        );
                    }
                    let r = self.nonnegative(radius, &join(&path, &[f("radius")]), "radius", name);
                    let p = self.vec3(point, &join(&path, &[f("point")]), Scope::Params);
                    let n = self.axis(normal, &join(&path, &[f("normal")]), "the plane's normal");
                    (|| {
                        Some(ContactKind::Plane {
                            at: at?,
                            radius: r?,
                            point: p?,
                            normal: n?,
                            on: on?,
                        })
                    })()
                }
                spec::Contact::Spheres {
                    a,
                    b,
                    radius_a,
                    radius_b,
                    ..
                } => {
                    let pa = self.contact_anchor(a, bodies, &join(&path, &[f("a")]), name);
                    let pb = self.contact_anchor(b, bodies, &join(&path, &[f("b")]), name);
                    let ra = self.nonnegative(
                        radius_a,
                        &join(&path, &[f("radius_a")]),
                        "radius_a",
                        name,
                    );
                    let rb = self.nonnegative(
                        radius_b,
                        &join(&path, &[f("radius_b")]),
                        "radius_b",
                        name,
                    );
                    if let (Some(x), Some(y)) = (&pa, &pb)
                        && x.body == y.body
                    {
                        self.error(
                            &join(&path, &[f("b")]),
                            format!(
                                "both spheres of contact `{name}` are on body `{}`",
                                bodies[x.body].name
                            ),
                            "a contact is between two bodies: put the second sphere on another body (or `ground`)",
                        );
                    }
                    (|| {
                        Some(ContactKind::Spheres {
                            a: pa?,
                            b: pb?,
                            radius_a: ra?,
                            radius_b: rb?,
                            // Set from the initial state once the system
                            // is built (`orient_spheres`).
                            tangent_reference: [1.0, 0.0, 0.0],
                        })
                    })()
                }
            };
            // Coulomb friction acts along a contact's tangent plane: a plane
            // contact and two spheres have one; a joint limit acts inside
            // its joint.
            let mu = match (c, mu) {
                (spec::Contact::JointLimit { .. }, Some(m)) if m > 0.0 => {
                    self.error(
                        &join(&path, &[f("mu")]),
                        format!("joint limit `{name}` has Coulomb friction (mu = {m})"),
                        "a joint limit stops its joint's coordinate and has no tangential direction: set `mu: 0` (or leave it out); joint friction is a force element",
                    );
                    None
                }
                (_, mu) => mu,
            };
            match (kind, e, mu) {
                (Some(kind), Some(e), Some(mu)) => out.push(ContactInfo {
                    name: name.to_string(),
                    kind,
                    e,
                    mu,
                    span: self.span(&path),
                }),
                _ => ok = false,
            }
        }
        (ok.then_some(out), nodes_ok.then_some(at_nodes))
    }

    /// A `Plane` contact whose `at` is a cable node: the cable and node
    /// exist (the cable alone, or hung at a body: the impact map then
    /// holds the attachments at the speed level), the plane is fixed in
    /// the world or on a body (`on`: its point and normal in the body's
    /// axes), and the node is not inside the plane at the start (the
    /// cable straight from `from` to `to`).
    fn cable_contact(
        &mut self,
        spec: &Spec,
        bodies: &[BodyInfo],
        c: &spec::Contact,
        path: &[crate::model::locate::Seg<'static>],
    ) -> Option<CableContactInfo> {
        let spec::Contact::Plane {
            name,
            at,
            radius,
            point,
            normal,
            on,
            e,
            mu,
        } = c
        else {
            return None;
        };
        let node = at.node?;
        let at_path = join(path, &[f("at")]);
        let mut ok = true;
        let cable = self.cable_node(spec, at, &at_path, name);
        // The plane's body (`0`: the ground, the world's axes).
        let body = match on {
            None => Some(0),
            Some(b) => self.body_ref(bodies, b, &join(path, &[f("on")]), "plane"),
        };
        if body.is_none() {
            ok = false;
        }
        let e = self.coefficient(e, &join(path, &[f("e")]), "`e`", name, 1.0);
        let mu = self.coefficient(mu, &join(path, &[f("mu")]), "`mu`", name, f64::INFINITY);
        let r = self.nonnegative(radius, &join(path, &[f("radius")]), "radius", name);
        let p = self.vec3(point, &join(path, &[f("point")]), Scope::Params);
        let n = self.axis(normal, &join(path, &[f("normal")]), "the plane's normal");
        let (cable, e, mu, r, p, n) = (cable?, e?, mu?, r?, p?, n?);
        if !ok {
            return None;
        }
        let normal = [n.unit[0], n.unit[1], n.unit[2]];
        let against = match body {
            Some(b) if b != 0 => CableTarget::BodyPlane {
                at: Point {
                    body: b,
                    position: p,
                    node: None,
                },
                normal,
            },
            _ => CableTarget::Plane {
                point: [p[0].value, p[1].value, p[2].value],
                normal,
            },
        };
        Some(CableContactInfo {
            name: name.clone(),
            cable,
            node,
            radius: r.value,
            against,
            e,
            mu,
            span: self.span(path),
        })
    }

    /// A `Spheres` contact with a cable node: `a` is the node (a sphere of
    /// `radius_a` about it), `b` another cable node or a sphere fixed in
    /// the world (`ground` with its centre as `point`); a body's sphere
    /// against a node is refused (the cable runtime evaluates node rows
    /// only). The pair is not inside itself at the start (the cables
    /// straight from `from` to `to`).
    fn cable_sphere(
        &mut self,
        spec: &Spec,
        bodies: &[BodyInfo],
        c: &spec::Contact,
        path: &[crate::model::locate::Seg<'static>],
    ) -> Option<CableContactInfo> {
        let spec::Contact::Spheres {
            name,
            a,
            b,
            radius_a,
            radius_b,
            e,
            mu,
        } = c
        else {
            return None;
        };
        let (a_path, b_path) = (join(path, &[f("a")]), join(path, &[f("b")]));
        let mut ok = true;
        let Some(node) = a.node else {
            self.error(
                &join(&b_path, &[f("node")]),
                format!("contact `{name}` has its cable node as `b` and `{}` as `a`", a.body),
                "put the cable node's sphere first, as `a`; `b` is another node or a sphere fixed in the world (`body: \"ground\"`)",
            );
            return None;
        };
        let cable = self.cable_node(spec, a, &a_path, name);
        let against = if let Some(other) = b.node {
            let there = self.cable_node(spec, b, &b_path, name);
            if there.is_some() && there == cable && other == node {
                self.error(
                    &join(&b_path, &[f("node")]),
                    format!(
                        "both spheres of contact `{name}` are about node {node} of `{}`",
                        a.body
                    ),
                    "a contact is between two nodes: name another node (or cable) as `b`",
                );
                ok = false;
            }
            there.map(|cable| CableTarget::Node { cable, node: other })
        } else if b.body == "ground" {
            if b.marker.is_some() {
                self.error(
                    &join(&b_path, &[f("marker")]),
                    format!("contact `{name}` centres its fixed sphere at a ground marker"),
                    "give the fixed sphere's centre as `point` (world axes, m)",
                );
                ok = false;
            }
            let centre = match &b.point {
                Some(p) => self
                    .vec3(p, &join(&b_path, &[f("point")]), Scope::Params)
                    .map(|p| [p[0].value, p[1].value, p[2].value]),
                None => Some([0.0; 3]),
            };
            centre.map(|centre| CableTarget::Sphere { centre })
        } else {
            // A sphere on a body: its centre moves with the body.
            // (Its radius is set below, once read.)
            self.contact_anchor(b, bodies, &b_path, name)
                .map(|at| CableTarget::BodySphere { at, radius: 0.0 })
        };
        let e = self.coefficient(e, &join(path, &[f("e")]), "`e`", name, 1.0);
        let mu = self.coefficient(mu, &join(path, &[f("mu")]), "`mu`", name, f64::INFINITY);
        let ra = self.nonnegative(radius_a, &join(path, &[f("radius_a")]), "radius_a", name);
        let rb = self.nonnegative(radius_b, &join(path, &[f("radius_b")]), "radius_b", name);
        let (cable, mut against, e, mu, ra, rb) = (cable?, against?, e?, mu?, ra?, rb?);
        if !ok {
            return None;
        }
        if let CableTarget::BodySphere { radius, .. } = &mut against {
            *radius = rb.value;
        }
        Some(CableContactInfo {
            name: name.clone(),
            cable,
            node,
            radius: ra.value + rb.value,
            against,
            e,
            mu,
            span: self.span(path),
        })
    }

    /// The cable of a contact's anchor at a cable node (`anchor.node`
    /// set): the cable exists, the node is one of its nodes, and the
    /// anchor gives no `point` or `marker`.
    fn cable_node(
        &mut self,
        spec: &Spec,
        at: &spec::Anchor,
        at_path: &[crate::model::locate::Seg<'static>],
        name: &str,
    ) -> Option<usize> {
        let node = at.node?;
        let mut ok = true;
        let cable = spec.cables.iter().position(|x| x.name == at.body);
        if cable.is_none() {
            let names: Vec<String> = spec
                .cables
                .iter()
                .map(|x| format!("`{}`", x.name))
                .collect();
            self.error(
                &join(at_path, &[f("body")]),
                format!("contact `{name}` is at node {node} of `{}`, which is no cable", at.body),
                if names.is_empty() {
                    "`node` names a cable's node: this model has no cables (for a body's point, leave `node` out)".to_string()
                } else {
                    format!("the cables are {}", names.join(", "))
                },
            );
            ok = false;
        }
        if at.point.is_some() || at.marker.is_some() {
            self.error(
                at_path,
                format!("contact `{name}` gives a cable node and a `point` or `marker`"),
                "a cable node is the contact's point itself: give `body` (the cable) and `node` only",
            );
            ok = false;
        }
        if let Some(k) = cable {
            let cab = &spec.cables[k];
            if node > cab.elements {
                self.error(
                    &join(at_path, &[f("node")]),
                    format!(
                        "contact `{name}` is at node {node} of cable `{}`, whose nodes are 0..={}",
                        cab.name, cab.elements
                    ),
                    "a cable of n elements has nodes 0 (at `from`) to n (at `to`)",
                );
                ok = false;
            }
        }
        if ok { cable } else { None }
    }

    /// A sphere's centre: an anchor on a body that is not the ground
    /// (except as the second sphere of a pair).
    fn contact_anchor(
        &mut self,
        a: &spec::Anchor,
        bodies: &[BodyInfo],
        path: &[crate::model::locate::Seg<'static>],
        name: &str,
    ) -> Option<Point> {
        let p = self.anchor(a, bodies, path)?;
        let second = path.last() == Some(&f("b"));
        if p.body == 0 && !second {
            self.error(
                &join(path, &[f("body")]),
                format!("contact `{name}` is on the ground, which never moves"),
                "name the moving body that touches (a sphere fixed in the world is the second, `b`, of `Spheres`)",
            );
            return None;
        }
        Some(p)
    }

    fn joint_limit(
        &mut self,
        joints: &[JointInfo],
        path: &[crate::model::locate::Seg<'static>],
        name: &str,
        joint: &str,
        lower: &Option<Num>,
        upper: &Option<Num>,
    ) -> Option<ContactKind> {
        let j = self.joint_ref(joints, joint, &join(path, &[f("joint")]));
        if let Some(j) = j {
            let info = &joints[j];
            if !matches!(info.kind, JointType::Revolute(_) | JointType::Prismatic(_)) {
                self.error(
                    &join(path, &[f("joint")]),
                    format!(
                        "joint limit `{name}` is on {} joint `{joint}`",
                        info.kind.name()
                    ),
                    "joint limits apply to revolute and prismatic joints (one coordinate)",
                );
                return None;
            }
            if info.motion != Motion::Free {
                self.error(
                    &join(path, &[f("joint")]),
                    format!(
                        "joint limit `{name}` is on joint `{joint}`, which is {}",
                        match info.motion {
                            Motion::Locked => "locked",
                            Motion::Prescribed(_) => "prescribed",
                            _ => "cut (closing a loop)",
                        }
                    ),
                    "a limit stops a free joint of the tree: limit another joint of the loop, or make this one a tree joint",
                );
                return None;
            }
        }
        if lower.is_none() && upper.is_none() {
            self.error(
                path,
                format!("joint limit `{name}` has neither `lower` nor `upper`"),
                "give `lower`, `upper` or both (rad for revolute, m for prismatic joints)",
            );
            return None;
        }
        let lo = lower
            .as_ref()
            .map(|n| self.quantity(n, &join(path, &[f("lower")]), Scope::Params));
        let hi = upper
            .as_ref()
            .map(|n| self.quantity(n, &join(path, &[f("upper")]), Scope::Params));
        if let (Some(Some(l)), Some(Some(h))) = (&lo, &hi)
            && l.value >= h.value
        {
            self.error(
                &join(path, &[f("upper")]),
                format!(
                    "joint limit `{name}`: upper {} is not above lower {}",
                    h.value, l.value
                ),
                "the upper limit must exceed the lower one",
            );
            return None;
        }
        let flat = |x: Option<Option<Quantity>>| match x {
            None => Some(None),
            Some(Some(q)) => Some(Some(q)),
            Some(None) => None,
        };
        Some(ContactKind::JointLimit {
            joint: j?,
            lower: flat(lo)?,
            upper: flat(hi)?,
        })
    }

    /// Per `Spheres` contact, the world axis its friction's tangent axes
    /// are taken from: the one least aligned with the line of centres at
    /// the initial state ([`crate::mech::contacts::tangent_axes`]).
    pub(super) fn orient_spheres(&mut self, sys: &mut System) {
        if !sys
            .contacts
            .iter()
            .any(|c| matches!(c.kind, ContactKind::Spheres { .. }))
        {
            return;
        }
        let Ok(num) = crate::mech::Numeric::new(sys) else {
            return;
        };
        let Ok(normals) = num.sphere_normals(sys, &sys.q0()) else {
            return;
        };
        for (c, n) in sys.contacts.iter_mut().zip(normals) {
            if let (
                ContactKind::Spheres {
                    tangent_reference, ..
                },
                Some(n),
            ) = (&mut c.kind, n)
            {
                let mut a = [0.0; 3];
                a[crate::mech::contacts::least_aligned_axis(n)] = 1.0;
                *tangent_reference = a;
            }
        }
    }

    /// Every contact at a cable node open at the initial state (the cable
    /// straight from its start to its end): a closed one is an error with
    /// its penetration and what would open it.
    pub(super) fn check_cable_contacts_open(&mut self, sys: &System) {
        let frames = crate::mech::mounts::frames_at_start(sys);
        let mut next = frames.iter();
        for c in &sys.cable_contacts {
            let frame = match c.against.on_body() {
                Some(_) => next.next(),
                None => None,
            };
            let (Some(cable), Some(g)) = (sys.cables.get(c.cable), c.gap_at_start(sys, frame))
            else {
                continue;
            };
            if g.is_finite() && g >= -PENETRATION_TOL {
                continue;
            }
            let (what, help) = match &c.against {
                CableTarget::Plane { .. } => (
                    "its plane".to_string(),
                    "further along the plane's normal (its `from` and `to`), or move the plane",
                ),
                CableTarget::Sphere { .. } => (
                    "the fixed sphere".to_string(),
                    "away from the sphere's centre (its `from` and `to`), or move the sphere or shrink the radii",
                ),
                CableTarget::BodyPlane { at, .. } => (
                    format!("the plane on body `{}`", sys.bodies[at.body].name),
                    "further along the plane's normal (its `from` and `to`), or move the body or the plane",
                ),
                CableTarget::BodySphere { at, .. } => (
                    format!("the sphere on body `{}`", sys.bodies[at.body].name),
                    "away from the sphere's centre (its `from` and `to`), or move the body or shrink the radii",
                ),
                CableTarget::Node { cable: k, node } => (
                    format!(
                        "the sphere about node {node} of cable `{}`",
                        sys.cables.get(*k).map_or("?", |x| x.name.as_str())
                    ),
                    "away from the other node (the cables' `from` and `to`), or shrink the radii",
                ),
            };
            self.diags.push(
                crate::diag::Diagnostic::error(
                    c.span,
                    format!(
                        "contact `{}`: node {} of cable `{}` penetrates {what} by {:.6e} m at the initial state",
                        c.name, c.node, cable.name, -g
                    ),
                )
                .with_help(format!("start the cable at least {:.6e} m {help}", -g)),
            );
        }
    }

    /// Every contact row open (`g ≥ 0`) at the initial state: a closed one
    /// is an error with its penetration and what would open it.
    pub(super) fn check_contacts_open(&mut self, sys: &System) {
        if sys.contacts.is_empty() {
            return;
        }
        let Ok(num) = crate::mech::Numeric::new(sys) else {
            return;
        };
        let Ok(rows) = num.contacts(sys, &sys.q0(), &sys.u0(), 0.0) else {
            return;
        };
        for ((c, row), (g, _)) in sys.contact_rows().into_iter().zip(rows) {
            if g.is_finite() && g >= -PENETRATION_TOL {
                continue;
            }
            let contact = &sys.contacts[c];
            let path = [f("contacts"), i(c)];
            let (message, help) = match &contact.kind {
                ContactKind::JointLimit { joint, .. } => {
                    let j = &sys.joints[*joint];
                    let unit = match j.kind {
                        JointType::Revolute(_) => "rad",
                        _ => "m",
                    };
                    let q = sys.q0()[j.q_index];
                    (
                        format!(
                            "joint limit `{row}` is violated at the initial state: `{}` = {q} is {:.6e} {unit} beyond it",
                            j.coordinate_names.first().map_or("?", String::as_str),
                            -g
                        ),
                        format!(
                            "start the joint inside its limits (`q0` of joint `{}`, or `--q0`), or move the limit",
                            j.name
                        ),
                    )
                }
                ContactKind::Plane { at, .. } => (
                    format!(
                        "contact `{row}` penetrates its plane by {:.6e} m at the initial state",
                        -g
                    ),
                    format!(
                        "start body `{}` at least {:.6e} m further along the plane's normal (the `q0` of the joints above it), or move the plane",
                        sys.bodies[at.body].name, -g
                    ),
                ),
                ContactKind::Spheres { a, b, .. } => (
                    format!(
                        "the spheres of contact `{row}` overlap by {:.6e} m at the initial state",
                        -g
                    ),
                    format!(
                        "move bodies `{}` and `{}` at least {:.6e} m apart (the `q0` of the joints above them), or make the radii smaller",
                        sys.bodies[a.body].name, sys.bodies[b.body].name, -g
                    ),
                ),
            };
            self.error(&path, message, help);
        }
    }
}
