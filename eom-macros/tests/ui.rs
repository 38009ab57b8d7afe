//! Every user-facing error of `#[multibody]`, pinned with trybuild.

use std::path::PathBuf;

/// trybuild builds the cases as a crate of its own in
/// `<target>/tests/trybuild/eom-macros`, which is the `CARGO_MANIFEST_DIR`
/// the macro resolves model paths against. The models the cases name are
/// copied there, so the cases pass wherever the target directory is (a
/// `CARGO_TARGET_DIR` outside the checkout included).
fn place_models() {
    // This test runs as `<target>/<profile>/deps/ui-<hash>`.
    let exe = std::env::current_exe().unwrap_or_else(|e| panic!("test executable: {e}"));
    let target = exe
        .ancestors()
        .nth(3)
        .unwrap_or_else(|| panic!("no target directory above {}", exe.display()));
    let project = target.join("tests").join("trybuild").join("eom-macros");
    std::fs::create_dir_all(&project).unwrap_or_else(|e| panic!("{}: {e}", project.display()));
    let ui = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("ui");
    for entry in std::fs::read_dir(&ui).unwrap_or_else(|e| panic!("{}: {e}", ui.display())) {
        let path = entry.unwrap_or_else(|e| panic!("{e}")).path();
        if path.extension().is_some_and(|x| x == "ron") {
            let name = path.file_name().unwrap_or_default();
            std::fs::copy(&path, project.join(name))
                .unwrap_or_else(|e| panic!("{} → {}: {e}", path.display(), project.display()));
        }
    }
}

#[test]
fn ui() {
    place_models();
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/*.rs");
}
