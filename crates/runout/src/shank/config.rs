//! shank.toml resolved into core types, and the channels a job reads.

use crate::job::Source;
use anyhow::{bail, Context, Result};
use runout_core::shank::{LoadPoint, PairAxis, SensorPair, ShankBeam, ShankSetup};
use runout_io::config::shank::{number, LoadPointWord, PairAxisWord, ShankConfig};
use runout_io::recording::{
    AxisMapping, ReadOptions, RecordingError, RecordingInfo, RecordingReader,
};
use runout_io::units::Quantity;
use std::io::BufRead;
use std::path::Path;

/// A streaming reader over a [`Source`].
pub(crate) type Reader = RecordingReader<Box<dyn BufRead + Send>>;

/// Everything resolved from shank.toml.
pub(crate) struct Resolved {
    pub(crate) setup: ShankSetup,
    pub(crate) density_source: String,
    pub(crate) cfg: ShankConfig,
    pub(crate) stiffness_source: String,
    pub(crate) sensor_unit: Option<String>,
    pub(crate) sensitivity_um_per_v: Option<f64>,
    pub(crate) sample_rate_hz: Option<f64>,
    /// `--time-var`: the time base from a named channel / variable.
    pub(crate) time_var: Option<String>,
}

pub(crate) fn load_config(config: &Source, rate: Option<f64>) -> Result<Resolved> {
    let file = config.name().to_string();
    let text = config
        .read_text()
        .with_context(|| format!("reading config {file}"))?;
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
    match b.load_point {
        None | Some(LoadPointWord::Tip) => {}
        Some(LoadPointWord::MidDepth) => {
            let Some(ap) = ap else {
                bail!("{file}: load_point = \"mid-depth\" needs axial_depth_mm");
            };
            beam = beam
                .with_load_point(LoadPoint::MidDepth { axial_depth_mm: ap })
                .with_context(|| format!("{file}: [shank]"))?;
        }
    }
    if let Some(k) = &b.holder_stiffness_nm_per_rad {
        let k =
            n("holder_stiffness_Nm_per_rad", k, Quantity::Dimensionless).or_else(|_| match k {
                runout_io::config::Value::Number(x) => Ok(*x),
                runout_io::config::Value::Text(t) => t.trim().parse::<f64>().map_err(|_| {
                    anyhow::anyhow!("{file}: holder_stiffness_Nm_per_rad = `{t}` is not a number")
                }),
            })?;
        beam = beam
            .with_holder_stiffness_nm_per_rad(k)
            .with_context(|| format!("{file}: [shank]"))?;
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
            "beam formula (docs/methods.md §3.1)".to_string(),
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
        let axis = match p.axis {
            PairAxisWord::X => PairAxis::X,
            PairAxisWord::Y => PairAxis::Y,
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
    let rate = match rate {
        Some(hz) => Some(hz),
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
    let density_source = resolve_dynamics(&file, config.dir(), &cfg, &mut setup)?;
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
        time_var: None,
        setup,
        cfg,
        stiffness_source: source,
    })
}

/// `[shank] density_kg_per_m3, teeth` and `[dynamics]` into `setup.dynamics`; returns where the
/// density comes from.
fn resolve_dynamics(
    file: &str,
    dir: &Path,
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
            let p = dir.join(f);
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
pub(crate) fn displacement_scale(info: &RecordingInfo, idx: usize, r: &Resolved) -> Result<f64> {
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
pub(crate) struct Plan {
    pub(crate) names: Vec<String>,
    pub(crate) scales: Vec<f64>,
    pub(crate) reference: Option<AxisMapping>,
}

pub(crate) fn open(source: &Source, r: &Resolved, names: &[String]) -> Result<Reader> {
    let mut o = ReadOptions::new().channels(names).chunk_rows(65_536);
    o.sample_rate_hz = r.sample_rate_hz;
    o.time_column = r.time_var.clone();
    source.open_recording(&o).map_err(|e| match e {
        RecordingError::NoSampleRate { .. } => {
            anyhow::anyhow!("{e}\n(or set [recording] sample_rate_hz in the config)")
        }
        e => e.into(),
    })
}

pub(crate) fn plan(source: &Source, r: &Resolved) -> Result<(Plan, RecordingInfo)> {
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
                    runout_io::recording::FrameAxis::X
                } else {
                    runout_io::recording::FrameAxis::Y
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
    let reader = open(source, r, &names)?;
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
                runout_io::recording::FrameAxis::X
            } else {
                runout_io::recording::FrameAxis::Y
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
