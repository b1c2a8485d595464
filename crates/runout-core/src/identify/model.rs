//! Fast one-revolution force model with analytic derivatives, for waveform fitting.
//!
//! Same discretisation and equations as [`crate::ForceModel::simulate`] with [`crate::ArcChip`],
//! from the same per-disk table [`crate::edge::EdgeTable`] (axial disks at mid-heights, local
//! radius R(z), lead angle κ(z), chip width db = dz/sin κ and immersion window per disk; arc chip
//! h = max(0, min_m [f_{i,m} sin φ + R_i − R_{i−m}]) with exact radii
//! R_i(z) = |R(z)u(ψ_i(z)) + e₀ + zτ|, normal chip h·sin κ, edge forces only where h > 0),
//! evaluated on a one-revolution grid θ_q = θ₀ + 2πq/N. Because the forces are linear in the six
//! coefficients once h is known (and K_c·h sin κ·db = K_c·h·dz), the model keeps per-sample
//! **basis sums** ([`NB`] = 16; w = h·dz for the shear rows, w = db for the edge rows,
//! s_κ = sin κ, c_κ = cos κ):
//!
//! | row | sum | row | sum |
//! |---|---|---|---|
//! | 0 | Σ h dz cos φ | 8 | Σ s_κ db cos φ |
//! | 1 | Σ h dz sin φ | 9 | Σ s_κ db sin φ |
//! | 2 | Σ db cos φ | 10 | Σ c_κ h dz cos φ |
//! | 3 | Σ db sin φ | 11 | Σ c_κ h dz sin φ |
//! | 4 | Σ s_κ h dz | 12 | Σ c_κ db cos φ |
//! | 5 | Σ s_κ db | 13 | Σ c_κ db sin φ |
//! | 6 | Σ s_κ h dz cos φ | 14 | Σ c_κ h dz |
//! | 7 | Σ s_κ h dz sin φ | 15 | Σ c_κ db |
//!
//! so that (forces on the workpiece, [`crate::ForceModel::simulate`])
//!
//! F_x = K_tc S₀ + K_rc S₇ − K_ac S₁₁ + K_te S₂ + K_re S₉ − K_ae S₁₃,
//! F_y = −K_tc S₁ + K_rc S₆ − K_ac S₁₀ − K_te S₃ + K_re S₈ − K_ae S₁₂,
//! F_z = −K_rc S₁₄ − K_re S₁₅ − K_ac S₄ − K_ae S₅.
//!
//! On a cylinder (s_κ = 1, c_κ = 0, db = dz) rows 6–9 repeat rows 0–3, rows 10–15 vanish and rows
//! 0–5 are the six sums of the flat model [Σh cos φ, Σh sin φ, Σcos φ, Σsin φ, Σh, Σ1]·dz: the
//! flat kernel accumulates only those and fills the rest.
//! Derivatives w.r.t. the runout vector e₀ (and tilt τ) of the shear rows
//! [S₀, S₁, S₄, S₆, S₇, S₁₀, S₁₁, S₁₄] ([`ND`] = 8):
//! ∂h/∂e = n_i − n_{i−m*}, n_i = (R(z) u_i + e(z))/R_i, m* the active term of the min;
//! ∂h/∂τ = z·∂h/∂e. (The edge-force switch at h = 0 is not differentiated: measure zero.)
//!
//! One kernel (issue 13 item 6, issue 18): these sums are computed by the same function that
//! serves [`crate::ForceModel::simulate`] (`force::kernel`: structure-of-arrays angle grid,
//! engagement runs with lane masks, SIMD lanes selected at run time); the simulation multiplies
//! them by the coefficients, the identification adds the derivatives.

use super::waveform::FrameAxis;
use crate::angle::wrap_tau;
use crate::coefficients::CuttingCoefficients;
use crate::cut::Cut;
use crate::cutter::Cutter;
use crate::edge::EdgeTable;
use crate::force::kernel::{dispatch, padded, Acc, ArcGrad, ArcLanes, Grid, Options};
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Number of basis sums per sample (module docs).
pub const NB: usize = 16;
/// Number of runout-derivative sums per sample and parameter (module docs).
pub const ND: usize = 8;

