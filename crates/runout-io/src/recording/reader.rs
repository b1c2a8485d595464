//! The streaming reader: header interpretation at open, then data rows parsed chunk by chunk.

use super::error::RecordingError;
use super::header::{
    detect_decimal_comma, detect_delimiter, is_unit_row, key_line, meta_number, split_unit,
};
#[cfg(target_arch = "x86_64")]
use super::text::WideCells;
use super::text::{
    binary_issue, decode, delimiter_ends_numbers, fields, parse_common_cell, parse_leading_number,
    parse_number, trim_field,
};
use super::{Channel, Format, ReadOptions, RecordingChunk, RecordingInfo};
use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

mod parallel;

type Result<T> = std::result::Result<T, RecordingError>;

/// Longest accepted line; a longer one is reported (bounded memory on garbage input).
const MAX_LINE_BYTES: u64 = runout_core::limits::MAX_LINE_BYTES as u64;
/// Data rows inspected at open for the decimal separator and the time step.
const PEEK_ROWS: usize = 1000;
/// Default rows per chunk.
pub const DEFAULT_CHUNK_ROWS: usize = 65_536;

/// Lines of the input with their 1-based numbers; lines read ahead wait in `pending`.
struct LineSource<R> {
    src: R,
    pending: VecDeque<(u64, Vec<u8>)>,
    line_no: u64,
    bytes: u64,
    file: String,
    /// Table mode: lines starting with `#` are comments (skipped like blank lines).
    comments: bool,
    /// Data rows after the read-ahead (issue 18): a block of the input, parsed in place.
    block: Block,
}

/// A block of input bytes in which data lines are parsed where they lie (no per-line copy):
/// `data[pos..end]` is not consumed yet; a line cut at the block's end is moved to the front
/// and completed by the next read (the block grows up to one longest line, [`MAX_LINE_BYTES`]).
#[derive(Default)]
struct Block {
    data: Vec<u8>,
    pos: usize,
    end: usize,
    eof: bool,
}

/// Bytes read into a [`Block`] at a time.
const BLOCK_BYTES: usize = 1 << 18;

/// Where the next line of a block is, or why there is none.
enum NextLine {
    /// `data[start..start + len]` (without its line ending); `consumed` bytes with it.
    Line {
        start: usize,
        len: usize,
        consumed: usize,
    },
    /// No line left: the end of the input.
    End,
}

impl Block {
    /// The next complete line, reading more from `src` when the block holds only part of one.
    /// A line of [`MAX_LINE_BYTES`] bytes or more (without its ending) is an error at `line`.
    fn next_line<R: Read>(&mut self, src: &mut R, file: &str, line: u64) -> Result<NextLine> {
        loop {
            let rest = &self.data[self.pos..self.end];
            if let Some(k) = memchr::memchr(b'\n', rest) {
                if k as u64 >= MAX_LINE_BYTES {
                    return Err(long_line(file, line));
                }
                let start = self.pos;
                self.pos += k + 1;
                return Ok(NextLine::Line {
                    start,
                    len: k,
                    consumed: k + 1,
                });
            }
            if rest.len() as u64 >= MAX_LINE_BYTES {
                return Err(long_line(file, line));
            }
            if self.eof {
                if rest.is_empty() {
                    return Ok(NextLine::End);
                }
                let (start, len) = (self.pos, rest.len());
                self.pos = self.end;
                return Ok(NextLine::Line {
                    start,
                    len,
                    consumed: len,
                });
            }
            // keep the partial line, make room, read more
            self.data.copy_within(self.pos..self.end, 0);
            self.end -= self.pos;
            self.pos = 0;
            let want = (self.end + BLOCK_BYTES).max(BLOCK_BYTES);
            if self.data.len() < want {
                self.data.resize(want, 0);
            }
            let n = loop {
                match src.read(&mut self.data[self.end..]) {
                    Ok(n) => break n,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(error) => {
                        return Err(RecordingError::Io {
                            file: file.to_string(),
                            error,
                        })
                    }
                }
            };
            if n == 0 {
                self.eof = true;
            }
            self.end += n;
        }
    }
}

/// The error for a line of [`MAX_LINE_BYTES`] bytes or more.
fn long_line(file: &str, line: u64) -> RecordingError {
    RecordingError::Binary {
        file: file.to_string(),
        line,
        detail: format!("line longer than {MAX_LINE_BYTES} bytes"),
    }
}

impl<R: BufRead> LineSource<R> {
    /// Whether a line carries no data (blank, or a `#` comment in table mode).
    fn is_blank(&self, line: &[u8]) -> bool {
        let t = trim_field(line);
        t.is_empty() || (self.comments && t.first() == Some(&b'#'))
    }

    /// Next line from the underlying reader (not from `pending`), without its line ending.
    fn read_src(&mut self, buf: &mut Vec<u8>) -> Result<Option<u64>> {
        buf.clear();
        let n = (&mut self.src)
            .take(MAX_LINE_BYTES)
            .read_until(b'\n', buf)
            .map_err(|error| RecordingError::Io {
                file: self.file.clone(),
                error,
            })?;
        if n == 0 {
            return Ok(None);
        }
        self.bytes += n as u64;
        self.line_no += 1;
        if buf.last() == Some(&b'\n') {
            buf.pop();
        } else if n as u64 == MAX_LINE_BYTES {
            return Err(long_line(&self.file, self.line_no));
        }
        if buf.last() == Some(&b'\r') {
            buf.pop();
        }
        if self.line_no == 1 {
            if buf.starts_with(&[0xEF, 0xBB, 0xBF]) {
                buf.drain(..3);
            } else if buf.starts_with(&[0xFF, 0xFE]) || buf.starts_with(&[0xFE, 0xFF]) {
                return Err(RecordingError::Binary {
                    file: self.file.clone(),
                    line: 1,
                    detail: "UTF-16 text; export the recording as UTF-8 or ANSI text".into(),
                });
            }
        }
        Ok(Some(self.line_no))
    }

    /// Next line, first from the read-ahead queue.
    fn next(&mut self, buf: &mut Vec<u8>) -> Result<Option<u64>> {
        if let Some((n, line)) = self.pending.pop_front() {
            *buf = line;
            return Ok(Some(n));
        }
        self.read_src(buf)
    }

    /// Next non-blank line, checked to be text.
    fn next_nonblank(&mut self, buf: &mut Vec<u8>) -> Result<Option<u64>> {
        while let Some(n) = self.next(buf)? {
            if self.comments && trim_field(buf).first() == Some(&b'#') {
                continue;
            }
            self.check_text(n, buf)?;
            if !trim_field(buf).is_empty() {
                return Ok(Some(n));
            }
        }
        Ok(None)
    }

    fn check_text(&self, line: u64, buf: &[u8]) -> Result<()> {
        match binary_issue(buf) {
            Some(detail) => Err(RecordingError::Binary {
                file: self.file.clone(),
                line,
                detail,
            }),
            None => Ok(()),
        }
    }
}

/// What to do with each field of a data row.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Slot {
    Skip,
    Time,
    Channel(usize),
}

/// A streaming reader of one recording (generic CSV/TSV or Kistler DynoWare text export).
///
/// Opening reads only the header and up to 1000 data rows (kept for the reader); then
/// [`RecordingReader::read_chunk`] parses rows into a reusable [`RecordingChunk`], so memory is bounded by
/// the chunk size whatever the file length. After an error the reader is finished.
pub struct RecordingReader<R> {
    lines: LineSource<R>,
    info: RecordingInfo,
    slots: Vec<Slot>,
    time_scale: f64,
    time_column: usize,
    sample: u64,
    previous_time: f64,
    warnings: Vec<String>,
    buf: Vec<u8>,
    chunk_rows: usize,
    finished: bool,
    /// A binary format (.mat, TDMS, HDF5, Parquet) delivering the chunks instead of the lines.
    binary: Option<Box<crate::formats::BinaryRecording>>,
    /// Table mode ([`RecordingReader::table_from_reader`]): the line number of each row of the
    /// last chunk.
    row_lines: Option<Vec<u64>>,
    /// The file a text recording was opened from, when the process allows its data rows to be
    /// mapped instead of read ([`crate::mapped::allow_mapped_files`]; used by the parallel
    /// parse).
    mappable: Option<File>,
    /// Whether the data rows were parsed from a mapping (for tests).
    data_mapped: bool,
}

impl<R: BufRead + Send + 'static> RecordingReader<R> {
    /// The same reader over a boxed source, so that readers of files, of bytes in memory and of
    /// the binary formats share one type.
    pub fn boxed(self) -> RecordingReader<Box<dyn BufRead + Send>> {
        let LineSource {
            src,
            pending,
            line_no,
            bytes,
            file,
            comments,
            block,
        } = self.lines;
        RecordingReader {
            lines: LineSource {
                src: Box::new(src),
                pending,
                line_no,
                bytes,
                file,
                comments,
                block,
            },
            info: self.info,
            slots: self.slots,
            time_scale: self.time_scale,
            time_column: self.time_column,
            sample: self.sample,
            previous_time: self.previous_time,
            warnings: self.warnings,
            buf: self.buf,
            chunk_rows: self.chunk_rows,
            finished: self.finished,
            binary: self.binary,
            row_lines: self.row_lines,
            mappable: self.mappable,
            data_mapped: self.data_mapped,
        }
    }
}

