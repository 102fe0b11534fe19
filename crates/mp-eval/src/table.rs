//! Markdown tables of the evaluations' reports.

use std::fmt::Write;

/// A Markdown table: a header row, the delimiter row and the body rows.
/// Cells are written as given (a `|` inside a cell is escaped).
#[derive(Debug, Clone, Default)]
pub struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column names.
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Self {
        Table {
            header: header.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    /// Adds a row; a row shorter than the header is padded with empty
    /// cells, a longer one keeps its cells (the header grows empty names).
    pub fn row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) -> &mut Self {
        self.rows.push(cells.into_iter().map(Into::into).collect());
        self
    }

    /// The number of body rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether the table has no body row.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The table as Markdown, one line per row, ending with a newline.
    pub fn markdown(&self) -> String {
        let width = self
            .rows
            .iter()
            .map(Vec::len)
            .chain([self.header.len()])
            .max()
            .unwrap_or(0);
        let mut out = String::new();
        let line = |out: &mut String, cells: &[String]| {
            out.push('|');
            for i in 0..width {
                let cell = cells.get(i).map(String::as_str).unwrap_or("");
                let _ = write!(out, " {} |", cell.replace('|', "\\|"));
            }
            out.push('\n');
        };
        line(&mut out, &self.header);
        out.push('|');
        for _ in 0..width {
            out.push_str("---|");
        }
        out.push('\n');
        for r in &self.rows {
            line(&mut out, r);
        }
        out
    }
}

impl std::fmt::Display for Table {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.markdown())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_delimiter_and_rows() {
        let mut t = Table::new(["video", "count"]);
        t.row(["a|b", "3"]).row(["c"]);
        assert_eq!(
            t.markdown(),
            "| video | count |\n|---|---|\n| a\\|b | 3 |\n| c |  |\n"
        );
        assert_eq!(t.len(), 2);
    }

    #[test]
    fn an_empty_table_is_a_header() {
        let t = Table::new(["x"]);
        assert!(t.is_empty());
        assert_eq!(t.to_string(), "| x |\n|---|\n");
    }
}
