//! Apache Parquet files (as written by pyarrow, pandas, Spark, polars), read and written with the
//! `parquet` crate's own column API (no Arrow). Channels are numeric top-level columns: `DOUBLE`,
//! `FLOAT`, `INT32`, `INT64` including their integer logical types (`int8` … `uint64`; unsigned
//! values are read as unsigned); nulls are read as NaN and reported by the jobs' finite-value
//! checks. The column name is the channel name. Key-value metadata `fs` / `sample_rate_hz` gives
//! the sample rate. Compressions read: uncompressed, snappy, gzip, zstd, lz4 (raw and Hadoop);
//! another one (brotli, LZO) is an error naming it.
//!
//! Memory: one row group of the read columns at a time (decoded to f64).

use super::{Catalog, Entry, Opened, Result, Source};
use crate::recording::{Format, RecordingError};
use parquet::basic::{Compression, ConvertedType, LogicalType, Repetition, Type as Physical};
use parquet::column::reader::{ColumnReader, ColumnReaderImpl};
use parquet::data_type::{ByteArray, ByteArrayType, DataType, DoubleType};
use parquet::file::reader::{ChunkReader, FileReader, SerializedFileReader};
use parquet::schema::types::{ColumnDescriptor, Type as SchemaType};
use std::path::Path;
use std::sync::Arc;

fn perr(file: &str, e: impl std::fmt::Display) -> RecordingError {
    RecordingError::Format {
        file: file.into(),
        message: format!("Parquet: {e}"),
    }
}

/// Run a call into the parquet crate, turning its panics on malformed files (found by fuzzing,
/// e.g. `offset + len out of bounds` in 60.1's buffers) into an error naming the file.
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

/// Records decoded per `read_records` call.
const BATCH: usize = 65_536;

/// The compressions this build decodes (the `parquet` crate's codec features enabled in
/// `Cargo.toml`).
fn codec_supported(c: Compression) -> bool {
    matches!(
        c,
        Compression::UNCOMPRESSED
            | Compression::SNAPPY
            | Compression::GZIP(_)
            | Compression::ZSTD(_)
            | Compression::LZ4
            | Compression::LZ4_RAW
    )
}

/// The codec's name as Parquet spells it (`BROTLI`, without the level).
fn codec_name(c: Compression) -> String {
    let s = c.to_string();
    s.split('(').next().unwrap_or(&s).to_string()
}

/// How a numeric column's stored values become f64.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Num {
    /// `FLOAT`.
    F32,
    /// `DOUBLE`.
    F64,
    /// `INT32`, signed (plain, `int8`, `int16`, `int32`).
    I32,
    /// `INT32` holding an unsigned value (`uint8`, `uint16`, `uint32`).
    U32,
    /// `INT64`, signed.
    I64,
    /// `INT64` holding an unsigned value (`uint64`).
    U64,
}

/// The integer type a logical / converted annotation states: (bits, signed); `Some((0, true))`
/// for no annotation (a plain integer of the physical width); `None` for a non-integer one (date,
/// time, timestamp, decimal…).
fn int_annotation(c: &ColumnDescriptor) -> Option<(u8, bool)> {
    match c.logical_type_ref() {
        Some(LogicalType::Integer(t)) => return Some((t.bit_width as u8, t.is_signed)),
        Some(_) => return None,
        None => {}
    }
    Some(match c.converted_type() {
        ConvertedType::NONE => (0, true),
        ConvertedType::INT_8 => (8, true),
        ConvertedType::INT_16 => (16, true),
        ConvertedType::INT_32 => (32, true),
        ConvertedType::INT_64 => (64, true),
        ConvertedType::UINT_8 => (8, false),
        ConvertedType::UINT_16 => (16, false),
        ConvertedType::UINT_32 => (32, false),
        ConvertedType::UINT_64 => (64, false),
        _ => return None,
    })
}

