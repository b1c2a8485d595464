//! Writing results: never onto one of the user's inputs (compared by file identity, not by
//! name), never half-written (each file goes to a temporary file in the same folder; all of them
//! are renamed onto their destinations by [`commit_all`] when the command has succeeded, and
//! removed by [`discard_all`] when it failed), and `-` means standard output.

use anyhow::{bail, Context, Result};
use std::fs::File;
use std::io::{self, BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Finished temporary files waiting for the command's outcome: (temporary, destination).
static PENDING: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());

fn pending() -> std::sync::MutexGuard<'static, Vec<(PathBuf, PathBuf)>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Write errors noticed where they could not be returned (a writer dropped unfinished).
static LATE_ERRORS: Mutex<Vec<String>> = Mutex::new(Vec::new());

/// The command succeeded: rename every finished temporary file onto its destination (or, if a
/// dropped writer failed, remove them all and report it).
pub fn commit_all() -> Result<()> {
    let late = std::mem::take(&mut *LATE_ERRORS.lock().unwrap_or_else(|e| e.into_inner()));
    if let Some(e) = late.into_iter().next() {
        discard_all();
        bail!("{e}");
    }
    let files = std::mem::take(&mut *pending());
    let mut first_err = None;
    for (tmp, dest) in files {
        if let Err(e) = std::fs::rename(&tmp, &dest) {
            let _ = std::fs::remove_file(&tmp);
            first_err.get_or_insert(anyhow::anyhow!("writing {}: {e}", dest.display()));
        }
    }
    first_err.map_or(Ok(()), Err)
}

/// The command failed: remove every temporary file, leaving the destinations as they were.
pub fn discard_all() {
    for (tmp, _) in std::mem::take(&mut *pending()) {
        let _ = std::fs::remove_file(&tmp);
    }
}

/// Identity of an existing file: device and inode on Unix, the canonical path elsewhere (or
/// where the metadata cannot be read).
#[derive(Debug, PartialEq, Eq)]
enum FileId {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

fn file_id(p: &Path) -> Option<FileId> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let Ok(m) = std::fs::metadata(p) {
            return Some(FileId::Inode(m.dev(), m.ino()));
        }
    }
    std::fs::canonicalize(p).ok().map(FileId::Path)
}

/// True if `a` and `b` name the same existing file (hard links, symbolic links, `./x` vs `x`).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (file_id(a), file_id(b)) {
        (Some(x), Some(y)) => x == y,
        _ => false,
    }
}

/// Refuse to write onto one of the user's input files: `out` is compared with every input by
/// file identity (device + inode on Unix), so a hard or symbolic link to an input is refused
/// too. `-` (stdout) is always allowed.
pub fn check_not_input(out: &Path, inputs: &[&Path]) -> Result<()> {
    if out == Path::new("-") {
        return Ok(());
    }
    for i in inputs {
        if same_file(out, i) {
            bail!(
                "refusing to write {}: it is the input file {} (the same file, by device and \
                 inode); choose another output path",
                out.display(),
                i.display()
            );
        }
    }
    Ok(())
}

/// True if the two files have the same bytes (or are the same file). Streams both; sizes are
/// compared first.
pub fn identical_files(a: &Path, b: &Path) -> io::Result<bool> {
    if same_file(a, b) {
        return Ok(true);
    }
    let (ma, mb) = (std::fs::metadata(a)?, std::fs::metadata(b)?);
    if !(ma.is_file() && mb.is_file()) || ma.len() != mb.len() {
        return Ok(false);
    }
    let (mut fa, mut fb) = (File::open(a)?, File::open(b)?);
    let (mut ba, mut bb) = (vec![0u8; 1 << 16], vec![0u8; 1 << 16]);
    loop {
        let n = read_full(&mut fa, &mut ba)?;
        let m = read_full(&mut fb, &mut bb)?;
        if n != m || ba[..n] != bb[..m] {
            return Ok(false);
        }
        if n == 0 {
            return Ok(true);
        }
    }
}

fn read_full(f: &mut File, buf: &mut [u8]) -> io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..])? {
            0 => break,
            k => n += k,
        }
    }
    Ok(n)
}

/// Refuse two inputs that are the same file or have identical contents (e.g. one recording
/// given twice as two feeds); `what` names them in the message.
pub fn check_distinct(inputs: &[PathBuf], what: &str) -> Result<()> {
    for (i, a) in inputs.iter().enumerate() {
        for (j, b) in inputs.iter().enumerate().skip(i + 1) {
            if identical_files(a, b).unwrap_or(false) {
                bail!(
                    "{what} {} ({}) and {} ({}) are identical: each must be its own \
                     measurement (a repeated file would make the fit meaningless)",
                    i + 1,
                    a.display(),
                    j + 1,
                    b.display()
                );
            }
        }
    }
    Ok(())
}

/// A file being written: bytes go to a temporary file next to `dest`. Finished (or dropped
/// without a write error), it waits for [`commit_all`]; after a write error it is removed and
/// `dest` is left as it was.
pub struct AtomicFile {
    inner: Option<BufWriter<File>>,
    tmp: PathBuf,
    dest: PathBuf,
    failed: bool,
}

