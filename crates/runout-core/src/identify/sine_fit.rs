//! Seed 003 per-tooth peak sine fit, methods.md §4.2 eq. (10)–(12).
//!
//! The peaks F_i (i = 0..K−1, teeth in cutting order) are fitted by the **linear** least squares
//! F_i = C + a·sin(2πi/K) + b·cos(2πi/K), i.e. F_i = C + A·sin(φ + 2πi/K) with A = hypot(a, b),
//! φ = atan2(b, a). Then
//!
//! ρ = (A / C)·f_z·sin γ / (2·sin(π/K))      (eq. 12)
//! λ = φ − π + π/K                            (`conventions.md`; seed 003's α₀ = λ)
//!
//! γ is the immersion angle at which every tooth peaks (all teeth assumed to peak at the same angle,
//! R ≫ ρ): the angle of largest chip thickness f_z·sin φ in [φ_st, φ_ex].
//!
//! Two fitting hypotheses ([`SineHypothesis`]): `Teeth` (H0, the K peaks, each once — the plain
//! least-squares fit) and `ClosedPeriod` (H1, K + 1 points with F_K = F₀ — the period closed, as
//! the seed's Fig. 5 presumably plots it). **H1 reproduces the seed's Table 2 to its printed
//! rounding** (methods.md §4.3); H0 weights every tooth equally and differs by ≤ 0.45 N, 0.8 N, 0.3°.
//!
//! Standard errors: both estimators are linear in the peaks, β̂ = (C, a, b) = L·F, so
//! Cov(β̂) = L·Σ_F·Lᵀ with Σ_F = diag(se_i²) when per-tooth standard errors are given
//! (revolution-to-revolution scatter), otherwise Σ_F = σ̂²·I with σ̂² = RSS₀/(K − 3) from the H0
//! residuals (K − 3 residual degrees of freedom; the duplicated point of H1 is not an independent
//! observation). A, φ, ρ and λ get their standard errors by the **delta method** (first-order
//! propagation of Cov(C, a, b)). K = 3 without per-tooth errors: exactly determined, no residual
//! dof, hence no standard errors (reported as `None`). K = 2: degenerate, see
//! [`IdentifyError::DegenerateTwoTeeth`].

use super::error::IdentifyError;
use crate::cut::Cut;
use crate::cutter::Cutter;
use crate::error::{positive, ParamError};
use crate::fit::{linear_lsq, r_squared};
use crate::force::ToothPeak;
use crate::runout::seed::lambda_from_seed003_phase;
use nalgebra::{DMatrix, DVector, Matrix3};
use serde::Serialize;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Per-tooth peak forces F_i (N), teeth `0..K-1` in cutting order, with optional standard errors.
#[derive(Debug, Clone, PartialEq)]
pub struct ToothPeaks {
    values: Vec<f64>,
    se: Option<Vec<f64>>,
}

impl ToothPeaks {
    /// Peaks in N, one per tooth in cutting order (K ≥ 2, finite).
    pub fn new(values_n: Vec<f64>) -> Result<Self, ParamError> {
        if values_n.len() < 2 {
            return Err(ParamError::new(
                "peaks_N",
                "one peak per tooth, at least 2",
                format!("{} value(s)", values_n.len()),
            ));
        }
        for (i, v) in values_n.iter().enumerate() {
            if !v.is_finite() {
                return Err(ParamError::new(
                    format!("peaks_N[{i}]"),
                    "a finite force (N)",
                    v,
                ));
            }
            // peak forces are magnitudes: a negative one would give a negative runout offset
            if *v < 0.0 {
                return Err(ParamError::new(
                    format!("peaks_N[{i}]"),
                    "a peak force >= 0 N (peaks are magnitudes, the largest force of each tooth)",
                    v,
                ));
            }
        }
        if values_n.iter().all(|v| *v == 0.0) {
            return Err(ParamError::new(
                "peaks_N",
                "peaks that are positive (at least one tooth > 0 N): all zero gives no runout",
                "all 0",
            ));
        }
        Ok(ToothPeaks {
            values: values_n,
            se: None,
        })
    }

