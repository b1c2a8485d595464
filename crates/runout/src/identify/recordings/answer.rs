//! The one answer of `identify RECORDING…` (issue 21): the runout ρ ± SE and λ ± SE, the method it
//! came from, a status (`identified` / `partly identified` / `not identified`) with the reasons in
//! plain words, the six coefficients each with its own status, the plausibility guards
//! (`runout_core::plausibility`) and the assumed defaults as warnings, and the other estimates as
//! cross-checks with why they may differ.
//!
//! The status is the runout's: `identified` when ρ and λ pass their standard-error tests and every
//! guard; `partly identified` when ρ does but λ does not (K = 2 with straight flutes: only the
//! offset along the tooth line is observable; or λ's SE too large); `not identified` otherwise.
//! A coefficient that fails its SE test or its plausibility (negative, or outside the range
//! published for metals, ±2·SE) is reported as not identified, without a value to use.

use super::report::{Fitted, FullSignalReport, RecordingReport};
use super::{FileResult, RecordingsRequest, Verdicts};
use runout_core::plausibility::{self, Finding, Severity};
use runout_core::CuttingCoefficients;
use schemars::JsonSchema;
use serde::Serialize;

pub use crate::answer::{IDENTIFIED, NOT_IDENTIFIED, PARTLY};

/// The runout of the answer; values only when identified.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct RunoutAnswer {
    /// Runout offset ρ (µm); `null` when not identified.
    pub offset_um: Option<f64>,
    pub offset_um_se: Option<f64>,
    /// Runout angle λ (deg, from tooth 0 in the direction of rotation); `null` when not
    /// identified or only the offset along the tooth line is observable.
    pub angle_deg: Option<f64>,
    pub angle_deg_se: Option<f64>,
    /// `identified`, `along the tooth line only` (K = 2, straight flutes) or `not identified`.
    pub angle: String,
}

/// One cutting coefficient of the answer; the value only when identified.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct CoefficientAnswer {
    /// `K_tc`, `K_rc`, `K_ac`, `K_te`, `K_re` or `K_ae`.
    pub name: String,
    /// `N/mm²` (shear) or `N/mm` (edge).
    pub unit: String,
    /// The value in `unit`; `null` when not identified.
    pub value: Option<f64>,
    pub value_se: Option<f64>,
    /// `identified` or `not identified`.
    pub status: String,
    /// Why not, in words.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// Another estimate of the runout, shown as a cross-check.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct CrossCheck {
    /// Which estimate (`sine fit of the per-tooth peaks`).
    pub estimate: String,
    /// The recording it came from.
    pub file: String,
    pub offset_um: f64,
    pub offset_um_se: Option<f64>,
    pub angle_deg: f64,
    pub angle_deg_se: Option<f64>,
    /// Why it may differ from the answer.
    pub why_it_may_differ: String,
}

/// The answer: what a user should take from the report.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Answer {
    /// `identified`, `partly identified` or `not identified` (the runout's status; each
    /// coefficient has its own).
    pub status: String,
    /// The method the answer came from.
    pub method: String,
    pub runout: RunoutAnswer,
    pub coefficients: Vec<CoefficientAnswer>,
    /// Why the status is not `identified`, and what to do; also coefficients not identified.
    pub reasons: Vec<String>,
    /// Plausibility warnings and assumed defaults, each with what to check.
    pub warnings: Vec<String>,
    /// Other estimates of the runout, with why they may differ.
    pub cross_checks: Vec<CrossCheck>,
}

fn words(f: &Finding) -> String {
    f.to_string()
}

/// Guards on the recordings themselves: clipped channels, the same data twice, teeth × rpm
/// against the spectrum, the forces' magnitude against the cut (diameter, teeth, a_p, f_z).
pub(super) fn data_findings(req: &RecordingsRequest, files: &[FileResult]) -> Vec<Finding> {
    let mut out: Vec<Finding> = files.iter().flat_map(|f| f.clipped.clone()).collect();
    let items: Vec<(String, u64)> = files
        .iter()
        .map(|f| (f.name.clone(), f.content_hash))
        .collect();
    out.extend(plausibility::duplicates(&items));
    let k = req.cutter.teeth();
    for f in files {
        if let Some(x) = teeth_rpm(&f.name, k, f.cut.rpm(), f.analysis.scan.tooth_passing.hz) {
            out.push(x);
        }
    }
    out.extend(force_magnitude_findings(req, files));
    out
}

