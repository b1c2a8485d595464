//! `chip compare`: the arc, circle-intersection and equivalent models against the exact IUCT on a
//! case set: errors and throughput.

use super::{case_inputs, read_cases, select};
use crate::job::{Report, Source};
use anyhow::Result;
use runout_core::chip::compare::{
    arc_values, equivalent_values, evaluate_models, exact_values, ErrorAccumulator, ErrorMetrics,
    ModelValues,
};
use runout_core::chip::{calibration_grid, fit_compensation, CompensationFit, EquivalentParams};
use runout_io::config::chip::ChipCase;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::time::Instant;

/// `runout chip compare`.
#[derive(Debug, Clone)]
pub struct CompareRequest {
    /// Case-set file (TOML: `[defaults]` and `[[case]]` tables).
    pub config: Source,
    /// Only the cases whose name contains this text.
    pub case: Option<String>,
    /// The equivalent model's effective-edge phase refinement (methods.md §2.4).
    pub phase_refinement: bool,
    /// Also fit (k₁, k₂) per case on 12 calibration angles per tooth.
    pub fit_k: bool,
}

/// Error metrics of one model against the exact IUCT.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Metrics {
    pub mean_relative_error_percent: f64,
    pub normalised_mae_percent: f64,
    pub max_abs_error_um: f64,
    pub points_in_relative_metric: usize,
}

impl From<&ErrorMetrics> for Metrics {
    fn from(m: &ErrorMetrics) -> Self {
        Self {
            mean_relative_error_percent: m.mean_relative * 100.0,
            normalised_mae_percent: m.normalised_mae * 100.0,
            max_abs_error_um: m.max_abs_mm * 1e3,
            points_in_relative_metric: m.points_relative,
        }
    }
}

/// Errors per model.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ModelErrors {
    pub arc: Metrics,
    pub circle: Metrics,
    pub equivalent: Metrics,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equivalent_fitted_k: Option<Metrics>,
}

impl ModelErrors {
    fn of(m: &[ErrorMetrics]) -> Self {
        Self {
            arc: (&m[0]).into(),
            circle: (&m[1]).into(),
            equivalent: (&m[2]).into(),
            equivalent_fitted_k: m.get(3).map(Metrics::from),
        }
    }

    /// (model name, metrics) in report order.
    pub fn list(&self) -> Vec<(&'static str, &Metrics)> {
        let mut v = vec![
            ("arc", &self.arc),
            ("circle", &self.circle),
            ("equivalent", &self.equivalent),
        ];
        if let Some(f) = &self.equivalent_fitted_k {
            v.push(("equivalent_fitted_k", f));
        }
        v
    }
}

/// Points per second (wall time, one thread).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Throughput {
    pub exact: f64,
    pub equivalent: f64,
    pub arc: f64,
}

/// Throughput of all cases pooled.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PooledThroughput {
    pub exact: f64,
    pub equivalent: f64,
    pub arc: f64,
    pub note: String,
}

/// (k₁, k₂) fitted on calibration angles.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct FittedK {
    pub k1: f64,
    pub k2: f64,
    pub k1_std_error: f64,
    pub k2_std_error: f64,
    pub condition: f64,
    pub rms_residual_um: f64,
    pub calibration_points: usize,
}

/// One case.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct CaseReport {
    pub name: String,
    pub points: usize,
    pub errors_vs_exact: ModelErrors,
    pub throughput_points_per_s: Throughput,
    pub fitted_k: Option<FittedK>,
}

/// What the metrics mean.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct MetricsDefinitions {
    pub mean_relative_error: String,
    pub normalised_mae: String,
}

/// The equivalent model's parameters.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct EquivalentModel {
    pub k1: f64,
    pub k2: f64,
    pub phase_refinement: bool,
}

/// `runout.chip.compare/1`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct CompareReport {
    /// `runout.chip.compare/1`
    #[schemars(extend("const" = "runout.chip.compare/1"))]
    pub schema: String,
    pub config: String,
    pub metrics: MetricsDefinitions,
    pub equivalent_model: EquivalentModel,
    pub cases: Vec<CaseReport>,
    pub pooled: ModelErrors,
    pub throughput_points_per_s: PooledThroughput,
    /// Warnings of the cases (configuration, exact solver), in order; not part of the JSON.
    #[serde(skip)]
    #[schemars(skip)]
    pub warnings: Vec<String>,
    /// The files read (case file, toolpaths): what an output must not overwrite.
    #[serde(skip)]
    #[schemars(skip)]
    pub inputs: Vec<PathBuf>,
}

impl Report for CompareReport {
    const SCHEMA: &'static str = "runout.chip.compare/1";
}

/// Points per second of `f` over `n` points: repeated until 50 ms have elapsed.
fn throughput(n: usize, mut f: impl FnMut() -> Vec<f64>) -> f64 {
    let start = Instant::now();
    let mut reps = 0usize;
    while reps < 2 || start.elapsed().as_secs_f64() < 0.05 {
        std::hint::black_box(f());
        reps += 1;
    }
    (n * reps) as f64 / start.elapsed().as_secs_f64()
}

