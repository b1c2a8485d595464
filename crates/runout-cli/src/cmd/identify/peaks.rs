//! `runout identify peaks --teeth K --fz-mm F --ae-mm A --diameter-mm D --peaks-N p0,p1,…`:
//! seed 003 per-tooth peak sine fit (methods.md §4.2, eq. 10–12). Flags → [`PeaksRequest`] →
//! [`identify::peaks`] → JSON / text.

use anyhow::{bail, Context, Result};
use runout::identify::{self, render, PeaksRequest};
use runout_core::identify::SineHypothesis;
use runout_io::units::{parse_quantity, Quantity};
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
    /// Write the JSON result (schema runout.identify.peaks/2); `-` for stdout.
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

fn optional(text: &Option<String>, flag: &str, q: Quantity) -> Result<Option<f64>> {
    text.as_deref().map(|t| quantity(t, flag, q)).transpose()
}

/// K peaks once each, or the closed period (`--closed-period`).
pub fn hypothesis(closed_period: bool) -> SineHypothesis {
    if closed_period {
        SineHypothesis::ClosedPeriod
    } else {
        SineHypothesis::Teeth
    }
}

fn request(a: &Args) -> Result<PeaksRequest> {
    let peaks = list(&a.peaks_n, "peaks-N", Quantity::ForceN)?;
    let k = peaks.len();
    if let Some(t) = &a.teeth {
        let t = quantity(t, "teeth", Quantity::Dimensionless)?;
        if t != k as f64 {
            let t = runout_core::limits::show(t);
            bail!("--teeth {t} but --peaks-N has {k} values (one peak per tooth expected)");
        }
    }
    let mut req = PeaksRequest::new(peaks, quantity(&a.fz_mm, "fz-mm", Quantity::LengthMm)?);
    req.mode = a.mode.parse()?;
    req.ae_mm = optional(&a.ae_mm, "ae-mm", Quantity::LengthMm)?;
    req.diameter_mm = optional(&a.diameter_mm, "diameter-mm", Quantity::LengthMm)?;
    req.peak_immersion_deg = optional(
        &a.peak_immersion_deg,
        "peak-immersion-deg",
        Quantity::AngleDeg,
    )?;
    req.peaks_se_N = a
        .peaks_se_n
        .as_deref()
        .map(|se| list(se, "peaks-se-N", Quantity::ForceN))
        .transpose()?;
    req.hypothesis = hypothesis(a.closed_period);
    Ok(req)
}

pub fn run(a: Args) -> Result<()> {
    let report = identify::peaks(&request(&a)?)?;
    super::emit(a.json.as_deref(), &report, || render::peaks(&report))
}
