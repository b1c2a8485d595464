//! # runout-core
//!
//! The pure model of a rotating cutter whose axis is offset from the spindle axis, and the
//! methods built on it. No file I/O: readers and writers live in `runout-io`, the command line in
//! `runout-cli`.
//!
//! Units and conventions are those of `docs/conventions.md`: lengths in mm, forces in N,
//! time in s, angles in **radians** inside the library, tooth numbering in cutting order, runout
//! e = ρ·(cos λ, sin λ) measured from tooth 0 in the direction of rotation.
//!
//! ```
//! use runout_core::*;
//! let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians())?;
//! let runout = Runout::new(0.008, 0.0)?;
//! let r0 = runout.tooth_radius(&cutter, 0, 0.0);
//! assert!((r0 - 5.008).abs() < 1e-9);
//! # Ok::<(), runout_core::ParamError>(())
//! ```
#![warn(missing_docs)]

pub mod angle;
pub mod chain;
pub mod chip;
pub mod coefficients;
pub mod cut;
pub mod cutter;
pub mod displacement;
pub mod edge;
pub mod error;
pub mod estimate;
pub mod fit;
pub mod force;
pub mod grind;
pub mod identify;
pub mod limits;
pub mod plausibility;
pub mod runout;
pub mod shank;
pub mod signal;
pub mod verdict;

pub use chip::{ArcChip, ChipAtHeight, ChipThickness, EquivalentChip, ExactChip};
pub use coefficients::CuttingCoefficients;
pub use cut::{Cut, Engagement, MillingMode};
pub use cutter::{Cutter, FluteLead, RadiusProfile};
pub use error::ParamError;
pub use estimate::Estimate;
pub use force::{tooth_peaks, ForceModel, ForceSeries, Sampling, ToothPeak};
pub use runout::Runout;
