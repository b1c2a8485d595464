//! The simulated cut as the channels of an instrument recording: air-cut padding, the sensor
//! ([`super::sensor`]) and Gaussian white noise after it.

use super::sensor::{through_sensor, SensorChain, OVERSAMPLE};
use anyhow::{bail, Result};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use runout_core::ForceSeries;

/// How the cut is written as a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingOptions {
    /// Gaussian white noise on each channel, σ in percent of the peak |F_xy| of the cut.
    pub noise_percent: f64,
    /// Air cut (no force, noise only) before and after the cut (s).
    pub air_cut_s: f64,
    /// Seed of the noise generator.
    pub seed: u64,
}

impl Default for RecordingOptions {
    fn default() -> Self {
        Self {
            noise_percent: 0.0,
            air_cut_s: 0.0,
            seed: 1,
        }
    }
}

/// The recording's channels (N, workpiece frame) at `sample_rate_hz`.
#[derive(Debug, Clone, Default)]
pub struct RecordingDetail {
    pub sample_rate_hz: f64,
    pub fx: Vec<f64>,
    pub fy: Vec<f64>,
    pub fz: Vec<f64>,
    /// Noise as requested (% of the peak |F_xy|) and as applied (σ, N).
    pub noise_percent: f64,
    pub noise_sigma_N: f64,
    /// The sensor's one-line description (`None` = rigid).
    pub sensor: Option<String>,
}

/// The series padded with `air_cut_s` of air cut at each end, through the sensor (decimated to
/// `fs`), plus noise of σ = `noise_percent`% of the peak |F_xy| (seeded).
pub fn channels(
    fs: f64,
    s: &ForceSeries,
    o: &RecordingOptions,
    sensor: Option<&SensorChain>,
) -> Result<RecordingDetail> {
    let (pct, air) = (o.noise_percent, o.air_cut_s);
    if !(pct >= 0.0 && air >= 0.0) {
        bail!(
            "--noise-percent and --air-cut-s must be >= 0 (got {}, {})",
            runout_core::limits::show(pct),
            runout_core::limits::show(air)
        );
    }
    runout_core::limits::result_size("--air-cut-s", 2.0 * air * fs + s.fx.len() as f64, 3.0)?;
    let peak = s.fxy().into_iter().fold(0.0, f64::max);
    let sigma = pct / 100.0 * peak;
    let normal = Normal::new(0.0, sigma.max(0.0)).map_err(|e| anyhow::anyhow!("noise: {e}"))?;
    let mut rng = rand::rngs::StdRng::seed_from_u64(o.seed);
    // with a sensor the series is OVERSAMPLE× finer than the recording: pad at the fine rate,
    // run through the sensor, decimate; the noise goes in after the sensor
    let fine = sensor.map_or(1, |_| OVERSAMPLE);
    let pad = (air * fs).round() as usize * fine;
    let mut channel = |v: &[f64], axis: usize| -> Vec<f64> {
        let mut out = vec![0.0; pad];
        out.extend_from_slice(v);
        out.extend(std::iter::repeat_n(0.0, pad));
        if let Some(sc) = sensor {
            let chain = [&sc.chain.x, &sc.chain.y, &sc.chain.z][axis];
            out = through_sensor(chain, fs, &out);
        }
        if sigma > 0.0 {
            out.iter_mut().for_each(|x| *x += normal.sample(&mut rng));
        }
        out
    };
    let (fx, fy, fz) = (channel(&s.fx, 0), channel(&s.fy, 1), channel(&s.fz, 2));
    Ok(RecordingDetail {
        sample_rate_hz: fs,
        fx,
        fy,
        fz,
        noise_percent: pct,
        noise_sigma_N: sigma,
        sensor: sensor.map(|sc| sc.description.clone()),
    })
}