impl RecordingReader<BufReader<File>> {
    /// Open a file and read its header (see [`RecordingReader::from_reader`]).
    pub fn open(path: impl AsRef<Path>, options: &ReadOptions) -> Result<Self> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let f = File::open(path).map_err(|error| RecordingError::Io {
            file: file.clone(),
            error,
        })?;
        let mappable = if crate::mapped::allowed() {
            f.try_clone().ok()
        } else {
            None
        };
        let mut r = Self::from_reader(BufReader::with_capacity(1 << 16, f), &file, options)?;
        r.info.file_bytes = std::fs::metadata(path).ok().map(|m| m.len());
        r.mappable = mappable;
        Ok(r)
    }
}

impl<'a> RecordingReader<std::io::Cursor<&'a [u8]>> {
    /// Read a recording held in memory; `name` is used in messages.
    pub fn from_bytes(name: &str, bytes: &'a [u8], options: &ReadOptions) -> Result<Self> {
        let mut r = Self::from_reader(std::io::Cursor::new(bytes), name, options)?;
        r.info.file_bytes = Some(bytes.len() as u64);
        Ok(r)
    }
}

impl<R: BufRead> RecordingReader<R> {
    /// The same reader with its size in bytes set (for progress), when the source knows it.
    pub fn with_file_bytes(mut self, bytes: Option<u64>) -> Self {
        self.info.file_bytes = bytes;
        self
    }

    /// Read the header of a recording from `src`; `file` names it in messages.
    ///
    /// Recognises a DynoWare export by its first line (`DynoWare,Version …`), else a generic
    /// CSV/TSV with a header row and an optional unit row. The delimiter (comma, semicolon, tab)
    /// and decimal commas are detected. The sample rate is, in order: `options.sample_rate_hz`,
    /// the DynoWare `Sampling rate [Hz]` line, the time column's step; a time column is then
    /// checked row by row against it (strictly increasing, within half a sample period).
    pub fn from_reader(src: R, file: &str, options: &ReadOptions) -> Result<Self> {
        Self::from_reader_mode(src, file, options, false)
    }

    /// Table mode, for tables whose columns are interpreted by the caller (the displacement
    /// signal, `crate::displacement`): every column is a channel (no time column is detected or
    /// checked; the sample rate is not used and reported as 1 Hz), lines starting with `#` are
    /// comments, and [`RecordingReader::chunk_lines`] gives the line of each row.
    pub(crate) fn table_from_reader(src: R, file: &str) -> Result<Self> {
        Self::from_reader_mode(src, file, &ReadOptions::new(), true)
    }

    fn from_reader_mode(src: R, file: &str, options: &ReadOptions, table: bool) -> Result<Self> {
        options.validate(file)?;
        let mut lines = LineSource {
            src,
            pending: VecDeque::new(),
            line_no: 0,
            bytes: 0,
            file: file.to_string(),
            comments: table,
            block: Block::default(),
        };
        let mut buf = Vec::new();
        let Some(first_no) = lines.next_nonblank(&mut buf)? else {
            return Err(RecordingError::Empty { file: file.into() });
        };
        let mut warnings = Vec::new();
        let header = if buf.len() >= 8 && buf[..8].eq_ignore_ascii_case(b"dynoware") {
            read_dynoware_header(&mut lines, &mut buf, first_no, &mut warnings)?
        } else {
            read_generic_header(&mut lines, &mut buf, first_no)?
        };
        // read ahead the first data rows
        let mut peeked = 0;
        while peeked < PEEK_ROWS {
            let mut l = Vec::new();
            match lines.read_src(&mut l)? {
                Some(n) => {
                    if !lines.is_blank(&l) {
                        peeked += 1;
                    }
                    lines.pending.push_back((n, l));
                }
                None => break,
            }
        }
        let first_data = lines
            .pending
            .iter()
            .find(|(_, l)| !lines.is_blank(l))
            .map(|(n, l)| (*n, l.clone()));
        let Some((_, first_data)) = first_data else {
            return Err(RecordingError::NoData {
                file: file.into(),
                line: lines.line_no + 1,
            });
        };
        let delim = header.delimiter;
        let decimal_comma = detect_decimal_comma(&first_data, delim);
        Self::assemble(lines, header, decimal_comma, options, warnings, table)
    }

    /// Resolve columns, sample rate and time checks from the parsed header.
    fn assemble(
        lines: LineSource<R>,
        header: HeaderParts,
        decimal_comma: bool,
        options: &ReadOptions,
        mut warnings: Vec<String>,
        table: bool,
    ) -> Result<Self> {
        let file = lines.file.clone();
        let columns = header.columns(&mut warnings);
        let available = columns
            .iter()
            .map(|c| c.header.clone())
            .collect::<Vec<_>>()
            .join(", ");
        let missing = |name: &str| RecordingError::MissingColumn {
            file: file.clone(),
            line: header.names_line,
            name: name.to_string(),
            available: available.clone(),
        };
        let time = match &options.time_column {
            Some(name) => Some(find_column(&columns, name).ok_or_else(|| missing(name))?),
            None if table => None,
            None => columns.iter().position(|c| {
                matches!(
                    c.name.to_ascii_lowercase().as_str(),
                    "time" | "t" | "zeit" | "timestamp"
                )
            }),
        };
        let selected: Vec<usize> = match &options.channels {
            Some(names) => names
                .iter()
                .map(|n| find_column(&columns, n).ok_or_else(|| missing(n)))
                .collect::<Result<_>>()?,
            None => (0..columns.len()).filter(|&i| Some(i) != time).collect(),
        };
        let mut slots = vec![Slot::Skip; columns.len()];
        for (k, &i) in selected.iter().enumerate() {
            slots[i] = Slot::Channel(k);
        }
        let time_scale = match time {
            Some(i) => {
                slots[i] = Slot::Time;
                time_unit_scale(&columns[i]).ok_or_else(|| RecordingError::Header {
                    file: file.clone(),
                    line: header.names_line,
                    message: format!(
                        "time column `{}` has unit `{}`; expected s, ms, us or min",
                        crate::textfile::quote(&columns[i].header),
                        crate::textfile::quote(&columns[i].unit.clone().unwrap_or_default())
                    ),
                })?
            }
            None => 1.0,
        };
        // sample rate: caller, DynoWare header, time column
        let times: Vec<f64> = match time {
            Some(i) => lines
                .pending
                .iter()
                .filter(|(_, l)| !trim_field(l).is_empty())
                .map_while(|(_, l)| {
                    fields(l, header.delimiter)
                        .nth(i)
                        .and_then(|f| parse_number(f, decimal_comma))
                })
                .map(|t| t * time_scale)
                .collect(),
            None => Vec::new(),
        };
        let (meta_rate, bad_meta_rate) = match header.sampling_rate(decimal_comma) {
            Ok(rate) => (rate, None),
            Err(bad) => (None, Some(bad)),
        };
        // rate over the strictly increasing prefix (a later defect is reported at its line)
        let increasing = 1 + times.windows(2).take_while(|w| w[1] > w[0]).count();
        let times = &times[..increasing.min(times.len())];
        let time_rate = (times.len() >= 2)
            .then(|| (times.len() - 1) as f64 / (times[times.len() - 1] - times[0]))
            .filter(|f| f.is_finite() && *f > 0.0);
        let (rate, source) = if table {
            (1.0, "not used (a table read by its caller)".to_string())
        } else if let Some(f) = options.sample_rate_hz {
            if let Some(m) = meta_rate {
                if ((m - f) / f).abs() > 1e-9 {
                    warnings.push(format!(
                        "{file}: sample rate {f} Hz given, but the header says {m} Hz; using {f} Hz"
                    ));
                }
            }
            (f, "given by the caller".to_string())
        } else if let Some(m) = meta_rate {
            (m, "from the header's sampling-rate line".to_string())
        } else if let Some(t) = time_rate {
            (t, "estimated from the time column's first rows".to_string())
        } else {
            let mut extra = if time.is_some() {
                " with at least two valid rows".to_string()
            } else {
                String::new()
            };
            if let Some(bad) = &bad_meta_rate {
                extra.push_str(&format!(
                    " and the header's {} is not a sample rate",
                    bad.describe()
                ));
            }
            return Err(RecordingError::NoSampleRate { file, extra });
        };
        if let (Some(bad), false) = (&bad_meta_rate, table) {
            warnings.push(format!(
                "{file}:{}: the header's {} is not a sample rate (a positive, finite number of Hz \
                 expected): ignored, using {rate} Hz {source}",
                bad.line,
                bad.describe()
            ));
        }
        let start = options.start_time_s.unwrap_or(0.0);
        let info = RecordingInfo {
            file: file.clone(),
            format: header.format.clone(),
            delimiter: header.delimiter as char,
            decimal_comma,
            metadata: header.metadata.clone(),
            time_column: time.map(|i| columns[i].clone()),
            channels: selected.iter().map(|&i| columns[i].clone()).collect(),
            columns,
            sample_rate_hz: rate,
            sample_rate_source: source,
            start_time_s: times.first().copied().unwrap_or(start),
            expected_samples: header.expected_samples(),
            header_lines: header.last_line,
            file_bytes: None,
        };
        Ok(Self {
            lines,
            info,
            slots,
            time_scale,
            time_column: time.map_or(0, |i| i + 1),
            sample: 0,
            previous_time: f64::NEG_INFINITY,
            warnings,
            buf: Vec::new(),
            chunk_rows: if options.chunk_rows == 0 {
                DEFAULT_CHUNK_ROWS
            } else {
                options.chunk_rows
            },
            finished: false,
            binary: None,
            row_lines: table.then(Vec::new),
            mappable: None,
            data_mapped: false,
        })
    }

