//! The offset + tilt of an axis: the straight line e(z) = e₀ + z·τ through spindle-frame
//! vectors E_i measured at heights z_i, methods.md §1.6 (displacement readings at several
//! heights, the shank's air-cut templates at the two sensor heights, §3.2 end) and §5.2 (the
//! per-layer first harmonics of a probed bar).
//!
//! Each component c ∈ {x, y} is an ordinary least-squares line E_i,c ≈ e₀,c + z_i·τ_c, with design
//! X = [1, z_i] solved through its SVD ([`LinearLsq`]). The covariance of (e₀,c, τ_c) is
//! Cov_c = σ_c²·(XᵀX)⁻¹ when the noise comes from the residual scatter ([`LineNoise::PerComponent`]:
//! σ_c² = RSS_c/(n − 2); [`LineNoise::Pooled`]: σ² = (RSS_x + RSS_y)/(2n − 4) for both), and the
//! sandwich Cov = (XᵀX)⁻¹·Xᵀ·diag(s_i²)·X·(XᵀX)⁻¹ when each point carries a known standard error
//! s_i ([`LineNoise::Known`]). At a height z the vector e(z) has per-component variance
//! gᵀ·Cov_c·g with g = (1, z).

use super::linear::{FitError, LinearLsq};
use crate::estimate::Estimate;
use crate::runout::Runout;
use nalgebra::{DMatrix, DVector, Matrix2};
use serde::Serialize;

/// Where the standard errors of an offset + tilt fit come from.
#[derive(Debug, Clone, PartialEq)]
pub enum LineNoise {
    /// Residual scatter of each component about its line: σ_c² = RSS_c/(n − 2) (grind layers).
    PerComponent,
    /// Residual scatter pooled over both components: σ² = (RSS_x + RSS_y)/(2n − 4)
    /// (displacement heights: isotropic sensor noise).
    Pooled,
    /// A known standard error s_i (mm, the same for both components) of each point, e.g. from the
    /// template averaging of the shank (§3.2); one value per point.
    Known(Vec<f64>),
}

/// Result of [`fit_offset_tilt`]: the runout e(z) = e₀ + z·τ of an axis, with standard errors.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OffsetTiltFit {
    /// e₀ (mm): the offset vector (x, y) at z = 0, each component ± its standard error.
    pub offset: [Estimate; 2],
    /// τ (mm/mm): the tilt vector (x, y), each component ± its standard error.
    pub tilt: [Estimate; 2],
    /// Per point: E_i − e(z_i) (mm), what a rigid offset + tilt does not explain.
    pub residuals: Vec<[f64; 2]>,
    /// RMS of |E_i − e(z_i)| (mm): √((RSS_x + RSS_y)/n).
    pub residual_rms: f64,
    /// Number of points n.
    pub points: usize,
    /// Covariance of (e₀,c, τ_c) per component c (mm², mm²/mm, mm²/mm²); `None` without noise estimate.
    #[serde(skip)]
    covariance: Option<[Matrix2<f64>; 2]>,
}

impl OffsetTiltFit {
    /// A fit that could not be formed (fewer than two points): every value `NaN`, no standard errors.
    pub fn undetermined(points: usize) -> Self {
        let nan = Estimate::new(f64::NAN, None);
        OffsetTiltFit {
            offset: [nan; 2],
            tilt: [nan; 2],
            residuals: vec![[f64::NAN; 2]; points],
            residual_rms: f64::NAN,
            points,
            covariance: None,
        }
    }

    /// e₀ (mm) as a vector.
    pub fn offset_mm(&self) -> [f64; 2] {
        [self.offset[0].value, self.offset[1].value]
    }

    /// τ (mm/mm) as a vector.
    pub fn tilt_vector(&self) -> [f64; 2] {
        [self.tilt[0].value, self.tilt[1].value]
    }

    /// Standard errors of the components of e₀ (mm), when estimable.
    pub fn offset_se(&self) -> Option<[f64; 2]> {
        Some([self.offset[0].se?, self.offset[1].se?])
    }

    /// Standard errors of the components of τ (mm/mm), when estimable.
    pub fn tilt_se(&self) -> Option<[f64; 2]> {
        Some([self.tilt[0].se?, self.tilt[1].se?])
    }

