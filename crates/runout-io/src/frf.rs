//! Measured frequency-response (FRF) tables for the measuring chain (issue 11): an impact-test
//! export converted to one row per frequency,
//!
//! ```text
//! # tool tip, hammer on the cutter, sensors at the shank (any comment lines)
//! freq_Hz, xx_re, xx_im, yy_re, yy_im[, zz_re, zz_im]
//! 0,       1.0,   0.0,   1.0,   0.0
//! 10,      1.0001, -0.0001, 1.0001, -0.0001
//! ```
//!
//! Comma, semicolon, tab or whitespace separated; the header names the columns (any order,
//! case-insensitive; `freq_Hz` or `frequency_Hz`); `xx` is the response of x to a force in x
//! (direct term; cross terms are not modelled). Values in any consistent unit (µm/N, m/N,
//! (m/s²)/N converted to receptance first): each axis is normalised by its first row, which is
//! taken as the static value, so the table should start at or near 0 Hz
//! ([`runout_core::chain::FrfCurve`]). Frequencies strictly increasing. Axes without columns
//! are rigid.

use runout_core::chain::{AxisChain, Complex64, FrfCurve, MeasuringChain};
use std::path::Path;

/// Error naming the file, the line and what was expected (the shared [`crate::LocatedError`]).
pub type FrfError = crate::LocatedError;

/// Read an FRF table from a file (see the module docs).
pub fn read_frf(path: &Path) -> Result<MeasuringChain, FrfError> {
    let file = path.display().to_string();
    let text = crate::textfile::read_text(path).map_err(|e| FrfError {
        message: format!("FRF table: {}", e.message),
        ..e
    })?;
    parse_frf(&file, &text)
}

/// Parse the text of an FRF table; `file` names it in errors. Read with the shared table
/// reader (`runout_io::table`, fields separated by commas, semicolons, tabs or spaces).
pub fn parse_frf(file: &str, text: &str) -> Result<MeasuringChain, FrfError> {
    let err = |line: usize, message: String| FrfError::new(file, line, message);
    if text
        .lines()
        .all(|l| l.trim().is_empty() || l.trim_start().starts_with('#'))
    {
        return Err(err(
            0,
            "empty: expected a header `freq_Hz, xx_re, xx_im, yy_re, yy_im` and rows".into(),
        ));
    }
    let t = crate::table::parse_text(file, text, true)?;
    let hline = t.header_line;
    let header = crate::textfile::quote(&t.headers.join(", "));
    let freq = t
        .column("freq_hz")
        .or_else(|| t.column("frequency_hz"))
        .ok_or_else(|| {
            err(
                hline,
                format!("header `{header}` has no `freq_Hz` column (expected freq_Hz, xx_re, xx_im, yy_re, yy_im[, zz_re, zz_im])"),
            )
        })?;
    let mut axes = Vec::new(); // (axis, re column, im column)
    for (a, name) in ["xx", "yy", "zz"].iter().enumerate() {
        match (
            t.column(&format!("{name}_re")),
            t.column(&format!("{name}_im")),
        ) {
            (Some(r), Some(i)) => axes.push((a, r, i)),
            (None, None) => {}
            _ => {
                return Err(err(
                    hline,
                    format!("header `{header}`: give both {name}_re and {name}_im"),
                ))
            }
        }
    }
    if axes.is_empty() {
        return Err(err(
            hline,
            format!("header `{header}` has no response columns (xx_re, xx_im, yy_re, yy_im)"),
        ));
    }
    let mut f: Vec<f64> = Vec::new();
    let mut v: Vec<Vec<Complex64>> = vec![Vec::new(); 3];
    let rows: Vec<usize> = t.rows.iter().map(|r| r.0).collect();
    for (r, &ln) in rows.iter().enumerate() {
        let fv = t.number(r, &freq)?;
        if let Some(&prev) = f.last() {
            if fv <= prev {
                return Err(err(
                    ln,
                    format!("frequency {fv} Hz not above the previous {prev} Hz (expected strictly increasing)"),
                ));
            }
        } else if fv < 0.0 {
            return Err(err(ln, format!("frequency {fv} Hz: expected ≥ 0 Hz")));
        }
        f.push(fv);
        for (a, re, im) in &axes {
            v[*a].push(Complex64::new(t.number(r, re)?, t.number(r, im)?));
        }
    }
    let axes: Vec<usize> = axes.iter().map(|x| x.0).collect();
    let mut chain = MeasuringChain::default();
    for &a in &axes {
        let name = format!("{file} {}", ["xx", "yy", "zz"][a]);
        let curve = FrfCurve::new(&name, f.clone(), std::mem::take(&mut v[a]))
            .map_err(|e| err(if rows.is_empty() { hline } else { rows[0] }, e.to_string()))?;
        let axis = AxisChain::Frf(curve);
        match a {
            0 => chain.x = axis,
            1 => chain.y = axis,
            _ => chain.z = axis,
        }
    }
    Ok(chain)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_and_normalises() {
        let t = "# impact test\nfreq_Hz; xx_re; xx_im; yy_re; yy_im\n0;2;0;4;0\n100;2;2;4;-4\n";
        let c = parse_frf("t.csv", t).unwrap();
        assert_eq!(
            c.x.response(50.0).unwrap(),
            Complex64::new(1.0, 0.5),
            "normalised by the first row, interpolated"
        );
        assert_eq!(c.y.response(100.0).unwrap(), Complex64::new(1.0, -1.0));
        assert!(c.z.is_rigid());
        assert!(c.x.response(100.5).is_none());
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = parse_frf("t.csv", "freq_Hz,xx_re,xx_im\n0,1,0\n5,1\n").unwrap_err();
        assert_eq!((e.line, e.file.as_str()), (3, "t.csv"));
        assert!(e.to_string().starts_with("t.csv:3: 2 fields"), "{e}");
        let e = parse_frf("t.csv", "freq_Hz,xx_re,xx_im\n0,1,0\n1,1,x\n").unwrap_err();
        assert!(
            e.to_string().contains("t.csv:3:3: `x` in column `xx_im`"),
            "{e}"
        );
        let e = parse_frf("t.csv", "freq_Hz,xx_re,xx_im\n10,1,0\n5,1,0\n").unwrap_err();
        assert!(e.to_string().contains("t.csv:3: frequency 5 Hz"), "{e}");
        let e = parse_frf("t.csv", "f,xx_re,xx_im\n").unwrap_err();
        assert!(
            e.to_string().contains("t.csv:1:") && e.message.contains("freq_Hz"),
            "{e}"
        );
        let e = parse_frf("t.csv", "freq_Hz,xx_re\n").unwrap_err();
        assert!(e.message.contains("xx_im"), "{e}");
        let e = parse_frf("t.csv", "freq_Hz xx_re  xx_im\n0 1 0\n1 1 x\n").unwrap_err();
        assert!(e.to_string().starts_with("t.csv:3:3: `x`"), "{e}");
        let e = parse_frf("t.csv", "freq_Hz,xx_re,xx_im\n0,0,0\n1,1,0\n").unwrap_err();
        assert!(e.message.contains("non-zero static"), "{e}");
    }
}
