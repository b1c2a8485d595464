//! Identification of (ρ, λ) from per-tooth readings, methods.md §1.5.
//!
//! Model (methods.md eq. 0.1 = seed eq. 2 in our numbering): the reading of tooth i, converted to a
//! radial position, is P_i = c + R_i(e), R_i(e) = |R(z)·u(ψ_i(z)) + e|, with an unknown common
//! constant c (sensor zero). Only radius differences carry information (seed eq. 8).
//!
//! * K ≥ 3, [`ToothMethod::Joint`]: linear first-order start (§1.5 step 1), then
//!   Levenberg–Marquardt on (c, e_x, e_y) (the `levenberg-marquardt` crate, a MINPACK port: well
//!   kept, and its trust region copes with a start far from the optimum should the first-order
//!   start be poor). The vector parametrisation e = ρ·(cos λ, sin λ) is the same model as (ρ, λ)
//!   but stays regular at ρ → 0; ρ, λ and their standard errors follow from e and its covariance.
//!   Fitting the positions with the constant c is equivalent to fitting the K cyclic differences
//!   ΔR_i (§1.5 "Equations") but gives independent residuals and hence exact standard errors.
//! * K = 2: the closed form of seed eq. (4) (§1.5 step 2) with ρ known; ±λ are both reported unless
//!   a spindle phase resolves the mirror ambiguity.
//! * [`ToothMethod::SeedScan`]: the seed's iterative scan (§1.5 step 3) with ρ known: λ on a 1° grid
//!   minimising J(λ) = Σ (ΔR_i^model − ΔR_i^meas)², refined by 1-D Gauss–Newton to |Δλ| < 1e−6 rad.

use super::beam::BeamGeometry;
use super::error::DisplacementError;
use super::estimate::{polar_with_covariance, AngleEstimate, NoiseSource};
use super::readings::ToothReadings;
use crate::angle::wrap_pi;
use crate::cutter::Cutter;
use crate::fit::LinearLsq;
use crate::runout::Runout;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{storage::Owned, DMatrix, DVector, Dyn, Matrix2, Matrix3, OMatrix, Vector3, U3};
use serde::Serialize;
use std::f64::consts::PI;

/// Which identification algorithm to use for per-tooth readings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ToothMethod {
    /// K ≥ 3: joint least squares on (ρ, λ); K = 2: closed form (methods.md §1.5 steps 1, 2, 4).
    #[default]
    Joint,
    /// The seed's 1° scan of λ with ρ known, refined by Gauss–Newton (§1.5 step 3).
    SeedScan,
}

/// Inputs of [`identify_from_teeth`] besides the readings.
#[derive(Debug, Clone)]
pub struct ToothFitOptions {
    /// The cutter (K teeth, pitch, helix, nominal radius).
    pub cutter: Cutter,
    /// Height z (mm from the tip) at which the tooth tips were read.
    pub height_mm: f64,
    /// Algorithm.
    pub method: ToothMethod,
    /// Runout length ρ (mm) at this height from the height regression; required for K = 2 and
    /// for [`ToothMethod::SeedScan`], a consistency check otherwise.
    pub known_offset_mm: Option<f64>,
    /// Standard error of `known_offset_mm` (mm), propagated into σ_λ for K = 2.
    pub known_offset_se_mm: Option<f64>,
    /// Standard deviation σ_P of one reading (mm), when known from the sensor.
    pub noise_mm: Option<f64>,
    /// Beam inclination / lateral offset correction (methods.md §1.4).
    pub beam: BeamGeometry,
    /// Approximate direction of the runout (rad, spindle frame), e.g. from the spindle angle of
    /// the maximum reading; resolves the ±λ ambiguity of K = 2.
    pub phase_hint_rad: Option<f64>,
}

