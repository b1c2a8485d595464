//! Arc (circular-path) chip model with runout, `conventions.md` and methods.md eq. (0.4):
//!
//! h_i(φ) = max(0, min_{m=1..K} [ f_{i,m}·sin φ + R_i − R_{i−m} ])
//!
//! with f_{i,m} the feed between the passes of tooth i−m and tooth i: m·f_z for uniform pitch,
//! K·f_z·(gap angle)/2π for variable pitch. The min over m handles teeth that skip the cut.

use super::{ChipAtHeight, ChipThickness};
use crate::cutter::Cutter;
use crate::error::{positive, ParamError};
use crate::runout::Runout;
use std::f64::consts::TAU;

/// Arc chip-thickness model (linear in sin φ).
#[derive(Debug, Clone)]
pub struct ArcChip {
    cutter: Cutter,
    runout: Runout,
    fz: f64,
}

impl ArcChip {
    /// Model for `cutter` with `runout` at feed per tooth `fz_mm`.
    pub fn new(cutter: &Cutter, runout: &Runout, fz_mm: f64) -> Result<Self, ParamError> {
        positive("fz_mm", fz_mm)?;
        Ok(ArcChip {
            cutter: cutter.clone(),
            runout: *runout,
            fz: fz_mm,
        })
    }
}

/// Arc model prepared at one height: per (tooth, m) feed and radius difference.
#[derive(Debug, Clone)]
pub struct ArcAtHeight {
    k: usize,
    /// `feed[i*k + m-1]` = f_{i,m} (mm).
    feed: Vec<f64>,
    /// `dr[i*k + m-1]` = R_i − R_{i−m} (mm).
    dr: Vec<f64>,
}

impl ArcAtHeight {
    /// Actual radius differences R_i − R_{i−m} (mm), `m` in `1..=K`.
    pub fn radius_difference(&self, tooth: usize, m: usize) -> f64 {
        self.dr[tooth * self.k + m - 1]
    }

    /// Feed f_{i,m} (mm) between the passes of tooth i−m and tooth i, `m` in `1..=K`.
    pub fn feed(&self, tooth: usize, m: usize) -> f64 {
        self.feed[tooth * self.k + m - 1]
    }
}

impl ChipThickness for ArcChip {
    type AtHeight = ArcAtHeight;

    fn name(&self) -> &'static str {
        "arc"
    }

    fn at_height(&self, z: f64) -> ArcAtHeight {
        let k = self.cutter.teeth();
        let radii = self.runout.tooth_radii(&self.cutter, z);
        let mut feed = Vec::with_capacity(k * k);
        let mut dr = Vec::with_capacity(k * k);
        for i in 0..k {
            for m in 1..=k {
                let gap = self.cutter.gap(i, m);
                feed.push(self.fz * k as f64 * gap / TAU);
                dr.push(radii[i] - radii[(i + k * m - m) % k]);
            }
        }
        ArcAtHeight { k, feed, dr }
    }
}

impl ChipAtHeight for ArcAtHeight {
    #[inline]
    fn thickness(&self, tooth: usize, _phi: f64, sin_phi: f64, _cos_phi: f64) -> f64 {
        let base = tooth * self.k;
        let feed = &self.feed[base..base + self.k];
        let dr = &self.dr[base..base + self.k];
        let mut h = f64::INFINITY;
        for (f, d) in feed.iter().zip(dr) {
            h = h.min(f * sin_phi + d);
        }
        h.max(0.0)
    }
}
