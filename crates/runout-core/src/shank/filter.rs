//! Zero-phase Butterworth low-pass as second-order sections, designed here by the bilinear
//! transform (≈ 80 lines instead of `sci-rs`, which would add a second nalgebra and ~22 s of
//! build for one filter; the design is checked against the exact Butterworth magnitude
//! |H(f)|² = 1/(1 + (tan(πf/f_s)/tan(πf_c/f_s))^{2N}) in the tests), plus a streaming
//! forward–backward filter that processes blocks with overlapping margins so that hour-long
//! records are filtered in bounded memory (methods.md §3.2 step 7: low-pass below the first
//! bending mode).

use std::collections::VecDeque;
use std::f64::consts::PI;

/// One biquad: y = (b0 + b1 z⁻¹ + b2 z⁻²)/(1 + a1 z⁻¹ + a2 z⁻²) x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biquad {
    /// Numerator b0, b1, b2.
    pub b: [f64; 3],
    /// Denominator a1, a2 (a0 = 1).
    pub a: [f64; 2],
}

/// A Butterworth low-pass of order N as cascaded biquads (unit DC gain).
#[derive(Debug, Clone, PartialEq)]
pub struct Butterworth {
    /// The sections.
    pub sections: Vec<Biquad>,
    /// Order N.
    pub order: usize,
    /// Cutoff (−3 dB of one pass), Hz.
    pub cutoff_hz: f64,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
}

/// Complex multiply/divide helpers on (re, im).
fn cdiv(a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
    let d = b.0 * b.0 + b.1 * b.1;
    ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
}

impl Butterworth {
    /// Design: analog poles ω_c·e^{jπ(2k+N+1)/(2N)} with ω_c = tan(πf_c/f_s) (pre-warped),
    /// bilinear z = (1 + s)/(1 − s), zeros at z = −1, each section scaled to unit DC gain.
    /// Requires 1 ≤ N ≤ 16 and 0 < f_c < f_s/2.
    pub fn lowpass(order: usize, cutoff_hz: f64, sample_rate_hz: f64) -> Option<Self> {
        let valid = (1..=16).contains(&order)
            && cutoff_hz > 0.0
            && sample_rate_hz.is_finite()
            && cutoff_hz < sample_rate_hz / 2.0;
        if !valid {
            return None;
        }
        let wc = (PI * cutoff_hz / sample_rate_hz).tan();
        let mut sections = Vec::new();
        for k in 0..order / 2 {
            let th = PI * (2 * k + order + 1) as f64 / (2 * order) as f64;
            let p = (wc * th.cos(), wc * th.sin());
            let z = cdiv((1.0 + p.0, p.1), (1.0 - p.0, -p.1));
            let a1 = -2.0 * z.0;
            let a2 = z.0 * z.0 + z.1 * z.1;
            let g = (1.0 + a1 + a2) / 4.0;
            sections.push(Biquad {
                b: [g, 2.0 * g, g],
                a: [a1, a2],
            });
        }
        if order % 2 == 1 {
            let p = -wc;
            let z = (1.0 + p) / (1.0 - p);
            let g = (1.0 - z) / 2.0;
            sections.push(Biquad {
                b: [g, g, 0.0],
                a: [-z, 0.0],
            });
        }
        Some(Self {
            sections,
            order,
            cutoff_hz,
            sample_rate_hz,
        })
    }

    /// Samples after which the slowest pole's impulse response has decayed by e⁻²⁵ (≈ 10⁻¹¹):
    /// 25·f_s/(2π f_c sin(π/2N)); the margin of the block filter.
    pub fn settling_samples(&self) -> usize {
        let zeta = (PI / (2 * self.order) as f64).sin();
        (25.0 * self.sample_rate_hz / (2.0 * PI * self.cutoff_hz * zeta)).ceil() as usize
    }

    /// Filter `x` in place forward (zero initial state), direct form II transposed.
    pub fn filter_forward(&self, x: &mut [f64]) {
        for s in &self.sections {
            let (mut z1, mut z2) = (0.0, 0.0);
            for v in x.iter_mut() {
                let y = s.b[0] * *v + z1;
                z1 = s.b[1] * *v - s.a[0] * y + z2;
                z2 = s.b[2] * *v - s.a[1] * y;
                *v = y;
            }
        }
    }

    /// Forward–backward (zero-phase) filtering of a whole block with odd extension of `pad`
    /// samples at both ends (as scipy's `filtfilt(padtype="odd")`, but zero initial states).
    pub fn filtfilt(&self, x: &[f64], pad: usize) -> Vec<f64> {
        if x.is_empty() {
            return Vec::new();
        }
        let pad = pad.min(x.len() - 1);
        let mut ext = Vec::with_capacity(x.len() + 2 * pad);
        ext.extend((1..=pad).rev().map(|i| 2.0 * x[0] - x[i]));
        ext.extend_from_slice(x);
        let n = x.len();
        ext.extend((1..=pad).map(|i| 2.0 * x[n - 1] - x[n - 1 - i]));
        self.filter_forward(&mut ext);
        ext.reverse();
        self.filter_forward(&mut ext);
        ext.reverse();
        ext[pad..pad + n].to_vec()
    }
}

