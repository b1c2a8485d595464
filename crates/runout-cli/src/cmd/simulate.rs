//! `runout simulate CONFIG.toml [flags]`: mechanistic force simulation with runout.

use crate::output;
use anyhow::{Context, Result};
use runout_core::chip::EquivalentParams;
use runout_core::{
    tooth_peaks, ArcChip, EquivalentChip, ExactChip, ForceModel, ForceSeries, ToothPeak,
};
use runout_io::config::simulate::{resolve_simulate, simulate_key_names, SimulateCase};
use runout_io::config::{layer_from_toml, Layer, Settings, Value};
use runout_io::units::{parse_quantity, Quantity};
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;

/// Flags of `runout simulate`. Every config key is also a flag; flags override the file.
/// Values may carry a unit suffix of the right quantity (`--runout-um 0.008mm`, `--diameter-mm 10mm`).
#[derive(clap::Args, Debug, Default)]
pub struct CaseFlags {
    /// Number of teeth K.
    #[arg(long, allow_hyphen_values = true)]
    pub teeth: Option<String>,
    /// Cutter diameter D (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub diameter_mm: Option<String>,
    /// Helix angle (deg); 0 for straight flutes.
    #[arg(long, allow_hyphen_values = true)]
    pub helix_deg: Option<String>,
    /// Variable pitch angles (deg), K comma-separated values summing to 360.
    #[arg(long, allow_hyphen_values = true)]
    pub pitch_deg: Option<String>,
    /// Flute length (mm).
    #[arg(long, allow_hyphen_values = true)]
    pub flute_length_mm: Option<String>,
    /// End profile: flat | ball | bull_nose | tapered (default flat).
    #[arg(long, allow_hyphen_values = true)]
    pub profile: Option<String>,
    /// Corner radius r_c of a bull_nose cutter (mm), 0 < r_c <= D/2.
    #[arg(long, allow_hyphen_values = true)]
    pub corner_radius_mm: Option<String>,
    /// Taper (half-cone) angle of a tapered cutter (deg), 0 < α < 45; D is the tip diameter.
    #[arg(long, allow_hyphen_values = true)]
    pub taper_deg: Option<String>,
    /// Flute winding on a ball, bull-nose or taper: constant_lead | constant_helix (default constant_lead).
    #[arg(long, allow_hyphen_values = true)]
    pub flute_lead: Option<String>,
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
    /// case can be given by flags alone.
    pub config: Option<PathBuf>,
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
    /// Plot forces vs spindle angle with each tooth's peak marked (.svg or .png).
    #[arg(long)]
    pub plot: Option<PathBuf>,
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
    /// Field delimiter of the recording: comma | semicolon | tab.
    #[arg(long, default_value = "comma")]
    pub delimiter: String,
    /// Write decimal commas (needs --delimiter semicolon or tab).
    #[arg(long)]
    pub decimal_comma: bool,
}

