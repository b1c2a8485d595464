//! Methods on the averaged signals: the sine fit of the peaks (§4.2), the mean-force
//! calibration (§4.4), start angles (§4.7) and the joint full-signal fit (§4.5).

use super::{FileResult, RecordingsRequest};
use runout_core::identify::{
    calibrate_mean_forces, full_signal_fit, harmonic_start_angle, peak_immersion,
    radius_difference, refine_start_angle, sine_fit, AveragedWaveform, FrameAxis as FitAxis,
    FullSignalFit, FullSignalOptions, MeanForceCalibration, MeanForces, PeakConditions, SineFit,
    SineHypothesis, ToothPeaks, WaveformCase, WaveformComponent as FitComponent,
};
use runout_core::signal::{ForceComponent, SignalAnalysis, ToothReference};
use runout_core::{angle::wrap_pi, Cut, Cutter, CuttingCoefficients};

pub(super) fn peak_sine_fit(
    cutter: &Cutter,
    cut: &Cut,
    an: &SignalAnalysis,
) -> Result<SineFit, String> {
    let peaks: Vec<f64> = an.average.tooth_peaks.iter().map(|p| p.peak).collect();
    let se: Vec<f64> = an.average.tooth_peaks.iter().map(|p| p.se).collect();
    let mut tp = ToothPeaks::new(peaks).map_err(|e| e.to_string())?;
    if se.iter().all(|s| s.is_finite() && *s > 0.0) {
        tp = tp.with_se(se).map_err(|e| e.to_string())?;
    }
    let cond =
        PeakConditions::new(cut.fz(), peak_immersion(cutter, cut)).map_err(|e| e.to_string())?;
    sine_fit(&tp, &cond, SineHypothesis::Teeth).map_err(|e| e.to_string())
}

pub(super) fn mean_force_calibration(
    case: &RecordingsRequest,
    files: &[FileResult],
) -> Result<MeanForceCalibration, String> {
    let feeds: Vec<f64> = files.iter().map(|f| f.cut.fz()).collect();
    let distinct = {
        let mut v = feeds.clone();
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
        v.len()
    };
    if distinct < 2 {
        return Err("needs recordings at ≥ 2 different feeds".into());
    }
    let c0 = &files[0].cut;
    if files.iter().any(|f| {
        (f.cut.ap() - c0.ap()).abs() > 1e-12
            || f.cut.immersion(&case.cutter) != c0.immersion(&case.cutter)
    }) {
        return Err("needs the same a_p and engagement in every recording".into());
    }
    let data: Vec<MeanForces> = files
        .iter()
        .map(|f| MeanForces {
            fz_mm: f.cut.fz(),
            fx_n: f.mean_force[0],
            fy_n: f.mean_force[1],
            fz_n: f.mean_force[2].is_finite().then_some(f.mean_force[2]),
        })
        .collect();
    if !case.cutter.is_flat() {
        // κ(z) and the per-disk window: the general design (400 disks: the integrals per disk
        // are exact, the disks only sample R(z) and κ(z))
        let design = runout_core::identify::MeanForceDesign::new(
            &runout_core::edge::EdgeTable::new(&case.cutter, c0, 400),
        );
        return runout_core::identify::calibrate_mean_forces_general(&design, &data)
            .map_err(|e| e.to_string());
    }
    let (st, ex) = c0.immersion(&case.cutter);
    calibrate_mean_forces(case.cutter.teeth(), c0.ap(), st, ex, &data).map_err(|e| e.to_string())
}

pub(super) fn coefficients_of(c: &MeanForceCalibration) -> CuttingCoefficients {
    CuttingCoefficients::from_array([
        c.ktc.value,
        c.krc.value,
        c.kac.map_or(0.0, |e| e.value),
        c.kte.value,
        c.kre.value,
        c.kae.map_or(0.0, |e| e.value),
    ])
}

/// A typical coefficient ratio: only the phase of the tooth-passing harmonic is used.
pub(super) fn default_coefficients() -> CuttingCoefficients {
    CuttingCoefficients::from_array([2000.0, 800.0, 300.0, 0.0, 0.0, 0.0])
}

/// Reference for the branch of the harmonic alignment: the pipeline's tooth-0 period start maps
/// to the entry angle φ_st, which keeps its tooth numbering.
pub(super) fn branch_reference(cutter: &Cutter, f: &FileResult) -> f64 {
    let avg = &f.analysis.average;
    let (st, _) = f.cut.immersion(cutter);
    let b0 = avg
        .tooth_peaks
        .first()
        .map(|p| p.period_start)
        .unwrap_or(0.0);
    avg.angle_origin - b0 + st
}

