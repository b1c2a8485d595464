//! Wheel-path compensation w′_k = w_k + ε_k·N_k (methods.md §5.4) with the predicted remaining
//! error of each point.

use super::edge::EdgeLine;
use super::interp::{Interpolator, RangePolicy, Scheme};
use crate::error::ParamError;
use crate::fit::OffsetTiltFit;

/// One compensated point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompensatedPoint {
    /// ε_k (mm).
    pub eps: f64,
    /// True when u_k was outside the probed range (the range policy was applied).
    pub outside: bool,
    /// Offset ε_k·N_k (mm).
    pub offset: [f64; 3],
    /// Original wheel position w_k (mm); the edge point itself when no wheel path is given.
    pub wheel: [f64; 3],
    /// Compensated wheel position w′_k (mm).
    pub compensated: [f64; 3],
    /// Predicted radial error of the finished edge without compensation, relative to the fitted
    /// bar axis: −e(u_k)·n_k (mm; > 0 = edge too far from the real axis), first order.
    pub before: f64,
    /// Predicted remaining radial error with compensation: ε_k − e(u_k)·n_k (mm), where e is the
    /// fitted rigid axis ([`super::DeviationMap::axis`]): the part of ε that a rigid offset + tilt does not explain
    /// (interpolation error, noise, form error).
    pub remaining: f64,
}

/// Compensation of a whole edge / wheel path.
#[derive(Debug, Clone, PartialEq)]
pub struct Compensation {
    /// Per point, in edge order.
    pub points: Vec<CompensatedPoint>,
    /// Scheme used.
    pub scheme: Scheme,
    /// Range policy used.
    pub range: RangePolicy,
}

impl Compensation {
    /// Number of points outside the probed range.
    pub fn outside_count(&self) -> usize {
        self.points.iter().filter(|p| p.outside).count()
    }

    /// (rms, max |·|) of the predicted remaining error (mm).
    pub fn remaining_stats(&self) -> (f64, f64) {
        rms_max(self.points.iter().map(|p| p.remaining))
    }

    /// (rms, max |·|) of the predicted error without compensation (mm).
    pub fn before_stats(&self) -> (f64, f64) {
        rms_max(self.points.iter().map(|p| p.before))
    }
}

/// (rms, max |x|) of a sequence; (0, 0) when empty.
pub fn rms_max(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut n, mut ss, mut mx) = (0usize, 0.0, 0.0f64);
    for x in v {
        n += 1;
        ss += x * x;
        mx = mx.max(x.abs());
    }
    if n == 0 {
        (0.0, 0.0)
    } else {
        ((ss / n as f64).sqrt(), mx)
    }
}

/// Compensate `edge`: ε_k = interp(u_k, α_k), w′_k = w_k + ε_k·N_k (methods.md §5.4).
/// `wheel` (optional) gives the wheel position for each edge point (same count); without it the
/// edge points themselves are offset.
///
/// ```
/// use runout_core::grind::*;
/// let alpha: Vec<f64> = (0..8).map(|j| j as f64 * std::f64::consts::TAU / 8.0).collect();
/// let u = [0.0, 20.0];
/// let r: Vec<Vec<f64>> = u.iter().map(|_| alpha.iter().map(|a| 3.0 + 0.008 * a.cos()).collect()).collect();
/// let map = DeviationMap::new(&ProbeGrid::from_radii(&u, &alpha, &r, Generatrix::cylinder(3.0).unwrap()).unwrap());
/// let f = Interpolator::new(&map, Scheme::FirstHarmonic, RangePolicy::Clamp);
/// let edge = EdgeLine::helical_flat(6.0, 2, 30.0, 0.0, 20.0, 50).unwrap();
/// let c = compensate(&f, &map.axis, &edge, None).unwrap();
/// assert!(c.remaining_stats().1 < 1e-12); // a rigid offset is compensated exactly
/// ```
pub fn compensate(
    interp: &Interpolator,
    axis: &OffsetTiltFit,
    edge: &EdgeLine,
    wheel: Option<&[[f64; 3]]>,
) -> Result<Compensation, ParamError> {
    if let Some(w) = wheel {
        if w.len() != edge.points.len() {
            return Err(ParamError::new(
                "wheel path",
                format!("one wheel position per edge point ({})", edge.points.len()),
                w.len(),
            ));
        }
    }
    let points = edge
        .points
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let v = interp.eval(p.u, p.alpha);
            let n = p.normal;
            let offset = [v.eps * n[0], v.eps * n[1], v.eps * n[2]];
            let w = wheel.map_or(p.position, |w| w[k]);
            let e = axis.at(p.u);
            let en = e[0] * p.alpha.cos() + e[1] * p.alpha.sin();
            CompensatedPoint {
                eps: v.eps,
                outside: v.outside,
                offset,
                wheel: w,
                compensated: [w[0] + offset[0], w[1] + offset[1], w[2] + offset[2]],
                before: -en,
                remaining: v.eps - en,
            }
        })
        .collect();
    Ok(Compensation {
        points,
        scheme: interp.scheme(),
        range: interp.range(),
    })
}
