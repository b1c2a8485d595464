//! `shank.toml`: configuration of `runout shank force` (methods.md §3, issue 6).
//!
//! ```toml
//! [shank]                      # beam (methods.md §3.1)
//! modulus_gpa = 210
//! diameter_mm = 8
//! tool_length_mm = 65          # holder face to tool end
//! l1_mm = 10                   # sensor I height from the holder face
//! l2_mm = 30                   # sensor II height (nearer the tip)
//! load_point = "tip"           # or "mid-depth" (l_tool − a_p/2, needs axial_depth_mm)
//! axial_depth_mm = 2           # also sets the runout report height a_p/2 above the tip
//! # holder_stiffness_Nm_per_rad = 2e4   # rotational stiffness of the holder (optional)
//! # stiffness_N_per_um = 1.95           # measured K_δ (static calibration) overrides the beam
//! # density_kg_per_m3 = 7850    # for the first bending mode; default 14 500 (carbide) if
//! #                              # modulus_gpa ≥ 400, else 7 850 (steel)
//! # teeth = 3                    # tooth-passing harmonics k·K·n/60 (k ≤ 5) checked against the band
//!
//! [spindle]
//! rpm = 3000                   # nominal
//! # pulse_channel = "pulse"    # once-per-revolution mark (θ = 0 at its rising edge)
//!
//! [[pair]]                     # one per direction (x = feed, y = feed-normal)
//! axis = "x"
//! sensor_I = "xI"              # channel names in the recording
//! sensor_II = "xII"
//! sign = 1                     # −1 if a positive reading means the shank moved towards −axis
//!
//! [recording]
//! # sample_rate_hz = 20000     # if the file has no time column / rate line
//! # sensor_unit = "um"         # if the header gives no unit (um, mm, nm, V)
//! # sensitivity_um_per_V = 50  # for channels in V
//! # reference_axes = "x = -Fy, y = -Fx"   # dynamometer channels → workpiece frame (validation)
//!
//! [processing]
//! # air_cut_s = [[0.0, 0.4], [6.5, 6.8]]  # else detected
//! drift_correction = true
//! # lowpass_hz = 2000          # zero-phase Butterworth below the first bending mode
//! # lowpass_order = 4
//! # sensor_range_um = [-250, 250]         # samples at/after the limits are flagged
//!
//! [dynamics]                   # bending response of the tool (issue 11; docs/shank.md)
//! # beam_damping = 0.03        # ζ of the beam's first mode (bandwidth estimate)
//! # sensor_mode_hz = "beam"    # correct the force by one mode: Hz, or "beam" (its first mode)
//! # sensor_damping = 0.03      # ζ of that mode
//! # frf = "tool_frf.csv"       # or by a measured FRF (freq_Hz, xx_re, xx_im, yy_re, yy_im),
//! #                            # path relative to this file
//! # deconvolution_floor = 0.1  # ε of G = (1/H)·|H|⁴/(|H|⁴ + ε⁴) (dimensionless)
//! ```

use super::{ConfigError, Value};
use crate::units::{parse_quantity, Quantity};
use serde::Deserialize;

/// The whole file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShankConfig {
    /// Beam geometry.
    pub shank: BeamSection,
    /// Spindle.
    pub spindle: SpindleSection,
    /// Sensor pairs (1 or 2).
    pub pair: Vec<PairSection>,
    /// Recording details.
    #[serde(default)]
    pub recording: RecordingSection,
    /// Processing options.
    #[serde(default)]
    pub processing: ProcessingSection,
    /// Bending dynamics and force correction.
    #[serde(default)]
    pub dynamics: DynamicsSection,
}

/// `[dynamics]`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicsSection {
    /// Damping ratio of the beam's first mode (dimensionless).
    pub beam_damping: Option<f64>,
    /// Mode to correct by (Hz, or `"beam"`).
    pub sensor_mode_hz: Option<Value>,
    /// Damping ratio of that mode (dimensionless).
    pub sensor_damping: Option<f64>,
    /// Measured FRF file (relative to the config file).
    pub frf: Option<String>,
    /// Floor ε of the regularised inverse (dimensionless).
    pub deconvolution_floor: Option<f64>,
}

/// `load_point = "tip" | "mid-depth"`: where the cutting force acts on the shank beam.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum LoadPointWord {
    /// At the tool tip (l_tool).
    #[serde(rename = "tip")]
    Tip,
    /// At mid axial depth (l_tool − a_p/2; needs `axial_depth_mm`).
    #[serde(rename = "mid-depth")]
    MidDepth,
}

/// `axis = "x" | "y"` of a `[[pair]]` (upper case accepted).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum PairAxisWord {
    /// x: the feed direction.
    #[serde(rename = "x", alias = "X")]
    X,
    /// y: feed-normal.
    #[serde(rename = "y", alias = "Y")]
    Y,
}

impl PairAxisWord {
    /// `x` or `y`.
    pub fn name(self) -> &'static str {
        match self {
            PairAxisWord::X => "x",
            PairAxisWord::Y => "y",
        }
    }
}

