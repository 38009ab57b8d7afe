//! URDF: text → `urdf::convert` → the converted RON text checked as the
//! loader does → (small models) `generate_checked`.
#![no_main]

use eom_gen::model::{self, Source, urdf};
use libfuzzer_sys::fuzz_target;
use std::hint::black_box;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let src = Source::new("fuzz.urdf", text);
    match urdf::convert(&src) {
        Err(report) => {
            assert!(!report.diagnostics.is_empty());
            black_box(report.to_string());
        }
        Ok(import) => {
            black_box(&import.notes);
            black_box(src.render_all(&import.warnings));
            common::exercise(model::check(&import.source));
        }
    }
});
