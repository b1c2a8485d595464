//! CSV tables for the displacement methods (methods.md §1): per-tooth readings, runout at several
//! heights, and raw displacement signals. Columns are found by name (case-insensitive), the unit is
//! the last `_`-separated part of the name and is converted to mm / rad / s here, at the boundary
//! (`conventions.md`). Lines starting with `#` are comments. Every error names the file, the line
//! and the column.
//!
//! | table | columns |
//! |---|---|
//! | teeth | `tooth` (0-based, cutting order) or `seed_edge` (1-based, seed 000 numbering), `reading_<um\|mm\|nm>` |
//! | heights | `z_<mm\|um>`, `tir_<unit>` (total indicated runout) or `runout_<unit>` (= TIR/2), optional `angle_<deg\|rad>` (direction of the runout) |
//! | signal | `time_<s\|ms>`, one or more `disp_<name>_<unit>`, optional `pulse` (once per revolution) or `encoder_<deg\|rad>`; any recording format (CSV, .mat, TDMS, HDF5, Parquet), see [`read_signal_with`] |

mod signal;

pub use signal::{read_signal, read_signal_with, SignalOptions, SignalSection, SignalTable};

use crate::units::Quantity;
use runout_core::runout::seed::tooth_from_seed000_edge;
use std::path::Path;
use thiserror::Error;

