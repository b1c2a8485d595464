//! Pass 1, part a: averaged power spectrum (Welch) of F_x and F_y and the tooth-passing line.
//!
//! Non-overlapping frames of L samples (L = the power of two ≥ 8 nominal revolutions, at most
//! 2¹⁶), mean removed, Hann window, zero-padded ×4, real FFT (`realfft`); power spectra of F_x and
//! F_y summed over frames (all of the first 64 frames, then a thinning subset: see
//! `transformed`). A record shorter than one frame is analysed as one
//! zero-padded partial frame. The tooth-passing line is the largest bin within
//! K·n/60·(1 ± band), refined by a parabola through the log-power of the bin and its neighbours
//! (quadratic interpolation of a Hann-windowed peak; bias ≪ 0.01 bin with ×4 zero padding).
//! Memory: 2·L input samples + 4·L FFT buffer + 2·L + 1 spectrum values, independent of length.

use super::SignalError;
use crate::signal::stats::{median, parabolic_peak};
use realfft::{RealFftPlanner, RealToComplex};
use std::f64::consts::PI;
use std::sync::Arc;

/// Zero-padding factor of each frame.
const PAD: usize = 4;
/// Largest frame length (samples).
const MAX_FRAME: usize = 1 << 16;

/// Streaming Welch power spectrum of (F_x, F_y).
pub(crate) struct Welch {
    frame: usize,
    fs: f64,
    buf: [Vec<f64>; 2],
    fft: Arc<dyn RealToComplex<f64>>,
    input: Vec<f64>,
    output: Vec<realfft::num_complex::Complex<f64>>,
    psd: Vec<f64>,
    window: Vec<f64>,
    frames: usize,
    /// Frames started (transformed or skipped).
    seen: usize,
    /// `transformed(seen)`, kept with `seen` (issue 18: computed per sample, its remainder was
    /// a division per sample on pass 1's main thread).
    transforming: bool,
    /// Samples of the current frame when it is skipped.
    skipped_fill: usize,
}

/// Whether frame `i` is transformed: all of the first 64, then every ⌊i/64⌋+1-th, so about
/// 64·(1 + ln(N/64)) of N frames cost an FFT (the spectrum only has to locate the line; the
/// phase tracker refines the frequency). Deterministic, hence independent of chunking.
fn transformed(i: usize) -> bool {
    i < 64 || i.checked_rem(i / 64 + 1) == Some(0)
}

/// Hann window of length `len` (periodic-symmetric at sample centres).
fn hann(len: usize) -> Vec<f64> {
    (0..len)
        .map(|i| 0.5 - 0.5 * (2.0 * PI * (i as f64 + 0.5) / len as f64).cos())
        .collect()
}

/// The tooth-passing line found in the spectrum.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ToothPassingLine {
    /// Refined frequency (Hz).
    #[serde(rename = "frequency_hz")]
    pub hz: f64,
    /// Power of the line relative to the strongest line above half the nominal spindle frequency.
    pub relative_power: f64,
    /// Power of the line relative to the median power in K·n/60·[0.5, 1.5].
    pub prominence: f64,
    /// Bin width of the un-padded frame, f_s/L (Hz): the spectral resolution.
    pub resolution_hz: f64,
    /// Frames averaged (0 when the record was shorter than one frame and analysed as one
    /// zero-padded partial frame).
    pub frames: usize,
    /// Strongest spindle harmonic j·f (j = 1..K−1) below the tooth-passing line: (Hz, power
    /// relative to the line). Above 0.1 (−10 dB) suggests fewer teeth than stated (K/d teeth put
    /// their tooth-passing line on harmonic K/d), or a large runout (runout side-bands are typically
    /// 15–25 dB weaker).
    #[serde(rename = "strongest_below_hz_and_relative_power")]
    pub strongest_below: (f64, f64),
}