impl CaseFlags {
    /// The flags that were given, as a settings layer.
    pub fn layer(&self, extra: &[(&str, &Option<String>)]) -> Layer {
        let c = self;
        let pairs: Vec<(&str, &Option<String>)> = vec![
            ("teeth", &c.teeth),
            ("diameter_mm", &c.diameter_mm),
            ("helix_deg", &c.helix_deg),
            ("pitch_deg", &c.pitch_deg),
            ("flute_length_mm", &c.flute_length_mm),
            ("profile", &c.profile),
            ("corner_radius_mm", &c.corner_radius_mm),
            ("taper_deg", &c.taper_deg),
            ("flute_lead", &c.flute_lead),
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
        let values = pairs
            .into_iter()
            .chain(extra.iter().copied())
            .filter_map(|(k, v)| v.as_ref().map(|v| (k.to_string(), Value::Text(v.clone()))))
            .collect();
        Layer {
            origin: "command line".into(),
            values,
        }
    }
}

/// Settings from an optional TOML file overlaid by flags.
pub fn settings(
    config: Option<&std::path::Path>,
    flags: Layer,
    known: &[&str],
) -> Result<Settings> {
    let mut s = Settings::new();
    if let Some(path) = config {
        let text = runout_io::textfile::read_text(path)
            .with_context(|| format!("reading config {}", path.display()))?;
        s.push(layer_from_toml(&path.display().to_string(), &text, known)?);
    }
    s.push(flags);
    Ok(s)
}

pub fn run(a: Args) -> Result<()> {
    let flags = a.case.layer(&[
        ("revolutions", &a.revolutions),
        ("step_deg", &a.step_deg),
        ("disks", &a.disks),
        ("chip_model", &a.chip_model),
    ]);
    let s = settings(a.config.as_deref(), flags, &simulate_key_names())?;
    let mut case = resolve_simulate(&s)?;
    let sensor = a.sensor.chain()?;
    if sensor.is_some() && a.recording.recording.is_none() {
        anyhow::bail!("--sensor-mode-hz / --sensor-frf: a sensor chain applies to the recording; give --recording FILE and --sample-rate-hz");
    }
    // with a sensor, the cut is simulated finer than the recording (see simulate_sensor)
    let oversample = if sensor.is_some() {
        super::simulate_sensor::OVERSAMPLE
    } else {
        1
    };
    let rate = a
        .recording
        .sample_rate_hz
        .as_deref()
        .map(|t| parse_flag("--sample-rate-hz", t, Quantity::FrequencyHz))
        .transpose()?;
    if let Some(fs) = rate {
        if fs <= 0.0 {
            anyhow::bail!("--sample-rate-hz: expected a sample rate > 0 Hz, got {fs}");
        }
        let step_deg = 360.0 * case.cut.rpm() / 60.0 / fs / oversample as f64;
        case.sampling =
            runout_core::Sampling::new(case.sampling.revolutions, step_deg, case.sampling.disks)
                .map_err(|e| anyhow::anyhow!("--sample-rate-hz {fs}: {e}"))?;
        case.check_work()?;
    }
    let inputs: Vec<&std::path::Path> = a.config.iter().map(|p| p.as_path()).collect();
    for out in [&a.out, &a.json, &a.plot, &a.recording.recording]
        .into_iter()
        .flatten()
    {
        output::check_not_input(out, &inputs)?;
    }

    let model = ForceModel {
        cutter: case.cutter.clone(),
        runout: case.runout,
        cut: case.cut,
        coefficients: case.coefficients,
    };
    let series = simulate_with(&model, &case)?;
    let peaks = tooth_peaks(&series, &case.cutter, &case.cut);

    if let Some(out) = &a.out {
        write_csv(out, &series)?;
    }
    if let Some(path) = &a.recording.recording {
        let fs = rate.ok_or_else(|| anyhow::anyhow!("--recording needs --sample-rate-hz"))?;
        write_recording(path, fs, &series, &a.recording, sensor.as_ref())?;
    }
    let mut summary = summary_json(&case, &series, &peaks);
    if let Some(sc) = &sensor {
        summary["sensor"] = sc.json.clone();
    }
    if let Some(j) = &a.json {
        output::write_text(j, &(serde_json::to_string_pretty(&summary)? + "\n"))?;
    }
    if let Some(p) = &a.plot {
        runout_io::plot::force_plot(
            p,
            &series,
            &peaks,
            "runout simulate: forces on the workpiece",
        )?;
    }
    let to_stdout = |p: &Option<PathBuf>| p.as_deref() == Some(std::path::Path::new("-"));
    if !to_stdout(&a.json) && !to_stdout(&a.out) {
        print_text(&case, &series, &peaks);
    }
    Ok(())
}

/// Run the simulation with the configured chip-thickness model.
fn simulate_with(model: &ForceModel, case: &SimulateCase) -> Result<ForceSeries> {
    let (c, r, fz) = (&case.cutter, &case.runout, case.cut.fz());
    Ok(match case.chip_model.as_str() {
        "exact" => model.simulate(&ExactChip::new(c, r, fz)?, &case.sampling),
        "equivalent" => model.simulate(
            &EquivalentChip::new(c, r, fz, EquivalentParams::default())?,
            &case.sampling,
        ),
        _ => model.simulate(&ArcChip::new(c, r, fz)?, &case.sampling),
    })
}

fn parse_flag(flag: &str, text: &str, q: Quantity) -> Result<f64> {
    parse_quantity(text, q).map_err(|e| anyhow::anyhow!("{flag}: {e}"))
}

/// The simulated cut as a DynoWare text export, with air-cut padding and white noise.
fn write_recording(
    path: &std::path::Path,
    fs: f64,
    s: &ForceSeries,
    r: &RecordingFlags,
    sensor: Option<&super::simulate_sensor::SensorChain>,
) -> Result<()> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let pct = parse_flag("--noise-percent", &r.noise_percent, Quantity::Dimensionless)?;
    let air = parse_flag("--air-cut-s", &r.air_cut_s, Quantity::TimeS)?;
    if !(pct >= 0.0 && air >= 0.0) {
        anyhow::bail!("--noise-percent and --air-cut-s must be >= 0 (got {pct}, {air})");
    }
    runout_core::limits::result_size("--air-cut-s", 2.0 * air * fs + s.fx.len() as f64, 3.0)?;
    let delimiter = match r.delimiter.as_str() {
        "comma" => ',',
        "semicolon" => ';',
        "tab" => '\t',
        other => anyhow::bail!("--delimiter: expected comma, semicolon or tab, got `{other}`"),
    };
    let peak = s.fxy().into_iter().fold(0.0, f64::max);
    let sigma = pct / 100.0 * peak;
    let normal = Normal::new(0.0, sigma.max(0.0)).map_err(|e| anyhow::anyhow!("noise: {e}"))?;
    let mut rng = rand::rngs::StdRng::seed_from_u64(r.seed);
    // with a sensor the series is OVERSAMPLE× finer than the recording: pad at the fine rate,
    // run through the sensor, decimate; the noise goes in after the sensor
    let fine = sensor.map_or(1, |_| super::simulate_sensor::OVERSAMPLE);
    let pad = (air * fs).round() as usize * fine;
    let mut channel = |v: &[f64], axis: usize| -> Vec<f64> {
        let mut out = vec![0.0; pad];
        out.extend_from_slice(v);
        out.extend(std::iter::repeat_n(0.0, pad));
        if let Some(sc) = sensor {
            let chain = [&sc.chain.x, &sc.chain.y, &sc.chain.z][axis];
            out = super::simulate_sensor::through_sensor(chain, fs, &out);
        }
        if sigma > 0.0 {
            out.iter_mut().for_each(|x| *x += normal.sample(&mut rng));
        }
        out
    };
    let (fx, fy, fz) = (channel(&s.fx, 0), channel(&s.fy, 1), channel(&s.fz, 2));
    let style = runout_io::export::TextStyle {
        delimiter,
        decimal_comma: r.decimal_comma,
    };
    let mut w = output::create(path)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().replace(".txt", ".dwd"))
        .unwrap_or_default();
    let noise = format!("{pct}% of peak |F_xy| ({sigma:.3} N)");
    let sensor_text = sensor.map_or_else(
        || "rigid".to_string(),
        |sc| {
            format!(
                "{} - cut simulated {}x oversampled then filtered and decimated - noise after the sensor",
                sc.description,
                super::simulate_sensor::OVERSAMPLE
            )
            // the header line must stay one field whatever the delimiter
            .replace([',', ';', '\t'], " ")
        },
    );
    let meta = [
        ("Filename", name.as_str()),
        ("Cycle No", "1"),
        ("Comment", "simulated by runout simulate"),
        ("Noise", noise.as_str()),
        ("Sensor", sensor_text.as_str()),
    ];
    let chans = [
        runout_io::export::Channel {
            name: "Fx",
            unit: "N",
            data: &fx,
        },
        runout_io::export::Channel {
            name: "Fy",
            unit: "N",
            data: &fy,
        },
        runout_io::export::Channel {
            name: "Fz",
            unit: "N",
            data: &fz,
        },
    ];
    runout_io::export::write_dynoware(&mut w, fs, &meta, &chans, style)
        .with_context(|| format!("writing {}", path.display()))?;
    w.flush()?;
    Ok(())
}