/// A problem reading a displacement table.
#[derive(Debug, Error)]
pub enum TableError {
    /// The file could not be read.
    #[error("{file}: {message}")]
    File {
        /// File name.
        file: String,
        /// What happened.
        message: String,
    },
    /// A required column is missing or a header is malformed.
    #[error("{file}: header: {message}")]
    Header {
        /// File name.
        file: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A cell could not be read.
    #[error("{file}:{line}: column `{column}`: {message}")]
    Cell {
        /// File name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// Column name.
        column: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A row-level problem (wrong number of fields, irregular time step…).
    #[error("{file}:{line}: {message}")]
    Row {
        /// File name.
        file: String,
        /// 1-based line number.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// A problem at a sample of a binary recording (no lines).
    #[error("{file}: sample {sample} (0-based): {message}")]
    Sample {
        /// File name.
        file: String,
        /// 0-based sample index.
        sample: u64,
        /// What is wrong.
        message: String,
    },
    /// The recording reader's error (a signal is read through [`crate::recording`]).
    #[error(transparent)]
    Recording(Box<crate::recording::RecordingError>),
}

/// One column located in the header, with the factor from its unit to the canonical one.
#[derive(Debug, Clone)]
struct Column {
    index: usize,
    name: String,
    factor: f64,
}

/// A parsed CSV file: header names and rows with their line numbers.
struct Table {
    file: String,
    headers: Vec<String>,
    rows: Vec<(u64, csv::StringRecord)>,
}

/// Open a CSV table: the header (lower-cased names) and the record reader positioned after it.
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

type CsvReader<'a> = csv::Reader<Box<dyn std::io::Read + 'a>>;

fn open_table(input: TableInput<'_>) -> Result<(Table, CsvReader<'_>), TableError> {
    let (file, reader): (String, Box<dyn std::io::Read + '_>) = match input {
        TableInput::Path(path) => {
            let file = path.display().to_string();
            let unreadable = |e: &std::io::Error| TableError::File {
                file: file.clone(),
                message: format!("cannot read: {}", crate::report::io_problem(e)),
            };
            let f = std::fs::File::open(path).map_err(|e| unreadable(&e))?;
            if f.metadata().map_err(|e| unreadable(&e))?.is_dir() {
                return Err(TableError::File {
                    file,
                    message: "is a folder: expected a CSV file".into(),
                });
            }
            (file, Box::new(f))
        }
        TableInput::Reader { name, reader, .. } => (name.to_string(), reader),
    };
    let unreadable = |e: &std::io::Error| TableError::File {
        file: file.clone(),
        message: format!("cannot read: {}", crate::report::io_problem(e)),
    };
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(false)
        .from_reader(reader);
    let headers: Vec<String> = rdr
        .headers()
        .map_err(|e| match e.kind() {
            csv::ErrorKind::Io(e) => unreadable(e),
            _ => TableError::Row {
                file: file.clone(),
                line: e.position().map_or(1, |p| p.line()),
                message: format!("header: {}", csv_problem(&e)),
            },
        })?
        .iter()
        .map(|h| h.trim().to_ascii_lowercase())
        .collect();
    let table = Table {
        file,
        headers,
        rows: Vec::new(),
    };
    Ok((table, rdr))
}

/// The next record and its 1-based line number, with a row error naming the line.
fn next_record<R: std::io::Read>(
    t: &Table,
    records: &mut csv::StringRecordsIter<'_, R>,
) -> Result<Option<(u64, csv::StringRecord)>, TableError> {
    match records.next() {
        None => Ok(None),
        Some(Err(e)) => Err(match e.position() {
            Some(p) => TableError::Row {
                file: t.file.clone(),
                line: p.line(),
                message: csv_problem(&e),
            },
            None => TableError::File {
                file: t.file.clone(),
                message: csv_problem(&e),
            },
        }),
        Some(Ok(rec)) => Ok(Some((rec.position().map_or(0, |p| p.line()), rec))),
    }
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

/// A whole (small) table in memory.
fn read_table(input: TableInput<'_>) -> Result<Table, TableError> {
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
        return Err(TableError::File {
            file: name,
            message: format!(
                "{len} bytes: larger than the {max} bytes a table may have (limit MAX_TABLE_BYTES)"
            ),
        });
    }
    let (mut t, mut rdr) = open_table(input)?;
    let mut records = rdr.records();
    while let Some(row) = next_record(&t, &mut records)? {
        t.rows.push(row);
    }
    if t.rows.is_empty() {
        return Err(TableError::File {
            file: t.file,
            message: "no data rows".into(),
        });
    }
    Ok(t)
}

impl Table {
    /// The column named `base_<unit>` with a unit of quantity `q` (factor to q's canonical unit).
    fn unit_column(&self, base: &str, q: Quantity) -> Result<Option<Column>, TableError> {
        let prefix = format!("{base}_");
        for (index, h) in self.headers.iter().enumerate() {
            let Some(unit) = h.strip_prefix(&prefix) else {
                continue;
            };
            if unit.contains('_') {
                continue;
            }
            let factor = q.unit_factor(unit).ok_or_else(|| TableError::Header {
                file: self.file.clone(),
                message: format!(
                    "column `{}`: unit `{}` is not a unit of {q} (e.g. `{base}_{}`)",
                    crate::textfile::quote(h),
                    crate::textfile::quote(unit),
                    q.unit().replace('µ', "u")
                ),
            })?;
            return Ok(Some(Column {
                index,
                name: h.clone(),
                factor,
            }));
        }
        Ok(None)
    }

    fn plain_column(&self, name: &str) -> Option<Column> {
        self.headers
            .iter()
            .position(|h| h == name)
            .map(|index| Column {
                index,
                name: name.into(),
                factor: 1.0,
            })
    }

    fn missing(&self, what: &str) -> TableError {
        TableError::Header {
            file: self.file.clone(),
            message: format!(
                "no column {what}; the header has {}",
                crate::textfile::quote(&self.headers.join(", "))
            ),
        }
    }

    /// Cell `col` of row `r` as a finite number times the column's unit factor.
    fn number(&self, r: usize, col: &Column) -> Result<f64, TableError> {
        let (line, rec) = &self.rows[r];
        self.cell(*line, rec, col)
    }

    /// Cell `col` of record `rec` (at `line`) as a finite number times the column's unit factor.
    fn cell(&self, line: u64, rec: &csv::StringRecord, col: &Column) -> Result<f64, TableError> {
        let text = rec.get(col.index).unwrap_or("");
        let quoted = || crate::textfile::quote(text);
        let v: f64 = text
            .parse()
            .map_err(|_| self.cell_error(line, col, format!("`{}` is not a number", quoted())))?;
        if !(v * col.factor).is_finite() {
            return Err(self.cell_error(
                line,
                col,
                format!("`{}` is not a finite number", quoted()),
            ));
        }
        Ok(v * col.factor)
    }

    fn cell_error(&self, line: u64, col: &Column, message: String) -> TableError {
        TableError::Cell {
            file: self.file.clone(),
            line,
            column: col.name.clone(),
            message,
        }
    }
}

/// Per-tooth readings: `(tooth, reading_mm)` with teeth in our numbering (0-based, cutting order).
#[derive(Debug, Clone, PartialEq)]
pub struct ToothTable {
    /// `(tooth, reading in mm)` pairs in file order.
    pub readings: Vec<(usize, f64)>,
    /// True when the file used the seed's `seed_edge` numbering (converted).
    pub from_seed_edges: bool,
}

/// Read a per-tooth readings table (`tooth,reading_um` or `seed_edge,reading_um`). `teeth` (K) is
/// needed to map seed edges and to check tooth numbers.
pub fn read_tooth_table<'a>(
    input: impl Into<TableInput<'a>>,
    teeth: usize,
) -> Result<ToothTable, TableError> {
    let t = read_table(input.into())?;
    let reading = t
        .unit_column("reading", Quantity::LengthMm)?
        .ok_or_else(|| t.missing("`reading_<unit>` (e.g. reading_um)"))?;
    let (tooth_col, seed) = match (t.plain_column("tooth"), t.plain_column("seed_edge")) {
        (Some(c), None) => (c, false),
        (None, Some(c)) => (c, true),
        (Some(_), Some(_)) => {
            return Err(TableError::Header {
                file: t.file.clone(),
                message: "both `tooth` and `seed_edge` columns: give one numbering".into(),
            })
        }
        (None, None) => {
            return Err(t.missing("`tooth` (0-based, cutting order) or `seed_edge` (1-based)"))
        }
    };
    let mut readings = Vec::with_capacity(t.rows.len());
    for r in 0..t.rows.len() {
        let (line, rec) = &t.rows[r];
        let text = rec.get(tooth_col.index).unwrap_or("");
        let n: usize = text.parse().map_err(|_| {
            t.cell_error(
                *line,
                &tooth_col,
                format!("`{text}` is not a tooth number (integer)"),
            )
        })?;
        let tooth = if seed {
            tooth_from_seed000_edge(n, teeth).ok_or_else(|| {
                t.cell_error(
                    *line,
                    &tooth_col,
                    format!("seed edge {n} is not in 1..={teeth}"),
                )
            })?
        } else if n < teeth {
            n
        } else {
            return Err(t.cell_error(
                *line,
                &tooth_col,
                format!("tooth {n} is not in 0..{teeth} (teeth are 0-based)"),
            ));
        };
        readings.push((tooth, t.number(r, &reading)?));
    }
    Ok(ToothTable {
        readings,
        from_seed_edges: seed,
    })
}

/// One row of a multi-height table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightRow {
    /// Height z (mm).
    pub z_mm: f64,
    /// Runout r(z) = TIR/2 (mm), seed eq. (5).
    pub runout_mm: f64,
    /// Direction of the runout (rad, spindle frame), when the table has an angle column.
    pub angle_rad: Option<f64>,
}

/// Read a multi-height table: `z_mm` and `tir_<unit>` or `runout_<unit>`, optional `angle_<unit>`.
pub fn read_height_table<'a>(
    input: impl Into<TableInput<'a>>,
) -> Result<Vec<HeightRow>, TableError> {
    let t = read_table(input.into())?;
    let z = t
        .unit_column("z", Quantity::LengthMm)?
        .ok_or_else(|| t.missing("`z_<unit>` (e.g. z_mm)"))?;
    let (value, half) = match (
        t.unit_column("tir", Quantity::LengthMm)?,
        t.unit_column("runout", Quantity::LengthMm)?,
    ) {
        (Some(c), None) => (c, 0.5),
        (None, Some(c)) => (c, 1.0),
        (Some(_), Some(_)) => {
            return Err(TableError::Header {
                file: t.file.clone(),
                message: "both `tir_*` and `runout_*` columns: give one".into(),
            })
        }
        (None, None) => {
            return Err(
                t.missing("`tir_<unit>` (total indicated runout) or `runout_<unit>` (= TIR/2)")
            )
        }
    };
    let angle = t.unit_column("angle", Quantity::AngleDeg)?;
    (0..t.rows.len())
        .map(|r| {
            let v = t.number(r, &value)?;
            if v < 0.0 {
                return Err(t.cell_error(
                    t.rows[r].0,
                    &value,
                    format!("{v} is negative; runout and TIR are ≥ 0"),
                ));
            }
            Ok(HeightRow {
                z_mm: t.number(r, &z)?,
                runout_mm: v * half,
                angle_rad: angle
                    .as_ref()
                    .map(|a| t.number(r, a).map(f64::to_radians))
                    .transpose()?,
            })
        })
        .collect()
}
