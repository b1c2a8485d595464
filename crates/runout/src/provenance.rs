//! Provenance of a report (issue 21 item 6): which program made it, from which command, from which
//! inputs (name, size, SHA-256) and when — so the same report made on two machines can be compared,
//! and a report can be traced back to its recordings.
//!
//! Jobs return their report alone; a front end that writes it stamps it:
//!
//! ```
//! use runout::provenance::{Provenance, Stamped};
//! use runout::Source;
//! let inputs = [Source::bytes("rec.csv", b"time_s,Fx_N\n0,1\n".to_vec())];
//! let provenance = Provenance::new(["runout", "identify", "rec.csv"], &inputs)?;
//! assert_eq!(provenance.inputs[0].size_bytes, 16);
//! assert_eq!(provenance.inputs[0].sha256.len(), 64);
//! assert!(provenance.tool.starts_with("runout "));
//! # Ok::<(), std::io::Error>(())
//! ```
//!
//! [`Stamped`] serialises as the report's own fields followed by `provenance`, so a stamped JSON is
//! the report's JSON plus one field.

use crate::job::Source;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// Where a report came from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct Provenance {
    /// Program and version, e.g. `runout 0.1.0`.
    pub tool: String,
    /// The command line as given (program name first), or the calling front end's equivalent
    /// (e.g. `["python", "runout.identify", …]`).
    pub command_line: Vec<String>,
    /// Every input file or in-memory source the job read, in the order given.
    pub inputs: Vec<InputFile>,
    /// Inputs named on the command line that can be read only once (a pipe such as
    /// `<(zcat rec.txt.gz)` or standard input, a FIFO, a device): the job read them, so they
    /// could not be read again to hash them. Their names as given; left out of the JSON when
    /// empty. A report with such inputs cannot be traced back to their content.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_hashed: Vec<String>,
    /// When the report was made: UTC, RFC 3339 with seconds (`2026-11-25T07:12:03Z`).
    pub created_utc: String,
}

/// One input of a report.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct InputFile {
    /// The name the input was given by (a path as typed, or the name of in-memory bytes).
    pub name: String,
    /// Size in bytes (for named arrays: of their hashed form — each name, a NUL byte, and the
    /// samples as little-endian f64).
    pub size_bytes: u64,
    /// SHA-256 of the content, lower-case hex (64 characters).
    pub sha256: String,
}

impl Provenance {
    /// Provenance of a report made now by this program from `inputs`, for the command line
    /// `command_line`. Reads each input once to hash it (files are streamed: memory does not grow
    /// with their size); an input that cannot be read is an error naming it.
    pub fn new<I, S>(command_line: I, inputs: &[Source]) -> std::io::Result<Self>
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        let inputs = inputs.iter().map(InputFile::of).collect::<Result<_, _>>()?;
        Ok(Self::of_inputs(command_line, inputs))
    }

    /// Provenance of a report made now by this program from inputs already hashed (e.g. by
    /// [`InputHashing`]), for the command line `command_line`.
    pub fn of_inputs<I, S>(command_line: I, inputs: Vec<InputFile>) -> Self
    where
        I: IntoIterator<Item = S>,
        S: Into<String>,
    {
        Self {
            tool: format!("runout {}", env!("CARGO_PKG_VERSION")),
            command_line: command_line.into_iter().map(Into::into).collect(),
            inputs,
            not_hashed: Vec::new(),
            created_utc: utc_now_rfc3339(),
        }
    }

    /// The same provenance, naming `streams` as inputs that were read once and not hashed
    /// ([`Provenance::not_hashed`]).
    ///
    /// ```
    /// use runout::provenance::Provenance;
    /// let p = Provenance::of_inputs(["runout", "identify", "/dev/stdin"], vec![])
    ///     .with_not_hashed(vec!["/dev/stdin".into()]);
    /// assert_eq!(p.not_hashed, ["/dev/stdin"]);
    /// assert!(p.summary_line().ends_with("[inputs: ; not hashed (read once): /dev/stdin]"));
    /// ```
    pub fn with_not_hashed(mut self, streams: Vec<String>) -> Self {
        self.not_hashed = streams;
        self
    }

    /// One line for the metadata of a plot: tool, time, command line and the inputs' hashes
    /// (first 12 hex digits).
    pub fn summary_line(&self) -> String {
        let inputs: Vec<String> = self
            .inputs
            .iter()
            .map(|i| format!("{} sha256:{}", i.name, &i.sha256[..12]))
            .collect();
        let streams = if self.not_hashed.is_empty() {
            String::new()
        } else {
            format!("; not hashed (read once): {}", self.not_hashed.join(", "))
        };
        format!(
            "{} at {}: {} [inputs: {}{streams}]",
            self.tool,
            self.created_utc,
            self.command_line.join(" "),
            inputs.join(", ")
        )
    }
}

