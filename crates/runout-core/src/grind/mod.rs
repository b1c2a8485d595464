//! Grinding compensation of the bar-stock clamping error of end mills (seed 004,
//! methods.md §5).
//!
//! Pipeline: probe rows → [`ProbeGrid`] (tip compensation, checks) → [`DeviationMap`] (seed
//! δ_ij, per-layer first harmonic, fitted axis offset + tilt, residual form) → [`Interpolator`]
//! (first harmonic by default, or the seed's bilinear with periodic wrap; clamp or extrapolate
//! outside the probed range) on an [`EdgeLine`] → [`compensate`] (w′ = w + ε·N, predicted
//! remaining error). [`SimulatedBar`] and [`grind_check`] reproduce methods.md §5.5.
//!
//! Frame: u along the work-head axis from the tool tip (mm), α in the bar frame, positive in the
//! direction of spindle rotation, tooth 0 at α = 0 at the tip (`conventions.md`).

mod compensate;
mod deviation;
mod edge;
mod error;
mod interp;
mod nominal;
mod probe;
mod simulate;

pub use compensate::{compensate, rms_max, CompensatedPoint, Compensation};
pub use deviation::{DeviationMap, LayerDeviation};
pub use edge::{EdgeKind, EdgeLine, EdgePoint};
pub use error::GrindError;
pub use interp::{Interpolated, Interpolator, RangePolicy, Scheme};
pub use nominal::Generatrix;
pub use probe::{
    DuplicatePolicy, Layer, MissingPolicy, ProbeGrid, ProbeOptions, ProbePoint, Touch,
};
pub use simulate::{grind_check, uniform_grid, GrindCheck, SimulatedBar};
