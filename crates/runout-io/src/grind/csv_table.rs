//! A small numeric CSV table reader: header names (trimmed, case-insensitive), `#` comment lines,
//! every value parsed as f64 with the file line and column named on error.

use std::collections::HashMap;

/// A CSV problem with its position.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}", .line.map(|l| format!(", line {l}")).unwrap_or_default())]
pub struct CsvError {
    /// File name as given.
    pub file: String,
    /// 1-based line, if the problem is in one line.
    pub line: Option<usize>,
    /// What is wrong and what was expected.
    pub message: String,
}

/// Parsed numeric table.
pub(crate) struct Table {
    pub file: String,
    pub index: HashMap<String, usize>,
    /// (line number, values) per data row; empty cells are `None`.
    pub rows: Vec<(usize, Vec<Option<f64>>)>,
}

impl Table {
    pub fn parse(text: &str, file: &str, known: &[&str]) -> Result<Table, CsvError> {
        let err = |line: Option<usize>, message: String| CsvError {
            file: file.into(),
            line,
            message,
        };
        let mut rdr = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let headers = rdr
            .headers()
            .map_err(|e| err(None, format!("cannot read the header: {e}")))?
            .clone();
        // the reader's position of the header does not count the comment lines before it
        let header_line = text
            .lines()
            .position(|l| !l.trim().is_empty() && !l.starts_with('#'))
            .map_or(1, |i| i + 1);
        let names: Vec<String> = headers.iter().map(|h| h.to_ascii_lowercase()).collect();
        let mut index = HashMap::new();
        for (k, n) in names.iter().enumerate() {
            if !known.contains(&n.as_str()) {
                return Err(err(
                    Some(header_line),
                    format!(
                        "unknown column `{}` (expected some of: {})",
                        crate::textfile::quote(n),
                        known.join(", ")
                    ),
                ));
            }
            if index.insert(n.clone(), k).is_some() {
                return Err(err(
                    Some(header_line),
                    format!("column `{n}` appears twice"),
                ));
            }
        }
        let mut rows = Vec::new();
        for rec in rdr.records() {
            let rec = rec.map_err(|e| {
                let line = e.position().map(|p| p.line() as usize);
                err(line, format!("malformed CSV: {e}"))
            })?;
            let line = rec.position().map_or(0, |p| p.line() as usize);
            let mut vals = Vec::with_capacity(rec.len());
            for (k, cell) in rec.iter().enumerate() {
                if cell.is_empty() {
                    vals.push(None);
                    continue;
                }
                let v: f64 = cell
                    .parse()
                    .ok()
                    .filter(|v: &f64| v.is_finite())
                    .ok_or_else(|| {
                        err(
                            Some(line),
                            format!(
                                "column `{}`: `{}` is not a finite number",
                                names[k],
                                crate::textfile::quote(cell)
                            ),
                        )
                    })?;
                vals.push(Some(v));
            }
            rows.push((line, vals));
        }
        if rows.is_empty() {
            return Err(err(None, "no data rows".into()));
        }
        Ok(Table {
            file: file.into(),
            index,
            rows,
        })
    }

    pub fn has(&self, name: &str) -> bool {
        self.index.contains_key(name)
    }

    /// Value of column `name` in row `r`, required.
    pub fn get(&self, r: usize, name: &str) -> Result<f64, CsvError> {
        self.opt(r, name)?.ok_or_else(|| CsvError {
            file: self.file.clone(),
            line: Some(self.rows[r].0),
            message: format!("column `{name}` is empty"),
        })
    }

    /// Value of column `name` in row `r` if the column exists and the cell is filled.
    pub fn opt(&self, r: usize, name: &str) -> Result<Option<f64>, CsvError> {
        Ok(self
            .index
            .get(name)
            .and_then(|&k| self.rows[r].1.get(k).copied().flatten()))
    }

    pub fn err(&self, line: Option<usize>, message: String) -> CsvError {
        CsvError {
            file: self.file.clone(),
            line,
            message,
        }
    }
}
