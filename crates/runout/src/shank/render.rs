//! The shank reports as text (what the CLI prints) and plots.

use super::{CalibrationReport, ForceReport, StiffnessReport, Thinned};
use anyhow::Result;
use runout_io::lineplot::{stacked_plot, Curve, Panel};
use serde_json::Value;
use std::fmt::Write;
use std::path::Path;

/// A number as the JSON shows it (`20000.0`, `null` when not finite).
fn j(v: f64) -> Value {
    Value::from(v)
}

/// `runout shank stiffness` text.
pub fn stiffness_text(r: &StiffnessReport) -> String {
    format!(
        "K_delta = {:.6} N/um  (I = {:.2} mm^4, load at {} mm from the holder face)\n\
         first bending mode {:.0} Hz ({} kg/m^3): static force usable to {:.0} Hz (|H - 1| <= 10 %)\n",
        r.stiffness_N_per_um,
        r.second_moment_mm4,
        r.load_point_mm,
        r.first_bending_mode_hz,
        r.density_kg_per_m3,
        r.usable_bandwidth_hz
    )
}

/// `runout shank calibrate` text.
pub fn calibration_text(r: &CalibrationReport) -> String {
    r.answer.text() + &calibration_body(r)
}

fn calibration_body(r: &CalibrationReport) -> String {
    let mut s = format!(
        "K_delta = {:.4} ± {:.4} N/um at {} mm (beam formula {:.4}); R² {:.6}, residual {:.3} um, condition {:.1}\n",
        r.stiffness_N_per_um,
        r.stiffness_N_per_um_se,
        r.at_load_point_mm,
        r.beam_stiffness_N_per_um,
        r.r_squared,
        r.residual_rms_um,
        r.condition_number
    );
    match (r.holder_compliance_rad_per_Nm, r.holder_compliance_rad_per_Nm_se) {
        (Some(c), Some(se)) => {
            s += &format!("holder: rotational compliance {c:.4e} ± {se:.1e} rad/(N·m)\n")
        }
        _ => s += "holder: not identifiable with a single load point (use --load-point-channel with ≥ 2 positions)\n",
    }
    s
}

/// `runout shank force` text summary.
pub fn force_text(r: &ForceReport) -> String {
    r.answer.text() + &force_body(r)
}

fn force_body(j_: &ForceReport) -> String {
    let mut s = String::new();
    let r = &j_.runout;
    let _ = writeln!(
        s,
        "recording        {}  ({} samples at {} Hz)",
        j_.recording,
        j_.samples,
        j(j_.sample_rate_hz)
    );
    let _ = writeln!(
        s,
        "stiffness        K_delta = {:.4} N/um ({})",
        j_.stiffness_N_per_um, j_.stiffness_source
    );
    let _ = writeln!(
        s,
        "spindle          {:.4} rpm ± {:.1e} ({})",
        j_.spindle.rpm, j_.spindle.rpm_se, j_.spindle.source
    );
    let _ = writeln!(
        s,
        "air cuts (s)     {}   cut (s) {}",
        serde_json::to_string(&j_.air_cut_s).unwrap_or_default(),
        serde_json::to_string(&j_.cut_s).unwrap_or_default()
    );
    let _ = writeln!(
        s,
        "runout           offset {:.2} ± {:.2} um at {} mm above the tip, angle {:.1} deg; tilt {:.3} um/mm at {:.1} deg",
        r.offset_um,
        r.offset_um_se,
        j(r.at_height_above_tip_mm),
        r.angle_deg,
        r.tilt_um_per_mm,
        r.tilt_angle_deg,
    );
    let _ = writeln!(s, "                 (angle {})", r.angle_reference);
    for f in &j_.force_over_cut {
        let _ = writeln!(
            s,
            "force F{} (N)     mean {:.2}  rms {:.2}  min {:.2}  max {:.2}",
            f.axis, f.mean_N, f.rms_N, f.min_N, f.max_N
        );
    }
    let d = &j_.dynamics;
    let _ = writeln!(
        s,
        "bandwidth        first bending mode {:.0} Hz (beam model, {:.0} kg/m3, damping {}); static F = K*Delta usable to {:.0} Hz (|H - 1| <= 10 %)",
        d.first_bending_mode_hz,
        d.density_kg_per_m3,
        j(d.beam_damping),
        d.uncorrected_bandwidth_hz,
    );
    if let Some(c) = &d.correction {
        let _ = writeln!(
            s,
            "                 corrected by {}: usable to {:.0} Hz",
            c.source,
            d.corrected_bandwidth_hz.unwrap_or(f64::NAN)
        );
    }
    if let Some(sr) = &d.spectral_resonance {
        let _ = writeln!(
            s,
            "                 resonance seen in the cut spectrum at {:.0} Hz (damping {}): static relation usable to {:.0} Hz",
            sr.frequency_hz,
            sr.damping.map_or("not fitted".into(), |z| format!("{z:.3}")),
            sr.static_usable_bandwidth_hz.unwrap_or(f64::NAN)
        );
    }
    if let Some(ft) = d.tooth_frequency_hz {
        let _ = writeln!(
            s,
            "                 tooth passing {ft:.1} Hz, harmonics 1-5 up to {:.0} Hz",
            5.0 * ft
        );
    }
    for v in j_.validation.iter().flat_map(|v| &v.per_axis) {
        let _ = writeln!(
            s,
            "validation F{}    RMS error {:.3} N ({:.2} %), peak error {:.3} N, correlation {:.5}",
            v.axis,
            v.rms_error_N,
            100.0 * v.relative_rms_error,
            v.peak_error_N,
            v.correlation
        );
    }
    for w in &j_.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    if let Some(v) = &j_.verdict {
        s += &crate::verdict::verdict_text(v);
    }
    s
}

