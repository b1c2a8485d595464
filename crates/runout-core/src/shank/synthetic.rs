//! Synthetic shank-sensor recordings for tests, examples and benchmarks: the beam's deflection
//! under a periodic cutting force plus the air-cut pattern (runout offset + tilt and shank form
//! error rotating with the spindle), gap offsets, optional drift, spindle-speed error and sensor
//! noise — the forward model that [`super::process_in_memory`] inverts. With a [`MeasuringChain`]
//! the tool's bending response is included (issue 11 item 7): the deflections follow the force
//! through H of the axis, integrated in the time domain by [`crate::chain::AxisChain::filter`]
//! (exact for a force linear between samples), so that a recording through a mode tests the
//! correction.

use super::{PairAxis, ShankBeam};
use crate::chain::MeasuringChain;
use std::f64::consts::TAU;

/// Parameters of a synthetic recording.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticShank {
    /// Beam (sensor heights, tool length, stiffness).
    pub beam: ShankBeam,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// True spindle speed, rpm (the nominal one may differ).
    pub rpm: f64,
    /// Revolutions of air cut before, of cut, of air cut after.
    pub revolutions: (f64, f64, f64),
    /// Runout offset at the tip (x, y) in the spindle frame at θ = 0, mm.
    pub offset_mm: (f64, f64),
    /// Tilt vector, mm/mm.
    pub tilt: (f64, f64),
    /// Shank form error: amplitude (mm) of the 2× and 3× harmonics.
    pub form_mm: (f64, f64),
    /// Gap (DC) of sensors I and II, mm.
    pub gap_mm: (f64, f64),
    /// Linear drift of sensor II over the record, mm.
    pub drift_mm: f64,
    /// Revolutions of linear force ramp at entry and exit.
    pub ramp_revolutions: f64,
    /// Add a once-per-revolution pulse channel (5 V for 5 % of a revolution from θ = 0).
    pub pulse: bool,
    /// Bending response between the force and the deflections, per axis (x, y; z unused);
    /// rigid by default.
    pub chain: MeasuringChain,
}

/// A generated recording.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticRecording {
    /// Columns: per axis (x, y) sensor I and II displacement (mm), then the pulse if any.
    pub columns: Vec<Vec<f64>>,
    /// True force on the workpiece per axis, N (before the chain).
    pub force_n: [Vec<f64>; 2],
    /// First and one-past-last sample of the cut.
    pub cut: (usize, usize),
}

impl SyntheticShank {
    /// Generate with the force on the workpiece given per revolution (`fx`, `fy` sampled
    /// uniformly over one revolution of θ, periodic) and a noise source (mm per call).
    pub fn generate(
        &self,
        fx: &[f64],
        fy: &[f64],
        noise: impl FnMut() -> f64,
    ) -> SyntheticRecording {
        self.generate_with_random_force(fx, fy, 0.0, noise)
    }

    /// As [`SyntheticShank::generate`], plus a random (white, Gaussian, per-sample independent,
    /// reproducible) force of RMS `random_force_n` N on each axis during the cut, scaled by the
    /// entry/exit ramp — the broadband part of a real cutting force that makes the bending
    /// resonance visible in the cut spectrum. It is part of the true force.
    pub fn generate_with_random_force(
        &self,
        fx: &[f64],
        fy: &[f64],
        random_force_n: f64,
        mut noise: impl FnMut() -> f64,
    ) -> SyntheticRecording {
        // xorshift64 + Box–Muller, fixed seed
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let mut gauss = move || {
            let (u1, u2) = (uniform(), uniform());
            (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
        };
        let per_rev = fx.len();
        let force_at = |th: f64, v: &[f64]| {
            let u = (th / TAU).rem_euclid(1.0) * per_rev as f64;
            let i = u.floor() as usize % per_rev;
            let w = u - u.floor();
            v[i] * (1.0 - w) + v[(i + 1) % per_rev] * w
        };
        let b = &self.beam;
        let (c1, c2) = (
            b.compliance_at_mm_per_n(b.l1_mm),
            b.compliance_at_mm_per_n(b.l2_mm),
        );
        let (z1, z2) = (b.tool_length_mm - b.l1_mm, b.tool_length_mm - b.l2_mm);
        let f = self.rpm / 60.0;
        let (ra, rc, rb) = self.revolutions;
        let fs = self.sample_rate_hz;
        let total = ((ra + rc + rb) / f * fs) as usize;
        let start = (ra / f * fs) as usize;
        let end = ((ra + rc) / f * fs) as usize;
        let mut cols = vec![Vec::with_capacity(total); 4 + usize::from(self.pulse)];
        let (mut tx, mut ty) = (Vec::with_capacity(total), Vec::with_capacity(total));
        let e_at = |z: f64| {
            (
                self.offset_mm.0 + z * self.tilt.0,
                self.offset_mm.1 + z * self.tilt.1,
            )
        };
        for k in 0..total {
            let th = TAU * f * k as f64 / fs;
            let rev = th / TAU;
            let env = if k < start || k >= end {
                0.0
            } else {
                let r_in = (rev - ra).min(ra + rc - rev);
                (r_in / self.ramp_revolutions.max(1e-9)).clamp(0.0, 1.0)
            };
            let (rx, ry) = if random_force_n > 0.0 && env > 0.0 {
                (random_force_n * gauss(), random_force_n * gauss())
            } else {
                (0.0, 0.0)
            };
            tx.push(env * (force_at(th, fx) + rx));
            ty.push(env * (force_at(th, fy) + ry));
        }
        // the force the deflections follow: through the bending response of each axis
        let seen = [self.chain.x.filter(fs, &tx), self.chain.y.filter(fs, &ty)];
        for (k, (&sx, &sy)) in seen[0].iter().zip(&seen[1]).enumerate() {
            let t = k as f64 / fs;
            let th = TAU * f * t;
            let rev = th / TAU;
            for axis in [PairAxis::X, PairAxis::Y] {
                let a = usize::from(axis == PairAxis::Y);
                let f_wp = if a == 0 { sx } else { sy };
                for (h, (z, c, gap)) in [(z1, c1, self.gap_mm.0), (z2, c2, self.gap_mm.1)]
                    .into_iter()
                    .enumerate()
                {
                    let e = e_at(z);
                    // x sensor sees Re(E·e^{jθ}), y sensor −Im(E·e^{jθ}) (clockwise rotation)
                    let (re, im) = (
                        e.0 * th.cos() - e.1 * th.sin(),
                        e.0 * th.sin() + e.1 * th.cos(),
                    );
                    let runout = if a == 0 { re } else { -im };
                    let form = self.form_mm.0 * (2.0 * th + 0.3 + h as f64).cos()
                        / (1.0 + h as f64)
                        + self.form_mm.1 * (3.0 * th + 1.1 * a as f64).sin();
                    let drift = self.drift_mm * t / (total as f64 / fs) * h as f64;
                    // the tool is pushed by −F (force on the workpiece is F)
                    cols[2 * a + h].push(gap + runout + form + c * (-f_wp) + drift + noise());
                }
            }
            if self.pulse {
                cols[4].push(if rev.fract() < 0.05 { 5.0 } else { 0.0 });
            }
        }
        SyntheticRecording {
            columns: cols,
            force_n: [tx, ty],
            cut: (start, end),
        }
    }
}
