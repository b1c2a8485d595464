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
    /// Tapered (conical) flank with a flat bottom: R(z) = R + z·tan α, α = `taper_deg`;
    /// the nominal diameter is the diameter at the tip.
    Tapered {
        /// Taper (half-cone) angle α (deg), 0 < α < 45.
        taper_deg: f64,
    },
}

/// How the flute is wound along a non-cylindrical envelope (Engin & Altintas 2001, §2.2).
///
/// On the cylinder both are the same: lag ψ(z) = z·tan β / R.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FluteLead {
    /// Constant lead (the usual ball-end grind, Lee & Altintas 1996): ψ(z) = z·tan β₀ / R₀, the
    /// local helix angle varies, tan β(z) = R(z)·tan β₀ / R₀.
    #[default]
    ConstantLead,
    /// Constant helix angle β₀ along the edge: dψ = tan β₀ · ds / R(z), ds the arc length of the
    /// envelope's generator (E&A eq. for the helical flute with constant helix angle).
    ConstantHelix,
}

/// A milling cutter.
///
/// ```
/// use runout_core::Cutter;
/// let c = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
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
    lead: FluteLead,
}

impl Cutter {
    /// Flat end mill with uniform pitch; `helix_rad` is the helix angle in radians (0 for
    /// straight flutes; conventions.md: radians inside the library, degrees at the interface).
    pub fn flat(diameter_mm: f64, teeth: usize, helix_rad: f64) -> Result<Self, ParamError> {
        crate::limits::teeth("teeth", teeth)?;
        let pitch = vec![TAU / teeth as f64; teeth];
        Self::new(
            diameter_mm,
            pitch,
            helix_rad,
            f64::INFINITY,
            RadiusProfile::Flat,
        )
    }

