//! Geometry drawn by `eom-gen animate` (`geometry` of a body,
//! `ground_geometry`): positive sizes, non-zero scales, colours in
//! `[0, 1]`, mesh files of a known format (a missing file is a warning:
//! the dynamics do not need it, the animation refuses it).

use super::{Ctx, Scope, f, i, join};
use crate::model::locate::Seg;
use crate::model::spec::{Frame, Geometry, Num, V3};
use crate::system::{GeometryInfo, Shape};

/// The mesh formats `eom-gen animate` reads (STL, OBJ and COLLADA).
pub(crate) const MESH_FORMATS: [&str; 3] = ["stl", "obj", "dae"];

impl Ctx<'_> {
    /// The shapes `list` at `path` of `owner` (a body's name or `ground`).
    pub(super) fn geometries(
        &mut self,
        list: &[Geometry],
        path: &[Seg<'static>],
        owner: &str,
    ) -> Vec<GeometryInfo> {
        let mut out = Vec::new();
        for (k, g) in list.iter().enumerate() {
            let gpath = join(path, &[i(k)]);
            if let Some(info) = self.geometry(g, &gpath, owner) {
                out.push(info);
            }
        }
        out
    }

    fn geometry(
        &mut self,
        g: &Geometry,
        path: &[Seg<'static>],
        owner: &str,
    ) -> Option<GeometryInfo> {
        let (frame, color) = match g {
            Geometry::Box { frame, color, .. }
            | Geometry::Cylinder { frame, color, .. }
            | Geometry::Sphere { frame, color, .. }
            | Geometry::Mesh { frame, color, .. } => (frame, color),
        };
        let shape = match g {
            Geometry::Box { size, .. } => {
                let v = self.vec3(size, &join(path, &[f("size")]), Scope::Params);
                let v = v.map(|v| [v[0].value, v[1].value, v[2].value]);
                match v {
                    Some(v) if v.iter().all(|x| x.is_finite() && *x > 0.0) => Some(Shape::Box(v)),
                    Some(v) => {
                        self.error(
                            &join(path, &[f("size")]),
                            format!("box of `{owner}` has size {v:?}"),
                            "a box's edge lengths are positive, in m",
                        );
                        None
                    }
                    None => None,
                }
            }
            Geometry::Cylinder { radius, length, .. } => {
                let r = self.size(radius, &join(path, &[f("radius")]), "radius", owner);
                let l = self.size(length, &join(path, &[f("length")]), "length", owner);
                Some(Shape::Cylinder {
                    radius: r?,
                    length: l?,
                })
            }
            Geometry::Sphere { radius, .. } => self
                .size(radius, &join(path, &[f("radius")]), "radius", owner)
                .map(Shape::Sphere),
            Geometry::Mesh { file, scale, .. } => self.mesh(file, scale.as_ref(), path, owner),
        };
        let frame_info = self.frame(
            &Frame {
                position: frame.position.clone(),
                orientation: frame.orientation.clone(),
            },
            &join(path, &[f("frame")]),
        );
        let color = match color {
            Some((r, g, b)) if [r, g, b].iter().all(|c| (0.0..=1.0).contains(*c)) => {
                Some([*r, *g, *b])
            }
            Some(c) => {
                self.error(
                    &join(path, &[f("color")]),
                    format!("colour of a shape of `{owner}` is {c:?}"),
                    "a colour is `(r, g, b)` with each component in [0, 1]",
                );
                return None;
            }
            None => None,
        };
        Some(GeometryInfo {
            shape: shape?,
            frame: frame_info?,
            color,
        })
    }

    /// A positive finite length.
    fn size(&mut self, n: &Num, path: &[Seg<'static>], what: &str, owner: &str) -> Option<f64> {
        let q = self.quantity(n, path, Scope::Params)?;
        if q.value.is_finite() && q.value > 0.0 {
            Some(q.value)
        } else {
            self.error(
                path,
                format!("{what} of a shape of `{owner}` is {}", q.value),
                format!("a {what} is positive, in m"),
            );
            None
        }
    }

    fn mesh(
        &mut self,
        file: &str,
        scale: Option<&V3>,
        path: &[Seg<'static>],
        owner: &str,
    ) -> Option<Shape> {
        let at = join(path, &[f("file")]);
        let scale = match scale {
            None => Some([1.0; 3]),
            Some(s) => {
                let spath = join(path, &[f("scale")]);
                let v = self.vec3(s, &spath, Scope::Params)?;
                let v = [v[0].value, v[1].value, v[2].value];
                if v.iter().all(|x| x.is_finite() && *x != 0.0) {
                    Some(v)
                } else {
                    self.error(
                        &spath,
                        format!("scale of mesh `{file}` of `{owner}` is {v:?}"),
                        "each component of a mesh's scale is a finite number other than 0 (0.001 for a mesh in mm)",
                    );
                    None
                }
            }
        };
        let ext = std::path::Path::new(file)
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !ext.as_deref().is_some_and(|e| MESH_FORMATS.contains(&e)) {
            self.error(
                &at,
                format!("mesh `{file}` of `{owner}` is not an STL, OBJ or COLLADA file"),
                "a mesh file ends in `.stl`, `.obj` or `.dae` (any case)",
            );
            return None;
        }
        let full = self.model_relative(file);
        if file.starts_with("package://") {
            self.warning(
                &at,
                format!("mesh `{file}` of `{owner}` is a ROS package path"),
                "`eom-gen animate` cannot read it: write the path relative to this model file (a URDF import resolves `package://` itself; see docs/model-format.md)",
            );
        } else if !full.is_file() {
            self.warning(
                &at,
                format!(
                    "mesh `{file}` of `{owner}` is not a file (`{}`)",
                    full.display()
                ),
                "`eom-gen animate` refuses the model until it is there; paths are relative to this model file",
            );
        }
        Some(Shape::Mesh {
            file: file.to_string(),
            path: full,
            scale: scale?,
        })
    }

    /// `file` relative to this model file's directory (as given, if
    /// absolute).
    pub(super) fn model_relative(&self, file: &str) -> std::path::PathBuf {
        let model_dir = std::path::Path::new(&self.src.path)
            .parent()
            .unwrap_or(std::path::Path::new(""));
        self.dir.join(model_dir).join(file)
    }
}
