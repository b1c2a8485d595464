//! The job framework: where inputs come from ([`Source`]), how progress is reported
//! ([`Progress`]), and the report convention ([`Report`]).

use runout_io::recording::{ReadOptions, RecordingError, RecordingReader};
use runout_io::textfile::TextFileError;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Progress of a long job, in bytes of input per stage (a pass over a recording). The CLI
/// turns it into progress bars; a library caller may ignore it ([`NoProgress`]).
pub trait Progress {
    /// A stage starts (`"pass 1/2"`), over `total_bytes` of input if known.
    fn begin(&mut self, _stage: &str, _total_bytes: Option<u64>) {}
    /// Bytes of the stage done so far.
    fn set_position(&mut self, _bytes: u64) {}
    /// Bytes done since the last call.
    fn advance(&mut self, _bytes: u64) {}
    /// The stage is finished.
    fn end(&mut self) {}
}

/// Reports nothing.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoProgress;

impl Progress for NoProgress {}

/// A typed report: serialises to the job's JSON; `SCHEMA` is its `schema` field
/// (`runout.<job>/<version>`; the version changes when a field changes meaning or is removed).
pub trait Report: serde::Serialize + schemars::JsonSchema {
    /// `runout.<job>/<version>`.
    const SCHEMA: &'static str;
}

/// The report as pretty JSON with a final newline (what `--json` writes).
pub fn to_json<R: Report>(report: &R) -> serde_json::Result<String> {
    Ok(serde_json::to_string_pretty(report)? + "\n")
}

/// Where an input comes from: a file, or bytes in memory (from Python, a network, a distributed
/// engine) with a display name. Messages name the source by [`Source::name`] as they name a
/// file, with line and column.
#[derive(Debug, Clone)]
pub struct Source {
    name: String,
    kind: Kind,
}

#[derive(Debug, Clone)]
enum Kind {
    Path(PathBuf),
    Bytes(Arc<[u8]>),
    Arrays(Arc<runout_io::formats::Arrays>),
}

impl Source {
    /// A file.
    pub fn path(path: impl Into<PathBuf>) -> Self {
        let path = path.into();
        Self {
            name: path.display().to_string(),
            kind: Kind::Path(path),
        }
    }

    /// Bytes in memory, named `name` in messages.
    pub fn bytes(name: impl Into<String>, bytes: impl Into<Arc<[u8]>>) -> Self {
        Self {
            name: name.into(),
            kind: Kind::Bytes(bytes.into()),
        }
    }

    /// Named arrays in memory (NumPy arrays from the Python package), named `name` in messages:
    /// a recording (read without a round trip through text; `t`/`time_s` is the time vector, a
    /// one-value `fs` the sample rate), or a table whose columns are the arrays (a CSV with one
    /// column per array, values written exactly, for the table readers).
    pub fn arrays(name: impl Into<String>, arrays: runout_io::formats::Arrays) -> Self {
        Self {
            name: name.into(),
            kind: Kind::Arrays(Arc::new(arrays)),
        }
    }

    /// The name used in messages and reports (the path as given, for a file).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The file, if the source is one.
    pub fn as_path(&self) -> Option<&Path> {
        match &self.kind {
            Kind::Path(p) => Some(p),
            Kind::Bytes(_) | Kind::Arrays(_) => None,
        }
    }

    /// The bytes, if the source is bytes held in memory.
    pub fn as_bytes(&self) -> Option<&[u8]> {
        match &self.kind {
            Kind::Path(_) | Kind::Arrays(_) => None,
            Kind::Bytes(b) => Some(b),
        }
    }

    /// The named arrays, if the source is arrays held in memory.
    pub fn as_arrays(&self) -> Option<&runout_io::formats::Arrays> {
        match &self.kind {
            Kind::Arrays(a) => Some(a),
            Kind::Path(_) | Kind::Bytes(_) => None,
        }
    }

    /// The folder that relative file names inside this source are resolved from (the file's
    /// folder; `.` for bytes).
    pub fn dir(&self) -> &Path {
        self.as_path()
            .and_then(Path::parent)
            .unwrap_or(Path::new("."))
    }

    /// The whole source as UTF-8 text, with the size and line-length limits of
    /// [`runout_io::textfile::read_text`].
    pub fn read_text(&self) -> Result<String, TextFileError> {
        match &self.kind {
            Kind::Path(p) => runout_io::textfile::read_text(p),
            Kind::Bytes(b) => runout_io::textfile::text_from_bytes(&self.name, b.to_vec()),
            Kind::Arrays(a) => runout_io::textfile::text_from_bytes(&self.name, arrays_csv(a)),
        }
    }

    /// The source as a table input of `runout_io::displacement` (a file, or the bytes).
    pub fn table_input(&self) -> runout_io::displacement::TableInput<'_> {
        match &self.kind {
            Kind::Path(p) => runout_io::displacement::TableInput::Path(p),
            Kind::Bytes(b) => runout_io::displacement::TableInput::Reader {
                name: &self.name,
                reader: Box::new(&b[..]),
                len: Some(b.len() as u64),
            },
            Kind::Arrays(a) => {
                let csv = arrays_csv(a);
                runout_io::displacement::TableInput::Reader {
                    name: &self.name,
                    len: Some(csv.len() as u64),
                    reader: Box::new(std::io::Cursor::new(csv)),
                }
            }
        }
    }

    /// A streaming recording reader over the source (header read; see
    /// [`RecordingReader::from_reader`]).
    pub fn open_recording(
        &self,
        options: &ReadOptions,
    ) -> Result<RecordingReader<Box<dyn BufRead + Send>>, RecordingError> {
        match &self.kind {
            // any supported format, detected by content (runout_io::formats)
            Kind::Path(p) => Ok(runout_io::recording::open_recording(p, options)?.boxed()),
            // any supported format held in memory, detected by content
            Kind::Bytes(b) => {
                runout_io::formats::recording_from_shared(&self.name, b.clone(), None, options)
            }
            Kind::Arrays(a) => {
                Ok(runout_io::formats::recording_from_arrays(&self.name, a, options)?.boxed())
            }
        }
    }
}