fn curve(rows: &Thinned, name: &str, c: usize, scale: f64) -> Curve {
    Curve {
        name: name.into(),
        points: rows.rows.iter().map(|(t, v)| (*t, v[c] * scale)).collect(),
    }
}

/// The plots of `shank force` into `dir` (which must exist) as `ext` (svg or png): raw,
/// template, deflection, force, force_zoom.
pub fn force_plots(dir: &Path, ext: &str, report: &ForceReport) -> Result<()> {
    let p = &report.plot;
    let np = p.axes.len();
    let names = &p.sensor_names;
    let raw_panel = Panel {
        y_label: "displacement (µm)".into(),
        curves: names
            .iter()
            .enumerate()
            .map(|(c, n)| curve(&p.raw, n, c, 1e3))
            .collect(),
    };
    stacked_plot(
        &dir.join(format!("raw.{ext}")),
        "Raw displacement signals",
        "time (s)",
        &[raw_panel],
    )?;
    let tpl = Panel {
        y_label: "air-cut template g(θ) (µm)".into(),
        curves: p
            .templates
            .iter()
            .zip(names)
            .map(|(bins, n)| Curve {
                name: n.clone(),
                points: bins
                    .iter()
                    .enumerate()
                    .map(|(b, v)| (360.0 * (b as f64 + 0.5) / bins.len() as f64, v * 1e3))
                    .collect(),
            })
            .collect(),
    };
    stacked_plot(
        &dir.join(format!("template.{ext}")),
        "Angle-synchronous air-cut templates",
        "spindle angle θ (deg)",
        &[tpl],
    )?;
    let defl: Vec<Panel> = p
        .axes
        .iter()
        .enumerate()
        .map(|(d, a)| Panel {
            y_label: format!("{a} deflection (µm)"),
            curves: vec![
                curve(&p.series, "δ_I", np + 2 * d, 1.0),
                curve(&p.series, "δ_II", np + 2 * d + 1, 1.0),
            ],
        })
        .collect();
    stacked_plot(
        &dir.join(format!("deflection.{ext}")),
        "Shank deflections δ_I, δ_II (template subtracted)",
        "time (s)",
        &defl,
    )?;
    let force_panels = |rows: &Thinned| -> Vec<Panel> {
        p.axes
            .iter()
            .enumerate()
            .map(|(d, a)| {
                let mut curves = vec![curve(rows, &format!("F{a} shank"), d, 1.0)];
                if p.has_reference {
                    curves.push(curve(rows, &format!("F{a} reference"), 3 * np + d, 1.0));
                }
                Panel {
                    y_label: format!("F{a} on workpiece (N)"),
                    curves,
                }
            })
            .collect()
    };
    stacked_plot(
        &dir.join(format!("force.{ext}")),
        "Cutting force from shank deflection",
        "time (s)",
        &force_panels(&p.series),
    )?;
    if !p.zoomed.is_empty() {
        let z = Thinned::from_rows(p.zoomed.clone());
        stacked_plot(
            &dir.join(format!("force_zoom.{ext}")),
            "Cutting force, 5 revolutions mid-cut",
            "time (s)",
            &force_panels(&z),
        )?;
    }
    Ok(())
}
