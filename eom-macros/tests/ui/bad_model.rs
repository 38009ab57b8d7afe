use eom_macros::multibody;

// trybuild builds this file in `target/tests/trybuild/eom-macros`, which is
// the `CARGO_MANIFEST_DIR` the macro sees; the model sits next to this file.
#[multibody(model = "../../../../eom-macros/tests/ui/bad_model.ron")]
pub struct Broken;

fn main() {}
