//! Edge lines F(v_k) on which the deviation is evaluated (methods.md §5.3): the helical
//! peripheral edge of a flat end mill, a ball-end edge (the same constant-lead helix continued
//! onto the hemisphere) or any points given by the caller.
//!
//! Frame: the bar frame of methods.md §5.1, right-handed, z = work-head axis from the tool tip
//! towards the shank, α counter-clockwise about +z. The spindle turns clockwise seen from the
//! shank (`conventions.md`), so spindle-frame angles are ψ = −α: a right-hand helix has
//! α_i(z) = β₀ + 2πi/K + z·tan β_h/R (methods.md §5.3, β(v) = β₀ + z tan λ_h / r_E), with tooth 0
//! at α = β₀ at the tip and teeth in cutting order. u_k = z_k.

use crate::angle::wrap_tau;
use crate::cutter::{Cutter, RadiusProfile};
use crate::error::{positive, ParamError};
use std::f64::consts::TAU;

/// One edge point with its interpolation coordinates and offset direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgePoint {
    /// Position F(v_k) in the bar frame (mm).
    pub position: [f64; 3],
    /// Axial parameter u_k = z_E(v_k) (mm).
    pub u: f64,
    /// Edge phase α_k = β(v_k) mod 2π (rad).
    pub alpha: f64,
    /// Unit offset direction N_k: the theoretical radial direction (cos α_k, sin α_k, 0)
    /// (methods.md §5.4) unless given.
    pub normal: [f64; 3],
    /// Flute (tooth) index, 0 for caller-given points.
    pub flute: usize,
}

/// The kind of edge, which decides how the finished-edge error is measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EdgeKind {
    /// Peripheral (cylindrical) edge: radius error = distance from the actual tool axis − R.
    Peripheral,
    /// Ball end of radius `radius_mm` with centre on the axis at z = radius: for z < radius the
    /// error is the distance from the actual ball centre − radius.
    Ball {
        /// Ball radius (mm).
        radius_mm: f64,
    },
    /// Caller-given points (treated as peripheral).
    Points,
}

/// An edge line: its points in order (flute by flute).
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeLine {
    /// Points.
    pub points: Vec<EdgePoint>,
    /// Kind.
    pub kind: EdgeKind,
}

fn radial(alpha: f64) -> [f64; 3] {
    [alpha.cos(), alpha.sin(), 0.0]
}

fn check_range(z0: f64, z1: f64, n: usize) -> Result<(), ParamError> {
    crate::error::non_negative("edge_start_mm", z0)?;
    if !(z1.is_finite() && z1 > z0) {
        return Err(ParamError::new(
            "edge_end_mm",
            format!("a length above edge_start_mm = {z0}"),
            z1,
        ));
    }
    if !(2..=crate::limits::MAX_POINTS_PER_FLUTE).contains(&n) {
        return Err(ParamError::new(
            "points_per_flute",
            format!("an integer in [2, {}]", crate::limits::MAX_POINTS_PER_FLUTE),
            n,
        ));
    }
    Ok(())
}

fn sample(cutter: &Cutter, z0: f64, z1: f64, n: usize) -> Vec<EdgePoint> {
    let mut pts = Vec::with_capacity(cutter.teeth() * n);
    for i in 0..cutter.teeth() {
        for k in 0..n {
            let z = z0 + (z1 - z0) * k as f64 / (n - 1) as f64;
            // bar-frame phase α = −ψ_i(z) (see the module doc)
            let alpha = wrap_tau(-cutter.tooth_angle(i, z));
            let r = cutter.radius_at(z);
            pts.push(EdgePoint {
                position: [r * alpha.cos(), r * alpha.sin(), z],
                u: z,
                alpha,
                normal: radial(alpha),
                flute: i,
            });
        }
    }
    pts
}

