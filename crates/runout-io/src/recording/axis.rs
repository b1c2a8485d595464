//! Axis mapping from instrument channels to the workpiece frame (conventions.md: x = feed,
//! y = feed-normal, z up), with sign and swap, parsed from text such as
//! `x = -Fy, y = -Fx, z = -Fz` and echoed back in the same form for results.

use super::{RecordingChunk, RecordingError, RecordingInfo};
pub use runout_core::identify::FrameAxis;
use std::fmt;

/// Where one workpiece axis comes from: a channel and a sign.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisSource {
    /// Channel name (as in the recording's header, with or without unit).
    pub channel: String,
    /// +1 or −1.
    pub sign: f64,
}

/// Workpiece axis ← ± instrument channel, for x, y and (optionally) z.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisMapping {
    axes: [Option<AxisSource>; 3],
}

/// A malformed axis mapping text.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("axis mapping `{}`: {message}", crate::textfile::quote(.text))]
pub struct AxisMappingError {
    /// The text given.
    pub text: String,
    /// What is wrong and what was expected.
    pub message: String,
}

impl AxisMapping {
    /// Parse `x = -Fy, y = -Fx, z = -Fz` (entries separated by `,` or `;`, any order, `+`
    /// optional, at least x or y, each axis and each channel at most once). A channel may be a
    /// column of a 2-D array, `M(:,2)` or `D[:,1]` (the comma inside brackets does not separate).
    pub fn parse(text: &str) -> Result<Self, AxisMappingError> {
        let err = |message: String| AxisMappingError {
            text: text.to_string(),
            message,
        };
        let mut axes: [Option<AxisSource>; 3] = [None, None, None];
        for entry in split_entries(text)
            .into_iter()
            .map(str::trim)
            .filter(|e| !e.is_empty())
        {
            let (lhs, rhs) = entry.split_once('=').ok_or_else(|| {
                err(format!(
                    "`{}` is not of the form `x = -Fy`",
                    crate::textfile::quote(entry)
                ))
            })?;
            let axis = match lhs.trim().to_ascii_lowercase().as_str() {
                "x" => FrameAxis::X,
                "y" => FrameAxis::Y,
                "z" => FrameAxis::Z,
                other => {
                    return Err(err(format!(
                        "`{other}` is not an axis (expected x, y or z)"
                    )))
                }
            };
            let rhs = rhs.trim();
            let (sign, channel) = match rhs.strip_prefix('-') {
                Some(c) => (-1.0, c.trim()),
                None => (1.0, rhs.strip_prefix('+').unwrap_or(rhs).trim()),
            };
            if channel.is_empty() || channel.contains(char::is_whitespace) {
                return Err(err(format!(
                    "`{entry}`: expected one channel name after `=`"
                )));
            }
            if axes[axis.index()].is_some() {
                return Err(err(format!("axis {} given twice", axis.letter())));
            }
            if axes.iter().flatten().any(|s| s.channel == channel) {
                return Err(err(format!(
                    "channel `{}` used for two axes",
                    crate::textfile::quote(channel)
                )));
            }
            axes[axis.index()] = Some(AxisSource {
                channel: channel.to_string(),
                sign,
            });
        }
        if axes[0].is_none() && axes[1].is_none() {
            return Err(err(
                "map at least x or y (e.g. `x = -Fy, y = -Fx, z = -Fz`)".into(),
            ));
        }
        Ok(Self { axes })
    }

    /// The identity mapping, only when the channels are literally named for the axes
    /// (`x`, `Fx`, `F_x`, `force_x`, …, case-insensitive, with or without unit): there is no
    /// hidden default for other names.
    pub fn identity_for<S: AsRef<str>>(channels: &[S]) -> Result<Self, AxisMappingError> {
        let mut axes: [Option<AxisSource>; 3] = [None, None, None];
        for c in channels {
            let full = c.as_ref();
            let base = super::header::split_unit(full).0.to_ascii_lowercase();
            let axis = ["x", "y", "z"].iter().position(|a| {
                ["", "f", "f_", "force_", "force"]
                    .iter()
                    .any(|p| base == format!("{p}{a}"))
            });
            if let Some(a) = axis {
                if axes[a].is_some() {
                    return Err(AxisMappingError {
                        text: String::new(),
                        message: format!("two channels are named for axis {}", ['x', 'y', 'z'][a]),
                    });
                }
                axes[a] = Some(AxisSource {
                    channel: full.to_string(),
                    sign: 1.0,
                });
            }
        }
        if axes[0].is_none() || axes[1].is_none() {
            let names: Vec<String> = channels
                .iter()
                .map(|c| crate::textfile::quote(c.as_ref()))
                .collect();
            return Err(AxisMappingError {
                text: String::new(),
                message: format!(
                    "no axis mapping given and the channels ({}) are not named x/y/z; give one, \
                     e.g. `x = -Fy, y = -Fx, z = -Fz`",
                    names.join(", ")
                ),
            });
        }
        Ok(Self { axes })
    }

