//! Triangle meshes for the animation page (`crate::animate`): STL (binary
//! and ASCII), Wavefront OBJ and COLLADA 1.4/1.5 (`.dae`, in `dae.rs`:
//! its scene graph, `<unit>` and `<up_axis>` applied), read into shared
//! vertices and triangles.

use std::collections::HashMap;

/// A triangle mesh: vertex positions `[x, y, z]` (as in the file, before
/// any URDF scale; a COLLADA file's node transforms, unit and up axis
/// applied, so in metres, Z up) and triangles as three vertex indices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, 3 per vertex.
    pub positions: Vec<f32>,
    /// Triangles, 3 indices per triangle.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Adds a vertex, sharing one already there at the same position.
    fn vertex(&mut self, seen: &mut HashMap<[u32; 3], u32>, p: [f32; 3]) -> u32 {
        let key = p.map(|x| (x + 0.0).to_bits());
        *seen.entry(key).or_insert_with(|| {
            self.positions.extend_from_slice(&p);
            (self.positions.len() / 3 - 1) as u32
        })
    }

    pub(crate) fn from_triangles(tris: impl Iterator<Item = [[f32; 3]; 3]>) -> Mesh {
        let mut m = Mesh::default();
        let mut seen = HashMap::new();
        for t in tris {
            for p in t {
                let k = m.vertex(&mut seen, p);
                m.indices.push(k);
            }
        }
        m
    }
}

/// Reads the mesh file at `path` (format by extension, any case).
pub fn read(path: &std::path::Path) -> Result<Mesh, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let shown = path.display();
    let bytes = std::fs::read(path).map_err(|e| format!("cannot read `{shown}`: {e}"))?;
    let mesh = match ext.as_str() {
        "stl" => stl(&bytes),
        "obj" => obj(&String::from_utf8_lossy(&bytes)),
        "dae" => std::str::from_utf8(&bytes)
            .map_err(|_| "a COLLADA file that is not UTF-8 text".to_string())
            .and_then(crate::dae::dae),
        _ => Err("not an STL, OBJ or COLLADA file (by its extension)".to_string()),
    }
    .map_err(|e| format!("`{shown}`: {e}"))?;
    if mesh.indices.is_empty() {
        return Err(format!("`{shown}` has no triangles"));
    }
    if mesh.positions.iter().any(|x| !x.is_finite()) {
        return Err(format!("`{shown}` has a vertex that is not finite"));
    }
    Ok(mesh)
}

/// An STL file: binary (80-byte header, count, 50 bytes per triangle) if
/// its size says so, else ASCII (`solid … facet … vertex x y z …`).
pub fn stl(bytes: &[u8]) -> Result<Mesh, String> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) {
            let f =
                |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
            let tris = (0..n).map(|k| {
                let o = 84 + 50 * k + 12;
                [0, 1, 2].map(|v| [0, 1, 2].map(|c| f(o + 12 * v + 4 * c)))
            });
            return Ok(Mesh::from_triangles(tris));
        }
    }
    let text = std::str::from_utf8(bytes).map_err(|_| {
        "neither a binary STL (its size does not match its triangle count) nor ASCII".to_string()
    })?;
    if !text.trim_start().starts_with("solid") {
        return Err("neither a binary STL (its size does not match its triangle count) nor an ASCII one (`solid …`)".into());
    }
    let mut verts = Vec::new();
    for (line_no, line) in text.lines().enumerate() {
        let mut w = line.split_whitespace();
        if w.next() == Some("vertex") {
            let v: Vec<f32> = w.filter_map(|x| x.parse().ok()).collect();
            let [x, y, z] = v[..] else {
                return Err(format!(
                    "line {}: a vertex needs three numbers",
                    line_no + 1
                ));
            };
            verts.push([x, y, z]);
        }
    }
    if verts.len() % 3 != 0 {
        return Err(format!("{} vertices: not whole triangles", verts.len()));
    }
    Ok(Mesh::from_triangles(
        verts.chunks_exact(3).map(|t| [t[0], t[1], t[2]]),
    ))
}