/// The forces' magnitude against the cut: recordings of one geometry (a_p, engagement) are
/// judged together, so that several feeds give the shear coefficient free of edge forces
/// (`plausibility::force_magnitude`).
fn force_magnitude_findings(req: &RecordingsRequest, files: &[FileResult]) -> Vec<Finding> {
    let mut groups: Vec<(runout_core::Cut, Vec<&FileResult>)> = Vec::new();
    for f in files {
        let same = |c: &runout_core::Cut| {
            c.ap() == f.cut.ap() && c.immersion(&req.cutter) == f.cut.immersion(&req.cutter)
        };
        match groups.iter_mut().find(|(c, _)| same(c)) {
            Some((_, g)) => g.push(f),
            None => groups.push((f.cut, vec![f])),
        }
    }
    let cutter = &req.cutter;
    groups
        .iter()
        .filter_map(|(cut, group)| {
            let geometry = plausibility::MeanForceGeometry::new(cutter, cut);
            let forces: Vec<plausibility::MeanForce> = group
                .iter()
                .map(|f| plausibility::MeanForce {
                    fz_mm: f.cut.fz(),
                    fxy_n: [f.mean_force[0], f.mean_force[1]],
                })
                .collect();
            let names: Vec<&str> = group.iter().map(|f| f.name.as_str()).collect();
            let (st, ex) = cut.immersion(cutter);
            let words = format!(
                "{} teeth, a_p {} mm and immersion {:.1}°–{:.1}° of a {} mm {} cutter",
                cutter.teeth(),
                cut.ap(),
                st.to_degrees(),
                ex.to_degrees(),
                cutter.diameter(),
                profile_word(cutter.profile()),
            );
            plausibility::force_magnitude(&names.join(", "), &words, &geometry, &forces)
        })
        .collect()
}

fn profile_word(p: &runout_core::RadiusProfile) -> &'static str {
    match p {
        runout_core::RadiusProfile::Flat => "flat-end",
        runout_core::RadiusProfile::Ball => "ball-end",
        runout_core::RadiusProfile::BullNose { .. } => "bull-nose",
        runout_core::RadiusProfile::Tapered { .. } => "tapered",
    }
}

/// The tooth-passing line of the spectrum (`line_hz`) against K·n/60: when the strongest line near
/// it is at another multiple m of the nominal spindle frequency (off by more than 3 %), the
/// teeth or the rpm are wrong.
pub(super) fn teeth_rpm(name: &str, teeth: usize, rpm: f64, line_hz: f64) -> Option<Finding> {
    let spindle_hz = rpm / 60.0;
    let expected = teeth as f64 * spindle_hz;
    if !(line_hz.is_finite() && spindle_hz > 0.0) || (line_hz - expected).abs() <= 0.03 * expected {
        return None;
    }
    let m = line_hz / spindle_hz;
    let at = if (m - m.round()).abs() < 0.03 * m.round().max(1.0) {
        format!("{:.0} × the spindle frequency", m.round())
    } else {
        format!("{m:.2} × the spindle frequency")
    };
    Some(Finding {
        code: "teeth_rpm_contradicted",
        subject: name.into(),
        message: format!(
            "in {name} the strongest periodic component near the tooth-passing frequency is at \
             {line_hz:.1} Hz = {at}, not K × n/60 = {teeth} × {spindle_hz:.2} = {expected:.1} Hz"
        ),
        hint: "check --teeth and --rpm (the nominal spindle speed) against the cutter and the \
               machine"
            .into(),
        severity: Severity::NotIdentified,
    })
}

