//! `runout displacement signal RECORDING.csv`: raw displacement signal → runout vector
//! (first harmonic by linear least squares; per-revolution TIR; optional per-tooth extrema).

use super::*;
use runout_core::displacement::{
    fit_signal, identify_from_teeth, per_revolution_runout, per_tooth_extrema, SensorChannel,
    SignalFit, SignalInput, SpindleReference, ToothFitOptions,
};
use runout_io::displacement::{read_signal, SignalSection};
use runout_io::displacement_plot::{teeth_polar_plot, TeethPlot};

/// Arguments of `runout displacement signal`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// CSV with `time_<s|ms>`, `disp_<name>_<um|mm>` channels, optional `pulse` (once per revolution)
    /// or `encoder_<deg|rad>`.
    pub recording: PathBuf,
    /// Angle of each displacement sensor (deg, in the direction of rotation, comma-separated, one per
    /// `disp_*` column in file order). Default 0 for a single channel.
    #[arg(long, allow_hyphen_values = true)]
    pub sensor_angles_deg: Option<String>,
    /// Spindle angle source: `auto` (pulse, else encoder, else estimated), `pulse`, `encoder`, `none` (estimate from the spectrum).
    #[arg(long, allow_hyphen_values = true)]
    pub reference: Option<String>,
    /// Lowest plausible spindle speed (rpm) when the speed is estimated.
    #[arg(long, allow_hyphen_values = true)]
    pub rpm_min: Option<String>,
    /// Highest plausible spindle speed (rpm) when the speed is estimated.
    #[arg(long, allow_hyphen_values = true)]
    pub rpm_max: Option<String>,
    /// Diameter of the measured round section (mm); needed with --inclination-deg/--beam-offset-mm.
    #[arg(long, allow_hyphen_values = true)]
    pub surface_diameter_mm: Option<String>,
    /// Spindle angle of tooth 0 measured from the once-per-revolution mark (deg); λ is reported from tooth 0.
    #[arg(long, allow_hyphen_values = true)]
    pub tooth0_deg: Option<String>,
    /// Start of the section to analyse (s, on the file's time axis); default: the start. Samples
    /// outside the section are read and dropped, so long files need not fit in memory.
    #[arg(long, allow_hyphen_values = true)]
    pub from_s: Option<String>,
    /// End of the section to analyse (s); default: the end. At most 20 M samples are kept.
    #[arg(long, allow_hyphen_values = true)]
    pub to_s: Option<String>,
    #[command(flatten)]
    pub cutter: CutterFlags,
    #[command(flatten)]
    pub beam: BeamFlags,
    #[command(flatten)]
    pub out: OutputFlags,
}

