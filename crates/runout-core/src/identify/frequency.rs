//! Frequency-domain runout estimate, methods.md §4.7 (generalised).
//!
//! §4.7: with the linear per-edge chip model, the force harmonic at the spindle frequency is
//! F₁ = −j·K·ρ·sin(π/K)·e^{jφ}·P₁ (runout enters only at n ≢ 0 mod K), so the runout vector follows
//! from F₁ by a complex division. Here the same statement is evaluated numerically for any
//! helix, pitch, engagement and component: the model's response to the runout vector e = (e_x, e_y)
//! is linear to first order, F(θ) ≈ F⁽⁰⁾(θ) + J_x(θ)·e_x + J_y(θ)·e_y, with J the analytic
//! derivative of [`RevolutionModel`] at e = 0 (which **is** the linear chip model
//! h = f sin φ + e·(u_i − u_{i−1})). Taking the first Fourier coefficient
//! X₁ = Σ_q F(θ_q)·e^{−jθ_q} of every measured component of every recording gives
//! X₁ − X₁⁽⁰⁾ = G_x·e_x + G_y·e_y (complex), solved for (e_x, e_y) by real least squares
//! (2 unknowns, 2 equations per component). For straight flutes and one component this is
//! exactly (4.7); it is exact on the linear chip model and biased by chip clipping near
//! entry/exit and by edge forces (methods.md §4.7: −3…−6 %, 2–4°). Use it as a start value.
//! It needs the cutting coefficients (shear ratio); K = 2 works (n = 1 ≠ K).
//! A single DFT bin is a direct O(N) sum — cheaper than an FFT of the whole revolution.

use super::error::IdentifyError;
use super::model::{force_from_basis, runout_gradient, RevolutionModel};
use super::waveform::WaveformCase;
use crate::coefficients::CuttingCoefficients;
use crate::fit::{fourier_coefficient, linear_lsq, FitError};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// Result of the frequency-domain estimate (mm, rad).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrequencyEstimate {
    /// Runout vector e = (e_x, e_y) (mm, spindle frame).
    pub vector: [f64; 2],
    /// Offset ρ (mm).
    pub offset: f64,
    /// Angle λ (rad).
    pub angle: f64,
    /// Relative residual of the harmonic equations ‖X₁ − G e‖/‖X₁‖.
    pub relative_residual: f64,
}

/// First Fourier coefficient Σ v_q e^{−jθ_q} as (re, im) ([`fourier_coefficient`]).
fn first_harmonic(values: impl Iterator<Item = f64>, angles: &[f64]) -> (f64, f64) {
    fourier_coefficient(values, angles.iter().copied())
}

/// Estimate the runout vector from the spindle-frequency harmonic of the averaged waveforms,
/// given the cutting coefficients, with `disks` axial disks (≥ 1).
pub fn frequency_estimate(
    cases: &[WaveformCase],
    coefficients: &CuttingCoefficients,
    disks: usize,
) -> Result<FrequencyEstimate, IdentifyError> {
    let mut rows: Vec<[f64; 2]> = Vec::new();
    let mut rhs: Vec<f64> = Vec::new();
    for case in cases {
        let n = case.waveform.validate()?;
        let model =
            RevolutionModel::new(&case.cutter, &case.cut, case.waveform.start_angle, n, disks);
        let sums = model.sums([0.0, 0.0], [0.0, 0.0], false);
        let angles: Vec<f64> = (0..n).map(|q| case.waveform.angle(q)).collect();
        for comp in &case.waveform.components {
            let x1 = first_harmonic(comp.values.iter().copied(), &angles);
            let f0 = first_harmonic(
                sums.base
                    .iter()
                    .map(|b| force_from_basis(comp.axis, b, coefficients)),
                &angles,
            );
            let gx = first_harmonic(
                sums.deriv
                    .iter()
                    .map(|d| runout_gradient(comp.axis, &d[0], coefficients)),
                &angles,
            );
            let gy = first_harmonic(
                sums.deriv
                    .iter()
                    .map(|d| runout_gradient(comp.axis, &d[1], coefficients)),
                &angles,
            );
            rows.push([gx.0, gy.0]);
            rhs.push(x1.0 - f0.0);
            rows.push([gx.1, gy.1]);
            rhs.push(x1.1 - f0.1);
        }
    }
    let x = DMatrix::from_fn(rows.len(), 2, |r, c| rows[r][c]);
    let y = DVector::from_vec(rhs);
    let fit = linear_lsq("frequency-domain runout estimate", &x, &y).map_err(|e| match e {
        FitError::Singular { what, reason } => IdentifyError::Singular {
            what,
            reason: format!(
                "{reason}: one direction of the runout vector does not change the spindle \
                 harmonic (K = 2 with straight flutes: only the component along the tooth line \
                 is observable)"
            ),
        },
        other => other.into(),
    })?;
    let e = [fit.beta[0], fit.beta[1]];
    Ok(FrequencyEstimate {
        vector: e,
        offset: e[0].hypot(e[1]),
        angle: e[1].atan2(e[0]),
        relative_residual: fit.rss.sqrt() / y.norm().max(f64::MIN_POSITIVE),
    })
}