impl InputFile {
    /// Name, size and SHA-256 of one source (files are streamed: memory does not grow with
    /// their size).
    pub fn of(source: &Source) -> std::io::Result<Self> {
        let mut done = InputHashing::new(vec![source.clone()]).finish()?;
        Ok(done.pop().expect("one input hashed"))
    }

    fn finished(source: &Source, size_bytes: u64, hasher: Sha256) -> Self {
        Self {
            name: source.name().to_string(),
            size_bytes,
            sha256: hex(&hasher.finalize()),
        }
    }
}

/// Bytes read and hashed per [`InputHashing::step`].
const STEP_BYTES: usize = 1 << 16;

/// The SHA-256 of a list of inputs computed in steps of at most 64 KiB, so that the work can
/// change threads: a clone is a checkpoint — the inputs done, the hash state, the position in
/// the current input and the current input's open file, shared (read at positions, not through
/// a cursor), so that a checkpoint goes on with the file that was opened even when its name has
/// since been removed or given to another file. The CLI hashes on a background thread that runs
/// only on otherwise idle cores and, when the report is ready, goes on from the latest
/// checkpoint on its own thread rather than wait for the background one (which a busy machine
/// may not schedule for long).
///
/// ```
/// use runout::provenance::{InputFile, InputHashing};
/// use runout::Source;
/// let inputs = vec![Source::bytes("a.csv", b"t,Fx\n0,1\n".to_vec())];
/// let mut hashing = InputHashing::new(inputs.clone());
/// let checkpoint = hashing.clone();
/// while !hashing.step()? {}
/// // the checkpoint, finished elsewhere, gives the same hashes
/// assert_eq!(checkpoint.finish()?, hashing.finish()?);
/// assert_eq!(InputHashing::new(inputs.clone()).finish()?, vec![InputFile::of(&inputs[0])?]);
/// # Ok::<(), std::io::Error>(())
/// ```
#[derive(Debug)]
pub struct InputHashing {
    inputs: std::sync::Arc<[Source]>,
    /// The inputs hashed, in order (the first `done.len()` inputs).
    done: Vec<InputFile>,
    /// The hash state of the current input.
    hasher: Sha256,
    /// Bytes of the current input hashed.
    offset: u64,
    /// The current input, open (shared with the clones; read at `offset`), and its length
    /// when it was opened.
    file: Option<std::sync::Arc<(std::fs::File, u64)>>,
    /// Read buffer (not carried by a clone).
    buf: Vec<u8>,
}

impl Clone for InputHashing {
    fn clone(&self) -> Self {
        Self {
            inputs: self.inputs.clone(),
            done: self.done.clone(),
            hasher: self.hasher.clone(),
            offset: self.offset,
            file: self.file.clone(),
            buf: Vec::new(),
        }
    }
}

impl InputHashing {
    /// Nothing hashed yet.
    pub fn new(inputs: Vec<Source>) -> Self {
        Self {
            inputs: inputs.into(),
            done: Vec::new(),
            hasher: Sha256::new(),
            offset: 0,
            file: None,
            buf: Vec::new(),
        }
    }

    /// True when every input is hashed.
    pub fn is_done(&self) -> bool {
        self.done.len() == self.inputs.len()
    }

    /// Hash the next at most 64 KiB of the current input (an in-memory source at once); true
    /// when every input is hashed. An input that cannot be opened or read is an error naming
    /// it (the state is then unchanged: a later step tries the same read again).
    pub fn step(&mut self) -> std::io::Result<bool> {
        let inputs = std::sync::Arc::clone(&self.inputs);
        let Some(source) = inputs.get(self.done.len()) else {
            return Ok(true);
        };
        let Some(path) = source.as_path() else {
            let size = hash_in_memory(source, &mut self.hasher);
            self.close_input(source, size);
            return Ok(self.is_done());
        };
        let file = match &self.file {
            Some(f) => std::sync::Arc::clone(f),
            None => {
                let f = std::fs::File::open(path).map_err(|e| named(source, e))?;
                let len = f.metadata().map_err(|e| named(source, e))?.len();
                self.file.insert(std::sync::Arc::new((f, len))).clone()
            }
        };
        let (file, opened_len) = &*file;
        self.buf.resize(STEP_BYTES, 0);
        let n = read_some_at(file, &mut self.buf, self.offset, source)?;
        if n == 0 {
            if self.offset != *opened_len {
                // shortened or grown while it was hashed: the hash would be of neither the file
                // that was opened nor, perhaps, the one the job read
                return Err(named(
                    source,
                    std::io::Error::other(format!(
                        "it changed while it was read ({opened_len} bytes when opened, {} read)",
                        self.offset
                    )),
                ));
            }
            self.close_input(source, self.offset);
        } else {
            self.hasher.update(&self.buf[..n]);
            self.offset += n as u64;
        }
        Ok(self.is_done())
    }

