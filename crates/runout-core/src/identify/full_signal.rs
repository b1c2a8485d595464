//! Full-signal identification (beyond seed 003): non-linear least squares of the synchronously
//! averaged waveforms of all measured components of one or several recordings against the
//! mechanistic force model with runout (issue 3 item 7).
//!
//! Model: [`RevolutionModel`] — the same equations and discretisation as
//! [`crate::ForceModel::simulate`] with [`crate::ArcChip`]. Unknowns: the runout **vector**
//! e = (ρ cos λ, ρ sin λ) (no singularity at ρ = 0; fitted in µm), optionally the tilt vector τ
//! (µm/mm), and the cutting coefficients K_tc, K_rc, K_te, K_re (always) and K_ac, K_ae (only when an
//! F_z component is measured; otherwise fixed at 0 and reported as not identified). Several
//! recordings (e.g. different feeds) share all unknowns.
//!
//! Residuals r = (model − measured)/w with w the per-sample standard error when every component
//! carries one, else w = 1 N. Solver: Levenberg–Marquardt (`levenberg-marquardt` crate) with the
//! analytic Jacobian. Start: runout from the frequency-domain estimate (§4.7,
//! [`frequency_estimate`]) or the caller's guess (e.g. the sine fit), coefficients from the exact
//! linear least squares at that runout (the forces are linear in the coefficients).
//!
//! Uncertainty: Cov = s²·(JᵀJ)⁻¹ at the solution with s² = Σr²/(n − p) (the "scaled" covariance:
//! correct when the weights are right up to a common factor), standard errors from its diagonal,
//! ρ and λ by the delta method from Cov(e_x, e_y). The condition number is that of J with unit-norm
//! columns; above 1e8 the fit is flagged ill-conditioned. Averaged-waveform samples are treated
//! as independent (true for white measurement noise; coloured noise makes the SEs optimistic).

use super::error::IdentifyError;
use super::frequency::{frequency_estimate, FrequencyEstimate};
use super::lsq::linear_lsq;
use super::model::{coefficient_gradient, force_from_basis, runout_gradient, BasisSums, RevolutionModel};
use super::sine_fit::Estimate;
use super::waveform::{Axis, WaveformCase};
use crate::coefficients::CuttingCoefficients;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{storage::Owned, DMatrix, DVector, Dyn};
use serde::Serialize;

/// Options of [`full_signal_fit`].
#[derive(Debug, Clone, Default)]
pub struct FullSignalOptions {
    /// Axial disks of the model; `None` = automatic (helix lag ≤ 0.5° per disk, 1 for straight
    /// flutes, at least 8 when fitting tilt).
    pub disks: Option<usize>,
    /// Also fit the tilt vector τ.
    pub fit_tilt: bool,
    /// Start value of the runout vector e (mm); `None` = frequency-domain estimate.
    pub initial_runout: Option<[f64; 2]>,
}

/// Result of the full-signal fit. Offsets mm, angles rad, coefficients N/mm² and N/mm.
#[derive(Debug, Clone, Serialize)]
pub struct FullSignalFit {
    /// Runout offset ρ (mm).
    pub offset: Estimate,
    /// Runout angle λ (rad).
    pub angle: Estimate,
    /// Runout vector components e_x, e_y (mm).
    pub vector: [Estimate; 2],
    /// Tilt vector τ (mm/mm), when fitted.
    pub tilt: Option<[Estimate; 2]>,
    /// Fitted coefficients (K_ac, K_ae are 0 when no F_z was measured).
    pub coefficients: [f64; 6],
    /// Their standard errors (`None` = not identified / not fitted).
    pub coefficient_se: [Option<f64>; 6],
    /// Names of the fitted parameters, in the order of `correlation`.
    pub parameters: Vec<String>,
    /// Correlation matrix of the fitted parameters.
    pub correlation: Vec<Vec<f64>>,
    /// RMS of the unweighted residuals (N).
    pub residual_rms_n: f64,
    /// R² = 1 − RSS/TSS (unweighted, TSS about each component's mean).
    pub r_squared: f64,
    /// Condition number of the column-normalised Jacobian.
    pub condition: f64,
    /// True when the condition number exceeds 1e8.
    pub ill_conditioned: bool,
    /// Number of residuals n and residual degrees of freedom n − p.
    pub n: usize,
    /// Residual degrees of freedom.
    pub dof: usize,
    /// Model evaluations used by the solver.
    pub evaluations: usize,
    /// Solver termination reason.
    pub termination: String,
    /// The start value from the frequency-domain estimate, when used.
    pub initial: Option<FrequencyEstimate>,
    /// Axial disks used.
    pub disks: usize,
    /// Warnings (ill-conditioning, non-convergence, coefficients not identified).
    pub warnings: Vec<String>,
}

