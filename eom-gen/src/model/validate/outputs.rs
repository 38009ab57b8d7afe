//! Requested outputs, rigid and of flexible bodies.

use super::{Ctx, Scope, f, i, join};
use crate::diag::list_names;
use crate::model::flex_outputs::{self, FlexOutput};
use crate::model::locate::Seg;
use crate::model::spec::{self, Spec};
use crate::system::*;

impl Ctx<'_> {
    /// A flexible-body output on body `b`, its problems reported at `path`.
    pub(super) fn flex_output(
        &mut self,
        want: FlexOutput<'_>,
        b: usize,
        body: &BodyInfo,
        path: &[Seg<'static>],
    ) -> Option<OutputKind> {
        match flex_outputs::resolve(want, b, body) {
            Ok(kind) => Some(kind),
            Err(problems) => {
                for p in problems {
                    self.error(&join(path, &[f(p.field)]), p.message, p.help);
                }
                None
            }
        }
    }

    pub(super) fn outputs(
        &mut self,
        spec: &Spec,
        bodies: &[BodyInfo],
        joints: &[JointInfo],
    ) -> Option<Vec<OutputKind>> {
        let mut out = Vec::new();
        let mut ok = true;
        for (k, o) in spec.outputs.iter().enumerate() {
            let path = [f("outputs"), i(k)];
            let kind = match o {
                spec::Output::Position { body, marker }
                | spec::Output::Velocity { body, marker } => {
                    let b = self.body_ref(bodies, body, &join(&path, &[f("body")]), "output");
                    let m = b.and_then(|b| {
                        let found = bodies[b].markers.iter().position(|x| &x.name == marker);
                        let failed = self
                            .failed_markers
                            .contains(&(body.clone(), marker.clone()));
                        if found.is_none() && !failed {
                            let names = bodies[b].markers.iter().map(|x| x.name.as_str());
                            self.error(
                                &join(&path, &[f("marker")]),
                                format!("body `{body}` has no marker `{marker}`"),
                                format!("its markers are {}", list_names(names)),
                            );
                        }
                        found
                    });
                    match (b, m, o) {
                        (Some(b), Some(m), spec::Output::Position { .. }) => {
                            Some(OutputKind::Position(b, m))
                        }
                        (Some(b), Some(m), _) => Some(OutputKind::Velocity(b, m)),
                        _ => None,
                    }
                }
                spec::Output::JointReaction { joint } => self
                    .joint_ref(joints, joint, &join(&path, &[f("joint")]))
                    .map(OutputKind::JointReaction),
                spec::Output::Energy => Some(OutputKind::Energy),
                spec::Output::Momentum => Some(OutputKind::Momentum),
                spec::Output::Deformation { name, body, x }
                | spec::Output::SectionForces { name, body, x } => {
                    let b = self.body_ref(bodies, body, &join(&path, &[f("body")]), "output");
                    let x = self.quantity(x, &join(&path, &[f("x")]), Scope::Params);
                    match (b, x) {
                        (Some(b), Some(x)) => {
                            let want = if matches!(o, spec::Output::Deformation { .. }) {
                                FlexOutput::Deformation(name, x.value)
                            } else {
                                FlexOutput::SectionForces(name, x.value)
                            };
                            self.flex_output(want, b, &bodies[b], &path)
                        }
                        _ => None,
                    }
                }
                spec::Output::NodePosition { body, node } => self
                    .body_ref(bodies, body, &join(&path, &[f("body")]), "output")
                    .and_then(|b| {
                        self.flex_output(FlexOutput::NodePosition(*node), b, &bodies[b], &path)
                    }),
                spec::Output::ElasticEnergy { body } => self
                    .body_ref(bodies, body, &join(&path, &[f("body")]), "output")
                    .and_then(|b| {
                        self.flex_output(FlexOutput::ElasticEnergy, b, &bodies[b], &path)
                    }),
            };
            match kind {
                Some(kind) => out.push(kind),
                None => ok = false,
            }
        }
        ok.then_some(out)
    }
}
