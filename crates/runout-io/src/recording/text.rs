//! Low-level text handling: line classification, field splitting and a fast exact float parser.
//!
//! The float parser is specialised for recording cells (`-12.345`, `1,5` with decimal commas,
//! `3.2e-05`): it accumulates up to 19 significant digits in a `u64` and, when the mantissa is
//! below 2⁵³ and the power of ten at most 10²², returns `m·10^e` or `m/10^−e`, which is
//! correctly rounded because both operands are exact (Clinger's fast path). Anything else falls
//! back to `str::parse::<f64>` (also correctly rounded). It is ~3–4× faster than going through
//! the `csv` crate's records + `str::parse` (figure in `benches/read.rs` and the module docs).

/// Exact powers of ten representable in f64.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Trim ASCII blanks and one pair of surrounding double quotes.
pub(crate) fn trim_field(mut b: &[u8]) -> &[u8] {
    while let [first, rest @ ..] = b {
        if *first == b' ' || *first == b'\t' {
            b = rest;
        } else {
            break;
        }
    }
    while let [rest @ .., last] = b {
        if *last == b' ' || *last == b'\t' || *last == b'\r' {
            b = rest;
        } else {
            break;
        }
    }
    if b.len() >= 2 && b[0] == b'"' && b[b.len() - 1] == b'"' {
        b = &b[1..b.len() - 1];
    }
    b
}

/// Parse one cell as a finite f64; `decimal_comma` accepts `,` as the decimal separator.
/// Returns `None` for anything that is not a finite number (empty, text, `nan`, `inf`).
pub(crate) fn parse_number(cell: &[u8], decimal_comma: bool) -> Option<f64> {
    let b = trim_field(cell);
    let n = b.len();
    let mut i = 0;
    let neg = match b.first() {
        Some(b'-') => {
            i = 1;
            true
        }
        Some(b'+') => {
            i = 1;
            false
        }
        _ => false,
    };
    let mut mant: u64 = 0;
    let mut sig = 0u32;
    let mut exp10: i32 = 0;
    let mut any_digit = false;
    let mut in_frac = false;
    while i < n {
        let c = b[i];
        if c.is_ascii_digit() {
            any_digit = true;
            if sig >= 19 {
                return slow_parse(b, decimal_comma);
            }
            mant = mant * 10 + u64::from(c - b'0');
            if mant != 0 {
                sig += 1;
            }
            if in_frac {
                exp10 -= 1;
            }
        } else if !in_frac && (c == b'.' || (decimal_comma && c == b',')) {
            in_frac = true;
        } else {
            break;
        }
        i += 1;
    }
    if !any_digit {
        return None;
    }
    if i < n {
        if b[i] != b'e' && b[i] != b'E' {
            return None;
        }
        i += 1;
        let eneg = match b.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let start = i;
        let mut e: i32 = 0;
        while i < n && b[i].is_ascii_digit() {
            e = (e * 10 + i32::from(b[i] - b'0')).min(100_000);
            i += 1;
        }
        if i == start || i < n {
            return None;
        }
        exp10 += if eneg { -e } else { e };
    }
    let v = if mant == 0 {
        0.0
    } else if mant < (1u64 << 53) && (-22..=22).contains(&exp10) {
        let m = mant as f64;
        if exp10 < 0 {
            m / POW10[(-exp10) as usize]
        } else {
            m * POW10[exp10 as usize]
        }
    } else {
        return slow_parse(b, decimal_comma);
    };
    Some(if neg { -v } else { v })
}

/// Fallback: the standard library's correctly rounded parser (after mapping `,` to `.`).
fn slow_parse(b: &[u8], decimal_comma: bool) -> Option<f64> {
    let s: String = b
        .iter()
        .map(|&c| {
            if decimal_comma && c == b',' {
                '.'
            } else {
                c as char
            }
        })
        .collect();
    // reject forms std accepts but a recording cell must not contain
    if s.bytes()
        .any(|c| c.is_ascii_alphabetic() && c != b'e' && c != b'E')
    {
        return None;
    }
    s.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Does the cell hold a number (used to classify header and unit rows)?
pub(crate) fn is_number(cell: &[u8], decimal_comma: bool) -> bool {
    parse_number(cell, decimal_comma).is_some()
}

/// Split a line on `delim`. Allocation-free iterator over the raw fields.
pub(crate) fn fields(line: &[u8], delim: u8) -> impl Iterator<Item = &[u8]> {
    line.split(move |&c| c == delim)
}

/// Why a line is not text, if it is not.
pub(crate) fn binary_issue(line: &[u8]) -> Option<String> {
    if let Some(p) = memchr::memchr(0, line) {
        return Some(format!("NUL byte at byte {} of the line", p + 1));
    }
    if let Some(p) = line
        .iter()
        .position(|&c| c < 0x20 && c != b'\t' && c != b'\r' && c != b'\n')
    {
        return Some(format!(
            "control character 0x{:02x} at byte {} of the line",
            line[p],
            p + 1
        ));
    }
    if let Err(e) = std::str::from_utf8(line) {
        // Windows-1252/Latin-1 header text (e.g. "Meßzeit") is accepted if it is sparse.
        let high = line.iter().filter(|&&c| c >= 0x80).count();
        if high * 10 > line.len() {
            return Some(format!(
                "invalid UTF-8 at byte {} of the line",
                e.valid_up_to() + 1
            ));
        }
    }
    None
}

/// Decode a header line: UTF-8, else Latin-1 (already checked by [`binary_issue`]).
pub(crate) fn decode(line: &[u8]) -> String {
    match std::str::from_utf8(line) {
        Ok(s) => s.to_string(),
        Err(_) => line.iter().map(|&c| c as char).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_parser_matches_std_on_common_and_edge_forms() {
        let cases = [
            "0",
            "-0",
            "1",
            "-12.345",
            "0.000001",
            "123456789012345678",
            "1234567890123456789012",
            "3.2e-05",
            "1E3",
            "+4.5",
            "0.1",
            "0.30000000000000004",
            "9007199254740993",
            "1e22",
            "1e23",
            "4.9e-324",
            "1.7976931348623157e308",
            " 2.5 ",
            "\"7.25\"",
            ".5",
            "5.",
        ];
        for c in cases {
            let expect: f64 = c.trim().trim_matches('"').parse().unwrap();
            assert_eq!(parse_number(c.as_bytes(), false), Some(expect), "{c}");
        }
    }

    #[test]
    fn decimal_comma_and_rejections() {
        assert_eq!(parse_number(b"-1,25", true), Some(-1.25));
        assert_eq!(parse_number(b"-1,25", false), None);
        for bad in [
            "", "-", "abc", "1.2.3", "nan", "inf", "1e", "1e+", "1x", "1e400", "--1",
        ] {
            assert_eq!(parse_number(bad.as_bytes(), true), None, "{bad}");
        }
    }

    #[test]
    fn binary_detection() {
        assert!(binary_issue(b"1,2\x003").is_some());
        assert!(binary_issue(b"\xff\xfe\xfd\xfc").is_some());
        assert!(binary_issue(b"Me\xdfzeit [s]:,50").is_none());
        assert!(binary_issue(b"Time\tFx").is_none());
    }
}
