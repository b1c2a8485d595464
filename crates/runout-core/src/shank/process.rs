//! The two-pass streaming pipeline of the shank method (methods.md §3.2 steps 1–8):
//!
//! 1. [`Survey`] (pass 1, streaming): per nominal revolution ("block") the mean and standard
//!    deviation of the raw difference x_II − x_I of each sensor pair; the first and last
//!    `max_template_revolutions` revolutions of raw samples (bounded buffers); pulse edges;
//!    clipped (flat-at-the-rail) runs.
//! 2. [`analyse`]: air-cut segments (given, or the leading/trailing runs of blocks that match the
//!    first/last revolutions, one block of margin at the cut side), spindle angle (pulse, else 1×
//!    phase advance between the air cuts), angle templates per channel, DC level (constant, or
//!    linear between the two air cuts = drift correction), runout offset + tilt (§1.6).
//! 3. [`Reconstructor`] (pass 2, streaming): δ = x − g(θ(t)) − dc(t), Δ = δ_II − δ_I,
//!    F_workpiece = −sign·K_δ·Δ (force on the workpiece, conventions.md), optional zero-phase
//!    low-pass, saturated samples flagged and their force set to NaN, optional comparison with a
//!    reference dynamometer channel; optional deconvolution of the force by the tool's bending
//!    response ([`super::Deconvolver`], before the low-pass).
//!
//! Memory: O(max_template_revolutions × samples per revolution) plus one f32 pair per pair and
//! revolution, plus the low-pass and deconvolution blocks (a few thousand samples per column),
//! independent of the record length otherwise.

// Column-major data (`columns[c][k]`) reads clearest with index loops.
#![allow(clippy::needless_range_loop)]

use super::deconvolve::Deconvolver;
use super::filter::{Butterworth, ZeroPhaseStream};
use super::spindle::{frequency_from_air, PhaseSegment, PulseDetector, SpindlePhase};
use super::template::{AngleTemplate, TemplateBuilder};
use super::{ShankBeam, ShankError};
use std::collections::VecDeque;
use std::f64::consts::FRAC_PI_2;

/// Workpiece axis measured by a sensor pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairAxis {
    /// Feed direction x.
    X,
    /// Feed-normal direction y.
    Y,
}

impl PairAxis {
    /// `x` or `y`.
    pub fn letter(self) -> char {
        match self {
            PairAxis::X => 'x',
            PairAxis::Y => 'y',
        }
    }

    /// Direction angle β in the x–y plane (x: 0, y: π/2).
    fn beta(self) -> f64 {
        match self {
            PairAxis::X => 0.0,
            PairAxis::Y => FRAC_PI_2,
        }
    }
}

/// Two displacement sensors in one direction: I at l_I (nearer the holder), II at l_II.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorPair {
    /// Direction.
    pub axis: PairAxis,
    /// +1 if a positive reading means the shank moved towards +axis, −1 otherwise.
    pub sign: f64,
}

/// Everything the pipeline needs. Input rows are, in this order: for each pair the sensor-I and
/// sensor-II displacement (mm), then the pulse channel if `has_pulse`, then one reference force
/// per pair (N, workpiece frame) if `has_reference`.
#[derive(Debug, Clone, PartialEq)]
pub struct ShankSetup {
    /// Beam geometry (sensor heights, tool length).
    pub beam: ShankBeam,
    /// K_δ used for F = K_δ·Δ, N/mm (beam formula or static calibration).
    pub stiffness_n_per_mm: f64,
    /// Sensor pairs (1 or 2).
    pub pairs: Vec<SensorPair>,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Time of sample 0, s.
    pub start_time_s: f64,
    /// Nominal spindle speed, rpm (block length, search window).
    pub nominal_rpm: f64,
    /// A once-per-revolution pulse channel follows the displacement channels.
    pub has_pulse: bool,
    /// Reference force channels (one per pair) follow.
    pub has_reference: bool,
    /// Air-cut segments given by the user, s (empty = detect).
    pub air_cut_s: Vec<(f64, f64)>,
    /// Linear drift correction between the two air cuts.
    pub drift_correction: bool,
    /// Zero-phase Butterworth low-pass (order, cutoff Hz).
    pub lowpass: Option<(usize, f64)>,
    /// Minimum air-cut revolutions for a template (≥ 5).
    pub min_air_revolutions: usize,
    /// Revolutions kept per air-cut segment.
    pub max_template_revolutions: usize,
    /// Sensor range (low, high), mm: samples at or beyond are flagged as saturated.
    pub sensor_range_mm: Option<(f64, f64)>,
    /// Height above the tool tip where runout is reported (cutting zone, a_p/2), mm.
    pub cutting_height_mm: f64,
    /// Angle bins of the template (0 = half the samples per revolution, 16…2048).
    pub template_bins: usize,
    /// Bending dynamics: density, beam damping, teeth, optional force correction (issue 11).
    pub dynamics: super::ShankDynamics,
}

impl ShankSetup {
    /// Displacement channels (2 per pair).
    pub fn displacement_channels(&self) -> usize {
        2 * self.pairs.len()
    }

    /// Channels per input row.
    pub fn input_channels(&self) -> usize {
        self.displacement_channels()
            + usize::from(self.has_pulse)
            + if self.has_reference {
                self.pairs.len()
            } else {
                0
            }
    }

    /// Nominal samples per revolution.
    pub fn samples_per_rev(&self) -> f64 {
        self.sample_rate_hz * 60.0 / self.nominal_rpm
    }

