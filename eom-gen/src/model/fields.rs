//! Reading a RON file with every unknown field reported at once.
//!
//! `ron` stops at the first unknown field. To report them all, each one
//! found is blanked out (replaced by spaces, so every byte offset stays
//! where it was) and the text is read again, until it reads or fails for
//! another reason. That other failure is reported only when there was no
//! unknown field: it may be a consequence of the blanking (a misspelled
//! required field is then missing), and a first run should not show
//! follow-on errors.

use super::diag::{Report, Source};
use super::locate::{self, Field, Kind, Node};
use super::{ron_diagnostic, ron_options};
use ron::error::Error as RonError;
use serde::de::DeserializeOwned;

/// Most unknown fields reported (and reads of the text) per file.
const MAX_UNKNOWN: usize = 100;

/// Reads `src` as a `T`: syntax and type errors (the first one), or every
/// unknown field of the file.
pub(crate) fn read<T: DeserializeOwned>(src: &Source) -> Result<T, Report> {
    let tree = locate::parse(&src.text);
    let mut text = src.text.clone();
    let mut diagnostics = Vec::new();
    for _ in 0..MAX_UNKNOWN {
        let e = match ron_options().from_str::<T>(&text) {
            Ok(value) if diagnostics.is_empty() => return Ok(value),
            Ok(_) => break,
            Err(e) => e,
        };
        // Offsets in the blanked text are offsets in the original.
        let d = ron_diagnostic(&Source::new(src.path.clone(), text.clone()), &e);
        let unknown = matches!(e.code, RonError::NoSuchStructField { .. });
        if !unknown && !diagnostics.is_empty() {
            break;
        }
        let at = d.span.map(|s| s.start);
        diagnostics.push(d);
        let field = at.and_then(|at| tree.as_ref().and_then(|t| field_named_at(t, at)));
        match field {
            Some(field) if unknown && blank(&mut text, field) => {}
            _ => break,
        }
    }
    Err(Report {
        source: src.clone(),
        diagnostics,
    })
}

/// The field whose name starts at byte `at`.
fn field_named_at(node: &Node, at: usize) -> Option<&Field> {
    if at < node.span.start || at >= node.span.end {
        return None;
    }
    match &node.kind {
        Kind::Fields(fields) => fields.iter().find_map(|f| {
            if f.name_span.start == at {
                Some(f)
            } else {
                field_named_at(&f.value, at)
            }
        }),
        Kind::Items(items) => items.iter().find_map(|n| field_named_at(n, at)),
        Kind::Map(entries) => entries
            .iter()
            .find_map(|(k, v)| field_named_at(k, at).or_else(|| field_named_at(v, at))),
        Kind::Atom => None,
    }
}

/// Replaces `name: value` and a comma after it by spaces (newlines kept);
/// false if the range is not a clean cut of the text.
fn blank(text: &mut String, field: &Field) -> bool {
    let mut start = field.name_span.start;
    if start >= 2 && text.as_bytes().get(start - 2..start) == Some(b"r#") {
        start -= 2; // a raw identifier
    }
    let mut end = field.value.span.end;
    let bytes = text.as_bytes();
    let mut k = end;
    while bytes.get(k).is_some_and(u8::is_ascii_whitespace) {
        k += 1;
    }
    if bytes.get(k) == Some(&b',') {
        end = k + 1;
    }
    if start >= end
        || end > text.len()
        || !text.is_char_boundary(start)
        || !text.is_char_boundary(end)
    {
        return false;
    }
    let spaces: String = text[start..end]
        .bytes()
        .map(|b| if b == b'\n' { '\n' } else { ' ' })
        .collect();
    text.replace_range(start..end, &spaces);
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Spec;

    const TEXT: &str = r#"Model(
    name: "m",
    bodies: [(name: "b", mass: 1, cmo: (0, 0, 1))],
    joints: [(naem: "j", kind: Revolute(axsi: (0, 0, 1), axis: (0, 0, 1)), parent: "ground", child: "b")],
)"#;

    #[test]
    fn every_unknown_field_is_reported_at_its_name() {
        let src = Source::new("m.ron", TEXT);
        let report = read::<Spec>(&src).expect_err("unknown fields");
        let found: Vec<(&str, &str)> = report
            .diagnostics
            .iter()
            .map(|d| {
                let s = d.span.expect("located");
                (&TEXT[s.start..s.end], d.message.as_str())
            })
            .collect();
        assert_eq!(
            found,
            [
                ("cmo", "unknown field `cmo` of `Body`"),
                ("naem", "unknown field `naem` of `Joint`"),
                ("axsi", "unknown field `axsi` of `Revolute`"),
            ],
            "each unknown field once, none of the follow-on `missing field name`"
        );
    }

    #[test]
    fn blanking_keeps_offsets_and_newlines() {
        let mut text = "(a: 1, bb: [\n2], c: 3)".to_string();
        let tree = locate::parse(&text).expect("parses");
        let field = field_named_at(&tree, 7).expect("`bb`");
        assert!(blank(&mut text, field));
        assert_eq!(text, "(a: 1,      \n    c: 3)");
    }
}
