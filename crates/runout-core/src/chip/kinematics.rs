//! Cutter kinematics for chip thickness: translation + tool-axis swing + spindle rotation,
//! with runout offset, tilt and a radius profile R(z) — methods.md §2.1, eq. (2.1):
//!
//! E_i(z,t) = P(t) + z·u(t) + a_i(z,t)·e₁(t) + b_i(z,t)·e₂(t),
//! (a_i, b_i) = Rot(Θ(t))·(x_i(z), y_i(z)),  Θ(t) = ω t + Θ₀,
//!
//! where (x_i, y_i) = R(z)·(cos ψ_i(z), sin ψ_i(z)) + e(z) is the spindle-frame edge point
//! (`Runout::tooth_point`, conventions.md) and (u, e₁, e₂) the tool frame. The frame is moved by
//! a [`ToolMotion`]: position P(t) of the tool tip on the spindle axis, axis u(t), reference
//! direction e₁(t) (transported with minimal rotation, methods.md §2.1), their velocities.
//! e₂ = σ·u × e₁ with σ = −1 for clockwise spindle rotation seen from above (conventions.md; then
//! with u = +z and e₁ = +y, e₂ = +x and the spindle angle equals Altintas' immersion angle φ)
//! and σ = +1 for counter-clockwise rotation (the frame of the python reference, methods App. A.3).

use crate::cutter::{Cutter, RadiusProfile};
use crate::error::{finite, positive, ParamError};
use crate::runout::Runout;
use nalgebra::Vector3;

/// 3-D vector (mm, mm/s or rad/s). nalgebra's fixed-size vector compiles to plain arithmetic.
pub type Vec3 = Vector3<f64>;

/// Tool frame and its velocity at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Tool tip point on the spindle axis P(t) (mm).
    pub p: Vec3,
    /// Unit tool axis u(t) (tip → holder).
    pub u: Vec3,
    /// Unit reference direction e₁(t) ⊥ u (spindle angle Θ = 0 points along e₁).
    pub e1: Vec3,
    /// Tip velocity Ṗ (mm/s).
    pub v: Vec3,
    /// Angular velocity Ω (rad/s) of the (u, e₁, e₂) frame: u̇ = Ω×u, ė₁ = Ω×e₁.
    pub w: Vec3,
}

/// A tool motion: the pose of the non-rotating tool frame as a function of time.
pub trait ToolMotion: Send + Sync {
    /// Pose at time `t` (s). Must be defined for all t (extrapolate outside a path) because the
    /// chip thickness looks back by up to one revolution.
    fn pose(&self, t: f64) -> Pose;

    /// Whether the pose is an analytic function of time on all of [t0, t1] (no junction of
    /// segments inside), so that bulk evaluators may interpolate it there
    /// ([`super::EquivalentEvaluator`]). The default `false` makes them evaluate the motion
    /// directly.
    fn smooth_on(&self, _t0: f64, _t1: f64) -> bool {
        false
    }

    /// The motion around time `t` as a [`RigidStep`] (pose at `t` plus the screw that moves it),
    /// for motions that are a rigid rotation at constant angular velocity about a point moving at
    /// constant velocity on an interval containing `t`. Solvers then reach nearby times by an
    /// incremental rotation instead of re-evaluating [`Self::pose`]. Default: `None`.
    fn rigid_step(&self, _t: f64) -> Option<RigidStep> {
        None
    }
}

/// A constant screw motion of the tool frame around a reference time: on [lo, hi) the frame turns
/// at constant angular velocity Ω = rate·ŵ and the point C = P + pivot·u moves at constant
/// velocity v_c, so that for t = t_r + δ
///
/// frame(t) = Rot(ŵ, rate·δ)·frame(t_r),   P(t) = P(t_r) + v_c·δ + pivot·(u(t_r) − u(t)),
/// Ṗ(t) = v_c − pivot·Ω×u(t)
///
/// (exact for [`StraightFeed`], [`ConstantSwing`] and each segment of a [`ClPath`]). The rotation
/// by a small angle uses [`small_sin_cos`]: no libm call, same result as [`ToolMotion::pose`] to
/// rounding (|δP| ~ 1e-14 mm on the benchmark paths, tested in `tests/core/chip_models.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidStep {
    /// Reference time t_r (s).
    pub t: f64,
    /// Pose at t_r.
    pub pose: Pose,
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// Rodrigues terms of u and e₁ (v ↦ v + sin α·ŵ×v + (1 − cos α)·(ŵ(ŵ·v) − v)), precomputed:
    /// [ŵ×u, ŵ(ŵ·u) − u, ŵ×e₁, ŵ(ŵ·e₁) − e₁].
    pub(super) terms: [Vec3; 4],
    /// Rotation rate (rad/s).
    pub(super) rate: f64,
    /// Height of the point C above the tip (mm).
    pub(super) pivot: f64,
    /// Velocity of C (mm/s).
    pub(super) vc: Vec3,
}

