//! The measuring chain, tooth numbering across recordings, per-recording consistency and the
//! verdict per parameter for `identify RECORDING…` (issue 11 items 1, 3, 5; methods.md §4.7).

use super::fit::waveform_case;
use super::{ChainChoice, FileResult, RecordingsRequest};
use crate::job::Source;
use runout_core::angle::wrap_pi;
use runout_core::chain::{AxisChain, MeasuringChain, SensorMode};
use runout_core::identify::{
    full_signal_fit, residual_at, ChainModel, ChainOptions, FrameAxis as FitAxis, FullSignalFit,
    FullSignalOptions, RunoutObservability,
};
use runout_core::signal::ToothReference;
use schemars::JsonSchema;
use serde::Serialize;
use std::f64::consts::TAU;

/// For `auto` to use the fitted chain, the modes must change a tooth-passing harmonic inside the
/// band by at least this much (|H − 1|) ...
const AUTO_MIN_EFFECT: f64 = 0.02;
/// ... and explain the waveform significantly better than the rigid model: the F statistic
/// ((RSS_rigid − RSS_chain)/q)/(RSS_chain/(n − p)), q = 2 per mode, must exceed this. The
/// residuals of an averaged waveform are correlated, so the threshold is far above the nominal
/// 0.1 % point of F (≈ 7): a mode fitted to a rigid sensor's noise and model error reaches
/// neither condition in the round-trip tests.
const AUTO_MIN_F: f64 = 50.0;
/// ... and at least one fitted mode must be a resonance (ζ ≤ 0.3): a heavily damped "mode" that
/// improves the fit is absorbing model error (geometry), not describing the sensor (PHM 2010
/// ball-end slice fitted as a flat end mill: ζ 1.35 on y).
const AUTO_MAX_DAMPING: f64 = 0.3;

/// What was decided about the measuring chain, as reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ChainDecision {
    /// What the user asked for: auto | rigid | modes | frf | band.
    pub requested: String,
    /// What the reported fit used: rigid | fitted_modes | measured_frf | band_limit.
    pub used: String,
    /// Why, in words.
    pub reason: String,
    /// Largest |H(k·f_rev) − 1| of the fitted/given chain at a tooth-passing harmonic in the band.
    pub max_effect_at_tooth_harmonics: Option<f64>,
    /// R² of the chain fit and of the rigid model on the same band.
    pub band_r_squared: Option<f64>,
    pub band_rigid_r_squared: Option<f64>,
}

fn spindle_hz(f: &FileResult) -> f64 {
    f.analysis.speed.rpm / 60.0
}

fn axes_of(files: &[FileResult]) -> Vec<FitAxis> {
    let mut axes = vec![FitAxis::X, FitAxis::Y];
    if files.iter().all(|f| f.analysis.average.has_fz) {
        axes.push(FitAxis::Z);
    }
    axes
}

/// Options of a chain fit of `files` with `model`.
pub(super) fn chain_options(
    case: &RecordingsRequest,
    files: &[FileResult],
    model: ChainModel,
    initial: Option<[f64; 2]>,
    fixed: Option<[f64; 6]>,
    free_angles: bool,
) -> FullSignalOptions {
    FullSignalOptions {
        disks: None,
        fit_tilt: case.fit_tilt,
        initial_runout: initial,
        chain: Some(ChainOptions {
            model,
            spindle_hz: files.iter().map(spindle_hz).collect(),
            samples_per_rev: files
                .iter()
                .map(|f| Some(f.info.sample_rate_hz / spindle_hz(f)))
                .collect(),
            free_start_angle: files
                .iter()
                .map(|f| {
                    free_angles && f.analysis.average.tooth_reference != ToothReference::Absolute
                })
                .collect(),
        }),
        fixed_coefficients: fixed,
    }
}

/// The fitted-modes model with the user's start values (one, or per axis).
fn fitted_modes(case: &RecordingsRequest, files: &[FileResult]) -> ChainModel {
    let axes = axes_of(files);
    let start = |i: usize| {
        case.sensor_mode_hz.as_ref().map(|v| {
            let f = *v.get(i).unwrap_or(&v[0]);
            SensorMode {
                frequency_hz: f,
                damping: 0.03,
                gain: 1.0,
            }
        })
    };
    ChainModel::FitModes {
        axes: axes
            .iter()
            .enumerate()
            .map(|(i, &a)| (a, start(i)))
            .collect(),
        fit_gain: false,
    }
}

