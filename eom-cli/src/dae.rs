//! COLLADA 1.4/1.5 (`.dae`) triangles for the animation page
//! (`crate::mesh`): positions of `<triangles>`, `<polylist>`,
//! `<polygons>`, `<trifans>` and `<tristrips>` in
//! `<library_geometries>`, placed by the visual scene's node transforms
//! (`<matrix>`, `<translate>`, `<rotate>`, `<scale>`,
//! `<instance_geometry>`, `<instance_node>`, `<instance_controller>` in
//! its rest pose), then scaled by `<asset><unit meter>` and turned from
//! the file's `<up_axis>` into Z up (as ROS does for URDF meshes).
//! Normals, texture coordinates, materials, skinning weights and bones (a
//! skin is its bind-shape geometry), morph targets, lines and `<ph>`
//! holes are not read.

use crate::mesh::Mesh;
use nalgebra::{Matrix4, Rotation3, Unit, Vector3};
use roxmltree::{Document, Node};
use std::collections::HashMap;

/// Nested `<instance_node>`s deeper than this are taken for a cycle.
const MAX_DEPTH: usize = 64;

type Tri = [[f64; 3]; 3];

/// The triangles of a COLLADA document, in metres, Z up.
pub fn dae(text: &str) -> Result<Mesh, String> {
    let doc = Document::parse(text).map_err(|e| format!("not COLLADA XML: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "COLLADA" {
        return Err(format!(
            "the root element is `<{}>`, not `<COLLADA>`",
            root.tag_name().name()
        ));
    }
    let at = |n: Node| {
        let p = doc.text_pos_at(n.range().start);
        format!("line {}:{}", p.row, p.col)
    };
    let (meter, up) = asset(root, &at)?;

    let mut geometries: HashMap<&str, Node> = HashMap::new();
    let mut nodes: HashMap<&str, Node> = HashMap::new();
    let mut controllers: HashMap<&str, Node> = HashMap::new();
    for n in root.descendants().filter(Node::is_element) {
        match (n.tag_name().name(), n.attribute("id")) {
            ("geometry", Some(id)) => {
                geometries.insert(id, n);
            }
            ("node", Some(id)) => {
                nodes.insert(id, n);
            }
            ("controller", Some(id)) => {
                controllers.insert(id, n);
            }
            _ => {}
        }
    }
    let r = Reader {
        at: &at,
        geometries,
        nodes,
        controllers,
        meshes: HashMap::new().into(),
    };

    // The scene named by `<scene><instance_visual_scene>`, else the first
    // visual scene; without one, every geometry where it stands.
    let scenes: Vec<Node> = root
        .descendants()
        .filter(|n| n.has_tag_name_local("visual_scene"))
        .collect();
    let chosen = child(root, "scene")
        .and_then(|s| child(s, "instance_visual_scene"))
        .and_then(|i| i.attribute("url"))
        .and_then(|u| u.strip_prefix('#'))
        .and_then(|id| scenes.iter().find(|s| s.attribute("id") == Some(id)))
        .or(scenes.first());
    let mut tris = Vec::new();
    match chosen {
        Some(scene) => {
            for n in children(*scene, "node") {
                r.node(n, Matrix4::identity(), 0, &mut tris)?;
            }
        }
        None => {
            let mut all: Vec<&Node> = r.geometries.values().collect();
            all.sort_by_key(|n| n.range().start);
            for g in all {
                tris.extend(r.geometry(*g)?.iter().copied());
            }
        }
    }

    let turn = match up {
        Up::Z => Matrix4::identity(),
        // Y up: +90° about X takes Y to Z.
        Up::Y => Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2)
            .to_homogeneous(),
        // X up: −90° about Y takes X to Z.
        Up::X => Rotation3::from_axis_angle(&Vector3::y_axis(), -std::f64::consts::FRAC_PI_2)
            .to_homogeneous(),
    };
    let to_z_up = Matrix4::new_scaling(meter) * turn;
    let mesh = Mesh::from_triangles(
        tris.iter()
            .map(|t| t.map(|p| point(&to_z_up, p).map(|x| x as f32))),
    );
    if mesh.indices.is_empty() {
        return Err(
            "no triangles (`<triangles>`, `<polylist>` or `<polygons>`) in the scene".into(),
        );
    }
    Ok(mesh)
}