impl RigidStep {
    /// The screw about unit `axis` at `rate` through the point `pivot` above the tip, whose
    /// velocity is `vc`, valid on [lo, hi), seen from `pose` at time `t`.
    #[allow(clippy::too_many_arguments)]
    fn new(
        t: f64,
        pose: Pose,
        lo: f64,
        hi: f64,
        axis: Vec3,
        rate: f64,
        pivot: f64,
        vc: Vec3,
    ) -> Self {
        let terms = [
            axis.cross(&pose.u),
            axis * axis.dot(&pose.u) - pose.u,
            axis.cross(&pose.e1),
            axis * axis.dot(&pose.e1) - pose.e1,
        ];
        RigidStep {
            t,
            pose,
            lo,
            hi,
            terms,
            rate,
            pivot,
            vc,
        }
    }

    /// Largest rotation (rad) reached incrementally; beyond it [`Self::pose_at`] declines.
    pub(super) const MAX_ANGLE: f64 = 0.5;

    /// Whether `t` lies in the interval of this screw (no CL-path junction in between).
    #[inline]
    pub fn covers(&self, t: f64) -> bool {
        t >= self.lo && t < self.hi
    }

    /// Pose at time `t`, or `None` when `t` is outside the interval of this screw (a CL-path
    /// junction) or the rotation is too large for the small-angle series.
    #[inline]
    pub fn pose_at(&self, t: f64) -> Option<Pose> {
        if !self.covers(t) {
            return None;
        }
        let dt = t - self.t;
        let angle = self.rate * dt;
        if angle.abs() > Self::MAX_ANGLE {
            return None;
        }
        let (s, c) = small_sin_cos(angle);
        let [cu, pu, ce, pe] = &self.terms;
        let u = self.pose.u + cu * s + pu * (1.0 - c);
        let e1 = self.pose.e1 + ce * s + pe * (1.0 - c);
        let (p, v) = if self.pivot == 0.0 {
            (self.pose.p + self.vc * dt, self.vc)
        } else {
            (
                self.pose.p + self.vc * dt + (self.pose.u - u) * self.pivot,
                self.vc - self.pose.w.cross(&u) * self.pivot,
            )
        };
        Some(Pose {
            p,
            u,
            e1,
            v,
            w: self.pose.w,
        })
    }
}

/// Pose at `t` from `step` when it applies there, else from the motion itself.
#[inline]
pub fn pose_near<M: ToolMotion>(motion: &M, step: Option<&RigidStep>, t: f64) -> Pose {
    step.and_then(|s| s.pose_at(t))
        .unwrap_or_else(|| motion.pose(t))
}

/// Rodrigues rotation of `v` about unit axis `w` by the angle with sine `s` and cosine `c`.
#[inline]
pub fn rotate(w: &Vec3, s: f64, c: f64, v: &Vec3) -> Vec3 {
    v * c + w.cross(v) * s + w * (w.dot(v) * (1.0 - c))
}

/// Unit vector ⊥ `u` closest to +y (falls back to +x when u ∥ y): the reference e₁ at the start.
pub fn reference_e1(u: &Vec3) -> Vec3 {
    let y = Vec3::y();
    let cand = y - u * u.dot(&y);
    if cand.norm() > 1e-6 {
        cand.normalize()
    } else {
        let x = Vec3::x();
        (x - u * u.dot(&x)).normalize()
    }
}

/// 3-axis straight feed: P(t) = P₀ + v·t, fixed axis u and e₁.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StraightFeed {
    /// Tip position at t = 0 (mm).
    pub p0: Vec3,
    /// Feed velocity (mm/s).
    pub v: Vec3,
    /// Unit tool axis.
    pub u: Vec3,
    /// Unit reference direction ⊥ u.
    pub e1: Vec3,
}

impl StraightFeed {
    /// Workpiece-frame 3-axis feed along +x at `speed_mm_s` with u = +z and e₁ = +y (so that,
    /// with clockwise rotation, spindle angle = immersion angle φ, conventions.md).
    pub fn along_x(speed_mm_s: f64) -> Self {
        StraightFeed {
            p0: Vec3::zeros(),
            v: Vec3::new(speed_mm_s, 0.0, 0.0),
            u: Vec3::z(),
            e1: Vec3::y(),
        }
    }
}

impl ToolMotion for StraightFeed {
    fn smooth_on(&self, _t0: f64, _t1: f64) -> bool {
        true
    }
    #[inline]
    fn pose(&self, t: f64) -> Pose {
        Pose {
            p: self.p0 + self.v * t,
            u: self.u,
            e1: self.e1,
            v: self.v,
            w: Vec3::zeros(),
        }
    }
}

/// 3-axis circular feed in the xy plane: P(t) = C + r_c·(cos α, sin α, 0), α = α₀ + Ω_c·t;
/// axis +z, e₁ = +y (the tool frame does not turn with the path).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircularFeed {
    /// Centre of the tip path (mm).
    pub centre: Vec3,
    /// Path radius r_c (mm).
    pub radius: f64,
    /// Path angle α₀ at t = 0 (rad).
    pub start_angle: f64,
    /// Path angular rate Ω_c (rad/s; positive = counter-clockwise seen from +z).
    pub rate: f64,
}

impl CircularFeed {
    /// Circle of radius `radius_mm` about `centre` travelled at tip speed `speed_mm_s`
    /// (`ccw` = counter-clockwise seen from above).
    pub fn new(
        centre: Vec3,
        radius_mm: f64,
        speed_mm_s: f64,
        ccw: bool,
    ) -> Result<Self, ParamError> {
        positive("path_radius_mm", radius_mm)?;
        positive("feed_mm_s", speed_mm_s)?;
        let rate = speed_mm_s / radius_mm * if ccw { 1.0 } else { -1.0 };
        Ok(CircularFeed {
            centre,
            radius: radius_mm,
            start_angle: 0.0,
            rate,
        })
    }
}

