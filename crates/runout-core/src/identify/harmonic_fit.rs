//! Full-signal identification through the measuring chain (issue 11): the averaged waveform is
//! periodic, so the fit works per spindle harmonic k and axis,
//!
//! Y_k = H_axis(k·f_rev) · S_k · e^{ikδ} · C_k(e, τ, K),
//!
//! where C_k are the harmonics of the rigid cut model ([`RevolutionModel`], the same model as the
//! time-domain fit), H the measuring chain ([`crate::chain`]: a known FRF or modes, or fitted
//! modes), S_k = sinc²(πk/n_s) the attenuation of the linear interpolation that resampled the
//! record (n_s raw samples per revolution) onto the averaging grid (expected value over the
//! fractional sample positions; 1 when the waveform was not resampled), and δ an optional
//! spindle-angle correction per recording (without a once-per-revolution reference the angle
//! origin comes from the tooth-passing phase, which a resonant chain shifts).
//!
//! Residuals are the real and imaginary parts of Y_k − X_k (X the measured harmonics) for
//! k = 0..k_max, scaled so that their sum of squares is the time-domain sum of squares of the
//! band-limited difference (Parseval), and divided by each component's RMS standard error when
//! every component carries one. k_max excludes the Nyquist harmonic and is cut by the band limit
//! and by the range of a measured FRF. A **band-limited** fit is the rigid model on k ≤ k_max
//! only: the cheap fallback that ignores what the chain does above the band.
//!
//! Solution: fitted modes start from a scan of f_n (ζ 0.03) when no start is given; the runout
//! vector from the frequency-domain estimate and a scan (coefficients solved linearly at every
//! point, as in the time-domain fit), then Levenberg–Marquardt on all parameters with the smooth
//! variant of the model, then a compass search of the runout on the exact variant (see the
//! time-domain fit's docs for why), with the coefficients re-solved linearly.

use super::covariance::{fit_covariance, harmonic_groups};
use super::error::IdentifyError;
use super::frequency::frequency_estimate;
use super::full_signal::{
    candidate_runouts, compass_search, distinct_starts, fit_summary, FitSummaryInput,
    FullSignalFit, FullSignalOptions, RunoutObservability, NAMES, RUNOUT_STEP_UM,
};
use super::model::{
    coefficient_gradient, grouping, join_grouped, BasisSums, GroupingScope, RevolutionModel, NB,
};
use super::sine_fit::Estimate;
use super::waveform::{FrameAxis, WaveformCase};
use crate::chain::{AxisChain, Complex64, MeasuringChain, SensorMode};
use crate::coefficients::CuttingCoefficients;
use crate::fit::linear_lsq_beta;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{storage::Owned, DMatrix, DVector, Dyn};
use rayon::prelude::*;
use realfft::RealFftPlanner;
use serde::Serialize;
use std::f64::consts::PI;
use std::sync::Arc;

/// Oversampling L of the model grid: the rigid model is evaluated at L·N angles per revolution,
/// so that the chain acts on its true harmonics up to L·N/2 before they are folded by the
/// N-point sampling (a sharp entry or exit has harmonics far above N/2; applying H to the
/// already-aliased N-point harmonics biased K_te by −3.5 % in the K = 4 down-milling round trip).
const OVERSAMPLE: usize = 4;
/// Oversampling of the stage-1 model (see [`harmonic_fit`]).
const COARSE_OVERSAMPLE: usize = 2;

/// How the measuring chain enters the full-signal fit.
#[derive(Debug, Clone, PartialEq)]
pub enum ChainModel {
    /// A known chain (measured FRF, or stated modes), not fitted.
    Known(MeasuringChain),
    /// One second-order mode per listed axis, shared by all recordings, fitted (f_n, ζ, gain)
    /// jointly with runout and coefficients. `None` start values are found by a scan.
    FitModes {
        /// Axes with a mode and their start values (`None` = scan f_n, ζ 0.03, gain 1).
        axes: Vec<(FrameAxis, Option<SensorMode>)>,
        /// Also fit each mode's relative gain (default: a pure second-order mode, gain 1, whose
        /// peak height 1/2ζ is then carried by the damping alone).
        fit_gain: bool,
    },
    /// Rigid model on the harmonics 0..=`max_harmonic` of the spindle frequency only.
    BandLimit {
        /// Highest spindle harmonic fitted.
        max_harmonic: usize,
    },
}

/// Options of the chain-aware (harmonic) fit, per recording where a vector.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainOptions {
    /// The chain.
    pub model: ChainModel,
    /// Spindle frequency f_rev (Hz) of each recording (measured).
    pub spindle_hz: Vec<f64>,
    /// Raw samples per revolution of each recording when its average was resampled by linear
    /// interpolation (the signal pipeline); `None` = not resampled (S_k = 1).
    pub samples_per_rev: Vec<Option<f64>>,
    /// Fit a spindle-angle correction δ for each recording (no absolute angle reference).
    pub free_start_angle: Vec<bool>,
}

/// The identified (or given) chain, as reported.
#[derive(Debug, Clone, Serialize)]
pub struct ChainFitReport {
    /// `fitted_modes`, `measured_frf`, `stated_modes` or `band_limit`.
    pub kind: String,
    /// Highest spindle harmonic fitted, per recording.
    pub max_harmonic: Vec<usize>,
    /// Fitted modes: axis, natural frequency (Hz), damping ratio, gain, each ± SE.
    pub modes: Vec<FittedMode>,
    /// Spindle-angle corrections δ (rad) per recording (0 with no SE when not fitted).
    pub start_angle_shift: Vec<Estimate>,
    /// R² of the rigid model (chain removed, same band, coefficients re-solved) for comparison.
    pub rigid_r_squared: f64,
}

/// One fitted sensor mode.
#[derive(Debug, Clone, Serialize)]
pub struct FittedMode {
    /// Axis of the workpiece frame.
    pub axis: FrameAxis,
    /// Natural frequency (Hz).
    pub frequency_hz: Estimate,
    /// Damping ratio.
    pub damping: Estimate,
    /// Relative gain.
    pub gain: Estimate,
}

/// Per-case fixed data: measured harmonics and band.
#[derive(Clone)]
struct CaseData {
    n: usize,
    kmax: usize,
    spindle_hz: f64,
    interp: Vec<f64>,
    /// Measured harmonics per component (k = 0..=kmax), unnormalised DFT.
    measured: Vec<Vec<Complex64>>,
    /// Weight per component (RMS standard error, or 1 N).
    weight: Vec<f64>,
    free_angle: Option<usize>,
}

/// `f(m)` at every harmonic m that `used` marks, `zero` at the others.
fn at_used<T: Clone>(used: &[bool], zero: T, f: impl Fn(usize) -> T) -> Vec<T> {
    let mut t = vec![zero; used.len()];
    for (m, &u) in used.iter().enumerate() {
        if u {
            t[m] = f(m);
        }
    }
    t
}

/// Rigid-model harmonic k of the six coefficient-gradient columns (K order) for axis, from the
/// basis harmonics `b` ([r][k]) of one case.
fn gradient_harmonic(b: &[Vec<Complex64>], axis: FrameAxis, k: usize) -> [Complex64; 6] {
    let mut re = [0.0; NB];
    let mut im = [0.0; NB];
    for r in 0..NB {
        re[r] = b[r][k].re;
        im[r] = b[r][k].im;
    }
    let gr = coefficient_gradient(axis, &re);
    let gi = coefficient_gradient(axis, &im);
    std::array::from_fn(|i| Complex64::new(gr[i], gi[i]))
}

/// What the design matrix, the residuals and the chain columns read, tabulated once per
/// evaluation of the parameters ([`HarmonicProblem::tables`]); indices [case][component][m] at
/// the folded true harmonics m (zero where no row folds m). The parts that do not depend on the
/// modes are shared (`Arc`) with the tables of a mode scan's candidates
/// ([`HarmonicProblem::with_modes`]).
struct Tables {
    /// Per case: the harmonics m that some fitted row folds.
    used: Arc<Vec<Vec<bool>>>,
    /// Per case with a free angle: e^{imδ}.
    polar: Arc<Vec<Option<Vec<Complex64>>>>,
    /// The chain factor H(m·f_rev)·e^{imδ}.
    h: Vec<Vec<Vec<Complex64>>>,
    /// The six coefficient-gradient harmonics of the rigid model.
    g: Arc<Vec<Vec<Vec<[Complex64; 6]>>>>,
    /// The measured rows ([`HarmonicProblem::measured_rows`]).
    y: Arc<DVector<f64>>,
}

