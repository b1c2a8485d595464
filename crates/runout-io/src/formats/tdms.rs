//! NI TDMS (LabVIEW, DAQmx), an own reader following NI's published file format ("TDMS File
//! Format Internal Structure"): segments of lead-in (`TDSm`, table of contents, offsets), metadata
//! and raw data.
//!
//! Handled: multiple segments; contiguous and interleaved raw data; big-endian segments
//! (`kTocBigEndian`); incremental metadata (a new object list, objects added to the previous list,
//! a raw-data index "same as the previous segment", segments without metadata that repeat the
//! previous layout); several chunks per segment and a short final chunk; DAQmx raw data (format
//! changing and digital line scalers) with the channel's scaling chain (`NI_Scale[n]`: linear,
//! polynomial, the DAQmx scaler itself); waveform properties `wf_increment` (→ sample rate) and
//! `wf_start_offset` (→ time of the first sample); `unit_string` as the unit; a file cut off while
//! writing (next-segment offset `0xFFFF…`) is read up to its end.
//!
//! Memory: opening reads only lead-ins and metadata and keeps, per channel and segment, where its
//! values are; samples are then read range by range (bounded buffers), never the whole file.

use super::{Catalog, Entry, Opened, Result, Source};
use crate::recording::{Format, RecordingError};
use std::collections::HashMap;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

const TOC_META: u32 = 1 << 1;
const TOC_NEW_OBJ_LIST: u32 = 1 << 2;
const TOC_RAW: u32 = 1 << 3;
const TOC_INTERLEAVED: u32 = 1 << 5;
const TOC_BIG_ENDIAN: u32 = 1 << 6;
const TOC_DAQMX: u32 = 1 << 7;
const LEAD_IN: u64 = 28;
/// Largest metadata block of one segment read into memory.
const MAX_META: u64 = runout_core::limits::MAX_TABLE_BYTES;
/// Largest byte block read at once when delivering samples.
const READ_BLOCK: u64 = 8 << 20;

trait ReadSeek: Read + Seek + Send {}
impl<T: Read + Seek + Send> ReadSeek for T {}

/// Element types of raw data.
#[derive(Debug, Clone, Copy, PartialEq)]
enum DType {
    I8,
    I16,
    I32,
    I64,
    U8,
    U16,
    U32,
    U64,
    F32,
    F64,
    Bool,
    /// Types that are not numbers (strings, timestamps, complex): size in bytes, or 0 if variable.
    Other(u32, u64),
}

impl DType {
    fn from_code(code: u32) -> Self {
        match code {
            1 => DType::I8,
            2 => DType::I16,
            3 => DType::I32,
            4 => DType::I64,
            5 => DType::U8,
            6 => DType::U16,
            7 => DType::U32,
            8 => DType::U64,
            9 | 0x19 => DType::F32,
            10 | 0x1A => DType::F64,
            0x21 => DType::Bool,
            0x44 => DType::Other(code, 16),
            11 | 0x1B => DType::Other(code, 16),
            0x08000c => DType::Other(code, 8),
            0x10000d => DType::Other(code, 16),
            c => DType::Other(c, 0),
        }
    }

    fn from_daqmx(code: u32) -> Self {
        match code {
            0 => DType::U8,
            1 => DType::I8,
            2 => DType::U16,
            3 => DType::I16,
            4 => DType::U32,
            5 => DType::I32,
            6 => DType::U64,
            7 => DType::I64,
            8 => DType::F32,
            9 => DType::F64,
            c => DType::Other(c, 0),
        }
    }

    fn size(self) -> u64 {
        match self {
            DType::I8 | DType::U8 | DType::Bool => 1,
            DType::I16 | DType::U16 => 2,
            DType::I32 | DType::U32 | DType::F32 => 4,
            DType::I64 | DType::U64 | DType::F64 => 8,
            DType::Other(_, s) => s,
        }
    }

    fn numeric(self) -> bool {
        !matches!(self, DType::Other(..))
    }

    fn name(self) -> String {
        match self {
            DType::I8 => "i8".into(),
            DType::I16 => "i16".into(),
            DType::I32 => "i32".into(),
            DType::I64 => "i64".into(),
            DType::U8 => "u8".into(),
            DType::U16 => "u16".into(),
            DType::U32 => "u32".into(),
            DType::U64 => "u64".into(),
            DType::F32 => "f32".into(),
            DType::F64 => "f64".into(),
            DType::Bool => "bool".into(),
            DType::Other(0x20, _) => "string".into(),
            DType::Other(0x44, _) => "timestamp".into(),
            DType::Other(c, _) => format!("type 0x{c:x}"),
        }
    }