    fn validate(&self) -> Result<(), ShankError> {
        let p = |param: &str, expected: &str, got: String| {
            ShankError::Param(crate::ParamError::new(param, expected, got))
        };
        if self.pairs.is_empty() || self.pairs.len() > 2 {
            return Err(p(
                "pairs",
                "1 or 2 sensor pairs",
                self.pairs.len().to_string(),
            ));
        }
        if !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0) {
            return Err(p("sample_rate_hz", "> 0", self.sample_rate_hz.to_string()));
        }
        if !(self.nominal_rpm.is_finite() && self.nominal_rpm > 0.0) {
            return Err(p("rpm", "> 0", self.nominal_rpm.to_string()));
        }
        if self.samples_per_rev() < 16.0 {
            return Err(p(
                "sample_rate_hz",
                "at least 16 samples per spindle revolution",
                format!("{:.1} samples per revolution", self.samples_per_rev()),
            ));
        }
        if self.samples_per_rev() > crate::limits::MAX_SAMPLES_PER_REV as f64 {
            return Err(p(
                "sample_rate_hz",
                &format!(
                    "at most {} samples per spindle revolution (limit MAX_SAMPLES_PER_REV)",
                    crate::limits::MAX_SAMPLES_PER_REV
                ),
                format!("{:.4e} samples per revolution", self.samples_per_rev()),
            ));
        }
        for (q, &(a, b)) in self.air_cut_s.iter().enumerate() {
            if !(a.is_finite() && b.is_finite() && a >= 0.0 && a < b) {
                return Err(p(
                    &format!("air_cut_s[{q}]"),
                    "a window [start, end] in s with 0 <= start < end",
                    format!("[{}, {}]", crate::limits::show(a), crate::limits::show(b)),
                ));
            }
        }
        if !(self.stiffness_n_per_mm.is_finite() && self.stiffness_n_per_mm > 0.0) {
            return Err(p(
                "stiffness_N_per_um",
                "> 0",
                self.stiffness_n_per_mm.to_string(),
            ));
        }
        if self.min_air_revolutions < 5 {
            return Err(p(
                "min_air_revolutions",
                "≥ 5 (methods.md §3.2 step 3)",
                self.min_air_revolutions.to_string(),
            ));
        }
        Ok(())
    }
}

/// A sample-index range [start, end).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SampleRange {
    /// First sample.
    pub start: u64,
    /// One past the last sample.
    pub end: u64,
}

impl SampleRange {
    /// Samples in the range.
    pub fn len(&self) -> u64 {
        self.end.saturating_sub(self.start)
    }

