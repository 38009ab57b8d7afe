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

    /// Reads the text [`Table::to_csv`] writes: a header of names, then
    /// rows of numbers (`NaN` and `inf` allowed). A row of the wrong length
    /// or a field that is not a number is an error naming its line and
    /// column.
    pub fn from_csv(text: &str) -> Result<Table, String> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let Some((_, first)) = lines.next() else {
            return Err("the file is empty: expected a header line of column names".into());
        };
        let header: Vec<String> = first.split(',').map(|h| h.trim().to_string()).collect();
        if let Some(k) = header.iter().position(String::is_empty) {
            return Err(format!("line 1: column {} has no name", k + 1));
        }
        let mut table = Table::new(header);
        for (k, line) in lines {
            let row: Vec<f64> = line
                .split(',')
                .enumerate()
                .map(|(c, x)| {
                    x.trim().parse::<f64>().map_err(|_| {
                        format!(
                            "line {}: column `{}`: `{}` is not a number",
                            k + 1,
                            table.header.get(c).map_or("?", String::as_str),
                            x.trim()
                        )
                    })
                })
                .collect::<Result<_, _>>()?;
            if row.len() != table.header.len() {
                return Err(format!(
                    "line {}: {} value(s) under a header of {} column(s)",
                    k + 1,
                    row.len(),
                    table.header.len()
                ));
            }
            table.rows.push(row);
        }
        Ok(table)
    }

    /// The values of the column `name`, if there is one.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.header.iter().position(|h| h == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
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
        let read = Table::from_csv(&csv).unwrap_or_default();
        assert_eq!(read.header, t.header);
        assert_eq!(read.rows[0], t.rows[0]);
        assert!(read.rows[1][1].is_nan());
    }

    #[test]
    fn malformed_csv_names_line_and_column() {
        let e = Table::from_csv("t,x\n0,1\n0.1,abc\n")
            .err()
            .unwrap_or_default();
        assert_eq!(e, "line 3: column `x`: `abc` is not a number");
        let e = Table::from_csv("t,x\n0,1,2\n").err().unwrap_or_default();
        assert_eq!(e, "line 2: 3 value(s) under a header of 2 column(s)");
        assert!(Table::from_csv("").is_err());
    }
}
