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
#[cfg(target_arch = "x86_64")]
use crate::recording::text::WideCells;
use std::io::{BufRead, Read};
use std::sync::mpsc;

/// Lines of a job that may fail the common-row path before the job may stop trying it.
const COMMON_MISSES: u64 = 16;

/// Whether a job whose `misses` lines (of `lines` so far) failed a fast path goes on trying it
/// first: lines of another form go the full way, and when they are more than one in eight the
/// job stops trying the fast path.
fn keep_trying(misses: u64, lines: u64) -> bool {
    misses < COMMON_MISSES || misses * 8 < lines
}

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
    /// Rows taken from the structural index and stretches indexed (tests check the wide path
    /// is taken, and not scanned again and again).
    #[cfg(test)]
    indexed: usize,
    #[cfg(test)]
    stretches: usize,
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
/// rare in the job, takes the full path. On x86-64 with SSSE3 and SSE4.1 common rows are first
/// taken from a structural index ([`parse_job_wide`]), with the same results.
fn parse_job(p: &RowParser<'_>, has_time: bool, bytes: &[u8], out: &mut Parsed) {
    #[cfg(target_arch = "x86_64")]
    if let Some(wide) = WideCells::detect() {
        // SAFETY: `detect` found the features `parse_job_wide` is compiled for.
        unsafe { parse_job_wide(wide, p, has_time, bytes, out) };
        return;
    }
    parse_job_scalar(p, has_time, bytes, out);
}

/// [`parse_job`] line by line, without the wide parser.
fn parse_job_scalar(p: &RowParser<'_>, has_time: bool, bytes: &[u8], out: &mut Parsed) {
    out.bytes = bytes.len() as u64;
    let mut st = JobState::new(p);
    while st.pos < bytes.len() {
        if !parse_job_line(p, has_time, bytes, &mut st, out) {
            break;
        }
    }
    out.lines = st.line;
}

/// [`parse_job`] on x86-64 with SSSE3 and SSE4.1: common rows are taken from a structural
/// index of the text (issue 18). The positions of every delimiter and line feed of a block of
/// the job are found first, 64 bytes per step (`wide::structurals`); a row then has the bounds
/// of all its cells before any is parsed, so the cells are parsed independently of each other
/// (`wide::number_cell`) instead of each cell's start waiting for the previous cell's digit scan
/// to end (that chain of loads, compares and exits was the parse's time, whatever the scan's
/// width). A row the index cannot take (another form, too close to the job's end) goes through
/// [`parse_job_line`], and the index resumes after it.
///
/// # Safety
/// The CPU must have SSSE3 and SSE4.1 (which holding a [`WideCells`] proves).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "ssse3,sse4.1")]
unsafe fn parse_job_wide(
    wide: WideCells,
    p: &RowParser<'_>,
    has_time: bool,
    bytes: &[u8],
    out: &mut Parsed,
) {
    out.bytes = bytes.len() as u64;
    let mut st = JobState::new(p);
    let mut index = StructuralIndex::new(p.slots.len());
    let mut fast = st.common;
    let mut fast_misses = 0u64;
    while st.pos < bytes.len() {
        if fast {
            match index.row(wide, p, bytes, st.pos, &mut out.values) {
                IndexedRow::Row(next, time) => {
                    #[cfg(test)]
                    {
                        out.indexed += 1;
                    }
                    if has_time {
                        out.times.push(time);
                    }
                    out.rows += 1;
                    st.line += 1;
                    st.pos = next;
                    continue;
                }
                IndexedRow::Other => {
                    for v in &mut out.values {
                        v.truncate(out.rows);
                    }
                    fast_misses += 1;
                    fast = keep_trying(fast_misses, st.line);
                }
                IndexedRow::Unindexed => {}
                // (indexing on would scan a stretch again for every such row)
                IndexedRow::TooLong => fast = false,
            }
        }
        if !parse_job_line(p, has_time, bytes, &mut st, out) {
            break;
        }
    }
    out.lines = st.line;
    #[cfg(test)]
    {
        out.stretches = index.stretches;
    }
}

