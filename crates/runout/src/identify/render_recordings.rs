//! `identify RECORDING…` as text (what the CLI prints).

use super::recordings::{Calibration, FullSignalReport, RecordingReport, RecordingsReport};
use runout_core::identify::MeanForceCalibration;
use runout_core::RadiusProfile;
use std::fmt::Write;

fn pm(se: Option<f64>, scale: f64, digits: usize) -> String {
    se.filter(|s| s.is_finite())
        .map_or_else(|| "(no SE)".into(), |s| format!("± {:.digits$}", s * scale))
}

/// The profile in the config vocabulary (`profile = …`, `corner_radius_mm`, `taper_deg`).
fn profile_label(p: &RadiusProfile) -> String {
    match p {
        RadiusProfile::Flat => "flat".into(),
        RadiusProfile::Ball => "ball".into(),
        RadiusProfile::BullNose { corner_mm } => {
            format!("bull_nose (corner radius {corner_mm} mm)")
        }
        RadiusProfile::Tapered { taper_deg } => format!("tapered ({taper_deg}°)"),
    }
}

/// The answer block that opens the report.
fn answer_text(a: &super::Answer) -> String {
    let mut s = String::new();
    let rho = match (a.runout.offset_um, a.runout.angle_deg) {
        (Some(o), Some(l)) => format!(
            "runout ρ = {o:.2} {} µm at λ = {l:.1} {}° (from tooth 0, in the rotation direction)",
            pm(a.runout.offset_um_se, 1.0, 2),
            pm(a.runout.angle_deg_se, 1.0, 1)
        ),
        (Some(o), None) => format!(
            "runout ρ = {o:.2} {} µm, angle λ {}",
            pm(a.runout.offset_um_se, 1.0, 2),
            if a.runout.angle == "along the tooth line only" {
                "not observable: offset along the tooth line only".to_string()
            } else {
                "not identified".to_string()
            }
        ),
        _ => "runout not identified".to_string(),
    };
    let _ = writeln!(s, "\nANSWER: {rho}");
    let _ = writeln!(s, "  status: {}", a.status);
    let _ = writeln!(s, "  method: {}", a.method);
    let ok: Vec<String> = a
        .coefficients
        .iter()
        .filter_map(|c| {
            c.value
                .map(|v| format!("{} {v:.1} {} {}", c.name, pm(c.value_se, 1.0, 1), c.unit))
        })
        .collect();
    if !ok.is_empty() {
        let _ = writeln!(s, "  coefficients: {}", ok.join(", "));
    }
    let not: Vec<&str> = a
        .coefficients
        .iter()
        .filter(|c| c.value.is_none())
        .map(|c| c.name.as_str())
        .collect();
    if !not.is_empty() {
        let _ = writeln!(s, "  not identified: {} (see reasons)", not.join(", "));
    }
    for r in &a.reasons {
        let _ = writeln!(s, "  reason: {r}");
    }
    for w in &a.warnings {
        let _ = writeln!(s, "  warning: {w}");
    }
    s
}

/// True when every recording is a full slot (entry 0°, exit 180°), where the mean-force
/// calibration is unbiased by runout.
fn slotting(r: &RecordingsReport) -> bool {
    r.recordings
        .iter()
        .all(|c| c.entry_deg.abs() < 1e-7 && (c.exit_deg - 180.0).abs() < 1e-7)
}

