//! Sensor beam geometry corrections, methods.md §1.4 (seed eq. 9).
//!
//! * Inclination α_i of the beam to the surface normal: a radial displacement ΔL is seen as
//!   ΔL′ = ΔL·sec α_i, so ΔL = ΔL′·cos α_i (seed eq. 9: δ = ΔL − ΔL′ = ΔL(1 − sec α)).
//! * Beam parallel to the radial direction but offset by b from the axis, on a tool of radius R:
//!   it hits the surface where the normal is at α_b = asin(b/R); a centre offset e is seen with
//!   amplitude e·R/sqrt(R² − b²) = e·sec α_b and its direction is the normal's, rotated by α_b.

use super::error::DisplacementError;
use crate::error::{finite, ParamError};

/// Beam inclination and lateral offset of a displacement sensor (methods.md §1.4).
///
/// ```
/// use runout_core::displacement::BeamGeometry;
/// // b = 50 µm on R = 250 µm: the sensor sees the runout +2.06 % too large
/// let beam = BeamGeometry::new(0.0, 0.050).unwrap();
/// let f = beam.amplitude_factor(0.25).unwrap();
/// assert!((1.0 / f - 1.0206).abs() < 1e-4);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BeamGeometry {
    inclination: f64,
    offset: f64,
}

impl BeamGeometry {
    /// A perpendicular beam aimed through the axis (no correction).
    pub fn ideal() -> Self {
        BeamGeometry::default()
    }

    /// Beam inclined by `inclination_rad` (|α| < 90°) to the surface normal and offset laterally by
    /// `offset_mm` from the spindle axis (positive towards increasing sensor angle).
    pub fn new(inclination_rad: f64, offset_mm: f64) -> Result<Self, ParamError> {
        finite("inclination_deg", inclination_rad)?;
        finite("beam_offset_mm", offset_mm)?;
        if inclination_rad.abs() >= 80f64.to_radians() {
            return Err(ParamError::new(
                "inclination_deg",
                "an angle with |α| < 80°",
                inclination_rad.to_degrees(),
            ));
        }
        Ok(BeamGeometry {
            inclination: inclination_rad,
            offset: offset_mm,
        })
    }

    /// Inclination α_i (rad).
    pub fn inclination(&self) -> f64 {
        self.inclination
    }

    /// Lateral beam offset b (mm).
    pub fn offset(&self) -> f64 {
        self.offset
    }

    /// Factor that turns a displacement seen along the beam into a radial displacement of the
    /// measured surface of radius `radius_mm`: cos α_i · sqrt(R² − b²)/R (methods.md §1.4).
    pub fn amplitude_factor(&self, radius_mm: f64) -> Result<f64, DisplacementError> {
        Ok(self.inclination.cos() * self.offset_cosine(radius_mm)?)
    }

    /// Rotation α_b = asin(b/R) (rad) of the effective sensing direction caused by the lateral beam
    /// offset, in the sense of increasing sensor angle (methods.md §1.4).
    pub fn direction_shift(&self, radius_mm: f64) -> Result<f64, DisplacementError> {
        self.offset_cosine(radius_mm)?;
        Ok((self.offset / radius_mm).asin())
    }

    fn offset_cosine(&self, radius_mm: f64) -> Result<f64, DisplacementError> {
        if !(radius_mm.is_finite() && radius_mm > 0.0) {
            return Err(ParamError::new("radius_mm", "a finite number > 0", radius_mm).into());
        }
        if self.offset.abs() >= 0.9 * radius_mm {
            return Err(ParamError::new(
                "beam_offset_mm",
                format!(
                    "|b| < 0.9·R = {:.4} mm (the beam must hit the tool near its axis)",
                    0.9 * radius_mm
                ),
                self.offset,
            )
            .into());
        }
        let s = self.offset / radius_mm;
        Ok((1.0 - s * s).sqrt())
    }
}
