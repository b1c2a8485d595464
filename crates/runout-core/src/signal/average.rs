//! Pass 3 over the section: synchronous average per revolution and per-tooth peaks.
//!
//! Each complete revolution of the section (between two revolution marks: θ(t) = 2πr with
//! θ(t) = 2π·f·(t − t₀) + w(t) − w(0) for the estimated angle (w the tracked wander), rising edges
//! for a pulse channel, piecewise linear between the N edges of an encoder) is resampled at M uniform spindle-angle bins θ_j = θ_origin + 2πj/M by linear
//! interpolation between the neighbouring samples. Per bin and component (F_x, F_y, F_z, |F_xy|,
//! |F_xy| computed from the interpolated F_x, F_y) the mean, the revolution-to-revolution
//! standard deviation and the standard error sd/√n are accumulated (shifted sums).
//!
//! **Tooth periods** (`force::tooth_peaks`): tooth i owns θ ∈ [b₀ + 2πi/K, b₀ + 2π(i+1)/K).
//! Absolute (pulse with tooth-0 angle and the entry angle φ_st): b₀ = φ_st, exactly as in
//! `tooth_peaks`. Otherwise the spindle angle origin is arbitrary: b₀ is put half a tooth period
//! before the maximum of the K-th harmonic of the chosen component in the first revolution
//! (midway between tooth pulses), and "tooth 0" is the tooth whose period begins first at or
//! after θ_origin — an arbitrary reference tooth; the runout angle is then relative to it.
//!
//! **Per-tooth peak** (`conventions.md`, "Signals"): the maximum of the synchronously averaged
//! chosen component within the tooth period (parabolic refinement over the neighbouring bins).
//! Its uncertainty is revolution-to-revolution scatter, taken as the larger of two standard
//! errors: that of the revolutions' values at the peak's bin, and that of the per-revolution
//! maxima in the period (sd/√n; alone it understates the scatter of the average's maximum on a
//! flat top by ≈ 1.6× in the tests). The mean of the per-revolution maxima is reported too; noise
//! lifts every per-revolution maximum, so it is biased upwards (≈ +0.6 σ of the sample noise in
//! the tests) and is not the estimate.
//!
//! The air-cut offset found in pass 1 is subtracted first (`SignalConfig::subtract_air_offset`).
//!
//! Memory: one revolution of samples (3 channels) + 4·M running statistics + K per-tooth.

use super::chunk::ChunkGuard;
use super::pulse::PulseEdgeDetector;
use super::scan::ScanResult;
use super::stats::{parabolic_peak, BinStats, RunningStats};
use super::tracker::SpindleSpeed;
use super::{ForceComponent, SignalChunk, SignalConfig, SignalError};
use crate::angle::wrap_tau;
use serde::Serialize;
use std::f64::consts::{PI, TAU};

/// How the spindle angle θ of the average relates to the machine.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AngleReference {
    /// θ = tooth-0 angle given at the pulse edge: absolute (tooth 0's tip at immersion θ).
    Absolute,
    /// θ = 0 at the pulse edge that starts each revolution.
    PulseEdge,
    /// θ = 0 at the section start `t_ref_s`, advancing at the measured speed and following the
    /// tracked wander (`SpindleSpeed::angle_wander`).
    SectionStart {
        /// Section start (s).
        t_ref_s: f64,
    },
}

/// Which tooth is tooth 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ToothReference {
    /// Tooth numbering is that of the cutter (pulse angle and entry angle known).
    Absolute,
    /// Tooth 0 is an arbitrary reference tooth: the one whose period begins first after the
    /// angle origin. Peaks are in cutting order from it.
    Arbitrary,
}

/// Synchronous average of one component.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ComponentAverage {
    /// Which component.
    pub component: ForceComponent,
    /// Mean per bin (N).
    #[serde(rename = "mean_N")]
    pub mean: Vec<f64>,
    /// Revolution-to-revolution standard deviation per bin (N).
    #[serde(rename = "sd_N")]
    pub sd: Vec<f64>,
    /// Standard error of the mean per bin, sd/√n (N).
    #[serde(rename = "se_N")]
    pub se: Vec<f64>,
}

