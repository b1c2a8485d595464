//! Edge-force-aware pooled fit of all peaks of several tests, methods.md §4.6.
//!
//! Model (teeth i, tests j, first-order chip h = f_z sin γ + R_i − R_{i−1}):
//!
//! F_ij = C₀ + E·a_j + K·a_j·[f_j·sin γ_j − 2ρ·sin(π/K)·sin(λ + (2i−1)π/K)]
//!
//! (spec form with S = K·sin γ). With u = ρ cos λ, v = ρ sin λ it is **linear** in
//! (C₀, E, K, K·u, K·v): F = C₀ + E a + K a f sin γ − 2 sin(π/K)·a·[Ku·sin((2i−1)π/K) + Kv·cos((2i−1)π/K)],
//! so it is solved by linear least squares; ρ = hypot(Ku, Kv)/K and λ = atan2(Kv, Ku) with
//! standard errors by the delta method from Cov = σ̂²(XᵀX)⁻¹, σ̂² = RSS/(n − p).
//! Separating the edge terms from the shear term needs ≥ 2 distinct feeds.

use super::error::IdentifyError;
use super::peak_test::PeakTest;
use super::sine_fit::Estimate;
use crate::fit::{linear_lsq, r_squared};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use std::f64::consts::PI;

/// Which edge (ploughing) force terms the pooled model contains.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeModel {
    /// No edge force (the seed's eq. 12).
    None,
    /// A constant C₀.
    Constant,
    /// C₀ + E·a_p (edge force proportional to the cut length; best fit on the seed's data).
    ConstantPlusDepth,
}

/// Result of the pooled fit. Offset in mm, angle in rad.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PooledFit {
    /// The edge model.
    pub edge_model: EdgeModel,
    /// Runout offset ρ (mm).
    pub offset: Estimate,
    /// Runout angle λ (rad).
    pub angle: Estimate,
    /// Lumped coefficient K (N/mm²).
    pub k_lumped: Estimate,
    /// Constant edge term C₀ (N), if in the model.
    pub constant_n: Option<Estimate>,
    /// Edge force per mm of depth E (N/mm), if in the model.
    pub edge_n_per_mm: Option<Estimate>,
    /// Residual RMS sqrt(RSS/n) (N).
    pub residual_rms: f64,
    /// R² over all peaks.
    pub r_squared: f64,
    /// Number of peaks n and residual dof n − p.
    pub n: usize,
    /// Residual degrees of freedom.
    pub dof: usize,
    /// Condition number of the design matrix.
    pub condition: f64,
}

/// Pooled linear least-squares fit of all peaks of `tests` (same K) with edge model `edge`.
pub fn pooled_fit(tests: &[PeakTest], edge: EdgeModel) -> Result<PooledFit, IdentifyError> {
    let k = tests.first().map(|t| t.peaks.teeth()).unwrap_or(0);
    if k < 3 {
        return Err(IdentifyError::too_few("pooled peak fit", "K >= 3 teeth", k));
    }
    let kf = k as f64;
    let n_edge = match edge {
        EdgeModel::None => 0,
        EdgeModel::Constant => 1,
        EdgeModel::ConstantPlusDepth => 2,
    };
    let p = n_edge + 3;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut y = Vec::new();
    let s = 2.0 * (PI / kf).sin();
    for t in tests {
        let a = t.ap_mm;
        let fs = t.conditions.fz_mm * t.conditions.sin_gamma;
        for (i, f) in t.peaks.values().iter().enumerate() {
            let w = (2.0 * i as f64 - 1.0) * PI / kf;
            let mut r = Vec::with_capacity(p);
            if n_edge >= 1 {
                r.push(1.0);
            }
            if n_edge >= 2 {
                r.push(a);
            }
            r.extend([a * fs, -s * a * w.sin(), -s * a * w.cos()]);
            rows.push(r);
            y.push(*f);
        }
    }
    let n = y.len();
    let x = DMatrix::from_fn(n, p, |r, c| rows[r][c]);
    let fit = linear_lsq("pooled peak fit", &x, &DVector::from_column_slice(&y))?;
    let b = &fit.beta;
    let (kk, ku, kv) = (b[n_edge], b[n_edge + 1], b[n_edge + 2]);
    let rho = ku.hypot(kv) / kk;
    let lambda = kv.atan2(ku);
    let h = ku.hypot(kv);
    let mut g_rho = vec![0.0; p];
    g_rho[n_edge] = -h / (kk * kk);
    g_rho[n_edge + 1] = ku / (h * kk);
    g_rho[n_edge + 2] = kv / (h * kk);
    let mut g_lam = vec![0.0; p];
    g_lam[n_edge + 1] = -kv / (h * h);
    g_lam[n_edge + 2] = ku / (h * h);
    let unit = |j: usize| {
        let mut g = vec![0.0; p];
        g[j] = 1.0;
        Estimate::delta_method(b[j], &fit, &g)
    };
    Ok(PooledFit {
        edge_model: edge,
        offset: Estimate::delta_method(rho, &fit, &g_rho),
        angle: Estimate::delta_method(lambda, &fit, &g_lam),
        k_lumped: unit(n_edge),
        constant_n: (n_edge >= 1).then(|| unit(0)),
        edge_n_per_mm: (n_edge >= 2).then(|| unit(1)),
        residual_rms: (fit.rss / n as f64).sqrt(),
        r_squared: r_squared(&y, fit.rss),
        n,
        dof: fit.dof(),
        condition: fit.condition,
    })
}
