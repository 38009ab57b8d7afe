//! What every target does with a reader's result: render the diagnostics
//! (spans must stay inside the text), and for a small model that checks,
//! generate its code (formulation and emission must not panic either).

use eom_gen::model::{Checked, Report};
use eom_gen::{EmitOptions, generate_checked};
use std::hint::black_box;

/// Models up to this many bodies and coordinates are generated; larger ones
/// only checked, so that one execution stays in the milliseconds.
const MAX_BODIES: usize = 6;
const MAX_COORDINATES: usize = 12;

pub fn exercise(result: Result<Checked, Report>) {
    let checked = match result {
        Ok(checked) => checked,
        Err(report) => {
            assert!(
                !report.diagnostics.is_empty(),
                "a rejected model has at least one diagnostic"
            );
            black_box(report.to_string());
            return;
        }
    };
    black_box(checked.render_warnings());
    let system = &checked.system;
    if system.bodies.len() > MAX_BODIES || system.coordinate_names().len() > MAX_COORDINATES {
        return;
    }
    match generate_checked(checked, &EmitOptions::default()) {
        Ok(generated) => {
            black_box(generated.source.len());
        }
        Err(e) => {
            black_box(e.to_string());
        }
    }
}
