//! `inspect`: what a recording holds — channels (variables, TDMS channels, HDF5 datasets,
//! Parquet columns), units, lengths, sample rates — for every supported format (issue 16 item 4).

pub mod render;

use crate::job::{Report, Source};
use anyhow::{bail, Result};
use runout_io::formats::{inspect as catalog, split_selector};
use runout_io::recording::{Format, ReadOptions};
use schemars::JsonSchema;
use serde::Serialize;

/// `runout inspect`: a recording file (a `FILE:SEL` selection is ignored: the whole file is
/// listed).
#[derive(Debug, Clone)]
pub struct InspectRequest {
    pub recording: Source,
    /// Sample rate (Hz), for a text recording with neither a time column nor a sampling-rate line.
    pub sample_rate_hz: Option<f64>,
}

/// The recording's format (snake_case: `generic_csv`, `{"dynoware": {…}}`, `{"tdms": {…}}`).
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FormatReport {
    /// A CSV/TSV with a header row.
    GenericCsv,
    /// A Kistler DynoWare text export.
    #[serde(rename = "dynoware")]
    DynoWare {
        version: String,
    },
    /// A MATLAB .mat file (`5` or `7.3`).
    Mat {
        version: String,
    },
    /// An NI TDMS file (4712 or 4713).
    Tdms {
        version: u32,
    },
    Hdf5,
    Parquet,
    /// Arrays in memory (the Python package's NumPy arrays; `runout_io::formats::Arrays`).
    Arrays,
}

impl From<&Format> for FormatReport {
    fn from(f: &Format) -> Self {
        match f {
            Format::GenericCsv => Self::GenericCsv,
            Format::DynoWare { version } => Self::DynoWare {
                version: version.clone(),
            },
            Format::Mat { version } => Self::Mat {
                version: version.clone(),
            },
            Format::Tdms { version } => Self::Tdms { version: *version },
            Format::Hdf5 => Self::Hdf5,
            Format::Parquet => Self::Parquet,
            Format::Arrays => Self::Arrays,
        }
    }
}

/// One array (channel) of the file.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct EntryReport {
    /// Full name as written in a selection: `rec.Fx`, `Group/Fx`, `/grp/Fx`, `Fx`.
    pub name: String,
    /// The struct / group holding it, if any.
    pub group: Option<String>,
    /// Last component of the name (`Fx`).
    pub short: String,
    /// Number of samples.
    pub len: u64,
    /// Element type as stored (`f64`, `i16`, `text`…).
    pub dtype: String,
    pub unit: Option<String>,
    pub sample_rate_hz: Option<f64>,
    pub start_time_s: Option<f64>,
    /// The value, if the array holds exactly one number.
    pub scalar: Option<f64>,
    /// Whether the array can be delivered as a channel.
    pub readable: bool,
    pub note: Option<String>,
}

/// `runout.inspect/2`: what a recording holds.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct InspectReport {
    /// `runout.inspect/2`
    #[schemars(extend("const" = "runout.inspect/2"))]
    pub schema: String,
    pub file: String,
    pub format: FormatReport,
    pub entries: Vec<EntryReport>,
    /// File-level properties as (name, value).
    pub metadata: Vec<(String, String)>,
}

impl Report for InspectReport {
    const SCHEMA: &'static str = "runout.inspect/2";
}

/// List what the recording holds.
pub fn inspect(req: &InspectRequest) -> Result<InspectReport> {
    let Some(p) = req.recording.as_path() else {
        bail!(
            "{}: inspect reads a file (an in-memory source is opened with Source::open_recording)",
            req.recording.name()
        );
    };
    let (path, _) = split_selector(p);
    let mut o = ReadOptions::new();
    o.sample_rate_hz = req.sample_rate_hz;
    let c = catalog(&path, &o)?;
    Ok(InspectReport {
        schema: InspectReport::SCHEMA.into(),
        file: path.display().to_string(),
        format: (&c.format).into(),
        entries: c
            .entries
            .into_iter()
            .map(|e| EntryReport {
                name: e.name,
                group: e.group,
                short: e.short,
                len: e.len,
                dtype: e.dtype,
                unit: e.unit,
                sample_rate_hz: e.sample_rate_hz,
                start_time_s: e.start_time_s,
                scalar: e.scalar,
                readable: e.readable,
                note: e.note,
            })
            .collect(),
        metadata: c.metadata,
    })
}
