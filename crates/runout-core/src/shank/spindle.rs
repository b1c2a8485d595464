//! Spindle angle for the shank method (methods.md §3.2 step 2): from once-per-revolution pulse
//! edges, or from the 1× component of the air-cut signal, its frequency refined by the phase
//! advance between the air-cut segments before and after the cut.

use std::f64::consts::TAU;

/// The spindle angle θ(t) (radians, unwrapped, positive in the direction of rotation).
#[derive(Debug, Clone, PartialEq)]
pub enum SpindlePhase {
    /// Constant speed: θ(t) = 2π·f·(t − t₀).
    Constant {
        /// Rotation frequency f, Hz.
        frequency_hz: f64,
        /// Standard error of f, Hz.
        frequency_se_hz: f64,
        /// Time of θ = 0, s.
        t0_s: f64,
        /// How f was obtained.
        source: String,
    },
    /// Pulse edges (θ = 2π·i at edge i), linear in between, extrapolated with the end periods.
    Pulses {
        /// Rising-edge times, s (≥ 2, increasing).
        edges_s: Vec<f64>,
    },
}

impl SpindlePhase {
    /// θ(t), rad. `hint` speeds up sequential look-ups (start with 0).
    pub fn angle(&self, t: f64, hint: &mut usize) -> f64 {
        match self {
            SpindlePhase::Constant {
                frequency_hz, t0_s, ..
            } => TAU * frequency_hz * (t - t0_s),
            SpindlePhase::Pulses { edges_s: e } => {
                let n = e.len();
                let mut i = (*hint).min(n - 2);
                if t < e[i] {
                    i = e.partition_point(|&x| x <= t).saturating_sub(1).min(n - 2);
                } else {
                    while i + 2 < n && t >= e[i + 1] {
                        i += 1;
                    }
                }
                *hint = i;
                TAU * (i as f64 + (t - e[i]) / (e[i + 1] - e[i]))
            }
        }
    }

    /// Mean rotation frequency, Hz.
    pub fn mean_frequency_hz(&self) -> f64 {
        match self {
            SpindlePhase::Constant { frequency_hz, .. } => *frequency_hz,
            SpindlePhase::Pulses { edges_s: e } => (e.len() - 1) as f64 / (e[e.len() - 1] - e[0]),
        }
    }

    /// Standard error of the mean frequency, Hz (pulse: from the scatter of the periods).
    pub fn frequency_se_hz(&self) -> f64 {
        match self {
            SpindlePhase::Constant {
                frequency_se_hz, ..
            } => *frequency_se_hz,
            SpindlePhase::Pulses { edges_s: e } => {
                let p: Vec<f64> = e.windows(2).map(|w| w[1] - w[0]).collect();
                let m = p.iter().sum::<f64>() / p.len() as f64;
                let sd = (p.iter().map(|x| (x - m).powi(2)).sum::<f64>()
                    / (p.len().max(2) - 1) as f64)
                    .sqrt();
                // f = 1/T: se_f = se_T/T²; edges are a cumulative sum, so se of the mean period
                // over the record is ≈ jitter/(n·T) – bounded here by sd/√n.
                sd / (p.len() as f64).sqrt() / (m * m)
            }
        }
    }
}

