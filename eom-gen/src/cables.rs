//! A checked model whose cables hang at markers of its rigid bodies, as
//! one large model of `eom_sim::large::mixed`: every cable of the model
//! built by its kernel's name into one structure
//! (`eom_sim::large::ancf::chains`, each cable's nodes at its own offset),
//! the ends held at markers by attachment constraints, cables held at no
//! marker (free, or held to ground) simply part of the same structure, and
//! the rigid part from the generated functions (`mass_matrix`, `bias`,
//! `energy`, `attachments`), interpreted or compiled.
//!
//! A rigid part with constraint equations of its own (cut joints closing
//! loops, the model's holonomic `constraints:`, rheonomic ones included)
//! brings their position-level rows `Φ_r(q, t) = 0` and `Φ_q` from the
//! generated `constraints` function (`J = Φ_q` as `q̇ = u`): more rows of
//! the mixed model's constraint block ([`RigidPart::constraints`]). Its
//! start is assembled onto the loops ([`rigid_start`]). Speed-level
//! (nonholonomic) equations, such as a rolling disk's no-slip
//! conditions, are refused by name: the index-3 method holds positions.

use crate::ancf::Kind;
use crate::functions::Function;
use crate::mech::Formulation;
use crate::system::{CableInfo, Support, System};
use eom_sim::elements::Element;
use eom_sim::large::ancf::{ChainSpec, Chains, Section, chains};
use eom_sim::large::{ByName, MixedModel, RigidPart};

/// Why a model's cables cannot run with its rigid part: each names the
/// model, cable, marker or coordinate concerned and what would be right.
#[derive(Clone, Debug, PartialEq)]
pub enum CableError {
    /// The rigid part has speed-level equations (their names).
    Nonholonomic {
        /// The model.
        model: String,
        /// The nonholonomic rows.
        rows: Vec<String>,
    },
    /// Coordinates and speeds differ in number (or quaternions).
    SpeedsNotRates {
        /// The model.
        model: String,
        /// Coordinates and speeds, when their numbers differ.
        sizes: Option<(usize, usize)>,
    },
    /// A planar cable hangs at a marker that leaves the plane z = 0.
    OffPlane {
        /// The cable.
        cable: String,
        /// Its element type.
        element: &'static str,
        /// `body.marker`.
        marker: String,
        /// Its end (true) or start.
        end: bool,
        /// Held by a clamp (whose axis may turn out of the plane).
        clamp: bool,
    },
    /// The rigid part's loops do not close near the initial values.
    LoopOpen {
        /// The model.
        model: String,
        /// `|Φ|` after assembly.
        residual: f64,
        /// The loops' equations.
        constraints: Vec<String>,
    },
    /// Assembly moves initial values (coordinate, given, closed).
    StartMoved {
        /// The model.
        model: String,
        /// The loops' equations.
        constraints: Vec<String>,
        /// Each moved coordinate: name, given value, closed value.
        moved: Vec<(String, f64, f64)>,
    },
    /// The model has no cables.
    NoCables {
        /// The model.
        model: String,
    },
    /// A cable's chain could not be built.
    Chain {
        /// The cable.
        cable: String,
        /// Why.
        error: eom_sim::large::ancf::ChainError,
    },
    /// A node force at a node the cable does not have.
    NoNode {
        /// The cable.
        cable: String,
        /// The node asked for.
        node: usize,
        /// Its last node.
        last: usize,
    },
    /// The mixed model could not be formed.
    Mixed {
        /// The model.
        model: String,
        /// Why.
        error: eom_sim::large::MixedError,
    },
}

