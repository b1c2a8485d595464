//! `runout shank …`: cutting force from two-point shank deflection (seed 002, methods.md §3).
//!
//! * `runout shank stiffness --modulus-gpa 210 --diameter-mm 8 --tool-length-mm 65 --l1-mm 10
//!   --l2-mm 30 [--json -]` — K_δ of the beam model (JSON key `stiffness_N_per_um`).
//! * `runout shank force RECORDING --config shank.toml [--out F.csv|F.bin] [--json J|-]
//!   [--plot-dir DIR]` — two streaming passes over the recording (bounded memory), force and
//!   deflections written as computed, runout from the air cuts, validation against a reference.
//! * `runout shank calibrate RECORDING --config shank.toml --force-channel F --load-point-mm A`
//!   — static calibration of K_δ (and the holder term with several load points).

use crate::output;
use anyhow::{bail, Context, Result};
use runout_core::shank::{
    analyse, calibrate, LoadPoint, LoadStep, OutputBlock, PairAxis, Reconstructor, SensorPair,
    ShankAnalysis, ShankBeam, ShankSetup, Survey,
};
use runout_io::config::shank::{number, ShankConfig};
use runout_io::lineplot::{stacked_plot, Curve, Panel};
use runout_io::recording::{
    AxisMapping, BinaryLayout, BinaryWriter, Chunk, CsvWriter, ReadOptions, RecordingError,
    RecordingInfo, RecordingReader,
};
use runout_io::units::{parse_quantity, Quantity};
use serde_json::json;
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
    /// Young's modulus E of the shank (GPa).
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
    /// Height of sensor II from the holder face l_II (mm), l_I < l_II ≤ l_tool.
    #[arg(long, allow_hyphen_values = true)]
    l2_mm: String,
    /// Load at mid axial depth, l_tool − a_p/2: the axial depth of cut a_p (mm).
    #[arg(long, allow_hyphen_values = true)]
    ap_mm: Option<String>,
    /// Rotational stiffness of the tool holder k_θ (N·m/rad); default rigid.
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
    /// Write the force/deflection time series: `.csv` (text) or `.bin` (binary layout
    /// runout.binary/1, see --binary-type); `-` = CSV to stdout.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Parse the text recording again in pass 2 instead of keeping a temporary binary copy of
    /// the channels (in the temp directory, ≈ 8 bytes per channel and sample, deleted at the end).
    #[arg(long)]
    reparse: bool,
    /// Element type of a `.bin` output: f32 or f64.
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
        Sub::Calibrate(c) => calibrate_cmd(c),
    }
}

fn flag(name: &str, text: &str, q: Quantity) -> Result<f64> {
    parse_quantity(text, q).with_context(|| format!("--{name}"))
}

fn stiffness(a: StiffnessArgs) -> Result<()> {
    let mut beam = ShankBeam::new(
        flag("modulus-gpa", &a.modulus_gpa, Quantity::ModulusGpa)?,
        flag("diameter-mm", &a.diameter_mm, Quantity::LengthMm)?,
        flag("tool-length-mm", &a.tool_length_mm, Quantity::LengthMm)?,
        flag("l1-mm", &a.l1_mm, Quantity::LengthMm)?,
        flag("l2-mm", &a.l2_mm, Quantity::LengthMm)?,
    )?;
    if let Some(ap) = &a.ap_mm {
        beam = beam.with_load_point(LoadPoint::MidDepth {
            axial_depth_mm: flag("ap-mm", ap, Quantity::LengthMm)?,
        })?;
    }
    if let Some(k) = &a.holder_stiffness_nm_per_rad {
        let k: f64 = k.trim().parse().with_context(|| {
            format!("--holder-stiffness-nm-per-rad: `{k}` is not a number (N·m/rad)")
        })?;
        beam = beam.with_holder_stiffness(k * 1e3)?;
    }
    let k = beam.stiffness_n_per_um();
    let density = match &a.density_kg_per_m3 {
        Some(t) => t
            .trim()
            .parse::<f64>()
            .map_err(|_| anyhow::anyhow!("--density-kg-per-m3: `{t}` is not a number (kg/m³)"))?,
        None => runout_core::shank::default_density_kg_per_m3(beam.modulus_n_per_mm2 / 1e3),
    };
    let f1 = beam
        .first_bending_mode_hz(density)
        .context("--density-kg-per-m3")?;
    let mode = runout_core::chain::SensorMode::new(f1, 0.03, 1.0)?;
    let band = runout_core::shank::usable_bandwidth_hz(
        &runout_core::chain::AxisChain::Modes(vec![mode]),
        None,
        10.0 * f1,
    );
    let j = json!({
        "schema": "runout.shank.stiffness/1",
        "first_bending_mode_hz": f1,
        "density_kg_per_m3": density,
        "usable_bandwidth_hz": band,
        "bandwidth_criterion": "|H(f) - 1| <= 10 % for one mode at f1, damping 0.03 (docs/shank.md)",
        "stiffness_N_per_um": k,
        "stiffness_N_per_mm": beam.stiffness_n_per_mm(),
        "second_moment_mm4": beam.second_moment_mm4(),
        "load_point_mm": beam.load_distance_mm(),
        "holder_stiffness_Nm_per_rad": beam.holder_rotational_stiffness_nmm_per_rad.map(|k| k / 1e3),
        "inputs": {
            "modulus_gpa": beam.modulus_n_per_mm2 / 1e3,
            "diameter_mm": beam.diameter_mm,
            "tool_length_mm": beam.tool_length_mm,
            "l1_mm": beam.l1_mm,
            "l2_mm": beam.l2_mm,
        },
        "formula": "K = 6EI / [l2^2(3a - l2) - l1^2(3a - l1) + 6EI(l2 - l1)a/k_theta], I = pi d^4/64 (methods.md 3.1)",
    });
    if let Some(p) = &a.json {
        output::write_text(p, &(serde_json::to_string_pretty(&j)? + "\n"))?;
    }
    if a.json.as_deref() != Some(Path::new("-")) {
        println!(
            "K_delta = {k:.6} N/um  (I = {:.2} mm^4, load at {} mm from the holder face)",
            beam.second_moment_mm4(),
            beam.load_distance_mm()
        );
        println!(
            "first bending mode {f1:.0} Hz ({density} kg/m^3): static force usable to {band:.0} Hz (|H - 1| <= 10 %)"
        );
    }
    Ok(())
}

/// Everything resolved from shank.toml.
struct Resolved {
    setup: ShankSetup,
    density_source: String,
    cfg: ShankConfig,
    stiffness_source: String,
    sensor_unit: Option<String>,
    sensitivity_um_per_v: Option<f64>,
    sample_rate_hz: Option<f64>,
}