/// One-revolution evaluator for a cutter, cut and angle grid.
#[derive(Debug, Clone)]
pub struct RevolutionModel {
    k: usize,
    disks: usize,
    /// The shared per-disk geometry and engagement.
    table: EdgeTable,
    /// f_{i,m} = f_z·K·gap(i, m)/2π, index i*K + m − 1.
    feed: Vec<f64>,
    /// θ, sin θ, cos θ per grid sample (structure of arrays, the kernel's layout).
    grid: Grid,
    /// Apply the edge forces over the whole engagement window instead of only where h > 0
    /// (default false = as the simulation). The window-gated variant is continuous in the
    /// runout; the full-signal fit uses it for its first stage (see `full_signal`).
    pub edge_in_window: bool,
}

/// Per-sample basis sums and runout derivatives (see module docs).
#[derive(Debug, Clone)]
pub struct BasisSums {
    /// `base[q]` = the [`NB`] basis sums of sample q (module docs; rows 0–5 are
    /// [Σh cos, Σh sin, Σcos, Σsin, Σh, Σ1]·dz on a cylinder).
    pub base: Vec<[f64; NB]>,
    /// `deriv[q][p]` = ∂[S₀, S₁, S₄, S₆, S₇, S₁₀, S₁₁, S₁₄]/∂p for p = e_x, e_y (mm), then
    /// τ_x, τ_y (mm/mm).
    pub deriv: Vec<Vec<[f64; ND]>>,
}

impl RevolutionModel {
    /// Evaluator on the grid θ_q = `start_angle` + 2πq/`samples` with `disks` axial disks.
    pub fn new(cutter: &Cutter, cut: &Cut, start_angle: f64, samples: usize, disks: usize) -> Self {
        let k = cutter.teeth();
        let disks = disks.max(1);
        let table = EdgeTable::new(cutter, cut, disks);
        let mut feed = Vec::with_capacity(k * k);
        for i in 0..k {
            for m in 1..=k {
                feed.push(cut.fz() * k as f64 * cutter.gap(i, m) / TAU);
            }
        }
        let grid = Grid::new(
            (0..samples).map(|q| start_angle + TAU * q as f64 / samples as f64),
            TAU / samples.max(1) as f64,
            true,
        );
        RevolutionModel {
            k,
            disks,
            table,
            feed,
            grid,
            edge_in_window: false,
        }
    }

    /// Number of grid samples.
    pub fn samples(&self) -> usize {
        self.grid.len
    }

    /// True when κ = 90° on every disk: basis rows 6–9 repeat rows 0–3 and rows 10–15 are zero.
    pub fn is_flat(&self) -> bool {
        self.table.is_flat()
    }

    /// The per-disk geometry and engagement table.
    pub fn table(&self) -> &EdgeTable {
        &self.table
    }

    /// Basis sums for runout offset `e` (mm) and tilt `tau` (mm/mm); `tilt_derivs` adds the
    /// τ derivatives.
    pub fn sums(&self, e: [f64; 2], tau: [f64; 2], tilt_derivs: bool) -> BasisSums {
        self.compute(e, tau, if tilt_derivs { 4 } else { 2 })
    }

    /// [`RevolutionModel::sums`] through the κ(z) kernel also on a cylinder (verification and
    /// benchmarks: on a flat end mill the results are the same).
    pub fn sums_general(&self, e: [f64; 2], tau: [f64; 2], tilt_derivs: bool) -> BasisSums {
        self.compute_kernel::<true>(e, tau, if tilt_derivs { 4 } else { 2 })
    }

    /// Basis sums only (no derivatives): `deriv` is empty per sample.
    pub fn base_sums(&self, e: [f64; 2], tau: [f64; 2]) -> BasisSums {
        self.compute(e, tau, 0)
    }

    /// The sums with `np` derivatives per sample (the flat kernel on a cylinder, rows 6–9
    /// filled from rows 0–3).
    fn compute(&self, e: [f64; 2], tau: [f64; 2], np: usize) -> BasisSums {
        if self.table.is_flat() {
            let mut s = self.compute_kernel::<false>(e, tau, np);
            for b in &mut s.base {
                b.copy_within(0..4, 6);
            }
            for d in s.deriv.iter_mut().flatten() {
                d[3] = d[0];
                d[4] = d[1];
            }
            s
        } else {
            self.compute_kernel::<true>(e, tau, np)
        }
    }