/// Peak of one tooth period.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ToothPeakEstimate {
    /// Tooth index (cutting order; see [`ToothReference`]).
    pub tooth: usize,
    /// Start of the tooth period θ (rad).
    #[serde(rename = "period_start_rad")]
    pub period_start: f64,
    /// The per-tooth peak (N): maximum of the synchronously averaged waveform in the period.
    #[serde(rename = "peak_N")]
    pub peak: f64,
    /// Standard error of `peak` (N): the larger of the revolution-to-revolution standard error
    /// at the peak's bin (sd of the revolutions' values there /√n) and that of the per-revolution
    /// maxima (`per_rev_max_se`).
    #[serde(rename = "se_N")]
    pub se: f64,
    /// Spindle angle θ of `peak` (rad, in [0, 2π)).
    #[serde(rename = "angle_rad")]
    pub angle: f64,
    /// Mean over the revolutions of the per-revolution maxima in the period (N). Noise lifts each
    /// maximum, so this exceeds `peak` by the noise-induced bias of a maximum (≈ 0.6 σ of the
    /// sample noise in the tests); use it to gauge that bias, not as the peak.
    #[serde(rename = "per_rev_max_mean_N")]
    pub per_rev_max_mean: f64,
    /// Revolution-to-revolution standard deviation of the per-revolution maxima (N).
    #[serde(rename = "per_rev_max_sd_N")]
    pub per_rev_max_sd: f64,
    /// Standard error of `per_rev_max_mean`, sd/√n (N).
    #[serde(rename = "per_rev_max_se_N")]
    pub per_rev_max_se: f64,
}

/// Result of pass 3.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SyncAverage {
    /// Bins per revolution M.
    pub bins: usize,
    /// θ of bin 0 (rad); bin j is at θ_origin + 2πj/M.
    #[serde(rename = "angle_origin_rad")]
    pub angle_origin: f64,
    /// Meaning of the angle.
    pub angle_reference: AngleReference,
    /// Revolutions averaged n.
    pub revolutions: usize,
    /// F_z was recorded (otherwise its average is 0).
    pub has_fz: bool,
    /// Static offset (F_x, F_y, F_z) subtracted from every sample before averaging (N), if any.
    #[serde(rename = "offset_subtracted_N")]
    pub offset_subtracted: Option<[f64; 3]>,
    /// Averages of F_x, F_y, F_z, |F_xy| in [`ForceComponent::ALL`] order.
    pub components: Vec<ComponentAverage>,
    /// Force component whose per-tooth peaks are given.
    pub peak_component: ForceComponent,
    /// Which tooth is tooth 0.
    pub tooth_reference: ToothReference,
    /// Per-tooth peaks, tooth 0 first.
    pub tooth_peaks: Vec<ToothPeakEstimate>,
}

impl SyncAverage {
    /// Spindle angle θ (rad) of bin j.
    pub fn angle(&self, j: usize) -> f64 {
        self.angle_origin + TAU * j as f64 / self.bins as f64
    }
    /// Average of one component.
    pub fn component(&self, c: ForceComponent) -> &ComponentAverage {
        &self.components[c.index()]
    }
}

enum Marks {
    Linear {
        t_ref: f64,
        period: f64,
        next: u64,
        last: u64,
        wander: Vec<(f64, f64)>,
    },
    Pulse {
        det: PulseEdgeDetector,
        to: f64,
    },
}

/// Pass-3 accumulator: feed every chunk again, then [`SyncAverager::finish`].
pub struct SyncAverager {
    fs: f64,
    guard: ChunkGuard,
    m: usize,
    k: usize,
    per_rev: usize,
    component: ForceComponent,
    origin: f64,
    angle_reference: AngleReference,
    absolute_start: Option<f64>,
    marks: Marks,
    from: f64,
    stop: u64,
    buf: Vec<[f64; 3]>,
    buf_start: u64,
    edges: Vec<f64>,
    max_buf: usize,
    acc: BinStats,
    scratch: Vec<f64>,
    owner: Option<(f64, Owners)>,
    teeth: Vec<RunningStats>,
    revs: usize,
    has_fz: bool,
    offset: Option<[f64; 3]>,
}