/// The coefficients' statuses: the verdicts of the fit (SE tests), then plausibility and sign.
fn coefficients(
    f: &FullSignalReport,
    verdicts: &Verdicts,
    general: bool,
) -> Vec<CoefficientAnswer> {
    let all = f.coefficients.all();
    let keys = ["ktc", "krc", "kac", "kte", "kre", "kae"];
    let values: Vec<f64> = all.iter().map(|x| x.0).collect();
    let se: Vec<f64> = all.iter().map(|x| x.1.unwrap_or(f64::NAN)).collect();
    let plaus = CuttingCoefficients::new(
        [values[0], values[1], values[2]],
        [values[3], values[4], values[5]],
    )
    .map(|k| plausibility::coefficients(&k, Some([se[0], se[1], se[2], se[3], se[4], se[5]])))
    .unwrap_or_default();
    all.iter()
        .enumerate()
        .map(|(i, &(v, s))| {
            let (name, unit) = plausibility::COEFFICIENT_NAMES[i];
            let mut why: Vec<String> = Vec::new();
            if s.is_none() {
                why.push("not fitted (held at its start value)".into());
            }
            if let Some(r) = verdicts
                .parameters
                .iter()
                .find(|p| p.parameter == keys[i])
                .and_then(|p| p.reason.clone())
            {
                why.push(r);
            }
            if general {
                why.push("the fit as a whole is not identified".into());
            }
            why.extend(plaus.iter().filter(|p| p.subject == name).map(words));
            if v < 0.0 && !why.iter().any(|w| w.contains("negative")) {
                why.push(format!(
                    "negative ({v:.2} {unit}): possible in a fit but not a value to use for a \
                     metal; model error (geometry, helix, resonance) is absorbed here"
                ));
            }
            let ok = why.is_empty();
            CoefficientAnswer {
                name: name.into(),
                unit: unit.into(),
                value: ok.then_some(v),
                value_se: if ok { s } else { None },
                status: if ok { IDENTIFIED } else { NOT_IDENTIFIED }.into(),
                reason: (!ok).then(|| format!("{name}: {}", why.join("; "))),
            }
        })
        .collect()
}

fn cross_checks(recs: &[RecordingReport], fit_ok: bool) -> Vec<CrossCheck> {
    recs.iter()
        .filter_map(|r| {
            let s = r.sine_fit.ok()?;
            let slot = r.entry_deg.abs() < 1e-7 && (r.exit_deg - 180.0).abs() < 1e-7;
            let why = if slot {
                "the sine fit uses only the per-tooth peaks of the resultant and ignores the \
                 edge forces and the helix"
            } else {
                "biased at partial immersion: edge forces are not in its model, and teeth that \
                 lose contact are not either"
            };
            Some(CrossCheck {
                estimate: "sine fit of the per-tooth peaks".into(),
                file: r.file.clone(),
                offset_um: s.offset_um,
                offset_um_se: s.offset_um_se,
                angle_deg: s.angle_deg,
                angle_deg_se: s.angle_deg_se,
                why_it_may_differ: if fit_ok {
                    why.into()
                } else {
                    format!("{why}; shown because the full-signal fit failed, not as the answer")
                },
            })
        })
        .collect()
}

