//! The report of `identify RECORDING…` (`runout.identify.recording/3`) and its construction.

use super::fit::{
    fitted_radius_difference_um, model_waveforms, radius_difference_um, radius_difference_warnings,
};
use super::{ChainDecision, Consistency, Extra, FileResult, RecordingsRequest, Verdicts};
use crate::job::Report;
use runout_core::identify::{ChainFitReport, FullSignalFit, MeanForceCalibration, SineFit};
use runout_core::signal::{ForceComponent, ToothReference};
use runout_core::{FluteLead, RadiusProfile};
use runout_io::recording::Format;
use schemars::JsonSchema;
use serde::Serialize;
use serde_json::Value;

/// The cutter and options as reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RecordingsInputs {
    pub teeth: usize,
    pub diameter_mm: f64,
    pub helix_deg: f64,
    /// End profile: `{"kind": "flat" | "ball" | "bull_nose" | "tapered", …}`.
    #[schemars(with = "Value")]
    pub profile: RadiusProfile,
    /// `constant_lead` or `constant_helix`.
    #[schemars(with = "String")]
    pub flute_lead: FluteLead,
    pub nominal_rpm: Option<f64>,
    /// `fxy`, `fx`, `fy` or `fz`.
    pub peak_component: String,
    pub fit_tilt: bool,
    pub section_s: Option<(f64, f64)>,
}

/// The measured spindle speed.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SpindleReport {
    pub rpm: f64,
    pub rpm_se: f64,
    pub nominal_rpm: f64,
    pub deviation_percent: f64,
    pub method: String,
}

/// The section analysed (s).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SectionReport {
    pub from_s: f64,
    pub to_s: f64,
    /// True when given, false when detected.
    pub overridden: bool,
}

/// Mean forces over the averaged revolution (N).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct MeanForceN {
    pub fx: f64,
    pub fy: f64,
    pub fz: Option<f64>,
}

/// One tooth's peak of the averaged waveform.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Peak {
    pub tooth: usize,
    pub peak_N: f64,
    pub peak_N_se: f64,
    pub spindle_angle_deg: f64,
}

/// The seed-003 sine fit of a recording's per-tooth peaks (methods.md §4.2).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct SineFitReport {
    pub method: String,
    pub mean_N: f64,
    pub mean_N_se: Option<f64>,
    pub amplitude_N: f64,
    pub amplitude_N_se: Option<f64>,
    pub phase_deg: f64,
    pub phase_deg_se: Option<f64>,
    pub offset_um: f64,
    pub offset_um_se: Option<f64>,
    pub angle_deg: f64,
    pub angle_deg_se: Option<f64>,
    pub r_squared: f64,
}

/// A fit, or why it is not available.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Fitted<T> {
    /// The fit.
    Fit(T),
    /// Why not.
    Failed {
        /// The reason.
        error: String,
    },
}

impl<T> Fitted<T> {
    /// The fit, if there is one.
    pub fn ok(&self) -> Option<&T> {
        match self {
            Self::Fit(t) => Some(t),
            Self::Failed { .. } => None,
        }
    }
}

/// What one recording gave.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RecordingReport {
    pub file: String,
    #[schemars(with = "Value")]
    pub format: Format,
    pub metadata: Vec<(String, String)>,
    pub sample_rate_hz: f64,
    pub samples: u64,
    pub axes: String,
    pub fz_mm: f64,
    pub ap_mm: f64,
    pub entry_deg: f64,
    pub exit_deg: f64,
    pub spindle: SpindleReport,
    pub section: SectionReport,
    pub revolutions_averaged: usize,
    pub offset_subtracted_N: Option<[f64; 3]>,
    /// `absolute` (pulse + tooth-0 angle) or `arbitrary`.
    #[schemars(with = "String")]
    pub tooth_reference: ToothReference,
    pub mean_force_N: MeanForceN,
    /// `Fxy`, `Fx`, `Fy` or `Fz`.
    pub peak_component: String,
    pub tooth_peaks: Vec<Peak>,
    pub sine_fit: Fitted<SineFitReport>,
    pub radius_difference_um: Option<f64>,
    pub radius_difference_um_se: Option<f64>,
    pub warnings: Vec<String>,
}

