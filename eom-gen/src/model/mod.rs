//! Model files: RON schema ([`spec`]), parsing, validation and diagnostics,
//! scenes ([`scene`]) and URDF import ([`urdf`]).
//!
//! [`load`] reads any model file — a RON model, a scene or a URDF (see
//! [`Format`]) — and is the only place that tells them apart. [`parse`]
//! turns RON text into a [`Spec`] (syntax and type errors, from `ron`),
//! and [`check`] turns text into a validated [`System`] reporting every
//! problem at once, each at its `file:line:col`; [`check_file`] does both.
//! The [`builder`] constructs the same [`Spec`] in code.
//!
//! The model sits at the top of the pipeline: it builds the [`System`] and
//! uses the initial state of [`crate::mech::initial`]; nothing below it
//! imports from here.

pub mod builder;
mod drive;
mod fields;
mod flex_outputs;
mod load;
pub mod locate;
mod read;
pub mod rotation;
pub mod scene;
pub mod spec;
pub mod urdf;
mod validate;

// The diagnostics and the expression language sit below the pipeline
// (the validated `System` and the formulation use them too); they are
// re-exported here under their old paths.
pub use crate::{diag, expr};
pub use diag::{Diagnostic, Report, Severity, Source, Span};
pub use drive::{DriveError, drive_inputs, set_initial};
pub use load::{Loaded, load, load_in, load_model, load_with};
pub use read::{Format, read, read_in};
pub use spec::Spec;
// The initial state is computed below the model (the constraint formulation
// needs it too); re-exported for the validator's users.
pub use crate::mech::initial::{Gap, closure_gaps, initial_poses};

use crate::system::System;
use diag::{did_you_mean, list_names};
use ron::error::Error as RonError;

/// A model that passed validation, with its warnings.
#[derive(Clone, Debug)]
pub struct Checked {
    /// The validated system.
    pub system: System,
    /// The parsed specification.
    pub spec: Spec,
    /// Warnings (never errors).
    pub warnings: Vec<Diagnostic>,
    /// The model source, for rendering the warnings.
    pub source: Source,
    /// The scene applied to the model, if it was read through one.
    pub scene: Option<scene::SceneInfo>,
    /// What the conversion did, when the model was imported from a URDF.
    pub urdf_notes: Option<Vec<String>>,
    /// The import's warnings (located in the URDF), when the model was
    /// imported from a URDF.
    pub urdf_warnings: Option<Report>,
}

impl Checked {
    /// The model's warnings and then the scene's, rendered.
    pub fn render_warnings(&self) -> String {
        let mut out = String::new();
        if let Some(w) = &self.urdf_warnings {
            out += &w.source.render_all(&w.diagnostics);
        }
        out += &self.source.render_all(&self.warnings);
        if let Some(s) = &self.scene {
            out += &s.source.render_all(&s.warnings);
        }
        out
    }

    /// The functions to generate symbolically: the scene's `functions`
    /// (completed by what cannot be derived), else all of them.
    pub fn request(&self) -> crate::functions::FunctionSet {
        self.scene
            .as_ref()
            .map_or_else(crate::functions::FunctionSet::all_requested, |s| {
                s.spec.request()
            })
    }

    /// The text the generated code is derived from, for its content hash:
    /// the model's, after the scene's when there is one.
    pub fn content(&self) -> String {
        match &self.scene {
            Some(s) => format!("{}\n{}", s.source.text, self.source.text),
            None => self.source.text.clone(),
        }
    }
}

fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// Parses model text into a [`Spec`]: syntax and type errors only (the
/// first one), or every unknown field at once.
pub fn parse(src: &Source) -> Result<Spec, Report> {
    fields::read(src)
}

/// Parses and validates model text of any [`Format`]: a scene is checked
/// with its model, relative to the working directory; a URDF is converted
/// first.
pub fn check(src: &Source) -> Result<Checked, Report> {
    check_in(src, std::path::Path::new(""))
}

/// [`check`] for a source whose path is relative to `root` (as in a proc
/// macro, where paths are relative to the crate's manifest directory).
pub fn check_in(src: &Source, root: &std::path::Path) -> Result<Checked, Report> {
    Loaded::from_source(src.clone())?.check_in(root)
}

/// Validates an already parsed [`Spec`] whose text is `src`.
pub fn check_spec(src: &Source, spec: Spec) -> Result<Checked, Report> {
    check_spec_in(src, spec, std::path::Path::new(""))
}

/// [`check_spec`] for a source whose path is relative to `dir` (files the
/// model names, such as modal data, are read relative to the model there).
pub fn check_spec_in(src: &Source, spec: Spec, dir: &std::path::Path) -> Result<Checked, Report> {
    let root = locate::parse(&src.text);
    let (system, diagnostics) = validate::check_in_dir(src, &spec, root.as_ref(), true, dir);
    match system {
        Some(system) => Ok(Checked {
            system,
            spec,
            warnings: diagnostics,
            source: src.clone(),
            scene: None,
            urdf_notes: None,
            urdf_warnings: None,
        }),
        None => Err(Report {
            source: src.clone(),
            diagnostics,
        }),
    }
}