#[derive(Clone)]
struct HarmonicProblem<'a> {
    cases: &'a [WaveformCase],
    data: Vec<CaseData>,
    models: Vec<RevolutionModel>,
    coef_idx: Vec<usize>,
    /// Coefficients held fixed (all of them, when `coef_idx` is empty).
    base_kc: [f64; 6],
    fit_tilt: bool,
    known: Option<MeasuringChain>,
    /// Fitted modes: axis per mode; parameters (ln f_n, ln ζ, g) in x (logs keep f_n, ζ > 0).
    mode_axes: Vec<FrameAxis>,
    fit_gain: bool,
    /// Gains of the modes when not fitted (kept out of x).
    fixed_gain: Vec<f64>,
    /// ln of the highest natural frequency allowed: 1.2 × the top of the lowest fitted band.
    max_mode_ln_hz: f64,
    /// Parameters: e (µm, 2) [, τ (µm/mm, 2)], coefficients, modes (3 each), δ (rad) per free case.
    x: DVector<f64>,
    /// Harmonics of the six basis sums per case: [r][k].
    basis: Vec<Vec<Vec<Complex64>>>,
    planner_cache: Vec<std::sync::Arc<dyn realfft::RealToComplex<f64>>>,
    /// Oversampling of the model grid of `models` (stage 1 coarser than stage 2).
    oversample: usize,
    /// Rigid comparison: chain switched off (band kept).
    rigid: bool,
    /// Leave the runout columns of the Jacobian empty ([`RestProblem`]).
    freeze_runout: bool,
    /// Use only the harmonics k ≡ 0 (mod this number of teeth): to first order in ρ the runout
    /// adds nothing there (Σ_i cos(λ + 2πi/K) terms cancel), so the mode scan sees the chain
    /// without the runout misfit, which dominates the cost before the runout is found.
    tooth_harmonics_only: Option<usize>,
}

/// The fit with the runout held: coefficients, chain parameters and angle shifts only. On the
/// exact model (edge forces only where h > 0) the residuals are smooth in these, so LM works
/// there; the smooth model's edge forces where h ≤ 0 (e.g. near a down-milling exit, where the
/// smaller teeth's chip vanishes) otherwise leak into the damping (ζ 0.040 for 0.030).
struct RestProblem<'a> {
    p: HarmonicProblem<'a>,
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for RestProblem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        let nr = self.p.n_runout();
        self.p.x.rows_mut(nr, x.len()).copy_from(x);
    }
    fn params(&self) -> DVector<f64> {
        let nr = self.p.n_runout();
        self.p.x.rows(nr, self.p.x.len() - nr).into_owned()
    }
    fn residuals(&self) -> Option<DVector<f64>> {
        self.p.residuals()
    }
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let nr = self.p.n_runout();
        let j = self.p.jacobian()?;
        Some(j.columns(nr, j.ncols() - nr).into_owned())
    }
}

/// Alternate, on the exact model, a compass search of the runout (coefficients linear, the rest
/// held) and LM on everything but the runout; twice. Returns the evaluations.
/// Modes in `rescan` (those without a start value) are scanned again after each compass search:
/// with the runout close, a mode left in a local minimum by stage 1 (K = 2 at low feeds: y at
/// 7.6 kHz for 1.1 kHz) is found by its own scan.
fn refine_on_exact_model(
    p: &mut HarmonicProblem<'_>,
    rescan: &[usize],
    teeth: usize,
) -> Result<usize, IdentifyError> {
    let nr = p.n_runout();
    p.set_smooth(false);
    let dirs: Vec<Vec<f64>> = (0..nr)
        .map(|k| (0..nr).map(|j| if j == k { 1.0 } else { 0.0 }).collect())
        .collect();
    let mut evals = 0;
    for round in 0..2 {
        let step = if round == 0 {
            (0.05 * p.x[0].hypot(p.x[1])).max(0.5)
        } else {
            0.1
        };
        let x_runout: Vec<f64> = (0..nr).map(|i| p.x[i]).collect();
        // 0.02 µm: a tenth of the smallest runout SE of the round trips (0.18 µm)
        // each trial point on a copy of p: its cost depends on the runout only (the
        // coefficients are solved afresh), so the search may cost two points at once
        let here: &HarmonicProblem<'_> = p;
        let (xr, e) = compass_search(&x_runout, &dirs, step, 0.02, |t| {
            let mut q = here.clone();
            for (i, v) in t.iter().enumerate() {
                q.x[i] = *v;
            }
            q.recompute();
            q.profile_cost()
        });
        evals += e;
        for (i, v) in xr.iter().enumerate() {
            p.x[i] = *v;
        }
        p.recompute();
        if round == 0 {
            for &m in rescan {
                scan_modes(p, &[m], teeth, false);
            }
        }
        p.linear_coefficients()?;
        let mut rest = p.clone();
        rest.freeze_runout = true;
        let before = p.residual_vec().iter().map(|r| r * r).sum::<f64>();
        let (done, report) = LevenbergMarquardt::new()
            .with_patience(100)
            .minimize(RestProblem { p: rest });
        evals += report.number_of_evaluations;
        let after = 2.0 * report.objective_function;
        if !(done.p.x.iter().all(|v| v.is_finite()) && after <= before) {
            continue; // keep the compass result
        }
        let mut q = done.p;
        q.freeze_runout = false;
        *p = q;
    }
    Ok(evals)
}

