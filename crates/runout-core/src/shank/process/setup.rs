//! Sensor pairs and the recording layout of the shank method (methods.md §3.2).

// Column-major data (`columns[c][k]`) reads clearest with index loops.
#![allow(clippy::needless_range_loop)]

use super::super::{ShankBeam, ShankError};
#[allow(unused_imports)]
use super::*;
use std::f64::consts::FRAC_PI_2;

/// Workpiece axis measured by a sensor pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairAxis {
    /// Feed direction x.
    X,
    /// Feed-normal direction y.
    Y,
}

impl PairAxis {
    /// `x` or `y`.
    pub fn letter(self) -> char {
        match self {
            PairAxis::X => 'x',
            PairAxis::Y => 'y',
        }
    }

    /// Direction angle β in the x–y plane (x: 0, y: π/2).
    pub(super) fn beta(self) -> f64 {
        match self {
            PairAxis::X => 0.0,
            PairAxis::Y => FRAC_PI_2,
        }
    }
}

/// Two displacement sensors in one direction: I at l_I (nearer the holder), II at l_II.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorPair {
    /// Direction.
    pub axis: PairAxis,
    /// +1 if a positive reading means the shank moved towards +axis, −1 otherwise.
    pub sign: f64,
}

/// Everything the pipeline needs. Input rows are, in this order: for each pair the sensor-I and
/// sensor-II displacement (mm), then the pulse channel if `has_pulse`, then one reference force
/// per pair (N, workpiece frame) if `has_reference`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShankSetup {
    /// Beam geometry (sensor heights, tool length).
    pub beam: ShankBeam,
    /// K_δ used for F = K_δ·Δ, N/mm (beam formula or static calibration).
    pub stiffness_n_per_mm: f64,
    /// Sensor pairs (1 or 2).
    pub pairs: Vec<SensorPair>,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Time of sample 0, s.
    pub start_time_s: f64,
    /// Nominal spindle speed, rpm (block length, search window).
    pub nominal_rpm: f64,
    /// A once-per-revolution pulse channel follows the displacement channels.
    pub has_pulse: bool,
    /// Reference force channels (one per pair) follow.
    pub has_reference: bool,
    /// Air-cut segments given by the user, s (empty = detect).
    pub air_cut_s: Vec<(f64, f64)>,
    /// Linear drift correction between the two air cuts.
    pub drift_correction: bool,
    /// Zero-phase Butterworth low-pass (order, cutoff Hz).
    pub lowpass: Option<(usize, f64)>,
    /// Minimum air-cut revolutions for a template (≥ 5).
    pub min_air_revolutions: usize,
    /// Revolutions kept per air-cut segment.
    pub max_template_revolutions: usize,
    /// Sensor range (low, high), mm: samples at or beyond are flagged as saturated.
    pub sensor_range_mm: Option<(f64, f64)>,
    /// Height above the tool tip where runout is reported (cutting zone, a_p/2), mm.
    pub cutting_height_mm: f64,
    /// Angle bins of the template (0 = half the samples per revolution, 16…2048).
    pub template_bins: usize,
    /// Bending dynamics: density, beam damping, teeth, optional force correction (issue 11).
    pub dynamics: super::super::ShankDynamics,
}

impl ShankSetup {
    /// Displacement channels (2 per pair).
    pub fn displacement_channels(&self) -> usize {
        2 * self.pairs.len()
    }

    /// Channels per input row.
    pub fn input_channels(&self) -> usize {
        self.displacement_channels()
            + usize::from(self.has_pulse)
            + if self.has_reference {
                self.pairs.len()
            } else {
                0
            }
    }

    /// Nominal samples per revolution.
    pub fn samples_per_rev(&self) -> f64 {
        self.sample_rate_hz * 60.0 / self.nominal_rpm
    }

    pub(super) fn validate(&self) -> Result<(), ShankError> {
        let p = |param: &str, expected: &str, got: String| {
            ShankError::Param(crate::ParamError::new(param, expected, got))
        };
        if self.pairs.is_empty() || self.pairs.len() > 2 {
            return Err(p(
                "pairs",
                "1 or 2 sensor pairs",
                self.pairs.len().to_string(),
            ));
        }
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(p("sample_rate_hz", "> 0", self.sample_rate_hz.to_string()));
        }
        if !(self.nominal_rpm.is_finite() && self.nominal_rpm > 0.0) {
            return Err(p("rpm", "> 0", self.nominal_rpm.to_string()));
        }
        if self.samples_per_rev() < 16.0 {
            return Err(p(
                "sample_rate_hz",
                "at least 16 samples per spindle revolution",
                format!("{:.1} samples per revolution", self.samples_per_rev()),
            ));
        }
        if self.samples_per_rev() > crate::limits::MAX_SAMPLES_PER_REV as f64 {
            return Err(p(
                "sample_rate_hz",
                &format!(
                    "at most {} samples per spindle revolution",
                    crate::limits::MAX_SAMPLES_PER_REV
                ),
                format!("{:.4e} samples per revolution", self.samples_per_rev()),
            ));
        }
        for (q, &(a, b)) in self.air_cut_s.iter().enumerate() {
            if !(a.is_finite() && b.is_finite() && a >= 0.0 && a < b) {
                return Err(p(
                    &format!("air_cut_s[{q}]"),
                    "a window [start, end] in s with 0 <= start < end",
                    format!("[{}, {}]", crate::limits::show(a), crate::limits::show(b)),
                ));
            }
        }
        if !(self.stiffness_n_per_mm.is_finite() && self.stiffness_n_per_mm > 0.0) {
            return Err(p(
                "stiffness_N_per_um",
                "> 0",
                self.stiffness_n_per_mm.to_string(),
            ));
        }
        if self.min_air_revolutions < 5 {
            return Err(p(
                "min_air_revolutions",
                "≥ 5 (docs/methods.md §3.2 step 3)",
                self.min_air_revolutions.to_string(),
            ));
        }
        Ok(())
    }
}

/// A sample-index range [start, end).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleRange {
    /// First sample.
    pub start: u64,
    /// One past the last sample.
    pub end: u64,
}

impl SampleRange {
    /// Samples in the range.
    pub fn len(&self) -> u64 {
        self.end.saturating_sub(self.start)
    }

    /// True if empty.
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }
}
