//! Errors of the grinding-compensation method: each names the probe row (1-based data row of
//! the probe table, as carried in [`super::ProbePoint::row`]) or the parameter at fault.

use crate::error::ParamError;
use thiserror::Error;

/// Invalid probe data or compensation input (methods.md §5).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum GrindError {
    /// A parameter out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// A value in a probe row is NaN or infinite.
    #[error("row {row}: `{field}` is not a finite number ({value})")]
    NonFinite {
        /// Probe row.
        row: usize,
        /// Field name with unit.
        field: String,
        /// The value.
        value: f64,
    },
    /// A layer has fewer than three probe angles (no first harmonic / no wrap-around possible).
    #[error("layer {layer} (u = {u_mm} mm, rows {first_row}..{last_row}): {count} distinct probe angle(s), at least 3 are needed")]
    TooFewAngles {
        /// Layer label.
        layer: String,
        /// Axial position (mm).
        u_mm: f64,
        /// First row of the layer.
        first_row: usize,
        /// Last row of the layer.
        last_row: usize,
        /// Distinct angles found.
        count: usize,
    },
    /// Fewer than two layers: no interpolation along the bar axis.
    #[error(
        "probe grid has {0} layer(s); at least 2 layers are needed to interpolate along the bar"
    )]
    TooFewLayers(usize),
    /// A new layer's axial position does not increase.
    #[error("row {row}: layer {layer} at u = {u_mm} mm does not increase over the previous layer at u = {previous_u_mm} mm (layers must be listed in increasing u)")]
    LayersNotIncreasing {
        /// Row where the layer starts.
        row: usize,
        /// Layer label.
        layer: String,
        /// Its axial position (mm).
        u_mm: f64,
        /// The previous layer's axial position (mm).
        previous_u_mm: f64,
    },
    /// Rows of one layer are not contiguous.
    #[error("row {row}: layer {layer} appears again after another layer (rows of a layer must be contiguous)")]
    LayerNotContiguous {
        /// Offending row.
        row: usize,
        /// Layer label.
        layer: String,
    },
    /// Two rows probe the same grid point.
    #[error("row {row}: duplicate probe point at layer {layer}, angle {angle_deg}° (first given in row {first_row})")]
    Duplicate {
        /// Second row.
        row: usize,
        /// First row.
        first_row: usize,
        /// Layer label.
        layer: String,
        /// Angle (deg).
        angle_deg: f64,
    },
    /// A grid angle probed on other layers is missing on this layer.
    #[error("layer {layer} (u = {u_mm} mm): no probe point at angle {angle_deg}° although other layers have one (missing grid point; choose the `skip` policy to accept)")]
    Missing {
        /// Layer label.
        layer: String,
        /// Axial position (mm).
        u_mm: f64,
        /// Missing angle (deg).
        angle_deg: f64,
    },
    /// A touched point far from the nominal surface: the probe missed or hit debris.
    #[error("row {row}: measured radius {radius_mm:.6} mm is {distance_um:.1} µm from the nominal radius {nominal_mm:.6} mm at u = {u_mm} mm (limit {limit} µm: probe miss?)", limit = crate::limits::show(*.limit_um))]
    ProbeMiss {
        /// Row.
        row: usize,
        /// Measured radius (mm).
        radius_mm: f64,
        /// Nominal radius (mm).
        nominal_mm: f64,
        /// Axial position (mm).
        u_mm: f64,
        /// |measured − nominal| (µm).
        distance_um: f64,
        /// Tolerance (µm).
        limit_um: f64,
    },
}