impl HarmonicProblem<'_> {
    fn n_runout(&self) -> usize {
        if self.fit_tilt {
            4
        } else {
            2
        }
    }
    fn coef_start(&self) -> usize {
        self.n_runout()
    }
    fn mode_start(&self) -> usize {
        self.n_runout() + self.coef_idx.len()
    }
    /// Parameters per mode: ln f_n, ln ζ [, gain].
    fn per_mode(&self) -> usize {
        if self.fit_gain {
            3
        } else {
            2
        }
    }
    fn mode_offset(&self, m: usize) -> usize {
        self.mode_start() + self.per_mode() * m
    }
    fn angle_start(&self) -> usize {
        self.mode_start() + self.per_mode() * self.mode_axes.len()
    }
    fn set_gain(&mut self, m: usize, g: f64) {
        if self.fit_gain {
            let o = self.mode_offset(m) + 2;
            self.x[o] = g;
        } else {
            self.fixed_gain[m] = g;
        }
    }
    fn runout(&self) -> ([f64; 2], [f64; 2]) {
        self.runout_of(&self.x)
    }
    /// Runout offset (mm) and tilt (mm/mm) of parameters `x`.
    fn runout_of(&self, x: &DVector<f64>) -> ([f64; 2], [f64; 2]) {
        let e = [x[0] * 1e-3, x[1] * 1e-3];
        let t = if self.fit_tilt {
            [x[2] * 1e-3, x[3] * 1e-3]
        } else {
            [0.0; 2]
        };
        (e, t)
    }
    fn set_runout(&mut self, e: [f64; 2]) {
        self.x[0] = e[0] * 1e3;
        self.x[1] = e[1] * 1e3;
    }
    fn coefficients(&self) -> CuttingCoefficients {
        let mut a = self.base_kc;
        for (p, &i) in self.coef_idx.iter().enumerate() {
            a[i] = self.x[self.coef_start() + p];
        }
        CuttingCoefficients::from_array(a)
    }
    fn mode(&self, m: usize) -> SensorMode {
        let o = self.mode_offset(m);
        // bounded: f_n within the fitted band (a mode above it is not seen in the record, and the
        // oversampled model would otherwise let a sharp one fold into the band: z at 20 kHz on a
        // 10 kHz record), ζ 1e-4..2 so that a wild solver step cannot overflow
        SensorMode {
            frequency_hz: self.x[o].clamp(0.0, self.max_mode_ln_hz).exp(),
            damping: self.x[o + 1].clamp(-9.2, 0.7).exp(),
            gain: if self.fit_gain {
                self.x[o + 2]
            } else {
                self.fixed_gain[m]
            },
        }
    }
    fn set_smooth(&mut self, smooth: bool) {
        for m in &mut self.models {
            m.edge_in_window = smooth;
        }
        self.recompute();
    }
    /// Basis sums and their harmonics at the current runout.
    fn recompute(&mut self) {
        let (e, t) = self.runout();
        self.basis = self.basis_at(e, t);
    }
    /// Basis harmonics of every case at runout offset `e` (mm) and tilt `t` (mm/mm).
    fn basis_at(&self, e: [f64; 2], t: [f64; 2]) -> Vec<Vec<Vec<Complex64>>> {
        (0..self.models.len())
            .map(|c| {
                let s = self.models[c].base_sums(e, t);
                self.basis_harmonics(c, &s)
            })
            .collect()
    }
    /// Harmonics 0..=L·N/2 of the [`NB`] basis sums on the oversampled grid, scaled by 1/L so
    /// that they compare with an N-point DFT. On a cylinder only rows 0–5 are transformed (rows
    /// 6–9 repeat rows 0–3, rows 10–15 are zero: `model` module docs).
    fn basis_harmonics(&self, c: usize, s: &BasisSums) -> Vec<Vec<Complex64>> {
        let fft = &self.planner_cache[c];
        let flat = self.models[c].is_flat();
        let transform = |r: usize| -> Vec<Complex64> {
            let mut buf: Vec<f64> = s.base.iter().map(|b| b[r]).collect();
            let mut out = fft.make_output_vec();
            fft.process(&mut buf, &mut out).expect("fft length");
            out.iter().map(|v| v / self.oversample as f64).collect()
        };
        if flat {
            let mut rows: Vec<Vec<Complex64>> = (0..6).map(transform).collect();
            let zero = vec![Complex64::new(0.0, 0.0); rows[0].len()];
            for r in 0..4 {
                rows.push(rows[r].clone());
            }
            rows.resize(NB, zero);
            rows
        } else {
            (0..NB).map(transform).collect()
        }
    }
    /// What N-point sampling makes of a real signal with harmonics Y_m (m = 0..=L·N/2) at
    /// harmonic k, times the resampling attenuation S_k:
    /// X_k = S_k·(Σ_{j≥0} Y_{k+jN} + Σ_{j≥1} conj(Y_{jN−k})).
    fn fold(&self, c: usize, k: usize, y: impl Fn(usize) -> Complex64) -> Complex64 {
        let d = &self.data[c];
        let top = self.oversample * d.n / 2;
        let mut sum = Complex64::new(0.0, 0.0);
        let mut m = k;
        while m <= top {
            sum += y(m);
            m += d.n;
        }
        let mut m = d.n;
        while m >= k && m - k <= top {
            sum += y(m - k).conj();
            m += d.n;
        }
        sum * d.interp[k]
    }
    /// [`HarmonicProblem::fold`] of the six coefficient-gradient columns at once (the same sums
    /// in the same order: identical values), H and the gradient read from the tables `t`.
    fn fold_gradient(
        &self,
        c: usize,
        k: usize,
        h: &[Complex64],
        g: &[[Complex64; 6]],
    ) -> [Complex64; 6] {
        let d = &self.data[c];
        let top = self.oversample * d.n / 2;
        let mut sum = [Complex64::new(0.0, 0.0); 6];
        let mut add = |m: usize, conj: bool| {
            let (h, g) = (h[m], &g[m]);
            for i in 0..6 {
                let v = h * g[i];
                sum[i] += if conj { v.conj() } else { v };
            }
        };
        let mut m = k;
        while m <= top {
            add(m, false);
            m += d.n;
        }
        let mut m = d.n;
        while m >= k && m - k <= top {
            add(m - k, true);
            m += d.n;
        }
        sum.map(|v| v * d.interp[k])
    }
    /// The true harmonics m (0..=L·N/2) of case c that the fitted rows fold
    /// ([`HarmonicProblem::fold`] over the rows' k).
    fn folded_harmonics(&self, c: usize) -> Vec<bool> {
        let d = &self.data[c];
        let top = self.oversample * d.n / 2;
        let mut used = vec![false; top + 1];
        for k in 0..=d.kmax {
            if self.tooth_harmonics_only.is_some_and(|t| k % t != 0) {
                continue;
            }
            let mut m = k;
            while m <= top {
                used[m] = true;
                m += d.n;
            }
            let mut m = d.n;
            while m >= k && m - k <= top {
                used[m - k] = true;
                m += d.n;
            }
        }
        used
    }
    /// The chain factor and the coefficient-gradient harmonics of every component at every
    /// folded harmonic m, and the measured rows, computed once per evaluation of the current
    /// parameters (the design matrix, the residuals and the chain columns all read them; the
    /// same values as computing them where used).
    fn tables(&self) -> Tables {
        self.tables_for(&self.basis)
    }
    /// [`HarmonicProblem::tables`] with the basis harmonics `basis` (of another runout).
    fn tables_for(&self, basis: &[Vec<Vec<Complex64>>]) -> Tables {
        let zero = Complex64::new(0.0, 0.0);
        let used: Vec<Vec<bool>> = (0..self.data.len())
            .map(|c| self.folded_harmonics(c))
            .collect();
        // e^{imδ}: one per harmonic, shared by the components
        let polar: Vec<Option<Vec<Complex64>>> = (0..self.data.len())
            .map(|c| {
                self.data[c].free_angle.map(|i| {
                    let delta = self.x[self.angle_start() + i];
                    used[c]
                        .iter()
                        .enumerate()
                        .map(|(m, &u)| {
                            if u {
                                Complex64::from_polar(1.0, m as f64 * delta)
                            } else {
                                zero
                            }
                        })
                        .collect()
                })
            })
            .collect();
        let g = self.at_used_harmonics(&used, [zero; 6], |c, axis, m| {
            gradient_harmonic(&basis[c], axis, m)
        });
        let (y, _) = self.measured_rows();
        let (used, polar) = (Arc::new(used), Arc::new(polar));
        Tables {
            h: self.chain_factors(&used, &polar),
            used,
            polar,
            g: Arc::new(g),
            y: Arc::new(DVector::from_vec(y)),
        }
    }
    /// `t` with the chain factors of the current modes: valid for a candidate that changed the
    /// modes `ms` only (not the runout, the angles, the chain's other parts or the rows). Only
    /// the components on the axes of `ms` are computed again (a per-axis scan changes one axis
    /// of three); the others keep `t`'s factors, which are what [`HarmonicProblem::factor_with`]
    /// gives for them, as no mode of their axis changed (the same values, bit for bit).
    fn with_modes(&self, t: &Tables, ms: &[usize]) -> Tables {
        let modes: Vec<SensorMode> = (0..self.mode_axes.len()).map(|m| self.mode(m)).collect();
        let changed: Vec<FrameAxis> = ms.iter().map(|&m| self.mode_axes[m]).collect();
        let h = (0..self.data.len())
            .map(|c| {
                let comps = &self.cases[c].waveform.components;
                comps
                    .iter()
                    .zip(&t.h[c])
                    .map(|(comp, old)| {
                        if !changed.contains(&comp.axis) {
                            return old.clone();
                        }
                        at_used(&t.used[c], Complex64::new(0.0, 0.0), |m| {
                            self.factor_with(c, comp.axis, m, t.polar[c].as_deref(), &modes)
                        })
                    })
                    .collect()
            })
            .collect();
        Tables {
            h,
            used: Arc::clone(&t.used),
            polar: Arc::clone(&t.polar),
            g: Arc::clone(&t.g),
            y: Arc::clone(&t.y),
        }
    }
    /// The chain factor [`HarmonicProblem::factor_with`] of every component at the folded
    /// harmonics `used`.
    fn chain_factors(
        &self,
        used: &[Vec<bool>],
        polar: &[Option<Vec<Complex64>>],
    ) -> Vec<Vec<Vec<Complex64>>> {
        let modes: Vec<SensorMode> = (0..self.mode_axes.len()).map(|m| self.mode(m)).collect();
        self.at_used_harmonics(used, Complex64::new(0.0, 0.0), |c, axis, m| {
            self.factor_with(c, axis, m, polar[c].as_deref(), &modes)
        })
    }
    /// `f(case, axis, m)` for every case, every component of its waveform and every folded
    /// harmonic m that `used` marks, `zero` at the others: the layout of [`Tables`]' per-harmonic
    /// tables.
    fn at_used_harmonics<T: Clone>(
        &self,
        used: &[Vec<bool>],
        zero: T,
        f: impl Fn(usize, FrameAxis, usize) -> T,
    ) -> Vec<Vec<Vec<T>>> {
        (0..self.data.len())
            .map(|c| {
                self.cases[c]
                    .waveform
                    .components
                    .iter()
                    .map(|comp| at_used(&used[c], zero.clone(), |m| f(c, comp.axis, m)))
                    .collect()
            })
            .collect()
    }
    /// H(m·f_rev)·e^{imδ} of case c, axis, true harmonic m (only e^{imδ} for the rigid
    /// comparison). A measured FRF is held at its last value above its range. `polar` holds
    /// e^{imδ} per m when the case has a free angle, `modes` the current fitted modes.
    fn factor_with(
        &self,
        c: usize,
        axis: FrameAxis,
        k: usize,
        polar: Option<&[Complex64]>,
        modes: &[SensorMode],
    ) -> Complex64 {
        let d = &self.data[c];
        let mut h = Complex64::new(1.0, 0.0);
        if let Some(p) = polar {
            h *= p[k];
        }
        if self.rigid {
            return h;
        }
        let f = k as f64 * d.spindle_hz;
        if let Some(chain) = &self.known {
            h *= chain.axis(axis).response_clamped(f);
        }
        if let Some(m) = self.mode_axes.iter().position(|&a| a == axis) {
            let mode = &modes[m];
            h *= Complex64::new(1.0 - mode.gain, 0.0) + mode.unit_response(f) * mode.gain;
        }
        h
    }
    /// Chain and angle shift on the rigid-model harmonics, H(m)·Σ_i g_i(m)·K_i, at every folded
    /// harmonic m of the component's tables `t`.
    fn chained_model(h: &[Complex64], g: &[[Complex64; 6]], kc: &[f64; 6]) -> Vec<Complex64> {
        h.iter()
            .zip(g)
            .map(|(h, g)| *h * (0..6).map(|i| g[i] * kc[i]).sum::<Complex64>())
            .collect()
    }
    fn n_residuals(&self) -> usize {
        let mut n = 0;
        self.rows(|_, _, k, _| n += if k > 0 { 2 } else { 1 });
        n
    }
    /// Visit every residual row: (case, component index, harmonic, scale of re/im rows).
    fn rows(&self, mut f: impl FnMut(usize, usize, usize, f64)) {
        for (c, d) in self.data.iter().enumerate() {
            for comp in 0..d.measured.len() {
                for k in 0..=d.kmax {
                    if self.tooth_harmonics_only.is_some_and(|t| k % t != 0) {
                        continue;
                    }
                    let s = if k == 0 { 1.0 } else { 2f64.sqrt() }
                        / (d.n as f64).sqrt()
                        / d.weight[comp];
                    f(c, comp, k, s);
                }
            }
        }
    }
    /// Push the rows of a complex value (re, and im for k > 0).
    fn push(out: &mut Vec<f64>, v: Complex64, k: usize, s: f64) {
        out.push(v.re * s);
        if k > 0 {
            out.push(v.im * s);
        }
    }
    fn residual_vec(&self) -> Vec<f64> {
        self.residual_vec_with(&self.tables())
    }
    /// Residuals with the tables of the current parameters ([`HarmonicProblem::tables`]).
    fn residual_vec_with(&self, tables: &Tables) -> Vec<f64> {
        let y = Self::chained_models(tables, &self.coefficients().to_array());
        let mut out = Vec::with_capacity(self.n_residuals());
        self.rows(|c, comp, k, s| {
            let ym = &y[c][comp];
            let v = self.fold(c, k, |m| ym[m]);
            Self::push(&mut out, v - self.data[c].measured[comp][k], k, s);
        });
        out
    }
    /// [`HarmonicProblem::chained_model`] of every component: [case][component][m].
    fn chained_models(t: &Tables, kc: &[f64; 6]) -> Vec<Vec<Vec<Complex64>>> {
        t.h.iter()
            .zip(t.g.iter())
            .map(|(hc, gc)| {
                hc.iter()
                    .zip(gc)
                    .map(|(h, g)| Self::chained_model(h, g, kc))
                    .collect()
            })
            .collect()
    }
    /// Measured rows (for R²) and the per-row "mean" part (k = 0 rows).
    fn measured_rows(&self) -> (Vec<f64>, Vec<bool>) {
        let mut out = Vec::new();
        let mut dc = Vec::new();
        self.rows(|c, comp, k, s| {
            Self::push(&mut out, self.data[c].measured[comp][k], k, s);
            dc.resize(out.len(), k == 0);
        });
        (out, dc)
    }
    /// Design matrix of the coefficients (chain included), from the tables of the current
    /// parameters.
    fn coefficient_design(&self, tables: &Tables) -> DMatrix<f64> {
        let mut x = DMatrix::zeros(self.n_residuals(), self.coef_idx.len());
        self.coefficient_design_rows(tables, &mut x, None);
        x
    }
    /// The rows of [`HarmonicProblem::coefficient_design`] written into `x`: those of the
    /// components on `axes` only, or all of them (`None`); the other rows are left as they are.
    fn coefficient_design_rows(
        &self,
        tables: &Tables,
        x: &mut DMatrix<f64>,
        axes: Option<&[FrameAxis]>,
    ) {
        let mut row = 0;
        self.rows(|c, comp, k, s| {
            let axis = self.cases[c].waveform.components[comp].axis;
            if axes.is_none_or(|a| a.contains(&axis)) {
                let folded = self.fold_gradient(c, k, &tables.h[c][comp], &tables.g[c][comp]);
                for (j, &i) in self.coef_idx.iter().enumerate() {
                    let v = folded[i];
                    x[(row, j)] = v.re * s;
                    if k > 0 {
                        x[(row + 1, j)] = v.im * s;
                    }
                }
            }
            row += if k > 0 { 2 } else { 1 };
        });
    }
    fn linear_coefficients(&mut self) -> Result<(), IdentifyError> {
        if self.coef_idx.is_empty() {
            return Ok(());
        }
        let tables = self.tables();
        self.linear_coefficients_with(&tables)
    }
    /// The coefficients solved linearly, with the tables of the current parameters (which do
    /// not depend on the coefficients: they stay valid after the solve).
    fn linear_coefficients_with(&mut self, tables: &Tables) -> Result<(), IdentifyError> {
        if self.coef_idx.is_empty() {
            return Ok(());
        }
        let x = self.coefficient_design(tables);
        let beta = linear_lsq_beta("coefficients", x, &tables.y)?;
        let c0 = self.coef_start();
        for c in 0..self.coef_idx.len() {
            self.x[c0 + c] = beta[c];
        }
        Ok(())
    }
    /// The profile cost of a mode-scan candidate (its coefficients solved and set, as
    /// [`HarmonicProblem::profile_cost_with`] does), cheaper:
    ///
    /// * the coefficients by the normal equations (XᵀX)β = Xᵀy (Cholesky) instead of the SVD,
    ///   when κ(XᵀX) ≤ ‖XᵀX‖_F‖(XᵀX)⁻¹‖_F < 1e20 proves κ(X) < 1e10, far inside the SVD's rank
    ///   test (1e-12); otherwise by the SVD, with its errors. The scan only compares costs: at a
    ///   least-squares optimum the cost is stationary in β, so the β error of the normal
    ///   equations (relative κ(X)²·ε ≈ 1e-10 at κ(X) ~ 1e3) moves the cost by its square — far
    ///   below the differences between grid points — and every fit that reports coefficients
    ///   solves them again by the SVD afterwards;
    /// * the cost as ‖y − Xβ‖² through the design X already built (one product of an n × p
    ///   matrix), where [`HarmonicProblem::residual_vec_with`] evaluates and folds the chained
    ///   model again (a tenth of a mode scan's time). The two are the same residuals summed in
    ///   another order when the coefficients held out of X are zero, as they are whenever
    ///   coefficients are fitted (`base_kc` is zero outside `coef_idx`); otherwise the model's
    ///   own residuals are used.
    /// * with `base`, the design of the scan's base tables and the axes whose modes the
    ///   candidate moved: only those axes' rows are built again, the others copied (the same
    ///   values, as their chain factors are the base's: [`HarmonicProblem::with_modes`]).
    ///
    /// An error (nothing set) when the linear solve fails.
    fn scan_cost(
        &mut self,
        tables: &Tables,
        base: Option<(&DMatrix<f64>, &[FrameAxis])>,
    ) -> Result<f64, IdentifyError> {
        let model_cost = |p: &mut Self| {
            p.linear_coefficients_with(tables)?;
            Ok(p.residual_vec_with(tables).iter().map(|r| r * r).sum())
        };
        let held_out_zero = (0..6)
            .filter(|i| !self.coef_idx.contains(i))
            .all(|i| self.base_kc[i] == 0.0);
        if self.coef_idx.is_empty() || !held_out_zero {
            return model_cost(self);
        }
        let x = match base {
            Some((design, axes)) => {
                let mut x = design.clone();
                self.coefficient_design_rows(tables, &mut x, Some(axes));
                x
            }
            None => self.coefficient_design(tables),
        };
        let a = x.tr_mul(&x);
        let beta = a.clone().cholesky().and_then(|chol| {
            let bound = a.norm() * chol.inverse().norm();
            (bound < 1e20).then(|| chol.solve(&x.tr_mul(&tables.y)))
        });
        let Some(beta) = beta else {
            return model_cost(self);
        };
        let c0 = self.coef_start();
        for c in 0..self.coef_idx.len() {
            self.x[c0 + c] = beta[c];
        }
        Ok((&*tables.y - x * beta).norm_squared())
    }
    fn profile_cost(&mut self) -> f64 {
        let tables = self.tables();
        self.profile_cost_with(&tables)
    }
    /// [`HarmonicProblem::profile_cost`] with the tables of the current parameters.
    fn profile_cost_with(&mut self, tables: &Tables) -> f64 {
        match self.linear_coefficients_with(tables) {
            Ok(()) => self.residual_vec_with(tables).iter().map(|r| r * r).sum(),
            Err(_) => f64::INFINITY,
        }
    }
    /// Columns of the chain parameters and angle shifts, analytic.
    fn chain_columns(&self, j: &mut DMatrix<f64>, tables: &Tables) {
        let as_ = self.angle_start();
        let y_all = Self::chained_models(tables, &self.coefficients().to_array());
        let mut row = 0;
        self.rows(|c, comp, k, s| {
            let axis = self.cases[c].waveform.components[comp].axis;
            let mut put = |col: usize, v: Complex64| {
                j[(row, col)] = v.re * s;
                if k > 0 {
                    j[(row + 1, col)] = v.im * s;
                }
            };
            let ym = &y_all[c][comp];
            let y = |m: usize| ym[m];
            if let Some(mi) = self.mode_axes.iter().position(|&a| a == axis) {
                let mode = self.mode(mi);
                let f = |m: usize| m as f64 * self.data[c].spindle_hz;
                // everything but this mode's factor, times the derivative of that factor
                let rest = |m: usize| {
                    let h =
                        Complex64::new(1.0 - mode.gain, 0.0) + mode.unit_response(f(m)) * mode.gain;
                    y(m) / h
                };
                let o = self.mode_offset(mi);
                // parameters ln f_n, ln ζ: ∂/∂ln x = x·∂/∂x
                put(
                    o,
                    self.fold(c, k, |m| {
                        rest(m)
                            * mode.unit_response_derivatives(f(m)).0
                            * mode.gain
                            * mode.frequency_hz
                    }),
                );
                put(
                    o + 1,
                    self.fold(c, k, |m| {
                        rest(m) * mode.unit_response_derivatives(f(m)).1 * mode.gain * mode.damping
                    }),
                );
                if self.fit_gain {
                    put(
                        o + 2,
                        self.fold(c, k, |m| rest(m) * (mode.unit_response(f(m)) - 1.0)),
                    );
                }
            }
            if let Some(i) = self.data[c].free_angle {
                put(
                    as_ + i,
                    self.fold(c, k, |m| y(m) * Complex64::new(0.0, m as f64)),
                );
            }
            row += if k > 0 { 2 } else { 1 };
        });
    }
}

