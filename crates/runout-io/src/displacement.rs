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
//! | signal | `time_<s\|ms>`, one or more `disp_<name>_<unit>`, optional `pulse` (once per revolution) or `encoder_<deg\|rad>` |

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

/// A raw displacement recording at a constant sample rate.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalTable {
    /// Sample rate (Hz) from the time column.
    pub sample_rate_hz: f64,
    /// Time of the first sample (s).
    pub start_s: f64,
    /// Displacement channels: (name, samples in mm), in header order.
    pub channels: Vec<(String, Vec<f64>)>,
    /// Once-per-revolution channel, if present (raw levels).
    pub pulse: Option<Vec<f64>>,
    /// Encoder angle (rad), if present.
    pub encoder_rad: Option<Vec<f64>>,
}

/// Which part of a raw signal to keep, and how much at most (memory stays bounded: samples
/// outside the section are parsed and dropped, never stored).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignalSection {
    /// Keep samples at t ≥ `from_s` (s); `None` = from the start.
    pub from_s: Option<f64>,
    /// Keep samples at t ≤ `to_s` (s); `None` = to the end.
    pub to_s: Option<f64>,
    /// Largest number of samples kept; more is an error that asks for a shorter section.
    pub max_samples: usize,
}

impl SignalSection {
    /// Default cap: 20 M samples (400 s at 50 kHz; ≈ 32 B per sample with two channels).
    pub const MAX_SAMPLES: usize = 20_000_000;
}

impl Default for SignalSection {
    fn default() -> Self {
        SignalSection {
            from_s: None,
            to_s: None,
            max_samples: Self::MAX_SAMPLES,
        }
    }
}

/// Read a raw signal: `time_<s|ms>`, `disp_<name>_<unit>` columns, optional `pulse` or
/// `encoder_<deg|rad>`, keeping the samples of `section` (parsed straight into numbers, one
/// record at a time). The time step must be constant (every kept sample within ¼ step of the
/// grid).
///
/// ```
/// use runout_io::displacement::{read_signal, SignalSection};
/// let dir = tempfile::tempdir().unwrap();
/// let p = dir.path().join("s.csv");
/// let rows: String = (0..100).map(|i| format!("{},{}\n", i as f64 * 1e-3, i)).collect();
/// std::fs::write(&p, format!("time_s,disp_a_um\n{rows}")).unwrap();
/// let section = SignalSection { from_s: Some(0.0105), to_s: Some(0.0195), ..Default::default() };
/// let t = read_signal(&p, &section).unwrap();
/// assert_eq!(t.channels[0].1.len(), 9); // 11 ms … 19 ms
/// assert!((t.start_s - 0.011).abs() < 1e-12);
/// assert!((t.sample_rate_hz - 1000.0).abs() < 1e-6);
/// ```
pub fn read_signal<'a>(
    input: impl Into<TableInput<'a>>,
    section: &SignalSection,
) -> Result<SignalTable, TableError> {
    let (t, mut rdr) = open_table(input.into())?;
    let time = t
        .unit_column("time", Quantity::TimeS)?
        .ok_or_else(|| t.missing("`time_<unit>` (e.g. time_s)"))?;
    let disp: Vec<Column> = t
        .headers
        .iter()
        .enumerate()
        .filter_map(|(index, h)| {
            let rest = h.strip_prefix("disp_")?;
            let (name, unit) = rest.rsplit_once('_').unwrap_or((rest, ""));
            Some((index, h, name.to_string(), unit.to_string()))
        })
        .map(|(index, h, name, unit)| {
            let factor = Quantity::LengthMm.unit_factor(&unit).ok_or_else(|| TableError::Header {
                file: t.file.clone(),
                message: format!(
                    "column `{}`: expected `disp_<name>_<unit>` with a length unit (um, mm), got unit `{}`",
                    crate::textfile::quote(h),
                    crate::textfile::quote(&unit)
                ),
            })?;
            Ok(Column { index, name: name.clone(), factor }).map(|c: Column| Column { name: h.clone(), ..c })
        })
        .collect::<Result<_, TableError>>()?;
    if disp.is_empty() {
        return Err(
            t.missing("`disp_<name>_<unit>` (e.g. disp_a_um): at least one displacement channel")
        );
    }
    let pulse_col = t.plain_column("pulse");
    let encoder_col = t.unit_column("encoder", Quantity::AngleDeg)?;
    let from = section.from_s.unwrap_or(f64::NEG_INFINITY);
    let to = section.to_s.unwrap_or(f64::INFINITY);
    let mut times = Vec::new();
    let mut lines = Vec::new();
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); disp.len()];
    let mut pulse = pulse_col.as_ref().map(|_| Vec::new());
    let mut encoder = encoder_col.as_ref().map(|_| Vec::new());
    let mut rows = 0usize;
    let mut span: Option<(f64, f64)> = None; // first and last time read
    let mut stopped_early = false;
    let mut records = rdr.records();
    while let Some((line, rec)) = next_record(&t, &mut records)? {
        rows += 1;
        let ti = t.cell(line, &rec, &time)?;
        span = Some((span.map_or(ti, |s| s.0), ti));
        if ti < from {
            continue;
        }
        if ti > to {
            stopped_early = true;
            break;
        }
        if times.len() == section.max_samples {
            return Err(TableError::Row {
                file: t.file.clone(),
                line,
                message: format!(
                    "more than {} samples in the selected section: select a shorter one (--from-s/--to-s, s); a few revolutions suffice",
                    section.max_samples
                ),
            });
        }
        times.push(ti);
        lines.push(line);
        for (c, v) in disp.iter().zip(values.iter_mut()) {
            v.push(t.cell(line, &rec, c)?);
        }
        if let (Some(c), Some(p)) = (&pulse_col, pulse.as_mut()) {
            p.push(t.cell(line, &rec, c)?);
        }
        if let (Some(c), Some(e)) = (&encoder_col, encoder.as_mut()) {
            e.push(t.cell(line, &rec, c)?.to_radians());
        }
    }
    if rows == 0 {
        return Err(TableError::File {
            file: t.file.clone(),
            message: "no data rows".into(),
        });
    }
    if times.is_empty() {
        return Err(TableError::File {
            file: t.file.clone(),
            message: format!(
                "no sample in the selected section [{}, {}] s; the signal's times run from {} s \
                 to {}{} s: choose --from-s/--to-s (s) inside them",
                section.from_s.map_or("start".into(), |v| v.to_string()),
                section.to_s.map_or("end".into(), |v| v.to_string()),
                span.map_or(0.0, |s| s.0),
                if stopped_early { "at least " } else { "" },
                span.map_or(0.0, |s| s.1),
            ),
        });
    }
    let sample_rate_hz = check_time_grid(&t, &time, &times, &lines)?;
    let channels = disp
        .iter()
        .zip(values)
        .map(|(c, v)| {
            let name = c
                .name
                .trim_start_matches("disp_")
                .rsplit_once('_')
                .map_or(c.name.clone(), |x| x.0.to_string());
            (name, v)
        })
        .collect();
    Ok(SignalTable {
        sample_rate_hz,
        start_s: times[0],
        channels,
        pulse,
        encoder_rad: encoder,
    })
}

