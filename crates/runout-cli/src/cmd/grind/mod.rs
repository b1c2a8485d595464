//! `runout grind …`: grinding compensation of the bar clamping error (seed 004, methods.md §5).
//! Flags → a request of [`runout::grind`] → the report as JSON, text, plots and files.

mod check;
mod compensate;

use anyhow::{Context, Result};
use runout::grind::{EdgeSpec, GeneratedEdge};
use runout::Source;
use runout_io::units::{parse_quantity, Quantity};

/// `runout grind …`
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub command: GrindCommand,
}

/// Grinding subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum GrindCommand {
    /// Compensate the bar clamping error on an edge / wheel path and optionally an NC program.
    Compensate(Box<compensate::CompensateArgs>),
    /// Simulation check (methods.md §5.5): a bar with known offset + tilt + probe noise is probed,
    /// the edge ground with and without compensation; radius and profile errors of both schemes.
    Check(Box<check::CheckArgs>),
}

/// The edge: generated (flat / ball) or read from a CSV.
#[derive(clap::Args, Debug)]
pub struct EdgeFlags {
    /// Edge: `flat` (helical peripheral edge), `ball` (ball end), or a CSV file with
    /// `x_mm,y_mm,z_mm[,nx,ny,nz][,wx_mm,wy_mm,wz_mm]` (bar frame).
    #[arg(long = "edge", default_value = "flat")]
    pub kind: String,
    /// Edge diameter (mm) for flat/ball edges (default: the bar diameter).
    #[arg(long, allow_hyphen_values = true)]
    pub edge_diameter_mm: Option<String>,
    /// Number of teeth (flutes) K (count). Old spelling `--flutes` (hidden, one release).
    #[arg(long, alias = "flutes", default_value = "4")]
    pub teeth: usize,
    /// Helix angle (deg).
    #[arg(long, allow_hyphen_values = true, default_value = "30")]
    pub helix_deg: String,
    /// Edge start, axial position from the tool tip (mm).
    #[arg(long, allow_hyphen_values = true, default_value = "0")]
    pub edge_from_mm: String,
    /// Edge end (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub edge_to_mm: Option<String>,
    /// Points per flute (count).
    #[arg(long, default_value = "200")]
    pub points_per_flute: usize,
    /// Angular position of flute 0 at the tip in the bar frame (deg).
    #[arg(long, allow_hyphen_values = true, default_value = "0")]
    pub edge_phase_deg: String,
}

pub fn run(a: Args) -> Result<()> {
    match a.command {
        GrindCommand::Compensate(c) => compensate::compensate_cmd(*c),
        GrindCommand::Check(c) => check::run(*c),
    }
}

/// `--outside clamp|extrapolate`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum Outside {
    Clamp,
    Extrapolate,
}

/// `--outside`: what happens outside the probed u range.
pub(crate) fn outside(text: &str) -> Result<runout_core::grind::RangePolicy> {
    use runout_core::grind::RangePolicy;
    Ok(match crate::flags::choice("--outside", text)? {
        Outside::Clamp => RangePolicy::Clamp,
        Outside::Extrapolate => RangePolicy::Extrapolate,
    })
}

pub(crate) fn q(flag: &str, text: &str, quantity: Quantity) -> Result<f64> {
    parse_quantity(text, quantity).with_context(|| format!("--{flag}"))
}

impl EdgeFlags {
    /// True for a generated edge (`flat` or `ball`), false for a CSV file.
    pub fn generated(&self) -> bool {
        self.kind == "flat" || self.kind == "ball"
    }

    /// The edge: a CSV source, or the generated edge's parameters.
    pub fn spec(&self) -> Result<EdgeSpec> {
        if !self.generated() {
            return Ok(EdgeSpec::Csv(Source::path(&self.kind)));
        }
        Ok(EdgeSpec::Generated(self.generated_edge()?))
    }

    /// The generated edge's parameters from the flags.
    pub fn generated_edge(&self) -> Result<GeneratedEdge> {
        Ok(GeneratedEdge {
            ball: self.kind == "ball",
            diameter_mm: self
                .edge_diameter_mm
                .as_deref()
                .map(|d| q("edge-diameter-mm", d, Quantity::LengthMm))
                .transpose()?,
            flutes: self.teeth,
            helix_deg: q("helix-deg", &self.helix_deg, Quantity::AngleDeg)?,
            from_mm: q("edge-from-mm", &self.edge_from_mm, Quantity::LengthMm)?,
            to_mm: self
                .edge_to_mm
                .as_deref()
                .map(|z| q("edge-to-mm", z, Quantity::LengthMm))
                .transpose()?,
            points_per_flute: self.points_per_flute,
            phase_rad: q("edge-phase-deg", &self.edge_phase_deg, Quantity::AngleDeg)?.to_radians(),
        })
    }
}
