//! Markdown tables of the evaluations' reports.

use std::fmt::Write;

/// How a column's cells are aligned: the delimiter row writes `---` for
/// [`Align::Left`] (the default) and `---:` for [`Align::Right`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Align {
    /// `---`: text, the default.
    #[default]
    Left,
    /// `---:`: numbers.
    Right,
}

/// A Markdown table: a header row, the delimiter row and the body rows.
/// Cells are written as given (a `|` inside a cell is escaped).
#[derive(Debug, Clone, Default)]
pub struct Table {
    header: Vec<String>,
    align: Vec<Align>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column names.
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Self {
        Table {
            header: header.into_iter().map(Into::into).collect(),
            align: Vec::new(),
            rows: Vec::new(),
        }
    }

    /// Sets the columns' alignments, first column first; a column without
    /// one is [`Align::Left`].
    pub fn align(mut self, align: impl IntoIterator<Item = Align>) -> Self {
        self.align = align.into_iter().collect();
        self
    }

    /// Adds a column named `name` with alignment `align` after the present
    /// ones (for headers built in a loop).
    pub fn column(&mut self, name: impl Into<String>, align: Align) -> &mut Self {
        self.align.resize(self.header.len(), Align::Left);
        self.header.push(name.into());
        self.align.push(align);
        self
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
        for i in 0..width {
            out.push_str(match self.align.get(i).copied().unwrap_or_default() {
                Align::Left => "---|",
                Align::Right => "---:|",
            });
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

    #[test]
    fn right_aligned_columns_end_with_a_colon() {
        let mut t = Table::new(["name", "n"]).align([Align::Left, Align::Right]);
        t.row(["a", "1"]);
        assert_eq!(t.markdown(), "| name | n |\n|---|---:|\n| a | 1 |\n");
        let mut t = Table::new(["name"]);
        t.column("n", Align::Right).column("note", Align::Left);
        t.row(["a", "1", "x"]);
        assert_eq!(
            t.markdown(),
            "| name | n | note |\n|---|---:|---|\n| a | 1 | x |\n"
        );
    }
}