fn load_config(path: &Path, rate_flag: Option<&str>) -> Result<Resolved> {
    let file = path.display().to_string();
    let text =
        runout_io::textfile::read_text(path).with_context(|| format!("reading config {file}"))?;
    let cfg = ShankConfig::parse(&file, &text)?;
    let b = &cfg.shank;
    let n = |key: &str, v: &runout_io::config::Value, q| number(&file, key, v, q);
    let mut beam = ShankBeam::new(
        n("modulus_gpa", &b.modulus_gpa, Quantity::ModulusGpa)?,
        n("diameter_mm", &b.diameter_mm, Quantity::LengthMm)?,
        n("tool_length_mm", &b.tool_length_mm, Quantity::LengthMm)?,
        n("l1_mm", &b.l1_mm, Quantity::LengthMm)?,
        n("l2_mm", &b.l2_mm, Quantity::LengthMm)?,
    )
    .with_context(|| format!("{file}: [shank]"))?;
    let ap = b
        .axial_depth_mm
        .as_ref()
        .map(|v| n("axial_depth_mm", v, Quantity::LengthMm))
        .transpose()?;
    match b.load_point.as_deref() {
        None | Some("tip") => {}
        Some("mid-depth") => {
            let Some(ap) = ap else {
                bail!("{file}: load_point = \"mid-depth\" needs axial_depth_mm");
            };
            beam = beam.with_load_point(LoadPoint::MidDepth { axial_depth_mm: ap })?;
        }
        Some(o) => bail!("{file}: load_point = `{o}`: expected \"tip\" or \"mid-depth\""),
    }
    if let Some(k) = &b.holder_stiffness_nm_per_rad {
        let k =
            n("holder_stiffness_Nm_per_rad", k, Quantity::Dimensionless).or_else(|_| match k {
                runout_io::config::Value::Number(x) => Ok(*x),
                runout_io::config::Value::Text(t) => t.trim().parse::<f64>().map_err(|_| {
                    anyhow::anyhow!("{file}: holder_stiffness_Nm_per_rad = `{t}` is not a number")
                }),
            })?;
        beam = beam.with_holder_stiffness(k * 1e3)?;
    }
    let (stiffness, source) = match &b.stiffness_n_per_um {
        Some(v) => {
            let k = match v {
                runout_io::config::Value::Number(x) => *x,
                runout_io::config::Value::Text(t) => t
                    .trim()
                    .trim_end_matches("N/um")
                    .trim()
                    .parse()
                    .map_err(|_| {
                        anyhow::anyhow!(
                            "{file}: stiffness_N_per_um = `{t}` is not a number of N/µm"
                        )
                    })?,
            };
            if !(k.is_finite() && k > 0.0) {
                bail!("{file}: stiffness_N_per_um must be > 0, got {k}");
            }
            (
                k * 1e3,
                "stiffness_N_per_um from the config (static calibration)".to_string(),
            )
        }
        None => (
            beam.stiffness_n_per_mm(),
            "beam formula (methods.md 3.1)".to_string(),
        ),
    };
    if cfg.pair.is_empty() || cfg.pair.len() > 2 {
        bail!(
            "{file}: give one or two [[pair]] sections (x and/or y), found {}",
            cfg.pair.len()
        );
    }
    let mut pairs = Vec::new();
    for p in &cfg.pair {
        let axis = match p.axis.trim() {
            "x" | "X" => PairAxis::X,
            "y" | "Y" => PairAxis::Y,
            o => {
                bail!("{file}: [[pair]] axis = `{o}`: expected \"x\" (feed) or \"y\" (feed-normal)")
            }
        };
        if p.sign != 1.0 && p.sign != -1.0 {
            bail!("{file}: [[pair]] sign = {}: expected 1 or -1", p.sign);
        }
        if pairs.iter().any(|q: &SensorPair| q.axis == axis) {
            bail!("{file}: two [[pair]] sections for axis {}", axis.letter());
        }
        pairs.push(SensorPair { axis, sign: p.sign });
    }
    let rpm = n("rpm", &cfg.spindle.rpm, Quantity::SpeedRpm)?;
    let rate = match rate_flag {
        Some(t) => Some(flag("sample-rate-hz", t, Quantity::FrequencyHz)?),
        None => cfg
            .recording
            .sample_rate_hz
            .as_ref()
            .map(|v| n("sample_rate_hz", v, Quantity::FrequencyHz))
            .transpose()?,
    };
    let pr = &cfg.processing;
    let mut setup = ShankSetup::new(beam, pairs, rate.unwrap_or(1.0), rpm);
    setup.stiffness_n_per_mm = stiffness;
    setup.has_pulse = cfg.spindle.pulse_channel.is_some();
    setup.has_reference = cfg.recording.reference_axes.is_some();
    setup.air_cut_s = pr
        .air_cut_s
        .clone()
        .unwrap_or_default()
        .into_iter()
        .map(|[a, b]| (a, b))
        .collect();
    setup.drift_correction = pr.drift_correction;
    if let Some(hz) = &pr.lowpass_hz {
        setup.lowpass = Some((
            pr.lowpass_order.unwrap_or(4),
            n("lowpass_hz", hz, Quantity::FrequencyHz)?,
        ));
    }
    setup.sensor_range_mm = pr.sensor_range_um.map(|[a, b]| (a * 1e-3, b * 1e-3));
    if let Some(m) = pr.min_air_revolutions {
        setup.min_air_revolutions = m;
    }
    if let Some(m) = pr.max_template_revolutions {
        setup.max_template_revolutions = m.max(setup.min_air_revolutions);
    }
    setup.cutting_height_mm = ap.map_or(0.0, |a| a / 2.0);
    let density_source = resolve_dynamics(&file, path, &cfg, &mut setup)?;
    let sensitivity = cfg
        .recording
        .sensitivity_um_per_v
        .as_ref()
        .map(|v| {
            n("sensitivity_um_per_V", v, Quantity::Dimensionless).or_else(|_| match v {
                runout_io::config::Value::Number(x) => Ok(*x),
                _ => Err(anyhow::anyhow!(
                    "{file}: sensitivity_um_per_V must be a number"
                )),
            })
        })
        .transpose()?;
    Ok(Resolved {
        density_source,
        sensor_unit: cfg.recording.sensor_unit.clone(),
        sensitivity_um_per_v: sensitivity,
        sample_rate_hz: rate,
        setup,
        cfg,
        stiffness_source: source,
    })
}

