//! `identify peaks`: the seed-003 sine fit of one set of per-tooth peak forces
//! (methods.md §4.2, eq. 10–12).

use crate::job::Report;
use anyhow::{anyhow, Result};
use runout_core::identify::{
    sine_fit, ErrorSource, PeakConditions, SineFit, SineHypothesis, ToothPeaks,
};
use runout_core::{Cut, Cutter, MillingMode};
use schemars::JsonSchema;
use serde::Serialize;

/// One set of per-tooth peaks and the cut they were measured in.
#[derive(Debug, Clone, PartialEq)]
pub struct PeaksRequest {
    /// Per-tooth peak forces (N), teeth in cutting order (K = their number).
    pub peaks_N: Vec<f64>,
    /// Per-tooth standard errors of the peaks (N), e.g. revolution scatter/√M.
    pub peaks_se_N: Option<Vec<f64>>,
    /// Feed per tooth f_z (mm).
    pub fz_mm: f64,
    /// Milling mode (the seed's tests: up).
    pub mode: MillingMode,
    /// Radial depth a_e (mm); needed for the peak angle unless slotting or given.
    pub ae_mm: Option<f64>,
    /// Cutter diameter D (mm); needed for the peak angle unless slotting or given.
    pub diameter_mm: Option<f64>,
    /// Immersion angle γ of the peaks (deg); default: the angle of the largest chip.
    pub peak_immersion_deg: Option<f64>,
    /// K peaks once each, or K + 1 points with the period closed (the seed's Table 2, §4.3).
    pub hypothesis: SineHypothesis,
}

impl PeaksRequest {
    /// Peaks at feed `fz_mm`, up-milling, K peaks once each; set the other fields as needed.
    pub fn new(peaks_N: Vec<f64>, fz_mm: f64) -> Self {
        Self {
            peaks_N,
            peaks_se_N: None,
            fz_mm,
            mode: MillingMode::Up,
            ae_mm: None,
            diameter_mm: None,
            peak_immersion_deg: None,
            hypothesis: SineHypothesis::Teeth,
        }
    }
}

/// The inputs of `identify peaks` as reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PeaksInputs {
    pub teeth: usize,
    pub fz_mm: f64,
    pub ae_mm: Option<f64>,
    pub diameter_mm: Option<f64>,
    /// `up`, `down` or `slot`.
    #[schemars(with = "String")]
    pub mode: MillingMode,
    pub peak_immersion_deg: f64,
    pub peaks_N: Vec<f64>,
    /// Standard errors of the peaks (N).
    #[serde(rename = "peaks_N_se", alias = "peaks_se_N")]
    pub peaks_se_N: Option<Vec<f64>>,
}

/// A sine fit F_i = C + A sin(φ + 2πi/K) of per-tooth peaks (§4.2) with its inputs `I`;
/// angles in degrees from tooth 0 in the direction of rotation, offset in µm.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PeakFitReport<I> {
    /// `teeth` (K peaks) or `closed_period` (K + 1 points).
    #[schemars(with = "String")]
    pub hypothesis: SineHypothesis,
    pub inputs: I,
    pub mean_N: f64,
    pub mean_N_se: Option<f64>,
    pub amplitude_N: f64,
    pub amplitude_N_se: Option<f64>,
    pub phase_deg: f64,
    pub phase_deg_se: Option<f64>,
    pub r_squared: f64,
    pub offset_um: f64,
    pub offset_um_se: Option<f64>,
    pub angle_deg: f64,
    pub angle_deg_se: Option<f64>,
    pub residual_dof: usize,
    pub residual_rms_N: f64,
    pub fitted_N: Vec<f64>,
}

impl<I> PeakFitReport<I> {
    /// The report of `fit` with its `inputs`.
    pub fn new(fit: &SineFit, inputs: I) -> Self {
        let deg = |v: Option<f64>| v.map(f64::to_degrees);
        Self {
            hypothesis: fit.hypothesis,
            inputs,
            mean_N: fit.mean.value,
            mean_N_se: fit.mean.se,
            amplitude_N: fit.amplitude.value,
            amplitude_N_se: fit.amplitude.se,
            phase_deg: fit.phase.value.to_degrees(),
            phase_deg_se: deg(fit.phase.se),
            r_squared: fit.r_squared,
            offset_um: fit.offset.value * 1e3,
            offset_um_se: fit.offset.se.map(|x| x * 1e3),
            angle_deg: fit.angle.value.to_degrees(),
            angle_deg_se: deg(fit.angle.se),
            residual_dof: fit.dof,
            residual_rms_N: fit.residual_rms,
            fitted_N: fit.fitted.clone(),
        }
    }
}

