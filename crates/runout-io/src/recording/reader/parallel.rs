//! Data rows parsed on several threads (issue 18): a splitter thread cuts the input after the
//! read-ahead into jobs of whole lines (≈ [`JOB_BYTES`]), parse workers turn them into columns
//! (round robin, so job `k` is worker `k mod W`'s), and the calling thread takes the results
//! in file order: it numbers the samples, checks the time column and cuts the rows into chunks
//! of the requested size — the same chunks, values, line numbers and first error as
//! [`RecordingReader::read_chunk`] called in a loop.
//!
//! Memory is bounded by the jobs in flight: per worker one job queued, one being parsed and one
//! result queued, plus the result being taken (≈ 4 × 1 MiB of text and its columns: a result
//! keeps its text until its rows are taken, so that an error's position in bytes can be found in
//! it), whatever the file's length.

use super::{
    checked_time, long_line, trim_field, RecordingChunk, RecordingError, RecordingReader, Result,
    RowParser, Slot, MAX_LINE_BYTES,
};
use crate::mapped::MappedFile;
use std::io::{BufRead, Read};
use std::sync::mpsc;

/// Lines of a job that may fail the common-row path before the job may stop trying it.
const COMMON_MISSES: u64 = 16;

/// Bytes of input per job (cut at the next line end).
const JOB_BYTES: usize = 1 << 20;

/// Work for a parse worker.
enum Job {
    /// Whole lines of the data section (the first `n` bytes of the buffer; the rest is spare
    /// room kept initialised for the next use, so a recycled buffer is never zeroed again); the
    /// last line lacks its line end only at the end of the input (or when it is too long, which
    /// the worker reports).
    Lines(Vec<u8>, usize),
    /// The input could not be read after the lines of the jobs before.
    Io(std::io::Error),
    /// Whole lines of a mapped input: `map[start..end]`.
    Span(usize, usize),
}

/// What a worker made of a job.
#[derive(Default)]
struct Parsed {
    /// Rows parsed (before an error, if any).
    rows: usize,
    /// Their time cells, scaled to s (empty without a time column).
    times: Vec<f64>,
    /// Their values per channel.
    values: Vec<Vec<f64>>,
    /// 0-based lines of the job that held no row (blank), ascending.
    blank: Vec<u64>,
    /// Lines of the job.
    lines: u64,
    /// Bytes of the job.
    bytes: u64,
    /// The error at the job's last line (numbered from 1 at the job's first line).
    error: Option<RecordingError>,
    /// Bytes of the job up to the error: through the failing line, as the serial reader has
    /// consumed it when it reports the error.
    error_bytes: u64,
    /// The job's text, kept until the rows are taken (a time error's position in bytes is
    /// found in it), then handed back to the splitter.
    text: Vec<u8>,
    /// A mapped job's bytes in the map (its `text` is then empty).
    span: Option<(usize, usize)>,
}

impl Parsed {
    fn reset(&mut self, channels: usize) {
        self.rows = 0;
        self.times.clear();
        self.values.resize_with(channels, Vec::new);
        self.values.iter_mut().for_each(Vec::clear);
        self.blank.clear();
        self.lines = 0;
        self.bytes = 0;
        self.error = None;
        self.error_bytes = 0;
        self.span = None;
    }

    /// Bytes of the job's text through its first `lines` lines, endings included.
    fn bytes_through(&self, map: &[u8], lines: u64) -> u64 {
        if lines == 0 {
            return 0;
        }
        let text = match self.span {
            Some((a, b)) => &map[a..b],
            None => &self.text[..self.bytes as usize],
        };
        memchr::memchr_iter(b'\n', text)
            .nth(lines as usize - 1)
            .map_or(text.len(), |k| k + 1) as u64
    }

    /// The 0-based line in the job of row `row`.
    fn line_of(&self, row: usize) -> u64 {
        let mut line = row as u64;
        for &b in &self.blank {
            if b <= line {
                line += 1;
            } else {
                break;
            }
        }
        line
    }
}

