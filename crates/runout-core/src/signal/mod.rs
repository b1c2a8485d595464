//! Signal pipeline for measured force recordings (issue 3, items 2–4): spindle angle and speed,
//! steady-cut detection, synchronous averaging per revolution and per-tooth peaks.
//!
//! Conventions (`conventions.md`, "Signals"): a recording is a set of channels at a constant
//! sample rate; forces on the workpiece in the workpiece frame (the reader applies the axis
//! mapping); spindle angle θ as in `ForceSeries::angle` (tooth 0's tip at immersion θ) when it is
//! absolute. Angles in radians, times in s, forces in N.
//!
//! # Streaming in bounded memory: three passes of accumulators
//! A recording of hours at 50 kHz is fed chunk by chunk ([`SignalChunk`]: `&[f64]` per channel), three
//! times:
//! 1. [`SpindleScan`] — Welch spectrum of F_x, F_y → coarse tooth-passing line and the consistency
//!    check against K and rpm; per-revolution envelope → steady section; pulse-channel range.
//! 2. [`PhaseTracker`] — over the section: phase of the tooth-passing harmonic per revolution
//!    regressed on time (or pulse-edge timing) → spindle speed ± standard error, and the
//!    spindle-angle wander about constant speed (≤ [`MAX_KNOTS`] knots) that pass 3 follows.
//! 3. [`SyncAverager`] — over the section: every revolution resampled on a uniform angle grid and
//!    averaged (mean, sd, se per bin), per-tooth peaks with revolution-to-revolution scatter.
//!
//! Memory per pass is independent of the recording length: pass 1 ≤ 2·L + 4·L + 2·L + 1 f64 for the
//! spectrum (frame L ≤ 2¹⁶) + 2¹⁵ envelope blocks × 7 numbers; pass 2 ≤ 4096 phase knots × 2;
//! pass 3 one revolution of samples × 3 (an encoder: its N + 1 edge times) + 4·M bin statistics
//! × 3 numbers (M bins) + K. [`analyse_replay`] runs the three passes
//! over a replayable source; [`analyse`] over samples in memory.
//!
//! ```
//! use runout_core::signal::{analyse, SignalChunk, SignalConfig};
//! // 3 teeth at 6000 rpm, 20 kHz: a pulse per tooth, one tooth 10 % stronger
//! let fs = 20_000.0;
//! let f = 6000.0 / 60.0;
//! let (mut fx, mut fy) = (vec![], vec![]);
//! for n in 0..4000 {
//!     let th = std::f64::consts::TAU * f * n as f64 / fs;
//!     let tooth = ((3.0 * th / std::f64::consts::TAU).floor() as usize) % 3;
//!     let pulse = (3.0 * th).sin().max(0.0) * if tooth == 0 { 110.0 } else { 100.0 };
//!     fx.push(pulse);
//!     fy.push(0.3 * pulse);
//! }
//! let cfg = SignalConfig::new(fs, 3, 6000.0)?;
//! let a = analyse(&cfg, SignalChunk { fx: &fx, fy: &fy, fz: None, pulse: None })?;
//! assert!((a.speed.rpm - 6000.0).abs() < 1.0);
//! let peaks: Vec<f64> = a.average.tooth_peaks.iter().map(|p| p.peak).collect();
//! let (hi, lo) = (peaks.iter().cloned().fold(0.0, f64::max), peaks.iter().cloned().fold(1e9, f64::min));
//! assert!((hi / lo - 1.1).abs() < 0.01);
//! # Ok::<(), runout_core::signal::SignalError>(())
//! ```

mod average;
mod chunk;
mod config;
mod error;
mod pulse;
mod scan;
mod spectrum;
mod stats;
mod steady;
mod tracker;

pub use average::{
    AngleReference, ComponentAverage, SyncAverage, SyncAverager, ToothPeakEstimate, ToothReference,
};
pub use chunk::SignalChunk;
pub use config::{ForceComponent, PulseConfig, SignalConfig};
pub use error::SignalError;
pub use pulse::PulseEdgeDetector;
pub use scan::{ScanResult, SpindleScan};
pub use spectrum::ToothPassingLine;
pub use stats::RunningStats;
pub use steady::{SteadySection, MAX_BLOCKS};
pub use tracker::{PhaseTracker, SpeedMethod, SpindleSpeed, MAX_KNOTS};

/// Everything the pipeline found (serialisable; angles in rad, forces in N, times in s: the CLI
/// converts angles to degrees).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SignalAnalysis {
    /// Pass 1: spectrum line, section, recording length.
    pub scan: ScanResult,
    /// Pass 2: spindle speed ± se.
    pub speed: SpindleSpeed,
    /// Pass 3: synchronous average and per-tooth peaks.
    pub average: SyncAverage,
    /// Warnings for the report (e.g. speed > 2 % from nominal); never printed by the library.
    pub warnings: Vec<String>,
}

/// A sink the replay callback feeds chunks into.
pub type ChunkSink<'s> = dyn FnMut(SignalChunk<'_>) -> Result<(), SignalError> + 's;

