//! Spindle angle of an averaged waveform when the recording has no absolute angle reference.
//!
//! Without a once-per-revolution mark whose angle to tooth 0 is known, the synchronous average
//! starts at an arbitrary spindle angle θ₀. The full-signal fit needs θ₀ (tooth 0's tip at
//! immersion θ at bin 0, `conventions.md`): an error δ rotates the projection of tangential and
//! radial forces, so K_rc absorbs ≈ K_tc·δ (0.5° ≈ 2 % of K_rc).
//!
//! 1. [`harmonic_start_angle`]: the tooth-passing harmonic is runout-free in the linear chip model
//!    (methods.md §4.7: F_K = K·f_t·Q_K), and a shift θ₀ multiplies the model's harmonic P_K by
//!    e^{jKθ₀}; so θ₀ = arg(Σ_c M_K,c·conj(P_K,c))/K modulo 2π/K, with the branch nearest a
//!    reference angle (the one that keeps the caller's tooth numbering).
//! 2. [`refine_start_angle`]: given runout, the model is linear in the six coefficients, so the
//!    residual after a linear least-squares solve is a cheap function of θ₀; a grid over ±w and a
//!    parabola through the best three points give θ₀ to a small fraction of a degree.

use super::model::{
    coefficient_gradient, force_from_basis, grouping, with_grouping, RevolutionModel,
};
use super::waveform::{FrameAxis, WaveformCase};
use crate::angle::wrap_pi;
use crate::coefficients::CuttingCoefficients;
use crate::fit::{fourier_coefficient, LinearLsq};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Axial disks for alignment evaluations: 0.1° of helix lag per disk and at least
/// [`crate::edge::min_disks`] (as the full-signal fit's automatic choice), at most 2000.
fn disks(case: &WaveformCase) -> usize {
    let lag = case.cut.ap() * case.cutter.tan_helix().abs() / case.cutter.radius();
    ((lag / 0.1f64.to_radians()).ceil() as usize)
        .max(crate::edge::min_disks(&case.cutter, &case.cut))
        .clamp(1, 2000)
}

/// Model forces per axis on the waveform's grid starting at `start` (rad).
pub fn model_forces(
    case: &WaveformCase,
    start: f64,
    e: [f64; 2],
    tau: [f64; 2],
    kc: &CuttingCoefficients,
) -> [Vec<f64>; 3] {
    let n = case.waveform.samples();
    let b = RevolutionModel::new(&case.cutter, &case.cut, start, n, disks(case))
        .base_sums(e, tau)
        .base;
    let f = |ax| {
        b.iter()
            .map(|s| force_from_basis(ax, s, kc))
            .collect::<Vec<_>>()
    };
    [f(FrameAxis::X), f(FrameAxis::Y), f(FrameAxis::Z)]
}

/// k-th Fourier coefficient of one revolution of bins ([`fourier_coefficient`]).
fn harmonic(v: &[f64], k: usize) -> (f64, f64) {
    let n = v.len() as f64;
    fourier_coefficient(
        v.iter().copied(),
        (0..v.len()).map(|j| TAU * (k * j) as f64 / n),
    )
}

/// θ₀ from the tooth-passing harmonic of the measured F_x, F_y against the model with runout `e`,
/// tilt `tau` and coefficients `kc` (only the ratios matter), on the branch nearest `reference`.
///
/// ```
/// use runout_core::*;
/// use runout_core::identify::{harmonic_start_angle, AveragedWaveform, FrameAxis, WaveformCase};
/// let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
/// let cut = Cut::new(3000.0, 0.08, 2.0).unwrap().radial(2.0, MillingMode::Down, &cutter).unwrap();
/// let kc = CuttingCoefficients::new([2000.0, 800.0, 300.0], [60.0, 100.0, 0.0]).unwrap();
/// let m = ForceModel { cutter: cutter.clone(), runout: Runout::none(), cut, coefficients: kc };
/// let s = m.simulate(&ArcChip::new(&cutter, &Runout::none(), 0.08).unwrap(), &Sampling::new(1.0, 1.0, 400).unwrap());
/// // the same revolution seen from bin 0 at θ = 37°
/// let rot = |v: &[f64]| (0..360).map(|j| v[(j + 37) % 360]).collect::<Vec<_>>();
/// let w = AveragedWaveform::average(0.0, 360, &[(FrameAxis::X, &rot(&s.fx)), (FrameAxis::Y, &rot(&s.fy))]).unwrap();
/// let case = WaveformCase { cutter, cut, waveform: w };
/// // the harmonic estimate is approximate (edge-force steps, disk discretisation): within 0.1°
/// let t0 = harmonic_start_angle(&case, [0.0; 2], [0.0; 2], &kc, 0.6);
/// assert!((t0.to_degrees() - 37.0).abs() < 0.1);
/// // the residual refinement pins it to a small fraction of the 1° sample spacing
/// let (t1, _) = runout_core::identify::refine_start_angle(&case, t0, 1f64.to_radians(), [0.0; 2], [0.0; 2]);
/// assert!((t1.to_degrees() - 37.0).abs() < 0.02);
/// ```
pub fn harmonic_start_angle(
    case: &WaveformCase,
    e: [f64; 2],
    tau: [f64; 2],
    kc: &CuttingCoefficients,
    reference: f64,
) -> f64 {
    let k = case.cutter.teeth();
    let model = model_forces(case, 0.0, e, tau, kc);
    let (mut re, mut im) = (0.0, 0.0);
    for c in &case.waveform.components {
        let p = match c.axis {
            FrameAxis::X => &model[0],
            FrameAxis::Y => &model[1],
            FrameAxis::Z => continue,
        };
        let (mr, mi) = harmonic(&c.values, k);
        let (pr, pi) = harmonic(p, k);
        re += mr * pr + mi * pi;
        im += mi * pr - mr * pi;
    }
    let base = im.atan2(re) / k as f64;
    (0..k)
        .map(|n| base + TAU * n as f64 / k as f64)
        .min_by(|a, b| {
            wrap_pi(a - reference)
                .abs()
                .total_cmp(&wrap_pi(b - reference).abs())
        })
        .unwrap_or(base)
}

