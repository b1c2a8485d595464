//! Result types shared by the displacement methods: the angle with its ill-posedness status,
//! and the conversion of a runout vector with covariance into (ρ, λ) with standard errors.

use nalgebra::Matrix2;
use serde::Serialize;

/// Largest standard error of λ for which the angle is reported (methods.md §1.5 rule:
/// report θ only if σ_θ < 10°).
pub const ANGLE_SE_LIMIT_RAD: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// The runout angle λ (rad, `conventions.md`) as identified, or why it is not.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum AngleEstimate {
    /// λ is determined; `se_rad` is its standard error when the noise is known.
    Determined {
        /// λ (rad) in (−π, π].
        angle_rad: f64,
        /// Standard error (rad), `None` when no noise estimate is available.
        se_rad: Option<f64>,
    },
    /// Two mirror solutions ±λ fit equally well (K = 2 without spindle phase, methods.md §1.5).
    Ambiguous {
        /// Both candidates (rad).
        candidates_rad: [f64; 2],
        /// Standard error of each (rad), when known.
        se_rad: Option<f64>,
        /// Why it is ambiguous and how to resolve it.
        reason: String,
    },
    /// λ cannot be trusted (offset too small for the noise, …).
    Undetermined {
        /// Why.
        reason: String,
        /// The numerical estimate that was rejected (rad), for diagnosis only.
        rejected_rad: Option<f64>,
        /// Its standard error (rad), when known.
        se_rad: Option<f64>,
    },
}

impl AngleEstimate {
    /// The angle when it is determined.
    pub fn angle(&self) -> Option<f64> {
        match self {
            AngleEstimate::Determined { angle_rad, .. } => Some(*angle_rad),
            _ => None,
        }
    }

    /// Standard error (rad) of the (candidate) angle, when known.
    pub fn se(&self) -> Option<f64> {
        match self {
            AngleEstimate::Determined { se_rad, .. }
            | AngleEstimate::Ambiguous { se_rad, .. }
            | AngleEstimate::Undetermined { se_rad, .. } => *se_rad,
        }
    }

    /// Apply the §1.5 rule: a determined angle whose standard error exceeds
    /// [`ANGLE_SE_LIMIT_RAD`] (or is not finite) becomes undetermined.
    pub fn checked(angle_rad: f64, se_rad: Option<f64>, offset_mm: f64) -> AngleEstimate {
        match se_rad {
            Some(se) if se.is_nan() || se >= ANGLE_SE_LIMIT_RAD => AngleEstimate::Undetermined {
                reason: format!(
                    "offset {:.4} µm is too small for the noise: σ_λ = {:.1}° exceeds the 10° limit of docs/methods.md §1.5",
                    offset_mm * 1e3,
                    se.to_degrees()
                ),
                rejected_rad: Some(angle_rad),
                se_rad: Some(se),
            },
            _ if offset_mm <= 0.0 => AngleEstimate::Undetermined {
                reason: "offset is zero: the angle is undefined".into(),
                rejected_rad: None,
                se_rad,
            },
            _ => AngleEstimate::Determined {
                angle_rad: crate::angle::wrap_pi(angle_rad),
                se_rad,
            },
        }
    }
}

/// Where the noise level σ_P used for the standard errors came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseSource {
    /// Given by the user (sensor specification).
    Given,
    /// Scatter of repeated readings of the same tooth (pooled).
    Repeats,
    /// Residual of the fit (degrees of freedom > 0).
    Residual,
    /// Not available: standard errors are not reported.
    Unknown,
}

/// Polar form (ρ, λ) of a vector e = (e_x, e_y) with covariance `cov` (mm²), with first-order
/// standard errors: σ_ρ² = uᵀCu, σ_λ² = vᵀCv/ρ², u = (cos λ, sin λ), v = (−sin λ, cos λ).
/// Returns (ρ, λ, σ_ρ, σ_λ).
///
/// ```
/// use runout_core::displacement::polar_with_covariance;
/// let c = nalgebra::Matrix2::new(1e-8, 0.0, 0.0, 1e-8);
/// let (r, l, sr, sl) = polar_with_covariance([0.0, 0.005], &c);
/// assert!((r - 0.005).abs() < 1e-15 && (l - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
/// assert!((sr - 1e-4).abs() < 1e-12 && (sl - 0.02).abs() < 1e-12);
/// ```
pub fn polar_with_covariance(e: [f64; 2], cov: &Matrix2<f64>) -> (f64, f64, f64, f64) {
    let rho = e[0].hypot(e[1]);
    let lambda = e[1].atan2(e[0]);
    let (s, c) = lambda.sin_cos();
    let var_rho = c * c * cov[(0, 0)] + 2.0 * s * c * cov[(0, 1)] + s * s * cov[(1, 1)];
    let var_t = s * s * cov[(0, 0)] - 2.0 * s * c * cov[(0, 1)] + c * c * cov[(1, 1)];
    let se_lambda = if rho > 0.0 {
        var_t.max(0.0).sqrt() / rho
    } else {
        f64::INFINITY
    };
    (rho, lambda, var_rho.max(0.0).sqrt(), se_lambda)
}