/// The report as text.
pub fn recordings_text(r: &RecordingsReport) -> String {
    let i = &r.inputs;
    let mut s = format!(
        "runout identify: K = {}, D = {} mm, helix {:.1}°, profile {}\n",
        i.teeth,
        i.diameter_mm,
        i.helix_deg,
        profile_label(&i.profile)
    );
    s += &answer_text(&r.answer);
    s += "\ndetails (the per-recording sine fits are cross-checks, not the answer):\n";
    for f in &r.recordings {
        s += &recording_text(f);
    }
    s += &calibration_text(r);
    let _ = writeln!(s, "measuring chain: {}", r.measuring_chain.decision.reason);
    if let (Some(c), Some(f)) = (&r.measuring_chain.fit, r.full_signal.ok()) {
        for m in &c.modes {
            let _ = writeln!(
                s,
                "  mode on {}: {:.1} {} Hz, ζ {:.4} {}",
                crate::words::plain(&m.axis),
                m.frequency_hz.value,
                pm(m.frequency_hz.se, 1.0, 1),
                m.damping.value,
                pm(m.damping.se, 1.0, 4)
            );
        }
        let _ = writeln!(
            s,
            "  harmonics fitted: 0..{} of the spindle frequency; R² {:.4} (rigid model on the same band {:.4})",
            c.max_harmonic.iter().max().unwrap_or(&0),
            f.r_squared,
            c.rigid_r_squared
        );
    }
    for n in &r.tooth_numbering_aligned {
        let _ = writeln!(
            s,
            "tooth numbering of {} shifted by {} tooth pitch(es) to agree with the other recordings",
            r.recordings[n.recording].file, n.shifted_by_teeth
        );
    }
    match &r.full_signal {
        super::Fitted::Fit(f) => s += &fit_text(r, f),
        super::Fitted::Failed { error } => {
            let _ = writeln!(s, "full-signal fit: failed: {error}");
        }
    }
    if let Some(v) = &r.verdict {
        s += &crate::verdict::verdict_text(v);
    }
    s
}

fn recording_text(f: &RecordingReport) -> String {
    let mut s = format!(
        "\n{} ({} samples at {} Hz; axes {})\n",
        f.file, f.samples, f.sample_rate_hz, f.axes
    );
    let sp = &f.spindle;
    let _ = writeln!(
        s,
        "  spindle {:.2} ± {:.2} rpm (nominal {:.0}, {:+.2} %); steady cut {:.3}–{:.3} s{}, {} revolutions averaged",
        sp.rpm,
        sp.rpm_se,
        sp.nominal_rpm,
        sp.deviation_percent,
        f.section.from_s,
        f.section.to_s,
        if f.section.overridden { " (given)" } else { " (detected)" },
        f.revolutions_averaged
    );
    let peaks: Vec<String> = f
        .tooth_peaks
        .iter()
        .map(|p| format!("{:.1} ± {:.1}", p.peak_N, p.peak_N_se))
        .collect();
    let _ = writeln!(
        s,
        "  per-tooth peaks of {} (N): {}",
        f.peak_component,
        peaks.join(", ")
    );
    match &f.sine_fit {
        super::Fitted::Fit(x) => {
            let _ = writeln!(
                s,
                "  sine fit (seed 003, cross-check): ρ = {:.2} {} µm, λ = {:.1} {}°, R² = {:.4}",
                x.offset_um,
                pm(x.offset_um_se, 1.0, 2),
                x.angle_deg,
                pm(x.angle_deg_se, 1.0, 1),
                x.r_squared
            );
            let slot = f.entry_deg.abs() < 1e-7 && (f.exit_deg - 180.0).abs() < 1e-7;
            let _ = writeln!(
                s,
                "    {}",
                if slot {
                    "(peaks of the resultant only: edge forces and helix are not in its model)"
                } else {
                    "(biased at partial immersion: edge forces are not in its model)"
                }
            );
        }
        super::Fitted::Failed { error } => {
            let _ = writeln!(s, "  sine fit (seed 003): not available: {error}");
        }
    }
    if let Some(d) = f.radius_difference_um {
        let _ = writeln!(
            s,
            "  radius difference R₀ − R₁ from the two peaks: {d:.2} {} µm (how unevenly the teeth cut; λ needs the full-signal fit)",
            pm(f.radius_difference_um_se, 1.0, 2)
        );
    }
    for w in &f.warnings {
        let _ = writeln!(s, "  warning: {w}");
    }
    s
}

