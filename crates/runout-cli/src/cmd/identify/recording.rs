//! `runout identify RECORDING… --config cut.toml`: runout and cutting coefficients from measured
//! force recordings — the product's main job. Flags and config → [`runout::identify::resolve`]
//! → [`runout::identify::recordings`] → JSON, text ([`runout::identify::recordings_text`]) and
//! plots ([`super::plots`]).

use crate::flags::{CutterFlags, PlotFormat};
use crate::output;
use anyhow::{bail, Context, Result};
use runout::identify::{self, recordings_text};
use runout::Source;
use runout_io::config::{Layer, Value};
use std::path::{Path, PathBuf};

/// Arguments of `runout identify RECORDING…`.
#[derive(clap::Args, Debug, Default)]
pub struct RecordingArgs {
    /// Force recordings (Kistler DynoWare text export, or CSV/TSV with a header row); several
    /// recordings at different feeds are fitted jointly. `-` reads one text recording from
    /// standard input (as does a pipe, e.g. `<(zcat rec.txt.gz)`).
    #[arg(value_name = "RECORDING")]
    pub recordings: Vec<PathBuf>,
    /// Cut description (TOML) with the keys of the flags below.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// The cutter (the flags of every command that takes one; `crate::flags::CutterFlags`).
    #[command(flatten)]
    pub cutter: CutterFlags,
    /// Nominal spindle speed (rpm); the actual speed is measured from the signal.
    #[arg(long)]
    pub rpm: Option<String>,
    /// Feed per tooth (mm): one value, or comma-separated, one per recording.
    #[arg(long)]
    pub fz_mm: Option<String>,
    /// Axial depth (mm): one value, or one per recording.
    #[arg(long)]
    pub ap_mm: Option<String>,
    /// Radial depth (mm).
    #[arg(long)]
    pub ae_mm: Option<String>,
    /// Milling mode: up | down | slot.
    #[arg(long)]
    pub mode: Option<String>,
    /// Instrument channels → workpiece frame (x feed, y feed-normal, z up), e.g. "x = -Fy, y = -Fx, z = -Fz".
    #[arg(long, allow_hyphen_values = true)]
    pub axes: Option<String>,
    /// Sample rate (Hz), when the file has neither a time column nor a sampling-rate line.
    #[arg(long)]
    pub sample_rate_hz: Option<String>,
    #[command(flatten)]
    pub time: crate::flags::TimeFlags,
    /// Start of the section to analyse (s); default: the steady cut, detected.
    #[arg(long)]
    pub from_s: Option<String>,
    /// End of the section to analyse (s).
    #[arg(long)]
    pub to_s: Option<String>,
    /// Component of the per-tooth peaks: fxy (resultant |F_xy|, N) | fx | fy | fz.
    #[arg(long)]
    pub peak_component: Option<String>,
    /// Once-per-revolution (or encoder) channel name.
    #[arg(long)]
    pub pulse_channel: Option<String>,
    /// Spindle angle of tooth 0 at the pulse edge (deg): makes the tooth numbering absolute.
    #[arg(long, allow_hyphen_values = true)]
    pub tooth0_angle_deg: Option<String>,
    /// Also fit the runout tilt (µm/mm).
    #[arg(long)]
    pub fit_tilt: bool,
    /// Measuring chain (the dynamometer's own dynamics): auto | rigid | modes | frf | band.
    /// auto (default) fits one second-order mode per axis and uses it where it explains the
    /// waveform significantly better; modes always; frf uses --sensor-frf; band fits only the
    /// harmonics up to --max-harmonic (or an automatic limit below the resonance).
    #[arg(long)]
    pub chain: Option<String>,
    /// Measured FRF of the dynamometer (CSV: freq_Hz, xx_re, xx_im, yy_re, yy_im[, zz_re, zz_im],
    /// normalised to H(0) = 1); implies --chain frf.
    #[arg(long)]
    pub sensor_frf: Option<String>,
    /// Start value of the sensor mode's natural frequency (Hz): one value, or x,y[,z].
    #[arg(long)]
    pub sensor_mode_hz: Option<String>,
    /// Band limit: fit only spindle harmonics 0..N (count); implies --chain band.
    #[arg(long)]
    pub max_harmonic: Option<String>,
    /// Write the JSON result (`-` for stdout).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Directory for the plots (created if missing): waveform overlay, per-tooth peaks, polar runout.
    #[arg(long)]
    pub plot_dir: Option<PathBuf>,
    /// Plot file type (svg or png; no unit).
    #[arg(long, value_enum, default_value_t = PlotFormat::Svg)]
    pub plot_format: PlotFormat,
    #[command(flatten)]
    pub report: crate::cmd::report::ReportFlags,
}

