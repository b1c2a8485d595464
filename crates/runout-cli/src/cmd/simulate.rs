//! `runout simulate CONFIG.toml [flags]`: mechanistic force simulation with runout.

use crate::flags::{config_file, CutterFlags, PlotFlags};
use crate::output;
use anyhow::{Context, Result};
use runout::simulate::{render, simulate, RecordingOptions, SimulateRequest};
use runout::Source;
use runout_io::config::Layer;
use runout_io::units::{parse_quantity, Quantity};
use std::path::{Path, PathBuf};

/// Flags of `runout simulate`. Every config key is also a flag; flags override the file.
/// Values may carry a unit suffix of the right quantity (`--runout-um 0.008mm`, `--diameter-mm 10mm`).
#[derive(clap::Args, Debug, Default)]
pub struct CaseFlags {
    #[command(flatten)]
    pub cutter: CutterFlags,
    /// Spindle speed (rpm).
    #[arg(long, allow_hyphen_values = true)]
    pub rpm: Option<String>,
    /// Feed per tooth f_z (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub fz_mm: Option<String>,
    /// Axial depth of cut a_p (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub ap_mm: Option<String>,
    /// Radial depth of cut a_e (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub ae_mm: Option<String>,
    /// Milling mode: up | down | slot.
    #[arg(long, allow_hyphen_values = true)]
    pub mode: Option<String>,
    /// Explicit entry immersion angle (deg), instead of --ae-mm/--mode.
    #[arg(long, allow_hyphen_values = true)]
    pub entry_deg: Option<String>,
    /// Explicit exit immersion angle (deg).
    #[arg(long, allow_hyphen_values = true)]
    pub exit_deg: Option<String>,
    /// Runout offset ρ (µm).
    #[arg(long, allow_hyphen_values = true)]
    pub runout_um: Option<String>,
    /// Runout angle λ (deg), from tooth 0 in the direction of rotation.
    #[arg(long, allow_hyphen_values = true)]
    pub runout_angle_deg: Option<String>,
    /// Runout tilt |τ| (µm per mm of height above the tip).
    #[arg(long, allow_hyphen_values = true)]
    pub tilt_um_per_mm: Option<String>,
    /// Tilt direction in the spindle frame (deg).
    #[arg(long, allow_hyphen_values = true)]
    pub tilt_angle_deg: Option<String>,
    /// Tangential shear coefficient K_tc (N/mm²).
    #[arg(long, allow_hyphen_values = true)]
    pub ktc: Option<String>,
    /// Radial shear coefficient K_rc (N/mm²).
    #[arg(long, allow_hyphen_values = true)]
    pub krc: Option<String>,
    /// Axial shear coefficient K_ac (N/mm²).
    #[arg(long, allow_hyphen_values = true)]
    pub kac: Option<String>,
    /// Tangential edge coefficient K_te (N/mm).
    #[arg(long, allow_hyphen_values = true)]
    pub kte: Option<String>,
    /// Radial edge coefficient K_re (N/mm).
    #[arg(long, allow_hyphen_values = true)]
    pub kre: Option<String>,
    /// Axial edge coefficient K_ae (N/mm).
    #[arg(long, allow_hyphen_values = true)]
    pub kae: Option<String>,
}

/// Arguments of `runout simulate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Case file (TOML) with the keys of the flags below (e.g. `diameter_mm = 10`). Optional: a
    /// case can be given by flags alone. Same as --config FILE.
    #[arg(value_name = "CONFIG")]
    pub config: Option<PathBuf>,
    /// Case file (TOML), as the positional CONFIG.
    #[arg(long = "config", value_name = "FILE")]
    pub config_flag: Option<PathBuf>,
    #[command(flatten)]
    pub case: CaseFlags,
    /// Spindle revolutions to simulate (count).
    #[arg(long, allow_hyphen_values = true)]
    pub revolutions: Option<String>,
    /// Angular step (deg).
    #[arg(long, allow_hyphen_values = true)]
    pub step_deg: Option<String>,
    /// Number of axial disks (count).
    #[arg(long, allow_hyphen_values = true)]
    pub disks: Option<String>,
    /// Chip-thickness model: arc | exact | equivalent (methods.md eq. 0.4, 2.2–2.3, 2.8).
    #[arg(long, allow_hyphen_values = true)]
    pub chip_model: Option<String>,
    /// Write the force time series as CSV (time_s, angle_deg, fx_N, fy_N, fz_N, torque_Nm, h<i>_mm); `-` for stdout.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write the JSON summary (inputs, per-tooth peaks, mean forces); `-` for stdout.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Plots: forces vs spindle angle with each tooth's peak marked (`forces.<format>`).
    #[command(flatten)]
    pub plots: PlotFlags,
    #[command(flatten)]
    pub recording: RecordingFlags,
    #[command(flatten)]
    pub sensor: super::simulate_sensor::SensorFlags,
}

