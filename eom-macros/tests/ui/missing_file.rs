use eom_macros::multibody;

#[multibody(model = "models/does_not_exist.ron")]
pub struct Missing;

fn main() {}