/// The mean-force calibration (methods.md §4.4), or why it was skipped.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Calibration {
    /// Coefficients with the per-component regressions.
    Fitted(#[schemars(with = "Value")] Box<MeanForceCalibration>),
    /// Why not.
    Skipped {
        /// The reason.
        skipped: String,
    },
}

/// The six coefficients of the full-signal fit (N/mm², N/mm) with their standard errors.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Coefficients {
    pub ktc_N_per_mm2: f64,
    pub ktc_N_per_mm2_se: Option<f64>,
    pub krc_N_per_mm2: f64,
    pub krc_N_per_mm2_se: Option<f64>,
    pub kac_N_per_mm2: f64,
    pub kac_N_per_mm2_se: Option<f64>,
    pub kte_N_per_mm: f64,
    pub kte_N_per_mm_se: Option<f64>,
    pub kre_N_per_mm: f64,
    pub kre_N_per_mm_se: Option<f64>,
    pub kae_N_per_mm: f64,
    pub kae_N_per_mm_se: Option<f64>,
}

impl Coefficients {
    /// (value, SE) in the order K_tc, K_rc, K_ac, K_te, K_re, K_ae.
    pub fn all(&self) -> [(f64, Option<f64>); 6] {
        [
            (self.ktc_N_per_mm2, self.ktc_N_per_mm2_se),
            (self.krc_N_per_mm2, self.krc_N_per_mm2_se),
            (self.kac_N_per_mm2, self.kac_N_per_mm2_se),
            (self.kte_N_per_mm, self.kte_N_per_mm_se),
            (self.kre_N_per_mm, self.kre_N_per_mm_se),
            (self.kae_N_per_mm, self.kae_N_per_mm_se),
        ]
    }
}

/// The full-signal fit of all recordings jointly (methods.md §4.5).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct FullSignalReport {
    pub method: String,
    pub offset_um: f64,
    pub offset_um_se: Option<f64>,
    pub angle_deg: f64,
    pub angle_deg_se: Option<f64>,
    pub tilt_um_per_mm: Option<[f64; 2]>,
    pub tilt_um_per_mm_se: Option<[Option<f64>; 2]>,
    /// `"full"`, or `{"along_direction": {"direction": [x, y]}}`.
    #[schemars(with = "Value")]
    pub observability: runout_core::identify::RunoutObservability,
    pub coefficients: Coefficients,
    pub parameters: Vec<String>,
    pub correlation: Vec<Vec<f64>>,
    pub residual_rms_N: f64,
    pub r_squared: f64,
    pub condition: f64,
    pub ill_conditioned: bool,
    pub disks: usize,
    pub start_angle_deg: Vec<f64>,
    pub warnings: Vec<String>,
}

/// The full-signal fit or why it failed.
pub type FullSignal = Fitted<FullSignalReport>;

/// The measuring chain: the decision and the fitted (or given) chain.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct MeasuringChainReport {
    pub decision: ChainDecision,
    #[schemars(with = "Option<Value>")]
    pub fit: Option<ChainFitReport>,
}

/// A recording whose tooth numbering was shifted to agree with the others.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Renumbered {
    /// Index of the recording.
    pub recording: usize,
    pub shifted_by_teeth: usize,
}

/// The averaged waveform of one recording and the fitted model as the sensor records it (for
/// plots; not serialised).
#[derive(Debug, Clone, Default)]
pub struct WaveformPlot {
    /// Spindle angle of each bin (deg).
    pub angle_deg: Vec<f64>,
    /// Measured F_x, F_y, F_z (N); F_z only when recorded (`components` = 3).
    pub measured_N: [Vec<f64>; 3],
    /// The model (N), when the full-signal fit succeeded.
    pub predicted_N: Option<[Vec<f64>; 3]>,
    /// 2 (x, y) or 3 (with z).
    pub components: usize,
}

