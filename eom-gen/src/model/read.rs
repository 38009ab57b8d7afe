//! Reading model files: their text (invalid UTF-8 as a located error,
//! never echoed) and what they are ([`Format`]). A leaf of the model stage:
//! the URDF importer and the loader read through it.

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
            let bytes = e.as_bytes();
            let control = |b: &u8| *b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r');
            // A binary file (an executable, an image, a compressed file)
            // is named, never echoed to the terminal.
            if bytes.iter().any(control) {
                return Ok(Err(Report {
                    source: Source::new(path, ""),
                    diagnostics: vec![
                        Diagnostic::file_error(format!(
                            "not a text file (byte {at} is not UTF-8, and it holds control characters)"
                        ))
                        .with_help(
                            "give a model (`.ron`), a scene (`.scene.ron`) or a URDF (`.urdf`) file, saved as UTF-8 text",
                        ),
                    ],
                }));
            }
            // Text with a stray byte: shown where it is.
            let text = String::from_utf8_lossy(bytes).into_owned();
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
