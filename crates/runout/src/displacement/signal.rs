//! `displacement signal`: raw displacement signal → runout vector (first harmonic by linear
//! least squares; per-revolution TIR; optional per-tooth extrema).

use super::{name_of, AngleReport, BeamReport, ConsequencesReport, Sensor};
use crate::job::{Report, Source};
use crate::verdict::{VerdictBasis, VerdictReport};
use anyhow::{bail, Context, Result};
use runout_core::displacement::{
    consequences, fit_signal, identify_from_teeth, per_revolution_runout, per_tooth_extrema,
    Consequences, RevolutionRunout, SensorChannel, SignalFit, SignalInput, SpindleReference,
    ToothFit, ToothFitOptions,
};
use runout_core::Cutter;
use runout_io::displacement::{read_signal_with, SignalOptions, SignalSection};
use runout_io::displacement_plot::TeethPlot;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Which spindle angle source to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ReferenceChoice {
    /// Pulse, else encoder, else estimated from the spectrum.
    #[default]
    Auto,
    Pulse,
    Encoder,
    /// Estimated from the spectrum.
    None,
}

/// `runout displacement signal`.
#[derive(Debug, Clone)]
pub struct SignalRequest {
    /// A recording of any format (CSV, .mat, TDMS, HDF5, Parquet) with `time_<s|ms>`,
    /// `disp_<name>_<um|mm>`, optional `pulse` or `encoder_<deg|rad>` (or named in `read`).
    pub recording: Source,
    pub section: SignalSection,
    /// Channel mapping, time variable, sample rate (Hz); defaults follow the naming convention.
    pub read: SignalOptions,
    /// Angle of each sensor (rad, file order); `None`: 0 for a single channel.
    pub sensor_angles_rad: Option<Vec<f64>>,
    pub sensor: Sensor,
    pub reference: ReferenceChoice,
    /// Plausible speed range (rpm) when the speed is estimated.
    pub rpm_range: (f64, f64),
    /// Diameter of the measured round section (mm); needed with an inclined or offset beam.
    pub surface_diameter_mm: Option<f64>,
    /// Spindle angle of tooth 0 from the mark (rad).
    pub tooth0_rad: f64,
    /// The cutter, for per-tooth extrema and consequences.
    pub cutter: Option<Cutter>,
    /// Height of the readings above the tip (mm).
    pub height_mm: f64,
    pub fz_mm: Option<f64>,
    pub hole_path_mm: Option<f64>,
}

/// The input as reported.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SignalInputReport {
    pub file: String,
    pub channels: Vec<String>,
}

/// One channel's own fit.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ChannelReport {
    pub channel: String,
    pub sensor_angle_deg: f64,
    pub offset_um: f64,
    pub angle_deg: f64,
    pub residual_sd_um: f64,
}

/// The section analysed.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SectionReport {
    pub from_s: f64,
    pub to_s: f64,
    pub samples: usize,
}

/// TIR/2 per revolution of one channel (seed eq. 5).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PerRevolution {
    pub channel: String,
    pub half_tir_mean_um: f64,
    pub half_tir_sd_um: Option<f64>,
}

/// The per-tooth extrema fit (channel 0).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SignalTeeth {
    pub offset_um: f64,
    #[serde(alias = "offset_se_um")]
    pub offset_um_se: Option<f64>,
    pub positions_um: Vec<f64>,
    pub notes: Vec<String>,
    #[serde(flatten)]
    pub angle: AngleReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub consequences: Option<ConsequencesReport>,
}

/// `runout.displacement.signal/2`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SignalReport {
    /// `runout.displacement.signal/2`
    #[schemars(extend("const" = "runout.displacement.signal/2"))]
    pub schema: String,
    /// The result first: ρ ± SE, λ ± SE, the method, the status and its reasons (issue 21).
    #[serde(default)]
    pub answer: crate::answer::Answer,
    pub input: SignalInputReport,
    pub reference: String,
    pub rpm: f64,
    pub rpm_sd: Option<f64>,
    pub revolutions: usize,
    pub samples_used: usize,
    pub offset_um: f64,
    #[serde(alias = "offset_se_um")]
    pub offset_um_se: f64,
    pub vector_um: [f64; 2],
    pub channel_agreement_chi2: Option<f64>,
    pub channels: Vec<ChannelReport>,
    pub notes: Vec<String>,
    #[serde(flatten)]
    pub angle: AngleReport,
    pub section: SectionReport,
    pub beam: BeamReport,
    pub per_revolution: Vec<PerRevolution>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub teeth: Option<SignalTeeth>,
    /// Pass/fail against the runout tolerance and the consequences for the cut (issue 15).
    pub verdict: Option<VerdictReport>,
    /// The core results behind the text and the plot; not part of the JSON.
    #[serde(skip)]
    #[schemars(skip)]
    pub detail: SignalDetail,
}

