//! Per-tooth sensor readings P_i and the radius differences of seed eq. (8).

use super::error::{check_finite, DisplacementError};
use serde::Serialize;

/// What the sensor reports (methods.md §1.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SensorSign {
    /// Distance from the sensor to the surface (triangulation lasers): the radial position is
    /// P = −reading + const.
    #[default]
    Distance,
    /// Radial position of the surface (larger = further from the spindle axis).
    Radial,
}

impl SensorSign {
    /// Radial position (up to a constant) of a reading: `−reading` for [`SensorSign::Distance`].
    #[inline]
    pub fn radial(self, reading: f64) -> f64 {
        match self {
            SensorSign::Distance => -reading,
            SensorSign::Radial => reading,
        }
    }
}

/// Readings of the tooth tips at one height, converted to radial positions (mm, up to a common
/// constant), teeth numbered 0..K−1 in cutting order (`conventions.md`).
///
/// A tooth may have several readings (repeated revolutions); they are averaged and their scatter
/// estimates the sensor noise.
///
/// ```
/// use runout_core::displacement::{SensorSign, ToothReadings};
/// let r = ToothReadings::new(3, &[(0, 0.004), (1, 0.001), (2, -0.002)], SensorSign::Radial).unwrap();
/// let d = r.radius_differences();
/// assert!((d[0] - 0.003).abs() < 1e-15 && (d[2] + 0.006).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ToothReadings {
    samples: Vec<Vec<f64>>,
}

impl ToothReadings {
    /// Build from `(tooth, reading_mm)` pairs. Errors: a tooth out of `0..teeth`, a tooth without
    /// any reading, a non-finite reading, fewer than 2 teeth.
    pub fn new(
        teeth: usize,
        readings: &[(usize, f64)],
        sign: SensorSign,
    ) -> Result<Self, DisplacementError> {
        if teeth < 2 {
            return Err(DisplacementError::TooFew {
                what: "teeth".into(),
                got: teeth,
                need: 2,
            });
        }
        let values: Vec<f64> = readings.iter().map(|r| r.1).collect();
        check_finite("reading", &values)?;
        let mut samples = vec![Vec::new(); teeth];
        for (index, &(tooth, value)) in readings.iter().enumerate() {
            if tooth >= teeth {
                return Err(DisplacementError::ToothOutOfRange {
                    index,
                    tooth,
                    teeth,
                });
            }
            samples[tooth].push(sign.radial(value));
        }
        let missing: Vec<usize> = (0..teeth).filter(|&i| samples[i].is_empty()).collect();
        if !missing.is_empty() {
            return Err(DisplacementError::MissingTooth { teeth, missing });
        }
        Ok(ToothReadings { samples })
    }

    /// One reading per tooth, tooth i = index i.
    pub fn from_values(values_mm: &[f64], sign: SensorSign) -> Result<Self, DisplacementError> {
        let pairs: Vec<(usize, f64)> = values_mm.iter().copied().enumerate().collect();
        ToothReadings::new(values_mm.len(), &pairs, sign)
    }

    /// Number of teeth K.
    pub fn teeth(&self) -> usize {
        self.samples.len()
    }

    /// Readings of each tooth as radial positions (mm).
    pub fn samples(&self) -> &[Vec<f64>] {
        &self.samples
    }

    /// Mean radial position P_i of each tooth (mm).
    pub fn positions(&self) -> Vec<f64> {
        self.samples
            .iter()
            .map(|s| s.iter().sum::<f64>() / s.len() as f64)
            .collect()
    }

    /// Pooled standard deviation (mm) of one reading, from teeth read more than once; `None`
    /// when no tooth has repeats.
    pub fn repeat_noise(&self) -> Option<f64> {
        let (mut ss, mut dof) = (0.0, 0usize);
        for s in &self.samples {
            if s.len() > 1 {
                let m = s.iter().sum::<f64>() / s.len() as f64;
                ss += s.iter().map(|v| (v - m) * (v - m)).sum::<f64>();
                dof += s.len() - 1;
            }
        }
        (dof > 0).then(|| (ss / dof as f64).sqrt())
    }

    /// Standard error (mm) of each tooth's mean for one-reading noise `sigma_mm`: σ/√n_i.
    pub fn mean_se(&self, sigma_mm: f64) -> Vec<f64> {
        self.samples
            .iter()
            .map(|s| sigma_mm / (s.len() as f64).sqrt())
            .collect()
    }

    /// Scale every reading by `factor` (beam correction, methods.md §1.4).
    pub fn scaled(&self, factor: f64) -> ToothReadings {
        ToothReadings {
            samples: self
                .samples
                .iter()
                .map(|s| s.iter().map(|v| v * factor).collect())
                .collect(),
        }
    }

    /// Radius differences ΔR_i = P_i − P_{(i+1) mod K} (mm) between consecutive teeth in cutting
    /// order, methods.md eq. (8) written in our numbering (the seed's ΔR_k = P_k − P_{k+1} runs
    /// against cutting order: its ΔR_k is −ΔR of our teeth (1−k, −k)). Σ ΔR_i = 0.
    pub fn radius_differences(&self) -> Vec<f64> {
        let p = self.positions();
        let k = p.len();
        (0..k).map(|i| p[i] - p[(i + 1) % k]).collect()
    }
}
