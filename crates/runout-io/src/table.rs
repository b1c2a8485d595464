//! The one reader of small delimited text tables (displacement readings and heights, raw
//! displacement signals, grind probe and edge tables, peak tables): `#` comment lines, a header row
//! whose names (trimmed, case-insensitive) find the columns — with the unit as the last
//! `_`-separated part of a name (`reading_um`, `z_mm`, converted at the boundary, `conventions.md`)
//! — and every error a [`LocatedError`] naming the file, the line and, for a cell, the column
//! (`file:line:column: message`).

use crate::located::LocatedError;
use crate::units::Quantity;
use std::path::Path;

/// Where a table comes from: a file, or bytes from any reader with a name for messages and
/// their size if known.
pub enum TableInput<'a> {
    /// A file.
    Path(&'a Path),
    /// A reader (bytes in memory, a network stream), named `name` in messages.
    Reader {
        /// Name used in messages, as a file's path would be.
        name: &'a str,
        /// The bytes.
        reader: Box<dyn std::io::Read + 'a>,
        /// Size in bytes, if known (checked against the table limit before reading).
        len: Option<u64>,
    },
}

impl<'a> From<&'a Path> for TableInput<'a> {
    fn from(p: &'a Path) -> Self {
        TableInput::Path(p)
    }
}

impl<'a> From<&'a std::path::PathBuf> for TableInput<'a> {
    fn from(p: &'a std::path::PathBuf) -> Self {
        TableInput::Path(p)
    }
}

/// One column found in the header, with the factor from its unit to the canonical one
/// (1 for a column without unit).
#[derive(Debug, Clone)]
pub(crate) struct Column {
    /// 0-based field index.
    pub index: usize,
    /// Header name (lower case).
    pub name: String,
    /// Factor from the column's unit to the canonical unit.
    pub factor: f64,
}

/// A parsed table: the header names (as written, trimmed; matched case-insensitively) and the
/// rows with their 1-based line numbers.
pub(crate) struct Table {
    pub file: String,
    pub headers: Vec<String>,
    /// The header names in lower case, for matching.
    pub lower: Vec<String>,
    /// Cells may use a decimal comma (the separator is not a comma).
    decimal_comma: bool,
    /// 1-based line of the header row (0 when unknown: a streamed input).
    pub header_line: usize,
    pub rows: Vec<(usize, csv::StringRecord)>,
}

pub(crate) type CsvReader<'a> = csv::Reader<Box<dyn std::io::Read + 'a>>;

/// The separator of a text table: the most frequent of tab, `;` and `,` in its header row.
pub(crate) fn detect_delimiter(text: &str) -> u8 {
    let header = text
        .lines()
        .find(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .unwrap_or("");
    [b'\t', b';', b',']
        .into_iter()
        .max_by_key(|d| header.bytes().filter(|b| b == d).count())
        .unwrap_or(b',')
}

/// A CSV reader's error without its position (the caller names the line), with what to do.
fn csv_problem(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::Io(e) => format!("cannot read: {}", crate::report::io_problem(e)),
        csv::ErrorKind::Utf8 { .. } => {
            "not UTF-8 text (a binary file, or another encoding: save it as UTF-8)".into()
        }
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => format!(
            "{len} fields, expected {expected_len} as in the header (a missing or extra separator)"
        ),
        _ => e.to_string(),
    }
}