/// Options for writing the simulated cut as an instrument recording (a test or example input).
#[derive(clap::Args, Debug, Default)]
pub struct RecordingFlags {
    /// Write the forces as a Kistler DynoWare text export (channels Fx, Fy, Fz in N, workpiece frame).
    #[arg(long)]
    pub recording: Option<PathBuf>,
    /// Sample rate of the recording (Hz); sets the angular step to 360·rpm/(60·rate).
    #[arg(long)]
    pub sample_rate_hz: Option<String>,
    /// Gaussian white noise added to each channel, σ in percent of the peak |F_xy| of the cut.
    #[arg(long, default_value = "0")]
    pub noise_percent: String,
    /// Air cut (no force, noise only) before and after the cut (s).
    #[arg(long, default_value = "0")]
    pub air_cut_s: String,
    /// Seed of the noise generator (integer).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Field delimiter of the recording.
    #[arg(long, value_enum, default_value_t = Delimiter::Comma)]
    pub delimiter: Delimiter,
    /// Write decimal commas (needs --delimiter semicolon or tab).
    #[arg(long)]
    pub decimal_comma: bool,
}

/// Field delimiter of a written recording.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Delimiter {
    #[default]
    Comma,
    Semicolon,
    Tab,
}

impl Delimiter {
    /// The character.
    pub fn char(self) -> char {
        match self {
            Delimiter::Comma => ',',
            Delimiter::Semicolon => ';',
            Delimiter::Tab => '\t',
        }
    }
}

impl CaseFlags {
    /// The flags that were given (and `extra` ones), as a settings layer.
    pub fn layer(&self, extra: &[(&str, &Option<String>)]) -> Layer {
        let c = self;
        let pairs: [(&str, &Option<String>); 17] = [
            ("rpm", &c.rpm),
            ("fz_mm", &c.fz_mm),
            ("ap_mm", &c.ap_mm),
            ("ae_mm", &c.ae_mm),
            ("mode", &c.mode),
            ("entry_deg", &c.entry_deg),
            ("exit_deg", &c.exit_deg),
            ("runout_um", &c.runout_um),
            ("runout_angle_deg", &c.runout_angle_deg),
            ("tilt_um_per_mm", &c.tilt_um_per_mm),
            ("tilt_angle_deg", &c.tilt_angle_deg),
            ("ktc", &c.ktc),
            ("krc", &c.krc),
            ("kac", &c.kac),
            ("kte", &c.kte),
            ("kre", &c.kre),
            ("kae", &c.kae),
        ];
        runout::case::flag_layer(
            c.cutter
                .pairs()
                .into_iter()
                .chain(pairs)
                .chain(extra.iter().copied()),
        )
    }
}

fn parse_flag(flag: &str, text: &str, q: Quantity) -> Result<f64> {
    parse_quantity(text, q).map_err(|e| anyhow::anyhow!("{flag}: {e}"))
}

pub fn run(a: Args) -> Result<()> {
    let flags = a.case.layer(&[
        ("revolutions", &a.revolutions),
        ("step_deg", &a.step_deg),
        ("disks", &a.disks),
        ("chip_model", &a.chip_model),
    ]);
    let config = config_file(&a.config, &a.config_flag)?.map(Source::path);
    let mut req = SimulateRequest::from_config(config.as_ref(), flags)?;
    req.sensor = a.sensor.request()?;
    let r = &a.recording;
    req.sample_rate_hz = r
        .sample_rate_hz
        .as_deref()
        .map(|t| parse_flag("--sample-rate-hz", t, Quantity::FrequencyHz))
        .transpose()?;
    if r.recording.is_some() {
        req.recording = Some(RecordingOptions {
            noise_percent: parse_flag(
                "--noise-percent",
                &r.noise_percent,
                Quantity::Dimensionless,
            )?,
            air_cut_s: parse_flag("--air-cut-s", &r.air_cut_s, Quantity::TimeS)?,
            seed: r.seed,
        });
    }
    let inputs: Vec<&Path> = req.inputs.iter().map(|p| p.as_path()).collect();
    let plot = a.plots.file("forces");
    crate::flags::check_outputs([&a.out, &a.json, &plot, &r.recording], &inputs)?;
    let spin = crate::progress::Spinner::new("simulating");
    let report = simulate(&req)?;
    drop(spin);
    if let Some(out) = &a.out {
        render::forces_csv(output::create(out)?, &report)?;
    }
    if let Some(path) = &r.recording {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let style = runout_io::export::TextStyle {
            delimiter: r.delimiter.char(),
            decimal_comma: r.decimal_comma,
        };
        render::recording(output::create(path)?, &report, &name, style)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(j) = &a.json {
        output::write_text(j, &crate::provenance::stamped_json(&report)?)?;
    }
    if let Some(p) = &plot {
        a.plots.create_dir()?;
        render::plot(p, &report)?;
    }
    let to_stdout = |p: &Option<PathBuf>| p.as_deref() == Some(Path::new("-"));
    if !to_stdout(&a.json) && !to_stdout(&a.out) {
        print!("{}", render::text(&report));
    }
    Ok(())
}
