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
    let arch = pulp::Arch::new();
    (0..n.div_ceil(PEAK_BLOCK))
        .into_par_iter()
        .map(|b| {
            arch.dispatch(Scan {
                series,
                tip: &tip,
                st,
                samples: b * PEAK_BLOCK..((b + 1) * PEAK_BLOCK).min(n),
                blank: &blank,
            })
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

/// One block of [`tooth_peaks`] as a [`pulp::WithSimd`] operation, so that the scan is compiled
/// with the detected instruction set (its `floor` in `wrap_tau` becomes one rounding
/// instruction instead of a call; the same values, floor is exact).
struct Scan<'a> {
    series: &'a ForceSeries,
    tip: &'a [f64],
    st: f64,
    samples: std::ops::Range<usize>,
    blank: &'a [ToothPeak],
}

impl pulp::WithSimd for Scan<'_> {
    type Output = Vec<ToothPeak>;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> Vec<ToothPeak> {
        let Scan {
            series,
            tip,
            st,
            samples,
            blank,
        } = self;
        let mut peaks = blank.to_vec();
        // a sample below every tooth's peak cannot raise any: skipped before its owner and
        // hypot are computed ([`hypot_below`]); the others are taken exactly as before
        let mut low = f64::NEG_INFINITY;
        for q in samples {
            let (x, y) = (series.fx[q], series.fy[q]);
            if hypot_below(x, y, low) {
                continue;
            }
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
            let f = x.hypot(y);
            let p = &mut peaks[owner];
            if f > p.peak_fxy {
                p.peak_fxy = f;
                p.angle = wrap_tau(theta);
                p.immersion = wrap_tau(theta + tip[owner]);
                low = peaks
                    .iter()
                    .map(|p| hypot_floor(p.peak_fxy))
                    .fold(f64::INFINITY, f64::min);
            }
        }
        peaks
    }
}

/// Samples per parallel block of [`tooth_peaks`].
const PEAK_BLOCK: usize = 16384;

/// A threshold on x² + y² below which `x.hypot(y) < m` for sure (so that a running maximum of
/// hypot can skip the call; issue 18, hypot was ~5 % of a `runout simulate`): m²·(1 − 10⁻¹⁴),
/// or −∞ (no skipping) when m is not a normal positive value with a normal square.
///
/// Why it is safe: hypot is within 1 ulp of t = √(x² + y²), and the computed x·x + y·y is within
/// 2 ulp of t² (no overflow or underflow when it is ≥ m² > 10⁻³⁰⁰). So hypot(x, y) ≥ m implies
/// x·x + y·y ≥ m²(1 − 2⁻⁵²)²(1 − 2⁻⁵¹) > m²(1 − 10⁻¹⁴) (a margin 20× the rounding). A square
/// that overflows is +∞ and is never below the threshold; NaN compares false (never skipped).
#[inline]
pub(crate) fn hypot_floor(m: f64) -> f64 {
    if m > 1e-150 && m < 1e150 {
        m * m * (1.0 - 1e-14)
    } else {
        f64::NEG_INFINITY
    }
}

/// True when `x.hypot(y)` is certainly below the m of `floor` = [`hypot_floor`]`(m)`.
#[inline]
pub(crate) fn hypot_below(x: f64, y: f64, floor: f64) -> bool {
    x * x + y * y < floor
}