/// Parse the lines of a job as `Block::next_line` + `RecordingReader::parse_row` would (line
/// length limit, `\r\n` endings, blank lines skipped), the time cells unchecked. A common row
/// (plain numbers, nothing else) is parsed as it is scanned, without a search for its end first
/// (`RowParser::parse_common_line`); any other line, or a common row's line when such rows are
/// rare in the job, takes the full path.
fn parse_job(p: &RowParser<'_>, has_time: bool, bytes: &[u8], out: &mut Parsed) {
    out.bytes = bytes.len() as u64;
    let mut pos = 0;
    let mut line = 0u64;
    let mut common = p.common_lines();
    let mut misses = 0u64;
    while pos < bytes.len() {
        let rest = &bytes[pos..];
        if common {
            let mut time = None;
            if let Some(consumed) = p.parse_common_line(rest, &mut out.values, &mut time) {
                if has_time {
                    out.times.push(time.unwrap_or(f64::NAN));
                }
                out.rows += 1;
                line += 1;
                pos += consumed;
                continue;
            }
            for v in &mut out.values {
                v.truncate(out.rows);
            }
            // lines of another form (exponents, blanks, quotes) go the full way; when they are
            // more than one in eight, the job stops trying the common path first
            misses += 1;
            common = misses < COMMON_MISSES || misses * 8 < line;
        }
        let (mut len, consumed) = match memchr::memchr(b'\n', rest) {
            Some(k) => (k, k + 1),
            None => (rest.len(), rest.len()),
        };
        line += 1;
        if len as u64 >= MAX_LINE_BYTES {
            out.error = Some(long_line(&p.info.file, line));
            out.error_bytes = pos as u64;
            break;
        }
        pos += consumed;
        if len > 0 && rest[len - 1] == b'\r' {
            len -= 1;
        }
        let row = &rest[..len];
        if trim_field(row).is_empty() {
            out.blank.push(line - 1);
            continue;
        }
        let mut time = None;
        if let Err(e) = p.parse(line, row, &mut out.values, &mut time) {
            for v in &mut out.values {
                v.truncate(out.rows);
            }
            out.error = Some(e);
            out.error_bytes = pos as u64;
            break;
        }
        if has_time {
            out.times.push(time.unwrap_or(f64::NAN));
        }
        out.rows += 1;
    }
    out.lines = line;
}

/// Cut the input into jobs of whole lines, starting with `carry` (bytes read ahead, not
/// parsed yet); job `k` goes to `jobs[k mod W]`. Ends at the end of the input, at a read error
/// (sent in order, after the whole lines before it), or when a worker has stopped.
fn split<R: Read>(
    src: &mut R,
    (mut carry, mut eof): (Vec<u8>, bool),
    job_bytes: usize,
    jobs: Vec<mpsc::SyncSender<Job>>,
    free: mpsc::Receiver<Vec<u8>>,
) {
    let read_bytes = READ_BYTES.min(job_bytes);
    let w = jobs.len();
    let mut k = 0;
    let mut send = |job: Job| {
        let sent = jobs[k % w].send(job).is_ok();
        k += 1;
        sent
    };
    loop {
        if eof && carry.is_empty() {
            return;
        }
        // a recycled buffer's bytes are initialised up to its length: they are reused as they
        // are (zeroing ≈ 1 MiB per job before reading over it was ≈ 2 % of the reading's CPU)
        let mut buf = free.try_recv().unwrap_or_default();
        let mut filled = carry.len();
        if buf.len() < filled {
            buf.resize(filled, 0);
        }
        buf[..filled].copy_from_slice(&carry);
        carry.clear();
        let mut searched = 0;
        let mut failed = None;
        let mut last = false;
        let cut = loop {
            if eof {
                break filled;
            }
            if filled >= job_bytes {
                if let Some(p) = memchr::memrchr(b'\n', &buf[searched..filled]) {
                    break searched + p + 1;
                }
                searched = filled;
                if filled as u64 > MAX_LINE_BYTES {
                    // no line end at all: the worker reports the line as too long
                    last = true;
                    break filled;
                }
            }
            let want = filled.max(job_bytes.saturating_sub(read_bytes)) + read_bytes;
            if buf.len() < want {
                buf.resize(want, 0);
            }
            let n = loop {
                match src.read(&mut buf[filled..want]) {
                    Ok(n) => break Some(n),
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        failed = Some(e);
                        break None;
                    }
                }
            };
            filled += n.unwrap_or(0);
            match n {
                Some(0) => eof = true,
                Some(_) => {}
                None => break memchr::memrchr(b'\n', &buf[..filled]).map_or(0, |p| p + 1),
            }
        };
        carry.extend_from_slice(&buf[cut..filled]);
        if cut > 0 && !send(Job::Lines(buf, cut)) {
            return;
        }
        if let Some(e) = failed {
            send(Job::Io(e));
            return;
        }
        if last {
            return;
        }
    }
}