    fn decode(self, b: &[u8], big: bool) -> f64 {
        macro_rules! v {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                (if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }) as f64
            }};
        }
        match self {
            DType::I8 => b[0] as i8 as f64,
            DType::U8 | DType::Bool => b[0] as f64,
            DType::I16 => v!(i16, 2),
            DType::U16 => v!(u16, 2),
            DType::I32 => v!(i32, 4),
            DType::U32 => v!(u32, 4),
            DType::I64 => v!(i64, 8),
            DType::U64 => v!(u64, 8),
            DType::F32 => v!(f32, 4),
            DType::F64 => v!(f64, 8),
            DType::Other(..) => f64::NAN,
        }
    }
}

/// A property value.
#[derive(Debug, Clone, PartialEq)]
enum Prop {
    Num(f64),
    Text(String),
}

impl Prop {
    fn text(&self) -> String {
        match self {
            Prop::Num(v) => v.to_string(),
            Prop::Text(s) => s.clone(),
        }
    }
}

/// A DAQmx scaler of a channel.
#[derive(Debug, Clone, PartialEq)]
struct Scaler {
    dtype: DType,
    buffer: u32,
    byte_offset: u64,
    bit: Option<u32>,
}

/// A channel's raw-data index in a segment.
#[derive(Debug, Clone, PartialEq)]
struct RawIndex {
    dtype: DType,
    count: u64,
    /// DAQmx: the scalers and the raw data widths (bytes per buffer).
    daqmx: Option<(Vec<Scaler>, Vec<u64>)>,
}

/// Where a run of a channel's values lies: `chunks` repetitions of `count` values, value `j` of
/// chunk `c` at `pos + c·chunk_bytes + j·stride`.
#[derive(Debug, Clone)]
struct Piece {
    first: u64,
    pos: u64,
    count: u64,
    chunks: u64,
    chunk_bytes: u64,
    stride: u64,
    dtype: DType,
    big: bool,
    bit: Option<u32>,
}

impl Piece {
    fn len(&self) -> u64 {
        self.count * self.chunks
    }
}

/// One object (root, group or channel) over the file.
#[derive(Debug, Default)]
struct Obj {
    path: String,
    parts: Vec<String>,
    props: Vec<(String, Prop)>,
    last_index: Option<RawIndex>,
    pieces: Vec<Piece>,
    len: u64,
    dtype: Option<DType>,
    daqmx: bool,
    /// The raw-data index in the current segment (`None`: no data in it).
    cur: Option<RawIndex>,
}

impl Obj {
    fn prop(&self, key: &str) -> Option<&Prop> {
        self.props
            .iter()
            .rev()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v)
    }
    fn num(&self, key: &str) -> Option<f64> {
        match self.prop(key) {
            Some(Prop::Num(v)) => Some(*v),
            Some(Prop::Text(s)) => s.trim().parse().ok(),
            None => None,
        }
    }
}

/// Split a TDMS object path `/'Group'/'Ch''x'` into its components.
fn split_path(path: &str) -> Option<Vec<String>> {
    let mut parts = Vec::new();
    if path == "/" {
        return Some(parts);
    }
    let b: Vec<char> = path.chars().collect();
    let mut i = 0;
    while i < b.len() {
        if b[i] != '/' {
            return None;
        }
        i += 1;
        if i >= b.len() || b[i] != '\'' {
            return None;
        }
        i += 1;
        let mut s = String::new();
        loop {
            if i >= b.len() {
                return None;
            }
            if b[i] == '\'' {
                if i + 1 < b.len() && b[i + 1] == '\'' {
                    s.push('\'');
                    i += 2;
                    continue;
                }
                i += 1;
                break;
            }
            s.push(b[i]);
            i += 1;
        }
        parts.push(s);
    }
    Some(parts)
}

/// A scale of the `NI_Scale[n]` chain.
#[derive(Debug, Clone)]
enum Scale {
    Raw,
    Linear {
        slope: f64,
        intercept: f64,
        input: i64,
    },
    Polynomial {
        coefficients: Vec<f64>,
        input: i64,
    },
}