impl RecordingArgs {
    fn layer(&self) -> Layer {
        let pairs: [(&str, &Option<String>); 16] = [
            ("chain", &self.chain),
            ("sensor_frf", &self.sensor_frf),
            ("sensor_mode_hz", &self.sensor_mode_hz),
            ("max_harmonic", &self.max_harmonic),
            ("rpm", &self.rpm),
            ("fz_mm", &self.fz_mm),
            ("ap_mm", &self.ap_mm),
            ("ae_mm", &self.ae_mm),
            ("mode", &self.mode),
            ("axes", &self.axes),
            ("sample_rate_hz", &self.sample_rate_hz),
            ("from_s", &self.from_s),
            ("to_s", &self.to_s),
            ("peak_component", &self.peak_component),
            ("pulse_channel", &self.pulse_channel),
            ("tooth0_angle_deg", &self.tooth0_angle_deg),
        ];
        let mut layer = runout::case::flag_layer(self.cutter.pairs().into_iter().chain(pairs));
        if self.fit_tilt {
            layer
                .values
                .insert("fit_tilt".into(), Value::Text("true".into()));
        }
        layer
    }
}

pub fn run(a: RecordingArgs) -> Result<()> {
    if a.recordings.is_empty() {
        bail!("no recording given: `runout identify RECORDING… --config cut.toml` (or `runout identify peaks|tests`)");
    }
    let recordings = stdin_as_path(&a.recordings)?;
    let sources = recordings.iter().map(Source::path).collect();
    let config = a.config.as_ref().map(Source::path);
    let mut req = identify::resolve(config.as_ref(), a.layer(), sources)?;
    req.time_var = a.time.time_var.clone();
    let mut inputs: Vec<&Path> = recordings.iter().map(|p| p.as_path()).collect();
    if let Some(c) = &a.config {
        inputs.push(c);
    }
    if let Some(h) = &a.report.html {
        output::check_not_input(h, &inputs)?;
    }
    if let Some(j) = &a.json {
        output::check_not_input(j, &inputs)?;
    }
    let ext = a.plot_format.ext();
    let mut report = identify::recordings(&req, &mut crate::progress::Bars::default())?;
    a.report.judge(&mut report)?;
    a.report.write(&report)?;
    // assumed defaults that change the answer, on stderr too (after the job: an input error
    // stays a plain `error: …` message)
    for w in &req.assumed {
        crate::progress::warn(w);
    }
    if report.answer.status != "identified" {
        crate::exit::not_identified();
    }
    super::emit(a.json.as_deref(), &report, || recordings_text(&report))?;
    if let Some(dir) = &a.plot_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        super::plots::write(dir, ext, &report)?;
    }
    Ok(())
}

/// The recordings with `-` read as standard input (`/dev/stdin`), which can be given once.
fn stdin_as_path(recordings: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let dashes = recordings.iter().filter(|p| p.as_os_str() == "-").count();
    if dashes > 1 {
        bail!("`-` (standard input) is given {dashes} times among the recordings: it can be read once");
    }
    Ok(recordings
        .iter()
        .map(|p| {
            if p.as_os_str() == "-" {
                PathBuf::from("/dev/stdin")
            } else {
                p.clone()
            }
        })
        .collect())
}