/// Cut a mapped input into jobs of whole lines, as [`split`] cuts a read one: about
/// `job_bytes` each, cut after the last line end in them, or after the first one past them; a
/// line with no end within [`MAX_LINE_BYTES`] is sent alone, for its worker to report, and ends
/// the cutting. Job `k` goes to `jobs[k mod W]`; ends early when a worker has stopped.
fn split_map(map: &[u8], job_bytes: usize, jobs: Vec<mpsc::SyncSender<Job>>) {
    let w = jobs.len();
    let mut pos = 0;
    for k in 0.. {
        if pos >= map.len() {
            return;
        }
        let want = pos.saturating_add(job_bytes).min(map.len());
        let (end, last) = if want == map.len() {
            (want, false)
        } else if let Some(p) = memchr::memrchr(b'\n', &map[pos..want]) {
            (pos + p + 1, false)
        } else {
            let limit = (pos + MAX_LINE_BYTES as usize + 1).min(map.len()).max(want);
            match memchr::memchr(b'\n', &map[want..limit]) {
                Some(p) => (want + p + 1, false),
                None => (limit, limit < map.len()),
            }
        };
        if jobs[k % w].send(Job::Span(pos, end)).is_err() || last {
            return;
        }
        pos = end;
    }
}

/// Bytes asked of the input per read.
const READ_BYTES: usize = 1 << 16;

impl<R: BufRead + Send> RecordingReader<R> {
    /// Read all remaining rows in chunks of `max_rows` (the last one shorter), calling
    /// `each(chunk, rows, bytes_read)` for each; `each` may swap the chunk for another
    /// (recycled) one, and stops the reading by returning `false`. The chunks, their values,
    /// the line numbers and the first error are those of [`RecordingReader::read_chunk`] in a
    /// loop; a text recording's data rows are parsed on `workers` threads (binary formats,
    /// table mode and `workers < 2` read serially). After it the reader is finished.
    pub fn for_each_chunk(
        &mut self,
        chunk: &mut RecordingChunk,
        max_rows: usize,
        workers: usize,
        each: impl FnMut(&mut RecordingChunk, usize, u64) -> bool,
    ) -> Result<()> {
        self.for_each_chunk_in_jobs_of(JOB_BYTES, chunk, max_rows, workers, each)
    }