/// The element type of a leaf column, named as Arrow names it (`Float64`, `Int16`, `UInt32`,
/// `Utf8`…), and how to read it when it is a number.
fn classify(c: &ColumnDescriptor) -> (String, Option<Num>) {
    let int = |phys_bits: u8, signed_num: Num, unsigned_num: Num| match int_annotation(c) {
        Some((bits, signed)) => {
            let bits = if bits == 0 { phys_bits } else { bits };
            let name = format!("{}Int{bits}", if signed { "" } else { "U" });
            (name, Some(if signed { signed_num } else { unsigned_num }))
        }
        None => (annotated(c), None),
    };
    match c.physical_type() {
        Physical::DOUBLE if c.logical_type_ref().is_none() => ("Float64".into(), Some(Num::F64)),
        Physical::FLOAT if c.logical_type_ref().is_none() => ("Float32".into(), Some(Num::F32)),
        Physical::INT32 => int(32, Num::I32, Num::U32),
        Physical::INT64 => int(64, Num::I64, Num::U64),
        Physical::BOOLEAN => ("Boolean".into(), None),
        Physical::BYTE_ARRAY
            if matches!(c.logical_type_ref(), Some(LogicalType::String))
                || c.converted_type() == ConvertedType::UTF8 =>
        {
            ("Utf8".into(), None)
        }
        _ => (annotated(c), None),
    }
}

/// `INT64 (timestamp)`-style description of a column that is not a plain number.
fn annotated(c: &ColumnDescriptor) -> String {
    let phys = c.physical_type().to_string();
    match c.logical_type_ref() {
        Some(LogicalType::Timestamp(_)) => format!("{phys} (timestamp)"),
        Some(l) => format!("{phys} ({l:?})"),
        None if c.converted_type() != ConvertedType::NONE => {
            format!("{phys} ({})", c.converted_type())
        }
        None => phys,
    }
}

/// Decode one column chunk (every record of it) into `out`: each value through `conv`, each null
/// as `null()`; an error past `max` records (a corrupted page count must not allocate unboundedly).
fn decode_typed<T: DataType, O>(
    mut r: ColumnReaderImpl<T>,
    max_def: i16,
    max: usize,
    conv: impl Fn(&T::T) -> std::result::Result<O, String>,
    null: impl Fn() -> O,
    out: &mut Vec<O>,
) -> std::result::Result<(), String> {
    let mut vals: Vec<T::T> = Vec::new();
    let mut defs: Vec<i16> = Vec::new();
    let start = out.len();
    loop {
        vals.clear();
        defs.clear();
        let (records, values, _) = r
            .read_records(BATCH, Some(&mut defs), None, &mut vals)
            .map_err(|e| e.to_string())?;
        if records == 0 {
            return Ok(());
        }
        if max_def == 0 {
            for v in &vals[..values.min(vals.len())] {
                out.push(conv(v)?);
            }
        } else {
            // one definition level per record (no repetition): a value where it is the maximum
            let mut it = vals.iter();
            for &d in &defs[..records.min(defs.len())] {
                if d >= max_def {
                    let v = it
                        .next()
                        .ok_or("fewer values than the definition levels state")?;
                    out.push(conv(v)?);
                } else {
                    out.push(null());
                }
            }
        }
        if out.len() - start > max {
            return Err(format!("more than the {max} rows the row group states"));
        }
    }
}

/// Decode a numeric column chunk to f64, nulls as NaN.
fn decode(
    cr: ColumnReader,
    num: Num,
    max_def: i16,
    max: usize,
    out: &mut Vec<f64>,
) -> std::result::Result<(), String> {
    let nan = || f64::NAN;
    match (cr, num) {
        (ColumnReader::DoubleColumnReader(r), Num::F64) => {
            decode_typed(r, max_def, max, |v| Ok(*v), nan, out)
        }
        (ColumnReader::FloatColumnReader(r), Num::F32) => {
            decode_typed(r, max_def, max, |v| Ok(f64::from(*v)), nan, out)
        }
        (ColumnReader::Int32ColumnReader(r), Num::I32) => {
            decode_typed(r, max_def, max, |v| Ok(f64::from(*v)), nan, out)
        }
        (ColumnReader::Int32ColumnReader(r), Num::U32) => {
            // unsigned values stored in INT32's bits
            decode_typed(r, max_def, max, |v| Ok(f64::from(*v as u32)), nan, out)
        }
        (ColumnReader::Int64ColumnReader(r), Num::I64) => {
            decode_typed(r, max_def, max, |v| Ok(*v as f64), nan, out)
        }
        (ColumnReader::Int64ColumnReader(r), Num::U64) => {
            decode_typed(r, max_def, max, |v| Ok(*v as u64 as f64), nan, out)
        }
        (_, num) => Err(format!(
            "the column reader does not match the type ({num:?})"
        )),
    }
}