/// Demeaned samples times a Hann window (suppresses leakage of the 2×, 3× … form harmonics and
/// of the DC level into the 1× phasor; the window is symmetric, so the phase refers to the
/// segment centre).
pub fn hann_prepared(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    if n == 0 {
        return Vec::new();
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let m = (n.max(2) - 1) as f64;
    x.iter()
        .enumerate()
        .map(|(k, v)| (v - mean) * (std::f64::consts::PI * k as f64 / m).sin().powi(2))
        .collect()
}

/// The 1× phasor of a uniformly sampled segment, Hann-windowed:
/// X(f) = Σ w_k(x_k − x̄)·e^{−j2πf(t_k − t_c)}, t_c the segment centre. Returns (|X|², arg X).
pub fn phasor(x: &[f64], t_start: f64, sample_rate_hz: f64, f: f64) -> (f64, f64) {
    phasor_prepared(&hann_prepared(x), t_start, sample_rate_hz, f)
}

/// [`phasor`] on samples already passed through [`hann_prepared`].
pub fn phasor_prepared(xw: &[f64], t_start: f64, sample_rate_hz: f64, f: f64) -> (f64, f64) {
    let n = xw.len();
    if n == 0 {
        return (0.0, 0.0);
    }
    let dt = 1.0 / sample_rate_hz;
    let tc = t_start + (n - 1) as f64 * dt / 2.0;
    let (mut re, mut im) = (0.0, 0.0);
    let step = -TAU * f * dt;
    let (cs, ss) = (step.cos(), step.sin());
    let mut k = 0;
    while k < n {
        // exact angle every 1024 samples, rotation recurrence in between
        let a0 = -TAU * f * (t_start + k as f64 * dt - tc);
        let (mut c, mut s) = (a0.cos(), a0.sin());
        for &d in &xw[k..(k + 1024).min(n)] {
            re += d * c;
            im += d * s;
            let c2 = c * cs - s * ss;
            s = s * cs + c * ss;
            c = c2;
        }
        k += 1024;
    }
    (re * re + im * im, im.atan2(re))
}

/// Frequency of the strongest component within `f_nominal·(1 ± 10 %)`: a grid of step
/// 0.25/T then golden-section refinement of |X(f)|².
pub fn peak_frequency(x: &[f64], t_start: f64, sample_rate_hz: f64, f_nominal: f64) -> f64 {
    let duration = x.len() as f64 / sample_rate_hz;
    let step = 0.25 / duration;
    let (lo, hi) = (0.9 * f_nominal, 1.1 * f_nominal);
    let xw = hann_prepared(x);
    let power = |f: f64| phasor_prepared(&xw, t_start, sample_rate_hz, f).0;
    let mut best = (f_nominal, power(f_nominal));
    let mut f = lo;
    while f <= hi {
        let p = power(f);
        if p > best.1 {
            best = (f, p);
        }
        f += step;
    }
    // golden section on [best − step, best + step]
    let (mut a, mut b) = (best.0 - step, best.0 + step);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut pc, mut pd) = (power(c), power(d));
    for _ in 0..60 {
        if pc > pd {
            b = d;
            d = c;
            pd = pc;
            c = b - g * (b - a);
            pc = power(c);
        } else {
            a = c;
            c = d;
            pc = pd;
            d = a + g * (b - a);
            pd = power(d);
        }
        if (b - a) < 1e-13 * f_nominal {
            break;
        }
    }
    (a + b) / 2.0
}

/// One air-cut segment's data for the phase estimate.
#[derive(Debug, Clone, Copy)]
pub struct PhaseSegment<'a> {
    /// Samples of the reference displacement channel.
    pub x: &'a [f64],
    /// Time of the first sample, s.
    pub t_start: f64,
}

