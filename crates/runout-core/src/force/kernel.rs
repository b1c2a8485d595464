//! The one force kernel: per-sample basis sums of the discretised mechanistic model (methods.md
//! §4.1), shared by [`crate::ForceModel::simulate`] (basis sums · coefficients, plus the
//! per-tooth outputs of a simulation) and [`crate::identify::RevolutionModel`] (basis sums and
//! their runout derivatives). The basis rows are documented in [`crate::identify`]'s model module
//! (`NB` = 16 rows: Σ h dz cos φ, Σ h dz sin φ, Σ db cos φ, …).
//!
//! Layout and evaluation order (issue 18):
//!
//! * **structure of arrays**: the angle grid (θ, sin θ, cos θ) and every accumulator row are
//!   contiguous `f64` arrays over the samples of a block; [`L`] consecutive samples are one lane
//!   vector ([`V`]);
//! * **engagement runs**: a (disk, tooth) element is inside its immersion window
//!   [φ_st, φ_ex] on one contiguous run of samples per revolution. Only the lane vectors that
//!   can meet that run (its predicted bounds, two guard samples each side, rounded out to whole
//!   vectors) are visited; inside them the exact test of the scalar model,
//!   `wrap_2π(θ + ψ − φ_st) ≤ φ_ex − φ_st`, is a lane **mask** — the inner loop has no branches,
//!   h > 0 and the window are masks, and the min over the previous passes of the arc chip is a
//!   compare-and-select;
//! * **trigonometry**: sin φ and cos φ of every element come from the sample's sin θ, cos θ and
//!   the element's sin ψ, cos ψ by the addition theorem (no trigonometric call in the kernel).
//!   Every quantity that decides a mask (θ + ψ − φ_st, its wrap, sin φ, h) is computed with the
//!   same operations in the same order as the scalar model, so engagement and the h > 0 switch
//!   are bit-identical to it; only the accumulation order of the sums differs (relative
//!   differences ~1e-15).
//!
//! The lane loops are plain fixed-size array loops compiled inside [`pulp::Arch::dispatch`],
//! which selects AVX-512 / AVX2+FMA / SSE code at run time (portable, stable Rust): the
//! compiler turns each lane loop into one vector instruction of the selected width.

// `!(h <= 0)` and `!(width < …)` are deliberate: they keep the scalar model's NaN semantics.
// The lane functions take lane vectors by reference, many of them.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::too_many_arguments)]

use crate::angle::wrap_tau;
use crate::chip::ChipAtHeight;
use crate::coefficients::CuttingCoefficients;
use crate::edge::EdgeTable;
use std::f64::consts::TAU;

/// Samples per lane vector.
pub(crate) const L: usize = 8;
/// One lane vector.
pub(crate) type V = [f64; L];

/// Round `n` up to a whole number of lane vectors.
#[inline]
pub(crate) fn padded(n: usize) -> usize {
    n.div_ceil(L) * L
}

/// Chip thickness of one (disk, tooth) element on a lane vector.
pub(crate) trait LaneChip: Sync {
    /// True when [`LaneChip::eval`] fills the gradient of the active term.
    const GRAD: bool;
    /// Raw chip thickness `h` (mm; the element cuts where h > 0) of tooth `i` on disk `j` at
    /// immersions `phi` with sines `s` and cosines `c`; with [`LaneChip::GRAD`] also ∂h/∂e of the
    /// active term of the min (`gx`, `gy`).
    fn eval(&self, j: usize, i: usize, phi: &V, s: &V, c: &V, h: &mut V, gx: &mut V, gy: &mut V);
}

/// Arc chip (methods.md eq. 0.4) as per-(disk, tooth, m) terms:
/// h = min_m [f_{i,m} sin φ + ΔR_{i,m}], with optional ∂h/∂e = Δn of the active term.
pub(crate) struct ArcLanes {
    pub k: usize,
    /// f_{i,m} at index (j·K + i)·K + m − 1.
    pub feed: Vec<f64>,
    /// R_i − R_{i−m}, same index.
    pub dr: Vec<f64>,
    /// n_i − n_{i−m} (x, y), same index (empty without gradients).
    pub dnx: Vec<f64>,
    pub dny: Vec<f64>,
}

