//! Raw displacement signals for `displacement signal`: a thin layer on the generic streaming
//! recording reader ([`crate::recording`], [`crate::formats`]), so the signal is read from every
//! recording format — CSV/TSV text, MATLAB `.mat` v5 / v7.3, NI TDMS, HDF5, Parquet. This layer only names the roles of the channels, converts units, keeps the
//! selected section and checks the time grid; parsing, format detection and selection
//! (`data.mat:600`) are the recording reader's.
//!
//! Channels are found by name, in every format the same way: `time_<s|ms>`, one or more
//! `disp_<name>_<unit>` (a length unit; in a binary file without the `_<unit>` suffix, the unit
//! the file states), optional `pulse` (once per revolution) or `encoder_<deg|rad>`; or by an
//! explicit mapping `a = NAME [um], b = NAME, pulse = NAME, encoder = NAME [deg]` (like the
//! identify axis mapping). Without a time channel, the time base is the reader's: a named time
//! variable (`--time-var`: sample times, or a scalar sample rate), the file's sample rate, or
//! `--sample-rate-hz`.

use super::TableInput;
use crate::formats::{self, BinaryRecording, Kind};
use crate::recording::{Channel, ReadOptions, RecordingChunk, RecordingError, RecordingReader};
use crate::textfile::quote;
use crate::units::Quantity;
use std::io::{BufRead, BufReader, Read};
use thiserror::Error;

/// A problem reading a displacement signal (any recording format).
#[derive(Debug, Error)]
pub enum SignalError {
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

/// How to find the channels and the time base (all optional: the defaults read a file that
/// follows the naming convention).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SignalOptions {
    /// Channel mapping `a = NAME [um], b = NAME, pulse = NAME, encoder = NAME [deg]`: the
    /// displacement channels in this order under the names before `=`; `pulse` and `encoder` name
    /// the reference channels. The unit in brackets, else the unit the file states for the
    /// channel. `None`: by the naming convention (module documentation).
    pub channels: Option<String>,
    /// Channel / variable holding the sample times (s, or the unit of its `_<unit>` suffix or
    /// header), or in a binary file a scalar sample rate (Hz).
    pub time_var: Option<String>,
    /// Sample rate (Hz): the time base when there is no time channel; with one, the times must
    /// lie on this rate's grid (within ¼ sample).
    pub sample_rate_hz: Option<f64>,
}

/// Read a raw signal following the naming convention: [`read_signal_with`] with default options.
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
) -> Result<SignalTable, SignalError> {
    read_signal_with(input, section, &SignalOptions::default())
}

/// Read a raw signal of any recording format (detected by content; a path may carry a selector,
/// `data.mat:600`), keeping the samples of `section` (read chunk by chunk; samples outside it are
/// dropped). The time step must be constant: every kept sample within ¼ step of the grid, no step
/// more than ½ step from the typical (median) step.
pub fn read_signal_with<'a>(
    input: impl Into<TableInput<'a>>,
    section: &SignalSection,
    options: &SignalOptions,
) -> Result<SignalTable, SignalError> {
    if let Some(f) = options.sample_rate_hz {
        if !(f.is_finite() && f > 0.0) {
            return Err(SignalError::File {
                file: "--sample-rate-hz".into(),
                message: format!("expected a positive number of Hz, got {f}"),
            });
        }
    }
    let mut rows = open(input.into(), options)?;
    let plan = plan(&rows, options)?;
    collect(&mut rows, &plan, section, options)
}

/// The rows of a signal: a text table (with line numbers) or a binary recording.
enum Rows<'a> {
    Text {
        file: String,
        reader: Box<RecordingReader<Box<dyn BufRead + 'a>>>,
    },
    Binary {
        file: String,
        rec: Box<BinaryRecording>,
        /// (alias, header) of every selectable array, for the plan.
        names: Vec<(String, Channel)>,
    },
}

impl Rows<'_> {
    fn file(&self) -> &str {
        match self {
            Rows::Text { file, .. } | Rows::Binary { file, .. } => file,
        }
    }
}

fn recording_error(e: RecordingError) -> SignalError {
    match e {
        RecordingError::Io { file, error } => SignalError::File {
            file,
            message: format!("cannot read: {}", crate::report::io_problem(&error)),
        },
        RecordingError::NoData { file, .. } => SignalError::File {
            file,
            message: "no data rows".into(),
        },
        e => SignalError::Recording(Box::new(e)),
    }
}

