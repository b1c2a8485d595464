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
//!   six coefficients), several recordings jointly; works for K = 2.

mod error;
mod frequency;
mod full_signal;
mod lsq;
mod mean_force;
mod model;
mod multi_test;
mod peak_coefficients;
mod pooled;
mod sine_fit;
mod waveform;

pub use error::IdentifyError;
pub use frequency::{frequency_estimate, FrequencyEstimate};
pub use full_signal::{full_signal_fit, FullSignalFit, FullSignalOptions, RunoutObservability};
pub use lsq::{fit_line, linear_lsq, r_squared, LinearFit, Regression};
pub use mean_force::{
    calibrate_mean_forces, immersion_integrals, MeanForceCalibration, MeanForces,
};
pub use model::{
    coefficient_gradient, force_from_basis, runout_gradient, BasisSums, RevolutionModel,
};
pub use multi_test::{analyse_tests, MultiTestResult, PeakTest, TestResult};
pub use peak_coefficients::{coefficients_at_peak, PeakCoefficients};
pub use pooled::{pooled_fit, EdgeModel, PooledFit};
pub use sine_fit::{
    peak_immersion, sine_fit, ErrorSource, Estimate, PeakConditions, SineFit, SineHypothesis,
    ToothPeaks,
};
pub use waveform::{AveragedWaveform, Axis, Component, WaveformCase};
