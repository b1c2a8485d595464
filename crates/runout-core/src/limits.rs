//! Limits as policy: the range every numeric input accepts and the largest work a command will
//! start. Every reader and constructor checks against these constants **before allocating**, and
//! the error names the limit, the value and the key or flag (as a [`ParamError`]).
//!
//! Units as in `conventions.md`: lengths in mm, feeds in mm/min or mm/tooth, time in s.
//!
//! | what | accepted | constant |
//! |---|---|---|
//! | teeth K | 1 ..= 360 | [`MAX_TEETH`] |
//! | axial disks | 1 ..= 10 000 | [`MAX_DISKS`] |
//! | samples per revolution | 1 ..= 100 000 | [`MAX_SAMPLES_PER_REV`] |
//! | points per flute (grind) | ..= 1 000 000 | [`MAX_POINTS_PER_FLUTE`] |
//! | revolutions | ..= 100 000 | [`MAX_REVOLUTIONS`] |
//! | probe grid points (layers × angles) | ..= 1 000 000 | [`MAX_PROBE_POINTS`] |
//! | Monte-Carlo draws | ..= 100 000 | [`MAX_DRAWS`] |
//! | coordinates in files (mm) | \|x\| ≤ 100 000 | [`MAX_COORDINATE_MM`] |
//! | cutter, shank, edge diameter (mm) | [0.001, 2 000] | [`MIN_DIAMETER_MM`], [`MAX_DIAMETER_MM`] |
//! | shank modulus E (GPa) | [1, 2 000] | [`MIN_MODULUS_GPA`], [`MAX_MODULUS_GPA`] |
//! | holder rotational stiffness k_θ (N·m/rad) | [1, 10¹²] | [`MIN_HOLDER_STIFFNESS_NM_PER_RAD`] |
//! | gap between the shank's two sensors (mm) | ≥ 0.001 | [`MIN_SENSOR_GAP_MM`] |
//! | feed per tooth f_z (mm) | (0, 10] | [`MAX_FZ_MM`] |
//! | feed rate (mm/min) | [0.001, 1 000 000] | [`MIN_FEED_MM_MIN`], [`MAX_FEED_MM_MIN`] |
//! | depths a_p, a_e (mm) | a_p in [0.001, 1 000], a_e in (0, D] | [`MIN_DEPTH_MM`], [`MAX_DEPTH_MM`] |
//! | spindle speed (rpm) | (0, 1 000 000] | [`MAX_RPM`] |
//! | runout ρ | < cutter radius R | [`runout_vs_radius`] |
//! | cutting coefficients (N/mm², N/mm) | \|K\| ≤ 10⁶ | [`MAX_COEFFICIENT`] |
//! | simulated revolutions | ≥ 1 (a peak per tooth) | [`MIN_SIMULATED_REVOLUTIONS`] |
//! | any value given with a unit (flags, config keys) | \|x\| ≤ 10⁵ mm, 10⁸ µm, 10⁶ deg, 10⁶ rpm, 10⁶ N/mm², 10⁶ N/mm, 10⁴ GPa, 10⁹ N, 10⁷ s, 10⁹ Hz, 10⁶ µm/mm, 10¹⁵ plain | [`MAX_ABS_QUANTITY`] |
//! | text line (bytes) | ≤ 1 MiB | [`MAX_LINE_BYTES`] |
//! | header of a recording (bytes) | ≤ 1 MiB | [`MAX_HEADER_BYTES`] |
//! | non-streaming table or config file (bytes) | ≤ 64 MiB | [`MAX_TABLE_BYTES`] |
//! | chip/force evaluations of one command | ≤ 10¹⁰ | [`MAX_EVALUATIONS`] |
//! | time samples of one result | ≤ 20 000 000 | [`MAX_SAMPLES`] |
//! | result memory of one command (bytes) | ≤ 2 GiB | [`MAX_RESULT_BYTES`] |

use crate::ParamError;

/// A number for a message: as written when short, in exponent form when long (`1e300`, not 301
/// digits).
pub fn show(v: f64) -> String {
    let s = v.to_string();
    if s.len() > 16 {
        format!("{v:e}")
    } else {
        s
    }
}

