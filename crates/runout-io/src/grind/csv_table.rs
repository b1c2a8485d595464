//! The grind tables (probe points, edge lines) on the shared table reader (`runout_io::table`):
//! only the known columns are accepted, every value is a finite number, and every error is the
//! shared [`LocatedError`] naming the file, the line and the column.

use crate::table::{self, Column};
use crate::LocatedError;

/// A grind CSV problem with its position: the shared [`LocatedError`]
/// (`file[:line[:column]]: message`).
pub type CsvError = LocatedError;

/// A parsed grind table.
pub(crate) struct Table {
    t: table::Table,
    /// (line number) per data row.
    pub rows: Vec<(usize,)>,
}

impl Table {
    pub fn parse(text: &str, file: &str, known: &[&str]) -> Result<Table, CsvError> {
        let t = table::parse_text(file, text, false)?;
        let mut seen: Vec<&str> = Vec::new();
        for n in &t.lower {
            if !known.contains(&n.as_str()) {
                return Err(CsvError::new(
                    file,
                    t.header_line,
                    format!(
                        "unknown column `{}` (expected some of: {})",
                        crate::textfile::quote(n),
                        known.join(", ")
                    ),
                ));
            }
            if seen.contains(&n.as_str()) {
                return Err(CsvError::new(
                    file,
                    t.header_line,
                    format!("column `{}` appears twice", crate::textfile::quote(n)),
                ));
            }
            seen.push(n);
        }
        if t.rows.is_empty() {
            return Err(CsvError::new(file, 0, "no data rows"));
        }
        let rows = t.rows.iter().map(|r| (r.0,)).collect();
        Ok(Table { t, rows })
    }

    fn column(&self, name: &str) -> Option<Column> {
        self.t.column(name)
    }

    pub fn has(&self, name: &str) -> bool {
        self.t.has(name)
    }

    /// Value of column `name` in row `r`, required.
    pub fn get(&self, r: usize, name: &str) -> Result<f64, CsvError> {
        match self.column(name) {
            Some(c) => self.t.number(r, &c),
            None => Err(self.err(Some(self.rows[r].0), format!("no column `{name}`"))),
        }
    }

    /// Value of column `name` in row `r` if the column exists and the cell is filled.
    pub fn opt(&self, r: usize, name: &str) -> Result<Option<f64>, CsvError> {
        self.t.optional(r, self.column(name).as_ref())
    }

    pub fn err(&self, line: Option<usize>, message: String) -> CsvError {
        CsvError::new(&self.t.file, line.unwrap_or(0), message)
    }
}