    /// Attach per-tooth standard errors (N, > 0), e.g. the revolution-to-revolution scatter of
    /// each peak divided by √(revolutions).
    pub fn with_se(mut self, se_n: Vec<f64>) -> Result<Self, ParamError> {
        if se_n.len() != self.values.len() {
            return Err(ParamError::new(
                "peaks_se_N",
                format!("{} standard errors (one per tooth)", self.values.len()),
                format!("{} value(s)", se_n.len()),
            ));
        }
        for (i, s) in se_n.iter().enumerate() {
            positive(&format!("peaks_se_N[{i}]"), *s)?;
        }
        self.se = Some(se_n);
        Ok(self)
    }

    /// The peaks of a simulated or measured [`ToothPeak`] table (|F_xy| peaks).
    pub fn from_tooth_peaks(peaks: &[ToothPeak]) -> Result<Self, ParamError> {
        Self::new(peaks.iter().map(|p| p.peak_fxy).collect())
    }

    /// Number of teeth K.
    pub fn teeth(&self) -> usize {
        self.values.len()
    }
    /// The peaks (N).
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// Their standard errors (N), if given.
    pub fn se(&self) -> Option<&[f64]> {
        self.se.as_deref()
    }
}

/// Feed and peak angle that convert the fitted ratio A/C into an offset (eq. 12).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PeakConditions {
    /// Feed per tooth f_z (mm).
    pub fz_mm: f64,
    /// sin γ, γ = immersion angle of the per-tooth peak.
    pub sin_gamma: f64,
}

impl PeakConditions {
    /// From the feed per tooth (mm) and the peak immersion angle γ (rad).
    pub fn new(fz_mm: f64, peak_immersion_rad: f64) -> Result<Self, ParamError> {
        positive("fz_mm", fz_mm)?;
        let s = peak_immersion_rad.sin();
        if s.is_nan() || s <= 1e-6 {
            return Err(ParamError::new(
                "peak_immersion_deg",
                "an immersion angle with sin γ > 0 (0 < γ < 180°)",
                peak_immersion_rad.to_degrees(),
            ));
        }
        Ok(PeakConditions {
            fz_mm,
            sin_gamma: s,
        })
    }

    /// For a cut: γ = the immersion angle of largest f_z·sin φ in [φ_st, φ_ex], i.e. the exit
    /// angle arccos(1 − a_e/R) in up-milling with a_e ≤ R (the seed's β), the entry angle in
    /// down-milling with a_e ≤ R, and 90° in slotting or when a_e > R.
    ///
    /// ```
    /// use runout_core::{identify::PeakConditions, Cut, Cutter, MillingMode};
    /// let c = Cutter::flat(10.0, 4, 0.0).unwrap();
    /// let cut = Cut::new(3240.0, 0.08, 1.0).unwrap().radial(2.0, MillingMode::Up, &c).unwrap();
    /// let p = PeakConditions::from_cut(&c, &cut).unwrap();
    /// assert!((p.sin_gamma - 0.8).abs() < 1e-12); // β = arccos(3/5) = 53.13°
    /// ```
    pub fn from_cut(cutter: &Cutter, cut: &Cut) -> Result<Self, ParamError> {
        Self::new(cut.fz(), peak_immersion(cutter, cut))
    }
}

/// Immersion angle (rad) of the largest sin φ in [φ_st, φ_ex] (within one turn).
pub fn peak_immersion(cutter: &Cutter, cut: &Cut) -> f64 {
    let (st, ex) = cut.immersion(cutter);
    if st <= FRAC_PI_2 && ex >= FRAC_PI_2 {
        FRAC_PI_2
    } else if st.sin() >= ex.sin() {
        st
    } else {
        ex
    }
}

/// Which points the sine is fitted to (methods.md §4.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SineHypothesis {
    /// H0: the K peaks, each once (plain least squares; the default).
    #[default]
    Teeth,
    /// H1: K + 1 points with F_K = F₀ (period closed) — reproduces the seed's Table 2.
    ClosedPeriod,
}

