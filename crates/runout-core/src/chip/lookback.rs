//! The equivalent IUCT (methods.md eq. 2.8) evaluated in bulk along a tool path.
//!
//! Eq. (2.8) needs the axis displacement d_m = [A(z,t) − A(z,t+τ_m)]_⊥u of eq. (2.4) for every
//! previous pass m; evaluated directly that is one pose of the motion per m (K + 1 per point,
//! each with trigonometry and, on a CL path, a segment search). Over one revolution the axis path
//! is smooth (a straight or circular feed, a constant-rate swing, one slerp segment of a CL path),
//! so [`LookBack`] represents it by the cubic Hermite interpolant of the poses at the window ends
//! t − T and t (positions and velocities, T = 2π/ω):
//!
//!   A(z, t + τ) ≈ h₀₀(s)·A₀ + h₁₀(s)·T·Ȧ₀ + h₀₁(s)·A₁ + h₁₁(s)·T·Ȧ₁,   s = 1 + τ/T,
//!   d_m = h₀₀·(A₁ − A₀) − T·h₁₀·Ȧ₀ − T·h₁₁·Ȧ₁          (h₀₀ + h₀₁ = 1),
//!
//! with A = P + z·u, Ȧ = Ṗ + z·Ω×u. Its error is at most T⁴/384·max|A⁗| (zero for a straight
//! feed; 6e-10 mm for a 60°/s swing at z = 20 mm and 6000 rpm), far below the model's own
//! second-order error. The two poses and the spindle angle are shared by every tooth and height
//! at time t, the Hermite weights depend on (height, tooth, m) only and are precomputed, and all
//! vectors are taken in the tool frame (e₁, e₂) of time t, where n and t̂ live — so a point costs
//! a handful of multiply-adds per m and no trigonometry.
//!
//! Where the window spans a junction of the motion ([`ToolMotion::smooth_on`] is false, e.g. a
//! CL point less than one revolution of feed back) the interpolant would cut the corner. There
//! the poses are taken at the *nominal* look-backs τ_g = −gap/ω (K distinct values for uniform
//! pitch, shared by every height and tooth) and shifted to the refined look-back τ = τ_g + Δτ
//! (methods.md §2.4; Δτ = (δ_i − δ_{i−m})/ω, a few µs) to first order:
//!
//!   d_m = [A(z,t) − A(z,t+τ_g)] − Δτ·Ȧ(z,t+τ_g),
//!
//! exact without phase refinement, otherwise in error by Δτ²/2·|Ä| (≈ 1e-10 mm), or by at most
//! |Δτ|·|ΔȦ| in the rare case that a junction falls between t + τ_g and t + τ.

use super::closed_form::EquivalentParams;
use super::kinematics::{HeightGeometry, ToolKinematics, ToolMotion, Vec3};

/// A 2-D vector in the tool frame (e₁, e₂) of the window's current time (mm or mm/s).
type Plane = [f64; 2];

#[inline]
fn axpy(a: f64, x: Plane, y: Plane) -> Plane {
    [a * x[0] + y[0], a * x[1] + y[1]]
}

/// The motion over one look-back window [t − T, t] (everything that depends on t only).
///
/// ```
/// use runout_core::chip::*;
/// use runout_core::{Cutter, Runout};
/// let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
/// let runout = Runout::new(0.010, 40f64.to_radians()).unwrap();
/// let swing = ConstantSwing::new(Vec3::new(40.0, 0.0, 0.0), Vec3::y(), 1.0, 0.0).unwrap();
/// let kin = ToolKinematics::new(&cutter, &runout, 6000.0, 0.0, SpindleSense::Clockwise, swing).unwrap();
/// let eval = EquivalentEvaluator::new(&kin, &[2.0, 8.0], EquivalentParams::default());
/// let window = eval.look_back(0.05);
/// assert!(window.is_interpolated()); // a constant swing has no junctions
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct LookBack {
    /// Current time t (s).
    pub t: f64,
    /// (sin Θ(t), cos Θ(t)).
    spin: (f64, f64),
    /// False when the motion has a junction in the window (use `shared`).
    smooth: bool,
    /// In the frame (e₁, e₂) of time t: P(t) − P(t−T), u(t) − u(t−T) (their sum with weight z
    /// is A₁ − A₀), Ṗ and Ω×u at t − T and at t (Ȧ = Ṗ + z·Ω×u).
    dp: Plane,
    du: Plane,
    v0: Plane,
    wu0: Plane,
    v1: Plane,
    wu1: Plane,
    /// Junction in the window: per nominal look-back τ_g, [P(t) − P(t+τ_g), u(t) − u(t+τ_g),
    /// Ṗ(t+τ_g), (Ω×u)(t+τ_g)] in the frame of t (empty when smooth).
    shared: Vec<[Plane; 4]>,
}

