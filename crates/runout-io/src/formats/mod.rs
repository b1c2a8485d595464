//! Binary recording formats (issue 16): MATLAB `.mat` (v5 and v7.3), NI TDMS, HDF5 and Parquet. Each format is read into a [`Catalog`] (every array the file
//! holds: name, length, unit, rate) and a [`Source`] that delivers sample ranges of one array; a
//! [`BinaryRecording`] then selects channels and the time base and yields the same
//! [`RecordingInfo`] and [`RecordingChunk`]s as the CSV/DynoWare reader, so every job reads every format
//! through [`open_recording`].
//!
//! Memory, per format:
//! * TDMS: streamed; the index of segments (a few numbers per channel and segment) plus one chunk.
//! * HDF5 / MAT v7.3: streamed by hyperslab (chunk by chunk of the dataset).
//! * Parquet: one row group of the file's numeric columns at a time.
//! * MAT v5: the whole file is read and every numeric array decoded (a compressed variable must be
//!   inflated whole); bounded by [`runout_core::limits::MAX_RESULT_BYTES`] of decoded data.
//!
//! Selection `FILE:SEL` (e.g. `data.mat:600`): the channels are the arrays in struct / group `SEL`
//! (`rec600.Fx` as `Fx`), or the arrays named `NAME_SEL` (`Fx_600` as `Fx`), so one axis mapping
//! (`x = -Fx, y = -Fy`) serves every recording in a "one file, five feeds" file.

pub mod arrays;
pub mod detect;
pub mod hdf5;
pub mod mat;
pub mod parquet;
pub mod tdms;

pub use arrays::{recording_from_arrays, Arrays};
pub use detect::{detect, detect_file, Kind};

use crate::recording::{
    Channel, Format, ReadOptions, RecordingChunk, RecordingError, RecordingInfo, RecordingReader,
};
use serde::Serialize;
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

type Result<T> = std::result::Result<T, RecordingError>;

/// One array in a binary file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Entry {
    /// Full name as written in a selection: `rec.Fx`, `Group/Fx`, `/grp/Fx`, `Fx`.
    pub name: String,
    /// The struct / group holding it, if any (`rec`, `Group`, `/grp`).
    pub group: Option<String>,
    /// Last component of the name (`Fx`).
    pub short: String,
    /// Number of samples (elements).
    pub len: u64,
    /// Element type as stored (`f64`, `i16`, `DAQmx i16 (scaled)`…).
    pub dtype: String,
    /// Unit, if the file states one.
    pub unit: Option<String>,
    /// Sample rate the file states for this array (TDMS `wf_increment`, HDF5 `fs`), Hz.
    pub sample_rate_hz: Option<f64>,
    /// Time of the first sample the file states (TDMS `wf_start_offset`), s.
    pub start_time_s: Option<f64>,
    /// The value, if the array holds exactly one number (a sample-rate variable).
    pub scalar: Option<f64>,
    /// Whether the array can be delivered as a channel (a numeric vector).
    pub readable: bool,
    /// Why not, or other remarks.
    pub note: Option<String>,
}

impl Entry {
    pub(crate) fn numeric(name: String, group: Option<String>, short: String, len: u64) -> Self {
        Entry {
            name,
            group,
            short,
            len,
            dtype: "f64".into(),
            unit: None,
            sample_rate_hz: None,
            start_time_s: None,
            scalar: None,
            readable: true,
            note: None,
        }
    }
}

/// What a binary file holds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Catalog {
    /// The file's format.
    pub format: Format,
    /// Every array, in file order.
    pub entries: Vec<Entry>,
    /// File-level properties (TDMS root properties, MAT header text, HDF5 root attributes).
    pub metadata: Vec<(String, String)>,
}

