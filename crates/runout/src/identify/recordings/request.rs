//! The request of `identify RECORDING…` and its one resolver from a TOML config + flag layer.

use crate::job::Source;
use anyhow::{bail, Context, Result};
use runout_core::signal::ForceComponent;
use runout_core::{Cut, Cutter};
use runout_io::config::identify::{identify_key_names, resolve_identify, IdentifyCase};
use runout_io::config::{layer_from_toml, Layer, Settings};

/// How the measuring chain (the dynamometer's own dynamics) is handled (methods.md §4.7).
#[derive(Debug, Clone, Default)]
pub enum ChainChoice {
    /// Fit one second-order mode per axis and use it where it explains the waveform
    /// significantly better than a rigid sensor.
    #[default]
    Auto,
    /// A rigid sensor.
    Rigid,
    /// Always the fitted modes.
    Modes,
    /// A measured FRF (CSV: freq_Hz, xx_re, xx_im, yy_re, yy_im[, zz_re, zz_im], H(0) = 1).
    Frf(Source),
    /// Only the spindle harmonics 0..N (`None`: an automatic limit below the resonance).
    Band(Option<usize>),
}

impl ChainChoice {
    /// The name in the config vocabulary: auto | rigid | modes | frf | band.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Rigid => "rigid",
            Self::Modes => "modes",
            Self::Frf(_) => "frf",
            Self::Band(_) => "band",
        }
    }
}

/// Recordings of one cutter, the cut of each, and the options of the signal pipeline and fits.
#[derive(Debug, Clone)]
pub struct RecordingsRequest {
    /// Force recordings (DynoWare text export, CSV/TSV or any format of `runout_io::formats`);
    /// several recordings at different feeds are fitted jointly.
    pub recordings: Vec<Source>,
    /// The cutter.
    pub cutter: Cutter,
    /// One cut per recording (feed and depth may differ).
    pub cuts: Vec<Cut>,
    /// Instrument channels → workpiece frame, e.g. `"x = -Fy, y = -Fx, z = -Fz"`; `None`: the
    /// channels named Fx, Fy[, Fz].
    pub axes: Option<String>,
    /// Sample rate (Hz), when a file has neither a time column nor a rate line.
    pub sample_rate_hz: Option<f64>,
    /// Channel / variable holding the sample times (or, in a binary file, a scalar sample rate
    /// in Hz) used as the time base (`--time-var`); `None`: auto-detected.
    pub time_var: Option<String>,
    /// Section to analyse (s); `None`: the steady cut, detected.
    pub section_s: Option<(f64, f64)>,
    /// Component of the per-tooth peaks (default the resultant |F_xy|).
    pub peak_component: ForceComponent,
    /// Once-per-revolution (or encoder) channel.
    pub pulse_channel: Option<String>,
    /// Pulses per revolution of the pulse channel.
    pub pulses_per_rev: usize,
    /// Spindle angle of tooth 0 at the pulse edge (deg): makes the tooth numbering absolute.
    pub tooth0_angle_deg: Option<f64>,
    /// Also fit the runout tilt.
    pub fit_tilt: bool,
    /// The measuring chain.
    pub chain: ChainChoice,
    /// Start values of the fitted modes' natural frequencies (Hz): one, or per axis x, y[, z].
    pub sensor_mode_hz: Option<Vec<f64>>,
    /// Parameters that change the answer and were not given, so their defaults were assumed,
    /// each as a warning naming the flag (e.g. `assumed helix 0°: pass --helix-deg`); filled by
    /// [`resolve`], reported in the answer's warnings.
    pub assumed: Vec<String>,
}

impl RecordingsRequest {
    /// `recordings` cut with `cuts` (one per recording) by `cutter`; default options.
    pub fn new(recordings: Vec<Source>, cutter: Cutter, cuts: Vec<Cut>) -> Self {
        Self {
            recordings,
            cutter,
            cuts,
            axes: None,
            sample_rate_hz: None,
            time_var: None,
            section_s: None,
            peak_component: ForceComponent::Fxy,
            pulse_channel: None,
            pulses_per_rev: 1,
            tooth0_angle_deg: None,
            fit_tilt: false,
            chain: ChainChoice::Auto,
            sensor_mode_hz: None,
            assumed: Vec::new(),
        }
    }

