//! Values with optional unit suffixes (`8mm`, `12um`, `210GPa`, `3240rpm`, `30deg`).
//!
//! `conventions.md`, "Units": a suffix that does not match the quantity is an error, never
//! silently converted; a suffix of the right quantity is converted to the unit the key names.

use std::fmt;

/// The physical quantity a key or flag holds; each has a canonical unit (the one in its name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Length, canonical mm.
    LengthMm,
    /// Length, canonical µm.
    LengthUm,
    /// Angle, canonical degrees.
    AngleDeg,
    /// Spindle speed, canonical rpm.
    SpeedRpm,
    /// Specific cutting force, canonical N/mm² (= MPa).
    ForcePerArea,
    /// Edge force per unit length, canonical N/mm.
    ForcePerLength,
    /// Young's modulus, canonical GPa.
    ModulusGpa,
    /// Force, canonical N.
    ForceN,
    /// Time, canonical s.
    TimeS,
    /// Frequency, canonical Hz.
    FrequencyHz,
    /// Tilt, canonical µm/mm.
    TiltUmPerMm,
    /// Plain number without unit (counts, ratios).
    Dimensionless,
}

impl Quantity {
    /// Canonical unit, as written in help texts.
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::LengthMm => "mm",
            Quantity::LengthUm => "µm",
            Quantity::AngleDeg => "deg",
            Quantity::SpeedRpm => "rpm",
            Quantity::ForcePerArea => "N/mm²",
            Quantity::ForcePerLength => "N/mm",
            Quantity::ModulusGpa => "GPa",
            Quantity::ForceN => "N",
            Quantity::TimeS => "s",
            Quantity::FrequencyHz => "Hz",
            Quantity::TiltUmPerMm => "µm/mm",
            Quantity::Dimensionless => "",
        }
    }

    /// Factor from a unit `suffix` (as in a column header: `N`, `kN`, `um`) to the canonical unit;
    /// an empty suffix means the canonical unit (as in [`parse_quantity`]); `None` when the suffix
    /// is not a unit of this quantity.
    ///
    /// ```
    /// use runout_io::units::Quantity;
    /// assert_eq!(Quantity::ForceN.unit_factor("kN"), Some(1e3));
    /// assert_eq!(Quantity::LengthMm.unit_factor(""), Some(1.0));
    /// assert_eq!(Quantity::ForceN.unit_factor("V"), None);
    /// ```
    pub fn unit_factor(self, suffix: &str) -> Option<f64> {
        if suffix.trim().is_empty() {
            Some(1.0)
        } else {
            self.factor(suffix)
        }
    }

    fn factor(self, suffix: &str) -> Option<f64> {
        let s = suffix.trim();
        let s = s.replace('²', "2").replace(['µ', 'μ'], "u");
        let s = s.as_str();
        let length_mm = match s {
            "mm" => Some(1.0),
            "um" | "micron" | "microns" => Some(1e-3),
            "m" => Some(1e3),
            "cm" => Some(10.0),
            "nm" => Some(1e-6),
            _ => None,
        };
        match self {
            Quantity::LengthMm => length_mm,
            Quantity::LengthUm => length_mm.map(|f| f * 1e3),
            Quantity::AngleDeg => match s {
                "deg" | "°" | "degree" | "degrees" => Some(1.0),
                "rad" => Some(180.0 / std::f64::consts::PI),
                _ => None,
            },
            Quantity::SpeedRpm => match s {
                "rpm" | "1/min" | "min-1" => Some(1.0),
                "rps" | "Hz" | "hz" => Some(60.0),
                _ => None,
            },
            Quantity::ForcePerArea => match s {
                "N/mm2" | "MPa" | "N/mm^2" => Some(1.0),
                "GPa" => Some(1e3),
                _ => None,
            },
            Quantity::ForcePerLength => match s {
                "N/mm" => Some(1.0),
                "N/m" => Some(1e-3),
                _ => None,
            },
            Quantity::ModulusGpa => match s {
                "GPa" => Some(1.0),
                "MPa" | "N/mm2" => Some(1e-3),
                _ => None,
            },
            Quantity::ForceN => match s {
                "N" => Some(1.0),
                "kN" => Some(1e3),
                _ => None,
            },
            Quantity::TimeS => match s {
                "s" => Some(1.0),
                "ms" => Some(1e-3),
                "min" => Some(60.0),
                _ => None,
            },
            Quantity::FrequencyHz => match s {
                "Hz" | "hz" => Some(1.0),
                "kHz" | "khz" => Some(1e3),
                _ => None,
            },
            Quantity::TiltUmPerMm => match s {
                "um/mm" => Some(1.0),
                "mm/mm" | "rad" => Some(1e3),
                _ => None,
            },
            Quantity::Dimensionless => None,
        }
    }
}