/// [`ArcLanes`] with the gradient of the active term.
pub(crate) struct ArcGrad(pub ArcLanes);

#[inline(always)]
fn arc_eval<const G: bool>(
    a: &ArcLanes,
    j: usize,
    i: usize,
    s: &V,
    h: &mut V,
    gx: &mut V,
    gy: &mut V,
) {
    let k = a.k;
    let b = (j * k + i) * k;
    let feed = &a.feed[b..b + k];
    let dr = &a.dr[b..b + k];
    *h = [f64::INFINITY; L];
    for m in 0..k {
        let (f, d) = (feed[m], dr[m]);
        if G {
            let (nx, ny) = (a.dnx[b + m], a.dny[b + m]);
            for l in 0..L {
                // same operations as the scalar model: f·s then + ΔR, strict < keeps the first m
                let v = f * s[l] + d;
                let lt = v < h[l];
                h[l] = if lt { v } else { h[l] };
                gx[l] = if lt { nx } else { gx[l] };
                gy[l] = if lt { ny } else { gy[l] };
            }
        } else {
            for l in 0..L {
                h[l] = h[l].min(f * s[l] + d);
            }
        }
    }
}

impl LaneChip for ArcLanes {
    const GRAD: bool = false;
    #[inline(always)]
    fn eval(&self, j: usize, i: usize, _: &V, s: &V, _: &V, h: &mut V, gx: &mut V, gy: &mut V) {
        arc_eval::<false>(self, j, i, s, h, gx, gy)
    }
}

impl LaneChip for ArcGrad {
    const GRAD: bool = true;
    #[inline(always)]
    fn eval(&self, j: usize, i: usize, _: &V, s: &V, _: &V, h: &mut V, gx: &mut V, gy: &mut V) {
        arc_eval::<true>(&self.0, j, i, s, h, gx, gy)
    }
}

/// Any chip model through its scalar per-height evaluator, one call per lane.
pub(crate) struct ScalarLanes<A: ChipAtHeight>(pub Vec<A>);

impl<A: ChipAtHeight> LaneChip for ScalarLanes<A> {
    const GRAD: bool = false;
    #[inline(always)]
    fn eval(&self, j: usize, i: usize, phi: &V, s: &V, c: &V, h: &mut V, _: &mut V, _: &mut V) {
        let ev = &self.0[j];
        for l in 0..L {
            h[l] = ev.thickness(i, phi[l], s[l], c[l]);
        }
    }
}

/// Angle grid of one block of samples (structure of arrays, [`padded`] length; padding lanes
/// have θ = NaN and are never engaged).
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    pub theta: Vec<f64>,
    pub sin: Vec<f64>,
    pub cos: Vec<f64>,
    /// Real samples.
    pub len: usize,
    /// Angular step between samples (rad).
    pub step: f64,
    /// The grid is one whole revolution (engagement runs wrap around).
    pub periodic: bool,
}

impl Grid {
    /// Grid from angles, with sin and cos of each.
    pub fn new(theta: impl Iterator<Item = f64>, step: f64, periodic: bool) -> Self {
        let mut g = Grid {
            theta: Vec::new(),
            sin: Vec::new(),
            cos: Vec::new(),
            len: 0,
            step,
            periodic,
        };
        g.fill(theta);
        g
    }

    /// Refill the grid with new angles, reusing its buffers (a simulation's blocks).
    pub fn fill(&mut self, theta: impl Iterator<Item = f64>) {
        self.theta.clear();
        self.sin.clear();
        self.cos.clear();
        for t in theta {
            let (s, c) = t.sin_cos();
            self.theta.push(t);
            self.sin.push(s);
            self.cos.push(c);
        }
        self.len = self.theta.len();
        let p = padded(self.len);
        self.theta.resize(p, f64::NAN);
        self.sin.resize(p, 0.0);
        self.cos.resize(p, 0.0);
    }
}

/// What the kernel accumulates besides the basis rows.
#[derive(Clone, Copy)]
pub(crate) struct Options {
    /// Edge rows over the whole window, not only where h > 0 (identify's first stage).
    pub edge_in_window: bool,
    /// Runout-derivative parameters (0, 2: e_x, e_y; 4: and τ_x, τ_y); needs a gradient chip.
    pub np: usize,
}