/// Open a table: the header and the record reader positioned after it.
pub(crate) fn open(
    input: TableInput<'_>,
    delimiter: u8,
) -> Result<(Table, CsvReader<'_>), LocatedError> {
    let (file, reader): (String, Box<dyn std::io::Read + '_>) = match input {
        TableInput::Path(path) => {
            let file = path.display().to_string();
            let unreadable = |e: &std::io::Error| {
                LocatedError::new(
                    &file,
                    0,
                    format!("cannot read: {}", crate::report::io_problem(e)),
                )
            };
            let f = std::fs::File::open(path).map_err(|e| unreadable(&e))?;
            if f.metadata().map_err(|e| unreadable(&e))?.is_dir() {
                return Err(LocatedError::new(
                    file,
                    0,
                    "is a folder: expected a CSV file",
                ));
            }
            (file, Box::new(f))
        }
        TableInput::Reader { name, reader, .. } => (name.to_string(), reader),
    };
    let mut rdr = csv::ReaderBuilder::new()
        .delimiter(delimiter)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(false)
        .from_reader(reader);
    let headers: Vec<String> = rdr
        .headers()
        .map_err(|e| match e.kind() {
            csv::ErrorKind::Io(_) => LocatedError::new(&file, 0, csv_problem(&e)),
            _ => LocatedError::new(
                &file,
                e.position().map_or(1, |p| p.line() as usize),
                format!("header: {}", csv_problem(&e)),
            ),
        })?
        .iter()
        .map(|h| h.trim().to_string())
        .collect();
    let table = Table {
        file,
        lower: headers.iter().map(|h| h.to_ascii_lowercase()).collect(),
        headers,
        decimal_comma: delimiter != b',',
        header_line: 0,
        rows: Vec::new(),
    };
    Ok((table, rdr))
}

/// The next record and its 1-based line number, with a row error naming the line.
pub(crate) fn next_record<R: std::io::Read>(
    t: &Table,
    records: &mut csv::StringRecordsIter<'_, R>,
) -> Result<Option<(usize, csv::StringRecord)>, LocatedError> {
    match records.next() {
        None => Ok(None),
        Some(Err(e)) => Err(LocatedError::new(
            &t.file,
            e.position().map_or(0, |p| p.line() as usize),
            csv_problem(&e),
        )),
        Some(Ok(rec)) => Ok(Some((rec.position().map_or(0, |p| p.line() as usize), rec))),
    }
}

/// A whole (small, ≤ `MAX_TABLE_BYTES`) table in memory, with at least one data row.
pub(crate) fn read(input: TableInput<'_>, delimiter: u8) -> Result<Table, LocatedError> {
    let t = read_all(input, delimiter)?;
    if t.rows.is_empty() {
        return Err(LocatedError::new(t.file, 0, "no data rows"));
    }
    Ok(t)
}

/// A whole (small, ≤ `MAX_TABLE_BYTES`) table in memory, possibly without rows.
fn read_all(input: TableInput<'_>, delimiter: u8) -> Result<Table, LocatedError> {
    let max = runout_core::limits::MAX_TABLE_BYTES;
    let (name, len) = match &input {
        TableInput::Path(path) => (
            path.display().to_string(),
            std::fs::metadata(path)
                .ok()
                .filter(|m| m.is_file())
                .map(|m| m.len()),
        ),
        TableInput::Reader { name, len, .. } => (name.to_string(), *len),
    };
    if let Some(len) = len.filter(|&l| l > max) {
        return Err(LocatedError::new(
            name,
            0,
            format!("{len} bytes: larger than the {max} bytes a table may have"),
        ));
    }
    let (mut t, mut rdr) = open(input, delimiter)?;
    let mut records = rdr.records();
    while let Some(row) = next_record(&t, &mut records)? {
        t.rows.push(row);
    }
    Ok(t)
}