impl EdgeLine {
    /// Helical peripheral edges of a flat end mill: K uniform flutes, helix angle (deg), diameter
    /// (mm), from z0 to z1 (mm from the tip), `n` points per flute; α_i(z) = 2πi/K + z·tan β_h/R
    /// = −ψ_i(z) (methods.md §5.3; `conventions.md` tooth angles). Rotate with [`EdgeLine::rotated`].
    ///
    /// ```
    /// use runout_core::grind::EdgeLine;
    /// let e = EdgeLine::helical_flat(6.0, 4, 30.0, 0.0, 20.0, 11).unwrap();
    /// assert_eq!(e.points.len(), 44);
    /// assert!((e.points[1].position[0].hypot(e.points[1].position[1]) - 3.0).abs() < 1e-12);
    /// ```
    pub fn helical_flat(
        diameter_mm: f64,
        flutes: usize,
        helix_deg: f64,
        z0: f64,
        z1: f64,
        n: usize,
    ) -> Result<Self, ParamError> {
        check_range(z0, z1, n)?;
        crate::limits::result_size("points_per_flute", flutes as f64 * n as f64, 8.0)?;
        let cutter = Cutter::flat(diameter_mm, flutes, helix_deg.to_radians())?;
        Ok(EdgeLine {
            points: sample(&cutter, z0, z1, n),
            kind: EdgeKind::Peripheral,
        })
    }

    /// Ball-end edges: the constant-lead helix α_i(z) = 2πi/K + z·tan β_h/R on the profile
    /// r(z) = √(R² − (R − z)²) for z < R (hemisphere), cylinder above; z0..z1 from the tip.
    pub fn ball_end(
        diameter_mm: f64,
        flutes: usize,
        helix_deg: f64,
        z0: f64,
        z1: f64,
        n: usize,
    ) -> Result<Self, ParamError> {
        check_range(z0, z1, n)?;
        crate::limits::teeth("flutes", flutes)?;
        crate::limits::result_size("points_per_flute", flutes as f64 * n as f64, 8.0)?;
        let pitch = vec![TAU / flutes as f64; flutes];
        let cutter = Cutter::new(
            diameter_mm,
            pitch,
            helix_deg.to_radians(),
            z1,
            RadiusProfile::Ball,
        )?;
        Ok(EdgeLine {
            points: sample(&cutter, z0, z1, n),
            kind: EdgeKind::Ball {
                radius_mm: diameter_mm / 2.0,
            },
        })
    }

    /// The same edge turned by `phase` (rad) about the bar axis: α → α + β₀.
    pub fn rotated(mut self, phase: f64) -> Self {
        let (c, s) = (phase.cos(), phase.sin());
        for p in &mut self.points {
            let [x, y, z] = p.position;
            p.position = [c * x - s * y, s * x + c * y, z];
            let [nx, ny, nz] = p.normal;
            p.normal = [c * nx - s * ny, s * nx + c * ny, nz];
            p.alpha = wrap_tau(p.alpha + phase);
        }
        self
    }

    /// Caller-given edge points (bar frame, mm) with optional offset directions (normalised
    /// here); u = z, α = atan2(y, x). A point on the axis without a given normal is refused
    /// (its angle is undefined); the error names the point index (0-based).
    pub fn from_points(
        positions: &[[f64; 3]],
        normals: Option<&[[f64; 3]]>,
    ) -> Result<Self, ParamError> {
        if let Some(n) = normals {
            if n.len() != positions.len() {
                return Err(ParamError::new(
                    "edge normals",
                    format!("one per point ({})", positions.len()),
                    n.len(),
                ));
            }
        }
        let mut pts = Vec::with_capacity(positions.len());
        for (k, p) in positions.iter().enumerate() {
            for c in p {
                crate::error::finite(&format!("edge point {k}"), *c)?;
            }
            let r = p[0].hypot(p[1]);
            let normal = match normals {
                Some(ns) => normalise(ns[k]).ok_or_else(|| {
                    ParamError::new(format!("edge normal {k}"), "a non-zero vector", "zero")
                })?,
                None => {
                    positive(&format!("edge point {k} radius (no normal given)"), r)?;
                    radial(p[1].atan2(p[0]))
                }
            };
            let alpha = wrap_tau(p[1].atan2(p[0]));
            pts.push(EdgePoint {
                position: *p,
                u: p[2],
                alpha,
                normal,
                flute: 0,
            });
        }
        Ok(EdgeLine {
            points: pts,
            kind: EdgeKind::Points,
        })
    }
}

fn normalise(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (n.is_finite() && n > 0.0).then(|| [v[0] / n, v[1] / n, v[2] / n])
}