/// Constants of a simulation.
pub(crate) struct SimConsts {
    /// R_i(z_j) per element (j·K + i), for the torque.
    pub radius: Vec<f64>,
    /// The cutting coefficients.
    pub kc: CuttingCoefficients,
}

/// Accumulators of one block (each row `stride` samples long).
pub(crate) struct Acc {
    pub stride: usize,
    /// Basis rows: 16, or 6 on the flat kernel (rows 0–5); not filled by a simulation.
    pub base: Vec<f64>,
    /// Derivative rows, parameter-major: 8 per parameter (3 on the flat kernel).
    pub deriv: Vec<f64>,
    /// Simulation only: F_x, F_y, F_z (N) and the torque (N·mm), 4 rows.
    pub force: Vec<f64>,
    /// Simulation only: own F_x, F_y per tooth (2K rows).
    pub own: Vec<f64>,
    /// Simulation only: normal chip at the lowest disk per tooth (K rows).
    pub chip: Vec<f64>,
    /// Simulation only: largest normal chip per tooth.
    pub max_chip: Vec<V>,
}

impl Acc {
    pub fn new(stride: usize, general: bool, np: usize, sim_teeth: Option<usize>) -> Self {
        let rows = if sim_teeth.is_some() {
            0
        } else if general {
            16
        } else {
            6
        };
        let drows = if general { 8 } else { 3 };
        let k = sim_teeth.unwrap_or(0);
        let sim = sim_teeth.is_some();
        Acc {
            stride,
            base: vec![0.0; rows * stride],
            deriv: vec![0.0; np * drows * stride],
            force: vec![0.0; if sim { 4 * stride } else { 0 }],
            own: vec![0.0; 2 * k * stride],
            chip: vec![0.0; k * stride],
            max_chip: vec![[0.0; L]; k],
        }
    }

    /// Zero every accumulator for a block of `stride` samples, reusing the buffers (a
    /// simulation's blocks; the same rows as [`Acc::new`] with `sim_teeth`).
    pub fn reset_sim(&mut self, stride: usize) {
        let k = self.max_chip.len();
        self.stride = stride;
        for (v, rows) in [
            (&mut self.force, 4),
            (&mut self.own, 2 * k),
            (&mut self.chip, k),
        ] {
            v.clear();
            v.resize(rows * stride, 0.0);
        }
        self.max_chip.fill([0.0; L]);
    }

    /// Add `other` (same shape) into `self`.
    pub fn add(&mut self, other: &Acc) {
        for (a, b) in self.base.iter_mut().zip(&other.base) {
            *a += b;
        }
        for (a, b) in self.deriv.iter_mut().zip(&other.deriv) {
            *a += b;
        }
    }
}

#[inline(always)]
fn row(acc: &mut [f64], r: usize, stride: usize, t: usize) -> &mut V {
    (&mut acc[r * stride + t..r * stride + t + L])
        .try_into()
        .expect("lane vector")
}

/// `a += x(l)` on the lanes where `on`, `+ 0.0` elsewhere (one straight lane loop).
#[inline(always)]
fn masked_add(a: &mut V, on: &[bool; L], x: impl Fn(usize) -> f64) {
    for l in 0..L {
        a[l] += if on[l] { x(l) } else { 0.0 };
    }
}

#[inline(always)]
fn add_to(a: &mut V, x: &V) {
    for l in 0..L {
        a[l] += x[l];
    }
}