#[derive(Clone, Copy)]
enum Up {
    X,
    Y,
    Z,
}

/// `<asset><unit meter>` (1 if absent) and `<up_axis>` (Y_UP if absent,
/// as the schema says).
fn asset(root: Node, at: &dyn Fn(Node) -> String) -> Result<(f64, Up), String> {
    let Some(a) = child(root, "asset") else {
        return Ok((1.0, Up::Y));
    };
    let meter = match child(a, "unit").and_then(|u| u.attribute("meter")) {
        None => 1.0,
        Some(m) => match m.trim().parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 => v,
            _ => {
                let u = child(a, "unit").unwrap_or(a);
                return Err(format!(
                    "{}: `<unit meter=\"{m}\">` is not a positive number",
                    at(u)
                ));
            }
        },
    };
    let up = match child(a, "up_axis") {
        None => Up::Y,
        Some(u) => match u.text().map(str::trim) {
            Some("X_UP") => Up::X,
            Some("Y_UP") => Up::Y,
            Some("Z_UP") => Up::Z,
            other => {
                return Err(format!(
                    "{}: `<up_axis>` is `{}`, not X_UP, Y_UP or Z_UP",
                    at(u),
                    other.unwrap_or("")
                ));
            }
        },
    };
    Ok((meter, up))
}

struct Reader<'a, 'input> {
    at: &'a dyn Fn(Node) -> String,
    geometries: HashMap<&'a str, Node<'a, 'input>>,
    nodes: HashMap<&'a str, Node<'a, 'input>>,
    controllers: HashMap<&'a str, Node<'a, 'input>>,
    /// Each geometry's triangles once, however often it is instanced.
    meshes: std::cell::RefCell<HashMap<&'a str, std::rc::Rc<Vec<Tri>>>>,
}

impl<'a, 'input> Reader<'a, 'input> {
    /// A `<node>`: its transforms in order after `parent`'s, its
    /// geometries, instanced nodes and child nodes.
    fn node(
        &self,
        n: Node<'a, 'input>,
        parent: Matrix4<f64>,
        depth: usize,
        out: &mut Vec<Tri>,
    ) -> Result<(), String> {
        if depth > MAX_DEPTH {
            return Err(format!(
                "{}: nodes nested deeper than {MAX_DEPTH} (an `<instance_node>` cycle?)",
                (self.at)(n)
            ));
        }
        let mut m = parent;
        for c in n.children().filter(Node::is_element) {
            let local = match c.tag_name().name() {
                "matrix" => {
                    let v = self.floats(c, 16)?;
                    Matrix4::from_row_slice(&v)
                }
                "translate" => {
                    let v = self.floats(c, 3)?;
                    Matrix4::new_translation(&Vector3::new(v[0], v[1], v[2]))
                }
                "rotate" => {
                    let v = self.floats(c, 4)?;
                    let axis = Vector3::new(v[0], v[1], v[2]);
                    if axis.norm() == 0.0 {
                        Matrix4::identity()
                    } else {
                        Rotation3::from_axis_angle(&Unit::new_normalize(axis), v[3].to_radians())
                            .to_homogeneous()
                    }
                }
                "scale" => {
                    let v = self.floats(c, 3)?;
                    Matrix4::new_nonuniform_scaling(&Vector3::new(v[0], v[1], v[2]))
                }
                "lookat" | "skew" => {
                    return Err(format!(
                        "{}: `<{}>` node transforms are not read; bake them into `<matrix>`",
                        (self.at)(c),
                        c.tag_name().name()
                    ));
                }
                _ => continue,
            };
            m *= local;
        }
        for c in n.children().filter(Node::is_element) {
            match c.tag_name().name() {
                "instance_geometry" => {
                    let g = self.target(c, &self.geometries, "geometry")?;
                    self.place(g, &m, out)?;
                }
                "instance_controller" => {
                    // A skin or morph drawn in its rest pose: the base
                    // geometry (after a skin's bind-shape matrix).
                    let ctrl = self.target(c, &self.controllers, "controller")?;
                    let Some(kind) = ctrl
                        .children()
                        .find(|k| k.has_tag_name_local("skin") || k.has_tag_name_local("morph"))
                    else {
                        continue;
                    };
                    let mut at = m;
                    if let Some(b) = child(kind, "bind_shape_matrix") {
                        at *= Matrix4::from_row_slice(&self.floats(b, 16)?);
                    }
                    let g = self.target_by(kind, "source", &self.geometries, "geometry")?;
                    self.place(g, &at, out)?;
                }
                "instance_node" => {
                    let target = self.target(c, &self.nodes, "node")?;
                    self.node(target, m, depth + 1, out)?;
                }
                "node" => self.node(c, m, depth + 1, out)?,
                _ => {}
            }
        }
        Ok(())
    }