impl ToolMotion for CircularFeed {
    fn smooth_on(&self, _t0: f64, _t1: f64) -> bool {
        true
    }
    #[inline]
    fn pose(&self, t: f64) -> Pose {
        let (s, c) = (self.start_angle + self.rate * t).sin_cos();
        Pose {
            p: self.centre + Vec3::new(self.radius * c, self.radius * s, 0.0),
            u: Vec3::z(),
            e1: Vec3::y(),
            v: Vec3::new(-self.radius * s, self.radius * c, 0.0) * self.rate,
            w: Vec3::zeros(),
        }
    }
}

/// Feed with a constant-rate swing of the tool axis (methods.md §2.5 "5-axis, swing"):
/// frame(t) = Rot(w, Ω·t)·frame₀ and the point at height `pivot` on the axis moves along
/// p₀ + pivot·u₀ + v·t, so P(t) = p₀ + v·t + pivot·(u₀ − u(t)). `pivot = 0`: swing about the tip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantSwing {
    /// Tip position at t = 0 (mm).
    pub p0: Vec3,
    /// Velocity of the pivot point (mm/s).
    pub v: Vec3,
    /// Axis at t = 0.
    pub u0: Vec3,
    /// e₁ at t = 0.
    pub e1: Vec3,
    /// Unit swing axis w.
    pub axis: Vec3,
    /// Swing rate Ω (rad/s).
    pub rate: f64,
    /// Pivot height above the tip (mm).
    pub pivot: f64,
}

impl ConstantSwing {
    /// Axis +z and e₁ = +y at t = 0, feed `v`, swing about `axis` (normalised) at `rate_rad_s`
    /// about the point `pivot_mm` above the tip.
    pub fn new(v: Vec3, axis: Vec3, rate_rad_s: f64, pivot_mm: f64) -> Result<Self, ParamError> {
        let n = axis.norm();
        if !(n.is_finite() && n > 0.0) {
            return Err(ParamError::new(
                "swing_axis",
                "a non-zero vector",
                format!("{axis:?}"),
            ));
        }
        finite("swing_deg_s", rate_rad_s)?;
        finite("pivot_mm", pivot_mm)?;
        Ok(ConstantSwing {
            p0: Vec3::zeros(),
            v,
            u0: Vec3::z(),
            e1: Vec3::y(),
            axis: axis / n,
            rate: rate_rad_s,
            pivot: pivot_mm,
        })
    }
}

impl ToolMotion for ConstantSwing {
    fn smooth_on(&self, _t0: f64, _t1: f64) -> bool {
        true
    }
    #[inline]
    fn pose(&self, t: f64) -> Pose {
        let (s, c) = (self.rate * t).sin_cos();
        let u = rotate(&self.axis, s, c, &self.u0);
        let w = self.axis * self.rate;
        Pose {
            p: self.p0 + self.v * t + (self.u0 - u) * self.pivot,
            u,
            e1: rotate(&self.axis, s, c, &self.e1),
            v: self.v - w.cross(&u) * self.pivot,
            w,
        }
    }
    fn rigid_step(&self, t: f64) -> Option<RigidStep> {
        Some(RigidStep::new(
            t,
            self.pose(t),
            f64::NEG_INFINITY,
            f64::INFINITY,
            self.axis,
            self.rate,
            self.pivot,
            self.v,
        ))
    }
}

/// One cutter-location point of a CL path (tool tip, axis, feed to reach the next point).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClPoint {
    /// Tool tip position (mm).
    pub p: Vec3,
    /// Unit tool axis.
    pub u: Vec3,
    /// Feed (mm/s) of the move from this point to the next one.
    pub feed: f64,
}

/// One precomputed segment n → n+1 of a CL path.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Segment {
    t0: f64,
    dt: f64,
    p: Vec3,
    dp: Vec3,
    u: Vec3,
    e1: Vec3,
    /// Unit rotation axis w_n (zero when the axis does not change).
    w: Vec3,
    /// Swing angle Δ_n (rad).
    angle: f64,
}

/// CL-path-driven motion (methods.md §2.1): linear translation of the tip between CL points,
/// axis swing by slerp u(t) = Rot(w_n, s·Δ_n)·u_n with w_n = u_n × u_{n+1}/|…|,
/// Δ_n = arccos(u_n·u_{n+1}), e₁ transported by the same rotation (minimal rotation),
/// time stamps t_{n+1} = t_n + |P_{n+1} − P_n|/F_n (tip feed). Before the first and after the
/// last point the first/last segment is extrapolated.
#[derive(Debug, Clone, PartialEq)]
pub struct ClPath {
    segments: Vec<Segment>,
}