/// Open the input: detect the format by content; text as a table (every column delivered,
/// `#` comments, line numbers), binary through [`formats`] with the reader's time base.
fn open<'a>(input: TableInput<'a>, options: &SignalOptions) -> Result<Rows<'a>, SignalError> {
    let (file, kind, head, rest): (String, Kind, Vec<u8>, Box<dyn Read + 'a>) = match input {
        TableInput::Path(path) => {
            let (path, selector) = formats::split_selector(path);
            let file = path.display().to_string();
            let unreadable = |e: &std::io::Error| SignalError::File {
                file: file.clone(),
                message: format!("cannot read: {}", crate::report::io_problem(e)),
            };
            let f = std::fs::File::open(&path).map_err(|e| unreadable(&e))?;
            if f.metadata().map_err(|e| unreadable(&e))?.is_dir() {
                return Err(SignalError::File {
                    file,
                    message: "is a folder: expected a CSV file".into(),
                });
            }
            let kind = formats::detect_file(&path).map_err(|e| unreadable(&e))?;
            if kind != Kind::Text {
                let opened = formats::open_kind(kind, &path, &file).map_err(recording_error)?;
                let bytes = f.metadata().ok().map(|m| m.len());
                return binary(opened, file, selector.as_deref(), options, bytes);
            }
            if let Some(sel) = selector {
                return Err(SignalError::File {
                    file,
                    message: format!("a selector (`:{sel}`) applies to .mat, TDMS, HDF5 and Parquet files, not to text"),
                });
            }
            (file, kind, Vec::new(), Box::new(f))
        }
        TableInput::Reader {
            name, mut reader, ..
        } => {
            // enough bytes to detect the format (an HDF5 userblock puts the signature at 512…)
            let mut head = Vec::new();
            (&mut reader)
                .take(4096)
                .read_to_end(&mut head)
                .map_err(|e| SignalError::File {
                    file: name.into(),
                    message: format!("cannot read: {}", crate::report::io_problem(&e)),
                })?;
            let kind = formats::detect(&head);
            (name.to_string(), kind, head, reader)
        }
    };
    if kind != Kind::Text {
        let mut bytes = head;
        let max = runout_core::limits::MAX_RESULT_BYTES as u64;
        rest.take(max + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| SignalError::File {
                file: file.clone(),
                message: format!("cannot read: {}", crate::report::io_problem(&e)),
            })?;
        if bytes.len() as u64 > max {
            return Err(SignalError::File {
                file,
                message: format!("more than {max} bytes in memory: pass the file by path"),
            });
        }
        let n = bytes.len() as u64;
        let opened = formats::open_bytes(kind, &bytes, &file).map_err(recording_error)?;
        return binary(opened, file, None, options, Some(n));
    }
    let src: Box<dyn BufRead + 'a> = Box::new(BufReader::with_capacity(
        1 << 16,
        std::io::Cursor::new(head).chain(rest),
    ));
    let reader = RecordingReader::table_from_reader(src, &file).map_err(recording_error)?;
    Ok(Rows::Text {
        file,
        reader: Box::new(reader),
    })
}

/// Name the channels of a binary recording from its catalog, then open it with them.
fn binary<'a>(
    opened: formats::Opened,
    file: String,
    selector: Option<&str>,
    options: &SignalOptions,
    bytes: Option<u64>,
) -> Result<Rows<'a>, SignalError> {
    let sel = formats::selectable(&opened.catalog, &file, selector).map_err(recording_error)?;
    let names: Vec<(String, Channel)> = sel
        .iter()
        .enumerate()
        .filter(|(_, (_, i))| opened.catalog.entries[*i].readable)
        .map(|(k, (alias, i))| {
            let e = &opened.catalog.entries[*i];
            (
                alias.clone(),
                Channel {
                    name: alias.clone(),
                    header: e.name.clone(),
                    unit: e.unit.clone(),
                    column: k + 1,
                },
            )
        })
        .collect();
    let columns: Vec<Channel> = names.iter().map(|(_, c)| c.clone()).collect();
    let r = roles(&file, &columns, options, false)?;
    let mut ro = ReadOptions::new();
    ro.sample_rate_hz = options.sample_rate_hz;
    ro.time_column = options.time_var.clone();
    if let Some(t) = &r.time {
        // a `time_<unit>` channel is the time base (converted and checked here, ¼ step, also
        // against --sample-rate-hz): the reader takes it as its time vector, whatever its unit
        ro.time_column = Some(names[t.index].0.clone());
        ro.sample_rate_hz = None;
    }
    ro.channels = Some(r.order.iter().map(|&i| names[i].0.clone()).collect());
    let rec = BinaryRecording::new(opened, &file, selector, &ro, bytes).map_err(recording_error)?;
    Ok(Rows::Binary {
        file,
        rec: Box::new(rec),
        names,
    })
}