    /// True if empty.
    pub fn is_empty(&self) -> bool {
        self.end <= self.start
    }
}

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
    pulse: Option<PulseDetector>,
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
                if let Some(p) = &mut self.pulse {
                    p.push(t, v);
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
        if let Some(mut det) = PulseDetector::new(lo, hi) {
            let dt = 1.0 / self.setup.sample_rate_hz;
            for (k, &v) in p.iter().enumerate() {
                det.push(self.setup.start_time_s + k as f64 * dt, v);
            }
            self.pulse = Some(det);
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
            pulse_edges_s: self.pulse.map(|p| p.edges_s),
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
    head: Vec<Vec<f64>>,
    tail_start: u64,
    tail: Vec<Vec<f64>>,
    given: Vec<(SampleRange, Vec<Vec<f64>>)>,
    /// Pulse edges, s (if a pulse channel was given and swings).
    pub pulse_edges_s: Option<Vec<f64>>,
    /// Clipped runs per displacement channel (start, end, value).
    pub flat_runs: Vec<Vec<(u64, u64, f64)>>,
    /// Runs of samples at or beyond the sensor range (start, end).
    pub range_runs: Vec<(u64, u64)>,
    setup: ShankSetup,
}

impl SurveyResult {
    /// Samples of `range` from the head, tail or given buffers, per kept channel.
    fn samples_of(&self, range: SampleRange) -> Option<Vec<Vec<f64>>> {
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

/// Runout of the tool from the air-cut templates (methods.md §3.2 end, §1.6).
#[derive(Debug, Clone, PartialEq)]
pub struct ShankRunout {
    /// Offset vector at the cutting height (re, im) = ρ·e^{jλ}, mm; angle from θ = 0.
    pub offset_mm: (f64, f64),
    /// Standard error per component of the offset, mm.
    pub offset_se_mm: f64,
    /// Offset at the tool tip (z = 0), mm.
    pub tip_offset_mm: (f64, f64),
    /// Tilt vector T = dE/dz (mm/mm).
    pub tilt: (f64, f64),
    /// Standard error per component of the tilt (mm/mm).
    pub tilt_se: f64,
    /// Height above the tip of the reported offset, mm.
    pub cutting_height_mm: f64,
    /// Per pair and height: (z above tip mm, E re, E im) in the spindle frame, mm.
    pub at_sensors: Vec<(f64, f64, f64)>,
}

impl ShankRunout {
    /// Offset magnitude ρ, mm.
    pub fn offset_magnitude_mm(&self) -> f64 {
        self.offset_mm.0.hypot(self.offset_mm.1)
    }

    /// Offset angle λ from the θ = 0 reference, rad (wrapped to (−π, π]).
    pub fn offset_angle_rad(&self) -> f64 {
        self.offset_mm.1.atan2(self.offset_mm.0)
    }

    /// Tilt magnitude, mm/mm.
    pub fn tilt_magnitude(&self) -> f64 {
        self.tilt.0.hypot(self.tilt.1)
    }

    /// Tilt direction, rad.
    pub fn tilt_angle_rad(&self) -> f64 {
        self.tilt.1.atan2(self.tilt.0)
    }
}

/// DC level of a channel: constant, or linear between two times (constant outside).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DcLevel {
    /// (time s, level mm) at the first air cut.
    pub a: (f64, f64),
    /// (time s, level mm) at the second air cut (= a if constant).
    pub b: (f64, f64),
}

impl DcLevel {
    /// Level at time t, mm.
    pub fn at(&self, t: f64) -> f64 {
        if self.b.0 <= self.a.0 || t <= self.a.0 {
            self.a.1
        } else if t >= self.b.0 {
            self.b.1
        } else {
            self.a.1 + (self.b.1 - self.a.1) * (t - self.a.0) / (self.b.0 - self.a.0)
        }
    }
}

/// Result of the analysis between the two passes.
#[derive(Debug, Clone)]
pub struct ShankAnalysis {
    /// Air-cut segments used (before and after the cut).
    pub air_segments: Vec<SampleRange>,
    /// Samples between the air cuts (the cut), if any.
    pub cut: Option<SampleRange>,
    /// Air revolutions found before and after the cut (detection), for messages.
    pub air_revolutions_found: (usize, usize),
    /// Spindle angle.
    pub spindle: SpindlePhase,
    /// One template per displacement channel (pair 0 I, pair 0 II, …).
    pub templates: Vec<AngleTemplate>,
    /// DC level per displacement channel.
    pub dc: Vec<DcLevel>,
    /// Runout from the templates.
    pub runout: ShankRunout,
    /// Clipped sample ranges (merged over channels).
    pub saturated: Vec<SampleRange>,
    /// Samples flagged as saturated (clipped runs + out-of-range).
    pub saturated_samples: u64,
    /// Non-fatal findings.
    pub warnings: Vec<String>,
    /// K_δ, N/mm.
    pub stiffness_n_per_mm: f64,
    /// RMS of x − g − dc over the air cuts per channel (template quality), mm.
    pub air_residual_rms_mm: Vec<f64>,
    /// First bending mode, usable bandwidth and tooth-passing check (issue 11 item 7).
    pub bandwidth: super::ShankBandwidth,
    /// Resonance seen in the cut spectrum (set after pass 2 by [`process_in_memory`], or from
    /// [`Reconstructor::spectral_resonance`]).
    pub spectral_resonance: Option<super::SpectralResonance>,
}

/// Detect the air cuts from the block statistics (see the module docs).
fn detect_air(survey: &SurveyResult) -> Result<(Vec<SampleRange>, (usize, usize)), ShankError> {
    let s = &survey.setup;
    let np = s.pairs.len();
    let nb = survey.blocks.len() / np;
    let m0 = s.min_air_revolutions;
    let l = survey.block_len as u64;
    if nb < m0 {
        return Err(ShankError::NoAirCut(format!(
            "the record has {nb} revolutions; at least {m0} air-cut revolutions are needed"
        )));
    }
    let stat = |b: usize, d: usize| survey.blocks[b * np + d];
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    // noise of the raw difference from the head's first blocks (first differences / √2)
    let noise: Vec<f64> = (0..np)
        .map(|d| {
            let (a, b) = (&survey.head[2 * d], &survey.head[2 * d + 1]);
            let n = (m0 * survey.block_len).min(a.len());
            let diffs: Vec<f64> = (1..n)
                .map(|k| (b[k] - a[k]) - (b[k - 1] - a[k - 1]))
                .collect();
            let ms = diffs.iter().map(|v| v * v).sum::<f64>() / diffs.len().max(1) as f64;
            (ms / 2.0).sqrt()
        })
        .collect();
    let base = |range: std::ops::Range<usize>, d: usize| {
        let mut m: Vec<f64> = range.clone().map(|b| f64::from(stat(b, d).0)).collect();
        let mut sd: Vec<f64> = range.map(|b| f64::from(stat(b, d).1)).collect();
        (median(&mut m), median(&mut sd))
    };
    let start: Vec<(f64, f64)> = (0..np).map(|d| base(0..m0, d)).collect();
    let end: Vec<(f64, f64)> = (0..np).map(|d| base(nb - m0..nb, d)).collect();
    let tol: Vec<f64> = (0..np)
        .map(|d| (0.1 * start[d].1).max(8.0 * noise[d]).max(1e-6))
        .collect();
    let is_air = |b: usize, base: &[(f64, f64)]| {
        (0..np).all(|d| {
            let (m, sd) = stat(b, d);
            (f64::from(m) - base[d].0).abs() <= tol[d]
                && (f64::from(sd) - start[d].1).abs() <= tol[d]
        })
    };
    if !(0..m0).all(|b| is_air(b, &start)) {
        return Err(ShankError::NoAirCut(format!(
            "the first {m0} revolutions differ from each other by more than the tolerance \
             ({:.3} µm): the record does not start with a stable air cut; give air_cut_s",
            tol[0] * 1e3
        )));
    }
    let lead = (0..nb).take_while(|&b| is_air(b, &start)).count();
    if lead == nb {
        return Ok((
            vec![SampleRange {
                start: 0,
                end: survey.samples,
            }],
            (nb, 0),
        ));
    }
    let trail = (0..nb).rev().take_while(|&b| is_air(b, &end)).count();
    let before = lead.saturating_sub(1);
    let after = trail.saturating_sub(1);
    let mut segs = Vec::new();
    if before >= m0 {
        segs.push(SampleRange {
            start: 0,
            end: before as u64 * l,
        });
    }
    if after >= m0 {
        let start = (nb - after) as u64 * l;
        segs.push(SampleRange {
            start,
            end: survey.samples,
        });
    }
    if segs.is_empty() {
        return Err(ShankError::NoAirCut(format!(
            "found {lead} air-cut revolutions before the cut and {trail} after (1 of each is \
             margin); at least {m0} stable revolutions are needed; record the spindle running \
             idle before the cut or give air_cut_s"
        )));
    }
    Ok((segs, (lead, trail)))
}

/// Between the passes: segments, spindle angle, templates, DC, runout (see the module docs).
pub fn analyse(survey: &SurveyResult) -> Result<ShankAnalysis, ShankError> {
    let s = &survey.setup;
    let fs = s.sample_rate_hz;
    let dt = 1.0 / fs;
    let nd = s.displacement_channels();
    let mut warnings = Vec::new();
    let (mut segments, found) = if s.air_cut_s.is_empty() {
        detect_air(survey)?
    } else {
        let segs: Vec<SampleRange> = survey
            .given
            .iter()
            .map(|(r, _)| SampleRange {
                // a window past the end of the recording is empty (and refused below)
                start: r.start.min(survey.samples),
                end: r.end.min(survey.samples).max(r.start.min(survey.samples)),
            })
            .collect();
        let spr = s.samples_per_rev();
        for r in &segs {
            if (r.len() as f64) < s.min_air_revolutions as f64 * spr {
                return Err(ShankError::NoAirCut(format!(
                    "the given air cut {:.4}–{:.4} s holds {:.1} revolutions; at least {} are needed",
                    s.start_time_s + r.start as f64 * dt,
                    s.start_time_s + r.end as f64 * dt,
                    r.len() as f64 / spr,
                    s.min_air_revolutions
                )));
            }
        }
        (segs, (0, 0))
    };
    let cut = if segments.len() == 2 {
        Some(SampleRange {
            start: segments[0].end,
            end: segments[1].start,
        })
    } else if segments[0].start == 0 && segments[0].end < survey.samples {
        Some(SampleRange {
            start: segments[0].end,
            end: survey.samples,
        })
    } else if segments[0].start > 0 {
        Some(SampleRange {
            start: 0,
            end: segments[0].start,
        })
    } else {
        None
    };
    // bound the data used per segment: the first revolutions of a leading or given segment,
    // the last ones of a trailing segment (all held in the pass-1 buffers)
    let cap = (s.max_template_revolutions as f64 * s.samples_per_rev()).ceil() as u64;
    for r in segments.iter_mut() {
        if r.start == 0 || !s.air_cut_s.is_empty() {
            r.end = r.end.min(r.start + cap);
        } else {
            r.start = r.start.max(r.end.saturating_sub(cap));
        }
    }
    let data: Vec<Vec<Vec<f64>>> = segments
        .iter()
        .map(|r| {
            survey.samples_of(*r).ok_or_else(|| {
                ShankError::Input(format!(
                    "air-cut samples {}–{} were not kept in memory",
                    r.start, r.end
                ))
            })
        })
        .collect::<Result<_, _>>()?;
    if segments.len() == 1 && cut.is_some() {
        warnings.push(
            "only one air-cut segment: the spindle speed comes from that segment alone and no \
             drift correction is possible; record an idle segment after the cut too"
                .into(),
        );
    }
    // spindle angle
    let f_nom = s.nominal_rpm / 60.0;
    let spindle = match &survey.pulse_edges_s {
        Some(e) if e.len() >= 2 => SpindlePhase::Pulses { edges_s: e.clone() },
        _ => {
            if s.has_pulse {
                warnings.push("the pulse channel has fewer than 2 edges; spindle angle estimated from the 1× component instead".into());
            }
            // reference channel: the one with the largest 1× amplitude in the first segment
            let best = (0..nd)
                .max_by(|&a, &b| {
                    let pa = super::spindle::phasor(&data[0][a], 0.0, fs, f_nom).0;
                    let pb = super::spindle::phasor(&data[0][b], 0.0, fs, f_nom).0;
                    pa.total_cmp(&pb)
                })
                .unwrap_or(0);
            let segs: Vec<PhaseSegment> = segments
                .iter()
                .zip(&data)
                .map(|(r, d)| PhaseSegment {
                    x: &d[best],
                    t_start: s.start_time_s + r.start as f64 * dt,
                })
                .collect();
            let (f, se, source) = frequency_from_air(&segs, fs, f_nom);
            SpindlePhase::Constant {
                frequency_hz: f,
                frequency_se_hz: se,
                t0_s: s.start_time_s,
                source,
            }
        }
    };
    let f_est = spindle.mean_frequency_hz();
    if ((f_est - f_nom) / f_nom).abs() > 0.02 {
        warnings.push(format!(
            "spindle speed {:.2} rpm differs from the nominal {:.2} rpm by more than 2 %",
            f_est * 60.0,
            s.nominal_rpm
        ));
    }
    // templates
    let spr = fs / f_est;
    let bins = if s.template_bins > 0 {
        s.template_bins
    } else {
        ((spr / 2.0).floor() as usize).clamp(16, 2048)
    };
    let mut builders: Vec<TemplateBuilder> = (0..nd).map(|_| TemplateBuilder::new(bins)).collect();
    let sat = saturated_ranges(survey);
    for (r, d) in segments.iter().zip(&data) {
        let mut hint = 0;
        let mut sp = 0;
        for k in 0..d[0].len() {
            let n = r.start + k as u64;
            if is_in(&sat, n, &mut sp) {
                continue;
            }
            let th = spindle.angle(s.start_time_s + n as f64 * dt, &mut hint);
            for (c, b) in builders.iter_mut().enumerate() {
                b.push(th, d[c][k]);
            }
        }
    }
    let templates: Vec<AngleTemplate> = builders
        .into_iter()
        .map(|b| b.finish(spr))
        .collect::<Option<_>>()
        .ok_or_else(|| {
            ShankError::NoAirCut("the air-cut segments hold no usable samples".into())
        })?;
    let revs = templates[0].revolutions;
    if revs < s.min_air_revolutions {
        return Err(ShankError::NoAirCut(format!(
            "the air cuts hold {revs} complete revolutions; at least {} are needed",
            s.min_air_revolutions
        )));
    }
    // DC level per segment, drift line
    let mut dc = Vec::new();
    let mut air_rms = Vec::new();
    for c in 0..nd {
        let mut levels = Vec::new();
        let (mut ss, mut cnt) = (0.0, 0usize);
        for (r, d) in segments.iter().zip(&data) {
            let mut hint = 0;
            let mut acc = 0.0;
            for (k, v) in d[c].iter().enumerate() {
                let t = s.start_time_s + (r.start + k as u64) as f64 * dt;
                acc += v - templates[c].value(spindle.angle(t, &mut hint));
            }
            let level = acc / d[c].len() as f64;
            let tc = s.start_time_s + (r.start as f64 + r.len() as f64 / 2.0) * dt;
            levels.push((tc, level, d[c].len() as f64));
        }
        let level = if s.drift_correction && levels.len() == 2 {
            DcLevel {
                a: (levels[0].0, levels[0].1),
                b: (levels[1].0, levels[1].1),
            }
        } else {
            let w: f64 = levels.iter().map(|l| l.2).sum();
            let m = levels.iter().map(|l| l.1 * l.2).sum::<f64>() / w;
            DcLevel {
                a: (levels[0].0, m),
                b: (levels[0].0, m),
            }
        };
        for (r, d) in segments.iter().zip(&data) {
            let mut hint = 0;
            for (k, v) in d[c].iter().enumerate() {
                let t = s.start_time_s + (r.start + k as u64) as f64 * dt;
                let e = v - templates[c].value(spindle.angle(t, &mut hint)) - level.at(t);
                ss += e * e;
                cnt += 1;
            }
        }
        dc.push(level);
        air_rms.push((ss / cnt.max(1) as f64).sqrt());
    }
    let runout = runout_from_templates(s, &templates);
    let saturated_samples = sat.iter().map(|r| r.len()).sum::<u64>();
    if saturated_samples > 0 {
        warnings.push(format!(
            "{saturated_samples} displacement samples are saturated (clipped at the sensor's range); their force is not computed (NaN) and they are flagged in the output"
        ));
    }
    let axes: Vec<PairAxis> = s.pairs.iter().map(|p| p.axis).collect();
    let (bandwidth, band_warning) =
        super::bandwidth(&s.beam, &s.dynamics, &axes, f_est, fs).map_err(ShankError::Param)?;
    warnings.extend(band_warning);
    Ok(ShankAnalysis {
        bandwidth,
        spectral_resonance: None,
        air_segments: segments,
        cut,
        air_revolutions_found: found,
        spindle,
        templates,
        dc,
        runout,
        saturated: sat,
        saturated_samples,
        warnings,
        stiffness_n_per_mm: s.stiffness_n_per_mm,
        air_residual_rms_mm: air_rms,
    })
}

/// Clipped runs of all channels merged into sorted ranges.
fn saturated_ranges(survey: &SurveyResult) -> Vec<SampleRange> {
    let mut all: Vec<SampleRange> = survey
        .flat_runs
        .iter()
        .flatten()
        .map(|&(a, b, _)| SampleRange { start: a, end: b })
        .chain(
            survey
                .range_runs
                .iter()
                .map(|&(a, b)| SampleRange { start: a, end: b }),
        )
        .collect();
    all.sort_by_key(|r| r.start);
    let mut merged: Vec<SampleRange> = Vec::new();
    for r in all {
        match merged.last_mut() {
            Some(m) if r.start <= m.end => m.end = m.end.max(r.end),
            _ => merged.push(r),
        }
    }
    merged
}

/// Is sample n inside a sorted range list (sequential access via `pos`)?
fn is_in(ranges: &[SampleRange], n: u64, pos: &mut usize) -> bool {
    while *pos < ranges.len() && ranges[*pos].end <= n {
        *pos += 1;
    }
    *pos < ranges.len() && ranges[*pos].start <= n
}

/// Offset and tilt from the first harmonics at the two heights of each pair (methods.md §1.6):
/// E_wp = sign·E·e^{−jβ} (β = 0 for x, π/2 for y), heights z = l_tool − l above the tip,
/// T = (E_II − E_I)/(z_II − z_I), E(z_c) = E_I + (z_c − z_I)·T, averaged over the pairs.
fn runout_from_templates(s: &ShankSetup, templates: &[AngleTemplate]) -> ShankRunout {
    let zi = s.beam.tool_length_mm - s.beam.l1_mm;
    let zii = s.beam.tool_length_mm - s.beam.l2_mm;
    let zc = s.cutting_height_mm;
    let rot = |e: (f64, f64), p: &SensorPair| {
        let (c, sn) = (p.axis.beta().cos(), p.axis.beta().sin());
        (p.sign * (e.0 * c + e.1 * sn), p.sign * (e.1 * c - e.0 * sn))
    };
    let np = s.pairs.len() as f64;
    let (mut off, mut tip, mut tilt) = ((0.0, 0.0), (0.0, 0.0), (0.0, 0.0));
    let (mut off_var, mut tilt_var) = (0.0, 0.0);
    let mut at = Vec::new();
    for (d, p) in s.pairs.iter().enumerate() {
        let e1 = rot(templates[2 * d].first_harmonic, p);
        let e2 = rot(templates[2 * d + 1].first_harmonic, p);
        let se = |t: &AngleTemplate| {
            let (a, b) = t.first_harmonic_se;
            ((a * a + b * b) / 2.0).sqrt()
        };
        let (s1, s2) = (se(&templates[2 * d]), se(&templates[2 * d + 1]));
        let t = ((e2.0 - e1.0) / (zii - zi), (e2.1 - e1.1) / (zii - zi));
        let w = (zc - zi) / (zii - zi);
        off.0 += (e1.0 + (zc - zi) * t.0) / np;
        off.1 += (e1.1 + (zc - zi) * t.1) / np;
        tip.0 += (e1.0 - zi * t.0) / np;
        tip.1 += (e1.1 - zi * t.1) / np;
        tilt.0 += t.0 / np;
        tilt.1 += t.1 / np;
        off_var += ((1.0 - w).powi(2) * s1 * s1 + w * w * s2 * s2) / (np * np);
        tilt_var += (s1 * s1 + s2 * s2) / (zii - zi).powi(2) / (np * np);
        at.push((zi, e1.0, e1.1));
        at.push((zii, e2.0, e2.1));
    }
    ShankRunout {
        offset_mm: off,
        offset_se_mm: off_var.sqrt(),
        tip_offset_mm: tip,
        tilt,
        tilt_se: tilt_var.sqrt(),
        cutting_height_mm: zc,
        at_sensors: at,
    }
}

/// Streaming comparison of the shank force with a reference force (validation mode).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ForceComparison {
    n: u64,
    sa: f64,
    sb: f64,
    saa: f64,
    sbb: f64,
    sab: f64,
    see: f64,
    max_abs_err: f64,
    max_a: f64,
    max_b: f64,
}

/// Validation metrics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComparisonMetrics {
    /// Samples compared.
    pub samples: u64,
    /// RMS of (shank − reference), N.
    pub rms_error_n: f64,
    /// RMS of the reference, N.
    pub rms_reference_n: f64,
    /// rms_error / rms_reference.
    pub relative_rms_error: f64,
    /// Largest |shank − reference| at one sample, N.
    pub max_abs_error_n: f64,
    /// Peak error: max|shank| − max|reference|, N.
    pub peak_error_n: f64,
    /// Pearson correlation coefficient.
    pub correlation: f64,
}