impl ClPath {
    /// Build the path; `points[n].feed` is the feed of the move n → n+1 (mm/s).
    /// Errors: fewer than 2 points, non-unit or zero axis, zero-length or zero-feed move,
    /// antiparallel consecutive axes.
    pub fn new(points: &[ClPoint]) -> Result<Self, ParamError> {
        if points.len() < 2 {
            return Err(ParamError::new(
                "cl_path",
                "at least 2 CL points",
                points.len(),
            ));
        }
        for (n, q) in points.iter().enumerate() {
            if (q.u.norm() - 1.0).abs() > 1e-9 {
                return Err(ParamError::new(
                    format!("cl_path point {n} axis"),
                    "a unit vector",
                    format!("norm {}", q.u.norm()),
                ));
            }
        }
        let mut segments = Vec::with_capacity(points.len() - 1);
        let mut e1 = reference_e1(&points[0].u);
        let mut t0 = 0.0;
        for (n, pair) in points.windows(2).enumerate() {
            let seg = Self::segment(n, &pair[0], &pair[1], t0, e1)?;
            let (s, c) = seg.angle.sin_cos();
            e1 = rotate(&seg.w, s, c, &seg.e1);
            // re-orthonormalise against rounding drift over long paths
            e1 = (e1 - pair[1].u * pair[1].u.dot(&e1)).normalize();
            t0 += seg.dt;
            segments.push(seg);
        }
        Ok(ClPath { segments })
    }

    fn segment(
        n: usize,
        a: &ClPoint,
        b: &ClPoint,
        t0: f64,
        e1: Vec3,
    ) -> Result<Segment, ParamError> {
        let dp = b.p - a.p;
        let len = dp.norm();
        if len <= 1e-12 {
            return Err(ParamError::new(
                format!("cl_path move {n}→{}", n + 1),
                "a move of non-zero tip length",
                "0 mm",
            ));
        }
        if !(a.feed.is_finite() && a.feed > 0.0) {
            return Err(ParamError::new(
                format!("cl_path point {n} feed_mm_min"),
                "a feed > 0",
                a.feed * 60.0,
            ));
        }
        let cross = a.u.cross(&b.u);
        let sin = cross.norm();
        let cos = a.u.dot(&b.u);
        if cos < -1.0 + 1e-9 {
            return Err(ParamError::new(
                format!("cl_path move {n}→{}", n + 1),
                "consecutive tool axes that are not antiparallel",
                "a 180° axis flip",
            ));
        }
        let (w, angle) = if sin > 1e-15 {
            (cross / sin, sin.atan2(cos))
        } else {
            (Vec3::zeros(), 0.0)
        };
        Ok(Segment {
            t0,
            dt: len / a.feed,
            p: a.p,
            dp,
            u: a.u,
            e1,
            w,
            angle,
        })
    }

    /// Total duration of the path (s).
    pub fn duration(&self) -> f64 {
        let last = self.segments.last().expect("non-empty");
        last.t0 + last.dt
    }

    /// Time stamp (s) of CL point `n`.
    pub fn time_of_point(&self, n: usize) -> f64 {
        if n < self.segments.len() {
            self.segments[n].t0
        } else {
            self.duration()
        }
    }

    /// Number of segments (CL points − 1).
    pub fn len(&self) -> usize {
        self.segments.len()
    }

    /// Always false (a path has at least one segment).
    pub fn is_empty(&self) -> bool {
        self.segments.is_empty()
    }

    /// Index of the segment whose formula applies at `t` (the first/last one outside the path).
    fn segment_index(&self, t: f64) -> usize {
        self.segments
            .partition_point(|s| s.t0 <= t)
            .saturating_sub(1)
    }

    fn find(&self, t: f64) -> &Segment {
        &self.segments[self.segment_index(t)]
    }
}

impl ToolMotion for ClPath {
    fn smooth_on(&self, t0: f64, t1: f64) -> bool {
        self.segment_index(t0) == self.segment_index(t1)
    }
    fn pose(&self, t: f64) -> Pose {
        Self::pose_on(self.find(t), t)
    }
    fn rigid_step(&self, t: f64) -> Option<RigidStep> {
        // the first and last segments are extrapolated beyond the path (see `pose`)
        let n = self.segment_index(t);
        let seg = &self.segments[n];
        let lo = if n == 0 { f64::NEG_INFINITY } else { seg.t0 };
        let hi = if n + 1 == self.segments.len() {
            f64::INFINITY
        } else {
            self.segments[n + 1].t0
        };
        Some(RigidStep::new(
            t,
            Self::pose_on(seg, t),
            lo,
            hi,
            seg.w,
            seg.angle / seg.dt,
            0.0,
            seg.dp / seg.dt,
        ))
    }
}

impl ClPath {
    /// Pose at `t` by the formula of segment `seg`.
    #[inline]
    fn pose_on(seg: &Segment, t: f64) -> Pose {
        let s = (t - seg.t0) / seg.dt;
        let (sn, cs) = (s * seg.angle).sin_cos();
        Pose {
            p: seg.p + seg.dp * s,
            u: rotate(&seg.w, sn, cs, &seg.u),
            e1: rotate(&seg.w, sn, cs, &seg.e1),
            v: seg.dp / seg.dt,
            w: seg.w * (seg.angle / seg.dt),
        }
    }
}

/// Machine joints of a head-head 5-axis machine at one CL block: pivot position (X, Y, Z),
/// head rotations A (about x) and C (about z), feed to the next block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointPoint {
    /// Pivot point position (mm), workpiece frame.
    pub xyz: Vec3,
    /// A axis (rad), rotation about x.
    pub a: f64,
    /// C axis (rad), rotation about z.
    pub c: f64,
    /// Tip feed (mm/s) of the move to the next block.
    pub feed: f64,
}

