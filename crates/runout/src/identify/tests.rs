//! `identify tests`: several per-tooth peak tests (seed 003 Table 1 style) from a CSV or TOML
//! table → per-test sine fits, regressions of A on a_p and C on f_z·a_p, K_T/K_R (seed eq. 17),
//! pooled edge-force-aware fit (methods.md §4.4, §4.6).

use super::finite;
use super::peaks::{peak_angle, PeakFitReport};
use crate::job::{Report, Source};
use anyhow::{anyhow, bail, Context, Result};
use runout_core::identify::{
    analyse_tests, EdgeModel, MultiTestResult, PeakConditions, PeakTest, PooledFit, Regression,
    SineHypothesis, ToothPeaks,
};
use runout_core::MillingMode;
use runout_io::peak_table::{parse_csv, parse_toml, read_peak_table, PeakRow, PeakTable};
use schemars::JsonSchema;
use serde::Serialize;

/// Values for the tests whose row (and the table's settings) do not give them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TestsDefaults {
    /// Cutter diameter D (mm).
    pub diameter_mm: Option<f64>,
    /// Radial depth a_e (mm).
    pub ae_mm: Option<f64>,
    /// Milling mode (default up).
    pub mode: Option<MillingMode>,
    /// Peak immersion angle γ (deg) for all tests (default: from the engagement).
    pub peak_immersion_deg: Option<f64>,
}

/// A table of tests and how to fit them.
#[derive(Debug, Clone)]
pub struct TestsRequest {
    /// The table: CSV/TSV (columns test, fz_mm, ap_mm, peak0_N…, optional se0_N…, fx_at_peak_N,
    /// fy_at_peak_N, diameter_mm, ae_mm, mode) or TOML (`[[test]]` tables; a name ending in
    /// `.toml`).
    pub table: Source,
    /// Values the rows do not give; they override the table's own settings.
    pub defaults: TestsDefaults,
    /// K peaks once each, or K + 1 points with the period closed (the seed's Table 2).
    pub hypothesis: SineHypothesis,
}

impl TestsRequest {
    /// The table with no defaults, K peaks once each.
    pub fn new(table: Source) -> Self {
        Self {
            table,
            defaults: TestsDefaults::default(),
            hypothesis: SineHypothesis::Teeth,
        }
    }
}

/// The inputs of one test as reported.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct TestInputs {
    pub fz_mm: f64,
    pub ap_mm: f64,
    pub peak_immersion_deg: f64,
}

/// One test: its sine fit, label, coefficients (N/mm², seed eq. 17) and the edge-corrected ρ.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct TestReport {
    pub warnings: Vec<String>,
    /// Where the standard errors come from, in words.
    pub standard_errors: String,
    #[serde(flatten)]
    pub fit: PeakFitReport<TestInputs>,
    pub label: String,
    pub kt_N_per_mm2: Option<f64>,
    pub kr_N_per_mm2: Option<f64>,
    pub k_N_per_mm2: Option<f64>,
    pub offset_edge_corrected_um: Option<f64>,
}

macro_rules! regression_report {
    ($name:ident, $slope:ident, $slope_se:ident, $unit:literal) => {
        #[doc = concat!("A straight-line fit with its slope in ", $unit, " (methods.md §4.4).")]
        #[derive(Debug, Clone, Serialize, JsonSchema)]
        pub struct $name {
            pub $slope: f64,
            pub $slope_se: Option<f64>,
            pub intercept_N: f64,
            pub intercept_N_se: Option<f64>,
            pub with_intercept: bool,
            pub r_squared: f64,
            pub points: usize,
        }

        impl From<&Regression> for $name {
            fn from(r: &Regression) -> Self {
                Self {
                    $slope: r.slope,
                    $slope_se: finite(r.slope_se),
                    intercept_N: r.intercept,
                    intercept_N_se: finite(r.intercept_se),
                    with_intercept: r.with_intercept,
                    r_squared: r.r_squared,
                    points: r.n,
                }
            }
        }
    };
}

regression_report!(RegressionPerMm, slope_N_per_mm, slope_N_per_mm_se, "N/mm");
regression_report!(
    RegressionPerMm2,
    slope_N_per_mm2,
    slope_N_per_mm2_se,
    "N/mm²"
);