impl ToothFitOptions {
    /// Defaults for `cutter`: readings at the tip, joint method, no extra information.
    pub fn new(cutter: Cutter) -> Self {
        ToothFitOptions {
            cutter,
            height_mm: 0.0,
            method: ToothMethod::Joint,
            known_offset_mm: None,
            known_offset_se_mm: None,
            noise_mm: None,
            beam: BeamGeometry::ideal(),
            phase_hint_rad: None,
        }
    }
}

/// Result of [`identify_from_teeth`].
#[derive(Debug, Clone, Serialize)]
pub struct ToothFit {
    /// Algorithm used.
    pub method: ToothMethod,
    /// Runout length ρ (mm).
    pub offset_mm: f64,
    /// Standard error of ρ (mm); `None` without a noise estimate or when ρ was given.
    pub offset_se_mm: Option<f64>,
    /// Runout angle λ (rad) or why it is not determined.
    pub angle: AngleEstimate,
    /// Corrected radial positions P_i (mm, mean over repeats, beam-corrected).
    pub positions_mm: Vec<f64>,
    /// Measured radius differences ΔR_i = P_i − P_{i+1} (mm).
    pub radius_differences_mm: Vec<f64>,
    /// RMS of the residuals P_i − c − R_i (mm); for K ≥ 4 it estimates tooth form errors.
    pub residual_rms_mm: f64,
    /// Degrees of freedom of the residual.
    pub dof: usize,
    /// Noise σ_P of one reading (mm) used for the standard errors.
    pub noise_mm: Option<f64>,
    /// Where `noise_mm` came from.
    pub noise_source: NoiseSource,
    /// Condition number of the normal matrix JᵀJ of the joint fit (K ≥ 3).
    pub condition_number: Option<f64>,
    /// Beam correction factor applied to the readings (methods.md §1.4).
    pub beam_factor: f64,
    /// Warnings (inconsistencies clamped, consistency check failed…).
    pub notes: Vec<String>,
}

impl ToothFit {
    /// The identified runout when λ is determined.
    pub fn runout(&self) -> Option<Runout> {
        let l = self.angle.angle()?;
        Runout::new(self.offset_mm, l).ok()
    }
}

/// Identify (ρ, λ) from per-tooth readings (methods.md §1.5).
///
/// ```
/// use runout_core::{Cutter, Runout};
/// use runout_core::displacement::*;
/// let cutter = Cutter::flat(0.5, 3, 0.0).unwrap();
/// let truth = Runout::new(0.005, 40f64.to_radians()).unwrap();
/// let p: Vec<f64> = (0..3).map(|i| truth.tooth_radius(&cutter, i, 0.0)).collect();
/// let readings = ToothReadings::from_values(&p, SensorSign::Radial).unwrap();
/// let fit = identify_from_teeth(&readings, &ToothFitOptions::new(cutter)).unwrap();
/// assert!((fit.offset_mm - 0.005).abs() < 1e-12);
/// assert!((fit.angle.angle().unwrap().to_degrees() - 40.0).abs() < 1e-8);
/// ```
pub fn identify_from_teeth(
    readings: &ToothReadings,
    opts: &ToothFitOptions,
) -> Result<ToothFit, DisplacementError> {
    let k = opts.cutter.teeth();
    if readings.teeth() != k {
        return Err(DisplacementError::TooFew {
            what: format!(
                "teeth with readings for a {k}-tooth cutter (readings cover {} teeth)",
                readings.teeth()
            ),
            got: readings.teeth(),
            need: k,
        });
    }
    check_known_offset(opts)?;
    let factor = opts
        .beam
        .amplitude_factor(opts.cutter.radius_at(opts.height_mm))?;
    let readings = readings.scaled(factor);
    let (noise, noise_source) = noise_level(&readings, opts, factor);
    match (opts.method, k) {
        (ToothMethod::Joint, 2) => two_teeth(&readings, opts, noise, noise_source, factor),
        (ToothMethod::Joint, _) => joint(&readings, opts, noise, noise_source, factor),
        (ToothMethod::SeedScan, _) => seed_scan(&readings, opts, noise, noise_source, factor),
    }
}

