//! Pass 1 over the recording: spectrum, envelope and pulse range → coarse speed and section.

use super::chunk::ChunkGuard;
use super::pulse::Range;
use super::spectrum::{ToothPassingLine, Welch};
use super::steady::{Envelope, SteadySection};
use super::{SignalChunk, SignalConfig, SignalError};

/// Pass-1 accumulator: feed every chunk of the recording, then [`SpindleScan::finish`].
///
/// Memory: the Welch buffers (≤ 2¹⁶-sample frames), the envelope (≤ 2¹⁵ blocks) and the pulse
/// range; independent of the recording length.
pub struct SpindleScan {
    cfg: SignalConfig,
    guard: ChunkGuard,
    welch: Welch,
    envelope: Envelope,
    pulse: Range,
}

/// What pass 1 found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ScanResult {
    /// Samples in the recording.
    pub samples: u64,
    /// Duration (s) = samples / f_s.
    pub duration_s: f64,
    /// The tooth-passing line of the spectrum.
    pub tooth_passing: ToothPassingLine,
    /// Coarse spindle frequency from the spectrum, line/K (Hz).
    pub coarse_spindle_hz: f64,
    /// The section to average (detected, or the override).
    pub section: SteadySection,
    /// Pulse thresholds (low, high) to use in passes 2 and 3, in the pulse channel's unit.
    #[serde(rename = "pulse_thresholds_low_high")]
    pub pulse_thresholds: Option<(f64, f64)>,
    /// F_z present in the chunks.
    pub has_fz: bool,
}

impl SpindleScan {
    /// Start pass 1.
    pub fn new(cfg: &SignalConfig) -> Result<Self, SignalError> {
        cfg.validate()?;
        let spr = cfg.samples_per_rev();
        Ok(SpindleScan {
            cfg: cfg.clone(),
            guard: ChunkGuard::default(),
            welch: Welch::new(cfg.sample_rate_hz, spr),
            envelope: Envelope::new(spr.round().max(1.0) as u64),
            pulse: Range::default(),
        })
    }

    /// Feed the next chunk.
    pub fn push(&mut self, c: SignalChunk) -> Result<(), SignalError> {
        self.guard
            .check(&c, self.cfg.sample_rate_hz, self.cfg.pulse.is_some())?;
        self.welch.push_all(c.fx, c.fy);
        self.envelope.push_all(c.fx, c.fy, c.fz);
        if let Some(p) = c.pulse {
            p.iter().for_each(|&v| self.pulse.push(v));
        }
        Ok(())
    }

    /// Finish pass 1: length check, tooth-passing line, section, pulse thresholds.
    pub fn finish(mut self) -> Result<ScanResult, SignalError> {
        let cfg = &self.cfg;
        let fs = cfg.sample_rate_hz;
        let samples = self.guard.next;
        let duration_s = samples as f64 / fs;
        let rev_s = 60.0 / cfg.nominal_rpm;
        if duration_s < 2.0 * rev_s {
            return Err(SignalError::TooShort {
                what: "recording",
                seconds: duration_s,
                revolutions: duration_s / rev_s,
                rpm: cfg.nominal_rpm,
            });
        }
        self.welch.finish();
        let line = self
            .welch
            .tooth_passing(cfg.teeth, cfg.nominal_rpm, cfg.search_band)?;
        let coarse = line.hz / cfg.teeth as f64;
        let section = match cfg.section_s {
            Some((a, b)) => {
                let mut s = override_section(a, b, duration_s, 60.0 / cfg.nominal_rpm)?;
                s.air_offset = self
                    .envelope
                    .detect(fs, 60.0 / cfg.nominal_rpm)
                    .ok()
                    .and_then(|d| d.air_offset);
                s
            }
            None => self.envelope.detect(fs, 60.0 / cfg.nominal_rpm)?,
        };
        let pulse_thresholds = match cfg.pulse {
            None => None,
            Some(p) => Some(p.thresholds.or(self.pulse.thresholds()).ok_or_else(|| {
                SignalError::Pulse {
                    reason: format!(
                        "the channel is flat (min {} = max {}): no edges",
                        self.pulse.min, self.pulse.max
                    ),
                }
            })?),
        };
        Ok(ScanResult {
            samples,
            duration_s,
            tooth_passing: line,
            coarse_spindle_hz: coarse,
            section,
            pulse_thresholds,
            has_fz: self.guard.has_fz(),
        })
    }
}

fn override_section(
    a: f64,
    b: f64,
    duration: f64,
    rev_s: f64,
) -> Result<SteadySection, SignalError> {
    if b > duration + 1e-9 {
        return Err(crate::error::ParamError::new(
            "to_s",
            format!("a time within the recording (<= {duration:.6} s)"),
            b,
        )
        .into());
    }
    if b - a < 2.0 * rev_s {
        return Err(SignalError::TooShort {
            what: "section from_s..to_s",
            seconds: b - a,
            revolutions: (b - a) / rev_s,
            rpm: 60.0 / rev_s,
        });
    }
    Ok(SteadySection {
        from_s: a,
        to_s: b,
        overridden: true,
        block_s: 0.0,
        air_level: f64::NAN,
        cut_level: f64::NAN,
        threshold: f64::NAN,
        trim_tolerance: 0.0,
        trimmed_blocks: 0,
        air_offset: None,
    })
}