/// Motion of a machine **without RTCP** (methods.md §2.1): the joints (X, Y, Z, A, C) are
/// interpolated linearly between blocks and the tool pose follows from the forward kinematics of a
/// head-head machine with pivot length L (pivot → tool tip):
///
/// R = Rz(C)·Rx(A), u = R ẑ, e₁ = R ŷ, P = X − L·u,
/// Ω = Ċ ẑ + Ȧ Rz(C) x̂, Ṗ = Ẋ − L·Ω × u.
///
/// Segment durations: tip chord |P_{n+1} − P_n| / F_n. Extrapolated outside the blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct JointPath {
    points: Vec<JointPoint>,
    times: Vec<f64>,
    pivot: f64,
}

impl JointPath {
    /// Joint path with pivot length `pivot_mm` (≥ 0).
    pub fn new(points: &[JointPoint], pivot_mm: f64) -> Result<Self, ParamError> {
        if points.len() < 2 {
            return Err(ParamError::new(
                "joint_path",
                "at least 2 blocks",
                points.len(),
            ));
        }
        finite("pivot_mm", pivot_mm)?;
        let mut times = vec![0.0];
        for (n, w) in points.windows(2).enumerate() {
            let chord = (Self::tip(&w[1], pivot_mm) - Self::tip(&w[0], pivot_mm)).norm();
            if !(w[0].feed.is_finite() && w[0].feed > 0.0) || chord <= 1e-12 {
                return Err(ParamError::new(
                    format!("joint_path block {n}"),
                    "a feed > 0 and a tip move of non-zero length",
                    format!("feed {} mm/s, chord {chord} mm", w[0].feed),
                ));
            }
            times.push(times[n] + chord / w[0].feed);
        }
        Ok(JointPath {
            points: points.to_vec(),
            times,
            pivot: pivot_mm,
        })
    }

    fn rotation(a: f64, c: f64) -> (Vec3, Vec3, Vec3) {
        let (sa, ca) = a.sin_cos();
        let (sc, cc) = c.sin_cos();
        // columns of Rz(C)·Rx(A): images of x̂, ŷ, ẑ
        let x = Vec3::new(cc, sc, 0.0);
        let y = Vec3::new(-sc * ca, cc * ca, sa);
        let z = Vec3::new(sc * sa, -cc * sa, ca);
        (x, y, z)
    }

    /// Tool tip of a block (forward kinematics).
    pub fn tip(q: &JointPoint, pivot: f64) -> Vec3 {
        q.xyz - Self::rotation(q.a, q.c).2 * pivot
    }

    /// Total duration (s).
    pub fn duration(&self) -> f64 {
        *self.times.last().expect("≥ 2 blocks")
    }
}

impl JointPath {
    /// Index of the block interval whose interpolation applies at `t` (clamped outside).
    fn block_index(&self, t: f64) -> usize {
        self.times
            .partition_point(|&s| s <= t)
            .clamp(1, self.points.len() - 1)
            - 1
    }
}

impl ToolMotion for JointPath {
    fn smooth_on(&self, t0: f64, t1: f64) -> bool {
        self.block_index(t0) == self.block_index(t1)
    }

    fn pose(&self, t: f64) -> Pose {
        let n = self.block_index(t);
        let (p0, p1) = (&self.points[n], &self.points[n + 1]);
        let dt = self.times[n + 1] - self.times[n];
        let s = (t - self.times[n]) / dt;
        let (a, c) = (p0.a + s * (p1.a - p0.a), p0.c + s * (p1.c - p0.c));
        let (a_dot, c_dot) = ((p1.a - p0.a) / dt, (p1.c - p0.c) / dt);
        let (x_rot, e1, u) = Self::rotation(a, c);
        let w = Vec3::z() * c_dot + Vec3::new(x_rot.x, x_rot.y, 0.0) * a_dot;
        let xyz = p0.xyz + (p1.xyz - p0.xyz) * s;
        Pose {
            p: xyz - u * self.pivot,
            u,
            e1,
            v: (p1.xyz - p0.xyz) / dt - w.cross(&u) * self.pivot,
            w,
        }
    }
}

/// Direction of spindle rotation seen from above the tool (looking down −u).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpindleSense {
    /// Clockwise: the toolkit default (conventions.md), e₂ = e₁ × u.
    #[default]
    Clockwise,
    /// Counter-clockwise: e₂ = u × e₁ (frame of methods.md App. A.3).
    CounterClockwise,
}

impl SpindleSense {
    /// σ in e₂ = σ·u × e₁.
    pub fn sigma(self) -> f64 {
        match self {
            SpindleSense::Clockwise => -1.0,
            SpindleSense::CounterClockwise => 1.0,
        }
    }
}

/// Spindle-frame edge point of one tooth at one height and its z-derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpindlePoint {
    /// (x_i, y_i)(z) = R(z)·(cos ψ_i, sin ψ_i) + e(z) (mm).
    pub xy: [f64; 2],
    /// d(x_i, y_i)/dz (mm/mm).
    pub dxy: [f64; 2],
}