fn check_known_offset(opts: &ToothFitOptions) -> Result<(), DisplacementError> {
    if let Some(r) = opts.known_offset_mm {
        if !(r.is_finite() && r >= 0.0) {
            return Err(
                crate::ParamError::new("offset_um", "a finite number >= 0", r * 1e3).into(),
            );
        }
    }
    if let Some(s) = opts.noise_mm {
        if !(s.is_finite() && s > 0.0) {
            return Err(crate::ParamError::new("noise_um", "a finite number > 0", s * 1e3).into());
        }
    }
    if !opts.height_mm.is_finite() {
        return Err(crate::ParamError::new("height_mm", "a finite number", opts.height_mm).into());
    }
    Ok(())
}

/// σ_P of one (beam-corrected) reading: given > repeats; the residual is used later if neither.
fn noise_level(
    r: &ToothReadings,
    opts: &ToothFitOptions,
    factor: f64,
) -> (Option<f64>, NoiseSource) {
    if let Some(s) = opts.noise_mm {
        (Some(s * factor), NoiseSource::Given)
    } else if let Some(s) = r.repeat_noise() {
        (Some(s), NoiseSource::Repeats)
    } else {
        (None, NoiseSource::Unknown)
    }
}

/// Model radii R_i(e) (mm) at the readings' height.
fn model_radii(cutter: &Cutter, z: f64, e: [f64; 2]) -> Vec<f64> {
    let ro = Runout::from_vector(e);
    (0..cutter.teeth())
        .map(|i| ro.tooth_radius(cutter, i, z))
        .collect()
}

/// Least-squares problem P_i = c + R_i(e), weighted by √n_i (n_i readings of tooth i).
struct PositionsProblem<'a> {
    cutter: &'a Cutter,
    z: f64,
    p: Vec<f64>,
    w: Vec<f64>,
    x: Vector3<f64>,
}

impl LeastSquaresProblem<f64, Dyn, U3> for PositionsProblem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, U3>;
    type ParameterStorage = Owned<f64, U3>;

    fn set_params(&mut self, x: &Vector3<f64>) {
        self.x = *x;
    }
    fn params(&self) -> Vector3<f64> {
        self.x
    }
    fn residuals(&self) -> Option<DVector<f64>> {
        let r = model_radii(self.cutter, self.z, [self.x[1], self.x[2]]);
        Some(DVector::from_iterator(
            self.p.len(),
            (0..self.p.len()).map(|i| self.w[i] * (self.p[i] - self.x[0] - r[i])),
        ))
    }
    fn jacobian(&self) -> Option<OMatrix<f64, Dyn, U3>> {
        Some(positions_jacobian(
            self.cutter,
            self.z,
            [self.x[1], self.x[2]],
            &self.w,
        ))
    }
}

/// ∂(residual_i)/∂(c, e_x, e_y) = −w_i·(1, n_i) with n_i the unit vector of tooth point i.
fn positions_jacobian(cutter: &Cutter, z: f64, e: [f64; 2], w: &[f64]) -> OMatrix<f64, Dyn, U3> {
    let ro = Runout::from_vector(e);
    let k = cutter.teeth();
    let mut j = OMatrix::<f64, Dyn, U3>::zeros(k);
    for i in 0..k {
        let (x, y) = ro.tooth_point(cutter, i, z);
        let n = x.hypot(y);
        j[(i, 0)] = -w[i];
        j[(i, 1)] = -w[i] * x / n;
        j[(i, 2)] = -w[i] * y / n;
    }
    j
}

/// Linear first-order start (§1.5 step 1): P_i ≈ c + e_x cos ψ_i + e_y sin ψ_i (+ R).
fn linear_start(cutter: &Cutter, z: f64, p: &[f64], w: &[f64]) -> Option<Vector3<f64>> {
    let k = p.len();
    let r = cutter.radius_at(z);
    let a = DMatrix::from_fn(k, 3, |i, c| {
        let psi = cutter.tooth_angle(i, z);
        w[i] * [1.0, psi.cos(), psi.sin()][c]
    });
    let b = DVector::from_iterator(k, (0..k).map(|i| w[i] * (p[i] - r)));
    let x = LinearLsq::new(a).beta(&b, 1e-12).ok()?;
    Some(Vector3::new(x[0], x[1], x[2]))
}

