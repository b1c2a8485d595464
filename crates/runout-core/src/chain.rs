//! The measuring chain between the cut and the recorded signal (issue 11).
//!
//! A dynamometer, its fixture and the workpiece (or a tool shank read by displacement sensors) are
//! not rigid: the recorded force is the cutting force seen through the sensor's dynamics. For the
//! periodic, synchronously averaged waveform this is one complex factor per spindle harmonic k
//! and axis:
//!
//! measured(kΩ) = H(kΩ) · cut(kΩ),   H(0) = 1,
//!
//! with H either
//! * **second-order modes** ([`SensorMode`]): H(f) = (1 − Σg_j) + Σ g_j / (1 − r_j² + 2iζ_j r_j),
//!   r_j = f / f_j — the classic single-degree-of-freedom receptance normalised to its static
//!   value, with relative gains g_j (one mode with g = 1 is the pure mode); or
//! * a **measured FRF** ([`FrfCurve`]): an impact-test export, interpolated linearly in its real
//!   and imaginary parts and normalised by its lowest-frequency value (taken as static).
//!
//! [`AxisChain::filter`] runs a sampled series through the chain in the time domain, which is how
//! `runout simulate` puts a resonant sensor into synthetic recordings: each mode is integrated
//! exactly for an input that is linear between samples (first-order hold), so that a sinusoid at
//! f reaches its steady state with the gain |H(f)|·sinc²(f/f_s) of the hold.
//!
//! ```
//! use runout_core::chain::{AxisChain, SensorMode};
//! let chain = AxisChain::Modes(vec![SensorMode::new(1100.0, 0.03, 1.0)?]);
//! assert!((chain.response(0.0).unwrap().re - 1.0).abs() < 1e-12);
//! let at_mode = chain.response(1100.0).unwrap();
//! assert!((at_mode.norm() - 1.0 / (2.0 * 0.03)).abs() < 1e-9); // Q = 1/2ζ at resonance
//! # Ok::<(), runout_core::ParamError>(())
//! ```

use crate::error::ParamError;
use crate::identify::FrameAxis;
use nalgebra::{Matrix2, Matrix4, Vector2};
pub use realfft::num_complex::Complex64;
use serde::Serialize;

/// One second-order mode of the sensor: natural frequency f_n (Hz), damping ratio ζ and relative
/// gain g (the share of the static response that passes through the mode).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SensorMode {
    /// Natural frequency f_n (Hz).
    pub frequency_hz: f64,
    /// Damping ratio ζ (dimensionless, 0 < ζ < 1).
    pub damping: f64,
    /// Relative gain g (dimensionless); 1 for a single mode.
    pub gain: f64,
}

impl SensorMode {
    /// A mode with f_n > 0 Hz, 0 < ζ < 1 and a finite gain.
    pub fn new(frequency_hz: f64, damping: f64, gain: f64) -> Result<Self, ParamError> {
        if !(frequency_hz.is_finite() && frequency_hz > 0.0) {
            return Err(ParamError::new(
                "sensor_mode_hz",
                "a natural frequency > 0 Hz",
                frequency_hz,
            ));
        }
        if !(damping.is_finite() && damping > 0.0 && damping < 1.0) {
            return Err(ParamError::new(
                "sensor_damping",
                "a damping ratio between 0 and 1 (exclusive)",
                damping,
            ));
        }
        if !gain.is_finite() {
            return Err(ParamError::new(
                "sensor_gain",
                "a finite relative gain",
                gain,
            ));
        }
        Ok(SensorMode {
            frequency_hz,
            damping,
            gain,
        })
    }

    /// Normalised receptance 1 / (1 − r² + 2iζr), r = f/f_n (without the gain).
    pub fn unit_response(&self, f_hz: f64) -> Complex64 {
        let r = f_hz / self.frequency_hz;
        Complex64::new(1.0 - r * r, 2.0 * self.damping * r).inv()
    }

