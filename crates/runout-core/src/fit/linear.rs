//! Ordinary linear least squares with covariance, and straight-line regressions.
//!
//! β̂ = argmin ‖y − Xβ‖² by SVD (nalgebra); with σ̂² = RSS/(n − p) the covariance is
//! Cov(β̂) = σ̂²·(XᵀX)⁻¹ (standard errors are the square roots of its diagonal). The condition
//! number is κ(X) = s_max/s_min, and R² = 1 − RSS/Σ(y − ȳ)².
//!
//! A tall X (n ≥ 2p, every fit's design here) is first reduced by a Householder QR, X = Q·R, and
//! the SVD taken of the p × p factor R = U_R·S·Vᵀ (the R-SVD of Golub & Van Loan §5.4.5): X has
//! the same singular values S and right vectors V, and β̂ = V·S⁺·U_Rᵀ·(Qᵀy)₁..ₚ. Measured on
//! nalgebra 0.34 (2772 × 6, the chain fit's coefficient design at 50 kHz): 342 → 86 µs, because
//! the SVD of the tall matrix itself bidiagonalises all n rows and accumulates an n × p U.

use nalgebra::{DMatrix, DVector, Dyn, QR, SVD};
use serde::Serialize;
use thiserror::Error;

/// Why a least-squares fit could not be solved. Converts into each method's error type with the
/// same message (e.g. [`crate::identify::IdentifyError`]).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FitError {
    /// Fewer observations than needed.
    #[error("not enough data for {what}: need {needed}, got {got}")]
    TooFewData {
        /// Which fit.
        what: String,
        /// What is needed.
        needed: String,
        /// What was given.
        got: String,
    },
    /// The design matrix is rank deficient.
    #[error("{what} is singular: {reason}")]
    Singular {
        /// Which fit.
        what: String,
        /// Why.
        reason: String,
    },
}

impl FitError {
    pub(crate) fn too_few(what: &str, needed: impl ToString, got: impl ToString) -> Self {
        FitError::TooFewData {
            what: what.into(),
            needed: needed.to_string(),
            got: got.to_string(),
        }
    }
    pub(crate) fn singular(what: &str, reason: impl ToString) -> Self {
        FitError::Singular {
            what: what.into(),
            reason: reason.to_string(),
        }
    }
}

/// The SVD of a design matrix X, ready to solve y ≈ X·β for one or several right-hand sides.
///
/// ```
/// use nalgebra::{DMatrix, DVector};
/// use runout_core::fit::LinearLsq;
/// let x = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 1.0, 1.0, 1.0, 2.0]);
/// let lsq = LinearLsq::new(x);
/// let fit = lsq.solve(&DVector::from_vec(vec![1.0, 3.0, 5.0]), 0.0).unwrap();
/// assert!((fit.beta[0] - 1.0).abs() < 1e-12 && (fit.beta[1] - 2.0).abs() < 1e-12);
/// assert!(fit.rss < 1e-20);
/// ```
#[derive(Debug, Clone)]
pub struct LinearLsq {
    x: DMatrix<f64>,
    factors: Factors,
}

/// The SVD of X, taken of R after a QR when X is tall (module docs): singular values, V and the
/// map from y to the coordinates that the SVD's U acts on.
#[derive(Debug, Clone)]
struct Factors {
    /// X = Q·R when X was reduced first (`svd` is then R's).
    qr: Option<QR<f64, Dyn, Dyn>>,
    svd: SVD<f64, Dyn, Dyn>,
}

