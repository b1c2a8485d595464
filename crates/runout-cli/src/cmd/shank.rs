//! `runout shank …`: cutting force from two-point shank deflection (seed 002, methods.md §3).
//! Flags → a request of [`runout::shank`] → the report as JSON, text and plots.
//!
//! * `runout shank stiffness --modulus-gpa 210 --diameter-mm 8 --tool-length-mm 65 --l1-mm 10
//!   --l2-mm 30 [--json -]` — K_δ of the beam model (JSON key `stiffness_N_per_um`).
//! * `runout shank force RECORDING --config shank.toml [--out F.csv|F.bin] [--json J|-]
//!   [--plot-dir DIR]` — two streaming passes over the recording (bounded memory), force and
//!   deflections written as computed, runout from the air cuts, validation against a reference.
//! * `runout shank calibrate RECORDING --config shank.toml --force-channel F --load-point-mm A`
//!   — static calibration of K_δ (and the holder term with several load points).

use crate::flags::{choice, PlotFormat};
use crate::output;
use anyhow::{bail, Context, Result};
use runout::shank::{self, render, CalibrateRequest, ForceRequest, LoadPointFrom, SeriesFormat};
use runout::Source;
use runout_io::recording::BinaryLayout;
use runout_io::units::{parse_quantity, Quantity};
use std::path::{Path, PathBuf};

/// `runout shank` subcommands.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    command: Sub,
}

#[derive(clap::Subcommand, Debug)]
enum Sub {
    /// Shank stiffness K_δ = 6EI/[l_II²(3l_tool − l_II) − l_I²(3l_tool − l_I)] (N/µm).
    Stiffness(StiffnessArgs),
    /// Force, deflections and runout from a recording of two displacement sensors per direction.
    Force(ForceArgs),
    /// Static calibration of K_δ from a recording with a known load (load cell channel).
    Calibrate(CalibrateArgs),
}

/// Flags of `runout shank stiffness`.
#[derive(clap::Args, Debug)]
pub struct StiffnessArgs {
    /// Young's modulus E of the shank (GPa, 1–2000).
    #[arg(long, allow_hyphen_values = true)]
    modulus_gpa: String,
    /// Shank diameter d (mm).
    #[arg(long, allow_hyphen_values = true)]
    diameter_mm: String,
    /// Tool length from the holder face to the tool end l_tool (mm).
    #[arg(long, allow_hyphen_values = true)]
    tool_length_mm: String,
    /// Height of sensor I from the holder face l_I (mm).
    #[arg(long, allow_hyphen_values = true)]
    l1_mm: String,
    /// Height of sensor II from the holder face l_II (mm), l_I + 0.001 ≤ l_II ≤ l_tool.
    #[arg(long, allow_hyphen_values = true)]
    l2_mm: String,
    /// Load at mid axial depth, l_tool − a_p/2: the axial depth of cut a_p (mm).
    #[arg(long, allow_hyphen_values = true)]
    ap_mm: Option<String>,
    /// Rotational stiffness of the tool holder k_θ (N·m/rad, 1–1e12); default rigid.
    #[arg(long, allow_hyphen_values = true)]
    holder_stiffness_nm_per_rad: Option<String>,
    /// Density of the tool (kg/m³) for its first bending mode; default 14500 (carbide) if
    /// --modulus-gpa ≥ 400, else 7850 (steel).
    #[arg(long, allow_hyphen_values = true)]
    density_kg_per_m3: Option<String>,
    /// Write JSON here (`-` = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
}

/// `--binary-type`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum BinaryType {
    F32,
    F64,
}