/// Largest number of teeth (flutes, edges) of a cutter.
pub const MAX_TEETH: usize = 360;
/// Largest number of axial disks of a force simulation.
pub const MAX_DISKS: usize = 10_000;
/// Largest number of time samples per spindle revolution.
pub const MAX_SAMPLES_PER_REV: usize = 100_000;
/// Largest number of points per flute of a ground edge.
pub const MAX_POINTS_PER_FLUTE: usize = 1_000_000;
/// Largest probe grid (layers × angles) of a simulated probe.
pub const MAX_PROBE_POINTS: usize = 1_000_000;
/// Largest number of Monte-Carlo draws.
pub const MAX_DRAWS: usize = 100_000;
/// Largest number of spindle revolutions simulated or sampled.
pub const MAX_REVOLUTIONS: f64 = 100_000.0;
/// Largest |coordinate| (mm) in a toolpath, NC program or table (100 m).
pub const MAX_COORDINATE_MM: f64 = 1.0e5;
/// Smallest cutter, shank or edge diameter (mm): 1 µm.
pub const MIN_DIAMETER_MM: f64 = 1.0e-3;
/// Largest cutter diameter (mm).
pub const MAX_DIAMETER_MM: f64 = 2_000.0;
/// Smallest Young's modulus of a tool shank (GPa): tool materials run from ≈ 70 (aluminium
/// extensions) to ≈ 1 050 (diamond); 1 GPa keeps every beam formula far from underflow.
pub const MIN_MODULUS_GPA: f64 = 1.0;
/// Largest Young's modulus of a tool shank (GPa).
pub const MAX_MODULUS_GPA: f64 = 2_000.0;
/// Smallest rotational stiffness of a tool holder (N·m/rad): real holders are 10⁴–10⁷; below
/// 1 N·m/rad the holder term x·a/k_θ of the compliance overflows for subnormal inputs.
pub const MIN_HOLDER_STIFFNESS_NM_PER_RAD: f64 = 1.0;
/// Largest rotational stiffness of a tool holder (N·m/rad); stiffer is a rigid clamp.
pub const MAX_HOLDER_STIFFNESS_NM_PER_RAD: f64 = 1.0e12;
/// Smallest height difference between the shank's two displacement sensors (mm): 1 µm, as the
/// smallest diameter (below it l_II² − l_I² underflows and K_δ comes out infinite).
pub const MIN_SENSOR_GAP_MM: f64 = 1.0e-3;
/// Largest feed per tooth f_z (mm).
pub const MAX_FZ_MM: f64 = 10.0;
/// Smallest feed rate (mm/min) of a toolpath move.
pub const MIN_FEED_MM_MIN: f64 = 1.0e-3;
/// Largest feed rate (mm/min) of a toolpath move.
pub const MAX_FEED_MM_MIN: f64 = 1.0e6;
/// Largest depth of cut a_p or a_e (mm).
pub const MAX_DEPTH_MM: f64 = 1_000.0;
/// Smallest axial depth of cut a_p (mm): 1 µm.
pub const MIN_DEPTH_MM: f64 = 1.0e-3;
/// Largest spindle speed (rpm).
pub const MAX_RPM: f64 = 1.0e6;
/// Largest |cutting coefficient| (N/mm² shear, N/mm edge) given as an input.
pub const MAX_COEFFICIENT: f64 = 1.0e6;
/// Fewest revolutions of a force simulation: every tooth's peak needs one full revolution.
pub const MIN_SIMULATED_REVOLUTIONS: f64 = 1.0;
/// Largest |value| of a number given with a unit, per quantity (unit as written, value, limit
/// name): a flag or key beyond it is refused, whatever its meaning, so no later product or
/// power of it overflows.
pub const MAX_ABS_QUANTITY: &[(&str, f64)] = &[
    ("mm", MAX_COORDINATE_MM),
    ("µm", MAX_COORDINATE_MM * 1e3),
    ("deg", 1.0e6),
    ("rpm", MAX_RPM),
    ("N/mm²", MAX_COEFFICIENT),
    ("N/mm", MAX_COEFFICIENT),
    ("GPa", 1.0e4),
    ("N", 1.0e9),
    ("s", 1.0e7),
    ("Hz", 1.0e9),
    ("µm/mm", 1.0e6),
    ("", 1.0e15),
];

/// The [`MAX_ABS_QUANTITY`] of the quantity written in `unit` (`""` for plain numbers).
pub fn max_abs_quantity(unit: &str) -> f64 {
    MAX_ABS_QUANTITY
        .iter()
        .find(|(u, _)| *u == unit)
        .map_or(1.0e15, |(_, m)| *m)
}

/// Longest line of a text file (bytes).
pub const MAX_LINE_BYTES: usize = 1024 * 1024;
/// Largest header of a recording (bytes before the first data row).
pub const MAX_HEADER_BYTES: usize = 1024 * 1024;
/// Largest file read whole into memory (tables, configs, toolpaths, NC programs; bytes).
pub const MAX_TABLE_BYTES: u64 = 64 * 1024 * 1024;
/// Largest number of elementary evaluations (sample × disk × tooth × look-back tooth for the
/// chip models; × K again for the exact model's Newton search) one command will start.
pub const MAX_EVALUATIONS: f64 = 1.0e10;
/// Largest number of time samples of one result (a simulation, a written recording, a grid).
pub const MAX_SAMPLES: usize = 20_000_000;
/// Largest memory of one result (bytes).
pub const MAX_RESULT_BYTES: f64 = 2.0 * 1024.0 * 1024.0 * 1024.0;