fn calibration_text(r: &RecordingsReport) -> String {
    match &r.mean_force_calibration {
        Calibration::Fitted(k) => {
            let k: &MeanForceCalibration = k.as_ref();
            format!(
                "\nmean-force calibration: K_tc {:.1}, K_rc {:.1} N/mm², K_te {:.2}, K_re {:.2} N/mm{}\n",
                k.ktc.value,
                k.krc.value,
                k.kte.value,
                k.kre.value,
                if slotting(r) {
                    ""
                } else {
                    "\n  (start value only: with runout at partial immersion teeth lose contact near sin φ = 0, which biases it; the full-signal fit models this)"
                }
            )
        }
        Calibration::Skipped { skipped } => {
            format!("\nmean-force calibration: skipped ({skipped})\n")
        }
    }
}

fn fit_text(r: &RecordingsReport, f: &FullSignalReport) -> String {
    let v = &r.status;
    let status = |p: &str| v.parameters.iter().find(|x| x.parameter == p);
    let shown = |p: &str| status(p).is_none_or(|x| x.status == "identified");
    let head = if shown("offset") && shown("angle") {
        "full-signal fit (the answer's source)"
    } else {
        "full-signal fit (NOT IDENTIFIED, see below)"
    };
    let mut s = format!(
        "{head}: ρ = {:.2} {} µm, λ = {:.1} {}° (from tooth 0, in the rotation direction)\n",
        f.offset_um,
        pm(f.offset_um_se, 1.0, 2),
        f.angle_deg,
        pm(f.angle_deg_se, 1.0, 1)
    );
    if let Some(d) = r.fitted_radius_difference_um {
        let _ = writeln!(
            s,
            "  radius difference R₀ − R₁ of the fitted runout: {d:.2} µm"
        );
        for w in &r.radius_difference_warnings {
            let _ = writeln!(s, "  warning: {w}");
        }
    }
    let names = ["K_tc", "K_rc", "K_ac", "K_te", "K_re", "K_ae"];
    let keys = ["ktc", "krc", "kac", "kte", "kre", "kae"];
    let units = ["N/mm²", "N/mm²", "N/mm²", "N/mm", "N/mm", "N/mm"];
    let parts: Vec<String> = f
        .coefficients
        .all()
        .iter()
        .enumerate()
        .map(|(i, (c, se))| {
            let value = format!("{c:.1} {} {}", pm(*se, 1.0, 1), units[i]);
            let rejected = r
                .answer
                .coefficients
                .get(i)
                .is_some_and(|a| a.value.is_none());
            if (se.is_some() && !shown(keys[i])) || rejected {
                format!("{} not identified ({value})", names[i])
            } else {
                format!("{} {value}", names[i])
            }
        })
        .collect();
    let _ = writeln!(s, "  {}", parts.join(", "));
    let _ = writeln!(
        s,
        "  residual RMS {:.2} N, R² {:.4}, condition {:.2e}{}",
        f.residual_rms_N,
        f.r_squared,
        f.condition,
        if f.ill_conditioned {
            " (ILL-CONDITIONED)"
        } else {
            ""
        }
    );
    for w in &f.warnings {
        let _ = writeln!(s, "  warning: {w}");
    }
    for x in &v.fit {
        let _ = writeln!(s, "  NOT IDENTIFIED (any parameter): {x}");
    }
    for x in &v.parameters {
        if let Some(why) = &x.reason {
            let _ = writeln!(s, "  not identified: {}: {why}", x.parameter);
        }
    }
    if let Some(c) = &r.consistency {
        let _ = writeln!(
            s,
            "  per recording (coefficients and chain of the joint fit held): ρ spread {:.1} %, λ spread {:.1}°",
            c.offset_spread_percent, c.angle_spread_deg
        );
        for x in &c.recordings {
            let _ = writeln!(
                s,
                "    {}: ρ = {:.2} {} µm, λ = {:.1} {}°{}",
                x.file,
                x.offset_um,
                pm(x.offset_um_se, 1.0, 2),
                x.angle_deg,
                pm(x.angle_deg_se, 1.0, 1),
                if x.disagrees { "  (DISAGREES)" } else { "" }
            );
        }
        for w in &c.warnings {
            let _ = writeln!(s, "  warning: {w}");
        }
    }
    s
}
