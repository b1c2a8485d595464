//! Lexer for ISO (RS-274 / DIN 66025) NC blocks: words with f64 values and byte spans into the
//! original text, comments `( … )` and `; …`, block delete `/`, `%` lines. Nothing is
//! normalised, so untouched text can be written back byte for byte (crates.md §3: the `gcode`
//! crate stores f32 and mangles comments, hence this own lexer).

use super::NcError;
use std::ops::Range;

/// A word: address letter and number.
#[derive(Debug, Clone, PartialEq)]
pub struct Word {
    /// Address letter, upper case.
    pub letter: char,
    /// Value.
    pub value: f64,
    /// Byte span of the number text in the whole program.
    pub number: Range<usize>,
    /// Byte span of the whole word (letter to last digit).
    pub span: Range<usize>,
    /// Digits after the decimal point as written (0 if none).
    pub decimals: usize,
}

/// One line (block) of the program.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// 1-based line number.
    pub number: usize,
    /// Byte span of the line content (without the line ending).
    pub content: Range<usize>,
    /// Words in order.
    pub words: Vec<Word>,
}

/// Split `text` into lines (keeping `\n`, `\r\n` and lone `\r` endings out of the content) and
/// lex each one.
pub fn lex(text: &str) -> Result<Vec<Line>, NcError> {
    let bytes = text.as_bytes();
    let mut lines = Vec::new();
    let mut start = 0;
    let mut number = 1;
    while start < bytes.len() {
        let mut end = start;
        while end < bytes.len() && bytes[end] != b'\n' && bytes[end] != b'\r' {
            end += 1;
        }
        lines.push(lex_line(text, number, start..end)?);
        let mut next = end;
        if next < bytes.len() && bytes[next] == b'\r' {
            next += 1;
        }
        if next < bytes.len() && bytes[next] == b'\n' {
            next += 1;
        }
        start = next;
        number += 1;
    }
    Ok(lines)
}

fn lex_line(text: &str, number: usize, content: Range<usize>) -> Result<Line, NcError> {
    let b = text.as_bytes();
    let col = |i: usize| text[content.start..i].chars().count() + 1;
    let err = |i: usize, msg: String| NcError {
        line: number,
        column: col(i),
        message: msg,
    };
    let mut words = Vec::new();
    let mut i = content.start;
    let end = content.end;
    while i < end {
        let c = b[i];
        match c {
            b' ' | b'\t' => i += 1,
            b'%' if words.is_empty() => {
                // program start/end marker; anything after it on the line is a comment
                break;
            }
            b'/' if words.is_empty() => i += 1, // block delete
            b'(' => {
                let close = text[i..end]
                    .find(')')
                    .ok_or_else(|| err(i, "comment `(` is not closed on this line".into()))?;
                i += close + 1;
            }
            b';' => break,
            c if c.is_ascii_alphabetic() => {
                let w = lex_word(text, i, end).map_err(|(at, m)| err(at, m))?;
                i = w.span.end;
                words.push(w);
            }
            _ => {
                let ch = text[i..].chars().next().unwrap_or('?');
                return Err(err(
                    i,
                    format!("unexpected character `{ch}` (expected a word such as `X10.5`, a comment or `;`)"),
                ));
            }
        }
    }
    Ok(Line {
        number,
        content,
        words,
    })
}

/// Largest |value| of an NC word: the coordinate limit in µm (words are mm or inch coordinates,
/// feeds, speeds, line numbers).
const MAX_WORD_VALUE: f64 = runout_core::limits::MAX_COORDINATE_MM * 1e3;

/// Letter, optional blanks, then [+-]digits[.digits] or [+-].digits.
fn lex_word(text: &str, at: usize, end: usize) -> Result<Word, (usize, String)> {
    let b = text.as_bytes();
    let letter = (b[at] as char).to_ascii_uppercase();
    let mut i = at + 1;
    while i < end && (b[i] == b' ' || b[i] == b'\t') {
        i += 1;
    }
    let num_start = i;
    if i < end && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    let int_start = i;
    while i < end && b[i].is_ascii_digit() {
        i += 1;
    }
    let int_digits = i - int_start;
    let mut decimals = 0;
    if i < end && b[i] == b'.' {
        i += 1;
        let f = i;
        while i < end && b[i].is_ascii_digit() {
            i += 1;
        }
        decimals = i - f;
    }
    if int_digits == 0 && decimals == 0 {
        return Err((
            at,
            format!("word `{letter}` has no number (variables, expressions and named programs are not supported)"),
        ));
    }
    let written = &text[num_start..i];
    let quoted = || match written.char_indices().nth(80) {
        Some((n, _)) => format!("{}…", &written[..n]),
        None => written.to_string(),
    };
    let value: f64 = written
        .parse()
        .map_err(|_| (num_start, format!("`{}` is not a number", quoted())))?;
    if !(value.is_finite() && value.abs() <= MAX_WORD_VALUE) {
        return Err((
            num_start,
            format!(
                "word `{letter}`: number `{}` out of range (|value| <= {MAX_WORD_VALUE:e})",
                quoted()
            ),
        ));
    }
    Ok(Word {
        letter,
        value,
        number: num_start..i,
        span: at..i,
        decimals,
    })
}
