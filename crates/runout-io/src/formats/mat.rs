//! MATLAB 5.0 MAT-files (v5/v6/v7: uncompressed and zlib-compressed variables), as written by
//! MATLAB, Octave and `scipy.io.savemat`. v7.3 files are HDF5 and are read by [`super::hdf5`].
//!
//! Read: numeric arrays of every class (double, single, int8 … uint64; the stored element type may
//! be narrower than the class, as MATLAB writes it), row or column vectors, 2-D matrices (each
//! column `M(:,j)` of a tall matrix becomes a channel), structs (fields `rec.Fx`, nested
//! `rec.a.b`), struct arrays (element k's fields as `s(k).Fx`, 1-based), cell arrays (cell k as
//! `c{k}`; cells holding numeric vectors are channels), logical arrays. Char, sparse, complex and
//! object arrays (also as cells or fields) are listed with a note and are not channels: naming
//! one is an error that says what it is. Both byte orders (`IM` / `MI`).
//!
//! Memory: the whole file is read and every numeric array decoded into f64 (a compressed variable
//! must be inflated whole). The decoded size is bounded by
//! [`runout_core::limits::MAX_RESULT_BYTES`]; sizes in the file are checked against the bytes
//! actually present before anything is allocated.

use super::{Catalog, Entry, MemorySource, Opened, Result};
use crate::recording::{Format, RecordingError};
use std::io::Read;
use std::path::Path;

const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MI_UTF8: u32 = 16;

const MX_CELL: u32 = 1;
const MX_STRUCT: u32 = 2;
const MX_OBJECT: u32 = 3;
const MX_CHAR: u32 = 4;
const MX_SPARSE: u32 = 5;

/// Largest decoded size of the numeric data of one file (bytes of f64).
const MAX_DECODED: u64 = runout_core::limits::MAX_RESULT_BYTES as u64;
/// Deepest struct / cell nesting followed.
const MAX_DEPTH: usize = 16;
/// Most elements of a struct or cell array that are read (each has at least an 8-byte tag in
/// the file, so the file size bounds it anyway; this keeps listings readable).
const MAX_ELEMENTS: u64 = 10_000;

/// Open a MAT v5 file (read whole, see the module documentation).
pub fn open_path(path: &Path, file: &str) -> Result<Opened> {
    let len = std::fs::metadata(path)
        .map_err(|error| RecordingError::Io {
            file: file.into(),
            error,
        })?
        .len();
    if len > MAX_DECODED {
        return Err(err(
            file,
            0,
            format!("the file has {len} bytes; MAT v5 files are read whole and the limit is {MAX_DECODED} bytes (README \"Limits and safety\"); save as v7.3 (HDF5, streamed)"),
        ));
    }
    let bytes = std::fs::read(path).map_err(|error| RecordingError::Io {
        file: file.into(),
        error,
    })?;
    open_bytes(&bytes, file)
}

fn err(file: &str, offset: u64, message: String) -> RecordingError {
    RecordingError::Format {
        file: file.into(),
        message: format!("MAT-file byte {offset}: {message}"),
    }
}

struct Parser<'f> {
    file: &'f str,
    big: bool,
    decoded: u64,
    entries: Vec<Entry>,
    arrays: Vec<Vec<f64>>,
}

/// A cursor over a byte buffer; `base` is the file offset of `buf[0]` (for messages; inside a
/// compressed variable it is the offset of the compressed element).
struct Cur<'a> {
    buf: &'a [u8],
    pos: usize,
    base: u64,
    inflated: bool,
}

