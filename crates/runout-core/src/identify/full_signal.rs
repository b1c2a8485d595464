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
//! carries one, else w = 1 N. Solution in two stages:
//! 1. on the *smooth* variant of the model (edge forces over the whole engagement window, which
//!    makes the residuals continuous in the runout): a scan of the runout vector around the
//!    start value (frequency-domain estimate §4.7 [`frequency_estimate`], or the caller's guess,
//!    e.g. the sine fit) with the coefficients solved exactly by linear least squares at each
//!    point (the forces are linear in them), then Levenberg–Marquardt (`levenberg-marquardt`
//!    crate; analytic coefficient columns, central differences over ±0.1 µm for the runout);
//! 2. on the *exact* model (edge forces only where h > 0, as the simulation): a derivative-free
//!    compass search of the runout parameters on the profile cost (coefficients re-solved
//!    linearly), because the exact residuals jump by K_e·dz wherever a tooth's chip crosses zero
//!    and a gradient method stalls on those steps.
//!
//! Uncertainty: Cov = s²·(JᵀJ)⁻¹ at the solution with s² = Σr²/(n − p) (the "scaled" covariance:
//! correct when the weights are right up to a common factor), standard errors from its diagonal,
//! ρ and λ by the delta method from Cov(e_x, e_y). The condition number is that of J with unit-norm
//! columns; above 1e8 the fit is flagged ill-conditioned. Averaged-waveform samples are treated
//! as independent (true for white measurement noise; coloured noise makes the SEs optimistic).

use super::covariance::{fit_covariance, time_blocks_to_harmonics, FitCovariance};
use super::error::IdentifyError;
use super::frequency::{frequency_estimate, FrequencyEstimate};
use super::harmonic_fit::{harmonic_fit, ChainFitReport, ChainOptions};
use super::model::{
    coefficient_gradient, force_from_basis, grouping, join_grouped, runout_gradient, with_grouping,
    BasisSums, GroupingScope, RevolutionModel,
};
use super::sine_fit::Estimate;
use super::waveform::{FrameAxis, WaveformCase};
use crate::coefficients::CuttingCoefficients;
use crate::fit::linear_lsq;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{storage::Owned, DMatrix, DVector, Dyn};
use rayon::prelude::*;
use serde::Serialize;

/// Options of [`full_signal_fit`].
#[derive(Debug, Clone, Default)]
pub struct FullSignalOptions {
    /// Axial disks of the model; `None` = automatic (helix lag a_p·tanβ/R ≤ 0.1° per disk, 1 for
    /// straight flutes, at least 8 when fitting tilt, at most 2000). Coarser disks bias the
    /// coefficients: 0.5° per disk gave −1.8 % on K_tc at a_p = 8 mm, 30° helix.
    pub disks: Option<usize>,
    /// Also fit the tilt vector τ.
    pub fit_tilt: bool,
    /// Start value of the runout vector e (mm); `None` = frequency-domain estimate.
    pub initial_runout: Option<[f64; 2]>,
    /// Fit through a measuring chain (fitted modes, a known FRF or a band limit) in the
    /// harmonic domain (module `identify::harmonic_fit`); `None` = rigid sensor, time-domain fit.
    pub chain: Option<ChainOptions>,
    /// Hold the cutting coefficients [K_tc, K_rc, K_ac, K_te, K_re, K_ae] at these values (only
    /// with `chain`): a single recording cannot separate shear from edge coefficients, so the
    /// per-recording runout fits hold those of the joint fit (issue 11 item 5).
    pub fixed_coefficients: Option<[f64; 6]>,
}

/// Result of the full-signal fit. Offsets mm, angles rad, coefficients N/mm² and N/mm.
#[derive(Debug, Clone, Serialize)]
pub struct FullSignalFit {
    /// Runout offset ρ (mm).
    pub offset: Estimate,
    /// Runout angle λ (rad).
    pub angle: Estimate,
    /// Whether both components of the runout vector were identifiable.
    pub observability: RunoutObservability,
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
    /// Model evaluations of the solver (stage-1 residual evaluations + stage-2 search points).
    pub evaluations: usize,
    /// Termination reason of the stage-1 Levenberg–Marquardt solver.
    pub termination: String,
    /// The start value from the frequency-domain estimate, when used.
    pub initial: Option<FrequencyEstimate>,
    /// Axial disks used.
    pub disks: usize,
    /// Warnings (ill-conditioning, non-convergence, coefficients not identified).
    pub warnings: Vec<String>,
    /// The measuring chain of a chain-aware fit (`None` for the rigid time-domain fit).
    pub chain: Option<ChainFitReport>,
    /// The two standard errors of ρ (mm) whose larger is `offset.se`: classic s²(JᵀJ)⁻¹ and
    /// robust (harmonic-cluster sandwich), for diagnostics and the coverage test.
    #[serde(skip)]
    pub offset_se_parts: SeParts,
}

/// Classic and robust standard errors of one quantity (see module `identify::covariance`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SeParts {
    /// s²·(JᵀJ)⁻¹, independent residuals of equal variance.
    pub classic: f64,
    /// Harmonic-cluster sandwich.
    pub robust: f64,
}

/// Which part of the runout vector the data determine.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RunoutObservability {
    /// Both components (offset and angle).
    Full,
    /// Only the component along `direction` (unit spindle-frame vector): K = 2 with straight
    /// flutes and no tilt, where the offset across the tooth line changes no radius difference.
    AlongDirection {
        /// Unit vector of the observable direction.
        direction: [f64; 2],
    },
}

