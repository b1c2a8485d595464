//! Several peak tests of one tool installation (seed 003 §2.3): per-test sine fits, the secondary
//! regressions of A on a_p and of C on f_z·a_p (methods.md §4.4), K_T/K_R by seed eq. (17), the
//! vector mean of the runout, and the edge-force-aware pooled fit (§4.6) when ≥ 2 feeds are given.

use super::error::IdentifyError;
use super::peak_coefficients::{coefficients_at_peak, PeakCoefficients};
use super::peak_test::PeakTest;
use super::pooled::{pooled_fit, EdgeModel, PooledFit};
use super::sine_fit::{sine_fit, SineFit, SineHypothesis};
use crate::fit::{fit_line, Regression};
use serde::Serialize;

/// Per-test result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TestResult {
    /// Label.
    pub label: String,
    /// f_z (mm).
    pub fz_mm: f64,
    /// a_p (mm).
    pub ap_mm: f64,
    /// The sine fit.
    pub fit: SineFit,
    /// K_T, K_R from eq. (17) when F̄_x and F̄_y were given.
    pub coefficients: Option<PeakCoefficients>,
}

/// Everything the multi-test analysis reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MultiTestResult {
    /// Per-test fits.
    pub tests: Vec<TestResult>,
    /// A = b·a_p + c over all tests (needs ≥ 2 distinct a_p).
    pub amplitude_vs_ap: Option<Regression>,
    /// A = b·a_p through the origin.
    pub amplitude_vs_ap_origin: Option<Regression>,
    /// C = b·f_z·a_p + c (the intercept is the edge/ploughing part, seed eq. 15–16).
    pub mean_vs_fz_ap: Option<Regression>,
    /// C = b·f_z·a_p through the origin.
    pub mean_vs_fz_ap_origin: Option<Regression>,
    /// Vector mean of the per-test runout vectors: (offset mm, angle rad).
    pub vector_mean: (f64, f64),
    /// Arithmetic means of the per-test offsets (mm) and angles (rad), as the seed reports them.
    pub arithmetic_mean: (f64, f64),
    /// Edge-force-aware pooled fit (methods.md §4.6), when ≥ 2 distinct f_z·a_p and feeds.
    pub pooled: Option<PooledFit>,
    /// Pooled fit without an edge term, for comparison.
    pub pooled_no_edge: Option<PooledFit>,
    /// Per-test offsets (mm) with C corrected by the pooled fit's edge force C₀ + E·a_p
    /// ([`SineFit::edge_corrected_offset`]), when the pooled fit exists.
    pub edge_corrected_offsets: Option<Vec<f64>>,
}

fn distinct(values: impl Iterator<Item = f64>) -> usize {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs().max(1.0));
    v.len()
}

/// Analyse several tests (all with the same tool, same K).
pub fn analyse_tests(
    tests: &[PeakTest],
    hypothesis: SineHypothesis,
) -> Result<MultiTestResult, IdentifyError> {
    if tests.is_empty() {
        return Err(IdentifyError::too_few("multi-test analysis", "1 test", 0));
    }
    let k = tests[0].peaks.teeth();
    if let Some(t) = tests.iter().find(|t| t.peaks.teeth() != k) {
        return Err(IdentifyError::Param(crate::ParamError::new(
            format!("test {} peaks", t.label),
            format!("{k} peaks (same number of teeth in every test)"),
            t.peaks.teeth(),
        )));
    }
    let mut results = Vec::with_capacity(tests.len());
    for t in tests {
        let fit = sine_fit(&t.peaks, &t.conditions, hypothesis)?;
        let coefficients = match (t.fx_at_peak_n, t.fy_at_peak_n) {
            (Some(fx), Some(fy)) => Some(coefficients_at_peak(
                fx,
                fy,
                t.peak_immersion_rad,
                t.conditions.fz_mm,
                t.ap_mm,
            )?),
            _ => None,
        };
        results.push(TestResult {
            label: t.label.clone(),
            fz_mm: t.conditions.fz_mm,
            ap_mm: t.ap_mm,
            fit,
            coefficients,
        });
    }
    let ap: Vec<f64> = results.iter().map(|r| r.ap_mm).collect();
    let fa: Vec<f64> = results.iter().map(|r| r.fz_mm * r.ap_mm).collect();
    let amp: Vec<f64> = results.iter().map(|r| r.fit.amplitude.value).collect();
    let mean: Vec<f64> = results.iter().map(|r| r.fit.mean.value).collect();
    let n_ap = distinct(ap.iter().copied());
    let n_fa = distinct(fa.iter().copied());
    let n_fz = distinct(results.iter().map(|r| r.fz_mm));
    let line = |x: &[f64], y: &[f64], icpt: bool, nd: usize| {
        (nd >= if icpt { 2 } else { 1 })
            .then(|| fit_line(x, y, icpt).ok())
            .flatten()
    };

    let (mut sx, mut sy, mut so, mut sa) = (0.0, 0.0, 0.0, 0.0);
    for r in &results {
        sx += r.fit.offset.value * r.fit.angle.value.cos();
        sy += r.fit.offset.value * r.fit.angle.value.sin();
        so += r.fit.offset.value;
        sa += r.fit.angle.value;
    }
    let n = results.len() as f64;
    let pooled_ok = n_fz >= 2 && n_fa >= 2 && k >= 3;
    let pooled = if pooled_ok {
        Some(pooled_fit(tests, EdgeModel::ConstantPlusDepth)?)
    } else {
        None
    };
    let edge_corrected_offsets = pooled.as_ref().map(|p| {
        let c0 = p.constant_n.map(|e| e.value).unwrap_or(0.0);
        let e = p.edge_n_per_mm.map(|e| e.value).unwrap_or(0.0);
        results
            .iter()
            .map(|r| r.fit.edge_corrected_offset(c0 + e * r.ap_mm))
            .collect()
    });
    Ok(MultiTestResult {
        amplitude_vs_ap: line(&ap, &amp, true, n_ap),
        amplitude_vs_ap_origin: line(&ap, &amp, false, n_ap),
        mean_vs_fz_ap: line(&fa, &mean, true, n_fa),
        mean_vs_fz_ap_origin: line(&fa, &mean, false, n_fa),
        vector_mean: ((sx / n).hypot(sy / n), (sy / n).atan2(sx / n)),
        arithmetic_mean: (so / n, sa / n),
        pooled,
        edge_corrected_offsets,
        pooled_no_edge: if pooled_ok {
            Some(pooled_fit(tests, EdgeModel::None)?)
        } else {
            None
        },
        tests: results,
    })
}