impl Factors {
    fn new(x: DMatrix<f64>) -> Self {
        let (n, p) = x.shape();
        if p > 0 && n >= 2 * p {
            let qr = x.qr();
            let svd = qr.r().svd(true, true);
            Self { qr: Some(qr), svd }
        } else {
            Self {
                qr: None,
                svd: x.svd(true, true),
            }
        }
    }
    fn smax(&self) -> f64 {
        self.svd.singular_values.max()
    }
    fn smin(&self) -> f64 {
        self.svd.singular_values.min()
    }
    /// β̂ = X⁺y, singular values ≤ `eps` treated as zero (nalgebra's `SVD::solve`).
    fn solve(&self, y: &DVector<f64>, eps: f64) -> Result<DVector<f64>, &'static str> {
        match &self.qr {
            None => self.svd.solve(y, eps),
            Some(qr) => {
                let mut qty = y.clone();
                qr.q_tr_mul(&mut qty);
                let p = self.svd.singular_values.len();
                self.svd.solve(&qty.rows(0, p).into_owned(), eps)
            }
        }
    }
}

impl LinearLsq {
    /// Decompose X (n × p) by SVD (through a QR when n ≥ 2p: module docs).
    pub fn new(x: DMatrix<f64>) -> Self {
        let factors = Factors::new(x.clone());
        Self { x, factors }
    }
    /// The design matrix X.
    pub fn design(&self) -> &DMatrix<f64> {
        &self.x
    }
    /// Largest singular value of X.
    pub fn smax(&self) -> f64 {
        self.factors.smax()
    }
    /// Smallest singular value of X.
    pub fn smin(&self) -> f64 {
        self.factors.smin()
    }
    /// 2-norm condition number κ(X) = s_max/s_min.
    pub fn condition(&self) -> f64 {
        self.smax() / self.smin()
    }
    /// β̂ = X⁺y by the SVD, treating singular values ≤ `eps` as zero (nalgebra's `SVD::solve`).
    pub fn beta(&self, y: &DVector<f64>, eps: f64) -> Result<DVector<f64>, &'static str> {
        self.factors.solve(y, eps)
    }
    /// (XᵀX)⁻¹ = V·S⁻²·Vᵀ from the SVD (the well-conditioned way).
    pub fn xtx_inv(&self) -> DMatrix<f64> {
        let svd = &self.factors.svd;
        let v_t = svd.v_t.as_ref().expect("SVD computed with V");
        let inv_s2 = DMatrix::from_diagonal(&svd.singular_values.map(|s| 1.0 / (s * s)));
        v_t.transpose() * inv_s2 * v_t
    }
    /// (XᵀX)⁻¹ by inverting the normal matrix (LU), `None` when it is singular. Kept for the fits
    /// whose published outputs (grind, shank calibration, chip compensation) were computed this
    /// way; agrees with [`LinearLsq::xtx_inv`] to rounding on well-conditioned problems.
    pub fn normal_inverse(&self) -> Option<DMatrix<f64>> {
        (self.x.transpose() * &self.x).try_inverse()
    }
    /// Solve y ≈ X·β (singular values ≤ `eps` treated as zero), with residuals, RSS and the
    /// SVD-based (XᵀX)⁻¹.
    pub fn solve(&self, y: &DVector<f64>, eps: f64) -> Result<LinearFit, &'static str> {
        let (n, p) = self.x.shape();
        let beta = self.beta(y, eps)?;
        let residuals = y - &self.x * &beta;
        let rss = residuals.norm_squared();
        Ok(LinearFit {
            beta,
            xtx_inv: self.xtx_inv(),
            rss,
            residuals,
            n,
            p,
            condition: self.condition(),
        })
    }
}

/// Result of a linear least-squares fit y ≈ X·β.
#[derive(Debug, Clone)]
pub struct LinearFit {
    /// Coefficients β̂.
    pub beta: DVector<f64>,
    /// (XᵀX)⁻¹ (unscaled covariance).
    pub xtx_inv: DMatrix<f64>,
    /// Residual sum of squares.
    pub rss: f64,
    /// Residuals y − Xβ̂.
    pub residuals: DVector<f64>,
    /// Number of observations n.
    pub n: usize,
    /// Number of coefficients p.
    pub p: usize,
    /// 2-norm condition number of X (largest / smallest singular value).
    pub condition: f64,
}