    /// Step to the end; the inputs' names, sizes and hashes in order.
    pub fn finish(mut self) -> std::io::Result<Vec<InputFile>> {
        while !self.step()? {}
        Ok(self.done)
    }

    fn close_input(&mut self, source: &Source, size_bytes: u64) {
        let hasher = std::mem::take(&mut self.hasher);
        self.done
            .push(InputFile::finished(source, size_bytes, hasher));
        self.offset = 0;
        self.file = None;
    }
}

/// Hash an in-memory source (bytes, or named arrays: each channel's name, a NUL, then its
/// samples as little-endian f64); its size in that form.
fn hash_in_memory(source: &Source, hasher: &mut Sha256) -> u64 {
    match source.as_arrays() {
        Some(arrays) => {
            let mut total = 0u64;
            for (name, samples) in &arrays.columns {
                hasher.update(name.as_bytes());
                hasher.update([0u8]);
                for v in samples.iter() {
                    hasher.update(v.to_le_bytes());
                }
                total += name.len() as u64 + 1 + 8 * samples.len() as u64;
            }
            total
        }
        None => {
            let bytes = source.as_bytes().unwrap_or_default();
            hasher.update(bytes);
            bytes.len() as u64
        }
    }
}

/// One read into `buf` at byte `offset` of `file`, whatever its cursor (positional: the clones
/// of an [`InputHashing`] share the file); again when interrupted; errors name the source.
fn read_some_at(
    file: &std::fs::File,
    buf: &mut [u8],
    offset: u64,
    source: &Source,
) -> std::io::Result<usize> {
    #[cfg(unix)]
    use std::os::unix::fs::FileExt;
    #[cfg(windows)]
    use std::os::windows::fs::FileExt;
    loop {
        #[cfg(unix)]
        let r = file.read_at(buf, offset);
        #[cfg(windows)]
        let r = file.seek_read(buf, offset);
        match r {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            r => return r.map_err(|e| named(source, e)),
        }
    }
}

fn named(source: &Source, e: std::io::Error) -> std::io::Error {
    std::io::Error::new(
        e.kind(),
        format!("{}: cannot read to hash it: {e}", source.name()),
    )
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// A report with its provenance: serialises as the report's fields followed by `provenance`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Stamped<'a, R: Serialize + JsonSchema> {
    /// The report.
    #[serde(flatten)]
    pub report: &'a R,
    /// Where it came from.
    pub provenance: &'a Provenance,
}

/// Now, UTC, as RFC 3339 with whole seconds.
pub fn utc_now_rfc3339() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    rfc3339_from_unix(secs)
}