    /// A geometry's triangles (read once) placed by `m`.
    fn place(
        &self,
        g: Node<'a, 'input>,
        m: &Matrix4<f64>,
        out: &mut Vec<Tri>,
    ) -> Result<(), String> {
        let id = g.attribute("id").unwrap_or("");
        let cached = self.meshes.borrow().get(id).cloned();
        let tris = match cached {
            Some(t) => t,
            None => {
                let t = std::rc::Rc::new(self.geometry(g)?);
                self.meshes.borrow_mut().insert(id, t.clone());
                t
            }
        };
        out.extend(tris.iter().map(|t| t.map(|p| point(m, p))));
        Ok(())
    }

    /// The element an instance's `url="#id"` names.
    fn target(
        &self,
        inst: Node,
        table: &HashMap<&'a str, Node<'a, 'input>>,
        what: &str,
    ) -> Result<Node<'a, 'input>, String> {
        self.target_by(inst, "url", table, what)
    }

    /// The element `inst`'s attribute `attr="#id"` names.
    fn target_by(
        &self,
        inst: Node,
        attr: &str,
        table: &HashMap<&'a str, Node<'a, 'input>>,
        what: &str,
    ) -> Result<Node<'a, 'input>, String> {
        let url = inst.attribute(attr).unwrap_or("");
        url.strip_prefix('#')
            .and_then(|id| table.get(id).copied())
            .ok_or_else(|| {
                format!(
                    "{}: `<{} {attr}>` names `{url}`, not a `<{what}>` in this file (`#id`)",
                    (self.at)(inst),
                    inst.tag_name().name()
                )
            })
    }

