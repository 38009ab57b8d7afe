//! Where each value of a RON file is: a small, forgiving RON reader that
//! keeps only structure and byte spans.
//!
//! `ron` + serde check types and report syntax errors with positions, but a
//! value that deserialises fine carries no position. Validation finds most
//! problems after deserialisation (an unknown body name, a negative mass),
//! so it asks this locator for the span of a value by its path, e.g.
//! `joints[2].kind.axis`. The reader never panics: on anything it does not
//! understand it stops, and lookups fall back to the nearest ancestor found.

use crate::diag::Span;

/// Deepest nesting the reader descends into (`ron` stops at 128 too).
const MAX_DEPTH: usize = 256;

/// One value with its span.
#[derive(Clone, Debug, Default)]
pub struct Node {
    /// The whole value, including a struct or variant name before `(`.
    pub span: Span,
    /// `Name` in `Name(...)` or a bare identifier value.
    pub name: Option<String>,
    /// What is inside.
    pub kind: Kind,
}

/// The shape of a value.
#[derive(Clone, Debug, Default)]
pub enum Kind {
    /// `(a: 1, b: 2)` or `Name(a: 1)`.
    Fields(Vec<Field>),
    /// `[1, 2]`, `(1, 2)` or `Name(1, 2)`.
    Items(Vec<Node>),
    /// `{ k: v }`.
    Map(Vec<(Node, Node)>),
    /// A number, string, character, boolean or bare identifier.
    #[default]
    Atom,
}

/// A named field of a struct-like value.
#[derive(Clone, Debug)]
pub struct Field {
    /// The field name.
    pub name: String,
    /// Span of the field name.
    pub name_span: Span,
    /// The value.
    pub value: Node,
}

/// One step of a path into a value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Seg<'a> {
    /// A named field.
    Field(&'a str),
    /// An element of a list or tuple.
    Index(usize),
}

/// Reads `text` into a tree of spans; `None` if it has no value at all.
pub fn parse(text: &str) -> Option<Node> {
    let mut r = Reader {
        s: text.as_bytes(),
        i: 0,
        depth: 0,
    };
    r.skip_ws();
    // `#![enable(...)]` attributes.
    while r.peek() == Some(b'#') {
        r.skip_balanced_attribute();
        r.skip_ws();
    }
    r.value()
}

