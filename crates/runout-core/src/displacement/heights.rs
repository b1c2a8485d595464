//! Runout at the cutting height from readings at several heights, methods.md §1.3 and §1.6.
//!
//! * [`HeightRegression::Ols`] (default): ordinary least squares of r on z,
//!   b₁ = Σ(r_i − r̄)(z_i − z̄)/Σ(z_i − z̄)², r(z_c) = r̄ + b₁(z_c − z̄) — unbiased, because the
//!   errors are in r and z is set by the machine axis (methods.md §1.3 recommendation).
//! * [`HeightRegression::SeedEq6`]: the seed's eq. (6),(7), r = r̄ − z̄·Σ(r_i − r̄)²/Σ(r_i − r̄)(z_i − z̄),
//!   with z measured from z_c (paper-compatible; biased and heavy-tailed with noise, §1.3).
//! * [`vector_at_height`]: complex first-harmonic line E(z) = E₀ + z·T (§1.6), giving the offset and
//!   tilt vectors; r(z_c) = |E₀ + z_c·T|, λ(z_c) = arg(E₀ + z_c·T).

use super::error::{check_finite, DisplacementError};
use super::estimate::{polar_with_covariance, AngleEstimate};
use crate::fit::{fit_offset_tilt, LineNoise, OffsetTiltFit};
use crate::runout::Runout;
use nalgebra::Matrix2;
use serde::Serialize;

/// Regression of runout on height.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HeightRegression {
    /// Ordinary least squares of r on z (default, unbiased).
    #[default]
    Ols,
    /// The seed's eq. (6) (reverse regression; paper-compatible option).
    SeedEq6,
}

/// Result of [`runout_at_height`].
#[derive(Debug, Clone, Serialize)]
pub struct HeightFit {
    /// Method used.
    pub method: HeightRegression,
    /// Height z_c (mm) at which the runout is wanted.
    pub height_mm: f64,
    /// Runout length r(z_c) (mm).
    pub offset_mm: f64,
    /// Standard error of r(z_c) (mm), OLS only and with more than two heights.
    pub offset_se_mm: Option<f64>,
    /// Slope dr/dz (mm/mm) of the fitted line (OLS slope; for eq. (6) the reverse-regression slope 1/d).
    pub slope: f64,
    /// Standard error of the OLS slope (mm/mm).
    pub slope_se: Option<f64>,
    /// Coefficient of determination of the OLS line.
    pub r_squared: f64,
    /// RMS residual of the OLS line (mm).
    pub residual_rms_mm: f64,
    /// Number of heights.
    pub points: usize,
    /// Warnings (negative extrapolated runout…).
    pub notes: Vec<String>,
}

impl HeightFit {
    /// r(z) on the fitted line (mm).
    pub fn at(&self, z_mm: f64) -> f64 {
        self.offset_mm + self.slope * (z_mm - self.height_mm)
    }
}

fn check_heights(z: &[f64], what: &str, n: usize) -> Result<(), DisplacementError> {
    check_finite("height", z)?;
    if n < 2 {
        return Err(DisplacementError::TooFew {
            what: what.into(),
            got: n,
            need: 2,
        });
    }
    let zbar = z.iter().sum::<f64>() / n as f64;
    let szz: f64 = z.iter().map(|v| (v - zbar).powi(2)).sum();
    if szz <= 1e-24 * (1.0 + zbar * zbar) {
        return Err(DisplacementError::HeightsEqual { z_mm: z[0] });
    }
    Ok(())
}

