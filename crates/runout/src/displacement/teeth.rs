//! `displacement teeth`: per-tooth readings → (ρ, λ), methods.md §1.5.

use super::{name_of, AngleReport, BeamReport, ConsequencesReport, Sensor};
use crate::answer::{Answer, Answered, CrossCheck, Quantity};
use crate::job::{Report, Source};
use crate::verdict::{VerdictBasis, VerdictReport};
use anyhow::{Context, Result};
use runout_core::displacement::{
    consequences, identify_from_teeth, Consequences, SensorSign, ToothFit, ToothFitOptions,
    ToothReadings,
};
use runout_io::displacement::read_tooth_table;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `runout displacement teeth`: the readings table and the fit options (cutter, height,
/// method, known offset, noise, beam, phase hint inside `options`).
#[derive(Debug, Clone)]
pub struct TeethRequest {
    /// CSV with `tooth` or `seed_edge` and `reading_<um|mm>`.
    pub readings: Source,
    pub options: ToothFitOptions,
    /// Sensor sign convention (the beam is `options.beam`).
    pub sign: SensorSign,
    /// Feed per tooth (mm) for the predicted chip loads.
    pub fz_mm: Option<f64>,
    /// Circular tool path diameter (mm) for the predicted hole diameter.
    pub hole_path_mm: Option<f64>,
}

/// The inputs as reported.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct TeethInput {
    pub file: String,
    pub tooth_numbering: String,
    pub teeth: usize,
    pub diameter_mm: f64,
    pub helix_deg: f64,
    pub height_mm: f64,
    pub beam: BeamReport,
    pub known_offset_um: Option<f64>,
    #[serde(alias = "known_offset_se_um")]
    pub known_offset_um_se: Option<f64>,
    pub noise_um: Option<f64>,
    pub phase_deg: Option<f64>,
}

/// `runout.displacement.teeth/2`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct TeethReport {
    /// `runout.displacement.teeth/2`
    #[schemars(extend("const" = "runout.displacement.teeth/2"))]
    pub schema: String,
    /// The result first: ρ ± SE, λ ± SE, the method, the status and its reasons (issue 21).
    #[serde(default)]
    pub answer: Answer,
    pub input: TeethInput,
    pub method: String,
    pub offset_um: f64,
    #[serde(alias = "offset_se_um")]
    pub offset_um_se: Option<f64>,
    pub positions_um: Vec<f64>,
    pub radius_differences_um: Vec<f64>,
    pub residual_rms_um: f64,
    pub dof: usize,
    pub noise_used_um: Option<f64>,
    pub noise_source: String,
    pub condition_number: Option<f64>,
    pub beam_factor: f64,
    pub notes: Vec<String>,
    pub consequences: Option<ConsequencesReport>,
    /// Pass/fail against the runout tolerance and the consequences for the cut (issue 15).
    pub verdict: Option<VerdictReport>,
    #[serde(flatten)]
    pub angle: AngleReport,
    /// The core results behind the text and the plot; not part of the JSON.
    #[serde(skip)]
    #[schemars(skip)]
    pub detail: TeethDetail,
}

/// The core results of `displacement teeth`.
#[derive(Debug, Clone, Default)]
pub struct TeethDetail {
    pub fit: Option<ToothFit>,
    pub options: Option<ToothFitOptions>,
    pub consequences: Option<Consequences>,
}

impl Answered for TeethReport {
    fn answer(&self) -> &Answer {
        &self.answer
    }
}

impl Report for TeethReport {
    const SCHEMA: &'static str = "runout.displacement.teeth/2";
}

