//! `runout identify peaks --teeth K --fz-mm F --ae-mm A --diameter-mm D --peaks-N p0,p1,…`:
//! seed 003 per-tooth peak sine fit (methods.md §4.2, eq. 10–12).

use super::pm;
use crate::output;
use anyhow::{anyhow, bail, Context, Result};
use runout_core::identify::{sine_fit, PeakConditions, SineFit, SineHypothesis, ToothPeaks};
use runout_core::{Cut, Cutter, MillingMode};
use runout_io::units::{parse_quantity, Quantity};
use serde_json::json;
use std::path::PathBuf;

/// Flags of `runout identify peaks`. Values may carry a unit suffix of the right quantity.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Number of teeth K (must equal the number of peaks).
    #[arg(long, allow_hyphen_values = true)]
    pub teeth: Option<String>,
    /// Feed per tooth f_z (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub fz_mm: String,
    /// Radial depth of cut a_e (mm); not needed with --mode slot or --peak-immersion-deg.
    #[arg(long, allow_hyphen_values = true)]
    pub ae_mm: Option<String>,
    /// Cutter diameter D (mm); not needed with --mode slot or --peak-immersion-deg.
    #[arg(long, allow_hyphen_values = true)]
    pub diameter_mm: Option<String>,
    /// Per-tooth peak forces (N), comma-separated, teeth in cutting order.
    #[arg(long = "peaks-N", allow_hyphen_values = true)]
    pub peaks_n: String,
    /// Per-tooth standard errors of the peaks (N), comma-separated (e.g. revolution scatter/√M).
    #[arg(long = "peaks-se-N", allow_hyphen_values = true)]
    pub peaks_se_n: Option<String>,
    /// Milling mode: up | down | slot [default up, the seed's tests].
    #[arg(long, default_value = "up")]
    pub mode: String,
    /// Immersion angle γ of the peaks (deg); default: the angle of the largest chip
    /// (exit in up-milling, entry in down-milling, 90° in slotting).
    #[arg(long, allow_hyphen_values = true)]
    pub peak_immersion_deg: Option<String>,
    /// Fit K + 1 points with the period closed (F_K = F_0): reproduces the seed's Table 2
    /// (methods.md §4.3). Default: the K peaks once each (plain least squares).
    #[arg(long)]
    pub closed_period: bool,
    /// Write the JSON result (schema runout.identify.peaks/1); `-` for stdout.
    #[arg(long, allow_hyphen_values = true)]
    pub json: Option<PathBuf>,
}

fn list(text: &str, what: &str, q: Quantity) -> Result<Vec<f64>> {
    text.split(',')
        .enumerate()
        .map(|(i, t)| {
            parse_quantity(t, q)
                .with_context(|| format!("--{what}: value {} `{}`", i + 1, t.trim()))
        })
        .collect()
}

fn quantity(text: &str, flag: &str, q: Quantity) -> Result<f64> {
    parse_quantity(text, q).with_context(|| format!("--{flag}"))
}

/// Peak immersion γ (rad) from the flags.
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
        anyhow!("--diameter-mm is needed to find the peak angle in {mode:?} milling (or give --peak-immersion-deg)")
    })?;
    let ae = ae_mm.ok_or_else(|| {
        anyhow!("--ae-mm is needed to find the peak angle in {mode:?} milling (or give --peak-immersion-deg)")
    })?;
    let cutter = Cutter::flat(d, teeth.max(1), 0.0)?;
    let cut = Cut::new(1000.0, fz_mm, 1.0)?.radial(ae, mode, &cutter)?;
    Ok(runout_core::identify::peak_immersion(&cutter, &cut))
}