    /// Derivatives of [`SensorMode::unit_response`] with respect to f_n (per Hz) and ζ.
    pub fn unit_response_derivatives(&self, f_hz: f64) -> (Complex64, Complex64) {
        let r = f_hz / self.frequency_hz;
        let d = Complex64::new(1.0 - r * r, 2.0 * self.damping * r);
        let h2 = (d * d).inv();
        // ∂D/∂r = −2r + 2iζ, ∂r/∂f_n = −r/f_n; ∂D/∂ζ = 2ir
        let dd_dfn = Complex64::new(-2.0 * r, 2.0 * self.damping) * (-r / self.frequency_hz);
        let dd_dz = Complex64::new(0.0, 2.0 * r);
        (-h2 * dd_dfn, -h2 * dd_dz)
    }
}

/// A measured frequency response of one axis: frequencies (Hz, increasing) and complex values,
/// normalised so that the lowest-frequency value is 1 (that value is taken as the static one;
/// an impact-test export should start at or near 0 Hz).
#[derive(Debug, Clone, PartialEq)]
pub struct FrfCurve {
    freq_hz: Vec<f64>,
    values: Vec<Complex64>,
}

impl FrfCurve {
    /// Build from (frequency, response) pairs; `name` labels errors (e.g. the file and axis).
    pub fn new(name: &str, freq_hz: Vec<f64>, values: Vec<Complex64>) -> Result<Self, ParamError> {
        if freq_hz.len() < 2 || freq_hz.len() != values.len() {
            return Err(ParamError::new(
                name,
                "at least 2 (frequency, response) rows",
                format!("{} frequencies, {} values", freq_hz.len(), values.len()),
            ));
        }
        if let Some(i) = (0..freq_hz.len()).find(|&i| {
            !freq_hz[i].is_finite()
                || freq_hz[i] < 0.0
                || (i > 0 && freq_hz[i] <= freq_hz[i - 1])
                || !(values[i].re.is_finite() && values[i].im.is_finite())
        }) {
            return Err(ParamError::new(
                format!("{name} row {}", i + 1),
                "finite values at frequencies >= 0 Hz, strictly increasing",
                format!("{} Hz, {}", freq_hz[i], values[i]),
            ));
        }
        let h0 = values[0];
        if h0.norm() == 0.0 {
            return Err(ParamError::new(
                format!("{name} row 1"),
                "a non-zero static response (the FRF is normalised by it)",
                h0,
            ));
        }
        Ok(FrfCurve {
            values: values.iter().map(|v| v / h0).collect(),
            freq_hz,
        })
    }

    /// Highest frequency of the table (Hz).
    pub fn max_frequency_hz(&self) -> f64 {
        *self.freq_hz.last().expect("at least 2 rows")
    }

    /// Linear interpolation at `f_hz`; `None` above the table. Below the first frequency the
    /// first (static) value 1 is used.
    pub fn at(&self, f_hz: f64) -> Option<Complex64> {
        let f = &self.freq_hz;
        if f_hz.is_nan() || f_hz > self.max_frequency_hz() {
            return None;
        }
        if f_hz <= f[0] {
            return Some(self.values[0]);
        }
        let i = f.partition_point(|&x| x <= f_hz).min(f.len() - 1);
        let t = (f_hz - f[i - 1]) / (f[i] - f[i - 1]);
        Some(self.values[i - 1] * (1.0 - t) + self.values[i] * t)
    }
}

/// The chain of one axis.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum AxisChain {
    /// H = 1 at every frequency.
    #[default]
    Rigid,
    /// Second-order modes: H = (1 − Σg) + Σ g·H_mode.
    Modes(Vec<SensorMode>),
    /// A measured FRF.
    Frf(FrfCurve),
}