    /// General cutter. `pitch_rad[q]` is the angle from tooth q to tooth q+1 (cyclic), summing to 2π;
    /// `helix_rad` is the helix angle, |β| ≤ 89° (both in radians, conventions.md). Errors name
    /// the interface keys (`pitch_deg`, `helix_deg`) with the values in degrees.
    /// `flute_length_mm` may be infinite (unbounded).
    pub fn new(
        diameter_mm: f64,
        pitch_rad: Vec<f64>,
        helix_rad: f64,
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
        let helix = finite("helix_deg", helix_rad)?;
        if helix.abs() > 89f64.to_radians() {
            return Err(ParamError::new(
                "helix_deg",
                "a helix angle in [-89°, 89°]",
                helix.to_degrees(),
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
        match profile {
            RadiusProfile::BullNose { corner_mm } => {
                if !(corner_mm > 0.0 && corner_mm <= radius) {
                    return Err(ParamError::new(
                        "corner_radius_mm",
                        format!("a corner radius in (0, R = {radius}] mm"),
                        corner_mm,
                    ));
                }
            }
            RadiusProfile::Tapered { taper_deg } => {
                if !(taper_deg > 0.0 && taper_deg < 45.0) {
                    return Err(ParamError::new(
                        "taper_deg",
                        "a taper (half-cone) angle in (0, 45) degrees",
                        taper_deg,
                    ));
                }
            }
            RadiusProfile::Flat | RadiusProfile::Ball => {}
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
            tan_helix: helix.tan(),
            helix,
            flute_length: flute_length_mm,
            profile,
            lead: FluteLead::ConstantLead,
        })
    }

    /// The same cutter with flutes wound as `lead` (default [`FluteLead::ConstantLead`]).
    pub fn with_lead(mut self, lead: FluteLead) -> Self {
        self.lead = lead;
        self
    }

    /// How the flutes are wound.
    pub fn lead(&self) -> FluteLead {
        self.lead
    }

    /// True for a cylindrical cutter (κ = 90° at every height).
    pub fn is_flat(&self) -> bool {
        matches!(self.profile, RadiusProfile::Flat)
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
    /// ψ_i(z) = ψ_i − lag(z) (`conventions.md`, right-hand helix); for a flat end mill and for
    /// constant-lead flutes lag(z) = z·tan β / R, see [`Cutter::lag`].
    #[inline]
    pub fn tooth_angle(&self, i: usize, z: f64) -> f64 {
        match self.lead {
            FluteLead::ConstantLead => self.tip_angles[i] - z * self.tan_helix / self.radius,
            FluteLead::ConstantHelix => self.tip_angles[i] - self.lag(z),
        }
    }

    /// Lag angle ψ(z) (rad) of a flute at height z relative to the tip (Engin & Altintas 2001,
    /// "Mechanics and dynamics of general milling cutters, Part I", §2.2):
    ///
    /// * constant lead (and every flat end mill): ψ(z) = z·tan β₀ / R₀;
    /// * constant helix: dψ/dz = tan β₀ / (R(z)·sin κ(z)) (ds = dz / sin κ along the generator):
    ///   - tapered: ψ(z) = tan β₀ · ln(R(z)/R₀) / sin α;
    ///   - ball: ψ(z) = tan β₀ · (1 + ln tan(κ(z)/2)) below the equator (z < R; κ = 90° there,
    ///     continuous with the cylinder above, ψ = z·tan β₀/R₀ for z ≥ R), −∞ at the tip, where
    ///     no constant-helix flute can reach; evaluated at z ≥ 1e-9 mm;
    ///   - bull nose: cylinder above the corner, ψ(z) = ψ(r_c) − tan β₀ ∫_κ^{π/2} r_c dκ′ /
    ///     (R − r_c + r_c sin κ′) in the corner (Simpson, 64 intervals).
    pub fn lag(&self, z: f64) -> f64 {
        let t = self.tan_helix;
        let r = self.radius;
        if self.lead == FluteLead::ConstantLead || t == 0.0 {
            return z * t / r;
        }
        match self.profile {
            RadiusProfile::Flat => z * t / r,
            RadiusProfile::Tapered { taper_deg } => {
                let a = taper_deg.to_radians();
                t * (self.radius_at(z) / r).ln() / a.sin()
            }
            RadiusProfile::Ball => {
                if z >= r {
                    z * t / r
                } else {
                    let kappa = self.lead_angle(z.max(1e-9));
                    t * (1.0 + (kappa / 2.0).tan().ln())
                }
            }
            RadiusProfile::BullNose { corner_mm: rc } => {
                if z >= rc {
                    z * t / r
                } else {
                    let k0 = self.lead_angle(z.max(0.0));
                    let f = |k: f64| rc / (r - rc + rc * k.sin());
                    let n = 64;
                    let hstep = (std::f64::consts::FRAC_PI_2 - k0) / n as f64;
                    let mut acc = f(k0) + f(std::f64::consts::FRAC_PI_2);
                    for q in 1..n {
                        let w = if q % 2 == 1 { 4.0 } else { 2.0 };
                        acc += w * f(k0 + q as f64 * hstep);
                    }
                    rc * t / r - t * acc * hstep / 3.0
                }
            }
        }
    }

    /// dψ/dz (rad/mm), the slope of [`Cutter::lag`]: tan β₀ / R₀ for constant-lead flutes (and
    /// every flat end mill), tan β₀ / (R(z)·sin κ(z)) for constant-helix flutes (Engin &
    /// Altintas 2001, §2.2), evaluated at z ≥ 1e-9 mm (the ball's tip is singular).
    ///
    /// ```
    /// use runout_core::{Cutter, RadiusProfile};
    /// let c = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
    /// assert!((c.lag_slope(2.0) - 30f64.to_radians().tan() / 5.0).abs() < 1e-15);
    /// ```
    pub fn lag_slope(&self, z: f64) -> f64 {
        let t = self.tan_helix;
        if self.lead == FluteLead::ConstantLead || t == 0.0 {
            return t / self.radius;
        }
        let z = z.max(1e-9);
        let (sin_kappa, _) = self.lead_sin_cos(z);
        t / (self.radius_at(z) * sin_kappa)
    }

    /// Axial immersion (lead) angle κ(z) (rad) between the tool axis and the outward normal of
    /// the envelope at height z (Lee & Altintas 1996; Engin & Altintas 2001): 90° on a
    /// cylinder; ball: sin κ = R(z)/R, cos κ = (R − z)/R; bull nose: sin κ = (R(z) − R + r_c)/r_c
    /// in the corner; tapered: κ = 90° − α. The chip thickness normal to the edge is h·sin κ.
    ///
    /// ```
    /// use runout_core::{Cutter, RadiusProfile};
    /// let ball = Cutter::new(6.0, vec![std::f64::consts::TAU / 3.0; 3], 30.0f64.to_radians(), 20.0, RadiusProfile::Ball).unwrap();
    /// // at z = R/2 the sphere's normal is 60° from the axis
    /// assert!((ball.lead_angle(1.5).to_degrees() - 60.0).abs() < 1e-9);
    /// ```
    pub fn lead_angle(&self, z: f64) -> f64 {
        let (s, c) = self.lead_sin_cos(z);
        s.atan2(c)
    }

    /// Arc length (mm) of the envelope's generator from the tip (z = 0) to height z: the edge
    /// length per unit of flute lag, ∫₀^z dz′/sin κ(z′) (E&A's dS without the helical part):
    /// ball R·κ(z) below the equator, bull nose r_c·κ(z) in the corner, tapered z/cos α,
    /// cylinder z (continued above a ball or corner). The flat bottom of a bull nose or taper
    /// (κ = 0, no height) is not part of it.
    pub fn arc_length(&self, z: f64) -> f64 {
        let z = z.max(0.0);
        let corner = |rc: f64| {
            if z >= rc {
                rc * std::f64::consts::FRAC_PI_2 + (z - rc)
            } else {
                rc * self.lead_angle(z)
            }
        };
        match self.profile {
            RadiusProfile::Flat => z,
            RadiusProfile::Ball => corner(self.radius),
            RadiusProfile::BullNose { corner_mm } => corner(corner_mm),
            RadiusProfile::Tapered { taper_deg } => z / taper_deg.to_radians().cos(),
        }
    }

    /// (sin κ, cos κ) at height z, see [`Cutter::lead_angle`]; exactly (1, 0) on a cylinder.
    pub fn lead_sin_cos(&self, z: f64) -> (f64, f64) {
        let r = self.radius;
        let corner = |rc: f64| {
            if z >= rc {
                (1.0, 0.0)
            } else {
                let zc = z.max(0.0);
                let c = (rc - zc) / rc;
                ((1.0 - c * c).max(0.0).sqrt(), c)
            }
        };
        match self.profile {
            RadiusProfile::Flat => (1.0, 0.0),
            RadiusProfile::Ball => corner(r),
            RadiusProfile::BullNose { corner_mm } => corner(corner_mm),
            RadiusProfile::Tapered { taper_deg } => {
                let a = taper_deg.to_radians();
                (a.cos(), a.sin())
            }
        }
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
            RadiusProfile::Tapered { taper_deg } => r + z.max(0.0) * taper_deg.to_radians().tan(),
        }
    }
}