/// Where a job's parse stands: the next line's first byte, the lines done, and whether common
/// rows are still tried first (and how often they failed).
struct JobState {
    pos: usize,
    line: u64,
    common: bool,
    misses: u64,
}

impl JobState {
    fn new(p: &RowParser<'_>) -> Self {
        Self {
            pos: 0,
            line: 0,
            common: p.common_lines(),
            misses: 0,
        }
    }
}

/// The line of `bytes` at `st.pos` (which is before the end) parsed into `out` and `st` moved
/// past it: a common row first when such rows are the job's rule, else the full path. False
/// after an error (recorded in `out`): the job stops there.
#[inline(always)]
fn parse_job_line(
    p: &RowParser<'_>,
    has_time: bool,
    bytes: &[u8],
    st: &mut JobState,
    out: &mut Parsed,
) -> bool {
    let rest = &bytes[st.pos..];
    if st.common {
        let mut time = None;
        if let Some(consumed) = p.parse_common_line(rest, &mut out.values, &mut time) {
            if has_time {
                out.times.push(time.unwrap_or(f64::NAN));
            }
            out.rows += 1;
            st.line += 1;
            st.pos += consumed;
            return true;
        }
        for v in &mut out.values {
            v.truncate(out.rows);
        }
        // lines of another form: exponents, blanks, quotes
        st.misses += 1;
        st.common = keep_trying(st.misses, st.line);
    }
    let (mut len, consumed) = match memchr::memchr(b'\n', rest) {
        Some(k) => (k, k + 1),
        None => (rest.len(), rest.len()),
    };
    st.line += 1;
    if len as u64 >= MAX_LINE_BYTES {
        out.error = Some(long_line(&p.info.file, st.line));
        out.error_bytes = st.pos as u64;
        return false;
    }
    st.pos += consumed;
    if len > 0 && rest[len - 1] == b'\r' {
        len -= 1;
    }
    let row = &rest[..len];
    if trim_field(row).is_empty() {
        out.blank.push(st.line - 1);
        return true;
    }
    let mut time = None;
    if let Err(e) = p.parse(st.line, row, &mut out.values, &mut time) {
        for v in &mut out.values {
            v.truncate(out.rows);
        }
        out.error = Some(e);
        out.error_bytes = st.pos as u64;
        return false;
    }
    if has_time {
        out.times.push(time.unwrap_or(f64::NAN));
    }
    out.rows += 1;
    true
}

/// Bytes of a job indexed at a time (the positions stay in the first-level cache).
#[cfg(target_arch = "x86_64")]
const INDEX_BYTES: usize = 16 << 10;

/// The positions of the delimiters and line feeds of a stretch of a job, taken row by row.
#[cfg(target_arch = "x86_64")]
struct StructuralIndex {
    /// Positions (from `from`) of the stretch's structural bytes; `len` of them are valid.
    at: Vec<u32>,
    len: usize,
    /// The next position to take.
    next: usize,
    /// The stretch's first byte in the job (`usize::MAX` before the first stretch).
    from: usize,
    /// Cells per row.
    slots: usize,
    /// Stretches indexed.
    #[cfg(test)]
    stretches: usize,
}

/// What the index made of the row at a position.
#[cfg(target_arch = "x86_64")]
enum IndexedRow {
    /// A common row: where the next line starts, and the time cell's value (scaled; NaN
    /// without a time column).
    Row(usize, f64),
    /// Not a common row (values of the row may have been pushed: the caller truncates).
    Other,
    /// The row's end is not indexed (a long line, or too close to the job's end for the
    /// wide loads): the line goes the scalar way, which does not count as another form.
    Unindexed,
    /// The row is longer than a stretch of the index: the job's rows go the scalar way.
    TooLong,
}

