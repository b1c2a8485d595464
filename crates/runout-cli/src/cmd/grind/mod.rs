//! `runout grind …`: grinding compensation of the bar clamping error (seed 004, methods.md §5).

mod check;
mod compensate;

use anyhow::{bail, Context, Result};
use runout_core::grind::EdgeLine;
use runout_io::units::{parse_quantity, Quantity};
use std::path::{Path, PathBuf};

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
    /// Number of flutes K.
    #[arg(long, default_value = "4")]
    pub flutes: usize,
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

pub(crate) fn q(flag: &str, text: &str, quantity: Quantity) -> Result<f64> {
    parse_quantity(text, quantity).with_context(|| format!("--{flag}"))
}

pub(crate) fn read(path: &Path, what: &str) -> Result<String> {
    runout_io::textfile::read_text(path).with_context(|| format!("reading {what}"))
}

/// The edge and, for CSV edges, the wheel positions and the CSV path.
pub(crate) type EdgeInput = (EdgeLine, Option<Vec<[f64; 3]>>, Option<PathBuf>);

/// Build the edge; `bar_d` and `u_end` are the defaults for the diameter and the edge end (mm).
pub(crate) fn edge(a: &EdgeFlags, bar_d: f64, u_end: f64) -> Result<EdgeInput> {
    let kind = a.kind.as_str();
    if kind != "flat" && kind != "ball" {
        let p = PathBuf::from(kind);
        let text = read(&p, "edge")?;
        let t = runout_io::grind::read_edge_csv(&text, kind)?;
        for (k, p) in t.points.iter().enumerate() {
            let on_axis = p[0].hypot(p[1]) == 0.0;
            let zero_normal = t.normals.as_ref().is_some_and(|n| n[k] == [0.0; 3]);
            if zero_normal || (on_axis && t.normals.is_none()) {
                bail!(
                    "{kind}, line {}: {} (its offset direction is undefined)",
                    t.lines[k],
                    if zero_normal {
                        "normal (0, 0, 0)"
                    } else {
                        "point on the bar axis without a normal"
                    }
                );
            }
        }
        let e = EdgeLine::from_points(&t.points, t.normals.as_deref())
            .with_context(|| format!("edge {kind}"))?;
        return Ok((e, t.wheel, Some(p)));
    }
    let d = match &a.edge_diameter_mm {
        Some(d) => q("edge-diameter-mm", d, Quantity::LengthMm)?,
        None => bar_d,
    };
    let helix = q("helix-deg", &a.helix_deg, Quantity::AngleDeg)?;
    let z0 = q("edge-from-mm", &a.edge_from_mm, Quantity::LengthMm)?;
    let z1 = match &a.edge_to_mm {
        Some(z) => q("edge-to-mm", z, Quantity::LengthMm)?,
        None => u_end,
    };
    let phase = q("edge-phase-deg", &a.edge_phase_deg, Quantity::AngleDeg)?.to_radians();
    let e = if kind == "flat" {
        EdgeLine::helical_flat(d, a.flutes, helix, z0, z1, a.points_per_flute)?
    } else {
        EdgeLine::ball_end(d, a.flutes, helix, z0, z1, a.points_per_flute)?
    };
    Ok((e.rotated(phase), None, None))
}