    /// A reader delivering the chunks of a binary recording (see [`crate::formats`]); `src` is
    /// not read.
    pub(crate) fn from_binary(src: R, rec: crate::formats::BinaryRecording) -> Self {
        let info = rec.info().clone();
        Self {
            lines: LineSource {
                src,
                pending: VecDeque::new(),
                line_no: 0,
                bytes: 0,
                file: info.file.clone(),
                comments: false,
                block: Block::default(),
            },
            info,
            slots: Vec::new(),
            time_scale: 1.0,
            time_column: 0,
            sample: 0,
            previous_time: f64::NEG_INFINITY,
            warnings: Vec::new(),
            buf: Vec::new(),
            chunk_rows: DEFAULT_CHUNK_ROWS,
            finished: false,
            binary: Some(Box::new(rec)),
            row_lines: None,
            mappable: None,
            data_mapped: false,
        }
    }

    /// What the header said: format, channels, units, metadata, sample rate.
    pub fn info(&self) -> &RecordingInfo {
        &self.info
    }

    /// Non-fatal findings so far (rate given vs header, sample count vs header, unit clashes).
    pub fn warnings(&self) -> &[String] {
        if let Some(b) = &self.binary {
            return b.warnings();
        }
        &self.warnings
    }

    /// Bytes consumed from the input so far (for progress bars), including read-ahead.
    pub fn bytes_read(&self) -> u64 {
        if let Some(b) = &self.binary {
            return b.bytes_read();
        }
        self.lines.bytes
    }

    /// The line number (counted from 1) of data sample `sample` (0-based) of a text
    /// recording, read on from here (serially); `None` for a binary format, or when that sample
    /// was already read or the data end before it. For an error message that names a sample
    /// found implausible after parsing, e.g. a force beyond any dynamometer's range (the
    /// chunks carry no line numbers: blank lines make them differ from the rows').
    ///
    /// ```
    /// use runout_io::recording::{ReadOptions, RecordingReader};
    /// let text = "time_s,Fx_N\n0,1\n\n \n0.001,2\n0.002,3\n";
    /// let open = || RecordingReader::from_reader(text.as_bytes(), "rec.csv", &ReadOptions::new());
    /// assert_eq!(open()?.line_of_sample(0)?, Some(2));
    /// assert_eq!(open()?.line_of_sample(2)?, Some(6)); // after two blank lines
    /// assert_eq!(open()?.line_of_sample(3)?, None); // three samples only
    /// # Ok::<(), runout_io::recording::RecordingError>(())
    /// ```
    pub fn line_of_sample(mut self, sample: u64) -> Result<Option<u64>> {
        if self.binary.is_some() || sample < self.sample {
            return Ok(None);
        }
        self.row_lines = Some(Vec::new());
        let mut chunk = RecordingChunk::default();
        loop {
            let first = self.sample;
            let rows = self.read_chunk(&mut chunk, DEFAULT_CHUNK_ROWS)?;
            if rows == 0 {
                return Ok(None);
            }
            if sample < first + rows as u64 {
                return Ok(self.chunk_lines().get((sample - first) as usize).copied());
            }
        }
    }

    /// Samples delivered so far.
    pub fn samples_read(&self) -> u64 {
        if let Some(b) = &self.binary {
            return b.samples_read();
        }
        self.sample
    }

    /// Fill `chunk` (cleared first, capacity kept) with up to `max_rows` rows; returns the
    /// number of rows, 0 at the end of the data.
    pub fn read_chunk(&mut self, chunk: &mut RecordingChunk, max_rows: usize) -> Result<usize> {
        if let Some(b) = &mut self.binary {
            return b.read_chunk(chunk, max_rows);
        }
        let mut rows = self.read_pending_rows(chunk, max_rows)?;
        if rows < max_rows && !self.finished {
            if let Err(e) = self.read_block_rows(chunk, max_rows, &mut rows) {
                self.finished = true;
                return Err(e);
            }
        }
        Ok(rows)
    }

    /// `chunk` emptied for the next rows (text recordings), then filled with the lines read
    /// ahead at open, up to `max_rows` of them: the rows taken (0 once finished). An error
    /// finishes the reader.
    fn read_pending_rows(&mut self, chunk: &mut RecordingChunk, max_rows: usize) -> Result<usize> {
        chunk.first_sample = self.sample;
        chunk.time_s.clear();
        chunk.values.resize_with(self.info.channels.len(), Vec::new);
        for v in &mut chunk.values {
            v.clear();
        }
        if let Some(l) = &mut self.row_lines {
            l.clear();
        }
        if self.finished {
            return Ok(0);
        }
        let mut buf = std::mem::take(&mut self.buf);
        let mut rows = 0;
        // the lines read ahead at open, one by one
        let result = loop {
            if rows == max_rows || self.lines.pending.is_empty() {
                break Ok(());
            }
            let line = match self.lines.next(&mut buf) {
                Ok(Some(n)) => n,
                Ok(None) => unreachable!("a pending line"),
                Err(e) => break Err(e),
            };
            if self.lines.is_blank(&buf) {
                continue;
            }
            if let Err(e) = self.parse_row(line, &buf, chunk) {
                break Err(e);
            }
            if let Some(l) = &mut self.row_lines {
                l.push(line);
            }
            rows += 1;
        };
        self.buf = buf;
        if result.is_err() {
            self.finished = true;
        }
        result.map(|()| rows)
    }

    /// The rows after the read-ahead, parsed in place in the input block (issue 18: no copy of
    /// each line); the same line numbers, blank/comment skipping and errors as line by line.
    fn read_block_rows(
        &mut self,
        chunk: &mut RecordingChunk,
        max_rows: usize,
        rows: &mut usize,
    ) -> Result<()> {
        let mut block = std::mem::take(&mut self.lines.block);
        let result = loop {
            if *rows == max_rows {
                break Ok(());
            }
            let next = block.next_line(
                &mut self.lines.src,
                &self.lines.file,
                self.lines.line_no + 1,
            );
            let (start, mut len) = match next {
                Ok(NextLine::Line {
                    start,
                    len,
                    consumed,
                }) => {
                    self.lines.bytes += consumed as u64;
                    (start, len)
                }
                Ok(NextLine::End) => {
                    self.finish();
                    break Ok(());
                }
                Err(e) => {
                    self.lines.line_no += 1;
                    break Err(e);
                }
            };
            self.lines.line_no += 1;
            let line = self.lines.line_no;
            if len > 0 && block.data[start + len - 1] == b'\r' {
                len -= 1;
            }
            let row = &block.data[start..start + len];
            if self.lines.is_blank(row) {
                continue;
            }
            if let Err(e) = self.parse_row(line, row, chunk) {
                break Err(e);
            }
            if let Some(l) = &mut self.row_lines {
                l.push(line);
            }
            *rows += 1;
        };
        self.lines.block = block;
        result
    }

    /// Table mode: the line number of each row of the last chunk (empty otherwise).
    pub(crate) fn chunk_lines(&self) -> &[u64] {
        self.row_lines.as_deref().unwrap_or(&[])
    }

    /// Next chunk of the configured size (`ReadOptions::chunk_rows`), `None` at the end.
    pub fn next_chunk(&mut self) -> Result<Option<RecordingChunk>> {
        let mut c = RecordingChunk::default();
        let n = self.read_chunk(&mut c, self.chunk_rows)?;
        Ok((n > 0).then_some(c))
    }

    fn finish(&mut self) {
        self.finished = true;
        if let Some(n) = self.info.expected_samples {
            if n != self.sample {
                self.warnings.push(format!(
                    "{}: the header announces {n} samples per channel, the file has {}",
                    self.info.file, self.sample
                ));
            }
        }
    }

