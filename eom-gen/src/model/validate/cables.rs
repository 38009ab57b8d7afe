//! ANCF cables: names, element types, geometry, section and material,
//! supports, loads, and ends held at markers of rigid bodies.

use super::{Ctx, Scope, f, i, is_ident, join};
use crate::diag::{did_you_mean, list_names};
use crate::model::locate::Seg;
use crate::model::spec::{self, Num, Spec};
use crate::system::*;
use std::collections::HashSet;

impl Ctx<'_> {
    /// The ANCF chains: names, element types, geometry, section and
    /// material, supports, end force; every problem reported.
    pub(super) fn cables(
        &mut self,
        spec: &Spec,
        gravity: Option<&Vec3Q>,
        bodies: &[BodyInfo],
    ) -> Option<Vec<CableInfo>> {
        use crate::system::{CableSection, ChainInfo, Support};
        let g = gravity.map_or([0.0; 3], |g| [g[0].value, g[1].value, g[2].value]);
        let mut out = Vec::new();
        let mut ok = true;
        let mut names = HashSet::new();
        for (k, c) in spec.cables.iter().enumerate() {
            let path = [f("cables"), i(k)];
            let at = |field: &'static str| join(&path, &[f(field)]);
            let name = c.name.as_str();
            if !is_ident(name) {
                self.error(
                    &at("name"),
                    format!("cable name `{name}` is not an identifier"),
                    "use letters, digits and `_`",
                );
                ok = false;
            } else if !names.insert(name) {
                self.error(
                    &at("name"),
                    format!("cable `{name}` is defined twice"),
                    "give every cable its own name",
                );
                ok = false;
            }
            let kernel = c.element.name();
            if c.elements == 0 {
                self.error(
                    &at("elements"),
                    format!("cable `{name}` has no elements"),
                    "a cable needs at least one element (the tests converge from 4 to 64)",
                );
                ok = false;
            }
            let from = self.vec3(&c.from, &at("from"), Scope::Params);
            let to = self.vec3(&c.to, &at("to"), Scope::Params);
            let end_force = self.vec3(&c.end_force, &at("end_force"), Scope::Params);
            let distributed =
                self.vec3(&c.distributed_load, &at("distributed_load"), Scope::Params);
            let positive = |cx: &mut Self, n: &Num, field: &'static str, what: &str, unit: &str| {
                let q = cx.quantity(n, &at(field), Scope::Params)?;
                if q.value.is_nan() || q.value <= 0.0 {
                    cx.error(
                        &at(field),
                        format!("{what} `{field}` of cable `{name}` is {} {unit}", q.value),
                        format!("a cable needs a positive {what} ({unit})"),
                    );
                    return None;
                }
                Some(q.value)
            };
            let young = positive(self, &c.young, "young", "Young's modulus", "Pa");
            let density = positive(self, &c.density, "density", "density", "kg/m³");
            let width = c
                .width
                .as_ref()
                .map(|n| positive(self, n, "width", "section width", "m"));
            let height = c
                .height
                .as_ref()
                .map(|n| positive(self, n, "height", "section height", "m"));
            let area = c
                .area
                .as_ref()
                .map(|n| positive(self, n, "area", "section area", "m²"));
            let second = c
                .second_moment
                .as_ref()
                .map(|n| positive(self, n, "second_moment", "second moment of area", "m⁴"));
            let rect = match (width, height) {
                (Some(Some(b)), Some(Some(h))) => Some((b, h)),
                (Some(_), None) | (None, Some(_)) => {
                    let missing = if c.width.is_none() { "width" } else { "height" };
                    self.error(
                        &path,
                        format!("cable `{name}` gives one side of a rectangular section but not `{missing}`"),
                        "give both `width` and `height`, or `area` and `second_moment`",
                    );
                    None
                }
                _ => None,
            };
            let area = match area {
                Some(a) => a,
                None => rect.map(|(b, h)| b * h),
            };
            let second = match second {
                Some(s) => s,
                None => rect.map(|(b, h)| b * h * h * h / 12.0),
            };
            if c.area.is_none() && c.width.is_none() {
                self.error(
                    &path,
                    format!("cable `{name}` has no section area"),
                    "give `area` and `second_moment`, or `width` and `height` of a rectangular section",
                );
            }
            if c.second_moment.is_none() && c.width.is_none() {
                self.error(
                    &path,
                    format!("cable `{name}` has no second moment of area"),
                    "give `second_moment` (m⁴), or `width` and `height` of a rectangular section",
                );
            }
            if c.element == crate::ancf::Kind::Beam2D && rect.is_none() && c.width.is_none() {
                self.error(
                    &at("element"),
                    format!("`Beam2D` cable `{name}` needs a rectangular section"),
                    "the continuum beam integrates over the section: give `width` and `height`",
                );
            }
            let poisson = self.quantity(&c.poisson, &at("poisson"), Scope::Params);
            if let Some(p) = &poisson
                && !(0.0..0.5).contains(&p.value)
            {
                self.error(
                    &at("poisson"),
                    format!("Poisson's ratio of cable `{name}` is {}", p.value),
                    "it lies in [0, 0.5)",
                );
            }
            let da = self.nonnegative(
                &c.damping_axial,
                &at("damping_axial"),
                "axial damping",
                name,
            );
            let db = self.nonnegative(
                &c.damping_bending,
                &at("damping_bending"),
                "bending damping",
                name,
            );
            let mu = self.nonnegative(&c.retardation, &at("retardation"), "retardation time", name);
            let end_mass = self.nonnegative(&c.end_mass, &at("end_mass"), "end mass", name);
            let planar = c.element != crate::ancf::Kind::Cable3D;
            if let (Some(a), Some(b)) = (&from, &to) {
                let (a, b) = (values(a), values(b));
                if (a - b).norm() <= 0.0 {
                    self.error(
                        &at("to"),
                        format!("the ends of cable `{name}` coincide"),
                        "`from` and `to` are the two ends of the straight reference line",
                    );
                    ok = false;
                }
                if planar && (a.z != 0.0 || b.z != 0.0) {
                    self.error(
                        &at(if a.z != 0.0 { "from" } else { "to" }),
                        format!("`{kernel}` cable `{name}` leaves the plane z = 0"),
                        "planar elements move in the x–y plane: give z = 0, or use `Cable3D`",
                    );
                    ok = false;
                }
            }
            if let Some(d) = &distributed {
                let d = values(d);
                if !(d.x.is_finite() && d.y.is_finite() && d.z.is_finite()) {
                    self.error(
                        &at("distributed_load"),
                        format!("the distributed load of cable `{name}` is not finite"),
                        "give a load per unit length in N/m",
                    );
                    ok = false;
                } else if planar && d.z != 0.0 {
                    self.error(
                        &at("distributed_load"),
                        format!(
                            "`{kernel}` cable `{name}` has a distributed load out of its plane (z = {})",
                            d.z
                        ),
                        "planar elements carry loads in the x–y plane: give z = 0, or use `Cable3D`",
                    );
                    ok = false;
                }
            }
            let mut node_forces = Vec::new();
            for (j, nf) in c.node_forces.iter().enumerate() {
                let here = |field: &'static str| join(&path, &[f("node_forces"), i(j), f(field)]);
                if nf.node > c.elements {
                    self.error(
                        &here("node"),
                        format!(
                            "cable `{name}` has no node {} (its nodes are 0 to {})",
                            nf.node, c.elements
                        ),
                        "node j lies at from + j/elements · (to − from)",
                    );
                    ok = false;
                }
                let Some(force) = self.vec3(&nf.force, &here("force"), Scope::Params) else {
                    ok = false;
                    continue;
                };
                let fv = values(&force);
                if !(fv.x.is_finite() && fv.y.is_finite() && fv.z.is_finite()) {
                    self.error(
                        &here("force"),
                        format!("a node force of cable `{name}` is not finite"),
                        "give a force in N",
                    );
                    ok = false;
                } else if planar && fv.z != 0.0 {
                    self.error(
                        &here("force"),
                        format!(
                            "`{kernel}` cable `{name}` has a node force out of its plane (z = {})",
                            fv.z
                        ),
                        "planar elements carry loads in the x–y plane: give z = 0, or use `Cable3D`",
                    );
                    ok = false;
                }
                node_forces.push((nf.node, [fv.x, fv.y, fv.z]));
            }
            let motion = self.cable_motion(c, &path, (from.as_ref(), to.as_ref()), planar, spec);
            ok &= motion.is_some();
            if planar && g[2] != 0.0 {
                self.warning(
                    &[f("gravity")],
                    format!("gravity has a z component that planar cable `{name}` does not feel"),
                    "planar elements move in the x–y plane",
                );
            }
            if c.start.is_free() && c.end.is_free() {
                self.warning(
                    &at("start"),
                    format!("cable `{name}` is held at neither end"),
                    "it can move freely (dynamics); a static solve will refuse it",
                );
            }
            let start_at = c.start_at.as_ref().map(|m| {
                self.cable_mount(m, c.start, &at("start_at"), "start", name, planar, bodies)
            });
            let end_at = c
                .end_at
                .as_ref()
                .map(|m| self.cable_mount(m, c.end, &at("end_at"), "end", name, planar, bodies));
            let (start_at, end_at) = match (start_at, end_at) {
                (Some(None), _) | (_, Some(None)) => {
                    ok = false;
                    (None, None)
                }
                (a, b) => (a.flatten(), b.flatten()),
            };
            // An end held at a marker is free in the chain: the attachment
            // constraint holds it.
            let support = |e: spec::CableEnd, mounted: bool| match e {
                _ if mounted => Support::Free,
                spec::CableEnd::Free => Support::Free,
                spec::CableEnd::Pinned => Support::Pinned,
                spec::CableEnd::Clamped => Support::Clamped,
            };
            let (
                Some(from),
                Some(to),
                Some(end_force),
                Some(young),
                Some(density),
                Some(area),
                Some(second),
                Some(poisson),
                Some(da),
                Some(db),
                Some(mu),
                Some(end_mass),
                Some(distributed),
            ) = (
                from,
                to,
                end_force,
                young,
                density,
                area,
                second,
                poisson,
                da,
                db,
                mu,
                end_mass,
                distributed,
            )
            else {
                ok = false;
                continue;
            };
            let v = |q: &Vec3Q| [q[0].value, q[1].value, q[2].value];
            let (b, h) = rect.unwrap_or((0.0, 0.0));
            out.push(CableInfo {
                name: name.to_string(),
                chain: ChainInfo {
                    element: c.element,
                    start: v(&from),
                    end: v(&to),
                    elements: c.elements,
                    section: CableSection {
                        e: young,
                        nu: poisson.value,
                        rho: density,
                        area,
                        inertia: second,
                        b,
                        h,
                        damping_axial: da.value,
                        damping_bending: db.value,
                        retardation: mu.value,
                    },
                    start_support: support(c.start, start_at.is_some()),
                    end_support: support(c.end, end_at.is_some()),
                    end_force: v(&end_force),
                    end_mass: end_mass.value,
                    gravity: g,
                },
                start_at,
                end_at,
                distributed_load: v(&distributed),
                node_forces,
                initial_motion: motion.unwrap_or_default(),
            });
        }
        ok.then_some(out)
    }

    /// A cable's initial rigid motion, `[velocity of from, angular
    /// velocity]`: finite, in the plane of a planar cable, only in a model
    /// of cables alone (the mixed runtime starts its cables at rest), and
    /// at rest at every end held to the ground (a clamped end also not
    /// turning). `None` after reporting what is wrong.
    fn cable_motion(
        &mut self,
        c: &spec::Cable,
        path: &[Seg<'static>],
        (from, to): (Option<&Vec3Q>, Option<&Vec3Q>),
        planar: bool,
        spec: &Spec,
    ) -> Option<[[f64; 3]; 2]> {
        let name = c.name.as_str();
        let at = |field: &'static str| join(path, &[f(field)]);
        let v = self.vec3(&c.velocity, &at("velocity"), Scope::Params);
        let w = self.vec3(&c.angular_velocity, &at("angular_velocity"), Scope::Params);
        let (v, w) = (values(&v?), values(&w?));
        let mut ok = true;
        for (x, field, what) in [(v, "velocity", "m/s"), (w, "angular_velocity", "rad/s")] {
            if !x.iter().all(|c| c.is_finite()) {
                self.error(
                    &at(field),
                    format!("the initial `{field}` of cable `{name}` is not finite"),
                    format!("give three numbers in {what}"),
                );
                ok = false;
            }
        }
        if planar && v.z != 0.0 {
            self.error(
                &at("velocity"),
                format!(
                    "`{}` cable `{name}` would leave its plane: initial velocity z = {}",
                    c.element.name(),
                    v.z
                ),
                "planar elements move in the x–y plane: give z = 0, or use `Cable3D`",
            );
            ok = false;
        }
        if planar && (w.x != 0.0 || w.y != 0.0) {
            self.error(
                &at("angular_velocity"),
                format!(
                    "`{}` cable `{name}` would leave its plane: angular velocity ({}, {}, {}) rad/s",
                    c.element.name(),
                    w.x,
                    w.y,
                    w.z
                ),
                "a planar cable turns about z only: give (0, 0, ω)",
            );
            ok = false;
        }
        let moving = v.norm() > 0.0 || w.norm() > 0.0;
        let field = if v.norm() > 0.0 {
            "velocity"
        } else {
            "angular_velocity"
        };
        if ok && moving && !spec.bodies.is_empty() {
            self.error(
                &at(field),
                format!("cable `{name}` is given an initial `{field}` in a model with rigid bodies"),
                "initial cable velocities are for models of cables alone; with rigid bodies every cable starts at rest",
            );
            ok = false;
        }
        if let (true, true, Some(a), Some(b)) = (ok, moving, from, to) {
            let (a, b) = (values(a), values(b));
            let scale = v.norm() + w.norm() * (b - a).norm();
            let tangent = (b - a).normalize();
            let ends = [
                ("start", c.start, c.start_at.is_some(), a),
                ("end", c.end, c.end_at.is_some(), b),
            ];
            for (end, held, mounted, p) in ends {
                if held.is_free() || mounted {
                    continue;
                }
                let speed = v + w.cross(&(p - a));
                let turning = w.cross(&tangent);
                let clamped = held == spec::CableEnd::Clamped;
                if speed.norm() > 1e-12 * scale || (clamped && turning.norm() > 1e-12 * w.norm()) {
                    let how = if clamped { "clamped" } else { "pinned" };
                    self.error(
                        &at(field),
                        format!(
                            "the {end} of cable `{name}` is {how} to the ground but its initial motion moves it \
                             (speed ({:.6}, {:.6}, {:.6}) m/s{})",
                            speed.x,
                            speed.y,
                            speed.z,
                            if clamped && turning.norm() > 0.0 { ", and turns it" } else { "" }
                        ),
                        "an end held to the ground starts at rest: give a motion that vanishes there \
                         (a pinned start: `velocity` zero and an `angular_velocity` about it)",
                    );
                    ok = false;
                }
            }
        }
        ok.then_some([[v.x, v.y, v.z], [w.x, w.y, w.z]])
    }

    /// A cable end held at a marker of a rigid body: the body and marker
    /// exist, the body is rigid and not ground, the end is pinned or
    /// clamped, a clamped end gives its `axis` (in the cable's plane for
    /// planar elements), a pinned one none. `None` inside: an error was
    /// reported.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn cable_mount(
        &mut self,
        m: &spec::CableMount,
        how: spec::CableEnd,
        path: &[Seg<'static>],
        end: &str,
        cable: &str,
        planar: bool,
        bodies: &[BodyInfo],
    ) -> Option<CableMountInfo> {
        let span = self.span(path);
        let body = self.body_ref(bodies, &m.body, &join(path, &[f("body")]), "mount");
        let mut ok = body.is_some();
        if let Some(b) = body {
            if b == 0 {
                self.error(
                    &join(path, &[f("body")]),
                    format!("the {end} of cable `{cable}` is held at a marker of `ground`"),
                    format!("hold it to ground with `{end}: Pinned` or `{end}: Clamped` alone (at the `from`/`to` point), or name a rigid body"),
                );
                ok = false;
            } else if bodies[b].flexible.is_some() {
                self.error(
                    &join(path, &[f("body")]),
                    format!(
                        "the {end} of cable `{cable}` is held at flexible body `{}`",
                        m.body
                    ),
                    "cables attach to markers of rigid bodies only",
                );
                ok = false;
            }
        }
        let marker = body.filter(|&b| b != 0).and_then(|b| {
            let found = bodies[b].markers.iter().position(|x| x.name == m.marker);
            if found.is_none() {
                let names = bodies[b].markers.iter().map(|x| x.name.as_str());
                let help = match did_you_mean(&m.marker, names.clone()) {
                    Some(best) => format!("did you mean `{best}`?"),
                    None => format!("its markers are {}", list_names(names)),
                };
                self.error(
                    &join(path, &[f("marker")]),
                    format!("body `{}` has no marker `{}`", m.body, m.marker),
                    help,
                );
            }
            found
        });
        ok &= marker.is_some();
        let axis = match (how, &m.axis) {
            (spec::CableEnd::Free, _) => {
                self.error(
                    path,
                    format!("the {end} of cable `{cable}` is `Free` but held at marker `{}.{}`", m.body, m.marker),
                    format!("say how the marker holds it: `{end}: Pinned` (position) or `{end}: Clamped` (position and direction, with `axis`)"),
                );
                ok = false;
                None
            }
            (spec::CableEnd::Clamped, None) => {
                self.error(
                    path,
                    format!(
                        "the {end} of cable `{cable}` is clamped at marker `{}.{}` without an `axis`",
                        m.body, m.marker
                    ),
                    "give `axis: (1, 0, 0)`: the direction, in the marker's axes, along which the cable leaves the marker",
                );
                ok = false;
                None
            }
            (spec::CableEnd::Pinned, Some(_)) => {
                self.error(
                    &join(path, &[f("axis")]),
                    format!("the {end} of cable `{cable}` is pinned: it turns freely, so `axis` means nothing"),
                    format!("remove `axis`, or clamp the end (`{end}: Clamped`)"),
                );
                ok = false;
                None
            }
            (spec::CableEnd::Pinned, None) => None,
            (spec::CableEnd::Clamped, Some(a)) => {
                let ap = join(path, &[f("axis")]);
                match self.axis(a, &ap, "the clamp's axis") {
                    Some(a) if planar && a.unit.z.abs() > 1e-12 => {
                        self.error(
                            &ap,
                            format!("the clamp's axis of planar cable `{cable}` leaves the x–y plane"),
                            "give an axis with z = 0 (in the marker's axes; planar models turn about z)",
                        );
                        ok = false;
                        None
                    }
                    Some(a) => Some([a.unit.x, a.unit.y, a.unit.z]),
                    None => {
                        ok = false;
                        None
                    }
                }
            }
        };
        let (Some(body), Some(marker), true) = (body, marker, ok) else {
            return None;
        };
        Some(CableMountInfo {
            body,
            marker,
            axis,
            span,
        })
    }
}
