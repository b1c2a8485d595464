//! Shank stiffness from beam theory (methods.md §3.1).
//!
//! Euler–Bernoulli cantilever clamped at the holder face (x = 0), point load F at x = a,
//! uniform E·I over the measured part, I = π·d⁴/64. Deflection per unit load
//! y(x)/F = x²(3a − x)/(6EI) for x ≤ a and a²(3x − a)/(6EI) for x > a; with a holder of rotational
//! stiffness k_θ the clamp turns by F·a/k_θ and adds x·a/k_θ (holder translation cancels in the
//! difference). The relative deflection of sensor II (l_II) w.r.t. sensor I (l_I) is
//! Δ = F·[c(l_II) − c(l_I)], so
//!
//! K_δ = F/Δ = 6EI / [l_II²(3a − l_II) − l_I²(3a − l_I) + 6EI·(l_II − l_I)·a/k_θ]   (methods.md §3.1)
//!
//! which for a = l_tool and k_θ = ∞ is the patent's formula (1.948754 and 17.287361 N/µm for its
//! two worked examples, methods.md §7).

use crate::error::{positive, ParamError};
use crate::limits::{
    show, within, MAX_HOLDER_STIFFNESS_NM_PER_RAD, MAX_MODULUS_GPA,
    MIN_HOLDER_STIFFNESS_NM_PER_RAD, MIN_MODULUS_GPA, MIN_SENSOR_GAP_MM,
};

/// Where the resultant cutting force acts on the tool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadPoint {
    /// At the tool end, a = l_tool (the patent's assumption).
    Tip,
    /// At mid axial depth, a = l_tool − a_p/2 (methods.md §3.1 option).
    MidDepth {
        /// Axial depth of cut a_p, mm.
        axial_depth_mm: f64,
    },
    /// At a given distance from the holder face, mm.
    At {
        /// a, mm from the holder face.
        distance_mm: f64,
    },
}

/// The tool shank as a cantilever with two displacement sensors (heights from the holder face).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShankBeam {
    /// Young's modulus E, N/mm² (= MPa; 210 GPa = 210 000 N/mm²).
    pub modulus_n_per_mm2: f64,
    /// Shank diameter d, mm.
    pub diameter_mm: f64,
    /// Tool length from the holder face to the tool end l_tool, mm.
    pub tool_length_mm: f64,
    /// Height of sensor I (nearer the holder) from the holder face l_I, mm.
    pub l1_mm: f64,
    /// Height of sensor II (nearer the tip) from the holder face l_II, mm.
    pub l2_mm: f64,
    /// Load point.
    pub load_point: LoadPoint,
    /// Rotational stiffness of the holder k_θ, N·mm/rad (`None` = rigid clamp).
    pub holder_rotational_stiffness_nmm_per_rad: Option<f64>,
}

impl ShankBeam {
    /// A shank with a rigid clamp and the load at the tip (the patent's model). `modulus_gpa` in
    /// GPa; lengths in mm. Errors: non-positive values, l_I = l_II, l_I > l_II, l_II > l_tool.
    pub fn new(
        modulus_gpa: f64,
        diameter_mm: f64,
        tool_length_mm: f64,
        l1_mm: f64,
        l2_mm: f64,
    ) -> Result<Self, ParamError> {
        let beam = ShankBeam {
            modulus_n_per_mm2: within(
                "modulus_gpa",
                modulus_gpa,
                MIN_MODULUS_GPA,
                MAX_MODULUS_GPA,
                "GPa",
            )? * 1e3,
            diameter_mm: crate::limits::diameter("diameter_mm", diameter_mm)?,
            tool_length_mm: positive("tool_length_mm", tool_length_mm)?,
            l1_mm,
            l2_mm,
            load_point: LoadPoint::Tip,
            holder_rotational_stiffness_nmm_per_rad: None,
        };
        beam.validate()?;
        Ok(beam)
    }

    /// The same shank with another load point (checked: sensors between holder and tool end,
    /// load point within the tool).
    pub fn with_load_point(mut self, load_point: LoadPoint) -> Result<Self, ParamError> {
        self.load_point = load_point;
        self.validate()?;
        Ok(self)
    }

    /// The same shank in a holder of rotational stiffness k_θ (N·mm/rad). Checked in the unit
    /// users give it, N·m/rad (`holder_stiffness_Nm_per_rad`, in
    /// [[`MIN_HOLDER_STIFFNESS_NM_PER_RAD`], [`MAX_HOLDER_STIFFNESS_NM_PER_RAD`]]).
    pub fn with_holder_stiffness(mut self, k_theta_nmm_per_rad: f64) -> Result<Self, ParamError> {
        within(
            "holder_stiffness_Nm_per_rad",
            k_theta_nmm_per_rad / 1e3,
            MIN_HOLDER_STIFFNESS_NM_PER_RAD,
            MAX_HOLDER_STIFFNESS_NM_PER_RAD,
            "N·m/rad",
        )?;
        self.holder_rotational_stiffness_nmm_per_rad = Some(k_theta_nmm_per_rad);
        self.validate()?;
        Ok(self)
    }

    /// [`ShankBeam::with_holder_stiffness`] with k_θ in N·m/rad, the unit users give it: checked
    /// before the conversion, so that an error shows the value as given (1e308 N·m/rad is
    /// ∞ N·mm/rad).
    pub fn with_holder_stiffness_nm_per_rad(
        self,
        k_theta_nm_per_rad: f64,
    ) -> Result<Self, ParamError> {
        within(
            "holder_stiffness_Nm_per_rad",
            k_theta_nm_per_rad,
            MIN_HOLDER_STIFFNESS_NM_PER_RAD,
            MAX_HOLDER_STIFFNESS_NM_PER_RAD,
            "N·m/rad",
        )?;
        self.with_holder_stiffness(k_theta_nm_per_rad * 1e3)
    }