impl LookBack {
    /// True when the motion is smooth over the window and the Hermite look-back is used;
    /// false when it spans a junction and the shared nominal look-back poses are used.
    pub fn is_interpolated(&self) -> bool {
        self.smooth
    }
}

/// Per-height tables: the height geometry and, per pass (tooth, m) in the order of
/// [`HeightGeometry::pass_index`], `[h₀₀, −T·h₁₀, −T·h₁₁, ΔR, 1/R_{i−m}, Δτ]` (Hermite weights,
/// R_i − R_{i−m}, inverse previous radius, look-back minus its nominal value) — one contiguous
/// row per pass.
#[derive(Debug, Clone, PartialEq)]
struct HeightTable {
    geo: HeightGeometry,
    passes: Vec<[f64; 6]>,
    /// Spindle-frame unit radial direction of each tooth's edge point, (x, y)/R_i.
    unit: Vec<[f64; 2]>,
}

/// Equivalent-model evaluator for a set of heights along any [`ToolMotion`].
///
/// ```
/// use runout_core::chip::*;
/// use runout_core::{Cutter, Runout};
/// // methods.md §7: App. A.3 defaults, edge 0, z = 5, t = T + (5/48)T; the equivalent model
/// // with phase refinement gives 92.99 µm (exact 92.987 µm)
/// let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
/// let runout = Runout::new(0.010, 40f64.to_radians()).unwrap();
/// let motion = StraightFeed { p0: Vec3::zeros(), v: Vec3::new(40.0, 0.0, 0.0), u: Vec3::z(), e1: Vec3::x() };
/// let kin = ToolKinematics::new(&cutter, &runout, 6000.0, 0.0, SpindleSense::CounterClockwise, motion).unwrap();
/// let eval = EquivalentEvaluator::new(&kin, &[5.0], EquivalentParams::default());
/// let window = eval.look_back(0.01 * (1.0 + 5.0 / 48.0));
/// let h = eval.raw(&window, 0, 0).max(0.0);
/// assert!((h * 1e3 - 92.987).abs() < 0.01);
/// ```
#[derive(Debug, Clone)]
pub struct EquivalentEvaluator<'k, M> {
    kin: &'k ToolKinematics<M>,
    params: EquivalentParams,
    /// Window length T = 2π/ω (s).
    window: f64,
    /// Earliest look-back τ over all heights and passes (s, ≤ 0).
    tau_min: f64,
    /// Distinct nominal look-backs τ_g = −gap/ω (s) and the group of each pass (tooth, m).
    nominal: Vec<f64>,
    group: Vec<usize>,
    heights: Vec<HeightTable>,
}

/// Cubic Hermite basis on [0, 1]: (h₀₀, h₁₀, h₁₁) at s (h₀₁ = 1 − h₀₀).
#[inline]
fn hermite(s: f64) -> (f64, f64, f64) {
    let s2 = s * s;
    let s3 = s2 * s;
    (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, s3 - s2)
}

