//! Running statistics (Welford) used by the accumulators: O(1) memory per quantity.

/// Running mean and variance of a stream of numbers (Welford's algorithm).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunningStats {
    n: u64,
    mean: f64,
    m2: f64,
}

impl RunningStats {
    /// Add one value.
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }
    /// Number of values.
    pub fn count(&self) -> u64 {
        self.n
    }
    /// Mean (0 when empty).
    pub fn mean(&self) -> f64 {
        self.mean
    }
    /// Sample standard deviation (n − 1 in the denominator; 0 when n < 2).
    pub fn sd(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            (self.m2 / (self.n - 1) as f64).sqrt()
        }
    }
    /// Standard error of the mean, sd/√n (0 when n < 2).
    pub fn se(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            self.sd() / (self.n as f64).sqrt()
        }
    }
}

/// Running mean and variance of many quantities observed together (one value each per
/// update, e.g. the bins of a revolution), by shifted sums: the first values K are the shifts,
/// then Σ(x−K) and Σ(x−K)² (no division per value, unlike Welford, and vectorisable; with the
/// shift the cancellation in Σ(x−K)² − (Σ(x−K))²/n is that of the spread around K, not around 0).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct BinStats {
    n: u64,
    shift: Vec<f64>,
    s1: Vec<f64>,
    s2: Vec<f64>,
}

impl BinStats {
    /// Statistics of `len` quantities.
    pub fn new(len: usize) -> Self {
        BinStats {
            n: 0,
            shift: vec![0.0; len],
            s1: vec![0.0; len],
            s2: vec![0.0; len],
        }
    }
    /// Add one observation of every quantity (`x.len()` = len).
    pub fn push(&mut self, x: &[f64]) {
        if self.n == 0 {
            self.shift.copy_from_slice(x);
        }
        for (((s1, s2), &k), &v) in self.s1.iter_mut().zip(&mut self.s2).zip(&self.shift).zip(x) {
            let d = v - k;
            *s1 += d;
            *s2 += d * d;
        }
        self.n += 1;
    }
    /// Mean of quantity i.
    pub fn mean(&self, i: usize) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            self.shift[i] + self.s1[i] / self.n as f64
        }
    }
    /// Sample standard deviation of quantity i (0 when n < 2).
    pub fn sd(&self, i: usize) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        let n = self.n as f64;
        ((self.s2[i] - self.s1[i] * self.s1[i] / n).max(0.0) / (n - 1.0)).sqrt()
    }
    /// Standard error of the mean of quantity i, sd/√n.
    pub fn se(&self, i: usize) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            self.sd(i) / (self.n as f64).sqrt()
        }
    }
}

/// Median of a slice (NaN when empty); the slice is copied.
pub(crate) fn median(v: &[f64]) -> f64 {
    quantile(v, 0.5)
}

/// Linear-interpolated quantile `q ∈ [0, 1]` of a slice (NaN when empty).
pub(crate) fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let x = q.clamp(0.0, 1.0) * (s.len() - 1) as f64;
    let i = x.floor() as usize;
    let j = (i + 1).min(s.len() - 1);
    s[i] + (s[j] - s[i]) * (x - i as f64)
}

/// Vertex of the parabola through (−1, a), (0, b), (1, c): (offset in [−½, ½], value).
///
/// Used to refine a discrete maximum b between neighbours a and c; returns (0, b) when the three
/// points are not concave.
pub(crate) fn parabolic_peak(a: f64, b: f64, c: f64) -> (f64, f64) {
    let den = a - 2.0 * b + c;
    if den.partial_cmp(&0.0) != Some(std::cmp::Ordering::Less) {
        return (0.0, b);
    }
    let d = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
    (d, b - 0.25 * (a - c) * d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass() {
        let v = [1.0, 4.0, 2.5, -3.0, 7.25];
        let mut s = RunningStats::default();
        v.iter().for_each(|&x| s.push(x));
        let m = v.iter().sum::<f64>() / 5.0;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / 4.0;
        assert!((s.mean() - m).abs() < 1e-12);
        assert!((s.sd() - var.sqrt()).abs() < 1e-12);
        assert!((s.se() - (var / 5.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn bin_stats_match_welford_with_a_large_mean() {
        let v: Vec<f64> = (0..1000).map(|i| 1e6 + (i as f64 * 0.7).sin()).collect();
        let (mut a, mut b) = (RunningStats::default(), BinStats::new(2));
        v.iter().for_each(|&x| {
            a.push(x);
            b.push(&[x, 2.0 * x])
        });
        assert!((a.mean() - b.mean(0)).abs() < 1e-9 && (2.0 * a.mean() - b.mean(1)).abs() < 1e-9);
        assert!((a.sd() - b.sd(0)).abs() < 1e-9 * a.sd());
        assert!((a.se() - b.se(0)).abs() < 1e-9 * a.se());
    }

    #[test]
    fn parabola_vertex_exact_for_quadratic() {
        // y = 5 − (x − 0.3)² sampled at −1, 0, 1
        let f = |x: f64| 5.0 - (x - 0.3).powi(2);
        let (d, v) = parabolic_peak(f(-1.0), f(0.0), f(1.0));
        assert!((d - 0.3).abs() < 1e-12 && (v - 5.0).abs() < 1e-12);
        assert_eq!(parabolic_peak(1.0, 0.0, 1.0), (0.0, 0.0));
    }

    #[test]
    fn quantiles() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(quantile(&[0.0, 10.0], 0.25), 2.5);
        assert!(median(&[]).is_nan());
    }
}
