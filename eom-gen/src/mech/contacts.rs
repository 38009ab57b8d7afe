//! Unilateral contacts (issue #26; Wittenburg ch. 6, Pfeiffer and Glocker):
//! per gap row of [`System::contact_rows`] the gap `g(q)` and its normal
//! speed `ġ = w(q)ᵀ u`. Written once over [`Scalar`]: on `f64` it is the
//! numeric twin ([`super::Numeric::contacts`], which the validator uses to
//! refuse a contact closed at the initial state), on `Expr` the generated
//! function `contacts` (`formulate` adds `w = ∂ġ/∂u` and the acceleration
//! term `γ` with `g̈ = wᵀ u̇ − γ`).

use super::applied::Site;
use super::env::Env;
use super::error::MechError;
use super::kinematics::{Evaluator, Kinematics};
use super::lower::Lowering;
use super::tree::TreeModel;
use crate::sym::{Scalar, Vec3};
use crate::system::{ContactKind, Point, System};
use std::ops::Add;

/// The gap `g` and normal speed `ġ` of every contact row, in the order of
/// [`System::contact_rows`].
pub fn gaps<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
    q: &[S],
    u: &[S],
) -> Result<Vec<(S, S)>, MechError> {
    let low = Lowering::new(env);
    let site = |p: &Point| site_of(tree, &low, ev, k, p);
    let mut out = Vec::new();
    for c in &sys.contacts {
        match &c.kind {
            ContactKind::JointLimit {
                joint,
                lower,
                upper,
            } => {
                let j = &sys.joints[*joint];
                let (qj, uj) = (q[j.q_index], u[j.u_index]);
                if let Some(l) = lower {
                    out.push((qj - low.quantity(l)?, uj));
                }
                if let Some(h) = upper {
                    out.push((low.quantity(h)? - qj, -uj));
                }
            }
            ContactKind::Plane {
                at,
                radius,
                point,
                normal,
                on,
            } => {
                let (x, v) = site(at)?;
                let plane = PlaneAt::new(tree, &low, k, point, normal, *on)?;
                // ġ = n·(v − v_b(x)): the plane's own motion at x (its
                // normal turning included: ṅ·(x − p) = n·(ω × (x − p))).
                let vb = plane.velocity(ev, k, x);
                out.push((
                    plane.n.dot(x - plane.p) - low.quantity(radius)?,
                    plane.n.dot(v - vb),
                ));
            }
            ContactKind::Spheres {
                a,
                b,
                radius_a,
                radius_b,
                ..
            } => {
                let (xa, va) = site(a)?;
                let (xb, vb) = site(b)?;
                let d = xa - xb;
                let dist = d.norm();
                let g = dist - low.quantity(radius_a)? - low.quantity(radius_b)?;
                out.push((g, d.dot(va - vb) / dist));
            }
        }
    }
    Ok(out)
}

/// Per gap row, the loads (in the layout of [`TreeModel::loads`]) of a
/// unit normal impulse `Λ = 1`: along `n` at a plane contact's centre,
/// along `±d̂` at the centres of two spheres (the line of action passes
/// through the contact point, so the centre carries the same moment).
/// Joint limits act inside their joint: no load.
pub fn unit_loads<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
) -> Result<Vec<Vec<super::spatial::Force<S>>>, MechError> {
    use super::spatial::Force;
    let low = Lowering::new(env);
    let mut out = Vec::new();
    // A world force `fw` at the anchor `p` into `loads`.
    let apply = |loads: &mut Vec<Force<S>>, p: &Point, fw: Vec3<S>| -> Result<(), MechError> {
        load_at(tree, ev, k, loads, &anchor(tree, &low, p)?, fw);
        Ok(())
    };
    for c in &sys.contacts {
        let fresh = || vec![Force::zero(); tree.loads()];
        match &c.kind {
            ContactKind::JointLimit { lower, upper, .. } => {
                for _ in lower.iter().chain(upper) {
                    out.push(fresh());
                }
            }
            ContactKind::Plane {
                at,
                normal,
                point,
                on,
                ..
            } => {
                let plane = PlaneAt::new(tree, &low, k, point, normal, *on)?;
                let mut l = fresh();
                apply(&mut l, at, plane.n)?;
                // The reaction on the plane's body, on the same line.
                let x = site_of(tree, &low, ev, k, at)?.0;
                plane.react(&mut l, k, x, -plane.n);
                out.push(l);
            }
            ContactKind::Spheres { a, b, .. } => {
                let d = site_of(tree, &low, ev, k, a)?.0 - site_of(tree, &low, ev, k, b)?.0;
                let unit = d.scale(S::one() / d.norm());
                let mut l = fresh();
                apply(&mut l, a, unit)?;
                apply(&mut l, b, -unit)?;
                out.push(l);
            }
        }
    }
    Ok(out)
}