/// Loads, parses and validates a model file of any [`Format`].
pub fn check_file(path: &str) -> Result<Checked, Report> {
    load(path)?.check()
}

/// [`check_file`] with parameter values replaced (see
/// [`Loaded::check_with`]).
pub fn check_file_with_values(path: &str, values: &[(String, f64)]) -> Result<Checked, Report> {
    load(path)?.check_with(std::path::Path::new(""), values)
}

/// Parses and validates a RON model with the named parameters' values
/// replaced; a name the model does not have is an error with the closest
/// name.
fn check_model_with(
    src: &Source,
    values: &[(String, f64)],
    dir: &std::path::Path,
) -> Result<Checked, Report> {
    let mut spec = parse(src)?;
    let mut unknown = Vec::new();
    for (name, value) in values {
        match spec.parameters.iter_mut().find(|p| p.name == *name) {
            Some(p) => p.value = spec::Num::Value(*value),
            None => {
                let names = spec.parameters.iter().map(|p| p.name.as_str());
                let d = Diagnostic::file_error(format!("the model has no parameter `{name}`"));
                unknown.push(match did_you_mean(name, names) {
                    Some(m) => d.with_help(format!("did you mean `{m}`?")),
                    None => d.with_help(format!(
                        "its parameters: {}",
                        spec.parameters
                            .iter()
                            .map(|p| format!("`{}`", p.name))
                            .collect::<Vec<_>>()
                            .join(", ")
                    )),
                });
            }
        }
    }
    if !unknown.is_empty() {
        return Err(Report {
            source: src.clone(),
            diagnostics: unknown,
        });
    }
    check_spec_in(src, spec, dir)
}

fn ron_diagnostic(src: &Source, e: &ron::error::SpannedError) -> Diagnostic {
    let start = src.offset_of(e.span.start.line, e.span.start.col);
    let end = src
        .offset_of(e.span.end.line, e.span.end.col)
        .max(start + 1);
    let span = Span::new(start, end);
    let outer = |o: &Option<String>| o.as_ref().map_or(String::new(), |o| format!(" of `{o}`"));
    let (message, help) = match &e.code {
        RonError::NoSuchStructField {
            expected,
            found,
            outer: o,
        } => (
            format!("unknown field `{found}`{}", outer(o)),
            suggest_field(found, expected, o.as_deref()),
        ),
        RonError::MissingStructField { field, outer: o } => (
            format!("missing field `{field}`{}", outer(o)),
            format!("add `{field}: …` (see docs/model-format.md)"),
        ),
        RonError::DuplicateStructField { field, outer: o } => (
            format!("field `{field}`{} is given twice", outer(o)),
            "remove one of them".to_string(),
        ),
        RonError::NoSuchEnumVariant {
            expected,
            found,
            outer: o,
        } => (
            format!("unknown variant `{found}`{}", outer(o)),
            suggest(found, expected, "variants"),
        ),
        RonError::InvalidValueForType { expected, found } => (
            format!("expected {expected}, found {found}"),
            "see docs/model-format.md for the type of each field".to_string(),
        ),
        RonError::ExpectedDifferentStructName { expected, found } => (
            format!("expected `{expected}(…)`, found `{found}(…)`"),
            format!("write `{expected}(` or just `(`"),
        ),
        RonError::ExpectedDifferentLength { expected, found } => (
            format!("expected {expected}, found {found} element(s)"),
            "vectors have three components: `(x, y, z)`".to_string(),
        ),
        other => (
            format!("{other}"),
            "the model is a RON file: see docs/model-format.md".to_string(),
        ),
    };
    Diagnostic::error(span, message).with_help(help)
}

fn suggest(found: &str, expected: &[&str], what: &str) -> String {
    match did_you_mean(found, expected.iter().copied()) {
        Some(best) => format!("did you mean `{best}`?"),
        None => format!("{what} are {}", list_names(expected.iter().copied())),
    }
}

/// Did-you-mean and the list of valid fields, e.g. "did you mean
/// `rest_length`? `SpringDamper` has the fields `name`, `a`, …".
fn suggest_field(found: &str, expected: &[&str], outer: Option<&str>) -> String {
    let list = match outer {
        Some(o) => format!("`{o}` has the fields "),
        None => "the fields are ".to_string(),
    } + &list_names(expected.iter().copied());
    // A typo, else a shortened or lengthened name (`rest_len`, `rest_angle`).
    let best = did_you_mean(found, expected.iter().copied()).or_else(|| {
        let mut prefixed = expected.iter().copied().filter(|e| {
            e.len().min(found.len()) >= 3 && (e.starts_with(found) || found.starts_with(e))
        });
        match (prefixed.next(), prefixed.next()) {
            (Some(only), None) => Some(only),
            _ => None,
        }
    });
    match best {
        Some(best) => format!("did you mean `{best}`? {list}"),
        None => list,
    }
}