fn check_time_grid(
    t: &Table,
    col: &Column,
    times: &[f64],
    lines: &[u64],
) -> Result<f64, TableError> {
    let n = times.len();
    if n < 2 {
        return Err(TableError::File {
            file: t.file.clone(),
            message: "a signal needs at least 2 samples".into(),
        });
    }
    let dt = (times[n - 1] - times[0]) / (n - 1) as f64;
    if dt.is_nan() || dt <= 0.0 {
        return Err(t.cell_error(lines[n - 1], col, "time does not increase".into()));
    }
    for i in 1..n {
        if times[i] <= times[i - 1] {
            return Err(t.cell_error(
                lines[i],
                col,
                format!(
                    "time does not increase ({} s after {} s on line {})",
                    times[i],
                    times[i - 1],
                    lines[i - 1]
                ),
            ));
        }
    }
    // a gap or a jump first shows as one step far from the typical step (the median of at most
    // 4096 steps spread over the signal): name that line rather than where the accumulated
    // drift leaves the grid
    let stride = ((n - 1) / 4096).max(1);
    let mut sample: Vec<f64> = (1..n)
        .step_by(stride)
        .map(|i| times[i] - times[i - 1])
        .collect();
    sample.sort_by(f64::total_cmp);
    let typical = sample[sample.len() / 2];
    for i in 1..n {
        let step = times[i] - times[i - 1];
        if (step - typical).abs() > 0.5 * typical {
            return Err(t.cell_error(
                lines[i],
                col,
                format!(
                    "time step {step:.6e} s from the previous sample (line {}) differs from the typical step {typical:.6e} s: samples must be evenly spaced without gaps (not on a constant-rate grid)",
                    lines[i - 1]
                ),
            ));
        }
    }
    for (i, &ti) in times.iter().enumerate() {
        if (ti - times[0] - i as f64 * dt).abs() > 0.25 * dt {
            return Err(t.cell_error(
                lines[i],
                col,
                format!(
                    "time {ti} s is off the constant-rate grid (step {dt:.6e} s): samples must be evenly spaced without gaps"
                ),
            ));
        }
    }
    Ok(1.0 / dt)
}
