//! Reading a whole text file (table, config, toolpath, NC program) with bounded memory: files
//! larger than [`MAX_TABLE_BYTES`] and lines longer than [`MAX_LINE_BYTES`] are refused before
//! they are parsed, and messages quote at most 80 characters of the offending text.

use runout_core::limits::{MAX_LINE_BYTES, MAX_TABLE_BYTES};
use std::io::Read;
use std::path::Path;

/// Why a text file could not be read; `Display` gives `file[:line]: message` (the shared
/// [`crate::LocatedError`]; line 0 = the whole file).
pub type TextFileError = crate::LocatedError;

/// At most 80 characters of `text` (with `…` when cut), for messages; control characters
/// (line breaks, tabs, NUL …) are escaped (`\n`) so that a message stays on one line.
pub fn quote(text: &str) -> String {
    let cut = match text.char_indices().nth(80) {
        Some((i, _)) => &text[..i],
        None => text,
    };
    let mut out: String = cut
        .chars()
        .flat_map(|c| {
            let escaped = c.is_control().then(|| c.escape_default());
            escaped
                .into_iter()
                .flatten()
                .chain((!c.is_control()).then_some(c))
        })
        .collect();
    if cut.len() < text.len() {
        out.push('…');
    }
    out
}

/// Read `path` as UTF-8 text, refusing files over [`MAX_TABLE_BYTES`] (checked on the size
/// before reading, and again while reading for files without a size such as pipes) and lines
/// over [`MAX_LINE_BYTES`].
pub fn read_text(path: &Path) -> Result<String, TextFileError> {
    let file = path.display().to_string();
    let err = |line: Option<usize>, message: String| {
        TextFileError::new(file.clone(), line.unwrap_or(0), message)
    };
    let too_big = |size: u64| {
        err(
            None,
            format!(
                "{size} bytes: larger than the {MAX_TABLE_BYTES} bytes a table, config or toolpath \
                 may have; split the file"
            ),
        )
    };
    let f = std::fs::File::open(path).map_err(|e| {
        err(
            None,
            format!("cannot read: {}", crate::report::io_problem(&e)),
        )
    })?;
    let meta = f.metadata().map_err(|e| {
        err(
            None,
            format!("cannot read: {}", crate::report::io_problem(&e)),
        )
    })?;
    if meta.is_dir() {
        return Err(err(None, "is a folder: expected a file".into()));
    }
    if meta.len() > MAX_TABLE_BYTES {
        return Err(too_big(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    f.take(MAX_TABLE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| {
            err(
                None,
                format!("cannot read: {}", crate::report::io_problem(&e)),
            )
        })?;
    text_from_bytes(&file, bytes)
}

/// The same checks as [`read_text`] on bytes already in memory (a config or table passed by a
/// library caller); `file` names them in messages.
pub fn text_from_bytes(file: &str, bytes: Vec<u8>) -> Result<String, TextFileError> {
    let err =
        |line: Option<usize>, message: String| TextFileError::new(file, line.unwrap_or(0), message);
    if bytes.len() as u64 > MAX_TABLE_BYTES {
        return Err(err(
            None,
            format!(
                "{} bytes: larger than the {MAX_TABLE_BYTES} bytes a table, config or toolpath \
                 may have; split the file",
                bytes.len()
            ),
        ));
    }
    check_lines(file, &bytes)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let raw = e.as_bytes();
        let line = raw[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        err(
            Some(line),
            "not UTF-8 text (a binary file, or another encoding: save it as UTF-8)".into(),
        )
    })
}

/// Refuse lines longer than [`MAX_LINE_BYTES`].
fn check_lines(file: &str, bytes: &[u8]) -> Result<(), TextFileError> {
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if line.len() > MAX_LINE_BYTES {
            let head = String::from_utf8_lossy(&line[..line.len().min(320)]);
            return Err(TextFileError {
                file: file.into(),
                line: n + 1,
                column: None,
                message: format!(
                    "line of {} bytes: longer than {MAX_LINE_BYTES}, starting `{}`",
                    line.len(),
                    quote(&head)
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quotes_are_short_and_on_one_line() {
        assert_eq!(quote("a\nb\t\0c"), "a\\nb\\t\\u{0}c");
        assert_eq!(quote(&"é".repeat(100)), format!("{}…", "é".repeat(80)));
        assert_eq!(quote("plain µm"), "plain µm");
    }

    #[test]
    fn long_lines_and_big_files_are_refused_with_a_short_quote() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("one_line.csv");
        std::fs::write(&p, "a".repeat(MAX_LINE_BYTES + 10)).unwrap();
        let e = read_text(&p).unwrap_err();
        assert_eq!(e.line(), Some(1));
        assert!(
            e.message.contains(&format!("longer than {MAX_LINE_BYTES}")),
            "{e}"
        );
        assert!(e.to_string().len() < 300, "{e}");
        let big = dir.path().join("big.csv");
        std::fs::File::create(&big)
            .unwrap()
            .set_len(MAX_TABLE_BYTES + 1)
            .unwrap();
        let e = read_text(&big).unwrap_err();
        assert!(e.message.contains("split the file"), "{e}");
        let ok = dir.path().join("ok.csv");
        std::fs::write(&ok, "a,b\n1,2\n").unwrap();
        assert_eq!(read_text(&ok).unwrap(), "a,b\n1,2\n");
    }
}
