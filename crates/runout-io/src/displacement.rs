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

pub use signal::{
    read_signal, read_signal_with, SignalError, SignalOptions, SignalSection, SignalTable,
};

use crate::table::{self, Table};
use crate::units::Quantity;
use crate::LocatedError;
use runout_core::runout::seed::tooth_from_seed000_edge;

pub use crate::table::TableInput;

/// A problem reading a displacement table: the shared [`LocatedError`] (`file[:line[:column]]:
/// message`; header problems say `header:`, cell problems name the column).
pub type TableError = LocatedError;

fn read_table(input: TableInput<'_>) -> Result<Table, TableError> {
    table::read(input, b',')
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
    let (tooth_col, seed) = match (t.column("tooth"), t.column("seed_edge")) {
        (Some(c), None) => (c, false),
        (None, Some(c)) => (c, true),
        (Some(_), Some(_)) => {
            return Err(
                t.header_error("both `tooth` and `seed_edge` columns: give one numbering".into())
            )
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
                format!(
                    "`{}` is not a tooth number (integer)",
                    crate::textfile::quote(text)
                ),
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
            return Err(t.header_error("both `tir_*` and `runout_*` columns: give one".into()))
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
