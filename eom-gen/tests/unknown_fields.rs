//! Unknown fields are errors everywhere in the model and scene formats,
//! each reported at the misspelled name.
//!
//! Every field name of every bundled model and scene, of the RON examples
//! in `docs/model-format.md` and `README.md`, and of the fixtures (which
//! use every struct, variant and field of both formats) is misspelled in
//! turn, two ways (a letter appended, two letters swapped). `check` must
//! then fail with exactly one error, `unknown field `…``, at that name's
//! line and column: not a silent default (issue #14: `rest_len` in a
//! `SpringDamper` used to give a rest length of 0) and not a follow-on
//! error.

use eom_gen::model::locate::{self, Kind, Node};
use eom_gen::model::{Report, Source};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the workspace holds eom-gen")
        .to_path_buf()
}

/// Checks a model or scene whose path is relative to the workspace.
fn check_text(path: &str, text: &str) -> Result<(), Report> {
    let src = Source::new(path, text);
    // Relative to the workspace: a scene's model and a model's modal data
    // file are read from there.
    eom_gen::model::check_in(&src, &workspace()).map(|_| ())
}

/// `(path, text)` of every file under test; paths relative to the workspace.
fn corpus() -> Vec<(String, String)> {
    let root = workspace();
    let mut files = Vec::new();
    for dir in [
        "models",
        "models/scenes",
        "models/ancf",
        "eom-gen/tests/fixtures",
    ] {
        let mut names: Vec<PathBuf> = std::fs::read_dir(root.join(dir))
            .expect("read the directory")
            .map(|e| e.expect("directory entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "ron"))
            .collect();
        names.sort();
        for p in names {
            let rel = p.strip_prefix(&root).expect("under the workspace");
            let text = std::fs::read_to_string(&p).expect("read the file");
            files.push((rel.display().to_string(), text));
        }
    }
    // The format's examples: the ```ron blocks of the docs. A block opening
    // with `// models/…` is checked under that path (scenes name their
    // model relative to it), others under the document's name.
    for doc in ["docs/model-format.md", "README.md"] {
        let text = std::fs::read_to_string(root.join(doc)).expect("read the doc");
        let mut lines = text.lines();
        let mut n = 0;
        while let Some(line) = lines.next() {
            if line.trim() != "```ron" {
                continue;
            }
            n += 1;
            let block: Vec<&str> = lines.by_ref().take_while(|l| l.trim() != "```").collect();
            let block = block.join("\n") + "\n";
            let named = block
                .lines()
                .next()
                .and_then(|l| l.strip_prefix("// "))
                .and_then(|l| l.split_whitespace().next())
                .filter(|p| p.starts_with("models/"));
            let path = match named {
                Some(p) if p.ends_with(".scene.ron") => p.to_string(),
                _ => format!("{doc}#example{n}.ron"),
            };
            files.push((path, block));
        }
    }
    files
}

/// Every field name in the tree: (name, byte offset).
fn field_names(node: &Node, out: &mut Vec<(String, usize)>) {
    match &node.kind {
        Kind::Fields(fields) => {
            for f in fields {
                out.push((f.name.clone(), f.name_span.start));
                field_names(&f.value, out);
            }
        }
        Kind::Items(items) => items.iter().for_each(|n| field_names(n, out)),
        Kind::Map(entries) => entries.iter().for_each(|(k, v)| {
            field_names(k, out);
            field_names(v, out);
        }),
        Kind::Atom => {}
    }
}

/// The misspellings tried for `name`: a letter appended, and the first two
/// neighbouring letters that differ swapped.
fn misspellings(name: &str) -> Vec<String> {
    let mut out = vec![format!("{name}x")];
    let chars: Vec<char> = name.chars().collect();
    if let Some(k) = (1..chars.len()).find(|&k| {
        chars[k - 1] != chars[k] && chars[k - 1..=k].iter().all(|c| c.is_ascii_alphabetic())
    }) {
        let mut swapped = chars.clone();
        swapped.swap(k - 1, k);
        out.push(swapped.into_iter().collect());
    }
    out
}

/// Every struct and struct-like variant of the two formats: each must
/// appear in the corpus, with each of its fields.
const STRUCTS: [&str; 33] = [
    "JointLimit",
    "Plane",
    "Spheres",
    "Model",
    "CableMount",
    "Parameter",
    "Body",
    "Marker",
    "Frame",
    "Joint",
    "Anchor",
    "AxisAngle",
    "Revolute",
    "Prismatic",
    "Cylindrical",
    "Universal",
    "Screw",
    "SpringDamper",
    "JointSpringDamper",
    "JointForce",
    "Actuator",
    "RollingDisk",
    "Holonomic",
    "Beam",
    "AssumedModes",
    "Modal",
    "FixedNode",
    "Timoshenko",
    "Position",
    "Velocity",
    "JointReaction",
    "Scene",
    "Lock",
];

#[test]
fn every_misspelled_field_is_an_error_at_its_name() {
    let mut checked = 0;
    // Struct → its fields (from the help line), and the fields misspelled.
    let mut declared: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut mutated: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut failures = Vec::new();
    for (path, text) in corpus() {
        if let Err(report) = check_text(&path, &text) {
            panic!("{path} must be valid before it is mutated:\n{report}");
        }
        let tree = locate::parse(&text).expect("a RON value");
        let mut names = Vec::new();
        field_names(&tree, &mut names);
        assert!(!names.is_empty(), "{path} has fields");
        for (name, at) in names {
            for wrong in misspellings(&name) {
                let mut mutant = text.clone();
                mutant.replace_range(at..at + name.len(), &wrong);
                let src = Source::new(path.as_str(), mutant.as_str());
                let lc = src.line_col(at);
                let place = format!("{path}:{}:{}", lc.line, lc.col);
                checked += 1;
                let report = match check_text(&path, &mutant) {
                    Ok(()) => {
                        failures.push(format!("{place}: `{name}` → `{wrong}` is accepted"));
                        continue;
                    }
                    Err(r) => r,
                };
                let want = format!("unknown field `{wrong}` of `");
                let [d] = report.diagnostics.as_slice() else {
                    failures.push(format!(
                        "{place}: `{name}` → `{wrong}` gives {} diagnostics, want one:\n{report}",
                        report.diagnostics.len()
                    ));
                    continue;
                };
                if report.source.path != path
                    || d.span.map(|s| s.start) != Some(at)
                    || !d.message.starts_with(&want)
                {
                    failures.push(format!(
                        "{place}: `{name}` → `{wrong}`: want `{want}…` here, got:\n{report}"
                    ));
                    continue;
                }
                let outer = d.message[want.len()..].trim_end_matches('`').to_string();
                let help = d.help.as_deref().unwrap_or("");
                let Some(list) = help.split(" has the fields ").nth(1) else {
                    failures.push(format!("{place}: help without the fields: {help}"));
                    continue;
                };
                let fields = list.split(", ").map(|f| f.trim_matches('`').to_string());
                declared.entry(outer.clone()).or_default().extend(fields);
                mutated.entry(outer).or_default().insert(name.clone());
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {checked} misspellings not reported at the name:\n{}",
        failures.len(),
        failures.join("\n")
    );
    for s in STRUCTS {
        assert!(
            declared.contains_key(s),
            "no field of `{s}` in the corpus: add one to tests/fixtures"
        );
    }
    for (s, fields) in &declared {
        let missing: Vec<&String> = fields.difference(&mutated[s]).collect();
        assert!(
            missing.is_empty(),
            "fields of `{s}` never misspelled (add them to tests/fixtures): {missing:?}"
        );
    }
    assert!(checked > 2000, "{checked} misspellings checked");
    eprintln!(
        "{checked} misspellings of the fields of {} structs and variants",
        declared.len()
    );
}

#[test]
fn several_misspelled_fields_are_reported_together() {
    let path = "models/pendulum.ron";
    let text = std::fs::read_to_string(workspace().join(path)).expect("read");
    let tree = locate::parse(&text).expect("a RON value");
    let mut names = Vec::new();
    field_names(&tree, &mut names);
    let mut mutant = text.clone();
    // From the end, so the earlier offsets stay valid.
    for (name, at) in names.iter().rev() {
        mutant.replace_range(*at..*at + name.len(), &format!("{name}x"));
    }
    let report = check_text(path, &mutant).expect_err("misspelled");
    let got: Vec<usize> = report
        .diagnostics
        .iter()
        .map(|d| d.span.expect("located").start)
        .collect();
    // Fields inside a misspelled field are not read: the outermost ones.
    let top: Vec<usize> = match &locate::parse(&mutant).expect("a RON value").kind {
        Kind::Fields(fields) => fields.iter().map(|f| f.name_span.start).collect(),
        _ => panic!("a model is a struct"),
    };
    assert_eq!(got, top, "every top-level field, in file order:\n{report}");
}