    /// The row parser of this reader (shared by the parse workers of [`Self::for_each_chunk`]).
    fn row_parser(&self) -> RowParser<'_> {
        RowParser {
            slots: &self.slots,
            delim: self.info.delimiter as u8,
            dc: self.info.decimal_comma,
            time_scale: self.time_scale,
            info: &self.info,
        }
    }

    /// Parse one data row into `chunk` (hot loop).
    fn parse_row(&mut self, line: u64, row: &[u8], chunk: &mut RecordingChunk) -> Result<()> {
        let mut time = None;
        let mut failure = self
            .row_parser()
            .parse(line, row, &mut chunk.values, &mut time)
            .err();
        if failure.is_none() {
            failure = self.check_time(line, time, chunk).err();
        }
        if let Some(e) = failure {
            let len = chunk.time_s.len();
            for v in &mut chunk.values {
                v.truncate(len);
            }
            return Err(e);
        }
        self.sample += 1;
        Ok(())
    }

    /// Check the time cell (if any) and push the sample time.
    fn check_time(
        &mut self,
        line: u64,
        time: Option<f64>,
        chunk: &mut RecordingChunk,
    ) -> Result<()> {
        let t = checked_time(
            &self.info,
            self.time_column,
            self.sample,
            &mut self.previous_time,
            time,
            || line,
        )?;
        chunk.time_s.push(t);
        Ok(())
    }
}

/// The time of sample `sample` (at line `line()`, computed only for an error): the time cell
/// `time` checked against the previous one (strictly increasing) and against the sample rate
/// (within half a period of t₀ + sample/f_s), or t₀ + sample/f_s without a time column.
/// `previous` is updated.
#[inline]
fn checked_time(
    info: &RecordingInfo,
    time_column: usize,
    sample: u64,
    previous: &mut f64,
    time: Option<f64>,
    line: impl Fn() -> u64,
) -> Result<f64> {
    let fs = info.sample_rate_hz;
    let expected = info.start_time_s + sample as f64 / fs;
    let Some(t) = time else {
        return Ok(expected);
    };
    if t <= *previous {
        return Err(RecordingError::TimeNotMonotonic {
            file: info.file.clone(),
            line: line(),
            column: time_column,
            time_s: t,
            previous_s: *previous,
        });
    }
    if (t - expected).abs() > 0.5 / fs {
        return Err(RecordingError::RateInconsistent {
            file: info.file.clone(),
            line: line(),
            column: time_column,
            time_s: t,
            sample,
            rate_hz: fs,
            rate_source: info.sample_rate_source.clone(),
            start_s: info.start_time_s,
            expected_s: expected,
        });
    }
    *previous = t;
    Ok(t)
}

/// The cells of a data row into channel values and the time (scaled to s): the part of the
/// row parsing that needs no state of the reader, so parse workers can share it.
#[derive(Clone, Copy)]
struct RowParser<'a> {
    slots: &'a [Slot],
    delim: u8,
    dc: bool,
    time_scale: f64,
    info: &'a RecordingInfo,
}

impl RowParser<'_> {
    /// Parse the cells of `row` (line `line`): each channel's value pushed to `values`, the
    /// time cell (if any) to `time`. On an error some channels may have one value too many
    /// (the caller truncates).
    #[inline]
    fn parse(
        &self,
        line: u64,
        row: &[u8],
        values: &mut [Vec<f64>],
        time: &mut Option<f64>,
    ) -> Result<()> {
        let delim = self.delim;
        let dc = self.dc;
        let fused = delimiter_ends_numbers(delim, dc);
        let mut n_fields = 0;
        // the fields of the row by position (as `fields`), each parsed where it lies: a common
        // number cell in one pass that also finds its end, anything else split off first
        let mut start = 0;
        for j in 0.. {
            let slot = self.slots.get(j);
            n_fields = j + 1;
            let leading = match slot {
                Some(Slot::Channel(_) | Slot::Time) if fused => {
                    parse_leading_number(&row[start..], delim, dc)
                }
                _ => None,
            };
            let end = if let Some((v, len)) = leading {
                match slot {
                    Some(&Slot::Channel(k)) => values[k].push(v),
                    _ => *time = Some(v * self.time_scale),
                }
                start + len
            } else {
                let end = row[start..]
                    .iter()
                    .position(|&c| c == delim)
                    .map_or(row.len(), |k| start + k);
                let f = &row[start..end];
                match slot {
                    Some(Slot::Skip) => {}
                    Some(&slot) => match parse_number(f, dc) {
                        Some(v) => match slot {
                            Slot::Channel(k) => values[k].push(v),
                            _ => *time = Some(v * self.time_scale),
                        },
                        None => return Err(self.cell_error(line, row, j, f)),
                    },
                    None if trim_field(f).is_empty() => {}
                    None => return Err(self.field_count_error(line, row)),
                }
                end
            };
            if end == row.len() {
                break;
            }
            start = end + 1;
        }
        if n_fields < self.slots.len() {
            return Err(self.field_count_error(line, row));
        }
        Ok(())
    }

    /// Whether [`RowParser::parse_common_line`] may be tried: a delimiter that cannot be part
    /// of a number, and every field a channel or the time (no skipped column, whose cell may
    /// hold anything).
    fn common_lines(&self) -> bool {
        delimiter_ends_numbers(self.delim, self.dc)
            && !self.slots.is_empty()
            && !self.slots.contains(&Slot::Skip)
    }

    /// Parse the line at the start of `rest` when it is a common row: one common number cell
    /// per slot ([`parse_common_cell`]), separated by the delimiter and ended by `\n` or
    /// `\r\n`. Returns the bytes of the line with its ending; values pushed and `time` set as
    /// [`RowParser::parse`] would for the same row. `None` for any other line, with some
    /// channels possibly one value longer (the caller truncates) and nothing else changed: the
    /// line then goes through [`RowParser::parse`] (issue 18: a common row needs no search for
    /// its end before its cells are parsed, ≈ 7 % of the parse).
    #[inline]
    fn parse_common_line(
        &self,
        rest: &[u8],
        values: &mut [Vec<f64>],
        time: &mut Option<f64>,
    ) -> Option<usize> {
        let last = self.slots.len() - 1;
        let mut start = 0;
        for (j, slot) in self.slots.iter().enumerate() {
            let (v, len, end) = parse_common_cell(&rest[start..], self.delim, self.dc)?;
            match *slot {
                Slot::Channel(k) => values[k].push(v),
                Slot::Time => *time = Some(v * self.time_scale),
                Slot::Skip => return None,
            }
            let at = start + len;
            if j < last {
                if end != self.delim {
                    return None;
                }
                start = at + 1;
            } else {
                let consumed = match end {
                    b'\n' => at + 1,
                    b'\r' if rest.get(at + 1) == Some(&b'\n') => at + 2,
                    _ => return None,
                };
                // (a line this long is an error the full path reports)
                return (consumed <= MAX_LINE_BYTES as usize).then_some(consumed);
            }
        }
        None
    }

    /// The common row `bytes[pos..]` whose cells end at the indexed positions `from + ends[j]`
    /// (a structural index: the delimiters and the line feed of the row, in order): its channel
    /// values pushed to `values` and its time cell's value returned (scaled; NaN without a
    /// time column). `None` when a cell ends at another byte or is not a plain number cell
    /// ([`WideCells::number_cell`]), with values possibly pushed (the caller truncates). For a
    /// row it takes, values and time are [`RowParser::parse_common_line`]'s (the same cells
    /// parsed to the same bits), the line's length aside (the caller checks it).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "ssse3,sse4.1")]
    #[inline]
    pub(super) fn indexed_row(
        &self,
        wide: WideCells,
        bytes: &[u8],
        pos: usize,
        from: usize,
        ends: &[u32],
        values: &mut [Vec<f64>],
    ) -> Option<f64> {
        let last = ends.len().checked_sub(1)?;
        let mut start = pos;
        let mut time = f64::NAN;
        for (j, (&e, slot)) in ends.iter().zip(self.slots).enumerate() {
            let e = from + e as usize;
            let mut end = e;
            if j < last {
                if bytes[e] != self.delim {
                    return None;
                }
            } else {
                if bytes[e] != b'\n' {
                    return None;
                }
                if end > start && bytes[end - 1] == b'\r' {
                    end -= 1;
                }
            }
            let v = wide.number_cell(bytes, start, end.checked_sub(start)?, self.dc)?;
            match *slot {
                Slot::Channel(k) => values[k].push(v),
                Slot::Time => time = v * self.time_scale,
                Slot::Skip => return None,
            }
            start = e + 1;
        }
        Some(time)
    }

    fn cell_error(&self, line: u64, row: &[u8], j: usize, cell: &[u8]) -> RecordingError {
        if let Some(detail) = binary_issue(row) {
            return RecordingError::Binary {
                file: self.info.file.clone(),
                line,
                detail,
            };
        }
        let mut text = decode(trim_field(cell));
        if text.chars().count() > 40 {
            text = text.chars().take(40).collect::<String>() + "…";
        }
        // control characters escaped: a lone `\r` printed raw sent a terminal's cursor back
        // over the file and line of the message
        let text = crate::textfile::quote(&text);
        RecordingError::NotNumeric {
            file: self.info.file.clone(),
            line,
            column: j + 1,
            name: self.info.columns[j].header.clone(),
            text,
        }
    }

    fn field_count_error(&self, line: u64, row: &[u8]) -> RecordingError {
        if let Some(detail) = binary_issue(row) {
            return RecordingError::Binary {
                file: self.info.file.clone(),
                line,
                detail,
            };
        }
        let delim = self.info.delimiter as u8;
        let found = fields(row, delim).count();
        let hint = if self.info.delimiter == ',' && row.contains(&b'.') {
            String::new()
        } else if self.info.delimiter == ',' {
            " (decimal commas need a semicolon or tab delimiter)".to_string()
        } else {
            String::new()
        };
        RecordingError::FieldCount {
            file: self.info.file.clone(),
            line,
            expected: self.slots.len(),
            found,
            hint,
        }
    }
}

