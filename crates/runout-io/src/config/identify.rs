//! Keys of `runout identify RECORDING…`: the cutter and cut (as in `runout simulate`, without
//! runout and coefficients, which are the unknowns), how to read the recordings, and the
//! signal-pipeline options.

use super::simulate::{resolve_cut, resolve_cutter};
use super::{ConfigError, Settings};
use crate::units::Quantity;
use runout_core::{Cut, Cutter};

/// Every key: (key, quantity, help). The flag is `--key-with-dashes`.
pub const IDENTIFY_KEYS: &[(&str, Quantity, &str)] = &[
    ("teeth", Quantity::Dimensionless, "number of teeth K"),
    ("diameter_mm", Quantity::LengthMm, "cutter diameter D (mm)"),
    (
        "helix_deg",
        Quantity::AngleDeg,
        "helix angle (deg) [default 0]",
    ),
    (
        "pitch_deg",
        Quantity::AngleDeg,
        "variable pitch angles (deg) [default uniform]",
    ),
    ("flute_length_mm", Quantity::LengthMm, "flute length (mm)"),
    (
        "profile",
        Quantity::Dimensionless,
        "end profile: flat | ball | bull_nose | tapered [default flat]",
    ),
    (
        "corner_radius_mm",
        Quantity::LengthMm,
        "corner radius r_c of a bull_nose cutter (mm), 0 < r_c <= D/2",
    ),
    (
        "taper_deg",
        Quantity::AngleDeg,
        "taper (half-cone) angle of a tapered cutter (deg), 0 < α < 45; D is the tip diameter",
    ),
    (
        "flute_lead",
        Quantity::Dimensionless,
        "flute winding on a ball, bull-nose or taper: constant_lead | constant_helix [default constant_lead]",
    ),
    (
        "rpm",
        Quantity::SpeedRpm,
        "nominal spindle speed (rpm); the actual speed is measured",
    ),
    (
        "fz_mm",
        Quantity::LengthMm,
        "feed per tooth (mm); one value, or one per recording",
    ),
    (
        "ap_mm",
        Quantity::LengthMm,
        "axial depth (mm); one value, or one per recording",
    ),
    ("ae_mm", Quantity::LengthMm, "radial depth (mm)"),
    ("mode", Quantity::Dimensionless, "up | down | slot"),
    (
        "entry_deg",
        Quantity::AngleDeg,
        "explicit entry immersion angle (deg)",
    ),
    (
        "exit_deg",
        Quantity::AngleDeg,
        "explicit exit immersion angle (deg)",
    ),
    (
        "axes",
        Quantity::Dimensionless,
        "instrument channels → workpiece frame, e.g. \"x = -Fy, y = -Fx, z = -Fz\"",
    ),
    (
        "sample_rate_hz",
        Quantity::FrequencyHz,
        "sample rate (Hz) when the file has neither a time column nor a rate line",
    ),
    (
        "from_s",
        Quantity::TimeS,
        "start of the section to analyse (s) [default: detected steady cut]",
    ),
    ("to_s", Quantity::TimeS, "end of the section to analyse (s)"),
    (
        "peak_component",
        Quantity::Dimensionless,
        "component of the per-tooth peaks: fxy | fx | fy | fz [default fxy]",
    ),
    (
        "pulse_channel",
        Quantity::Dimensionless,
        "once-per-revolution (or encoder) channel name",
    ),
    (
        "pulses_per_rev",
        Quantity::Dimensionless,
        "pulses per revolution of the pulse channel [default 1]",
    ),
    (
        "tooth0_angle_deg",
        Quantity::AngleDeg,
        "spindle angle of tooth 0 at the pulse edge (deg): makes tooth numbering absolute",
    ),
    (
        "fit_tilt",
        Quantity::Dimensionless,
        "also fit the runout tilt (true/false) [default false]",
    ),
    (
        "chain",
        Quantity::Dimensionless,
        "measuring chain (sensor dynamics): auto | rigid | modes | frf | band [default auto: fit one \
         mode per axis and use it where it explains the waveform significantly better]",
    ),
    (
        "sensor_frf",
        Quantity::Dimensionless,
        "measured FRF file (CSV: freq_Hz, xx_re, xx_im, yy_re, yy_im[, zz_re, zz_im], H(0) = 1); implies chain = frf",
    ),
    (
        "sensor_mode_hz",
        Quantity::FrequencyHz,
        "start value of the fitted sensor mode's natural frequency (Hz): one value, or x,y[,z] [default: scanned]",
    ),
    (
        "max_harmonic",
        Quantity::Dimensionless,
        "band limit: fit only spindle harmonics 0..N (count) with a rigid model; implies chain = band",
    ),
];