impl ForceComparison {
    /// Add one pair of samples (skipped if either is NaN).
    pub fn push(&mut self, shank: f64, reference: f64) {
        if !(shank.is_finite() && reference.is_finite()) {
            return;
        }
        let e = shank - reference;
        self.n += 1;
        self.sa += shank;
        self.sb += reference;
        self.saa += shank * shank;
        self.sbb += reference * reference;
        self.sab += shank * reference;
        self.see += e * e;
        self.max_abs_err = self.max_abs_err.max(e.abs());
        self.max_a = self.max_a.max(shank.abs());
        self.max_b = self.max_b.max(reference.abs());
    }

    /// The metrics so far.
    pub fn metrics(&self) -> ComparisonMetrics {
        let n = self.n.max(1) as f64;
        let cov = self.sab / n - self.sa * self.sb / n / n;
        let va = self.saa / n - (self.sa / n).powi(2);
        let vb = self.sbb / n - (self.sb / n).powi(2);
        let rms_ref = (self.sbb / n).sqrt();
        let rms_err = (self.see / n).sqrt();
        ComparisonMetrics {
            samples: self.n,
            rms_error_n: rms_err,
            rms_reference_n: rms_ref,
            relative_rms_error: rms_err / rms_ref,
            max_abs_error_n: self.max_abs_err,
            peak_error_n: self.max_a - self.max_b,
            correlation: cov / (va * vb).sqrt(),
        }
    }
}