    /// The request of a resolved config case (the FRF file, if any, named relative to the
    /// working directory as given).
    pub fn from_case(recordings: Vec<Source>, case: IdentifyCase) -> Self {
        use runout_io::config::identify::{Chain, PeakComponent};
        let chain = match case.chain {
            Chain::Auto => ChainChoice::Auto,
            Chain::Rigid => ChainChoice::Rigid,
            Chain::Modes => ChainChoice::Modes,
            Chain::Frf => ChainChoice::Frf(Source::path(case.sensor_frf.unwrap_or_default())),
            Chain::Band => ChainChoice::Band(case.max_harmonic),
        };
        let peak_component = match case.peak_component {
            PeakComponent::Fxy => ForceComponent::Fxy,
            PeakComponent::Fx => ForceComponent::Fx,
            PeakComponent::Fy => ForceComponent::Fy,
            PeakComponent::Fz => ForceComponent::Fz,
        };
        Self {
            axes: case.axes,
            sample_rate_hz: case.sample_rate_hz,
            section_s: case.section_s,
            peak_component,
            pulse_channel: case.pulse_channel,
            pulses_per_rev: case.pulses_per_rev,
            tooth0_angle_deg: case.tooth0_angle.map(f64::to_degrees),
            fit_tilt: case.fit_tilt,
            chain,
            sensor_mode_hz: case.sensor_mode_hz,
            ..Self::new(recordings, case.cutter, case.cuts)
        }
    }

    /// At least one recording and one cut per recording.
    pub(super) fn validate(&self) -> Result<()> {
        if self.recordings.is_empty() {
            bail!("no recording given: `runout identify RECORDING… --config cut.toml` (or `runout identify peaks|tests`)");
        }
        if self.cuts.len() != self.recordings.len() {
            bail!(
                "{} recordings but {} cuts: give one cut per recording",
                self.recordings.len(),
                self.cuts.len()
            );
        }
        Ok(())
    }

    /// Tooth-0 angle (rad).
    pub(super) fn tooth0_angle(&self) -> Option<f64> {
        self.tooth0_angle_deg.map(f64::to_radians)
    }

    /// The peak component in the config vocabulary (`fxy`, `fx`, `fy`, `fz`).
    pub(super) fn peak_component_name(&self) -> &'static str {
        match self.peak_component {
            ForceComponent::Fx => "fx",
            ForceComponent::Fy => "fy",
            ForceComponent::Fz => "fz",
            ForceComponent::Fxy => "fxy",
        }
    }
}

/// The one resolver of `identify` cases: the config (TOML, keys of
/// `runout_io::config::identify`) under the `flags` layer (which wins), for `recordings`.
pub fn resolve(
    config: Option<&Source>,
    flags: Layer,
    recordings: Vec<Source>,
) -> Result<RecordingsRequest> {
    let known = identify_key_names();
    let mut s = Settings::new();
    if let Some(src) = config {
        let text = src
            .read_text()
            .with_context(|| format!("reading config {}", src.name()))?;
        s.push(layer_from_toml(src.name(), &text, &known)?);
    }
    s.push(flags);
    let case = resolve_identify(&s, recordings.len())?;
    let mut assumed = Vec::new();
    if !s.has("helix_deg") {
        assumed.push(
            "assumed helix 0° (straight flutes): pass --helix-deg (or helix_deg in the config); \
             on a helical cutter the coefficients and the angle change"
                .to_string(),
        );
    }
    if !s.has("profile") {
        assumed.push(
            "assumed a flat end mill: pass --profile (ball, bull_nose with --corner-radius-mm, \
             tapered) when the cut is on a rounded or tapered end"
                .to_string(),
        );
    }
    Ok(RecordingsRequest {
        assumed,
        ..RecordingsRequest::from_case(recordings, case)
    })
}
