//! Per-tooth peak table: the maximum of |F_xy| within each tooth period.
//!
//! Tooth i's period is the part of each revolution from the moment its tip (z = 0) reaches the
//! entry angle φ_st until tooth i+1's tip does (`conventions.md`, "Signals": per-tooth peak).

use super::ForceSeries;
use crate::angle::wrap_tau;
use crate::cut::Cut;
use crate::cutter::Cutter;
use rayon::prelude::*;

/// Peak of one tooth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToothPeak {
    /// Tooth index (cutting order).
    pub tooth: usize,
    /// Largest |F_xy| (N) in the tooth's periods.
    pub peak_fxy: f64,
    /// Spindle angle θ (rad, wrapped to one turn) where it occurred.
    pub angle: f64,
    /// Immersion angle of the tooth's tip at the peak (rad).
    pub immersion: f64,
    /// Largest chip thickness of the tooth (mm), over all disks.
    pub max_chip: f64,
    /// Largest |F_xy| (N) of the tooth's own contribution.
    pub own_peak_fxy: f64,
}

/// Per-tooth peaks of |F_xy| in a simulated series.
pub fn tooth_peaks(series: &ForceSeries, cutter: &Cutter, cut: &Cut) -> Vec<ToothPeak> {
    let k = cutter.teeth();
    let (st, _) = cut.immersion(cutter);
    let blank: Vec<ToothPeak> = (0..k)
        .map(|i| ToothPeak {
            tooth: i,
            peak_fxy: f64::NEG_INFINITY,
            angle: f64::NAN,
            immersion: f64::NAN,
            max_chip: series.max_chip.get(i).copied().unwrap_or(0.0),
            own_peak_fxy: series.own_peak_fxy.get(i).copied().unwrap_or(0.0),
        })
        .collect();
    if k == 0 {
        return blank;
    }
    // tip angles ψ_i(0), hoisted out of the sample loop (issue 18: the loop was ~10 % of a
    // `runout simulate`); the same expressions per sample, so the same owner and peaks
    let tip: Vec<f64> = (0..k).map(|i| cutter.tooth_angle(i, 0.0)).collect();
    // Blocks of samples in parallel (issue 18), each scanned in order keeping the first sample
    // of its largest |F_xy| per tooth; merged in sample order keeping the earlier block's peak on
    // a tie: the first sample of the largest value over the series, as one sequential scan.
    let n = series.angle.len().min(series.fx.len()).min(series.fy.len());
    (0..n.div_ceil(PEAK_BLOCK))
        .into_par_iter()
        .map(|b| {
            let mut peaks = blank.clone();
            for q in b * PEAK_BLOCK..((b + 1) * PEAK_BLOCK).min(n) {
                let theta = series.angle[q];
                // the tooth whose tip entered most recently owns this sample (the first on a tie)
                let mut owner = 0;
                let mut best = wrap_tau(theta + tip[0] - st);
                for (i, &t) in tip.iter().enumerate().skip(1) {
                    let r = wrap_tau(theta + t - st);
                    if r.total_cmp(&best).is_lt() {
                        owner = i;
                        best = r;
                    }
                }
                let f = series.fx[q].hypot(series.fy[q]);
                let p = &mut peaks[owner];
                if f > p.peak_fxy {
                    p.peak_fxy = f;
                    p.angle = wrap_tau(theta);
                    p.immersion = wrap_tau(theta + tip[owner]);
                }
            }
            peaks
        })
        .reduce(
            || blank.clone(),
            |a, b| {
                a.into_iter()
                    .zip(b)
                    .map(|(a, b)| if b.peak_fxy > a.peak_fxy { b } else { a })
                    .collect()
            },
        )
}

/// Samples per parallel block of [`tooth_peaks`].
const PEAK_BLOCK: usize = 16384;