impl SpindlePoint {
    /// Effective radius R_i(z) = |(x_i, y_i)|, methods.md eq. (0.1).
    #[inline]
    pub fn radius(&self) -> f64 {
        self.xy[0].hypot(self.xy[1])
    }
    /// Spindle-frame angle ψ_i + δ_i of the effective edge (rad), methods.md eq. (0.2).
    #[inline]
    pub fn angle(&self) -> f64 {
        self.xy[1].atan2(self.xy[0])
    }
}

/// Edge point, axis point and the partial derivatives used by the Newton solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeState {
    /// Edge point E_i(z,t) (mm).
    pub pos: Vec3,
    /// Spindle-axis point A(z,t) = P + z·u (mm).
    pub axis_point: Vec3,
    /// ∂E/∂t = Ṗ + Ω×(E − P) + ω(−b e₁ + a e₂) (mm/s), methods.md §2.2.
    pub d_dt: Vec3,
    /// ∂E/∂z = u + (a′ e₁ + b′ e₂) (mm/mm), methods.md §2.2.
    pub d_dz: Vec3,
    /// Tool axis u.
    pub u: Vec3,
}

/// dR/dz of the radius profile (slope of the envelope; ∞ avoided by clamping z ≥ 1e-9 mm).
pub fn radius_slope(cutter: &Cutter, z: f64) -> f64 {
    let r = cutter.radius();
    let corner = |rc: f64| {
        if z >= rc {
            0.0
        } else {
            let zc = z.max(1e-9);
            let q = (rc * rc - (rc - zc) * (rc - zc)).max(1e-300).sqrt();
            (rc - zc) / q
        }
    };
    match cutter.profile() {
        RadiusProfile::Flat => 0.0,
        RadiusProfile::Ball => corner(r),
        RadiusProfile::BullNose { corner_mm } => corner(*corner_mm),
        RadiusProfile::Tapered { taper_deg } => taper_deg.to_radians().tan(),
    }
}

/// The full kinematic model of eq. (2.1): cutter, runout, spindle and tool motion.
#[derive(Debug, Clone)]
pub struct ToolKinematics<M> {
    cutter: Cutter,
    runout: Runout,
    omega: f64,
    inv_omega: f64,
    theta0: f64,
    sense: SpindleSense,
    motion: M,
    /// Spindle time between the passes of tooth i−m and tooth i: `gap_time[i*K + m−1]` (s).
    gap_time: Vec<f64>,
    /// Runout vector e₀ at the tip (mm).
    offset0: [f64; 2],
}

impl<M: ToolMotion> ToolKinematics<M> {
    /// Kinematics at spindle speed `rpm` (> 0), spindle angle Θ(0) = `theta0_rad`.
    pub fn new(
        cutter: &Cutter,
        runout: &Runout,
        rpm: f64,
        theta0_rad: f64,
        sense: SpindleSense,
        motion: M,
    ) -> Result<Self, ParamError> {
        positive("rpm", rpm)?;
        finite("theta0_deg", theta0_rad)?;
        let omega = rpm * std::f64::consts::TAU / 60.0;
        let k = cutter.teeth();
        let gap_time = (0..k)
            .flat_map(|i| (1..=k).map(move |m| (i, m)))
            .map(|(i, m)| cutter.gap(i, m) / omega)
            .collect();
        Ok(ToolKinematics {
            cutter: cutter.clone(),
            runout: *runout,
            omega,
            inv_omega: 1.0 / omega,
            theta0: theta0_rad,
            sense,
            motion,
            gap_time,
            offset0: runout.vector_at(0.0),
        })
    }

    /// The cutter.
    pub fn cutter(&self) -> &Cutter {
        &self.cutter
    }
    /// The runout.
    pub fn runout(&self) -> &Runout {
        &self.runout
    }
    /// Spindle speed ω (rad/s).
    #[inline]
    pub fn omega(&self) -> f64 {
        self.omega
    }
    /// 1/ω (s/rad).
    #[inline]
    pub fn inv_omega(&self) -> f64 {
        self.inv_omega
    }
    /// Tooth period T/K for uniform pitch; in general the gap time, see [`Self::gap_time`].
    pub fn period(&self) -> f64 {
        std::f64::consts::TAU / self.omega
    }
    /// Spindle sense.
    pub fn sense(&self) -> SpindleSense {
        self.sense
    }
    /// The tool motion.
    pub fn motion(&self) -> &M {
        &self.motion
    }
    /// Spindle time (s) from the pass of tooth i−m to the pass of tooth i (m in 1..=K).
    #[inline]
    pub fn gap_time(&self, tooth: usize, m: usize) -> f64 {
        self.gap_time[tooth * self.cutter.teeth() + m - 1]
    }
    /// Spindle angle Θ(t) = ω t + Θ₀ (rad, not wrapped).
    #[inline]
    pub fn spindle_angle(&self, t: f64) -> f64 {
        self.omega * t + self.theta0
    }
    /// Time at which tooth `tooth`'s nominal edge at height `z` is at spindle-frame angle
    /// `angle` (rad) in the revolution starting at Θ = Θ₀: Θ(t) + ψ_i(z) = angle.
    pub fn time_at_tooth_angle(&self, tooth: usize, z: f64, angle: f64) -> f64 {
        (angle - self.cutter.tooth_angle(tooth, z) - self.theta0) / self.omega
    }

