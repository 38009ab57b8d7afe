//! Diagnostics: every problem in a model, each with `file:line:col`, the
//! offending name in backticks, and a `help:` line saying what would be right.
//!
//! Positions are byte ranges into the model source; they are turned into
//! 1-based line and column numbers (columns count characters, as `ron` and
//! rustc do) only when a diagnostic is rendered.
//!
//! A leaf module below the whole pipeline: the parser and validator
//! ([`crate::model`]) report with it, the validated [`crate::System`]
//! keeps a [`Span`] for each of its named entities, and errors found while
//! formulating ([`crate::mech`]) become [`Diagnostic`]s at those spans.

use std::fmt;

/// A byte range `start..end` into a model source.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Span {
    /// First byte.
    pub start: usize,
    /// One past the last byte.
    pub end: usize,
}

impl Span {
    /// The range `start..end`.
    pub fn new(start: usize, end: usize) -> Self {
        Span {
            start,
            end: end.max(start),
        }
    }
}

/// How bad a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    /// The model is rejected.
    Error,
    /// The model is accepted, but something looks wrong.
    Warning,
}

/// One problem found in a model.
#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    /// Error or warning.
    pub severity: Severity,
    /// Where in the source; `None` only for problems with the file itself.
    pub span: Option<Span>,
    /// What is wrong, naming the offending item in backticks.
    pub message: String,
    /// What would be right.
    pub help: Option<String>,
}

impl Diagnostic {
    /// An error at `span`.
    pub fn error(span: Span, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Error,
            span: Some(span),
            message: message.into(),
            help: None,
        }
    }

    /// A warning at `span`.
    pub fn warning(span: Span, message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(span, message)
        }
    }

    /// An error without a position (unreadable file and the like).
    pub fn file_error(message: impl Into<String>) -> Self {
        Diagnostic {
            severity: Severity::Error,
            span: None,
            message: message.into(),
            help: None,
        }
    }

    /// Adds the `help:` line.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// True for errors (as opposed to warnings).
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// A model file's name (as the user gave it) and its text.
#[derive(Clone, Debug)]
pub struct Source {
    /// The path exactly as given on the command line or to the API.
    pub path: String,
    /// The whole text.
    pub text: String,
}

/// A 1-based line and character column.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LineCol {
    /// Line, from 1.
    pub line: usize,
    /// Column in characters, from 1.
    pub col: usize,
}

impl Source {
    /// A source from its path and text.
    pub fn new(path: impl Into<String>, text: impl Into<String>) -> Self {
        Source {
            path: path.into(),
            text: text.into(),
        }
    }

    /// Line and column of byte `offset` (clamped to the text, and to a
    /// character boundary).
    pub fn line_col(&self, offset: usize) -> LineCol {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &self.text[..offset];
        let line = 1 + before.bytes().filter(|&b| b == b'\n').count();
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let col = 1 + before[line_start..].chars().count();
        LineCol { line, col }
    }

    /// Byte offset of a 1-based line and character column (as `ron`
    /// reports them); clamped to the text.
    pub fn offset_of(&self, line: usize, col: usize) -> usize {
        let mut offset = 0;
        for _ in 1..line {
            match self.text[offset..].find('\n') {
                Some(i) => offset += i + 1,
                None => return self.text.len(),
            }
        }
        let rest = &self.text[offset..];
        let line_end = rest.find('\n').unwrap_or(rest.len());
        let in_line = rest[..line_end]
            .char_indices()
            .nth(col.saturating_sub(1))
            .map_or(line_end, |(i, _)| i);
        offset + in_line
    }

    /// Renders one diagnostic, rustc style: a `path:line:col: error: …`
    /// first line, the source line with a caret underline, and `help:`.
    pub fn render(&self, d: &Diagnostic) -> String {
        let kind = match d.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        let mut out = String::new();
        match d.span {
            Some(span) => {
                let lc = self.line_col(span.start);
                out += &format!(
                    "{}:{}:{}: {kind}: {}\n",
                    self.path, lc.line, lc.col, d.message
                );
                out += &self.snippet(span, lc);
            }
            None => out += &format!("{}: {kind}: {}\n", self.path, d.message),
        }
        if let Some(help) = &d.help {
            out += &format!("  = help: {help}\n");
        }
        out
    }

    /// Renders every diagnostic, in source order.
    pub fn render_all(&self, diags: &[Diagnostic]) -> String {
        diags.iter().map(|d| self.render(d)).collect()
    }

