//! The input of the multi-test methods (methods.md §4.4): one test's cut conditions and per-tooth
//! peaks. Its own module so that `multi_test` (per-test fits + regressions) and `pooled` (one fit
//! over all tests) both depend on it without depending on each other.

use super::sine_fit::{PeakConditions, ToothPeaks};

/// One test: cut conditions, per-tooth peaks and optionally the nominal forces at the peak angle.
#[derive(Debug, Clone, PartialEq)]
pub struct PeakTest {
    /// Label (e.g. "1").
    pub label: String,
    /// Axial depth a_p (mm).
    pub ap_mm: f64,
    /// Feed and peak angle.
    pub conditions: PeakConditions,
    /// Peak immersion angle γ (rad) — for eq. (17).
    pub peak_immersion_rad: f64,
    /// Per-tooth peaks.
    pub peaks: ToothPeaks,
    /// Nominal F̄_x at the peak angle (N, workpiece frame), if measured.
    pub fx_at_peak_n: Option<f64>,
    /// Nominal F̄_y at the peak angle (N, workpiece frame), if measured.
    pub fy_at_peak_n: Option<f64>,
}
