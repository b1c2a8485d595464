//! Raw displacement signals → runout (methods.md §1.3, §1.6; `conventions.md` "Signals").
//!
//! Sensor s sits at fixed angle β_s (measured in the direction of rotation from the direction the
//! spindle-frame zero faces at φ = 0). A round section offset by e = ρ(cos λ_m, sin λ_m) from the
//! rotation axis (λ_m measured from the spindle zero) gives the radial position
//!
//!   P_s(φ) = c_s + ρ·cos(λ_m + φ − β_s) = c_s + a_s cos φ + b_s sin φ,
//!   (a_s, b_s) = M_s·(e_x, e_y),  M_s = [[cos β_s, sin β_s], [sin β_s, −cos β_s]]  (M_s² = I),
//!
//! so each channel's first harmonic (linear least squares, one pass) gives e_s = M_s·(a_s, b_s); the
//! channels are combined by inverse-covariance weighting. λ = λ_m − φ_ref with φ_ref the spindle
//! angle of tooth 0 from the mark. The beam correction (§1.4) scales the amplitude and rotates β_s.

mod extrema;
mod harmonic;
mod track;

pub use extrema::{per_revolution_runout, per_tooth_extrema, RevolutionRunout};
pub use track::{SpindleTrack, TrackSource};

use super::beam::BeamGeometry;
use super::error::{check_finite, DisplacementError};
use super::estimate::{polar_with_covariance, AngleEstimate};
use super::readings::SensorSign;
use nalgebra::{Matrix2, Vector2};
use serde::Serialize;

/// One displacement channel.
#[derive(Debug, Clone, Copy)]
pub struct SensorChannel<'a> {
    /// Samples (mm).
    pub displacement_mm: &'a [f64],
    /// Sensor angle β (rad, direction of rotation, fixed frame).
    pub angle_rad: f64,
    /// Distance or radial position.
    pub sign: SensorSign,
}

/// Where the spindle angle comes from.
#[derive(Debug, Clone, Copy)]
pub enum SpindleReference<'a> {
    /// Once-per-revolution mark channel (any levels; rising edges through the mid level).
    Pulse(&'a [f64]),
    /// Spindle angle (rad) of every sample.
    Encoder(&'a [f64]),
    /// No reference: estimate the speed within `rpm_min..rpm_max` from the spectrum; the angle
    /// is then relative to the spindle position at the first sample.
    Estimate {
        /// Lowest plausible speed (rpm).
        rpm_min: f64,
        /// Highest plausible speed (rpm).
        rpm_max: f64,
    },
}

/// A raw recording at constant sample rate.
#[derive(Debug, Clone)]
pub struct SignalInput<'a> {
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Displacement channels (all the same length).
    pub channels: Vec<SensorChannel<'a>>,
    /// Spindle angle source.
    pub reference: SpindleReference<'a>,
    /// Radius (mm) of the measured round section (for the beam correction).
    pub surface_radius_mm: f64,
    /// Beam inclination / offset (methods.md §1.4).
    pub beam: BeamGeometry,
    /// Spindle-frame angle φ_ref (rad) of tooth 0 measured from the mark (λ = λ_mark − φ_ref).
    pub reference_angle_rad: f64,
}

/// First-harmonic result of one channel.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelFit {
    /// Sensor angle used (rad, beam-corrected).
    pub sensor_angle_rad: f64,
    /// Runout vector from this channel alone (mm, spindle frame, from tooth 0).
    pub vector_mm: [f64; 2],
    /// Its length (mm).
    pub offset_mm: f64,
    /// Residual standard deviation of the channel (mm, radial).
    pub residual_sd_mm: f64,
}

/// Result of [`fit_signal`].
#[derive(Debug, Clone, Serialize)]
pub struct SignalFit {
    /// Spindle angle source.
    pub reference: TrackSource,
    /// Spindle speed (rpm).
    pub rpm: f64,
    /// Revolution-to-revolution speed standard deviation (rpm).
    pub rpm_sd: Option<f64>,
    /// Complete revolutions in the record.
    pub revolutions: usize,
    /// Samples used in the fit.
    pub samples_used: usize,
    /// Combined runout vector (mm, spindle frame, from tooth 0).
    pub vector_mm: [f64; 2],
    /// ρ (mm).
    pub offset_mm: f64,
    /// Standard error of ρ (mm).
    pub offset_se_mm: f64,
    /// λ (rad) or why it is undetermined.
    pub angle: AngleEstimate,
    /// Per-channel results.
    pub channels: Vec<ChannelFit>,
    /// χ² per degree of freedom of the channel vectors about the combined vector (≈ 1 when the
    /// sensors agree; ≫ 1: wrong sensor angle, rotation sense, or form error).
    pub channel_agreement_chi2: Option<f64>,
    /// Warnings.
    pub notes: Vec<String>,
}

fn check_input(input: &SignalInput<'_>) -> Result<usize, DisplacementError> {
    if !(input.sample_rate_hz.is_finite() && input.sample_rate_hz > 0.0) {
        return Err(crate::ParamError::new(
            "sample_rate_hz",
            "a finite number > 0",
            input.sample_rate_hz,
        )
        .into());
    }
    let first = input.channels.first().ok_or_else(|| {
        DisplacementError::Signal("no displacement channel: at least one is needed".into())
    })?;
    let n = first.displacement_mm.len();
    for (k, ch) in input.channels.iter().enumerate() {
        if ch.displacement_mm.len() != n {
            return Err(DisplacementError::Signal(format!(
                "channel {k} has {} samples, channel 0 has {n}",
                ch.displacement_mm.len()
            )));
        }
        check_finite(
            &format!("sample of displacement channel {k}"),
            ch.displacement_mm,
        )?;
        if !ch.angle_rad.is_finite() {
            return Err(crate::ParamError::new(
                "sensor_angle_deg",
                "a finite number",
                ch.angle_rad,
            )
            .into());
        }
    }
    match input.reference {
        SpindleReference::Pulse(p) | SpindleReference::Encoder(p) if p.len() != n => {
            Err(DisplacementError::Signal(format!(
                "the reference channel has {} samples, the displacement channels {n}",
                p.len()
            )))
        }
        _ if n < 16 => Err(DisplacementError::TooFew {
            what: "samples in the signal".into(),
            got: n,
            need: 16,
        }),
        _ => Ok(n),
    }
}

