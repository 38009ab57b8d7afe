//! RON models: text → `model::check` → (small models) `generate_checked`.
//! A text whose top-level value is `Scene(…)` is left to the `scene` target
//! (it would read its model relative to the working directory).
#![no_main]

use eom_gen::model::{self, Format, Source};
use libfuzzer_sys::fuzz_target;

#[path = "common.rs"]
mod common;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let src = Source::new("fuzz.ron", text);
    if Format::of(&src.path, &src.text) != Format::Ron {
        return;
    }
    common::exercise(model::check(&src));
});
