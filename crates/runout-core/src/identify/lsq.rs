//! Ordinary linear least squares with covariance, and straight-line regressions.
//!
//! β̂ = argmin ‖y − Xβ‖² by SVD (nalgebra); with σ̂² = RSS/(n − p) the covariance is
//! Cov(β̂) = σ̂²·(XᵀX)⁻¹ (standard errors are the square roots of its diagonal).

use super::error::IdentifyError;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Result of a linear least-squares fit y ≈ X·β.
#[derive(Debug, Clone)]
pub struct LinearFit {
    /// Coefficients β̂.
    pub beta: DVector<f64>,
    /// (XᵀX)⁻¹ (unscaled covariance).
    pub xtx_inv: DMatrix<f64>,
    /// Residual sum of squares.
    pub rss: f64,
    /// Residuals y − Xβ̂.
    pub residuals: DVector<f64>,
    /// Number of observations n.
    pub n: usize,
    /// Number of coefficients p.
    pub p: usize,
    /// 2-norm condition number of X (largest / smallest singular value).
    pub condition: f64,
}

impl LinearFit {
    /// Residual degrees of freedom n − p.
    pub fn dof(&self) -> usize {
        self.n.saturating_sub(self.p)
    }
    /// σ̂² = RSS/(n − p), `None` without residual degrees of freedom.
    pub fn sigma2(&self) -> Option<f64> {
        (self.dof() > 0).then(|| self.rss / self.dof() as f64)
    }
    /// Cov(β̂) = σ̂²(XᵀX)⁻¹, `None` without residual degrees of freedom.
    pub fn covariance(&self) -> Option<DMatrix<f64>> {
        self.sigma2().map(|s2| &self.xtx_inv * s2)
    }
}

/// Solve y ≈ X·β by SVD. Errors when X has fewer rows than columns or is rank deficient
/// (relative singular value below 1e-12).
pub fn linear_lsq(
    what: &str,
    x: &DMatrix<f64>,
    y: &DVector<f64>,
) -> Result<LinearFit, IdentifyError> {
    let (n, p) = x.shape();
    if n < p {
        return Err(IdentifyError::too_few(what, format!("{p} observations"), n));
    }
    let svd = x.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let smin = svd.singular_values.min();
    if smax.is_nan() || smax <= 0.0 || smin <= 1e-12 * smax {
        return Err(IdentifyError::singular(
            what,
            format!("design matrix rank deficient (singular values {smin:.3e} .. {smax:.3e})"),
        ));
    }
    let beta = svd
        .solve(y, 0.0)
        .map_err(|e| IdentifyError::singular(what, e))?;
    let v_t = svd.v_t.as_ref().expect("SVD computed with V");
    let inv_s2 = DMatrix::from_diagonal(&svd.singular_values.map(|s| 1.0 / (s * s)));
    let xtx_inv = v_t.transpose() * inv_s2 * v_t;
    let residuals = y - x * &beta;
    let rss = residuals.norm_squared();
    Ok(LinearFit {
        beta,
        xtx_inv,
        rss,
        residuals,
        n,
        p,
        condition: smax / smin,
    })
}

/// Coefficient of determination R² = 1 − RSS/Σ(y − ȳ)² (1 when y is constant and fitted exactly).
pub fn r_squared(y: &[f64], rss: f64) -> f64 {
    let n = y.len().max(1) as f64;
    let mean = y.iter().sum::<f64>() / n;
    let tss: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
    if tss > 0.0 {
        1.0 - rss / tss
    } else if rss <= 1e-24 {
        1.0
    } else {
        0.0
    }
}

/// A straight-line regression y = slope·x (+ intercept).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Regression {
    /// Slope.
    pub slope: f64,
    /// Standard error of the slope (`NaN` without residual dof).
    pub slope_se: f64,
    /// Intercept (0 for a fit through the origin).
    pub intercept: f64,
    /// Standard error of the intercept (`NaN` through the origin or without residual dof).
    pub intercept_se: f64,
    /// True when the intercept was fitted.
    pub with_intercept: bool,
    /// R² = 1 − RSS/Σ(y − ȳ)² (centred, also for the fit through the origin).
    pub r_squared: f64,
    /// Number of points.
    pub n: usize,
}

/// Least-squares line y = a + b·x (`with_intercept`) or y = b·x through the origin.
///
/// ```
/// use runout_core::identify::fit_line;
/// let r = fit_line(&[1.0, 2.0, 3.0], &[3.0, 5.0, 7.0], true).unwrap();
/// assert!((r.slope - 2.0).abs() < 1e-12 && (r.intercept - 1.0).abs() < 1e-12);
/// ```
pub fn fit_line(x: &[f64], y: &[f64], with_intercept: bool) -> Result<Regression, IdentifyError> {
    if x.len() != y.len() {
        return Err(IdentifyError::too_few(
            "line fit",
            format!("{} y values", x.len()),
            y.len(),
        ));
    }
    let p = if with_intercept { 2 } else { 1 };
    let design = DMatrix::from_fn(x.len(), p, |r, c| if c == 0 { x[r] } else { 1.0 });
    let fit = linear_lsq("line fit", &design, &DVector::from_column_slice(y))?;
    let se = |i: usize| {
        fit.covariance()
            .map(|c| c[(i, i)].sqrt())
            .unwrap_or(f64::NAN)
    };
    Ok(Regression {
        slope: fit.beta[0],
        slope_se: se(0),
        intercept: if with_intercept { fit.beta[1] } else { 0.0 },
        intercept_se: if with_intercept { se(1) } else { f64::NAN },
        with_intercept,
        r_squared: r_squared(y, fit.rss),
        n: x.len(),
    })
}