impl HarmonicProblem<'_> {
    /// The residuals at x ± [`RUNOUT_STEP_UM`] along each of the first `cols` runout
    /// parameters, in the order (+, −) per parameter: only the basis changes, the rest of x is
    /// kept. The 2·`cols` evaluations are independent: in parallel (two contiguous halves on
    /// two threads), gathered in order.
    fn runout_differences(&self, cols: usize) -> Vec<Vec<f64>> {
        let g = grouping();
        (0..2 * cols)
            .into_par_iter()
            .with_min_len(cols.max(1))
            .map(|i| {
                let _g = GroupingScope::new(g);
                let mut x = self.x.clone();
                x[i / 2] += if i % 2 == 0 {
                    RUNOUT_STEP_UM
                } else {
                    -RUNOUT_STEP_UM
                };
                let (e, t) = self.runout_of(&x);
                self.residual_vec_with(&self.tables_for(&self.basis_at(e, t)))
            })
            .collect()
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for HarmonicProblem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        let moved = (0..self.n_runout()).any(|i| x[i] != self.x[i]);
        self.x.copy_from(x);
        if moved || self.basis.is_empty() {
            self.recompute();
        }
    }
    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }
    fn residuals(&self) -> Option<DVector<f64>> {
        let r = DVector::from_vec(self.residual_vec());
        r.iter().all(|v| v.is_finite()).then_some(r)
    }
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let n = self.n_residuals();
        let np = self.x.len();
        let mut j = DMatrix::zeros(n, np);
        // runout columns: central differences (see RUNOUT_STEP_UM)
        let runout_cols = if self.freeze_runout {
            0
        } else {
            self.n_runout()
        };
        // (the runout differences and the tables at x are independent: in parallel)
        let (cols, tables) =
            join_grouped(|| self.runout_differences(runout_cols), || self.tables());
        for (p, pm) in cols.chunks(2).enumerate() {
            for (r, (a, b)) in pm[0].iter().zip(&pm[1]).enumerate() {
                j[(r, p)] = (a - b) / (2.0 * RUNOUT_STEP_UM);
            }
        }
        let design = self.coefficient_design(&tables);
        j.columns_mut(self.coef_start(), self.coef_idx.len())
            .copy_from(&design);
        self.chain_columns(&mut j, &tables);
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}

