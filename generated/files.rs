// The models `generated/src/` holds, one module each: read by the
// regenerate example (`eom-gen/examples/regenerate.rs`), which writes
// them, and by the freshness test (`tests/generated.rs`), which compares
// them, through `include!`, so the two cannot list different files.
// Not a module of the `eom-generated` crate.

/// Mixed models of `models/ancf/` whose rigid part is generated too (the
/// cables' kernels are model-independent, in `elements/src/`).
pub const MIXED: [&str; 3] = [
    "ancf/pendulum_rod",
    "ancf/fourbar_cable",
    "ancf/pendulum_peg",
];

/// Scenes generated too: arm7 with its derivatives, so that the batched
/// tests run `forward_dynamics_derivatives_lanes` (with its dense product)
/// lane by lane against the single-state function.
pub const SCENES: [(&str, &str); 1] = [(
    "arm7_derivatives",
    "tests/scenes/arm7_derivatives.scene.ron",
)];

/// Every generated module as `(module name, file relative to the
/// repository root)`: each `models/*.ron` in name order, then [`MIXED`],
/// then [`SCENES`].
pub fn generated_files(root: &str) -> std::io::Result<Vec<(String, String)>> {
    let mut names: Vec<String> = std::fs::read_dir(format!("{root}/models"))?
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().into_string().ok())
        .filter_map(|n| n.strip_suffix(".ron").map(str::to_string))
        .collect();
    names.sort();
    names.extend(MIXED.iter().map(|m| m.to_string()));
    let mut files: Vec<(String, String)> = names
        .iter()
        .map(|path| {
            let name = path.rsplit('/').next().unwrap_or(path).to_string();
            (name, format!("models/{path}.ron"))
        })
        .collect();
    files.extend(SCENES.iter().map(|(n, f)| (n.to_string(), f.to_string())));
    Ok(files)
}