    /// A `<geometry>`'s triangles in its own coordinates (other kinds
    /// than `<mesh>`, e.g. splines, give none).
    fn geometry(&self, g: Node) -> Result<Vec<Tri>, String> {
        let Some(mesh) = child(g, "mesh") else {
            return Ok(Vec::new());
        };
        let mut tris = Vec::new();
        for prim in mesh.children().filter(Node::is_element) {
            let kind = prim.tag_name().name();
            if !matches!(
                kind,
                "triangles" | "polylist" | "polygons" | "trifans" | "tristrips"
            ) {
                continue;
            }
            let inputs: Vec<Node> = children(prim, "input").collect();
            let mut stride = 1;
            let mut vertex = None;
            for i in &inputs {
                let off = match i.attribute("offset") {
                    None => 0,
                    Some(o) => o.trim().parse::<usize>().map_err(|_| {
                        format!("{}: `<input offset=\"{o}\">` is not a count", (self.at)(*i))
                    })?,
                };
                stride = stride.max(off + 1);
                if i.attribute("semantic") == Some("VERTEX") {
                    vertex = Some((off, *i));
                }
            }
            let Some((voff, vin)) = vertex else {
                return Err(format!(
                    "{}: `<{kind}>` has no `<input semantic=\"VERTEX\">`",
                    (self.at)(prim)
                ));
            };
            let pos = self.positions(mesh, vin)?;
            // Polygons as lists of position indices.
            let polys: Vec<(Node, Vec<usize>)> = match kind {
                "polygons" | "trifans" | "tristrips" => children(prim, "p")
                    .map(|p| Ok((p, self.counts(p)?)))
                    .collect::<Result<_, String>>()?,
                _ => {
                    let p = child(prim, "p");
                    let all = match p {
                        Some(p) => self.counts(p)?,
                        None => Vec::new(),
                    };
                    vec![(p.unwrap_or(prim), all)]
                }
            };
            let vcount = match (kind, child(prim, "vcount")) {
                ("polylist", Some(v)) => Some(self.counts(v)?),
                ("polylist", None) => {
                    return Err(format!(
                        "{}: `<polylist>` has no `<vcount>`",
                        (self.at)(prim)
                    ));
                }
                _ => None,
            };
            for (p, idx) in &polys {
                if idx.len() % stride != 0 {
                    return Err(format!(
                        "{}: {} indices are not whole vertices of {stride} inputs",
                        (self.at)(*p),
                        idx.len()
                    ));
                }
                let corner = |k: usize| -> Result<[f64; 3], String> {
                    let i = idx[k * stride + voff];
                    pos.get(i).copied().ok_or_else(|| {
                        format!(
                            "{}: vertex index {i} is past the {} positions",
                            (self.at)(*p),
                            pos.len()
                        )
                    })
                };
                let n = idx.len() / stride;
                let sizes: Vec<usize> = match (kind, &vcount) {
                    ("triangles", _) => {
                        if n % 3 != 0 {
                            return Err(format!(
                                "{}: {n} vertices are not whole triangles",
                                (self.at)(*p)
                            ));
                        }
                        vec![3; n / 3]
                    }
                    (_, Some(v)) => {
                        if v.iter().sum::<usize>() != n {
                            return Err(format!(
                                "{}: `<vcount>` adds up to {}, but `<p>` has {n} vertices",
                                (self.at)(prim),
                                v.iter().sum::<usize>()
                            ));
                        }
                        v.clone()
                    }
                    _ => vec![n],
                };
                let mut start = 0;
                for s in sizes {
                    if s < 3 && kind == "polylist" {
                        return Err(format!("{}: a polygon of {s} vertices", (self.at)(*p)));
                    }
                    for j in 1..s.saturating_sub(1) {
                        tris.push(if kind != "tristrips" {
                            // Fan from the first corner.
                            [corner(start)?, corner(start + j)?, corner(start + j + 1)?]
                        } else if j % 2 == 1 {
                            // Strip: every other triangle turned back.
                            [
                                corner(start + j - 1)?,
                                corner(start + j)?,
                                corner(start + j + 1)?,
                            ]
                        } else {
                            [
                                corner(start + j)?,
                                corner(start + j - 1)?,
                                corner(start + j + 1)?,
                            ]
                        });
                    }
                    start += s;
                }
            }
        }
        Ok(tris)
    }

