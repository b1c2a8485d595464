//! `runout identify tests TABLE`: several per-tooth peak tests (seed 003 Table 1 style) from a
//! CSV or TOML table → per-test sine fits, regressions, K_T/K_R (seed eq. 17), pooled
//! edge-force-aware fit (methods.md §4.4, §4.6). Flags → [`TestsRequest`] → [`identify::tests`].

use crate::output;
use anyhow::{Context, Result};
use runout::identify::{self, render, TestsDefaults, TestsRequest};
use runout::Source;
use runout_io::units::{parse_quantity, Quantity};
use std::path::PathBuf;

/// Arguments of `runout identify tests`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Table of tests: CSV/TSV (columns test, fz_mm, ap_mm, peak0_N…, optional se0_N…,
    /// fx_at_peak_N, fy_at_peak_N, diameter_mm, ae_mm, mode) or TOML ([[test]] tables).
    pub table: PathBuf,
    /// Cutter diameter D (mm) for tests whose row does not give it.
    #[arg(long, allow_hyphen_values = true)]
    pub diameter_mm: Option<String>,
    /// Radial depth a_e (mm) for tests whose row does not give it.
    #[arg(long, allow_hyphen_values = true)]
    pub ae_mm: Option<String>,
    /// Milling mode up | down | slot for tests whose row does not give it [default up].
    #[arg(long)]
    pub mode: Option<String>,
    /// Peak immersion angle γ (deg) for all tests (default: from the engagement).
    #[arg(long, allow_hyphen_values = true)]
    pub peak_immersion_deg: Option<String>,
    /// Fit K + 1 points per test with the period closed (reproduces the seed's Table 2).
    #[arg(long)]
    pub closed_period: bool,
    /// Write the JSON result (schema runout.identify.tests/1); `-` for stdout.
    #[arg(long, allow_hyphen_values = true)]
    pub json: Option<PathBuf>,
}

fn q(text: &Option<String>, flag: &str, quantity: Quantity) -> Result<Option<f64>> {
    text.as_deref()
        .map(|t| parse_quantity(t, quantity).with_context(|| format!("--{flag}")))
        .transpose()
}

fn request(a: &Args) -> Result<TestsRequest> {
    let mut req = TestsRequest::new(Source::path(&a.table));
    req.defaults = TestsDefaults {
        diameter_mm: q(&a.diameter_mm, "diameter-mm", Quantity::LengthMm)?,
        ae_mm: q(&a.ae_mm, "ae-mm", Quantity::LengthMm)?,
        mode: a
            .mode
            .as_deref()
            .map(str::parse)
            .transpose()
            .context("--mode")?,
        peak_immersion_deg: q(
            &a.peak_immersion_deg,
            "peak-immersion-deg",
            Quantity::AngleDeg,
        )?,
    };
    req.hypothesis = super::peaks::hypothesis(a.closed_period);
    Ok(req)
}

pub fn run(a: Args) -> Result<()> {
    if let Some(j) = &a.json {
        output::check_not_input(j, &[a.table.as_path()])?;
    }
    let report = identify::tests(&request(&a)?)?;
    super::emit(a.json.as_deref(), &report, || render::tests(&report))
}