/// Which coefficient indices (into [K_tc, K_rc, K_ac, K_te, K_re, K_ae]) are fitted.
fn fitted_coefficients(cases: &[WaveformCase]) -> Vec<usize> {
    let has_z = cases
        .iter()
        .any(|c| c.waveform.components.iter().any(|k| k.axis == Axis::Z));
    if has_z {
        vec![0, 1, 2, 3, 4, 5]
    } else {
        vec![0, 1, 3, 4]
    }
}

/// Automatic disk count: helix lag a_p·tanβ/R per disk ≤ 0.5°.
fn auto_disks(cases: &[WaveformCase], tilt: bool) -> usize {
    let lag = cases
        .iter()
        .map(|c| (c.cut.ap() * c.cutter.tan_helix() / c.cutter.radius()).abs().to_degrees())
        .fold(0.0, f64::max);
    let d = (lag / 0.5).ceil().max(1.0) as usize;
    if tilt {
        d.max(8)
    } else {
        d
    }
    .min(400)
}

struct Problem<'a> {
    cases: &'a [WaveformCase],
    models: Vec<RevolutionModel>,
    coef_idx: Vec<usize>,
    fit_tilt: bool,
    /// Parameters: e (µm) [, τ (µm/mm)], coefficients.
    x: DVector<f64>,
    sums: Vec<BasisSums>,
    weights: bool,
}

impl Problem<'_> {
    fn n_runout(&self) -> usize {
        if self.fit_tilt {
            4
        } else {
            2
        }
    }
    fn runout(&self) -> ([f64; 2], [f64; 2]) {
        let e = [self.x[0] * 1e-3, self.x[1] * 1e-3];
        let t = if self.fit_tilt {
            [self.x[2] * 1e-3, self.x[3] * 1e-3]
        } else {
            [0.0, 0.0]
        };
        (e, t)
    }
    fn coefficients(&self) -> CuttingCoefficients {
        let mut a = [0.0; 6];
        let nr = self.n_runout();
        for (p, &i) in self.coef_idx.iter().enumerate() {
            a[i] = self.x[nr + p];
        }
        CuttingCoefficients::from_array(a)
    }
    fn weight(&self, c: usize, comp: usize, q: usize) -> f64 {
        if self.weights {
            self.cases[c].waveform.components[comp].se.as_ref().map(|s| s[q]).unwrap_or(1.0)
        } else {
            1.0
        }
    }
    fn recompute(&mut self) {
        let (e, t) = self.runout();
        let tilt = self.fit_tilt;
        self.sums = self.models.iter().map(|m| m.sums(e, t, tilt)).collect();
    }
    fn n_residuals(&self) -> usize {
        self.cases
            .iter()
            .map(|c| c.waveform.components.len() * c.waveform.samples())
            .sum()
    }
    /// Unweighted model − measured.
    fn raw_residuals(&self) -> Vec<f64> {
        let kc = self.coefficients();
        let mut r = Vec::with_capacity(self.n_residuals());
        for (c, case) in self.cases.iter().enumerate() {
            for comp in &case.waveform.components {
                for (q, v) in comp.values.iter().enumerate() {
                    r.push(force_from_basis(comp.axis, &self.sums[c].base[q], &kc) - v);
                }
            }
        }
        r
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.x.copy_from(x);
        self.recompute();
    }
    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }
    fn residuals(&self) -> Option<DVector<f64>> {
        let raw = self.raw_residuals();
        let mut i = 0;
        let mut out = DVector::zeros(raw.len());
        for (c, case) in self.cases.iter().enumerate() {
            for (k, comp) in case.waveform.components.iter().enumerate() {
                for q in 0..comp.values.len() {
                    out[i] = raw[i] / self.weight(c, k, q);
                    i += 1;
                }
            }
        }
        out.iter().all(|v| v.is_finite()).then_some(out)
    }
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let kc = self.coefficients();
        let nr = self.n_runout();
        let np = self.x.len();
        let mut j = DMatrix::zeros(self.n_residuals(), np);
        let mut row = 0;
        for (c, case) in self.cases.iter().enumerate() {
            let s = &self.sums[c];
            for (k, comp) in case.waveform.components.iter().enumerate() {
                for q in 0..comp.values.len() {
                    let w = self.weight(c, k, q);
                    for p in 0..nr {
                        // e in µm, τ in µm/mm: derivative per mm × 1e-3
                        j[(row, p)] = runout_gradient(comp.axis, &s.deriv[q][p], &kc) * 1e-3 / w;
                    }
                    let g = coefficient_gradient(comp.axis, &s.base[q]);
                    for (p, &i) in self.coef_idx.iter().enumerate() {
                        j[(row, nr + p)] = g[i] / w;
                    }
                    row += 1;
                }
            }
        }
        Some(j)
    }
}