impl std::fmt::Display for CableError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CableError::Nonholonomic { model, rows } => write!(
                f,
                "the rigid part of `{model}` has speed-level (nonholonomic) constraint equations ({}): beside cables the index-3 method holds positions only, `Φ(q, t) = 0` (cut joints, `Holonomic` constraints); a rolling contact's no-slip conditions have no position form",
                rows.join(", ")
            ),
            CableError::SpeedsNotRates {
                model,
                sizes: Some((nq, nu)),
            } => write!(
                f,
                "the rigid part of `{model}` has {nq} coordinates and {nu} speeds: cables join rigid parts whose speeds are the coordinates' rates (revolute, prismatic joints)"
            ),
            CableError::SpeedsNotRates { model, sizes: None } => write!(
                f,
                "the rigid part of `{model}` has speeds that are not the coordinates' rates (q̇ ≠ u): cables join revolute and prismatic chains"
            ),
            CableError::OffPlane {
                cable,
                element,
                marker,
                end,
                clamp,
            } => write!(
                f,
                "cable `{cable}` is planar ({element}) but the marker `{marker}` holding its {} leaves the plane z = 0 as the rigid part moves{}: use `Cable3D`, or keep the marker in the x–y plane (revolute joints about z, prismatic joints in x–y)",
                if *end { "end" } else { "start" },
                if *clamp {
                    " (or its clamp's axis turns out of the plane)"
                } else {
                    ""
                }
            ),
            CableError::LoopOpen {
                model,
                residual,
                constraints,
            } => write!(
                f,
                "the rigid part of `{model}` does not close its loops near the initial values: |Φ| = {residual:.3e} after assembly ({}); check the joint frames and the initial values of the loop's joints",
                constraints.join(", ")
            ),
            CableError::StartMoved {
                model,
                constraints,
                moved,
            } => write!(
                f,
                "the initial values of `{model}` do not close its loops ({}): assembly moves {}; give the closed values (the cables' `from`/`to` must meet their markers there)",
                constraints.join(", "),
                moved
                    .iter()
                    .map(|(n, x, y)| format!("`{n}` from {x} to {y}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            CableError::NoCables { model } => write!(f, "model `{model}` has no cables"),
            CableError::Chain { cable, error } => write!(f, "cable `{cable}`: {error}"),
            CableError::NoNode { cable, node, last } => write!(
                f,
                "cable `{cable}` has no node {node} (its nodes are 0 to {last})"
            ),
            CableError::Mixed { model, error } => write!(f, "model `{model}`: {error}"),
        }
    }
}

impl std::error::Error for CableError {}

/// The runtime's kernel of a generator's element type (its registry
/// `eom_sim::elements::Element` runs the kernels `ancf::emit` wrote).
pub fn element(kind: Kind) -> Element {
    match kind {
        Kind::Cable2D => Element::Cable2D,
        Kind::Cable2DGreen => Element::Cable2DGreen,
        Kind::Cable3D => Element::Cable3D,
        Kind::Beam2D => Element::Beam2D,
    }
}

/// The runtime's description of a validated cable's chain
/// (`eom_sim::large::ancf::chain` builds it by its kernel).
pub fn chain_spec(cable: &CableInfo) -> ChainSpec {
    let c = &cable.chain;
    let s = &c.section;
    let support = |s: Support| match s {
        Support::Free => eom_sim::large::ancf::Support::Free,
        Support::Pinned => eom_sim::large::ancf::Support::Pinned,
        Support::Clamped => eom_sim::large::ancf::Support::Clamped,
    };
    ChainSpec {
        kernel: element(c.element),
        start: c.start,
        end: c.end,
        elements: c.elements,
        section: Section {
            e: s.e,
            nu: s.nu,
            rho: s.rho,
            area: s.area,
            inertia: s.inertia,
            b: s.b,
            h: s.h,
            damping_axial: s.damping_axial,
            damping_bending: s.damping_bending,
            retardation: s.retardation,
        },
        start_support: support(c.start_support),
        end_support: support(c.end_support),
        end_force: c.end_force,
        end_mass: c.end_mass,
        gravity: c.gravity,
    }
}

/// One cable of a model with elements: what it is and where its nodes sit
/// in the structure's full coordinates (the runtime's layout).
pub use eom_sim::large::CableLayout as MixedCable;

/// A mixed model and how to read its cables.
pub struct Mixed<'r> {
    /// The model.
    pub model: MixedModel<'r>,
    /// Every cable of the model, in file order.
    pub cables: Vec<MixedCable>,
}

