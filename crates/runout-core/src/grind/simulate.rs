//! Simulation check (methods.md §5.5): a bar clamped with a known offset + tilt is probed (with
//! noise), the edge is ground with and without compensation, and the finished edge's radius and
//! profile errors are measured against the bar's real axis, in exact geometry.

use super::compensate::{rms_max, Compensation};
use super::edge::{EdgeKind, EdgeLine};
use super::error::GrindError;
use super::nominal::Generatrix;
use super::probe::ProbeGrid;
use crate::error::{finite, positive, ParamError};
use std::f64::consts::TAU;

/// A cylindrical bar of radius R whose real axis is e(u) = e₀ + u·τ in the bar frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulatedBar {
    /// Bar radius R (mm).
    pub radius_mm: f64,
    /// Axis offset e₀ at u = 0 (mm).
    pub offset: [f64; 2],
    /// Axis tilt τ (mm/mm).
    pub tilt: [f64; 2],
}

/// Uniform probing grid (methods.md §5.1): u_i = u_a + i(u_b − u_a)/(M − 1), α_j = 2πj/C.
pub fn uniform_grid(
    u_a: f64,
    u_b: f64,
    layers: usize,
    angles: usize,
) -> Result<(Vec<f64>, Vec<f64>), ParamError> {
    if layers < 2 {
        return Err(ParamError::new("layers", "an integer >= 2", layers));
    }
    if angles < 3 {
        return Err(ParamError::new("angles", "an integer >= 3", angles));
    }
    // checked before the grid is allocated
    crate::limits::work(
        "layers",
        "probe points (layers × angles)",
        layers as f64 * angles as f64,
        crate::limits::MAX_PROBE_POINTS as f64,
    )?;
    if u_b.is_nan() || u_a.is_nan() || u_b <= u_a {
        return Err(ParamError::new(
            "u_end_mm",
            format!("a value above u_start_mm = {u_a}"),
            u_b,
        ));
    }
    let u = (0..layers)
        .map(|i| u_a + (u_b - u_a) * i as f64 / (layers - 1) as f64)
        .collect();
    let a = (0..angles)
        .map(|j| TAU * j as f64 / angles as f64)
        .collect();
    Ok((u, a))
}

impl SimulatedBar {
    /// A bar of radius `radius_mm` with axis offset `offset` (mm) and tilt `tilt` (mm/mm).
    pub fn new(radius_mm: f64, offset: [f64; 2], tilt: [f64; 2]) -> Result<Self, ParamError> {
        positive("bar_radius_mm", radius_mm)?;
        for (k, v) in offset.iter().chain(&tilt).enumerate() {
            finite(&format!("bar offset/tilt component {k}"), *v)?;
        }
        Ok(SimulatedBar {
            radius_mm,
            offset,
            tilt,
        })
    }

    /// Real axis e(u) = e₀ + u·τ (mm).
    pub fn axis_at(&self, u: f64) -> [f64; 2] {
        [
            self.offset[0] + u * self.tilt[0],
            self.offset[1] + u * self.tilt[1],
        ]
    }

    /// Exact radius at which a probe moving radially inward at height u, angle α touches the
    /// tilted cylinder: the larger root r of dist((r n, u), axis line)² = R².
    pub fn probe_radius(&self, u: f64, alpha: f64) -> f64 {
        let (n0, n1) = (alpha.cos(), alpha.sin());
        let e = self.axis_at(u);
        let t = self.tilt;
        let l2 = 1.0 + t[0] * t[0] + t[1] * t[1];
        let (ne, nt, et) = (
            n0 * e[0] + n1 * e[1],
            n0 * t[0] + n1 * t[1],
            e[0] * t[0] + e[1] * t[1],
        );
        let a = 1.0 - nt * nt / l2;
        let b = ne - nt * et / l2;
        let c = e[0] * e[0] + e[1] * e[1] - et * et / l2 - self.radius_mm * self.radius_mm;
        (b + (b * b - a * c).sqrt()) / a
    }