/// `runout.identify.recording/3`: runout and cutting coefficients from force recordings.
/// (`/2` added `answer`, the one result to use, first.)
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RecordingsReport {
    /// `runout.identify.recording/3`
    #[schemars(extend("const" = "runout.identify.recording/3"))]
    pub schema: String,
    /// The one answer: runout ρ ± SE, λ ± SE, the method, the status (`identified` /
    /// `partly identified` / `not identified`) with the reasons, the coefficients each with its
    /// status, the plausibility warnings and the sine fits as cross-checks.
    pub answer: super::answer::Answer,
    pub conventions: String,
    pub inputs: RecordingsInputs,
    pub recordings: Vec<RecordingReport>,
    pub mean_force_calibration: Calibration,
    pub full_signal: FullSignal,
    pub measuring_chain: MeasuringChainReport,
    pub tooth_numbering_aligned: Vec<Renumbered>,
    pub consistency: Option<Consistency>,
    pub status: Verdicts,
    pub fitted_radius_difference_um: Option<f64>,
    pub radius_difference_warnings: Vec<String>,
    /// Pass/fail of the full-signal runout against the tolerance and its consequences for the
    /// cut at the largest f_z of the recordings (issue 15).
    pub verdict: Option<crate::verdict::VerdictReport>,
    /// Per recording, the waveforms for plots.
    #[serde(skip)]
    #[schemars(skip)]
    pub waveforms: Vec<WaveformPlot>,
}

impl Report for RecordingsReport {
    const SCHEMA: &'static str = "runout.identify.recording/3";
}

const DEG: f64 = 57.29577951308232; // 1f64.to_degrees()

fn est(v: f64, se: Option<f64>, scale: f64) -> (f64, Option<f64>) {
    (v * scale, se.map(|s| s * scale))
}

fn sine_report(s: &Result<SineFit, String>) -> Fitted<SineFitReport> {
    let f = match s {
        Err(e) => return Fitted::Failed { error: e.clone() },
        Ok(f) => f,
    };
    let (mean_N, mean_N_se) = est(f.mean.value, f.mean.se, 1.0);
    let (amplitude_N, amplitude_N_se) = est(f.amplitude.value, f.amplitude.se, 1.0);
    let (phase_deg, phase_deg_se) = est(f.phase.value, f.phase.se, DEG);
    let (offset_um, offset_um_se) = est(f.offset.value, f.offset.se, 1e3);
    let (angle_deg, angle_deg_se) = est(f.angle.value, f.angle.se, DEG);
    Fitted::Fit(SineFitReport {
        method: "seed 003 sine fit of per-tooth peaks (docs/methods.md §4.2)".into(),
        mean_N,
        mean_N_se,
        amplitude_N,
        amplitude_N_se,
        phase_deg,
        phase_deg_se,
        offset_um,
        offset_um_se,
        angle_deg,
        angle_deg_se,
        r_squared: f.r_squared,
    })
}