    /// The source of one axis, if mapped.
    pub fn source(&self, axis: FrameAxis) -> Option<&AxisSource> {
        self.axes[axis.index()].as_ref()
    }

    /// Find the mapped channels in a recording (error names the missing channel).
    pub fn resolve(&self, info: &RecordingInfo) -> Result<ResolvedAxes, RecordingError> {
        let mut sources = [None; 3];
        for (a, s) in self.axes.iter().enumerate() {
            if let Some(s) = s {
                let i = info.channel_index(&s.channel).ok_or_else(|| {
                    RecordingError::MissingColumn {
                        file: info.file.clone(),
                        line: info.header_lines,
                        name: s.channel.clone(),
                        available: info
                            .channels
                            .iter()
                            .map(|c| c.header.clone())
                            .collect::<Vec<_>>()
                            .join(", "),
                    }
                })?;
                sources[a] = Some((i, s.sign));
            }
        }
        Ok(ResolvedAxes { sources })
    }
}

impl fmt::Display for AxisMapping {
    /// Canonical text, e.g. `x = -Fy, y = -Fx, z = -Fz` (parses back to the same mapping).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = FrameAxis::ALL
            .iter()
            .filter_map(|&a| {
                self.source(a).map(|s| {
                    format!(
                        "{} = {}{}",
                        a.letter(),
                        if s.sign < 0.0 { "-" } else { "" },
                        s.channel
                    )
                })
            })
            .collect();
        write!(f, "{}", parts.join(", "))
    }
}

/// An axis mapping bound to the channel indices of one recording.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResolvedAxes {
    sources: [Option<(usize, f64)>; 3],
}

impl ResolvedAxes {
    /// Is this axis mapped?
    pub fn has(&self, axis: FrameAxis) -> bool {
        self.sources[axis.index()].is_some()
    }

    /// Workpiece-frame values of `axis` for the whole chunk into `out` (cleared first);
    /// false if the axis is not mapped.
    pub fn map_chunk(&self, chunk: &RecordingChunk, axis: FrameAxis, out: &mut Vec<f64>) -> bool {
        out.clear();
        match self.sources[axis.index()] {
            Some((i, sign)) => {
                out.extend(chunk.values[i].iter().map(|v| sign * v));
                true
            }
            None => false,
        }
    }

    /// One sample of `axis` from a row of channel values.
    pub fn value(&self, axis: FrameAxis, row: &[f64]) -> Option<f64> {
        self.sources[axis.index()].map(|(i, s)| s * row[i])
    }
}

/// Split a mapping into entries at `,` or `;` outside brackets (`D[:,1]`, `M(:,2)`, `c{1}` stay
/// whole).
pub(crate) fn split_entries(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (i, ch) in text.char_indices() {
        match ch {
            '[' | '(' | '{' => depth += 1,
            ']' | ')' | '}' => depth = (depth - 1).max(0),
            ',' | ';' if depth == 0 => {
                out.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(&text[start..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_and_echo() {
        let m = AxisMapping::parse("x = -Fy, y = -Fx, z = -Fz").unwrap();
        assert_eq!(m.to_string(), "x = -Fy, y = -Fx, z = -Fz");
        assert_eq!(AxisMapping::parse(&m.to_string()).unwrap(), m);
        let m = AxisMapping::parse("y=+Fx; x= Fy").unwrap();
        assert_eq!(m.to_string(), "x = Fy, y = Fx");
        for bad in [
            "",
            "x = Fy, x = Fx",
            "w = Fx",
            "x = Fy, y = Fy",
            "x -Fy",
            "x = ",
            "z = Fz",
        ] {
            assert!(AxisMapping::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn identity_only_for_axis_names() {
        let m = AxisMapping::identity_for(&["Fx", "Fy", "Fz"]).unwrap();
        assert_eq!(m.to_string(), "x = Fx, y = Fy, z = Fz");
        let m = AxisMapping::identity_for(&["force_x_N", "force_y_N", "ae_rms_V"]).unwrap();
        assert_eq!(m.to_string(), "x = force_x_N, y = force_y_N");
        assert!(AxisMapping::identity_for(&["ch1", "ch2", "ch3"]).is_err());
        assert!(AxisMapping::identity_for(&["Fx", "Fz"]).is_err());
    }

    /// Channel names and the mapping text are user text: their control characters are escaped
    /// in messages (a raw ESC or CR would drive the terminal instead of being shown).
    #[test]
    fn control_characters_in_messages_are_escaped() {
        let e = AxisMapping::identity_for(&["ch\u{1b}[2J1", "ch\r2"]).unwrap_err();
        let shown = e.to_string();
        assert!(!shown.chars().any(char::is_control), "{shown:?}");
        assert!(
            shown.contains("ch\\u{1b}[2J1") && shown.contains("ch\\r2"),
            "{shown}"
        );
        let e = AxisMapping::parse("x = F\u{7}x, w = Fy").unwrap_err();
        let shown = e.to_string();
        assert!(!shown.chars().any(char::is_control), "{shown:?}");
    }
}