/// A Wavefront OBJ file: `v x y z` and `f a b c …` (polygons fanned into
/// triangles; `a/b/c` takes the vertex index; negative indices count from
/// the end).
pub fn obj(text: &str) -> Result<Mesh, String> {
    let mut pos: Vec<[f32; 3]> = Vec::new();
    let mut m = Mesh::default();
    let mut seen = HashMap::new();
    for (line_no, line) in text.lines().enumerate() {
        let at = || format!("line {}", line_no + 1);
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let v: Vec<f32> = w.take(3).filter_map(|x| x.parse().ok()).collect();
                let [x, y, z] = v[..] else {
                    return Err(format!("{}: a vertex needs three numbers", at()));
                };
                pos.push([x, y, z]);
            }
            Some("f") => {
                let mut face = Vec::new();
                for item in w {
                    let first = item.split('/').next().unwrap_or("");
                    let k: i64 = first
                        .parse()
                        .map_err(|_| format!("{}: face vertex `{item}` is not an index", at()))?;
                    let n = pos.len() as i64;
                    let k = if k < 0 { n + k } else { k - 1 };
                    let p = usize::try_from(k)
                        .ok()
                        .and_then(|k| pos.get(k))
                        .ok_or_else(|| {
                            format!("{}: face vertex `{item}` is not a vertex so far", at())
                        })?;
                    face.push(*p);
                }
                if face.len() < 3 {
                    return Err(format!("{}: a face needs three vertices", at()));
                }
                for j in 1..face.len() - 1 {
                    for p in [face[0], face[j], face[j + 1]] {
                        let k = m.vertex(&mut seen, p);
                        m.indices.push(k);
                    }
                }
            }
            _ => {}
        }
    }
    Ok(m)
}

