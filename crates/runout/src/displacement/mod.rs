//! Displacement jobs (methods.md §1, seed 000): runout in position from per-tooth readings,
//! from runout at several heights, or from a raw displacement signal.

mod heights;
pub mod render;
mod signal;
mod teeth;

pub use heights::{
    heights, HeightsDetail, HeightsInput, HeightsReport, HeightsRequest, VectorReport,
};
pub use signal::{
    signal, ChannelReport, PerRevolution, ReferenceChoice, SectionReport, SignalDetail,
    SignalInputReport, SignalReport, SignalRequest, SignalTeeth,
};
pub use teeth::{teeth, TeethDetail, TeethInput, TeethReport, TeethRequest};

use runout_core::displacement::{AngleEstimate, BeamGeometry, Consequences, SensorSign};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The serialised name of a core enum (`"joint"`, `"pulse"`, …).
fn name_of<T: Serialize>(t: &T) -> String {
    match serde_json::to_value(t) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(v) => v.to_string(),
        Err(_) => String::new(),
    }
}

/// The displacement sensor: its sign convention and beam geometry (§1.4).
#[derive(Debug, Clone, Copy)]
pub struct Sensor {
    pub sign: SensorSign,
    pub beam: BeamGeometry,
}

/// The sensor as reported.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct BeamReport {
    pub sensor: String,
    pub inclination_deg: f64,
    pub beam_offset_mm: f64,
}

impl From<&Sensor> for BeamReport {
    fn from(s: &Sensor) -> Self {
        Self {
            sensor: format!("{:?}", s.sign).to_lowercase(),
            inclination_deg: s.beam.inclination().to_degrees(),
            beam_offset_mm: s.beam.offset(),
        }
    }
}

/// An angle estimate (degrees), flattened into its report: `angle_status` is `determined`,
/// `ambiguous` (two candidates) or `undetermined` (with the reason).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct AngleReport {
    pub angle_status: String,
    pub angle_deg: Option<f64>,
    #[serde(alias = "angle_se_deg")]
    pub angle_deg_se: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_candidates_deg: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_rejected_deg: Option<Option<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_reason: Option<String>,
}

impl From<&AngleEstimate> for AngleReport {
    fn from(a: &AngleEstimate) -> Self {
        let se = a.se().map(f64::to_degrees);
        let none = |status: &str| AngleReport {
            angle_status: status.into(),
            angle_deg: None,
            angle_deg_se: se,
            angle_candidates_deg: None,
            angle_rejected_deg: None,
            angle_reason: None,
        };
        match a {
            AngleEstimate::Determined { angle_rad, .. } => AngleReport {
                angle_deg: Some(angle_rad.to_degrees()),
                ..none("determined")
            },
            AngleEstimate::Ambiguous {
                candidates_rad,
                reason,
                ..
            } => AngleReport {
                angle_candidates_deg: Some([
                    candidates_rad[0].to_degrees(),
                    candidates_rad[1].to_degrees(),
                ]),
                angle_reason: Some(reason.clone()),
                ..none("ambiguous")
            },
            AngleEstimate::Undetermined {
                reason,
                rejected_rad,
                ..
            } => AngleReport {
                angle_rejected_deg: Some(rejected_rad.map(f64::to_degrees)),
                angle_reason: Some(reason.clone()),
                ..none("undetermined")
            },
        }
    }
}

/// Predicted consequences (§1.7).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ConsequencesReport {
    pub height_mm: f64,
    pub tooth_radii_mm: Vec<f64>,
    pub slot_width_mm: f64,
    pub hole_diameter_mm: Option<f64>,
    pub fz_mm: Option<f64>,
    pub chip_load_um: Option<Vec<f64>>,
}

impl From<&Consequences> for ConsequencesReport {
    fn from(c: &Consequences) -> Self {
        Self {
            height_mm: c.height_mm,
            tooth_radii_mm: c.tooth_radii_mm.clone(),
            slot_width_mm: c.slot_width_mm,
            hole_diameter_mm: c.hole_diameter_mm,
            fz_mm: c.fz_mm,
            chip_load_um: c
                .chip_load_mm
                .as_ref()
                .map(|v| v.iter().map(|h| h * 1e3).collect()),
        }
    }
}

/// The answer of a displacement report (issue 21 item 1): ρ ± SE must pass the SE test
/// (`crate::answer::se_test`: an SE, at most 25 % of ρ) and the size guards
/// (`runout_core::plausibility::runout_size`: ρ against the radius, and against f_z when given);
/// the angle must be determined for `identified` (ambiguous or undetermined → `partly
/// identified`, with the reason). `angle = None` means the command does not measure an angle
/// (heights without angles): the status is then the offset's alone.
#[allow(clippy::too_many_arguments)]
pub(crate) fn runout_answer(
    method: &str,
    offset_um: f64,
    offset_um_se: Option<f64>,
    angle: Option<&AngleReport>,
    radius_mm: f64,
    fz_mm: Option<f64>,
    what_to_do: &str,
    cross_checks: Vec<crate::answer::CrossCheck>,
) -> crate::answer::Answer {
    use crate::answer::{Answer, RunoutAnswer, IDENTIFIED, NOT_IDENTIFIED};
    use runout_core::plausibility::{runout_size, Severity};
    let mut reasons = Vec::new();
    let mut warnings = Vec::new();
    if let Some(r) = crate::answer::se_test("runout ρ", offset_um, offset_um_se, "µm", what_to_do)
    {
        reasons.push(r);
    }
    for f in runout_size(offset_um.abs() * 1e-3, radius_mm, fz_mm.unwrap_or(0.0)) {
        // no cutter given (heights): the limit is the absolute one, no radius to name
        let words = f.to_string().replace(" for a cutter of radius inf mm", "");
        match f.severity {
            Severity::NotIdentified => reasons.push(words),
            Severity::Warning => warnings.push(words),
        }
    }
    let rho_ok = reasons.is_empty();
    let (angle_ok, angle_words) = match angle {
        None => (true, "not measured (no angles in the input)".to_string()),
        Some(a) => match a.angle_status.as_str() {
            "determined" => (true, IDENTIFIED.to_string()),
            "ambiguous" => (false, "ambiguous (two candidates)".to_string()),
            _ => (false, NOT_IDENTIFIED.to_string()),
        },
    };
    if rho_ok && !angle_ok {
        if let Some(a) = angle {
            let why = a
                .angle_reason
                .clone()
                .unwrap_or_else(|| "not determined".into());
            reasons.push(format!("runout angle λ {angle_words}: {why}"));
        }
    }
    let angle_value = angle
        .filter(|_| rho_ok && angle_ok)
        .and_then(|a| a.angle_deg);
    Answer {
        status: Answer::status_of(rho_ok, angle_ok).into(),
        method: method.into(),
        runout: Some(RunoutAnswer {
            offset_um: rho_ok.then_some(offset_um),
            offset_um_se: if rho_ok { offset_um_se } else { None },
            angle_deg: angle_value,
            angle_deg_se: if angle_value.is_some() {
                angle.and_then(|a| a.angle_deg_se)
            } else {
                None
            },
            angle: if rho_ok {
                angle_words
            } else {
                NOT_IDENTIFIED.into()
            },
        }),
        results: Vec::new(),
        reasons,
        warnings,
        cross_checks,
    }
}