    /// [`RecordingReader::for_each_chunk`] with jobs of about `job_bytes` bytes of input
    /// (for tests: small jobs cut small inputs into many, so that their seams are exercised).
    #[doc(hidden)]
    pub fn for_each_chunk_in_jobs_of(
        &mut self,
        job_bytes: usize,
        chunk: &mut RecordingChunk,
        max_rows: usize,
        workers: usize,
        mut each: impl FnMut(&mut RecordingChunk, usize, u64) -> bool,
    ) -> Result<()> {
        let job_bytes = job_bytes.max(1);
        let max_rows = max_rows.max(1);
        let parallel =
            self.binary.is_none() && self.row_lines.is_none() && workers > 1 && !self.finished;
        if !parallel {
            loop {
                let n = self.read_chunk(chunk, max_rows)?;
                if n == 0 || !each(chunk, n, self.bytes_read()) {
                    return Ok(());
                }
            }
        }
        // serially: the lines read ahead at open; the chunk they leave partly filled is
        // continued by the parse workers (before, a whole first chunk was parsed serially:
        // 65 536 rows on one core, ≈ 20 ms of a 100 MB recording with the other core idle)
        loop {
            let n = self.read_pending_rows(chunk, max_rows)?;
            if n < max_rows {
                break;
            }
            if !each(chunk, n, self.bytes_read()) {
                return Ok(());
            }
        }
        let block = std::mem::take(&mut self.lines.block);
        let carry = block.data[block.pos..block.end].to_vec();
        let eof = block.eof;
        drop(block);
        let slots = self.slots.clone();
        let info = self.info.clone();
        let has_time = slots.contains(&Slot::Time);
        let parser = RowParser {
            slots: &slots,
            delim: info.delimiter as u8,
            dc: info.decimal_comma,
            time_scale: self.time_scale,
            info: &info,
        };
        let channels = info.channels.len();
        let time_column = self.time_column;
        let src = &mut self.lines.src;
        let mut line_no = self.lines.line_no;
        let mut bytes = self.lines.bytes;
        let mut sample = self.sample;
        let mut previous = self.previous_time;
        let reset = |chunk: &mut RecordingChunk, sample: u64| {
            chunk.first_sample = sample;
            chunk.time_s.clear();
            chunk.values.resize_with(channels, Vec::new);
            chunk.values.iter_mut().for_each(Vec::clear);
        };
        // the rest of a file mapped, when the process allows it (`crate::mapped`), from the
        // first byte not parsed yet: the bytes the reader holds must be the map's first ones
        let mapped = self
            .mappable
            .take()
            .and_then(|f| MappedFile::new(f, bytes))
            .filter(|m| m.bytes().starts_with(&carry));
        let map: &[u8] = mapped.as_ref().map_or(&[], |m| m.bytes());
        self.data_mapped = mapped.is_some();
        let ended = std::thread::scope(|scope| -> Result<bool> {
            let mut job_tx = Vec::new();
            let mut res_rx = Vec::new();
            let mut free_res = Vec::new();
            let (free_buf_tx, free_buf_rx) = mpsc::channel::<Vec<u8>>();
            for _ in 0..workers {
                let (jt, jr) = mpsc::sync_channel::<Job>(1);
                let (rt, rr) = mpsc::sync_channel::<Parsed>(1);
                let (ft, fr) = mpsc::channel::<Parsed>();
                let info = &info;
                scope.spawn(move || {
                    for job in jr {
                        let mut out = fr.try_recv().unwrap_or_default();
                        out.reset(channels);
                        match job {
                            Job::Lines(b, n) => {
                                parse_job(&parser, has_time, &b[..n], &mut out);
                                out.text = b;
                            }
                            Job::Span(a, b) => {
                                parse_job(&parser, has_time, &map[a..b], &mut out);
                                out.span = Some((a, b));
                            }
                            Job::Io(error) => {
                                out.error = Some(RecordingError::Io {
                                    file: info.file.clone(),
                                    error,
                                })
                            }
                        }
                        if rt.send(out).is_err() {
                            break;
                        }
                    }
                });
                job_tx.push(jt);
                res_rx.push(rr);
                free_res.push(ft);
            }
            if mapped.is_some() {
                scope.spawn(move || split_map(map, job_bytes, job_tx));
            } else {
                scope.spawn(move || split(src, (carry, eof), job_bytes, job_tx, free_buf_rx));
            }
            // `chunk` holds the rows read ahead at open that did not fill a chunk (maybe none)
            let mut result = Ok(true);
            'jobs: for k in 0.. {
                let w = k % workers;
                let Ok(mut p) = res_rx[w].recv() else { break };
                let mut r = 0;
                while r < p.rows {
                    if chunk.len() == max_rows {
                        if !each(chunk, max_rows, bytes) {
                            result = Ok(false);
                            break 'jobs;
                        }
                        reset(chunk, sample);
                    }
                    let take = (max_rows - chunk.len()).min(p.rows - r);
                    let mut good = take;
                    for i in r..r + take {
                        let time = has_time.then(|| p.times[i]);
                        let line = || line_no + 1 + p.line_of(i);
                        match checked_time(&info, time_column, sample, &mut previous, time, line) {
                            Ok(t) => {
                                chunk.time_s.push(t);
                                sample += 1;
                            }
                            Err(e) => {
                                good = i - r;
                                result = Err(e);
                                // the serial reader has consumed the row's line
                                bytes += p.bytes_through(map, p.line_of(i) + 1);
                                break;
                            }
                        }
                    }
                    for (c, v) in chunk.values.iter_mut().zip(&p.values) {
                        c.extend_from_slice(&v[r..r + good]);
                    }
                    if result.is_err() {
                        break 'jobs;
                    }
                    r += take;
                }
                if let Some(mut e) = p.error {
                    // a chunk filled by the rows before the error is handed on first, as
                    // `read_chunk` returns it before the call that meets the error
                    if chunk.len() == max_rows && !each(chunk, max_rows, bytes) {
                        result = Ok(false);
                        break;
                    }
                    shift_line(&mut e, line_no);
                    bytes += p.error_bytes;
                    result = Err(e);
                    break;
                }
                line_no += p.lines;
                bytes += p.bytes;
                if let (Some((a, b)), Some(m)) = (p.span, &mapped) {
                    m.release(a, b);
                }
                free_buf_tx.send(std::mem::take(&mut p.text)).ok();
                free_res[w].send(p).ok();
            }
            drop(res_rx);
            if matches!(result, Ok(true)) && !chunk.time_s.is_empty() {
                let n = chunk.len();
                if !each(chunk, n, bytes) {
                    result = Ok(false);
                }
            }
            result
        });
        // a mapped file shortened meanwhile: its error, whatever the parse made of the zeros
        // put where its end was (a stop asked by the caller stays a stop)
        let ended = match mapped.and_then(|m| m.shortened()) {
            Some(error) if !matches!(ended, Ok(false)) => Err(RecordingError::Io {
                file: info.file.clone(),
                error,
            }),
            _ => ended,
        };
        self.lines.line_no = line_no;
        self.lines.bytes = bytes;
        self.sample = sample;
        self.previous_time = previous;
        match ended {
            Ok(true) => {
                self.finish();
                Ok(())
            }
            Ok(false) => {
                self.finished = true;
                Ok(())
            }
            Err(e) => {
                self.finished = true;
                Err(e)
            }
        }
    }
}

/// Number an error's line from the job's first line (`before` lines precede the job).
fn shift_line(e: &mut RecordingError, before: u64) {
    match e {
        RecordingError::Binary { line, .. }
        | RecordingError::FieldCount { line, .. }
        | RecordingError::NotNumeric { line, .. }
        | RecordingError::TimeNotMonotonic { line, .. }
        | RecordingError::RateInconsistent { line, .. } => *line += before,
        _ => {}
    }
}
