//! Model comparison on a case (methods.md §2.5): exact vs arc, circle-intersection and
//! equivalent IUCT on a grid of (tooth, height, time), with the two error metrics of §2.5:
//!
//! * mean relative error: mean |Δh|/h_exact over points with h_exact > 5 % of max h_exact;
//! * normalised MAE: Σ|Δh| / Σ h_exact over all points.

use super::closed_form::{arc_at, closed_forms_at, equivalent_at, EquivalentParams};
use super::exact::{exact_at_time, reference, NewtonOptions, RayTime};
use super::kinematics::{
    CircularFeed, ClPath, ConstantSwing, HeightGeometry, JointPath, Pose, RigidStep, StraightFeed,
    ToolKinematics, ToolMotion,
};
use super::lookback::EquivalentEvaluator;

/// Any of the supported tool motions (one type, so a case set can mix them).
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// 3-axis straight feed.
    Straight(StraightFeed),
    /// 3-axis circular feed.
    Circular(CircularFeed),
    /// Feed with a constant-rate axis swing.
    Swing(ConstantSwing),
    /// CL-path-driven 5-axis motion.
    Path(ClPath),
    /// Joint-space interpolation without RTCP.
    Joints(JointPath),
}

impl ToolMotion for Motion {
    #[inline]
    fn pose(&self, t: f64) -> Pose {
        match self {
            Motion::Straight(m) => m.pose(t),
            Motion::Circular(m) => m.pose(t),
            Motion::Swing(m) => m.pose(t),
            Motion::Path(m) => m.pose(t),
            Motion::Joints(m) => m.pose(t),
        }
    }
    #[inline]
    fn rigid_step(&self, t: f64) -> Option<RigidStep> {
        match self {
            Motion::Straight(m) => m.rigid_step(t),
            Motion::Circular(m) => m.rigid_step(t),
            Motion::Swing(m) => m.rigid_step(t),
            Motion::Path(m) => m.rigid_step(t),
            Motion::Joints(m) => m.rigid_step(t),
        }
    }
    fn smooth_on(&self, t0: f64, t1: f64) -> bool {
        match self {
            Motion::Straight(m) => m.smooth_on(t0, t1),
            Motion::Circular(m) => m.smooth_on(t0, t1),
            Motion::Swing(m) => m.smooth_on(t0, t1),
            Motion::Path(m) => m.smooth_on(t0, t1),
            Motion::Joints(m) => m.smooth_on(t0, t1),
        }
    }
}

/// One evaluation point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplePoint {
    /// Tooth.
    pub tooth: usize,
    /// Height z (mm).
    pub z: f64,
    /// Time t (s).
    pub t: f64,
}

/// The grid: every tooth at every height at `samples` times evenly spread over
/// [t0, t0 + span).
pub fn sample_grid(
    teeth: usize,
    heights: &[f64],
    t0: f64,
    span: f64,
    samples: usize,
) -> Vec<SamplePoint> {
    let mut out = Vec::with_capacity(teeth * heights.len() * samples);
    for j in 0..samples {
        let t = t0 + span * j as f64 / samples as f64;
        for &z in heights {
            for tooth in 0..teeth {
                out.push(SamplePoint { tooth, z, t });
            }
        }
    }
    out
}

/// h (mm, ≥ 0) of every model at every point.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelValues {
    /// Exact, eq. (2.2)–(2.3).
    pub exact: Vec<f64>,
    /// Linear arc, eq. (2.5).
    pub arc: Vec<f64>,
    /// Circle intersection, eq. (2.6).
    pub circle: Vec<f64>,
    /// Equivalent, eq. (2.8).
    pub equivalent: Vec<f64>,
    /// Points where the exact Newton solve missed its tolerance (should be 0).
    pub unconverged: usize,
}

/// Height geometries of the distinct heights of `points` (looked up by exact equality).
struct Heights(Vec<HeightGeometry>);

impl Heights {
    fn new<M: ToolMotion>(kin: &ToolKinematics<M>, points: &[SamplePoint]) -> Self {
        Heights(
            distinct_heights(points)
                .iter()
                .map(|&z| kin.at_height(z))
                .collect(),
        )
    }
    fn get(&self, z: f64) -> &HeightGeometry {
        self.0.iter().find(|g| g.z == z).expect("prepared")
    }
}

/// The distinct heights of `points`, in order of first appearance (a height is looked up only
/// where it differs from the previous point's).
fn distinct_heights(points: &[SamplePoint]) -> Vec<f64> {
    let mut v: Vec<f64> = Vec::new();
    for same in points.chunk_by(|a, b| a.z == b.z) {
        if !v.contains(&same[0].z) {
            v.push(same[0].z);
        }
    }
    v
}

/// Evaluate all models at `points` (the equivalent model by [`equivalent_values`]).
pub fn evaluate_models<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    points: &[SamplePoint],
    params: &EquivalentParams,
) -> ModelValues {
    let opts = NewtonOptions::default();
    let heights = Heights::new(kin, points);
    let mut v = ModelValues {
        equivalent: equivalent_values(kin, points, params),
        ..Default::default()
    };
    let mut time = None::<RayTime>;
    for q in points {
        let geo = heights.get(q.z);
        let e = exact_at_time(kin, geo, q.tooth, ray_time(kin, &mut time, q.t), &opts);
        v.unconverged += usize::from(!e.converged);
        v.exact.push(e.h());
        let c = closed_forms_at(kin, geo, q.tooth, q.t, params);
        v.arc.push(c.arc.max(0.0));
        v.circle.push(c.circle.max(0.0));
    }
    v
}