impl Node {
    /// The node at `path`, or the deepest ancestor found, with how many
    /// segments were matched.
    pub fn find(&self, path: &[Seg<'_>]) -> (&Node, usize) {
        let mut node = self.unwrap_some();
        for (depth, seg) in path.iter().enumerate() {
            let next = match (seg, &node.kind) {
                (Seg::Field(f), Kind::Fields(fields)) => {
                    fields.iter().find(|x| x.name == *f).map(|x| &x.value)
                }
                (Seg::Index(i), Kind::Items(items)) => items.get(*i),
                _ => None,
            };
            match next {
                Some(n) => node = n.unwrap_some(),
                None => return (node, depth),
            }
        }
        (node, path.len())
    }

    /// Span of the value at `path` (or of its deepest ancestor found).
    pub fn span_of(&self, path: &[Seg<'_>]) -> Span {
        self.find(path).0.span
    }

    /// Span of the *name* of the field at `path` when it is a named field,
    /// else of the value.
    pub fn field_name_span(&self, path: &[Seg<'_>]) -> Span {
        if let Some((Seg::Field(f), parent)) = path.split_last() {
            let (node, matched) = self.find(parent);
            if matched == parent.len()
                && let Kind::Fields(fields) = &node.kind
                && let Some(field) = fields.iter().find(|x| x.name == *f)
            {
                return field.name_span;
            }
        }
        self.span_of(path)
    }

    /// `Some(x)` is transparent to paths (implicit `Some` is allowed too).
    fn unwrap_some(&self) -> &Node {
        match (&self.name, &self.kind) {
            (Some(n), Kind::Items(items)) if n == "Some" && items.len() == 1 => {
                items[0].unwrap_some()
            }
            _ => self,
        }
    }
}

/// Offset of the first character of a string value's contents, given the
/// span of the string literal (handles `"…"`, `r"…"` and `r#"…"#`).
pub fn string_contents_start(text: &str, span: Span) -> usize {
    text.get(span.start..span.end)
        .and_then(|s| s.find('"'))
        .map_or(span.start, |i| span.start + i + 1)
}

struct Reader<'a> {
    s: &'a [u8],
    i: usize,
    depth: usize,
}

impl Reader<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn peek_at(&self, k: usize) -> Option<u8> {
        self.s.get(self.i + k).copied()
    }

    fn skip_ws(&mut self) {
        loop {
            match self.peek() {
                Some(b' ' | b'\t' | b'\n' | b'\r') => self.i += 1,
                Some(b'/') if self.peek_at(1) == Some(b'/') => {
                    while let Some(c) = self.peek() {
                        self.i += 1;
                        if c == b'\n' {
                            break;
                        }
                    }
                }
                Some(b'/') if self.peek_at(1) == Some(b'*') => {
                    // RON block comments nest.
                    self.i += 2;
                    let mut level = 1;
                    while level > 0 && self.i < self.s.len() {
                        if self.peek() == Some(b'/') && self.peek_at(1) == Some(b'*') {
                            level += 1;
                            self.i += 2;
                        } else if self.peek() == Some(b'*') && self.peek_at(1) == Some(b'/') {
                            level -= 1;
                            self.i += 2;
                        } else {
                            self.i += 1;
                        }
                    }
                }
                _ => return,
            }
        }
    }

    fn skip_balanced_attribute(&mut self) {
        // `#![...]`: skip to the matching `]`.
        let mut level = 0usize;
        while let Some(c) = self.peek() {
            self.i += 1;
            match c {
                b'[' => level += 1,
                b']' => {
                    level = level.saturating_sub(1);
                    if level == 0 {
                        return;
                    }
                }
                _ => {}
            }
        }
    }

    fn is_ident_byte(c: u8) -> bool {
        c.is_ascii_alphanumeric() || c == b'_' || c >= 0x80
    }

    fn value(&mut self) -> Option<Node> {
        if self.depth >= MAX_DEPTH {
            return None;
        }
        self.depth += 1;
        let node = self.value_inner();
        self.depth -= 1;
        node
    }

    fn value_inner(&mut self) -> Option<Node> {
        self.skip_ws();
        let start = self.i;
        let c = self.peek()?;
        match c {
            b'(' => self.group(start, None),
            b'[' => {
                self.i += 1;
                let items = self.items(b']');
                Some(self.node(start, None, Kind::Items(items)))
            }
            b'{' => {
                self.i += 1;
                let mut entries = Vec::new();
                loop {
                    self.skip_ws();
                    match self.peek() {
                        None => break,
                        Some(b'}') => {
                            self.i += 1;
                            break;
                        }
                        Some(b',') => self.i += 1,
                        _ => {
                            let key = self.value()?;
                            self.skip_ws();
                            if self.peek() == Some(b':') {
                                self.i += 1;
                            }
                            let value = self.value()?;
                            entries.push((key, value));
                        }
                    }
                }
                Some(self.node(start, None, Kind::Map(entries)))
            }
            b'"' => {
                self.string_body();
                Some(self.node(start, None, Kind::Atom))
            }
            b'\'' => {
                self.i += 1;
                while let Some(c) = self.peek() {
                    self.i += 1;
                    match c {
                        b'\\' => self.i += 1,
                        b'\'' => break,
                        _ => {}
                    }
                }
                Some(self.node(start, None, Kind::Atom))
            }
            b'r' if matches!(self.peek_at(1), Some(b'"' | b'#')) && self.raw_string_ahead() => {
                self.raw_string();
                Some(self.node(start, None, Kind::Atom))
            }
            b'b' if self.peek_at(1) == Some(b'"') => {
                self.i += 1;
                self.string_body();
                Some(self.node(start, None, Kind::Atom))
            }
            c if c == b'-' || c == b'+' || c == b'.' || c.is_ascii_digit() => {
                while let Some(c) = self.peek() {
                    if Self::is_ident_byte(c) || matches!(c, b'.' | b'+' | b'-') {
                        self.i += 1;
                    } else {
                        break;
                    }
                }
                Some(self.node(start, None, Kind::Atom))
            }
            c if Self::is_ident_byte(c) => {
                if c == b'r' && self.peek_at(1) == Some(b'#') {
                    self.i += 2;
                }
                let name_start = self.i;
                while self.peek().is_some_and(Self::is_ident_byte) {
                    self.i += 1;
                }
                let name = String::from_utf8_lossy(&self.s[name_start..self.i]).into_owned();
                let after_name = self.i;
                self.skip_ws();
                if self.peek() == Some(b'(') {
                    self.group(start, Some(name))
                } else {
                    self.i = after_name;
                    Some(self.node(start, Some(name), Kind::Atom))
                }
            }
            _ => None,
        }
    }

    fn node(&self, start: usize, name: Option<String>, kind: Kind) -> Node {
        Node {
            span: Span::new(start, self.i.min(self.s.len())),
            name,
            kind,
        }
    }

    /// `( … )` after an optional name: named fields or plain items.
    fn group(&mut self, start: usize, name: Option<String>) -> Option<Node> {
        self.i += 1; // `(`
        self.skip_ws();
        if self.field_ahead() {
            let mut fields = Vec::new();
            loop {
                self.skip_ws();
                match self.peek() {
                    None => break,
                    Some(b')') => {
                        self.i += 1;
                        break;
                    }
                    Some(b',') => self.i += 1,
                    Some(c) if Self::is_ident_byte(c) => {
                        if c == b'r' && self.peek_at(1) == Some(b'#') {
                            self.i += 2;
                        }
                        let name_start = self.i;
                        while self.peek().is_some_and(Self::is_ident_byte) {
                            self.i += 1;
                        }
                        let name_span = Span::new(name_start, self.i);
                        let field =
                            String::from_utf8_lossy(&self.s[name_start..self.i]).into_owned();
                        self.skip_ws();
                        if self.peek() != Some(b':') {
                            return Some(self.node(start, name, Kind::Fields(fields)));
                        }
                        self.i += 1;
                        let Some(value) = self.value() else {
                            return Some(self.node(start, name, Kind::Fields(fields)));
                        };
                        fields.push(Field {
                            name: field,
                            name_span,
                            value,
                        });
                    }
                    Some(_) => return Some(self.node(start, name, Kind::Fields(fields))),
                }
            }
            Some(self.node(start, name, Kind::Fields(fields)))
        } else {
            let items = self.items(b')');
            Some(self.node(start, name, Kind::Items(items)))
        }
    }

    /// Is the next token `ident :` (and not `ident ::`)?
    fn field_ahead(&self) -> bool {
        let mut k = self.i;
        if self.s.get(k) == Some(&b'r') && self.s.get(k + 1) == Some(&b'#') {
            k += 2;
        }
        let ident_start = k;
        while self.s.get(k).copied().is_some_and(Self::is_ident_byte) {
            k += 1;
        }
        if k == ident_start || self.s.get(ident_start).is_some_and(u8::is_ascii_digit) {
            return false;
        }
        while matches!(self.s.get(k), Some(b' ' | b'\t' | b'\n' | b'\r')) {
            k += 1;
        }
        self.s.get(k) == Some(&b':') && self.s.get(k + 1) != Some(&b':')
    }

    fn items(&mut self, close: u8) -> Vec<Node> {
        let mut items = Vec::new();
        loop {
            self.skip_ws();
            match self.peek() {
                None => break,
                Some(c) if c == close => {
                    self.i += 1;
                    break;
                }
                Some(b',') => self.i += 1,
                _ => match self.value() {
                    Some(v) => items.push(v),
                    None => break,
                },
            }
        }
        items
    }

    fn string_body(&mut self) {
        self.i += 1; // opening quote
        while let Some(c) = self.peek() {
            self.i += 1;
            match c {
                b'\\' => self.i += 1,
                b'"' => break,
                _ => {}
            }
        }
        self.i = self.i.min(self.s.len());
    }

    fn raw_string_ahead(&self) -> bool {
        let mut k = self.i + 1;
        while self.s.get(k) == Some(&b'#') {
            k += 1;
        }
        self.s.get(k) == Some(&b'"')
    }

    fn raw_string(&mut self) {
        self.i += 1; // `r`
        let mut hashes = 0;
        while self.peek() == Some(b'#') {
            hashes += 1;
            self.i += 1;
        }
        self.i += 1; // opening quote
        while let Some(c) = self.peek() {
            self.i += 1;
            if c == b'"' && (0..hashes).all(|k| self.peek_at(k) == Some(b'#')) {
                self.i += hashes;
                break;
            }
        }
        self.i = self.i.min(self.s.len());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"// header
#![enable(implicit_some)]
Model(
    name: "m", /* a /* nested */ comment */
    bodies: [
        (name: "a", com: (0, "-l/2", 0)),
        Body(name: "b", inertia: Diag(1, 2, 3)),
    ],
    gravity: Some((0, 0, -9.81)),
    parameters: { "k": 1 },
)
"#;

    fn text_at(path: &[Seg<'_>]) -> &'static str {
        let root = parse(TEXT).expect("parses");
        let span = root.span_of(path);
        &TEXT[span.start..span.end]
    }

    #[test]
    fn finds_values_by_path() {
        use Seg::*;
        assert_eq!(text_at(&[Field("name")]), "\"m\"");
        assert_eq!(
            text_at(&[Field("bodies"), Index(0), Field("name")]),
            "\"a\""
        );
        assert_eq!(
            text_at(&[Field("bodies"), Index(0), Field("com"), Index(1)]),
            "\"-l/2\""
        );
        assert_eq!(
            text_at(&[Field("bodies"), Index(1), Field("inertia"), Index(2)]),
            "3"
        );
        // `Some(...)` is transparent.
        assert_eq!(text_at(&[Field("gravity"), Index(2)]), "-9.81");
    }

    #[test]
    fn missing_paths_fall_back_to_the_nearest_ancestor() {
        use Seg::*;
        assert_eq!(
            text_at(&[Field("bodies"), Index(1), Field("mass")]),
            r#"Body(name: "b", inertia: Diag(1, 2, 3))"#
        );
        let root = parse(TEXT).expect("parses");
        let (_, matched) = root.find(&[Field("bodies"), Index(7)]);
        assert_eq!(matched, 1);
    }

    #[test]
    fn field_names_have_spans() {
        use Seg::*;
        let root = parse(TEXT).expect("parses");
        let span = root.field_name_span(&[Field("bodies"), Index(1), Field("inertia")]);
        assert_eq!(&TEXT[span.start..span.end], "inertia");
    }

    #[test]
    fn string_contents_start_skips_quotes() {
        let text = r##"x: r#"ab"#, y: "cd""##;
        assert_eq!(string_contents_start(text, Span::new(3, 10)), 6);
        assert_eq!(string_contents_start(text, Span::new(15, 19)), 16);
    }

    #[test]
    fn deep_nesting_and_garbage_do_not_panic() {
        let deep = "[".repeat(100_000);
        assert!(parse(&deep).is_some());
        for text in [
            "",
            ")",
            "(a: ",
            "r#",
            "\"unterminated",
            "(a: 1, b",
            "{ 1: }",
            "'x",
        ] {
            let _ = parse(text);
        }
    }
}