pub use crate::estimate::Estimate;

/// Where the standard errors of a sine fit come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorSource {
    /// From the given per-tooth standard errors.
    PerToothSe,
    /// From the fit residuals, σ̂² = RSS/(K − 3).
    Residuals,
    /// None available (K = 3 without per-tooth errors: exactly determined).
    Unavailable,
}

/// Result of the per-tooth peak sine fit (eq. 10–12). Angles in rad, offset in mm.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SineFit {
    /// Number of teeth K.
    pub teeth: usize,
    /// Fitting hypothesis used.
    pub hypothesis: SineHypothesis,
    /// Mean C (N).
    pub mean: Estimate,
    /// Amplitude A (N).
    pub amplitude: Estimate,
    /// Phase φ (rad, in [0, 2π)).
    pub phase: Estimate,
    /// Runout offset ρ (mm), eq. (12).
    pub offset: Estimate,
    /// Runout angle λ = φ − π + π/K (rad, in (−π, π]).
    pub angle: Estimate,
    /// R² of the fitted points (K points under H0, K + 1 under H1).
    pub r_squared: f64,
    /// Residual degrees of freedom K − 3.
    pub dof: usize,
    /// Residual RMS over the teeth (N).
    pub residual_rms: f64,
    /// Fitted value per tooth (N).
    pub fitted: Vec<f64>,
    /// Where the standard errors come from.
    pub error_source: ErrorSource,
    /// The conditions used for eq. (12).
    pub conditions: PeakConditions,
    /// Notes on validity (edge skipping, exact determination…).
    pub warnings: Vec<String>,
}

/// K = 2 (issue 11 item 4): two peaks cannot give λ, but they give how unevenly the teeth cut —
/// the radius difference R₀ − R₁ (mm) — with the proportional-peak model behind eq. (12): at
/// the peak immersion γ, h₀,₁ = f_z·sin γ ± (R₀ − R₁) and F_i = C·h_i, so
///
/// R₀ − R₁ = f_z·sin γ·(F₀ − F₁)/(F₀ + F₁),
///
/// with its SE by the delta method from the per-tooth SEs (∂/∂F₀ = 2g·F₁/S², ∂/∂F₁ = −2g·F₀/S²,
/// g = f_z sin γ, S = F₀ + F₁). Edge forces (a constant per tooth) bias it towards 0 as they bias
/// the sine fit; it saturates at ±f_z·sin γ where the smaller tooth stops cutting.
///
/// ```
/// use runout_core::identify::{radius_difference, PeakConditions, ToothPeaks};
/// let peaks = ToothPeaks::new(vec![330.0, 270.0]).unwrap().with_se(vec![2.0, 2.0]).unwrap();
/// let d = radius_difference(&peaks, &PeakConditions { fz_mm: 0.1, sin_gamma: 1.0 }).unwrap();
/// assert!((d.value - 0.01).abs() < 1e-12); // 10 µm
/// assert!(d.se.unwrap() > 0.0);
/// ```
pub fn radius_difference(
    peaks: &ToothPeaks,
    conditions: &PeakConditions,
) -> Result<Estimate, IdentifyError> {
    let f = peaks.values();
    if f.len() != 2 {
        return Err(IdentifyError::too_few(
            "radius difference",
            "exactly 2 teeth",
            f.len(),
        ));
    }
    let g = conditions.fz_mm * conditions.sin_gamma;
    let sum = f[0] + f[1];
    if sum.is_nan() || sum <= 0.0 || f[0] <= 0.0 || f[1] <= 0.0 {
        return Err(IdentifyError::singular(
            "radius difference",
            format!("the peaks must be positive, got {} and {} N", f[0], f[1]),
        ));
    }
    let value = g * (f[0] - f[1]) / sum;
    let se = peaks.se().map(|se| {
        let d0 = 2.0 * g * f[1] / (sum * sum);
        let d1 = -2.0 * g * f[0] / (sum * sum);
        (d0 * d0 * se[0] * se[0] + d1 * d1 * se[1] * se[1]).sqrt()
    });
    Ok(Estimate { value, se })
}

