//! Per-revolution max/min (seed eq. 5) and per-tooth extrema in angular windows (seed eq. 8 input).

use super::super::error::DisplacementError;
use super::super::readings::ToothReadings;
use super::track::SpindleTrack;
use super::{SensorChannel, SignalInput};
use crate::angle::wrap_pi;
use crate::cutter::Cutter;
use serde::Serialize;

/// Half the total indicated runout per revolution, Δr = (L_max − L_min)/2 (seed eq. 5), of one
/// channel, beam-corrected.
#[derive(Debug, Clone, Serialize)]
pub struct RevolutionRunout {
    /// Sensor angle (rad).
    pub sensor_angle_rad: f64,
    /// Δr of each complete revolution (mm).
    pub half_tir_mm: Vec<f64>,
    /// Mean of `half_tir_mm` (mm).
    pub mean_mm: f64,
    /// Standard deviation over revolutions (mm); `None` with one revolution.
    pub sd_mm: Option<f64>,
}

/// Seed eq. (5) for every complete revolution of every channel.
pub fn per_revolution_runout(
    input: &SignalInput<'_>,
    track: &SpindleTrack,
) -> Result<Vec<RevolutionRunout>, DisplacementError> {
    let factor = input.beam.amplitude_factor(input.surface_radius_mm)?;
    if track.revolutions.is_empty() {
        return Err(DisplacementError::Signal(
            "no complete revolution in the record: the max/min per revolution (seed eq. 5) needs one"
                .into(),
        ));
    }
    Ok(input
        .channels
        .iter()
        .map(|ch| {
            let v: Vec<f64> = track
                .revolutions
                .iter()
                .map(|&(a, b)| {
                    let (lo, hi) = ch.displacement_mm[a..b]
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
                            (l.min(x), h.max(x))
                        });
                    0.5 * (hi - lo) * factor
                })
                .collect();
            let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
            let sd = (v.len() > 1).then(|| {
                (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
            });
            RevolutionRunout {
                sensor_angle_rad: ch.angle_rad,
                half_tir_mm: v,
                mean_mm: mean,
                sd_mm: sd,
            }
        })
        .collect())
}

/// Per-tooth readings from one channel: in every complete revolution, the largest radial position
/// within ±half the smallest pitch of the spindle angle at which tooth i faces the sensor,
/// φ_i* = β − (ψ_i(z) + φ_ref) (β = sensor angle, φ_ref = angle of tooth 0 from the mark).
/// Returned as radial positions (not beam-corrected; [`super::super::identify_from_teeth`] does it),
/// one reading per tooth and revolution.
pub fn per_tooth_extrema(
    input: &SignalInput<'_>,
    track: &SpindleTrack,
    channel: usize,
    cutter: &Cutter,
    height_mm: f64,
) -> Result<ToothReadings, DisplacementError> {
    let ch: &SensorChannel<'_> = input.channels.get(channel).ok_or_else(|| {
        DisplacementError::Signal(format!(
            "channel {channel} requested, the signal has {} displacement channel(s)",
            input.channels.len()
        ))
    })?;
    let k = cutter.teeth();
    let half = 0.5 * cutter.pitch().iter().cloned().fold(f64::INFINITY, f64::min);
    let centres: Vec<f64> = (0..k)
        .map(|i| ch.angle_rad - cutter.tooth_angle(i, height_mm) - input.reference_angle_rad)
        .collect();
    let mut pairs = Vec::with_capacity(track.revolutions.len() * k);
    for &(a, b) in &track.revolutions {
        let mut best = vec![f64::NEG_INFINITY; k];
        for (i, &x) in ch.displacement_mm.iter().enumerate().take(b).skip(a) {
            let Some(phi) = track.angle(i) else { continue };
            let p = ch.sign.radial(x);
            for (t, c) in centres.iter().enumerate() {
                if wrap_pi(phi - c).abs() < half && p > best[t] {
                    best[t] = p;
                }
            }
        }
        pairs.extend(
            best.iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .map(|(t, v)| (t, *v)),
        );
    }
    ToothReadings::new(k, &pairs, super::super::SensorSign::Radial)
}
