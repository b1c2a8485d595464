//! Runout: the vector **e** from the spindle axis to the tool's geometric axis.
//!
//! `conventions.md`, "Runout": e = ρ·(cos λ, sin λ) in the spindle frame, ρ ≥ 0, λ measured from
//! tooth 0 in the direction of rotation; optional tilt: e(z) = e₀ + z·τ.
//! Actual radius of tooth i (methods.md eq. 0.1): R_i(z) = |R(z)·u(ψ_i(z)) + e(z)|.

use crate::cutter::Cutter;
use crate::error::{finite, non_negative, ParamError};
use std::f64::consts::PI;

/// Parallel-offset (and optionally tilt) runout of a cutter.
///
/// ```
/// use runout_core::Runout;
/// let r = Runout::new(0.008, 30f64.to_radians()).unwrap();
/// assert!((r.offset_um() - 8.0).abs() < 1e-12);
/// let [ex, ey] = r.vector_at(0.0);
/// assert!((ex - 0.008 * 30f64.to_radians().cos()).abs() < 1e-15 && ey > 0.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Runout {
    offset: f64,
    angle: f64,
    /// Tilt τ (mm per mm of height) as a spindle-frame vector.
    tilt: [f64; 2],
}

impl Runout {
    /// No runout.
    pub fn none() -> Self {
        Runout::default()
    }

    /// Offset ρ (mm, ≥ 0) at angle λ (rad).
    pub fn new(offset_mm: f64, angle_rad: f64) -> Result<Self, ParamError> {
        if !(offset_mm.is_finite() && offset_mm >= 0.0) {
            return Err(ParamError::new(
                "runout_um",
                "a finite offset >= 0 µm",
                offset_mm * 1e3,
            ));
        }
        finite("runout_angle_deg", angle_rad)?;
        Ok(Runout {
            offset: offset_mm,
            angle: angle_rad,
            tilt: [0.0; 2],
        })
    }

    /// Offset given as a spindle-frame vector (mm).
    pub fn from_vector(e: [f64; 2]) -> Self {
        Runout {
            offset: e[0].hypot(e[1]),
            angle: e[1].atan2(e[0]),
            tilt: [0.0; 2],
        }
    }

    /// Add a tilt: τ of magnitude `tilt_mm_per_mm` at spindle-frame angle `tilt_angle_rad`.
    pub fn with_tilt(
        mut self,
        tilt_mm_per_mm: f64,
        tilt_angle_rad: f64,
    ) -> Result<Self, ParamError> {
        non_negative("tilt_um_per_mm", tilt_mm_per_mm)?;
        finite("tilt_angle_deg", tilt_angle_rad)?;
        self.tilt = [
            tilt_mm_per_mm * tilt_angle_rad.cos(),
            tilt_mm_per_mm * tilt_angle_rad.sin(),
        ];
        Ok(self)
    }

    /// Add a tilt given as a spindle-frame vector (mm/mm).
    pub fn with_tilt_vector(mut self, tau: [f64; 2]) -> Self {
        self.tilt = tau;
        self
    }

    /// Offset ρ (mm) at the tip, z = 0.
    pub fn offset(&self) -> f64 {
        self.offset
    }
    /// Offset ρ in µm.
    pub fn offset_um(&self) -> f64 {
        self.offset * 1e3
    }
    /// Angle λ (rad) at z = 0.
    pub fn angle(&self) -> f64 {
        self.angle
    }
    /// Tilt vector τ (mm/mm).
    pub fn tilt(&self) -> [f64; 2] {
        self.tilt
    }
    /// True when there is a non-zero tilt.
    pub fn has_tilt(&self) -> bool {
        self.tilt != [0.0, 0.0]
    }

    /// e(z) = e₀ + z·τ (mm, spindle frame).
    #[inline]
    pub fn vector_at(&self, z: f64) -> [f64; 2] {
        [
            self.offset * self.angle.cos() + z * self.tilt[0],
            self.offset * self.angle.sin() + z * self.tilt[1],
        ]
    }

    /// Exact actual cutting radius of tooth `i` at height `z` (mm), methods.md eq. (0.1):
    /// R_i(z) = |R(z)·u(ψ_i(z)) + e(z)|.
    ///
    /// ```
    /// use runout_core::{Cutter, Runout};
    /// // methods.md §7: R 0.25 mm, r 5 µm, θ 60°, K 2 → 0.252537126, 0.247537876
    /// let c = Cutter::flat(0.5, 2, 0.0).unwrap();
    /// let r = Runout::new(0.005, 60f64.to_radians()).unwrap();
    /// assert!((r.tooth_radius(&c, 0, 0.0) - 0.252537126).abs() < 1e-9);
    /// assert!((r.tooth_radius(&c, 1, 0.0) - 0.247537876).abs() < 1e-9);
    /// ```
    #[inline]
    pub fn tooth_radius(&self, cutter: &Cutter, i: usize, z: f64) -> f64 {
        let (x, y) = self.tooth_point(cutter, i, z);
        x.hypot(y)
    }

