//! Errors of the identification methods: each names what is missing or degenerate and what to do.

use crate::error::ParamError;
use thiserror::Error;

/// Why an identification could not produce a result.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum IdentifyError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// K = 2 in the per-tooth sine fit (methods.md §4.2): sin(πi) = 0, so only A·sin φ is
    /// observable; offset and angle cannot both be found from two peaks.
    #[error(
        "the per-tooth sine fit is degenerate for K = 2: only the mean C = {mean_n:.3} N and \
         A·sin(φ) = {a_sin_phi_n:.3} N are observable (offset and angle cannot be separated; \
         docs/methods.md §4.2). Use the full-signal identification (`runout identify RECORDING…`), which \
         works for K = 2"
    )]
    DegenerateTwoTeeth {
        /// Mean of the two peaks C (N).
        mean_n: f64,
        /// The only observable runout term A·sin φ = (F₀ − F₁)/2 (N).
        a_sin_phi_n: f64,
    },
    /// Not enough data for the requested fit.
    #[error("not enough data for {what}: need {needed}, got {got}")]
    TooFewData {
        /// Which fit.
        what: String,
        /// What is needed.
        needed: String,
        /// What was given.
        got: String,
    },
    /// The least-squares problem is singular (rank deficient).
    #[error("{what} is singular: {reason}")]
    Singular {
        /// Which fit.
        what: String,
        /// Why (e.g. all feeds equal).
        reason: String,
    },
}

impl From<crate::fit::FitError> for IdentifyError {
    fn from(e: crate::fit::FitError) -> Self {
        match e {
            crate::fit::FitError::TooFewData { what, needed, got } => {
                IdentifyError::TooFewData { what, needed, got }
            }
            crate::fit::FitError::Singular { what, reason } => {
                IdentifyError::Singular { what, reason }
            }
        }
    }
}

impl IdentifyError {
    /// Shorthand for [`IdentifyError::TooFewData`].
    pub(crate) fn too_few(what: &str, needed: impl ToString, got: impl ToString) -> Self {
        IdentifyError::TooFewData {
            what: what.into(),
            needed: needed.to_string(),
            got: got.to_string(),
        }
    }
    /// Shorthand for [`IdentifyError::Singular`].
    pub(crate) fn singular(what: &str, reason: impl ToString) -> Self {
        IdentifyError::Singular {
            what: what.into(),
            reason: reason.to_string(),
        }
    }
}