impl Mixed<'_> {
    /// Position of `node` of cable `cable` (index into [`Mixed::cables`])
    /// in the structure's full coordinates (`z = 0` when planar).
    pub fn node_position(&self, q_full: &[f64], cable: usize, node: usize) -> [f64; 3] {
        self.cables[cable].node_position(q_full, node)
    }

    /// The index of the cable named `name`.
    pub fn cable(&self, name: &str) -> Option<usize> {
        self.cables.iter().position(|c| c.name == name)
    }
}

/// True if the model has rigid bodies beside its cables (held at their
/// markers, touching them, or neither): it runs as one mixed model
/// ([`mixed`]).
pub fn has_rigid_part(sys: &System) -> bool {
    sys.bodies.len() > 1
}

/// Why the rigid part of `sys` cannot join its cables, or `Ok`: the large
/// runtime needs `q̇ = u` (no quaternions, no speeds other than the
/// coordinates' rates), constraint equations of its own only at the
/// position level (holonomic: cut joints, `Holonomic` constraints), and a
/// planar cable's ends held at markers that move in the plane z = 0
/// ([`check_planar_mounts`]). Any number of cables, of any kernels.
pub fn check_rigid(sys: &System, f: &Formulation) -> Result<(), CableError> {
    if f.constraint_names.len() > f.n_holonomic {
        return Err(CableError::Nonholonomic {
            model: sys.name.clone(),
            rows: f.constraint_names[f.n_holonomic..].to_vec(),
        });
    }
    let (nq, nu) = (sys.nq(), sys.nu());
    if nq != nu || !sys.quaternion_indices().is_empty() {
        return Err(CableError::SpeedsNotRates {
            model: sys.name.clone(),
            sizes: Some((nq, nu)),
        });
    }
    // q̇ = u at a generic state.
    let q: Vec<f64> = sys
        .q0()
        .iter()
        .enumerate()
        .map(|(i, x)| x + 0.1 + 0.01 * i as f64)
        .collect();
    let u: Vec<f64> = (0..nu).map(|i| 0.3 + 0.7 * i as f64).collect();
    let x = crate::interpret::Point {
        sys,
        q: &q,
        u: &u,
        udot: &[],
        tau: &[],
        inputs: &[],
        params: &[],
        multipliers: &[],
        t: 0.0,
    };
    let qdot = crate::interpret::evaluate_function(f, Function::Qdot, &x).unwrap_or_default();
    if qdot.len() != nu
        || qdot
            .iter()
            .zip(&u)
            .any(|(a, b)| (a - b).abs() > 1e-12 * (1.0 + b.abs()))
    {
        return Err(CableError::SpeedsNotRates {
            model: sys.name.clone(),
            sizes: None,
        });
    }
    check_planar_mounts(sys, f, &x)
}

/// A planar cable (`Cable2D`, `Cable2DGreen`, `Beam2D`) moves in the plane
/// z = 0, and its attachments hold only the x and y of its end: the
/// marker it hangs at must stay in that plane (`p_z = 0` and `∂p_z/∂q = 0`),
/// and a clamp's normal `n₁` too, at the generic state `x` (else the
/// marker would leave the cable behind, unseen). `Err` names the cable,
/// its end and the marker.
fn check_planar_mounts(
    sys: &System,
    f: &Formulation,
    x: &crate::interpret::Point<'_>,
) -> Result<(), CableError> {
    let mounts = sys.cable_mounts();
    let planar = |c: usize| sys.cables[c].chain.element.dim() == 2;
    if !mounts.iter().any(|(c, _, _)| planar(*c)) {
        return Ok(());
    }
    let stride = 1 + sys.nq();
    let rows = crate::interpret::evaluate_function(f, Function::Attachments, x).unwrap_or_default();
    let mut at = 0;
    for (c, end, m) in &mounts {
        let n_rows = if m.axis.is_some() { 9 } else { 3 };
        let block = rows.get(at * stride..(at + n_rows) * stride);
        at += n_rows;
        if !planar(*c) {
            continue;
        }
        // Rows p_z (2) and, for a clamp, n₁_z (5): value and partials.
        let checked: &[usize] = if m.axis.is_some() { &[2, 5] } else { &[2] };
        let off_plane = match block {
            Some(b) => checked
                .iter()
                .flat_map(|r| &b[r * stride..(r + 1) * stride])
                .any(|v| v.is_nan() || v.abs() > 1e-12),
            None => true,
        };
        if off_plane {
            let cable = &sys.cables[*c];
            let body = &sys.bodies[m.body];
            return Err(CableError::OffPlane {
                cable: cable.name.clone(),
                element: cable.chain.element.name(),
                marker: format!("{}.{}", body.name, body.markers[m.marker].name),
                end: *end,
                clamp: m.axis.is_some(),
            });
        }
    }
    Ok(())
}