impl<'k, M: ToolMotion> EquivalentEvaluator<'k, M> {
    /// Prepare the heights `heights_mm` (index = position in this slice).
    pub fn new(kin: &'k ToolKinematics<M>, heights_mm: &[f64], params: EquivalentParams) -> Self {
        let window = kin.period();
        let k = kin.cutter().teeth();
        // nominal look-backs are height-independent; group equal ones (uniform pitch: K groups)
        let mut nominal: Vec<f64> = Vec::new();
        let group: Vec<usize> = (0..k)
            .flat_map(|i| (1..=k).map(move |m| -kin.gap_time(i, m)))
            .map(|tau| {
                let same = |g: &f64| (g - tau).abs() <= 1e-12 * window;
                nominal.iter().position(same).unwrap_or_else(|| {
                    nominal.push(tau);
                    nominal.len() - 1
                })
            })
            .collect();
        let mut tau_min = -window;
        let heights = heights_mm
            .iter()
            .map(|&z| {
                let geo = kin.at_height(z);
                let taus = if params.phase_refinement {
                    &geo.tau_aligned
                } else {
                    &geo.tau_nominal
                };
                tau_min = taus.iter().copied().fold(tau_min, f64::min);
                let passes = (0..k)
                    .flat_map(|i| (1..=k).map(move |m| (i, m)))
                    .map(|(i, m)| {
                        let q = geo.pass_index(i, m);
                        let (h00, h10, h11) = hermite(1.0 + taus[q] / window);
                        let rp = geo.radius[geo.previous(i, m)];
                        let shift = taus[q] - nominal[group[q]];
                        [
                            h00,
                            -window * h10,
                            -window * h11,
                            geo.radius[i] - rp,
                            1.0 / rp,
                            shift,
                        ]
                    })
                    .collect();
                let unit = geo
                    .points
                    .iter()
                    .zip(&geo.radius)
                    .map(|(p, r)| [p.xy[0] / r, p.xy[1] / r])
                    .collect();
                HeightTable { geo, passes, unit }
            })
            .collect();
        EquivalentEvaluator {
            kin,
            params,
            window,
            tau_min,
            nominal,
            group,
            heights,
        }
    }

    /// The look-back window ending at time `t`: two poses and one spindle angle, plus one pose
    /// per nominal look-back when the window spans a junction of the motion.
    pub fn look_back(&self, t: f64) -> LookBack {
        let kin = self.kin;
        let motion = kin.motion();
        let now = motion.pose(t);
        let back = motion.pose(t - self.window);
        let e1 = now.e1;
        let e2 = now.u.cross(&now.e1) * kin.sense().sigma();
        let plane = |v: Vec3| [v.dot(&e1), v.dot(&e2)];
        let smooth = motion.smooth_on(t + self.tau_min, t);
        let shared = if smooth {
            Vec::new()
        } else {
            self.nominal
                .iter()
                .map(|tau| {
                    let p = motion.pose(t + tau);
                    [
                        plane(now.p - p.p),
                        plane(now.u - p.u),
                        plane(p.v),
                        plane(p.w.cross(&p.u)),
                    ]
                })
                .collect()
        };
        LookBack {
            t,
            spin: kin.spindle_angle(t).sin_cos(),
            smooth,
            dp: plane(now.p - back.p),
            du: plane(now.u - back.u),
            v0: plane(back.v),
            wu0: plane(back.w.cross(&back.u)),
            v1: plane(now.v),
            wu1: plane(now.w.cross(&now.u)),
            shared,
        }
    }

    /// Raw equivalent IUCT (mm; negative = no chip) of `tooth` at height index `height` at the
    /// window's time, eq. (2.8) with d_m from the look-back (module docs).
    #[inline]
    pub fn raw(&self, w: &LookBack, height: usize, tooth: usize) -> f64 {
        self.at_height(w, height).raw(tooth)
    }

    /// The window's quantities at one height, for evaluating several teeth there.
    #[inline]
    pub fn at_height<'a>(&'a self, w: &'a LookBack, height: usize) -> HeightLookBack<'a, 'k, M> {
        let tab = &self.heights[height];
        let z = tab.geo.z;
        HeightLookBack {
            eval: self,
            w,
            tab,
            d01: axpy(z, w.du, w.dp),
            a0: axpy(z, w.wu0, w.v0),
            a1: axpy(z, w.wu1, w.v1),
        }
    }
}