    /// Spindle-frame edge point of `tooth` at height `z` and its z-derivative
    /// (helix ψ′ = −tan β / R, profile slope R′(z), tilt τ).
    #[inline]
    pub fn spindle_point(&self, tooth: usize, z: f64) -> SpindlePoint {
        let psi = self.cutter.tooth_angle(tooth, z);
        self.spindle_point_sc(psi.sin_cos(), z)
    }

    /// [`Self::spindle_point`] of `tooth` at a height `z` near the prepared height `geo.z`
    /// (a Newton iterate z′): the edge direction u(ψ_i(z′)) is u(ψ_i(z)) turned by the small
    /// angle ψ_i(z′) − ψ_i(z) (series sin/cos, no libm call; same value to rounding).
    #[inline]
    pub fn spindle_point_near(&self, geo: &HeightGeometry, tooth: usize, z: f64) -> SpindlePoint {
        let turn = self.cutter.tooth_angle(tooth, z) - self.cutter.tooth_angle(tooth, geo.z);
        if turn.abs() > 0.5 {
            return self.spindle_point(tooth, z);
        }
        let (st, ct) = small_sin_cos(turn);
        let (s0, c0) = geo.direction[tooth];
        self.spindle_point_sc((s0 * ct + c0 * st, c0 * ct - s0 * st), z)
    }

    /// Spindle-frame edge point at height `z` whose nominal edge direction is (sin ψ, cos ψ).
    #[inline]
    fn spindle_point_sc(&self, (s, c): (f64, f64), z: f64) -> SpindlePoint {
        let r = self.cutter.radius_at(z);
        let dr = radius_slope(&self.cutter, z);
        let dpsi = -self.cutter.lag_slope(z);
        // e(z) = e₀ + z·τ with e₀ cached (Runout::vector_at would take a libm sin_cos per call)
        let tau = self.runout.tilt();
        let e = [self.offset0[0] + z * tau[0], self.offset0[1] + z * tau[1]];
        SpindlePoint {
            xy: [r * c + e[0], r * s + e[1]],
            dxy: [
                dr * c - r * dpsi * s + tau[0],
                dr * s + r * dpsi * c + tau[1],
            ],
        }
    }

    /// Spindle-axis point A(z,t) = P(t) + z·u(t) (mm).
    #[inline]
    pub fn axis_point(&self, z: f64, t: f64) -> Vec3 {
        let p = self.motion.pose(t);
        p.p + p.u * z
    }

    /// Axis-point velocity per radian of spindle rotation a = (Ṗ + Ω×(z u))/ω (mm/rad),
    /// methods.md §2.4, and the axis u at time t.
    #[inline]
    pub fn axis_velocity_per_rad(&self, z: f64, t: f64) -> (Vec3, Vec3) {
        let p = self.motion.pose(t);
        ((p.v + p.w.cross(&p.u) * z) * self.inv_omega, p.u)
    }

    /// Edge state of the tooth with spindle point `sp` at time `t + tau`, with the spindle angle
    /// evaluated as Θ(t) + ω·τ so that rounding of a large Θ(t) is common to all teeth.
    #[inline]
    pub fn edge_at(&self, sp: &SpindlePoint, z: f64, t: f64, tau: f64) -> EdgeState {
        let pose = self.motion.pose(t + tau);
        let theta = self.spindle_angle(t) + self.omega * tau;
        self.edge_from_pose(&pose, sp, z, theta)
    }

    /// Edge state from a pose and spindle angle Θ (eq. 2.1 and its derivatives).
    #[inline]
    pub fn edge_from_pose(&self, pose: &Pose, sp: &SpindlePoint, z: f64, theta: f64) -> EdgeState {
        let (sn, cs) = theta.sin_cos();
        self.edge_from_pose_sc(pose, sp, z, sn, cs)
    }

    /// Edge state from a pose and (sin Θ, cos Θ).
    #[inline]
    pub fn edge_from_pose_sc(
        &self,
        pose: &Pose,
        sp: &SpindlePoint,
        z: f64,
        sn: f64,
        cs: f64,
    ) -> EdgeState {
        let e2 = pose.u.cross(&pose.e1) * self.sense.sigma();
        let [x, y] = sp.xy;
        let [dx, dy] = sp.dxy;
        let a = x * cs - y * sn;
        let b = x * sn + y * cs;
        let da = dx * cs - dy * sn;
        let db = dx * sn + dy * cs;
        let radial = pose.e1 * a + e2 * b;
        let rel = pose.u * z + radial;
        // rotation in the (e₁, e₂) plane: with e₂ = σ u × e₁, positive Θ turns e₁ towards e₂
        let spin = (e2 * a - pose.e1 * b) * self.omega;
        EdgeState {
            pos: pose.p + rel,
            axis_point: pose.p + pose.u * z,
            d_dt: pose.v + pose.w.cross(&rel) + spin,
            d_dz: pose.u + pose.e1 * da + e2 * db,
            u: pose.u,
        }
    }

    /// Edge point E_i(z,t) (mm), eq. (2.1).
    pub fn edge_point(&self, tooth: usize, z: f64, t: f64) -> Vec3 {
        let sp = self.spindle_point(tooth, z);
        self.edge_at(&sp, z, t, 0.0).pos
    }
}

