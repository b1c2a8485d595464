//! Errors of the recording readers: every variant names the file and, where it applies, the
//! 1-based line and column (field number) of the offending cell.

/// An error while reading a recording.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// The operating system could not read the file. The cause is part of the message (with
    /// what to do), not a separate `source()` (`crate::report`: printed once).
    #[error("{file}: cannot read: {}", crate::report::io_problem(.error))]
    Io {
        /// The file.
        file: String,
        /// The I/O error.
        error: std::io::Error,
    },
    /// The file has no content at all (or only blank lines). The format cannot be told from no
    /// bytes, so the message names what any of them would start with.
    #[error(
        "{file}: the file is empty: expected a recording (a text export with a header row, then \
         data rows, or a MATLAB, HDF5, TDMS or Parquet file)"
    )]
    Empty {
        /// The file.
        file: String,
    },
    /// The file is not text: NUL bytes, invalid UTF-8 or control characters.
    #[error("{file}:{line}: binary data, not a text recording ({detail})")]
    Binary {
        /// The file.
        file: String,
        /// 1-based line.
        line: u64,
        /// What was found.
        detail: String,
    },
    /// The header (channel names, units, DynoWare key lines) is malformed.
    #[error("{file}:{line}: {message}")]
    Header {
        /// The file.
        file: String,
        /// 1-based line.
        line: u64,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A requested column is not in the header.
    #[error(
        "{file}:{line}: no column `{}` (columns in the header: {})",
        crate::textfile::quote(.name),
        crate::textfile::quote(.available)
    )]
    MissingColumn {
        /// The file.
        file: String,
        /// 1-based line of the header row.
        line: u64,
        /// The requested name.
        name: String,
        /// The names found, comma separated.
        available: String,
    },
    /// A data row has too few fields (or extra non-empty ones).
    #[error("{file}:{line}: expected {expected} fields, found {found}{hint}")]
    FieldCount {
        /// The file.
        file: String,
        /// 1-based line.
        line: u64,
        /// Fields in the header.
        expected: usize,
        /// Fields in this row.
        found: usize,
        /// Extra explanation (may be empty).
        hint: String,
    },
    /// A cell of a selected column is not a finite number.
    #[error(
        "{file}:{line}:{column}: `{text}` in column `{}` is not a finite number",
        crate::textfile::quote(.name)
    )]
    NotNumeric {
        /// The file.
        file: String,
        /// 1-based line.
        line: u64,
        /// 1-based column (field number).
        column: usize,
        /// The column name.
        name: String,
        /// The cell text (truncated).
        text: String,
    },
    /// The time column does not increase.
    #[error("{file}:{line}:{column}: time {time_s} s is not after the previous sample's {previous_s} s (time must increase strictly)")]
    TimeNotMonotonic {
        /// The file.
        file: String,
        /// 1-based line.
        line: u64,
        /// 1-based column of the time column.
        column: usize,
        /// This row's time.
        time_s: f64,
        /// The previous row's time.
        previous_s: f64,
    },
    /// The time column disagrees with the sample rate by more than half a sample period.
    #[error("{file}:{line}:{column}: time {time_s} s but sample {sample} at {rate_hz} Hz from t0 = {start_s} s is at {expected_s} s (time column inconsistent with the sample rate {rate_source})")]
    RateInconsistent {
        /// The file.
        file: String,
        /// 1-based line.
        line: u64,
        /// 1-based column of the time column.
        column: usize,
        /// This row's time.
        time_s: f64,
        /// 0-based sample index.
        sample: u64,
        /// The sample rate used.
        rate_hz: f64,
        /// Where the rate came from.
        rate_source: String,
        /// Time of sample 0.
        start_s: f64,
        /// Time expected for this sample.
        expected_s: f64,
    },
    /// No sample rate: no time column and none given.
    #[error("{file}: no sample rate: the file has no time column{extra}; give the sample rate (e.g. --sample-rate-hz 50000)")]
    NoSampleRate {
        /// The file.
        file: String,
        /// Extra explanation (may be empty).
        extra: String,
    },
    /// A header but no data rows.
    #[error("{file}:{line}: header found but no data rows follow")]
    NoData {
        /// The file.
        file: String,
        /// Line after the header.
        line: u64,
    },
    /// A bad option from the caller (sample rate, chunk size, axis mapping).
    #[error("{file}: {message}")]
    Option {
        /// The file.
        file: String,
        /// What is wrong.
        message: String,
    },
    /// A binary recording (.mat, TDMS, HDF5, Parquet) is malformed or unsupported; the message
    /// names the byte offset or the variable and what was expected.
    #[error("{file}: {message}")]
    Format {
        /// The file.
        file: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A requested variable / channel / dataset is not in a binary recording.
    #[error("{file}: no {what} `{name}`; the file holds: {available}")]
    MissingChannel {
        /// The file.
        file: String,
        /// `channel`, `time variable`.
        what: String,
        /// The requested name.
        name: String,
        /// What the file holds (names, lengths, types).
        available: String,
    },
}
