//! No model file makes `check` panic, and every error it reports has a
//! location inside the file. The inputs are the bundled models, mutated:
//! truncated, with characters deleted, inserted or swapped, and with
//! values replaced by hostile ones (`inf`, `NaN`, huge exponents, unknown
//! names, unbalanced brackets).

use eom_gen::model::{Source, check, load};
use proptest::prelude::*;

/// The bundled models and the RON fuzzing seeds (`fuzz/seeds/ron_model`:
/// models that are wrong in ways only the mechanics shows, such as a loop
/// that cannot close).
fn bundled() -> Vec<String> {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let mut paths: Vec<_> = ["models", "fuzz/seeds/ron_model"]
        .iter()
        .flat_map(|dir| {
            std::fs::read_dir(format!("{root}/{dir}"))
                .map(|d| d.filter_map(|e| e.ok()).map(|e| e.path()).collect())
                .unwrap_or_else(|_| Vec::new())
        })
        .collect();
    paths.sort();
    paths
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .filter_map(|p| std::fs::read_to_string(p).ok())
        .collect()
}

/// The bundled scenes, as (path relative to the repository, text).
fn bundled_scenes() -> Vec<(String, String)> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/scenes");
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.ends_with(".scene.ron"))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
        .into_iter()
        .filter_map(|n| {
            let text = std::fs::read_to_string(format!("{dir}/{n}")).ok()?;
            Some((format!("models/scenes/{n}"), text))
        })
        .collect()
}

const TOKENS: &[&str] = &[
    "",
    "-1",
    "0",
    "1e400",
    "inf",
    "NaN",
    "-inf",
    "\"",
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    ",",
    ":",
    "\"ground\"",
    "\"1/0\"",
    "\"sqrt(-1)\"",
    "\"((((\"",
    "\"x\"",
    "\"t\"",
    "Spherical",
    "Free",
    "Fixed",
    "true",
    "Some(",
    "None",
    "//",
    "/*",
    "r#\"",
    "'",
    "ü",
    "\u{0}",
    "1.5",
    "\"pi\"",
    "[]",
    "()",
    "InverseDynamics",
    "MassMatrix",
    "functions: [],",
    "functions: [Bias, MassMatrix],",
];

#[derive(Clone, Debug)]
enum Mutation {
    Truncate(usize),
    Delete(usize, usize),
    Insert(usize, &'static str),
    Replace(usize, usize, &'static str),
    Swap(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let token = proptest::sample::select(TOKENS);
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), 1usize..40).prop_map(|(a, n)| Mutation::Delete(a, n)),
        (any::<usize>(), token.clone()).prop_map(|(a, t)| Mutation::Insert(a, t)),
        (any::<usize>(), 1usize..12, token).prop_map(|(a, n, t)| Mutation::Replace(a, n, t)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::Swap(a, b)),
    ]
}

/// Applies a mutation on character boundaries.
fn apply(text: &str, m: &Mutation) -> String {
    let chars: Vec<char> = text.chars().collect();
    let n = chars.len().max(1);
    let s = |v: &[char]| v.iter().collect::<String>();
    match *m {
        Mutation::Truncate(a) => s(&chars[..a % n]),
        Mutation::Delete(a, k) => {
            let a = a % n;
            let b = (a + k).min(chars.len());
            s(&chars[..a]) + &s(&chars[b..])
        }
        Mutation::Insert(a, t) => {
            let a = a % n;
            s(&chars[..a]) + t + &s(&chars[a..])
        }
        Mutation::Replace(a, k, t) => {
            let a = a % n;
            let b = (a + k).min(chars.len());
            s(&chars[..a]) + t + &s(&chars[b..])
        }
        Mutation::Swap(a, b) => {
            let mut c = chars.clone();
            if !c.is_empty() {
                let (a, b) = (a % c.len(), b % c.len());
                c.swap(a, b);
            }
            s(&c)
        }
    }
}