/// A runout as offset (µm) and angle (deg).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PolarMean {
    pub offset_um: f64,
    pub angle_deg: f64,
}

impl PolarMean {
    fn of((offset_mm, angle_rad): (f64, f64)) -> Self {
        Self {
            offset_um: offset_mm * 1e3,
            angle_deg: angle_rad.to_degrees(),
        }
    }
}

/// The pooled fit of all peaks (methods.md §4.6).
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct PooledReport {
    /// `none`, `constant` or `constant_plus_depth`.
    #[schemars(with = "String")]
    pub edge_model: EdgeModel,
    pub offset_um: f64,
    pub offset_um_se: Option<f64>,
    pub angle_deg: f64,
    pub angle_deg_se: Option<f64>,
    pub k_lumped_N_per_mm2: f64,
    pub k_lumped_N_per_mm2_se: Option<f64>,
    pub constant_N: Option<f64>,
    pub constant_N_se: Option<f64>,
    pub edge_N_per_mm: Option<f64>,
    pub edge_N_per_mm_se: Option<f64>,
    pub residual_rms_N: f64,
    pub r_squared: f64,
    pub peaks: usize,
    pub residual_dof: usize,
    pub condition_number: f64,
}

impl From<&PooledFit> for PooledReport {
    fn from(p: &PooledFit) -> Self {
        Self {
            edge_model: p.edge_model,
            offset_um: p.offset.value * 1e3,
            offset_um_se: p.offset.se.map(|s| s * 1e3),
            angle_deg: p.angle.value.to_degrees(),
            angle_deg_se: p.angle.se.map(f64::to_degrees),
            k_lumped_N_per_mm2: p.k_lumped.value,
            k_lumped_N_per_mm2_se: p.k_lumped.se,
            constant_N: p.constant_n.map(|e| e.value),
            constant_N_se: p.constant_n.and_then(|e| e.se),
            edge_N_per_mm: p.edge_n_per_mm.map(|e| e.value),
            edge_N_per_mm_se: p.edge_n_per_mm.and_then(|e| e.se),
            residual_rms_N: p.residual_rms,
            r_squared: p.r_squared,
            peaks: p.n,
            residual_dof: p.dof,
            condition_number: p.condition,
        }
    }
}

/// `runout.identify.tests/1`: per-test fits, regressions, means and pooled fits.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct TestsReport {
    /// `runout.identify.tests/1`
    #[schemars(extend("const" = "runout.identify.tests/1"))]
    pub schema: String,
    pub table: String,
    pub method: String,
    pub tests: Vec<TestReport>,
    pub amplitude_vs_ap: Option<RegressionPerMm>,
    pub amplitude_vs_ap_origin: Option<RegressionPerMm>,
    pub mean_vs_fz_ap: Option<RegressionPerMm2>,
    pub mean_vs_fz_ap_origin: Option<RegressionPerMm2>,
    pub vector_mean: PolarMean,
    pub arithmetic_mean: PolarMean,
    pub pooled_edge_aware: Option<PooledReport>,
    pub pooled_no_edge: Option<PooledReport>,
}

impl Report for TestsReport {
    const SCHEMA: &'static str = "runout.identify.tests/1";
}

/// The table of the request (TOML by the `.toml` name, else CSV/TSV).
fn read_table(src: &Source) -> Result<PeakTable> {
    if let Some(p) = src.as_path() {
        return Ok(read_peak_table(p)?);
    }
    let text = src.read_text()?;
    let name = src.name();
    let toml = name.to_ascii_lowercase().ends_with(".toml");
    Ok(if toml {
        parse_toml(name, &text)?
    } else {
        parse_csv(name, &text)?
    })
}

fn parse_mode(text: &str) -> Result<MillingMode> {
    Ok(text.parse()?)
}

