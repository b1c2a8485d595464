//! `shank calibrate`: static calibration of K_δ (and the holder term with several load points)
//! from a recording with a known load.

use super::config::{displacement_scale, load_config, open};
use crate::job::{Report, Source};
use anyhow::Result;
use runout_core::shank::{LoadPoint, LoadStep};
use runout_io::recording::{ReadOptions, RecordingChunk};
use schemars::JsonSchema;
use serde::Serialize;

/// Where the load point comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadPointFrom {
    /// A constant distance from the holder face (mm).
    Fixed(f64),
    /// A channel with the distance (mm) per sample.
    Channel(String),
}

/// `runout shank calibrate`: the recording (sensors of the first pair and a load cell), the
/// config, and where the load is.
#[derive(Debug, Clone)]
pub struct CalibrateRequest {
    pub recording: Source,
    pub config: Source,
    /// Load-cell channel (N), positive towards +axis of the pair.
    pub force_channel: String,
    pub load_point: LoadPointFrom,
    /// Sample rate (Hz) if the file has no time column.
    pub sample_rate_hz: Option<f64>,
}

/// `runout.shank.calibration/2`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[allow(non_snake_case)]
pub struct CalibrationReport {
    /// `runout.shank.calibration/2`
    #[schemars(extend("const" = "runout.shank.calibration/2"))]
    pub schema: String,
    /// The result first: K_δ ± SE, the status and its reasons, the beam formula as a
    /// cross-check (issue 21).
    pub answer: crate::answer::Answer,
    pub recording: String,
    pub steps: usize,
    pub stiffness_N_per_um: f64,
    pub stiffness_N_per_um_se: f64,
    pub at_load_point_mm: f64,
    pub beam_stiffness_N_per_um: f64,
    pub beam_scale: Option<f64>,
    pub beam_scale_se: Option<f64>,
    pub holder_stiffness_Nm_per_rad: Option<f64>,
    pub holder_compliance_rad_per_Nm: Option<f64>,
    pub holder_compliance_rad_per_Nm_se: Option<f64>,
    pub offset_um: f64,
    pub residual_rms_um: f64,
    pub r_squared: f64,
    pub condition_number: f64,
}

impl crate::answer::Answered for CalibrationReport {
    fn answer(&self) -> &crate::answer::Answer {
        &self.answer
    }
}

impl Report for CalibrationReport {
    const SCHEMA: &'static str = "runout.shank.calibration/2";
}

/// Fit K_δ (and the holder compliance) to the load steps of the recording.
pub fn calibrate(req: &CalibrateRequest) -> Result<CalibrationReport> {
    let r = load_config(&req.config, req.sample_rate_hz)?;
    let p = &r.cfg.pair[0];
    let mut names = vec![
        p.sensor_i.clone(),
        p.sensor_ii.clone(),
        req.force_channel.clone(),
    ];
    let fixed = match &req.load_point {
        LoadPointFrom::Fixed(a) => Some(*a),
        LoadPointFrom::Channel(c) => {
            names.push(c.clone());
            None
        }
    };
    let mut reader = match open(&req.recording, &r, &names) {
        Err(e) if e.to_string().contains("no sample rate") => {
            let mut o = ReadOptions::new().channels(&names);
            o.sample_rate_hz = Some(1.0);
            req.recording.open_recording(&o)?
        }
        other => other?,
    };
    let info = reader.info().clone();
    let s0 = displacement_scale(&info, 0, &r)?;
    let s1 = displacement_scale(&info, 1, &r)?;
    let sign = r.setup.pairs[0].sign;
    let mut steps = Vec::new();
    let mut chunk = RecordingChunk::default();
    while reader.read_chunk(&mut chunk, 65_536)? > 0 {
        for k in 0..chunk.len() {
            steps.push(LoadStep {
                force_n: chunk.values[2][k],
                load_point_mm: fixed
                    .unwrap_or_else(|| chunk.values.get(3).map_or(f64::NAN, |c| c[k])),
                delta_mm: sign * (chunk.values[1][k] * s1 - chunk.values[0][k] * s0),
            });
        }
    }
    let beam = if let Some(a0) = fixed {
        r.setup
            .beam
            .with_load_point(LoadPoint::At { distance_mm: a0 })?
    } else {
        r.setup.beam
    };
    let cal = runout_core::shank::calibrate(&beam, &steps)?;
    let (k, k_se) = (
        cal.stiffness_n_per_mm / 1e3,
        cal.stiffness_se_n_per_mm / 1e3,
    );
    let answer = {
        use crate::answer::{Answer, CrossCheck, Quantity};
        let reason = crate::answer::se_test(
            "stiffness K_δ",
            k,
            Some(k_se),
            "N/µm",
            "load in more steps over a wider force range",
        )
        .or_else(|| {
            (k <= 0.0).then(|| {
                format!(
                    "stiffness K_δ = {k:.4} N/µm is not positive: check the sign of the pair \
                     (sensor_I/sensor_II) and of the force channel"
                )
            })
        });
        let ok = reason.is_none();
        Answer {
            status: Answer::status_of(ok, true).into(),
            method: format!(
                "least squares of the load cell's force against the deflection difference \
                 δ_II − δ_I over {} samples (docs/methods.md §3.1)",
                cal.steps
            ),
            runout: None,
            results: vec![if ok {
                Quantity::identified("stiffness K_δ", "N/µm", k, Some(k_se))
            } else {
                Quantity::not_identified("stiffness K_δ", "N/µm")
            }],
            reasons: reason.into_iter().collect(),
            warnings: Vec::new(),
            cross_checks: vec![CrossCheck {
                estimate: "beam formula from the shank's diameter, modulus and lengths".into(),
                values: vec![Quantity::cross_check(
                    "stiffness K_δ",
                    "N/µm",
                    beam.stiffness_n_per_um(),
                    None,
                )],
                why_it_may_differ: "the formula assumes a rigid holder and the nominal modulus \
                                    and diameter; the holder's compliance and the flutes lower \
                                    the measured stiffness"
                    .into(),
            }],
        }
    };
    Ok(CalibrationReport {
        schema: CalibrationReport::SCHEMA.into(),
        answer,
        recording: info.file,
        steps: cal.steps,
        stiffness_N_per_um: cal.stiffness_n_per_mm / 1e3,
        stiffness_N_per_um_se: cal.stiffness_se_n_per_mm / 1e3,
        at_load_point_mm: beam.load_distance_mm(),
        beam_stiffness_N_per_um: beam.stiffness_n_per_um(),
        beam_scale: cal.beam_scale.map(|b| b.0),
        beam_scale_se: cal.beam_scale.map(|b| b.1),
        holder_stiffness_Nm_per_rad: cal.holder_compliance_rad_per_nmm.map(|c| 1.0 / c.0 / 1e3),
        holder_compliance_rad_per_Nm: cal.holder_compliance_rad_per_nmm.map(|c| c.0 * 1e3),
        holder_compliance_rad_per_Nm_se: cal.holder_compliance_rad_per_nmm.map(|c| c.1 * 1e3),
        offset_um: cal.offset_mm * 1e3,
        residual_rms_um: cal.residual_rms_mm * 1e3,
        r_squared: cal.r_squared,
        condition_number: cal.condition_number,
    })
}
