//! What an identified runout does to the cut, methods.md §1.7.
//!
//! * Actual radius of every tooth: R_i(z) = |R(z)·u(ψ_i(z)) + e(z)| ([`Runout::tooth_radius`], eq. 0.1).
//! * Slot width W = 2·max_i R_i (static, no deflection); circular/helical hole of path diameter
//!   D_path: D_hole = D_path + 2·max_i R_i.
//! * Per-tooth chip load: the arc model (eq. 0.4) at φ = 90°,
//!   h_i = max(0, min_m [m·f_z + R_i − R_{i−m}]) ([`ArcChip`]); teeth with h_i = 0 do not cut.

use super::error::DisplacementError;
use crate::chip::{ArcChip, ChipThickness};
use crate::cutter::Cutter;
use crate::runout::Runout;
use serde::Serialize;
use std::f64::consts::FRAC_PI_2;

/// Predicted consequences of a runout at one height.
#[derive(Debug, Clone, Serialize)]
pub struct Consequences {
    /// Height z (mm).
    pub height_mm: f64,
    /// Actual radius R_i of every tooth (mm), teeth in cutting order.
    pub tooth_radii_mm: Vec<f64>,
    /// Slot width 2·max R_i (mm).
    pub slot_width_mm: f64,
    /// Hole diameter D_path + 2·max R_i (mm), when a path diameter was given.
    pub hole_diameter_mm: Option<f64>,
    /// Feed per tooth f_z (mm) used for `chip_load_mm`.
    pub fz_mm: Option<f64>,
    /// Largest chip thickness of every tooth (mm), arc model at φ = 90°.
    pub chip_load_mm: Option<Vec<f64>>,
}

/// Consequences of `runout` on `cutter` at height `z_mm`; `fz_mm` adds per-tooth chip loads,
/// `hole_path_diameter_mm` the hole diameter.
///
/// ```
/// use runout_core::{Cutter, Runout};
/// use runout_core::displacement::consequences;
/// let c = Cutter::flat(10.0, 2, 0.0).unwrap();
/// let r = Runout::new(0.010, 0.0).unwrap();
/// let q = consequences(&c, &r, 0.0, Some(0.005), None).unwrap();
/// assert!((q.slot_width_mm - 10.020).abs() < 1e-12);
/// // tooth 1 is 20 µm smaller: with f_z = 5 µm it never cuts, tooth 0 takes 2·f_z
/// let h = q.chip_load_mm.unwrap();
/// assert!((h[0] - 0.010).abs() < 1e-9 && h[1] == 0.0);
/// ```
pub fn consequences(
    cutter: &Cutter,
    runout: &Runout,
    z_mm: f64,
    fz_mm: Option<f64>,
    hole_path_diameter_mm: Option<f64>,
) -> Result<Consequences, DisplacementError> {
    if !z_mm.is_finite() {
        return Err(crate::ParamError::new("height_mm", "a finite number", z_mm).into());
    }
    if let Some(d) = hole_path_diameter_mm {
        if !(d.is_finite() && d >= 0.0) {
            return Err(crate::ParamError::new("hole_path_mm", "a finite number >= 0", d).into());
        }
    }
    let radii = runout.tooth_radii(cutter, z_mm);
    let max = radii.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let chip_load_mm = match fz_mm {
        Some(fz) => {
            let model = ArcChip::new(cutter, runout, fz)?;
            Some(
                (0..cutter.teeth())
                    .map(|i| model.thickness(i, z_mm, FRAC_PI_2))
                    .collect(),
            )
        }
        None => None,
    };
    Ok(Consequences {
        height_mm: z_mm,
        tooth_radii_mm: radii,
        slot_width_mm: 2.0 * max,
        hole_diameter_mm: hole_path_diameter_mm.map(|d| d + 2.0 * max),
        fz_mm,
        chip_load_mm,
    })
}