/// Scale of a time column's unit to seconds.
fn time_unit_scale(c: &Channel) -> Option<f64> {
    match c.unit.as_deref().map(str::trim) {
        None | Some("") | Some("s") | Some("sec") => Some(1.0),
        Some("ms") => Some(1e-3),
        Some("us") | Some("µs") | Some("μs") => Some(1e-6),
        Some("min") => Some(60.0),
        _ => None,
    }
}

/// Find a column by its full header text or by its name without unit (exact, then
/// case-insensitive).
pub(crate) fn find_column(columns: &[Channel], name: &str) -> Option<usize> {
    let n = name.trim();
    let base = split_unit(n).0;
    columns
        .iter()
        .position(|c| c.header == n)
        .or_else(|| columns.iter().position(|c| c.name == n))
        .or_else(|| {
            columns
                .iter()
                .position(|c| c.header.eq_ignore_ascii_case(n) || c.name.eq_ignore_ascii_case(n))
        })
        .or_else(|| {
            columns
                .iter()
                .position(|c| c.name.eq_ignore_ascii_case(&base))
        })
}

/// The parsed header before columns are resolved.
struct HeaderParts {
    format: Format,
    delimiter: u8,
    metadata: Vec<(String, String)>,
    /// The line of each `metadata` entry.
    metadata_lines: Vec<u64>,
    names: Vec<String>,
    units: Option<Vec<String>>,
    names_line: u64,
    last_line: u64,
}

/// A DynoWare `Sampling rate` line whose value is no sample rate (0, negative, not finite, not a
/// number): ignored, with a warning naming it.
struct BadRate {
    line: u64,
    key: String,
    value: String,
}

impl BadRate {
    /// `` `Sampling rate [Hz]: 0` ``: the line's key and value, as messages quote it.
    fn describe(&self) -> String {
        format!("`{}: {}`", self.key, self.value)
    }
}

impl HeaderParts {
    /// Columns with units from the names and the unit row (the unit row wins on a clash).
    fn columns(&self, warnings: &mut Vec<String>) -> Vec<Channel> {
        let mut names = self.names.clone();
        while names.len() > 1 && names.last().is_some_and(|n| n.is_empty()) {
            names.pop();
        }
        names
            .iter()
            .enumerate()
            .map(|(j, h)| {
                let header = if h.is_empty() {
                    format!("column{}", j + 1)
                } else {
                    h.clone()
                };
                let (name, mut unit) = split_unit(&header);
                if let Some(u) = self
                    .units
                    .as_ref()
                    .and_then(|u| u.get(j))
                    .filter(|u| !u.is_empty())
                {
                    if unit.as_ref().is_some_and(|h| h != u) {
                        warnings.push(format!(
                            "column `{}`: unit row says `{}`, using it",
                            crate::textfile::quote(&header),
                            crate::textfile::quote(u)
                        ));
                    }
                    unit = Some(u.clone());
                }
                Channel {
                    name,
                    header,
                    unit,
                    column: j + 1,
                }
            })
            .collect()
    }

    /// Index of the first metadata entry whose key starts with `prefix` (lower case).
    fn meta_index(&self, prefix: &str) -> Option<usize> {
        self.metadata
            .iter()
            .position(|(k, _)| k.to_ascii_lowercase().starts_with(prefix))
    }

    fn meta(&self, prefix: &str) -> Option<(&str, &str)> {
        let (k, v) = &self.metadata[self.meta_index(prefix)?];
        Some((k.as_str(), v.as_str()))
    }

    /// `Sampling rate [Hz]` (or `[kHz]`) from DynoWare metadata, in Hz: `Ok(None)` without such
    /// a line, [`BadRate`] when its value is not a positive, finite number.
    fn sampling_rate(&self, decimal_comma: bool) -> std::result::Result<Option<f64>, BadRate> {
        let Some(i) = self.meta_index("sampling rate") else {
            return Ok(None);
        };
        let (k, v) = &self.metadata[i];
        let scale = if k.to_ascii_lowercase().contains("khz") {
            1e3
        } else {
            1.0
        };
        match meta_number(v, decimal_comma).map(|f| f * scale) {
            Some(f) if f.is_finite() && f > 0.0 => Ok(Some(f)),
            _ => Err(BadRate {
                line: self.metadata_lines.get(i).copied().unwrap_or(0),
                key: k.clone(),
                value: v.clone(),
            }),
        }
    }

    fn expected_samples(&self) -> Option<u64> {
        let (_, v) = self.meta("samples per channel")?;
        v.trim().parse().ok()
    }
}

/// Header of a DynoWare export; `buf` holds line 1.
fn read_dynoware_header<R: BufRead>(
    lines: &mut LineSource<R>,
    buf: &mut Vec<u8>,
    first_no: u64,
    warnings: &mut Vec<String>,
) -> Result<HeaderParts> {
    let file = lines.file.clone();
    let header_err = |line: u64, message: String| RecordingError::Header {
        file: file.clone(),
        line,
        message,
    };
    let delimiter = match buf.get(8) {
        Some(&d) if d == b',' || d == b';' || d == b'\t' => d,
        _ => {
            return Err(header_err(
                first_no,
                "expected `DynoWare` followed by a comma, semicolon or tab".into(),
            ))
        }
    };
    let first = decode(buf);
    let version = first[9..]
        .trim()
        .trim_end_matches(delimiter as char)
        .trim()
        .to_string();
    let mut metadata = Vec::new();
    let mut metadata_lines = Vec::new();
    let (names_line, names) = loop {
        let Some(n) = lines.next_nonblank(buf)? else {
            return Err(header_err(
                lines.line_no,
                "DynoWare header ended before the channel-name row (e.g. `Time,Fx,Fy,Fz`)".into(),
            ));
        };
        if lines.bytes > runout_core::limits::MAX_HEADER_BYTES as u64 {
            return Err(header_err(
                n,
                format!(
                    "DynoWare header longer than {} bytes without a channel-name row",
                    runout_core::limits::MAX_HEADER_BYTES
                ),
            ));
        }
        let s = decode(buf);
        match key_line(&s, delimiter as char) {
            Some(kv) => {
                metadata.push(kv);
                metadata_lines.push(n);
            }
            None => break (n, split_cells(&s, delimiter)),
        }
    };
    let Some(units_line) = lines.next_nonblank(buf)? else {
        return Err(header_err(
            names_line + 1,
            "DynoWare header ended before the unit row (e.g. `s,N,N,N`)".into(),
        ));
    };
    let units = if is_unit_row(buf, delimiter, true) {
        Some(split_cells(&decode(buf), delimiter))
    } else {
        warnings.push(format!(
            "{file}:{units_line}: no unit row after the channel names (DynoWare normally has one)"
        ));
        lines.pending.push_front((units_line, std::mem::take(buf)));
        None
    };
    Ok(HeaderParts {
        format: Format::DynoWare { version },
        delimiter,
        metadata,
        metadata_lines,
        names,
        last_line: if units.is_some() {
            units_line
        } else {
            names_line
        },
        units,
        names_line,
    })
}

/// Header of a generic CSV/TSV; `buf` holds the header row.
fn read_generic_header<R: BufRead>(
    lines: &mut LineSource<R>,
    buf: &mut Vec<u8>,
    first_no: u64,
) -> Result<HeaderParts> {
    let header = std::mem::take(buf);
    let next = lines.next_nonblank(buf)?;
    let delimiter = detect_delimiter(&header, next.map(|_| buf.as_slice()));
    if fields(&header, delimiter).all(|f| parse_number(f, true).is_some()) {
        return Err(RecordingError::Header {
            file: lines.file.clone(),
            line: first_no,
            message: "the first line is numeric: a header row with the channel names is required \
                      (e.g. `time_s,fx_N,fy_N` or `Fx [N];Fy [N]`)"
                .into(),
        });
    }
    let names = split_cells(&decode(&header), delimiter);
    let mut last_line = first_no;
    let units = match next {
        Some(n) if is_unit_row(buf, delimiter, true) => {
            last_line = n;
            Some(split_cells(&decode(buf), delimiter))
        }
        Some(n) => {
            lines.pending.push_front((n, std::mem::take(buf)));
            None
        }
        None => None,
    };
    Ok(HeaderParts {
        format: Format::GenericCsv,
        delimiter,
        metadata: Vec::new(),
        metadata_lines: Vec::new(),
        names,
        units,
        names_line: first_no,
        last_line,
    })
}