/// Arrays as a CSV table: the names as the header row, one row per index (shorter arrays leave
/// their cells empty), every value in Rust's shortest round-trip form (read back exactly).
fn arrays_csv(a: &runout_io::formats::Arrays) -> Vec<u8> {
    use std::fmt::Write;
    let rows = a.columns.iter().map(|(_, v)| v.len()).max().unwrap_or(0);
    let mut s = a
        .columns
        .iter()
        .map(|(n, _)| n.as_str())
        .collect::<Vec<_>>()
        .join(",");
    s.push('\n');
    for i in 0..rows {
        for (k, (_, v)) in a.columns.iter().enumerate() {
            if k > 0 {
                s.push(',');
            }
            if let Some(x) = v.get(i) {
                let _ = write!(s, "{x}");
            }
        }
        s.push('\n');
    }
    s.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binary_bytes_in_memory_read_like_the_file() {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../runout-io/tests/fixtures/matrix.h5");
        let o = ReadOptions::new().channels(&["data/Fx", "dataT[:,1]"]);
        let mut a = Source::path(&p).open_recording(&o).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        let mut b = Source::bytes("mem.h5", &bytes[..])
            .open_recording(&o)
            .unwrap();
        assert_eq!(b.info().file, "mem.h5");
        assert_eq!(a.info().sample_rate_hz, b.info().sample_rate_hz);
        let (mut ca, mut cb) = Default::default();
        let (na, nb) = (
            a.read_chunk(&mut ca, 1000).unwrap(),
            b.read_chunk(&mut cb, 1000).unwrap(),
        );
        assert_eq!((na, nb), (200, 200));
        let (ca, cb): (
            runout_io::recording::RecordingChunk,
            runout_io::recording::RecordingChunk,
        ) = (ca, cb);
        assert_eq!(ca.values, cb.values);
        assert_eq!(ca.time_s, cb.time_s);
        // a truncated copy: a clear error naming the source, no panic
        let e = Source::bytes("cut.h5", &bytes[..300])
            .open_recording(&o)
            .err()
            .unwrap();
        assert!(e.to_string().contains("cut.h5"), "{e}");
    }

    #[test]
    fn a_source_in_memory_reads_like_a_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.csv");
        let text = "time_s,a_um\n0,1\n0.001,2\n0.002,3\n";
        std::fs::write(&p, text).unwrap();
        let o = ReadOptions::new();
        let from_file = Source::path(&p).open_recording(&o).unwrap();
        let from_bytes = Source::bytes("mem.csv", text.as_bytes())
            .open_recording(&o)
            .unwrap();
        assert_eq!(
            from_file.info().sample_rate_hz,
            from_bytes.info().sample_rate_hz
        );
        assert_eq!(from_bytes.info().file, "mem.csv");
        assert_eq!(from_bytes.info().file_bytes, Some(text.len() as u64));
        assert_eq!(from_file.info().file_bytes, Some(text.len() as u64));
        // messages name the in-memory source like a file, with its line
        let bad = Source::bytes("mem.csv", &b"time_s,a_um\n0,1\n0.001,x\n"[..]);
        let mut r = bad.open_recording(&o).unwrap();
        let mut chunk = runout_io::recording::RecordingChunk::default();
        let e = loop {
            match r.read_chunk(&mut chunk, 10) {
                Ok(0) => panic!("bad value accepted"),
                Ok(_) => {}
                Err(e) => break e.to_string(),
            }
        };
        assert!(e.starts_with("mem.csv:3"), "{e}");
        // text sources keep the limits and name the source
        let e = Source::bytes("cfg.toml", &[0xffu8, 0xfe][..])
            .read_text()
            .unwrap_err();
        assert!(e.to_string().starts_with("cfg.toml:1: not UTF-8"), "{e}");
        assert_eq!(Source::path(&p).read_text().unwrap(), text);
        assert_eq!(Source::path(&p).dir(), dir.path());
        assert_eq!(Source::bytes("x", &b""[..]).dir(), Path::new("."));
    }

    #[test]
    fn arrays_are_a_recording_and_a_table() {
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.001).collect();
        let a: Vec<f64> = t.iter().map(|t| 0.1 + t * t).collect();
        let arrays = runout_io::formats::Arrays {
            columns: vec![
                ("time_s".into(), Arc::from(t.as_slice())),
                ("a_um".into(), Arc::from(a.as_slice())),
            ],
        };
        let s = Source::arrays("numpy", arrays);
        let mut r = s.open_recording(&ReadOptions::new()).unwrap();
        assert_eq!(r.info().file, "numpy");
        let mut chunk = runout_io::recording::RecordingChunk::default();
        r.read_chunk(&mut chunk, 1000).unwrap();
        assert_eq!(chunk.channel(0), &a[..]);
        // as text: the same values, exactly, through a CSV reader
        let text = s.read_text().unwrap();
        let mut r =
            RecordingReader::from_bytes("csv", text.as_bytes(), &ReadOptions::new()).unwrap();
        r.read_chunk(&mut chunk, 1000).unwrap();
        assert_eq!(chunk.channel(0), &a[..]);
        assert!(s.as_path().is_none());
    }

    #[test]
    fn a_missing_file_is_named() {
        let e = Source::path("/no/such/rec.csv")
            .open_recording(&ReadOptions::new())
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("/no/such/rec.csv"), "{e}");
    }
}