/// Highest harmonic of case c: below Nyquist, within a band limit and a measured FRF's range.
fn max_harmonic(n: usize, spindle_hz: f64, model: &ChainModel, axes: &[FrameAxis]) -> usize {
    let mut kmax = (n - 1) / 2;
    match model {
        ChainModel::BandLimit { max_harmonic } => kmax = kmax.min(*max_harmonic),
        ChainModel::Known(chain) => {
            for &a in axes {
                if let AxisChain::Frf(f) = chain.axis(a) {
                    kmax = kmax.min((f.max_frequency_hz() / spindle_hz).floor() as usize);
                }
            }
        }
        ChainModel::FitModes { .. } => {}
    }
    kmax
}

fn case_data(
    case: &WaveformCase,
    opts: &ChainOptions,
    c: usize,
    free_index: Option<usize>,
    planner: &mut RealFftPlanner<f64>,
) -> Result<CaseData, IdentifyError> {
    let n = case.waveform.validate()?;
    let spindle_hz = opts.spindle_hz[c];
    if !(spindle_hz.is_finite() && spindle_hz > 0.0) {
        return Err(IdentifyError::too_few(
            "chain fit",
            "a spindle frequency > 0 Hz per recording",
            spindle_hz,
        ));
    }
    let axes: Vec<FrameAxis> = case.waveform.components.iter().map(|k| k.axis).collect();
    let kmax = max_harmonic(n, spindle_hz, &opts.model, &axes);
    let fft = planner.plan_fft_forward(n);
    let measured = case
        .waveform
        .components
        .iter()
        .map(|comp| {
            let mut buf = comp.values.clone();
            let mut out = fft.make_output_vec();
            fft.process(&mut buf, &mut out).expect("fft length");
            out.truncate(kmax + 1);
            out
        })
        .collect();
    let weight = case
        .waveform
        .components
        .iter()
        .map(|comp| {
            comp.se.as_ref().map_or(1.0, |s| {
                (s.iter().map(|v| v * v).sum::<f64>() / s.len() as f64).sqrt()
            })
        })
        .collect::<Vec<f64>>();
    let all_se = case.waveform.components.iter().all(|k| k.se.is_some());
    let interp = (0..=kmax)
        .map(|k| match opts.samples_per_rev[c] {
            Some(spr) if k > 0 => {
                let x = PI * k as f64 / spr;
                (x.sin() / x).powi(2)
            }
            _ => 1.0,
        })
        .collect();
    Ok(CaseData {
        n,
        kmax,
        spindle_hz,
        interp,
        measured,
        weight: if all_se {
            weight
        } else {
            vec![1.0; axes.len()]
        },
        free_angle: free_index,
    })
}

/// Start values of the modes without one: a scan of f_n from the tooth-passing frequency to
/// 0.9 × Nyquist (121 log-spaced points, ζ 0.03 and 0.1 — a broad mode finds a resonance between
/// two harmonics that a sharp one misses — gain 1), coefficients solved linearly at each point:
/// first one frequency shared by all those modes (every axis's evidence at once), then each
/// mode on its own, kept only where it lowers the cost (axes with different modes).
/// Returns true when the scan lowered the cost below that of the current values.
fn scan_modes(p: &mut HarmonicProblem<'_>, which: &[usize], teeth: usize, per_axis: bool) -> bool {
    if which.is_empty() {
        return false;
    }
    let current: Vec<(f64, f64)> = which
        .iter()
        .map(|&m| (p.x[p.mode_offset(m)], p.x[p.mode_offset(m) + 1]))
        .collect();
    let gains: Vec<f64> = which.iter().map(|&m| p.mode(m).gain).collect();
    let start_cost = p.profile_cost();
    let lo = p
        .data
        .iter()
        .map(|d| d.spindle_hz * teeth as f64)
        .fold(f64::INFINITY, f64::min);
    let hi = p
        .data
        .iter()
        .map(|d| 0.9 * d.spindle_hz * d.kmax as f64)
        .fold(0.0, f64::max)
        .max(2.0 * lo);
    let grid: Vec<(f64, f64)> = [0.03f64, 0.1]
        .iter()
        .flat_map(|&z| (0..=120).map(move |s| (lo * (hi / lo).powf(s as f64 / 120.0), z)))
        .collect();
    let set = |p: &mut HarmonicProblem<'_>, ms: &[usize], f: f64, z: f64| {
        for &m in ms {
            let o = p.mode_offset(m);
            p.x[o] = f.ln();
            p.x[o + 1] = z.ln();
            p.set_gain(m, 1.0);
        }
    };
    let scan = |p: &mut HarmonicProblem<'_>, ms: &[usize], mut best: (f64, f64, f64)| {
        for (&(f, z), &c) in grid.iter().zip(&grid_costs(p, ms, &grid, &set)) {
            if c < best.0 {
                best = (c, f, z);
            }
        }
        set(p, ms, best.1, best.2);
        best
    };
    let joint = scan(p, which, (f64::INFINITY, lo, 0.03));
    let improved = |p: &mut HarmonicProblem<'_>, best: f64| {
        if best < start_cost * (1.0 - 1e-3) {
            return true;
        }
        for (i, &m) in which.iter().enumerate() {
            let o = p.mode_offset(m);
            p.x[o] = current[i].0;
            p.x[o + 1] = current[i].1;
            p.set_gain(m, gains[i]);
        }
        false
    };
    if !per_axis {
        return improved(p, joint.0);
    }
    for &m in which {
        let here = (joint.0, joint.1, joint.2);
        let best = scan(p, &[m], here);
        set(p, &[m], best.1, best.2);
    }
    let end = p.profile_cost();
    improved(p, end)
}