/// Fit F_i = C + A·sin(φ + 2πi/K) to per-tooth peaks and convert to runout (eq. 10–12).
///
/// ```
/// use runout_core::identify::{sine_fit, PeakConditions, SineHypothesis, ToothPeaks};
/// // seed 003 Table 1 test 1 (methods.md §7): C 314.96, A 53.60, φ 100.05°, ρ 7.70 µm, α₀ −34.95°
/// let peaks = ToothPeaks::new(vec![366.6, 307.9, 259.9, 326.6]).unwrap();
/// let cond = PeakConditions { fz_mm: 0.08, sin_gamma: 0.8 };
/// let f = sine_fit(&peaks, &cond, SineHypothesis::ClosedPeriod).unwrap();
/// assert!((f.mean.value - 314.96).abs() < 0.005 && (f.amplitude.value - 53.60).abs() < 0.005);
/// assert!((f.phase.value.to_degrees() - 100.05).abs() < 0.005);
/// assert!((f.offset.value * 1e3 - 7.70).abs() < 0.005);
/// assert!((f.angle.value.to_degrees() + 34.95).abs() < 0.005);
/// ```
pub fn sine_fit(
    peaks: &ToothPeaks,
    conditions: &PeakConditions,
    hypothesis: SineHypothesis,
) -> Result<SineFit, IdentifyError> {
    let k = peaks.teeth();
    let f = peaks.values();
    if k == 2 {
        return Err(IdentifyError::DegenerateTwoTeeth {
            mean_n: 0.5 * (f[0] + f[1]),
            a_sin_phi_n: 0.5 * (f[0] - f[1]),
        });
    }
    let kf = k as f64;
    let design = |n: usize| {
        DMatrix::from_fn(n, 3, |i, c| {
            let t = TAU * i as f64 / kf;
            [1.0, t.sin(), t.cos()][c]
        })
    };
    // H0 fit: residual variance and the fitted values.
    let x0 = design(k);
    let fit0 = linear_lsq("sine fit", &x0, &DVector::from_column_slice(f))?;
    // Linear estimator β̂ = L·F for the chosen hypothesis.
    let l = match hypothesis {
        SineHypothesis::Teeth => &fit0.xtx_inv * x0.transpose(),
        SineHypothesis::ClosedPeriod => {
            let x1 = design(k + 1);
            let m = DMatrix::from_fn(k + 1, k, |r, c| if r % k == c { 1.0 } else { 0.0 });
            let xtx_inv = (x1.transpose() * &x1)
                .try_inverse()
                .ok_or_else(|| IdentifyError::singular("sine fit", "closed-period design"))?;
            xtx_inv * x1.transpose() * m
        }
    };
    let y = DVector::from_column_slice(f);
    let beta = &l * &y;
    let (c, a, b) = (beta[0], beta[1], beta[2]);

    let (cov, error_source) = match (peaks.se(), fit0.sigma2()) {
        (Some(se), _) => {
            let sigma =
                DMatrix::from_diagonal(&DVector::from_iterator(k, se.iter().map(|s| s * s)));
            (Some(&l * sigma * l.transpose()), ErrorSource::PerToothSe)
        }
        (None, Some(s2)) => (Some(&l * l.transpose() * s2), ErrorSource::Residuals),
        (None, None) => (None, ErrorSource::Unavailable),
    };
    let cov3: Option<Matrix3<f64>> = cov.map(|m| Matrix3::from_fn(|r, q| m[(r, q)]));

    let amp = a.hypot(b);
    let phase = crate::angle::wrap_tau(b.atan2(a));
    let g = conditions.fz_mm * conditions.sin_gamma / (2.0 * (PI / kf).sin());
    let rho = amp / c * g;
    let lambda = lambda_from_seed003_phase(phase, k);

    // Delta method: gradients w.r.t. (C, a, b).
    let grad_a = [0.0, a / amp, b / amp];
    let grad_phi = [0.0, -b / (amp * amp), a / (amp * amp)];
    let grad_rho = [-amp * g / (c * c), g / c * a / amp, g / c * b / amp];
    let se_of = |grad: [f64; 3]| {
        cov3.map(|m| {
            let v = nalgebra::Vector3::from(grad);
            (v.transpose() * m * v)[0].max(0.0).sqrt()
        })
    };

    let fitted: Vec<f64> = (0..k)
        .map(|i| c + amp * (phase + TAU * i as f64 / kf).sin())
        .collect();
    let r2 = match hypothesis {
        SineHypothesis::Teeth => r_squared(f, fit0.rss),
        SineHypothesis::ClosedPeriod => {
            let y5: Vec<f64> = (0..=k).map(|i| f[i % k]).collect();
            let rss: f64 = y5
                .iter()
                .enumerate()
                .map(|(i, v)| (v - fitted[i % k]).powi(2))
                .sum();
            r_squared(&y5, rss)
        }
    };
    let rss_teeth: f64 = f.iter().zip(&fitted).map(|(v, p)| (v - p).powi(2)).sum();

    if !(rho.is_finite() && c.is_finite() && amp.is_finite()) {
        return Err(IdentifyError::Singular {
            what: "the per-tooth sine fit".into(),
            reason: format!(
                "the peaks give no finite runout (mean C = {c:e} N, amplitude A = {amp:e} N); \
                 check the peak forces (N) and f_z"
            ),
        });
    }
    let mut warnings = Vec::new();
    if k == 3 {
        warnings.push(
            "K = 3: the sine has 3 unknowns and 3 peaks — exactly determined, R² ≡ 1, no residual \
             degrees of freedom"
                .to_string(),
        );
    }
    if error_source == ErrorSource::Unavailable {
        warnings.push(
            "no standard errors: no residual degrees of freedom and no per-tooth standard errors \
             given"
                .to_string(),
        );
    }
    if amp >= c {
        warnings.push(format!(
            "A = {amp:.2} N ≥ C = {c:.2} N: some teeth do not cut (edge skipping); eq. (12) does \
             not hold — use the full-signal identification"
        ));
    }
    Ok(SineFit {
        teeth: k,
        hypothesis,
        mean: Estimate::new(c, se_of([1.0, 0.0, 0.0])),
        amplitude: Estimate::new(amp, se_of(grad_a)),
        phase: Estimate::new(phase, se_of(grad_phi)),
        offset: Estimate::new(rho, se_of(grad_rho)),
        angle: Estimate::new(lambda, se_of(grad_phi)),
        r_squared: r2,
        dof: k.saturating_sub(3),
        residual_rms: (rss_teeth / kf).sqrt(),
        fitted,
        error_source,
        conditions: *conditions,
        warnings,
    })
}