/// A numeric top-level column.
#[derive(Debug, Clone)]
struct Col {
    /// Leaf index in the file schema.
    leaf: usize,
    num: Num,
    max_def: i16,
}

struct PqSource<R: ChunkReader + 'static> {
    reader: SerializedFileReader<R>,
    file: String,
    /// Column name of each entry.
    names: Vec<String>,
    /// Rows before each row group (one more than the row groups: the total last).
    starts: Vec<u64>,
    /// How to read each entry (`None`: not numeric).
    cols: Vec<Option<Col>>,
    /// The row group decoded and its decoded columns (by entry, decoded on first use).
    cache: Option<(usize, Vec<Option<Vec<f64>>>)>,
}

impl<R: ChunkReader + 'static> PqSource<R> {
    /// Decode column `entry` of row group `rg` into the cache (dropping another row group's).
    fn load(&mut self, entry: usize, rg: usize) -> Result<()> {
        if self.cache.as_ref().is_none_or(|(i, _)| *i != rg) {
            self.cache = Some((rg, vec![None; self.cols.len()]));
        }
        if let Some((_, c)) = &self.cache {
            if c[entry].is_some() {
                return Ok(());
            }
        }
        let name = &self.names[entry];
        let Some(col) = self.cols[entry].clone() else {
            return Err(perr(&self.file, format!("column `{name}` is not numeric")));
        };
        let rows = (self.starts[rg + 1] - self.starts[rg]) as usize;
        let ctx = |m: String| perr(&self.file, format!("row group {rg}, column `{name}`: {m}"));
        let group = self
            .reader
            .get_row_group(rg)
            .map_err(|e| ctx(e.to_string()))?;
        let codec = group.metadata().column(col.leaf).compression();
        if !codec_supported(codec) {
            return Err(ctx(format!(
                "compressed with {}, which runout does not read (it reads uncompressed, SNAPPY, \
                 GZIP, ZSTD, LZ4 and LZ4_RAW; e.g. pyarrow `compression=\"zstd\"`)",
                codec_name(codec)
            )));
        }
        let cr = group
            .get_column_reader(col.leaf)
            .map_err(|e| ctx(e.to_string()))?;
        let mut v = Vec::new();
        decode(cr, col.num, col.max_def, rows, &mut v).map_err(ctx)?;
        if v.len() != rows {
            return Err(ctx(format!("expected {rows} rows, decoded {}", v.len())));
        }
        if let Some((_, c)) = &mut self.cache {
            c[entry] = Some(v);
        }
        Ok(())
    }
}

impl<R: ChunkReader + 'static> Source for PqSource<R> {
    fn read(&mut self, entry: usize, start: u64, n: usize, out: &mut Vec<f64>) -> Result<()> {
        let end = start + n as u64;
        let mut s = start;
        while s < end {
            let rg = self.starts.partition_point(|&r| r <= s).saturating_sub(1);
            if rg + 1 >= self.starts.len() {
                break;
            }
            let file = self.file.clone();
            guard(&file, || self.load(entry, rg))?;
            let rows_end = self.starts[rg + 1];
            let Some(col) = self.cache.as_ref().and_then(|(_, c)| c[entry].as_ref()) else {
                break;
            };
            let a = (s - self.starts[rg]) as usize;
            let b = (end.min(rows_end) - self.starts[rg]) as usize;
            if b > col.len() || a >= b {
                break;
            }
            out.extend_from_slice(&col[a..b]);
            s = end.min(rows_end);
        }
        Ok(())
    }
}

