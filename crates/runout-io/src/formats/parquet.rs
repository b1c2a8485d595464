//! Apache Parquet files (as written by pyarrow, pandas, Spark, polars), behind the `parquet` cargo
//! feature. Channels are numeric top-level columns (float, integer; nulls are read as NaN and
//! reported by the jobs' finite-value checks); the column name is the channel name. Key-value
//! metadata `fs` / `sample_rate_hz` gives the sample rate.
//!
//! Memory: one row group of the numeric columns at a time (decoded to f64).

use super::{Catalog, Entry, Opened, Result, Source};
use crate::recording::{Format, RecordingError};
use arrow_array::{Array, ArrayRef, PrimitiveArray};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use parquet::arrow::ProjectionMask;
use parquet::file::reader::ChunkReader;
use std::path::Path;

fn perr(file: &str, e: impl std::fmt::Display) -> RecordingError {
    RecordingError::Format {
        file: file.into(),
        message: format!("Parquet: {e}"),
    }
}

/// Run a call into the parquet/arrow crates, turning their panics on malformed files (found by
/// fuzzing, e.g. `offset + len out of bounds` in arrow-buffer 60.1) into an error naming the file.
fn guard<T>(file: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(p) => {
            let m = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(perr(
                file,
                format!("malformed file: the decoder failed ({m})"),
            ))
        }
    }
}

fn to_f64(a: &ArrayRef, out: &mut Vec<f64>) -> bool {
    use arrow_array::types::*;
    macro_rules! prim {
        ($t:ty) => {
            if let Some(p) = a.as_any().downcast_ref::<PrimitiveArray<$t>>() {
                out.extend((0..p.len()).map(|i| {
                    if p.is_null(i) {
                        f64::NAN
                    } else {
                        p.value(i) as f64
                    }
                }));
                return true;
            }
        };
    }
    prim!(Float64Type);
    prim!(Float32Type);
    prim!(Int8Type);
    prim!(Int16Type);
    prim!(Int32Type);
    prim!(Int64Type);
    prim!(UInt8Type);
    prim!(UInt16Type);
    prim!(UInt32Type);
    prim!(UInt64Type);
    false
}

struct PqSource<T: ChunkReader + Clone + 'static> {
    data: T,
    file: String,
    /// Rows before each row group.
    starts: Vec<u64>,
    /// Leaf column index of each entry.
    leaf: Vec<usize>,
    /// The decoded row group: (index, one vector per entry).
    cache: Option<(usize, Vec<Vec<f64>>)>,
}

impl<T: ChunkReader + Clone + 'static> PqSource<T> {
    fn load(&mut self, rg: usize) -> Result<()> {
        if self.cache.as_ref().is_some_and(|(i, _)| *i == rg) {
            return Ok(());
        }
        let file = self.file.clone();
        let b = ParquetRecordBatchReaderBuilder::try_new(self.data.clone())
            .map_err(|e| perr(&file, e))?;
        let mask = ProjectionMask::leaves(b.parquet_schema(), self.leaf.iter().copied());
        let reader = b
            .with_row_groups(vec![rg])
            .with_projection(mask)
            .with_batch_size(65_536)
            .build()
            .map_err(|e| perr(&file, e))?;
        let mut cols = vec![Vec::new(); self.leaf.len()];
        for batch in reader {
            let batch = batch.map_err(|e| perr(&file, format!("row group {rg}: {e}")))?;
            for (k, c) in cols.iter_mut().enumerate() {
                let a = batch.column(k);
                if !to_f64(a, c) {
                    return Err(perr(
                        &file,
                        format!("row group {rg}: column {k} is not numeric"),
                    ));
                }
            }
        }
        self.cache = Some((rg, cols));
        Ok(())
    }
}

impl<T: ChunkReader + Clone + Send + 'static> Source for PqSource<T> {
    fn read(&mut self, entry: usize, start: u64, n: usize, out: &mut Vec<f64>) -> Result<()> {
        let end = start + n as u64;
        let mut s = start;
        while s < end {
            let rg = self.starts.partition_point(|&r| r <= s).saturating_sub(1);
            if rg + 1 >= self.starts.len() {
                break;
            }
            let file = self.file.clone();
            guard(&file, || self.load(rg))?;
            let rows_end = self.starts[rg + 1];
            let Some((_, cols)) = &self.cache else { break };
            let col = &cols[entry];
            let a = (s - self.starts[rg]) as usize;
            let b = ((end.min(rows_end)) - self.starts[rg]) as usize;
            if b > col.len() || a >= b {
                return Err(perr(
                    &self.file,
                    format!(
                        "row group {rg}: expected {} rows, decoded {}",
                        rows_end - self.starts[rg],
                        col.len()
                    ),
                ));
            }
            out.extend_from_slice(&col[a..b]);
            s = end.min(rows_end);
        }
        Ok(())
    }
}