fn weights(r: &ToothReadings) -> Vec<f64> {
    r.samples()
        .iter()
        .map(|s| (s.len() as f64).sqrt())
        .collect()
}

fn joint(
    readings: &ToothReadings,
    opts: &ToothFitOptions,
    noise: Option<f64>,
    mut noise_source: NoiseSource,
    factor: f64,
) -> Result<ToothFit, DisplacementError> {
    let (cutter, z, k) = (&opts.cutter, opts.height_mm, opts.cutter.teeth());
    let p = readings.positions();
    let w = weights(readings);
    let start = linear_start(cutter, z, &p, &w)
        .ok_or_else(|| DisplacementError::Fit("linear first-order start is singular".into()))?;
    let problem = PositionsProblem {
        cutter,
        z,
        p: p.clone(),
        w: w.clone(),
        x: start,
    };
    let (solved, report) = LevenbergMarquardt::new().minimize(problem);
    if !report.termination.was_successful() {
        return Err(DisplacementError::Fit(format!(
            "Levenberg–Marquardt stopped: {:?}",
            report.termination
        )));
    }
    let x = solved.x;
    let e = [x[1], x[2]];
    let res = solved.residuals().unwrap_or_else(|| DVector::zeros(k));
    let rss = res.norm_squared();
    let dof = k - 3;
    let jac = positions_jacobian(cutter, z, e, &w);
    let jtj: Matrix3<f64> = jac.transpose() * &jac;
    let sv = jtj.singular_values();
    let condition = sv.max() / sv.min();
    let sigma = noise.or_else(|| {
        (dof > 0).then(|| {
            noise_source = NoiseSource::Residual;
            (rss / dof as f64).sqrt()
        })
    });
    let (rho, lambda, se_rho, se_lambda) = match (sigma, jtj.try_inverse()) {
        (Some(s), Some(inv)) => {
            let cov = Matrix2::new(inv[(1, 1)], inv[(1, 2)], inv[(2, 1)], inv[(2, 2)]) * (s * s);
            let (r, l, sr, sl) = polar_with_covariance(e, &cov);
            (r, l, Some(sr), Some(sl))
        }
        _ => (e[0].hypot(e[1]), e[1].atan2(e[0]), None, None),
    };
    let mut notes = Vec::new();
    if sigma.is_none() {
        notes.push(format!(
            "no noise estimate (K = {k} leaves no residual degrees of freedom and no tooth was read twice): standard errors unknown; give the sensor noise or repeat the readings"
        ));
    }
    if let Some(known) = opts.known_offset_mm {
        consistency_note(&mut notes, rho, se_rho, known, opts.known_offset_se_mm);
    }
    Ok(ToothFit {
        method: ToothMethod::Joint,
        offset_mm: rho,
        offset_se_mm: se_rho,
        angle: AngleEstimate::checked(lambda, se_lambda, rho),
        radius_differences_mm: readings.radius_differences(),
        positions_mm: p,
        residual_rms_mm: (rss / w.iter().map(|v| v * v).sum::<f64>()).sqrt(),
        dof,
        noise_mm: sigma,
        noise_source,
        condition_number: Some(condition),
        beam_factor: factor,
        notes,
    })
}

/// §1.5 step 4: |ρ_fit − ρ_disp| < 3σ.
fn consistency_note(
    notes: &mut Vec<String>,
    rho: f64,
    se: Option<f64>,
    known: f64,
    known_se: Option<f64>,
) {
    let s = (se.unwrap_or(0.0).powi(2) + known_se.unwrap_or(0.0).powi(2)).sqrt();
    if s > 0.0 && (rho - known).abs() > 3.0 * s {
        notes.push(format!(
            "inconsistent offsets: fitted {:.3} µm vs height regression {:.3} µm differ by more than 3σ = {:.3} µm (tooth form errors?)",
            rho * 1e3,
            known * 1e3,
            3.0 * s * 1e3
        ));
    }
}