    /// The identification's own loop as it was before issue 18 (baseline of the benchmarks and
    /// oracle of the equivalence tests): `general` forces the κ(z) kernel, `np` derivatives.
    #[doc(hidden)]
    pub fn sums_baseline(&self, e: [f64; 2], tau: [f64; 2], np: usize, general: bool) -> BasisSums {
        let mut s = if general || !self.table.is_flat() {
            self.compute_baseline::<true>(e, tau, np)
        } else {
            self.compute_baseline::<false>(e, tau, np)
        };
        if !general && self.table.is_flat() {
            for b in &mut s.base {
                b.copy_within(0..4, 6);
            }
            for d in s.deriv.iter_mut().flatten() {
                d[3] = d[0];
                d[4] = d[1];
            }
        }
        s
    }

    /// The shared kernel ([`crate::force`]'s `kernel` module): the arc chip with exact radii
    /// and the gradient of its active term, disks in blocks summed in a fixed grouping (in
    /// parallel only for a very large model, see [`PARALLEL_WORK`]).
    fn compute_kernel<const GENERAL: bool>(
        &self,
        e: [f64; 2],
        tau: [f64; 2],
        np: usize,
    ) -> BasisSums {
        let k = self.k;
        let kk = self.disks * k * k;
        let mut lanes = ArcLanes {
            k,
            feed: Vec::with_capacity(kk),
            dr: Vec::with_capacity(kk),
            dnx: Vec::with_capacity(kk),
            dny: Vec::with_capacity(kk),
        };
        let mut pts = Vec::with_capacity(k);
        for j in 0..self.disks {
            lanes.feed.extend_from_slice(&self.feed);
            self.differences_into(j, e, tau, &mut pts, &mut lanes);
        }
        let lanes = ArcGrad(lanes);
        let opts = Options {
            edge_in_window: self.edge_in_window,
            np,
        };
        let n = self.grid.len;
        let stride = padded(n);
        let arch = pulp::Arch::new();
        let run = |disks: std::ops::Range<usize>| {
            let mut acc = Acc::new(stride, GENERAL, np, None);
            dispatch::<ArcGrad, GENERAL, false>(
                arch,
                &self.table,
                &lanes,
                &self.grid,
                disks,
                opts,
                None,
                &mut acc,
            );
            acc
        };
        // Disks in contiguous blocks, one kernel dispatch and one accumulator per block, split
        // and summed as rayon's `fold`/`reduce` over single disks did before (and the baseline
        // still does) on a pool of one thread: same splitter, same halves, same left + right
        // sums, so the results are bit-identical to it there — without a dispatch per disk and
        // an accumulator per rayon split. The grouping is that of one thread at any thread
        // count (rayon's own depends on the thread count and on which halves were stolen, so
        // its last digits varied from run to run on two threads): the results do not depend
        // on the threads. The halves run in parallel only when the work is large enough to
        // repay waking the pool's threads.
        let acc = if self.disks >= 8 {
            // the grouping of the caller that started the fit, also in the tasks it runs in
            // parallel (see [`grouping`])
            let outside = grouping();
            let parallel = rayon::current_num_threads() > 1 && self.disks * n >= PARALLEL_WORK;
            split_sum(0..self.disks, 1, false, outside, parallel, &run)
        } else {
            run(0..self.disks)
        };
        let (rows, drows) = if GENERAL { (NB, ND) } else { (6, 3) };
        let base = (0..n)
            .map(|q| {
                let mut b = [0.0f64; NB];
                for (r, v) in b.iter_mut().enumerate().take(rows) {
                    *v = acc.base[r * stride + q];
                }
                b
            })
            .collect();
        let deriv = (0..n)
            .map(|q| {
                (0..np)
                    .map(|p| {
                        let mut d = [0.0f64; ND];
                        for (r, v) in d.iter_mut().enumerate().take(drows) {
                            *v = acc.deriv[(p * drows + r) * stride + q];
                        }
                        d
                    })
                    .collect()
            })
            .collect();
        BasisSums { base, deriv }
    }

