use eom_macros::multibody;

// One misspelled field in the model gives one error: the code that uses
// the struct (`Misspelled::default()`) does not add a cascade of its own.
#[multibody(model = "misspelled_field.ron")]
pub struct Misspelled;

fn main() {
    let _model = Misspelled::default();
}
