//! The tool's bending resonance seen in the cut spectrum (issue 11 item 7, the measured
//! alternative to the beam formula).
//!
//! The periodic part of the cutting force puts lines at the spindle harmonics j·f; its random part
//! (chip-to-chip variation, material) is broadband, and through the bending response it reaches
//! the sensors shaped by |H(f)|², which peaks at the mode. So the resonance is found **between**
//! the lines: a Welch power spectrum of the force from the deflection over the cut (Hann window,
//! non-overlapping frames of the power of two ≥ 32 revolutions, so lines are ≥ 32 bins apart),
//! bins within ±6 bins of a spindle harmonic masked (the Hann leakage of a line 60 dB above the
//! broadband falls below it there: −31 dB first side lobe, −18 dB/octave), then one level per
//! gap between two harmonics (median of its unmasked bins, robust to leakage). The resonance is
//! the highest gap level from 3·f to 0.4·f_s if it stands ≥ 10× (10 dB) above the median gap
//! level, its frequency refined by a parabola through the log-levels of it and its two
//! neighbours, its damping from the half-power width, ζ ≈ Δf/(2f_r) (coarse: the levels are one
//! spindle spacing apart). A cut without broadband content, or too short for one frame (32
//! revolutions), shows none. Memory: one frame per column.

use realfft::{RealFftPlanner, RealToComplex};
use std::sync::Arc;

/// Revolutions per frame (at least).
const FRAME_REVOLUTIONS: f64 = 32.0;
/// Bins masked on each side of a spindle harmonic.
const MASK_BINS: f64 = 6.0;
/// Prominence of the peak gap level over the median gap level to accept a resonance.
const MIN_PROMINENCE: f64 = 10.0;

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// Vertex offset (−0.5…0.5) of the parabola through (−1, a), (0, b), (1, c); 0 if not a peak.
fn parabolic_peak(a: f64, b: f64, c: f64) -> f64 {
    let den = a - 2.0 * b + c;
    if den < 0.0 {
        (0.5 * (a - c) / den).clamp(-0.5, 0.5)
    } else {
        0.0
    }
}

/// A resonance seen in the cut spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralResonance {
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio fitted to the peak's shape, if enough bins were free of lines.
    pub damping: Option<f64>,
    /// Peak gap level over the median gap level.
    pub prominence: f64,
    /// Frames averaged.
    pub frames: usize,
}

/// Streaming Welch spectrum of one or more force columns (powers summed over the columns).
#[derive(Clone)]
pub struct ResonanceSpectrum {
    frame: usize,
    fs: f64,
    spindle_hz: f64,
    buf: Vec<Vec<f64>>,
    window: Vec<f64>,
    psd: Vec<f64>,
    frames: usize,
    fft: Arc<dyn RealToComplex<f64>>,
}

impl std::fmt::Debug for ResonanceSpectrum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ResonanceSpectrum")
            .field("frame", &self.frame)
            .field("frames", &self.frames)
            .finish()
    }
}