pub fn run(a: Args) -> Result<()> {
    let file = a.recording.display().to_string();
    let section = SignalSection {
        from_s: quantity("from-s", &a.from_s, Quantity::TimeS)?,
        to_s: quantity("to-s", &a.to_s, Quantity::TimeS)?,
        ..Default::default()
    };
    if let (Some(f), Some(t)) = (section.from_s, section.to_s) {
        if t <= f {
            bail!("--to-s ({t} s) must be after --from-s ({f} s)");
        }
    }
    let table = read_signal(&a.recording, &section)?;
    let sign = sensor_sign(&a.beam.sensor)?;
    let angles = sensor_angles(&a.sensor_angles_deg, table.channels.len())?;
    let beam = a.beam.beam()?;
    let ideal = beam.inclination() == 0.0 && beam.offset() == 0.0;
    let surface = match quantity(
        "surface-diameter-mm",
        &a.surface_diameter_mm,
        Quantity::LengthMm,
    )? {
        Some(d) => 0.5 * d,
        None if ideal => 1.0, // unused: the ideal beam needs no radius
        None => {
            bail!("--surface-diameter-mm is required with --inclination-deg / --beam-offset-mm")
        }
    };
    let rpm_min = quantity("rpm-min", &a.rpm_min, Quantity::SpeedRpm)?.unwrap_or(60.0);
    let rpm_max = quantity("rpm-max", &a.rpm_max, Quantity::SpeedRpm)?.unwrap_or(60_000.0);
    let estimate = SpindleReference::Estimate { rpm_min, rpm_max };
    let reference = match (a.reference.as_deref().unwrap_or("auto"), &table.pulse, &table.encoder_rad) {
        ("auto" | "pulse", Some(p), _) => SpindleReference::Pulse(p),
        ("auto" | "encoder", None, Some(e)) | ("encoder", _, Some(e)) => SpindleReference::Encoder(e),
        ("auto" | "none", _, _) => estimate,
        ("pulse", None, _) => bail!("{file}: --reference pulse but the file has no `pulse` column (missing channel)"),
        ("encoder", _, None) => bail!("{file}: --reference encoder but the file has no `encoder_<deg|rad>` column (missing channel)"),
        (o, _, _) => bail!("--reference: `{o}` is not auto, pulse, encoder or none"),
    };
    let input = SignalInput {
        sample_rate_hz: table.sample_rate_hz,
        channels: table
            .channels
            .iter()
            .zip(&angles)
            .map(|((_, v), b)| SensorChannel {
                displacement_mm: v,
                angle_rad: *b,
                sign,
            })
            .collect(),
        reference,
        surface_radius_mm: surface,
        beam,
        reference_angle_rad: quantity("tooth0-deg", &a.tooth0_deg, Quantity::AngleDeg)?
            .unwrap_or(0.0)
            .to_radians(),
    };
    let (fit, track) = fit_signal(&input).with_context(|| file.clone())?;
    // seed eq. (5) is a by-product: a record without a complete revolution still gets the fit
    let revs = per_revolution_runout(&input, &track).unwrap_or_default();
    let mut json = to_json(&file, &table.channels, &fit)?;
    let samples = table.channels[0].1.len();
    let end_s = table.start_s + (samples - 1) as f64 / table.sample_rate_hz;
    json["section"] = json!({"from_s": table.start_s, "to_s": end_s, "samples": samples});
    json["beam"] = a.beam.json()?;
    json["per_revolution"] = revs
        .iter()
        .zip(&table.channels)
        .map(|(r, (name, _))| {
            json!({"channel": name, "half_tir_mean_um": r.mean_mm * 1e3, "half_tir_sd_um": r.sd_mm.map(|s| s * 1e3)})
        })
        .collect();
    let mut text = to_text(&file, &table.channels, &fit);
    text += &format!(
        "  section {:.6}–{end_s:.6} s ({samples} samples at {:.1} Hz)\n",
        table.start_s, table.sample_rate_hz
    );
    for (r, (name, _)) in revs.iter().zip(&table.channels) {
        text += &format!(
            "  channel {name}: TIR/2 per revolution (seed eq. 5) {:.4} µm (sd {})\n",
            r.mean_mm * 1e3,
            r.sd_mm.map_or("–".into(), |s| format!("{:.4} µm", s * 1e3))
        );
    }
    let mut plot = TeethPlot {
        tooth_angles_rad: vec![],
        measured_um: vec![],
        model_um: None,
        offset_um: fit.offset_mm * 1e3,
        angle_rad: fit.angle.angle(),
        title: format!("runout from signal: {:.3} µm", fit.offset_mm * 1e3),
    };
    if let Some(cutter) = a.cutter.cutter()? {
        let z = a.cutter.height()?;
        let readings =
            per_tooth_extrema(&input, &track, 0, &cutter, z).with_context(|| file.clone())?;
        let mut opts = ToothFitOptions::new(cutter.clone());
        opts.height_mm = z;
        opts.beam = beam;
        opts.known_offset_mm = Some(fit.offset_mm);
        opts.phase_hint_rad = fit.angle.angle();
        let tf = identify_from_teeth(&readings, &opts)
            .with_context(|| format!("{file}: per-tooth extrema"))?;
        let mut tj = json!({
            "offset_um": tf.offset_mm * 1e3,
            "offset_se_um": tf.offset_se_mm.map(|s| s * 1e3),
            "positions_um": tf.positions_mm.iter().map(|p| p * 1e3).collect::<Vec<_>>(),
            "notes": tf.notes,
        });
        if let (Value::Object(m), Value::Object(x)) = (&mut tj, angle_json(&tf.angle)) {
            m.extend(x);
        }
        text += &format!(
            "per-tooth extrema (channel 0): offset {:.3} µm, {}\n",
            tf.offset_mm * 1e3,
            angle_text(&tf.angle)
        );
        if let Some(r) = tf.runout() {
            let c = a.cutter.consequences(&cutter, &r)?;
            tj["consequences"] = consequences_json(&c);
            text += &consequences_text(&c);
        }
        json["teeth"] = tj;
        let pm = tf.positions_mm.iter().sum::<f64>() / tf.positions_mm.len() as f64;
        plot.tooth_angles_rad = (0..cutter.teeth())
            .map(|i| cutter.tooth_angle(i, z))
            .collect();
        plot.measured_um = tf.positions_mm.iter().map(|p| (p - pm) * 1e3).collect();
    }
    if let Some(p) = &a.out.plot {
        crate::output::check_not_input(p, &[&a.recording])?;
        teeth_polar_plot(p, &plot)?;
    }
    a.out.write(&a.recording, &json, &text)
}