/// Fit the runout to per-tooth readings.
pub fn teeth(req: &TeethRequest) -> Result<TeethReport> {
    let opts = &req.options;
    let cutter = &opts.cutter;
    let k = cutter.teeth();
    let name = req.readings.name();
    let table = read_tooth_table(req.readings.table_input(), k)?;
    let readings =
        ToothReadings::new(k, &table.readings, req.sign).with_context(|| name.to_string())?;
    let fit = identify_from_teeth(&readings, opts).with_context(|| name.to_string())?;
    let cons = match fit.runout() {
        Some(r) => Some(consequences(
            cutter,
            &r,
            opts.height_mm,
            req.fz_mm,
            req.hole_path_mm,
        )?),
        None => None,
    };
    let um = |v: &[f64]| v.iter().map(|x| x * 1e3).collect::<Vec<_>>();
    let angle = AngleReport::from(&fit.angle);
    let spread = {
        let p = &fit.positions_mm;
        let max = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let min = p.iter().copied().fold(f64::INFINITY, f64::min);
        (max - min) / 2.0 * 1e3
    };
    let answer = super::runout_answer(
        &format!(
            "{} fit of the runout to the per-tooth readings (docs/methods.md §1.5)",
            crate::words::plain(&fit.method)
        ),
        fit.offset_mm * 1e3,
        fit.offset_se_mm.map(|x| x * 1e3),
        Some(&angle),
        cutter.diameter() / 2.0,
        req.fz_mm,
        "repeat the readings (several sweeps give the noise) or pass --noise-um, the noise of one \
         reading",
        vec![CrossCheck {
            estimate: "half the spread of the readings, (max P − min P)/2".into(),
            values: vec![Quantity::cross_check("runout offset ρ", "µm", spread, None)],
            why_it_may_differ: format!(
                "equals ρ only when two teeth lie along the runout direction; with {k} teeth it is \
                 smaller otherwise, and it takes the reading noise as runout"
            ),
        }],
    );
    let sensor = Sensor {
        sign: req.sign,
        beam: opts.beam,
    };
    Ok(TeethReport {
        schema: TeethReport::SCHEMA.into(),
        answer,
        input: TeethInput {
            file: name.to_string(),
            tooth_numbering: if table.from_seed_edges {
                "seed_edge (converted: tooth = (1 - k) mod K)"
            } else {
                "tooth (0-based, cutting order)"
            }
            .into(),
            teeth: k,
            diameter_mm: cutter.diameter(),
            helix_deg: cutter.helix().to_degrees(),
            height_mm: opts.height_mm,
            beam: BeamReport::from(&sensor),
            known_offset_um: opts.known_offset_mm.map(|x| x * 1e3),
            known_offset_um_se: opts.known_offset_se_mm.map(|x| x * 1e3),
            noise_um: opts.noise_mm.map(|x| x * 1e3),
            phase_deg: opts.phase_hint_rad.map(f64::to_degrees),
        },
        method: name_of(&fit.method),
        offset_um: fit.offset_mm * 1e3,
        offset_um_se: fit.offset_se_mm.map(|x| x * 1e3),
        positions_um: um(&fit.positions_mm),
        radius_differences_um: um(&fit.radius_differences_mm),
        residual_rms_um: fit.residual_rms_mm * 1e3,
        dof: fit.dof,
        noise_used_um: fit.noise_mm.map(|x| x * 1e3),
        noise_source: name_of(&fit.noise_source),
        condition_number: fit.condition_number,
        beam_factor: fit.beam_factor,
        notes: fit.notes.clone(),
        consequences: cons.as_ref().map(ConsequencesReport::from),
        verdict: Some(VerdictReport::new(
            VerdictBasis {
                offset_um: fit.offset_mm * 1e3,
                offset_um_se: fit.offset_se_mm.map(|x| x * 1e3),
                angle_deg: fit.angle.angle().map(f64::to_degrees),
                teeth: Some(k),
                diameter_mm: Some(cutter.diameter()),
                helix_deg: cutter.helix().to_degrees(),
                height_mm: opts.height_mm,
                fz_mm: req.fz_mm,
            },
            None,
        )?),
        angle,
        detail: TeethDetail {
            fit: Some(fit),
            options: Some(opts.clone()),
            consequences: cons,
        },
    })
}