/// Names of all keys.
pub fn identify_key_names() -> Vec<&'static str> {
    IDENTIFY_KEYS.iter().map(|k| k.0).collect()
}

/// A resolved identification case.
#[derive(Debug, Clone)]
pub struct IdentifyCase {
    /// The cutter.
    pub cutter: Cutter,
    /// One cut per recording (feed and depth may differ).
    pub cuts: Vec<Cut>,
    /// Axis mapping text, if given.
    pub axes: Option<String>,
    /// Sample rate (Hz), if given.
    pub sample_rate_hz: Option<f64>,
    /// Section override (s).
    pub section_s: Option<(f64, f64)>,
    /// Component of the per-tooth peaks.
    pub peak_component: PeakComponent,
    /// Pulse channel name.
    pub pulse_channel: Option<String>,
    /// Pulses per revolution.
    pub pulses_per_rev: usize,
    /// Tooth-0 angle at the pulse edge (rad).
    pub tooth0_angle: Option<f64>,
    /// Fit the tilt too.
    pub fit_tilt: bool,
    /// Measuring chain.
    pub chain: Chain,
    /// Measured FRF file.
    pub sensor_frf: Option<String>,
    /// Start values of the fitted modes' natural frequencies (Hz): one, or per axis x, y[, z].
    pub sensor_mode_hz: Option<Vec<f64>>,
    /// Band limit (highest spindle harmonic).
    pub max_harmonic: Option<usize>,
}

/// `peak_component = fxy | fx | fy | fz`: the force component whose per-tooth peaks are fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PeakComponent {
    /// Resultant |F_xy| (N).
    #[default]
    Fxy,
    /// F_x (N).
    Fx,
    /// F_y (N).
    Fy,
    /// F_z (N).
    Fz,
}

/// `chain = auto | rigid | modes | frf | band`: how the measuring chain (the dynamometer's own
/// dynamics) is modelled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Chain {
    /// Fit one second-order mode per axis and use it where it explains the waveform
    /// significantly better.
    #[default]
    Auto,
    /// No sensor dynamics.
    Rigid,
    /// Always the fitted modes.
    Modes,
    /// The measured FRF of `sensor_frf`.
    Frf,
    /// Only the spindle harmonics up to `max_harmonic` (rigid).
    Band,
}

fn per_recording(s: &Settings, key: &str, n: usize) -> Result<Vec<f64>, ConfigError> {
    let v = s
        .list(key, Quantity::LengthMm)?
        .ok_or_else(|| ConfigError::Missing {
            key: key.into(),
            flag: key.replace('_', "-"),
            what: "one value, or one per recording".into(),
        })?;
    match v.len() {
        1 => Ok(vec![v[0]; n]),
        m if m == n => Ok(v),
        m => Err(ConfigError::Key {
            source_name: s.origin(key).unwrap_or("config").into(),
            key: key.into(),
            message: if n == 1 {
                format!("expected 1 value for the 1 recording given, got {m}")
            } else {
                format!("expected 1 value, or {n} (one per recording: {n} given), got {m}")
            },
        }),
    }
}