/// The rigid part of `sys` run by the interpreter (see [`check_rigid`]).
pub fn interpreted_rigid<'a>(f: &'a Formulation, sys: &'a System) -> Box<dyn RigidPart + 'a> {
    let interp = crate::interpret::Interpreted::new(f, sys);
    let len = crate::mech::mounts::mount_rows(sys) * (1 + sys.nq());
    Box::new(
        ByName::new(sys.nu(), len, move |name, at, out| {
            eom_sim::Simulate::evaluate(&interp, name, at, out)
        })
        .with_constraints(f.constraint_names.len(), holonomic_names(f))
        .with_energy_source(energy_source(sys))
        .with_contacts(contact_names(sys))
        .with_frames(sys.cable_frames().len()),
    )
}

/// The names of the rigid part's contact rows (a joint limit's lower and
/// upper rows apart), the rows of the generated `contacts`, for
/// [`ByName::with_contacts`].
pub fn contact_names(sys: &System) -> Vec<String> {
    sys.contact_rows().into_iter().map(|(_, r)| r).collect()
}

/// What can feed energy into the rigid part of `sys`
/// ([`System::energy_sources`], joined), for
/// [`ByName::with_energy_source`]; `None` for a passive rigid part.
pub fn energy_source(sys: &System) -> Option<String> {
    let sources = sys.energy_sources();
    (!sources.is_empty()).then(|| sources.join(", "))
}

/// The names of the rigid part's holonomic equations (the rows
/// [`RigidPart::constraints`] gives), for [`ByName::with_constraints`].
pub fn holonomic_names(f: &Formulation) -> Vec<String> {
    f.constraint_names[..f.n_holonomic.min(f.constraint_names.len())].to_vec()
}

/// The rigid part's starting coordinates and speeds: the model's `q0`,
/// `u0`, and when it has constraint equations of its own, assembled onto
/// them (`eom_sim::constrained::assemble`: Newton onto `Φ(q, t) = 0`, then
/// the smallest change of the speeds onto `J u + Φ_t = 0`). The cables'
/// reference lines are given in the file, at the markers of `q0`: an
/// assembly that has to move a coordinate by more than `1e-8` is refused,
/// naming the coordinate and the value that closes the loop.
pub fn rigid_start(sys: &System, f: &Formulation) -> Result<(Vec<f64>, Vec<f64>), CableError> {
    let (q0, u0) = (sys.q0(), sys.u0());
    if f.constraint_names.is_empty() {
        return Ok((q0, u0));
    }
    let interp = crate::interpret::Interpreted::new(f, sys);
    let a = eom_sim::constrained::assemble(&interp, &q0, &u0, 0.0);
    if a.residual.is_nan() || a.residual > 1e-10 {
        return Err(CableError::LoopOpen {
            model: sys.name.clone(),
            residual: a.residual,
            constraints: f.constraint_names.clone(),
        });
    }
    let names = sys.coordinate_names();
    let moved: Vec<(String, f64, f64)> = q0
        .iter()
        .zip(&a.q)
        .zip(&names)
        .filter(|((x, y), _)| (*x - *y).is_nan() || (*x - *y).abs() > 1e-8)
        .map(|((x, y), n)| (n.to_string(), *x, *y))
        .collect();
    if !moved.is_empty() {
        return Err(CableError::StartMoved {
            model: sys.name.clone(),
            constraints: f.constraint_names.clone(),
            moved,
        });
    }
    Ok((a.q, a.u))
}

