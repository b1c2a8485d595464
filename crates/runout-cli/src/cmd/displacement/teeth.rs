//! `runout displacement teeth READINGS.csv`: per-tooth readings → (ρ, λ), methods.md §1.5.

use super::*;
use runout::displacement::{render, teeth, TeethRequest};
use runout::Source;
use runout_core::displacement::{ToothFitOptions, ToothMethod};

/// Arguments of `runout displacement teeth`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// CSV with `tooth` (0-based, cutting order) or `seed_edge` (1-based, seed 000) and
    /// `reading_<um|mm>`; several rows per tooth are averaged (their scatter estimates the noise).
    pub readings: PathBuf,
    #[command(flatten)]
    pub cutter: CutterFlags,
    #[command(flatten)]
    pub beam: BeamFlags,
    /// Method: `joint` (default; K ≥ 3 least squares, K = 2 closed form) or `scan` (the seed's 1° scan, needs --runout-um).
    #[arg(long, allow_hyphen_values = true)]
    pub method: Option<String>,
    /// Runout length ρ at this height from the height regression (µm); required for K = 2 and
    /// `scan`. Old spelling `--offset-um` (hidden, one release).
    #[arg(long, alias = "offset-um", allow_hyphen_values = true)]
    pub runout_um: Option<String>,
    /// Standard error of --runout-um (µm). Old spelling `--offset-se-um`.
    #[arg(long, alias = "offset-se-um", allow_hyphen_values = true)]
    pub runout_se_um: Option<String>,
    /// Sensor noise σ_P of one reading (µm), if known.
    #[arg(long, allow_hyphen_values = true)]
    pub noise_um: Option<String>,
    /// Approximate runout direction from the spindle phase (deg, from tooth 0 in the direction of rotation); resolves the K = 2 mirror ambiguity.
    #[arg(long, allow_hyphen_values = true)]
    pub phase_deg: Option<String>,
    #[command(flatten)]
    pub out: OutputFlags,
}

/// `--method joint|scan`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum MethodArg {
    Joint,
    Scan,
}

pub fn run(a: Args) -> Result<()> {
    let cutter = a
        .cutter
        .cutter()?
        .context("--teeth and --diameter-mm are required")?;
    let sign = sensor_sign(&a.beam.sensor)?;
    let method = match a
        .method
        .as_deref()
        .map(|t| choice::<MethodArg>("--method", t))
        .transpose()?
    {
        None | Some(MethodArg::Joint) => ToothMethod::Joint,
        Some(MethodArg::Scan) => ToothMethod::SeedScan,
    };
    let mut opts = ToothFitOptions::new(cutter);
    opts.height_mm = a.cutter.height()?;
    opts.method = method;
    opts.known_offset_mm = um_as_mm("runout-um", &a.runout_um)?;
    opts.known_offset_se_mm = um_as_mm("runout-se-um", &a.runout_se_um)?;
    opts.noise_mm = um_as_mm("noise-um", &a.noise_um)?;
    opts.beam = a.beam.beam()?;
    opts.phase_hint_rad =
        quantity("phase-deg", &a.phase_deg, Quantity::AngleDeg)?.map(f64::to_radians);
    let (fz_mm, hole_path_mm) = a.cutter.fz_and_hole()?;
    let plot = a.out.check(&a.readings, "teeth")?;
    let mut report = teeth(&TeethRequest {
        readings: Source::path(&a.readings),
        options: opts,
        sign,
        fz_mm,
        hole_path_mm,
    })?;
    a.out.report.judge(&mut report)?;
    crate::exit::from_answer(&report);
    if let Some(p) = &plot {
        a.out.plots.create_dir()?;
        render::teeth_plot(p, &report)?;
    }
    a.out.write(&report, &render::teeth_text(&report))
}
