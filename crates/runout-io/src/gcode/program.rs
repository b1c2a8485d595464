//! Modal interpretation of linear moves (G0/G1, G90/G91, G20/G21) and the coordinate rewriter.

use super::lexer::{lex, Line};
use super::NcError;

/// Axis letters tracked, in this order: X Y Z (linear, offset) and A B C (rotary, kept).
pub const AXES: [char; 6] = ['X', 'Y', 'Z', 'A', 'B', 'C'];

/// A linear move (G0 or G1) with at least one axis word.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionBlock {
    /// 1-based line number.
    pub line: usize,
    /// G0 (rapid) rather than G1.
    pub rapid: bool,
    /// G91 incremental mode was active.
    pub incremental: bool,
    /// G20 inch mode was active (offsets in mm are converted).
    pub inch: bool,
    /// Absolute target per axis (program units); `None` while an axis was never programmed.
    pub target: [Option<f64>; 6],
    /// Index of each axis word in the line's words, if present.
    pub word: [Option<usize>; 6],
    line_index: usize,
}

/// Options of [`NcProgram::rewrite`].
#[derive(Debug, Clone, PartialEq)]
pub struct RewriteOptions {
    /// Minimum digits after the decimal point of a rewritten or inserted coordinate (4 = 0.1 µm
    /// in mm programs). A changed word keeps more digits if it had more.
    pub decimals: usize,
}

impl Default for RewriteOptions {
    fn default() -> Self {
        RewriteOptions { decimals: 4 }
    }
}

/// A parsed NC program: the original text, its lines and its linear moves.
#[derive(Debug, Clone)]
pub struct NcProgram<'a> {
    text: &'a str,
    lines: Vec<Line>,
    blocks: Vec<MotionBlock>,
}

#[derive(Clone, Copy, PartialEq)]
enum Motion {
    None,
    Rapid,
    Linear,
    Arc,
    Canned,
}

impl<'a> NcProgram<'a> {
    /// Lex and interpret `text`. Refused with the line and column: unknown characters, words
    /// without a number, a letter twice in a block, arcs (G2/G3) or canned cycles with axis
    /// words, G10/G28/G30/G52/G53/G92 with axis words, axis words with no motion mode, and an
    /// incremental move from an unknown position.
    pub fn parse(text: &'a str) -> Result<Self, NcError> {
        let lines = lex(text)?;
        let mut blocks = Vec::new();
        let (mut motion, mut inc, mut inch) = (Motion::None, false, false);
        let mut pos: [Option<f64>; 6] = [None; 6];
        for (li, line) in lines.iter().enumerate() {
            let at = |k: usize, message: String| NcError {
                line: line.number,
                column: text[line.content.start..line.words[k].span.start]
                    .chars()
                    .count()
                    + 1,
                message,
            };
            let mut seen = [false; 26];
            let mut word: [Option<usize>; 6] = [None; 6];
            let mut special = None;
            let mut dwell = false;
            for (k, w) in line.words.iter().enumerate() {
                let slot = (w.letter as u8 - b'A') as usize;
                if w.letter != 'G' && w.letter != 'M' {
                    if seen[slot] {
                        return Err(at(
                            k,
                            format!("word `{}` appears twice in this block", w.letter),
                        ));
                    }
                    seen[slot] = true;
                }
                if let Some(a) = AXES.iter().position(|&c| c == w.letter) {
                    word[a] = Some(k);
                }
                if w.letter == 'G' {
                    let g = (w.value * 10.0).round() as i64;
                    match g {
                        0 => motion = Motion::Rapid,
                        10 => motion = Motion::Linear,
                        20 | 30 => motion = Motion::Arc,
                        40 => dwell = true,
                        730 | 740 | 760 | 810..=890 if g % 10 == 0 => motion = Motion::Canned,
                        800 => motion = Motion::None,
                        200 => inch = true,
                        210 => inch = false,
                        900 => inc = false,
                        910 => inc = true,
                        100 | 280 | 300 | 520 | 530 | 920 => special = Some(k),
                        _ => {}
                    }
                }
            }
            let first_axis = word.iter().flatten().min().copied();
            let Some(fa) = first_axis else { continue };
            if dwell {
                continue; // G4 X… is a dwell time, not a coordinate
            }
            if let Some(k) = special {
                return Err(at(
                    k,
                    format!(
                        "G{} with axis words is not supported (it changes positions or frames outside linear moves)",
                        line.words[k].value
                    ),
                ));
            }
            let rapid = match motion {
                Motion::Rapid => true,
                Motion::Linear => false,
                Motion::Arc => {
                    return Err(at(fa, "circular interpolation (G2/G3) is not supported: only linear moves G0/G1 can be offset".into()))
                }
                Motion::Canned => {
                    return Err(at(fa, "axis words in a canned cycle are not supported".into()))
                }
                Motion::None => {
                    return Err(at(fa, "axis words but no motion mode (G0/G1) is active".into()))
                }
            };
            for a in 0..6 {
                if let Some(k) = word[a] {
                    let v = line.words[k].value;
                    pos[a] = if inc {
                        Some(
                            pos[a].ok_or_else(|| {
                                at(
                                    k,
                                    format!(
                                        "incremental {} move from an unknown position",
                                        AXES[a]
                                    ),
                                )
                            })? + v,
                        )
                    } else {
                        Some(v)
                    };
                }
            }
            blocks.push(MotionBlock {
                line: line.number,
                rapid,
                incremental: inc,
                inch,
                target: pos,
                word,
                line_index: li,
            });
        }
        Ok(NcProgram {
            text,
            lines,
            blocks,
        })
    }