/// `secs` after 1970-01-01T00:00:00Z as RFC 3339 (UTC, `Z`). Days to civil date by Howard
/// Hinnant's `civil_from_days` (proleptic Gregorian calendar).
pub fn rfc3339_from_unix(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rfc3339_of_known_instants() {
        assert_eq!(rfc3339_from_unix(0), "1970-01-01T00:00:00Z");
        assert_eq!(rfc3339_from_unix(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(rfc3339_from_unix(1_795_650_723), "2026-11-25T23:52:03Z");
        assert_eq!(rfc3339_from_unix(4_107_542_399), "2100-02-28T23:59:59Z");
    }

    #[test]
    fn sha256_of_known_content() {
        // FIPS 180-2 test vector "abc"
        let i = InputFile::of(&Source::bytes("abc", b"abc".to_vec())).unwrap();
        assert_eq!(
            i.sha256,
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(i.size_bytes, 3);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("abc.txt");
        std::fs::write(&p, "abc").unwrap();
        assert_eq!(InputFile::of(&Source::path(&p)).unwrap().sha256, i.sha256);
        let missing = InputFile::of(&Source::path(dir.path().join("none.csv"))).unwrap_err();
        assert!(missing.to_string().contains("none.csv"), "{missing}");
    }

    /// A checkpoint taken after any number of steps, finished on its own (it opens the file
    /// again and seeks), gives the hashes of [`InputFile::of`] — across files of 0, 1 step, a
    /// step and 7 bytes, three steps, and in-memory bytes between them; the original goes on
    /// unaffected by its clones.
    #[test]
    fn a_checkpoint_finished_elsewhere_gives_the_same_hashes() {
        let dir = tempfile::tempdir().unwrap();
        let mut inputs = Vec::new();
        for (i, len) in [STEP_BYTES + 7, 0, STEP_BYTES, 3 * STEP_BYTES]
            .into_iter()
            .enumerate()
        {
            let p = dir.path().join(format!("f{i}.bin"));
            // content that differs per position (a shifted or repeated block changes the hash)
            let bytes: Vec<u8> = (0..len).map(|k| (k * 31 + k / 251 + i) as u8).collect();
            std::fs::write(&p, bytes).unwrap();
            inputs.push(Source::path(p));
            if i == 1 {
                inputs.push(Source::bytes("mem", b"in memory".to_vec()));
            }
        }
        let expected: Vec<InputFile> = inputs.iter().map(|s| InputFile::of(s).unwrap()).collect();
        let mut hashing = InputHashing::new(inputs.clone());
        let mut steps = 0;
        loop {
            let checkpoint = hashing.clone();
            assert_eq!(
                checkpoint.finish().unwrap(),
                expected,
                "checkpoint after {steps} steps"
            );
            steps += 1;
            if hashing.step().unwrap() {
                break;
            }
        }
        // 3 + 1 + 1 + 2 + 4 steps: a file's last step reads its end
        assert_eq!(steps, 11);
        assert!(hashing.is_done());
        assert_eq!(hashing.finish().unwrap(), expected);
    }

    /// A checkpoint goes on with the file that was open when it was taken: its name removed,
    /// or given to a file of other content, does not change the hash (the clones share the
    /// open file and read it at their own positions, in any order).
    #[test]
    fn a_checkpoint_hashes_the_file_that_was_opened() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("rec.txt");
        let content: Vec<u8> = (0..3 * STEP_BYTES + 5).map(|k| (k % 241) as u8).collect();
        std::fs::write(&p, &content).unwrap();
        let expected = InputFile::of(&Source::bytes("rec.txt", content)).unwrap();
        let mut hashing = InputHashing::new(vec![Source::path(&p)]);
        hashing.step().unwrap();
        let checkpoint = hashing.clone();
        hashing.step().unwrap(); // the original reads on: the checkpoint's position is its own
        std::fs::remove_file(&p).unwrap();
        std::fs::write(&p, b"another file under the same name").unwrap();
        let done = checkpoint.finish().unwrap();
        assert_eq!(
            (done[0].size_bytes, &done[0].sha256),
            (expected.size_bytes, &expected.sha256)
        );
        assert_eq!(hashing.finish().unwrap()[0].sha256, expected.sha256);
    }

    /// An input shortened or grown while it is hashed is an error naming it and both sizes: its
    /// hash would be of neither the file that was opened nor, perhaps, the one the job read.
    #[test]
    fn an_input_changed_while_hashed_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("rec.txt");
        let content: Vec<u8> = (0..3 * STEP_BYTES + 5).map(|k| (k % 241) as u8).collect();
        for (new_len, read) in [
            (STEP_BYTES + 9, STEP_BYTES + 9),
            (5 * STEP_BYTES, 5 * STEP_BYTES),
        ] {
            std::fs::write(&p, &content).unwrap();
            let mut hashing = InputHashing::new(vec![Source::path(&p)]);
            hashing.step().unwrap();
            let f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
            f.set_len(new_len as u64).unwrap();
            let e = hashing.finish().unwrap_err().to_string();
            assert!(
                e.contains("rec.txt")
                    && e.contains(&format!(
                        "changed while it was read ({} bytes when opened, {read} read)",
                        content.len()
                    )),
                "{e}"
            );
        }
    }

    /// An input that cannot be read stops the hashing with an error naming it, at every try.
    #[test]
    fn a_missing_input_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let inputs = vec![
            Source::bytes("mem", b"x".to_vec()),
            Source::path(dir.path().join("gone.csv")),
        ];
        let mut hashing = InputHashing::new(inputs);
        assert!(!hashing.step().unwrap());
        for _ in 0..2 {
            let e = hashing.step().unwrap_err();
            assert!(e.to_string().contains("gone.csv"), "{e}");
        }
        assert!(!hashing.is_done());
    }

    #[test]
    fn stamped_is_the_report_plus_provenance() {
        #[derive(Serialize, JsonSchema)]
        struct R {
            schema: &'static str,
            offset_um: f64,
        }
        let p = Provenance::new(["runout", "x"], &[]).unwrap();
        let v = serde_json::to_value(Stamped {
            report: &R {
                schema: "runout.x/1",
                offset_um: 8.0,
            },
            provenance: &p,
        })
        .unwrap();
        assert_eq!(v["offset_um"], 8.0);
        assert_eq!(v["provenance"]["command_line"][1], "x");
        assert_eq!(v.as_object().unwrap().len(), 3);
    }
}
