//! The verdict on an identified runout and its consequences for the cut, as a field of the
//! reports that identify a runout (`displacement teeth|heights|signal`, `shank force`,
//! `identify`): one source for the text, the JSON and the HTML report. The numbers come from
//! [`runout_core::verdict`] (equations and the cited default tolerance there).
//!
//! The report keeps what it was computed from ([`VerdictBasis`]), so a saved JSON report can be
//! judged again against another tolerance ([`VerdictReport::with_tolerance`], `runout report
//! --tolerance-um`).

use anyhow::Result;
use runout_core::verdict::{
    axis_split, default_tolerance_tir_mm, verdict, AxisSplit, VerdictInput,
    DEFAULT_TOLERANCE_SOURCE,
};
use runout_core::{Cutter, Runout};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What the verdict is computed from (lengths as in the report: µm for runout, mm otherwise).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VerdictBasis {
    /// Identified offset ρ (µm) at `height_mm`.
    pub offset_um: f64,
    /// Its standard error (µm), if known.
    #[serde(alias = "offset_se_um")]
    pub offset_um_se: Option<f64>,
    /// Its angle λ (deg from tooth 0 in the direction of rotation), if determined; without it the
    /// per-tooth consequences cannot be assigned to teeth and are left out.
    pub angle_deg: Option<f64>,
    /// Number of teeth K, if known.
    pub teeth: Option<usize>,
    /// Cutter diameter D (mm), if known (also picks the default tolerance).
    pub diameter_mm: Option<f64>,
    /// Helix angle (deg).
    pub helix_deg: f64,
    /// Height above the tip (mm) of the verdict.
    pub height_mm: f64,
    /// Feed per tooth f_z (mm), if known.
    pub fz_mm: Option<f64>,
}

/// One tooth's share of the cut.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ToothVerdict {
    /// Tooth number (0-based, cutting order).
    pub tooth: usize,
    /// Actual radius R_i (mm).
    pub radius_mm: f64,
    /// R_i − R (µm).
    pub radius_deviation_um: f64,
    /// Largest chip h_i (µm), arc model at φ = 90°.
    pub max_chip_um: Option<f64>,
    /// Share of the load, h_i / Σ h_j (0–1).
    pub load_share: Option<f64>,
}

/// Runout at the tip against higher up the tool.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct AxisReport {
    /// Runout |e| at the tip (cutting height) (µm).
    pub tip_offset_um: f64,
    /// Runout |e| at the upper height (µm).
    pub upper_offset_um: f64,
    /// What the upper height is (`gauge line`, `upper sensor`, `highest reading`).
    pub upper_name: String,
    /// Upper height above the tip (mm).
    pub upper_height_mm: f64,
    /// Tilt |τ| of the tool axis (µm per mm).
    pub tilt_um_per_mm: f64,
    /// `tilt` or `offset`: which dominates the runout at the tip.
    pub dominated_by: String,
}

impl AxisReport {
    /// From the core split; `upper_name` says what the upper height is.
    pub fn new(s: &AxisSplit, upper_name: &str) -> Self {
        Self {
            tip_offset_um: s.tip_offset_mm * 1e3,
            upper_offset_um: s.upper_offset_mm * 1e3,
            upper_name: upper_name.into(),
            upper_height_mm: s.upper_height_mm,
            tilt_um_per_mm: s.tilt_mm_per_mm * 1e3,
            dominated_by: s.dominated_by.clone(),
        }
    }

    /// From runout vectors (µm, polar: magnitude and angle in deg) at the tip and at
    /// `upper_height_mm` above it.
    pub fn from_polar(
        tip: (f64, f64),
        upper: (f64, f64),
        upper_height_mm: f64,
        upper_name: &str,
    ) -> Result<Self> {
        let v = |(m, a): (f64, f64)| {
            let a = a.to_radians();
            [m * 1e-3 * a.cos(), m * 1e-3 * a.sin()]
        };
        Ok(Self::new(
            &axis_split(v(tip), v(upper), upper_height_mm)?,
            upper_name,
        ))
    }
}

