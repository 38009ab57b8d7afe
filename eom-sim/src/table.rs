//! The one CSV writer of a run: a header of column names and rows of
//! numbers, written the same for every model kind (`t` first, every
//! number in Rust's shortest round-trip form, so a value read back is the
//! value computed).

use std::fmt::Write;

/// Rows of numbers under named columns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Column names (`t` first by convention).
    pub header: Vec<String>,
    /// Rows, each as long as the header.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// An empty table with these columns.
    pub fn new(header: Vec<String>) -> Self {
        Table {
            header,
            rows: Vec::new(),
        }
    }

    /// Appends a row.
    pub fn push(&mut self, row: Vec<f64>) {
        debug_assert_eq!(row.len(), self.header.len());
        self.rows.push(row);
    }

    /// The CSV text: the header, then one line per row.
    pub fn to_csv(&self) -> String {
        let mut text = self.header.join(",");
        text.push('\n');
        for row in &self.rows {
            for (k, x) in row.iter().enumerate() {
                if k > 0 {
                    text.push(',');
                }
                let _ = write!(text, "{x:?}");
            }
            text.push('\n');
        }
        text
    }

    /// Writes [`Table::to_csv`] to `path`.
    pub fn write(&self, path: &str) -> std::io::Result<()> {
        std::fs::write(path, self.to_csv())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_back_exactly() {
        let mut t = Table::new(vec!["t".into(), "x".into()]);
        t.push(vec![0.1, 1.0 / 3.0]);
        t.push(vec![1e-300, f64::NAN]);
        let csv = t.to_csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "t,x");
        let back: Vec<f64> = lines[1]
            .split(',')
            .map(|s| s.parse().unwrap_or(f64::NAN))
            .collect();
        assert_eq!(back, vec![0.1, 1.0 / 3.0]);
        assert_eq!(lines[2], "1e-300,NaN");
    }
}
