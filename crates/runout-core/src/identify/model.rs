//! Fast one-revolution force model with analytic derivatives, for waveform fitting.
//!
//! Same discretisation and equations as [`crate::ForceModel::simulate`] with [`crate::ArcChip`]
//! (axial disks at mid-heights, arc chip h = max(0, min_m [f_{i,m} sin φ + R_i − R_{i−m}]) with
//! exact radii R_i(z) = |R(z)u(ψ_i(z)) + e₀ + zτ|, edge forces only where h > 0), evaluated on a
//! one-revolution grid θ_q = θ₀ + 2πq/N. Because the forces are linear in the six coefficients
//! once h is known, the model keeps per-sample **basis sums**
//!
//! S = [Σh·cos φ, Σh·sin φ, Σcos φ, Σsin φ, Σh, Σ1]·dz   (over teeth and disks in cut, h > 0)
//!
//! so that F_x = K_tc S₀ + K_rc S₁ + K_te S₂ + K_re S₃, F_y = −K_tc S₁ + K_rc S₀ − K_te S₃ + K_re S₂,
//! F_z = −K_ac S₄ − K_ae S₅ (forces on the workpiece, `force` module docs), plus the derivatives
//! of [Σh cos φ, Σh sin φ, Σh] w.r.t. the runout vector e₀ (and tilt τ):
//! ∂h/∂e = n_i − n_{i−m*}, n_i = (R u_i + e(z))/R_i, m* the active term of the min;
//! ∂h/∂τ = z·∂h/∂e. (The edge-force switch at h = 0 is not differentiated: measure zero.)

use super::waveform::Axis;
use crate::angle::wrap_tau;
use crate::coefficients::CuttingCoefficients;
use crate::cut::Cut;
use crate::cutter::Cutter;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Per (disk, tooth) geometry.
#[derive(Debug, Clone, Copy)]
struct Slice {
    psi: f64,
    cos_psi: f64,
    sin_psi: f64,
}

/// One-revolution evaluator for a cutter, cut and angle grid.
#[derive(Debug, Clone)]
pub struct RevolutionModel {
    k: usize,
    disks: usize,
    dz: f64,
    heights: Vec<f64>,
    /// R(z_j) per disk.
    radius: Vec<f64>,
    slices: Vec<Slice>,
    /// f_{i,m} = f_z·K·gap(i, m)/2π, index i*K + m − 1.
    feed: Vec<f64>,
    st: f64,
    width: f64,
    /// (θ, sin θ, cos θ) per grid sample.
    grid: Vec<(f64, f64, f64)>,
    /// Apply the edge forces over the whole engagement window instead of only where h > 0
    /// (default false = as the simulation). The window-gated variant is continuous in the
    /// runout; the full-signal fit uses it for its first stage (see `full_signal`).
    pub edge_in_window: bool,
}

/// Per-sample basis sums and runout derivatives (see module docs).
#[derive(Debug, Clone)]
pub struct BasisSums {
    /// `base[q]` = [Σh cos, Σh sin, Σcos, Σsin, Σh, Σ1]·dz.
    pub base: Vec<[f64; 6]>,
    /// `deriv[q][p]` = ∂[Σh cos, Σh sin, Σh]·dz/∂p for p = e_x, e_y (mm), then τ_x, τ_y (mm/mm).
    pub deriv: Vec<Vec<[f64; 3]>>,
}

