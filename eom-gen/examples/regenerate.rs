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

// `MIXED`, `SCENES` and `generated_files`, shared with the freshness test.
include!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../generated/files.rs"
));

fn main() -> ExitCode {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    if elements(root) != ExitCode::SUCCESS {
        return ExitCode::from(1);
    }
    if std::env::args().nth(1).as_deref() == Some("elements") {
        return ExitCode::SUCCESS;
    }
    let files = match generated_files(root) {
        Ok(files) => files,
        Err(e) => {
            eprintln!("cannot read models/: {e}");
            return ExitCode::from(1);
        }
    };
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
