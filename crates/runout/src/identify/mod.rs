//! Identify jobs (methods.md §4, seed 003): runout and cutting coefficients from force
//! recordings ([`recordings`], the main job), from one per-tooth peak table ([`peaks`]), or
//! from several peak tests ([`tests`]).

#![allow(non_snake_case)] // field names carry their units as the JSON does (`mean_N`)

mod peaks;
mod recordings;
pub mod render;
mod render_recordings;
mod tests;

pub use peaks::{peak_angle, peaks, PeakFitReport, PeaksInputs, PeaksReport, PeaksRequest};
pub use recordings::{
    recordings, resolve, Answer, Calibration, ChainChoice, ChainDecision, CoefficientAnswer,
    Coefficients, Consistency, CrossCheck, Fitted, FullSignal, FullSignalReport, MeanForceN,
    MeasuringChainReport, Peak, RecordingReport, RecordingRunout, RecordingsInputs,
    RecordingsReport, RecordingsRequest, Renumbered, RunoutAnswer, SectionReport, SineFitReport,
    SpindleReport, Status, Verdicts, WaveformPlot,
};
pub use render_recordings::recordings_text;
pub use tests::{
    tests, PolarMean, PooledReport, RegressionPerMm, RegressionPerMm2, TestInputs, TestReport,
    TestsDefaults, TestsReport, TestsRequest,
};

/// `Some(x)` when x is finite (a standard error that could be computed).
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}