/// The chain a fit used, as a [`MeasuringChain`] (for the per-recording fits and plots).
pub(super) fn chain_of(fit: &FullSignalFit, given: Option<&MeasuringChain>) -> MeasuringChain {
    let mut chain = given.cloned().unwrap_or_default();
    if let Some(c) = &fit.chain {
        for m in &c.modes {
            let mode = SensorMode {
                frequency_hz: m.frequency_hz.value,
                damping: m.damping.value,
                gain: m.gain.value,
            };
            let slot = match m.axis {
                FitAxis::X => &mut chain.x,
                FitAxis::Y => &mut chain.y,
                FitAxis::Z => &mut chain.z,
            };
            *slot = AxisChain::Modes(vec![mode]);
        }
    }
    chain
}

/// Largest |H(k·f_rev) − 1| over the tooth-passing harmonics k = mK inside the fitted band.
fn effect_at_tooth_harmonics(
    chain: &MeasuringChain,
    fit: &FullSignalFit,
    files: &[FileResult],
    teeth: usize,
) -> f64 {
    let Some(c) = &fit.chain else { return 0.0 };
    let mut worst = 0.0f64;
    for (f, &kmax) in files.iter().zip(&c.max_harmonic) {
        for k in (teeth..=kmax).step_by(teeth) {
            for axis in [&chain.x, &chain.y, &chain.z] {
                let h = axis.response_clamped(k as f64 * spindle_hz(f));
                worst = worst.max((h - 1.0).norm());
            }
        }
    }
    worst
}

fn apply_angle_shifts(files: &mut [FileResult], fit: &FullSignalFit) {
    if let Some(c) = &fit.chain {
        for (f, d) in files.iter_mut().zip(&c.start_angle_shift) {
            f.start_angle += d.value;
        }
    }
}

/// Fit through the requested chain; `rigid` is today's time-domain fit of the same recordings.
/// Returns the fit to report and the decision.
type Selected = (
    Result<FullSignalFit, String>,
    ChainDecision,
    Option<MeasuringChain>,
);