/// Visit the lane vectors (sample offsets `t`, multiples of [`L`]) of a block of `len` samples
/// (`stride` padded) that can hold samples of an element inside its window: `a` =
/// wrap(θ₀ + ψ − φ_st) at the block's first sample, `width` the window, `step` the sample
/// spacing. Each vector is visited at most once.
#[inline(always)]
fn runs(a: f64, width: f64, step: f64, len: usize, out: &mut Vec<(usize, usize)>) {
    out.clear();
    let full = padded(len);
    if !(width < TAU - 2.0 * (L as f64 + 2.0) * step) || !a.is_finite() {
        // (almost) always engaged, or an undefined window: every vector
        out.push((0, full));
        return;
    }
    let mut done = 0usize;
    let mut visit = |lo: f64, hi: f64, done: &mut usize| {
        // samples t with lo ≤ t ≤ hi (fractional), guarded by two samples each side
        let t0 = (lo.floor() - 2.0).max(0.0);
        let t1 = (hi.ceil() + 3.0).min(len as f64);
        if t1 <= t0 {
            return;
        }
        let b0 = ((t0 as usize) / L * L).max(*done);
        let b1 = padded(t1 as usize);
        if b1 > b0 {
            out.push((b0, b1));
        }
        *done = (*done).max(b1);
    };
    // r-th revolution after the block's first sample (on a one-revolution grid, r = 1 is the
    // run that wraps around to the start)
    {
        let mut r = 0.0f64;
        loop {
            let lo = (TAU * r - a) / step;
            if lo - 2.0 >= len as f64 {
                break;
            }
            visit(lo, (TAU * r - a + width) / step, &mut done);
            r += 1.0;
        }
    }
}

