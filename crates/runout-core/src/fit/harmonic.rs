//! First-harmonic / Fourier-series least squares.
//!
//! On a full period of uniformly spaced angles the least-squares fit of x ≈ c + a cos(kθ) +
//! b sin(kθ) is the Fourier coefficient X_k = Σ x_q e^{−jkθ_q} = (n/2)(a − jb)
//! ([`fourier_coefficient`], [`fourier_coefficient_uniform`]); on arbitrary angles (a streaming
//! record that does not span whole revolutions) the normal equations of (1, cos φ, sin φ) are
//! accumulated in one pass and solved ([`HarmonicSums`], methods.md §1.6).

use nalgebra::{Matrix2, Matrix3, Vector3};

/// X = Σ v_q e^{−jθ_q} as (re, im) = (Σ v cos θ, −Σ v sin θ), summed in order.
///
/// The caller gives the angles (e.g. k·2π·q/n for the k-th harmonic of a revolution of n bins),
/// so every call site keeps its own angle formula.
///
/// ```
/// use runout_core::fit::fourier_coefficient;
/// use std::f64::consts::TAU;
/// let n = 36;
/// let angles: Vec<f64> = (0..n).map(|q| TAU * q as f64 / n as f64).collect();
/// let x: Vec<f64> = angles.iter().map(|t| 2.0 * (t - 0.5).cos()).collect();
/// let (re, im) = fourier_coefficient(x.iter().copied(), angles.iter().copied());
/// // X₁ = (n/2)·A·e^{−jϕ}: amplitude 2, phase 0.5
/// assert!((re.hypot(im) / (n as f64 / 2.0) - 2.0).abs() < 1e-12);
/// assert!((-im.atan2(re) - 0.5).abs() < 1e-12);
/// ```
pub fn fourier_coefficient(
    values: impl IntoIterator<Item = f64>,
    angles: impl IntoIterator<Item = f64>,
) -> (f64, f64) {
    values
        .into_iter()
        .zip(angles)
        .fold((0.0, 0.0), |(re, im), (v, t)| {
            (re + v * t.cos(), im - v * t.sin())
        })
}

/// [`fourier_coefficient`] of x − x̄ at the uniformly spaced angles φ_i = step·(offset + i), the
/// cosine and sine advanced by a rotation recurrence (restarted from libm every 1024 samples, so
/// the rounding drift stays below ~1e-13) — for long streaming records.
pub fn fourier_coefficient_uniform(x: &[f64], offset: usize, step: f64) -> (f64, f64) {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let (ss, cs) = step.sin_cos();
    let (mut acc_c, mut acc_s) = (0.0, 0.0);
    let mut i = 0;
    while i < x.len() {
        let end = (i + 1024).min(x.len());
        let (mut s, mut c) = (step * (offset + i) as f64).sin_cos();
        for v in &x[i..end] {
            let d = v - mean;
            acc_c += d * c;
            acc_s += d * s;
            let c2 = c * cs - s * ss;
            s = s * cs + c * ss;
            c = c2;
        }
        i = end;
    }
    (acc_c, -acc_s)
}

/// Linear least-squares fit x_i ≈ c + a·cos φ_i + b·sin φ_i of one channel.
#[derive(Debug, Clone, Copy)]
pub struct HarmonicFit {
    /// (c, a, b).
    pub beta: Vector3<f64>,
    /// Covariance of (a, b) (units²).
    pub cov_ab: Matrix2<f64>,
    /// Residual standard deviation.
    pub sigma: f64,
}

/// One-pass normal equations of x ≈ c + a cos φ + b sin φ for several channels sampled at the
/// same angles (methods.md §1.6): Gram sums n, Σc, Σs, Σc², Σcs, Σs²; per channel Σx, Σx·c,
/// Σx·s, Σx², each channel shifted by its first sample for precision.
#[derive(Debug, Clone)]
pub struct HarmonicSums {
    g: [f64; 6],
    shift: Vec<f64>,
    acc: Vec<[f64; 4]>,
}

impl HarmonicSums {
    /// Sums for channels whose values are taken about `shift` (one per channel).
    pub fn new(shift: Vec<f64>) -> Self {
        let acc = vec![[0.0; 4]; shift.len()];
        Self {
            g: [0.0; 6],
            shift,
            acc,
        }
    }
    /// Add one sample at angle φ given as (cos φ, sin φ), with the channels' values.
    pub fn push(&mut self, c: f64, s: f64, values: impl IntoIterator<Item = f64>) {
        let g = &mut self.g;
        g[0] += 1.0;
        g[1] += c;
        g[2] += s;
        g[3] += c * c;
        g[4] += c * s;
        g[5] += s * s;
        for ((x, a), sh) in values.into_iter().zip(&mut self.acc).zip(&self.shift) {
            let v = x - sh;
            a[0] += v;
            a[1] += v * c;
            a[2] += v * s;
            a[3] += v * v;
        }
    }
    /// Solve the normal equations of every channel; `None` when the angles do not determine
    /// (c, a, b) (singular Gram matrix). The residual variance RSS/(n − 3) is floored at 1e-24 of
    /// the mean square so that noise-free data still weight the channels (equally).
    pub fn solve(&self) -> Option<Vec<HarmonicFit>> {
        let g = &self.g;
        let gram = Matrix3::new(g[0], g[1], g[2], g[1], g[3], g[4], g[2], g[4], g[5]);
        let inv = gram.try_inverse()?;
        let n = g[0];
        Some(
            self.acc
                .iter()
                .zip(&self.shift)
                .map(|(a, sh)| {
                    let rhs = Vector3::new(a[0], a[1], a[2]);
                    let mut beta = inv * rhs;
                    let rss = (a[3] - beta.dot(&rhs)).max(0.0);
                    let floor = 1e-24 * (a[3] / n).max(f64::MIN_POSITIVE);
                    let s2 = (rss / (n - 3.0).max(1.0)).max(floor);
                    beta[0] += sh;
                    HarmonicFit {
                        beta,
                        cov_ab: Matrix2::new(inv[(1, 1)], inv[(1, 2)], inv[(2, 1)], inv[(2, 2)])
                            * s2,
                        sigma: s2.sqrt(),
                    }
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// On whole revolutions the streaming normal equations and the Fourier coefficient give the
    /// same (a, b): X₁ = (n/2)(a − jb). Tolerance 1e-12 relative: both are O(n·ε) sums.
    #[test]
    fn normal_equations_match_fourier_on_full_periods() {
        let n = 360;
        let th: Vec<f64> = (0..n).map(|q| TAU * q as f64 / n as f64).collect();
        let x: Vec<f64> = th
            .iter()
            .map(|t| 0.3 + 1.5 * t.cos() - 0.7 * t.sin())
            .collect();
        let mut sums = HarmonicSums::new(vec![x[0]]);
        for (t, v) in th.iter().zip(&x) {
            sums.push(t.cos(), t.sin(), [*v]);
        }
        let f = sums.solve().unwrap()[0];
        let (re, im) = fourier_coefficient(x.iter().copied(), th.iter().copied());
        let h = n as f64 / 2.0;
        assert!((f.beta[1] - re / h).abs() < 1e-12 && (f.beta[2] + im / h).abs() < 1e-12);
        assert!((f.beta[0] - 0.3).abs() < 1e-12);
        let (ur, ui) = fourier_coefficient_uniform(&x, 0, TAU / n as f64);
        assert!((ur - re).abs() < 1e-10 && (ui - im).abs() < 1e-10);
    }
}
