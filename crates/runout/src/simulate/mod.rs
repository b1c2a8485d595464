//! `simulate`: mechanistic milling forces with runout (methods.md §0, §4.1), optionally written
//! as an instrument recording seen through a simulated sensor ([`sensor`]) with air cut and
//! noise ([`recording`]): a test or example input for `identify`.

#![allow(non_snake_case)] // field names carry their units as the JSON does (`mean_fx_N`)

pub mod recording;
pub mod render;
pub mod sensor;

pub use recording::{RecordingDetail, RecordingOptions};
pub use sensor::{SensorChain, SensorReport, SensorRequest, OVERSAMPLE};

use crate::job::{Report, Source};
use anyhow::{bail, Result};
use runout_core::chip::EquivalentParams;
use runout_core::{
    tooth_peaks, ArcChip, EquivalentChip, ExactChip, ForceModel, ForceSeries, RadiusProfile,
    Sampling, ToothPeak,
};
use runout_io::config::simulate::{
    resolve_simulate, simulate_key_names, ForceChipModel, SimulateCase,
};
use runout_io::config::Layer;
use schemars::JsonSchema;
use serde::Serialize;
use std::path::PathBuf;

/// `runout simulate`: a resolved case, and how (if at all) it is written as a recording.
#[derive(Debug, Clone)]
pub struct SimulateRequest {
    /// Cutter, runout, cut, coefficients, sampling and chip model (core types).
    pub case: SimulateCase,
    /// Sample rate of the recording (Hz): sets the angular step to 360·rpm/(60·rate)
    /// (÷ [`OVERSAMPLE`] with a sensor).
    pub sample_rate_hz: Option<f64>,
    /// Write the cut as a recording (needs `sample_rate_hz`).
    pub recording: Option<RecordingOptions>,
    /// The sensor between the cut and the recording (needs `recording`); `None` = rigid.
    pub sensor: Option<SensorRequest>,
    /// The files the request was read from (case file): what an output must not overwrite.
    pub inputs: Vec<PathBuf>,
}

impl SimulateRequest {
    /// A resolved case, simulated without a recording.
    pub fn new(case: SimulateCase) -> Self {
        Self {
            case,
            sample_rate_hz: None,
            recording: None,
            sensor: None,
            inputs: Vec::new(),
        }
    }

    /// The case of an optional TOML case file (keys of [`simulate_key_names`]) overlaid by
    /// `overrides` (e.g. [`crate::case::value_layer`]`([("runout_um", "8um")])`).
    pub fn from_config(config: Option<&Source>, overrides: Layer) -> Result<Self> {
        let s = crate::case::settings(config, overrides, &simulate_key_names())?;
        let mut r = Self::new(resolve_simulate(&s)?);
        r.inputs = config
            .and_then(Source::as_path)
            .map(|p| p.to_path_buf())
            .into_iter()
            .collect();
        Ok(r)
    }
}

/// The end profile as reported (`{"kind": "flat"}`, `{"kind": "ball"}`, …).
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ProfileReport {
    Flat,
    Ball,
    BullNose { corner_mm: f64 },
    Tapered { taper_deg: f64 },
}

impl From<&RadiusProfile> for ProfileReport {
    fn from(p: &RadiusProfile) -> Self {
        match *p {
            RadiusProfile::Flat => Self::Flat,
            RadiusProfile::Ball => Self::Ball,
            RadiusProfile::BullNose { corner_mm } => Self::BullNose { corner_mm },
            RadiusProfile::Tapered { taper_deg } => Self::Tapered { taper_deg },
        }
    }
}

/// The flute winding as reported.
#[derive(Debug, Clone, Copy, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FluteLeadReport {
    ConstantLead,
    ConstantHelix,
}