    /// Spindle-frame position (mm) of tooth `i`'s edge point at height `z` relative to the spindle axis.
    #[inline]
    pub fn tooth_point(&self, cutter: &Cutter, i: usize, z: f64) -> (f64, f64) {
        let psi = cutter.tooth_angle(i, z);
        let r = cutter.radius_at(z);
        let e = self.vector_at(z);
        (r * psi.cos() + e[0], r * psi.sin() + e[1])
    }

    /// Angular shift δ_i (rad) of the effective edge relative to the nominal edge, methods.md eq. (0.2).
    #[inline]
    pub fn tooth_phase_shift(&self, cutter: &Cutter, i: usize, z: f64) -> f64 {
        let (x, y) = self.tooth_point(cutter, i, z);
        let psi = cutter.tooth_angle(i, z);
        crate::angle::wrap_pi(y.atan2(x) - psi)
    }

    /// First-order actual radius (mm), methods.md eq. (0.3): R_i ≈ R(z) + e(z)·u(ψ_i(z)).
    #[inline]
    pub fn tooth_radius_first_order(&self, cutter: &Cutter, i: usize, z: f64) -> f64 {
        let psi = cutter.tooth_angle(i, z);
        let e = self.vector_at(z);
        cutter.radius_at(z) + e[0] * psi.cos() + e[1] * psi.sin()
    }

    /// Actual radii of all teeth at height `z` (mm).
    pub fn tooth_radii(&self, cutter: &Cutter, z: f64) -> Vec<f64> {
        (0..cutter.teeth())
            .map(|i| self.tooth_radius(cutter, i, z))
            .collect()
    }
}

/// Conversions between this toolkit's runout angle λ and the conventions of the source documents
/// (methods.md §0, conventions.md "Mapping of the published conventions").
pub mod seed {
    use super::*;

    /// Seed 003: the fitted sine phase φ of F_i = C + A·sin(φ + 2πi/K) gives λ = φ − π + π/K.
    ///
    /// ```
    /// use runout_core::runout::seed::lambda_from_seed003_phase;
    /// // Table 2 test 1: φ = 100.05° → α₀ = λ = −34.95°
    /// let l = lambda_from_seed003_phase(100.05f64.to_radians(), 4);
    /// assert!((l.to_degrees() + 34.95).abs() < 1e-9);
    /// ```
    pub fn lambda_from_seed003_phase(phase_rad: f64, teeth: usize) -> f64 {
        crate::angle::wrap_pi(phase_rad - PI + PI / teeth as f64)
    }

    /// Inverse of [`lambda_from_seed003_phase`].
    pub fn seed003_phase_from_lambda(lambda_rad: f64, teeth: usize) -> f64 {
        crate::angle::wrap_tau(lambda_rad + PI - PI / teeth as f64)
    }

    /// Seed 003's α₀ equals λ.
    pub fn lambda_from_seed003_alpha0(alpha0_rad: f64) -> f64 {
        alpha0_rad
    }

    /// Seed 000: θ = λ, r = ρ.
    pub fn lambda_from_seed000_theta(theta_rad: f64) -> f64 {
        theta_rad
    }

    /// Seed 000 edge k (1-based, counted against cutting order) is our tooth (1 − k) mod K.
    ///
    /// ```
    /// use runout_core::runout::seed::{tooth_from_seed000_edge, seed000_edge_from_tooth};
    /// assert_eq!(tooth_from_seed000_edge(1, 4), Some(0));
    /// assert_eq!(tooth_from_seed000_edge(2, 4), Some(3));
    /// assert_eq!(tooth_from_seed000_edge(5, 4), None);
    /// assert_eq!(seed000_edge_from_tooth(3, 4), 2);
    /// ```
    /// Returns `None` when `k` is not in `1..=K`.
    pub fn tooth_from_seed000_edge(k: usize, teeth: usize) -> Option<usize> {
        (k >= 1 && k <= teeth).then(|| (teeth + 1 - k) % teeth)
    }

    /// Inverse of [`tooth_from_seed000_edge`].
    pub fn seed000_edge_from_tooth(i: usize, teeth: usize) -> usize {
        (teeth - i % teeth) % teeth + 1
    }
}