impl LinearFit {
    /// Residual degrees of freedom n − p.
    pub fn dof(&self) -> usize {
        self.n.saturating_sub(self.p)
    }
    /// σ̂² = RSS/(n − p), `None` without residual degrees of freedom.
    pub fn sigma2(&self) -> Option<f64> {
        (self.dof() > 0).then(|| self.rss / self.dof() as f64)
    }
    /// Cov(β̂) = σ̂²(XᵀX)⁻¹, `None` without residual degrees of freedom.
    pub fn covariance(&self) -> Option<DMatrix<f64>> {
        self.sigma2().map(|s2| &self.xtx_inv * s2)
    }
}

/// Solve y ≈ X·β by SVD. Errors when X has fewer rows than columns or is rank deficient
/// (relative singular value below 1e-12).
pub fn linear_lsq(what: &str, x: &DMatrix<f64>, y: &DVector<f64>) -> Result<LinearFit, FitError> {
    let (n, p) = x.shape();
    if n < p {
        return Err(FitError::too_few(what, format!("{p} observations"), n));
    }
    let lsq = LinearLsq::new(x.clone());
    check_rank(what, lsq.smax(), lsq.smin())?;
    lsq.solve(y, 0.0).map_err(|e| FitError::singular(what, e))
}

/// The rank test of [`linear_lsq`]: relative singular value above 1e-12.
fn check_rank(what: &str, smax: f64, smin: f64) -> Result<(), FitError> {
    if smax.is_nan() || smax <= 0.0 || smin <= 1e-12 * smax {
        return Err(FitError::singular(
            what,
            format!("design matrix rank deficient (singular values {smin:.3e} .. {smax:.3e})"),
        ));
    }
    Ok(())
}

/// β̂ of [`linear_lsq`] only (the same SVD, checks and errors, so the same values), without the
/// residuals, covariance and condition number: for the inner loops of profile fits that need
/// the coefficients alone.
pub fn linear_lsq_beta(
    what: &str,
    x: DMatrix<f64>,
    y: &DVector<f64>,
) -> Result<DVector<f64>, FitError> {
    let (n, p) = x.shape();
    if n < p {
        return Err(FitError::too_few(what, format!("{p} observations"), n));
    }
    let f = Factors::new(x);
    check_rank(what, f.smax(), f.smin())?;
    f.solve(y, 0.0).map_err(|e| FitError::singular(what, e))
}

/// Coefficient of determination R² = 1 − RSS/Σ(y − ȳ)² (1 when y is constant and fitted exactly).
pub fn r_squared(y: &[f64], rss: f64) -> f64 {
    let n = y.len().max(1) as f64;
    let mean = y.iter().sum::<f64>() / n;
    let tss: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
    if tss > 0.0 {
        1.0 - rss / tss
    } else if rss <= 1e-24 {
        1.0
    } else {
        0.0
    }
}

/// A straight-line regression y = slope·x (+ intercept).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Regression {
    /// Slope.
    pub slope: f64,
    /// Standard error of the slope (`NaN` without residual dof).
    pub slope_se: f64,
    /// Intercept (0 for a fit through the origin).
    pub intercept: f64,
    /// Standard error of the intercept (`NaN` through the origin or without residual dof).
    pub intercept_se: f64,
    /// True when the intercept was fitted.
    pub with_intercept: bool,
    /// R² = 1 − RSS/Σ(y − ȳ)² (centred, also for the fit through the origin).
    pub r_squared: f64,
    /// Number of points.
    pub n: usize,
}