/// The case as simulated, units in the names.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SimulateInputs {
    pub teeth: usize,
    pub diameter_mm: f64,
    pub helix_deg: f64,
    pub profile: ProfileReport,
    pub flute_lead: FluteLeadReport,
    pub pitch_deg: Vec<f64>,
    pub rpm: f64,
    pub fz_mm: f64,
    pub ap_mm: f64,
    pub entry_deg: f64,
    pub exit_deg: f64,
    pub runout_um: f64,
    pub runout_angle_deg: f64,
    /// Tilt vector (µm per mm of height), spindle frame.
    pub tilt_um_per_mm: [f64; 2],
    pub ktc_N_per_mm2: f64,
    pub krc_N_per_mm2: f64,
    pub kac_N_per_mm2: f64,
    pub kte_N_per_mm: f64,
    pub kre_N_per_mm: f64,
    pub kae_N_per_mm: f64,
    pub revolutions: f64,
    pub step_deg: f64,
    pub disks: usize,
    /// `arc`, `exact` or `equivalent`.
    pub chip_model: String,
}

/// Peak |F_xy| of one tooth.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ToothPeakReport {
    pub tooth: usize,
    pub peak_fxy_N: f64,
    pub spindle_angle_deg: f64,
    pub immersion_deg: f64,
    pub max_chip_mm: f64,
    /// Peak of the tooth's own contribution (N).
    pub own_peak_fxy_N: f64,
}

/// `runout.simulate/1`: the inputs, tooth radii, mean forces and per-tooth peaks.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SimulateReport {
    /// `runout.simulate/1`
    #[schemars(extend("const" = "runout.simulate/1"))]
    pub schema: String,
    pub inputs: SimulateInputs,
    /// Radius of each tooth's tip with the runout (mm).
    pub tooth_radii_mm: Vec<f64>,
    pub mean_fx_N: f64,
    pub mean_fy_N: f64,
    pub mean_fz_N: f64,
    pub mean_torque_Nm: f64,
    pub tooth_peaks: Vec<ToothPeakReport>,
    /// Samples of the simulated series.
    pub samples: usize,
    /// The simulated sensor of the recording (absent for a rigid one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor: Option<SensorReport>,
    /// The series behind the CSV, the plot and the recording; not part of the JSON.
    #[serde(skip)]
    #[schemars(skip)]
    pub detail: SimulateDetail,
}

impl Report for SimulateReport {
    const SCHEMA: &'static str = "runout.simulate/1";
}

/// The simulated series and what is derived from it.
#[derive(Debug, Clone, Default)]
pub struct SimulateDetail {
    /// Forces, torque and chip thickness per sample.
    pub series: ForceSeries,
    /// Per-tooth peaks (angles in rad).
    pub peaks: Vec<ToothPeak>,
    /// The recording's channels, when one was requested.
    pub recording: Option<RecordingDetail>,
}

/// Run the simulation with the case's chip-thickness model.
fn simulate_series(case: &SimulateCase) -> Result<ForceSeries> {
    let model = ForceModel {
        cutter: case.cutter.clone(),
        runout: case.runout,
        cut: case.cut,
        coefficients: case.coefficients,
    };
    let (c, r, fz) = (&case.cutter, &case.runout, case.cut.fz());
    Ok(match case.chip_model {
        ForceChipModel::Exact => model.simulate(&ExactChip::new(c, r, fz)?, &case.sampling),
        ForceChipModel::Equivalent => model.simulate(
            &EquivalentChip::new(c, r, fz, EquivalentParams::default())?,
            &case.sampling,
        ),
        ForceChipModel::Arc => model.simulate(&ArcChip::new(c, r, fz)?, &case.sampling),
    })
}