impl AxisChain {
    /// H(f); `None` where a measured FRF does not reach `f_hz`.
    pub fn response(&self, f_hz: f64) -> Option<Complex64> {
        match self {
            AxisChain::Rigid => Some(Complex64::new(1.0, 0.0)),
            AxisChain::Modes(modes) => {
                let static_share = 1.0 - modes.iter().map(|m| m.gain).sum::<f64>();
                Some(
                    modes
                        .iter()
                        .map(|m| m.unit_response(f_hz) * m.gain)
                        .fold(Complex64::new(static_share, 0.0), |a, b| a + b),
                )
            }
            AxisChain::Frf(c) => c.at(f_hz),
        }
    }

    /// H(f), a measured FRF held at its last value above its range.
    pub fn response_clamped(&self, f_hz: f64) -> Complex64 {
        match self {
            AxisChain::Frf(c) => c.at(f_hz).unwrap_or(c.values[c.values.len() - 1]),
            other => other.response(f_hz).unwrap_or(Complex64::new(1.0, 0.0)),
        }
    }

    /// One revolution of a periodic waveform (N samples at spindle frequency `spindle_hz`) as the
    /// chain records it: harmonic k times H(k·f_rev) (and times sinc²(πk/n_s) when the record,
    /// n_s samples per revolution, was resampled onto the grid by linear interpolation), k < N/2.
    pub fn apply_periodic(
        &self,
        values: &[f64],
        spindle_hz: f64,
        samples_per_rev: Option<f64>,
    ) -> Vec<f64> {
        let n = values.len();
        if n < 2 || self.is_rigid() && samples_per_rev.is_none() {
            return values.to_vec();
        }
        let mut planner = realfft::RealFftPlanner::<f64>::new();
        let fwd = planner.plan_fft_forward(n);
        let inv = planner.plan_fft_inverse(n);
        let mut buf = values.to_vec();
        let mut spec = fwd.make_output_vec();
        fwd.process(&mut buf, &mut spec).expect("fft length");
        for (k, s) in spec.iter_mut().enumerate().skip(1) {
            let mut h = self.response_clamped(k as f64 * spindle_hz);
            if let Some(spr) = samples_per_rev {
                let x = std::f64::consts::PI * k as f64 / spr;
                h *= (x.sin() / x).powi(2);
            }
            *s *= h;
        }
        if n.is_multiple_of(2) {
            if let Some(s) = spec.last_mut() {
                s.im = 0.0;
            }
        }
        let mut out = inv.make_output_vec();
        inv.process(&mut spec, &mut out).expect("fft length");
        out.iter().map(|v| v / n as f64).collect()
    }

    /// True for [`AxisChain::Rigid`].
    pub fn is_rigid(&self) -> bool {
        matches!(self, AxisChain::Rigid)
    }

    /// Run a series sampled at `sample_rate_hz` through the chain (starting at rest at the first
    /// value). Modes: exact first-order-hold integration of each mode. Measured FRF: circular
    /// filtering of the zero-padded series by FFT, the FRF held at its last value above its range.
    pub fn filter(&self, sample_rate_hz: f64, values: &[f64]) -> Vec<f64> {
        match self {
            AxisChain::Rigid => values.to_vec(),
            AxisChain::Modes(modes) => {
                let static_share = 1.0 - modes.iter().map(|m| m.gain).sum::<f64>();
                let mut out: Vec<f64> = values.iter().map(|v| v * static_share).collect();
                for m in modes {
                    for (o, y) in out.iter_mut().zip(mode_filter(m, sample_rate_hz, values)) {
                        *o += m.gain * y;
                    }
                }
                out
            }
            AxisChain::Frf(c) => frf_filter(c, sample_rate_hz, values),
        }
    }
}