fn required_offset(opts: &ToothFitOptions, why: &str) -> Result<f64, DisplacementError> {
    opts.known_offset_mm
        .ok_or_else(|| DisplacementError::NeedsOffset { reason: why.into() })
}

/// K = 2 closed form (§1.5 step 2): cos θ' = ΔR·sqrt(a − ΔR²/4)/(2Rρ), a = R² + ρ², θ' measured
/// from tooth 0's direction at this height; λ = ψ₀(z) ± θ'.
fn two_teeth(
    readings: &ToothReadings,
    opts: &ToothFitOptions,
    noise: Option<f64>,
    noise_source: NoiseSource,
    factor: f64,
) -> Result<ToothFit, DisplacementError> {
    let cutter = &opts.cutter;
    if !cutter.is_uniform_pitch() {
        return Err(DisplacementError::Fit(
            "the K = 2 closed form needs uniform pitch; use the scan method".into(),
        ));
    }
    let rho = required_offset(
        opts,
        "K = 2 gives one equation for two unknowns (docs/methods.md §1.5)",
    )?;
    let (z, r) = (opts.height_mm, cutter.radius_at(opts.height_mm));
    let p = readings.positions();
    let delta = p[0] - p[1];
    let n = readings.samples();
    let sigma_delta = noise.map(|s| s * (1.0 / n[0].len() as f64 + 1.0 / n[1].len() as f64).sqrt());
    let mut notes = Vec::new();
    let delta = clamp_delta(delta, rho, sigma_delta, &mut notes)?;
    let a = r * r + rho * rho;
    let cos_t = if rho > 0.0 {
        (delta * (a - delta * delta / 4.0).sqrt() / (2.0 * r * rho)).clamp(-1.0, 1.0)
    } else {
        1.0
    };
    let theta = cos_t.acos();
    let psi0 = cutter.tooth_angle(0, z);
    let se = two_teeth_se(
        cutter,
        z,
        rho,
        psi0 + theta,
        sigma_delta,
        opts.known_offset_se_mm,
    );
    let angle = resolve_mirror(psi0, theta, se, rho, opts.phase_hint_rad, &mut notes);
    if noise.is_none() {
        notes.push(
            "no noise estimate: σ_λ unknown; give the sensor noise or repeat the readings".into(),
        );
    }
    Ok(ToothFit {
        method: ToothMethod::Joint,
        offset_mm: rho,
        offset_se_mm: opts.known_offset_se_mm,
        angle,
        radius_differences_mm: readings.radius_differences(),
        positions_mm: p,
        residual_rms_mm: 0.0,
        dof: 0,
        noise_mm: noise,
        noise_source,
        condition_number: None,
        beam_factor: factor,
        notes,
    })
}

/// |ΔR₁| ≤ 2ρ: beyond it by more than 3σ_Δ (or at all without a noise estimate, beyond rounding)
/// is an error; within the noise it is clamped and flagged (methods.md §1.5).
fn clamp_delta(
    delta: f64,
    rho: f64,
    sigma_delta: Option<f64>,
    notes: &mut Vec<String>,
) -> Result<f64, DisplacementError> {
    let max = 2.0 * rho;
    if delta.abs() <= max {
        return Ok(delta);
    }
    let tol = sigma_delta.map_or(1e-12 + 1e-9 * max, |s| 3.0 * s);
    if delta.abs() - max > tol {
        return Err(DisplacementError::InconsistentDifference {
            delta_um: delta.abs() * 1e3,
            max_um: max * 1e3,
            tolerance_um: tol * 1e3,
        });
    }
    notes.push(format!(
        "|ΔR| = {:.4} µm exceeded 2·offset = {:.4} µm within the noise; clamped (θ' = 0 or 180°)",
        delta.abs() * 1e3,
        max * 1e3
    ));
    Ok(delta.clamp(-max, max))
}