/// Runout length at height `z_c_mm` from (z_i, r_i) pairs (mm; r_i = half the TIR at z_i,
/// seed eq. 5), methods.md §1.3.
///
/// ```
/// use runout_core::displacement::{runout_at_height, HeightRegression};
/// let pts = [(1.0, 0.0034), (2.0, 0.0038), (3.0, 0.0042)];
/// let fit = runout_at_height(&pts, 0.0, HeightRegression::Ols).unwrap();
/// assert!((fit.offset_mm - 0.0030).abs() < 1e-12);
/// ```
pub fn runout_at_height(
    points: &[(f64, f64)],
    z_c_mm: f64,
    method: HeightRegression,
) -> Result<HeightFit, DisplacementError> {
    let n = points.len();
    let z: Vec<f64> = points.iter().map(|p| p.0).collect();
    let r: Vec<f64> = points.iter().map(|p| p.1).collect();
    check_heights(&z, "heights for the runout regression", n)?;
    check_finite("runout", &r)?;
    if !z_c_mm.is_finite() {
        return Err(crate::ParamError::new("at_mm", "a finite number", z_c_mm).into());
    }
    let nf = n as f64;
    let zbar = z.iter().sum::<f64>() / nf;
    let rbar = r.iter().sum::<f64>() / nf;
    let szz: f64 = z.iter().map(|v| (v - zbar).powi(2)).sum();
    let srr: f64 = r.iter().map(|v| (v - rbar).powi(2)).sum();
    let szr: f64 = z.iter().zip(&r).map(|(a, b)| (a - zbar) * (b - rbar)).sum();
    let b1 = szr / szz;
    let rss: f64 = z
        .iter()
        .zip(&r)
        .map(|(a, b)| (b - rbar - b1 * (a - zbar)).powi(2))
        .sum();
    let dof = n - 2;
    let s2 = (dof > 0).then(|| rss / dof as f64);
    let r_squared = if srr > 0.0 { 1.0 - rss / srr } else { 1.0 };
    let mut notes = Vec::new();
    let (offset, slope, se, slope_se) = match method {
        HeightRegression::Ols => {
            let at = rbar + b1 * (z_c_mm - zbar);
            let se = s2.map(|s2| (s2 * (1.0 / nf + (z_c_mm - zbar).powi(2) / szz)).sqrt());
            (at, b1, se, s2.map(|s2| (s2 / szz).sqrt()))
        }
        HeightRegression::SeedEq6 => {
            if szr == 0.0 {
                return Err(DisplacementError::Fit(
                    "seed eq. (6): Σ(r − r̄)(z − z̄) = 0, the reverse regression is undefined".into(),
                ));
            }
            let at = rbar - (zbar - z_c_mm) * srr / szr;
            notes.push("seed eq. (6) (reverse regression) is biased with noisy r; prefer OLS (docs/methods.md §1.3)".into());
            (at, srr / szr, None, None)
        }
    };
    if offset < 0.0 {
        notes.push(format!(
            "extrapolated runout {:.3} µm is negative: the line does not describe |e(z)| down to z = {z_c_mm} mm (offset and tilt not coplanar? use the vector fit)",
            offset * 1e3
        ));
    }
    Ok(HeightFit {
        method,
        height_mm: z_c_mm,
        offset_mm: offset,
        offset_se_mm: se,
        slope,
        slope_se,
        r_squared,
        residual_rms_mm: (rss / nf).sqrt(),
        points: n,
        notes,
    })
}

/// Result of [`vector_at_height`]: the offset + tilt line and the runout at the height z_c.
#[derive(Debug, Clone, Serialize)]
pub struct VectorHeightFit {
    /// Height z_c (mm) of the reported runout.
    pub height_mm: f64,
    /// The line E(z) = E₀ + z·T (spindle frame; E₀ in mm at z = 0, T in mm/mm), with standard
    /// errors from the residual scatter pooled over both components (`None` with two heights).
    pub line: OffsetTiltFit,
    /// ρ(z_c) (mm).
    pub offset_mm: f64,
    /// Standard error of ρ(z_c) (mm), with more than two heights.
    pub offset_se_mm: Option<f64>,
    /// λ(z_c) or why it is undetermined.
    pub angle: AngleEstimate,
}

impl VectorHeightFit {
    /// The runout e(z) = E₀ + z·T as a [`Runout`] (z = 0 reference).
    pub fn runout(&self) -> Runout {
        self.line.runout()
    }
}

/// Complex line E(z) = E₀ + z·T through first-harmonic vectors E_i = (x, y) (mm, spindle frame)
/// at heights z_i, by linear least squares ([`fit_offset_tilt`], methods.md §1.6); evaluated at
/// `z_c_mm`, with σ² = Σ|E_i − E(z_i)|²/(2n − 4) for both components.
///
/// ```
/// use runout_core::displacement::vector_at_height;
/// let pts = [(1.0, [0.003, 0.001]), (2.0, [0.003, 0.002]), (3.0, [0.003, 0.003])];
/// let fit = vector_at_height(&pts, 0.0).unwrap();
/// assert!((fit.offset_mm - 0.003).abs() < 1e-12 && fit.angle.angle().unwrap().abs() < 1e-9);
/// ```
pub fn vector_at_height(
    points: &[(f64, [f64; 2])],
    z_c_mm: f64,
) -> Result<VectorHeightFit, DisplacementError> {
    let n = points.len();
    let z: Vec<f64> = points.iter().map(|p| p.0).collect();
    check_heights(&z, "heights for the vector regression", n)?;
    let flat: Vec<f64> = points.iter().flat_map(|p| p.1).collect();
    check_finite("runout vector component", &flat)?;
    let line = fit_offset_tilt(points, &LineNoise::Pooled)
        .map_err(|e| DisplacementError::Fit(e.to_string()))?;
    let at = line.at(z_c_mm);
    let (rho, lambda, se_rho, se_l) = match line.at_variance(z_c_mm) {
        Some(v) => {
            let (r, l, sr, sl) = polar_with_covariance(at, &Matrix2::new(v[0], 0.0, 0.0, v[1]));
            (r, l, Some(sr), Some(sl))
        }
        None => (at[0].hypot(at[1]), at[1].atan2(at[0]), None, None),
    };
    Ok(VectorHeightFit {
        height_mm: z_c_mm,
        line,
        offset_mm: rho,
        offset_se_mm: se_rho,
        angle: AngleEstimate::checked(lambda, se_l, rho),
    })
}
