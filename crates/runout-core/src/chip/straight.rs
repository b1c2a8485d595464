//! The exact and equivalent models in steady 3-axis straight feed behind the
//! [`ChipThickness`] interface used by the force simulation.
//!
//! Frame (conventions.md): feed along +x, u = +z, e₁ = +y, clockwise rotation, so the spindle
//! angle of a tooth is its immersion angle φ (clockwise from +y). Tooth i at nominal immersion φ
//! at height z is evaluated at the time where Θ(t) + ψ_i(z) = φ. In steady straight feed h depends
//! only on (i, z, φ) (shifting t by one revolution translates the whole picture), so the spindle
//! speed is immaterial; the kinematics run at 60 rpm (T = 1 s) with feed K·f_z per revolution.

use super::closed_form::EquivalentParams;
use super::exact::NewtonOptions;
use super::kinematics::{small_sin_cos, SpindleSense, StraightFeed, ToolKinematics};
use super::{ChipAtHeight, ChipThickness};
use crate::angle::wrap_pi;
use crate::cutter::Cutter;
use crate::error::{positive, ParamError};
use crate::runout::Runout;
use std::f64::consts::TAU;

/// Spindle speed of the internal kinematics (rpm): any value gives the same h.
const RPM: f64 = 60.0;

/// Steady 3-axis straight-feed kinematics for `cutter` with `runout` at feed per tooth `fz_mm`.
pub fn straight_feed_kinematics(
    cutter: &Cutter,
    runout: &Runout,
    fz_mm: f64,
) -> Result<ToolKinematics<StraightFeed>, ParamError> {
    positive("fz_mm", fz_mm)?;
    let feed_per_rev = fz_mm * cutter.teeth() as f64;
    let motion = StraightFeed::along_x(feed_per_rev * RPM / 60.0);
    ToolKinematics::new(cutter, runout, RPM, 0.0, SpindleSense::Clockwise, motion)
}

/// Exact IUCT (methods.md eq. 2.2–2.3) in steady 3-axis straight feed.
///
/// With a constant axis the trajectory of every edge point at height z stays in the plane of the
/// ray, so eq. (2.3) reduces exactly to one scalar equation (methods.md §2.4, "exact-for-straight-
/// feed alternative"): with the previous tooth's effective edge aligned with the ray at look-back
/// τ₀ (eq. 0.2), d = K f_z·(turn/2π)·x̂ the feed since then, a = K f_z/2π·x̂ the feed per radian and
/// ψ the further spindle rotation to the crossing,
///
/// R_p sin ψ + (a·t̂)ψ = d·t̂,   s = R_p cos ψ − d·n + ψ (a·n),   h = max(0, R_i − max_m s_m),
///
/// solved by Newton in ψ to |Δψ|·R_p < 1e-12 mm. Identical to [`super::exact_iuct`] (3-D Newton)
/// on [`straight_feed_kinematics`] (tested to 1e-11 mm).
///
/// ```
/// use runout_core::{ChipThickness, Cutter, Runout, ExactChip};
/// let cutter = Cutter::flat(10.0, 4, 0.0).unwrap();
/// let exact = ExactChip::new(&cutter, &Runout::none(), 0.1).unwrap();
/// // the trochoid: close to f_z·sin φ at 90° (second-order term f²cos²φ/2R vanishes there)
/// let h = exact.thickness(0, 2.0, 90f64.to_radians());
/// assert!((h - 0.1).abs() < 1e-5);
/// ```
#[derive(Debug, Clone)]
pub struct ExactChip {
    cutter: Cutter,
    runout: Runout,
    fz: f64,
    opts: NewtonOptions,
}

impl ExactChip {
    /// Model for `cutter` with `runout` at feed per tooth `fz_mm`.
    pub fn new(cutter: &Cutter, runout: &Runout, fz_mm: f64) -> Result<Self, ParamError> {
        positive("fz_mm", fz_mm)?;
        Ok(ExactChip {
            cutter: cutter.clone(),
            runout: *runout,
            fz: fz_mm,
            opts: NewtonOptions::default(),
        })
    }
    /// The equivalent 3-D kinematics (for the general solvers).
    pub fn kinematics(&self) -> ToolKinematics<StraightFeed> {
        straight_feed_kinematics(&self.cutter, &self.runout, self.fz).expect("validated")
    }
}

