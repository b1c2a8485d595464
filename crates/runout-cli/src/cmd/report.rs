//! `--html FILE` and `--tolerance-um` of the jobs, and `runout report JSON… --html FILE`: the
//! engineer's report ([`runout::html`], issue 15).

use anyhow::{bail, Context, Result};
use runout::html::ToSection;
use runout::verdict::HasVerdict;
use runout_io::units::{parse_quantity, Quantity};
use std::path::{Path, PathBuf};

/// `--html` alone (jobs without a runout verdict).
#[derive(clap::Args, Debug, Default)]
pub struct HtmlFlag {
    /// Write the report as one self-contained HTML page (inline plots and CSS, no script or
    /// network resource; prints on A4).
    #[arg(long, allow_hyphen_values = true)]
    pub html: Option<PathBuf>,
}

impl HtmlFlag {
    /// Write the page of `report` when `--html` is given.
    pub fn write<R: ToSection>(&self, report: &R) -> Result<()> {
        if let Some(p) = &self.html {
            crate::output::write_text(p, &runout::html::render(report)?)?;
        }
        Ok(())
    }
}

/// `--html` and `--tolerance-um` (jobs that identify a runout).
#[derive(clap::Args, Debug, Default)]
pub struct ReportFlags {
    /// Write the report as one self-contained HTML page (verdict, set-up, results, inline plots
    /// and CSS, no script or network resource; prints on A4).
    #[arg(long, allow_hyphen_values = true)]
    pub html: Option<PathBuf>,
    /// Runout tolerance as total indicated runout TIR = 2ρ (µm) for the verdict; default ISO
    /// 15488 class 1: 10 µm for cutters up to 10 mm, 15 µm above.
    #[arg(long, allow_hyphen_values = true)]
    pub tolerance_um: Option<String>,
}

impl ReportFlags {
    /// The tolerance (µm TIR), checked.
    pub fn tolerance_um(&self) -> Result<Option<f64>> {
        tolerance(&self.tolerance_um)
    }

    /// Judge the report's verdict against `--tolerance-um` (before any output is written).
    pub fn judge<R: HasVerdict>(&self, report: &mut R) -> Result<()> {
        report.set_tolerance(self.tolerance_um()?)
    }

    /// Write the page of `report` when `--html` is given.
    pub fn write<R: ToSection>(&self, report: &R) -> Result<()> {
        HtmlFlag {
            html: self.html.clone(),
        }
        .write(report)
    }
}

fn tolerance(v: &Option<String>) -> Result<Option<f64>> {
    let Some(t) = v else { return Ok(None) };
    let um = parse_quantity(t, Quantity::LengthUm).context("--tolerance-um")?;
    if !(um.is_finite() && um > 0.0) {
        bail!("--tolerance-um: expected a tolerance > 0 µm (total indicated runout), got {t}");
    }
    Ok(Some(um))
}

/// Arguments of `runout report`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Saved JSON reports (`--json` of identify, displacement, shank force, grind compensate, chip
    /// compare); several go into one page with a comparison table.
    #[arg(required = true)]
    pub reports: Vec<PathBuf>,
    /// The HTML page to write (`-` = stdout).
    #[arg(long, allow_hyphen_values = true)]
    pub html: PathBuf,
    /// Judge the verdicts again against this tolerance, TIR = 2ρ (µm); default: as saved.
    #[arg(long, allow_hyphen_values = true)]
    pub tolerance_um: Option<String>,
    /// Page title.
    #[arg(long, default_value = "Runout report")]
    pub title: String,
}

/// Run `runout report`.
pub fn run(a: Args) -> Result<()> {
    let inputs: Vec<&Path> = a.reports.iter().map(PathBuf::as_path).collect();
    crate::output::check_not_input(&a.html, &inputs)?;
    let mut texts = Vec::new();
    for p in &a.reports {
        let text = runout_io::textfile::read_text(p)?;
        texts.push((p.display().to_string(), text));
    }
    let sections = runout::html::sections_from_json(&texts, tolerance(&a.tolerance_um)?)?;
    crate::output::write_text(&a.html, &runout::html::page(&a.title, &sections)?)
}
