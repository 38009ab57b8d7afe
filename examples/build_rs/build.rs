//! Generates the double pendulum into `OUT_DIR` at build time.

fn main() {
    eom_gen::Builder::new()
        .model("../../models/double_pendulum.ron")
        .compile()
        .unwrap_or_else(|e| panic!("{e}"));
}
