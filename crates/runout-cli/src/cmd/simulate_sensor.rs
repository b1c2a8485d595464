//! Sensor flags of `runout simulate --recording …` (issue 11 item 2): parsed into a
//! [`SensorRequest`]; the chain itself (modes, FRF filtering, oversampling) is
//! [`runout::simulate::sensor`].

use anyhow::{bail, Result};
use runout::simulate::SensorRequest;
use runout::Source;
use runout_io::units::{parse_quantity, Quantity};
use std::path::PathBuf;

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
    /// The sensor given by the flags, `None` when none was given (a rigid sensor).
    pub fn request(&self) -> Result<Option<SensorRequest>> {
        if self.sensor_frf.is_some() && self.sensor_mode_hz.is_some() {
            bail!("--sensor-frf and --sensor-mode-hz: give one sensor chain, not both");
        }
        if self.sensor_damping.is_some() && self.sensor_mode_hz.is_none() {
            bail!(
                "--sensor-damping needs --sensor-mode-hz (the natural frequency of the mode, Hz)"
            );
        }
        if let Some(path) = &self.sensor_frf {
            return Ok(Some(SensorRequest::Frf(Source::path(path))));
        }
        let Some(f_text) = &self.sensor_mode_hz else {
            return Ok(None);
        };
        let frequency_hz = per_axis(
            "--sensor-mode-hz",
            f_text,
            Quantity::FrequencyHz,
            "a natural frequency > 0 Hz (or `rigid`)",
        )?;
        let damping = self
            .sensor_damping
            .as_deref()
            .map(|t| {
                per_axis(
                    "--sensor-damping",
                    t,
                    Quantity::Dimensionless,
                    "a damping ratio between 0 and 1",
                )
            })
            .transpose()?;
        Ok(Some(SensorRequest::Modes {
            frequency_hz,
            damping,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use runout::simulate::sensor::{chain, SensorChain};
    use runout_core::chain::{AxisChain, SensorMode};

    struct F(SensorFlags);
    impl F {
        fn chain(&self) -> Result<Option<SensorChain>> {
            self.0.request()?.as_ref().map(chain).transpose()
        }
    }

    fn flags(f: Option<&str>, z: Option<&str>) -> F {
        F(SensorFlags {
            sensor_mode_hz: f.map(String::from),
            sensor_damping: z.map(String::from),
            sensor_frf: None,
        })
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