/// Least-squares line y = a + b·x (`with_intercept`) or y = b·x through the origin.
///
/// ```
/// use runout_core::fit::fit_line;
/// let r = fit_line(&[1.0, 2.0, 3.0], &[3.0, 5.0, 7.0], true).unwrap();
/// assert!((r.slope - 2.0).abs() < 1e-12 && (r.intercept - 1.0).abs() < 1e-12);
/// ```
pub fn fit_line(x: &[f64], y: &[f64], with_intercept: bool) -> Result<Regression, FitError> {
    if x.len() != y.len() {
        return Err(FitError::too_few(
            "line fit",
            format!("{} y values", x.len()),
            y.len(),
        ));
    }
    let p = if with_intercept { 2 } else { 1 };
    let design = DMatrix::from_fn(x.len(), p, |r, c| if c == 0 { x[r] } else { 1.0 });
    let fit = linear_lsq("line fit", &design, &DVector::from_column_slice(y))?;
    let se = |i: usize| {
        fit.covariance()
            .map(|c| c[(i, i)].sqrt())
            .unwrap_or(f64::NAN)
    };
    Ok(Regression {
        slope: fit.beta[0],
        slope_se: se(0),
        intercept: if with_intercept { fit.beta[1] } else { 0.0 },
        intercept_se: if with_intercept { se(1) } else { f64::NAN },
        with_intercept,
        r_squared: r_squared(y, fit.rss),
        n: x.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two ways to (XᵀX)⁻¹ agree to rounding on a well-conditioned design (κ ≈ 10):
    /// relative 1e-12 is ~10⁴ ulps, far above the κ²·ε ≈ 1e-14 expected difference.
    #[test]
    fn svd_and_normal_inverse_agree() {
        let x = DMatrix::from_fn(20, 3, |r, c| {
            ((r as f64) * 0.37 + c as f64).sin() + (c == 0) as u8 as f64
        });
        let lsq = LinearLsq::new(x);
        let a = lsq.xtx_inv();
        let b = lsq.normal_inverse().unwrap();
        assert!((a - &b).amax() <= 1e-12 * b.amax());
    }

    /// The SVD of X itself (the route before the QR reduction), as the reference.
    fn direct(x: &DMatrix<f64>, y: &DVector<f64>) -> (DVector<f64>, DVector<f64>, DMatrix<f64>) {
        let svd = x.clone().svd(true, true);
        let beta = svd.solve(y, 0.0).unwrap();
        let v_t = svd.v_t.clone().unwrap();
        let inv_s2 = DMatrix::from_diagonal(&svd.singular_values.map(|s| 1.0 / (s * s)));
        let xtx_inv = v_t.transpose() * inv_s2 * v_t;
        (beta, svd.singular_values, xtx_inv)
    }

    /// A tall design with condition number ≈ 10^`log_kappa`: columns scaled by powers of ten
    /// and mixed (the chain fit's designs mix N/mm² and N/mm columns, κ ~ 1e3).
    fn design(n: usize, p: usize, log_kappa: f64, seed: u64) -> DMatrix<f64> {
        let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let base = DMatrix::from_fn(n, p, |_, _| rnd());
        let scale = DMatrix::from_diagonal(&DVector::from_fn(p, |j, _| {
            10f64.powf(-log_kappa * j as f64 / (p - 1).max(1) as f64)
        }));
        let mix = DMatrix::from_fn(p, p, |i, j| if i == j { 1.0 } else { 0.3 * rnd() });
        base * scale * mix
    }

    proptest::proptest! {
        /// The QR-then-SVD route gives the tall SVD's β̂, singular values and (XᵀX)⁻¹: β̂ to
        /// 1e-9·κ relative, singular values to 1e-9 of s_max, (XᵀX)⁻¹ to 1e-9·κ² of its
        /// largest entry, for κ up to 1e5 (the fits' designs: κ ~ 1e0–1e3). The bound is set by
        /// the reference, not by the new route: nalgebra's SVD of the tall matrix itself was off
        /// by 1.2e-10·s_max in the smallest singular value of a graded design
        /// (`a_graded_design_matches_lapack`, κ 7e7), where a normwise backward-stable result is
        /// within ≈ 1e-14·s_max; beyond κ ≈ 1e7 its β̂ then differs from the QR route's by
        /// tens of percent, and only LAPACK can say which is right (the QR route, there).
        #[test]
        fn the_qr_route_equals_the_svd_of_x(
            n in 12usize..3000,
            p in 1usize..7,
            log_kappa in 0.0f64..5.0,
            seed in proptest::prelude::any::<u64>(),
        ) {
            proptest::prop_assume!(n >= 2 * p);
            let x = design(n, p, log_kappa, seed);
            let y = &x * DVector::from_fn(p, |j, _| 1.0 + j as f64)
                + DVector::from_fn(n, |i, _| ((i * 7919 % 101) as f64 - 50.0) * 1e-3);
            let lsq = LinearLsq::new(x.clone());
            proptest::prop_assert!(lsq.factors.qr.is_some());
            let fit = lsq.solve(&y, 0.0).unwrap();
            let (beta, sv, xtx_inv) = direct(&x, &y);
            let kappa = sv.max() / sv.min();
            proptest::prop_assert!(
                (&fit.beta - &beta).amax() <= 1e-9 * kappa * beta.amax(),
                "β {} vs {} (κ {kappa:.1e})", fit.beta, beta
            );
            let mut a: Vec<f64> = lsq.factors.svd.singular_values.iter().copied().collect();
            let mut b: Vec<f64> = sv.iter().copied().collect();
            a.sort_by(f64::total_cmp);
            b.sort_by(f64::total_cmp);
            for (u, v) in a.iter().zip(&b) {
                proptest::prop_assert!((u - v).abs() <= 1e-9 * sv.max(), "{u:e} {v:e} smax {:e}", sv.max());
            }
            proptest::prop_assert!(
                (fit.xtx_inv - &xtx_inv).amax() <= 1e-9 * kappa * kappa * xtx_inv.amax()
            );
            let beta_only = linear_lsq_beta("demo", x, &y).unwrap();
            proptest::prop_assert_eq!(beta_only, fit.beta);
        }
    }

    /// A graded design (κ ≈ 7e7, columns 10^0 … 10^-7.8) where the route matters: singular
    /// values against LAPACK (`numpy.linalg.svd` 2.x of the same matrix, built by `design` in
    /// Python; also `numpy.linalg.qr` then `svd` of R: the same digits). The QR route agrees to
    /// 1e-10 relative in every singular value, including the smallest; nalgebra 0.34's SVD of
    /// the tall matrix itself is 0.8 % off in the smallest (2.0864e-7), which is why the
    /// property test above cannot hold the routes closer than its bound.
    #[test]
    fn a_graded_design_matches_lapack() {
        let x = design(2380, 5, 7.824628366003778, 7525356199652450297);
        let lapack = [
            14.468260812758318,
            0.15695609108183142,
            0.0017576092832809445,
            1.9023796297458667e-05,
            2.069410308698708e-07,
        ];
        let lsq = LinearLsq::new(x.clone());
        let mut sv: Vec<f64> = lsq.factors.svd.singular_values.iter().copied().collect();
        sv.sort_by(|a, b| b.total_cmp(a));
        for (s, l) in sv.iter().zip(lapack) {
            assert!((s - l).abs() <= 1e-10 * l, "{s:e} vs LAPACK {l:e}");
        }
        // (as the old route called it, with U and V: without them nalgebra gets 2.06941e-7)
        let tall = x.svd(true, true).singular_values.min();
        assert!((tall - lapack[4]).abs() > 1e-3 * lapack[4], "{tall:e}");
    }

    /// The rank test sees a dependent column through R as it did through X (tall and square).
    #[test]
    fn rank_deficiency_is_seen_through_the_qr() {
        for n in [4, 40, 4000] {
            let x = DMatrix::from_fn(n, 3, |r, c| match c {
                0 => 1.0,
                1 => (r as f64 * 0.1).sin(),
                _ => 2.0 - 3.0 * (r as f64 * 0.1).sin(),
            });
            let e = linear_lsq_beta("demo fit", x, &DVector::zeros(n)).unwrap_err();
            assert!(e.to_string().contains("rank deficient"), "{n}: {e}");
        }
    }

    #[test]
    fn rank_deficient_is_an_error_naming_the_fit() {
        let x = DMatrix::from_fn(5, 2, |r, _| r as f64);
        let e = linear_lsq("demo fit", &x, &DVector::zeros(5)).unwrap_err();
        assert!(e
            .to_string()
            .starts_with("demo fit is singular: design matrix rank deficient"));
    }
}
