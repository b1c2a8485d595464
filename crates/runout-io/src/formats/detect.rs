//! Format detection by content (magic bytes), never by extension alone.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

/// A recording file's format, by content.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Kind {
    /// Text: DynoWare export, CSV or TSV.
    Text,
    /// MATLAB 5.0 MAT-file (v5 / v6 / v7, compressed or not).
    Mat5,
    /// MATLAB v4 (unsupported; recognised for the message).
    Mat4,
    /// HDF5, the signature at `offset` (0, 512, 1024, …); MATLAB v7.3 files have it at 512.
    Hdf5 {
        /// Byte offset of the HDF5 signature.
        offset: u64,
    },
    /// NI TDMS (`TDSm` lead-in).
    Tdms,
    /// Apache Parquet (`PAR1`).
    Parquet,
}

impl Kind {
    /// The format's name, for messages.
    ///
    /// ```
    /// use runout_io::formats::Kind;
    /// assert_eq!(Kind::Tdms.name(), "TDMS");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Kind::Text => "text",
            Kind::Mat5 => "MATLAB .mat",
            Kind::Mat4 => "MATLAB v4 .mat",
            Kind::Hdf5 { offset: 0 } => "HDF5",
            Kind::Hdf5 { .. } => "MATLAB v7.3 / HDF5",
            Kind::Tdms => "TDMS",
            Kind::Parquet => "Parquet",
        }
    }
}

/// The HDF5 superblock signature.
pub const HDF5_SIGNATURE: [u8; 8] = [0x89, b'H', b'D', b'F', b'\r', b'\n', 0x1a, b'\n'];

/// Detect from the first bytes of a file (give at least 132 bytes, and the bytes at 512, 1024…
/// for a userblock HDF5 file; shorter input is classified as far as it goes).
pub fn detect(bytes: &[u8]) -> Kind {
    if bytes.starts_with(b"TDSm") {
        return Kind::Tdms;
    }
    if bytes.starts_with(b"PAR1") {
        return Kind::Parquet;
    }
    if bytes.starts_with(&HDF5_SIGNATURE) {
        return Kind::Hdf5 { offset: 0 };
    }
    let mut off = 512usize;
    while off + 8 <= bytes.len() {
        if bytes[off..off + 8] == HDF5_SIGNATURE {
            return Kind::Hdf5 { offset: off as u64 };
        }
        off *= 2;
    }
    if bytes.len() >= 128 && bytes.starts_with(b"MATLAB") {
        let endian = &bytes[126..128];
        if endian == b"IM" || endian == b"MI" {
            return Kind::Mat5;
        }
    }
    if bytes.starts_with(b"MATLAB 5.0 MAT-file") {
        return Kind::Mat5; // truncated header: the MAT reader reports it
    }
    if bytes.len() >= 20 && bytes[..4] == [0, 0, 0, 0] && bytes[12..16] != [0, 0, 0, 0] {
        // MAT v4: type 0 (little-endian double full matrix), rows, cols, imag, name length
        let namelen = u32::from_le_bytes([bytes[16], bytes[17], bytes[18], bytes[19]]);
        if (1..64).contains(&namelen) {
            return Kind::Mat4;
        }
    }
    Kind::Text
}

/// Detect the format of a file: reads its first 132 bytes and probes 512, 1024, 2048, … for an
/// HDF5 signature (up to 1 MiB).
pub fn detect_file(path: &Path) -> std::io::Result<Kind> {
    let mut f = std::fs::File::open(path)?;
    let mut head = vec![0u8; 132];
    let n = read_full(&mut f, &mut head)?;
    head.truncate(n);
    let k = detect(&head);
    // a MATLAB v7.3 file starts with MAT text, then HDF5 at 512
    if !matches!(k, Kind::Text | Kind::Mat5) || n < 132 {
        return Ok(k);
    }
    let len = f.metadata()?.len();
    let mut off = 512u64;
    let mut sig = [0u8; 8];
    while off + 8 <= len && off <= 1 << 20 {
        f.seek(SeekFrom::Start(off))?;
        if read_full(&mut f, &mut sig)? == 8 && sig == HDF5_SIGNATURE {
            return Ok(Kind::Hdf5 { offset: off });
        }
        off *= 2;
    }
    Ok(k)
}

fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}
