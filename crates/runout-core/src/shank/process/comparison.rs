//! Comparison of the reconstructed force with a reference dynamometer channel.

// Column-major data (`columns[c][k]`) reads clearest with index loops.
#![allow(clippy::needless_range_loop)]

#[allow(unused_imports)]
use super::*;

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
