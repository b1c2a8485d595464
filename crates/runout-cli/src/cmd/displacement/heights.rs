//! `runout displacement heights TABLE.csv`: runout at several heights → runout at the cutting
//! height (methods.md §1.3; §1.6 vector fit when the table has an angle column).

use super::*;
use runout::displacement::{heights, render, HeightsRequest};
use runout::Source;
use runout_core::displacement::HeightRegression;

/// Arguments of `runout displacement heights`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// CSV with `z_<mm>` and `tir_<um>` (total indicated runout) or `runout_<um>` (= TIR/2), optional
    /// `angle_<deg>` (direction of the runout from the spindle phase) for the offset + tilt fit.
    pub table: PathBuf,
    /// Height at which the runout is wanted (mm, same origin as z; the cutting edges).
    #[arg(long, allow_hyphen_values = true)]
    pub at_mm: Option<String>,
    /// Regression: `ols` (default, unbiased) or `eq6` (the seed's eq. 6, paper-compatible, biased).
    #[arg(long, allow_hyphen_values = true)]
    pub method: Option<String>,
    #[command(flatten)]
    pub out: OutputFlags,
}

/// `--method ols|eq6`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum MethodArg {
    Ols,
    Eq6,
}

pub fn run(a: Args) -> Result<()> {
    let at_mm = quantity("at-mm", &a.at_mm, Quantity::LengthMm)?.unwrap_or(0.0);
    let method = match a
        .method
        .as_deref()
        .map(|t| choice::<MethodArg>("--method", t))
        .transpose()?
    {
        None | Some(MethodArg::Ols) => HeightRegression::Ols,
        Some(MethodArg::Eq6) => HeightRegression::SeedEq6,
    };
    let plot = a.out.check(&a.table, "heights")?;
    let mut report = heights(&HeightsRequest {
        table: Source::path(&a.table),
        at_mm,
        method,
    })?;
    a.out.report.judge(&mut report)?;
    crate::exit::from_answer(&report);
    if let Some(p) = &plot {
        a.out.plots.create_dir()?;
        render::heights_plot(p, &report)?;
    }
    a.out.write(&report, &render::heights_text(&report))
}