    /// The positions behind a `VERTEX` input: its `<vertices>`'
    /// `POSITION` input, that `<source>`'s `<float_array>` read by its
    /// `<accessor stride>` (x, y, z the first three of each stride).
    fn positions(&self, mesh: Node, vin: Node) -> Result<Vec<[f64; 3]>, String> {
        let by_id = |tag: &str, url: Option<&str>| {
            url.and_then(|u| u.strip_prefix('#')).and_then(|id| {
                mesh.descendants()
                    .find(|n| n.has_tag_name_local(tag) && n.attribute("id") == Some(id))
            })
        };
        let verts = by_id("vertices", vin.attribute("source")).ok_or_else(|| {
            format!(
                "{}: the VERTEX input's source is not a `<vertices>` of this mesh",
                (self.at)(vin)
            )
        })?;
        let pin = children(verts, "input")
            .find(|i| i.attribute("semantic") == Some("POSITION"))
            .ok_or_else(|| {
                format!(
                    "{}: `<vertices>` has no `<input semantic=\"POSITION\">`",
                    (self.at)(verts)
                )
            })?;
        let src = by_id("source", pin.attribute("source")).ok_or_else(|| {
            format!(
                "{}: the POSITION input's source is not a `<source>` of this mesh",
                (self.at)(pin)
            )
        })?;
        let arr = child(src, "float_array").ok_or_else(|| {
            format!(
                "{}: the position `<source>` has no `<float_array>`",
                (self.at)(src)
            )
        })?;
        let acc = child(src, "technique_common").and_then(|t| child(t, "accessor"));
        let attr = |name: &str, default: usize| -> Result<usize, String> {
            match acc.and_then(|a| a.attribute(name)) {
                None => Ok(default),
                Some(s) => s.trim().parse().map_err(|_| {
                    format!(
                        "{}: `<accessor {name}=\"{s}\">` is not a count",
                        (self.at)(acc.unwrap_or(src))
                    )
                }),
            }
        };
        let stride = attr("stride", 3)?;
        let offset = attr("offset", 0)?;
        if stride < 3 {
            return Err(format!(
                "{}: positions with an accessor stride of {stride}, fewer than x, y, z",
                (self.at)(acc.unwrap_or(src))
            ));
        }
        let v = self.floats(arr, 0)?;
        let count = attr("count", v.len().saturating_sub(offset) / stride)?;
        let need = count
            .checked_mul(stride)
            .and_then(|n| n.checked_add(offset))
            .filter(|&n| n <= v.len())
            .ok_or_else(|| {
                format!(
                    "{}: the accessor wants {count} positions of stride {stride}, but the array has {} numbers",
                    (self.at)(acc.unwrap_or(src)),
                    v.len()
                )
            })?;
        Ok(v[offset..need]
            .chunks_exact(stride)
            .map(|c| [c[0], c[1], c[2]])
            .collect())
    }

    /// The numbers in `n`'s text; `want` of them unless `want` is 0.
    fn floats(&self, n: Node, want: usize) -> Result<Vec<f64>, String> {
        let v = n
            .text()
            .unwrap_or("")
            .split_whitespace()
            .map(|w| {
                w.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        format!(
                            "{}: `{w}` in `<{}>` is not a finite number",
                            (self.at)(n),
                            n.tag_name().name()
                        )
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        if want != 0 && v.len() != want {
            return Err(format!(
                "{}: `<{}>` has {} numbers, not {want}",
                (self.at)(n),
                n.tag_name().name(),
                v.len()
            ));
        }
        Ok(v)
    }

    /// The indices or counts in `n`'s text.
    fn counts(&self, n: Node) -> Result<Vec<usize>, String> {
        n.text()
            .unwrap_or("")
            .split_whitespace()
            .map(|w| {
                w.parse::<usize>().map_err(|_| {
                    format!(
                        "{}: `{w}` in `<{}>` is not an index",
                        (self.at)(n),
                        n.tag_name().name()
                    )
                })
            })
            .collect()
    }
}

/// `m` applied to the point `p`.
fn point(m: &Matrix4<f64>, p: [f64; 3]) -> [f64; 3] {
    let q = m.transform_point(&nalgebra::Point3::from(p));
    [q.x, q.y, q.z]
}

fn child<'a, 'i: 'a>(n: Node<'a, 'i>, tag: &'a str) -> Option<Node<'a, 'i>> {
    children(n, tag).next()
}

fn children<'a, 'i: 'a>(n: Node<'a, 'i>, tag: &'a str) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    n.children().filter(move |c| c.has_tag_name_local(tag))
}

trait Local {
    fn has_tag_name_local(&self, tag: &str) -> bool;
}

impl Local for Node<'_, '_> {
    /// The element's name is `tag`, whatever its namespace (1.4 and 1.5
    /// differ).
    fn has_tag_name_local(&self, tag: &str) -> bool {
        self.is_element() && self.tag_name().name() == tag
    }
}
