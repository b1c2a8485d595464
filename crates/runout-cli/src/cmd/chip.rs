//! `runout chip compare CONFIG` and `runout chip eval CONFIG`: instantaneous undeformed chip
//! thickness (IUCT) with runout, methods.md §2 — exact (eq. 2.2–2.3), arc (2.5), circle
//! intersection (2.6), equivalent (2.8) on 3-axis and 5-axis kinematics (eq. 2.1). Flags → a
//! request of [`runout::chip`] → the report as JSON, text, CSV and plots.

use crate::flags::{choice, config_file, renamed, PlotFlags};
use crate::output;
use anyhow::{bail, Context, Result};
use runout::chip::{compare as compare_job, eval as eval_job, render, ChipModel};
use runout::chip::{CompareRequest, EvalRequest};
use runout::Source;
use std::path::{Path, PathBuf};

/// Arguments of `runout chip`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub command: ChipCommand,
}

/// `runout chip` subcommands.
#[derive(clap::Subcommand, Debug)]
pub enum ChipCommand {
    /// Compare the arc, circle-intersection and equivalent models against the exact IUCT on a
    /// case set (examples/chip/*.toml): errors and throughput.
    Compare(CompareArgs),
    /// Evaluate the chip thickness h along the motion of one case (3-axis or 5-axis toolpath).
    Eval(EvalArgs),
}

/// Arguments of `runout chip compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// Case-set file (TOML: [defaults] and [[case]] tables). Same as --config FILE.
    #[arg(value_name = "CONFIG", required_unless_present = "config_flag")]
    pub config: Option<PathBuf>,
    /// Case-set file (TOML), as the positional CONFIG.
    #[arg(long = "config", value_name = "FILE")]
    pub config_flag: Option<PathBuf>,
    /// Only the cases whose name contains this text (a name, no unit).
    #[arg(long)]
    pub case: Option<String>,
    /// Equivalent model without the effective-edge phase refinement (methods.md §2.4).
    #[arg(long)]
    pub no_phase_refinement: bool,
    /// Also fit (k₁, k₂) per case on 12 calibration angles per tooth and report that model.
    #[arg(long)]
    pub fit_k: bool,
    /// Write the JSON result (schema runout.chip.compare/1); `-` for stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub report: crate::cmd::report::HtmlFlag,
}

/// Arguments of `runout chip eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Case file (TOML, same format as for compare). Same as --config FILE.
    #[arg(value_name = "CONFIG", required_unless_present = "config_flag")]
    pub config: Option<PathBuf>,
    /// Case file (TOML), as the positional CONFIG.
    #[arg(long = "config", value_name = "FILE")]
    pub config_flag: Option<PathBuf>,
    /// Case to evaluate (name contains this text); default the first case.
    #[arg(long)]
    pub case: Option<String>,
    /// Chip-thickness model: exact | equivalent | arc | circle [default exact].
    #[arg(long, allow_hyphen_values = true)]
    pub chip_model: Option<String>,
    /// Deprecated, use --chip-model.
    #[arg(long, hide = true, conflicts_with = "chip_model")]
    pub model: Option<String>,
    /// CSV of h per tooth/height/time (time_s, spindle_angle_deg, tooth, z_mm, h_<model>_mm); `-` for stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Plots: h (µm) vs spindle angle per tooth at one height (`chip_angle.<format>`) and the
    /// map of the peak h (`chip_map.<format>`).
    #[command(flatten)]
    pub plots: PlotFlags,
    /// Height of the angle plot (mm); default the lowest height of the case.
    #[arg(long)]
    pub plot_height_mm: Option<f64>,
    /// Spindle revolutions shown in the angle plot (count).
    #[arg(long, default_value_t = 2.0)]
    pub plot_revolutions: f64,
    /// Map of the peak h per spindle revolution over path time × height, as one file (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// Write the JSON summary (schema runout.chip.eval/1); `-` for stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// A chip-thickness model of `chip eval`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum ModelArg {
    Exact,
    Equivalent,
    Arc,
    Circle,
}