impl SyncAverager {
    /// Start pass 3 with the results of passes 1 and 2.
    pub fn new(
        cfg: &SignalConfig,
        scan: &ScanResult,
        speed: &SpindleSpeed,
    ) -> Result<Self, SignalError> {
        cfg.validate()?;
        let fs = cfg.sample_rate_hz;
        let (from, to) = (scan.section.from_s, scan.section.to_s);
        let m = cfg.bins();
        let period = 1.0 / speed.hz();
        let (marks, per_rev, origin, angle_reference) = match (cfg.pulse, scan.pulse_thresholds) {
            (Some(p), Some((lo, hi))) => (
                Marks::Pulse {
                    det: PulseEdgeDetector::new(lo, hi),
                    to,
                },
                p.pulses_per_rev,
                p.tooth0_angle_rad.map_or(0.0, wrap_tau),
                if p.tooth0_angle_rad.is_some() {
                    AngleReference::Absolute
                } else {
                    AngleReference::PulseEdge
                },
            ),
            _ => (
                Marks::Linear {
                    t_ref: from,
                    period,
                    next: 0,
                    last: ((to - from) / period + 1e-9).floor() as u64,
                    wander: speed.angle_wander.clone(),
                },
                1,
                0.0,
                AngleReference::SectionStart { t_ref_s: from },
            ),
        };
        let absolute_start = if cfg.absolute_teeth() {
            cfg.entry_angle_rad
        } else {
            None
        };
        Ok(SyncAverager {
            fs,
            guard: ChunkGuard::default(),
            m,
            k: cfg.teeth,
            per_rev,
            component: cfg.peak_component,
            origin,
            angle_reference,
            absolute_start,
            marks,
            from,
            stop: (to * fs).ceil() as u64 + 2,
            buf: Vec::new(),
            buf_start: 0,
            edges: Vec::with_capacity(per_rev + 1),
            // 4 nominal revolutions (the pulse path errors out beyond; the linear path holds one)
            max_buf: (4.0
                * (60.0 / cfg.nominal_rpm).max(period.min(1.5 * 60.0 / cfg.nominal_rpm))
                * fs) as usize
                + 16,
            acc: BinStats::new(4 * m),
            scratch: vec![0.0; 4 * m],
            owner: None,
            teeth: vec![RunningStats::default(); cfg.teeth],
            revs: 0,
            has_fz: scan.has_fz,
            offset: if cfg.subtract_air_offset {
                scan.section.air_offset
            } else {
                None
            },
        })
    }

    /// The same pass over a replay whose values pass 1 has checked finite
    /// ([`super::analyse_replay`]): each chunk's lengths and channel set are still checked.
    pub(crate) fn replaying(mut self) -> Self {
        self.guard = ChunkGuard::values_checked();
        self
    }

    /// Samples fed so far.
    pub(crate) fn samples(&self) -> u64 {
        self.guard.next
    }

