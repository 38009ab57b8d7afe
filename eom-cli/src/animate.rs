//! The animation page of a run (`eom-gen animate`, `simulate --html`):
//! one self-contained HTML file that plays the motion in 3-D with
//! three.js (inlined from `assets/three.bundle.min.js`, made by
//! `assets/bundle.sh`), orbit, zoom, play/pause, a time slider and speed.
//!
//! The page gets poses, not vertices: the scene (per body its joint
//! frames, centre of mass, joint axis and markers, in body coordinates)
//! once, then per frame each body's world position and quaternion,
//! rounded to 6 decimals. The frames are the rows of the run's CSV.

use crate::error::Error;
use eom_gen::mech::numeric::{Numeric, PlacedShape, Scene};
use eom_gen::system::Shape;
use eom_sim::table::Table;
use std::fmt::Write;

const THREE: &str = include_str!("../assets/three.bundle.min.js");
const PAGE: &str = include_str!("../assets/animate.html");

/// The page for the trajectory `table` (columns `t` and the coordinates)
/// of `sys`, with the run's contact `events` (impacts flash the bodies
/// they hit).
pub fn html(
    sys: &eom_gen::system::System,
    table: &Table,
    events: &[eom_sim::run::ContactEvent],
) -> Result<String, Error> {
    let num = Numeric::new(sys).map_err(|e| Error::Refused(format!("{}: {e}", sys.name)))?;
    let scene = num
        .scene(sys)
        .map_err(|e| Error::Refused(format!("{}: {e}", sys.name)))?;
    let names = sys.coordinate_names();
    let column = |name: &str| {
        table
            .header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| Error::Format(format!("the trajectory has no column `{name}`")))
    };
    let t_col = column("t")?;
    let q_cols = names
        .iter()
        .map(|n| column(n))
        .collect::<Result<Vec<_>, _>>()?;
    // Cables: their nodes' positions per frame (columns `CABLE.nodeK.x`,
    // `.y`, `.z` of the run's table), drawn as the deformed chain.
    let mut cables = Vec::new();
    for c in &sys.cables {
        let mut cols = Vec::new();
        for k in 0.. {
            let at = |a: &str| {
                let name = format!("{}.node{k}.{a}", c.name);
                table.header.iter().position(|h| *h == name)
            };
            match (at("x"), at("y"), at("z")) {
                (Some(x), Some(y), Some(z)) => cols.extend([x, y, z]),
                _ => break,
            }
        }
        if cols.len() < 6 {
            return Err(Error::Format(format!(
                "the trajectory has no node positions of cable `{}` (`{}.node0.x`, …)",
                c.name, c.name
            )));
        }
        cables.push((c.name.clone(), cols));
    }
    let flexes = flex_bodies(sys, &scene)?;
    if let Some(f) = flexes.iter().find(|f| f.q_index + f.k > q_cols.len()) {
        return Err(Error::Format(format!(
            "the elastic coordinates of `{}` lie past the model's {} coordinates",
            scene.bodies[f.body].name,
            q_cols.len()
        )));
    }
    let mut flex_frames = String::from("[");
    let mut cable_frames = String::from("[");
    let mut frames = String::from("[");
    let mut times = String::from("[");
    let mut q = vec![0.0; q_cols.len()];
    for (k, row) in table.rows.iter().enumerate() {
        for (x, &c) in q.iter_mut().zip(&q_cols) {
            *x = row[c];
        }
        let t = row[t_col];
        let poses = num
            .world_poses(&q, t)
            .map_err(|e| Error::Refused(format!("{} at t = {t}: {e}", sys.name)))?;
        if k > 0 {
            frames.push(',');
            times.push(',');
            cable_frames.push(',');
            flex_frames.push(',');
        }
        flex_frames.push('[');
        for (j, x) in flexes
            .iter()
            .flat_map(|f| &q[f.q_index..f.q_index + f.k])
            .enumerate()
        {
            if j > 0 {
                flex_frames.push(',');
            }
            flex_frames.push_str(&significant(*x)?);
        }
        flex_frames.push(']');
        cable_frames.push('[');
        for (j, &c) in cables.iter().flat_map(|(_, cols)| cols).enumerate() {
            if j > 0 {
                cable_frames.push(',');
            }
            cable_frames.push_str(&number(row[c])?);
        }
        cable_frames.push(']');
        times.push_str(&number(t)?);
        frames.push('[');
        for (i, p) in poses.iter().enumerate() {
            let quat = quaternion(&p.rotation);
            for (j, v) in p.origin.iter().chain(&quat).enumerate() {
                if i + j > 0 {
                    frames.push(',');
                }
                frames.push_str(&number(*v)?);
            }
        }
        frames.push(']');
    }
    frames.push(']');
    times.push(']');
    cable_frames.push(']');
    flex_frames.push(']');
    let cable_list: Vec<serde_json::Value> = cables
        .iter()
        .map(|(name, cols)| serde_json::json!({ "name": name, "nodes": cols.len() / 3 }))
        .collect();
    if table.rows.is_empty() {
        return Err(Error::Refused(format!(
            "{}: the run recorded no frames to animate",
            sys.name
        )));
    }
    let mut meshes = Meshes::default();
    let bodies = bodies_json(sys, &scene, &mut meshes)?;
    let ground_geometry = shapes_json(&scene.ground_geometry, "ground", &mut meshes)?;
    let mut data = String::new();
    let _ = write!(
        data,
        "{{\"name\":{},\"gravity\":{},\"bodies\":{},\"ground\":{},\"groundGeometry\":{},\"meshes\":{},\"impacts\":{},\"cables\":{},\"cableFrames\":{cable_frames},\"flex\":{},\"flexFrames\":{flex_frames},\"t\":{times},\"poses\":{frames}}}",
        serde_json::to_string(&sys.name).unwrap_or_default(),
        serde_json::to_string(&gravity(&num)).unwrap_or_default(),
        bodies,
        serde_json::to_string(&scene.ground).unwrap_or_else(|_| "[]".into()),
        serde_json::to_string(&ground_geometry).unwrap_or_else(|_| "[]".into()),
        serde_json::to_string(&meshes.list).unwrap_or_else(|_| "[]".into()),
        serde_json::to_string(&impacts(sys, &scene, events)).unwrap_or_else(|_| "[]".into()),
        serde_json::to_string(&cable_list).unwrap_or_else(|_| "[]".into()),
        flex_json(&flexes)?,
    );
    // The data sits in a <script> element: no `</` may close it early.
    let data = data.replace("</", "<\\/");
    let title = sys.name.replace('&', "&amp;").replace('<', "&lt;");
    Ok(PAGE
        .replace("{{TITLE}}", &title)
        .replace("{{DATA}}", &data)
        .replace("{{THREE}}", THREE))
}

