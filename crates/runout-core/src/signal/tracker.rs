//! Pass 2 over the section: the spindle speed and its standard error.
//!
//! **Without a pulse channel** (phase tracking): the section is cut into blocks of one coarse
//! revolution, 1/f̂ with f̂ = (tooth-passing line)/K from pass 1. In block b the chosen component x
//! is demodulated at the coarse tooth-passing frequency f̂_tp = K·f̂, referenced to the section
//! start t₀:  X_b = Σ_n x_n·exp(−i·2π·f̂_tp·(t_n − t₀)). A rectangular window of exactly one
//! revolution makes every other spindle harmonic (the runout side-bands at f̂_tp ± f̂, …)
//! orthogonal. If x carries A·cos(2π·f_tp·(t − t₀) + ϕ₀), then arg X_b = ϕ₀ + 2π·(f_tp − f̂_tp)·t̄_b,
//! so the (unwrapped) block phases regressed on the block mid-times give f_tp − f̂_tp as the
//! slope/2π, with the ordinary least-squares standard error s/√Σ(t̄_b − t̄)² (s² = residual
//! sum of squares/(B − 2)). Spindle frequency f = f_tp/K, se(f) = se(f_tp)/K. Unwrapping is
//! unambiguous while |f_tp − f̂_tp| < f̂/2 (the coarse estimate is good to a fraction of a
//! spectral bin, far better). With fewer than 3 blocks the coarse estimate is returned with
//! se = resolution/(K·√12).
//!
//! A real spindle's speed wanders (regulation, load): over minutes a constant-speed angle would
//! drift by many degrees. The block phases are therefore also kept as knots (≤ [`MAX_KNOTS`],
//! averaged in groups when more), and their deviation from the straight line, divided by K, is
//! the spindle-angle wander w(t) that the synchronous average follows.
//!
//! **With a pulse channel**: rising edges in the section, edge time regressed on edge number
//! (slope = period per edge, f = 1/(N·slope), se by the delta method); the revolution-to-
//! revolution period scatter is reported as the speed variation.
//!
//! Memory: O(1) (regression sums; for an encoder the last N edge times).

use super::chunk::ChunkGuard;
use super::pulse::PulseEdgeDetector;
use super::scan::ScanResult;
use super::stats::RunningStats;
use super::{ForceComponent, SignalChunk, SignalConfig, SignalError};
use serde::Serialize;
use std::collections::VecDeque;
use std::f64::consts::TAU;

/// How the spindle speed was measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpeedMethod {
    /// Pulse / encoder edge timing.
    Pulse,
    /// Spectral line refined by phase tracking of the tooth-passing harmonic.
    PhaseTracking,
    /// Spectral line only (too few revolutions to track the phase).
    Spectrum,
}

/// Measured spindle speed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpindleSpeed {
    /// How it was measured.
    pub method: SpeedMethod,
    /// Spindle speed (rpm).
    pub rpm: f64,
    /// Standard error of `rpm` (rpm).
    pub rpm_se: f64,
    /// Nominal speed (rpm) as stated.
    pub nominal_rpm: f64,
    /// (rpm − nominal)/nominal.
    pub deviation: f64,
    /// Coarse speed from the spectral line (rpm).
    pub coarse_rpm: f64,
    /// Regression points (blocks or edges).
    pub points: usize,
    /// Residual RMS of the regression, in `residual_unit`.
    pub residual_rms: f64,
    /// Unit of `residual_rms`: "rad" (phase tracking) or "s" (pulse edge times).
    pub residual_unit: &'static str,
    /// Revolution-to-revolution relative scatter of the period (pulse method only).
    pub speed_variation: Option<f64>,
    /// Phase tracking: spindle-angle wander w(t) = (φ(t) − φ_lin(t))/K (rad) at knots t (s from the
    /// section start), φ the tracked tooth-passing phase and φ_lin its straight-line fit; the
    /// synchronous average follows θ(t) = 2π·f·(t − t₀) + w(t) − w(0). At most
    /// [`MAX_KNOTS`] knots. Empty for the pulse and spectrum methods.
    #[serde(skip)]
    pub angle_wander: Vec<(f64, f64)>,
    /// Largest |w| (rad): how far the spindle angle strays from constant speed.
    #[serde(rename = "angle_wander_max_rad")]
    pub angle_wander_max: f64,
}