/// The verdict (field `verdict` of the reports).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VerdictReport {
    /// `pass`, `marginal` (the tolerance lies within the ±2σ interval of the TIR) or `fail`.
    pub status: String,
    /// Total indicated runout TIR = 2ρ (µm).
    pub tir_um: f64,
    /// Standard error of the TIR (µm).
    #[serde(alias = "tir_se_um")]
    pub tir_um_se: Option<f64>,
    /// Tolerance on the TIR (µm).
    pub tolerance_tir_um: f64,
    /// `given`, or the standard the default comes from.
    pub tolerance_source: String,
    /// Slot / wall oversize 2·(max R_i − R) (µm); 2ρ when the teeth are unknown.
    pub slot_oversize_um: f64,
    /// Nominal largest chip f_z (µm).
    pub nominal_chip_um: Option<f64>,
    /// Largest chip of any tooth (µm).
    pub max_chip_um: Option<f64>,
    /// Tooth with the largest chip: most load, wears first.
    pub most_loaded_tooth: Option<usize>,
    /// Teeth that do not cut.
    pub idle_teeth: Vec<usize>,
    /// Feed per tooth keeping the most loaded tooth at the nominal chip (mm).
    pub compensated_fz_mm: Option<f64>,
    /// Metal removal rate lost at that feed (%).
    pub productivity_loss_percent: Option<f64>,
    /// Per tooth (empty when the cutter or the angle is unknown).
    pub teeth: Vec<ToothVerdict>,
    /// Runout at the tip against higher up the tool, when measured at two heights.
    pub axis: Option<AxisReport>,
    /// The verdict and what to do, in words.
    pub findings: Vec<String>,
    /// What it was computed from.
    pub basis: VerdictBasis,
}

impl VerdictReport {
    /// The verdict on `basis` against `tolerance_tir_um` (`None`: the ISO 15488 class-1
    /// default for the diameter, [`runout_core::verdict::default_tolerance_tir_mm`]).
    pub fn new(basis: VerdictBasis, tolerance_tir_um: Option<f64>) -> Result<Self> {
        let cutter = match (basis.teeth, basis.diameter_mm, basis.angle_deg) {
            (Some(k), Some(d), Some(_)) => Some(Cutter::flat(d, k, basis.helix_deg.to_radians())?),
            _ => None,
        };
        let rho = basis.offset_um.max(0.0) * 1e-3;
        let v = verdict(&VerdictInput {
            runout: Runout::new(rho, basis.angle_deg.unwrap_or(0.0).to_radians())?,
            offset_se_mm: basis.offset_um_se.map(|s| s * 1e-3),
            cutter: cutter.clone(),
            height_mm: basis.height_mm,
            fz_mm: basis.fz_mm,
            tolerance_tir_mm: Some(
                tolerance_tir_um
                    .map(|t| t * 1e-3)
                    .unwrap_or_else(|| default_tolerance_tir_mm(basis.diameter_mm)),
            ),
        })?;
        let source = match tolerance_tir_um {
            Some(_) => "given",
            None => DEFAULT_TOLERANCE_SOURCE,
        };
        let r_nom = cutter
            .as_ref()
            .map_or(0.0, |c| c.radius_at(basis.height_mm));
        let um = |x: Option<f64>| x.map(|v| v * 1e3);
        let mut r = Self {
            status: v.status.as_str().into(),
            tir_um: v.tir_mm * 1e3,
            tir_um_se: um(v.tir_se_mm),
            tolerance_tir_um: v.tolerance_tir_mm * 1e3,
            tolerance_source: source.into(),
            slot_oversize_um: v.slot_oversize_mm * 1e3,
            nominal_chip_um: um(v.nominal_chip_mm),
            max_chip_um: um(v.max_chip_mm),
            most_loaded_tooth: v.most_loaded_tooth,
            idle_teeth: v.idle_teeth.clone(),
            compensated_fz_mm: v.compensated_fz_mm,
            productivity_loss_percent: v.productivity_loss_percent,
            teeth: v
                .teeth
                .iter()
                .map(|t| ToothVerdict {
                    tooth: t.tooth,
                    radius_mm: t.radius_mm,
                    radius_deviation_um: (t.radius_mm - r_nom) * 1e3,
                    max_chip_um: um(t.max_chip_mm),
                    load_share: t.load_share,
                })
                .collect(),
            axis: None,
            findings: vec![],
            basis,
        };
        r.findings = r.words();
        Ok(r)
    }