/// One channel's role: index in the delivered values, unit factor, names.
#[derive(Debug, Clone)]
struct Role {
    /// Index into the chunk's values.
    index: usize,
    /// Factor to the canonical unit (mm, s, degrees).
    factor: f64,
    /// Header text (lower-cased for text tables, as written for binary arrays) for messages.
    header: String,
    /// Reported name (`a` for `disp_a_um`).
    name: String,
}

/// Roles of the columns; `order` lists the column indices in delivery order for a binary
/// recording (whose chunks hold only the selected arrays).
struct Roles {
    time: Option<Role>,
    disp: Vec<Role>,
    pulse: Option<Role>,
    encoder: Option<Role>,
    order: Vec<usize>,
}

type Plan = Roles;

fn plan(rows: &Rows<'_>, options: &SignalOptions) -> Result<Plan, SignalError> {
    match rows {
        Rows::Text { file, reader } => roles(file, &reader.info().columns, options, true),
        Rows::Binary { file, names, .. } => {
            let columns: Vec<Channel> = names.iter().map(|(_, c)| c.clone()).collect();
            let mut r = roles(file, &columns, options, false)?;
            // the binary chunks hold the selected arrays in `order`
            let pos = |i: usize| r.order.iter().position(|&o| o == i).unwrap_or(0);
            for role in r
                .time
                .iter_mut()
                .chain(r.disp.iter_mut())
                .chain(r.pulse.iter_mut())
                .chain(r.encoder.iter_mut())
            {
                role.index = pos(role.index);
            }
            Ok(r)
        }
    }
}

