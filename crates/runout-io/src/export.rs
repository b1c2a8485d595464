//! Writers for recordings in instrument formats, used to make realistic test and example files
//! (a simulated cut written the way a Kistler DynoWare text export looks).

use std::io::{self, Write};

/// Field delimiter and decimal separator of a text export.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TextStyle {
    /// Field delimiter: `,`, `;` or `\t`.
    pub delimiter: char,
    /// Write `1,5` instead of `1.5` (German/Chinese Windows locales; needs `;` or tab delimiters).
    pub decimal_comma: bool,
}

impl Default for TextStyle {
    fn default() -> Self {
        TextStyle {
            delimiter: ',',
            decimal_comma: false,
        }
    }
}

/// A channel to write: name, unit, samples.
#[derive(Debug, Clone, Copy)]
pub struct Channel<'a> {
    /// Channel name (`Fx`).
    pub name: &'a str,
    /// Unit (`N`).
    pub unit: &'a str,
    /// Samples at the common rate.
    pub data: &'a [f64],
}

/// Write a DynoWare text export: `DynoWare,Version …`, `Key:,value` lines, the channel-name row
/// (`Time,Fx,…`), the unit row (`s,N,…`), then one row per sample with the time column first.
///
/// ```
/// use runout_io::export::{write_dynoware, Channel, TextStyle};
/// let fx = [1.0, 2.5];
/// let mut out = Vec::new();
/// write_dynoware(&mut out, 1000.0, &[("Filename", "sim.dwd")], &[Channel { name: "Fx", unit: "N", data: &fx }], TextStyle::default()).unwrap();
/// let text = String::from_utf8(out).unwrap();
/// assert!(text.starts_with("DynoWare,Version 2.5.1.2\n"));
/// assert!(text.contains("Sampling rate [Hz]:,1000\n"));
/// assert!(text.ends_with("Time,Fx\ns,N\n0,1\n0.001,2.5\n"));
/// ```
pub fn write_dynoware<W: Write>(
    w: &mut W,
    rate_hz: f64,
    meta: &[(&str, &str)],
    channels: &[Channel],
    style: TextStyle,
) -> io::Result<()> {
    let d = style.delimiter;
    if style.decimal_comma && d == ',' {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "decimal comma needs a ';' or tab delimiter",
        ));
    }
    let n = channels.iter().map(|c| c.data.len()).min().unwrap_or(0);
    let num = |v: f64| {
        let s = format!("{v}");
        if style.decimal_comma {
            s.replace('.', ",")
        } else {
            s
        }
    };
    writeln!(w, "DynoWare{d}Version 2.5.1.2")?;
    for (k, v) in meta {
        writeln!(w, "{k}:{d}{v}")?;
    }
    writeln!(w, "Sampling rate [Hz]:{d}{}", num(rate_hz))?;
    writeln!(
        w,
        "Measuring time [s]:{d}{}",
        num((n.saturating_sub(1)) as f64 / rate_hz)
    )?;
    writeln!(w, "Samples per channel:{d}{n}")?;
    write!(w, "Time")?;
    for c in channels {
        write!(w, "{d}{}", c.name)?;
    }
    write!(w, "\ns")?;
    for c in channels {
        write!(w, "{d}{}", c.unit)?;
    }
    writeln!(w)?;
    for q in 0..n {
        let t = (q as f64 / rate_hz * 1e9).round() / 1e9;
        write!(w, "{}", num(t))?;
        for c in channels {
            write!(w, "{d}{}", num((c.data[q] * 1e4).round() / 1e4))?;
        }
        writeln!(w)?;
    }
    Ok(())
}
