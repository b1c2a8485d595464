//! Pass 1, part b: per-revolution envelope of the forces and the steady-cut detector.
//!
//! Blocks of one nominal revolution (round(f_s·60/n) samples) accumulate Σ and Σ² of F_x, F_y,
//! F_z. At most [`MAX_BLOCKS`] blocks are kept: when full, neighbouring blocks are merged in pairs
//! (sums add exactly) and the block length doubles, so memory is bounded whatever the length and
//! the time resolution of the detection degrades gracefully (one revolution up to 2¹⁵ revolutions).
//!
//! Level of block r: ℓ_r = √( Σ_c var_c,r + |m_r − m_air|² ) with m_air the mean force vector of the
//! quietest block (least variance): the dynamic force plus the static force relative to air
//! cutting, insensitive to a dynamometer offset. Detection:
//! 1. ℓ_lo = 5th, ℓ_hi = 95th percentile of the levels. If ℓ_hi < 2·ℓ_lo there is no air-cut
//!    contrast and every block is taken as cutting; otherwise the threshold is (ℓ_lo + ℓ_hi)/2 and
//!    the cut is the longest run of blocks at or above it.
//! 2. Entry/exit trimming: blocks at either end of the run whose level differs from the run's
//!    median by more than tol = max(5 %, 4·1.4826·MAD/median) are removed.
//! 3. At least two revolutions must remain.
//!
//! The mean force over the air-cut blocks (level ≤ 2·ℓ_lo) is the instrument's static offset,
//! reported and (by default) subtracted before averaging.

use super::SignalError;
use crate::signal::stats::{median, quantile};
use serde::Serialize;

/// Largest number of envelope blocks kept.
pub const MAX_BLOCKS: usize = 1 << 15;

#[derive(Debug, Clone, Copy, Default)]
struct Block {
    n: u64,
    sum: [f64; 3],
    sq: [f64; 3],
}

impl Block {
    fn merge(a: Block, b: Block) -> Block {
        let mut c = a;
        c.n += b.n;
        for i in 0..3 {
            c.sum[i] += b.sum[i];
            c.sq[i] += b.sq[i];
        }
        c
    }
    fn mean(&self) -> [f64; 3] {
        let n = self.n.max(1) as f64;
        [self.sum[0] / n, self.sum[1] / n, self.sum[2] / n]
    }
    fn variance(&self) -> f64 {
        let n = self.n.max(1) as f64;
        let m = self.mean();
        (0..3)
            .map(|i| (self.sq[i] / n - m[i] * m[i]).max(0.0))
            .sum()
    }
}

/// Streaming per-revolution envelope.
#[derive(Debug, Clone)]
pub(crate) struct Envelope {
    block_len: u64,
    blocks: Vec<Block>,
    current: Block,
}

/// The section of the recording used for averaging, and how it was found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteadySection {
    /// Start (s from the first sample).
    pub from_s: f64,
    /// End (s).
    pub to_s: f64,
    /// True when given by the caller (`from_s/to_s` override), false when detected.
    pub overridden: bool,
    /// Envelope block length (s): the time resolution of the detection.
    pub block_s: f64,
    /// Air-cut (low) level ℓ_lo (N).
    #[serde(rename = "air_level_N")]
    pub air_level: f64,
    /// Cutting level: median level of the section (N).
    #[serde(rename = "cut_level_N")]
    pub cut_level: f64,
    /// Threshold between air cut and cutting (N); 0 when there was no air-cut contrast.
    #[serde(rename = "threshold_N")]
    pub threshold: f64,
    /// Relative tolerance used to trim entry/exit blocks.
    pub trim_tolerance: f64,
    /// Blocks removed as entry/exit transients.
    pub trimmed_blocks: usize,
    /// Mean force (F_x, F_y, F_z) over the air-cut blocks (level ≤ 2·ℓ_lo), N: the static
    /// offset of the instrument; `None` when no air cut was distinguishable.
    #[serde(rename = "air_offset_N")]
    pub air_offset: Option<[f64; 3]>,
}

impl Envelope {
    /// Blocks of `block_len` samples (≥ 1).
    pub fn new(block_len: u64) -> Self {
        Envelope {
            block_len: block_len.max(1),
            blocks: Vec::new(),
            current: Block::default(),
        }
    }

    /// Add one sample (F_x, F_y, F_z): the reference for [`Envelope::push_all`].
    #[cfg(test)]
    pub fn push(&mut self, f: [f64; 3]) {
        let c = &mut self.current;
        c.n += 1;
        for (i, &x) in f.iter().enumerate() {
            c.sum[i] += x;
            c.sq[i] += x * x;
        }
        if c.n == self.block_len {
            self.close_block();
        }
    }