impl RevolutionModel {
    /// Evaluator on the grid θ_q = `start_angle` + 2πq/`samples` with `disks` axial disks.
    pub fn new(cutter: &Cutter, cut: &Cut, start_angle: f64, samples: usize, disks: usize) -> Self {
        let k = cutter.teeth();
        let disks = disks.max(1);
        let dz = cut.ap() / disks as f64;
        let heights: Vec<f64> = (0..disks).map(|j| (j as f64 + 0.5) * dz).collect();
        let slices = heights
            .iter()
            .flat_map(|&z| {
                (0..k).map(move |i| {
                    let psi = cutter.tooth_angle(i, z);
                    Slice {
                        psi,
                        cos_psi: psi.cos(),
                        sin_psi: psi.sin(),
                    }
                })
            })
            .collect();
        let mut feed = Vec::with_capacity(k * k);
        for i in 0..k {
            for m in 1..=k {
                feed.push(cut.fz() * k as f64 * cutter.gap(i, m) / TAU);
            }
        }
        let (st, ex) = cut.immersion(cutter);
        let grid = (0..samples)
            .map(|q| {
                let t = start_angle + TAU * q as f64 / samples as f64;
                let (s, c) = t.sin_cos();
                (t, s, c)
            })
            .collect();
        RevolutionModel {
            k,
            disks,
            dz,
            radius: heights.iter().map(|&z| cutter.radius_at(z)).collect(),
            heights,
            slices,
            feed,
            st,
            width: ex - st,
            grid,
            edge_in_window: false,
        }
    }

    /// Number of grid samples.
    pub fn samples(&self) -> usize {
        self.grid.len()
    }

    /// Basis sums for runout offset `e` (mm) and tilt `tau` (mm/mm); `tilt_derivs` adds the
    /// τ derivatives.
    pub fn sums(&self, e: [f64; 2], tau: [f64; 2], tilt_derivs: bool) -> BasisSums {
        self.compute(e, tau, if tilt_derivs { 4 } else { 2 })
    }

    /// Basis sums only (no derivatives): `deriv` is empty per sample.
    pub fn base_sums(&self, e: [f64; 2], tau: [f64; 2]) -> BasisSums {
        self.compute(e, tau, 0)
    }

    /// Samples are independent: evaluated in parallel (rayon), `np` derivatives per sample.
    fn compute(&self, e: [f64; 2], tau: [f64; 2], np: usize) -> BasisSums {
        let k = self.k;
        // per disk: radii, unit normals, and the per-tooth active differences are sample-independent
        let mut dr = vec![0.0; self.disks * k * k];
        let mut dn = vec![[0.0f64; 2]; self.disks * k * k];
        for j in 0..self.disks {
            let z = self.heights[j];
            let ez = [e[0] + z * tau[0], e[1] + z * tau[1]];
            let r = self.radius[j];
            let pts: Vec<([f64; 2], f64)> = (0..k)
                .map(|i| {
                    let sl = &self.slices[j * k + i];
                    let p = [r * sl.cos_psi + ez[0], r * sl.sin_psi + ez[1]];
                    let ri = p[0].hypot(p[1]);
                    ([p[0] / ri, p[1] / ri], ri)
                })
                .collect();
            for i in 0..k {
                for m in 1..=k {
                    let o = (i + k * m - m) % k;
                    let idx = (j * k + i) * k + m - 1;
                    dr[idx] = pts[i].1 - pts[o].1;
                    dn[idx] = [pts[i].0[0] - pts[o].0[0], pts[i].0[1] - pts[o].0[1]];
                }
            }
        }
        // Each (disk, tooth) is in the engagement for one contiguous run of grid samples: visit
        // only that run (plus a guard sample each side) and apply the same exact test
        // `wrap(θ + ψ − φ_st) ≤ width` as the simulation. Disks in parallel (rayon), reduced.
        let n = self.grid.len();
        let dtheta = TAU / n as f64;
        let run = ((self.width / dtheta).floor() as usize + 3).min(n);
        let theta0 = self.grid.first().map(|g| g.0).unwrap_or(0.0);
        let empty = || (vec![[0.0f64; 6]; n], vec![[0.0f64; 3]; n * np]);
        let disk = |(mut b, mut d): (Vec<[f64; 6]>, Vec<[f64; 3]>), j: usize| {
            let z = self.heights[j];
            let dz = self.dz;
            for i in 0..k {
                let sl = &self.slices[j * k + i];
                let a = wrap_tau(theta0 + sl.psi - self.st);
                let first = ((TAU - a) / dtheta).floor() as i64 - 1;
                let base_idx = (j * k + i) * k;
                for t in 0..run {
                    let q = (first + t as i64).rem_euclid(n as i64) as usize;
                    let (theta, st_t, ct_t) = self.grid[q];
                    let rel = wrap_tau(theta + sl.psi - self.st);
                    if rel > self.width {
                        continue;
                    }
                    let s = st_t * sl.cos_psi + ct_t * sl.sin_psi;
                    let co = ct_t * sl.cos_psi - st_t * sl.sin_psi;
                    let mut h = f64::INFINITY;
                    let mut arg = 0;
                    for m in 0..k {
                        let v = self.feed[i * k + m] * s + dr[base_idx + m];
                        if v < h {
                            h = v;
                            arg = m;
                        }
                    }
                    if h <= 0.0 {
                        if self.edge_in_window {
                            let bq = &mut b[q];
                            bq[2] += co * dz;
                            bq[3] += s * dz;
                            bq[5] += dz;
                        }
                        continue;
                    }
                    let bq = &mut b[q];
                    bq[0] += h * co * dz;
                    bq[1] += h * s * dz;
                    bq[2] += co * dz;
                    bq[3] += s * dz;
                    bq[4] += h * dz;
                    bq[5] += dz;
                    let g = dn[base_idx + arg];
                    for (p, dp) in d[q * np..(q + 1) * np].iter_mut().enumerate() {
                        let gh = match p {
                            0 => g[0],
                            1 => g[1],
                            2 => z * g[0],
                            _ => z * g[1],
                        } * dz;
                        dp[0] += gh * co;
                        dp[1] += gh * s;
                        dp[2] += gh;
                    }
                }
            }
            (b, d)
        };
        let add = |(mut b1, mut d1): (Vec<[f64; 6]>, Vec<[f64; 3]>),
                   (b2, d2): (Vec<[f64; 6]>, Vec<[f64; 3]>)| {
            for (x, y) in b1.iter_mut().zip(&b2) {
                for r in 0..6 {
                    x[r] += y[r];
                }
            }
            for (x, y) in d1.iter_mut().zip(&d2) {
                for r in 0..3 {
                    x[r] += y[r];
                }
            }
            (b1, d1)
        };
        let (base, flat) = if self.disks >= 8 {
            (0..self.disks)
                .into_par_iter()
                .fold(empty, disk)
                .reduce(empty, add)
        } else {
            (0..self.disks).fold(empty(), disk)
        };
        let deriv = (0..n)
            .map(|q| flat[q * np..(q + 1) * np].to_vec())
            .collect();
        BasisSums { base, deriv }
    }
}

