//! Recordings: streaming readers for measured signals (generic CSV/TSV and Kistler DynoWare
//! text exports), an axis mapping from instrument channels to the workpiece frame, and a
//! streaming CSV writer.
//!
//! ```
//! use runout_io::recording::{ReadOptions, RecordingReader, RecordingChunk};
//! let text = "DynoWare,Version 2.5.1.2\nSampling rate [Hz]:,1000\nTime,Fx,Fy\ns,N,N\n\
//!             0.000,1.5,2.5\n0.001,1.6,2.4\n";
//! let mut r = RecordingReader::from_bytes("demo.txt", text.as_bytes(), &ReadOptions::new()).unwrap();
//! assert_eq!(r.info().sample_rate_hz, 1000.0);
//! let mut chunk = RecordingChunk::default();
//! assert_eq!(r.read_chunk(&mut chunk, 1024).unwrap(), 2);
//! assert_eq!(chunk.channel(1), &[2.5, 2.4]);
//! ```
//!
//! Formats (issue 3 item 1):
//! * **Generic CSV/TSV**: a header row of channel names, optionally a unit row; units also from
//!   the names (`fx_N`, `Fx [N]`, `Fx (N)`); a time column (`time`, `t`, `Time [s]`, `time_ms`…,
//!   or named by the caller) or a sample rate given by the caller.
//! * **DynoWare**: line 1 `DynoWare,Version …`, `Key:,value` lines (kept as metadata; the
//!   `Sampling rate [Hz]` and `Samples per channel` lines are used), the channel-name row, the unit
//!   row, data.
//! * Delimiters comma, semicolon, tab (detected); decimal commas with semicolon/tab delimiters;
//!   UTF-8 (with or without BOM) or Latin-1 header text; CRLF or LF line ends.
//!
//! Memory: the reader holds one line, up to 1000 read-ahead rows and the caller's chunk.

mod axis;
mod error;
pub(crate) mod header;
mod reader;
mod text;
mod writer;

pub use crate::formats::{open_recording, recording_from_bytes};
pub(crate) use axis::split_entries;
pub use axis::AxisMappingError;
pub use axis::{AxisMapping, AxisSource, FrameAxis, ResolvedAxes};
pub use error::RecordingError;
pub use reader::{RecordingReader, DEFAULT_CHUNK_ROWS};
pub use writer::{read_binary, BinaryLayout, BinaryWriter, CsvWriter, BINARY_MAGIC};

use serde::Serialize;
use std::path::Path;

/// How to read a recording.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Sample rate in Hz; required when the file has neither a time column nor a DynoWare
    /// sampling-rate line; if given, it takes precedence and a time column is checked against it.
    pub sample_rate_hz: Option<f64>,
    /// Name of the time column; `None` = auto-detect (`time`, `t`, `zeit`, `timestamp`).
    pub time_column: Option<String>,
    /// Channels to read, by name (with or without unit); `None` = every non-time column.
    pub channels: Option<Vec<String>>,
    /// Time of the first sample when there is no time column, s (default 0).
    pub start_time_s: Option<f64>,
    /// Rows per chunk for [`RecordingReader::next_chunk`] (0 = 65 536).
    pub chunk_rows: usize,
}

impl ReadOptions {
    /// Default options: auto-detect everything, all channels.
    pub fn new() -> Self {
        Self::default()
    }

    /// Set the sample rate, Hz.
    pub fn sample_rate_hz(mut self, hz: f64) -> Self {
        self.sample_rate_hz = Some(hz);
        self
    }

    /// Select channels by name.
    pub fn channels<S: AsRef<str>>(mut self, names: &[S]) -> Self {
        self.channels = Some(names.iter().map(|s| s.as_ref().to_string()).collect());
        self
    }

    /// Name the time column.
    pub fn time_column(mut self, name: &str) -> Self {
        self.time_column = Some(name.to_string());
        self
    }

    /// Rows per chunk.
    pub fn chunk_rows(mut self, rows: usize) -> Self {
        self.chunk_rows = rows;
        self
    }

    fn validate(&self, file: &str) -> Result<(), RecordingError> {
        if let Some(f) = self.sample_rate_hz {
            if !(f.is_finite() && f > 0.0) {
                return Err(RecordingError::Option {
                    file: file.into(),
                    message: format!(
                        "sample rate must be a positive number of Hz, got {f} (--sample-rate-hz / `sample_rate_hz`)"
                    ),
                });
            }
        }
        if let Some(t) = self.start_time_s {
            if !t.is_finite() {
                return Err(RecordingError::Option {
                    file: file.into(),
                    message: format!("start time must be finite, got {t}"),
                });
            }
        }
        Ok(())
    }
}

/// The recording's format (serialised in snake_case: `generic_csv`, `{"dynoware": {…}}`, …).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Format {
    /// A CSV/TSV with a header row.
    GenericCsv,
    /// A Kistler DynoWare text export.
    #[serde(rename = "dynoware")]
    DynoWare {
        /// The version on line 1 (`Version 2.5.1.2`).
        version: String,
    },
    /// A MATLAB .mat file (`5` or `7.3`).
    Mat {
        /// MAT-file version.
        version: String,
    },
    /// An NI TDMS file.
    Tdms {
        /// TDMS version (4712 or 4713).
        version: u32,
    },
    /// An HDF5 file.
    Hdf5,
    /// An Apache Parquet file.
    Parquet,
    /// Arrays in memory (the Python package's NumPy arrays, [`crate::formats::Arrays`]).
    Arrays,
}