    /// Add samples (F_x, F_y, F_z; no F_z = 0) — the same sums, in the same order, as
    /// [`Envelope::push`] sample by sample, with the running sums of a block held in registers
    /// (issue 18: stored back to the block after every sample, each sum waited for its own
    /// store, and pass 1's scan took ≈ 2× longer).
    pub fn push_all(&mut self, fx: &[f64], fy: &[f64], fz: Option<&[f64]>) {
        let n = fx.len().min(fy.len());
        let mut i = 0;
        while i < n {
            let c = &mut self.current;
            let end = n.min(i + (self.block_len - c.n) as usize);
            let (mut s, mut q) = (c.sum, c.sq);
            match fz {
                Some(fz) => {
                    for ((&x, &y), &z) in fx[i..end].iter().zip(&fy[i..end]).zip(&fz[i..end]) {
                        (s[0], q[0]) = (s[0] + x, q[0] + x * x);
                        (s[1], q[1]) = (s[1] + y, q[1] + y * y);
                        (s[2], q[2]) = (s[2] + z, q[2] + z * z);
                    }
                }
                // the sums of F_z stay +0 (adding 0 · 0 to +0 is +0)
                None => {
                    for (&x, &y) in fx[i..end].iter().zip(&fy[i..end]) {
                        (s[0], q[0]) = (s[0] + x, q[0] + x * x);
                        (s[1], q[1]) = (s[1] + y, q[1] + y * y);
                    }
                }
            }
            (c.sum, c.sq) = (s, q);
            c.n += (end - i) as u64;
            i = end;
            if c.n == self.block_len {
                self.close_block();
            }
        }
    }

    /// The current block is complete: kept, and pairs of blocks merged when there are
    /// [`MAX_BLOCKS`].
    fn close_block(&mut self) {
        self.blocks.push(std::mem::take(&mut self.current));
        if self.blocks.len() == MAX_BLOCKS {
            self.blocks = self
                .blocks
                .chunks(2)
                .map(|p| Block::merge(p[0], p[1]))
                .collect();
            self.block_len *= 2;
        }
    }

    /// The complete blocks, plus the trailing partial block when it holds ≥ half a block.
    fn all_blocks(&self) -> Vec<Block> {
        let mut b = self.blocks.clone();
        if 2 * self.current.n >= self.block_len {
            b.push(self.current);
        }
        b
    }

    /// Levels ℓ_r of the blocks (N).
    fn levels(&self, blocks: &[Block]) -> Vec<f64> {
        let quiet = blocks
            .iter()
            .min_by(|a, b| a.variance().total_cmp(&b.variance()))
            .map(|b| b.mean())
            .unwrap_or([0.0; 3]);
        blocks
            .iter()
            .map(|b| {
                let m = b.mean();
                let d2: f64 = (0..3).map(|i| (m[i] - quiet[i]).powi(2)).sum();
                (b.variance() + d2).sqrt()
            })
            .collect()
    }