/// `[shank] density_kg_per_m3, teeth` and `[dynamics]` into `setup.dynamics`; returns where the
/// density comes from.
fn resolve_dynamics(
    file: &str,
    path: &Path,
    cfg: &ShankConfig,
    setup: &mut ShankSetup,
) -> Result<String> {
    let b = &cfg.shank;
    let d = &cfg.dynamics;
    let fraction = |key: &str, v: Option<f64>, default: f64| -> Result<f64> {
        let x = v.unwrap_or(default);
        if !(x.is_finite() && x > 0.0 && x < 1.0) {
            bail!("{file}: [dynamics] {key} = {x}: expected a damping ratio between 0 and 1 (dimensionless)");
        }
        Ok(x)
    };
    let dy = &mut setup.dynamics;
    let modulus_gpa = setup.beam.modulus_n_per_mm2 / 1e3;
    let source = match &b.density_kg_per_m3 {
        Some(v) => {
            let rho = number(file, "density_kg_per_m3", v, Quantity::Dimensionless)?;
            if !(rho.is_finite() && rho > 0.0) {
                bail!("{file}: [shank] density_kg_per_m3 = {rho}: expected a density > 0 kg/m³");
            }
            dy.density_kg_per_m3 = rho;
            "density_kg_per_m3 from the config".to_string()
        }
        None => format!(
            "default for modulus_gpa = {modulus_gpa} ({}; carbide 14500 kg/m3 if modulus_gpa >= 400, else steel 7850 kg/m3)",
            if modulus_gpa >= 400.0 { "carbide" } else { "steel" }
        ),
    };
    if let Some(k) = b.teeth {
        if k == 0 {
            bail!("{file}: [shank] teeth = 0: expected the number of teeth of the cutter (≥ 1)");
        }
        dy.teeth = Some(k);
    }
    dy.beam_damping = fraction("beam_damping", d.beam_damping, 0.03)?;
    let floor = d.deconvolution_floor.unwrap_or(0.1);
    if !(floor.is_finite() && floor > 0.0 && floor <= 1.0) {
        bail!("{file}: [dynamics] deconvolution_floor = {floor}: expected 0 < ε ≤ 1 (dimensionless, |H| where the correction fades out)");
    }
    let chain = match (&d.sensor_mode_hz, &d.frf) {
        (Some(_), Some(_)) => {
            bail!("{file}: [dynamics] give sensor_mode_hz or frf, not both")
        }
        (None, None) => {
            if d.sensor_damping.is_some() {
                bail!("{file}: [dynamics] sensor_damping needs sensor_mode_hz (Hz or \"beam\")");
            }
            None
        }
        (Some(v), None) => {
            let zeta = fraction("sensor_damping", d.sensor_damping, 0.03)?;
            let (hz, what) = match v {
                runout_io::config::Value::Text(t) if t.trim() == "beam" => (
                    setup
                        .beam
                        .first_bending_mode_hz(dy.density_kg_per_m3)
                        .with_context(|| format!("{file}: [shank]"))?,
                    "first bending mode of the beam model",
                ),
                v => (
                    number(file, "sensor_mode_hz", v, Quantity::FrequencyHz).map_err(|e| {
                        anyhow::anyhow!("{e} (or \"beam\" for the beam's own first mode)")
                    })?,
                    "sensor_mode_hz",
                ),
            };
            let mode = runout_core::chain::SensorMode::new(hz, zeta, 1.0)
                .with_context(|| format!("{file}: [dynamics]"))?;
            let axis = runout_core::chain::AxisChain::Modes(vec![mode]);
            Some((
                runout_core::chain::MeasuringChain {
                    x: axis.clone(),
                    y: axis,
                    z: runout_core::chain::AxisChain::Rigid,
                },
                format!("one mode at {hz:.1} Hz, damping {zeta} ({what})"),
            ))
        }
        (None, Some(f)) => {
            let p = path.parent().unwrap_or(Path::new(".")).join(f);
            let chain = runout_io::frf::read_frf(&p)?;
            for pair in &setup.pairs {
                let h = if pair.axis == PairAxis::X {
                    &chain.x
                } else {
                    &chain.y
                };
                if h.is_rigid() {
                    let a = pair.axis.letter();
                    bail!(
                        "{}: no {a}{a}_re/{a}{a}_im columns for the [[pair]] on axis {a} ({file}: [dynamics] frf)",
                        p.display()
                    );
                }
            }
            Some((chain, format!("measured FRF {}", p.display())))
        }
    };
    dy.correction = chain.map(|(chain, source)| runout_core::shank::Correction {
        chain,
        source,
        floor,
    });
    Ok(source)
}

/// Scale from a displacement channel's unit to mm.
fn displacement_scale(info: &RecordingInfo, idx: usize, r: &Resolved) -> Result<f64> {
    let ch = &info.channels[idx];
    let unit = ch.unit.clone().or_else(|| r.sensor_unit.clone());
    let Some(unit) = unit else {
        bail!(
            "{}: channel `{}` has no unit in the header; set [recording] sensor_unit (um, mm, nm or V)",
            info.file, ch.header
        );
    };
    let u = unit.trim().replace(['µ', 'μ'], "u");
    Ok(match u.as_str() {
        "mm" => 1.0,
        "um" | "micron" => 1e-3,
        "nm" => 1e-6,
        "m" => 1e3,
        "V" | "mV" => {
            let s = r.sensitivity_um_per_v.with_context(|| {
                format!("{}: channel `{}` is in {u}; set [recording] sensitivity_um_per_V", info.file, ch.header)
            })?;
            s * 1e-3 * if u == "mV" { 1e-3 } else { 1.0 }
        }
        other => bail!(
            "{}: channel `{}` has unit `{other}`; expected a length (um, mm, nm) or V with sensitivity_um_per_V",
            info.file, ch.header
        ),
    })
}

/// Channels to read and their role.
struct Plan {
    names: Vec<String>,
    scales: Vec<f64>,
    reference: Option<AxisMapping>,
}

fn open(
    path: &Path,
    r: &Resolved,
    names: &[String],
) -> Result<RecordingReader<std::io::BufReader<std::fs::File>>> {
    let mut o = ReadOptions::new().channels(names).chunk_rows(65_536);
    o.sample_rate_hz = r.sample_rate_hz;
    runout_io::recording::open_recording(path, &o).map_err(|e| match e {
        RecordingError::NoSampleRate { .. } => {
            anyhow::anyhow!("{e}\n(or set [recording] sample_rate_hz in the config)")
        }
        e => e.into(),
    })
}

