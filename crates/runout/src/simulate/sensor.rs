//! The simulated measuring chain of `simulate` with a recording (issue 11 item 2): a resonant
//! dynamometer between the cut and the written recording.
//!
//! As a real sensor: the cut is simulated [`OVERSAMPLE`]× finer than the recording, each force
//! channel (with its air-cut padding, so the sensor rings at the cut's entry as a real one does)
//! runs through the chain at that rate ([`AxisChain::filter`]: exact first-order-hold
//! integration of each mode, or FFT filtering by a measured FRF), is decimated to the recording
//! rate, and only then does the measurement noise go in (noise is after the sensor).

use crate::job::Source;
use anyhow::{bail, Context, Result};
use runout_core::chain::{AxisChain, MeasuringChain, SensorMode};
use schemars::JsonSchema;
use serde::Serialize;

/// Oversampling of the simulated cut relative to the recording when a sensor chain is given:
/// the first-order hold of the filter attenuates harmonic f by sinc²(πf/(8·f_s)) — < 0.3 % up
/// to 0.2·f_s, < 1.3 % at the recording's Nyquist frequency.
pub const OVERSAMPLE: usize = 8;

/// Default damping ratio ζ of a simulated sensor mode.
pub const DEFAULT_DAMPING: f64 = 0.03;

/// The sensor of a simulated recording.
#[derive(Debug, Clone)]
pub enum SensorRequest {
    /// One second-order mode per axis (x, y, z): natural frequency (Hz; `None` = rigid axis)
    /// and damping ratio ζ (0 < ζ < 1; `None` on an axis with a mode is an error). `damping`
    /// `None` = [`DEFAULT_DAMPING`] on every axis.
    Modes {
        frequency_hz: [Option<f64>; 3],
        damping: Option<[Option<f64>; 3]>,
    },
    /// A measured FRF table (`freq_Hz, xx_re, xx_im, yy_re, yy_im[, zz_re, zz_im]`).
    Frf(Source),
}

/// One mode of the simulated sensor, as reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ModeReport {
    /// `x`, `y` or `z`.
    pub axis: String,
    pub frequency_hz: f64,
    /// Damping ratio ζ (dimensionless).
    pub damping: f64,
}

/// The simulated sensor as reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum SensorReport {
    /// A measured FRF on the listed axes (the others rigid).
    MeasuredFrf {
        file: String,
        axes: Vec<String>,
        oversample: usize,
    },
    /// Second-order modes (axes not listed are rigid).
    Modes {
        modes: Vec<ModeReport>,
        oversample: usize,
    },
}

/// The chain, a one-line description (for the recording's header) and the report.
#[derive(Debug, Clone)]
pub struct SensorChain {
    /// Chain per axis.
    pub chain: MeasuringChain,
    /// Human-readable description.
    pub description: String,
    /// As reported in the JSON.
    pub report: SensorReport,
}

/// The chain a request describes; errors name the flag (`--sensor-mode-hz`, `--sensor-damping`,
/// `--sensor-frf`) and what was expected.
pub fn chain(req: &SensorRequest) -> Result<SensorChain> {
    match req {
        SensorRequest::Frf(src) => {
            let chain = match src.as_path() {
                Some(p) => runout_io::frf::read_frf(p),
                None => {
                    runout_io::frf::parse_frf(src.name(), &src.read_text().context("--sensor-frf")?)
                }
            }
            .context("--sensor-frf")?;
            let axes: Vec<String> = ["x", "y", "z"]
                .into_iter()
                .zip([&chain.x, &chain.y, &chain.z])
                .filter(|(_, c)| !c.is_rigid())
                .map(|(a, _)| a.to_string())
                .collect();
            Ok(SensorChain {
                description: format!(
                    "measured FRF {} on {} (other axes rigid)",
                    src.name(),
                    axes.join(" ")
                ),
                chain,
                report: SensorReport::MeasuredFrf {
                    file: src.name().to_string(),
                    axes,
                    oversample: OVERSAMPLE,
                },
            })
        }
        SensorRequest::Modes {
            frequency_hz,
            damping,
        } => modes(frequency_hz, &damping.unwrap_or([Some(DEFAULT_DAMPING); 3])),
    }
}

fn modes(f: &[Option<f64>; 3], z: &[Option<f64>; 3]) -> Result<SensorChain> {
    let mut axes = [AxisChain::Rigid, AxisChain::Rigid, AxisChain::Rigid];
    let mut parts = Vec::new();
    let mut reports = Vec::new();
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
        reports.push(ModeReport {
            axis: name.to_string(),
            frequency_hz: fn_hz,
            damping: zeta,
        });
    }
    if parts.is_empty() {
        bail!("--sensor-mode-hz: every axis is `rigid`; expected at least one natural frequency > 0 Hz");
    }
    let [x, y, zc] = axes;
    Ok(SensorChain {
        chain: MeasuringChain { x, y, z: zc },
        description: format!("second-order mode {} (other axes rigid)", parts.join(" / ")),
        report: SensorReport::Modes {
            modes: reports,
            oversample: OVERSAMPLE,
        },
    })
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

    fn modes_req(f: [Option<f64>; 3], z: Option<[Option<f64>; 3]>) -> SensorRequest {
        SensorRequest::Modes {
            frequency_hz: f,
            damping: z,
        }
    }

    #[test]
    fn modes_per_axis_and_rigid_axes() {
        let c = chain(&modes_req(
            [Some(1100.0), Some(1300.0), None],
            Some([Some(0.03), Some(0.05), Some(0.1)]),
        ))
        .unwrap();
        assert_eq!(
            c.chain.y,
            AxisChain::Modes(vec![SensorMode::new(1300.0, 0.05, 1.0).unwrap()])
        );
        assert!(c.chain.z.is_rigid());
        assert!(c
            .description
            .contains("x 1100 Hz zeta 0.03 / y 1300 Hz zeta 0.05"));
    }

    #[test]
    fn errors_name_the_flag() {
        for (f, z, want) in [
            (
                [Some(-5.0); 3],
                None,
                "--sensor-mode-hz (axis x): expected a natural frequency",
            ),
            (
                [Some(1100.0); 3],
                Some([Some(1.5); 3]),
                "--sensor-damping (axis x): expected a damping ratio",
            ),
            (
                [Some(1100.0); 3],
                Some([Some(0.03), None, Some(0.03)]),
                "--sensor-damping: axis y has a mode at 1100 Hz but damping `rigid`",
            ),
            ([None; 3], None, "every axis is `rigid`"),
        ] {
            let e = chain(&modes_req(f, z)).unwrap_err().to_string();
            assert!(e.contains(want), "{f:?} {z:?}: {e}");
        }
    }

    #[test]
    fn an_frf_in_memory_is_named() {
        let text = "freq_Hz,xx_re,xx_im,yy_re,yy_im\n0,1,0,1,0\n1000,1.5,-0.2,1.2,-0.1\n";
        let c = chain(&SensorRequest::Frf(Source::bytes(
            "mem_frf.csv",
            text.as_bytes(),
        )))
        .unwrap();
        assert!(!c.chain.x.is_rigid() && c.chain.z.is_rigid());
        assert!(
            c.description.contains("mem_frf.csv on x y"),
            "{}",
            c.description
        );
    }
}
