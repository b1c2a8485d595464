//! `runout grind compensate`: bar clamping-error compensation for end-mill grinding (seed 004,
//! methods.md §5; see [`runout::grind::compensate`]).

use super::{outside, q, EdgeFlags};
use crate::flags::{choice, PlotFormat};
use crate::output;
use anyhow::{bail, Context, Result};
use runout::grind::{
    compensate, render, AngleSense, CompensateRequest, GeneratrixFrom, NcMapping, NcRequest,
};
use runout::Source;
use runout_core::grind::*;
use runout_io::units::Quantity;
use std::path::{Path, PathBuf};

/// Flags of `runout grind compensate`.
#[derive(clap::Args, Debug)]
pub struct CompensateArgs {
    /// Probe table (CSV): `layer` and/or `u_mm`, `angle_deg`, and `radius_mm` or `x_mm,y_mm[,z_mm]`.
    #[arg(long)]
    pub probe: PathBuf,
    /// Sense of the probe table's `angle_deg`, seen from the shank looking at the tip: ccw (the
    /// bar frame: right-handed about the axis towards the shank) | cw (negated on reading; only
    /// `angle_deg` is affected, x/y columns are taken as bar-frame coordinates).
    #[arg(long, default_value = "ccw")]
    pub probe_angle_sense: String,
    /// Nominal bar diameter (mm) for a cylindrical generatrix.
    #[arg(long, allow_hyphen_values = true)]
    pub bar_diameter_mm: Option<String>,
    /// Nominal generatrix table (CSV with `u_mm,radius_mm`) instead of a cylinder.
    #[arg(long)]
    pub generatrix: Option<PathBuf>,
    /// Probe-tip radius (mm) to compensate: Q = tip centre − r·N. 0 if already compensated.
    #[arg(long, allow_hyphen_values = true)]
    pub probe_tip_radius_mm: Option<String>,
    /// A radius farther than this from nominal is a probe miss (µm).
    #[arg(long, allow_hyphen_values = true, default_value = "200")]
    pub miss_limit_um: String,
    /// Duplicate grid points: error | average.
    #[arg(long, default_value = "error")]
    pub duplicates: String,
    /// Missing grid points: error | skip.
    #[arg(long, default_value = "error")]
    pub missing: String,
    /// Interpolation: first-harmonic (exact for offset + tilt) | bilinear (the seed's).
    #[arg(long, default_value = "first-harmonic")]
    pub scheme: String,
    /// Outside the probed u range: clamp | extrapolate.
    #[arg(long, default_value = "clamp")]
    pub outside: String,
    #[command(flatten)]
    pub edge: EdgeFlags,
    /// Input NC program (ISO G-code) whose linear moves are offset.
    #[arg(long)]
    pub nc: Option<PathBuf>,
    /// Output NC program (must not be an input file).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// NC block ↔ offset mapping: `index` (k-th move ↔ k-th edge point) or `xyz` (the move's
    /// X Y Z is a bar-frame point: u = Z, α = atan2(Y, X); rotary axes must stay constant).
    #[arg(long, default_value = "index")]
    pub nc_map: String,
    /// Which NC moves are offset: feed (G1 only) | all (G0 and G1).
    #[arg(long, default_value = "feed")]
    pub nc_moves: String,
    /// Minimum decimals written in rewritten NC coordinates (4 = 0.1 µm).
    #[arg(long, default_value = "4")]
    pub nc_decimals: usize,
    /// Write the compensated path CSV (per point ε_um, wheel before/after, predicted errors); `-` for stdout.
    #[arg(long)]
    pub path_out: Option<PathBuf>,
    /// Write the JSON report; `-` for stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Directory for plots: deviation_heatmap, eps_along_edge, radial_error. Old spelling
    /// `--plots` (hidden, one release).
    #[arg(long, alias = "plots", value_name = "DIR")]
    pub plot_dir: Option<PathBuf>,
    /// Plot format: svg | png.
    #[arg(long, default_value = "svg")]
    pub plot_format: String,
    #[command(flatten)]
    pub report: crate::cmd::report::HtmlFlag,
}

fn options(a: &CompensateArgs) -> Result<ProbeOptions> {
    Ok(ProbeOptions {
        tip_radius_mm: match &a.probe_tip_radius_mm {
            Some(t) => q("probe-tip-radius-mm", t, Quantity::LengthMm)?,
            None => 0.0,
        },
        miss_limit_mm: q("miss-limit-um", &a.miss_limit_um, Quantity::LengthUm)? * 1e-3,
        angle_tolerance: 1e-6,
        duplicates: match choice("--duplicates", &a.duplicates)? {
            Duplicates::Error => DuplicatePolicy::Error,
            Duplicates::Average => DuplicatePolicy::Average,
        },
        missing: match choice("--missing", &a.missing)? {
            Missing::Error => MissingPolicy::Error,
            Missing::Skip => MissingPolicy::Skip,
        },
    })
}

