//! One loader for every model file: a RON model (`.ron`), a scene
//! (`.scene.ron`, or any file whose top-level value is `Scene(…)`) and a
//! URDF robot (`.urdf`). [`Format::of`] is the only place that tells them
//! apart; [`load`] reads a file, converts a URDF into a RON model, and
//! [`Loaded::check`] validates the result (a scene with its model, which
//! is loaded the same way). [`check_file`](super::check_file),
//! [`generate_file`](crate::generate_file), the [`Builder`](crate::Builder),
//! the CLI and `#[multibody]` all go through here.

use super::read::{Format, read_in, read_text};
use super::{Checked, check_model_with, scene, urdf};
use crate::diag::{Report, Source};
use std::path::Path;

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
    /// How URDF files are imported: this one, and a scene's URDF model.
    pub urdf_options: urdf::Options,
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
                    urdf_options: *options,
                })
            }
            format => Ok(Loaded {
                format,
                source: src,
                urdf_notes: None,
                urdf_warnings: None,
                urdf_options: *options,
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
        self.check_with(root, &[])
    }

    /// [`Loaded::check_in`] with parameter values replaced (`eom-gen
    /// simulate --param NAME=VALUE`): each named parameter of the model (a
    /// scene's model) takes the value instead of what the file says, before
    /// validation, so fixed parameters are inlined with it and tunable ones
    /// default to it. A name the model does not have is an error with the
    /// closest name.
    pub fn check_with(&self, root: &Path, values: &[(String, f64)]) -> Result<Checked, Report> {
        match self.format {
            Format::Scene => check_scene(&self.source, root, values, &self.urdf_options),
            Format::Ron | Format::Urdf => {
                let mut checked = check_model_with(&self.source, values, root)?;
                checked.urdf_notes = self.urdf_notes.clone();
                if let Some(w) = &self.urdf_warnings {
                    // The importer reported inconsistent inertias at their
                    // place in the URDF; not again in the converted text.
                    checked.warnings.retain(|d| {
                        !d.message.starts_with("inertia of body")
                            && !d.message.ends_with("is a ROS package path")
                            && !d.message.starts_with("the mass matrix is singular")
                    });
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

/// Reads a model file of any format and returns the RON text to check: a
/// `.urdf` converted (URDF errors are reported against the URDF), anything
/// else as is. The same as [`load`]`(path)?.source`.
pub fn load_model(path: &str) -> Result<Source, Report> {
    Ok(load(path)?.source)
}

/// [`load`] with the URDF import [`urdf::Options`] (`balance_inertia`,
/// `strict`).
pub fn load_with(path: &str, options: &urdf::Options) -> Result<Loaded, Report> {
    Loaded::from_source_with(super::read::read(path)?, options)
}

/// A scene: reads and validates its model (RON or URDF, relative to
/// `root`), then validates the scene against it and applies it.
fn check_scene(
    src: &Source,
    root: &Path,
    values: &[(String, f64)],
    options: &urdf::Options,
) -> Result<Checked, Report> {
    let spec = scene::parse(src)?;
    let shown = scene::model_path(&src.path, &spec.model);
    let shown_str = shown.display().to_string();
    let read = read_text(root, &shown_str).map_err(|e| {
        scene::model_error(
            src,
            format!(
                "cannot read model `{}` (`{}`): {e}",
                spec.model,
                shown.display()
            ),
            "`model` is the path of a `.ron` model or `.urdf` file, relative to this scene file",
        )
    })?;
    let model = Loaded::from_source_with(read?, options)?;
    if model.format == Format::Scene {
        return Err(scene::model_error(
            src,
            format!("model `{}` is itself a scene", spec.model),
            "a scene names a model file; copy what the other scene selects into this one",
        ));
    }
    // The scene's parameter values, then the caller's (which win).
    let mut all: Vec<(String, f64)> = spec
        .parameters
        .iter()
        .filter(|(n, _)| !values.iter().any(|(m, _)| m == *n))
        .map(|(n, v)| (n.clone(), *v))
        .collect();
    all.extend(values.iter().cloned());
    scene::check_parameter_values(src, &spec, &model.source)?;
    let checked = model.check_with(root, &all)?;
    scene::apply(src, spec, shown, checked)
}