/// Every error is located; a model that passes `check` with closed loops
/// assembles: its initial state is put on the loop closures to within the
/// tolerance a run starts from (`eom_sim::ASSEMBLY_TOL`), so no accepted
/// model is simulated with its loops open.
fn assert_located(text: &str) -> Result<(), TestCaseError> {
    match check(&Source::new("m.ron", text)) {
        Ok(c) => {
            let sys = &c.system;
            if !sys.graph.cut_joints().is_empty()
                && let Ok(num) = eom_gen::mech::Numeric::new(sys)
                && let Ok(a) = num.assemble(&sys.q0(), &sys.u0(), 0.0)
            {
                prop_assert!(
                    a.residual <= eom_sim::ASSEMBLY_TOL,
                    "accepted by check, but its loops assemble only to max |Φ| {:e} (want ≤ {:e})",
                    a.residual,
                    eom_sim::ASSEMBLY_TOL
                );
            }
            Ok(())
        }
        Err(report) => {
            prop_assert!(
                !report.diagnostics.is_empty(),
                "an error report names at least one error"
            );
            for d in &report.diagnostics {
                let span = d
                    .span
                    .ok_or_else(|| TestCaseError::fail(format!("no location: {d:?}")))?;
                prop_assert!(
                    span.start <= text.len(),
                    "span {span:?} beyond the text ({})",
                    text.len()
                );
            }
            // Rendering never panics either.
            let _ = report.to_string();
            Ok(())
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4096, ..ProptestConfig::default() })]

    #[test]
    fn mutated_models_never_panic_and_errors_have_locations(
        which in any::<usize>(),
        mutations in proptest::collection::vec(mutation(), 1..4),
    ) {
        let models = bundled();
        prop_assume!(!models.is_empty());
        let mut text = models[which % models.len()].clone();
        for m in &mutations {
            text = apply(&text, m);
        }
        assert_located(&text)?;
    }

    #[test]
    fn mutated_scenes_never_panic_and_errors_have_locations(
        which in any::<usize>(),
        mutations in proptest::collection::vec(mutation(), 1..4),
    ) {
        let scenes = bundled_scenes();
        prop_assume!(!scenes.is_empty());
        let (path, mut text) = scenes[which % scenes.len()].clone();
        for m in &mutations {
            text = apply(&text, m);
        }
        let root = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."));
        match eom_gen::model::check_in(&Source::new(path, text), root) {
            // An accepted scene asks for functions from which every other
            // one can be computed.
            Ok(c) => prop_assert_eq!(c.request(), c.request().derivable()),
            Err(report) => {
                prop_assert!(!report.diagnostics.is_empty());
                for d in &report.diagnostics {
                    let span = d
                        .span
                        .ok_or_else(|| TestCaseError::fail(format!("no location: {d:?}")))?;
                    prop_assert!(span.start <= report.source.text.len(), "span {span:?} beyond the text");
                }
                let _ = report.to_string();
            }
        }
    }

    #[test]
    fn arbitrary_text_never_panics(text in "\\PC{0,200}") {
        assert_located(&text)?;
    }
}

#[test]
fn bundled_models_are_found() {
    assert!(bundled().len() >= 11, "models/ holds the bundled models");
    assert!(
        bundled_scenes().len() >= 2,
        "models/scenes/ holds the arm7 scenes"
    );
}

#[test]
fn invalid_utf8_is_reported_at_its_byte() {
    let dir = std::env::temp_dir().join(format!("eom-robustness-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join("bad.ron");
    let _ = std::fs::write(&path, b"Model(\n  name: \"x\xff\",\n)");
    let path = path.to_string_lossy().into_owned();
    let report = load(&path).expect_err("not UTF-8");
    let d = &report.diagnostics[0];
    let lc = report.source.line_col(d.span.map_or(0, |s| s.start));
    assert_eq!((lc.line, lc.col), (2, 11), "{report}");
    let missing = load("no/such/model.ron").expect_err("missing file");
    assert!(
        missing
            .to_string()
            .starts_with("no/such/model.ron: error: cannot read model file")
    );
}

#[test]
fn deeply_nested_input_is_an_error_not_a_stack_overflow() {
    for text in [
        "[".repeat(50_000),
        "(".repeat(50_000),
        format!("Model(name: \"{}\")", "(".repeat(50_000)),
    ] {
        assert!(check(&Source::new("deep.ron", text)).is_err());
    }
}

/// The bundled four-bar with its second ground pivot 4 m further away:
/// links of 1 m cannot reach, so no configuration closes the loop. `check`
/// refuses it at the cut joint `c` (line and column in the file), naming
/// the smallest residual assembly reached, instead of a warning followed
/// by "valid".
#[test]
fn a_loop_that_cannot_close_is_an_error_at_its_cut_joint() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../fuzz/seeds/ron_model/fourbar_impossible.ron"
    );
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let report = match check(&Source::new("fourbar_impossible.ron", text.as_str())) {
        Ok(_) => panic!("got a valid model, want an error: the loop cannot close"),
        Err(r) => r,
    };
    let errors: Vec<_> = report.diagnostics.iter().filter(|d| d.is_error()).collect();
    assert_eq!(errors.len(), 1, "got {errors:?}, want one error");
    let e = errors[0];
    assert!(
        e.message.contains("cut joint `c` cannot be closed") && e.message.contains("max |Φ|"),
        "got `{}`",
        e.message
    );
    let line = e.span.map(|s| report.source.line_col(s.start).line);
    let want = text
        .lines()
        .position(|l| l.contains("name: \"c\""))
        .map(|k| k + 1);
    assert!(
        line.is_some() && line <= want && line >= want.map(|w| w.saturating_sub(2)),
        "got the error at line {line:?}, want the cut joint `c` (line {want:?})"
    );
}
