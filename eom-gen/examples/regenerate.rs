//! Regenerates `generated/src/` from every model in `models/`, and the ANCF
//! element kernels in `elements/src/` (one file per element type):
//! `cargo run -p eom-gen --example regenerate` (`-- elements` for the
//! element kernels only).

use std::process::ExitCode;

/// Writes one file per ANCF element type and prints its op counts.
fn elements(root: &str) -> ExitCode {
    for kind in eom_gen::ancf::Kind::ALL {
        let k = eom_gen::ancf::derive(kind);
        let path = format!("{root}/elements/src/{}.rs", k.def.module);
        eprintln!("… {path}");
        for (name, p) in [
            ("internal_forces", &k.forces),
            ("internal_jacobians", &k.jacobians),
            ("elastic_forces", &k.elastic_forces),
            ("elastic_stiffness", &k.elastic_stiffness),
            ("mass", &k.mass),
            ("uniform_load", &k.load),
        ] {
            eprintln!("    {}", eom_gen::ancf::emit::op_line(name, p));
        }
        if let Err(e) = std::fs::write(&path, eom_gen::ancf::emit::emit(&k)) {
            eprintln!("cannot write {path}: {e}");
            return ExitCode::from(1);
        }
    }
    ExitCode::SUCCESS
}

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

fn main() -> ExitCode {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    if elements(root) != ExitCode::SUCCESS {
        return ExitCode::from(1);
    }
    if std::env::args().nth(1).as_deref() == Some("elements") {
        return ExitCode::SUCCESS;
    }
    let mut names: Vec<String> = match std::fs::read_dir(format!("{root}/models")) {
        Ok(dir) => dir
            .filter_map(|e| e.ok())
            .filter_map(|e| e.file_name().into_string().ok())
            .filter_map(|n| n.strip_suffix(".ron").map(str::to_string))
            .collect(),
        Err(e) => {
            eprintln!("cannot read models/: {e}");
            return ExitCode::from(1);
        }
    };
    names.sort();
    // Mixed models (rigid bodies holding ANCF cables) under models/ancf/:
    // their rigid part is generated code like any model's.
    names.extend(MIXED.iter().map(|m| m.to_string()));
    let mut files: Vec<(String, String)> = names
        .iter()
        .map(|path| {
            let name = path.rsplit('/').next().unwrap_or(path).to_string();
            (name, format!("models/{path}.ron"))
        })
        .collect();
    files.extend(SCENES.iter().map(|(n, f)| (n.to_string(), f.to_string())));
    let mut lib = String::from(
        "//! Generated source of every bundled model, one module per model, committed\n\
         //! so readers can see what eom-gen emits. A test fails when a file is stale;\n\
         //! refresh with `cargo run -p eom-gen --example regenerate`.\n\n",
    );
    for (name, model) in &files {
        eprintln!("… {model}");
        let src = match std::fs::read_to_string(format!("{root}/{model}")) {
            Ok(text) => eom_gen::Source::new(model.clone(), text),
            Err(e) => {
                eprintln!("cannot read {model}: {e}");
                return ExitCode::from(1);
            }
        };
        // With the batched functions (`NAME_lanes`), which the tests run
        // lane by lane against the single-state ones.
        let opts = eom_gen::EmitOptions {
            lanes: true,
            ..Default::default()
        };
        match eom_gen::generate_with(&src, &opts) {
            Ok(g) => {
                if let Err(e) = std::fs::write(format!("{root}/generated/src/{name}.rs"), g.source)
                {
                    eprintln!("cannot write generated/src/{name}.rs: {e}");
                    return ExitCode::from(1);
                }
                lib += &format!(
                    "/// Model `{name}`, generated from `{model}`.\n#[rustfmt::skip] // formatted by prettyplease; stays byte-identical\npub mod {name};\n"
                );
            }
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::from(1);
            }
        }
    }
    if let Err(e) = std::fs::write(format!("{root}/generated/src/lib.rs"), lib) {
        eprintln!("cannot write generated/src/lib.rs: {e}");
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}
