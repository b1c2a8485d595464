//! The one answer of the displacement, shank and grind reports (issue 21 item 1), in the shape of
//! `identify`'s (`crate::identify::recordings::answer`): what a user should take from the report,
//! first in the JSON (right after `schema`) and in the text.
//!
//! * `status`: `identified` / `partly identified` / `not identified` — whether the result can be
//!   used as it stands; the CLI exits 3 unless `identified`.
//! * `method`: where the result came from.
//! * `runout`: the runout ρ ± SE and λ ± SE when the command measures one (values only when
//!   identified); `results`: the other quantities of the answer (tilt, stiffness, deviations),
//!   each ± SE with its own status.
//! * `reasons`: why the status is not `identified`, in plain words with what to do;
//!   `warnings`: plausibility warnings that do not change the status.
//! * `cross_checks`: other estimates in the report, each with why it may differ.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `identified`.
pub const IDENTIFIED: &str = "identified";
/// `partly identified`.
pub const PARTLY: &str = "partly identified";
/// `not identified`.
pub const NOT_IDENTIFIED: &str = "not identified";

/// The largest standard error of a result, as a fraction of its value, for the result to be
/// called identified: at SE > 25 % the value's first digit is uncertain (a 2-SE interval spans
/// ±50 %), so it is not a number to use as it stands.
pub const MAX_RELATIVE_SE: f64 = 0.25;

/// The runout of an answer; values only when identified.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
pub struct RunoutAnswer {
    /// Runout offset ρ (µm); `null` when not identified.
    pub offset_um: Option<f64>,
    /// Its standard error (µm).
    pub offset_um_se: Option<f64>,
    /// Runout angle λ (deg, from tooth 0 in the direction of rotation, or from the report's
    /// angle origin); `null` when not identified.
    pub angle_deg: Option<f64>,
    /// Its standard error (deg).
    pub angle_deg_se: Option<f64>,
    /// `identified`, `ambiguous (two candidates)`, `along the tooth line only` or
    /// `not identified`.
    pub angle: String,
}

/// One quantity of an answer or of a cross-check, ± SE.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
pub struct Quantity {
    /// The quantity in words (`runout offset ρ`, `tilt`, `stiffness K_δ`).
    pub name: String,
    /// Its unit (`µm`, `deg`, `µm/mm`, `N/µm`).
    pub unit: String,
    /// The value in `unit`; `null` when not identified.
    pub value: Option<f64>,
    /// Its standard error in `unit`, when known.
    pub value_se: Option<f64>,
    /// `identified` or `not identified` (in a cross-check: `cross-check`).
    pub status: String,
}

impl Quantity {
    /// An identified quantity.
    pub fn identified(name: &str, unit: &str, value: f64, se: Option<f64>) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
            value: Some(value),
            value_se: se,
            status: IDENTIFIED.into(),
        }
    }

    /// A quantity that is not identified: no value to use.
    pub fn not_identified(name: &str, unit: &str) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
            value: None,
            value_se: None,
            status: NOT_IDENTIFIED.into(),
        }
    }

    /// A value shown as a cross-check.
    pub fn cross_check(name: &str, unit: &str, value: f64, se: Option<f64>) -> Self {
        Self {
            status: "cross-check".into(),
            ..Self::identified(name, unit, value, se)
        }
    }
}

/// Another estimate in the report, with why it may differ from the answer.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
pub struct CrossCheck {
    /// Which estimate.
    pub estimate: String,
    /// Its values.
    pub values: Vec<Quantity>,
    /// Why it may differ from the answer.
    pub why_it_may_differ: String,
}

/// The answer of a report.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
pub struct Answer {
    /// `identified`, `partly identified` or `not identified`.
    pub status: String,
    /// The method the answer came from.
    pub method: String,
    /// The runout, when the command measures one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runout: Option<RunoutAnswer>,
    /// The other results, each with its status.
    pub results: Vec<Quantity>,
    /// Why the status is not `identified`, and what to do.
    pub reasons: Vec<String>,
    /// Plausibility warnings, each with what to check.
    pub warnings: Vec<String>,
    /// Other estimates, with why they may differ.
    pub cross_checks: Vec<CrossCheck>,
}

impl Answer {
    /// Whether the status is `identified` (exit code 0).
    pub fn is_identified(&self) -> bool {
        self.status == IDENTIFIED
    }