/// Rotation frequency from one or two air-cut segments (methods.md §3.2 step 2): the 1× peak of
/// each segment, then — with two segments — f = (N + Δφ/2π)/(t_B − t_A) with N the whole number
/// of revolutions between the segment centres and Δφ the phase advance of the 1× phasor.
/// Returns (f, standard error of f, source text).
pub fn frequency_from_air(
    segments: &[PhaseSegment<'_>],
    sample_rate_hz: f64,
    f_nominal: f64,
) -> (f64, f64, String) {
    let dt = 1.0 / sample_rate_hz;
    let centre = |s: &PhaseSegment| s.t_start + (s.x.len() - 1) as f64 * dt / 2.0;
    let peaks: Vec<f64> = segments
        .iter()
        .map(|s| peak_frequency(s.x, s.t_start, sample_rate_hz, f_nominal))
        .collect();
    // per-segment precision from the revolution-to-revolution scatter of the phase
    let seg_se = |s: &PhaseSegment, f: f64| -> f64 {
        let per_rev = (sample_rate_hz / f).round() as usize;
        let revs = s.x.len() / per_rev.max(1);
        if revs < 3 {
            return f64::NAN;
        }
        let phases: Vec<f64> = (0..revs)
            .map(|r| {
                let part = &s.x[r * per_rev..(r + 1) * per_rev];
                let t = s.t_start + (r * per_rev) as f64 * dt;
                phasor(part, t, sample_rate_hz, f).1
            })
            .collect();
        // residual scatter about a straight line (chunks are not exactly one period long)
        let u = unwrap(&phases);
        let n = u.len() as f64;
        let rm = (n - 1.0) / 2.0;
        let um = u.iter().sum::<f64>() / n;
        let sxx: f64 = (0..u.len()).map(|r| (r as f64 - rm).powi(2)).sum();
        let sxy: f64 = u
            .iter()
            .enumerate()
            .map(|(r, p)| (r as f64 - rm) * (p - um))
            .sum();
        let slope = sxy / sxx;
        let rss: f64 = u
            .iter()
            .enumerate()
            .map(|(r, p)| (p - um - slope * (r as f64 - rm)).powi(2))
            .sum();
        (rss / (n - 2.0).max(1.0)).sqrt() / n.sqrt()
    };
    if segments.len() < 2 {
        let f = peaks[0];
        let s = &segments[0];
        let duration = s.x.len() as f64 * dt;
        let se = seg_se(s, f) * 2.0 / (TAU * duration);
        return (
            f,
            se,
            "1× peak of the air cut before the cut (one segment only)".into(),
        );
    }
    let (a, b) = (&segments[0], &segments[segments.len() - 1]);
    let (ta, tb) = (centre(a), centre(b));
    let mut f = (peaks[0] + peaks[peaks.len() - 1]) / 2.0;
    let mut se = f64::NAN;
    for _ in 0..2 {
        let pa = phasor(a.x, a.t_start, sample_rate_hz, f).1;
        let pb = phasor(b.x, b.t_start, sample_rate_hz, f).1;
        let dphi = pb - pa;
        let n = (f * (tb - ta) - dphi / TAU).round();
        f = (n + dphi / TAU) / (tb - ta);
        let s2 = seg_se(a, f).powi(2) + seg_se(b, f).powi(2);
        se = s2.sqrt() / (TAU * (tb - ta));
    }
    (
        f,
        se,
        "1× phase advance between the air cuts before and after the cut".into(),
    )
}

/// Unwrap a sequence of angles (rad).
fn unwrap(p: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(p.len());
    let mut offset = 0.0f64;
    for (i, &v) in p.iter().enumerate() {
        if i > 0 {
            let d: f64 = v + offset - out[i - 1];
            offset -= TAU * (d / TAU).round();
        }
        out.push(v + offset);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phase_advance_refines_the_frequency() {
        let fs = 10_000.0;
        let f_true = 50.0 * 1.001;
        let sig = |t: f64| {
            0.005 * (TAU * f_true * t + 0.7).cos() + 0.001 * (2.0 * TAU * f_true * t).sin()
        };
        let a: Vec<f64> = (0..2000).map(|k| sig(k as f64 / fs)).collect();
        let tb = 6.0;
        let b: Vec<f64> = (0..2000).map(|k| sig(tb + k as f64 / fs)).collect();
        let (f, _, _) = frequency_from_air(
            &[
                PhaseSegment {
                    x: &a,
                    t_start: 0.0,
                },
                PhaseSegment { x: &b, t_start: tb },
            ],
            fs,
            50.0,
        );
        assert!((f - f_true).abs() < 1e-7 * f_true, "{f} vs {f_true}");
    }

    #[test]
    fn pulse_edges_and_angle() {
        let fs = 10_000.0;
        let edges_s = crate::signal::PulseEdgeDetector::mid_with_hysteresis(0.0, 5.0)
            .unwrap()
            .edges((0..10_000).map(|k| {
                let t = k as f64 / fs;
                (t, if (t * 25.0).fract() < 0.1 { 5.0 } else { 0.0 })
            }));
        assert_eq!(edges_s.len(), 24);
        let p = SpindlePhase::Pulses {
            edges_s: edges_s.clone(),
        };
        assert!((p.mean_frequency_hz() - 25.0).abs() < 1e-9);
        let mut h = 0;
        let a = p.angle(edges_s[3] + 0.02, &mut h);
        assert!((a - TAU * 3.5).abs() < 1e-2, "{a}");
    }
}