fn build<R: ChunkReader + 'static>(data: R, file: &str) -> Result<Opened> {
    let reader = SerializedFileReader::new(data).map_err(|e| perr(file, e))?;
    let meta = reader.metadata();
    let mut starts = vec![0u64];
    for rg in meta.row_groups() {
        let last = *starts.last().unwrap_or(&0);
        starts.push(last.saturating_add(rg.num_rows().max(0) as u64));
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
    let leaves = meta.file_metadata().schema_descr();
    let mut entries = Vec::new();
    let mut cols = Vec::new();
    let mut names = Vec::new();
    for f in leaves.root_schema().get_fields() {
        let name = f.name().to_string();
        let mut e = Entry::numeric(name.clone(), None, name.clone(), rows);
        e.sample_rate_hz = rate;
        // the leaf of a top-level primitive, not repeated, column
        let leaf = (0..leaves.num_columns())
            .find(|&c| leaves.column(c).path().parts() == [name.clone()])
            .filter(|_| {
                f.is_primitive() && f.get_basic_info().repetition() != Repetition::REPEATED
            });
        let col = match leaf {
            Some(l) => {
                let d = leaves.column(l);
                let (dtype, num) = classify(&d);
                e.dtype = dtype;
                num.map(|num| Col {
                    leaf: l,
                    num,
                    max_def: d.max_def_level(),
                })
            }
            None => {
                e.dtype = if f.is_group() {
                    "group".into()
                } else {
                    "list".into()
                };
                None
            }
        };
        if col.is_none() {
            e.readable = false;
            e.note = Some("not a numeric column".into());
        } else if let Some(c) = &col {
            let bad = meta
                .row_groups()
                .iter()
                .map(|g| g.column(c.leaf).compression())
                .find(|c| !codec_supported(*c));
            if let Some(codec) = bad {
                e.note = Some(format!(
                    "compressed with {}, which runout does not read",
                    codec_name(codec)
                ));
            }
        }
        cols.push(col);
        names.push(name);
        entries.push(e);
    }
    let mut src = PqSource {
        reader,
        file: file.into(),
        names,
        starts,
        cols,
        cache: None,
    };
    // scalars: 1-row columns
    if rows == 1 {
        for (i, e) in entries.iter_mut().enumerate() {
            if e.readable && e.note.is_none() {
                let mut v = Vec::new();
                src.read(i, 0, 1, &mut v)?;
                e.scalar = v.first().copied();
            }
        }
    }
    Ok(Opened {
        catalog: Catalog {
            format: Format::Parquet,
            entries,
            metadata: kv,
        },
        source: Box::new(src),
    })
}

/// Open a Parquet file (row group by row group).
pub fn open_path(path: &Path, file: &str) -> Result<Opened> {
    let f = std::fs::File::open(path).map_err(|error| RecordingError::Io {
        file: file.into(),
        error,
    })?;
    guard(file, || build(f, file))
}

