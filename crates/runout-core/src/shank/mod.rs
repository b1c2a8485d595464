//! Cutting force from two-point shank deflection (seed 002, methods.md §3): the shank stiffness
//! K_δ from beam theory or a static calibration, the air-cut template subtraction pipeline that
//! turns two displacement sensors per direction into δ_I, δ_II, Δ = δ_II − δ_I and
//! F = K_δ·Δ, the runout offset and tilt from the same air-cut templates (§3.2 end, §1.6), and
//! validation metrics against a reference dynamometer.
//!
//! ```
//! use runout_core::shank::ShankBeam;
//! // patent example 1 (methods.md §7): 1.948754 N/µm
//! let k = ShankBeam::new(210.0, 8.0, 65.0, 10.0, 30.0)?.stiffness_n_per_um();
//! assert!((k - 1.948754).abs() < 1e-6);
//! # Ok::<(), runout_core::ParamError>(())
//! ```

mod calibration;
mod deconvolve;
mod dynamics;
mod filter;
mod process;
mod resonance;
mod spindle;
mod stiffness;
mod synthetic;
mod template;

pub use calibration::{calibrate, LoadStep, StaticCalibration};
pub use deconvolve::Deconvolver;
pub use dynamics::{
    bandwidth, chain_peak_hz, correction_gain, default_density_kg_per_m3, regularised_inverse,
    spectral_check, usable_bandwidth_hz, Correction, ShankBandwidth, ShankDynamics,
    BANDWIDTH_TOLERANCE, CARBIDE_DENSITY_KG_PER_M3, CHECKED_TOOTH_HARMONICS,
    STEEL_DENSITY_KG_PER_M3,
};
pub use filter::{Biquad, Butterworth, ZeroPhaseStream};
pub use process::{
    analyse, append, process_in_memory, ComparisonMetrics, DcLevel, ForceComparison, OutputBlock,
    PairAxis, Reconstructor, SampleRange, SensorPair, ShankAnalysis, ShankRunout, ShankSetup,
    Survey, SurveyResult,
};
pub use resonance::{ResonanceSpectrum, SpectralResonance};
pub use spindle::{frequency_from_air, peak_frequency, phasor, PhaseSegment, SpindlePhase};
pub use stiffness::{LoadPoint, ShankBeam};
pub use synthetic::{SyntheticRecording, SyntheticShank};
pub use template::{AngleTemplate, TemplateBuilder};

/// Errors of the shank method.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShankError {
    /// A parameter out of range (names it).
    #[error(transparent)]
    Param(#[from] crate::ParamError),
    /// No usable air-cut segment (says what was found and what is needed).
    #[error("no air-cut segment found: {0}")]
    NoAirCut(String),
    /// Input data inconsistent with the setup.
    #[error("input: {0}")]
    Input(String),
    /// Static calibration impossible or ill-conditioned.
    #[error("static calibration: {0}")]
    Calibration(String),
}

impl ShankSetup {
    /// A setup with defaults: drift correction on, no low-pass, ≥ 5 and ≤ 50 template
    /// revolutions, no sensor range, runout at the tool tip, automatic bins; dynamics: steel or
    /// carbide density by modulus, ζ = 0.03, teeth unknown, no correction.
    pub fn new(
        beam: ShankBeam,
        pairs: Vec<SensorPair>,
        sample_rate_hz: f64,
        nominal_rpm: f64,
    ) -> Self {
        Self {
            dynamics: ShankDynamics::for_beam(&beam),
            stiffness_n_per_mm: beam.stiffness_n_per_mm(),
            beam,
            pairs,
            sample_rate_hz,
            start_time_s: 0.0,
            nominal_rpm,
            has_pulse: false,
            has_reference: false,
            air_cut_s: Vec::new(),
            drift_correction: true,
            lowpass: None,
            min_air_revolutions: 5,
            max_template_revolutions: 50,
            sensor_range_mm: None,
            cutting_height_mm: 0.0,
            template_bins: 0,
        }
    }
}