/// Per (tooth, m) constants of the straight-feed models at one height.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Pass {
    /// R_i − R_{i−m} (mm).
    delta_r: f64,
    /// R_{i−m} (mm).
    r_prev: f64,
    /// 1/R_{i−m} (1/mm).
    inv_r_prev: f64,
    /// Feed D_m since the aligned (or nominal) pass of tooth i − m (mm).
    d: f64,
}

/// Per-height tables shared by the straight-feed exact and equivalent models.
#[derive(Debug, Clone)]
struct StraightHeight {
    k: usize,
    /// (cos δ_i, sin δ_i) per tooth.
    shift: Vec<(f64, f64)>,
    pass: Vec<Pass>,
    /// Feed per radian K f_z/2π (mm/rad).
    a: f64,
}

impl StraightHeight {
    fn new(cutter: &Cutter, runout: &Runout, fz: f64, z: f64, aligned: bool) -> Self {
        let k = cutter.teeth();
        let feed_rev = fz * k as f64;
        let pts: Vec<(f64, f64)> = (0..k).map(|i| runout.tooth_point(cutter, i, z)).collect();
        let radius = |i: usize| pts[i].0.hypot(pts[i].1);
        let phase = |i: usize| pts[i].1.atan2(pts[i].0);
        let shift = (0..k)
            .map(|i| {
                let d = wrap_pi(phase(i) - cutter.tooth_angle(i, z));
                (d.cos(), d.sin())
            })
            .collect();
        let mut pass = Vec::with_capacity(k * k);
        for i in 0..k {
            for m in 1..=k {
                let p = (i + k * m - m) % k;
                let gap = cutter.gap(i, m);
                let turn = if aligned {
                    gap - wrap_pi(phase(i) - phase(p) + gap)
                } else {
                    gap
                };
                pass.push(Pass {
                    delta_r: radius(i) - radius(p),
                    r_prev: radius(p),
                    inv_r_prev: 1.0 / radius(p),
                    d: feed_rev * turn / TAU,
                });
            }
        }
        StraightHeight {
            k,
            shift,
            pass,
            a: feed_rev / TAU,
        }
    }

    /// (sin, cos) of the effective immersion φ + δ_i.
    #[inline]
    fn effective(&self, tooth: usize, sin_phi: f64, cos_phi: f64) -> (f64, f64) {
        let (cd, sd) = self.shift[tooth];
        (sin_phi * cd + cos_phi * sd, cos_phi * cd - sin_phi * sd)
    }

    #[inline]
    fn passes(&self, tooth: usize) -> &[Pass] {
        &self.pass[tooth * self.k..(tooth + 1) * self.k]
    }
}

/// [`ExactChip`] at one height.
#[derive(Debug, Clone)]
pub struct ExactAtHeight {
    geo: StraightHeight,
    opts: NewtonOptions,
}

impl ChipThickness for ExactChip {
    type AtHeight = ExactAtHeight;
    fn name(&self) -> &'static str {
        "exact"
    }
    fn at_height(&self, z: f64) -> ExactAtHeight {
        ExactAtHeight {
            geo: StraightHeight::new(&self.cutter, &self.runout, self.fz, z, true),
            opts: self.opts,
        }
    }
}

impl ExactAtHeight {
    /// R_i − s_m for one previous pass: scalar Newton on ψ (see [`ExactChip`]).
    #[inline]
    fn pass_thickness(&self, p: &Pass, s: f64, c: f64) -> f64 {
        let a = self.geo.a;
        let (dt, at) = (p.d * c, a * c);
        let mut psi = dt / (p.r_prev + at);
        for _ in 0..self.opts.max_iter {
            let (sn, cs) = small_sin_cos(psi);
            let step = (p.r_prev * sn + at * psi - dt) / (p.r_prev * cs + at);
            psi -= step;
            if (step * p.r_prev).abs() < self.opts.tol_mm {
                break;
            }
        }
        let cs = small_sin_cos(psi).1;
        // R_i − s = ΔR + R_p − (R_p cos ψ − d·n + ψ a·n)
        p.delta_r + p.r_prev * (1.0 - cs) + p.d * s - psi * a * s
    }
}

impl ChipAtHeight for ExactAtHeight {
    #[inline]
    fn thickness(&self, tooth: usize, _phi: f64, sin_phi: f64, cos_phi: f64) -> f64 {
        let (s, c) = self.geo.effective(tooth, sin_phi, cos_phi);
        let mut h = f64::INFINITY;
        for p in self.geo.passes(tooth) {
            h = h.min(self.pass_thickness(p, s, c));
        }
        h.max(0.0)
    }
}