/// Exact first-order-hold discretisation of y'' + 2ζω y' + ω² y = ω² u: with
/// exp([[A·T, B·T, 0], [0, 0, 1], [0, 0, 0]]) = [[Φ, Γa, Γb], …], the state s = (y, y') steps as
/// s⁺ = Φ s + Γa u_k + Γb (u_{k+1} − u_k).
fn mode_filter(m: &SensorMode, fs: f64, u: &[f64]) -> Vec<f64> {
    let w = std::f64::consts::TAU * m.frequency_hz;
    let t = 1.0 / fs;
    let a = Matrix2::new(0.0, 1.0, -w * w, -2.0 * m.damping * w) * t;
    let b = Vector2::new(0.0, w * w) * t;
    let mut big = Matrix4::zeros();
    big.fixed_view_mut::<2, 2>(0, 0).copy_from(&a);
    big.fixed_view_mut::<2, 1>(0, 2).copy_from(&b);
    big[(2, 3)] = 1.0;
    let e = big.exp();
    let phi: Matrix2<f64> = e.fixed_view::<2, 2>(0, 0).into_owned();
    let ga: Vector2<f64> = e.fixed_view::<2, 1>(0, 2).into_owned();
    let gb: Vector2<f64> = e.fixed_view::<2, 1>(0, 3).into_owned();
    let mut s = Vector2::new(u.first().copied().unwrap_or(0.0), 0.0);
    let mut out = Vec::with_capacity(u.len());
    for (k, &uk) in u.iter().enumerate() {
        out.push(s[0]);
        let next = u.get(k + 1).copied().unwrap_or(uk);
        s = phi * s + ga * uk + gb * (next - uk);
    }
    out
}

fn frf_filter(c: &FrfCurve, fs: f64, u: &[f64]) -> Vec<f64> {
    let n = u.len();
    if n == 0 {
        return Vec::new();
    }
    let len = (2 * n).next_power_of_two();
    let mut planner = realfft::RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(len);
    let inv = planner.plan_fft_inverse(len);
    let mean = u.iter().sum::<f64>() / n as f64;
    let mut buf: Vec<f64> = u.iter().map(|v| v - mean).collect();
    buf.resize(len, 0.0);
    let mut spec = fwd.make_output_vec();
    fwd.process(&mut buf, &mut spec).expect("fft length");
    let last = c.values[c.values.len() - 1];
    for (k, s) in spec.iter_mut().enumerate() {
        let f = k as f64 * fs / len as f64;
        *s *= c.at(f).unwrap_or(last);
    }
    // the Nyquist and DC bins of a real spectrum must be real
    spec[0].im = 0.0;
    if let Some(s) = spec.last_mut() {
        s.im = 0.0;
    }
    let mut out = inv.make_output_vec();
    inv.process(&mut spec, &mut out).expect("fft length");
    out.truncate(n);
    out.iter().map(|v| v / len as f64 + mean).collect()
}

/// The measuring chain of all three axes of the workpiece frame (cross-axis terms are not
/// modelled).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeasuringChain {
    /// F_x (feed direction).
    pub x: AxisChain,
    /// F_y (feed-normal direction).
    pub y: AxisChain,
    /// F_z (tool axis).
    pub z: AxisChain,
}

impl MeasuringChain {
    /// The chain of `axis`.
    pub fn axis(&self, axis: FrameAxis) -> &AxisChain {
        match axis {
            FrameAxis::X => &self.x,
            FrameAxis::Y => &self.y,
            FrameAxis::Z => &self.z,
        }
    }

