//! The displacement reports as text (what the CLI prints) and plots.

use super::{HeightsReport, SignalReport, TeethReport};
use crate::verdict::verdict_text;
use anyhow::{Context, Result};
use runout_core::displacement::{AngleEstimate, Consequences};
use runout_io::displacement_plot::{height_plot, teeth_polar_plot, HeightPlot, TeethPlot};
use std::path::Path;

/// Text line of an angle estimate.
pub fn angle_text(a: &AngleEstimate) -> String {
    let se = |s: Option<f64>| {
        s.map_or("σ unknown".to_string(), |s| {
            format!("± {:.2}° (1σ)", s.to_degrees())
        })
    };
    match a {
        AngleEstimate::Determined { angle_rad, se_rad } => {
            format!("angle λ = {:.2}° {}", angle_rad.to_degrees(), se(*se_rad))
        }
        AngleEstimate::Ambiguous {
            candidates_rad,
            se_rad,
            reason,
        } => format!(
            "angle λ = {:.2}° or {:.2}° {} — AMBIGUOUS: {reason}",
            candidates_rad[0].to_degrees(),
            candidates_rad[1].to_degrees(),
            se(*se_rad)
        ),
        AngleEstimate::Undetermined { reason, .. } => format!("angle λ UNDETERMINED: {reason}"),
    }
}

/// Text of the consequences.
pub fn consequences_text(c: &Consequences) -> String {
    let mut s = String::from("predicted (docs/methods.md §1.7):\n");
    for (i, r) in c.tooth_radii_mm.iter().enumerate() {
        s += &format!("  tooth {i}: radius {r:.6} mm");
        if let Some(h) = &c.chip_load_mm {
            s += &format!(", chip load {:.3} µm", h[i] * 1e3);
        }
        s += "\n";
    }
    s += &format!("  slot width {:.6} mm\n", c.slot_width_mm);
    if let Some(d) = c.hole_diameter_mm {
        s += &format!("  hole diameter {d:.6} mm\n");
    }
    s
}

/// Notes as text lines.
fn notes_text(notes: &[String]) -> String {
    notes.iter().map(|n| format!("note: {n}\n")).collect()
}

/// `displacement teeth` text.
pub fn teeth_text(r: &TeethReport) -> String {
    r.answer.text() + &teeth_body(r)
}

fn teeth_body(r: &TeethReport) -> String {
    let Some(fit) = &r.detail.fit else {
        return String::new();
    };
    let mut s = format!(
        "runout from per-tooth readings ({}; method {})\n",
        r.input.file,
        crate::words::plain(&fit.method)
    );
    s += &match fit.offset_se_mm {
        Some(se) => format!(
            "offset ρ = {:.3} ± {:.3} µm (1σ)\n",
            fit.offset_mm * 1e3,
            se * 1e3
        ),
        None => format!("offset ρ = {:.3} µm\n", fit.offset_mm * 1e3),
    };
    s += &angle_text(&fit.angle);
    s += "\n";
    s += &format!(
        "residual rms {:.4} µm, dof {}, noise {} ({})\n",
        fit.residual_rms_mm * 1e3,
        fit.dof,
        fit.noise_mm
            .map_or("unknown".into(), |n| format!("{:.4} µm", n * 1e3)),
        crate::words::plain(&fit.noise_source)
    );
    for (i, (p, d)) in fit
        .positions_mm
        .iter()
        .zip(&fit.radius_differences_mm)
        .enumerate()
    {
        s += &format!(
            "  tooth {i}: P = {:.4} µm, ΔR = P{i} − P{} = {:.4} µm\n",
            p * 1e3,
            (i + 1) % fit.positions_mm.len(),
            d * 1e3
        );
    }
    if let Some(c) = &r.detail.consequences {
        s += &consequences_text(c);
    }
    s += &notes_text(&fit.notes);
    s + &r.verdict.as_ref().map_or(String::new(), verdict_text)
}

/// `displacement teeth` polar plot.
pub fn teeth_plot(path: &Path, r: &TeethReport) -> Result<()> {
    let (Some(fit), Some(opts)) = (&r.detail.fit, &r.detail.options) else {
        return Ok(());
    };
    let cutter = &opts.cutter;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let pm = mean(&fit.positions_mm);
    let model = fit.runout().map(|ro| {
        let radii = ro.tooth_radii(cutter, opts.height_mm);
        let m = mean(&radii);
        radii.iter().map(|v| (v - m) * 1e3).collect()
    });
    let d = TeethPlot {
        tooth_angles_rad: (0..cutter.teeth())
            .map(|i| cutter.tooth_angle(i, opts.height_mm))
            .collect(),
        measured_um: fit.positions_mm.iter().map(|p| (p - pm) * 1e3).collect(),
        model_um: model,
        offset_um: fit.offset_mm * 1e3,
        angle_rad: fit.angle.angle(),
        title: format!(
            "per-tooth radii, K = {} (runout {:.3} µm)",
            cutter.teeth(),
            fit.offset_mm * 1e3
        ),
    };
    Ok(teeth_polar_plot(path, &d)?)
}

/// `displacement heights` text.
pub fn heights_text(r: &HeightsReport) -> String {
    r.answer.text() + &heights_body(r)
}

