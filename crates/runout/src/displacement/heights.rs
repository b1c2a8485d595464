//! `displacement heights`: runout at several heights → runout at the cutting height
//! (methods.md §1.3; §1.6 vector fit when the table has an angle column).

use super::{name_of, AngleReport};
use crate::job::{Report, Source};
use crate::verdict::{AxisReport, VerdictBasis, VerdictReport};
use anyhow::{Context, Result};
use runout_core::displacement::{
    runout_at_height, vector_at_height, HeightFit, HeightRegression, VectorHeightFit,
};
use runout_io::displacement::read_height_table;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `runout displacement heights`.
#[derive(Debug, Clone)]
pub struct HeightsRequest {
    /// CSV with `z_<mm>` and `tir_<um>` or `runout_<um>`, optional `angle_<deg>`.
    pub table: Source,
    /// Height at which the runout is wanted (mm).
    pub at_mm: f64,
    pub method: HeightRegression,
}

/// The input as reported.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct HeightsInput {
    pub file: String,
    pub points: usize,
}

/// The offset + tilt vector fit (§1.6).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct VectorReport {
    pub offset_um: f64,
    #[serde(alias = "offset_se_um")]
    pub offset_um_se: Option<f64>,
    pub offset_at_zero_um: [f64; 2],
    pub tilt_um_per_mm: [f64; 2],
    pub residual_rms_um: f64,
    #[serde(flatten)]
    pub angle: AngleReport,
}

/// `runout.displacement.heights/2`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct HeightsReport {
    /// `runout.displacement.heights/2`
    #[schemars(extend("const" = "runout.displacement.heights/2"))]
    pub schema: String,
    /// The result first: ρ ± SE at the cutting height (λ ± SE with the angle column), the
    /// method, the status and its reasons (issue 21).
    #[serde(default)]
    pub answer: crate::answer::Answer,
    pub input: HeightsInput,
    pub method: String,
    pub at_mm: f64,
    pub offset_um: f64,
    #[serde(alias = "offset_se_um")]
    pub offset_um_se: Option<f64>,
    pub slope_um_per_mm: f64,
    #[serde(alias = "slope_se_um_per_mm")]
    pub slope_um_per_mm_se: Option<f64>,
    pub r_squared: f64,
    pub residual_rms_um: f64,
    pub notes: Vec<String>,
    pub vector: Option<VectorReport>,
    /// Pass/fail against the runout tolerance, and the runout at the cutting height against the
    /// highest reading (tilt) (issue 15).
    pub verdict: Option<VerdictReport>,
    /// The core results behind the text and the plot; not part of the JSON.
    #[serde(skip)]
    #[schemars(skip)]
    pub detail: HeightsDetail,
}

/// The core results of `displacement heights`.
#[derive(Debug, Clone, Default)]
pub struct HeightsDetail {
    /// (z mm, runout mm) points.
    pub points: Vec<(f64, f64)>,
    pub fit: Option<HeightFit>,
    pub vector: Option<VectorHeightFit>,
}

impl crate::answer::Answered for HeightsReport {
    fn answer(&self) -> &crate::answer::Answer {
        &self.answer
    }
}

impl Report for HeightsReport {
    const SCHEMA: &'static str = "runout.displacement.heights/2";
}