impl Parser<'_> {
    fn u32(&self, b: &[u8]) -> u32 {
        let a = [b[0], b[1], b[2], b[3]];
        if self.big {
            u32::from_be_bytes(a)
        } else {
            u32::from_le_bytes(a)
        }
    }

    fn at(&self, c: &Cur, message: String) -> RecordingError {
        let where_ = if c.inflated {
            format!(
                "compressed variable at byte {}, inflated byte {}",
                c.base, c.pos
            )
        } else {
            format!("byte {}", c.base + c.pos as u64)
        };
        RecordingError::Format {
            file: self.file.into(),
            message: format!("MAT-file {where_}: {message}"),
        }
    }

    /// Read a data-element tag: (type, size, data slice); advances past the padded data.
    fn element<'a>(&self, c: &mut Cur<'a>) -> Result<(u32, &'a [u8])> {
        if c.buf.len() - c.pos < 8 {
            return Err(self.at(
                c,
                format!(
                    "truncated: expected an 8-byte data-element tag, {} bytes left",
                    c.buf.len() - c.pos
                ),
            ));
        }
        let w0 = self.u32(&c.buf[c.pos..]);
        let small = if self.big { w0 & 0xFFFF } else { w0 >> 16 };
        if small != 0 {
            // small data element: 2-byte size, 2-byte type, 4 bytes of data
            let (ty, n) = if self.big {
                (w0 >> 16, small)
            } else {
                (w0 & 0xFFFF, small)
            };
            if n > 4 {
                return Err(self.at(c, format!("small data element of {n} bytes (at most 4)")));
            }
            let d = &c.buf[c.pos + 4..c.pos + 4 + n as usize];
            c.pos += 8;
            return Ok((ty, d));
        }
        let ty = w0;
        let n = self.u32(&c.buf[c.pos + 4..]) as usize;
        let start = c.pos + 8;
        if c.buf.len() - start < n {
            return Err(self.at(
                c,
                format!(
                    "truncated: data element of type {ty} announces {n} bytes, {} left",
                    c.buf.len() - start
                ),
            ));
        }
        let d = &c.buf[start..start + n];
        let padded = if ty == MI_COMPRESSED {
            n
        } else {
            n.div_ceil(8) * 8
        };
        c.pos = (start + padded).min(c.buf.len());
        Ok((ty, d))
    }

    fn top_level(&mut self, bytes: &[u8]) -> Result<()> {
        let mut c = Cur {
            buf: bytes,
            pos: 128,
            base: 0,
            inflated: false,
        };
        while c.pos < c.buf.len() {
            let at = c.pos as u64;
            let (ty, data) = self.element(&mut c)?;
            match ty {
                MI_MATRIX => self.matrix(data, at + 8, false, None, 0)?,
                MI_COMPRESSED => {
                    let inflated = self.inflate(data, at)?;
                    let mut ic = Cur {
                        buf: &inflated,
                        pos: 0,
                        base: at,
                        inflated: true,
                    };
                    while ic.pos < ic.buf.len() {
                        let (ity, idata) = self.element(&mut ic)?;
                        if ity == MI_MATRIX {
                            self.matrix(idata, at, true, None, 0)?;
                        } else {
                            return Err(self.at(
                                &ic,
                                format!("expected a matrix (type 14) in a compressed element, found type {ity}"),
                            ));
                        }
                    }
                }
                other => {
                    return Err(err(
                        self.file,
                        at,
                        format!(
                            "expected a variable (data type 14 or 15), found data type {other}"
                        ),
                    ))
                }
            }
        }
        Ok(())
    }

    fn inflate(&mut self, data: &[u8], at: u64) -> Result<Vec<u8>> {
        let budget = MAX_DECODED.saturating_sub(self.decoded);
        let mut out = Vec::new();
        let mut z = flate2::read::ZlibDecoder::new(data).take(budget + 1);
        z.read_to_end(&mut out).map_err(|e| {
            err(
                self.file,
                at,
                format!(
                    "compressed variable ({} bytes) does not inflate: {e}",
                    data.len()
                ),
            )
        })?;
        if out.len() as u64 > budget {
            return Err(err(
                self.file,
                at,
                format!("compressed variable inflates to more than the limit of {MAX_DECODED} bytes (README \"Limits and safety\")"),
            ));
        }
        self.decoded += out.len() as u64 / 2;
        Ok(out)
    }

    /// A miMATRIX element's content; `prefix` = struct path for fields.
    fn matrix(
        &mut self,
        data: &[u8],
        base: u64,
        inflated: bool,
        field: Option<(&str, &str)>,
        depth: usize,
    ) -> Result<()> {
        if data.is_empty() {
            if let Some((group, name)) = field {
                self.push_note(group, name, 0, "empty", "empty matrix");
            }
            return Ok(());
        }
        let mut c = Cur {
            buf: data,
            pos: 0,
            base,
            inflated,
        };
        let (ty, flags) = self.element(&mut c)?;
        if ty != MI_UINT32 || flags.len() != 8 {
            return Err(self.at(
                &c,
                format!(
                    "array flags: expected 8 bytes of uint32 (type 6), found type {ty}, {} bytes",
                    flags.len()
                ),
            ));
        }
        let f0 = self.u32(flags);
        let class = f0 & 0xFF;
        let complex = f0 & 0x0800 != 0;
        let logical = f0 & 0x0200 != 0;
        let (ty, dims_b) = self.element(&mut c)?;
        if ty != MI_INT32 || dims_b.len() < 8 || dims_b.len() % 4 != 0 {
            return Err(self.at(
                &c,
                format!(
                    "dimensions: expected ≥ 2 int32 (type 5), found type {ty}, {} bytes",
                    dims_b.len()
                ),
            ));
        }
        let dims: Vec<u64> = dims_b
            .chunks_exact(4)
            .map(|b| self.u32(b) as i32)
            .map(|d| d.max(0) as u64)
            .collect();
        let count = dims.iter().try_fold(1u64, |a, &d| a.checked_mul(d));
        let (ty, name_b) = self.element(&mut c)?;
        if ty != MI_INT8 && ty != MI_UINT8 && ty != MI_UTF8 {
            return Err(self.at(
                &c,
                format!("array name: expected int8 text (type 1), found type {ty}"),
            ));
        }
        let own = String::from_utf8_lossy(name_b)
            .trim_end_matches('\0')
            .to_string();
        let (group, name) = match field {
            Some((g, n)) => (Some(g.to_string()).filter(|g| !g.is_empty()), n.to_string()),
            None => (None, own),
        };
        let full = match &group {
            Some(g) => format!("{g}.{name}"),
            None => name.clone(),
        };
        let gname = group.clone().unwrap_or_default();
        let dims_text = dims
            .iter()
            .map(|d| d.to_string())
            .collect::<Vec<_>>()
            .join("×");
        match class {
            MX_STRUCT => {
                let (ty, fl) = self.element(&mut c)?;
                if ty != MI_INT32 || fl.len() != 4 {
                    return Err(
                        self.at(&c, "struct: expected the field-name length (int32)".into())
                    );
                }
                let flen = self.u32(fl) as usize;
                let (_, names_b) = self.element(&mut c)?;
                if flen == 0 || names_b.len() % flen != 0 {
                    return Err(self.at(
                        &c,
                        format!("struct `{full}`: {} bytes of field names is not a multiple of the name length {flen}", names_b.len()),
                    ));
                }
                let fields: Vec<String> = names_b
                    .chunks_exact(flen)
                    .map(|b| {
                        let end = b.iter().position(|&x| x == 0).unwrap_or(b.len());
                        String::from_utf8_lossy(&b[..end]).into_owned()
                    })
                    .collect();
                let count = count.unwrap_or(0);
                if count > MAX_ELEMENTS || depth >= MAX_DEPTH {
                    self.push_note(
                        &gname,
                        &full,
                        count,
                        "struct",
                        &format!("{dims_text} struct array: more than {MAX_ELEMENTS} elements or nested deeper than {MAX_DEPTH}, not read"),
                    );
                    return Ok(());
                }
                // a struct array: element k (1-based, column-major) as `s(k)`, its fields `s(k).Fx`
                for k in 0..count {
                    let owner = if count == 1 {
                        full.clone()
                    } else {
                        format!("{full}({})", k + 1)
                    };
                    for fname in &fields {
                        let at = c.pos;
                        let (ty, fd) = self.element(&mut c)?;
                        if ty != MI_MATRIX {
                            return Err(self.at(
                                &c,
                                format!("struct `{owner}` field `{fname}` at {at}: expected a matrix (type 14), found type {ty}"),
                            ));
                        }
                        let fb = if inflated { base } else { base + at as u64 + 8 };
                        self.matrix(fd, fb, inflated, Some((&owner, fname)), depth + 1)?;
                    }
                }
                Ok(())
            }
            MX_CELL => {
                let count = count.unwrap_or(0);
                if count > MAX_ELEMENTS || depth >= MAX_DEPTH {
                    self.push_note(
                        &gname,
                        &full,
                        count,
                        "cell array",
                        &format!("{dims_text} cell array: more than {MAX_ELEMENTS} cells or nested deeper than {MAX_DEPTH}, not read"),
                    );
                    return Ok(());
                }
                // cell k (1-based, column-major) as `c{k}`: numeric vectors are channels, other
                // element types are listed with a note (and refused by name)
                for k in 0..count {
                    let at = c.pos;
                    let (ty, fd) = self.element(&mut c)?;
                    if ty != MI_MATRIX {
                        return Err(self.at(
                            &c,
                            format!("cell array `{full}` cell {} at {at}: expected a matrix (type 14), found type {ty}", k + 1),
                        ));
                    }
                    let fb = if inflated { base } else { base + at as u64 + 8 };
                    let cname = format!("{name}{{{}}}", k + 1);
                    self.matrix(fd, fb, inflated, Some((&gname, &cname)), depth + 1)?;
                }
                Ok(())
            }
            MX_OBJECT | MX_CHAR | MX_SPARSE => {
                let what = match class {
                    MX_OBJECT => "object",
                    MX_CHAR => "char array",
                    _ => "sparse matrix",
                };
                self.push_note(
                    &gname,
                    &full,
                    count.unwrap_or(0),
                    what,
                    &format!("{dims_text} {what}, not a channel"),
                );
                Ok(())
            }
            6..=15 => {
                let Some(count) = count else {
                    return Err(self.at(&c, format!("`{full}`: dimensions {dims_text} overflow")));
                };
                let (ty, real) = self.element(&mut c)?;
                let size = match ty {
                    MI_INT8 | MI_UINT8 => 1,
                    MI_INT16 | MI_UINT16 => 2,
                    MI_INT32 | MI_UINT32 | MI_SINGLE => 4,
                    MI_DOUBLE | MI_INT64 | MI_UINT64 => 8,
                    other => {
                        return Err(
                            self.at(&c, format!("`{full}`: unknown numeric data type {other}"))
                        )
                    }
                };
                if real.len() as u64 != count * size {
                    return Err(self.at(
                        &c,
                        format!(
                            "`{full}` ({dims_text}): expected {} bytes of data, found {}",
                            count * size,
                            real.len()
                        ),
                    ));
                }
                if complex {
                    self.push_note(
                        &gname,
                        &full,
                        count,
                        "complex",
                        &format!("{dims_text} complex, not a channel"),
                    );
                    return Ok(());
                }
                self.decoded += count * 8;
                if self.decoded > MAX_DECODED {
                    return Err(self.at(&c, format!("decoded data exceed the limit of {MAX_DECODED} bytes (README \"Limits and safety\")")));
                }
                let values = self.decode(ty, real);
                let dtype = match class {
                    6 => "f64",
                    7 => "f32",
                    8 => "i8",
                    9 if logical => "logical",
                    9 => "u8",
                    10 => "i16",
                    11 => "u16",
                    12 => "i32",
                    13 => "u32",
                    14 => "i64",
                    _ => "u64",
                };
                let (rows, cols) = (
                    dims[0],
                    dims[1..]
                        .iter()
                        .try_fold(1u64, |a, &d| a.checked_mul(d))
                        .unwrap_or(u64::MAX),
                );
                let group = group.clone();
                if rows <= 1 || cols <= 1 {
                    let mut e = Entry::numeric(full.clone(), group, name.clone(), count);
                    e.dtype = dtype.into();
                    if count == 1 {
                        e.scalar = values.first().copied();
                    }
                    e.readable = count > 0;
                    if dims.len() > 2 {
                        e.note = Some(dims_text.clone());
                    }
                    self.entries.push(e);
                    self.arrays.push(values);
                } else {
                    // a matrix: each column M(:,j) a channel of `rows` samples
                    for j in 0..cols {
                        let n = format!("{name}(:,{})", j + 1);
                        let f = match &group {
                            Some(g) => format!("{g}.{n}"),
                            None => n.clone(),
                        };
                        let mut e = Entry::numeric(f, group.clone(), n, rows);
                        e.dtype = dtype.into();
                        e.note = Some(format!(
                            "column {} of the {dims_text} matrix `{full}`",
                            j + 1
                        ));
                        self.entries.push(e);
                        let s = (j * rows) as usize;
                        self.arrays.push(values[s..s + rows as usize].to_vec());
                    }
                }
                Ok(())
            }
            other => {
                self.push_note(
                    &gname,
                    &full,
                    count.unwrap_or(0),
                    "unknown",
                    &format!("unknown array class {other}"),
                );
                Ok(())
            }
        }
    }

    fn push_note(&mut self, group: &str, full: &str, len: u64, dtype: &str, note: &str) {
        let short = full.rsplit('.').next().unwrap_or(full).to_string();
        let mut e = Entry::numeric(
            full.into(),
            (!group.is_empty()).then(|| group.to_string()),
            short,
            len,
        );
        e.dtype = dtype.into();
        e.readable = false;
        e.note = Some(note.into());
        self.entries.push(e);
        self.arrays.push(Vec::new());
    }

    fn decode(&self, ty: u32, b: &[u8]) -> Vec<f64> {
        macro_rules! conv {
            ($t:ty, $n:expr) => {
                b.chunks_exact($n)
                    .map(|c| {
                        let a: [u8; $n] = c.try_into().unwrap_or([0; $n]);
                        (if self.big {
                            <$t>::from_be_bytes(a)
                        } else {
                            <$t>::from_le_bytes(a)
                        }) as f64
                    })
                    .collect()
            };
        }
        match ty {
            MI_INT8 => b.iter().map(|&x| x as i8 as f64).collect(),
            MI_UINT8 => b.iter().map(|&x| x as f64).collect(),
            MI_INT16 => conv!(i16, 2),
            MI_UINT16 => conv!(u16, 2),
            MI_INT32 => conv!(i32, 4),
            MI_UINT32 => conv!(u32, 4),
            MI_SINGLE => conv!(f32, 4),
            MI_INT64 => conv!(i64, 8),
            MI_UINT64 => conv!(u64, 8),
            _ => conv!(f64, 8),
        }
    }
}