    /// Feed the next chunk.
    pub fn push(&mut self, c: SignalChunk) -> Result<(), SignalError> {
        let start = self.guard.next;
        self.guard
            .check(&c, self.fs, matches!(self.marks, Marks::Pulse { .. }))?;
        let len = (self.stop + 1).saturating_sub(start).min(c.len() as u64) as usize;
        let mut i = 0;
        while i < len {
            let linear = match &self.marks {
                Marks::Linear {
                    t_ref,
                    period,
                    next,
                    last,
                    wander,
                } => Some((*next <= *last).then(|| mark_time(*t_ref, *period, *next, wander))),
                Marks::Pulse { .. } => None,
            };
            if let Some(te) = linear {
                // append up to and including the first sample after the next mark, in bulk
                let ne = te.map_or(u64::MAX, |te| (te * self.fs).floor() as u64 + 1);
                let seg_end = (ne.saturating_sub(start).saturating_add(1)).min(len as u64) as usize;
                let seg_end = seg_end.max(i + 1);
                self.append(&c, i, seg_end, start);
                i = seg_end;
                if let Some(te) = te {
                    if ne < start + i as u64 {
                        if let Marks::Linear { next, .. } = &mut self.marks {
                            *next += 1;
                        }
                        self.on_edge(te);
                    }
                }
            } else {
                let n = start + i as u64;
                let t = n as f64 / self.fs;
                let v = c.pulse.map_or(0.0, |p| p[i]);
                let (edge, to) = match &mut self.marks {
                    Marks::Pulse { det, to } => (det.push(t, v), *to),
                    Marks::Linear { .. } => (None, f64::INFINITY),
                };
                self.append(&c, i, i + 1, start);
                i += 1;
                if let Some(te) = edge {
                    if te > to {
                        self.edges.clear();
                        self.stop = n;
                        break;
                    } else if te >= self.from {
                        self.on_edge(te);
                    }
                }
            }
            if self.buf.len() > self.max_buf {
                return Err(SignalError::Pulse {
                    reason: format!(
                        "no revolution mark between {:.6} s and {:.6} s (more than 4 revolutions): the pulse is missing or the speed is wrong",
                        self.buf_start as f64 / self.fs,
                        (start + i as u64) as f64 / self.fs
                    ),
                });
            }
        }
        Ok(())
    }

    /// Append samples `i0..i1` of `c` (global index `start + i`) to the buffer, offset removed.
    /// Outside a revolution only the last two samples are kept.
    fn append(&mut self, c: &SignalChunk, i0: usize, i1: usize, start: u64) {
        let mut i0 = i0;
        if self.edges.is_empty() {
            i0 = i0.max(i1.saturating_sub(2));
            let total = self.buf.len() + (i1 - i0);
            let d = total.saturating_sub(2).min(self.buf.len());
            self.buf.drain(..d);
            self.buf_start += d as u64;
        }
        if self.buf.is_empty() {
            self.buf_start = start + i0 as u64;
        }
        let o = self.offset.unwrap_or([0.0; 3]);
        // `c.force(i) − o` per sample, over slice iterators (no per-sample bounds checks and
        // F_z test)
        let xy = c.fx[i0..i1].iter().zip(&c.fy[i0..i1]);
        match c.fz {
            Some(fz) => self.buf.extend(
                xy.zip(&fz[i0..i1])
                    .map(|((x, y), z)| [x - o[0], y - o[1], z - o[2]]),
            ),
            None => self
                .buf
                .extend(xy.map(|(x, y)| [x - o[0], y - o[1], 0.0 - o[2]])),
        }
    }

    fn on_edge(&mut self, te: f64) {
        self.edges.push(te);
        if self.edges.len() == self.per_rev + 1 {
            self.revolution();
            self.edges.clear();
            self.edges.push(te);
        }
        if self.edges.len() > 1 {
            return; // inside a revolution (encoder): keep everything since its first edge
        }
        // a revolution starts here: keep the samples from just before it
        let keep = ((te * self.fs).floor() as u64)
            .saturating_sub(1)
            .max(self.buf_start);
        let drop = ((keep - self.buf_start) as usize).min(self.buf.len().saturating_sub(2));
        self.buf.drain(..drop);
        self.buf_start += drop as u64;
    }