/// Pass 2: reconstructs δ_I, δ_II, Δ and the force sample by sample.
#[derive(Debug, Clone)]
pub struct Reconstructor {
    setup: ShankSetup,
    analysis: ShankAnalysis,
    n: u64,
    hint: usize,
    sat_pos: usize,
    filter: Option<ZeroPhaseStream>,
    deconvolver: Option<Deconvolver>,
    spectrum: Option<super::ResonanceSpectrum>,
    pending: VecDeque<(u64, bool, Vec<f64>)>,
    staged: Vec<Vec<f64>>,
    scratch: Vec<f64>,
    filtered: Vec<Vec<f64>>,
    comparisons: Vec<ForceComparison>,
}

/// Output rows of pass 2, column-wise: see [`Reconstructor::column_names`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OutputBlock {
    /// Sample index of each row.
    pub sample: Vec<u64>,
    /// Time, s.
    pub time_s: Vec<f64>,
    /// Force on the workpiece per pair, N (NaN where saturated).
    pub force_n: Vec<Vec<f64>>,
    /// δ_I per pair, µm.
    pub delta_i_um: Vec<Vec<f64>>,
    /// δ_II per pair, µm.
    pub delta_ii_um: Vec<Vec<f64>>,
    /// Reference force per pair (if any), N.
    pub reference_n: Vec<Vec<f64>>,
    /// Saturated flag.
    pub saturated: Vec<bool>,
}

