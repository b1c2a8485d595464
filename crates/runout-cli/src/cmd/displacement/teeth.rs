//! `runout displacement teeth READINGS.csv`: per-tooth readings → (ρ, λ), methods.md §1.5.

use super::*;
use runout_core::displacement::{
    identify_from_teeth, ToothFit, ToothFitOptions, ToothMethod, ToothReadings,
};
use runout_io::displacement::read_tooth_table;
use runout_io::displacement_plot::{teeth_polar_plot, TeethPlot};

/// Arguments of `runout displacement teeth`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// CSV with `tooth` (0-based, cutting order) or `seed_edge` (1-based, seed 000) and
    /// `reading_<um|mm>`; several rows per tooth are averaged (their scatter estimates the noise).
    pub readings: PathBuf,
    #[command(flatten)]
    pub cutter: CutterFlags,
    #[command(flatten)]
    pub beam: BeamFlags,
    /// Method: `joint` (default; K ≥ 3 least squares, K = 2 closed form) or `scan` (the seed's 1° scan, needs --offset-um).
    #[arg(long, allow_hyphen_values = true)]
    pub method: Option<String>,
    /// Runout length ρ at this height from the height regression (µm); required for K = 2 and `scan`.
    #[arg(long, allow_hyphen_values = true)]
    pub offset_um: Option<String>,
    /// Standard error of --offset-um (µm).
    #[arg(long, allow_hyphen_values = true)]
    pub offset_se_um: Option<String>,
    /// Sensor noise σ_P of one reading (µm), if known.
    #[arg(long, allow_hyphen_values = true)]
    pub noise_um: Option<String>,
    /// Approximate runout direction from the spindle phase (deg, from tooth 0 in the direction of rotation); resolves the K = 2 mirror ambiguity.
    #[arg(long, allow_hyphen_values = true)]
    pub phase_deg: Option<String>,
    #[command(flatten)]
    pub out: OutputFlags,
}

pub fn run(a: Args) -> Result<()> {
    let cutter = a
        .cutter
        .cutter()?
        .context("--teeth and --diameter-mm are required")?;
    let k = cutter.teeth();
    let sign = sensor_sign(&a.beam.sensor)?;
    let method = match a.method.as_deref() {
        None | Some("joint") => ToothMethod::Joint,
        Some("scan") => ToothMethod::SeedScan,
        Some(o) => bail!("--method: `{o}` is not `joint` or `scan`"),
    };
    let mut opts = ToothFitOptions::new(cutter.clone());
    opts.height_mm = a.cutter.height()?;
    opts.method = method;
    opts.known_offset_mm = um_as_mm("offset-um", &a.offset_um)?;
    opts.known_offset_se_mm = um_as_mm("offset-se-um", &a.offset_se_um)?;
    opts.noise_mm = um_as_mm("noise-um", &a.noise_um)?;
    opts.beam = a.beam.beam()?;
    opts.phase_hint_rad =
        quantity("phase-deg", &a.phase_deg, Quantity::AngleDeg)?.map(f64::to_radians);
    let table = read_tooth_table(&a.readings, k)?;
    let readings = ToothReadings::new(k, &table.readings, sign)
        .with_context(|| format!("{}", a.readings.display()))?;
    let fit = identify_from_teeth(&readings, &opts)
        .with_context(|| format!("{}", a.readings.display()))?;
    let cons = match fit.runout() {
        Some(r) => Some(a.cutter.consequences(&cutter, &r)?),
        None => None,
    };
    let json = to_json(
        &a,
        &cutter,
        &opts,
        &fit,
        cons.as_ref(),
        table.from_seed_edges,
    )?;
    let text = to_text(&a, &fit, cons.as_ref());
    if let Some(p) = &a.out.plot {
        crate::output::check_not_input(p, &[&a.readings])?;
        teeth_polar_plot(p, &plot_data(&cutter, &opts, &fit))?;
    }
    a.out.write(&a.readings, &json, &text)
}