/// One column of the header.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Channel {
    /// Name without unit (`Fx` for `Fx [N]`, `fx` for `fx_N`).
    pub name: String,
    /// Header text as written.
    pub header: String,
    /// Unit from the unit row or the name, if any.
    pub unit: Option<String>,
    /// 1-based column (field) number.
    pub column: usize,
}

/// What the header of a recording says.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordingInfo {
    /// File name used in messages.
    pub file: String,
    /// Generic CSV or DynoWare.
    pub format: Format,
    /// Field delimiter (`,`, `;` or tab).
    pub delimiter: char,
    /// Whether numbers use a decimal comma.
    pub decimal_comma: bool,
    /// DynoWare `Key:,value` lines in file order (keys without the colon).
    pub metadata: Vec<(String, String)>,
    /// Every column of the header.
    pub columns: Vec<Channel>,
    /// The channels delivered, in the order of [`RecordingChunk::values`].
    pub channels: Vec<Channel>,
    /// The time column, if any.
    pub time_column: Option<Channel>,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Where the sample rate came from.
    pub sample_rate_source: String,
    /// Time of sample 0, s.
    pub start_time_s: f64,
    /// DynoWare `Samples per channel`, if stated.
    pub expected_samples: Option<u64>,
    /// Last header line number (data start after it).
    pub header_lines: u64,
    /// Size of the input in bytes, if known.
    pub file_bytes: Option<u64>,
}

impl RecordingInfo {
    /// Index in [`RecordingInfo::channels`] of a delivered channel, by name (with or without unit;
    /// exact, then case-insensitive).
    pub fn channel_index(&self, name: &str) -> Option<usize> {
        reader::find_column(&self.channels, name)
    }

    /// A metadata value by key (case-insensitive, the key may omit a trailing `[unit]`).
    pub fn metadata_value(&self, key: &str) -> Option<&str> {
        let k = key.trim().to_ascii_lowercase();
        self.metadata
            .iter()
            .find(|(mk, _)| {
                let m = mk.to_ascii_lowercase();
                m == k || header::split_unit(&m).0 == k
            })
            .map(|(_, v)| v.as_str())
    }

    /// Duration announced by the header (`Samples per channel`/rate), s, if stated.
    pub fn expected_duration_s(&self) -> Option<f64> {
        self.expected_samples
            .map(|n| n.saturating_sub(1) as f64 / self.sample_rate_hz)
    }
}

/// A block of consecutive samples: time and one vector per delivered channel.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RecordingChunk {
    /// Index of the first sample in the recording (0-based).
    pub first_sample: u64,
    /// Sample times, s (the time column, or t₀ + k/f_s).
    pub time_s: Vec<f64>,
    /// Values per channel (same order as [`RecordingInfo::channels`]), in the file's units.
    pub values: Vec<Vec<f64>>,
}

impl RecordingChunk {
    /// Rows in the chunk.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True if the chunk has no rows.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// Values of channel `i` (index into [`RecordingInfo::channels`]).
    pub fn channel(&self, i: usize) -> &[f64] {
        &self.values[i]
    }
}

/// A whole recording in memory (for small files; stream long ones with [`RecordingReader`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Header information.
    pub info: RecordingInfo,
    /// Sample times, s.
    pub time_s: Vec<f64>,
    /// Values per channel.
    pub values: Vec<Vec<f64>>,
    /// Non-fatal findings.
    pub warnings: Vec<String>,
}

impl Recording {
    /// Read a whole file.
    pub fn read(path: impl AsRef<Path>, options: &ReadOptions) -> Result<Self, RecordingError> {
        Self::drain(RecordingReader::open(path, options)?)
    }

    /// Read a whole recording from memory.
    pub fn from_bytes(
        name: &str,
        bytes: &[u8],
        options: &ReadOptions,
    ) -> Result<Self, RecordingError> {
        Self::drain(RecordingReader::from_bytes(name, bytes, options)?)
    }

    fn drain<R: std::io::BufRead>(mut r: RecordingReader<R>) -> Result<Self, RecordingError> {
        let mut all = RecordingChunk {
            values: vec![Vec::new(); r.info().channels.len()],
            ..RecordingChunk::default()
        };
        let mut c = RecordingChunk::default();
        while r.read_chunk(&mut c, DEFAULT_CHUNK_ROWS)? > 0 {
            all.time_s.extend_from_slice(&c.time_s);
            for (a, v) in all.values.iter_mut().zip(&c.values) {
                a.extend_from_slice(v);
            }
        }
        Ok(Self {
            info: r.info().clone(),
            time_s: all.time_s,
            values: all.values,
            warnings: r.warnings().to_vec(),
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True if there are no samples.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// A channel's values by name (with or without unit).
    pub fn channel(&self, name: &str) -> Option<&[f64]> {
        self.info
            .channel_index(name)
            .map(|i| self.values[i].as_slice())
    }
}

/// Read a whole (small) recording file: [`Recording::read`].
pub fn read_all(
    path: impl AsRef<Path>,
    options: &ReadOptions,
) -> Result<Recording, RecordingError> {
    Recording::read(path, options)
}