    /// The status from the runout's (or the main result's) checks: not identified when any
    /// reason was found for the value, partly when only the angle (or a secondary result) is
    /// missing.
    pub fn status_of(value_ok: bool, all_ok: bool) -> &'static str {
        if !value_ok {
            NOT_IDENTIFIED
        } else if all_ok {
            IDENTIFIED
        } else {
            PARTLY
        }
    }

    /// The first lines of a text report: the answer, its reasons, warnings and cross-checks.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let pm = |v: Option<f64>, se: Option<f64>, unit: &str, digits: usize| {
            let sep = if unit == "°" { "" } else { " " };
            match (v, se) {
                (Some(v), Some(se)) => format!("{v:.digits$} ± {se:.digits$}{sep}{unit}"),
                (Some(v), None) => format!("{v:.digits$}{sep}{unit} (no SE)"),
                _ => "not identified".to_string(),
            }
        };
        let head = match &self.runout {
            Some(r) if r.offset_um.is_some() => {
                let angle = match r.angle_deg {
                    Some(_) => format!(" at λ = {}", pm(r.angle_deg, r.angle_deg_se, "°", 1)),
                    None => format!(", angle {}", r.angle),
                };
                format!(
                    "runout ρ = {}{angle}",
                    pm(r.offset_um, r.offset_um_se, "µm", 2)
                )
            }
            Some(_) => "runout not identified".to_string(),
            None => self
                .results
                .first()
                .map(|q| {
                    format!(
                        "{} = {}",
                        q.name,
                        pm(q.value, q.value_se, &q.unit, digits(&q.unit))
                    )
                })
                .unwrap_or_else(|| "no result".into()),
        };
        s += &format!("ANSWER: {head}\n");
        s += &format!("  status: {}\n", self.status);
        s += &format!("  method: {}\n", self.method);
        let skip = usize::from(self.runout.is_none());
        for q in self.results.iter().skip(skip) {
            s += &format!(
                "  {} = {}\n",
                q.name,
                pm(q.value, q.value_se, &q.unit, digits(&q.unit))
            );
        }
        for r in &self.reasons {
            s += &format!("  reason: {r}\n");
        }
        for w in &self.warnings {
            s += &format!("  warning: {w}\n");
        }
        for c in &self.cross_checks {
            let vals: Vec<String> = c
                .values
                .iter()
                .map(|q| {
                    format!(
                        "{} {}",
                        q.name,
                        pm(q.value, q.value_se, &q.unit, digits(&q.unit))
                    )
                })
                .collect();
            s += &format!(
                "  cross-check ({}): {} — {}\n",
                c.estimate,
                vals.join(", "),
                c.why_it_may_differ
            );
        }
        s + "\n"
    }
}

fn digits(unit: &str) -> usize {
    match unit {
        "µm/mm" | "N/µm" => 4,
        "deg" | "°" => 1,
        _ => 2,
    }
}

/// Why a value ± SE is not identified: no SE, a non-finite value, or SE > 25 % of the value
/// ([`MAX_RELATIVE_SE`]); `None` when it passes.
pub fn se_test(
    name: &str,
    value: f64,
    se: Option<f64>,
    unit: &str,
    what_to_do: &str,
) -> Option<String> {
    if !value.is_finite() {
        return Some(format!("{name} is not a number: {what_to_do}"));
    }
    match se {
        None => Some(format!(
            "{name} = {value:.3} {unit} has no standard error (too few readings for the noise to be \
             estimated): {what_to_do}"
        )),
        Some(s) if !s.is_finite() || s > MAX_RELATIVE_SE * value.abs() => Some(format!(
            "{name} = {value:.3} ± {s:.3} {unit}: the standard error is more than {:.0} % of the \
             value, so the value is not one to use: {what_to_do}",
            MAX_RELATIVE_SE * 100.0
        )),
        _ => None,
    }
}

/// Something that carries an [`Answer`] (the CLI sets exit code 3 unless it is identified).
pub trait Answered {
    /// The report's answer.
    fn answer(&self) -> &Answer;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn se_test_fails_above_a_quarter_of_the_value_and_without_se() {
        assert!(se_test("ρ", 8.0, Some(1.9), "µm", "").is_none());
        assert!(se_test("ρ", 8.0, Some(2.1), "µm", "").is_some());
        assert!(se_test("ρ", 8.0, None, "µm", "").is_some());
        assert!(se_test("ρ", f64::NAN, Some(0.1), "µm", "").is_some());
    }

    #[test]
    fn text_opens_with_the_answer() {
        let a = Answer {
            status: IDENTIFIED.into(),
            method: "m".into(),
            runout: Some(RunoutAnswer {
                offset_um: Some(6.03),
                offset_um_se: Some(0.15),
                angle_deg: Some(25.4),
                angle_deg_se: Some(1.4),
                angle: IDENTIFIED.into(),
            }),
            ..Answer::default()
        };
        let t = a.text();
        assert!(
            t.starts_with(
                "ANSWER: runout ρ = 6.03 ± 0.15 µm at λ = 25.4 ± 1.4°\n  status: identified"
            ),
            "{t}"
        );
    }
}