/// Everything of the kinematics that depends on the height z only (precomputed once per height
/// so that the per-point solvers do no trigonometry of the tooth geometry).
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGeometry {
    /// Height z (mm).
    pub z: f64,
    k: usize,
    /// Spindle-frame edge point per tooth.
    pub points: Vec<SpindlePoint>,
    /// (sin ψ_i(z), cos ψ_i(z)) of the nominal edge direction per tooth.
    pub direction: Vec<(f64, f64)>,
    /// Effective radius R_i(z) per tooth (mm), eq. (0.1).
    pub radius: Vec<f64>,
    /// Effective edge angle ψ_i + δ_i per tooth (rad), eq. (0.2).
    pub phase: Vec<f64>,
    /// Look-back τ = −gap/ω (s) per (tooth, m): `[i*K + m−1]`.
    pub tau_nominal: Vec<f64>,
    /// Look-back τ = −gap/ω + (δ_i − δ_{i−m})/ω (s): previous effective edge aligned with the ray.
    pub tau_aligned: Vec<f64>,
    /// (sin, cos) of ω·τ_aligned per (tooth, m).
    pub turn_aligned: Vec<(f64, f64)>,
    /// Tooth i − m per (tooth, m).
    prev: Vec<usize>,
}

impl HeightGeometry {
    /// Number of teeth.
    pub fn teeth(&self) -> usize {
        self.k
    }
    /// Index i·K + m − 1 of the (tooth, m) tables.
    #[inline]
    pub fn pass_index(&self, tooth: usize, m: usize) -> usize {
        tooth * self.k + m - 1
    }
    /// Tooth i − m (cyclic).
    #[inline]
    pub fn previous(&self, tooth: usize, m: usize) -> usize {
        self.prev[self.pass_index(tooth, m)]
    }
}

impl<M: ToolMotion> ToolKinematics<M> {
    /// Precompute the height-dependent geometry at `z`.
    pub fn at_height(&self, z: f64) -> HeightGeometry {
        let k = self.cutter.teeth();
        let direction: Vec<(f64, f64)> = (0..k)
            .map(|i| self.cutter.tooth_angle(i, z).sin_cos())
            .collect();
        let points: Vec<SpindlePoint> = direction
            .iter()
            .map(|&sc| self.spindle_point_sc(sc, z))
            .collect();
        let radius: Vec<f64> = points.iter().map(SpindlePoint::radius).collect();
        let phase: Vec<f64> = points.iter().map(SpindlePoint::angle).collect();
        let mut tau_nominal = Vec::with_capacity(k * k);
        let mut tau_aligned = Vec::with_capacity(k * k);
        for i in 0..k {
            for m in 1..=k {
                let p = (i + k * m - m) % k;
                let gap = self.gap_time(i, m);
                let shift = crate::angle::wrap_pi(phase[i] - phase[p] + gap * self.omega);
                tau_nominal.push(-gap);
                tau_aligned.push(-gap + shift / self.omega);
            }
        }
        let turn_aligned = tau_aligned
            .iter()
            .map(|t| (t * self.omega).sin_cos())
            .collect();
        let prev = (0..k * k)
            .map(|q| (q / k + k * (q % k + 1) - (q % k + 1)) % k)
            .collect();
        HeightGeometry {
            prev,
            turn_aligned,
            z,
            k,
            points,
            direction,
            radius,
            phase,
            tau_nominal,
            tau_aligned,
        }
    }
}

/// (sin x, cos x) for a small angle by Taylor polynomials of degree 15/16 in Horner form
/// (|x| ≤ 0.5: truncation error below 1e-19, i.e. correctly rounded to ~1 ulp), libm otherwise.
/// Used for the Newton increments of the spindle angle: ~3× cheaper than libm `sin_cos`
/// (measured in `benches/chip.rs`, which prints the libm baseline) at full double accuracy.
#[inline]
pub fn small_sin_cos(x: f64) -> (f64, f64) {
    let q = x * x;
    if q < SMALL_ANGLE_SQ {
        // |x| ≤ 1/8: degree 9/10 suffice (next terms x¹¹/11! < 3e-18, x¹²/12! < 4e-20)
        let ps = SIN_TAYLOR[..4].iter().rev().fold(0.0, |acc, c| acc * q + c);
        let pc = COS_TAYLOR[..5].iter().rev().fold(0.0, |acc, c| acc * q + c);
        return (x + x * q * ps, 1.0 + q * pc);
    }
    if x.abs() > 0.5 {
        return x.sin_cos();
    }
    let ps = SIN_TAYLOR.iter().rev().fold(0.0, |acc, c| acc * q + c);
    let pc = COS_TAYLOR.iter().rev().fold(0.0, |acc, c| acc * q + c);
    (x + x * q * ps, 1.0 + q * pc)
}

/// Below this x², [`small_sin_cos`] uses its degree-9/10 branch (|x| < 1/8).
pub(super) const SMALL_ANGLE_SQ: f64 = 0.015625;

/// Taylor coefficients of (sin x − x)/x³ in x² ([`small_sin_cos`]).
pub(super) const SIN_TAYLOR: [f64; 7] = [
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
];
/// Taylor coefficients of (cos x − 1)/x² in x² ([`small_sin_cos`]).
pub(super) const COS_TAYLOR: [f64; 8] = [
    -1.0 / 2.0,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
];
