//! Header interpretation: DynoWare key lines, channel names with units, unit rows, delimiter
//! and decimal-comma detection.

use super::text::{decode, fields, is_number, trim_field};

/// Units recognised as a suffix of a column name (`fx_N`) — a closed list so that names such
/// as `tooth_count` are not split.
const UNIT_TOKENS: &[&str] = &[
    "N", "kN", "mN", "Nm", "N.m", "s", "ms", "us", "µs", "Hz", "kHz", "V", "mV", "g", "um", "µm",
    "mm", "m", "nm", "deg", "rad", "rpm", "A", "mA", "pC", "Pa", "MPa", "degC", "°C", "K", "%",
];

/// A column's name split from its unit: `Fx [N]`, `Fx (N)`, `fx_N` → (`Fx`/`fx`, `N`).
pub(crate) fn split_unit(header: &str) -> (String, Option<String>) {
    let h = header.trim();
    for (open, close) in [('[', ']'), ('(', ')')] {
        if h.ends_with(close) {
            if let Some(p) = h.rfind(open) {
                let unit = h[p + 1..h.len() - 1].trim();
                let name = h[..p].trim();
                if !name.is_empty() && !unit.is_empty() {
                    return (name.to_string(), Some(unit.to_string()));
                }
            }
        }
    }
    if let Some(p) = h.rfind('_') {
        let unit = &h[p + 1..];
        if p > 0 && UNIT_TOKENS.contains(&unit) {
            return (h[..p].to_string(), Some(unit.to_string()));
        }
    }
    (h.to_string(), None)
}

/// Does a row look like a unit row (every non-empty cell short, unit-like, not a number)?
pub(crate) fn is_unit_row(line: &[u8], delim: u8, decimal_comma: bool) -> bool {
    let mut any = false;
    for f in fields(line, delim) {
        let f = trim_field(f);
        if f.is_empty() {
            continue;
        }
        if is_number(f, decimal_comma) || f.len() > 16 {
            return false;
        }
        let s = decode(f);
        let unit_like = s
            .chars()
            .all(|c| c.is_alphabetic() || "/^*.·%°µ[]()-2 3".contains(c) || c.is_ascii_digit())
            && s.chars().any(|c| c.is_alphabetic() || c == '%');
        if !unit_like {
            return false;
        }
        any = true;
    }
    any
}

/// Choose the delimiter of a generic CSV from its header line and first data line: the
/// candidate (tab, semicolon, comma) giving ≥ 2 header fields and the same count in the data
/// line; else the one giving the most header fields; a single-column file gets a comma.
pub(crate) fn detect_delimiter(header: &[u8], data: Option<&[u8]>) -> u8 {
    let count = |l: &[u8], d: u8| l.iter().filter(|&&c| c == d).count() + 1;
    let cands = [b'\t', b';', b','];
    for d in cands {
        let h = count(header, d);
        if h >= 2 && data.is_none_or(|l| count(l, d) == h) {
            return d;
        }
    }
    cands
        .into_iter()
        .max_by_key(|&d| (count(header, d), d == b','))
        .filter(|&d| count(header, d) >= 2)
        .unwrap_or(b',')
}

/// Decimal commas are in use if the delimiter is not a comma and a data cell contains one.
pub(crate) fn detect_decimal_comma(data: &[u8], delim: u8) -> bool {
    delim != b',' && data.contains(&b',')
}

/// Parse a value of a DynoWare key line (`10000`, `50,000` with decimal commas).
pub(crate) fn meta_number(value: &str, decimal_comma: bool) -> Option<f64> {
    super::text::parse_number(value.as_bytes(), decimal_comma)
        .or_else(|| super::text::parse_number(value.as_bytes(), true))
}

/// A key line `Key:,value` of a DynoWare header → (key without colon, value).
pub(crate) fn key_line(line: &str, delim: char) -> Option<(String, String)> {
    let (k, v) = match line.split_once(delim) {
        Some((k, v)) => (k.trim(), v),
        None => (line.trim(), ""),
    };
    let key = k.strip_suffix(':')?;
    let value = v.trim().trim_end_matches(delim).trim();
    Some((key.trim().to_string(), value.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_from_names() {
        assert_eq!(split_unit("Fx [N]"), ("Fx".into(), Some("N".into())));
        assert_eq!(split_unit("Fx (N)"), ("Fx".into(), Some("N".into())));
        assert_eq!(split_unit("fx_N"), ("fx".into(), Some("N".into())));
        assert_eq!(
            split_unit("force_x_N"),
            ("force_x".into(), Some("N".into()))
        );
        assert_eq!(split_unit("tooth_count"), ("tooth_count".into(), None));
        assert_eq!(split_unit("Time"), ("Time".into(), None));
    }

    #[test]
    fn delimiters() {
        assert_eq!(detect_delimiter(b"Time;Fx;Fy", Some(b"0,0;1,5;2,5")), b';');
        assert_eq!(detect_delimiter(b"Time\tFx", Some(b"0,0\t1,5")), b'\t');
        assert_eq!(detect_delimiter(b"t,fx,fy", Some(b"0,1,2")), b',');
        assert_eq!(detect_delimiter(b"fx", Some(b"1.5")), b',');
        assert!(is_unit_row(b"s,N,N,N", b',', false));
        assert!(!is_unit_row(b"0,1.5,2,3", b',', false));
        assert_eq!(
            key_line("Sampling rate [Hz]:,10000", ','),
            Some(("Sampling rate [Hz]".into(), "10000".into()))
        );
        assert_eq!(key_line("Time,Fx", ','), None);
    }
}
