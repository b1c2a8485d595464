//! Errors of the pure library: every one names the parameter and what was expected.

use thiserror::Error;

/// A model or method parameter that is out of its valid range.
///
/// ```
/// use runout_core::Cutter;
/// let err = Cutter::flat(-1.0, 4, 30.0f64.to_radians()).unwrap_err();
/// assert!(err.to_string().contains("diameter_mm"));
/// ```
#[derive(Debug, Clone, PartialEq, Error)]
#[error("invalid parameter `{param}`: expected {expected}, got {got}")]
pub struct ParamError {
    /// Name of the parameter, as used in configs and flags (with its unit suffix).
    pub param: String,
    /// What a valid value looks like.
    pub expected: String,
    /// The offending value, rendered.
    pub got: String,
}

impl ParamError {
    /// Build an error for parameter `param`. A number rendered longer than 16 characters (an
    /// `f64`'s `Display` writes 1e-255 with 255 zeros) is given in scientific notation instead
    /// ([`crate::limits::show`]), so that every message stays short.
    pub fn new(param: impl Into<String>, expected: impl Into<String>, got: impl ToString) -> Self {
        let got = got.to_string();
        let got = match got.parse::<f64>() {
            Ok(v) if got.len() > 16 => crate::limits::show(v),
            _ => got,
        };
        ParamError {
            param: param.into(),
            expected: expected.into(),
            got,
        }
    }
}

/// Check that `value` is finite and strictly positive.
pub(crate) fn positive(param: &str, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ParamError::new(
            param,
            "a finite number > 0",
            crate::limits::show(value),
        ))
    }
}

/// Check that `value` is finite and non-negative.
pub(crate) fn non_negative(param: &str, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ParamError::new(
            param,
            "a finite number >= 0",
            crate::limits::show(value),
        ))
    }
}

/// Check that `value` is finite.
pub(crate) fn finite(param: &str, value: f64) -> Result<f64, ParamError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ParamError::new(
            param,
            "a finite number",
            crate::limits::show(value),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::ParamError;

    /// Extreme numbers are rendered short (scientific), other values as given.
    #[test]
    fn extreme_numbers_are_shown_short() {
        let e = ParamError::new("step_deg", "an angular step in (0, 90] degrees", 4.9e255);
        assert_eq!(e.got, "4.9e255");
        assert!(e.to_string().len() < 100, "{e}");
        assert_eq!(ParamError::new("x", "y", 3.9e-255).got, "3.9e-255");
        assert_eq!(ParamError::new("x", "y", 12.5).got, "12.5");
        assert_eq!(ParamError::new("x", "y", "a name").got, "a name");
    }
}