/// Flags of `runout shank force`.
#[derive(clap::Args, Debug)]
pub struct ForceArgs {
    /// The recording (generic CSV/TSV or DynoWare text export).
    recording: PathBuf,
    /// Configuration (shank.toml; see the documentation of `runout_io::config::shank`).
    #[arg(long)]
    config: PathBuf,
    /// Sample rate (Hz) when the file has no time column; overrides the config.
    #[arg(long, allow_hyphen_values = true)]
    sample_rate_hz: Option<String>,
    #[command(flatten)]
    time: crate::flags::TimeFlags,
    /// Write the force/deflection time series: `.csv` (text) or `.bin` (binary layout
    /// runout.binary/1, see --binary-type); `-` = CSV to stdout.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Parse the text recording again in pass 2 instead of keeping a temporary binary copy of
    /// the channels (in the temp directory, ≈ 8 bytes per channel and sample, deleted at the end).
    #[arg(long)]
    reparse: bool,
    /// Element type of a `.bin` output: f32 | f64 (bytes per value 4 | 8).
    #[arg(long, default_value = "f32")]
    binary_type: String,
    /// Write the JSON summary here (`-` = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write plots into this directory: raw, template, deflection, force, force_zoom.
    #[arg(long)]
    plot_dir: Option<PathBuf>,
    /// Plot file type: svg or png.
    #[arg(long, default_value = "svg")]
    plot_format: String,
    #[command(flatten)]
    report: crate::cmd::report::ReportFlags,
}

