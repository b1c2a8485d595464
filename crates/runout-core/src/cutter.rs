//! The cutter: diameter, teeth, pitch, helix and the radius profile R(z).
//!
//! Conventions (`conventions.md`, "Teeth and angles"): teeth are numbered `0..K-1` in cutting
//! order; tooth i sits at spindle-frame angle ψ_i = −Σ_{q<i} pitch_q at the tool tip (z = 0),
//! so uniform pitch gives ψ_i = −2πi/K; a right-hand helix lags by z·tan β / R.

use crate::error::{finite, ParamError};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Radius profile R(z) of the cutting edge envelope along the tool axis (z from the tip, mm).
///
/// Flat end mills are cylindrical; ball and bull-nose profiles are the hook for methods
/// that evaluate along the flank (chip thickness along a 5-axis path, grinding).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RadiusProfile {
    /// Cylinder of the nominal radius.
    Flat,
    /// Hemispherical end of the nominal radius: R(z) = sqrt(R² − (R − z)²) for z < R.
    Ball,
    /// Torus corner of radius `corner_mm`: cylinder above z = r_c.
    BullNose {
        /// Corner radius (mm), 0 < r_c ≤ R.
        corner_mm: f64,
    },
}

/// A milling cutter.
///
/// ```
/// use runout_core::Cutter;
/// let c = Cutter::flat(10.0, 4, 30.0).unwrap();
/// assert_eq!(c.teeth(), 4);
/// assert!((c.radius() - 5.0).abs() < 1e-15);
/// // tooth 1 of a uniform 4-tooth cutter sits at −90° at the tip
/// assert!((c.tooth_angle(1, 0.0).to_degrees() + 90.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Cutter {
    radius: f64,
    pitch: Vec<f64>,
    /// ψ_i at z = 0 (rad), ψ_0 = 0.
    tip_angles: Vec<f64>,
    tan_helix: f64,
    helix: f64,
    flute_length: f64,
    profile: RadiusProfile,
}

impl Cutter {
    /// Flat end mill with uniform pitch; `helix_deg` is the helix angle (0 for straight flutes).
    pub fn flat(diameter_mm: f64, teeth: usize, helix_deg: f64) -> Result<Self, ParamError> {
        crate::limits::teeth("teeth", teeth)?;
        let pitch = vec![TAU / teeth as f64; teeth];
        Self::new(
            diameter_mm,
            pitch,
            helix_deg,
            f64::INFINITY,
            RadiusProfile::Flat,
        )
    }

    /// General cutter. `pitch_rad[q]` is the angle from tooth q to tooth q+1 (cyclic), summing to 2π.
    /// `flute_length_mm` may be infinite (unbounded).
    pub fn new(
        diameter_mm: f64,
        pitch_rad: Vec<f64>,
        helix_deg: f64,
        flute_length_mm: f64,
        profile: RadiusProfile,
    ) -> Result<Self, ParamError> {
        let d = crate::limits::diameter("diameter_mm", diameter_mm)?;
        crate::limits::teeth("teeth", pitch_rad.len())?;
        for (q, p) in pitch_rad.iter().enumerate() {
            if !(p.is_finite() && *p > 0.0) {
                return Err(ParamError::new(
                    format!("pitch_deg[{q}]"),
                    "a finite angle > 0",
                    p.to_degrees(),
                ));
            }
        }
        let sum: f64 = pitch_rad.iter().sum();
        if (sum - TAU).abs() > 1e-6 {
            return Err(ParamError::new(
                "pitch_deg",
                "pitch angles summing to 360°",
                format!("sum {:.6}°", sum.to_degrees()),
            ));
        }
        let helix = finite("helix_deg", helix_deg)?;
        if !(-89.0..=89.0).contains(&helix) {
            return Err(ParamError::new(
                "helix_deg",
                "a helix angle in [-89°, 89°]",
                helix,
            ));
        }
        if flute_length_mm.is_nan() || flute_length_mm <= 0.0 {
            return Err(ParamError::new(
                "flute_length_mm",
                "a length > 0 (mm)",
                flute_length_mm,
            ));
        }
        let radius = d / 2.0;
        if let RadiusProfile::BullNose { corner_mm } = profile {
            if !(corner_mm > 0.0 && corner_mm <= radius) {
                return Err(ParamError::new(
                    "corner_mm",
                    format!("a corner radius in (0, {radius}] mm"),
                    corner_mm,
                ));
            }
        }
        let mut tip_angles = Vec::with_capacity(pitch_rad.len());
        let mut acc = 0.0;
        for p in &pitch_rad {
            tip_angles.push(-acc);
            acc += p;
        }
        Ok(Cutter {
            radius,
            pitch: pitch_rad,
            tip_angles,
            tan_helix: helix.to_radians().tan(),
            helix: helix.to_radians(),
            flute_length: flute_length_mm,
            profile,
        })
    }

