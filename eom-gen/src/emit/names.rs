//! Rust names for model names: every string maps to a valid, stable Rust
//! identifier, so that no model, robot or parameter name can break the
//! generated code (see `docs/model-format.md`, "Names in generated code").
//!
//! - The model struct is the model name in CamelCase ([`type_name`]): the
//!   name is cut into words at every character that is not an ASCII letter
//!   or digit, each word gets an upper-case first letter, and the words are
//!   joined (`double_pendulum` → `DoublePendulum`). An empty result, or one
//!   starting with a digit, gets the prefix `Model` (`2dof_planar` →
//!   `Model2dofPlanar`, `_` → `Model`); a result that is a keyword or a
//!   name the generated code uses unqualified (`Self`, `Default`, `Clone`,
//!   `Copy`, `Debug`, `PartialEq`, `Some`, `None`, `Ok`, `Err`, `Option`,
//!   `Result`) gets the suffix `Model` (`self` → `SelfModel`).
//! - Fields (tunable parameters) keep their name where it is an identifier
//!   ([`field_names`]): other characters become `_`, a leading digit (or
//!   an empty name) gets the prefix `_`, a keyword is written raw
//!   (`type` → `r#type`), except `self`, `Self`, `super`, `crate` and `_`,
//!   which cannot be raw and get the suffix `_`. Names that collide after
//!   that get `_2`, `_3`, … in model order.
//!
//! The original names stay in the doc comments and in the `NAME` and
//! `*_NAMES` constants.

use proc_macro2::{Ident, Span};

/// Rust's keywords (strict and reserved, every edition up to 2024), which
/// are not identifiers.
const KEYWORDS: [&str; 53] = [
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for",
    "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return",
    "self", "Self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use", "where",
    "while", "async", "await", "dyn", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "gen", "_",
];

/// Keywords that cannot be raw identifiers.
const NOT_RAW: [&str; 5] = ["self", "Self", "super", "crate", "_"];

/// Names the generated code uses without a path: a model struct with one
/// of them would shadow it.
const USED_UNQUALIFIED: [&str; 12] = [
    "Self",
    "Default",
    "Clone",
    "Copy",
    "Debug",
    "PartialEq",
    "Some",
    "None",
    "Ok",
    "Err",
    "Option",
    "Result",
];

/// True if `s` is a Rust keyword (or `_`).
pub fn is_keyword(s: &str) -> bool {
    KEYWORDS.contains(&s)
}

/// The model struct's name for the model name `name` (see the module
/// documentation); always a valid, non-keyword identifier in CamelCase.
pub fn type_name(name: &str) -> String {
    let mut s: String = name
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty())
        .map(|w| {
            let mut c = w.chars();
            c.next().map_or(String::new(), |f| {
                f.to_ascii_uppercase().to_string() + c.as_str()
            })
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert_str(0, "Model");
    }
    if is_keyword(&s) || USED_UNQUALIFIED.contains(&s.as_str()) {
        s.push_str("Model");
    }
    s
}

/// `name` made an identifier: other characters → `_`, a leading digit or
/// an empty name prefixed `_`, `self`, `Self`, `super`, `crate` and `_`
/// suffixed `_`. Other keywords are returned as they are (written raw by
/// [`ident`]).
fn sanitize(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    if NOT_RAW.contains(&s.as_str()) {
        s.push('_');
    }
    s
}

/// The identifier for an already sanitised name: raw for a keyword.
pub fn ident(s: &str) -> Ident {
    if is_keyword(s) && !NOT_RAW.contains(&s) {
        Ident::new_raw(s, Span::call_site())
    } else {
        Ident::new(s, Span::call_site())
    }
}

/// Field identifiers for `names`, in order: each made an identifier (see
/// the module documentation), later collisions suffixed `_2`, `_3`, ….
pub fn field_names<'a>(names: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let mut taken: Vec<String> = Vec::new();
    names
        .into_iter()
        .map(|n| {
            let base = sanitize(n);
            let mut name = base.clone();
            let mut k = 2;
            while taken.contains(&name) {
                name = format!("{base}_{k}");
                k += 1;
            }
            taken.push(name.clone());
            name
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn type_names() {
        assert_eq!(type_name("double_pendulum"), "DoublePendulum");
        assert_eq!(type_name("arm7"), "Arm7");
        assert_eq!(type_name("2dof_planar"), "Model2dofPlanar");
        assert_eq!(type_name("_2dof_planar"), "Model2dofPlanar");
        assert_eq!(type_name("self"), "SelfModel");
        assert_eq!(type_name("Self"), "SelfModel");
        assert_eq!(type_name("_"), "Model");
        assert_eq!(type_name(""), "Model");
        assert_eq!(type_name("default"), "DefaultModel");
        assert_eq!(type_name("my-robot.v2"), "MyRobotV2");
        assert_eq!(type_name("ünï"), "N");
    }

    #[test]
    fn fields() {
        assert_eq!(
            field_names(["g", "type", "self", "self_", "_", "9a", "a-b", "a_b", ""]),
            [
                "g", "type", "self_", "self__2", "__", "_9a", "a_b", "a_b_2", "___2"
            ]
        );
        assert_eq!(ident("type").to_string(), "r#type");
        assert_eq!(ident("gen").to_string(), "r#gen");
        assert_eq!(ident("self_").to_string(), "self_");
    }

    #[test]
    fn every_result_parses_as_an_identifier() {
        for n in [
            "self", "Self", "super", "crate", "_", "fn", "2", "", "é", "a b", "Self_",
        ] {
            let t = type_name(n);
            assert!(syn::parse_str::<syn::Ident>(&t).is_ok(), "{n:?} → {t}");
            for f in field_names([n]) {
                let i = ident(&f).to_string();
                assert!(syn::parse_str::<syn::Ident>(&i).is_ok(), "{n:?} → {i}");
            }
        }
    }
}