/// Profile cost at each grid point (f_n, ζ) of the modes `ms`, in grid order, and p left as
/// the serial loop `for (f, z) in grid { set(p, ms, f, z); p.profile_cost() }` leaves it: the
/// modes at the last point and the coefficients of the last successful linear solve. Each
/// point's cost depends on the modes, runout and angles only (the coefficients are solved
/// afresh), so the points are evaluated in parallel (rayon, one clone of p per task) and the
/// costs come back in grid order: the same numbers, bit for bit, at any thread count.
fn grid_costs(
    p: &mut HarmonicProblem<'_>,
    ms: &[usize],
    grid: &[(f64, f64)],
    set: &(impl Fn(&mut HarmonicProblem<'_>, &[usize], f64, f64) + Sync),
) -> Vec<f64> {
    // the candidates change the modes only: the rest of the tables is computed once, and the
    // design's rows of the axes without a moved mode
    let base = p.tables();
    let axes: Vec<FrameAxis> = ms.iter().map(|&m| p.mode_axes[m]).collect();
    let design = (!p.coef_idx.is_empty()).then(|| p.coefficient_design(&base));
    let reuse = design.as_ref().map(|d| (d, &axes[..]));
    if rayon::current_num_threads() <= 1 || grid.len() < 2 {
        return grid
            .iter()
            .map(|&(f, z)| {
                set(p, ms, f, z);
                let t = p.with_modes(&base, ms);
                p.scan_cost(&t, reuse).unwrap_or(f64::INFINITY)
            })
            .collect();
    }
    let (c0, nk) = (p.coef_start(), p.coef_idx.len());
    let shared: &HarmonicProblem<'_> = p;
    let base = &base;
    let evaluated: Vec<(f64, Option<Vec<f64>>)> = grid
        .par_iter()
        .map_init(
            || shared.clone(),
            |q, &(f, z)| {
                set(q, ms, f, z);
                let tables = q.with_modes(base, ms);
                match q.scan_cost(&tables, reuse) {
                    Ok(c) => (c, Some((0..nk).map(|i| q.x[c0 + i]).collect())),
                    Err(_) => (f64::INFINITY, None),
                }
            },
        )
        .collect();
    if let Some(&(f, z)) = grid.last() {
        set(p, ms, f, z);
    }
    if let Some(kc) = evaluated.iter().rev().find_map(|(_, k)| k.as_ref()) {
        for (i, v) in kc.iter().enumerate() {
            p.x[c0 + i] = *v;
        }
    }
    evaluated.into_iter().map(|(c, _)| c).collect()
}

/// Basis harmonics of the rigid model at runout parameters (e [, τ]) already evaluated: the
/// runout scan visits the same candidates up to three times with different chain parameters,
/// and the basis depends on the runout (and the smooth/exact switch, fixed during the scans)
/// only — so each candidate's model is evaluated once (identical results, a third of the work).
type BasisCache = Vec<(Vec<f64>, Vec<Vec<Vec<Complex64>>>)>;

/// Profile cost at each candidate runout vector (the rest of x as it is), best first, and p
/// left as the serial loop over the candidates leaves it (the last candidate's runout and
/// basis, the coefficients of the last successful linear solve). The candidates are
/// independent (the coefficients are solved afresh at each): their bases and costs are
/// evaluated in parallel (rayon, one clone of p per task) and gathered in candidate order —
/// the same numbers at any thread count.
fn scan_runouts(
    p: &mut HarmonicProblem<'_>,
    candidates: &[[f64; 2]],
    cache: &mut BasisCache,
) -> Vec<(f64, DVector<f64>)> {
    /// Per candidate: its key, the basis when not cached, the cost, x after the solve and
    /// whether the solve succeeded.
    type Evaluated = (
        Vec<f64>,
        Option<Vec<Vec<Vec<Complex64>>>>,
        f64,
        DVector<f64>,
        bool,
    );
    let nr = p.n_runout();
    let (c0, nk) = (p.coef_start(), p.coef_idx.len());
    let shared: &HarmonicProblem<'_> = p;
    let cached: &BasisCache = cache;
    let g = grouping();
    let evaluated: Vec<Evaluated> = candidates
        .par_iter()
        .map_init(
            || shared.clone(),
            |q, &e| {
                let _g = GroupingScope::new(g);
                q.set_runout(e);
                let key: Vec<f64> = (0..nr).map(|i| q.x[i]).collect();
                // (the tables straight from the cached basis, or from the one computed here,
                // which is then handed out rather than copied: only the tables read the basis)
                let (tables, fresh) = match cached.iter().find(|(k, _)| *k == key) {
                    Some((_, b)) => (q.tables_for(b), None),
                    None => {
                        q.recompute();
                        (q.tables(), Some(std::mem::take(&mut q.basis)))
                    }
                };
                let solved = q.linear_coefficients_with(&tables).is_ok();
                let c = if solved {
                    q.residual_vec_with(&tables).iter().map(|r| r * r).sum()
                } else {
                    f64::INFINITY
                };
                (key, fresh, c, q.x.clone(), solved)
            },
        )
        .collect();
    let mut scored: Vec<(f64, DVector<f64>)> = Vec::new();
    let mut last_kc: Option<Vec<f64>> = None;
    let mut last_key: Option<Vec<f64>> = None;
    for (key, fresh, c, x, solved) in evaluated {
        // the cache as the serial loop fills it (a key repeated among the candidates is
        // stored once, with the basis of its first evaluation: the same values)
        if let Some(b) = fresh {
            if !cache.iter().any(|(k, _)| *k == key) {
                cache.push((key.clone(), b));
            }
        }
        if solved {
            last_kc = Some((0..nk).map(|i| x[c0 + i]).collect());
        }
        last_key = Some(key);
        if c.is_finite() {
            scored.push((c, x));
        }
    }
    // p's runout and basis as the serial loop leaves them: the last candidate's (its basis is
    // in the cache now; copied once, not at every candidate)
    if let Some(key) = last_key {
        for (i, v) in key.iter().enumerate() {
            p.x[i] = *v;
        }
        p.basis = cache
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, b)| b.clone())
            .unwrap_or_default();
    }
    if let Some(kc) = last_kc {
        for (i, v) in kc.iter().enumerate() {
            p.x[c0 + i] = *v;
        }
    }
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    scored
}