impl SpindleSpeed {
    /// Spindle frequency (Hz).
    pub fn hz(&self) -> f64 {
        self.rpm / 60.0
    }
    /// Warning text when the speed differs from nominal by more than 2 %.
    pub fn warning(&self) -> Option<String> {
        (self.deviation.abs() > 0.02).then(|| {
            format!(
                "measured spindle speed {:.1} ± {:.1} rpm differs from the nominal {:.1} rpm by {:+.2} % (more than 2 %)",
                self.rpm,
                self.rpm_se,
                self.nominal_rpm,
                100.0 * self.deviation
            )
        })
    }
}

/// Straight-line regression sums y = a + b·x.
#[derive(Debug, Clone, Copy, Default)]
struct LineFit {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    sxy: f64,
    syy: f64,
}

impl LineFit {
    fn push(&mut self, x: f64, y: f64) {
        self.n += 1.0;
        self.sx += x;
        self.sy += y;
        self.sxx += x * x;
        self.sxy += x * y;
        self.syy += y * y;
    }
    /// Value of the fitted line at x.
    fn at(&self, x: f64) -> f64 {
        let n = self.n;
        let b = (self.sxy - self.sx * self.sy / n) / (self.sxx - self.sx * self.sx / n);
        (self.sy - b * self.sx) / n + b * x
    }
    /// (slope, se of slope, residual rms); needs n ≥ 3.
    fn solve(&self) -> (f64, f64, f64) {
        let n = self.n;
        let dxx = self.sxx - self.sx * self.sx / n;
        let dxy = self.sxy - self.sx * self.sy / n;
        let dyy = self.syy - self.sy * self.sy / n;
        let b = dxy / dxx;
        let ssr = (dyy - b * dxy).max(0.0);
        let s2 = ssr / (n - 2.0);
        (b, (s2 / dxx).sqrt(), (ssr / n).sqrt())
    }
}

enum Mode {
    Phase {
        f_tp: f64,
        /// Coarse revolutions per second (block index = ⌊(t − t₀)·f̂⌋).
        rev_s: f64,
        blocks: u64,
        block: Option<u64>,
        acc: (f64, f64),
        rot: (f64, f64),
        ph: (f64, f64),
        tsum: f64,
        count: u64,
        last_phase: Option<f64>,
        fit: LineFit,
        knots: Knots,
    },
    Pulse {
        det: PulseEdgeDetector,
        per_rev: usize,
        edges: u64,
        recent: VecDeque<f64>,
        periods: RunningStats,
        fit: LineFit,
        t_first: Option<f64>,
    },
}

/// Pass-2 accumulator: feed every chunk of the recording again, then [`PhaseTracker::finish`].
pub struct PhaseTracker {
    cfg: SignalConfig,
    guard: ChunkGuard,
    from: f64,
    to: f64,
    coarse_hz: f64,
    resolution_hz: f64,
    component: ForceComponent,
    mode: Mode,
    /// The component of each sample of the chunk being fed.
    values: Vec<f64>,
}