/// A count (teeth, disks, …) in `1..=max`.
pub fn count(key: &str, value: usize, max: usize) -> Result<usize, ParamError> {
    if (1..=max).contains(&value) {
        Ok(value)
    } else {
        Err(ParamError::new(
            key,
            format!("an integer in [1, {max}]"),
            value,
        ))
    }
}

/// A diameter (mm) in [[`MIN_DIAMETER_MM`], [`MAX_DIAMETER_MM`]].
pub fn diameter(key: &str, value: f64) -> Result<f64, ParamError> {
    within(key, value, MIN_DIAMETER_MM, MAX_DIAMETER_MM, "mm")
}

/// Number of teeth K, checked before anything is allocated per tooth.
pub fn teeth(key: &str, value: usize) -> Result<usize, ParamError> {
    count(key, value, MAX_TEETH)
}

/// A finite number in `(0, max]` (`unit` for the message).
pub fn positive_at_most(key: &str, value: f64, max: f64, unit: &str) -> Result<f64, ParamError> {
    if value.is_finite() && value > 0.0 && value <= max {
        Ok(value)
    } else {
        Err(ParamError::new(
            key,
            format!("a number in (0, {max}] {unit}"),
            show(value),
        ))
    }
}

/// A finite number in `[min, max]`.
pub fn within(key: &str, value: f64, min: f64, max: f64, unit: &str) -> Result<f64, ParamError> {
    if value.is_finite() && (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(ParamError::new(
            key,
            format!("a number in [{min}, {max}] {unit}"),
            show(value),
        ))
    }
}

/// A coordinate (mm) with |x| ≤ [`MAX_COORDINATE_MM`].
pub fn coordinate(key: &str, value: f64) -> Result<f64, ParamError> {
    within(key, value, -MAX_COORDINATE_MM, MAX_COORDINATE_MM, "mm")
}

/// A feed rate (mm/min) in [[`MIN_FEED_MM_MIN`], [`MAX_FEED_MM_MIN`]].
pub fn feed_mm_min(key: &str, value: f64) -> Result<f64, ParamError> {
    within(key, value, MIN_FEED_MM_MIN, MAX_FEED_MM_MIN, "mm/min")
}

/// Runout offset ρ (mm) strictly below the cutter radius R (mm): a larger offset would put the
/// spindle axis outside the tool.
pub fn runout_vs_radius(key: &str, rho_mm: f64, radius_mm: f64) -> Result<f64, ParamError> {
    if rho_mm.is_finite() && rho_mm >= 0.0 && rho_mm < radius_mm {
        Ok(rho_mm)
    } else {
        Err(ParamError::new(
            key,
            format!(
                "a runout offset >= 0 and below the cutter radius R = {radius_mm} mm = {} µm",
                radius_mm * 1e3
            ),
            format!("{} µm", show(rho_mm * 1e3)),
        ))
    }
}

/// Work a command would start: `amount` (of `what`) must not exceed `max`; `key` names the
/// setting that drives it.
pub fn work(key: &str, what: &str, amount: f64, max: f64) -> Result<(), ParamError> {
    if amount.is_finite() && amount <= max {
        Ok(())
    } else {
        Err(ParamError::new(
            key,
            format!("at most {max:.3e} {what} in one command"),
            format!("{amount:.3e} {what}"),
        ))
    }
}

/// Samples and memory of a result of `samples` rows of `values_per_sample` f64 each.
pub fn result_size(key: &str, samples: f64, values_per_sample: f64) -> Result<(), ParamError> {
    work(key, "samples", samples, MAX_SAMPLES as f64)?;
    work(
        key,
        "bytes",
        samples * values_per_sample * 8.0,
        MAX_RESULT_BYTES,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_key_the_limit_and_the_value() {
        let e = teeth("teeth", 4_000_000_000).unwrap_err().to_string();
        assert!(e.contains("`teeth`") && e.contains("[1, 360]") && e.contains("4000000000"));
        assert!(teeth("teeth", 0).is_err());
        assert_eq!(teeth("teeth", 360), Ok(360));
        let e = coordinate("GOTO x", 1e300).unwrap_err().to_string();
        assert!(
            e.contains("[-100000, 100000] mm") && e.contains("1e300") && !e.contains("MAX_"),
            "{e}"
        );
        assert!(coordinate("x", f64::NAN).is_err());
        assert!(feed_mm_min("FEDRAT", 1e-300).is_err());
        assert!(runout_vs_radius("runout_um", 5.0, 5.0).is_err());
        assert!(runout_vs_radius("runout_um", 4.999, 5.0).is_ok());
        let e = work("teeth", "evaluations", 2e10, MAX_EVALUATIONS)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("at most 1.000e10 evaluations") && e.contains("2.000e10"),
            "{e}"
        );
        assert!(result_size("revolutions", 1e9, 1.0).is_err());
        assert!(result_size("revolutions", 1e6, 10.0).is_ok());
    }
}