/// Parse a MAT v5 file held in memory.
pub fn open_bytes(bytes: &[u8], file: &str) -> Result<Opened> {
    if bytes.len() < 128 {
        return Err(err(
            file,
            bytes.len() as u64,
            format!(
                "truncated: a MAT v5 file starts with a 128-byte header, the file has {} bytes",
                bytes.len()
            ),
        ));
    }
    let big = match &bytes[126..128] {
        b"IM" => false,
        b"MI" => true,
        other => {
            return Err(err(
                file,
                126,
                format!("expected the endian indicator `IM` or `MI`, found {other:?}"),
            ))
        }
    };
    let text = String::from_utf8_lossy(&bytes[..116])
        .trim_end_matches(['\0', ' '])
        .to_string();
    let mut p = Parser {
        file,
        big,
        decoded: 0,
        entries: Vec::new(),
        arrays: Vec::new(),
    };
    p.top_level(bytes)?;
    let version = if text.contains("MATLAB 5.0") {
        "5"
    } else {
        "5?"
    };
    Ok(Opened {
        catalog: Catalog {
            format: Format::Mat {
                version: version.into(),
            },
            entries: p.entries,
            metadata: vec![("header".into(), text)],
        },
        source: Box::new(MemorySource { arrays: p.arrays }),
    })
}
