//! Interpolation of the deviation map onto an edge point (u, α) (methods.md §5.3, §5.5).

use super::deviation::{DeviationMap, LayerDeviation};
use crate::angle::wrap_tau;
use std::f64::consts::TAU;

/// How the deviation is carried from the probe grid to an edge point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scheme {
    /// Per-layer first harmonic (c_i, s_i), linear in u, evaluated exactly in angle:
    /// ε = c(u) cos α + s(u) sin α (methods.md §5.5). Exact for a rigid offset + tilt. Default.
    #[default]
    FirstHarmonic,
    /// The seed's bilinear interpolation of δ_ij in (u, α) with periodic wrap
    /// α_{C+1} = 2π + α_1 (methods.md §5.3). Its angular chord error is up to
    /// |e|·(1 − cos(π/C)).
    Bilinear,
}

/// What to do with an edge point outside the probed range [u_1, u_M].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RangePolicy {
    /// Use the end layer's value (s clamped to [0, 1]). Default.
    #[default]
    Clamp,
    /// Extend the end segment linearly (s < 0 or s > 1); the error grows with tilt noise.
    Extrapolate,
}

/// ε at one edge point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interpolated {
    /// Radial deviation ε (mm): > 0 means the real bar surface is outward at that angle.
    pub eps: f64,
    /// True when u was outside [u_1, u_M] (then the [`RangePolicy`] was applied).
    pub outside: bool,
}

/// Evaluates ε(u, α) on a deviation map.
#[derive(Debug, Clone)]
pub struct Interpolator<'a> {
    map: &'a DeviationMap,
    u: Vec<f64>,
    scheme: Scheme,
    range: RangePolicy,
}

impl<'a> Interpolator<'a> {
    /// An interpolator over `map` (which has ≥ 2 layers, each with ≥ 3 angles, by construction).
    pub fn new(map: &'a DeviationMap, scheme: Scheme, range: RangePolicy) -> Self {
        Interpolator {
            map,
            u: map.u(),
            scheme,
            range,
        }
    }

    /// The scheme in use.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// The range policy in use.
    pub fn range(&self) -> RangePolicy {
        self.range
    }

    /// ε(u, α): layer segment u_m ≤ u ≤ u_{m+1}, s = (u − u_m)/(u_{m+1} − u_m), then the scheme
    /// (methods.md §5.3 bilinear; §5.5 first harmonic). `alpha` in rad, any range.
    ///
    /// ```
    /// use runout_core::grind::*;
    /// let alpha: Vec<f64> = (0..8).map(|j| j as f64 * std::f64::consts::TAU / 8.0).collect();
    /// let u = [0.0, 10.0];
    /// let r: Vec<Vec<f64>> = u.iter().map(|_| alpha.iter().map(|a| 3.0 + 0.01 * a.cos()).collect()).collect();
    /// let grid = ProbeGrid::from_radii(&u, &alpha, &r, Generatrix::cylinder(3.0).unwrap()).unwrap();
    /// let map = DeviationMap::new(&grid);
    /// let f = Interpolator::new(&map, Scheme::FirstHarmonic, RangePolicy::Clamp);
    /// assert!((f.eval(5.0, 1.0).eps - 0.01 * 1f64.cos()).abs() < 1e-12);
    /// ```
    pub fn eval(&self, u: f64, alpha: f64) -> Interpolated {
        let n = self.u.len();
        let m = self.u.partition_point(|&x| x <= u).clamp(1, n - 1) - 1;
        let mut s = (u - self.u[m]) / (self.u[m + 1] - self.u[m]);
        let outside = !(0.0..=1.0).contains(&s);
        if self.range == RangePolicy::Clamp {
            s = s.clamp(0.0, 1.0);
        }
        let (lo, hi) = (&self.map.layers[m], &self.map.layers[m + 1]);
        let eps = match self.scheme {
            Scheme::FirstHarmonic => {
                let c = lo.c + s * (hi.c - lo.c);
                let sn = lo.s + s * (hi.s - lo.s);
                c * alpha.cos() + sn * alpha.sin()
            }
            Scheme::Bilinear => {
                let a = wrap_tau(alpha);
                (1.0 - s) * angular(lo, a) + s * angular(hi, a)
            }
        };
        Interpolated { eps, outside }
    }
}

/// Linear interpolation of δ_ij in angle within one layer with periodic wrap: between α_C and
/// α_1 + 2π (methods.md §5.3). `a` in [0, 2π).
fn angular(l: &LayerDeviation, a: f64) -> f64 {
    let c = l.alpha.len();
    let k = l.alpha.partition_point(|&x| x <= a);
    let (n0, n1, a0, a1) = if k == 0 {
        (c - 1, 0, l.alpha[c - 1] - TAU, l.alpha[0])
    } else if k == c {
        (c - 1, 0, l.alpha[c - 1], l.alpha[0] + TAU)
    } else {
        (k - 1, k, l.alpha[k - 1], l.alpha[k])
    };
    let t = (a - a0) / (a1 - a0);
    (1.0 - t) * l.delta[n0] + t * l.delta[n1]
}
