//! Identification of runout (and cutting coefficients) from measured forces, methods.md §4.
//!
//! All functions take in-memory data (per-tooth peak tables, mean forces, synchronously averaged
//! waveforms); reading recordings is `runout-io`'s job. Conventions: `conventions.md` (teeth in
//! cutting order, runout e = ρ(cos λ, sin λ) from tooth 0 in the rotation direction, forces on the
//! workpiece). Angles in rad, lengths in mm.
//!
//! * [`sine_fit`] — seed 003 per-tooth peak sine fit (eq. 10–12) with standard errors.
//! * [`analyse_tests`] — several tests: regressions, K_T/K_R (seed eq. 17), pooled
//!   edge-force-aware fit ([`pooled_fit`], §4.6).
//! * [`calibrate_mean_forces`] — coefficients from mean forces over ≥ 2 feeds (Altintas).
//! * [`frequency_estimate`] — spindle-harmonic runout estimate (§4.7), a fast start value.
//! * [`full_signal_fit`] — non-linear least squares of averaged waveforms (runout vector, tilt,
//!   six coefficients), several recordings jointly; works for K = 2 with a helical cutter (with
//!   straight flutes only the offset along the tooth line is observable, reported as such).
//!
//! From a recording: synchronously average whole revolutions on a uniform spindle-angle grid
//! whose θ = 0 puts tooth 0's tip at immersion 0 ([`AveragedWaveform::average`]), wrap it with
//! the cutter and cut in a [`WaveformCase`], and fit:
//!
//! ```
//! use runout_core::identify::*;
//! use runout_core::*;
//! let cutter = Cutter::flat(10.0, 4, 0.0)?;
//! let runout = Runout::new(0.008, 0.5)?;
//! let cut = Cut::new(3000.0, 0.08, 1.0)?.radial(3.0, MillingMode::Down, &cutter)?;
//! let kc = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1])?;
//! let model = ForceModel { cutter: cutter.clone(), runout, cut, coefficients: kc };
//! let s = model.simulate(&ArcChip::new(&cutter, &runout, 0.08)?, &Sampling::new(3.0, 1.0, 1)?);
//! let w = AveragedWaveform::average(0.0, 360, &[(FrameAxis::X, &s.fx), (FrameAxis::Y, &s.fy)])?;
//! let fit = full_signal_fit(&[WaveformCase { cutter, cut, waveform: w }], &FullSignalOptions::default())?;
//! assert!((fit.offset.value - 0.008).abs() < 1e-5 && (fit.angle.value - 0.5).abs() < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod alignment;
mod covariance;
mod error;
mod frequency;
mod full_signal;
mod harmonic_fit;
mod mean_force;
mod model;
mod multi_test;
mod peak_coefficients;
mod peak_test;
mod pooled;
mod sine_fit;
mod waveform;

pub use crate::fit::{fit_line, linear_lsq, r_squared, LinearFit, Regression};
pub use alignment::{harmonic_start_angle, model_forces, refine_start_angle, residual_at};
pub use error::IdentifyError;
pub use frequency::{frequency_estimate, FrequencyEstimate};
pub use full_signal::{
    full_signal_fit, FullSignalFit, FullSignalOptions, RunoutObservability, SeParts,
};
pub use harmonic_fit::{ChainFitReport, ChainModel, ChainOptions, FittedMode};
pub use mean_force::{
    calibrate_mean_forces, calibrate_mean_forces_general, immersion_integrals,
    MeanForceCalibration, MeanForceDesign, MeanForces,
};
pub use model::{
    coefficient_gradient, force_from_basis, on_pool, runout_gradient, BasisSums, RevolutionModel,
    NB, ND,
};
pub use multi_test::{analyse_tests, MultiTestResult, TestResult};
pub use peak_coefficients::{coefficients_at_peak, PeakCoefficients};
pub use peak_test::PeakTest;
pub use pooled::{pooled_fit, EdgeModel, PooledFit};
pub use sine_fit::{
    peak_immersion, radius_difference, sine_fit, ErrorSource, Estimate, PeakConditions, SineFit,
    SineHypothesis, ToothPeaks,
};
pub use waveform::{AveragedWaveform, FrameAxis, WaveformCase, WaveformComponent};