    /// Resample the buffered revolution and accumulate it.
    fn revolution(&mut self) {
        let (m, n_e) = (self.m, self.per_rev);
        let buf = &self.buf[..];
        let last = buf.len() - 1;
        let (lastf, base) = (last as f64, self.buf_start as f64);
        let (sx, rest) = self.scratch.split_at_mut(m);
        let (sy, rest) = rest.split_at_mut(m);
        let (sz, sxy) = rest.split_at_mut(m);
        // bins j ∈ [⌈qM/N⌉, ⌈(q+1)M/N⌉) lie between edges q and q+1 (angle linear in time there)
        for q in 0..n_e {
            let (j0, j1) = ((q * m).div_ceil(n_e), ((q + 1) * m).div_ceil(n_e));
            let x0 = self.edges[q] * self.fs - base;
            let dx = (self.edges[q + 1] - self.edges[q]) * self.fs;
            let step = n_e as f64 / m as f64;
            let bins = sx[j0..j1]
                .iter_mut()
                .zip(&mut sy[j0..j1])
                .zip(&mut sz[j0..j1]);
            let qf = q as f64;
            for (j, ((vx, vy), vz)) in (j0..j1).zip(bins) {
                // j and the floor below converted as signed integers, the same values as
                // unsigned ones (both are far below 2⁵³), in one instruction each instead of
                // the four of an unsigned conversion (issue 18: with `append` over slice
                // iterators, pass 3 −12 %)
                let u = j as i64 as f64 * step - qf;
                let x = (x0 + u * dx).clamp(0.0, lastf);
                // 0 ≤ x ≤ last after the clamp (a NaN gives 0 either way): the signed
                // conversion is the same floor as `as usize`, in one instruction, and the
                // index needs no `min(last)` (issue 18: with slice iterators instead of
                // indexing, pass 3 −9 %)
                let floor = x as i64;
                let i = floor as usize;
                let w = x - floor as f64;
                let (a, b) = (buf[i], buf[(i + 1).min(last)]);
                let f0 = a[0] + w * (b[0] - a[0]);
                let f1 = a[1] + w * (b[1] - a[1]);
                *vx = f0;
                *vy = f1;
                *vz = a[2] + w * (b[2] - a[2]);
            }
        }
        ForceComponent::Fxy.of_each(sx, sy, None, sxy);
        self.acc.push(&self.scratch);
        let ci = self.component.index();
        let wave = &self.scratch[ci * m..(ci + 1) * m];
        if self.owner.is_none() {
            let b0 = self
                .absolute_start
                .unwrap_or_else(|| harmonic_boundary(wave, self.k, self.origin));
            self.owner = Some((b0, owners(m, self.k, self.origin, b0)));
        }
        if let Some((_, owner)) = &self.owner {
            for (i, p) in period_peaks(wave, owner, self.k).into_iter().enumerate() {
                self.teeth[i].push(p.1);
            }
        }
        self.revs += 1;
    }

    /// Finish pass 3.
    pub fn finish(self) -> Result<SyncAverage, SignalError> {
        if self.revs < 2 {
            return Err(SignalError::TooShort {
                what: "section (complete revolutions averaged)",
                seconds: self.revs as f64,
                revolutions: self.revs as f64,
                rpm: f64::NAN,
            });
        }
        let m = self.m;
        let components: Vec<ComponentAverage> = ForceComponent::ALL
            .iter()
            .map(|&c| {
                let bins = c.index() * m..(c.index() + 1) * m;
                ComponentAverage {
                    component: c,
                    mean: bins.clone().map(|i| self.acc.mean(i)).collect(),
                    sd: bins.clone().map(|i| self.acc.sd(i)).collect(),
                    se: bins.map(|i| self.acc.se(i)).collect(),
                }
            })
            .collect();
        let (b0, owner) = self.owner.clone().unwrap_or_default();
        let chosen = &components[self.component.index()];
        let tooth_peaks = period_peaks(&chosen.mean, &owner, self.k)
            .into_iter()
            .enumerate()
            .map(|(i, (jf, peak))| {
                let bin_se = if jf.is_finite() {
                    let j = jf.floor() as usize % m;
                    chosen.se[j].max(chosen.se[(j + 1) % m])
                } else {
                    f64::NAN
                };
                ToothPeakEstimate {
                    tooth: i,
                    period_start: wrap_tau(b0 + TAU * i as f64 / self.k as f64),
                    peak,
                    se: bin_se.max(self.teeth[i].se()),
                    angle: wrap_tau(self.origin + TAU * jf / m as f64),
                    per_rev_max_mean: self.teeth[i].mean(),
                    per_rev_max_sd: self.teeth[i].sd(),
                    per_rev_max_se: self.teeth[i].se(),
                }
            })
            .collect();
        Ok(SyncAverage {
            bins: m,
            angle_origin: self.origin,
            angle_reference: self.angle_reference,
            revolutions: self.revs,
            has_fz: self.has_fz,
            offset_subtracted: self.offset,
            components,
            peak_component: self.component,
            tooth_reference: if self.absolute_start.is_some() {
                ToothReference::Absolute
            } else {
                ToothReference::Arbitrary
            },
            tooth_peaks,
        })
    }
}