    /// Add the tip-vs-upper comparison (and its finding).
    pub fn with_axis(mut self, axis: Option<AxisReport>) -> Self {
        self.axis = axis;
        self.findings = self.words();
        self
    }

    /// The same verdict against another tolerance (`None`: the default).
    pub fn with_tolerance(&self, tolerance_tir_um: Option<f64>) -> Result<Self> {
        Ok(Self::new(self.basis.clone(), tolerance_tir_um)?.with_axis(self.axis.clone()))
    }

    /// The findings in words: the status, then the consequences and what to change.
    fn words(&self) -> Vec<String> {
        let mut w = Vec::new();
        let se = self
            .tir_um_se
            .map_or(String::new(), |s| format!(" ± {s:.2}"));
        let tol = format!(
            "the tolerance {:.1} µm TIR ({})",
            self.tolerance_tir_um, self.tolerance_source
        );
        w.push(match self.status.as_str() {
            "pass" => format!(
                "PASS: runout TIR 2ρ = {:.2}{se} µm is within {tol}.",
                self.tir_um
            ),
            "fail" => format!(
                "FAIL: runout TIR 2ρ = {:.2}{se} µm exceeds {tol}.",
                self.tir_um
            ),
            _ => format!(
                "MARGINAL: runout TIR 2ρ = {:.2}{se} µm is within 2σ of {tol}; measure again or longer to decide.",
                self.tir_um
            ),
        });
        if let (Some(t), Some(h), Some(n)) = (
            self.most_loaded_tooth,
            self.max_chip_um,
            self.nominal_chip_um,
        ) {
            let share = self.teeth.get(t).and_then(|x| x.load_share).unwrap_or(0.0);
            let k = self.teeth.len().max(1);
            w.push(format!(
                "Tooth {t} takes the largest chip, {h:.2} µm against {n:.2} µm nominal ({:+.1} %), and {:.1} % of the load (nominal {:.1} %): it wears or chips first.",
                100.0 * (h / n - 1.0),
                100.0 * share,
                100.0 / k as f64
            ));
        }
        if !self.idle_teeth.is_empty() {
            let list: Vec<String> = self.idle_teeth.iter().map(|t| t.to_string()).collect();
            w.push(format!(
                "Tooth {} does not cut: the runout exceeds what the feed per tooth can absorb.",
                list.join(", ")
            ));
        }
        w.push(format!(
            "Slot and walls are cut {:.2} µm oversize (2·(max R_i − R)); feed marks repeat once per revolution.",
            self.slot_oversize_um
        ));
        if let (Some(c), Some(p), Some(fz)) = (
            self.compensated_fz_mm,
            self.productivity_loss_percent,
            self.basis.fz_mm,
        ) {
            if p > 0.05 {
                w.push(format!(
                    "To keep the most loaded tooth at the nominal chip, feed f_z = {c:.4} mm instead of {fz:.4} mm: {p:.1} % less metal removal rate."
                ));
            }
        }
        if let Some(a) = &self.axis {
            w.push(format!(
                "Runout {:.2} µm at the tip, {:.2} µm at the {} ({:.1} mm above): tilt {:.3} µm/mm, {}.",
                a.tip_offset_um,
                a.upper_offset_um,
                a.upper_name,
                a.upper_height_mm,
                a.tilt_um_per_mm,
                if a.dominated_by == "tilt" {
                    "the tool axis is inclined (check the taper and collet seating for dirt or damage)"
                } else {
                    "a parallel offset (collet / holder eccentricity)"
                }
            ));
        }
        if self.status != "pass" {
            w.push(
                "What to change: clean and re-clamp the tool (turn it in the collet to find the best position), or use a holder of a better class (shrink-fit / hydraulic, ≤ 3 µm); otherwise run at the compensated feed."
                    .into(),
            );
        }
        if self.basis.angle_deg.is_none() && self.basis.teeth.is_some() {
            w.push(
                "The runout angle is not determined: the per-tooth consequences are left out."
                    .into(),
            );
        }
        w
    }
}