/// The chain-aware full-signal fit; called by [`super::full_signal_fit`] when
/// [`FullSignalOptions::chain`] is set.
pub(crate) fn harmonic_fit(
    cases: &[WaveformCase],
    options: &FullSignalOptions,
    chain: &ChainOptions,
    disks: usize,
) -> Result<FullSignalFit, IdentifyError> {
    let nc = cases.len();
    if chain.spindle_hz.len() != nc
        || chain.samples_per_rev.len() != nc
        || chain.free_start_angle.len() != nc
    {
        return Err(IdentifyError::too_few(
            "chain fit",
            format!("spindle speed, samples per revolution and angle flag for {nc} recordings"),
            chain.spindle_hz.len(),
        ));
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let mut free = 0;
    let mut data = Vec::with_capacity(nc);
    for (c, case) in cases.iter().enumerate() {
        let idx = chain.free_start_angle[c].then(|| {
            free += 1;
            free - 1
        });
        data.push(case_data(case, chain, c, idx, &mut planner)?);
    }
    let has_z = cases
        .iter()
        .any(|c| c.waveform.components.iter().any(|k| k.axis == FrameAxis::Z));
    let coef_idx: Vec<usize> = if options.fixed_coefficients.is_some() {
        vec![]
    } else if has_z {
        vec![0, 1, 2, 3, 4, 5]
    } else {
        vec![0, 1, 3, 4]
    };
    type ModeStarts = Vec<(FrameAxis, Option<SensorMode>)>;
    let (known, mode_starts, fit_gain): (Option<MeasuringChain>, ModeStarts, bool) =
        match &chain.model {
            ChainModel::Known(c) => (Some(c.clone()), vec![], false),
            ChainModel::FitModes { axes, fit_gain } => (None, axes.clone(), *fit_gain),
            ChainModel::BandLimit { .. } => (None, vec![], false),
        };
    let nr = if options.fit_tilt { 4 } else { 2 };
    let per_mode = if fit_gain { 3 } else { 2 };
    let np = nr + coef_idx.len() + per_mode * mode_starts.len() + free;
    let build = |disks: usize, ovs: usize| -> Vec<RevolutionModel> {
        cases
            .iter()
            .map(|c| {
                RevolutionModel::new(
                    &c.cutter,
                    &c.cut,
                    c.waveform.start_angle,
                    ovs * c.waveform.samples(),
                    disks,
                )
            })
            .collect()
    };
    let models = build(disks, OVERSAMPLE);
    // Stage 1 (scans and LM from rough starts) runs on a model with 5× coarser disks (helix lag
    // ≤ 0.5° per disk): it only has to bring every parameter near the optimum, which stage 2
    // then refines on the full model (the compass search and LM there are local). Measured on
    // the five-feed 2-flute bench: fitted-mode fit 3.9 s → 0.79 s together with the stage-2
    // changes below (docs/measuring-chain.md, "Speed").
    // (and on a 2× instead of 4× oversampled grid: 4× is needed for the final accuracy — 2×
    // left ζ 9 % high in the K = 4 round trip — but not to get near the optimum)
    let coarse = build((disks / 5).max(1), COARSE_OVERSAMPLE);
    let mut plans = |ovs: usize| -> Vec<_> {
        data.iter()
            .map(|d| planner.plan_fft_forward(ovs * d.n))
            .collect()
    };
    let planner_cache = plans(OVERSAMPLE);
    let coarse_plans = plans(COARSE_OVERSAMPLE);
    let mut p = HarmonicProblem {
        cases,
        data,
        models,
        coef_idx: coef_idx.clone(),
        base_kc: options.fixed_coefficients.unwrap_or([0.0; 6]),
        fit_tilt: options.fit_tilt,
        known,
        mode_axes: mode_starts.iter().map(|m| m.0).collect(),
        fit_gain,
        fixed_gain: vec![1.0; mode_starts.len()],
        max_mode_ln_hz: 16.1,
        x: DVector::zeros(np),
        basis: Vec::new(),
        planner_cache,
        oversample: OVERSAMPLE,
        rigid: false,
        freeze_runout: false,
        tooth_harmonics_only: None,
    };
    p.max_mode_ln_hz = p
        .data
        .iter()
        .map(|d| (1.2 * d.kmax as f64 * d.spindle_hz).ln())
        .fold(16.1, f64::min);
    let n = p.n_residuals();
    if n <= np {
        return Err(IdentifyError::too_few(
            "chain fit",
            format!("more than {np} harmonic residuals (raise the band limit)"),
            n,
        ));
    }
    // modes without a start value begin switched off (gain 0) until their scan
    for (m, (_, start)) in mode_starts.iter().enumerate() {
        let s = start.unwrap_or(SensorMode {
            frequency_hz: 1000.0,
            damping: 0.03,
            gain: 0.0,
        });
        let o = p.mode_offset(m);
        p.x[o] = s.frequency_hz.ln();
        p.x[o + 1] = s.damping.ln();
        p.set_gain(m, s.gain);
    }
    // Start values: runout from the frequency-domain estimate (harmonic 1 is far below any
    // sensor mode), coefficients linear; modes without a start value scanned; then the runout scan.
    let full_models = std::mem::replace(&mut p.models, coarse);
    let full_plans = std::mem::replace(&mut p.planner_cache, coarse_plans);
    p.oversample = COARSE_OVERSAMPLE;
    p.set_smooth(true);
    p.linear_coefficients()?;
    let mut e_start = options.initial_runout.unwrap_or([0.0; 2]);
    let initial = frequency_estimate(cases, &p.coefficients(), disks).ok();
    if let (Some(f), None) = (initial, options.initial_runout) {
        e_start = f.vector;
    }
    p.set_runout(e_start);
    p.recompute();
    let teeth = cases[0].cutter.teeth();
    // Mode scans first, at zero runout: the chain shapes the tooth-passing harmonics, which the
    // runout hardly changes, while a runout start from the frequency estimate can be far off on
    // resonant data (46 µm for 10 µm in the K = 2 round trip) and a sharp mode scanned there
    // loses to a broad one. Then the runout scan with the modes in (rings of 3, 10 and 30 µm
    // besides the usual ones around the start values).
    let unstarted: Vec<usize> = (0..mode_starts.len())
        .filter(|&m| mode_starts[m].1.is_none())
        .collect();
    if !unstarted.is_empty() {
        p.set_runout([0.0; 2]);
        p.recompute();
        p.tooth_harmonics_only = Some(teeth);
        scan_modes(&mut p, &unstarted, teeth, false);
        p.tooth_harmonics_only = None;
    }
    let mut candidates = vec![e_start];
    if let Some(f) = initial {
        candidates.push(f.vector);
    }
    candidates.extend(candidate_runouts(&candidates));
    for r in [0.003, 0.010, 0.030] {
        candidates.extend(
            candidate_runouts(&[[r / 1.5, 0.0]])
                .into_iter()
                .skip(16)
                .take(16),
        );
    }
    let mut starts = Vec::new();
    let mut cache = BasisCache::new();
    let scored = scan_runouts(&mut p, &candidates, &mut cache);
    if unstarted.is_empty() {
        // LM from the best scan point, and from the second when its cost is comparable (2×):
        // with edge skipping (large ρ, K = 2) the cost has local minima
        let best = scored.first().map_or(f64::INFINITY, |s| s.0);
        starts.extend(scored.into_iter().take(2).filter(|s| s.0 <= 2.0 * best));
    } else {
        // At low feeds the runout clips the smaller tooth's chip, which changes the tooth
        // harmonics too: scan the modes again at the best runout (all harmonics), once with one
        // frequency for all axes and once per axis (axes with different modes), then the runout
        // again; LM from both.
        for per_axis in [false, true] {
            if let Some((_, x)) = scored.first() {
                p.x.copy_from(x);
                p.recompute();
            }
            scan_modes(&mut p, &unstarted, teeth, per_axis);
            if let Some(best) = scan_runouts(&mut p, &candidates, &mut cache)
                .into_iter()
                .next()
            {
                starts.push(best);
            }
        }
    }
    let mut best: Option<(
        HarmonicProblem<'_>,
        levenberg_marquardt::MinimizationReport<f64>,
    )> = None;
    // (the solves from the starts are independent: in parallel, compared in start order)
    let g = grouping();
    let runs: Vec<_> = distinct_starts(starts.iter().collect())
        .into_par_iter()
        .with_max_len(1)
        .map(|(_, x)| {
            let _g = GroupingScope::new(g);
            let mut start = p.clone();
            start.x.copy_from(x);
            start.recompute();
            LevenbergMarquardt::new().with_patience(200).minimize(start)
        })
        .collect();
    for (done, report) in runs {
        if best
            .as_ref()
            .is_none_or(|(_, r)| report.objective_function < r.objective_function)
        {
            best = Some((done, report));
        }
    }
    let (mut p, report) =
        best.ok_or_else(|| IdentifyError::singular("chain fit", "no valid start value"))?;
    // Stage 2: exact model (see [`refine_on_exact_model`]).
    p.models = full_models;
    p.planner_cache = full_plans;
    p.oversample = OVERSAMPLE;
    p.recompute();
    p.linear_coefficients()?;
    let evals = refine_on_exact_model(&mut p, &unstarted, teeth)?;
    let raw = p.residual_vec();
    // Covariance: Jacobian on the smooth model at the solution (see the time-domain fit).
    // (runout columns from the smooth model: the exact model's differences also catch its
    // edge-force steps, which carry no information per sample; the rest from the exact model).
    // (the exact model's Jacobian without its runout columns, which the smooth model's replace,
    // and the smooth model's runout differences, which do not need its basis at x: in parallel)
    let mut exact = p.clone();
    exact.freeze_runout = true;
    let mut smooth = p.clone();
    for m in &mut smooth.models {
        m.edge_in_window = true;
    }
    let singular = || IdentifyError::singular("chain fit", "non-finite Jacobian");
    let (jac, smooth_cols) = join_grouped(|| exact.jacobian(), || smooth.runout_differences(nr));
    let mut jac = jac.ok_or_else(singular)?;
    for (c, pm) in smooth_cols.chunks(2).enumerate() {
        for (r, (a, b)) in pm[0].iter().zip(&pm[1]).enumerate() {
            jac[(r, c)] = (a - b) / (2.0 * RUNOUT_STEP_UM);
        }
    }
    if !jac.iter().all(|v| v.is_finite()) {
        return Err(singular());
    }
    let res = DVector::from_vec(raw.clone());
    let groups = harmonic_groups(&p.data.iter().map(|d| d.kmax).collect::<Vec<_>>(), &{
        cases
            .iter()
            .map(|c| c.waveform.components.len())
            .collect::<Vec<_>>()
    });
    let cov = fit_covariance(&jac, &res, &groups);
    // R² of the band about each component's mean: the k = 0 rows are the means.
    let (meas, dc) = p.measured_rows();
    let tss: f64 = meas
        .iter()
        .zip(&dc)
        .filter(|(_, d)| !**d)
        .map(|(v, _)| v * v)
        .sum();
    let rss: f64 = raw.iter().map(|r| r * r).sum();
    // Rigid comparison: same band, chain off, coefficients and runout re-solved linearly at the
    // chain fit's runout (profile), angle shifts kept.
    let mut rig = p.clone();
    rig.rigid = true;
    let rigid_rss = rig.profile_cost();
    let rigid_r2 = 1.0 - rigid_rss / tss;

    let mut names: Vec<String> = vec!["ex_um".into(), "ey_um".into()];
    if options.fit_tilt {
        names.extend(["tilt_x_um_per_mm".into(), "tilt_y_um_per_mm".into()]);
    }
    names.extend(coef_idx.iter().map(|&i| NAMES[i].to_string()));
    for a in &p.mode_axes {
        let ax = format!("{a:?}").to_lowercase();
        names.extend([format!("mode_{ax}_ln_hz"), format!("mode_{ax}_ln_damping")]);
        if fit_gain {
            names.push(format!("mode_{ax}_gain"));
        }
    }
    for (c, d) in p.data.iter().enumerate() {
        if d.free_angle.is_some() {
            names.push(format!("start_angle_shift_{c}_rad"));
        }
    }
    let se = |i: usize| cov.se(i);
    let modes = (0..p.mode_axes.len())
        .map(|m| {
            let o = p.mode_offset(m);
            let mode = p.mode(m);
            FittedMode {
                axis: p.mode_axes[m],
                frequency_hz: Estimate {
                    value: mode.frequency_hz,
                    se: Some(se(o) * mode.frequency_hz),
                },
                damping: Estimate {
                    value: mode.damping,
                    se: Some(se(o + 1) * mode.damping),
                },
                gain: Estimate {
                    value: mode.gain,
                    se: fit_gain.then(|| se(o + 2)),
                },
            }
        })
        .collect();
    let shifts = p
        .data
        .iter()
        .map(|d| match d.free_angle {
            Some(i) => Estimate {
                value: p.x[p.angle_start() + i],
                se: Some(se(p.angle_start() + i)),
            },
            None => Estimate {
                value: 0.0,
                se: None,
            },
        })
        .collect();
    let kind = match &chain.model {
        ChainModel::FitModes { .. } => "fitted_modes",
        ChainModel::BandLimit { .. } => "band_limit",
        ChainModel::Known(c)
            if [&c.x, &c.y, &c.z]
                .iter()
                .any(|a| matches!(a, AxisChain::Frf(_))) =>
        {
            "measured_frf"
        }
        ChainModel::Known(_) => "stated_modes",
    };
    let report_chain = ChainFitReport {
        kind: kind.into(),
        max_harmonic: p.data.iter().map(|d| d.kmax).collect(),
        modes,
        start_angle_shift: shifts,
        rigid_r_squared: rigid_r2,
    };
    let (e, tau) = p.runout();
    let mut coefficients = p.base_kc;
    let mut coefficient_se = [None; 6];
    for (j, &i) in coef_idx.iter().enumerate() {
        coefficients[i] = p.x[nr + j];
        coefficient_se[i] = Some(se(nr + j));
    }
    let mut fit = fit_summary(FitSummaryInput {
        e,
        tau: options.fit_tilt.then_some(tau),
        cov: &cov,
        runout_dirs: &[[1.0, 0.0], [0.0, 1.0]],
        coefficients,
        coefficient_se,
        parameters: names,
        rss,
        tss,
        n,
        np,
        evaluations: report.number_of_evaluations + evals,
        termination: format!("{:?}", report.termination),
        converged: report.termination.was_successful(),
        initial,
        disks,
        observability: RunoutObservability::Full,
        has_z,
    });
    fit.chain = Some(report_chain);
    Ok(fit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::AveragedWaveform;
    use crate::{ArcChip, Cut, Cutter, ForceModel, MillingMode, Runout, Sampling};

    /// One revolution of the K = 4 down-milling cut (ρ 8 µm) in x, y, z, 180 bins.
    fn case() -> WaveformCase {
        let cutter = Cutter::flat(10.0, 4, 30f64.to_radians()).unwrap();
        let cut = Cut::new(3240.0, 0.05, 2.0)
            .unwrap()
            .radial(2.0, MillingMode::Down, &cutter)
            .unwrap();
        let kc = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, 3.1]).unwrap();
        let runout = Runout::new(0.008, -50f64.to_radians()).unwrap();
        let m = ForceModel {
            cutter: cutter.clone(),
            runout,
            cut,
            coefficients: kc,
        };
        let chip = ArcChip::new(&cutter, &runout, 0.05).unwrap();
        let s = m.simulate(&chip, &Sampling::new(1.0, 2.0, 50).unwrap());
        let waveform = AveragedWaveform::average(
            0.0,
            180,
            &[
                (FrameAxis::X, &s.fx[..180]),
                (FrameAxis::Y, &s.fy[..180]),
                (FrameAxis::Z, &s.fz[..180]),
            ],
        )
        .unwrap();
        WaveformCase {
            cutter,
            cut,
            waveform,
        }
    }

    /// A stage-1 problem on `cases` with one fitted mode per axis (x, y, z), at ρ 8 µm.
    fn problem(cases: &[WaveformCase]) -> HarmonicProblem<'_> {
        let axes = [FrameAxis::X, FrameAxis::Y, FrameAxis::Z];
        let chain = ChainOptions {
            model: ChainModel::FitModes {
                axes: axes.iter().map(|&a| (a, None)).collect(),
                fit_gain: false,
            },
            spindle_hz: vec![54.0],
            samples_per_rev: vec![Some(185.2)],
            free_start_angle: vec![false],
        };
        let mut planner = RealFftPlanner::<f64>::new();
        let data = vec![case_data(&cases[0], &chain, 0, None, &mut planner).unwrap()];
        let c = &cases[0];
        let models = vec![RevolutionModel::new(
            &c.cutter,
            &c.cut,
            c.waveform.start_angle,
            COARSE_OVERSAMPLE * c.waveform.samples(),
            10,
        )];
        let np = 2 + 6 + 2 * axes.len();
        let mut p = HarmonicProblem {
            cases,
            data,
            models,
            coef_idx: vec![0, 1, 2, 3, 4, 5],
            base_kc: [0.0; 6],
            fit_tilt: false,
            known: None,
            mode_axes: axes.to_vec(),
            fit_gain: false,
            fixed_gain: vec![1.0; axes.len()],
            max_mode_ln_hz: 16.1,
            x: DVector::zeros(np),
            basis: Vec::new(),
            planner_cache: vec![planner.plan_fft_forward(COARSE_OVERSAMPLE * 180)],
            oversample: COARSE_OVERSAMPLE,
            rigid: false,
            freeze_runout: false,
            tooth_harmonics_only: None,
        };
        for (m, f) in [900.0f64, 1300.0, 2500.0].iter().enumerate() {
            let o = p.mode_offset(m);
            p.x[o] = f.ln();
            p.x[o + 1] = 0.03f64.ln();
        }
        let lambda = (-50f64).to_radians();
        p.set_runout([0.008 * lambda.cos(), 0.008 * lambda.sin()]);
        p.set_smooth(true);
        p
    }

    /// The mode scans' shortcuts against the full computations, with each axis's mode moved in
    /// turn and all three at once: the chain factors of [`HarmonicProblem::with_modes`] equal
    /// the tables computed afresh bit for bit, the design with the unmoved axes' rows copied
    /// gives the same cost and coefficients bit for bit, and [`HarmonicProblem::scan_cost`] gives the
    /// profile cost (SVD solve, model residuals) to 1e-9 relative and its coefficients to 1e-7
    /// (the normal equations' κ²ε at κ ~ 1e3, with margin).
    #[test]
    fn mode_scan_shortcuts_equal_the_full_computations() {
        let cases = [case()];
        let p = problem(&cases);
        let base = p.tables();
        let moves: [&[usize]; 4] = [&[0], &[1], &[2], &[0, 1, 2]];
        for (i, ms) in moves.iter().enumerate() {
            let mut q = p.clone();
            for &m in *ms {
                let o = q.mode_offset(m);
                q.x[o] = (700.0 + 450.0 * (i + m) as f64).ln();
                q.x[o + 1] = 0.05f64.ln();
            }
            let quick = q.with_modes(&base, ms);
            let full = q.tables();
            assert_eq!(quick.h, full.h, "modes {ms:?}");
            // a stale axis would be caught: the unchanged axes really differ between modes
            assert_ne!(base.h, full.h);
            // the design's rows of the unmoved axes copied from the base design: the same bits
            let axes: Vec<FrameAxis> = ms.iter().map(|&m| q.mode_axes[m]).collect();
            let design = q.coefficient_design(&base);
            let mut r = q.clone();
            let reused = r.scan_cost(&quick, Some((&design, &axes))).unwrap();
            let mut a = q.clone();
            let cost = a.scan_cost(&full, None).unwrap();
            assert_eq!(reused.to_bits(), cost.to_bits(), "modes {ms:?}");
            assert_eq!(r.x, a.x);
            let mut b = q.clone();
            let want = b.profile_cost_with(&full);
            assert!((cost - want).abs() <= 1e-9 * want, "{cost} vs {want}");
            for c in 0..6 {
                let (x, y) = (a.x[2 + c], b.x[2 + c]);
                assert!((x - y).abs() <= 1e-7 * y.abs().max(1.0), "K{c}: {x} vs {y}");
            }
        }
    }
}