/// σ_λ for K = 2: sqrt(σ_Δ² + (∂Δ/∂ρ·σ_ρ)²)/|∂Δ/∂λ|, derivatives of the exact model
/// (first order: σ_P/(√2·ρ·|sin θ|), methods.md §1.5).
fn two_teeth_se(
    cutter: &Cutter,
    z: f64,
    rho: f64,
    lambda: f64,
    sigma_delta: Option<f64>,
    rho_se: Option<f64>,
) -> Option<f64> {
    let d = |rho: f64, l: f64| {
        let r = model_radii(cutter, z, [rho * l.cos(), rho * l.sin()]);
        r[0] - r[1]
    };
    let h = 1e-6;
    let dl = (d(rho, lambda + h) - d(rho, lambda - h)) / (2.0 * h);
    let hr = 1e-6 * rho.max(1e-6);
    let dr =
        (d(rho + hr, lambda) - d((rho - hr).max(0.0), lambda)) / (rho + hr - (rho - hr).max(0.0));
    let s = sigma_delta?;
    let var = s * s + (dr * rho_se.unwrap_or(0.0)).powi(2);
    Some(if dl == 0.0 {
        f64::INFINITY
    } else {
        var.sqrt() / dl.abs()
    })
}

/// Two mirror candidates λ = ψ₀ ± θ'; pick by the phase hint when given (methods.md §1.5 "K = 2").
fn resolve_mirror(
    psi0: f64,
    theta: f64,
    se: Option<f64>,
    rho: f64,
    hint: Option<f64>,
    notes: &mut Vec<String>,
) -> AngleEstimate {
    let cands = [wrap_pi(psi0 + theta), wrap_pi(psi0 - theta)];
    if let Some(s) = se.filter(|s| s.is_nan() || *s >= super::ANGLE_SE_LIMIT_RAD) {
        return AngleEstimate::Undetermined {
            reason: format!(
                "K = 2: σ_λ = {:.1}° exceeds the 10° limit (θ' = {:.1}° is near 0° or 180°, where dθ/dΔR → ∞, or the offset {:.3} µm is too small for the noise; docs/methods.md §1.5)",
                s.to_degrees(),
                theta.to_degrees(),
                rho * 1e3
            ),
            rejected_rad: Some(cands[0]),
            se_rad: Some(s),
        };
    }
    match hint {
        Some(h) => {
            let dist = |c: f64| wrap_pi(c - h).abs();
            let best = if dist(cands[0]) <= dist(cands[1]) { cands[0] } else { cands[1] };
            if dist(best) > PI / 4.0 {
                notes.push(format!(
                    "phase hint {:.1}° is {:.1}° from the chosen solution {:.1}°",
                    h.to_degrees(),
                    dist(best).to_degrees(),
                    best.to_degrees()
                ));
            }
            AngleEstimate::checked(best, se, rho)
        }
        None if theta.sin().abs() < 1e-12 => AngleEstimate::checked(cands[0], se, rho),
        None => AngleEstimate::Ambiguous {
            candidates_rad: cands,
            se_rad: se,
            reason: "K = 2: ΔR depends only on cos θ, so ±θ fit equally (mirror about the tooth line); give the spindle phase of the runout to choose".into(),
        },
    }
}

/// Model ΔR_i = R_i − R_{i+1} (mm) for runout (ρ, λ).
fn model_differences(cutter: &Cutter, z: f64, rho: f64, lambda: f64) -> Vec<f64> {
    let r = model_radii(cutter, z, [rho * lambda.cos(), rho * lambda.sin()]);
    let k = r.len();
    (0..k).map(|i| r[i] - r[(i + 1) % k]).collect()
}