/// The tangent axes `t₁`, `t₂` of a plane with unit normal `n` (world
/// axes): `t₁` the world axis least aligned with `n` (ties: x before y
/// before z) projected onto the plane and normalised, `t₂ = n × t₁`; so a
/// floor with `n = +z` has `t₁ = +x`, `t₂ = +y`.
pub fn tangent_axes(n: [f64; 3]) -> [[f64; 3]; 2] {
    let axis = least_aligned_axis(n);
    let mut t1 = [0.0; 3];
    t1[axis] = 1.0;
    let along = n[axis];
    for k in 0..3 {
        t1[k] -= along * n[k];
    }
    let len = (t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]).sqrt();
    let t1 = t1.map(|x| super::lower::snap(x / len));
    let t2 = [
        n[1] * t1[2] - n[2] * t1[1],
        n[2] * t1[0] - n[0] * t1[2],
        n[0] * t1[1] - n[1] * t1[0],
    ]
    .map(super::lower::snap);
    [t1, t2]
}

/// The world axis (0 x, 1 y, 2 z) least aligned with `n`; ties: x before
/// y before z.
pub fn least_aligned_axis(n: [f64; 3]) -> usize {
    let mut axis = 0;
    for k in 1..3 {
        if n[k].abs() < n[axis].abs() {
            axis = k;
        }
    }
    axis
}

/// Whether any contact has tangential rows: a plane contact or two
/// spheres with `μ > 0` (validation refuses friction on joint limits).
pub fn has_friction(sys: &System) -> bool {
    sys.contacts.iter().any(|c| {
        c.mu > 0.0
            && matches!(
                c.kind,
                ContactKind::Plane { .. } | ContactKind::Spheres { .. }
            )
    })
}

/// The unit line of centres `n = (x_a − x_b)/‖x_a − x_b‖` of every
/// `Spheres` contact (`None` for the other kinds).
pub fn sphere_normals<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
) -> Result<Vec<Option<Vec3<S>>>, MechError> {
    let low = Lowering::new(env);
    let mut out = Vec::new();
    for c in &sys.contacts {
        out.push(match &c.kind {
            ContactKind::Spheres { a, b, .. } => {
                let (xa, _) = site_of(tree, &low, ev, k, a)?;
                let (xb, _) = site_of(tree, &low, ev, k, b)?;
                let d = xa - xb;
                Some(d.scale(S::one() / d.norm()))
            }
            _ => None,
        });
    }
    Ok(out)
}

/// The material point an anchor names (body or node coordinates).
fn anchor<S: Scalar>(
    tree: &TreeModel<S>,
    low: &Lowering<'_, S>,
    p: &Point,
) -> Result<Site<S>, MechError> {
    Ok(Site {
        body: tree.index_of_body[p.body],
        node: p.node,
        point: low.vec3(&p.position)?,
    })
}

/// World position and velocity of an anchor.
fn site_of<S: Scalar>(
    tree: &TreeModel<S>,
    low: &Lowering<'_, S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
    p: &Point,
) -> Result<(Vec3<S>, Vec3<S>), MechError> {
    Ok(ev.site(k, &anchor(tree, low, p)?))
}

/// The tangent axes of two spheres touching along the unit line of
/// centres `n`: `t₁ = (a − (a·n) n)/‖…‖` from the contact's world axis
/// `a` (`tangent_reference`), `t₂ = n × t₁`.
fn sphere_tangents<S: Scalar>(n: Vec3<S>, reference: [f64; 3]) -> [Vec3<S>; 2] {
    let a = Vec3::from_f64(reference);
    let t = a - n.scale(a.dot(n));
    let t1 = t.scale(S::one() / t.norm());
    [t1, n.cross(t1)]
}

/// The loads of a world force `fw` at the material point `site` (body or
/// node coordinates) into `loads`; nothing on the ground.
fn load_at<S: Scalar>(
    tree: &TreeModel<S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
    loads: &mut [super::spatial::Force<S>],
    site: &Site<S>,
    fw: Vec3<S>,
) {
    let Some(i) = site.body else {
        return;
    };
    let (slot, frame) = match site.node {
        Some(node) => match tree.node_load(i, node) {
            Some(slot) => (slot, ev.node_frame(k, i, node).map(|x| x.0)),
            None => (i, None),
        },
        None => (i, None),
    };
    let e = frame.map_or(k.world[i].e, |f| f.e);
    let fb = e.tr_mul_vec(fw);
    loads[slot] = loads[slot].add(super::spatial::Force {
        n: site.point.cross(fb),
        f: fb,
    });
}