/// A value that could not be read as the expected quantity.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UnitError {
    /// Not a number at all.
    #[error("`{text}` is not a number (expected {expected})")]
    NotANumber {
        /// Input text.
        text: String,
        /// Description of what was expected.
        expected: String,
    },
    /// A unit suffix of another quantity, or an unknown one.
    #[error("`{text}` has unit `{suffix}`, which is not a recognised unit for {expected}")]
    WrongUnit {
        /// Input text.
        text: String,
        /// The suffix found.
        suffix: String,
        /// Description of what was expected.
        expected: String,
    },
    /// Beyond the largest magnitude accepted for the quantity
    /// ([`runout_core::limits::MAX_ABS_QUANTITY`]).
    #[error("`{text}` is out of range: expected |value| <= {max:e} {unit}")]
    OutOfRange {
        /// Input text.
        text: String,
        /// The largest magnitude.
        max: f64,
        /// The canonical unit.
        unit: &'static str,
    },
    /// NaN or infinite.
    #[error("`{text}` is not finite (expected {expected})")]
    NotFinite {
        /// Input text.
        text: String,
        /// Description of what was expected.
        expected: String,
    },
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Quantity::Dimensionless => write!(f, "a plain number"),
            q => write!(f, "a value in {}", q.unit()),
        }
    }
}

/// Parse `text` as quantity `q`, converting a matching unit suffix to the canonical unit.
///
/// ```
/// use runout_io::units::{parse_quantity, Quantity};
/// assert_eq!(parse_quantity("10", Quantity::LengthMm).unwrap(), 10.0);
/// assert!((parse_quantity("12um", Quantity::LengthMm).unwrap() - 0.012).abs() < 1e-15);
/// assert!((parse_quantity("0.008 mm", Quantity::LengthUm).unwrap() - 8.0).abs() < 1e-12);
/// assert!(parse_quantity("10rpm", Quantity::LengthMm).is_err());
/// assert!(parse_quantity("nan", Quantity::LengthMm).is_err());
/// ```
pub fn parse_quantity(text: &str, q: Quantity) -> Result<f64, UnitError> {
    let v = parse_unbounded(text, q).map_err(|e| match e {
        UnitError::NotANumber { text, expected } => UnitError::NotANumber {
            text: crate::textfile::quote(&text),
            expected,
        },
        UnitError::WrongUnit {
            text,
            suffix,
            expected,
        } => UnitError::WrongUnit {
            text: crate::textfile::quote(&text),
            suffix: crate::textfile::quote(&suffix),
            expected,
        },
        UnitError::NotFinite { text, expected } => UnitError::NotFinite {
            text: crate::textfile::quote(&text),
            expected,
        },
        other => other,
    })?;
    let max = runout_core::limits::max_abs_quantity(q.unit());
    if v.abs() > max {
        return Err(UnitError::OutOfRange {
            text: crate::textfile::quote(text.trim()),
            max,
            unit: q.unit(),
        });
    }
    Ok(v)
}

fn parse_unbounded(text: &str, q: Quantity) -> Result<f64, UnitError> {
    let t = text.trim();
    let expected = q.to_string();
    // split the numeric prefix from the suffix
    let split = t
        .char_indices()
        .find(|&(i, c)| {
            !(c.is_ascii_digit()
                || c == '.'
                || c == '+'
                || c == '-'
                || ((c == 'e' || c == 'E')
                    && i > 0
                    && t[i + 1..]
                        .starts_with(|d: char| d.is_ascii_digit() || d == '-' || d == '+')))
        })
        .map(|(i, _)| i)
        .unwrap_or(t.len());
    let (num, suffix) = t.split_at(split);
    let lower = t.to_ascii_lowercase();
    if matches!(
        lower.as_str(),
        "nan" | "inf" | "-inf" | "+inf" | "infinity" | "-infinity"
    ) {
        return Err(UnitError::NotFinite {
            text: t.into(),
            expected,
        });
    }
    let v: f64 = num.trim().parse().map_err(|_| UnitError::NotANumber {
        text: t.into(),
        expected: expected.clone(),
    })?;
    if !v.is_finite() {
        return Err(UnitError::NotFinite {
            text: t.into(),
            expected,
        });
    }
    let suffix = suffix.trim();
    if suffix.is_empty() {
        return Ok(v);
    }
    match q.factor(suffix) {
        Some(f) => Ok(v * f),
        None => Err(UnitError::WrongUnit {
            text: t.into(),
            suffix: suffix.into(),
            expected,
        }),
    }
}
