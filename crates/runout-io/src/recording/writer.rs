//! Streaming writers for long outputs: CSV (shortest round-trip decimal text via `ryu`) and a
//! documented little-endian binary layout.
//!
//! ## Binary layout (`runout.binary/1`)
//! | offset | size | content |
//! |---|---|---|
//! | 0 | 8 | magic `RUNOUTB1` |
//! | 8 | 4 | u32 LE: header length H in bytes |
//! | 12 | H | UTF-8 JSON header, padded with spaces so that 12 + H is a multiple of 8: `{"schema":"runout.binary/1","dtype":"f64"\|"f32","columns":[…],…}` plus caller metadata |
//! | 12 + H | … | rows, row-major: for each sample the values of all columns, IEEE-754 little-endian of `dtype` |
//!
//! The number of rows is (file length − 12 − H) / (columns × 4 or 8); a file cut short by a
//! crash loses at most the last partial row.

use std::io::{self, BufWriter, Read, Write};

/// A CSV writer that writes each row as it comes (bounded memory).
pub struct CsvWriter<W: Write> {
    out: BufWriter<W>,
    columns: usize,
    rows: u64,
    digits: ryu::Buffer,
}

impl<W: Write> CsvWriter<W> {
    /// Start a CSV with the given header names (put units in them: `fx_N`).
    pub fn new<S: AsRef<str>>(w: W, header: &[S]) -> io::Result<Self> {
        let mut out = BufWriter::with_capacity(1 << 16, w);
        let names: Vec<&str> = header.iter().map(AsRef::as_ref).collect();
        writeln!(out, "{}", names.join(","))?;
        Ok(Self {
            out,
            columns: names.len(),
            rows: 0,
            digits: ryu::Buffer::new(),
        })
    }

    /// Write one row (must have as many values as the header has names).
    pub fn write_row(&mut self, values: &[f64]) -> io::Result<()> {
        if values.len() != self.columns {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "row of {} values for {} columns",
                    values.len(),
                    self.columns
                ),
            ));
        }
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.out.write_all(b",")?;
            }
            if v.is_finite() {
                self.out
                    .write_all(self.digits.format_finite(*v).as_bytes())?;
            } else {
                self.out.write_all(b"NaN")?;
            }
        }
        self.out.write_all(b"\n")?;
        self.rows += 1;
        Ok(())
    }

    /// Write several rows given as columns of equal length.
    pub fn write_columns(&mut self, columns: &[&[f64]]) -> io::Result<()> {
        let n = columns.first().map_or(0, |c| c.len());
        if columns.iter().any(|c| c.len() != n) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "columns of unequal length",
            ));
        }
        let mut row = vec![0.0; columns.len()];
        for k in 0..n {
            for (r, c) in row.iter_mut().zip(columns) {
                *r = c[k];
            }
            self.write_row(&row)?;
        }
        Ok(())
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Flush and return the inner writer.
    pub fn finish(self) -> io::Result<W> {
        self.out.into_inner().map_err(|e| e.into_error())
    }
}

/// Element type of the binary layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinaryLayout {
    /// 4-byte IEEE-754 little-endian.
    F32,
    /// 8-byte IEEE-754 little-endian.
    F64,
}

impl BinaryLayout {
    fn name(self) -> &'static str {
        match self {
            BinaryLayout::F32 => "f32",
            BinaryLayout::F64 => "f64",
        }
    }

    fn size(self) -> usize {
        match self {
            BinaryLayout::F32 => 4,
            BinaryLayout::F64 => 8,
        }
    }
}

/// Magic bytes of the binary layout.
pub const BINARY_MAGIC: &[u8; 8] = b"RUNOUTB1";

/// A streaming writer of the binary layout documented in this module.
pub struct BinaryWriter<W: Write> {
    out: BufWriter<W>,
    layout: BinaryLayout,
    columns: usize,
    rows: u64,
}

