//! Scenes: scene text → `model::check_in` against a root directory holding
//! the bundled models (and the URDF fixtures under `urdf/`) → (small
//! models) `generate_checked`. The scene is read as `scenes/fuzz.scene.ron`,
//! like the bundled scenes (`model: "../arm7.ron"`). A scene whose model
//! path leaves the root is skipped: the fuzzer is not to read the machine's
//! files.
#![no_main]

use eom_gen::model::{self, Source, scene};
use libfuzzer_sys::fuzz_target;
use std::path::{Component, Path, PathBuf};
use std::sync::OnceLock;

#[path = "common.rs"]
mod common;

const SCENE: &str = "scenes/fuzz.scene.ron";

/// A fresh directory with copies of `models/*.ron` (and `scenes/`), the
/// `every_field` fixtures in `scenes/` (their scene names
/// `every_field.ron` next to it) and the URDF fixtures in `urdf/`.
fn root() -> &'static Path {
    static ROOT: OnceLock<PathBuf> = OnceLock::new();
    ROOT.get_or_init(|| {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let root = std::env::temp_dir().join(format!("eom-fuzz-scene-{}", std::process::id()));
        let copy_all = |from: &Path, to: &Path, ext: &str| {
            std::fs::create_dir_all(to).unwrap();
            for e in std::fs::read_dir(from).unwrap() {
                let p = e.unwrap().path();
                if p.is_file() && p.to_string_lossy().ends_with(ext) {
                    std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
                }
            }
        };
        copy_all(&repo.join("models"), &root, ".ron");
        copy_all(&repo.join("models/scenes"), &root.join("scenes"), ".ron");
        copy_all(
            &repo.join("eom-gen/tests/fixtures"),
            &root.join("scenes"),
            ".ron",
        );
        copy_all(
            &repo.join("eom-gen/tests/fixtures/urdf"),
            &root.join("urdf"),
            ".urdf",
        );
        root
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let src = Source::new(SCENE, text);
    if let Ok(spec) = scene::parse(&src) {
        let path = scene::model_path(SCENE, &spec.model);
        if !path.components().all(|c| matches!(c, Component::Normal(_))) {
            return;
        }
    }
    common::exercise(model::check_in(&src, root()));
});
