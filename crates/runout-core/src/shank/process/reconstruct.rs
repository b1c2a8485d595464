//! Pass 2 of the shank pipeline (methods.md §3.2 steps 6–8): the streaming force reconstruction.

// Column-major data (`columns[c][k]`) reads clearest with index loops.
#![allow(clippy::needless_range_loop)]

use super::super::deconvolve::Deconvolver;
use super::super::filter::{Butterworth, ZeroPhaseStream};
use super::super::ShankError;
#[allow(unused_imports)]
use super::*;
use std::collections::VecDeque;

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
    spectrum: Option<super::super::ResonanceSpectrum>,
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
            super::super::ResonanceSpectrum::new(
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
    /// stands out ([`super::super::ResonanceSpectrum`]).
    pub fn spectral_resonance(&self) -> Option<super::super::SpectralResonance> {
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