fn write_csv(dest: &std::path::Path, s: &ForceSeries) -> Result<()> {
    let mut w = output::create(dest)?;
    let k = s.chip.len();
    write!(w, "time_s,angle_deg,fx_N,fy_N,fz_N,torque_Nm")?;
    for i in 0..k {
        write!(w, ",h{i}_mm")?;
    }
    writeln!(w)?;
    for q in 0..s.len() {
        write!(
            w,
            "{:.9},{:.4},{:.6},{:.6},{:.6},{:.6}",
            s.time[q],
            s.angle[q].to_degrees(),
            s.fx[q],
            s.fy[q],
            s.fz[q],
            s.torque[q]
        )?;
        for i in 0..k {
            write!(w, ",{:.7}", s.chip[i][q])?;
        }
        writeln!(w)?;
    }
    w.flush()?;
    Ok(())
}

/// JSON summary, schema `runout.simulate/1`: inputs echoed with units in the names.
pub fn summary_json(
    case: &SimulateCase,
    s: &ForceSeries,
    peaks: &[ToothPeak],
) -> serde_json::Value {
    let c = &case.cutter;
    let cut = &case.cut;
    let (st, ex) = cut.immersion(c);
    let k = &case.coefficients;
    let m = s.means();
    json!({
        "schema": "runout.simulate/1",
        "inputs": {
            "teeth": c.teeth(),
            "diameter_mm": c.diameter(),
            "helix_deg": c.helix().to_degrees(),
            "profile": c.profile(),
            "flute_lead": c.lead(),
            "pitch_deg": c.pitch().iter().map(|p| p.to_degrees()).collect::<Vec<_>>(),
            "rpm": cut.rpm(),
            "fz_mm": cut.fz(),
            "ap_mm": cut.ap(),
            "entry_deg": st.to_degrees(),
            "exit_deg": ex.to_degrees(),
            "runout_um": case.runout.offset_um(),
            "runout_angle_deg": case.runout.angle().to_degrees(),
            "tilt_um_per_mm": [case.runout.tilt()[0] * 1e3, case.runout.tilt()[1] * 1e3],
            "ktc_N_per_mm2": k.ktc, "krc_N_per_mm2": k.krc, "kac_N_per_mm2": k.kac,
            "kte_N_per_mm": k.kte, "kre_N_per_mm": k.kre, "kae_N_per_mm": k.kae,
            "revolutions": case.sampling.revolutions,
            "step_deg": case.sampling.step.to_degrees(),
            "disks": case.sampling.disks,
            "chip_model": case.chip_model,
        },
        "tooth_radii_mm": case.runout.tooth_radii(c, 0.0),
        "mean_fx_N": m[0], "mean_fy_N": m[1], "mean_fz_N": m[2], "mean_torque_Nm": m[3],
        "tooth_peaks": peaks.iter().map(|p| json!({
            "tooth": p.tooth,
            "peak_fxy_N": p.peak_fxy,
            "spindle_angle_deg": p.angle.to_degrees(),
            "immersion_deg": p.immersion.to_degrees(),
            "max_chip_mm": p.max_chip,
            "own_peak_fxy_N": p.own_peak_fxy,
        })).collect::<Vec<_>>(),
        "samples": s.len(),
    })
}

fn print_text(case: &SimulateCase, s: &ForceSeries, peaks: &[ToothPeak]) {
    let m = s.means();
    println!(
        "runout simulate: K = {}, D = {} mm, {} rpm, f_z = {} mm, a_p = {} mm, runout {:.2} µm at {:.1}°",
        case.cutter.teeth(),
        case.cutter.diameter(),
        case.cut.rpm(),
        case.cut.fz(),
        case.cut.ap(),
        case.runout.offset_um(),
        case.runout.angle().to_degrees()
    );
    println!(
        "{} samples; mean F_x {:.2} N, F_y {:.2} N, F_z {:.2} N, torque {:.4} N·m",
        s.len(),
        m[0],
        m[1],
        m[2],
        m[3]
    );
    println!("tooth  peak |F_xy| (N)  at spindle angle (deg)  max chip (µm)");
    for p in peaks {
        println!(
            "{:>5}  {:>16.3}  {:>22.2}  {:>13.3}",
            p.tooth,
            p.peak_fxy,
            p.angle.to_degrees(),
            p.max_chip * 1e3
        );
    }
}