/// Split a header line into trimmed cells (quotes removed).
fn split_cells(s: &str, delimiter: u8) -> Vec<String> {
    s.split(delimiter as char)
        .map(|c| c.trim().trim_matches('"').trim().to_string())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    /// A time column with a unit other than s, ms, us or min: the message quotes the column's
    /// name and unit (here the unit) with their control characters escaped (user text from the header; C0
    /// controls such as ESC are refused as binary data before, C1 controls such as CSI U+009B
    /// are valid UTF-8 text that a terminal may still obey).
    #[test]
    fn a_time_unit_error_escapes_the_header_text() {
        let t = "time [h\u{9b}2J\u{85}],Fx\n0,1\n1,2\n2,3\n";
        let e = RecordingReader::from_bytes("x.txt", t.as_bytes(), &ReadOptions::new())
            .err()
            .expect("an hour unit is refused");
        let shown = e.to_string();
        assert!(shown.contains("has unit"), "{shown}");
        assert!(!shown.chars().any(char::is_control), "{shown:?}");
        // (the name is the whole header cell; the unit is trimmed of white space, U+0085 too)
        assert!(shown.contains("`time [h\\u{9b}2J\\u{85}]`"), "{shown}");
        assert!(
            shown.contains("unit `h\\u{9b}2J`; expected s, ms, us or min"),
            "{shown}"
        );
    }

    /// A DynoWare `Sampling rate` that is no sample rate (0, negative, not finite, not a number)
    /// is ignored for the time column's step, as before, but no longer silently: a warning names
    /// the file, the line, the value, and the rate used instead (where it comes from).
    #[test]
    fn dynoware_rate_that_is_no_rate_is_a_warning_naming_the_line() {
        let text = |rate: &str| {
            format!(
                "DynoWare,Version 2.5.1.2\nFilename:,x.dwd\nSampling rate [Hz]:,{rate}\n\
                 Time,Fx,Fy\ns,N,N\n0,1,2\n0.5,3,4\n1,5,6\n1.5,7,8\n"
            )
        };
        for rate in ["0", "-10000", "inf", "NaN", "ten", ""] {
            let t = text(rate);
            let r = RecordingReader::from_bytes("x.txt", t.as_bytes(), &ReadOptions::new())
                .unwrap_or_else(|e| panic!("{rate}: {e}"));
            // the time column's step (0.5 s), exactly: 3 steps / 1.5 s
            assert_eq!(r.info().sample_rate_hz, 2.0, "{rate}");
            assert_eq!(
                r.warnings(),
                [format!(
                    "x.txt:3: the header's `Sampling rate [Hz]: {rate}` is not a sample rate (a \
                     positive, finite number of Hz expected): ignored, using 2 Hz estimated from \
                     the time column's first rows"
                )],
                "{rate}"
            );
            // a rate given by the caller is the one used, and the message says so
            let opts = ReadOptions::new().sample_rate_hz(2.0);
            let r = RecordingReader::from_bytes("x.txt", t.as_bytes(), &opts).unwrap();
            assert!(
                r.warnings()[0].ends_with("ignored, using 2 Hz given by the caller"),
                "{:?}",
                r.warnings()
            );
        }
        // a good rate: used, no warning (the time column agrees with it)
        let t = text("2");
        let r = RecordingReader::from_bytes("x.txt", t.as_bytes(), &ReadOptions::new()).unwrap();
        assert_eq!(r.info().sample_rate_hz, 2.0);
        assert!(r.warnings().is_empty(), "{:?}", r.warnings());
        // [kHz] scales; 1e306 kHz overflows to infinity: no rate either
        let t = text("1e306").replace("[Hz]", "[kHz]");
        let r = RecordingReader::from_bytes("x.txt", t.as_bytes(), &ReadOptions::new()).unwrap();
        assert!(r.warnings()[0].starts_with("x.txt:3: the header's `Sampling rate [kHz]: 1e306`"));
        // without a time column, the error says why the header's rate was not taken
        let t = "DynoWare,Version 2.5\nSampling rate [Hz]:,0\nFx,Fy\nN,N\n1,2\n3,4\n";
        let e = RecordingReader::from_bytes("x.txt", t.as_bytes(), &ReadOptions::new())
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains(
                "no time column and the header's `Sampling rate [Hz]: 0` is not a sample rate"
            ),
            "{e}"
        );
    }

    /// A source that gives at most 7 bytes per read, so that lines are cut anywhere between
    /// reads of the input block.
    struct Trickle<'a>(&'a [u8]);

    impl Read for Trickle<'_> {
        fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
            let n = self.0.len().min(out.len()).min(7);
            out[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }

    /// 200 000 rows (≈ 5 MB, many input blocks) with CRLF endings on every third line, a blank
    /// line every 997 lines and no line ending at the end; the value of each cell is its text.
    fn text() -> (Vec<u8>, Vec<[f64; 2]>) {
        let mut s = String::from("time_s,a_N,b_N\n");
        let mut rows = Vec::new();
        for k in 0..200_000u32 {
            let (a, b) = (
                format!("{:.4}", f64::from(k) * 0.37 - 5e3),
                format!("-{k}.5"),
            );
            s += &format!("{:.4},{a},{b}", f64::from(k) / 1e4);
            s += if k % 3 == 0 { "\r\n" } else { "\n" };
            if k % 997 == 0 {
                s += " \r\n";
            }
            rows.push([a.parse().unwrap(), b.parse().unwrap()]);
        }
        s.pop(); // the last line has no ending
        (s.into_bytes(), rows)
    }

    fn read_all<R: BufRead>(mut r: RecordingReader<R>, chunk_rows: usize) -> Result<Vec<[f64; 2]>> {
        let mut c = RecordingChunk::default();
        let mut out = Vec::new();
        let mut first = 0;
        while r.read_chunk(&mut c, chunk_rows)? > 0 {
            assert_eq!(c.first_sample, first);
            first += c.len() as u64;
            out.extend(c.values[0].iter().zip(&c.values[1]).map(|(a, b)| [*a, *b]));
        }
        Ok(out)
    }

    /// In-place parsing over input blocks gives every row, exactly, whatever the read sizes
    /// and chunk sizes, and counts every byte of the input.
    #[test]
    fn block_parsing_gives_every_row_across_reads() {
        let (bytes, rows) = text();
        let opts = ReadOptions::new();
        let r = RecordingReader::from_bytes("t.csv", &bytes, &opts).unwrap();
        assert_eq!(read_all(r, 65_536).unwrap(), rows);
        let mut r = RecordingReader::from_bytes("t.csv", &bytes, &opts).unwrap();
        let mut c = RecordingChunk::default();
        while r.read_chunk(&mut c, 1000).unwrap() > 0 {}
        assert_eq!(r.bytes_read(), bytes.len() as u64);
        let trickle = BufReader::with_capacity(5, Trickle(&bytes));
        let r = RecordingReader::from_reader(trickle, "t.csv", &opts).unwrap();
        assert_eq!(read_all(r, 777).unwrap(), rows);
    }

    /// A bad cell or an over-long line deep in the file is reported at its line and column,
    /// counted across blank lines and input blocks.
    #[test]
    fn block_parsing_errors_name_the_line() {
        let (bytes, _) = text();
        let text = String::from_utf8(bytes).unwrap();
        let mut lines: Vec<String> = text.split('\n').map(String::from).collect();
        lines[150_000] = "15.0,1.0,x7".into();
        let bad = lines.join("\n");
        let src = BufReader::with_capacity(5, Trickle(bad.as_bytes()));
        let trickle = RecordingReader::from_reader(src, "t.csv", &ReadOptions::new()).unwrap();
        let whole = RecordingReader::from_bytes("t.csv", bad.as_bytes(), &ReadOptions::new());
        for result in [read_all(trickle, 4096), read_all(whole.unwrap(), 4096)] {
            match result {
                Err(RecordingError::NotNumeric { line, column, .. }) => {
                    assert_eq!((line, column), (150_001, 3));
                }
                other => panic!("{:?}", other.map(|v| v.len())),
            }
        }
        for (len, long) in [
            (MAX_LINE_BYTES as usize, true),
            (MAX_LINE_BYTES as usize - 1, false),
        ] {
            let mut l = lines.clone();
            l[100_000] = "1".repeat(len);
            let src = BufReader::new(Cursor::new(l.join("\n").into_bytes()));
            let r = RecordingReader::from_reader(src, "t.csv", &ReadOptions::new()).unwrap();
            match read_all(r, 65_536) {
                Err(RecordingError::Binary { line, detail, .. }) if long => {
                    assert_eq!(line, 100_001);
                    assert!(detail.contains("longer than"), "{detail}");
                }
                // one line under the limit is read and refused as a cell (10^(2^20) is no
                // finite number)
                Err(RecordingError::NotNumeric { line, column, .. }) if !long => {
                    assert_eq!((line, column), (100_001, 1))
                }
                other => panic!("{len}: {:?}", other.map(|v| v.len())),
            }
        }
    }

    /// A chunk as bits (first sample, times, values per channel).
    type Bits = (u64, Vec<u64>, Vec<Vec<u64>>);

    fn bits(c: &RecordingChunk) -> Bits {
        let b = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        (
            c.first_sample,
            b(&c.time_s),
            c.values.iter().map(|v| b(v)).collect(),
        )
    }

    /// Chunks, the error (as its message), bytes read and warnings of `read_chunk` in a loop.
    fn serial<R: BufRead>(
        mut r: RecordingReader<R>,
        rows: usize,
    ) -> (Vec<Bits>, Option<String>, u64, Vec<String>) {
        let mut c = RecordingChunk::default();
        let mut out = Vec::new();
        let error = loop {
            match r.read_chunk(&mut c, rows) {
                Ok(0) => break None,
                Ok(_) => out.push(bits(&c)),
                Err(e) => break Some(e.to_string()),
            }
        };
        (out, error, r.bytes_read(), r.warnings().to_vec())
    }

    /// The same with [`RecordingReader::for_each_chunk`] on `workers` threads.
    fn parallel<R: BufRead + Send>(
        mut r: RecordingReader<R>,
        rows: usize,
        workers: usize,
    ) -> (Vec<Bits>, Option<String>, u64, Vec<String>) {
        let mut c = RecordingChunk::default();
        let mut out = Vec::new();
        let mut last_bytes = 0;
        let error = r
            .for_each_chunk(&mut c, rows, workers, |c, n, bytes| {
                assert_eq!(c.len(), n);
                assert!(bytes >= last_bytes);
                last_bytes = bytes;
                out.push(bits(c));
                // hand back another buffer, as a pipeline recycling chunks does
                *c = RecordingChunk::default();
                true
            })
            .err()
            .map(|e| e.to_string());
        (out, error, r.bytes_read(), r.warnings().to_vec())
    }

    /// A cell holding a control character (a lone carriage return, a tab in a comma-separated
    /// file) is quoted escaped in the error, so that the message stays readable on a terminal.
    #[test]
    fn control_characters_in_a_bad_cell_are_escaped() {
        let text = "time_s,a_N\n0.0,1\n0.1,1\r5\n";
        let mut r =
            RecordingReader::from_bytes("c.csv", text.as_bytes(), &ReadOptions::new()).unwrap();
        let e = r
            .read_chunk(&mut RecordingChunk::default(), 10)
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.csv:3:2: `1\\r5`"), "{e}");
        assert!(!e.contains('\r'), "{e:?}");
    }

    /// [`RecordingReader::line_of_sample`] over 150 000 rows with blank lines (empty, blanks, a
    /// lone `\r`) every few rows: the line of samples among the rows read ahead at open, at a
    /// chunk's edges and at the end, against the lines the text was written with.
    #[test]
    fn the_line_of_a_sample_counts_blank_lines() {
        let mut text = String::from("time_s,Fx_N\n");
        let mut lines = Vec::new(); // line of each sample
        let mut line = 1;
        for i in 0..150_000u64 {
            if i % 7 == 3 {
                text.push_str(["\n", "  \n", "\r\n"][(i % 3) as usize]);
                line += 1;
            }
            text.push_str(&format!("{},{}\n", i as f64 * 1e-4, i % 13));
            line += 1;
            lines.push(line);
        }
        let open =
            || RecordingReader::from_bytes("t.csv", text.as_bytes(), &ReadOptions::new()).unwrap();
        let last = lines.len() as u64 - 1;
        for s in [
            0, 1, 2, 3, 4, 999, 1000, 1001, 65_535, 65_536, 131_072, last,
        ] {
            assert_eq!(
                open().line_of_sample(s).unwrap(),
                Some(lines[s as usize]),
                "sample {s}"
            );
        }
        assert_eq!(open().line_of_sample(last + 1).unwrap(), None);
        // from a reader that has read on: the samples behind it are not found
        let mut r = open();
        r.read_chunk(&mut RecordingChunk::default(), 10).unwrap();
        assert_eq!(r.line_of_sample(5).unwrap(), None);
        let mut r = open();
        r.read_chunk(&mut RecordingChunk::default(), 10).unwrap();
        assert_eq!(r.line_of_sample(10).unwrap(), Some(lines[10]));
    }

    /// [`parallel`] with jobs of `job_bytes`.
    fn parallel_in_jobs_of(
        mut r: RecordingReader<std::io::Cursor<&[u8]>>,
        job_bytes: usize,
        rows: usize,
    ) -> (Vec<Bits>, Option<String>, u64, Vec<String>) {
        let mut c = RecordingChunk::default();
        let mut out = Vec::new();
        let error = r
            .for_each_chunk_in_jobs_of(job_bytes, &mut c, rows, 2, |c, _, _| {
                out.push(bits(c));
                true
            })
            .err()
            .map(|e| e.to_string());
        (out, error, r.bytes_read(), r.warnings().to_vec())
    }

    /// What a reading gave: chunks, first error, bytes read, warnings.
    type Outcome = (Vec<Bits>, Option<String>, u64, Vec<String>);

    /// [`parallel_in_jobs_of`] over `bytes` written to a file and mapped (`mapped` module):
    /// the name in messages is the file's path. Asserts that the data rows were mapped (unless
    /// the rows read ahead at open hold an error).
    fn mapped_in_jobs_of(
        bytes: &[u8],
        job_bytes: usize,
        rows: usize,
        workers: usize,
    ) -> (Outcome, String) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        std::fs::write(&path, bytes).unwrap();
        let name = path.display().to_string();
        // SAFETY: test files are not written while they are read
        unsafe { crate::mapped::allow_mapped_files() };
        let mut r = RecordingReader::open(&path, &ReadOptions::new()).unwrap();
        let mut c = RecordingChunk::default();
        let mut out = Vec::new();
        let error = r
            .for_each_chunk_in_jobs_of(job_bytes, &mut c, rows, workers, |c, _, _| {
                out.push(bits(c));
                true
            })
            .err()
            .map(|e| e.to_string());
        // (an error in the rows read ahead at open comes before any mapping)
        assert!(
            r.data_mapped || error.is_some(),
            "the rows were read, not mapped"
        );
        ((out, error, r.bytes_read(), r.warnings().to_vec()), name)
    }

    /// Line `form` of the forms the common-row path must either take (signs, `.5`, `5.`,
    /// `-0.000`, a long fraction) or hand back to the full path (exponents, blanks, quotes, a
    /// lone `\r`, fields missing or extra, long mantissas, text, times off), for the row of
    /// time `t` (issue 18).
    fn odd_line(form: usize, t: &str) -> String {
        match form {
            0 => format!("{t},1.5e2,-3"),
            1 => String::new(),
            2 => format!(" {t}, 1.5,2 "),
            3 => format!("\"{t}\",1,\"2\""),
            4 => format!("{t},1\r5,2"),
            5 => format!("{t},1"),
            6 => format!("{t},1,2,3"),
            7 => format!("{t},1,2,"),
            8 => format!("{t},+1,-0"),
            9 => format!("{t},12345678901234567890,1"),
            10 => format!("{t},.5,5."),
            11 => format!("{t},-,1"),
            12 => format!("{t},1,2\r"),
            13 => format!("{t},0x1,2"),
            14 => "0.0001,1,2".to_string(), // time going back
            15 => "1e9,1,2".to_string(),    // time off the rate
            _ => format!("{t},-0.000,123456.7890123"),
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

        /// Lines of every form after the rows read ahead at open — common rows, exponents,
        /// blanks, quotes, a lone carriage return, missing and extra fields, signs, long
        /// mantissas — with `\n` or `\r\n` endings: parsing in small jobs on 2 threads gives
        /// `read_chunk`'s chunks, bytes read, warnings and first error (issue 18: the common-row
        /// path and its hand-back to the full path).
        #[test]
        fn jobs_equal_serial_on_lines_of_every_form(
            odd in proptest::collection::vec((1000usize..1400, 0usize..17), 0..40),
            job_bytes in 16usize..600,
            crlf in proptest::bool::ANY,
        ) {
            let mut lines: Vec<String> = (0..1400u32)
                .map(|k| format!("{:.4},{:.3},-{}.25", f64::from(k) / 1e4, f64::from(k) * 0.7 - 300.0, k % 7))
                .collect();
            for (at, form) in odd {
                let t = format!("{:.4}", at as f64 / 1e4);
                lines[at] = odd_line(form, &t);
            }
            let end = if crlf { "\r\n" } else { "\n" };
            let text = format!("time_s,a_N,b_N{end}{}", lines.join(end));
            let bytes = text.as_bytes();
            let opts = ReadOptions::new();
            let want = serial(RecordingReader::from_bytes("t.csv", bytes, &opts).unwrap(), 97);
            let got = parallel_in_jobs_of(RecordingReader::from_bytes("t.csv", bytes, &opts).unwrap(), job_bytes, 97);
            proptest::prop_assert_eq!(&got.1, &want.1);
            proptest::prop_assert_eq!(got.2, want.2, "bytes read");
            proptest::prop_assert_eq!(&got.3, &want.3);
            proptest::prop_assert!(got.0 == want.0, "chunks");
            // the same lines from a mapped file (its path in the messages)
            let (got, name) = mapped_in_jobs_of(bytes, job_bytes, 97, 2);
            let want = serial(RecordingReader::from_bytes(&name, bytes, &opts).unwrap(), 97);
            proptest::prop_assert_eq!(&got.1, &want.1);
            proptest::prop_assert_eq!(got.2, want.2, "bytes read (mapped)");
            proptest::prop_assert!(got.0 == want.0, "chunks (mapped)");
        }
    }

    /// Parsing on 2 and 3 threads gives the chunks of `read_chunk` bit for bit (same sizes,
    /// first samples, times, values), the same bytes read and the same end-of-data warning, at
    /// chunk sizes below and above the job size and across input blocks cut anywhere.
    /// A file mapped instead of read (issue 18, `mapped` module) gives `read_chunk`'s chunks,
    /// bytes read and warnings bit for bit: mixed line ends, blank lines and no final line
    /// end (the `text` fixture), behind a DynoWare header and a UTF-8 byte-order mark, in jobs
    /// of the default size and of a few bytes, on 2 and 3 workers.
    #[test]
    fn mapped_files_parse_as_read_files() {
        let (bytes, _) = text();
        let opts = ReadOptions::new();
        let mut dyno = b"\xEF\xBB\xBFDynoWare,Version 2.5\nSampling rate [Hz]:,10000\nSamples per channel:,5\n".to_vec();
        dyno.extend_from_slice(&bytes);
        for src in [&bytes, &dyno] {
            for (job_bytes, workers) in [(1 << 20, 2), (1 << 20, 3), (97, 2)] {
                let (got, name) = mapped_in_jobs_of(src, job_bytes, 65_536, workers);
                let want = serial(
                    RecordingReader::from_bytes(&name, src, &opts).unwrap(),
                    65_536,
                );
                assert!(want.1.is_none());
                assert!(got == want, "jobs of {job_bytes} bytes, {workers} workers");
            }
        }
    }

    /// A mapped file shortened while its rows are parsed (issue 18): the pages past its new end
    /// fault (SIGBUS), the guard puts zeros there, and the reading ends in an error naming the
    /// file as shortened — no panic, no crash, and no chunk past the rows before the cut. The
    /// same file read whole gives every row.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_mapped_file_shortened_while_read_is_an_error() {
        let mut text = String::from("time_s,a_N,b_N\n");
        for k in 0..800_000u32 {
            text += &format!(
                "{:.5},{:.4},-{}.5\n",
                f64::from(k) / 1e5,
                f64::from(k) * 0.37,
                k % 91
            );
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("growing.csv");
        std::fs::write(&path, &text).unwrap();
        // SAFETY: the file is shortened (not written in place) while it is read
        unsafe { crate::mapped::allow_mapped_files() };
        let mut r = RecordingReader::open(&path, &ReadOptions::new()).unwrap();
        let mut c = RecordingChunk::default();
        let mut rows = 0;
        let cut = 1_000_000u64;
        let e = r
            .for_each_chunk(&mut c, 4096, 2, |c, n, _| {
                if rows == 0 {
                    std::fs::OpenOptions::new()
                        .write(true)
                        .open(&path)
                        .unwrap()
                        .set_len(cut)
                        .unwrap();
                }
                rows += n;
                assert!(c.time_s.iter().all(|t| t.is_finite()));
                true
            })
            .unwrap_err()
            .to_string();
        assert!(r.data_mapped);
        assert!(
            e.contains("growing.csv")
                && e.contains(&format!(
                    "shortened while it was being read ({} bytes when opened, {cut} now)",
                    text.len()
                )),
            "{e}"
        );
        // fewer rows than the file had (the parse stopped at the zeros or at the error)
        assert!(rows < 800_000, "{rows} rows");
        std::fs::write(&path, &text).unwrap();
        let mut r = RecordingReader::open(&path, &ReadOptions::new()).unwrap();
        let mut rows = 0;
        r.for_each_chunk(&mut c, 4096, 2, |_, n, _| {
            rows += n;
            true
        })
        .unwrap();
        assert_eq!(rows, 800_000);
    }

    #[test]
    fn parallel_parsing_equals_serial() {
        let (bytes, _) = text();
        let opts = ReadOptions::new();
        for rows in [65_536, 777, 1_000_000] {
            let want = serial(
                RecordingReader::from_bytes("t.csv", &bytes, &opts).unwrap(),
                rows,
            );
            assert!(want.1.is_none() && want.0.iter().map(|c| c.1.len()).sum::<usize>() == 200_000);
            for workers in [2, 3] {
                let r = RecordingReader::from_bytes("t.csv", &bytes, &opts).unwrap();
                assert!(
                    parallel(r, rows, workers) == want,
                    "{rows} rows, {workers} workers"
                );
            }
            let trickle = BufReader::with_capacity(5, Trickle(&bytes));
            let r = RecordingReader::from_reader(trickle, "t.csv", &opts).unwrap();
            assert!(parallel(r, rows, 2) == want, "{rows} rows, trickled");
        }
        // a DynoWare header announcing another sample count: the same warning at the end
        let mut dyno =
            b"DynoWare,Version 2.5\nSampling rate [Hz]:,10000\nSamples per channel:,5\n".to_vec();
        dyno.extend_from_slice(&bytes);
        let want = serial(
            RecordingReader::from_bytes("d.txt", &dyno, &opts).unwrap(),
            65_536,
        );
        assert!(
            want.3.iter().any(|w| w.contains("announces 5 samples")),
            "{:?}",
            want.3
        );
        let r = RecordingReader::from_bytes("d.txt", &dyno, &opts).unwrap();
        assert!(parallel(r, 65_536, 2) == want);
    }

    /// The first error in file order, with its line and column, after the same chunks as the
    /// serial reader: bad cells, missing fields, time going back or off the rate, over-long
    /// lines (with and without a line end) and a read error — early, deep and at the end.
    #[test]
    fn parallel_parsing_reports_the_first_error_in_order() {
        let (bytes, _) = text();
        let all = String::from_utf8(bytes).unwrap();
        let lines: Vec<String> = all.split('\n').map(String::from).collect();
        let n = lines.len();
        let opts = ReadOptions::new();
        let long = "1".repeat(MAX_LINE_BYTES as usize);
        let cases: Vec<(usize, String, &str)> = vec![
            (1500, "0.1499,1.0,x7".into(), ":3: `x7`"),
            (150_000, "15.0,1.0,x7".into(), ":3: `x7`"),
            (n - 1, "19.9999,1.0".into(), "expected 3 fields, found 2"),
            (60_000, "5.9,1.0,2.0".into(), "is not after the previous"),
            (
                90_000,
                "9.00009,1.0,2.0".into(),
                "inconsistent with the sample rate",
            ),
            (120_000, long.clone(), "longer than"),
            (n - 1, long.clone(), "longer than"),
        ];
        for (at, bad, what) in cases {
            let mut l = lines.clone();
            l[at] = bad;
            // a second, later error must not be the one reported
            if at + 3 < n {
                l[at + 3] = "x,y,z".into();
            }
            let src = l.join("\n").into_bytes();
            for rows in [65_536, 4096] {
                let want = serial(
                    RecordingReader::from_bytes("t.csv", &src, &opts).unwrap(),
                    rows,
                );
                let e = want.1.clone().unwrap_or_default();
                assert!(e.starts_with(&format!("t.csv:{}:", at + 1)), "{e}");
                assert!(e.contains(what), "{e}");
                let r = RecordingReader::from_bytes("t.csv", &src, &opts).unwrap();
                let got = parallel(r, rows, 2);
                assert_eq!(got.1, want.1, "line {}", at + 1);
                assert_eq!(got.2, want.2, "bytes read at the error at line {}", at + 1);
                assert!(
                    got.0 == want.0,
                    "chunks before the error at line {}",
                    at + 1
                );
            }
            // from a mapped file, in jobs of the default size and small ones
            for job_bytes in [1 << 20, 4099] {
                let (got, name) = mapped_in_jobs_of(&src, job_bytes, 4096, 2);
                let want = serial(
                    RecordingReader::from_bytes(&name, &src, &opts).unwrap(),
                    4096,
                );
                assert_eq!(got.1, want.1, "mapped, line {}", at + 1);
                assert_eq!(got.2, want.2, "mapped, bytes read at line {}", at + 1);
                assert!(got.0 == want.0, "mapped, chunks before line {}", at + 1);
            }
        }
        // a read error after 3 MB: the rows before it, then the error
        struct Failing<'a>(&'a [u8], usize);
        impl Read for Failing<'_> {
            fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
                if self.1 == 0 {
                    return Err(std::io::Error::other("disk gone"));
                }
                let n = self.0.len().min(out.len()).min(self.1);
                out[..n].copy_from_slice(&self.0[..n]);
                self.0 = &self.0[n..];
                self.1 -= n;
                Ok(n)
            }
        }
        let (bytes, _) = text();
        let src = || BufReader::new(Failing(&bytes, 3_000_000));
        let want = serial(
            RecordingReader::from_reader(src(), "t.csv", &opts).unwrap(),
            4096,
        );
        assert!(
            want.1.as_deref().unwrap_or_default().contains("disk gone"),
            "{want:?}"
        );
        let got = parallel(
            RecordingReader::from_reader(src(), "t.csv", &opts).unwrap(),
            4096,
            2,
        );
        assert_eq!(got.1, want.1);
        assert!(got.0 == want.0);
    }
}