fn fitted_values(
    case: &ChipCase,
    params: &EquivalentParams,
) -> Result<(Vec<f64>, CompensationFit)> {
    let kin = &case.kin;
    let t0 = case.points.first().map(|p| p.t).unwrap_or(0.0);
    let calib = calibration_grid(kin, &case.spec.heights_mm, 12, t0);
    let fit = fit_compensation(kin, &calib, params.phase_refinement)
        .map_err(|e| anyhow::anyhow!("case `{}`: fitting (k1, k2): {e}", case.name))?;
    Ok((equivalent_values(kin, &case.points, &fit.params), fit))
}

/// (report, rates) of one case; pools its errors into `pooled`.
fn compare_case(
    case: &ChipCase,
    params: &EquivalentParams,
    fit_k: bool,
    pooled: &mut [ErrorAccumulator; 4],
    warnings: &mut Vec<String>,
) -> Result<(CaseReport, [f64; 3])> {
    let kin = &case.kin;
    let pts = &case.points;
    let v: ModelValues = evaluate_models(kin, pts, params);
    if v.unconverged > 0 {
        warnings.push(format!(
            "case `{}`: the exact solver missed 1e-12 mm at {} of {} points",
            case.name,
            v.unconverged,
            pts.len()
        ));
    }
    let mut metrics = Vec::new();
    for (q, vals) in [&v.arc, &v.circle, &v.equivalent].into_iter().enumerate() {
        let mut acc = ErrorAccumulator::default();
        acc.add(vals, &v.exact);
        pooled[q].add(vals, &v.exact);
        metrics.push(acc.metrics());
    }
    let mut fit = None;
    if fit_k {
        let (vals, f) = fitted_values(case, params)?;
        let mut acc = ErrorAccumulator::default();
        acc.add(&vals, &v.exact);
        pooled[3].add(&vals, &v.exact);
        metrics.push(acc.metrics());
        fit = Some(f);
    }
    let rates = [
        throughput(pts.len(), || exact_values(kin, pts)),
        throughput(pts.len(), || equivalent_values(kin, pts, params)),
        throughput(pts.len(), || arc_values(kin, pts)),
    ];
    Ok((
        CaseReport {
            name: case.name.clone(),
            points: pts.len(),
            errors_vs_exact: ModelErrors::of(&metrics),
            throughput_points_per_s: Throughput {
                exact: rates[0],
                equivalent: rates[1],
                arc: rates[2],
            },
            fitted_k: fit.map(|f| FittedK {
                k1: f.params.k1,
                k2: f.params.k2,
                k1_std_error: f.std_error[0],
                k2_std_error: f.std_error[1],
                condition: f.condition,
                rms_residual_um: f.rms_residual_mm * 1e3,
                calibration_points: f.points,
            }),
        },
        rates,
    ))
}

/// Compare the models against the exact IUCT on every selected case.
pub fn compare(req: &CompareRequest) -> Result<CompareReport> {
    let cases = select(
        read_cases(&req.config)?,
        req.case.as_deref(),
        req.config.name(),
    )?;
    let params = EquivalentParams {
        phase_refinement: req.phase_refinement,
        ..EquivalentParams::default()
    };
    let mut pooled = [ErrorAccumulator::default(); 4];
    let mut results = Vec::new();
    let mut warnings = Vec::new();
    for c in &cases {
        warnings.extend(c.warnings.iter().cloned());
        results.push(compare_case(
            c,
            &params,
            req.fit_k,
            &mut pooled,
            &mut warnings,
        )?);
    }
    let n_models = if req.fit_k { 4 } else { 3 };
    let pooled: Vec<ErrorMetrics> = (0..n_models).map(|q| pooled[q].metrics()).collect();
    let total_pts: usize = results.iter().map(|r| r.0.points).sum();
    let pooled_rate = |q: usize| {
        total_pts as f64
            / results
                .iter()
                .map(|r| r.0.points as f64 / r.1[q])
                .sum::<f64>()
    };
    Ok(CompareReport {
        schema: CompareReport::SCHEMA.into(),
        config: req.config.name().to_string(),
        metrics: MetricsDefinitions {
            mean_relative_error: "mean |h_model - h_exact| / h_exact over points with h_exact > 5 % of the case's max h_exact".into(),
            normalised_mae: "sum |h_model - h_exact| / sum h_exact over all points".into(),
        },
        equivalent_model: EquivalentModel {
            k1: params.k1,
            k2: params.k2,
            phase_refinement: params.phase_refinement,
        },
        throughput_points_per_s: PooledThroughput {
            exact: pooled_rate(0),
            equivalent: pooled_rate(1),
            arc: pooled_rate(2),
            note: "wall time, one thread, all cases pooled; general 3-D kinematics path".into(),
        },
        cases: results.into_iter().map(|r| r.0).collect(),
        pooled: ModelErrors::of(&pooled),
        warnings,
        inputs: case_inputs(&req.config, &cases),
    })
}