impl OutputBlock {
    /// Rows.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True if empty.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    fn clear(&mut self, pairs: usize, reference: bool) {
        self.sample.clear();
        self.time_s.clear();
        self.saturated.clear();
        for v in [
            &mut self.force_n,
            &mut self.delta_i_um,
            &mut self.delta_ii_um,
        ] {
            v.resize_with(pairs, Vec::new);
            v.iter_mut().for_each(Vec::clear);
        }
        self.reference_n
            .resize_with(if reference { pairs } else { 0 }, Vec::new);
        self.reference_n.iter_mut().for_each(Vec::clear);
    }
}

impl Reconstructor {
    /// Start pass 2 from the analysis.
    pub fn new(survey: &SurveyResult, analysis: &ShankAnalysis) -> Result<Self, ShankError> {
        let s = &survey.setup;
        let filter = match s.lowpass {
            Some((order, hz)) => Some(ZeroPhaseStream::new(
                Butterworth::lowpass(order, hz, s.sample_rate_hz).ok_or_else(|| {
                    ShankError::Param(crate::ParamError::new(
                        "lowpass_hz",
                        format!(
                            "0 < cutoff < half the sample rate ({} Hz), order 1–16",
                            s.sample_rate_hz / 2.0
                        ),
                        format!("{hz} Hz, order {order}"),
                    ))
                })?,
                3 * s.pairs.len(),
            )),
            None => None,
        };
        // force columns (one per pair) deconvolved by the chain of their axis; δ columns delayed
        let deconvolver = s.dynamics.correction.as_ref().map(|c| {
            let np = s.pairs.len();
            let cols: Vec<Option<&crate::chain::AxisChain>> = (0..3 * np)
                .map(|i| {
                    (i < np).then(|| match s.pairs[i].axis {
                        PairAxis::X => &c.chain.x,
                        PairAxis::Y => &c.chain.y,
                    })
                })
                .collect();
            Deconvolver::new(&cols, c.floor, s.sample_rate_hz)
        });
        let spectrum = analysis.cut.map(|_| {
            super::ResonanceSpectrum::new(
                s.pairs.len(),
                s.sample_rate_hz,
                analysis.spindle.mean_frequency_hz(),
            )
        });
        Ok(Self {
            spectrum,
            setup: s.clone(),
            analysis: analysis.clone(),
            n: 0,
            hint: 0,
            sat_pos: 0,
            filter,
            deconvolver,
            staged: vec![Vec::new(); 3 * s.pairs.len()],
            scratch: vec![0.0; 3 * s.pairs.len()],
            pending: VecDeque::new(),
            filtered: vec![Vec::new(); 3 * s.pairs.len()],
            comparisons: vec![ForceComparison::default(); s.pairs.len()],
        })
    }

