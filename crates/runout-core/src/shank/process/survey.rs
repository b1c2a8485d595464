//! Pass 1 of the shank pipeline (methods.md §3.2 step 1): the streaming survey.

// Column-major data (`columns[c][k]`) reads clearest with index loops.
#![allow(clippy::needless_range_loop)]

use super::super::ShankError;
#[allow(unused_imports)]
use super::*;
use crate::signal::PulseEdgeDetector;
use std::collections::VecDeque;

/// Pass 1 accumulator.
#[derive(Debug, Clone)]
pub struct Survey {
    setup: ShankSetup,
    block_len: usize,
    n: u64,
    cur: Vec<(f64, f64)>,
    cur_count: usize,
    /// Per block, per pair: (mean, std) of x_II − x_I, mm.
    blocks: Vec<(f32, f32)>,
    head: Vec<Vec<f64>>,
    head_cap: usize,
    tail: Vec<VecDeque<f64>>,
    tail_cap: usize,
    given: Vec<(SampleRange, Vec<Vec<f64>>)>,
    pulse: Option<(PulseEdgeDetector, Vec<f64>)>,
    flat: Vec<(f64, u64, u64)>,
    /// Flat runs per channel: (start, end, value).
    pub flat_runs: Vec<Vec<(u64, u64, f64)>>,
    range: Vec<(f64, f64)>,
    range_open: Vec<Option<u64>>,
    range_runs: Vec<(u64, u64)>,
}

/// Samples in a row of identical values from which the run counts as clipped.
const FLAT_RUN: u64 = 8;

impl Survey {
    /// Start pass 1.
    pub fn new(setup: &ShankSetup) -> Result<Self, ShankError> {
        setup.validate()?;
        let block_len = setup.samples_per_rev().round() as usize;
        let cap = (setup
            .max_template_revolutions
            .max(setup.min_air_revolutions)
            + 2)
            * block_len;
        let nd = setup.displacement_channels() + usize::from(setup.has_pulse);
        let dt = 1.0 / setup.sample_rate_hz;
        let given = setup
            .air_cut_s
            .iter()
            .map(|&(a, b)| {
                let s = ((a - setup.start_time_s) / dt).ceil().max(0.0) as u64;
                let e = ((b - setup.start_time_s) / dt).floor().max(0.0) as u64;
                // a window shorter than one sample is empty, never reversed
                let e = e.min(s + cap as u64).max(s);
                (SampleRange { start: s, end: e }, vec![Vec::new(); nd])
            })
            .collect();
        Ok(Self {
            block_len,
            n: 0,
            cur: vec![(0.0, 0.0); setup.pairs.len()],
            cur_count: 0,
            blocks: Vec::new(),
            head: vec![Vec::new(); nd],
            head_cap: cap,
            tail: vec![VecDeque::new(); nd],
            tail_cap: cap,
            given,
            pulse: None,
            flat: vec![(f64::NAN, 0, 0); setup.displacement_channels()],
            flat_runs: vec![Vec::new(); setup.displacement_channels()],
            range: vec![(f64::INFINITY, f64::NEG_INFINITY); setup.displacement_channels()],
            range_open: vec![None; setup.displacement_channels()],
            range_runs: Vec::new(),
            setup: setup.clone(),
        })
    }

    /// Samples seen.
    pub fn samples(&self) -> u64 {
        self.n
    }

    /// Feed a chunk: `columns[c][k]` in the input order of [`ShankSetup`].
    pub fn push(&mut self, columns: &[&[f64]]) -> Result<(), ShankError> {
        let nd = self.setup.displacement_channels();
        let nkeep = nd + usize::from(self.setup.has_pulse);
        if columns.len() < nkeep || columns.iter().any(|c| c.len() != columns[0].len()) {
            return Err(ShankError::Input(format!(
                "{} channels per row, expected {}",
                columns.len(),
                self.setup.input_channels()
            )));
        }
        let len = columns.first().map_or(0, |c| c.len());
        let dt = 1.0 / self.setup.sample_rate_hz;
        for k in 0..len {
            let n = self.n;
            for (d, acc) in self.cur.iter_mut().enumerate() {
                let diff = columns[2 * d + 1][k] - columns[2 * d][k];
                acc.0 += diff;
                acc.1 += diff * diff;
            }
            self.cur_count += 1;
            for c in 0..nd {
                let v = columns[c][k];
                let r = &mut self.range[c];
                r.0 = r.0.min(v);
                r.1 = r.1.max(v);
                let f = &mut self.flat[c];
                if v == f.0 {
                    f.2 = n + 1;
                } else {
                    if f.2 - f.1 >= FLAT_RUN && self.flat_runs[c].len() < 100_000 {
                        self.flat_runs[c].push((f.1, f.2, f.0));
                    }
                    *f = (v, n, n + 1);
                }
                if let Some((lo, hi)) = self.setup.sensor_range_mm {
                    let out = v <= lo || v >= hi;
                    match (out, self.range_open[c]) {
                        (true, None) => self.range_open[c] = Some(n),
                        (false, Some(s)) => {
                            self.range_runs.push((s, n));
                            self.range_open[c] = None;
                        }
                        _ => {}
                    }
                }
            }
            if self.head[0].len() < self.head_cap {
                for c in 0..nkeep {
                    self.head[c].push(columns[c][k]);
                }
            }
            for c in 0..nkeep {
                if self.tail[c].len() == self.tail_cap {
                    self.tail[c].pop_front();
                }
                self.tail[c].push_back(columns[c][k]);
            }
            for (r, store) in &mut self.given {
                if n >= r.start && n < r.end {
                    for c in 0..nkeep {
                        store[c].push(columns[c][k]);
                    }
                }
            }
            if self.setup.has_pulse {
                let t = self.setup.start_time_s + n as f64 * dt;
                let v = columns[nd][k];
                if let Some((det, edges)) = &mut self.pulse {
                    edges.extend(det.push(t, v));
                } else if self.head[0].len() == (2 * self.block_len).min(self.head_cap) {
                    self.start_pulse();
                }
            }
            if self.cur_count == self.block_len {
                self.close_block();
            }
            self.n += 1;
        }
        Ok(())
    }