/// The unit line of centres from `b` to `a`.
fn unit_line<S: Scalar>(
    tree: &TreeModel<S>,
    low: &Lowering<'_, S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
    a: &Point,
    b: &Point,
) -> Result<Vec3<S>, MechError> {
    let d = site_of(tree, low, ev, k, a)?.0 - site_of(tree, low, ev, k, b)?.0;
    Ok(d.scale(S::one() / d.norm()))
}

/// The material point of the body carrying `at` that touches the plane:
/// `at`'s position less `radius · n`, in the coordinates of the frame `at`
/// is given in (the body's, or its node's).
fn touching_point<S: Scalar>(
    tree: &TreeModel<S>,
    low: &Lowering<'_, S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
    at: &Point,
    radius: S,
    n: Vec3<S>,
) -> Result<Site<S>, MechError> {
    let body = tree.index_of_body[at.body];
    let point = low.vec3(&at.position)?;
    let rot = body.map(|i| {
        at.node
            .and_then(|node| ev.node_frame(k, i, node))
            .map_or(k.world[i].e, |f| f.0.e)
    });
    let offset = rot.map_or(n.scale(radius), |e| e.tr_mul_vec(n.scale(radius)));
    Ok(Site {
        body,
        node: at.node,
        point: point - offset,
    })
}

/// Where a contact with friction touches, at a state: the touching
/// material point `a`, what it slides on, and the tangent axes `t₁`, `t₂`
/// (world axes).
struct Touch<S> {
    a: Site<S>,
    on: Against<S>,
    tangents: [Vec3<S>; 2],
}

/// What a touching point slides on.
enum Against<S> {
    /// A plane (fixed, or moving with its body).
    Plane(PlaneAt<S>),
    /// The other sphere's touching material point.
    Point(Site<S>),
}

/// The touch of contact `c` if it has friction (`μ > 0`): for a plane the
/// anchor less `radius · n` (so a rolling sphere has `v_t = 0`) and the
/// plane's [`tangent_axes`]; for two spheres a's surface point towards b
/// against b's towards a, along [`sphere_tangents`]. `None` for every
/// contact without tangential rows.
fn touch<S: Scalar>(
    c: &crate::system::ContactInfo,
    tree: &TreeModel<S>,
    low: &Lowering<'_, S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
) -> Result<Option<Touch<S>>, MechError> {
    if c.mu <= 0.0 {
        return Ok(None);
    }
    Ok(match &c.kind {
        ContactKind::Plane {
            at,
            radius,
            normal,
            point,
            on,
        } => {
            let plane = PlaneAt::new(tree, low, k, point, normal, *on)?;
            Some(Touch {
                a: touching_point(tree, low, ev, k, at, low.quantity(radius)?, plane.n)?,
                tangents: plane.tangents(),
                on: Against::Plane(plane),
            })
        }
        ContactKind::Spheres {
            a,
            b,
            radius_a,
            radius_b,
            tangent_reference,
        } => {
            let n = unit_line(tree, low, ev, k, a, b)?;
            Some(Touch {
                a: touching_point(tree, low, ev, k, a, low.quantity(radius_a)?, n)?,
                on: Against::Point(touching_point(
                    tree,
                    low,
                    ev,
                    k,
                    b,
                    low.quantity(radius_b)?,
                    -n,
                )?),
                tangents: sphere_tangents(n, *tangent_reference),
            })
        }
        ContactKind::JointLimit { .. } => None,
    })
}

/// Per gap row (in the order of [`gaps`]) the tangential speeds
/// `v_t = (t₁·v, t₂·v)` of the touching material point relative to what
/// it slides on (see [`touch`]); zero for every row without friction.
pub fn tangential_speeds<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
) -> Result<Vec<[S; 2]>, MechError> {
    let low = Lowering::new(env);
    let mut out = Vec::new();
    for c in &sys.contacts {
        match touch(c, tree, &low, ev, k)? {
            Some(t) => {
                let (xa, va) = ev.site(k, &t.a);
                let v = va
                    - match &t.on {
                        Against::Plane(plane) => plane.velocity(ev, k, xa),
                        Against::Point(b) => ev.site(k, b).1,
                    };
                out.push(t.tangents.map(|t| t.dot(v)));
            }
            None => {
                for _ in c.rows() {
                    out.push([S::zero(), S::zero()]);
                }
            }
        }
    }
    Ok(out)
}