/// First estimate of the spindle angle of bin 0 (absolute with a pulse + tooth-0 angle,
/// otherwise from the tooth-passing harmonic, methods.md §4.7).
pub(super) fn initial_start_angle(
    cutter: &Cutter,
    f: &FileResult,
    kc: &CuttingCoefficients,
) -> f64 {
    if f.analysis.average.tooth_reference == ToothReference::Absolute {
        return f.analysis.average.angle_origin;
    }
    let mut probe = waveform_case(cutter, f);
    probe.waveform.start_angle = 0.0;
    harmonic_start_angle(&probe, [0.0; 2], [0.0; 2], kc, branch_reference(cutter, f))
}

pub(super) fn waveform_case(cutter: &Cutter, f: &FileResult) -> WaveformCase {
    let avg = &f.analysis.average;
    let comp = |c: ForceComponent, axis: FitAxis| {
        let x = avg.component(c);
        let values = x.mean.clone();
        let se = Some(x.se.clone()).filter(|s| s.iter().all(|v| v.is_finite() && *v > 0.0));
        FitComponent { axis, values, se }
    };
    let mut components = vec![
        comp(ForceComponent::Fx, FitAxis::X),
        comp(ForceComponent::Fy, FitAxis::Y),
    ];
    if avg.has_fz {
        components.push(comp(ForceComponent::Fz, FitAxis::Z));
    }
    WaveformCase {
        cutter: cutter.clone(),
        cut: f.cut,
        waveform: AveragedWaveform {
            start_angle: f.start_angle,
            components,
            revolutions: avg.revolutions,
        },
    }
}

/// Full-signal fit of all recordings. Without an absolute angle, each recording's start angle is
/// first searched within ±8° without runout, then refined against the fitted runout (±1°, coefficients re-solved linearly) and the fit
/// repeated until no start angle moves by more than 0.005° (at most 3 refits).
pub(super) fn fit_all(
    case: &RecordingsRequest,
    files: &mut [FileResult],
) -> Result<FullSignalFit, String> {
    let opts = FullSignalOptions {
        fit_tilt: case.fit_tilt,
        ..FullSignalOptions::default()
    };
    let cases = |files: &[FileResult]| {
        files
            .iter()
            .map(|f| waveform_case(&case.cutter, f))
            .collect::<Vec<_>>()
    };
    // The harmonic start can be several degrees off when edge forces dominate (straight flutes):
    // first a wide search without runout (runout modulates amplitudes, not the timing).
    for f in files
        .iter_mut()
        .filter(|f| f.analysis.average.tooth_reference != ToothReference::Absolute)
    {
        let wc = waveform_case(&case.cutter, f);
        // a ball, bull nose or taper: the harmonic phase of a start model without the lead angle
        // can be far off (the tooth-passing harmonic mixes windows that differ per disk), so
        // the search spans half a tooth pitch
        let half = if case.cutter.is_flat() {
            8f64.to_radians()
        } else {
            std::f64::consts::PI / case.cutter.teeth() as f64
        };
        f.start_angle = refine_start_angle(&wc, f.start_angle, half, [0.0; 2], [0.0; 2]).0;
    }
    let mut fit = full_signal_fit(&cases(files), &opts).map_err(|e| e.to_string())?;
    // A ball, bull nose or taper couples the start angle more strongly with λ (the runout is
    // seen through a few small per-disk windows): wider steps and more alternations. Measured
    // on a ball at a_p 0.2 mm: the runout-free search lands 1–2° off, which ±1° steps do not
    // recover (R² 0.95 instead of 0.9999).
    let (half, rounds) = if case.cutter.is_flat() {
        (1f64.to_radians(), 3)
    } else {
        (4f64.to_radians(), 8)
    };
    for _ in 0..rounds {
        let e = [fit.vector[0].value, fit.vector[1].value];
        let tau = fit.tilt.map_or([0.0; 2], |t| [t[0].value, t[1].value]);
        let mut moved = 0.0f64;
        for f in files
            .iter_mut()
            .filter(|f| f.analysis.average.tooth_reference != ToothReference::Absolute)
        {
            let wc = waveform_case(&case.cutter, f);
            let (t, _) = refine_start_angle(&wc, f.start_angle, half, e, tau);
            moved = moved.max(wrap_pi(t - f.start_angle).abs());
            f.start_angle = t;
        }
        if moved < 0.005f64.to_radians() {
            break;
        }
        let o = FullSignalOptions {
            initial_runout: Some(e),
            ..opts.clone()
        };
        fit = full_signal_fit(&cases(files), &o).map_err(|e| e.to_string())?;
    }
    Ok(fit)
}