#[cfg(target_arch = "x86_64")]
impl StructuralIndex {
    fn new(slots: usize) -> Self {
        Self {
            at: vec![0; INDEX_BYTES + 64],
            len: 0,
            next: 0,
            from: usize::MAX,
            slots,
            #[cfg(test)]
            stretches: 0,
        }
    }

    /// The row that starts at `pos`, parsed from its indexed cells.
    #[target_feature(enable = "ssse3,sse4.1")]
    #[inline]
    fn row(
        &mut self,
        wide: WideCells,
        p: &RowParser<'_>,
        bytes: &[u8],
        pos: usize,
        values: &mut [Vec<f64>],
    ) -> IndexedRow {
        // positions before `pos` belong to lines taken the other way
        while self.next < self.len && self.from + (self.at[self.next] as usize) < pos {
            self.next += 1;
        }
        if self.next + self.slots > self.len {
            if self.from == pos {
                return IndexedRow::Unindexed;
            }
            let to = (pos + INDEX_BYTES).min(bytes.len());
            self.len = wide.structurals(bytes, pos, to, p.delim, &mut self.at);
            #[cfg(test)]
            {
                self.stretches += 1;
            }
            self.from = pos;
            self.next = 0;
            if self.slots > self.len {
                // a stretch cut short of a whole row: rows longer than a stretch
                return if to < bytes.len() {
                    IndexedRow::TooLong
                } else {
                    IndexedRow::Unindexed
                };
            }
        }
        let ends = &self.at[self.next..self.next + self.slots];
        let line_end = self.from + ends[self.slots - 1] as usize;
        if line_end + 16 > bytes.len() {
            return IndexedRow::Unindexed;
        }
        match p.indexed_row(wide, bytes, pos, self.from, ends, values) {
            Some(time) if (line_end + 1 - pos) as u64 <= MAX_LINE_BYTES => {
                self.next += self.slots;
                IndexedRow::Row(line_end + 1, time)
            }
            _ => IndexedRow::Other,
        }
    }
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

/// The wide parse of a job equals the line-by-line one, field by field and bit for bit.
#[cfg(all(test, target_arch = "x86_64"))]
mod wide_tests {
    use super::*;
    use crate::recording::ReadOptions;

    /// `(rows, times, values, blank, lines, bytes, error, error_bytes)` with floats as bits.
    type Summary = (
        usize,
        Vec<u64>,
        Vec<Vec<u64>>,
        Vec<u64>,
        u64,
        u64,
        Option<String>,
        u64,
    );

    fn summary(out: &Parsed) -> Summary {
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        (
            out.rows,
            bits(&out.times),
            out.values.iter().map(|v| bits(v)).collect(),
            out.blank.clone(),
            out.lines,
            out.bytes,
            out.error.as_ref().map(ToString::to_string),
            out.error_bytes,
        )
    }

    /// Both parses of `body` (the data rows after `header`), and whether the wide one ran.
    fn both(header: &str, body: &str) -> (Summary, Summary) {
        // the parser of a recording with this header (its own rows give the sample rate)
        let (d, p) = if header.contains(';') {
            (';', ',')
        } else {
            (',', '.')
        };
        let rows: String = (0..5)
            .map(|k| format!("0{p}0{k}{d}1{p}5{d}2{p}5\n"))
            .collect();
        let text = format!("{header}{rows}");
        let r = RecordingReader::from_bytes("w.csv", text.as_bytes(), &ReadOptions::new())
            .expect("header");
        let p = r.row_parser();
        let has_time = p.slots.contains(&Slot::Time);
        let channels = r.info().columns.len();
        let run = |wide: bool| {
            let mut out = Parsed::default();
            out.reset(channels);
            match WideCells::detect() {
                // SAFETY: detected.
                Some(w) if wide => unsafe {
                    parse_job_wide(w, &p, has_time, body.as_bytes(), &mut out)
                },
                _ => parse_job_scalar(&p, has_time, body.as_bytes(), &mut out),
            }
            summary(&out)
        };
        (run(false), run(true))
    }