/// Time of revolution mark r: θ(t) = 2π·(t − t₀)/P + w(t − t₀) − w(0) = 2π·r, solved by
/// fixed-point iteration (w changes by ≪ 1 rad per revolution, so three steps are exact to
/// rounding).
fn mark_time(t_ref: f64, period: f64, r: u64, wander: &[(f64, f64)]) -> f64 {
    let mut t = t_ref + r as f64 * period;
    if wander.is_empty() {
        return t;
    }
    let w0 = super::tracker::wander_at(wander, 0.0);
    for _ in 0..3 {
        let w = super::tracker::wander_at(wander, t - t_ref) - w0;
        t = t_ref + (r as f64 - w / TAU) * period;
    }
    t
}

/// b₀ half a tooth period before the maximum of the K-th harmonic of `wave`, reduced to the
/// first boundary at or after `origin`.
fn harmonic_boundary(wave: &[f64], k: usize, origin: f64) -> f64 {
    let m = wave.len();
    let (re, im) = crate::fit::fourier_coefficient(
        wave.iter().copied(),
        (0..m).map(|j| k as f64 * TAU * j as f64 / m as f64),
    );
    // wave ≈ A·cos(K(θ−θ_origin) − ψ) with ψ = −arg X: maximum at θ_origin + ψ/K
    let psi = -im.atan2(re);
    let pitch = TAU / k as f64;
    let b = psi / k as f64 - PI / k as f64;
    origin + b.rem_euclid(pitch)
}

/// Which tooth owns each bin, floor(wrap(θ_j − b₀)/(2π/K)), as runs of consecutive bins in
/// ascending order (at most K + 1: the period that began before bin 0 owns both ends).
#[derive(Debug, Clone, Default)]
struct Owners(Vec<(std::ops::Range<usize>, usize)>);

fn owners(m: usize, k: usize, origin: f64, b0: f64) -> Owners {
    let mut runs: Vec<(std::ops::Range<usize>, usize)> = Vec::new();
    for j in 0..m {
        let th = origin + TAU * j as f64 / m as f64;
        let tooth = ((wrap_tau(th - b0) / (TAU / k as f64)) as usize).min(k - 1);
        match runs.last_mut() {
            Some((run, t)) if *t == tooth => run.end = j + 1,
            _ => runs.push((j..j + 1, tooth)),
        }
    }
    Owners(runs)
}