/// Standard base64 (RFC 4648, with padding) of `bytes`.
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= c.len() {
                out.push(char::from(A[(n >> (18 - 6 * k)) as usize & 63]));
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit tetrahedron in ASCII STL, binary STL and OBJ: four shared
    /// vertices, four triangles, the same in every format.
    #[test]
    fn tetrahedron_in_every_format() {
        let p = [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let tris = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let mut ascii = String::from("solid t\n");
        let mut binary = vec![0u8; 80];
        binary.extend_from_slice(&4u32.to_le_bytes());
        let mut objtext = String::new();
        for v in p {
            objtext += &format!("v {} {} {}\n", v[0], v[1], v[2]);
        }
        for t in tris {
            ascii += "facet normal 0 0 0\nouter loop\n";
            binary.extend_from_slice(&[0u8; 12]);
            for k in t {
                ascii += &format!("vertex {} {} {}\n", p[k][0], p[k][1], p[k][2]);
                for c in p[k] {
                    binary.extend_from_slice(&c.to_le_bytes());
                }
            }
            ascii += "endloop\nendfacet\n";
            binary.extend_from_slice(&[0u8; 2]);
            objtext += &format!("f {}/1 {} {}//3\n", t[0] + 1, t[1] + 1, t[2] as i64 - 4);
        }
        ascii += "endsolid t\n";
        for m in [stl(ascii.as_bytes()), stl(&binary), obj(&objtext)] {
            let m = match m {
                Ok(m) => m,
                Err(e) => panic!("{e}"),
            };
            assert_eq!(m.positions.len(), 12, "four shared vertices");
            assert_eq!(m.indices.len(), 12, "four triangles");
            let back: Vec<[f32; 3]> = m
                .indices
                .iter()
                .map(|&k| {
                    let k = k as usize * 3;
                    [m.positions[k], m.positions[k + 1], m.positions[k + 2]]
                })
                .collect();
            let want: Vec<[f32; 3]> = tris.iter().flatten().map(|&k| p[k]).collect();
            assert_eq!(back, want);
        }
    }

    #[test]
    fn bad_meshes_are_errors() {
        assert!(stl(b"not a mesh").is_err());
        assert!(stl(b"solid x\nvertex 1 2\n").is_err());
        assert!(obj("v 0 0 0\nf 1 2 3\n").is_err());
        assert!(obj("v 0 0 0\nf 1 1\n").is_err());
        assert!(obj("f a b c\n").is_err());
        let dae = read(std::path::Path::new("no-such-robot.DAE"));
        assert!(dae.is_err_and(|e| e.contains("no-such-robot.DAE")));
    }

    /// The unit cube `[0, 1]³`: corner `k` at `(k & 1, k >> 1 & 1, k >> 2)`,
    /// its six faces as quads.
    const CUBE_QUADS: [[usize; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];

    /// A COLLADA 1.4 file holding the unit cube: `asset` and `scene`
    /// spliced in, the faces as `<triangles>` or `<polylist>` quads, each
    /// corner with a position and a normal index (index stride 2).
    fn cube_dae(asset: &str, quads: bool, scene: &str) -> String {
        let pos: Vec<String> = (0..8)
            .map(|k| format!("{} {} {}", k & 1, k >> 1 & 1, k >> 2))
            .collect();
        let mut p = String::new();
        let faces: Vec<Vec<usize>> = if quads {
            CUBE_QUADS.iter().map(|q| q.to_vec()).collect()
        } else {
            CUBE_QUADS
                .iter()
                .flat_map(|q| [vec![q[0], q[1], q[2]], vec![q[0], q[2], q[3]]])
                .collect()
        };
        for (f, face) in faces.iter().enumerate() {
            for k in face {
                p += &format!("{k} {} ", f / if quads { 1 } else { 2 });
            }
        }
        let inputs = r##"<input semantic="VERTEX" source="#cube-v" offset="0"/>
            <input semantic="NORMAL" source="#cube-n" offset="1"/>"##;
        let prim = if quads {
            format!(
                "<polylist count=\"6\">{inputs}<vcount>4 4 4 4 4 4</vcount><p>{p}</p></polylist>"
            )
        } else {
            format!("<triangles count=\"12\">{inputs}<p>{p}</p></triangles>")
        };
        format!(
            r##"<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset>{asset}</asset>
  <library_geometries>
    <geometry id="cube" name="cube"><mesh>
      <source id="cube-p">
        <float_array id="cube-p-a" count="24">{}</float_array>
        <technique_common><accessor source="#cube-p-a" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <source id="cube-n">
        <float_array id="cube-n-a" count="18">0 0 -1 0 0 1 0 -1 0 0 1 0 -1 0 0 1 0 0</float_array>
        <technique_common><accessor source="#cube-n-a" count="6" stride="3"/></technique_common>
      </source>
      <vertices id="cube-v"><input semantic="POSITION" source="#cube-p"/></vertices>
      {prim}
    </mesh></geometry>
  </library_geometries>
  {scene}
</COLLADA>"##,
            pos.join(" ")
        )
    }

    /// The bounding box `[min, max]` of a mesh's vertices.
    fn bounds(m: &Mesh) -> [[f32; 3]; 2] {
        let mut b = [[f32::INFINITY; 3], [f32::NEG_INFINITY; 3]];
        for v in m.positions.chunks_exact(3) {
            for c in 0..3 {
                b[0][c] = b[0][c].min(v[c]);
                b[1][c] = b[1][c].max(v[c]);
            }
        }
        b
    }

    /// The volume a closed triangle mesh encloses, positive when its
    /// triangles wind outward: the sum of the tetrahedra from the origin
    /// to each triangle, `a · (b × c) / 6`.
    fn signed_volume(m: &Mesh) -> f64 {
        let p = |k: u32| {
            let k = k as usize * 3;
            [m.positions[k], m.positions[k + 1], m.positions[k + 2]].map(f64::from)
        };
        m.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [p(t[0]), p(t[1]), p(t[2])];
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum()
    }

    fn assert_box(m: &Mesh, want: [[f32; 3]; 2]) {
        let got = bounds(m);
        for e in 0..2 {
            for c in 0..3 {
                assert!(
                    (got[e][c] - want[e][c]).abs() <= 1e-6 * (1.0 + want[e][c].abs()),
                    "bounding box: got {got:?}, want {want:?}"
                );
            }
        }
        assert_eq!(m.positions.len(), 8 * 3, "eight shared corners");
        assert_eq!(m.indices.len(), 12 * 3, "twelve triangles");
    }

    /// The unit cube as `<triangles>`, Z up, in centimetres
    /// (`<unit meter="0.01">`), without a visual scene: `[0, 0.01]³` m.
    #[test]
    fn collada_cube_in_centimetres() {
        let text = cube_dae(
            r#"<unit name="centimeter" meter="0.01"/><up_axis>Z_UP</up_axis>"#,
            false,
            "",
        );
        let m = crate::dae::dae(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_box(&m, [[0.0; 3], [0.01; 3]]);
    }

    /// The cube as `<polylist>` quads, Y up, under a node `<scale>2 2 2`
    /// whose child node's `<matrix>` translates by (1, 2, 3). In the file's
    /// frame a corner p goes to 2 (p + (1, 2, 3)): x ∈ [2, 4], y ∈ [4, 6],
    /// z ∈ [6, 8] (scale then translate would give [1, 3] × [2, 4] × [3, 5]).
    /// Y up turns +90° about X, (x, y, z) → (x, −z, y): x ∈ [2, 4],
    /// y ∈ [−8, −6], z ∈ [4, 6].
    #[test]
    fn collada_cube_under_node_transforms() {
        let scene = r##"<library_visual_scenes><visual_scene id="s">
            <node id="outer"><scale>2 2 2</scale>
              <node id="inner">
                <matrix>1 0 0 1  0 1 0 2  0 0 1 3  0 0 0 1</matrix>
                <instance_geometry url="#cube"/>
              </node>
            </node>
          </visual_scene></library_visual_scenes>
          <scene><instance_visual_scene url="#s"/></scene>"##;
        let text = cube_dae("<up_axis>Y_UP</up_axis>", true, scene);
        let m = crate::dae::dae(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_box(&m, [[2.0, -8.0, 4.0], [4.0, -6.0, 6.0]]);
        // Every triangle keeps the cube's outward winding under a proper
        // rotation: the signed volume stays +8 (side 2).
        let vol = signed_volume(&m);
        assert!((vol - 8.0).abs() < 1e-9, "volume: got {vol}, want 8");
    }

    /// The cube from `<library_nodes>` by `<instance_node>` under a node
    /// that translates by (10, 0, 0) then rotates 90° about z (applied to
    /// the cube in reverse order): (x, y, z) → (10 − y, x, z), so
    /// [9, 10] × [0, 1] × [0, 1]. X up turns −90° about Y,
    /// (x, y, z) → (−z, y, x): [−1, 0] × [0, 1] × [9, 10].
    #[test]
    fn collada_cube_by_instance_node_x_up() {
        let scene = r##"<library_nodes><node id="lib"><instance_geometry url="#cube"/></node></library_nodes>
          <library_visual_scenes><visual_scene id="s">
            <node><translate>10 0 0</translate><rotate>0 0 1 90</rotate>
              <instance_node url="#lib"/>
            </node>
          </visual_scene></library_visual_scenes>"##;
        let text = cube_dae("<up_axis>X_UP</up_axis>", false, scene);
        let m = crate::dae::dae(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_box(&m, [[-1.0, 0.0, 9.0], [0.0, 1.0, 10.0]]);
    }

    /// The cube's six faces as `<tristrips>` of four corners each (the
    /// quad a, b, c, d as the strip a, b, d, c): the same box and the
    /// outward winding kept, signed volume +1.
    #[test]
    fn collada_cube_as_tristrips() {
        let tri = cube_dae("<up_axis>Z_UP</up_axis>", false, "");
        let start = tri.find("<triangles").unwrap_or(0);
        let end = tri
            .find("</triangles>")
            .map_or(0, |e| e + "</triangles>".len());
        let strips: String = CUBE_QUADS
            .iter()
            .enumerate()
            .map(|(f, q)| format!("<p>{} {f} {} {f} {} {f} {} {f}</p>", q[0], q[1], q[3], q[2]))
            .collect();
        let text = format!(
            r##"{}<tristrips count="6"><input semantic="VERTEX" source="#cube-v" offset="0"/>
            <input semantic="NORMAL" source="#cube-n" offset="1"/>{strips}</tristrips>{}"##,
            &tri[..start],
            &tri[end..]
        );
        let m = crate::dae::dae(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_box(&m, [[0.0; 3], [1.0; 3]]);
        let vol = signed_volume(&m);
        assert!((vol - 1.0).abs() < 1e-9, "volume: got {vol}, want 1");
    }

    /// A skinned cube (`<instance_controller>` of a `<skin>` with a
    /// bind-shape matrix translating by (0, 0, 5)) is drawn in its rest
    /// pose: [0, 1] × [0, 1] × [5, 6].
    #[test]
    fn collada_skin_in_rest_pose() {
        let scene = r##"<library_controllers><controller id="c"><skin source="#cube">
            <bind_shape_matrix>1 0 0 0  0 1 0 0  0 0 1 5  0 0 0 1</bind_shape_matrix>
          </skin></controller></library_controllers>
          <library_visual_scenes><visual_scene id="s">
            <node><instance_controller url="#c"/></node>
          </visual_scene></library_visual_scenes>"##;
        let text = cube_dae("<up_axis>Z_UP</up_axis>", true, scene);
        let m = crate::dae::dae(&text).unwrap_or_else(|e| panic!("{e}"));
        assert_box(&m, [[0.0, 0.0, 5.0], [1.0, 1.0, 6.0]]);
    }

    /// Broken COLLADA files are errors naming the file and what is wrong.
    #[test]
    fn bad_collada_is_an_error_naming_the_file() {
        let dir = std::env::temp_dir().join(format!("eom-bad-dae-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&dir);
        let cube = cube_dae("", false, "");
        let cases = [
            (
                "broken.dae",
                "<COLLADA><library_geometries>".to_string(),
                "XML",
            ),
            ("empty.dae", "<COLLADA/>".to_string(), "no triangles"),
            (
                "past.dae",
                cube.replace("<p>0 0 ", "<p>8 0 "),
                "past the 8 positions",
            ),
            (
                "short.dae",
                cube.replace("count=\"8\" stride", "count=\"9\" stride"),
                "9 positions",
            ),
            (
                "up.dae",
                cube_dae("<up_axis>W_UP</up_axis>", false, ""),
                "W_UP",
            ),
        ];
        for (name, text, what) in cases {
            let path = dir.join(name);
            let _ = std::fs::write(&path, text);
            match read(&path) {
                Ok(_) => panic!("{name} was read"),
                Err(e) => assert!(e.contains(name) && e.contains(what), "{name}: {e}"),
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn base64_of_rfc_4648_examples() {
        for (raw, enc) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(raw.as_bytes()), enc);
        }
    }
}
