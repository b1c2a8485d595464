//! Errors of the displacement methods: each names what was wrong and what was expected.

use crate::error::ParamError;
use thiserror::Error;

/// Why a displacement identification could not be done.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DisplacementError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// Some teeth have no reading (methods.md §1.2 needs one P_i per tooth).
    #[error("no reading for tooth {missing:?} of {teeth}: every tooth 0..{teeth} needs at least one reading")]
    MissingTooth {
        /// Number of teeth K.
        teeth: usize,
        /// Teeth (0-based, cutting order) without a reading.
        missing: Vec<usize>,
    },
    /// A reading refers to a tooth that does not exist.
    #[error(
        "reading {index} refers to tooth {tooth}, but the cutter has {teeth} teeth (0..{teeth})"
    )]
    ToothOutOfRange {
        /// Index of the reading.
        index: usize,
        /// The tooth it names.
        tooth: usize,
        /// Number of teeth K.
        teeth: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what} {index} is not a finite number ({value})")]
    NotFinite {
        /// What the value is (`reading`, `height`, `sample of channel a`…).
        what: String,
        /// Its index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// K = 2: |ΔR₁| exceeds 2ρ (no real θ, methods.md §1.5) by more than the noise allows.
    #[error("inconsistent readings: |ΔR| = {delta_um:.4} µm exceeds 2·offset = {max_um:.4} µm (tolerance {tolerance_um:.4} µm); the offset from the height regression is too small, or the readings contain tool form errors")]
    InconsistentDifference {
        /// |ΔR₁| (µm).
        delta_um: f64,
        /// The largest possible |ΔR₁| for the given offset (µm).
        max_um: f64,
        /// Noise tolerance used (µm).
        tolerance_um: f64,
    },
    /// The method needs the runout length ρ from elsewhere (height regression).
    #[error("{reason}: give the runout length (offset) at the cutting height, e.g. from the height regression")]
    NeedsOffset {
        /// Why.
        reason: String,
    },
    /// Too few data points for the fit.
    #[error("{what}: got {got}, need at least {need}")]
    TooFew {
        /// What is counted.
        what: String,
        /// How many there are.
        got: usize,
        /// How many are needed.
        need: usize,
    },
    /// All heights are equal, so no line through r(z) exists.
    #[error("all heights are equal (z = {z_mm} mm): the regression over height needs at least two different heights")]
    HeightsEqual {
        /// The common height (mm).
        z_mm: f64,
    },
    /// A problem with a raw signal (missing or short channel, no reference marks…).
    #[error("signal: {0}")]
    Signal(String),
    /// The numerical fit failed.
    #[error("fit failed: {0}")]
    Fit(String),
}

/// Check that every value is finite; `what` names the kind of value in the error.
pub(crate) fn check_finite(what: &str, values: &[f64]) -> Result<(), DisplacementError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(DisplacementError::NotFinite {
            what: what.to_string(),
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}