fn fit_report(fit: &Result<FullSignalFit, String>, files: &[FileResult]) -> FullSignal {
    let f = match fit {
        Err(e) => return Fitted::Failed { error: e.clone() },
        Ok(f) => f,
    };
    let c = |i: usize| f.coefficients[i];
    let s = |i: usize| f.coefficient_se[i];
    let (offset_um, offset_um_se) = est(f.offset.value, f.offset.se, 1e3);
    let (angle_deg, angle_deg_se) = est(f.angle.value, f.angle.se, DEG);
    Fitted::Fit(FullSignalReport {
        method: "full-signal non-linear least squares of the averaged waveforms (all recordings jointly)".into(),
        offset_um,
        offset_um_se,
        angle_deg,
        angle_deg_se,
        tilt_um_per_mm: f.tilt.map(|t| [t[0].value * 1e3, t[1].value * 1e3]),
        tilt_um_per_mm_se: f.tilt.map(|t| [t[0].se.map(|s| s * 1e3), t[1].se.map(|s| s * 1e3)]),
        observability: f.observability,
        coefficients: Coefficients {
            ktc_N_per_mm2: c(0),
            ktc_N_per_mm2_se: s(0),
            krc_N_per_mm2: c(1),
            krc_N_per_mm2_se: s(1),
            kac_N_per_mm2: c(2),
            kac_N_per_mm2_se: s(2),
            kte_N_per_mm: c(3),
            kte_N_per_mm_se: s(3),
            kre_N_per_mm: c(4),
            kre_N_per_mm_se: s(4),
            kae_N_per_mm: c(5),
            kae_N_per_mm_se: s(5),
        },
        parameters: f.parameters.clone(),
        correlation: f.correlation.clone(),
        residual_rms_N: f.residual_rms_n,
        r_squared: f.r_squared,
        condition: f.condition,
        ill_conditioned: f.ill_conditioned,
        disks: f.disks,
        start_angle_deg: files.iter().map(|x| x.start_angle.to_degrees()).collect(),
        warnings: f.warnings.clone(),
    })
}

fn recording_report(req: &RecordingsRequest, f: &FileResult) -> RecordingReport {
    let a = &f.analysis;
    let (st, ex) = f.cut.immersion(&req.cutter);
    let rd = radius_difference_um(&req.cutter, f);
    RecordingReport {
        file: f.name.clone(),
        format: f.info.format.clone(),
        metadata: f.info.metadata.clone(),
        sample_rate_hz: f.info.sample_rate_hz,
        samples: a.scan.samples,
        axes: f.axes.clone(),
        fz_mm: f.cut.fz(),
        ap_mm: f.cut.ap(),
        entry_deg: st.to_degrees(),
        exit_deg: ex.to_degrees(),
        spindle: SpindleReport {
            rpm: a.speed.rpm,
            rpm_se: a.speed.rpm_se,
            nominal_rpm: a.speed.nominal_rpm,
            deviation_percent: 100.0 * a.speed.deviation,
            method: crate::words::snake(&a.speed.method),
        },
        section: SectionReport {
            from_s: a.scan.section.from_s,
            to_s: a.scan.section.to_s,
            overridden: a.scan.section.overridden,
        },
        revolutions_averaged: a.average.revolutions,
        offset_subtracted_N: a.average.offset_subtracted,
        tooth_reference: a.average.tooth_reference,
        mean_force_N: MeanForceN {
            fx: f.mean_force[0],
            fy: f.mean_force[1],
            fz: f.mean_force[2].is_finite().then_some(f.mean_force[2]),
        },
        peak_component: crate::words::snake(&a.average.peak_component),
        tooth_peaks: a
            .average
            .tooth_peaks
            .iter()
            .map(|p| Peak {
                tooth: p.tooth,
                peak_N: p.peak,
                peak_N_se: p.se,
                spindle_angle_deg: p.angle.to_degrees(),
            })
            .collect(),
        sine_fit: sine_report(&f.sine),
        radius_difference_um: rd.map(|d| d.0),
        radius_difference_um_se: rd.and_then(|d| d.1),
        warnings: a
            .warnings
            .iter()
            .chain(&f.reader_warnings)
            .cloned()
            .collect(),
    }
}

fn inputs(req: &RecordingsRequest, files: &[FileResult]) -> RecordingsInputs {
    let c = &req.cutter;
    RecordingsInputs {
        teeth: c.teeth(),
        diameter_mm: c.diameter(),
        helix_deg: c.helix().to_degrees(),
        profile: c.profile().clone(),
        flute_lead: c.lead(),
        nominal_rpm: files.first().map(|f| f.cut.rpm()),
        peak_component: req.peak_component_name().into(),
        fit_tilt: req.fit_tilt,
        section_s: req.section_s,
    }
}

