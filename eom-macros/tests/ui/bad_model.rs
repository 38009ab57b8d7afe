use eom_macros::multibody;

// trybuild builds this file as a crate in `<target>/tests/trybuild/eom-macros`,
// the `CARGO_MANIFEST_DIR` the macro sees; `tests/ui.rs` copies the model
// there first.
#[multibody(model = "bad_model.ron")]
pub struct Broken;

fn main() {}