/// The impacts of the run: `[t, [scene body indices]]` for every impact
/// event, the bodies of each contact row that took an impulse (a joint
/// limit's child body; a sphere's body; both spheres' bodies).
pub fn impacts(
    sys: &eom_gen::system::System,
    scene: &Scene,
    events: &[eom_sim::run::ContactEvent],
) -> Vec<(f64, Vec<usize>)> {
    use eom_gen::system::ContactKind;
    let scene_index = |id: usize| {
        let name = &sys.bodies.get(id)?.name;
        scene.bodies.iter().position(|b| &b.name == name)
    };
    events
        .iter()
        .filter(|e| matches!(e.kind, eom_sim::run::ContactEventKind::Impact) && e.t.is_finite())
        .map(|e| {
            let mut hit: Vec<usize> = e
                .contacts
                .iter()
                .filter(|c| c.impulse > 0.0)
                .filter_map(|c| {
                    let name = c.contact.split('.').next().unwrap_or("");
                    sys.contacts.iter().find(|k| k.name == name)
                })
                .flat_map(|k| match &k.kind {
                    ContactKind::JointLimit { joint, .. } => {
                        vec![sys.joints.get(*joint).map_or(0, |j| j.child)]
                    }
                    ContactKind::Plane { at, .. } => vec![at.body],
                    ContactKind::Spheres { a, b, .. } => vec![a.body, b.body],
                })
                .filter_map(scene_index)
                .collect();
            hit.sort_unstable();
            hit.dedup();
            (e.t, hit)
        })
        .collect()
}

/// A flexible (floating-frame) body as the page draws it: stations along
/// it, each at `p + S q_f` in the body frame (`S` the station's
/// translational shapes, 3 × k, linear in the elastic coordinates), so the
/// page gets the shapes once and per frame only the body's pose and its
/// `k` elastic coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct FlexDrawing {
    /// The body's index in the scene (tree order).
    pub body: usize,
    /// Its first elastic coordinate in the system's `q`.
    pub q_index: usize,
    /// Number of elastic coordinates `k`.
    pub k: usize,
    /// The stations' undeformed places, body axes.
    pub places: Vec<[f64; 3]>,
    /// Per station, the rows `x, y, z` of its shapes (each `k` long).
    pub shapes: Vec<[Vec<f64>; 3]>,
    /// Which stations are finite-element (or named) nodes.
    pub nodes: Vec<usize>,
    /// Stations along an axis, joined by rods (a beam, assumed modes);
    /// `false`: an imported model's nodes, drawn as balls alone (no
    /// element connectivity is read).
    pub line: bool,
}

/// Stations per element of a built-in beam: the Hermite cubics between
/// the nodes drawn by this many straight pieces.
pub const PIECES_PER_ELEMENT: usize = 4;

/// Stations along a body with assumed modes (its shape functions of `x`
/// evaluated at each).
pub const ASSUMED_PIECES: usize = 32;