/// `[shank]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamSection {
    /// Young's modulus (GPa).
    pub modulus_gpa: Value,
    /// Shank diameter (mm).
    pub diameter_mm: Value,
    /// Holder face to tool end (mm).
    pub tool_length_mm: Value,
    /// Sensor I height (mm).
    pub l1_mm: Value,
    /// Sensor II height (mm).
    pub l2_mm: Value,
    /// Where the cutting force acts (default the tip).
    pub load_point: Option<LoadPointWord>,
    /// Axial depth of cut (mm).
    pub axial_depth_mm: Option<Value>,
    /// Holder rotational stiffness (N·m/rad).
    #[serde(rename = "holder_stiffness_Nm_per_rad")]
    pub holder_stiffness_nm_per_rad: Option<Value>,
    /// Measured K_δ (N/µm).
    #[serde(rename = "stiffness_N_per_um")]
    pub stiffness_n_per_um: Option<Value>,
    /// Density of the tool (kg/m³).
    pub density_kg_per_m3: Option<Value>,
    /// Number of teeth of the cutter.
    pub teeth: Option<usize>,
}

/// `[spindle]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpindleSection {
    /// Nominal speed (rpm).
    pub rpm: Value,
    /// Pulse channel name.
    pub pulse_channel: Option<String>,
}

/// `[[pair]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairSection {
    /// `x` (feed) or `y` (feed-normal).
    pub axis: PairAxisWord,
    /// Channel of sensor I (at l1_mm).
    #[serde(rename = "sensor_I")]
    pub sensor_i: String,
    /// Channel of sensor II (at l2_mm).
    #[serde(rename = "sensor_II")]
    pub sensor_ii: String,
    /// +1 or −1.
    #[serde(default = "one")]
    pub sign: f64,
}

fn one() -> f64 {
    1.0
}

/// `[recording]`.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingSection {
    /// Sample rate (Hz).
    pub sample_rate_hz: Option<Value>,
    /// Unit of displacement channels without one in the header.
    pub sensor_unit: Option<String>,
    /// Sensor sensitivity for channels in volts (µm/V).
    #[serde(rename = "sensitivity_um_per_V")]
    pub sensitivity_um_per_v: Option<Value>,
    /// Axis mapping of the reference dynamometer channels.
    pub reference_axes: Option<String>,
}

/// `[processing]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProcessingSection {
    /// Air-cut segments (s).
    pub air_cut_s: Option<Vec<[f64; 2]>>,
    /// Linear drift correction between the air cuts.
    #[serde(default = "yes")]
    pub drift_correction: bool,
    /// Low-pass cutoff (Hz).
    pub lowpass_hz: Option<Value>,
    /// Low-pass order.
    pub lowpass_order: Option<usize>,
    /// Sensor range (µm).
    pub sensor_range_um: Option<[f64; 2]>,
    /// Minimum air revolutions.
    pub min_air_revolutions: Option<usize>,
    /// Revolutions kept per air cut.
    pub max_template_revolutions: Option<usize>,
}

fn yes() -> bool {
    true
}

impl Default for ProcessingSection {
    fn default() -> Self {
        Self {
            air_cut_s: None,
            drift_correction: true,
            lowpass_hz: None,
            lowpass_order: None,
            sensor_range_um: None,
            min_air_revolutions: None,
            max_template_revolutions: None,
        }
    }
}

impl ShankConfig {
    /// Parse the TOML text of `file` (unknown keys are errors with line and column).
    pub fn parse(file: &str, text: &str) -> Result<Self, ConfigError> {
        if let Ok(t) = text.parse::<toml::Table>() {
            super::reject_non_finite(file, &t)?;
        }
        toml::from_str(text).map_err(|e| ConfigError::Parse {
            file: file.into(),
            message: super::toml_error(text, &e),
        })
    }
}

/// Read a numeric value with its unit (`"8mm"`, `210`), naming the key on error.
pub fn number(file: &str, key: &str, v: &Value, q: Quantity) -> Result<f64, ConfigError> {
    let err = |message: String| ConfigError::Key {
        source_name: file.into(),
        key: key.into(),
        message,
    };
    match v {
        Value::Number(x) if x.is_finite() => Ok(*x),
        Value::Number(x) => Err(err(format!("{x} is not finite"))),
        Value::Text(t) => parse_quantity(t, q).map_err(|e| err(e.to_string())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_example_and_rejects_typos() {
        let text = "[shank]\nmodulus_gpa = 210\ndiameter_mm = \"8mm\"\ntool_length_mm = 65\nl1_mm = 10\nl2_mm = 30\n\
                    [spindle]\nrpm = 3000\n[[pair]]\naxis = \"x\"\nsensor_I = \"xI\"\nsensor_II = \"xII\"\n";
        let c = ShankConfig::parse("s.toml", text).unwrap();
        assert_eq!(
            number(
                "s.toml",
                "diameter_mm",
                &c.shank.diameter_mm,
                Quantity::LengthMm
            )
            .unwrap(),
            8.0
        );
        assert!(c.processing.drift_correction);
        let bad = text.replace("l2_mm", "l3_mm");
        let e = ShankConfig::parse("s.toml", &bad).unwrap_err().to_string();
        assert!(e.contains("l3_mm") && e.contains("s.toml"), "{e}");
    }
}