/// Residual sum of squares (N²) of the waveform against the model started at `start`, with the
/// coefficients solved by linear least squares for the given runout and tilt.
pub fn residual_at(case: &WaveformCase, start: f64, e: [f64; 2], tau: [f64; 2]) -> f64 {
    let n = case.waveform.samples();
    let b = RevolutionModel::new(&case.cutter, &case.cut, start, n, disks(case))
        .base_sums(e, tau)
        .base;
    // one design row per sample: ∂F/∂(K_tc, K_rc, K_ac, K_te, K_re, K_ae) from the shared basis
    // (`model` module docs; on a cylinder the x–y and z blocks decouple)
    let mut rows: Vec<[f64; 6]> = Vec::new();
    let mut y: Vec<f64> = Vec::new();
    for c in &case.waveform.components {
        for (q, v) in c.values.iter().enumerate() {
            rows.push(coefficient_gradient(c.axis, &b[q]));
            y.push(*v);
        }
    }
    lsq_rss(&rows, &y)
}

fn lsq_rss<const P: usize>(rows: &[[f64; P]], y: &[f64]) -> f64 {
    if rows.is_empty() {
        return 0.0;
    }
    let lsq = LinearLsq::new(DMatrix::from_fn(rows.len(), P, |r, c| rows[r][c]));
    let yv = DVector::from_column_slice(y);
    match lsq.solve(&yv, 1e-12) {
        Ok(fit) => fit.rss,
        Err(_) => yv.norm_squared(),
    }
}

/// θ₀ minimising [`residual_at`] within ±`half_width` (rad) of `start`: a 41-point grid, then a
/// second 41-point grid over ±2 steps around the best point, then a parabola through the best
/// point and its neighbours. The points of a grid are independent: they are costed in parallel
/// (rayon, one contiguous chunk per thread) and gathered in grid order. Returns (θ₀, RSS).
pub fn refine_start_angle(
    case: &WaveformCase,
    start: f64,
    half_width: f64,
    e: [f64; 2],
    tau: [f64; 2],
) -> (f64, f64) {
    const N: usize = 41;
    let (mut centre, mut width) = (start, half_width);
    let mut last = (start, f64::INFINITY, 0.0, [f64::NAN; 3]);
    for _ in 0..2 {
        let step = 2.0 * width / (N - 1) as f64;
        let grid: Vec<f64> = (0..N).map(|i| centre - width + step * i as f64).collect();
        // independent points: in parallel, gathered in grid order (the same numbers at any
        // thread count)
        let g = grouping();
        let rss: Vec<f64> = grid
            .par_iter()
            // (rayon splits a range while half of it is ≥ the minimum: 2 chunks on 2 threads)
            .with_min_len((N / rayon::current_num_threads()).max(1))
            .map(|&t| with_grouping(g, || residual_at(case, t, e, tau)))
            .collect();
        let best = (0..N)
            .min_by(|&a, &b| rss[a].total_cmp(&rss[b]))
            .unwrap_or(N / 2);
        let around = if best == 0 || best == N - 1 {
            [f64::NAN; 3]
        } else {
            [rss[best - 1], rss[best], rss[best + 1]]
        };
        last = (grid[best], rss[best], step, around);
        centre = grid[best];
        width = 2.0 * step;
    }
    let (t, r, step, [r0, r1, r2]) = last;
    let denom = r0 - 2.0 * r1 + r2;
    if denom.is_nan() || denom <= 0.0 {
        return (t, r);
    }
    let shift = (0.5 * (r0 - r2) / denom).clamp(-1.0, 1.0);
    let tp = t + shift * step;
    let rp = residual_at(case, tp, e, tau);
    if rp < r {
        (tp, rp)
    } else {
        (t, r)
    }
}
