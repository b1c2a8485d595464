//! The simulated measuring chain of `runout simulate --recording …` (issue 11 item 2): a
//! resonant dynamometer between the cut and the written recording.
//!
//! As a real sensor: the cut is simulated [`OVERSAMPLE`]× finer than the recording, each force
//! channel (with its air-cut padding, so the sensor rings at the cut's entry as a real one does)
//! runs through the chain at that rate ([`AxisChain::filter`]: exact first-order-hold
//! integration of each mode, or FFT filtering by a measured FRF), is decimated to the recording
//! rate, and only then does the measurement noise go in (noise is after the sensor).

use anyhow::{bail, Context, Result};
use runout_core::chain::{AxisChain, MeasuringChain, SensorMode};
use runout_io::units::{parse_quantity, Quantity};
use std::path::PathBuf;

/// Oversampling of the simulated cut relative to the recording when a sensor chain is given:
/// the first-order hold of the filter attenuates harmonic f by sinc²(πf/(8·f_s)) — < 0.3 % up
/// to 0.2·f_s, < 1.3 % at the recording's Nyquist frequency.
pub const OVERSAMPLE: usize = 8;

/// Sensor flags of `runout simulate --recording …`.
#[derive(clap::Args, Debug, Default)]
pub struct SensorFlags {
    /// Simulated sensor mode: natural frequency f_n (Hz) of one second-order mode on every force
    /// axis, or per axis as a comma list `x,y,z` (e.g. `1100,1300,2500`; `rigid` for an axis
    /// without a mode). The cut is then simulated 8× oversampled, filtered by the mode, decimated
    /// to --sample-rate-hz, and the noise is added after the sensor (--out, --json peaks and
    /// --plot then show the oversampled cut itself, without the sensor). Needs --recording.
    #[arg(long, allow_hyphen_values = true)]
    pub sensor_mode_hz: Option<String>,
    /// Damping ratio ζ of the sensor mode(s) (dimensionless, 0 < ζ < 1), one value for every axis
    /// or a comma list `x,y,z` [default 0.03].
    #[arg(long, allow_hyphen_values = true)]
    pub sensor_damping: Option<String>,
    /// Simulated sensor from a measured FRF table (columns `freq_Hz, xx_re, xx_im, yy_re, yy_im[,
    /// zz_re, zz_im]`, frequency in Hz, responses in any consistent unit, normalised by the first
    /// row; axes without columns are rigid), instead of --sensor-mode-hz. Needs --recording.
    #[arg(long)]
    pub sensor_frf: Option<PathBuf>,
}

/// The parsed chain and a one-line description of it (for the recording's header and the JSON).
#[derive(Debug, Clone)]
pub struct SensorChain {
    /// Chain per axis.
    pub chain: MeasuringChain,
    /// Human-readable description.
    pub description: String,
    /// JSON description.
    pub json: serde_json::Value,
}

/// One value or three (x, y, z) from a comma list; `rigid` entries are `None`.
fn per_axis(flag: &str, text: &str, q: Quantity, what: &str) -> Result<[Option<f64>; 3]> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if !(parts.len() == 1 || parts.len() == 3) {
        bail!(
            "{flag}: expected one {what} for every axis or three as `x,y,z`, got {} values in `{text}`",
            parts.len()
        );
    }
    let mut out = [None; 3];
    for (i, p) in parts.iter().enumerate() {
        let v = if p.eq_ignore_ascii_case("rigid") {
            None
        } else {
            Some(
                parse_quantity(p, q)
                    .map_err(|e| anyhow::anyhow!("{flag}: expected {what}: {e}"))?,
            )
        };
        if parts.len() == 1 {
            out = [v; 3];
        } else {
            out[i] = v;
        }
    }
    Ok(out)
}