    /// Probe the bar on grid (u, α), adding `noise()` (mm) to each radius.
    pub fn probe(
        &self,
        u: &[f64],
        alpha: &[f64],
        mut noise: impl FnMut() -> f64,
    ) -> Result<ProbeGrid, GrindError> {
        let r: Vec<Vec<f64>> = u
            .iter()
            .map(|&ui| {
                alpha
                    .iter()
                    .map(|&a| self.probe_radius(ui, a) + noise())
                    .collect()
            })
            .collect();
        ProbeGrid::from_radii(u, alpha, &r, Generatrix::cylinder(self.radius_mm)?)
    }

    /// Distance of point `p` from the real axis line (mm).
    pub fn distance_from_axis(&self, p: [f64; 3]) -> f64 {
        let e = self.axis_at(p[2]);
        let t = self.tilt;
        let q = [p[0] - e[0], p[1] - e[1]];
        let l2 = 1.0 + t[0] * t[0] + t[1] * t[1];
        let qd = q[0] * t[0] + q[1] * t[1];
        (q[0] * q[0] + q[1] * q[1] - qd * qd / l2).max(0.0).sqrt()
    }

    /// Error of a finished edge point (mm): where nominal point `f` was ground at `g`, the distance
    /// from the real axis (or from the real ball centre on a ball end) minus the nominal one.
    pub fn finished_error(&self, kind: EdgeKind, f: [f64; 3], g: [f64; 3]) -> f64 {
        match kind {
            EdgeKind::Ball { radius_mm: rb } if f[2] < rb => {
                let c = self.axis_at(rb);
                let d = [g[0] - c[0], g[1] - c[1], g[2] - rb];
                (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() - rb
            }
            _ => self.distance_from_axis(g) - f[0].hypot(f[1]),
        }
    }
}

/// Result of a simulated grind (all mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GrindCheck {
    /// RMS of the interpolation error ε_k − e(u_k)·n_k against the true axis (methods.md §5.5).
    pub interpolation_rms: f64,
    /// Max |ε_k − e(u_k)·n_k|.
    pub interpolation_max: f64,
    /// Radius error without compensation: max |finished error|.
    pub radius_error_before: f64,
    /// Radius error with compensation.
    pub radius_error_after: f64,
    /// Profile error without compensation: max − min of the finished error.
    pub profile_before: f64,
    /// Profile error with compensation.
    pub profile_after: f64,
}

/// Grind `edge` on `bar` without and with `comp` (computed for that edge) and measure the
/// finished edge against the bar's real axis (methods.md §5.5).
pub fn grind_check(bar: &SimulatedBar, edge: &EdgeLine, comp: &Compensation) -> GrindCheck {
    let pts = || edge.points.iter().zip(&comp.points);
    let (interpolation_rms, interpolation_max) = rms_max(pts().map(|(p, c)| {
        let e = bar.axis_at(p.u);
        c.eps - (e[0] * p.alpha.cos() + e[1] * p.alpha.sin())
    }));
    let before: Vec<f64> = pts()
        .map(|(p, _)| bar.finished_error(edge.kind, p.position, p.position))
        .collect();
    let after: Vec<f64> = pts()
        .map(|(p, c)| {
            let g = [
                p.position[0] + c.offset[0],
                p.position[1] + c.offset[1],
                p.position[2] + c.offset[2],
            ];
            bar.finished_error(edge.kind, p.position, g)
        })
        .collect();
    let band = |v: &[f64]| {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                (l.min(*x), h.max(*x))
            });
        (hi - lo).max(0.0)
    };
    GrindCheck {
        interpolation_rms,
        interpolation_max,
        radius_error_before: rms_max(before.iter().copied()).1,
        radius_error_after: rms_max(after.iter().copied()).1,
        profile_before: band(&before),
        profile_after: band(&after),
    }
}