/// Find the roles among `columns` (text: by lower-cased header; binary: by alias, case-insensitive).
fn roles(
    file: &str,
    columns: &[Channel],
    options: &SignalOptions,
    text: bool,
) -> Result<Roles, SignalError> {
    let headers: Vec<String> = columns
        .iter()
        .map(|c| {
            if text {
                c.header.trim().to_ascii_lowercase()
            } else {
                c.name.clone()
            }
        })
        .collect();
    let lower: Vec<String> = headers.iter().map(|h| h.to_ascii_lowercase()).collect();
    let header_err = |message: String| SignalError::Header {
        file: file.into(),
        message,
    };
    let missing = |what: &str| {
        header_err(format!(
            "no column {what}; the {} has {}",
            if text { "header" } else { "file" },
            quote(&headers.join(", "))
        ))
    };
    let role = |index: usize, factor: f64, name: String| Role {
        index,
        factor,
        header: headers[index].clone(),
        name,
    };
    // `base_<unit>` with a unit of `q`
    let unit_column = |base: &str, q: Quantity| -> Result<Option<Role>, SignalError> {
        let prefix = format!("{base}_");
        for (index, h) in lower.iter().enumerate() {
            let Some(unit) = h.strip_prefix(&prefix) else {
                continue;
            };
            if unit.contains('_') {
                continue;
            }
            let unit = &headers[index][prefix.len()..];
            let factor = q.unit_factor(unit).ok_or_else(|| {
                header_err(format!(
                    "column `{}`: unit `{}` is not a unit of {q} (e.g. `{base}_{}`)",
                    quote(&headers[index]),
                    quote(unit),
                    q.unit().replace('µ', "u")
                ))
            })?;
            return Ok(Some(role(index, factor, headers[index].clone())));
        }
        Ok(None)
    };
    // a column named by the user: header / name, exact then case-insensitive
    let find = |name: &str| -> Option<usize> {
        let n = name.trim();
        columns
            .iter()
            .position(|c| c.header == n || c.name == n)
            .or_else(|| {
                columns.iter().position(|c| {
                    c.header.eq_ignore_ascii_case(n)
                        || c.name.eq_ignore_ascii_case(n)
                        || c.header.trim_start_matches('/').eq_ignore_ascii_case(n)
                })
            })
            .or_else(|| {
                let base = crate::recording::header::split_unit(n).0;
                columns
                    .iter()
                    .position(|c| c.name.eq_ignore_ascii_case(&base))
            })
    };
    let named_missing = |what: &str, name: &str| {
        header_err(format!(
            "{what} `{}` not found; the {} has {}",
            quote(name),
            if text { "header" } else { "file" },
            quote(&headers.join(", "))
        ))
    };
    // the unit a column states (unit row, `[unit]`, file attribute), or its `_unit` suffix
    let stated_unit =
        |i: usize| -> Option<String> { columns[i].unit.clone().filter(|u| !u.trim().is_empty()) };
    // time
    let time = match &options.time_var {
        Some(t) if text => {
            let i = find(t).ok_or_else(|| named_missing("time column (--time-var)", t))?;
            let unit = stated_unit(i).or_else(|| {
                lower[i]
                    .rsplit_once('_')
                    .map(|(_, u)| u.to_string())
                    .filter(|u| Quantity::TimeS.unit_factor(u).is_some())
            });
            let factor = Quantity::TimeS
                .unit_factor(unit.as_deref().unwrap_or(""))
                .ok_or_else(|| {
                    header_err(format!(
                        "time column `{}`: unit `{}` is not a unit of time (s, ms)",
                        quote(&headers[i]),
                        quote(unit.as_deref().unwrap_or(""))
                    ))
                })?;
            Some(role(i, factor, headers[i].clone()))
        }
        // a binary file's named time variable is the reader's time base
        Some(_) => None,
        None => unit_column("time", Quantity::TimeS)?,
    };
    if time.is_none() && text && options.sample_rate_hz.is_none() {
        return Err(missing("`time_<unit>` (e.g. time_s)"));
    }
    let mut disp = Vec::new();
    let mut pulse = None;
    let mut encoder = None;
    match &options.channels {
        Some(map) => {
            for item in crate::recording::split_entries(map)
                .into_iter()
                .map(str::trim)
                .filter(|s| !s.is_empty())
            {
                let Some((key, src)) = item.split_once('=') else {
                    return Err(SignalError::File {
                        file: "--channels".into(),
                        message: format!(
                            "`{}`: expected `NAME = CHANNEL [unit]` (e.g. `a = Dx [um], pulse = trig`)",
                            quote(item)
                        ),
                    });
                };
                let key = key.trim();
                // `NAME [unit]`: the unit in brackets after a space (`D[:,1] [mm]` keeps its column)
                let src = src.trim();
                let (src, unit) = match src.rfind(" [").filter(|_| src.ends_with(']')) {
                    Some(p) => (
                        src[..p].trim(),
                        Some(src[p + 2..src.len() - 1].trim().to_string()),
                    ),
                    None => (src, None),
                };
                let i = find(src).ok_or_else(|| named_missing("channel", src))?;
                let unit = unit.or_else(|| stated_unit(i));
                match key.to_ascii_lowercase().as_str() {
                    "pulse" => pulse = Some(role(i, 1.0, "pulse".into())),
                    "encoder" => {
                        let u = unit.unwrap_or_else(|| "deg".into());
                        let f = Quantity::AngleDeg.unit_factor(&u).ok_or_else(|| {
                            header_err(format!(
                                "channel `{}` (encoder): unit `{}` is not an angle (deg, rad)",
                                quote(src),
                                quote(&u)
                            ))
                        })?;
                        encoder = Some(role(i, f, headers[i].clone()));
                    }
                    _ => {
                        let Some(u) = unit else {
                            return Err(header_err(format!(
                                "channel `{}` states no unit: write it in the mapping, `{key} = {src} [um]`",
                                quote(src)
                            )));
                        };
                        let f = Quantity::LengthMm.unit_factor(&u).ok_or_else(|| {
                            header_err(format!(
                                "channel `{}`: expected a length unit (um, mm), got unit `{}`",
                                quote(src),
                                quote(&u)
                            ))
                        })?;
                        disp.push(role(i, f, key.to_string()));
                    }
                }
            }
        }
        None => {
            for (index, h) in lower.iter().enumerate() {
                let Some(rest) = h.strip_prefix("disp_") else {
                    continue;
                };
                let original = &headers[index]["disp_".len()..];
                let (name, unit) = match rest.rsplit_once('_') {
                    Some((n, _)) => (
                        original[..n.len()].to_string(),
                        original[n.len() + 1..].to_string(),
                    ),
                    None => (original.to_string(), String::new()),
                };
                // a binary array may state its unit instead of the suffix
                let unit = if unit.is_empty() && !text {
                    stated_unit(index).unwrap_or_default()
                } else {
                    unit
                };
                let factor = Quantity::LengthMm.unit_factor(&unit).ok_or_else(|| {
                    header_err(format!(
                        "column `{}`: expected `disp_<name>_<unit>` with a length unit (um, mm), got unit `{}`",
                        quote(&headers[index]),
                        quote(&unit)
                    ))
                })?;
                disp.push(role(index, factor, name));
            }
            pulse = lower
                .iter()
                .position(|h| h == "pulse")
                .map(|i| role(i, 1.0, "pulse".into()));
            encoder = unit_column("encoder", Quantity::AngleDeg)?;
        }
    }
    if disp.is_empty() {
        return Err(missing(
            "`disp_<name>_<unit>` (e.g. disp_a_um): at least one displacement channel",
        ));
    }
    let order = time
        .iter()
        .chain(&disp)
        .chain(&pulse)
        .chain(&encoder)
        .map(|r| r.index)
        .collect();
    Ok(Roles {
        time,
        disp,
        pulse,
        encoder,
        order,
    })
}

