//! The numeric toolbox shared by every method: linear least squares with covariance, standard
//! errors, condition number and R² ([`linear`]), first-harmonic / Fourier-series least squares
//! ([`harmonic`]), and the offset + tilt line of an axis ([`offset_tilt`]: one fit for the
//! displacement heights, the shank templates and the grind layers). Every fit in `chip`, `grind`,
//! `shank`, `displacement` and `identify` goes through these; the decompositions come from `nalgebra` (no home-made linear algebra).

pub mod harmonic;
pub mod linear;
pub mod offset_tilt;

pub use harmonic::{fourier_coefficient, HarmonicFit, HarmonicSums};
pub use linear::{
    fit_line, linear_lsq, linear_lsq_beta, r_squared, FitError, LinearFit, LinearLsq, Regression,
};
pub use offset_tilt::{fit_offset_tilt, LineNoise, OffsetTiltFit};