/// Every cable of the model in one structure, in file order (each cable's
/// nodes after the previous cable's; its distributed load and node forces
/// carried over), and where each cable sits: a model of cables alone runs
/// as this structure, a mixed model joins it to its rigid part.
pub fn structure(sys: &System) -> Result<(Chains, Vec<MixedCable>), CableError> {
    if sys.cables.is_empty() {
        return Err(CableError::NoCables {
            model: sys.name.clone(),
        });
    }
    let specs: Vec<_> = sys.cables.iter().map(chain_spec).collect();
    let mut built = chains(&specs).map_err(|e| CableError::Chain {
        cable: sys.cables[e.chain].name.clone(),
        error: e.error,
    })?;
    for (k, c) in sys.cables.iter().enumerate() {
        if c.distributed_load != [0.0; 3] {
            built.add_distributed_load(k, c.distributed_load);
        }
        let part = &built.parts[k];
        for &(node, f) in &c.node_forces {
            if node >= part.nodes {
                return Err(CableError::NoNode {
                    cable: c.name.clone(),
                    node,
                    last: part.nodes - 1,
                });
            }
            for (k, &fk) in f.iter().enumerate().take(part.dim) {
                built.model.add_point_load(part.position_index(node, k), fk);
            }
        }
    }
    if sys.cables.iter().any(|c| c.initial_motion != [[0.0; 3]; 2]) {
        let mut v0 = vec![0.0; built.model.n_full()];
        for (k, c) in sys.cables.iter().enumerate() {
            let [v, w] = c.initial_motion;
            for (i, vi) in built.rigid_velocity(k, v, w) {
                v0[i] = vi;
            }
        }
        built.model.set_initial_velocity(v0);
    }
    let cables = sys
        .cables
        .iter()
        .zip(&built.parts)
        .map(|(c, p)| MixedCable {
            name: c.name.clone(),
            kernel: p.kernel.name(),
            dim: p.dim,
            node_coords: p.node_coords,
            nodes: p.nodes,
            offset: p.offset,
        })
        .collect();
    Ok((built, cables))
}