fn build<T: ChunkReader + Clone + Send + 'static>(data: T, file: &str) -> Result<Opened> {
    let b = ParquetRecordBatchReaderBuilder::try_new(data.clone()).map_err(|e| perr(file, e))?;
    let meta = b.metadata().clone();
    let schema = b.schema().clone();
    let mut starts = vec![0u64];
    for rg in meta.row_groups() {
        let last = *starts.last().unwrap_or(&0);
        starts.push(last + rg.num_rows().max(0) as u64);
    }
    let rows = *starts.last().unwrap_or(&0);
    let kv: Vec<(String, String)> = meta
        .file_metadata()
        .key_value_metadata()
        .map(|v| {
            v.iter()
                .filter(|k| k.key != "ARROW:schema" && k.key != "pandas")
                .map(|k| (k.key.clone(), k.value.clone().unwrap_or_default()))
                .collect()
        })
        .unwrap_or_default();
    let rate = kv
        .iter()
        .find(|(k, _)| {
            matches!(
                k.to_ascii_lowercase().as_str(),
                "fs" | "sample_rate_hz" | "sample_rate"
            )
        })
        .and_then(|(_, v)| v.trim().parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v > 0.0);
    let mut entries = Vec::new();
    let mut leaf = Vec::new();
    // leaf index = position among the leaves; top-level primitive fields map 1:1
    let leaves = meta.file_metadata().schema_descr();
    for (i, f) in schema.fields().iter().enumerate() {
        let mut e = Entry::numeric(f.name().clone(), None, f.name().clone(), rows);
        e.dtype = format!("{}", f.data_type());
        e.readable = f.data_type().is_numeric() && !f.data_type().is_nested();
        e.sample_rate_hz = rate;
        if let Some(u) = f.metadata().get("unit") {
            e.unit = Some(u.clone());
        }
        if !e.readable {
            e.note = Some("not a numeric column".into());
        }
        // find the leaf with this top-level name
        let li = (0..leaves.num_columns())
            .find(|&c| leaves.column(c).path().parts() == [f.name().clone()]);
        match li {
            Some(l) if e.readable => leaf.push(l),
            _ => {
                e.readable = false;
                leaf.push(usize::MAX);
            }
        }
        let _ = i;
        entries.push(e);
    }
    // only readable columns are decoded: remap
    let readable: Vec<usize> = (0..entries.len())
        .filter(|&i| entries[i].readable)
        .collect();
    let mut src = PqSource {
        data,
        file: file.into(),
        starts,
        leaf: readable.iter().map(|&i| leaf[i]).collect(),
        cache: None,
    };
    // scalars: 1-row columns
    if rows == 1 {
        for (k, &i) in readable.iter().enumerate() {
            let mut v = Vec::new();
            src.read(k, 0, 1, &mut v)?;
            entries[i].scalar = v.first().copied();
        }
    }
    Ok(Opened {
        catalog: Catalog {
            format: Format::Parquet,
            entries,
            metadata: kv,
        },
        source: Box::new(Remap {
            inner: src,
            map: (0..leaf.len())
                .map(|i| readable.iter().position(|&r| r == i))
                .collect(),
            file: file.into(),
        }),
    })
}

struct Remap<S> {
    inner: S,
    map: Vec<Option<usize>>,
    file: String,
}

impl<S: Source> Source for Remap<S> {
    fn read(&mut self, entry: usize, start: u64, n: usize, out: &mut Vec<f64>) -> Result<()> {
        match self.map.get(entry).copied().flatten() {
            Some(k) => self.inner.read(k, start, n, out),
            None => Err(perr(&self.file, format!("column {entry} is not numeric"))),
        }
    }
}

/// Open a Parquet file (row group by row group).
pub fn open_path(path: &Path, file: &str) -> Result<Opened> {
    let f = std::fs::File::open(path).map_err(|error| RecordingError::Io {
        file: file.into(),
        error,
    })?;
    guard(file, || build(SharedFile(std::sync::Arc::new(f)), file))
}

/// Open a Parquet file held in memory.
pub fn open_bytes(bytes: Vec<u8>, file: &str) -> Result<Opened> {
    guard(file, || build(bytes::Bytes::from(bytes), file))
}

/// A file shared by the readers of several row groups.
#[derive(Clone)]
struct SharedFile(std::sync::Arc<std::fs::File>);

impl parquet::file::reader::Length for SharedFile {
    fn len(&self) -> u64 {
        self.0.metadata().map(|m| m.len()).unwrap_or(0)
    }
}

