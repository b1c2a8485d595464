//! Errors of the signal pipeline: each names the channel, sample, parameter or finding at fault.

use crate::error::ParamError;
use thiserror::Error;

/// Why a recording could not be turned into a spindle angle, a steady section or an average.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SignalError {
    /// A configuration value is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A sample is NaN or infinite.
    #[error("channel `{channel}`, sample {sample} (t = {time_s:.6} s): expected a finite number, got {value}")]
    NonFinite {
        /// Channel name (`fx`, `fy`, `fz`, `pulse`).
        channel: &'static str,
        /// Sample index from the start of the recording (0-based).
        sample: u64,
        /// Time of that sample (s).
        time_s: f64,
        /// The offending value.
        value: f64,
    },
    /// The channels of a chunk differ in length, or a channel appears/disappears between chunks.
    #[error("chunk starting at sample {sample}: {what}")]
    Channels {
        /// First sample index of the chunk.
        sample: u64,
        /// What is inconsistent.
        what: String,
    },
    /// The recording (or the chosen section) covers fewer than two spindle revolutions.
    #[error("{what} is {seconds:.6} s = {revolutions:.2} revolutions at {rpm} rpm: at least 2 revolutions are needed")]
    TooShort {
        /// "recording" or "section".
        what: &'static str,
        /// Its duration (s).
        seconds: f64,
        /// Its length in revolutions at `rpm`.
        revolutions: f64,
        /// Spindle speed used (rpm).
        rpm: f64,
    },
    /// No tooth-passing line where the stated teeth and rpm put it.
    #[error(
        "spectrum inconsistent with {teeth} teeth at {rpm} rpm: expected a tooth-passing line at {expected_hz:.2} Hz \
         (search band {band_lo_hz:.2}–{band_hi_hz:.2} Hz), {finding}; the strongest line is at {strongest_hz:.2} Hz \
         (= {strongest_as_rpm:.0} rpm if it were the tooth-passing frequency of {teeth} teeth, \
         half that if it were its second harmonic). \
         Check `teeth` and `rpm`."
    )]
    SpectrumInconsistent {
        /// Stated number of teeth K.
        teeth: usize,
        /// Stated spindle speed (rpm).
        rpm: f64,
        /// K·n/60 (Hz).
        expected_hz: f64,
        /// Lower end of the search band (Hz).
        band_lo_hz: f64,
        /// Upper end of the search band (Hz).
        band_hi_hz: f64,
        /// What failed.
        finding: String,
        /// Frequency of the strongest spectral line above half the spindle frequency (Hz).
        strongest_hz: f64,
        /// 60·strongest/K.
        strongest_as_rpm: f64,
    },
    /// No steady cutting section of at least two revolutions.
    #[error("no steady cut found: {reason}")]
    NoCut {
        /// What the detector saw.
        reason: String,
    },
    /// The once-per-revolution (or encoder) channel does not give usable edges.
    #[error("pulse channel: {reason}")]
    Pulse {
        /// What is wrong.
        reason: String,
    },
}