impl<W: Write> BinaryWriter<W> {
    /// Start a file: `columns` names (with units), element type, extra JSON metadata merged
    /// into the header (an object, or `null`).
    pub fn new<S: AsRef<str>>(
        w: W,
        columns: &[S],
        layout: BinaryLayout,
        metadata: serde_json::Value,
    ) -> io::Result<Self> {
        let mut header = serde_json::json!({
            "schema": "runout.binary/1",
            "dtype": layout.name(),
            "endianness": "little",
            "order": "row-major (all columns of sample 0, then sample 1, ...)",
            "columns": columns.iter().map(|c| c.as_ref()).collect::<Vec<_>>(),
        });
        if let (Some(h), serde_json::Value::Object(m)) = (header.as_object_mut(), metadata) {
            for (k, v) in m {
                h.entry(k).or_insert(v);
            }
        }
        let mut text = header.to_string().into_bytes();
        while !(12 + text.len()).is_multiple_of(8) {
            text.push(b' ');
        }
        let mut out = BufWriter::with_capacity(1 << 16, w);
        out.write_all(BINARY_MAGIC)?;
        out.write_all(&(text.len() as u32).to_le_bytes())?;
        out.write_all(&text)?;
        Ok(Self {
            out,
            layout,
            columns: columns.len(),
            rows: 0,
        })
    }

    /// Write one row.
    pub fn write_row(&mut self, values: &[f64]) -> io::Result<()> {
        if values.len() != self.columns {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "row of {} values for {} columns",
                    values.len(),
                    self.columns
                ),
            ));
        }
        for &v in values {
            match self.layout {
                BinaryLayout::F32 => self.out.write_all(&(v as f32).to_le_bytes())?,
                BinaryLayout::F64 => self.out.write_all(&v.to_le_bytes())?,
            }
        }
        self.rows += 1;
        Ok(())
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Flush and return the inner writer.
    pub fn finish(self) -> io::Result<W> {
        self.out.into_inner().map_err(|e| e.into_error())
    }
}

/// Read a whole binary-layout file (small files, tests): (JSON header, rows as columns).
pub fn read_binary(mut r: impl Read) -> io::Result<(serde_json::Value, Vec<Vec<f64>>)> {
    let bad = |m: &str| io::Error::new(io::ErrorKind::InvalidData, m.to_string());
    let mut head = [0u8; 12];
    r.read_exact(&mut head)?;
    if &head[..8] != BINARY_MAGIC {
        return Err(bad("not a runout binary file (magic RUNOUTB1 missing)"));
    }
    let h = u32::from_le_bytes([head[8], head[9], head[10], head[11]]) as usize;
    let mut text = vec![0u8; h];
    r.read_exact(&mut text)?;
    let header: serde_json::Value =
        serde_json::from_slice(&text).map_err(|e| bad(&format!("bad JSON header: {e}")))?;
    let ncols = header["columns"].as_array().map_or(0, |c| c.len());
    let layout = match header["dtype"].as_str() {
        Some("f32") => BinaryLayout::F32,
        Some("f64") => BinaryLayout::F64,
        _ => return Err(bad("dtype must be f32 or f64")),
    };
    let mut data = Vec::new();
    r.read_to_end(&mut data)?;
    let mut cols = vec![Vec::new(); ncols];
    if ncols > 0 {
        for (k, e) in data.chunks_exact(layout.size()).enumerate() {
            let v = match layout {
                BinaryLayout::F32 => f64::from(f32::from_le_bytes([e[0], e[1], e[2], e[3]])),
                BinaryLayout::F64 => {
                    f64::from_le_bytes([e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7]])
                }
            };
            cols[k % ncols].push(v);
        }
        let n = cols[ncols - 1].len();
        for c in &mut cols {
            c.truncate(n);
        }
    }
    Ok((header, cols))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_and_binary_round_trip() {
        let mut w = CsvWriter::new(Vec::new(), &["t_s", "fx_N"]).unwrap();
        w.write_row(&[0.0, 1.25]).unwrap();
        w.write_row(&[1e-5, -0.1]).unwrap();
        assert!(w.write_row(&[1.0]).is_err());
        let text = String::from_utf8(w.finish().unwrap()).unwrap();
        assert_eq!(text, "t_s,fx_N\n0.0,1.25\n0.00001,-0.1\n");

        for layout in [BinaryLayout::F32, BinaryLayout::F64] {
            let mut b = BinaryWriter::new(
                Vec::new(),
                &["t_s", "fx_N"],
                layout,
                serde_json::json!({"sample_rate_hz": 1000.0}),
            )
            .unwrap();
            b.write_row(&[0.0, 1.25]).unwrap();
            b.write_row(&[0.001, -0.1]).unwrap();
            let bytes = b.finish().unwrap();
            let h = u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
            assert_eq!((12 + h) % 8, 0);
            let (header, cols) = read_binary(bytes.as_slice()).unwrap();
            assert_eq!(header["sample_rate_hz"], 1000.0);
            assert_eq!(cols[1][0], 1.25);
            // f32 rounding: relative 6e-8
            assert!((cols[1][1] + 0.1).abs() < 1e-7);
        }
    }
}
