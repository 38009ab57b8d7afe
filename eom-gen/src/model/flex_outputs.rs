//! The outputs of flexible bodies (`Deformation`, `SectionForces`,
//! `NodePosition`, `ElasticEnergy`), checked alike in models and scenes:
//! each validator finds the body and evaluates `x`, this says what else is
//! wrong.

use crate::graph::BodyId;
use crate::system::{BodyInfo, FlexSource, OutputKind};

/// A flexible-body output with its body found and `x` evaluated.
pub(crate) enum FlexOutput<'a> {
    /// `Deformation(name, body, x)`.
    Deformation(&'a str, f64),
    /// `SectionForces(name, body, x)`.
    SectionForces(&'a str, f64),
    /// `NodePosition(body, node)`.
    NodePosition(usize),
    /// `ElasticEnergy(body)`.
    ElasticEnergy,
}

/// One problem: the field it is at, what is wrong, what would be right.
pub(crate) struct Problem {
    /// The output's field.
    pub field: &'static str,
    /// What is wrong.
    pub message: String,
    /// What would be right.
    pub help: String,
}

fn is_identifier(s: &str) -> bool {
    let mut c = s.chars();
    c.next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && c.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The output on body `b`, or every problem with it.
pub(crate) fn resolve(
    out: FlexOutput<'_>,
    b: BodyId,
    body: &BodyInfo,
) -> Result<OutputKind, Vec<Problem>> {
    let what = match out {
        FlexOutput::Deformation(..) => "Deformation",
        FlexOutput::SectionForces(..) => "SectionForces",
        FlexOutput::NodePosition(_) => "NodePosition",
        FlexOutput::ElasticEnergy => "ElasticEnergy",
    };
    let Some(flex) = body.flexible.as_deref() else {
        return Err(vec![Problem {
            field: "body",
            message: format!(
                "output `{what}` needs a flexible body, but `{}` is rigid",
                body.name
            ),
            help: "name a body with `flexible: Beam(…)`".into(),
        }]);
    };
    let mut problems = Vec::new();
    // Sections need the built-in beam's elements; assumed modes and
    // imported modal data have their shapes only at their nodes.
    let source = match &flex.source {
        FlexSource::Beam => None,
        FlexSource::Assumed { .. } => Some("assumed modes"),
        FlexSource::Modal { .. } => Some("imported modal data"),
    };
    if let (Some(source), FlexOutput::Deformation(..) | FlexOutput::SectionForces(..)) =
        (source, &out)
    {
        return Err(vec![Problem {
            field: "body",
            message: format!(
                "output `{what}` at a section needs the built-in beam's elements, but `{}` has {source}",
                body.name
            ),
            help: "ask for `NodePosition` at a node of the body (named in its `nodes`, or the modal file's) or for `ElasticEnergy`".into(),
        }]);
    }
    let nodes = flex.modes.shapes.nrows() / 6;
    let length = flex.beam.length;
    let mut section = |name: &str, x: f64| {
        if !is_identifier(name) {
            problems.push(Problem {
                field: "name",
                message: format!("output name `{name}` is not an identifier"),
                help: "use letters, digits and `_`, starting with a letter".into(),
            });
        }
        if !(0.0..=length).contains(&x) {
            problems.push(Problem {
                field: "x",
                message: format!(
                    "section x = {x} m is not on beam `{}`, which runs from 0 to {length} m",
                    body.name
                ),
                help: format!("give 0 ≤ x ≤ {length}"),
            });
        }
    };
    let kind = match out {
        FlexOutput::Deformation(name, x) => {
            section(name, x);
            OutputKind::Deformation {
                body: b,
                x,
                name: name.to_string(),
            }
        }
        FlexOutput::SectionForces(name, x) => {
            section(name, x);
            OutputKind::SectionForces {
                body: b,
                x,
                name: name.to_string(),
            }
        }
        FlexOutput::NodePosition(node) => {
            let last = match source {
                None => flex.beam.elements,
                Some(_) => nodes.saturating_sub(1),
            };
            if node > last || (source.is_some() && nodes == 0) {
                problems.push(Problem {
                    field: "node",
                    message: if nodes == 0 {
                        format!("node {node} does not exist: `{}` has no nodes", body.name)
                    } else {
                        format!(
                            "node {node} does not exist: {}`{}` has nodes 0..={last}",
                            if source.is_none() { "beam " } else { "" },
                            body.name
                        )
                    },
                    help: if nodes == 0 {
                        "name nodes on the body (`nodes: [(name, x)]`) first".into()
                    } else {
                        format!("give a node from 0 to {last}")
                    },
                });
            }
            OutputKind::NodePosition { body: b, node }
        }
        FlexOutput::ElasticEnergy => OutputKind::ElasticEnergy(b),
    };
    if problems.is_empty() {
        Ok(kind)
    } else {
        Err(problems)
    }
}