/// Per gap row the loads of a unit tangential impulse along `t₁` and along
/// `t₂` at the touching material point, and its reaction on what it slides
/// on (see [`touch`]); no load for rows without friction.
pub fn tangential_unit_loads<S: Scalar>(
    sys: &System,
    tree: &TreeModel<S>,
    env: &dyn Env<S>,
    ev: &Evaluator<'_, S>,
    k: &Kinematics<S>,
) -> Result<Vec<[Vec<super::spatial::Force<S>>; 2]>, MechError> {
    use super::spatial::Force;
    let low = Lowering::new(env);
    let mut out = Vec::new();
    for c in &sys.contacts {
        let fresh = || vec![Force::zero(); tree.loads()];
        match touch(c, tree, &low, ev, k)? {
            Some(t) => {
                let xa = ev.site(k, &t.a).0;
                let mut pair = [fresh(), fresh()];
                for (l, dir) in pair.iter_mut().zip(t.tangents) {
                    load_at(tree, ev, k, l, &t.a, dir);
                    match &t.on {
                        Against::Plane(plane) => plane.react(l, k, xa, -dir),
                        Against::Point(b) => load_at(tree, ev, k, l, b, -dir),
                    }
                }
                out.push(pair);
            }
            None => {
                for _ in c.rows() {
                    out.push([fresh(), fresh()]);
                }
            }
        }
    }
    Ok(out)
}

/// The plane of a `Plane` contact at a state: its unit normal `n` and a
/// point `p` in world axes, its tangent axes, and the tree body it is
/// fixed on (`None`: the ground).
struct PlaneAt<S> {
    n: Vec3<S>,
    p: Vec3<S>,
    body: Option<usize>,
    /// The normal as written (world axes, or the body's).
    n0: [f64; 3],
    /// The body's axes in the world (`None`: the ground).
    axes: Option<crate::sym::Mat3<S>>,
}

impl<S: Scalar> PlaneAt<S> {
    fn new(
        tree: &TreeModel<S>,
        low: &Lowering<'_, S>,
        k: &Kinematics<S>,
        point: &crate::system::Vec3Q,
        normal: &crate::system::Axis,
        on: usize,
    ) -> Result<Self, MechError> {
        let n0 = [normal.unit.x, normal.unit.y, normal.unit.z].map(super::lower::snap);
        let (n, p) = (Vec3::from_f64(n0), low.vec3(point)?);
        let body = tree.index_of_body[on];
        Ok(match body {
            None => PlaneAt {
                n,
                p,
                body,
                n0,
                axes: None,
            },
            Some(i) => {
                let w = &k.world[i];
                PlaneAt {
                    n: w.e.mul_vec(n),
                    p: w.point(p),
                    body,
                    n0,
                    axes: Some(w.e),
                }
            }
        })
    }

    /// The world velocity of the plane's material point at world `x`.
    fn velocity(&self, ev: &Evaluator<'_, S>, k: &Kinematics<S>, x: Vec3<S>) -> Vec3<S> {
        match self.body {
            None => Vec3::zero(),
            Some(i) => {
                let w = &k.world[i];
                ev.point(k, Some(i), w.e.tr_mul_vec(x - w.r)).1
            }
        }
    }

    /// The tangent axes `t₁`, `t₂` in world axes ([`tangent_axes`] of the
    /// written normal, turned with the plane's body).
    fn tangents(&self) -> [Vec3<S>; 2] {
        tangent_axes(self.n0).map(|t| {
            let t = Vec3::from_f64(t);
            self.axes.as_ref().map_or(t, |e| e.mul_vec(t))
        })
    }

    /// Adds the world force `fw` at world point `x` to the plane's body
    /// (nothing for the ground).
    fn react(
        &self,
        loads: &mut [super::spatial::Force<S>],
        k: &Kinematics<S>,
        x: Vec3<S>,
        fw: Vec3<S>,
    ) {
        if let Some(i) = self.body {
            let w = &k.world[i];
            let fb = w.e.tr_mul_vec(fw);
            let point = w.e.tr_mul_vec(x - w.r);
            loads[i] = loads[i].add(super::spatial::Force {
                n: point.cross(fb),
                f: fb,
            });
        }
    }
}
