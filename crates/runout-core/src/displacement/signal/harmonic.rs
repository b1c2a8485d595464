//! First harmonic of each channel by linear least squares on (1, cos φ, sin φ), methods.md §1.6:
//! one pass over the samples accumulates the normal equations (no global search).

use super::track::SpindleTrack;
use nalgebra::{Matrix2, Matrix3, Vector3};

/// Linear least-squares fit x_i ≈ c + a·cos φ_i + b·sin φ_i of one channel.
#[derive(Debug, Clone, Copy)]
pub(crate) struct HarmonicFit {
    /// (c, a, b).
    pub beta: Vector3<f64>,
    /// Covariance of (a, b) (units²).
    pub cov_ab: Matrix2<f64>,
    /// Residual standard deviation.
    pub sigma: f64,
}

/// Fit every channel in `channels` (same length, indexed like the track) on the track's angles.
pub(crate) fn fit_harmonics(track: &SpindleTrack, channels: &[&[f64]]) -> Option<Vec<HarmonicFit>> {
    let m = channels.len();
    // Gram sums: n, Σc, Σs, Σcc, Σcs, Σss; per channel: Σx, Σxc, Σxs, Σxx (about a shift for precision)
    let shift: Vec<f64> = channels
        .iter()
        .map(|x| x.first().copied().unwrap_or(0.0))
        .collect();
    let mut g = [0.0f64; 6];
    let mut acc = vec![[0.0f64; 4]; m];
    track.for_each(|i, c, s| {
        g[0] += 1.0;
        g[1] += c;
        g[2] += s;
        g[3] += c * c;
        g[4] += c * s;
        g[5] += s * s;
        for (k, x) in channels.iter().enumerate() {
            let v = x[i] - shift[k];
            let a = &mut acc[k];
            a[0] += v;
            a[1] += v * c;
            a[2] += v * s;
            a[3] += v * v;
        }
    });
    let gram = Matrix3::new(g[0], g[1], g[2], g[1], g[3], g[4], g[2], g[4], g[5]);
    let inv = gram.try_inverse()?;
    let n = g[0];
    Some(
        acc.iter()
            .zip(&shift)
            .map(|(a, sh)| {
                let rhs = Vector3::new(a[0], a[1], a[2]);
                let mut beta = inv * rhs;
                let rss = (a[3] - beta.dot(&rhs)).max(0.0);
                // floor at 1e-12 of the signal's rms so that noise-free data still weight the
                // channels (equally) instead of dividing by a zero variance
                let floor = 1e-24 * (a[3] / n).max(f64::MIN_POSITIVE);
                let s2 = (rss / (n - 3.0).max(1.0)).max(floor);
                beta[0] += sh;
                HarmonicFit {
                    beta,
                    cov_ab: Matrix2::new(inv[(1, 1)], inv[(1, 2)], inv[(2, 1)], inv[(2, 2)]) * s2,
                    sigma: s2.sqrt(),
                }
            })
            .collect(),
    )
}