/// The model's contacts at cable nodes over the structure `cables` lays
/// out ([`structure`]): per contact the node's position coordinates along
/// the plane's normal, `g = n·x − (n·p + r)` (a planar cable's `z = 0`),
/// and along the plane's tangent axes for Coulomb friction: `t1`, `t2` of
/// the rigid contacts ([`crate::mech::contacts::tangent_axes`]) for a
/// spatial cable; for a planar one `t1 = n × z` in its plane (`t2 = z`
/// has no coordinate there, its row is empty).
pub fn node_contacts(sys: &System, cables: &[MixedCable]) -> Vec<eom_sim::large::NodeContact> {
    // A body's plane or sphere: its frame, in `System::cable_frames` order.
    let start = crate::mech::mounts::frames_at_start(sys);
    let mut frames = 0..;
    sys.cable_contacts
        .iter()
        .map(|c| (c, c.against.on_body().and_then(|_| frames.next())))
        .filter_map(|(c, frame)| {
            let layout = cables.get(c.cable)?;
            let base = layout.offset + c.node * layout.node_coords;
            let along = |d: [f64; 3]| -> Vec<(usize, f64)> {
                (0..layout.dim.min(3))
                    .filter(|&a| d[a] != 0.0)
                    .map(|a| (base + a, d[a]))
                    .collect()
            };
            let coords = |layout: &MixedCable, node: usize| -> Vec<usize> {
                let base = layout.offset + node * layout.node_coords;
                (0..layout.dim.min(3)).map(|a| base + a).collect()
            };
            // A node's sphere against `b`'s coordinates or a fixed `centre`:
            // the planar rule for its friction axes (`t1 = n × z`) where
            // both centres stay in the x–y plane (`other_planar`), the
            // spatial one otherwise (a `Cable3D` on either side, or a fixed
            // centre off the plane).
            let sphere = |b: Vec<usize>, centre: [f64; 3], other_planar: bool| {
                let reference = (layout.dim != 2 || !other_planar).then(|| {
                    let mut a = [0.0; 3];
                    let line = c.line_at_start(sys, None).unwrap_or([0.0, 0.0, 1.0]);
                    a[crate::mech::contacts::least_aligned_axis(line)] = 1.0;
                    a
                });
                eom_sim::large::NodeContact {
                    name: c.name.clone(),
                    row: Vec::new(),
                    level: 0.0,
                    e: c.e,
                    mu: c.mu,
                    tangents: [Vec::new(), Vec::new()],
                    sphere: Some(eom_sim::large::NodeSphere {
                        a: coords(layout, c.node),
                        b,
                        centre,
                        radius: c.radius,
                        reference,
                    }),
                    body: None,
                }
            };
            // A body's plane (normal and tangent axes in its axes) or
            // sphere (its reference axis from the line of centres at the
            // start, as for rigid spheres).
            let on_body = |plane: Option<[f64; 3]>, radius_b: f64| {
                let frame = frame?;
                let line = c
                    .line_at_start(sys, start.get(frame))
                    .unwrap_or([0.0, 0.0, 1.0]);
                let mut reference = [0.0; 3];
                reference[crate::mech::contacts::least_aligned_axis(line)] = 1.0;
                Some(eom_sim::large::NodeContact {
                    name: c.name.clone(),
                    row: Vec::new(),
                    level: 0.0,
                    e: c.e,
                    mu: c.mu,
                    tangents: [Vec::new(), Vec::new()],
                    sphere: None,
                    body: Some(eom_sim::large::NodeOnBody {
                        a: coords(layout, c.node),
                        frame,
                        plane: plane.map(|n| {
                            let [t1, t2] = crate::mech::contacts::tangent_axes(n);
                            [n, t1, t2]
                        }),
                        radius_a: c.radius - radius_b,
                        radius_b,
                        reference,
                    }),
                })
            };
            let (point, n) = match &c.against {
                crate::system::CableTarget::Plane { point, normal } => (*point, *normal),
                // A sphere: rows evaluated per state by the runtime; the
                // other centre (a node's coordinates, or fixed), and
                // whether it stays in the x–y plane.
                crate::system::CableTarget::Sphere { centre } => {
                    return Some(sphere(Vec::new(), *centre, centre[2] == 0.0));
                }
                crate::system::CableTarget::Node { cable, node } => {
                    let other = cables.get(*cable)?;
                    return Some(sphere(coords(other, *node), [0.0; 3], other.dim == 2));
                }
                crate::system::CableTarget::BodyPlane { normal, .. } => {
                    return on_body(Some(*normal), 0.0);
                }
                crate::system::CableTarget::BodySphere { radius, .. } => {
                    return on_body(None, *radius);
                }
            };
            let [t1, t2] = if layout.dim == 2 {
                [[n[1], -n[0], 0.0], [0.0, 0.0, -1.0]]
            } else {
                crate::mech::contacts::tangent_axes(n)
            };
            let row = (0..layout.dim).map(|a| (base + a, n[a])).collect();
            let level = (0..3).map(|a| n[a] * point[a]).sum::<f64>() + c.radius;
            Some(eom_sim::large::NodeContact {
                name: c.name.clone(),
                row,
                level,
                e: c.e,
                mu: c.mu,
                tangents: [along(t1), along(t2)],
                sphere: None,
                body: None,
            })
        })
        .collect()
}

/// Every cable of the model in one structure ([`structure`]), joined to
/// the rigid part `rigid` at the cable
/// ends held at markers (`System::cable_mounts` order, the order of the
/// generated `attachments`). Cables held at no marker are part of the
/// structure too (free, or held to ground by their supports).
pub fn mixed<'r>(sys: &System, rigid: Box<dyn RigidPart + 'r>) -> Result<Mixed<'r>, CableError> {
    let (built, cables) = structure(sys)?;
    let mut attachments = Vec::new();
    for (c, end, mount) in sys.cable_mounts() {
        let cable = &sys.cables[c];
        let name = format!("{}.{}", cable.name, if end { "end" } else { "start" });
        attachments.push(built.parts[c].attachment(&name, end, mount.axis.is_some()));
    }
    let model =
        MixedModel::new(built.model, rigid, attachments).map_err(|error| CableError::Mixed {
            model: sys.name.clone(),
            error,
        })?;
    Ok(Mixed { model, cables })
}