fn sensor_angles(v: &Option<String>, n: usize) -> Result<Vec<f64>> {
    let Some(text) = v else {
        if n == 1 {
            return Ok(vec![0.0]);
        }
        bail!("--sensor-angles-deg is required: the file has {n} displacement channels (give {n} comma-separated angles)");
    };
    let a: Vec<f64> = text
        .split(',')
        .map(|t| parse_quantity(t, Quantity::AngleDeg).map(f64::to_radians))
        .collect::<Result<_, _>>()
        .context("--sensor-angles-deg")?;
    if a.len() != n {
        bail!(
            "--sensor-angles-deg has {} angle(s), the file has {n} displacement channel(s)",
            a.len()
        );
    }
    Ok(a)
}

fn to_json(file: &str, ch: &[(String, Vec<f64>)], fit: &SignalFit) -> Result<Value> {
    let mut v = json!({
        "schema": "runout.displacement.signal/1",
        "input": { "file": file, "channels": ch.iter().map(|c| c.0.clone()).collect::<Vec<_>>() },
        "reference": fit.reference,
        "rpm": fit.rpm,
        "rpm_sd": fit.rpm_sd,
        "revolutions": fit.revolutions,
        "samples_used": fit.samples_used,
        "offset_um": fit.offset_mm * 1e3,
        "offset_se_um": fit.offset_se_mm * 1e3,
        "vector_um": [fit.vector_mm[0] * 1e3, fit.vector_mm[1] * 1e3],
        "channel_agreement_chi2": fit.channel_agreement_chi2,
        "channels": fit.channels.iter().zip(ch).map(|(c, (name, _))| json!({
            "channel": name,
            "sensor_angle_deg": c.sensor_angle_rad.to_degrees(),
            "offset_um": c.offset_mm * 1e3,
            "angle_deg": c.vector_mm[1].atan2(c.vector_mm[0]).to_degrees(),
            "residual_sd_um": c.residual_sd_mm * 1e3,
        })).collect::<Vec<_>>(),
        "notes": fit.notes,
    });
    if let (Value::Object(m), Value::Object(a)) = (&mut v, angle_json(&fit.angle)) {
        m.extend(a);
    }
    Ok(v)
}

fn to_text(file: &str, ch: &[(String, Vec<f64>)], fit: &SignalFit) -> String {
    let mut s = format!(
        "runout from signal ({file}; {} channel(s), spindle angle {:?}, {:.3} rpm, {} revolutions)\n",
        ch.len(),
        fit.reference,
        fit.rpm,
        fit.revolutions
    );
    s += &format!(
        "offset ρ = {:.4} ± {:.4} µm (1σ)\n",
        fit.offset_mm * 1e3,
        fit.offset_se_mm * 1e3
    );
    s += &angle_text(&fit.angle);
    s += "\n";
    for (c, (name, _)) in fit.channels.iter().zip(ch) {
        s += &format!(
            "  channel {name} at {:.1}°: {:.4} µm at {:.2}°, residual sd {:.4} µm\n",
            c.sensor_angle_rad.to_degrees(),
            c.offset_mm * 1e3,
            c.vector_mm[1].atan2(c.vector_mm[0]).to_degrees(),
            c.residual_sd_mm * 1e3
        );
    }
    s + &notes_text(&fit.notes)
}