/// A [`LookBack`] window at one prepared height: A₁ − A₀, Ȧ₀, Ȧ₁ in the frame of t.
///
/// ```
/// use runout_core::chip::*;
/// use runout_core::{Cutter, Runout};
/// let cutter = Cutter::flat(10.0, 4, 30.0f64.to_radians()).unwrap();
/// let kin = ToolKinematics::new(&cutter, &Runout::none(), 6000.0, 0.0,
///     SpindleSense::Clockwise, StraightFeed::along_x(40.0)).unwrap();
/// let eval = EquivalentEvaluator::new(&kin, &[5.0], EquivalentParams::default());
/// let window = eval.look_back(0.0321);
/// let at = eval.at_height(&window, 0);
/// // every tooth of the height from one set of window vectors; no runout: the teeth share the
/// // chip, and the largest is close to f_z = 40 mm/s / (4 · 100 rev/s) = 0.1 mm
/// let h: Vec<f64> = (0..4).map(|i| at.raw(i).max(0.0)).collect();
/// assert!(h.iter().all(|&x| x <= 0.1 + 1e-3));
/// assert!(h.iter().any(|&x| x > 0.05));
/// ```
#[derive(Debug, Clone, Copy)]
pub struct HeightLookBack<'a, 'k, M> {
    eval: &'a EquivalentEvaluator<'k, M>,
    w: &'a LookBack,
    tab: &'a HeightTable,
    d01: Plane,
    a0: Plane,
    a1: Plane,
}

impl<M: ToolMotion> HeightLookBack<'_, '_, M> {
    /// Raw equivalent IUCT (mm; negative = no chip) of `tooth`, eq. (2.8).
    ///
    /// d_m·n and d_m·t̂ are linear in the Hermite weights, so the three window vectors are
    /// projected on n and t̂ once per point and each pass costs six multiply-adds for them.
    #[inline]
    pub fn raw(&self, tooth: usize) -> f64 {
        let (w, tab) = (self.w, self.tab);
        // ray n = (a, b)/R in (e₁, e₂), t̂ = (−b, a)/R (eq. 2.1 rotated by Θ(t))
        let [x, y] = tab.unit[tooth];
        let (sn, cs) = w.spin;
        let n = [x * cs - y * sn, x * sn + y * cs];
        let dot_n = |v: Plane| v[0] * n[0] + v[1] * n[1];
        let dot_t = |v: Plane| v[1] * n[0] - v[0] * n[1];
        let an = dot_n(self.a1) * self.eval.kin.inv_omega();
        let k2an = self.eval.params.k2 * an;
        let half_k1 = 0.5 * self.eval.params.k1;
        let value = |delta_r: f64, inv_rp: f64, dn: f64, dt: f64| {
            delta_r + dn + dt * inv_rp * (half_k1 * dt - k2an)
        };
        let k = tab.geo.teeth();
        let rows = &tab.passes[tooth * k..(tooth + 1) * k];
        let mut h = f64::INFINITY;
        if w.smooth {
            let pn = [dot_n(self.d01), dot_n(self.a0), dot_n(self.a1)];
            let pt = [dot_t(self.d01), dot_t(self.a0), dot_t(self.a1)];
            for &[c0, c1, c2, delta_r, inv_rp, _] in rows {
                let dn = c0 * pn[0] + c1 * pn[1] + c2 * pn[2];
                let dt = c0 * pt[0] + c1 * pt[1] + c2 * pt[2];
                h = min(h, value(delta_r, inv_rp, dn, dt));
            }
        } else {
            let z = tab.geo.z;
            let groups = &self.eval.group[tooth * k..(tooth + 1) * k];
            for (&[.., delta_r, inv_rp, shift], &g) in rows.iter().zip(groups) {
                let [dp, du, v, wu] = w.shared[g];
                let (d0, a0) = (axpy(z, du, dp), axpy(z, wu, v));
                let d = [d0[0] - shift * a0[0], d0[1] - shift * a0[1]];
                h = min(h, value(delta_r, inv_rp, dot_n(d), dot_t(d)));
            }
        }
        h
    }
}

/// min(h, v) as a plain compare (one `minsd`) instead of f64::min's NaN blend on the
/// loop-carried chain: 10 % faster in `benches/chip.rs`; a NaN v is skipped by both.
#[inline(always)]
fn min(h: f64, v: f64) -> f64 {
    if v < h {
        v
    } else {
        h
    }
}