    /// A cell of the kinds recordings hold, and of the kinds the wide parser must refuse.
    fn cell(kind: u8, v: f64, d: usize, comma: bool) -> String {
        let plain = format!("{v:.d$}");
        let plain = if comma {
            plain.replace('.', ",")
        } else {
            plain
        };
        match kind % 16 {
            0 => format!("{v:e}"),
            1 => format!(" {plain}"),
            2 => format!("\"{plain}\""),
            3 => "x1".into(),
            4 => String::new(),
            5 => format!("+{}", plain.trim_start_matches('-')),
            6 => format!("{}1234567890123", plain),
            7 => plain.trim_start_matches(['-', '0']).to_string(),
            8 => format!("{plain}."),
            _ => plain,
        }
    }

    /// The wide and the line-by-line parse of `body`, the rows of a recording with `header`
    /// (time first); `None` on a CPU without the wide parser.
    fn wide_and_scalar(header: &str, body: &str) -> Option<(Parsed, Parsed)> {
        let text = format!("{header}{body}");
        let r = RecordingReader::from_bytes("w.csv", text.as_bytes(), &ReadOptions::new())
            .expect("header");
        let p = r.row_parser();
        let w = WideCells::detect()?;
        let (mut wide, mut scalar) = (Parsed::default(), Parsed::default());
        wide.reset(r.info().columns.len());
        scalar.reset(r.info().columns.len());
        // SAFETY: detected.
        unsafe { parse_job_wide(w, &p, true, body.as_bytes(), &mut wide) };
        parse_job_scalar(&p, true, body.as_bytes(), &mut scalar);
        Some((wide, scalar))
    }

    /// Common rows are taken from the index, also right after lines of other forms (the index
    /// resumes after them), until the last rows of the job (whose 16-byte loads would pass its
    /// end); the values are the line-by-line ones.
    #[test]
    fn the_index_takes_the_common_rows() {
        let mut body = String::new();
        let mut common = 0;
        for k in 0..3000 {
            let t = format!("{}", f64::from(k) / 1e4);
            if k % 97 == 5 {
                body += &format!("{t},1e-3,2\n");
            } else if k % 89 == 7 {
                body += "\r\n";
            } else {
                body += &format!("{t},{}.{},-{}\r\n", k % 41, k % 1000, k % 7);
                common += 1;
            }
        }
        let Some((out, scalar)) = wide_and_scalar("time_s,fx_N,fy_N\n", &body) else {
            return;
        };
        assert!(
            out.indexed >= common - 1 && out.indexed <= common,
            "{} of {common}",
            out.indexed
        );
        // each stretch indexed once (not again after every line taken the scalar way)
        assert!(
            out.stretches <= body.len() / INDEX_BYTES + 2,
            "{}",
            out.stretches
        );
        assert!(summary(&scalar) == summary(&out) && out.rows == 3000 - 34);
    }

    /// Rows longer than a stretch of the index (thousands of channels) are parsed the scalar
    /// way from the first one on, with the same results.
    #[test]
    fn rows_longer_than_a_stretch_go_the_scalar_way() {
        let channels = INDEX_BYTES / 3;
        let names: Vec<String> = (0..channels).map(|c| format!("c{c}")).collect();
        let header = format!("time_s,{}\n", names.join(","));
        let row = |k: usize| {
            let cells: Vec<String> = (0..channels)
                .map(|c| format!("{}.5", (c + k) % 97))
                .collect();
            format!("{},{}\n", k as f64 / 100.0, cells.join(","))
        };
        let body: String = (0..6).map(row).collect();
        assert!(body.len() / 6 > INDEX_BYTES);
        let Some((wide, scalar)) = wide_and_scalar(&header, &body) else {
            return;
        };
        assert!(wide.indexed == 0 && wide.stretches == 1 && wide.rows == 6);
        assert!(summary(&wide) == summary(&scalar));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]

