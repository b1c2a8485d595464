//! Static calibration of the shank stiffness (methods.md §3.1, "best practice"): known loads F_j
//! applied at distances a_j from the holder face, measured relative deflections Δ_j = δ_II − δ_I.
//!
//! Model (linear in the unknowns b, s, c_θ):
//!
//! Δ_j = b + F_j·[ s·(B(a_j)/(6EI)) + c_θ·(l_II − l_I)·a_j ],  B(a) = l_II²(3a − l_II) − l_I²(3a − l_I)
//!
//! with b a zero offset, s the ratio of the true to the nominal bending compliance (1 if E, d are
//! right) and c_θ = 1/k_θ the holder's rotational compliance. s and c_θ are separable only with
//! loads at ≥ 2 distances; with a single distance the fit is Δ = b + F/K_δ and the holder term
//! is reported as not identifiable. Ordinary least squares; standard errors from
//! σ²(XᵀX)⁻¹ with σ² = RSS/(n − p); K_δ's error by linear propagation.

use super::{ShankBeam, ShankError};
use crate::fit::LinearLsq;
use nalgebra::{DMatrix, DVector};

/// One static load step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadStep {
    /// Applied force (load cell), N.
    pub force_n: f64,
    /// Distance of the load from the holder face, mm.
    pub load_point_mm: f64,
    /// Measured δ_II − δ_I, mm.
    pub delta_mm: f64,
}

/// Result of a static calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticCalibration {
    /// K_δ at the beam's load point, N/mm.
    pub stiffness_n_per_mm: f64,
    /// Standard error of K_δ, N/mm.
    pub stiffness_se_n_per_mm: f64,
    /// Bending-compliance scale s and its standard error (only with ≥ 2 load points).
    pub beam_scale: Option<(f64, f64)>,
    /// Holder rotational compliance c_θ = 1/k_θ, rad/(N·mm), and its standard error (only with
    /// ≥ 2 load points).
    pub holder_compliance_rad_per_nmm: Option<(f64, f64)>,
    /// Zero offset b, mm.
    pub offset_mm: f64,
    /// Residual RMS, mm.
    pub residual_rms_mm: f64,
    /// Coefficient of determination.
    pub r_squared: f64,
    /// Condition number of the column-scaled design matrix.
    pub condition_number: f64,
    /// Number of load steps.
    pub steps: usize,
}

/// Fit K_δ (and, with loads at ≥ 2 distances, the beam scale and the holder compliance) to
/// static load steps. Needs ≥ 3 steps with ≥ 2 different forces (≥ 4 steps with two distances).
pub fn calibrate(beam: &ShankBeam, steps: &[LoadStep]) -> Result<StaticCalibration, ShankError> {
    let bad = |m: String| ShankError::Calibration(m);
    if steps
        .iter()
        .any(|s| !(s.force_n.is_finite() && s.load_point_mm.is_finite() && s.delta_mm.is_finite()))
    {
        return Err(bad("a load step has a non-finite value".into()));
    }
    let a0 = steps.first().map_or(0.0, |s| s.load_point_mm);
    let two_points = steps
        .iter()
        .any(|s| (s.load_point_mm - a0).abs() > 1e-6 * a0.abs().max(1.0));
    let p = if two_points { 3 } else { 2 };
    if steps.len() < p + 1 {
        return Err(bad(format!(
            "{} load steps for {p} unknowns: need at least {}",
            steps.len(),
            p + 1
        )));
    }
    let ei = beam.modulus_n_per_mm2 * beam.second_moment_mm4();
    let span = beam.l2_mm - beam.l1_mm;
    let bend = |a: f64| {
        (ShankBeam::bending_shape_mm3(beam.l2_mm, a) - ShankBeam::bending_shape_mm3(beam.l1_mm, a))
            / (6.0 * ei)
    };
    let n = steps.len();
    let mut x = DMatrix::zeros(n, p);
    let y = DVector::from_iterator(n, steps.iter().map(|s| s.delta_mm));
    for (j, s) in steps.iter().enumerate() {
        x[(j, 0)] = 1.0;
        if two_points {
            x[(j, 1)] = s.force_n * bend(s.load_point_mm);
            x[(j, 2)] = s.force_n * span * s.load_point_mm;
        } else {
            x[(j, 1)] = s.force_n;
        }
    }
    // column scaling for conditioning
    let scale: Vec<f64> = (0..p)
        .map(|c| x.column(c).norm().max(f64::MIN_POSITIVE))
        .collect();
    let mut xs = x.clone();
    for (c, sc) in scale.iter().enumerate() {
        xs.column_mut(c).scale_mut(1.0 / sc);
    }
    let lsq = LinearLsq::new(xs);
    let condition_number = lsq.condition();
    if !(condition_number.is_finite() && condition_number < 1e10) {
        return Err(bad(format!(
            "the load steps do not determine the unknowns (condition number {condition_number:.3e}); use ≥ 2 different forces{}",
            if two_points { " at each load point" } else { "" }
        )));
    }
    let beta_s = lsq
        .beta(&y, 1e-14)
        .map_err(|e| bad(format!("least squares failed: {e}")))?;
    let beta: Vec<f64> = (0..p).map(|c| beta_s[c] / scale[c]).collect();
    let resid = &y - &x * DVector::from_vec(beta.clone());
    let rss = resid.norm_squared();
    let mean = y.mean();
    let tss = y.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
    let dof = (n - p) as f64;
    let sigma2 = rss / dof;
    let xtx_inv = lsq
        .normal_inverse()
        .ok_or_else(|| bad("singular normal matrix".into()))?;
    let cov = |i: usize, j: usize| sigma2 * xtx_inv[(i, j)] / (scale[i] * scale[j]);
    let a_nom = beam.load_distance_mm();
    let (compliance, var_c, beam_scale, holder) = if two_points {
        let g = [0.0, bend(a_nom), span * a_nom];
        let c = g[1] * beta[1] + g[2] * beta[2];
        let var: f64 = (1..3)
            .flat_map(|i| (1..3).map(move |j| (i, j)))
            .map(|(i, j)| g[i] * g[j] * cov(i, j))
            .sum();
        (
            c,
            var,
            Some((beta[1], cov(1, 1).sqrt())),
            Some((beta[2], cov(2, 2).sqrt())),
        )
    } else {
        (beta[1], cov(1, 1), None, None)
    };
    if !(compliance.is_finite() && compliance > 0.0) {
        return Err(bad(format!(
            "fitted compliance {compliance:.3e} mm/N is not positive: check the sign of the deflection channels"
        )));
    }
    Ok(StaticCalibration {
        stiffness_n_per_mm: 1.0 / compliance,
        stiffness_se_n_per_mm: var_c.max(0.0).sqrt() / (compliance * compliance),
        beam_scale,
        holder_compliance_rad_per_nmm: holder,
        offset_mm: beta[0],
        residual_rms_mm: (rss / n as f64).sqrt(),
        r_squared: if tss > 0.0 { 1.0 - rss / tss } else { f64::NAN },
        condition_number,
        steps: n,
    })
}