fn plot_data(cutter: &Cutter, opts: &ToothFitOptions, fit: &ToothFit) -> TeethPlot {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let pm = mean(&fit.positions_mm);
    let model = fit.runout().map(|r| {
        let radii = r.tooth_radii(cutter, opts.height_mm);
        let m = mean(&radii);
        radii.iter().map(|v| (v - m) * 1e3).collect()
    });
    TeethPlot {
        tooth_angles_rad: (0..cutter.teeth())
            .map(|i| cutter.tooth_angle(i, opts.height_mm))
            .collect(),
        measured_um: fit.positions_mm.iter().map(|p| (p - pm) * 1e3).collect(),
        model_um: model,
        offset_um: fit.offset_mm * 1e3,
        angle_rad: fit.angle.angle(),
        title: format!(
            "per-tooth radii, K = {} (runout {:.3} µm)",
            cutter.teeth(),
            fit.offset_mm * 1e3
        ),
    }
}

fn to_json(
    a: &Args,
    cutter: &Cutter,
    opts: &ToothFitOptions,
    fit: &ToothFit,
    cons: Option<&Consequences>,
    seed_edges: bool,
) -> Result<Value> {
    let um = |v: &[f64]| v.iter().map(|x| x * 1e3).collect::<Vec<_>>();
    let mut v = json!({
        "schema": "runout.displacement.teeth/1",
        "input": {
            "file": a.readings.display().to_string(),
            "tooth_numbering": if seed_edges { "seed_edge (converted: tooth = (1 - k) mod K)" } else { "tooth (0-based, cutting order)" },
            "teeth": cutter.teeth(),
            "diameter_mm": cutter.diameter(),
            "helix_deg": cutter.helix().to_degrees(),
            "height_mm": opts.height_mm,
            "beam": a.beam.json()?,
            "known_offset_um": opts.known_offset_mm.map(|x| x * 1e3),
            "known_offset_se_um": opts.known_offset_se_mm.map(|x| x * 1e3),
            "noise_um": opts.noise_mm.map(|x| x * 1e3),
            "phase_deg": opts.phase_hint_rad.map(f64::to_degrees),
        },
        "method": fit.method,
        "offset_um": fit.offset_mm * 1e3,
        "offset_se_um": fit.offset_se_mm.map(|x| x * 1e3),
        "positions_um": um(&fit.positions_mm),
        "radius_differences_um": um(&fit.radius_differences_mm),
        "residual_rms_um": fit.residual_rms_mm * 1e3,
        "dof": fit.dof,
        "noise_used_um": fit.noise_mm.map(|x| x * 1e3),
        "noise_source": fit.noise_source,
        "condition_number": fit.condition_number,
        "beam_factor": fit.beam_factor,
        "notes": fit.notes,
        "consequences": cons.map(consequences_json),
    });
    if let (Value::Object(m), Value::Object(ang)) = (&mut v, angle_json(&fit.angle)) {
        m.extend(ang);
    }
    Ok(v)
}

fn to_text(a: &Args, fit: &ToothFit, cons: Option<&Consequences>) -> String {
    let mut s = format!(
        "runout from per-tooth readings ({}; method {:?})\n",
        a.readings.display(),
        fit.method
    );
    s += &match fit.offset_se_mm {
        Some(se) => format!(
            "offset ρ = {:.3} ± {:.3} µm (1σ)\n",
            fit.offset_mm * 1e3,
            se * 1e3
        ),
        None => format!("offset ρ = {:.3} µm\n", fit.offset_mm * 1e3),
    };
    s += &angle_text(&fit.angle);
    s += "\n";
    s += &format!(
        "residual rms {:.4} µm, dof {}, noise {} ({:?})\n",
        fit.residual_rms_mm * 1e3,
        fit.dof,
        fit.noise_mm
            .map_or("unknown".into(), |n| format!("{:.4} µm", n * 1e3)),
        fit.noise_source
    );
    for (i, (p, d)) in fit
        .positions_mm
        .iter()
        .zip(&fit.radius_differences_mm)
        .enumerate()
    {
        s += &format!(
            "  tooth {i}: P = {:.4} µm, ΔR = P{i} − P{} = {:.4} µm\n",
            p * 1e3,
            (i + 1) % fit.positions_mm.len(),
            d * 1e3
        );
    }
    if let Some(c) = cons {
        s += &consequences_text(c);
    }
    s + &notes_text(&fit.notes)
}