#[derive(Debug, Clone)]
struct Scaling {
    scales: Vec<Scale>,
}

impl Scaling {
    fn from_props(o: &Obj) -> std::result::Result<Option<Self>, String> {
        let Some(n) = o.num("NI_Number_Of_Scales") else {
            return Ok(None);
        };
        if let Some(Prop::Text(s)) = o.prop("NI_Scaling_Status") {
            if s.eq_ignore_ascii_case("scaled") {
                return Ok(None);
            }
        }
        let n = n as i64;
        if !(1..=64).contains(&n) {
            return Ok(None);
        }
        let mut scales = Vec::new();
        for i in 0..n {
            let p = |k: &str| o.num(&format!("NI_Scale[{i}]_{k}"));
            let input = |k: &str| p(&format!("{k}_Input_Source")).map_or(-1, |v| v as i64);
            let ty = o.prop(&format!("NI_Scale[{i}]_Scale_Type")).map(Prop::text);
            scales.push(match ty.as_deref() {
                None => Scale::Raw,
                Some("Linear") => Scale::Linear {
                    slope: p("Linear_Slope").unwrap_or(1.0),
                    intercept: p("Linear_Y_Intercept").unwrap_or(0.0),
                    input: input("Linear"),
                },
                Some("Polynomial") => {
                    let m = p("Polynomial_Coefficients_Size").unwrap_or(0.0) as i64;
                    let coefficients = (0..m.clamp(0, 64))
                        .map(|k| p(&format!("Polynomial_Coefficients[{k}]")).unwrap_or(0.0))
                        .collect();
                    Scale::Polynomial {
                        coefficients,
                        input: input("Polynomial"),
                    }
                }
                Some(other) => {
                    return Err(format!(
                        "scale NI_Scale[{i}] of type `{other}` is not supported (linear and polynomial are)"
                    ))
                }
            });
        }
        Ok(Some(Scaling { scales }))
    }

    fn apply(&self, raw: f64) -> f64 {
        self.eval(self.scales.len() as i64 - 1, raw, 0)
    }

    fn eval(&self, i: i64, raw: f64, depth: usize) -> f64 {
        if i < 0 || i as usize >= self.scales.len() || depth > 64 {
            return raw;
        }
        match &self.scales[i as usize] {
            Scale::Raw => raw,
            Scale::Linear {
                slope,
                intercept,
                input,
            } => self.eval(*input, raw, depth + 1) * slope + intercept,
            Scale::Polynomial {
                coefficients,
                input,
            } => {
                let x = self.eval(*input, raw, depth + 1);
                coefficients.iter().rev().fold(0.0, |acc, c| acc * x + c)
            }
        }
    }
}

struct Meta<'a> {
    b: &'a [u8],
    pos: usize,
    big: bool,
    base: u64,
    file: &'a str,
}