/// Where a sample is, for messages: a line of a text file, or a sample of a binary array.
#[derive(Debug, Clone, Copy)]
enum At {
    Line(u64),
    Sample(u64),
}

impl std::fmt::Display for At {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            At::Line(l) => write!(f, "line {l}"),
            At::Sample(s) => write!(f, "sample {s}"),
        }
    }
}

fn at_error(file: &str, at: At, column: Option<&str>, message: String) -> SignalError {
    match (at, column) {
        (At::Line(line), Some(c)) => SignalError::Cell {
            file: file.into(),
            line,
            column: c.into(),
            message,
        },
        (At::Line(line), None) => SignalError::Row {
            file: file.into(),
            line,
            message,
        },
        (At::Sample(sample), c) => SignalError::Sample {
            file: file.into(),
            sample,
            message: match c {
                Some(c) => format!("`{}`: {message}", quote(c)),
                None => message,
            },
        },
    }
}

/// Read the rows, keep the section, check the grid.
fn collect(
    rows: &mut Rows<'_>,
    plan: &Plan,
    section: &SignalSection,
    options: &SignalOptions,
) -> Result<SignalTable, SignalError> {
    let file = rows.file().to_string();
    let from = section.from_s.unwrap_or(f64::NEG_INFINITY);
    let to = section.to_s.unwrap_or(f64::INFINITY);
    let mut times = Vec::new();
    let mut ats = Vec::new();
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); plan.disp.len()];
    let mut pulse = plan.pulse.as_ref().map(|_| Vec::new());
    let mut encoder = plan.encoder.as_ref().map(|_| Vec::new());
    let mut n_rows = 0u64;
    let mut span: Option<(f64, f64)> = None; // first and last time read
    let mut stopped_early = false;
    let mut chunk = RecordingChunk::default();
    let fs = options.sample_rate_hz;
    // a finite number times the role's factor
    let cell = |v: f64, at: At, r: &Role| -> Result<f64, SignalError> {
        let x = v * r.factor;
        if !x.is_finite() {
            return Err(at_error(
                &file,
                at,
                Some(&r.header),
                format!("`{v}` is not a finite number"),
            ));
        }
        Ok(x)
    };
    'read: loop {
        let (n, lines): (usize, Vec<u64>) = match rows {
            Rows::Text { reader, .. } => {
                let n = reader
                    .read_chunk(&mut chunk, 65_536)
                    .map_err(recording_error)?;
                (n, reader.chunk_lines().to_vec())
            }
            Rows::Binary { rec, .. } => (
                rec.read_chunk(&mut chunk, 65_536)
                    .map_err(recording_error)?,
                Vec::new(),
            ),
        };
        if n == 0 {
            break;
        }
        for k in 0..n {
            let at = match lines.get(k) {
                Some(&l) => At::Line(l),
                None => At::Sample(chunk.first_sample + k as u64),
            };
            n_rows += 1;
            let ti = match (&plan.time, fs, &rows) {
                (Some(r), _, _) => cell(chunk.values[r.index][k], at, r)?,
                (None, Some(f), Rows::Text { .. }) => (n_rows - 1) as f64 / f,
                (None, _, _) => chunk.time_s[k],
            };
            span = Some((span.map_or(ti, |s| s.0), ti));
            if ti < from {
                continue;
            }
            if ti > to {
                stopped_early = true;
                break 'read;
            }
            if times.len() == section.max_samples {
                return Err(at_error(
                    &file,
                    at,
                    None,
                    format!(
                        "more than {} samples in the selected section: select a shorter one (--from-s/--to-s, s); a few revolutions suffice",
                        section.max_samples
                    ),
                ));
            }
            times.push(ti);
            ats.push(at);
            for (r, v) in plan.disp.iter().zip(values.iter_mut()) {
                v.push(cell(chunk.values[r.index][k], at, r)?);
            }
            if let (Some(r), Some(p)) = (&plan.pulse, pulse.as_mut()) {
                p.push(cell(chunk.values[r.index][k], at, r)?);
            }
            if let (Some(r), Some(e)) = (&plan.encoder, encoder.as_mut()) {
                e.push(cell(chunk.values[r.index][k], at, r)?.to_radians());
            }
        }
    }
    if n_rows == 0 {
        return Err(SignalError::File {
            file,
            message: "no data rows".into(),
        });
    }
    if times.is_empty() {
        return Err(SignalError::File {
            file,
            message: format!(
                "no sample in the selected section [{}, {}] s; the signal's times run from {} s \
                 to {}{} s: choose --from-s/--to-s (s) inside them",
                section
                    .from_s
                    .map_or("start".into(), runout_core::limits::show),
                section.to_s.map_or("end".into(), runout_core::limits::show),
                runout_core::limits::show(span.map_or(0.0, |s| s.0)),
                if stopped_early { "at least " } else { "" },
                runout_core::limits::show(span.map_or(0.0, |s| s.1)),
            ),
        });
    }
    let time_name = plan
        .time
        .as_ref()
        .map(|r| r.header.clone())
        .or_else(|| options.time_var.clone())
        .unwrap_or_else(|| "time".into());
    let sample_rate_hz = check_time_grid(&file, &time_name, &times, &ats)?;
    if let (Some(f), Some(_)) = (fs, &plan.time) {
        // the time channel and the stated rate must describe the same grid (¼ sample)
        for (i, &ti) in times.iter().enumerate() {
            let expected = times[0] + i as f64 / f;
            if (ti - expected).abs() > 0.25 / f {
                return Err(at_error(
                    &file,
                    ats[i],
                    Some(&time_name),
                    format!(
                        "time {ti} s disagrees with --sample-rate-hz {f} Hz (expected {expected} s within ¼ sample; the time channel's rate is {sample_rate_hz} Hz): give one or make them agree"
                    ),
                ));
            }
        }
    }
    let channels = plan
        .disp
        .iter()
        .zip(values)
        .map(|(r, v)| (r.name.clone(), v))
        .collect();
    Ok(SignalTable {
        sample_rate_hz: match (fs, &plan.time) {
            (Some(f), None) if matches!(rows, Rows::Text { .. }) => f,
            _ => sample_rate_hz,
        },
        start_s: times[0],
        channels,
        pulse,
        encoder_rad: encoder,
    })
}