/// The flexible bodies of the scene: a built-in beam at
/// [`PIECES_PER_ELEMENT`] stations per element (the elements' cubic
/// interpolation of the mode shapes, `flex_outputs::deformation`);
/// assumed modes at [`ASSUMED_PIECES`]` + 1` stations (their shape
/// functions, `flex::assumed::section`); imported modal data at their
/// nodes (`flex_outputs::node_point`, where their shapes are known).
pub fn flex_bodies(
    sys: &eom_gen::system::System,
    scene: &Scene,
) -> Result<Vec<FlexDrawing>, Error> {
    use eom_gen::mech::flex_outputs::{deformation, node_point};
    use eom_gen::system::FlexSource;
    let mut out = Vec::new();
    for (i, b) in scene.bodies.iter().enumerate() {
        let Some(flex) = sys
            .bodies
            .iter()
            .find(|s| s.name == b.name)
            .and_then(|s| s.flexible.as_deref())
        else {
            continue;
        };
        let k = flex.count();
        let unit = |j: usize| -> Vec<f64> { (0..k).map(|m| f64::from(u8::from(m == j))).collect() };
        let zero = vec![0.0; k];
        let mut places = Vec::new();
        let mut shapes_at = Vec::new();
        let mut nodes = Vec::new();
        match flex.source {
            FlexSource::Beam => {
                let beam = &flex.beam;
                let n = beam.elements * PIECES_PER_ELEMENT;
                for s in 0..=n {
                    let x = beam.length * s as f64 / n as f64;
                    if s % PIECES_PER_ELEMENT == 0 {
                        nodes.push(places.len());
                    }
                    places.push([x, 0.0, 0.0]);
                    let cols: Vec<[f64; 6]> =
                        (0..k).map(|j| deformation(flex, x, &unit(j))).collect();
                    shapes_at.push(std::array::from_fn(|r| cols.iter().map(|c| c[r]).collect()));
                }
            }
            FlexSource::Assumed { ref shapes, .. } => {
                // The shape functions of `x` along the body.
                let n = ASSUMED_PIECES;
                for s in 0..=n {
                    let x = flex.beam.length * s as f64 / n as f64;
                    let Some(sec) = eom_gen::flex::assumed::section(shapes, x) else {
                        continue;
                    };
                    if s == 0 || s == n {
                        nodes.push(places.len());
                    }
                    places.push([x, 0.0, 0.0]);
                    shapes_at.push(std::array::from_fn(|r| {
                        (0..k).map(|j| sec.translation[(r, j)]).collect()
                    }));
                }
            }
            FlexSource::Modal { .. } => {
                for node in 0..flex.modes.shapes.nrows() / 6 {
                    let p = node_point(flex, node, &zero).0;
                    nodes.push(places.len());
                    places.push(p);
                    let cols: Vec<[f64; 3]> = (0..k)
                        .map(|j| {
                            let d = node_point(flex, node, &unit(j)).0;
                            [d[0] - p[0], d[1] - p[1], d[2] - p[2]]
                        })
                        .collect();
                    shapes_at.push(std::array::from_fn(|r| cols.iter().map(|c| c[r]).collect()));
                }
            }
        }
        if places.len() < 2 {
            continue;
        }
        out.push(FlexDrawing {
            body: i,
            q_index: flex.q_index,
            k,
            places,
            shapes: shapes_at,
            nodes,
            line: !matches!(flex.source, FlexSource::Modal { .. }),
        });
    }
    Ok(out)
}

/// The page's `flex`: per flexible body its scene index, `k`, where its
/// coordinates sit in a row of `flexFrames`, the stations' places `p`
/// (3 per station), their shapes `s` (3 × k per station, row-major) and
/// the node stations.
fn flex_json(flexes: &[FlexDrawing]) -> Result<String, Error> {
    let mut s = String::from("[");
    let mut at = 0;
    for (n, f) in flexes.iter().enumerate() {
        if n > 0 {
            s.push(',');
        }
        let list = |v: &mut dyn Iterator<Item = &f64>| -> Result<String, Error> {
            let items: Vec<String> = v.map(|x| significant(*x)).collect::<Result<_, _>>()?;
            Ok(items.join(","))
        };
        let p = list(&mut f.places.iter().flatten())?;
        let sh = list(&mut f.shapes.iter().flatten().flatten())?;
        let _ = write!(
            s,
            "{{\"body\":{},\"k\":{},\"at\":{at},\"p\":[{p}],\"s\":[{sh}],\"nodes\":{},\"line\":{}}}",
            f.body,
            f.k,
            serde_json::to_string(&f.nodes).unwrap_or_else(|_| "[]".into()),
            f.line,
        );
        at += f.k;
    }
    s.push(']');
    Ok(s)
}

/// `x` with 7 significant digits (elastic coordinates and shapes can be
/// far below the 6 decimals of a pose); not finite refuses.
fn significant(x: f64) -> Result<String, Error> {
    if !x.is_finite() {
        return Err(Error::Refused(format!(
            "the trajectory holds {x}: nothing to animate"
        )));
    }
    if x == 0.0 {
        return Ok("0".into());
    }
    let s = format!("{x:.6e}");
    let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
    let mut m = mantissa.to_string();
    if m.contains('.') {
        while m.ends_with('0') {
            m.pop();
        }
        if m.ends_with('.') {
            m.pop();
        }
    }
    Ok(if exp == "0" { m } else { format!("{m}e{exp}") })
}

/// Gravity in world axes (zero vector if none).
fn gravity(num: &Numeric) -> [f64; 3] {
    num.tree().gravity.0
}

/// The meshes of the page, each file once (base64 of little-endian
/// `f32` positions and `u32` triangle indices).
#[derive(Default)]
struct Meshes {
    index: std::collections::HashMap<std::path::PathBuf, usize>,
    list: Vec<serde_json::Value>,
}

impl Meshes {
    fn get(&mut self, path: &std::path::Path) -> Result<usize, String> {
        if let Some(&k) = self.index.get(path) {
            return Ok(k);
        }
        let m = crate::mesh::read(path)?;
        let v: Vec<u8> = m.positions.iter().flat_map(|x| x.to_le_bytes()).collect();
        let i: Vec<u8> = m.indices.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.list.push(serde_json::json!({
            "v": crate::mesh::base64(&v),
            "i": crate::mesh::base64(&i),
        }));
        self.index.insert(path.to_path_buf(), self.list.len() - 1);
        Ok(self.list.len() - 1)
    }
}

