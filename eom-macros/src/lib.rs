//! `#[multibody(model = "models/x.ron")]`: eom-gen at compile time.
