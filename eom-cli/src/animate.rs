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

mod flex;
use flex::{flex_bodies, flex_json, significant};

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

    /// A COLLADA mesh is drawn: the page holds its one triangle (three
    /// vertices, in metres from `<unit meter="0.5">`), and a COLLADA file
    /// without triangles refuses the page naming the file.
    #[test]
    fn collada_is_accepted() {
        let dir = std::env::temp_dir().join(format!("eom-dae-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::write(
            dir.join("arm.dae"),
            r##"<COLLADA version="1.5.0"><asset><unit meter="0.5"/><up_axis>Z_UP</up_axis></asset>
              <library_geometries><geometry id="g"><mesh>
                <source id="p"><float_array id="a" count="9">0 0 0 1 0 0 0 1 0</float_array>
                  <technique_common><accessor source="#a" count="3" stride="3"/></technique_common></source>
                <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
                <triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
              </mesh></geometry></library_geometries></COLLADA>"##,
        );
        let _ = std::fs::write(dir.join("empty.dae"), "<COLLADA/>");
        let page = |file: &str| {
            let model = dir.join("m.ron");
            let _ = std::fs::write(
                &model,
                format!(
                    r#"(name: "m", bodies: [(name: "b", mass: 1, geometry: [Mesh(file: "{file}")])],
                   joints: [(name: "j", kind: Revolute(axis: (0, 0, 1)), parent: "ground", child: "b")])"#
                ),
            );
            let path = model.display().to_string();
            let Ok(opened) = crate::open::open(&path, &Default::default(), &Default::default())
            else {
                panic!("cannot open {path}");
            };
            let mut table = Table::new(vec!["t".into(), "j".into()]);
            table.push(vec![0.0, 0.0]);
            html(&opened.checked.system, &table, &[]).map_err(|e| e.to_string())
        };
        let good = page("arm.dae");
        let empty = page("empty.dae");
        let _ = std::fs::remove_dir_all(&dir);
        let want = crate::mesh::base64(
            &[0.0f32, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.5, 0.0]
                .iter()
                .flat_map(|x| x.to_le_bytes())
                .collect::<Vec<u8>>(),
        );
        match good {
            Ok(html) => assert!(
                html.contains(&want),
                "the triangle's vertices {want} are not in the page"
            ),
            Err(e) => panic!("a COLLADA mesh was refused: {e}"),
        }
        match empty {
            Err(e) => assert!(e.contains("empty.dae") && e.contains("no triangles"), "{e}"),
            Ok(_) => panic!("a COLLADA file without triangles was accepted"),
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
