//! Grinding jobs (seed 004, methods.md §5): compensation of the bar clamping error from a probe
//! grid (wheel path and NC program), and the simulation check of the schemes.

mod check;
mod compensate;
pub mod render;

pub use check::{
    check, offset_xy_um, CheckInputs, CheckReport, CheckRequest, SchemeCheck, Uncompensated,
};
pub use compensate::{
    compensate, AngleSense, AxisReport, CompensateDetail, CompensateReport, CompensateRequest,
    CompensationReport, GeneratrixFrom, GridReport, InputsReport, LayerReport, NcMapping, NcReport,
    NcRequest,
};

use crate::job::Source;
use anyhow::{bail, Context, Result};
use runout_core::grind::EdgeLine;

/// The edge to grind: generated or read from a CSV.
#[derive(Debug, Clone)]
pub enum EdgeSpec {
    /// A CSV with `x_mm,y_mm,z_mm[,nx,ny,nz][,wx_mm,wy_mm,wz_mm]` (bar frame).
    Csv(Source),
    /// A generated helical (flat) or ball-end edge.
    Generated(GeneratedEdge),
}

/// Parameters of a generated edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeneratedEdge {
    /// Ball end instead of a flat (helical peripheral) edge.
    pub ball: bool,
    /// Edge diameter (mm); default the bar diameter.
    pub diameter_mm: Option<f64>,
    pub flutes: usize,
    pub helix_deg: f64,
    /// Edge start from the tip (mm).
    pub from_mm: f64,
    /// Edge end (mm); default the end of the probed range.
    pub to_mm: Option<f64>,
    pub points_per_flute: usize,
    /// Angular position of flute 0 at the tip, bar frame (rad).
    pub phase_rad: f64,
}

impl EdgeSpec {
    /// `flat`, `ball` or the CSV's name.
    pub fn name(&self) -> String {
        match self {
            EdgeSpec::Csv(s) => s.name().to_string(),
            EdgeSpec::Generated(g) => if g.ball { "ball" } else { "flat" }.into(),
        }
    }
}

/// The edge and, for CSV edges, the wheel positions.
pub(crate) fn edge(
    spec: &EdgeSpec,
    bar_d: f64,
    u_end: f64,
) -> Result<(EdgeLine, Option<Vec<[f64; 3]>>)> {
    match spec {
        EdgeSpec::Csv(src) => {
            let kind = src.name();
            let text = src.read_text().context("reading edge")?;
            let t = runout_io::grind::read_edge_csv(&text, kind)?;
            for (k, p) in t.points.iter().enumerate() {
                let on_axis = p[0].hypot(p[1]) == 0.0;
                let zero_normal = t.normals.as_ref().is_some_and(|n| n[k] == [0.0; 3]);
                if zero_normal || (on_axis && t.normals.is_none()) {
                    bail!(
                        "{kind}, line {}: {} (its offset direction is undefined)",
                        t.lines[k],
                        if zero_normal {
                            "normal (0, 0, 0)"
                        } else {
                            "point on the bar axis without a normal"
                        }
                    );
                }
            }
            let e = EdgeLine::from_points(&t.points, t.normals.as_deref())
                .with_context(|| format!("edge {kind}"))?;
            Ok((e, t.wheel))
        }
        EdgeSpec::Generated(g) => {
            let d = g.diameter_mm.unwrap_or(bar_d);
            let z1 = g.to_mm.unwrap_or(u_end);
            let e = if g.ball {
                EdgeLine::ball_end(d, g.flutes, g.helix_deg, g.from_mm, z1, g.points_per_flute)?
            } else {
                EdgeLine::helical_flat(d, g.flutes, g.helix_deg, g.from_mm, z1, g.points_per_flute)?
            };
            Ok((e.rotated(g.phase_rad), None))
        }
    }
}