    /// Per (tooth, m) of disk j: R_i − R_{i−m} and n_i − n_{i−m} for runout e₀ + zτ, appended
    /// to the lanes' `dr`, `dnx`, `dny` (index i·K + m − 1; `pts` is scratch space).
    fn differences_into(
        &self,
        j: usize,
        e: [f64; 2],
        tau: [f64; 2],
        pts: &mut Vec<([f64; 2], f64)>,
        lanes: &mut ArcLanes,
    ) {
        let k = self.k;
        let disk = self.table.disk(j);
        let z = disk.z;
        let ez = [e[0] + z * tau[0], e[1] + z * tau[1]];
        let r = disk.radius;
        pts.clear();
        pts.extend(self.table.elements(j).iter().map(|sl| {
            let p = [r * sl.cos_psi + ez[0], r * sl.sin_psi + ez[1]];
            let ri = p[0].hypot(p[1]);
            ([p[0] / ri, p[1] / ri], ri)
        }));
        for i in 0..k {
            for m in 1..=k {
                let o = (i + k * m - m) % k;
                lanes.dr.push(pts[i].1 - pts[o].1);
                lanes.dnx.push(pts[i].0[0] - pts[o].0[0]);
                lanes.dny.push(pts[i].0[1] - pts[o].0[1]);
            }
        }
    }