/// Regress runout on height; with angles, the offset + tilt vector fit as well.
pub fn heights(req: &HeightsRequest) -> Result<HeightsReport> {
    let rows = read_height_table(req.table.table_input())?;
    let file = req.table.name().to_string();
    let at = req.at_mm;
    let pts: Vec<(f64, f64)> = rows.iter().map(|r| (r.z_mm, r.runout_mm)).collect();
    let fit = runout_at_height(&pts, at, req.method).with_context(|| file.clone())?;
    let vpts: Option<Vec<(f64, [f64; 2])>> = rows
        .iter()
        .map(|r| {
            r.angle_rad
                .map(|l| (r.z_mm, [r.runout_mm * l.cos(), r.runout_mm * l.sin()]))
        })
        .collect();
    let vector = vpts
        .map(|p| vector_at_height(&p, at))
        .transpose()
        .with_context(|| file.clone())?;
    // tip (the cutting height) against the highest reading: vectors with the angle column,
    // else the magnitudes of the regression
    let z_top = pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let axis = if z_top > at {
        let (tip, top) = match &vector {
            Some(v) => {
                let e = |z: f64| {
                    let [x, y] = v.line.at(z);
                    (x.hypot(y) * 1e3, y.atan2(x).to_degrees())
                };
                (e(at), e(z_top))
            }
            None => ((fit.at(at) * 1e3, 0.0), (fit.at(z_top) * 1e3, 0.0)),
        };
        Some(AxisReport::from_polar(
            tip,
            top,
            z_top - at,
            "highest reading",
        )?)
    } else {
        None
    };
    let verdict = VerdictReport::new(
        VerdictBasis {
            offset_um: fit.offset_mm * 1e3,
            offset_um_se: fit.offset_se_mm.map(|s| s * 1e3),
            angle_deg: vector
                .as_ref()
                .and_then(|v| v.angle.angle())
                .map(f64::to_degrees),
            teeth: None,
            diameter_mm: None,
            helix_deg: 0.0,
            height_mm: fit.height_mm,
            fz_mm: None,
        },
        None,
    )?
    .with_axis(axis);
    let regression = crate::answer::Quantity::cross_check(
        "runout offset ρ",
        "µm",
        fit.offset_mm * 1e3,
        fit.offset_se_mm.map(|s| s * 1e3),
    );
    let todo = "measure at more heights, or repeat the readings at each height";
    let answer = match &vector {
        Some(v) => {
            let angle = AngleReport::from(&v.angle);
            super::runout_answer(
                "offset + tilt vector fit e(z) = e₀ + z·τ of the runout vectors, at the cutting \
                 height (docs/methods.md §1.6)",
                v.offset_mm * 1e3,
                v.offset_se_mm.map(|s| s * 1e3),
                Some(&angle),
                f64::INFINITY,
                None,
                todo,
                vec![crate::answer::CrossCheck {
                    estimate: format!(
                        "straight line through the runout magnitudes ({})",
                        crate::words::plain(&fit.method)
                    ),
                    values: vec![regression],
                    why_it_may_differ: "the magnitudes |e(z)| are not linear in z when the \
                                        offset and the tilt point in different directions; \
                                        the vector fit uses the angles"
                        .into(),
                }],
            )
        }
        None => super::runout_answer(
            &format!(
                "straight line through the runout magnitudes ({}), extrapolated to the cutting \
                 height (docs/methods.md §1.3)",
                crate::words::plain(&fit.method)
            ),
            fit.offset_mm * 1e3,
            fit.offset_se_mm.map(|s| s * 1e3),
            None,
            f64::INFINITY,
            None,
            todo,
            Vec::new(),
        ),
    };
    Ok(HeightsReport {
        schema: HeightsReport::SCHEMA.into(),
        answer,
        input: HeightsInput {
            file,
            points: fit.points,
        },
        method: name_of(&fit.method),
        at_mm: fit.height_mm,
        offset_um: fit.offset_mm * 1e3,
        offset_um_se: fit.offset_se_mm.map(|s| s * 1e3),
        slope_um_per_mm: fit.slope * 1e3,
        slope_um_per_mm_se: fit.slope_se.map(|s| s * 1e3),
        r_squared: fit.r_squared,
        residual_rms_um: fit.residual_rms_mm * 1e3,
        notes: fit.notes.clone(),
        vector: vector.as_ref().map(|v| VectorReport {
            offset_um: v.offset_mm * 1e3,
            offset_um_se: v.offset_se_mm.map(|s| s * 1e3),
            offset_at_zero_um: v.line.offset_mm().map(|x| x * 1e3),
            tilt_um_per_mm: v.line.tilt_vector().map(|x| x * 1e3),
            residual_rms_um: v.line.residual_rms * 1e3,
            angle: AngleReport::from(&v.angle),
        }),
        verdict: Some(verdict),
        detail: HeightsDetail {
            points: pts,
            fit: Some(fit),
            vector,
        },
    })
}