/// The shapes of `owner` for the page: kind and sizes, origin and unit
/// quaternion in the body, colour; a mesh by its index in `meshes`.
fn shapes_json(
    shapes: &[PlacedShape],
    owner: &str,
    meshes: &mut Meshes,
) -> Result<Vec<serde_json::Value>, Error> {
    shapes
        .iter()
        .map(|s| {
            let mut g = match &s.shape {
                Shape::Box(size) => serde_json::json!({ "box": size }),
                Shape::Cylinder { radius, length } => {
                    serde_json::json!({ "cylinder": [radius, length] })
                }
                Shape::Sphere(r) => serde_json::json!({ "sphere": r }),
                Shape::Mesh { file, path, scale } => {
                    let k = meshes
                        .get(path)
                        .map_err(|e| Error::Refused(format!("`{owner}`: mesh `{file}`: {e}")))?;
                    serde_json::json!({ "mesh": k, "scale": scale })
                }
            };
            g["p"] = serde_json::json!(s.origin);
            g["q"] = serde_json::json!(quaternion(&s.rotation));
            if let Some(c) = s.color {
                g["color"] = serde_json::json!(c);
            }
            Ok(g)
        })
        .collect()
}

fn bodies_json(
    sys: &eom_gen::system::System,
    scene: &Scene,
    meshes: &mut Meshes,
) -> Result<String, Error> {
    // Names as the user wrote them (a URDF's `link 1`, `joint_0.0`).
    let body_label = |name: &str| {
        sys.bodies
            .iter()
            .find(|b| b.name == name)
            .and_then(|b| b.label.clone())
            .unwrap_or_else(|| name.to_string())
    };
    let joint_label = |name: &str| {
        sys.joints
            .iter()
            .find(|j| j.name == name)
            .and_then(|j| j.label.clone())
            .unwrap_or_else(|| name.to_string())
    };
    let list: Vec<serde_json::Value> = scene
        .bodies
        .iter()
        .map(|b| {
            let geometry = shapes_json(&b.geometry, &b.name, meshes)?;
            Ok(serde_json::json!({
                "name": b.name,
                "label": body_label(&b.name),
                "joint": b.joint,
                "jointLabel": joint_label(&b.joint),
                "parent": b.parent,
                "jp": b.joint_on_parent,
                "jb": b.joint_on_body,
                "axis": b.axis,
                "prismatic": b.prismatic,
                "com": b.com,
                "mass": b.mass,
                "markers": b.markers,
                "loops": b.loop_joints,
                "geometry": geometry,
            }))
        })
        .collect::<Result<_, Error>>()?;
    Ok(serde_json::to_string(&list).unwrap_or_else(|_| "[]".into()))
}

/// `x` with 6 decimals, trailing zeros dropped; a value that is not
/// finite cannot be drawn and refuses.
fn number(x: f64) -> Result<String, Error> {
    if !x.is_finite() {
        return Err(Error::Refused(format!(
            "the trajectory holds {x}: nothing to animate"
        )));
    }
    let mut s = format!("{x:.6}");
    while s.ends_with('0') {
        s.pop();
    }
    if s.ends_with('.') {
        s.pop();
    }
    if s == "-0" {
        s = "0".into();
    }
    Ok(s)
}