    /// Nominal radius R (mm).
    pub fn radius(&self) -> f64 {
        self.radius
    }
    /// Nominal diameter (mm).
    pub fn diameter(&self) -> f64 {
        2.0 * self.radius
    }
    /// Number of teeth K.
    pub fn teeth(&self) -> usize {
        self.pitch.len()
    }
    /// Pitch angles (rad): `pitch()[q]` from tooth q to tooth q+1.
    pub fn pitch(&self) -> &[f64] {
        &self.pitch
    }
    /// True when all pitch angles are equal.
    pub fn is_uniform_pitch(&self) -> bool {
        let p0 = self.pitch[0];
        self.pitch.iter().all(|p| (p - p0).abs() < 1e-12)
    }
    /// Helix angle β (rad).
    pub fn helix(&self) -> f64 {
        self.helix
    }
    /// tan β.
    pub fn tan_helix(&self) -> f64 {
        self.tan_helix
    }
    /// Flute length (mm); infinite when not given.
    pub fn flute_length(&self) -> f64 {
        self.flute_length
    }
    /// Radius profile.
    pub fn profile(&self) -> &RadiusProfile {
        &self.profile
    }

    /// Spindle-frame angle ψ_i(z) of tooth `i` at height `z` (rad):
    /// ψ_i(z) = ψ_i − z·tan β / R (`conventions.md`, right-hand helix).
    #[inline]
    pub fn tooth_angle(&self, i: usize, z: f64) -> f64 {
        self.tip_angles[i] - z * self.tan_helix / self.radius
    }

    /// Angular gap (rad, in (0, 2π]) from tooth `i − m` to tooth `i` (cyclic), i.e. how far
    /// the spindle turns between their passes; m = K gives 2π.
    pub fn gap(&self, i: usize, m: usize) -> f64 {
        let k = self.teeth();
        (0..m).map(|q| self.pitch[(i + k * m - 1 - q) % k]).sum()
    }

    /// Nominal envelope radius R(z) (mm) of the profile at height z ≥ 0 from the tip.
    ///
    /// ```
    /// use runout_core::{Cutter, RadiusProfile};
    /// let ball = Cutter::new(10.0, vec![std::f64::consts::PI; 2], 0.0, 20.0, RadiusProfile::Ball).unwrap();
    /// assert!((ball.radius_at(5.0) - 5.0).abs() < 1e-12);
    /// assert!((ball.radius_at(1.0) - 3.0).abs() < 1e-12);
    /// ```
    pub fn radius_at(&self, z: f64) -> f64 {
        let r = self.radius;
        match self.profile {
            RadiusProfile::Flat => r,
            RadiusProfile::Ball => {
                if z >= r {
                    r
                } else {
                    let zc = z.max(0.0);
                    (r * r - (r - zc) * (r - zc)).max(0.0).sqrt()
                }
            }
            RadiusProfile::BullNose { corner_mm: rc } => {
                if z >= rc {
                    r
                } else {
                    let zc = z.max(0.0);
                    (r - rc) + (rc * rc - (rc - zc) * (rc - zc)).max(0.0).sqrt()
                }
            }
        }
    }
}