fn heights_body(r: &HeightsReport) -> String {
    let Some(fit) = &r.detail.fit else {
        return String::new();
    };
    let file = &r.input.file;
    let mut s = format!(
        "runout vs height ({file}; {} heights, {})\n",
        fit.points,
        crate::words::plain(&fit.method)
    );
    s += &match fit.offset_se_mm {
        Some(se) => format!(
            "runout at z = {} mm: {:.3} ± {:.3} µm (1σ)\n",
            fit.height_mm,
            fit.offset_mm * 1e3,
            se * 1e3
        ),
        None => format!(
            "runout at z = {} mm: {:.3} µm\n",
            fit.height_mm,
            fit.offset_mm * 1e3
        ),
    };
    s += &format!(
        "slope {:.4} µm/mm, R² {:.4}, residual rms {:.4} µm\n",
        fit.slope * 1e3,
        fit.r_squared,
        fit.residual_rms_mm * 1e3
    );
    if let Some(v) = &r.detail.vector {
        s += &format!(
            "vector fit (offset + tilt, docs/methods.md §1.6): runout {:.3} µm, {}; tilt ({:.4}, {:.4}) µm/mm\n",
            v.offset_mm * 1e3,
            angle_text(&v.angle),
            v.line.tilt[0].value * 1e3,
            v.line.tilt[1].value * 1e3
        );
    }
    s += &notes_text(&fit.notes);
    s + &r.verdict.as_ref().map_or(String::new(), verdict_text)
}

/// `displacement heights` plot: points, regression line, result with its ±2σ bar.
pub fn heights_plot(path: &Path, r: &HeightsReport) -> Result<()> {
    let Some(fit) = &r.detail.fit else {
        return Ok(());
    };
    let pts = &r.detail.points;
    let zs = pts.iter().map(|p| p.0).chain([fit.height_mm]);
    let (z0, z1) = zs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
        (a.min(z), b.max(z))
    });
    let d = HeightPlot {
        points: pts.iter().map(|(z, r)| (*z, r * 1e3)).collect(),
        line: vec![(z0, fit.at(z0) * 1e3), (z1, fit.at(z1) * 1e3)],
        line_label: format!(
            "{} fit, R² = {:.4}",
            crate::words::plain(&fit.method),
            fit.r_squared
        ),
        at: (
            fit.height_mm,
            fit.offset_mm * 1e3,
            fit.offset_se_mm.map(|s| s * 1e3),
        ),
        title: "runout vs height (r = TIR/2)".into(),
    };
    Ok(height_plot(path, &d)?)
}

/// `displacement signal` text.
pub fn signal_text(r: &SignalReport) -> String {
    r.answer.text() + &signal_body(r)
}

fn signal_body(r: &SignalReport) -> String {
    let Some(fit) = &r.detail.fit else {
        return String::new();
    };
    let ch = &r.input.channels;
    let mut s = format!(
        "runout from signal ({}; {} channel(s), spindle angle from {}, {:.3} rpm, {} revolutions)\n",
        r.input.file,
        ch.len(),
        crate::words::plain(&fit.reference),
        fit.rpm,
        fit.revolutions
    );
    s += &format!(
        "offset ρ = {:.4} ± {:.4} µm (1σ)\n",
        fit.offset_mm * 1e3,
        fit.offset_se_mm * 1e3
    );
    s += &angle_text(&fit.angle);
    s += "\n";
    for (c, name) in fit.channels.iter().zip(ch) {
        s += &format!(
            "  channel {name} at {:.1}°: {:.4} µm at {:.2}°, residual sd {:.4} µm\n",
            c.sensor_angle_rad.to_degrees(),
            c.offset_mm * 1e3,
            c.vector_mm[1].atan2(c.vector_mm[0]).to_degrees(),
            c.residual_sd_mm * 1e3
        );
    }
    s += &notes_text(&fit.notes);
    s += &format!(
        "  section {:.6}–{:.6} s ({} samples at {:.1} Hz)\n",
        r.section.from_s, r.section.to_s, r.section.samples, r.detail.sample_rate_hz
    );
    for (rv, name) in r.detail.revolutions.iter().zip(ch) {
        s += &format!(
            "  channel {name}: TIR/2 per revolution (seed eq. 5) {:.4} µm (sd {})\n",
            rv.mean_mm * 1e3,
            rv.sd_mm
                .map_or("–".into(), |s| format!("{:.4} µm", s * 1e3))
        );
    }
    if let Some((tf, cons)) = &r.detail.teeth {
        s += &format!(
            "per-tooth extrema (channel 0): offset {:.3} µm, {}\n",
            tf.offset_mm * 1e3,
            angle_text(&tf.angle)
        );
        if let Some(c) = cons {
            s += &consequences_text(c);
        }
    }
    s + &r.verdict.as_ref().map_or(String::new(), verdict_text)
}

/// `displacement signal` polar plot.
pub fn signal_plot(path: &Path, r: &SignalReport) -> Result<()> {
    let d = r.detail.plot.as_ref().context("no plot data")?;
    Ok(teeth_polar_plot(path, d)?)
}