/// Check the runout columns of the Jacobian at the start point; when one direction is
/// unobservable (singular-value ratio < 1e-4), restrict the fit to the observable one.
fn runout_observability(p: &mut Problem<'_>) -> RunoutObservability {
    p.analytic = true;
    p.recompute();
    let jac = p.jacobian();
    // (the sums stay the analytic ones here: every user recomputes them first — the stage-1
    // scan and `set_smooth` — so the plain sums are not computed again only to be replaced)
    p.analytic = false;
    let Some(j) = jac else {
        return RunoutObservability::Full;
    };
    let g = j.columns(0, 2).transpose() * j.columns(0, 2);
    let eig = nalgebra::SymmetricEigen::new(nalgebra::Matrix2::from_fn(|r, c| g[(r, c)]));
    let (imax, imin) = if eig.eigenvalues[0] >= eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    let (lmax, lmin) = (eig.eigenvalues[imax], eig.eigenvalues[imin].max(0.0));
    if lmax > 0.0 && (lmin / lmax).sqrt() >= 1e-4 {
        return RunoutObservability::Full;
    }
    let v = eig.eigenvectors.column(imax);
    let d = [v[0], v[1]];
    let (e, _) = p.runout();
    let rest: Vec<f64> = p.x.iter().skip(2).copied().collect();
    p.dirs = vec![d];
    p.x = DVector::from_iterator(1 + rest.len(), std::iter::once(0.0).chain(rest));
    p.set_runout(e);
    p.recompute();
    RunoutObservability::AlongDirection { direction: d }
}

/// Which coefficient indices (into [K_tc, K_rc, K_ac, K_te, K_re, K_ae]) are fitted.
fn fitted_coefficients(cases: &[WaveformCase]) -> Vec<usize> {
    let has_z = cases
        .iter()
        .any(|c| c.waveform.components.iter().any(|k| k.axis == FrameAxis::Z));
    if has_z {
        vec![0, 1, 2, 3, 4, 5]
    } else {
        vec![0, 1, 3, 4]
    }
}

/// Automatic disk count: helix lag a_p·tanβ/R per disk ≤ 0.1°, and at least
/// [`crate::edge::min_disks`] for a ball, bull-nose or tapered cutter.
fn auto_disks(cases: &[WaveformCase], tilt: bool) -> usize {
    let lag = cases
        .iter()
        .map(|c| {
            (c.cut.ap() * c.cutter.tan_helix() / c.cutter.radius())
                .abs()
                .to_degrees()
        })
        .fold(0.0, f64::max);
    let profile = cases
        .iter()
        .map(|c| crate::edge::min_disks(&c.cutter, &c.cut))
        .max()
        .unwrap_or(1);
    let d = ((lag / 0.1).ceil().max(1.0) as usize).max(profile);
    if tilt { d.max(8) } else { d }.min(2000)
}

#[derive(Clone)]
struct Problem<'a> {
    cases: &'a [WaveformCase],
    models: Vec<RevolutionModel>,
    coef_idx: Vec<usize>,
    fit_tilt: bool,
    /// Directions spanning the fitted runout vector: e = Σ t_k·d_k (both axes, or only the
    /// observable one when the other is degenerate).
    dirs: Vec<[f64; 2]>,
    /// Parameters: t (µm) [, τ (µm/mm)], coefficients.
    x: DVector<f64>,
    sums: Vec<BasisSums>,
    weights: bool,
    /// Use the analytic runout derivatives (covariance) instead of central differences (solver).
    analytic: bool,
}