    fn validate(&self) -> Result<(), ParamError> {
        let (l1, l2, lt) = (self.l1_mm, self.l2_mm, self.tool_length_mm);
        if !(l1.is_finite() && l1 >= 0.0) {
            return Err(ParamError::new(
                "l1_mm",
                "a finite height ≥ 0 mm from the holder face",
                l1,
            ));
        }
        let (l1s, lts) = (show(l1), show(lt));
        if !l2.is_finite() || l2 == l1 {
            return Err(ParamError::new(
                "l2_mm",
                format!("a height different from l1_mm = {l1s} (sensors at equal heights measure no relative deflection)"),
                l2,
            ));
        }
        if l2 < l1 {
            return Err(ParamError::new(
                "l2_mm",
                format!("sensor II farther from the holder than sensor I (l2_mm > l1_mm = {l1s})"),
                l2,
            ));
        }
        if l2 - l1 < MIN_SENSOR_GAP_MM {
            return Err(ParamError::new(
                "l2_mm",
                format!(
                    "sensors at least {MIN_SENSOR_GAP_MM} mm apart (l2_mm ≥ l1_mm + {MIN_SENSOR_GAP_MM} = {})",
                    show(l1 + MIN_SENSOR_GAP_MM)
                ),
                l2,
            ));
        }
        if l2 > lt {
            return Err(ParamError::new(
                "l2_mm",
                format!("a height on the tool, ≤ tool_length_mm = {lts}"),
                l2,
            ));
        }
        // the load must lie beyond sensor I: below it both sensors see only the rotation of the
        // loaded end, δII − δI = a²(l2 − l1)/2EI → 0 and K_δ → ∞ (a = 1e-308 gave K_δ = inf)
        let a = self.load_distance_mm();
        if !(a.is_finite() && a > l1 && a <= lt) {
            return Err(ParamError::new(
                "load_point_mm",
                format!(
                    "a load point on the tool beyond sensor I, l1_mm = {l1s} < a ≤ tool_length_mm = {lts}"
                ),
                a,
            ));
        }
        // every input in range keeps K_δ finite and positive; this guards the combinations
        let k = self.stiffness_n_per_mm();
        if !(k.is_finite() && k > 0.0) {
            return Err(ParamError::new(
                "shank",
                "a beam whose stiffness K_δ = F/(δ_II − δ_I) is a finite number > 0 N/mm \
                 (check modulus_gpa, diameter_mm, l1_mm, l2_mm, tool_length_mm)",
                k,
            ));
        }
        Ok(())
    }

    /// Load point a from the holder face, mm.
    pub fn load_distance_mm(&self) -> f64 {
        match self.load_point {
            LoadPoint::Tip => self.tool_length_mm,
            LoadPoint::MidDepth { axial_depth_mm } => self.tool_length_mm - axial_depth_mm / 2.0,
            LoadPoint::At { distance_mm } => distance_mm,
        }
    }

    /// Second moment of area I = π·d⁴/64, mm⁴.
    pub fn second_moment_mm4(&self) -> f64 {
        std::f64::consts::PI * self.diameter_mm.powi(4) / 64.0
    }

    /// Bending part of the compliance at x per unit load at a, 6EI·y/F = x²(3a − x) (x ≤ a) or
    /// a²(3x − a) (x > a), mm³.
    pub fn bending_shape_mm3(x: f64, a: f64) -> f64 {
        if x <= a {
            x * x * (3.0 * a - x)
        } else {
            a * a * (3.0 * x - a)
        }
    }

    /// Deflection at height x per newton of load, mm/N (beam + holder rotation; holder
    /// translation omitted because it cancels in δ_II − δ_I).
    pub fn compliance_at_mm_per_n(&self, x_mm: f64) -> f64 {
        let a = self.load_distance_mm();
        let ei = self.modulus_n_per_mm2 * self.second_moment_mm4();
        let rot = self
            .holder_rotational_stiffness_nmm_per_rad
            .map_or(0.0, |k| x_mm * a / k);
        Self::bending_shape_mm3(x_mm, a) / (6.0 * ei) + rot
    }

    /// K_δ = F/(δ_II − δ_I), N/mm (methods.md §3.1). The holder terms of the two sensors are
    /// subtracted as one product, (l_II − l_I)·a/k_θ: for a very soft holder each alone could
    /// overflow, and ∞ − ∞ is NaN.
    pub fn stiffness_n_per_mm(&self) -> f64 {
        let (l1, l2, a) = (self.l1_mm, self.l2_mm, self.load_distance_mm());
        let ei = self.modulus_n_per_mm2 * self.second_moment_mm4();
        let bending =
            (Self::bending_shape_mm3(l2, a) - Self::bending_shape_mm3(l1, a)) / (6.0 * ei);
        let holder = self
            .holder_rotational_stiffness_nmm_per_rad
            .map_or(0.0, |k| (l2 - l1) * a / k);
        1.0 / (bending + holder)
    }

    /// K_δ in N/µm.
    pub fn stiffness_n_per_um(&self) -> f64 {
        self.stiffness_n_per_mm() / 1e3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patent_examples() {
        let k1 = ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0)
            .unwrap()
            .stiffness_n_per_um();
        let k2 = ShankBeam::new(610.0, 12.0, 85.0, 15.0, 35.0)
            .unwrap()
            .stiffness_n_per_um();
        assert!((k1 - 1.948754).abs() < 1e-6, "{k1}");
        assert!((k2 - 17.287361).abs() < 1e-6, "{k2}");
    }
}