/// Equivalent-thickness model (methods.md eq. 2.8) in steady 3-axis straight feed, evaluated
/// without trigonometry: with φₑ = φ + δ_i the effective immersion, s = sin φₑ, c = cos φₑ,
/// D_m the feed travelled since the (phase-refined) pass of tooth i−m and a = K f_z/2π,
///
/// h = max(0, min_m [ ΔR_m + D_m s + k₁ D_m² c²/(2R_{i−m}) − k₂ D_m c·a s/R_{i−m} ]).
///
/// Identical to [`super::equivalent_iuct`] on [`straight_feed_kinematics`] (tested).
#[derive(Debug, Clone)]
pub struct EquivalentChip {
    cutter: Cutter,
    runout: Runout,
    fz: f64,
    params: EquivalentParams,
}

impl EquivalentChip {
    /// Model with compensation `params` (use `EquivalentParams::default()` for k₁ = k₂ = 1
    /// with phase refinement).
    pub fn new(
        cutter: &Cutter,
        runout: &Runout,
        fz_mm: f64,
        params: EquivalentParams,
    ) -> Result<Self, ParamError> {
        positive("fz_mm", fz_mm)?;
        Ok(EquivalentChip {
            cutter: cutter.clone(),
            runout: *runout,
            fz: fz_mm,
            params,
        })
    }
}

/// [`EquivalentChip`] at one height: per (tooth, m) the coefficients of
/// h_m = ΔR + D·s + [k₁D²/2R_p]·c² − [k₂D·a/R_p]·c·s, stored as structure-of-arrays so that the
/// min over m is a short branch-free loop.
#[derive(Debug, Clone)]
pub struct EquivalentAtHeight {
    k: usize,
    /// (cos δ_i, sin δ_i) per tooth.
    shift: Vec<(f64, f64)>,
    delta_r: Vec<f64>,
    d: Vec<f64>,
    circle: Vec<f64>,
    trochoid: Vec<f64>,
}

impl ChipThickness for EquivalentChip {
    type AtHeight = EquivalentAtHeight;
    fn name(&self) -> &'static str {
        "equivalent"
    }
    fn at_height(&self, z: f64) -> EquivalentAtHeight {
        let geo = StraightHeight::new(
            &self.cutter,
            &self.runout,
            self.fz,
            z,
            self.params.phase_refinement,
        );
        let (k1, k2, a) = (self.params.k1, self.params.k2, geo.a);
        let col = |f: &dyn Fn(&Pass) -> f64| geo.pass.iter().map(f).collect::<Vec<f64>>();
        EquivalentAtHeight {
            k: geo.k,
            shift: geo.shift.clone(),
            delta_r: col(&|p| p.delta_r),
            d: col(&|p| p.d),
            circle: col(&|p| k1 * p.d * p.d * 0.5 * p.inv_r_prev),
            trochoid: col(&|p| k2 * p.d * a * p.inv_r_prev),
        }
    }
}

impl ChipAtHeight for EquivalentAtHeight {
    #[inline]
    fn thickness(&self, tooth: usize, _phi: f64, sin_phi: f64, cos_phi: f64) -> f64 {
        let (cd, sd) = self.shift[tooth];
        let s = sin_phi * cd + cos_phi * sd;
        let c = cos_phi * cd - sin_phi * sd;
        let (cc, cs) = (c * c, c * s);
        let r = tooth * self.k..(tooth + 1) * self.k;
        let (dr, d) = (&self.delta_r[r.clone()], &self.d[r.clone()]);
        let (ci, tr) = (&self.circle[r.clone()], &self.trochoid[r]);
        let n = dr.len();
        // equal lengths let the optimiser drop the bounds checks
        assert!(d.len() == n && ci.len() == n && tr.len() == n);
        let term = |m: usize| dr[m] + d[m] * s + ci[m] * cc - tr[m] * cs;
        // two interleaved minima halve the dependency chain of the reduction
        let (mut h0, mut h1) = (f64::INFINITY, f64::INFINITY);
        let mut m = 0;
        while m + 1 < n {
            h0 = h0.min(term(m));
            h1 = h1.min(term(m + 1));
            m += 2;
        }
        if m < n {
            h0 = h0.min(term(m));
        }
        h0.min(h1).max(0.0)
    }
}