impl SineFit {
    /// Offset ρ (mm) with the mean C corrected for an edge (ploughing) force `edge_n` (N) that
    /// does not depend on the chip: ρ = A/(C − C_edge)·f_z sin γ/(2 sin(π/K)) — the seed's
    /// modified eq. (12) with C′ (methods.md §4.6). `edge_n` from a regression of C on f_z·a_p
    /// (its intercept) or from the pooled fit (C₀ + E·a_p).
    ///
    /// ```
    /// use runout_core::identify::{sine_fit, PeakConditions, SineHypothesis, ToothPeaks};
    /// let p = ToothPeaks::new(vec![366.6, 307.9, 259.9, 326.6]).unwrap();
    /// let f = sine_fit(&p, &PeakConditions { fz_mm: 0.08, sin_gamma: 0.8 }, SineHypothesis::ClosedPeriod).unwrap();
    /// // methods.md §4.6: C − 32.7 N → 8.59 µm (test 1)
    /// assert!((f.edge_corrected_offset(32.7) * 1e3 - 8.59).abs() < 0.01);
    /// ```
    pub fn edge_corrected_offset(&self, edge_n: f64) -> f64 {
        let g = self.conditions.fz_mm * self.conditions.sin_gamma
            / (2.0 * (PI / self.teeth as f64).sin());
        self.amplitude.value / (self.mean.value - edge_n) * g
    }
}
