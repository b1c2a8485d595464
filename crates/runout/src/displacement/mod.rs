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
    pub angle_se_deg: Option<f64>,
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
            angle_se_deg: se,
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