/// Open a Parquet file held in memory.
pub fn open_bytes(bytes: Vec<u8>, file: &str) -> Result<Opened> {
    guard(file, || build(bytes::Bytes::from(bytes), file))
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

/// The Parquet schema of a table: `optional double` for [`TableColumn::Float`], `required binary
/// (STRING)` for [`TableColumn::Text`] (what pyarrow reads as `float64` / `string`).
fn table_schema(columns: &[(String, TableColumn)]) -> parquet::errors::Result<SchemaType> {
    let fields = columns
        .iter()
        .map(|(name, c)| {
            let t = match c {
                TableColumn::Float(_) => SchemaType::primitive_type_builder(name, Physical::DOUBLE)
                    .with_repetition(Repetition::OPTIONAL)
                    .build(),
                TableColumn::Text(_) => {
                    SchemaType::primitive_type_builder(name, Physical::BYTE_ARRAY)
                        .with_repetition(Repetition::REQUIRED)
                        .with_logical_type(Some(LogicalType::String))
                        .with_converted_type(ConvertedType::UTF8)
                        .build()
                }
            };
            t.map(Arc::new)
        })
        .collect::<parquet::errors::Result<Vec<_>>>()?;
    SchemaType::group_type_builder("schema")
        .with_fields(fields)
        .build()
}

/// Write a table of named, typed columns (all the same length) as one Parquet file (one row
/// group, snappy-compressed), e.g. the batch summary. `file` names the output in messages.
pub fn write_table<W: std::io::Write + Send>(
    w: W,
    columns: &[(String, TableColumn)],
    file: &str,
) -> std::result::Result<(), RecordingError> {
    use parquet::file::properties::WriterProperties;
    use parquet::file::writer::SerializedFileWriter;
    let rows = columns.first().map(|(_, c)| c.len()).unwrap_or(0);
    if let Some((name, _)) = columns.iter().find(|(_, c)| c.len() != rows) {
        return Err(perr(
            file,
            format!("column `{name}` has a different length than the first ({rows} rows)"),
        ));
    }
    let run = || -> parquet::errors::Result<()> {
        let schema = Arc::new(table_schema(columns)?);
        let props = Arc::new(
            WriterProperties::builder()
                .set_compression(Compression::SNAPPY)
                .build(),
        );
        let mut writer = SerializedFileWriter::new(w, schema, props)?;
        let mut group = writer.next_row_group()?;
        let mut k = 0;
        while let Some(mut col) = group.next_column()? {
            match &columns[k].1 {
                TableColumn::Float(v) => {
                    let values: Vec<f64> = v.iter().flatten().copied().collect();
                    let defs: Vec<i16> = v.iter().map(|x| i16::from(x.is_some())).collect();
                    col.typed::<DoubleType>()
                        .write_batch(&values, Some(&defs), None)?;
                }
                TableColumn::Text(v) => {
                    let values: Vec<ByteArray> =
                        v.iter().map(|s| ByteArray::from(s.as_str())).collect();
                    col.typed::<ByteArrayType>()
                        .write_batch(&values, None, None)?;
                }
            }
            col.close()?;
            k += 1;
        }
        group.close()?;
        writer.close()?;
        Ok(())
    };
    run().map_err(|e| perr(file, e))
}

/// Read a table written by [`write_table`] (or any Parquet file of top-level `DOUBLE` and UTF-8
/// columns): the columns in file order. Another column type is an error naming it.
pub fn read_table(path: &Path) -> std::result::Result<Vec<(String, TableColumn)>, RecordingError> {
    let file = path.display().to_string();
    let f = std::fs::File::open(path).map_err(|error| RecordingError::Io {
        file: file.clone(),
        error,
    })?;
    guard(&file, || {
        let reader = SerializedFileReader::new(f).map_err(|e| perr(&file, e))?;
        let meta = reader.metadata();
        let leaves = meta.file_metadata().schema_descr();
        let mut out = Vec::new();
        for f in leaves.root_schema().get_fields() {
            let name = f.name().to_string();
            let leaf = (0..leaves.num_columns())
                .find(|&c| leaves.column(c).path().parts() == [name.clone()])
                .filter(|_| f.is_primitive());
            let Some(l) = leaf else {
                return Err(perr(
                    &file,
                    format!("column `{name}`: not a primitive column"),
                ));
            };
            let d = leaves.column(l);
            let (dtype, num) = classify(&d);
            let col = match num {
                Some(Num::F64) => TableColumn::Float(Vec::new()),
                Some(_) => {
                    return Err(perr(
                        &file,
                        format!("column `{name}`: expected DOUBLE, got {dtype}"),
                    ))
                }
                None if dtype == "Utf8" => TableColumn::Text(Vec::new()),
                None => {
                    return Err(perr(
                        &file,
                        format!("column `{name}`: expected UTF-8 text, got {dtype}"),
                    ))
                }
            };
            out.push((name, col, l, d.max_def_level()));
        }
        for g in 0..reader.num_row_groups() {
            let group = reader.get_row_group(g).map_err(|e| perr(&file, e))?;
            let rows = group.metadata().num_rows().max(0) as usize;
            for (name, col, leaf, max_def) in &mut out {
                let ctx = |m: String| perr(&file, format!("row group {g}, column `{name}`: {m}"));
                let cr = group
                    .get_column_reader(*leaf)
                    .map_err(|e| ctx(e.to_string()))?;
                match col {
                    TableColumn::Float(v) => match cr {
                        ColumnReader::DoubleColumnReader(r) => {
                            decode_typed(r, *max_def, rows, |x| Ok(Some(*x)), || None, v)
                        }
                        _ => Err("the column reader does not match the type (DOUBLE)".into()),
                    },
                    TableColumn::Text(v) => match cr {
                        ColumnReader::ByteArrayColumnReader(r) => {
                            decode_typed(r, *max_def, rows, text, String::new, v)
                        }
                        _ => Err("the column reader does not match the type (UTF-8 text)".into()),
                    },
                }
                .map_err(ctx)?;
            }
        }
        Ok(out.into_iter().map(|(n, c, _, _)| (n, c)).collect())
    })
}

/// A `BYTE_ARRAY` value as UTF-8 text.
fn text(b: &ByteArray) -> std::result::Result<String, String> {
    std::str::from_utf8(b.data())
        .map(String::from)
        .map_err(|e| format!("invalid UTF-8 text: {e}"))
}