    fn start_pulse(&mut self) {
        let nd = self.setup.displacement_channels();
        let p = &self.head[nd];
        let (lo, hi) = p.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, &v| {
            (a.0.min(v), a.1.max(v))
        });
        if let Some(mut det) = PulseEdgeDetector::mid_with_hysteresis(lo, hi) {
            let dt = 1.0 / self.setup.sample_rate_hz;
            let edges = p
                .iter()
                .enumerate()
                .filter_map(|(k, &v)| det.push(self.setup.start_time_s + k as f64 * dt, v))
                .collect();
            self.pulse = Some((det, edges));
        }
    }

    fn close_block(&mut self) {
        let n = self.cur_count as f64;
        for acc in &mut self.cur {
            let mean = acc.0 / n;
            let var = (acc.1 / n - mean * mean).max(0.0);
            self.blocks.push((mean as f32, var.sqrt() as f32));
            *acc = (0.0, 0.0);
        }
        self.cur_count = 0;
    }

    /// End of pass 1.
    pub fn finish(mut self) -> Result<SurveyResult, ShankError> {
        // a partial last block is not classified (its statistics are not comparable)
        if self.setup.has_pulse && self.pulse.is_none() {
            self.start_pulse();
        }
        let n = self.n;
        let nd = self.setup.displacement_channels();
        for c in 0..nd {
            let f = self.flat[c];
            if f.2 - f.1 >= FLAT_RUN {
                self.flat_runs[c].push((f.1, f.2, f.0));
            }
            // a clipped run sits at the channel's extreme value
            let (lo, hi) = self.range[c];
            self.flat_runs[c].retain(|r| r.2 == lo || r.2 == hi);
            if let Some(s) = self.range_open[c] {
                self.range_runs.push((s, n));
            }
        }
        let tail_start = n - self.tail[0].len() as u64;
        Ok(SurveyResult {
            samples: n,
            block_len: self.block_len,
            blocks: self.blocks,
            head: self.head,
            tail_start,
            tail: self.tail.into_iter().map(Vec::from).collect(),
            given: self.given,
            pulse_edges_s: self.pulse.map(|p| p.1),
            flat_runs: self.flat_runs,
            range_runs: self.range_runs,
            setup: self.setup,
        })
    }
}

/// What pass 1 found.
#[derive(Debug, Clone)]
pub struct SurveyResult {
    /// Samples in the record.
    pub samples: u64,
    /// Samples per block (nominal revolution).
    pub block_len: usize,
    /// Per block and pair: (mean, std) of x_II − x_I, mm.
    pub blocks: Vec<(f32, f32)>,
    pub(super) head: Vec<Vec<f64>>,
    pub(super) tail_start: u64,
    pub(super) tail: Vec<Vec<f64>>,
    pub(super) given: Vec<(SampleRange, Vec<Vec<f64>>)>,
    /// Pulse edges, s (if a pulse channel was given and swings).
    pub pulse_edges_s: Option<Vec<f64>>,
    /// Clipped runs per displacement channel (start, end, value).
    pub flat_runs: Vec<Vec<(u64, u64, f64)>>,
    /// Runs of samples at or beyond the sensor range (start, end).
    pub range_runs: Vec<(u64, u64)>,
    pub(super) setup: ShankSetup,
}

impl SurveyResult {
    /// Samples of `range` from the head, tail or given buffers, per kept channel.
    pub(super) fn samples_of(&self, range: SampleRange) -> Option<Vec<Vec<f64>>> {
        let head_len = self.head[0].len() as u64;
        if range.end <= head_len {
            return Some(
                self.head
                    .iter()
                    .map(|c| c[range.start as usize..range.end as usize].to_vec())
                    .collect(),
            );
        }
        if range.start >= self.tail_start {
            let (s, e) = (
                (range.start - self.tail_start) as usize,
                (range.end - self.tail_start) as usize,
            );
            return Some(self.tail.iter().map(|c| c[s..e].to_vec()).collect());
        }
        self.given
            .iter()
            .find(|(r, _)| r.start == range.start)
            .map(|(r, store)| {
                let e = (range.end.min(r.end) - r.start) as usize;
                store.iter().map(|c| c[..e].to_vec()).collect()
            })
    }
}