/// K = 2: the radius difference R₀ − R₁ from the two per-tooth peaks (the sine fit is
/// degenerate there), µm ± SE.
pub(super) fn radius_difference_um(cutter: &Cutter, f: &FileResult) -> Option<(f64, Option<f64>)> {
    if cutter.teeth() != 2 {
        return None;
    }
    let p = &f.analysis.average.tooth_peaks;
    let mut tp = ToothPeaks::new(p.iter().map(|p| p.peak).collect()).ok()?;
    let se: Vec<f64> = p.iter().map(|p| p.se).collect();
    if se.iter().all(|s| s.is_finite() && *s > 0.0) {
        tp = tp.with_se(se).ok()?;
    }
    let cond = PeakConditions::new(f.cut.fz(), peak_immersion(cutter, &f.cut)).ok()?;
    let d = radius_difference(&tp, &cond).ok()?;
    Some((d.value * 1e3, d.se.map(|s| s * 1e3)))
}

/// R₀ − R₁ (µm) at the tool tip from a fitted runout (the full-signal check of the peak value).
pub(super) fn fitted_radius_difference_um(cutter: &Cutter, fit: &FullSignalFit) -> Option<f64> {
    if cutter.teeth() != 2 {
        return None;
    }
    let r = runout_core::Runout::new(fit.offset.value, fit.angle.value).ok()?;
    Some((r.tooth_radius(cutter, 0, 0.0) - r.tooth_radius(cutter, 1, 0.0)) * 1e3)
}

/// K = 2: the peaks' radius difference as a check of the full-signal fit (issue 11 item 4): a
/// warning per recording where they disagree by more than max(3 SE, 30 % of the fitted value,
/// 1 µm) — the proportional-peak model is biased by edge forces and helix smearing, hence the
/// generous bound; a sign flip or a factor of two points at a wrong fit or tooth numbering.
pub(super) fn radius_difference_warnings(
    cutter: &Cutter,
    files: &[FileResult],
    fit: &FullSignalFit,
) -> Vec<String> {
    let Some(d_fit) = fitted_radius_difference_um(cutter, fit) else {
        return Vec::new();
    };
    files
        .iter()
        .filter_map(|f| {
            let (d, se) = radius_difference_um(cutter, f)?;
            let bound = (3.0 * se.unwrap_or(0.0)).max(0.3 * d_fit.abs()).max(1.0);
            ((d - d_fit).abs() > bound).then(|| {
                format!(
                    "{}: the two peaks give R₀ − R₁ = {d:.2} µm, the full-signal fit {d_fit:.2} µm \
                     (more than {bound:.2} µm apart): check the fit and the tooth numbering",
                    f.name
                )
            })
        })
        .collect()
}

/// The fitted model of one recording's averaged waveform, as the sensor records it (through
/// the chain and resampling when a chain was used), for plots.
pub(super) fn model_waveforms(
    req: &RecordingsRequest,
    f: &FileResult,
    fit: &FullSignalFit,
    extra: &super::Extra,
) -> [Vec<f64>; 3] {
    let kc = CuttingCoefficients::from_array(fit.coefficients);
    let tau = fit.tilt.map_or([0.0; 2], |t| [t[0].value, t[1].value]);
    let mut pred = runout_core::identify::model_forces(
        &waveform_case(&req.cutter, f),
        f.start_angle,
        [fit.vector[0].value, fit.vector[1].value],
        tau,
        &kc,
    );
    if fit.chain.is_some() && extra.decision.used != "band_limit" {
        let chain = super::chain::chain_of(fit, extra.given.as_ref());
        let f_rev = f.analysis.speed.rpm / 60.0;
        let spr = Some(f.info.sample_rate_hz / f_rev);
        for (p, axis) in pred.iter_mut().zip([&chain.x, &chain.y, &chain.z]) {
            *p = axis.apply_periodic(p, f_rev, spr);
        }
    }
    pred
}