impl ResonanceSpectrum {
    /// Frames of the power of two ≥ 32 revolutions of `spindle_hz` at `sample_rate_hz`.
    pub fn new(columns: usize, sample_rate_hz: f64, spindle_hz: f64) -> Self {
        let frame = ((FRAME_REVOLUTIONS * sample_rate_hz / spindle_hz).ceil() as usize)
            .next_power_of_two()
            .clamp(1024, 1 << 20);
        let window = (0..frame)
            .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * (i as f64 + 0.5) / frame as f64).cos())
            .collect();
        Self {
            fft: RealFftPlanner::<f64>::new().plan_fft_forward(frame),
            frame,
            fs: sample_rate_hz,
            spindle_hz,
            buf: vec![Vec::with_capacity(frame); columns],
            window,
            psd: vec![0.0; frame / 2 + 1],
            frames: 0,
        }
    }

    /// Add one sample per column; a non-finite value drops the frame in progress.
    pub fn push(&mut self, row: &[f64]) {
        if row.iter().any(|v| !v.is_finite()) {
            self.buf.iter_mut().for_each(Vec::clear);
            return;
        }
        for (b, v) in self.buf.iter_mut().zip(row) {
            b.push(*v);
        }
        if self.buf[0].len() == self.frame {
            for b in &mut self.buf {
                let mean = b.iter().sum::<f64>() / b.len() as f64;
                let mut x: Vec<f64> = b
                    .iter()
                    .zip(&self.window)
                    .map(|(v, w)| (v - mean) * w)
                    .collect();
                let mut out = self.fft.make_output_vec();
                if self.fft.process(&mut x, &mut out).is_ok() {
                    for (p, z) in self.psd.iter_mut().zip(&out) {
                        *p += z.norm_sqr();
                    }
                }
                b.clear();
            }
            self.frames += 1;
        }
    }

    /// Drop the samples of an unfinished frame (e.g. at the end of the cut).
    pub fn break_frame(&mut self) {
        self.buf.iter_mut().for_each(Vec::clear);
    }

    /// Frames averaged so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The resonance, if one stands out (module docs).
    pub fn resonance(&self) -> Option<SpectralResonance> {
        if self.frames == 0 {
            return None;
        }
        let df = self.fs / self.frame as f64;
        let fsp = self.spindle_hz;
        let top = 0.4 * self.fs;
        let gaps: Vec<(f64, f64)> = (3..)
            .map(|j| j as f64 * fsp)
            .take_while(|&f| f + fsp <= top)
            .filter_map(|f| {
                let lo = ((f / df) + MASK_BINS).ceil() as usize;
                let hi = (((f + fsp) / df) - MASK_BINS).floor() as usize;
                (hi > lo).then(|| (f + fsp / 2.0, median(&self.psd[lo..=hi])))
            })
            .collect();
        if gaps.len() < 5 {
            return None;
        }
        let levels: Vec<f64> = gaps.iter().map(|g| g.1).collect();
        let base = median(&levels);
        let (i, &peak) = levels
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))?;
        let prominence = peak / base.max(f64::MIN_POSITIVE);
        if prominence.is_nan() || prominence < MIN_PROMINENCE || i == 0 || i + 1 == levels.len() {
            return None;
        }
        let l = |k: usize| levels[k].max(f64::MIN_POSITIVE).ln();
        let d = parabolic_peak(l(i - 1), l(i), l(i + 1));
        let coarse = gaps[i].0 + d * fsp;
        // refine: fit ln P = c − ln|1 − r² + 2iζr|² (white broadband force through one mode) to
        // the unmasked bins within ±4 spindle spacings, by a grid over f_n (±10 %, 0.1 % steps)
        // and ζ (0.003–0.3, 2 % steps), c in closed form
        let bins: Vec<(f64, f64)> = (((coarse - 4.0 * fsp) / df).max(1.0) as usize
            ..((coarse + 4.0 * fsp) / df).min((self.psd.len() - 1) as f64) as usize)
            .filter_map(|k| {
                let f = k as f64 * df;
                let off = (f / fsp - (f / fsp).round()).abs() * fsp / df;
                (off > MASK_BINS && self.psd[k] > 0.0).then(|| (f, self.psd[k].ln()))
            })
            .collect();
        let sse = |fn_: f64, z: f64| {
            let r: Vec<f64> = bins
                .iter()
                .map(|&(f, lp)| {
                    let x = f / fn_;
                    lp + ((1.0 - x * x).powi(2) + (2.0 * z * x).powi(2)).ln()
                })
                .collect();
            let c = r.iter().sum::<f64>() / r.len() as f64;
            r.iter().map(|v| (v - c).powi(2)).sum::<f64>()
        };
        let mut best = (f64::INFINITY, coarse, None);
        if bins.len() >= 10 {
            for a in -100..=100 {
                let fn_ = coarse * (1.0 + a as f64 * 1e-3);
                let mut z = 0.003;
                while z < 0.3 {
                    let e = sse(fn_, z);
                    if e < best.0 {
                        best = (e, fn_, Some(z));
                    }
                    z *= 1.02;
                }
            }
        }
        let (f_r, damping) = (best.1, best.2);
        Some(SpectralResonance {
            frequency_hz: f_r,
            damping,
            prominence,
            frames: self.frames,
        })
    }
}
