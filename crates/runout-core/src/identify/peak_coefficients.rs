//! Lumped tangential/radial coefficients K_T, K_R from the nominal forces at the peak angle,
//! seed 003 eq. (17).
//!
//! Seed eq. (17) (up-milling, immersion θ ∈ [0, β]):
//! F̄_x(θ) = f_z·a_p·sin θ·(K_R·sin θ + K_T·cos θ),
//! F̄_y(θ) = f_z·a_p·sin θ·(−K_R·cos θ + K_T·sin θ)   (seed frame).
//!
//! In this toolkit's workpiece frame (`conventions.md`, forces on the workpiece,
//! F_y = −F_t sin φ + F_r cos φ) the y row has the **opposite sign**: F_y = −F_y(seed).
//! This function takes F_y in the workpiece frame. Inverting the rotation:
//! K_R = (F̄_x sin θ + F̄_y cos θ)/(f a sin θ), K_T = (F̄_x cos θ − F̄_y sin θ)/(f a sin θ),
//! K = hypot(K_T, K_R).

use crate::error::{finite, positive, ParamError};
use serde::Serialize;

/// K_T, K_R (N/mm²) and their resultant K from seed eq. (17).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PeakCoefficients {
    /// Tangential coefficient K_T (N/mm²).
    pub kt: f64,
    /// Radial coefficient K_R (N/mm²).
    pub kr: f64,
    /// Resultant K = hypot(K_T, K_R) (N/mm²), seed eq. (18).
    pub k: f64,
}

/// Solve seed eq. (17) for K_T, K_R from the nominal forces F̄_x, F̄_y (N, **workpiece frame**) at
/// immersion `theta_rad` with feed `fz_mm` and axial depth `ap_mm`.
///
/// ```
/// use runout_core::identify::coefficients_at_peak;
/// // seed 003 test 1: F̄_x(β) = 315.9 N, F̄_y(β) = 89.3 N (seed frame) → K_T ≈ 4077.8, K_R ≈ 3111.6
/// let beta = (3.0f64 / 5.0).acos();
/// let k = coefficients_at_peak(315.9, -89.3, beta, 0.08, 1.0).unwrap();
/// assert!((k.kt - 4077.8).abs() < 0.5 && (k.kr - 3111.6).abs() < 0.5);
/// ```
pub fn coefficients_at_peak(
    fx_n: f64,
    fy_n: f64,
    theta_rad: f64,
    fz_mm: f64,
    ap_mm: f64,
) -> Result<PeakCoefficients, ParamError> {
    finite("fx_at_peak_N", fx_n)?;
    finite("fy_at_peak_N", fy_n)?;
    positive("fz_mm", fz_mm)?;
    positive("ap_mm", ap_mm)?;
    let (s, c) = theta_rad.sin_cos();
    if s.is_nan() || s <= 1e-6 {
        return Err(ParamError::new(
            "peak_immersion_deg",
            "an angle with sin θ > 0",
            theta_rad.to_degrees(),
        ));
    }
    let q = fz_mm * ap_mm * s;
    let kr = (fx_n * s + fy_n * c) / q;
    let kt = (fx_n * c - fy_n * s) / q;
    Ok(PeakCoefficients {
        kt,
        kr,
        k: kt.hypot(kr),
    })
}