fn plan(path: &Path, r: &Resolved) -> Result<(Plan, RecordingInfo)> {
    let mut names = Vec::new();
    for p in &r.cfg.pair {
        names.push(p.sensor_i.clone());
        names.push(p.sensor_ii.clone());
    }
    if let Some(pc) = &r.cfg.spindle.pulse_channel {
        names.push(pc.clone());
    }
    let reference = match &r.cfg.recording.reference_axes {
        Some(t) => {
            let m = AxisMapping::parse(t)?;
            for p in &r.setup.pairs {
                let axis = if p.axis == PairAxis::X {
                    runout_io::recording::Axis::X
                } else {
                    runout_io::recording::Axis::Y
                };
                let Some(src) = m.source(axis) else {
                    bail!(
                        "reference_axes `{t}` does not map axis {} of a [[pair]]",
                        p.axis.letter()
                    );
                };
                names.push(src.channel.clone());
            }
            Some(m)
        }
        None => None,
    };
    let reader = open(path, r, &names)?;
    let info = reader.info().clone();
    let nd = r.setup.displacement_channels();
    let mut scales = Vec::new();
    for i in 0..names.len() {
        scales.push(if i < nd {
            displacement_scale(&info, i, r)?
        } else if i == nd && r.setup.has_pulse {
            1.0
        } else {
            // reference force: N (kN converted), with the mapping's sign
            let ch = &info.channels[i];
            let unit = ch.unit.as_deref().unwrap_or("N");
            let s = match unit {
                "N" => 1.0,
                "kN" => 1e3,
                o => bail!(
                    "{}: reference channel `{}` has unit `{o}`; expected N or kN",
                    info.file,
                    ch.header
                ),
            };
            let m = reference.as_ref().expect("reference mapping");
            let k = i - nd - usize::from(r.setup.has_pulse);
            let axis = if r.setup.pairs[k].axis == PairAxis::X {
                runout_io::recording::Axis::X
            } else {
                runout_io::recording::Axis::Y
            };
            s * m.source(axis).map_or(1.0, |s| s.sign)
        });
    }
    Ok((
        Plan {
            names,
            scales,
            reference,
        },
        info,
    ))
}

/// Keeps a bounded, evenly thinned copy of a stream for plots.
struct Thinned {
    stride: u64,
    seen: u64,
    rows: Vec<(f64, Vec<f64>)>,
}

impl Thinned {
    fn new() -> Self {
        Self {
            stride: 1,
            seen: 0,
            rows: Vec::new(),
        }
    }

    fn push(&mut self, t: f64, v: impl FnOnce() -> Vec<f64>) {
        if self.seen.is_multiple_of(self.stride) {
            self.rows.push((t, v()));
            if self.rows.len() >= 8000 {
                let mut i = 0;
                self.rows.retain(|_| {
                    i += 1;
                    i % 2 == 1
                });
                self.stride *= 2;
            }
        }
        self.seen += 1;
    }

    fn curve(&self, name: &str, c: usize, scale: f64) -> Curve {
        Curve {
            name: name.into(),
            points: self.rows.iter().map(|(t, v)| (*t, v[c] * scale)).collect(),
        }
    }
}

/// Output sink: CSV or binary.
enum Sink {
    Csv(CsvWriter<Box<dyn std::io::Write>>),
    Bin(BinaryWriter<Box<dyn std::io::Write>>),
}

impl Sink {
    fn row(&mut self, v: &[f64]) -> std::io::Result<()> {
        match self {
            Sink::Csv(w) => w.write_row(v),
            Sink::Bin(w) => w.write_row(v),
        }
    }

    fn finish(self) -> std::io::Result<()> {
        match self {
            Sink::Csv(w) => w.finish().map(|_| ()),
            Sink::Bin(w) => w.finish().map(|_| ()),
        }?;
        Ok(())
    }
}

/// Per-axis statistics of the force over the cut.
#[derive(Default, Clone)]
struct Stats {
    n: u64,
    sum: f64,
    sum2: f64,
    min: f64,
    max: f64,
}

impl Stats {
    fn push(&mut self, v: f64) {
        if !v.is_finite() {
            return;
        }
        if self.n == 0 {
            self.min = v;
            self.max = v;
        }
        self.n += 1;
        self.sum += v;
        self.sum2 += v * v;
        self.min = self.min.min(v);
        self.max = self.max.max(v);
    }
}

