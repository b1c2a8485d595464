//! `runout grind check`: the simulation check of methods.md §5.5 (see [`runout::grind::check`]).

use super::{q, EdgeFlags};
use crate::output;
use anyhow::{bail, Result};
use runout::grind::{check, render, CheckRequest};
use runout_io::units::Quantity;
use std::path::PathBuf;

/// Flags of `runout grind check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Bar diameter (mm).
    #[arg(long, allow_hyphen_values = true, default_value = "6")]
    pub bar_diameter_mm: String,
    /// Runout (axis offset) length ρ at u = 0 (µm), with --runout-angle-deg; default the offset
    /// x,y = 8,−4 µm.
    #[arg(long, allow_hyphen_values = true, conflicts_with = "offset_um")]
    pub runout_um: Option<String>,
    /// Direction of the runout at u = 0 in the bar frame, from x towards y (deg) [default 0].
    #[arg(
        long,
        allow_hyphen_values = true,
        requires = "runout_um",
        conflicts_with = "offset_um"
    )]
    pub runout_angle_deg: Option<String>,
    /// Deprecated, use --runout-um/--runout-angle-deg: axis offset at u = 0, bar frame x,y (µm).
    #[arg(long, hide = true, allow_hyphen_values = true)]
    pub offset_um: Option<String>,
    /// Axis tilt x,y (µm/mm).
    #[arg(long, allow_hyphen_values = true, default_value = "0.3,0.5")]
    pub tilt_um_per_mm: String,
    /// Probe layers M (count).
    #[arg(long, default_value = "5")]
    pub layers: usize,
    /// Probe angles per layer C (count).
    #[arg(long, default_value = "8")]
    pub angles: usize,
    /// First probe layer u (mm from the tip).
    #[arg(long, allow_hyphen_values = true, default_value = "2")]
    pub u_from_mm: String,
    /// Last probe layer u (mm).
    #[arg(long, allow_hyphen_values = true, default_value = "28")]
    pub u_to_mm: String,
    /// Probe noise, standard deviation (µm).
    #[arg(long, allow_hyphen_values = true, default_value = "0")]
    pub noise_um: String,
    /// Number of probe draws averaged (count).
    #[arg(long, default_value = "1")]
    pub draws: usize,
    /// Random seed of the probe noise (integer).
    #[arg(long, default_value = "1")]
    pub seed: u64,
    /// Outside the probed u range: clamp | extrapolate.
    #[arg(long, default_value = "clamp")]
    pub outside: String,
    #[command(flatten)]
    pub edge: EdgeFlags,
    /// Write the JSON result; `-` for stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

fn pair(flag: &str, text: &str, quantity: Quantity) -> Result<[f64; 2]> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != 2 {
        bail!("--{flag}: expected two comma-separated values x,y, got `{text}`");
    }
    Ok([q(flag, parts[0], quantity)?, q(flag, parts[1], quantity)?])
}

pub fn run(a: CheckArgs) -> Result<()> {
    let bar_diameter_mm = q("bar-diameter-mm", &a.bar_diameter_mm, Quantity::LengthMm)?;
    let offset_um = match (&a.runout_um, &a.offset_um) {
        (Some(rho), _) => runout::grind::offset_xy_um(
            q("runout-um", rho, Quantity::LengthUm)?,
            match &a.runout_angle_deg {
                Some(t) => q("runout-angle-deg", t, Quantity::AngleDeg)?,
                None => 0.0,
            },
        ),
        (None, Some(xy)) => pair("offset-um", xy, Quantity::LengthUm)?,
        (None, None) => [8.0, -4.0],
    };
    let tilt_um_per_mm = pair("tilt-um-per-mm", &a.tilt_um_per_mm, Quantity::TiltUmPerMm)?;
    let noise_um = q("noise-um", &a.noise_um, Quantity::LengthUm)?;
    let range = super::outside(&a.outside)?;
    let u0 = q("u-from-mm", &a.u_from_mm, Quantity::LengthMm)?;
    let u1 = q("u-to-mm", &a.u_to_mm, Quantity::LengthMm)?;
    if !a.edge.generated() {
        bail!("--edge: the check generates its edge: flat | ball");
    }
    let spin = crate::progress::Spinner::new("simulating the grind");
    let report = check(&CheckRequest {
        bar_diameter_mm,
        offset_um,
        tilt_um_per_mm,
        layers: a.layers,
        angles: a.angles,
        u_range_mm: [u0, u1],
        noise_um,
        draws: a.draws,
        seed: a.seed,
        range,
        edge: a.edge.generated_edge()?,
    })?;
    drop(spin);
    crate::exit::from_answer(&report);
    if let Some(j) = &a.json {
        output::write_text(j, &crate::provenance::stamped_json(&report)?)?;
        if j.as_os_str() == "-" {
            return Ok(());
        }
    }
    print!("{}", render::check_text(&report));
    Ok(())
}