pub fn run(a: Args) -> Result<()> {
    let peaks = list(&a.peaks_n, "peaks-N", Quantity::ForceN)?;
    let k = peaks.len();
    if let Some(t) = &a.teeth {
        let t = quantity(t, "teeth", Quantity::Dimensionless)?;
        if t != k as f64 {
            bail!("--teeth {t} but --peaks-N has {k} values (one peak per tooth expected)");
        }
    }
    let fz = quantity(&a.fz_mm, "fz-mm", Quantity::LengthMm)?;
    let mode: MillingMode = a.mode.parse()?;
    let ae = a
        .ae_mm
        .as_deref()
        .map(|t| quantity(t, "ae-mm", Quantity::LengthMm))
        .transpose()?;
    let d = a
        .diameter_mm
        .as_deref()
        .map(|t| quantity(t, "diameter-mm", Quantity::LengthMm))
        .transpose()?;
    let explicit = a
        .peak_immersion_deg
        .as_deref()
        .map(|t| quantity(t, "peak-immersion-deg", Quantity::AngleDeg))
        .transpose()?;
    let gamma = peak_angle(mode, ae, d, explicit, fz, k)?;
    let mut tooth_peaks = ToothPeaks::new(peaks.clone())?;
    if let Some(se) = &a.peaks_se_n {
        tooth_peaks = tooth_peaks.with_se(list(se, "peaks-se-N", Quantity::ForceN)?)?;
    }
    let cond = PeakConditions::new(fz, gamma)?;
    let hyp = if a.closed_period {
        SineHypothesis::ClosedPeriod
    } else {
        SineHypothesis::Teeth
    };
    let fit = sine_fit(&tooth_peaks, &cond, hyp)?;
    let inputs = json!({
        "teeth": k,
        "fz_mm": fz,
        "ae_mm": ae,
        "diameter_mm": d,
        "mode": mode,
        "peak_immersion_deg": gamma.to_degrees(),
        "peaks_N": peaks,
        "peaks_se_N": tooth_peaks.se(),
    });
    let j = fit_json(&fit, inputs);
    if let Some(p) = &a.json {
        output::write_text(p, &(serde_json::to_string_pretty(&j)? + "\n"))?;
    }
    if a.json.as_deref() != Some(std::path::Path::new("-")) {
        print_text(&fit, &peaks, gamma);
    }
    Ok(())
}

/// JSON of a sine fit, schema `runout.identify.peaks/1`.
pub fn fit_json(fit: &SineFit, inputs: serde_json::Value) -> serde_json::Value {
    let deg = |v: Option<f64>| v.map(f64::to_degrees);
    let um = |v: Option<f64>| v.map(|x| x * 1e3);
    json!({
        "schema": "runout.identify.peaks/1",
        "method": "seed003 per-tooth peak sine fit F_i = C + A sin(phi + 2 pi i/K) (methods.md 4.2)",
        "hypothesis": fit.hypothesis,
        "inputs": inputs,
        "mean_N": fit.mean.value,
        "mean_N_se": fit.mean.se,
        "amplitude_N": fit.amplitude.value,
        "amplitude_N_se": fit.amplitude.se,
        "phase_deg": fit.phase.value.to_degrees(),
        "phase_deg_se": deg(fit.phase.se),
        "r_squared": fit.r_squared,
        "offset_um": fit.offset.value * 1e3,
        "offset_um_se": um(fit.offset.se),
        "angle_deg": fit.angle.value.to_degrees(),
        "angle_deg_se": deg(fit.angle.se),
        "residual_dof": fit.dof,
        "residual_rms_N": fit.residual_rms,
        "fitted_N": fit.fitted,
        "standard_errors": match fit.error_source {
            runout_core::identify::ErrorSource::PerToothSe => "from the given per-tooth standard errors; A, phi, offset, angle by the delta method",
            runout_core::identify::ErrorSource::Residuals => "from the residuals, sigma^2 = RSS/(K-3); A, phi, offset, angle by the delta method",
            runout_core::identify::ErrorSource::Unavailable => "not available: no residual degrees of freedom (K = 3) and no per-tooth standard errors",
        },
        "warnings": fit.warnings,
    })
}

fn print_text(fit: &SineFit, peaks: &[f64], gamma: f64) {
    println!(
        "runout identify peaks: K = {}, sine fit ({}), peak angle γ = {:.2}°",
        fit.teeth,
        match fit.hypothesis {
            SineHypothesis::Teeth => "K peaks",
            SineHypothesis::ClosedPeriod => "closed period, K + 1 points",
        },
        gamma.to_degrees()
    );
    println!("tooth  peak (N)  fitted (N)");
    for (i, (p, f)) in peaks.iter().zip(&fit.fitted).enumerate() {
        println!("{i:>5}  {p:>8.2}  {f:>10.2}");
    }
    println!(
        "mean C      {:>9.2} N {}",
        fit.mean.value,
        pm(fit.mean.se, 2)
    );
    println!(
        "amplitude A {:>9.2} N {}",
        fit.amplitude.value,
        pm(fit.amplitude.se, 2)
    );
    println!(
        "phase φ     {:>9.2}° {}",
        fit.phase.value.to_degrees(),
        pm(fit.phase.se.map(f64::to_degrees), 2)
    );
    println!("R² = {:.4}, residual dof {}", fit.r_squared, fit.dof);
    println!(
        "runout offset ρ = {:.2} µm {}, angle λ = {:.2}° {} (from tooth 0, in the rotation direction)",
        fit.offset.value * 1e3,
        pm(fit.offset.se.map(|s| s * 1e3), 2),
        fit.angle.value.to_degrees(),
        pm(fit.angle.se.map(f64::to_degrees), 2)
    );
    for w in &fit.warnings {
        println!("warning: {w}");
    }
}