impl AtomicFile {
    fn create(dest: &Path) -> Result<Self> {
        let dir = match dest.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let name = dest
            .file_name()
            .with_context(|| format!("{}: not a file name", dest.display()))?;
        let tmp = dir.join(format!(
            ".{}.{}.tmp",
            name.to_string_lossy(),
            std::process::id()
        ));
        let f = File::create(&tmp).with_context(|| format!("creating {}", dest.display()))?;
        Ok(AtomicFile {
            inner: Some(BufWriter::new(f)),
            tmp,
            dest: dest.to_path_buf(),
            failed: false,
        })
    }

    /// Flush; the file is renamed onto its destination by [`commit_all`].
    pub fn finish(mut self) -> Result<()> {
        self.commit()
            .with_context(|| format!("writing {}", self.dest.display()))
    }

    fn commit(&mut self) -> io::Result<()> {
        let Some(mut w) = self.inner.take() else {
            return Ok(());
        };
        let done = w.flush();
        drop(w);
        match &done {
            Ok(()) => pending().push((self.tmp.clone(), self.dest.clone())),
            Err(_) => {
                let _ = std::fs::remove_file(&self.tmp);
            }
        }
        done
    }

    fn track<T>(&mut self, r: io::Result<T>) -> io::Result<T> {
        if r.is_err() {
            self.failed = true;
        }
        r
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let r = match self.inner.as_mut() {
            Some(w) => w.write(buf),
            None => Err(io::Error::other("file already finished")),
        };
        self.track(r)
    }
    fn flush(&mut self) -> io::Result<()> {
        let r = match self.inner.as_mut() {
            Some(w) => w.flush(),
            None => Ok(()),
        };
        self.track(r)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if self.inner.is_none() {
            return;
        }
        if self.failed || std::thread::panicking() {
            self.inner.take();
            let _ = std::fs::remove_file(&self.tmp);
        } else if let Err(e) = self.commit() {
            LATE_ERRORS
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(format!("writing {}: {e}", self.dest.display()));
        }
    }
}

/// True where `dest` exists and is not a regular file (`/dev/null`, a FIFO): written in place,
/// never replaced by a rename.
fn is_special(dest: &Path) -> bool {
    std::fs::metadata(dest).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// Write `text` to `dest` (`-` = stdout) through a temporary file renamed at the end.
pub fn write_text(dest: &Path, text: &str) -> Result<()> {
    if dest == Path::new("-") {
        let mut out = io::stdout().lock();
        out.write_all(text.as_bytes())?;
        out.flush()?;
        Ok(())
    } else if is_special(dest) {
        std::fs::write(dest, text).with_context(|| format!("writing {}", dest.display()))
    } else {
        let mut f = AtomicFile::create(dest)?;
        f.write_all(text.as_bytes())
            .with_context(|| format!("writing {}", dest.display()))?;
        f.finish()
    }
}

/// Open `dest` for buffered writing (`-` = stdout). A file is written to a temporary file in the
/// same folder and renamed onto `dest` when the writer is dropped after the last successful
/// write; after a write error nothing is renamed.
pub fn create(dest: &Path) -> Result<Box<dyn Write>> {
    if dest == Path::new("-") {
        Ok(Box::new(BufWriter::new(io::stdout())))
    } else if is_special(dest) {
        let f = File::options()
            .write(true)
            .open(dest)
            .with_context(|| format!("opening {}", dest.display()))?;
        Ok(Box::new(BufWriter::new(f)))
    } else {
        Ok(Box::new(AtomicFile::create(dest)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hard_links_are_the_same_file_and_outputs_are_renamed_into_place() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("in.nc");
        std::fs::write(&a, "G1 X1\n").unwrap();
        let link = dir.path().join("link.nc");
        std::fs::hard_link(&a, &link).unwrap();
        assert!(same_file(&a, &link));
        assert!(check_not_input(&link, &[&a]).is_err());
        let other = dir.path().join("out.nc");
        assert!(check_not_input(&other, &[&a]).is_ok());
        write_text(&other, "G1 X2\n").unwrap();
        commit_all().unwrap();
        assert_eq!(std::fs::read_to_string(&other).unwrap(), "G1 X2\n");
        let copy = dir.path().join("copy.nc");
        std::fs::write(&copy, "G1 X1\n").unwrap();
        assert!(identical_files(&a, &copy).unwrap());
        assert!(!identical_files(&a, &other).unwrap());
        {
            let mut w = create(&dir.path().join("w.csv")).unwrap();
            writeln!(w, "a,b").unwrap();
        }
        // not there before the command's outcome is known
        assert!(!dir.path().join("w.csv").exists());
        commit_all().unwrap();
        assert_eq!(
            std::fs::read_to_string(dir.path().join("w.csv")).unwrap(),
            "a,b\n"
        );
        // no temporary files left behind
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
    }
}
