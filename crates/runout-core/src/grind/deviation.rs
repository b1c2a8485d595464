//! Deviation map: the seed's per-layer deviation δ_ij, the per-layer first harmonic, the fitted
//! bar axis (offset + tilt) and the residual form error (methods.md §5.2, §5.5).

use super::probe::{Layer, ProbeGrid};
use crate::fit::{fit_offset_tilt, LineNoise, LinearLsq, OffsetTiltFit};
use nalgebra::{DMatrix, DVector};

/// Deviations of one layer.
#[derive(Debug, Clone, PartialEq)]
pub struct LayerDeviation {
    /// Axial position u_i (mm).
    pub u: f64,
    /// Probe angles α_j (rad), ascending in [0, 2π).
    pub alpha: Vec<f64>,
    /// Seed deviation δ_ij = R_ij − (R_i,max + R_i,min)/2 (mm), methods.md §5.2.
    pub delta: Vec<f64>,
    /// R_i,avg = (R_i,max + R_i,min)/2 (mm).
    pub r_avg: f64,
    /// Mean radius a_i of the first-harmonic fit (mm).
    pub mean: f64,
    /// First-harmonic cosine coefficient c_i (mm): for a uniform grid c_i = (2/C)Σ_j R_ij cos α_j
    /// (methods.md §5.5); computed by least squares so that irregular angles also work.
    pub c: f64,
    /// First-harmonic sine coefficient s_i (mm), likewise.
    pub s: f64,
    /// RMS of the residual form error R_ij − (a_i + c_i cos α_j + s_i sin α_j) (mm).
    pub form_rms: f64,
    /// Largest |residual form error| (mm).
    pub form_max: f64,
    /// Condition number of the per-layer harmonic fit (√2 for a uniform grid).
    pub condition: f64,
}

/// The deviation map of a probe grid.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviationMap {
    /// Per-layer deviations, in increasing u.
    pub layers: Vec<LayerDeviation>,
    /// Fitted bar axis: the least-squares line e(u) = e₀ + u·τ through the per-layer first
    /// harmonics, (c_i, s_i) ≈ e(u_i) because R_ij ≈ R + e(u_i)·(cos α_j, sin α_j) (methods.md §5.2);
    /// standard errors from the residual scatter of each component (`None` with only 2 layers);
    /// `residuals` are the per-layer (c_i, s_i) − e(u_i).
    pub axis: OffsetTiltFit,
}

impl DeviationMap {
    /// Compute δ_ij, the first harmonics and the axis fit from a probe grid.
    ///
    /// ```
    /// use runout_core::grind::{DeviationMap, Generatrix, ProbeGrid};
    /// let alpha: Vec<f64> = (0..8).map(|j| j as f64 * std::f64::consts::TAU / 8.0).collect();
    /// let u = [5.0, 10.0, 15.0];
    /// // pure offset of 10 µm along x: R_ij ≈ 3 + 0.01 cos α_j
    /// let r: Vec<Vec<f64>> = u.iter().map(|_| alpha.iter().map(|a| 3.0 + 0.01 * a.cos()).collect()).collect();
    /// let grid = ProbeGrid::from_radii(&u, &alpha, &r, Generatrix::cylinder(3.0).unwrap()).unwrap();
    /// let map = DeviationMap::new(&grid);
    /// assert!((map.axis.offset[0].value - 0.01).abs() < 1e-12 && map.axis.tilt[0].value.abs() < 1e-12);
    /// ```
    pub fn new(grid: &ProbeGrid) -> Self {
        let layers: Vec<LayerDeviation> = grid.layers.iter().map(layer_deviation).collect();
        let axis = fit_axis(&layers);
        DeviationMap { layers, axis }
    }

    /// Axial positions u_i (mm).
    pub fn u(&self) -> Vec<f64> {
        self.layers.iter().map(|l| l.u).collect()
    }

    /// Largest |δ_ij| over the grid (mm).
    pub fn max_abs_delta(&self) -> f64 {
        self.layers
            .iter()
            .flat_map(|l| l.delta.iter())
            .fold(0.0, |m, d| m.max(d.abs()))
    }
}

fn layer_deviation(l: &Layer) -> LayerDeviation {
    let (lo, hi) = l
        .radius
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
            (lo.min(*r), hi.max(*r))
        });
    let r_avg = 0.5 * (lo + hi);
    let delta = l.radius.iter().map(|r| r - r_avg).collect();
    let n = l.alpha.len();
    let a = DMatrix::from_fn(n, 3, |j, k| match k {
        0 => 1.0,
        1 => l.alpha[j].cos(),
        _ => l.alpha[j].sin(),
    });
    let b = DVector::from_column_slice(&l.radius);
    let lsq = LinearLsq::new(a);
    let condition = lsq.condition();
    let x = lsq
        .beta(&b, 1e-12 * lsq.smax())
        .unwrap_or_else(|_| DVector::from_element(3, f64::NAN));
    let res = &b - lsq.design() * &x;
    let form_rms = (res.norm_squared() / n as f64).sqrt();
    let form_max = res.amax();
    LayerDeviation {
        u: l.u,
        alpha: l.alpha.clone(),
        delta,
        r_avg,
        mean: x[0],
        c: x[1],
        s: x[2],
        form_rms,
        form_max,
        condition,
    }
}

/// Least squares of (c_i, s_i) on [1, u_i] ([`fit_offset_tilt`]); a grid is built with ≥ 2
/// layers, a hand-made one with fewer gets an undetermined (`NaN`) axis.
fn fit_axis(layers: &[LayerDeviation]) -> OffsetTiltFit {
    let points: Vec<(f64, [f64; 2])> = layers.iter().map(|l| (l.u, [l.c, l.s])).collect();
    fit_offset_tilt(&points, &LineNoise::PerComponent)
        .unwrap_or_else(|_| OffsetTiltFit::undetermined(layers.len()))
}
