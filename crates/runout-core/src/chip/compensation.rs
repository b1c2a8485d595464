//! Least-squares fit of the compensation parameters (k₁, k₂) of the equivalent model
//! (methods.md eq. 2.8, "parameterised thickness compensation") to exact IUCT values at a few
//! calibration points of the actual tool path.
//!
//! At each point the active previous pass m* is the argmin of eq. (2.8) at k₁ = k₂ = 1; the model
//! is linear in (k₁, k₂) there: h_exact − (ΔR + d·n) = k₁·X₁ + k₂·X₂ with X₁ = (d·t̂)²/2R_p,
//! X₂ = −(d·t̂)(a·n)/R_p. Solved by SVD (nalgebra); the condition number and RMS residual are
//! reported. Points where the exact tooth does not cut are skipped.

use super::closed_form::{pass_terms, EquivalentParams};
use super::exact::{exact_at, NewtonOptions, Ray};
use super::kinematics::{ToolKinematics, ToolMotion};
use crate::error::ParamError;
use crate::fit::LinearLsq;
use nalgebra::{DMatrix, DVector};

/// A calibration point: tooth, height z (mm), time t (s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationPoint {
    /// Tooth index.
    pub tooth: usize,
    /// Height from the tip (mm).
    pub z: f64,
    /// Time (s).
    pub t: f64,
}

/// Result of [`fit_compensation`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompensationFit {
    /// Fitted parameters (with the phase-refinement flag used).
    pub params: EquivalentParams,
    /// Standard errors of (k₁, k₂) from σ²(AᵀA)⁻¹, σ² = RSS/(n − 2).
    pub std_error: [f64; 2],
    /// RMS of h_exact − h_eq at the calibration points (mm).
    pub rms_residual_mm: f64,
    /// Condition number σ_max/σ_min of the 2-column design matrix.
    pub condition: f64,
    /// Number of cutting points used.
    pub points: usize,
}

/// Fit (k₁, k₂) on `points` to the exact IUCT (methods.md §2.4). Error when fewer than 3 cutting
/// points or the two regressors are not separable (condition > 1e8).
pub fn fit_compensation<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    points: &[CalibrationPoint],
    phase_refinement: bool,
) -> Result<CompensationFit, ParamError> {
    let opts = NewtonOptions::default();
    let targets: Vec<f64> = points
        .iter()
        .map(|q| exact_at(kin, &kin.at_height(q.z), q.tooth, q.t, &opts).raw)
        .collect();
    fit_compensation_to(kin, points, &targets, phase_refinement)
}

/// Fit (k₁, k₂) of eq. (2.8) to given target thicknesses `targets[j]` (mm, raw: ≤ 0 = no cut,
/// skipped) at `points[j]` — the least-squares core of [`fit_compensation`], also usable with
/// measured or externally computed chip thicknesses.
pub fn fit_compensation_to<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    points: &[CalibrationPoint],
    targets: &[f64],
    phase_refinement: bool,
) -> Result<CompensationFit, ParamError> {
    if targets.len() != points.len() {
        return Err(ParamError::new(
            "targets",
            format!("{} values (one per calibration point)", points.len()),
            targets.len(),
        ));
    }
    let mut rows: Vec<[f64; 3]> = Vec::with_capacity(points.len());
    for (q, &h) in points.iter().zip(targets) {
        if h <= 0.0 {
            continue;
        }
        let geo = kin.at_height(q.z);
        let ray = Ray::at(kin, &geo, q.tooth, q.t);
        let active = (1..=kin.cutter().teeth())
            .map(|m| pass_terms(kin, &geo, &ray, q.tooth, m, q.t, phase_refinement))
            .min_by(|a, b| a.equivalent(1.0, 1.0).total_cmp(&b.equivalent(1.0, 1.0)))
            .expect("K >= 1");
        rows.push([
            active.circle_term(),
            active.trochoid_term(),
            h - active.linear,
        ]);
    }
    solve_rows(&rows, phase_refinement)
}

/// Least squares on rows [X₁, X₂, y] with the condition number and standard errors.
fn solve_rows(rows: &[[f64; 3]], phase_refinement: bool) -> Result<CompensationFit, ParamError> {
    if rows.len() < 3 {
        return Err(ParamError::new(
            "calibration_points",
            "at least 3 points where the tooth cuts",
            rows.len(),
        ));
    }
    let lsq = LinearLsq::new(DMatrix::from_fn(rows.len(), 2, |r, c| rows[r][c]));
    let b = DVector::from_fn(rows.len(), |r, _| rows[r][2]);
    let condition = lsq.condition();
    if !(condition.is_finite() && condition < 1e8) {
        return Err(ParamError::new(
            "calibration_points",
            "points that separate the circle and trochoid terms (condition < 1e8)",
            format!("condition {condition:.3e}"),
        ));
    }
    let fit = lsq.solve(&b, 1e-14).map_err(|e| {
        ParamError::new("calibration_points", "a solvable least-squares problem", e)
    })?;
    let (k, rss) = (&fit.beta, fit.rss);
    // covariance σ²(AᵀA)⁻¹ with σ² = RSS/(n − 2)
    let sigma2 = rss / (rows.len() as f64 - 2.0);
    let cov = lsq
        .normal_inverse()
        .map(|inv| inv * sigma2)
        .unwrap_or_else(|| DMatrix::from_element(2, 2, f64::INFINITY));
    Ok(CompensationFit {
        params: EquivalentParams {
            k1: k[0],
            k2: k[1],
            phase_refinement,
        },
        std_error: [cov[(0, 0)].sqrt(), cov[(1, 1)].sqrt()],
        rms_residual_mm: (rss / rows.len() as f64).sqrt(),
        condition,
        points: rows.len(),
    })
}

/// Calibration points spread over one revolution: `per_tooth` spindle angles per tooth at each
/// height in `heights`, starting at time `t0`.
pub fn calibration_grid<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    heights: &[f64],
    per_tooth: usize,
    t0: f64,
) -> Vec<CalibrationPoint> {
    let k = kin.cutter().teeth();
    let period = kin.period();
    let mut out = Vec::with_capacity(k * heights.len() * per_tooth);
    for &z in heights {
        for tooth in 0..k {
            for j in 0..per_tooth {
                let t = t0 + period * (j as f64 + 0.5) / per_tooth as f64;
                out.push(CalibrationPoint { tooth, z, t });
            }
        }
    }
    out
}
