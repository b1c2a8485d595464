//! `runout displacement <teeth|heights|signal> …`: runout identified in position from displacement
//! readings (methods.md §1, seed 000). Flags → a request of [`runout::displacement`] → the
//! report as JSON, text and plot. Shared flags and output helpers live here; each input kind
//! has its own file.

mod heights;
mod signal;
mod teeth;

use crate::flags::choice;
use anyhow::{bail, Context, Result};
use runout::displacement::Sensor;
use runout_core::displacement::{BeamGeometry, SensorSign};
use runout_core::Cutter;
use runout_io::units::{parse_quantity, Quantity};
use std::path::{Path, PathBuf};

/// Input kinds of `runout displacement`.
#[derive(clap::Subcommand, Debug)]
pub enum Kind {
    /// Per-tooth readings (CSV `tooth,reading_um` or `seed_edge,reading_um`) → offset and angle.
    Teeth(teeth::Args),
    /// Runout at several heights (CSV `z_mm,tir_um[,angle_deg]`) → runout at the cutting height.
    Heights(heights::Args),
    /// Raw signal (CSV `time_s,disp_a_um[,disp_b_um…][,pulse|encoder_deg]`) → runout vector.
    Signal(signal::Args),
}

/// Arguments of `runout displacement`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub kind: Kind,
}

/// Run `runout displacement`.
pub fn run(a: Args) -> Result<()> {
    match a.kind {
        Kind::Teeth(a) => teeth::run(a),
        Kind::Heights(a) => heights::run(a),
        Kind::Signal(a) => signal::run(a),
    }
}

/// Output flags shared by every kind.
#[derive(clap::Args, Debug, Default)]
pub struct OutputFlags {
    /// Write the JSON result (schema `runout.displacement.<kind>/1`); `-` for stdout.
    #[arg(long, allow_hyphen_values = true)]
    pub json: Option<PathBuf>,
    /// Write the human-readable report here instead of stdout (`-` = stdout).
    #[arg(long, allow_hyphen_values = true)]
    pub text: Option<PathBuf>,
    /// Plot (`teeth`, `heights` or `signal`.<format>).
    #[command(flatten)]
    pub plots: crate::flags::PlotFlags,
    #[command(flatten)]
    pub report: crate::cmd::report::ReportFlags,
}

impl OutputFlags {
    /// Refuse outputs that overwrite `input`; the plot file of `kind`.
    pub fn check(&self, input: &Path, kind: &str) -> Result<Option<PathBuf>> {
        let plot = self.plots.file(kind);
        crate::flags::check_outputs([&self.json, &self.text, &plot, &self.report.html], &[input])?;
        Ok(plot)
    }

    /// Write JSON and text (text to stdout unless the JSON goes there).
    pub fn write<R: runout::Report + runout::html::ToSection>(
        &self,
        report: &R,
        text: &str,
    ) -> Result<()> {
        self.report.write(report)?;
        if let Some(j) = &self.json {
            crate::output::write_text(j, &crate::provenance::stamped_json(report)?)?;
        }
        let json_on_stdout = self.json.as_deref() == Some(Path::new("-"));
        match &self.text {
            Some(t) => crate::output::write_text(t, text)?,
            None if !json_on_stdout => crate::output::write_text(Path::new("-"), text)?,
            None => {}
        }
        Ok(())
    }
}

/// Parse an optional flag value of quantity `q`; the error names the flag.
pub fn quantity(flag: &str, v: &Option<String>, q: Quantity) -> Result<Option<f64>> {
    v.as_deref()
        .map(|t| parse_quantity(t, q).with_context(|| format!("--{flag}")))
        .transpose()
}

/// An optional flag in µm (suffixes allowed), returned in mm.
pub fn um_as_mm(flag: &str, v: &Option<String>) -> Result<Option<f64>> {
    Ok(quantity(flag, v, Quantity::LengthUm)?.map(|x| x * 1e-3))
}

/// `--sensor distance|radial`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum SignArg {
    /// The reading grows away from the tool (triangulation lasers).
    Distance,
    /// The reading grows with the radius.
    Radial,
}

/// `--sensor distance|radial` (default distance).
pub fn sensor_sign(v: &Option<String>) -> Result<SensorSign> {
    Ok(
        match v
            .as_deref()
            .map(|t| choice::<SignArg>("--sensor", t))
            .transpose()?
        {
            None | Some(SignArg::Distance) => SensorSign::Distance,
            Some(SignArg::Radial) => SensorSign::Radial,
        },
    )
}

/// Cutter flags shared by teeth and signal: the cutter (the flags of every command) and where
/// it is read.
#[derive(clap::Args, Debug, Default)]
pub struct CutterFlags {
    #[command(flatten)]
    pub cutter: crate::flags::CutterFlags,
    /// Height z of the readings above the tool tip (mm); tooth angles follow the helix.
    #[arg(long, allow_hyphen_values = true)]
    pub height_mm: Option<String>,
    /// Feed per tooth f_z (mm) for the predicted per-tooth chip loads.
    #[arg(long, allow_hyphen_values = true)]
    pub fz_mm: Option<String>,
    /// Diameter of a circular tool path (mm) for the predicted hole diameter.
    #[arg(long, allow_hyphen_values = true)]
    pub hole_path_mm: Option<String>,
}

impl CutterFlags {
    /// The cutter, when --teeth and --diameter-mm are given.
    pub fn cutter(&self) -> Result<Option<Cutter>> {
        self.cutter.cutter()
    }
    /// Height (mm), default 0.
    pub fn height(&self) -> Result<f64> {
        Ok(quantity("height-mm", &self.height_mm, Quantity::LengthMm)?.unwrap_or(0.0))
    }
    /// Feed per tooth (mm) and hole path diameter (mm) for the consequences (§1.7).
    pub fn fz_and_hole(&self) -> Result<(Option<f64>, Option<f64>)> {
        Ok((
            quantity("fz-mm", &self.fz_mm, Quantity::LengthMm)?,
            quantity("hole-path-mm", &self.hole_path_mm, Quantity::LengthMm)?,
        ))
    }
}

/// Beam flags (methods.md §1.4).
#[derive(clap::Args, Debug, Default)]
pub struct BeamFlags {
    /// Sensor output: `distance` (default; grows away from the tool, triangulation lasers) or `radial`.
    #[arg(long, allow_hyphen_values = true)]
    pub sensor: Option<String>,
    /// Beam inclination to the surface normal (deg), seed eq. (9).
    #[arg(long, allow_hyphen_values = true)]
    pub inclination_deg: Option<String>,
    /// Lateral offset of the beam from the spindle axis (mm), methods.md §1.4.
    #[arg(long, allow_hyphen_values = true)]
    pub beam_offset_mm: Option<String>,
}

impl BeamFlags {
    /// The beam geometry.
    pub fn beam(&self) -> Result<BeamGeometry> {
        let inc =
            quantity("inclination-deg", &self.inclination_deg, Quantity::AngleDeg)?.unwrap_or(0.0);
        let b =
            quantity("beam-offset-mm", &self.beam_offset_mm, Quantity::LengthMm)?.unwrap_or(0.0);
        Ok(BeamGeometry::new(inc.to_radians(), b)?)
    }
    /// The sensor: sign convention and beam.
    pub fn sensor(&self) -> Result<Sensor> {
        Ok(Sensor {
            sign: sensor_sign(&self.sensor)?,
            beam: self.beam()?,
        })
    }
}