fn check_time_grid(file: &str, col: &str, times: &[f64], ats: &[At]) -> Result<f64, SignalError> {
    let n = times.len();
    let cell_error = |at: At, message: String| at_error(file, at, Some(col), message);
    if n < 2 {
        return Err(SignalError::File {
            file: file.into(),
            message: "a signal needs at least 2 samples".into(),
        });
    }
    let dt = (times[n - 1] - times[0]) / (n - 1) as f64;
    if dt.is_nan() || dt <= 0.0 {
        return Err(cell_error(ats[n - 1], "time does not increase".into()));
    }
    for i in 1..n {
        if times[i] <= times[i - 1] {
            return Err(cell_error(
                ats[i],
                format!(
                    "time does not increase ({} s after {} s on {})",
                    times[i],
                    times[i - 1],
                    ats[i - 1]
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
            return Err(cell_error(
                ats[i],
                format!(
                    "time step {step:.6e} s from the previous sample ({}) differs from the typical step {typical:.6e} s: samples must be evenly spaced without gaps (not on a constant-rate grid)",
                    ats[i - 1]
                ),
            ));
        }
    }
    for (i, &ti) in times.iter().enumerate() {
        if (ti - times[0] - i as f64 * dt).abs() > 0.25 * dt {
            return Err(cell_error(
                ats[i],
                format!(
                    "time {ti} s is off the constant-rate grid (step {dt:.6e} s): samples must be evenly spaced without gaps"
                ),
            ));
        }
    }
    Ok(1.0 / dt)
}
