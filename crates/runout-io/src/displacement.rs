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

use crate::table::{self, Column, Table};
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
    let (t, mut rdr) = table::open(input.into(), b',')?;
    let time = t
        .unit_column("time", Quantity::TimeS)?
        .ok_or_else(|| t.missing("`time_<unit>` (e.g. time_s)"))?;
    let disp: Vec<Column> = t
        .lower
        .iter()
        .enumerate()
        .filter_map(|(index, h)| {
            let rest = h.strip_prefix("disp_")?;
            let (name, unit) = rest.rsplit_once('_').unwrap_or((rest, ""));
            Some((index, h, name.to_string(), unit.to_string()))
        })
        .map(|(index, h, _name, unit)| {
            let factor = Quantity::LengthMm.unit_factor(&unit).ok_or_else(|| t.header_error(format!(
                    "column `{}`: expected `disp_<name>_<unit>` with a length unit (um, mm), got unit `{}`",
                    crate::textfile::quote(h),
                    crate::textfile::quote(&unit)
                )))?;
            Ok(Column { index, name: h.clone(), factor })
        })
        .collect::<Result<_, TableError>>()?;
    if disp.is_empty() {
        return Err(
            t.missing("`disp_<name>_<unit>` (e.g. disp_a_um): at least one displacement channel")
        );
    }
    let pulse_col = t.column("pulse");
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
    while let Some((line, rec)) = table::next_record(&t, &mut records)? {
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
            return Err(t.row_error(
                line,
                format!(
                    "more than {} samples in the selected section: select a shorter one (--from-s/--to-s, s); a few revolutions suffice",
                    section.max_samples
                ),
            ));
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
        return Err(LocatedError::new(&t.file, 0, "no data rows"));
    }
    if times.is_empty() {
        return Err(LocatedError::new(
            &t.file,
            0,
            format!(
                "no sample in the selected section [{}, {}] s; the signal's times run from {} s \
                 to {}{} s: choose --from-s/--to-s (s) inside them",
                section.from_s.map_or("start".into(), |v| v.to_string()),
                section.to_s.map_or("end".into(), |v| v.to_string()),
                span.map_or(0.0, |s| s.0),
                if stopped_early { "at least " } else { "" },
                span.map_or(0.0, |s| s.1),
            ),
        ));
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
    lines: &[usize],
) -> Result<f64, TableError> {
    let n = times.len();
    if n < 2 {
        return Err(LocatedError::new(
            &t.file,
            0,
            "a signal needs at least 2 samples",
        ));
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
