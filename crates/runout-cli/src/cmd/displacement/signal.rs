//! `runout displacement signal RECORDING.csv`: raw displacement signal → runout vector
//! (first harmonic by linear least squares; per-revolution TIR; optional per-tooth extrema).

use super::*;
use runout::displacement::{render, signal, ReferenceChoice, SignalRequest};
use runout::Source;
use runout_io::displacement::SignalSection;

/// Arguments of `runout displacement signal`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Recording (CSV, .mat, TDMS, HDF5, Parquet; `FILE:SEL` selects one of several) with
    /// `time_<s|ms>`, `disp_<name>_<um|mm>` channels, optional `pulse` (once per revolution) or
    /// `encoder_<deg|rad>`; other names through --channels.
    pub recording: PathBuf,
    /// Channels by name when they do not follow the naming convention, like the identify axis
    /// mapping: `a = Dx [um], b = Dy [mm], pulse = trig, encoder = angle [deg]` (unit in
    /// brackets, else the unit the file states).
    #[arg(long, allow_hyphen_values = true)]
    pub channels: Option<String>,
    #[command(flatten)]
    pub time: crate::flags::TimeFlags,
    /// Sample rate (Hz): the time base of a file without a time channel; with one, its times
    /// must lie on this rate's grid (within ¼ sample).
    #[arg(long, allow_hyphen_values = true)]
    pub sample_rate_hz: Option<String>,
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
    /// Spindle angle of tooth 0 measured from the once-per-revolution mark (deg); λ is reported
    /// from tooth 0. Old spelling `--tooth0-deg` (hidden, one release).
    #[arg(long, alias = "tooth0-deg", allow_hyphen_values = true)]
    pub tooth0_angle_deg: Option<String>,
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

/// `--reference auto|pulse|encoder|none`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum ReferenceArg {
    Auto,
    Pulse,
    Encoder,
    None,
}

pub fn run(a: Args) -> Result<()> {
    let section = SignalSection {
        from_s: quantity("from-s", &a.from_s, Quantity::TimeS)?,
        to_s: quantity("to-s", &a.to_s, Quantity::TimeS)?,
        ..Default::default()
    };
    if let (Some(f), Some(t)) = (section.from_s, section.to_s) {
        if t <= f {
            bail!(
                "--to-s ({} s) must be after --from-s ({} s)",
                runout_core::limits::show(t),
                runout_core::limits::show(f)
            );
        }
    }
    let sensor_angles_rad = a
        .sensor_angles_deg
        .as_deref()
        .map(|text| {
            text.split(',')
                .map(|t| parse_quantity(t, Quantity::AngleDeg).map(f64::to_radians))
                .collect::<Result<Vec<f64>, _>>()
                .context("--sensor-angles-deg")
        })
        .transpose()?;
    let reference = match a
        .reference
        .as_deref()
        .map(|t| choice::<ReferenceArg>("--reference", t))
        .transpose()?
    {
        None | Some(ReferenceArg::Auto) => ReferenceChoice::Auto,
        Some(ReferenceArg::Pulse) => ReferenceChoice::Pulse,
        Some(ReferenceArg::Encoder) => ReferenceChoice::Encoder,
        Some(ReferenceArg::None) => ReferenceChoice::None,
    };
    let (fz_mm, hole_path_mm) = a.cutter.fz_and_hole()?;
    let req = SignalRequest {
        recording: Source::path(&a.recording),
        section,
        read: runout_io::displacement::SignalOptions {
            channels: a.channels.clone(),
            time_var: a.time.time_var.clone(),
            sample_rate_hz: quantity("sample-rate-hz", &a.sample_rate_hz, Quantity::FrequencyHz)?,
        },
        sensor_angles_rad,
        sensor: a.beam.sensor()?,
        reference,
        rpm_range: (
            quantity("rpm-min", &a.rpm_min, Quantity::SpeedRpm)?.unwrap_or(60.0),
            quantity("rpm-max", &a.rpm_max, Quantity::SpeedRpm)?.unwrap_or(60_000.0),
        ),
        surface_diameter_mm: quantity(
            "surface-diameter-mm",
            &a.surface_diameter_mm,
            Quantity::LengthMm,
        )?,
        tooth0_rad: quantity("tooth0-angle-deg", &a.tooth0_angle_deg, Quantity::AngleDeg)?
            .unwrap_or(0.0)
            .to_radians(),
        cutter: a.cutter.cutter()?,
        height_mm: a.cutter.height()?,
        fz_mm,
        hole_path_mm,
    };
    let plot = a.out.check(&a.recording, "signal")?;
    let spin = crate::progress::Spinner::new("fitting the displacement signal");
    let mut report = signal(&req)?;
    drop(spin);
    a.out.report.judge(&mut report)?;
    crate::exit::from_answer(&report);
    if let Some(p) = &plot {
        a.out.plots.create_dir()?;
        render::signal_plot(p, &report)?;
    }
    a.out.write(&report, &render::signal_text(&report))
}
