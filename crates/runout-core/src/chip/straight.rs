//! The exact and equivalent models in steady 3-axis straight feed behind the
//! [`ChipThickness`] interface used by the force simulation.
//!
//! Frame (conventions.md): feed along +x, u = +z, e₁ = +y, clockwise rotation, so the spindle
//! angle of a tooth is its immersion angle φ (clockwise from +y). Tooth i at nominal immersion φ
//! at height z is evaluated at the time where Θ(t) + ψ_i(z) = φ. In steady straight feed h depends
//! only on (i, z, φ) (shifting t by one revolution translates the whole picture), so the spindle
//! speed is immaterial; the kinematics run at 60 rpm (T = 1 s) with feed K·f_z per revolution.

use super::closed_form::EquivalentParams;
use super::exact::{exact_iuct, NewtonOptions};
use super::kinematics::{SpindleSense, StraightFeed, ToolKinematics};
use super::{ChipAtHeight, ChipThickness};
use crate::angle::wrap_pi;
use crate::cutter::Cutter;
use crate::error::{positive, ParamError};
use crate::runout::Runout;
use std::f64::consts::TAU;
use std::sync::Arc;

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
    ToolKinematics::new(
        cutter,
        runout,
        RPM,
        0.0,
        SpindleSense::Clockwise,
        motion,
    )
}

/// Exact IUCT (methods.md eq. 2.2–2.3) in steady 3-axis straight feed.
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
    kin: Arc<ToolKinematics<StraightFeed>>,
    opts: NewtonOptions,
}

impl ExactChip {
    /// Model for `cutter` with `runout` at feed per tooth `fz_mm`.
    pub fn new(cutter: &Cutter, runout: &Runout, fz_mm: f64) -> Result<Self, ParamError> {
        Ok(ExactChip {
            kin: Arc::new(straight_feed_kinematics(cutter, runout, fz_mm)?),
            opts: NewtonOptions::default(),
        })
    }
    /// The underlying kinematics.
    pub fn kinematics(&self) -> &ToolKinematics<StraightFeed> {
        &self.kin
    }
}

/// [`ExactChip`] at one height.
#[derive(Debug, Clone)]
pub struct ExactAtHeight {
    kin: Arc<ToolKinematics<StraightFeed>>,
    z: f64,
    opts: NewtonOptions,
}

impl ChipThickness for ExactChip {
    type AtHeight = ExactAtHeight;
    fn name(&self) -> &'static str {
        "exact"
    }
    fn at_height(&self, z: f64) -> ExactAtHeight {
        ExactAtHeight {
            kin: self.kin.clone(),
            z,
            opts: self.opts,
        }
    }
}

impl ChipAtHeight for ExactAtHeight {
    fn thickness(&self, tooth: usize, phi: f64, _sin_phi: f64, _cos_phi: f64) -> f64 {
        let t = self.kin.time_at_tooth_angle(tooth, self.z, phi);
        exact_iuct(&self.kin, tooth, self.z, t, &self.opts).h()
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

/// Per (tooth, m) constants of [`EquivalentChip`] at one height.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct PassConst {
    delta_r: f64,
    d: f64,
    /// k₁·D²/(2R_p)
    c1: f64,
    /// k₂·D·a/R_p
    c2: f64,
}

/// [`EquivalentChip`] at one height.
#[derive(Debug, Clone)]
pub struct EquivalentAtHeight {
    k: usize,
    /// (cos δ_i, sin δ_i) per tooth.
    shift: Vec<(f64, f64)>,
    pass: Vec<PassConst>,
}

impl ChipThickness for EquivalentChip {
    type AtHeight = EquivalentAtHeight;
    fn name(&self) -> &'static str {
        "equivalent"
    }
    fn at_height(&self, z: f64) -> EquivalentAtHeight {
        let k = self.cutter.teeth();
        let feed_rev = self.fz * k as f64;
        let a = feed_rev / TAU;
        let pts: Vec<(f64, f64)> = (0..k)
            .map(|i| self.runout.tooth_point(&self.cutter, i, z))
            .collect();
        let radius = |i: usize| pts[i].0.hypot(pts[i].1);
        let phase = |i: usize| pts[i].1.atan2(pts[i].0);
        let shift = (0..k)
            .map(|i| {
                let d = wrap_pi(phase(i) - self.cutter.tooth_angle(i, z));
                (d.cos(), d.sin())
            })
            .collect();
        let mut pass = Vec::with_capacity(k * k);
        for i in 0..k {
            for m in 1..=k {
                let p = (i + k * m - m) % k;
                let gap = self.cutter.gap(i, m);
                let turn = if self.params.phase_refinement {
                    gap - wrap_pi(phase(i) - phase(p) + gap)
                } else {
                    gap
                };
                let d = feed_rev * turn / TAU;
                let rp = radius(p);
                pass.push(PassConst {
                    delta_r: radius(i) - rp,
                    d,
                    c1: self.params.k1 * d * d / (2.0 * rp),
                    c2: self.params.k2 * d * a / rp,
                });
            }
        }
        EquivalentAtHeight { k, shift, pass }
    }
}

impl ChipAtHeight for EquivalentAtHeight {
    #[inline]
    fn thickness(&self, tooth: usize, _phi: f64, sin_phi: f64, cos_phi: f64) -> f64 {
        let (cd, sd) = self.shift[tooth];
        let s = sin_phi * cd + cos_phi * sd;
        let c = cos_phi * cd - sin_phi * sd;
        let mut h = f64::INFINITY;
        for p in &self.pass[tooth * self.k..(tooth + 1) * self.k] {
            h = h.min(p.delta_r + p.d * s + p.c1 * c * c - p.c2 * c * s);
        }
        h.max(0.0)
    }
}
