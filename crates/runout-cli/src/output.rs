//! Writing results: files are never overwritten silently when they are the user's inputs, and
//! `-` means standard output.

use anyhow::{bail, Context, Result};
use std::io::Write;
use std::path::Path;

/// Refuse to write onto one of the user's input files.
pub fn check_not_input(out: &Path, inputs: &[&Path]) -> Result<()> {
    let canon = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    for i in inputs {
        if out.exists() && canon(out) == canon(i) {
            bail!("refusing to write {}: it is an input file", out.display());
        }
    }
    Ok(())
}

/// Write `text` to `dest` (`-` = stdout).
pub fn write_text(dest: &Path, text: &str) -> Result<()> {
    if dest == Path::new("-") {
        let mut out = std::io::stdout().lock();
        out.write_all(text.as_bytes())?;
        out.flush()?;
        Ok(())
    } else {
        std::fs::write(dest, text).with_context(|| format!("writing {}", dest.display()))
    }
}

/// Open `dest` for buffered writing (`-` = stdout).
pub fn create(dest: &Path) -> Result<Box<dyn Write>> {
    if dest == Path::new("-") {
        Ok(Box::new(std::io::BufWriter::new(std::io::stdout())))
    } else {
        let f =
            std::fs::File::create(dest).with_context(|| format!("creating {}", dest.display()))?;
        Ok(Box::new(std::io::BufWriter::new(f)))
    }
}
