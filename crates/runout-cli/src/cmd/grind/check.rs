//! `runout grind check`: the simulation check of methods.md §5.5 — a bar clamped with a known
//! offset + tilt is probed with noise, the edge is ground without compensation, with the seed's
//! bilinear scheme and with the first-harmonic scheme, and the finished edge is measured.

use super::{edge, q, EdgeFlags};
use crate::output;
use anyhow::{bail, Result};
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use runout_core::grind::*;
use runout_io::units::Quantity;
use serde_json::json;
use std::path::PathBuf;

/// Flags of `runout grind check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Bar diameter (mm).
    #[arg(long, allow_hyphen_values = true, default_value = "6")]
    pub bar_diameter_mm: String,
    /// Axis offset at u = 0, bar frame x,y (µm).
    #[arg(long, allow_hyphen_values = true, default_value = "8,-4")]
    pub offset_um: String,
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
    /// Random seed of the probe noise.
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

/// Mean over draws of the grind check for each scheme.
fn mean_checks(
    bar: &SimulatedBar,
    grid: &(Vec<f64>, Vec<f64>),
    edge: &EdgeLine,
    sigma: f64,
    a: &CheckArgs,
    range: RangePolicy,
) -> Result<[GrindCheck; 2]> {
    let mut rng = StdRng::seed_from_u64(a.seed);
    let normal = Normal::new(0.0, sigma)?;
    let zero = GrindCheck {
        interpolation_rms: 0.0,
        interpolation_max: 0.0,
        radius_error_before: 0.0,
        radius_error_after: 0.0,
        profile_before: 0.0,
        profile_after: 0.0,
    };
    let mut acc = [zero; 2];
    let w = 1.0 / a.draws as f64;
    for _ in 0..a.draws {
        let map = DeviationMap::new(&bar.probe(&grid.0, &grid.1, || normal.sample(&mut rng))?);
        for (k, scheme) in [Scheme::Bilinear, Scheme::FirstHarmonic]
            .into_iter()
            .enumerate()
        {
            let f = Interpolator::new(&map, scheme, range);
            let c = grind_check(bar, edge, &compensate(&f, &map.axis, edge, None)?);
            let s = &mut acc[k];
            s.interpolation_rms += w * c.interpolation_rms;
            s.interpolation_max += w * c.interpolation_max;
            s.radius_error_before += w * c.radius_error_before;
            s.radius_error_after += w * c.radius_error_after;
            s.profile_before += w * c.profile_before;
            s.profile_after += w * c.profile_after;
        }
    }
    Ok(acc)
}

pub fn run(a: CheckArgs) -> Result<()> {
    let d = q("bar-diameter-mm", &a.bar_diameter_mm, Quantity::LengthMm)?;
    let off = pair("offset-um", &a.offset_um, Quantity::LengthUm)?;
    let tilt = pair("tilt-um-per-mm", &a.tilt_um_per_mm, Quantity::TiltUmPerMm)?;
    let sigma = q("noise-um", &a.noise_um, Quantity::LengthUm)? * 1e-3;
    runout_core::limits::count(
        "--draws",
        a.draws,
        runout_core::limits::MAX_DRAWS,
        "MAX_DRAWS",
    )?;
    let range = match a.outside.as_str() {
        "clamp" => RangePolicy::Clamp,
        "extrapolate" => RangePolicy::Extrapolate,
        o => bail!("--outside: expected clamp | extrapolate, got `{o}`"),
    };
    let u0 = q("u-from-mm", &a.u_from_mm, Quantity::LengthMm)?;
    let u1 = q("u-to-mm", &a.u_to_mm, Quantity::LengthMm)?;
    if a.edge.kind != "flat" && a.edge.kind != "ball" {
        bail!("--edge: the check generates its edge: flat | ball");
    }
    let bar = SimulatedBar::new(
        d / 2.0,
        [off[0] * 1e-3, off[1] * 1e-3],
        [tilt[0] * 1e-3, tilt[1] * 1e-3],
    )?;
    let grid = uniform_grid(u0, u1, a.layers, a.angles)?;
    let (edge, _, _) = edge(&a.edge, d, u1)?;
    runout_core::limits::work(
        "--draws",
        "evaluations (draws × probe points × edge points)",
        a.draws as f64 * (a.layers * a.angles) as f64 * edge.points.len() as f64,
        runout_core::limits::MAX_EVALUATIONS,
        "MAX_EVALUATIONS",
    )?;
    let [bil, har] = mean_checks(&bar, &grid, &edge, sigma, &a, range)?;
    let um = |x: f64| x * 1e3;
    let row = |c: &GrindCheck| {
        json!({
            "interpolation_rms_um": um(c.interpolation_rms),
            "interpolation_max_um": um(c.interpolation_max),
            "radius_error_after_um": um(c.radius_error_after),
            "profile_error_after_um": um(c.profile_after),
        })
    };
    let report = json!({
        "schema": "runout.grind.check/1",
        "inputs": {
            "bar_diameter_mm": d, "offset_um": off, "tilt_um_per_mm": tilt,
            "layers": a.layers, "angles": a.angles, "u_range_mm": [u0, u1],
            "noise_um": um(sigma), "draws": a.draws, "seed": a.seed,
            "edge": a.edge.kind, "edge_points": edge.points.len(),
            "outside_probed_range": format!("{range:?}"),
        },
        "definitions": "interpolation error ε − e(u)·n against the true axis; radius error max |r − r_nominal| and profile error max − min of the finished edge about the real axis (ball: about the real ball centre); averages over draws",
        "uncompensated": {
            "radius_error_um": um(har.radius_error_before),
            "profile_error_um": um(har.profile_before),
        },
        "bilinear": row(&bil),
        "first_harmonic": row(&har),
    });
    if let Some(j) = &a.json {
        output::write_text(j, &(serde_json::to_string_pretty(&report)? + "\n"))?;
        if j.as_os_str() == "-" {
            return Ok(());
        }
    }
    println!(
        "runout grind check: bar D {d} mm, offset ({}, {}) µm, tilt ({}, {}) µm/mm, M{}×C{} on u {u0}..{u1} mm, noise {} µm, {} draw(s), {} edge points",
        off[0], off[1], tilt[0], tilt[1], a.layers, a.angles, um(sigma), a.draws, edge.points.len()
    );
    println!(
        "                     interp. rms / max (µm)   radius error (µm)   profile error (µm)"
    );
    println!(
        "no compensation      {:>22}   {:>17.3}   {:>18.3}",
        "-",
        um(har.radius_error_before),
        um(har.profile_before)
    );
    for (name, c) in [("seed (bilinear)", &bil), ("first harmonic", &har)] {
        println!(
            "{name:<19}  {:>10.3} / {:>9.3}   {:>17.3}   {:>18.3}",
            um(c.interpolation_rms),
            um(c.interpolation_max),
            um(c.radius_error_after),
            um(c.profile_after)
        );
    }
    Ok(())
}