    /// True when no axis has dynamics.
    pub fn is_rigid(&self) -> bool {
        self.x.is_rigid() && self.y.is_rigid() && self.z.is_rigid()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steady-state gain and phase of a sampled sinusoid through the time-domain mode filter
    /// equal |H(f)| and arg H(f) up to the first-order hold's sinc²(f/f_s) (a real factor).
    #[test]
    fn mode_filter_matches_the_receptance() {
        let m = SensorMode::new(1100.0, 0.03, 1.0).unwrap();
        let fs = 96_000.0;
        for f in [200.0, 900.0, 1100.0, 1500.0, 4000.0] {
            let n = 96_000;
            let u: Vec<f64> = (0..n)
                .map(|q| (std::f64::consts::TAU * f * q as f64 / fs).sin())
                .collect();
            let y = AxisChain::Modes(vec![m]).filter(fs, &u);
            // fit a·sin + b·cos over the last half (transient decayed: e^{−ζωt} < 1e-20)
            let (mut ss, mut sc) = (0.0, 0.0);
            for (q, yq) in y.iter().enumerate().skip(n / 2) {
                let ph = std::f64::consts::TAU * f * q as f64 / fs;
                ss += yq * ph.sin();
                sc += yq * ph.cos();
            }
            let half = (n / 2) as f64 / 2.0;
            let got = Complex64::new(ss / half, sc / half);
            let x = std::f64::consts::PI * f / fs;
            let sinc2 = (x.sin() / x).powi(2);
            let want = m.unit_response(f) * sinc2;
            assert!(
                (got - want).norm() < 2e-3 * want.norm(),
                "{f} Hz: {got} vs {want}"
            );
        }
    }

    #[test]
    fn derivatives_match_differences() {
        let m = SensorMode::new(1100.0, 0.05, 1.0).unwrap();
        let f = 950.0;
        let (dfn, dz) = m.unit_response_derivatives(f);
        let h = 1e-4;
        let num_fn = (SensorMode::new(1100.0 + h, 0.05, 1.0)
            .unwrap()
            .unit_response(f)
            - SensorMode::new(1100.0 - h, 0.05, 1.0)
                .unwrap()
                .unit_response(f))
            / (2.0 * h);
        let num_z = (SensorMode::new(1100.0, 0.05 + 1e-7, 1.0)
            .unwrap()
            .unit_response(f)
            - SensorMode::new(1100.0, 0.05 - 1e-7, 1.0)
                .unwrap()
                .unit_response(f))
            / 2e-7;
        assert!((dfn - num_fn).norm() < 1e-6 * num_fn.norm());
        assert!((dz - num_z).norm() < 1e-5 * num_z.norm());
    }

    #[test]
    fn frf_interpolates_and_normalises() {
        let c = FrfCurve::new(
            "frf",
            vec![0.0, 100.0, 200.0],
            vec![
                Complex64::new(2.0, 0.0),
                Complex64::new(4.0, 2.0),
                Complex64::new(0.0, 0.0),
            ],
        )
        .unwrap();
        assert_eq!(c.at(0.0), Some(Complex64::new(1.0, 0.0)));
        assert_eq!(c.at(50.0), Some(Complex64::new(1.5, 0.5)));
        assert_eq!(c.at(200.1), None);
        let err = FrfCurve::new(
            "f.csv xx",
            vec![0.0, 0.0],
            vec![Complex64::new(1.0, 0.0); 2],
        );
        assert!(err.unwrap_err().to_string().contains("f.csv xx row 2"));
    }

    /// The FFT filter with the mode's own FRF reproduces the mode filter on a slow signal.
    #[test]
    fn frf_filter_agrees_with_mode_filter() {
        let m = SensorMode::new(800.0, 0.05, 1.0).unwrap();
        let fs = 50_000.0;
        let freq: Vec<f64> = (0..=2500).map(|i| i as f64 * 10.0).collect();
        let vals = freq.iter().map(|&f| m.unit_response(f)).collect();
        let frf = AxisChain::Frf(FrfCurve::new("frf", freq, vals).unwrap());
        let u: Vec<f64> = (0..20_000)
            .map(|q| {
                let t = q as f64 / fs;
                (std::f64::consts::TAU * 150.0 * t).sin().max(0.0) * 100.0
            })
            .collect();
        let a = AxisChain::Modes(vec![m]).filter(fs, &u);
        let b = frf.filter(fs, &u);
        // compare after the start transient, away from the circular wrap at the end
        let err = (5000..15_000)
            .map(|q| (a[q] - b[q]).abs())
            .fold(0.0, f64::max);
        assert!(err < 0.5, "max difference {err} N on a 100 N signal");
    }
}