impl Problem<'_> {
    fn n_runout(&self) -> usize {
        self.dirs.len() + if self.fit_tilt { 2 } else { 0 }
    }
    fn runout(&self) -> ([f64; 2], [f64; 2]) {
        let mut e = [0.0; 2];
        for (k, d) in self.dirs.iter().enumerate() {
            e[0] += self.x[k] * d[0] * 1e-3;
            e[1] += self.x[k] * d[1] * 1e-3;
        }
        let nd = self.dirs.len();
        let t = if self.fit_tilt {
            [self.x[nd] * 1e-3, self.x[nd + 1] * 1e-3]
        } else {
            [0.0, 0.0]
        };
        (e, t)
    }
    /// Switch all models between the smooth (edge forces over the window) and exact variants.
    fn set_smooth(&mut self, smooth: bool) {
        for m in &mut self.models {
            m.edge_in_window = smooth;
        }
        self.recompute();
    }
    /// Set the runout vector e (mm), projected on the fitted directions.
    fn set_runout(&mut self, e: [f64; 2]) {
        for k in 0..self.dirs.len() {
            let d = self.dirs[k];
            self.x[k] = (e[0] * d[0] + e[1] * d[1]) * 1e3;
        }
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
            self.cases[c].waveform.components[comp]
                .se
                .as_ref()
                .map(|s| s[q])
                .unwrap_or(1.0)
        } else {
            1.0
        }
    }
    /// Model sums at the current parameters (with the analytic runout derivatives only when
    /// `analytic` is set — the solver's Jacobian uses differences).
    fn recompute(&mut self) {
        let (e, t) = self.runout();
        let tilt = self.fit_tilt;
        self.sums = if self.analytic {
            self.models.iter().map(|m| m.sums(e, t, tilt)).collect()
        } else {
            self.models.iter().map(|m| m.base_sums(e, t)).collect()
        };
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
        let nr = self.n_runout();
        let np = self.x.len();
        let mut j = DMatrix::zeros(self.n_residuals(), np);
        // Runout columns by central differences over ±RUNOUT_STEP_UM (see the constant; forward
        // differences stalled LM in the straight-flute edge-skipping round trip), or
        // analytic (smooth part only) for the covariance.
        let kc = self.coefficients();
        // (the 2·nr shifted evaluations are independent: in parallel, gathered in order)
        let fd: Vec<DVector<f64>> = if self.analytic {
            (0..nr)
                .map(|p| self.analytic_runout_column(p, &kc))
                .collect()
        } else {
            let g = grouping();
            let shifted: Vec<Vec<f64>> = (0..2 * nr)
                .into_par_iter()
                .with_min_len(nr.max(1))
                .map(|i| {
                    let _g = GroupingScope::new(g);
                    let mut q = self.clone();
                    let step = if i % 2 == 0 {
                        RUNOUT_STEP_UM
                    } else {
                        -RUNOUT_STEP_UM
                    };
                    q.x[i / 2] += step;
                    q.recompute();
                    q.raw_residuals()
                })
                .collect();
            shifted
                .chunks(2)
                .map(|pm| {
                    let (fp, here) = (&pm[0], &pm[1]);
                    DVector::from_iterator(
                        fp.len(),
                        fp.iter()
                            .zip(here)
                            .map(|(a, b)| (a - b) / (2.0 * RUNOUT_STEP_UM)),
                    )
                })
                .collect()
        };
        let mut row = 0;
        for (c, case) in self.cases.iter().enumerate() {
            let s = &self.sums[c];
            for (k, comp) in case.waveform.components.iter().enumerate() {
                for q in 0..comp.values.len() {
                    let w = self.weight(c, k, q);
                    for (p, col) in fd.iter().enumerate() {
                        j[(row, p)] = col[row] / w;
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

impl Problem<'_> {
    /// Analytic ∂(model)/∂x_p (N per µm or per µm/mm) of runout parameter p, unweighted.
    fn analytic_runout_column(&self, p: usize, kc: &CuttingCoefficients) -> DVector<f64> {
        let nd = self.dirs.len();
        let mut out = Vec::with_capacity(self.n_residuals());
        for (c, case) in self.cases.iter().enumerate() {
            let s = &self.sums[c];
            for comp in &case.waveform.components {
                for q in 0..comp.values.len() {
                    let de = |i: usize| runout_gradient(comp.axis, &s.deriv[q][i], kc);
                    let v = if p < nd {
                        let d = self.dirs[p];
                        de(0) * d[0] + de(1) * d[1]
                    } else {
                        de(2 + p - nd)
                    };
                    out.push(v * 1e-3);
                }
            }
        }
        DVector::from_vec(out)
    }
}

/// Profile cost: coefficients solved exactly (linear) at the current runout; weighted RSS.
fn profile_cost(p: &mut Problem<'_>) -> f64 {
    match linear_coefficients(p) {
        Ok(()) => p
            .residuals()
            .map(|r| r.norm_squared())
            .unwrap_or(f64::INFINITY),
        Err(_) => f64::INFINITY,
    }
}

/// Stage 2 of the fit: compass (pattern) search of the runout parameters on the **exact** model's
/// profile cost (coefficients re-solved linearly at each point). Derivative-free, so the
/// edge-force steps of the exact model (see [`RUNOUT_STEP_UM`]) cannot stall it; steps from
/// max(0.5 µm, 5 % of ρ) halved down to 0.005 µm. Each trial point is costed on a copy of the
/// problem (the cost depends on the runout only: the coefficients are solved afresh), so the
/// search can cost a direction's two trial points at once ([`compass_search`]). Returns the
/// number of model evaluations.
fn pattern_search(p: &mut Problem<'_>) -> usize {
    let nr = p.n_runout();
    // (`search_directions` computes p's sums at x0)
    let x0 = p.x.clone();
    let dirs = search_directions(p);
    let (e, _) = p.runout();
    let step = (0.05 * e[0].hypot(e[1]) * 1e3).max(0.5);
    let start: Vec<f64> = (0..nr).map(|k| x0[k]).collect();
    let here: &Problem<'_> = p;
    let (best, evals) = compass_search(&start, &dirs, step, 0.005, |t| {
        let mut q = here.clone();
        for (k, v) in t.iter().enumerate() {
            q.x[k] = *v;
        }
        // (`linear_coefficients` recomputes the sums at the trial runout)
        profile_cost(&mut q)
    });
    for (k, v) in best.iter().enumerate() {
        p.x[k] = *v;
    }
    // (`linear_coefficients` recomputes the sums at the best runout)
    profile_cost(p);
    evals
}

/// Compass (pattern) search: from `x0` try ± `step`·d along each direction d, take the first
/// improvement, halve the step when none improves; stop below `min_step` (µm) or after 600
/// evaluations. Returns the best point and the number of cost evaluations.
///
/// The two trial points of a direction, x + step·d and x − step·d, are costed at once
/// ([`rayon::join`]; `cost` must depend on its argument only) and the first improvement taken
/// in that order: the same path, points and costs as trying them one after the other, at any
/// thread count. A − point costed although the + point improved is not counted in the
/// evaluations (the serial search would not have costed it).
///
/// A point is costed once ([`CostedPoints`]): the search comes back to points it has costed —
/// after a move x → x + step·d, the next round's x − step·d is the old point again, bit for bit
/// whenever the two additions are exact — and, as `cost` depends on its argument only, the
/// remembered cost is the one costing it again would give (issue 18: on the 1 MB head of the
/// 100 MB benchmark recording, 62 of the fits' 1059 model evaluations were such repeats, 18 of
/// them on the chain fit's 4× oversampled exact model). The path, the result and the
/// evaluation count (which counts trial points, costed or remembered) are unchanged.
pub(crate) fn compass_search(
    x0: &[f64],
    dirs: &[Vec<f64>],
    step0: f64,
    min_step: f64,
    cost: impl Fn(&[f64]) -> f64 + Sync,
) -> (Vec<f64>, usize) {
    let mut x = x0.to_vec();
    let mut costed = CostedPoints::default();
    let mut best = costed.cost(&x, &cost);
    let mut step = step0;
    let mut evals = 1;
    let parallel = rayon::current_num_threads() > 1;
    while step > min_step && evals < 600 {
        let mut moved = false;
        for d in dirs {
            let trial = |sign: f64| -> Vec<f64> {
                x.iter()
                    .zip(d)
                    .map(|(v, dv)| v + sign * step * dv)
                    .collect()
            };
            let (plus, minus) = (trial(1.0), trial(-1.0));
            let (cp, cm) = match (costed.get(&plus), costed.get(&minus)) {
                (None, None) if parallel => {
                    let (cp, cm) = join_grouped(|| cost(&plus), || cost(&minus));
                    costed.insert(&plus, cp);
                    costed.insert(&minus, cm);
                    (cp, cm)
                }
                (cp, cm) => {
                    let cp = cp.unwrap_or_else(|| costed.cost(&plus, &cost));
                    // the − point only when the + point does not improve
                    let cm = match cm {
                        Some(cm) => cm,
                        None if cp < best => f64::NAN,
                        None => costed.cost(&minus, &cost),
                    };
                    (cp, cm)
                }
            };
            evals += 1;
            if cp < best {
                best = cp;
                x = plus;
                moved = true;
                continue;
            }
            evals += 1;
            if cm < best {
                best = cm;
                x = minus;
                moved = true;
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    (x, evals)
}

/// The costs of the points a [`compass_search`] has costed, by the points' bits.
#[derive(Default)]
struct CostedPoints(std::collections::HashMap<Vec<u64>, f64>);

impl CostedPoints {
    fn key(p: &[f64]) -> Vec<u64> {
        p.iter().map(|v| v.to_bits()).collect()
    }
    fn get(&self, p: &[f64]) -> Option<f64> {
        self.0.get(&Self::key(p)).copied()
    }
    fn insert(&mut self, p: &[f64], c: f64) {
        self.0.insert(Self::key(p), c);
    }
    /// `cost(p)`, remembered.
    fn cost(&mut self, p: &[f64], cost: impl Fn(&[f64]) -> f64) -> f64 {
        let c = cost(p);
        self.insert(p, c);
        c
    }
}

/// Scan points of the runout vector around the start values: 16 angles × offsets 0.5, 1, 1.5 of
/// the largest start offset (at least 2 µm).
pub(crate) fn candidate_runouts(starts: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let r0 = starts
        .iter()
        .map(|e| e[0].hypot(e[1]))
        .fold(0.002, f64::max);
    let mut out = Vec::with_capacity(48);
    for scale in [0.5, 1.0, 1.5] {
        for a in 0..16 {
            let (s, c) = (a as f64 * std::f64::consts::TAU / 16.0).sin_cos();
            out.push([r0 * scale * c, r0 * scale * s]);
        }
    }
    out
}

/// Search directions for [`pattern_search`]: eigenvectors of the profile Gauss–Newton matrix of
/// the runout parameters (analytic Jacobian with the coefficient columns projected out), scaled
/// by 1/√eigenvalue relative to the least determined one — i.e. steps in standard-error units,
/// so that a narrow diagonal valley (offset–tilt correlation) is followed instead of stalling.
fn search_directions(p: &mut Problem<'_>) -> Vec<Vec<f64>> {
    let nr = p.n_runout();
    let axes = || {
        (0..nr)
            .map(|k| (0..nr).map(|j| if j == k { 1.0 } else { 0.0 }).collect())
            .collect()
    };
    p.analytic = true;
    p.recompute();
    let jac = p.jacobian();
    // (the search costs its points on copies that recompute their sums, and then recomputes
    // p's at the best point: the plain sums at the start are not needed again)
    p.analytic = false;
    let Some(j) = jac else { return axes() };
    let np = j.ncols();
    let jr = j.columns(0, nr).into_owned();
    let jc = j.columns(nr, np - nr).into_owned();
    // residual of J_r after projecting on span(J_c): J_r − J_c (J_cᵀJ_c)⁻¹ J_cᵀ J_r
    let Some(inv) = (jc.transpose() * &jc).try_inverse() else {
        return axes();
    };
    let proj = &jr - &jc * (inv * (jc.transpose() * &jr));
    let h = proj.transpose() * proj;
    let eig = nalgebra::SymmetricEigen::new(h);
    let lmin = eig
        .eigenvalues
        .iter()
        .cloned()
        .fold(f64::INFINITY, f64::min);
    if lmin.is_nan() || lmin <= 0.0 {
        return axes();
    }
    (0..nr)
        .map(|k| {
            let scale = (lmin / eig.eigenvalues[k]).sqrt();
            eig.eigenvectors
                .column(k)
                .iter()
                .map(|v| v * scale)
                .collect()
        })
        .collect()
}

/// Linear least squares of the coefficients at the problem's current runout.
fn linear_coefficients(p: &mut Problem<'_>) -> Result<(), IdentifyError> {
    let nr = p.n_runout();
    let ncoef = p.coef_idx.len();
    p.recompute();
    // weighted design (the sums do not depend on the coefficients) and measured values
    let n = p.n_residuals();
    let mut x = DMatrix::zeros(n, ncoef);
    let mut y = DVector::zeros(n);
    let mut row = 0;
    for (c, case) in p.cases.iter().enumerate() {
        for (k, comp) in case.waveform.components.iter().enumerate() {
            for (q, v) in comp.values.iter().enumerate() {
                let w = p.weight(c, k, q);
                let g = coefficient_gradient(comp.axis, &p.sums[c].base[q]);
                for (j, &i) in p.coef_idx.iter().enumerate() {
                    x[(row, j)] = g[i] / w;
                }
                y[row] = v / w;
                row += 1;
            }
        }
    }
    let fit = linear_lsq("coefficient start values", &x, &y)?;
    for c in 0..ncoef {
        p.x[nr + c] = fit.beta[c];
    }
    Ok(())
}

/// Step (µm, or µm/mm for tilt) of the central differences for the runout columns of the
/// Jacobian. The analytic derivative ([`RevolutionModel::sums`]) misses the edge-force switch at
/// h = 0: where a tooth's chip vanishes inside the engagement (edge skipping, up-milling entry)
/// moving the runout moves that boundary, and with many axial disks the sum of the small steps is
/// a real slope. Ignoring it stalled LM 1.9 µm from the optimum (K = 2, ρ = 27 µm); a 0.1 µm
/// difference spans enough steps to see the macroscopic slope.
pub(crate) const RUNOUT_STEP_UM: f64 = 0.1;

pub(crate) const NAMES: [&str; 6] = ["ktc", "krc", "kac", "kte", "kre", "kae"];

/// Identify runout (and tilt) and the cutting coefficients from averaged waveforms: check the
/// cases, set up the problem, pick start values, fit locally (LM on the smooth model, then a
/// pattern search on the exact one), and summarise with the robust covariance.
pub fn full_signal_fit(
    cases: &[WaveformCase],
    options: &FullSignalOptions,
) -> Result<FullSignalFit, IdentifyError> {
    let weights = validate_cases(cases)?;
    let disks = options
        .disks
        .unwrap_or_else(|| auto_disks(cases, options.fit_tilt))
        .max(1);
    if let Some(chain) = &options.chain {
        return harmonic_fit(cases, options, chain, disks);
    }
    let mut problem = new_problem(cases, options.fit_tilt, disks, weights);
    let np_full = problem.x.len();
    let n = problem.n_residuals();
    if n <= np_full {
        return Err(IdentifyError::too_few(
            "full-signal fit",
            format!("more than {np_full} samples"),
            n,
        ));
    }
    let (e_start, initial) = start_values(&mut problem, options, disks)?;
    // Observability of the runout direction: with K = 2 straight flutes the offset across the
    // tooth line changes no radius difference (methods.md §4.2/§1.5 mirror ambiguity).
    let observability = runout_observability(&mut problem);
    let nr = problem.n_runout();
    let np = problem.x.len();
    let mut candidates = vec![e_start];
    if let Some(f) = initial {
        candidates.push(f.vector);
    }
    candidates.extend(candidate_runouts(&candidates));
    let (mut problem, report) = local_fit(problem, candidates)?;
    let cov = covariance_at_solution(&mut problem, cases)?;
    let rss: f64 = problem.raw_residuals().iter().map(|r| r * r).sum();
    let (e, tau) = problem.runout();
    let coef_idx = problem.coef_idx.clone();
    let mut coefficients = [0.0; 6];
    let mut coefficient_se = [None; 6];
    for (p, &i) in coef_idx.iter().enumerate() {
        coefficients[i] = problem.x[nr + p];
        coefficient_se[i] = Some(cov.se(nr + p));
    }
    Ok(fit_summary(FitSummaryInput {
        e,
        tau: options.fit_tilt.then_some(tau),
        cov: &cov,
        runout_dirs: &problem.dirs,
        coefficients,
        coefficient_se,
        parameters: parameter_names(problem.dirs.len(), options.fit_tilt, &coef_idx),
        rss,
        tss: total_sum_of_squares(cases),
        n,
        np,
        evaluations: report.number_of_evaluations,
        termination: format!("{:?}", report.termination),
        converged: report.termination.was_successful(),
        initial,
        disks,
        observability,
        has_z: coef_idx.len() == 6,
    }))
}

/// At least one case, each waveform valid; returns whether every component carries standard
/// errors (then the residuals are weighted by them).
fn validate_cases(cases: &[WaveformCase]) -> Result<bool, IdentifyError> {
    if cases.is_empty() {
        return Err(IdentifyError::too_few("full-signal fit", "1 recording", 0));
    }
    for c in cases {
        c.waveform.validate()?;
    }
    Ok(cases
        .iter()
        .all(|c| c.waveform.components.iter().all(|k| k.se.is_some())))
}

/// The least-squares problem at zero parameters: one revolution model per case.
fn new_problem(cases: &[WaveformCase], fit_tilt: bool, disks: usize, weights: bool) -> Problem<'_> {
    let coef_idx = fitted_coefficients(cases);
    let nr_full = if fit_tilt { 4 } else { 2 };
    let np_full = nr_full + coef_idx.len();
    let models: Vec<RevolutionModel> = cases
        .iter()
        .map(|c| {
            RevolutionModel::new(
                &c.cutter,
                &c.cut,
                c.waveform.start_angle,
                c.waveform.samples(),
                disks,
            )
        })
        .collect();
    Problem {
        cases,
        models,
        coef_idx,
        fit_tilt,
        dirs: vec![[1.0, 0.0], [0.0, 1.0]],
        x: DVector::zeros(np_full),
        sums: Vec::new(),
        weights,
        analytic: false,
    }
}

/// Start values: the frequency-domain estimate (§4.7) unless the caller gave a runout, with the
/// coefficients solved exactly there. Returns the start runout and the frequency estimate.
fn start_values(
    problem: &mut Problem<'_>,
    options: &FullSignalOptions,
    disks: usize,
) -> Result<([f64; 2], Option<FrequencyEstimate>), IdentifyError> {
    linear_coefficients(problem)?;
    let mut initial = None;
    let mut e_start = options.initial_runout.unwrap_or([0.0, 0.0]);
    if let Ok(f) = frequency_estimate(problem.cases, &problem.coefficients(), disks) {
        initial = Some(f);
        if options.initial_runout.is_none() {
            e_start = f.vector;
        }
    }
    problem.set_runout(e_start);
    linear_coefficients(problem)?;
    Ok((e_start, initial))
}

/// Stage 1 on the smooth variant of the model (edge forces over the whole engagement window,
/// continuous in e): a scan of the candidate runouts with the exactly solved coefficients at each,
/// then LM from the best (and from the second best when its cost is within 2×; the candidates
/// and the two solves are independent and run in parallel, in a fixed order) — with edge
/// skipping (large ρ, K = 2) the cost has local minima the frequency estimate alone can fall into.
/// Stage 2: derivative-free pattern search on the exact model (edge forces only where h > 0, as
/// the simulation) from the stage-1 solution. With straight flutes the exact model's residuals
/// jump by K_e·a_p where a tooth's chip crosses 0 and LM stalls there (round trip K = 6,
/// ρ = 28 µm: 3 µm off; K = 3, ρ = 3 µm: 0.16 µm off).
fn local_fit<'a>(
    mut problem: Problem<'a>,
    candidates: Vec<[f64; 2]>,
) -> Result<(Problem<'a>, levenberg_marquardt::MinimizationReport<f64>), IdentifyError> {
    problem.set_smooth(true);
    // the candidates are independent (each starts from zero coefficients, solved afresh): in
    // parallel, gathered in candidate order
    let here = &problem;
    let g = grouping();
    let mut scored: Vec<(f64, DVector<f64>)> = candidates
        .par_iter()
        .map_init(
            || here.clone(),
            |q, &e| {
                let _g = GroupingScope::new(g);
                q.x.fill(0.0);
                q.set_runout(e);
                if linear_coefficients(q).is_ok() {
                    if let Some(r) = q.residuals() {
                        return Some((r.norm_squared(), q.x.clone()));
                    }
                }
                None
            },
        )
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let lm = || LevenbergMarquardt::new().with_patience(200);
    let mut best: Option<(Problem<'_>, levenberg_marquardt::MinimizationReport<f64>)> = None;
    // second start only when its scan cost is comparable (within 2×) to the best one's; the
    // two solves are independent: in parallel, compared in start order
    let best_cost = scored.first().map(|c| c.0).unwrap_or(f64::INFINITY);
    let starts: Vec<_> = scored
        .iter()
        .take(2)
        .filter(|c| c.0 <= 2.0 * best_cost)
        .collect();
    let runs: Vec<_> = distinct_starts(starts)
        .into_par_iter()
        .with_max_len(1)
        .map(|(_, x)| {
            with_grouping(g, || {
                let mut start = problem.clone();
                start.set_params(x);
                lm().minimize(start)
            })
        })
        .collect();
    for (done, report) in runs {
        let better = best
            .as_ref()
            .is_none_or(|(_, r)| report.objective_function < r.objective_function);
        if better {
            best = Some((done, report));
        }
    }
    let best = best.map(|(mut p, r1)| {
        // (the exact model's sums are first computed by `pattern_search`, with derivatives)
        for m in &mut p.models {
            m.edge_in_window = false;
        }
        let evals = pattern_search(&mut p);
        let mut r = r1;
        r.number_of_evaluations += evals;
        (p, r)
    });
    best.ok_or_else(|| IdentifyError::singular("full-signal fit", "no valid start value"))
}

/// The starts whose parameters differ, bit for bit, from every earlier one's, in order. A
/// solve from a start equal to an earlier one would repeat it exactly (the same start, the same
/// grouping of the sums), and the earlier one is kept on a tie: leaving it out changes no
/// result. It happens in the chain fit, whose two starts (after the joint and the per-axis mode
/// scans) coincide when the per-axis scan keeps the joint scan's modes — on the bundled
/// example and on the 100 MB benchmark recording's first 30 000 lines, one LM solve was done
/// twice side by side (−7 % of the job's CPU time, the same wall time: the twin ran on the
/// other core); here, when the frequency estimate, both the start value and a candidate, is
/// also the scan's best two.
pub(crate) fn distinct_starts<T>(starts: Vec<&(T, DVector<f64>)>) -> Vec<&(T, DVector<f64>)> {
    let same = |a: &DVector<f64>, b: &DVector<f64>| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
    };
    let mut out: Vec<&(T, DVector<f64>)> = Vec::with_capacity(starts.len());
    for s in starts {
        if !out.iter().any(|o| same(&o.1, &s.1)) {
            out.push(s);
        }
    }
    out
}

/// Robust covariance at the solution, from the analytic (smooth) runout derivatives: the
/// differences also catch the edge-force steps, which carry no statistical information per sample
/// and would inflate JᵀJ (standard errors 5× too small in the round-trip tests). Each
/// (recording, component) block is rotated to harmonics first.
fn covariance_at_solution(
    problem: &mut Problem<'_>,
    cases: &[WaveformCase],
) -> Result<FitCovariance, IdentifyError> {
    problem.analytic = true;
    problem.recompute();
    let jac = problem
        .jacobian()
        .ok_or_else(|| IdentifyError::singular("full-signal fit", "Jacobian"))?;
    let res = problem
        .residuals()
        .ok_or_else(|| IdentifyError::singular("full-signal fit", "non-finite residuals"))?;
    let blocks: Vec<usize> = cases
        .iter()
        .flat_map(|c| std::iter::repeat_n(c.waveform.samples(), c.waveform.components.len()))
        .collect();
    let (jh, rh, groups) = time_blocks_to_harmonics(&jac, &res, &blocks);
    Ok(fit_covariance(&jh, &rh, &groups))
}

/// Σ (v − v̄)² over every component about its own mean, unweighted (N²), for R².
fn total_sum_of_squares(cases: &[WaveformCase]) -> f64 {
    let mut tss = 0.0;
    for case in cases {
        for comp in &case.waveform.components {
            let m = comp.values.iter().sum::<f64>() / comp.values.len() as f64;
            tss += comp.values.iter().map(|v| (v - m).powi(2)).sum::<f64>();
        }
    }
    tss
}

/// Names of the fitted parameters: the runout ones (two components, or one along the tooth line
/// when only that is observable), tilt, then the coefficients.
fn parameter_names(runout_dirs: usize, fit_tilt: bool, coef_idx: &[usize]) -> Vec<String> {
    let mut parameters: Vec<String> = if runout_dirs == 2 {
        vec!["ex_um".to_string(), "ey_um".to_string()]
    } else {
        vec!["e_along_tooth_line_um".to_string()]
    };
    if fit_tilt {
        parameters.extend([
            "tilt_x_um_per_mm".to_string(),
            "tilt_y_um_per_mm".to_string(),
        ]);
    }
    parameters.extend(coef_idx.iter().map(|&i| NAMES[i].to_string()));
    parameters
}

/// What [`fit_summary`] turns into a [`FullSignalFit`].
pub(crate) struct FitSummaryInput<'a> {
    /// Runout vector e (mm) and tilt τ (mm/mm, when fitted).
    pub e: [f64; 2],
    pub tau: Option<[f64; 2]>,
    pub cov: &'a FitCovariance,
    /// Directions of the fitted runout parameters (µm along each), parameters 0..nd.
    pub runout_dirs: &'a [[f64; 2]],
    pub coefficients: [f64; 6],
    pub coefficient_se: [Option<f64>; 6],
    pub parameters: Vec<String>,
    /// Unweighted residual and total sums of squares (N²).
    pub rss: f64,
    pub tss: f64,
    pub n: usize,
    pub np: usize,
    pub evaluations: usize,
    pub termination: String,
    pub converged: bool,
    pub initial: Option<FrequencyEstimate>,
    pub disks: usize,
    pub observability: RunoutObservability,
    pub has_z: bool,
}

/// Offsets, angles and their SEs by the delta method (e = Σ t_k d_k, t in µm), R², warnings.
pub(crate) fn fit_summary(s: FitSummaryInput<'_>) -> FullSignalFit {
    let np = s.np;
    let nd = s.runout_dirs.len();
    let [ex, ey] = s.e;
    let rho = ex.hypot(ey);
    // gradient of a function of e, mapped to the parameter vector (µm → mm)
    let along = |g: [f64; 2]| {
        let mut v = DVector::zeros(np);
        for (k, d) in s.runout_dirs.iter().enumerate() {
            v[k] = (g[0] * d[0] + g[1] * d[1]) * 1e-3;
        }
        v
    };
    let (g_rho, g_lam) = if rho > 0.0 {
        ([ex / rho, ey / rho], [-ey / (rho * rho), ex / (rho * rho)])
    } else {
        ([f64::NAN; 2], [f64::NAN; 2])
    };
    let ill = s.cov.condition.is_nan() || s.cov.condition >= 1e8;
    let mut warnings = Vec::new();
    if ill {
        warnings.push(format!(
            "ill-conditioned fit (condition number {:.3e}): the parameters are not separately identifiable from these recordings (see the correlation matrix); add feeds or components",
            s.cov.condition
        ));
    }
    if !s.converged {
        warnings.push(format!("solver did not converge: {}", s.termination));
    }
    if let RunoutObservability::AlongDirection { direction } = s.observability {
        warnings.push(format!(
            "runout only partly observable (K = 2, straight flutes, no tilt): only the component \
             along the tooth line (spindle-frame direction {:.1}°) changes the chip thickness; \
             the offset reported is that component, a lower bound of ρ, and the angle is not \
             identified (use a helical cutter, or a displacement measurement)",
            direction[1].atan2(direction[0]).to_degrees()
        ));
    }
    let r2 = if s.tss > 0.0 {
        1.0 - s.rss / s.tss
    } else {
        f64::NAN
    };
    if s.tss > 0.0 && s.rss / s.tss > 0.1 {
        warnings.push(format!(
            "poor fit: R² = {r2:.3} (the model explains < 90 % of the waveform variance) — check the \
             cut conditions, the axis mapping, the spindle-angle reference and the sensor's resonance"
        ));
    }
    if !s.has_z {
        warnings.push("no F_z measured: K_ac and K_ae not identified (fixed at 0)".into());
    }
    let tilt_se = |k: usize| s.cov.se(nd + k) * 1e-3;
    FullSignalFit {
        offset: Estimate {
            value: rho,
            se: Some(s.cov.se_of(&along(g_rho))),
        },
        angle: Estimate {
            value: ey.atan2(ex),
            se: (nd == 2).then(|| s.cov.se_of(&along(g_lam))),
        },
        observability: s.observability,
        vector: [
            Estimate {
                value: ex,
                se: Some(s.cov.se_of(&along([1.0, 0.0]))),
            },
            Estimate {
                value: ey,
                se: Some(s.cov.se_of(&along([0.0, 1.0]))),
            },
        ],
        tilt: s.tau.map(|t| {
            [
                Estimate {
                    value: t[0],
                    se: Some(tilt_se(0)),
                },
                Estimate {
                    value: t[1],
                    se: Some(tilt_se(1)),
                },
            ]
        }),
        coefficients: s.coefficients,
        coefficient_se: s.coefficient_se,
        parameters: s.parameters,
        correlation: s.cov.correlation(),
        residual_rms_n: (s.rss / s.n as f64).sqrt(),
        r_squared: r2,
        condition: s.cov.condition,
        ill_conditioned: ill,
        n: s.n,
        dof: s.n - np,
        evaluations: s.evaluations,
        termination: s.termination,
        initial: s.initial,
        disks: s.disks,
        warnings,
        chain: None,
        offset_se_parts: {
            let [classic, robust] = s.cov.se_parts_of(&along(g_rho));
            SeParts { classic, robust }
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The compass search before its points were remembered (issue 18), as the oracle.
    fn compass_search_costing_every_point(
        x0: &[f64],
        dirs: &[Vec<f64>],
        step0: f64,
        min_step: f64,
        cost: impl Fn(&[f64]) -> f64,
    ) -> (Vec<f64>, usize) {
        let mut x = x0.to_vec();
        let mut best = cost(&x);
        let (mut step, mut evals) = (step0, 1);
        while step > min_step && evals < 600 {
            let mut moved = false;
            for d in dirs {
                let trial = |sign: f64| -> Vec<f64> {
                    x.iter()
                        .zip(d)
                        .map(|(v, dv)| v + sign * step * dv)
                        .collect()
                };
                let (plus, minus) = (trial(1.0), trial(-1.0));
                let cp = cost(&plus);
                evals += 1;
                if cp < best {
                    (best, x, moved) = (cp, plus, true);
                    continue;
                }
                let cm = cost(&minus);
                evals += 1;
                if cm < best {
                    (best, x, moved) = (cm, minus, true);
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
        (x, evals)
    }

    /// A point is costed once, and the search takes the path of the one that costed every
    /// trial point: the same point, the same evaluation count, on one thread and on two. The
    /// cost's minimum is off the grid of the steps, along both axes and a diagonal, from
    /// starts where the steps are exact (points come back bit for bit) and where they are not.
    #[test]
    fn compass_search_costs_each_point_once_on_the_same_path() {
        let dirs = vec![vec![1.0, 0.0], vec![0.0, 1.0], vec![0.6, 0.8]];
        let f =
            |x: &[f64]| (x[0] - 0.3137).powi(2) + 3.0 * (x[1] + 1.271).powi(2) + 0.4 * x[0] * x[1];
        for (x0, step) in [([2.0, 3.0], 0.5), ([-1.1, 0.7], 0.37), ([0.0, 0.0], 1.0)] {
            let calls = std::sync::Mutex::new(Vec::new());
            let counted = |x: &[f64]| {
                calls
                    .lock()
                    .unwrap()
                    .push(x.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
                f(x)
            };
            let reference_calls = std::cell::Cell::new(0);
            let reference = compass_search_costing_every_point(&x0, &dirs, step, 1e-3, |x| {
                reference_calls.set(reference_calls.get() + 1);
                f(x)
            });
            for threads in [1, 2] {
                calls.lock().unwrap().clear();
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let got = pool.install(|| compass_search(&x0, &dirs, step, 1e-3, counted));
                assert_eq!(
                    got.1, reference.1,
                    "evaluations, start {x0:?}, {threads} thread(s)"
                );
                assert!(
                    got.0
                        .iter()
                        .zip(&reference.0)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{:?} against {:?}, start {x0:?}, {threads} thread(s)",
                    got.0,
                    reference.0
                );
                let mut seen = calls.lock().unwrap().clone();
                let n = seen.len();
                seen.sort();
                seen.dedup();
                assert_eq!(
                    seen.len(),
                    n,
                    "a point costed twice, start {x0:?}, {threads} thread(s)"
                );
                if threads == 1 {
                    // exact steps bring the search back to points it has costed
                    assert!(
                        n < reference_calls.get(),
                        "start {x0:?}: {n} costs, the oracle {}",
                        reference_calls.get()
                    );
                }
            }
        }
    }

    /// Equal means the same bits: the first of equal starts is kept, in order; −0 and +0 are
    /// different starts (a solve may take them apart), a NaN equals itself.
    #[test]
    fn distinct_starts_keep_the_first_of_equal_ones() {
        let v = |x: &[f64]| DVector::from_column_slice(x);
        let starts = [
            (1, v(&[1.0, 2.0])),
            (2, v(&[1.0, 2.0])),
            (3, v(&[0.0, f64::NAN])),
            (4, v(&[-0.0, f64::NAN])),
            (5, v(&[0.0, f64::NAN])),
            (6, v(&[1.0, 2.0, 3.0])),
        ];
        let kept: Vec<i32> = distinct_starts(starts.iter().collect())
            .iter()
            .map(|s| s.0)
            .collect();
        assert_eq!(kept, [1, 3, 4, 6]);
    }
}
