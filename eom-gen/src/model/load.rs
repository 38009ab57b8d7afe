//! One loader for every model file: a RON model (`.ron`), a scene
//! (`.scene.ron`, or any file whose top-level value is `Scene(…)`) and a
//! URDF robot (`.urdf`). [`Format::of`] is the only place that tells them
//! apart; [`load`] reads a file, converts a URDF into a RON model, and
//! [`Loaded::check`] validates the result (a scene with its model, which
//! is loaded the same way). [`check_file`](super::check_file),
//! [`generate_file`](crate::generate_file), the [`Builder`](crate::Builder),
//! the CLI and `#[multibody]` all go through here.

use super::{Checked, check_model, scene, urdf};
use crate::diag::{Diagnostic, Report, Source, Span};
use std::path::Path;

/// What a model file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A RON model, `Model(…)`.
    Ron,
    /// A scene, `Scene(model: "…", …)`, naming a RON or URDF model.
    Scene,
    /// A URDF robot description, converted to a RON model when loaded.
    Urdf,
}

impl Format {
    /// The format of the file `path` with contents `text`: `.urdf` (any
    /// case) is URDF; a name ending in `.scene.ron`, or text whose
    /// top-level value is `Scene(…)`, is a scene; anything else a RON model.
    pub fn of(path: &str, text: &str) -> Format {
        let ext = Path::new(path).extension();
        if ext.is_some_and(|e| e.eq_ignore_ascii_case("urdf")) {
            Format::Urdf
        } else if path.ends_with(".scene.ron")
            || super::locate::parse(text).is_some_and(|n| n.name.as_deref() == Some("Scene"))
        {
            Format::Scene
        } else {
            Format::Ron
        }
    }
}

/// A model file, read and (for a URDF) converted.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// What the file was.
    pub format: Format,
    /// The text to check: the file itself, or for a URDF the converted RON
    /// model, whose path is `<urdf path> (converted)`
    /// ([`urdf::CONVERTED`]).
    pub source: Source,
    /// For a URDF, what the conversion did that the user should know.
    pub urdf_notes: Option<Vec<String>>,
    /// For a URDF, the conversion's warnings, located in the URDF.
    pub urdf_warnings: Option<Report>,
}

impl Loaded {
    /// Classifies `src` (see [`Format::of`]) and converts a URDF; URDF
    /// errors are reported against the URDF.
    pub fn from_source(src: Source) -> Result<Loaded, Report> {
        Self::from_source_with(src, &urdf::Options::default())
    }

    /// [`Loaded::from_source`] with the URDF import [`urdf::Options`]
    /// (`balance_inertia`, `strict`; ignored for other formats).
    pub fn from_source_with(src: Source, options: &urdf::Options) -> Result<Loaded, Report> {
        match Format::of(&src.path, &src.text) {
            Format::Urdf => {
                let import = urdf::convert_with(&src, options)?;
                Ok(Loaded {
                    format: Format::Urdf,
                    source: import.source,
                    urdf_notes: Some(import.notes),
                    urdf_warnings: Some(Report {
                        source: src,
                        diagnostics: import.warnings,
                    }),
                })
            }
            format => Ok(Loaded {
                format,
                source: src,
                urdf_notes: None,
                urdf_warnings: None,
            }),
        }
    }

    /// Validates the model (a scene with its model, relative to the
    /// working directory).
    pub fn check(&self) -> Result<Checked, Report> {
        self.check_in(Path::new(""))
    }

    /// [`Loaded::check`] for a file whose path is relative to `root` (a
    /// scene's model is read from there).
    pub fn check_in(&self, root: &Path) -> Result<Checked, Report> {
        match self.format {
            Format::Scene => scene::check_in(&self.source, root),
            Format::Ron | Format::Urdf => {
                let mut checked = check_model(&self.source)?;
                checked.urdf_notes = self.urdf_notes.clone();
                if let Some(w) = &self.urdf_warnings {
                    // The importer reported inconsistent inertias at their
                    // place in the URDF; not again in the converted text.
                    checked
                        .warnings
                        .retain(|d| !d.message.starts_with("inertia of body"));
                    checked.urdf_warnings = Some(w.clone());
                }
                Ok(checked)
            }
        }
    }
}

/// Reads a model file of any [`Format`], converting a URDF. `path` is kept
/// exactly as given for diagnostics.
pub fn load(path: &str) -> Result<Loaded, Report> {
    load_in(Path::new(""), path)
}

/// [`load`] for a `path` relative to `root` (diagnostics name `path`).
pub fn load_in(root: &Path, path: &str) -> Result<Loaded, Report> {
    Loaded::from_source(read_in(root, path)?)
}

/// [`load`] with the URDF import [`urdf::Options`] (`balance_inertia`,
/// `strict`).
pub fn load_with(path: &str, options: &urdf::Options) -> Result<Loaded, Report> {
    Loaded::from_source_with(read(path)?, options)
}

/// Reads a file as text, without looking at what it is.
pub fn read(path: &str) -> Result<Source, Report> {
    read_in(Path::new(""), path)
}

/// [`read`] for a `path` relative to `root` (diagnostics name `path`).
pub fn read_in(root: &Path, path: &str) -> Result<Source, Report> {
    read_text(root, path).map_err(|e| Report {
        source: Source::new(path, ""),
        diagnostics: vec![
            Diagnostic::file_error(format!("cannot read model file: {e}"))
                .with_help("give the path of a `.ron` model file, e.g. `models/pendulum.ron`"),
        ],
    })?
}

/// The file's text; an I/O error apart (a scene reports it at its `model`
/// field), invalid UTF-8 as a diagnostic at its first bad byte.
pub(crate) fn read_text(root: &Path, path: &str) -> std::io::Result<Result<Source, Report>> {
    let bytes = std::fs::read(root.join(path))?;
    Ok(match String::from_utf8(bytes) {
        Ok(text) => Ok(Source::new(path, text)),
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let text = String::from_utf8_lossy(e.as_bytes()).into_owned();
            Err(Report {
                source: Source::new(path, text),
                diagnostics: vec![
                    Diagnostic::error(Span::new(at, at + 1), "model file is not valid UTF-8")
                        .with_help("save the file as UTF-8 text"),
                ],
            })
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_is_told_by_name_then_text() {
        assert_eq!(
            Format::of("r.URDF", "Scene(model: \"m.ron\")"),
            Format::Urdf
        );
        assert_eq!(Format::of("a.scene.ron", ""), Format::Scene);
        assert_eq!(
            Format::of("a.ron", "// c\nScene(model: \"m.ron\")"),
            Format::Scene
        );
        assert_eq!(Format::of("a.ron", "Model(name: \"m\")"), Format::Ron);
        assert_eq!(
            Format::of("robot.urdf (converted)", "Model(name: \"m\")"),
            Format::Ron
        );
    }
}