impl From<ModelArg> for ChipModel {
    fn from(m: ModelArg) -> Self {
        match m {
            ModelArg::Exact => ChipModel::Exact,
            ModelArg::Equivalent => ChipModel::Equivalent,
            ModelArg::Arc => ChipModel::Arc,
            ModelArg::Circle => ChipModel::Circle,
        }
    }
}

/// The case file from the positional CONFIG or --config.
fn case_file(positional: &Option<PathBuf>, flag: &Option<PathBuf>) -> Result<Source> {
    config_file(positional, flag)?
        .map(Source::path)
        .context("give the case file (CONFIG or --config FILE)")
}

pub fn run(a: Args) -> Result<()> {
    match a.command {
        ChipCommand::Compare(c) => compare(c),
        ChipCommand::Eval(e) => eval(e),
    }
}

/// Refuse outputs that overwrite one of `inputs`.
fn check_outputs(outputs: &[&Option<PathBuf>], inputs: &[PathBuf]) -> Result<()> {
    let inputs: Vec<&Path> = inputs.iter().map(|p| p.as_path()).collect();
    for out in outputs.iter().copied().flatten() {
        output::check_not_input(out, &inputs)?;
    }
    Ok(())
}

fn compare(a: CompareArgs) -> Result<()> {
    let spin = crate::progress::Spinner::new("comparing the chip models");
    let report = compare_job(&CompareRequest {
        config: case_file(&a.config, &a.config_flag)?,
        case: a.case.clone(),
        phase_refinement: !a.no_phase_refinement,
        fit_k: a.fit_k,
    })?;
    drop(spin);
    for w in &report.warnings {
        crate::progress::warn(w);
    }
    check_outputs(&[&a.json, &a.report.html], &report.inputs)?;
    a.report.write(&report)?;
    if let Some(j) = &a.json {
        output::write_text(j, &crate::provenance::stamped_json(&report)?)?;
    }
    if a.json.as_deref() != Some(Path::new("-")) {
        print!("{}", render::compare_text(&report));
    }
    Ok(())
}

fn eval(a: EvalArgs) -> Result<()> {
    if a.plot_revolutions.is_nan() || a.plot_revolutions <= 0.0 {
        bail!(
            "--plot-revolutions: expected a count > 0, got {}",
            a.plot_revolutions
        );
    }
    let (flag, model) = renamed(("--chip-model", &a.chip_model), ("--model", &a.model));
    let model = model
        .as_deref()
        .map(|t| choice::<ModelArg>(flag, t))
        .transpose()?
        .unwrap_or(ModelArg::Exact)
        .into();
    let spin = crate::progress::Spinner::new("evaluating the chip thickness");
    let report = eval_job(&EvalRequest {
        config: case_file(&a.config, &a.config_flag)?,
        case: a.case.clone(),
        model,
    })?;
    drop(spin);
    let plot = a.plots.file("chip_angle");
    let map = a.map.clone().or_else(|| a.plots.in_dir("chip_map"));
    check_outputs(&[&a.out, &plot, &map, &a.json], &report.detail.inputs)?;
    for w in &report.warnings {
        crate::progress::warn(w);
    }
    if let Some(out) = &a.out {
        render::eval_csv(output::create(out)?, &report)?;
    }
    if plot.is_some() || map.is_some() {
        a.plots.create_dir()?;
    }
    if let Some(p) = &plot {
        render::eval_angle_plot(p, &report, a.plot_height_mm, a.plot_revolutions)?;
    }
    if let Some(p) = &map {
        render::eval_map_plot(p, &report)?;
    }
    if let Some(j) = &a.json {
        output::write_text(j, &crate::provenance::stamped_json(&report)?)?;
    }
    let to_stdout = |p: &Option<PathBuf>| p.as_deref() == Some(Path::new("-"));
    if !to_stdout(&a.json) && !to_stdout(&a.out) {
        print!("{}", render::eval_text(&report));
    }
    Ok(())
}
