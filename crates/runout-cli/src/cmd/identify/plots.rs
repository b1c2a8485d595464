//! The plots of `runout identify RECORDING… --plot-dir DIR`, drawn from the report: per
//! recording the averaged waveform against the fitted model and the per-tooth peaks with their
//! sine fit, and the polar plot of every runout estimate (±1 SE).

use anyhow::Result;
use runout::identify::{Fitted, RecordingReport, RecordingsReport, WaveformPlot};
use runout_io::plot::identify::{
    runout_polar, tooth_peak_bars, waveform_overlay, Curve, RunoutMark,
};
use std::path::Path;

fn file_label(file: &str) -> String {
    Path::new(file)
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn curves(v: &[Vec<f64>; 3]) -> [Curve<'_>; 3] {
    let label = ["F_x (N)", "F_y (N)", "F_z (N)"];
    [0, 1, 2].map(|i| Curve {
        label: label[i],
        values: &v[i],
    })
}

fn waveform(dir: &Path, ext: &str, i: usize, r: &RecordingsReport, w: &WaveformPlot) -> Result<()> {
    let Some(pred) = &w.predicted_N else {
        return Ok(());
    };
    let rec = &r.recordings[i];
    let title = format!(
        "{}: averaged ({} rev) vs full-signal model{}",
        file_label(&rec.file),
        rec.revolutions_averaged,
        match r.measuring_chain.decision.used.as_str() {
            "rigid" => "",
            "band_limit" => " (rigid, fitted on the band)",
            _ => " through the measuring chain",
        }
    );
    let n = w.components;
    waveform_overlay(
        &dir.join(format!("waveform_{i}.{ext}")),
        &w.angle_deg,
        &curves(&w.measured_N)[..n],
        &curves(pred)[..n],
        &title,
    )?;
    Ok(())
}

fn peaks(dir: &Path, ext: &str, i: usize, rec: &RecordingReport) -> Result<()> {
    let Fitted::Fit(s) = &rec.sine_fit else {
        return Ok(());
    };
    let p: Vec<f64> = rec.tooth_peaks.iter().map(|p| p.peak_N).collect();
    let se: Vec<f64> = rec.tooth_peaks.iter().map(|p| p.peak_N_se).collect();
    let title = format!(
        "{}: per-tooth peaks of {}",
        file_label(&rec.file),
        rec.peak_component
    );
    tooth_peak_bars(
        &dir.join(format!("tooth_peaks_{i}.{ext}")),
        &p,
        &se,
        s.mean_N,
        s.amplitude_N,
        s.phase_deg.to_radians(),
        &title,
    )?;
    Ok(())
}

/// A runout estimate: label, ρ (µm), λ (deg) and their SEs.
type Mark = (String, f64, f64, Option<f64>, Option<f64>);

/// Every runout estimate: the sine fit of each recording, then the full-signal fit.
fn marks(r: &RecordingsReport) -> Vec<Mark> {
    let mut m: Vec<_> = r
        .recordings
        .iter()
        .filter_map(|rec| {
            let s = rec.sine_fit.ok()?;
            let label = format!("sine fit {}", file_label(&rec.file));
            Some((
                label,
                s.offset_um,
                s.angle_deg,
                s.offset_um_se,
                s.angle_deg_se,
            ))
        })
        .collect();
    if let Some(f) = r.full_signal.ok() {
        m.push((
            "full-signal fit".into(),
            f.offset_um,
            f.angle_deg,
            f.offset_um_se,
            f.angle_deg_se,
        ));
    }
    m
}

/// All plots of the report into `dir` (`ext`: svg or png).
pub fn write(dir: &Path, ext: &str, r: &RecordingsReport) -> Result<()> {
    for (i, w) in r.waveforms.iter().enumerate() {
        waveform(dir, ext, i, r, w)?;
        peaks(dir, ext, i, &r.recordings[i])?;
    }
    let m = marks(r);
    let rm: Vec<RunoutMark> = m
        .iter()
        .map(|(l, o, a, ose, ase)| RunoutMark {
            label: l,
            offset_um: *o,
            angle_deg: *a,
            offset_um_se: ose.unwrap_or(f64::NAN),
            angle_deg_se: ase.unwrap_or(f64::NAN),
        })
        .collect();
    runout_polar(
        &dir.join(format!("runout_polar.{ext}")),
        &rm,
        r.inputs.teeth,
        "identified runout (±1 SE)",
    )?;
    Ok(())
}
