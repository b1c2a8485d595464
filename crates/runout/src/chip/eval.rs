//! `chip eval`: the chip thickness h along the motion of one case (3-axis or 5-axis toolpath).

use super::{case_inputs, read_cases, select};
use crate::job::{Report, Source};
use anyhow::{bail, Result};
use runout_core::chip::compare::equivalent_values;
use runout_core::chip::{
    arc_at, closed_forms_at, exact_at_time, EquivalentParams, NewtonOptions, RayTime,
};
use runout_io::config::chip::ChipCase;
use schemars::JsonSchema;
use serde::Serialize;
use std::path::PathBuf;

/// A chip-thickness model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChipModel {
    Exact,
    Equivalent,
    Arc,
    Circle,
}

impl ChipModel {
    /// `exact`, `equivalent`, `arc` or `circle`.
    pub fn name(self) -> &'static str {
        match self {
            ChipModel::Exact => "exact",
            ChipModel::Equivalent => "equivalent",
            ChipModel::Arc => "arc",
            ChipModel::Circle => "circle",
        }
    }
}

/// `runout chip eval`.
#[derive(Debug, Clone)]
pub struct EvalRequest {
    /// Case file (TOML, as for compare).
    pub config: Source,
    /// Case to evaluate (name contains this text); default the first.
    pub case: Option<String>,
    pub model: ChipModel,
}

/// `runout.chip.eval/1`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct EvalReport {
    /// `runout.chip.eval/1`
    #[schemars(extend("const" = "runout.chip.eval/1"))]
    pub schema: String,
    pub case: String,
    pub model: String,
    pub motion: String,
    pub teeth: usize,
    pub diameter_mm: f64,
    pub rpm: f64,
    pub runout_um: f64,
    pub runout_angle_deg: f64,
    pub heights_mm: Vec<f64>,
    pub points: usize,
    pub max_h_um_per_tooth: Vec<f64>,
    pub warnings: Vec<String>,
    /// The case and h at its points, for the CSV and the plots; not part of the JSON.
    #[serde(skip)]
    #[schemars(skip)]
    pub detail: EvalDetail,
}

/// The case evaluated and its h (mm, ≥ 0) per point.
#[derive(Debug, Clone, Default)]
pub struct EvalDetail {
    pub case: Option<ChipCase>,
    pub h_mm: Vec<f64>,
    /// The files read (case file, toolpaths): what an output must not overwrite.
    pub inputs: Vec<PathBuf>,
}

impl Report for EvalReport {
    const SCHEMA: &'static str = "runout.chip.eval/1";
}

/// h (mm, ≥ 0) of `model` at every point of the case.
fn eval_model(case: &ChipCase, model: ChipModel) -> Result<Vec<f64>> {
    let kin = &case.kin;
    let params = EquivalentParams::default();
    if model == ChipModel::Equivalent {
        // the bulk evaluator (one look-back per time, shared by teeth and heights)
        return Ok(equivalent_values(kin, &case.points, &params));
    }
    let opts = NewtonOptions::default();
    let mut geo: Option<runout_core::chip::HeightGeometry> = None;
    // the pose, screw and spindle angle of a time, shared by its teeth and heights
    let mut time: Option<RayTime> = None;
    let mut out = Vec::with_capacity(case.points.len());
    for q in &case.points {
        if geo.as_ref().is_none_or(|g| g.z != q.z) {
            geo = Some(kin.at_height(q.z));
        }
        let g = geo.as_ref().expect("set above");
        let h = match model {
            ChipModel::Exact => {
                if time.as_ref().is_none_or(|r| r.t != q.t) {
                    time = Some(RayTime::new(kin, q.t));
                }
                let e = exact_at_time(kin, g, q.tooth, time.as_ref().expect("set above"), &opts);
                if !e.converged {
                    bail!(
                        "exact solver did not converge (tooth {}, z {} mm, t {} s)",
                        q.tooth,
                        q.z,
                        q.t
                    );
                }
                e.raw
            }
            ChipModel::Arc => arc_at(kin, g, q.tooth, q.t),
            ChipModel::Circle | ChipModel::Equivalent => {
                closed_forms_at(kin, g, q.tooth, q.t, &params).circle
            }
        };
        out.push(h.max(0.0));
    }
    Ok(out)
}

/// Largest h (mm) of each tooth.
pub fn per_tooth_max(case: &ChipCase, h: &[f64]) -> Vec<f64> {
    let mut m = vec![0.0f64; case.kin.cutter().teeth()];
    for (q, v) in case.points.iter().zip(h) {
        m[q.tooth] = m[q.tooth].max(*v);
    }
    m
}

/// Evaluate the model along the case's motion.
pub fn eval(req: &EvalRequest) -> Result<EvalReport> {
    let case = select(
        read_cases(&req.config)?,
        req.case.as_deref(),
        req.config.name(),
    )?
    .remove(0);
    let inputs = case_inputs(&req.config, std::slice::from_ref(&case));
    let h = eval_model(&case, req.model)?;
    let s = &case.spec;
    Ok(EvalReport {
        schema: EvalReport::SCHEMA.into(),
        case: case.name.clone(),
        model: req.model.name().into(),
        motion: s.motion.name().into(),
        teeth: s.teeth,
        diameter_mm: s.diameter_mm,
        rpm: s.rpm,
        runout_um: s.runout_um,
        runout_angle_deg: s.runout_angle_deg,
        heights_mm: s.heights_mm.clone(),
        points: h.len(),
        max_h_um_per_tooth: per_tooth_max(&case, &h).iter().map(|v| v * 1e3).collect(),
        warnings: case.warnings.clone(),
        detail: EvalDetail {
            case: Some(case),
            h_mm: h,
            inputs,
        },
    })
}