    /// The loop before issue 18; `GENERAL = false` accumulates only the cylinder's rows 0–5
    /// (derivative rows 0–2), which is exact when κ = 90° on every disk.
    fn compute_baseline<const GENERAL: bool>(
        &self,
        e: [f64; 2],
        tau: [f64; 2],
        np: usize,
    ) -> BasisSums {
        let k = self.k;
        // per disk: radii, unit normals, and the per-tooth active differences are sample-independent
        let mut dr = vec![0.0; self.disks * k * k];
        let mut dn = vec![[0.0f64; 2]; self.disks * k * k];
        for j in 0..self.disks {
            let disk = self.table.disk(j);
            let z = disk.z;
            let ez = [e[0] + z * tau[0], e[1] + z * tau[1]];
            let r = disk.radius;
            let pts: Vec<([f64; 2], f64)> = self
                .table
                .elements(j)
                .iter()
                .map(|sl| {
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
        let n = self.grid.len;
        let dtheta = TAU / n as f64;
        let theta0 = if n > 0 { self.grid.theta[0] } else { 0.0 };
        type Acc = (Vec<[f64; NB]>, Vec<[f64; ND]>);
        let empty = || (vec![[0.0f64; NB]; n], vec![[0.0f64; ND]; n * np]);
        let disk = |(mut b, mut d): Acc, j: usize| {
            let geo = self.table.disk(j);
            let z = geo.z;
            let dz = geo.dz;
            let db = geo.db;
            let (sk, ck) = (geo.sin_kappa, geo.cos_kappa);
            let (st, width) = (geo.entry, geo.width);
            if width.is_nan() || width < 0.0 {
                return (b, d);
            }
            let run = ((width / dtheta).floor() as usize + 3).min(n);
            for (i, sl) in self.table.elements(j).iter().enumerate() {
                let a = wrap_tau(theta0 + sl.psi - st);
                let first = ((TAU - a) / dtheta).floor() as i64 - 1;
                let base_idx = (j * k + i) * k;
                for t in 0..run {
                    let q = (first + t as i64).rem_euclid(n as i64) as usize;
                    let (theta, st_t, ct_t) =
                        (self.grid.theta[q], self.grid.sin[q], self.grid.cos[q]);
                    let rel = wrap_tau(theta + sl.psi - st);
                    if rel > width {
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
                            if GENERAL {
                                bq[2] += co * db;
                                bq[3] += s * db;
                                bq[5] += sk * db;
                                bq[8] += sk * co * db;
                                bq[9] += sk * s * db;
                                bq[12] += ck * co * db;
                                bq[13] += ck * s * db;
                                bq[15] += ck * db;
                            } else {
                                bq[2] += co * dz;
                                bq[3] += s * dz;
                                bq[5] += dz;
                            }
                        }
                        continue;
                    }
                    let bq = &mut b[q];
                    if GENERAL {
                        let hz = h * dz;
                        bq[0] += hz * co;
                        bq[1] += hz * s;
                        bq[2] += co * db;
                        bq[3] += s * db;
                        bq[4] += sk * hz;
                        bq[5] += sk * db;
                        bq[6] += sk * hz * co;
                        bq[7] += sk * hz * s;
                        bq[8] += sk * co * db;
                        bq[9] += sk * s * db;
                        bq[10] += ck * hz * co;
                        bq[11] += ck * hz * s;
                        bq[12] += ck * co * db;
                        bq[13] += ck * s * db;
                        bq[14] += ck * hz;
                        bq[15] += ck * db;
                    } else {
                        bq[0] += h * co * dz;
                        bq[1] += h * s * dz;
                        bq[2] += co * dz;
                        bq[3] += s * dz;
                        bq[4] += h * dz;
                        bq[5] += dz;
                    }
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
                        if GENERAL {
                            dp[2] += sk * gh;
                            dp[3] += sk * gh * co;
                            dp[4] += sk * gh * s;
                            dp[5] += ck * gh * co;
                            dp[6] += ck * gh * s;
                            dp[7] += ck * gh;
                        } else {
                            dp[2] += gh;
                        }
                    }
                }
            }
            (b, d)
        };
        let add = |(mut b1, mut d1): Acc, (b2, d2): Acc| {
            let rows = if GENERAL { NB } else { 6 };
            let drows = if GENERAL { ND } else { 3 };
            for (x, y) in b1.iter_mut().zip(&b2) {
                for r in 0..rows {
                    x[r] += y[r];
                }
            }
            for (x, y) in d1.iter_mut().zip(&d2) {
                for r in 0..drows {
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

thread_local! {
    /// The grouping of [`split_sum`] set for the tasks of a parallel section ([`with_grouping`]).
    static CALLER_OUTSIDE: std::cell::Cell<Option<bool>> = const { std::cell::Cell::new(None) };
}

/// Whether the sums computed now take the grouping of a call from outside the rayon pool
/// ([`split_sum`]'s `outside`): the value [`with_grouping`] set on this thread, else whether
/// this thread is outside the pool. A fit that costs independent points in parallel reads it
/// once in its serial step and runs each task under [`with_grouping`] with it, so a point's
/// sums are those the serial step would compute, bit for bit, wherever the task runs.
pub(crate) fn grouping() -> bool {
    CALLER_OUTSIDE
        .with(|c| c.get())
        .unwrap_or_else(|| rayon::current_thread_index().is_none())
}

/// [`grouping`] = `outside` on this thread while the value lives (the previous setting is
/// restored when it is dropped, also on a panic).
pub(crate) struct GroupingScope(Option<bool>);

impl GroupingScope {
    pub(crate) fn new(outside: bool) -> Self {
        GroupingScope(CALLER_OUTSIDE.with(|c| c.replace(Some(outside))))
    }
}

impl Drop for GroupingScope {
    fn drop(&mut self) {
        CALLER_OUTSIDE.with(|c| c.set(self.0));
    }
}

/// Runs `f` as one task on the rayon pool (the calling thread waits), so that the parallel
/// sections of the fits inside it are nested in the pool (work stealing between its threads)
/// instead of each being handed to the pool from outside and waited for (issue 18: each such
/// hand-off wakes a sleeping thread, ≈ 0.1–0.2 ms on a virtual machine). The sums keep the
/// grouping of the caller (whether it runs outside the pool: the disk sums are grouped as
/// there), so the results are the same bit for bit as when `f`
/// runs on the calling thread. On a thread of the pool, `f` simply runs.
///
/// ```
/// let x = runout_core::identify::on_pool(|| 2 + 2);
/// assert_eq!(x, 4);
/// ```
pub fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        return f();
    }
    let outside = grouping();
    rayon::scope(|_| with_grouping(outside, f))
}

/// Runs `f` with [`grouping`] = `outside` on this thread ([`GroupingScope`]).
pub(crate) fn with_grouping<R>(outside: bool, f: impl FnOnce() -> R) -> R {
    let _scope = GroupingScope::new(outside);
    f()
}

/// [`rayon::join`] of `a` and `b`, both with the caller's [`grouping`].
pub(crate) fn join_grouped<A, B, RA, RB>(a: A, b: B) -> (RA, RB)
where
    A: FnOnce() -> RA + Send,
    B: FnOnce() -> RB + Send,
    RA: Send,
    RB: Send,
{
    let g = grouping();
    rayon::join(|| with_grouping(g, a), || with_grouping(g, b))
}

/// Disk blocks × grid samples from which [`split_sum`] runs the halves in parallel. The fits
/// also use the second core at a coarser grain (trial points, grid candidates and difference
/// columns costed in parallel: `full_signal`, `harmonic_fit`, `alignment`). When each compute
/// was handed to the pool from the calling thread, splitting one (e.g. 133 disks × 185 or 740
/// samples, 0.1–1 ms) cost more than it saved: waking the pool's threads from the serial steps
/// (2 threads slower than 1 on the `identify` bench head job, about a quarter of the fits' CPU
/// in futex and scheduler calls), and the threshold was 2²⁰. Since the fits run as one task on
/// the pool ([`on_pool`]), a split is taken by a thread of the same pool: with 2¹⁴ (every
/// model of the fits but stage 1's coarse one) the 1 MB head job took 0.200 → 0.190,
/// 0.196 → 0.188 and 0.177 → 0.173 s in three shuffled A/Bs of 21–31 rounds (2¹³, which
/// splits the coarse model too: 0.175 s), reports bit-identical (the halves are the same,
/// [`split_sum`]); on the 100 MB job within the noise (0.444 / 0.447 s).
const PARALLEL_WORK: usize = 1 << 14;

/// `run` over `disks`, split in halves (at len/2) and summed left + right, with the decisions
/// of rayon's adaptive splitter (`splits` starts at the pool's thread count and halves per
/// split; a half that runs "migrated" resets it to the thread count) on a pool of ONE thread,
/// where nothing is stolen: a half is migrated only when its join was injected into the pool
/// from a thread outside it (`outside`, the top join; rayon then runs both halves with the
/// injected flag). That is the grouping of `(0..disks).into_par_iter().fold(…).reduce(…)`
/// there, with whole blocks as leaves. The halves run in parallel ([`rayon::join`]) when
/// `parallel`, else one after the other: the same sums in the same order either way.
fn split_sum<F>(
    disks: std::ops::Range<usize>,
    mut splits: usize,
    migrated: bool,
    outside: bool,
    parallel: bool,
    run: &F,
) -> Acc
where
    F: Fn(std::ops::Range<usize>) -> Acc + Sync,
{
    let len = disks.len();
    let split = len / 2 >= 1
        && if migrated {
            splits = 1.max(splits / 2);
            true
        } else if splits > 0 {
            splits /= 2;
            true
        } else {
            false
        };
    if !split {
        return run(disks);
    }
    let mid = disks.start + len / 2;
    let left = || split_sum(disks.start..mid, splits, outside, false, parallel, run);
    let right = || split_sum(mid..disks.end, splits, outside, false, parallel, run);
    let (mut a, b) = if parallel {
        rayon::join(left, right)
    } else {
        (left(), right())
    };
    a.add(&b);
    a
}

/// Force component `axis` (N) of sample sums `b` with coefficients `kc` (module docs).
#[inline]
pub fn force_from_basis(axis: FrameAxis, b: &[f64; NB], kc: &CuttingCoefficients) -> f64 {
    match axis {
        FrameAxis::X => {
            kc.ktc * b[0] + kc.krc * b[7] - kc.kac * b[11] + kc.kte * b[2] + kc.kre * b[9]
                - kc.kae * b[13]
        }
        FrameAxis::Y => {
            -kc.ktc * b[1] + kc.krc * b[6] - kc.kac * b[10] - kc.kte * b[3] + kc.kre * b[8]
                - kc.kae * b[12]
        }
        FrameAxis::Z => -kc.krc * b[14] - kc.kre * b[15] - kc.kac * b[4] - kc.kae * b[5],
    }
}

/// Derivatives ∂F_axis/∂(K_tc, K_rc, K_ac, K_te, K_re, K_ae) of sample sums `b`.
#[inline]
pub fn coefficient_gradient(axis: FrameAxis, b: &[f64; NB]) -> [f64; 6] {
    match axis {
        FrameAxis::X => [b[0], b[7], -b[11], b[2], b[9], -b[13]],
        FrameAxis::Y => [-b[1], b[6], -b[10], -b[3], b[8], -b[12]],
        FrameAxis::Z => [0.0, -b[14], -b[4], 0.0, -b[15], -b[5]],
    }
}

/// ∂F_axis/∂p from the runout derivative sums `d` = ∂[S₀, S₁, S₄, S₆, S₇, S₁₀, S₁₁, S₁₄]/∂p.
#[inline]
pub fn runout_gradient(axis: FrameAxis, d: &[f64; ND], kc: &CuttingCoefficients) -> f64 {
    match axis {
        FrameAxis::X => kc.ktc * d[0] + kc.krc * d[4] - kc.kac * d[6],
        FrameAxis::Y => -kc.ktc * d[1] + kc.krc * d[3] - kc.kac * d[5],
        FrameAxis::Z => -kc.krc * d[7] - kc.kac * d[2],
    }
}