/// Exact h only (for throughput measurement).
pub fn exact_values<M: ToolMotion>(kin: &ToolKinematics<M>, points: &[SamplePoint]) -> Vec<f64> {
    let opts = NewtonOptions::default();
    let heights = Heights::new(kin, points);
    let mut time = None::<RayTime>;
    points
        .iter()
        .map(|q| {
            let time = ray_time(kin, &mut time, q.t);
            exact_at_time(kin, heights.get(q.z), q.tooth, time, &opts).h()
        })
        .collect()
}

/// [`exact_values`] by the scalar baseline solver, one point and one previous pass after the
/// other ([`super::exact::reference::exact_at`]): the same values bit for bit.
#[doc(hidden)]
pub fn exact_values_reference<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    points: &[SamplePoint],
) -> Vec<f64> {
    let opts = NewtonOptions::default();
    let heights = Heights::new(kin, points);
    points
        .iter()
        .map(|q| reference::exact_at(kin, heights.get(q.z), q.tooth, q.t, &opts).h())
        .collect()
}

/// The prepared time `t`, reused while consecutive points share it.
#[inline]
fn ray_time<'a, M: ToolMotion>(
    kin: &ToolKinematics<M>,
    cache: &'a mut Option<RayTime>,
    t: f64,
) -> &'a RayTime {
    match cache {
        Some(c) if c.t == t => {}
        _ => *cache = Some(RayTime::new(kin, t)),
    }
    cache.as_ref().expect("set above")
}

/// Equivalent h (mm, ≥ 0) at `points` by the bulk [`EquivalentEvaluator`]: one look-back window
/// per run of consecutive points with the same time, shared by their teeth and heights.
pub fn equivalent_values<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    points: &[SamplePoint],
    params: &EquivalentParams,
) -> Vec<f64> {
    let zs = distinct_heights(points);
    let eval = EquivalentEvaluator::new(kin, &zs, *params);
    let mut out = Vec::with_capacity(points.len());
    for run in points.chunk_by(|a, b| a.t == b.t) {
        let window = eval.look_back(run[0].t);
        // consecutive points of one height share the height's window vectors
        for same in run.chunk_by(|a, b| a.z == b.z) {
            let height = zs.iter().position(|&z| z == same[0].z).expect("listed");
            let at = eval.at_height(&window, height);
            out.extend(same.iter().map(|q| at.raw(q.tooth).max(0.0)));
        }
    }
    out
}

/// Equivalent h by the direct per-point evaluation [`equivalent_at`] (K + 1 poses per point):
/// the reference for [`equivalent_values`].
pub fn equivalent_values_direct<M: ToolMotion>(
    kin: &ToolKinematics<M>,
    points: &[SamplePoint],
    params: &EquivalentParams,
) -> Vec<f64> {
    let heights = Heights::new(kin, points);
    points
        .iter()
        .map(|q| equivalent_at(kin, heights.get(q.z), q.tooth, q.t, params).max(0.0))
        .collect()
}

/// Linear-arc h only (for throughput measurement).
pub fn arc_values<M: ToolMotion>(kin: &ToolKinematics<M>, points: &[SamplePoint]) -> Vec<f64> {
    let heights = Heights::new(kin, points);
    points
        .iter()
        .map(|q| arc_at(kin, heights.get(q.z), q.tooth, q.t).max(0.0))
        .collect()
}

/// Error of a model against the exact values (methods.md §2.5 metrics).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ErrorMetrics {
    /// Mean |Δh|/h over points with h_exact > 5 % of max h_exact (fraction, not %).
    pub mean_relative: f64,
    /// Σ|Δh| / Σ h_exact over all points (fraction).
    pub normalised_mae: f64,
    /// Largest |Δh| (mm).
    pub max_abs_mm: f64,
    /// Points entering the relative metric.
    pub points_relative: usize,
}

/// Accumulators so that several cases can be pooled.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ErrorAccumulator {
    rel_sum: f64,
    rel_n: usize,
    abs_sum: f64,
    h_sum: f64,
    max_abs: f64,
}

impl ErrorAccumulator {
    /// Add one case: `model` vs `exact` values (same order).
    pub fn add(&mut self, model: &[f64], exact: &[f64]) {
        let hmax = exact.iter().copied().fold(0.0, f64::max);
        for (m, e) in model.iter().zip(exact) {
            let d = (m - e).abs();
            self.abs_sum += d;
            self.h_sum += e;
            self.max_abs = self.max_abs.max(d);
            if *e > 0.05 * hmax {
                self.rel_sum += d / e;
                self.rel_n += 1;
            }
        }
    }
    /// The metrics so far.
    pub fn metrics(&self) -> ErrorMetrics {
        ErrorMetrics {
            mean_relative: self.rel_sum / self.rel_n.max(1) as f64,
            normalised_mae: self.abs_sum / self.h_sum.max(f64::MIN_POSITIVE),
            max_abs_mm: self.max_abs,
            points_relative: self.rel_n,
        }
    }
}

/// Metrics of one model against exact.
pub fn error_metrics(model: &[f64], exact: &[f64]) -> ErrorMetrics {
    let mut acc = ErrorAccumulator::default();
    acc.add(model, exact);
    acc.metrics()
}
