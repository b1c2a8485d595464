//! Nominal bar generatrix R(u) and its surface normal (methods.md §5.1).

use crate::error::ParamError;

/// The theoretical bar surface P(u, α) = (R(u) cos α, R(u) sin α, u) is given by its generatrix.
///
/// u is the axial position along the grinder's work-head axis (mm, from the tool tip towards the
/// shank, the same axis as the cutter's z in `conventions.md`).
#[derive(Debug, Clone, PartialEq)]
pub enum Generatrix {
    /// Cylinder of constant radius (mm).
    Cylinder {
        /// Radius (mm).
        radius_mm: f64,
    },
    /// Piecewise-linear table of (u, R) pairs, u strictly increasing; constant beyond its ends.
    Table {
        /// Axial positions (mm).
        u_mm: Vec<f64>,
        /// Radii (mm).
        radius_mm: Vec<f64>,
    },
}

impl Generatrix {
    /// A cylinder of radius `radius_mm` (> 0).
    pub fn cylinder(radius_mm: f64) -> Result<Self, ParamError> {
        crate::error::positive("bar_radius_mm", radius_mm)?;
        Ok(Generatrix::Cylinder { radius_mm })
    }

    /// A table generatrix; needs ≥ 2 points, u strictly increasing, radii > 0.
    pub fn table(u_mm: Vec<f64>, radius_mm: Vec<f64>) -> Result<Self, ParamError> {
        if u_mm.len() != radius_mm.len() || u_mm.len() < 2 {
            return Err(ParamError::new(
                "generatrix",
                "at least 2 (u_mm, radius_mm) pairs of equal count",
                format!("{} u, {} radii", u_mm.len(), radius_mm.len()),
            ));
        }
        for k in 0..u_mm.len() {
            crate::error::finite(&format!("generatrix u_mm[{k}]"), u_mm[k])?;
            crate::error::positive(&format!("generatrix radius_mm[{k}]"), radius_mm[k])?;
            if k > 0 && u_mm[k] <= u_mm[k - 1] {
                return Err(ParamError::new(
                    format!("generatrix u_mm[{k}]"),
                    format!("a value above u_mm[{}] = {}", k - 1, u_mm[k - 1]),
                    u_mm[k],
                ));
            }
        }
        Ok(Generatrix::Table { u_mm, radius_mm })
    }

    /// R(u) (mm).
    pub fn radius(&self, u: f64) -> f64 {
        self.radius_and_slope(u).0
    }

    /// (R(u), R′(u)); the table is linear between points and constant outside.
    pub fn radius_and_slope(&self, u: f64) -> (f64, f64) {
        match self {
            Generatrix::Cylinder { radius_mm } => (*radius_mm, 0.0),
            Generatrix::Table { u_mm, radius_mm } => {
                let n = u_mm.len();
                if u <= u_mm[0] {
                    return (radius_mm[0], 0.0);
                }
                if u >= u_mm[n - 1] {
                    return (radius_mm[n - 1], 0.0);
                }
                let k = u_mm.partition_point(|&x| x <= u).clamp(1, n - 1) - 1;
                let slope = (radius_mm[k + 1] - radius_mm[k]) / (u_mm[k + 1] - u_mm[k]);
                (radius_mm[k] + slope * (u - u_mm[k]), slope)
            }
        }
    }

    /// Outward unit normal N(u, α) = normalise(T_α × T_u) = (cos α, sin α, −R′)/√(1 + R′²),
    /// methods.md §5.1.
    ///
    /// ```
    /// use runout_core::grind::Generatrix;
    /// let g = Generatrix::cylinder(3.0).unwrap();
    /// let n = g.normal(5.0, 0.0);
    /// assert!((n[0] - 1.0).abs() < 1e-15 && n[2] == 0.0);
    /// ```
    pub fn normal(&self, u: f64, alpha: f64) -> [f64; 3] {
        let (_, slope) = self.radius_and_slope(u);
        let k = 1.0 / (1.0 + slope * slope).sqrt();
        [alpha.cos() * k, alpha.sin() * k, -slope * k]
    }
}