/// The answer of the report.
pub(super) fn build(
    req: &RecordingsRequest,
    files: &[FileResult],
    full: &Fitted<FullSignalReport>,
    verdicts: &Verdicts,
    recs: &[RecordingReport],
    chain_used: &str,
) -> Answer {
    let mut warnings: Vec<String> = req.assumed.clone();
    let mut reasons: Vec<String> = Vec::new();
    let data = data_findings(req, files);
    let f = match full {
        Fitted::Failed { error } => {
            reasons.push(format!(
                "the full-signal fit failed ({error}): the sine fits below are biased cross-checks, \
                 not the answer"
            ));
            for d in &data {
                match d.severity {
                    Severity::NotIdentified => reasons.push(words(d)),
                    Severity::Warning => warnings.push(words(d)),
                }
            }
            return Answer {
                status: NOT_IDENTIFIED.into(),
                method: "none: the full-signal fit failed".into(),
                runout: RunoutAnswer {
                    offset_um: None,
                    offset_um_se: None,
                    angle_deg: None,
                    angle_deg_se: None,
                    angle: NOT_IDENTIFIED.into(),
                },
                coefficients: Vec::new(),
                reasons,
                warnings,
                cross_checks: cross_checks(recs, false),
            };
        }
        Fitted::Fit(f) => f,
    };
    let general = !verdicts.fit.is_empty();
    reasons.extend(verdicts.fit.iter().cloned());
    let own = |p: &str| {
        verdicts
            .parameters
            .iter()
            .find(|x| x.parameter == p)
            .and_then(|x| x.reason.clone())
    };
    // runout
    let radius = req.cutter.diameter() / 2.0;
    let fz_min = files
        .iter()
        .map(|x| x.cut.fz())
        .fold(f64::INFINITY, f64::min);
    let size = plausibility::runout_size(f.offset_um * 1e-3, radius, fz_min);
    let mut rho_ok = !general;
    if let Some(r) = own("offset") {
        reasons.push(format!("runout ρ: {r}"));
        rho_ok = false;
    }
    for x in size.iter().chain(&data) {
        match x.severity {
            Severity::NotIdentified => {
                reasons.push(words(x));
                rho_ok = false;
            }
            Severity::Warning => warnings.push(words(x)),
        }
    }
    let along = matches!(
        f.observability,
        runout_core::identify::RunoutObservability::AlongDirection { .. }
    );
    let angle_reason = own("angle");
    let angle_ok = rho_ok && !along && angle_reason.is_none();
    if rho_ok {
        if let Some(r) = &angle_reason {
            reasons.push(format!("runout angle λ: {r}"));
        }
    }
    let status = if !rho_ok {
        NOT_IDENTIFIED
    } else if angle_ok {
        IDENTIFIED
    } else {
        PARTLY
    };
    let coefficients = coefficients(f, verdicts, general);
    if rho_ok {
        reasons.extend(coefficients.iter().filter_map(|c| c.reason.clone()));
    }
    Answer {
        status: status.into(),
        method: format!(
            "full-signal fit of the averaged waveforms of all recordings jointly, through the \
             measuring chain ({})",
            chain_used.replace('_', " ")
        ),
        runout: RunoutAnswer {
            offset_um: rho_ok.then_some(f.offset_um),
            offset_um_se: if rho_ok { f.offset_um_se } else { None },
            angle_deg: angle_ok.then_some(f.angle_deg),
            angle_deg_se: if angle_ok { f.angle_deg_se } else { None },
            angle: if !rho_ok {
                NOT_IDENTIFIED
            } else if along {
                "along the tooth line only"
            } else if angle_ok {
                IDENTIFIED
            } else {
                NOT_IDENTIFIED
            }
            .into(),
        },
        coefficients,
        reasons,
        warnings,
        cross_checks: cross_checks(recs, true),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn teeth_rpm_guard_fires_only_on_a_contradiction() {
        // 4 teeth at 3240 rpm: the line at 216 Hz agrees (within the 3 % tolerance: 1 %)
        assert!(teeth_rpm("a", 4, 3240.0, 216.0 * 1.01).is_none());
        // told 3 teeth, the line is at 4 × 54 Hz
        let f = teeth_rpm("a", 3, 3240.0, 216.0).expect("contradiction");
        assert!(
            f.message.contains("4 × the spindle frequency"),
            "{}",
            f.message
        );
        assert_eq!(f.severity, Severity::NotIdentified);
    }

    #[test]
    fn runout_larger_than_the_feed_per_tooth_is_a_warning_not_a_failure() {
        // ρ 8 µm, R 5 mm: f_z 0.05 mm passes, f_z 0.005 mm triggers the warning
        assert!(plausibility::runout_size(0.008, 5.0, 0.05).is_empty());
        let w = plausibility::runout_size(0.008, 5.0, 0.005);
        assert_eq!(w[0].code, "runout_exceeds_feed");
        assert_eq!(w[0].severity, Severity::Warning);
    }
}
