//! Synchronously averaged force waveforms over one spindle revolution, and their averaging.
//!
//! A waveform holds the measured components (F_x, F_y and optionally F_z, N, forces on the
//! workpiece in the workpiece frame) on a uniform spindle-angle grid θ_q = θ₀ + q·2π/N,
//! q = 0..N−1, where θ is the spindle angle of [`crate::ForceModel::simulate`]: tooth 0's tip is
//! at immersion θ. Optional per-sample standard errors (revolution-to-revolution scatter / √M).

use crate::cut::Cut;
use crate::cutter::Cutter;
use crate::error::ParamError;
use serde::Serialize;
use std::f64::consts::TAU;

/// An axis of the workpiece frame (conventions.md: x = feed, y = feed-normal, z up): the
/// direction of a force component, or the target of a channel in an axis mapping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameAxis {
    /// Feed direction x.
    X,
    /// Feed-normal direction y.
    Y,
    /// Tool axis z (up).
    Z,
}

impl FrameAxis {
    /// All axes in order.
    pub const ALL: [FrameAxis; 3] = [FrameAxis::X, FrameAxis::Y, FrameAxis::Z];

    /// Position in [`FrameAxis::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// Lower-case letter `x`, `y` or `z`.
    pub fn letter(self) -> char {
        ['x', 'y', 'z'][self.index()]
    }
}

/// One measured force component over one revolution.
#[derive(Debug, Clone, PartialEq)]
pub struct WaveformComponent {
    /// Which force.
    pub axis: FrameAxis,
    /// Averaged values (N), one per grid angle.
    pub values: Vec<f64>,
    /// Standard errors (N) per sample, if known.
    pub se: Option<Vec<f64>>,
}

/// Synchronously averaged waveform of one recording over one revolution.
#[derive(Debug, Clone, PartialEq)]
pub struct AveragedWaveform {
    /// Spindle angle θ₀ (rad) of sample 0.
    pub start_angle: f64,
    /// Measured components (each of the same length N).
    pub components: Vec<WaveformComponent>,
    /// Number of revolutions averaged (for reports).
    pub revolutions: usize,
}

impl AveragedWaveform {
    /// Check that all components have the same length N ≥ 8, finite values and positive errors.
    pub fn validate(&self) -> Result<usize, ParamError> {
        let n = self.components.first().map(|c| c.values.len()).unwrap_or(0);
        if self.components.is_empty() || n < 8 {
            return Err(ParamError::new(
                "waveform",
                "at least one component with >= 8 samples per revolution",
                format!("{} components, {n} samples", self.components.len()),
            ));
        }
        for c in &self.components {
            let name = format!("waveform f{:?}", c.axis).to_lowercase();
            if c.values.len() != n {
                return Err(ParamError::new(
                    name,
                    format!("{n} samples like the first component"),
                    c.values.len(),
                ));
            }
            if let Some(q) = c.values.iter().position(|v| !v.is_finite()) {
                return Err(ParamError::new(
                    format!("{name}[{q}]"),
                    "a finite force",
                    c.values[q],
                ));
            }
            if let Some(se) = &c.se {
                if se.len() != n || se.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
                    return Err(ParamError::new(
                        format!("{name} standard errors"),
                        format!("{n} finite values > 0"),
                        "invalid",
                    ));
                }
            }
        }
        Ok(n)
    }

    /// Samples per revolution N.
    pub fn samples(&self) -> usize {
        self.components.first().map(|c| c.values.len()).unwrap_or(0)
    }

    /// Grid angle θ_q (rad).
    pub fn angle(&self, q: usize) -> f64 {
        self.start_angle + TAU * q as f64 / self.samples() as f64
    }

    /// Synchronous average of `revolutions` whole revolutions of `samples_per_rev` samples each
    /// from sample series starting at spindle angle `start_angle` (rad). Standard errors are the
    /// revolution-to-revolution standard deviation / √M (M ≥ 2).
    ///
    /// ```
    /// use runout_core::identify::{AveragedWaveform, FrameAxis};
    /// let x: Vec<f64> = (0..40).map(|q| (q % 10) as f64 + if q < 10 { 0.1 } else { 0.0 }).collect();
    /// let w = AveragedWaveform::average(0.0, 10, &[(FrameAxis::X, &x)]).unwrap();
    /// assert_eq!(w.revolutions, 4);
    /// assert!((w.components[0].values[3] - 3.025).abs() < 1e-12);
    /// ```
    pub fn average(
        start_angle: f64,
        samples_per_rev: usize,
        series: &[(FrameAxis, &[f64])],
    ) -> Result<Self, ParamError> {
        let len = series.first().map(|s| s.1.len()).unwrap_or(0);
        if samples_per_rev < 8 {
            return Err(ParamError::new(
                "samples_per_rev",
                "an integer >= 8",
                samples_per_rev,
            ));
        }
        let m = len / samples_per_rev;
        if m < 1 {
            return Err(ParamError::new(
                "series",
                format!("at least one revolution of {samples_per_rev} samples"),
                format!("{len} samples"),
            ));
        }
        let components = series
            .iter()
            .map(|(axis, v)| {
                let mean: Vec<f64> = (0..samples_per_rev)
                    .map(|q| (0..m).map(|r| v[r * samples_per_rev + q]).sum::<f64>() / m as f64)
                    .collect();
                let se = (m >= 2).then(|| {
                    (0..samples_per_rev)
                        .map(|q| {
                            let ss: f64 = (0..m)
                                .map(|r| (v[r * samples_per_rev + q] - mean[q]).powi(2))
                                .sum();
                            (ss / (m - 1) as f64 / m as f64).sqrt().max(1e-12)
                        })
                        .collect()
                });
                WaveformComponent {
                    axis: *axis,
                    values: mean,
                    se,
                }
            })
            .collect();
        Ok(AveragedWaveform {
            start_angle,
            components,
            revolutions: m,
        })
    }
}

/// One recording for identification: the tool, the cut and the averaged waveform.
#[derive(Debug, Clone)]
pub struct WaveformCase {
    /// The cutter (teeth, diameter, helix, pitch).
    pub cutter: Cutter,
    /// Cut conditions (f_z, a_p, engagement).
    pub cut: Cut,
    /// The averaged waveform.
    pub waveform: AveragedWaveform,
}