/// Flags of `runout shank calibrate`.
#[derive(clap::Args, Debug)]
pub struct CalibrateArgs {
    /// Recording with the sensor channels of the first [[pair]] and a load-cell channel.
    recording: PathBuf,
    /// Configuration (shank.toml).
    #[arg(long)]
    config: PathBuf,
    /// Load-cell channel (N), positive towards +axis of the pair (force on the tool).
    #[arg(long)]
    force_channel: String,
    /// Load point from the holder face (mm), if constant.
    #[arg(long, allow_hyphen_values = true)]
    load_point_mm: Option<String>,
    /// Channel with the load point (mm) per sample, for loads at several positions.
    #[arg(long)]
    load_point_channel: Option<String>,
    /// Sample rate (Hz) if the file has no time column.
    #[arg(long, allow_hyphen_values = true)]
    sample_rate_hz: Option<String>,
    /// Write JSON here (`-` = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Run `runout shank …`.
pub fn run(a: Args) -> Result<()> {
    match a.command {
        Sub::Stiffness(s) => stiffness(s),
        Sub::Force(f) => force(f),
        Sub::Calibrate(c) => calibrate(c),
    }
}

fn flag(name: &str, text: &str, q: Quantity) -> Result<f64> {
    parse_quantity(text, q).with_context(|| format!("--{name}"))
}

fn opt_flag(name: &str, text: Option<&str>, q: Quantity) -> Result<Option<f64>> {
    text.map(|t| flag(name, t, q)).transpose()
}

/// Write the JSON (`-` = stdout) and print the text unless the JSON went to stdout.
fn emit<R: runout::Report>(
    json: Option<&Path>,
    report: &R,
    text: impl FnOnce() -> String,
) -> Result<()> {
    if let Some(p) = json {
        output::write_text(p, &crate::provenance::stamped_json(report)?)?;
    }
    if json != Some(Path::new("-")) {
        print!("{}", text());
    }
    Ok(())
}

fn stiffness(a: StiffnessArgs) -> Result<()> {
    let req = shank::StiffnessRequest {
        modulus_gpa: flag("modulus-gpa", &a.modulus_gpa, Quantity::ModulusGpa)?,
        diameter_mm: flag("diameter-mm", &a.diameter_mm, Quantity::LengthMm)?,
        tool_length_mm: flag("tool-length-mm", &a.tool_length_mm, Quantity::LengthMm)?,
        l1_mm: flag("l1-mm", &a.l1_mm, Quantity::LengthMm)?,
        l2_mm: flag("l2-mm", &a.l2_mm, Quantity::LengthMm)?,
        ap_mm: opt_flag("ap-mm", a.ap_mm.as_deref(), Quantity::LengthMm)?,
        holder_stiffness_Nm_per_rad: a
            .holder_stiffness_nm_per_rad
            .as_deref()
            .map(|k| {
                k.trim().parse::<f64>().with_context(|| {
                    format!("--holder-stiffness-nm-per-rad: `{k}` is not a number (N·m/rad)")
                })
            })
            .transpose()?,
        density_kg_per_m3: a
            .density_kg_per_m3
            .as_deref()
            .map(|t| {
                t.trim().parse::<f64>().map_err(|_| {
                    anyhow::anyhow!("--density-kg-per-m3: `{t}` is not a number (kg/m³)")
                })
            })
            .transpose()?,
    };
    let report = shank::stiffness(&req).map_err(stiffness_flag_error)?;
    emit(a.json.as_deref(), &report, || {
        render::stiffness_text(&report)
    })
}

/// A beam parameter out of range, named by its flag as every other flag error is
/// (`--l2-mm (key \`l2_mm\`): expected …`); the load point comes from `--ap-mm`.
fn stiffness_flag_error(e: anyhow::Error) -> anyhow::Error {
    let Some(p) = e.downcast_ref::<runout_core::ParamError>() else {
        return e;
    };
    let flag = match p.param.as_str() {
        "load_point_mm" => "--ap-mm".to_string(),
        "shank" => return e,
        key => format!("--{}", key.replace('_', "-").to_lowercase()),
    };
    anyhow::anyhow!(
        "{flag} (key `{}`): expected {}, got {}",
        p.param,
        p.expected,
        p.got
    )
}

fn force(a: ForceArgs) -> Result<()> {
    let mut req = ForceRequest::new(Source::path(&a.recording), Source::path(&a.config));
    req.sample_rate_hz = opt_flag(
        "sample-rate-hz",
        a.sample_rate_hz.as_deref(),
        Quantity::FrequencyHz,
    )?;
    req.time_var = a.time.time_var.clone();
    req.reparse = a.reparse;
    let html = a.report.html.clone();
    for out in [&a.out, &a.json, &html].into_iter().flatten() {
        output::check_not_input(out, &[&a.recording, &a.config])?;
    }
    if a.plot_dir.is_some() {
        choice::<PlotFormat>("--plot-format", &a.plot_format)?;
    }
    let mut writer = None;
    if let Some(p) = &a.out {
        let format = if p.extension().is_some_and(|e| e == "bin") {
            SeriesFormat::Binary(match choice("--binary-type", &a.binary_type)? {
                BinaryType::F32 => BinaryLayout::F32,
                BinaryType::F64 => BinaryLayout::F64,
            })
        } else {
            SeriesFormat::Csv
        };
        req.series = Some((p.display().to_string(), format));
        writer = Some(output::create(p)?);
    }
    let mut report = shank::force_to(&req, writer, &mut crate::progress::Bars::default())?;
    a.report.judge(&mut report)?;
    crate::exit::from_answer(&report);
    a.report.write(&report)?;
    if let Some(p) = &a.json {
        output::write_text(p, &crate::provenance::stamped_json(&report)?)?;
    }
    if let Some(dir) = &a.plot_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        render::force_plots(dir, &a.plot_format, &report)?;
    }
    if a.json.as_deref() != Some(Path::new("-")) && a.out.as_deref() != Some(Path::new("-")) {
        print!("{}", render::force_text(&report));
    }
    Ok(())
}

fn calibrate(a: CalibrateArgs) -> Result<()> {
    let fixed = opt_flag(
        "load-point-mm",
        a.load_point_mm.as_deref(),
        Quantity::LengthMm,
    )?;
    let load_point = match (fixed, &a.load_point_channel) {
        (Some(mm), None) => LoadPointFrom::Fixed(mm),
        (None, Some(c)) => LoadPointFrom::Channel(c.clone()),
        _ => bail!("give exactly one of --load-point-mm and --load-point-channel"),
    };
    let req = CalibrateRequest {
        recording: Source::path(&a.recording),
        config: Source::path(&a.config),
        force_channel: a.force_channel.clone(),
        load_point,
        sample_rate_hz: opt_flag(
            "sample-rate-hz",
            a.sample_rate_hz.as_deref(),
            Quantity::FrequencyHz,
        )?,
    };
    let report = shank::calibrate(&req)?;
    crate::exit::from_answer(&report);
    if let Some(pj) = &a.json {
        output::check_not_input(pj, &[&a.recording, &a.config])?;
    }
    emit(a.json.as_deref(), &report, || {
        render::calibration_text(&report)
    })
}
