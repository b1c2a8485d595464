//! The answer type of a fitted scalar: value ± standard error.

use crate::fit::LinearFit;
use nalgebra::DVector;
use serde::Serialize;

/// A value with its standard error (`None` when it cannot be estimated, e.g. no residual
/// degrees of freedom).
///
/// ```
/// use nalgebra::{DMatrix, DVector};
/// use runout_core::{fit::linear_lsq, Estimate};
/// let x = DMatrix::from_row_slice(4, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0, 3.0]);
/// let fit = linear_lsq("line", &x, &DVector::from_vec(vec![1.0, 3.1, 4.9, 7.0])).unwrap();
/// let slope = Estimate::from_fit(&fit, 1);
/// assert!((slope.value - 1.98).abs() < 1e-12 && slope.se.unwrap() > 0.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Estimate {
    /// The estimate.
    pub value: f64,
    /// Its standard error, if available.
    #[serde(rename = "value_se")]
    pub se: Option<f64>,
}

impl Estimate {
    /// value ± se.
    pub fn new(value: f64, se: Option<f64>) -> Self {
        Estimate { value, se }
    }

    /// Coefficient `i` of a linear fit with its standard error √(σ̂²·[(XᵀX)⁻¹]ᵢᵢ)
    /// (`None` without residual degrees of freedom).
    pub fn from_fit(fit: &LinearFit, i: usize) -> Self {
        Estimate {
            value: fit.beta[i],
            se: fit.covariance().map(|c| c[(i, i)].sqrt()),
        }
    }

    /// A derived quantity g(β̂) = `value` with the delta-method standard error
    /// √(∇gᵀ·Cov(β̂)·∇g), `gradient` = ∇g at β̂ (`None` without residual degrees of freedom).
    pub fn delta_method(value: f64, fit: &LinearFit, gradient: &[f64]) -> Self {
        let se = fit.covariance().map(|m| {
            let g = DVector::from_column_slice(gradient);
            (g.transpose() * m * &g)[0].max(0.0).sqrt()
        });
        Estimate { value, se }
    }
}