fn force(a: ForceArgs) -> Result<()> {
    let mut r = load_config(&a.config, a.sample_rate_hz.as_deref())?;
    for out in [&a.out, &a.json].into_iter().flatten() {
        output::check_not_input(out, &[&a.recording, &a.config])?;
    }
    let (plan, info) = plan(&a.recording, &r)?;
    r.setup.sample_rate_hz = info.sample_rate_hz;
    r.setup.start_time_s = info.start_time_s;
    let nd = r.setup.displacement_channels();
    let nkeep = nd + usize::from(r.setup.has_pulse);
    let bar = progress(info.file_bytes, "pass 1/2");
    // pass 1
    let mut survey = Survey::new(&r.setup)?;
    let mut reader = open(&a.recording, &r, &plan.names)?;
    let mut chunk = Chunk::default();
    let mut raw = Thinned::new();
    let mut spill = if a.reparse {
        None
    } else {
        Some(Spill::create(plan.names.len())?)
    };
    while reader.read_chunk(&mut chunk, 65_536)? > 0 {
        scale_chunk(&mut chunk, &plan.scales);
        if let Some(sp) = spill.as_mut() {
            sp.write(&chunk)?;
        }
        let cols: Vec<&[f64]> = chunk.values.iter().map(Vec::as_slice).collect();
        survey.push(&cols[..nkeep])?;
        for k in 0..chunk.len() {
            raw.push(chunk.time_s[k], || {
                (0..nd).map(|c| chunk.values[c][k]).collect()
            });
        }
        bar.set_position(reader.bytes_read());
    }
    bar.finish_and_clear();
    let samples = survey.samples();
    let survey = survey.finish()?;
    let analysis = analyse(&survey).with_context(|| info.file.clone())?;
    // pass 2
    let mut rec = Reconstructor::new(&survey, &analysis)?;
    let columns = rec.column_names();
    let mut sink = match &a.out {
        None => None,
        Some(p) if p.extension().is_some_and(|e| e == "bin") => {
            let layout = match a.binary_type.as_str() {
                "f32" => BinaryLayout::F32,
                "f64" => BinaryLayout::F64,
                o => bail!("--binary-type `{o}`: expected f32 or f64"),
            };
            Some(Sink::Bin(BinaryWriter::new(
                output::create(p)?,
                &columns,
                layout,
                json!({"sample_rate_hz": info.sample_rate_hz, "source": info.file, "saturated": "1 = sensor saturated, force NaN"}),
            )?))
        }
        Some(p) => {
            // fixed decimals: time to 1/(100 f_s), forces 0.1 mN, deflections 0.01 nm
            let dt_dec = (info.sample_rate_hz.log10().ceil() as u32 + 2).min(12);
            let decimals: Vec<u32> = columns
                .iter()
                .map(|c| match c.as_str() {
                    "time_s" => dt_dec,
                    "saturated" => 0,
                    c if c.ends_with("_um") => 5,
                    _ => 4,
                })
                .collect();
            Some(Sink::Csv(
                CsvWriter::new(output::create(p)?, &columns)?.with_decimals(&decimals)?,
            ))
        }
    };
    let bar = progress(info.file_bytes, "pass 2/2");
    let mut warnings: Vec<String> = reader.warnings().to_vec();
    let mut source = match spill.as_mut() {
        Some(sp) => Pass2::Spill(sp.reader()?),
        None => Pass2::Text(Box::new(open(&a.recording, &r, &plan.names)?)),
    };
    let mut out = OutputBlock::default();
    let mut series = Thinned::new();
    let mut stats = vec![Stats::default(); r.setup.pairs.len()];
    let spr = r.setup.sample_rate_hz / analysis.spindle.mean_frequency_hz();
    let zoom = analysis.cut.map(|c| {
        let mid = (c.start + c.end) / 2;
        (
            mid.saturating_sub((2.5 * spr) as u64),
            mid + (2.5 * spr) as u64,
        )
    });
    let mut zoomed: Vec<(f64, Vec<f64>)> = Vec::new();
    let mut row = vec![0.0; columns.len()];
    let mut consume = |out: &OutputBlock, sink: &mut Option<Sink>| -> Result<()> {
        let np = out.force_n.len();
        for i in 0..out.len() {
            row[0] = out.time_s[i];
            let mut c = 1;
            for d in 0..np {
                row[c] = out.force_n[d][i];
                c += 1;
            }
            for d in 0..np {
                row[c] = out.delta_i_um[d][i];
                row[c + 1] = out.delta_ii_um[d][i];
                c += 2;
            }
            for rv in &out.reference_n {
                row[c] = rv[i];
                c += 1;
            }
            row[c] = f64::from(u8::from(out.saturated[i]));
            if let Some(s) = sink.as_mut() {
                s.row(&row)?;
            }
            let n = out.sample[i];
            if analysis.cut.is_none_or(|c| n >= c.start && n < c.end) {
                for (st, f) in stats.iter_mut().zip(&out.force_n) {
                    st.push(f[i]);
                }
            }
            series.push(out.time_s[i], || row[1..].to_vec());
            if zoom.is_some_and(|(z0, z1)| n >= z0 && n < z1) {
                zoomed.push((out.time_s[i], row[1..].to_vec()));
            }
        }
        Ok(())
    };
    loop {
        let n = match &mut source {
            Pass2::Text(rd) => {
                let n = rd.read_chunk(&mut chunk, 65_536)?;
                scale_chunk(&mut chunk, &plan.scales);
                bar.set_position(rd.bytes_read());
                n
            }
            Pass2::Spill(sr) => {
                let n = sr.read_chunk(&mut chunk)?;
                bar.inc(n as u64 * info.file_bytes.unwrap_or(0) / samples.max(1));
                n
            }
        };
        if n == 0 {
            break;
        }
        let cols: Vec<&[f64]> = chunk.values.iter().map(Vec::as_slice).collect();
        rec.push(&cols, &mut out)?;
        consume(&out, &mut sink)?;
    }
    drop(spill);
    rec.finish(&mut out);
    consume(&out, &mut sink)?;
    bar.finish_and_clear();
    if let Some(s) = sink {
        s.finish().context("writing the output")?;
    }
    let comparison = rec.comparison();
    let mut analysis = analysis;
    analysis.spectral_resonance = rec.spectral_resonance();
    warnings.extend(analysis.warnings.iter().cloned());
    let axes: Vec<PairAxis> = r.setup.pairs.iter().map(|p| p.axis).collect();
    let seen_usable = analysis.spectral_resonance.map(|seen| {
        let (usable, w) = runout_core::shank::spectral_check(
            &analysis.bandwidth,
            &r.setup.dynamics,
            &axes,
            &seen,
            r.setup.sample_rate_hz,
        );
        warnings.extend(w);
        usable
    });
    let summary = summary_json(
        &a,
        &r,
        &info,
        samples,
        &analysis,
        seen_usable,
        &stats,
        comparison.as_deref(),
        &plan,
        &warnings,
        &columns,
    );
    if let Some(p) = &a.json {
        output::write_text(p, &(serde_json::to_string_pretty(&summary)? + "\n"))?;
    }
    if let Some(dir) = &a.plot_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        if a.plot_format != "svg" && a.plot_format != "png" {
            bail!("--plot-format `{}`: expected svg or png", a.plot_format);
        }
        plots(dir, &a.plot_format, &r, &raw, &series, &zoomed, &analysis)?;
    }
    if a.json.as_deref() != Some(Path::new("-")) && a.out.as_deref() != Some(Path::new("-")) {
        print_summary(&summary);
    }
    Ok(())
}

/// Where pass 2 reads from.
enum Pass2 {
    Text(Box<RecordingReader<std::io::BufReader<std::fs::File>>>),
    Spill(SpillReader),
}

/// A temporary binary copy of the converted channels (per chunk: u64 LE row count, then each
/// channel's values as f64 LE), deleted when dropped.
struct Spill {
    path: PathBuf,
    writer: Option<std::io::BufWriter<std::fs::File>>,
    channels: usize,
}

impl Spill {
    fn create(channels: usize) -> Result<Self> {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let path =
            std::env::temp_dir().join(format!("runout-shank-{}-{nanos}.tmp", std::process::id()));
        let f = std::fs::File::create(&path).with_context(|| {
            format!(
                "creating the temporary file {} (or use --reparse)",
                path.display()
            )
        })?;
        Ok(Self {
            path,
            writer: Some(std::io::BufWriter::with_capacity(1 << 20, f)),
            channels,
        })
    }

    fn write(&mut self, chunk: &Chunk) -> Result<()> {
        use std::io::Write;
        let w = self.writer.as_mut().expect("writer open during pass 1");
        let mut bytes = Vec::with_capacity(8 + 8 * chunk.len() * self.channels);
        bytes.extend_from_slice(&(chunk.len() as u64).to_le_bytes());
        for c in &chunk.values {
            for v in c {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        w.write_all(&bytes)
            .with_context(|| format!("writing {} (or use --reparse)", self.path.display()))
    }

    fn reader(&mut self) -> Result<SpillReader> {
        use std::io::Write;
        if let Some(mut w) = self.writer.take() {
            w.flush()
                .with_context(|| format!("writing {}", self.path.display()))?;
        }
        let f = std::fs::File::open(&self.path)
            .with_context(|| format!("reading {}", self.path.display()))?;
        Ok(SpillReader {
            r: std::io::BufReader::with_capacity(1 << 20, f),
            channels: self.channels,
            first: 0,
            bytes: Vec::new(),
        })
    }
}

impl Drop for Spill {
    fn drop(&mut self) {
        self.writer = None;
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Reads the spill file chunk by chunk.
struct SpillReader {
    r: std::io::BufReader<std::fs::File>,
    channels: usize,
    first: u64,
    bytes: Vec<u8>,
}

impl SpillReader {
    fn read_chunk(&mut self, chunk: &mut Chunk) -> Result<usize> {
        use std::io::Read;
        let mut head = [0u8; 8];
        match self.r.read_exact(&mut head) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(0),
            Err(e) => return Err(e).context("reading the temporary file"),
        }
        let n = u64::from_le_bytes(head) as usize;
        chunk.first_sample = self.first;
        chunk.time_s.clear();
        chunk.values.resize_with(self.channels, Vec::new);
        self.bytes.resize(8 * n, 0);
        for c in &mut chunk.values {
            self.r
                .read_exact(&mut self.bytes)
                .context("reading the temporary file")?;
            c.clear();
            c.extend(
                self.bytes
                    .chunks_exact(8)
                    .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])),
            );
        }
        self.first += n as u64;
        Ok(n)
    }
}