/// The verdict as text lines (the text reports end with it).
pub fn verdict_text(v: &VerdictReport) -> String {
    let mut s = String::from("verdict:\n");
    for f in &v.findings {
        s += &format!("  {f}\n");
    }
    for t in &v.teeth {
        s += &format!(
            "  tooth {}: radius {:.4} mm ({:+.2} µm)",
            t.tooth, t.radius_mm, t.radius_deviation_um
        );
        if let (Some(h), Some(l)) = (t.max_chip_um, t.load_share) {
            s += &format!(", max chip {h:.2} µm, load {:.1} %", 100.0 * l);
        }
        s += "\n";
    }
    s
}

/// A report that may carry a verdict (the jobs that identify a runout).
pub trait HasVerdict {
    /// The verdict field.
    fn verdict_slot(&mut self) -> &mut Option<VerdictReport>;
    /// The verdict, if any.
    fn verdict(&self) -> Option<&VerdictReport>;

    /// Judge again against `tolerance_tir_um` (µm TIR; `None`: leave the default).
    fn set_tolerance(&mut self, tolerance_tir_um: Option<f64>) -> Result<()> {
        if let (Some(t), Some(v)) = (tolerance_tir_um, self.verdict_slot().as_ref()) {
            let w = v.with_tolerance(Some(t))?;
            *self.verdict_slot() = Some(w);
        }
        Ok(())
    }
}

macro_rules! has_verdict {
    ($($t:ty),*) => {$(
        impl HasVerdict for $t {
            fn verdict_slot(&mut self) -> &mut Option<VerdictReport> {
                &mut self.verdict
            }
            fn verdict(&self) -> Option<&VerdictReport> {
                self.verdict.as_ref()
            }
        }
    )*};
}

has_verdict!(
    crate::displacement::TeethReport,
    crate::displacement::HeightsReport,
    crate::displacement::SignalReport,
    crate::shank::ForceReport,
    crate::identify::RecordingsReport
);

#[cfg(test)]
mod tests {
    use super::*;

    fn basis() -> VerdictBasis {
        VerdictBasis {
            offset_um: 10.0,
            offset_um_se: Some(0.5),
            angle_deg: Some(0.0),
            teeth: Some(4),
            diameter_mm: Some(10.0),
            helix_deg: 0.0,
            height_mm: 0.0,
            fz_mm: Some(0.05),
        }
    }

    #[test]
    fn report_units_and_words() {
        let v = VerdictReport::new(basis(), None).unwrap();
        assert_eq!(v.status, "fail");
        assert!((v.tir_um - 20.0).abs() < 1e-12);
        assert_eq!(v.tir_um_se, Some(1.0));
        assert_eq!(v.tolerance_tir_um, 10.0);
        assert_eq!(v.most_loaded_tooth, Some(3));
        assert!((v.teeth[0].radius_deviation_um - 10.0).abs() < 1e-9);
        assert!((v.max_chip_um.unwrap() - 60.00999).abs() < 1e-4);
        assert!(v.findings[0].starts_with("FAIL"), "{:?}", v.findings);
        assert!(v.findings.iter().any(|f| f.contains("f_z = 0.0417 mm")));
        // judged again against 25 µm: passes (2(10 + 1) = 22 ≤ 25), same consequences
        let w = v.with_tolerance(Some(25.0)).unwrap();
        assert_eq!(w.status, "pass");
        assert_eq!(w.tolerance_source, "given");
        assert_eq!(w.teeth, v.teeth);
        // a JSON round trip keeps it
        let j = serde_json::to_string(&v).unwrap();
        let back: VerdictReport = serde_json::from_str(&j).unwrap();
        assert_eq!(back, v);
    }

    #[test]
    fn without_the_angle_no_teeth() {
        let mut b = basis();
        b.angle_deg = None;
        let v = VerdictReport::new(b, None).unwrap();
        assert!(v.teeth.is_empty() && v.most_loaded_tooth.is_none());
        assert!(v.findings.iter().any(|f| f.contains("not determined")));
    }
}