pub(super) fn select_chain(
    case: &RecordingsRequest,
    files: &mut [FileResult],
    rigid: Result<FullSignalFit, String>,
) -> Result<Selected, anyhow::Error> {
    let requested = case.chain.name().to_string();
    let initial = rigid
        .as_ref()
        .ok()
        .map(|f| [f.vector[0].value, f.vector[1].value]);
    let mut decision = ChainDecision {
        requested: requested.clone(),
        used: "rigid".into(),
        reason: "rigid sensor assumed (--chain rigid)".into(),
        max_effect_at_tooth_harmonics: None,
        band_r_squared: None,
        band_rigid_r_squared: None,
    };
    let teeth = case.cutter.teeth();
    let model = match &case.chain {
        ChainChoice::Rigid => return Ok((rigid, decision, None)),
        ChainChoice::Frf(src) => ChainModel::Known(read_frf(src)?),
        ChainChoice::Band(max) => ChainModel::BandLimit {
            max_harmonic: match max {
                Some(m) => *m,
                None => auto_band(case, files, initial)?,
            },
        },
        ChainChoice::Auto | ChainChoice::Modes => fitted_modes(case, files),
    };
    let given = match &model {
        ChainModel::Known(c) => Some(c.clone()),
        _ => None,
    };
    let opts = chain_options(case, files, model, initial, None, true);
    let wc: Vec<_> = files
        .iter()
        .map(|f| waveform_case(&case.cutter, f))
        .collect();
    let fit = full_signal_fit(&wc, &opts).map_err(|e| e.to_string());
    let Ok(chain_fit) = fit else {
        let err = fit.err().unwrap_or_default();
        if requested == "auto" {
            decision.reason = format!("rigid: the fitted-mode check failed ({err})");
            return Ok((rigid, decision, None));
        }
        return Ok((Err(err), decision, given));
    };
    let report = chain_fit
        .chain
        .as_ref()
        .expect("chain fit has a chain report");
    let chain = chain_of(&chain_fit, given.as_ref());
    let effect = effect_at_tooth_harmonics(&chain, &chain_fit, files, teeth);
    decision.max_effect_at_tooth_harmonics = Some(effect);
    decision.band_r_squared = Some(chain_fit.r_squared);
    decision.band_rigid_r_squared = Some(report.rigid_r_squared);
    let ratio = (1.0 - report.rigid_r_squared) / (1.0 - chain_fit.r_squared).max(1e-12);
    let q = 2.0 * report.modes.iter().filter(|m| m.gain.value != 0.0).count() as f64;
    let f_stat = if q > 0.0 {
        ((chain_fit.r_squared - report.rigid_r_squared) / q)
            / ((1.0 - chain_fit.r_squared).max(1e-12) / chain_fit.dof.max(1) as f64)
    } else {
        0.0
    };
    let modes_text = report
        .modes
        .iter()
        .filter(|m| m.gain.value != 0.0)
        .map(|m| {
            format!(
                "{:?} {:.0} Hz (ζ {:.3})",
                m.axis, m.frequency_hz.value, m.damping.value
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
        .to_lowercase();
    let modes_text = if modes_text.is_empty() {
        "none lowers the misfit".to_string()
    } else {
        modes_text
    };
    decision.used = report.kind.clone();
    decision.reason = match report.kind.as_str() {
        "band_limit" => format!(
            "band limit: harmonics 0..{} of the spindle frequency fitted with the rigid model",
            report.max_harmonic.iter().max().unwrap_or(&0)
        ),
        "measured_frf" => "measured FRF given (--sensor-frf)".into(),
        _ => format!(
            "resonance detected: {modes_text}; |H − 1| up to {:.0} % at the tooth-passing harmonics; \
             misfit of the rigid model {:.1}× that of the chain (F = {f_stat:.0})",
            100.0 * effect,
            ratio
        ),
    };
    let resonant = report
        .modes
        .iter()
        .any(|m| m.gain.value != 0.0 && m.damping.value <= AUTO_MAX_DAMPING);
    if requested == "auto" && !(f_stat >= AUTO_MIN_F && effect >= AUTO_MIN_EFFECT && resonant) {
        decision.used = "rigid".into();
        decision.reason = if !resonant && effect >= AUTO_MIN_EFFECT {
            format!(
                "rigid: the fitted modes ({modes_text}) are too heavily damped to be a sensor \
                 resonance (ζ > {AUTO_MAX_DAMPING}); they would only absorb model error"
            )
        } else if effect < AUTO_MIN_EFFECT {
            format!(
                "rigid: no resonance reaching the tooth-passing harmonics (one mode per axis \
                 fitted: {modes_text}; |H − 1| ≤ {:.1} % there, below the {} % that would matter)",
                100.0 * effect,
                100.0 * AUTO_MIN_EFFECT
            )
        } else {
            format!(
                "rigid: a fitted mode ({modes_text}) would change the tooth-passing harmonics by up \
                 to {:.0} % but does not explain the waveform significantly better (F = {f_stat:.1} \
                 < {AUTO_MIN_F}); use --chain modes to force it",
                100.0 * effect
            )
        };
        return Ok((rigid, decision, None));
    }
    apply_angle_shifts(files, &chain_fit);
    Ok((Ok(chain_fit), decision, given))
}

/// A measured FRF from a file or bytes.
fn read_frf(src: &Source) -> Result<MeasuringChain, anyhow::Error> {
    Ok(match src.as_path() {
        Some(p) => runout_io::frf::read_frf(p)?,
        None => runout_io::frf::parse_frf(src.name(), &src.read_text()?)?,
    })
}

/// Automatic band limit: fit one mode per axis and keep the harmonics where the fitted chain
/// changes the waveform by < 5 % (|H − 1| < 0.05), at least K + 1.
fn auto_band(
    case: &RecordingsRequest,
    files: &[FileResult],
    initial: Option<[f64; 2]>,
) -> Result<usize, anyhow::Error> {
    let teeth = case.cutter.teeth();
    let opts = chain_options(case, files, fitted_modes(case, files), initial, None, true);
    let wc: Vec<_> = files
        .iter()
        .map(|f| waveform_case(&case.cutter, f))
        .collect();
    let fit = full_signal_fit(&wc, &opts)?;
    let chain = chain_of(&fit, None);
    let f_rev = files.iter().map(spindle_hz).fold(f64::INFINITY, f64::min);
    let mut k = 1;
    while k < 4096 {
        let worst = [&chain.x, &chain.y, &chain.z]
            .iter()
            .map(|a| (a.response_clamped((k + 1) as f64 * f_rev) - 1.0).norm())
            .fold(0.0, f64::max);
        if worst >= 0.05 {
            break;
        }
        k += 1;
    }
    Ok(k.max(teeth + 1))
}

/// Tooth numbering across recordings (issue 11 item 5): without an absolute angle each
/// recording's tooth 0 is the first tooth period of its own average, and a larger peak moving to
/// the other tooth flips it. Each recording is tried on every branch θ₀ + j·2π/K against the
/// joint fit's runout (coefficients re-solved for that recording); returns the recordings moved.
pub(super) fn align_tooth_numbering(
    case: &RecordingsRequest,
    files: &mut [FileResult],
    fit: &FullSignalFit,
) -> Vec<(usize, usize)> {
    let k = case.cutter.teeth();
    let e = [fit.vector[0].value, fit.vector[1].value];
    let tau = fit.tilt.map_or([0.0; 2], |t| [t[0].value, t[1].value]);
    let mut moved = Vec::new();
    for (c, f) in files.iter_mut().enumerate() {
        if f.analysis.average.tooth_reference == ToothReference::Absolute {
            continue;
        }
        let wc = waveform_case(&case.cutter, f);
        let cost = |j: usize| residual_at(&wc, f.start_angle + TAU * j as f64 / k as f64, e, tau);
        let here = cost(0);
        let (best_j, best) =
            (1..k)
                .map(|j| (j, cost(j)))
                .fold((0, here), |a, b| if b.1 < a.1 { b } else { a });
        // a clear preference only (10 % lower misfit): otherwise the numbering stays
        if best_j != 0 && best < 0.9 * here {
            f.start_angle = wrap_pi(f.start_angle + TAU * best_j as f64 / k as f64);
            moved.push((c, best_j));
        }
    }
    moved
}

/// One recording's runout with the coefficients (and chain) of the joint fit held.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RecordingRunout {
    pub file: String,
    pub offset_um: f64,
    pub offset_um_se: Option<f64>,
    pub angle_deg: f64,
    pub angle_deg_se: Option<f64>,
    pub r_squared: f64,
    /// True when it disagrees with the joint fit (see `consistency`).
    pub disagrees: bool,
}

/// Spread of the per-recording runouts.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Consistency {
    pub recordings: Vec<RecordingRunout>,
    /// (max − min)/mean of ρ over the recordings (%).
    pub offset_spread_percent: f64,
    /// Largest angular distance between two recordings' λ (deg).
    pub angle_spread_deg: f64,
    pub warnings: Vec<String>,
}

/// Per-recording runout fits with the joint coefficients and chain held (a single recording
/// cannot separate shear from edge coefficients). A recording disagrees when its runout vector is
/// more than max(3 SE, 15 % of ρ) from the joint one — e.g. a tool re-clamped between cuts.
pub(super) fn consistency(
    case: &RecordingsRequest,
    files: &[FileResult],
    joint: &FullSignalFit,
    given: Option<&MeasuringChain>,
) -> Option<Consistency> {
    if files.len() < 2 || joint.observability != RunoutObservability::Full {
        return None;
    }
    let chain = chain_of(joint, given);
    let e0 = [joint.vector[0].value, joint.vector[1].value];
    let rho0 = joint.offset.value;
    let mut recs = Vec::new();
    for f in files {
        let one = std::slice::from_ref(f);
        let opts = chain_options(
            case,
            one,
            ChainModel::Known(chain.clone()),
            Some(e0),
            Some(joint.coefficients),
            false,
        );
        let fit = full_signal_fit(&[waveform_case(&case.cutter, f)], &opts).ok()?;
        let d = (fit.vector[0].value - e0[0]).hypot(fit.vector[1].value - e0[1]);
        let se = fit.offset.se.unwrap_or(0.0);
        let valid = |s: Option<f64>| s.filter(|v| v.is_finite() && *v > 0.0);
        recs.push(RecordingRunout {
            file: f.name.clone(),
            offset_um: fit.offset.value * 1e3,
            offset_um_se: valid(fit.offset.se).map(|s| s * 1e3),
            angle_deg: fit.angle.value.to_degrees(),
            angle_deg_se: valid(fit.angle.se).map(f64::to_degrees),
            r_squared: fit.r_squared,
            disagrees: d > (3.0 * se).max(0.15 * rho0),
        });
    }
    let rho: Vec<f64> = recs.iter().map(|r| r.offset_um).collect();
    let mean = rho.iter().sum::<f64>() / rho.len() as f64;
    let spread =
        rho.iter().cloned().fold(f64::MIN, f64::max) - rho.iter().cloned().fold(f64::MAX, f64::min);
    let mut ang = 0.0f64;
    for a in &recs {
        for b in &recs {
            ang = ang.max(
                wrap_pi((a.angle_deg - b.angle_deg).to_radians())
                    .abs()
                    .to_degrees(),
            );
        }
    }
    let warnings = recs
        .iter()
        .filter(|r| r.disagrees)
        .map(|r| {
            format!(
                "{}: runout {:.2} µm at {:.1}° disagrees with the joint fit ({:.2} µm at {:.1}°) — \
                 was the tool re-clamped, or are the cut conditions of this recording right?",
                r.file,
                r.offset_um,
                r.angle_deg,
                rho0 * 1e3,
                joint.angle.value.to_degrees()
            )
        })
        .collect();
    Some(Consistency {
        recordings: recs,
        offset_spread_percent: 100.0 * spread / mean.max(f64::MIN_POSITIVE),
        angle_spread_deg: ang,
        warnings,
    })
}

/// Reasons that concern the whole fit (printed once), and the status per parameter.
#[derive(Debug, Clone, Serialize, Default, JsonSchema)]
pub struct Verdicts {
    /// Reasons for which no parameter of the fit is identified.
    pub fit: Vec<String>,
    pub parameters: Vec<Status>,
}

/// Status of one identified quantity.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Status {
    pub parameter: String,
    /// `identified` or `not_identified`.
    pub status: String,
    /// Why not, and what to do.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// A parameter is not identified when its SE exceeds this fraction of its value (ρ and the
/// coefficients), the angle's SE exceeds 15°, the fit explains < 90 % of the waveform, or it is
/// physically implausible (a negative shear or edge coefficient).
const SE_FRACTION: f64 = 0.25;
const ANGLE_SE_DEG: f64 = 15.0;

/// Verdicts for ρ, λ and the six coefficients, with the likely cause in words.
pub(super) fn verdicts(
    fit: &FullSignalFit,
    decision: &ChainDecision,
    files: &[FileResult],
) -> Verdicts {
    let min_revs = files
        .iter()
        .map(|f| f.analysis.average.revolutions)
        .min()
        .unwrap_or(0);
    let mut general = Vec::new();
    if fit.r_squared < 0.9 {
        let mut why = format!(
            "the model explains only {:.0} % of the waveform (R² {:.3} < 0.9)",
            100.0 * fit.r_squared.max(0.0),
            fit.r_squared
        );
        if decision.used == "rigid"
            && decision
                .band_r_squared
                .is_some_and(|r| r > fit.r_squared + 0.05)
        {
            why.push_str(&format!(
                "; a sensor resonance is likely and not modelled ({}): try --chain modes",
                decision.reason
            ));
        } else {
            why.push_str(
                "; check the cutter geometry (diameter, helix, end profile), the cut conditions \
                 (a_p, a_e, mode), the axis mapping (--axes) and the sensor's resonance (--chain modes)",
            );
        }
        general.push(why);
    }
    if fit.ill_conditioned {
        general.push(format!(
            "the fit is ill-conditioned (condition {:.2e}): add feeds or components",
            fit.condition
        ));
    }
    if min_revs < 10 {
        general.push(format!(
            "only {min_revs} revolutions averaged: record at least 10–20 steady revolutions"
        ));
    }
    let status = |name: &str, own: Option<String>| Status {
        parameter: name.into(),
        status: if general.is_empty() && own.is_none() {
            "identified".into()
        } else {
            "not_identified".into()
        },
        reason: own,
    };
    let rel = |v: f64, se: Option<f64>| match se {
        Some(s) if s.is_finite() && s <= SE_FRACTION * v.abs() => None,
        Some(s) => Some(format!(
            "its standard error ({s:.3}) exceeds {:.0} % of its value ({v:.3})",
            100.0 * SE_FRACTION
        )),
        None => Some("no standard error".into()),
    };
    let mut out = vec![status(
        "offset",
        rel(fit.offset.value * 1e3, fit.offset.se.map(|s| s * 1e3)),
    )];
    let angle_own = match (fit.observability, fit.angle.se) {
        (RunoutObservability::AlongDirection { .. }, _) => Some(
            "only the offset along the tooth line is observable (K = 2, straight flutes): use a \
             helical cutter or a displacement measurement"
                .to_string(),
        ),
        (_, Some(s)) if s.to_degrees() <= ANGLE_SE_DEG => None,
        (_, s) => Some(format!(
            "its standard error ({}) exceeds {ANGLE_SE_DEG}°",
            s.map_or("none".into(), |s| format!("{:.1}°", s.to_degrees()))
        )),
    };
    out.push(status("angle", angle_own));
    let names = ["ktc", "krc", "kac", "kte", "kre", "kae"];
    for (i, n) in names.iter().enumerate() {
        let Some(se) = fit.coefficient_se[i] else {
            continue;
        };
        let v = fit.coefficients[i];
        let mut own = rel(v, Some(se));
        if [0, 1, 3, 4].contains(&i) && v <= 0.0 {
            own = Some(format!(
                "negative ({v:.2}), which is physically implausible: model error (geometry, \
                 resonance, axis mapping) is absorbed here"
            ));
        }
        out.push(status(n, own));
    }
    Verdicts {
        fit: general,
        parameters: out,
    }
}