/// Run the three passes over a source that can be replayed: `replay(sink)` must feed the whole
/// recording, in order, chunk by chunk, into `sink` (e.g. by re-reading a file). It is called
/// three times, and must deliver the same samples each time: pass 1 checks every value finite,
/// passes 2 and 3 check each chunk's lengths and channel set, their number of samples and that
/// their results are finite (a replay that breaks this is an error, never a silently wrong
/// average). Errors of the source (type `E`) pass through.
pub fn analyse_replay<E, R>(cfg: &SignalConfig, mut replay: R) -> Result<SignalAnalysis, E>
where
    E: From<SignalError>,
    R: FnMut(&mut ChunkSink<'_>) -> Result<(), E>,
{
    let mut scan = SpindleScan::new(cfg)?;
    replay(&mut |c| scan.push(c))?;
    let scan = scan.finish()?;
    // passes 2 and 3 see the values pass 1 checked finite: they check lengths and the channel
    // set of each chunk, the number of samples at the end, and that their results are finite
    let mut tracker = PhaseTracker::new(cfg, &scan)?.replaying();
    replay(&mut |c| tracker.push(c))?;
    same_recording(2, tracker.samples(), scan.samples)?;
    let speed = tracker.finish()?;
    let mut avg = SyncAverager::new(cfg, &scan, &speed)?.replaying();
    replay(&mut |c| avg.push(c))?;
    same_recording(3, avg.samples(), scan.samples)?;
    let average = avg.finish()?;
    let finite = speed.rpm.is_finite()
        && speed
            .angle_wander
            .iter()
            .all(|(t, w)| t.is_finite() && w.is_finite())
        && average
            .components
            .iter()
            .all(|c| c.mean.iter().all(|m| m.is_finite()));
    if !finite {
        return Err(SignalError::Channels {
            sample: 0,
            what: "a replay delivered values that are not finite where pass 1 saw none: the replay must \
                   deliver the recording of pass 1"
                .into(),
        }
        .into());
    }
    let mut warnings: Vec<String> = speed.warning().into_iter().collect();
    if speed.method == SpeedMethod::Spectrum {
        warnings.push(format!(
            "fewer than 3 revolutions in the section: the speed is the spectral estimate only (resolution {:.2} Hz on the tooth-passing line)",
            scan.tooth_passing.resolution_hz
        ));
    }
    if speed.method == SpeedMethod::Pulse && (speed.rpm / speed.coarse_rpm - 1.0).abs() > 0.01 {
        warnings.push(format!(
            "the pulse channel gives {:.1} rpm but the tooth-passing line {:.1} rpm: check pulses_per_rev ({}) and teeth ({})",
            speed.rpm,
            speed.coarse_rpm,
            cfg.pulse.map_or(0, |p| p.pulses_per_rev),
            cfg.teeth
        ));
    }
    let (below_hz, below_rel) = scan.tooth_passing.strongest_below;
    if below_rel > 0.1 {
        warnings.push(format!(
            "a line at {below_hz:.1} Hz, below the tooth-passing line at {:.1} Hz, is only {:.1} dB weaker (runout side-bands \
             are typically ≥ 15 dB weaker): the stated {} teeth may be too many, or the runout is large",
            scan.tooth_passing.hz,
            -10.0 * below_rel.log10(),
            cfg.teeth
        ));
    }
    if average.tooth_reference == ToothReference::Arbitrary {
        warnings.push(
            "no absolute spindle angle (pulse with tooth-0 angle and entry angle): tooth 0 is an arbitrary reference tooth".into(),
        );
    }
    Ok(SignalAnalysis {
        scan,
        speed,
        average,
        warnings,
    })
}

/// The error for a replay (pass `pass`) that delivered `got` samples where pass 1 saw `want`.
fn same_recording(pass: u8, got: u64, want: u64) -> Result<(), SignalError> {
    if got == want {
        return Ok(());
    }
    Err(SignalError::Channels {
        sample: got.min(want),
        what: format!(
            "the replay of pass {pass} delivered {got} samples where pass 1 saw {want}: the replay \
             must deliver the recording of pass 1"
        ),
    })
}

/// Run the pipeline over a recording held in memory (one chunk of all samples).
pub fn analyse(cfg: &SignalConfig, rec: SignalChunk<'_>) -> Result<SignalAnalysis, SignalError> {
    analyse_replay(cfg, |sink: &mut ChunkSink<'_>| sink(rec))
}

/// Run the pipeline over a recording in memory, fed in chunks of `chunk` samples (for tests of
/// the streaming path and for benchmarks).
pub fn analyse_chunked(
    cfg: &SignalConfig,
    rec: SignalChunk<'_>,
    chunk: usize,
) -> Result<SignalAnalysis, SignalError> {
    let step = chunk.max(1);
    analyse_replay(cfg, |sink: &mut ChunkSink<'_>| {
        (0..rec.len())
            .step_by(step)
            .try_for_each(|a| sink(rec.slice(a, (a + step).min(rec.len()))))
    })
}
