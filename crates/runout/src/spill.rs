//! The two-pass helper: jobs that read a long recording twice (a survey, then the output) keep
//! the converted channels of pass 1 in a temporary binary file and read them back in pass 2
//! instead of parsing the text again.
//!
//! Layout, per block: u64 LE row count, then each channel's values as f64 LE. The file is
//! deleted when the [`Spill`] is dropped (also on errors).
//!
//! Read back either through a [`SpillReader`] (the blocks copied into a chunk's columns) or,
//! when the process allows mapped files (`runout_io::mapped`), as [`MappedSpill`] blocks whose
//! columns are the file's pages themselves (issue 18: no copy).

use runout_io::mapped::MappedFile;
use runout_io::recording::RecordingChunk;
use std::fs::File;
use std::io::{self, BufReader, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// Buffer of the spill's writer and reader: writes and reads of at least this many bytes go
/// straight between the values and the file (one copy instead of two).
const BUFFER_BYTES: usize = 1 << 16;

/// A temporary binary copy of a recording's channels, written block by block.
#[derive(Debug)]
pub struct Spill {
    path: PathBuf,
    writer: Option<BufWriter<File>>,
    channels: usize,
    rows: u64,
}

impl Spill {
    /// A fresh name in the temporary directory: `runout-<tag>-<pid>-<nanos>.tmp`.
    pub fn temp_path(tag: &str) -> PathBuf {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        std::env::temp_dir().join(format!("runout-{tag}-{}-{nanos}.tmp", std::process::id()))
    }

    /// Create the file at `path` for blocks of `channels` columns.
    pub fn create(path: PathBuf, channels: usize) -> io::Result<Self> {
        let f = File::create(&path)?;
        Ok(Self {
            path,
            // small buffers: a block's columns (≈ 0.5 MB each) bypass them, the row counts do not
            writer: Some(BufWriter::with_capacity(BUFFER_BYTES, f)),
            channels,
            rows: 0,
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Append the chunk's channels (its time column is not kept: pass 2 numbers samples from
    /// 0). Panics if called after [`Spill::reader`].
    pub fn write(&mut self, chunk: &RecordingChunk) -> io::Result<()> {
        let w = self
            .writer
            .as_mut()
            .expect("spill written before it is read");
        let n = chunk.len();
        w.write_all(&(n as u64).to_le_bytes())?;
        for c in chunk.values.iter().take(self.channels) {
            if cfg!(target_endian = "little") {
                // the values' memory is the file's layout: one copy into the writer
                w.write_all(bytemuck::cast_slice(c))?;
            } else {
                // straight into the writer's buffer, a few values at a time
                let mut bytes = [0u8; 8 * 64];
                for part in c.chunks(64) {
                    for (b, v) in bytes.chunks_exact_mut(8).zip(part) {
                        b.copy_from_slice(&v.to_le_bytes());
                    }
                    w.write_all(&bytes[..8 * part.len()])?;
                }
            }
        }
        self.rows += n as u64;
        Ok(())
    }

    /// Flush the blocks written (once; later writes panic).
    fn finish_writing(&mut self) -> io::Result<()> {
        match self.writer.take() {
            Some(mut w) => w.flush(),
            None => Ok(()),
        }
    }

    /// Finish writing and map the blocks (`None` when the process does not allow mapped files,
    /// the spill is empty, or on a big-endian machine: then [`Spill::reader`]).
    pub fn mapped(&mut self) -> io::Result<Option<MappedSpill>> {
        self.finish_writing()?;
        if cfg!(target_endian = "big") {
            return Ok(None);
        }
        let map = MappedFile::new(File::open(&self.path)?, 0);
        Ok(map.map(|map| MappedSpill {
            map,
            channels: self.channels,
            pos: 0,
            released: 0,
        }))
    }

    /// Finish writing and read the blocks back from the start.
    pub fn reader(&mut self) -> io::Result<SpillReader> {
        self.finish_writing()?;
        let f = File::open(&self.path)?;
        Ok(SpillReader {
            r: BufReader::with_capacity(BUFFER_BYTES, f),
            channels: self.channels,
            first: 0,
            bytes: Vec::new(),
        })
    }
}

impl Drop for Spill {
    fn drop(&mut self) {
        self.writer = None;
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Reads a [`Spill`] back block by block.
#[derive(Debug)]
pub struct SpillReader {
    r: BufReader<File>,
    channels: usize,
    first: u64,
    bytes: Vec<u8>,
}

impl SpillReader {
    /// The next block into `chunk` (values only, `first_sample` set, no time column); 0 at the end.
    pub fn read_chunk(&mut self, chunk: &mut RecordingChunk) -> io::Result<usize> {
        let mut head = [0u8; 8];
        match self.r.read_exact(&mut head) {
            Ok(()) => {}
            Err(e) if e.kind() == io::ErrorKind::UnexpectedEof => return Ok(0),
            Err(e) => return Err(e),
        }
        let n = u64::from_le_bytes(head) as usize;
        chunk.first_sample = self.first;
        chunk.time_s.clear();
        chunk.values.resize_with(self.channels, Vec::new);
        for c in &mut chunk.values {
            if cfg!(target_endian = "little") {
                // the file's layout is the values' memory: read straight into them (a recycled
                // buffer of the same length is not cleared first: every value is overwritten)
                c.resize(n, 0.0);
                self.r.read_exact(bytemuck::cast_slice_mut(c))?;
            } else {
                self.bytes.resize(8 * n, 0);
                self.r.read_exact(&mut self.bytes)?;
                c.clear();
                c.extend(
                    self.bytes.chunks_exact(8).map(|b| {
                        f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
                    }),
                );
            }
        }
        self.first += n as u64;
        Ok(n)
    }
}

/// A [`Spill`]'s blocks in a mapped file: each block's columns borrowed from the map.
pub struct MappedSpill {
    map: MappedFile,
    channels: usize,
    /// Where the next block starts (bytes).
    pos: usize,
    /// Bytes released from memory: the blocks before `released` have been handed out and used.
    released: usize,
}

impl MappedSpill {
    /// The next block's columns (each the block's rows long), or `None` at the end; the block
    /// before is released from the process's memory (`MappedFile::release`). An error when the
    /// file does not hold the block its row count announces.
    pub fn next_block(&mut self) -> io::Result<Option<Vec<&[f64]>>> {
        self.map.release(self.released, self.pos);
        self.released = self.pos;
        let bytes = self.map.bytes();
        let Some(head) = bytes.get(self.pos..self.pos + 8) else {
            return if self.pos == bytes.len() {
                Ok(None)
            } else {
                Err(truncated(self.pos))
            };
        };
        let n = u64::from_le_bytes(head.try_into().expect("8 bytes"));
        let width = usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(8))
            .ok_or_else(|| truncated(self.pos))?;
        let start = self.pos + 8;
        let end = width
            .checked_mul(self.channels)
            .and_then(|b| b.checked_add(start))
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| truncated(self.pos))?;
        let columns = (0..self.channels)
            .map(|k| {
                let b = &bytes[start + k * width..start + (k + 1) * width];
                bytemuck::try_cast_slice(b).map_err(|e| io::Error::other(e.to_string()))
            })
            .collect::<io::Result<Vec<&[f64]>>>()?;
        self.pos = end;
        Ok(Some(columns))
    }

    /// The end of the reading: an error if the file was shortened meanwhile.
    pub fn finish(self) -> io::Result<()> {
        self.map.shortened().map_or(Ok(()), Err)
    }
}

fn truncated(at: usize) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!("the block at byte {at} is cut short"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_come_back_bit_for_bit_and_the_file_is_removed() {
        let path = Spill::temp_path("test");
        let mut s = Spill::create(path.clone(), 2).unwrap();
        let mut c = RecordingChunk {
            time_s: vec![0.0, 0.1, 0.2],
            values: vec![vec![1.0, f64::NAN, -0.0], vec![1e-300, 2.5, f64::INFINITY]],
            ..Default::default()
        };
        s.write(&c).unwrap();
        c.time_s = vec![0.3];
        c.values = vec![vec![7.0], vec![8.0]];
        s.write(&c).unwrap();
        assert_eq!(s.rows(), 4);
        let mut r = s.reader().unwrap();
        let mut back = RecordingChunk::default();
        assert_eq!(r.read_chunk(&mut back).unwrap(), 3);
        assert_eq!(back.first_sample, 0);
        assert!(back.values[0][1].is_nan() && back.values[0][2].is_sign_negative());
        assert_eq!(back.values[1], vec![1e-300, 2.5, f64::INFINITY]);
        assert_eq!(r.read_chunk(&mut back).unwrap(), 1);
        assert_eq!((back.first_sample, back.values[1][0]), (3, 8.0));
        assert_eq!(r.read_chunk(&mut back).unwrap(), 0);
        assert!(path.exists());
        drop(s);
        assert!(!path.exists());
    }

    /// Mapped, the blocks are the same bits as read (issue 18); a file cut inside a block is an
    /// error, not a shorter block.
    #[test]
    fn mapped_blocks_are_the_blocks_read() {
        // SAFETY: the test's files are not written in place while they are read
        unsafe { runout_io::mapped::allow_mapped_files() };
        let path = Spill::temp_path("test-mapped");
        let mut s = Spill::create(path.clone(), 2).unwrap();
        let mut c = RecordingChunk::default();
        for n in [3usize, 5, 65_536, 1] {
            c.time_s = vec![0.0; n];
            c.values = vec![
                (0..n).map(|i| i as f64 * 0.1 - 7.0).collect(),
                (0..n)
                    .map(|i| if i == 1 { f64::NAN } else { -(i as f64) })
                    .collect(),
            ];
            s.write(&c).unwrap();
        }
        let mut read = Vec::new();
        let mut r = s.reader().unwrap();
        let mut back = RecordingChunk::default();
        while r.read_chunk(&mut back).unwrap() > 0 {
            read.push(
                back.values
                    .iter()
                    .map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                    .collect::<Vec<_>>(),
            );
        }
        assert_eq!(read.len(), 4);
        let mapped_here = s.mapped().unwrap();
        // mapped files are allowed on Linux only
        assert_eq!(mapped_here.is_some(), cfg!(target_os = "linux"));
        let Some(mut m) = mapped_here else { return };
        let mut mapped = Vec::new();
        while let Some(cols) = m.next_block().unwrap() {
            mapped.push(
                cols.iter()
                    .map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                    .collect::<Vec<_>>(),
            );
        }
        assert_eq!(mapped, read);
        m.finish().unwrap();
        // cut inside the last block
        let len = std::fs::metadata(&path).unwrap().len();
        let copy = Spill::temp_path("test-cut");
        std::fs::copy(&path, &copy).unwrap();
        std::fs::OpenOptions::new()
            .write(true)
            .open(&copy)
            .unwrap()
            .set_len(len - 4)
            .unwrap();
        let mut m = MappedSpill {
            map: MappedFile::new(File::open(&copy).unwrap(), 0).unwrap(),
            channels: 2,
            pos: 0,
            released: 0,
        };
        let mut blocks = 0;
        let e = loop {
            match m.next_block() {
                Ok(Some(_)) => blocks += 1,
                Ok(None) => panic!("a cut block read as whole"),
                Err(e) => break e,
            }
        };
        assert_eq!(blocks, 3);
        assert!(e.to_string().contains("cut short"), "{e}");
        std::fs::remove_file(&copy).unwrap();
    }
}