/// The kernel: accumulate disks `disks` of `table` on the samples of `grid` into `acc`.
///
/// `GENERAL = false` is the cylinder (κ = 90° and db = dz on every disk: only rows 0–5, without
/// the common factor dz); `SIM` adds the simulation's torque rows, per-tooth own forces, the
/// chip at the lowest disk and the largest chip per tooth.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn accumulate<C: LaneChip, const GENERAL: bool, const SIM: bool>(
    table: &EdgeTable,
    chip: &C,
    grid: &Grid,
    disks: std::ops::Range<usize>,
    opts: Options,
    sim: Option<&SimConsts>,
    acc: &mut Acc,
) {
    let k = table.teeth();
    let stride = acc.stride;
    let np = if C::GRAD { opts.np } else { 0 };
    let drows = if GENERAL { 8 } else { 3 };
    let none = SimConsts {
        radius: Vec::new(),
        kc: CuttingCoefficients {
            ktc: 0.0,
            krc: 0.0,
            kac: 0.0,
            kte: 0.0,
            kre: 0.0,
            kae: 0.0,
        },
    };
    let simc = sim.unwrap_or(&none);
    let mut spans: Vec<(usize, usize)> = Vec::with_capacity(8);
    for j in disks {
        let disk = table.disk(j);
        let (st, mut width) = (disk.entry, disk.width);
        if width.is_nan() {
            if grid.periodic {
                continue;
            }
            // the scalar model's test `rel > width` is false for every sample
            width = f64::INFINITY;
        }
        if width < 0.0 {
            continue;
        }
        let (dz, db, sk, ck, z) = (disk.dz, disk.db, disk.sin_kappa, disk.cos_kappa, disk.z);
        for (i, el) in table.elements(j).iter().enumerate() {
            let (psi, cpsi, spsi) = (el.psi, el.cos_psi, el.sin_psi);
            let radius = simc.radius.get(j * k + i).copied().unwrap_or(0.0);
            let a = wrap_tau(grid.theta[0] + psi - st);
            runs(a, width, grid.step, grid.len, &mut spans);
            for &(b0, b1) in &spans {
                let mut t = b0;
                while t < b1 {
                    let th: &V = grid.theta[t..t + L].try_into().expect("lanes");
                    let sth: &V = grid.sin[t..t + L].try_into().expect("lanes");
                    let cth: &V = grid.cos[t..t + L].try_into().expect("lanes");
                    let mut rel = [0.0; L];
                    let mut phi = [0.0; L];
                    let mut s = [0.0; L];
                    let mut co = [0.0; L];
                    let mut win = [false; L];
                    for l in 0..L {
                        // exactly the scalar model's operations (no fused multiply-add)
                        let x = th[l] + psi - st;
                        let w = x - TAU * (x / TAU).floor();
                        rel[l] = if w >= TAU { 0.0 } else { w };
                        win[l] = rel[l] <= width;
                        phi[l] = st + rel[l];
                        s[l] = sth[l] * cpsi + cth[l] * spsi;
                        co[l] = cth[l] * cpsi - sth[l] * spsi;
                    }
                    if !win.iter().any(|&w| w) {
                        // no lane inside the window (a guard vector): nothing to add
                        t += L;
                        continue;
                    }
                    let mut h = [0.0; L];
                    let mut gx = [0.0; L];
                    let mut gy = [0.0; L];
                    chip.eval(j, i, &phi, &s, &co, &mut h, &mut gx, &mut gy);
                    let mut cut = [false; L];
                    let mut edge = [false; L];
                    for l in 0..L {
                        cut[l] = win[l] && !(h[l] <= 0.0);
                        edge[l] = if opts.edge_in_window { win[l] } else { cut[l] };
                    }
                    // Each term below is the old loops' expression with the same association, masked
                    // by a select (adding an exact 0 elsewhere): results are bit-identical to them.
                    if SIM {
                        let kc = &simc.kc;
                        let mut f = [[0.0; L]; 4];
                        let mut dxy = [[0.0; L]; 2];
                        for l in 0..L {
                            let (ft, frad, fax) = if GENERAL {
                                let hz = h[l] * dz;
                                let ft = kc.ktc * hz + kc.kte * db;
                                let fr = kc.krc * hz + kc.kre * db;
                                let fa = kc.kac * hz + kc.kae * db;
                                (ft, fr * sk - fa * ck, fr * ck + fa * sk)
                            } else {
                                (
                                    (kc.ktc * h[l] + kc.kte) * dz,
                                    (kc.krc * h[l] + kc.kre) * dz,
                                    (kc.kac * h[l] + kc.kae) * dz,
                                )
                            };
                            let dx = ft * co[l] + frad * s[l];
                            let dy = -ft * s[l] + frad * co[l];
                            let on = cut[l];
                            dxy[0][l] = if on { dx } else { 0.0 };
                            dxy[1][l] = if on { dy } else { 0.0 };
                            f[2][l] = if on { fax } else { 0.0 };
                            f[3][l] = if on { ft * radius } else { 0.0 };
                        }
                        let fs = &mut acc.force;
                        add_to(row(fs, 0, stride, t), &dxy[0]);
                        add_to(row(fs, 1, stride, t), &dxy[1]);
                        let fz = row(fs, 2, stride, t);
                        for l in 0..L {
                            fz[l] -= f[2][l];
                        }
                        add_to(row(fs, 3, stride, t), &f[3]);
                        add_to(row(&mut acc.own, 2 * i, stride, t), &dxy[0]);
                        add_to(row(&mut acc.own, 2 * i + 1, stride, t), &dxy[1]);
                    } else {
                        // Row by row, each a straight lane loop (vectorised): the old loops'
                        // expression per row with the same association, masked by a select.
                        let base = &mut acc.base;
                        let mut hz = [0.0; L];
                        for l in 0..L {
                            hz[l] = h[l] * dz;
                        }
                        if GENERAL {
                            masked_add(row(base, 0, stride, t), &cut, |l| hz[l] * co[l]);
                            masked_add(row(base, 1, stride, t), &cut, |l| hz[l] * s[l]);
                            masked_add(row(base, 2, stride, t), &edge, |l| co[l] * db);
                            masked_add(row(base, 3, stride, t), &edge, |l| s[l] * db);
                            masked_add(row(base, 4, stride, t), &cut, |l| sk * hz[l]);
                            masked_add(row(base, 5, stride, t), &edge, |_| sk * db);
                            masked_add(row(base, 6, stride, t), &cut, |l| sk * hz[l] * co[l]);
                            masked_add(row(base, 7, stride, t), &cut, |l| sk * hz[l] * s[l]);
                            masked_add(row(base, 8, stride, t), &edge, |l| sk * co[l] * db);
                            masked_add(row(base, 9, stride, t), &edge, |l| sk * s[l] * db);
                            masked_add(row(base, 10, stride, t), &cut, |l| ck * hz[l] * co[l]);
                            masked_add(row(base, 11, stride, t), &cut, |l| ck * hz[l] * s[l]);
                            masked_add(row(base, 12, stride, t), &edge, |l| ck * co[l] * db);
                            masked_add(row(base, 13, stride, t), &edge, |l| ck * s[l] * db);
                            masked_add(row(base, 14, stride, t), &cut, |l| ck * hz[l]);
                            masked_add(row(base, 15, stride, t), &edge, |_| ck * db);
                        } else {
                            masked_add(row(base, 0, stride, t), &cut, |l| h[l] * co[l] * dz);
                            masked_add(row(base, 1, stride, t), &cut, |l| h[l] * s[l] * dz);
                            masked_add(row(base, 2, stride, t), &edge, |l| co[l] * dz);
                            masked_add(row(base, 3, stride, t), &edge, |l| s[l] * dz);
                            masked_add(row(base, 4, stride, t), &cut, |l| hz[l]);
                            masked_add(row(base, 5, stride, t), &edge, |_| dz);
                        }
                        for p in 0..np {
                            let (g, f) = match p {
                                0 => (&gx, 1.0),
                                1 => (&gy, 1.0),
                                2 => (&gx, z),
                                _ => (&gy, z),
                            };
                            let d = &mut acc.deriv;
                            let r0 = p * drows;
                            let mut gh = [0.0; L];
                            for l in 0..L {
                                gh[l] = if p < 2 { g[l] * dz } else { f * g[l] * dz };
                            }
                            masked_add(row(d, r0, stride, t), &cut, |l| gh[l] * co[l]);
                            masked_add(row(d, r0 + 1, stride, t), &cut, |l| gh[l] * s[l]);
                            if GENERAL {
                                masked_add(row(d, r0 + 2, stride, t), &cut, |l| sk * gh[l]);
                                masked_add(row(d, r0 + 3, stride, t), &cut, |l| sk * gh[l] * co[l]);
                                masked_add(row(d, r0 + 4, stride, t), &cut, |l| sk * gh[l] * s[l]);
                                masked_add(row(d, r0 + 5, stride, t), &cut, |l| ck * gh[l] * co[l]);
                                masked_add(row(d, r0 + 6, stride, t), &cut, |l| ck * gh[l] * s[l]);
                                masked_add(row(d, r0 + 7, stride, t), &cut, |l| ck * gh[l]);
                            } else {
                                masked_add(row(d, r0 + 2, stride, t), &cut, |l| gh[l]);
                            }
                        }
                    }
                    if SIM {
                        let mut hn = [0.0; L];
                        for l in 0..L {
                            let hp = if h[l] > 0.0 { h[l] } else { 0.0 };
                            hn[l] = if GENERAL { hp * sk } else { hp };
                        }
                        if j == 0 {
                            let c = row(&mut acc.chip, i, stride, t);
                            for l in 0..L {
                                c[l] = if win[l] { hn[l] } else { c[l] };
                            }
                        }
                        let mc = &mut acc.max_chip[i];
                        for l in 0..L {
                            let v = if cut[l] { hn[l] } else { 0.0 };
                            mc[l] = mc[l].max(v);
                        }
                    }
                    t += L;
                }
            }
        }
    }
}