    /// Output column names with units.
    pub fn column_names(&self) -> Vec<String> {
        let mut v = vec!["time_s".to_string()];
        let p = &self.setup.pairs;
        v.extend(p.iter().map(|p| format!("f{}_N", p.axis.letter())));
        for q in p {
            v.push(format!("delta_{}_I_um", q.axis.letter()));
            v.push(format!("delta_{}_II_um", q.axis.letter()));
        }
        if self.setup.has_reference {
            v.extend(
                p.iter()
                    .map(|p| format!("reference_f{}_N", p.axis.letter())),
            );
        }
        v.push("saturated".into());
        v
    }

    /// Feed a chunk (columns in the input order); rows ready are written to `out` (cleared
    /// first; with a low-pass they lag by the filter margin). Errors if the chunk has fewer
    /// columns than the setup needs or columns of unequal length.
    pub fn push(&mut self, columns: &[&[f64]], out: &mut OutputBlock) -> Result<(), ShankError> {
        let np = self.setup.pairs.len();
        out.clear(np, self.setup.has_reference);
        let len = columns.first().map_or(0, |c| c.len());
        if columns.len() < self.setup.input_channels() || columns.iter().any(|c| c.len() != len) {
            return Err(ShankError::Input(format!(
                "{} columns per chunk, expected {} of equal length",
                columns.len(),
                self.setup.input_channels()
            )));
        }
        let dt = 1.0 / self.setup.sample_rate_hz;
        let k_delta = self.analysis.stiffness_n_per_mm;
        let nd = self.setup.displacement_channels();
        let ref0 = nd + usize::from(self.setup.has_pulse);
        let mut row = vec![0.0; 3 * np];
        for k in 0..len {
            let n = self.n;
            let t = self.setup.start_time_s + n as f64 * dt;
            let th = self.analysis.spindle.angle(t, &mut self.hint);
            let mut sat = is_in(&self.analysis.saturated, n, &mut self.sat_pos);
            for (d, p) in self.setup.pairs.iter().enumerate() {
                let mut delta = [0.0; 2];
                for (h, dv) in delta.iter_mut().enumerate() {
                    let c = 2 * d + h;
                    let x = columns[c][k];
                    if let Some((lo, hi)) = self.setup.sensor_range_mm {
                        sat |= x <= lo || x >= hi;
                    }
                    *dv = x - self.analysis.templates[c].value(th) - self.analysis.dc[c].at(t);
                }
                row[d] = -p.sign * k_delta * (delta[1] - delta[0]);
                row[np + 2 * d] = delta[0] * 1e3;
                row[np + 2 * d + 1] = delta[1] * 1e3;
            }
            let refs: Vec<f64> = if self.setup.has_reference {
                (0..np).map(|d| columns[ref0 + d][k]).collect()
            } else {
                Vec::new()
            };
            self.n += 1;
            if let (Some(sp), Some(c)) = (&mut self.spectrum, self.analysis.cut) {
                if n >= c.start && n < c.end && !sat {
                    sp.push(&row[..np]);
                } else {
                    sp.break_frame();
                }
            }
            if self.filter.is_none() && self.deconvolver.is_none() {
                self.emit(n, sat, &row, &refs, out);
                continue;
            }
            self.pending.push_back((n, sat, refs));
            match &mut self.deconvolver {
                Some(d) => d.push(&row, &mut self.staged),
                None => {
                    for (st, v) in self.staged.iter_mut().zip(&row) {
                        st.push(*v);
                    }
                }
            }
            self.stage_to_filter(false);
            self.drain_filtered(out);
        }
        Ok(())
    }

