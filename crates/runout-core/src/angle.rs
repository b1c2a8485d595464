//! Angle helpers. Inside the library angles are radians; degrees only at the interface
//! (`docs/conventions.md`, "Units").

use std::f64::consts::TAU;

/// Wrap an angle into `[0, 2π)`.
///
/// ```
/// use runout_core::angle::wrap_tau;
/// assert!((wrap_tau(-0.5) - (std::f64::consts::TAU - 0.5)).abs() < 1e-15);
/// ```
#[inline]
pub fn wrap_tau(a: f64) -> f64 {
    let w = a - TAU * (a / TAU).floor();
    if w >= TAU {
        0.0
    } else {
        w
    }
}

/// Wrap an angle into `(-π, π]`.
///
/// ```
/// use runout_core::angle::wrap_pi;
/// assert!((wrap_pi(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
/// ```
#[inline]
pub fn wrap_pi(a: f64) -> f64 {
    let w = wrap_tau(a);
    if w > std::f64::consts::PI {
        w - TAU
    } else {
        w
    }
}

/// Wrap an angle in degrees into `(-180, 180]`.
#[inline]
pub fn wrap_deg180(a: f64) -> f64 {
    wrap_pi(a.to_radians()).to_degrees()
}