        /// Jobs of common rows mixed with every other kind of line (exponents, blanks,
        /// quotes, signs, long and empty cells, missing and extra fields, CRLF, a missing last
        /// line end), with `.` and `,` decimals: the same rows, values, lines and first error.
        #[test]
        fn wide_job_equals_line_by_line(
            rows in proptest::collection::vec(
                (0u8..64, -2e4f64..2e4, 0usize..7, 0u8..40, proptest::bool::ANY), 1..400),
            comma in proptest::bool::ANY,
            last_end in proptest::bool::ANY,
        ) {
            let (delim, header) = if comma {
                (";", "time_s;fx_N;fy_N\n")
            } else {
                (",", "time_s,fx_N,fy_N\n")
            };
            let mut body = String::new();
            for (k, &(kind, v, d, line_kind, crlf)) in rows.iter().enumerate() {
                let t = format!("{}", k as f64 / 100.0);
                let t = if comma { t.replace('.', ",") } else { t };
                // most lines common, as in recordings; the rest of every kind
                let cells = [t, cell(kind, v, d, comma), cell(kind / 4, -v / 3.0, d, comma)];
                let line = match line_kind {
                    0 => String::new(),
                    1 => cells[..2].join(delim),
                    2 => format!("{}{delim}9", cells.join(delim)),
                    3 => "   ".into(),
                    _ => cells.join(delim),
                };
                body += &line;
                body += if crlf { "\r\n" } else { "\n" };
            }
            if !last_end {
                body.pop();
            }
            let (scalar, wide) = both(header, &body);
            proptest::prop_assert_eq!(scalar, wide);
        }

        /// The structural index equals a byte-by-byte search, at any start and length.
        #[test]
        fn structurals_equal_a_byte_search(text in "[,;\n0-9a.]{0,300}", from in 0usize..70) {
            let Some(w) = WideCells::detect() else { return Ok(()) };
            let bytes = text.as_bytes();
            let from = from.min(bytes.len());
            let mut at = vec![0u32; bytes.len() - from + 64];
            for delim in [b',', b';'] {
                // SAFETY: detected.
                let n = unsafe { w.structurals(bytes, from, bytes.len(), delim, &mut at) };
                let want: Vec<u32> = bytes[from..]
                    .iter()
                    .enumerate()
                    .filter(|&(_, &c)| c == delim || c == b'\n')
                    .map(|(k, _)| k as u32)
                    .collect();
                proptest::prop_assert_eq!(&at[..n], &want[..]);
            }
        }

        /// A cell the wide parser takes has `parse_number`'s bits; plain cells up to 15 bytes
        /// are always taken.
        #[test]
        fn number_cells_equal_parse_number(
            cell in "[-+]?[0-9.,eE]{0,17}",
            v in -1e6f64..1e6,
            d in 0usize..9,
            dc in proptest::bool::ANY,
        ) {
            let Some(w) = WideCells::detect() else { return Ok(()) };
            for c in [cell.clone(), format!("{v:.d$}")] {
                let mut bytes = c.clone().into_bytes();
                bytes.extend_from_slice(&[b'\n'; 16]);
                // SAFETY: detected.
                let got = unsafe { w.number_cell(&bytes, 0, c.len(), dc) };
                let want = crate::recording::text::parse_number(c.as_bytes(), dc);
                if let Some(x) = got {
                    proptest::prop_assert_eq!(Some(x.to_bits()), want.map(f64::to_bits), "{:?}", c);
                }
                let digits = c.strip_prefix(['-', '+']).unwrap_or(&c);
                let plain = c.len() <= 15
                    && digits.bytes().filter(|&x| x == b'.').count() <= 1
                    && digits.bytes().all(|x| x.is_ascii_digit() || x == b'.')
                    && digits.bytes().any(|x| x.is_ascii_digit());
                if plain {
                    proptest::prop_assert!(got.is_some(), "{:?}", c);
                }
            }
        }
    }
}