impl SensorFlags {
    /// The chain given by the flags, `None` when none was given (a rigid sensor).
    pub fn chain(&self) -> Result<Option<SensorChain>> {
        if self.sensor_frf.is_some() && self.sensor_mode_hz.is_some() {
            bail!("--sensor-frf and --sensor-mode-hz: give one sensor chain, not both");
        }
        if self.sensor_damping.is_some() && self.sensor_mode_hz.is_none() {
            bail!(
                "--sensor-damping needs --sensor-mode-hz (the natural frequency of the mode, Hz)"
            );
        }
        if let Some(path) = &self.sensor_frf {
            let chain = runout_io::frf::read_frf(path).context("--sensor-frf")?;
            let axes: Vec<&str> = ["x", "y", "z"]
                .into_iter()
                .zip([&chain.x, &chain.y, &chain.z])
                .filter(|(_, c)| !c.is_rigid())
                .map(|(a, _)| a)
                .collect();
            let description = format!(
                "measured FRF {} on {} (other axes rigid)",
                path.display(),
                axes.join(" ")
            );
            let json = serde_json::json!({
                "kind": "measured_frf",
                "file": path.display().to_string(),
                "axes": axes,
                "oversample": OVERSAMPLE,
            });
            return Ok(Some(SensorChain {
                chain,
                description,
                json,
            }));
        }
        let Some(f_text) = &self.sensor_mode_hz else {
            return Ok(None);
        };
        let f = per_axis(
            "--sensor-mode-hz",
            f_text,
            Quantity::FrequencyHz,
            "a natural frequency > 0 Hz (or `rigid`)",
        )?;
        let z = match &self.sensor_damping {
            Some(t) => per_axis(
                "--sensor-damping",
                t,
                Quantity::Dimensionless,
                "a damping ratio between 0 and 1",
            )?,
            None => [Some(0.03); 3],
        };
        let mut axes = [AxisChain::Rigid, AxisChain::Rigid, AxisChain::Rigid];
        let mut parts = Vec::new();
        let mut modes_json = Vec::new();
        for (i, name) in ["x", "y", "z"].iter().enumerate() {
            let Some(fn_hz) = f[i] else { continue };
            let zeta = z[i].ok_or_else(|| {
                anyhow::anyhow!("--sensor-damping: axis {name} has a mode at {fn_hz} Hz but damping `rigid`; expected a damping ratio between 0 and 1")
            })?;
            let mode = SensorMode::new(fn_hz, zeta, 1.0).map_err(|e| {
                let flag = if e.param == "sensor_damping" {
                    "--sensor-damping"
                } else {
                    "--sensor-mode-hz"
                };
                anyhow::anyhow!(
                    "{flag} (axis {name}): expected {}, got {}",
                    e.expected,
                    e.got
                )
            })?;
            axes[i] = AxisChain::Modes(vec![mode]);
            parts.push(format!("{name} {fn_hz} Hz zeta {zeta}"));
            modes_json.push(serde_json::json!({
                "axis": name,
                "frequency_hz": fn_hz,
                "damping": zeta,
            }));
        }
        if parts.is_empty() {
            bail!("--sensor-mode-hz: every axis is `rigid`; expected at least one natural frequency > 0 Hz");
        }
        let [x, y, zc] = axes;
        Ok(Some(SensorChain {
            chain: MeasuringChain { x, y, z: zc },
            description: format!("second-order mode {} (other axes rigid)", parts.join(" / ")),
            json: serde_json::json!({
                "kind": "modes",
                "modes": modes_json,
                "oversample": OVERSAMPLE,
            }),
        }))
    }
}

/// Run one padded channel, sampled at `OVERSAMPLE·fs`, through `chain` and decimate it to `fs`.
pub fn through_sensor(chain: &AxisChain, fs: f64, fine: &[f64]) -> Vec<f64> {
    chain
        .filter(fs * OVERSAMPLE as f64, fine)
        .into_iter()
        .step_by(OVERSAMPLE)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flags(f: Option<&str>, z: Option<&str>) -> SensorFlags {
        SensorFlags {
            sensor_mode_hz: f.map(String::from),
            sensor_damping: z.map(String::from),
            sensor_frf: None,
        }
    }

    #[test]
    fn lists_and_rigid_axes() {
        let c = flags(Some("1100,1.3kHz,rigid"), Some("0.03,0.05,0.1"))
            .chain()
            .unwrap()
            .unwrap();
        assert_eq!(
            c.chain.y,
            AxisChain::Modes(vec![SensorMode::new(1300.0, 0.05, 1.0).unwrap()])
        );
        assert!(c.chain.z.is_rigid());
        assert!(flags(None, None).chain().unwrap().is_none());
    }

    #[test]
    fn errors_name_the_flag() {
        for (f, z, want) in [
            (Some("1100,1200"), None, "--sensor-mode-hz: expected one"),
            (
                Some("-5"),
                None,
                "--sensor-mode-hz (axis x): expected a natural frequency",
            ),
            (
                Some("1100"),
                Some("1.5"),
                "--sensor-damping (axis x): expected a damping ratio",
            ),
            (
                Some("1100"),
                Some("abc"),
                "--sensor-damping: expected a damping ratio",
            ),
            (
                Some("1100mm"),
                None,
                "--sensor-mode-hz: expected a natural frequency",
            ),
            (
                None,
                Some("0.03"),
                "--sensor-damping needs --sensor-mode-hz",
            ),
            (Some("rigid"), None, "every axis is `rigid`"),
        ] {
            let e = flags(f, z).chain().unwrap_err().to_string();
            assert!(e.contains(want), "{f:?} {z:?}: {e}");
        }
    }
}
