//! Runout identified in position from displacement measurements (methods.md §1, seed 000).
//!
//! A displacement sensor (laser triangulation, capacitive, dial gauge) looks at the rotating tool.
//! From its readings this module identifies the runout vector e = ρ·(cos λ, sin λ)
//! (`conventions.md`, "Runout") in three ways:
//!
//! * [`teeth`]: one reading per tooth tip P_i at the cutting height → radius differences
//!   ΔR_i (methods.md eq. 8) → (ρ, λ) by a joint least-squares fit of the exact model (eq. 0.1 / seed
//!   eq. 2) for K ≥ 3, the closed form of seed eq. (4) for K = 2, or the seed's 1° scan;
//! * [`heights`]: runout (half the TIR, seed eq. 5) at several heights → runout at the cutting height by
//!   ordinary least squares (default), the seed's eq. (6), or the complex offset + tilt fit (§1.6);
//! * [`signal`]: a raw displacement recording (one or more sensors, optional once-per-revolution or
//!   encoder channel) → first harmonic by linear least squares, per-revolution max/min, per-tooth
//!   extrema.
//!
//! Every estimate carries its standard error (§1.5 error propagation) and the angle is reported
//! as undetermined, with the reason, when the offset is too small for the noise ([`AngleEstimate`]).
//! [`consequences()`] turns an identified runout into tooth radii, slot width, hole diameter and
//! per-tooth chip loads (§1.7).
//!
//! Angles are radians, lengths mm (µm only in reports).

pub mod beam;
pub mod consequences;
pub mod error;
pub mod estimate;
pub mod heights;
pub mod readings;
pub mod signal;
pub mod teeth;

pub use beam::BeamGeometry;
pub use consequences::{consequences, Consequences};
pub use error::DisplacementError;
pub use estimate::{polar_with_covariance, AngleEstimate, NoiseSource, ANGLE_SE_LIMIT_RAD};
pub use heights::{
    runout_at_height, vector_at_height, HeightFit, HeightRegression, VectorHeightFit,
};
pub use readings::{SensorSign, ToothReadings};
pub use signal::{
    fit_signal, per_revolution_runout, per_tooth_extrema, spindle_track, ChannelFit,
    RevolutionRunout, SensorChannel, SignalFit, SignalInput, SpindleReference, SpindleTrack,
    TrackSource,
};
pub use teeth::{identify_from_teeth, ToothFit, ToothFitOptions, ToothMethod};