    /// e(z) = e₀ + z·τ (mm).
    pub fn at(&self, z: f64) -> [f64; 2] {
        [
            self.offset[0].value + z * self.tilt[0].value,
            self.offset[1].value + z * self.tilt[1].value,
        ]
    }

    /// Variance of each component of e(z) (mm²): gᵀ·Cov_c·g, g = (1, z); `None` without noise estimate.
    pub fn at_variance(&self, z: f64) -> Option<[f64; 2]> {
        let cov = self.covariance.as_ref()?;
        let v = |m: &Matrix2<f64>| m[(0, 0)] + 2.0 * z * m[(0, 1)] + z * z * m[(1, 1)];
        Some([v(&cov[0]), v(&cov[1])])
    }

    /// The runout e(z) = e₀ + z·τ as a [`Runout`] (z = 0 reference).
    pub fn runout(&self) -> Runout {
        Runout::from_vector(self.offset_mm()).with_tilt_vector(self.tilt_vector())
    }
}

/// Fit e(z) = e₀ + z·τ through `points` = (z_i, E_i) (mm, spindle or bar frame), methods.md §1.6
/// and §5.2; standard errors as `noise` says. Needs at least two points; heights that are all
/// equal leave the tilt undetermined (the SVD then returns the minimum-norm line), so callers that
/// face user input check the heights first and name the offending value.
///
/// ```
/// use runout_core::fit::{fit_offset_tilt, LineNoise};
/// let pts = [(1.0, [0.003, 0.001]), (2.0, [0.003, 0.002]), (3.0, [0.003, 0.003])];
/// let fit = fit_offset_tilt(&pts, &LineNoise::PerComponent).unwrap();
/// assert!((fit.offset[0].value - 0.003).abs() < 1e-15 && fit.offset[1].value.abs() < 1e-15);
/// assert!((fit.tilt[1].value - 0.001).abs() < 1e-15 && fit.residual_rms < 1e-15);
/// assert!((fit.runout().vector_at(2.0)[1] - 0.002).abs() < 1e-15);
/// ```
pub fn fit_offset_tilt(
    points: &[(f64, [f64; 2])],
    noise: &LineNoise,
) -> Result<OffsetTiltFit, FitError> {
    let m = points.len();
    if m < 2 {
        return Err(FitError::too_few("offset + tilt fit", "2 heights", m));
    }
    if let LineNoise::Known(s) = noise {
        if s.len() != m {
            return Err(FitError::too_few(
                "offset + tilt fit",
                format!("one standard error per point ({m})"),
                s.len(),
            ));
        }
    }
    let lsq = LinearLsq::new(DMatrix::from_fn(m, 2, |i, k| {
        if k == 0 {
            1.0
        } else {
            points[i].0
        }
    }));
    let mut coef = [[0.0; 2]; 2]; // [component][intercept, slope]
    let mut residuals = vec![[0.0; 2]; m];
    let mut rss = [0.0; 2];
    for comp in 0..2 {
        let b = DVector::from_iterator(m, points.iter().map(|p| p.1[comp]));
        let x = lsq
            .beta(&b, 1e-14)
            .unwrap_or_else(|_| DVector::from_element(2, f64::NAN));
        coef[comp] = [x[0], x[1]];
        let r = &b - lsq.design() * &x;
        for i in 0..m {
            residuals[i][comp] = r[i];
        }
        rss[comp] = r.norm_squared();
    }
    let inv = lsq
        .normal_inverse()
        .map(|a| Matrix2::new(a[(0, 0)], a[(0, 1)], a[(1, 0)], a[(1, 1)]));
    let covariance = inv.and_then(|inv| match noise {
        LineNoise::PerComponent => (m > 2).then(|| rss.map(|r| inv * (r / (m - 2) as f64))),
        LineNoise::Pooled => (m > 2).then(|| {
            let s2 = (rss[0] + rss[1]) / (2 * m - 4) as f64;
            [inv * s2, inv * s2]
        }),
        LineNoise::Known(s) => {
            let mut meat = Matrix2::zeros();
            for (p, si) in points.iter().zip(s) {
                let g = nalgebra::Vector2::new(1.0, p.0);
                meat += g * g.transpose() * (si * si);
            }
            let c = inv * meat * inv;
            Some([c, c])
        }
    });
    let se = |c: usize, k: usize| covariance.map(|cov| cov[c][(k, k)].sqrt());
    Ok(OffsetTiltFit {
        offset: [
            Estimate::new(coef[0][0], se(0, 0)),
            Estimate::new(coef[1][0], se(1, 0)),
        ],
        tilt: [
            Estimate::new(coef[0][1], se(0, 1)),
            Estimate::new(coef[1][1], se(1, 1)),
        ],
        residuals,
        residual_rms: ((rss[0] + rss[1]) / m as f64).sqrt(),
        points: m,
        covariance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two heights with known per-point errors: the line passes through the two cluster means, so
    /// e(z) at any z is (1 − w)·Ē_I + w·Ē_II with w = (z − z_I)/(z_II − z_I), and the sandwich
    /// variance must equal (1 − w)²·Σs_I²/n² + w²·Σs_II²/n² (the shank's former closed form).
    /// Relative 1e-12: a few rounding steps on O(1) numbers.
    #[test]
    fn known_noise_at_two_heights_matches_the_closed_form() {
        let (zi, zii) = (20.0, 45.0);
        let s = [0.002, 0.003, 0.0015, 0.0025];
        let pts = [
            (zi, [0.010, 0.002]),
            (zii, [0.015, 0.001]),
            (zi, [0.011, 0.0025]),
            (zii, [0.0155, 0.0012]),
        ];
        let fit = fit_offset_tilt(&pts, &LineNoise::Known(s.to_vec())).unwrap();
        let zc = 3.0;
        let w: f64 = (zc - zi) / (zii - zi);
        let want = ((1.0 - w).powi(2) * (s[0] * s[0] + s[2] * s[2])
            + w * w * (s[1] * s[1] + s[3] * s[3]))
            / 4.0;
        let got = fit.at_variance(zc).unwrap();
        assert!((got[0] - want).abs() < 1e-12 * want && (got[1] - want).abs() < 1e-12 * want);
        let tilt_var = (s.iter().map(|v| v * v).sum::<f64>()) / (zii - zi).powi(2) / 4.0;
        let tse = fit.tilt_se().unwrap();
        assert!((tse[0] * tse[0] - tilt_var).abs() < 1e-12 * tilt_var);
        let e1x = (0.010 + 0.011) / 2.0;
        let e2x = (0.015 + 0.0155) / 2.0;
        assert!((fit.at(zc)[0] - ((1.0 - w) * e1x + w * e2x)).abs() < 1e-15);
    }

    /// Pooled and per-component noise give the same covariance shape (XᵀX)⁻¹, scaled by the
    /// pooled or per-component residual variance; with two points there is no residual and no SE.
    #[test]
    fn residual_noise_options() {
        let pts = [
            (0.0, [1.0, 0.0]),
            (1.0, [2.1, 0.5]),
            (2.0, [2.9, 1.0]),
            (3.0, [4.0, 1.4]),
        ];
        let a = fit_offset_tilt(&pts, &LineNoise::PerComponent).unwrap();
        let b = fit_offset_tilt(&pts, &LineNoise::Pooled).unwrap();
        let rss: Vec<f64> = (0..2)
            .map(|c| a.residuals.iter().map(|r| r[c] * r[c]).sum())
            .collect();
        let (va, vb) = (a.at_variance(0.0).unwrap(), b.at_variance(0.0).unwrap());
        // (XᵀX)⁻¹₀₀ = Σz²/(nΣz² − (Σz)²) = 14/20 for z = 0..3
        assert!((va[0] - rss[0] / 2.0 * 0.7).abs() < 1e-14);
        assert!((va[1] - rss[1] / 2.0 * 0.7).abs() < 1e-14);
        assert!((vb[0] - (rss[0] + rss[1]) / 4.0 * 0.7).abs() < 1e-14 && vb[0] == vb[1]);
        let two = fit_offset_tilt(&pts[..2], &LineNoise::PerComponent).unwrap();
        assert!(two.offset_se().is_none() && two.at_variance(1.0).is_none());
        assert!(fit_offset_tilt(&pts[..1], &LineNoise::Pooled).is_err());
    }
}