/// Simulate the case; with `sample_rate_hz` the step follows the rate, with `recording` the
/// cut is also written as channels through the sensor with air cut and noise.
pub fn simulate(req: &SimulateRequest) -> Result<SimulateReport> {
    let mut case = req.case.clone();
    let sensor = req.sensor.as_ref().map(sensor::chain).transpose()?;
    if sensor.is_some() && req.recording.is_none() {
        bail!("--sensor-mode-hz / --sensor-frf: a sensor chain applies to the recording; give --recording FILE and --sample-rate-hz");
    }
    // with a sensor, the cut is simulated finer than the recording (see `sensor`)
    let oversample = if sensor.is_some() { OVERSAMPLE } else { 1 };
    if let Some(fs) = req.sample_rate_hz {
        if fs.is_nan() || fs <= 0.0 {
            bail!(
                "--sample-rate-hz: expected a sample rate > 0 Hz, got {}",
                runout_core::limits::show(fs)
            );
        }
        let step_deg = 360.0 * case.cut.rpm() / 60.0 / fs / oversample as f64;
        case.sampling = Sampling::new(case.sampling.revolutions, step_deg, case.sampling.disks)
            .map_err(|e| {
                anyhow::anyhow!("--sample-rate-hz {}: {e}", runout_core::limits::show(fs))
            })?;
        case.check_work()?;
    }
    let series = simulate_series(&case)?;
    let peaks = tooth_peaks(&series, &case.cutter, &case.cut);
    let recording = match &req.recording {
        None => None,
        Some(o) => {
            let fs = req
                .sample_rate_hz
                .ok_or_else(|| anyhow::anyhow!("--recording needs --sample-rate-hz"))?;
            Some(recording::channels(fs, &series, o, sensor.as_ref())?)
        }
    };
    Ok(report(&case, series, peaks, recording, sensor))
}

fn report(
    case: &SimulateCase,
    series: ForceSeries,
    peaks: Vec<ToothPeak>,
    recording: Option<RecordingDetail>,
    sensor: Option<SensorChain>,
) -> SimulateReport {
    let c = &case.cutter;
    let cut = &case.cut;
    let (st, ex) = cut.immersion(c);
    let k = &case.coefficients;
    let m = series.means();
    let tilt = case.runout.tilt();
    let inputs = SimulateInputs {
        teeth: c.teeth(),
        diameter_mm: c.diameter(),
        helix_deg: c.helix().to_degrees(),
        profile: c.profile().into(),
        flute_lead: match c.lead() {
            runout_core::FluteLead::ConstantLead => FluteLeadReport::ConstantLead,
            runout_core::FluteLead::ConstantHelix => FluteLeadReport::ConstantHelix,
        },
        pitch_deg: c.pitch().iter().map(|p| p.to_degrees()).collect(),
        rpm: cut.rpm(),
        fz_mm: cut.fz(),
        ap_mm: cut.ap(),
        entry_deg: st.to_degrees(),
        exit_deg: ex.to_degrees(),
        runout_um: case.runout.offset_um(),
        runout_angle_deg: case.runout.angle().to_degrees(),
        tilt_um_per_mm: [tilt[0] * 1e3, tilt[1] * 1e3],
        ktc_N_per_mm2: k.ktc,
        krc_N_per_mm2: k.krc,
        kac_N_per_mm2: k.kac,
        kte_N_per_mm: k.kte,
        kre_N_per_mm: k.kre,
        kae_N_per_mm: k.kae,
        revolutions: case.sampling.revolutions,
        step_deg: case.sampling.step.to_degrees(),
        disks: case.sampling.disks,
        chip_model: case.chip_model.name().into(),
    };
    SimulateReport {
        schema: SimulateReport::SCHEMA.into(),
        inputs,
        tooth_radii_mm: case.runout.tooth_radii(c, 0.0),
        mean_fx_N: m[0],
        mean_fy_N: m[1],
        mean_fz_N: m[2],
        mean_torque_Nm: m[3],
        tooth_peaks: peaks
            .iter()
            .map(|p| ToothPeakReport {
                tooth: p.tooth,
                peak_fxy_N: p.peak_fxy,
                spindle_angle_deg: p.angle.to_degrees(),
                immersion_deg: p.immersion.to_degrees(),
                max_chip_mm: p.max_chip,
                own_peak_fxy_N: p.own_peak_fxy,
            })
            .collect(),
        samples: series.len(),
        sensor: sensor.map(|s| s.report),
        detail: SimulateDetail {
            series,
            peaks,
            recording,
        },
    }
}