fn scheme(a: &CompensateArgs) -> Result<(Scheme, RangePolicy)> {
    let s = match choice("--scheme", &a.scheme)? {
        SchemeArg::FirstHarmonic => Scheme::FirstHarmonic,
        SchemeArg::Bilinear => Scheme::Bilinear,
    };
    Ok((s, outside(&a.outside)?))
}

/// `--duplicates`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum Duplicates {
    Error,
    Average,
}

/// `--missing`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum Missing {
    Error,
    Skip,
}

/// `--scheme`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum SchemeArg {
    FirstHarmonic,
    Bilinear,
}

/// `--probe-angle-sense`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum Sense {
    Ccw,
    Cw,
}

/// `--nc-map`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum NcMap {
    Index,
    Xyz,
}

/// `--nc-moves`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum NcMoves {
    Feed,
    All,
}

pub fn compensate_cmd(a: CompensateArgs) -> Result<()> {
    let angle_sense = match choice("--probe-angle-sense", &a.probe_angle_sense)? {
        Sense::Ccw => AngleSense::Ccw,
        Sense::Cw => AngleSense::Cw,
    };
    let generatrix = match (&a.generatrix, &a.bar_diameter_mm) {
        (Some(_), Some(_)) => bail!("give --bar-diameter-mm or --generatrix, not both"),
        (None, None) => {
            bail!("give the nominal bar: --bar-diameter-mm D or --generatrix table.csv")
        }
        (None, Some(d)) => GeneratrixFrom::Cylinder(q("bar-diameter-mm", d, Quantity::LengthMm)?),
        (Some(p), None) => GeneratrixFrom::Table(Source::path(p)),
    };
    let (scheme, range) = scheme(&a)?;
    let edge = a.edge.spec()?;
    let mut inputs: Vec<&Path> = vec![a.probe.as_path()];
    inputs.extend(a.generatrix.as_deref());
    let edge_path = PathBuf::from(&a.edge.kind);
    if !a.edge.generated() {
        inputs.push(&edge_path);
    }
    inputs.extend(a.nc.as_deref());
    for out in [&a.out, &a.path_out, &a.json, &a.report.html]
        .into_iter()
        .flatten()
    {
        output::check_not_input(out, &inputs)?;
        if a.nc.as_deref().is_some_and(|n| output::same_file(out, n)) {
            bail!(
                "refusing to write {}: it is the input NC program",
                out.display()
            );
        }
    }
    let nc = match (&a.nc, &a.out) {
        (Some(nc), Some(out)) => Some(NcRequest {
            program: Source::path(nc),
            output: out.display().to_string(),
            mapping: match choice("--nc-map", &a.nc_map)? {
                NcMap::Index => NcMapping::Index,
                NcMap::Xyz => NcMapping::Xyz,
            },
            all_moves: match choice("--nc-moves", &a.nc_moves)? {
                NcMoves::Feed => false,
                NcMoves::All => true,
            },
            decimals: a.nc_decimals,
        }),
        (Some(_), None) => bail!("--nc needs --out for the compensated program"),
        (None, Some(_)) => bail!("--out needs --nc (the program to compensate)"),
        (None, None) => None,
    };
    let plot_format = match &a.plot_dir {
        Some(_) => Some(choice::<PlotFormat>("--plot-format", &a.plot_format)?),
        None => None,
    };
    let report = compensate(&CompensateRequest {
        probe: Source::path(&a.probe),
        angle_sense,
        generatrix,
        options: options(&a)?,
        scheme,
        range,
        edge,
        nc,
    })?;
    crate::exit::from_answer(&report);
    if let (Some(out), Some(text)) = (&a.out, &report.detail.nc_text) {
        output::write_text(out, text)?;
    }
    if let Some(p) = &a.path_out {
        render::compensate_path_csv(output::create(p)?, &report)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    if let (Some(dir), Some(f)) = (&a.plot_dir, plot_format) {
        render::compensate_plots(dir, f.ext(), &report)?;
    }
    a.report.write(&report)?;
    if let Some(j) = &a.json {
        output::write_text(j, &crate::provenance::stamped_json(&report)?)?;
    }
    let to_stdout = |p: &Option<PathBuf>| p.as_deref() == Some(Path::new("-"));
    if !to_stdout(&a.json) && !to_stdout(&a.path_out) {
        print!("{}", render::compensate_text(&report));
    }
    Ok(())
}