/// Per tooth: (refined bin position, refined maximum) of `wave` over the bins it owns: the
/// first bin of the largest value in ascending bin order, refined by a parabola through it and
/// its neighbours. Run by run with the running maximum held (issue 18: the bin-by-bin owner
/// lookup and re-read of the maximum were ≈ 11 % of pass 3).
fn period_peaks(wave: &[f64], owner: &Owners, k: usize) -> Vec<(f64, f64)> {
    let m = wave.len();
    let mut best: Vec<Option<(usize, f64)>> = vec![None; k];
    for (run, tooth) in &owner.0 {
        let mut bins = run.clone().zip(&wave[run.clone()]);
        let (mut at, mut top) = match best[*tooth] {
            Some(b) => b,
            None => match bins.next() {
                Some((j, &x)) => (j, x),
                None => continue,
            },
        };
        for (j, &x) in bins {
            if x > top {
                (at, top) = (j, x);
            }
        }
        best[*tooth] = Some((at, top));
    }
    best.into_iter()
        .map(|b| match b {
            None => (f64::NAN, f64::NAN),
            Some((j, _)) => {
                let (d, v) = parabolic_peak(wave[(j + m - 1) % m], wave[j], wave[(j + 1) % m]);
                ((j as f64 + d).rem_euclid(m as f64), v)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The bin-by-bin search that the run-by-run [`period_peaks`] replaced (issue 18).
    fn period_peaks_per_bin(wave: &[f64], owner: &[usize], k: usize) -> Vec<(f64, f64)> {
        let m = wave.len();
        let mut best: Vec<Option<usize>> = vec![None; k];
        for (j, (&x, &o)) in wave.iter().zip(owner).enumerate() {
            if best[o].is_none_or(|b| x > wave[b]) {
                best[o] = Some(j);
            }
        }
        best.into_iter()
            .map(|b| match b {
                None => (f64::NAN, f64::NAN),
                Some(j) => {
                    let (d, v) = parabolic_peak(wave[(j + m - 1) % m], wave[j], wave[(j + 1) % m]);
                    ((j as f64 + d).rem_euclid(m as f64), v)
                }
            })
            .collect()
    }

    proptest! {
        /// Same owners and the same peaks, bit for bit, as the per-bin search: any bin count,
        /// tooth count, origin and boundary, with ties (values on a coarse grid) and NaNs.
        #[test]
        fn run_by_run_peaks_equal_the_per_bin_search(
            m in 1usize..400,
            k in 1usize..9,
            origin in -7.0f64..7.0,
            b0 in -7.0f64..7.0,
            seed in any::<u64>(),
            nan_every in 0usize..50,
        ) {
            let mut state = seed | 1;
            let wave: Vec<f64> = (0..m)
                .map(|j| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    if nan_every > 0 && j % nan_every == nan_every - 1 {
                        f64::NAN
                    } else {
                        (state % 16) as f64 * 0.5 // few levels: many ties
                    }
                })
                .collect();
            let runs = owners(m, k, origin, b0);
            let per_bin: Vec<usize> = (0..m)
                .map(|j| {
                    let th = origin + TAU * j as f64 / m as f64;
                    ((wrap_tau(th - b0) / (TAU / k as f64)) as usize).min(k - 1)
                })
                .collect();
            let mut flat = vec![usize::MAX; m];
            let mut next = 0;
            for (run, t) in &runs.0 {
                prop_assert_eq!(run.start, next, "runs are consecutive and ascending");
                prop_assert!(run.end > run.start);
                flat[run.clone()].iter_mut().for_each(|o| *o = *t);
                next = run.end;
            }
            prop_assert_eq!(next, m);
            prop_assert_eq!(&flat, &per_bin);
            let new = period_peaks(&wave, &runs, k);
            let old = period_peaks_per_bin(&wave, &per_bin, k);
            for (a, b) in new.iter().zip(&old) {
                prop_assert_eq!(a.0.to_bits(), b.0.to_bits());
                prop_assert_eq!(a.1.to_bits(), b.1.to_bits());
            }
        }
    }

    #[test]
    fn boundary_sits_midway_between_pulses() {
        // three cosine pulses centred at 0.5, 0.5 + 2π/3, 0.5 + 4π/3
        let m = 360;
        let wave: Vec<f64> = (0..m)
            .map(|j| {
                let th = TAU * j as f64 / m as f64;
                (3.0 * (th - 0.5)).cos().max(0.0).powi(3)
            })
            .collect();
        let b0 = harmonic_boundary(&wave, 3, 0.0);
        assert!((b0 - (0.5 - PI / 3.0 + TAU / 3.0)).abs() < 1e-9, "{b0}");
        let own = owners(m, 3, 0.0, b0);
        let peaks = period_peaks(&wave, &own, 3);
        // the pulse at 0.5 rad belongs to the last period (it began before θ = 0)
        assert!((peaks[2].0 * TAU / m as f64 - 0.5).abs() < 0.01);
        assert!(peaks.iter().all(|p| (p.1 - 1.0).abs() < 1e-3));
    }
}