/// Streaming zero-phase filter of several columns: blocks are filtered forward–backward with
/// `margin` samples of overlap on each side (odd extension at the record's two ends), so the
/// output equals whole-record filtering to ~10⁻¹¹ relative while holding only
/// `block + 2·margin` samples per column.
#[derive(Debug, Clone)]
pub struct ZeroPhaseStream {
    filter: Butterworth,
    margin: usize,
    block: usize,
    buffer: Vec<VecDeque<f64>>,
    /// Global index of buffer[0].
    start: u64,
    /// Next global index to emit.
    next_out: u64,
    total_in: u64,
}

impl ZeroPhaseStream {
    /// A stream of `columns` columns.
    pub fn new(filter: Butterworth, columns: usize) -> Self {
        let margin = filter.settling_samples().max(1);
        Self {
            block: (8 * margin).max(4096),
            filter,
            margin,
            buffer: vec![VecDeque::new(); columns],
            start: 0,
            next_out: 0,
            total_in: 0,
        }
    }

    /// Latency: samples pushed but not yet emitted at most.
    pub fn margin(&self) -> usize {
        self.margin
    }

    /// Push one row; filtered rows that are ready are appended to `out` (one Vec per column).
    pub fn push(&mut self, row: &[f64], out: &mut [Vec<f64>]) {
        for (b, v) in self.buffer.iter_mut().zip(row) {
            b.push_back(*v);
        }
        self.total_in += 1;
        if self.total_in - self.next_out >= (self.block + self.margin) as u64 {
            self.process(false, out);
        }
    }

    /// Flush the remaining rows at the end of the record.
    pub fn finish(&mut self, out: &mut [Vec<f64>]) {
        if self.total_in > self.next_out {
            self.process(true, out);
        }
    }

    fn process(&mut self, last: bool, out: &mut [Vec<f64>]) {
        let first = self.start == 0 && self.next_out == 0;
        let end = if last {
            self.total_in
        } else {
            self.total_in - self.margin as u64
        };
        let skip = (self.next_out - self.start) as usize;
        let emit = (end - self.next_out) as usize;
        for (c, b) in self.buffer.iter_mut().enumerate() {
            let x: Vec<f64> = b.iter().copied().collect();
            let y = if first || last {
                // odd extension at the record's ends, overlap margin elsewhere
                self.filter.filtfilt(&x, self.margin)
            } else {
                self.filter.filtfilt(&x, 0)
            };
            out[c].extend_from_slice(&y[skip..skip + emit]);
        }
        self.next_out = end;
        let keep_from = self
            .next_out
            .saturating_sub(self.margin as u64)
            .max(self.start);
        let drop = (keep_from - self.start) as usize;
        for b in &mut self.buffer {
            b.drain(..drop);
        }
        self.start = keep_from;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magnitude_is_butterworth() {
        for order in [1, 2, 4, 5] {
            let f = Butterworth::lowpass(order, 500.0, 10_000.0).unwrap();
            for freq in [0.0, 100.0, 500.0, 1000.0, 3000.0] {
                let w = 2.0 * PI * freq / 10_000.0;
                let (c, s) = (w.cos(), w.sin());
                let mut h = (1.0, 0.0);
                for q in &f.sections {
                    // z^-1 = e^{-jw}
                    let num = (
                        q.b[0] + q.b[1] * c + q.b[2] * (2.0 * w).cos(),
                        -q.b[1] * s - q.b[2] * (2.0 * w).sin(),
                    );
                    let den = (
                        1.0 + q.a[0] * c + q.a[1] * (2.0 * w).cos(),
                        -q.a[0] * s - q.a[1] * (2.0 * w).sin(),
                    );
                    let r = cdiv(num, den);
                    h = (h.0 * r.0 - h.1 * r.1, h.0 * r.1 + h.1 * r.0);
                }
                let mag2 = h.0 * h.0 + h.1 * h.1;
                let ratio = (PI * freq / 10_000.0).tan() / (PI * 500.0 / 10_000.0).tan();
                let expect = 1.0 / (1.0 + ratio.powi(2 * order as i32));
                assert!(
                    (mag2 - expect).abs() < 1e-12,
                    "N{order} f{freq}: {mag2} vs {expect}"
                );
            }
        }
    }

    #[test]
    fn streaming_equals_whole_record() {
        let f = Butterworth::lowpass(4, 800.0, 20_000.0).unwrap();
        let x: Vec<f64> = (0..50_000)
            .map(|k| {
                (k as f64 * 0.01).sin()
                    + 0.3 * (k as f64 * 1.3).sin()
                    + if k > 20_000 { 2.0 } else { 0.0 }
            })
            .collect();
        let whole = f.filtfilt(&x, f.settling_samples());
        let mut s = ZeroPhaseStream::new(f, 1);
        let mut out = vec![Vec::new()];
        for v in &x {
            s.push(&[*v], &mut out);
        }
        s.finish(&mut out);
        assert_eq!(out[0].len(), x.len());
        let err = out[0]
            .iter()
            .zip(&whole)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-8, "{err}");
    }
}
