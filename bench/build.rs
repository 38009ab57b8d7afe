//! Generates spatial n-link chains (built with the builder API) for the
//! per-call benchmarks.

fn main() {
    let out = std::env::var("OUT_DIR").unwrap_or_else(|_| ".".into());
    let mut builder = eom_gen::Builder::new();
    for n in [10, 50] {
        let mut spec = eom_gen::model::builder::n_link_chain(n, true);
        spec.name = format!("chain{n}");
        let path = format!("{out}/chain{n}.ron");
        std::fs::write(&path, spec.to_ron()).unwrap_or_else(|e| panic!("{path}: {e}"));
        builder = builder.model(path);
    }
    builder.compile().unwrap_or_else(|e| panic!("{e}"));
    // The same 10-link chain with fused multiply-adds, for the FMA test.
    let mut spec = eom_gen::model::builder::n_link_chain(10, true);
    spec.name = "chain10_fma".into();
    let path = format!("{out}/chain10_fma.ron");
    std::fs::write(&path, spec.to_ron()).unwrap_or_else(|e| panic!("{path}: {e}"));
    eom_gen::Builder::new()
        .model(path)
        .fma(true)
        .compile()
        .unwrap_or_else(|e| panic!("{e}"));
    println!("cargo:rerun-if-changed=build.rs");
}
