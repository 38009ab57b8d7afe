use eom_macros::multibody;

#[multibody(modle = "models/pendulum.ron")]
pub struct Misspelt;

fn main() {}