/// Linear least squares of the coefficients at the problem's current runout.
fn linear_coefficients(p: &mut Problem<'_>) -> Result<(), IdentifyError> {
    let nr = p.n_runout();
    let ncoef = p.coef_idx.len();
    for v in p.x.iter_mut().skip(nr) {
        *v = 0.0;
    }
    p.recompute();
    let jac = p.jacobian().expect("jacobian");
    let x = jac.columns(nr, ncoef).into_owned();
    // residuals at zero coefficients = −measured/w
    let y = -p.residuals().ok_or_else(|| IdentifyError::singular("full-signal fit", "non-finite data"))?;
    let fit = linear_lsq("coefficient start values", &x, &y)?;
    for c in 0..ncoef {
        p.x[nr + c] = fit.beta[c];
    }
    p.recompute();
    Ok(())
}

const NAMES: [&str; 6] = ["ktc", "krc", "kac", "kte", "kre", "kae"];

/// Identify runout (and tilt) and the cutting coefficients from averaged waveforms.
pub fn full_signal_fit(
    cases: &[WaveformCase],
    options: &FullSignalOptions,
) -> Result<FullSignalFit, IdentifyError> {
    if cases.is_empty() {
        return Err(IdentifyError::too_few("full-signal fit", "1 recording", 0));
    }
    for c in cases {
        c.waveform.validate()?;
    }
    let weights = cases
        .iter()
        .all(|c| c.waveform.components.iter().all(|k| k.se.is_some()));
    let disks = options.disks.unwrap_or_else(|| auto_disks(cases, options.fit_tilt)).max(1);
    let coef_idx = fitted_coefficients(cases);
    let nr = if options.fit_tilt { 4 } else { 2 };
    let np = nr + coef_idx.len();
    let models: Vec<RevolutionModel> = cases
        .iter()
        .map(|c| {
            RevolutionModel::new(&c.cutter, &c.cut, c.waveform.start_angle, c.waveform.samples(), disks)
        })
        .collect();
    let mut problem = Problem {
        cases,
        models,
        coef_idx: coef_idx.clone(),
        fit_tilt: options.fit_tilt,
        x: DVector::zeros(np),
        sums: Vec::new(),
        weights,
    };
    let n = problem.n_residuals();
    if n <= np {
        return Err(IdentifyError::too_few("full-signal fit", format!("more than {np} samples"), n));
    }
    // Start values.
    let mut initial = None;
    if let Some(e) = options.initial_runout {
        problem.x[0] = e[0] * 1e3;
        problem.x[1] = e[1] * 1e3;
        linear_coefficients(&mut problem)?;
    } else {
        linear_coefficients(&mut problem)?;
        if let Ok(f) = frequency_estimate(cases, &problem.coefficients(), disks) {
            problem.x[0] = f.vector[0] * 1e3;
            problem.x[1] = f.vector[1] * 1e3;
            initial = Some(f);
            linear_coefficients(&mut problem)?;
        }
    }
    let (mut problem, report) = LevenbergMarquardt::new()
        .with_patience(200)
        .minimize(problem);
    problem.recompute();
    let jac = problem
        .jacobian()
        .ok_or_else(|| IdentifyError::singular("full-signal fit", "Jacobian"))?;
    let res = problem
        .residuals()
        .ok_or_else(|| IdentifyError::singular("full-signal fit", "non-finite residuals"))?;
    let raw = problem.raw_residuals();
    let rss_w = res.norm_squared();
    let dof = n - np;
    let s2 = rss_w / dof as f64;

    // Condition number of the column-normalised Jacobian, and the covariance.
    let norms: Vec<f64> = (0..np).map(|c| jac.column(c).norm().max(f64::MIN_POSITIVE)).collect();
    let jn = DMatrix::from_fn(n, np, |r, c| jac[(r, c)] / norms[c]);
    let svd = jn.svd(false, true);
    let (smax, smin) = (svd.singular_values.max(), svd.singular_values.min());
    let condition = if smin > 0.0 { smax / smin } else { f64::INFINITY };
    let v_t = svd.v_t.as_ref().expect("V computed");
    let inv = DMatrix::from_diagonal(&svd.singular_values.map(|s| if s > 0.0 { 1.0 / (s * s) } else { f64::INFINITY }));
    let cov_n = v_t.transpose() * inv * v_t;
    let cov = DMatrix::from_fn(np, np, |r, c| cov_n[(r, c)] * s2 / (norms[r] * norms[c]));
    let se = |i: usize| cov[(i, i)].max(0.0).sqrt();
    let correlation: Vec<Vec<f64>> = (0..np)
        .map(|r| (0..np).map(|c| cov[(r, c)] / (se(r) * se(c))).collect())
        .collect();

    // Runout in mm with delta-method ρ, λ.
    let (ex, ey) = (problem.x[0] * 1e-3, problem.x[1] * 1e-3);
    let cov_e = [
        [cov[(0, 0)] * 1e-6, cov[(0, 1)] * 1e-6],
        [cov[(1, 0)] * 1e-6, cov[(1, 1)] * 1e-6],
    ];
    let rho = ex.hypot(ey);
    let quad = |g: [f64; 2]| {
        (g[0] * g[0] * cov_e[0][0] + 2.0 * g[0] * g[1] * cov_e[0][1] + g[1] * g[1] * cov_e[1][1])
            .max(0.0)
            .sqrt()
    };
    let (g_rho, g_lam) = if rho > 0.0 {
        ([ex / rho, ey / rho], [-ey / (rho * rho), ex / (rho * rho)])
    } else {
        ([f64::NAN; 2], [f64::NAN; 2])
    };
    let mut coefficients = [0.0; 6];
    let mut coefficient_se = [None; 6];
    for (p, &i) in coef_idx.iter().enumerate() {
        coefficients[i] = problem.x[nr + p];
        coefficient_se[i] = Some(se(nr + p));
    }
    let mut parameters = vec!["ex_um".to_string(), "ey_um".to_string()];
    if options.fit_tilt {
        parameters.extend(["tilt_x_um_per_mm".to_string(), "tilt_y_um_per_mm".to_string()]);
    }
    parameters.extend(coef_idx.iter().map(|&i| NAMES[i].to_string()));

    // R² about each component's mean, unweighted.
    let mut tss = 0.0;
    for case in cases {
        for comp in &case.waveform.components {
            let m = comp.values.iter().sum::<f64>() / comp.values.len() as f64;
            tss += comp.values.iter().map(|v| (v - m).powi(2)).sum::<f64>();
        }
    }
    let rss: f64 = raw.iter().map(|r| r * r).sum();
    let ill = !(condition < 1e8);
    let mut warnings = Vec::new();
    if ill {
        warnings.push(format!(
            "ill-conditioned fit (condition number {condition:.3e}): the parameters are not separately identifiable from these recordings (see the correlation matrix); add feeds or components"
        ));
    }
    if !report.termination.was_successful() {
        warnings.push(format!("solver did not converge: {:?}", report.termination));
    }
    if coef_idx.len() < 6 {
        warnings.push("no F_z measured: K_ac and K_ae not identified (fixed at 0)".into());
    }
    Ok(FullSignalFit {
        offset: Estimate { value: rho, se: Some(quad(g_rho)) },
        angle: Estimate { value: ey.atan2(ex), se: Some(quad(g_lam)) },
        vector: [
            Estimate { value: ex, se: Some(cov_e[0][0].max(0.0).sqrt()) },
            Estimate { value: ey, se: Some(cov_e[1][1].max(0.0).sqrt()) },
        ],
        tilt: options.fit_tilt.then(|| {
            [
                Estimate { value: problem.x[2] * 1e-3, se: Some(se(2) * 1e-3) },
                Estimate { value: problem.x[3] * 1e-3, se: Some(se(3) * 1e-3) },
            ]
        }),
        coefficients,
        coefficient_se,
        parameters,
        correlation,
        residual_rms_n: (rss / n as f64).sqrt(),
        r_squared: if tss > 0.0 { 1.0 - rss / tss } else { f64::NAN },
        condition,
        ill_conditioned: ill,
        n,
        dof,
        evaluations: report.number_of_evaluations,
        termination: format!("{:?}", report.termination),
        initial,
        disks,
        warnings,
    })
}