impl Catalog {
    /// `name (len, unit)` of every entry, comma separated, for messages.
    pub fn listing(&self) -> String {
        if self.entries.is_empty() {
            return "nothing".into();
        }
        self.entries
            .iter()
            .map(|e| {
                let mut s = format!("{} ({} × {}", e.name, e.len, e.dtype);
                if let Some(u) = &e.unit {
                    s += &format!(", {u}");
                }
                if let Some(v) = e.scalar {
                    s += &format!(" = {v}");
                }
                if let Some(n) = &e.note {
                    s += &format!("; {n}");
                }
                s + ")"
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Delivers sample ranges of a catalog's arrays.
pub trait Source: Send {
    /// Append samples `start .. start + n` of entry `entry` (index into [`Catalog::entries`]) to
    /// `out`, converted to f64 (and scaled, for TDMS scalers). Called with increasing `start`.
    fn read(&mut self, entry: usize, start: u64, n: usize, out: &mut Vec<f64>) -> Result<()>;
}

/// A binary file opened: what it holds and a way to read it.
pub struct Opened {
    /// What the file holds.
    pub catalog: Catalog,
    /// The reader.
    pub source: Box<dyn Source>,
}

/// Split `data.mat:600` into the path and the selector, when the whole string is not an existing
/// file and the part before the last `:` is (a Windows drive `C:` is never split).
pub fn split_selector(spec: &Path) -> (PathBuf, Option<String>) {
    let s = spec.to_string_lossy();
    if spec.exists() {
        return (spec.to_path_buf(), None);
    }
    if let Some(i) = s.rfind(':') {
        let (p, sel) = (&s[..i], &s[i + 1..]);
        if !sel.is_empty() && !sel.contains(['/', '\\']) && p.len() > 1 && Path::new(p).is_file() {
            return (PathBuf::from(p), Some(sel.to_string()));
        }
    }
    (spec.to_path_buf(), None)
}

/// Open a recording of any supported format, detected by content (magic bytes): DynoWare/CSV/TSV
/// text, MATLAB `.mat` v5 / v7.3, NI TDMS, HDF5, Parquet. `path` may carry
/// a selector, `data.mat:600` (see the module documentation). A pipe, FIFO or device (e.g.
/// `/dev/stdin`) is opened once and read in order: text recordings only.
pub fn open_recording(
    path: impl AsRef<Path>,
    options: &ReadOptions,
) -> Result<RecordingReader<BufReader<File>>> {
    let (path, selector) = split_selector(path.as_ref());
    let file = path.display().to_string();
    if is_stream(&path) {
        return open_stream(&path, &file, selector.as_deref(), options);
    }
    let kind = detect_file(&path).map_err(|error| RecordingError::Io {
        file: file.clone(),
        error,
    })?;
    if kind == Kind::Text {
        if let Some(sel) = selector {
            return Err(selector_on_text(file, &sel));
        }
        return RecordingReader::open(&path, options);
    }
    let opened = open_kind(kind, &path, &file)?;
    let bytes = std::fs::metadata(&path).ok().map(|m| m.len());
    let rec = BinaryRecording::new(opened, &file, selector.as_deref(), options, bytes)?;
    let f = File::open(&path).map_err(|error| RecordingError::Io {
        file: file.clone(),
        error,
    })?;
    Ok(RecordingReader::from_binary(BufReader::new(f), rec))
}

/// Whether `path` names something that can be read only once, in order (a pipe, a FIFO, a
/// device): neither a regular file nor a folder. Such a path must be opened once only: a second
/// reader would take bytes from the first.
///
/// ```
/// assert!(!runout_io::formats::is_stream(std::path::Path::new("Cargo.toml")));
/// assert!(!runout_io::formats::is_stream(std::path::Path::new("no such file")));
/// ```
pub fn is_stream(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// A recording that can be read only once, in order: a pipe (`<(zcat rec.txt.gz)`, standard
/// input), a FIFO or a device. Opened once and its format detected from the first bytes the
/// reader holds, so no byte is read twice or lost (a second open of a pipe would start where the
/// first read stopped). Only text recordings are read this way: the binary formats need to seek.
fn open_stream(
    path: &Path,
    file: &str,
    selector: Option<&str>,
    options: &ReadOptions,
) -> Result<RecordingReader<BufReader<File>>> {
    let io = |error| RecordingError::Io {
        file: file.to_string(),
        error,
    };
    let mut src = BufReader::with_capacity(1 << 16, File::open(path).map_err(io)?);
    let kind = detect(src.fill_buf().map_err(io)?);
    if kind != Kind::Text {
        return Err(RecordingError::Format {
            file: file.to_string(),
            message: format!(
                "a {} file cannot be read from a pipe or device (it is read with random access): \
                 save it to a file and give that path",
                kind.name()
            ),
        });
    }
    if let Some(sel) = selector {
        return Err(selector_on_text(file.to_string(), sel));
    }
    RecordingReader::from_reader(src, file, options)
}

/// The error for a `:SEL` selector given with a text recording.
fn selector_on_text(file: String, sel: &str) -> RecordingError {
    RecordingError::Format {
        file,
        message: format!(
            "a selector (`:{sel}`) applies to .mat, TDMS, HDF5 and Parquet files, not to text recordings"
        ),
    }
}

/// Like [`open_recording`] for a file held in memory; `name` is used in messages, `selector` as
/// the `:SEL` suffix.
pub fn recording_from_bytes<'a>(
    name: &str,
    bytes: &'a [u8],
    selector: Option<&str>,
    options: &ReadOptions,
) -> Result<RecordingReader<std::io::Cursor<&'a [u8]>>> {
    let kind = detect(bytes);
    if kind == Kind::Text {
        return RecordingReader::from_bytes(name, bytes, options);
    }
    let opened = open_bytes(kind, bytes, name)?;
    let rec = BinaryRecording::new(opened, name, selector, options, Some(bytes.len() as u64))?;
    Ok(RecordingReader::from_binary(
        std::io::Cursor::new(&bytes[..0]),
        rec,
    ))
}

/// Like [`recording_from_bytes`], as a reader of one type for text and binary content alike,
/// not borrowing `bytes` (a binary file is decoded or indexed at open; text is copied once into
/// the reader). For sources held in memory by a front end (`runout::Source::bytes`).
pub fn recording_from_shared(
    name: &str,
    bytes: std::sync::Arc<[u8]>,
    selector: Option<&str>,
    options: &ReadOptions,
) -> Result<RecordingReader<Box<dyn std::io::BufRead + Send>>> {
    let n = bytes.len() as u64;
    let kind = detect(&bytes);
    if kind == Kind::Text {
        if let Some(sel) = selector {
            return Err(RecordingError::Format {
                file: name.into(),
                message: format!(
                    "a selector (`:{sel}`) applies to .mat, TDMS, HDF5 and Parquet files, not to text recordings"
                ),
            });
        }
        let src: Box<dyn std::io::BufRead + Send> = Box::new(std::io::Cursor::new(bytes));
        return Ok(RecordingReader::from_reader(src, name, options)?.with_file_bytes(Some(n)));
    }
    let opened = open_bytes(kind, &bytes, name)?;
    let rec = BinaryRecording::new(opened, name, selector, options, Some(n))?;
    let empty: Box<dyn std::io::BufRead + Send> = Box::new(std::io::Cursor::new(Vec::new()));
    Ok(RecordingReader::from_binary(empty, rec))
}

fn unsupported(kind: Kind, file: &str) -> RecordingError {
    RecordingError::Format {
        file: file.into(),
        message: match kind {
            Kind::Mat4 => "a MATLAB v4 .mat file: save it as v5 (`save -v7`) or v7.3".into(),
            k => format!("unsupported format {k:?}"),
        },
    }
}

/// Open a binary file of a detected kind.
pub fn open_kind(kind: Kind, path: &Path, file: &str) -> Result<Opened> {
    match kind {
        Kind::Mat5 => mat::open_path(path, file),
        Kind::Hdf5 { .. } => hdf5::open_path(path, file),
        Kind::Tdms => tdms::open_path(path, file),
        Kind::Parquet => parquet::open_path(path, file),
        k => Err(unsupported(k, file)),
    }
}

/// Open a binary file held in memory.
pub fn open_bytes(kind: Kind, bytes: &[u8], file: &str) -> Result<Opened> {
    match kind {
        Kind::Mat5 => mat::open_bytes(bytes, file),
        Kind::Hdf5 { .. } => hdf5::open_bytes(bytes, file),
        Kind::Tdms => tdms::open_bytes(bytes.to_vec(), file),
        Kind::Parquet => parquet::open_bytes(bytes.to_vec(), file),
        k => Err(unsupported(k, file)),
    }
}

/// What `runout inspect` prints: the catalog of a binary file, or the header of a text one.
pub fn inspect(path: &Path, options: &ReadOptions) -> Result<Catalog> {
    let file = path.display().to_string();
    let r = if is_stream(path) {
        open_stream(path, &file, None, options)?
    } else {
        let kind = detect_file(path).map_err(|error| RecordingError::Io {
            file: file.clone(),
            error,
        })?;
        if kind != Kind::Text {
            return Ok(open_kind(kind, path, &file)?.catalog);
        }
        RecordingReader::open(path, options)?
    };
    let info = r.info();
    let mut entries = Vec::new();
    for c in info.time_column.iter().chain(&info.channels) {
        let mut e = Entry::numeric(c.header.clone(), None, c.name.clone(), 0);
        e.unit = c.unit.clone();
        e.dtype = "text".into();
        e.len = info.expected_samples.unwrap_or(0);
        e.sample_rate_hz = Some(info.sample_rate_hz);
        e.note = (info.expected_samples.is_none()).then(|| "length not in the header".into());
        entries.push(e);
    }
    Ok(Catalog {
        format: info.format.clone(),
        entries,
        metadata: info.metadata.clone(),
    })
}

/// Names that are taken as a time vector when no time variable is named.
const TIME_NAMES: [&str; 5] = ["t", "time", "time_s", "zeit", "timestamp"];
/// Names that are taken as a sample-rate scalar (Hz) when no variable is named.
const RATE_NAMES: [&str; 7] = [
    "fs",
    "fs_hz",
    "sample_rate",
    "sample_rate_hz",
    "samplerate",
    "sampling_rate",
    "sampling_rate_hz",
];

/// A candidate array and the name it is delivered under.
struct Candidate {
    entry: usize,
    alias: String,
}

/// The arrays a selection sees and the names they are delivered under: every array under its
/// short name, or with a selector `SEL` the arrays of struct / group `SEL` and those named
/// `NAME_SEL` (as `NAME`), plus file-level time and sample-rate variables.
fn candidates(catalog: &Catalog, file: &str, selector: Option<&str>) -> Result<Vec<Candidate>> {
    let listing = || catalog.listing();
    Ok(match selector {
        None => catalog
            .entries
            .iter()
            .enumerate()
            .map(|(i, e)| Candidate {
                entry: i,
                alias: e.short.clone(),
            })
            .collect(),
        Some(sel) => {
            let nsel = norm(sel);
            let mut v: Vec<Candidate> = catalog
                .entries
                .iter()
                .enumerate()
                .filter(|(_, e)| e.group.as_deref().map(norm).as_deref() == Some(&nsel))
                .map(|(i, e)| Candidate {
                    entry: i,
                    alias: e.short.clone(),
                })
                .collect();
            let suffix = format!("_{sel}");
            for (i, e) in catalog.entries.iter().enumerate() {
                if let Some(base) = e.short.strip_suffix(&suffix) {
                    if !base.is_empty() && !v.iter().any(|c| c.alias == base) {
                        v.push(Candidate {
                            entry: i,
                            alias: base.to_string(),
                        });
                    }
                }
            }
            // file-level scalars and time vectors stay visible (a shared `fs` or `t`)
            for (i, e) in catalog.entries.iter().enumerate() {
                let low = e.short.to_ascii_lowercase();
                if e.group.is_none()
                    && (TIME_NAMES.contains(&low.as_str()) || RATE_NAMES.contains(&low.as_str()))
                    && !v.iter().any(|c| c.alias.eq_ignore_ascii_case(&e.short))
                {
                    v.push(Candidate {
                        entry: i,
                        alias: e.short.clone(),
                    });
                }
            }
            if v.iter().all(|c| catalog.entries[c.entry].len <= 1) {
                return Err(RecordingError::Format {
                    file: file.into(),
                    message: format!(
                        "selector `{sel}`: no struct/group `{sel}` and no variables named `NAME_{sel}`; the file holds: {}",
                        listing()
                    ),
                });
            }
            v
        }
    })
}

/// The channel names a selection offers (`alias`, index into [`Catalog::entries`]), in file
/// order: what [`BinaryRecording::new`] accepts in [`ReadOptions::channels`].
pub fn selectable(
    catalog: &Catalog,
    file: &str,
    selector: Option<&str>,
) -> Result<Vec<(String, usize)>> {
    Ok(candidates(catalog, file, selector)?
        .into_iter()
        .map(|c| (c.alias, c.entry))
        .collect())
}

/// A binary recording: channels and time base chosen, read chunk by chunk.
pub struct BinaryRecording {
    info: RecordingInfo,
    source: Box<dyn Source>,
    columns: Vec<usize>,
    time: Option<usize>,
    len: u64,
    sample: u64,
    warnings: Vec<String>,
    finished: bool,
    bytes: u64,
}

/// The other spelling of a 2-D array's column: `D[:,k]` (0-based) ↔ `D(:,k+1)` (1-based).
pub fn column_spelling(name: &str) -> Option<String> {
    let n = name.trim();
    if let Some(base) = n.strip_suffix(']') {
        let (base, k) = base.rsplit_once("[:,")?;
        let k: u64 = k.trim().parse().ok()?;
        return Some(format!("{base}(:,{})", k + 1));
    }
    let base = n.strip_suffix(')')?;
    let (base, j) = base.rsplit_once("(:,")?;
    let j: u64 = j.trim().parse().ok()?;
    (j >= 1).then(|| format!("{base}[:,{}]", j - 1))
}

fn norm(name: &str) -> String {
    // `'Group'/'Fx'` → `Group/Fx`; leading `/` dropped
    name.trim()
        .replace("'/'", "/")
        .trim_matches('\'')
        .trim_start_matches('/')
        .to_string()
}

impl BinaryRecording {
    /// Choose channels (`options.channels`, or every readable vector) and the time base.
    pub fn new(
        opened: Opened,
        file: &str,
        selector: Option<&str>,
        options: &ReadOptions,
        file_bytes: Option<u64>,
    ) -> Result<Self> {
        let Opened { catalog, source } = opened;
        let listing = || catalog.listing();
        let cands = candidates(&catalog, file, selector)?;
        let find_exact = |name: &str| -> Option<usize> {
            let n = norm(name);
            let by = |f: &dyn Fn(&Candidate) -> bool| cands.iter().find(|c| f(c)).map(|c| c.entry);
            by(&|c| c.alias == n)
                .or_else(|| by(&|c| norm(&catalog.entries[c.entry].name) == n))
                .or_else(|| by(&|c| c.alias.eq_ignore_ascii_case(&n)))
                .or_else(|| by(&|c| norm(&catalog.entries[c.entry].name).eq_ignore_ascii_case(&n)))
                // a name without the unit suffix of the array's name (`xI` for `xI_um`), as
                // in a text header
                .or_else(|| {
                    by(&|c| {
                        crate::recording::header::split_unit(&c.alias)
                            .0
                            .eq_ignore_ascii_case(&n)
                    })
                })
        };
        // a column of a 2-D array in either spelling: `D[:,k]` (0-based) or `D(:,k+1)` (MATLAB)
        let find = |name: &str| -> Option<usize> {
            find_exact(name).or_else(|| column_spelling(name).and_then(|a| find_exact(&a)))
        };
        let missing = |what: &str, name: &str| RecordingError::MissingChannel {
            file: file.into(),
            what: what.into(),
            name: name.into(),
            available: listing(),
        };
        // the time variable: named, or auto-detected among the candidates
        let named_time = match &options.time_column {
            Some(t) => Some(find(t).ok_or_else(|| missing("time variable", t))?),
            None => None,
        };
        let auto = |names: &[&str], scalar: bool| {
            cands
                .iter()
                .find(|c| {
                    let e = &catalog.entries[c.entry];
                    names.contains(&c.alias.to_ascii_lowercase().as_str())
                        && e.readable
                        && (e.scalar.is_some() == scalar)
                })
                .map(|c| c.entry)
        };
        let time_entry = match named_time {
            Some(i) => Some(i),
            None => auto(&TIME_NAMES, false),
        };
        let rate_var = match named_time {
            Some(i) if catalog.entries[i].scalar.is_some() => Some(i),
            Some(_) => None,
            None => auto(&RATE_NAMES, true),
        };
        let time_vec = time_entry.filter(|&i| catalog.entries[i].scalar.is_none());
        // channels
        let columns: Vec<usize> = match &options.channels {
            Some(names) => names
                .iter()
                .map(|n| find(n).ok_or_else(|| missing("channel", n)))
                .collect::<Result<_>>()?,
            None => {
                let vecs: Vec<usize> = cands
                    .iter()
                    .map(|c| c.entry)
                    .filter(|&i| {
                        let e = &catalog.entries[i];
                        e.readable && e.scalar.is_none() && e.len > 1 && Some(i) != time_vec
                    })
                    .collect();
                let longest = vecs.iter().map(|&i| catalog.entries[i].len).max();
                vecs.into_iter()
                    .filter(|&i| Some(catalog.entries[i].len) == longest)
                    .collect()
            }
        };
        if columns.is_empty() {
            return Err(RecordingError::Format {
                file: file.into(),
                message: format!("no numeric channel to read; the file holds: {}", listing()),
            });
        }
        for &i in &columns {
            let e = &catalog.entries[i];
            if !e.readable {
                return Err(RecordingError::Format {
                    file: file.into(),
                    message: format!(
                        "`{}` is not a numeric vector ({}); the file holds: {}",
                        e.name,
                        e.note.clone().unwrap_or_else(|| e.dtype.clone()),
                        listing()
                    ),
                });
            }
        }
        let len = catalog.entries[columns[0]].len;
        for &i in columns.iter().chain(time_vec.iter()) {
            let e = &catalog.entries[i];
            if e.len != len {
                return Err(RecordingError::Format {
                    file: file.into(),
                    message: format!(
                        "`{}` has {} samples but `{}` has {len}; channels of one recording must have equal lengths",
                        e.name, e.len, catalog.entries[columns[0]].name
                    ),
                });
            }
        }
        let mut source = source;
        // time base: caller's rate, named variable, the file's per-channel rate, auto variable
        let first = &catalog.entries[columns[0]];
        let mut t_head = Vec::new();
        if let Some(t) = time_vec {
            source.read(t, 0, (len.min(1000)) as usize, &mut t_head)?;
        }
        let time_rate = (t_head.len() >= 2)
            .then(|| (t_head.len() - 1) as f64 / (t_head[t_head.len() - 1] - t_head[0]))
            .filter(|f| f.is_finite() && *f > 0.0);
        let var_rate = rate_var.and_then(|i| catalog.entries[i].scalar);
        // a named time base and a given rate must agree (a rate variable to 1e-9 relative; a
        // time vector sample by sample within ½ sample period, checked as it is read)
        if let (Some(f), Some(v), Some(i), Some(_)) = (
            options.sample_rate_hz,
            var_rate,
            rate_var,
            &options.time_column,
        ) {
            if ((v - f) / f).abs().is_nan() || ((v - f) / f).abs() > 1e-9 {
                return Err(RecordingError::Format {
                    file: file.into(),
                    message: format!(
                        "the time variable `{}` says {v} Hz but --sample-rate-hz is {f} Hz: give one, or make them agree",
                        catalog.entries[i].name
                    ),
                });
            }
        }
        let (rate, rate_source) = if let Some(f) = options.sample_rate_hz {
            (f, "given by the caller".to_string())
        } else if let (Some(f), Some(i)) = (var_rate, rate_var) {
            (
                f,
                format!("from the variable `{}`", catalog.entries[i].name),
            )
        } else if let Some(f) = first.sample_rate_hz {
            (f, format!("from the properties of `{}`", first.name))
        } else if let (Some(f), Some(i)) = (time_rate, time_vec) {
            (
                f,
                format!(
                    "estimated from the first samples of `{}`",
                    catalog.entries[i].name
                ),
            )
        } else {
            return Err(RecordingError::NoSampleRate {
                file: file.into(),
                extra: format!(
                    " (name a sample-rate or time variable, e.g. `fs` or `t`; the file holds: {})",
                    listing()
                ),
            });
        };
        if !(rate.is_finite() && rate > 0.0) {
            return Err(RecordingError::Format {
                file: file.into(),
                message: format!("sample rate {rate} Hz ({rate_source}) is not a positive number"),
            });
        }
        let start = t_head
            .first()
            .copied()
            .or(options.start_time_s)
            .or(first.start_time_s)
            .unwrap_or(0.0);
        let channel = |i: usize, k: usize| {
            let e = &catalog.entries[i];
            Channel {
                name: e.short.clone(),
                header: e.name.clone(),
                // the file's unit, else the unit suffix of the name (`xI_um`), as in a text header
                unit: e
                    .unit
                    .clone()
                    .or_else(|| crate::recording::header::split_unit(&e.short).1),
                column: k + 1,
            }
        };
        // deliver under the alias used for selection (`Fx` for `Fx_600`)
        let alias_of = |i: usize| {
            cands
                .iter()
                .find(|c| c.entry == i)
                .map(|c| c.alias.clone())
                .unwrap_or_else(|| catalog.entries[i].short.clone())
        };
        let all: Vec<Channel> = catalog
            .entries
            .iter()
            .enumerate()
            .map(|(i, _)| {
                let mut c = channel(i, i);
                c.name = alias_of(i);
                c
            })
            .collect();
        let channels = columns.iter().map(|&i| all[i].clone()).collect();
        let mut metadata = catalog.metadata.clone();
        if let Some(s) = selector {
            metadata.push(("selector".into(), s.into()));
        }
        let info = RecordingInfo {
            file: file.into(),
            format: catalog.format.clone(),
            delimiter: ',',
            decimal_comma: false,
            metadata,
            columns: all,
            channels,
            time_column: time_vec.map(|i| channel(i, i)),
            sample_rate_hz: rate,
            sample_rate_source: rate_source,
            start_time_s: start,
            expected_samples: Some(len),
            header_lines: 0,
            file_bytes,
        };
        Ok(Self {
            info,
            source,
            columns,
            time: time_vec,
            len,
            sample: 0,
            warnings: Vec::new(),
            finished: false,
            bytes: file_bytes.unwrap_or(0),
        })
    }

    /// Channels, units, rate.
    pub fn info(&self) -> &RecordingInfo {
        &self.info
    }

    /// Non-fatal findings.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Samples delivered so far.
    pub fn samples_read(&self) -> u64 {
        self.sample
    }

    /// Approximate bytes consumed (proportional to the samples delivered).
    pub fn bytes_read(&self) -> u64 {
        if self.len == 0 {
            return self.bytes;
        }
        (self.bytes as f64 * self.sample as f64 / self.len as f64) as u64
    }

    /// Fill `chunk` with up to `max_rows` samples; 0 at the end.
    pub fn read_chunk(&mut self, chunk: &mut RecordingChunk, max_rows: usize) -> Result<usize> {
        chunk.first_sample = self.sample;
        chunk.time_s.clear();
        chunk.values.resize_with(self.columns.len(), Vec::new);
        for v in &mut chunk.values {
            v.clear();
        }
        if self.finished || self.sample >= self.len {
            self.finished = true;
            return Ok(0);
        }
        let n = (self.len - self.sample).min(max_rows.max(1) as u64) as usize;
        let result = self.fill(chunk, n);
        if result.is_err() {
            self.finished = true;
        }
        result?;
        self.sample += n as u64;
        Ok(n)
    }

    fn fill(&mut self, chunk: &mut RecordingChunk, n: usize) -> Result<()> {
        for (k, &e) in self.columns.iter().enumerate() {
            self.source.read(e, self.sample, n, &mut chunk.values[k])?;
            if chunk.values[k].len() != n {
                return Err(RecordingError::Format {
                    file: self.info.file.clone(),
                    message: format!(
                        "`{}`: expected {n} samples from sample {}, got {}",
                        self.info.channels[k].header,
                        self.sample,
                        chunk.values[k].len()
                    ),
                });
            }
        }
        match self.time {
            Some(t) => {
                self.source.read(t, self.sample, n, &mut chunk.time_s)?;
                if chunk.time_s.len() != n {
                    return Err(RecordingError::Format {
                        file: self.info.file.clone(),
                        message: format!(
                            "time vector: expected {n} samples, got {}",
                            chunk.time_s.len()
                        ),
                    });
                }
                self.check_times(&chunk.time_s)?;
            }
            None => {
                let fs = self.info.sample_rate_hz;
                let t0 = self.info.start_time_s;
                chunk
                    .time_s
                    .extend((0..n as u64).map(|k| t0 + (self.sample + k) as f64 / fs));
            }
        }
        Ok(())
    }
}

impl BinaryRecording {
    /// A time vector must increase and stay on the sample-rate grid: every sample within ½ sample
    /// period of t₀ + k/f_s (the tolerance of the text reader's time column).
    fn check_times(&mut self, times: &[f64]) -> Result<()> {
        let fs = self.info.sample_rate_hz;
        let t0 = self.info.start_time_s;
        let name = self
            .info
            .time_column
            .as_ref()
            .map_or("time", |c| c.header.as_str());
        for (k, &t) in times.iter().enumerate() {
            let sample = self.sample + k as u64;
            let expected = t0 + sample as f64 / fs;
            if t.is_nan() || (t - expected).abs() > 0.5 / fs {
                return Err(RecordingError::Format {
                    file: self.info.file.clone(),
                    message: format!(
                        "time variable `{name}`, sample {sample}: {t} s, but sample {sample} at {fs} Hz (the sample rate {}) from t0 = {t0} s is at {expected} s: the times are not evenly spaced within ½ sample period{}",
                        self.info.sample_rate_source,
                        if self.info.sample_rate_source.contains("caller") {
                            " (the time variable disagrees with --sample-rate-hz)"
                        } else {
                            ""
                        }
                    ),
                });
            }
        }
        Ok(())
    }
}

/// An in-memory source: decoded arrays (MAT v5, small files).
pub(crate) struct MemorySource {
    pub(crate) arrays: Vec<Vec<f64>>,
}

impl Source for MemorySource {
    fn read(&mut self, entry: usize, start: u64, n: usize, out: &mut Vec<f64>) -> Result<()> {
        let a = &self.arrays[entry];
        let s = (start as usize).min(a.len());
        let e = s.saturating_add(n).min(a.len());
        out.extend_from_slice(&a[s..e]);
        Ok(())
    }
}