/// The seed's scan (§1.5 step 3): 1° grid of λ over (−180°, 180°], then 1-D Gauss–Newton.
fn seed_scan(
    readings: &ToothReadings,
    opts: &ToothFitOptions,
    noise: Option<f64>,
    mut noise_source: NoiseSource,
    factor: f64,
) -> Result<ToothFit, DisplacementError> {
    let rho = required_offset(opts, "the seed's scan identifies only the angle")?;
    let (cutter, z, k) = (&opts.cutter, opts.height_mm, opts.cutter.teeth());
    let meas = readings.radius_differences();
    let cost = |l: f64| -> f64 {
        model_differences(cutter, z, rho, l)
            .iter()
            .zip(&meas)
            .map(|(m, d)| (m - d).powi(2))
            .sum()
    };
    let mut lambda = (-179..=180)
        .map(|d| (d as f64).to_radians())
        .min_by(|a, b| cost(*a).total_cmp(&cost(*b)))
        .unwrap_or(0.0);
    let grad = |l: f64| -> Vec<f64> {
        let h = 1e-7;
        let (p, m) = (
            model_differences(cutter, z, rho, l + h),
            model_differences(cutter, z, rho, l - h),
        );
        p.iter().zip(&m).map(|(a, b)| (a - b) / (2.0 * h)).collect()
    };
    for _ in 0..50 {
        let g = grad(lambda);
        let res: Vec<f64> = model_differences(cutter, z, rho, lambda)
            .iter()
            .zip(&meas)
            .map(|(m, d)| m - d)
            .collect();
        let gg: f64 = g.iter().map(|v| v * v).sum();
        if gg == 0.0 {
            break;
        }
        let step = -g.iter().zip(&res).map(|(a, b)| a * b).sum::<f64>() / gg;
        lambda += step;
        if step.abs() < 1e-6 {
            break;
        }
    }
    let rss = cost(lambda);
    let dof = k.saturating_sub(2);
    let sigma = noise.or_else(|| {
        (dof > 0).then(|| {
            noise_source = NoiseSource::Residual;
            // each ΔR carries 2σ_P² of variance; K − 1 independent differences, one parameter
            (rss / (2.0 * dof as f64)).sqrt()
        })
    });
    let se = sigma.map(|s| scan_se(&grad(lambda), readings, s));
    let mut notes = Vec::new();
    let angle = if k == 2 {
        let psi0 = cutter.tooth_angle(0, z);
        let theta = wrap_pi(lambda - psi0).abs();
        resolve_mirror(psi0, theta, se, rho, opts.phase_hint_rad, &mut notes)
    } else {
        AngleEstimate::checked(lambda, se, rho)
    };
    Ok(ToothFit {
        method: ToothMethod::SeedScan,
        offset_mm: rho,
        offset_se_mm: opts.known_offset_se_mm,
        angle,
        radius_differences_mm: meas,
        positions_mm: readings.positions(),
        residual_rms_mm: (rss / k as f64).sqrt(),
        dof,
        noise_mm: sigma,
        noise_source,
        condition_number: None,
        beam_factor: factor,
        notes,
    })
}

/// σ_λ of the 1-D least squares on the correlated differences D = A·P:
/// var λ = gᵀ·cov(D)·g/(gᵀg)², cov(D) = σ²·A·diag(1/n_i)·Aᵀ.
fn scan_se(g: &[f64], readings: &ToothReadings, sigma: f64) -> f64 {
    let k = g.len();
    let n: Vec<f64> = readings.samples().iter().map(|s| s.len() as f64).collect();
    // (Aᵀg)_j = g_j − g_{j−1}; gᵀ A W⁻¹ Aᵀ g = Σ_j (g_j − g_{j−1})²/n_j
    let num: f64 = (0..k)
        .map(|j| (g[j] - g[(j + k - 1) % k]).powi(2) / n[j])
        .sum();
    let gg: f64 = g.iter().map(|v| v * v).sum();
    sigma * num.sqrt() / gg
}