    /// Detect the steady cut (module doc). `fs` in Hz, `rev_s` one nominal revolution (s).
    pub fn detect(&self, fs: f64, rev_s: f64) -> Result<SteadySection, SignalError> {
        let blocks = self.all_blocks();
        let lv = self.levels(&blocks);
        // block r starts at sample r·block_len; the last may be partial
        let end_s = |r: usize| (blocks[..r].iter().map(|b| b.n).sum::<u64>()) as f64 / fs;
        let block_s = self.block_len as f64 / fs;
        let no_cut = |reason: String| SignalError::NoCut { reason };
        if lv.len() < 2 {
            return Err(no_cut(format!(
                "only {} complete revolution(s) of data",
                lv.len()
            )));
        }
        let (lo, hi) = (quantile(&lv, 0.05), quantile(&lv, 0.95));
        if hi.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(no_cut(
                "the force is constant (zero variation in every revolution)".into(),
            ));
        }
        let contrast = hi >= 2.0 * lo;
        let threshold = if contrast { 0.5 * (lo + hi) } else { 0.0 };
        // longest run at or above the threshold
        let (mut best, mut start) = ((0usize, 0usize), None);
        for (r, &l) in lv
            .iter()
            .chain(std::iter::once(&f64::NEG_INFINITY))
            .enumerate()
        {
            match (l >= threshold, start) {
                (true, None) => start = Some(r),
                (false, Some(s)) => {
                    if r - s > best.1 - best.0 {
                        best = (s, r);
                    }
                    start = None;
                }
                _ => {}
            }
        }
        let run = &lv[best.0..best.1];
        let med = median(run);
        let mad = median(&run.iter().map(|l| (l - med).abs()).collect::<Vec<_>>());
        let tol = (4.0 * 1.4826 * mad / med).max(0.05);
        let off = |l: f64| (l - med).abs() > tol * med;
        let (mut a, mut b) = best;
        while a < b && off(lv[a]) {
            a += 1;
        }
        while b > a && off(lv[b - 1]) {
            b -= 1;
        }
        let span_s = end_s(b) - end_s(a);
        if span_s < 2.0 * rev_s * (1.0 - 1e-9) {
            return Err(no_cut(format!(
                "the longest stable run above the threshold {threshold:.3} N (air level {lo:.3} N, cutting level {hi:.3} N) \
                 lasts {span_s:.4} s, less than two revolutions ({:.4} s)",
                2.0 * rev_s
            )));
        }
        let air: Vec<&Block> = blocks
            .iter()
            .zip(&lv)
            .filter(|(_, &l)| contrast && l <= 2.0 * lo)
            .map(|(b, _)| b)
            .collect();
        let air_offset = (!air.is_empty()).then(|| {
            let sum = air
                .iter()
                .fold(Block::default(), |acc, b| Block::merge(acc, **b));
            sum.mean()
        });
        Ok(SteadySection {
            from_s: end_s(a),
            to_s: end_s(b),
            overridden: false,
            block_s,
            air_level: lo,
            cut_level: median(&lv[a..b]),
            threshold,
            trim_tolerance: tol,
            trimmed_blocks: (a - best.0) + (best.1 - b),
            air_offset,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn feed(env: &mut Envelope, revs: usize, len: usize, amp: f64) {
        for n in 0..revs * len {
            let s = (n as f64 * 0.3).sin();
            env.push([5.0 + amp * s, -2.0 + amp * s * 0.5, 1.0]);
        }
    }

    #[test]
    fn finds_the_cut_between_air_and_trims_a_ramp() {
        let mut e = Envelope::new(100);
        feed(&mut e, 5, 100, 0.01); // air with an offset
        feed(&mut e, 1, 100, 3.0); // entry: lower level
        feed(&mut e, 20, 100, 10.0);
        feed(&mut e, 4, 100, 0.01);
        let s = e.detect(1000.0, 0.1).unwrap();
        assert!(
            (s.from_s - 0.6).abs() < 1e-9 && (s.to_s - 2.6).abs() < 1e-9,
            "{s:?}"
        );
        assert_eq!(s.trimmed_blocks, 0); // the entry block is below the threshold here
        let off = s.air_offset.unwrap();
        assert!(
            (off[0] - 5.0).abs() < 1e-3
                && (off[1] + 2.0).abs() < 1e-3
                && (off[2] - 1.0).abs() < 1e-9
        );
    }

    #[test]
    fn merging_keeps_memory_bounded() {
        let mut e = Envelope::new(1);
        for n in 0..(3 * MAX_BLOCKS) {
            e.push([n as f64, 0.0, 0.0]);
        }
        assert!(e.blocks.len() < MAX_BLOCKS && e.block_len == 4);
    }

    proptest::proptest! {
        /// [`Envelope::push_all`] over chunks of any sizes gives the blocks, bit for bit, of
        /// [`Envelope::push`] sample by sample, with and without F_z, across block merges.
        #[test]
        fn push_all_equals_push_sample_by_sample(
            values in proptest::collection::vec((-1e4f64..1e4, -1e4f64..1e4, -1e4f64..1e4), 0..600),
            cuts in proptest::collection::vec(0usize..80, 0..20),
            block_len in 1u64..40,
            with_z in proptest::bool::ANY,
        ) {
            let (fx, fy, fz): (Vec<f64>, Vec<f64>, Vec<f64>) = (
                values.iter().map(|v| v.0).collect(),
                values.iter().map(|v| v.1).collect(),
                values.iter().map(|v| v.2).collect(),
            );
            let mut one = Envelope::new(block_len);
            for i in 0..fx.len() {
                one.push([fx[i], fy[i], if with_z { fz[i] } else { 0.0 }]);
            }
            let mut all = Envelope::new(block_len);
            let mut at = 0usize;
            for c in cuts.iter().chain(std::iter::once(&usize::MAX)) {
                let end = at.saturating_add(*c).min(fx.len());
                all.push_all(&fx[at..end], &fy[at..end], with_z.then(|| &fz[at..end]));
                at = end;
            }
            let bits = |e: &Envelope| -> Vec<(u64, [u64; 6])> {
                e.blocks.iter().chain(std::iter::once(&e.current)).map(|b| {
                    (b.n, [b.sum[0], b.sum[1], b.sum[2], b.sq[0], b.sq[1], b.sq[2]].map(f64::to_bits))
                }).collect()
            };
            proptest::prop_assert_eq!(bits(&one), bits(&all));
            proptest::prop_assert_eq!(one.block_len, all.block_len);
        }
    }

    #[test]
    fn pure_air_is_not_a_cut() {
        let mut e = Envelope::new(100);
        for _ in 0..10 * 100 {
            e.push([1.0, 2.0, 3.0]);
        }
        assert!(matches!(
            e.detect(1000.0, 0.1),
            Err(SignalError::NoCut { .. })
        ));
    }
}