/// One call of [`accumulate`] as a [`pulp::WithSimd`] operation: `with_simd` is inlined into
/// pulp's `#[target_feature]` entry of the detected instruction set, and [`accumulate`] (always
/// inlined) with it, so the lane loops compile to AVX-512 / AVX2 vectors (a plain closure is not
/// inlined there and would run with the baseline SSE2 instructions).
struct Job<'a, C, const GENERAL: bool, const SIM: bool> {
    table: &'a EdgeTable,
    chip: &'a C,
    grid: &'a Grid,
    disks: std::ops::Range<usize>,
    opts: Options,
    sim: Option<&'a SimConsts>,
    acc: &'a mut Acc,
}

impl<C: LaneChip, const GENERAL: bool, const SIM: bool> pulp::WithSimd
    for Job<'_, C, GENERAL, SIM>
{
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        accumulate::<C, GENERAL, SIM>(
            self.table, self.chip, self.grid, self.disks, self.opts, self.sim, self.acc,
        )
    }
}

/// [`accumulate`] with the SIMD instruction set detected at run time ([`pulp::Arch`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn dispatch<C: LaneChip, const GENERAL: bool, const SIM: bool>(
    arch: pulp::Arch,
    table: &EdgeTable,
    chip: &C,
    grid: &Grid,
    disks: std::ops::Range<usize>,
    opts: Options,
    sim: Option<&SimConsts>,
    acc: &mut Acc,
) {
    arch.dispatch(Job::<C, GENERAL, SIM> {
        table,
        chip,
        grid,
        disks,
        opts,
        sim,
        acc,
    })
}