/// Force component `axis` (N) of sample sums `b` with coefficients `kc`.
#[inline]
pub fn force_from_basis(axis: Axis, b: &[f64; 6], kc: &CuttingCoefficients) -> f64 {
    match axis {
        Axis::X => kc.ktc * b[0] + kc.krc * b[1] + kc.kte * b[2] + kc.kre * b[3],
        Axis::Y => -kc.ktc * b[1] + kc.krc * b[0] - kc.kte * b[3] + kc.kre * b[2],
        Axis::Z => -kc.kac * b[4] - kc.kae * b[5],
    }
}

/// Derivatives ∂F_axis/∂(K_tc, K_rc, K_ac, K_te, K_re, K_ae) of sample sums `b`.
#[inline]
pub fn coefficient_gradient(axis: Axis, b: &[f64; 6]) -> [f64; 6] {
    match axis {
        Axis::X => [b[0], b[1], 0.0, b[2], b[3], 0.0],
        Axis::Y => [-b[1], b[0], 0.0, -b[3], b[2], 0.0],
        Axis::Z => [0.0, 0.0, -b[4], 0.0, 0.0, -b[5]],
    }
}

/// ∂F_axis/∂p from the runout derivative sums `d` = ∂[Σh cos, Σh sin, Σh]/∂p.
#[inline]
pub fn runout_gradient(axis: Axis, d: &[f64; 3], kc: &CuttingCoefficients) -> f64 {
    match axis {
        Axis::X => kc.ktc * d[0] + kc.krc * d[1],
        Axis::Y => -kc.ktc * d[1] + kc.krc * d[0],
        Axis::Z => -kc.kac * d[2],
    }
}