/// Resolve the settings for `recordings` recordings.
pub fn resolve_identify(s: &Settings, recordings: usize) -> Result<IdentifyCase, ConfigError> {
    let cutter = resolve_cutter(s)?;
    let fz = per_recording(s, "fz_mm", recordings)?;
    let ap = per_recording(s, "ap_mm", recordings)?;
    let cuts = fz
        .iter()
        .zip(&ap)
        .map(|(f, a)| resolve_cut(s, &cutter, *f, *a))
        .collect::<Result<Vec<_>, _>>()?;
    let section_s = match (
        s.quantity("from_s", Quantity::TimeS)?,
        s.quantity("to_s", Quantity::TimeS)?,
    ) {
        (None, None) => None,
        (a, b) => {
            let (a, b) = (a.unwrap_or(0.0), b.unwrap_or(f64::INFINITY));
            if b <= a || a < 0.0 {
                return Err(ConfigError::Key {
                    source_name: s
                        .origin("to_s")
                        .or(s.origin("from_s"))
                        .unwrap_or("config")
                        .into(),
                    key: "from_s/to_s".into(),
                    message: format!(
                        "expected 0 <= from_s < to_s, got {} and {}",
                        runout_core::limits::show(a),
                        runout_core::limits::show(b)
                    ),
                });
            }
            Some((a, b))
        }
    };
    let peak_component: PeakComponent = s.choice("peak_component")?.unwrap_or_default();
    let fit_tilt = match s
        .text("fit_tilt")?
        .as_deref()
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        None | Some("false") | Some("no") => false,
        Some("true") | Some("yes") => true,
        Some(other) => {
            return Err(ConfigError::Key {
                source_name: s.origin("fit_tilt").unwrap_or("config").into(),
                key: "fit_tilt".into(),
                message: format!(
                    "expected true or false, got `{}`",
                    crate::textfile::quote(other)
                ),
            })
        }
    };
    let sensor_frf = s.text("sensor_frf")?;
    let max_harmonic = s.count("max_harmonic")?;
    let chain = match s.choice::<Chain>("chain")? {
        Some(c) => c,
        None if sensor_frf.is_some() => Chain::Frf,
        None if max_harmonic.is_some() => Chain::Band,
        None => Chain::Auto,
    };
    if chain == Chain::Frf && sensor_frf.is_none() {
        return Err(ConfigError::Key {
            source_name: s.origin("chain").unwrap_or("config").into(),
            key: "chain".into(),
            message: "chain = frf needs sensor_frf (--sensor-frf FILE)".into(),
        });
    }
    let sensor_mode_hz = s.list("sensor_mode_hz", Quantity::FrequencyHz)?;
    if let Some(v) = &sensor_mode_hz {
        if v.is_empty() || v.len() > 3 || v.iter().any(|f| !(f.is_finite() && *f > 0.0)) {
            return Err(ConfigError::Key {
                source_name: s.origin("sensor_mode_hz").unwrap_or("config").into(),
                key: "sensor_mode_hz".into(),
                message: format!(
                    "expected one natural frequency > 0 Hz, or one per axis x,y[,z], got {v:?}"
                ),
            });
        }
    }
    if max_harmonic == Some(0) {
        return Err(ConfigError::Key {
            source_name: s.origin("max_harmonic").unwrap_or("config").into(),
            key: "max_harmonic".into(),
            message: "expected a spindle harmonic >= 1".into(),
        });
    }
    Ok(IdentifyCase {
        cutter,
        cuts,
        axes: s.text("axes")?,
        sample_rate_hz: s.quantity("sample_rate_hz", Quantity::FrequencyHz)?,
        section_s,
        peak_component,
        pulse_channel: s.text("pulse_channel")?,
        pulses_per_rev: s.count("pulses_per_rev")?.unwrap_or(1),
        tooth0_angle: s
            .quantity("tooth0_angle_deg", Quantity::AngleDeg)?
            .map(f64::to_radians),
        fit_tilt,
        chain,
        sensor_frf,
        sensor_mode_hz,
        max_harmonic,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{layer_from_toml, Settings};

    /// A list of feeds that matches neither one value nor the recordings: the message names the
    /// key, the file, how many values were expected for how many recordings, and how many came
    /// (with one recording it once read "expected 1 value or 1 (one per recording)").
    #[test]
    fn a_list_of_the_wrong_length_names_what_was_expected() {
        let toml =
            "teeth = 4\ndiameter_mm = 10\nhelix_deg = 30\nrpm = 3240\nfz_mm = [0.05, 0.08]\n\
                    ap_mm = 2\nae_mm = 2\nmode = \"down\"\n";
        let mut s = Settings::new();
        s.push(layer_from_toml("cut.toml", toml, &identify_key_names()).unwrap());
        let one = resolve_identify(&s, 1).unwrap_err().to_string();
        assert!(
            one.contains("cut.toml")
                && one.contains("fz_mm")
                && one.ends_with("expected 1 value for the 1 recording given, got 2"),
            "{one}"
        );
        let three = resolve_identify(&s, 3).unwrap_err().to_string();
        assert!(
            three.ends_with("expected 1 value, or 3 (one per recording: 3 given), got 2"),
            "{three}"
        );
        assert!(resolve_identify(&s, 2).is_ok());
    }
}
