//! `identify RECORDING…`: runout and cutting coefficients from measured force recordings — the
//! product's main job (methods.md §4).
//!
//! Per recording: stream the file once, mapping instrument channels to the workpiece frame and
//! spilling the forces to a temporary file ([`crate::spill::Spill`]); the signal pipeline
//! (`runout_core::signal`) runs its three passes (spectrum + steady-cut detection, spindle-speed
//! tracking, synchronous average + per-tooth peaks) over the text once and the spill twice. Then:
//! the seed-003 sine fit of the per-tooth peaks, the mean-force calibration (≥ 2 feeds), and the
//! full-signal fit of all recordings jointly through the measuring chain (§4.5, §4.7).

mod answer;
mod chain;
mod fit;
mod read;
mod report;
mod request;

pub use answer::{Answer, CoefficientAnswer, CrossCheck, RunoutAnswer};
pub use chain::{ChainDecision, Consistency, RecordingRunout, Status, Verdicts};
pub use report::{
    Calibration, Coefficients, Fitted, FullSignal, FullSignalReport, MeanForceN,
    MeasuringChainReport, Peak, RecordingReport, RecordingsInputs, RecordingsReport, Renumbered,
    SectionReport, SineFitReport, SpindleReport, WaveformPlot,
};
pub use request::{resolve, ChainChoice, RecordingsRequest};

use crate::job::Progress;
use anyhow::{Context, Result};
use runout_core::chain::MeasuringChain;
use runout_core::identify::SineFit;
use runout_core::signal::SignalAnalysis;
use runout_core::Cut;
use runout_io::recording::RecordingInfo;

/// What the chain selection, tooth numbering, consistency and verdicts gave.
struct Extra {
    decision: ChainDecision,
    given: Option<MeasuringChain>,
    renumbered: Vec<(usize, usize)>,
    consistency: Option<Consistency>,
    verdicts: Verdicts,
}

/// What one recording gave.
struct FileResult {
    name: String,
    info: RecordingInfo,
    axes: String,
    cut: Cut,
    analysis: SignalAnalysis,
    mean_force: [f64; 3],
    start_angle: f64,
    sine: Result<SineFit, String>,
    reader_warnings: Vec<String>,
    /// Channels with flat tops at their range limit (pass 1).
    clipped: Vec<runout_core::plausibility::Finding>,
    /// Hash of the mapped force samples (the same data passed twice).
    content_hash: u64,
}

/// Runs the job: every recording through the signal pipeline (progress: one stage per
/// recording), then the sine fits, the mean-force calibration and the joint full-signal fit.
pub fn recordings(
    req: &RecordingsRequest,
    progress: &mut dyn Progress,
) -> Result<RecordingsReport> {
    req.validate()?;
    let mut files = Vec::with_capacity(req.recordings.len());
    for (src, cut) in req.recordings.iter().zip(&req.cuts) {
        let r = read::analyse(src, req, cut, progress)
            .with_context(|| format!("analysing {}", src.name()))?;
        files.push(r);
    }
    // the fits on the thread pool as one task: their parallel sections are nested there
    // rather than each handed over from this thread (same results bit for bit)
    runout_core::identify::on_pool(|| fit_and_report(req, files))
}

/// The fits after the reading: the mean-force calibration, the full-signal fit of all
/// recordings, the chain check, the consistency and the verdicts, into the report.
fn fit_and_report(req: &RecordingsRequest, mut files: Vec<FileResult>) -> Result<RecordingsReport> {
    let calibration = fit::mean_force_calibration(req, &files);
    let guess = calibration
        .as_ref()
        .ok()
        .map(fit::coefficients_of)
        .unwrap_or_else(fit::default_coefficients);
    for f in files.iter_mut() {
        f.start_angle = fit::initial_start_angle(&req.cutter, f, &guess);
    }
    let rigid = fit::fit_all(req, &mut files);
    // tooth numbering consistent across the recordings of the joint fit, then the chain
    let mut renumbered = Vec::new();
    if let (Ok(f), true) = (&rigid, files.len() > 1) {
        renumbered = chain::align_tooth_numbering(req, &mut files, f);
    }
    let rigid = if renumbered.is_empty() {
        rigid
    } else {
        fit::fit_all(req, &mut files)
    };
    let (fit, decision, given) = chain::select_chain(req, &mut files, rigid)?;
    let consistency = fit
        .as_ref()
        .ok()
        .and_then(|f| chain::consistency(req, &files, f, given.as_ref()));
    let verdicts = fit
        .as_ref()
        .map(|f| chain::verdicts(f, &decision, &files))
        .unwrap_or_default();
    let extra = Extra {
        decision,
        given,
        renumbered,
        consistency,
        verdicts,
    };
    Ok(report::build(req, &files, &calibration, &fit, &extra))
}