/// `x.iter().zip(y).fold(0.0, |p, (x, y)| p.max(x.hypot(*y)))` (the same value: max takes
/// no rounding and the skipped samples are below it, [`hypot_floor`]), with hypot called only
/// on samples that can raise the running maximum.
pub(crate) fn max_hypot(x: &[f64], y: &[f64]) -> f64 {
    let mut m = 0.0f64;
    let mut floor = f64::NEG_INFINITY;
    for (a, b) in x.iter().zip(y) {
        // hypot(±0, ±0) = +0 cannot raise m ≥ +0 either
        if hypot_below(*a, *b, floor) || (*a == 0.0 && *b == 0.0) {
            continue;
        }
        let h = a.hypot(*b);
        if h > m {
            m = h;
            floor = hypot_floor(m);
        } else {
            m = m.max(h);
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Cut, MillingMode};

    /// A small deterministic generator (no extra dependency): uniform in [0, 1).
    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Values that stress the skip: exact ties, neighbours 1 ulp apart, zeros, signed zeros,
    /// NaN, ±∞, subnormal and huge magnitudes, plus smooth force-like data.
    fn series(n: usize, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let mut s = seed;
        let special = [
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            5e-324,
            1e-160,
            1e160,
            f64::MAX,
            300.0,
            300.0f64.next_up(),
            300.0f64.next_down(),
        ];
        let pick = |s: &mut u64| {
            let r = lcg(s);
            if r < 0.05 {
                special[(lcg(s) * special.len() as f64) as usize]
            } else if r < 0.3 {
                0.0
            } else {
                (lcg(s) - 0.5) * 600.0
            }
        };
        let x = (0..n).map(|_| pick(&mut s)).collect();
        let y = (0..n).map(|_| pick(&mut s)).collect();
        (x, y)
    }

    #[test]
    fn max_hypot_is_the_fold_of_hypot_bit_for_bit() {
        for seed in 0..200u64 {
            let (x, y) = series(500, seed);
            // without the special values too (so that the skip is exercised on finite data)
            let finite: Vec<(f64, f64)> = x
                .iter()
                .zip(&y)
                .map(|(a, b)| (*a, *b))
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .collect();
            let (fx, fy): (Vec<f64>, Vec<f64>) = finite.into_iter().unzip();
            for (x, y) in [(&x, &y), (&fx, &fy)] {
                let want = x
                    .iter()
                    .zip(y.iter())
                    .fold(0.0f64, |p, (a, b)| p.max(a.hypot(*b)));
                let got = max_hypot(x, y);
                assert_eq!(got.to_bits(), want.to_bits(), "seed {seed}");
            }
        }
    }

    /// The sequential scan `tooth_peaks` was before it ran in blocks (issue 18).
    fn sequential(series: &ForceSeries, cutter: &Cutter, cut: &Cut) -> Vec<ToothPeak> {
        let k = cutter.teeth();
        let (st, _) = cut.immersion(cutter);
        let mut peaks: Vec<ToothPeak> = (0..k)
            .map(|i| ToothPeak {
                tooth: i,
                peak_fxy: f64::NEG_INFINITY,
                angle: f64::NAN,
                immersion: f64::NAN,
                max_chip: series.max_chip.get(i).copied().unwrap_or(0.0),
                own_peak_fxy: series.own_peak_fxy.get(i).copied().unwrap_or(0.0),
            })
            .collect();
        for (q, &theta) in series.angle.iter().enumerate() {
            let mut owner = 0;
            let mut best = wrap_tau(theta + cutter.tooth_angle(0, 0.0) - st);
            for i in 1..k {
                let r = wrap_tau(theta + cutter.tooth_angle(i, 0.0) - st);
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
                p.immersion = wrap_tau(theta + cutter.tooth_angle(owner, 0.0));
            }
        }
        peaks
    }

    #[test]
    fn blocked_tooth_peaks_equal_the_sequential_scan() {
        let cutter = Cutter::flat(10.0, 3, 0.5).unwrap();
        let cut = Cut::new(3000.0, 0.05, 1.0)
            .unwrap()
            .radial(2.0, MillingMode::Down, &cutter)
            .unwrap();
        // several blocks, with repeated values (ties across blocks: the first must win)
        for (seed, n) in [(1u64, 3 * PEAK_BLOCK + 17), (2, 100), (3, 2 * PEAK_BLOCK)] {
            let (mut fx, mut fy) = series(n, seed);
            for q in (0..n).step_by(997) {
                fx[q] = 299.0;
                fy[q] = 17.0;
            }
            let step = 0.01;
            let s = ForceSeries {
                angle: (0..n).map(|q| step * q as f64).collect(),
                fx,
                fy,
                max_chip: vec![0.1; 3],
                own_peak_fxy: vec![1.0; 3],
                ..Default::default()
            };
            let (a, b) = (
                tooth_peaks(&s, &cutter, &cut),
                sequential(&s, &cutter, &cut),
            );
            assert_eq!(a.len(), b.len());
            for (a, b) in a.iter().zip(&b) {
                assert_eq!(a.peak_fxy.to_bits(), b.peak_fxy.to_bits(), "seed {seed}");
                assert_eq!(a.angle.to_bits(), b.angle.to_bits(), "seed {seed}");
                assert_eq!(a.immersion.to_bits(), b.immersion.to_bits(), "seed {seed}");
            }
        }
    }
}