impl Meta<'_> {
    fn err(&self, what: &str) -> RecordingError {
        RecordingError::Format {
            file: self.file.into(),
            message: format!("TDMS metadata byte {}: {what}", self.base + self.pos as u64),
        }
    }
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8]> {
        if self.b.len() - self.pos < n {
            return Err(self.err(&format!(
                "truncated {what}: expected {n} bytes, {} left in the metadata",
                self.b.len() - self.pos
            )));
        }
        let s = &self.b[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> Result<u32> {
        let big = self.big;
        let b = self.take(4, what)?;
        let a = [b[0], b[1], b[2], b[3]];
        Ok(if big {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        })
    }
    fn u64(&mut self, what: &str) -> Result<u64> {
        let big = self.big;
        let b = self.take(8, what)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(if big {
            u64::from_be_bytes(a)
        } else {
            u64::from_le_bytes(a)
        })
    }
    fn string(&mut self, what: &str) -> Result<String> {
        let n = self.u32(what)? as usize;
        let b = self.take(n, what)?;
        Ok(String::from_utf8_lossy(b).into_owned())
    }
    fn prop_value(&mut self, code: u32) -> Result<Prop> {
        Ok(match code {
            0x20 => Prop::Text(self.string("string property")?),
            0x44 => {
                let big = self.big;
                let b = self.take(16, "timestamp property")?;
                let (frac, secs) = if big {
                    (
                        u64::from_be_bytes(b[8..16].try_into().unwrap_or([0; 8])),
                        i64::from_be_bytes(b[0..8].try_into().unwrap_or([0; 8])),
                    )
                } else {
                    (
                        u64::from_le_bytes(b[0..8].try_into().unwrap_or([0; 8])),
                        i64::from_le_bytes(b[8..16].try_into().unwrap_or([0; 8])),
                    )
                };
                Prop::Num(secs as f64 + frac as f64 / 18_446_744_073_709_551_616.0)
            }
            c => {
                let t = DType::from_code(c);
                let n = t.size();
                if n == 0 {
                    return Err(self.err(&format!("property of unknown data type 0x{c:x}")));
                }
                let big = self.big;
                let b = self.take(n as usize, "property value")?;
                if t.numeric() {
                    Prop::Num(t.decode(b, big))
                } else {
                    Prop::Text(format!("<{}>", t.name()))
                }
            }
        })
    }
}

/// The parsed index of a TDMS file.
struct Index {
    objects: Vec<Obj>,
    warnings: Vec<String>,
    version: u32,
}

fn parse_index<R: Read + Seek>(src: &mut R, file_len: u64, file: &str) -> Result<Index> {
    let io = |error: std::io::Error| RecordingError::Io {
        file: file.into(),
        error,
    };
    let ferr = |offset: u64, message: String| RecordingError::Format {
        file: file.into(),
        message: format!("TDMS byte {offset}: {message}"),
    };
    let mut objects: Vec<Obj> = Vec::new();
    let mut by_path: HashMap<String, usize> = HashMap::new();
    let mut list: Vec<usize> = Vec::new();
    let mut warnings = Vec::new();
    let mut version = 0;
    let mut seg_start = 0u64;
    let mut seg_no = 0u64;
    while seg_start < file_len {
        if file_len - seg_start < LEAD_IN {
            return Err(ferr(
                seg_start,
                format!(
                    "truncated lead-in of segment {seg_no}: expected 28 bytes, {} left",
                    file_len - seg_start
                ),
            ));
        }
        src.seek(SeekFrom::Start(seg_start)).map_err(io)?;
        let mut lead = [0u8; 28];
        src.read_exact(&mut lead).map_err(io)?;
        if &lead[0..4] != b"TDSm" {
            return Err(ferr(
                seg_start,
                format!(
                    "segment {seg_no}: expected the tag `TDSm`, found {:?}",
                    &lead[0..4]
                ),
            ));
        }
        let toc = u32::from_le_bytes([lead[4], lead[5], lead[6], lead[7]]);
        let big = toc & TOC_BIG_ENDIAN != 0;
        let rd32 = |b: &[u8]| {
            let a = [b[0], b[1], b[2], b[3]];
            if big {
                u32::from_be_bytes(a)
            } else {
                u32::from_le_bytes(a)
            }
        };
        let rd64 = |b: &[u8]| {
            let mut a = [0u8; 8];
            a.copy_from_slice(&b[..8]);
            if big {
                u64::from_be_bytes(a)
            } else {
                u64::from_le_bytes(a)
            }
        };
        version = rd32(&lead[8..12]);
        let next = rd64(&lead[12..20]);
        let raw_off = rd64(&lead[20..28]);
        let body = seg_start + LEAD_IN;
        let avail = file_len - body;
        let (seg_len, cut) = if next == u64::MAX || next > avail {
            if next != u64::MAX {
                warnings.push(format!(
                    "{file}: segment {seg_no} at byte {seg_start} announces {next} bytes, {avail} are present (file cut off?); reading what is there"
                ));
            }
            (avail, true)
        } else {
            (next, false)
        };
        if raw_off > seg_len {
            return Err(ferr(
                seg_start + 20,
                format!("segment {seg_no}: raw data offset {raw_off} beyond the segment's {seg_len} bytes"),
            ));
        }
        if toc & TOC_META != 0 {
            if raw_off > MAX_META {
                return Err(ferr(
                    seg_start + 20,
                    format!(
                        "segment {seg_no}: {raw_off} bytes of metadata exceed the limit {MAX_META}"
                    ),
                ));
            }
            let mut mb = vec![0u8; raw_off as usize];
            src.read_exact(&mut mb).map_err(io)?;
            let mut m = Meta {
                b: &mb,
                pos: 0,
                big,
                base: body,
                file,
            };
            let n_obj = m.u32("object count")?;
            if n_obj as usize > mb.len() / 8 {
                return Err(m.err(&format!(
                    "{n_obj} objects cannot fit in {} bytes of metadata",
                    mb.len()
                )));
            }
            if toc & TOC_NEW_OBJ_LIST != 0 {
                list.clear();
            }
            for _ in 0..n_obj {
                let path = m.string("object path")?;
                let id = match by_path.get(&path) {
                    Some(&i) => i,
                    None => {
                        let parts = split_path(&path).ok_or_else(|| {
                            m.err(&format!("object path `{path}`: expected `/` or `/'group'` or `/'group'/'channel'`"))
                        })?;
                        objects.push(Obj {
                            path: path.clone(),
                            parts,
                            ..Obj::default()
                        });
                        by_path.insert(path.clone(), objects.len() - 1);
                        objects.len() - 1
                    }
                };
                let ilen = m.u32("raw data index length")?;
                let index = match ilen {
                    0xFFFF_FFFF => None,
                    0 => Some(objects[id].last_index.clone().ok_or_else(|| {
                        m.err(&format!("object `{path}`: raw data index \"same as previous\" but no previous segment had one"))
                    })?),
                    0x1269 | 0x126A | 0x6912_0000 | 0x6913_0000 => {
                        let code = m.u32("DAQmx data type")?;
                        let dim = m.u32("array dimension")?;
                        let count = m.u64("number of values")?;
                        if dim != 1 {
                            return Err(m.err(&format!("object `{path}`: array dimension {dim}, expected 1")));
                        }
                        let ns = m.u32("scaler count")?;
                        if ns as usize > mb.len() / 17 {
                            return Err(m.err(&format!("{ns} scalers cannot fit in the metadata")));
                        }
                        let mut scalers = Vec::new();
                        for _ in 0..ns {
                            let dt = m.u32("scaler data type")?;
                            let buffer = m.u32("raw buffer index")?;
                            let off = m.u32("raw byte offset")?;
                            let (byte_offset, bit) = if ilen == 0x6913_0000 || ilen == 0x126A {
                                m.take(1, "sample format bitmap")?;
                                ((off / 8) as u64, Some(off % 8))
                            } else {
                                m.u32("sample format bitmap")?;
                                (off as u64, None)
                            };
                            m.u32("scale id")?;
                            scalers.push(Scaler {
                                dtype: DType::from_daqmx(dt),
                                buffer,
                                byte_offset,
                                bit,
                            });
                        }
                        let nw = m.u32("raw data width count")?;
                        if nw as usize > mb.len() / 4 {
                            return Err(m.err(&format!("{nw} raw data widths cannot fit in the metadata")));
                        }
                        let mut widths = Vec::new();
                        for _ in 0..nw {
                            widths.push(m.u32("raw data width")? as u64);
                        }
                        let dtype = if code == 0xFFFF_FFFF {
                            scalers.first().map_or(DType::Other(code, 0), |s| s.dtype)
                        } else {
                            DType::from_code(code)
                        };
                        Some(RawIndex {
                            dtype,
                            count,
                            daqmx: Some((scalers, widths)),
                        })
                    }
                    _ => {
                        let code = m.u32("data type")?;
                        let dim = m.u32("array dimension")?;
                        let count = m.u64("number of values")?;
                        if dim != 1 {
                            return Err(m.err(&format!("object `{path}`: array dimension {dim}, expected 1")));
                        }
                        if code == 0x20 {
                            m.u64("total size of strings")?;
                        }
                        Some(RawIndex {
                            dtype: DType::from_code(code),
                            count,
                            daqmx: None,
                        })
                    }
                };
                if let Some(ix) = &index {
                    objects[id].last_index = Some(ix.clone());
                }
                // the object's data in this segment: None = none
                objects[id].daqmx |= index.as_ref().is_some_and(|i| i.daqmx.is_some());
                let pos = list.iter().position(|&o| o == id);
                match pos {
                    Some(_) => {}
                    None => list.push(id),
                }
                // mark whether it has data in this segment via a per-segment table below
                seg_index_set(&mut objects[id], index);
                let np = m.u32("property count")?;
                if np as usize > mb.len() / 9 {
                    return Err(m.err(&format!("{np} properties cannot fit in the metadata")));
                }
                for _ in 0..np {
                    let name = m.string("property name")?;
                    let code = m.u32("property data type")?;
                    let v = m.prop_value(code)?;
                    objects[id].props.push((name, v));
                }
            }
        }
        // raw data of this segment
        if toc & TOC_RAW != 0 && seg_len > raw_off {
            let data_start = body + raw_off;
            let data_len = seg_len - raw_off;
            let with_data: Vec<usize> = list
                .iter()
                .copied()
                .filter(|&o| objects[o].cur.as_ref().is_some_and(|i| i.count > 0))
                .collect();
            layout(
                &mut objects,
                &with_data,
                data_start,
                data_len,
                toc & TOC_INTERLEAVED != 0,
                big,
                toc & TOC_DAQMX != 0,
            )
            .map_err(|m| ferr(data_start, format!("segment {seg_no}: {m}")))?;
        }
        if cut {
            break;
        }
        seg_start = body + seg_len;
        seg_no += 1;
    }
    Ok(Index {
        objects,
        warnings,
        version,
    })
}

fn seg_index_set(o: &mut Obj, index: Option<RawIndex>) {
    o.cur = index;
}

/// Lay out the values of one segment's raw data (all its chunks).
fn layout(
    objects: &mut [Obj],
    with_data: &[usize],
    start: u64,
    len: u64,
    interleaved: bool,
    big: bool,
    daqmx_flag: bool,
) -> std::result::Result<(), String> {
    if with_data.is_empty() {
        return Ok(());
    }
    let daqmx = with_data
        .iter()
        .any(|&o| objects[o].cur.as_ref().is_some_and(|i| i.daqmx.is_some()));
    if daqmx {
        if !with_data
            .iter()
            .all(|&o| objects[o].cur.as_ref().is_some_and(|i| i.daqmx.is_some()))
        {
            return Err("a mix of DAQmx and plain channels in one segment is not supported".into());
        }
        let _ = daqmx_flag;
        // buffers: (values, width)
        let mut dims: Vec<(u64, u64)> = Vec::new();
        for &o in with_data {
            let ix = objects[o].cur.clone().ok_or("no index")?;
            let (scalers, widths) = ix.daqmx.clone().ok_or("no DAQmx index")?;
            if dims.is_empty() {
                dims = widths.iter().map(|&w| (0, w)).collect();
            }
            for s in &scalers {
                let d = dims.get_mut(s.buffer as usize).ok_or_else(|| {
                    format!(
                        "scaler of `{}` names raw buffer {} of {}",
                        objects[o].path,
                        s.buffer,
                        widths.len()
                    )
                })?;
                d.0 = d.0.max(ix.count);
            }
        }
        let chunk: u64 = dims
            .iter()
            .try_fold(0u64, |a, &(n, w)| {
                n.checked_mul(w).and_then(|b| a.checked_add(b))
            })
            .ok_or("DAQmx chunk size overflows")?;
        if chunk == 0 {
            return Ok(());
        }
        let chunks = len / chunk;
        let rest = len % chunk;
        for &o in with_data {
            let ix = objects[o].cur.clone().ok_or("no index")?;
            let (scalers, _) = ix.daqmx.clone().ok_or("no DAQmx index")?;
            let s = scalers
                .first()
                .ok_or_else(|| format!("`{}`: DAQmx data without a scaler", objects[o].path))?;
            let b = s.buffer as usize;
            let (n, w) = dims[b];
            if s.byte_offset + s.dtype.size() > w || !s.dtype.numeric() {
                return Err(format!(
                    "`{}`: DAQmx scaler at byte {} of {} does not fit the raw data width {w}",
                    objects[o].path,
                    s.byte_offset,
                    s.dtype.name()
                ));
            }
            let buf_off: u64 = dims[..b].iter().map(|&(n, w)| n * w).sum();
            let mut add = |pos: u64, count: u64, chunks: u64| {
                let obj = &mut objects[o];
                let p = Piece {
                    first: obj.len,
                    pos,
                    count,
                    chunks,
                    chunk_bytes: chunk,
                    stride: w,
                    dtype: s.dtype,
                    big,
                    bit: s.bit,
                };
                obj.len += p.len();
                obj.dtype = Some(s.dtype);
                if p.len() > 0 {
                    obj.pieces.push(p);
                }
            };
            add(start + buf_off + s.byte_offset, n, chunks);
            if rest > 0 {
                // short final chunk: buffers in order, as many values as fit
                let before = buf_off;
                let fit = if rest > before {
                    ((rest - before) / w).min(n)
                } else {
                    0
                };
                add(start + chunks * chunk + buf_off + s.byte_offset, fit, 1);
            }
        }
        return Ok(());
    }
    let mut sizes = Vec::new();
    for &o in with_data {
        let ix = objects[o].cur.as_ref().ok_or("no index")?;
        let sz = ix.dtype.size();
        if sz == 0 {
            return Err(format!(
                "`{}` holds {} data; only fixed-size values can be skipped or read",
                objects[o].path,
                ix.dtype.name()
            ));
        }
        sizes.push((ix.count, sz));
    }
    if interleaved {
        let n = sizes[0].0;
        if sizes.iter().any(|&(c, _)| c != n) {
            return Err("interleaved channels with different value counts".into());
        }
        let row: u64 = sizes.iter().map(|&(_, s)| s).sum();
        let chunk = n.checked_mul(row).ok_or("chunk size overflows")?;
        let total_rows = len / row;
        let chunks = total_rows / n;
        let rest_rows = total_rows % n;
        let mut off = 0;
        for (k, &o) in with_data.iter().enumerate() {
            let dtype = objects[o].cur.as_ref().map(|i| i.dtype).ok_or("no index")?;
            for (pos, count, ch) in [
                (start + off, n, chunks),
                (start + chunks * chunk + off, rest_rows, 1),
            ] {
                let obj = &mut objects[o];
                let p = Piece {
                    first: obj.len,
                    pos,
                    count,
                    chunks: ch,
                    chunk_bytes: chunk,
                    stride: row,
                    dtype,
                    big,
                    bit: None,
                };
                obj.len += p.len();
                obj.dtype = Some(dtype);
                if p.len() > 0 {
                    obj.pieces.push(p);
                }
            }
            off += sizes[k].1;
        }
    } else {
        let chunk: u64 = sizes
            .iter()
            .try_fold(0u64, |a, &(n, s)| {
                n.checked_mul(s).and_then(|b| a.checked_add(b))
            })
            .ok_or("chunk size overflows")?;
        if chunk == 0 {
            return Ok(());
        }
        let chunks = len / chunk;
        let mut rest = len % chunk;
        let mut off = 0;
        for (k, &o) in with_data.iter().enumerate() {
            let (n, s) = sizes[k];
            let dtype = objects[o].cur.as_ref().map(|i| i.dtype).ok_or("no index")?;
            let fit = (rest / s).min(n);
            rest -= fit * s;
            for (pos, count, ch) in [
                (start + off, n, chunks),
                (start + chunks * chunk + off, fit, 1),
            ] {
                let obj = &mut objects[o];
                let p = Piece {
                    first: obj.len,
                    pos,
                    count,
                    chunks: ch,
                    chunk_bytes: chunk,
                    stride: s,
                    dtype,
                    big,
                    bit: None,
                };
                obj.len += p.len();
                obj.dtype = Some(dtype);
                if p.len() > 0 {
                    obj.pieces.push(p);
                }
            }
            off += n * s;
        }
    }
    Ok(())
}

struct TdmsSource {
    src: Box<dyn ReadSeek>,
    file: String,
    channels: Vec<(Vec<Piece>, Option<Scaling>)>,
    buf: Vec<u8>,
}

impl Source for TdmsSource {
    fn read(&mut self, entry: usize, start: u64, n: usize, out: &mut Vec<f64>) -> Result<()> {
        let (pieces, scaling) = &self.channels[entry];
        let mut s = start;
        let end = start + n as u64;
        let mut k = pieces.partition_point(|p| p.first + p.len() <= s);
        while s < end && k < pieces.len() {
            let p = &pieces[k];
            let i = s - p.first;
            let (c, j) = (i / p.count, i % p.count);
            let m = (p.count - j)
                .min(end - s)
                .min((READ_BLOCK / p.stride).max(1));
            let size = p.dtype.size();
            let pos = p.pos + c * p.chunk_bytes + j * p.stride;
            let bytes = (m - 1) * p.stride + size;
            self.buf.resize(bytes as usize, 0);
            self.src
                .seek(SeekFrom::Start(pos))
                .and_then(|_| self.src.read_exact(&mut self.buf))
                .map_err(|e| RecordingError::Format {
                    file: self.file.clone(),
                    message: format!(
                        "TDMS byte {pos}: cannot read {bytes} bytes of channel data ({e})"
                    ),
                })?;
            for v in 0..m {
                let o = (v * p.stride) as usize;
                let mut x = p.dtype.decode(&self.buf[o..o + size as usize], p.big);
                if let Some(bit) = p.bit {
                    x = ((x as u64 >> bit) & 1) as f64;
                }
                out.push(match scaling {
                    Some(sc) => sc.apply(x),
                    None => x,
                });
            }
            s += m;
            if s >= p.first + p.len() {
                k += 1;
            }
        }
        Ok(())
    }
}

fn build(mut src: Box<dyn ReadSeek>, file_len: u64, file: &str) -> Result<Opened> {
    let index = parse_index(&mut src, file_len, file)?;
    let mut entries = Vec::new();
    let mut channels = Vec::new();
    let mut metadata = vec![("TDMS version".to_string(), index.version.to_string())];
    let root = index.objects.iter().find(|o| o.parts.is_empty());
    if let Some(r) = root {
        metadata.extend(r.props.iter().map(|(k, v)| (k.clone(), v.text())));
    }
    for w in &index.warnings {
        metadata.push(("warning".into(), w.clone()));
    }
    for o in &index.objects {
        if o.parts.len() != 2 {
            continue;
        }
        let group = index
            .objects
            .iter()
            .find(|g| g.parts.len() == 1 && g.parts[0] == o.parts[0]);
        let mut scaling = Scaling::from_props(o);
        if matches!(scaling, Ok(None)) {
            if let Some(g) = group {
                scaling = Scaling::from_props(g);
            }
        }
        let name = format!("{}/{}", o.parts[0], o.parts[1]);
        let mut e = Entry::numeric(name, Some(o.parts[0].clone()), o.parts[1].clone(), o.len);
        let dtype = o.dtype.or(o.last_index.as_ref().map(|i| i.dtype));
        e.dtype = dtype.map_or("no data".into(), |d| d.name());
        if o.daqmx {
            e.dtype = format!("DAQmx {}", e.dtype);
        }
        e.readable = dtype.is_some_and(|d| d.numeric());
        e.unit = o
            .prop("unit_string")
            .map(Prop::text)
            .filter(|s| !s.is_empty());
        if let Some(inc) = o.num("wf_increment").filter(|v| v.is_finite() && *v > 0.0) {
            e.sample_rate_hz = Some(1.0 / inc);
        }
        e.start_time_s = o.num("wf_start_offset").filter(|v| v.is_finite());
        let sc = match scaling {
            Ok(s) => s,
            Err(m) => {
                e.readable = false;
                e.note = Some(m);
                None
            }
        };
        if sc.is_some() {
            e.dtype += " (scaled)";
        }
        if e.len == 1 && e.readable {
            let mut v = Vec::new();
            let mut tmp = TdmsSource {
                src: Box::new(std::io::Cursor::new(Vec::new())),
                file: file.into(),
                channels: vec![],
                buf: vec![],
            };
            std::mem::swap(&mut tmp.src, &mut src);
            tmp.channels.push((o.pieces.clone(), sc.clone()));
            tmp.read(0, 0, 1, &mut v)?;
            std::mem::swap(&mut tmp.src, &mut src);
            e.scalar = v.first().copied();
        }
        entries.push(e);
        channels.push((o.pieces.clone(), sc));
    }
    Ok(Opened {
        catalog: Catalog {
            format: Format::Tdms {
                version: index.version,
            },
            entries,
            metadata,
        },
        source: Box::new(TdmsSource {
            src,
            file: file.into(),
            channels,
            buf: Vec::new(),
        }),
    })
}

/// Open a TDMS file (streamed: only the index is read at open).
pub fn open_path(path: &Path, file: &str) -> Result<Opened> {
    let f = std::fs::File::open(path).map_err(|error| RecordingError::Io {
        file: file.into(),
        error,
    })?;
    let len = f
        .metadata()
        .map_err(|error| RecordingError::Io {
            file: file.into(),
            error,
        })?
        .len();
    build(Box::new(std::io::BufReader::new(f)), len, file)
}

/// Open a TDMS file held in memory.
pub fn open_bytes(bytes: Vec<u8>, file: &str) -> Result<Opened> {
    let len = bytes.len() as u64;
    build(Box::new(std::io::Cursor::new(bytes)), len, file)
}