impl ChunkReader for SharedFile {
    type T = <std::fs::File as ChunkReader>::T;
    fn get_read(&self, start: u64) -> parquet::errors::Result<Self::T> {
        self.0.as_ref().get_read(start)
    }
    fn get_bytes(&self, start: u64, length: usize) -> parquet::errors::Result<bytes::Bytes> {
        self.0.as_ref().get_bytes(start, length)
    }
}

/// A typed column of a table written as Parquet ([`write_table`]): 64-bit floats (nullable:
/// `None` is a null, e.g. a value not available) or UTF-8 text.
#[derive(Debug, Clone, PartialEq)]
pub enum TableColumn {
    /// Parquet `DOUBLE` (Arrow `Float64`), nullable.
    Float(Vec<Option<f64>>),
    /// Parquet `BYTE_ARRAY` UTF-8 (Arrow `Utf8`), not null.
    Text(Vec<String>),
}

impl TableColumn {
    fn len(&self) -> usize {
        match self {
            TableColumn::Float(v) => v.len(),
            TableColumn::Text(v) => v.len(),
        }
    }
}

/// Write a table of named, typed columns (all the same length) as one Parquet file (one row
/// group, snappy-compressed), e.g. the batch summary. `file` names the output in messages.
pub fn write_table<W: std::io::Write + Send>(
    w: W,
    columns: &[(String, TableColumn)],
    file: &str,
) -> std::result::Result<(), RecordingError> {
    use arrow_array::{Float64Array, RecordBatch, StringArray};
    use parquet::arrow::ArrowWriter;
    use parquet::basic::Compression;
    use parquet::file::properties::WriterProperties;
    use std::sync::Arc;
    let rows = columns.first().map(|(_, c)| c.len()).unwrap_or(0);
    if let Some((name, _)) = columns.iter().find(|(_, c)| c.len() != rows) {
        return Err(perr(
            file,
            format!("column `{name}` has a different length than the first ({rows} rows)"),
        ));
    }
    let arrays = columns.iter().map(|(name, c)| {
        let (a, nullable): (ArrayRef, bool) = match c {
            TableColumn::Float(v) => (Arc::new(Float64Array::from(v.clone())), true),
            TableColumn::Text(v) => (Arc::new(StringArray::from(v.clone())), false),
        };
        (name.as_str(), a, nullable)
    });
    let batch = RecordBatch::try_from_iter_with_nullable(arrays).map_err(|e| perr(file, e))?;
    let props = WriterProperties::builder()
        .set_compression(Compression::SNAPPY)
        .build();
    let mut writer =
        ArrowWriter::try_new(w, batch.schema(), Some(props)).map_err(|e| perr(file, e))?;
    writer.write(&batch).map_err(|e| perr(file, e))?;
    writer.close().map_err(|e| perr(file, e))?;
    Ok(())
}

/// Read a table written by [`write_table`] (or any Parquet file of top-level `DOUBLE` and UTF-8
/// columns): the columns in file order. Another column type is an error naming it.
pub fn read_table(path: &Path) -> std::result::Result<Vec<(String, TableColumn)>, RecordingError> {
    use arrow_array::{Float64Array, RecordBatchReader, StringArray};
    let file = path.display().to_string();
    let f = std::fs::File::open(path).map_err(|error| RecordingError::Io {
        file: file.clone(),
        error,
    })?;
    guard(&file, || {
        let reader = ParquetRecordBatchReaderBuilder::try_new(f)
            .and_then(|b| b.build())
            .map_err(|e| perr(&file, e))?;
        let mut out: Vec<(String, TableColumn)> = reader
            .schema()
            .fields()
            .iter()
            .map(|fl| {
                let empty = if fl.data_type().is_numeric() {
                    TableColumn::Float(Vec::new())
                } else {
                    TableColumn::Text(Vec::new())
                };
                (fl.name().clone(), empty)
            })
            .collect();
        for batch in reader {
            let batch = batch.map_err(|e| perr(&file, e))?;
            for ((name, col), a) in out.iter_mut().zip(batch.columns()) {
                match col {
                    TableColumn::Float(v) => {
                        let a = a.as_any().downcast_ref::<Float64Array>().ok_or_else(|| {
                            perr(
                                &file,
                                format!("column `{name}`: expected DOUBLE, got {}", a.data_type()),
                            )
                        })?;
                        v.extend(a.iter());
                    }
                    TableColumn::Text(v) => {
                        let a = a.as_any().downcast_ref::<StringArray>().ok_or_else(|| {
                            perr(
                                &file,
                                format!(
                                    "column `{name}`: expected UTF-8 text, got {}",
                                    a.data_type()
                                ),
                            )
                        })?;
                        v.extend(a.iter().map(|s| s.unwrap_or_default().to_string()));
                    }
                }
            }
        }
        Ok(out)
    })
}