    /// Rows out of the deconvolution (if any) into the low-pass (if any).
    fn stage_to_filter(&mut self, last: bool) {
        let staged = std::mem::take(&mut self.staged);
        match &mut self.filter {
            Some(f) => {
                for i in 0..staged[0].len() {
                    for (r, c) in self.scratch.iter_mut().zip(&staged) {
                        *r = c[i];
                    }
                    f.push(&self.scratch, &mut self.filtered);
                }
                if last {
                    f.finish(&mut self.filtered);
                }
            }
            None => {
                for (fc, sc) in self.filtered.iter_mut().zip(&staged) {
                    fc.extend_from_slice(sc);
                }
            }
        }
        self.staged = staged;
        self.staged.iter_mut().for_each(Vec::clear);
    }

    /// Flush at the end of the record (only needed with a low-pass or a correction).
    pub fn finish(&mut self, out: &mut OutputBlock) {
        out.clear(self.setup.pairs.len(), self.setup.has_reference);
        if self.filter.is_none() && self.deconvolver.is_none() {
            return;
        }
        if let Some(d) = &mut self.deconvolver {
            d.finish(&mut self.staged);
        }
        self.stage_to_filter(true);
        self.drain_filtered(out);
    }

    fn drain_filtered(&mut self, out: &mut OutputBlock) {
        let m = self.filtered[0].len();
        let cols = std::mem::take(&mut self.filtered);
        let mut row = vec![0.0; cols.len()];
        for i in 0..m {
            for (r, c) in row.iter_mut().zip(&cols) {
                *r = c[i];
            }
            let (n, sat, refs) = self
                .pending
                .pop_front()
                .expect("one pending row per filtered row");
            self.emit(n, sat, &row, &refs, out);
        }
        self.filtered = cols;
        self.filtered.iter_mut().for_each(Vec::clear);
    }

    fn emit(&mut self, n: u64, sat: bool, row: &[f64], refs: &[f64], out: &mut OutputBlock) {
        let np = self.setup.pairs.len();
        out.sample.push(n);
        out.time_s
            .push(self.setup.start_time_s + n as f64 / self.setup.sample_rate_hz);
        out.saturated.push(sat);
        let in_cut = self.analysis.cut.is_none_or(|c| n >= c.start && n < c.end);
        for d in 0..np {
            let f = if sat { f64::NAN } else { row[d] };
            out.force_n[d].push(f);
            out.delta_i_um[d].push(row[np + 2 * d]);
            out.delta_ii_um[d].push(row[np + 2 * d + 1]);
            if let Some(r) = refs.get(d) {
                out.reference_n[d].push(*r);
                if in_cut {
                    self.comparisons[d].push(f, *r);
                }
            }
        }
    }

    /// The bending resonance seen in the spectrum of the (uncorrected) force over the cut, if one
    /// stands out ([`super::ResonanceSpectrum`]).
    pub fn spectral_resonance(&self) -> Option<super::SpectralResonance> {
        self.spectrum.as_ref().and_then(|s| s.resonance())
    }

    /// Validation metrics per pair over the cut (if reference channels were given).
    pub fn comparison(&self) -> Option<Vec<ComparisonMetrics>> {
        self.setup.has_reference.then(|| {
            self.comparisons
                .iter()
                .map(ForceComparison::metrics)
                .collect()
        })
    }
}

/// Convenience for small records held in memory: both passes over `columns`.
/// Returns the analysis (with the resonance seen in the cut spectrum and its warning) and the
/// full output.
pub fn process_in_memory(
    setup: &ShankSetup,
    columns: &[&[f64]],
) -> Result<(ShankAnalysis, OutputBlock, Option<Vec<ComparisonMetrics>>), ShankError> {
    let mut survey = Survey::new(setup)?;
    survey.push(columns)?;
    let result = survey.finish()?;
    let mut analysis = analyse(&result)?;
    let mut rec = Reconstructor::new(&result, &analysis)?;
    let mut all = OutputBlock::default();
    let mut part = OutputBlock::default();
    rec.push(columns, &mut part)?;
    append(&mut all, &part);
    rec.finish(&mut part);
    append(&mut all, &part);
    let cmp = rec.comparison();
    analysis.spectral_resonance = rec.spectral_resonance();
    if let Some(seen) = &analysis.spectral_resonance {
        let axes: Vec<PairAxis> = setup.pairs.iter().map(|p| p.axis).collect();
        let (_, w) = super::spectral_check(
            &analysis.bandwidth,
            &setup.dynamics,
            &axes,
            seen,
            setup.sample_rate_hz,
        );
        analysis.warnings.extend(w);
    }
    Ok((analysis, all, cmp))
}

/// Append `b` to `a`.
pub fn append(a: &mut OutputBlock, b: &OutputBlock) {
    a.sample.extend_from_slice(&b.sample);
    a.time_s.extend_from_slice(&b.time_s);
    a.saturated.extend_from_slice(&b.saturated);
    for (x, y) in [
        (&mut a.force_n, &b.force_n),
        (&mut a.delta_i_um, &b.delta_i_um),
        (&mut a.delta_ii_um, &b.delta_ii_um),
        (&mut a.reference_n, &b.reference_n),
    ] {
        x.resize_with(y.len(), Vec::new);
        for (u, v) in x.iter_mut().zip(y) {
            u.extend_from_slice(v);
        }
    }
}