    fn snippet(&self, span: Span, lc: LineCol) -> String {
        let line_text = self.text.lines().nth(lc.line - 1).unwrap_or("");
        let width = lc.line.to_string().len();
        let start_col = lc.col - 1;
        let line_chars = line_text.chars().count();
        // Underline up to the end of the span or of the line, at least one caret.
        let end = self.line_col(span.end);
        let end_col = if end.line == lc.line {
            end.col - 1
        } else {
            line_chars
        };
        let carets = end_col.saturating_sub(start_col).max(1);
        format!(
            "{pad} |\n{line} | {line_text}\n{pad} | {spaces}{marks}\n",
            pad = " ".repeat(width),
            line = lc.line,
            spaces = " ".repeat(start_col),
            marks = "^".repeat(carets),
        )
    }
}

/// All diagnostics of a failed stage, with the source they point into.
#[derive(Clone, Debug)]
pub struct Report {
    /// The model source.
    pub source: Source,
    /// Every problem, sorted by position.
    pub diagnostics: Vec<Diagnostic>,
}

impl Report {
    /// True if any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.source.render_all(&self.diagnostics))
    }
}

impl std::error::Error for Report {}

/// The closest of `candidates` to `name`, if it is close enough to be a
/// plausible typo: at most one edit per three characters, counting a swap
/// of neighbours as one edit and ignoring case (so names of one or two
/// characters are matched only up to case).
pub fn did_you_mean<'a>(
    name: &str,
    candidates: impl IntoIterator<Item = &'a str>,
) -> Option<&'a str> {
    let limit = name.chars().count() / 3;
    let lower = name.to_lowercase();
    candidates
        .into_iter()
        .filter(|c| *c != name)
        .map(|c| (edit_distance(&lower, &c.to_lowercase()), c))
        .filter(|&(d, _)| d <= limit)
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// Edit distance over characters with adjacent transpositions (optimal
/// string alignment): insertions, deletions, substitutions and swaps of
/// neighbours each cost 1.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let w = b.len() + 1;
    let mut d = vec![0usize; (a.len() + 1) * w];
    for i in 0..=a.len() {
        d[i * w] = i;
    }
    for (j, cell) in d.iter_mut().enumerate().take(w) {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[(i - 1) * w + j] + 1)
                .min(d[i * w + j - 1] + 1)
                .min(d[(i - 1) * w + j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[(i - 2) * w + j - 2] + 1);
            }
            d[i * w + j] = best;
        }
    }
    d[a.len() * w + b.len()]
}

/// `` `a`, `b`, `c` `` — a list of names for help messages.
pub fn list_names<'a>(names: impl IntoIterator<Item = &'a str>) -> String {
    let names: Vec<String> = names.into_iter().map(|n| format!("`{n}`")).collect();
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_characters_from_one() {
        let s = Source::new("m.ron", "ab\nçd\n");
        assert_eq!(s.line_col(0), LineCol { line: 1, col: 1 });
        assert_eq!(s.line_col(3), LineCol { line: 2, col: 1 });
        // `ç` is two bytes: the `d` after it is column 2.
        assert_eq!(s.line_col(5), LineCol { line: 2, col: 2 });
        // Inside a multi-byte character: clamped back to its start.
        assert_eq!(s.line_col(4), LineCol { line: 2, col: 1 });
        assert_eq!(s.line_col(999), LineCol { line: 3, col: 1 });
    }

    #[test]
    fn offset_of_inverts_line_col() {
        let s = Source::new("m.ron", "ab\nçd\nxyz");
        for off in [0, 1, 3, 5, 6, 8] {
            let lc = s.line_col(off);
            assert_eq!(s.offset_of(lc.line, lc.col), off, "offset {off}");
        }
    }

    #[test]
    fn render_points_at_the_span() {
        let s = Source::new("m.ron", "(\n  mass: -1,\n)\n");
        let d = Diagnostic::error(Span::new(10, 12), "mass of `b` is -1")
            .with_help("use a positive mass");
        let want = "m.ron:2:9: error: mass of `b` is -1\n  |\n2 |   mass: -1,\n  |         ^^\n  = help: use a positive mass\n";
        assert_eq!(s.render(&d), want);
    }

    #[test]
    fn did_you_mean_finds_typos_only() {
        assert_eq!(
            did_you_mean("lnk1", ["link1", "link2", "ground"]),
            Some("link1")
        );
        assert_eq!(did_you_mean("zzzzz", ["link1", "ground"]), None);
        assert_eq!(
            did_you_mean("cmo", ["name", "com", "mass"]),
            Some("com"),
            "a swap is one edit"
        );
        assert_eq!(
            did_you_mean("L", ["g", "l"]),
            Some("l"),
            "short names match up to case"
        );
        assert_eq!(
            did_you_mean("t", ["g", "l"]),
            None,
            "short names are not guessed"
        );
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("ab", "ba"), 1);
    }
}