/// One row as a core peak test, with the request's defaults filling what the row lacks.
fn peak_test(table: &PeakTable, r: &PeakRow, d: &TestsDefaults, file: &str) -> Result<PeakTest> {
    let s = &table.settings;
    let at = || format!("{file}:{} (test {})", r.line, r.label);
    let k = r.peaks_n.len();
    if let Some(t) = s.teeth {
        if t != k {
            bail!("{}: {k} peaks but teeth = {t}", at());
        }
    }
    let mode = match (&r.mode, d.mode, &s.mode) {
        (Some(m), _, _) => parse_mode(m).with_context(at)?,
        (None, Some(m), _) => m,
        (None, None, Some(m)) => parse_mode(m).with_context(at)?,
        (None, None, None) => MillingMode::Up,
    };
    let gamma = peak_angle(
        mode,
        r.ae_mm.or(d.ae_mm).or(s.ae_mm),
        r.diameter_mm.or(d.diameter_mm).or(s.diameter_mm),
        d.peak_immersion_deg.or(s.peak_immersion_deg),
        r.fz_mm,
        k,
    )
    .with_context(at)?;
    let mut peaks = ToothPeaks::new(r.peaks_n.clone()).with_context(at)?;
    if let Some(se) = &r.peaks_se_n {
        peaks = peaks.with_se(se.clone()).with_context(at)?;
    }
    Ok(PeakTest {
        label: r.label.clone(),
        ap_mm: r.ap_mm,
        conditions: PeakConditions::new(r.fz_mm, gamma).with_context(at)?,
        peak_immersion_rad: gamma,
        peaks,
        fx_at_peak_n: r.fx_at_peak_n,
        fy_at_peak_n: r.fy_at_peak_n,
    })
}

/// Per-test fits, regressions, K_T/K_R and pooled fits of the request's table (§4.4, §4.6).
pub fn tests(req: &TestsRequest) -> Result<TestsReport> {
    let table = read_table(&req.table)?;
    let file = req.table.name().to_string();
    let tests = table
        .rows
        .iter()
        .map(|r| peak_test(&table, r, &req.defaults, &file))
        .collect::<Result<Vec<_>>>()?;
    let res = analyse_tests(&tests, req.hypothesis).map_err(|e| anyhow!("{file}: {e}"))?;
    Ok(report(&res, file))
}

fn test_report(r: &MultiTestResult, i: usize) -> TestReport {
    let t = &r.tests[i];
    let inputs = TestInputs {
        fz_mm: t.fz_mm,
        ap_mm: t.ap_mm,
        peak_immersion_deg: t.fit.conditions.sin_gamma.asin().to_degrees(),
    };
    TestReport {
        warnings: t.fit.warnings.clone(),
        standard_errors: super::peaks::error_source_text(t.fit.error_source).into(),
        fit: PeakFitReport::new(&t.fit, inputs),
        label: t.label.clone(),
        kt_N_per_mm2: t.coefficients.map(|c| c.kt),
        kr_N_per_mm2: t.coefficients.map(|c| c.kr),
        k_N_per_mm2: t.coefficients.map(|c| c.k),
        offset_edge_corrected_um: r.edge_corrected_offsets.as_ref().map(|v| v[i] * 1e3),
    }
}

fn report(r: &MultiTestResult, table: String) -> TestsReport {
    TestsReport {
        schema: TestsReport::SCHEMA.into(),
        table,
        method: "seed003 per-tooth peak sine fit per test (docs/methods.md §4.2); regressions 4.4; K_T/K_R seed eq. 17 (F_y in the workpiece frame); pooled edge-aware fit 4.6".into(),
        tests: (0..r.tests.len()).map(|i| test_report(r, i)).collect(),
        amplitude_vs_ap: r.amplitude_vs_ap.as_ref().map(Into::into),
        amplitude_vs_ap_origin: r.amplitude_vs_ap_origin.as_ref().map(Into::into),
        mean_vs_fz_ap: r.mean_vs_fz_ap.as_ref().map(Into::into),
        mean_vs_fz_ap_origin: r.mean_vs_fz_ap_origin.as_ref().map(Into::into),
        vector_mean: PolarMean::of(r.vector_mean),
        arithmetic_mean: PolarMean::of(r.arithmetic_mean),
        pooled_edge_aware: r.pooled.as_ref().map(Into::into),
        pooled_no_edge: r.pooled_no_edge.as_ref().map(Into::into),
    }
}