/// The unit quaternion `[x, y, z, w]` of the rotation matrix `r` (rows;
/// Shepperd's method, the largest of the four candidates first).
pub fn quaternion(r: &[[f64; 3]; 3]) -> [f64; 4] {
    let tr = r[0][0] + r[1][1] + r[2][2];
    let q = if tr > r[0][0].max(r[1][1]).max(r[2][2]) {
        let s = 2.0 * (1.0 + tr).sqrt();
        [
            (r[2][1] - r[1][2]) / s,
            (r[0][2] - r[2][0]) / s,
            (r[1][0] - r[0][1]) / s,
            s / 4.0,
        ]
    } else if r[0][0] >= r[1][1] && r[0][0] >= r[2][2] {
        let s = 2.0 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
        [
            s / 4.0,
            (r[0][1] + r[1][0]) / s,
            (r[0][2] + r[2][0]) / s,
            (r[2][1] - r[1][2]) / s,
        ]
    } else if r[1][1] >= r[2][2] {
        let s = 2.0 * (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt();
        [
            (r[0][1] + r[1][0]) / s,
            s / 4.0,
            (r[1][2] + r[2][1]) / s,
            (r[0][2] - r[2][0]) / s,
        ]
    } else {
        let s = 2.0 * (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt();
        [
            (r[0][2] + r[2][0]) / s,
            (r[1][2] + r[2][1]) / s,
            s / 4.0,
            (r[1][0] - r[0][1]) / s,
        ]
    };
    let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.map(|x| x / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quaternion of a rotation by θ about a unit axis n is
    /// (n sin θ/2, cos θ/2), through every branch of Shepperd's method.
    #[test]
    fn quaternion_of_axis_angle() {
        for (n, theta) in [
            ([0.0, 0.0, 1.0], 0.3),
            ([1.0, 0.0, 0.0], 3.0),
            ([0.0, 1.0, 0.0], 3.1),
            ([0.0, 0.0, 1.0], 3.1),
            ([0.6, 0.0, 0.8], 2.0),
        ] {
            let (s, c) = (f64::sin(theta), f64::cos(theta));
            let k = [[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]];
            let mut r = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    let kk: f64 = (0..3).map(|m| k[i][m] * k[m][j]).sum();
                    r[i][j] = f64::from(u8::from(i == j)) + s * k[i][j] + (1.0 - c) * kk;
                }
            }
            let q = quaternion(&r);
            let h = theta / 2.0;
            let want = [n[0] * h.sin(), n[1] * h.sin(), n[2] * h.sin(), h.cos()];
            let sign = if q[3] * want[3] < 0.0 { -1.0 } else { 1.0 };
            for (a, b) in q.iter().zip(want) {
                assert!((sign * a - b).abs() < 1e-12, "{q:?} vs {want:?}");
            }
        }
    }

    /// The page of the double pendulum: its data parses; one time and one
    /// pose (position, unit quaternion) per body per frame; and the poses
    /// are the pendulum's closed form: the lower body hangs at
    /// l1 (sin q1, −cos q1, 0) turned by q1 + q2 about z.
    #[test]
    fn double_pendulum_page() {
        let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/double_pendulum.ron");
        let Ok(opened) = crate::open::open(model, &Default::default(), &Default::default()) else {
            panic!("cannot open {model}");
        };
        let sys = &opened.checked.system;
        let mut table = Table::new(vec!["t".into(), "q1".into(), "q2".into(), "u1".into()]);
        let frames = [(0.0, 2.0, -2.2), (0.5, 0.3, 1.1), (1.0, -1.0, 4.0)];
        for (t, q1, q2) in frames {
            table.push(vec![t, q1, q2, 0.0]);
        }
        let page = match html(sys, &table, &[]) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        assert!(page.starts_with("<!DOCTYPE html>"));
        assert!(!page.contains("{{"), "a placeholder is left");
        assert!(!page.contains("src=\"http"), "the page loads nothing");
        let start = page.find(r#"type="application/json">"#).map(|i| i + 24);
        let data = start.and_then(|s| Some(&page[s..s + page[s..].find("</script>")?]));
        let data: serde_json::Value = match data.map(serde_json::from_str) {
            Some(Ok(v)) => v,
            other => panic!("the page's data does not parse: {other:?}"),
        };
        let bodies = data["bodies"].as_array().map(Vec::len);
        assert_eq!(bodies, Some(2));
        assert_eq!(data["t"].as_array().map(Vec::len), Some(3));
        let poses = data["poses"].as_array().cloned().unwrap_or_default();
        assert_eq!(poses.len(), 3);
        for (pose, (_, q1, q2)) in poses.iter().zip(frames) {
            let p: Vec<f64> = pose
                .as_array()
                .map(|v| v.iter().filter_map(|x| x.as_f64()).collect())
                .unwrap_or_default();
            assert_eq!(p.len(), 14, "two bodies × (position, quaternion)");
            let lower = &p[7..];
            let want = [
                q1.sin(),
                -q1.cos(),
                0.0,
                0.0,
                0.0,
                ((q1 + q2) / 2.0).sin(),
                ((q1 + q2) / 2.0).cos(),
            ];
            let sign = if lower[6] * want[6] < 0.0 { -1.0 } else { 1.0 };
            for (k, (a, b)) in lower.iter().zip(want).enumerate() {
                let a = if k >= 3 { sign * a } else { *a };
                assert!(
                    (a - b).abs() < 1e-6,
                    "lower body: {lower:?}, closed form {want:?}"
                );
            }
        }
    }

    /// The page of the hub and beam draws the beam deformed: per frame the
    /// body frame's pose and the 4 modal coordinates, once the stations'
    /// mode shapes. Evaluated as the page does (`R (p + S q_f) + r`), the
    /// places of the beam's root, middle and tip nodes agree with the
    /// model's own outputs `NodePosition` (the formulated `outputs`,
    /// interpreted) to the page's rounding, while the bending moves the
    /// tip by centimetres.
    #[test]
    fn hub_beam_page_carries_the_deformation() {
        // models/hub_beam.ron with node outputs.
        let text = include_str!("../../models/hub_beam.ron").replace(
                "    joints: [",
                "    outputs: [NodePosition(body: \"beam\", node: 0), \
                 NodePosition(body: \"beam\", node: 5), NodePosition(body: \"beam\", node: 10)],\n    joints: [",
            );
        let dir = std::env::temp_dir().join(format!("eom-flexpage-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let path = dir.join("hub_beam.ron");
        let _ = std::fs::write(&path, text);
        let opened = crate::open::open(
            &path.display().to_string(),
            &Default::default(),
            &Default::default(),
        );
        let _ = std::fs::remove_dir_all(&dir);
        let Ok(opened) = opened else {
            panic!("cannot open the hub and beam with outputs");
        };
        let sys = &opened.checked.system;
        let f =
            match eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested()) {
                Ok(f) => f,
                Err(e) => panic!("{e}"),
            };
        let names: Vec<String> = sys
            .coordinate_names()
            .iter()
            .map(|n| n.to_string())
            .collect();
        assert_eq!(
            names.len(),
            5,
            "hub angle and 4 modal coordinates: {names:?}"
        );
        let mut header = vec!["t".to_string()];
        header.extend(names);
        let mut table = Table::new(header);
        let frames = [
            [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.5, 0.7, 0.06, -0.01, 0.004, 0.001],
            [1.0, 2.0, -0.05, 0.02, -0.003, 0.0005],
        ];
        for f in frames {
            table.push(f.to_vec());
        }
        let page = match html(sys, &table, &[]) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        let start = page.find(r#"type="application/json">"#).map(|i| i + 24);
        let data = start.and_then(|s| Some(&page[s..s + page[s..].find("</script>")?]));
        let data: serde_json::Value = match data.map(serde_json::from_str) {
            Some(Ok(v)) => v,
            other => panic!("the page's data does not parse: {other:?}"),
        };
        let nums = |v: &serde_json::Value| -> Vec<f64> {
            v.as_array()
                .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
                .unwrap_or_default()
        };
        let flex = &data["flex"][0];
        let (body, k) = (flex["body"].as_u64(), flex["k"].as_u64());
        assert_eq!(k, Some(4));
        assert_eq!(flex["line"], true, "a beam is drawn along its axis");
        let body = body.unwrap_or(0) as usize;
        assert_eq!(data["bodies"][body]["name"], "beam");
        let (p, shapes) = (nums(&flex["p"]), nums(&flex["s"]));
        let nodes: Vec<usize> = nums(&flex["nodes"]).iter().map(|&x| x as usize).collect();
        assert_eq!(nodes.len(), 11, "10 elements: 11 nodes");
        assert_eq!(p.len(), 3 * (10 * PIECES_PER_ELEMENT + 1));
        assert_eq!(shapes.len(), 4 * p.len());
        let mut tip_bend: f64 = 0.0;
        for (frame, row) in frames.iter().enumerate() {
            let pose = nums(&data["poses"][frame]);
            let qf = nums(&data["flexFrames"][frame]);
            assert_eq!(qf, row[2..], "the elastic coordinates, frame {frame}");
            let (r, quat) = (
                &pose[7 * body..7 * body + 3],
                &pose[7 * body + 3..7 * body + 7],
            );
            // v' = v + 2w (u × v) + 2 u × (u × v), u = (x, y, z).
            let turn = |v: [f64; 3]| {
                let u = [quat[0], quat[1], quat[2]];
                let cross = |a: [f64; 3], b: [f64; 3]| {
                    [
                        a[1] * b[2] - a[2] * b[1],
                        a[2] * b[0] - a[0] * b[2],
                        a[0] * b[1] - a[1] * b[0],
                    ]
                };
                let c = cross(u, v);
                let cc = cross(u, c);
                std::array::from_fn::<f64, 3, _>(|i| v[i] + 2.0 * quat[3] * c[i] + 2.0 * cc[i])
            };
            let x = eom_gen::interpret::Point {
                sys,
                q: &row[1..],
                u: &[0.0; 5],
                udot: &[0.0; 5],
                tau: &[],
                inputs: &[],
                params: &[],
                multipliers: &[],
                t: row[0],
            };
            let outputs = eom_gen::interpret::evaluate_function(
                &f,
                eom_gen::functions::Function::Outputs,
                &x,
            )
            .unwrap_or_default();
            let mut compared = 0;
            for (node, &st) in nodes.iter().enumerate() {
                let local: [f64; 3] = std::array::from_fn(|a| {
                    p[3 * st + a]
                        + (0..4)
                            .map(|m| shapes[12 * st + 4 * a + m] * qf[m])
                            .sum::<f64>()
                });
                let drawn: [f64; 3] = std::array::from_fn(|a| r[a] + turn(local)[a]);
                let rigid: [f64; 3] = std::array::from_fn(|a| {
                    r[a] + turn([p[3 * st], p[3 * st + 1], p[3 * st + 2]])[a]
                });
                let Some(at) = f
                    .output_names
                    .iter()
                    .position(|n| *n == format!("beam_node{node}_x"))
                else {
                    continue;
                };
                let want = &outputs[at..at + 3];
                let err = (0..3)
                    .map(|a| (drawn[a] - want[a]).abs())
                    .fold(0.0, f64::max);
                assert!(
                    err < 2e-6,
                    "frame {frame}, node {node}: drawn {drawn:?}, output {want:?}"
                );
                compared += 1;
                let bend = (0..3)
                    .map(|a| (rigid[a] - want[a]).abs())
                    .fold(0.0, f64::max);
                tip_bend = tip_bend.max(bend);
            }
            assert_eq!(compared, 3, "nodes 0, 5 and 10");
        }
        assert!(
            tip_bend > 0.01,
            "the frames bend the beam by only {tip_bend} m"
        );
    }

    /// A rod with assumed modes (docs/model-format.md's example, turned on
    /// a hub) is drawn along its shape functions: the station at `L/2`
    /// of the page, evaluated as the page does, is the model's own
    /// `NodePosition` output of a named node there, and its first shape
    /// `v = sin(πx/L)` bends it by `q₁` in the body's `y` there.
    #[test]
    fn assumed_modes_are_drawn_along_their_shapes() {
        let text = r#"Model(name: "assumed_rod", parameters: [(name: "L", value: 10.0)],
            bodies: [(name: "rod", flexible: AssumedModes(
                length: "L", rho_a: 1.2, rho_ip: 1e-4, ea: 2.8e7, ei_y: 1.4e4, ei_z: 1.4e4, gj: 1e4,
                shapes: [(v: "sin(pi*x/L)"), (v: "sin(2*pi*x/L)", w: "0"),
                         (u: "sin(pi*x/(2*L))"), (phi: "sin(pi*x/(2*L))")],
                nodes: [(name: "mid", x: "L/2")]))],
            joints: [(name: "hub", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "rod")],
            outputs: [NodePosition(body: "rod", node: 0)])"#;
        let dir = std::env::temp_dir().join(format!("eom-assumed-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let path = dir.join("assumed_rod.ron");
        let _ = std::fs::write(&path, text);
        let opened = crate::open::open(
            &path.display().to_string(),
            &Default::default(),
            &Default::default(),
        );
        let _ = std::fs::remove_dir_all(&dir);
        let opened = match opened {
            Ok(o) => o,
            Err(_) => panic!("cannot open the assumed-modes rod"),
        };
        let sys = &opened.checked.system;
        let f =
            match eom_gen::mech::formulate(sys, eom_gen::functions::FunctionSet::all_requested()) {
                Ok(f) => f,
                Err(e) => panic!("{e}"),
            };
        let q = [0.4, 0.3, -0.1, 0.02, 0.05];
        let mut header = vec!["t".to_string()];
        header.extend(sys.coordinate_names().iter().map(|n| n.to_string()));
        let mut table = Table::new(header);
        table.push([0.0].into_iter().chain(q).collect());
        let page = match html(sys, &table, &[]) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        let start = page.find(r#"type="application/json">"#).map(|i| i + 24);
        let data = start.and_then(|s| Some(&page[s..s + page[s..].find("</script>")?]));
        let data: serde_json::Value = match data.map(serde_json::from_str) {
            Some(Ok(v)) => v,
            other => panic!("the page's data does not parse: {other:?}"),
        };
        let nums = |v: &serde_json::Value| -> Vec<f64> {
            v.as_array()
                .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
                .unwrap_or_default()
        };
        let flex = &data["flex"][0];
        let (p, shapes, qf) = (
            nums(&flex["p"]),
            nums(&flex["s"]),
            nums(&data["flexFrames"][0]),
        );
        assert_eq!(p.len(), 3 * (ASSUMED_PIECES + 1));
        assert_eq!(qf, q[1..]);
        let st = ASSUMED_PIECES / 2;
        let local: [f64; 3] = std::array::from_fn(|a| {
            p[3 * st + a]
                + (0..4)
                    .map(|m| shapes[12 * st + 4 * a + m] * qf[m])
                    .sum::<f64>()
        });
        // u = q₃ sin(π/4), v = q₁ sin(π/2) + q₂ sin(π) at x = L/2.
        let want_local = [5.0 + q[3] * (std::f64::consts::PI / 4.0).sin(), q[1], 0.0];
        for a in 0..3 {
            assert!(
                (local[a] - want_local[a]).abs() < 1e-6,
                "{local:?} vs {want_local:?}"
            );
        }
        let pose = nums(&data["poses"][0]);
        let (c, s) = (q[0].cos(), q[0].sin());
        assert!((pose[0..3].iter().map(|x| x.abs()).sum::<f64>()) < 1e-12);
        let drawn = [
            c * local[0] - s * local[1],
            s * local[0] + c * local[1],
            local[2],
        ];
        let x = eom_gen::interpret::Point {
            sys,
            q: &q,
            u: &[0.0; 5],
            udot: &[0.0; 5],
            tau: &[],
            inputs: &[],
            params: &[],
            multipliers: &[],
            t: 0.0,
        };
        let out =
            eom_gen::interpret::evaluate_function(&f, eom_gen::functions::Function::Outputs, &x)
                .unwrap_or_default();
        let Some(at) = f.output_names.iter().position(|n| n == "rod_node0_x") else {
            panic!("outputs {:?}", f.output_names)
        };
        for a in 0..3 {
            assert!(
                (drawn[a] - out[at + a]).abs() < 2e-6,
                "drawn {drawn:?}, output {:?}",
                &out[at..at + 3]
            );
        }
    }

    /// The four-bar's loop is closed by one cut joint: the page draws it
    /// on both bodies it joins (two points; none on ground).
    #[test]
    fn fourbar_page_draws_its_cut_joint() {
        let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/fourbar.ron");
        let Ok(opened) = crate::open::open(model, &Default::default(), &Default::default()) else {
            panic!("cannot open {model}");
        };
        let sys = &opened.checked.system;
        let Ok(scene) = Numeric::new(sys).and_then(|n| n.scene(sys)) else {
            panic!("no scene");
        };
        assert_eq!(sys.graph.cut_joints().len(), 1);
        let held: usize = scene.bodies.iter().map(|b| b.loop_joints.len()).sum();
        assert_eq!((held, scene.ground.len()), (2, 0));
    }

    /// The page of a URDF with every kind of `<visual>`: each shape on
    /// its body (the welded base's box on the ground), each mesh file once,
    /// and the binary STL pyramid decoded back: 5 shared vertices, 6
    /// triangles, in mm as in the file (the scale 0.001 is the shape's).
    #[test]
    fn urdf_visuals_page() {
        let model = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../eom-gen/tests/urdf/visual_pkg/robots/visuals.urdf"
        );
        let Ok(opened) = crate::open::open(model, &Default::default(), &Default::default()) else {
            panic!("cannot open {model}");
        };
        let sys = &opened.checked.system;
        let mut table = Table::new(vec!["t".into(), "joint_0_0".into()]);
        table.push(vec![0.0, 0.5]);
        table.push(vec![0.1, 0.6]);
        let page = match html(sys, &table, &[]) {
            Ok(p) => p,
            Err(e) => panic!("{e}"),
        };
        let start = page.find(r#"type="application/json">"#).map(|i| i + 24);
        let data = start.and_then(|s| Some(&page[s..s + page[s..].find("</script>")?]));
        let data: serde_json::Value = match data.map(serde_json::from_str) {
            Some(Ok(v)) => v,
            other => panic!("the page's data does not parse: {other:?}"),
        };
        let shapes = &data["bodies"][0]["geometry"];
        let kinds: Vec<&str> = shapes
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|g| {
                        ["box", "cylinder", "sphere", "mesh"]
                            .into_iter()
                            .find(|k| g.get(k).is_some())
                    })
                    .collect()
            })
            .unwrap_or_default();
        assert_eq!(kinds, ["cylinder", "sphere", "mesh", "mesh"]);
        assert_eq!(shapes[2]["mesh"], 0);
        assert_eq!(shapes[3]["mesh"], 1);
        assert_eq!(
            data["groundGeometry"][0]["box"],
            serde_json::json!([0.3, 0.3, 0.1])
        );
        assert_eq!(data["meshes"].as_array().map(Vec::len), Some(2));
        let decode = |s: &serde_json::Value| -> Vec<u8> {
            let s = s.as_str().unwrap_or("");
            let a = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
            let sextets: Vec<u32> = s
                .bytes()
                .filter(|&c| c != b'=')
                .filter_map(|c| a.iter().position(|&x| x == c).map(|p| p as u32))
                .collect();
            let mut out = Vec::new();
            for c in sextets.chunks(4) {
                let n = c
                    .iter()
                    .enumerate()
                    .fold(0u32, |n, (k, &x)| n | (x << (18 - 6 * k)));
                out.extend(&n.to_be_bytes()[1..c.len()]);
            }
            out
        };
        let v = decode(&data["meshes"][0]["v"]);
        let i = decode(&data["meshes"][0]["i"]);
        assert_eq!((v.len() / 12, i.len() / 12), (5, 6), "vertices, triangles");
        let top = v
            .chunks(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .fold(f32::MIN, f32::max);
        assert_eq!(top, 150.0);
    }

    /// An impact event of the bouncing ball's floor contact names the
    /// ball (scene body 0) when its row took an impulse, and no body when
    /// it took none.
    #[test]
    fn impacts_name_the_bodies_they_hit() {
        let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/bouncing_ball.ron");
        let Ok(opened) = crate::open::open(model, &Default::default(), &Default::default()) else {
            panic!("cannot open {model}");
        };
        let sys = &opened.checked.system;
        let Ok(scene) = Numeric::new(sys).and_then(|n| n.scene(sys)) else {
            panic!("no scene");
        };
        let contact = |t: f64, impulse: f64| eom_sim::run::ContactEvent {
            t,
            kind: eom_sim::run::ContactEventKind::Impact,
            contacts: vec![eom_sim::run::ContactImpulse {
                contact: sys.contacts[0].name.clone(),
                speed_before: -1.0,
                speed_after: 0.5,
                impulse,
                tangential_impulse: [0.0; 2],
                tangential_speed_before: [0.0; 2],
                tangential_speed_after: [0.0; 2],
            }],
            energy_before: 0.0,
            energy_after: 0.0,
            generalized_impulse: Vec::new(),
            joint_impulses: Vec::new(),
        };
        let events = [contact(0.45, 1.0), contact(0.9, 0.0)];
        let hits = impacts(sys, &scene, &events);
        assert_eq!(hits, [(0.45, vec![0]), (0.9, vec![])]);
    }

    /// A COLLADA mesh refuses the page, saying what to do.
    #[test]
    fn collada_is_refused() {
        let dir = std::env::temp_dir().join(format!("eom-dae-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::write(dir.join("arm.dae"), "<COLLADA/>");
        let model = dir.join("m.ron");
        let _ = std::fs::write(
            &model,
            r#"(name: "m", bodies: [(name: "b", mass: 1, geometry: [Mesh(file: "arm.dae")])],
               joints: [(name: "j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "b")])"#,
        );
        let path = model.display().to_string();
        let Ok(opened) = crate::open::open(&path, &Default::default(), &Default::default()) else {
            panic!("cannot open {path}");
        };
        let mut table = Table::new(vec!["t".into(), "j".into()]);
        table.push(vec![0.0, 0.0]);
        let out = html(&opened.checked.system, &table, &[]);
        let _ = std::fs::remove_dir_all(&dir);
        match out {
            Err(e) => assert!(e.to_string().contains("COLLADA"), "{e}"),
            Ok(_) => panic!("a COLLADA mesh was accepted"),
        }
    }

    #[test]
    fn numbers_are_short() {
        assert_eq!(number(1.0).ok().as_deref(), Some("1"));
        assert_eq!(number(-0.0000001).ok().as_deref(), Some("0"));
        assert_eq!(number(0.1234567).ok().as_deref(), Some("0.123457"));
        assert!(number(f64::NAN).is_err());
    }
}