/// The spindle angle track of a recording.
pub fn spindle_track(input: &SignalInput<'_>) -> Result<SpindleTrack, DisplacementError> {
    check_input(input)?;
    let fs = input.sample_rate_hz;
    match input.reference {
        SpindleReference::Pulse(p) => track::from_pulse(p, fs),
        SpindleReference::Encoder(a) => track::from_encoder(a, fs),
        SpindleReference::Estimate { rpm_min, rpm_max } => {
            if !(rpm_min > 0.0 && rpm_max > rpm_min && rpm_max.is_finite()) {
                return Err(crate::ParamError::new(
                    "rpm range",
                    "0 < rpm_min < rpm_max",
                    format!("{rpm_min}..{rpm_max}"),
                )
                .into());
            }
            let sig: Vec<&[f64]> = input.channels.iter().map(|c| c.displacement_mm).collect();
            track::estimated(&sig, fs, (rpm_min, rpm_max))
        }
    }
}

/// Identify the runout vector from a raw recording: spindle angle track, first harmonic of every
/// channel by linear least squares, inverse-covariance combination (module doc).
///
/// Returns the fit and the track (reuse it for [`per_revolution_runout`] / [`per_tooth_extrema`]).
pub fn fit_signal(input: &SignalInput<'_>) -> Result<(SignalFit, SpindleTrack), DisplacementError> {
    let track = spindle_track(input)?;
    let factor = input.beam.amplitude_factor(input.surface_radius_mm)?;
    let shift = input.beam.direction_shift(input.surface_radius_mm)?;
    let sig: Vec<&[f64]> = input.channels.iter().map(|c| c.displacement_mm).collect();
    let fits = harmonic::fit_harmonics(&track, &sig).ok_or_else(|| {
        DisplacementError::Signal(
            "the spindle angles do not cover a revolution: singular fit".into(),
        )
    })?;
    let mut info = Matrix2::zeros();
    let mut info_e = Vector2::zeros();
    let mut per_channel = Vec::with_capacity(fits.len());
    let mut estimates = Vec::with_capacity(fits.len());
    let rot = |v: Vector2<f64>| {
        let (s, c) = input.reference_angle_rad.sin_cos();
        Vector2::new(c * v[0] + s * v[1], -s * v[0] + c * v[1])
    };
    for (ch, fit) in input.channels.iter().zip(&fits) {
        let sgn = ch.sign.radial(1.0) * factor;
        let beta = ch.angle_rad + shift;
        let (sb, cb) = beta.sin_cos();
        let m = Matrix2::new(cb, sb, sb, -cb);
        let e = m * Vector2::new(fit.beta[1], fit.beta[2]) * sgn;
        let cov = m * fit.cov_ab * m.transpose() * (sgn * sgn);
        let w = cov.try_inverse().ok_or_else(|| {
            DisplacementError::Fit("zero residual: cannot weight channels".into())
        })?;
        info += w;
        info_e += w * e;
        estimates.push((e, w));
        let er = rot(e);
        per_channel.push(ChannelFit {
            sensor_angle_rad: beta,
            vector_mm: [er[0], er[1]],
            offset_mm: er.norm(),
            residual_sd_mm: fit.sigma * factor,
        });
    }
    let cov = info
        .try_inverse()
        .ok_or_else(|| DisplacementError::Fit("singular channel combination".into()))?;
    let e = cov * info_e;
    let chi2 = (estimates.len() > 1).then(|| {
        let s: f64 = estimates
            .iter()
            .map(|(es, w)| ((es - e).transpose() * w * (es - e))[0])
            .sum();
        s / (2.0 * (estimates.len() - 1) as f64)
    });
    let er = rot(e);
    // rotation by −φ_ref leaves the (isotropic part of the) covariance unchanged; rotate it exactly
    let (s, c) = input.reference_angle_rad.sin_cos();
    let r = Matrix2::new(c, s, -s, c);
    let cov_r = r * cov * r.transpose();
    let (rho, lambda, se_rho, se_l) = polar_with_covariance([er[0], er[1]], &cov_r);
    let mut notes = Vec::new();
    if let Some(x) = chi2.filter(|x| *x > 25.0) {
        notes.push(format!(
            "the sensors disagree (χ²/dof = {x:.1}): check the sensor angles, the rotation sense and the sign (distance vs radial)"
        ));
    }
    if track.source == TrackSource::Estimated {
        notes.push("no spindle reference: the angle is relative to the spindle position at the first sample".into());
    }
    Ok((
        SignalFit {
            reference: track.source,
            rpm: track.rpm,
            rpm_sd: track.rpm_sd,
            revolutions: track.revolutions.len(),
            samples_used: track.samples_used(),
            vector_mm: [er[0], er[1]],
            offset_mm: rho,
            offset_se_mm: se_rho,
            angle: AngleEstimate::checked(lambda, Some(se_l), rho),
            channels: per_channel,
            channel_agreement_chi2: chi2,
            notes,
        },
        track,
    ))
}