fn scale_chunk(chunk: &mut Chunk, scales: &[f64]) {
    for (v, s) in chunk.values.iter_mut().zip(scales) {
        if *s != 1.0 {
            v.iter_mut().for_each(|x| *x *= s);
        }
    }
}

fn progress(bytes: Option<u64>, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(bytes.unwrap_or(0));
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:40}] {bytes}/{total_bytes} ({bytes_per_sec}, {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(what.to_string());
    bar
}

#[allow(clippy::too_many_arguments)]
fn summary_json(
    a: &ForceArgs,
    r: &Resolved,
    info: &RecordingInfo,
    samples: u64,
    an: &ShankAnalysis,
    seen_usable_hz: Option<f64>,
    stats: &[Stats],
    cmp: Option<&[runout_core::shank::ComparisonMetrics]>,
    plan: &Plan,
    warnings: &[String],
    columns: &[String],
) -> serde_json::Value {
    let s = &r.setup;
    let fs = s.sample_rate_hz;
    let t = |n: u64| s.start_time_s + n as f64 / fs;
    let ro = &an.runout;
    let deg = |x: f64, y: f64| y.atan2(x).to_degrees();
    let (spindle_source, rpm_se) = match &an.spindle {
        runout_core::shank::SpindlePhase::Constant {
            source,
            frequency_se_hz,
            ..
        } => (source.clone(), frequency_se_hz * 60.0),
        runout_core::shank::SpindlePhase::Pulses { .. } => (
            "once-per-revolution pulse".to_string(),
            an.spindle.frequency_se_hz() * 60.0,
        ),
    };
    let angle_ref = if s.has_pulse {
        "from the pulse mark's rising edge (theta = 0), in the direction of rotation"
    } else {
        "from an arbitrary spindle-angle origin (theta = 0 at the first sample; no pulse channel): only magnitudes and the offset-to-tilt angle are meaningful"
    };
    let forces: Vec<serde_json::Value> = s
        .pairs
        .iter()
        .zip(stats)
        .map(|(p, st)| {
            let n = st.n.max(1) as f64;
            json!({
                "axis": p.axis.letter().to_string(),
                "mean_N": st.sum / n,
                "rms_N": (st.sum2 / n).sqrt(),
                "min_N": st.min,
                "max_N": st.max,
            })
        })
        .collect();
    json!({
        "schema": "runout.shank.force/1",
        "recording": info.file,
        "format": format!("{:?}", info.format),
        "samples": samples,
        "sample_rate_hz": fs,
        "duration_s": samples as f64 / fs,
        "pairs": r.cfg.pair.iter().map(|p| json!({"axis": p.axis, "sensor_I": p.sensor_i, "sensor_II": p.sensor_ii, "sign": p.sign})).collect::<Vec<_>>(),
        "stiffness_N_per_um": s.stiffness_n_per_mm / 1e3,
        "stiffness_source": r.stiffness_source,
        "beam": {"modulus_gpa": s.beam.modulus_n_per_mm2 / 1e3, "diameter_mm": s.beam.diameter_mm, "tool_length_mm": s.beam.tool_length_mm, "l1_mm": s.beam.l1_mm, "l2_mm": s.beam.l2_mm, "load_point_mm": s.beam.load_distance_mm()},
        "spindle": {"source": spindle_source, "rpm": an.spindle.mean_frequency_hz() * 60.0, "rpm_se": rpm_se, "nominal_rpm": s.nominal_rpm},
        "air_cut_s": an.air_segments.iter().map(|g| [t(g.start), t(g.end)]).collect::<Vec<_>>(),
        "cut_s": an.cut.map(|c| [t(c.start), t(c.end)]),
        "template_revolutions": an.templates[0].revolutions,
        "air_residual_rms_um": an.air_residual_rms_mm.iter().map(|v| v * 1e3).collect::<Vec<_>>(),
        "runout": {
            "offset_um": ro.offset_magnitude_mm() * 1e3,
            "offset_se_um": ro.offset_se_mm * 1e3,
            "angle_deg": ro.offset_angle_rad().to_degrees(),
            "at_height_above_tip_mm": ro.cutting_height_mm,
            "tip_offset_um": ro.tip_offset_mm.0.hypot(ro.tip_offset_mm.1) * 1e3,
            "tip_angle_deg": deg(ro.tip_offset_mm.0, ro.tip_offset_mm.1),
            "tilt_um_per_mm": ro.tilt_magnitude() * 1e3,
            "tilt_se_um_per_mm": ro.tilt_se * 1e3,
            "tilt_angle_deg": ro.tilt_angle_rad().to_degrees(),
            "angle_reference": angle_ref,
            "per_sensor": ro.at_sensors.iter().map(|(z, x, y)| json!({"height_above_tip_mm": z, "runout_um": x.hypot(*y) * 1e3, "angle_deg": deg(*x, *y)})).collect::<Vec<_>>(),
        },
        "force_over_cut": forces,
        "validation": cmp.map(|m| json!({
            "reference_axes": plan.reference.as_ref().map(|m| m.to_string()),
            "per_axis": s.pairs.iter().zip(m).map(|(p, c)| json!({
                "axis": p.axis.letter().to_string(),
                "samples": c.samples,
                "rms_error_N": c.rms_error_n,
                "rms_reference_N": c.rms_reference_n,
                "relative_rms_error": c.relative_rms_error,
                "max_abs_error_N": c.max_abs_error_n,
                "peak_error_N": c.peak_error_n,
                "correlation": c.correlation,
            })).collect::<Vec<_>>(),
        })),
        "dynamics": dynamics_json(r, an, seen_usable_hz),
        "saturated_samples": an.saturated_samples,
        "lowpass_hz": s.lowpass.map(|l| l.1),
        "output": a.out.as_ref().map(|p| json!({"path": p.display().to_string(), "columns": columns})),
        "warnings": warnings,
    })
}

/// The bending mode, usable bandwidth and correction (issue 11 item 7).
fn dynamics_json(
    r: &Resolved,
    an: &ShankAnalysis,
    seen_usable_hz: Option<f64>,
) -> serde_json::Value {
    let b = &an.bandwidth;
    let c = r.setup.dynamics.correction.as_ref();
    json!({
        "first_bending_mode_hz": b.beam_mode_hz,
        "first_bending_mode_source": "Euler-Bernoulli cantilever from the [shank] beam: f1 = (beta1 L)^2/(2 pi) sqrt(E I/(rho A L^4)), beta1 L = 1.8751 clamped (holder spring lowers it)",
        "beam_damping": b.beam_damping,
        "density_kg_per_m3": b.density_kg_per_m3,
        "density_source": r.density_source,
        "bandwidth_criterion": "lowest frequency where the reconstructed force harmonic is off by more than 10 %: |G(f) H(f) - 1| > 0.1 (G = 1 without correction)",
        "uncorrected_bandwidth_hz": b.uncorrected_hz,
        "corrected_bandwidth_hz": b.corrected_hz,
        "usable_bandwidth_hz": b.usable_hz(),
        "correction": c.map(|c| json!({
            "source": c.source,
            "deconvolution_floor": c.floor,
            "method": "overlap-save FFT blocks, G = (1/H) |H|^4/(|H|^4 + eps^4)",
        })),
        "teeth": r.setup.dynamics.teeth,
        "tooth_frequency_hz": b.tooth_frequency_hz,
        "tooth_harmonics_beyond_band": b.harmonics_beyond.iter().map(|(k, f)| json!({"harmonic": k, "frequency_hz": f})).collect::<Vec<_>>(),
        "spectral_resonance": an.spectral_resonance.map(|s| json!({
            "frequency_hz": s.frequency_hz,
            "damping": s.damping,
            "prominence": s.prominence,
            "frames": s.frames,
            "static_usable_bandwidth_hz": seen_usable_hz,
            "method": "Welch spectrum of the uncorrected force over the cut between the spindle lines; f and damping fitted to the peak (docs/shank.md)",
        })),
    })
}

fn print_summary(j: &serde_json::Value) {
    let r = &j["runout"];
    println!(
        "recording        {}  ({} samples at {} Hz)",
        j["recording"].as_str().unwrap_or(""),
        j["samples"],
        j["sample_rate_hz"]
    );
    println!(
        "stiffness        K_delta = {:.4} N/um ({})",
        j["stiffness_N_per_um"].as_f64().unwrap_or(f64::NAN),
        j["stiffness_source"].as_str().unwrap_or("")
    );
    println!(
        "spindle          {:.4} rpm ± {:.1e} ({})",
        j["spindle"]["rpm"].as_f64().unwrap_or(f64::NAN),
        j["spindle"]["rpm_se"].as_f64().unwrap_or(f64::NAN),
        j["spindle"]["source"].as_str().unwrap_or("")
    );
    println!(
        "air cuts (s)     {}   cut (s) {}",
        j["air_cut_s"], j["cut_s"]
    );
    println!(
        "runout           offset {:.2} ± {:.2} um at {} mm above the tip, angle {:.1} deg; tilt {:.3} um/mm at {:.1} deg",
        r["offset_um"].as_f64().unwrap_or(f64::NAN),
        r["offset_se_um"].as_f64().unwrap_or(f64::NAN),
        r["at_height_above_tip_mm"],
        r["angle_deg"].as_f64().unwrap_or(f64::NAN),
        r["tilt_um_per_mm"].as_f64().unwrap_or(f64::NAN),
        r["tilt_angle_deg"].as_f64().unwrap_or(f64::NAN),
    );
    println!(
        "                 (angle {})",
        r["angle_reference"].as_str().unwrap_or("")
    );
    for f in j["force_over_cut"].as_array().into_iter().flatten() {
        println!(
            "force F{} (N)     mean {:.2}  rms {:.2}  min {:.2}  max {:.2}",
            f["axis"].as_str().unwrap_or(""),
            f["mean_N"].as_f64().unwrap_or(f64::NAN),
            f["rms_N"].as_f64().unwrap_or(f64::NAN),
            f["min_N"].as_f64().unwrap_or(f64::NAN),
            f["max_N"].as_f64().unwrap_or(f64::NAN)
        );
    }
    let d = &j["dynamics"];
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    println!(
        "bandwidth        first bending mode {:.0} Hz (beam model, {:.0} kg/m3, damping {}); static F = K*Delta usable to {:.0} Hz (|H - 1| <= 10 %)",
        f(&d["first_bending_mode_hz"]),
        f(&d["density_kg_per_m3"]),
        d["beam_damping"],
        f(&d["uncorrected_bandwidth_hz"]),
    );
    if let Some(c) = d["correction"].as_object() {
        println!(
            "                 corrected by {}: usable to {:.0} Hz",
            c["source"].as_str().unwrap_or(""),
            f(&d["corrected_bandwidth_hz"])
        );
    }
    if let Some(sr) = d["spectral_resonance"].as_object() {
        println!(
            "                 resonance seen in the cut spectrum at {:.0} Hz (damping {}): static relation usable to {:.0} Hz",
            f(&sr["frequency_hz"]),
            sr["damping"].as_f64().map_or("not fitted".into(), |z| format!("{z:.3}")),
            f(&sr["static_usable_bandwidth_hz"])
        );
    }
    if let Some(ft) = d["tooth_frequency_hz"].as_f64() {
        println!(
            "                 tooth passing {ft:.1} Hz, harmonics 1-5 up to {:.0} Hz",
            5.0 * ft
        );
    }
    for v in j["validation"]["per_axis"].as_array().into_iter().flatten() {
        println!(
            "validation F{}    RMS error {:.3} N ({:.2} %), peak error {:.3} N, correlation {:.5}",
            v["axis"].as_str().unwrap_or(""),
            v["rms_error_N"].as_f64().unwrap_or(f64::NAN),
            100.0 * v["relative_rms_error"].as_f64().unwrap_or(f64::NAN),
            v["peak_error_N"].as_f64().unwrap_or(f64::NAN),
            v["correlation"].as_f64().unwrap_or(f64::NAN)
        );
    }
    for w in j["warnings"].as_array().into_iter().flatten() {
        println!("warning: {}", w.as_str().unwrap_or(""));
    }
}

fn plots(
    dir: &Path,
    ext: &str,
    r: &Resolved,
    raw: &Thinned,
    series: &Thinned,
    zoomed: &[(f64, Vec<f64>)],
    an: &ShankAnalysis,
) -> Result<()> {
    let s = &r.setup;
    let np = s.pairs.len();
    let names: Vec<String> = r
        .cfg
        .pair
        .iter()
        .flat_map(|p| [p.sensor_i.clone(), p.sensor_ii.clone()])
        .collect();
    let raw_panel = Panel {
        y_label: "displacement (µm)".into(),
        curves: names
            .iter()
            .enumerate()
            .map(|(c, n)| raw.curve(n, c, 1e3))
            .collect(),
    };
    stacked_plot(
        &dir.join(format!("raw.{ext}")),
        "Raw displacement signals",
        "time (s)",
        &[raw_panel],
    )?;
    let tpl = Panel {
        y_label: "air-cut template g(θ) (µm)".into(),
        curves: an
            .templates
            .iter()
            .zip(&names)
            .map(|(t, n)| Curve {
                name: n.clone(),
                points: t
                    .bins
                    .iter()
                    .enumerate()
                    .map(|(b, v)| (360.0 * (b as f64 + 0.5) / t.bins.len() as f64, v * 1e3))
                    .collect(),
            })
            .collect(),
    };
    stacked_plot(
        &dir.join(format!("template.{ext}")),
        "Angle-synchronous air-cut templates",
        "spindle angle θ (deg)",
        &[tpl],
    )?;
    let defl: Vec<Panel> = s
        .pairs
        .iter()
        .enumerate()
        .map(|(d, p)| Panel {
            y_label: format!("{} deflection (µm)", p.axis.letter()),
            curves: vec![
                series.curve("δ_I", np + 2 * d, 1.0),
                series.curve("δ_II", np + 2 * d + 1, 1.0),
            ],
        })
        .collect();
    stacked_plot(
        &dir.join(format!("deflection.{ext}")),
        "Shank deflections δ_I, δ_II (template subtracted)",
        "time (s)",
        &defl,
    )?;
    let force_panels = |rows: &Thinned| -> Vec<Panel> {
        s.pairs
            .iter()
            .enumerate()
            .map(|(d, p)| {
                let mut curves = vec![rows.curve(&format!("F{} shank", p.axis.letter()), d, 1.0)];
                if s.has_reference {
                    curves.push(rows.curve(
                        &format!("F{} reference", p.axis.letter()),
                        3 * np + d,
                        1.0,
                    ));
                }
                Panel {
                    y_label: format!("F{} on workpiece (N)", p.axis.letter()),
                    curves,
                }
            })
            .collect()
    };
    stacked_plot(
        &dir.join(format!("force.{ext}")),
        "Cutting force from shank deflection",
        "time (s)",
        &force_panels(series),
    )?;
    if !zoomed.is_empty() {
        let z = Thinned {
            stride: 1,
            seen: 0,
            rows: zoomed.to_vec(),
        };
        stacked_plot(
            &dir.join(format!("force_zoom.{ext}")),
            "Cutting force, 5 revolutions mid-cut",
            "time (s)",
            &force_panels(&z),
        )?;
    }
    Ok(())
}

fn calibrate_cmd(a: CalibrateArgs) -> Result<()> {
    let r = load_config(&a.config, a.sample_rate_hz.as_deref())?;
    let p = &r.cfg.pair[0];
    let mut names = vec![
        p.sensor_i.clone(),
        p.sensor_ii.clone(),
        a.force_channel.clone(),
    ];
    if let Some(c) = &a.load_point_channel {
        names.push(c.clone());
    }
    let fixed = a
        .load_point_mm
        .as_deref()
        .map(|t| flag("load-point-mm", t, Quantity::LengthMm))
        .transpose()?;
    if fixed.is_none() == a.load_point_channel.is_none() {
        bail!("give exactly one of --load-point-mm and --load-point-channel");
    }
    let mut reader = match open(&a.recording, &r, &names) {
        Err(e) if e.to_string().contains("no sample rate") => {
            let mut o = ReadOptions::new().channels(&names);
            o.sample_rate_hz = Some(1.0);
            runout_io::recording::open_recording(&a.recording, &o)?
        }
        other => other?,
    };
    let info = reader.info().clone();
    let s0 = displacement_scale(&info, 0, &r)?;
    let s1 = displacement_scale(&info, 1, &r)?;
    let sign = r.setup.pairs[0].sign;
    let mut steps = Vec::new();
    let mut chunk = Chunk::default();
    while reader.read_chunk(&mut chunk, 65_536)? > 0 {
        for k in 0..chunk.len() {
            steps.push(LoadStep {
                force_n: chunk.values[2][k],
                load_point_mm: fixed
                    .unwrap_or_else(|| chunk.values.get(3).map_or(f64::NAN, |c| c[k])),
                delta_mm: sign * (chunk.values[1][k] * s1 - chunk.values[0][k] * s0),
            });
        }
    }
    let beam = if let Some(a0) = fixed {
        r.setup
            .beam
            .with_load_point(LoadPoint::At { distance_mm: a0 })?
    } else {
        r.setup.beam
    };
    let cal = calibrate(&beam, &steps)?;
    let j = json!({
        "schema": "runout.shank.calibration/1",
        "recording": info.file,
        "steps": cal.steps,
        "stiffness_N_per_um": cal.stiffness_n_per_mm / 1e3,
        "stiffness_se_N_per_um": cal.stiffness_se_n_per_mm / 1e3,
        "at_load_point_mm": beam.load_distance_mm(),
        "beam_stiffness_N_per_um": beam.stiffness_n_per_um(),
        "beam_scale": cal.beam_scale.map(|b| b.0),
        "beam_scale_se": cal.beam_scale.map(|b| b.1),
        "holder_stiffness_Nm_per_rad": cal.holder_compliance_rad_per_nmm.map(|c| 1.0 / c.0 / 1e3),
        "holder_compliance_rad_per_Nm": cal.holder_compliance_rad_per_nmm.map(|c| c.0 * 1e3),
        "holder_compliance_se_rad_per_Nm": cal.holder_compliance_rad_per_nmm.map(|c| c.1 * 1e3),
        "offset_um": cal.offset_mm * 1e3,
        "residual_rms_um": cal.residual_rms_mm * 1e3,
        "r_squared": cal.r_squared,
        "condition_number": cal.condition_number,
    });
    if let Some(pj) = &a.json {
        output::check_not_input(pj, &[&a.recording, &a.config])?;
        output::write_text(pj, &(serde_json::to_string_pretty(&j)? + "\n"))?;
    }
    if a.json.as_deref() != Some(Path::new("-")) {
        println!(
            "K_delta = {:.4} ± {:.4} N/um at {} mm (beam formula {:.4}); R² {:.6}, residual {:.3} um, condition {:.1}",
            cal.stiffness_n_per_mm / 1e3,
            cal.stiffness_se_n_per_mm / 1e3,
            beam.load_distance_mm(),
            beam.stiffness_n_per_um(),
            cal.r_squared,
            cal.residual_rms_mm * 1e3,
            cal.condition_number
        );
        match cal.holder_compliance_rad_per_nmm {
            Some((c, se)) => println!("holder: rotational compliance {:.4e} ± {:.1e} rad/(N·m)", c * 1e3, se * 1e3),
            None => println!("holder: not identifiable with a single load point (use --load-point-channel with ≥ 2 positions)"),
        }
    }
    Ok(())
}