impl Welch {
    /// Frames of ≈ 8 nominal revolutions at `fs` Hz.
    pub fn new(fs: f64, samples_per_rev: f64) -> Self {
        let frame = ((8.0 * samples_per_rev).ceil() as usize)
            .next_power_of_two()
            .clamp(256, MAX_FRAME);
        let n = frame * PAD;
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n);
        let input = fft.make_input_vec();
        let output = fft.make_output_vec();
        Welch {
            frame,
            fs,
            buf: [Vec::with_capacity(frame), Vec::with_capacity(frame)],
            fft,
            input,
            output,
            psd: vec![0.0; n / 2 + 1],
            window: hann(frame),
            frames: 0,
            seen: 0,
            transforming: transformed(0),
            skipped_fill: 0,
        }
    }

    /// Add samples of F_x, F_y: [`Welch::push`] sample by sample, a frame's run at a time
    /// (copied into the frame, or counted when the frame is skipped).
    pub fn push_all(&mut self, fx: &[f64], fy: &[f64]) {
        let n = fx.len().min(fy.len());
        let mut i = 0;
        while i < n {
            if !self.transforming {
                let take = (self.frame - self.skipped_fill).min(n - i);
                self.skipped_fill += take;
                i += take;
                if self.skipped_fill == self.frame {
                    self.skipped_fill = 0;
                    self.next_frame();
                }
                continue;
            }
            let take = (self.frame - self.buf[0].len()).min(n - i);
            self.buf[0].extend_from_slice(&fx[i..i + take]);
            self.buf[1].extend_from_slice(&fy[i..i + take]);
            i += take;
            if self.buf[0].len() == self.frame {
                self.transform();
                self.frames += 1;
                self.next_frame();
            }
        }
    }

    /// Add one sample of F_x, F_y: the reference for [`Welch::push_all`].
    #[cfg(test)]
    pub fn push(&mut self, fx: f64, fy: f64) {
        if !self.transforming {
            self.skipped_fill += 1;
            if self.skipped_fill == self.frame {
                self.skipped_fill = 0;
                self.next_frame();
            }
            return;
        }
        self.buf[0].push(fx);
        self.buf[1].push(fy);
        if self.buf[0].len() == self.frame {
            self.transform();
            self.frames += 1;
            self.next_frame();
        }
    }

    /// The next frame starts.
    fn next_frame(&mut self) {
        self.seen += 1;
        self.transforming = transformed(self.seen);
    }

    fn transform(&mut self) {
        let len = self.buf[0].len();
        let partial;
        let window = if len == self.frame {
            &self.window
        } else {
            partial = hann(len);
            &partial
        };
        for c in 0..2 {
            let b = &self.buf[c];
            let mean = b.iter().sum::<f64>() / len as f64;
            self.input.iter_mut().for_each(|v| *v = 0.0);
            for ((dst, &x), &w) in self.input.iter_mut().zip(b).zip(window) {
                *dst = (x - mean) * w;
            }
            // the plan and buffers are sized together: process cannot fail
            if self.fft.process(&mut self.input, &mut self.output).is_ok() {
                for (p, z) in self.psd.iter_mut().zip(&self.output) {
                    *p += z.norm_sqr();
                }
            }
        }
        self.buf[0].clear();
        self.buf[1].clear();
    }

    /// Finish: analyse a partial frame if no full one was seen. Returns frames averaged.
    pub fn finish(&mut self) -> usize {
        if self.frames == 0 && self.buf[0].len() >= 16 {
            self.transform();
        }
        self.frames
    }

    /// Frequency of padded bin k (Hz).
    fn bin_hz(&self) -> f64 {
        self.fs / (self.frame * PAD) as f64
    }

    /// Find the tooth-passing line near `expected_hz` (relative half-band `band`).
    ///
    /// Accepted when (a) the largest bin in the band is a local maximum inside it, (b) its power
    /// is ≥ 10 % of the strongest line above half the spindle frequency (−10 dB) and (c) it
    /// stands ≥ 4× above the median power in expected·[0.5, 1.5]. Otherwise the spectrum is
    /// inconsistent with the stated teeth or rpm.
    pub fn tooth_passing(
        &self,
        teeth: usize,
        rpm: f64,
        band: f64,
    ) -> Result<ToothPassingLine, SignalError> {
        let expected = teeth as f64 * rpm / 60.0;
        let df = self.bin_hz();
        let nb = self.psd.len();
        let bin = |f: f64| ((f / df).round().max(0.0) as usize).min(nb - 1);
        let (lo, hi) = (bin(expected * (1.0 - band)), bin(expected * (1.0 + band)));
        let s_lo = bin(0.5 * rpm / 60.0).max(1);
        let s_hi = nb - 1;
        let argmax = |a: usize, b: usize| {
            (a..=b).fold(a, |m, k| if self.psd[k] > self.psd[m] { k } else { m })
        };
        let strongest = argmax(s_lo, s_hi);
        let p_max = self.psd[strongest];
        let fail = |finding: String| SignalError::SpectrumInconsistent {
            teeth,
            rpm,
            expected_hz: expected,
            band_lo_hz: expected * (1.0 - band),
            band_hi_hz: expected * (1.0 + band),
            finding,
            strongest_hz: strongest as f64 * df,
            strongest_as_rpm: strongest as f64 * df * 60.0 / teeth as f64,
        };
        if p_max.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(fail("the signal has no variation (flat spectrum)".into()));
        }
        let k = argmax(lo, hi);
        let p = self.psd[k];
        if k == 0 || k + 1 >= nb || self.psd[k - 1] > p || self.psd[k + 1] > p || k == lo || k == hi
        {
            return Err(fail(
                "the largest value in the band is at its edge, not a peak".into(),
            ));
        }
        let rel = p / p_max;
        if rel < 0.1 {
            return Err(fail(format!(
                "the largest peak in the band is {:.1} dB below the strongest line (limit 10 dB)",
                -10.0 * rel.log10()
            )));
        }
        let ctx = &self.psd[bin(0.5 * expected)..=bin(1.5 * expected)];
        let prominence = p / median(ctx).max(f64::MIN_POSITIVE);
        if prominence < 4.0 {
            return Err(fail(format!(
                "the largest peak in the band stands only {prominence:.1}× above the median of its surroundings (limit 4×)"
            )));
        }
        let l = |i: usize| self.psd[i].max(f64::MIN_POSITIVE).ln();
        let (d, _) = parabolic_peak(l(k - 1), l(k), l(k + 1));
        let hz = (k as f64 + d) * df;
        // spindle harmonics j·f below the tooth-passing line (j = 1..K−1), ± half an un-padded bin
        let below = (1..teeth)
            .map(|j| {
                let c = j as f64 * hz / teeth as f64;
                let (a, b) = (
                    bin(c) - (PAD / 2).min(bin(c)),
                    (bin(c) + PAD / 2).min(nb - 1),
                );
                let q = argmax(a, b);
                (q as f64 * df, self.psd[q] / p)
            })
            .fold((0.0, 0.0), |m, x| if x.1 > m.1 { x } else { m });
        Ok(ToothPassingLine {
            hz,
            relative_power: rel,
            prominence,
            resolution_hz: self.fs / self.frame as f64,
            frames: self.frames,
            strongest_below: below,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`Welch::push_all`] over chunks of any sizes gives the spectrum, bit for bit, of
    /// [`Welch::push`] sample by sample: 300 frames of 256 samples, so that frames are both
    /// transformed and skipped, and a partial frame at the end.
    #[test]
    fn push_all_equals_push_sample_by_sample() {
        let n = 300 * 256 + 100;
        let fx: Vec<f64> = (0..n)
            .map(|i| (i as f64 * 0.37).sin() + (i % 7) as f64)
            .collect();
        let fy: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos() * 3.0).collect();
        let mut one = Welch::new(10_000.0, 30.0);
        for i in 0..n {
            one.push(fx[i], fy[i]);
        }
        let mut all = Welch::new(10_000.0, 30.0);
        let (mut at, mut k) = (0, 0usize);
        while at < n {
            // chunk sizes 1, 2, … 700, then again: across frame edges in every phase
            let end = (at + 1 + k % 700).min(n);
            all.push_all(&fx[at..end], &fy[at..end]);
            (at, k) = (end, k + 37);
        }
        assert_eq!(one.frame, 256);
        assert_eq!((one.finish(), one.seen), (all.finish(), all.seen));
        assert!(one.frames > 64 && one.frames < 300, "{}", one.frames);
        let bits = |w: &Welch| w.psd.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&one), bits(&all));
    }

    #[test]
    fn finds_a_pure_tone_within_a_small_fraction_of_a_bin() {
        let fs = 10_000.0;
        let f0 = 501.3;
        let mut w = Welch::new(fs, 100.0);
        for n in 0..20_000 {
            let t = n as f64 / fs;
            w.push((2.0 * PI * f0 * t).sin(), 0.3 * (2.0 * PI * f0 * t).cos());
        }
        w.finish();
        // K = 5 at 6000 rpm → 500 Hz expected
        let line = w.tooth_passing(5, 6000.0, 0.1).unwrap();
        // un-padded bin = 10 kHz/1024 ≈ 9.8 Hz; ×4 padding + log-parabola: error < 0.05 bin
        assert!(
            (line.hz - f0).abs() < 0.05 * line.resolution_hz,
            "{}",
            line.hz
        );
        // wrong teeth: 4 teeth at 6000 rpm → 400 Hz, nothing there
        assert!(matches!(
            w.tooth_passing(4, 6000.0, 0.1),
            Err(SignalError::SpectrumInconsistent { .. })
        ));
    }
}