/// The averaged waveforms and the model for the plots.
fn waveform(
    req: &RecordingsRequest,
    f: &FileResult,
    fit: &Result<FullSignalFit, String>,
    extra: &Extra,
) -> WaveformPlot {
    let avg = &f.analysis.average;
    let tau = std::f64::consts::TAU;
    WaveformPlot {
        angle_deg: (0..avg.bins)
            .map(|j| (f.start_angle + tau * j as f64 / avg.bins as f64).to_degrees())
            .collect(),
        measured_N: [ForceComponent::Fx, ForceComponent::Fy, ForceComponent::Fz]
            .map(|c| avg.component(c).mean.clone()),
        predicted_N: fit
            .as_ref()
            .ok()
            .map(|fit| model_waveforms(req, f, fit, extra)),
        components: if avg.has_fz { 3 } else { 2 },
    }
}

/// The report of the job.
pub(super) fn build(
    req: &RecordingsRequest,
    files: &[FileResult],
    cal: &Result<MeanForceCalibration, String>,
    fit: &Result<FullSignalFit, String>,
    extra: &Extra,
) -> RecordingsReport {
    let c = &req.cutter;
    let full_signal = fit_report(fit, files);
    let recordings: Vec<RecordingReport> = files.iter().map(|f| recording_report(req, f)).collect();
    let answer = super::answer::build(
        req,
        files,
        &full_signal,
        &extra.verdicts,
        &recordings,
        &extra.decision.used,
    );
    let mut report = RecordingsReport {
        schema: RecordingsReport::SCHEMA.into(),
        answer,
        conventions: "angles from tooth 0 in the direction of rotation; forces on the workpiece; tooth 0 is absolute only with a pulse channel and tooth0_angle_deg, otherwise the first tooth period of the average".into(),
        inputs: inputs(req, files),
        recordings,
        mean_force_calibration: match cal {
            Err(e) => Calibration::Skipped { skipped: e.clone() },
            Ok(k) => Calibration::Fitted(Box::new(k.clone())),
        },
        full_signal,
        measuring_chain: MeasuringChainReport {
            decision: extra.decision.clone(),
            fit: fit.as_ref().ok().and_then(|f| f.chain.clone()),
        },
        tooth_numbering_aligned: extra
            .renumbered
            .iter()
            .map(|&(recording, shifted_by_teeth)| Renumbered {
                recording,
                shifted_by_teeth,
            })
            .collect(),
        consistency: extra.consistency.clone(),
        status: extra.verdicts.clone(),
        fitted_radius_difference_um: fit
            .as_ref()
            .ok()
            .and_then(|f| fitted_radius_difference_um(c, f)),
        radius_difference_warnings: fit
            .as_ref()
            .map(|f| radius_difference_warnings(c, files, f))
            .unwrap_or_default(),
        verdict: None,
        waveforms: files.iter().map(|f| waveform(req, f, fit, extra)).collect(),
    };
    match verdict_of(&report) {
        Ok(v) => report.verdict = v,
        // a verdict that cannot be formed is said, not silently dropped
        Err(e) => report.answer.warnings.push(format!("no verdict: {e:#}")),
    }
    report
}

/// The verdict on the full-signal runout (issue 15), at the tip, for the cutter of the inputs
/// (flat with its helix; a profiled cutter is judged by its nominal diameter) and the largest
/// f_z of the recordings; none without a full-signal fit.
fn verdict_of(r: &RecordingsReport) -> anyhow::Result<Option<crate::verdict::VerdictReport>> {
    let Some(f) = r.full_signal.ok() else {
        return Ok(None);
    };
    let fz = r
        .recordings
        .iter()
        .map(|x| x.fz_mm)
        .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))));
    crate::verdict::VerdictReport::new(
        crate::verdict::VerdictBasis {
            offset_um: f.offset_um,
            offset_um_se: f.offset_um_se,
            angle_deg: Some(f.angle_deg),
            teeth: Some(r.inputs.teeth),
            diameter_mm: Some(r.inputs.diameter_mm),
            helix_deg: r.inputs.helix_deg,
            height_mm: 0.0,
            fz_mm: fz,
        },
        None,
    )
    .map(Some)
}