/// The core results of `displacement signal`.
#[derive(Debug, Clone, Default)]
pub struct SignalDetail {
    pub fit: Option<SignalFit>,
    pub sample_rate_hz: f64,
    pub revolutions: Vec<RevolutionRunout>,
    pub teeth: Option<(ToothFit, Option<Consequences>)>,
    pub plot: Option<TeethPlot>,
}

impl crate::answer::Answered for SignalReport {
    fn answer(&self) -> &crate::answer::Answer {
        &self.answer
    }
}

impl Report for SignalReport {
    const SCHEMA: &'static str = "runout.displacement.signal/2";
}

fn sensor_angles(given: &Option<Vec<f64>>, n: usize) -> Result<Vec<f64>> {
    let Some(a) = given else {
        if n == 1 {
            return Ok(vec![0.0]);
        }
        bail!("--sensor-angles-deg is required: the file has {n} displacement channels (give {n} comma-separated angles)");
    };
    if a.len() != n {
        bail!(
            "--sensor-angles-deg has {} angle(s), the file has {n} displacement channel(s)",
            a.len()
        );
    }
    Ok(a.clone())
}

/// Fit the runout vector to a raw displacement signal.
pub fn signal(req: &SignalRequest) -> Result<SignalReport> {
    let file = req.recording.name().to_string();
    let table = read_signal_with(req.recording.table_input(), &req.section, &req.read)?;
    let sign = req.sensor.sign;
    let angles = sensor_angles(&req.sensor_angles_rad, table.channels.len())?;
    let beam = req.sensor.beam;
    let ideal = beam.inclination() == 0.0 && beam.offset() == 0.0;
    let surface = match req.surface_diameter_mm {
        Some(d) => 0.5 * d,
        None if ideal => 1.0, // unused: the ideal beam needs no radius
        None => {
            bail!("--surface-diameter-mm is required with --inclination-deg / --beam-offset-mm")
        }
    };
    let (rpm_min, rpm_max) = req.rpm_range;
    let estimate = SpindleReference::Estimate { rpm_min, rpm_max };
    use ReferenceChoice as R;
    let reference = match (req.reference, &table.pulse, &table.encoder_rad) {
        (R::Auto | R::Pulse, Some(p), _) => SpindleReference::Pulse(p),
        (R::Auto | R::Encoder, None, Some(e)) | (R::Encoder, _, Some(e)) => SpindleReference::Encoder(e),
        (R::Auto | R::None, _, _) => estimate,
        (R::Pulse, None, _) => bail!("{file}: --reference pulse but the file has no `pulse` column (missing channel)"),
        (R::Encoder, _, None) => bail!("{file}: --reference encoder but the file has no `encoder_<deg|rad>` column (missing channel)"),
    };
    let input = SignalInput {
        sample_rate_hz: table.sample_rate_hz,
        channels: table
            .channels
            .iter()
            .zip(&angles)
            .map(|((_, v), b)| SensorChannel {
                displacement_mm: v,
                angle_rad: *b,
                sign,
            })
            .collect(),
        reference,
        surface_radius_mm: surface,
        beam,
        reference_angle_rad: req.tooth0_rad,
    };
    let (fit, track) = fit_signal(&input).with_context(|| file.clone())?;
    // seed eq. (5) is a by-product: a record without a complete revolution still gets the fit
    let revs = per_revolution_runout(&input, &track).unwrap_or_default();
    let samples = table.channels[0].1.len();
    let end_s = table.start_s + (samples - 1) as f64 / table.sample_rate_hz;
    let mut plot = TeethPlot {
        tooth_angles_rad: vec![],
        measured_um: vec![],
        model_um: None,
        offset_um: fit.offset_mm * 1e3,
        angle_rad: fit.angle.angle(),
        title: format!("runout from signal: {:.3} µm", fit.offset_mm * 1e3),
    };
    let mut teeth = None;
    if let Some(cutter) = &req.cutter {
        let z = req.height_mm;
        let readings =
            per_tooth_extrema(&input, &track, 0, cutter, z).with_context(|| file.clone())?;
        let mut opts = ToothFitOptions::new(cutter.clone());
        opts.height_mm = z;
        opts.beam = beam;
        opts.known_offset_mm = Some(fit.offset_mm);
        opts.phase_hint_rad = fit.angle.angle();
        let tf = identify_from_teeth(&readings, &opts)
            .with_context(|| format!("{file}: per-tooth extrema"))?;
        let cons = match tf.runout() {
            Some(r) => Some(consequences(cutter, &r, z, req.fz_mm, req.hole_path_mm)?),
            None => None,
        };
        let pm = tf.positions_mm.iter().sum::<f64>() / tf.positions_mm.len() as f64;
        plot.tooth_angles_rad = (0..cutter.teeth())
            .map(|i| cutter.tooth_angle(i, z))
            .collect();
        plot.measured_um = tf.positions_mm.iter().map(|p| (p - pm) * 1e3).collect();
        teeth = Some((tf, cons));
    }
    let names = &table.channels;
    let verdict = VerdictReport::new(
        VerdictBasis {
            offset_um: fit.offset_mm * 1e3,
            offset_um_se: Some(fit.offset_se_mm * 1e3),
            angle_deg: fit.angle.angle().map(f64::to_degrees),
            teeth: req.cutter.as_ref().map(Cutter::teeth),
            diameter_mm: req.cutter.as_ref().map(Cutter::diameter),
            helix_deg: req.cutter.as_ref().map_or(0.0, |c| c.helix().to_degrees()),
            height_mm: req.height_mm,
            fz_mm: req.fz_mm,
        },
        None,
    )?;
    let angle = AngleReport::from(&fit.angle);
    let mut checks: Vec<crate::answer::CrossCheck> = revs
        .iter()
        .zip(names)
        .map(|(r, (name, _))| crate::answer::CrossCheck {
            estimate: format!("TIR/2 per revolution of {name} (seed eq. 5), mean"),
            values: vec![crate::answer::Quantity::cross_check(
                "runout offset ρ",
                "µm",
                r.mean_mm * 1e3,
                r.sd_mm.map(|s| s * 1e3),
            )],
            why_it_may_differ: "half the peak-to-peak displacement includes the out-of-round \
                                of the surface, the tooth profile and the noise; the first \
                                harmonic is the runout alone"
                .into(),
        })
        .collect();
    if let Some((tf, _)) = &teeth {
        checks.push(crate::answer::CrossCheck {
            estimate: "fit to the per-tooth extrema".into(),
            values: vec![crate::answer::Quantity::cross_check(
                "runout offset ρ",
                "µm",
                tf.offset_mm * 1e3,
                tf.offset_se_mm.map(|s| s * 1e3),
            )],
            why_it_may_differ: "uses one extremum per tooth instead of the whole revolution, \
                                so it is noisier and sees the edge profile"
                .into(),
        });
    }
    let answer = super::runout_answer(
        "first harmonic of the displacement against the spindle angle, least squares over the \
         whole section (docs/methods.md §1.5)",
        fit.offset_mm * 1e3,
        Some(fit.offset_se_mm * 1e3),
        Some(&angle),
        req.cutter
            .as_ref()
            .map_or(f64::INFINITY, |c| c.diameter() / 2.0),
        req.fz_mm,
        "record more revolutions, or check the sensor's gain and mounting",
        checks,
    );
    Ok(SignalReport {
        schema: SignalReport::SCHEMA.into(),
        answer,
        input: SignalInputReport {
            file: file.clone(),
            channels: names.iter().map(|c| c.0.clone()).collect(),
        },
        reference: name_of(&fit.reference),
        rpm: fit.rpm,
        rpm_sd: fit.rpm_sd,
        revolutions: fit.revolutions,
        samples_used: fit.samples_used,
        offset_um: fit.offset_mm * 1e3,
        offset_um_se: fit.offset_se_mm * 1e3,
        vector_um: [fit.vector_mm[0] * 1e3, fit.vector_mm[1] * 1e3],
        channel_agreement_chi2: fit.channel_agreement_chi2,
        channels: fit
            .channels
            .iter()
            .zip(names)
            .map(|(c, (name, _))| ChannelReport {
                channel: name.clone(),
                sensor_angle_deg: c.sensor_angle_rad.to_degrees(),
                offset_um: c.offset_mm * 1e3,
                angle_deg: c.vector_mm[1].atan2(c.vector_mm[0]).to_degrees(),
                residual_sd_um: c.residual_sd_mm * 1e3,
            })
            .collect(),
        notes: fit.notes.clone(),
        angle,
        section: SectionReport {
            from_s: table.start_s,
            to_s: end_s,
            samples,
        },
        beam: BeamReport::from(&req.sensor),
        per_revolution: revs
            .iter()
            .zip(names)
            .map(|(r, (name, _))| PerRevolution {
                channel: name.clone(),
                half_tir_mean_um: r.mean_mm * 1e3,
                half_tir_sd_um: r.sd_mm.map(|s| s * 1e3),
            })
            .collect(),
        teeth: teeth.as_ref().map(|(tf, cons)| SignalTeeth {
            offset_um: tf.offset_mm * 1e3,
            offset_um_se: tf.offset_se_mm.map(|s| s * 1e3),
            positions_um: tf.positions_mm.iter().map(|p| p * 1e3).collect(),
            notes: tf.notes.clone(),
            angle: AngleReport::from(&tf.angle),
            consequences: cons.as_ref().map(ConsequencesReport::from),
        }),
        verdict: Some(verdict),
        detail: SignalDetail {
            fit: Some(fit),
            sample_rate_hz: table.sample_rate_hz,
            revolutions: revs,
            teeth,
            plot: Some(plot),
        },
    })
}
