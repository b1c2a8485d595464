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

fn read_table(path: &Path) -> Result<Table, TableError> {
    let file = path.display().to_string();
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .flexible(false)
        .from_path(path)
        .map_err(|e| TableError::File {
            file: file.clone(),
            message: e.to_string(),
        })?;
    let headers: Vec<String> = rdr
        .headers()
        .map_err(|e| TableError::Header {
            file: file.clone(),
            message: e.to_string(),
        })?
        .iter()
        .map(|h| h.trim().to_ascii_lowercase())
        .collect();
    let mut rows = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line());
            TableError::Row {
                file: file.clone(),
                line,
                message: e.to_string(),
            }
        })?;
        let line = rec.position().map_or(0, |p| p.line());
        rows.push((line, rec));
    }
    if rows.is_empty() {
        return Err(TableError::File {
            file,
            message: "no data rows".into(),
        });
    }
    Ok(Table {
        file,
        headers,
        rows,
    })
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
                    "column `{h}`: unit `{unit}` is not a unit of {q} (e.g. `{base}_{}`)",
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
                self.headers.join(", ")
            ),
        }
    }

    /// Cell `col` of row `r` as a finite number times the column's unit factor.
    fn number(&self, r: usize, col: &Column) -> Result<f64, TableError> {
        let (line, rec) = &self.rows[r];
        let text = rec.get(col.index).unwrap_or("");
        let v: f64 = text
            .parse()
            .map_err(|_| self.cell_error(*line, col, format!("`{text}` is not a number")))?;
        if !v.is_finite() {
            return Err(self.cell_error(*line, col, format!("`{text}` is not a finite number")));
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
pub fn read_tooth_table(path: &Path, teeth: usize) -> Result<ToothTable, TableError> {
    let t = read_table(path)?;
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
pub fn read_height_table(path: &Path) -> Result<Vec<HeightRow>, TableError> {
    let t = read_table(path)?;
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

/// Read a raw signal: `time_<s|ms>`, `disp_<name>_<unit>` columns, optional `pulse` or
/// `encoder_<deg|rad>`. The time step must be constant (every sample within ¼ step of the grid).
pub fn read_signal(path: &Path) -> Result<SignalTable, TableError> {
    let t = read_table(path)?;
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
                message: format!("column `{h}`: expected `disp_<name>_<unit>` with a length unit (um, mm), got unit `{unit}`"),
            })?;
            Ok(Column { index, name: name.clone(), factor }).map(|c: Column| Column { name: h.clone(), ..c })
        })
        .collect::<Result<_, TableError>>()?;
    if disp.is_empty() {
        return Err(
            t.missing("`disp_<name>_<unit>` (e.g. disp_a_um): at least one displacement channel")
        );
    }
    let n = t.rows.len();
    let times: Vec<f64> = (0..n)
        .map(|r| t.number(r, &time))
        .collect::<Result<_, _>>()?;
    let sample_rate_hz = check_time_grid(&t, &time, &times)?;
    let channels = disp
        .iter()
        .map(|c| {
            let v = (0..n)
                .map(|r| t.number(r, c))
                .collect::<Result<Vec<f64>, _>>()?;
            let name = c
                .name
                .trim_start_matches("disp_")
                .rsplit_once('_')
                .map_or(c.name.clone(), |x| x.0.to_string());
            Ok((name, v))
        })
        .collect::<Result<_, TableError>>()?;
    let pulse = t
        .plain_column("pulse")
        .map(|c| {
            (0..n)
                .map(|r| t.number(r, &c))
                .collect::<Result<Vec<f64>, _>>()
        })
        .transpose()?;
    let encoder_rad = t
        .unit_column("encoder", Quantity::AngleDeg)?
        .map(|c| {
            (0..n)
                .map(|r| t.number(r, &c).map(f64::to_radians))
                .collect::<Result<Vec<f64>, _>>()
        })
        .transpose()?;
    Ok(SignalTable {
        sample_rate_hz,
        start_s: times[0],
        channels,
        pulse,
        encoder_rad,
    })
}

fn check_time_grid(t: &Table, col: &Column, times: &[f64]) -> Result<f64, TableError> {
    let n = times.len();
    if n < 2 {
        return Err(TableError::File {
            file: t.file.clone(),
            message: "a signal needs at least 2 samples".into(),
        });
    }
    let dt = (times[n - 1] - times[0]) / (n - 1) as f64;
    if dt.is_nan() || dt <= 0.0 {
        return Err(t.cell_error(t.rows[n - 1].0, col, "time does not increase".into()));
    }
    for (i, &ti) in times.iter().enumerate() {
        if (ti - times[0] - i as f64 * dt).abs() > 0.25 * dt {
            return Err(t.cell_error(
                t.rows[i].0,
                col,
                format!(
                    "time {ti} s is off the constant-rate grid (step {dt:.6e} s): samples must be evenly spaced without gaps"
                ),
            ));
        }
    }
    Ok(1.0 / dt)
}
