//! The JSON schemas of the reports (generated with `schemars`, published under `docs/schema/`).

use crate::job::Report;

/// A report's schema as pretty JSON with a final newline.
pub fn schema_json<R: Report>() -> String {
    let schema = schemars::schema_for!(R);
    serde_json::to_string_pretty(&schema).unwrap_or_default() + "\n"
}

/// Every report of the library: (`schema` id, file name under `docs/schema/`, schema JSON).
pub fn all() -> Vec<(&'static str, String, String)> {
    fn one<R: Report>() -> (&'static str, String, String) {
        let id = R::SCHEMA;
        let name = id
            .trim_start_matches("runout.")
            .split('/')
            .next()
            .unwrap_or(id)
            .to_string();
        (id, format!("{name}.json"), schema_json::<R>())
    }
    vec![
        one::<crate::shank::StiffnessReport>(),
        one::<crate::shank::ForceReport>(),
        one::<crate::shank::CalibrationReport>(),
        one::<crate::displacement::TeethReport>(),
        one::<crate::displacement::HeightsReport>(),
        one::<crate::displacement::SignalReport>(),
        one::<crate::chip::CompareReport>(),
        one::<crate::chip::EvalReport>(),
        one::<crate::grind::CompensateReport>(),
        one::<crate::grind::CheckReport>(),
        one::<crate::identify::PeaksReport>(),
        one::<crate::identify::TestsReport>(),
        one::<crate::identify::RecordingsReport>(),
        one::<crate::simulate::SimulateReport>(),
        one::<crate::inspect::InspectReport>(),
        one::<crate::batch::BatchReport>(),
    ]
}