impl PhaseTracker {
    /// Start pass 2 with the result of pass 1.
    pub fn new(cfg: &SignalConfig, scan: &ScanResult) -> Result<Self, SignalError> {
        cfg.validate()?;
        let (from, to) = (scan.section.from_s, scan.section.to_s);
        let coarse = scan.coarse_spindle_hz;
        let mode = match (cfg.pulse, scan.pulse_thresholds) {
            (Some(p), Some((lo, hi))) => Mode::Pulse {
                det: PulseEdgeDetector::new(lo, hi),
                per_rev: p.pulses_per_rev,
                edges: 0,
                recent: VecDeque::with_capacity(p.pulses_per_rev + 1),
                periods: RunningStats::default(),
                fit: LineFit::default(),
                t_first: None,
            },
            _ => {
                let f_tp = coarse * cfg.teeth as f64;
                let dt = 1.0 / cfg.sample_rate_hz;
                Mode::Phase {
                    f_tp,
                    rev_s: coarse,
                    blocks: ((to - from) * coarse).floor().max(0.0) as u64,
                    block: None,
                    acc: (0.0, 0.0),
                    rot: ((TAU * f_tp * dt).cos(), -(TAU * f_tp * dt).sin()),
                    ph: (1.0, 0.0),
                    tsum: 0.0,
                    count: 0,
                    last_phase: None,
                    fit: LineFit::default(),
                    knots: Knots::default(),
                }
            }
        };
        Ok(PhaseTracker {
            cfg: cfg.clone(),
            guard: ChunkGuard::default(),
            from,
            to,
            coarse_hz: coarse,
            resolution_hz: scan.tooth_passing.resolution_hz,
            component: cfg.peak_component,
            mode,
            values: Vec::new(),
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
        let fs = self.cfg.sample_rate_hz;
        self.guard.check(&c, fs, self.cfg.pulse.is_some())?;
        let (from, to) = (self.from, self.to);
        match &mut self.mode {
            Mode::Phase {
                f_tp,
                rev_s,
                blocks,
                block,
                acc,
                rot,
                ph,
                tsum,
                count,
                last_phase,
                fit,
                knots,
            } => {
                let dt = 1.0 / fs;
                let values = &mut self.values;
                values.resize(c.len(), 0.0);
                self.component.of_each(c.fx, c.fy, c.fz, values);
                let rel_of = |i: usize| (start + i as u64) as f64 * dt - from;
                let block_of = |rel: f64| (rel * *rev_s).floor() as u64;
                let n = c.len();
                let mut i = 0;
                while i < n {
                    let rel = rel_of(i);
                    if rel < 0.0 {
                        i += 1;
                        continue;
                    }
                    let b = block_of(rel);
                    if b >= *blocks {
                        break;
                    }
                    if *block != Some(b) {
                        close_block(*acc, *tsum, *count, last_phase, fit, knots);
                        *block = Some(b);
                        *acc = (0.0, 0.0);
                        *tsum = 0.0;
                        *count = 0;
                        let a = -TAU * (*f_tp * rel).fract();
                        *ph = (a.cos(), a.sin());
                    }
                    // the samples of this chunk in block b: the block index is non-decreasing
                    // in the sample (each step of rel_of and block_of is monotone, rounding
                    // included), so its end is found by bisection on the same expressions and
                    // the samples up to it skip the per-sample block test (issue 18: the
                    // pass's loop ≈ 2× faster, the same operations on each sample)
                    let (mut lo, mut hi) = (i + 1, n);
                    while lo < hi {
                        let mid = lo + (hi - lo) / 2;
                        if block_of(rel_of(mid)) == b {
                            lo = mid + 1;
                        } else {
                            hi = mid;
                        }
                    }
                    for (j, &x) in values.iter().enumerate().take(lo).skip(i) {
                        let rel = rel_of(j);
                        acc.0 += x * ph.0;
                        acc.1 += x * ph.1;
                        *tsum += rel;
                        *count += 1;
                        *ph = (ph.0 * rot.0 - ph.1 * rot.1, ph.0 * rot.1 + ph.1 * rot.0);
                    }
                    i = lo;
                }
            }
            Mode::Pulse {
                det,
                per_rev,
                edges,
                recent,
                periods,
                fit,
                t_first,
            } => {
                let p = c.pulse.unwrap_or(&[]);
                for (i, &v) in p.iter().enumerate() {
                    let t = (start + i as u64) as f64 / fs;
                    let Some(te) = det.push(t, v) else { continue };
                    if te < from || te > to {
                        continue;
                    }
                    let t0 = *t_first.get_or_insert(te);
                    fit.push(*edges as f64, te - t0);
                    *edges += 1;
                    recent.push_back(te);
                    if recent.len() > *per_rev {
                        let old = recent.pop_front().unwrap_or(te);
                        periods.push(te - old);
                    }
                }
            }
        }
        Ok(())
    }

    /// Finish pass 2.
    pub fn finish(mut self) -> Result<SpindleSpeed, SignalError> {
        let k = self.cfg.teeth as f64;
        let nominal = self.cfg.nominal_rpm;
        let coarse_rpm = 60.0 * self.coarse_hz;
        let mut wander = Vec::new();
        let (method, hz, se, points, rms, var) = match &mut self.mode {
            Mode::Phase {
                f_tp,
                acc,
                tsum,
                count,
                last_phase,
                fit,
                knots,
                ..
            } => {
                close_block(*acc, *tsum, *count, last_phase, fit, knots);
                let k_points = knots.finish();
                if fit.n >= 3.0 {
                    let (slope, se, rms) = fit.solve();
                    wander = k_points
                        .iter()
                        .map(|&(t, phi)| (t, (phi - fit.at(t)) / k))
                        .collect();
                    let f = (*f_tp + slope / TAU) / k;
                    (
                        SpeedMethod::PhaseTracking,
                        f,
                        se / TAU / k,
                        fit.n as usize,
                        rms,
                        None,
                    )
                } else {
                    let se = self.resolution_hz / (k * 12f64.sqrt());
                    (
                        SpeedMethod::Spectrum,
                        self.coarse_hz,
                        se,
                        fit.n as usize,
                        f64::NAN,
                        None,
                    )
                }
            }
            Mode::Pulse {
                per_rev,
                edges,
                periods,
                fit,
                ..
            } => {
                let need = 2 * *per_rev as u64 + 1;
                if *edges < need.max(3) {
                    return Err(SignalError::Pulse {
                        reason: format!(
                            "{} rising edge(s) in the section {:.6}–{:.6} s; at least {} needed (two revolutions at {} pulse(s)/rev)",
                            edges,
                            self.from,
                            self.to,
                            need.max(3),
                            per_rev
                        ),
                    });
                }
                let (slope, se_slope, rms) = fit.solve();
                let f = 1.0 / (*per_rev as f64 * slope);
                let variation = periods.sd() / periods.mean();
                (
                    SpeedMethod::Pulse,
                    f,
                    f * se_slope / slope,
                    *edges as usize,
                    rms,
                    Some(variation),
                )
            }
        };
        if !(hz.is_finite() && hz > 0.0) {
            return Err(SignalError::NoCut {
                reason: format!(
                    "the spindle speed could not be measured in the section (got {hz} Hz)"
                ),
            });
        }
        let rpm = 60.0 * hz;
        Ok(SpindleSpeed {
            method,
            rpm,
            rpm_se: 60.0 * se,
            nominal_rpm: nominal,
            deviation: rpm / nominal - 1.0,
            coarse_rpm,
            points,
            residual_rms: rms,
            residual_unit: if method == SpeedMethod::Pulse {
                "s"
            } else {
                "rad"
            },
            speed_variation: var,
            angle_wander_max: wander.iter().map(|w| w.1.abs()).fold(0.0, f64::max),
            angle_wander: wander,
        })
    }
}

/// Close a phase-tracking block: unwrap its phase against the previous one and add the point.
fn close_block(
    acc: (f64, f64),
    tsum: f64,
    count: u64,
    last: &mut Option<f64>,
    fit: &mut LineFit,
    knots: &mut Knots,
) {
    if count == 0 || (acc.0 == 0.0 && acc.1 == 0.0) {
        return;
    }
    let raw = acc.1.atan2(acc.0);
    let phase = match *last {
        None => raw,
        Some(p) => p + crate::angle::wrap_pi(raw - p),
    };
    *last = Some(phase);
    let t = tsum / count as f64;
    fit.push(t, phase);
    knots.push(t, phase);
}

/// Largest number of phase knots kept.
pub const MAX_KNOTS: usize = 4096;

/// The unwrapped block phases (t, φ), averaged in groups so that at most [`MAX_KNOTS`] are kept:
/// when full, neighbours are merged in pairs and the group size doubles (bounded memory; the
/// phase curve is then known at a coarser time resolution).
#[derive(Debug, Clone, Default)]
struct Knots {
    group: usize,
    pending: (f64, f64, usize),
    points: Vec<(f64, f64)>,
}

impl Knots {
    fn push(&mut self, t: f64, phi: f64) {
        self.group = self.group.max(1);
        let p = &mut self.pending;
        p.0 += t;
        p.1 += phi;
        p.2 += 1;
        if p.2 == self.group {
            self.points.push((p.0 / p.2 as f64, p.1 / p.2 as f64));
            self.pending = (0.0, 0.0, 0);
            if self.points.len() == MAX_KNOTS {
                self.points = self
                    .points
                    .chunks(2)
                    .map(|c| (0.5 * (c[0].0 + c[1].0), 0.5 * (c[0].1 + c[1].1)))
                    .collect();
                self.group *= 2;
            }
        }
    }
    fn finish(&mut self) -> Vec<(f64, f64)> {
        let p = self.pending;
        if p.2 > 0 {
            self.points.push((p.0 / p.2 as f64, p.1 / p.2 as f64));
            self.pending = (0.0, 0.0, 0);
        }
        std::mem::take(&mut self.points)
    }
}

/// Spindle-angle wander w(t) (rad) at time `t` (s from the section start): linear interpolation
/// of the knots, extrapolated along the first/last segment beyond the ends (knots sit at block
/// centres, half a block inside the section); 0 without knots, constant with one.
pub(crate) fn wander_at(knots: &[(f64, f64)], t: f64) -> f64 {
    match knots.len() {
        0 => 0.0,
        1 => knots[0].1,
        n => {
            let i = knots.partition_point(|k| k.0 <= t).clamp(1, n - 1);
            let (a, b) = (knots[i - 1], knots[i]);
            a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
        }
    }
}