/// A table from text already read, possibly without data rows (the caller checks the header
/// first). The separator is the most frequent of tab, `;` and `,` in the header row; with none
/// of them, `whitespace` allows fields separated by runs of spaces.
pub(crate) fn parse_text(file: &str, text: &str, whitespace: bool) -> Result<Table, LocatedError> {
    let header_line = text
        .lines()
        .position(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let header = header_line.map_or("", |i| text.lines().nth(i).unwrap_or(""));
    let spaced;
    let (text, delimiter) = if whitespace && !header.contains([',', ';', '\t']) {
        // one tab between the fields of each line (comments and line count kept)
        spaced = text
            .lines()
            .map(|l| {
                if l.trim_start().starts_with('#') {
                    l.to_string()
                } else {
                    l.split_whitespace().collect::<Vec<_>>().join("\t")
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        (spaced.as_str(), b'\t')
    } else {
        (text, detect_delimiter(text))
    };
    let input = TableInput::Reader {
        name: file,
        reader: Box::new(text.as_bytes()),
        len: Some(text.len() as u64),
    };
    let mut t = read_all(input, delimiter)?;
    // the reader's position of the header does not count the comment lines before it
    t.header_line = header_line.map_or(1, |i| i + 1);
    Ok(t)
}

impl Table {
    /// The column named `base_<unit>` with a unit of quantity `q` (factor to q's canonical unit).
    pub fn unit_column(&self, base: &str, q: Quantity) -> Result<Option<Column>, LocatedError> {
        let prefix = format!("{base}_");
        for (index, h) in self.lower.iter().enumerate() {
            let Some(unit) = h.strip_prefix(&prefix) else {
                continue;
            };
            if unit.contains('_') {
                continue;
            }
            let factor = q.unit_factor(unit).ok_or_else(|| {
                self.header_error(format!(
                    "column `{}`: unit `{}` is not a unit of {q} (e.g. `{base}_{}`)",
                    crate::textfile::quote(h),
                    crate::textfile::quote(unit),
                    q.unit().replace('µ', "u")
                ))
            })?;
            return Ok(Some(Column {
                index,
                name: self.headers[index].clone(),
                factor,
            }));
        }
        Ok(None)
    }

    /// The column named `name` (case-insensitive), without unit.
    pub fn column(&self, name: &str) -> Option<Column> {
        self.lower
            .iter()
            .position(|h| h.eq_ignore_ascii_case(name))
            .map(|index| Column {
                index,
                name: self.headers[index].clone(),
                factor: 1.0,
            })
    }

    /// True when the header has a column `name`.
    pub fn has(&self, name: &str) -> bool {
        self.column(name).is_some()
    }

    /// A problem with the header as a whole: `file[:header line]: header: message`.
    pub fn header_error(&self, message: String) -> LocatedError {
        LocatedError::new(&self.file, self.header_line, format!("header: {message}"))
    }

    /// A required column is missing: names what was expected and what the header has.
    pub fn missing(&self, what: &str) -> LocatedError {
        self.header_error(format!(
            "no column {what}; the header has {}",
            crate::textfile::quote(&self.headers.join(", "))
        ))
    }

    /// The text of cell `col` of row `r` (`""` when the row is short).
    pub fn text(&self, r: usize, col: &Column) -> &str {
        self.rows[r].1.get(col.index).unwrap_or("")
    }

    /// Cell `col` of row `r` as a finite number times the column's unit factor.
    pub fn number(&self, r: usize, col: &Column) -> Result<f64, LocatedError> {
        let (line, rec) = &self.rows[r];
        self.cell(*line, rec, col)
    }

    /// Cell `col` of row `r` as a number, `None` when the column is absent or the cell empty.
    pub fn optional(&self, r: usize, col: Option<&Column>) -> Result<Option<f64>, LocatedError> {
        match col {
            Some(c) if !self.text(r, c).is_empty() => self.number(r, c).map(Some),
            _ => Ok(None),
        }
    }

    /// Cell `col` of record `rec` (at `line`) as a finite number times the column's unit factor
    /// (a decimal comma is accepted when the separator is not a comma).
    pub fn cell(
        &self,
        line: usize,
        rec: &csv::StringRecord,
        col: &Column,
    ) -> Result<f64, LocatedError> {
        let text = rec.get(col.index).unwrap_or("");
        let at =
            |message: String| LocatedError::new(&self.file, line, message).at_column(col.index + 1);
        if text.is_empty() {
            return Err(at(format!(
                "column `{}` is empty: expected a number",
                col.name
            )));
        }
        let parsed = if self.decimal_comma {
            text.replace(',', ".").parse::<f64>()
        } else {
            text.parse::<f64>()
        };
        let quoted = crate::textfile::quote(text);
        let v = parsed.map_err(|_| {
            at(format!(
                "`{quoted}` in column `{}` is not a number",
                col.name
            ))
        })?;
        if !(v * col.factor).is_finite() {
            return Err(at(format!(
                "`{quoted}` in column `{}` is not finite (expected a finite number)",
                col.name
            )));
        }
        Ok(v * col.factor)
    }

    /// Any other problem with one cell: `file:line:column: column `name`: message`.
    pub fn cell_error(&self, line: usize, col: &Column, message: String) -> LocatedError {
        LocatedError::new(
            &self.file,
            line,
            format!("column `{}`: {message}", crate::textfile::quote(&col.name)),
        )
        .at_column(col.index + 1)
    }
}