    /// The linear moves, in program order.
    pub fn motion_blocks(&self) -> &[MotionBlock] {
        &self.blocks
    }

    /// The lexed lines.
    pub fn lines(&self) -> &[Line] {
        &self.lines
    }

    /// Rewrite the program with per-motion-block offsets (mm, X Y Z; `None` = no offset). Each
    /// block's new target is its original target + offset; a present coordinate word whose value
    /// changes (beyond half a unit of the last written digit) gets its number replaced, an absent
    /// one is inserted (after the block's last axis word) when the modal position would
    /// otherwise be wrong. Every other byte is copied unchanged, so all-`None` or all-zero
    /// offsets reproduce the input exactly. `offsets.len()` must equal the number of motion
    /// blocks (else an error with line 0).
    pub fn rewrite(
        &self,
        offsets: &[Option<[f64; 3]>],
        opts: &RewriteOptions,
    ) -> Result<String, NcError> {
        if offsets.len() != self.blocks.len() {
            return Err(NcError {
                line: 0,
                column: 0,
                message: format!(
                    "{} offsets for {} motion blocks",
                    offsets.len(),
                    self.blocks.len()
                ),
            });
        }
        let mut edits: Vec<(usize, usize, String)> = Vec::new();
        let mut cmd: [Option<f64>; 3] = [None; 3];
        for (b, off) in self.blocks.iter().zip(offsets) {
            let line = &self.lines[b.line_index];
            let scale = if b.inch { 1.0 / 25.4 } else { 1.0 };
            let d = off.map(|o| [o[0] * scale, o[1] * scale, o[2] * scale]);
            let mut inserts = String::new();
            for a in 0..3 {
                let da = d.map_or(0.0, |d| d[a]);
                let Some(orig) = b.target[a] else {
                    if da != 0.0 {
                        return Err(NcError {
                            line: b.line,
                            column: 1,
                            message: format!(
                                "{} position is unknown here (no earlier {} word): cannot offset it",
                                AXES[a], AXES[a]
                            ),
                        });
                    }
                    continue;
                };
                let desired = orig + da;
                match b.word[a] {
                    Some(k) => {
                        let w = &line.words[k];
                        let dec = w.decimals.max(opts.decimals);
                        let base = if b.incremental {
                            cmd[a].unwrap_or(orig - w.value)
                        } else {
                            0.0
                        };
                        let value = desired - base;
                        // a word written with more decimals than f64 holds is kept unless the
                        // change is above the rounding of `desired - base`
                        let rounding = 8.0 * f64::EPSILON * desired.abs().max(base.abs()).max(1.0);
                        if (value - w.value).abs() < half_unit(dec).max(rounding) {
                            cmd[a] = Some(base + w.value);
                        } else {
                            let s = format_number(value, dec);
                            cmd[a] = Some(base + s.parse::<f64>().unwrap_or(value));
                            edits.push((w.number.start, w.number.end, s));
                        }
                    }
                    None => {
                        let now = cmd[a].unwrap_or(orig);
                        if (desired - now).abs() >= half_unit(opts.decimals) {
                            let value = if b.incremental {
                                desired - now
                            } else {
                                desired
                            };
                            let s = format_number(value, opts.decimals);
                            let written = s.parse::<f64>().unwrap_or(value);
                            cmd[a] = Some(if b.incremental {
                                now + written
                            } else {
                                written
                            });
                            inserts.push(' ');
                            inserts.push(AXES[a]);
                            inserts.push_str(&s);
                        } else {
                            cmd[a] = Some(now);
                        }
                    }
                }
            }
            if !inserts.is_empty() {
                let at = b
                    .word
                    .iter()
                    .flatten()
                    .map(|&k| line.words[k].span.end)
                    .max()
                    .unwrap_or(line.content.end);
                edits.push((at, at, inserts));
            }
        }
        edits.sort_by_key(|e| (e.0, e.1));
        let mut out = String::with_capacity(self.text.len() + 16 * edits.len());
        let mut last = 0;
        for (s, e, t) in edits {
            out.push_str(&self.text[last..s]);
            out.push_str(&t);
            last = e;
        }
        out.push_str(&self.text[last..]);
        Ok(out)
    }
}

fn half_unit(decimals: usize) -> f64 {
    0.5 * 10f64.powi(-(decimals as i32))
}

/// Fixed-point with `dec` decimals, without a negative zero.
fn format_number(v: f64, dec: usize) -> String {
    let s = format!("{v:.dec$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}