/// Where the standard errors of a sine fit come from, in words.
pub(super) fn error_source_text(e: ErrorSource) -> &'static str {
    match e {
        ErrorSource::PerToothSe => {
            "from the given per-tooth standard errors; A, phi, offset, angle by the delta method"
        }
        ErrorSource::Residuals => {
            "from the residuals, sigma^2 = RSS/(K-3); A, phi, offset, angle by the delta method"
        }
        ErrorSource::Unavailable => {
            "not available: no residual degrees of freedom (K = 3) and no per-tooth standard errors"
        }
    }
}

/// `runout.identify.peaks/2`: the sine fit of one set of per-tooth peaks.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PeaksReport {
    /// `runout.identify.peaks/2`
    #[schemars(extend("const" = "runout.identify.peaks/2"))]
    pub schema: String,
    pub method: String,
    #[serde(flatten)]
    pub fit: PeakFitReport<PeaksInputs>,
    /// Where the standard errors come from, in words.
    pub standard_errors: String,
    pub warnings: Vec<String>,
}

impl Report for PeaksReport {
    const SCHEMA: &'static str = "runout.identify.peaks/2";
}

/// Peak immersion γ (rad): `explicit_deg` if given, π/2 in a slot, else the angle of the
/// largest chip of the engagement (methods.md §4.2).
pub fn peak_angle(
    mode: MillingMode,
    ae_mm: Option<f64>,
    diameter_mm: Option<f64>,
    explicit_deg: Option<f64>,
    fz_mm: f64,
    teeth: usize,
) -> Result<f64> {
    if let Some(g) = explicit_deg {
        return Ok(g.to_radians());
    }
    if mode == MillingMode::Slot {
        return Ok(std::f64::consts::FRAC_PI_2);
    }
    let d = diameter_mm.ok_or_else(|| {
        anyhow!("--diameter-mm is needed to find the peak angle in {} milling (or give --peak-immersion-deg)", crate::words::plain(&mode))
    })?;
    let ae = ae_mm.ok_or_else(|| {
        anyhow!(
            "--ae-mm is needed to find the peak angle in {} milling (or give --peak-immersion-deg)",
            crate::words::plain(&mode)
        )
    })?;
    let cutter = Cutter::flat(d, teeth.max(1), 0.0)?;
    let cut = Cut::new(1000.0, fz_mm, 1.0)?.radial(ae, mode, &cutter)?;
    Ok(runout_core::identify::peak_immersion(&cutter, &cut))
}

/// The sine fit of the request's peaks (§4.2).
pub fn peaks(req: &PeaksRequest) -> Result<PeaksReport> {
    let k = req.peaks_N.len();
    let gamma = peak_angle(
        req.mode,
        req.ae_mm,
        req.diameter_mm,
        req.peak_immersion_deg,
        req.fz_mm,
        k,
    )?;
    let mut tooth_peaks = ToothPeaks::new(req.peaks_N.clone())?;
    if let Some(se) = &req.peaks_se_N {
        tooth_peaks = tooth_peaks.with_se(se.clone())?;
    }
    let cond = PeakConditions::new(req.fz_mm, gamma)?;
    let fit = sine_fit(&tooth_peaks, &cond, req.hypothesis)?;
    let inputs = PeaksInputs {
        teeth: k,
        fz_mm: req.fz_mm,
        ae_mm: req.ae_mm,
        diameter_mm: req.diameter_mm,
        mode: req.mode,
        peak_immersion_deg: gamma.to_degrees(),
        peaks_N: req.peaks_N.clone(),
        peaks_se_N: tooth_peaks.se().map(<[f64]>::to_vec),
    };
    Ok(PeaksReport {
        schema: PeaksReport::SCHEMA.into(),
        method:
            "seed003 per-tooth peak sine fit F_i = C + A sin(phi + 2 pi i/K) (docs/methods.md §4.2)"
                .into(),
        fit: PeakFitReport::new(&fit, inputs),
        standard_errors: error_source_text(fit.error_source).into(),
        warnings: fit.warnings.clone(),
    })
}
