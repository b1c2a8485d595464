//! The numeric toolbox shared by every method: linear least squares with covariance, standard
//! errors, condition number and R² ([`linear`]), and first-harmonic / Fourier-series least squares
//! ([`harmonic`]). Every fit in `chip`, `grind`, `shank`, `displacement` and `identify` goes
//! through these; the decompositions come from `nalgebra` (no home-made linear algebra).

pub mod harmonic;
pub mod linear;

pub use harmonic::{fourier_coefficient, HarmonicFit, HarmonicSums};
pub use linear::{fit_line, linear_lsq, r_squared, FitError, LinearFit, LinearLsq, Regression};
